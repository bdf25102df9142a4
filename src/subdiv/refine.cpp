// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Butterfly refinement kernels.
//
// Layout: the coarse field is a padded row-major plane; fine row 2y interleaves even nodes
// (copies of coarse row y) with horizontal-edge nodes, fine row 2y+1 interleaves vertical-edge
// nodes (even x) with diagonal-edge nodes (odd x). One pass over the coarse rows writes each
// fine row exactly once, left to right, so the output streams through memory once and the
// four coarse rows a step reads stay in L1/L2. Each row is a separate function taking
// __restrict pointers, so GCC vectorises it even when called from an OpenMP-outlined loop (the
// outlining drops __restrict on captured variables; see TESTING-NOTES.md).
//
// Invariant: every odd value is computed by `butterfly` with a fixed grouping of the sums and
// no FMA contraction (-ffp-contract=off), so it depends only on the eight tap values, never on
// the thread count, the instruction set's vector width or the position in the row.
//
// Alternatives rejected: one generic loop over (offset, weight) taps (the weights then become
// loads, and 8 multiplies replace 3); three separate passes, one per direction, writing strided
// output (three times the write traffic on the output's cache lines); computing only canonical
// nodes and scattering to twins (branches in the row loop; twins are 0.1 % of the nodes).
#include <pliant/subdiv/refine.h>

#include <algorithm>
#include <cstddef>

namespace pliant::subdiv
{
namespace
{

// The regular modified butterfly with its sums grouped by weight class (the grouping is part of
// the results' definition: tests/subdiv/reference_butterfly.cpp follows it).
template <typename T>
inline T butterfly(T a0, T a1, T b0, T b1, T c0, T c1, T c2, T c3) noexcept
{
    return (T(0.5) * (a0 + a1) + T(0.125) * (b0 + b1)) - T(0.0625) * ((c0 + c1) + (c2 + c3));
}

// Fine row 2y: even nodes copied from coarse row y, horizontal-edge nodes between them.
// `in` points at coarse node (0, y), `out` at fine node (0, 2y); n = 2W edges per row.
template <typename T>
void even_row(const T* __restrict in, T* __restrict out, const TapOffsets& h, int n) noexcept
{
    const T* a0 = in + h[0];
    const T* a1 = in + h[1];
    const T* b0 = in + h[2];
    const T* b1 = in + h[3];
    const T* c0 = in + h[4];
    const T* c1 = in + h[5];
    const T* c2 = in + h[6];
    const T* c3 = in + h[7];
    for (int x = 0; x < n; ++x)
    {
        out[2 * x] = in[x];
        out[2 * x + 1] = butterfly(a0[x], a1[x], b0[x], b1[x], c0[x], c1[x], c2[x], c3[x]);
    }
    out[2 * n] = in[n];
}

// Fine row 2y+1: vertical-edge nodes (2x, 2y+1) and diagonal-edge nodes (2x+1, 2y+1).
template <typename T>
void odd_row(const T* __restrict in, T* __restrict out, const TapOffsets& v, const TapOffsets& d,
             int n) noexcept
{
    const T* va0 = in + v[0];
    const T* va1 = in + v[1];
    const T* vb0 = in + v[2];
    const T* vb1 = in + v[3];
    const T* vc0 = in + v[4];
    const T* vc1 = in + v[5];
    const T* vc2 = in + v[6];
    const T* vc3 = in + v[7];
    const T* da0 = in + d[0];
    const T* da1 = in + d[1];
    const T* db0 = in + d[2];
    const T* db1 = in + d[3];
    const T* dc0 = in + d[4];
    const T* dc1 = in + d[5];
    const T* dc2 = in + d[6];
    const T* dc3 = in + d[7];
    for (int x = 0; x < n; ++x)
    {
        out[2 * x] = butterfly(va0[x], va1[x], vb0[x], vb1[x], vc0[x], vc1[x], vc2[x], vc3[x]);
        out[2 * x + 1] = butterfly(da0[x], da1[x], db0[x], db1[x], dc0[x], dc1[x], dc2[x], dc3[x]);
    }
    out[2 * n] = butterfly(va0[n], va1[n], vb0[n], vb1[n], vc0[n], vc1[n], vc2[n], vc3[n]);
}

template <typename T>
struct RowJob
{
    const T* in = nullptr;
    T* out = nullptr;
    std::ptrdiff_t in_stride = 0;
    std::ptrdiff_t out_stride = 0;
    const TapOffsets* h = nullptr;
    const TapOffsets* v = nullptr;
    const TapOffsets* d = nullptr;
    int n = 0;     // edges per coarse row (2W)
    int rows = 0;  // coarse rows (W+1)
};

// Coarse row y produces fine rows 2y and 2y+1 (the last coarse row only the even one).
template <typename T>
inline void do_row(const RowJob<T>& job, int y) noexcept
{
    const T* in = job.in + static_cast<std::ptrdiff_t>(y) * job.in_stride;
    T* out = job.out + static_cast<std::ptrdiff_t>(2 * y) * job.out_stride;
    even_row(in, out, *job.h, job.n);
    if (y + 1 < job.rows)
        odd_row(in, out + job.out_stride, *job.v, *job.d, job.n);
}

// Below this many fine nodes per thread, waking a second thread costs more than it saves (a
// level-6 step takes ~50 us on one core); the result is the same either way.
constexpr long k_min_nodes_per_thread = 1L << 16;

template <typename T>
void run_rows(const RowJob<T>& job, int threads) noexcept
{
    const long fine_nodes = 4L * job.rows * (job.n + 1);
    threads = static_cast<int>(std::min<long>(threads, fine_nodes / k_min_nodes_per_thread));
    if (threads <= 1)
    {
        for (int y = 0; y < job.rows; ++y)
            do_row(job, y);
        return;
    }
    // Static schedule: contiguous blocks of rows per thread, no reduction, so the output is the
    // same for any thread count.
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int y = 0; y < job.rows; ++y)
        do_row(job, y);
}

}  // namespace

