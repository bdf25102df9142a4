// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/render/mesh_renderer.h>
#include <pliant/render/normals.h>

#include "render/gl_api.h"
#include "render/program.h"
#include "render/shaders.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pliant::render
{

struct MeshRenderer::Impl
{
    Program program;
    GLuint vao = 0;
    GLuint vertices = 0;  // interleaved x y z nx ny nz value
    GLuint indices = 0;
    std::size_t triangles = 0;
    std::size_t vertex_count = 0;
    Bounds bounds{};
    float max_abs_value = 0.0F;
    std::vector<std::array<std::uint32_t, 3>> faces;  // of the last upload, for update()
    std::vector<core::Vec3> computed_normals;         // reused by update()
    std::vector<float> interleaved;                   // reused by update()

    // Fills `interleaved` (7 floats per vertex), the bounds and the largest |value|.
    void interleave(std::span<const core::Vec3> positions, std::span<const core::Vec3> normals,
                    std::span<const float> values);

    Impl() = default;
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;
    ~Impl()
    {
        const std::array<GLuint, 2> buffers{vertices, indices};
        gl::glDeleteBuffers(2, buffers.data());
        gl::glDeleteVertexArrays(1, &vao);
    }
};

core::Result<MeshRenderer> MeshRenderer::create()
{
    PLIANT_ASSERT(gl::is_loaded(), "MeshRenderer::create: no GL context (call load_gl)");
    auto program =
        Program::create(with_snippets(shaders::k_mesh_vert, {shaders::k_phong_outputs}).c_str(),
                        shaders::k_phong_frag, "mesh");
    if (!program)
        return program.error();
    auto impl = std::make_unique<Impl>();
    impl->program = std::move(*program);
    gl::glGenVertexArrays(1, &impl->vao);
    std::array<GLuint, 2> buffers{};
    gl::glGenBuffers(2, buffers.data());
    impl->vertices = buffers[0];
    impl->indices = buffers[1];

    constexpr GLsizei k_stride = 7 * sizeof(float);
    gl::glBindVertexArray(impl->vao);
    gl::glBindBuffer(GL_ARRAY_BUFFER, impl->vertices);
    gl::glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl->indices);
    gl::glEnableVertexAttribArray(0);
    gl::glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, k_stride, nullptr);
    gl::glEnableVertexAttribArray(1);
    gl::glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, k_stride,
                              reinterpret_cast<const void*>(3 * sizeof(float)));
    gl::glEnableVertexAttribArray(2);
    gl::glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, k_stride,
                              reinterpret_cast<const void*>(6 * sizeof(float)));
    gl::glBindVertexArray(0);
    return MeshRenderer(std::move(impl));
}

MeshRenderer::MeshRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
MeshRenderer::MeshRenderer(MeshRenderer&&) noexcept = default;
MeshRenderer& MeshRenderer::operator=(MeshRenderer&&) noexcept = default;
MeshRenderer::~MeshRenderer() = default;

void MeshRenderer::Impl::interleave(std::span<const core::Vec3> positions,
                                    std::span<const core::Vec3> normals,
                                    std::span<const float> values)
{
    interleaved.resize(positions.size() * 7U);
    max_abs_value = 0.0F;
    for (std::size_t i = 0; i < positions.size(); ++i)
    {
        float* v = interleaved.data() + i * 7U;
        v[0] = static_cast<float>(positions[i].x);
        v[1] = static_cast<float>(positions[i].y);
        v[2] = static_cast<float>(positions[i].z);
        v[3] = static_cast<float>(normals[i].x);
        v[4] = static_cast<float>(normals[i].y);
        v[5] = static_cast<float>(normals[i].z);
        v[6] = values.empty() ? 0.0F : values[i];
        max_abs_value = std::max(max_abs_value, std::abs(v[6]));
    }
    bounds = bounds_of(positions);
}

