// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The membrane model of docs/design.md §4: settings, the assembled model (rest geometry, cotangent
/// stiffness as a three-weight stencil, lumped mass) and the integrated state (u, v).
///
/// Design
/// - `MembraneModel` holds everything that changes only at a re-assembly: rest positions P, rest
///   normals N, the stiffness K as three edge weights per node (to the +x, +y and +(1,1)
///   neighbours; the other three edges of a node are its neighbours' weights) and the lumped
///   mass. All planes share one stride (ghost ring 1), so a kernel reads the seven stencil
///   points at fixed offsets with no branch.
/// - The weights and masses of ghost nodes are computed from ghost-padded positions, not copied:
///   every formula is symmetric under the gluing isometries (pairs of opposite terms are added
///   first, and IEEE addition commutes), so a ghost or twin node computes bit for bit what its
///   canonical node computes.
/// - Corners (docs/design.md §1): a corner's six grid triangles are its three real triangles, each
/// seen
///   twice through the ghost map. The stencil therefore gives at a corner twice the real stiffness
///   row and twice the real lumped mass; `M⁻¹K` is exact. `multiplicity()` is 2 there, 1
///   elsewhere; `unique_mass()` and `energy()` divide it out.
/// - `MembraneState` holds u [m] and v [m/s] (ghost ring 1), the time [s] and the tick; it is the
///   only thing integrated, hashed and sent.
///
/// Alternatives rejected: an assembled sparse matrix (Eigen SpMV is ~7x slower than the stencil
/// at level 10 and needs an index per entry); six weights per node (twice the bytes per stage).

