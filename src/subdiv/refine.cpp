// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Butterfly refinement kernels.
//
// Layout: the coarse field is a padded row-major plane; fine row 2y interleaves even nodes
// (copies of coarse row y) with horizontal-edge nodes, fine row 2y+1 interleaves vertical-edge
// nodes (even x) with diagonal-edge nodes (odd x). One loop over coarse row y writes both fine
// rows, left to right, so the output is written once and the four coarse rows a step reads stay
// in L1/L2. The loop reads the eleven distinct taps of a coarse position once for all three
// masks (offsets from the constexpr masks, so the compiler sees which taps coincide; GCC 12
// still folds some repeats into the additions: 19 vector loads per 16 positions, against 25
// for separate per-row loops). It takes __restrict pointers, so GCC vectorises it even when
// called from an OpenMP-outlined region (GCC's outlining drops __restrict on captured
// variables, and a loop on them is then not vectorised; -fopt-info-vec shows which loops are).
//
// Output planes larger than the last-level cache can hold beside their input (level 10) are
// written with streaming stores: without them every output line was first read from memory
// (write-allocate) and evicted the input, and a 9 -> 10 step of three float planes (25 MB out,
// 32 MB L3) ran at half the per-node speed of 8 -> 9. Float rows go through an L1-resident row
// buffer (RowStreamer); double rows, with AVX-512, are computed by the fused loop written with
// intrinsics and streamed straight from the registers (row_pair_streamed: one two-source permute
// per vector aligns the row, whatever its offset): 20 % faster in double at 9 -> 10, but 15 %
// slower in float, where the row buffer stays (docs/subdivision.md, "Streaming from the
// registers"). Smaller outputs are written directly and stay in cache for their next use.
//
// Invariant: every odd value is computed by `butterfly` with a fixed grouping of the sums and
// no FMA contraction (-ffp-contract=off), so it depends only on the eight tap values, never on
// the thread count, the instruction set's vector width, the store path or the position in the
// row (tests/subdiv/refine_kernel_test.cpp pins it against the earlier per-row kernel).
//
// Alternatives rejected: one generic loop over (offset, weight) taps (the weights then become
// loads, and 8 multiplies replace 3); three separate passes, one per direction, writing strided
// output (three times the write traffic on the output's cache lines); computing only canonical
// nodes and scattering to twins (branches in the row loop; twins are 0.1 % of the nodes); one
// loop per fine row with the plan's runtime offsets (the previous kernel: the compiler cannot
// tell which taps coincide; about 20 % slower in cache); streaming a whole row after
// computing it (the stores then do not overlap the arithmetic: 9 -> 10 took 1.6 ms, against 1.1
// with chunks of 128 edges); software prefetch of row y+2 in the streamed loop (no gain at 64,
// 256 or 1,024 floats ahead).
#include <pliant/subdiv/refine.h>

#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

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

// The eleven distinct taps of coarse position x over all three masks (rows y-1 .. y+2), read
// once into locals. Reading each mask's eight taps separately would be 24 reads per position;
// GCC does not merge them all on its own (it folds repeated reads into the additions).
template <typename T>
struct TapValues
{
    T m1[3];  // row y-1, dx = -1 .. 1
    T z0[3];  // row y,   dx = -1 .. 1
    T p1[4];  // row y+1, dx = -1 .. 2
    T p2;     // row y+2, dx = 1
};

template <int Dx, int Dy, typename Taps>
inline auto tap(const Taps& t) noexcept
{
    if constexpr (Dy == -1 && Dx >= -1 && Dx <= 1)
        return t.m1[Dx + 1];
    else if constexpr (Dy == 0 && Dx >= -1 && Dx <= 1)
        return t.z0[Dx + 1];
    else if constexpr (Dy == 1 && Dx >= -1 && Dx <= 2)
        return t.p1[Dx + 1];
    else
    {
        static_assert(Dy == 2 && Dx == 1, "a mask tap outside the eleven read by row_pair");
        return t.p2;
    }
}

