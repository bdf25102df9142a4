// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant demo`: the README's main job. On the bundled mesh (or --mesh FILE), with no other
// argument: validate and remesh onto the tetrahedral grid, then run a real collaborative session
// on this machine: a master and two participants over UDP on 127.0.0.1 (ENet), each simulating
// the leaves the master gave it around its user's point of interest, two users grabbing
// different parts, and a viewer joining late. Every frame is rendered offscreen from what a peer
// displays (the viewer once it has joined), in owner colours; the master records the inputs and
// the recording is replayed on one process at the end, which must give the same state bit for
// bit. Everything lands in demo-out/.
//
// The peers run in this one thread and share a virtual clock that advances one stream interval
// at a time; each interval is pumped (poll and advance every peer) until every member reached its
// tick. So the frames, the statistics and the recording are the same on a slow machine as on a
// fast one, and the wall time is the cost of the work, not of waiting. Real-time sessions between
// processes are `pliant host` and `pliant join`.
//
// `--view` runs the same peers on a second thread, paced to the wall clock and repeating the
// grabs every --duration seconds, and opens the viewer (GLFW + ImGui) on the main thread, where
// it joins the master over 127.0.0.1 in place of the scripted late viewer; closing the window
// ends the session. No offscreen frames are rendered then, and the replay is left to
// `pliant replay` (the recording is still written).
#include <pliant/core/assert.h>
#include <pliant/core/file_io.h>
#include <pliant/core/grid_io.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/net/enet_transport.h>
#include <pliant/remesh/remesh.h>
#include <pliant/render/draw_settings.h>
#include <pliant/render/framebuffer.h>
#include <pliant/render/grid_renderer.h>
#include <pliant/render/image.h>
#include <pliant/render/offscreen_context.h>
#include <pliant/session/recording.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>
#include <pliant/subdiv/refine.h>

#include <spdlog/spdlog.h>

#include "cli_common.h"
#include "commands.h"

