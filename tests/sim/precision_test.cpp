// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Mixed precision (Precision::Mixed, docs/physics.md §9) against the double-precision step, the
// independent reference here: a mixed step differs from it only by the rounding of its float
// increments (~1e-7 of a step's change, never of u itself), so one step is compared node by node
// relative to the step's change, at step sizes from far below to the stable limit, with forces
// held and ramped; a run with re-assembly follows the double run (stale float weights would not);
// results do not depend on the thread count; restricted steps ignore the setting. The physics
// checks (frequencies, energy) run in both precisions in dynamics_test.cpp.

#include <pliant/sim/rkf45.h>

#include <gtest/gtest.h>

#include "sim_test_util.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace pliant::sim
{
namespace
{

MembraneSettings material(Precision precision)
{
    MembraneSettings s;
    s.beta = 0.5;
    s.k_f = 1.0;
    s.precision = precision;
    return s;
}

MembraneState moving_state(const MembraneModel& m, double scale = 1.0)
{
    MembraneState s = MembraneState::at_rest(m.grid());
    test::set_field(m, s.u,
                    [scale](const core::Vec3& p) {
                        return scale * (0.02 * test::zonal(2, p) + 0.01 * p.x * p.y + 0.004 * p.z);
                    });
    test::set_field(m, s.v,
                    [scale](const core::Vec3& p)
                    { return scale * (0.01 * test::zonal(3, p) - 0.005 * p.x); });
    return s;
}

const Force k_forces[2] = {{-1, {0.0, 0.6, 0.8}, 0.4, {0.1, 0.3, 0.2}},
                           {17, {}, 0.0, {1.0, 0.0, 0.5}}};

// Largest |a - b| over unique nodes, and largest |b - start| (the step's change).
struct Gap
{
    double diff = 0.0;
    double change = 0.0;
};

Gap gap(const MembraneModel& m, const core::Field<double>& a, const core::Field<double>& b,
        const core::Field<double>& start)
{
    Gap g;
    for (const core::NodeIndex n : m.grid().node_of_unique())
    {
        g.diff = std::max(g.diff, std::fabs(a[n] - b[n]));
        g.change = std::max(g.change, std::fabs(b[n] - start[n]));
    }
    return g;
}

TEST(Precision, OneMixedStepIsTheDoubleStepToTheRoundingOfItsChange)
{
    MembraneModel md = test::sphere_model(6, material(Precision::Double));
    MembraneModel mm = test::sphere_model(6, material(Precision::Mixed));
    const double h_stable = stable_fixed_step(md);
    for (const bool ramp : {false, true})
        for (const double h : {1e-5, 1e-4, 0.1 * h_stable, h_stable})
            for (const int threads : {1, 2})
            {
                MembraneSettings loose = md.settings();
                // Every trial accepted: the comparison is of one step of size h.
                loose.rtol = 0.5;
                loose.atol = 1.0;
                loose.dt_min = 1e-7;
                loose.threads = threads;
                ASSERT_TRUE(md.set_settings(loose).has_value());
                loose.precision = Precision::Mixed;
                ASSERT_TRUE(mm.set_settings(loose).has_value());
                const MembraneState start = moving_state(md);
                MembraneState sd = start;
                MembraneState sm = start;
                Rkf45Workspace wd(md, threads);
                Rkf45Workspace wm(mm, threads);
                if (ramp)
                {
                    // From no force at t = 0 to k_forces at t = 2h: each stage's force differs.
                    begin_force_ramp(md, wd, k_forces, 0.0, 2.0 * h);
                    begin_force_ramp(mm, wm, k_forces, 0.0, 2.0 * h);
                }
                else
                {
                    set_forces(md, wd, k_forces);
                    set_forces(mm, wm, k_forces);
                }
                wd.set_next_dt(h);
                wm.set_next_dt(h);
                const StepReport rd = step_prepared(md, sd, wd);
                const StepReport rm = step_prepared(mm, sm, wm);
                ASSERT_EQ(rd.dt, h);
                ASSERT_EQ(rm.dt, h);
                const Gap gu = gap(md, sm.u, sd.u, start.u);
                const Gap gv = gap(md, sm.v, sd.v, start.v);
                std::printf(
                    "ramp %d, h %.3e, %d thread(s): |du| %.2e of the change %.2e, |dv| "
                    "%.2e of %.2e, error %.6e / %.6e\n",
                    ramp ? 1 : 0, h, threads, gu.diff, gu.change, gv.diff, gv.change, rm.error,
                    rd.error);
                // float rounds to 6e-8; a few dozen operations per node.
                EXPECT_LT(gu.diff, 1e-5 * gu.change) << "h " << h << ", ramp " << ramp;
                EXPECT_LT(gv.diff, 1e-5 * gv.change) << "h " << h << ", ramp " << ramp;
                EXPECT_GT(gu.diff, 0.0) << "the mixed step must be the float one";
                // The error estimate, a combination of the slopes in float: its rounding is that
                // of the step's change (the scale here, atol + rtol |y|, is >= 1), far above
                // the estimate itself for small steps.
                const double floor = 1e-6 * std::max(gu.change, gv.change);
                EXPECT_LT(std::fabs(rm.error - rd.error), 1e-3 * rd.error + floor)
                    << "h " << h << ", ramp " << ramp;
            }
}

TEST(Precision, MixedRefusesTolerancesAndStepsBelowFloatRange)
{
    MembraneSettings set = material(Precision::Mixed);
    set.atol = 1e-35;
    const auto refused = validate(set);
    ASSERT_FALSE(refused.has_value());
    EXPECT_NE(refused.error().message.find("atol must be >= 1e-30 with precision mixed"),
              std::string::npos)
        << refused.error().message;
    set.precision = Precision::Double;
    EXPECT_TRUE(validate(set).has_value());
    set.precision = Precision::Mixed;
    set.atol = 1e-30;
    EXPECT_TRUE(validate(set).has_value());
    set.dt_min = 1e-13;
    const auto tiny_step = validate(set);
    ASSERT_FALSE(tiny_step.has_value());
    EXPECT_NE(tiny_step.error().message.find("dt_min must be >= 1e-12 s"), std::string::npos);
    // Only the values the step mode uses: fixed steps ignore atol and dt_min, adaptive ones
    // fixed_dt.
    set.fixed_step = true;
    set.atol = 1e-35;
    EXPECT_TRUE(validate(set).has_value());
    set.fixed_dt = 1e-13;
    const auto tiny_fixed = validate(set);
    ASSERT_FALSE(tiny_fixed.has_value());
    EXPECT_NE(tiny_fixed.error().message.find("fixed_dt must be >= 1e-12 s"), std::string::npos);
    set.fixed_step = false;
    set.atol = 1e-8;
    set.dt_min = 1e-7;
    EXPECT_TRUE(validate(set).has_value());
}

TEST(Precision, SmallGridsToo)
{
    // The coarsest grids (3 to 33 rows) on one and two threads: the ring rows, the band split and
    // the twin and ghost copies at their smallest.
    for (int level = 1; level <= 5; ++level)
        for (const int threads : {1, 2})
        {
            MembraneSettings set = material(Precision::Double);
            set.fixed_step = true;
            set.fixed_dt = 1e-3;
            set.threads = threads;
            MembraneModel md = test::sphere_model(level, set);
            set.precision = Precision::Mixed;
            MembraneModel mm = test::sphere_model(level, set);
            const MembraneState start = moving_state(md);
            MembraneState sd = start;
            MembraneState sm = start;
            Rkf45Workspace wd(md, threads);
            Rkf45Workspace wm(mm, threads);
            // The point force and a face every level has (level 1: 16 faces).
            const Force forces[2] = {k_forces[0], {3, {}, 0.0, {1.0, 0.0, 0.5}}};
            for (int k = 0; k < 5; ++k)
            {
                (void)step(md, sd, wd, forces);
                (void)step(mm, sm, wm, forces);
            }
            const Gap g = gap(md, sm.u, sd.u, start.u);
            EXPECT_LT(g.diff, 1e-5 * g.change) << "level " << level << ", threads " << threads;
            EXPECT_GT(g.change, 0.0) << "level " << level;
        }
}

TEST(Precision, MixedRunWithReassemblyFollowsTheDoubleRun)
{
    MembraneSettings set = material(Precision::Double);
    set.fixed_step = true;
    set.fixed_dt = 2e-3;
    set.reassemble_every = 3;
    MembraneModel md = test::sphere_model(5, set);
    set.precision = Precision::Mixed;
    MembraneModel mm = test::sphere_model(5, set);
    // Deformations of 10-20 % of the radius: re-assembly changes the weights by as much.
    const MembraneState start = moving_state(md, 8.0);
    MembraneState sd = start;
    MembraneState sm = start;
    Rkf45Workspace wd(md);
    Rkf45Workspace wm(mm);
    double worst = 0.0;
    double size = 0.0;
    int reassembled = 0;
    for (int k = 0; k < 60; ++k)
    {
        (void)step(md, sd, wd, k_forces);
        const StepReport r = step(mm, sm, wm, k_forces);
        reassembled += r.reassembled ? 1 : 0;
        // The float weights are those of the model's current assembly.
        ASSERT_EQ(wm.mixed_assembly, mm.assembly_id()) << "step " << k;
        const Gap g = gap(md, sm.u, sd.u, start.u);
        worst = std::max(worst, g.diff);
        size = std::max(size, g.change);
    }
    std::printf("largest |u_mixed - u_double| over 60 steps: %.3e (largest change %.3e)\n", worst,
                size);
    EXPECT_EQ(reassembled, 19);
    EXPECT_GT(size, 0.01);
    EXPECT_LT(worst, 1e-5 * size);
}

std::uint64_t mixed_hash(int threads, Precision precision)
{
    MembraneSettings set = material(precision);
    set.rtol = 1e-5;
    set.threads = threads;
    MembraneModel m = test::sphere_model(5, set);
    MembraneState s = moving_state(m);
    Rkf45Workspace ws(m, threads);
    for (int k = 0; k < 300; ++k)
        EXPECT_FALSE(has_flag(
            step(m, s, ws, k < 150 ? std::span<const Force>(k_forces) : std::span<const Force>())
                .status,
            StepStatus::NonFinite));
    return s.hash();
}

TEST(Precision, MixedIsTheSameForOneAndTwoThreads)
{
    const std::uint64_t one = mixed_hash(1, Precision::Mixed);
    EXPECT_EQ(one, mixed_hash(2, Precision::Mixed));
    EXPECT_NE(one, mixed_hash(1, Precision::Double));
}

TEST(Precision, RestrictedStepsRunInDouble)
{
    MembraneSettings set = material(Precision::Double);
    set.fixed_step = true;
    set.fixed_dt = 2e-3;
    MembraneModel md = test::sphere_model(5, set);
    set.precision = Precision::Mixed;
    MembraneModel mm = test::sphere_model(5, set);
    const auto regions = md.leaf_regions();
    const std::vector<core::Region> owned(regions.begin(),
                                          regions.begin() + static_cast<long>(regions.size() / 2));
    StepOptions opt;
    opt.owned = owned;
    MembraneState sd = moving_state(md);
    MembraneState sm = moving_state(md);
    Rkf45Workspace wd(md);
    Rkf45Workspace wm(mm);
    for (int k = 0; k < 10; ++k)
    {
        (void)step(md, sd, wd, k_forces, opt);
        (void)step(mm, sm, wm, k_forces, opt);
        ASSERT_EQ(sd.hash(), sm.hash()) << "step " << k;
    }
}

}  // namespace
}  // namespace pliant::sim
