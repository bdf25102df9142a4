// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Runge-Kutta-Fehlberg 4(5) for the membrane (docs/design.md §4), forces, and the step API.
///
/// Design
/// - The ODE is u' = v, v' = a(u, v) = -beta v - k_f u - M^-1 K u + M^-1 f. Only the six velocity
///   slopes kv_s are stored: the displacement slopes are the stage velocities
///   V_s = v + h sum_j a_sj kv_j, so the stage displacements are
///   U_s = u + h c_s v + h^2 sum_m (A^2)_sm kv_m. U_s is computed a row at a time into a small
///   per-thread buffer and the stencil reads it there, so K is never applied to a stored stage
///   plane ("fused" stages). The sixth stage is fused with the final update and the error
///   estimate, so kv_6 is never stored.
/// - Full steps run as a row pipeline (src/sim/row_pipeline.cpp, docs/physics.md §8): all six
///   stages in one sweep over the rows, the slopes in per-thread ring rows, one band of rows per
///   thread and no barrier inside a step; only u, v and the model are read from memory.
///   Restricted steps run on the same pipeline over the rows and x-segments of their owned
///   regions only (plus the one-node ring of Dirichlet stage displacements the stencil reads),
///   planned once per owned set. The stage-by-stage pass (kv planes, a barrier and a twin/ghost
///   copy after each stage) remains for grids whose copies do not fit the pipeline and for tests.
///   Every node gets the same operations in the same order either way.
/// - The propagated solution is the 5th-order one (local extrapolation); the embedded 4th-order
///   solution only gives the error estimate, in the max norm over canonical nodes,
///   |e_i| / (atol + rtol max(|y_i|, |y_new_i|)) for u and v. Max is order-independent, so the
///   error (and hence every accept/reject decision) is identical for any thread count.
/// - Every node's arithmetic is the same whichever thread or band runs it, so results are
///   bit-identical for any thread count. Twins and the ghost ring are copied from canonical
///   nodes after each slope row (pipeline) or stage (stage pass).
/// - Restricted steps: only the canonical nodes inside `owned` regions are integrated; all
///   others are Dirichlet values held fixed at their step-start u during the step (their v and
///   slopes are taken as zero) and are left untouched (or, with StepOptions::keep_outside false,
///   untouched as far as the stencils' first ring). Restricting to all leaves gives the full
///   step bit for bit.
/// - Forces enter as dense acceleration planes built from the force list (see `Force` for how
///   they are spread over nodes): the acceleration `accel` at time `accel_time` and its rate
///   `accel_rate`, so stage s of a step from t with size h adds
///   accel + (t + c_s h - accel_time) accel_rate. The rate is zero (forces constant over the
///   step) except inside `advance_to` with `ForceHold::Linear`, which ramps each node's force
///   from its value at the call's start to the new forces' at its target time.