void MeshRenderer::upload(std::span<const core::Vec3> positions,
                          std::span<const std::array<std::uint32_t, 3>> faces,
                          std::span<const core::Vec3> normals, std::span<const float> values)
{
    PLIANT_ASSERT(!positions.empty(), "MeshRenderer::upload: no vertices");
    PLIANT_ASSERT(normals.empty() || normals.size() == positions.size(),
                  "MeshRenderer::upload: one normal per vertex");
    PLIANT_ASSERT(values.empty() || values.size() == positions.size(),
                  "MeshRenderer::upload: one value per vertex");
    Impl& s = *impl_;
    s.faces.assign(faces.begin(), faces.end());
    if (normals.empty())
    {
        s.computed_normals.resize(positions.size());
        mesh_normals(positions, faces, s.computed_normals);
        normals = s.computed_normals;
    }
    s.interleave(positions, normals, values);
    s.triangles = faces.size();
    s.vertex_count = positions.size();
    gl::glBindVertexArray(s.vao);
    gl::glBindBuffer(GL_ARRAY_BUFFER, s.vertices);
    gl::glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(s.interleaved.size() * sizeof(float)),
                     s.interleaved.data(), GL_STATIC_DRAW);
    gl::glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                     static_cast<GLsizeiptr>(faces.size() * sizeof(faces[0])), faces.data(),
                     GL_STATIC_DRAW);
    gl::glBindVertexArray(0);
    // A mesh drawn as uploaded keeps only its faces; update() grows these again once.
    s.interleaved = {};
    s.computed_normals = {};
}

void MeshRenderer::update(std::span<const core::Vec3> positions,
                          std::span<const core::Vec3> normals, std::span<const float> values)
{
    Impl& s = *impl_;
    PLIANT_ASSERT(s.triangles > 0, "MeshRenderer::update: nothing uploaded");
    PLIANT_ASSERT(positions.size() == s.vertex_count,
                  "MeshRenderer::update: not one position per uploaded vertex");
    PLIANT_ASSERT(normals.empty() || normals.size() == positions.size(),
                  "MeshRenderer::update: one normal per vertex");
    PLIANT_ASSERT(values.empty() || values.size() == positions.size(),
                  "MeshRenderer::update: one value per vertex");
    if (normals.empty())
    {
        s.computed_normals.resize(positions.size());
        mesh_normals(positions, s.faces, s.computed_normals);
        normals = s.computed_normals;
    }
    s.interleave(positions, normals, values);
    gl::glBindBuffer(GL_ARRAY_BUFFER, s.vertices);
    gl::glBufferSubData(GL_ARRAY_BUFFER, 0,
                        static_cast<GLsizeiptr>(s.interleaved.size() * sizeof(float)),
                        s.interleaved.data());
    gl::glBindBuffer(GL_ARRAY_BUFFER, 0);
}

CameraMatrices MeshRenderer::camera(const CameraSettings& settings, int width,
                                    int height) const noexcept
{
    return make_camera(settings, impl_->bounds, width, height);
}

void MeshRenderer::draw(const DrawSettings& settings, int width, int height) const
{
    const Impl& s = *impl_;
    PLIANT_ASSERT(s.triangles > 0, "MeshRenderer::draw: nothing uploaded");
    DrawSettings mesh_settings = settings;
    if (mesh_settings.color == ColorMode::Owner)
        mesh_settings.color = ColorMode::None;
    const CameraMatrices cam = camera(settings.camera, width, height);
    set_draw_uniforms(s.program, mesh_settings, cam, s.max_abs_value);
    gl::glBindVertexArray(s.vao);
    const auto count = static_cast<GLsizei>(s.triangles * 3U);
    draw_passes(s.program, mesh_settings, width, height,
                [count] { gl::glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr); });
    gl::glBindVertexArray(0);
}

const Bounds& MeshRenderer::bounds() const noexcept
{
    return impl_->bounds;
}

std::size_t MeshRenderer::triangle_count() const noexcept
{
    return impl_->triangles;
}

}  // namespace pliant::render
