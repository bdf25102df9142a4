// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `TetraGrid`: the regular triangle grid over the tetrahedral domain (docs/design.md §1), the one
/// grid type every stage shares.
///
/// Data layout and invariants
/// - Level n has W = 2^n; nodes (x, y) with 0 <= x <= 2W, 0 <= y <= W, row-major, index y*nx + x.
/// - Each cell (x..x+1, y..y+1) is split by the diagonal (x, y)-(x+1, y+1).
/// - The border is glued into a tetrahedron: x = 0 with x = 2W; the top row folded at c = (W, W);
///   the bottom row folded at b = (W, 0). A border node and its twins are one surface vertex; the
///   twin with the smallest index is canonical, and fields keep twins equal to it.
/// - The ghost map sends any node outside the rectangle (within `k_max_ghost` of it) to the
///   canonical in-range node it stands for; every map is an isometry that keeps the diagonal
///   direction, so stencils need no border or corner branch.
/// - Quad-tree: the cells form two W x W squares (x <= W and x >= W); a tree node (square, depth,
///   ix, iy) covers a half-open node rectangle; each canonical node lies in exactly one leaf at
///   each depth (the top row y = W is closed into the upper leaves).
///
/// Alternatives rejected: storing only unique vertices (2W^2+2) would save 0.1 % of memory but
/// every stencil would need an index indirection; a ghost map evaluated per access would put
/// branches in every kernel.

