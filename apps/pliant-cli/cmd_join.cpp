// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant join HOST:PORT [--viewer] [--script F] [--duration S] [--stats F.csv]`: joins a
// collaborative session as a participant or a viewer (docs/session.md).
#include <pliant/net/enet_transport.h>
#include <pliant/net/secure_transport.h>
#include <pliant/session/runner.h>
#include <pliant/session/session.h>

#include <spdlog/spdlog.h>

#include "cli_common.h"
#include "commands.h"
#include "peer_files.h"
#include "stream_options.h"

#include <array>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>

namespace pliant::cli
{
namespace
{

struct JoinOptions
{
    std::string master;
    bool viewer = false;
    std::uint16_t port = 0;
    double duration = 60.0;
    std::string script;
    std::string stats;
    std::string save;         ///< this peer's view of the object, written at the end
    std::uint64_t ticks = 0;  ///< exact mode: stop stepping at this tick (0: never)
    std::string name = "peer";
    std::string passphrase;
    std::string key_file;
    StreamOptions stream;  ///< --compress, --cap, --stream-coarsen
};

int run_join(const JoinOptions& opt, const GlobalOptions& global)
{
    auto master = net::resolve_address(opt.master);
    if (!master)
    {
        // A malformed MASTER is a usage error (2); a host name that does not resolve is the
        // network's failure (3, NetworkError).
        const int status = report(master.error());
        return master.error().code == core::ErrorCode::InvalidArgument ? k_exit_usage : status;
    }
    if (const auto why = undialable(*master, opt.master, opt.port))
    {
        spdlog::error("join: {}", *why);
        return k_exit_usage;
    }
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
        // A viewer's grabs are refused now; faces are checked once the welcome gives the grid.
        if (opt.viewer)
            if (auto ok =
                    session::check_script(run.script, std::numeric_limits<std::int64_t>::max(),
                                          session::SessionRole::Viewer, opt.script);
                !ok)
                return report(ok.error());
    }
    const NamedFile inputs[] = {{opt.script, "--script"}};
    if (auto status = check_peer_outputs("join", inputs, opt.stats, {}, opt.save))
        return *status;
    auto secured = secure_or_plain(net::make_enet_transport(), opt.passphrase, opt.key_file);
    if (!secured)
        return report(secured.error());
    auto transport = std::move(*secured);
    auto bound = transport->open(net::Address{{0, 0, 0, 0}, opt.port});
    if (!bound)
        return report(bound.error());
    if (opt.port == 0 && !opt.viewer)
        spdlog::info(
            "join: listening on port {} (after a failover that makes this peer the "
            "master, joiners dial it there; --port fixes it)",
            bound->port);
    session::SessionSettings settings;
    settings.name = opt.name;
    settings.listen_port = bound->port;
    settings.max_ticks = opt.ticks;
    apply_stream_options(opt.stream, settings);
    auto s = session::Session::join(
        *transport, *master, opt.viewer ? net::Role::Viewer : net::Role::Participant, settings);
    if (!s)
        return report(s.error());
    run.stop = install_interrupt_flag();  // Ctrl-C: leave or end cleanly
    run.secure = dynamic_cast<const net::SecureTransport*>(transport.get());
    auto summary = session::run_peer(**s, run);
    if (!summary)
        return report(summary.error());
    if (!(*s)->refusal().empty())
    {
        spdlog::error("join: {}", (*s)->refusal());
        return k_exit_failure;
    }
    if (!(*s)->ready() && run.stop != nullptr && *run.stop != 0)
    {
        if (!global.quiet)
            std::printf("join: interrupted before the model arrived from %s\n", opt.master.c_str());
        return 0;  // Ctrl-C is a clean end, as after the model
    }
    if (!(*s)->ready())
    {
        if (const auto failure = (*s)->join_failure())
            spdlog::error("{}", join_failure_message(opt.master, *failure, run.secure != nullptr));
        else if (summary->stats.bytes_received == 0)  // --duration ended before any answer
            spdlog::error(
                "join: {} never answered within --duration {:g} s: check the address and port, "
                "that `pliant host` runs there, and that no firewall drops UDP to it",
                opt.master, opt.duration);
        else
            spdlog::error(
                "join: {} answered but the model had not all arrived when --duration "
                "{:g} s ended",
                opt.master, opt.duration);
        return k_exit_failure;
    }
    if (!opt.save.empty())
        if (auto ok = save_peer_state(**s, opt.save); !ok)
            return report(ok.error());
    if (!global.quiet)  // -q: errors only
        std::printf(
            "join (id %u): model in %.2f s; %.1f s, tick %llu, %llu bytes out, %llu bytes in, %s\n",
            static_cast<unsigned>((*s)->id().value), summary->model_s, summary->elapsed_s,
            static_cast<unsigned long long>(summary->final_tick),
            static_cast<unsigned long long>(summary->stats.bytes_sent),
            static_cast<unsigned long long>(summary->stats.bytes_received),
            refused_summary(*transport, summary->auth_refused).c_str());
    return end_status(**s, "join", summary->stats_error);
}

void add_join_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<JoinOptions>();
    CLI::App* cmd = app.add_subcommand(
        "join", "Join a collaborative session as a participant (default) or a viewer.");
    cmd->footer(
        "Examples:\n"
        "  pliant join 127.0.0.1:7777 --script grab.txt --stats peer.csv\n"
        "  pliant join 192.168.1.20:7777 --viewer --duration 30\n"
        "  PLIANT_PASSPHRASE='long shared secret' pliant join 203.0.113.5:7777\n"
        "Use the master's --passphrase/--key-file (or PLIANT_PASSPHRASE): without one the\n"
        "session is unencrypted; with a different one the master refuses the connection.\n"
        "Ctrl-C (or SIGTERM) leaves cleanly: a participant hands its leaves over first.\n\n"
        "Exit codes: 0 the peer ran its --duration, left or saw the session end; 1 bad input (a\n"
        "script line, a --stats/--save path, a key file, --ticks in a fast session; --stats\n"
        "unwritable mid-run); 2 usage error (a MASTER that is malformed or IPv6, 0.0.0.0 or this\n"
        "peer's own --port; two outputs naming one file); 3 the master's host name is not found,\n"
        "the master never answered (given up after about 5 s, or at --duration), refused this\n"
        "peer, or the simulation diverged.");
    cmd->add_option("MASTER", opt->master,
                    "The master's address HOST:PORT: a.b.c.d, localhost or a host name (IPv4)")
        ->required();
    cmd->add_flag("--viewer", opt->viewer, "Only watch (simulate nothing)");
    cmd->add_option("-p,--port", opt->port, "UDP port to listen on for other peers (0: any)")
        ->check(port_number(0))
        ->capture_default_str();
    cmd->add_option("--duration", opt->duration, "Run time [s]")
        ->check(positive_number())
        ->capture_default_str();
    cmd->add_option("--script", opt->script, "Script of timed grabs / leave")
        ->check(existing_input_file("--script"));
    cmd->add_option("--stats", opt->stats, "Per-second statistics CSV");
    cmd->add_option("--ticks", opt->ticks,
                    "Exact sessions: stop stepping at this tick (0: never); give every peer the "
                    "master's --ticks, so that all end on the same state")
        ->check(no_minus_sign())
        ->capture_default_str();
    cmd->add_option("--save", opt->save,
                    "Write what this peer shows at the end to FILE.pgrid (positions, u, v and "
                    "the owner of every node: `pliant render FILE.pgrid --color owner`)");
    cmd->add_option("--name", opt->name, "Peer name (printable ASCII, 1..32)")
        ->capture_default_str();
    add_secret_options(cmd, opt->passphrase, opt->key_file);
    add_stream_options(cmd, opt->stream);
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_join(*opt, global); }));
}

const CommandRegistrar k_register_join{{"join", 51, &add_join_command}};

}  // namespace
}  // namespace pliant::cli
