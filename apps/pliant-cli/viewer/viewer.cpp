// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The viewer's window, frame loop, input, sessions, screenshots and surface export (design:
// viewer_app.h).
#include <pliant/mesh/io.h>
#include <pliant/net/enet_transport.h>
#include <pliant/render/camera.h>
#include <pliant/render/gl_loader.h>
#include <pliant/render/image.h>

#define GLFW_INCLUDE_NONE
#include <GL/glcorearb.h>
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>
#include <spdlog/spdlog.h>

#include "../peer_files.h"
#include "picking.h"
#include "viewer_app.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <new>
#include <optional>
#include <vector>

namespace pliant::viewer
{
namespace
{

/// Keeps large blocks in the heap between frames. By default glibc serves blocks above its
/// mmap threshold with fresh mappings and returns freed memory to the system, so the large
/// per-frame buffers of Mesa's software rasteriser (llvmpipe bins a 262K-triangle frame into
/// tens of MB) were mapped, faulted in page by page and unmapped every frame: 7.1 fps at display
/// level 8 against 22.8 with these limits raised (docs/viewer.md, Real time).
void keep_large_allocations()
{
#if defined(__GLIBC__)
    (void)mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest allowed value
    (void)mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

/// The most simulated time one frame advances [s]: a slower machine falls behind real time
/// rather than freezing (docs/viewer.md, Real time).
constexpr double k_max_frame_interval = 0.1;

/// The few GL calls the viewer makes itself (render::GridRenderer makes the rest through the
/// render module's table, loaded by render::load_gl from the same glfwGetProcAddress).
struct ViewerGl
{
    PFNGLBINDFRAMEBUFFERPROC bind_framebuffer = nullptr;
    PFNGLVIEWPORTPROC viewport = nullptr;
    PFNGLCLEARCOLORPROC clear_color = nullptr;
    PFNGLCLEARPROC clear = nullptr;
    PFNGLREADBUFFERPROC read_buffer = nullptr;
    PFNGLPIXELSTOREIPROC pixel_store = nullptr;
    PFNGLREADPIXELSPROC read_pixels = nullptr;
    PFNGLFINISHPROC finish = nullptr;

    bool load()
    {
        // reinterpret_cast between function pointer types is how GetProcAddress works.
        bind_framebuffer =
            reinterpret_cast<PFNGLBINDFRAMEBUFFERPROC>(glfwGetProcAddress("glBindFramebuffer"));
        viewport = reinterpret_cast<PFNGLVIEWPORTPROC>(glfwGetProcAddress("glViewport"));
        clear_color = reinterpret_cast<PFNGLCLEARCOLORPROC>(glfwGetProcAddress("glClearColor"));
        clear = reinterpret_cast<PFNGLCLEARPROC>(glfwGetProcAddress("glClear"));
        read_buffer = reinterpret_cast<PFNGLREADBUFFERPROC>(glfwGetProcAddress("glReadBuffer"));
        pixel_store = reinterpret_cast<PFNGLPIXELSTOREIPROC>(glfwGetProcAddress("glPixelStorei"));
        read_pixels = reinterpret_cast<PFNGLREADPIXELSPROC>(glfwGetProcAddress("glReadPixels"));
        finish = reinterpret_cast<PFNGLFINISHPROC>(glfwGetProcAddress("glFinish"));
        return bind_framebuffer && viewport && clear_color && clear && read_buffer && pixel_store &&
               read_pixels && finish;
    }
};

ViewerGl g_gl;

/// The back buffer as an image, top row first.
render::Image read_back_buffer(int width, int height)
{
    render::Image image;
    image.width = width;
    image.height = height;
    image.rgba.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4U);
    g_gl.bind_framebuffer(GL_READ_FRAMEBUFFER, 0);
    g_gl.read_buffer(GL_BACK);
    g_gl.pixel_store(GL_PACK_ALIGNMENT, 1);
    g_gl.read_pixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
    const std::size_t row = static_cast<std::size_t>(width) * 4U;
    for (int y = 0; y < height / 2; ++y)
        std::swap_ranges(image.rgba.begin() + static_cast<std::ptrdiff_t>(row * y),
                         image.rgba.begin() + static_cast<std::ptrdiff_t>(row * (y + 1)),
                         image.rgba.begin() + static_cast<std::ptrdiff_t>(row * (height - 1 - y)));
    return image;
}

/// Fraction of pixels that differ from the background by more than 8 of 255 in some channel.
double coverage(const render::Image& image, const render::Rgb& background)
{
    const int bg[3] = {static_cast<int>(std::lround(background.r * 255.0F)),
                       static_cast<int>(std::lround(background.g * 255.0F)),
                       static_cast<int>(std::lround(background.b * 255.0F))};
    std::size_t object = 0;
    const std::size_t n = image.rgba.size() / 4U;
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
            if (std::abs(image.rgba[i * 4U + static_cast<std::size_t>(c)] - bg[c]) > 8)
            {
                ++object;
                break;
            }
    return n > 0 ? static_cast<double>(object) / static_cast<double>(n) : 0.0;
}

Viewer* viewer_of(GLFWwindow* window)
{
    return static_cast<Viewer*>(glfwGetWindowUserPointer(window));
}

void on_cursor(GLFWwindow* window, double x, double y)
{
    viewer_of(window)->mouse_move(x, y);
}

void on_button(GLFWwindow* window, int button, int action, int /*mods*/)
{
    if (button != GLFW_MOUSE_BUTTON_LEFT)
        return;
    Viewer* v = viewer_of(window);
    if (action == GLFW_PRESS && v->imgui_ready_ && ImGui::GetIO().WantCaptureMouse)
        return;
    double x = 0.0;
    double y = 0.0;
    glfwGetCursorPos(window, &x, &y);
    v->mouse_button(action == GLFW_PRESS, x, y);
}

void on_scroll(GLFWwindow* window, double /*dx*/, double dy)
{
    Viewer* v = viewer_of(window);
    if (v->imgui_ready_ && ImGui::GetIO().WantCaptureMouse)
        return;
    double x = 0.0;
    double y = 0.0;
    glfwGetCursorPos(window, &x, &y);
    v->wheel(x, y, dy);
}

void on_key(GLFWwindow* window, int key, int /*scancode*/, int action, int /*mods*/)
{
    Viewer* v = viewer_of(window);
    if (action != GLFW_PRESS || (v->imgui_ready_ && ImGui::GetIO().WantCaptureKeyboard))
        return;
    switch (key)
    {
    case GLFW_KEY_P:
    case GLFW_KEY_F12: v->key("p"); break;
    case GLFW_KEY_W: v->key("w"); break;
    case GLFW_KEY_C: v->key("c"); break;
    case GLFW_KEY_E: v->key("e"); break;
    case GLFW_KEY_H: v->key("h"); break;
    case GLFW_KEY_R: v->key("r"); break;
    case GLFW_KEY_SPACE: v->key("space"); break;
    case GLFW_KEY_ESCAPE: v->key("escape"); break;
    default: break;
    }
}

void on_glfw_error(int code, const char* message)
{
    spdlog::error("view: GLFW error {}: {}", code, message);
}

/// The export formats of the panel's combo box (viewer_panels.cpp), in its order.
constexpr std::array<const char*, 4> k_export_extensions{"obj", "ply", "gltf", "glb"};

double seconds(std::chrono::steady_clock::duration d)
{
    return std::chrono::duration<double>(d).count();
}

/// The first `pliant-view-NNNN.<extension>` that does not exist in the working folder
/// (bounded search: none after 9999).
std::optional<std::filesystem::path> first_free_name(const char* extension)
{
    std::error_code ec;
    for (int k = 0; k < 10000; ++k)
    {
        char name[64];
        std::snprintf(name, sizeof name, "pliant-view-%04d.%s", k, extension);
        if (!std::filesystem::exists(name, ec))
            return std::filesystem::path(name);
    }
    return std::nullopt;
}

}  // namespace

Viewer::Viewer(const ViewerOptions& options) : options_(options)
{
    draw_.background = {0.17F, 0.18F, 0.21F};
    if (options.owner_colors)
        color_ = render::ColorMode::Owner;
    draw_.color = color_;
    display_level_ = options.display_level;
    if (options.port != 0)  // the Session panel's host listens on --port too
        host_port_ = options.port;
}

Viewer::~Viewer()
{
    load_.reset();  // cancels a remeshing in progress and waits for its worker to stop
    session_.reset();
    transport_.reset();
    renderer_.reset();
    if (imgui_ready_)
    {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    if (window_ != nullptr)
        glfwDestroyWindow(window_);
    glfwTerminate();
}

void Viewer::set_status(std::string message, bool error)
{
    if (error)
        spdlog::error("view: {}", message);
    else
        spdlog::info("view: {}", message);
    status_ = std::move(message);
    status_error_ = error;
}

const sim::MembraneModel* Viewer::model() const noexcept
{
    if (session_)
        return session_->model();
    return local_ ? &local_->model() : nullptr;
}

bool Viewer::object_shown() const noexcept
{
    return renderer_ && gpu_surface_valid_ && !view_.empty();
}

render::CameraMatrices Viewer::camera_matrices() const
{
    int w = 0;
    int h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    return renderer_->camera(draw_.camera, std::max(w, 1), std::max(h, 1));
}

// --- loading -----------------------------------------------------------------------------

void Viewer::start_load(const std::filesystem::path& path)
{
    if (load_)
    {
        set_status("already loading " + load_->path().filename().string(), true);
        return;
    }
    // A new surface replaces the session's: the master's load would end the session for every
    // peer. Leave (or end) it first, on purpose.
    if (session_)
    {
        set_status(
            "leave the session before loading another surface (" + path.filename().string() + ")",
            true);
        return;
    }
    load_ = std::make_unique<LoadJob>(path, options_.level);
    set_status("loading " + path.string(), false);
}

void Viewer::finish_load()
{
    if (!load_ || !load_->done())
        return;
    auto result = load_->take();
    const std::string name = load_->path().filename().string();
    load_.reset();
    if (!result)
    {
        if (result.error().code == core::ErrorCode::Cancelled)
            set_status("loading " + name + " cancelled (" + result.error().message + ")", false);
        else
            set_status(result.error().message, true);
        return;
    }
    if (session_)  // not reached: joining or hosting cancels a load
        leave_session();
    max_u_reached_ = 0.0;  // the exit summary speaks of the object shown last
    start_local(std::move(*result));
}

void Viewer::cancel_load(const std::string& why)
{
    if (!load_)
        return;
    const std::string name = load_->path().filename().string();
    load_.reset();  // cancels the worker and joins it
    spdlog::info("view: loading {} cancelled: {}", name, why);
}

void Viewer::drop_grab() noexcept
{
    grab_.reset();
    if (drag_ == Drag::Grab)
        drag_ = Drag::None;
}

void Viewer::start_local(LoadedSurface surface)
{
    const int level = surface.grid.level();
    const sim::MembraneSettings material = default_material(level);
    // The loaded surface passed the load; its simulation may still need more memory than
    // there is: an error in the window, and the viewer goes on with what it had.
    std::optional<core::Result<LocalSim>> sim;
    try
    {
        sim.emplace(LocalSim::create(surface.grid, surface.positions, material));
    }
    catch (const std::bad_alloc&)
    {
        set_status(surface.description + ": out of memory for its simulation; choose a lower level",
                   true);
        return;
    }
    if (!*sim)
    {
        set_status(sim->error().message, true);
        return;
    }
    material_ = material;
    drop_grab();
    local_.emplace(std::move(**sim));
    surface_name_ = surface.description;
    set_status(surface.description, false);
    // --resume: the first surface (the rest grid the caller checked the state against) goes on
    // from the saved state; a surface loaded later starts at rest.
    if (options_.resume_state && !resume_applied_ &&
        options_.resume_state->u.level() == surface.grid.level())
    {
        local_->set_state(*options_.resume_state);
        resume_applied_ = true;
        surface_name_ += ", resumed from " + options_.resume.filename().string();
        set_status(surface_name_, false);
    }
    surface_.emplace(std::move(surface));
    rest_bounds_.reset();
    shown_owner_level_ = -1;
    display_level_ = initial_display_level(level);
}

int Viewer::initial_display_level(int sim_level) const
{
    const int highest = max_display_level(sim_level);
    if (options_.display_level < 0)
        return std::min(sim_level + 1, std::max(sim_level, 8));
    if (options_.display_level > highest)
        spdlog::warn("view: --display-level {} is above simulation level {} + 3; showing level {}",
                     options_.display_level, sim_level, highest);
    else if (options_.display_level < sim_level)
        spdlog::warn("view: --display-level {} is below the simulation level {}; showing level {}",
                     options_.display_level, sim_level, sim_level);
    return std::clamp(options_.display_level, sim_level, highest);
}

// --- sessions ------------------------------------------------------------------------------

bool Viewer::join_session(const std::string& address, bool participant)
{
    auto master = net::resolve_address(address);
    if (!master)
    {
        set_status(master.error().message, true);
        return false;
    }
    if (const auto why = cli::undialable(*master, address, options_.port))
    {
        set_status("join: " + *why, true);
        return false;
    }
    leave_session();
    drop_grab();
    transport_ = cli::secure_or_plain(net::make_enet_transport(), options_.secret);
    auto bound = transport_->open(net::Address{{0, 0, 0, 0}, options_.port});
    if (!bound)
    {
        set_status(bound.error().message, true);
        transport_.reset();
        return false;
    }
    session::SessionSettings settings;
    settings.name = options_.name;
    settings.listen_port = bound->port;
    auto s = session::Session::join(
        *transport_, *master, participant ? net::Role::Participant : net::Role::Viewer, settings);
    if (!s)
    {
        set_status(s.error().message, true);
        transport_.reset();
        return false;
    }
    session_ = std::move(*s);
    session_address_ = address;
    hosting_ = false;
    cancel_load("joined " + address);
    max_u_reached_ = 0.0;
    // The Session panel's field shows the address tried, so a retry is one click.
    std::snprintf(join_address_.data(), join_address_.size(), "%s", address.c_str());
    joined_ = false;
    open_session_panel_ = true;
    local_.reset();
    rest_bounds_.reset();
    shown_epoch_ = 0;
    shown_owner_level_ = -1;
    last_stats_ = {};
    set_status("joining " + address + (participant ? " as a participant" : " as a viewer") +
                   " (waiting for the master's answer and the model)",
               false);
    return true;
}

bool Viewer::host_session(std::uint16_t port, bool exact)
{
    if (!surface_)
    {
        set_status("host: load a surface first", true);
        return false;
    }
    leave_session();
    drop_grab();
    transport_ = cli::secure_or_plain(net::make_enet_transport(), options_.secret);
    auto bound = transport_->open(net::Address{{0, 0, 0, 0}, port});
    if (!bound)
    {
        set_status(bound.error().message, true);
        transport_.reset();
        return false;
    }
    // What the local simulation runs with (the Material panel's edits once applied), not the
    // panel's fields.
    sim::MembraneSettings material = local_ ? local_->model().settings() : material_;
    const sim::MembraneSettings before = material;
    material.fixed_step = exact;
    if (exact)
    {
        // Lockstep has no error control: the step `pliant host` takes, 1 ms or 0.9 of the
        // grid's stable step where that is shorter (docs/physics.md §5).
        auto probe = sim::MembraneModel::create(surface_->grid, surface_->positions, material);
        if (!probe)
        {
            set_status(probe.error().message, true);
            transport_.reset();
            return false;
        }
        material.fixed_dt = std::min(1e-3, 0.9 * sim::stable_fixed_step(*probe));
    }
    session::SessionSettings settings;
    settings.coupling = exact ? session::Coupling::Exact : session::Coupling::Fast;
    settings.name = options_.name;
    settings.listen_port = bound->port;
    auto s = session::Session::host(*transport_, surface_->grid, surface_->positions, material,
                                    settings);
    if (!s)
    {
        set_status(s.error().message, true);
        transport_.reset();
        return false;
    }
    session_ = std::move(*s);
    material_before_host_ = before;
    session_address_ = "port " + std::to_string(bound->port);
    cancel_load("hosting on port " + std::to_string(bound->port));
    joined_ = true;
    hosting_ = true;
    open_session_panel_ = true;
    local_.reset();
    shown_epoch_ = 0;
    shown_owner_level_ = -1;
    last_stats_ = {};
    set_status("hosting on port " + std::to_string(bound->port) + (exact ? " (exact)" : " (fast)"),
               false);
    return true;
}

void Viewer::leave_session(const std::string& message, bool error)
{
    if (!session_)
        return;
    grab_.reset();
    if (session_->role() == session::SessionRole::Master)
        session_->shutdown();
    else
    {
        session_->leave();
        // Bounded wait for the hand-over of this peer's leaves (the runner does the same).
        const auto stop = Clock::now() + std::chrono::seconds(3);
        while (!session_->left() && Clock::now() < stop)
        {
            session_->poll();
            session_->advance(seconds(Clock::now().time_since_epoch()));
            session_->wait(500e-6);
        }
    }
    // Keep showing the object: a local simulation of the session's model from rest (whatever
    // was shown before the join); the earlier object only when the model never arrived.
    if (!hosting_ && session_->model() != nullptr)
    {
        const sim::MembraneModel& m = *session_->model();
        surface_.emplace(LoadedSurface{m.grid(), m.rest_positions(), "the session's surface"});
    }
    session_.reset();
    transport_.reset();
    if (surface_)
    {
        LoadedSurface copy{surface_->grid, surface_->positions, surface_->description};
        start_local(std::move(copy));
        // A host goes on with the material it hosted with (the Material panel's applied
        // edits), not the level's default.
        if (hosting_ && material_before_host_ && local_ &&
            local_->set_settings(*material_before_host_))
            material_ = *material_before_host_;
    }
    material_before_host_.reset();
    set_status(message, error);
}

void Viewer::pump_session()
{
    double now_s = 0.0;
    // A lockstep tick needs one message round with every peer, so a participant polls several
    // times per frame (bounded, 4 ms) rather than once: otherwise the session could advance at
    // most one tick per frame.
    const auto budget_end = Clock::now() + std::chrono::milliseconds(4);
    const bool simulates = session_->role() != session::SessionRole::Viewer;
    do
    {
        session_->poll();
        // The clock is read after poll(): a stop of the process within it must show as a gap
        // in advance() (SessionSettings::pause_s), or the departures poll() found then would
        // be taken for the others' (docs/session.md §6).
        now_s = seconds(Clock::now().time_since_epoch());
        session_->advance(now_s);
        if (!simulates)
            break;
        session_->wait(250e-6);  // ends when a neighbour's halo or heartbeat arrives
    } while (Clock::now() < budget_end && !session_->left());
    if (session_->left())
    {
        // Why: this peer's step diverged, the session refused its settings, the master never
        // answered (a joiner gets the model right after the greeting), or the link broke or the
        // master ended it.
        std::string why;
        if (const auto tick = session_->diverged())
            why = "the simulation diverged at tick " + std::to_string(*tick) +
                  ": this peer left the session (the others, if any, took its share over; a step "
                  "above the stable one, or forces without a limit; docs/session.md §7)";
        else if (!session_->refusal().empty())
            why = "this peer left the session at " + session_address_ + ": " + session_->refusal();
        else if (session_->role() == session::SessionRole::Master)
            why = "the session hosted on " + session_address_ + " ended";
        else if (const auto failure = session_->join_failure();
                 failure && failure->reason != net::DisconnectReason::TimedOut &&
                 failure->reason != net::DisconnectReason::None)
            why =
                cli::join_failure_message(session_address_, *failure, options_.secret.has_value());
        else if (!session_->ready())
            why = "could not reach the master at " + session_address_ +
                  ": no answer (is `pliant host` running there, on that UDP port?)";
        else
            why = "the session ended: the master at " + session_address_ +
                  " ended it or the connection was lost";
        session_failed_ = true;
        leave_session(why, true);
        return;
    }
    if (!joined_ && session_->ready())
    {
        joined_ = true;
        set_status(
            "joined " + session_address_ + " as " +
                (session_->role() == session::SessionRole::Viewer ? "a viewer" : "a participant") +
                " (id " + std::to_string(session_->id().value) + ", level " +
                std::to_string(session_->model()->grid().level()) + ")",
            false);
    }
}

// --- simulation and display ------------------------------------------------------------------

void Viewer::simulate(double wall_dt)
{
    std::vector<sim::Force> forces;
    if (grab_ && !view_.empty())
        forces.push_back(grab_->force(view_));
    if (session_)
    {
        const session::SessionStats before = session_->stats();
        if (session_->ready() && session_->role() != session::SessionRole::Viewer)
        {
            std::vector<net::UserForce> list;
            for (const sim::Force& f : forces)
            {
                net::UserForce u;
                u.target.kind = net::TargetKind::Position;
                u.target.position = {f.point.x, f.point.y, f.point.z};
                u.target.radius = f.radius;
                u.force = {f.vector.x, f.vector.y, f.vector.z};
                list.push_back(u);
            }
            if (auto ok = session_->set_forces(std::move(list)); !ok)
                set_status(ok.error().message, true);
        }
        pump_session();
        if (!session_)
            return;
        const session::SessionStats s = session_->stats();
        step_ms_.push(static_cast<float>((s.step_seconds - before.step_seconds) * 1e3));
        latency_ms_.push(static_cast<float>((s.halo_age_s + s.view_delay_s) * 1e3));
        const double now = seconds(Clock::now().time_since_epoch());
        if (now - last_stats_time_ >= 0.5)
        {
            const double dt = last_stats_time_ > 0.0 ? now - last_stats_time_ : 0.5;
            kbps_in_.push(static_cast<float>(
                static_cast<double>(s.bytes_received - last_stats_.bytes_received) / dt / 1e3));
            kbps_out_.push(static_cast<float>(
                static_cast<double>(s.bytes_sent - last_stats_.bytes_sent) / dt / 1e3));
            last_stats_ = s;
            last_stats_time_ = now;
        }
        return;
    }
    if (local_ && !paused_)
    {
        // A grab's spring is held over the frame: slow frames get a shorter simulated interval
        // (slow motion) rather than an unstable hold (grab_hold_limit).
        const double interval = grab_
                                    ? std::min(k_max_frame_interval,
                                               grab_hold_limit(local_->model().settings(), *grab_))
                                    : k_max_frame_interval;
        local_->advance(wall_dt, forces, interval);
        step_ms_.push(static_cast<float>(local_->last_step_seconds() * 1e3));
    }
}

void Viewer::update_owners()
{
    const sim::MembraneModel* m = model();
    const core::TetraGrid& grid = m->grid();
    std::vector<std::uint16_t> coarse(grid.node_count(), render::k_no_owner);
    if (session_)
    {
        const std::vector<net::PeerId> owners = session_->owners();
        const session::LeafGraph* graph = session_->leaf_graph();
        if (graph != nullptr && !owners.empty())
            for (std::uint32_t n = 0; n < grid.node_count(); ++n)
            {
                const std::uint32_t leaf = graph->leaf_of(core::NodeIndex{n});
                if (leaf < owners.size() && owners[leaf] != net::k_no_peer)
                    coarse[n] = owners[leaf].value;
            }
        shown_epoch_ = session_->epoch();
    }
    else
    {
        // Locally: the quad-tree leaves of the simulation's parallel work split.
        const auto regions = m->leaf_regions();
        for (std::size_t k = 0; k < regions.size(); ++k)
            for (int y = regions[k].y0; y < regions[k].y1; ++y)
                for (int x = regions[k].x0; x < regions[k].x1; ++x)
                    if (grid.is_canonical(grid.index(x, y)))
                        coarse[grid.index(x, y).value] = static_cast<std::uint16_t>(k);
        for (const core::TwinPair& t : grid.twins())
            coarse[t.twin.value] = coarse[t.canonical.value];
    }
    // Owners are labels: a display node takes the owner of the sim node at its rounded-down
    // position (as `pliant render --level-up` does).
    const core::TetraGrid& display = view_.display_grid();
    const int shift = display.level() - grid.level();
    owners_display_.assign(display.node_count(), render::k_no_owner);
    for (int y = 0; y < display.ny(); ++y)
        for (int x = 0; x < display.nx(); ++x)
            owners_display_[display.index(x, y).value] =
                coarse[grid.index(x >> shift, y >> shift).value];
    renderer_->upload_owners(display, owners_display_);
    shown_owner_level_ = display.level();
}

void Viewer::update_surface()
{
    const sim::MembraneModel* m = model();
    if (m == nullptr)
    {
        gpu_surface_valid_ = false;
        return;
    }
    const core::Field<double>& u = session_ ? session_->view_u() : local_->state().u;
    const int level = m->grid().level();
    if (display_level_ < level || display_level_ > max_display_level(level))
        display_level_ = initial_display_level(level);  // a joined session's model
    view_.update(*m, u, display_level_ - level);
    renderer_->upload(view_.display_grid(), view_.display_positions(), &view_.display_u());
    gpu_surface_valid_ = true;
    if (!rest_bounds_)
    {
        // The rest surface's nodes, not the first surface drawn: a resumed state or a session
        // joined mid-pull is already deformed.
        const core::TetraGrid& g = m->grid();
        const core::Vec3Field<double>& rest = m->rest_positions();
        std::vector<core::Vec3> points;
        points.reserve(static_cast<std::size_t>(g.nx()) * static_cast<std::size_t>(g.ny()));
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
                points.push_back({rest[0].at(x, y), rest[1].at(x, y), rest[2].at(x, y)});
        rest_bounds_ = render::bounds_of(points);
        object_radius_ = rest_bounds_->radius();
        draw_.camera.fit_to = rest_bounds_;
    }
    max_u_reached_ = std::max(max_u_reached_, view_.max_abs_u());
    const bool owners_stale = shown_owner_level_ != view_.display_grid().level() ||
                              (session_ && session_->epoch() != shown_epoch_);
    if (owners_stale)
        update_owners();
}

// --- input -----------------------------------------------------------------------------------

void Viewer::mouse_move(double x, double y)
{
    const double dx = x - mouse_x_;
    const double dy = y - mouse_y_;
    mouse_x_ = x;
    mouse_y_ = y;
    if (drag_ == Drag::Orbit)
    {
        draw_.camera.azimuth_deg -= 0.4 * dx;
        draw_.camera.elevation_deg = std::clamp(draw_.camera.elevation_deg + 0.4 * dy, -89.0, 89.0);
    }
    else if (drag_ == Drag::Grab && grab_ && object_shown())
    {
        // Move the target in the plane through it facing the camera (as seen at the press).
        int w = 0;
        int h = 0;
        glfwGetWindowSize(window_, &w, &h);
        const Ray ray = pixel_ray(camera_matrices(), x, y, std::max(w, 1), std::max(h, 1));
        const double denom = core::dot(ray.direction, grab_plane_normal_);
        if (std::abs(denom) > 1e-9)
        {
            const double t = core::dot(grab_->target - ray.origin, grab_plane_normal_) / denom;
            if (t > 0.0)
                grab_->target = ray.origin + ray.direction * t;
        }
    }
}

void Viewer::mouse_button(bool down, double x, double y)
{
    mouse_x_ = x;
    mouse_y_ = y;
    if (!down)
    {
        drag_ = Drag::None;
        grab_.reset();
        return;
    }
    drag_ = Drag::Orbit;
    if (!object_shown())
        return;
    const bool can_push = !session_ || session_->role() != session::SessionRole::Viewer;
    int w = 0;
    int h = 0;
    glfwGetWindowSize(window_, &w, &h);
    const render::CameraMatrices cam = camera_matrices();
    const Ray ray = pixel_ray(cam, x, y, std::max(w, 1), std::max(h, 1));
    // on the surface as drawn (refined to the display level), so the point grabbed is the one
    // under the cursor, at a silhouette too
    const auto hit = view_.pick(ray);
    if (!hit || !can_push)
        return;
    const sim::MembraneSettings& material = model()->settings();
    Grab g;
    g.at = hit->first;
    g.target = hit->second;
    g.radius = grab_radius_factor_ * object_radius_;
    g.stiffness = grab_stiffness_scale_ * default_grab_stiffness(material, g.radius);
    grab_ = g;
    grab_plane_normal_ = core::normalized(hit->second - cam.eye);
    drag_ = Drag::Grab;
}

void Viewer::wheel(double /*x*/, double /*y*/, double clicks)
{
    zoom_ = std::clamp(zoom_ * std::pow(0.88, clicks), 0.05, 20.0);
}

void Viewer::key(std::string_view name)
{
    if (name == "p" || name == "f12")
        request_screenshot(std::nullopt);
    else if (name == "e")
        export_surface(std::nullopt);
    else if (name == "w")
        draw_.wireframe = !draw_.wireframe;
    else if (name == "c")
        color_ = color_ == render::ColorMode::None           ? render::ColorMode::Displacement
                 : color_ == render::ColorMode::Displacement ? render::ColorMode::Owner
                                                             : render::ColorMode::None;
    else if (name == "h")
        options_.hide_panels = !options_.hide_panels;
    else if (name == "r" && local_)
        local_->reset();
    else if (name == "space")
        paused_ = !paused_;
    else if (name == "escape")
        glfwSetWindowShouldClose(window_, GLFW_TRUE);
}

// --- screenshots -------------------------------------------------------------------------------

void Viewer::request_screenshot(std::optional<std::filesystem::path> path)
{
    if (path)
    {
        screenshot_request_ = std::move(*path);
        return;
    }
    // The first free name, as for exports: a screenshot never overwrites an earlier one.
    if (auto name = first_free_name("png"))
        screenshot_request_ = std::move(*name);
    else
        set_status("screenshot: pliant-view-0000 ... 9999.png all exist in the working folder",
                   true);
}

bool Viewer::write_screenshot(const std::filesystem::path& path, int width, int height)
{
    std::error_code ec;
    if (path.has_parent_path())
        std::filesystem::create_directories(path.parent_path(), ec);
    if (auto ok = render::write_png(path, read_back_buffer(width, height)); !ok)
    {
        set_status(ok.error().message, true);
        return false;
    }
    set_status("screenshot " + path.string(), false);
    return true;
}

// --- export --------------------------------------------------------------------------------------

void Viewer::export_file(std::string_view file)
{
    // A scripted export that fails makes the run fail (exit 3), as a failed --screenshot does.
    if (!export_surface(std::filesystem::path(file)))
        script_failed_ = true;
}

void Viewer::load_file(std::string_view file)
{
    start_load(std::filesystem::path(file));
}

bool Viewer::export_surface(std::optional<std::filesystem::path> path)
{
    if (!object_shown())
    {
        set_status("export: nothing to export yet", true);
        return false;
    }
    if (!path)
    {
        // The first free name, so an export never overwrites an earlier one.
        const std::size_t format = static_cast<std::size_t>(std::clamp(export_format_, 0, 3));
        path = first_free_name(k_export_extensions[format]);
        if (!path)
        {
            set_status("export: pliant-view-0000 ... 9999 all exist in the working folder", true);
            return false;
        }
    }
    // The simulation-level surface: the state itself, not its refined display.
    mesh::TriMesh surface;
    surface.positions = view_.positions();
    surface.faces = view_.faces();
    if (auto ok = mesh::export_mesh(*path, surface); !ok)
    {
        set_status(ok.error().message, true);
        return false;
    }
    const int level = model() != nullptr ? model()->grid().level() : 0;
    set_status("exported " + path->string() + " (" + std::to_string(surface.vertex_count()) +
                   " vertices, " + std::to_string(surface.face_count()) +
                   " faces, simulation level " + std::to_string(level) + ")",
               false);
    std::printf("view: exported %s (%zu vertices, %zu faces, simulation level %d)\n",
                path->string().c_str(), surface.vertex_count(), surface.face_count(), level);
    return true;
}

// --- the frame loop ------------------------------------------------------------------------------

int Viewer::run()
{
    // A broken script is refused before any window opens.
    if (!options_.script.empty())
    {
        auto events = load_input_script(options_.script);
        if (!events)
        {
            spdlog::error("view: {}", events.error().message);
            return 1;
        }
        script_.emplace(std::move(*events));
        if (options_.exit_after > 0.0 && script_->end_time() > options_.exit_after)
            spdlog::warn(
                "view: {} runs until {:g} s, after --exit-after {:g} s: what it does "
                "after that will not run",
                options_.script.string(), script_->end_time(), options_.exit_after);
    }
    keep_large_allocations();
    glfwSetErrorCallback(on_glfw_error);
    if (glfwInit() != GLFW_TRUE)
    {
        spdlog::error(
            "view: GLFW could not start (no display? set DISPLAY, or run under `xvfb-run -a`)");
        return 3;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    window_ = glfwCreateWindow(options_.width, options_.height, "pliant view", nullptr, nullptr);
    if (window_ == nullptr)
    {
        spdlog::error("view: no window with an OpenGL 3.3 core context (see the GLFW error)");
        return 3;
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(options_.vsync ? 1 : 0);
    if (auto ok = render::load_gl(glfwGetProcAddress); !ok)
    {
        spdlog::error("view: {}", ok.error().message);
        return 3;
    }
    if (!g_gl.load())
    {
        spdlog::error("view: the context lacks glReadPixels and friends");
        return 3;
    }
    auto renderer = render::GridRenderer::create();
    if (!renderer)
    {
        spdlog::error("view: {}", renderer.error().message);
        return 3;
    }
    renderer_.emplace(std::move(*renderer));
    const std::string gl = render::gl_description();
    spdlog::info("view: {}", gl);

    glfwSetWindowUserPointer(window_, this);
    glfwSetCursorPosCallback(window_, on_cursor);
    glfwSetMouseButtonCallback(window_, on_button);
    glfwSetScrollCallback(window_, on_scroll);
    glfwSetKeyCallback(window_, on_key);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the working folder
    ImGui::StyleColorsDark();
    // Installs ImGui's callbacks, which chain to the ones above.
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
    imgui_ready_ = true;

    const bool headless = options_.exit_after > 0.0;
    std::error_code ec;
    if (options_.input.empty())
        start_load(options_.bundled_mesh);
    else if (std::filesystem::exists(options_.input, ec))
        start_load(options_.input);
    else if (auto address = net::resolve_address(options_.input))
    {
        if (!join_session(options_.input, options_.participant) && headless)
            return 1;
    }
    else
    {
        // Neither: say both, since a misspelt file and a host name look alike.
        set_status(options_.input +
                       " is neither an existing file nor a HOST:PORT to join (a.b.c.d:port, "
                       "localhost:port or hostname:port): " +
                       address.error().message,
                   true);
        if (headless)
            return 1;
    }

    const auto start = Clock::now();
    last_frame_ = start;
    double frame_seconds_sum = 0.0;
    std::uint64_t timed_frames = 0;
    bool interrupted = false;
    while (glfwWindowShouldClose(window_) == GLFW_FALSE)
    {
        if (options_.stop != nullptr && *options_.stop != 0)
        {
            // Ctrl-C: close as the window's close button does (a load is cancelled, a
            // session left with its hand-over).
            spdlog::info("view: interrupted; closing");
            interrupted = true;
            break;
        }
        glfwPollEvents();
        const auto now = Clock::now();
        const double wall_dt = seconds(now - last_frame_);
        last_frame_ = now;
        frame_ms_.push(static_cast<float>(wall_dt * 1e3));
        if (shown_since_)
        {
            frame_seconds_sum += wall_dt;
            ++timed_frames;
        }

        finish_load();
        if (headless && !load_ && !object_shown() && !session_ && status_error_)
            return 1;  // the input failed to load or the join failed: nothing to test
        if (headless && session_failed_)
            return 1;  // the session was lost: what the run checks did not happen
        if (headless && !shown_since_ && seconds(now - start) > options_.exit_after + 300.0)
        {
            spdlog::error("view: nothing to show after {:.0f} s; giving up", seconds(now - start));
            return 3;
        }
        if (shown_since_)
        {
            const double t = seconds(now - *shown_since_);
            if (script_)
                script_->play(t, *this);
            if (headless && t >= options_.exit_after)
                break;
        }
        simulate(wall_dt);
        update_surface();
        if (object_shown() && !shown_since_)
            shown_since_ = Clock::now();

        int fb_w = 0;
        int fb_h = 0;
        glfwGetFramebufferSize(window_, &fb_w, &fb_h);
        fb_w = std::max(fb_w, 1);
        fb_h = std::max(fb_h, 1);
        g_gl.bind_framebuffer(GL_FRAMEBUFFER, 0);
        g_gl.viewport(0, 0, fb_w, fb_h);
        draw_.color = color_;
        if (rest_bounds_)
            draw_.camera.distance =
                zoom_ *
                render::fit_distance(rest_bounds_->radius(), draw_.camera.fov_y_deg, fb_w, fb_h);
        draw_.displacement_range = static_cast<float>(std::max(0.02 * object_radius_, 1e-9));
        if (object_shown())
            renderer_->draw(draw_, fb_w, fb_h);
        else
        {
            g_gl.clear_color(draw_.background.r, draw_.background.g, draw_.background.b, 1.0F);
            g_gl.clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        }
        if (screenshot_request_ && object_shown())
            last_coverage_ = coverage(read_back_buffer(fb_w, fb_h), draw_.background);

        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        draw_panels();
        ImGui::Render();
        ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

        if (screenshot_request_)
        {
            write_screenshot(*screenshot_request_, fb_w, fb_h);
            screenshot_request_.reset();
        }
        glfwSwapBuffers(window_);
        ++frames_;
    }

    // The final screenshot (--screenshot): the last frame drawn again, scene first for the
    // coverage figure, then with the panels.
    int fb_w = 0;
    int fb_h = 0;
    glfwGetFramebufferSize(window_, &fb_w, &fb_h);
    fb_w = std::max(fb_w, 1);  // a minimised window may report 0 x 0, as in the loop
    fb_h = std::max(fb_h, 1);
    bool shot_ok = true;
    if (!options_.screenshot.empty() && object_shown())
    {
        g_gl.bind_framebuffer(GL_FRAMEBUFFER, 0);
        renderer_->draw(draw_, fb_w, fb_h);
        last_coverage_ = coverage(read_back_buffer(fb_w, fb_h), draw_.background);
        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        draw_panels();
        ImGui::Render();
        ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
        shot_ok = write_screenshot(options_.screenshot, fb_w, fb_h);
    }
    if (session_)
        leave_session();

    const double elapsed = seconds(Clock::now() - start);
    std::printf(
        "view: %llu frames in %.1f s (%.1f fps while showing), display level %d "
        "(%zu triangles), %s\n",
        static_cast<unsigned long long>(frames_), elapsed,
        frame_seconds_sum > 0.0 ? static_cast<double>(timed_frames) / frame_seconds_sum : 0.0,
        display_level_, renderer_->triangle_count(), gl.c_str());
    std::printf("view: largest |u| reached %.4e m = %.3f %% of the object radius\n", max_u_reached_,
                object_radius_ > 0.0 ? 100.0 * max_u_reached_ / object_radius_ : 0.0);
    if (!options_.screenshot.empty())
    {
        if (!object_shown())
        {
            spdlog::error("view: nothing was shown, no screenshot written");
            return interrupted ? 130 : 3;
        }
        if (shot_ok)  // write_screenshot said why it could not
            std::printf("view: screenshot %s (%dx%d), the object covers %.1f %% of the 3D view\n",
                        options_.screenshot.string().c_str(), fb_w, fb_h, 100.0 * last_coverage_);
    }
    std::fflush(stdout);
    if (!shot_ok)
        return 3;
    if (script_failed_)
    {
        spdlog::error("view: a scripted export failed (above)");
        return 3;
    }
    return interrupted ? 130 : 0;  // 130: the CLI's status for a run stopped by Ctrl-C
}

bool display_available(std::string* why)
{
    // GLFW reports why through the error callback; keep its last message.
    static thread_local std::string last;
    last.clear();
    glfwSetErrorCallback([](int code, const char* message)
                         { last = "GLFW error " + std::to_string(code) + ": " + message; });
    const bool ok = glfwInit() == GLFW_TRUE;
    if (ok)
        glfwTerminate();
    glfwSetErrorCallback(nullptr);
    if (!ok && why != nullptr)
        *why = last.empty() ? std::string("GLFW could not start (no display?)") : last;
    return ok;
}

int run_viewer(const ViewerOptions& options)
{
    Viewer viewer(options);
    return viewer.run();
}

}  // namespace pliant::viewer
