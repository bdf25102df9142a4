// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The GPU re-meshing look-up (render::sample_on_gpu) against two independent references:
// - closed form: an ellipsoid whose sphere map is its icosphere before scaling, and an
//   octahedron (large triangles that cross the views' near plane): the exact sample of node p
//   lies on p's ray through the chord polyhedron, so diag(1/a, 1/b, 1/c)·sample must be parallel
//   to p and on the icosphere's chord surface (octahedron: |x| + |y| + |z| = 1);
// - the CPU sampler (remesh::sample_surface) on a real mesh (spot) with its real sphere map,
//   levels 4-6: the two must agree within k_tolerance of the bounding-box diagonal.
// Also: every node gets a sample and twins are equal; a hole (a missing triangle) is reported
// as an error, never left as zero; a domain map other than the tetrahedron's is refused by the
// colour look-up; the remesh() sampler hook runs the GPU sampler and the report says so.
// GPU point location (render::locate_on_gpu) on both domain maps: the triangle it reads under
// each node contains the node's sphere point (checked with the edge functions here, in double),
// and remesh::sample_surface started from those triangles gives the CPU sampler's positions.

#include <pliant/core/sphere_domain.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/remesh/remesh.h>
#include <pliant/remesh/sample.h>
#include <pliant/remesh/sphere_map.h>
#include <pliant/render/gpu_sampler.h>

