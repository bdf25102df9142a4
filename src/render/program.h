// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A linked GLSL program (vertex + fragment) with RAII ownership, shared by the grid and mesh
// renderers.

#include <pliant/core/result.h>
#include <pliant/render/draw_settings.h>

#include "render/gl_api.h"

#include <initializer_list>
#include <string>
#include <utility>

namespace pliant::render
{

class Program
{
public:
    Program() = default;
    /// Compiles and links. \return GraphicsError with the compiler's log.
    static core::Result<Program> create(const char* vertex_source, const char* fragment_source,
                                        const char* name);
    ~Program();
    Program(Program&& o) noexcept : id_(std::exchange(o.id_, 0U)) {}
    Program& operator=(Program&& o) noexcept
    {
        std::swap(id_, o.id_);
        return *this;
    }
    Program(const Program&) = delete;
    Program& operator=(const Program&) = delete;

    [[nodiscard]] GLuint id() const noexcept { return id_; }
    [[nodiscard]] GLint uniform(const char* name) const noexcept
    {
        return gl::glGetUniformLocation(id_, name);
    }

private:
    GLuint id_ = 0;
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
    gl::glUniform1i(program.uniform("u_flat"), 1);
    gl::glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    draw_triangles();
    gl::glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    gl::glUniform1i(program.uniform("u_flat"), 0);
}

}  // namespace pliant::render
