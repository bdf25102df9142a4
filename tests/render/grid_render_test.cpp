// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// GridRenderer against geometry known in closed form: a unit sphere built on the tetrahedral
// grid (sphere_grid.h), seen from a known camera, must cover the disc the perspective formula
// predicts, without holes along the tetrahedron's seams; the normals the vertex shader computes
// from neighbour texels must equal area-weighted normals computed on the CPU (normals.h); owner
// and displacement colouring must show the colours asked for.

#include <pliant/render/framebuffer.h>
#include <pliant/render/grid_renderer.h>
#include <pliant/render/mesh_renderer.h>
#include <pliant/render/normals.h>

#include "gl_fixture.h"
#include "sphere_grid.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

namespace pliant::test
{
namespace
{

constexpr int k_size = 192;
constexpr double k_distance = 4.0;
constexpr double k_fov_deg = 30.0;

render::DrawSettings sphere_settings()
{
    render::DrawSettings s;
    s.camera = {
        .azimuth_deg = 20.0, .elevation_deg = 15.0, .distance = k_distance, .fov_y_deg = k_fov_deg};
    s.background = {0.0F, 1.0F, 0.0F};  // pure green: never a shade of the surface colours
    s.base_color = {0.7F, 0.6F, 0.5F};
    return s;
}

/// Radius in pixels of the silhouette of the unit sphere at `k_distance` (its angular radius
/// is asin(1/d)).
double expected_radius_px()
{
    const double alpha = std::asin(1.0 / k_distance);
    const double half_fov = 0.5 * k_fov_deg * std::numbers::pi / 180.0;
    return std::tan(alpha) / std::tan(half_fov) * 0.5 * k_size;
}

struct Shot
{
    render::Image image;
    render::CameraMatrices camera;
};

Shot render_grid(const core::TetraGrid& grid, const core::Vec3Field<double>& positions,
                 const render::DrawSettings& settings, const core::Field<double>* values = nullptr,
                 std::span<const std::uint16_t> owners = {})
{
    auto renderer = render::GridRenderer::create();
    EXPECT_TRUE(renderer.has_value()) << renderer.error().message;
    auto fb = render::Framebuffer::create(k_size, k_size);
    EXPECT_TRUE(fb.has_value()) << fb.error().message;
    renderer->upload(grid, positions, values);
    if (!owners.empty())
        renderer->upload_owners(grid, owners);
    fb->bind();
    renderer->draw(settings, k_size, k_size);
    return {fb->read_rgba8(), renderer->camera(settings.camera, k_size, k_size)};
}

bool is_background(const render::Image& image, int x, int y)
{
    return is_rgb(image, x, y, 0, 255, 0);
}

TEST_F(GlTest, SphereCoversTheExpectedDisc)
{
    const auto grid = core::TetraGrid::create(5).value();
    const auto p = sphere_positions(grid);
    const Shot shot = render_grid(grid, p, sphere_settings());
    const core::Vec3 c = render::project_to_pixel(shot.camera, {0, 0, 0}, k_size, k_size);
    const double r = expected_radius_px();

    int covered = 0;
    double sx = 0.0;
    double sy = 0.0;
    int holes = 0;
    int spill = 0;
    for (int y = 0; y < k_size; ++y)
        for (int x = 0; x < k_size; ++x)
        {
            const double d = std::hypot(x + 0.5 - c.x, y + 0.5 - c.y);
            const bool object = !is_background(shot.image, x, y);
            covered += object ? 1 : 0;
            sx += object ? x + 0.5 : 0.0;
            sy += object ? y + 0.5 : 0.0;
            holes += (!object && d < 0.97 * r) ? 1 : 0;  // a crack or hole inside the disc
            spill += (object && d > 1.02 * r) ? 1 : 0;
        }
    ASSERT_GT(covered, 0);
    // The inscribed polyhedron's silhouette is slightly inside the sphere's: within 2 %.
    const double measured = std::sqrt(covered / std::numbers::pi);
    EXPECT_NEAR(measured / r, 1.0, 0.02) << "measured radius " << measured << " px";
    EXPECT_NEAR(sx / covered, c.x, 0.5);
    EXPECT_NEAR(sy / covered, c.y, 0.5);
    EXPECT_EQ(holes, 0);
    EXPECT_EQ(spill, 0);
}

TEST_F(GlTest, PhongCentreIsBrighterThanTheRim)
{
    const auto grid = core::TetraGrid::create(5).value();
    const Shot shot = render_grid(grid, sphere_positions(grid), sphere_settings());
    const core::Vec3 c = render::project_to_pixel(shot.camera, {0, 0, 0}, k_size, k_size);
    const double r = expected_radius_px();
    const double centre = luma(shot.image, static_cast<int>(c.x), static_cast<int>(c.y));
    for (int k = 0; k < 8; ++k)
    {
        const double phi = k * std::numbers::pi / 4.0;
        const int x = static_cast<int>(c.x + 0.9 * r * std::cos(phi));
        const int y = static_cast<int>(c.y + 0.9 * r * std::sin(phi));
        ASSERT_FALSE(is_background(shot.image, x, y));
        // Head light: the centre faces the light (diffuse 1 plus the highlight), the rim at
        // 0.9 r is lit at cos(asin(0.9)) ~ 0.44.
        EXPECT_GT(centre, luma(shot.image, x, y) + 40.0) << "direction " << k;
    }
}

/// Points along every seam edge (the glued border of the rectangle), in model space.
std::vector<core::Vec3> seam_points(const core::TetraGrid& grid, const core::Vec3Field<double>& p)
{
    std::vector<core::Vec3> out;
    auto add_edge = [&](int x0, int y0, int x1, int y1)
    {
        const core::Vec3 a = node_position(p, grid.index(x0, y0));
        const core::Vec3 b = node_position(p, grid.index(x1, y1));
        for (int k = 0; k <= 4; ++k)
            out.push_back(a + (b - a) * (k / 4.0));
    };
    for (int x = 0; x < grid.nx() - 1; ++x)
    {
        add_edge(x, 0, x + 1, 0);
        add_edge(x, grid.w(), x + 1, grid.w());
    }
    for (int y = 0; y < grid.w(); ++y)
        add_edge(0, y, 0, y + 1);
    return out;
}

TEST_F(GlTest, NoCracksAndSmoothShadingAlongSeams)
{
    const auto grid = core::TetraGrid::create(4).value();
    const auto p = sphere_positions(grid);
    render::DrawSettings s = sphere_settings();
    s.specular = 0.0F;  // the highlight's steep slope would dominate the smoothness measure
    const Shot shot = render_grid(grid, p, s);
    const core::Vec3 c = render::project_to_pixel(shot.camera, {0, 0, 0}, k_size, k_size);
    const double r = expected_radius_px();
    const core::Vec3 eye = shot.camera.eye;

    // Second difference of luma along the image row, |L(x-2) - 2 L(x) + L(x+2)|: small where
    // shading is smooth, large at a crack (background) or a crease (a normal that jumps).
    auto bend = [&](int x, int y)
    {
        return std::abs(luma(shot.image, x - 2, y) - 2.0 * luma(shot.image, x, y) +
                        luma(shot.image, x + 2, y));
    };
    int checked = 0;
    double worst_seam = 0.0;
    for (const core::Vec3& q : seam_points(grid, p))
    {
        if (core::dot(q, eye - q) <= 0.0)  // the far side of the sphere
            continue;
        const core::Vec3 px = render::project_to_pixel(shot.camera, q, k_size, k_size);
        if (std::hypot(px.x - c.x, px.y - c.y) > 0.8 * r)
            continue;
        const int x = static_cast<int>(px.x);
        const int y = static_cast<int>(px.y);
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
                EXPECT_FALSE(is_background(shot.image, x + dx, y + dy))
                    << "crack at pixel " << x + dx << "," << y + dy;
        worst_seam = std::max(worst_seam, bend(x, y));
        ++checked;
    }
    EXPECT_GT(checked, 50);
    // The same measure over the whole inner disc, seams or not.
    double worst_inside = 0.0;
    for (int y = 0; y < k_size; ++y)
        for (int x = 2; x < k_size - 2; ++x)
            if (std::hypot(x + 0.5 - c.x, y + 0.5 - c.y) < 0.8 * r)
                worst_inside = std::max(worst_inside, bend(x, y));
    std::printf("[render] %d seam samples, worst bend %.2f on seams, %.2f in the disc\n", checked,
                worst_seam, worst_inside);
    EXPECT_LE(worst_seam, 6.0) << "inside the disc at worst " << worst_inside;
    EXPECT_LE(worst_inside, 6.0);
    // The sampler itself sees background where there is some (so it can fail).
    EXPECT_TRUE(is_background(shot.image, 0, 0));
}

void expect_gpu_normals_match_cpu_normals(render::GridNormals mode)
{
    const auto grid = core::TetraGrid::create(3).value();
    const auto p = sphere_positions(grid);
    const auto cpu = render::grid_normals(grid, p);
    constexpr int k_fb = 384;
    auto renderer = render::GridRenderer::create(mode);
    ASSERT_TRUE(renderer.has_value()) << renderer.error().message;
    auto fb = render::Framebuffer::create(k_fb, k_fb, render::PixelFormat::Rgba32f);
    ASSERT_TRUE(fb.has_value()) << fb.error().message;
    renderer->upload(grid, p);
    render::DrawSettings s = sphere_settings();
    s.camera.distance = 4.5;
    s.shading = render::Shading::Normals;
    s.points = true;  // one pixel per node: the vertex shader's normal, not an interpolation
    s.background = {0.0F, 0.0F, 0.0F};
    fb->bind();
    renderer->draw(s, k_fb, k_fb);
    const std::vector<float> pixels = fb->read_rgba32f();
    const render::CameraMatrices cam = renderer->camera(s.camera, k_fb, k_fb);

    int checked = 0;
    int border_checked = 0;
    double worst = 0.0;
    for (const core::NodeIndex n : grid.node_of_unique())
    {
        const core::Vec3 q = node_position(p, n);
        const core::Vec3 normal{cpu[0][n], cpu[1][n], cpu[2][n]};
        if (core::dot(normal, core::normalized(cam.eye - q)) < 0.3)
            continue;  // hidden, or so oblique that a neighbour may cover the pixel
        const core::Vec3 px = render::project_to_pixel(cam, q, k_fb, k_fb);
        // The point covers the pixel it falls in; search the 3x3 block for the pixel written
        // by this vertex (alpha = node index, a twin counts as the same vertex).
        bool found = false;
        for (int dy = -1; dy <= 1 && !found; ++dy)
            for (int dx = -1; dx <= 1 && !found; ++dx)
            {
                const int x = static_cast<int>(px.x) + dx;
                const int y = static_cast<int>(px.y) + dy;
                if (x < 0 || y < 0 || x >= k_fb || y >= k_fb)
                    continue;
                const float* t =
                    pixels.data() +
                    (static_cast<std::size_t>(y) * k_fb + static_cast<std::size_t>(x)) * 4U;
                if (t[0] == 0.0F && t[1] == 0.0F && t[2] == 0.0F)
                    continue;
                const auto node = static_cast<std::uint32_t>(t[3]);
                if (node >= grid.node_count() ||
                    grid.unique_id(core::NodeIndex{node}) != grid.unique_id(n))
                    continue;
                const core::Vec3 gpu{2.0 * static_cast<double>(t[0]) - 1.0,
                                     2.0 * static_cast<double>(t[1]) - 1.0,
                                     2.0 * static_cast<double>(t[2]) - 1.0};
                worst = std::max(worst, core::norm(gpu - normal));
                found = true;
            }
        EXPECT_TRUE(found) << "node " << n.value << " not found near pixel " << px.x << "," << px.y;
        ++checked;
        const core::GridCoord g = grid.coord(n);
        border_checked += (g.x == 0 || g.y == 0 || g.y == grid.w() || g.x == grid.nx() - 1);
    }
    std::printf("[render] %d nodes (%d on seams) checked, worst |n_gpu - n_cpu| = %.2e\n", checked,
                border_checked, worst);
    // About a third of the 130 vertices face the camera steeply enough; many lie on seams.
    EXPECT_GT(checked, 30);
    EXPECT_GT(border_checked, 8);
    EXPECT_LT(worst, 1e-4) << "float texture positions give ~1e-6; a wrong ghost gives ~0.1";
}

TEST_F(GlTest, ShaderNormalsMatchAreaWeightedCpuNormals)
{
    expect_gpu_normals_match_cpu_normals(render::GridNormals::PassToBuffer);
}

TEST_F(GlTest, FetchedNormalsMatchAreaWeightedCpuNormals)
{
    expect_gpu_normals_match_cpu_normals(render::GridNormals::PassFetch);
}

TEST_F(GlTest, VertexShaderNormalsMatchAreaWeightedCpuNormals)
{
    expect_gpu_normals_match_cpu_normals(render::GridNormals::VertexShader);
}

TEST_F(GlTest, NormalPassDrawsWhatVertexShaderNormalsDraw)
{
    // The three GridNormals modes run the same formula on the same texels: the pictures must
    // agree, and keep agreeing after new positions, new owners and new values (the pass and
    // the copy must rerun after every upload, not only the first).
    const auto grid = core::TetraGrid::create(4).value();
    const auto round = sphere_positions(grid);
    auto bumpy = sphere_positions(grid);
    core::Field<double> bump(grid);
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const core::Vec3 q{round[0].at(x, y), round[1].at(x, y), round[2].at(x, y)};
            bump.at(x, y) = 0.08 * std::sin(7.0 * q.x) * std::cos(5.0 * q.y + 2.0 * q.z);
            for (std::size_t c = 0; c < 3; ++c)
                bumpy[c].at(x, y) = round[c].at(x, y) * (1.0 + bump.at(x, y));
        }
    std::vector<std::uint16_t> halves(grid.node_count());
    std::vector<std::uint16_t> thirds(grid.node_count());
    for (std::uint32_t i = 0; i < grid.node_count(); ++i)
    {
        const core::GridCoord g = grid.coord(grid.canonical(core::NodeIndex{i}));
        halves[i] = g.x <= grid.w() ? 0 : 1;
        thirds[i] = static_cast<std::uint16_t>(g.x * 3 / grid.nx() + 2);
    }
    constexpr std::array modes{render::GridNormals::PassToBuffer, render::GridNormals::PassFetch,
                               render::GridNormals::VertexShader};  // the last is the reference
    std::vector<render::GridRenderer> renderers;
    for (const render::GridNormals mode : modes)
    {
        auto r = render::GridRenderer::create(mode);
        ASSERT_TRUE(r.has_value()) << r.error().message;
        renderers.push_back(std::move(*r));
    }
    auto fb = render::Framebuffer::create(k_size, k_size);
    ASSERT_TRUE(fb.has_value()) << fb.error().message;
    render::DrawSettings s = sphere_settings();
    s.color = render::ColorMode::Owner;
    s.wireframe = true;
    auto shot = [&](const render::GridRenderer& r)
    {
        fb->bind();
        r.draw(s, k_size, k_size);
        return fb->read_rgba8();
    };
    auto compare = [&](const char* what)
    {
        const render::Image reference = shot(renderers.back());
        for (std::size_t m = 0; m + 1 < renderers.size(); ++m)
        {
            const render::Image a = shot(renderers[m]);
            int worst = 0;
            int differing = 0;
            for (std::size_t i = 0; i < a.rgba.size(); ++i)
            {
                const int d = std::abs(a.rgba[i] - reference.rgba[i]);
                worst = std::max(worst, d);
                differing += d > 0;
            }
            std::printf("[render] %s, mode %zu: %d of %zu channels differ, by at most %d\n", what,
                        m, differing, a.rgba.size(), worst);
            EXPECT_LE(worst, 1) << what << ", mode " << m;
        }
        return reference;
    };
    for (render::GridRenderer& r : renderers)
    {
        r.upload(grid, round);
        r.upload_owners(grid, halves);
    }
    const render::Image first = compare("sphere, two owners");
    for (render::GridRenderer& r : renderers)
        r.upload(grid, bumpy);
    const render::Image second = compare("bumpy sphere, two owners");
    for (render::GridRenderer& r : renderers)
        r.upload_owners(grid, thirds);
    const render::Image third = compare("bumpy sphere, three owners");
    s.color = render::ColorMode::Displacement;
    for (render::GridRenderer& r : renderers)
        r.upload(grid, bumpy, &bump);
    const render::Image fourth = compare("bumpy sphere, displacement colours");
    EXPECT_NE(first.rgba, second.rgba) << "new positions must change the picture";
    EXPECT_NE(second.rgba, third.rgba) << "new owners must change the picture";
    EXPECT_NE(third.rgba, fourth.rgba);
}

TEST_F(GlTest, OwnerColouringShowsTheTwoOwners)
{
    const auto grid = core::TetraGrid::create(4).value();
    const auto p = sphere_positions(grid);
    // Half and half: the left square (x <= W, canonical nodes) to owner 0, the rest to 1.
    std::vector<std::uint16_t> owners(grid.node_count());
    for (std::uint32_t i = 0; i < grid.node_count(); ++i)
        owners[i] = grid.coord(grid.canonical(core::NodeIndex{i})).x <= grid.w() ? 0 : 1;
    render::DrawSettings s = sphere_settings();
    s.ambient = 1.0F;  // unlit: every pixel exactly its base colour
    s.specular = 0.0F;
    s.color = render::ColorMode::Owner;

    auto count = [](const render::Image& image, render::Rgb c)
    {
        int n = 0;
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x)
            {
                const std::uint8_t* q = image.pixel(x, y);
                n += std::abs(q[0] - c.r * 255.0F) <= 1.5F &&
                     std::abs(q[1] - c.g * 255.0F) <= 1.5F && std::abs(q[2] - c.b * 255.0F) <= 1.5F;
            }
        return n;
    };
    const Shot owned = render_grid(grid, p, s, nullptr, owners);
    const int object = k_size * k_size - count(owned.image, s.background);
    const int first = count(owned.image, render::owner_color(0));
    const int second = count(owned.image, render::owner_color(1));
    std::printf("[render] %d object pixels: %d owner 0, %d owner 1\n", object, first, second);
    EXPECT_GT(first, object / 5);
    EXPECT_GT(second, object / 5);
    EXPECT_EQ(first + second, object);