// The butterfly of mask M from the tap values (offsets are compile-time constants from the
// constexpr masks of butterfly_mask.h).
template <const Mask& M, typename T>
inline T apply(const TapValues<T>& t) noexcept
{
    return butterfly(tap<M[0].dx, M[0].dy>(t), tap<M[1].dx, M[1].dy>(t), tap<M[2].dx, M[2].dy>(t),
                     tap<M[3].dx, M[3].dy>(t), tap<M[4].dx, M[4].dy>(t), tap<M[5].dx, M[5].dy>(t),
                     tap<M[6].dx, M[6].dy>(t), tap<M[7].dx, M[7].dy>(t));
}

template <typename T>
inline TapValues<T> read_taps(const T* rm1, const T* r0, const T* r1, const T* r2, int x) noexcept
{
    return {{rm1[x - 1], rm1[x], rm1[x + 1]},
            {r0[x - 1], r0[x], r0[x + 1]},
            {r1[x - 1], r1[x], r1[x + 1], r1[x + 2]},
            r2[x + 1]};
}

// The vertical edge at the row's end, x = n: its mask does not read (2, 1), which would lie
// past the ghost column.
template <typename T>
inline T vertical_at_end(const T* rm1, const T* r0, const T* r1, const T* r2, int n) noexcept
{
    const TapValues<T> t{{rm1[n - 1], rm1[n], rm1[n + 1]},
                         {r0[n - 1], r0[n], r0[n + 1]},
                         {r1[n - 1], r1[n], r1[n + 1], T{}},
                         r2[n + 1]};
    return apply<k_vertical_mask>(t);
}

// Fine rows 2y and 2y+1 for the coarse edges x0 <= x < x1 of row y. `r0` points at coarse node
// (0, y) (rm1, r1, r2 at rows y-1, y+1, y+2); `even` and `odd` at fine nodes (0, 2y) and
// (0, 2y+1). Fine row 2y interleaves even nodes (copies) with horizontal-edge nodes, fine row
// 2y+1 vertical-edge nodes (even x) with diagonal-edge nodes (odd x).
template <typename T>
void row_pair(const T* __restrict rm1, const T* __restrict r0, const T* __restrict r1,
              const T* __restrict r2, T* __restrict even, T* __restrict odd, int x0,
              int x1) noexcept
{
    for (int x = x0; x < x1; ++x)
    {
        const TapValues<T> t = read_taps(rm1, r0, r1, r2, x);
        even[2 * x] = t.z0[1];
        even[2 * x + 1] = apply<k_horizontal_mask>(t);
        odd[2 * x] = apply<k_vertical_mask>(t);
        odd[2 * x + 1] = apply<k_diagonal_mask>(t);
    }
}

// Fine row 2y alone (the last coarse row, which has no row y+1 edges above it).
template <typename T>
void even_row(const T* __restrict rm1, const T* __restrict r0, const T* __restrict r1,
              T* __restrict even, int x0, int x1) noexcept
{
    for (int x = x0; x < x1; ++x)
    {
        // Row y+2 does not exist here and the horizontal mask does not read it.
        const TapValues<T> t{{rm1[x - 1], rm1[x], rm1[x + 1]},
                             {r0[x - 1], r0[x], r0[x + 1]},
                             {r1[x - 1], r1[x], r1[x + 1], r1[x + 2]},
                             T{}};
        even[2 * x] = t.z0[1];
        even[2 * x + 1] = apply<k_horizontal_mask>(t);
    }
}

#if defined(__AVX512F__)
constexpr int k_vector_bytes = 64;
#elif defined(__AVX__)
constexpr int k_vector_bytes = 32;
#elif defined(__SSE2__)
constexpr int k_vector_bytes = 16;
#else
constexpr int k_vector_bytes = 0;  // no streaming stores: plain copies
#endif

// One non-temporal (streaming) store of a whole vector at `dst` (aligned) from `src`.
inline void stream_vector(float* dst, const float* src) noexcept
{
#if defined(__AVX512F__)
    _mm512_stream_ps(dst, _mm512_loadu_ps(src));
#elif defined(__AVX__)
    _mm256_stream_ps(dst, _mm256_loadu_ps(src));
#elif defined(__SSE2__)
    _mm_stream_ps(dst, _mm_loadu_ps(src));
#else
    *dst = *src;
#endif
}

