// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Google Benchmark programs: the console output as usual, and every finished run handed to a
// callback that turns it into bench_report.h rows. `run_with_report` replaces BENCHMARK_MAIN's
// body: it takes --json/--csv/--quick out of argv, in quick mode shortens the minimum time per
// benchmark, runs the registered benchmarks and writes the report.

#include <benchmark/benchmark.h>

#include "bench_report.h"

#include <functional>
#include <string>
#include <vector>

namespace pliant::bench
{

/// A console reporter that also passes each (non-aggregate, successful) run to a callback.
class CaptureReporter final : public benchmark::ConsoleReporter
{
public:
    using Callback = std::function<void(const benchmark::BenchmarkReporter::Run&)>;
    explicit CaptureReporter(Callback on_run) : on_run_(std::move(on_run)) {}

    void ReportRuns(const std::vector<Run>& runs) override
    {
        for (const Run& r : runs)
            if (!r.error_occurred && r.run_type == Run::RT_Iteration)
                on_run_(r);
        ConsoleReporter::ReportRuns(runs);
    }

private:
    Callback on_run_;
};

/// Real time per iteration of a run, in seconds.
inline double real_seconds(const benchmark::BenchmarkReporter::Run& r)
{
    return r.GetAdjustedRealTime() / benchmark::GetTimeUnitMultiplier(r.time_unit);
}

/// A counter of a run, or `fallback` when absent.
inline double counter(const benchmark::BenchmarkReporter::Run& r, const std::string& name,
                      double fallback = 0.0)
{
    const auto it = r.counters.find(name);
    return it == r.counters.end() ? fallback : static_cast<double>(it->second);
}

/// Parses the report options, initialises Google Benchmark (quick: `quick_min_time` seconds
/// per benchmark), runs everything registered and writes the report. \return the exit code.
inline int run_with_report(Report& report, int argc, char** argv,
                           const CaptureReporter::Callback& on_run, double quick_min_time = 0.05)
{
    if (!report.parse_args(argc, argv))
        return 2;
    std::vector<std::string> storage(argv, argv + argc);
    if (report.quick())
        storage.insert(storage.begin() + 1,
                       "--benchmark_min_time=" + std::to_string(quick_min_time));
    std::vector<char*> args;
    for (std::string& s : storage)
        args.push_back(s.data());
    args.push_back(nullptr);
    int n = static_cast<int>(storage.size());
    benchmark::Initialize(&n, args.data());
    if (benchmark::ReportUnrecognizedArguments(n, args.data()))
        return 2;
    CaptureReporter reporter(on_run);
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    return report.write() ? 0 : 1;
}

}  // namespace pliant::bench
