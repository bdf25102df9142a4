// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Remesh benchmark: every committed test mesh and two large inputs (spot and blub with every
// triangle split into 4 or 16 by midpoint subdivision: 57K and 94K faces) at levels 5..8.
// Counters: seconds per phase (sphere map, domain map, sample, measure), PSNR, L2 stretch
// efficiency. The quality part runs once per case (it does not depend on timing).
//
//   build/<dir>/bench/remesh/bench_remesh --benchmark_filter='spot/7'
//   PLIANT_BENCH_LEVELS=7 build/<dir>/bench/remesh/bench_remesh --benchmark_repetitions=3
//   bench_remesh --quick --json remesh.json --csv remesh.csv      (what `pliant bench` runs)
//
// With --json/--csv (bench/common/bench_report.h) each case runs once, measuring in the same
// call (the timed figure then includes the "measure" phase, reported apart), at levels 4..7 of
// the five shared meshes and level 7 of the two large inputs; --quick: spot, blub and
// cube_minus_sphere at levels 4..6. Rows: PSNR, Hausdorff, L2 efficiency and seconds per phase,
// sized by the output vertices 2W^2 + 2.

#include <pliant/mesh/io.h>
#include <pliant/remesh/remesh.h>

#include <benchmark/benchmark.h>

#include "gbench_report.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace
{

using namespace pliant;

// Report mode: one remesh per case, measured in the same call.
bool g_single_run = false;

/// Each triangle split into four at its edge midpoints (shared midpoints welded).
mesh::TriMesh subdivide(const mesh::TriMesh& m)
{
    mesh::TriMesh out;
    out.positions = m.positions;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b)
    {
        const auto key = std::minmax(a, b);
        const auto it = mid.find(key);
        if (it != mid.end())
            return it->second;
        const auto id = static_cast<std::uint32_t>(out.positions.size());
        out.positions.push_back((m.positions[a] + m.positions[b]) * 0.5);
        mid.emplace(key, id);
        return id;
    };
    for (const auto& f : m.faces)
    {
        const std::uint32_t ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]),
                            ca = midpoint(f[2], f[0]);
        out.faces.push_back({f[0], ab, ca});
        out.faces.push_back({ab, f[1], bc});
        out.faces.push_back({ca, bc, f[2]});
        out.faces.push_back({ab, bc, ca});
    }
    return out;
}

const std::map<std::string, mesh::TriMesh>& meshes()
{
    static const std::map<std::string, mesh::TriMesh> all = []
    {
        std::map<std::string, mesh::TriMesh> m;
        const std::filesystem::path dir =
            std::filesystem::path(PLIANT_SOURCE_DIR) / "tests" / "data" / "meshes";
        for (const auto& [name, file] : std::vector<std::pair<std::string, std::string>>{
                 {"fox", "fox.ply"},
                 {"spot", "spot_triangulated.obj"},
                 {"cube_minus_sphere", "cube_minus_sphere.obj"},
                 {"cactus", "cactus.off"},
                 {"blub", "blub_triangulated.obj"}})
        {
            auto r = mesh::import_mesh(dir / file);
            if (r)
                m.emplace(name, std::move(*r));
        }
        if (m.count("blub"))
            m.emplace("blub_x4_57k", subdivide(m.at("blub")));
        if (m.count("spot"))
            m.emplace("spot_x16_94k", subdivide(subdivide(m.at("spot"))));
        return m;
    }();
    return all;
}

remesh::RemeshSettings settings(int level, bool measure)
{
    remesh::RemeshSettings s;
    s.level = level;
    s.measure = measure;
    return s;
}