template <typename T>
void refine(const ConvolutionPlan& plan, const core::Field<T>& in, core::Field<T>& out,
            int threads) noexcept
{
    PLIANT_ASSERT(in.level() == plan.coarse_level(), "refine: input is not at the plan's level");
    PLIANT_ASSERT(out.level() == plan.fine_level(), "refine: output is not at the fine level");
    PLIANT_ASSERT(in.ghost() >= k_refine_ghost, "refine: input needs a ghost ring of width 1");
    PLIANT_ASSERT(threads >= 1, "refine: threads must be >= 1");
    PLIANT_ASSERT(static_cast<const void*>(in.padded().data()) !=
                      static_cast<const void*>(out.padded().data()),
                  "refine: input and output must be distinct fields");

    RowJob<T> job;
    job.in = in.origin();
    job.out = out.origin();
    job.in_stride = in.stride();
    job.out_stride = out.stride();
    job.h = &plan.offsets(EdgeDirection::Horizontal, in.ghost());
    job.v = &plan.offsets(EdgeDirection::Vertical, in.ghost());
    job.d = &plan.offsets(EdgeDirection::Diagonal, in.ghost());
    job.n = 2 * plan.coarse_grid().w();
    job.rows = plan.coarse_grid().ny();
    run_rows(job, threads);

    core::sync_twins(plan.fine_grid(), out);
    core::fill_ghosts(plan.fine_grid(), out);
}

template <typename T>
void refine(const ConvolutionPlan& plan, const core::Vec3Field<T>& in, core::Vec3Field<T>& out,
            int threads) noexcept
{
    for (std::size_t c = 0; c < 3; ++c)
        refine(plan, in[c], out[c], threads);
}

template <typename T>
void restrict(const ConvolutionPlan& plan, const core::Field<T>& fine,
              core::Field<T>& coarse) noexcept
{
    PLIANT_ASSERT(fine.level() == plan.fine_level(), "restrict: fine field of another level");
    PLIANT_ASSERT(coarse.level() == plan.coarse_level(), "restrict: coarse field of another level");
    const int nx = plan.coarse_grid().nx();
    const int ny = plan.coarse_grid().ny();
    for (int y = 0; y < ny; ++y)
    {
        const T* src = fine.origin() + fine.offset(0, 2 * y);
        T* dst = coarse.origin() + coarse.offset(0, y);
        for (int x = 0; x < nx; ++x)
            dst[x] = src[2 * x];
    }
    core::fill_ghosts(plan.coarse_grid(), coarse);
}

