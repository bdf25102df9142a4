// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Point location in a spherical mesh and barycentric interpolation of the input surface: the
// sampler (sample.cpp) and the untangling of folded samples (untangle.cpp) share them, so a node
// moved by the untangling is sampled exactly as the sampler would sample it.

#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>
#include <pliant/remesh/sample.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace pliant::remesh::detail
{

using core::Vec3;

/// Face adjacency: neighbour of face f across edge (t[k], t[k+1]) at 3f+k.
inline std::vector<std::uint32_t> face_neighbours(std::span<const mesh::Face> faces)
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

inline constexpr double k_edge_tolerance = 1e-14;

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

/// The input surface at a located point: barycentric weights of the central projection onto the
/// chord triangle; a slightly negative weight (a point on an edge, within the tolerance) is
/// clamped.
inline Vec3 interpolate(const mesh::TriMesh& mesh, const Location& loc) noexcept
{
    const double w0 = std::max(0.0, loc.e[0]), w1 = std::max(0.0, loc.e[1]),
                 w2 = std::max(0.0, loc.e[2]);
    const double sum = w0 + w1 + w2;
    const auto& t = mesh.faces[loc.face];
    if (sum > 0.0)
        return (mesh.positions[t[0]] * w0 + mesh.positions[t[1]] * w1 + mesh.positions[t[2]] * w2) /
               sum;
    return (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
}

}  // namespace pliant::remesh::detail
