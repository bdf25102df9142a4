// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant refine GRID --levels K -o OUT`: modified butterfly refinement of a native grid file
// (docs/subdivision.md). Every channel of the file (positions px/py/pz and any other per-node
// field, e.g. a displacement u) is refined by the same operator; OUT is a .pgrid with the same
// channels, or an .obj/.ply/.gltf/.glb surface of the refined positions.
#include <pliant/core/grid_io.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/mesh/io.h>
#include <pliant/subdiv/refine.h>

#include <spdlog/spdlog.h>

#include "cli_common.h"
#include "commands.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace pliant::cli
{
namespace
{

struct RefineOptions
{
    std::filesystem::path grid;
    std::filesystem::path out;
    int levels = 1;
    int threads = 1;
};

int run_refine(const RefineOptions& opt, const GlobalOptions& global)
{
    warn_if_more_threads_than_cores(opt.threads, "-j");
    using core::ErrorCode;
    const std::string ext = lower_extension(opt.out);
    if (ext != ".pgrid" && ext != ".obj" && ext != ".ply" && ext != ".gltf" && ext != ".glb")
        return report({ErrorCode::UnsupportedFormat,
                       "refine: output " + opt.out.string() +
                           " must end in .pgrid (native grid), .obj, .ply, .gltf or .glb"});
    std::error_code ec;
    if (!std::filesystem::is_regular_file(opt.grid, ec))
        return report({ErrorCode::IoError,
                       "refine: " + opt.grid.string() +
                           (std::filesystem::exists(opt.grid, ec) ? ": not a regular file"
                                                                  : ": no such file") +
                           " (expected a .pgrid grid file; make one with `pliant remesh`)"});
    // Before the work, not after it; nothing is created (the output is written whole at the end).
    if (auto ok = check_writable(opt.out, "refine: -o"); !ok)
        return report(ok.error());
    const NamedFile inputs[] = {{opt.grid, "GRID"}};
    const NamedFile outputs[] = {{opt.out, "-o"}};
    if (const auto clash = file_clash(inputs, outputs))
    {
        spdlog::error("refine: {}", *clash);
        return k_exit_usage;
    }
    // Ctrl-C: stop between levels and channels, or while an OBJ/PLY is formatted; nothing
    // is written.
    ProgressBar bar(global);
    bar.stop_on(install_interrupt_flag());
    const auto interrupted = [&]
    {
        spdlog::error("refine: interrupted; {} not written", opt.out.string());
        return k_exit_interrupted;
    };

    auto file = core::load_grid(opt.grid);
    if (!file)
        return report(file.error());
    const int level = file->level;
    // The finest level first: "--levels 0 or fewer" is no advice (--levels starts at 1).
    if (level >= core::k_max_level)
        return report({ErrorCode::InvalidArgument, "refine: " + opt.grid.string() +
                                                       " is already at the finest level " +
                                                       std::to_string(core::k_max_level) +
                                                       ": there is nothing finer to refine to"});
    if (level + opt.levels > core::k_max_level)
        return report({ErrorCode::InvalidArgument,
                       "refine: " + opt.grid.string() + " is level " + std::to_string(level) +
                           "; level " + std::to_string(level) + " + " + std::to_string(opt.levels) +
                           " = " + std::to_string(level + opt.levels) +
                           " exceeds the finest level " + std::to_string(core::k_max_level) +
                           " (use --levels " + std::to_string(core::k_max_level - level) +
                           " or fewer)"});

    auto grid = core::TetraGrid::create(level);
    if (!grid)
        return report(grid.error());
    // Checks that the file has positions, even when only they are written.
    if (auto geometry = core::geometry_of(*grid, *file); !geometry)
        return report({geometry.error().code, opt.grid.string() + ": " + geometry.error().message});

    auto plans = subdiv::make_plans(level, opt.levels);
    if (!plans)
        return report(plans.error());

    // Each channel at the working ghost width the mask needs.
    std::vector<core::Field<double>> channels;
    channels.reserve(file->fields.size());
    for (const core::NamedField& nf : file->fields)
    {
        core::Field<double>& f = channels.emplace_back(*grid, subdiv::k_refine_ghost);
        for (int y = 0; y < f.ny(); ++y)
            for (int x = 0; x < f.nx(); ++x)
                f.at(x, y) = nf.values.at(x, y);
        core::fill_ghosts(*grid, f);
    }

    const auto start = std::chrono::steady_clock::now();
    for (const subdiv::ConvolutionPlan& plan : *plans)
    {
        const auto t0 = std::chrono::steady_clock::now();
        for (core::Field<double>& f : channels)
        {
            if (bar.stop_requested())
                return interrupted();
            core::Field<double> next(plan.fine_grid(), subdiv::k_refine_ghost);
            subdiv::refine(plan, f, next, opt.threads);
            f = std::move(next);
        }
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count();
        // The threads used: one per 65,536 fine nodes at most (subdiv::refine_threads).
        const int used = subdiv::refine_threads(plan, opt.threads);
        spdlog::debug(
            "refine: level {} -> {}: {:.3f} ms for {} channel(s), {} grid nodes ({} "
            "surface vertices), {} thread(s){}",
            plan.coarse_level(), plan.fine_level(), ms, channels.size(),
            plan.fine_grid().node_count(), plan.fine_grid().unique_count(), used,
            used < opt.threads
                ? fmt::format(" (-j {}: at most one per 65,536 fine nodes)", opt.threads)
                : std::string());
    }
    const double total_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const core::TetraGrid& fine = plans->back().fine_grid();

    // Owners are labels, not a smooth field: a fine node takes the owner of the coarse node at
    // its rounded-down coarse position (as `render --level-up` draws them), twins their
    // canonical node's, so no fractional id appears along the borders between peers.
    for (std::size_t i = 0; i < channels.size(); ++i)
        if (file->fields[i].name == "owner")
        {
            const core::Field<double>& coarse = file->fields[i].values;
            core::Field<double>& f = channels[i];
            for (int y = 0; y < fine.ny(); ++y)
                for (int x = 0; x < fine.nx(); ++x)
                {
                    const core::GridCoord c = fine.coord(fine.canonical(fine.index(x, y)));
                    f.at(x, y) = coarse.at(c.x >> opt.levels, c.y >> opt.levels);
                }
        }

    core::GridFile out;
    out.level = fine.level();
    for (std::size_t i = 0; i < channels.size(); ++i)
    {
        core::Field<double> plain(fine, 0);
        for (int y = 0; y < plain.ny(); ++y)
            for (int x = 0; x < plain.nx(); ++x)
            {
                // The mask's sums can overflow values near the largest double.
                const double v = channels[i].at(x, y);
                if (!std::isfinite(v))
                    return report({ErrorCode::InvalidArgument,
                                   "refine: " + opt.grid.string() + ": refining channel '" +
                                       file->fields[i].name + "' gave a value that is not finite " +
                                       "(the input's values are too large for the mask's sums); "
                                       "nothing written"});
                plain.at(x, y) = v;
            }
        out.fields.push_back({file->fields[i].name, std::move(plain)});
    }

    if (bar.stop_requested())
        return interrupted();
    if (ext == ".pgrid")
    {
        if (auto saved = core::save_grid(opt.out, out); !saved)
            return report(saved.error());
    }
    else
    {
        auto positions = core::geometry_of(fine, out);
        if (!positions)
            return report(positions.error());
        const mesh::TriMesh surface = mesh::from_grid(fine, *positions);
        // Cancelled: Ctrl-C while the file was formatted (nothing written), or while its
        // writing waited on a FIFO (the message says which; exit 130 either way).
        if (auto saved = mesh::export_mesh(opt.out, surface, &bar); !saved)
            return saved.error().code == ErrorCode::Cancelled &&
                           saved.error().message.find(": cancelled during ") != std::string::npos
                       ? interrupted()
                       : report(saved.error());
    }
    // Ctrl-C while the file was written (a file is written whole or not at all): it stays, and
    // a script sees the interruption (it exited 0).
    if (bar.stop_requested())
    {
        spdlog::error("refine: interrupted while {} was written; it was written whole",
                      opt.out.string());
        return k_exit_interrupted;
    }
    spdlog::debug("refine: {} levels in {:.3f} ms", opt.levels, total_ms);
    if (!global.quiet)
        std::printf("%s: level %d -> %d, %zu vertices, %zu faces, %zu channel(s) -> %s\n",
                    opt.grid.string().c_str(), level, fine.level(), fine.unique_count(),
                    fine.face_count(), channels.size(), opt.out.string().c_str());
    return 0;
}

void add_refine_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<RefineOptions>();
    CLI::App* cmd = app.add_subcommand(
        "refine",
        "Refine a grid by modified butterfly subdivision (interpolating: the input nodes keep "
        "their positions; each level quadruples the faces).");
    cmd->footer(
        "Every channel of GRID (positions px/py/pz and any other per-node field such as a\n"
        "displacement u) is refined by the same operator. A .pgrid OUT keeps all channels; an\n"
        ".obj, .ply, .gltf or .glb OUT gets the refined surface (2W^2+2 vertices, 4W^2 faces,\n"
        "W = 2^level; glTF stores float32, a .gltf writes its buffer to OUT's stem + .bin).\n"
        "The level of GRID plus --levels may be at most 10.\n\n"
        "Examples:\n"
        "  pliant refine spot.pgrid --levels 2 -o spot_fine.pgrid\n"
        "  pliant refine spot.pgrid --levels 3 -o spot_fine.obj --verbose   # timing per level");
    cmd->add_option("GRID", opt->grid, "Input grid file (.pgrid, from `pliant remesh`)")
        ->required();
    cmd->add_option("-l,--levels", opt->levels, "Number of levels to refine (level + K <= 10)")
        ->check(whole_number_in(1, 9))
        ->capture_default_str();
    cmd->add_option("-o,--output", opt->out, "Output file: .pgrid, .obj, .ply, .gltf or .glb")
        ->required();
    cmd->add_option("-j,--threads", opt->threads,
                    "Threads for the convolution (results are identical for any count)")
        ->check(whole_number_in(1, 256))
        ->capture_default_str();
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_refine(*opt, global); }));
}

const CommandRegistrar k_register_refine{{"refine", 30, &add_refine_command}};

}  // namespace
}  // namespace pliant::cli
