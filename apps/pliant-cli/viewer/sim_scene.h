// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// What the viewer simulates and shows (docs/viewer.md):
// - `LocalSim`: a sim::MembraneModel and its state, advanced in real time: one
//   sim::advance_to per frame towards the wall clock, with the simulated interval and the number
//   of steps capped so a slow machine lags behind real time instead of freezing the window.
// - `SurfaceView`: the deformed surface p = P + u N of any model (local, or a session's display
//   state) at the simulation level, as a triangle soup over unique vertices for picking, and
//   refined by modified butterfly to the display level for the renderer. All planes are made
//   once per (level, display level) and reused every frame.
// - `Grab`: a mouse drag turned into a sim::Force: the picked point of the drawn surface, kept
//   as where it lies on the grid (`SurfacePoint`); the force is a spring from that point's
//   current position on the drawn surface to where the mouse has dragged it, applied as a point
//   force (radius around the same grid point on the simulation-level rest surface).

#include <pliant/core/field.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>
#include <pliant/subdiv/convolution_plan.h>

#include "picking.h"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace pliant::viewer
{

/// The default material: the demo's (cmd_demo.cpp), lightly damped and with a foundation so the
/// surface springs back after a drag.
[[nodiscard]] sim::MembraneSettings default_material(int level);

class LocalSim
{
public:
    /// \return the model's errors (DegenerateFace, ...).
    static core::Result<LocalSim> create(const core::TetraGrid& grid,
                                         const core::Vec3Field<double>& rest,
                                         const sim::MembraneSettings& settings);

    /// Advances by the wall-clock interval `wall_dt` (capped at `max_interval`), at most
    /// `max_steps` steps, with `forces`. Returns what advance_to did; NonFinite resets the state.
    sim::AdvanceReport advance(double wall_dt, std::span<const sim::Force> forces,
                               double max_interval = 0.1, std::uint64_t max_steps = 400);
    /// New material or integrator settings: the model is rebuilt from the rest positions (the
    /// state is kept). \return the model's validation errors (the old model stays).
    core::Result<void> set_settings(const sim::MembraneSettings& settings);
    /// Back to rest.
    void reset();
    /// Goes on from `state` (of this model's grid, ghosts synced).
    void set_state(sim::MembraneState state) { state_ = std::move(state); }

    [[nodiscard]] const sim::MembraneModel& model() const noexcept { return *model_; }
    [[nodiscard]] const sim::MembraneState& state() const noexcept { return state_; }
    [[nodiscard]] double last_step_seconds() const noexcept { return last_step_s_; }

private:
    LocalSim() = default;
    std::unique_ptr<sim::MembraneModel> model_;
    std::unique_ptr<sim::Rkf45Workspace> workspace_;
    sim::MembraneState state_;
    core::Vec3Field<double> rest_;
    double last_step_s_ = 0.0;
};

/// A point of the surface by where it lies on the grid: x, y in cells of the simulation level
/// (0 <= x <= 2W, 0 <= y <= W). It names the same point of the object at every level, since
/// refinement keeps each level's nodes and splits each grid triangle into four with the same
/// diagonal; within a triangle the point is placed linearly.
struct SurfacePoint
{
    double x = 0.0;
    double y = 0.0;
};

class SurfaceView
{
public:
    /// Recomputes the sim-level surface from `model` and `u` (ghost ring >= 0, twins equal) and
    /// refines it `display_levels` levels (0 .. 10 - level). Allocates only when the levels
    /// change.
    void update(const sim::MembraneModel& model, const core::Field<double>& u, int display_levels);

    /// \pre !empty() for the three display accessors.
    [[nodiscard]] const core::TetraGrid& display_grid() const noexcept
    {
        return plans_.empty() ? *grid_ : plans_.back().fine_grid();
    }
    [[nodiscard]] const core::Vec3Field<double>& display_positions() const noexcept
    {
        return levels_.back().p;
    }
    [[nodiscard]] const core::Field<double>& display_u() const noexcept { return levels_.back().u; }
    /// Sim-level deformed positions per unique vertex, and the faces (TetraGrid::triangles()).
    [[nodiscard]] const std::vector<core::Vec3>& positions() const noexcept { return unique_; }
    [[nodiscard]] const std::vector<std::array<std::uint32_t, 3>>& faces() const noexcept
    {
        return faces_;
    }
    /// Rest position per unique vertex.
    [[nodiscard]] const std::vector<core::Vec3>& rest_positions() const noexcept { return rest_; }
    /// The nearest point where `ray` meets the display surface (the refined one the renderer
    /// draws, not the simulation level's), and where it lies; nullopt for a miss. Brute force
    /// over the display triangles (4^k times the simulation level's; about 6 ms for 262K
    /// triangles here), so made on a mouse press only. \pre !empty().
    [[nodiscard]] std::optional<std::pair<SurfacePoint, core::Vec3>> pick(
        const Ray& ray) const noexcept;
    /// The point `at` on the display surface. \pre !empty().
    [[nodiscard]] core::Vec3 display_point(SurfacePoint at) const noexcept;
    /// The point `at` on the simulation level's rest surface. \pre !empty().
    [[nodiscard]] core::Vec3 rest_point(SurfacePoint at) const noexcept;
    /// Largest |u| over the nodes at the sim level, this update.
    [[nodiscard]] double max_abs_u() const noexcept { return max_abs_u_; }
    [[nodiscard]] bool empty() const noexcept { return faces_.empty(); }

private:
    int level_ = 0;
    int display_levels_ = -1;
    std::vector<subdiv::ConvolutionPlan> plans_;
    struct Planes
    {
        core::Vec3Field<double> p;
        core::Field<double> u;
    };
    std::optional<core::TetraGrid> grid_;
    // levels_[k]: p and u at sim level + k (ghost ring 1, as refine's input needs).
    std::vector<Planes> levels_;
    std::vector<core::Vec3> unique_;
    std::vector<core::Vec3> rest_;
    std::vector<std::array<std::uint32_t, 3>> faces_;
    double max_abs_u_ = 0.0;
};

/// A drag in progress on the surface.
struct Grab
{
    SurfacePoint at;         ///< the grabbed point
    core::Vec3 target{};     ///< where the mouse holds the grabbed point (world)
    double radius = 0.0;     ///< support radius of the force [m]
    double stiffness = 0.0;  ///< spring constant [N/m]

    /// The grabbed point on the current display surface (what the mouse holds).
    [[nodiscard]] core::Vec3 current(const SurfaceView& view) const noexcept;
    /// The grabbed point on the rest surface.
    [[nodiscard]] core::Vec3 rest(const SurfaceView& view) const noexcept;
    /// The force: stiffness * (target - current) at the rest point, within `radius`.
    [[nodiscard]] sim::Force force(const SurfaceView& view) const noexcept;
};

/// A spring constant that moves a grabbed patch of `radius` about halfway to the mouse against
/// the foundation and the tension of `material` (N/m).
[[nodiscard]] double default_grab_stiffness(const sim::MembraneSettings& material, double radius);

/// The longest simulated interval over which a grab's spring force may be held unchanged [s]. The
/// force is evaluated once per frame from the shown surface and held for the frame's interval;
/// the grabbed patch (mass rho pi r^2) on the spring oscillates at omega = sqrt(k / (rho pi r^2)),
/// and held much longer than 1/omega the spring overshoots further every frame: at 3.8 fps with
/// the 0.1 s cap the surface reached |u| = 12 km. Frames slower than this run the simulation in
/// slow motion instead (docs/viewer.md, Real time).
[[nodiscard]] double grab_hold_limit(const sim::MembraneSettings& material, const Grab& grab);

}  // namespace pliant::viewer
