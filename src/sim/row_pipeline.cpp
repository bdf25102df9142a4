// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// The fused row pipeline of an RKF45 trial step, full or restricted (docs/physics.md §8).
//
// Design
// - Since u' = v, stage S applies K only to U_S = u + h c_S v + h^2 sum (A^2)_Sm kv_m, and
//   (A^2)_{S,S-1} = 0: stage S at row y needs kv_{S-1} at row y only and kv_0..kv_{S-2} at rows
//   y - 1 .. y + 1. A wavefront therefore runs all six stages in one sweep over the rows: at
//   sweep position j, stages 0 and 1 compute row j, stages 2 and 3 row j - 1, stages 4 and 5
//   row j - 2. Each pair runs in one loop over the row (stage P + 1 reads kv_P at its own node
//   only), sharing the loads of v, the weights, 1/m and the forces. Every slope row is read within
//   three sweep positions of being written, so kv_1..kv_4 live in ring buffers of four rows per
//   thread (cache resident; kv_5 and kv_6 never leave the loop) instead of five grid planes: a
//   step reads u, v, the three weights, 1/m and the force plane once and writes u_new and v_new
//   once (11 doubles per node with the write-allocate, instead of 64).
// - Twins and ghosts: the gluing keeps every twin and ghost column in its own row, and the ghost
//   rows y = -1 and y = ny read rows 1 and ny - 2 only (TetraGrid::fold), so the model's copy
//   table is applied row by row right after a slope row is written: before any later stage
//   reads it. plan_pipeline checks these rules on the actual table and leaves the pipeline off
//   otherwise (the stage-by-stage pass then runs).
// - Threads: the rows are split into one band per thread. A band recomputes the slope rows its
//   stages need next to it (kv_1, kv_2 two rows beyond each end, kv_3, kv_4 one row), so bands
//   need no barrier; the extra work is 6 row-stages per band end (under 1 % at level 8 on two
//   threads). Every node gets the same operations with the same inputs whichever band or thread
//   computes it, so results are bit-identical for any thread count and to the stage-by-stage
//   pass.
// - Restricted steps (StepOptions::owned) run the same sweep over the rows holding owned nodes,
//   and within a row over the planned x-segments only (plan_restricted, once per owned set): the
//   kernels over the owned regions' merged x-intervals, the U fills over those of the row and its
//   two neighbours one node wider. Positions whose canonical node is not owned are Dirichlet:
//   the stage pass gives them v = 0 and zero slopes, so their U is u + 0.0 for every stage and
//   no slope outside the owned set is ever needed (no growing halo). A slope is read only at a
//   moving position, which this sweep computed (or copied from its canonical node), so stale
//   ring values elsewhere are never read. Twins inside an owned rectangle whose canonical node is
//   not owned are computed at the last pair with zero inputs (dirichlet_row), as the stage pass
//   does, for the NaN probe.
// - Needed nodes (StepOptions::needed): each pair has its own plan, its kernels over the needed
//   nodes dilated by 2, 1 and 0 stencil rings (within the owned set), its fills about them. A
//   pair's stencil reads the earlier pairs' slopes within one ring of its kernels only, where
//   those were computed; the fills also compute U at positions no kernel reads (the widened
//   intervals' corners), from stale ring values, which is harmless.
//
// Alternatives rejected: square leaf tiles with a shrinking halo (the first plan): they need a
// ghost ring of 3 on every model and state plane and redundant halo work on four sides (13 % at
// 64 x 64), where full-width rows need neither; keeping the kv planes and only reordering the
// loops: at level 10 the five planes (84 MB) still stream to memory.

#include <pliant/core/assert.h>

#include <omp.h>

#include "sim/rkf45_internal.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

namespace pliant::sim::detail
{
namespace
{

constexpr int k_ring = 4;  // rows of kv_m in flight: written at j, last read at j + 3
// Buffered rows per thread: kv_1..kv_4 rings, their ghost rows below and above, and three
// rolling U rows for each of the six stages.
constexpr int k_stored = 4;  // kv_1..kv_4 (kv_5 and kv_6 stay inside the last pair's loop)
constexpr int k_kv_ghost_row = k_stored * k_ring;
constexpr int k_U_row = k_kv_ghost_row + 2 * k_stored;
constexpr int k_rows_per_thread = k_U_row + 3 * 6;

// A mixed-precision step (rkf45.h) also keeps the rows of K u (written by the first pair, read
// by the later ones at their own node) in a ring after the others.
constexpr int k_ku_row = k_rows_per_thread;
constexpr int k_rows_per_thread_mixed = k_rows_per_thread + k_ring;

// One thread's rows (64-byte aligned) of doubles, or of floats in a mixed-precision step; row
// pointers point at grid x = 0 (x = -1 .. nx are valid).
template <class T>
struct BandRows
{
    // Rows start `pad` values (64 bytes) before grid x = 0, so that x = 0 of every buffered row
    // is 64-byte aligned (one cache line: AVX-512 loads of x .. x + 7 then touch one line, not
    // two).
    static constexpr std::size_t pad = 64 / sizeof(T);
    T* base;
    std::size_t len;
    int ny;

    [[nodiscard]] T* kv_row(int m, int y) const noexcept
    {
        std::size_t r = 0;
        if (y < 0)
            r = static_cast<std::size_t>(k_kv_ghost_row + m);
        else if (y >= ny)
            r = static_cast<std::size_t>(k_kv_ghost_row + k_stored + m);
        else
            r = static_cast<std::size_t>(m * k_ring + (y & (k_ring - 1)));
        return base + r * len + pad;
    }
    [[nodiscard]] T* U_row(int stage, int y) const noexcept
    {
        const int slot = (y + 3) % 3;  // y >= -1
        return base + static_cast<std::size_t>(k_U_row + 3 * stage + slot) * len + pad;
    }
    [[nodiscard]] T* ku_row(int y) const noexcept
    {
        return base + static_cast<std::size_t>(k_ku_row + (y & (k_ring - 1))) * len + pad;
    }
};
using BandBuffers = BandRows<double>;

// The planes of one trial (ghost-ring-1 origins, one stride).
struct Inputs
{
    const double* u;
    const double* v;
    const double* wx;
    const double* wy;
    const double* wd;
    const double* inv_m;
    const double* acc;
    const double* acc_rate;
    const char* forced;  // [y]: row y has a non-zero force acceleration or rate
    double* u_out;
    double* v_out;
    // Mixed precision: the float copies of wx, wy, wd and 1/m (same layout).
    const float* fwx;
    const float* fwy;
    const float* fwd;
    const float* finv_m;
    std::ptrdiff_t s;
    int nx;
    int ny;
    const Rkf45Workspace* ws;

