// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "sim_scene.h"

#include <pliant/subdiv/refine.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

namespace pliant::viewer
{

sim::MembraneSettings default_material(int level)
{
    sim::MembraneSettings ms;
    ms.T = 2.0;
    ms.rho = 1.0;
    ms.beta = 1.5;
    ms.k_f = 6.0;
    ms.rtol = 1e-4;
    // Below level 8 a step is too short to share between threads (cmd_demo.cpp measured it).
    ms.threads = level >= 8 ? 0 : 1;
    // From level 8 on a step costs milliseconds: float increments make it ~1.6x faster
    // (docs/physics.md §9); the panel's switch turns them off.
    ms.precision = level >= 8 ? sim::Precision::Mixed : sim::Precision::Double;
    return ms;
}

core::Result<LocalSim> LocalSim::create(const core::TetraGrid& grid,
                                        const core::Vec3Field<double>& rest,
                                        const sim::MembraneSettings& settings)
{
    auto model = sim::MembraneModel::create(grid, rest, settings);
    if (!model)
        return model.error();
    LocalSim s;
    s.model_ = std::make_unique<sim::MembraneModel>(std::move(*model));
    s.workspace_ = std::make_unique<sim::Rkf45Workspace>(*s.model_, settings.threads);
    s.state_ = sim::MembraneState::at_rest(grid);
    s.rest_ = rest;
    return s;
}

sim::AdvanceReport LocalSim::advance(double wall_dt, std::span<const sim::Force> forces,
                                     double max_interval, std::uint64_t max_steps)
{
    const auto start = std::chrono::steady_clock::now();
    const double target = state_.time + std::clamp(wall_dt, 0.0, max_interval);
    sim::AdvanceReport report =
        sim::advance_to(*model_, state_, *workspace_, target, forces, {}, max_steps);
    last_step_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (sim::has_flag(report.status, sim::StepStatus::NonFinite))
        reset();
    return report;
}

core::Result<void> LocalSim::set_settings(const sim::MembraneSettings& settings)
{
    auto model = sim::MembraneModel::create(model_->grid(), rest_, settings);
    if (!model)
        return model.error();
    const double dt = workspace_->next_dt();
    model_ = std::make_unique<sim::MembraneModel>(std::move(*model));
    workspace_ = std::make_unique<sim::Rkf45Workspace>(*model_, settings.threads);
    workspace_->set_next_dt(std::clamp(dt, settings.dt_min, settings.dt_max));
    return {};
}

void LocalSim::reset()
{
    state_ = sim::MembraneState::at_rest(model_->grid());
}

void SurfaceView::update(const sim::MembraneModel& model, const core::Field<double>& u,
                         int display_levels)
{
    const core::TetraGrid& grid = model.grid();
    display_levels = std::clamp(display_levels, 0, core::k_max_level - grid.level());
    if (grid.level() != level_ || display_levels != display_levels_ || levels_.empty())
    {
        level_ = grid.level();
        display_levels_ = display_levels;
        grid_ = grid;
        plans_.clear();
        if (display_levels > 0)
            plans_ = subdiv::make_plans(level_, display_levels).value();
        levels_.clear();
        for (int k = 0; k <= display_levels; ++k)
        {
            const core::TetraGrid& g =
                k == 0 ? grid : plans_[static_cast<std::size_t>(k - 1)].fine_grid();
            Planes planes;
            for (auto& p : planes.p)
                p = core::Field<double>(g, 1);
            planes.u = core::Field<double>(g, 1);
            levels_.push_back(std::move(planes));
        }
        faces_ = grid.triangles();
        unique_.assign(grid.unique_count(), core::Vec3{});
        rest_.assign(grid.unique_count(), core::Vec3{});
    }
    // The rest positions at every update, not only when the levels change: another surface
    // (a load, a session's model) at the same level has other ones, and a grab on it is
    // placed through them.
    {
        const auto& P = model.rest_positions();
        const auto nodes = grid.node_of_unique();
        for (std::size_t i = 0; i < rest_.size(); ++i)
            rest_[i] = {P[0][nodes[i]], P[1][nodes[i]], P[2][nodes[i]]};
    }
    // p = P + u N at the sim level (twins equal because P, N and u have equal twins).
    const auto& P = model.rest_positions();
    const auto& N = model.normals();
    Planes& base = levels_.front();
    double max_u = 0.0;
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const double ux = u.at(x, y);
            max_u = std::max(max_u, std::abs(ux));
            for (std::size_t c = 0; c < 3; ++c)
                base.p[c].at(x, y) = P[c].at(x, y) + ux * N[c].at(x, y);
            base.u.at(x, y) = ux;
        }
    max_abs_u_ = max_u;
    for (std::size_t i = 0; i < unique_.size(); ++i)
    {
        const core::NodeIndex n = grid.node_of_unique()[i];
        unique_[i] = {base.p[0][n], base.p[1][n], base.p[2][n]};
    }
    for (auto& plane : base.p)
        core::fill_ghosts(grid, plane);
    core::fill_ghosts(grid, base.u);
    for (std::size_t k = 0; k < plans_.size(); ++k)
    {
        subdiv::refine(plans_[k], levels_[k].p, levels_[k + 1].p);
        subdiv::refine(plans_[k], levels_[k].u, levels_[k + 1].u);
    }
}

