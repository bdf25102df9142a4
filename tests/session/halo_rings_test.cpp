// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Why the exact coupling integrates its nodes dilated by halo rings: a restricted RKF45 step
// holds the other nodes fixed, and the error this makes moves inwards as the stages read their
// neighbours' stage displacements. In the sim's fused form U_s = u + h c_s v + h^2 (A^2 kv)_s,
// stage s reads slopes up to s-2 only (A is strictly lower triangular), so the error moves one
// ring per two stages and has reached ring 3 by the sixth. With a large step (the error far
// above rounding) and a rough state, a step restricted to a share dilated by r rings equals the
// full step bit for bit on the share exactly when r >= 3 (docs/session.md §4).
#include <pliant/session/partition.h>
#include <pliant/sim/rkf45.h>

#include <gtest/gtest.h>

#include "grid_shapes.h"

#include <cmath>
#include <cstdio>
#include <random>

namespace pliant::session
{
namespace
{

// `needed`: the step computes each stage pair only where the share reads it
// (StepOptions::needed).
double restricted_error(int rings, bool needed = false)
{
    const int level = 5;
    const core::TetraGrid g = core::TetraGrid::create(level).value();
    sim::MembraneSettings set;
    set.fixed_step = true;
    set.fixed_dt = 0.02;  // h^2 K/M ~ 0.1: the contamination stays far above rounding
    set.beta = 0.3;
    set.k_f = 1.0;
    set.threads = 1;
    auto model = sim::MembraneModel::create(g, scenes::sphere_grid(g, 1.0), set).value();
    sim::MembraneState start = sim::MembraneState::at_rest(g);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uni(-1e-2, 1e-2);
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            start.u.at(x, y) = uni(rng);
            start.v.at(x, y) = uni(rng);
        }
    model.sync(start.u);
    model.sync(start.v);

    sim::MembraneState full = start;
    sim::Rkf45Workspace ws_full(model, 1);
    sim::step(model, full, ws_full, {});

    // A share: the leaves of square 0 with iy < 2 (a quarter of the surface).
    const LeafGraph graph(g, 2);
    std::vector<char> share(g.node_count(), 0);
    for (std::size_t l = 0; l < graph.size(); ++l)
        if (graph.leaves()[l].square == 0 && graph.leaves()[l].iy < 2)
            for (const core::NodeIndex n : graph.nodes(l))
                share[n.value] = 1;
    const auto runs = core::node_runs(g, core::dilate_nodes(g, share, rings));
    sim::MembraneState part = start;
    sim::Rkf45Workspace ws_part(model, 1);
    const auto own = core::node_runs(g, share);
    sim::StepOptions opt;
    opt.owned = runs;
    if (needed)
        opt.needed = own;
    sim::step(model, part, ws_part, {}, opt);

    double err = 0.0;
    for (std::uint32_t i = 0; i < g.node_count(); ++i)
        if (share[i] != 0)
        {
            const core::GridCoord c = g.coord(core::NodeIndex{i});
            err = std::max(err, std::fabs(part.u.at(c.x, c.y) - full.u.at(c.x, c.y)));
            err = std::max(err, std::fabs(part.v.at(c.x, c.y) - full.v.at(c.x, c.y)));
        }
    return err;
}

TEST(HaloRings, ThreeRingsMakeARestrictedStepExactAndTwoDoNot)
{
    const double e0 = restricted_error(0);
    const double e1 = restricted_error(1);
    const double e2 = restricted_error(2);
    std::printf("restricted vs full step on the share: rings 0 %.3e, 1 %.3e, 2 %.3e\n", e0, e1, e2);
    EXPECT_GT(e0, e1);
    EXPECT_GT(e1, e2);
    EXPECT_GT(e2, 0.0);
    for (const int r : {3, 4, 5, 6, 7})
        EXPECT_EQ(restricted_error(r), 0.0) << r;
}

// The same with the stage pairs cut to where the share reads them (as sessions step): the
// share's error is the plain restricted step's, exact from 3 rings.
TEST(HaloRings, NeededNodesNeedTheSameThreeRings)
{
    for (const int r : {0, 1, 2})
    {
        EXPECT_EQ(restricted_error(r, true), restricted_error(r)) << r;
        EXPECT_GT(restricted_error(r, true), 0.0) << r;
    }
    for (const int r : {3, 4, 6})
        EXPECT_EQ(restricted_error(r, true), 0.0) << r;
}

TEST(HaloRings, DilationFollowsTheGhostMapAndRunsCoverExactlyTheMask)
{
    const core::TetraGrid g = core::TetraGrid::create(4).value();
    std::vector<char> one(g.node_count(), 0);
    const core::NodeIndex a = g.corners()[0];
    one[a.value] = 1;
    const auto d1 = core::dilate_nodes(g, one, 1);
    // A corner of the tetrahedron has three surface neighbours (and itself).
    std::size_t count = 0;
    for (std::uint32_t i = 0; i < g.node_count(); ++i)
        count += d1[i] != 0 ? 1U : 0U;
    EXPECT_EQ(count, 4U);
    const auto d3 = core::dilate_nodes(g, one, 3);
    std::size_t covered = 0;
    for (const core::Region& r : core::node_runs(g, d3))
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x)
            {
                EXPECT_TRUE(g.is_canonical(g.index(x, y)));
                EXPECT_NE(d3[g.index(x, y).value], 0);
                ++covered;
            }
    std::size_t canonical_in_mask = 0;
    for (std::uint32_t i = 0; i < g.node_count(); ++i)
        canonical_in_mask += (d3[i] != 0 && g.is_canonical(core::NodeIndex{i})) ? 1U : 0U;
    EXPECT_EQ(covered, canonical_in_mask);
}

}  // namespace
}  // namespace pliant::session
