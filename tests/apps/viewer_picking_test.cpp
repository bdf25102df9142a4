// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The viewer's pure parts, with no window: the pixel ray (against render::project_to_pixel, its
// independent inverse), the ray/triangle test (against hand-computed hits), the surface picker
// (against the analytic sphere a sphere grid approximates) and the input script parser/player
// (its errors name the file and line; unknown keys are refused).
#include <pliant/core/tetra_grid.h>
#include <pliant/render/camera.h>

#include <gtest/gtest.h>

#include "../../apps/pliant-cli/viewer/input_script.h"
#include "../../apps/pliant-cli/viewer/picking.h"
#include "../../scenes/grid_shapes.h"
#include "support/test_paths.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::viewer
{
namespace
{

render::CameraMatrices test_camera(int w, int h)
{
    render::Bounds b;
    b.lo = {-1.0, -1.0, -1.0};
    b.hi = {1.0, 1.0, 1.0};
    b.point_radius = 1.0;
    render::CameraSettings s;
    s.azimuth_deg = 40.0;
    s.elevation_deg = 25.0;
    return render::make_camera(s, b, w, h);
}

double distance_to_ray(const Ray& r, const core::Vec3& p)
{
    const core::Vec3 d = p - r.origin;
    return core::norm(d - r.direction * core::dot(d, r.direction));
}

TEST(ViewerPicking, InverseTimesMatrixIsIdentity)
{
    const render::CameraMatrices cam = test_camera(640, 480);
    const auto inv = invert(cam.view_projection);
    ASSERT_TRUE(inv.has_value());
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
        {
            double s = 0.0;
            for (int k = 0; k < 4; ++k)
                s += cam.view_projection.m[static_cast<std::size_t>(k * 4 + r)] *
                     inv->m[static_cast<std::size_t>(c * 4 + k)];
            EXPECT_NEAR(s, r == c ? 1.0 : 0.0, 1e-12) << r << "," << c;
        }
    render::Mat4 zero;
    EXPECT_FALSE(invert(zero).has_value());
}

TEST(ViewerPicking, PixelRayPassesThroughTheProjectedPoint)
{
    const int w = 640;
    const int h = 480;
    const render::CameraMatrices cam = test_camera(w, h);
    for (int i = 0; i < 50; ++i)
    {
        // Points spread through the box around the target.
        const core::Vec3 p{std::sin(i * 1.3), std::cos(i * 0.7), std::sin(i * 2.1 + 0.4)};
        const core::Vec3 px = render::project_to_pixel(cam, p, w, h);
        const Ray ray = pixel_ray(cam, px.x, px.y, w, h);
        EXPECT_NEAR(core::norm(ray.direction), 1.0, 1e-12);
        EXPECT_LT(distance_to_ray(ray, p), 1e-9) << i;
        EXPECT_GT(core::dot(p - ray.origin, ray.direction), 0.0);
    }
}

TEST(ViewerPicking, RayTriangleHitsAndMisses)
{
    const core::Vec3 a{0, 0, 0};
    const core::Vec3 b{2, 0, 0};
    const core::Vec3 c{0, 2, 0};
    const Ray down{{0.5, 0.25, 3.0}, {0, 0, -1}};
    const auto hit = intersect(down, a, b, c);
    ASSERT_TRUE(hit.has_value());
    EXPECT_NEAR(hit->t, 3.0, 1e-14);
    EXPECT_NEAR(hit->b1, 0.25, 1e-14);  // x = 2 b1
    EXPECT_NEAR(hit->b2, 0.125, 1e-14);
    // The back side counts too (the surface's orientation depends on the remeshing).
    const Ray up{{0.5, 0.25, -3.0}, {0, 0, 1}};
    EXPECT_TRUE(intersect(up, a, b, c).has_value());
    // Outside the triangle, behind the origin, parallel.
    EXPECT_FALSE(intersect(Ray{{1.5, 1.5, 3.0}, {0, 0, -1}}, a, b, c).has_value());
    EXPECT_FALSE(intersect(Ray{{0.5, 0.25, -3.0}, {0, 0, -1}}, a, b, c).has_value());
    EXPECT_FALSE(intersect(Ray{{0.5, 0.25, 1.0}, {1, 0, 0}}, a, b, c).has_value());
}

TEST(ViewerPicking, PickFindsTheNearSideOfASphereGrid)
{
    const core::TetraGrid grid = core::TetraGrid::create(5).value();
    const core::Vec3Field<double> p = scenes::sphere_grid(grid, 1.0);
    std::vector<core::Vec3> positions(grid.unique_count());
    for (std::size_t i = 0; i < positions.size(); ++i)
    {
        const core::NodeIndex n = grid.node_of_unique()[i];
        positions[i] = {p[0][n], p[1][n], p[2][n]};
    }
    const auto faces = grid.triangles();
    // A flat triangle inscribed in the unit sphere lies at most r^2 / 2 + O(r^4) below it (r its
    // circumradius, below its longest edge): bound the sag by the longest edge.
    double longest = 0.0;
    for (const auto& f : faces)
        for (int k = 0; k < 3; ++k)
            longest =
                std::max(longest, core::norm(positions[f[static_cast<std::size_t>(k)]] -
                                             positions[f[static_cast<std::size_t>((k + 1) % 3)]]));
    ASSERT_LT(longest, 0.2);
    const double sag = 0.5 * longest * longest;
    for (int i = 0; i < 20; ++i)
    {
        const core::Vec3 dir =
            core::normalized({std::cos(i * 0.9) + 0.1, std::sin(i * 1.7), std::cos(i * 2.3)});
        // From 3 units out towards a point 0.5 off the centre line: two crossings, the first
        // at the analytic near root.
        const core::Vec3 origin = dir * 3.0;
        const core::Vec3 aim = core::normalized(core::Vec3{0.3, -0.2, 0.4} - origin);
        const Ray ray{origin, aim};
        const double bq = core::dot(origin, aim);
        const double disc = bq * bq - (core::dot(origin, origin) - 1.0);
        ASSERT_GT(disc, 0.05);
        const double t_near = -bq - std::sqrt(disc);
        const auto hit = pick(ray, positions, faces);
        ASSERT_TRUE(hit.has_value()) << i;
        EXPECT_NEAR(hit->t, t_near, 5.0 * sag / std::sqrt(disc) + 1e-9) << i;
        // The face and weights it reports give back its point: it lies in that face.
        ASSERT_LT(hit->face, faces.size());
        const auto& f = faces[hit->face];
        EXPECT_GE(hit->b1, -1e-12);
        EXPECT_GE(hit->b2, -1e-12);
        EXPECT_LE(hit->b1 + hit->b2, 1.0 + 1e-12);
        const core::Vec3 on_face = positions[f[0]] * (1.0 - hit->b1 - hit->b2) +
                                   positions[f[1]] * hit->b1 + positions[f[2]] * hit->b2;
        EXPECT_LT(core::norm(on_face - hit->point), 1e-12) << i;
        EXPECT_LE(core::norm(hit->point), 1.0 + 1e-12);
        EXPECT_GE(core::norm(hit->point), 1.0 - sag);
    }
    // A ray that passes by misses.
    EXPECT_FALSE(pick(Ray{{0, 3, 3}, {1, 0, 0}}, positions, faces).has_value());
}

struct Recorder final : InputSink
{
    std::vector<std::string> log;
    void mouse_move(double x, double y) override
    {
        log.push_back("move " + std::to_string(static_cast<int>(x)) + " " +
                      std::to_string(static_cast<int>(y)));
    }
    void mouse_button(bool down, double x, double y) override
    {
        log.push_back(std::string(down ? "down " : "up ") + std::to_string(static_cast<int>(x)) +
                      " " + std::to_string(static_cast<int>(y)));
    }
    void wheel(double, double, double clicks) override
    {
        log.push_back("wheel " + std::to_string(static_cast<int>(clicks)));
    }
    void key(std::string_view name) override { log.push_back("key " + std::string(name)); }
    void export_file(std::string_view file) override
    {
        log.push_back("export " + std::string(file));
    }
    void load_file(std::string_view file) override { log.push_back("load " + std::string(file)); }
};

TEST(ViewerScript, LoadAndExportArePlayedWithTheirFiles)
{
    auto events = parse_input_script("0.3 export out.GLB\n0.2 load other.pgrid\n");
    ASSERT_TRUE(events.has_value()) << events.error().message;
    ScriptPlayer player(std::move(*events));
    Recorder r;
    player.play(1.0, r);
    const std::vector<std::string> expected{"load other.pgrid", "export out.GLB"};
    EXPECT_EQ(r.log, expected);
    // A load needs its file; an export its format.
    EXPECT_FALSE(parse_input_script("0.2 load\n").has_value());
    EXPECT_FALSE(parse_input_script("0.2 export out.txt\n").has_value());
    auto control = parse_input_script("0.2 load a\x01.pgrid\n", "s.txt");
    ASSERT_FALSE(control.has_value());
    EXPECT_EQ(control.error().message.rfind("s.txt:1: load file name has a control byte (0x01)", 0),
              0U)
        << control.error().message;
}

TEST(ViewerScript, ParsesAndPlaysInOrder)
{
    auto events = parse_input_script(
        "# comment\n"
        "0.5 drag 100 200 -> 300 400 for 1.0\n"
        "\n"
        "2.0 wheel 10 20 -2  # zoom out\n"
        "0.1 key P\n");
    ASSERT_TRUE(events.has_value()) << events.error().message;
    ASSERT_EQ(events->size(), 3U);
    EXPECT_EQ((*events)[0].kind, ScriptEvent::Kind::Key);  // sorted by time
    EXPECT_EQ((*events)[0].key, "p");
    ScriptPlayer player(std::move(*events));
    EXPECT_DOUBLE_EQ(player.end_time(), 2.0);
    Recorder r;
    player.play(0.0, r);
    EXPECT_TRUE(r.log.empty());
    player.play(0.2, r);
    player.play(0.5, r);
    player.play(1.0, r);  // halfway
    player.play(1.6, r);  // past the end: final move and release
    player.play(2.5, r);
    EXPECT_TRUE(player.finished());
    const std::vector<std::string> expected{"key p",        "move 100 200", "down 100 200",
                                            "move 200 300", "move 300 400", "up 300 400",
                                            "wheel -2"};
    EXPECT_EQ(r.log, expected);
}

TEST(ViewerScript, RejectsMalformedLines)
{
    for (const char* bad :
         {"drag 1 2 -> 3 4 for 1", "0.5 drag 1 2 3 4 for 1", "0.5 drag 1 2 -> 3 4 for -1",
          "-1 key p", "0.5 jump 1 2", "0.5 wheel 1 2", "0.5 wheel 1 2 nan", "0.5 key p extra",
          "0 drag 0 0 -> 1 1 for 2\n1 drag 0 0 -> 1 1 for 1"})
    {
        auto r = parse_input_script(bad);
        ASSERT_FALSE(r.has_value()) << bad;
        EXPECT_EQ(r.error().code, core::ErrorCode::ParseError);
    }
    auto line = parse_input_script("0.1 key p\n0.5 jump 1 2\n", "drag.txt");
    ASSERT_FALSE(line.has_value());
    EXPECT_EQ(line.error().message.rfind("drag.txt:2: unknown command `jump`", 0), 0U)
        << line.error().message;
    auto overlap = parse_input_script("0 drag 0 0 -> 1 1 for 2\n\n1 drag 0 0 -> 1 1 for 1\n");
    ASSERT_FALSE(overlap.has_value());
    EXPECT_EQ(overlap.error().message, "script:3: this drag starts before the drag of line 1 ends");
}

TEST(ViewerScript, RejectsUnknownKeysNamingFileAndLine)
{
    // Every key the viewer handles is accepted, in any case.
    for (const std::string_view key : k_script_keys)
    {
        auto ok = parse_input_script("0.1 key " + std::string(key) + "\n");
        EXPECT_TRUE(ok.has_value()) << key << ": " << ok.error().message;
    }
    EXPECT_TRUE(parse_input_script("0.1 key SPACE\n0.2 key F12\n").has_value());
    // A key it ignores would make a test pass without doing what it says.
    auto bad = parse_input_script("0.1 key p\n# q quits?\n0.2 key q\n", "run.txt");
    ASSERT_FALSE(bad.has_value());
    EXPECT_EQ(bad.error().code, core::ErrorCode::ParseError);
    EXPECT_EQ(bad.error().message,
              "run.txt:3: unknown key `q` (expected p, f12, e, w, c, h, r, space or escape)");
}

// An export name is one word of the file's own bytes: a NUL in it would end the name the system
// sees early (another file written), so control bytes are refused (found by fuzz_scripts);
// other bytes, UTF-8 included, and any case of the extension are kept.
TEST(ViewerScript, ExportNamesRefuseControlBytes)
{
    using namespace std::string_literals;
    auto nul = parse_input_script("0.1 export a\0b.glb\n"s, "x.txt");
    ASSERT_FALSE(nul.has_value());
    EXPECT_EQ(nul.error().message,
              "x.txt:1: export file name has a control byte (0x00) at character 2");
    EXPECT_FALSE(parse_input_script("0.1 export a\x7f.obj\n"s).has_value());
    EXPECT_FALSE(parse_input_script("0.1 export a\x01.ply\n"s).has_value());
    auto ok = parse_input_script("0.1 export r\xc3\xa9sultat.GLB\n"s);
    ASSERT_TRUE(ok.has_value()) << ok.error().message;
    EXPECT_EQ(ok->at(0).file, "r\xc3\xa9sultat.GLB");
}

TEST(ViewerScript, FileErrorsNameTheFile)
{
    const std::filesystem::path path = test::scratch_dir("ViewerScript") / "bad.txt";
    {
        std::ofstream out(path);
        out << "0.1 wheel 1 2\n";
    }
    auto r = load_input_script(path);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().message.rfind(path.string() + ":1: expected `TIME wheel X Y CLICKS`", 0),
              0U)
        << r.error().message;
}

}  // namespace
}  // namespace pliant::viewer
