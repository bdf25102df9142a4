// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Session numbers for docs/session.md, all peers in one thread over a SimulatedNetwork (5 ms
// one-way latency): per level and peer count, the partition's balance and fragments, the CPU time
// of each peer's steps per simulated second against one process stepping everything, the bytes
// each peer sends per simulated second, and the fast-vs-exact error of a scripted pull.
//   pliant_bench_session [levels...] [--quick] [--json FILE] [--csv FILE]   (default: 5 6 7;
//   quick: 5 6 without the 1 kHz-frame variant)
// --json/--csv rows (bench/common/bench_report.h), sized by the number of peers (1..4): per
// coupling ("exact", "fast", "fast 1 kHz") the step seconds per simulated second of the busiest
// peer and the mean peer, their ratio to one process stepping every node, the payload bytes sent
// per simulated second per peer and the fast-vs-exact error; "no partitioning" is that one
// process (every peer of an unpartitioned session steps every node); the partition's imbalance,
// fragments and border edges.
#include <pliant/net/simulated_transport.h>
#include <pliant/session/partition.h>
#include <pliant/session/session.h>
#include <pliant/sim/rkf45.h>

#include "bench_report.h"
#include "grid_shapes.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

using namespace pliant;

namespace
{

sim::MembraneSettings material()
{
    sim::MembraneSettings m;
    m.beta = 0.5;
    m.k_f = 1.0;
    m.fixed_step = true;
    m.fixed_dt = 1e-3;
    m.threads = 1;
    return m;
}

struct RunResult
{
    std::vector<double> step_s;  // per peer
    std::vector<double> bytes_out;
    double max_u_diff = 0.0;
    double max_u = 0.0;
};

net::UserForce pull(std::uint32_t face)
{
    net::UserForce f;
    f.target.kind = net::TargetKind::Face;
    f.target.face = face;
    f.force = {0.0, 0.0, 0.5};
    return f;
}

/// One run: `peers` participants (master included), `ticks` steps after everyone is in.
RunResult run(int level, int peers, session::Coupling coupling, std::uint64_t ticks,
              const sim::MembraneState* reference_state, double rate_hz = 60.0)
{
    net::SimulatedNetwork network;
    std::vector<std::unique_ptr<net::Transport>> tr;
    std::vector<std::unique_ptr<session::Session>> s;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    session::SessionSettings set;
    set.coupling = coupling;
    set.max_ticks = ticks;
    set.frame_rate_hz = rate_hz;
    set.stream_rate_hz = rate_hz;
    tr.push_back(network.create_endpoint());
    const net::Address master = tr.back()->open({}).value();
    s.push_back(
        session::Session::host(*tr.back(), grid, scenes::sphere_grid(grid, 1.0), material(), set)
            .value());
    const std::uint32_t faces = static_cast<std::uint32_t>(grid.face_count());
    for (int k = 1; k < peers; ++k)
    {
        tr.push_back(network.create_endpoint());
        (void)tr.back()->open({}).value();
        s.push_back(
            session::Session::join(*tr.back(), master, net::Role::Participant, set).value());
        s.back()->set_points_of_interest(
            {net::Target{net::TargetKind::Face,
                         static_cast<std::uint32_t>(k) * faces / static_cast<std::uint32_t>(peers),
                         {0, 0, 0},
                         0.0}});
    }
    // Scripted pull: the master's face from tick 100 to 400, the last peer's from 200.
    s[0]->set_forces({pull(faces / 7)}, 100);
    s[0]->set_forces({}, 400);
    if (peers > 1)
        s.back()->set_forces({pull(faces / 2 + 5)}, 200);
    double now = 0.0;
    auto all_done = [&]
    {
        for (const auto& p : s)
            if (p->tick() < ticks)
                return false;
        return true;
    };
    for (int it = 0; it < 4'000'000 && !all_done(); ++it)
    {
        for (auto& p : s)
            p->poll();
        for (auto& p : s)
            p->advance(now);
        network.advance(0.0005);
        now += 0.0005;
    }
    RunResult r;
    for (const auto& p : s)
    {
        const auto st = p->stats();
        r.step_s.push_back(st.step_seconds);
        r.bytes_out.push_back(static_cast<double>(st.bytes_sent));
    }
    if (reference_state != nullptr)
        for (const auto& p : s)
        {
            const auto owners = p->owners();
            for (const core::NodeIndex n : grid.node_of_unique())
            {
                const core::GridCoord c = grid.coord(n);
                r.max_u = std::max(r.max_u, std::fabs(reference_state->u.at(c.x, c.y)));
                if (owners[p->leaf_graph()->leaf_of(n)] == p->id())
                    r.max_u_diff = std::max(
                        r.max_u_diff,
                        std::fabs(p->state().u.at(c.x, c.y) - reference_state->u.at(c.x, c.y)));
            }
        }
    return r;
}

/// The single-process run of the same pulls (forces by increasing sender id, as the session).
sim::MembraneState reference(sim::MembraneModel& model, int peers, std::uint64_t ticks)
{
    const auto faces = static_cast<std::uint32_t>(model.grid().face_count());
    sim::MembraneState st = sim::MembraneState::at_rest(model.grid());
    sim::Rkf45Workspace ws(model, 1);
    for (std::uint64_t t = 0; t < ticks; ++t)
    {
        std::vector<sim::Force> f;
        if (t >= 100 && t < 400)
            f.push_back(session::to_sim_force(pull(faces / 7)));
        if (t >= 200)
            f.push_back(session::to_sim_force(pull(faces / 2 + 5)));
        (void)peers;
        sim::step(model, st, ws, f);
    }
    return st;
}

}  // namespace

