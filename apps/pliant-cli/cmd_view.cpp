// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant view [GRID|MESH|HOST:PORT]`: the interactive viewer (GLFW + Dear ImGui,
// docs/viewer.md). This file only parses the options; the viewer lives in viewer/ and is built
// when viewer/viewer.cmake finds GLFW and ImGui (PLIANT_HAVE_VIEWER). Without them the command
// still exists and says what to install.
#include "cli_common.h"
#include "commands.h"
#include "peer_files.h"

#ifdef PLIANT_HAVE_VIEWER
#include "viewer/sim_scene.h"
#include "viewer/viewer.h"
#endif

#include <pliant/net/transport.h>

#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>

namespace pliant::cli
{
namespace
{

struct ViewOptions
{
    std::string input;
    int level = 6;
    int display_level = -1;
    std::string size = "1280x720";
    std::string script;
    std::string screenshot;
    double exit_after = 0.0;
    bool participant = false;
    bool level_given = false;  ///< --level on the command line (it applies to a mesh only)
    std::string name = "viewer";
    std::uint16_t port = 0;
    bool no_vsync = false;
    bool hide_panels = false;
    std::string resume;  ///< a saved state of INPUT to start the local simulation from
    std::string passphrase;
    std::string key_file;
};

int run_view(const ViewOptions& opt)
{
#ifdef PLIANT_HAVE_VIEWER
    int w = 0;
    int h = 0;
    char x = 0;
    int used = 0;  // the whole text must be read: "640x480junk" is not a size
    if (std::sscanf(opt.size.c_str(), "%d%c%d%n", &w, &x, &h, &used) != 3 ||
        static_cast<std::size_t>(used) != opt.size.size() || (x != 'x' && x != 'X') || w < 64 ||
        h < 64 || w > 8192 || h > 8192)
    {
        spdlog::error("view: --size {} is not WxH with 64 <= W, H <= 8192", opt.size);
        return k_exit_usage;
    }
    std::error_code ec;
    // INPUT is checked before any window opens: a misspelt file is bad input, whether or not a
    // display is at hand (it was reported as "no display" first).
    if (!opt.input.empty() && !std::filesystem::exists(opt.input, ec))
    {
        auto address = net::resolve_address(opt.input);
        if (!address)
            return report({core::ErrorCode::IoError,
                           "view: " + opt.input +
                               " is neither an existing file nor a HOST:PORT to join "
                               "(a.b.c.d:port, localhost:port or hostname:port): " +
                               address.error().message});
        if (const auto why = undialable(*address, opt.input, opt.port))
        {
            spdlog::error("view: {}", *why);
            return k_exit_usage;
        }
    }
    if (opt.level_given && lower_extension(opt.input) == ".pgrid")
        spdlog::warn("view: --level is the remeshing level of a mesh; {} keeps its own level",
                     opt.input);
    if (opt.participant && !opt.input.empty() && std::filesystem::exists(opt.input, ec))
        spdlog::warn("view: --participant is for joining HOST:PORT; {} is a file, simulated here",
                     opt.input);
    // The screenshot's folder is made as the viewer would, and the path checked, before any
    // window opens: not after the whole run.
    if (!opt.screenshot.empty())
    {
        const std::filesystem::path shot(opt.screenshot);
        if (shot.has_parent_path())
            std::filesystem::create_directories(shot.parent_path(), ec);
        if (auto ok = check_writable(shot, "view: --screenshot"); !ok)
            return report(ok.error());
    }
    std::shared_ptr<const sim::MembraneState> resume_state;
    if (!opt.resume.empty())
    {
        // Checked before any window opens: INPUT must be the rest grid the state belongs to.
        if (lower_extension(opt.input) != ".pgrid")
            return report(
                {core::ErrorCode::InvalidArgument,
                 "view: --resume needs INPUT to be the rest grid (.pgrid) the state "
                 "was simulated on" +
                     (opt.input.empty() ? std::string() : std::string(", not ") + opt.input)});
        auto rest = load_rest_geometry("view", opt.input, opt.level, 1.0, "equal-area", opt.resume);
        if (!rest)
            return report(rest.error());
        auto model = sim::MembraneModel::create(rest->grid, rest->positions,
                                                viewer::default_material(rest->grid.level()));
        if (!model)
            return report(in_grid_file(opt.input, model.error()));
        auto saved = load_saved_state(opt.resume, *model);
        if (!saved)
            return report(saved.error());
        resume_state = std::make_shared<const sim::MembraneState>(std::move(*saved));
    }
    // The secret is derived once (Argon2id takes a while), before any window opens.
    auto secret = session_secret(opt.passphrase, opt.key_file);
    if (!secret)
        return report(secret.error());
    viewer::ViewerOptions v;
    v.secret = *secret;
    v.input = opt.input;
    v.resume = opt.resume;
    v.resume_state = std::move(resume_state);
    v.bundled_mesh = bundled_mesh();
    v.level = opt.level;
    v.display_level = opt.display_level;
    v.width = w;
    v.height = h;
    v.script = opt.script;
    v.screenshot = opt.screenshot;
    v.exit_after = opt.exit_after;
    v.participant = opt.participant;
    v.name = opt.name;
    v.port = opt.port;
    v.vsync = !opt.no_vsync;
    v.hide_panels = opt.hide_panels;
    v.stop = install_interrupt_flag();  // Ctrl-C: close as the window does, exit 130
    return viewer::run_viewer(v);
#else
    (void)opt;
    spdlog::error(
        "view: pliant was built without the viewer (libglfw3-dev, libimgui-dev); install them "
        "and reconfigure");
    return k_exit_failure;
#endif
}

void add_view_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<ViewOptions>();
    CLI::App* cmd = app.add_subcommand(
        "view", "Interactive viewer: simulate, drag the surface, join or host a session.");
    cmd->footer(
        "INPUT is a .pgrid grid, a mesh (remeshed at --level on a worker thread), or HOST:PORT\n"
        "of a session's master, HOST a.b.c.d or a host name (joins as a viewer, or with\n"
        "--participant; when the master does not answer, the window says so in red and a run\n"
        "with --exit-after exits with status 1). Without INPUT the bundled spot.obj is\n"
        "remeshed. Left drag on the surface pulls it; on the background it orbits; the wheel\n"
        "zooms; P or F12 saves a screenshot (the first free pliant-view-NNNN.png); E exports the\n"
        "surface (pliant-view-NNNN.obj, or the Export panel's format); W wireframe; C colouring;\n"
        "Space pause; R rest; H hides the panels; Esc quits. Loading another surface needs the\n"
        "session left first. --script, --screenshot and\n"
        "--exit-after make a headless run for tests (docs/viewer.md); their clocks start when\n"
        "the object shows. Ctrl-C in the terminal closes the viewer as its window does (a\n"
        "session left with its hand-over, --screenshot written), exit status 130. A session\n"
        "with a secret (host/join --passphrase or --key-file) needs the same one here, for\n"
        "joining and for the Session panel's host.\n\n"
        "Examples:\n"
        "  pliant view                                   # the bundled cow, level 6\n"
        "  pliant view spot.pgrid --display-level 8\n"
        "  pliant view 127.0.0.1:7777 --participant\n"
        "  pliant view spot.pgrid --resume end.pgrid     # go on from a saved state\n"
        "  xvfb-run -a pliant view grid.pgrid --script drag.txt --screenshot v.png "
        "--exit-after 3");
    cmd->add_option("INPUT", opt->input, "GRID (.pgrid), MESH, or HOST:PORT");
    CLI::Option* level = cmd->add_option("-l,--level", opt->level, "Remeshing level for a mesh")
                             ->check(whole_number_in(1, 10))
                             ->capture_default_str();
    cmd->add_option("--display-level", opt->display_level,
                    "Display level (butterfly refinement of the simulated surface), from the "
                    "simulation level to simulation level + 3 (at most 10), as the Display "
                    "panel's slider; a level outside is clamped with a warning. Default: "
                    "simulation level + 1, at most 8")
        ->check(whole_number_in(1, 10));
    cmd->add_option("--size", opt->size, "Window size WxH")->capture_default_str();
    cmd->add_option("--script", opt->script, "Timed mouse events (docs/viewer.md)")
        ->check(existing_input_file("--script"));
    cmd->add_option("--screenshot", opt->screenshot, "Write a PNG of the last frame at exit");
    cmd->add_option("--exit-after", opt->exit_after,
                    "Quit this many seconds after the object first shows (0: never)")
        ->check(non_negative_number())
        ->capture_default_str();
    cmd->add_flag("--participant", opt->participant,
                  "Join HOST:PORT as a participant (simulates, may pull)");
    cmd->add_option("--name", opt->name, "Peer name in sessions")->capture_default_str();
    cmd->add_option("-p,--port", opt->port, "UDP port for sessions (0: any)")
        ->check(port_number(0))
        ->capture_default_str();
    add_secret_options(cmd, opt->passphrase, opt->key_file);
    cmd->add_flag("--no-vsync", opt->no_vsync, "Draw as fast as possible (for measuring fps)");
    cmd->add_flag("--hide-panels", opt->hide_panels, "Start with the panels hidden (H toggles)");
    cmd->add_option("--resume", opt->resume,
                    "Start the simulation of INPUT (its rest grid, .pgrid) from a saved state "
                    "(a --save of `host`/`join`, a `simulate` frame, demo's final.pgrid, "
                    "`replay -o`) instead of at rest")
        ->check(existing_input_file("--resume"));
    cmd->callback(command_callback(global,
                                   [opt, level]() -> int
                                   {
                                       opt->level_given = level->count() > 0;
                                       return run_view(*opt);
                                   }));
}

const CommandRegistrar k_register_view{{"view", 65, &add_view_command}};

}  // namespace
}  // namespace pliant::cli