void bench_remesh(benchmark::State& state, const std::string& name, int level)
{
    const mesh::TriMesh& m = meshes().at(name);
    remesh::QualityReport last;
    for (auto _ : state)
    {
        auto r = remesh::remesh(m, settings(level, g_single_run));
        if (!r)
        {
            state.SkipWithError(r.error().message.c_str());
            return;
        }
        last = r->report;
        benchmark::DoNotOptimize(r->positions);
    }
    for (const auto& p : last.phases)
        state.counters[p.name + " s"] = p.seconds;
    if (g_single_run)
    {
        state.counters["PSNR dB"] = last.distance.psnr_db;
        state.counters["Hausdorff %"] = 100.0 * last.distance.hausdorff_relative;
    }
    else
    {
        // the quality of the (deterministic) result, measured once outside the timed loop
        auto measured = remesh::remesh(m, settings(level, true));
        if (measured)
        {
            state.counters["PSNR dB"] = measured->report.distance.psnr_db;
            state.counters["Hausdorff %"] = 100.0 * measured->report.distance.hausdorff_relative;
            state.counters["measure s"] = measured->report.phases.back().seconds;
        }
    }
    state.counters["L2 eff"] = last.stretch_efficiency;
    state.counters["faces in"] = static_cast<double>(m.faces.size());
}

/// Counter name -> metric name: "PSNR dB" -> "psnr_db", "Hausdorff %" -> "hausdorff_pct".
std::string metric_name(const std::string& counter)
{
    std::string out;
    for (const char c : counter)
    {
        if (c == ' ' || c == '-')
            out += '_';
        else if (c == '%')
            out += "pct";
        else
            out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return out;
}

}  // namespace

int main(int argc, char** argv)
{
    bench::Report report("remesh");
    // Peek for the report options: they change what is registered.
    for (int i = 1; i < argc; ++i)
    {
        const std::string a = argv[i];
        g_single_run = g_single_run || a == "--json" || a == "--csv" || a == "--quick";
    }
    bool quick = false;
    for (int i = 1; i < argc; ++i)
        quick = quick || std::string(argv[i]) == "--quick";
    std::vector<int> levels =
        g_single_run ? (quick ? std::vector<int>{4, 5, 6} : std::vector<int>{4, 5, 6, 7})
                     : std::vector<int>{5, 6, 7, 8};
    if (const char* env = std::getenv("PLIANT_BENCH_LEVELS"); env != nullptr)
        levels = {std::atoi(env)};
    for (const auto& [name, m] : meshes())
    {
        const bool large = name.find("_x") != std::string::npos;
        if (quick && name != "spot" && name != "blub" && name != "cube_minus_sphere")
            continue;
        for (const int level : levels)
        {
            if (g_single_run && large && level != 7)
                continue;
            benchmark::RegisterBenchmark((name + "/" + std::to_string(level)).c_str(),
                                         [name = name, level](benchmark::State& s)
                                         { bench_remesh(s, name, level); })
                ->Unit(benchmark::kMillisecond)
                ->Iterations(1)
                ->UseRealTime();
        }
    }
    benchmark::AddCustomContext("build",
#if defined(__AVX2__)
                                "AVX2"
#else
                                "portable"
#endif
    );
    if (!g_single_run)
    {
        benchmark::Initialize(&argc, argv);
        benchmark::RunSpecifiedBenchmarks();
        benchmark::Shutdown();
        return 0;
    }
    report.meta("meshes", "tests/data/meshes (README.md there lists V, F, genus)");
    return bench::run_with_report(
        report, argc, argv,
        [&report](const benchmark::BenchmarkReporter::Run& r)
        {
            const std::string name = r.run_name.function_name;
            const auto slash = name.find('/');
            const std::string mesh_name = name.substr(0, slash);
            const int level = slash == std::string::npos ? -1 : std::atoi(name.c_str() + slash + 1);
            const double w = static_cast<double>(1 << std::max(level, 0));
            const double vertices = 2.0 * w * w + 2.0;
            report.add(mesh_name, level, vertices, "vertices", "total_s", bench::real_seconds(r),
                       "s");
            for (const auto& [counter_name, value] : r.counters)
            {
                const std::string metric = metric_name(counter_name);
                const bool secs = metric.size() > 2 && metric.ends_with("_s");
                report.add(mesh_name, level, vertices, "vertices", metric,
                           static_cast<double>(value),
                           metric == "psnr_db"         ? "dB"
                           : metric == "hausdorff_pct" ? "%"
                           : secs                      ? "s"
                                                       : "1");
            }
        });
}
