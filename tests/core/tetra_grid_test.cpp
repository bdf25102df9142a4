// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Topology of the tetrahedral grid at every level, checked by counting (docs/design.md §1): the
// counts come from the closed-form tetrahedron subdivision, not from the grid code.
#include <pliant/core/tetra_grid.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <utility>

namespace pliant::core
{
namespace
{

using Tri = std::array<std::uint32_t, 3>;

Tri sorted(Tri t)
{
    std::sort(t.begin(), t.end());
    return t;
}

class GridLevel : public ::testing::TestWithParam<int>
{
protected:
    TetraGrid grid() const { return TetraGrid::create(GetParam()).value(); }
};

TEST_P(GridLevel, CountsAndEulerCharacteristic)
{
    const TetraGrid g = grid();
    const std::size_t w = static_cast<std::size_t>(g.w());
    EXPECT_EQ(g.node_count(), (2 * w + 1) * (w + 1));
    EXPECT_EQ(g.unique_count(), 2 * w * w + 2);
    const auto tris = g.triangles();
    EXPECT_EQ(tris.size(), 4 * w * w);

    // Sorting instead of maps keeps level 10 (4M faces) fast, also under sanitizers.
    std::vector<std::uint64_t> edges;
    edges.reserve(3 * tris.size());
    std::vector<Tri> distinct;
    distinct.reserve(tris.size());
    for (const Tri& t : tris)
    {
        ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) << "degenerate face";
        distinct.push_back(sorted(t));
        for (int k = 0; k < 3; ++k)
        {
            const std::uint64_t a = t[static_cast<std::size_t>(k)];
            const std::uint64_t b = t[static_cast<std::size_t>((k + 1) % 3)];
            edges.push_back((std::min(a, b) << 32) | std::max(a, b));
        }
    }
    std::sort(distinct.begin(), distinct.end());
    EXPECT_EQ(std::unique(distinct.begin(), distinct.end()), distinct.end())
        << "two grid triangles are the same face";
    std::sort(edges.begin(), edges.end());
    std::size_t edge_count = 0;
    for (std::size_t i = 0; i < edges.size();)
    {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i])
            ++j;
        ASSERT_EQ(j - i, 2U) << "edge " << (edges[i] >> 32) << "-" << (edges[i] & 0xffffffffU)
                             << " is not shared by exactly two faces";
        ++edge_count;
        i = j;
    }
    EXPECT_EQ(edge_count, 6 * w * w);
    const long chi = static_cast<long>(g.unique_count()) - static_cast<long>(edge_count) +
                     static_cast<long>(tris.size());
    EXPECT_EQ(chi, 2);
}

TEST_P(GridLevel, OrientationIsConsistent)
{
    // On a closed oriented surface every directed edge appears exactly once.
    const TetraGrid g = grid();
    std::vector<std::uint64_t> directed;
    for (const Tri& t : g.triangles())
        for (int k = 0; k < 3; ++k)
            directed.push_back((std::uint64_t{t[static_cast<std::size_t>(k)]} << 32) |
                               t[static_cast<std::size_t>((k + 1) % 3)]);
    std::sort(directed.begin(), directed.end());
    EXPECT_EQ(std::adjacent_find(directed.begin(), directed.end()), directed.end());
}

TEST_P(GridLevel, ValenceThreeAtTheFourCornersSixElsewhere)
{
    const TetraGrid g = grid();
    std::vector<std::uint64_t> edges;
    for (const Tri& t : g.triangles())
        for (int k = 0; k < 3; ++k)
        {
            const std::uint64_t p = t[static_cast<std::size_t>(k)];
            const std::uint64_t q = t[static_cast<std::size_t>((k + 1) % 3)];
            edges.push_back((std::min(p, q) << 32) | std::max(p, q));
        }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    std::vector<int> valence(g.unique_count(), 0);
    for (const std::uint64_t e : edges)
    {
        ++valence[e >> 32];
        ++valence[e & 0xffffffffU];
    }
    std::set<std::uint32_t> corner_ids;
    for (NodeIndex c : g.corners())
    {
        EXPECT_TRUE(g.is_canonical(c));
        corner_ids.insert(g.unique_id(c));
    }
    ASSERT_EQ(corner_ids.size(), 4U);
    int valence3 = 0;
    for (std::uint32_t v = 0; v < valence.size(); ++v)
    {
        if (corner_ids.count(v) != 0)
        {
            EXPECT_EQ(valence[v], 3) << "corner " << v;
            ++valence3;
        }
        else
        {
            ASSERT_EQ(valence[v], 6) << "vertex " << v;
        }
    }
    EXPECT_EQ(valence3, 4);
}

TEST_P(GridLevel, GhostsLandInRangeOnCanonicalNodes)
{
    const TetraGrid g = grid();
    const int width = k_max_ghost;
    for (int y = -width; y < g.ny() + width; ++y)
        for (int x = -width; x < g.nx() + width; ++x)
        {
            const GridCoord f = g.fold(x, y);
            ASSERT_TRUE(g.in_range(f.x, f.y)) << x << "," << y;
            const NodeIndex n = g.image(x, y);
            ASSERT_TRUE(g.is_canonical(n));
            if (g.in_range(x, y))
            {
                ASSERT_EQ(n, g.canonical(g.index(x, y)));
            }
        }
}

