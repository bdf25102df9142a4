// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/render/grid_renderer.h>

#include "render/gl_api.h"
#include "render/program.h"
#include "render/shaders.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace pliant::render
{

struct GridRenderer::Impl
{
    GridNormals normal_source = GridNormals::PassToBuffer;
    core::Vec3Field<double> displaced;  // upload_displaced's P + u N, kept for the next call
    Program program;        // grid.vert, grid_fetch.vert or grid_vertex_normals.vert; + phong.frag
    Program normal_pass;    // grid_normal_pass.vert + .frag (not for VertexShader)
    GLuint vao = 0;         // no attributes: the programs read gl_VertexID and textures
    GLuint positions = 0;   // RGBA32F, (nx + 2) x (ny + 2)
    GLuint owners = 0;      // R16UI, same size
    GLuint normals = 0;     // RGBA32F, nx x ny: unit normal, owner id (not for VertexShader)
    GLuint normal_fbo = 0;  // renders into `normals`
    // PassToBuffer: `positions` as a read framebuffer, and the buffer the copy fills: nx*ny
    // inner position texels, then nx*ny normal texels, read by `attrib_vao`.
    GLuint positions_fbo = 0;
    GLuint attributes = 0;
    GLuint attrib_vao = 0;
    bool normals_stale = true;  // positions or owners changed since the last normal pass
    std::array<GLuint, core::k_max_level + 1> index_buffers{};  // per level, made on first use
    int level = 0;
    int nx = 0;
    int ny = 0;
    Bounds bounds{};
    double max_abs_value = 0.0;
    std::vector<float> staging;  // padded RGBA texels, reused between uploads
    std::vector<std::uint16_t> owner_staging;

    Impl() = default;
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;
    ~Impl()
    {
        for (const GLuint b : index_buffers)
            if (b != 0U)
                gl::glDeleteBuffers(1, &b);
        const std::array<GLuint, 3> textures{positions, owners, normals};
        gl::glDeleteTextures(3, textures.data());
        gl::glDeleteFramebuffers(1, &normal_fbo);
        gl::glDeleteFramebuffers(1, &positions_fbo);
        gl::glDeleteBuffers(1, &attributes);
        gl::glDeleteVertexArrays(1, &attrib_vao);
        gl::glDeleteVertexArrays(1, &vao);
    }

    [[nodiscard]] int padded_width() const noexcept { return nx + 2; }
    [[nodiscard]] int padded_height() const noexcept { return ny + 2; }

    /// (Re)allocates the textures and the level's index buffer when the level changes.
    void prepare_level(const core::TetraGrid& grid);
    void upload_staging();
    void fill_owner_texture(std::span<const std::uint16_t> owners);
    /// Writes every node's unit normal and owner into `normals` (one triangle over an nx x ny
    /// target) and, for PassToBuffer, copies positions and normals into `attributes`; leaves
    /// the caller's framebuffers bound.
    void run_normal_pass();
};

namespace
{

void set_integer_sampling(GLuint texture)
{
    gl::glBindTexture(GL_TEXTURE_2D, texture);
    gl::glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl::glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl::glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl::glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

/// Attaches `texture` as colour attachment 0 of `fbo`, restoring the draw framebuffer binding.
/// \return whether `fbo` is complete.
bool attach_colour(GLuint fbo, GLuint texture)
{
    GLint bound = 0;
    gl::glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &bound);
    gl::glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo);
    gl::glFramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture,
                               0);
    const GLenum status = gl::glCheckFramebufferStatus(GL_DRAW_FRAMEBUFFER);
    gl::glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(bound));
    return status == GL_FRAMEBUFFER_COMPLETE;
}

}  // namespace

