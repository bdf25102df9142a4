// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The convolution against an independent implementation: OpenMesh's ModifiedButterflyT on the
// same level-n surface (docs/subdivision.md, "OpenMesh"). Each new OpenMesh vertex is matched to
// its edge by its two old neighbours (after a 1:4 split a new vertex is adjacent to exactly the
// two ends of the edge it split among the old vertices).
//
// Findings checked here:
// - every edge whose 8-tap stencil touches no corner: same position to 1e-12 relative (issue 4);
// - also every edge that merely has a corner among its b/c taps: OpenMesh applies its 8-point
//   rule there, found topologically, which is what the ghost map gives;
// - the 12 edges with a corner END: OpenMesh uses Zorin's valence-3 rule
//   (3/4 corner + 5/12 e0 - 1/12 (e1 + e2)), we use the regular mask with duplicated edges;
//   they differ, and OpenMesh's value is exactly that rule.
#include <pliant/subdiv/refine.h>

#include <gtest/gtest.h>

#include "grid_shapes.h"
#include "reference_openmesh.h"
#include "subdiv_test_helpers.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

namespace pliant::subdiv
{
namespace
{

using core::Field;
using core::TetraGrid;
using core::Vec3Field;

struct Comparison
{
    long plain = 0;          // stencil touches no corner
    long corner_taps = 0;    // a corner among b/c taps, not an end
    long corner_ends = 0;    // a corner is an end of the edge
    double worst_plain = 0;  // relative differences
    double worst_corner_taps = 0;
    double smallest_corner_end = 1e300;
    double worst_valence3_rule = 0;  // OpenMesh at corner ends vs Zorin's K = 3 rule
    long old_moved = 0;
};

Comparison compare(int level, const Vec3Field<double>& shape_coarse)
{
    const ConvolutionPlan plan = ConvolutionPlan::create(level).value();
    const TetraGrid& g = plan.coarse_grid();
    const TetraGrid& fg = plan.fine_grid();
    Vec3Field<double> fine{Field<double>(fg), Field<double>(fg), Field<double>(fg)};
    refine(plan, shape_coarse, fine);

    test::OmMesh mesh = test::to_openmesh(g, shape_coarse);
    const std::size_t n_old = mesh.n_vertices();
    EXPECT_TRUE(test::openmesh_butterfly(mesh, 1));
    EXPECT_EQ(mesh.n_vertices() - n_old, 6U * static_cast<std::size_t>(g.w() * g.w()));

    std::unordered_set<std::uint32_t> corner_ids;
    for (const core::NodeIndex c : g.corners())
        corner_ids.insert(g.unique_id(c));

    // Our odd nodes by edge, and whether their stencil touches a corner.
    struct OddNode
    {
        int x, y;
        bool corner_tap;
    };
    std::unordered_map<std::uint64_t, OddNode> by_edge;
    for (int fy = 0; fy < fg.ny(); ++fy)
        for (int fx = 0; fx < fg.nx(); ++fx)
        {
            if (!test::is_odd_node(fx, fy) || !fg.is_canonical(fg.index(fx, fy)))
                continue;
            const auto [p, q] = test::parent_edge(fx, fy);
            const EdgeDirection d = q.y == p.y   ? EdgeDirection::Horizontal
                                    : q.x == p.x ? EdgeDirection::Vertical
                                                 : EdgeDirection::Diagonal;
            bool touches = false;
            for (const Tap& t : mask(d))
                touches = touches || corner_ids.count(g.unique_id(g.image(p.x + t.dx, p.y + t.dy)));
            by_edge[test::edge_key(g.unique_id(g.index(p.x, p.y)),
                                   g.unique_id(g.index(q.x, q.y)))] = {fx, fy, touches};
        }

    auto point = [&](std::uint32_t unique)
    {
        const core::NodeIndex n = g.node_of_unique()[unique];
        return test::OmMesh::Point(shape_coarse[0][n], shape_coarse[1][n], shape_coarse[2][n]);
    };

    Comparison c;
    for (const auto vh : mesh.vertices())
    {
        const auto idx = static_cast<std::uint32_t>(vh.idx());
        if (idx < n_old)
        {
            c.old_moved += (mesh.point(vh) - point(idx)).norm() == 0.0 ? 0 : 1;
            continue;
        }
        std::vector<std::uint32_t> parents;
        for (const auto nb : mesh.vv_range(vh))
            if (static_cast<std::size_t>(nb.idx()) < n_old)
                parents.push_back(static_cast<std::uint32_t>(nb.idx()));
        EXPECT_EQ(parents.size(), 2U);
        if (parents.size() != 2)
            continue;
        const auto it = by_edge.find(test::edge_key(parents[0], parents[1]));
        EXPECT_NE(it, by_edge.end());
        if (it == by_edge.end())
            continue;
        const OddNode& node = it->second;
        const test::OmMesh::Point ours(fine[0].at(node.x, node.y), fine[1].at(node.x, node.y),
                                       fine[2].at(node.x, node.y));
        const double rel = (mesh.point(vh) - ours).norm() / std::max(1.0, ours.norm());
        const bool corner_end = corner_ids.count(parents[0]) || corner_ids.count(parents[1]);
        if (corner_end)
        {
            ++c.corner_ends;
            c.smallest_corner_end = std::min(c.smallest_corner_end, rel);
            // Zorin et al.'s valence-3 rule around the corner, other end weighted 5/12.
            const std::uint32_t corner = corner_ids.count(parents[0]) ? parents[0] : parents[1];
            const std::uint32_t other = corner == parents[0] ? parents[1] : parents[0];
            test::OmMesh::Point rule = 0.75 * point(corner) + (5.0 / 12.0) * point(other);
            // The corner's ring in OpenMesh is already split: take it from the coarse grid.
            const core::GridCoord cc = g.coord(g.node_of_unique()[corner]);
            std::unordered_set<std::uint32_t> ring;
            for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{1, 1}, std::pair{0, 1},
                                         std::pair{-1, 0}, std::pair{-1, -1}, std::pair{0, -1}})
                ring.insert(g.unique_id(g.image(cc.x + dx, cc.y + dy)));
            EXPECT_EQ(ring.size(), 3U) << "a corner has three distinct neighbours";
            for (const std::uint32_t r : ring)
                if (r != other)
                    rule -= (1.0 / 12.0) * point(r);
            c.worst_valence3_rule = std::max(
                c.worst_valence3_rule, (mesh.point(vh) - rule).norm() / std::max(1.0, rule.norm()));
        }
        else if (node.corner_tap)
        {
            ++c.corner_taps;
            c.worst_corner_taps = std::max(c.worst_corner_taps, rel);
        }
        else
        {
            ++c.plain;
            c.worst_plain = std::max(c.worst_plain, rel);
        }
    }
    return c;
}

