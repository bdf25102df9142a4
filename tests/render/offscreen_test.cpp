// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Offscreen set-up and PNG files: the context reports a 3.3+ core renderer, the EGL and OSMesa
// backends draw the same picture, a PNG read back has exactly the pixels written, and bad paths
// give the documented errors.

#include <pliant/render/framebuffer.h>
#include <pliant/render/grid_renderer.h>

#include "gl_fixture.h"
#include "render/program.h"
#include "sphere_grid.h"
#include "support/test_paths.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace pliant::test
{
namespace
{

render::Image small_sphere(int width, int height)
{
    const auto grid = core::TetraGrid::create(3).value();
    auto renderer = render::GridRenderer::create();
    EXPECT_TRUE(renderer.has_value()) << renderer.error().message;
    auto fb = render::Framebuffer::create(width, height);
    EXPECT_TRUE(fb.has_value()) << fb.error().message;
    renderer->upload(grid, sphere_positions(grid));
    fb->bind();
    render::DrawSettings s;
    s.background = {0.1F, 0.2F, 0.3F};
    renderer->draw(s, width, height);
    return fb->read_rgba8();
}

// A program looks its draw uniforms up when it links (so a frame does no look-up by name): each
// location is GL's own for that name, -1 for a uniform the program lacks, and a move keeps them.
TEST_F(GlTest, AProgramLooksItsDrawUniformsUpWhenItLinks)
{
    const char* vertex = R"(#version 330 core
uniform mat4 u_view_projection;
uniform int u_nx;
void main() { gl_Position = u_view_projection * vec4(float(u_nx), 0.0, 0.0, 1.0); }
)";
    const char* fragment = R"(#version 330 core
uniform vec3 u_eye;
uniform vec3 u_palette[8];
uniform float u_shininess;
out vec4 frag_color;
void main() { frag_color = vec4(u_eye + u_palette[3] * u_shininess, 1.0); }
)";
    auto made = render::Program::create(vertex, fragment, "test");
    ASSERT_TRUE(made) << made.error().message;
    const render::Program program = std::move(*made);
    std::vector<std::string> names;
    std::size_t present = 0;
    for (std::size_t k = 0; k < render::k_draw_uniforms; ++k)
    {
        const auto u = static_cast<render::DrawUniform>(k);
        names.emplace_back(render::draw_uniform_name(u));
        EXPECT_EQ(program.location(u), program.uniform(render::draw_uniform_name(u)))
            << names.back();
        present += program.location(u) >= 0 ? 1 : 0;
    }
    EXPECT_EQ(present, 5U);  // the five the shaders use
    EXPECT_GE(program.location(render::DrawUniform::Palette), 0);
    EXPECT_EQ(program.location(render::DrawUniform::Flat), -1);
    std::sort(names.begin(), names.end());
    EXPECT_EQ(std::adjacent_find(names.begin(), names.end()), names.end());  // one name each
}

TEST_F(GlTest, ContextIsCoreProfileThreeThreeOrLater)
{
    EXPECT_NE(context_->backend(), render::GlBackend::Auto);
    EXPECT_NE(context_->description().find('|'), std::string::npos);
    std::printf("[render] backend %s: %s\n", render::to_string(context_->backend()),
                context_->description().c_str());
}

TEST_F(GlTest, PngRoundTripKeepsEveryPixel)
{
    const render::Image image = small_sphere(64, 48);
    ASSERT_EQ(image.rgba.size(), 64U * 48U * 4U);
    const auto dir = scratch_dir("render_png");
    for (const bool keep_alpha : {false, true})
    {
        const auto path = dir / (keep_alpha ? "rgba.png" : "rgb.png");
        ASSERT_TRUE(render::write_png(path, image, keep_alpha).has_value());
        auto back = render::read_png(path);
        ASSERT_TRUE(back.has_value()) << back.error().message;
        EXPECT_EQ(back->width, 64);
        EXPECT_EQ(back->height, 48);
        EXPECT_EQ(back->rgba, image.rgba);  // alpha is 255 in the framebuffer either way
    }
    // Top row first: the background's colour in the top-left corner.
    const std::uint8_t* corner = image.pixel(0, 0);
    EXPECT_NEAR(corner[0], 0.1 * 255, 1.0);
    EXPECT_NEAR(corner[1], 0.2 * 255, 1.0);
    EXPECT_NEAR(corner[2], 0.3 * 255, 1.0);
}

TEST(RenderPng, ErrorsNameTheProblem)
{
    const auto dir = scratch_dir("render_png_errors");
    render::Image image{2, 2, std::vector<std::uint8_t>(16, 7)};
    auto missing_dir = render::write_png(dir / "no" / "such" / "dir.png", image);
    ASSERT_FALSE(missing_dir.has_value());
    EXPECT_EQ(missing_dir.error().code, core::ErrorCode::IoError);
    image.rgba.pop_back();
    EXPECT_EQ(render::write_png(dir / "short.png", image).error().code,
              core::ErrorCode::InvalidArgument);
    {
        std::ofstream(dir / "text.png") << "this is not a png file";
    }
    auto garbage = render::read_png(dir / "text.png");
    ASSERT_FALSE(garbage.has_value());
    EXPECT_EQ(garbage.error().code, core::ErrorCode::ParseError);
    EXPECT_EQ(render::read_png(dir / "absent.png").error().code, core::ErrorCode::IoError);
}

TEST_F(GlTest, EglAndOsMesaDrawTheSamePicture)
{
    const render::Image first = small_sphere(80, 80);
    const render::GlBackend other = context_->backend() == render::GlBackend::Egl
                                        ? render::GlBackend::OsMesa
                                        : render::GlBackend::Egl;
    auto second_context = render::OffscreenContext::create(other);
    if (!second_context && gl_required())
        FAIL() << "only one backend here: " << second_context.error().message;
    if (!second_context)
        GTEST_SKIP() << "only one backend here: " << second_context.error().message;
    const render::Image second = small_sphere(80, 80);
    int worst = 0;
    for (std::size_t i = 0; i < first.rgba.size(); ++i)
        worst = std::max(worst, std::abs(first.rgba[i] - second.rgba[i]));
    EXPECT_LE(worst, 2) << render::to_string(other) << ": " << second_context->description();
    // Switching back reloads the first context's entry points.
    ASSERT_TRUE(context_->make_current().has_value());
    EXPECT_EQ(small_sphere(80, 80).rgba, first.rgba);
}

TEST_F(GlTest, MultisampledFramebufferResolvesOnReadBack)
{
    auto fb = render::Framebuffer::create(32, 16, render::PixelFormat::Rgba8, 4);
    ASSERT_TRUE(fb.has_value()) << fb.error().message;
    EXPECT_GE(fb->samples(), 1);
    EXPECT_FALSE(render::Framebuffer::create(0, 16).has_value());
}

}  // namespace
}  // namespace pliant::test
