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
#include <memory>
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

/// A node to read and its pixel (column x, row y) in its view.
struct Entry
{
    core::NodeIndex node;
    int x = 0;
    int y = 0;
};

core::Error invalid(std::string message)
{
    return {core::ErrorCode::InvalidArgument, "sample_on_gpu: " + std::move(message)};
}

/// Reads the pixels of `entries` (sorted by row) into `out` (4 floats per entry), one
/// glReadPixels per row of pixels holding nodes, only as wide as that row's last node.
void read_entries(std::span<const Entry> entries, std::vector<float>& row, std::vector<float>& out)
{
    out.resize(entries.size() * 4);
    gl::glPixelStorei(GL_PACK_ALIGNMENT, 4);
    std::size_t first = 0;
    while (first < entries.size())
    {
        std::size_t last = first;
        int max_x = entries[first].x;
        while (last + 1 < entries.size() && entries[last + 1].y == entries[first].y)
            max_x = std::max(max_x, entries[++last].x);
        const int width = max_x + 1;
        row.resize(static_cast<std::size_t>(width) * 4);
        gl::glReadPixels(0, entries[first].y, width, 1, GL_RGBA, GL_FLOAT, row.data());
        for (std::size_t e = first; e <= last; ++e)
            std::copy_n(row.data() + static_cast<std::size_t>(entries[e].x) * 4, 4,
                        out.data() + e * 4);
        first = last + 1;
    }
}

/// The node's view: the tetrahedron face whose cone holds it most centrally, and its face
/// coordinates there (s, t): the central projection onto the face is P0 + s(P1 - P0) + t(P2 - P0).
struct Placement
{
    std::size_t view = 0;
    double score = -std::numeric_limits<double>::infinity();  // min barycentric coordinate
    double s = 0.0;
    double t = 0.0;
};

Placement place(std::span<const View> views, const Vec3& p)
{
    Placement best;
    for (std::size_t v = 0; v < views.size(); ++v)
    {
        const auto l = views[v].lambda(p);
        const double sum = l[0] + l[1] + l[2];
        if (!(sum > 0.0))
            continue;
        const double score = std::min({l[0], l[1], l[2]}) / sum;
        if (score > best.score)
            best = {v, score, l[1] / sum, l[2] / sum};
    }
    return best;
}

/// The inputs both GPU functions take, checked.
core::Result<void> check_inputs(const core::TetraGrid& grid,
                                const core::Vec3Field<double>& domain_sphere,
                                std::span<const Vec3> sphere_vertices, std::size_t positions,
                                std::span<const std::array<std::uint32_t, 3>> faces,
                                const char* who)
{
    constexpr std::size_t k_max_faces = std::size_t{1} << 24;  // ids exact in a float
    const std::string name = who;
    if (sphere_vertices.size() != positions || faces.empty() || faces.size() >= k_max_faces)
        return core::fail(core::ErrorCode::InvalidArgument,
                          name + ": " + std::to_string(sphere_vertices.size()) +
                              " sphere points, " + std::to_string(positions) + " positions and " +
                              std::to_string(faces.size()) +
                              " faces (need equal counts and 1 .. 2^24 - 1 faces)");
    for (const auto& f : faces)
        for (const std::uint32_t v : f)
            if (v >= sphere_vertices.size())
                return core::fail(core::ErrorCode::InvalidArgument,
                                  name + ": face index " + std::to_string(v) + " out of range");
    for (const auto& d : domain_sphere)
        if (d.level() != grid.level())
            return core::fail(core::ErrorCode::InvalidArgument,
                              name + ": domain map of another level");
    if (!gl::is_loaded())
        return core::fail(core::ErrorCode::GraphicsError,
                          name + ": no OpenGL context (create an OffscreenContext first)");
    return {};
}

/// The chord mesh uploaded with its clip coordinates in every view (and, for the look-up, the
/// original positions as colours), drawn one view at a time into an RGBA32F framebuffer whose
/// alpha is the triangle id + 1.
class ChordViews
{
public:
    ChordViews(const ChordViews&) = delete;
    ChordViews& operator=(const ChordViews&) = delete;
    ChordViews(ChordViews&&) = delete;
    ChordViews& operator=(ChordViews&&) = delete;

