// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Rest geometries built directly on a `TetraGrid` (header-only, namespace pliant::scenes), for
/// tests, benchmarks and the CLI when no remeshed grid file is given.
///
/// `sphere_grid(grid, radius, ghost, map)`: every node on the sphere of `radius` [m] about the
/// origin, through core::sphere_domain (twins equal bit for bit, ghosts filled). The default map
/// is the gnomonic one (the central projection of the regular tetrahedron with corners
/// a = (1,1,1), b = (1,-1,-1), c = (-1,1,-1), d = (-1,-1,1)): the tests' reference values and
/// the golden hash were taken on it. The CLI's built-in sphere and the membrane benchmark use
/// `core::SphereMap::EqualArea`, whose even cells allow about twice the stable step (1.8x without
/// damping, 2.05x with beta = 0.5; docs/physics.md §5).

#include <pliant/core/field.h>
#include <pliant/core/sphere_domain.h>
#include <pliant/core/tetra_grid.h>

namespace pliant::scenes
{

/// Grid nodes on the sphere of `radius` about the origin (see the file comment).
inline core::Vec3Field<double> sphere_grid(const core::TetraGrid& grid, double radius,
                                           int ghost = 0,
                                           core::SphereMap map = core::SphereMap::Gnomonic)
{
    return core::sphere_domain(grid, map, radius, ghost);
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
