// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Small helpers shared by the subdiv tests: random fields with equal twins, the parent edge of
// a fine odd node, and per-unique-vertex values of a field.

#include <pliant/core/field.h>
#include <pliant/core/tetra_grid.h>

#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace pliant::test
{

/// Uniform random values in [-1, 1) at canonical nodes, copied to twins, ghosts filled.
template <typename T>
core::Field<T> random_field(const core::TetraGrid& grid, int ghost, std::uint32_t seed)
{
    core::Field<T> f(grid, ghost);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> dist(-1.0, 1.0);
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
            f.at(x, y) = static_cast<T>(dist(rng));
    core::sync_twins(grid, f);
    core::fill_ghosts(grid, f);
    return f;
}

/// Whether fine node (X, Y) is an odd (new) node.
inline bool is_odd_node(int x, int y)
{
    return (x % 2) != 0 || (y % 2) != 0;
}

/// The two coarse nodes of the edge a fine odd node (X, Y) splits, as coarse coordinates.
inline std::pair<core::GridCoord, core::GridCoord> parent_edge(int x, int y)
{
    if (y % 2 == 0)  // horizontal
        return {{(x - 1) / 2, y / 2}, {(x + 1) / 2, y / 2}};
    if (x % 2 == 0)  // vertical
        return {{x / 2, (y - 1) / 2}, {x / 2, (y + 1) / 2}};
    return {{(x - 1) / 2, (y - 1) / 2}, {(x + 1) / 2, (y + 1) / 2}};  // diagonal
}

/// The field's value at each unique vertex (grid.node_of_unique() order).
template <typename T>
std::vector<double> unique_values(const core::TetraGrid& grid, const core::Field<T>& f)
{
    std::vector<double> v;
    v.reserve(grid.unique_count());
    for (const core::NodeIndex n : grid.node_of_unique())
        v.push_back(static_cast<double>(f[n]));
    return v;
}

/// Key of an undirected edge between unique vertex ids.
inline std::uint64_t edge_key(std::uint32_t a, std::uint32_t b)
{
    if (a > b)
        std::swap(a, b);
    return (static_cast<std::uint64_t>(a) << 32) | b;
}

}  // namespace pliant::test