inline void stream_vector(double* dst, const double* src) noexcept
{
#if defined(__AVX512F__)
    _mm512_stream_pd(dst, _mm512_loadu_pd(src));
#elif defined(__AVX__)
    _mm256_stream_pd(dst, _mm256_loadu_pd(src));
#elif defined(__SSE2__)
    _mm_stream_pd(dst, _mm_loadu_pd(src));
#else
    *dst = *src;
#endif
}

// Orders this thread's streaming stores before whatever follows (the twin and ghost passes, the
// end of the parallel region): they are weakly ordered.
inline void stream_fence() noexcept
{
#if defined(__SSE2__)
    _mm_sfence();
#endif
}

// Streams one fine row to `dst` while it is being computed into an L1-resident buffer: after
// each chunk the whole aligned vectors finished so far go out with streaming stores, so the
// stores drain to memory while the next chunk computes, and the output is written once without
// being read first (no read-for-ownership). The few nodes before the first aligned vector and
// after the last one are copied plainly at the end. Only copies: the values are those of the
// buffer, bit for bit.
template <typename T>
class RowStreamer
{
public:
    static constexpr int k_lanes = k_vector_bytes > 0 ? k_vector_bytes / int{sizeof(T)} : 1;

    RowStreamer(T* dst, const T* buf, int len) noexcept : dst_(dst), buf_(buf), len_(len)
    {
        // Without streaming stores (k_vector_bytes == 0) every node is a plain copy: head 0.
        constexpr std::uintptr_t k_align = k_vector_bytes > 0 ? k_vector_bytes : 1;
        const auto misalign = reinterpret_cast<std::uintptr_t>(dst) % k_align;
        head_ = misalign == 0 ? 0 : static_cast<int>((k_align - misalign) / sizeof(T));
        head_ = std::min(head_, len_);
        next_ = head_;
    }

    // buf[0 .. done) is final: stream every whole vector inside it.
    void advance(int done) noexcept
    {
        for (; next_ + k_lanes <= done; next_ += k_lanes)
            stream_vector(dst_ + next_, buf_ + next_);
    }

    // The whole row is in the buffer: the rest, and the head, go out with plain stores.
    void finish() noexcept
    {
        advance(len_);
        for (int i = 0; i < head_; ++i)
            dst_[i] = buf_[i];
        for (int i = next_; i < len_; ++i)
            dst_[i] = buf_[i];
    }

private:
    T* dst_;
    const T* buf_;
    int len_;
    int head_ = 0;
    int next_ = 0;
};

template <typename T>
struct RowJob
{
    const T* in = nullptr;
    T* out = nullptr;
    std::ptrdiff_t in_stride = 0;
    std::ptrdiff_t out_stride = 0;
    int n = 0;     // edges per coarse row (2W)
    int rows = 0;  // coarse rows (W+1)
};

// Coarse row y produces fine rows 2y and 2y+1 (the last coarse row only the even one), written
// straight into the output.
template <typename T>
inline void do_row(const RowJob<T>& job, int y) noexcept
{
    const T* r0 = job.in + static_cast<std::ptrdiff_t>(y) * job.in_stride;
    const T* rm1 = r0 - job.in_stride;
    const T* r1 = r0 + job.in_stride;
    T* even = job.out + static_cast<std::ptrdiff_t>(2 * y) * job.out_stride;
    const int n = job.n;
    if (y + 1 < job.rows)
    {
        const T* r2 = r1 + job.in_stride;
        T* odd = even + job.out_stride;
        row_pair(rm1, r0, r1, r2, even, odd, 0, n);
        odd[2 * n] = vertical_at_end(rm1, r0, r1, r2, n);
    }
    else
    {
        even_row(rm1, r0, r1, even, 0, n);
    }
    even[2 * n] = r0[n];
}

// The longest fine row: level k_max_level has nx = 2 * 2^k_max_level + 1 nodes.
constexpr int k_max_fine_row = 2 * (1 << core::k_max_level) + 1;

// Coarse edges per chunk of a streamed row: 256 fine nodes per fine row, small enough that the
// streaming stores of one chunk overlap the arithmetic of the next.
constexpr int k_stream_chunk = 128;

