// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/hash.h>
#include <pliant/sim/membrane.h>

#include "sim/stencil_internal.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>

namespace pliant::sim
{

std::string_view to_string(ForceHold hold) noexcept
{
    return hold == ForceHold::Linear ? "linear" : "step";
}

std::string_view to_string(Precision precision) noexcept
{
    return precision == Precision::Mixed ? "mixed" : "double";
}

namespace
{

using core::Field;
using core::Vec3;
using core::Vec3Field;

Vec3 at(const Vec3Field<double>& X, int x, int y) noexcept
{
    return {X[0].at(x, y), X[1].at(x, y), X[2].at(x, y)};
}

// cot of the angle at q in the triangle (a, b, q). Symmetric in a <-> b bit for bit: the dot
// product's terms keep their order and the cross product only changes sign.
double cot_at(const Vec3& a, const Vec3& b, const Vec3& q, bool& degenerate) noexcept
{
    const Vec3 ea = a - q;
    const Vec3 eb = b - q;
    const double c = core::norm(core::cross(ea, eb));
    if (!(c > 0.0) || !std::isfinite(c))
    {
        degenerate = true;
        return 0.0;
    }
    return core::dot(ea, eb) / c;
}

core::Result<void> check(bool ok, const std::string& what)
{
    if (ok)
        return {};
    return core::fail(core::ErrorCode::InvalidArgument, "MembraneSettings: " + what);
}

}  // namespace

core::Result<void> validate(const MembraneSettings& s)
{
    // Written as !(x > 0) so that NaN fails too.
    if (auto r = check(s.T > 0.0 && std::isfinite(s.T), "T (tension, N/m) must be > 0"); !r)
        return r;
    if (auto r = check(s.rho > 0.0 && std::isfinite(s.rho), "rho (kg/m^2) must be > 0"); !r)
        return r;
    if (auto r = check(s.beta >= 0.0 && std::isfinite(s.beta), "beta (1/s) must be >= 0"); !r)
        return r;
    if (auto r = check(s.k_f >= 0.0 && std::isfinite(s.k_f), "k_f (1/s^2) must be >= 0"); !r)
        return r;
    if (auto r = check(s.max_force >= 0.0 && std::isfinite(s.max_force),
                       "max_force (N) must be >= 0 (0: no limit)");
        !r)
        return r;
    if (auto r = check(s.reassemble_every >= 0, "reassemble_every must be >= 0"); !r)
        return r;
    if (auto r = check(s.rtol >= 0.0 && s.rtol < 1.0, "rtol must be in [0, 1)"); !r)
        return r;
    if (auto r = check(s.atol > 0.0 && std::isfinite(s.atol), "atol must be > 0"); !r)
        return r;
    // A mixed step computes in float, whose smallest normal number is 1.2e-38 (denormals flush
    // to zero during a step): its error norm divides by atol + rtol |y|, and its coefficients
    // scale with h^2. Only the values the step mode uses are checked.
    const bool mixed = s.precision == Precision::Mixed;
    const bool adaptive = !s.fixed_step;
    if (auto r = check(!mixed || !adaptive || s.atol >= 1e-30,
                       "atol must be >= 1e-30 with precision mixed (its error norm is a float)");
        !r)
        return r;
    if (auto r = check(!mixed || !adaptive || s.dt_min >= 1e-12,
                       "dt_min must be >= 1e-12 s with precision mixed (its coefficients, h^2 "
                       "times the tableau's, are floats)");
        !r)
        return r;
    if (auto r = check(!mixed || adaptive || s.fixed_dt >= 1e-12,
                       "fixed_dt must be >= 1e-12 s with precision mixed (its coefficients, h^2 "
                       "times the tableau's, are floats)");
        !r)
        return r;
    if (auto r = check(s.dt_min > 0.0 && s.dt_max >= s.dt_min && std::isfinite(s.dt_max),
                       "need 0 < dt_min <= dt_max");
        !r)
        return r;
    if (auto r = check(s.dt_initial >= s.dt_min && s.dt_initial <= s.dt_max,
                       "dt_initial must be in [dt_min, dt_max]");
        !r)
        return r;
    if (auto r = check(s.safety > 0.0 && s.safety <= 1.0, "safety must be in (0, 1]"); !r)
        return r;
    if (auto r = check(s.max_growth > 1.0 && std::isfinite(s.max_growth), "max_growth must be > 1");
        !r)
        return r;
    if (auto r = check(s.min_shrink > 0.0 && s.min_shrink < 1.0, "min_shrink must be in (0, 1)");
        !r)
        return r;
    if (auto r = check(s.fixed_dt > 0.0 && std::isfinite(s.fixed_dt), "fixed_dt must be > 0"); !r)
        return r;
    if (auto r = check(s.threads >= 0, "threads must be >= 0"); !r)
        return r;
    return check(s.leaf_depth >= -1, "leaf_depth must be >= -1");
}

MembraneState MembraneState::at_rest(const core::TetraGrid& grid)
{
    MembraneState s;
    s.u = Field<double>(grid, 1);
    s.v = Field<double>(grid, 1);
    return s;
}

std::uint64_t MembraneState::hash() const noexcept
{
    std::uint64_t h = 0xcbf29ce484222325ULL;
    for (const Field<double>* f : {&u, &v})
        for (int y = 0; y < f->ny(); ++y)
            h = core::hash_span(std::span<const double>(f->origin() + f->offset(0, y),
                                                        static_cast<std::size_t>(f->nx())),
                                h);
    const double t = time;
    h = core::hash_span(std::span<const double>(&t, 1), h);
    return core::hash_span(std::span<const std::uint64_t>(&tick, 1), h);
}

core::Result<MembraneModel> MembraneModel::create(const core::TetraGrid& grid,
                                                  const Vec3Field<double>& rest,
                                                  const MembraneSettings& settings)
{
    if (auto r = validate(settings); !r)
        return r.error();
    for (const auto& f : rest)
        if (f.level() != grid.level() || f.nx() != grid.nx() || f.ny() != grid.ny())
            return core::fail(core::ErrorCode::InvalidArgument,
                              "MembraneModel::create: rest positions are not of level " +
                                  std::to_string(grid.level()));
    MembraneModel m;
    m.grid_ = grid;
    m.settings_ = settings;
    for (int k = 0; k < 3; ++k)
    {
        m.P_[static_cast<std::size_t>(k)] = Field<double>(grid, 2);
        m.N_[static_cast<std::size_t>(k)] = Field<double>(grid, 1);
    }
    for (std::size_t k = 0; k < 3; ++k)
    {
        for (int y = 0; y < grid.ny(); ++y)
            for (int x = 0; x < grid.nx(); ++x)
            {
                const double value = rest[k].at(x, y);
                if (!std::isfinite(value))
                    return core::fail(core::ErrorCode::NonFiniteCoordinate,
                                      "rest position of node (" + std::to_string(x) + ", " +
                                          std::to_string(y) + ") is not finite");
                m.P_[k].at(x, y) = value;
            }
        core::sync_twins(grid, m.P_[k]);
        core::fill_ghosts(grid, m.P_[k]);
    }

    // Twin and ghost copies of a ghost-ring-1 plane.
    const Field<double> probe(grid, 1);
    for (const core::TwinPair& t : grid.twins())
    {
        const core::GridCoord a = grid.coord(t.twin);
        const core::GridCoord b = grid.coord(t.canonical);
        m.sync_.push_back({probe.padded_offset(a.x, a.y), probe.padded_offset(b.x, b.y)});
    }
    for (const core::GhostCopy& g : grid.ghost_table(1))
        m.sync_.push_back(g);

    // Leaves of the work split and the bounds of their rest positions.
    const int depth = settings.leaf_depth < 0 ? std::max(0, grid.level() - 6)
                                              : std::min(settings.leaf_depth, grid.level());
    m.leaves_ = grid.leaves(depth);
    for (const core::LeafId& leaf : m.leaves_)
    {
        const core::Region r = grid.leaf_region(leaf);
        m.regions_.push_back(r);
        Vec3 lo = at(m.P_, r.x0, r.y0);
        Vec3 hi = lo;
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x)
            {
                const Vec3 p = at(m.P_, x, y);
                lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
                hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
            }
        m.bounds_.push_back(lo);
        m.bounds_.push_back(hi);
    }

