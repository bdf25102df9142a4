// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The fused row pipeline of full steps (src/sim/row_pipeline.cpp) against (1) the stage-by-stage
// pass, bit for bit, and (2) a slow straightforward RKF45 step written here from the classic
// tableau: full stage planes U_s, V_s, kv_s, K applied with apply_stiffness, Dirichlet nodes
// outside the owned regions, the error norm over canonical nodes found by TetraGrid.

#include <pliant/core/tetra_grid.h>
#include <pliant/sim/rkf45.h>

#include <gtest/gtest.h>

#include "sim_test_util.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

namespace pliant::sim
{
namespace
{

MembraneSettings settings(int threads, bool fixed, int leaf_depth = -1)
{
    MembraneSettings s;
    s.beta = 0.4;
    s.k_f = 0.7;
    s.rtol = 1e-5;
    s.threads = threads;
    s.fixed_step = fixed;
    s.fixed_dt = 0.002;
    s.leaf_depth = leaf_depth;
    return s;
}

// A state with structure everywhere, corners and seams included.
MembraneState varied_state(const MembraneModel& m)
{
    MembraneState s = MembraneState::at_rest(m.grid());
    test::set_field(m, s.u,
                    [](const core::Vec3& p) { return 0.01 * p.x * p.z + 0.003 * p.y - 0.002; });
    test::set_field(m, s.v, [](const core::Vec3& p) { return 0.02 * p.y * p.y - 0.01 * p.z; });
    return s;
}

// A point force near the tetrahedron corner (0, 0), one on face 0 (at that corner), and a
// point force on the seam x = 0 / x = 2W.
std::vector<Force> forces_for(const MembraneModel& m)
{
    const core::TetraGrid& g = m.grid();
    const core::Vec3 corner = test::rest(m, g.index(0, 0));
    const core::Vec3 seam = test::rest(m, g.index(0, g.w() / 2));
    return {{-1, corner, 0.5, {0.1, 0.3, 0.2}},
            {0, {}, 0.0, {1.0, 0.0, 0.5}},
            {-1, seam, 0.3, {-0.2, 0.1, 0.4}}};
}

// Owned regions of a "peer": a few leaves and single-row runs through the corners and the
// seam, as sessions pass them.
std::vector<core::Region> some_regions(const MembraneModel& m)
{
    const core::TetraGrid& g = m.grid();
    const int w = g.w();
    std::vector<core::Region> r;
    const auto leaves = m.leaf_regions();
    for (std::size_t k = 0; k < leaves.size(); k += 3)
        r.push_back(leaves[k]);
    r.push_back({0, 0, w / 2 + 1, 1});          // bottom row from corner a
    r.push_back({w - 1, w, w + 1, w + 1});      // around corner c on the top row
    r.push_back({2 * w - 1, 1, 2 * w + 1, 2});  // the seam x = 2W
    return r;
}

// `ramp`: the forces ramp up over the first half (a linear hold, begin_force_ramp) and down
// to none over the second, so every stage adds accel + ft * rate with both planes non-zero.
std::vector<MembraneState> run(MembraneModel m, bool pipeline, std::span<const core::Region> owned,
                               int steps, std::vector<StepReport>& reports, bool ramp = false)
{
    MembraneState s = varied_state(m);
    Rkf45Workspace ws(m, std::max(1, m.settings().threads));
    EXPECT_TRUE(ws.pipeline_ok);
    ws.use_pipeline = pipeline;
    const std::vector<Force> f = forces_for(m);
    StepOptions opt;
    opt.owned = owned;
    std::vector<MembraneState> states;
    for (int k = 0; k < steps; ++k)
    {
        if (ramp)
        {
            if (k == 0)
                begin_force_ramp(m, ws, f, s.time, s.time + 0.02);
            if (k == steps / 2)
                begin_force_ramp(m, ws, {}, s.time, s.time + 0.01);
            reports.push_back(step_prepared(m, s, ws, opt));
        }
        else
            reports.push_back(
                step(m, s, ws, k < steps / 2 ? std::span<const Force>(f) : std::span<const Force>(),
                     opt));
        states.push_back(s);
    }
    return states;
}

TEST(Pipeline, PlannedForEveryLevel)
{
    for (int level = 1; level <= 10; ++level)
    {
        MembraneModel m = test::sphere_model(level, settings(1, true));
        const Rkf45Workspace ws(m, 3);
        EXPECT_TRUE(ws.pipeline_ok) << "level " << level;
        EXPECT_EQ(ws.below_copies.size(), static_cast<std::size_t>(m.grid().nx() + 2));
        EXPECT_EQ(ws.above_copies.size(), static_cast<std::size_t>(m.grid().nx() + 2));
    }
}

// The pipeline (any number of bands) and the stage-by-stage pass give the same bits, step by
// step, in adaptive (with rejections) and fixed mode; so do restricted steps over all leaves.
TEST(Pipeline, EqualsStageByStagePassBitForBit)
{
    for (int level = 1; level <= 6; ++level)
        for (const bool fixed : {false, true})
            for (const bool ramp : {false, true})
            {
                std::vector<StepReport> ref_reports;
                const std::vector<MembraneState> ref =
                    run(test::sphere_model(level, settings(1, fixed)), false, {}, 24, ref_reports,
                        ramp);
                for (const int threads : {1, 2, 3})
                {
                    std::vector<StepReport> reports;
                    const std::vector<MembraneState> got =
                        run(test::sphere_model(level, settings(threads, fixed)), true, {}, 24,
                            reports, ramp);
                    for (std::size_t k = 0; k < ref.size(); ++k)
                    {
                        ASSERT_EQ(got[k].hash(), ref[k].hash())
                            << "level " << level << (fixed ? " fixed" : " adaptive")
                            << (ramp ? " ramp" : "") << ", " << threads << " threads, step " << k;
                        ASSERT_EQ(got[k].u, ref[k].u);
                        ASSERT_EQ(got[k].v, ref[k].v);
                        ASSERT_EQ(reports[k].dt, ref_reports[k].dt);
                        ASSERT_EQ(reports[k].error, ref_reports[k].error);
                        ASSERT_EQ(reports[k].rejections, ref_reports[k].rejections);
                    }
                }
                // Restricted to every leaf: the stage pass again, equal to the pipeline.
                MembraneModel m = test::sphere_model(level, settings(2, fixed));
                const std::vector<core::Region> all(m.leaf_regions().begin(),
                                                    m.leaf_regions().end());
                std::vector<StepReport> reports;
                const std::vector<MembraneState> got =
                    run(std::move(m), true, all, 24, reports, ramp);
                for (std::size_t k = 0; k < ref.size(); ++k)
                    ASSERT_EQ(got[k].hash(), ref[k].hash()) << "level " << level << " restricted";
            }
}

// Owned sets shaped like a session's (leaves at depth level - 3, as sessions use): one leaf,
// the first half of the leaves, every other leaf (disjoint leaves touching at corners), the
// leaves of square 1 (its seams with square 0 and the folded rows), every leaf (a full step),
// exact-mode-like runs (a block of leaves dilated by two rings, as single-row regions), strips
// holding the twin column x = 2W or the folded halves of rows 0 and W without their canonical
// nodes (Dirichlet twins inside owned regions), and the overlapping regions of some_regions.
std::vector<std::vector<core::Region>> partition_like_sets(const MembraneModel& m)
{
    const core::TetraGrid& g = m.grid();
    const int w = g.w();
    std::vector<core::Region> leaves;
    for (const core::LeafId& l : g.leaves(std::max(0, g.level() - 3)))
        leaves.push_back(g.leaf_region(l));
    const std::size_t n = leaves.size();
    std::vector<std::vector<core::Region>> sets;
    sets.push_back({leaves[n / 2 + (n > 4 ? 1 : 0)]});
    sets.emplace_back(leaves.begin(), leaves.begin() + static_cast<std::ptrdiff_t>(n / 2));
    std::vector<core::Region> every_other;
    for (std::size_t k = 0; k < n; k += 2)
        every_other.push_back(leaves[k]);
    sets.push_back(every_other);
    std::vector<core::Region> square1;
    for (const core::Region& r : leaves)
        if (r.x0 >= w)
            square1.push_back(r);
    sets.push_back(square1);
    sets.push_back(leaves);
    // A block of leaves around (W/2, W/2) dilated by two rings, row by row.
    const core::Region block{std::max(0, w / 4 - 2), std::max(0, w / 4 - 2),
                             std::min(g.nx(), 3 * w / 4 + 2), std::min(g.ny(), 3 * w / 4 + 2)};
    std::vector<core::Region> runs;
    for (int y = block.y0; y < block.y1; ++y)
        runs.push_back({block.x0, y, block.x1, y + 1});
    sets.push_back(runs);
    sets.push_back({{2 * w - 2, 0, 2 * w + 1, g.ny()}});            // x = 2W without x = 0
    sets.push_back({{0, 0, 3, g.ny()}, {w + 1, 0, 2 * w + 1, 1}});  // x = 0; folded row 0
    sets.push_back({{w, w, 2 * w + 1, w + 1}, {w - 1, w - 1, w + 2, w + 1}});  // folded row W
    sets.push_back(some_regions(m));
    return sets;
}

// Restricted steps on the pipeline give the stage pass's bits for partition-like owned sets,
// step by step, at levels 1-6, adaptive and fixed, for 1-3 threads.
TEST(Pipeline, RestrictedEqualsStageByStagePassBitForBit)
{
    for (int level = 1; level <= 6; ++level)
        for (const bool fixed : {false, true})
        {
            const MembraneModel probe = test::sphere_model(level, settings(1, fixed));
            const std::vector<std::vector<core::Region>> sets = partition_like_sets(probe);
            for (std::size_t set = 0; set < sets.size(); ++set)
            {
                std::vector<StepReport> ref_reports;
                const std::vector<MembraneState> ref =
                    run(test::sphere_model(level, settings(1, fixed)), false, sets[set], 12,
                        ref_reports);
                for (const int threads : {1, 2, 3})
                {
                    std::vector<StepReport> reports;
                    const std::vector<MembraneState> got =
                        run(test::sphere_model(level, settings(threads, fixed)), true, sets[set],
                            12, reports);
                    for (std::size_t k = 0; k < ref.size(); ++k)
                    {
                        const std::string where =
                            "level " + std::to_string(level) + (fixed ? " fixed" : " adaptive") +
                            ", set " + std::to_string(set) + ", " + std::to_string(threads) +
                            " threads, step " + std::to_string(k);
                        ASSERT_EQ(got[k].hash(), ref[k].hash()) << where;
                        ASSERT_EQ(got[k].u, ref[k].u) << where;
                        ASSERT_EQ(got[k].v, ref[k].v) << where;
                        ASSERT_EQ(reports[k].dt, ref_reports[k].dt) << where;
                        ASSERT_EQ(reports[k].error, ref_reports[k].error) << where;
                        ASSERT_EQ(reports[k].rejections, ref_reports[k].rejections) << where;
                    }
                }
            }
        }
}

// Alternating owned sets in one workspace (the plan is cached per set) still gives the stage
// pass's bits.
TEST(Pipeline, RestrictedPlanFollowsTheOwnedSet)
{
    MembraneModel m = test::sphere_model(4, settings(2, false));
    const std::vector<std::vector<core::Region>> sets = partition_like_sets(m);
    MembraneState a = varied_state(m);
    MembraneState b = a;
    Rkf45Workspace wa(m, 2);
    Rkf45Workspace wb(m, 2);
    wb.use_pipeline = false;
    const std::vector<Force> f = forces_for(m);
    for (int k = 0; k < 30; ++k)
    {
        StepOptions opt;
        opt.owned = sets[static_cast<std::size_t>(k * 7) % sets.size()];
        const StepReport ra = step(m, a, wa, f, opt);
        const StepReport rb = step(m, b, wb, f, opt);
        ASSERT_EQ(a.u, b.u) << "step " << k;
        ASSERT_EQ(a.v, b.v) << "step " << k;
        ASSERT_EQ(ra.dt, rb.dt) << "step " << k;
        ASSERT_EQ(ra.rejections, rb.rejections) << "step " << k;
    }
}

// The canonical nodes inside `regions`, as a node mask.
std::vector<char> region_mask(const core::TetraGrid& g, std::span<const core::Region> regions)
{
    std::vector<char> mask(g.node_count(), 0);
    for (const core::Region& r : regions)
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x)
                if (const core::NodeIndex n = g.index(x, y); g.is_canonical(n))
                    mask[n.value] = 1;
    return mask;
}

// StepOptions::needed: the partition-like sets as needed nodes, owned = them dilated by 0-4
// rings. The pipeline (1-3 threads) gives the stage pass's bits, step by step, adaptive
// (the error norm over the needed nodes: same dt, error and rejections) and fixed; one fixed step
// gives the bits of the restricted step over the owned set on every needed node and leaves the
// other owned nodes as they were.
TEST(Pipeline, NeededNodesGetTheRestrictedStepsBits)
{
    for (int level = 1; level <= 6; ++level)
    {
        const MembraneModel probe = test::sphere_model(level, settings(1, true));
        const core::TetraGrid& g = probe.grid();
        const std::vector<std::vector<core::Region>> sets = partition_like_sets(probe);
        for (std::size_t set = 0; set < sets.size(); ++set)
            for (const int rings : {0, 1, 2, 3, 4})
            {
                const std::vector<char> want = region_mask(g, sets[set]);
                const std::vector<core::Region> owned =
                    core::node_runs(g, core::dilate_nodes(g, want, rings));
                const std::vector<core::Region> needed = core::node_runs(g, want);
                const std::string where0 = "level " + std::to_string(level) + ", set " +
                                           std::to_string(set) + ", " + std::to_string(rings) +
                                           " rings";
                for (const bool fixed : {false, true})
                {
                    const auto steps =
                        [&](bool pipeline, int threads, std::vector<StepReport>& reports)
                    {
                        MembraneModel m = test::sphere_model(level, settings(threads, fixed));
                        MembraneState s = varied_state(m);
                        Rkf45Workspace ws(m, threads);
                        ws.use_pipeline = pipeline;
                        const std::vector<Force> f = forces_for(m);
                        StepOptions opt;
                        opt.owned = owned;
                        opt.needed = needed;
                        std::vector<MembraneState> out;
                        for (int k = 0; k < 6; ++k)
                        {
                            reports.push_back(step(m, s, ws, f, opt));
                            out.push_back(s);
                        }
                        return out;
                    };
                    std::vector<StepReport> ref_reports;
                    const std::vector<MembraneState> ref = steps(false, 1, ref_reports);
                    for (const int threads : {1, 2, 3})
                    {
                        std::vector<StepReport> reports;
                        const std::vector<MembraneState> got = steps(true, threads, reports);
                        for (std::size_t k = 0; k < ref.size(); ++k)
                        {
                            const std::string where =
                                where0 + (fixed ? ", fixed, " : ", adaptive, ") +
                                std::to_string(threads) + " threads, step " + std::to_string(k);
                            ASSERT_EQ(got[k].u, ref[k].u) << where;
                            ASSERT_EQ(got[k].v, ref[k].v) << where;
                            ASSERT_EQ(reports[k].dt, ref_reports[k].dt) << where;
                            ASSERT_EQ(reports[k].error, ref_reports[k].error) << where;
                            ASSERT_EQ(reports[k].rejections, ref_reports[k].rejections) << where;
                        }
                    }
                }
                // One fixed step against the restricted step over the owned set.
                MembraneModel m = test::sphere_model(level, settings(2, true));
                const std::vector<Force> f = forces_for(m);
                MembraneState start = varied_state(m);
                Rkf45Workspace ws(m, 2);
                (void)step(m, start, ws, f);  // every slope non-zero
                MembraneState plain = start;
                MembraneState tiered = start;
                StepOptions opt;
                opt.owned = owned;
                (void)step(m, plain, ws, f, opt);
                opt.needed = needed;
                (void)step(m, tiered, ws, f, opt);
                for (int y = 0; y < g.ny(); ++y)
                    for (int x = 0; x < g.nx(); ++x)
                    {
                        const core::NodeIndex c = g.image(x, y);
                        const MembraneState& expect = want[c.value] != 0 ? plain : start;
                        ASSERT_EQ(tiered.u.at(x, y), expect.u.at(x, y))
                            << where0 << " at (" << x << ", " << y << ")";
                        ASSERT_EQ(tiered.v.at(x, y), expect.v.at(x, y))
                            << where0 << " at (" << x << ", " << y << ")";
                    }
            }
    }
}

// StepOptions::keep_outside = false, the swapping step: the partition-like sets as needed
// nodes, owned = them dilated by 0 rings (fast coupling's shape: needed = owned) or 3 (exact
// coupling's), levels 1-6, adaptive and fixed, 1-2 threads, and a caller that writes new values
// into every node beyond the owned ones (canonical positions and twins, not the ghosts) before
// every other step, as the session's fast peers do once per frame of several steps. After every
// step each owned node and each node of the first ring around them holds the copying step's
// bits, and dt, error and rejections are the same. The state has structure everywhere and the
// workspace's trial planes start at zero, so a node or a twin or ghost copy left out of what
// the swap carries over or syncs would show: in the kept nodes at once, and in the steps the
// caller does not prepare.
TEST(Pipeline, SwappingAcceptKeepsWhatTheNextStepReads)
{
    for (int level = 1; level <= 6; ++level)
    {
        const MembraneModel probe = test::sphere_model(level, settings(1, true));
        const core::TetraGrid& g = probe.grid();
        const std::vector<std::vector<core::Region>> sets = partition_like_sets(probe);
        for (std::size_t set = 0; set < sets.size(); ++set)
            for (const int rings : {0, 3})
            {
                const std::vector<char> want = region_mask(g, sets[set]);
                const std::vector<char> own = core::dilate_nodes(g, want, rings);
                const std::vector<char> kept = core::dilate_nodes(g, own, 1);
                const std::vector<core::Region> owned = core::node_runs(g, own);
                const std::vector<core::Region> needed =
                    rings > 0 ? core::node_runs(g, want) : std::vector<core::Region>{};
                for (const bool fixed : {false, true})
                    for (const int threads : {1, 2})
                    {
                        const auto steps = [&](bool keep_outside, std::vector<StepReport>& reports)
                        {
                            MembraneModel m = test::sphere_model(level, settings(threads, fixed));
                            MembraneState s = varied_state(m);
                            Rkf45Workspace ws(m, threads);
                            const std::vector<Force> f = forces_for(m);
                            StepOptions opt;
                            opt.owned = owned;
                            opt.needed = needed;
                            opt.keep_outside = keep_outside;
                            std::vector<MembraneState> out;
                            for (int k = 0; k < 6; ++k)
                            {
                                // The caller's boundary values, new before every other step
                                // (from the canonical node's coordinates, so twins agree).
                                for (int y = 0; y < g.ny() && k % 2 == 0; ++y)
                                    for (int x = 0; x < g.nx(); ++x)
                                        if (const core::NodeIndex n = g.image(x, y);
                                            own[n.value] == 0)
                                        {
                                            const core::GridCoord c = g.coord(n);
                                            s.u.at(x, y) =
                                                1e-3 * (k + 1) * std::sin(0.37 * c.x + 0.11 * c.y);
                                            s.v.at(x, y) = 2e-3 * std::cos(0.23 * c.x - 0.5 * k);
                                        }
                                reports.push_back(step(m, s, ws, f, opt));
                                out.push_back(s);
                            }
                            return out;
                        };
                        std::vector<StepReport> ref_reports;
                        const std::vector<MembraneState> ref = steps(true, ref_reports);
                        std::vector<StepReport> reports;
                        const std::vector<MembraneState> got = steps(false, reports);
                        for (std::size_t k = 0; k < ref.size(); ++k)
                        {
                            const std::string where =
                                "level " + std::to_string(level) + ", set " + std::to_string(set) +
                                ", " + std::to_string(rings) + " rings" +
                                (fixed ? ", fixed, " : ", adaptive, ") + std::to_string(threads) +
                                " threads, step " + std::to_string(k);
                            ASSERT_EQ(reports[k].dt, ref_reports[k].dt) << where;
                            ASSERT_EQ(reports[k].error, ref_reports[k].error) << where;
                            ASSERT_EQ(reports[k].rejections, ref_reports[k].rejections) << where;
                            for (int y = 0; y < g.ny(); ++y)
                                for (int x = 0; x < g.nx(); ++x)
                                    if (kept[g.image(x, y).value] != 0)
                                    {
                                        ASSERT_EQ(got[k].u.at(x, y), ref[k].u.at(x, y))
                                            << where << " at (" << x << ", " << y << ")";
                                        ASSERT_EQ(got[k].v.at(x, y), ref[k].v.at(x, y))
                                            << where << " at (" << x << ", " << y << ")";
                                    }
                        }
                    }
            }
    }
}

// The slow reference: one RKF45 step of size h with the classic tableau on full planes.
struct ReferenceStep
{
    core::Field<double> u, v;
    double error = 0.0;
};

// The force at stage s is accel + (t_force + c_s h) rate: t_force is the step's start time less
// the time the accel plane holds (Rkf45Workspace::accel_time).
ReferenceStep reference_step(const MembraneModel& m, const MembraneState& s0,
                             const core::Field<double>& accel, const core::Field<double>& rate,
                             double t_force, double h, std::span<const core::Region> owned)
{
    static constexpr double c[6] = {0.0, 1.0 / 4.0, 3.0 / 8.0, 12.0 / 13.0, 1.0, 1.0 / 2.0};
    static constexpr double a[6][5] = {
        {0, 0, 0, 0, 0},
        {1.0 / 4.0, 0, 0, 0, 0},
        {3.0 / 32.0, 9.0 / 32.0, 0, 0, 0},
        {1932.0 / 2197.0, -7200.0 / 2197.0, 7296.0 / 2197.0, 0, 0},
        {439.0 / 216.0, -8.0, 3680.0 / 513.0, -845.0 / 4104.0, 0},
        {-8.0 / 27.0, 2.0, -3544.0 / 2565.0, 1859.0 / 4104.0, -11.0 / 40.0}};
    static constexpr double b5[6] = {16.0 / 135.0,      0.0,         6656.0 / 12825.0,
                                     28561.0 / 56430.0, -9.0 / 50.0, 2.0 / 55.0};
    static constexpr double b4[6] = {25.0 / 216.0,    0.0,        1408.0 / 2565.0,
                                     2197.0 / 4104.0, -1.0 / 5.0, 0.0};
    const core::TetraGrid& g = m.grid();
    const MembraneSettings& set = m.settings();
    // A node moves iff its canonical node lies in an owned region (all nodes when none).
    const auto moves = [&](int x, int y)
    {
        if (owned.empty())
            return true;
        const core::GridCoord cc = g.coord(g.canonical(g.index(x, y)));
        for (const core::Region& r : owned)
            if (r.contains(cc.x, cc.y))
                return true;
        return false;
    };
    std::vector<core::Field<double>> U(6, core::Field<double>(g, 1)),
        V(6, core::Field<double>(g, 1)), kv(6, core::Field<double>(g, 1));
    core::Field<double> Ku(g, 1);
    for (int s = 0; s < 6; ++s)
    {
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
            {
                if (!moves(x, y))
                {
                    U[s].at(x, y) = s0.u.at(x, y);
                    V[s].at(x, y) = 0.0;
                    continue;
                }
                double du = 0.0;
                double dv = 0.0;
                for (int j = 0; j < s; ++j)
                {
                    du += a[s][j] * V[j].at(x, y);
                    dv += a[s][j] * kv[j].at(x, y);
                }
                U[s].at(x, y) = s0.u.at(x, y) + h * du;
                V[s].at(x, y) = s0.v.at(x, y) + h * dv;
            }
        m.sync(U[s]);
        m.sync(V[s]);
        apply_stiffness(m, U[s], Ku);
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
                kv[s].at(x, y) = moves(x, y)
                                     ? -set.beta * V[s].at(x, y) - set.k_f * U[s].at(x, y) -
                                           m.inverse_mass().at(x, y) * Ku.at(x, y) +
                                           (accel.at(x, y) + (t_force + c[s] * h) * rate.at(x, y))
                                     : 0.0;
        m.sync(kv[s]);
    }
    ReferenceStep out{s0.u, s0.v, 0.0};
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            if (!moves(x, y))
                continue;
            double du = 0.0, dv = 0.0, eu = 0.0, ev = 0.0;
            for (int j = 0; j < 6; ++j)
            {
                du += b5[j] * V[j].at(x, y);
                dv += b5[j] * kv[j].at(x, y);
                eu += (b5[j] - b4[j]) * V[j].at(x, y);
                ev += (b5[j] - b4[j]) * kv[j].at(x, y);
            }
            const double u0 = s0.u.at(x, y);
            const double v0 = s0.v.at(x, y);
            const double un = u0 + h * du;
            const double vn = v0 + h * dv;
            out.u.at(x, y) = un;
            out.v.at(x, y) = vn;
            if (g.is_canonical(g.index(x, y)))
                out.error =
                    std::max({out.error,
                              std::fabs(h * eu) /
                                  (set.atol + set.rtol * std::max(std::fabs(u0), std::fabs(un))),
                              std::fabs(h * ev) /
                                  (set.atol + set.rtol * std::max(std::fabs(v0), std::fabs(vn)))});
        }
    m.sync(out.u);
    m.sync(out.v);
    return out;
}

