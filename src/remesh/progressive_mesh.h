// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A progressive mesh by half-edge collapses (Hoppe 1996; Praun & Hoppe 2003 §4), built only to
// be undone: the spherical embedding starts from the 4-vertex base and re-inserts the removed
// vertices in reverse order.
//
// Data layout: faces keep their ids from the input; a collapse u -> v rewrites u to v in the
// faces around u ("modified") and kills the two faces on the edge. `coarse_faces` is the face
// array after all collapses: a killed face holds the vertices it had when it died, a modified
// face its latest content, so undoing the collapses in reverse order (v -> u in the modified
// faces, revive the killed ones) restores every intermediate mesh exactly.
//
// Invariants: every intermediate mesh is a simplicial 2-sphere (the link condition), so the
// base is a tetrahedron. Collapses are ordered by quadric error (Garland & Heckbert 1997) of
// moving u onto v plus a small edge-length term, and refused when they flip a surface normal;
// when no such collapse is left the geometric test is dropped (the embedding's correctness
// does not depend on it, only its coarse-level quality does).
//
// Alternatives rejected: OpenMesh's decimater (remesh may depend only on core and mesh);
// full-edge collapses with optimal positions (the coarse vertices would not be input
// vertices, and the stretch of coarse levels is measured against the input positions).

#include <pliant/core/progress.h>
#include <pliant/core/result.h>
#include <pliant/mesh/tri_mesh.h>

#include <array>
#include <cstdint>
#include <vector>

namespace pliant::remesh::detail
{

struct Collapse
{
    std::uint32_t removed = 0;  ///< u, the vertex that disappears
    std::uint32_t kept = 0;     ///< v, the vertex u merges into
    std::array<std::uint32_t, 2> killed_faces{};
    std::uint32_t first_modified = 0;  ///< into ProgressiveMesh::modified_faces
    std::uint32_t modified_count = 0;
};

struct ProgressiveMesh
{
    std::vector<Collapse> collapses;  ///< in collapse order (fine to coarse)
    std::vector<std::uint32_t> modified_faces;
    std::vector<mesh::Face> coarse_faces;  ///< face contents after all collapses (see above)
    std::vector<std::uint8_t> coarse_alive;
    std::array<std::uint32_t, 4> base_vertices{};
    std::size_t forced_collapses = 0;  ///< collapses done without the normal-flip test
};

/// Collapses `mesh` (closed genus 0, consistently oriented) down to a tetrahedron.
/// \return NotConverged if the collapses stop above 4 vertices (not a simplicial sphere).
core::Result<ProgressiveMesh> build_progressive_mesh(const mesh::TriMesh& mesh,
                                                     core::ProgressSink& progress);

}  // namespace pliant::remesh::detail
