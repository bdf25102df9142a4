// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Self-intersections of a triangle mesh and folded output triangles: the checks behind issue 3's
/// "no self-intersections added by the remesher" (docs/remesh.md §3.2, §4).
///
/// Intersections: every pair of faces that share no edge and have a point in common other than a
/// shared vertex (touching counts). A fold shows up as faces around one vertex overlapping, so
/// pairs sharing one vertex count too. Broad phase: the faces' bounding boxes in a uniform grid
/// (cell about twice the mean box extent), sorted by cell, each pair tested once, in the cell
/// holding the low corner of the two boxes' overlap; two faces sharing no vertex are dropped there
/// when the plane of either passes clear of that overlap (by more than rounding). The faces around
/// a vertex of valence 16 or more whose fan vertex_fan_is_star certifies (a cone's apex, a
/// fan-split cap) are paired apart from the grid: with each other never, with another face only
/// where its image seen along the fan's axis shares a direction with theirs (a binary search over
/// the fan's angles), so such a vertex costs its valence, not its square. A cell holding more
/// than 256 of the other faces is crowded (long slanted slivers side by side, as on a finely
/// divided cylinder, fill cells as long as they are, and share every cell along them in any
/// finer grid): the faces of crowded cells are paired with each other by a tree of boxes
/// oriented along them (an OBB tree, Gottschalk, Lin and Manocha 1996), which separates
/// neighbouring slivers that axis-aligned boxes cannot. Narrow phase: two
/// non-coplanar triangles meet iff an edge of one meets the other (their common segment ends on
/// edges), decided by orientation signs; the coplanar case by edge crossings and containment in the
/// plane the normal's dominant axis leaves. Orientations are evaluated in double with Shewchuk's
/// static error bound and, where that cannot decide the sign, again in 113-bit floating point
/// (`__float128`, long double where the compiler lacks it): not exact arithmetic, but the sign is
/// wrong only for configurations within about 1e-33 (relative) of degenerate.
///
/// Alternatives rejected: the tree for every face (four times slower than the grid on an even
/// mesh of a million faces); exact expansion arithmetic (Shewchuk's adaptive predicates; more
/// code for no difference measured on real meshes).

#include <pliant/core/progress.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant::remesh
{

/// Whether triangles (a0, a1, a2) and (b0, b1, b2) have a point in common (touching included).
/// Degenerate triangles are handled (a segment or point of space is tested as such, whether or
/// not it lies in the other's plane).
[[nodiscard]] bool triangles_intersect(const std::array<core::Vec3, 3>& a,
                                       const std::array<core::Vec3, 3>& b) noexcept;

/// Whether the closed segment pq and the closed triangle t have a point in common. Coordinates
/// must be finite (as after mesh validation); NaN gives no meaningful answer.
[[nodiscard]] bool edge_meets_triangle(const core::Vec3& p, const core::Vec3& q,
                                       const std::array<core::Vec3, 3>& t) noexcept;

/// Whether faces f and g of `mesh` intersect by intersecting_pairs' rule: never when they share
/// an edge; when they share one vertex, iff the edge of either opposite it meets the other.
/// `exact` false: double arithmetic only, an orientation within its rounding bound taken as 0
/// (touching, so the answer errs towards "intersect"), several times faster on nearly coplanar
/// faces (the untangling's inner loop).
[[nodiscard]] bool faces_intersect(const mesh::TriMesh& mesh, std::uint32_t f, std::uint32_t g,
                                   bool exact = true) noexcept;

/// Every pair {i, j}, i < j, of faces of `mesh` that share no edge and meet anywhere except at a
/// shared vertex, in increasing order. Faces sharing no vertex: triangles_intersect; faces
/// sharing one vertex meet elsewhere iff the edge of either opposite the shared vertex meets
/// the other (the overlap is convex and contains the vertex, so its far side lies on such an
/// edge). O(n log n) for meshes of even triangle sizes and for dense slivers side by side
/// (the tree); parallel (OpenMP), and the result does not depend on the thread count. The faces
/// around a vertex of 16 or more, which all pass the broad phase together, are not paired with
/// each other where vertex_fan_is_star certifies the fan (a cone's apex, a fan-split cap):
/// linear, not quadratic, in the valence.
/// `stop`: its stop_requested() is polled from the calling thread only (OpenMP's thread 0; not
/// from within an enclosing parallel region): between the serial stages, at each chunk of 64
/// grid cells that thread takes, every 256 faces within a cell, and at each share of the tree's
/// work and every 1,024 of its nodes visited; once it answers true the
/// count ends early and its result is incomplete (the caller asks the sink again, which must
/// still say true: ProgressSink, and discards it). A count of a million faces takes seconds.
[[nodiscard]] std::vector<std::array<std::uint32_t, 2>> intersecting_pairs(
    const mesh::TriMesh& mesh, const core::ProgressSink* stop = nullptr);

/// The pairs of intersecting_pairs(mesh) that have a face f with `touched[f] != 0` (one flag per
/// face), in the same order. After some vertices moved, these are the pairs to recount: a pair
/// of two untouched faces keeps its answer (the untangling's rounds recount this way). Tests
/// only the faces whose boxes meet the touched faces' bounding box.
/// `stop` as for intersecting_pairs.
[[nodiscard]] std::vector<std::array<std::uint32_t, 2>> intersecting_pairs_touching(
    const mesh::TriMesh& mesh, std::span<const std::uint8_t> touched,
    const core::ProgressSink* stop = nullptr);

/// Whether the faces `around` vertex v (every face of `mesh` that holds it, in any order) form a
/// simple star, so that no two of them meet except at v or along an edge they share: they are
/// one consistently oriented cycle (each face's edge leaving v is the previous face's edge
/// arriving at it), and projected along their summed normal every face keeps its orientation,
/// by a margin of 1e-10 relative (far above rounding), and their angles at v's image make one
/// full turn. The images then tile the plane around v's once, so two faces that are not
/// neighbours have images meeting only at v's; the projection is one-to-one on each face, so
/// the faces meet only at v. A fold, a flipped face, a fan winding twice, a pinched (non-manifold)
/// vertex or a face within 1e-10 of edge-on: false (not certified; not proof of a crossing).
[[nodiscard]] bool vertex_fan_is_star(const mesh::TriMesh& mesh, std::uint32_t v,
                                      std::span<const std::uint32_t> around);

/// intersecting_pairs(mesh, stop).size().
[[nodiscard]] std::size_t count_self_intersections(const mesh::TriMesh& mesh,
                                                   const core::ProgressSink* stop = nullptr);

/// Whether face `f` of `output` faces against the input surface at its samples: its normal makes
/// a negative dot product with the normal of each input face its three vertices were sampled
/// from (`sample_faces[v]`, a face of `input` per vertex of `output`). "Each", not "their sum":
/// a face spanning a sharp edge or the rim of a thin part legitimately faces away from one side.
/// A degenerate output face counts as not folded.
[[nodiscard]] bool is_folded(const mesh::TriMesh& output, std::size_t f, const mesh::TriMesh& input,
                             std::span<const std::uint32_t> sample_faces) noexcept;

/// Number of folded faces of `output` (is_folded).
/// \pre sample_faces.size() == output.positions.size(), every entry a face of `input`.
[[nodiscard]] std::size_t count_folded(const mesh::TriMesh& output, const mesh::TriMesh& input,
                                       std::span<const std::uint32_t> sample_faces) noexcept;

}  // namespace pliant::remesh
