// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Membrane benchmark (issue 5, docs/physics.md "Performance"). Prints a table and CSV lines:
//   triad,<threads>,<GB/s>
//   step,<level>,<threads>,<grid nodes>,<ns per node-step>,<node-steps/s>,<GB/s effective>
//   realtime,<level>,<threads>,<simulated s>,<wall s>,<ratio>,<steps>
//   largest real-time level, <threads> thread(s): <level> (ran the whole scenario in real time)
// Usage: pliant_bench_sim [max_level=10] [realtime_seconds=4] [min_level=6]
//                         [kernel] [gnomonic] [step] [mixed] [--quick] [--json FILE]
//                         [--csv FILE]
//   "kernel" runs only the step timing, 1 thread, 10 steps per level (for callgrind, whose
//   instruction counts are exactly repeatable on a shared machine).
//   The sphere is the equal-area grid (core::SphereMap::EqualArea, the CLI's built-in sphere);
//   "gnomonic" runs everything on the gnomonic one instead, for comparison.
//   The scenario's force is sampled once per frame and held linearly between frames
//   (sim::ForceHold::Linear, as `pliant simulate` does); "step" holds it constant
//   over each frame instead (the zero-order hold every run used until 2026-12-02).
//   "mixed" runs every step in mixed precision (sim::Precision::Mixed, docs/physics.md §9).
//   --help prints the usage (k_usage); an unknown option or a level out of range exits 2.
// The moving force slides from (1,0,0) to (0,0,1) along the great circle over 2 s (0.785 m/s),
// staying on the surface. (Until 2026-12-02 it slid along the chord: from 0.45 s to 1.55 s the
// point was more than its 0.2 m radius inside the sphere and the whole force fell on the nearest
// node, a singular load that forced ever smaller steps as the level grew.)
//   A real-time run simulates the scenario's 2 s, or stops at realtime_seconds of wall time.
//   --quick: levels 5..8, real-time runs cut at 0.6 s, 3 repetitions; --json/--csv: the same
//   figures as rows (bench/common/bench_report.h) plus the CPU share of the real-time scenario:
//   process CPU seconds per simulated second (the fraction of one core the simulation needs to keep
//   up with real time; load-independent where wall time is not), and the same estimated from the
//   fixed-step time per step times the adaptive run's steps per simulated second.
// Timings are medians of repeated runs; the machine is shared, so compare ratios within a run.

#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <omp.h>
#include <time.h>

#include "bench_report.h"
#include "grid_shapes.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

