// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A unit-sphere grid for render tests and benchmarks: each grid node is placed on a regular
// tetrahedron by its barycentric position in its face (docs/design.md §1: the left square holds
// faces abc and acd, the right square bad and bdc), then projected centrally onto the sphere.

#include <pliant/core/field.h>
#include <pliant/core/vec3.h>

#include <cmath>

namespace pliant::test
{

/// The point of the regular tetrahedron (corners on the unit sphere) that node (x, y) stands for.
inline core::Vec3 tetra_point(const core::TetraGrid& grid, int x, int y)
{
    const double s = 1.0 / std::sqrt(3.0);
    const core::Vec3 a{s, s, s};
    const core::Vec3 b{s, -s, -s};
    const core::Vec3 c{-s, s, -s};
    const core::Vec3 d{-s, -s, s};
    const double w = grid.w();
    if (x <= grid.w())
    {
        if (x >= y)  // triangle a(0,0) b(W,0) c(W,W)
            return a + (b - a) * ((x - y) / w) + (c - a) * (y / w);
        return a + (c - a) * (x / w) + (d - a) * ((y - x) / w);  // a(0,0) c(W,W) d(0,W)
    }
    const int xr = x - grid.w();
    if (xr >= y)  // b(W,0) a(2W,0) d(2W,W)
        return b + (a - b) * ((xr - y) / w) + (d - b) * (y / w);
    return b + (d - b) * (xr / w) + (c - b) * ((y - xr) / w);  // b(W,0) d(2W,W) c(W,W)
}

/// Node positions on the sphere of `radius` around the origin, every node (twins included).
inline core::Vec3Field<double> sphere_positions(const core::TetraGrid& grid, double radius = 1.0)
{
    core::Vec3Field<double> p{core::Field<double>(grid), core::Field<double>(grid),
                              core::Field<double>(grid)};
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const core::Vec3 q = core::normalized(tetra_point(grid, x, y)) * radius;
            p[0].at(x, y) = q.x;
            p[1].at(x, y) = q.y;
            p[2].at(x, y) = q.z;
        }
    for (auto& f : p)  // the two formulas at a seam may differ in the last bit
        core::sync_twins(grid, f);
    return p;
}

inline core::Vec3 node_position(const core::Vec3Field<double>& p, core::NodeIndex n)
{
    return {p[0][n], p[1][n], p[2][n]};
}

}  // namespace pliant::test