#ifdef PLIANT_HAVE_VIEWER
#include "viewer/viewer.h"
#endif

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace pliant::cli
{
namespace
{

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct DemoOptions
{
    fs::path mesh;
    fs::path out = "demo-out";
    int level = 6;
    int display_levels = 1;
    double duration = 3.0;
    double fps = 12.0;
    double dt = 0.0;  // 0: from the model's stability bound
    int width = 640;
    int height = 480;
    double wall_limit = 600.0;
    bool quick = false;  // applied by the command: the values below for options not given
    bool render = true;
    bool view = false;                 // open the viewer on the running session
    std::filesystem::path screenshot;  // --view: PNG of the viewer's last frame
    double exit_after = 0.0;           // --view: close the viewer after this many seconds
};

/// `--quick`: a small run (the tests'), for each of these options not given on the line.
constexpr int k_quick_level = 5;
constexpr double k_quick_duration = 2.0;
constexpr double k_quick_fps = 6.0;
constexpr int k_quick_width = 320;
constexpr int k_quick_height = 240;

/// The link between the session thread and the viewer of `pliant demo --view`: the session
/// thread announces the master's port once every participant is partitioned (0: it failed
/// before that); the viewer thread asks it to stop when its window closes.
struct LiveLink
{
    std::atomic<bool> stop{false};
    /// The viewer failed: the session's files are not written (they would describe a session
    /// nobody watched, and replace an earlier run's).
    std::atomic<bool> discard{false};
    std::promise<std::uint16_t> master_port;
    std::atomic<bool> announced{false};
    /// Ctrl-C (install_interrupt_flag, installed before the session thread starts).
    const volatile std::sig_atomic_t* interrupt = nullptr;

    void announce(std::uint16_t port)
    {
        if (!announced.exchange(true))
            master_port.set_value(port);
    }
};

double seconds_since(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string fmt(const char* format, double v)
{
    std::array<char, 64> b{};
    std::snprintf(b.data(), b.size(), format, v);
    return b.data();
}

/// A user's grab: a force on the nodes within `radius` of a rest point, held over [start, end).
struct Grab
{
    net::UserForce force;
    core::GridCoord node;  // the grid node nearest the point (for the latency probe)
    double start = 0.0;
    double end = 0.0;
};

/// Two users grabbing opposite ends of the object along its longest axis: the first pulls its
/// end outward, the second pushes its end inward, overlapping in time.
/// The extent of the model's rest bounding box along x, y and z.
core::Vec3 rest_extent(const sim::MembraneModel& model)
{
    const auto& P = model.rest_positions();
    const core::TetraGrid& g = model.grid();
    core::Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            const core::Vec3 p{P[0].at(x, y), P[1].at(x, y), P[2].at(x, y)};
            lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
    return hi - lo;
}

std::array<Grab, 2> make_grabs(const sim::MembraneModel& model, double duration)
{
    const auto& P = model.rest_positions();
    const auto& N = model.normals();
    const core::TetraGrid& g = model.grid();
    const core::Vec3 extent = rest_extent(model);
    const int axis =
        extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    auto coord = [&](core::GridCoord c) { return P[static_cast<std::size_t>(axis)].at(c.x, c.y); };
    core::GridCoord first{0, 0}, second{0, 0};
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            if (coord({x, y}) > coord(first))
                first = {x, y};
            if (coord({x, y}) < coord(second))
                second = {x, y};
        }
    const double diag = core::norm(extent);
    const double radius = 0.08 * diag;
    // Force scale: displaces the grabbed patch by a few per cent of the diagonal against the
    // elastic foundation (static u ~ F / (rho pi r^2 k_f)).
    const double magnitude =
        0.6 * model.settings().rho * 3.14159 * radius * radius * model.settings().k_f * 0.12 * diag;
    auto grab = [&](core::GridCoord c, double sign, double t0, double t1)
    {
        Grab out;
        out.node = c;
        out.force.target.kind = net::TargetKind::Position;
        out.force.target.position = {P[0].at(c.x, c.y), P[1].at(c.x, c.y), P[2].at(c.x, c.y)};
        out.force.target.radius = radius;
        for (std::size_t k = 0; k < 3; ++k)
            out.force.force[k] = sign * magnitude * N[k].at(c.x, c.y);
        out.start = t0;
        out.end = t1;
        return out;
    };
    return {grab(first, +1.0, 0.1 * duration, 0.55 * duration),
            grab(second, -1.0, 0.3 * duration, 0.8 * duration)};
}

/// One peer of the demo: its own UDP socket on 127.0.0.1 and its session.
struct Peer
{
    std::string name;
    std::unique_ptr<net::Transport> transport;
    net::Address address;
    std::unique_ptr<session::Session> session;
};

/// Offscreen pictures of what a peer displays, refined for display, in owner colours.
class FramePainter
{
public:
    static std::optional<FramePainter> create(int width, int height)
    {
        auto ctx = render::OffscreenContext::create();
        if (!ctx)
        {
            spdlog::warn("demo: no offscreen OpenGL ({}); continuing without pictures",
                         ctx.error().message);
            return std::nullopt;
        }
        auto fb = render::Framebuffer::create(width, height, render::PixelFormat::Rgba8, 4);
        auto gr = render::GridRenderer::create();
        if (!fb || !gr)
        {
            spdlog::warn("demo: cannot render offscreen ({}); continuing without pictures",
                         !fb ? fb.error().message : gr.error().message);
            return std::nullopt;
        }
        return FramePainter(std::move(*ctx), std::move(*fb), std::move(*gr), width, height);
    }

    /// Renders `peer`'s displayed surface with `levels` butterfly levels added, to `path`.
    core::Result<void> paint(const session::Session& peer, int levels, const fs::path& path)
    {
        const sim::MembraneModel& model = *peer.model();
        const core::TetraGrid& grid = model.grid();
        model.positions(peer.view_u(), positions_);
        core::Vec3Field<double> shown = positions_;
        if (levels > 0)
        {
            auto refined = subdiv::refine_levels(positions_, levels);
            if (!refined)
                return core::fail(refined.error().code, refined.error().message);
            shown = std::move(*refined);
        }
        if (!display_ || display_->level() != shown[0].level())
            display_ = core::TetraGrid::create(shown[0].level()).value();
        renderer_.upload(*display_, shown, nullptr);
        // Owner of each display node: the owner of the nearest simulation node.
        const auto owners = peer.owners();
        const session::LeafGraph* leaves = peer.leaf_graph();
        owner_ids_.assign(display_->node_count(), render::k_no_owner);
        if (!owners.empty() && leaves != nullptr)
        {
            const int half = levels > 0 ? 1 << (levels - 1) : 0;
            for (int y = 0; y < display_->ny(); ++y)
                for (int x = 0; x < display_->nx(); ++x)
                {
                    const int cx = std::min((x + half) >> levels, grid.nx() - 1);
                    const int cy = std::min((y + half) >> levels, grid.ny() - 1);
                    const auto leaf = leaves->leaf_of(grid.index(cx, cy));
                    owner_ids_[display_->index(x, y).value] =
                        static_cast<std::uint16_t>(owners[leaf].value);
                }
        }
        renderer_.upload_owners(*display_, owner_ids_);
        if (!camera_fixed_)
        {
            draw_.camera.fit_to = renderer_.bounds();
            camera_fixed_ = true;
        }
        framebuffer_.bind();
        renderer_.draw(draw_, width_, height_);
        return render::write_png(path, framebuffer_.read_rgba8());
    }

private:
    FramePainter(render::OffscreenContext ctx, render::Framebuffer fb, render::GridRenderer gr,
                 int width, int height)
        : context_(std::move(ctx)),
          framebuffer_(std::move(fb)),
          renderer_(std::move(gr)),
          width_(width),
          height_(height)
    {
        draw_.color = render::ColorMode::Owner;
        draw_.camera.azimuth_deg = 35.0;
        draw_.camera.elevation_deg = 20.0;
    }

    render::OffscreenContext context_;
    render::Framebuffer framebuffer_;
    render::GridRenderer renderer_;
    int width_ = 0;
    int height_ = 0;
    render::DrawSettings draw_;
    bool camera_fixed_ = false;
    std::optional<core::TetraGrid> display_;
    core::Vec3Field<double> positions_;
    std::vector<std::uint16_t> owner_ids_;
};

/// Writes the session's final state as a .pgrid: deformed positions px/py/pz, u, v, and the
/// owning peer's id per node under `master`'s newest partition (channel "owner"). u and v hold
/// each node's owner's values on canonical nodes; twins are given their canonical's.
core::Result<void> save_final_grid(const fs::path& path, const session::Session& master,
                                   core::Field<double> u, core::Field<double> v)
{
    const sim::MembraneModel& model = *master.model();
    const core::TetraGrid& grid = model.grid();
    core::sync_twins(grid, u);
    core::sync_twins(grid, v);
    core::Vec3Field<double> positions;
    model.positions(u, positions);
    core::GridFile file = core::make_geometry_file(grid, positions);
    core::Field<double> owner(grid, 0, -1.0);
    const std::vector<net::PeerId> owners = master.owners();
    if (const session::LeafGraph* leaves = master.leaf_graph(); leaves != nullptr)
        for (std::uint32_t n = 0; n < grid.node_count(); ++n)
        {
            const std::uint32_t leaf = leaves->leaf_of(core::NodeIndex{n});
            if (leaf < owners.size() && owners[leaf] != net::k_no_peer)
                owner[core::NodeIndex{n}] = owners[leaf].value;
        }
    core::sync_twins(grid, owner);
    file.fields.push_back({"u", std::move(u)});
    file.fields.push_back({"v", std::move(v)});
    file.fields.push_back({"owner", std::move(owner)});
    return core::save_grid(path, file);
}

/// Single-quotes `text` for /bin/sh.
std::string shell_quote(const std::string& text)
{
    std::string out = "'";
    for (const char c : text)
        out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

bool have_tool(const char* probe)
{
    // The whole pipeline's output is discarded, not only its last command's.
    return std::system(("{ " + std::string(probe) + "; } >/dev/null 2>&1").c_str()) == 0;
}

/// An animated GIF of the frames with ImageMagick or ffmpeg, when either is installed.
std::string make_animation(const fs::path& dir, double fps)
{
    const std::string frames = shell_quote((dir / "frame_").string());
    const std::string gif = shell_quote((dir / "demo.gif").string());
    std::string cmd;
    if (have_tool("convert -version | grep -q ImageMagick"))
        cmd = "convert -delay " + std::to_string(std::lround(100.0 / fps)) + " -loop 0 " + frames +
              "*.png -layers Optimize " + gif;
    else if (have_tool("ffmpeg -version"))
        cmd = "ffmpeg -y -loglevel error -framerate " + fmt("%g", fps) + " -i " + frames +
              "%04d.png -vf 'split[a][b];[a]palettegen[p];[b][p]paletteuse' " + gif;
    else
        return "skipped (install imagemagick or ffmpeg)";
    if (std::system((cmd + " >/dev/null 2>&1").c_str()) != 0)
        return "failed: " + cmd;
    return "demo.gif";
}

int run_demo(const DemoOptions& opt_in, const GlobalOptions& global, LiveLink* live_link)
{
    DemoOptions opt = opt_in;
    const bool live = live_link != nullptr;  // --view: paced, repeating, until the window closes
    if (live)
        opt.render = false;
    const auto t_start = Clock::now();
    const fs::path mesh_path = opt.mesh.empty() ? bundled_mesh() : opt.mesh;
    // 1. Import, validate, remesh. A refused mesh leaves --out as it was (not even made).
    auto mesh = mesh::import_mesh(mesh_path);
    if (!mesh)
        return report(mesh.error());
    if (auto ok = mesh::validate(*mesh, mesh_path.filename().string()); !ok)
        return report(ok.error());
    std::error_code ec;
    fs::create_directories(opt.out, ec);
    if (ec)
        return report({core::ErrorCode::IoError,
                       "demo: cannot create " + opt.out.string() + ": " + ec.message()});
    // A folder that exists but cannot be written (/proc/self, read-only) fails now, not after
    // the remeshing (nothing is created by the check).
    if (auto ok = check_writable(opt.out / "summary.md", "demo: --out"); !ok)
        return report(ok.error());
    spdlog::info("demo: {} ({} vertices, {} faces) is a closed genus-0 surface",
                 mesh_path.filename().string(), mesh->vertex_count(), mesh->face_count());
    ProgressBar progress(global);
    // Ctrl-C or SIGTERM: the remeshing stops and nothing is written; the session stops at its
    // next step (with --view: the viewer closes as its window does, and the session with it) and
    // the run ends as usual with what ran (the frames up to the last whole one; the final state,
    // recording and its replay check and the summary at the step reached), exit 130.
    const volatile std::sig_atomic_t* interrupt =
        live ? live_link->interrupt : install_interrupt_flag();
    const auto interrupted = [interrupt] { return interrupt != nullptr && *interrupt != 0; };
    progress.stop_on(interrupt);
    remesh::RemeshSettings rs;
    rs.level = opt.level;
    auto remeshed = remesh::remesh(*mesh, rs, &progress);
    if (!remeshed)
        return report(remeshed.error());
    const core::TetraGrid& grid = remeshed->grid;
    // 2. The material and a common fixed step the explicit integrator is stable at.
    sim::MembraneSettings material;
    material.T = 2.0;
    material.rho = 1.0;
    material.beta = 1.5;
    material.k_f = 6.0;
    material.fixed_step = true;
    auto probe = sim::MembraneModel::create(grid, remeshed->positions, material);
    if (!probe)
        return report(probe.error());
    const double stable = sim::stable_fixed_step(*probe);
    // A step far below the bound gains nothing and could not keep up: a thousandth of it is
    // already 1,000 times the steps a stable run needs (and 1e-300 overflowed the steps per
    // frame below). Checked before an earlier run's outputs go (below), as a refused mesh is.
    if (opt.dt > 0.0 && opt.dt < 1e-3 * stable)
    {
        spdlog::error(
            "demo: --dt {:.3g} s is below a thousandth of the stability bound {:.3g} s "
            "({:.3g} steps per second of session time); give at least {:.3g} s, or "
            "leave --dt out (0.9 x the bound)",
            opt.dt, stable, 1.0 / opt.dt, 1e-3 * stable);
        return k_exit_usage;
    }
    // The run starts: every output of an earlier run goes (a failed start above leaves them),
    // so that the folder never mixes two runs, even when this one fails part-way. Only the
    // demo's own names: frame_NNNN.png (four digits or more), not every frame_* (a simulate
    // run's frame_NNNNN.pgrid in the same folder is the user's).
    const auto is_demo_frame = [](const std::string& name)
    {
        constexpr std::string_view prefix = "frame_", suffix = ".png";
        if (name.size() < prefix.size() + 4 + suffix.size() || !name.starts_with(prefix) ||
            !name.ends_with(suffix))
            return false;
        return std::all_of(name.begin() + prefix.size(), name.end() - suffix.size(),
                           [](char c) { return c >= '0' && c <= '9'; });
    };
    std::size_t removed = 0;
    for (const auto& entry : fs::directory_iterator(opt.out, ec))
    {
        const std::string name = entry.path().filename().string();
        if (entry.is_regular_file(ec) &&
            (is_demo_frame(name) || name == "demo.gif" || name == "demo.mp4" ||
             name == "summary.md" || name == "session.prec" || name == "final.pgrid" ||
             name == "timeline.csv" || name == "grid.pgrid" || name == "remesh-report.json"))
            removed += fs::remove(entry.path(), ec) ? 1 : 0;
    }
    if (removed > 0)
        spdlog::info(
            "demo: removed {} file(s) of an earlier run from {} (frame_NNNN.png, "
            "demo.gif, summary.md, ...)",
            removed, opt.out.string());
    if (auto saved = core::save_grid(opt.out / "grid.pgrid",
                                     core::make_geometry_file(grid, remeshed->positions));
        !saved)
        return report(saved.error());
    if (auto written = core::write_text_file(opt.out / "remesh-report.json",
                                             remesh::to_json(remeshed->report) + "\n", "demo");
        !written)
        return report(written.error());

    const double want = opt.dt > 0.0 ? opt.dt : 0.9 * stable;
    // A whole number of ticks per frame, so every frame shows a tick boundary.
    const auto ticks_per_frame =
        static_cast<std::uint64_t>(std::ceil(1.0 / (opt.fps * want) - 1e-9));
    const double dt = 1.0 / (opt.fps * static_cast<double>(ticks_per_frame));
    if (opt.dt > 0.0 && dt < opt.dt * (1.0 - 1e-9))
        spdlog::info(
            "demo: --dt {:.3g} s rounded down to {:.3g} s, a whole number of steps per "
            "frame of 1/{:g} s",
            opt.dt, dt, opt.fps);
    if (dt > stable)
        spdlog::warn(
            "demo: a step of {:.3g} s is above the stability bound {:.3g} s: the "
            "membrane may blow up (the bound is conservative; the run stops if it does); leave "
            "--dt out (0.9 x the bound)",
            dt, stable);
    // The object's size, the diagonal of its rest bounding box: a displacement beyond it (or a
    // non-finite one) is no deformation this linear membrane describes but a run that diverged.
    const double object_size = core::norm(rest_extent(*probe));
    material.fixed_dt = dt;
    const std::array<Grab, 2> grabs = make_grabs(*probe, opt.duration);

    // 3. Four peers on 127.0.0.1: master, two participants, a viewer that joins late.
    std::array<Peer, 4> peers;
    const std::array<const char*, 4> names{"master", "user-A", "user-B", "viewer"};
    for (std::size_t k = 0; k < peers.size(); ++k)
    {
        Peer& p = peers[k];
        p.name = names[k];
        p.transport = net::make_enet_transport();
        auto bound = p.transport->open(net::Address{{127, 0, 0, 1}, 0});
        if (!bound)
            return report({core::ErrorCode::NetworkError,
                           "demo: cannot open a UDP socket on 127.0.0.1 (" + bound.error().message +
                               "); is the loopback interface up?"});
        p.address = *bound;
    }
    session::SessionSettings settings;
    settings.coupling = session::Coupling::Exact;
    settings.threads = 1;
    auto settings_for = [&](const Peer& p)
    {
        session::SessionSettings s = settings;
        s.name = p.name;
        s.listen_port = p.address.port;
        return s;
    };
    auto hosted = session::Session::host(*peers[0].transport, grid, remeshed->positions, material,
                                         settings_for(peers[0]));
    if (!hosted)
        return report(hosted.error());
    peers[0].session = std::move(*hosted);
    if (auto rec = peers[0].session->start_recording(); !rec)
        return report(rec.error());
    for (std::size_t k = 1; k <= 2; ++k)
    {
        auto joined = session::Session::join(*peers[k].transport, peers[0].address,
                                             net::Role::Participant, settings_for(peers[k]));
        if (!joined)
            return report(joined.error());
        peers[k].session = std::move(*joined);
        peers[k].session->set_points_of_interest({grabs[k - 1].force.target});
    }

    const auto t_session = Clock::now();
    // With --view the session runs until the window closes; --wall-limit still bounds the wait
    // for the participants to be partitioned.
    auto out_of_time = [&]
    {
        if (live && live_link->stop.load())
            return true;
        return (!live || !live_link->announced.load()) && seconds_since(t_session) > opt.wall_limit;
    };
    auto pump = [&](double now)
    {
        for (Peer& p : peers)
            if (p.session)
                p.session->poll();
        for (Peer& p : peers)
            if (p.session)
                p.session->advance(now);
    };
    auto members_at = [&](std::uint64_t tick)
    {
        for (std::size_t k = 0; k < 3; ++k)
            if (peers[k].session->tick() < tick)
                return false;
        return true;
    };
    // Everyone joins and is partitioned before the clock starts.
    while (!out_of_time() && !interrupted())
    {
        pump(0.0);
        auto owners = peers[0].session->owners();
        std::sort(owners.begin(), owners.end());
        if (peers[1].session->ready() && peers[2].session->ready() &&
            std::unique(owners.begin(), owners.end()) - owners.begin() == 3)
            break;
    }
    if (interrupted())
        return report(core::cancelled("demo", "the participants' join"));
    if (out_of_time())
        return report({core::ErrorCode::NetworkError,
                       "demo: the participants were not partitioned within the time limit"});
    const double t_joined = seconds_since(t_session);
    if (live)
        live_link->announce(peers[0].address.port);
    else
        spdlog::info("demo: the peers are partitioned; the session runs ({} steps per frame)",
                     ticks_per_frame);

    // 4. The scripted collaboration, one stream interval of virtual time at a time.
    std::optional<FramePainter> painter;
    if (opt.render)
        painter = FramePainter::create(opt.width, opt.height);
    const int display_levels = std::clamp(opt.display_levels, 0, core::k_max_level - grid.level());
    const int frames = std::max(1, static_cast<int>(std::lround(opt.duration * opt.fps)));
    const int substeps =
        std::max(1, static_cast<int>(std::ceil(settings.stream_rate_hz / opt.fps)));
    const double t_viewer = 0.4 * opt.duration;
    std::array<bool, 2> grabbing{false, false};
    double grab_set_at = -1.0, grab_seen_at = -1.0, grab_received_at = -1.0;
    double viewer_ready_at = -1.0;
    double view_delay_at_seen = 0.0;
    const double probe_base = peers[0].session->view_u().at(grabs[0].node.x, grabs[0].node.y);
    const double received_base = peers[0].session->display_u().at(grabs[0].node.x, grabs[0].node.y);
    std::ofstream energy_csv(opt.out / "timeline.csv");
    // One row per frame: the master's session time and tick, each participant's owned nodes,
    // the largest |u| in the frame shown (the viewer's once it has joined, else the master's).
    energy_csv << "time,ticks,owner_nodes_master,owner_nodes_A,owner_nodes_B,max_u,shown_by\n";
    double max_u = 0.0;         // over every frame shown (the summary's row)
    double diverged_at = -1.0;  // session time of the first frame beyond the object's size
    int painted = 0;
    int frames_run = 0;
    double reached = 0.0;  // session time reached, s
    const auto t_clock = Clock::now();
    for (int frame = 1; live ? !live_link->stop.load() : frame <= frames && !interrupted(); ++frame)
    {
        bool cut_short = false;  // Ctrl-C stopped the stepping within this frame
        for (int sub = 1; sub <= substeps; ++sub)
        {
            const double now = (frame - 1 + static_cast<double>(sub) / substeps) / opt.fps;
            const double previous = (frame - 1 + static_cast<double>(sub - 1) / substeps) / opt.fps;
            if (live)  // the viewer shows the session in real time
                std::this_thread::sleep_until(t_clock + std::chrono::duration_cast<Clock::duration>(
                                                            std::chrono::duration<double>(now)));
            // The users act on what they saw: grabs start and end between intervals (with
            // --view the script repeats every --duration seconds).
            const double phase = live ? std::fmod(previous, opt.duration) : previous;
            for (std::size_t k = 0; k < 2; ++k)
            {
                const bool on = phase >= grabs[k].start && phase < grabs[k].end;
                if (on != grabbing[k])
                {
                    auto ok = peers[k + 1].session->set_forces(
                        on ? std::vector<net::UserForce>{grabs[k].force}
                           : std::vector<net::UserForce>{});
                    PLIANT_ASSERT(ok.has_value(), "demo: a grab the model refuses");
                    grabbing[k] = on;
                    if (k == 0 && on && grab_set_at < 0.0)  // the first grab is timed
                        grab_set_at = previous;
                }
            }
            if (!live && !peers[3].session && previous >= t_viewer)
            {
                auto joined = session::Session::join(*peers[3].transport, peers[0].address,
                                                     net::Role::Viewer, settings_for(peers[3]));
                if (!joined)
                    return report(joined.error());
                peers[3].session = std::move(*joined);
            }
            const auto target = static_cast<std::uint64_t>(std::floor(now / dt + 1e-9));
            // Ctrl-C is heard between steps too: an interval can hold many of them.
            while (!members_at(target) && !out_of_time() && !interrupted())
                pump(now);
            if (!members_at(target) && interrupted())
            {
                cut_short = true;  // the interval was not reached
                break;
            }
            pump(now);  // one more pass streams the states of this interval
            if (live && out_of_time())
                break;  // the viewer's window closed
            if (out_of_time())
                return report({core::ErrorCode::NotConverged,
                               "demo: the session fell behind the wall-clock limit of " +
                                   fmt("%g", opt.wall_limit) +
                                   " s (a heavily loaded machine? try --quick)"});
            if (viewer_ready_at < 0.0 && peers[3].session && peers[3].session->ready())
                viewer_ready_at = now;
            const double seen = peers[0].session->view_u().at(grabs[0].node.x, grabs[0].node.y);
            if (grab_set_at >= 0.0 && grab_seen_at < 0.0 && seen != probe_base)
            {
                grab_seen_at = now;
                view_delay_at_seen = peers[0].session->stats().view_delay_s;
            }
            const double received =
                peers[0].session->display_u().at(grabs[0].node.x, grabs[0].node.y);
            if (grab_set_at >= 0.0 && grab_received_at < 0.0 && received != received_base)
                grab_received_at = now;
            reached = now;
        }
        if ((live && live_link->stop.load()) || cut_short)
            break;  // the frame was not reached: the frames end at the one before
        ++frames_run;
        const bool from_viewer = peers[3].session && peers[3].session->ready();
        const session::Session& shown = *peers[from_viewer ? 3 : 0].session;
        const core::Field<double>& u = shown.view_u();
        double frame_max_u = 0.0;
        bool finite = true;
        for (int y = 0; y < grid.ny(); ++y)
            for (int x = 0; x < grid.nx(); ++x)
            {
                finite = finite && std::isfinite(u.at(x, y));
                frame_max_u = std::max(frame_max_u, std::abs(u.at(x, y)));
            }
        if (!finite)
            frame_max_u = std::numeric_limits<double>::infinity();
        max_u = std::max(max_u, frame_max_u);
        // The master's clock: a viewer simulates nothing, so its own time stays at its join.
        energy_csv << peers[0].session->time() << ',' << peers[0].session->tick();
        for (std::size_t k = 0; k < 3; ++k)
            energy_csv << ',' << peers[k].session->stats().owned_nodes;
        energy_csv << ',' << frame_max_u << ',' << (from_viewer ? "viewer" : "master") << '\n';
        if (frame_max_u > object_size)  // diverged: the run stops, its outputs say so
        {
            diverged_at = reached;
            break;
        }
        if (painter)
        {
            std::array<char, 32> name{};
            std::snprintf(name.data(), name.size(), "frame_%04d.png", frame);
            if (auto w = painter->paint(shown, display_levels, opt.out / name.data()); !w)
                return report(w.error());
            ++painted;
        }
        if (!live)
            progress.update("session + render", static_cast<double>(frame) / frames);
    }
    const double t_run = seconds_since(t_session) - t_joined;
    if (live && live_link->discard.load())
        return k_exit_failure;  // the viewer said why

    // 5. The final state, assembled from every member's own leaves, and its replay.
    core::Field<double> final_u(grid), final_v(grid);
    for (std::size_t k = 0; k < 3; ++k)
    {
        const session::Session& s = *peers[k].session;
        const auto owners = s.owners();
        for (const core::NodeIndex n : grid.node_of_unique())
            if (owners[s.leaf_graph()->leaf_of(n)] == s.id())
            {
                const core::GridCoord c = grid.coord(n);
                final_u.at(c.x, c.y) = s.state().u.at(c.x, c.y);
                final_v.at(c.x, c.y) = s.state().v.at(c.x, c.y);
            }
    }
    session::Recording recording = peers[0].session->recording();
    recording.final_hash = session::state_hash(grid, final_u, final_v);
    // final.pgrid: that state with the master's partition, the owning peer's id per node
    // (channel "owner", docs/grid-format.md), for `pliant render final.pgrid --color owner`.
    if (auto saved = save_final_grid(opt.out / "final.pgrid", *peers[0].session, final_u, final_v);
        !saved)
        return report(saved.error());
    if (auto saved = session::save_recording(opt.out / "session.prec", recording); !saved)
        return report(saved.error());
    std::vector<session::SessionStats> stats;
    std::vector<double> rtt_ms;
    for (Peer& p : peers)
    {
        stats.push_back(p.session ? p.session->stats() : session::SessionStats{});
        double sum = 0.0;
        int n = 0;
        for (const net::PeerHandle h : p.transport->peers())
            if (const auto st = p.transport->stats(h))
            {
                sum += st->rtt_s;
                ++n;
            }
        rtt_ms.push_back(n > 0 ? 1e3 * sum / n : 0.0);
    }
    // The replay check (skipped with --view: a long interactive session is left to
    // `pliant replay`, which checks the same hash).
    const auto t_replay = Clock::now();
    bool identical = true;
    if (!live)
    {
        auto replayed = session::replay(recording);
        if (!replayed)
            return report(replayed.error());
        identical =
            session::state_hash(grid, replayed->state.u, replayed->state.v) == recording.final_hash;
    }
    const double replay_seconds = seconds_since(t_replay);

    // The master ends the session; everyone disconnects (bounded).
    peers[0].session->shutdown();
    for (int k = 0; k < 2000; ++k)
    {
        bool all_left = true;
        for (Peer& p : peers)
            if (p.session)
            {
                p.session->poll();
                all_left = all_left && p.session->left();
            }
        if (all_left)
            break;
    }
    const std::string animation =
        painted > 1 ? make_animation(opt.out, opt.fps) : std::string("skipped (no frames)");

    // 6. Summary.
    const auto& q = remeshed->report;
    std::string table;
    auto row = [&](const std::string& key, const std::string& value)
    {
        table += "| " + key + std::string(key.size() < 34 ? 34 - key.size() : 0, ' ') + " | " +
                 value + " |\n";
    };
    table += "| pliant demo                        | |\n|---|---|\n";
    row("input mesh", mesh_path.filename().string() + " (" + std::to_string(mesh->vertex_count()) +
                          " vertices, " + std::to_string(mesh->face_count()) + " faces)");
    row("grid level / vertices / triangles", std::to_string(grid.level()) + " / " +
                                                 std::to_string(grid.unique_count()) + " / " +
                                                 std::to_string(grid.face_count()));
    row("display level (butterfly)", std::to_string(grid.level() + display_levels));
    row("remesh", fmt("%.2f s", q.total_seconds) + ", " + q.sphere_method + ", PSNR " +
                      (q.measured ? fmt("%.1f dB", q.distance.psnr_db) : std::string("n/a")) +
                      ", inverted triangles " +
                      std::to_string(q.inverted_mesh + q.inverted_domain));
    row("coupling / fixed step", "exact lockstep / " + fmt("%.3f ms", 1e3 * dt) +
                                     " (stability bound " + fmt("%.3f ms)", 1e3 * stable));
    row("simulated time / ticks / frames",
        fmt("%.2f s", reached) + " / " + std::to_string(peers[0].session->tick()) + " / " +
            std::to_string(frames_run) +
            (diverged_at >= 0.0
                 ? (live ? std::string() : " of " + std::to_string(frames)) + " (diverged)"
             : !live && interrupted() && frames_run < frames
                 ? " of " + std::to_string(frames) + " (interrupted: Ctrl-C)"
                 : std::string()));
    row("session wall time", fmt("%.1f s", t_run) + " (" +
                                 fmt("%.2f", reached / std::max(t_run, 1e-9)) +
                                 " x real time, all peers in one thread)");
    // Session time, sampled once per interval of 1/(fps x substeps): the grab reaches the owner
    // at its next tick, the owner's stream (60 Hz) brings the leaf to the master, and the
    // master's view shows it after its interpolation delay (docs/session.md §5.3).
    row("grab -> received / shown by the master",
        (grab_received_at >= 0.0 ? fmt("%.0f ms", 1e3 * (grab_received_at - grab_set_at))
                                 : std::string("never")) +
            " / " +
            (grab_seen_at >= 0.0
                 ? fmt("%.0f ms of session time", 1e3 * (grab_seen_at - grab_set_at)) +
                       " (the view's interpolation delay then: " +
                       fmt("%.0f ms", 1e3 * view_delay_at_seen) + ")"
                 : std::string("not seen")));
    if (live)
        row("viewer", "the window (pliant view), joined over 127.0.0.1");
    else
        row("viewer joined at / shown from",
            peers[3].session ? fmt("%.2f s", t_viewer) + " / " +
                                   (viewer_ready_at >= 0.0 ? fmt("%.2f s", viewer_ready_at)
                                                           : std::string("never"))
                             : fmt("never (due at %.2f s)", t_viewer));
    row("largest displacement shown",
        diverged_at < 0.0 ? fmt("%.4f m", max_u)
                          : fmt("%.3g m: DIVERGED", max_u) + fmt(" at %.2f s", diverged_at) +
                                fmt(" (the object is %.3g m across)", object_size));
    if (live)
        row("replay of session.prec", "not checked with --view (pliant replay checks it)");
    else
        row("replay of session.prec", std::string(identical ? "bit-identical" : "DIFFERS") + " (" +
                                          fmt("%.1f s", replay_seconds) + ", 1 thread)");
    row("frames", painter ? std::to_string(painted) + " PNG frames, animation: " + animation
                          : std::string("skipped"));
    row("total wall time", fmt("%.1f s", seconds_since(t_start)));
    table +=
        "\n| peer | role | owned nodes | steps | step time | sent | received | RTT |\n"
        "|---|---|---:|---:|---:|---:|---:|---:|\n";
    const std::array<const char*, 4> roles{"master", "participant", "participant", "viewer"};
    for (std::size_t k = 0; k < peers.size(); ++k)
    {
        if (!peers[k].session)
            continue;  // --view: the window's own peer is not one of these
        const session::SessionStats& s = stats[k];
        // Simulated seconds the peer took part; under one stream interval (a --view window that
        // could not open) a rate means nothing.
        const double seconds =
            k == 3 && viewer_ready_at >= 0.0 ? reached - viewer_ready_at : reached;
        auto rate = [&](std::uint64_t bytes)
        {
            return seconds * settings.stream_rate_hz >= 1.0
                       ? fmt("%.0f kbit/s", 8e-3 * static_cast<double>(bytes) / seconds)
                       : std::string("-");
        };
        table += "| " + peers[k].name + " | " + roles[k] + " | " + std::to_string(s.owned_nodes) +
                 " | " + std::to_string(s.steps) + " | " +
                 (s.steps > 0 ? fmt("%.3f ms", 1e3 * s.step_seconds / static_cast<double>(s.steps))
                              : std::string("-")) +
                 " | " + rate(s.bytes_sent) + " | " + rate(s.bytes_received) + " | " +
                 fmt("%.1f ms", rtt_ms[k]) + " |\n";
    }
    table += "\nBandwidth is per second of session time (states stream at " +
             fmt("%.0f Hz", settings.stream_rate_hz) +
             "); RTT is ENet's smoothed round trip over 127.0.0.1.\n";
    if (!global.quiet)  // -q: only errors; summary.md holds the table
        std::printf("%s", table.c_str());
    if (auto written = core::write_text_file(opt.out / "summary.md", table, "demo"); !written)
        return report(written.error());
    if (!global.quiet)
        std::printf(
            "\nwrote %s (grid.pgrid, final.pgrid, %s, session.prec, timeline.csv, "
            "remesh-report.json, summary.md)\n",
            opt.out.string().c_str(),
            painted == 0              ? "no frames"
            : animation == "demo.gif" ? "frame_*.png, demo.gif"
                                      : "frame_*.png, no GIF");
    if (diverged_at >= 0.0)
        return report(
            {core::ErrorCode::NotConverged,
             fmt("demo: the membrane diverged at t = %.2f s", diverged_at) +
                 fmt(" (a displacement of %.3g m", max_u) +
                 fmt(", the object is %.3g m across) and the run stopped there; ", object_size) +
                 (dt > stable ? fmt("the step %.3g s", dt) +
                                    fmt(" is above the stability bound %.3g s: leave "
                                        "--dt out",
                                        stable)
                              : std::string("please report it with --mesh and the "
                                            "options given")) +
                 "; " + opt.out.string() + " holds what ran"});
    if (!identical)
        return report({core::ErrorCode::NotConverged,
                       "demo: replaying the recording did not reproduce the session's state"});
    if (!live && interrupted() && frames_run < frames)
    {
        spdlog::error("demo: interrupted after {} of {} frames; {} holds what ran", frames_run,
                      frames, opt.out.string());
        return k_exit_interrupted;
    }
    return 0;
}

/// `pliant demo --view`: the session on a second thread, the viewer on this one.
int run_demo_with_viewer(const DemoOptions& opt, const GlobalOptions& global)
{
#ifdef PLIANT_HAVE_VIEWER
    // No display: say so before any work, and leave --out as it is.
    if (std::string why; !viewer::display_available(&why))
    {
        spdlog::error(
            "demo --view: {} (set DISPLAY, run under `xvfb-run -a`, or run the demo "
            "without --view to render frames offscreen)",
            why);
        return k_exit_failure;
    }
    // The screenshot's path is checked before the run, as `pliant view` does: a bad one found
    // at the end failed the whole run and left no outputs.
    if (!opt.screenshot.empty())
    {
        std::error_code ec;
        if (opt.screenshot.has_parent_path())
            std::filesystem::create_directories(opt.screenshot.parent_path(), ec);
        if (auto ok = check_writable(opt.screenshot, "demo --view: --screenshot"); !ok)
            return report(ok.error());
    }
    LiveLink link;
    link.interrupt = install_interrupt_flag();
    std::future<std::uint16_t> port = link.master_port.get_future();
    int demo_rc = 0;
    std::thread session_thread(
        [&]
        {
            // Out of memory here would end the process (an exception leaving a thread): it
            // ends the session instead (said at once; the window shows the session gone), and
            // the demo exits 3 once the window is closed.
            try
            {
                demo_rc = run_demo(opt, global, &link);
            }
            catch (const std::bad_alloc&)
            {
                demo_rc = report_out_of_memory();
            }
            link.announce(0);  // no-op when the session was announced
        });
    const std::uint16_t master = port.get();
    int view_rc = 0;
    if (master != 0)
    {
        // Out of memory in the viewer ends it as a failure would (the session thread is
        // stopped and joined below; leaving here with it running would end the process).
        try
        {
            spdlog::info(
                "demo: the session runs; opening the viewer on 127.0.0.1:{} (close the "
                "window to end it)",
                master);
            viewer::ViewerOptions v;
            v.input = "127.0.0.1:" + std::to_string(master);
            v.bundled_mesh = bundled_mesh();
            v.screenshot = opt.screenshot;
            v.exit_after = opt.exit_after;
            v.name = "viewer";
            v.owner_colors = true;
            v.stop = link.interrupt;
            view_rc = viewer::run_viewer(v);
        }
        catch (const std::bad_alloc&)
        {
            view_rc = report_out_of_memory();
        }
        // A viewer that failed leaves no outputs; one closed by Ctrl-C ends the run as its
        // window's close does, with every output, and the demo exits 130.
        if (view_rc != 0 && view_rc != k_exit_interrupted)
            link.discard = true;
    }
    link.stop = true;
    session_thread.join();
    if (demo_rc == 0 && view_rc == k_exit_interrupted)
        spdlog::error("demo: interrupted; {} holds what ran", opt.out.string());
    return demo_rc != 0 ? demo_rc : view_rc;
#else
    (void)opt;
    (void)global;
    spdlog::error(
        "demo --view: pliant was built without the viewer (libglfw3-dev, libimgui-dev); install "
        "them and reconfigure, or run the demo without --view");
    return k_exit_failure;
#endif
}

void add_demo_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<DemoOptions>();
    CLI::App* cmd = app.add_subcommand(
        "demo",
        "Run the whole system on the bundled mesh: remesh it, then a collaborative session on\n"
        "this machine: a master and two participants over UDP on 127.0.0.1, each simulating its\n"
        "own part, two users grabbing different ends, a viewer joining late; frames rendered\n"
        "offscreen in owner colours, the inputs recorded and replayed bit for bit.\n"
        "Output (in --out, default demo-out/): frame_NNNN.png, demo.gif (with ImageMagick or\n"
        "ffmpeg), summary.md, session.prec (`pliant replay`), grid.pgrid, final.pgrid (the\n"
        "final state with the owning peer per node: `pliant render final.pgrid --color owner`),\n"
        "timeline.csv, remesh-report.json; these files of an earlier run there are removed\n"
        "first (other files stay).\n\n"
        "With a display, --view opens the viewer (`pliant view`) on the running session instead\n"
        "of rendering frames: the peers run in real time on a second thread, the two users'\n"
        "grabs repeat every --duration seconds, and closing the window ends the session (the\n"
        "summary and session.prec are still written; `pliant replay` checks the recording).\n"
        "Ctrl-C stops at the next step (with --view: closes the viewer as its window does)\n"
        "and the run ends with what ran: the frames up to the last whole one, the final\n"
        "state, the recording and its replay check at the step reached; exit status 130.\n\n"
        "Examples:\n"
        "  pliant demo                      # the bundled cow, level 6, 3 s at 12 fps\n"
        "  pliant demo --view               # watch it live in a window\n"
        "  pliant demo --quick              # level 5, 2 s at 6 fps, 320x240 (the tests)\n"
        "  pliant demo --mesh my.obj --level 7 --out /tmp/run");
    cmd->add_option("--mesh", opt->mesh, "Closed genus-0 mesh (default: the bundled data/spot.obj)")
        ->check(existing_input_file("--mesh"));
    cmd->add_option("-o,--out", opt->out, "Output folder")->capture_default_str();
    cmd->add_option("-l,--level", opt->level,
                    "Simulation grid level (W = 2^level; from 4, where the grid has leaves "
                    "enough for the demo's three simulating peers)")
        ->check(whole_number_in(4, 8))
        ->capture_default_str();
    cmd->add_option("--display-levels", opt->display_levels, "Butterfly levels added for display")
        ->check(whole_number_in(0, 3))
        ->capture_default_str();
    cmd->add_option("--duration", opt->duration, "Session time [s]")
        ->check(number_in(0.5, 120.0))
        ->capture_default_str();
    cmd->add_option("--fps", opt->fps, "Frames per second of session time")
        ->check(number_in(1.0, 60.0))
        ->capture_default_str();
    cmd->add_option("--dt", opt->dt, "Fixed step [s] (default: 0.9 x the stability bound)")
        ->check(positive_number());
    cmd->add_option("--width", opt->width, "Frame width [pixels]")
        ->check(whole_number_in(16, 4096))
        ->capture_default_str();
    cmd->add_option("--height", opt->height, "Frame height [pixels]")
        ->check(whole_number_in(16, 4096))
        ->capture_default_str();
    cmd->add_option("--wall-limit", opt->wall_limit, "Give up after this many wall seconds")
        ->check(positive_number())
        ->capture_default_str();
    cmd->add_flag("--quick", opt->quick,
                  "Level 5, 2 s, 6 fps, 320x240 (for tests); an option given beside it wins");
    // A plain flag setting the field (a CLI11 negated flag showed "{false}" in --help).
    cmd->add_flag_function(
        "--no-render", [opt](std::int64_t) { opt->render = false; },
        "Skip the pictures (no OpenGL needed)");
    cmd->add_flag("--view", opt->view,
                  "Open the viewer on the running session (needs a display; no frames)");
    cmd->add_option("--screenshot", opt->screenshot,
                    "With --view: write a PNG of the viewer's last frame at exit");
    cmd->add_option("--exit-after", opt->exit_after,
                    "With --view: close the viewer this many seconds after the object shows")
        ->check(positive_number());
    cmd->callback(command_callback(
        global,
        [opt, &global, cmd]()
        {
            if ((!opt->screenshot.empty() || opt->exit_after > 0.0) && !opt->view)
            {
                spdlog::error("demo: --screenshot and --exit-after go with --view");
                return k_exit_usage;
            }
            if (opt->out.empty())
            {
                spdlog::error("demo: --out is empty; give a folder (default demo-out)");
                return k_exit_usage;
            }
            // --quick sets the small run's values of the options not given; a given one wins.
            if (opt->quick)
            {
                if (cmd->count("--level") == 0)
                    opt->level = k_quick_level;
                if (cmd->count("--duration") == 0)
                    opt->duration = k_quick_duration;
                if (cmd->count("--fps") == 0)
                    opt->fps = k_quick_fps;
                if (cmd->count("--width") == 0)
                    opt->width = k_quick_width;
                if (cmd->count("--height") == 0)
                    opt->height = k_quick_height;
            }
            return opt->view ? run_demo_with_viewer(*opt, global) : run_demo(*opt, global, nullptr);
        }));
}

const CommandRegistrar k_register_demo{{"demo", 5, &add_demo_command}};

}  // namespace
}  // namespace pliant::cli