TEST_P(GridLevel, GhostMapPreservesTriangles)
{
    // Every grid triangle of the padded plane (at least one vertex inside) maps to a real face.
    const TetraGrid g = grid();
    std::vector<Tri> faces;
    for (const Tri& t : g.triangles())
        faces.push_back(sorted(t));
    std::sort(faces.begin(), faces.end());
    auto is_face = [&](const Tri& t) { return std::binary_search(faces.begin(), faces.end(), t); };
    const int width = std::min(2, g.w());
    auto uid = [&](int x, int y) { return g.unique_id(g.image(x, y)); };
    int checked = 0;
    for (int y = -width; y < g.ny() + width - 1; ++y)
        for (int x = -width; x < g.nx() + width - 1; ++x)
        {
            const bool touches = g.in_range(x, y) || g.in_range(x + 1, y) ||
                                 g.in_range(x + 1, y + 1) || g.in_range(x, y + 1);
            if (!touches)
                continue;
            const Tri lower = sorted({uid(x, y), uid(x + 1, y), uid(x + 1, y + 1)});
            const Tri upper = sorted({uid(x, y), uid(x + 1, y + 1), uid(x, y + 1)});
            ASSERT_TRUE(is_face(lower)) << "cell " << x << "," << y << " lower";
            ASSERT_TRUE(is_face(upper)) << "cell " << x << "," << y << " upper";
            checked += 2;
        }
    EXPECT_GT(checked, static_cast<int>(g.face_count()));
}

TEST_P(GridLevel, GhostTablesPointAtCanonicalSources)
{
    const TetraGrid g = grid();
    for (int width = 1; width <= k_max_ghost; ++width)
    {
        const std::int64_t stride = g.nx() + 2 * width;
        const auto table = g.ghost_table(width);
        const std::size_t ring =
            static_cast<std::size_t>(stride * (g.ny() + 2 * width)) - g.node_count();
        EXPECT_EQ(table.size(), ring);
        for (const GhostCopy& c : table)
        {
            const int sx = static_cast<int>(c.src % stride) - width;
            const int sy = static_cast<int>(c.src / stride) - width;
            ASSERT_TRUE(g.in_range(sx, sy));
            ASSERT_TRUE(g.is_canonical(g.index(sx, sy)));
        }
    }
}

TEST_P(GridLevel, TwinsAreTheGluedBorderNodes)
{
    const TetraGrid g = grid();
    const int w = g.w();
    EXPECT_EQ(g.twins().size(), g.node_count() - g.unique_count());
    for (const TwinPair& t : g.twins())
    {
        const GridCoord a = g.coord(t.twin);
        const GridCoord c = g.coord(t.canonical);
        EXPECT_LT(t.canonical, t.twin);
        const bool on_border = a.x == 0 || a.x == 2 * w || a.y == 0 || a.y == w;
        EXPECT_TRUE(on_border) << a.x << "," << a.y;
        // the twin's folded image under the gluing rules is itself, and the ghost just outside
        // the canonical node's side lands back on the surface next to it.
        EXPECT_TRUE(g.in_range(c.x, c.y));
    }
    EXPECT_EQ(g.canonical(g.index(2 * w, 0)), g.index(0, 0));
    EXPECT_EQ(g.canonical(g.index(2 * w, w)), g.index(0, w));
    EXPECT_EQ(g.canonical(g.index(2 * w - 1, 0)), g.index(1, 0));
    EXPECT_EQ(g.canonical(g.index(w + 1, w)), g.index(w - 1, w));
}

TEST_P(GridLevel, EveryCanonicalNodeInExactlyOneLeafAtEachDepth)
{
    const TetraGrid g = grid();
    for (int depth = 0; depth <= g.level(); ++depth)
    {
        std::vector<int> owners(g.node_count(), 0);
        for (const LeafId leaf : g.leaves(depth))
        {
            const Region r = g.leaf_region(leaf);
            for (int y = r.y0; y < r.y1; ++y)
                for (int x = r.x0; x < r.x1; ++x)
                {
                    ASSERT_TRUE(g.in_range(x, y));
                    const NodeIndex n = g.index(x, y);
                    if (g.is_canonical(n))
                        ++owners[n.value];
                }
        }
        for (std::uint32_t i = 0; i < owners.size(); ++i)
        {
            const NodeIndex n{i};
            ASSERT_EQ(owners[i], g.is_canonical(n) ? 1 : 0)
                << "depth " << depth << " node " << g.coord(n).x << "," << g.coord(n).y;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Levels1To10, GridLevel, ::testing::Range(1, 11));

TEST(TetraGrid, RefusesLevelsOutsideOneToTen)
{
    for (int bad : {-1, 0, 11, 30})
    {
        auto g = TetraGrid::create(bad);
        ASSERT_FALSE(g.has_value());
        EXPECT_EQ(g.error().code, ErrorCode::InvalidArgument);
        EXPECT_NE(g.error().message.find("level"), std::string::npos);
    }
}

TEST(TetraGrid, NodeCountsOfTheLiterature)
{
    EXPECT_EQ(TetraGrid::create(6)->node_count(), 8385U);
    EXPECT_EQ(TetraGrid::create(7)->node_count(), 33153U);
    EXPECT_EQ(TetraGrid::create(8)->node_count(), 131841U);
}

}  // namespace
}  // namespace pliant::core