namespace
{

/// Adds the rows of one coupling's run.
void add_rows(bench::Report& report, const std::string& name, int level, int peers,
              const RunResult& r, double single_s, double sim_seconds)
{
    double worst = 0.0;
    double sum = 0.0;
    double bytes = 0.0;
    for (std::size_t k = 0; k < r.step_s.size(); ++k)
    {
        worst = std::max(worst, r.step_s[k]);
        sum += r.step_s[k];
        bytes += r.bytes_out[k];
    }
    const double n = static_cast<double>(peers);
    report.add(name, level, n, "peers", "step_s_per_sim_s_max", worst / sim_seconds, "s/s");
    report.add(name, level, n, "peers", "step_s_per_sim_s_mean", sum / n / sim_seconds, "s/s");
    report.add(name, level, n, "peers", "compute_vs_single_max", worst / single_s, "1");
    report.add(name, level, n, "peers", "compute_vs_single_mean", sum / n / single_s, "1");
    report.add(name, level, n, "peers", "bytes_out_per_sim_s_per_peer", bytes / n / sim_seconds,
               "B/s");
    if (r.max_u > 0.0)
        report.add(name, level, n, "peers", "error_vs_single_rel", r.max_u_diff / r.max_u, "1");
}

}  // namespace

int main(int argc, char** argv)
{
    bench::Report report("session");
    if (!report.parse_args(argc, argv))
        return 2;
    std::vector<int> levels;
    for (int k = 1; k < argc; ++k)
        levels.push_back(std::atoi(argv[k]));
    if (levels.empty())
        levels = report.quick() ? std::vector<int>{5, 6} : std::vector<int>{5, 6, 7};
    report.meta("network", "SimulatedNetwork, 5 ms one-way latency, all peers in one thread");
    report.meta("material", "unit sphere, T=1, rho=1, beta=0.5, k_f=1, fixed dt 1 ms");
    const std::uint64_t ticks = 500;
    std::printf("# simulated network, 5 ms one-way latency, fixed dt 1 ms, %llu ticks, 1 thread\n",
                static_cast<unsigned long long>(ticks));
    std::printf(
        "level peers | imbalance fragments border | step CPU per peer / single (max) | "
        "MB/s out per peer (mean) | fast err rel\n");
    for (const int level : levels)
    {
        const core::TetraGrid grid = core::TetraGrid::create(level).value();
        // Single process: every node, full steps, same pulls at the same ticks.
        auto model =
            sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), material()).value();
        const double sim_seconds = static_cast<double>(ticks) * material().fixed_dt;
        double single_s = 0.0;
        {
            sim::MembraneState st = sim::MembraneState::at_rest(grid);
            sim::Rkf45Workspace ws(model, 1);
            const auto t0 = std::chrono::steady_clock::now();
            for (std::uint64_t t = 0; t < ticks; ++t)
                sim::step(model, st, ws, {});
            single_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        }
        // Fast vs exact: every peer's owned nodes against the single-process run (which the
        // exact coupling equals bit for bit, tests/session).
        const sim::MembraneState ref = reference(model, 0, ticks);
        const double vertices = static_cast<double>(grid.unique_count());
        report.add("single process", level, vertices, "vertices", "step_s_per_sim_s",
                   single_s / sim_seconds, "s/s");
        for (int peers = 1; peers <= 4; ++peers)
        {
            report.add("no partitioning", level, peers, "peers", "step_s_per_sim_s_max",
                       single_s / sim_seconds, "s/s");
            report.add("no partitioning", level, peers, "peers", "compute_vs_single_max", 1.0, "1");
        }
        {
            // One peer alone through the session (its per-tick overheads, no partner).
            const RunResult alone = run(level, 1, session::Coupling::Fast, ticks, nullptr);
            add_rows(report, "fast", level, 1, alone, single_s, sim_seconds);
            const RunResult alone_exact = run(level, 1, session::Coupling::Exact, ticks, nullptr);
            add_rows(report, "exact", level, 1, alone_exact, single_s, sim_seconds);
        }
        for (int peers = 2; peers <= 4; ++peers)
        {
            const RunResult exact = run(level, peers, session::Coupling::Exact, ticks, &ref);
            const RunResult fast = run(level, peers, session::Coupling::Fast, ticks, &ref);
            add_rows(report, "exact", level, peers, exact, single_s, sim_seconds);
            add_rows(report, "fast", level, peers, fast, single_s, sim_seconds);
            const session::LeafGraph graph(grid,
                                           session::leaf_depth_for(grid, net::ValueEncoding::F64));
            std::vector<session::Seat> seats;
            for (int k = 0; k < peers; ++k)
                seats.push_back({net::PeerId{static_cast<std::uint16_t>(k)}, std::nullopt});
            const auto q = session::measure_partition(
                grid, graph, session::partition_leaves(grid, graph, seats));
            std::size_t frags = 0;
            for (const auto& sh : q.shares)
                frags += sh.fragments;
            const double n = static_cast<double>(peers);
            report.add("partition", level, n, "peers", "imbalance", q.imbalance, "1");
            report.add("partition", level, n, "peers", "fragments", static_cast<double>(frags),
                       "1");
            report.add("partition", level, n, "peers", "border_edges",
                       static_cast<double>(q.border_edges), "1");
            double worst = 0.0;
            double bytes = 0.0;
            for (std::size_t k = 0; k < exact.step_s.size(); ++k)
            {
                worst = std::max(worst, exact.step_s[k]);
                bytes += exact.bytes_out[k];
            }
            std::printf(
                "%5d %5d | %9.3f %9zu %6zu | %.2f (exact)                      | %7.2f "
                "(exact)            | %.2e (exact: %.1e)\n",
                level, peers, q.imbalance, frags, q.border_edges, worst / single_s,
                bytes / static_cast<double>(peers) / sim_seconds / 1e6,
                fast.max_u > 0.0 ? fast.max_u_diff / fast.max_u : 0.0,
                exact.max_u > 0.0 ? exact.max_u_diff / exact.max_u : 0.0);
            double fworst = 0.0;
            double fbytes = 0.0;
            for (std::size_t k = 0; k < fast.step_s.size(); ++k)
            {
                fworst = std::max(fworst, fast.step_s[k]);
                fbytes += fast.bytes_out[k];
            }
            std::printf(
                "%5d %5d |                            | %.2f (fast)                       "
                "| %7.2f (fast)\n",
                level, peers, fworst / single_s,
                fbytes / static_cast<double>(peers) / sim_seconds / 1e6);
            if (report.quick())
            {
                std::fflush(stdout);
                continue;  // quick: no 1 kHz-frame variant
            }
            const RunResult fast1k =
                run(level, peers, session::Coupling::Fast, ticks, &ref, 1000.0);
            add_rows(report, "fast 1 kHz", level, peers, fast1k, single_s, sim_seconds);
            double kworst = 0.0;
            double kbytes = 0.0;
            for (std::size_t k = 0; k < fast1k.step_s.size(); ++k)
            {
                kworst = std::max(kworst, fast1k.step_s[k]);
                kbytes += fast1k.bytes_out[k];
            }
            std::printf(
                "%5d %5d |                            | %.2f (fast, 1 kHz frames)           "
                "| %7.2f (fast 1 kHz)      | %.2e\n",
                level, peers, kworst / single_s,
                kbytes / static_cast<double>(peers) / sim_seconds / 1e6,
                fast1k.max_u > 0.0 ? fast1k.max_u_diff / fast1k.max_u : 0.0);
            std::fflush(stdout);
        }
    }
    return report.write() ? 0 : 1;
}
