// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant host [GRID] [--port P] [--mode exact|fast] [--point-clearance auto|grown|inside]
// [--duration S] [--script F] [--stats F.csv]`:
// starts a collaborative session as its master over ENet (docs/session.md).
#include <pliant/core/tetra_grid.h>
#include <pliant/net/enet_transport.h>
#include <pliant/net/secure_transport.h>
#include <pliant/session/runner.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include "cli_common.h"
#include "commands.h"
#include "peer_files.h"
#include "stream_options.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

namespace pliant::cli
{
namespace
{

struct HostOptions
{
    std::string grid;
    int level = 5;
    std::string sphere_map = "equal-area";
    std::uint16_t port = 7777;
    std::string mode = "exact";
    std::string clearance = "auto";
    double duration = 60.0;
    std::string script;
    std::string stats;
    double dt = 0.0;          // 0: automatic (the smaller of 1 ms and 0.9 x the grid's stable step)
    std::uint64_t ticks = 0;  ///< exact mode: stop stepping at this tick (0: never)
    std::string record;       ///< exact mode: the recording, written at the end
    std::string save;         ///< this peer's view of the object, written at the end
    std::string resume;       ///< a saved state to start from instead of rest
    double tension = 1.0;     ///< T [N/m]
    double density = 1.0;     ///< rho [kg/m^2]
    double damping = 0.5;     ///< beta [1/s]
    double foundation = 1.0;  ///< k_f [1/s^2]
    std::optional<double> max_force;  ///< N; unset: sim::default_max_force; 0: no limit
    double max_barrier_wait = 10.0;   ///< s; exact mode: a member holding a tick this long goes
    std::string name = "master";
    std::string passphrase;
    std::string key_file;
    StreamOptions stream;  ///< --compress, --cap, --stream-coarsen
};

int run_host(const HostOptions& opt, const GlobalOptions& global)
{
    auto geometry =
        load_rest_geometry("host", opt.grid, opt.level, 1.0, opt.sphere_map, opt.resume);
    if (!geometry)
        return report(geometry.error());
    const core::TetraGrid& grid = geometry->grid;
    const core::Vec3Field<double>& rest = geometry->positions;
    session::RunOptions run;
    run.duration_s = opt.duration;
    run.stats_csv = opt.stats;
    if (!opt.script.empty())
    {
        auto script = session::load_script(opt.script);
        if (!script)
            return report(script.error());
        run.script = std::move(*script);
        run.script_name = opt.script;
        if (auto ok =
                session::check_script(run.script, static_cast<std::int64_t>(grid.face_count()),
                                      session::SessionRole::Master, opt.script);
            !ok)
            return report(ok.error());
    }
    // --save may name the --resume file: it was read whole at the start, and saving over it
    // is how a session carries on from where it stopped.
    const NamedFile inputs[] = {{opt.grid, "GRID"}, {opt.script, "--script"}};
    if (auto status = check_peer_outputs("host", inputs, opt.stats, opt.record, opt.save))
        return *status;
    if (!opt.resume.empty() && !opt.record.empty())
        return report({core::ErrorCode::InvalidArgument,
                       "host: --record needs a session that starts at rest (`pliant replay` "
                       "replays from rest); leave out --resume or --record"});
    if (opt.mode != "exact" && (opt.ticks != 0 || !opt.record.empty()))
        return report({core::ErrorCode::InvalidArgument,
                       "host: --ticks and --record need --mode exact (a fast session's state "
                       "depends on timing, so it cannot be replayed or stopped on one tick)"});
    auto secured = secure_or_plain(net::make_enet_transport(), opt.passphrase, opt.key_file);
    if (!secured)
        return report(secured.error());
    auto transport = std::move(*secured);
    auto bound = transport->open(net::Address{{0, 0, 0, 0}, opt.port});
    if (!bound)
        return report(bound.error());
    sim::MembraneSettings material;
    material.T = opt.tension;
    material.rho = opt.density;
    material.beta = opt.damping;
    material.k_f = opt.foundation;
    material.fixed_dt = opt.dt > 0.0 ? opt.dt : 1e-3;
    material.fixed_step = opt.mode == "exact";
    if (opt.mode == "exact")
    {
        // Lockstep has no error control: a step above the stability bound grows without limit.
        auto probe = sim::MembraneModel::create(grid, rest, material);
        if (!probe)
            return report(in_grid_file(opt.grid, probe.error()));
        const double stable = sim::stable_fixed_step(*probe);
        if (opt.dt == 0.0)
        {
            material.fixed_dt = std::min(1e-3, 0.9 * stable);
            spdlog::info("host: fixed step {:g} s (the grid's stable step is {:g} s)",
                         material.fixed_dt, stable);
        }
        else if (opt.dt > stable)
            spdlog::warn(
                "host: --dt {:g} s is above this grid's stable fixed step {:g} s "
                "(docs/physics.md §5): the session will likely blow up; use --dt {:g} "
                "or less, or leave --dt out",
                opt.dt, stable, 0.9 * stable);
    }
    std::optional<sim::MembraneState> start;
    if (!opt.resume.empty())
    {
        auto probe = sim::MembraneModel::create(grid, rest, material);
        if (!probe)
            return report(in_grid_file(opt.grid, probe.error()));
        auto saved = load_saved_state(opt.resume, *probe);
        if (!saved)
            return report(saved.error());
        start = std::move(*saved);
        spdlog::info("host: starting from the state saved in {} (time and tick start at 0)",
                     opt.resume);
    }
    session::SessionSettings settings;
    settings.coupling = opt.mode == "exact" ? session::Coupling::Exact : session::Coupling::Fast;
    if (opt.clearance == "grown")
        settings.point_clearance = session::PointClearance::AsGrown;
    else if (opt.clearance == "inside")
        settings.point_clearance = session::PointClearance::Inside;
    settings.max_force = opt.max_force;
    settings.max_barrier_wait_s = opt.max_barrier_wait;
    settings.name = opt.name;
    settings.listen_port = bound->port;
    settings.max_ticks = opt.ticks;
    apply_stream_options(opt.stream, settings);
    auto s = session::Session::host(*transport, grid, rest, material, settings,
                                    start ? &*start : nullptr);
    if (!s)
        return report(in_grid_file(opt.grid, s.error()));
    const double limit = (*s)->model()->settings().max_force;
    spdlog::info(
        "hosting level {} ({} mode, point clearance {}, force limit {}) on port {}, session id "
        "{:#010x}",
        grid.level(), opt.mode,
        (*s)->point_clearance() == session::PointClearance::Inside ? "inside" : "grown",
        limit > 0.0 ? fmt::format("{:.3g} N", limit) : std::string("none"), bound->port,
        (*s)->session_id());
    if (!global.quiet)  // -q: errors only
    {
        std::printf("hosting on port %u\n", static_cast<unsigned>(bound->port));
        std::fflush(stdout);
    }
    if (!opt.record.empty())
        if (auto ok = (*s)->start_recording(); !ok)
            return report(ok.error());
    run.stop = install_interrupt_flag();  // Ctrl-C: leave or end cleanly
    run.secure = dynamic_cast<const net::SecureTransport*>(transport.get());
    auto summary = session::run_peer(**s, run);
    if (!summary)
        return report(summary.error());
    if (!opt.record.empty())
    {
        auto recorded = save_master_recording(**s, opt.record);
        if (!recorded)
            return report(recorded.error());
        if (recorded->covered == 0)
            spdlog::warn(
                "host: {}: the master owned no node at the end, so the recording "
                "holds no final hash; `pliant replay` replays it without a check",
                opt.record);
        else if (!global.quiet)
            std::printf(
                "host: recorded %s: final hash of tick %llu over the master's %zu of "
                "%zu nodes\n",
                opt.record.c_str(), static_cast<unsigned long long>(summary->final_tick),
                recorded->covered, recorded->total);
    }
    if (!opt.save.empty())
        if (auto ok = save_peer_state(**s, opt.save); !ok)
            return report(ok.error());
    if (!(*s)->refusal().empty())
    {
        // Paused past the others' timeout: they went on without this master (the recording
        // and --save above keep what it had).
        spdlog::error("host: {}", (*s)->refusal());
        return k_exit_failure;
    }
    if (!global.quiet)
        std::printf("host: %.1f s, tick %llu, %llu bytes out, %llu bytes in, %s\n",
                    summary->elapsed_s, static_cast<unsigned long long>(summary->final_tick),
                    static_cast<unsigned long long>(summary->stats.bytes_sent),
                    static_cast<unsigned long long>(summary->stats.bytes_received),
                    refused_summary(*transport, summary->auth_refused).c_str());
    return end_status(**s, "host", summary->stats_error);
}

void add_host_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<HostOptions>();
    CLI::App* cmd = app.add_subcommand(
        "host", "Start a collaborative session as its master (UDP through ENet).");
    cmd->footer(
        "Peers join with `pliant join HOST:PORT`; the welcome carries the model, so they need no\n"
        "file. exact mode: lockstep with a common fixed step (--dt), identical to one process;\n"
        "fast mode: each peer steps its leaves with its neighbours' streamed state as boundary.\n"
        "--script: timed grabs and leave (docs/session.md); --stats: per-second CSV.\n\n"
        "Examples:\n"
        "  pliant host --duration 30 --stats host.csv            # sphere, level 5, port 7777\n"
        "  pliant host spot.pgrid --port 9000 --mode fast --script grab.txt\n"
        "  pliant host --key-file session.key     # head -c 32 /dev/urandom > session.key\n"
        "  pliant host spot.pgrid --save end.pgrid ... later: pliant host spot.pgrid --resume "
        "end.pgrid\n"
        "--passphrase / --key-file / PLIANT_PASSPHRASE: every datagram authenticated and\n"
        "encrypted; peers without the same secret are refused (docs/operations.md).\n"
        "Ctrl-C (or SIGTERM) ends the session cleanly for every peer before --duration.");
    cmd->add_option("GRID", opt->grid,
                    "Rest geometry (.pgrid from `pliant remesh`); omitted: a sphere of --level");
    cmd->add_option("-l,--level", opt->level, "Sphere level when GRID is omitted")
        ->check(whole_number_in(1, 10))
        ->capture_default_str();
    cmd->add_option("--sphere-map", opt->sphere_map,
                    "How the sphere's grid lies on it when GRID is omitted: equal-area (even "
                    "cells) or gnomonic (the paper's central projection)")
        ->check(CLI::IsMember({"equal-area", "gnomonic"}))
        ->capture_default_str();
    cmd->add_option("-p,--port", opt->port, "UDP port to listen on")
        ->check(port_number(1))
        ->capture_default_str();
    cmd->add_option("--mode", opt->mode, "Coupling: exact or fast")
        ->check(CLI::IsMember({"exact", "fast"}))
        ->capture_default_str();
    cmd->add_option("--point-clearance", opt->clearance,
                    "Room the partition leaves around each participant's point of interest: "
                    "grown (no border nearer a grab than a share grown around it: the most "
                    "accurate fast mode), inside (the point's leaf and its neighbours in the "
                    "participant's own band: bands cost less to step), auto (fast: grown, "
                    "exact: inside; exact mode's state does not depend on the borders)")
        ->check(CLI::IsMember({"auto", "grown", "inside"}))
        ->capture_default_str();
    cmd->add_option("--duration", opt->duration, "Run time [s]")
        ->check(positive_number())
        ->capture_default_str();
    cmd->add_option("--script", opt->script, "Script of timed grabs / leave")
        ->check(existing_input_file("--script"));
    cmd->add_option("--stats", opt->stats, "Per-second statistics CSV");
    cmd->add_option("--dt", opt->dt,
                    "Fixed step of exact mode [s]; default: the smaller of 1 ms and 0.9 x the "
                    "grid's stable step (a warning says when a given step is above it)")
        ->check(positive_number());
    cmd->add_option("--ticks", opt->ticks,
                    "Exact mode: stop stepping at this tick (0: never) and stream on until "
                    "--duration; give the participants the same --ticks, so that all end on the "
                    "same state")
        ->check(no_minus_sign())
        ->capture_default_str();
    cmd->add_option("--record", opt->record,
                    "Exact mode: record every peer's forces into FILE.prec, with the hash of the "
                    "final state; `pliant replay FILE.prec` checks one process reproduces it");
    cmd->add_option("--save", opt->save,
                    "Write what this peer shows at the end to FILE.pgrid (positions, u, v and "
                    "the owner of every node: `pliant render FILE.pgrid --color owner`)");
    cmd->add_option("--resume", opt->resume,
                    "Start from a saved state of GRID (u and v of a --save, demo's final.pgrid, "
                    "`replay -o` or a `simulate` frame) instead of at rest; time and tick start "
                    "at 0; not with --record")
        ->check(existing_input_file("--resume"));
    cmd->add_option("--tension", opt->tension, "Membrane tension T [N/m]")
        ->check(positive_number())
        ->capture_default_str();
    cmd->add_option("--density", opt->density, "Areal density rho [kg/m^2]")
        ->check(positive_number())
        ->capture_default_str();
    cmd->add_option("--damping", opt->damping, "Nodal velocity damping beta [1/s]")
        ->check(non_negative_number())
        ->capture_default_str();
    cmd->add_option("--foundation", opt->foundation,
                    "Elastic foundation k_f [1/s^2]: pulls the surface back to rest")
        ->check(non_negative_number())
        ->capture_default_str();
    cmd->add_option("--max-force", opt->max_force,
                    "Largest force [N] any peer's grab applies; a longer one acts scaled down "
                    "to it. Default: the force that holds a patch of a tenth of the object's "
                    "radius R a diameter from rest, (rho pi (R/10)^2 k_f + 2 pi T) 2R; 0: no "
                    "limit")
        ->check(non_negative_number());
    cmd->add_option("--max-barrier-wait", opt->max_barrier_wait,
                    "Exact mode: a participant that publishes no step for this long [s] while "
                    "the others wait for it (a hung or stopped process whose connection stays "
                    "up) is removed, and its share continues from its last streamed state; 0: "
                    "wait for ever")
        ->check(non_negative_number())
        ->capture_default_str();
    cmd->add_option("--name", opt->name, "Peer name (printable ASCII, 1..32)")
        ->capture_default_str();
    add_secret_options(cmd, opt->passphrase, opt->key_file);
    add_stream_options(cmd, opt->stream);
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_host(*opt, global); }));
}

const CommandRegistrar k_register_host{{"host", 50, &add_host_command}};

}  // namespace
}  // namespace pliant::cli
