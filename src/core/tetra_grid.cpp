// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/assert.h>
#include <pliant/core/tetra_grid.h>

#include <numeric>
#include <string>

namespace pliant::core
{
namespace
{

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t i)
{
    while (parent[i] != i)
    {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

// Joins two classes, keeping the smaller index as root (the canonical twin).
void unite(std::vector<std::uint32_t>& parent, std::uint32_t a, std::uint32_t b)
{
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a == b)
        return;
    if (a < b)
        parent[b] = a;
    else
        parent[a] = b;
}

}  // namespace

Result<TetraGrid> TetraGrid::create(int level)
{
    if (level < k_min_level || level > k_max_level)
        return fail(ErrorCode::InvalidArgument,
                    "TetraGrid::create: level " + std::to_string(level) + " is outside " +
                        std::to_string(k_min_level) + ".." + std::to_string(k_max_level));
    TetraGrid g;
    g.level_ = level;
    g.w_ = 1 << level;
    const int w = g.w_;
    const auto n = static_cast<std::uint32_t>(g.node_count());

    // Twins from the three gluing rules of docs/design.md §1, merged with a union-find.
    std::vector<std::uint32_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0U);
    for (int y = 0; y <= w; ++y)
        unite(parent, g.index(0, y).value, g.index(2 * w, y).value);
    for (int x = 0; x <= 2 * w; ++x)
    {
        unite(parent, g.index(x, 0).value, g.index(2 * w - x, 0).value);
        unite(parent, g.index(x, w).value, g.index(2 * w - x, w).value);
    }
    g.canonical_.resize(n);
    g.unique_of_node_.resize(n);
    for (std::uint32_t i = 0; i < n; ++i)
    {
        const std::uint32_t c = find_root(parent, i);
        g.canonical_[i] = c;
        if (c == i)
        {
            g.unique_of_node_[i] = static_cast<std::uint32_t>(g.node_of_unique_.size());
            g.node_of_unique_.push_back(NodeIndex{i});
        }
        else
        {
            g.unique_of_node_[i] = g.unique_of_node_[c];  // c < i: already numbered
            g.twins_.push_back(TwinPair{NodeIndex{i}, NodeIndex{c}});
        }
    }

    for (int width = 1; width <= k_max_ghost; ++width)
    {
        const std::int64_t stride = g.nx() + 2 * width;
        auto padded = [&](int x, int y)
        { return static_cast<std::int64_t>(y + width) * stride + (x + width); };
        std::vector<GhostCopy>& table = g.ghost_tables_[static_cast<std::size_t>(width)];
        for (int y = -width; y < g.ny() + width; ++y)
            for (int x = -width; x < g.nx() + width; ++x)
            {
                if (g.in_range(x, y))
                    continue;
                const GridCoord src = g.coord(g.image(x, y));
                table.push_back(GhostCopy{padded(x, y), padded(src.x, src.y)});
            }
    }
    return g;
}

GridCoord TetraGrid::fold(int x, int y) const noexcept
{
    const int w = w_;
    // Each rule is an isometry of the grid keeping the diagonal direction. The x rule is a
    // translation; the two y rules compose to a translation by 2W in y, so repeating them
    // brings any position inside.
    for (;;)
    {
        if (x < 0)
            x += 2 * w;
        else if (x > 2 * w)
            x -= 2 * w;
        else if (y < 0)
        {
            x = 2 * w - x;  // point reflection through b = (W, 0)
            y = -y;
        }
        else if (y > w)
        {
            x = 2 * w - x;  // point reflection through c = (W, W)
            y = 2 * w - y;
        }
        else
            return {x, y};
    }
}

NodeIndex TetraGrid::image(int x, int y) const noexcept
{
    const GridCoord c = fold(x, y);
    return canonical(index(c.x, c.y));
}

std::array<NodeIndex, 4> TetraGrid::corners() const noexcept
{
    return {index(0, 0), index(w_, 0), index(w_, w_), index(0, w_)};
}

std::vector<std::array<std::uint32_t, 3>> TetraGrid::node_triangles() const
{
    std::vector<std::array<std::uint32_t, 3>> tris;
    tris.reserve(face_count());
    for (int y = 0; y < w_; ++y)
        for (int x = 0; x < 2 * w_; ++x)
        {
            const std::uint32_t n00 = index(x, y).value;
            const std::uint32_t n10 = index(x + 1, y).value;
            const std::uint32_t n11 = index(x + 1, y + 1).value;
            const std::uint32_t n01 = index(x, y + 1).value;
            tris.push_back({n00, n10, n11});
            tris.push_back({n00, n11, n01});
        }
    return tris;
}

