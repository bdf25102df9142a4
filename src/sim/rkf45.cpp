// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/sim/rkf45.h>

#include <omp.h>

#include "sim/rkf45_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>

namespace pliant::sim
{
namespace
{

using core::Field;
using detail::Coeffs;
using detail::k_fehlberg;

// Products of the tableau that turn the second-order system into velocity slopes only:
// U_s = u + h c_s v + h^2 sum_m (A^2)_sm kv_m, u_new = u + h v + h^2 sum_m (b A)_m kv_m.
struct Derived
{
    double aa[6][6];  // A^2
    double ba[6];     // b5 A
    double ea[6];     // (b5 - b4) A
    double e[6];      // b5 - b4
};

constexpr Derived derive(const detail::Tableau& t)
{
    Derived d{};
    for (int s = 0; s < 6; ++s)
        for (int m = 0; m < 6; ++m)
        {
            double sum = 0.0;
            for (int j = 0; j < 6; ++j)
                sum += t.a[s][j] * t.a[j][m];
            d.aa[s][m] = sum;
        }
    for (int m = 0; m < 6; ++m)
    {
        double sb = 0.0;
        double se = 0.0;
        for (int s = 0; s < 6; ++s)
        {
            sb += t.b5[s] * t.a[s][m];
            se += (t.b5[s] - t.b4[s]) * t.a[s][m];
        }
        d.ba[m] = sb;
        d.ea[m] = se;
        d.e[m] = t.b5[m] - t.b4[m];
    }
    return d;
}

constexpr Derived k_derived = derive(k_fehlberg);

// Everything the stage-by-stage pass reads and writes (origins of ghost-ring-1 planes, one
// stride).
struct Planes
{
    const double* u;
    const double* v;  // v_src
    double* kv[5];
    const double* wx;
    const double* wy;
    const double* wd;
    const double* inv_m;
    const double* acc;
    const double* acc_rate;
    double* u_out;
    double* v_out;
    std::ptrdiff_t s;
};

// One stage over one region (the restricted step's pass): U_S three rows at a time into
// `buffer` (3 rows of nx + 3), then the row kernel. S < 5 writes kv_S; S == 5 also finishes the
// step (u_out, v_out) and gives the error norm over the region's canonical nodes and a NaN probe.
template <int S>
void stage_region(const detail::StageConstants& k, const Planes& p, const Coeffs& c,
                  const core::Region& r, double* buffer, std::size_t row_len, double& err_out,
                  double& probe_out)
{
    const std::ptrdiff_t s = p.s;
    const auto row = [s](const double* plane, int y)
    { return plane + static_cast<std::ptrdiff_t>(y) * s; };
    const auto fill = [&](int y, double* dst)
    {
        const double* kv[5] = {};
        for (int m = 0; m < 5; ++m)
            kv[m] = row(p.kv[m], y);
        detail::fill_row<S>(c, row(p.u, y), row(p.v, y), kv, dst, r.x0, r.x1);
    };
    // Row buffers indexed by grid x (x = -1 .. nx).
    double* rows[3] = {buffer + 1, buffer + 1 + row_len, buffer + 1 + 2 * row_len};
    fill(r.y0 - 1, rows[0]);
    fill(r.y0, rows[1]);
    double err = 0.0;
    double probe = 0.0;
    for (int y = r.y0; y < r.y1; ++y)
    {
        fill(y + 1, rows[2]);
        detail::StageRow sr{};
        sr.u = row(p.u, y);
        sr.v = row(p.v, y);
        for (int m = 0; m < 5; ++m)
            sr.kv[m] = row(p.kv[m], y);
        sr.wx = row(p.wx, y);
        sr.wy = row(p.wy, y);
        sr.wd = row(p.wd, y);
        sr.wy_below = row(p.wy, y - 1);
        sr.wd_below = row(p.wd, y - 1);
        sr.inv_m = row(p.inv_m, y);
        sr.acc = row(p.acc, y);
        sr.acc_rate = row(p.acc_rate, y);
        sr.U_below = rows[0];
        sr.U = rows[1];
        sr.U_above = rows[2];
        if constexpr (S < 5)
            sr.kv_out = p.kv[S] + static_cast<std::ptrdiff_t>(y) * s;
        else
        {
            sr.u_out = p.u_out + static_cast<std::ptrdiff_t>(y) * s;
            sr.v_out = p.v_out + static_cast<std::ptrdiff_t>(y) * s;
        }
        sr.y = y;
        err = std::max(err, detail::stage_row<S>(k, c, sr, r.x0, r.x1, probe));
        double* t = rows[0];
        rows[0] = rows[1];
        rows[1] = rows[2];
        rows[2] = t;
    }
    err_out = err;
    probe_out = probe;
}

template <int S>
void run_stage(const detail::StageConstants& k, const Planes& p, const Coeffs& c,
               std::span<const core::Region> regions, Rkf45Workspace& ws)
{
    const auto n = static_cast<std::ptrdiff_t>(regions.size());
    const std::size_t row_len = ws.row_buffer_len / 3;
#pragma omp for schedule(static)
    for (std::ptrdiff_t k_ = 0; k_ < n; ++k_)
    {
        double* buffer = ws.row_buffers.data() +
                         static_cast<std::size_t>(omp_get_thread_num()) * ws.row_buffer_len;
        const auto kk = static_cast<std::size_t>(k_);
        stage_region<S>(k, p, c, regions[kk], buffer, row_len, ws.leaf_error[kk],
                        ws.leaf_probe[kk]);
    }
}

struct TrialResult
{
    double error = 0.0;
    bool finite = true;
};

// One trial step of size h from (state.u, state.v or its masked copy) into ws.u_out / v_out,
// stage by stage over `regions` (a barrier and a twin/ghost copy between stages), the last
// stage and the update over `last` (StepOptions::needed, or `regions`).
void stage_trial(const MembraneModel& model, const MembraneState& state, Rkf45Workspace& ws,
                 std::span<const core::Region> regions, std::span<const core::Region> last,
                 const Coeffs& c, const detail::StageConstants& k, int threads, bool restricted)
{
    Planes p{};
    p.u = state.u.origin();
    p.v = restricted ? ws.v_src.origin() : state.v.origin();
    for (std::size_t m = 0; m < 5; ++m)
        p.kv[m] = ws.kv[m].origin();
    p.wx = model.weight_x().origin();
    p.wy = model.weight_y().origin();
    p.wd = model.weight_d().origin();
    p.inv_m = model.inverse_mass().origin();
    p.acc = ws.accel.origin();
    p.acc_rate = ws.accel_rate.origin();
    p.u_out = ws.u_out.origin();
    p.v_out = ws.v_out.origin();
    p.s = state.u.stride();

#pragma omp parallel num_threads(threads)
    {
        // Every thread of the pass flushes denormals (see FlushDenormals); all run in the same
        // mode, so results stay bit-identical for any thread count.
        const detail::FlushDenormals flush;
        run_stage<0>(k, p, c, regions, ws);
#pragma omp single
        model.sync(ws.kv[0]);
        run_stage<1>(k, p, c, regions, ws);
#pragma omp single
        model.sync(ws.kv[1]);
        run_stage<2>(k, p, c, regions, ws);
#pragma omp single
        model.sync(ws.kv[2]);
        run_stage<3>(k, p, c, regions, ws);
#pragma omp single
        model.sync(ws.kv[3]);
        run_stage<4>(k, p, c, regions, ws);
#pragma omp single
        model.sync(ws.kv[4]);
        run_stage<5>(k, p, c, last, ws);
    }
}

// One trial step: the fused row pipeline, full or restricted (planned by step_prepared), when
// the grid's copies fit it; else the stage-by-stage pass. Both run the same row kernels.
TrialResult trial(const MembraneModel& model, const MembraneState& state, Rkf45Workspace& ws,
                  std::span<const core::Region> regions, std::span<const core::Region> last,
                  double h, int threads, bool restricted)
{
    const MembraneSettings& set = model.settings();
    Coeffs c = detail::make_coeffs(h);
    // The forces' time at each stage, from the time their plane holds (0 but in a linear hold).
    for (int s = 0; s < 6; ++s)
        c.ft[s] = (state.time - ws.accel_time) + c.cu[s];
    const detail::StageConstants k{set.beta, set.k_f, set.rtol, set.atol, model.grid().w()};
    std::size_t parts = last.size();
    if (ws.pipeline_ok && ws.use_pipeline)
        parts = detail::pipeline_trial(model, state, ws, c, k, threads, restricted,
                                       set.precision == Precision::Mixed);
    else
        stage_trial(model, state, ws, regions, last, c, k, threads, restricted);
    TrialResult t;
    for (std::size_t i = 0; i < parts; ++i)
    {
        t.error = std::max(t.error, ws.leaf_error[i]);
        if (std::isnan(ws.leaf_probe[i]))
            t.finite = false;
    }
    return t;
}

void copy_regions(const Field<double>& from, Field<double>& to,
                  std::span<const core::Region> regions)
{
    for (const core::Region& r : regions)
        for (int y = r.y0; y < r.y1; ++y)
            std::copy(from.origin() + from.offset(r.x0, y), from.origin() + from.offset(r.x1, y),
                      to.origin() + to.offset(r.x0, y));
}

// An acceleration plane being written and the offsets it has written (to clear them later).
struct AccelTarget
{
    Field<double>& plane;
    std::vector<std::int64_t>& touched;
};

void add_node_accel(const MembraneModel& model, AccelTarget to, core::NodeIndex n, double force_n)
{
    const core::NodeIndex c = model.grid().canonical(n);
    const core::GridCoord g = model.grid().coord(c);
    const std::ptrdiff_t off = to.plane.padded_offset(g.x, g.y);
    to.plane.padded()[static_cast<std::size_t>(off)] += force_n / model.unique_mass(c);
    to.touched.push_back(off);
}

core::Vec3 normal_at(const MembraneModel& model, int x, int y)
{
    return {model.normals()[0].at(x, y), model.normals()[1].at(x, y), model.normals()[2].at(x, y)};
}

core::Vec3 rest_at(const MembraneModel& model, int x, int y)
{
    return {model.rest_positions()[0].at(x, y), model.rest_positions()[1].at(x, y),
            model.rest_positions()[2].at(x, y)};
}

void add_point_force(const MembraneModel& model, AccelTarget to, const Force& f)
{
    const core::TetraGrid& g = model.grid();
    const auto regions = model.leaf_regions();
    const auto bounds = model.leaf_bounds();
    const double r2 = f.radius * f.radius;
    // Pass 0 sums the weights, pass 1 applies them; both visit nodes in leaf order.
    double wsum = 0.0;
    for (int pass = 0; pass < 2; ++pass)
    {
        for (std::size_t k = 0; k < regions.size(); ++k)
        {
            const core::Vec3 lo = bounds[2 * k];
            const core::Vec3 hi = bounds[2 * k + 1];
            const core::Vec3 q{std::clamp(f.point.x, lo.x, hi.x), std::clamp(f.point.y, lo.y, hi.y),
                               std::clamp(f.point.z, lo.z, hi.z)};
            const core::Vec3 dq = q - f.point;
            if (core::dot(dq, dq) >= r2)
                continue;
            const core::Region r = regions[k];
            for (int y = r.y0; y < r.y1; ++y)
                for (int x = r.x0; x < r.x1; ++x)
                {
                    if (!g.is_canonical(g.index(x, y)))
                        continue;
                    const core::Vec3 d = rest_at(model, x, y) - f.point;
                    const double d2 = core::dot(d, d);
                    if (d2 >= r2)
                        continue;
                    const double t = 1.0 - d2 / r2;
                    const double w = t * t;
                    if (pass == 0)
                        wsum += w;
                    else
                        add_node_accel(model, to, g.index(x, y),
                                       w / wsum * core::dot(f.vector, normal_at(model, x, y)));
                }
        }
        if (pass == 0 && !(wsum > 0.0))
            break;
    }
    if (wsum > 0.0)
        return;
    // No node inside the radius: the nearest canonical node takes the whole force.
    double best = 0.0;
    core::NodeIndex best_node{};
    bool found = false;
    for (const core::NodeIndex n : g.node_of_unique())
    {
        const core::GridCoord c = g.coord(n);
        const core::Vec3 d = rest_at(model, c.x, c.y) - f.point;
        const double d2 = core::dot(d, d);
        if (!found || d2 < best)
        {
            best = d2;
            best_node = n;
            found = true;
        }
    }
    const core::GridCoord c = g.coord(best_node);
    add_node_accel(model, to, best_node, core::dot(f.vector, normal_at(model, c.x, c.y)));
}

// Clears the plane at the offsets it has written (canonical nodes) and forgets them; the
// caller syncs the plane's twins and ghosts.
void clear_written(AccelTarget to)
{
    auto data = to.plane.padded();
    for (const std::int64_t off : to.touched)
        data[static_cast<std::size_t>(off)] = 0.0;
    to.touched.clear();
}

// The accelerations of `forces` into `to.plane` (the previous ones cleared), synced.
void write_forces(const MembraneModel& model, AccelTarget to, std::span<const Force> forces)
{
    clear_written(to);
    const core::TetraGrid& g = model.grid();
    const int w2 = 2 * g.w();
    const double max_force = model.settings().max_force;
    for (Force f : forces)
    {
        f.vector = limit_force(f.vector, max_force);
        if (f.face >= 0)
        {
            PLIANT_ASSERT(static_cast<std::size_t>(f.face) < g.face_count(),
                          "set_forces: face out of range");
            const auto cell = f.face / 2;
            const int x = static_cast<int>(cell % w2);
            const int y = static_cast<int>(cell / w2);
            const core::NodeIndex n[3] = {
                g.index(x, y), (f.face % 2 == 0) ? g.index(x + 1, y) : g.index(x + 1, y + 1),
                (f.face % 2 == 0) ? g.index(x + 1, y + 1) : g.index(x, y + 1)};
            for (const core::NodeIndex node : n)
            {
                const core::GridCoord c = g.coord(node);
                add_node_accel(model, to, node,
                               core::dot(f.vector, normal_at(model, c.x, c.y)) / 3.0);
            }
        }
        else
            add_point_force(model, to, f);
    }
    model.sync(to.plane);
}

}  // namespace

detail::Coeffs detail::make_coeffs(double h)
{
    Coeffs c{};
    const double h2 = h * h;
    c.h = h;
    for (int s = 0; s < 6; ++s)
    {
        c.cu[s] = h * k_fehlberg.c[s];
        for (int m = 0; m < 6; ++m)
        {
            c.ck[s][m] = h2 * k_derived.aa[s][m];
            c.cv[s][m] = h * k_fehlberg.a[s][m];
        }
        c.ub[s] = h2 * k_derived.ba[s];
        c.vb[s] = h * k_fehlberg.b5[s];
        c.ue[s] = h2 * k_derived.ea[s];
        c.ve[s] = h * k_derived.e[s];
    }
    return c;
}

Rkf45Workspace::Rkf45Workspace(const MembraneModel& model, int threads)
{
    const core::TetraGrid& g = model.grid();
    max_threads = threads > 0 ? threads : std::max(1, omp_get_max_threads());
    for (int k = 0; k < 5; ++k)
        kv.emplace_back(g, 1);
    u_out = Field<double>(g, 1);
    v_out = Field<double>(g, 1);
    v_src = Field<double>(g, 1);
    accel = Field<double>(g, 1);
    accel_rate = Field<double>(g, 1);  // accel_end: on the first linear hold
    forced_rows.assign(static_cast<std::size_t>(g.ny()), 0);
    row_buffer_len = 3 * static_cast<std::size_t>(g.nx() + 3);
    row_buffers.assign(row_buffer_len * static_cast<std::size_t>(max_threads), 0.0);
    const std::size_t parts =
        std::max(model.leaf_regions().size(), static_cast<std::size_t>(max_threads));
    leaf_error.assign(parts, 0.0);
    leaf_probe.assign(parts, 0.0);
    detail::plan_pipeline(model, *this);
    if (model.settings().precision == Precision::Mixed)
        detail::prepare_mixed(model, *this);
    touched.reserve(4096);
    next_dt_ = model.settings().dt_initial;
}

namespace
{

/// |R(z)| of the propagated (fifth-order) Fehlberg solution for y' = z y / h.
double amplification(std::complex<double> z) noexcept
{
    std::array<std::complex<double>, 6> k{};
    std::complex<double> y = 1.0;
    for (int s = 0; s < 6; ++s)
    {
        std::complex<double> arg = 1.0;
        for (int m = 0; m < s; ++m)
            arg += k_fehlberg.a[s][m] * k[static_cast<std::size_t>(m)];
        k[static_cast<std::size_t>(s)] = z * arg;
        y += k_fehlberg.b5[s] * k[static_cast<std::size_t>(s)];
    }
    return std::abs(y);
}

/// Whether every mode of frequency in [0, omega_max] decaying at beta / 2 (nodal damping
/// B = beta M gives every mode the same rate) is amplified by at most 1 + growth per step.
bool stable_at(double h, double omega_max, double beta, double growth) noexcept
{
    const double re = -0.5 * beta * h;
    const double y_max = omega_max * h;
    constexpr int k_samples = 400;
    for (int i = 0; i <= k_samples; ++i)
    {
        const double y = y_max * i / k_samples;
        // Under-damped modes sit at -beta/2 +- i sqrt(omega^2 - beta^2/4); over-damped ones on
        // the real axis between -beta and 0: both are covered by these samples.
        const double im = std::sqrt(std::max(0.0, y * y - re * re));
        const double shift = y < -re ? std::sqrt(re * re - y * y) : 0.0;
        if (amplification({re - shift, im}) > 1.0 + growth ||
            amplification({re + shift, im}) > 1.0 + growth)
            return false;
    }
    return true;
}

}  // namespace

core::Vec3 limit_force(core::Vec3 force, double max_force) noexcept
{
    // hypot: the magnitude of a force near the double range's end does not overflow to inf.
    const double magnitude = std::hypot(force.x, force.y, force.z);
    if (!(max_force > 0.0) || !(magnitude > max_force))
        return force;
    return force * (max_force / magnitude);
}

double default_max_force(const core::TetraGrid& g, const core::Vec3Field<double>& rest,
                         const MembraneSettings& s) noexcept
{
    core::Vec3 lo{}, hi{};
    bool first = true;
    for (const core::NodeIndex n : g.node_of_unique())
    {
        const core::GridCoord c = g.coord(n);
        const core::Vec3 p{rest[0].at(c.x, c.y), rest[1].at(c.x, c.y), rest[2].at(c.x, c.y)};
        lo = first ? p : core::Vec3{std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = first ? p : core::Vec3{std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        first = false;
    }
    const double radius = 0.5 * core::norm(hi - lo);
    const double patch = 0.1 * radius;
    const double stiffness =
        s.rho * std::numbers::pi * patch * patch * s.k_f + 2.0 * std::numbers::pi * s.T;
    return stiffness * 2.0 * radius;
}

double stable_fixed_step(const MembraneModel& model) noexcept
{
    const core::TetraGrid& g = model.grid();
    const core::Field<double>& wx = model.weight_x();
    const core::Field<double>& wy = model.weight_y();
    const core::Field<double>& wd = model.weight_d();
    double lambda = 0.0;
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            const double row = std::abs(wx.at(x, y)) + std::abs(wx.at(x - 1, y)) +
                               std::abs(wy.at(x, y)) + std::abs(wy.at(x, y - 1)) +
                               std::abs(wd.at(x, y)) + std::abs(wd.at(x - 1, y - 1));
            lambda = std::max(lambda, 2.0 * row * model.inverse_mass().at(x, y));
        }
    const double omega_max = std::sqrt(lambda + model.settings().k_f);
    if (!(omega_max > 0.0))
        return model.settings().dt_max;
    // Largest omega_max h (in steps of 1 %) at which no mode grows by more than 1e-7 per step:
    // from beta h >= 0.012 the ceiling 3.5; with less damping the polynomial's growth near the
    // imaginary axis (|R(iy)| - 1 = 1.3e-5 at y = 0.5) sets it lower (docs/physics.md §5).
    const double beta = model.settings().beta;
    for (double y = 3.5; y > 0.005; y *= 0.99)
        if (stable_at(y / omega_max, omega_max, beta, 1e-7))
            return y / omega_max;
    return 0.005 / omega_max;
}

core::Result<void> validate_forces(const MembraneModel& model, std::span<const Force> forces)
{
    return validate_forces(static_cast<std::int64_t>(model.grid().face_count()), forces);
}

core::Result<void> validate_forces(std::int64_t faces, std::span<const Force> forces)
{
    for (std::size_t k = 0; k < forces.size(); ++k)
    {
        const Force& f = forces[k];
        const std::string name = "force " + std::to_string(k) + ": ";
        if (!core::is_finite(f.vector))
            return core::fail(core::ErrorCode::InvalidArgument, name + "vector is not finite");
        if (f.face >= faces)
            return core::fail(
                core::ErrorCode::InvalidArgument,
                name + "face " + std::to_string(f.face) + " is not below " + std::to_string(faces));
        if (f.face < 0 &&
            (!core::is_finite(f.point) || !(f.radius >= 0.0) || !std::isfinite(f.radius)))
            return core::fail(core::ErrorCode::InvalidArgument,
                              name + "point force needs a finite point and radius >= 0");
    }
    return {};
}

namespace
{

// ws.forced_rows from the offsets of non-zero accelerations and rates (canonical nodes), so the
// pipeline reads the force planes only there. Their twin and ghost copies need no marking of
// their own: the pipeline runs only when every copy into rows 0..ny-1 stays in its source's row
// (plan_pipeline checks it on the copy table), and nothing else reads forced_rows. (Walking the
// copy table here, one integer division per entry, took 4 % of a level-6 perf profile.)
void mark_forced_rows(const MembraneModel& model, Rkf45Workspace& ws)
{
    const std::ptrdiff_t stride = ws.accel.stride();
    const int ny = model.grid().ny();
    std::fill(ws.forced_rows.begin(), ws.forced_rows.end(), 0);
    // Padded offset -> row y (ghost ring 1); the ghost rows -1 and ny are read by no kernel.
    const auto row_of = [stride](std::int64_t off) { return static_cast<int>(off / stride) - 1; };
    const auto mark = [&](std::int64_t off)
    {
        if (const int y = row_of(off); y >= 0 && y < ny)
            ws.forced_rows[static_cast<std::size_t>(y)] = 1;
    };
    for (const std::int64_t off : ws.touched)
        mark(off);
    for (const std::int64_t off : ws.rate_touched)
        mark(off);
}

/// Before a re-assembly: the stencil masses it will replace (allocated by the first).
void capture_forced_masses(const MembraneModel& model, Rkf45Workspace& ws)
{
    ws.reassembly_masses = model.mass();  // same size after the first: no allocation
}

/// After a re-assembly: each force acceleration f / m_old becomes f / m_new (the lumped masses
/// follow the deformed area), and so do a linear hold's end values and rate. Every node is
/// scaled (the planes are zero off the forced nodes), so nothing is listed or allocated. The
/// ratio of stencil masses is that of the real masses: a corner's factor 2 cancels.
void rescale_force_accels(const MembraneModel& model, Rkf45Workspace& ws)
{
    const bool held = !ws.accel_end.padded().empty();
    const core::TetraGrid& g = model.grid();
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            const double scale = ws.reassembly_masses.at(x, y) / model.mass().at(x, y);
            ws.accel.at(x, y) *= scale;
            ws.accel_rate.at(x, y) *= scale;
            if (held)
                ws.accel_end.at(x, y) *= scale;
        }
    model.sync(ws.accel);
    model.sync(ws.accel_rate);
    if (held)
        model.sync(ws.accel_end);
}

}  // namespace

void set_forces(const MembraneModel& model, Rkf45Workspace& ws, std::span<const Force> forces)
{
    if (!ws.rate_touched.empty())
        end_force_ramp(model, ws, ws.accel_time, false);  // drop a ramp left open: rate zero
    write_forces(model, AccelTarget{ws.accel, ws.touched}, forces);
    mark_forced_rows(model, ws);
}

void begin_force_ramp(const MembraneModel& model, Rkf45Workspace& ws, std::span<const Force> forces,
                      double t0, double t1)
{
    PLIANT_ASSERT(t1 > t0, "begin_force_ramp: needs t1 > t0");
    if (!ws.rate_touched.empty())
        end_force_ramp(model, ws, t0, false);
    if (ws.accel_end.padded().empty())  // once per workspace: zero-order holds never need it
        ws.accel_end = Field<double>(model.grid(), 1);
    write_forces(model, AccelTarget{ws.accel_end, ws.end_touched}, forces);
    // The nodes whose acceleration may change: those of the old forces and of the new.
    ws.rate_touched.assign(ws.touched.begin(), ws.touched.end());
    ws.rate_touched.insert(ws.rate_touched.end(), ws.end_touched.begin(), ws.end_touched.end());
    std::sort(ws.rate_touched.begin(), ws.rate_touched.end());
    ws.rate_touched.erase(std::unique(ws.rate_touched.begin(), ws.rate_touched.end()),
                          ws.rate_touched.end());
    const double inv = 1.0 / (t1 - t0);
    const auto a0 = ws.accel.padded();
    const auto a1 = ws.accel_end.padded();
    auto rate = ws.accel_rate.padded();
    for (const std::int64_t off : ws.rate_touched)
    {
        const auto o = static_cast<std::size_t>(off);
        rate[o] = (a1[o] - a0[o]) * inv;
    }
    model.sync(ws.accel_rate);
    ws.accel_time = t0;
    mark_forced_rows(model, ws);
}

void end_force_ramp(const MembraneModel& model, Rkf45Workspace& ws, double t, bool reached)
{
    auto a = ws.accel.padded();
    auto rate = ws.accel_rate.padded();
    const auto a1 = ws.accel_end.padded();
    const double dt = t - ws.accel_time;
    // `accel` is now non-zero at most on the ramp's nodes: those stay in `touched` if they are
    // (a node the old forces left must not stay, or the list would grow frame after frame).
    ws.touched.clear();
    for (const std::int64_t off : ws.rate_touched)
    {
        const auto o = static_cast<std::size_t>(off);
        a[o] = reached ? a1[o] : a[o] + dt * rate[o];
        rate[o] = 0.0;
        if (a[o] != 0.0)
            ws.touched.push_back(off);
    }
    ws.rate_touched.clear();
    clear_written(AccelTarget{ws.accel_end, ws.end_touched});
    model.sync(ws.accel);
    model.sync(ws.accel_rate);
    model.sync(ws.accel_end);
    ws.accel_time = t;
    mark_forced_rows(model, ws);
}

StepReport step_prepared(MembraneModel& model, MembraneState& state, Rkf45Workspace& ws,
                         const StepOptions& options)
{
    const MembraneSettings& set = model.settings();
    StepReport report;
    const int threads =
        std::min(ws.max_threads, set.threads > 0 ? set.threads : omp_get_max_threads());

    const bool restricted = !options.owned.empty();
    const std::span<const core::Region> regions = restricted ? options.owned : model.leaf_regions();
    // The regions the last stage and the accept cover.
    const std::span<const core::Region> last =
        restricted && !options.needed.empty() ? options.needed : regions;
    if (const std::size_t n = std::max(regions.size(), last.size()); ws.leaf_error.size() < n)
    {
        ws.leaf_error.resize(n);
        ws.leaf_probe.resize(n);
    }
    if (restricted)
    {
        // Dirichlet nodes: v and every slope zero, so their stage displacements are u.
        const auto in_grid = [&](const core::Region& r)
        {
            return r.x0 >= 0 && r.y0 >= 0 && r.x1 <= model.grid().nx() &&
                   r.y1 <= model.grid().ny() && r.x0 <= r.x1 && r.y0 <= r.y1;
        };
        for (const core::Region& r : regions)
            PLIANT_ASSERT(in_grid(r), "step: owned region outside the grid");
        for (const core::Region& r : options.needed)
            PLIANT_ASSERT(in_grid(r), "step: needed region outside the grid");
        if (ws.pipeline_ok && ws.use_pipeline)
            detail::plan_restricted(model, regions, options.needed, ws);  // once per set
        else
        {
            ws.v_src.fill(0.0);
            copy_regions(state.v, ws.v_src, regions);
            model.sync(ws.v_src);
            for (auto& k : ws.kv)
                k.fill(0.0);
        }
    }
    // A swapping step (StepOptions::keep_outside false) syncs only the copies of the nodes it
    // reads or keeps: the others are the caller's to rewrite.
    const bool swapping = restricted && ws.pipeline_ok && ws.use_pipeline && !options.keep_outside;
    const auto sync_state = [&]
    {
        if (swapping)
        {
            detail::sync_live(ws, state.u);
            detail::sync_live(ws, state.v);
        }
        else
        {
            model.sync(state.u);
            model.sync(state.v);
        }
    };
    const bool reassemble = set.reassemble_every > 0 && state.tick > 0 &&
                            state.tick % static_cast<std::uint64_t>(set.reassemble_every) == 0 &&
                            model.assembled_tick() != state.tick;
    if (reassemble)
    {
        model.sync(state.u);  // the whole surface
        capture_forced_masses(model, ws);
        report.reassembled = model.reassemble(state.u).has_value();
        model.set_assembled_tick(state.tick);
        if (report.reassembled)
            rescale_force_accels(model, ws);
    }
    sync_state();

    double h = set.fixed_step ? set.fixed_dt : std::clamp(ws.next_dt(), set.dt_min, set.dt_max);
    bool limited = false;
    if (!set.fixed_step && options.dt_limit > 0.0 && h > options.dt_limit)
    {
        h = options.dt_limit;
        limited = true;
    }
    // Every retry shrinks h by 0.9 or more until it reaches dt_min, where the trial is accepted
    // or reports NonFinite: at most log(dt_min / h) / log(0.9) + 1 trials, under 6,700 for any
    // settings validate() accepts. (A fixed cap of 200 ended a step still shrinking, with
    // min_shrink near 1 and dt_min far below h, as NonFinite though nothing was.)
    for (;;)
    {
        const TrialResult t = trial(model, state, ws, regions, last, h, threads, restricted);
        const bool at_min = set.fixed_step || h <= set.dt_min;
        if (!t.finite)
        {
            if (at_min)
            {
                report.status = report.status | StepStatus::NonFinite;
                return report;
            }
            ++report.rejections;
            report.status = report.status | StepStatus::Rejected;
            h = std::max(set.dt_min, h * std::min(set.min_shrink, 0.9));
            continue;
        }
        if (t.error > 1.0 && !at_min)
        {
            ++report.rejections;
            report.status = report.status | StepStatus::Rejected;
            const double f = std::max(set.min_shrink, set.safety * std::pow(t.error, -0.2));
            h = std::max(set.dt_min, h * std::min(f, 0.9));
            continue;
        }
        if (t.error > 1.0 && !set.fixed_step)
            report.status = report.status | StepStatus::MinStepReached;
        // Accept.
        if (swapping)
            detail::accept_swapping(ws, state);
        else if (restricted && ws.pipeline_ok && ws.use_pipeline)
            detail::accept_restricted(ws, state);
        else if (restricted)
        {
            copy_regions(ws.u_out, state.u, last);
            copy_regions(ws.v_out, state.v, last);
        }
        else
        {
            std::swap(state.u, ws.u_out);
            std::swap(state.v, ws.v_out);
        }
        sync_state();
        state.time += h;
        ++state.tick;
        report.dt = h;
        report.error = t.error;
        if (!set.fixed_step)
        {
            const double f = t.error > 0.0 ? std::clamp(set.safety * std::pow(t.error, -0.2),
                                                        set.min_shrink, set.max_growth)
                                           : set.max_growth;
            double next = std::clamp(h * f, set.dt_min, set.dt_max);
            if (limited)
                next = std::max(next, std::clamp(ws.next_dt(), set.dt_min, set.dt_max));
            ws.set_next_dt(next);
        }
        return report;
    }
}

StepReport step(MembraneModel& model, MembraneState& state, Rkf45Workspace& ws,
                std::span<const Force> forces, const StepOptions& options)
{
    set_forces(model, ws, forces);
    return step_prepared(model, state, ws, options);
}

AdvanceReport advance_to(MembraneModel& model, MembraneState& state, Rkf45Workspace& ws,
                         double target_time, std::span<const Force> forces,
                         const StepOptions& options, std::uint64_t max_steps,
                         const core::ProgressSink* stop)
{
    PLIANT_ASSERT(std::isfinite(target_time), "advance_to: the target time is not finite");
    const MembraneSettings& set = model.settings();
    const bool ramp = set.force_hold == ForceHold::Linear && target_time > state.time;
    if (ramp)
        begin_force_ramp(model, ws, forces, state.time, target_time);
    else
        set_forces(model, ws, forces);
    AdvanceReport report;
    // Rounding slack of the times; with a fixed step, also well below the step (an absolute
    // 1e-12 s let a step of 1e-15 s take a thousand steps past the target).
    double slack = 1e-12 * std::max(1.0, std::fabs(target_time));
    if (set.fixed_step)
        slack = std::min(slack, 1e-3 * set.fixed_dt);
    StepOptions opt = options;
    while (report.steps < max_steps)
    {
        const double remaining = target_time - state.time;
        if (set.fixed_step ? remaining + slack < set.fixed_dt : remaining <= slack)
        {
            report.reached = true;
            break;
        }
        if (core::stop_requested(stop))
        {
            report.stopped = true;
            break;
        }
        opt.dt_limit = options.dt_limit > 0.0 ? std::min(options.dt_limit, remaining) : remaining;
        const StepReport r = step_prepared(model, state, ws, opt);
        report.status = report.status | r.status;
        report.rejections += r.rejections;
        if (has_flag(r.status, StepStatus::NonFinite))
            break;
        ++report.steps;
        if (has_flag(r.status, StepStatus::MinStepReached))
            ++report.at_min_steps;
        if (!set.fixed_step && r.dt >= remaining)
            state.time = target_time;  // land exactly, whatever the rounding of time += h
    }
    if (ramp)
        end_force_ramp(model, ws, state.time, state.time == target_time);
    return report;
}

}  // namespace pliant::sim