Vec3Field<double> ellipsoid(const TetraGrid& g)
{
    Vec3Field<double> p = test::sphere_positions(g, 1);
    const double scale[3] = {3.0, 1.0, 0.5};
    for (std::size_t c = 0; c < 3; ++c)
        for (double& v : p[c].padded())
            v *= scale[c];
    return p;
}

TEST(OpenMeshButterfly, SameNewVerticesAwayFromCorners)
{
    for (int level = 2; level <= 5; ++level)
        for (int shape = 0; shape < 2; ++shape)
        {
            const TetraGrid g = TetraGrid::create(level).value();
            const Vec3Field<double> coarse =
                shape == 0 ? test::sphere_positions(g, 1) : ellipsoid(g);
            const Comparison c = compare(level, coarse);
            SCOPED_TRACE("level " + std::to_string(level) + " shape " + std::to_string(shape));
            EXPECT_EQ(c.old_moved, 0) << "the scheme interpolates";
            EXPECT_GT(c.plain, 0);
            EXPECT_LE(c.worst_plain, 1e-12);
            // Stronger than the issue asks: corner vertices among b/c taps agree too.
            EXPECT_GT(c.corner_taps, 0);
            EXPECT_LE(c.worst_corner_taps, 1e-12);
            EXPECT_EQ(c.plain + c.corner_taps + c.corner_ends,
                      6L * static_cast<long>(g.w()) * g.w());
        }
}

TEST(OpenMeshButterfly, CornerEdgesDifferByTheValence3Rule)
{
    for (int level = 2; level <= 5; ++level)
    {
        const TetraGrid g = TetraGrid::create(level).value();
        const Comparison c = compare(level, test::sphere_positions(g, 1));
        SCOPED_TRACE("level " + std::to_string(level));
        EXPECT_EQ(c.corner_ends, 12) << "three edges at each of four corners";
        EXPECT_LE(c.worst_valence3_rule, 1e-12) << "OpenMesh uses Zorin's K = 3 rule there";
        EXPECT_GT(c.smallest_corner_end, 1e-6) << "and we do not (duplicated regular mask)";
    }
}

}  // namespace
}  // namespace pliant::subdiv