#include <pliant/core/field.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace pliant::sim
{

/// How `advance_to` holds the forces it is given between calls (docs/physics.md §3).
enum class ForceHold : std::uint8_t
{
    /// Zero-order hold: the forces act unchanged from the call's start to its target time.
    /// Lockstep sessions use it (every peer applies a user's force from the same tick).
    Step,
    /// First-order hold: the forces are the values at the call's target time, and each node's
    /// force goes linearly from the value the previous call reached to it, evaluated at every
    /// Runge-Kutta stage. A force sampled once per frame (a dragged pick, a scenario's moving
    /// finger) then changes continuously instead of jumping at every frame, which excites far
    /// less high-frequency motion; it reaches its new value at the frame's end (half a frame
    /// later on average than the zero-order hold).
    Linear,
};

/// "step" or "linear": the names `pliant simulate`'s scenarios and the benchmarks use.
[[nodiscard]] std::string_view to_string(ForceHold hold) noexcept;

/// The arithmetic of a full RKF45 step (docs/physics.md §9).
enum class Precision : std::uint8_t
{
    /// Every operation in double precision. Restricted steps (sessions), the stage-by-stage
    /// pass and the tests' references always run this way.
    Double,
    /// The state u, v and the step's result stay double; the stencil of the step-start
    /// displacement K u is taken in double, the six stages' increments over it (K (U_s - u),
    /// the stage velocities, the slopes, the error estimate) in single precision, from
    /// single-precision copies of the weights and 1/m. Rounding then scales with the
    /// increment of a step, not with u (K U_s in single precision would cancel most of its
    /// digits on a fine grid). Full steps on the row pipeline only; otherwise Double.
    Mixed,
};

/// "double" or "mixed".
[[nodiscard]] std::string_view to_string(Precision precision) noexcept;

/// Material, integrator and threading settings (SI units). Validated by `MembraneModel::create`.
struct MembraneSettings
{
    double T = 1.0;            ///< tension [N/m], > 0
    double rho = 1.0;          ///< areal density [kg/m^2], > 0
    double beta = 0.0;         ///< nodal velocity damping, B = beta M [1/s], >= 0
    double k_f = 0.0;          ///< elastic foundation, k_f M u [1/s^2], >= 0
    int reassemble_every = 0;  ///< R: re-assemble K and M from the deformed surface every R
                               ///< accepted steps; 0 = never. The masses then become rho/3 x
                               ///< the deformed areas (rho per deformed area), and the force
                               ///< accelerations f/m are rescaled to them
    double rtol = 1e-4;        ///< RKF45 relative tolerance (per node, max norm), >= 0
    double atol = 1e-8;        ///< RKF45 absolute tolerance, > 0: one value for both u [m]
                               ///< and v [m/s]
    double dt_min = 1e-7;      ///< smallest adaptive step [s], > 0
    double dt_max = 0.05;      ///< largest adaptive step [s], >= dt_min. The default is far
                               ///< above the stable step of a fine grid (1.2 ms at level 6
                               ///< without damping, docs/physics.md §5): the error control,
                               ///< not dt_max, keeps adaptive steps stable
    double dt_initial = 1e-3;  ///< first adaptive step [s], in [dt_min, dt_max]
    double safety = 0.9;       ///< step-size controller safety factor, in (0, 1]
    double max_growth = 5.0;   ///< largest step growth per accepted step, > 1
    double min_shrink = 0.2;   ///< smallest factor from one accepted step to the next; a
                               ///< rejection retries at h min(0.9, max(min_shrink,
                               ///< safety err^-1/5)), a non-finite trial at
                               ///< h min(0.9, min_shrink) (both at least dt_min); in (0, 1)
    bool fixed_step = false;   ///< lockstep mode: every step is exactly `fixed_dt`, never rejected
    double fixed_dt = 1e-3;    ///< step of the fixed-step mode [s], > 0
    ForceHold force_hold = ForceHold::Step;   ///< how `advance_to` holds forces between calls
    Precision precision = Precision::Double;  ///< arithmetic of full steps
    int threads = 0;                          ///< OpenMP threads for a step; 0 = OpenMP's default
    int leaf_depth = -1;  ///< quad-tree depth of the parallel work split; -1 = level - 6 (64 x 64
                          ///< node leaves), clamped to 0..level
    /// The largest user force [N] a step applies: a force of greater magnitude acts scaled down
    /// to it, its direction kept (sim::limit_force); 0 = no limit (the default), >= 0. Sessions
    /// set it for every peer (session::SessionSettings::max_force), so that one peer's grab
    /// cannot throw the shared object arbitrarily far or overflow it.
    double max_force = 0.0;
};

/// Kinetic, strain and foundation energy [J] over the unique vertices.
struct Energy
{
    double kinetic = 0.0;     ///< 1/2 v^T M v
    double strain = 0.0;      ///< 1/2 u^T K u
    double foundation = 0.0;  ///< 1/2 k_f u^T M u
    [[nodiscard]] double total() const noexcept { return kinetic + strain + foundation; }
};

/// The integrated state: normal displacement u [m] and velocity v [m/s] per node (ghost ring 1),
/// the simulated time [s] and the number of accepted steps.
struct MembraneState
{
    core::Field<double> u;
    core::Field<double> v;
    double time = 0.0;
    std::uint64_t tick = 0;

    /// The rest state (u = v = 0, time 0) for `grid`.
    [[nodiscard]] static MembraneState at_rest(const core::TetraGrid& grid);
    /// Hash of the in-range u and v values, the time and the tick (golden-hash tests, sync).
    [[nodiscard]] std::uint64_t hash() const noexcept;
};

class MembraneModel
{
public:
    /// Builds the model from rest positions (any ghost width; twins are taken from their
    /// canonical node). \return InvalidArgument for a setting out of range or positions of
    /// another level; NonFiniteCoordinate for a NaN/inf position; DegenerateFace for a node
    /// without a normal or a zero-area triangle (the cotangent weights would be infinite). The
    /// two geometry errors' messages name the node and not where the positions came from:
    /// callers that read them from a file put its name first.
    static core::Result<MembraneModel> create(const core::TetraGrid& grid,
                                              const core::Vec3Field<double>& rest_positions,
                                              const MembraneSettings& settings);

    [[nodiscard]] const core::TetraGrid& grid() const noexcept { return grid_; }
    [[nodiscard]] const MembraneSettings& settings() const noexcept { return settings_; }
    /// Changes the integrator / threading settings (not the material). \return InvalidArgument.
    core::Result<void> set_settings(const MembraneSettings& settings);

    /// Rest positions P [m] (ghost ring 2) and unit outward rest normals N (ghost ring 1).
    [[nodiscard]] const core::Vec3Field<double>& rest_positions() const noexcept { return P_; }
    [[nodiscard]] const core::Vec3Field<double>& normals() const noexcept { return N_; }
    /// Edge weights T/2 (cot a + cot b) [N/m] of the edges to (x+1, y), (x, y+1), (x+1, y+1).
    [[nodiscard]] const core::Field<double>& weight_x() const noexcept { return wx_; }
    [[nodiscard]] const core::Field<double>& weight_y() const noexcept { return wy_; }
    [[nodiscard]] const core::Field<double>& weight_d() const noexcept { return wd_; }
    /// Stencil lumped mass rho/3 * (sum of the six grid triangles' areas) [kg] (twice the real
    /// mass at the four corners) and its inverse, on the surface last assembled: the rest
    /// positions, or P + u N after `reassemble` (rho is then per deformed area).
    [[nodiscard]] const core::Field<double>& mass() const noexcept { return mass_; }
    [[nodiscard]] const core::Field<double>& inverse_mass() const noexcept { return inv_mass_; }
    /// 2 at the four tetrahedron corners, 1 elsewhere (see the file comment).
    [[nodiscard]] int multiplicity(core::NodeIndex n) const noexcept;
    /// The real lumped mass of a node [kg] (stencil mass / multiplicity).
    [[nodiscard]] double unique_mass(core::NodeIndex n) const noexcept;

    /// The leaves of the parallel work split, in their fixed order, and their node rectangles.
    [[nodiscard]] std::span<const core::LeafId> leaves() const noexcept { return leaves_; }
    [[nodiscard]] std::span<const core::Region> leaf_regions() const noexcept { return regions_; }
    /// Axis-aligned bounds of each leaf's rest positions (min then max), for force look-up.
    [[nodiscard]] std::span<const core::Vec3> leaf_bounds() const noexcept { return bounds_; }

    /// Twin and ghost copies (padded offsets of ghost-ring-1 planes) that make a plane
    /// consistent after its canonical nodes were written: twins first, then the ghost ring.
    [[nodiscard]] std::span<const core::GhostCopy> sync_table() const noexcept { return sync_; }
    /// Applies `sync_table()` to a ghost-ring-1 plane of this grid.
    void sync(core::Field<double>& f) const noexcept;

    /// Re-assembles K and M from the deformed surface P + u N (u with ghosts synced); P and N
    /// stay the rest geometry. The weights and masses are those `create` gives for rest
    /// positions P + u N, bit for bit. The first call allocates spare planes (the deformed
    /// positions and a second set of weights and masses, swapped in on success); later calls
    /// allocate nothing. \return DegenerateFace (the model is left unchanged) when a deformed
    /// triangle has zero area or a non-finite position.
    core::Result<void> reassemble(const core::Field<double>& u);
    /// The tick of the last re-assembly (0 after `create`).
    [[nodiscard]] std::uint64_t assembled_tick() const noexcept { return assembled_tick_; }
    void set_assembled_tick(std::uint64_t tick) noexcept { assembled_tick_ = tick; }
    /// An id of the current weights and masses, unique over every assembly of every model in
    /// the process (a workspace's single-precision copies follow it).
    [[nodiscard]] std::uint64_t assembly_id() const noexcept { return assembly_id_; }

    /// Deformed positions p = P + u N for every in-range node (`out` is resized to ghost 0).
    void positions(const core::Field<double>& u, core::Vec3Field<double>& out) const;

private:
    MembraneModel() = default;
    core::Result<void> assemble(const core::Vec3Field<double>& X);

    core::TetraGrid grid_ = core::TetraGrid::create(1).value();
    MembraneSettings settings_;
    core::Vec3Field<double> P_;
    core::Vec3Field<double> N_;
    core::Field<double> wx_, wy_, wd_, mass_, inv_mass_;
    // Scratch of `reassemble` (empty until its first call): the deformed positions (ghost ring
    // 2) and the planes the next assembly writes before they are swapped with the ones above.
    core::Vec3Field<double> deformed_;
    core::Field<double> spare_wx_, spare_wy_, spare_wd_, spare_mass_, spare_inv_mass_;
    std::vector<core::LeafId> leaves_;
    std::vector<core::Region> regions_;
    std::vector<core::Vec3> bounds_;
    std::vector<core::GhostCopy> sync_;
    std::uint64_t assembled_tick_ = 0;
    std::uint64_t assembly_id_ = 0;
};

/// Checks a settings aggregate. \return InvalidArgument naming the field and its range.
core::Result<void> validate(const MembraneSettings& settings);

/// out = K u with the stencil (corner rows doubled, see the file comment) for every in-range
/// node; `u` must have ghost ring >= 1 and be synced (`MembraneModel::sync`). `out` is resized
/// to a ghost-ring-1 plane and synced.
void apply_stiffness(const MembraneModel& model, const core::Field<double>& u,
                     core::Field<double>& out);

/// Kinetic, strain and foundation energy of a state (u, v synced), summed per leaf in the
/// model's fixed leaf order (independent of the thread count). \pre u and v are ghost-1 planes
/// of the model's level, as MembraneState::at_rest makes them (a PLIANT_ASSERT failure
/// otherwise).
[[nodiscard]] Energy energy(const MembraneModel& model, const MembraneState& state);

}  // namespace pliant::sim
