// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// bench_subdiv: butterfly refinement of positions (three planes) level n -> n+1 for n = 6..9,
// against OpenMesh's ModifiedButterflyT on the same surface, a STREAM-style copy of the same
// number of bytes and a copy that keeps STREAM's run rule, all in one run (ratios measured
// together; TESTING-NOTES.md: timings on a shared VM vary by +-20 %, so every figure is a median
// of repeated runs).
//
//   bench_subdiv [--quick] [--min-time SECONDS] [--json FILE] [--csv FILE]
//
// --quick: levels 6->7 .. 8->9, 0.05 s per figure, one OpenMesh run, STREAM-rule arrays of
// 64 MiB and a 256 MiB cold rotation (the rule is then not met, and the output says so);
// --json/--csv: one row per figure (bench/common/bench_report.h), sized by the output surface
// vertices.
//
// Columns: median time per refinement; output vertices per second (unique surface vertices of
// the fine level, 2(2W)^2+2, the same count OpenMesh produces); effective bandwidth = bytes of
// the in-range coarse planes read + fine planes written, divided by the time; the ratio to
// OpenMesh per output vertex; the fraction of the single-thread copy bandwidth ("x copy", the
// same-bytes copy) and of the single-thread STREAM-rule copy ("x rule copy").
//
// Why two copies (docs/subdivision.md, "Against a copy that keeps STREAM's run rule"): the
// same-bytes copy's two arrays (15.75 MB each at 9->10) stay largely in the development VM's L3,
// so it measures cache bandwidth, while the refinement's 25 MB output at 9->10 goes to memory.
// STREAM's run rule asks for arrays of at least 4x all the caches together, so the "STREAM-rule
// copy" uses two such arrays (sizes from sysconf; --quick keeps them small and says that the rule
// is not met). The "cold" rows refine the same surface while rotating through enough input/output
// field sets (> 4x the caches in all) that each refinement finds neither its input nor its output
// in cache, as one step of a pipeline does; the warm rows refine one set again and again.
#include <pliant/subdiv/refine.h>

#include <omp.h>
#include <unistd.h>

