// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Properties of the butterfly convolution (docs/style.md §10, subdiv): interpolation, restrict as
// the exact inverse, twins, linear precision, dimensions, convergence on a sphere, thread
// independence, and agreement with the slow halfedge reference everywhere.
#include <pliant/subdiv/refine.h>

#include <gtest/gtest.h>

#include "grid_shapes.h"
#include "reference_butterfly.h"
#include "subdiv_test_helpers.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

namespace pliant::subdiv
{
namespace
{

using core::Field;
using core::TetraGrid;

ConvolutionPlan plan_for(int level)
{
    auto plan = ConvolutionPlan::create(level);
    EXPECT_TRUE(plan.has_value());
    return std::move(plan).value();
}

template <typename T>
bool bit_equal(T a, T b)
{
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

template <typename T>
class RefineTyped : public ::testing::Test
{
};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(RefineTyped, Scalars);

TEST(ButterflyMask, RotatedMasksAreTheDerivedStencils)
{
    // Vertical and diagonal masks worked out by hand from the triangles around each edge
    // (docs/subdivision.md), against the rotation that builds them.
    const Mask vertical{{{0, 0}, {0, 1}, {-1, 0}, {1, 1}, {-1, -1}, {-1, 1}, {1, 2}, {1, 0}}};
    const Mask diagonal{{{0, 0}, {1, 1}, {0, 1}, {1, 0}, {-1, 0}, {1, 2}, {2, 1}, {0, -1}}};
    EXPECT_EQ(k_vertical_mask, vertical);
    EXPECT_EQ(k_diagonal_mask, diagonal);
    double sum = 0;
    for (std::size_t i = 0; i < k_tap_count; ++i)
        sum += tap_weight(i);
    EXPECT_EQ(sum, 1.0);
    // Every tap of every edge of the grid stays within k_refine_ghost of the rectangle, and a
    // smaller ring would not do.
    const TetraGrid g = TetraGrid::create(3).value();
    int outside_ring = 0;
    int on_ring = 0;
    for (EdgeDirection d :
         {EdgeDirection::Horizontal, EdgeDirection::Vertical, EdgeDirection::Diagonal})
    {
        const Tap far = mask(d)[1];  // the edge's other end
        for (int y = 0; y + far.dy < g.ny(); ++y)
            for (int x = 0; x + far.dx < g.nx(); ++x)
                for (const Tap& t : mask(d))
                {
                    const int tx = x + t.dx;
                    const int ty = y + t.dy;
                    outside_ring += (tx < -k_refine_ghost || tx >= g.nx() + k_refine_ghost ||
                                     ty < -k_refine_ghost || ty >= g.ny() + k_refine_ghost)
                                        ? 1
                                        : 0;
                    on_ring += g.in_range(tx, ty) ? 0 : 1;
                }
    }
    EXPECT_EQ(outside_ring, 0);
    EXPECT_GT(on_ring, 0);
}

TEST(ConvolutionPlan, LevelsAreChecked)
{
    EXPECT_FALSE(ConvolutionPlan::create(0).has_value());
    EXPECT_FALSE(ConvolutionPlan::create(10).has_value());
    EXPECT_EQ(ConvolutionPlan::create(10).error().code, core::ErrorCode::InvalidArgument);
    EXPECT_TRUE(ConvolutionPlan::create(9).has_value());
    EXPECT_FALSE(make_plans(8, 3).has_value());
    EXPECT_FALSE(make_plans(3, 0).has_value());
    auto plans = make_plans(2, 3);
    ASSERT_TRUE(plans.has_value());
    ASSERT_EQ(plans->size(), 3U);
    EXPECT_EQ((*plans)[2].fine_level(), 5);
}

TEST(ConvolutionPlan, OffsetsFollowTheStride)
{
    const ConvolutionPlan plan = plan_for(3);
    for (int g = 1; g <= core::k_max_ghost; ++g)
    {
        const std::ptrdiff_t stride = plan.coarse_grid().nx() + 2 * g;
        const TapOffsets& h = plan.offsets(EdgeDirection::Horizontal, g);
        EXPECT_EQ(h[1], 1);
        EXPECT_EQ(h[2], stride + 1);
        EXPECT_EQ(h[7], -stride - 1);
        EXPECT_EQ(plan.offsets(EdgeDirection::Vertical, g)[1], stride);
        EXPECT_EQ(plan.offsets(EdgeDirection::Diagonal, g)[1], stride + 1);
    }
}

TYPED_TEST(RefineTyped, RefinedDimensionsAreTheNextLevel)
{
    using T = TypeParam;
    for (int level = 1; level <= 6; ++level)
    {
        const ConvolutionPlan plan = plan_for(level);
        const auto in = test::random_field<T>(plan.coarse_grid(), 1, 7U);
        Field<T> out(plan.fine_grid(), 0);
        refine(plan, in, out);
        const int w = 1 << (level + 1);
        EXPECT_EQ(out.level(), level + 1);
        EXPECT_EQ(out.nx(), 2 * w + 1);
        EXPECT_EQ(out.ny(), w + 1);
        EXPECT_EQ(plan.fine_grid().unique_count(), 2U * static_cast<std::size_t>(w * w) + 2U);
        // refine_levels by k gives level n+k
        const std::vector<ConvolutionPlan> plans =
            make_plans(level, std::min(2, 10 - level)).value();
        const Field<T> deep = refine_levels<T>(plans, in);
        EXPECT_EQ(deep.level(), plans.back().fine_level());
        EXPECT_EQ(deep.nx(), plans.back().fine_grid().nx());
    }
}

TYPED_TEST(RefineTyped, OneShotRefineLevelsMatchesStepByStep)
{
    using T = TypeParam;
    const TetraGrid g = TetraGrid::create(3).value();
    auto in = test::random_field<T>(g, 0, 9U);  // no ghosts: refine_levels adds them
    const auto deep = refine_levels(in, 3);
    ASSERT_TRUE(deep.has_value());
    EXPECT_EQ(deep->level(), 6);
    Field<T> step = in;
    for (int level = 3; level < 6; ++level)
    {
        const ConvolutionPlan plan = plan_for(level);
        Field<T> padded(plan.coarse_grid(), 1);
        for (int y = 0; y < step.ny(); ++y)
            for (int x = 0; x < step.nx(); ++x)
                padded.at(x, y) = step.at(x, y);
        core::fill_ghosts(plan.coarse_grid(), padded);
        step = Field<T>(plan.fine_grid(), 0);
        refine(plan, padded, step);
    }
    EXPECT_TRUE(*deep == step);
    EXPECT_FALSE(refine_levels(in, 8).has_value()) << "3 + 8 > 10";
    EXPECT_EQ(refine_levels(in, 0).error().code, core::ErrorCode::InvalidArgument);
    const core::Vec3Field<T> three{in, in, in};
    const auto deep3 = refine_levels(three, 3);
    ASSERT_TRUE(deep3.has_value());
    EXPECT_TRUE((*deep3)[2] == step);
}

TYPED_TEST(RefineTyped, EvenNodesAreUnchangedBitForBit)
{
    using T = TypeParam;
    for (int level = 1; level <= 7; ++level)
    {
        const ConvolutionPlan plan = plan_for(level);
        const auto in = test::random_field<T>(plan.coarse_grid(), 1 + level % 3, 11U + level);
        Field<T> out(plan.fine_grid(), level % 2);
        refine(plan, in, out);
        int mismatches = 0;
        for (int y = 0; y < in.ny(); ++y)
            for (int x = 0; x < in.nx(); ++x)
                mismatches += bit_equal(out.at(2 * x, 2 * y), in.at(x, y)) ? 0 : 1;
        EXPECT_EQ(mismatches, 0) << "level " << level;
    }
}

TYPED_TEST(RefineTyped, RestrictOfRefineIsExactlyTheInput)
{
    using T = TypeParam;
    for (int level = 1; level <= 7; ++level)
    {
        const ConvolutionPlan plan = plan_for(level);
        const int ghost = 1 + level % 2;
        const auto in = test::random_field<T>(plan.coarse_grid(), ghost, 100U + level);
        Field<T> out(plan.fine_grid(), 1);
        refine(plan, in, out);
        // Field equality covers every element of the padded plane, ghosts included.
        EXPECT_TRUE(restrict(plan, out, ghost) == in) << "level " << level;
        // Several levels down and back up.
        if (level <= 5)
        {
            const auto plans = make_plans(level, 3).value();
            Field<T> fine = refine_levels<T>(plans, in, 2);
            for (std::size_t i = plans.size(); i-- > 0;)
                fine = restrict(plans[i], fine, i == 0 ? ghost : 2);
            EXPECT_TRUE(fine == in) << "level " << level << " three levels";
        }
    }
}

TYPED_TEST(RefineTyped, RefinedTwinsAgreeAndGhostsAreFilled)
{
    // refine() does not copy canonical nodes onto twins: the kernel must give them the same
    // bits (levels up to 9 -> 10, whose outputs take the streamed path).
    using T = TypeParam;
    for (int level = 1; level <= 9; ++level)
    {
        const ConvolutionPlan plan = plan_for(level);
        const auto in = test::random_field<T>(plan.coarse_grid(), 1, 300U + level);
        Field<T> out(plan.fine_grid(), 2);
        refine(plan, in, out);
        int mismatches = 0;
        for (const core::TwinPair& t : plan.fine_grid().twins())
            mismatches += bit_equal(out[t.twin], out[t.canonical]) ? 0 : 1;
        EXPECT_EQ(mismatches, 0) << "level " << level;
        Field<T> refilled = out;
        core::fill_ghosts(plan.fine_grid(), refilled);
        EXPECT_TRUE(refilled == out) << "ghosts of the output must already be filled";
    }
}

TYPED_TEST(RefineTyped, ThreadCountDoesNotChangeTheResult)
{
    using T = TypeParam;
    // large enough for several threads (refine.h: one per 65,536 fine nodes)
    const ConvolutionPlan plan = plan_for(8);
    const auto in = test::random_field<T>(plan.coarse_grid(), 1, 5U);
    Field<T> one(plan.fine_grid(), 1);
    refine(plan, in, one, 1);
    for (int threads : {2, 3, 4})
    {
        Field<T> many(plan.fine_grid(), 1);
        refine(plan, in, many, threads);
        EXPECT_TRUE(
            std::memcmp(one.padded().data(), many.padded().data(), one.padded().size_bytes()) == 0)
            << threads << " threads";
    }
}

// f = a x + b y + c on the flat (unfolded) grid, with dyadic coefficients so every product and
// sum is exact: every odd node whose eight taps lie inside the rectangle gets f at its own
// position exactly. Ghost taps see the folded grid, where f is not linear (the fold is a point
// reflection: f(ghost) = 2 f(b) - f(reflected), and f is not even equal at twins), so nodes
// whose stencil reaches a ghost are excluded; the tetrahedron test below covers linear
// precision across the whole closed surface.
TYPED_TEST(RefineTyped, LinearFieldsOnTheFlatGridAreReproducedExactly)
{
    using T = TypeParam;
    for (int level = 2; level <= 6; ++level)
    {
        const ConvolutionPlan plan = plan_for(level);
        const TetraGrid& g = plan.coarse_grid();
        auto f = [](double x, double y) { return 3.0 * x - 5.0 * y + 7.0; };
        Field<T> in(g, 1);
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
                in.at(x, y) = static_cast<T>(f(x, y));
        core::fill_ghosts(g, in);  // folded values, deliberately not linear
        Field<T> out(plan.fine_grid(), 0);
        refine(plan, in, out);

        const int w = g.w();
        long checked = 0;
        long wrong = 0;
        for (int fy = 0; fy < out.ny(); ++fy)
            for (int fx = 0; fx < out.nx(); ++fx)
            {
                if (!test::is_odd_node(fx, fy))
                    continue;
                const auto [p, q] = test::parent_edge(fx, fy);
                const EdgeDirection d = q.y == p.y   ? EdgeDirection::Horizontal
                                        : q.x == p.x ? EdgeDirection::Vertical
                                                     : EdgeDirection::Diagonal;
                bool inside = true;
                for (const Tap& t : mask(d))
                    inside = inside && g.in_range(p.x + t.dx, p.y + t.dy);
                if (!inside)
                    continue;
                ++checked;
                wrong += out.at(fx, fy) == static_cast<T>(f(fx / 2.0, fy / 2.0)) ? 0 : 1;
            }
        // Independent count of the interior-stencil edges: horizontal x in [1, 2W-2], y in
        // [1, W-1]; vertical x in [1, 2W-1], y in [1, W-2]; diagonal x in [1, 2W-2], y in
        // [1, W-2].
        const long expected = static_cast<long>(2 * w - 2) * (w - 1) +
                              static_cast<long>(2 * w - 1) * (w - 2) +
                              static_cast<long>(2 * w - 2) * (w - 2);
        EXPECT_EQ(checked, expected) << "level " << level;
        EXPECT_EQ(wrong, 0) << "level " << level;
    }
}

TYPED_TEST(RefineTyped, ConstantsAreReproducedEverywhere)
{
    using T = TypeParam;
    const ConvolutionPlan plan = plan_for(5);
    Field<T> in(plan.coarse_grid(), 1, T(0.3));
    Field<T> out(plan.fine_grid(), 1);
    refine(plan, in, out);
    double worst = 0;
    for (const T v : out.padded())
        worst = std::max(worst, std::abs(static_cast<double>(v) - static_cast<double>(T(0.3))));
    // 0.3 is not dyadic: a few roundings of the four-term sum.
    EXPECT_LE(worst, 4 * static_cast<double>(std::numeric_limits<T>::epsilon()));
    Field<T> in2(plan.coarse_grid(), 1, T(-2.5));  // dyadic: exact
    refine(plan, in2, out);
    EXPECT_EQ(*std::min_element(out.padded().begin(), out.padded().end()), T(-2.5));
    EXPECT_EQ(*std::max_element(out.padded().begin(), out.padded().end()), T(-2.5));
}

// Positions on the flat-faced tetrahedron are linear on each face. Every odd node whose stencil
// (ghosts resolved to the nodes they stand for) lies on one closed face is the exact midpoint
// of its edge; with integer corners and 1/W steps the arithmetic is exact. Nodes whose stencil
// straddles a tetrahedron edge are not (the surface bends there), which is expected.
TEST(Refine, TetrahedronFacesAreReproducedExactly)
{
    for (int level = 2; level <= 6; ++level)
    {
        const ConvolutionPlan plan = plan_for(level);
        const TetraGrid& g = plan.coarse_grid();
        const auto in = test::tetrahedron_positions(g, 1);
        core::Vec3Field<double> out{Field<double>(plan.fine_grid()),
                                    Field<double>(plan.fine_grid()),
                                    Field<double>(plan.fine_grid())};
        refine(plan, in, out);
        long checked = 0;
        long wrong = 0;
        for (int fy = 0; fy < out[0].ny(); ++fy)
            for (int fx = 0; fx < out[0].nx(); ++fx)
            {
                if (!test::is_odd_node(fx, fy))
                    continue;
                const auto [p, q] = test::parent_edge(fx, fy);
                const EdgeDirection d = q.y == p.y   ? EdgeDirection::Horizontal
                                        : q.x == p.x ? EdgeDirection::Vertical
                                                     : EdgeDirection::Diagonal;
                bool one_face = false;
                for (int face = 0; face < 4 && !one_face; ++face)
                {
                    bool all = true;
                    for (const Tap& t : mask(d))
                        all = all && test::in_face(g, face, p.x + t.dx, p.y + t.dy);
                    one_face = all;
                }
                if (!one_face)
                    continue;
                ++checked;
                const auto mid = test::tetrahedron_point(plan.fine_grid(), fx, fy);
                for (std::size_t c = 0; c < 3; ++c)
                    wrong += out[c].at(fx, fy) == mid[c] ? 0 : 1;
            }
        // Most edges are face-interior: all but O(W) of the 6W^2 (plus twins).
        const long w = g.w();
        EXPECT_GT(checked, 6 * w * w - 40 * w) << "level " << level;
        EXPECT_EQ(wrong, 0) << "level " << level;
    }
}

// Sample the unit sphere at level n, refine twice: the largest distance of the refined surface
// to the sphere falls as the sampling level rises (the scheme converges to a smooth surface
// through the samples, which approaches the sphere).
TEST(Refine, RefinedSphereApproachesTheSphere)
{
    double previous = 1.0;
    for (int level = 2; level <= 6; ++level)
    {
        const auto plans = make_plans(level, 2).value();
        const auto in = test::sphere_positions(plans.front().coarse_grid(), 0);
        const auto out = refine_levels<double>(plans, in);
        double worst = 0;
        for (int y = 0; y < out[0].ny(); ++y)
            for (int x = 0; x < out[0].nx(); ++x)
            {
                const double r = std::sqrt(out[0].at(x, y) * out[0].at(x, y) +
                                           out[1].at(x, y) * out[1].at(x, y) +
                                           out[2].at(x, y) * out[2].at(x, y));
                worst = std::max(worst, std::abs(r - 1.0));
            }
        EXPECT_LT(worst, 0.8 * previous) << "level " << level << " -> " << level + 2;
        previous = worst;
    }
    EXPECT_LT(previous, 1e-2);
}

// The slow halfedge reference (reference_butterfly.h) on grid.triangles(), evaluated edge by
// edge, against the convolution at every canonical odd node: bit for bit in double (same sum
// grouping), including the stencils around the four valence-3 corners.
TEST(Refine, MatchesTheHalfedgeReferenceEverywhereIncludingCorners)
{
    for (int level = 1; level <= 5; ++level)
    {
        const ConvolutionPlan plan = plan_for(level);
        const TetraGrid& g = plan.coarse_grid();
        const auto tris = g.triangles();
        const test::ReferenceButterfly ref(tris, g.unique_count());
        ASSERT_TRUE(ref.ok());
        ASSERT_EQ(ref.edge_count(), 6U * static_cast<std::size_t>(g.w() * g.w()));

        for (std::uint32_t seed = 0; seed < 2; ++seed)
        {
            const Field<double> in = seed == 0 ? test::sphere_positions(g, 1)[0]
                                               : test::random_field<double>(g, 1, 40U + level);
            const Field<float> in_f = [&]
            {
                Field<float> f(g, 1);
                for (std::size_t i = 0; i < f.padded().size(); ++i)
                    f.padded()[i] = static_cast<float>(in.padded()[i]);
                return f;
            }();
            Field<double> out(plan.fine_grid(), 0);
            Field<float> out_f(plan.fine_grid(), 0);
            refine(plan, in, out);
            refine(plan, in_f, out_f);

            const auto values = test::unique_values(g, in);
            std::unordered_map<std::uint64_t, double> expected;
            for (const std::uint32_t h : ref.edge_halfedges())
                expected[test::edge_key(ref.from(h), ref.to(h))] = ref.new_value(h, values);

            const TetraGrid& fg = plan.fine_grid();
            std::size_t seen = 0;
            long wrong = 0;
            long wrong_f = 0;
            for (int fy = 0; fy < fg.ny(); ++fy)
                for (int fx = 0; fx < fg.nx(); ++fx)
                {
                    if (!test::is_odd_node(fx, fy) || !fg.is_canonical(fg.index(fx, fy)))
                        continue;
                    const auto [p, q] = test::parent_edge(fx, fy);
                    const auto it = expected.find(test::edge_key(g.unique_id(g.index(p.x, p.y)),
                                                                 g.unique_id(g.index(q.x, q.y))));
                    ASSERT_NE(it, expected.end());
                    ++seen;
                    wrong += out.at(fx, fy) == it->second ? 0 : 1;
                    // float: the reference in double, within float rounding of |values| <= 1
                    wrong_f += std::abs(static_cast<double>(out_f.at(fx, fy)) - it->second) <= 1e-6
                                   ? 0
                                   : 1;
                }
            EXPECT_EQ(seen, expected.size()) << "every coarse edge has one canonical odd node";
            EXPECT_EQ(wrong, 0) << "level " << level << " seed " << seed;
            EXPECT_EQ(wrong_f, 0) << "level " << level << " seed " << seed;
        }
    }
}

// At a corner the topological stencil collapses onto the corner's 1-ring the way the ghost map
// does: spot-check one corner edge by hand against the offsets, so a reference that drifted to
// another rule would be caught here too.
TEST(Refine, CornerEdgeStencilIsTheDuplicatedRegularMask)
{
    const ConvolutionPlan plan = plan_for(3);
    const TetraGrid& g = plan.coarse_grid();
    const int w = g.w();
    // Edge from corner b = (W, 0) to p = (W+1, 0). Real neighbours of b: p, q = (W+1, 1),
    // r = (W, 1). Ghost taps: (W, -1) -> r, (W+1, -1) -> (W-1, 1), (W-1, -1) -> q.
    Field<double> in(g, 1);
    auto put = [&](int x, int y, double v)
    {
        in[g.image(x, y)] = v;  // the canonical twin; sync_twins copies it to the others
        core::sync_twins(g, in);
    };
    put(w, 0, 1.0);       // b
    put(w + 1, 0, 2.0);   // p
    put(w + 1, 1, 4.0);   // q
    put(w, 1, 8.0);       // r
    put(w + 2, 1, 16.0);  // c1
    put(w - 1, 1, 32.0);  // image of (W+1, -1)
    core::fill_ghosts(g, in);
    Field<double> out(plan.fine_grid(), 0);
    refine(plan, in, out);
    // 1/2 (b + p) + 1/8 (q + r) - 1/16 ((r + 16) + (32 + q))
    const double expected = 0.5 * 3.0 + 0.125 * 12.0 - 0.0625 * (24.0 + 36.0);
    EXPECT_EQ(out.at(2 * w + 1, 0), expected);
}

}  // namespace
}  // namespace pliant::subdiv
