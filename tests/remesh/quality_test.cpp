// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// The distance measurement itself: the BVH query against a brute-force scan, the exact
// point-triangle distance against hand-computed cases, and the two-sided distance between an
// icosphere and the unit sphere against the analytic chord/sagitta bounds.

#include <pliant/remesh/quality.h>

#include <gtest/gtest.h>

#include "remesh/obb_tree.h"
#include "remesh/quality_internal.h"
#include "shapes.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace pliant::remesh
{
namespace
{

using core::Vec3;

TEST(PointTriangleDistance, RegionsOfTheTriangle)
{
    const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    EXPECT_DOUBLE_EQ(point_triangle_distance({0.2, 0.2, 3.0}, a, b, c), 3.0);    // face
    EXPECT_DOUBLE_EQ(point_triangle_distance({-3.0, -4.0, 0.0}, a, b, c), 5.0);  // vertex a
    EXPECT_DOUBLE_EQ(point_triangle_distance({0.5, -2.0, 0.0}, a, b, c), 2.0);   // edge ab
    EXPECT_NEAR(point_triangle_distance({1.0, 1.0, 0.0}, a, b, c), std::sqrt(0.5), 1e-15);  // bc
    EXPECT_DOUBLE_EQ(point_triangle_distance({2.0, 0.0, 0.0}, a, b, c), 1.0);  // vertex b
}

double brute_distance(const mesh::TriMesh& m, const Vec3& p)
{
    double best = std::numeric_limits<double>::infinity();
    for (const auto& t : m.faces)
        best = std::min(best, point_triangle_distance(p, m.positions[t[0]], m.positions[t[1]],
                                                      m.positions[t[2]]));
    return best;
}

TEST(SurfaceDistance, DirectedMaxMatchesBruteForce)
{
    // the max over the vertices of `b` (samples = 1 adds one random point) must equal the
    // brute-force max over the same points; a and b are two different icosphere refinements
    const mesh::TriMesh a = scenes::icosphere(3);
    mesh::TriMesh b = scenes::icosphere(2);
    for (Vec3& p : b.positions)
        p = p * 1.05;
    const SurfaceDistance d = surface_distance(a, b, DistanceSettings{1, 1});
    double worst = 0.0;
    for (const Vec3& p : b.positions)
        worst = std::max(worst, brute_distance(a, p));
    // b's random extra sample cannot exceed the max distance of b's surface to a by much
    EXPECT_GE(d.other_to_reference.max, worst - 1e-12);
    EXPECT_LE(d.other_to_reference.max, worst + 0.05);
    double worst_a = 0.0;
    for (const Vec3& p : a.positions)
        worst_a = std::max(worst_a, brute_distance(b, p));
    EXPECT_GE(d.reference_to_other.max, worst_a - 1e-12);
    EXPECT_LE(d.reference_to_other.max, worst_a + 0.05);
}

TEST(SurfaceDistance, RandomQueriesMatchBruteForce)
{
    const mesh::TriMesh m = scenes::icosphere(3);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    for (int i = 0; i < 50; ++i)
    {
        const Vec3 p{u(rng), u(rng), u(rng)};
        mesh::TriMesh one;
        one.positions = {p, p + Vec3{1e-9, 0, 0}, p + Vec3{0, 1e-9, 0}};
        one.faces = {{0, 1, 2}};
        const SurfaceDistance d = surface_distance(m, one, DistanceSettings{1, 3});
        // one's samples: its three vertices and one interior point, all within 1e-9 of p
        EXPECT_NEAR(d.other_to_reference.max, brute_distance(m, p), 2e-9) << i;
    }
}

TEST(SurfaceDistance, IcosphereAgainstFinerSphere)
{
    // An icosphere with vertices on the unit sphere: its faces lie inside the sphere by at
    // most the sagitta 1 - cos(theta) of the largest face's circumradius angle. A much finer
    // icosphere stands in for the sphere. Identity gives 0 and PSNR capped.
    const mesh::TriMesh coarse = scenes::icosphere(2);
    const mesh::TriMesh fine = scenes::icosphere(5);
    double max_sag = 0.0;
    for (const auto& t : coarse.faces)
    {
        const Vec3 c =
            (coarse.positions[t[0]] + coarse.positions[t[1]] + coarse.positions[t[2]]) / 3.0;
        max_sag = std::max(max_sag, 1.0 - core::norm(c));
    }
    const SurfaceDistance d = surface_distance(fine, coarse);
    // coarse -> sphere: the deepest point of a face is its centroid-ish; the fine icosphere's
    // own sagitta (about 16x smaller) is the tolerance
    EXPECT_NEAR(d.other_to_reference.max, max_sag, 0.08 * max_sag);
    EXPECT_GT(d.rms, 0.2 * max_sag);
    EXPECT_LT(d.rms, max_sag);
    EXPECT_NEAR(d.diagonal, 2.0 * std::sqrt(3.0), 0.05);
    const SurfaceDistance same = surface_distance(coarse, coarse);
    EXPECT_LT(same.rms, 1e-12);
    EXPECT_GT(same.psnr_db, 200.0);
}

// A surface of slanted slivers is searched through oriented boxes, others through axis-aligned
// ones; both find the nearest points brute force finds, and the same distances as each other.
TEST(SurfaceDistance, OrientedBoxesFindTheNearestPointsAlignedOnesFind)
{
    const mesh::TriMesh frustum = scenes::frustum(400);
    EXPECT_TRUE(detail::mostly_slanted_slivers(frustum));
    EXPECT_FALSE(detail::mostly_slanted_slivers(scenes::icosphere(3)));
    EXPECT_FALSE(detail::mostly_slanted_slivers(scenes::frustum(12)));  // wide faces
    // The tree's nearest-point search against brute force, exactly: points in the box around
    // the frustum and points just off its sides (their nearest points inside slivers).
    std::vector<std::uint32_t> all(frustum.faces.size());
    for (std::uint32_t f = 0; f < all.size(); ++f)
        all[f] = f;
    const detail::ObbTree tree(frustum, all, {});
    const auto distance2 = [&](const Vec3& p, std::uint32_t f)
    {
        const auto& t = frustum.faces[f];
        const double d = point_triangle_distance(p, frustum.positions[t[0]],
                                                 frustum.positions[t[1]], frustum.positions[t[2]]);
        return d * d;
    };
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(-1.3, 1.3), unit(0.0, 1.0);
    for (int i = 0; i < 400; ++i)
    {
        Vec3 p{u(rng), u(rng), 0.5 + 0.6 * u(rng)};
        if (i % 2 == 1)
        {
            // beside a random side face, 1e-3 off its plane
            const auto& t = frustum.faces[4 * (rng() % 400) + 2 + rng() % 2];
            const Vec3 a = frustum.positions[t[0]], b = frustum.positions[t[1]],
                       c = frustum.positions[t[2]];
            double s = unit(rng), w = unit(rng);
            if (s + w > 1.0)
            {
                s = 1.0 - s;
                w = 1.0 - w;
            }
            const Vec3 n = core::normalized(core::cross(b - a, c - a));
            p = a + (b - a) * s + (c - a) * w + n * (i % 4 == 1 ? 1e-3 : -1e-3);
        }
        double brute = std::numeric_limits<double>::infinity();
        for (std::uint32_t f = 0; f < all.size(); ++f)
            brute = std::min(brute, distance2(p, f));
        EXPECT_EQ(tree.nearest2(p, [&](std::uint32_t f) { return distance2(p, f); }), brute) << i;
    }
    // whole surfaces: a frustum against a sphere through it, and two spheres
    mesh::TriMesh ball = scenes::icosphere(3);
    for (Vec3& p : ball.positions)
        p = p * 0.7 + Vec3{0.2, 0.1, 0.5};
    for (const auto& [a, b] : {std::pair{frustum, ball}, std::pair{ball, frustum},
                               std::pair{scenes::icosphere(3), ball}})
    {
        const DistanceSettings s{2000, 5};
        const SurfaceDistance aligned =
            detail::surface_distance_with(a, b, s, nullptr, detail::SearchBoxes::Aligned);
        const SurfaceDistance oriented =
            detail::surface_distance_with(a, b, s, nullptr, detail::SearchBoxes::Oriented);
        EXPECT_NEAR(oriented.rms, aligned.rms, 1e-12 * aligned.rms);
        EXPECT_NEAR(oriented.hausdorff, aligned.hausdorff, 1e-12 * aligned.hausdorff);
        EXPECT_NEAR(oriented.reference_to_other.mean, aligned.reference_to_other.mean,
                    1e-12 * aligned.reference_to_other.mean);
        EXPECT_NEAR(oriented.other_to_reference.mean, aligned.other_to_reference.mean,
                    1e-12 * aligned.other_to_reference.mean);
        EXPECT_GT(aligned.rms, 0.01);
    }
}

TEST(AreaSpread, UniformAndSkewed)
{
    mesh::TriMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    m.faces = {{0, 1, 2}, {1, 3, 2}};
    const AreaSpread s = area_spread(m);
    EXPECT_DOUBLE_EQ(s.min_over_max, 1.0);
    EXPECT_NEAR(s.cv, 0.0, 1e-15);
    m.positions[3] = {3, 3, 0};
    EXPECT_LT(area_spread(m).min_over_max, 0.5);
}

}  // namespace
}  // namespace pliant::remesh