template <typename T>
core::Field<T> restrict(const ConvolutionPlan& plan, const core::Field<T>& fine, int ghost)
{
    core::Field<T> coarse(plan.coarse_grid(), ghost);
    restrict(plan, fine, coarse);
    return coarse;
}

template <typename T>
core::Field<T> refine_levels(std::span<const ConvolutionPlan> plans, const core::Field<T>& in,
                             int out_ghost, int threads)
{
    PLIANT_ASSERT(!plans.empty(), "refine_levels: no plans");
    PLIANT_ASSERT(in.level() == plans.front().coarse_level(), "refine_levels: level mismatch");
    // A private copy with the ghost ring the mask needs: `in` may have none.
    core::Field<T> cur(plans.front().coarse_grid(), k_refine_ghost);
    for (int y = 0; y < in.ny(); ++y)
        for (int x = 0; x < in.nx(); ++x)
            cur.at(x, y) = in.at(x, y);
    core::fill_ghosts(plans.front().coarse_grid(), cur);
    for (std::size_t i = 0; i < plans.size(); ++i)
    {
        PLIANT_ASSERT(i == 0 || plans[i].coarse_level() == plans[i - 1].fine_level(),
                      "refine_levels: plans are not consecutive levels");
        const bool last = i + 1 == plans.size();
        core::Field<T> next(plans[i].fine_grid(), last ? out_ghost : k_refine_ghost);
        refine(plans[i], cur, next, threads);
        cur = std::move(next);
    }
    return cur;
}

template <typename T>
core::Vec3Field<T> refine_levels(std::span<const ConvolutionPlan> plans,
                                 const core::Vec3Field<T>& in, int out_ghost, int threads)
{
    return {refine_levels(plans, in[0], out_ghost, threads),
            refine_levels(plans, in[1], out_ghost, threads),
            refine_levels(plans, in[2], out_ghost, threads)};
}

template <typename T>
core::Result<core::Field<T>> refine_levels(const core::Field<T>& in, int levels, int out_ghost)
{
    auto plans = make_plans(in.level(), levels);
    if (!plans)
        return plans.error();
    return refine_levels<T>(*plans, in, out_ghost, 1);
}

template <typename T>
core::Result<core::Vec3Field<T>> refine_levels(const core::Vec3Field<T>& in, int levels,
                                               int out_ghost)
{
    auto plans = make_plans(in[0].level(), levels);
    if (!plans)
        return plans.error();
    return refine_levels<T>(*plans, in, out_ghost, 1);
}

#define PLIANT_SUBDIV_INSTANTIATE(T)                                                         \
    template void refine<T>(const ConvolutionPlan&, const core::Field<T>&, core::Field<T>&,  \
                            int) noexcept;                                                   \
    template void refine<T>(const ConvolutionPlan&, const core::Vec3Field<T>&,               \
                            core::Vec3Field<T>&, int) noexcept;                              \
    template void restrict<T>(const ConvolutionPlan&, const core::Field<T>&,                 \
                              core::Field<T>&) noexcept;                                     \
    template core::Field<T> restrict<T>(const ConvolutionPlan&, const core::Field<T>&, int); \
    template core::Field<T> refine_levels<T>(std::span<const ConvolutionPlan>,               \
                                             const core::Field<T>&, int, int);               \
    template core::Vec3Field<T> refine_levels<T>(std::span<const ConvolutionPlan>,           \
                                                 const core::Vec3Field<T>&, int, int);       \
    template core::Result<core::Field<T>> refine_levels<T>(const core::Field<T>&, int, int); \
    template core::Result<core::Vec3Field<T>> refine_levels<T>(const core::Vec3Field<T>&, int, int);

PLIANT_SUBDIV_INSTANTIATE(float)
PLIANT_SUBDIV_INSTANTIATE(double)

#undef PLIANT_SUBDIV_INSTANTIATE

}  // namespace pliant::subdiv
