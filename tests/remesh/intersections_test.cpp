// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// The self-intersection counter against independent references (hand-made pairs, a
// Möller–Trumbore edge test on random pairs, brute force over all pairs), and issue 3's
// "no self-intersections added by the remesher" on every committed real mesh.

#include <pliant/core/field.h>
#include <pliant/core/hash.h>
#include <pliant/mesh/io.h>
#include <pliant/remesh/intersections.h>
#include <pliant/remesh/remesh.h>
#include <pliant/remesh/sample.h>
#include <pliant/remesh/untangle.h>

#include <gtest/gtest.h>
#include <omp.h>

#include "remesh/intersections_internal.h"
#include "remesh/obb_tree.h"
#include "shapes.h"
#include "support/address_space.h"
#include "support/fp_traps.h"
#include "support/test_paths.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <new>
#include <ostream>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

namespace pliant::remesh
{
namespace
{

using core::Vec3;
using Tri = std::array<Vec3, 3>;

mesh::TriMesh load(const std::string& name)
{
    const test::FpTrapsOff off;  // Assimp computes with inf/NaN internally
    auto r = mesh::import_mesh(test::source_dir() / "tests" / "data" / "meshes" / name);
    EXPECT_TRUE(r) << (r ? "" : r.error().message);
    return r ? *r : mesh::TriMesh{};
}

// ---------------------------------------------------------------------------------------------
// hand-made pairs

TEST(TrianglesIntersect, HandMadePairs)
{
    const Tri xy{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{0, 2, 0}};
    // pierces the interior
    EXPECT_TRUE(triangles_intersect(xy, {Vec3{0.5, 0.5, -1}, Vec3{0.5, 0.5, 1}, Vec3{1, 0.2, 1}}));
    // above, parallel
    EXPECT_FALSE(triangles_intersect(xy, {Vec3{0, 0, 1}, Vec3{2, 0, 1}, Vec3{0, 2, 1}}));
    // crosses the plane outside the triangle (beyond the hypotenuse)
    EXPECT_FALSE(triangles_intersect(xy, {Vec3{1.5, 1.5, -1}, Vec3{1.5, 1.5, 1}, Vec3{3, 3, 0}}));
    // touches at one vertex on the plane, inside the triangle
    EXPECT_TRUE(triangles_intersect(xy, {Vec3{0.5, 0.5, 0}, Vec3{0.5, 0.5, 1}, Vec3{1, 0, 1}}));
    // a vertex just above the plane: no contact
    EXPECT_FALSE(
        triangles_intersect(xy, {Vec3{0.5, 0.5, 1e-12}, Vec3{0.5, 0.5, 1}, Vec3{1, 0, 1}}));
    // edge against edge, crossing (an X through the hypotenuse's line)
    EXPECT_TRUE(triangles_intersect(xy, {Vec3{1, 1, -1}, Vec3{1, 1, 1}, Vec3{3, 3, 0}}));
    // coplanar, overlapping
    EXPECT_TRUE(triangles_intersect(xy, {Vec3{1, 1, 0}, Vec3{-1, 0.5, 0}, Vec3{1, -1, 0}}));
    // coplanar, one inside the other
    EXPECT_TRUE(triangles_intersect(xy, {Vec3{0.2, 0.2, 0}, Vec3{0.5, 0.2, 0}, Vec3{0.2, 0.5, 0}}));
    // coplanar, disjoint
    EXPECT_FALSE(triangles_intersect(xy, {Vec3{3, 3, 0}, Vec3{4, 3, 0}, Vec3{3, 4, 0}}));
    // two faces folded over a common line but offset along it: no contact
    EXPECT_FALSE(triangles_intersect(xy, {Vec3{3, 0, 0}, Vec3{5, 0, 0}, Vec3{4, 0, 1}}));
}

// A degenerate triangle (its corners on one line) is a segment of space, which need not lie in
// the other's plane: projecting the two onto an arbitrary plane made skew segments "cross".
TEST(TrianglesIntersect, DegenerateTrianglesAreSegmentsOfSpace)
{
    const Tri xy{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}};
    // a segment passing beside the triangle (it crosses z = 0 at (0.25, -0.375), outside)
    const Tri beside{Vec3{0.2, -0.5, -0.1}, Vec3{0.8, 0.5, 1.9}, Vec3{0.8, 0.5, 1.9}};
    EXPECT_FALSE(triangles_intersect(xy, beside));
    EXPECT_FALSE(triangles_intersect(beside, xy));
    // one through it (three distinct collinear corners)
    const Tri through{Vec3{0.2, 0.2, -1}, Vec3{0.2, 0.2, 0.5}, Vec3{0.2, 0.2, 1}};
    EXPECT_TRUE(triangles_intersect(xy, through));
    EXPECT_TRUE(triangles_intersect(through, xy));
    // two segments of space: skew, crossing, collinear apart, collinear overlapping, a point on
    // one
    const Tri s1{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{1, 0, 0}};
    EXPECT_FALSE(triangles_intersect(s1, {Vec3{1, -1, 1}, Vec3{1, 1, 1}, Vec3{1, 1, 1}}));
    EXPECT_TRUE(triangles_intersect(s1, {Vec3{1, -1, 1}, Vec3{1, 1, -1}, Vec3{1, 0, 0}}));
    EXPECT_FALSE(triangles_intersect(s1, {Vec3{3, 0, 0}, Vec3{4, 0, 0}, Vec3{5, 0, 0}}));
    EXPECT_TRUE(triangles_intersect(s1, {Vec3{1.5, 0, 0}, Vec3{4, 0, 0}, Vec3{3, 0, 0}}));
    EXPECT_TRUE(triangles_intersect(s1, {Vec3{0.5, 0, 0}, Vec3{0.5, 0, 0}, Vec3{0.5, 0, 0}}));
    EXPECT_FALSE(
        triangles_intersect(s1, {Vec3{0.5, 0, 1e-9}, Vec3{0.5, 0, 1e-9}, Vec3{0.5, 0, 1e-9}}));
    // an edge against a degenerate face (the test for faces sharing one vertex)
    EXPECT_FALSE(edge_meets_triangle(Vec3{0.2, -0.5, -0.1}, Vec3{0.8, 0.5, 1.9},
                                     {Vec3{0, 0.5, 0}, Vec3{1, 0.5, 0}, Vec3{2, 0.5, 0}}));
    EXPECT_TRUE(edge_meets_triangle(Vec3{0.5, 0.5, -1}, Vec3{0.5, 0.5, 1},
                                    {Vec3{0, 0.5, 0}, Vec3{1, 0.5, 0}, Vec3{2, 0.5, 0}}));
}

// Two faces touching at a position they both hold (an unwelded mesh) far from the origin: the
// plane test took the centre of their boxes' overlap first, rounded relative to the coordinates
// (7 here), and found the touching face's plane clear of it.
TEST(SelfIntersections, FacesTouchingAtACopiedPositionFarFromTheOriginCount)
{
    mesh::TriMesh m;
    m.positions = {Vec3{-7.1799558486053137, -7.2671855173039699, -6.7051058493694633},
                   Vec3{-7.8818287729231828, -7.7593082873636661, -6.5391713023866069},
                   Vec3{-7.3020245259028265, -7.2715076476861, -6.274009093114211},
                   Vec3{-7.1799558486053137, -7.2671855173039699, -6.7051058493694633},
                   Vec3{-6.5296356384587444, -7.1088324598873731, -6.7092277139123944},
                   Vec3{-7.1799693678196723, -6.3134651632575185, -6.779437274946698}};
    m.faces = {{0, 1, 2}, {3, 4, 5}};
    const Tri a{m.positions[0], m.positions[1], m.positions[2]};
    const Tri b{m.positions[3], m.positions[4], m.positions[5]};
    ASSERT_TRUE(triangles_intersect(a, b));
    EXPECT_EQ(intersecting_pairs(m), (std::vector<std::array<std::uint32_t, 2>>{{0, 1}}));
    // and the same pair shifted far off: every copy of a sphere's faces touching another's
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> offset(-1e4, 1e4);
    for (int k = 0; k < 20; ++k)
    {
        const Vec3 shift{offset(rng), offset(rng), offset(rng)};
        mesh::TriMesh far = m;
        for (Vec3& p : far.positions)
            p += shift;
        const Tri fa{far.positions[0], far.positions[1], far.positions[2]};
        const Tri fb{far.positions[3], far.positions[4], far.positions[5]};
        if (triangles_intersect(fa, fb))
        {
            EXPECT_EQ(intersecting_pairs(far).size(), 1U) << k;
        }
    }
}

/// Independent reference for generic pairs: Möller–Trumbore for each of the six edges.
bool edge_hits(const Vec3& p, const Vec3& q, const Tri& t)
{
    const Vec3 d = q - p, e1 = t[1] - t[0], e2 = t[2] - t[0];
    const Vec3 h = core::cross(d, e2);
    const double a = core::dot(e1, h);
    if (std::abs(a) < 1e-14)
        return false;
    const Vec3 s = p - t[0];
    const double u = core::dot(s, h) / a;
    const Vec3 qq = core::cross(s, e1);
    const double v = core::dot(d, qq) / a;
    const double tt = core::dot(e2, qq) / a;
    return u >= 0 && v >= 0 && u + v <= 1 && tt >= 0 && tt <= 1;
}

TEST(TrianglesIntersect, AgreesWithMollerTrumboreOnRandomPairs)
{
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    const auto rnd = [&] { return Vec3{uni(rng), uni(rng), uni(rng)}; };
    int hits = 0;
    for (int i = 0; i < 20'000; ++i)
    {
        const Tri a{rnd(), rnd(), rnd()};
        const Tri b{rnd(), rnd(), rnd()};
        bool ref = false;
        for (int k = 0; k < 3; ++k)
            ref = ref || edge_hits(a[k], a[(k + 1) % 3], b) || edge_hits(b[k], b[(k + 1) % 3], a);
        EXPECT_EQ(triangles_intersect(a, b), ref) << i;
        hits += ref ? 1 : 0;
    }
    EXPECT_GT(hits, 1000);  // both outcomes well represented
    EXPECT_LT(hits, 19'000);
}

// edge_meets_triangle rejects a segment whose bounding box misses the triangle's before any
// orientation test: the answers must be those of the reference, whether the boxes are apart,
// overlap, or touch at one coordinate.
TEST(EdgeMeetsTriangle, AgreesWithMollerTrumboreOnRandomSegments)
{
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    const auto rnd = [&] { return Vec3{uni(rng), uni(rng), uni(rng)}; };
    int hits = 0, apart = 0;
    for (int i = 0; i < 20'000; ++i)
    {
        const Tri t{rnd(), rnd(), rnd()};
        const Vec3 p = rnd(), q = rnd();
        const bool ref = edge_hits(p, q, t);
        EXPECT_EQ(edge_meets_triangle(p, q, t), ref) << i;
        hits += ref ? 1 : 0;
        const auto coord_apart = [&](double Vec3::*c)
        {
            return std::max(p.*c, q.*c) < std::min({t[0].*c, t[1].*c, t[2].*c}) ||
                   std::min(p.*c, q.*c) > std::max({t[0].*c, t[1].*c, t[2].*c});
        };
        apart += coord_apart(&Vec3::x) || coord_apart(&Vec3::y) || coord_apart(&Vec3::z) ? 1 : 0;
    }
    EXPECT_GT(hits, 1000);
    EXPECT_GT(apart, 1000);  // the filter's path is taken
    EXPECT_LT(hits + apart, 19'000);
}

TEST(EdgeMeetsTriangle, BoxesTouchingAtOneCoordinateStillMeet)
{
    const Tri xy{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{0, 2, 0}};
    // in the plane, ending on the vertex (2,0,0): the boxes share x = 2 only
    EXPECT_TRUE(edge_meets_triangle(Vec3{2, 0, 0}, Vec3{3, 0, 0}, xy));
    // in the plane, starting just beyond it: boxes apart
    EXPECT_FALSE(edge_meets_triangle(Vec3{2.0000001, 0, 0}, Vec3{3, 0, 0}, xy));
    // across the plane, touching the triangle's box at z = 0 from above
    EXPECT_TRUE(edge_meets_triangle(Vec3{0.5, 0.5, 0}, Vec3{0.5, 0.5, 1}, xy));
    EXPECT_FALSE(edge_meets_triangle(Vec3{0.5, 0.5, 1e-300}, Vec3{0.5, 0.5, 1}, xy));
    // collinear with the hypotenuse, beyond its end: boxes apart in y
    EXPECT_FALSE(edge_meets_triangle(Vec3{-1, 3, 0}, Vec3{-2, 4, 0}, xy));
}

// ---------------------------------------------------------------------------------------------
// the broad phase against brute force

/// Every intersecting pair by brute force over all pairs (no grid, no stars, no plane test).
std::vector<std::array<std::uint32_t, 2>> brute_force_pair_list(const mesh::TriMesh& m)
{
    std::vector<std::array<std::uint32_t, 2>> out;
    for (std::uint32_t i = 0; i < m.faces.size(); ++i)
        for (std::uint32_t j = i + 1; j < m.faces.size(); ++j)
        {
            const auto& a = m.faces[i];
            const auto& b = m.faces[j];
            const Tri ta{m.positions[a[0]], m.positions[a[1]], m.positions[a[2]]};
            const Tri tb{m.positions[b[0]], m.positions[b[1]], m.positions[b[2]]};
            std::vector<std::array<std::size_t, 2>> shared;
            for (std::size_t k = 0; k < 3; ++k)
                for (std::size_t l = 0; l < 3; ++l)
                    if (a[k] == b[l])
                        shared.push_back({k, l});
            bool meet = false;
            if (shared.empty())
                meet = triangles_intersect(ta, tb);
            else if (shared.size() == 1)
            {
                const auto [k, l] = shared[0];
                meet = edge_meets_triangle(ta[(k + 1) % 3], ta[(k + 2) % 3], tb) ||
                       edge_meets_triangle(tb[(l + 1) % 3], tb[(l + 2) % 3], ta);
            }
            if (meet)
                out.push_back({i, j});
        }
    return out;
}

std::size_t brute_force_pairs(const mesh::TriMesh& m)
{
    return brute_force_pair_list(m).size();
}

/// Two overlapping spheres of different sizes in one mesh (icospheres of `big` and `small`
/// subdivisions): their faces cross along a circle.
mesh::TriMesh two_spheres(int big = 3, int small = 2)
{
    mesh::TriMesh two = scenes::icosphere(big);
    const mesh::TriMesh other = scenes::icosphere(small);
    const auto base = static_cast<std::uint32_t>(two.positions.size());
    for (const Vec3& p : other.positions)
        two.positions.push_back(p * 0.8 + Vec3{0.5, 0.1, 0.05});
    for (const auto& f : other.faces)
        two.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
    return two;
}

TEST(SelfIntersections, BroadPhaseMatchesBruteForce)
{
    // a closed sphere: none
    const mesh::TriMesh ico = scenes::icosphere(2);
    EXPECT_EQ(count_self_intersections(ico), 0U);
    EXPECT_EQ(brute_force_pairs(ico), 0U);
    // two overlapping spheres: their faces cross along a circle
    const mesh::TriMesh two = two_spheres();
    const std::size_t brute = brute_force_pairs(two);
    EXPECT_GT(brute, 50U);
    EXPECT_EQ(count_self_intersections(two), brute);
    // a sphere with one vertex pushed through the opposite side
    mesh::TriMesh dented = scenes::icosphere(2);
    dented.positions[0] = dented.positions[0] * -1.5;
    const std::size_t dent = brute_force_pairs(dented);
    EXPECT_GT(dent, 0U);
    EXPECT_EQ(count_self_intersections(dented), dent);
}

// The recount the untangling does after some vertices moved: the pairs touching the faces
// around them, joined to the earlier pairs of untouched faces, are exactly a whole count; and for
// any flags, intersecting_pairs_touching is the whole count's pairs with a flagged face.
TEST(SelfIntersections, PairsTouchingMovedFacesCompleteTheEarlierCount)
{
    mesh::TriMesh two = two_spheres();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> jitter(-0.15, 0.15);
    std::uniform_int_distribution<std::uint32_t> pick(
        0, static_cast<std::uint32_t>(two.positions.size() - 1));
    const auto faces_of = [&](std::span<const std::uint32_t> moved)
    {
        std::vector<std::uint8_t> touched(two.faces.size(), 0);
        for (std::size_t f = 0; f < two.faces.size(); ++f)
            for (const std::uint32_t v : two.faces[f])
                if (std::find(moved.begin(), moved.end(), v) != moved.end())
                    touched[f] = 1;
        return touched;
    };
    for (int trial = 0; trial < 20; ++trial)
    {
        const auto before = intersecting_pairs(two);
        // a local change (one vertex and its neighbourhood) or a scattered one
        std::vector<std::uint32_t> moved;
        const std::uint32_t centre = pick(rng);
        for (std::uint32_t k = 0; k < 1 + static_cast<std::uint32_t>(trial % 7); ++k)
            moved.push_back(trial % 2 == 0 ? pick(rng)
                                           : two.faces[centre % two.faces.size()][k % 3]);
        for (const std::uint32_t v : moved)
            two.positions[v] += Vec3{jitter(rng), jitter(rng), jitter(rng)};
        const auto touched = faces_of(moved);
        const auto after = intersecting_pairs(two);
        const auto fresh = intersecting_pairs_touching(two, touched);
        std::vector<std::array<std::uint32_t, 2>> expected_fresh;
        for (const auto& pr : after)
            if (touched[pr[0]] != 0 || touched[pr[1]] != 0)
                expected_fresh.push_back(pr);
        EXPECT_EQ(fresh, expected_fresh) << "trial " << trial;
        std::vector<std::array<std::uint32_t, 2>> joined;
        for (const auto& pr : before)
            if (touched[pr[0]] == 0 && touched[pr[1]] == 0)
                joined.push_back(pr);
        joined.insert(joined.end(), fresh.begin(), fresh.end());
        std::sort(joined.begin(), joined.end());
        EXPECT_EQ(joined, after) << "trial " << trial;
    }
    EXPECT_GT(intersecting_pairs(two).size(), 50U);
    // no flag: nothing; every flag: the whole count
    EXPECT_TRUE(
        intersecting_pairs_touching(two, std::vector<std::uint8_t>(two.faces.size(), 0)).empty());
    EXPECT_EQ(intersecting_pairs_touching(two, std::vector<std::uint8_t>(two.faces.size(), 1)),
              intersecting_pairs(two));
}

// A sink that asks to stop from its (after + 1)-th poll on, and notes how often it was polled and
// whether any poll came from a thread other than the one that made it.
class StopAfter final : public core::ProgressSink
{
public:
    explicit StopAfter(std::size_t after) : after_(after) {}
    void update(std::string_view, double) noexcept override {}
    [[nodiscard]] bool stop_requested() const noexcept override
    {
        if (std::this_thread::get_id() != owner_)
            foreign_.store(true);
        return polls_.fetch_add(1) + 1 > after_;
    }
    [[nodiscard]] std::size_t polls() const { return polls_.load(); }
    [[nodiscard]] bool polled_from_another_thread() const { return foreign_.load(); }

private:
    std::size_t after_;
    std::thread::id owner_ = std::this_thread::get_id();
    mutable std::atomic<std::size_t> polls_{0};
    mutable std::atomic<bool> foreign_{false};
};

// Runs `f` on one OpenMP thread (the polls are then deterministic), restoring the count after.
template <typename F>
auto on_one_thread(F&& f)
{
    const int before = omp_get_max_threads();
    omp_set_num_threads(1);
    auto r = f();
    omp_set_num_threads(before);
    return r;
}

// A long count polls its sink (from the calling thread only) and ends early once asked: a
// count of a million faces takes seconds, and remesh's Ctrl-C waited for it (2-7 s at level 10).
TEST(SelfIntersections, ACountPollsItsSinkAndEndsEarlyWhenAskedToStop)
{
    const mesh::TriMesh two = two_spheres(5, 4);
    const auto full = intersecting_pairs(two);
    ASSERT_GT(full.size(), 300U);
    // Not stopped: the same pairs, on any number of threads, polled from this thread only.
    StopAfter never(std::numeric_limits<std::size_t>::max());
    EXPECT_EQ(intersecting_pairs(two, &never), full);
    EXPECT_FALSE(never.polled_from_another_thread());
    // On one thread: 3 polls between the serial stages, then one per chunk of 64 cells.
    StopAfter counted(std::numeric_limits<std::size_t>::max());
    EXPECT_EQ(on_one_thread([&] { return intersecting_pairs(two, &counted); }), full);
    ASSERT_GT(counted.polls(), 3U + 20U);
    const std::size_t chunks = counted.polls() - 3;
    // Stopped within the parallel loop (after its k-th chunk): part of the pairs, more the later
    // the stop, and no poll after the first that said stop.
    std::size_t previous = 0;
    for (const std::size_t k : {chunks / 4, chunks / 2, chunks * 3 / 4})
    {
        StopAfter at(3 + k);
        const auto part = on_one_thread([&] { return intersecting_pairs(two, &at); });
        EXPECT_LT(part.size(), full.size()) << "chunks " << k;
        EXPECT_GE(part.size(), previous) << "chunks " << k;
        EXPECT_TRUE(std::includes(full.begin(), full.end(), part.begin(), part.end()));
        EXPECT_EQ(at.polls(), 3 + k + 1) << "chunks " << k;
        previous = part.size();
    }
    EXPECT_GT(previous, 0U);
    // Stopped at once: nothing, in each entry point.
    StopAfter at_once(0);
    EXPECT_TRUE(intersecting_pairs(two, &at_once).empty());
    StopAfter at_once_too(0);
    EXPECT_EQ(count_self_intersections(two, &at_once_too), 0U);
    std::vector<std::uint8_t> all(two.faces.size(), 1);
    StopAfter touching(0);
    EXPECT_TRUE(intersecting_pairs_touching(two, all, &touching).empty());
}

TEST(SelfIntersections, FacesSharingAVertexCountOnlyWhenTheyOverlap)
{
    mesh::TriMesh m;
    m.positions = {Vec3{0, 0, 0},    Vec3{1, 0, 0},       Vec3{0, 1, 0},       Vec3{-1, 0, 0.1},
                   Vec3{0, -1, 0.1}, Vec3{0.4, 0.2, 0.5}, Vec3{0.2, 0.4, -0.5}};
    // a fan around vertex 0: (0,1,2) and (0,3,4) meet only at 0
    m.faces = {{0, 1, 2}, {0, 3, 4}};
    EXPECT_EQ(count_self_intersections(m), 0U);
    // (0,5,6) stands through (0,1,2): its far edge pierces it at (0.3, 0.3, 0)
    m.faces = {{0, 1, 2}, {0, 5, 6}};
    EXPECT_EQ(count_self_intersections(m), 1U);
    // sharing an edge: never counted
    m.faces = {{0, 1, 2}, {0, 2, 5}};
    EXPECT_EQ(count_self_intersections(m), 0U);
}

// A flat fan in each axis plane (a cylinder's cap, the case orient3d answers 0 for without its
// 113-bit fallback): a sector that overlaps another counts, neighbours that only touch do not,
// as the brute-force count over every pair says.
TEST(SelfIntersections, FlatFansInAxisPlanesCountOverlappingSectorsOnly)
{
    for (int axis = 0; axis < 3; ++axis)
    {
        const auto at = [axis](double u, double v)
        {
            std::array<double, 3> c{0.25, 0.25, 0.25};  // the plane: coordinate `axis` = 0.25
            c[static_cast<std::size_t>((axis + 1) % 3)] = u;
            c[static_cast<std::size_t>((axis + 2) % 3)] = v;
            return Vec3{c[0], c[1], c[2]};
        };
        mesh::TriMesh m;
        m.positions.push_back(at(0.0, 0.0));
        constexpr int k_sides = 24;
        for (int k = 0; k < k_sides; ++k)
        {
            const double a = 2.0 * 3.14159265358979 * k / k_sides;
            m.positions.push_back(at(std::cos(a), std::sin(a)));
        }
        for (std::uint32_t k = 0; k < k_sides; ++k)
            m.faces.push_back({0, 1 + k, 1 + (k + 1) % k_sides});
        EXPECT_EQ(count_self_intersections(m), 0U) << "axis " << axis;
        // One sector spanning three, (0,3,6): it shares an edge with (0,2,3), (0,3,4), (0,5,6)
        // and (0,6,7), never counted, and only the vertex 0 with (0,4,5), inside it: 1 pair.
        m.faces.push_back({0, 3, 6});
        EXPECT_EQ(count_self_intersections(m), 1U) << "axis " << axis;
        EXPECT_EQ(brute_force_pairs(m), 1U) << "axis " << axis;
    }
}

// ---------------------------------------------------------------------------------------------
// stars: faces around a vertex of high valence, paired by angle about it

/// A closed cone of `sides` sides: apex 0 at (0, 0, apex_z), the cap's centre 1 at
/// (0, 0, cap_z), ring vertices 2.. on the unit circle at z = 0; outward faces when
/// apex_z > 0 >= cap_z.
mesh::TriMesh cone(std::uint32_t sides, double apex_z = 1.0, double cap_z = -0.2)
{
    mesh::TriMesh m;
    m.positions = {Vec3{0, 0, apex_z}, Vec3{0, 0, cap_z}};
    for (std::uint32_t k = 0; k < sides; ++k)
    {
        const double a = 2.0 * 3.14159265358979323846 * k / sides;
        m.positions.push_back(Vec3{std::cos(a), std::sin(a), 0.0});
    }
    for (std::uint32_t k = 0; k < sides; ++k)
    {
        const std::uint32_t b = 2 + k, c = 2 + (k + 1) % sides;
        m.faces.push_back({0, b, c});
        m.faces.push_back({1, c, b});
    }
    return m;
}

std::vector<std::uint32_t> faces_around(const mesh::TriMesh& m, std::uint32_t v)
{
    std::vector<std::uint32_t> out;
    for (std::uint32_t f = 0; f < m.faces.size(); ++f)
        if (std::find(m.faces[f].begin(), m.faces[f].end(), v) != m.faces[f].end())
            out.push_back(f);
    return out;
}

TEST(VertexFanIsStar, CertifiesConesAndFlatCapsAndRefusesFoldsTwistsAndPinches)
{
    const mesh::TriMesh c = cone(40);
    EXPECT_TRUE(vertex_fan_is_star(c, 0, faces_around(c, 0)));  // the apex
    EXPECT_TRUE(vertex_fan_is_star(c, 1, faces_around(c, 1)));  // the shallow cap's centre
    const mesh::TriMesh flat = cone(40, 1.0, 0.0);
    EXPECT_TRUE(vertex_fan_is_star(flat, 1, faces_around(flat, 1)));  // a flat fan
    // a ring vertex whose only faces are its two neighbours' on each side: valence 4, a star
    // too, and a part of the fan is not one
    EXPECT_TRUE(vertex_fan_is_star(c, 5, faces_around(c, 5)));
    auto part = faces_around(c, 0);
    part.pop_back();
    EXPECT_FALSE(vertex_fan_is_star(c, 0, part));
    // one ring vertex moved across its neighbour: the images of two faces fold over
    mesh::TriMesh folded = c;
    folded.positions[10] = Vec3{std::cos(0.5), std::sin(0.5), 0.0};  // between ring 12 and 13
    EXPECT_FALSE(vertex_fan_is_star(folded, 0, faces_around(folded, 0)));
    // a face turned over
    mesh::TriMesh flipped = c;
    std::swap(flipped.faces[6][1], flipped.faces[6][2]);
    EXPECT_FALSE(vertex_fan_is_star(flipped, 0, faces_around(flipped, 0)));
    // a fan winding twice around its vertex: every face turns the same way, the angles make two
    // turns
    mesh::TriMesh twice;
    twice.positions.push_back(Vec3{0, 0, 0});
    constexpr std::uint32_t k_link = 30;
    for (std::uint32_t k = 0; k < k_link; ++k)
    {
        const double a = 4.0 * 3.14159265358979323846 * k / k_link;
        twice.positions.push_back(Vec3{std::cos(a) * (1.0 + 0.01 * k), std::sin(a), -0.1});
    }
    for (std::uint32_t k = 0; k < k_link; ++k)
        twice.faces.push_back({0, 1 + k, 1 + (k + 1) % k_link});
    EXPECT_FALSE(vertex_fan_is_star(twice, 0, faces_around(twice, 0)));
    EXPECT_GT(brute_force_pair_list(twice).size(), 0U);
    // two cones' apexes at one vertex (a pinch): two cycles
    mesh::TriMesh pinch = c;
    const auto base = static_cast<std::uint32_t>(pinch.positions.size());
    for (const Vec3& p : c.positions)
        pinch.positions.push_back(Vec3{p.x, p.y, 2.0 - p.z});
    for (const auto& f : c.faces)
    {
        const auto at = [&](std::uint32_t x) { return x == 0 ? 0U : x + base; };
        pinch.faces.push_back({at(f[0]), at(f[2]), at(f[1])});
    }
    EXPECT_FALSE(vertex_fan_is_star(pinch, 0, faces_around(pinch, 0)));
    // a face of no area, seen edge-on from every direction: a flat fan with a ring vertex moved
    // onto the spoke to the one before it
    mesh::TriMesh edge_on = flat;
    edge_on.positions[7] = edge_on.positions[6] * 0.5;
    EXPECT_FALSE(vertex_fan_is_star(edge_on, 1, faces_around(edge_on, 1)));
}

// The pairs of meshes with stars (cones of 40 sides, their apex or cap pushed through, a ring
// vertex pushed inside, triangles through them with a corner on the axis, random jitter)
// against brute force over all pairs, from intersecting_pairs and from
// intersecting_pairs_touching with random flags.
TEST(SelfIntersections, StarsPairLikeBruteForce)
{
    std::vector<std::pair<std::string, mesh::TriMesh>> cases;
    cases.emplace_back("cone", cone(40));
    cases.emplace_back("flat cap", cone(40, 1.0, 0.0));
    cases.emplace_back("apex through the cap", cone(40, -0.5, -0.2));
    cases.emplace_back("cap's centre above the apex", cone(40, 1.0, 1.5));
    cases.emplace_back("cap's centre on the apex's side", cone(40, 1.0, 0.4));
    {
        mesh::TriMesh m = cone(40);
        m.positions[2 + 13] = Vec3{-0.6, -0.1, 0.2};  // a ring vertex through the far side
        cases.emplace_back("ring vertex through", std::move(m));
    }
    // triangles with a corner on the axis (the apex's image of it is the origin) crossing the
    // sides, touching them, passing beside them, and one through the apex's own position
    const auto with_triangle = [&](std::string name, const Tri& t, double cap_z)
    {
        mesh::TriMesh m = cone(40, 1.0, cap_z);
        const auto base = static_cast<std::uint32_t>(m.positions.size());
        m.positions.insert(m.positions.end(), t.begin(), t.end());
        m.faces.push_back({base, base + 1, base + 2});
        cases.emplace_back(std::move(name), std::move(m));
    };
    with_triangle("axis corner, crossing", {Vec3{0, 0, 0.5}, Vec3{2, 0.3, 0.5}, Vec3{2, 0.6, 0.5}},
                  -0.2);
    with_triangle("axis corner, tilted through",
                  {Vec3{0, 0, 0.3}, Vec3{2, -0.2, 0.7}, Vec3{1.8, 0.4, 0.6}}, -0.2);
    with_triangle("axis corner, outside", {Vec3{0, 0, 1.5}, Vec3{2, 0.3, 1.2}, Vec3{2, 0.6, 1.3}},
                  -0.2);
    with_triangle("axis corner, touching the apex",
                  {Vec3{0, 0, 1.0}, Vec3{2, 0.3, 1.0}, Vec3{2, 0.6, 1.0}}, -0.2);
    with_triangle("through the apex's point", {Vec3{-1, -1, 1}, Vec3{1, -1, 1}, Vec3{0, 2, 1}},
                  -0.2);
    with_triangle("in the flat cap's plane", {Vec3{0, 0, 0}, Vec3{2, 0.3, 0}, Vec3{2, 0.6, 0}},
                  0.0);
    std::mt19937 rng(11);
    // small triangles scattered about the sides and the cap, many crossing a face or two there
    // (no corner on the axis: their images' arcs pick the wedges)
    for (int k = 0; k < 4; ++k)
    {
        mesh::TriMesh m = cone(40, 1.0, k % 2 == 0 ? -0.2 : 0.0);
        std::uniform_real_distribution<double> unit(0.0, 1.0), spread(-1.0, 1.0);
        for (int t = 0; t < 60; ++t)
        {
            const double a = 6.283185307179586 * unit(rng), r = unit(rng);
            const bool side = t % 3 != 0;
            const Vec3 at = side ? Vec3{r * std::cos(a), r * std::sin(a), 1.0 - r}
                                 : Vec3{r * std::cos(a), r * std::sin(a), 0.0};
            const double size = 0.02 + 0.3 * unit(rng);
            const auto base = static_cast<std::uint32_t>(m.positions.size());
            for (int c = 0; c < 3; ++c)
                m.positions.push_back(at + Vec3{spread(rng), spread(rng), spread(rng)} * size);
            m.faces.push_back({base, base + 1, base + 2});
        }
        cases.emplace_back("scattered triangles #" + std::to_string(k), std::move(m));
    }
    for (const double size : {0.01, 0.05, 0.2, 0.6})
        for (int k = 0; k < 6; ++k)
        {
            std::uniform_real_distribution<double> jitter(-size, size);
            mesh::TriMesh m = cone(40, k % 2 == 0 ? 1.0 : 0.3, k % 3 == 0 ? 0.0 : -0.2);
            for (Vec3& p : m.positions)
                if (rng() % 3 == 0)
                    p += Vec3{jitter(rng), jitter(rng), jitter(rng)};
            cases.emplace_back("jitter " + std::to_string(size) + " #" + std::to_string(k),
                               std::move(m));
        }
    std::size_t meeting = 0, starred = 0;
    for (const auto& [name, m] : cases)
    {
        const auto brute = brute_force_pair_list(m);
        meeting += brute.empty() ? 0 : 1;
        starred += vertex_fan_is_star(m, 0, faces_around(m, 0)) ? 1 : 0;
        EXPECT_EQ(intersecting_pairs(m), brute) << name;
        std::vector<std::uint8_t> touched(m.faces.size(), 0);
        for (auto& t : touched)
            t = rng() % 5 == 0 ? 1 : 0;
        std::vector<std::array<std::uint32_t, 2>> expected;
        for (const auto& pr : brute)
            if (touched[pr[0]] != 0 || touched[pr[1]] != 0)
                expected.push_back(pr);
        EXPECT_EQ(intersecting_pairs_touching(m, touched), expected) << name;
    }
    // the cases exercise both answers and the stars
    EXPECT_GE(meeting, 12U);
    EXPECT_GE(starred, 20U);
}

// A face with a corner within 1e-6 of a star's axis (not on it) and the rest far from it: its
// image leaves the arc of its other two corners by up to eps / rho near the radius rho where it
// crosses the fan (rho = its height over the fan's steepness K), and the wedges it crosses
// there, outside that arc by less than (pi / 2) eps / rho, are still paired with it. (With K
// taken three times smaller, rho grows and the widening shrinks below what the edge sweeps.)
TEST(SelfIntersections, AFaceWithACornerNearTheAxisMeetsTheWedgesItsEdgeSweeps)
{
    // A steep cone (apex v at the origin, ring of radius 1 at z = -4: K = 4) of 40 sides and two
    // narrow wedges just below angle 0.
    mesh::TriMesh m;
    m.positions.push_back(Vec3{0, 0, 0});
    std::vector<double> angles{-1.9e-6, -1.3e-6};
    for (int k = 0; k < 40; ++k)
        angles.push_back(2.0 * 3.14159265358979323846 * k / 40.0);
    std::sort(angles.begin(), angles.end());
    for (const double a : angles)
        m.positions.push_back(Vec3{std::cos(a), std::sin(a), -4.0});
    const auto n = static_cast<std::uint32_t>(angles.size());
    for (std::uint32_t k = 0; k < n; ++k)
        m.faces.push_back({0, 1 + (k + 1) % n, 1 + k});
    ASSERT_TRUE(vertex_fan_is_star(m, 0, faces_around(m, 0)));
    // The face: a corner 3e-7 off the axis (towards negative angles) at z = -0.5, the others at
    // radius 0.9 at angles 0 and 0.01, all at z = -0.5: it crosses the cone on the circle of
    // radius rho = 0.5 / 4, where its edge from the near corner sits at angle -2.1e-6.
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    m.positions.push_back(Vec3{0, -3e-7, -0.5});
    m.positions.push_back(Vec3{0.9, 0, -0.5});
    m.positions.push_back(Vec3{0.9 * std::cos(0.01), 0.9 * std::sin(0.01), -0.5});
    m.faces.push_back({base, base + 1, base + 2});
    const auto brute = brute_force_pair_list(m);
    const auto t = static_cast<std::uint32_t>(m.faces.size() - 1);
    // it meets the two wedges wholly below angle 0 (faces 0, from -1.9e-6 to -1.3e-6, and n - 1,
    // up to -1.9e-6), beyond its corners' arc
    const auto meets = [&](std::uint32_t f)
    {
        return std::find(brute.begin(), brute.end(), std::array<std::uint32_t, 2>{f, t}) !=
               brute.end();
    };
    EXPECT_TRUE(meets(0));
    EXPECT_TRUE(meets(n - 1));
    EXPECT_EQ(intersecting_pairs(m), brute);
    std::vector<std::uint8_t> touched(m.faces.size(), 0);
    touched[t] = 1;
    EXPECT_EQ(intersecting_pairs_touching(m, touched), brute);
}

/// `k` horizontal triangles (planes z = const) and `k` vertical ones (x = const), each
/// horizontal one crossing each vertical one along a segment of y in [-1, 1]: k² intersecting
/// pairs, all in one cell of the broad phase's grid.
mesh::TriMesh crossing_stacks(std::uint32_t k)
{
    mesh::TriMesh m;
    for (std::uint32_t i = 0; i < k; ++i)
    {
        const double c = -0.5 + (static_cast<double>(i) + 0.5) / static_cast<double>(k);
        const auto v = static_cast<std::uint32_t>(m.positions.size());
        m.positions.insert(m.positions.end(), {Vec3{-4, -2, c}, Vec3{4, -2, c}, Vec3{0, 4, c},
                                               Vec3{c, -4, -2}, Vec3{c, 4, -2}, Vec3{c, 0, 4}});
        m.faces.push_back({v, v + 1, v + 2});
        m.faces.push_back({v + 3, v + 4, v + 5});
    }
    return m;
}

// ---------------------------------------------------------------------------------------------
// crowded cells: the oriented-box tree

/// `b`'s faces appended to `a`'s, its positions mapped by `f`.
template <typename Map>
mesh::TriMesh joined(mesh::TriMesh a, const mesh::TriMesh& b, Map f)
{
    const auto base = static_cast<std::uint32_t>(a.positions.size());
    for (const Vec3& p : b.positions)
        a.positions.push_back(f(p));
    for (const auto& t : b.faces)
        a.faces.push_back({t[0] + base, t[1] + base, t[2] + base});
    return a;
}

// Boxes that share a point are never reported apart, and boxes on either side of a plane are:
// against points sampled in one box and tested in the other, and against boxes built apart.
TEST(OrientedBoxes, SharingAPointIsNeverApartAndAGapAcrossAPlaneIs)
{
    std::mt19937_64 rng(31);
    std::uniform_real_distribution<double> unit(-1.0, 1.0), size(0.0, 1.0);
    const auto frame = [&]
    {
        Vec3 a{unit(rng), unit(rng), unit(rng)};
        Vec3 b{unit(rng), unit(rng), unit(rng)};
        a = core::normalized(a);
        b = core::normalized(b - a * core::dot(a, b));
        return std::array<Vec3, 3>{a, b, core::cross(a, b)};
    };
    const auto box = [&](const Vec3& centre)
    {
        detail::Obb o;
        o.centre = centre;
        o.axis = frame();
        // thin, flat and long boxes as well as fat ones
        for (double& h : o.half)
            h = size(rng) < 0.3 ? 1e-9 * size(rng) : size(rng);
        return o;
    };
    const auto inside = [](const detail::Obb& o, const Vec3& p)
    {
        for (int k = 0; k < 3; ++k)
            if (std::fabs(core::dot(p - o.centre, o.axis[k])) > o.half[k])
                return false;
        return true;
    };
    std::size_t sharing = 0, apart = 0;
    for (int trial = 0; trial < 4000; ++trial)
    {
        const detail::Obb a = box(Vec3{unit(rng), unit(rng), unit(rng)});
        const detail::Obb b = box(Vec3{unit(rng), unit(rng), unit(rng)});
        const bool may = detail::obbs_may_overlap(a, b);
        EXPECT_EQ(may, detail::obbs_may_overlap(b, a)) << trial;
        for (int s = 0; s < 200; ++s)
        {
            Vec3 p = a.centre;
            for (int k = 0; k < 3; ++k)
                p += a.axis[k] * (a.half[k] * (s < 8 ? ((s >> k) & 1 ? 1.0 : -1.0) : unit(rng)));
            if (inside(b, p))
            {
                ++sharing;
                EXPECT_TRUE(may) << trial;
                break;
            }
        }
        // b moved along a random direction n until its lowest point clears a's highest by 1e-6
        const Vec3 n = core::normalized(Vec3{unit(rng), unit(rng), unit(rng)});
        const auto reach = [&](const detail::Obb& o)
        {
            return o.half[0] * std::fabs(core::dot(o.axis[0], n)) +
                   o.half[1] * std::fabs(core::dot(o.axis[1], n)) +
                   o.half[2] * std::fabs(core::dot(o.axis[2], n));
        };
        detail::Obb c = b;
        c.centre = b.centre + n * (core::dot(a.centre - b.centre, n) + reach(a) + reach(b) + 1e-6);
        EXPECT_FALSE(detail::obbs_may_overlap(a, c)) << trial;
        EXPECT_FALSE(detail::obbs_may_overlap(c, a)) << trial;
        ++apart;
        // and touching: c's lowest corner along n on a's highest
        const auto corner = [&](const detail::Obb& o, double side)
        {
            Vec3 p = o.centre;
            for (int k = 0; k < 3; ++k)
                p += o.axis[k] * (core::dot(o.axis[k], n) * side >= 0.0 ? o.half[k] : -o.half[k]);
            return p;
        };
        c.centre = b.centre + (corner(a, 1.0) - corner(b, -1.0));
        EXPECT_TRUE(detail::obbs_may_overlap(a, c)) << trial;
        EXPECT_TRUE(detail::obbs_may_overlap(c, a)) << trial;
    }
    EXPECT_GT(sharing, 300U);
    EXPECT_EQ(apart, 4000U);
}

// The faces of crowded cells are paired by the oriented-box tree, the others by the grid, and
// the pairs are brute force's whatever the crowd threshold: every face by the tree (0), most
// (2, 8), or as in a count (the default) on meshes with and without crowded cells.
TEST(SelfIntersections, TheOrientedBoxTreePairsLikeBruteForce)
{
    std::vector<std::pair<std::string, mesh::TriMesh>> cases;
    cases.emplace_back("frustum", scenes::frustum(48));
    {
        mesh::TriMesh m = scenes::frustum(48);
        m.positions[2 + 5] = Vec3{-0.4, 0.1, 0.6};        // a ring vertex through the far side
        m.positions[2 + 48 + 30] = Vec3{0.2, 0.2, -0.3};  // and one through the bottom cap
        cases.emplace_back("dented frustum", std::move(m));
    }
    // slivers crossing slivers: a second frustum turned on its side through the first
    cases.emplace_back("crossed frustums",
                       joined(scenes::frustum(40), scenes::frustum(40, 0.3, -0.4),
                              [](const Vec3& p) {
                                  return Vec3{p.z - 0.5, p.y * 0.8, p.x + 0.4};
                              }));
    // touching: the second frustum's bottom ring laid on the first's top cap
    cases.emplace_back("stacked frustums",
                       joined(scenes::frustum(40, 0.5, 0.0), scenes::frustum(40, 0.5, 0.2),
                              [](const Vec3& p) {
                                  return Vec3{p.x * 0.5, p.y * 0.5, p.z + 1.0};
                              }));
    cases.emplace_back("frustum through a sphere", joined(scenes::frustum(48), scenes::icosphere(2),
                                                          [](const Vec3& p) {
                                                              return p * 0.6 + Vec3{0.5, 0.1, 0.7};
                                                          }));
    cases.emplace_back("two spheres", two_spheres(2, 2));
    cases.emplace_back("crossing stacks", crossing_stacks(12));
    {
        // a touching pair far from the origin, copied around a frustum
        mesh::TriMesh m = scenes::frustum(24);
        std::mt19937 rng(3);
        std::uniform_real_distribution<double> offset(-1e4, 1e4);
        for (int k = 0; k < 12; ++k)
        {
            const Vec3 shift{offset(rng), offset(rng), offset(rng)};
            mesh::TriMesh pair;
            pair.positions = {Vec3{-7.1799558486053137, -7.2671855173039699, -6.7051058493694633},
                              Vec3{-7.8818287729231828, -7.7593082873636661, -6.5391713023866069},
                              Vec3{-7.3020245259028265, -7.2715076476861, -6.274009093114211},
                              Vec3{-7.1799558486053137, -7.2671855173039699, -6.7051058493694633},
                              Vec3{-6.5296356384587444, -7.1088324598873731, -6.7092277139123944},
                              Vec3{-7.1799693678196723, -6.3134651632575185, -6.779437274946698}};
            pair.faces = {{0, 1, 2}, {3, 4, 5}};
            m = joined(std::move(m), pair, [&](const Vec3& p) { return p + shift; });
        }
        cases.emplace_back("touching pairs far off", std::move(m));
    }
    std::mt19937 rng(13);
    for (int k = 0; k < 6; ++k)
    {
        // jittered frustums: slivers folding into their neighbours
        mesh::TriMesh m =
            scenes::frustum(32 + 8 * static_cast<std::uint32_t>(k), 0.3 + 0.1 * k, 0.2 * k);
        std::uniform_real_distribution<double> jitter(-0.05, 0.05);
        for (Vec3& p : m.positions)
            if (rng() % 4 == 0)
                p += Vec3{jitter(rng), jitter(rng), jitter(rng)};
        cases.emplace_back("jittered frustum #" + std::to_string(k), std::move(m));
    }
    std::size_t meeting = 0, mixed = 0;
    for (const auto& [name, m] : cases)
    {
        const auto brute = brute_force_pair_list(m);
        meeting += brute.empty() ? 0 : 1;
        std::vector<std::uint8_t> touched(m.faces.size(), 0);
        for (auto& t : touched)
            t = rng() % 7 == 0 ? 1 : 0;
        std::vector<std::array<std::uint32_t, 2>> expected;
        for (const auto& pr : brute)
            if (touched[pr[0]] != 0 || touched[pr[1]] != 0)
                expected.push_back(pr);
        for (const std::size_t threshold : {std::size_t{0}, std::size_t{16}, std::size_t{32},
                                            std::size_t{64}, detail::k_crowded_cell})
        {
            const auto whole = detail::intersecting_pairs_with(m, {}, threshold);
            EXPECT_EQ(whole.pairs, brute) << name << ", threshold " << threshold;
            if (threshold == 0)
            {
                EXPECT_GT(whole.crowded, m.faces.size() / 3) << name;
            }
            else if (whole.crowded > 0 && whole.crowded < m.faces.size() / 2)
            {
                ++mixed;  // tree and grid both pairing
            }
            EXPECT_EQ(detail::intersecting_pairs_with(m, touched, threshold).pairs, expected)
                << name << ", threshold " << threshold << ", touching";
        }
    }
    EXPECT_GE(meeting, 8U);
    EXPECT_GE(mixed, 8U);
}

// The tree's pairing stops when asked too: polled at each job and every 1,024 nodes, from the
// calling thread only, it gives part of the pairs, more the later the stop.
TEST(SelfIntersections, TheTreeEndsEarlyWhenAskedToStop)
{
    const mesh::TriMesh two = two_spheres(4, 3);
    const auto full = detail::intersecting_pairs_with(two, {}, 0).pairs;
    ASSERT_GT(full.size(), 200U);
    StopAfter never(std::numeric_limits<std::size_t>::max());
    EXPECT_EQ(detail::intersecting_pairs_with(two, {}, 0, &never).pairs, full);
    EXPECT_FALSE(never.polled_from_another_thread());
    StopAfter counted(std::numeric_limits<std::size_t>::max());
    EXPECT_EQ(
        on_one_thread([&] { return detail::intersecting_pairs_with(two, {}, 0, &counted); }).pairs,
        full);
    const std::size_t polls = counted.polls();
    ASSERT_GT(polls, 20U);
    std::size_t previous = 0;
    for (const std::size_t k : {polls / 4, polls * 3 / 8, polls / 2})
    {
        StopAfter at(k);
        const auto part =
            on_one_thread([&] { return detail::intersecting_pairs_with(two, {}, 0, &at); }).pairs;
        EXPECT_LT(part.size(), full.size()) << "polls " << k;
        EXPECT_GE(part.size(), previous) << "polls " << k;
        EXPECT_TRUE(std::includes(full.begin(), full.end(), part.begin(), part.end()));
        EXPECT_EQ(at.polls(), k + 1) << "polls " << k;
        previous = part.size();
    }
    EXPECT_GT(previous, 0U);
}

// At the default threshold, the long slivers of a finely divided frustum (1,600 side faces)
// crowd their cells and the tree pairs them: the same pairs as brute force, with and without
// faces pushed through.
TEST(SelfIntersections, SlantedSliversSideBySideArePairedByTheTree)
{
    for (const bool dented : {false, true})
    {
        mesh::TriMesh m = scenes::frustum(800, 0.5, 0.4);
        if (dented)
        {
            m.positions[2 + 100] = Vec3{-0.5, -0.2, 0.5};
            m.positions[2 + 800 + 500] = Vec3{0.1, 0.3, -0.2};
        }
        const auto brute = brute_force_pair_list(m);
        EXPECT_EQ(brute.empty(), !dented);
        const auto counted = detail::intersecting_pairs_with(m, {}, detail::k_crowded_cell);
        EXPECT_GT(counted.crowded, 800U);
        EXPECT_EQ(counted.pairs, brute);
        EXPECT_EQ(intersecting_pairs(m), brute);
    }
}

// Running out of memory while the pairs are gathered (on the OpenMP threads) is a
// std::bad_alloc for the caller, as anywhere else, not std::terminate ending the process
// (remesh and the viewer report it as "out of memory"). In a child process whose address space
// is limited to 48 MiB above what it holds: the 2,100² pairs need 8 bytes each, 34 MiB, in a
// vector that doubles.
TEST(SelfIntersections, RunningOutOfMemoryAmongThePairsIsABadAlloc)
{
    EXPECT_EQ(count_self_intersections(crossing_stacks(12)), 144U);
#if defined(PLIANT_TEST_ASAN)
    GTEST_SKIP() << "AddressSanitizer's shadow memory needs more address space than any limit";
#else
    const test::ThreadsafeDeathTests threadsafe;
    const auto child = []
    {
        const mesh::TriMesh m = crossing_stacks(2100);
        // the OpenMP threads and their stacks first, then the limit
        if (count_self_intersections(crossing_stacks(4)) != 16 ||
            !test::limit_address_space(48u << 20))
            std::_Exit(3);
        try
        {
            const std::size_t n = count_self_intersections(m);
            std::fprintf(stderr, "no bad_alloc: %zu pairs\n", n);
            std::_Exit(4);
        }
        catch (const std::bad_alloc&)
        {
            std::fprintf(stderr, "std::bad_alloc reached the caller\n");
            std::_Exit(0);
        }
    };
    EXPECT_EXIT(child(), ::testing::ExitedWithCode(0), "std::bad_alloc reached the caller");
#endif
}

TEST(SelfIntersections, FoldCounterSeesAFlippedTriangle)
{
    mesh::TriMesh out = scenes::icosphere(1);
    std::vector<std::uint32_t> sample(out.positions.size());
    // every vertex "sampled" from the face of the same mesh that contains it
    for (std::size_t f = 0; f < out.faces.size(); ++f)
        for (const auto v : out.faces[f])
            sample[v] = static_cast<std::uint32_t>(f);
    EXPECT_EQ(count_folded(out, out, sample), 0U);
    mesh::TriMesh flipped = out;
    std::swap(flipped.faces[3][1], flipped.faces[3][2]);
    EXPECT_EQ(count_folded(flipped, out, sample), 1U);
}

// ---------------------------------------------------------------------------------------------
// issue 3: the remesher adds no self-intersections and no folds on any committed real mesh

struct MeshLevels
{
    const char* file;
    int min_level;
    int max_level;
};

// Test names show the file (gtest would print the struct's bytes, a pointer among them).
void PrintTo(const MeshLevels& c, std::ostream* os)
{
    *os << c.file << " levels " << c.min_level << ".." << c.max_level;
}

class RealMeshUntangled : public ::testing::TestWithParam<MeshLevels>
{
};

TEST_P(RealMeshUntangled, NoFoldsNoIntersectionsTwinsEqualOnTheSurface)
{
    const MeshLevels c = GetParam();
    // as remesh() maps it: split until it has RemeshSettings::min_map_faces faces (a no-op on
    // these meshes, all above it)
    const mesh::TriMesh m = split_for_map(load(c.file), RemeshSettings{}.min_map_faces);
    ASSERT_EQ(count_self_intersections(m), 0U) << "the input itself intersects";
    auto map = map_to_sphere(m);
    ASSERT_TRUE(map) << map.error().message;
    for (int level = c.min_level; level <= c.max_level; ++level)
    {
        const auto grid = *core::TetraGrid::create(level);
        const auto domain = core::sphere_domain(grid, core::SphereMap::EqualArea);
        auto pos = sample_surface(grid, domain, m, map->points);
        ASSERT_TRUE(pos);
        core::Vec3Field<double> points = domain;
        const UntangleStats st = untangle_samples(grid, m, map->points, points, *pos).value();
        std::printf(
            "%s level %d: sampled %zu folded, %zu pairs; after %zu, %zu (%zu nodes moved, "
            "%d rounds)\n",
            c.file, level, st.folded_sampled, st.intersections_sampled, st.folded, st.intersections,
            st.moved_nodes, st.rounds);
        // recounted here from the returned fields, not taken from the stats
        const mesh::TriMesh out = grid_surface(grid, *pos);
        EXPECT_EQ(count_self_intersections(out), 0U) << "level " << level;
        const auto faces = locate_samples(grid, points, m, map->points);
        EXPECT_EQ(count_folded(out, m, faces), 0U) << "level " << level;
        // twins equal, every node on its input face (to rounding) at its sample point
        for (const core::TwinPair& t : grid.twins())
            for (std::size_t k = 0; k < 3; ++k)
            {
                ASSERT_EQ((*pos)[k][t.twin], (*pos)[k][t.canonical]);
                ASSERT_EQ(points[k][t.twin], points[k][t.canonical]);
            }
        const auto nodes = grid.node_of_unique();
        double worst = 0.0;
        for (std::size_t u = 0; u < nodes.size(); ++u)
        {
            const auto& f = m.faces[faces[u]];
            const Vec3 p = out.positions[u];
            const Vec3 n = core::normalized(core::cross(m.positions[f[1]] - m.positions[f[0]],
                                                        m.positions[f[2]] - m.positions[f[0]]));
            worst = std::max(worst, std::abs(core::dot(p - m.positions[f[0]], n)));
        }
        EXPECT_LT(worst, 1e-9 * core::norm(m.positions[0]) + 1e-12) << "level " << level;
    }
}

// fox only at level 5: at levels 6-8 untangling still leaves folds on it (docs/remesh.md
// §3.2); see the test below
INSTANTIATE_TEST_SUITE_P(Meshes, RealMeshUntangled,
                         ::testing::Values(MeshLevels{"spot_triangulated.obj", 5, 7},
                                           MeshLevels{"cube_minus_sphere.obj", 5, 7},
                                           MeshLevels{"blub_triangulated.obj", 5, 7},
                                           MeshLevels{"cactus.off", 5, 6},
                                           MeshLevels{"fox.ply", 5, 5}),
                         [](const auto& param_info)
                         {
                             std::string n = param_info.param.file;
                             return n.substr(0, n.find_first_of("_."));
                         });

TEST(RemeshReport, CountsFoldsAndIntersectionsAndLeavesDistancesOutUnmeasured)
{
    RemeshSettings settings;
    settings.level = 4;
    settings.measure = false;
    auto r = remesh(scenes::icosphere(3), settings);
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_TRUE(r->report.input_checked);
    EXPECT_EQ(r->report.input_intersections, 0U);
    EXPECT_EQ(r->report.untangle.intersections, 0U);
    EXPECT_EQ(r->report.untangle.folded, 0U);
    const std::string json = to_json(r->report);
    for (const char* key :
         {"\"input_self_intersections\": 0", "\"self_intersections\": 0", "\"folded_triangles\": 0",
          "\"self_intersections_sampled\"", "\"untangle_moved_nodes\"", "\"untangle\": "})
        EXPECT_NE(json.find(key), std::string::npos) << key;
    EXPECT_EQ(json.find("psnr_db"), std::string::npos);
    EXPECT_EQ(json.find("rms_distance"), std::string::npos);
}

// Known limitation, measured: on fox (622 faces) untangling still leaves folded triangles at
// levels 6-8 (docs/remesh.md §3.2; level 5 is fold-free and in the suite above). Mapped as
// remesh() maps it (split to 2,488 faces, kink term on), level 6 samples 64 folded triangles and
// 119 crossing pairs; the rounds leave 8 folded (11 without the barrier descent) and no
// crossing, and the patch passes 2. This pins them so that nothing can regress unnoticed; the
// day the folds reach zero at every level, fox joins the suite above.
constexpr std::uint64_t k_fox6_golden = 0x255f288deaa68774ULL;

TEST(RealMeshUntangledFox, FewFoldsAsSampledAndFewAfterUntanglingAtLevel6)
{
    const mesh::TriMesh input = load("fox.ply");
    const mesh::TriMesh m = split_for_map(input, RemeshSettings{}.min_map_faces);
    ASSERT_EQ(m.faces.size(), 4 * input.faces.size());
    ASSERT_EQ(count_self_intersections(m), 0U);
    auto map = map_to_sphere(m);
    ASSERT_TRUE(map) << map.error().message;
    const auto grid = *core::TetraGrid::create(6);
    const auto domain = core::sphere_domain(grid, core::SphereMap::EqualArea);
    auto pos = sample_surface(grid, domain, m, map->points);
    ASSERT_TRUE(pos);
    core::Vec3Field<double> points = domain;
    const UntangleStats st = untangle_samples(grid, m, map->points, points, *pos).value();
    std::printf("fox.ply level 6: sampled %zu folded, %zu pairs; after %zu, %zu\n",
                st.folded_sampled, st.intersections_sampled, st.folded, st.intersections);
    // The untangled surface and sample points bit for bit: the untangling's speed-ups
    // (docs/remesh.md §3.3) kept its output bytes, and this keeps them kept. It depends only on
    // IEEE double arithmetic (no FMA contraction) and libm; update it only with a deliberate
    // change of the sphere map, the sampling or the untangling, and say so in CHANGELOG.md.
    std::uint64_t h = 0xcbf29ce484222325ULL;
    for (std::size_t k = 0; k < 3; ++k)
    {
        h = core::hash_span(std::span<const double>((*pos)[k].padded()), h);
        h = core::hash_span(std::span<const double>(points[k].padded()), h);
    }
    std::printf("fox.ply level 6: untangled hash 0x%016llx\n", static_cast<unsigned long long>(h));
    EXPECT_EQ(h, k_fox6_golden);
    EXPECT_LT(st.folded_sampled, 130U);
    EXPECT_LT(st.intersections_sampled, 240U);
    // recounted from the returned fields
    const mesh::TriMesh out = grid_surface(grid, *pos);
    EXPECT_EQ(count_self_intersections(out), 0U);
    const auto faces = locate_samples(grid, points, m, map->points);
    const std::size_t folded = count_folded(out, m, faces);
    EXPECT_EQ(folded, st.folded);
    EXPECT_LE(folded * 5, st.folded_sampled);
    // the patch passes keep twins equal and every node on its input face
    for (const core::TwinPair& t : grid.twins())
        for (std::size_t k = 0; k < 3; ++k)
        {
            ASSERT_EQ((*pos)[k][t.twin], (*pos)[k][t.canonical]);
            ASSERT_EQ(points[k][t.twin], points[k][t.canonical]);
        }
    double worst = 0.0;
    for (std::size_t u = 0; u < out.positions.size(); ++u)
    {
        const auto& f = m.faces[faces[u]];
        const Vec3 n = core::normalized(core::cross(m.positions[f[1]] - m.positions[f[0]],
                                                    m.positions[f[2]] - m.positions[f[0]]));
        worst = std::max(worst, std::abs(core::dot(out.positions[u] - m.positions[f[0]], n)));
    }
    EXPECT_LT(worst, 1e-9 * core::norm(m.positions[0]) + 1e-12);

    // without the barrier descent the compass search alone leaves more
    pos = sample_surface(grid, domain, m, map->points);
    ASSERT_TRUE(pos);
    points = domain;
    UntangleSettings no_barrier;
    no_barrier.barrier_epsilon = 0.0;
    no_barrier.patch_passes = 0;
    const UntangleStats plain_st =
        untangle_samples(grid, m, map->points, points, *pos, no_barrier).value();
    std::printf("fox.ply level 6 without the barrier descent: %zu folded\n", plain_st.folded);
    EXPECT_LT(folded, plain_st.folded);

    // without the patch passes (the rounds' one-node moves only) more are left, and the passes
    // that were kept moved no node off its input face
    pos = sample_surface(grid, domain, m, map->points);
    ASSERT_TRUE(pos);
    points = domain;
    UntangleSettings no_patch;
    no_patch.patch_passes = 0;
    const UntangleStats rounds_st =
        untangle_samples(grid, m, map->points, points, *pos, no_patch).value();
    std::printf("fox.ply level 6 without the patch passes: %zu folded, %zu pairs\n",
                rounds_st.folded, rounds_st.intersections);
    EXPECT_EQ(rounds_st.patch_passes, 0);
    EXPECT_GE(st.patch_passes, 1);
    EXPECT_LT(folded, rounds_st.folded);
    EXPECT_EQ(rounds_st.intersections, 0U);

    // the kink term is what removes most of them: the same split mesh mapped without it
    SphereMapSettings no_kink;
    no_kink.kink_weight = 0.0;
    auto plain = map_to_sphere(m, no_kink);
    ASSERT_TRUE(plain) << plain.error().message;
    auto plain_pos = sample_surface(grid, domain, m, plain->points);
    ASSERT_TRUE(plain_pos);
    const std::size_t plain_folded = count_folded(grid_surface(grid, *plain_pos), m,
                                                  locate_samples(grid, domain, m, plain->points));
    std::printf("fox.ply level 6 without the kink term: sampled %zu folded\n", plain_folded);
    EXPECT_LE(2 * st.folded_sampled, plain_folded);
}

}  // namespace
}  // namespace pliant::remesh