#include "bench_report.h"
#include "grid_shapes.h"
#include "reference_openmesh.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace
{

using namespace pliant;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Median of at least `min_reps` runs of `fn`, running until `min_time` seconds have passed.
template <typename Fn>
double median_time(Fn&& fn, double min_time, int min_reps, int max_reps = 1000)
{
    std::vector<double> t;
    const auto start = Clock::now();
    while (static_cast<int>(t.size()) < max_reps &&
           (static_cast<int>(t.size()) < min_reps || seconds_since(start) < min_time))
    {
        const auto t0 = Clock::now();
        fn();
        t.push_back(seconds_since(t0));
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

template <typename T>
core::Vec3Field<T> convert(const core::Vec3Field<double>& p, const core::TetraGrid& g, int ghost)
{
    core::Vec3Field<T> out{core::Field<T>(g, ghost), core::Field<T>(g, ghost),
                           core::Field<T>(g, ghost)};
    for (std::size_t c = 0; c < 3; ++c)
    {
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
                out[c].at(x, y) = static_cast<T>(p[c].at(x, y));
        core::fill_ghosts(g, out[c]);
    }
    return out;
}

template <typename T>
bool same_bits(const core::Vec3Field<T>& a, const core::Vec3Field<T>& b)
{
    for (std::size_t c = 0; c < 3; ++c)
        if (std::memcmp(a[c].padded().data(), b[c].padded().data(), a[c].padded().size_bytes()))
            return false;
    return true;
}

struct Row
{
    std::string what;
    double seconds = 0;
    double bytes = 0;
};

constexpr double k_mib = 1024.0 * 1024.0;

// The caches a copy could run from, summed as STREAM's run rule counts them: the L3 once (it is
// shared; in a VM, CPUID may report the whole host socket's L3, and then the rule asks for more
// than the VM's cores can use, which only makes it safer) plus each core's L2 and L1d.
struct Caches
{
    double l1d = 0;
    double l2 = 0;
    double l3 = 0;
    int cores = 1;
    bool l3_assumed = false;  // sysconf reported no L3: 64 MiB assumed

    [[nodiscard]] double total() const { return l3 + cores * (l2 + l1d); }
};

Caches query_caches()
{
    const auto bytes = [](int name) { return static_cast<double>(std::max(0L, sysconf(name))); };
    Caches c;
    c.l1d = bytes(_SC_LEVEL1_DCACHE_SIZE);
    c.l2 = bytes(_SC_LEVEL2_CACHE_SIZE);
    c.l3 = bytes(_SC_LEVEL3_CACHE_SIZE);
    c.cores = static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
    if (c.l3 == 0)
    {
        c.l3 = 64 * k_mib;
        c.l3_assumed = true;
    }
    return c;
}

// Bytes the STREAM-rule arrays and the cold rotation may take: at most 4 GiB per array and an
// eighth of the memory, so that the run stays clear of swapping on a small or shared machine.
double memory_cap()
{
    const double phys =
        static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGESIZE));
    const double cap = 4096 * k_mib;
    return phys > 0 ? std::min(cap, phys / 8) : cap;
}

// dst[i] = src[i] on one thread. GCC turns the loop into a library call (memmove, as it does
// STREAM's copy loop with memcpy), and glibc copies with non-temporal stores above its threshold
// (x86_non_temporal_threshold, 127 MiB on the development VM: `ld.so --list-tunables`), so a
// STREAM-rule copy moves no write-allocate bytes, which is what STREAM's byte count assumes.
void copy_floats(float* __restrict d, const float* __restrict s, std::size_t n)
{
    for (std::size_t i = 0; i < n; ++i)
        d[i] = s[i];
}

// The STREAM-rule copy on `threads` threads: each thread copies one contiguous part (STREAM's
// static schedule) with the same loop, so one and two threads use the same kind of stores.
void copy_parts(std::vector<float>& dst, const std::vector<float>& src, int threads)
{
    const std::size_t n = dst.size();
    if (threads == 1)
    {
        copy_floats(dst.data(), src.data(), n);
        return;
    }
#pragma omp parallel num_threads(threads)
    {
        const auto t = static_cast<std::size_t>(omp_get_thread_num());
        const auto nt = static_cast<std::size_t>(omp_get_num_threads());
        const std::size_t begin = n * t / nt;
        const std::size_t end = n * (t + 1) / nt;
        copy_floats(dst.data() + begin, src.data() + begin, end - begin);
    }
}

}  // namespace