namespace
{

using namespace pliant;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// CPU time of the whole process (every thread), s.
double process_cpu_seconds()
{
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// STREAM triad a = b + s c over arrays well outside the last-level cache (3 x 64 MiB).
double triad_gbs(int threads)
{
    const std::size_t n = std::size_t{1} << 23;
    std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
    const auto len = static_cast<std::ptrdiff_t>(n);
    std::vector<double> times;
    for (int rep = 0; rep < 7; ++rep)
    {
        const auto t0 = Clock::now();
        double* __restrict pa = a.data();
        const double* __restrict pb = b.data();
        const double* __restrict pc = c.data();
#pragma omp parallel for schedule(static) num_threads(threads)
        for (std::ptrdiff_t i = 0; i < len; ++i)
            pa[i] = pb[i] + 3.0 * pc[i];
        times.push_back(seconds_since(t0));
    }
    std::printf("%s", a[n / 2] == 7.0 ? "" : "?");  // keep the loop
    return 3.0 * 8.0 * static_cast<double>(n) / median(times) / 1e9;
}

sim::MembraneSettings bench_material()
{
    sim::MembraneSettings s;
    s.T = 1.0;
    s.rho = 1.0;
    s.beta = 0.5;
    s.k_f = 1.0;
    s.rtol = 1e-4;
    s.atol = 1e-8;
    return s;
}

// Doubles moved to and from memory per node per step by the integrator's fused row pipeline
// (docs/physics.md §8): it reads u, v, three weights, 1/m and the force plane once and writes
// u_new and v_new once (plus their write-allocate reads); the slopes stay in per-thread ring
// rows: 7 + 2 + 2 = 11 doubles. (The stage-by-stage pass it replaced moved 64.) In mixed
// precision the weights and 1/m are read as floats: 2 + 2 + 1 + 2 + 2 = 9.
constexpr double k_doubles_per_node_step = 11.0;
constexpr double k_doubles_per_node_step_mixed = 9.0;

// The benchmark scenario (scenes/bench.toml) lasts 2 s, the finger's slide: 120 frames of 1/60 s.
// (Until 2026-12-02 a real-time run went on for its whole wall-time window, past the scenario's
// end with the finger resting, into the focusing of the first waves at the antipode.)
constexpr int k_scenario_frames = 120;

constexpr const char* k_usage =
    "usage: pliant_bench_sim [max_level] [realtime_seconds] [min_level] [kernel] [gnomonic]\n"
    "                        [step] [mixed] [--quick] [--json FILE] [--csv FILE]\n"
    "RKF45 ns per node-step at levels min_level..max_level on 1 and 2 threads, a STREAM triad in\n"
    "the same run, and the largest level that runs the benchmark scenario (a point force sliding\n"
    "over the unit sphere for 2 s) in real time. Numbers are positional, in this order.\n"
    "  max_level         finest grid level, 1..10 (default 10; --quick: 8)\n"
    "  realtime_seconds  wall-time cap of each real-time run, s, >= 0 (default 4; --quick: 0.6);\n"
    "                    a run simulates the scenario's 2 s or stops at the cap\n"
    "  min_level         coarsest grid level, 1..max_level (default 6, --quick: 5, or max_level\n"
    "                    where lower)\n"
    "  kernel            only the step timing, 1 thread, 10 steps per level (for callgrind)\n"
    "  gnomonic          the gnomonic sphere instead of the equal-area one\n"
    "  step              hold the force constant over each frame instead of linearly\n"
    "  mixed             mixed precision: float increments over the double state\n"
    "  --quick           levels 5..8, real-time runs cut at 0.6 s, 3 repetitions\n"
    "  --json FILE, --csv FILE\n"
    "                    also write the figures as rows (bench/common/bench_report.h)\n"
    "  -h, --help        print this and exit\n";

}  // namespace

int main(int argc, char** argv)
{
    bench::Report report("sim");
    const bench::Usage usage(argv[0], k_usage);
    if (const auto status = report.parse_args(argc, argv, usage))
        return *status;
    const bool quick = report.quick();
    bool kernel_only = false;
    core::SphereMap sphere_map = core::SphereMap::EqualArea;
    sim::ForceHold hold = sim::ForceHold::Linear;
    sim::Precision precision = sim::Precision::Double;
    // The positional numbers in order (max_level, realtime_seconds, min_level); the words may
    // stand anywhere.
    std::vector<const char*> numbers;
    for (int i = 1; i < argc; ++i)
    {
        const std::string_view a = argv[i];
        if (a == "kernel")
            kernel_only = true;
        else if (a == "gnomonic")
            sphere_map = core::SphereMap::Gnomonic;
        else if (a == sim::to_string(sim::ForceHold::Step))
            hold = sim::ForceHold::Step;
        else if (a == sim::to_string(sim::Precision::Mixed))
        {
            precision = sim::Precision::Mixed;
            report.set_suite("mixed");  // `pliant bench mixed`
        }
        else if (numbers.size() == 3 || (a.starts_with('-') && !bench::parse_number(a)))
            return usage.unexpected(a);
        else
            numbers.push_back(argv[i]);
    }
    int max_level = quick ? 8 : 10;
    if (!numbers.empty())
    {
        const auto level =
            usage.int_in("max_level", numbers[0], core::k_min_level, core::k_max_level);
        if (!level)
            return 2;
        max_level = *level;
    }
    // Wall-time cap of a real-time run, which otherwise runs the whole scenario.
    double rt_seconds = quick ? 0.6 : 4.0;
    if (numbers.size() > 1)
    {
        const auto seconds = usage.number_in("realtime_seconds", numbers[1], 0.0,
                                             std::numeric_limits<double>::infinity());
        if (!seconds)
            return 2;
        rt_seconds = *seconds;
    }
    // The default coarsest level stays at or below max_level.
    int min_level = std::min(quick ? 5 : 6, max_level);
    if (numbers.size() > 2)
    {
        const auto level = usage.int_in("min_level", numbers[2], core::k_min_level, max_level);
        if (!level)
            return 2;
        min_level = *level;
    }
    const int reps = quick ? 3 : 5;
    const double node_steps_per_rep = quick ? 3e6 : 3e7;
    const double rep_cap_s = quick ? 0.4 : 4.0;  // wall seconds per repetition at most
#if defined(PLIANT_NATIVE_ISA)
    std::printf("build: -march=native, -ffp-contract=off, double state\n");
    report.meta("isa", "-march=native");
#else
    std::printf("build: portable ISA, -ffp-contract=off, double state\n");
    report.meta("isa", "portable");
#endif
    report.meta("material",
                "unit sphere, T=1 N/m, rho=1 kg/m2, beta=0.5 1/s, k_f=1 1/s2, "
                "rtol=1e-4, one point force sliding on the surface, frames of 1/60 s");
    report.meta("sphere_map", std::string(core::to_string(sphere_map)));
    std::printf("sphere: %s grid\n", std::string(core::to_string(sphere_map)).c_str());
    const std::string precision_name(sim::to_string(precision));
    report.meta("precision", precision_name);
    std::printf("precision of full steps: %s\n", precision_name.c_str());
    const double bytes_per_node_step =
        8.0 * (precision == sim::Precision::Mixed ? k_doubles_per_node_step_mixed
                                                  : k_doubles_per_node_step);
    const std::string hold_name(sim::to_string(hold));
    report.meta("force_hold", hold_name);
    std::printf("force hold between frames: %s\n", hold_name.c_str());
    if (!kernel_only)
        for (const int threads : {1, 2})
        {
            const double gbs = triad_gbs(threads);
            std::printf("triad,%d,%.2f\n", threads, gbs);
            report.add(std::to_string(threads) + (threads == 1 ? " thread" : " threads"), -1,
                       threads, "threads", "triad_bandwidth", gbs * 1e9, "B/s");
        }
    // ms per fixed step at 1 thread, per level (for the CPU share estimated from step time).
    std::vector<double> ms_per_step_1(core::k_max_level + 1, 0.0);

    for (int level = min_level; level <= max_level; ++level)
    {
        const core::TetraGrid grid = core::TetraGrid::create(level).value();
        for (const int threads : {1, 2})
        {
            if (kernel_only && threads > 1)
                continue;
            sim::MembraneSettings set = bench_material();
            set.fixed_step = true;
            set.fixed_dt = 1e-4;
            set.threads = threads;
            set.precision = precision;
            sim::MembraneModel model =
                sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0, 0, sphere_map), set)
                    .value();
            sim::MembraneState state = sim::MembraneState::at_rest(grid);
            sim::Rkf45Workspace ws(model, threads);
            const sim::Force force{-1, {1.0, 0.0, 0.0}, 0.2, {-1.0, 0.0, 0.0}};
            sim::set_forces(model, ws, std::span<const sim::Force>(&force, 1));
            const double nodes = static_cast<double>(grid.node_count());
            const int steps =
                kernel_only ? 10 : std::max(3, static_cast<int>(node_steps_per_rep / nodes));
            for (int k = 0; k < 2; ++k)
                (void)sim::step_prepared(model, state, ws);
            std::vector<double> per;
            std::vector<double> per_cpu;  // process CPU seconds per step (load-independent)
            for (int rep = 0; rep < (kernel_only ? 1 : reps); ++rep)
            {
                // Bounded in wall time too: on a loaded machine two OpenMP threads can run 100x
                // slower than one, and a quick run must still end in seconds.
                const auto t0 = Clock::now();
                const double c0 = process_cpu_seconds();
                int done = 0;
                while (done < steps && (done < 3 || seconds_since(t0) < rep_cap_s))
                {
                    (void)sim::step_prepared(model, state, ws);
                    ++done;
                }
                per.push_back(seconds_since(t0) / done);
                per_cpu.push_back((process_cpu_seconds() - c0) / done);
            }
            const double t = median(per);
            const double ns = t / nodes * 1e9;
            std::printf("step,%d,%d,%.0f,%.2f,%.3e,%.2f\n", level, threads, nodes, ns, nodes / t,
                        bytes_per_node_step * nodes / t / 1e9);
            const std::string c = std::to_string(threads) + (threads == 1 ? " thread" : " threads");
            report.add(c, level, nodes, "nodes", "ns_per_node_step", ns, "ns");
            report.add(c, level, nodes, "nodes", "ms_per_step", t * 1e3, "ms");
            report.add(c, level, nodes, "nodes", "cpu_ns_per_node_step",
                       median(per_cpu) / nodes * 1e9, "ns");
            report.add(c, level, nodes, "nodes", "node_steps_per_s", nodes / t, "1/s");
            report.add(c, level, nodes, "nodes", "effective_bandwidth",
                       bytes_per_node_step * nodes / t, "B/s");
            if (threads == 1)
                ms_per_step_1[static_cast<std::size_t>(level)] = t * 1e3;
            std::fflush(stdout);
        }
    }

    if (kernel_only)
        return report.write() ? 0 : 1;
    // Real time: the benchmark scenario (adaptive, one moving force), frames of 1/60 s.
    for (const int threads : {1, 2})
    {
        int largest = 0;  // the largest level that ran the scenario in real time (0: none)
        for (int level = min_level; level <= max_level; ++level)
        {
            const core::TetraGrid grid = core::TetraGrid::create(level).value();
            sim::MembraneSettings set = bench_material();
            set.threads = threads;
            set.force_hold = hold;
            set.precision = precision;
            sim::MembraneModel model =
                sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0, 0, sphere_map), set)
                    .value();
            sim::MembraneState state = sim::MembraneState::at_rest(grid);
            sim::Rkf45Workspace ws(model, threads);
            const auto t0 = Clock::now();
            const double cpu0 = process_cpu_seconds();
            std::uint64_t steps = 0;
            int frame = 0;
            while (seconds_since(t0) < rt_seconds && frame < k_scenario_frames)
            {
                ++frame;
                const double t = frame / 60.0;
                const double s = std::min(1.0, t / 2.0);            // the finger slides over 2 s
                const double angle = s * (std::numbers::pi / 2.0);  // along the great circle
                const sim::Force force{
                    -1, {std::cos(angle), 0.0, std::sin(angle)}, 0.2, {-1.0, 0.0, -1.0}};
                steps +=
                    sim::advance_to(model, state, ws, t, std::span<const sim::Force>(&force, 1))
                        .steps;
            }
            const double wall = seconds_since(t0);
            const double cpu = process_cpu_seconds() - cpu0;
            std::printf("realtime,%d,%d,%.3f,%.3f,%.3f,%llu\n", level, threads, state.time, wall,
                        state.time / wall, static_cast<unsigned long long>(steps));
            std::fflush(stdout);
            const std::string c = std::to_string(threads) + (threads == 1 ? " thread" : " threads");
            const double nodes = static_cast<double>(grid.node_count());
            const double steps_per_sim_s = static_cast<double>(steps) / state.time;
            report.add(c, level, nodes, "nodes", "realtime_ratio", state.time / wall, "1");
            report.add(c, level, nodes, "nodes", "steps_per_simulated_s", steps_per_sim_s, "1/s");
            report.add(c, level, nodes, "nodes", "cpu_share", cpu / state.time, "1");
            if (threads == 1 && ms_per_step_1[static_cast<std::size_t>(level)] > 0.0)
                report.add(c, level, nodes, "nodes", "cpu_share_from_step_time",
                           ms_per_step_1[static_cast<std::size_t>(level)] * 1e-3 * steps_per_sim_s,
                           "1");
            if (state.time >= wall && frame == k_scenario_frames)
                largest = level;
            if (state.time < wall * 0.5)
                break;  // far from real time: finer levels only get slower
        }
        std::printf("largest real-time level, %d %s: %d\n", threads,
                    threads == 1 ? "thread" : "threads", largest);
        report.add(std::to_string(threads) + (threads == 1 ? " thread" : " threads"), -1, threads,
                   "threads", "largest_realtime_level", largest, "level");
    }
    return report.write() ? 0 : 1;
}
