// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Test helpers: grid positions with a known shape.
// - `tetrahedron_positions`: every node mapped onto the regular tetrahedron with integer corners
//   A=(1,1,1), B=(1,-1,-1), C=(-1,1,-1), D=(-1,-1,1), by its barycentric position in the grid
//   face it lies in (docs/design.md §1: abc, acd lower/upper left square, abd, bcd lower/upper
//   right square). Coordinates are multiples of 1/W, so they and every butterfly sum of them are
//   exact in binary floating point.
// - `sphere_positions`: the same points normalised onto the unit sphere.
// - `face_of`: which of the four faces (0 abc, 1 acd, 2 abd, 3 bcd) contains a grid position in
//   its closed triangle, or -1 (outside the rectangle); a node on a face border reports the
//   first face found, `in_face` tests one face.

#include <pliant/core/field.h>
#include <pliant/core/tetra_grid.h>

#include <array>
#include <cmath>

namespace pliant::test
{

inline bool in_face(const core::TetraGrid& grid, int face, int x, int y)
{
    const int w = grid.w();
    switch (face)
    {
    case 0: return x >= 0 && x <= w && y >= 0 && y <= x;
    case 1: return x >= 0 && x <= w && y >= x && y <= w;
    case 2: return x >= w && x <= 2 * w && y >= 0 && y <= x - w;
    case 3: return x >= w && x <= 2 * w && y >= x - w && y <= w;
    default: return false;
    }
}

inline std::array<double, 3> tetrahedron_point(const core::TetraGrid& grid, int x, int y)
{
    using P = std::array<double, 3>;
    constexpr P A{1, 1, 1};
    constexpr P B{1, -1, -1};
    constexpr P C{-1, 1, -1};
    constexpr P D{-1, -1, 1};
    const double w = grid.w();
    // origin + s (p - origin) + t (q - origin)
    auto lerp = [](const P& o, const P& p, const P& q, double s, double t)
    {
        return P{o[0] + s * (p[0] - o[0]) + t * (q[0] - o[0]),
                 o[1] + s * (p[1] - o[1]) + t * (q[1] - o[1]),
                 o[2] + s * (p[2] - o[2]) + t * (q[2] - o[2])};
    };
    if (x <= grid.w())
    {
        if (y <= x)
            return lerp(A, B, C, (x - y) / w, y / w);  // face abc
        return lerp(A, C, D, x / w, (y - x) / w);      // face acd
    }
    const int u = x - grid.w();
    if (y <= u)
        return lerp(B, A, D, (u - y) / w, y / w);  // face abd
    return lerp(B, D, C, u / w, (y - u) / w);      // face bcd
}

inline core::Vec3Field<double> tetrahedron_positions(const core::TetraGrid& grid, int ghost)
{
    core::Vec3Field<double> p{core::Field<double>(grid, ghost), core::Field<double>(grid, ghost),
                              core::Field<double>(grid, ghost)};
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const auto q = tetrahedron_point(grid, x, y);
            for (int c = 0; c < 3; ++c)
                p[static_cast<std::size_t>(c)].at(x, y) = q[static_cast<std::size_t>(c)];
        }
    for (auto& f : p)
    {
        core::sync_twins(grid, f);  // exact already; keeps the invariant explicit
        core::fill_ghosts(grid, f);
    }
    return p;
}

inline core::Vec3Field<double> sphere_positions(const core::TetraGrid& grid, int ghost)
{
    core::Vec3Field<double> p = tetrahedron_positions(grid, ghost);
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const double r =
                std::sqrt(p[0].at(x, y) * p[0].at(x, y) + p[1].at(x, y) * p[1].at(x, y) +
                          p[2].at(x, y) * p[2].at(x, y));
            for (auto& f : p)
                f.at(x, y) /= r;
        }
    for (auto& f : p)
    {
        core::sync_twins(grid, f);
        core::fill_ghosts(grid, f);
    }
    return p;
}

}  // namespace pliant::test