// As do_row, through a row buffer and streaming stores (RowStreamer).
template <typename T>
inline void do_row_streamed(const RowJob<T>& job, int y, T* __restrict buf_even,
                            T* __restrict buf_odd) noexcept
{
    const T* r0 = job.in + static_cast<std::ptrdiff_t>(y) * job.in_stride;
    const T* rm1 = r0 - job.in_stride;
    const T* r1 = r0 + job.in_stride;
    T* even = job.out + static_cast<std::ptrdiff_t>(2 * y) * job.out_stride;
    const int n = job.n;
    const int len = 2 * n + 1;
    RowStreamer<T> se(even, buf_even, len);
    if (y + 1 < job.rows)
    {
        const T* r2 = r1 + job.in_stride;
        RowStreamer<T> so(even + job.out_stride, buf_odd, len);
        for (int x0 = 0; x0 < n; x0 += k_stream_chunk)
        {
            const int x1 = std::min(n, x0 + k_stream_chunk);
            row_pair(rm1, r0, r1, r2, buf_even, buf_odd, x0, x1);
            se.advance(2 * x1);
            so.advance(2 * x1);
        }
        buf_odd[2 * n] = vertical_at_end(rm1, r0, r1, r2, n);
        so.finish();
    }
    else
    {
        for (int x0 = 0; x0 < n; x0 += k_stream_chunk)
        {
            const int x1 = std::min(n, x0 + k_stream_chunk);
            even_row(rm1, r0, r1, buf_even, x0, x1);
            se.advance(2 * x1);
        }
    }
    buf_even[2 * n] = r0[n];
    se.finish();
}

#if defined(__AVX512F__)
// The 512-bit vector operations of the direct streamed rows: double only (8 lanes). In float the
// row buffer is faster (see the file comment).
template <typename T>
struct Wide;

template <>
struct Wide<double>
{
    using V = __m512d;
    static constexpr int k_lanes = 8;
    static V load(const double* p) noexcept { return _mm512_loadu_pd(p); }
    static V add(V a, V b) noexcept { return _mm512_add_pd(a, b); }
    static V sub(V a, V b) noexcept { return _mm512_sub_pd(a, b); }
    static V mul(double w, V a) noexcept { return _mm512_mul_pd(_mm512_set1_pd(w), a); }
    // Lane j of the result is lane idx[j] of the 2L lanes a:b.
    static V pick(V a, __m512i idx, V b) noexcept { return _mm512_permutex2var_pd(a, idx, b); }
    static __m512i index(const int (&i)[k_lanes]) noexcept
    {
        return _mm512_set_epi64(i[7], i[6], i[5], i[4], i[3], i[2], i[1], i[0]);
    }
    static void stream(double* p, V v) noexcept { _mm512_stream_pd(p, v); }
    static void store_first(double* p, int count, V v) noexcept
    {
        _mm512_mask_storeu_pd(p, static_cast<__mmask8>((1u << count) - 1u), v);
    }
};

// `butterfly` on vectors: the same operations in the same order, lane by lane.
template <typename T>
struct WideTaps
{
    using V = typename Wide<T>::V;

    // TapValues of vectors (a struct of its own: GCC drops a vector type's attributes when it
    // is a template argument).
    struct Values
    {
        V m1[3];
        V z0[3];
        V p1[4];
        V p2;
    };

    static V butterfly(V a0, V a1, V b0, V b1, V c0, V c1, V c2, V c3) noexcept
    {
        using W = Wide<T>;
        return W::sub(W::add(W::mul(T(0.5), W::add(a0, a1)), W::mul(T(0.125), W::add(b0, b1))),
                      W::mul(T(0.0625), W::add(W::add(c0, c1), W::add(c2, c3))));
    }

    template <const Mask& M>
    static V apply(const Values& t) noexcept
    {
        return butterfly(tap<M[0].dx, M[0].dy>(t), tap<M[1].dx, M[1].dy>(t),
                         tap<M[2].dx, M[2].dy>(t), tap<M[3].dx, M[3].dy>(t),
                         tap<M[4].dx, M[4].dy>(t), tap<M[5].dx, M[5].dy>(t),
                         tap<M[6].dx, M[6].dy>(t), tap<M[7].dx, M[7].dy>(t));
    }
};