    template <class T>
    [[nodiscard]] const T* row(const T* plane, int y) const noexcept
    {
        return plane + static_cast<std::ptrdiff_t>(y) * s;
    }
};

// Applies the model's twin and ghost copies that read slope row y of kv_m.
template <class T>
void copy_row(const Inputs& in, const BandRows<T>& b, int m, int y) noexcept
{
    const Rkf45Workspace& ws = *in.ws;
    T* row = b.kv_row(m, y) - 1;  // indexed by x + 1, as the copies
    const auto ys = static_cast<std::size_t>(y);
    for (std::size_t i = ws.row_copy_start[ys]; i < ws.row_copy_start[ys + 1]; ++i)
        row[ws.row_copies[i].dst] = row[ws.row_copies[i].src];
    if (y == 1)
    {
        T* dst = b.kv_row(m, -1) - 1;
        for (const core::GhostCopy& cp : ws.below_copies)
            dst[cp.dst] = row[cp.src];
    }
    if (y == in.ny - 2)
    {
        T* dst = b.kv_row(m, in.ny) - 1;
        for (const core::GhostCopy& cp : ws.above_copies)
            dst[cp.dst] = row[cp.src];
    }
}

// U_P and U_{P+1} of row yy over the segments [segs, end) (full steps: one, [-1, nx]): at moving
// positions in one loop over u and v (and kv_0..kv_3 as each needs), with the operations of
// fill_row<P> and fill_row<P + 1>; at Dirichlet positions (restricted steps) the stage pass
// computes u + c_S h v + ... with v and every slope +0.0, which is u + 0.0 for every stage (h > 0,
// so h c_S 0 = +0.0; the slope terms then add +-0.0 to a value that is not -0.0).
// All of a row's segments go in one call: a restricted step's cost per row segment is mostly
// per-call set-up (pointers, constants, loop entry), so one call per row, not per segment,
// cuts it (docs/physics.md §8).
template <int P>
void fill_pair(const Inputs& in, const Coeffs& c, const BandBuffers& b, int yy,
               const Rkf45Workspace::RowSegment* segs,
               const Rkf45Workspace::RowSegment* end) noexcept
{
    constexpr int A = P;
    constexpr int B = P + 1;
    const double* __restrict u = in.row(in.u, yy);
    const double* __restrict v = in.row(in.v, yy);
    const double* __restrict k0 = B > 2 ? b.kv_row(0, yy) : nullptr;
    const double* __restrict k1 = B > 2 ? b.kv_row(1, yy) : nullptr;
    const double* __restrict k2 = B > 4 ? b.kv_row(2, yy) : nullptr;
    const double* __restrict k3 = B > 4 ? b.kv_row(3, yy) : nullptr;
    double* __restrict da = b.U_row(A, yy);
    double* __restrict db = b.U_row(B, yy);
    for (; segs != end; ++segs)
    {
        const int x1 = segs->x1;
        if (!segs->moves)
        {
            for (int x = segs->x0; x < x1; ++x)
            {
                const double value = u[x] + 0.0;
                da[x] = value;
                db[x] = value;
            }
            continue;
        }
#pragma GCC ivdep
        for (int x = segs->x0; x < x1; ++x)
        {
            double kk[5] = {};
            if constexpr (B > 2)
            {
                kk[0] = k0[x];
                kk[1] = k1[x];
            }
            if constexpr (B > 4)
            {
                kk[2] = k2[x];
                kk[3] = k3[x];
            }
            const double ua = stage_displacement<A>(c, u[x], v[x], kk);
            const double ub = stage_displacement<B>(c, u[x], v[x], kk);
            da[x] = ua;
            db[x] = ub;
        }
    }
}

// Stages P and P + 1 of row y at the moving positions of the segments [segs, end) (full steps:
// one, [0, nx)), in one loop per segment, with the operations of stage_row<P> and
// stage_row<P + 1> (checked bit for bit by tests/sim/pipeline_test.cpp). Stage P + 1 reads
// kv_P only at its own node: the value just computed, which for a canonical node is what the
// stage pass reads from the kv_P plane (twins and ghosts are overwritten by copy_row before any
// other node reads them). P < 4 writes kv_P and kv_{P+1}; P == 4 finishes the step (u_new,
// v_new: kv_4 and kv_5 are never stored) and returns the row's error norm (see update_row in
// rkf45_internal.h for the reductions).
// Rows without forces (Forced = false; most rows of a picked surface) read neither force plane
// and add the +0.0 that acc + ft rate is there, so the bits are those of the stage pass.
template <int P, bool Forced>
double pair_row(const Inputs& in, const Coeffs& c, const StageConstants& k, const BandBuffers& b,
                int y, const Rkf45Workspace::RowSegment* segs,
                const Rkf45Workspace::RowSegment* end, double& probe) noexcept
{
    constexpr int A = P;
    constexpr int B = P + 1;
    const double* __restrict v = in.row(in.v, y);
    const double* __restrict k0 = A > 0 ? b.kv_row(0, y) : nullptr;
    const double* __restrict k1 = A > 1 ? b.kv_row(1, y) : nullptr;
    const double* __restrict k2 = A > 2 ? b.kv_row(2, y) : nullptr;
    const double* __restrict k3 = A > 3 ? b.kv_row(3, y) : nullptr;
    const double* __restrict wx = in.row(in.wx, y);
    const double* __restrict wy = in.row(in.wy, y);
    const double* __restrict wd = in.row(in.wd, y);
    const double* __restrict wyb = in.row(in.wy, y - 1);
    const double* __restrict wdb = in.row(in.wd, y - 1);
    const double* __restrict inv_m = in.row(in.inv_m, y);
    const double* __restrict acc = Forced ? in.row(in.acc, y) : nullptr;
    const double* __restrict rate = Forced ? in.row(in.acc_rate, y) : nullptr;
    const double* __restrict ap = b.U_row(A, y - 1);
    const double* __restrict ac = b.U_row(A, y);
    const double* __restrict an = b.U_row(A, y + 1);
    const double* __restrict bp = b.U_row(B, y - 1);
    const double* __restrict bc = b.U_row(B, y);
    const double* __restrict bn = b.U_row(B, y + 1);
    [[maybe_unused]] double* __restrict out_a = P < 4 ? b.kv_row(A, y) : nullptr;
    [[maybe_unused]] double* __restrict out_b = P < 4 ? b.kv_row(B, y) : nullptr;
    [[maybe_unused]] const double* __restrict u = in.row(in.u, y);
    [[maybe_unused]] double* __restrict u_out = in.u_out + static_cast<std::ptrdiff_t>(y) * in.s;
    [[maybe_unused]] double* __restrict v_out = in.v_out + static_cast<std::ptrdiff_t>(y) * in.s;
    std::int64_t err_bits = 0;
    std::int64_t bad = 0;
    const int x_canon = (y == 0 || y == k.w) ? k.w + 1 : 2 * k.w;
    for (; segs != end; ++segs)
    {
        if (!segs->moves)
            continue;
        const int x1 = segs->x1;
#pragma GCC ivdep
        for (int x = segs->x0; x < x1; ++x)
        {
            double kk[5] = {};
            if constexpr (A > 0)
                kk[0] = k0[x];
            if constexpr (A > 1)
                kk[1] = k1[x];
            if constexpr (A > 2)
                kk[2] = k2[x];
            if constexpr (A > 3)
                kk[3] = k3[x];
            const double vel = stage_velocity<A>(c, v[x], kk);
            const double uc = ac[x];
            const double ku = stencil(uc, ac[x + 1], ac[x - 1], an[x], ap[x], an[x + 1], ap[x - 1],
                                      wx[x], wx[x - 1], wy[x], wyb[x], wd[x], wdb[x - 1]);
            double fa = 0.0;
            double fb = 0.0;
            if constexpr (Forced)
            {
                fa = acc[x] + c.ft[A] * rate[x];
                fb = acc[x] + c.ft[B] * rate[x];
            }
            const double sa = stage_slope(k, vel, uc, inv_m[x], ku, fa);
            kk[A] = sa;
            const double vel_b = stage_velocity<B>(c, v[x], kk);
            const double ucb = bc[x];
            const double kub =
                stencil(ucb, bc[x + 1], bc[x - 1], bn[x], bp[x], bn[x + 1], bp[x - 1], wx[x],
                        wx[x - 1], wy[x], wyb[x], wd[x], wdb[x - 1]);
            const double sb = stage_slope(k, vel_b, ucb, inv_m[x], kub, fb);
            if constexpr (P < 4)
            {
                out_a[x] = sa;
                out_b[x] = sb;
            }
            else
            {
                update_node(k, c, u[x], v[x], kk, sb, x < x_canon, u_out[x], v_out[x], err_bits,
                            bad);
            }
        }
    }
    if (bad != 0)
        probe = std::numeric_limits<double>::quiet_NaN();
    return std::bit_cast<double>(err_bits);
}

// The last stage and the update at the Dirichlet nodes of a restricted step's kernel segment
// [x0, x1) of row y: twins inside an owned region whose canonical node is not owned. The stage
// pass computes them with v and every slope +0.0 (its masked planes); their u_new and v_new are
// overwritten by the accept's twin copy, but their NaN probe counts, so they are computed here
// with the same operations. Their slopes kv_0..kv_4 are never read (twin copies overwrite them,
// and readers of Dirichlet nodes take zeros), so the earlier pairs skip them.
double dirichlet_row(const Inputs& in, const Coeffs& c, const StageConstants& k,
                     const BandBuffers& b, int y, int x0, int x1, double& probe) noexcept
{
    const double* __restrict wx = in.row(in.wx, y);
    const double* __restrict wy = in.row(in.wy, y);
    const double* __restrict wd = in.row(in.wd, y);
    const double* __restrict wyb = in.row(in.wy, y - 1);
    const double* __restrict wdb = in.row(in.wd, y - 1);
    const double* __restrict inv_m = in.row(in.inv_m, y);
    const double* __restrict acc = in.row(in.acc, y);
    const double* __restrict rate = in.row(in.acc_rate, y);
    const double* __restrict bp = b.U_row(5, y - 1);
    const double* __restrict bc = b.U_row(5, y);
    const double* __restrict bn = b.U_row(5, y + 1);
    const double* __restrict u = in.row(in.u, y);
    double* __restrict u_out = in.u_out + static_cast<std::ptrdiff_t>(y) * in.s;
    double* __restrict v_out = in.v_out + static_cast<std::ptrdiff_t>(y) * in.s;
    std::int64_t err_bits = 0;
    std::int64_t bad = 0;
    const int x_canon = (y == 0 || y == k.w) ? k.w + 1 : 2 * k.w;
    for (int x = x0; x < x1; ++x)
    {
        const double kk[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
        const double vel = stage_velocity<5>(c, 0.0, kk);
        const double uc = bc[x];
        const double ku = stencil(uc, bc[x + 1], bc[x - 1], bn[x], bp[x], bn[x + 1], bp[x - 1],
                                  wx[x], wx[x - 1], wy[x], wyb[x], wd[x], wdb[x - 1]);
        const double a = stage_slope(k, vel, uc, inv_m[x], ku, acc[x] + c.ft[5] * rate[x]);
        update_node(k, c, u[x], 0.0, kk, a, x < x_canon, u_out[x], v_out[x], err_bits, bad);
    }
    if (bad != 0)
        probe = std::numeric_limits<double>::quiet_NaN();
    return std::bit_cast<double>(err_bits);
}

// The U rows of stages P, P + 1 at row yy: the whole row (full steps) or the row's fill segments
// (restricted steps).
template <int P, bool Restricted>
void fill_rows(const Inputs& in, const Coeffs& c, const BandBuffers& b, int yy) noexcept
{
    if constexpr (Restricted)
    {
        const Rkf45Workspace::PairPlan& plan = in.ws->pair_plans[P / 2];
        const auto r = static_cast<std::size_t>(yy + 1);
        const Rkf45Workspace::RowSegment* segs = plan.fill_segments.data();
        if (plan.fill_start[r] != plan.fill_start[r + 1])
            fill_pair<P>(in, c, b, yy, segs + plan.fill_start[r], segs + plan.fill_start[r + 1]);
    }
    else
    {
        const Rkf45Workspace::RowSegment whole{-1, in.nx + 1, true};
        fill_pair<P>(in, c, b, yy, &whole, &whole + 1);
    }
}

// Stages P and P + 1 at row y (the band's first row of this pair is `first`): the next U rows,
// the pair kernel, then the copies of the new slope rows. Returns the row's error norm (P = 4).
template <int P, bool Restricted>
double stage_pair(const Inputs& in, const Coeffs& c, const StageConstants& k, const BandBuffers& b,
                  int y, int first, double& probe) noexcept
{
    if (y == first)
    {
        fill_rows<P, Restricted>(in, c, b, y - 1);
        fill_rows<P, Restricted>(in, c, b, y);
    }
    fill_rows<P, Restricted>(in, c, b, y + 1);
    double err = 0.0;
    const bool forced = in.forced[y] != 0;
    if constexpr (Restricted)
    {
        const Rkf45Workspace::PairPlan& plan = in.ws->pair_plans[P / 2];
        const auto r = static_cast<std::size_t>(y);
        const Rkf45Workspace::RowSegment* first_seg =
            plan.kernel_segments.data() + plan.kernel_start[r];
        const Rkf45Workspace::RowSegment* end_seg =
            plan.kernel_segments.data() + plan.kernel_start[r + 1];
        if (first_seg != end_seg)
            err = forced ? pair_row<P, true>(in, c, k, b, y, first_seg, end_seg, probe)
                         : pair_row<P, false>(in, c, k, b, y, first_seg, end_seg, probe);
        if constexpr (P == 4)
            for (const Rkf45Workspace::RowSegment* seg = first_seg; seg != end_seg; ++seg)
                if (!seg->moves)
                    err = std::max(err, dirichlet_row(in, c, k, b, y, seg->x0, seg->x1, probe));
    }
    else
    {
        const Rkf45Workspace::RowSegment whole{0, in.nx, true};
        err = forced ? pair_row<P, true>(in, c, k, b, y, &whole, &whole + 1, probe)
                     : pair_row<P, false>(in, c, k, b, y, &whole, &whole + 1, probe);
    }
    if constexpr (P < 4)
    {
        // Restricted: a row none of whose copies reads a moving node is skipped (every copy
        // would write a Dirichlet position, whose slopes are never read).
        if (!Restricted || in.ws->copies_move[static_cast<std::size_t>(y)] != 0)
        {
            copy_row(in, b, P, y);
            copy_row(in, b, P + 1, y);
        }
    }
    return err;
}

// Rows [y0, y1) of the new state: the wavefront, with the slope rows beyond the band that its
// stages read recomputed here. pair(std::integral_constant<int, P>, y, first) runs stages P and
// P + 1 at row y (`first`: the band's first row of that pair) and returns the row's error norm.
template <class Pair>
void sweep_band(int ny, int y0, int y1, const Pair& pair, double& err) noexcept
{
    const int lo01 = std::max(0, y0 - 2);
    const int hi01 = std::min(ny, y1 + 2);
    const int lo23 = std::max(0, y0 - 1);
    const int hi23 = std::min(ny, y1 + 1);
    for (int j = lo01; j <= y1 + 1; ++j)
    {
        if (j < hi01)
            (void)pair(std::integral_constant<int, 0>{}, j, lo01);
        if (const int y = j - 1; y >= lo23 && y < hi23)
            (void)pair(std::integral_constant<int, 2>{}, y, lo23);
        if (const int y = j - 2; y >= y0 && y < y1)
            err = std::max(err, pair(std::integral_constant<int, 4>{}, y, y0));
    }
}

template <bool Restricted>
void run_band(const Inputs& in, const Coeffs& c, const StageConstants& k, const BandBuffers& b,
              int y0, int y1, double& err, double& probe) noexcept
{
    sweep_band(
        in.ny, y0, y1,
        [&](auto pair, int y, int first)
        { return stage_pair<decltype(pair)::value, Restricted>(in, c, k, b, y, first, probe); },
        err);
}

// ---- Mixed precision (MembraneSettings::precision, docs/physics.md §9) ----------------------
// The same sweep, with the stage displacements kept as increments D_S = U_S - u (float) and
// K U_S = K u + K D_S: K u is the stencil of the double state, taken once per trial (the first
// pair, in double, then rounded to float and kept in a ring row for the later pairs, which read
// it at their own node only, so it needs no twin copies); everything else a stage computes is
// an increment over the step-start state, in float. The update adds the float increments to the
// double u and v. In single precision K U_S itself would lose most of its digits on a fine grid
// (the differences of neighbouring U are ~ 1/nx of U); K D_S loses as many digits of D_S, which
// is ~ h v, so the rounding stays ~ 1e-7 of a step's change.

// Coefficients and constants rounded to float once per trial.
struct MixedCoeffs
{
    float cu[6];
    float ck[6][6];
    float cv[6][6];
    float ub[6];
    float vb[6];
    float ue[6];
    float ve[6];
    float h;
    float beta;
    float k_f;
    float rtol;
    float atol;
};

MixedCoeffs mixed_coeffs(const Coeffs& c, const StageConstants& k) noexcept
{
    MixedCoeffs f{};
    for (int s = 0; s < 6; ++s)
    {
        f.cu[s] = static_cast<float>(c.cu[s]);
        f.ub[s] = static_cast<float>(c.ub[s]);
        f.vb[s] = static_cast<float>(c.vb[s]);
        f.ue[s] = static_cast<float>(c.ue[s]);
        f.ve[s] = static_cast<float>(c.ve[s]);
        for (int m = 0; m < 6; ++m)
        {
            f.ck[s][m] = static_cast<float>(c.ck[s][m]);
            f.cv[s][m] = static_cast<float>(c.cv[s][m]);
        }
    }
    f.h = static_cast<float>(c.h);
    f.beta = static_cast<float>(k.beta);
    f.k_f = static_cast<float>(k.k_f);
    f.rtol = static_cast<float>(k.rtol);
    f.atol = static_cast<float>(k.atol);
    return f;
}

// D_S = h c_S v + h^2 sum_m (A^2)_{S,m} kv_m (stage_displacement less u).
template <int S>
[[gnu::always_inline]] inline float mixed_increment(const MixedCoeffs& c, float v,
                                                    const float (&kk)[5]) noexcept
{
    float d = c.cu[S] * v;
    for (int m = 0; m + 1 < S; ++m)
        d = d + c.ck[S][m] * kk[m];
    return d;
}

// update_node with float slopes: the increments of u and v and the error estimate in float,
// u_new and v_new in double; the error norm's max kept as the bits of a non-negative float.
[[gnu::always_inline]] inline void mixed_update(const MixedCoeffs& c, double u0, double v0,
                                                float u0f, float v0f, const float (&kk)[5], float a,
                                                bool canonical, double& u_new, double& v_new,
                                                std::int32_t& err_bits, std::int32_t& bad) noexcept
{
    float du = c.h * v0f;
    float dv = 0.0F;
    float eu = 0.0F;
    float ev = 0.0F;
    for (int m = 0; m < 5; ++m)
    {
        du = du + c.ub[m] * kk[m];
        dv = dv + c.vb[m] * kk[m];
        eu = eu + c.ue[m] * kk[m];
        ev = ev + c.ve[m] * kk[m];
    }
    dv = dv + c.vb[5] * a;
    ev = ev + c.ve[5] * a;
    const double un = u0 + static_cast<double>(du);
    const double vn = v0 + static_cast<double>(dv);
    u_new = un;
    v_new = vn;
    const float unf = static_cast<float>(un);
    const float vnf = static_cast<float>(vn);
    const float su = std::fabs(eu) / (c.atol + c.rtol * std::max(std::fabs(u0f), std::fabs(unf)));
    const float sv = std::fabs(ev) / (c.atol + c.rtol * std::max(std::fabs(v0f), std::fabs(vnf)));
    const float e = canonical ? std::max(su, sv) : 0.0F;
    err_bits = std::max(err_bits, std::bit_cast<std::int32_t>(e > 0.0F ? e : 0.0F));
    const double nan_probe = (un - un) + (vn - vn);
    bad |= nan_probe != 0.0 ? 1 : 0;
}

// D rows of stages P, P + 1 at row yy, x = -1 .. nx (stage 0 needs none: it reads u).
template <int P>
void mixed_fill_pair(const Inputs& in, const MixedCoeffs& c, const BandRows<float>& b,
                     int yy) noexcept
{
    constexpr int A = P;
    constexpr int B = P + 1;
    const double* __restrict v = in.row(in.v, yy);
    const float* __restrict k0 = B > 2 ? b.kv_row(0, yy) : nullptr;
    const float* __restrict k1 = B > 2 ? b.kv_row(1, yy) : nullptr;
    const float* __restrict k2 = B > 4 ? b.kv_row(2, yy) : nullptr;
    const float* __restrict k3 = B > 4 ? b.kv_row(3, yy) : nullptr;
    [[maybe_unused]] float* __restrict da = A > 0 ? b.U_row(A, yy) : nullptr;
    float* __restrict db = b.U_row(B, yy);
    const int x1 = in.nx + 1;
#pragma GCC ivdep
    for (int x = -1; x < x1; ++x)
    {
        float kk[5] = {};
        if constexpr (B > 2)
        {
            kk[0] = k0[x];
            kk[1] = k1[x];
        }
        if constexpr (B > 4)
        {
            kk[2] = k2[x];
            kk[3] = k3[x];
        }
        const auto vf = static_cast<float>(v[x]);
        if constexpr (A > 0)
            da[x] = mixed_increment<A>(c, vf, kk);
        db[x] = mixed_increment<B>(c, vf, kk);
    }
}

// Stages P and P + 1 of row y, x = 0 .. nx - 1 (pair_row's mixed twin). P = 0 takes K u of the
// double state and keeps it (float) in the ring for the later pairs.
template <int P, bool Forced>
double mixed_pair_row(const Inputs& in, const Coeffs& cd, const MixedCoeffs& c, int w,
                      const BandRows<float>& b, int y, double& probe) noexcept
{
    constexpr int A = P;
    constexpr int B = P + 1;
    const double* __restrict v = in.row(in.v, y);
    const double* __restrict u = in.row(in.u, y);
    [[maybe_unused]] const double* __restrict u_below = in.row(in.u, y - 1);
    [[maybe_unused]] const double* __restrict u_above = in.row(in.u, y + 1);
    const float* __restrict k0 = A > 0 ? b.kv_row(0, y) : nullptr;
    const float* __restrict k1 = A > 1 ? b.kv_row(1, y) : nullptr;
    const float* __restrict k2 = A > 2 ? b.kv_row(2, y) : nullptr;
    const float* __restrict k3 = A > 3 ? b.kv_row(3, y) : nullptr;
    const float* __restrict wx = in.row(in.fwx, y);
    const float* __restrict wy = in.row(in.fwy, y);
    const float* __restrict wd = in.row(in.fwd, y);
    const float* __restrict wyb = in.row(in.fwy, y - 1);
    const float* __restrict wdb = in.row(in.fwd, y - 1);
    const float* __restrict inv_m = in.row(in.finv_m, y);
    const double* __restrict acc = Forced ? in.row(in.acc, y) : nullptr;
    const double* __restrict rate = Forced ? in.row(in.acc_rate, y) : nullptr;
    [[maybe_unused]] const float* __restrict ap = A > 0 ? b.U_row(A, y - 1) : nullptr;
    [[maybe_unused]] const float* __restrict ac = A > 0 ? b.U_row(A, y) : nullptr;
    [[maybe_unused]] const float* __restrict an = A > 0 ? b.U_row(A, y + 1) : nullptr;
    const float* __restrict bp = b.U_row(B, y - 1);
    const float* __restrict bc = b.U_row(B, y);
    const float* __restrict bn = b.U_row(B, y + 1);
    [[maybe_unused]] float* __restrict ku_out = P == 0 ? b.ku_row(y) : nullptr;
    [[maybe_unused]] const float* __restrict ku_in = P > 0 ? b.ku_row(y) : nullptr;
    [[maybe_unused]] float* __restrict out_a = P < 4 ? b.kv_row(A, y) : nullptr;
    [[maybe_unused]] float* __restrict out_b = P < 4 ? b.kv_row(B, y) : nullptr;
    [[maybe_unused]] double* __restrict u_out = in.u_out + static_cast<std::ptrdiff_t>(y) * in.s;
    [[maybe_unused]] double* __restrict v_out = in.v_out + static_cast<std::ptrdiff_t>(y) * in.s;
    std::int32_t err_bits = 0;
    std::int32_t bad = 0;
    const int x_canon = (y == 0 || y == w) ? w + 1 : 2 * w;
    const int x1 = in.nx;
#pragma GCC ivdep
    for (int x = 0; x < x1; ++x)
    {
        float kk[5] = {};
        if constexpr (A > 0)
            kk[0] = k0[x];
        if constexpr (A > 1)
            kk[1] = k1[x];
        if constexpr (A > 2)
            kk[2] = k2[x];
        if constexpr (A > 3)
            kk[3] = k3[x];
        const auto vf = static_cast<float>(v[x]);
        const auto uf = static_cast<float>(u[x]);
        float ku = 0.0F;
        if constexpr (P == 0)
        {
            const auto d = [](float f) { return static_cast<double>(f); };
            ku = static_cast<float>(stencil(u[x], u[x + 1], u[x - 1], u_above[x], u_below[x],
                                            u_above[x + 1], u_below[x - 1], d(wx[x]), d(wx[x - 1]),
                                            d(wy[x]), d(wyb[x]), d(wd[x]), d(wdb[x - 1])));
            ku_out[x] = ku;
        }
        else
            ku = ku_in[x];
        float fa = 0.0F;
        float fb = 0.0F;
        if constexpr (Forced)
        {
            fa = static_cast<float>(acc[x] + cd.ft[A] * rate[x]);
            fb = static_cast<float>(acc[x] + cd.ft[B] * rate[x]);
        }
        float sa = 0.0F;
        if constexpr (A == 0)
            sa = stage_slope(c, vf, uf, inv_m[x], ku, fa);
        else
        {
            const float vel = stage_velocity<A>(c, vf, kk);
            const float dc = ac[x];
            const float kd = stencil(dc, ac[x + 1], ac[x - 1], an[x], ap[x], an[x + 1], ap[x - 1],
                                     wx[x], wx[x - 1], wy[x], wyb[x], wd[x], wdb[x - 1]);
            sa = stage_slope(c, vel, uf + dc, inv_m[x], ku + kd, fa);
        }
        kk[A] = sa;
        const float vel_b = stage_velocity<B>(c, vf, kk);
        const float dcb = bc[x];
        const float kdb = stencil(dcb, bc[x + 1], bc[x - 1], bn[x], bp[x], bn[x + 1], bp[x - 1],
                                  wx[x], wx[x - 1], wy[x], wyb[x], wd[x], wdb[x - 1]);
        const float sb = stage_slope(c, vel_b, uf + dcb, inv_m[x], ku + kdb, fb);
        if constexpr (P < 4)
        {
            out_a[x] = sa;
            out_b[x] = sb;
        }
        else
        {
            mixed_update(c, u[x], v[x], uf, vf, kk, sb, x < x_canon, u_out[x], v_out[x], err_bits,
                         bad);
        }
    }
    if (bad != 0)
        probe = std::numeric_limits<double>::quiet_NaN();
    return static_cast<double>(std::bit_cast<float>(err_bits));
}

// stage_pair's mixed twin (full steps only).
template <int P>
double mixed_stage_pair(const Inputs& in, const Coeffs& cd, const MixedCoeffs& c, int w,
                        const BandRows<float>& b, int y, int first, double& probe) noexcept
{
    if (y == first)
    {
        mixed_fill_pair<P>(in, c, b, y - 1);
        mixed_fill_pair<P>(in, c, b, y);
    }
    mixed_fill_pair<P>(in, c, b, y + 1);
    const double err = in.forced[y] != 0 ? mixed_pair_row<P, true>(in, cd, c, w, b, y, probe)
                                         : mixed_pair_row<P, false>(in, cd, c, w, b, y, probe);
    if constexpr (P < 4)
    {
        copy_row(in, b, P, y);
        copy_row(in, b, P + 1, y);
    }
    return err;
}

// run_band's mixed twin.
void mixed_run_band(const Inputs& in, const Coeffs& cd, const MixedCoeffs& c, int w,
                    const BandRows<float>& b, int y0, int y1, double& err, double& probe) noexcept
{
    sweep_band(
        in.ny, y0, y1,
        [&](auto pair, int y, int first)
        { return mixed_stage_pair<decltype(pair)::value>(in, cd, c, w, b, y, first, probe); },
        err);
}

// The first 64-byte boundary in a thread-row buffer (it holds 64 spare bytes for it).
template <class T>
T* aligned_rows(std::vector<T>& buffers) noexcept
{
    T* p = buffers.data();
    const auto misalign = reinterpret_cast<std::uintptr_t>(p) % 64U;
    return misalign == 0 ? p : p + (64U - misalign) / sizeof(T);
}

}  // namespace

void prepare_mixed(const MembraneModel& model, Rkf45Workspace& ws)
{
    const core::Field<double>* planes[4] = {&model.weight_x(), &model.weight_y(), &model.weight_d(),
                                            &model.inverse_mass()};
    const std::size_t n = planes[0]->padded().size();
    for (const core::Field<double>* plane : planes)
        PLIANT_ASSERT(plane->padded().size() == n && plane->stride() == planes[0]->stride(),
                      "prepare_mixed: the model's planes differ in layout");
    if (ws.mixed_assembly != model.assembly_id() || ws.mixed_plane_len != n)
    {
        ws.mixed_plane_len = n;
        ws.mixed_model.resize(4 * n);
        for (std::size_t p = 0; p < 4; ++p)
            std::transform(planes[p]->padded().begin(), planes[p]->padded().end(),
                           ws.mixed_model.begin() + static_cast<std::ptrdiff_t>(p * n),
                           [](double x) { return static_cast<float>(x); });
        ws.mixed_assembly = model.assembly_id();
    }
    if (ws.mixed_buffers.empty())
    {
        constexpr std::size_t pad = BandRows<float>::pad;
        ws.mixed_row_len =
            (pad + static_cast<std::size_t>(model.grid().nx()) + 1 + pad - 1) / pad * pad;
        ws.mixed_buffer_len = static_cast<std::size_t>(k_rows_per_thread_mixed) * ws.mixed_row_len;
        // + pad: room to align the first row to 64 bytes.
        ws.mixed_buffers.assign(
            ws.mixed_buffer_len * static_cast<std::size_t>(ws.max_threads) + pad, 0.0F);
    }
}

void plan_pipeline(const MembraneModel& model, Rkf45Workspace& ws)
{
    const core::TetraGrid& g = model.grid();
    const int nx = g.nx();
    const int ny = g.ny();
    const std::ptrdiff_t stride = nx + 2;
    constexpr std::size_t pad = BandBuffers::pad;
    ws.pipeline_row_len = (pad + static_cast<std::size_t>(nx) + 1 + pad - 1) / pad * pad;
    ws.pipeline_buffer_len = static_cast<std::size_t>(k_rows_per_thread) * ws.pipeline_row_len;
    // + 8: room to align the first row to 64 bytes (aligned_rows).
    ws.pipeline_buffers.assign(
        ws.pipeline_buffer_len * static_cast<std::size_t>(ws.max_threads) + 8, 0.0);
    std::vector<std::vector<core::GhostCopy>> per_row(static_cast<std::size_t>(ny));
    ws.below_copies.clear();
    ws.above_copies.clear();
    // Each position of the ghost ring must be written exactly once.
    std::vector<int> written(static_cast<std::size_t>(stride * (ny + 2)), 0);
    bool ok = ny >= 3;
    for (const core::GhostCopy& cp : model.sync_table())
    {
        const auto dy = static_cast<int>(cp.dst / stride) - 1;
        const auto dx = static_cast<int>(cp.dst % stride) - 1;
        const auto sy = static_cast<int>(cp.src / stride) - 1;
        const auto sx = static_cast<int>(cp.src % stride) - 1;
        const core::GhostCopy cols{dx + 1, sx + 1};
        ++written[static_cast<std::size_t>(cp.dst)];
        if (sx < 0 || sx >= nx || sy < 0 || sy >= ny)
            ok = false;
        else if (dy == sy)
            per_row[static_cast<std::size_t>(sy)].push_back(cols);
        else if (dy == -1 && sy == 1)
            ws.below_copies.push_back(cols);
        else if (dy == ny && sy == ny - 2)
            ws.above_copies.push_back(cols);
        else
            ok = false;
    }
    for (int y = -1; y <= ny; ++y)
        for (int x = -1; x <= nx; ++x)
            if ((y < 0 || y >= ny || x < 0 || x >= nx) &&
                written[static_cast<std::size_t>((y + 1) * stride + x + 1)] != 1)
                ok = false;
    ws.row_copies.clear();
    ws.row_copy_start.assign(1, 0);
    for (const auto& copies : per_row)
    {
        ws.row_copies.insert(ws.row_copies.end(), copies.begin(), copies.end());
        ws.row_copy_start.push_back(ws.row_copies.size());
    }
    ws.pipeline_ok = ok;
}

void plan_restricted(const MembraneModel& model, std::span<const core::Region> owned,
                     std::span<const core::Region> needed, Rkf45Workspace& ws)
{
    if (ws.restricted_planned && std::ranges::equal(owned, ws.restricted_key) &&
        std::ranges::equal(needed, ws.needed_key))
        return;
    const core::TetraGrid& g = model.grid();
    const int nx = g.nx();
    const int ny = g.ny();
    using Interval = std::pair<int, int>;
    using RowIntervals = std::vector<std::vector<Interval>>;
    const auto merge = [](std::vector<Interval>& iv)
    {
        std::sort(iv.begin(), iv.end());
        std::size_t n = 0;
        for (const Interval& i : iv)
        {
            if (n > 0 && i.first <= iv[n - 1].second)
                iv[n - 1].second = std::max(iv[n - 1].second, i.second);
            else
                iv[n++] = i;
        }
        iv.resize(n);
    };
    // The x-intervals of regions, per row, merged; `mark` flags their canonical nodes.
    const auto region_rows = [&](std::span<const core::Region> regions, std::vector<char>& mark)
    {
        RowIntervals rows(static_cast<std::size_t>(ny));
        for (const core::Region& r : regions)
            for (int y = r.y0; y < r.y1 && r.x0 < r.x1; ++y)
            {
                rows[static_cast<std::size_t>(y)].emplace_back(r.x0, r.x1);
                for (int x = r.x0; x < r.x1; ++x)
                    if (const core::NodeIndex n = g.index(x, y); g.is_canonical(n))
                        mark[n.value] = 1;
            }
        for (auto& iv : rows)
            merge(iv);
        return rows;
    };
    // The runs of canonical positions whose node is flagged, per row.
    const auto mask_rows = [&](const std::vector<char>& mask)
    {
        RowIntervals rows(static_cast<std::size_t>(ny));
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx;)
            {
                const auto in = [&](int xx)
                {
                    const core::NodeIndex n = g.index(xx, y);
                    return g.is_canonical(n) && mask[n.value] != 0;
                };
                if (!in(x))
                {
                    ++x;
                    continue;
                }
                const int x0 = x;
                while (x < nx && in(x))
                    ++x;
                rows[static_cast<std::size_t>(y)].emplace_back(x0, x);
            }
        return rows;
    };
    std::vector<char> inside(g.node_count(), 0);
    // The kernels' x-intervals of every row, per pair of stages.
    std::array<RowIntervals, 3> kernels;
    kernels[0] = region_rows(owned, inside);
    if (needed.empty())
        kernels[1] = kernels[2] = kernels[0];
    else
    {
        // Stages 5-6 over the needed nodes; 3-4 and 1-2 over the owned nodes those read, one
        // and two stencil rings out (a pair reads the previous pairs' slopes at its stencil's
        // neighbours only, rkf45.h).
        std::vector<char> want(g.node_count(), 0);
        kernels[2] = region_rows(needed, want);
        for (std::size_t i = 0; i < want.size(); ++i)
            PLIANT_ASSERT(want[i] == 0 || inside[i] != 0, "step: a needed node is not owned");
        for (const int rings : {1, 2})
        {
            std::vector<char> reach = core::dilate_nodes(g, want, rings);
            for (std::size_t i = 0; i < reach.size(); ++i)
                reach[i] = static_cast<char>(reach[i] != 0 && inside[i] != 0);
            kernels[static_cast<std::size_t>(2 - rings)] = mask_rows(reach);
        }
    }
    // A position moves iff the canonical node it stands for lies in an owned region.
    const auto moves = [&](int x, int y) { return inside[g.image(x, y).value] != 0; };
    // Splits [x0, x1) of row y into runs of moving and of Dirichlet positions.
    const auto split = [&](std::vector<Rkf45Workspace::RowSegment>& out, int y, int x0, int x1)
    {
        for (int x = x0; x < x1;)
        {
            const bool m = moves(x, y);
            int e = x + 1;
            while (e < x1 && moves(e, y) == m)
                ++e;
            out.push_back({x, e, m});
            x = e;
        }
    };
    for (std::size_t q = 0; q < 3; ++q)
    {
        Rkf45Workspace::PairPlan& plan = ws.pair_plans[q];
        const RowIntervals& rows = kernels[q];
        plan.kernel_segments.clear();
        plan.kernel_start.assign(1, 0);
        for (int y = 0; y < ny; ++y)
        {
            for (const Interval& i : rows[static_cast<std::size_t>(y)])
                split(plan.kernel_segments, y, i.first, i.second);
            plan.kernel_start.push_back(plan.kernel_segments.size());
        }
        // The fills: the kernel intervals of the row and its two neighbours, one node wider on
        // each side (the stencil reads x - 1 .. x + 1), over rows -1 .. ny.
        plan.fill_segments.clear();
        plan.fill_start.assign(1, 0);
        for (int y = -1; y <= ny; ++y)
        {
            std::vector<Interval> iv;
            for (int yy = std::max(0, y - 1); yy <= std::min(ny - 1, y + 1); ++yy)
                for (const Interval& i : rows[static_cast<std::size_t>(yy)])
                    iv.emplace_back(i.first - 1, i.second + 1);
            merge(iv);
            for (const Interval& i : iv)
                split(plan.fill_segments, y, i.first, i.second);
            plan.fill_start.push_back(plan.fill_segments.size());
        }
    }
    // The rows of the last pair's kernels, and their work for the band split.
    ws.restricted_work.assign(1, 0);
    ws.restricted_y0 = ny;
    ws.restricted_y1 = 0;
    for (int y = 0; y < ny; ++y)
    {
        std::size_t width = 0;
        for (const Interval& i : kernels[2][static_cast<std::size_t>(y)])
            width += static_cast<std::size_t>(i.second - i.first);
        if (width > 0)
        {
            ws.restricted_y0 = std::min(ws.restricted_y0, y);
            ws.restricted_y1 = y + 1;
        }
        // A row's fills, copies and loop set-up cost about as much as 32 nodes.
        ws.restricted_work.push_back(ws.restricted_work.back() + width + (width > 0 ? 32 : 0));
    }
    // Rows whose twin and ghost copies read a moving node.
    ws.copies_move.assign(static_cast<std::size_t>(ny), 0);
    const auto src_moves = [&](int y, const core::GhostCopy& cp)
    { return moves(static_cast<int>(cp.src) - 1, y); };
    for (int y = 0; y < ny; ++y)
    {
        const auto r = static_cast<std::size_t>(y);
        char any = 0;
        for (std::size_t i = ws.row_copy_start[r]; i < ws.row_copy_start[r + 1]; ++i)
            any = static_cast<char>(any | (src_moves(y, ws.row_copies[i]) ? 1 : 0));
        if (y == 1)
            for (const core::GhostCopy& cp : ws.below_copies)
                any = static_cast<char>(any | (src_moves(y, cp) ? 1 : 0));
        if (y == ny - 2)
            for (const core::GhostCopy& cp : ws.above_copies)
                any = static_cast<char>(any | (src_moves(y, cp) ? 1 : 0));
        ws.copies_move[r] = any;
    }
    if (ws.restricted_y0 >= ws.restricted_y1)
        ws.restricted_y0 = ws.restricted_y1 = 0;
    // The nodes a step reads or keeps (StepOptions::keep_outside false): the owned nodes, their
    // first ring (through the ghost map) and the images of every position the fills read.
    std::vector<char> live = core::dilate_nodes(g, inside, 1);
    for (const Rkf45Workspace::PairPlan& plan : ws.pair_plans)
        for (int y = -1; y <= ny; ++y)
            for (std::size_t i = plan.fill_start[static_cast<std::size_t>(y + 1)];
                 i < plan.fill_start[static_cast<std::size_t>(y + 2)]; ++i)
                for (int x = plan.fill_segments[i].x0; x < plan.fill_segments[i].x1; ++x)
                    live[g.image(x, y).value] = 1;
    // Their twin and ghost copies: the syncs of a swapping step.
    const std::ptrdiff_t stride = ws.u_out.stride();
    ws.live_sync.clear();
    for (const core::GhostCopy& cp : model.sync_table())
    {
        const auto dst = static_cast<std::ptrdiff_t>(cp.dst);
        const int x = static_cast<int>(dst % stride) - 1;  // ghost ring 1
        const int y = static_cast<int>(dst / stride) - 1;
        if (live[g.image(x, y).value] != 0)
            ws.live_sync.push_back(cp);
    }
    // What a swapping accept carries over: those nodes less the canonical positions the last
    // pair writes (twins and ghosts follow from the sync after the accept).
    for (int y = 0; y < ny; ++y)
        for (const Interval& i : kernels[2][static_cast<std::size_t>(y)])
            for (int x = i.first; x < i.second; ++x)
                if (const core::NodeIndex n = g.index(x, y); g.is_canonical(n))
                    live[n.value] = 0;
    ws.keep_runs = core::node_runs(g, live);
    ws.restricted_key.assign(owned.begin(), owned.end());
    ws.needed_key.assign(needed.begin(), needed.end());
    ws.restricted_planned = true;
}

void accept_restricted(const Rkf45Workspace& ws, MembraneState& state) noexcept
{
    const std::ptrdiff_t s = state.u.stride();
    const double* const uo = ws.u_out.origin();
    const double* const vo = ws.v_out.origin();
    double* const u = state.u.origin();
    double* const v = state.v.origin();
    const Rkf45Workspace::PairPlan& plan = ws.pair_plans[2];
    for (int y = ws.restricted_y0; y < ws.restricted_y1; ++y)
    {
        const auto r = static_cast<std::size_t>(y);
        const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(y) * s;
        // The segments of a row are disjoint and increasing: copy each maximal run at once.
        std::size_t i = plan.kernel_start[r];
        while (i < plan.kernel_start[r + 1])
        {
            const int x0 = plan.kernel_segments[i].x0;
            int x1 = plan.kernel_segments[i].x1;
            for (++i; i < plan.kernel_start[r + 1] && plan.kernel_segments[i].x0 == x1; ++i)
                x1 = plan.kernel_segments[i].x1;
            std::copy(uo + row + x0, uo + row + x1, u + row + x0);
            std::copy(vo + row + x0, vo + row + x1, v + row + x0);
        }
    }
}

void sync_live(const Rkf45Workspace& ws, core::Field<double>& f) noexcept
{
    double* const d = f.padded().data();
    for (const core::GhostCopy& c : ws.live_sync)
        d[c.dst] = d[c.src];
}

void accept_swapping(Rkf45Workspace& ws, MembraneState& state) noexcept
{
    const std::ptrdiff_t s = state.u.stride();
    const double* const u = state.u.origin();
    const double* const v = state.v.origin();
    double* const uo = ws.u_out.origin();
    double* const vo = ws.v_out.origin();
    for (const core::Region& r : ws.keep_runs)
        for (int y = r.y0; y < r.y1; ++y)
        {
            const std::ptrdiff_t a = static_cast<std::ptrdiff_t>(y) * s + r.x0;
            const std::ptrdiff_t b = static_cast<std::ptrdiff_t>(y) * s + r.x1;
            // Most runs are the one or two ring nodes at a share's row ends: a loop, not a
            // memmove call, for those.
            if (b - a <= 4)
                for (std::ptrdiff_t i = a; i < b; ++i)
                {
                    uo[i] = u[i];
                    vo[i] = v[i];
                }
            else
            {
                std::copy(u + a, u + b, uo + a);
                std::copy(v + a, v + b, vo + a);
            }
        }
    std::swap(state.u, ws.u_out);
    std::swap(state.v, ws.v_out);
}

std::size_t pipeline_trial(const MembraneModel& model, const MembraneState& state,
                           Rkf45Workspace& ws, const Coeffs& c, const StageConstants& k,
                           int threads, bool restricted, bool mixed)
{
    mixed = mixed && !restricted;
    if (mixed)
        prepare_mixed(model, ws);
    const core::TetraGrid& g = model.grid();
    Inputs in{};
    in.u = state.u.origin();
    in.v = state.v.origin();
    in.wx = model.weight_x().origin();
    in.wy = model.weight_y().origin();
    in.wd = model.weight_d().origin();
    in.inv_m = model.inverse_mass().origin();
    in.acc = ws.accel.origin();
    in.acc_rate = ws.accel_rate.origin();
    in.forced = ws.forced_rows.data();
    in.u_out = ws.u_out.origin();
    in.v_out = ws.v_out.origin();
    if (mixed)
    {
        const float* f = ws.mixed_model.data() + (in.wx - model.weight_x().padded().data());
        const auto n = static_cast<std::ptrdiff_t>(ws.mixed_plane_len);
        in.fwx = f;
        in.fwy = f + n;
        in.fwd = f + 2 * n;
        in.finv_m = f + 3 * n;
    }
    in.s = state.u.stride();
    in.nx = g.nx();
    in.ny = g.ny();
    in.ws = &ws;
    // Restricted steps: the rows holding owned nodes, split into bands of equal work.
    const int ylo = restricted ? ws.restricted_y0 : 0;
    const int yhi = restricted ? ws.restricted_y1 : in.ny;
    if (yhi <= ylo)
        return 0;
    const int bands = std::clamp(threads, 1, yhi - ylo);
    const auto band_start = [&](int band)
    {
        if (!restricted)
            return in.ny * band / bands;
        if (band == bands)
            return yhi;
        const std::size_t w0 = ws.restricted_work[static_cast<std::size_t>(ylo)];
        const std::size_t total = ws.restricted_work[static_cast<std::size_t>(yhi)] - w0;
        const std::size_t target =
            w0 + total * static_cast<std::size_t>(band) / static_cast<std::size_t>(bands);
        const auto it = std::lower_bound(ws.restricted_work.begin() + ylo,
                                         ws.restricted_work.begin() + yhi, target);
        return static_cast<int>(it - ws.restricted_work.begin());
    };
    double* const rows = aligned_rows(ws.pipeline_buffers);
    float* const mixed_rows = mixed ? aligned_rows(ws.mixed_buffers) : nullptr;
    const MixedCoeffs mc = mixed ? mixed_coeffs(c, k) : MixedCoeffs{};
    // Band `band` on the thread whose buffers start at `thread`.
    const auto run = [&](int band, int thread)
    {
        const BandBuffers b{rows + static_cast<std::size_t>(thread) * ws.pipeline_buffer_len,
                            ws.pipeline_row_len, in.ny};
        const int y0 = band_start(band);
        const int y1 = band_start(band + 1);
        double err = 0.0;
        double probe = 0.0;
        if (mixed)
        {
            const BandRows<float> fb{
                mixed_rows + static_cast<std::size_t>(thread) * ws.mixed_buffer_len,
                ws.mixed_row_len, in.ny};
            mixed_run_band(in, c, mc, k.w, fb, y0, y1, err, probe);
        }
        else if (restricted)
        {
            if (y0 < y1)
                run_band<true>(in, c, k, b, y0, y1, err, probe);
        }
        else
            run_band<false>(in, c, k, b, y0, y1, err, probe);
        ws.leaf_error[static_cast<std::size_t>(band)] = err;
        ws.leaf_probe[static_cast<std::size_t>(band)] = probe;
    };
    if (bands == 1)
    {
        // One band on the calling thread: an OpenMP region of one thread still costs libgomp
        // two futex calls (about 2 us on this VM, 3 % of a level-6 step, 10 % of a quarter of
        // it; docs/physics.md §8).
        const FlushDenormals flush;
        run(0, 0);
        return 1;
    }
#pragma omp parallel num_threads(threads)
    {
        // Denormals flushed on every thread (see FlushDenormals): the same mode everywhere.
        const FlushDenormals flush;
#pragma omp for schedule(static)
        for (int band = 0; band < bands; ++band)
            run(band, omp_get_thread_num());
    }
    return static_cast<std::size_t>(bands);
}

}  // namespace pliant::sim::detail