int main(int argc, char** argv)
{
    bench::Report report("subdiv");
    if (!report.parse_args(argc, argv))
        return 2;
    const bool quick = report.quick();
    double min_time = 0.5;
    for (int i = 1; i < argc; ++i)
    {
        const std::string a = argv[i];
        if (a == "--min-time" && i + 1 < argc)
            min_time = std::stod(argv[++i]);
        else
        {
            std::fprintf(stderr,
                         "usage: bench_subdiv [--quick] [--min-time SECONDS] [--json FILE] "
                         "[--csv FILE]\n");
            return 2;
        }
    }
    if (quick)
        min_time = 0.05;

#if defined(PLIANT_NATIVE_ISA)
    const char* isa = "-march=native";
#else
    const char* isa = "portable (no -march)";
#endif
#if defined(__AVX512F__)
    const char* vec = "AVX-512";
#elif defined(__AVX2__)
    const char* vec = "AVX2";
#else
    const char* vec = "SSE2";
#endif
    report.meta("isa", isa);
    report.meta("vector", vec);
    report.meta("omp_max_threads", std::to_string(omp_get_max_threads()));
    std::printf(
        "bench_subdiv: butterfly refinement of positions (3 planes), %s (%s), "
        "OpenMP max threads %d, min time %.2f s per figure\n",
        isa, vec, omp_get_max_threads(), min_time);

    // STREAM's run rule: each array at least 4x all the caches together. --quick keeps the arrays
    // (and the cold rotation) small so that the smoke run stays fast, and says so.
    const Caches caches = query_caches();
    const double rule_bytes = 4 * caches.total();
    const double cap = quick ? 64 * k_mib : memory_cap();
    const double array_bytes = std::min(rule_bytes, cap);
    const bool rule_met = array_bytes >= rule_bytes;
    // Whole cache lines (16 floats), rounded up so that the rule is met when not capped.
    const std::size_t rule_n =
        (static_cast<std::size_t>(std::ceil(array_bytes / sizeof(float))) + 15) / 16 * 16;
    const double rule_copy_bytes = 2.0 * static_cast<double>(rule_n) * sizeof(float);
    const double cold_budget = std::min(rule_bytes, quick ? 256 * k_mib : cap);
    std::printf(
        "caches: L3 %.1f MiB%s + %d x (L2 %.2f + L1d %.3f) MiB = %.1f MiB; STREAM rule: "
        "each array >= %.1f MiB\n",
        caches.l3 / k_mib, caches.l3_assumed ? " (none reported: assumed)" : "", caches.cores,
        caches.l2 / k_mib, caches.l1d / k_mib, caches.total() / k_mib, rule_bytes / k_mib);
    std::printf(
        "STREAM-rule copy: 2 arrays of %.1f MiB: rule %s; cold rows rotate through "
        "input/output sets of >= %.1f MiB in all (%s 4x the caches)\n",
        static_cast<double>(rule_n) * sizeof(float) / k_mib,
        rule_met ? "met" : (quick ? "NOT met (--quick)" : "NOT met (capped by memory)"),
        cold_budget / k_mib, cold_budget >= rule_bytes ? ">=" : "NOT >=");
    report.meta("cache_bytes_total", std::to_string(static_cast<long long>(caches.total())));
    report.meta("stream_rule_array_bytes", std::to_string(rule_n * sizeof(float)));
    report.meta("stream_rule_met", rule_met ? "yes" : "no");
    // Allocated (and first touched) once, outside every timed loop; 2 x array_bytes of memory.
    std::vector<float> rule_src(rule_n, 1.0f);
    std::vector<float> rule_dst(rule_n, 0.0f);

    std::printf("%-5s %-28s %10s %12s %9s %10s %9s %11s\n", "step", "variant", "median ms",
                "Mvert/s out", "GB/s", "x OpenMesh", "x copy", "x rule copy");

    for (int level = 6; level <= (quick ? 8 : 9); ++level)
    {
        const subdiv::ConvolutionPlan plan = subdiv::ConvolutionPlan::create(level).value();
        const core::TetraGrid& g = plan.coarse_grid();
        const core::TetraGrid& fg = plan.fine_grid();
        const auto sphere = test::sphere_positions(g, 1);
        const double out_vertices = static_cast<double>(fg.unique_count());
        const double nodes_in = static_cast<double>(g.node_count());
        const double nodes_out = static_cast<double>(fg.node_count());

        const auto in_f = convert<float>(sphere, g, 1);
        const auto in_d = convert<double>(sphere, g, 1);
        core::Vec3Field<float> out_f{core::Field<float>(fg, 1), core::Field<float>(fg, 1),
                                     core::Field<float>(fg, 1)};
        core::Vec3Field<float> out_f2 = out_f;
        core::Vec3Field<double> out_d{core::Field<double>(fg, 1), core::Field<double>(fg, 1),
                                      core::Field<double>(fg, 1)};

        const double bytes_f = 3.0 * (nodes_in + nodes_out) * sizeof(float);
        const double bytes_d = 3.0 * (nodes_in + nodes_out) * sizeof(double);

        std::vector<Row> rows;
        rows.push_back({"refine float, 1 thread",
                        median_time([&] { subdiv::refine(plan, in_f, out_f, 1); }, min_time, 5),
                        bytes_f});
        rows.push_back({"refine float, 2 threads",
                        median_time([&] { subdiv::refine(plan, in_f, out_f2, 2); }, min_time, 5),
                        bytes_f});
        rows.push_back({"refine double, 1 thread",
                        median_time([&] { subdiv::refine(plan, in_d, out_d, 1); }, min_time, 5),
                        bytes_d});
        const bool identical = same_bits(out_f, out_f2);

        // Cold: rotate through `sets` copies of the input and output, > 4x the caches in all, so
        // that when a set comes round again its lines have long been evicted: each refinement
        // reads its input from memory and writes an output that is not in cache, as one step of
        // a pipeline that refines a fresh field does. The copies are made (and their pages
        // touched) here, outside the timed loop; every set is timed at least once. On the
        // development VM the first touch of a page costs about 3 s per GiB, so this takes most of
        // the run's time; keeping freed memory in the process (mallopt) would save it, but would
        // also hand OpenMesh pages that are already mapped and change its figure several-fold
        // (docs/subdivision.md), so the allocator is left as it is.
        double set_bytes = 0;
        for (std::size_t c = 0; c < 3; ++c)
            set_bytes +=
                static_cast<double>(in_f[c].padded().size_bytes() + out_f[c].padded().size_bytes());
        const int sets = std::max(2, static_cast<int>(std::ceil(cold_budget / set_bytes)));
        bool cold_identical = true;
        {
            std::vector<core::Vec3Field<float>> cold_in(static_cast<std::size_t>(sets), in_f);
            // Zeroed outputs, so that the comparison below sees what the cold runs wrote.
            const core::Vec3Field<float> zero{core::Field<float>(fg, 1), core::Field<float>(fg, 1),
                                              core::Field<float>(fg, 1)};
            std::vector<core::Vec3Field<float>> cold_out(static_cast<std::size_t>(sets), zero);
            std::size_t k = 0;
            const auto cold = [&](int threads)
            {
                return median_time(
                    [&]
                    {
                        subdiv::refine(plan, cold_in[k], cold_out[k], threads);
                        k = (k + 1) % cold_in.size();
                    },
                    min_time, std::max(5, sets), std::max(1000, sets));
            };
            rows.push_back({"refine float cold, 1 thread", cold(1), bytes_f});
            rows.push_back({"refine float cold, 2 threads", cold(2), bytes_f});
            for (const auto& o : cold_out)
                cold_identical = cold_identical && same_bits(o, out_f);
        }
        std::printf("%d->%d cold rows: %d input/output sets in rotation, %.1f MiB in all\n", level,
                    level + 1, sets, sets * set_bytes / k_mib);
        report.add("refine float cold 1 thread", level + 1, out_vertices, "vertices",
                   "rotation_bytes", sets * set_bytes, "B");

        // STREAM "copy" of the same bytes as the float refinement: reads half, writes half.
        const auto copy_n = static_cast<std::size_t>(bytes_f / 2 / sizeof(float));
        std::vector<float> src(copy_n, 1.0f);
        std::vector<float> dst(copy_n, 0.0f);
        const double copy1 = median_time(
            [&]
            {
                float* __restrict d = dst.data();
                const float* __restrict s = src.data();
                for (std::size_t i = 0; i < copy_n; ++i)
                    d[i] = s[i];
            },
            min_time, 5);
        const double copy2 = median_time(
            [&]
            {
                float* d = dst.data();
                const float* s = src.data();
                const auto n = static_cast<std::ptrdiff_t>(copy_n);
#pragma omp parallel for schedule(static) num_threads(2)
                for (std::ptrdiff_t i = 0; i < n; ++i)
                    d[i] = s[i];
            },
            min_time, 5);
        rows.push_back({"STREAM copy, 1 thread", copy1, bytes_f});
        rows.push_back({"STREAM copy, 2 threads", copy2, bytes_f});

        // The STREAM-rule copy, measured at every level next to the refinement it is compared
        // with (memory bandwidth on a shared VM drifts within minutes).
        const double rule1 = median_time([&] { copy_parts(rule_dst, rule_src, 1); }, min_time, 5);
        const double rule2 = median_time([&] { copy_parts(rule_dst, rule_src, 2); }, min_time, 5);
        rows.push_back({"STREAM-rule copy, 1 thread", rule1, rule_copy_bytes});
        rows.push_back({"STREAM-rule copy, 2 threads", rule2, rule_copy_bytes});

        // OpenMesh on the same surface (double positions); the copy of the mesh is not timed.
        const test::OmMesh base = test::to_openmesh(g, sphere);
        const int om_reps = quick ? 1 : (level <= 7 ? 5 : (level == 8 ? 3 : 1));
        std::vector<double> om_times;
        for (int r = 0; r < om_reps; ++r)
        {
            test::OmMesh m = base;
            const auto t0 = Clock::now();
            test::openmesh_butterfly(m, 1);
            om_times.push_back(seconds_since(t0));
        }
        std::sort(om_times.begin(), om_times.end());
        const double om_only = om_times[om_times.size() / 2];
        rows.push_back({"OpenMesh ModifiedButterflyT", om_only, 0.0});

        const double om_rate = out_vertices / om_only;
        const double copy_bw = bytes_f / copy1;
        const double rule_bw = rule_copy_bytes / rule1;
        for (const Row& r : rows)
        {
            const bool is_copy = r.what.rfind("STREAM", 0) == 0;
            const double rate = out_vertices / r.seconds;
            std::printf("%d->%d %-28s %10.3f %12.1f %9.2f %10s %9.2f %11.2f\n", level, level + 1,
                        r.what.c_str(), r.seconds * 1e3, is_copy ? 0.0 : rate / 1e6,
                        r.bytes > 0 ? r.bytes / r.seconds / 1e9 : 0.0,
                        is_copy || r.bytes == 0 ? "-" : std::to_string(rate / om_rate).c_str(),
                        r.bytes > 0 ? (r.bytes / r.seconds) / copy_bw : 0.0,
                        r.bytes > 0 ? (r.bytes / r.seconds) / rule_bw : 0.0);
        }
        for (const Row& r : rows)
        {
            const bool is_copy = r.what.rfind("STREAM", 0) == 0;
            std::string c = r.what;  // "refine float, 1 thread" -> "refine float 1 thread"
            if (const auto comma = c.find(", "); comma != std::string::npos)
                c.erase(comma, 1);
            const double rate = out_vertices / r.seconds;
            report.add(c, level + 1, out_vertices, "vertices", "ms", r.seconds * 1e3, "ms");
            if (!is_copy)
            {
                report.add(c, level + 1, out_vertices, "vertices", "output_vertices_per_s", rate,
                           "1/s");
                report.add(c, level + 1, out_vertices, "vertices", "x_openmesh", rate / om_rate,
                           "1");
            }
            if (r.bytes > 0)
            {
                report.add(c, level + 1, out_vertices, "vertices", "bandwidth", r.bytes / r.seconds,
                           "B/s");
                report.add(c, level + 1, out_vertices, "vertices", "x_copy_1_thread",
                           (r.bytes / r.seconds) / copy_bw, "1");
                report.add(c, level + 1, out_vertices, "vertices", "x_stream_rule_copy_1_thread",
                           (r.bytes / r.seconds) / rule_bw, "1");
            }
        }
        std::printf("%d->%d 1 vs 2 threads bit-identical: %s\n", level, level + 1,
                    identical ? "yes" : "NO");
        std::printf("%d->%d cold output bit-identical to warm: %s\n", level, level + 1,
                    cold_identical ? "yes" : "NO");
        if (!identical || !cold_identical)
            return 1;
    }
    return report.write() ? 0 : 1;
}