    s.color = render::ColorMode::None;  // the same owners, not asked for: no palette colour
    const Shot plain = render_grid(grid, p, s, nullptr, owners);
    EXPECT_EQ(count(plain.image, render::owner_color(0)), 0);
    EXPECT_EQ(count(plain.image, render::owner_color(1)), 0);
}

TEST_F(GlTest, DisplacementColouringIsDiverging)
{
    const auto grid = core::TetraGrid::create(4).value();
    const auto p = sphere_positions(grid);
    core::Field<double> u(grid);  // u = y: outwards at the top, inwards at the bottom
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
            u.at(x, y) = p[1].at(x, y);
    render::DrawSettings s = sphere_settings();
    s.camera.elevation_deg = 0.0;
    s.color = render::ColorMode::Displacement;
    s.displacement_range = 0.5F;  // |u| >= 0.5 saturates to the map's end colours
    s.ambient = 1.0F;             // unlit, so pixels are the map's colours exactly
    s.specular = 0.0F;
    const Shot shot = render_grid(grid, p, s, &u);
    auto colour_at = [&](const core::Vec3& q)
    {
        const core::Vec3 px = render::project_to_pixel(shot.camera, q, k_size, k_size);
        return shot.image.pixel(static_cast<int>(px.x), static_cast<int>(px.y));
    };
    const std::uint8_t* top = colour_at({0, 0.6, 0.8});      // u = 0.6: outwards, warm end
    const std::uint8_t* bottom = colour_at({0, -0.6, 0.8});  // u = -0.6: inwards, cold end
    const std::uint8_t* middle = colour_at({0, 0.0, 1.0});   // u = 0: the neutral grey
    EXPECT_NEAR(top[0], 0.706 * 255, 2.0);
    EXPECT_NEAR(top[1], 0.016 * 255, 2.0);
    EXPECT_NEAR(top[2], 0.150 * 255, 2.0);
    EXPECT_NEAR(bottom[0], 0.230 * 255, 2.0);
    EXPECT_NEAR(bottom[1], 0.299 * 255, 2.0);
    EXPECT_NEAR(bottom[2], 0.754 * 255, 2.0);
    // Near the equator |u| is small: close to the grey, balanced between red and blue.
    EXPECT_NEAR(middle[0], middle[2], 25.0);
    EXPECT_GT(middle[1], 150);
}