// One fine row written with streaming stores straight from the registers. The row's vectors
// R_0, R_1, ... (R_k = row[kL .. kL+L)) arrive in order; `s` is the row's misalignment in
// lanes, so the aligned vector k of the destination holds row[kL - s .. kL - s + L): the last s
// lanes of R_{k-1} and the first L - s of R_k, one two-source permute. The first L - s nodes
// (before the first aligned address) and the last s (after the last) are masked plain stores.
template <typename T>
class WideRow
{
public:
    using W = Wide<T>;
    using V = typename W::V;
    static constexpr int L = W::k_lanes;

    explicit WideRow(T* row) noexcept
        : row_(row), s_(static_cast<int>((reinterpret_cast<std::uintptr_t>(row) / sizeof(T)) % L))
    {
        int idx[L];
        for (int j = 0; j < L; ++j)
            idx[j] = j < s_ ? L - s_ + j : L + j - s_;
        shift_ = W::index(idx);
    }

    // R_0.
    void first(V r) noexcept
    {
        if (s_ == 0)
            W::stream(row_, r);
        else
            W::store_first(row_, L - s_, r);
        prev_ = r;
    }

    // R_k, for k = 1, 2, ... in order.
    void put(int k, V r) noexcept
    {
        W::stream(row_ + (k * L - s_), W::pick(prev_, shift_, r));
        prev_ = r;
    }

    // After R_{m-1}: its last s lanes, at row[mL - s .. mL).
    void finish(int m) noexcept
    {
        if (s_ > 0)
            W::store_first(row_ + (m * L - s_), s_, W::pick(prev_, shift_, prev_));
    }

private:
    T* row_;
    int s_;
    __m512i shift_;
    V prev_{};
};

// Fine rows 2y and 2y+1 of coarse row y < rows - 1, computed L coarse edges at a time and
// streamed from the registers (n must be a multiple of L). Same values as row_pair.
template <typename T>
void row_pair_streamed(const T* __restrict rm1, const T* __restrict r0, const T* __restrict r1,
                       const T* __restrict r2, T* even, T* odd, int n) noexcept
{
    using W = Wide<T>;
    using V = typename W::V;
    using X = WideTaps<T>;
    constexpr int L = W::k_lanes;
    int lo_idx[L];
    int hi_idx[L];
    for (int j = 0; j < L; ++j)
    {
        lo_idx[j] = (j % 2 == 0 ? 0 : L) + j / 2;
        hi_idx[j] = (j % 2 == 0 ? 0 : L) + L / 2 + j / 2;
    }
    const __m512i lo = W::index(lo_idx);
    const __m512i hi = W::index(hi_idx);
    WideRow<T> we(even);
    WideRow<T> wo(odd);
    const auto taps = [&](int x) noexcept -> typename X::Values
    {
        return {{W::load(rm1 + x - 1), W::load(rm1 + x), W::load(rm1 + x + 1)},
                {W::load(r0 + x - 1), W::load(r0 + x), W::load(r0 + x + 1)},
                {W::load(r1 + x - 1), W::load(r1 + x), W::load(r1 + x + 1), W::load(r1 + x + 2)},
                W::load(r2 + x + 1)};
    };
    {
        const typename X::Values t = taps(0);
        const V h = X::template apply<k_horizontal_mask>(t);
        const V v = X::template apply<k_vertical_mask>(t);
        const V d = X::template apply<k_diagonal_mask>(t);
        we.first(W::pick(t.z0[1], lo, h));
        we.put(1, W::pick(t.z0[1], hi, h));
        wo.first(W::pick(v, lo, d));
        wo.put(1, W::pick(v, hi, d));
    }
    for (int x = L, k = 2; x < n; x += L, k += 2)
    {
        const typename X::Values t = taps(x);
        const V h = X::template apply<k_horizontal_mask>(t);
        const V v = X::template apply<k_vertical_mask>(t);
        const V d = X::template apply<k_diagonal_mask>(t);
        we.put(k, W::pick(t.z0[1], lo, h));
        we.put(k + 1, W::pick(t.z0[1], hi, h));
        wo.put(k, W::pick(v, lo, d));
        wo.put(k + 1, W::pick(v, hi, d));
    }
    we.finish(2 * n / L);
    wo.finish(2 * n / L);
    even[2 * n] = r0[n];
    odd[2 * n] = vertical_at_end(rm1, r0, r1, r2, n);
}
#endif