namespace
{

/// Where grid point (x, y) (in cells of a grid of `w`) lies: cell (cx, cy), its triangle t as
/// TetraGrid::node_triangles() orders them (0: (cx, cy), (cx + 1, cy), (cx + 1, cy + 1); 1:
/// (cx, cy), (cx + 1, cy + 1), (cx, cy + 1)) and the weights of that triangle's second and third
/// corner. Points outside the rectangle are clamped onto it.
struct InCell
{
    int cx = 0, cy = 0, t = 0;
    double b1 = 0.0, b2 = 0.0;
};

InCell locate(double x, double y, int w) noexcept
{
    InCell c;
    c.cx = std::clamp(static_cast<int>(std::floor(x)), 0, 2 * w - 1);
    c.cy = std::clamp(static_cast<int>(std::floor(y)), 0, w - 1);
    const double fx = std::clamp(x - c.cx, 0.0, 1.0), fy = std::clamp(y - c.cy, 0.0, 1.0);
    if (fy <= fx)
        c = {c.cx, c.cy, 0, fx - fy, fy};
    else
        c = {c.cx, c.cy, 1, fx, fy - fx};
    return c;
}

/// The grid nodes (x, y) of the corners of the triangle `c` names.
std::array<std::array<int, 2>, 3> corners(const InCell& c) noexcept
{
    if (c.t == 0)
        return {{{c.cx, c.cy}, {c.cx + 1, c.cy}, {c.cx + 1, c.cy + 1}}};
    return {{{c.cx, c.cy}, {c.cx + 1, c.cy + 1}, {c.cx, c.cy + 1}}};
}

}  // namespace

std::optional<std::pair<SurfacePoint, core::Vec3>> SurfaceView::pick(const Ray& ray) const noexcept
{
    const core::TetraGrid& g = display_grid();
    const core::Vec3Field<double>& p = display_positions();
    const auto at = [&](int x, int y) {
        return core::Vec3{p[0].at(x, y), p[1].at(x, y), p[2].at(x, y)};
    };
    std::optional<Hit> best;
    InCell where;
    for (int cy = 0; cy < g.w(); ++cy)
        for (int cx = 0; cx < 2 * g.w(); ++cx)
        {
            const core::Vec3 n00 = at(cx, cy), n10 = at(cx + 1, cy), n11 = at(cx + 1, cy + 1),
                             n01 = at(cx, cy + 1);
            for (int t = 0; t < 2; ++t)
            {
                const std::optional<Hit> hit =
                    t == 0 ? intersect(ray, n00, n10, n11) : intersect(ray, n00, n11, n01);
                if (hit && (!best || hit->t < best->t))
                {
                    best = hit;
                    where = {cx, cy, t, hit->b1, hit->b2};
                }
            }
        }
    if (!best)
        return std::nullopt;
    // the corners' grid positions weighted as the hit, in cells of the simulation level
    const auto c = corners(where);
    const double scale = 1.0 / static_cast<double>(1 << display_levels_);
    const double w0 = 1.0 - where.b1 - where.b2;
    const SurfacePoint sp{(w0 * c[0][0] + where.b1 * c[1][0] + where.b2 * c[2][0]) * scale,
                          (w0 * c[0][1] + where.b1 * c[1][1] + where.b2 * c[2][1]) * scale};
    return std::pair{sp, best->point};
}

core::Vec3 SurfaceView::display_point(SurfacePoint at) const noexcept
{
    const double scale = static_cast<double>(1 << display_levels_);
    const core::TetraGrid& g = display_grid();
    const core::Vec3Field<double>& p = display_positions();
    const InCell c = locate(at.x * scale, at.y * scale, g.w());
    const auto n = corners(c);
    const std::array<double, 3> w{1.0 - c.b1 - c.b2, c.b1, c.b2};
    core::Vec3 sum{};
    for (std::size_t k = 0; k < 3; ++k)
        sum += core::Vec3{p[0].at(n[k][0], n[k][1]), p[1].at(n[k][0], n[k][1]),
                          p[2].at(n[k][0], n[k][1])} *
               w[k];
    return sum;
}

core::Vec3 SurfaceView::rest_point(SurfacePoint at) const noexcept
{
    const int w = grid_->w();
    const InCell c = locate(at.x, at.y, w);
    const auto& f = faces_[static_cast<std::size_t>((c.cy * 2 * w + c.cx) * 2 + c.t)];
    return rest_[f[0]] * (1.0 - c.b1 - c.b2) + rest_[f[1]] * c.b1 + rest_[f[2]] * c.b2;
}

core::Vec3 Grab::current(const SurfaceView& view) const noexcept
{
    return view.display_point(at);
}

core::Vec3 Grab::rest(const SurfaceView& view) const noexcept
{
    return view.rest_point(at);
}

sim::Force Grab::force(const SurfaceView& view) const noexcept
{
    sim::Force f;
    f.point = rest(view);
    f.radius = radius;
    f.vector = (target - current(view)) * stiffness;
    return f;
}

double default_grab_stiffness(const sim::MembraneSettings& material, double radius)
{
    // A patch of radius r resists a normal displacement with about rho pi r^2 k_f (the
    // foundation) plus 2 pi T (tension; the logarithmic factor of a point-loaded membrane is of
    // order one here). A spring as stiff as the patch holds it halfway to the mouse.
    return material.rho * std::numbers::pi * radius * radius * material.k_f +
           2.0 * std::numbers::pi * material.T;
}

double grab_hold_limit(const sim::MembraneSettings& material, const Grab& grab)
{
    const double mass = material.rho * std::numbers::pi * grab.radius * grab.radius;
    if (!(grab.stiffness > 0.0) || !(mass > 0.0))
        return std::numeric_limits<double>::infinity();
    return 0.5 / std::sqrt(grab.stiffness / mass);
}

}  // namespace pliant::viewer