    // Outward orientation: the grid's faces are consistently oriented; flip all normals if the
    // enclosed signed volume is negative.
    double volume = 0.0;
    for (const auto& t : grid.node_triangles())
    {
        const auto p = [&](std::uint32_t n)
        {
            const core::GridCoord c = grid.coord(core::NodeIndex{n});
            return at(m.P_, c.x, c.y);
        };
        volume += core::dot(p(t[0]), core::cross(p(t[1]), p(t[2])));
    }
    const double sign = volume < 0.0 ? -1.0 : 1.0;

    // Area-weighted normals from the six grid triangles, opposite triangles paired (bitwise
    // equal at twins, see stencil_internal.h).
    static constexpr int k_dir[6][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 0}, {-1, -1}, {0, -1}};
    for (int y = -1; y <= grid.ny(); ++y)
        for (int x = -1; x <= grid.nx(); ++x)
        {
            const Vec3 c = at(m.P_, x, y);
            Vec3 cr[6];
            for (int k = 0; k < 6; ++k)
            {
                const int* d1 = k_dir[k];
                const int* d2 = k_dir[(k + 1) % 6];
                cr[k] = core::cross(at(m.P_, x + d1[0], y + d1[1]) - c,
                                    at(m.P_, x + d2[0], y + d2[1]) - c);
            }
            const Vec3 n = ((cr[0] + cr[3]) + (cr[1] + cr[4])) + (cr[2] + cr[5]);
            const double len = core::norm(n);
            if (!(len > 0.0) || !std::isfinite(len))
            {
                // Name the surface vertex (a ghost position stands for a node inside), and why:
                // products of edges that overflow or underflow are the scale's fault, not the
                // shape's (a unit sphere scaled by 1e300 or 1e-300 said "span no area").
                const core::GridCoord node = grid.fold(x, y);
                double edge = 0.0;  // the largest edge component (no square to overflow)
                for (const auto& d : k_dir)
                {
                    const Vec3 e = at(m.P_, x + d[0], y + d[1]) - c;
                    edge = std::max({edge, std::abs(e.x), std::abs(e.y), std::abs(e.z)});
                }
                const std::string where = "the rest surface has no normal at node (" +
                                          std::to_string(node.x) + ", " + std::to_string(node.y) +
                                          "): ";
                char size[32];
                std::snprintf(size, sizeof size, "%.3g", edge);
                if (!std::isfinite(len) || (edge > 0.0 && edge < 1e-150))
                    return core::fail(core::ErrorCode::DegenerateFace,
                                      where + "its edges (" + size + " m) are too " +
                                          (std::isfinite(len) ? "small" : "large") +
                                          " for their products to be computed in double "
                                          "precision; scale the object (pliant works in metres)");
                return core::fail(core::ErrorCode::DegenerateFace,
                                  where +
                                      "its neighbours' positions span no area (all equal, "
                                      "or on one line)");
            }
            m.N_[0].at(x, y) = sign * n.x / len;
            m.N_[1].at(x, y) = sign * n.y / len;
            m.N_[2].at(x, y) = sign * n.z / len;
        }

    if (auto r = m.assemble(m.P_); !r)
        return r.error();
    // The spare planes now hold nothing (the swap left the empty initial planes there): a
    // model that never re-assembles keeps one set of weights and masses.
    return m;
}

