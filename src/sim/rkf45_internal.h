// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The RKF45 arithmetic shared by the two ways a trial step is run (rkf45.cpp): the stage-by-stage
// pass over regions (grids whose copies do not fit the pipeline; the tests' reference) calls the
// row kernels below; the fused row pipeline of full and restricted steps (row_pipeline.cpp) runs
// two stages per loop but gives every node the same operations in the same order
// (tests/sim/pipeline_test.cpp checks it bit for bit). So results are the same whichever path,
// thread or band computes a node: full and restricted steps stay bit-identical, as sessions
// require.
//
// Row kernels take row pointers indexed by grid x (ghost column x = -1 included), not plane
// offsets, so a row can live in a full plane or in a small ring buffer.

#include <pliant/core/tetra_grid.h>
#include <pliant/sim/rkf45.h>

#include "sim/stencil_internal.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace pliant::sim::detail
{

// Fehlberg's 4(5) tableau (Hairer, Norsett & Wanner, Solving ODEs I, Table II.5.1).
struct Tableau
{
    double c[6];
    double a[6][6];
    double b5[6];
    double b4[6];
};

inline constexpr Tableau k_fehlberg = {
    {0.0, 1.0 / 4.0, 3.0 / 8.0, 12.0 / 13.0, 1.0, 1.0 / 2.0},
    {{0, 0, 0, 0, 0, 0},
     {1.0 / 4.0, 0, 0, 0, 0, 0},
     {3.0 / 32.0, 9.0 / 32.0, 0, 0, 0, 0},
     {1932.0 / 2197.0, -7200.0 / 2197.0, 7296.0 / 2197.0, 0, 0, 0},
     {439.0 / 216.0, -8.0, 3680.0 / 513.0, -845.0 / 4104.0, 0, 0},
     {-8.0 / 27.0, 2.0, -3544.0 / 2565.0, 1859.0 / 4104.0, -11.0 / 40.0, 0}},
    {16.0 / 135.0, 0.0, 6656.0 / 12825.0, 28561.0 / 56430.0, -9.0 / 50.0, 2.0 / 55.0},
    {25.0 / 216.0, 0.0, 1408.0 / 2565.0, 2197.0 / 4104.0, -1.0 / 5.0, 0.0},
};

// Step-size dependent coefficients, computed once per trial (the same on every thread):
// U_s = u + h c_s v + h^2 sum_m (A^2)_sm kv_m, u_new = u + h v + h^2 sum_m (b A)_m kv_m.
struct Coeffs
{
    double cu[6];     // h c_s
    double ck[6][6];  // h^2 (A^2)_sm
    double cv[6][6];  // h a_sj
    double ub[6];     // h^2 (b5 A)_m
    double vb[6];     // h b5_m
    double ue[6];     // h^2 ((b5 - b4) A)_m
    double ve[6];     // h (b5 - b4)_m
    double ft[6];     // force time of stage s since the force key
    double h = 0.0;
};

Coeffs make_coeffs(double h);

// Material and tolerances a stage reads, and W for the canonical-node rule of the error norm.
struct StageConstants
{
    double beta;
    double k_f;
    double rtol;
    double atol;
    int w;
};

// One row y of a stage: the inputs at row y (u, v, kv_0..kv_{S-1}, weights, 1/m, force
// accelerations), the weights of row y - 1 that the -y and -(1,1) edges read, the stage
// displacements U_S of rows y - 1, y, y + 1, and the outputs (kv_S, or u_new and v_new for S = 5).
struct StageRow
{
    const double* u;
    const double* v;
    const double* kv[5];
    const double* wx;
    const double* wy;
    const double* wd;
    const double* wy_below;  // wy of row y - 1
    const double* wd_below;  // wd of row y - 1
    const double* inv_m;
    const double* acc;
    const double* acc_rate;
    const double* U_below;
    const double* U;
    const double* U_above;
    double* kv_out;
    double* u_out;
    double* v_out;
    int y;
};

// The per-node formulas of a stage, written once: the stage pass (fill_row, stage_row) and the
// row pipeline (fill_pair, pair_row, dirichlet_row) must make the same operations in the same
// order, since tests compare their results bit for bit.

// U_S = u + h c_S v + h^2 sum_m (A^2)_{S,m} kv_m at one node, from its u, v and slopes
// kk[0..S-2] ((A^2)_{S,S-1} = 0: kv_{S-1} is not read).
template <int S>
[[gnu::always_inline]] inline double stage_displacement(const Coeffs& c, double u, double v,
                                                        const double (&kk)[5]) noexcept
{
    double value = u + c.cu[S] * v;
    for (int m = 0; m + 1 < S; ++m)
        value = value + c.ck[S][m] * kk[m];
    return value;
}

// V_S = v + h sum_{m < S} a_{S,m} kv_m at one node, from its slopes kk[0..S-1]. C is Coeffs with
// T = double, or the float coefficients of a mixed-precision step (row_pipeline.cpp).
template <int S, class C, class T>
[[gnu::always_inline]] inline T stage_velocity(const C& c, T v, const T (&kk)[5]) noexcept
{
    T vel = v;
    for (int m = 0; m < S; ++m)
        vel = vel + c.cv[S][m] * kk[m];
    return vel;
}

// The slope kv_S = -beta V_S - k_f U_S - (K U_S) / m + f at one node, from V_S, U_S, 1/m, the
// stencil's K U_S and the force acceleration f (acc + ft_S rate, or +0.0 where there is none).
// K is StageConstants with T = double, or a mixed-precision step's float constants.
template <class K, class T>
[[gnu::always_inline]] inline T stage_slope(const K& k, T vel, T uc, T inv_m, T ku, T f) noexcept
{
    return ((-k.beta * vel - k.k_f * uc) - inv_m * ku) + f;
}

// Stage displacements U_S at x in [x0 - 1, x1] into dst[x] (dst indexed by grid x) from the
// rows of u, v and kv_0..kv_{S-2} (row pointers indexed by grid x).
template <int S>
inline void fill_row(const Coeffs& c, const double* __restrict u, const double* __restrict v,
                     const double* const* kv, double* __restrict dst, int x0, int x1) noexcept
{
    // The rows never overlap dst (lets GCC vectorise without a runtime alias check per pointer
    // pair, which it would give up on).
    const double* __restrict k0 = S > 1 ? kv[0] : nullptr;
    const double* __restrict k1 = S > 2 ? kv[1] : nullptr;
    const double* __restrict k2 = S > 3 ? kv[2] : nullptr;
    const double* __restrict k3 = S > 4 ? kv[3] : nullptr;
#pragma GCC ivdep
    for (int x = x0 - 1; x <= x1; ++x)
    {
        double kk[5] = {};
        if constexpr (S > 1)
            kk[0] = k0[x];
        if constexpr (S > 2)
            kk[1] = k1[x];
        if constexpr (S > 3)
            kk[2] = k2[x];
        if constexpr (S > 4)
            kk[3] = k3[x];
        dst[x] = stage_displacement<S>(c, u[x], v[x], kk);
    }
}

// The fused last stage at one node: u_new, v_new from u0, v0, the slopes kk[0..4] and the sixth
// slope `a`, and the node's error (canonical nodes only) folded into err_bits, its non-finite
// result into `bad`. The error norm is a max over non-negative doubles, kept as the max of their
// bit patterns (IEEE order equals integer order for them) and the NaN probe as an integer flag:
// integer reductions vectorise, floating-point ones would not without reassociation
// (-ffast-math). NaN errors count as 0, as std::max(err, NaN) == err did; a NaN there implies a
// non-finite u_new or v_new, which the probe reports. Shared by stage_row (the stage pass) and
// the row pipeline, so both make the same operations in the same order.
[[gnu::always_inline]] inline void update_node(const StageConstants& k, const Coeffs& c, double u0,
                                               double v0, const double (&kk)[5], double a,
                                               bool canonical, double& u_new, double& v_new,
                                               std::int64_t& err_bits, std::int64_t& bad) noexcept
{
    double un = u0 + c.h * v0;
    double vn = v0;
    double eu = 0.0;
    double ev = 0.0;
    for (int m = 0; m < 5; ++m)
    {
        un = un + c.ub[m] * kk[m];
        vn = vn + c.vb[m] * kk[m];
        eu = eu + c.ue[m] * kk[m];
        ev = ev + c.ve[m] * kk[m];
    }
    vn = vn + c.vb[5] * a;
    ev = ev + c.ve[5] * a;
    u_new = un;
    v_new = vn;
    const double su = std::fabs(eu) / (k.atol + k.rtol * std::max(std::fabs(u0), std::fabs(un)));
    const double sv = std::fabs(ev) / (k.atol + k.rtol * std::max(std::fabs(v0), std::fabs(vn)));
    const double e = canonical ? std::max(su, sv) : 0.0;
    err_bits = std::max(err_bits, std::bit_cast<std::int64_t>(e > 0.0 ? e : 0.0));
    const double nan_probe = (un - un) + (vn - vn);  // NaN iff something is not finite
    bad |= nan_probe != 0.0 ? 1 : 0;
}

// The stage-S slopes of row r.y for x in [x0, x1). S < 5 writes kv_S; S == 5 writes u_new and
// v_new and returns the row's error norm over canonical nodes (max); a non-finite u_new or v_new
// sets `probe` to NaN.
template <int S>
inline double stage_row(const StageConstants& k, const Coeffs& c, const StageRow& r, int x0, int x1,
                        double& probe) noexcept
{
    const double* __restrict v = r.v;
    const double* __restrict wx = r.wx;
    const double* __restrict wy = r.wy;
    const double* __restrict wd = r.wd;
    const double* __restrict wyb = r.wy_below;
    const double* __restrict wdb = r.wd_below;
    const double* __restrict inv_m = r.inv_m;
    const double* __restrict acc = r.acc;
    const double* __restrict rate = r.acc_rate;
    const double* __restrict bp = r.U_below;
    const double* __restrict bc = r.U;
    const double* __restrict bn = r.U_above;
    const double* __restrict k0 = r.kv[0];
    const double* __restrict k1 = r.kv[1];
    const double* __restrict k2 = r.kv[2];
    const double* __restrict k3 = r.kv[3];
    const double* __restrict k4 = r.kv[4];
    // Error norm and NaN probe as integers (update_node says why).
    std::int64_t err_bits = 0;
    std::int64_t bad = 0;
    // Canonical nodes of this row: x < 2W, and x <= W on the folded rows y = 0 and y = W.
    const int x_canon = (r.y == 0 || r.y == k.w) ? k.w + 1 : 2 * k.w;
    [[maybe_unused]] double* __restrict out = r.kv_out;
    [[maybe_unused]] double* __restrict u_out = r.u_out;
    [[maybe_unused]] double* __restrict v_out = r.v_out;
    [[maybe_unused]] const double* __restrict u = r.u;
#pragma GCC ivdep
    for (int x = x0; x < x1; ++x)
    {
        double kk[5] = {};
        if constexpr (S > 0)
            kk[0] = k0[x];
        if constexpr (S > 1)
            kk[1] = k1[x];
        if constexpr (S > 2)
            kk[2] = k2[x];
        if constexpr (S > 3)
            kk[3] = k3[x];
        if constexpr (S > 4)
            kk[4] = k4[x];
        const double vel = stage_velocity<S>(c, v[x], kk);
        const double uc = bc[x];
        const double ku = stencil(uc, bc[x + 1], bc[x - 1], bn[x], bp[x], bn[x + 1], bp[x - 1],
                                  wx[x], wx[x - 1], wy[x], wyb[x], wd[x], wdb[x - 1]);
        const double a = stage_slope(k, vel, uc, inv_m[x], ku, acc[x] + c.ft[S] * rate[x]);
        if constexpr (S < 5)
        {
            out[x] = a;
        }
        else
        {
            update_node(k, c, u[x], v[x], kk, a, x < x_canon, u_out[x], v_out[x], err_bits, bad);
        }
    }
    if (bad != 0)
        probe = std::numeric_limits<double>::quiet_NaN();
    return std::bit_cast<double>(err_bits);
}

// Fills the fused pipeline's buffers and copy lists of `ws` for `model` (ws.pipeline_ok is
// false when a copy of the model's sync table does not fit the pipeline's row rules).
void plan_pipeline(const MembraneModel& model, Rkf45Workspace& ws);

// Mixed precision (Precision::Mixed): makes ws's float copies of the model's weights and 1/m
// when they are not those of its current assembly, and allocates the float rows once.
void prepare_mixed(const MembraneModel& model, Rkf45Workspace& ws);

// Plans restricted steps over `owned` (with `needed`, StepOptions::needed) on the pipeline (the
// per-row segments of `ws`); nothing to do when both equal the regions of the last plan.
void plan_restricted(const MembraneModel& model, std::span<const core::Region> owned,
                     std::span<const core::Region> needed, Rkf45Workspace& ws);

// Accepts a restricted pipeline trial: u_out and v_out into the state over the planned regions
// of the last pair (needed, or else owned: their merged row segments; the nodes copy_regions
// would copy).
void accept_restricted(const Rkf45Workspace& ws, MembraneState& state) noexcept;

// Accepts a restricted pipeline trial by swapping planes (StepOptions::keep_outside false):
// copies ws.keep_runs from the state into u_out and v_out, then swaps them with the state's.
void accept_swapping(Rkf45Workspace& ws, MembraneState& state) noexcept;

// The twin and ghost copies of a swapping step (ws.live_sync: those whose node the step reads
// or keeps) applied to a plane of the state.
void sync_live(const Rkf45Workspace& ws, core::Field<double>& f) noexcept;

// One trial step with the fused row pipeline (row_pipeline.cpp) into ws.u_out / v_out: a full
// one, or a restricted one over the owned set of the last plan_restricted (only its rows and
// segments are computed and written); `mixed`: a full one in mixed precision (Precision::Mixed;
// restricted steps ignore it). \return the number of bands: their error norms and NaN probes
// are ws.leaf_error / leaf_probe [0, bands).
std::size_t pipeline_trial(const MembraneModel& model, const MembraneState& state,
                           Rkf45Workspace& ws, const Coeffs& c, const StageConstants& k,
                           int threads, bool restricted, bool mixed);

// Sets FTZ and DAZ for the current thread for its lifetime (x86 SSE; elsewhere a no-op): the
// far tails of a wave decay into denormal numbers, which cost ~100x per operation on x86.
class FlushDenormals
{
public:
#if defined(__SSE__)
    FlushDenormals() : saved_(_mm_getcsr())
    {
        _mm_setcsr(saved_ | 0x8040U);
    }
    ~FlushDenormals()
    {
        _mm_setcsr(saved_);
    }

private:
    unsigned saved_;
#else
    FlushDenormals() = default;
#endif
public:
    FlushDenormals(const FlushDenormals&) = delete;
    FlushDenormals& operator=(const FlushDenormals&) = delete;
};

}  // namespace pliant::sim::detail
