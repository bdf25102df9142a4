// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Untangling folded samples (design in include/pliant/remesh/untangle.h).

#include <pliant/remesh/intersections.h>
#include <pliant/remesh/untangle.h>

#include "remesh/locate_internal.h"
#include "remesh/sphere_geometry_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace pliant::remesh
{
namespace
{

using core::Vec3;
using detail::Location;
using detail::Locator;

Vec3 at(const core::Vec3Field<double>& f, core::NodeIndex n) noexcept
{
    return {f[0][n], f[1][n], f[2][n]};
}

/// Faces under `points`, located in blocks of unique vertices (each walk starts at face 0 and
/// continues from the previous vertex), so the result does not depend on the thread count.
std::vector<std::uint32_t> locate_all(const Locator& locator, std::span<const Vec3> points)
{
    constexpr std::size_t k_block = 512;
    const auto n = static_cast<std::int64_t>(points.size());
    std::vector<std::uint32_t> faces(points.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t b = 0; b < n; b += static_cast<std::int64_t>(k_block))
    {
        SampleStats stats;
        std::uint32_t hint = 0;
        const auto end = std::min(n, b + static_cast<std::int64_t>(k_block));
        for (std::int64_t i = b; i < end; ++i)
        {
            hint = locator.locate(points[static_cast<std::size_t>(i)], hint, stats).face;
            faces[static_cast<std::size_t>(i)] = hint;
        }
    }
    return faces;
}

/// Neighbours of every vertex of a closed triangle mesh, as CSR.
struct Neighbours
{
    std::vector<std::uint32_t> offsets;
    std::vector<std::uint32_t> ids;
    [[nodiscard]] std::span<const std::uint32_t> of(std::uint32_t v) const noexcept
    {
        return {ids.data() + offsets[v], ids.data() + offsets[v + 1]};
    }
};

/// The neighbours of each vertex, ascending: each face adds its other two vertices to each of
/// its vertices' rows (bucketed by vertex, so linear in the faces), and a row is then sorted and
/// its repeats dropped. A sort of all 6F directed edges took 1.5 s at level 10 (4M faces).
Neighbours neighbours(std::size_t n, std::span<const mesh::Face> faces)
{
    std::vector<std::uint32_t> start(n + 1, 0);
    for (const auto& t : faces)
        for (const std::uint32_t v : t)
            start[v + 1] += 2;
    for (std::size_t i = 0; i < n; ++i)
        start[i + 1] += start[i];
    std::vector<std::uint32_t> all(start[n]);
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (const auto& t : faces)
        for (std::size_t k = 0; k < 3; ++k)
        {
            all[fill[t[k]]++] = t[(k + 1) % 3];
            all[fill[t[k]]++] = t[(k + 2) % 3];
        }
    Neighbours nb;
    nb.offsets.assign(n + 1, 0);
    nb.ids.reserve(all.size() / 2);
    for (std::size_t v = 0; v < n; ++v)
    {
        const auto first = all.begin() + start[v];
        const auto last = all.begin() + start[v + 1];
        std::sort(first, last);
        nb.ids.insert(nb.ids.end(), first, std::unique(first, last));
        nb.offsets[v + 1] = static_cast<std::uint32_t>(nb.ids.size());
    }
    return nb;
}

/// The eight directions of a compass search in the sphere's tangent plane at a point, and the
/// trial points a step h along them.
struct Compass
{
    Vec3 t1;
    Vec3 t2;

    explicit Compass(const Vec3& at)
    {
        const Vec3 helper = std::abs(at.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
        t1 = core::normalized(core::cross(at, helper));
        t2 = core::cross(at, t1);
    }
    /// The point a step h from s0 in direction k (0..7, 45 degrees apart), back on the sphere.
    [[nodiscard]] Vec3 point(const Vec3& s0, int k, double h) const
    {
        const double angle = 0.7853981633974483 * k;
        return core::normalized(s0 + (t1 * std::cos(angle) + t2 * std::sin(angle)) * h);
    }
};

}  // namespace

std::vector<std::uint32_t> locate_samples(const core::TetraGrid& grid,
                                          const core::Vec3Field<double>& points,
                                          const mesh::TriMesh& mesh,
                                          std::span<const core::Vec3> sphere)
{
    const auto nodes = grid.node_of_unique();
    std::vector<Vec3> s(nodes.size());
    for (std::size_t u = 0; u < nodes.size(); ++u)
        s[u] = at(points, nodes[u]);
    return locate_all(Locator(mesh.faces, sphere), s);
}

namespace
{

/// Output faces by the cells of a uniform grid their boxes overlap (brought up to date every
/// round; faces that moved since are found a round late, by the global check).
class FaceHash
{
public:
    FaceHash(const mesh::TriMesh& m, double cell) : h_(cell)
    {
        for (std::uint32_t f = 0; f < m.faces.size(); ++f)
            add(m, f, cells_);
        std::sort(cells_.begin(), cells_.end(), before);
    }

    /// As if built again from `m`, where only the faces with `moved[f] != 0` changed: their
    /// entries are replaced, the others kept (the same entries in the same order as a new
    /// build, for a fraction of its sort).
    void update(const mesh::TriMesh& m, std::span<const std::uint8_t> moved)
    {
        std::erase_if(cells_, [&](const Entry& e) { return moved[e.face] != 0; });
        std::vector<Entry> fresh;
        for (std::uint32_t f = 0; f < m.faces.size(); ++f)
            if (moved[f] != 0)
                add(m, f, fresh);
        std::sort(fresh.begin(), fresh.end(), before);
        const auto middle = static_cast<std::ptrdiff_t>(cells_.size());
        cells_.insert(cells_.end(), fresh.begin(), fresh.end());
        std::inplace_merge(cells_.begin(), cells_.begin() + middle, cells_.end(), before);
    }

    static std::array<Vec3, 2> box(const mesh::TriMesh& m, std::uint32_t f) noexcept
    {
        const Vec3& a = m.positions[m.faces[f][0]];
        const Vec3& b = m.positions[m.faces[f][1]];
        const Vec3& c = m.positions[m.faces[f][2]];
        return {
            Vec3{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})},
            Vec3{std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})}};
    }

    /// Faces whose registered cells overlap the box [lo, hi], sorted, without repeats.
    void query(const Vec3& lo, const Vec3& hi, std::vector<std::uint32_t>& out) const
    {
        out.clear();
        for_cells(lo, hi,
                  [&](std::uint64_t key)
                  {
                      auto it = std::lower_bound(cells_.begin(), cells_.end(), key,
                                                 [](const Entry& e, std::uint64_t k)
                                                 { return e.key < k; });
                      for (; it != cells_.end() && it->key == key; ++it)
                          out.push_back(it->face);
                  });
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }

private:
    struct Entry
    {
        std::uint64_t key;
        std::uint32_t face;
    };
    static bool before(const Entry& a, const Entry& b) noexcept
    {
        return a.key != b.key ? a.key < b.key : a.face < b.face;
    }
    void add(const mesh::TriMesh& m, std::uint32_t f, std::vector<Entry>& to) const
    {
        const auto [lo, hi] = box(m, f);
        for_cells(lo, hi, [&](std::uint64_t key) { to.push_back({key, f}); });
    }

    template <class F>
    void for_cells(const Vec3& lo, const Vec3& hi, F&& f) const
    {
        const auto c = [this](double v) { return static_cast<std::int64_t>(std::floor(v / h_)); };
        const std::int64_t x0 = c(lo.x), x1 = c(hi.x), y0 = c(lo.y), y1 = c(hi.y), z0 = c(lo.z),
                           z1 = c(hi.z);
        if (x1 - x0 > 64 || y1 - y0 > 64 || z1 - z0 > 64)
            return;  // a face far larger than the cells: left to the global check
        for (std::int64_t x = x0; x <= x1; ++x)
            for (std::int64_t y = y0; y <= y1; ++y)
                for (std::int64_t z = z0; z <= z1; ++z)
                {
                    // a hash of the cell (collisions only add candidates)
                    const auto ux = static_cast<std::uint64_t>(x) & 0x1fffffU;
                    const auto uy = static_cast<std::uint64_t>(y) & 0x1fffffU;
                    const auto uz = static_cast<std::uint64_t>(z) & 0x1fffffU;
                    f((ux << 42) | (uy << 21) | uz);
                }
    }

    double h_;
    std::vector<Entry> cells_;
};

}  // namespace