#include <pliant/core/field.h>
#include <pliant/core/progress.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>
#include <pliant/sim/membrane.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant::sim
{

/// A user force: on a picked face (`face` >= 0, an index into `TetraGrid::triangles()`), or on
/// the nodes within `radius` of `point` (`face` < 0). Only its component along each node's rest
/// normal acts (a membrane under tension carries no in-plane load in this model).
/// Distribution: a face gives each of its three vertices 1/3 of F.N_i; a point force gives node i
/// (rest position within the radius) the share w_i / sum w of F.N_i, w_i = (1 - (d_i/radius)^2)^2;
/// with no node inside the radius, the nearest node takes it all. Nodal force -> acceleration
/// f_i / m_i with the real lumped mass m_i of the current assembly (a re-assembly rescales the
/// accelerations held in the workspace to its new masses).
struct Force
{
    std::int64_t face = -1;  ///< face index (0 .. 4W^2-1), or any negative value (-1) for
                             ///< point + radius
    core::Vec3 point{};      ///< centre on the rest surface [m] (point forces)
    double radius = 0.0;     ///< support radius [m] (point forces), >= 0
    core::Vec3 vector{};     ///< the force [N]
};

/// `force` scaled down to magnitude `max_force` when it is longer (its direction kept), else
/// `force` itself, bit for bit; `max_force` 0 means no limit. Every step applies its forces
/// through it with MembraneSettings::max_force.
[[nodiscard]] core::Vec3 limit_force(core::Vec3 force, double max_force) noexcept;

/// A limit for user forces that real use stays under (session::SessionSettings::max_force's
/// default): the force that holds a patch of a tenth of the object's radius R one diameter 2R
/// away from rest, F = (rho pi (R/10)^2 k_f + 2 pi T) 2R, with R half the diagonal of the rest
/// positions' bounding box (canonical nodes of `rest`, any ghost width). The patch's stiffness
/// is the viewer's default grab spring's (docs/viewer.md): a drag at that stiffness reaches the
/// limit only a whole diameter away. Only T, rho and k_f of `material` count.
[[nodiscard]] double default_max_force(const core::TetraGrid& grid,
                                       const core::Vec3Field<double>& rest,
                                       const MembraneSettings& material) noexcept;

/// The largest fixed step [s] (within 1 %) at which no mode of `model` grows by more than 1e-7
/// per step: omega_max is bounded by Gershgorin's theorem on M^-1 K + k_f (row sums of the
/// stencil, 2 sum|w| / m per node, an over-estimate: 1.36x the true one on the equal-area
/// sphere at levels 5-8, 1.22-1.25x on the gnomonic one at levels 5-7), and every mode's
/// eigenvalues -beta/2 +- i sqrt(omega^2 - beta^2/4) for omega in [0, omega_max] are checked
/// against the stability polynomial of the propagated fifth-order Fehlberg solution, searching
/// down from omega_max h = 3.5 in steps of 1 %. Fehlberg's polynomial has a z^6 coefficient
/// 1/2080, below exp's 1/720, so it is above 1 on the imaginary axis for 0 < |z| < 2.046
/// (Dormand-Prince's, 1/600, is not, near 0): without damping no step is strictly stable, and
/// the bound keeps the growth under 1e-7 per step (omega_max h = 0.22). Damping moves every mode
/// left by beta h / 2, so the bound depends on beta h, i.e. on beta / omega_max: omega_max h
/// rises slowly with it (0.57 at beta / omega_max = 1e-4, 0.94 at 1e-3, 1.28 just below
/// 0.00342) and is the ceiling 3.5 for beta from 0.00342 omega_max (beta h = 0.012) up to
/// 0.084 omega_max. More damping shortens the step a little (the stable region is only 0.14
/// wide at Im z = 3.5: 3.46 at 0.09, 3.04 at 0.5), and from beta ~ omega_max the over-damped
/// modes near -beta bound it at beta h < 3.68, the end of the stable real interval. The same
/// beta thus gives another omega_max h on another grid (docs/physics.md §5 has the measured
/// steps).
[[nodiscard]] double stable_fixed_step(const MembraneModel& model) noexcept;

/// Checks forces against a model. \return InvalidArgument naming the force and the rule.
core::Result<void> validate_forces(const MembraneModel& model, std::span<const Force> forces);
/// The same for a grid of `face_count` faces (a face force's face must be below it), for a
/// caller that knows the grid before it has a model; with no grid known yet, pass the largest
/// int64 and every rule but the face's range is checked.
core::Result<void> validate_forces(std::int64_t face_count, std::span<const Force> forces);

/// Bit flags of a step's outcome.
enum class StepStatus : std::uint32_t
{
    Ok = 0,
    Rejected = 1U << 0,        ///< at least one trial step was rejected (count in the report)
    MinStepReached = 1U << 1,  ///< accepted at dt_min with the error still above tolerance
    NonFinite = 1U << 2,       ///< a trial produced NaN/inf at dt_min: the state was kept as is
};
[[nodiscard]] constexpr StepStatus operator|(StepStatus a, StepStatus b) noexcept
{
    return static_cast<StepStatus>(static_cast<std::uint32_t>(a) | static_cast<std::uint32_t>(b));
}
[[nodiscard]] constexpr bool has_flag(StepStatus s, StepStatus flag) noexcept
{
    return (static_cast<std::uint32_t>(s) & static_cast<std::uint32_t>(flag)) != 0;
}

/// What one `step` did.
struct StepReport
{
    StepStatus status = StepStatus::Ok;
    std::uint32_t rejections = 0;  ///< rejected trials before the accepted one
    double dt = 0.0;               ///< the accepted step [s] (0 when nothing was accepted)
    double error = 0.0;            ///< scaled error norm of the accepted step: <= 1 in
                                   ///< adaptive mode unless MinStepReached; computed in
                                   ///< fixed-step mode too, where it may exceed 1 and sets no
                                   ///< flag
    bool reassembled = false;      ///< K and M were re-assembled before this step
};

/// What one `advance_to` did.
struct AdvanceReport
{
    StepStatus status = StepStatus::Ok;  ///< union of the steps' flags
    std::uint64_t steps = 0;
    std::uint64_t rejections = 0;
    std::uint64_t at_min_steps = 0;  ///< accepted steps flagged MinStepReached (at dt_min
                                     ///< with the error above tolerance)
    /// The state is at the target: time == target (adaptive), or no full fixed step fits any
    /// more; also true, with no step taken, for a target at or before `state.time` (time never
    /// goes back).
    bool reached = false;
    bool stopped = false;  ///< `stop` asked advance_to to stop (between two steps)
};

/// Per-step options.
struct StepOptions
{
    /// Restrict the step to the canonical nodes inside these regions (see the file comment);
    /// empty = all nodes. Regions must lie inside the grid.
    std::span<const core::Region> owned{};
    /// Restricted steps only: the canonical nodes whose result the caller needs, inside the
    /// owned ones (empty = every owned node). Each pair of stages is then computed only where
    /// these nodes depend on it: stages 1-2 on `needed` dilated by 2 stencil rings, 3-4 by 1
    /// ring, 5-6 on `needed` itself (each within `owned`; the error reaches one ring inwards per
    /// two stages, docs/physics.md §6). Only the needed nodes are updated (the other owned nodes
    /// keep their state), and the error norm and the non-finite check cover them only. Their
    /// result is the restricted step's over `owned`, bit for bit; when `owned` holds `needed`
    /// dilated by 3 rings, it is the full step's (exact coupling's halo, docs/session.md §4.1).
    std::span<const core::Region> needed{};
    /// Restricted steps: whether the nodes beyond the owned ones and their first stencil ring
    /// keep their values. true: an accepted step copies its result into the state, and every
    /// node outside `needed` keeps its value. false: an accepted step on the pipeline swaps
    /// planes with the workspace as a full step does, after copying over only the owned nodes
    /// outside `needed` and the first ring around the owned ones (the Dirichlet values the
    /// stencils read): every node a following step reads or is asked to keep holds what it
    /// would hold with `true`, and the nodes beyond hold values of an earlier step. For callers
    /// that rewrite those nodes before they read them (the session's peers do: halos and other
    /// owners' states). Saves copying the result back, a few per cent of a half-grid step
    /// (docs/physics.md §8). Full steps and the stage-by-stage pass ignore it.
    bool keep_outside = true;
    /// Largest step for this call [s] (e.g. to land on a frame time); 0 = no limit.
    double dt_limit = 0.0;
};

/// All planes and buffers of the integrator, so a step allocates nothing. Also carries the
/// adaptive step proposal between calls. One workspace per state being integrated.
class Rkf45Workspace
{
public:
    /// \param threads the most OpenMP threads a step may use (0 = OpenMP's maximum).
    explicit Rkf45Workspace(const MembraneModel& model, int threads = 0);

    /// The step size the next adaptive step will try [s].
    [[nodiscard]] double next_dt() const noexcept { return next_dt_; }
    void set_next_dt(double dt) noexcept { next_dt_ = dt; }

    // Planes (ghost ring 1, the model's stride). Public for the kernels and tests; treat as
    // scratch.
    std::vector<core::Field<double>> kv;  ///< kv_1 .. kv_5
    core::Field<double> u_out, v_out;     ///< trial state
    core::Field<double> v_src;            ///< v masked to the owned nodes (restricted stage pass)
    core::Field<double> accel;            ///< force accelerations [m/s^2] at `accel_time`
    core::Field<double> accel_rate;       ///< their rate of change [m/s^3] (zero but in a ramp)
    core::Field<double> accel_end;  ///< a linear hold's accelerations at its end (allocated by the
                                    ///< first one)
    double accel_time = 0.0;        ///< the time [s] at which `accel` holds
    std::vector<double> row_buffers;  ///< per thread: 3 rows of stage displacements
    std::size_t row_buffer_len = 0;   ///< doubles per thread
    std::vector<double> leaf_error;   ///< per leaf (or pipeline band) error norm
    std::vector<double> leaf_probe;   ///< per leaf (or pipeline band) NaN probe
    // The fused row pipeline of full steps (docs/physics.md §8): per thread, ring rows of
    // kv_1..kv_4 and the rolling stage-displacement rows; the model's twin and ghost copies
    // regrouped by the row they read, as column pairs (dst, src) with x + 1 (0 = ghost column
    // x = -1): copies within row y are row_copies[row_copy_start[y] .. row_copy_start[y + 1]),
    // the ghost row y = -1 reads row 1 (below_copies), the ghost row y = ny reads row ny - 2
    // (above_copies).
    std::vector<double> pipeline_buffers;
    std::size_t pipeline_buffer_len = 0;  ///< doubles per thread
    std::size_t pipeline_row_len = 0;     ///< doubles per buffered row (8 + nx + 1, rounded up)
    std::vector<core::GhostCopy> row_copies;
    std::vector<std::size_t> row_copy_start;
    std::vector<core::GhostCopy> below_copies;
    std::vector<core::GhostCopy> above_copies;
    bool pipeline_ok = false;  ///< the copies fit the pipeline (always, for TetraGrid's gluing)
    // Restricted steps on the pipeline (docs/physics.md §8), planned once per owned and needed
    // set (`restricted_key`, `needed_key`: the regions of the last plan). Per pair of stages
    // (1-2, 3-4, 5-6): per row, the x-segments [x0, x1) of the stage-displacement fills (rows
    // -1 .. ny, at fill_start[y + 1]) and of the slope kernels (rows 0 .. ny - 1, at
    // kernel_start[y]), each marked by whether its nodes move (their canonical node is owned)
    // or are Dirichlet. All three pairs run over the owned set, or over `needed` dilated by 2,
    // 1 and 0 rings (StepOptions::needed). The rows [restricted_y0, restricted_y1) hold the last
    // pair's kernels, with the prefix sums of their widths (band split).
    struct RowSegment
    {
        int x0 = 0;
        int x1 = 0;
        bool moves = false;
    };
    struct PairPlan
    {
        std::vector<RowSegment> fill_segments;
        std::vector<std::size_t> fill_start;
        std::vector<RowSegment> kernel_segments;
        std::vector<std::size_t> kernel_start;
    };
    std::vector<core::Region> restricted_key;
    std::vector<core::Region> needed_key;
    bool restricted_planned = false;
    std::array<PairPlan, 3> pair_plans;
    std::vector<std::size_t> restricted_work;  ///< [y]: work of rows < y (width + a row cost)
    std::vector<char> copies_move;  ///< [y]: a twin/ghost copy of row y reads a moving node
    int restricted_y0 = 0;
    int restricted_y1 = 0;
    /// Steps with StepOptions::keep_outside false: the canonical nodes a swapping accept copies
    /// from the state into the trial planes before the swap (the owned nodes, their first ring
    /// and the nodes any fill reads, less those the last pair writes), and the twin and ghost
    /// copies such a step syncs (those whose node it reads or keeps).
    std::vector<core::Region> keep_runs;
    std::vector<core::GhostCopy> live_sync;
    // Full steps in mixed precision (MembraneSettings::precision, docs/physics.md §9): float
    // copies of the model's wx, wy, wd and 1/m planes (`mixed_plane_len` floats each, the
    // model's padded layout, in that order), made for the model's assembly `mixed_assembly`
    // (0: none yet); and per thread the pipeline's rows in float plus a ring of K u rows. Made
    // by the first mixed step (and after each re-assembly), by the constructor when the model
    // asks for mixed precision.
    std::vector<float> mixed_model;
    std::size_t mixed_plane_len = 0;
    std::uint64_t mixed_assembly = 0;
    std::vector<float> mixed_buffers;
    std::size_t mixed_buffer_len = 0;   ///< floats per thread
    std::size_t mixed_row_len = 0;      ///< floats per buffered row
    bool use_pipeline = true;           ///< false: all steps run stage by stage (tests, benchmarks)
    std::vector<std::int64_t> touched;  ///< accel offsets written by the last force set
    std::vector<std::int64_t> end_touched;   ///< accel_end offsets written (linear hold)
    std::vector<std::int64_t> rate_touched;  ///< accel_rate offsets set (linear hold)
    /// A re-assembly's scratch: the stencil masses before it, so that the force accelerations
    /// f / m follow the new masses (allocated by the first re-assembly).
    core::Field<double> reassembly_masses;
    /// [y]: accel or accel_rate may be non-zero in row y (the pipeline reads them only there).
    /// Kept by set_forces and the ramp functions; code that writes the planes directly must
    /// mark the rows it writes.
    std::vector<char> forced_rows;
    int max_threads = 1;

private:
    double next_dt_ = 0.0;
};

/// Writes the accelerations of `forces` into `ws.accel` (clearing the previous ones), held
/// constant from now on (zero rate).
/// \pre `validate_forces(model, forces)` succeeded.
void set_forces(const MembraneModel& model, Rkf45Workspace& ws, std::span<const Force> forces);

/// A linear hold: from time `t0` (where `ws.accel` holds the current forces, rate zero) to `t1`
/// > t0, each node's acceleration goes linearly to that of `forces`. Only the nodes the old or
/// new forces touch are visited. `end_force_ramp` closes it.
/// \pre `validate_forces(model, forces)` succeeded.
void begin_force_ramp(const MembraneModel& model, Rkf45Workspace& ws, std::span<const Force> forces,
                      double t0, double t1);

/// Ends a linear hold at time `t`: `ws.accel` becomes the ramp's value there (the new forces
/// exactly when `reached`, i.e. t is the ramp's end) and the rate zero.
void end_force_ramp(const MembraneModel& model, Rkf45Workspace& ws, double t, bool reached);

/// One step (adaptive or fixed per the model's settings) with the forces last given to
/// `set_forces`. Re-assembles K and M first when the tick is a multiple of R. A rejected trial
/// is retried with a smaller step; the state is only changed by an accepted step, and a
/// non-finite trial at dt_min leaves it untouched (NonFinite).
StepReport step_prepared(MembraneModel& model, MembraneState& state, Rkf45Workspace& ws,
                         const StepOptions& options = {});

/// `set_forces` then `step_prepared`.
StepReport step(MembraneModel& model, MembraneState& state, Rkf45Workspace& ws,
                std::span<const Force> forces, const StepOptions& options = {});

/// Steps until `state.time` reaches `target_time` [s] (adaptive: the last step is shortened to
/// land on it; fixed-step: as many whole steps as fit, the remainder waits for the next call),
/// with `forces` held as the model's `force_hold` says: unchanged over the call (Step), or
/// ramped linearly from the previous call's forces to reach `forces` at `target_time` (Linear;
/// the first call ramps up from zero). Real-time use: one call per frame. Stops early after
/// `max_steps` steps, on NonFinite, or when `stop` (may be null) says stop_requested(), polled
/// before every step (a user's Ctrl-C in `pliant simulate`; the state is then that of the last
/// whole step; a linear hold keeps the forces it reached). A target at or before `state.time`
/// takes no step (reached, and the forces are set for the next call).
/// \pre `target_time` is finite (a PLIANT_ASSERT failure otherwise: a NaN target would step
/// until `max_steps`).
AdvanceReport advance_to(MembraneModel& model, MembraneState& state, Rkf45Workspace& ws,
                         double target_time, std::span<const Force> forces,
                         const StepOptions& options = {}, std::uint64_t max_steps = 10'000'000,
                         const core::ProgressSink* stop = nullptr);

}  // namespace pliant::sim
