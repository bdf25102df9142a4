// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant remesh [MESH] --level N -o OUT [--report FILE.json]`: remeshes a closed genus-0 mesh
// onto the tetrahedral grid (docs/remesh.md). OUT by extension: .pgrid (native grid file,
// docs/grid-format.md), .obj, .ply, .gltf, .glb, .pfm. `--gpu` samples through an offscreen OpenGL
// context (render::sample_on_gpu on the gnomonic domain map, render::locate_on_gpu plus exact CPU
// interpolation on the equal-area one; docs/remesh.md, "GPU sampling").
#include <pliant/core/file_io.h>
#include <pliant/core/grid_io.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/remesh/remesh.h>
#include <pliant/remesh/sample.h>
#include <pliant/render/gpu_sampler.h>
#include <pliant/render/offscreen_context.h>

#include <spdlog/spdlog.h>

#include "cli_common.h"
#include "commands.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

namespace pliant::cli
{
namespace
{

struct RemeshOptions
{
    std::filesystem::path mesh;
    std::filesystem::path output;
    std::filesystem::path report;
    int level = 7;
    std::string method = "auto";
    bool no_measure = false;
    bool no_untangle = false;
    bool gpu = false;
    std::string domain_map = "equal-area";
};

int run_remesh(const RemeshOptions& opt, const GlobalOptions& global)
{
    const std::filesystem::path input = opt.mesh.empty() ? bundled_mesh() : opt.mesh;
    const std::string ext = lower_extension(opt.output);
    if (ext != ".pgrid" && ext != ".obj" && ext != ".ply" && ext != ".gltf" && ext != ".glb" &&
        ext != ".pfm")
        return report({core::ErrorCode::UnsupportedFormat,
                       "remesh: output '" + opt.output.string() +
                           "' must end in .pgrid, .obj, .ply, .gltf, .glb or .pfm"});

    // fail before minutes of work, not after: a path that cannot be written is refused now
    // (nothing is created; the outputs are written whole at the end, core::write_files)
    if (auto ok = check_writable(opt.output, "remesh: -o"); !ok)
        return report(ok.error());
    const NamedFile inputs[] = {{input, "mesh"}};
    const NamedFile outputs[] = {{opt.output, "-o"}, {opt.report, "--report"}};
    if (const auto clash = file_clash(inputs, outputs))
    {
        spdlog::error("remesh: {}", *clash);
        return k_exit_usage;
    }
    if (!opt.report.empty())
    {
        if (auto ok = check_writable(opt.report, "remesh: --report"); !ok)
            return report(ok.error());
    }

    auto m = mesh::import_mesh(input);
    if (!m)
        return report(m.error());
    if (auto ok = mesh::validate(*m, input.filename().string()); !ok)
        return report(ok.error());

    remesh::RemeshSettings settings;
    settings.level = opt.level;
    const bool gnomonic = opt.domain_map == "gnomonic";
    settings.domain_map = gnomonic ? core::SphereMap::Gnomonic : core::SphereMap::EqualArea;
    settings.measure = !opt.no_measure;
    settings.untangle.enabled = !opt.no_untangle;
    settings.sphere.method = opt.method == "spring"   ? remesh::SphereMethod::SpringEmbedder
                             : opt.method == "coarse" ? remesh::SphereMethod::CoarseToFine
                                                      : remesh::SphereMethod::Auto;
    // --gpu: the context must be current on this thread, where remesh() calls the sampler
    std::optional<render::OffscreenContext> context;
    if (opt.gpu)
    {
        auto made = render::OffscreenContext::create();
        if (!made)
        {
            spdlog::error("remesh --gpu: no OpenGL 3.3 context: {} [{}]", made.error().message,
                          core::to_string(made.error().code));
            return k_exit_failure;
        }
        context.emplace(std::move(*made));
        spdlog::debug("remesh: GPU sampler on {} ({})", context->description(),
                      render::to_string(context->backend()));
        // The gnomonic map puts every node on a pixel centre of its face's view: the paper's
        // colour look-up. Any other map: the GPU locates, the CPU interpolates (docs/remesh.md
        // §3.1).
        settings.sampler_name = gnomonic ? "gpu" : "gpu-located";
        settings.sampler =
            [gnomonic](const core::TetraGrid& grid, const core::Vec3Field<double>& domain,
                       const mesh::TriMesh& mesh,
                       std::span<const core::Vec3> sphere) -> core::Result<core::Vec3Field<double>>
        {
            render::GpuSampleStats stats;
            if (gnomonic)
            {
                auto samples = render::sample_on_gpu(grid, domain, sphere, mesh.positions,
                                                     mesh.faces, {}, &stats);
                if (samples)
                    spdlog::debug(
                        "remesh: GPU sampled {} nodes in {} views of {} px ({} px per "
                        "cell), {} overlapping, {:.3f} s",
                        stats.samples, stats.views, stats.viewport, stats.pixels_per_cell,
                        stats.overlaps, stats.seconds_render);
                return samples;
            }
            auto faces = render::locate_on_gpu(grid, domain, sphere, mesh.faces, {}, &stats);
            if (!faces)
                return faces.error();
            remesh::SampleStats walk;
            auto samples = remesh::sample_surface(grid, domain, mesh, sphere, &walk, *faces);
            if (samples)
                spdlog::debug(
                    "remesh: GPU located {} nodes in {} views of {} px ({} px per "
                    "cell, {:.3f} s); the CPU's walks from there took {} steps",
                    stats.samples, stats.views, stats.viewport, stats.pixels_per_cell,
                    stats.seconds_render, walk.walk_steps);
            return samples;
        };
    }
    ProgressBar bar(global);
    bar.stop_on(install_interrupt_flag());  // Ctrl-C: stop, write nothing
    auto result = remesh::remesh(*m, settings, &bar);
    if (!result)
    {
        if (result.error().code == core::ErrorCode::Cancelled)
        {
            spdlog::error("{}; nothing written", result.error().message);
            return k_exit_interrupted;
        }
        if (opt.gpu && result.error().code == core::ErrorCode::GraphicsError)
        {
            spdlog::error("remesh --gpu: {} [{}]", result.error().message,
                          core::to_string(result.error().code));
            return k_exit_failure;
        }
        core::Error e = result.error();
        // Name the file, and for a map that folded under a method the user chose, the way out.
        if (e.message.rfind(input.filename().string(), 0) != 0)
            e.message = input.filename().string() + ": " + e.message;
        if (e.code == core::ErrorCode::InvertedTriangles && opt.method == "spring")
            e.message +=
                "; --method auto (the default) goes on coarse-to-fine when the spring "
                "embedder folds";
        return report(e);
    }

    const remesh::QualityReport& q = result->report;
    const std::size_t allowed = q.input_checked ? q.input_intersections : 0;
    if (q.untangle.intersections > allowed || q.untangle.folded > 0)
        spdlog::warn(
            "remesh: the output has {} intersecting triangle pairs (the input {}) and {} folded "
            "triangles: {} (docs/remesh.md §3.2)",
            q.untangle.intersections,
            q.input_checked ? std::to_string(q.input_intersections) : std::string("unchecked"),
            q.untangle.folded,
            opt.no_untangle ? "the sampling made them and --no-untangle kept them, so the surface "
                              "stays closer to the input but folds over or crosses itself; leave "
                              "--no-untangle out for a surface without them, at some distance "
                              "from the input (\"What untangling costs\")"
                            : "the remesher added self-intersections or folds that untangling "
                              "could not remove; try another --level");

    core::Result<void> written;
    if (ext == ".pgrid")
        written =
            core::save_grid(opt.output, core::make_geometry_file(result->grid, result->positions));
    else if (ext == ".pfm")
        written = core::save_pfm(opt.output, result->positions);
    else
        written =
            mesh::export_mesh(opt.output, remesh::grid_surface(result->grid, result->positions));
    if (!written)
        return report(written.error());

    const std::string json = remesh::to_json(result->report);
    if (!opt.report.empty())
        if (auto ok = core::write_text_file(opt.report, json, "remesh: --report"); !ok)
            return report(ok.error());
    // Ctrl-C while the files were written (the write is not stopped midway: a file is written
    // whole or not at all): the files stay, and a script sees the interruption.
    if (bar.stop_requested())
    {
        spdlog::error("remesh: interrupted while {} was written; it was written whole",
                      opt.output.string());
        return k_exit_interrupted;
    }
    if (!global.quiet)
        std::fputs(remesh::to_text(result->report).c_str(), stdout);
    spdlog::debug("remesh: wrote {}", opt.output.string());
    return 0;
}

void add_remesh_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<RemeshOptions>();
    CLI::App* cmd = app.add_subcommand(
        "remesh",
        "Remesh a closed genus-0 mesh onto the tetrahedral grid (a geometry image).\n\n"
        "The mesh is validated first (see `pliant info`), mapped onto the unit sphere without\n"
        "folds (the paper's spring embedder where it suffices, else a coarse-to-fine embedding\n"
        "over a progressive mesh), the grid's tetrahedron is laid on the sphere (equal-area by\n"
        "default, so the samples spread evenly; --domain-map gnomonic for the paper's central\n"
        "projection), and the input surface is sampled at every grid node. A result with\n"
        "inverted triangles is never written. Output triangles that fold over or cross\n"
        "each other where the map is very anisotropic are untangled by moving their samples\n"
        "along the surface (--no-untangle keeps them); a warning says when the output still\n"
        "crosses itself more than the input or has a folded triangle. The quality report\n"
        "(distances, PSNR, stretch, area spread, times) is printed and, with --report,\n"
        "written as JSON (keys in docs/remesh.md).\n\n"
        "--gpu samples on the GPU. The sphere-mapped mesh is rendered from the sphere's centre\n"
        "into a float framebuffer, one view per tetrahedron face. With --domain-map gnomonic\n"
        "this is the reference paper's look-up: original positions as colours, each grid node\n"
        "exactly on a pixel centre; the result matches the CPU sampler within float32 rounding\n"
        "and the rasteriser's sub-pixel snapping (typically 1e-7 to a few 1e-6 of the\n"
        "bounding-box diagonal, docs/remesh.md \"GPU sampling\"). On the equal-area map\n"
        "(default) nodes fall between pixel centres, so the GPU does the point location (the\n"
        "triangle id under each node) and the CPU interpolates from there in double: the same\n"
        "result as the CPU sampler. Needs an OpenGL 3.3 context (EGL surfaceless or OSMesa,\n"
        "no display).\n\n"
        "Exit codes: 0 written; 1 invalid input mesh, an output extension pliant does not\n"
        "write, unwritable output or no fold-free map (inverted-triangles; the message says\n"
        "which rule, file or count); 3 the simplification did not converge, --gpu found no\n"
        "OpenGL 3.3 context or the GPU sampling failed, or out of memory; 2 usage error (an\n"
        "output that would replace the input mesh among them); 130 stopped by Ctrl-C (within a "
        "fraction of a second, about a second\n"
        "at level 10; nothing is written, an earlier file at -o stays as it was).\n\n"
        "Examples:\n"
        "  pliant remesh data/spot.obj --level 7 -o spot.pgrid --report spot.json\n"
        "  pliant remesh scan.ply -o scan.obj\n"
        "  pliant remesh data/spot.obj --level 7 -o spot.pgrid --gpu");
    cmd->add_option("mesh", opt->mesh, "Closed genus-0 mesh (default: the bundled spot.obj)");
    cmd->add_option("-l,--level", opt->level, "Grid level n (W = 2^n, 2W^2+2 vertices)")
        ->check(whole_number_in(1, 10))
        ->capture_default_str();
    cmd->add_option("-o,--output", opt->output, "Output: .pgrid, .obj, .ply, .gltf, .glb or .pfm")
        ->required();
    cmd->add_option("--report", opt->report, "Write the quality report as JSON to this file");
    cmd->add_option("--method", opt->method,
                    "Sphere map: auto (spring embedder, else coarse-to-fine), spring, coarse")
        ->check(CLI::IsMember({"auto", "spring", "coarse"}))
        ->capture_default_str();
    cmd->add_flag("--no-measure", opt->no_measure,
                  "Skip the distance measurement (about as long as the remeshing itself); the "
                  "--report JSON then has no distance keys");
    cmd->add_flag("--no-untangle", opt->no_untangle,
                  "Keep the samples where the domain map puts them, folds and crossings "
                  "included: closer to the input (higher PSNR), but the surface may fold over "
                  "and cross itself; the report still counts them (docs/remesh.md §3.2, \"What "
                  "untangling costs\")");
    cmd->add_option("--domain-map", opt->domain_map,
                    "Where the grid's nodes lie on the sphere: equal-area (even samples) or "
                    "gnomonic (the paper's central projection)")
        ->check(CLI::IsMember({"equal-area", "gnomonic"}))
        ->capture_default_str();
    cmd->add_flag("--gpu", opt->gpu,
                  "Sample the surface on the GPU (offscreen OpenGL 3.3): the paper's colour "
                  "look-up on the gnomonic map, GPU point location on the equal-area map "
                  "(docs/remesh.md, \"GPU sampling\")");
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_remesh(*opt, global); }));
}

const CommandRegistrar k_register_remesh{{"remesh", 20, &add_remesh_command}};

}  // namespace
}  // namespace pliant::cli
