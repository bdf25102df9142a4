// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// The remesher against invariants and independent references: fold counts recomputed here,
// output topology checked by mesh::validate, distances against analytic bounds, bit-exact
// grid files, and the PSNR bounds on the committed real meshes.

#include <pliant/core/grid_io.h>
#include <pliant/core/sphere_domain.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/remesh/intersections.h>
#include <pliant/remesh/remesh.h>
#include <pliant/remesh/sample.h>
#include <pliant/remesh/sphere_map.h>

#include <gtest/gtest.h>
#include <omp.h>

#include "remesh/progressive_mesh.h"
#include "shapes.h"
#include "support/fp_traps.h"
#include "support/test_paths.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace pliant::remesh
{
namespace
{

using core::Vec3;

mesh::TriMesh load(const std::string& name)
{
    const test::FpTrapsOff off;  // Assimp computes with inf/NaN internally
    auto r = mesh::import_mesh(test::source_dir() / "tests" / "data" / "meshes" / name);
    EXPECT_TRUE(r) << (r ? "" : r.error().message);
    return r ? *r : mesh::TriMesh{};
}

RemeshSettings rs(int level, bool measure = false, std::size_t samples = 0)
{
    RemeshSettings s;
    s.level = level;
    s.measure = measure;
    s.distance.samples = samples;
    return s;
}

SphereMapSettings sm(SphereMethod method)
{
    SphereMapSettings s;
    s.method = method;
    return s;
}

DistanceSettings ds(std::size_t samples)
{
    DistanceSettings s;
    s.samples = samples;
    return s;
}

/// Solid angle of the spherical triangle abc (Van Oosterom & Strackee), signed.
double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c)
{
    const double num = core::dot(a, core::cross(b, c));
    const double den = 1.0 + core::dot(a, b) + core::dot(b, c) + core::dot(c, a);
    return 2.0 * std::atan2(num, den);
}

// ---------------------------------------------------------------------------------------------
// progressive mesh

TEST(ProgressiveMesh, ReachesATetrahedronAndUndoesExactly)
{
    const mesh::TriMesh m = scenes::icosphere(3);
    core::NullProgress np;
    auto pm = detail::build_progressive_mesh(m, np);
    ASSERT_TRUE(pm) << pm.error().message;
    EXPECT_EQ(pm->collapses.size(), m.positions.size() - 4);
    std::size_t alive = 0;
    for (std::size_t f = 0; f < pm->coarse_faces.size(); ++f)
        if (pm->coarse_alive[f])
        {
            ++alive;
            for (const std::uint32_t v : pm->coarse_faces[f])
                EXPECT_TRUE(std::find(pm->base_vertices.begin(), pm->base_vertices.end(), v) !=
                            pm->base_vertices.end());
        }
    EXPECT_EQ(alive, 4U);
    // undo every collapse: the input faces come back exactly
    std::vector<mesh::Face> faces = pm->coarse_faces;
    for (std::size_t k = pm->collapses.size(); k-- > 0;)
    {
        const auto& c = pm->collapses[k];
        for (std::uint32_t j = 0; j < c.modified_count; ++j)
            for (auto& w : faces[pm->modified_faces[c.first_modified + j]])
                if (w == c.kept)
                    w = c.removed;
    }
    EXPECT_EQ(faces, m.faces);
}

TEST(ProgressiveMesh, RefusesATorus)
{
    core::NullProgress np;
    auto pm = detail::build_progressive_mesh(scenes::torus(), np);
    ASSERT_FALSE(pm);
    EXPECT_EQ(pm.error().code, core::ErrorCode::NotConverged);
}

// ---------------------------------------------------------------------------------------------
// sphere map

TEST(SphereMap, FoldCounterSeesAFlippedFace)
{
    mesh::TriMesh m = scenes::octahedron();
    std::vector<Vec3> q;
    for (const Vec3& p : m.positions)
        q.push_back(core::normalized(p));
    EXPECT_EQ(count_inverted(m.faces, q), 0U);
    std::swap(m.faces[0][1], m.faces[0][2]);
    EXPECT_EQ(count_inverted(m.faces, q), 1U);
}

void expect_bijective(const mesh::TriMesh& m, const SphereMap& map)
{
    EXPECT_EQ(count_inverted(m.faces, map.points), 0U);
    double total = 0.0;
    for (const auto& f : m.faces)
        total += solid_angle(map.points[f[0]], map.points[f[1]], map.points[f[2]]);
    // all faces positive and covering the sphere once: degree 1, so a bijection
    EXPECT_NEAR(total, 4.0 * 3.14159265358979323846, 1e-6);
    for (const Vec3& p : map.points)
        EXPECT_NEAR(core::norm(p), 1.0, 1e-12);
}

TEST(SphereMap, EveryMethodIsFoldFreeOnADumbbell)
{
    // not star-shaped: central projection folds the neck
    const mesh::TriMesh m = scenes::dumbbell();
    for (const SphereMethod method : {SphereMethod::Auto, SphereMethod::CoarseToFine})
    {
        auto map = map_to_sphere(m, sm(method));
        ASSERT_TRUE(map) << map.error().message;
        expect_bijective(m, *map);
    }
}

TEST(SphereMap, SpringEmbedderNeverReturnsFolds)
{
    // fox folds 27 % under central projection; the spring embedder alone either unfolds it or
    // fails loudly with the count, never returns a folded map
    const mesh::TriMesh m = load("fox.ply");
    auto map = map_to_sphere(m, sm(SphereMethod::SpringEmbedder));
    if (map)
        expect_bijective(m, *map);
    else
    {
        EXPECT_EQ(map.error().code, core::ErrorCode::InvertedTriangles);
        EXPECT_NE(map.error().message.find("inverted"), std::string::npos);
    }
}

// The split surface is the input's: same area and volume, closed and manifold, four faces per
// face, each new face inside the plane of the face it came from; the original vertices keep
// their indices and positions.
TEST(SplitForMap, SameSurfaceFourTimesTheFaces)
{
    const mesh::TriMesh m = load("fox.ply");
    const mesh::TriMesh s = split_for_map(m, 2000);
    ASSERT_EQ(s.faces.size(), 4 * m.faces.size());  // 622 -> 2488
    ASSERT_TRUE(mesh::validate(s, "split"));
    EXPECT_EQ(s.positions.size(), m.positions.size() + 3 * m.faces.size() / 2);
    for (std::size_t v = 0; v < m.positions.size(); ++v)
        ASSERT_TRUE(s.positions[v].x == m.positions[v].x && s.positions[v].y == m.positions[v].y &&
                    s.positions[v].z == m.positions[v].z);
    const auto area = [](const mesh::TriMesh& x)
    {
        double a = 0.0;
        for (const auto& f : x.faces)
            a += 0.5 * core::norm(core::cross(x.positions[f[1]] - x.positions[f[0]],
                                              x.positions[f[2]] - x.positions[f[0]]));
        return a;
    };
    EXPECT_NEAR(area(s), area(m), 1e-12 * area(m));
    EXPECT_NEAR(signed_volume(s), signed_volume(m), 1e-12 * std::abs(signed_volume(m)));
    double worst = 0.0;
    for (std::size_t f = 0; f < m.faces.size(); ++f)
    {
        const auto& t = m.faces[f];
        const Vec3 n = core::normalized(core::cross(m.positions[t[1]] - m.positions[t[0]],
                                                    m.positions[t[2]] - m.positions[t[0]]));
        for (std::size_t k = 0; k < 4; ++k)
            for (const std::uint32_t v : s.faces[4 * f + k])
                worst = std::max(worst, std::abs(core::dot(s.positions[v] - m.positions[t[0]], n)));
    }
    EXPECT_LT(worst, 1e-12 * core::norm(m.positions[0]) + 1e-12);
    // enough faces already: unchanged
    EXPECT_EQ(split_for_map(m, 600).faces, m.faces);
}

TEST(SphereMap, RefusesInwardFaces)
{
    mesh::TriMesh m = scenes::icosphere(1);
    for (auto& f : m.faces)
        std::swap(f[1], f[2]);
    auto map = map_to_sphere(m);
    ASSERT_FALSE(map);
    EXPECT_EQ(map.error().code, core::ErrorCode::InvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// domain map

TEST(DomainSphere, FoldFreeUnitTwinConsistentCoveringOnce)
{
    for (int level = 1; level <= 8; ++level)
    {
        const auto grid = *core::TetraGrid::create(level);
        const auto d = domain_sphere(grid);
        EXPECT_EQ(count_inverted_domain(grid, d), 0U) << level;
        for (const auto& f : d)
            EXPECT_EQ(core::max_twin_mismatch(grid, f), 0.0);
        const auto nodes = grid.node_of_unique();
        double total = 0.0;
        for (const auto& t : grid.triangles())
        {
            std::array<Vec3, 3> p;
            for (std::size_t k = 0; k < 3; ++k)
                p[k] = {d[0][nodes[t[k]]], d[1][nodes[t[k]]], d[2][nodes[t[k]]]};
            total += solid_angle(p[0], p[1], p[2]);
            EXPECT_NEAR(core::norm(p[0]), 1.0, 1e-14);
        }
        EXPECT_NEAR(total, 4.0 * 3.14159265358979323846, 1e-9) << level;
        // the corners sit on a regular tetrahedron: pairwise dot products -1/3
        const auto c = grid.corners();
        for (std::size_t i = 0; i < 4; ++i)
            for (std::size_t j = i + 1; j < 4; ++j)
            {
                const Vec3 a{d[0][c[i]], d[1][c[i]], d[2][c[i]]};
                const Vec3 b{d[0][c[j]], d[1][c[j]], d[2][c[j]]};
                EXPECT_NEAR(core::dot(a, b), -1.0 / 3.0, 1e-14);
            }
    }
}

// ---------------------------------------------------------------------------------------------
// whole pipeline on synthetic shapes

/// The remeshing of a convex shape around the origin (the icosphere, the ellipsoid): a closed
/// manifold of the grid's counts, twins equal, and no fold or self-intersection, recounted here
/// rather than taken from the report (remesh() refuses a result whose report counts any): on a
/// convex surface around the origin every face of an unfolded outward output faces away from
/// it, so a fold is a face whose normal points at the origin; intersections by the library's
/// count, which tests/remesh/intersections_test.cpp checks against brute force.
void expect_valid_output(const RemeshResult& r)
{
    const std::size_t w = static_cast<std::size_t>(r.grid.w());
    const mesh::TriMesh out = grid_surface(r.grid, r.positions);
    EXPECT_EQ(out.positions.size(), 2 * w * w + 2);
    EXPECT_EQ(out.faces.size(), 4 * w * w);
    const auto ok = mesh::validate(out, "remeshed");
    EXPECT_TRUE(ok) << (ok ? "" : ok.error().message);
    for (const auto& f : r.positions)
        EXPECT_EQ(core::max_twin_mismatch(r.grid, f), 0.0);
    std::size_t facing_in = 0;
    for (const auto& f : out.faces)
    {
        const Vec3 a = out.positions[f[0]];
        const Vec3 n = core::cross(out.positions[f[1]] - a, out.positions[f[2]] - a);
        const Vec3 centroid = (a + out.positions[f[1]] + out.positions[f[2]]) / 3.0;
        if (!(core::dot(n, centroid) > 0.0))
            ++facing_in;
    }
    EXPECT_EQ(facing_in, 0U) << "faces folded towards the origin";
    EXPECT_EQ(count_self_intersections(out), 0U);
}

/// Distance from p to the plane of triangle abc when p's projection falls inside the triangle
/// (barycentric coordinates from signed areas, each >= -1e-9), else infinity: whether p lies on
/// that face, written independently of the library's closest-point code.
double distance_on_face(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
    const Vec3 n = core::cross(b - a, c - a);
    const double n2 = core::dot(n, n);
    const double u = core::dot(core::cross(c - b, p - b), n) / n2;
    const double v = core::dot(core::cross(a - c, p - c), n) / n2;
    const double w = core::dot(core::cross(b - a, p - a), n) / n2;
    if (u < -1e-9 || v < -1e-9 || w < -1e-9)
        return std::numeric_limits<double>::infinity();
    return std::abs(core::dot(n, p - a)) / std::sqrt(n2);
}

TEST(Remesh, IcosphereNodesLieOnTheSphereUpToTheChordBound)
{
    // The icosphere's vertices are on the unit sphere and its faces are chords: every sampled
    // node lies on a face, so 1 - sagitta_max <= |p| <= 1 (to rounding). With 20480 faces the
    // bound is 2.8e-4; the exact statements are the chord bound and "on the input surface"
    // (checked below to 1e-12), not a fixed 1e-6 from the sphere, which would need an icosphere
    // of about five million faces.
    const mesh::TriMesh m = scenes::icosphere(5);
    double min_plane = 1.0;
    for (const auto& f : m.faces)
    {
        const Vec3 n = core::normalized(core::cross(m.positions[f[1]] - m.positions[f[0]],
                                                    m.positions[f[2]] - m.positions[f[0]]));
        min_plane = std::min(min_plane, std::abs(core::dot(n, m.positions[f[0]])));
    }
    auto r = remesh(m, rs(6));
    ASSERT_TRUE(r) << r.error().message;
    expect_valid_output(*r);
    double lo = 2.0, hi = 0.0;
    for (int y = 0; y < r->grid.ny(); ++y)
        for (int x = 0; x < r->grid.nx(); ++x)
        {
            const double n = core::norm(
                Vec3{r->positions[0].at(x, y), r->positions[1].at(x, y), r->positions[2].at(x, y)});
            lo = std::min(lo, n);
            hi = std::max(hi, n);
        }
    EXPECT_LE(hi, 1.0 + 1e-12);
    EXPECT_GE(lo, min_plane - 1e-12);
    EXPECT_LT(1.0 - min_plane, 5e-4);
    // Every node is a barycentric sample of an input face, so it lies on the input surface: on
    // some face near it (faces sorted by centroid x, those within reach tested), its distance
    // to that face's plane is rounding only.
    std::vector<std::pair<double, std::size_t>> by_x;
    for (std::size_t i = 0; i < m.faces.size(); ++i)
    {
        const auto& f = m.faces[i];
        by_x.emplace_back((m.positions[f[0]].x + m.positions[f[1]].x + m.positions[f[2]].x) / 3.0,
                          i);
    }
    std::sort(by_x.begin(), by_x.end());
    constexpr double k_reach = 0.1;  // > the icosphere's longest edge, 0.04
    double off_surface = 0.0;
    for (int y = 0; y < r->grid.ny(); ++y)
        for (int x = 0; x < r->grid.nx(); ++x)
        {
            const Vec3 p{r->positions[0].at(x, y), r->positions[1].at(x, y),
                         r->positions[2].at(x, y)};
            double nearest = 1e300;
            auto it = std::lower_bound(by_x.begin(), by_x.end(),
                                       std::pair{p.x - k_reach, std::size_t{0}});
            for (; it != by_x.end() && it->first <= p.x + k_reach; ++it)
            {
                const auto& f = m.faces[it->second];
                nearest = std::min(nearest, distance_on_face(p, m.positions[f[0]],
                                                             m.positions[f[1]], m.positions[f[2]]));
            }
            off_surface = std::max(off_surface, nearest);
        }
    EXPECT_LE(off_surface, 1e-12);
}

TEST(Remesh, ResamplingAGridIsNearIdentity)
{
    const mesh::TriMesh m = scenes::ellipsoid();
    auto first = remesh(m, rs(5));
    ASSERT_TRUE(first) << first.error().message;
    const mesh::TriMesh g = grid_surface(first->grid, first->positions);
    auto second = remesh(g, rs(5));
    ASSERT_TRUE(second) << second.error().message;
    expect_valid_output(*second);
    const mesh::TriMesh g2 = grid_surface(second->grid, second->positions);
    const SurfaceDistance d = surface_distance(g, g2, ds(20'000));
    // re-sampling a surface at the same density loses little: far below the level-5 error of
    // the first remesh against the ellipsoid itself
    const SurfaceDistance d0 = surface_distance(m, g, ds(20'000));
    EXPECT_LT(d.rms_relative, 2e-3);
    EXPECT_LT(d.rms, 2.0 * d0.rms + 1e-12);
}

TEST(Remesh, InwardFacingInputIsReoriented)
{
    mesh::TriMesh m = scenes::ellipsoid();
    for (auto& f : m.faces)
        std::swap(f[1], f[2]);
    auto r = remesh(m, rs(4));
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_TRUE(r->report.input_flipped);
    expect_valid_output(*r);
    // The printed summary says so too (only the JSON did).
    EXPECT_NE(to_text(r->report).find("input: its faces face inward"), std::string::npos);
    auto outward = remesh(scenes::ellipsoid(), rs(4));
    ASSERT_TRUE(outward) << outward.error().message;
    EXPECT_EQ(to_text(outward->report).find("face inward"), std::string::npos);
}

TEST(Remesh, RefusesABadLevelAndATorus)
{
    auto bad = remesh(scenes::icosphere(1), rs(11));
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, core::ErrorCode::InvalidArgument);
    auto torus = remesh(scenes::torus(), rs(4));
    EXPECT_FALSE(torus);
}

TEST(Remesh, NativeGridRoundTripsBitForBit)
{
    auto r = remesh(scenes::dumbbell(), rs(5));
    ASSERT_TRUE(r) << r.error().message;
    const auto path = test::scratch_dir("remesh_roundtrip") / "dumbbell.pgrid";
    ASSERT_TRUE(core::save_grid(path, core::make_geometry_file(r->grid, r->positions)));
    auto file = core::load_grid(path);
    ASSERT_TRUE(file) << file.error().message;
    auto back = core::geometry_of(r->grid, *file);
    ASSERT_TRUE(back) << back.error().message;
    for (std::size_t c = 0; c < 3; ++c)
    {
        const auto a = r->positions[c].padded();
        const auto b = (*back)[c].padded();
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
    }
}

TEST(Remesh, NegativeMeshesAreRefusedByValidation)
{
    for (const char* name :
         {"negative/bob_small_genus1.ply", "negative/hourglass_ico_nonmanifold_vertex.obj",
          "negative/stanford-bunny_open.obj",
          "negative/two_cubes_shared_edge_nonmanifold_edge.obj"})
    {
        const mesh::TriMesh m = load(name);
        EXPECT_FALSE(mesh::validate(m, name)) << name;
    }
}

TEST(Remesh, JsonReportHasTheMeasuredKeys)
{
    auto r = remesh(scenes::ellipsoid(), rs(4, true, 2000));
    ASSERT_TRUE(r) << r.error().message;
    const std::string j = to_json(r->report);
    for (const char* key :
         {"\"psnr_db\"", "\"rms_relative\"", "\"hausdorff_relative\"", "\"l2_stretch_efficiency\"",
          "\"area_cv\"", "\"inverted_mesh_triangles\": 0", "\"inverted_domain_triangles\": 0",
          "\"phase_seconds\""})
        EXPECT_NE(j.find(key), std::string::npos) << key;
    EXPECT_GT(r->report.distance.psnr_db, 30.0);
}

// ---------------------------------------------------------------------------------------------
// real meshes: the checks. One sphere map per mesh, sampled at every level.

struct MeshCase
{
    const char* file;
    double bound_db;  ///< issue 3: mean of the reference pair minus 3 dB, at level 7
    int max_level;    ///< the issue asks for levels 5..8
};

// Test names show the file (gtest would print the struct's bytes, a pointer among them).
void PrintTo(const MeshCase& c, std::ostream* os)
{
    *os << c.file;
}

class RealMesh : public ::testing::TestWithParam<MeshCase>
{
};

// The remesher's result does not depend on the thread count (docs/remesh.md): fox, which takes
// the split, the spring route and the untangling, remeshed at level 5 on one OpenMP thread and on
// two gives the same positions bit for bit and the same report (the PSNR to its last bits, below).
TEST(RemeshDeterminism, FoxLevel5SameBytesOnOneAndTwoThreads)
{
    const mesh::TriMesh m = load("fox.ply");
    RemeshSettings settings;
    settings.level = 5;
    const int before = omp_get_max_threads();
    omp_set_num_threads(1);
    auto one = remesh(m, settings);
    omp_set_num_threads(2);
    auto two = remesh(m, settings);
    omp_set_num_threads(before);
    ASSERT_TRUE(one) << one.error().message;
    ASSERT_TRUE(two) << two.error().message;
    for (std::size_t c = 0; c < 3; ++c)
    {
        const auto a = one->positions[c].padded();
        const auto b = two->positions[c].padded();
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size_bytes()), 0) << "plane " << c;
    }
    const QualityReport& a = one->report;
    const QualityReport& b = two->report;
    EXPECT_EQ(a.untangle.folded_sampled, b.untangle.folded_sampled);
    EXPECT_EQ(a.untangle.intersections_sampled, b.untangle.intersections_sampled);
    EXPECT_EQ(a.untangle.moved_nodes, b.untangle.moved_nodes);
    EXPECT_EQ(a.untangle.rounds, b.untangle.rounds);
    EXPECT_EQ(a.rms_stretch, b.rms_stretch);
    // The measure's sum of squared distances is reduced per thread: its last bits move with the
    // thread count (the maximum does not).
    EXPECT_NEAR(a.distance.psnr_db, b.distance.psnr_db, 1e-9);
    EXPECT_EQ(a.distance.hausdorff, b.distance.hausdorff);
}

TEST_P(RealMesh, FoldFreeClosedGenusZeroAndPsnrRisesWithLevel)
{
    const MeshCase c = GetParam();
    const mesh::TriMesh m = load(c.file);
    ASSERT_TRUE(mesh::validate(m, c.file));
    auto map = map_to_sphere(m);
    ASSERT_TRUE(map) << map.error().message;
    expect_bijective(m, *map);
    double previous = 0.0;
    for (int level = 5; level <= c.max_level; ++level)
    {
        const auto grid = *core::TetraGrid::create(level);
        // the domain map `pliant remesh` uses by default
        const auto dom = core::sphere_domain(grid, core::SphereMap::EqualArea);
        ASSERT_EQ(count_inverted_domain(grid, dom), 0U);
        auto pos = sample_surface(grid, dom, m, map->points);
        ASSERT_TRUE(pos);
        const mesh::TriMesh out = grid_surface(grid, *pos);
        const auto w = static_cast<std::size_t>(grid.w());
        EXPECT_EQ(out.positions.size(), 2 * w * w + 2);
        const auto ok = mesh::validate(out, "remeshed");
        EXPECT_TRUE(ok) << (ok ? "" : ok.error().message);
        const SurfaceDistance d = surface_distance(m, out, ds(30'000));
        std::printf("%s level %d: PSNR %.2f dB, RMS %.4g%%, Hausdorff %.3g%%\n", c.file, level,
                    d.psnr_db, 100.0 * d.rms_relative, 100.0 * d.hausdorff_relative);
        if (level > 5)
        {
            EXPECT_GT(d.psnr_db, previous + 2.0) << "level " << level;
        }
        if (level == 7)
        {
            EXPECT_GE(d.psnr_db, c.bound_db);
        }
        previous = d.psnr_db;
    }
}

// The equal-area domain map (the default) against the gnomonic one on the same sphere map: the
// samples spread more evenly over every real mesh (triangle-area cv at least a fifth lower) and
// lie closer to it (PSNR not lower; docs/remesh.md §2 has the level-7 figures, +0.2 to +3.0 dB).
TEST_P(RealMesh, EqualAreaDomainSpreadsTheSamplesMoreEvenly)
{
    const MeshCase c = GetParam();
    const mesh::TriMesh m = load(c.file);
    auto map = map_to_sphere(m);
    ASSERT_TRUE(map) << map.error().message;
    const auto grid = *core::TetraGrid::create(6);
    double cv[2] = {};
    double psnr[2] = {};
    const core::SphereMap maps[2] = {core::SphereMap::Gnomonic, core::SphereMap::EqualArea};
    for (int k = 0; k < 2; ++k)
    {
        const auto dom = core::sphere_domain(grid, maps[k]);
        ASSERT_EQ(count_inverted_domain(grid, dom), 0U);
        auto pos = sample_surface(grid, dom, m, map->points);
        ASSERT_TRUE(pos);
        const mesh::TriMesh out = grid_surface(grid, *pos);
        cv[k] = area_spread(out).cv;
        psnr[k] = surface_distance(m, out, ds(30'000)).psnr_db;
        std::printf("%s level 6, %s domain: area cv %.3f, PSNR %.2f dB\n", c.file,
                    std::string(core::to_string(maps[k])).c_str(), cv[k], psnr[k]);
    }
    EXPECT_LT(cv[1], 0.8 * cv[0]);
    EXPECT_GE(psnr[1], psnr[0]);
}

INSTANTIATE_TEST_SUITE_P(Meshes, RealMesh,
                         ::testing::Values(MeshCase{"spot_triangulated.obj", 71.45, 8},
                                           MeshCase{"cube_minus_sphere.obj", 73.1, 8},
                                           MeshCase{"blub_triangulated.obj", 71.95, 8},
                                           MeshCase{"cactus.off", 71.65, 8},
                                           MeshCase{"fox.ply", 66.8, 8}),
                         [](const auto& param_info)
                         {
                             std::string n = param_info.param.file;
                             return n.substr(0, n.find_first_of("_."));
                         });

}  // namespace
}  // namespace pliant::remesh