core::Result<void> MembraneModel::set_settings(const MembraneSettings& settings)
{
    if (auto r = validate(settings); !r)
        return r;
    if (settings.T != settings_.T || settings.rho != settings_.rho)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "MembraneModel::set_settings: T and rho are fixed at create()");
    const int old_depth = settings_.leaf_depth;
    settings_ = settings;
    settings_.leaf_depth = old_depth;  // the leaf split is fixed at create()
    return {};
}

core::Result<void> MembraneModel::assemble(const Vec3Field<double>& X)
{
    const core::TetraGrid& g = grid_;
    // The new planes are written into the spare ones (allocated by the first assembly or
    // re-assembly) and swapped in on success, so the model is unchanged on failure and a
    // re-assembly allocates nothing. Every assembly writes the same entries of them, so a reused
    // plane ends bit for bit as a fresh one would.
    for (Field<double>* f : {&spare_wx_, &spare_wy_, &spare_wd_, &spare_mass_, &spare_inv_mass_})
        if (f->empty() || f->level() != g.level() || f->ghost() != 1)
            *f = Field<double>(g, 1);
    Field<double>& wx = spare_wx_;
    Field<double>& wy = spare_wy_;
    Field<double>& wd = spare_wd_;
    Field<double>& mass = spare_mass_;
    Field<double>& inv = spare_inv_mass_;
    const double half_t = 0.5 * settings_.T;
    bool degenerate = false;
    core::GridCoord first_bad{0, 0};  // where the first degenerate triangle was met
    // Edge weights for every edge a stencil at an in-range node reads (x, y >= -1).
    for (int y = -1; y < g.ny(); ++y)
        for (int x = -1; x < g.nx(); ++x)
        {
            const bool before = degenerate;
            const Vec3 p = at(X, x, y);
            const Vec3 px = at(X, x + 1, y);
            const Vec3 py = at(X, x, y + 1);
            const Vec3 pd = at(X, x + 1, y + 1);
            // +x edge: opposite vertices (x+1, y+1) and (x, y-1).
            wx.at(x, y) = half_t * (cot_at(p, px, pd, degenerate) +
                                    cot_at(p, px, at(X, x, y - 1), degenerate));
            // +y edge: opposite vertices (x+1, y+1) and (x-1, y).
            wy.at(x, y) = half_t * (cot_at(p, py, pd, degenerate) +
                                    cot_at(p, py, at(X, x - 1, y), degenerate));
            // +(1,1) edge: opposite vertices (x+1, y) and (x, y+1).
            wd.at(x, y) = half_t * (cot_at(p, pd, px, degenerate) + cot_at(p, pd, py, degenerate));
            if (degenerate && !before)
                first_bad = g.coord(g.image(x, y));
        }
    if (degenerate)
        return core::fail(core::ErrorCode::DegenerateFace,
                          "a triangle of the surface at node (" + std::to_string(first_bad.x) +
                              ", " + std::to_string(first_bad.y) +
                              ") has zero area or a non-finite vertex (a node far from the "
                              "others, or nodes at one point)");

    static constexpr int k_dir[6][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 0}, {-1, -1}, {0, -1}};
    const double third_rho = settings_.rho / 3.0;
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            const Vec3 c = at(X, x, y);
            double area[6];
            for (int k = 0; k < 6; ++k)
            {
                const int* d1 = k_dir[k];
                const int* d2 = k_dir[(k + 1) % 6];
                area[k] = 0.5 * core::norm(core::cross(at(X, x + d1[0], y + d1[1]) - c,
                                                       at(X, x + d2[0], y + d2[1]) - c));
            }
            const double m =
                third_rho * (((area[0] + area[3]) + (area[1] + area[4])) + (area[2] + area[5]));
            mass.at(x, y) = m;
            inv.at(x, y) = 1.0 / m;  // m > 0: the weights above found no degenerate triangle
        }
    sync(mass);
    sync(inv);
    std::swap(wx_, wx);
    std::swap(wy_, wy);
    std::swap(wd_, wd);
    std::swap(mass_, mass);
    std::swap(inv_mass_, inv);
    static std::atomic<std::uint64_t> next_id{0};
    assembly_id_ = ++next_id;
    return {};
}