void GridRenderer::Impl::prepare_level(const core::TetraGrid& grid)
{
    if (index_buffers[static_cast<std::size_t>(grid.level())] == 0U)
    {
        // Twins are replaced by their canonical node: both sides of every seam then reference
        // the same vertices, so they are transformed and shaded once and cannot crack.
        std::vector<std::array<std::uint32_t, 3>> faces = grid.node_triangles();
        for (auto& f : faces)
            for (std::uint32_t& v : f)
                v = grid.canonical(core::NodeIndex{v}).value;
        GLuint buffer = 0;
        gl::glGenBuffers(1, &buffer);
        gl::glBindVertexArray(vao);
        gl::glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffer);
        gl::glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                         static_cast<GLsizeiptr>(faces.size() * sizeof(faces[0])), faces.data(),
                         GL_STATIC_DRAW);
        gl::glBindVertexArray(0);
        index_buffers[static_cast<std::size_t>(grid.level())] = buffer;
    }
    if (grid.level() == level)
        return;
    level = grid.level();
    nx = grid.nx();
    ny = grid.ny();
    staging.assign(
        static_cast<std::size_t>(padded_width()) * static_cast<std::size_t>(padded_height()) * 4U,
        0.0F);
    gl::glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl::glBindTexture(GL_TEXTURE_2D, positions);
    gl::glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, padded_width(), padded_height(), 0, GL_RGBA,
                     GL_FLOAT, nullptr);
    owner_staging.assign(
        static_cast<std::size_t>(padded_width()) * static_cast<std::size_t>(padded_height()),
        k_no_owner);
    gl::glBindTexture(GL_TEXTURE_2D, owners);
    gl::glTexImage2D(GL_TEXTURE_2D, 0, GL_R16UI, padded_width(), padded_height(), 0, GL_RED_INTEGER,
                     GL_UNSIGNED_SHORT, owner_staging.data());
    normals_stale = true;
    if (normal_source == GridNormals::VertexShader)
        return;
    gl::glBindTexture(GL_TEXTURE_2D, normals);
    gl::glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, nx, ny, 0, GL_RGBA, GL_FLOAT, nullptr);
    [[maybe_unused]] const bool normals_complete = attach_colour(normal_fbo, normals);
    PLIANT_ASSERT(normals_complete, "GridRenderer: the RGBA32F normal target is incomplete");
    if (normal_source != GridNormals::PassToBuffer)
        return;
    [[maybe_unused]] const bool positions_complete = attach_colour(positions_fbo, positions);
    PLIANT_ASSERT(positions_complete, "GridRenderer: the positions texture cannot be read back");
    const auto texels = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
    gl::glBindVertexArray(attrib_vao);
    gl::glBindBuffer(GL_ARRAY_BUFFER, attributes);
    gl::glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(texels * 2U * 16U), nullptr,
                     GL_STREAM_COPY);
    gl::glEnableVertexAttribArray(0);
    gl::glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 16, nullptr);
    gl::glEnableVertexAttribArray(1);
    gl::glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, 16,
                              reinterpret_cast<const void*>(texels * 16U));
    gl::glBindVertexArray(0);
    gl::glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void GridRenderer::Impl::run_normal_pass()
{
    GLint bound = 0;  // only the draw binding is touched
    gl::glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &bound);
    gl::glBindFramebuffer(GL_DRAW_FRAMEBUFFER, normal_fbo);
    gl::glViewport(0, 0, nx, ny);
    gl::glDisable(GL_DEPTH_TEST);
    gl::glUseProgram(normal_pass.id());
    gl::glActiveTexture(GL_TEXTURE0);
    gl::glBindTexture(GL_TEXTURE_2D, positions);
    gl::glActiveTexture(GL_TEXTURE1);
    gl::glBindTexture(GL_TEXTURE_2D, owners);
    gl::glActiveTexture(GL_TEXTURE0);
    gl::glBindVertexArray(vao);
    gl::glDrawArrays(GL_TRIANGLES, 0, 3);
    gl::glBindVertexArray(0);
    gl::glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(bound));
    normals_stale = false;
    if (normal_source != GridNormals::PassToBuffer)
        return;
    GLint read_bound = 0;
    gl::glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &read_bound);
    const auto texels = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
    gl::glBindBuffer(GL_PIXEL_PACK_BUFFER, attributes);
    // Rows of RGBA32F texels are multiples of 16 bytes: no pack alignment pads them.
    gl::glBindFramebuffer(GL_READ_FRAMEBUFFER, positions_fbo);
    gl::glReadBuffer(GL_COLOR_ATTACHMENT0);
    gl::glReadPixels(1, 1, nx, ny, GL_RGBA, GL_FLOAT, nullptr);
    gl::glBindFramebuffer(GL_READ_FRAMEBUFFER, normal_fbo);
    gl::glReadBuffer(GL_COLOR_ATTACHMENT0);
    gl::glReadPixels(0, 0, nx, ny, GL_RGBA, GL_FLOAT, reinterpret_cast<void*>(texels * 16U));
    gl::glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    gl::glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(read_bound));
}

void GridRenderer::Impl::upload_staging()
{
    gl::glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl::glBindTexture(GL_TEXTURE_2D, positions);
    gl::glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, padded_width(), padded_height(), GL_RGBA, GL_FLOAT,
                        staging.data());
    normals_stale = true;
}

void GridRenderer::Impl::fill_owner_texture(std::span<const std::uint16_t> node_owners)
{
    std::fill(owner_staging.begin(), owner_staging.end(), k_no_owner);
    const auto pw = static_cast<std::size_t>(padded_width());
    if (!node_owners.empty())
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x)
                owner_staging[static_cast<std::size_t>(y + 1) * pw +
                              static_cast<std::size_t>(x + 1)] =
                    node_owners[static_cast<std::size_t>(y) * static_cast<std::size_t>(nx) +
                                static_cast<std::size_t>(x)];
    gl::glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl::glBindTexture(GL_TEXTURE_2D, owners);
    gl::glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, padded_width(), padded_height(), GL_RED_INTEGER,
                        GL_UNSIGNED_SHORT, owner_staging.data());
    normals_stale = true;
}

