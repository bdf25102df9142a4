// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Domain -> sphere and sampling (design in include/pliant/remesh/sample.h).

#include <pliant/core/sphere_domain.h>
#include <pliant/remesh/sample.h>

#include "remesh/sphere_geometry_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace pliant::remesh
{
namespace
{

using core::Vec3;

/// Face adjacency: neighbour of face f across edge (t[k], t[k+1]) at 3f+k.
std::vector<std::uint32_t> face_neighbours(std::span<const mesh::Face> faces)
{
    struct Half
    {
        std::uint64_t key;
        std::uint32_t slot;
    };
    std::vector<Half> halves;
    halves.reserve(faces.size() * 3);
    for (std::uint32_t f = 0; f < faces.size(); ++f)
        for (std::uint32_t k = 0; k < 3; ++k)
        {
            const std::uint64_t a = faces[f][k], b = faces[f][(k + 1) % 3];
            halves.push_back({(a << 32) | b, 3 * f + k});
        }
    std::vector<Half> sorted = halves;
    std::sort(sorted.begin(), sorted.end(),
              [](const Half& x, const Half& y) { return x.key < y.key; });
    std::vector<std::uint32_t> nb(faces.size() * 3, std::numeric_limits<std::uint32_t>::max());
    for (const Half& h : halves)
    {
        const std::uint64_t twin = (h.key >> 32) | (h.key << 32);
        const auto it = std::lower_bound(sorted.begin(), sorted.end(), twin,
                                         [](const Half& x, std::uint64_t k) { return x.key < k; });
        if (it != sorted.end() && it->key == twin)
            nb[h.slot] = it->slot / 3;
    }
    return nb;
}

/// Edge functions of p in face (a, b, c): e[k] = p·(t[k+1] × t[k+2]), all >= 0 inside.
struct Location
{
    std::uint32_t face = 0;
    std::array<double, 3> e{};
};

constexpr double k_edge_tolerance = 1e-14;

class Locator
{
public:
    Locator(std::span<const mesh::Face> faces, std::span<const Vec3> q)
        : faces_(faces), q_(q), nb_(face_neighbours(faces))
    {
    }

    [[nodiscard]] std::array<double, 3> edges(std::uint32_t f, const Vec3& p) const noexcept
    {
        const Vec3& a = q_[faces_[f][0]];
        const Vec3& b = q_[faces_[f][1]];
        const Vec3& c = q_[faces_[f][2]];
        return {core::dot(p, core::cross(b, c)), core::dot(p, core::cross(c, a)),
                core::dot(p, core::cross(a, b))};
    }

    /// Walk from `start`; falls back to a scan of every face after a bounded number of steps.
    Location locate(const Vec3& p, std::uint32_t start, SampleStats& stats) const noexcept
    {
        std::uint32_t f = start;
        const std::size_t max_steps =
            64 + 4 * static_cast<std::size_t>(std::sqrt(static_cast<double>(faces_.size())));
        std::uint32_t turn = 0;
        for (std::size_t step = 0; step < max_steps; ++step)
        {
            const auto e = edges(f, p);
            ++stats.walk_steps;
            // leave through a violated edge; rotate the starting edge so that a walk cannot
            // cycle forever through the same three edges (a "remembering stochastic" walk)
            std::uint32_t out = 3;
            for (std::uint32_t k = 0; k < 3; ++k)
            {
                const std::uint32_t kk = (k + turn) % 3;
                if (e[kk] < -k_edge_tolerance)
                {
                    out = kk;
                    break;
                }
            }
            if (out == 3)
                return {f, e};
            ++turn;
            // edge opposite vertex `out` is (t[out+1], t[out+2]) = slot (out+1)%3
            f = nb_[3 * f + (out + 1) % 3];
        }
        ++stats.brute_force;
        Location best{start, edges(start, p)};
        double best_score = -std::numeric_limits<double>::infinity();
        for (std::uint32_t g = 0; g < faces_.size(); ++g)
        {
            const auto e = edges(g, p);
            const double score = std::min({e[0], e[1], e[2]});
            if (score > best_score && e[0] + e[1] + e[2] > 0.0)
            {
                best_score = score;
                best = {g, e};
            }
        }
        return best;
    }

private:
    std::span<const mesh::Face> faces_;
    std::span<const Vec3> q_;
    std::vector<std::uint32_t> nb_;
};

}  // namespace

core::Vec3Field<double> domain_sphere(const core::TetraGrid& grid)
{
    return core::sphere_domain(grid, core::SphereMap::Gnomonic);
}

std::size_t count_inverted_domain(const core::TetraGrid& grid,
                                  const core::Vec3Field<double>& sphere)
{
    const auto nodes = grid.node_of_unique();
    std::size_t n = 0;
    for (const auto& t : grid.triangles())
    {
        std::array<Vec3, 3> p;
        for (std::size_t k = 0; k < 3; ++k)
        {
            const core::NodeIndex i = nodes[t[k]];
            p[k] = {sphere[0][i], sphere[1][i], sphere[2][i]};
        }
        if (!(detail::orient(p[0], p[1], p[2]) > 0.0))
            ++n;
    }
    return n;
}

core::Result<core::Vec3Field<double>> sample_surface(const core::TetraGrid& grid,
                                                     const core::Vec3Field<double>& domain,
                                                     const mesh::TriMesh& mesh,
                                                     std::span<const core::Vec3> sphere,
                                                     SampleStats* stats,
                                                     std::span<const std::uint32_t> start_faces)
{
    if (sphere.size() != mesh.positions.size() || mesh.faces.empty())
        return core::fail(core::ErrorCode::InvalidArgument,
                          "sample_surface: sphere map has " + std::to_string(sphere.size()) +
                              " points for " + std::to_string(mesh.positions.size()) + " vertices");
    if (domain[0].level() != grid.level())
        return core::fail(core::ErrorCode::InvalidArgument,
                          "sample_surface: domain map of another level");
    if (!start_faces.empty())
    {
        if (start_faces.size() != grid.node_count())
            return core::fail(core::ErrorCode::InvalidArgument,
                              "sample_surface: " + std::to_string(start_faces.size()) +
                                  " start faces for " + std::to_string(grid.node_count()) +
                                  " grid nodes");
        for (std::size_t n = 0; n < start_faces.size(); ++n)
            if (start_faces[n] >= mesh.faces.size())
            {
                const core::GridCoord c =
                    grid.coord(core::NodeIndex{static_cast<std::uint32_t>(n)});
                return core::fail(core::ErrorCode::InvalidArgument,
                                  "sample_surface: start face " + std::to_string(start_faces[n]) +
                                      " of node (" + std::to_string(c.x) + ", " +
                                      std::to_string(c.y) + ") is out of range (" +
                                      std::to_string(mesh.faces.size()) + " faces)");
            }
    }
    const Locator locator(mesh.faces, sphere);
    core::Vec3Field<double> out{core::Field<double>(grid), core::Field<double>(grid),
                                core::Field<double>(grid)};
    const int ny = grid.ny(), nx = grid.nx();
    std::size_t steps = 0, brute = 0;
    // rows are independent: each starts from face 0 and then walks from its previous node
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : steps, brute)
    for (int y = 0; y < ny; ++y)
    {
        SampleStats local;
        std::uint32_t hint = 0;
        for (int x = 0; x < nx; ++x)
        {
            const core::NodeIndex n = grid.index(x, y);
            if (!grid.is_canonical(n))
                continue;
            const Vec3 p{domain[0][n], domain[1][n], domain[2][n]};
            const Location loc =
                locator.locate(p, start_faces.empty() ? hint : start_faces[n.value], local);
            hint = loc.face;
            // barycentric weights of the central projection onto the chord triangle; a
            // slightly negative weight (a point on an edge, within the tolerance) is clamped
            const double w0 = std::max(0.0, loc.e[0]), w1 = std::max(0.0, loc.e[1]),
                         w2 = std::max(0.0, loc.e[2]);
            const double sum = w0 + w1 + w2;
            const auto& t = mesh.faces[loc.face];
            Vec3 pos;
            if (sum > 0.0)
                pos = (mesh.positions[t[0]] * w0 + mesh.positions[t[1]] * w1 +
                       mesh.positions[t[2]] * w2) /
                      sum;
            else
                pos = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
            out[0][n] = pos.x;
            out[1][n] = pos.y;
            out[2][n] = pos.z;
        }
        steps += local.walk_steps;
        brute += local.brute_force;
    }
    for (auto& f : out)
        core::sync_twins(grid, f);
    if (stats != nullptr)
        *stats = {steps, brute};
    return out;
}

mesh::TriMesh grid_surface(const core::TetraGrid& grid, const core::Vec3Field<double>& positions)
{
    mesh::TriMesh m;
    const auto nodes = grid.node_of_unique();
    m.positions.reserve(nodes.size());
    for (const core::NodeIndex n : nodes)
        m.positions.push_back({positions[0][n], positions[1][n], positions[2][n]});
    m.faces = grid.triangles();
    return m;
}

}  // namespace pliant::remesh