TEST_F(GlTest, WireframeDrawsEdgesOnlyWhenAsked)
{
    const auto grid = core::TetraGrid::create(3).value();
    const auto p = sphere_positions(grid);
    render::DrawSettings s = sphere_settings();
    s.wire_color = {1.0F, 0.0F, 1.0F};  // magenta, unlike any shade of the surface
    auto wire_pixels = [&](const render::Image& image)
    {
        int n = 0;
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x)
                n += is_rgb(image, x, y, 255, 0, 255);
        return n;
    };
    EXPECT_EQ(wire_pixels(render_grid(grid, p, s).image), 0);
    s.wireframe = true;
    const int coarse = wire_pixels(render_grid(grid, p, s).image);
    const auto fine_grid = core::TetraGrid::create(4).value();
    const int fine = wire_pixels(render_grid(fine_grid, sphere_positions(fine_grid), s).image);
    EXPECT_GT(coarse, 200);
    EXPECT_GT(fine, coarse) << "twice the edges per direction, more line pixels";
}

TEST_F(GlTest, VertexBufferPathDrawsTheSameSphere)
{
    // The texture path (GPU normals) and the vertex-buffer path (CPU normals) must agree.
    const auto grid = core::TetraGrid::create(4).value();
    const auto p = sphere_positions(grid);
    const render::DrawSettings s = sphere_settings();
    const Shot by_texture = render_grid(grid, p, s);

    std::vector<core::Vec3> points;
    for (const core::NodeIndex n : grid.node_of_unique())
        points.push_back(node_position(p, n));
    const auto faces = grid.triangles();
    auto mesh = render::MeshRenderer::create();
    ASSERT_TRUE(mesh.has_value()) << mesh.error().message;
    mesh->upload(points, faces);
    auto fb = render::Framebuffer::create(k_size, k_size);
    ASSERT_TRUE(fb.has_value());
    fb->bind();
    mesh->draw(s, k_size, k_size);
    const render::Image by_buffer = fb->read_rgba8();

    double sum = 0.0;
    int worst = 0;
    for (std::size_t i = 0; i < by_buffer.rgba.size(); ++i)
    {
        const int d = std::abs(by_buffer.rgba[i] - by_texture.image.rgba[i]);
        sum += d;
        worst = std::max(worst, d);
    }
    EXPECT_LT(sum / static_cast<double>(by_buffer.rgba.size()), 0.05);
    EXPECT_LE(worst, 3);
}