core::Result<void> MembraneModel::reassemble(const Field<double>& u)
{
    const core::TetraGrid& g = grid_;
    Vec3Field<double>& X = deformed_;
    for (std::size_t k = 0; k < 3; ++k)
    {
        if (X[k].empty() || X[k].level() != g.level() || X[k].ghost() != 2)
            X[k] = Field<double>(g, 2);
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
                X[k].at(x, y) = P_[k].at(x, y) + u.at(x, y) * N_[k].at(x, y);
        core::sync_twins(g, X[k]);
        core::fill_ghosts(g, X[k]);
    }
    return assemble(X);
}

int MembraneModel::multiplicity(core::NodeIndex n) const noexcept
{
    const core::NodeIndex c = grid_.canonical(n);
    for (const core::NodeIndex corner : grid_.corners())
        if (c == corner)
            return 2;
    return 1;
}

double MembraneModel::unique_mass(core::NodeIndex n) const noexcept
{
    return mass_[n] / multiplicity(n);
}

void MembraneModel::sync(Field<double>& f) const noexcept
{
    PLIANT_ASSERT(f.ghost() == 1 && f.level() == grid_.level(), "sync: not a ghost-1 plane");
    double* d = f.padded().data();
    for (const core::GhostCopy& c : sync_)
        d[c.dst] = d[c.src];
}

