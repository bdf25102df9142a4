// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The self-intersection count's crowd threshold, and the count with another threshold for the
// tests (intersections.cpp, obb_tree.h).

#include <pliant/core/progress.h>
#include <pliant/mesh/tri_mesh.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant::remesh::detail
{

/// A grid cell holding more faces than this (those of certified stars apart) is crowded: its
/// faces are paired with each other by the oriented-box tree, not by the cell.
inline constexpr std::size_t k_crowded_cell = 256;

struct PairsWith
{
    std::vector<std::array<std::uint32_t, 2>> pairs;
    std::size_t crowded = 0;  // faces the tree paired (in the subset the count looked at)
};

/// intersecting_pairs_touching(mesh, touched, stop) (touched empty: intersecting_pairs(mesh,
/// stop)) with `crowded_cell` for the threshold: 0 pairs every face outside the stars by the
/// tree.
[[nodiscard]] PairsWith intersecting_pairs_with(const mesh::TriMesh& mesh,
                                                std::span<const std::uint8_t> touched,
                                                std::size_t crowded_cell,
                                                const core::ProgressSink* stop = nullptr);

}  // namespace pliant::remesh::detail
