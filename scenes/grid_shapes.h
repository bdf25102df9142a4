// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Rest geometries built directly on a `TetraGrid` (header-only, namespace pliant::scenes), for
/// tests, benchmarks and the CLI when no remeshed grid file is given.
///
/// `tetrahedron_point(grid, x, y)`: the point of the regular tetrahedron with corners
/// a = (1,1,1), b = (1,-1,-1), c = (-1,1,-1), d = (-1,-1,1) that grid position (x, y) stands
/// for: the rectangle's four triangles abc, acd (x <= W) and abd, bcd (x >= W) (DESIGN §1) are
/// mapped affinely onto the faces, i.e. each node sits at its face-barycentric position.
/// `sphere_grid(grid, radius, ghost)`: those points projected radially onto the sphere of
/// `radius` [m] about the origin (twins equal bit for bit, ghosts filled).

#include <pliant/core/field.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>

#include <cmath>

namespace pliant::scenes
{

inline core::Vec3 tetrahedron_point(const core::TetraGrid& grid, int x, int y)
{
    const core::Vec3 a{1.0, 1.0, 1.0};
    const core::Vec3 b{1.0, -1.0, -1.0};
    const core::Vec3 c{-1.0, 1.0, -1.0};
    const core::Vec3 d{-1.0, -1.0, 1.0};
    const double w = grid.w();
    if (x <= grid.w())
    {
        if (y <= x)  // abc: a (0,0), b (W,0), c (W,W)
            return a + (b - a) * ((x - y) / w) + (c - a) * (y / w);
        return a + (c - a) * (x / w) + (d - a) * ((y - x) / w);  // acd: d (0,W)
    }
    const int xs = x - grid.w();
    if (y <= xs)  // abd: b (W,0), a (2W,0), d (2W,W)
        return b + (a - b) * ((xs - y) / w) + (d - b) * (y / w);
    return b + (d - b) * (xs / w) + (c - b) * ((y - xs) / w);  // bcd: c (W,W)
}

/// Grid nodes on the sphere of `radius` about the origin (see the file comment).
inline core::Vec3Field<double> sphere_grid(const core::TetraGrid& grid, double radius,
                                           int ghost = 0)
{
    core::Vec3Field<double> out{core::Field<double>(grid, ghost), core::Field<double>(grid, ghost),
                                core::Field<double>(grid, ghost)};
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const core::Vec3 p = tetrahedron_point(grid, x, y);
            const core::Vec3 s = p * (radius / core::norm(p));
            out[0].at(x, y) = s.x;
            out[1].at(x, y) = s.y;
            out[2].at(x, y) = s.z;
        }
    for (auto& f : out)
    {
        core::sync_twins(grid, f);
        core::fill_ghosts(grid, f);
    }
    return out;
}

/// An ellipsoid with semi-axes (ax, ay, az) [m]: the sphere grid scaled per axis.
inline core::Vec3Field<double> ellipsoid_grid(const core::TetraGrid& grid, double ax, double ay,
                                              double az, int ghost = 0)
{
    core::Vec3Field<double> out = sphere_grid(grid, 1.0, ghost);
    const double s[3] = {ax, ay, az};
    for (int k = 0; k < 3; ++k)
        for (double& value : out[static_cast<std::size_t>(k)].padded())
            value *= s[k];
    return out;
}

}  // namespace pliant::scenes
