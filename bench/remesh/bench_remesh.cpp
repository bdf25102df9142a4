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

#include <pliant/mesh/io.h>
#include <pliant/remesh/remesh.h>

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace
{

using namespace pliant;

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
        auto r = remesh::remesh(m, settings(level, false));
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
    // the quality of the (deterministic) result, measured once outside the timed loop
    auto measured = remesh::remesh(m, settings(level, true));
    if (measured)
    {
        state.counters["PSNR dB"] = measured->report.distance.psnr_db;
        state.counters["Hausdorff %"] = 100.0 * measured->report.distance.hausdorff_relative;
        state.counters["measure s"] = measured->report.phases.back().seconds;
    }
    state.counters["L2 eff"] = last.stretch_efficiency;
    state.counters["faces in"] = static_cast<double>(m.faces.size());
}

}  // namespace

int main(int argc, char** argv)
{
    std::vector<int> levels{5, 6, 7, 8};
    if (const char* env = std::getenv("PLIANT_BENCH_LEVELS"); env != nullptr)
        levels = {std::atoi(env)};
    for (const auto& [name, m] : meshes())
        for (const int level : levels)
            benchmark::RegisterBenchmark((name + "/" + std::to_string(level)).c_str(),
                                         [name = name, level](benchmark::State& s)
                                         { bench_remesh(s, name, level); })
                ->Unit(benchmark::kMillisecond)
                ->Iterations(1)
                ->UseRealTime();
    benchmark::AddCustomContext("build",
#if defined(__AVX2__)
                                "AVX2"
#else
                                "portable"
#endif
    );
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
