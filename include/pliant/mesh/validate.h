// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Topology and geometry statistics of a `TriMesh`, and the input rules of docs/design.md §2.1
/// (closed, 2-manifold, connected, genus 0, finite, non-degenerate, consistently oriented), each
/// with its own `core::ErrorCode`. docs/mesh.md lists the rules with example messages.

#include <pliant/core/result.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>

#include <cstddef>
#include <optional>
#include <string_view>

namespace pliant::mesh
{

/// Counts and measures of a triangle mesh. Edges are undirected vertex pairs used by at least one
/// face; faces with an out-of-range index are skipped by the topology counts (and counted in
/// `bad_index_faces`).
struct MeshStats
{
    std::size_t vertices = 0;  ///< all positions (including unused ones)
    std::size_t faces = 0;
    std::size_t edges = 0;                  ///< distinct undirected edges
    std::size_t components = 0;             ///< connected components of the face graph (sharing
                                            ///< a vertex connects), isolated vertices excluded
    std::size_t unreferenced_vertices = 0;  ///< positions no face uses
    std::size_t boundary_edges = 0;         ///< edges with exactly one incident face
    std::size_t boundary_loops = 0;         ///< connected chains of boundary edges
    std::size_t non_manifold_edges = 0;     ///< edges with more than two incident faces
    std::size_t non_manifold_vertices = 0;  ///< vertices whose incident faces form > 1 fan
    std::size_t degenerate_faces = 0;       ///< repeated index or zero area
    std::size_t bad_index_faces = 0;        ///< faces with an index >= vertices
    std::size_t non_finite_vertices = 0;    ///< positions with NaN or infinity
    std::size_t inconsistent_edges = 0;     ///< 2-face edges traversed the same way by both
    long euler_characteristic = 0;          ///< χ = V - E + F over referenced vertices
    /// (2 - χ) / 2, set only when the genus is defined: closed, 2-manifold (edges and vertices),
    /// connected, no bad index. `std::nullopt` otherwise (`pliant info` prints "-", JSON null).
    std::optional<long> genus;
    core::Vec3 bbox_min;  ///< over finite referenced vertices (0 if none)
    core::Vec3 bbox_max;
    double bbox_diagonal = 0.0;  ///< |bbox_max - bbox_min|, file units
    double surface_area = 0.0;   ///< sum of triangle areas (finite faces only)
};

/// Computes every statistic in one pass over faces plus a sort of the edges: O(F log F). Never
/// fails; garbage in (bad indices, NaN) is counted, not trusted.
[[nodiscard]] MeshStats analyze(const TriMesh& mesh);

/// Checks the rules in this order, reporting the first that fails (the most basic first, since a
/// later rule's numbers mean little when an earlier one is broken):
///   1. BadIndex: a face refers to a vertex >= vertex count ("face 3 refers to vertex 9 of 8");
///   2. EmptyInput: no faces;
///   3. NonFiniteCoordinate: a used vertex has NaN/inf (which vertex);
///   4. DegenerateFace: repeated index or zero area (which face);
///   5. NonManifoldEdge: an edge with > 2 faces (count, one edge and its face count);
///   6. OpenBoundary: boundary edges (count, loops, one boundary vertex and its position);
///   7. NonManifoldVertex: a pinch vertex (count, one vertex and its fan count);
///   8. InconsistentOrientation: an edge both faces traverse the same way (count, one edge);
///   9. NotConnected: more than one component (count, and their face counts);
///  10. WrongGenus: χ != 2 (χ and the genus).
/// Unreferenced vertices are allowed (import drops them). Messages start with `source_name`,
/// e.g. "spot.obj: not a closed surface: 223 boundary edges in 5 loops (first at vertex 17
/// (0.1, 0.2, 0.3))".
/// \return success for a closed, connected, consistently oriented, genus-0 2-manifold.
[[nodiscard]] core::Result<void> validate(const TriMesh& mesh, std::string_view source_name);

}  // namespace pliant::mesh
