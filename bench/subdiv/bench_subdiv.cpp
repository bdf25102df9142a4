// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// bench_subdiv: butterfly refinement of positions (three planes) level n -> n+1 for n = 6..9,
// against OpenMesh's ModifiedButterflyT on the same surface and a STREAM-style copy of the same
// number of bytes, all in one run (ratios measured together; TESTING-NOTES.md: timings on a
// shared VM vary by +-20 %, so every figure is a median of repeated runs).
//
//   bench_subdiv [--quick] [--min-time SECONDS] [--json FILE] [--csv FILE]
//
// --quick: levels 6->7 .. 8->9, 0.05 s per figure, one OpenMesh run; --json/--csv: one row per
// figure (bench/common/bench_report.h), sized by the output surface vertices.
//
// Columns: median time per refinement; output vertices per second (unique surface vertices of
// the fine level, 2(2W)^2+2, the same count OpenMesh produces); effective bandwidth = bytes of
// the in-range coarse planes read + fine planes written, divided by the time; the ratio to
// OpenMesh per output vertex; the fraction of the single-thread copy bandwidth.
#include <pliant/subdiv/refine.h>

#include <omp.h>

#include "bench_report.h"
#include "grid_shapes.h"
#include "reference_openmesh.h"

#include <algorithm>
#include <chrono>
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
    std::printf("%-5s %-26s %10s %12s %9s %10s %9s\n", "step", "variant", "median ms",
                "Mvert/s out", "GB/s", "x OpenMesh", "x copy");

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
        for (const Row& r : rows)
        {
            const bool is_copy = r.what.rfind("STREAM", 0) == 0;
            const double rate = out_vertices / r.seconds;
            std::printf("%d->%d %-26s %10.3f %12.1f %9.2f %10s %9.2f\n", level, level + 1,
                        r.what.c_str(), r.seconds * 1e3, is_copy ? 0.0 : rate / 1e6,
                        r.bytes > 0 ? r.bytes / r.seconds / 1e9 : 0.0,
                        is_copy || r.bytes == 0 ? "-" : std::to_string(rate / om_rate).c_str(),
                        r.bytes > 0 ? (r.bytes / r.seconds) / copy_bw : 0.0);
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
            }
        }
        std::printf("%d->%d 1 vs 2 threads bit-identical: %s\n", level, level + 1,
                    identical ? "yes" : "NO");
        if (!identical)
            return 1;
    }
    return report.write() ? 0 : 1;
}
