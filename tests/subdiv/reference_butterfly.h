// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A slow, obviously correct modified butterfly for tests: per edge, on an explicit halfedge
// structure built from a closed triangle list (grid.triangles()), knowing nothing of the grid.
//
// How the stencil is defined (the regular 8-point rule, found topologically, applied at EVERY
// edge whatever the valences): for the edge a0-a1 with halfedges h (a0 -> a1) and o = opp(h),
//   b0 = apex of face(h), b1 = apex of face(o),
//   c0, c1 = apexes of the faces across the two other edges of face(h),
//   c2, c3 = apexes of the faces across the two other edges of face(o).
// "Across an edge" is always the opposite halfedge's face, so the rule needs no valence. At a
// valence-3 tetrahedron corner some of these vertices coincide (a corner's three faces surround
// it, so e.g. c1 of one wing is b1 of the other): exactly what the grid's ghost map gives, which
// duplicates each of the corner's edges (docs/design.md §1). This is NOT OpenMesh's rule at valence
// 3 (docs/subdivision.md).
//
// The value is summed with the kernel's grouping, pairing c's by wing:
//   (1/2 (a0 + a1) + 1/8 (b0 + b1)) - 1/16 ((c0 + c1) + (c2 + c3))
// Every pair is commutative in IEEE arithmetic, so in double it must match the kernel bit for
// bit whatever the edge's orientation.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant::test
{

struct ButterflyStencil
{
    std::uint32_t a0 = 0, a1 = 0, b0 = 0, b1 = 0;
    std::array<std::uint32_t, 4> c{};
};

class ReferenceButterfly
{
public:
    /// Builds the halfedge structure. Aborts the test (ADD_FAILURE + empty) on a mesh that is not
    /// a closed, consistently oriented 2-manifold.
    ReferenceButterfly(std::span<const std::array<std::uint32_t, 3>> faces,
                       std::size_t vertex_count);

    [[nodiscard]] bool ok() const { return ok_; }
    [[nodiscard]] std::size_t edge_count() const { return edges_.size(); }
    /// Each undirected edge once, as a halfedge a0 -> a1 with a0 < a1.
    [[nodiscard]] std::span<const std::uint32_t> edge_halfedges() const { return edges_; }

    [[nodiscard]] std::uint32_t from(std::uint32_t h) const { return from_[h]; }
    [[nodiscard]] std::uint32_t to(std::uint32_t h) const { return from_[next(h)]; }
    [[nodiscard]] static std::uint32_t next(std::uint32_t h) { return h / 3 * 3 + (h + 1) % 3; }
    [[nodiscard]] static std::uint32_t prev(std::uint32_t h) { return h / 3 * 3 + (h + 2) % 3; }
    [[nodiscard]] std::uint32_t opposite(std::uint32_t h) const { return opposite_[h]; }
    /// The vertex of h's face not on h.
    [[nodiscard]] std::uint32_t apex(std::uint32_t h) const { return from_[prev(h)]; }
    [[nodiscard]] std::uint32_t valence(std::uint32_t v) const { return valence_[v]; }

    [[nodiscard]] ButterflyStencil stencil(std::uint32_t h) const;
    /// The new value on the edge of halfedge h from per-vertex values.
    [[nodiscard]] double new_value(std::uint32_t h, std::span<const double> values) const;

private:
    bool ok_ = false;
    std::vector<std::uint32_t> from_;      // per halfedge 3f+i: faces[f][i]
    std::vector<std::uint32_t> opposite_;  // per halfedge
    std::vector<std::uint32_t> edges_;     // one halfedge per edge
    std::vector<std::uint32_t> valence_;   // per vertex
};

}  // namespace pliant::test