    /// \param colours 3 floats per vertex, or empty (every colour 0: only the ids are read).
    static core::Result<std::unique_ptr<ChordViews>> create(
        std::span<const View> views, int k, int w, std::span<const Vec3> sphere_vertices,
        std::span<const float> colours, std::span<const std::array<std::uint32_t, 3>> faces)
    {
        const int n_px = k * w + 1;
        const std::size_t nv = sphere_vertices.size();
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
        auto program =
            Program::create(shaders::k_sample_vert, shaders::k_sample_frag, "gpu sampler");
        if (!program)
            return program.error();
        auto fb = Framebuffer::create(n_px, n_px, PixelFormat::Rgba32f);
        if (!fb)
            return fb.error();
        std::unique_ptr<ChordViews> c(
            new ChordViews(std::move(*program), std::move(*fb), nv, faces.size()));
        gl::glGenVertexArrays(1, &c->vao_);
        gl::glBindVertexArray(c->vao_);
        gl::glGenBuffers(3, c->buffers_.data());
        const std::vector<float> zeros(colours.empty() ? nv * 3 : 0, 0.0F);
        const std::span<const float> rgb =
            colours.empty() ? std::span<const float>(zeros) : colours;
        gl::glBindBuffer(GL_ARRAY_BUFFER, c->buffers_[1]);
        gl::glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(rgb.size() * sizeof(float)),
                         rgb.data(), GL_STATIC_DRAW);
        gl::glEnableVertexAttribArray(1);
        gl::glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
        gl::glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, c->buffers_[2]);
        gl::glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                         static_cast<GLsizeiptr>(faces.size() * sizeof(faces[0])), faces.data(),
                         GL_STATIC_DRAW);
        gl::glBindBuffer(GL_ARRAY_BUFFER, c->buffers_[0]);
        gl::glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(clip.size() * sizeof(float)),
                         clip.data(), GL_STATIC_DRAW);
        gl::glEnableVertexAttribArray(0);
        gl::glUseProgram(c->program_.id());
        c->fb_.bind();
        gl::glClearColor(0.0F, 0.0F, 0.0F, 0.0F);
        gl::glEnable(GL_DEPTH_TEST);
        gl::glDepthMask(GL_TRUE);
        return c;
    }

    ~ChordViews()
    {
        gl::glDepthFunc(GL_LEQUAL);
        gl::glBindVertexArray(0);
        gl::glBindBuffer(GL_ARRAY_BUFFER, 0);
        gl::glDeleteBuffers(3, buffers_.data());
        gl::glDeleteVertexArrays(1, &vao_);
        gl::glUseProgram(0);
        gl::glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }

    /// Draws view `view`. Every fragment has depth ½ (z = 0): GL_LESS keeps the first triangle
    /// drawn over a pixel, GL_LEQUAL the last.
    void draw(std::size_t view, GLenum depth_func) const
    {
        gl::glDepthFunc(depth_func);
        gl::glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        gl::glVertexAttribPointer(
            0, 4, GL_FLOAT, GL_FALSE, 0,
            reinterpret_cast<const void*>(view * nv_ * 4 * sizeof(float)));  // NOLINT
        gl::glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(faces_ * 3), GL_UNSIGNED_INT,
                           nullptr);
    }

private:
    ChordViews(Program program, Framebuffer fb, std::size_t nv, std::size_t faces)
        : program_(std::move(program)), fb_(std::move(fb)), nv_(nv), faces_(faces)
    {
    }

    Program program_;
    Framebuffer fb_;
    std::size_t nv_ = 0;
    std::size_t faces_ = 0;
    GLuint vao_ = 0;
    std::array<GLuint, 3> buffers_{};  // clip coordinates, colours, indices
};

/// The domain tetrahedron from the grid's four corner nodes; its faces are the views.
std::array<View, 4> domain_views(const core::TetraGrid& grid,
                                 const core::Vec3Field<double>& domain_sphere)
{
    const auto c = grid.corners();
    std::array<Vec3, 4> corner;
    for (std::size_t i = 0; i < 4; ++i)
        corner[i] = {domain_sphere[0][c[i]], domain_sphere[1][c[i]], domain_sphere[2][c[i]]};
    return {make_view(corner[0], corner[1], corner[2]), make_view(corner[0], corner[2], corner[3]),
            make_view(corner[1], corner[0], corner[3]), make_view(corner[1], corner[3], corner[2])};
}

