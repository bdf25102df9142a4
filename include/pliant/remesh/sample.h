// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Domain -> sphere (DESIGN.md §2.3) and sampling the input surface at every grid node
/// (DESIGN.md §2.4).
///
/// The domain map is the central (gnomonic) projection of a regular tetrahedron: each grid
/// node is placed on its tetrahedron face by the piecewise-linear map that the grid's gluing
/// (DESIGN §1) already implies, then normalised. It is fold-free because central projection of
/// a convex polyhedron containing the origin is.
///
/// Sampling locates each node's sphere point in the spherical mesh by a walk from the previous
/// node's triangle (adjacent nodes are close, so a walk is a few steps), with a small tolerance
/// so a point on an edge or vertex is accepted by either neighbour (no gaps), and interpolates
/// the input's 3D positions with the barycentric coordinates of the point's central projection
/// onto the chord triangle (continuous across edges).

#include <pliant/core/field.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>

#include <cstddef>
#include <span>

namespace pliant::remesh
{

/// Unit-sphere point of every grid node (twins equal): core::sphere_domain with the gnomonic map,
/// which the GPU sampler needs (its views are perspective projections). Oriented so that the
/// grid's triangles (`TetraGrid::triangles()`) are counter-clockwise seen from outside.
[[nodiscard]] core::Vec3Field<double> domain_sphere(const core::TetraGrid& grid);

/// Grid triangles whose spherical triangle is not positively oriented.
[[nodiscard]] std::size_t count_inverted_domain(const core::TetraGrid& grid,
                                                const core::Vec3Field<double>& sphere);

/// Statistics of the point location, for the report and tests.
struct SampleStats
{
    std::size_t walk_steps = 0;   ///< triangles visited by all walks
    std::size_t brute_force = 0;  ///< nodes that needed the exhaustive fallback
};

/// Samples `mesh` at every grid node: its 3D position at the node's sphere point.
/// \pre `sphere` is a fold-free spherical map of `mesh` (map_to_sphere), `domain` from
/// domain_sphere(grid). \return InvalidArgument when the sizes disagree.
core::Result<core::Vec3Field<double>> sample_surface(const core::TetraGrid& grid,
                                                     const core::Vec3Field<double>& domain,
                                                     const mesh::TriMesh& mesh,
                                                     std::span<const core::Vec3> sphere,
                                                     SampleStats* stats = nullptr);

/// The grid surface as a mesh: vertex i at node `grid.node_of_unique()[i]`, faces
/// `grid.triangles()` (the same layout as mesh::from_grid).
[[nodiscard]] mesh::TriMesh grid_surface(const core::TetraGrid& grid,
                                         const core::Vec3Field<double>& positions);

}  // namespace pliant::remesh