TEST_F(GlTest, VertexBufferUpdateDrawsWhatAFreshUploadDraws)
{
    // A vertex-buffer mesh that moves (the sphere stretched into an ellipsoid, with values):
    // update() on the uploaded sphere must draw, pixel for pixel, what a new renderer given the
    // ellipsoid draws, and not what the sphere drew.
    const auto grid = core::TetraGrid::create(4).value();
    const auto p = sphere_positions(grid);
    std::vector<core::Vec3> sphere;
    for (const core::NodeIndex n : grid.node_of_unique())
        sphere.push_back(node_position(p, n));
    std::vector<core::Vec3> ellipsoid = sphere;
    std::vector<float> values;
    for (core::Vec3& v : ellipsoid)
    {
        v.x *= 1.4;
        values.push_back(static_cast<float>(v.z));
    }
    const auto faces = grid.triangles();
    render::DrawSettings s = sphere_settings();
    s.color = render::ColorMode::Displacement;
    auto fb = render::Framebuffer::create(k_size, k_size);
    ASSERT_TRUE(fb.has_value());
    fb->bind();
    const auto draw = [&](const render::MeshRenderer& mesh)
    {
        mesh.draw(s, k_size, k_size);
        return fb->read_rgba8();
    };

    auto moved = render::MeshRenderer::create();
    ASSERT_TRUE(moved.has_value()) << moved.error().message;
    moved->upload(sphere, faces);
    const render::Image before = draw(*moved);
    moved->update(ellipsoid, {}, values);
    const render::Image updated = draw(*moved);
    moved->update(ellipsoid, {}, values);  // the second call reuses its buffers
    const render::Image updated_again = draw(*moved);

    auto fresh = render::MeshRenderer::create();
    ASSERT_TRUE(fresh.has_value()) << fresh.error().message;
    fresh->upload(ellipsoid, faces, {}, values);
    const render::Image expected = draw(*fresh);

    EXPECT_EQ(updated.rgba, expected.rgba);
    EXPECT_EQ(updated_again.rgba, expected.rgba);
    EXPECT_NE(updated.rgba, before.rgba);
    EXPECT_EQ(moved->bounds().hi.x, fresh->bounds().hi.x);
    EXPECT_GT(moved->bounds().hi.x, 1.3);
}

}  // namespace
}  // namespace pliant::test