// Below this many fine nodes per thread, waking a second thread costs more than it saves (a
// level-6 step takes ~50 us on one core); the result is the same either way.
constexpr long k_min_nodes_per_thread = 1L << 16;

// Output planes at least this large are written with streaming stores. Smaller ones (up to
// level 9) stay in the last-level cache between a refinement and its use, which streaming
// would throw away; a level-10 plane (8.4 MB in float) does not fit there beside its input and
// the other two planes (bench/subdiv: 25 MB of output against a 32 MB L3).
constexpr std::size_t k_stream_bytes = std::size_t{6} << 20;

// Coarse rows y0 .. y1-1 on the calling thread.
template <typename T>
void rows_serial(const RowJob<T>& job, int y0, int y1, bool streamed) noexcept
{
    if (!streamed)
    {
        for (int y = y0; y < y1; ++y)
            do_row(job, y);
        return;
    }
    alignas(64) T buf_even[k_max_fine_row];
    alignas(64) T buf_odd[k_max_fine_row];
    for (int y = y0; y < y1; ++y)
    {
#if defined(__AVX512F__)
        if constexpr (std::is_same_v<T, double>)
        {
            if (y + 1 < job.rows && job.n % Wide<T>::k_lanes == 0)
            {
                const T* r0 = job.in + static_cast<std::ptrdiff_t>(y) * job.in_stride;
                T* even = job.out + static_cast<std::ptrdiff_t>(2 * y) * job.out_stride;
                row_pair_streamed(r0 - job.in_stride, r0, r0 + job.in_stride,
                                  r0 + 2 * job.in_stride, even, even + job.out_stride, job.n);
                continue;
            }
        }
#endif
        do_row_streamed(job, y, buf_even, buf_odd);
    }
    stream_fence();
}

/// The threads a refinement of `rows` coarse rows of `n` + 1 nodes uses when `threads` are
/// asked: at most one per k_min_nodes_per_thread fine nodes, at least one.
int threads_for(long rows, long n, int threads) noexcept
{
    const long fine_nodes = 4L * rows * (n + 1);
    return std::max(1,
                    static_cast<int>(std::min<long>(threads, fine_nodes / k_min_nodes_per_thread)));
}

template <typename T>
void run_rows(const RowJob<T>& job, int threads) noexcept
{
    const long fine_nodes = 4L * job.rows * (job.n + 1);
    const bool streamed = static_cast<std::size_t>(fine_nodes) * sizeof(T) >= k_stream_bytes;
    threads = threads_for(job.rows, job.n, threads);
    if (threads <= 1)
    {
        rows_serial(job, 0, job.rows, streamed);
        return;
    }
    // Static partition: a contiguous block of rows per thread, no reduction, so the output is
    // the same for any thread count.
#pragma omp parallel num_threads(threads)
    {
        const long t = omp_get_thread_num();
        const long nt = omp_get_num_threads();
        rows_serial(job, static_cast<int>(job.rows * t / nt),
                    static_cast<int>(job.rows * (t + 1) / nt), streamed);
    }
}

}  // namespace

int refine_threads(const ConvolutionPlan& plan, int threads) noexcept
{
    return threads_for(plan.coarse_grid().ny(), 2L * plan.coarse_grid().w(), threads);
}

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
    job.n = 2 * plan.coarse_grid().w();
    job.rows = plan.coarse_grid().ny();
    PLIANT_ASSERT(2 * job.n + 1 <= k_max_fine_row, "refine: fine row longer than the row buffer");
    run_rows(job, threads);

    // No sync_twins: the kernel writes every twin with the bits of its canonical node (the
    // gluing maps only swap the members of commutative pairs in `butterfly`'s grouping, and
    // the input's twins are equal), which RefinedTwinsAgreeAndGhostsAreFilled checks at levels
    // 1..9. At level 10 the copy cost 0.03 ms per plane once the output had left the cache.
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