double max_abs(const core::Field<double>& f)
{
    double worst = 0.0;
    for (const double x : f.padded())
        worst = std::max(worst, std::fabs(x));
    return worst;
}

// Largest difference over the whole padded plane (ghost ring and twins included).
double max_diff(const core::Field<double>& a, const core::Field<double>& b)
{
    double worst = 0.0;
    for (std::size_t i = 0; i < a.padded().size(); ++i)
        worst = std::max(worst, std::fabs(a.padded()[i] - b.padded()[i]));
    return worst;
}

TEST(Pipeline, MatchesStraightforwardStep)
{
    for (int level = 1; level <= 5; ++level)
        for (const bool restricted : {false, true})
            for (const int threads : {1, 2})
                for (const bool ramp : {false, true})
                {
                    MembraneModel m = test::sphere_model(level, settings(threads, true, 1));
                    const std::vector<core::Region> owned =
                        restricted ? some_regions(m) : std::vector<core::Region>{};
                    MembraneState s = varied_state(m);
                    Rkf45Workspace ws(m, threads);
                    const std::vector<Force> f = forces_for(m);
                    // Reach a state with every slope non-zero, then compare one step.
                    for (int k = 0; k < 3; ++k)
                        (void)step(m, s, ws, f);
                    const MembraneState before = s;
                    set_forces(m, ws, f);
                    if (ramp)  // from f, held since 1 ms ago, towards f's mirror image
                    {
                        std::vector<Force> g = f;
                        for (Force& one : g)
                            one.vector = one.vector * -1.5;
                        begin_force_ramp(m, ws, g, s.time - 1e-3, s.time + 0.01);
                    }
                    const double h = m.settings().fixed_dt;
                    const ReferenceStep ref = reference_step(m, before, ws.accel, ws.accel_rate,
                                                             before.time - ws.accel_time, h, owned);
                    StepOptions opt;
                    opt.owned = owned;
                    const StepReport r = step_prepared(m, s, ws, opt);
                    const std::string where =
                        "level " + std::to_string(level) + (restricted ? " restricted" : " full") +
                        (ramp ? " ramp" : "") + ", " + std::to_string(threads) + " threads";
                    // Same arithmetic in another order: agreement to rounding.
                    EXPECT_LE(max_diff(s.u, ref.u), 1e-13 * max_abs(ref.u)) << where;
                    EXPECT_LE(max_diff(s.v, ref.v), 1e-13 * max_abs(ref.v)) << where;
                    // The estimate is a small difference (tiny at level 1, where it nears the
                    // rounding of u and v scaled by 1/atol): relative plus absolute tolerance.
                    EXPECT_NEAR(r.error, ref.error, 1e-6 * ref.error + 1e-10) << where;
                    EXPECT_GT(ref.error, 0.0);
                    // The nodes that do not move keep their bits.
                    if (restricted)
                        for (int y = 0; y < m.grid().ny(); ++y)
                            for (int x = 0; x < m.grid().nx(); ++x)
                                if (ref.u.at(x, y) == before.u.at(x, y) &&
                                    ref.v.at(x, y) == before.v.at(x, y))
                                {
                                    ASSERT_EQ(s.u.at(x, y), before.u.at(x, y)) << where;
                                    ASSERT_EQ(s.v.at(x, y), before.v.at(x, y)) << where;
                                }
                }
}

}  // namespace
}  // namespace pliant::sim