core::Result<UntangleStats> untangle_samples(const core::TetraGrid& grid, const mesh::TriMesh& mesh,
                                             std::span<const core::Vec3> sphere,
                                             core::Vec3Field<double>& points,
                                             core::Vec3Field<double>& positions,
                                             const UntangleSettings& settings,
                                             core::ProgressSink* progress)
{
    // The patch passes halve epsilon from start down to end: an end of 0 (or a start of inf)
    // would never get there.
    if (!std::isfinite(settings.patch_epsilon_start) ||
        !std::isfinite(settings.patch_epsilon_end) ||
        !(settings.patch_epsilon_end > 0.0 &&
          settings.patch_epsilon_end <= settings.patch_epsilon_start))
        return core::fail(core::ErrorCode::InvalidArgument,
                          "untangle_samples: patch_epsilon_start " +
                              std::to_string(settings.patch_epsilon_start) +
                              " and patch_epsilon_end " +
                              std::to_string(settings.patch_epsilon_end) +
                              " must be finite with 0 < end <= start");
    const auto nodes = grid.node_of_unique();
    const std::size_t nu = nodes.size();
    const Locator locator(mesh.faces, sphere);
    std::vector<Vec3> s(nu);
    mesh::TriMesh out;
    out.positions.resize(nu);
    out.faces = grid.triangles();
    for (std::size_t u = 0; u < nu; ++u)
    {
        s[u] = at(points, nodes[u]);
        out.positions[u] = at(positions, nodes[u]);
    }
    std::vector<std::uint32_t> face = locate_all(locator, s);
    if (core::stop_requested(progress))
        return core::cancelled("remesh", "untangle");
    const Neighbours nb = neighbours(nu, out.faces);
    const detail::VertexFaces star = detail::vertex_faces(nu, out.faces);
    if (core::stop_requested(progress))
        return core::cancelled("remesh", "untangle");
    std::vector<Vec3> input_normal(mesh.faces.size());
    for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    {
        const auto& t = mesh.faces[f];
        input_normal[f] =
            core::normalized(core::cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                                         mesh.positions[t[2]] - mesh.positions[t[0]]));
    }
    double mean_edge = 0.0;
    for (const auto& t : out.faces)
        mean_edge += core::norm(out.positions[t[1]] - out.positions[t[0]]);
    mean_edge /= static_cast<double>(out.faces.size());

    // Quality of output face f: its signed area against the input's normal at its samples (the
    // most favourable of the three), over the sum of its squared edges (scale-free; at most
    // sqrt(3)/12 ~ 0.144, for an equilateral triangle on the input; negative when folded, as
    // is_folded counts). A star's quality is its worst face's.
    const auto quality = [&](std::uint32_t f)
    {
        const auto& t = out.faces[f];
        const Vec3 &a = out.positions[t[0]], &b = out.positions[t[1]], &c = out.positions[t[2]];
        const double e =
            core::dot(b - a, b - a) + core::dot(c - b, c - b) + core::dot(a - c, a - c);
        if (!(e > 0.0))
            return 0.0;
        const Vec3 n = core::cross(b - a, c - a);
        const double d = std::max({core::dot(n, input_normal[face[t[0]]]),
                                   core::dot(n, input_normal[face[t[1]]]),
                                   core::dot(n, input_normal[face[t[2]]])});
        return 0.5 * d / e;
    };
    // A vertex's score: crossings of its star's faces with each other and with the faces near
    // them (fewer is better), then the star's quality (higher is better).
    struct Score
    {
        std::size_t crossings = 0;
        double quality = 0.0;
        [[nodiscard]] bool better_than(const Score& o) const noexcept
        {
            return crossings != o.crossings ? crossings < o.crossings : quality > o.quality;
        }
    };
    // The faces near the node being relaxed (relax fills them): those of its star, and the
    // others with their boxes, which stay put while only that node moves.
    std::vector<std::uint32_t> near;
    std::vector<std::uint32_t> near_star;
    std::vector<std::uint32_t> near_other;
    std::vector<std::array<Vec3, 2>> near_other_box;
    const auto star_quality = [&](std::uint32_t v)
    {
        double q = std::numeric_limits<double>::infinity();
        for (const std::uint32_t f : star.of(v))
            q = std::min(q, quality(f));
        return q;
    };
    const auto overlap = [](const std::array<Vec3, 2>& a, const std::array<Vec3, 2>& b)
    {
        return !(a[1].x < b[0].x || b[1].x < a[0].x || a[1].y < b[0].y || b[1].y < a[0].y ||
                 a[1].z < b[0].z || b[1].z < a[0].z);
    };
    // Crossings of the relaxed node v's star with the near faces (relax sets them), each pair
    // inside the star once; counting stops above `cap` (a count up to `cap` is exact).
    const auto crossings = [&](std::uint32_t v, std::size_t cap)
    {
        std::size_t count = 0;
        const auto faces = star.of(v);
        for (std::size_t i = 0; i < faces.size() && count <= cap; ++i)
        {
            const auto bi = FaceHash::box(out, faces[i]);
            for (const std::uint32_t g : near_star)  // moved with v: boxes taken now
                if (g > faces[i] && overlap(bi, FaceHash::box(out, g)) &&
                    faces_intersect(out, faces[i], g, false))
                    ++count;
            for (std::size_t k = 0; k < near_other.size(); ++k)
                if (overlap(bi, near_other_box[k]) &&
                    faces_intersect(out, faces[i], near_other[k], false))
                    ++count;
        }
        return count;
    };
    const auto score = [&](std::uint32_t v, std::size_t cap) {
        return Score{crossings(v, cap), star_quality(v)};
    };

    std::vector<std::uint8_t> moved(nu, 0);
    SampleStats walk;
    std::optional<FaceHash> hash;
    // Tries sample point sn for vertex v; keeps it if `accept(new score)` says so.
    const auto try_move = [&](std::uint32_t v, const Vec3& sn, const auto& accept)
    {
        const Vec3 s_old = s[v], p_old = out.positions[v];
        const std::uint32_t f_old = face[v];
        const Location loc = locator.locate(sn, f_old, walk);
        s[v] = sn;
        face[v] = loc.face;
        out.positions[v] = detail::interpolate(mesh, loc);
        if (accept(v))
        {
            moved[v] = 1;
            return true;
        }
        s[v] = s_old;
        face[v] = f_old;
        out.positions[v] = p_old;
        return false;
    };

    // Barrier energy of v's star: the number of its folded faces first (at the rounds' eps 0.02 a
    // move never folds more of them; at the patch passes' eps 0.000625 one badly folded face,
    // q < -0.098, outweighs a fold, and the pass's global check bounds the result), then the sum
    // over its faces of 1 / chi(q), q the face's quality and chi(q) = (q + sqrt(q^2 + eps^2)) / 2,
    // a smooth stand-in for max(q, 0) (the untangling energy of Garanzha et al. 2021,
    // "Foldover-free maps in 50 lines of code"). It is finite for a folded face (about 4|q| /
    // eps^2: at most about 1,450 at eps 0.02, as q >= -0.144), so a folded star has a slope to
    // follow towards positive areas, and it rises steeply as a face of positive area flattens.
    // Unlike the worst face's quality, the sum sees every face of the star, so a node can trade a
    // little of one face for a lot of another. Measured on fox: without the fold count first (the
    // barrier alone, eps 0.02) untangling ended with more folds than before (level 5: 11 against
    // 6), the sum preferring slightly folded slivers to worse-shaped neighbours.
    constexpr double k_fold_cost = 1e6;     // more than a star's barrier sum at eps 0.02
    double eps = settings.barrier_epsilon;  // the patch passes shrink it
    const auto energy = [&](std::uint32_t v)
    {
        double e = 0.0;
        for (const std::uint32_t f : star.of(v))
        {
            const double q = quality(f);
            e += 2.0 / (q + std::sqrt(q * q + eps * eps)) + (q > 0.0 ? 0.0 : k_fold_cost);
        }
        return e;
    };
    // Compass search on the sphere for the lowest barrier energy of v's star, keeping it free of
    // crossings and within reach of its ring's centre c; the energy is checked first (cheap), the
    // crossings only for the best candidate of a step.
    const auto descend = [&](std::uint32_t v, const Vec3& c, double reach2, double lim)
    {
        const Compass compass(s[v]);
        double h = 0.25 * lim;
        double e0 = energy(v);
        std::array<std::pair<double, int>, 8> cand{};
        for (int iter = 0; iter < settings.barrier_steps && h > lim / 256.0; ++iter)
        {
            const Vec3 s0 = s[v];
            std::size_t n = 0;
            for (int k = 0; k < 8; ++k)
            {
                const Vec3 sn = compass.point(s0, k, h);
                try_move(v, sn,
                         [&](std::uint32_t w)
                         {
                             const Vec3 dn = c - out.positions[w];
                             if (core::dot(dn, dn) <= reach2)
                             {
                                 const double e = energy(w);
                                 if (e < e0)
                                     cand[n++] = {e, k};
                             }
                             return false;  // evaluated only
                         });
            }
            std::sort(cand.begin(), cand.begin() + static_cast<std::ptrdiff_t>(n));
            bool moved_here = false;
            for (std::size_t i = 0; i < n && !moved_here; ++i)
            {
                const Vec3 sn = compass.point(s0, cand[i].second, h);
                moved_here = try_move(v, sn,
                                      [&](std::uint32_t w)
                                      {
                                          if (crossings(w, 0) != 0)
                                              return false;
                                          e0 = cand[i].first;
                                          return true;
                                      });
            }
            if (!moved_here)
                h *= 0.5;
        }
    };

    // One step for vertex v: Laplacian smoothing on the input surface (a few Newton steps towards
    // the mean c of its neighbours through the inverse of the affine map of the input face under
    // the sample point, with backtracking: the map changes from face to face, by orders of
    // magnitude where the parameterisation is anisotropic), never making its star worse; then,
    // if the star still crosses something or is folded, a compass search on the sphere for the
    // best score (untangling in the spirit of Freitag & Plassmann 2000).
    // `patch`: the barrier descent alone (the patch passes below), else smoothing and untangling
    const auto relax = [&](std::uint32_t v, bool patch)
    {
        const auto ring = nb.of(v);
        Vec3 c{};
        double lim = std::numeric_limits<double>::infinity();
        for (const std::uint32_t w : ring)
        {
            c += out.positions[w];
            lim = std::min(lim, core::norm(s[w] - s[v]));
        }
        c = c / static_cast<double>(ring.size());
        // the node stays within reach of its ring's centre
        double reach2 = 0.0;
        for (const std::uint32_t w : ring)
            reach2 = std::max(reach2, core::dot(out.positions[w] - c, out.positions[w] - c));
        reach2 *= settings.reach * settings.reach;
        const double r = std::sqrt(reach2);
        Vec3 lo = c - Vec3{r, r, r}, hi = c + Vec3{r, r, r};
        for (const std::uint32_t w : ring)
        {
            const Vec3& p = out.positions[w];
            lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
        hash->query(lo, hi, near);
        std::erase_if(near,
                      [&](std::uint32_t g)
                      {
                          const auto bg = FaceHash::box(out, g);
                          return bg[1].x < lo.x || hi.x < bg[0].x || bg[1].y < lo.y ||
                                 hi.y < bg[0].y || bg[1].z < lo.z || hi.z < bg[0].z;
                      });
        near_star.clear();
        near_other.clear();
        near_other_box.clear();
        const auto own = star.of(v);
        for (const std::uint32_t g : near)
            if (std::find(own.begin(), own.end(), g) != own.end())
                near_star.push_back(g);
            else
            {
                near_other.push_back(g);
                near_other_box.push_back(FaceHash::box(out, g));
            }
        if (patch)
        {
            descend(v, c, reach2, lim);
            return;
        }
        Score current = score(v, std::numeric_limits<std::size_t>::max());
        for (int newton = 0; newton < 2; ++newton)
        {
            const Vec3 d = c - out.positions[v];
            const double dist2 = core::dot(d, d);
            const auto& t = mesh.faces[face[v]];
            const Vec3 &q0 = sphere[t[0]], &q1 = sphere[t[1]], &q2 = sphere[t[2]];
            const Vec3 n = core::cross(q1 - q0, q2 - q0);
            const double den = core::dot(n, s[v]);
            if (!(den > 0.0))
                break;
            const Vec3 x = s[v] * (core::dot(n, q0) / den);  // on the chord triangle
            // least-squares tangent move: a E1 + b E2 closest to c − p in the face's plane
            const Vec3 e1 = mesh.positions[t[1]] - mesh.positions[t[0]];
            const Vec3 e2 = mesh.positions[t[2]] - mesh.positions[t[0]];
            const double g00 = core::dot(e1, e1), g01 = core::dot(e1, e2), g11 = core::dot(e2, e2);
            const double det = g00 * g11 - g01 * g01;
            if (!(det > 1e-12 * g00 * g11))
                break;
            const double r0 = core::dot(e1, d), r1 = core::dot(e2, d);
            const double a = (g11 * r0 - g01 * r1) / det, b = (g00 * r1 - g01 * r0) / det;
            Vec3 dx = (q1 - q0) * a + (q2 - q0) * b;
            const double len = core::norm(dx);
            if (!(len > 0.0))
                break;
            if (len > 0.5 * lim)  // never jump over a neighbour's sphere point
                dx *= 0.5 * lim / len;
            bool accepted = false;
            for (int half = 0; half < 6 && !accepted; ++half, dx *= 0.5)
                accepted = try_move(v, core::normalized(x + dx),
                                    [&](std::uint32_t w)
                                    {
                                        const Vec3 dn = c - out.positions[w];
                                        if (!(core::dot(dn, dn) < dist2))
                                            return false;
                                        const double q = star_quality(w);
                                        if (q < std::min(current.quality, settings.min_quality))
                                            return false;
                                        const std::size_t cross = crossings(w, current.crossings);
                                        if (cross > current.crossings)
                                            return false;
                                        current = Score{cross, q};
                                        return true;
                                    });
            if (!accepted)
                break;
        }
        // only a star that crosses something or is folded searches further
        if (current.crossings == 0 && current.quality > 0.0)
            return;
        const Compass compass(s[v]);
        double h = 0.5 * lim;
        for (int iter = 0; iter < 12 && h > lim / 128.0; ++iter)
        {
            if (current.crossings == 0 && current.quality >= settings.min_quality)
                break;  // untangled, and not a sliver
            const Vec3 s0 = s[v];
            Score best = current;
            Vec3 best_s = s0;
            for (int k = 0; k < 8; ++k)
            {
                const Vec3 sn = compass.point(s0, k, h);
                try_move(v, sn,
                         [&](std::uint32_t w)
                         {
                             const Vec3 dn = c - out.positions[w];
                             if (!(core::dot(dn, dn) <= reach2))
                                 return false;
                             // Score::better_than without counting what cannot change the
                             // outcome: a candidate of no higher quality must cross less than
                             // the best, so counting stops there, and against a best that
                             // crosses nothing it cannot win at all (the folded stars' case,
                             // most of the search's candidates).
                             const double q = star_quality(w);
                             const bool higher = q > best.quality;
                             if (!higher && best.crossings == 0)
                                 return false;
                             const std::size_t cross =
                                 crossings(w, higher ? best.crossings : best.crossings - 1);
                             if (cross < best.crossings || (higher && cross == best.crossings))
                             {
                                 best = Score{cross, q};
                                 best_s = sn;
                             }
                             return false;  // evaluated only
                         });
            }
            if (best.better_than(current))
            {
                try_move(v, best_s, [](std::uint32_t) { return true; });
                current = best;
            }
            else
                h *= 0.5;
        }
        // a star still folded (its worst face's quality is no longer a guide: moving one fold
        // out of the way tends to fold another face) descends the barrier energy of all its
        // faces. Only folded stars do: descending every sliver-ish star near a fold moved
        // correct nodes far along the surface (cactus level 5: -5.5 dB, Hausdorff 3x).
        if (settings.barrier_epsilon > 0.0 && current.crossings == 0 && current.quality <= 0.0)
            descend(v, c, reach2, lim);
    };

    UntangleStats stats;
    std::vector<std::uint8_t> active(nu, 0);
    std::vector<std::uint32_t> list;
    // Progress: a sweep over the region (a round's or a patch pass's) is the unit, counted
    // against the most sweeps the settings allow (the bar jumps to the end when the surface is
    // untangled sooner); a stop is looked for every 64 nodes.
    int epsilons = 0;
    for (double e = settings.patch_epsilon_start; e >= 0.999 * settings.patch_epsilon_end; e *= 0.5)
        ++epsilons;
    const double units = std::max(1, settings.max_rounds * settings.sweeps +
                                         settings.patch_passes * epsilons * settings.patch_sweeps);
    double units_done = 0.0;
    bool stopped = false;
    // One Gauss-Seidel sweep over `list`; false when stopped.
    const auto sweep = [&](bool patch)
    {
        const auto n = static_cast<double>(list.size());
        for (std::size_t i = 0; i < list.size(); ++i)
        {
            if ((i & 63U) == 0 && progress != nullptr)
            {
                if (progress->stop_requested())
                {
                    stopped = true;
                    return false;
                }
                progress->update("untangle",
                                 std::min(0.99, (units_done + static_cast<double>(i) / n) / units));
            }
            relax(list[i], patch);
        }
        units_done += 1.0;
        return true;
    };
    // Grows the marked nodes (`active`) by `rings` rings of grid neighbours and lists them, in
    // node order, in `list`.
    const auto grow_region = [&](int rings)
    {
        for (int r = 0; r < rings; ++r)
        {
            list.clear();
            for (std::uint32_t v = 0; v < nu; ++v)
                if (active[v] == 1)
                    list.push_back(v);
            for (const std::uint32_t v : list)
                for (const std::uint32_t w : nb.of(v))
                    active[w] = 1;
        }
        list.clear();
        for (std::uint32_t v = 0; v < nu; ++v)
            if (active[v] != 0)
                list.push_back(v);
    };
    // The crossing pairs, recounted only around what moved: the pairs and positions of the last
    // count are kept, and a recount retests the pairs of the faces with a vertex moved since
    // (intersecting_pairs_touching); the others' answers cannot have changed. The same pairs
    // as a whole count, for a fraction of its time on large grids (a count of fox at level 9,
    // 1M faces, took 6.7 s; the rounds and passes count up to 11 times).
    std::vector<std::uint8_t> touched(out.faces.size(), 0);
    // Flags in `touched` the faces with a vertex moved since `at` was taken, and brings `at` up
    // to date; whether any moved.
    const auto moved_since = [&](std::vector<Vec3>& at)
    {
        std::fill(touched.begin(), touched.end(), std::uint8_t{0});
        bool any = false;
        for (std::size_t u = 0; u < nu; ++u)
            if (!(out.positions[u] == at[u]))
            {
                any = true;
                at[u] = out.positions[u];
                for (const std::uint32_t f : star.of(static_cast<std::uint32_t>(u)))
                    touched[f] = 1;
            }
        return any;
    };
    std::vector<std::array<std::uint32_t, 2>> pairs;
    std::vector<Vec3> counted_at;  // the positions of the last count
    const auto recount_pairs = [&]
    {
        if (counted_at.empty())
        {
            pairs = intersecting_pairs(out, progress);
            counted_at = out.positions;
            return;
        }
        if (!moved_since(counted_at))
            return;
        std::erase_if(pairs, [&](const std::array<std::uint32_t, 2>& pr)
                      { return touched[pr[0]] != 0 || touched[pr[1]] != 0; });
        const auto fresh = intersecting_pairs_touching(out, touched, progress);
        const auto middle = static_cast<std::ptrdiff_t>(pairs.size());
        pairs.insert(pairs.end(), fresh.begin(), fresh.end());
        std::inplace_merge(pairs.begin(), pairs.begin() + middle, pairs.end());
    };
    // The hash of faces for the near-face queries, likewise brought up to date around what moved
    // (a new build sorted the entries of every face, 8 % of fox's level-7 untangling).
    std::vector<Vec3> hashed_at;  // the positions of the hash
    const auto refresh_hash = [&]
    {
        if (!hash)
        {
            hash.emplace(out, 2.0 * mean_edge);
            hashed_at = out.positions;
        }
        else if (moved_since(hashed_at))
            hash->update(out, touched);
    };
    std::size_t best_total = std::numeric_limits<std::size_t>::max();
    int since_best = 0;
    for (int round = 0;; ++round)
    {
        std::fill(active.begin(), active.end(), std::uint8_t{0});
        std::size_t folded = 0;
        for (std::size_t f = 0; f < out.faces.size(); ++f)
            if (is_folded(out, f, mesh, face))
            {
                ++folded;
                for (const std::uint32_t v : out.faces[f])
                    active[v] = 1;
            }
        recount_pairs();
        if (core::stop_requested(progress))
            return core::cancelled("remesh", "untangle");  // the count may be incomplete
        for (const auto& pr : pairs)
            for (const std::uint32_t f : pr)
                for (const std::uint32_t v : out.faces[f])
                    active[v] = 1;
        if (round == 0)
        {
            stats.folded_sampled = folded;
            stats.intersections_sampled = pairs.size();
        }
        stats.folded = folded;
        stats.intersections = pairs.size();
        if (folded + pairs.size() < best_total)
        {
            best_total = folded + pairs.size();
            since_best = 0;
        }
        else
            ++since_best;
        if ((folded == 0 && pairs.empty()) || !settings.enabled || round >= settings.max_rounds ||
            since_best >= settings.patience)
            break;
        // grow the region by rings of grid neighbours: more rings as the rounds go on, so a
        // fold whose surroundings are not convex enough gets a wider patch
        grow_region(settings.rings + round / 4);
        refresh_hash();
        for (int k = 0; k < settings.sweeps && !stopped; ++k)
            sweep(false);
        if (stopped)
            return core::cancelled("remesh", "untangle");
        stats.rounds = round + 1;
    }

    // Patch passes, for folds the rounds left (fox's saddle patch): one node at a time, the rounds
    // stop where each star's move would fold one face to unfold another. Here the whole region of
    // folded faces plus `patch_rings` rings descends the barrier energy together, every node of it
    // (not only folded stars) for `patch_sweeps` Gauss-Seidel sweeps at each epsilon of a
    // shrinking schedule (Garanzha et al. 2021 shrink it as the map untangles): a wide barrier
    // first, so the slivers next to a fold have room to give, then a narrow one, as steep as the
    // quality measure near zero. A pass is kept only if the whole output then has fewer folded
    // faces plus crossing pairs and no more crossing pairs; otherwise the region gets its nodes
    // back and the passes stop. A mesh the rounds untangled never runs them, so its output keeps
    // its bytes. Measured on fox, levels 6 / 7 / 8: 8 / 17 / 102 folded triangles left by the
    // rounds -> 2 / 4 / 48, no crossing, for 1.4-1.8x the untangling time. Without the fold count
    // first (the barrier alone) every pass made more folds and was rejected (level 6: 8 -> 13).
    if (settings.enabled && settings.patch_passes > 0 && stats.folded > 0)
    {
        for (int pass = 0; pass < settings.patch_passes; ++pass)
        {
            std::fill(active.begin(), active.end(), std::uint8_t{0});
            for (std::size_t f = 0; f < out.faces.size(); ++f)
                if (is_folded(out, f, mesh, face))
                    for (const std::uint32_t v : out.faces[f])
                        active[v] = 1;
            grow_region(settings.patch_rings);
            std::vector<Vec3> s0(list.size()), p0(list.size());
            std::vector<std::uint32_t> f0(list.size());
            std::vector<std::uint8_t> m0(list.size());
            for (std::size_t i = 0; i < list.size(); ++i)
            {
                s0[i] = s[list[i]];
                p0[i] = out.positions[list[i]];
                f0[i] = face[list[i]];
                m0[i] = moved[list[i]];
            }
            for (eps = settings.patch_epsilon_start; eps >= 0.999 * settings.patch_epsilon_end;
                 eps *= 0.5)
            {
                refresh_hash();
                for (int k = 0; k < settings.patch_sweeps && !stopped; ++k)
                    sweep(true);
                if (stopped)
                    return core::cancelled("remesh", "untangle");
            }
            eps = settings.barrier_epsilon;
            std::size_t folded = 0;
            for (std::size_t f = 0; f < out.faces.size(); ++f)
                if (is_folded(out, f, mesh, face))
                    ++folded;
            recount_pairs();
            if (core::stop_requested(progress))
                return core::cancelled("remesh", "untangle");
            const std::size_t crossing = pairs.size();
            if (crossing <= stats.intersections &&
                folded + crossing < stats.folded + stats.intersections)
            {
                stats.folded = folded;
                stats.intersections = crossing;
                ++stats.patch_passes;
                if (folded == 0 && crossing == 0)
                    break;
                continue;
            }
            for (std::size_t i = 0; i < list.size(); ++i)
            {
                s[list[i]] = s0[i];
                out.positions[list[i]] = p0[i];
                face[list[i]] = f0[i];
                moved[list[i]] = m0[i];
            }
            break;
        }
    }

    for (std::size_t u = 0; u < nu; ++u)
        if (moved[u] != 0)
        {
            ++stats.moved_nodes;
            const core::NodeIndex n = nodes[u];
            points[0][n] = s[u].x;
            points[1][n] = s[u].y;
            points[2][n] = s[u].z;
            positions[0][n] = out.positions[u].x;
            positions[1][n] = out.positions[u].y;
            positions[2][n] = out.positions[u].z;
        }
    if (stats.moved_nodes > 0)
        for (std::size_t k = 0; k < 3; ++k)
        {
            core::sync_twins(grid, points[k]);
            core::sync_twins(grid, positions[k]);
        }
    return stats;
}

}  // namespace pliant::remesh