#include "gl_fixture.h"
#include "shapes.h"
#include "support/test_paths.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace pliant::test
{
namespace
{

using core::Vec3;

/// Documented tolerances (docs/remesh.md, "GPU sampling"): max |p_gpu − p_cpu| relative to the
/// input's bounding-box diagonal. With the automatic pixels per cell (views of ~1025 px) spot
/// measured up to 1.6e-7 at levels 4-6 (float32's floor); with one pixel per cell up to 1.4e-5
/// (the rasteriser's sub-pixel snapping times the local stretch of the sphere map, so it moves
/// with the map: 6.4e-6 before the peak-stretch term of docs/remesh.md §1.2). Meshes whose
/// sphere map compresses the surface more (fox, cactus) reach a few 1e-6 with the automatic
/// setting.
constexpr double k_tolerance = 1e-6;
constexpr double k_tolerance_one_pixel = 3e-5;
constexpr double k_tolerance_any_mesh = 1e-5;

Vec3 at(const core::Vec3Field<double>& f, core::NodeIndex n)
{
    return {f[0][n], f[1][n], f[2][n]};
}

double diagonal(const mesh::TriMesh& m)
{
    Vec3 lo = m.positions[0], hi = m.positions[0];
    for (const Vec3& p : m.positions)
    {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    return core::norm(hi - lo);
}

std::vector<Vec3> unit_points(const mesh::TriMesh& m)
{
    std::vector<Vec3> s;
    for (const Vec3& p : m.positions)
        s.push_back(core::normalized(p));
    return s;
}

/// Twins bit-identical to their canonical node.
void expect_twins_equal(const core::TetraGrid& grid, const core::Vec3Field<double>& f)
{
    for (const core::TwinPair& t : grid.twins())
        for (int c = 0; c < 3; ++c)
            ASSERT_EQ(f[c][t.twin], f[c][t.canonical]);
}

double max_difference(const core::TetraGrid& grid, const core::Vec3Field<double>& a,
                      const core::Vec3Field<double>& b)
{
    double worst = 0.0;
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const core::NodeIndex n = grid.index(x, y);
            worst = std::max(worst, core::norm(at(a, n) - at(b, n)));
        }
    return worst;
}

class GpuSamplerTest : public GlTest
{
};

TEST_F(GpuSamplerTest, EllipsoidSamplesLieOnTheirRaysAndOnTheSurface)
{
    const double a = 2.0, b = 1.0, c = 0.5;
    const mesh::TriMesh ball = scenes::icosphere(3);
    const mesh::TriMesh shape = scenes::ellipsoid(a, b, c, 3);
    ASSERT_EQ(ball.faces, shape.faces);
    const std::vector<Vec3> sphere = unit_points(ball);
    // the chord surface lies between the smallest face-plane distance and the unit sphere
    double r_in = 1.0;
    for (const auto& f : ball.faces)
    {
        const Vec3 n =
            core::normalized(core::cross(sphere[f[1]] - sphere[f[0]], sphere[f[2]] - sphere[f[0]]));
        r_in = std::min(r_in, core::dot(n, sphere[f[0]]));
    }
    for (const int level : {4, 6})
    {
        auto grid = core::TetraGrid::create(level);
        ASSERT_TRUE(grid);
        const auto domain = remesh::domain_sphere(*grid);
        render::GpuSampleStats stats;
        auto gpu =
            render::sample_on_gpu(*grid, domain, sphere, shape.positions, shape.faces, {}, &stats);
        ASSERT_TRUE(gpu) << gpu.error().message;
        EXPECT_EQ(stats.views, 4);
        EXPECT_EQ(stats.overlaps, 0U);
        EXPECT_EQ(stats.samples, grid->unique_count());
        expect_twins_equal(*grid, *gpu);
        double worst_ray = 0.0, worst_radius = 0.0;
        for (int y = 0; y < grid->ny(); ++y)
            for (int x = 0; x < grid->nx(); ++x)
            {
                const core::NodeIndex n = grid->index(x, y);
                const Vec3 s = at(*gpu, n);
                const Vec3 q{s.x / a, s.y / b, s.z / c};
                const Vec3 p = at(domain, n);
                worst_ray = std::max(worst_ray, core::norm(core::cross(q, p)));
                const double r = core::norm(q);
                worst_radius =
                    std::max({worst_radius, r - 1.0, r_in - r, core::dot(q, p) < 0.0 ? 1.0 : 0.0});
            }
        std::printf("level %d: off-ray %.3g, off-shell %.3g (k = %d, %d px views)\n", level,
                    worst_ray, worst_radius, stats.pixels_per_cell, stats.viewport);
        // float32: clip coordinates and colours carry 24-bit mantissas (~6e-8 relative); measured
        // 3e-7 off the ray and 1.2e-7 off the shell on llvmpipe
        EXPECT_LT(worst_ray, 2e-6) << "level " << level;
        EXPECT_LT(worst_radius, 1e-6) << "level " << level;
    }
}

TEST_F(GpuSamplerTest, OctahedronWithTrianglesCrossingTheNearPlane)
{
    const mesh::TriMesh octa = scenes::octahedron();
    const std::vector<Vec3> sphere = unit_points(octa);
    auto grid = core::TetraGrid::create(5);
    ASSERT_TRUE(grid);
    const auto domain = remesh::domain_sphere(*grid);
    render::GpuSampleStats stats;
    auto gpu = render::sample_on_gpu(*grid, domain, sphere, octa.positions, octa.faces, {}, &stats);
    ASSERT_TRUE(gpu) << gpu.error().message;
    EXPECT_EQ(stats.overlaps, 0U);
    auto cpu = remesh::sample_surface(*grid, domain, octa, sphere);
    ASSERT_TRUE(cpu);
    double worst = 0.0;
    for (int y = 0; y < grid->ny(); ++y)
        for (int x = 0; x < grid->nx(); ++x)
        {
            const core::NodeIndex n = grid->index(x, y);
            const Vec3 s = at(*gpu, n);
            // on the octahedron |x| + |y| + |z| = 1, and on the node's ray
            worst = std::max({worst, std::abs(std::abs(s.x) + std::abs(s.y) + std::abs(s.z) - 1.0),
                              core::norm(core::cross(s, at(domain, n)))});
        }
    EXPECT_LT(worst, 1e-5);
    EXPECT_LT(max_difference(*grid, *gpu, *cpu), k_tolerance * diagonal(octa));
}

TEST_F(GpuSamplerTest, SpotMatchesTheCpuSamplerAtLevels4To6)
{
    auto m =
        mesh::import_mesh(source_dir() / "tests" / "data" / "meshes" / "spot_triangulated.obj");
    ASSERT_TRUE(m) << m.error().message;
    ASSERT_TRUE(mesh::validate(*m, "spot"));
    ASSERT_GT(remesh::signed_volume(*m), 0.0);
    auto map = remesh::map_to_sphere(*m);
    ASSERT_TRUE(map) << map.error().message;
    const double diag = diagonal(*m);
    for (const int level : {4, 5, 6})
    {
        auto grid = core::TetraGrid::create(level);
        ASSERT_TRUE(grid);
        const auto domain = remesh::domain_sphere(*grid);
        auto cpu = remesh::sample_surface(*grid, domain, *m, map->points);
        ASSERT_TRUE(cpu);
        for (const int k : {1, 0})
        {
            render::GpuSamplerSettings settings;
            settings.pixels_per_cell = k;
            render::GpuSampleStats stats;
            auto gpu = render::sample_on_gpu(*grid, domain, map->points, m->positions, m->faces,
                                             settings, &stats);
            ASSERT_TRUE(gpu) << gpu.error().message;
            EXPECT_EQ(stats.overlaps, 0U);
            EXPECT_EQ(stats.samples, grid->unique_count());
            expect_twins_equal(*grid, *gpu);
            const double rel = max_difference(*grid, *gpu, *cpu) / diag;
            std::printf("spot level %d, %d px per cell: max |gpu - cpu| = %.3g of the diagonal\n",
                        level, stats.pixels_per_cell, rel);
            EXPECT_LT(rel, k == 1 ? k_tolerance_one_pixel : k_tolerance)
                << "level " << level << ", k " << stats.pixels_per_cell;
        }
    }
}

/// Canonical nodes whose sphere point lies in face `faces[n]` of the chord mesh (all three edge
/// functions p·(b×c) >= -1e-14, the CPU sampler's rule).
std::size_t nodes_inside(const core::TetraGrid& grid, const core::Vec3Field<double>& domain,
                         const mesh::TriMesh& m, std::span<const Vec3> sphere,
                         const std::vector<std::uint32_t>& faces)
{
    std::size_t inside = 0;
    for (const core::NodeIndex n : grid.node_of_unique())
    {
        const Vec3 p = at(domain, n);
        const auto& f = m.faces[faces[n.value]];
        const Vec3 &a = sphere[f[0]], &b = sphere[f[1]], &c = sphere[f[2]];
        if (core::dot(p, core::cross(b, c)) >= -1e-14 &&
            core::dot(p, core::cross(c, a)) >= -1e-14 && core::dot(p, core::cross(a, b)) >= -1e-14)
            ++inside;
    }
    return inside;
}

TEST_F(GpuSamplerTest, GpuLocationOnEitherDomainMapGivesTheCpuSamples)
{
    auto m =
        mesh::import_mesh(source_dir() / "tests" / "data" / "meshes" / "spot_triangulated.obj");
    ASSERT_TRUE(m) << m.error().message;
    auto map = remesh::map_to_sphere(*m);
    ASSERT_TRUE(map) << map.error().message;
    const double diag = diagonal(*m);
    for (const core::SphereMap dm : {core::SphereMap::EqualArea, core::SphereMap::Gnomonic})
        for (const int level : {4, 5, 6})
        {
            auto grid = core::TetraGrid::create(level);
            ASSERT_TRUE(grid);
            const auto domain = core::sphere_domain(*grid, dm);
            auto cpu = remesh::sample_surface(*grid, domain, *m, map->points);
            ASSERT_TRUE(cpu);
            for (const int k : {1, 0})
            {
                render::GpuSamplerSettings settings;
                settings.pixels_per_cell = k;
                render::GpuSampleStats stats;
                auto faces =
                    render::locate_on_gpu(*grid, domain, map->points, m->faces, settings, &stats);
                ASSERT_TRUE(faces) << faces.error().message;
                ASSERT_EQ(faces->size(), grid->node_count());
                EXPECT_EQ(stats.samples, grid->unique_count());
                const std::size_t inside = nodes_inside(*grid, domain, *m, map->points, *faces);
                remesh::SampleStats walk;
                auto located =
                    remesh::sample_surface(*grid, domain, *m, map->points, &walk, *faces);
                ASSERT_TRUE(located) << located.error().message;
                expect_twins_equal(*grid, *located);
                const double rel = max_difference(*grid, *located, *cpu) / diag;
                std::printf(
                    "spot level %d, %s map, %d px per cell: %zu of %zu nodes inside the "
                    "GPU's triangle, %zu walk steps, max |located - cpu| = %.3g of the "
                    "diagonal\n",
                    level, dm == core::SphereMap::EqualArea ? "equal-area" : "gnomonic",
                    stats.pixels_per_cell, inside, grid->unique_count(), walk.walk_steps, rel);
                // A point on an edge shared by two triangles may be interpolated in either: the
                // same position up to rounding.
                EXPECT_LT(rel, 1e-14) << "level " << level << ", k " << stats.pixels_per_cell;
                EXPECT_EQ(walk.brute_force, 0U);
                if (k == 1)
                    continue;  // a poor location (pixel centres up to half a cell away) still
                               // gives the same samples, only longer walks
                // The GPU did the point location. On the gnomonic map every node lies on a
                // pixel centre: its triangle is the one under it. On the equal-area map the
                // pixel centre is up to half a pixel away, and with spot's triangles about 25
                // pixels across in views of ~1025 px, about 5 % of the nodes have an edge in
                // between (measured 4.5-5.3 %): their walk takes one more step.
                const double share =
                    static_cast<double>(inside) / static_cast<double>(grid->unique_count());
                EXPECT_GT(share, dm == core::SphereMap::Gnomonic ? 0.999 : 0.9)
                    << "level " << level;
                EXPECT_LT(static_cast<double>(walk.walk_steps),
                          1.1 * static_cast<double>(grid->unique_count()))
                    << "level " << level;
            }
        }
}

TEST_F(GpuSamplerTest, AMissingTriangleIsAHoleAndAnError)
{
    mesh::TriMesh ball = scenes::icosphere(1);
    const std::vector<Vec3> sphere = unit_points(ball);
    ball.faces.erase(ball.faces.begin() + 7);
    auto grid = core::TetraGrid::create(4);
    ASSERT_TRUE(grid);
    auto gpu = render::sample_on_gpu(*grid, remesh::domain_sphere(*grid), sphere, ball.positions,
                                     ball.faces);
    ASSERT_FALSE(gpu);
    EXPECT_EQ(gpu.error().code, core::ErrorCode::GraphicsError);
    EXPECT_NE(gpu.error().message.find("no triangle covered"), std::string::npos)
        << gpu.error().message;
    // GPU location reports it the same way, on either domain map
    for (const core::SphereMap dm : {core::SphereMap::EqualArea, core::SphereMap::Gnomonic})
    {
        auto faces =
            render::locate_on_gpu(*grid, core::sphere_domain(*grid, dm), sphere, ball.faces);
        ASSERT_FALSE(faces);
        EXPECT_EQ(faces.error().code, core::ErrorCode::GraphicsError);
        EXPECT_NE(faces.error().message.find("no triangle covered"), std::string::npos)
            << faces.error().message;
    }
}

TEST(SampleStartFaces, BadStartFacesAreRefusedNamingTheNode)
{
    const mesh::TriMesh ball = scenes::icosphere(1);
    const std::vector<Vec3> sphere = unit_points(ball);
    auto grid = core::TetraGrid::create(3);
    ASSERT_TRUE(grid);
    const auto domain = remesh::domain_sphere(*grid);
    std::vector<std::uint32_t> faces(grid->node_count() - 1, 0);
    auto short_list = remesh::sample_surface(*grid, domain, ball, sphere, nullptr, faces);
    ASSERT_FALSE(short_list);
    EXPECT_EQ(short_list.error().code, core::ErrorCode::InvalidArgument);
    faces.assign(grid->node_count(), 0);
    faces[grid->index(3, 2).value] = static_cast<std::uint32_t>(ball.faces.size());
    auto out_of_range = remesh::sample_surface(*grid, domain, ball, sphere, nullptr, faces);
    ASSERT_FALSE(out_of_range);
    EXPECT_EQ(out_of_range.error().code, core::ErrorCode::InvalidArgument);
    EXPECT_NE(out_of_range.error().message.find("node (3, 2)"), std::string::npos)
        << out_of_range.error().message;
    // any start face in range gives the same samples as the walk from the previous node
    faces[grid->index(3, 2).value] = 5;
    auto from_zero = remesh::sample_surface(*grid, domain, ball, sphere, nullptr, faces);
    auto walked = remesh::sample_surface(*grid, domain, ball, sphere);
    ASSERT_TRUE(from_zero && walked);
    EXPECT_LT(max_difference(*grid, *from_zero, *walked), 1e-14);
}

TEST_F(GpuSamplerTest, RefusesADomainMapThatIsNotTheTetrahedron)
{
    const mesh::TriMesh ball = scenes::icosphere(2);
    const std::vector<Vec3> sphere = unit_points(ball);
    auto grid = core::TetraGrid::create(4);
    ASSERT_TRUE(grid);
    auto domain = remesh::domain_sphere(*grid);
    // move one interior node a little along the sphere: no longer a lattice point
    const core::NodeIndex n = grid->index(5, 2);
    const Vec3 p = core::normalized(at(domain, n) + Vec3{1e-3, 0.0, 0.0});
    domain[0][n] = p.x;
    domain[1][n] = p.y;
    domain[2][n] = p.z;
    auto gpu = render::sample_on_gpu(*grid, domain, sphere, ball.positions, ball.faces);
    ASSERT_FALSE(gpu);
    EXPECT_EQ(gpu.error().code, core::ErrorCode::InvalidArgument);
    // and sizes that disagree
    auto bad = render::sample_on_gpu(*grid, remesh::domain_sphere(*grid),
                                     std::span(sphere).first(3), ball.positions, ball.faces);
    EXPECT_FALSE(bad);
}

TEST_F(GpuSamplerTest, RemeshRunsThePluggedSamplerAndReportsIt)
{
    auto m = mesh::import_mesh(source_dir() / "tests" / "data" / "meshes" / "fox.ply");
    ASSERT_TRUE(m) << m.error().message;
    remesh::RemeshSettings settings;
    settings.level = 5;
    settings.measure = false;
    settings.domain_map = core::SphereMap::Gnomonic;  // the GPU sampler's views need it
    // the samplers are compared, not the untangling that follows them: on fox it moves many
    // nodes, and float32 differences of 1e-6 can make it choose other moves
    settings.untangle.enabled = false;
    auto cpu = remesh::remesh(*m, settings);
    ASSERT_TRUE(cpu) << cpu.error().message;
    EXPECT_EQ(cpu->report.sampler, "cpu");
    int calls = 0;
    settings.sampler_name = "gpu";
    settings.sampler = [&calls](const core::TetraGrid& grid, const core::Vec3Field<double>& domain,
                                const mesh::TriMesh& mesh, std::span<const core::Vec3> sphere)
    {
        ++calls;
        return render::sample_on_gpu(grid, domain, sphere, mesh.positions, mesh.faces);
    };
    auto gpu = remesh::remesh(*m, settings);
    ASSERT_TRUE(gpu) << gpu.error().message;
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(gpu->report.sampler, "gpu");
    EXPECT_NE(remesh::to_json(gpu->report).find("\"sampler\": \"gpu\""), std::string::npos);
    EXPECT_NE(remesh::to_text(gpu->report).find("sampler: gpu"), std::string::npos);
    EXPECT_LT(max_difference(gpu->grid, gpu->positions, cpu->positions) / diagonal(*m),
              k_tolerance_any_mesh);
}

}  // namespace
}  // namespace pliant::test