void MembraneModel::positions(const Field<double>& u, Vec3Field<double>& out) const
{
    for (std::size_t k = 0; k < 3; ++k)
    {
        if (out[k].level() != grid_.level() || out[k].ghost() != 0 || out[k].empty())
            out[k] = Field<double>(grid_, 0);
        for (int y = 0; y < grid_.ny(); ++y)
            for (int x = 0; x < grid_.nx(); ++x)
                out[k].at(x, y) = P_[k].at(x, y) + u.at(x, y) * N_[k].at(x, y);
    }
}

void apply_stiffness(const MembraneModel& model, const Field<double>& u, Field<double>& out)
{
    const core::TetraGrid& g = model.grid();
    PLIANT_ASSERT(u.ghost() == 1 && u.level() == g.level(), "apply_stiffness: u not ghost-1");
    if (out.ghost() != 1 || out.level() != g.level() || out.empty())
        out = Field<double>(g, 1);
    const std::ptrdiff_t s = u.stride();
    const double* wx = model.weight_x().origin();
    const double* wy = model.weight_y().origin();
    const double* wd = model.weight_d().origin();
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            const std::ptrdiff_t i = u.offset(x, y);
            out.origin()[i] = detail::stiffness_at(u.origin(), wx, wy, wd, i, s);
        }
    model.sync(out);
}

Energy energy(const MembraneModel& model, const MembraneState& state)
{
    const core::TetraGrid& g = model.grid();
    // The weights are read at the state's offsets: the planes must be the model's shape.
    PLIANT_ASSERT(state.u.level() == g.level() && state.v.level() == g.level() &&
                      state.u.ghost() == 1 && state.v.ghost() == 1,
                  "energy: the state's u and v are not ghost-1 planes of the model's level");
    const auto regions = model.leaf_regions();
    std::vector<Energy> parts(regions.size());
    const std::ptrdiff_t s = state.u.stride();
    const double* u = state.u.origin();
    const double* v = state.v.origin();
    const double* wx = model.weight_x().origin();
    const double* wy = model.weight_y().origin();
    const double* wd = model.weight_d().origin();
    const double* m = model.mass().origin();
    const double k_f = model.settings().k_f;
    const auto n_regions = static_cast<std::ptrdiff_t>(regions.size());
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t r = 0; r < n_regions; ++r)
    {
        const core::Region reg = regions[static_cast<std::size_t>(r)];
        Energy e;
        for (int y = reg.y0; y < reg.y1; ++y)
            for (int x = reg.x0; x < reg.x1; ++x)
            {
                const core::NodeIndex n = g.index(x, y);
                if (!g.is_canonical(n))
                    continue;
                const double mult = model.multiplicity(n);
                const std::ptrdiff_t i = state.u.offset(x, y);
                const double mi = m[i] / mult;
                e.kinetic += 0.5 * mi * v[i] * v[i];
                e.strain += 0.5 * u[i] * detail::stiffness_at(u, wx, wy, wd, i, s) / mult;
                e.foundation += 0.5 * k_f * mi * u[i] * u[i];
            }
        parts[static_cast<std::size_t>(r)] = e;
    }
    Energy total;
    for (const Energy& e : parts)  // fixed leaf order
    {
        total.kinetic += e.kinetic;
        total.strain += e.strain;
        total.foundation += e.foundation;
    }
    return total;
}

}  // namespace pliant::sim
