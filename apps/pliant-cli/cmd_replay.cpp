// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant replay RECORDING [-o OUT] [--until TICK] [--threads N]`: replays a session's recorded
// inputs (`pliant demo`, `pliant host --record`) on one process, checks the final state against
// the hash the session recorded, and exports the deformed surface.
#include <pliant/core/grid_io.h>
#include <pliant/mesh/io.h>
#include <pliant/session/recording.h>

#include <spdlog/spdlog.h>

#include "cli_common.h"
#include "commands.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace pliant::cli
{
namespace
{

struct ReplayOptions
{
    std::filesystem::path recording;
    std::filesystem::path out;
    std::optional<std::uint64_t> until;  ///< unset: the recording's end
    int threads = 1;
};

int run_replay(const ReplayOptions& opt, const GlobalOptions& global)
{
    warn_if_more_threads_than_cores(opt.threads, "-j");
    const std::string ext = lower_extension(opt.out);
    if (!opt.out.empty() && ext != ".pgrid" && ext != ".obj" && ext != ".ply" && ext != ".gltf" &&
        ext != ".glb")
        return report({core::ErrorCode::UnsupportedFormat,
                       "replay: output " + opt.out.string() +
                           " must end in .pgrid (u, v and deformed positions), .obj, .ply, .gltf "
                           "or .glb"});
    // Before the replay, not after it (nothing is created).
    if (!opt.out.empty())
        if (auto ok = check_writable(opt.out, "replay: -o"); !ok)
            return report(ok.error());
    const NamedFile inputs[] = {{opt.recording, "RECORDING"}};
    const NamedFile outputs[] = {{opt.out, "-o"}};
    if (const auto clash = file_clash(inputs, outputs))
    {
        spdlog::error("replay: {}", *clash);
        return k_exit_usage;
    }
    auto recording = session::load_recording(opt.recording);
    if (!recording)
        return report(recording.error());
    if (opt.until && *opt.until > recording->final_tick)
        return report(
            {core::ErrorCode::InvalidArgument, "replay: --until " + std::to_string(*opt.until) +
                                                   " is past the recording's "
                                                   "last tick " +
                                                   std::to_string(recording->final_tick)});
    ProgressBar progress(global);
    progress.stop_on(install_interrupt_flag());  // Ctrl-C: stop, write nothing
    auto result = session::replay(*recording, opt.threads, opt.until, &progress);
    if (!result)
    {
        if (result.error().code == core::ErrorCode::Cancelled)
        {
            spdlog::error("{}; nothing written (--until replays part of a recording)",
                          result.error().message);
            return k_exit_interrupted;
        }
        // "rec.prec: model blob: grid level 11, ...": the file whose content is refused.
        return report(
            {result.error().code, opt.recording.string() + ": " + result.error().message});
    }
    const core::TetraGrid& grid = result->model.grid();
    const std::uint64_t hash =
        session::state_hash(grid, result->state.u, result->state.v, recording->hash_mask);
    const std::size_t covered = session::hash_mask_count(grid, recording->hash_mask);
    // -q: errors only (the exit status says whether the replay matched).
    const bool say = !global.quiet;
    if (say)
        std::printf(
            "replayed %llu ticks (%.3f s at a fixed step of %.4g s), level %d, %zu force "
            "lists\n",
            static_cast<unsigned long long>(result->state.tick), result->state.time,
            result->model.settings().fixed_dt, grid.level(), recording->forces.size());
    if (say && covered == grid.unique_count())
        std::printf("final state hash %016llx\n", static_cast<unsigned long long>(hash));
    else if (say)
        std::printf(
            "final state hash %016llx over the %zu of %zu nodes the recording's hash "
            "covers (the master's own)\n",
            static_cast<unsigned long long>(hash), covered, grid.unique_count());
    int rc = 0;
    if (result->diverged)
    {
        spdlog::error(
            "replay: the step from tick {} gave non-finite values: the replay stopped "
            "there, {} ticks before the recording's end{} (a recording no session of "
            "this build made)",
            *result->diverged, recording->final_tick - *result->diverged,
            opt.out.empty() ? "" : "; -o gets the last finite state");
        rc = k_exit_failure;
    }
    else if (opt.until && *opt.until != recording->final_tick)
    {
        if (say)
            std::printf("stopped before the recording's end: no recorded hash to compare\n");
    }
    else if (recording->final_hash == 0)
    {
        if (say)
            std::printf("the recording holds no final hash to compare with\n");
    }
    else if (result->coupling == session::Coupling::Fast)
    {
        if (say)
            std::printf(
                "fast coupling: a replay reproduces the inputs, not the timing-dependent "
                "state (recorded hash %016llx)\n",
                static_cast<unsigned long long>(recording->final_hash));
    }
    else if (hash == recording->final_hash)
    {
        if (say)
            std::printf("bit-identical to the recorded session\n");
    }
    else
    {
        spdlog::error("replay: the state differs from the recorded session's (hash {:016x})",
                      recording->final_hash);
        rc = k_exit_failure;
    }
    if (!opt.out.empty())
    {
        core::Vec3Field<double> positions;
        result->model.positions(result->state.u, positions);
        core::Result<void> written;
        if (ext == ".pgrid")
        {
            core::GridFile file = core::make_geometry_file(grid, positions);
            for (const auto& [name, field] :
                 {std::pair{"u", &result->state.u}, std::pair{"v", &result->state.v}})
            {
                core::Field<double> plain(grid);
                for (int y = 0; y < grid.ny(); ++y)
                    for (int x = 0; x < grid.nx(); ++x)
                        plain.at(x, y) = field->at(x, y);
                file.fields.push_back({name, std::move(plain)});
            }
            written = core::save_grid(opt.out, file);
        }
        else
            written = mesh::export_mesh(opt.out, mesh::from_grid(grid, positions));
        if (!written)
            return report(written.error());
        if (say)
            std::printf("wrote the deformed surface to %s\n", opt.out.string().c_str());
    }
    return rc;
}

void add_replay_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<ReplayOptions>();
    CLI::App* cmd = app.add_subcommand(
        "replay", "Replay a recorded session on one process and check it reproduces the state.");
    cmd->footer(
        "A recording (.prec) holds the model and every peer's force lists with the ticks they\n"
        "applied from; `pliant demo` writes demo-out/session.prec and `pliant host --record F`\n"
        "writes one. In exact coupling the replay reproduces the session's final state bit for\n"
        "bit (exit status 3 if not). -o exports the replayed surface p = P + u N. Ctrl-C stops\n"
        "the replay, writes nothing and exits with status 130.\n\n"
        "Examples:\n"
        "  pliant replay demo-out/session.prec\n"
        "  pliant replay demo-out/session.prec -o final.ply\n"
        "  pliant replay session.prec --until 500 -o tick500.pgrid");
    cmd->add_option("RECORDING", opt->recording, "Recording file (.prec)")
        ->required()
        ->check(existing_input_file("RECORDING"));
    cmd->add_option("-o,--out", opt->out,
                    "Write the final surface: .pgrid, .obj, .ply, .gltf or .glb");
    cmd->add_option("--until", opt->until,
                    "Stop at this tick (0: the rest state the replay starts from; default: the "
                    "recording's end)")
        ->check(no_minus_sign());
    cmd->add_option("-j,--threads", opt->threads, "Threads of the replay (same result)")
        ->check(whole_number_in(1, 256))
        ->capture_default_str();
    cmd->callback(command_callback(global, [opt, &global]() { return run_replay(*opt, global); }));
}

const CommandRegistrar k_register_replay{{"replay", 55, &add_replay_command}};

}  // namespace
}  // namespace pliant::cli