void sort_rows(std::array<std::vector<Entry>, 4>& entries)
{
    for (auto& e : entries)
        std::sort(e.begin(), e.end(),
                  [](const Entry& a, const Entry& b)
                  { return a.y != b.y ? a.y < b.y : a.x < b.x; });
}

core::Error hole(const core::TetraGrid& grid, const Entry& en, std::size_t view, const char* who)
{
    const core::GridCoord g = grid.coord(en.node);
    return {core::ErrorCode::GraphicsError,
            std::string(who) + ": node (" + std::to_string(g.x) + ", " + std::to_string(g.y) +
                ") got no sample (view " + std::to_string(view) + ", pixel " +
                std::to_string(en.x) + ", " + std::to_string(en.y) +
                "): no triangle covered its ray"};
}

/// The four views and their size: k pixels per cell (the setting, or automatic: views of about
/// 1025 pixels, where the snapping error falls to float32's; docs/remesh.md, measured on spot),
/// n_px = k·W + 1 pixels square.
struct Views
{
    int k = 1;
    int n_px = 1;
    std::array<View, 4> views;
};

Views views_of(const core::TetraGrid& grid, const core::Vec3Field<double>& domain_sphere,
               const GpuSamplerSettings& settings)
{
    const int w = grid.w();
    const int k =
        settings.pixels_per_cell > 0 ? settings.pixels_per_cell : std::clamp(1024 / w, 1, 64);
    return {k, k * w + 1, domain_views(grid, domain_sphere)};
}

void report(GpuSampleStats* stats, const Views& vs, std::size_t samples, std::size_t overlaps,
            std::chrono::steady_clock::time_point start)
{
    if (stats == nullptr)
        return;
    stats->views = static_cast<int>(vs.views.size());
    stats->viewport = vs.n_px;
    stats->pixels_per_cell = vs.k;
    stats->samples = samples;
    stats->overlaps = overlaps;
    stats->seconds_render =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

core::Result<core::Vec3Field<double>> sample_on_gpu(
    const core::TetraGrid& grid, const core::Vec3Field<double>& domain_sphere,
    std::span<const core::Vec3> sphere_vertices, std::span<const core::Vec3> original_positions,
    std::span<const std::array<std::uint32_t, 3>> faces, const GpuSamplerSettings& settings,
    GpuSampleStats* stats)
{
    const auto start = std::chrono::steady_clock::now();
    if (auto ok = check_inputs(grid, domain_sphere, sphere_vertices, original_positions.size(),
                               faces, "sample_on_gpu");
        !ok)
        return ok.error();
    const Views vs = views_of(grid, domain_sphere, settings);
    const int w = grid.w();
    const int k = vs.k;
    const std::array<View, 4>& views = vs.views;

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
            const Placement pl =
                place(views, {domain_sphere[0][n], domain_sphere[1][n], domain_sphere[2][n]});
            const double si = pl.s * wd, sj = pl.t * wd;
            const double ri = std::round(si), rj = std::round(sj);
            if (!(pl.score >= -k_lattice_tolerance) || std::abs(si - ri) > k_lattice_tolerance ||
                std::abs(sj - rj) > k_lattice_tolerance || ri + rj > wd)
                return invalid(
                    "the sphere point of node (" + std::to_string(x) + ", " + std::to_string(y) +
                    ") is not a lattice point of the domain tetrahedron (the colour look-up "
                    "needs the gnomonic domain map, core::SphereMap::Gnomonic; locate_on_gpu "
                    "takes any)");
            entries[pl.view].push_back({n, k * static_cast<int>(ri), k * static_cast<int>(rj)});
        }
    sort_rows(entries);

    // Colours relative to the bounding-box centre: float32 then rounds relative to the size of
    // the object, not to its distance from the origin.
    Vec3 lo = original_positions[0], hi = original_positions[0];
    for (const Vec3& q : original_positions)
    {
        lo = {std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
        hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
    }
    const Vec3 centre = (lo + hi) * 0.5;
    std::vector<float> colours(sphere_vertices.size() * 3);
    for (std::size_t v = 0; v < sphere_vertices.size(); ++v)
    {
        const Vec3 q = original_positions[v] - centre;
        colours[3 * v] = static_cast<float>(q.x);
        colours[3 * v + 1] = static_cast<float>(q.y);
        colours[3 * v + 2] = static_cast<float>(q.z);
    }
    auto scene = ChordViews::create(views, k, w, sphere_vertices, colours, faces);
    if (!scene)
        return scene.error();

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
            (*scene)->draw(v, GL_LESS);
            read_entries(entries[v], row, first_pass);
        }
        (*scene)->draw(v, GL_LEQUAL);
        read_entries(entries[v], row, last_pass);
        for (std::size_t e = 0; e < entries[v].size(); ++e)
        {
            const float* px = last_pass.data() + e * 4;
            const Entry& en = entries[v][e];
            if (!(px[3] >= 1.0F) || !std::isfinite(px[0]) || !std::isfinite(px[1]) ||
                !std::isfinite(px[2]))
                return hole(grid, en, v, "sample_on_gpu");
            if (settings.check_overlaps && first_pass[e * 4 + 3] != px[3])
                ++overlaps;
            out[0][en.node] = static_cast<double>(px[0]) + centre.x;
            out[1][en.node] = static_cast<double>(px[1]) + centre.y;
            out[2][en.node] = static_cast<double>(px[2]) + centre.z;
            ++samples;
        }
    }
    scene->reset();
    for (auto& f : out)
        core::sync_twins(grid, f);
    report(stats, vs, samples, overlaps, start);
    return out;
}

