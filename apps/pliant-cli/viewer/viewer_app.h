// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The viewer's state, shared by viewer.cpp (window, frame loop, input, sessions, screenshots)
// and viewer_panels.cpp (the ImGui panels). A thin shell (docs/style.md §9): the simulation, the
// refinement and the drawing are the library's; this file wires them to a window.
//
// One frame: poll window events -> play the script -> poll a finished background load ->
// advance the simulation (local: sim::advance_to towards the wall clock; session: poll and
// advance the Session) -> refine p = P + u N to the display level and upload -> draw the
// surface with render::GridRenderer -> ImGui panels -> screenshot if asked -> swap buffers.
// The window never waits on work: a mesh is remeshed on a worker thread (mesh_loader.h) and the
// per-frame simulation is capped (sim_scene.h).

#include <pliant/core/tetra_grid.h>
#include <pliant/net/transport.h>
#include <pliant/render/draw_settings.h>
#include <pliant/render/grid_renderer.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>

#include "input_script.h"
#include "mesh_loader.h"
#include "sim_scene.h"
#include "viewer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

struct GLFWwindow;

namespace pliant::viewer
{

/// A fixed-size history for ImGui::PlotLines.
struct PlotHistory
{
    static constexpr std::size_t k_size = 240;
    std::array<float, k_size> values{};
    std::size_t next = 0;
    void push(float v) noexcept
    {
        values[next] = v;
        next = (next + 1) % k_size;
    }
    [[nodiscard]] float latest() const noexcept { return values[(next + k_size - 1) % k_size]; }
};

class Viewer final : public InputSink
{
public:
    explicit Viewer(const ViewerOptions& options);
    ~Viewer() override;
    Viewer(const Viewer&) = delete;
    Viewer& operator=(const Viewer&) = delete;

    /// Opens the window and runs until it closes. \return the exit code.
    int run();

    // InputSink: window pixel coordinates (x right, y down).
    void mouse_move(double x, double y) override;
    void mouse_button(bool down, double x, double y) override;
    void wheel(double x, double y, double clicks) override;
    void key(std::string_view name) override;
    void export_file(std::string_view file) override;
    void load_file(std::string_view file) override;

    // Panels (viewer_panels.cpp).
    void draw_panels();

    using Clock = std::chrono::steady_clock;

    // --- state (public to the two files of the viewer; nothing else sees this class) ---
    ViewerOptions options_;
    GLFWwindow* window_ = nullptr;
    bool imgui_ready_ = false;
    std::optional<render::GridRenderer> renderer_;
    render::DrawSettings draw_;
    render::ColorMode color_ = render::ColorMode::Displacement;
    double zoom_ = 1.0;  ///< distance / fitted distance
    std::optional<render::Bounds> rest_bounds_;

    // Loading.
    std::unique_ptr<LoadJob> load_;
    std::string status_;  ///< last message shown in the status panel (errors in red)
    bool status_error_ = false;
    std::string surface_name_;
    std::array<char, 512> load_path_{};

    // Local simulation.
    std::optional<LoadedSurface> surface_;
    std::optional<LocalSim> local_;
    sim::MembraneSettings material_;
    bool paused_ = false;
    int display_level_ = -1;  ///< absolute
    SurfaceView view_;
    bool gpu_surface_valid_ = false;

    // Sessions.
    std::unique_ptr<net::Transport> transport_;
    std::unique_ptr<session::Session> session_;
    std::uint32_t shown_epoch_ = 0;
    int shown_owner_level_ = -1;
    std::vector<std::uint16_t> owners_display_;
    session::SessionStats last_stats_{};
    double last_stats_time_ = 0.0;
    std::array<char, 64> join_address_{"127.0.0.1:7777"};
    int host_port_ = 7777;
    bool join_as_participant_ = true;
    bool host_exact_ = false;
    bool open_session_panel_ = false;  ///< unfold the Session panel once (joined or hosting)
    std::string session_address_;      ///< the master's HOST:PORT (hosting: "port N")
    bool joined_ = false;              ///< the status line said the join completed
    bool hosting_ = false;             ///< the session was started here (its surface is ours)
    /// The material the local simulation ran with when this viewer began hosting: it goes on
    /// with it after the session ends (start_local would take the level's default).
    std::optional<sim::MembraneSettings> material_before_host_;
    bool resume_applied_ = false;  ///< ViewerOptions::resume_state went to a simulation
    bool session_failed_ = false;  ///< a session ended on its own (a headless run fails)

    // Input.
    enum class Drag : std::uint8_t
    {
        None,
        Orbit,
        Grab,
    };
    Drag drag_ = Drag::None;
    double mouse_x_ = 0.0, mouse_y_ = 0.0;
    std::optional<Grab> grab_;
    core::Vec3 grab_plane_normal_{};  ///< view direction at the press
    double grab_radius_factor_ = 0.08;
    double grab_stiffness_scale_ = 1.0;

    // Script, timing, statistics.
    std::optional<ScriptPlayer> script_;
    std::optional<Clock::time_point> shown_since_;  ///< first frame with the object
    Clock::time_point last_frame_{};
    PlotHistory frame_ms_, step_ms_, kbps_in_, kbps_out_, latency_ms_;
    double max_u_reached_ = 0.0;
    double object_radius_ = 0.0;
    std::uint64_t frames_ = 0;
    std::optional<std::filesystem::path> screenshot_request_;
    int export_format_ = 0;  ///< index into k_export_extensions (viewer.cpp): obj ply gltf glb
    double last_coverage_ = -1.0;

    // Helpers (viewer.cpp).
    void start_load(const std::filesystem::path& path);
    void finish_load();
    void start_local(LoadedSurface surface);
    /// Lets go of a grab: the surface it holds (its face, rest point, radius) is about to be
    /// replaced, or the session it pulls in changes.
    void drop_grab() noexcept;
    /// Stops a remeshing in progress, saying so in the status line with `why`.
    void cancel_load(const std::string& why);
    /// The display level for a surface simulated at `sim_level`: --display-level clamped to
    /// sim_level .. max_display_level (with a warning above), else sim level + 1 up to 8.
    [[nodiscard]] int initial_display_level(int sim_level) const;
    /// The highest display level, as the panel's slider allows: sim level + 3, at most 10.
    [[nodiscard]] static int max_display_level(int sim_level) noexcept
    {
        return std::min(core::k_max_level, sim_level + 3);
    }
    bool join_session(const std::string& address, bool participant);
    bool host_session(std::uint16_t port, bool exact);
    /// Leaves (or, as master, ends) the session and goes on with a local simulation of its
    /// surface; `message` becomes the status line (an error keeps it red).
    void leave_session(const std::string& message = "left the session", bool error = false);
    void pump_session();
    void simulate(double wall_dt);
    void update_surface();
    void update_owners();
    [[nodiscard]] const sim::MembraneModel* model() const noexcept;
    [[nodiscard]] render::CameraMatrices camera_matrices() const;
    [[nodiscard]] bool object_shown() const noexcept;
    void set_status(std::string message, bool error);
    void request_screenshot(std::optional<std::filesystem::path> path);
    bool write_screenshot(const std::filesystem::path& path, int width, int height);
    /// Writes the simulation-level deformed surface p = P + u N (what is simulated and picked,
    /// not the refined display surface) with mesh::export_mesh; no path: the first free
    /// pliant-view-NNNN.<format> in the working folder. \return false (and an error status)
    /// when nothing is shown yet or the file cannot be written.
    bool export_surface(std::optional<std::filesystem::path> path);
    bool script_failed_ = false;  ///< a scripted export failed: the run ends with status 3
};

}  // namespace pliant::viewer
