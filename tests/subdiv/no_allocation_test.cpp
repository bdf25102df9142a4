// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Issue 4's "no allocation per call": with its plan made, `refine` and `restrict` into fields the
// caller owns allocate nothing, for one plane and three, float and double, 1 and 2 threads (7 -> 8,
// 131,841 fine nodes: the smallest step that runs on 2 threads; 6 -> 7 ran on one whatever was
// asked). Counted by a replaced operator new (tests/support/allocation_counter.cpp, linked into
// this executable only); OpenMP's own malloc calls are not counted.
#include <pliant/core/field.h>
#include <pliant/subdiv/convolution_plan.h>
#include <pliant/subdiv/refine.h>

#include <gtest/gtest.h>

#include "grid_shapes.h"
#include "support/allocation_counter.h"

namespace pliant::subdiv
{
namespace
{

template <typename T>
void check_refine_allocates_nothing(int threads)
{
    constexpr int level = 7;
    const core::TetraGrid coarse = core::TetraGrid::create(level).value();
    const core::TetraGrid fine = core::TetraGrid::create(level + 1).value();
    const ConvolutionPlan plan = make_plans(level, 1).value().front();
    const core::Vec3Field<double> sphere = test::sphere_positions(coarse, 0);
    core::Vec3Field<T> in;
    core::Vec3Field<T> out;
    for (std::size_t c = 0; c < 3; ++c)
    {
        in[c] = core::Field<T>(coarse, k_refine_ghost);
        for (int y = 0; y < coarse.ny(); ++y)
            for (int x = 0; x < coarse.nx(); ++x)
                in[c].at(x, y) = static_cast<T>(sphere[c].at(x, y));
        core::fill_ghosts(coarse, in[c]);
        out[c] = core::Field<T>(fine);
    }
    core::Field<T> back(coarse);
    ASSERT_EQ(refine_threads(plan, threads), threads);  // the threads asked for are used
    refine(plan, in, out, threads);  // first call: any lazy set-up (OpenMP's threads) happens here
    const std::uint64_t before = test::allocations();
    for (int k = 0; k < 20; ++k)
    {
        refine(plan, in, out, threads);
        refine(plan, in[0], out[0], threads);
        restrict(plan, out[1], back);
    }
    EXPECT_EQ(test::allocations() - before, 0U) << "threads " << threads;
    EXPECT_EQ(back.at(3, 2), in[1].at(3, 2));  // restrict(refine(f)) == f
}

TEST(NoAllocation, RefineAndRestrictAllocateNothing)
{
    for (const int threads : {1, 2})
    {
        check_refine_allocates_nothing<float>(threads);
        check_refine_allocates_nothing<double>(threads);
    }
}

}  // namespace
}  // namespace pliant::subdiv
