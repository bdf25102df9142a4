// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Domain -> sphere (docs/design.md §2.3) and sampling the input surface at every grid node
/// (docs/design.md §2.4).
///
/// The domain map (core::sphere_domain) puts every grid node on the unit sphere: equal-area
/// (the default) or the central (gnomonic) projection of a regular tetrahedron, where each node
/// sits on its tetrahedron face by the piecewise-linear map that the grid's gluing (docs/design.md
/// §1) implies (domain_sphere below). Both are fold-free.
///
/// Sampling locates each node's sphere point in the spherical mesh by a walk from the previous
/// node's triangle (adjacent nodes are close, so a walk is a few steps) or from a given start
/// face (the GPU's point location, render::locate_on_gpu), with a small tolerance
/// so a point on an edge or vertex is accepted by either neighbour (no gaps), and interpolates
/// the input's 3D positions with the barycentric coordinates of the point's central projection
/// onto the chord triangle (continuous across edges).

#include <pliant/core/field.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>

#include <cstddef>
#include <cstdint>
#include <span>

namespace pliant::remesh
{

/// Unit-sphere point of every grid node (twins equal): core::sphere_domain with the gnomonic map,
/// the one render::sample_on_gpu's colour look-up needs (its nodes must lie on pixel centres of
/// the tetrahedron faces' perspective views). Oriented so that the
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
/// core::sphere_domain (either map).
/// \param start_faces empty: each node's walk starts from the previous node's triangle (rows
/// start from face 0). Otherwise one face index per node index (grid.node_count() entries) to
/// start from, e.g. the GPU's point location (render::locate_on_gpu): a start next to the
/// node's triangle makes its walk one or two steps. The walk, its tolerance and the weights are
/// the same either way, so the result is too, up to the choice between two triangles for a
/// point on their shared edge (where both give the same position to rounding).
/// \return InvalidArgument when the sizes disagree or a start face is out of range.
core::Result<core::Vec3Field<double>> sample_surface(
    const core::TetraGrid& grid, const core::Vec3Field<double>& domain, const mesh::TriMesh& mesh,
    std::span<const core::Vec3> sphere, SampleStats* stats = nullptr,
    std::span<const std::uint32_t> start_faces = {});

/// The grid surface as a mesh: vertex i at node `grid.node_of_unique()[i]`, faces
/// `grid.triangles()` (the same layout as mesh::from_grid).
[[nodiscard]] mesh::TriMesh grid_surface(const core::TetraGrid& grid,
                                         const core::Vec3Field<double>& positions);

}  // namespace pliant::remesh
