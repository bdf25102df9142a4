// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The surface distance's choice of search boxes, for the tests (quality.cpp).

#include <pliant/core/progress.h>
#include <pliant/mesh/tri_mesh.h>
#include <pliant/remesh/quality.h>

namespace pliant::remesh::detail
{

/// Whether more than a quarter of `m`'s faces have a box whose surface exceeds 64 times their
/// area (slivers at a slant to the axes, longer than about 30 times their width): surface_distance
/// then searches `m` through the oriented-box tree instead of the axis-aligned BVH.
[[nodiscard]] bool mostly_slanted_slivers(const mesh::TriMesh& m) noexcept;

enum class SearchBoxes
{
    Auto,      // as surface_distance: oriented for a mesh of mostly slanted slivers
    Aligned,   // the axis-aligned BVH for both meshes
    Oriented,  // the oriented-box tree for both
};

/// surface_distance with the search boxes chosen.
[[nodiscard]] SurfaceDistance surface_distance_with(const mesh::TriMesh& reference,
                                                    const mesh::TriMesh& other,
                                                    const DistanceSettings& settings,
                                                    core::ProgressSink* progress,
                                                    SearchBoxes boxes);

}  // namespace pliant::remesh::detail