#include <pliant/core/result.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant::core
{

/// Index of a node in the (2W+1) x (W+1) grid, row-major (y * nx + x).
struct NodeIndex
{
    std::uint32_t value = 0;
    friend constexpr bool operator==(NodeIndex, NodeIndex) = default;
    friend constexpr auto operator<=>(NodeIndex, NodeIndex) = default;
};

/// Integer grid coordinates; may lie outside the rectangle (a ghost position).
struct GridCoord
{
    int x = 0;
    int y = 0;
    friend constexpr bool operator==(GridCoord, GridCoord) = default;
};

/// A quad-tree node: square 0 (x in [0, W]) or 1 (x in [W, 2W]), depth 0 (the whole square) to
/// the level (single cells), and its position (ix, iy) < 2^depth in that square.
struct LeafId
{
    std::uint8_t square = 0;
    std::uint8_t depth = 0;
    std::uint16_t ix = 0;
    std::uint16_t iy = 0;
    friend constexpr bool operator==(LeafId, LeafId) = default;
};

/// A half-open rectangle of grid nodes [x0, x1) x [y0, y1). The canonical nodes inside it are the
/// ones a region owns.
struct Region
{
    int x0 = 0;
    int y0 = 0;
    int x1 = 0;
    int y1 = 0;

    [[nodiscard]] constexpr bool contains(int x, int y) const noexcept
    {
        return x >= x0 && x < x1 && y >= y0 && y < y1;
    }
    [[nodiscard]] constexpr int width() const noexcept { return x1 - x0; }
    [[nodiscard]] constexpr int height() const noexcept { return y1 - y0; }
    friend constexpr bool operator==(const Region&, const Region&) = default;
};

/// One ghost cell to fill: the padded offset it is written to and the one it is read from.
struct GhostCopy
{
    std::int64_t dst = 0;
    std::int64_t src = 0;
};

/// A twin node and the canonical node it copies.
struct TwinPair
{
    NodeIndex twin;
    NodeIndex canonical;
};

/// The widest ghost ring a field may have (the refinement's convolutions and the membrane's
/// stencil need 1: subdiv::k_refine_ghost, sim's planes).
inline constexpr int k_max_ghost = 4;
inline constexpr int k_min_level = 1;
inline constexpr int k_max_level = 10;

class TetraGrid
{
public:
    /// \pre nothing. \return ErrorCode::InvalidArgument unless 1 <= level <= 10.
    static Result<TetraGrid> create(int level);

    [[nodiscard]] int level() const noexcept { return level_; }
    /// W = 2^level: cells along the short side.
    [[nodiscard]] int w() const noexcept { return w_; }
    [[nodiscard]] int nx() const noexcept { return 2 * w_ + 1; }
    [[nodiscard]] int ny() const noexcept { return w_ + 1; }
    /// All grid nodes, twins included: (2W+1)(W+1).
    [[nodiscard]] std::size_t node_count() const noexcept
    {
        return static_cast<std::size_t>(nx()) * static_cast<std::size_t>(ny());
    }
    /// Distinct surface vertices: 2W^2 + 2.
    [[nodiscard]] std::size_t unique_count() const noexcept { return node_of_unique_.size(); }
    /// Grid triangles = surface faces: 4W^2.
    [[nodiscard]] std::size_t face_count() const noexcept
    {
        return 4U * static_cast<std::size_t>(w_) * static_cast<std::size_t>(w_);
    }

    [[nodiscard]] bool in_range(int x, int y) const noexcept
    {
        return x >= 0 && x <= 2 * w_ && y >= 0 && y <= w_;
    }
    [[nodiscard]] NodeIndex index(int x, int y) const noexcept
    {
        PLIANT_DEBUG_ASSERT(in_range(x, y), "TetraGrid::index out of range");
        return NodeIndex{static_cast<std::uint32_t>(y * nx() + x)};
    }
    [[nodiscard]] GridCoord coord(NodeIndex n) const noexcept
    {
        const int i = static_cast<int>(n.value);
        return {i % nx(), i / nx()};
    }

    /// The in-range node a position stands for by the gluing rules (docs/design.md §1), before
    /// choosing the canonical twin. \pre the position lies within `w()` of the rectangle.
    [[nodiscard]] GridCoord fold(int x, int y) const noexcept;
    /// The canonical node a position (in range or ghost) stands for.
    [[nodiscard]] NodeIndex image(int x, int y) const noexcept;
    [[nodiscard]] NodeIndex canonical(NodeIndex n) const noexcept
    {
        return NodeIndex{canonical_[n.value]};
    }
    [[nodiscard]] bool is_canonical(NodeIndex n) const noexcept
    {
        return canonical_[n.value] == n.value;
    }
    /// Every non-canonical node with its canonical node, in increasing twin order.
    [[nodiscard]] std::span<const TwinPair> twins() const noexcept { return twins_; }

    /// The four tetrahedron corners a=(0,0), b=(W,0), c=(W,W), d=(0,W) (canonical nodes).
    [[nodiscard]] std::array<NodeIndex, 4> corners() const noexcept;

    /// Unique vertex id (0 .. 2W^2+1) of every node, twins sharing their canonical node's id.
    [[nodiscard]] std::uint32_t unique_id(NodeIndex n) const noexcept
    {
        return unique_of_node_[n.value];
    }
    /// The canonical node of every unique vertex id, in increasing node order.
    [[nodiscard]] std::span<const NodeIndex> node_of_unique() const noexcept
    {
        return node_of_unique_;
    }
    /// The 4W^2 faces over unique vertex ids, cell by cell: (x,y),(x+1,y),(x+1,y+1) then
    /// (x,y),(x+1,y+1),(x,y+1). Consistently oriented (an oriented closed surface).
    [[nodiscard]] std::vector<std::array<std::uint32_t, 3>> triangles() const;
    /// The same faces over grid node indices (before twin merging).
    [[nodiscard]] std::vector<std::array<std::uint32_t, 3>> node_triangles() const;

    /// Ghost copies for a field with a ghost ring of `width` (1..k_max_ghost), as offsets into the
    /// padded plane (stride nx + 2*width). Sources are canonical in-range nodes.
    [[nodiscard]] std::span<const GhostCopy> ghost_table(int width) const noexcept;

    /// The node rectangle of a quad-tree node. \pre depth <= level, ix, iy < 2^depth.
    [[nodiscard]] Region leaf_region(LeafId leaf) const noexcept;
    /// All quad-tree nodes at one depth: square 0 then 1, each row by row (iy, then ix).
    [[nodiscard]] std::vector<LeafId> leaves(int depth) const;

private:
    TetraGrid() = default;

    int level_ = 0;
    int w_ = 0;
    std::vector<std::uint32_t> canonical_;
    std::vector<std::uint32_t> unique_of_node_;
    std::vector<NodeIndex> node_of_unique_;
    std::vector<TwinPair> twins_;
    std::array<std::vector<GhostCopy>, k_max_ghost + 1> ghost_tables_;
};

/// `mask` (one flag per grid node, set on canonical nodes) grown by `rings` rings of grid
/// neighbours through the ghost map.
[[nodiscard]] std::vector<char> dilate_nodes(const TetraGrid& grid, std::vector<char> mask,
                                             int rings);

/// The canonical nodes whose flag is set as disjoint rectangles (maximal row runs, stacked when
/// consecutive rows have the same span): the `owned` list of a restricted sim step.
[[nodiscard]] std::vector<Region> node_runs(const TetraGrid& grid, const std::vector<char>& mask);

/// The six grid neighbours of (x, y) through the ghost map, as canonical nodes (a corner lists
/// some twice).
[[nodiscard]] std::array<NodeIndex, 6> grid_neighbours(const TetraGrid& grid, int x, int y);

}  // namespace pliant::core