std::vector<std::array<std::uint32_t, 3>> TetraGrid::triangles() const
{
    std::vector<std::array<std::uint32_t, 3>> tris = node_triangles();
    for (auto& t : tris)
        for (auto& v : t)
            v = unique_of_node_[v];
    return tris;
}

std::span<const GhostCopy> TetraGrid::ghost_table(int width) const noexcept
{
    PLIANT_ASSERT(width >= 1 && width <= k_max_ghost, "TetraGrid::ghost_table: bad width");
    return ghost_tables_[static_cast<std::size_t>(width)];
}

Region TetraGrid::leaf_region(LeafId leaf) const noexcept
{
    PLIANT_ASSERT(leaf.square <= 1 && leaf.depth <= level_, "leaf_region: bad leaf");
    const int size = w_ >> leaf.depth;
    PLIANT_ASSERT(leaf.ix < (1 << leaf.depth) && leaf.iy < (1 << leaf.depth),
                  "leaf_region: leaf position outside its square");
    Region r;
    r.x0 = leaf.square * w_ + leaf.ix * size;
    r.x1 = r.x0 + size;
    r.y0 = leaf.iy * size;
    r.y1 = r.y0 + size;
    if (r.y1 == w_)
        r.y1 = w_ + 1;  // the top row belongs to the upper leaves
    return r;
}

std::vector<LeafId> TetraGrid::leaves(int depth) const
{
    PLIANT_ASSERT(depth >= 0 && depth <= level_, "TetraGrid::leaves: bad depth");
    std::vector<LeafId> out;
    const int per_side = 1 << depth;
    out.reserve(2U * static_cast<std::size_t>(per_side) * static_cast<std::size_t>(per_side));
    for (int s = 0; s < 2; ++s)
        for (int iy = 0; iy < per_side; ++iy)
            for (int ix = 0; ix < per_side; ++ix)
                out.push_back(LeafId{static_cast<std::uint8_t>(s), static_cast<std::uint8_t>(depth),
                                     static_cast<std::uint16_t>(ix),
                                     static_cast<std::uint16_t>(iy)});
    return out;
}

std::array<NodeIndex, 6> grid_neighbours(const TetraGrid& grid, int x, int y)
{
    return {grid.image(x + 1, y), grid.image(x - 1, y),     grid.image(x, y + 1),
            grid.image(x, y - 1), grid.image(x + 1, y + 1), grid.image(x - 1, y - 1)};
}

std::vector<char> dilate_nodes(const TetraGrid& grid, std::vector<char> mask, int rings)
{
    PLIANT_ASSERT(mask.size() == grid.node_count(), "dilate_nodes: mask size");
    std::vector<std::uint32_t> front;
    for (std::uint32_t i = 0; i < mask.size(); ++i)
        if (mask[i] != 0)
            front.push_back(i);
    for (int r = 0; r < rings; ++r)
    {
        std::vector<std::uint32_t> next;
        for (const std::uint32_t i : front)
        {
            const GridCoord c = grid.coord(NodeIndex{i});
            for (const NodeIndex m : grid_neighbours(grid, c.x, c.y))
                if (mask[m.value] == 0)
                {
                    mask[m.value] = 1;
                    next.push_back(m.value);
                }
        }
        front = std::move(next);
    }
    return mask;
}

std::vector<Region> node_runs(const TetraGrid& grid, const std::vector<char>& mask)
{
    PLIANT_ASSERT(mask.size() == grid.node_count(), "node_runs: mask size");
    auto in = [&](int x, int y)
    {
        const NodeIndex n = grid.index(x, y);
        return grid.is_canonical(n) && mask[n.value] != 0;
    };
    // Row runs, merged with the run of the same span in the row above into one rectangle: the
    // restricted step works region by region with a few rows of overhead each, so fewer, taller
    // regions are cheaper (a union of leaves dilated by rings is mostly such rectangles).
    std::vector<Region> runs;
    std::vector<std::size_t> open;  // regions ending at the previous row
    for (int y = 0; y < grid.ny(); ++y)
    {
        std::vector<std::size_t> now;
        for (int x = 0; x < grid.nx();)
        {
            if (!in(x, y))
            {
                ++x;
                continue;
            }
            const int x0 = x;
            while (x < grid.nx() && in(x, y))
                ++x;
            bool merged = false;
            for (const std::size_t k : open)
                if (runs[k].x0 == x0 && runs[k].x1 == x && runs[k].y1 == y)
                {
                    runs[k].y1 = y + 1;
                    now.push_back(k);
                    merged = true;
                    break;
                }
            if (!merged)
            {
                runs.push_back(Region{x0, y, x, y + 1});
                now.push_back(runs.size() - 1);
            }
        }
        open = std::move(now);
    }
    return runs;
}

}  // namespace pliant::core