core::Result<std::vector<std::uint32_t>> locate_on_gpu(
    const core::TetraGrid& grid, const core::Vec3Field<double>& domain_sphere,
    std::span<const core::Vec3> sphere_vertices,
    std::span<const std::array<std::uint32_t, 3>> faces, const GpuSamplerSettings& settings,
    GpuSampleStats* stats)
{
    const auto start = std::chrono::steady_clock::now();
    if (auto ok = check_inputs(grid, domain_sphere, sphere_vertices, sphere_vertices.size(), faces,
                               "locate_on_gpu");
        !ok)
        return ok.error();
    const Views vs = views_of(grid, domain_sphere, settings);
    const int w = grid.w();
    const int k = vs.k;
    const int n_px = vs.n_px;
    const std::array<View, 4>& views = vs.views;

    // Each canonical node reads the pixel its ray passes through (window coordinates k·W·s + ½,
    // k·W·t + ½), in the view whose cone holds it most centrally.
    std::array<std::vector<Entry>, 4> entries;
    const double kw = static_cast<double>(k) * static_cast<double>(w);
    const auto pixel = [n_px](double window)
    { return std::clamp(static_cast<int>(std::floor(window)), 0, n_px - 1); };
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const core::NodeIndex n = grid.index(x, y);
            if (!grid.is_canonical(n))
                continue;
            const Vec3 p{domain_sphere[0][n], domain_sphere[1][n], domain_sphere[2][n]};
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                return invalid("the sphere point of node (" + std::to_string(x) + ", " +
                               std::to_string(y) + ") is not finite");
            const Placement pl = place(views, p);
            entries[pl.view].push_back({n, pixel(kw * pl.s + 0.5), pixel(kw * pl.t + 0.5)});
        }
    sort_rows(entries);
    auto scene = ChordViews::create(views, k, w, sphere_vertices, {}, faces);
    if (!scene)
        return scene.error();

    std::vector<std::uint32_t> out(grid.node_count(), 0);
    std::size_t samples = 0;
    std::vector<float> row, pass;
    for (std::size_t v = 0; v < views.size(); ++v)
    {
        if (entries[v].empty())
            continue;
        (*scene)->draw(v, GL_LEQUAL);
        read_entries(entries[v], row, pass);
        for (std::size_t e = 0; e < entries[v].size(); ++e)
        {
            const float id = pass[e * 4 + 3];
            if (!(id >= 1.0F) || !(id <= static_cast<float>(faces.size())))
                return hole(grid, entries[v][e], v, "locate_on_gpu");
            out[entries[v][e].node.value] = static_cast<std::uint32_t>(id) - 1U;
            ++samples;
        }
    }
    scene->reset();
    for (const core::TwinPair& t : grid.twins())
        out[t.twin.value] = out[t.canonical.value];
    report(stats, vs, samples, 0, start);
    return out;
}

}  // namespace pliant::render
