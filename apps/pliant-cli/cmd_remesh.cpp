// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant remesh [MESH] --level N -o OUT [--report FILE.json]`: remeshes a closed genus-0 mesh
// onto the tetrahedral grid (docs/remesh.md). OUT by extension: .pgrid (native grid file,
// docs/grid-format.md), .obj, .ply, .pfm.
#include <pliant/core/grid_io.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/remesh/remesh.h>
#include <pliant/remesh/sample.h>

#include <spdlog/spdlog.h>

#include "cli_common.h"
#include "commands.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
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
};

std::string lower_extension(const std::filesystem::path& p)
{
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

int run_remesh(const RemeshOptions& opt, const GlobalOptions& global)
{
    const std::filesystem::path input = opt.mesh.empty() ? bundled_mesh() : opt.mesh;
    const std::string ext = lower_extension(opt.output);
    if (ext != ".pgrid" && ext != ".obj" && ext != ".ply" && ext != ".pfm")
        return report(
            {core::ErrorCode::UnsupportedFormat, "remesh: output '" + opt.output.string() +
                                                     "' must end in .pgrid, .obj, .ply or .pfm"});

    auto m = mesh::import_mesh(input);
    if (!m)
        return report(m.error());
    if (auto ok = mesh::validate(*m, input.filename().string()); !ok)
        return report(ok.error());

    remesh::RemeshSettings settings;
    settings.level = opt.level;
    settings.measure = !opt.no_measure || !opt.report.empty();
    settings.sphere.method = opt.method == "spring"   ? remesh::SphereMethod::SpringEmbedder
                             : opt.method == "coarse" ? remesh::SphereMethod::CoarseToFine
                                                      : remesh::SphereMethod::Auto;
    ProgressBar bar(global);
    auto result = remesh::remesh(*m, settings, &bar);
    if (!result)
        return report(result.error());

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
    {
        std::ofstream out(opt.report, std::ios::binary);
        out << json;
        if (!out)
            return report({core::ErrorCode::IoError,
                           "remesh: cannot write report '" + opt.report.string() + "'"});
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
        "over a progressive mesh), the grid's tetrahedron is projected onto the sphere, and the\n"
        "input surface is sampled at every grid node. A result with inverted triangles is never\n"
        "written. The quality report (distances, PSNR, stretch, area spread, times) is printed\n"
        "and, with --report, written as JSON (keys in docs/remesh.md).\n\n"
        "Exit codes: 0 written; 1 invalid input mesh, unwritable output or no fold-free map\n"
        "(inverted-triangles; the message says which rule, file or count); 3 the simplification\n"
        "did not converge; 2 usage error.\n\n"
        "Examples:\n"
        "  pliant remesh data/spot.obj --level 7 -o spot.pgrid --report spot.json\n"
        "  pliant remesh scan.ply -o scan.obj");
    cmd->add_option("mesh", opt->mesh, "Closed genus-0 mesh (default: the bundled spot.obj)");
    cmd->add_option("-l,--level", opt->level, "Grid level n (W = 2^n, 2W^2+2 vertices)")
        ->check(CLI::Range(1, 10))
        ->capture_default_str();
    cmd->add_option("-o,--output", opt->output, "Output: .pgrid, .obj, .ply or .pfm")->required();
    cmd->add_option("--report", opt->report, "Write the quality report as JSON to this file");
    cmd->add_option("--method", opt->method,
                    "Sphere map: auto (spring embedder, else coarse-to-fine), spring, coarse")
        ->check(CLI::IsMember({"auto", "spring", "coarse"}))
        ->capture_default_str();
    cmd->add_flag("--no-measure", opt->no_measure,
                  "Skip the distance measurement (about as long as the remeshing itself)");
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_remesh(*opt, global); }));
}

const CommandRegistrar k_register{{"remesh", 20, &add_remesh_command}};

}  // namespace
}  // namespace pliant::cli