core::Result<GridRenderer> GridRenderer::create(GridNormals normals)
{
    PLIANT_ASSERT(gl::is_loaded(), "GridRenderer::create: no GL context (call load_gl)");
    auto impl = std::make_unique<Impl>();
    impl->normal_source = normals;
    if (normals != GridNormals::VertexShader)
    {
        auto program = Program::create(
            with_snippets(normals == GridNormals::PassFetch ? shaders::k_grid_fetch_vert
                                                            : shaders::k_grid_vert,
                          {shaders::k_phong_outputs})
                .c_str(),
            shaders::k_phong_frag, "grid");
        if (!program)
            return program.error();
        auto pass = Program::create(
            shaders::k_grid_normal_pass_vert,
            with_snippets(shaders::k_grid_normal_pass_frag, {shaders::k_grid_normal}).c_str(),
            "grid normal pass");
        if (!pass)
            return pass.error();
        impl->program = std::move(*program);
        impl->normal_pass = std::move(*pass);
    }
    else
    {
        auto program =
            Program::create(with_snippets(shaders::k_grid_vertex_normals_vert,
                                          {shaders::k_phong_outputs, shaders::k_grid_normal})
                                .c_str(),
                            shaders::k_phong_frag, "grid (vertex-shader normals)");
        if (!program)
            return program.error();
        impl->program = std::move(*program);
    }
    gl::glGenVertexArrays(1, &impl->vao);
    std::array<GLuint, 3> textures{};
    gl::glGenTextures(3, textures.data());
    impl->positions = textures[0];
    impl->owners = textures[1];
    impl->normals = textures[2];
    for (const GLuint t : textures)
        set_integer_sampling(t);
    gl::glUseProgram(impl->program.id());
    gl::glUniform1i(impl->program.uniform("u_positions"), 0);
    if (normals != GridNormals::VertexShader)
    {
        gl::glUniform1i(impl->program.uniform("u_normals"), 1);
        gl::glGenFramebuffers(1, &impl->normal_fbo);
        gl::glGenFramebuffers(1, &impl->positions_fbo);
        gl::glGenBuffers(1, &impl->attributes);
        gl::glGenVertexArrays(1, &impl->attrib_vao);
        gl::glUseProgram(impl->normal_pass.id());
        gl::glUniform1i(impl->normal_pass.uniform("u_positions"), 0);
        gl::glUniform1i(impl->normal_pass.uniform("u_owners"), 1);
    }
    else
        gl::glUniform1i(impl->program.uniform("u_owners"), 1);
    return GridRenderer(std::move(impl));
}

GridRenderer::GridRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GridRenderer::GridRenderer(GridRenderer&&) noexcept = default;
GridRenderer& GridRenderer::operator=(GridRenderer&&) noexcept = default;
GridRenderer::~GridRenderer() = default;

void GridRenderer::upload(const core::TetraGrid& grid, const core::Vec3Field<double>& positions,
                          const core::Field<double>* values)
{
    for (const auto& f : positions)
        PLIANT_ASSERT(f.level() == grid.level(), "GridRenderer::upload: field of another level");
    PLIANT_ASSERT(values == nullptr || values->level() == grid.level(),
                  "GridRenderer::upload: values of another level");
    Impl& s = *impl_;
    s.prepare_level(grid);
    const auto pw = static_cast<std::size_t>(s.padded_width());
    core::Vec3 lo{positions[0].at(0, 0), positions[1].at(0, 0), positions[2].at(0, 0)};
    core::Vec3 hi = lo;
    double max_abs = 0.0;
    for (int y = 0; y < s.ny; ++y)
    {
        float* row = s.staging.data() + (static_cast<std::size_t>(y + 1) * pw + 1U) * 4U;
        for (int x = 0; x < s.nx; ++x)
        {
            const double px = positions[0].at(x, y);
            const double py = positions[1].at(x, y);
            const double pz = positions[2].at(x, y);
            const double v = values != nullptr ? values->at(x, y) : 0.0;
            float* texel = row + static_cast<std::size_t>(x) * 4U;
            texel[0] = static_cast<float>(px);
            texel[1] = static_cast<float>(py);
            texel[2] = static_cast<float>(pz);
            texel[3] = static_cast<float>(v);
            lo = {std::min(lo.x, px), std::min(lo.y, py), std::min(lo.z, pz)};
            hi = {std::max(hi.x, px), std::max(hi.y, py), std::max(hi.z, pz)};
            max_abs = std::max(max_abs, std::abs(v));
        }
    }
    // The ghost ring: the same table core::fill_ghosts applies to a Field with ghost width 1
    // (its offsets address a plane of stride nx + 2, which is this texture's layout).
    for (const core::GhostCopy& g : grid.ghost_table(1))
        std::copy_n(s.staging.data() + g.src * 4, 4, s.staging.data() + g.dst * 4);
    s.bounds = {lo, hi};
    const core::Vec3 c = s.bounds.centre();
    double r2 = 0.0;
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x)
        {
            const core::Vec3 d{positions[0].at(x, y) - c.x, positions[1].at(x, y) - c.y,
                               positions[2].at(x, y) - c.z};
            r2 = std::max(r2, core::dot(d, d));
        }
    s.bounds.point_radius = std::sqrt(r2);
    s.max_abs_value = max_abs;
    s.upload_staging();
}

