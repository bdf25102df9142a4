// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A linked GLSL program (vertex + fragment) with RAII ownership, shared by the grid and mesh
// renderers.

#include <pliant/core/result.h>
#include <pliant/render/draw_settings.h>

#include "render/gl_api.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <utility>

namespace pliant::render
{

/// The uniforms set at every draw (set_draw_uniforms, draw_passes, the grid renderer's `u_nx`):
/// a Program looks them up once when it links, so a frame does no look-up by name.
enum class DrawUniform : std::uint8_t
{
    ViewProjection,
    Eye,
    ColorMode,
    Shading,
    Flat,
    BaseColor,
    WireColor,
    Palette,
    ValueRange,
    Ambient,
    Specular,
    Shininess,
    Nx,
};
inline constexpr std::size_t k_draw_uniforms = 13;

/// The GLSL name of `u` ("u_view_projection", ...).
[[nodiscard]] const char* draw_uniform_name(DrawUniform u) noexcept;

class Program
{
public:
    Program() = default;
    /// Compiles and links. \return GraphicsError with the compiler's log.
    static core::Result<Program> create(const char* vertex_source, const char* fragment_source,
                                        const char* name);
    ~Program();
    Program(Program&& o) noexcept : id_(std::exchange(o.id_, 0U)), locations_(o.locations_) {}
    Program& operator=(Program&& o) noexcept
    {
        std::swap(id_, o.id_);
        std::swap(locations_, o.locations_);
        return *this;
    }
    Program(const Program&) = delete;
    Program& operator=(const Program&) = delete;

    [[nodiscard]] GLuint id() const noexcept { return id_; }
    /// Looks `name` up (set-up code; a draw uses location()).
    [[nodiscard]] GLint uniform(const char* name) const noexcept
    {
        return gl::glGetUniformLocation(id_, name);
    }
    /// The location of draw uniform `u`, looked up when the program linked: -1 where the program
    /// has none (or the compiler dropped it as unused), which glUniform* ignores.
    [[nodiscard]] GLint location(DrawUniform u) const noexcept
    {
        return locations_[static_cast<std::size_t>(u)];
    }

private:
    GLuint id_ = 0;
    std::array<GLint, k_draw_uniforms> locations_{};
};

/// `source` with each snippet inserted, in order, after its `#version 330 core` line (GLSL has no
/// #include: shared declarations such as phong_outputs.glsl travel this way).
[[nodiscard]] std::string with_snippets(const char* source,
                                        std::initializer_list<const char*> snippets);

/// Binds `program` and sets the uniforms of phong.frag.glsl and `u_view_projection`.
void set_draw_uniforms(const Program& program, const DrawSettings& settings,
                       const CameraMatrices& camera, float value_range);

/// Clears (if asked) and runs `draw_triangles()` once shaded and, with a wireframe, once more
/// as lines over it (polygon offset pushes the fill back so the lines win the depth test).
template <typename DrawTriangles>
void draw_passes(const Program& program, const DrawSettings& settings, int width, int height,
                 DrawTriangles draw_triangles)
{
    gl::glViewport(0, 0, width, height);
    gl::glEnable(GL_DEPTH_TEST);
    gl::glDepthFunc(GL_LEQUAL);
    gl::glDepthMask(GL_TRUE);
    if (settings.clear)
    {
        gl::glClearColor(settings.background.r, settings.background.g, settings.background.b, 1.0F);
        gl::glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    }
    if (!settings.wireframe)
    {
        draw_triangles();
        return;
    }
    gl::glEnable(GL_POLYGON_OFFSET_FILL);
    gl::glPolygonOffset(1.0F, 1.0F);
    draw_triangles();
    gl::glDisable(GL_POLYGON_OFFSET_FILL);
    gl::glUniform1i(program.location(DrawUniform::Flat), 1);
    gl::glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    draw_triangles();
    gl::glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    gl::glUniform1i(program.location(DrawUniform::Flat), 0);
}

}  // namespace pliant::render
