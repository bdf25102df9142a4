// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// The GPU re-meshing look-up (design in include/pliant/render/gpu_sampler.h).
//
// Per tetrahedron face (P0, P1, P2), with λ = [P0 P1 P2]⁻¹ X the (unnormalised) barycentric
// coordinates of the central projection of X onto the face plane, w = λ0 + λ1 + λ2 is positive
// in front of the face and 1 on its plane, and s = λ1 / w, t = λ2 / w are the face coordinates.
// A view of N = k·W + 1 pixels with clip coordinates
//     x = k·W·(2λ1 − w) / N,   y = k·W·(2λ2 − w) / N,   z = 0,   w
// has window x = k·W·s + ½ (and y likewise), so face node (i, j) = (s, t)·W lies on the centre of
// pixel (k·i, k·j). The map X → clip is linear (no translation), hence a pixel's ray through
// the origin is exactly the node's ray, and perspective-correct interpolation of a vertex
// attribute is barycentric interpolation at the ray's hit on the chord triangle. z = 0 makes the
// near clip plane w = 0: the half of the sphere behind the view is clipped away.

#include <pliant/render/framebuffer.h>
#include <pliant/render/gpu_sampler.h>

#include "render/gl_api.h"
#include "render/program.h"
#include "render/shaders.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace pliant::render
{
namespace
{

using core::Vec3;

/// One face of the domain tetrahedron: its inverse vertex matrix as three rows.
struct View
{
    std::array<Vec3, 3> inverse_rows;  // λ_i = inverse_rows[i] · X

    [[nodiscard]] std::array<double, 3> lambda(const Vec3& x) const noexcept
    {
        return {core::dot(inverse_rows[0], x), core::dot(inverse_rows[1], x),
                core::dot(inverse_rows[2], x)};
    }
};

View make_view(const Vec3& p0, const Vec3& p1, const Vec3& p2)
{
    const double det = core::dot(p0, core::cross(p1, p2));
    return View{{core::cross(p1, p2) / det, core::cross(p2, p0) / det, core::cross(p0, p1) / det}};
}

/// A node to read: its pixel (k·i, k·j) in view `view`.
struct Entry
{
    core::NodeIndex node;
    int i = 0;
    int j = 0;
};

/// GL objects of one sampling run, released on every return path.
struct GlObjects
{
    GLuint vao = 0;
    std::array<GLuint, 3> buffers{};  // clip coordinates, positions, indices

    GlObjects() = default;
    GlObjects(const GlObjects&) = delete;
    GlObjects& operator=(const GlObjects&) = delete;
    ~GlObjects()
    {
        gl::glBindVertexArray(0);
        gl::glBindBuffer(GL_ARRAY_BUFFER, 0);
        gl::glDeleteBuffers(3, buffers.data());
        gl::glDeleteVertexArrays(1, &vao);
        gl::glUseProgram(0);
        gl::glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }
};

core::Error invalid(std::string message)
{
    return {core::ErrorCode::InvalidArgument, "sample_on_gpu: " + std::move(message)};
}

/// Reads the pixels of `entries` (sorted by row) into `out` (4 floats per entry), one
/// glReadPixels per row of nodes, only as wide as that row's last node.
void read_entries(std::span<const Entry> entries, int k, std::vector<float>& row,
                  std::vector<float>& out)
{
    out.resize(entries.size() * 4);
    gl::glPixelStorei(GL_PACK_ALIGNMENT, 4);
    std::size_t first = 0;
    while (first < entries.size())
    {
        std::size_t last = first;
        int max_i = entries[first].i;
        while (last + 1 < entries.size() && entries[last + 1].j == entries[first].j)
            max_i = std::max(max_i, entries[++last].i);
        const int width = k * max_i + 1;
        row.resize(static_cast<std::size_t>(width) * 4);
        gl::glReadPixels(0, k * entries[first].j, width, 1, GL_RGBA, GL_FLOAT, row.data());
        for (std::size_t e = first; e <= last; ++e)
            std::copy_n(row.data() + static_cast<std::size_t>(k * entries[e].i) * 4, 4,
                        out.data() + e * 4);
        first = last + 1;
    }
}

}  // namespace

core::Result<core::Vec3Field<double>> sample_on_gpu(
    const core::TetraGrid& grid, const core::Vec3Field<double>& domain_sphere,
    std::span<const core::Vec3> sphere_vertices, std::span<const core::Vec3> original_positions,
    std::span<const std::array<std::uint32_t, 3>> faces, const GpuSamplerSettings& settings,
    GpuSampleStats* stats)
{
    const auto start = std::chrono::steady_clock::now();
    constexpr std::size_t k_max_faces = std::size_t{1} << 24;  // ids exact in a float
    if (sphere_vertices.size() != original_positions.size() || faces.empty() ||
        faces.size() >= k_max_faces)
        return invalid(std::to_string(sphere_vertices.size()) + " sphere points, " +
                       std::to_string(original_positions.size()) + " positions and " +
                       std::to_string(faces.size()) +
                       " faces (need equal counts and 1 .. 2^24 - 1 faces)");
    for (const auto& f : faces)
        for (const std::uint32_t v : f)
            if (v >= sphere_vertices.size())
                return invalid("face index " + std::to_string(v) + " out of range");
    for (const auto& d : domain_sphere)
        if (d.level() != grid.level())
            return invalid("domain map of another level");
    if (!gl::is_loaded())
        return core::fail(core::ErrorCode::GraphicsError,
                          "sample_on_gpu: no OpenGL context (create an OffscreenContext first)");

    const int w = grid.w();
    // automatic: views of about 1025 pixels, where the snapping error falls to float32's
    // (docs/remesh.md, measured on spot)
    const int k =
        settings.pixels_per_cell > 0 ? settings.pixels_per_cell : std::clamp(1024 / w, 1, 64);
    const int n_px = k * w + 1;
    const auto at = [&domain_sphere](core::NodeIndex n) {
        return Vec3{domain_sphere[0][n], domain_sphere[1][n], domain_sphere[2][n]};
    };

    // The domain tetrahedron from the grid's corners; its four faces are the views.
    const auto c = grid.corners();
    const std::array<Vec3, 4> corner{at(c[0]), at(c[1]), at(c[2]), at(c[3])};
    const std::array<View, 4> views{
        make_view(corner[0], corner[1], corner[2]), make_view(corner[0], corner[2], corner[3]),
        make_view(corner[1], corner[0], corner[3]), make_view(corner[1], corner[3], corner[2])};

    // Each canonical node goes to the face whose cone holds it most centrally; its lattice
    // coordinates there must be integers (the gnomonic tetrahedron map), else it is refused.
    constexpr double k_lattice_tolerance = 1e-6;
    std::array<std::vector<Entry>, 4> entries;
    const double wd = static_cast<double>(w);
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const core::NodeIndex n = grid.index(x, y);
            if (!grid.is_canonical(n))
                continue;
            const Vec3 p = at(n);
            std::size_t best = 0;
            double best_score = -std::numeric_limits<double>::infinity();
            std::array<double, 3> best_b{};
            for (std::size_t v = 0; v < views.size(); ++v)
            {
                const auto l = views[v].lambda(p);
                const double sum = l[0] + l[1] + l[2];
                if (!(sum > 0.0))
                    continue;
                const std::array<double, 3> b{l[0] / sum, l[1] / sum, l[2] / sum};
                const double score = std::min({b[0], b[1], b[2]});
                if (score > best_score)
                {
                    best_score = score;
                    best = v;
                    best_b = b;
                }
            }
            const double si = best_b[1] * wd, sj = best_b[2] * wd;
            const double ri = std::round(si), rj = std::round(sj);
            if (!(best_score >= -k_lattice_tolerance) || std::abs(si - ri) > k_lattice_tolerance ||
                std::abs(sj - rj) > k_lattice_tolerance || ri + rj > wd)
                return invalid(
                    "the sphere point of node (" + std::to_string(x) + ", " + std::to_string(y) +
                    ") is not a lattice point of the domain tetrahedron (the GPU sampler "
                    "needs the gnomonic domain map, core::SphereMap::Gnomonic)");
            entries[best].push_back({n, static_cast<int>(ri), static_cast<int>(rj)});
        }
    for (auto& e : entries)
        std::sort(e.begin(), e.end(),
                  [](const Entry& a, const Entry& b)
                  { return a.j != b.j ? a.j < b.j : a.i < b.i; });

    // Colours relative to the bounding-box centre: float32 then rounds relative to the size of
    // the object, not to its distance from the origin.
    Vec3 lo = original_positions[0], hi = original_positions[0];
    for (const Vec3& q : original_positions)
    {
        lo = {std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
        hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
    }
    const Vec3 centre = (lo + hi) * 0.5;
    const std::size_t nv = sphere_vertices.size();
    std::vector<float> colours(nv * 3);
    for (std::size_t v = 0; v < nv; ++v)
    {
        const Vec3 q = original_positions[v] - centre;
        colours[3 * v] = static_cast<float>(q.x);
        colours[3 * v + 1] = static_cast<float>(q.y);
        colours[3 * v + 2] = static_cast<float>(q.z);
    }
    // clip coordinates of every vertex in every view, computed in double, rounded once
    const double scale = static_cast<double>(k * w) / static_cast<double>(n_px);
    std::vector<float> clip(views.size() * nv * 4);
    for (std::size_t v = 0; v < views.size(); ++v)
        for (std::size_t i = 0; i < nv; ++i)
        {
            const auto l = views[v].lambda(sphere_vertices[i]);
            const double ww = l[0] + l[1] + l[2];
            float* o = clip.data() + (v * nv + i) * 4;
            o[0] = static_cast<float>(scale * (2.0 * l[1] - ww));
            o[1] = static_cast<float>(scale * (2.0 * l[2] - ww));
            o[2] = 0.0F;
            o[3] = static_cast<float>(ww);
        }

    auto program = Program::create(shaders::k_sample_vert, shaders::k_sample_frag, "gpu sampler");
    if (!program)
        return program.error();
    auto fb = Framebuffer::create(n_px, n_px, PixelFormat::Rgba32f);
    if (!fb)
        return fb.error();

    GlObjects gl_objects;
    gl::glGenVertexArrays(1, &gl_objects.vao);
    gl::glBindVertexArray(gl_objects.vao);
    gl::glGenBuffers(3, gl_objects.buffers.data());
    gl::glBindBuffer(GL_ARRAY_BUFFER, gl_objects.buffers[0]);
    gl::glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(clip.size() * sizeof(float)),
                     clip.data(), GL_STATIC_DRAW);
    gl::glBindBuffer(GL_ARRAY_BUFFER, gl_objects.buffers[1]);
    gl::glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(colours.size() * sizeof(float)),
                     colours.data(), GL_STATIC_DRAW);
    gl::glEnableVertexAttribArray(1);
    gl::glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    gl::glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gl_objects.buffers[2]);
    gl::glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                     static_cast<GLsizeiptr>(faces.size() * sizeof(faces[0])), faces.data(),
                     GL_STATIC_DRAW);
    gl::glBindBuffer(GL_ARRAY_BUFFER, gl_objects.buffers[0]);
    gl::glEnableVertexAttribArray(0);

    gl::glUseProgram(program->id());
    fb->bind();
    gl::glClearColor(0.0F, 0.0F, 0.0F, 0.0F);
    gl::glEnable(GL_DEPTH_TEST);
    gl::glDepthMask(GL_TRUE);
    const auto index_count = static_cast<GLsizei>(faces.size() * 3);
    const auto draw = [&](std::size_t view, GLenum depth_func)
    {
        // every fragment has depth ½ (z = 0): GL_LESS keeps the first, GL_LEQUAL the last
        gl::glDepthFunc(depth_func);
        gl::glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        gl::glVertexAttribPointer(
            0, 4, GL_FLOAT, GL_FALSE, 0,
            reinterpret_cast<const void*>(view * nv * 4 * sizeof(float)));  // NOLINT
        gl::glDrawElements(GL_TRIANGLES, index_count, GL_UNSIGNED_INT, nullptr);
    };

    core::Vec3Field<double> out{core::Field<double>(grid), core::Field<double>(grid),
                                core::Field<double>(grid)};
    std::size_t overlaps = 0, samples = 0;
    std::vector<float> row, first_pass, last_pass;
    for (std::size_t v = 0; v < views.size(); ++v)
    {
        if (entries[v].empty())
            continue;
        if (settings.check_overlaps)
        {
            draw(v, GL_LESS);
            read_entries(entries[v], k, row, first_pass);
        }
        draw(v, GL_LEQUAL);
        read_entries(entries[v], k, row, last_pass);
        for (std::size_t e = 0; e < entries[v].size(); ++e)
        {
            const float* px = last_pass.data() + e * 4;
            const Entry& en = entries[v][e];
            if (!(px[3] >= 1.0F) || !std::isfinite(px[0]) || !std::isfinite(px[1]) ||
                !std::isfinite(px[2]))
            {
                const core::GridCoord g = grid.coord(en.node);
                return core::fail(core::ErrorCode::GraphicsError,
                                  "sample_on_gpu: node (" + std::to_string(g.x) + ", " +
                                      std::to_string(g.y) + ") got no sample (view " +
                                      std::to_string(v) + ", pixel " + std::to_string(k * en.i) +
                                      ", " + std::to_string(k * en.j) +
                                      "): no triangle covered its ray");
            }
            if (settings.check_overlaps && first_pass[e * 4 + 3] != px[3])
                ++overlaps;
            out[0][en.node] = static_cast<double>(px[0]) + centre.x;
            out[1][en.node] = static_cast<double>(px[1]) + centre.y;
            out[2][en.node] = static_cast<double>(px[2]) + centre.z;
            ++samples;
        }
    }
    gl::glDepthFunc(GL_LEQUAL);
    for (auto& f : out)
        core::sync_twins(grid, f);
    if (stats != nullptr)
    {
        stats->views = static_cast<int>(views.size());
        stats->viewport = n_px;
        stats->pixels_per_cell = k;
        stats->samples = samples;
        stats->overlaps = overlaps;
        stats->seconds_render =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return out;
}

}  // namespace pliant::render