void GridRenderer::upload_displaced(const core::TetraGrid& grid,
                                    const core::Vec3Field<double>& rest,
                                    const core::Vec3Field<double>& rest_normals,
                                    const core::Field<double>& u)
{
    core::Vec3Field<double>& p = impl_->displaced;  // allocated once per level
    for (auto& plane : p)
        if (plane.padded().empty() || plane.level() != grid.level() || plane.ghost() != 0)
            plane = core::Field<double>(grid);
    for (int c = 0; c < 3; ++c)
    {
        const auto i = static_cast<std::size_t>(c);
        for (int y = 0; y < grid.ny(); ++y)
            for (int x = 0; x < grid.nx(); ++x)
                p[i].at(x, y) = rest[i].at(x, y) + u.at(x, y) * rest_normals[i].at(x, y);
    }
    upload(grid, p, &u);
}

void GridRenderer::upload_owners(const core::TetraGrid& grid, std::span<const std::uint16_t> owners)
{
    PLIANT_ASSERT(grid.level() == impl_->level, "GridRenderer::upload_owners: upload a grid first");
    PLIANT_ASSERT(owners.empty() || owners.size() == grid.node_count(),
                  "GridRenderer::upload_owners: one owner per node");
    impl_->fill_owner_texture(owners);
}

CameraMatrices GridRenderer::camera(const CameraSettings& settings, int width,
                                    int height) const noexcept
{
    return make_camera(settings, impl_->bounds, width, height);
}

void GridRenderer::draw(const DrawSettings& settings, int width, int height) const
{
    Impl& s = *impl_;
    PLIANT_ASSERT(s.level > 0, "GridRenderer::draw: nothing uploaded");
    // Once per upload, not per draw: the wireframe pass and further views reuse the normals.
    if (s.normal_source != GridNormals::VertexShader && s.normals_stale)
        s.run_normal_pass();
    const CameraMatrices cam = camera(settings.camera, width, height);
    set_draw_uniforms(s.program, settings, cam, static_cast<float>(s.max_abs_value));
    gl::glUniform1i(s.program.location(DrawUniform::Nx), s.nx);
    gl::glBindVertexArray(s.normal_source == GridNormals::PassToBuffer ? s.attrib_vao : s.vao);
    gl::glActiveTexture(GL_TEXTURE0);
    gl::glBindTexture(GL_TEXTURE_2D, s.positions);
    gl::glActiveTexture(GL_TEXTURE1);
    gl::glBindTexture(GL_TEXTURE_2D,
                      s.normal_source == GridNormals::PassFetch ? s.normals : s.owners);
    gl::glActiveTexture(GL_TEXTURE0);
    gl::glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.index_buffers[static_cast<std::size_t>(s.level)]);
    const auto count = static_cast<GLsizei>(triangle_count() * 3U);
    const auto nodes = static_cast<GLsizei>(s.nx * s.ny);
    if (settings.points)
    {
        DrawSettings no_wire = settings;
        no_wire.wireframe = false;
        draw_passes(s.program, no_wire, width, height,
                    [nodes] { gl::glDrawArrays(GL_POINTS, 0, nodes); });
    }
    else
        draw_passes(s.program, settings, width, height,
                    [count] { gl::glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr); });
    gl::glBindVertexArray(0);
}

const Bounds& GridRenderer::bounds() const noexcept
{
    return impl_->bounds;
}

int GridRenderer::level() const noexcept
{
    return impl_->level;
}

std::size_t GridRenderer::triangle_count() const noexcept
{
    const auto w = static_cast<std::size_t>(1) << static_cast<unsigned>(impl_->level);
    return 4U * w * w;
}

double GridRenderer::max_abs_value() const noexcept
{
    return impl_->max_abs_value;
}

}  // namespace pliant::render
