// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Frames per second of the Phong renderer at 1280x720, offscreen, for a sphere grid of levels
// 6..9 (16K .. 1M triangles): the texture path (GridRenderer: positions in a float texture,
// normals from neighbour texels on the GPU, in its three GridNormals modes: the default normal
// pass copied into a vertex buffer, the normal pass fetched in the vertex shader, normals
// summed in the vertex shader) beside the plain vertex-buffer path (MeshRenderer: CPU normals
// in one interleaved buffer) in the same run. Each iteration draws one frame and waits for it
// (glFinish, as a buffer swap would in a window; no read-back). The counter "fps" is frames per
// second of wall time; the line printed first names GL_RENDERER. upload:1 gives new positions
// every frame, as the simulation loop does: the texture path re-uploads its texture and runs its
// normal pass, the vertex-buffer path computes its normals on the CPU and rewrites its vertex
// buffer (MeshRenderer::update); upload:0 draws what was uploaded once.
//
// Usage: bench_render [--benchmark_repetitions=3 --benchmark_report_aggregates_only=true]
//        bench_render [--quick] [--json FILE] [--csv FILE]    (what `pliant bench` runs)
// --quick: levels 6..8 and 0.3 s per figure; the rows (bench/common/bench_report.h) give fps and
// ms per frame sized by triangles, and the metadata GL_RENDERER.
// Set PLIANT_GL_BACKEND=osmesa to measure OSMesa instead of EGL.

#include <pliant/render/framebuffer.h>
#include <pliant/render/gl_loader.h>
#include <pliant/render/grid_renderer.h>
#include <pliant/render/mesh_renderer.h>
#include <pliant/render/offscreen_context.h>

#include <benchmark/benchmark.h>

#include "gbench_report.h"
#include "sphere_grid.h"

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

namespace
{

using namespace pliant;

constexpr int k_width = 1280;
constexpr int k_height = 720;

bench::Report g_report("render");

render::OffscreenContext& context()
{
    static std::optional<render::OffscreenContext> ctx;
    if (!ctx)
    {
        auto made = render::OffscreenContext::create();
        if (!made)
        {
            std::fprintf(stderr, "bench_render: %s\n", made.error().message.c_str());
            std::exit(1);
        }
        ctx.emplace(std::move(*made));
        g_report.meta("gl_backend", render::to_string(ctx->backend()));
        g_report.meta("gl_renderer", ctx->description());
        std::printf("bench_render: %s context: %s, %dx%d\n", render::to_string(ctx->backend()),
                    ctx->description().c_str(), k_width, k_height);
    }
    return *ctx;
}

void texture_path(benchmark::State& state, render::GridNormals normals)
{
    context();
    const int level = static_cast<int>(state.range(0));
    const auto grid = core::TetraGrid::create(level).value();
    const auto p = test::sphere_positions(grid);
    auto renderer = render::GridRenderer::create(normals).value();
    auto fb = render::Framebuffer::create(k_width, k_height).value();
    render::DrawSettings s;
    const bool upload_each_frame = state.range(1) != 0;
    renderer.upload(grid, p);
    fb.bind();
    for (auto _ : state)
    {
        if (upload_each_frame)  // as in the simulation loop: new positions every frame
            renderer.upload(grid, p);
        renderer.draw(s, k_width, k_height);
        render::gl_finish();
    }
    state.counters["fps"] =
        benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["triangles"] = static_cast<double>(renderer.triangle_count());
}

void BM_TexturePath(benchmark::State& state)
{
    texture_path(state, render::GridNormals::PassToBuffer);
}

void BM_TexturePathFetch(benchmark::State& state)
{
    texture_path(state, render::GridNormals::PassFetch);
}

void BM_TexturePathVertexNormals(benchmark::State& state)
{
    texture_path(state, render::GridNormals::VertexShader);
}

void BM_VertexBufferPath(benchmark::State& state)
{
    context();
    const int level = static_cast<int>(state.range(0));
    const auto grid = core::TetraGrid::create(level).value();
    const auto p = test::sphere_positions(grid);
    std::vector<core::Vec3> points;
    for (const core::NodeIndex n : grid.node_of_unique())
        points.push_back(test::node_position(p, n));
    auto renderer = render::MeshRenderer::create().value();
    renderer.upload(points, grid.triangles());
    auto fb = render::Framebuffer::create(k_width, k_height).value();
    render::DrawSettings s;
    const bool upload_each_frame = state.range(1) != 0;
    fb.bind();
    for (auto _ : state)
    {
        if (upload_each_frame)  // new positions every frame: CPU normals and the vertex buffer
            renderer.update(points);
        renderer.draw(s, k_width, k_height);
        render::gl_finish();
    }
    state.counters["fps"] =
        benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["triangles"] = static_cast<double>(renderer.triangle_count());
}

}  // namespace

int main(int argc, char** argv)
{
    bool quick = false;
    for (int i = 1; i < argc; ++i)
        quick = quick || std::string(argv[i]) == "--quick";
    const std::int64_t max_level = quick ? 8 : 9;
    std::vector<std::int64_t> levels;
    for (std::int64_t l = 6; l <= max_level; ++l)
        levels.push_back(l);
    benchmark::RegisterBenchmark("BM_TexturePath", BM_TexturePath)
        ->ArgsProduct({levels, {0, 1}})
        ->ArgNames({"level", "upload"})
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark("BM_TexturePathFetch", BM_TexturePathFetch)
        ->ArgsProduct({levels, {0, 1}})
        ->ArgNames({"level", "upload"})
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark("BM_TexturePathVertexNormals", BM_TexturePathVertexNormals)
        ->ArgsProduct({levels, {0, 1}})
        ->ArgNames({"level", "upload"})
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark("BM_VertexBufferPath", BM_VertexBufferPath)
        ->ArgsProduct({levels, {0, 1}})
        ->ArgNames({"level", "upload"})
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    return bench::run_with_report(
        g_report, argc, argv,
        [](const benchmark::BenchmarkReporter::Run& r)
        {
            const std::string fn = r.run_name.function_name;
            const std::string& args = r.run_name.args;
            const auto lp = args.find("level:");
            const int level = lp == std::string::npos ? -1 : std::atoi(args.c_str() + lp + 6);
            std::string c = fn == "BM_TexturePath"                ? "texture path"
                            : fn == "BM_TexturePathFetch"         ? "texture path, VS fetch"
                            : fn == "BM_TexturePathVertexNormals" ? "texture path, VS normals"
                                                                  : "vertex-buffer path";
            if (args.find("upload:1") != std::string::npos)
                c += " + upload";
            const double tris = bench::counter(r, "triangles");
            g_report.add(c, level, tris, "triangles", "fps", bench::counter(r, "fps"), "1/s");
            g_report.add(c, level, tris, "triangles", "ms_per_frame", bench::real_seconds(r) * 1e3,
                         "ms");
        },
        0.3);
}
