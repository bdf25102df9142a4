// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The optimised refine kernel (fused rows, compile-time taps, streaming stores for large
// outputs) against the straightforward per-row kernel it replaced, bit for bit at every node of
// the padded output: random fields, levels 1..9 (9 -> 10 takes the streaming path), float and
// double, ghost widths 1 and 2, one and two threads.
#include <pliant/subdiv/refine.h>

#include <gtest/gtest.h>

#include "subdiv_test_helpers.h"

#include <cstddef>
#include <cstring>

namespace pliant::subdiv
{
namespace
{

using core::Field;

// The previous kernel (src/subdiv/refine.cpp before the row fusion): the plan's flat tap
// offsets, one loop per fine row, the same grouping of the sums.
template <typename T>
T previous_butterfly(const T* p, const TapOffsets& o)
{
    return (T(0.5) * (p[o[0]] + p[o[1]]) + T(0.125) * (p[o[2]] + p[o[3]])) -
           T(0.0625) * ((p[o[4]] + p[o[5]]) + (p[o[6]] + p[o[7]]));
}

template <typename T>
void previous_refine(const ConvolutionPlan& plan, const Field<T>& in, Field<T>& out)
{
    const TapOffsets& h = plan.offsets(EdgeDirection::Horizontal, in.ghost());
    const TapOffsets& v = plan.offsets(EdgeDirection::Vertical, in.ghost());
    const TapOffsets& d = plan.offsets(EdgeDirection::Diagonal, in.ghost());
    const int n = 2 * plan.coarse_grid().w();
    const int rows = plan.coarse_grid().ny();
    for (int y = 0; y < rows; ++y)
    {
        const T* row = in.origin() + in.offset(0, y);
        T* even = out.origin() + out.offset(0, 2 * y);
        for (int x = 0; x < n; ++x)
        {
            even[2 * x] = row[x];
            even[2 * x + 1] = previous_butterfly(row + x, h);
        }
        even[2 * n] = row[n];
        if (y + 1 == rows)
            continue;
        T* odd = out.origin() + out.offset(0, 2 * y + 1);
        for (int x = 0; x < n; ++x)
        {
            odd[2 * x] = previous_butterfly(row + x, v);
            odd[2 * x + 1] = previous_butterfly(row + x, d);
        }
        odd[2 * n] = previous_butterfly(row + n, v);
    }
    core::sync_twins(plan.fine_grid(), out);
    core::fill_ghosts(plan.fine_grid(), out);
}

template <typename T>
class RefineKernel : public ::testing::Test
{
};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(RefineKernel, Scalars);

TYPED_TEST(RefineKernel, MatchesThePreviousKernelBitForBitAtEveryNode)
{
    using T = TypeParam;
    for (int level = 1; level <= 9; ++level)
    {
        auto plan = ConvolutionPlan::create(level);
        ASSERT_TRUE(plan.has_value());
        for (int ghost = 1; ghost <= 2; ++ghost)
        {
            if (level == 9 && ghost == 2)
                continue;  // the ghost width only moves the offsets; keep the large case short
            const auto in = test::random_field<T>(plan->coarse_grid(), ghost, 700U + level);
            Field<T> expected(plan->fine_grid(), ghost % 2);
            previous_refine(*plan, in, expected);
            for (int threads = 1; threads <= 2; ++threads)
            {
                Field<T> out(plan->fine_grid(), ghost % 2, T(-7));
                refine(*plan, in, out, threads);
                EXPECT_EQ(std::memcmp(out.padded().data(), expected.padded().data(),
                                      out.padded().size_bytes()),
                          0)
                    << "level " << level << " ghost " << ghost << " threads " << threads;
            }
        }
    }
}

}  // namespace
}  // namespace pliant::subdiv
