// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Domain -> sphere and sampling (design in include/pliant/remesh/sample.h).

#include <pliant/core/sphere_domain.h>
#include <pliant/remesh/sample.h>

#include "remesh/locate_internal.h"
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
using detail::Location;
using detail::Locator;

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
            const Vec3 pos = detail::interpolate(mesh, loc);
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
