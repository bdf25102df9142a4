// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Session numbers for docs/session.md, all peers in one thread over a SimulatedNetwork (5 ms
// one-way latency): per level and peer count, the partition's balance and fragments, the CPU time
// of each peer's steps per simulated second against one process stepping everything, the bytes
// each peer sends per simulated second, and the fast-vs-exact error of a scripted pull.
//   pliant_bench_session [levels...] [--quick] [--json FILE] [--csv FILE]   (default: 5 6 7;
//   quick: 5 6 without the 1 kHz-frame variant)
//   pliant_bench_session --stream [level] [--seconds S]   (streaming cost of 2 dragging peers)
//   pliant_bench_session --coarse [levels...] [--seconds S]   (coarse streaming, k = 0, 1, 2;
//   default levels 6 7)
//   pliant_bench_session --steps [levels...]   (each peer's restricted sim step alone against
//   the full step, thread CPU time; default levels 6 7 8)
//   pliant_bench_session --latency [levels...] [--enet]   (from a grab to the change appearing
//   on the other peers, virtual time; --enet: real time over ENet on 127.0.0.1; default levels
//   6 7 8)
//   pliant_bench_session --cpu [levels...]   (all the work of each peer per simulated second
//   against one peer alone, on a 0.5 ms LAN; default levels 6 7 8)
//   pliant_bench_session --join [levels...] [--loss P] [--runs N]   (how long a master, two
//   participants and a viewer take to join over ENet through an impairing relay, with ENet's
//   own retransmission and window and with the transport's; default levels 5 6)
//   --help prints the usage (k_usage); an unknown option or a level out of range exits 2.
// --json/--csv rows (bench/common/bench_report.h), sized by the number of peers (1..4): per
// coupling ("exact", "fast", "fast 1 kHz") the step seconds per simulated second of the busiest
// peer and the mean peer, their ratio to one process stepping every node, the payload bytes sent
// per simulated second per peer and the fast-vs-exact error; "no partitioning" is that one
// process (every peer of an unpartitioned session steps every node); the partition's imbalance,
// fragments and border edges.
#include <pliant/net/enet_transport.h>
#include <pliant/net/simulated_transport.h>
#include <pliant/session/partition.h>
#include <pliant/session/session.h>
#include <pliant/sim/rkf45.h>
#include <pliant/subdiv/convolution_plan.h>
#include <pliant/subdiv/refine.h>

#include <time.h>

#include "bench_report.h"
#include "grid_shapes.h"
#include "relay_session.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

using namespace pliant;

namespace
{

// The benchmark's forces are its own, on faces of the grid it made: one refused is a defect here.
void must(const core::Result<void>& queued)
{
    if (!queued)
    {
        std::fprintf(stderr, "pliant_bench_session: %s\n", queued.error().message.c_str());
        std::exit(1);
    }
}

constexpr const char* k_usage =
    "usage: pliant_bench_session [levels...] [--quick] [--json FILE] [--csv FILE]\n"
    "       pliant_bench_session --stream [level] [--seconds S]\n"
    "       pliant_bench_session --coarse [levels...] [--seconds S]\n"
    "       pliant_bench_session --steps [levels...] [--copy-accept] [--random-points N]\n"
    "       pliant_bench_session --latency [levels...] [--enet]\n"
    "       pliant_bench_session --cpu [levels...]\n"
    "       pliant_bench_session --join [levels...] [--loss P] [--runs N]\n"
    "Session numbers for docs/session.md: all peers in one thread over a simulated network (5 ms\n"
    "one-way latency), one thread per peer.\n"
    "  levels...    grid levels 1..10 (--coarse: 3..10). Without a mode, per level and peer count\n"
    "               (1..4): the partition's balance and fragments, the CPU time of each peer's\n"
    "               steps per simulated second against one process stepping everything, the\n"
    "               bytes each peer sends per simulated second, and the fast-vs-exact error of a\n"
    "               scripted pull, also in fast coupling with exact coupling's point clearance\n"
    "               (SessionSettings::point_clearance) (default levels 5 6 7; --quick: 5 6\n"
    "               without the 1 kHz-frame variant)\n"
    "  --stream     streaming cost of 2 peers dragging continuously, per encoding, at one level\n"
    "               (default 6)\n"
    "  --coarse     coarse streaming to a viewer, k = 0, 1, 2 levels coarser\n"
    "               (default levels 6 7)\n"
    "  --steps      each peer's restricted sim step alone against the full step, in thread CPU\n"
    "               time, per coupling's partition and for fast coupling under point clearance\n"
    "               inside (default levels 6 7 8; --quick: 6)\n"
    "  --copy-accept\n"
    "               with --steps: restricted steps copy their result back into the state\n"
    "               (sim::StepOptions::keep_outside) instead of swapping planes as the\n"
    "               session's peers do: the cost of that copy, against a run without it\n"
    "  --random-points N\n"
    "               with --steps: instead of the two fixed seat layouts, N layouts per level and\n"
    "               peer count in which every member declares a uniformly drawn face (fixed\n"
    "               seeds); the busiest peer's median and worst, and how many layouts meet the\n"
    "               compute target (55 % with 2 peers, 30 % with 4), 1..1000\n"
    "  --latency    from a grab to the change appearing on the other participants and a viewer,\n"
    "               2..4 participants, exact and fast coupling, in virtual time (default levels\n"
    "               6 7 8; --quick: 6)\n"
    "  --enet       with --latency: in real time over ENet on 127.0.0.1, a thread per peer\n"
    "  --cpu        all the work of each peer (steps, halos, streams, display) per simulated\n"
    "               second in the steady state, against one peer alone in its session, 1..4\n"
    "               participants, exact and fast coupling, on a 0.5 ms LAN, best of 3 runs\n"
    "               (default levels 6 7 8; --quick: level 6, one run)\n"
    "  --join       a master, two participants and a viewer join at once over ENet on\n"
    "               127.0.0.1 through a relay that delays each datagram 100-120 ms each way,\n"
    "               duplicates 1 %, holds 2 % back 20 ms and loses --loss; when the joiners hold\n"
    "               the model, when all are partitioned, when the full mesh is up (median and\n"
    "               worst), with ENet's own retransmission timer and 64 KiB window, with the\n"
    "               transport's fast retransmit, and with its 256 KiB window too (runs\n"
    "               alternate; default levels 5 6; --quick: 5, 3 runs)\n"
    "  --loss P     with --join: the probability a datagram is lost, 0..0.5 (default 0.1)\n"
    "  --runs N     with --join: joins per level and configuration, 1..1000 (default 10)\n"
    "  --seconds S  seconds measured by --stream and --coarse after 0.5 s of warm-up,\n"
    "               > 0 and <= 3600 (default 2)\n"
    "  --quick      short runs: the default suite at levels 5 6, --steps and --latency at 6\n"
    "  --json FILE, --csv FILE\n"
    "               also write the figures as rows (bench/common/bench_report.h)\n"
    "  -h, --help   print this and exit\n";

/// --coarse streams up to this many levels coarser than the grid.
constexpr int k_coarsest = 2;
/// The most --random-points layouts per level and peer count.
constexpr int k_max_random_layouts = 1000;
/// The longest --seconds: an hour of simulated streaming.
constexpr double k_max_seconds = 3600.0;
/// The most --runs of --join.
constexpr int k_max_join_runs = 1000;
/// A --join run that has not meshed by then is counted as not meshed, s.
constexpr double k_join_limit_s = 20.0;

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
    // Steady state (every peer in the partition, 20 ticks on), per peer: the wall time of its
    // poll() and advance() calls (all its work: steps, halos, streams, display), of its steps
    // alone, and its simulated seconds.
    std::vector<double> steady_busy_s;
    std::vector<double> steady_step_s;
    std::vector<double> steady_sim_s;
    double max_u_diff = 0.0;
    double max_u = 0.0;

    /// The busiest peer's step time, s.
    [[nodiscard]] double worst_step() const
    {
        return step_s.empty() ? 0.0 : *std::max_element(step_s.begin(), step_s.end());
    }
    /// Bytes sent by all peers.
    [[nodiscard]] double total_bytes() const
    {
        double sum = 0.0;
        for (const double b : bytes_out)
            sum += b;
        return sum;
    }
};

net::UserForce pull(std::uint32_t face)
{
    net::UserForce f;
    f.target.kind = net::TargetKind::Face;
    f.target.face = face;
    f.force = {0.0, 0.0, 0.5};
    return f;
}

/// The seats of the session runs: participant k declares face k F / P (its cell corner, as
/// Session::seed_of takes it), the master declares none; without `points`, nobody does.
std::vector<session::Seat> session_seats(const core::TetraGrid& grid, int peers, bool points)
{
    const auto faces = static_cast<std::uint32_t>(grid.face_count());
    const auto w2 = static_cast<std::uint32_t>(2 * grid.w());
    std::vector<session::Seat> seats;
    for (int k = 0; k < peers; ++k)
    {
        seats.push_back({net::PeerId{static_cast<std::uint16_t>(k)}, std::nullopt});
        if (points && k > 0)
        {
            const std::uint32_t cell =
                static_cast<std::uint32_t>(k) * faces / static_cast<std::uint32_t>(peers) / 2;
            seats.back().seed = grid.canonical(
                grid.index(static_cast<int>(cell % w2), static_cast<int>(cell / w2)));
        }
    }
    return seats;
}

/// One round of peers sharing one thread over the simulated network: every session polls, then
/// advances to `now`; then the network and `now` move on by `dt`.
void pump_sessions(std::vector<std::unique_ptr<session::Session>>& s,
                   net::SimulatedNetwork& network, double& now, double dt)
{
    for (auto& p : s)
        p->poll();
    for (auto& p : s)
        p->advance(now);
    network.advance(dt);
    now += dt;
}

/// One run: `peers` participants (master included), `ticks` steps after everyone is in.
RunResult run(int level, int peers, session::Coupling coupling, std::uint64_t ticks,
              const sim::MembraneState* reference_state, double rate_hz = 60.0,
              std::optional<session::PointClearance> clearance = std::nullopt,
              double latency_s = 0.005)
{
    net::SimulatedNetworkSettings network_settings;
    network_settings.link.latency_s = latency_s;
    net::SimulatedNetwork network(network_settings);
    std::vector<std::unique_ptr<net::Transport>> tr;
    std::vector<std::unique_ptr<session::Session>> s;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    session::SessionSettings set;
    set.coupling = coupling;
    set.point_clearance = clearance;
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
    must(s[0]->set_forces({pull(faces / 7)}, 100));
    must(s[0]->set_forces({}, 400));
    if (peers > 1)
        must(s.back()->set_forces({pull(faces / 2 + 5)}, 200));
    double now = 0.0;
    auto all_done = [&]
    {
        for (const auto& p : s)
            if (p->tick() < ticks)
                return false;
        return true;
    };
    // Steady state: every peer ready, in the master's partition and of its epoch; 20 ticks on.
    const auto settled = [&]
    {
        const auto owners = s[0]->owners();
        return std::all_of(s.begin(), s.end(),
                           [&](const auto& p)
                           {
                               return p->ready() && p->epoch() == s[0]->epoch() &&
                                      std::find(owners.begin(), owners.end(), p->id()) !=
                                          owners.end();
                           });
    };
    std::uint64_t steady_from = 0;  // the master's tick at which the steady state starts
    std::vector<double> busy(s.size(), 0.0);
    std::vector<double> busy0;
    std::vector<session::SessionStats> stats0;
    std::vector<double> time0;
    const auto timed = [&](std::size_t k, auto&& call)
    {
        const auto t0 = std::chrono::steady_clock::now();
        call();
        busy[k] += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    const double pump_dt = 0.0005;
    for (int it = 0; it < 4'000'000 && !all_done(); ++it)
    {
        // pump_sessions, each peer's calls timed; the network's deliveries are not theirs.
        network.deliver_due();
        for (std::size_t k = 0; k < s.size(); ++k)
            timed(k, [&] { s[k]->poll(); });
        for (std::size_t k = 0; k < s.size(); ++k)
            timed(k,
                  [&]
                  {
                      s[k]->advance(now);
                      // A peer that shows the object reads its view after every advance (the
                      // session computes the view's nodes when it is read, once per frame).
                      (void)s[k]->view_u();
                  });
        network.advance(pump_dt);
        now += pump_dt;
        if (busy0.empty())
        {
            if (steady_from == 0 && settled())
                steady_from = s[0]->tick() + 20;
            else if (steady_from != 0 && s[0]->tick() >= steady_from)
            {
                busy0 = busy;
                for (const auto& p : s)
                {
                    stats0.push_back(p->stats());
                    time0.push_back(p->state().time);
                }
            }
        }
    }
    RunResult r;
    for (std::size_t k = 0; k < s.size(); ++k)
    {
        const auto st = s[k]->stats();
        r.step_s.push_back(st.step_seconds);
        r.bytes_out.push_back(static_cast<double>(st.bytes_sent));
        if (!busy0.empty())
        {
            r.steady_busy_s.push_back(busy[k] - busy0[k]);
            r.steady_step_s.push_back(st.step_seconds - stats0[k].step_seconds);
            r.steady_sim_s.push_back(s[k]->state().time - time0[k]);
        }
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

/// Streaming cost of one encoding (docs/protocol.md §5.5, docs/results.md): two participants
/// (master and one joiner) in `fast` coupling, each dragging a grab around continuously (a force
/// whose direction turns once per second, re-sent every frame as a user drag would), streaming at
/// 60 Hz, measured over `seconds` of virtual time after a 0.5 s warm-up.
struct StreamResult
{
    double bytes_per_peer_s = 0.0;    // payload bytes out per peer per second (everything sent)
    double packets_per_peer_s = 0.0;  // datagrams out per peer per second
    double owned_nodes = 0.0;         // mean nodes owned per peer
    double max_u = 0.0;               // largest |u| at the end, m
    std::uint64_t leaf_states = 0, keys = 0, skips = 0, capped = 0, misses = 0;
};

StreamResult run_stream(int level, net::ValueEncoding encoding, double seconds, int u_exp,
                        int v_exp, double drag_hz, double drag_n, double cap_mbit,
                        net::Packing packing, bool batch, double ack_hz)
{
    net::SimulatedNetwork network;
    std::vector<std::unique_ptr<net::Transport>> tr;
    std::vector<std::unique_ptr<session::Session>> s;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    session::SessionSettings set;
    set.coupling = session::Coupling::Fast;
    set.stream_encoding = encoding;
    set.u_step_exponent = u_exp;
    set.v_step_exponent = v_exp;
    set.bandwidth_cap_mbit_s = cap_mbit;
    set.stream_packing = packing;
    set.batch_leaves = batch;
    set.ack_rate_hz = ack_hz;
    tr.push_back(network.create_endpoint());
    const net::Address master = tr.back()->open({}).value();
    s.push_back(
        session::Session::host(*tr.back(), grid, scenes::sphere_grid(grid, 1.0), material(), set)
            .value());
    tr.push_back(network.create_endpoint());
    (void)tr.back()->open({}).value();
    s.push_back(session::Session::join(*tr.back(), master, net::Role::Participant, set).value());
    const auto faces = static_cast<std::uint32_t>(grid.face_count());
    s[1]->set_points_of_interest({net::Target{net::TargetKind::Face, faces / 2, {0, 0, 0}, 0.0}});
    const double dt = 0.0005;
    double now = 0.0;
    const auto pump = [&] { pump_sessions(s, network, now, dt); };
    for (int it = 0; it < 40000; ++it)
    {
        const auto owners = s[0]->owners();
        if (s[1]->ready() && std::find(owners.begin(), owners.end(), s[1]->id()) != owners.end())
            break;
        pump();
    }
    // Each participant drags a grab near its own seed: 0.5 N turning at 1 Hz.
    const double poles[2] = {1.0, -1.0};
    auto drag = [&](double t)
    {
        for (int k = 0; k < 2; ++k)
        {
            net::UserForce f;
            f.target.kind = net::TargetKind::Position;
            f.target.position = {0.0, 0.0, poles[k]};
            f.target.radius = 0.3;
            const double a = 2.0 * 3.141592653589793 * drag_hz * t + k;
            f.force = {drag_n * std::cos(a), drag_n * std::sin(a), -0.6 * drag_n * poles[k]};
            must(s[static_cast<std::size_t>(k)]->set_forces({f}));
        }
    };
    const int per_frame = static_cast<int>(std::lround(1.0 / 60.0 / dt));
    auto run_for = [&](double span)
    {
        const int frames = static_cast<int>(std::lround(span * 60.0));
        for (int f = 0; f < frames; ++f)
        {
            drag(now);
            for (int k = 0; k < per_frame; ++k)
                pump();
        }
    };
    run_for(0.5);
    std::vector<session::SessionStats> before;
    for (const auto& p : s)
        before.push_back(p->stats());
    run_for(seconds);
    StreamResult r;
    for (std::size_t k = 0; k < s.size(); ++k)
    {
        const auto st = s[k]->stats();
        r.bytes_per_peer_s += static_cast<double>(st.bytes_sent - before[k].bytes_sent);
        r.packets_per_peer_s += static_cast<double>(st.packets_sent - before[k].packets_sent);
        r.owned_nodes += static_cast<double>(st.owned_nodes);
        r.leaf_states += st.leaf_states_sent - before[k].leaf_states_sent;
        r.keys += st.key_states_sent - before[k].key_states_sent;
        r.skips += st.quiescent_skips - before[k].quiescent_skips;
        r.capped += st.capped_skips - before[k].capped_skips;
        r.misses += st.baseline_misses;
    }
    const double n = static_cast<double>(s.size());
    r.bytes_per_peer_s /= n * seconds;
    r.packets_per_peer_s /= n * seconds;
    r.owned_nodes /= n;
    for (const core::NodeIndex node : grid.node_of_unique())
    {
        const core::GridCoord c = grid.coord(node);
        r.max_u = std::max(r.max_u, std::fabs(s[0]->display_u().at(c.x, c.y)));
    }
    return r;
}

/// `pliant_bench_session --stream [level] [--seconds S]`: raw f64 and f32 against quantised
/// deltas, measured over S simulated seconds (default 2; docs/session.md §4.2 uses 12 to show
/// that fast coupling stays bounded under continuous drags).
void stream_suite(bench::Report& report, int level, double seconds)
{
    constexpr double k_header_bytes = 38.0;  // UDP/IP + ENet per datagram (docs/results.md)
    std::printf(
        "# streaming, level %d, 2 participants dragging continuously, fast coupling, "
        "60 Hz, %.0f s measured after 0.5 s\n",
        level, seconds);
    std::printf(
        "drag | encoding | bits per node per frame, per node sent | Mbit/s out per peer "
        "(+%g B headers) | "
        "updates/s per leaf | LeafStates quiescent capped | max |u| m\n",
        k_header_bytes);
    struct Drag
    {
        const char* name;
        double hz, newton;
    };
    struct Case
    {
        const char* name;
        net::ValueEncoding encoding;
        int u_exp, v_exp;
        double cap;
        net::Packing packing = net::Packing::Rice;
        bool batch = true;
        double ack_hz = 60.0;
    };
    constexpr auto zstd = net::Packing::Zstd;
    constexpr auto rice = net::Packing::Rice;
    constexpr auto q = net::ValueEncoding::QuantisedDelta;
    const Drag drags[] = {{"strong", 1.0, 0.5}, {"moderate", 0.25, 0.2}};
    const Case cases[] = {
        {"f64", net::ValueEncoding::F64, -16, -12, 0.0},
        {"f32", net::ValueEncoding::F32, -16, -12, 0.0},
        // Version 3's coding: zstd-packed varints, one LeafState per leaf, acks at 20 Hz (the
        // acks in version 4's compact layout).
        {"v3 q 2^-16 2^-12", q, -16, -12, 0.0, zstd, false, 20.0},
        {"v3 q 2^-16 2^-12 cap 1.8", q, -16, -12, 1.8, zstd, false, 20.0},
        // Version 4, one step at a time: Rice, then batches, then acks at 60 Hz.
        {"rice q 2^-16 2^-12 ack 20", q, -16, -12, 0.0, rice, false, 20.0},
        {"batch q 2^-16 2^-12 ack 20", q, -16, -12, 0.0, rice, true, 20.0},
        {"v4 q 2^-16 2^-12", q, -16, -12, 0.0},
        {"v4 q 2^-20 2^-16", q, -20, -16, 0.0},
        {"v4 q 2^-14 2^-10 (default)", q, -14, -10, 0.0},
        {"v4 q 2^-12 2^-8", q, -12, -8, 0.0},
        {"v4 q 2^-14 2^-10 cap 1.0", q, -14, -10, 1.0},
    };
    const double leaves = static_cast<double>(
        2u << (2 * session::leaf_depth_for(core::TetraGrid::create(level).value(),
                                           net::ValueEncoding::F64)));
    for (const Drag& d : drags)
        for (const Case& c : cases)
        {
            const StreamResult r = run_stream(level, c.encoding, seconds, c.u_exp, c.v_exp, d.hz,
                                              d.newton, c.cap, c.packing, c.batch, c.ack_hz);
            const double bits_node = 8.0 * r.bytes_per_peer_s / (60.0 * r.owned_nodes);
            const double mbit = 8.0 * r.bytes_per_peer_s / 1e6;
            const double mbit_h =
                8.0 * (r.bytes_per_peer_s + k_header_bytes * r.packets_per_peer_s) / 1e6;
            const double rate = static_cast<double>(r.leaf_states) / (leaves * seconds);
            // Per node actually sent (LeafStates x mean nodes per leaf), everything out counted.
            const double node_updates_per_peer_s =
                static_cast<double>(r.leaf_states) / 2.0 / seconds * (2.0 * r.owned_nodes / leaves);
            const double bits_sent_node = 8.0 * r.bytes_per_peer_s / node_updates_per_peer_s;
            std::printf(
                "%-8s | %-26s | %6.2f %6.2f | %6.2f (%6.2f) | %5.1f | %llu %llu %llu | "
                "%.4f\n",
                d.name, c.name, bits_node, bits_sent_node, mbit, mbit_h, rate,
                static_cast<unsigned long long>(r.leaf_states),
                static_cast<unsigned long long>(r.skips), static_cast<unsigned long long>(r.capped),
                r.max_u);
            const std::string name = std::string("stream ") + d.name + " " + c.name;
            report.add(name, level, r.owned_nodes, "nodes", "bits_per_node_frame", bits_node,
                       "bit");
            report.add(name, level, r.owned_nodes, "nodes", "bits_per_node_sent", bits_sent_node,
                       "bit");
            report.add(name, level, r.owned_nodes, "nodes", "mbit_s_out_per_peer", mbit, "Mbit/s");
            report.add(name, level, r.owned_nodes, "nodes", "mbit_s_out_per_peer_with_headers",
                       mbit_h, "Mbit/s");
            report.add(name, level, r.owned_nodes, "nodes", "updates_per_leaf_s", rate, "1/s");
            if (r.misses != 0)
                std::printf("  (baseline misses: %llu)\n",
                            static_cast<unsigned long long>(r.misses));
        }
}

/// Coarse streaming (docs/session.md §5.2): two participants in `exact` coupling dragging as in
/// run_stream, streaming `k` levels coarser, and a viewer. Measured over `seconds` after 0.5 s:
/// the leaf-state bytes the viewer receives per second (the whole object's stream into one peer,
/// no halos: viewers get none), and at every frame the display error of the refined field,
/// refine_levels(restrict^k(S)) - S over every node, with S the owners' current state (what a
/// receiver shows once S has arrived: tests/session/coarse_stream_test.cpp checks it bit for
/// bit), and the viewer's display against S (which adds the stream's latency).
struct CoarseResult
{
    double bytes_in_per_s = 0.0;  // viewer, payload bytes
    double packets_in_per_s = 0.0;
    double refine_max = 0.0, refine_rms = 0.0;  // relative to max |u| and rms u of S
    double view_max = 0.0, view_rms = 0.0;
    double sim_per_clock = 0.0;  // simulated seconds per clock second (the lockstep's pace)
};

CoarseResult run_coarse(int level, int k, double seconds)
{
    // A LAN: 0.1 ms one way, so that the lockstep keeps up with the clock (with the default 5 ms
    // each tick waits a round trip and the drag would move little in `seconds`).
    net::SimulatedNetworkSettings lan;
    lan.link.latency_s = 1e-4;
    net::SimulatedNetwork network(lan);
    std::vector<std::unique_ptr<net::Transport>> tr;
    std::vector<std::unique_ptr<session::Session>> s;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    session::SessionSettings set;
    set.coupling = session::Coupling::Exact;
    set.stream_coarsen = k;
    tr.push_back(network.create_endpoint());
    const net::Address master = tr.back()->open({}).value();
    s.push_back(
        session::Session::host(*tr.back(), grid, scenes::sphere_grid(grid, 1.0), material(), set)
            .value());
    for (const net::Role role : {net::Role::Participant, net::Role::Viewer})
    {
        tr.push_back(network.create_endpoint());
        (void)tr.back()->open({}).value();
        s.push_back(session::Session::join(*tr.back(), master, role, set).value());
    }
    const auto faces = static_cast<std::uint32_t>(grid.face_count());
    s[1]->set_points_of_interest({net::Target{net::TargetKind::Face, faces / 2, {0, 0, 0}, 0.0}});
    const double dt = 0.0005;
    double now = 0.0;
    const auto pump = [&] { pump_sessions(s, network, now, dt); };
    for (int it = 0; it < 40000; ++it)
    {
        const auto owners = s[0]->owners();
        if (s[1]->ready() && s[2]->ready() &&
            std::find(owners.begin(), owners.end(), s[1]->id()) != owners.end())
            break;
        pump();
    }
    const double poles[2] = {1.0, -1.0};
    auto drag = [&](double t)
    {
        for (int p = 0; p < 2; ++p)
        {
            net::UserForce f;
            f.target.kind = net::TargetKind::Position;
            f.target.position = {0.0, 0.0, poles[p]};
            f.target.radius = 0.3;
            const double a = 2.0 * 3.141592653589793 * t + p;
            f.force = {0.5 * std::cos(a), 0.5 * std::sin(a), -0.3 * poles[p]};
            must(s[static_cast<std::size_t>(p)]->set_forces({f}));
        }
    };
    const auto plans =
        k > 0 ? subdiv::make_plans(level - k, k).value() : std::vector<subdiv::ConvolutionPlan>{};
    core::Field<double> truth(grid);
    CoarseResult r;
    double frames_measured = 0.0;
    auto measure = [&]
    {
        const auto owners = s[0]->owners();
        const session::LeafGraph& graph = *s[0]->leaf_graph();
        for (std::size_t l = 0; l < graph.size(); ++l)
        {
            const session::Session& o = owners[l] == s[0]->id() ? *s[0] : *s[1];
            for (const core::NodeIndex n : graph.nodes(l))
            {
                const core::GridCoord c = grid.coord(n);
                truth.at(c.x, c.y) = o.state().u.at(c.x, c.y);
            }
        }
        core::sync_twins(grid, truth);
        core::Field<double> shown = truth;
        if (k > 0)
        {
            core::Field<double> c = subdiv::restrict(plans[static_cast<std::size_t>(k - 1)], truth);
            for (int j = 2; j <= k; ++j)
                c = subdiv::restrict(plans[static_cast<std::size_t>(k - j)], c);
            shown = subdiv::refine_levels<double>(plans, c);
        }
        double max_u = 0.0, sum_u = 0.0, max_e = 0.0, sum_e = 0.0, max_v = 0.0, sum_v = 0.0;
        for (const core::NodeIndex n : grid.node_of_unique())
        {
            const core::GridCoord c = grid.coord(n);
            const double u = truth.at(c.x, c.y);
            const double e = shown.at(c.x, c.y) - u;
            const double w = s[2]->display_u().at(c.x, c.y) - u;
            max_u = std::max(max_u, std::fabs(u));
            max_e = std::max(max_e, std::fabs(e));
            max_v = std::max(max_v, std::fabs(w));
            sum_u += u * u;
            sum_e += e * e;
            sum_v += w * w;
        }
        if (max_u <= 0.0)
            return;
        r.refine_max = std::max(r.refine_max, max_e / max_u);
        r.view_max = std::max(r.view_max, max_v / max_u);
        r.refine_rms += std::sqrt(sum_e / sum_u);
        r.view_rms += std::sqrt(sum_v / sum_u);
        frames_measured += 1.0;
    };
    const int per_frame = static_cast<int>(std::lround(1.0 / 60.0 / dt));
    auto run_for = [&](double span, bool measuring)
    {
        const int frames = static_cast<int>(std::lround(span * 60.0));
        for (int f = 0; f < frames; ++f)
        {
            drag(now);
            for (int i = 0; i < per_frame; ++i)
                pump();
            if (measuring)
                measure();
        }
    };
    run_for(0.5, false);
    const session::SessionStats before = s[2]->stats();
    const double t0 = s[0]->time();
    run_for(seconds, true);
    // The stream runs on the clock (60 Hz of `now`), so rates are per clock second.
    r.sim_per_clock = (s[0]->time() - t0) / seconds;
    const session::SessionStats after = s[2]->stats();
    r.bytes_in_per_s = static_cast<double>(after.bytes_received - before.bytes_received) / seconds;
    r.packets_in_per_s =
        static_cast<double>(after.packets_received - before.packets_received) / seconds;
    r.refine_rms /= std::max(frames_measured, 1.0);
    r.view_rms /= std::max(frames_measured, 1.0);
    return r;
}

/// `pliant_bench_session --coarse [levels...] [--seconds S]`: coarse streaming, k = 0, 1, 2.
void coarse_suite(bench::Report& report, const std::vector<int>& levels, double seconds)
{
    std::printf(
        "# coarse streaming: 2 participants dragging 0.5 N turning at 1 Hz, exact coupling, "
        "and a viewer; 0.1 ms links; 60 Hz; %.1f s after 0.5 s\n",
        seconds);
    std::printf(
        "level k | viewer in: MB/s, datagrams/s, x less than k=0 | "
        "refined vs owner: max rel, rms rel | viewer shown vs owner now: max rel, rms rel | "
        "sim s per s\n");
    for (const int level : levels)
    {
        double full = 0.0;
        for (int k = 0; k <= k_coarsest; ++k)
        {
            const CoarseResult r = run_coarse(level, k, seconds);
            if (k == 0)
                full = r.bytes_in_per_s;
            std::printf("%d %d | %7.3f %7.0f %5.2f | %.2e %.2e | %.2e %.2e | %.2f\n", level, k,
                        r.bytes_in_per_s / 1e6, r.packets_in_per_s, full / r.bytes_in_per_s,
                        r.refine_max, r.refine_rms, r.view_max, r.view_rms, r.sim_per_clock);
            const std::string name = "coarse stream k=" + std::to_string(k);
            const double nodes =
                static_cast<double>(core::TetraGrid::create(level).value().node_count());
            report.add(name, level, nodes, "nodes", "viewer_bytes_in_per_s", r.bytes_in_per_s,
                       "B/s");
            report.add(name, level, nodes, "nodes", "refine_error_max_rel", r.refine_max, "1");
            report.add(name, level, nodes, "nodes", "refine_error_rms_rel", r.refine_rms, "1");
            report.add(name, level, nodes, "nodes", "view_error_max_rel", r.view_max, "1");
            report.add(name, level, nodes, "nodes", "view_error_rms_rel", r.view_rms, "1");
        }
    }
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

double thread_cpu_s()
{
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// One seat layout's steps (steps_suite): each peer's restricted step against the full step, per
/// partition, and the partitions' kinds (g grown shares, s slabs, r whole-row slabs, t turned
/// slabs, w wide shares, b blocks).
struct LayoutSteps
{
    char fast_kind = 'g';
    char exact_kind = 'g';
    char inside_kind = 'g';
    std::vector<double> fast;    // per peer, / full
    std::vector<double> exact;   // per peer, / full
    std::vector<double> inside;  // per peer, / full: fast coupling under clearance Inside
    double full_s = 0.0;         // one process's full step, seconds
};

/// The steps of one level (steps_suite): its model, leaf graph and the session runs' two pulls.
class LevelSteps
{
public:
    LevelSteps(int level, bool keep_outside)
        : grid_(core::TetraGrid::create(level).value()),
          model_(sim::MembraneModel::create(grid_, scenes::sphere_grid(grid_, 1.0), material())
                     .value()),
          graph_(grid_, session::leaf_depth_for(grid_, net::ValueEncoding::F64)),
          keep_outside_(keep_outside)
    {
        const auto faces = static_cast<std::uint32_t>(grid_.face_count());
        forces_ = {session::to_sim_force(pull(faces / 7)),
                   session::to_sim_force(pull(faces / 2 + 5))};
        steps_ = std::max(20, static_cast<int>(4e6 / static_cast<double>(grid_.node_count())));
    }

    [[nodiscard]] const core::TetraGrid& grid() const noexcept { return grid_; }

    /// Each coupling's partition of `seats` (session::PointClearance: AsGrown for fast, Inside for
    /// exact, and fast under Inside, the partition of SessionSettings::point_clearance = Inside),
    /// stepped: best of `rounds` interleaved rounds.
    [[nodiscard]] LayoutSteps measure(std::span<const session::Seat> seats, int rounds)
    {
        const std::size_t peers = seats.size();
        const auto fast_owners = session::partition_leaves(grid_, graph_, seats);
        const auto inside_owners =
            session::partition_leaves(grid_, graph_, seats, session::PointClearance::Inside);
        const auto exact_owners = session::partition_leaves(
            grid_, graph_, seats, session::PointClearance::Inside, session::k_exact_ring_cost);
        std::vector<std::vector<core::Region>> fast_sets(peers);
        std::vector<std::vector<core::Region>> inside_sets(peers);
        // Exact coupling: the own set dilated by the halo, computed where the own nodes read it
        // (StepOptions::needed), as the session steps.
        std::vector<std::vector<core::Region>> exact_sets(peers);
        std::vector<std::vector<core::Region>> exact_own(peers);
        for (std::size_t p = 0; p < peers; ++p)
        {
            const net::PeerId id = seats[p].peer;
            std::vector<char> mask(grid_.node_count(), 0);
            for (std::size_t l = 0; l < fast_owners.size(); ++l)
            {
                if (fast_owners[l] == id)
                    fast_sets[p].push_back(graph_.regions()[l]);
                if (inside_owners[l] == id)
                    inside_sets[p].push_back(graph_.regions()[l]);
                if (exact_owners[l] == id)
                    for (const core::NodeIndex n : graph_.nodes(l))
                        mask[n.value] = 1;
            }
            exact_own[p] = core::node_runs(grid_, mask);
            exact_sets[p] = core::node_runs(
                grid_,
                core::dilate_nodes(grid_, std::move(mask), session::SessionSettings{}.halo_rings));
        }
        LayoutSteps out;
        out.fast_kind = kind(seats, fast_owners);
        out.exact_kind = kind(seats, exact_owners);
        out.inside_kind = kind(seats, inside_owners);
        double full = 1e30;
        out.fast.assign(peers, 1e30);
        out.exact.assign(peers, 1e30);
        out.inside.assign(peers, 1e30);
        const bool same = inside_owners == fast_owners;
        for (int round = 0; round < rounds; ++round)
        {
            full = std::min(full, time_steps({}));
            for (std::size_t p = 0; p < peers; ++p)
            {
                out.fast[p] = std::min(out.fast[p], time_steps(fast_sets[p]));
                out.exact[p] = std::min(out.exact[p], time_steps(exact_sets[p], exact_own[p]));
                if (!same)
                    out.inside[p] = std::min(out.inside[p], time_steps(inside_sets[p]));
            }
        }
        if (same)
            out.inside = out.fast;
        for (std::vector<double>* t : {&out.fast, &out.exact, &out.inside})
            for (double& x : *t)
                x /= full;
        out.full_s = full;
        return out;
    }

private:
    /// The seconds of one step over `owned` (thread CPU time, the mean of steps_ steps after 3).
    double time_steps(std::span<const core::Region> owned,
                      std::span<const core::Region> needed = {})
    {
        sim::MembraneState st = sim::MembraneState::at_rest(grid_);
        sim::Rkf45Workspace ws(model_, 1);
        sim::StepOptions opt;
        opt.owned = owned;
        opt.needed = needed;
        opt.keep_outside = keep_outside_;  // the session's peers: false
        for (int k = 0; k < 3; ++k)
            (void)sim::step(model_, st, ws, forces_, opt);
        const double t0 = thread_cpu_s();
        for (int k = 0; k < steps_; ++k)
            (void)sim::step(model_, st, ws, forces_, opt);
        return (thread_cpu_s() - t0) / steps_;
    }

    char kind(std::span<const session::Seat> seats, const std::vector<net::PeerId>& owners) const
    {
        if (owners == session::grown_partition(grid_, graph_, seats))
            return 'g';
        if (owners == session::slab_partition(grid_, graph_, seats))
            return 's';
        if (owners == session::slab_partition(grid_, graph_, seats, 0, true))
            return 'r';
        for (const std::uint32_t row_hop : session::k_wide_row_hops)
            if (owners == session::wide_partition(grid_, graph_, seats, row_hop))
                return 'w';
        for (const auto& parts : session::block_layouts(seats.size()))
            if (owners == session::block_partition(grid_, graph_, seats, parts))
                return 'b';
        return 't';
    }

    core::TetraGrid grid_;
    sim::MembraneModel model_;
    session::LeafGraph graph_;
    std::vector<sim::Force> forces_;
    int steps_ = 20;
    bool keep_outside_ = false;
};

/// The largest and the mean of per-peer ratios.
std::pair<double, double> max_mean(const std::vector<double>& t)
{
    double worst = 0.0;
    double sum = 0.0;
    for (const double x : t)
    {
        worst = std::max(worst, x);
        sum += x;
    }
    return {worst, sum / static_cast<double>(t.size())};
}

/// --steps: the sim step alone, in thread CPU time (which the load of a shared machine inflates
/// far less than the wall time the session counters use): per level and peer count, each peer's
/// restricted step over its fast set (its leaves) and over its exact set (its leaves dilated by
/// the default halo_rings, as node runs) against the full step of one process; fixed dt 1 ms,
/// the two pulls of the session runs held on, one thread. Best of 5 interleaved rounds.
/// Accepted steps swap planes as the session's do, or, with `keep_outside` (--copy-accept),
/// copy their result back (sim::StepOptions::keep_outside).
/// Two seat layouts: no points of interest, and the session runs' (participant k declares face
/// k F / P, the master none). Each coupling gets the partition a session of it computes
/// (session::PointClearance: AsGrown for fast, Inside for exact), named g (grown shares) or s
/// (slabs); a last column steps fast coupling's own sets under Inside, the partition of
/// SessionSettings::point_clearance = Inside.
void steps_suite(bench::Report& report, const std::vector<int>& levels, bool keep_outside)
{
    std::printf(
        "# sim step CPU per peer / full step (thread CPU time, best of 5 rounds, 1 "
        "thread); partition: g grown shares, s slabs, r whole-row slabs, t turned slabs, w wide "
        "shares, b "
        "blocks\nlevel "
        "peers points | fast: max mean | exact: max mean | full step us | fast, clearance "
        "inside: max mean\n");
    for (const int level : levels)
    {
        LevelSteps steps(level, keep_outside);
        for (int peers = 2; peers <= 4; ++peers)
            for (const bool points : {false, true})
            {
                const std::vector<session::Seat> seats = session_seats(steps.grid(), peers, points);
                const LayoutSteps m = steps.measure(seats, 5);
                const auto [fmax, fmean] = max_mean(m.fast);
                const auto [emax, emean] = max_mean(m.exact);
                const auto [imax, imean] = max_mean(m.inside);
                std::printf("%5d %5d %6s | %c %.2f %.2f | %c %.2f %.2f | %12.0f | %c %.2f %.2f\n",
                            level, peers, points ? "yes" : "none", m.fast_kind, fmax, fmean,
                            m.exact_kind, emax, emean, m.full_s * 1e6, m.inside_kind, imax, imean);
                std::fflush(stdout);
                const double n = static_cast<double>(peers);
                const std::string fast_name =
                    points ? "step only, fast, session points" : "step only, fast";
                const std::string exact_name =
                    points ? "step only, exact, session points" : "step only, exact";
                report.add(fast_name, level, n, "peers", "step_cpu_vs_full_max", fmax, "1");
                report.add(fast_name, level, n, "peers", "step_cpu_vs_full_mean", fmean, "1");
                report.add(exact_name, level, n, "peers", "step_cpu_vs_full_max", emax, "1");
                report.add(exact_name, level, n, "peers", "step_cpu_vs_full_mean", emean, "1");
                const std::string inside_name = fast_name + ", clearance inside";
                report.add(inside_name, level, n, "peers", "step_cpu_vs_full_max", imax, "1");
                report.add(inside_name, level, n, "peers", "step_cpu_vs_full_mean", imean, "1");
            }
    }
}

/// The compute target for the busiest peer against one process (docs/session.md §8): 55 %
/// with 2 peers, 30 % with 4; none given for 3 (NaN).
double compute_target(int peers)
{
    return peers == 2 ? 0.55 : peers == 4 ? 0.30 : std::numeric_limits<double>::quiet_NaN();
}

/// --steps --random-points N: as steps_suite, over N seat layouts per level and peer count in
/// which every member (the master too) declares a face drawn uniformly (a fixed seed per level
/// and peer count, so a rerun draws the same layouts): per coupling's partition, the median and
/// the largest busiest-peer ratio over the layouts, how many meet compute_target, and how many
/// layouts took each kind of partition. Best of 3 rounds per layout.
void random_steps_suite(bench::Report& report, const std::vector<int>& levels, int layouts,
                        bool keep_outside)
{
    std::printf(
        "# sim step CPU of the busiest peer / full step over %d random point layouts "
        "(every member declares a uniformly drawn face; thread CPU time, best of 3 "
        "rounds, 1 thread): median, worst, layouts within the target (55 %% with 2 "
        "peers, 30 %% with 4), partitions taken (g grown, s slabs, r whole-row, t turned, w "
        "wide, b blocks)\n"
        "level peers | fast: median worst met kinds | exact: median worst met kinds | "
        "fast, clearance inside: median worst met kinds\n",
        layouts);
    for (const int level : levels)
    {
        LevelSteps steps(level, keep_outside);
        const core::TetraGrid& grid = steps.grid();
        const auto faces = static_cast<std::uint64_t>(grid.face_count());
        const auto w2 = static_cast<std::uint64_t>(2 * grid.w());
        for (int peers = 2; peers <= 4; ++peers)
        {
            std::mt19937_64 rng(static_cast<std::uint64_t>(1000 * level + peers));
            std::uniform_int_distribution<std::uint64_t> draw(0, faces - 1);
            struct Column
            {
                std::vector<double> busiest;
                std::string kinds;
            };
            std::array<Column, 3> cols;  // fast, exact, fast under Inside
            for (int k = 0; k < layouts; ++k)
            {
                std::vector<session::Seat> seats;
                for (int p = 0; p < peers; ++p)
                {
                    const std::uint64_t cell = draw(rng) / 2;  // two faces per cell
                    seats.push_back({net::PeerId{static_cast<std::uint16_t>(p)},
                                     grid.canonical(grid.index(static_cast<int>(cell % w2),
                                                               static_cast<int>(cell / w2)))});
                }
                const LayoutSteps m = steps.measure(seats, 3);
                cols[0].busiest.push_back(max_mean(m.fast).first);
                cols[0].kinds += m.fast_kind;
                cols[1].busiest.push_back(max_mean(m.exact).first);
                cols[1].kinds += m.exact_kind;
                cols[2].busiest.push_back(max_mean(m.inside).first);
                cols[2].kinds += m.inside_kind;
            }
            const double target = compute_target(peers);
            std::printf("%5d %5d", level, peers);
            const std::array<const char*, 3> names = {"random points, fast", "random points, exact",
                                                      "random points, fast, clearance inside"};
            for (std::size_t c = 0; c < cols.size(); ++c)
            {
                std::vector<double> b = cols[c].busiest;
                std::sort(b.begin(), b.end());
                const double median = b.size() % 2 == 1
                                          ? b[b.size() / 2]
                                          : 0.5 * (b[b.size() / 2 - 1] + b[b.size() / 2]);
                const auto met =
                    std::count_if(b.begin(), b.end(), [&](double x) { return x <= target; });
                std::string kinds;
                for (const char kc : {'g', 's', 'r', 't', 'w', 'b'})
                    if (const auto n = std::count(cols[c].kinds.begin(), cols[c].kinds.end(), kc))
                        kinds += std::to_string(n) + kc;
                if (std::isnan(target))
                    std::printf(" | %.2f %.2f   - %s", median, b.back(), kinds.c_str());
                else
                    std::printf(" | %.2f %.2f %3ld %s", median, b.back(), static_cast<long>(met),
                                kinds.c_str());
                const double n = static_cast<double>(peers);
                report.add(names[c], level, n, "peers", "busiest_step_vs_full_median", median, "1");
                report.add(names[c], level, n, "peers", "busiest_step_vs_full_worst", b.back(),
                           "1");
                if (!std::isnan(target))
                    report.add(names[c], level, n, "peers", "layouts_within_target",
                               static_cast<double>(met) / static_cast<double>(b.size()), "1");
            }
            std::printf("\n");
            std::fflush(stdout);
        }
    }
}

/// When a grab first shows on one peer (virtual seconds after it was given; < 0: not within the
/// run): the grabbed face's nodes 1 mm from rest, in what the peer holds (display_u: its own leaves
/// live, the others' newest states) and in what it draws (view_u: the others' leaves interpolated,
/// docs/session.md §5.3).
struct GrabSeen
{
    double display_mm = -1.0;
    double view_mm = -1.0;
};

/// Participant k's point of interest in the latency runs (as `run`): face k F / P.
net::Target seat_face(std::uint32_t faces, int k, int peers)
{
    return net::Target{net::TargetKind::Face,
                       static_cast<std::uint32_t>(k) * faces / static_cast<std::uint32_t>(peers),
                       {0, 0, 0},
                       0.0};
}

/// The latency runs' grab: `face` pulled with 0.5 N along the outward radius of its centre.
net::UserForce outward_pull(const core::TetraGrid& grid, const core::Vec3Field<double>& rest,
                            std::uint32_t face)
{
    core::Vec3 centre{};
    for (const std::uint32_t n : grid.node_triangles()[face])
    {
        const core::GridCoord c = grid.coord(core::NodeIndex{n});
        centre =
            centre + core::Vec3{rest[0].at(c.x, c.y), rest[1].at(c.x, c.y), rest[2].at(c.x, c.y)};
    }
    const core::Vec3 out = centre * (0.5 / core::norm(centre));
    net::UserForce f;
    f.target.kind = net::TargetKind::Face;
    f.target.face = face;
    f.force = {out.x, out.y, out.z};
    return f;
}

/// The largest |u| at a face's nodes.
double largest_on(const core::TetraGrid& grid, const core::Field<double>& u,
                  const std::array<std::uint32_t, 3>& nodes)
{
    double m = 0.0;
    for (const std::uint32_t n : nodes)
    {
        const core::GridCoord c = grid.coord(core::NodeIndex{n});
        m = std::max(m, std::fabs(u.at(c.x, c.y)));
    }
    return m;
}

/// `pliant_bench_session --latency`: `peers` participants (master included, the same points of
/// interest as `run`) and one viewer over the simulated network (`latency_s` one-way, streams
/// and frames at 60 Hz); once every participant owns leaves and 0.2 s more, the last participant
/// pulls the face of its own point of interest (0.5 N along the outward radius), `delay_s` later
/// still (the grab's phase against the streams). Per peer, when the grab shows (index
/// 0..peers-1 the participants, the last one the grabber, then the viewer).
std::vector<GrabSeen> run_latency(int level, int peers, session::Coupling coupling,
                                  double latency_s, double delay_s)
{
    net::SimulatedNetworkSettings net_settings;
    net_settings.link.latency_s = latency_s;
    net::SimulatedNetwork network(net_settings);
    std::vector<std::unique_ptr<net::Transport>> tr;
    std::vector<std::unique_ptr<session::Session>> s;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    const auto rest = scenes::sphere_grid(grid, 1.0);
    session::SessionSettings set;
    set.coupling = coupling;
    tr.push_back(network.create_endpoint());
    const net::Address master = tr.back()->open({}).value();
    s.push_back(session::Session::host(*tr.back(), grid, rest, material(), set).value());
    const auto faces = static_cast<std::uint32_t>(grid.face_count());
    const std::uint32_t grabbed = seat_face(faces, peers - 1, peers).face;
    for (int k = 1; k <= peers; ++k)
    {
        tr.push_back(network.create_endpoint());
        (void)tr.back()->open({}).value();
        const bool viewer = k == peers;
        s.push_back(session::Session::join(*tr.back(), master,
                                           viewer ? net::Role::Viewer : net::Role::Participant, set)
                        .value());
        if (!viewer)
            s.back()->set_points_of_interest({seat_face(faces, k, peers)});
    }
    const double dt = 0.00025;
    double now = 0.0;
    const auto pump = [&] { pump_sessions(s, network, now, dt); };
    const auto partitioned = [&]
    {
        for (const auto& p : s)
            if (!p->ready())
                return false;
        const auto owners = s[0]->owners();
        for (int k = 0; k < peers; ++k)
            if (std::find(owners.begin(), owners.end(), s[static_cast<std::size_t>(k)]->id()) ==
                owners.end())
                return false;
        return true;
    };
    for (int it = 0; it < 400000 && !partitioned(); ++it)
        pump();
    const double settle = now + 0.2 + delay_s;  // streams and views settle
    for (int it = 0; it < 400000 && now < settle; ++it)
        pump();
    // The grab: the last participant's own face, along the outward radius.
    const auto nodes = grid.node_triangles()[grabbed];
    const net::UserForce f = outward_pull(grid, rest, grabbed);
    must(s[static_cast<std::size_t>(peers - 1)]->set_forces({f}));
    const double t_grab = now;
    std::vector<GrabSeen> seen(s.size());
    const auto largest = [&](const core::Field<double>& u) { return largest_on(grid, u, nodes); };
    const auto done = [&]
    {
        for (const GrabSeen& g : seen)
            if (g.view_mm < 0.0)
                return false;
        return true;
    };
    // Bounded: at most 1 s of virtual time after the grab.
    for (int it = 0; it < 4000 && !done(); ++it)
    {
        pump();
        const double t = now - t_grab;
        for (std::size_t k = 0; k < s.size(); ++k)
        {
            const double d = largest(s[k]->display_u());
            const double v = largest(s[k]->view_u());
            if (seen[k].display_mm < 0.0 && d >= 1e-3)
                seen[k].display_mm = t;
            if (seen[k].view_mm < 0.0 && v >= 1e-3)
                seen[k].view_mm = t;
        }
    }
    return seen;
}

/// `--latency --enet`: the same grab in real time over ENet on 127.0.0.1, every peer in its own
/// thread running the CLI's loop (poll, advance to its wall clock, 0.2 ms sleep), so compute,
/// scheduling and the sockets are in the figures. The grabber pulls once it owns leaves and
/// 0.3 s more; each peer records when the face first stands 1 mm from rest (wall seconds after
/// the grab; < 0: not within 2 s). Empty when the session could not be set up.
std::vector<GrabSeen> run_latency_enet(int level, int peers, session::Coupling coupling)
{
    using Clock = std::chrono::steady_clock;
    struct Peer
    {
        std::unique_ptr<net::Transport> transport;
        std::unique_ptr<session::Session> session;
        net::Address address;
    };
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    const auto rest = scenes::sphere_grid(grid, 1.0);
    std::vector<Peer> ps(static_cast<std::size_t>(peers) + 1);  // participants, then the viewer
    for (Peer& p : ps)
    {
        p.transport = net::make_enet_transport();
        auto bound = p.transport->open(net::Address{{127, 0, 0, 1}, 0});
        if (!bound)
            return {};
        p.address = *bound;
    }
    session::SessionSettings set;
    set.coupling = coupling;
    set.threads = 1;
    const auto settings_for = [&](const Peer& p)
    {
        session::SessionSettings one = set;
        one.listen_port = p.address.port;
        return one;
    };
    auto hosted =
        session::Session::host(*ps[0].transport, grid, rest, material(), settings_for(ps[0]));
    if (!hosted)
        return {};
    ps[0].session = std::move(*hosted);
    const auto faces = static_cast<std::uint32_t>(grid.face_count());
    const std::uint32_t grabbed = seat_face(faces, peers - 1, peers).face;
    for (int k = 1; k <= peers; ++k)
    {
        Peer& p = ps[static_cast<std::size_t>(k)];
        const bool viewer = k == peers;
        auto joined = session::Session::join(*p.transport, ps[0].address,
                                             viewer ? net::Role::Viewer : net::Role::Participant,
                                             settings_for(p));
        if (!joined)
            return {};
        p.session = std::move(*joined);
        if (!viewer)
            p.session->set_points_of_interest({seat_face(faces, k, peers)});
    }
    const auto nodes = grid.node_triangles()[grabbed];
    const net::UserForce f = outward_pull(grid, rest, grabbed);

    const auto start = Clock::now();
    const auto elapsed = [&]
    { return std::chrono::duration<double>(Clock::now() - start).count(); };
    std::atomic<double> t_grab{-1.0};
    std::atomic<bool> stop{false};
    std::atomic<int> seen_count{0};
    std::vector<GrabSeen> at(ps.size());  // absolute times; each written by its own thread
    const auto largest = [&](const core::Field<double>& u) { return largest_on(grid, u, nodes); };
    const std::size_t grabber = static_cast<std::size_t>(peers - 1);
    std::vector<std::thread> threads;
    for (std::size_t k = 0; k < ps.size(); ++k)
        threads.emplace_back(
            [&, k]
            {
                session::Session& p = *ps[k].session;
                double owned_since = -1.0;
                // Bounded by the 30 s limit below (the main thread sets `stop`).
                while (!stop.load())
                {
                    p.poll();
                    const double now = elapsed();
                    p.advance(now);
                    if (k == grabber && p.ready() && t_grab.load() < 0.0)
                    {
                        const auto owners = p.owners();
                        if (owned_since < 0.0 &&
                            std::find(owners.begin(), owners.end(), p.id()) != owners.end())
                            owned_since = now;
                        if (owned_since >= 0.0 && now >= owned_since + 0.3)
                        {
                            must(p.set_forces({f}));
                            t_grab.store(elapsed());
                        }
                    }
                    if (p.ready() && at[k].view_mm < 0.0)
                    {
                        if (at[k].display_mm < 0.0 && largest(p.display_u()) >= 1e-3)
                            at[k].display_mm = elapsed();
                        if (largest(p.view_u()) >= 1e-3)
                        {
                            at[k].view_mm = elapsed();
                            seen_count.fetch_add(1);
                        }
                    }
                    if (!p.behind())  // as run_peer: no wait while behind real time
                        p.wait(200e-6);
                }
            });
    // Bounded: 30 s for the set-up and the grab, 2 s after the grab for it to show everywhere.
    while (elapsed() < 30.0)
    {
        const double tg = t_grab.load();
        if (seen_count.load() == static_cast<int>(ps.size()) || (tg >= 0.0 && elapsed() > tg + 2.0))
            break;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    stop.store(true);
    for (std::thread& t : threads)
        t.join();
    const double tg = t_grab.load();
    std::vector<GrabSeen> seen(ps.size());
    for (std::size_t k = 0; k < ps.size(); ++k)
    {
        if (tg >= 0.0 && at[k].display_mm >= 0.0)
            seen[k].display_mm = at[k].display_mm - tg;
        if (tg >= 0.0 && at[k].view_mm >= 0.0)
            seen[k].view_mm = at[k].view_mm - tg;
    }
    ps[0].session->shutdown();
    return seen;
}

/// --cpu: all the work of each peer (its poll() and advance() calls: steps, halos, heartbeats,
/// streams, display and view) per simulated second, in the steady state (every peer in the
/// partition), against one peer alone in its own session; 1..4 participants with the session
/// runs' points and pulls, exact and fast coupling, a LAN (0.5 ms one-way, so the exact lockstep
/// keeps its 1 kHz), 1,000 ticks of 1 ms, 60 Hz frames and streams, one thread per peer. All
/// peers share this one thread and its caches, so the figures include what the others' traffic
/// evicts; wall time of the calls (the machine's other load shows in them).
void cpu_suite(bench::Report& report, const std::vector<int>& levels)
{
    const int rounds = report.quick() ? 1 : 3;
    report.meta("network", "SimulatedNetwork, 0.5 ms one-way latency, all peers in one thread");
    report.meta("material", "unit sphere, T=1, rho=1, beta=0.5, k_f=1, fixed dt 1 ms");
    constexpr std::uint64_t ticks = 1000;
    constexpr double lan_s = 0.0005;
    std::printf(
        "# all work per peer (poll + advance) per simulated second, steady state, LAN 0.5 ms, "
        "%llu ticks, 1 thread per peer, best of %d runs (1..4 peers in turn)\n"
        "level coupling peers | work ms/s busiest mean | / alone: busiest mean | steps / "
        "alone's: busiest | not steps, busiest\n",
        static_cast<unsigned long long>(ticks), rounds);
    for (const int level : levels)
        for (const session::Coupling coupling : {session::Coupling::Exact, session::Coupling::Fast})
        {
            const char* name = coupling == session::Coupling::Exact ? "exact" : "fast";
            double alone_work = 0.0;
            double alone_step = 0.0;
            // Best of `rounds` runs, per peer (the same seats every run): the wall time of one
            // run scatters by +-25 % on a shared machine, and the machine's speed drifts from
            // minute to minute, so each round runs 1, 2, 3 and 4 peers in turn: the peer alone,
            // the denominator of every ratio, is measured across the same minutes as the others.
            std::array<RunResult, 4> best;
            std::array<bool, 4> incomplete{};
            for (int round = 0; round < rounds; ++round)
                for (int peers = 1; peers <= 4; ++peers)
                {
                    const auto p = static_cast<std::size_t>(peers - 1);
                    if (incomplete[p])
                        continue;
                    RunResult one =
                        run(level, peers, coupling, ticks, nullptr, 60.0, std::nullopt, lan_s);
                    RunResult& r = best[p];
                    if (one.steady_sim_s.size() != static_cast<std::size_t>(peers))
                    {
                        r = std::move(one);
                        incomplete[p] = true;
                        continue;
                    }
                    if (round == 0)
                    {
                        r = std::move(one);
                        continue;
                    }
                    for (std::size_t k = 0; k < one.steady_sim_s.size(); ++k)
                    {
                        if (one.steady_busy_s[k] / one.steady_sim_s[k] <
                            r.steady_busy_s[k] / r.steady_sim_s[k])
                        {
                            r.steady_busy_s[k] = one.steady_busy_s[k];
                            r.steady_sim_s[k] = one.steady_sim_s[k];
                            r.steady_step_s[k] = one.steady_step_s[k];
                        }
                    }
                }
            for (int peers = 1; peers <= 4; ++peers)
            {
                const RunResult& r = best[static_cast<std::size_t>(peers - 1)];
                if (r.steady_sim_s.size() != static_cast<std::size_t>(peers))
                {
                    std::printf("%5d %-8s %5d | no steady state within %llu ticks\n", level, name,
                                peers, static_cast<unsigned long long>(ticks));
                    continue;
                }
                double work_max = 0.0;
                double work_sum = 0.0;
                double step_max = 0.0;
                double rest_of_max = 0.0;
                for (int k = 0; k < peers; ++k)
                {
                    const auto i = static_cast<std::size_t>(k);
                    const double w = r.steady_busy_s[i] / r.steady_sim_s[i];
                    const double st = r.steady_step_s[i] / r.steady_sim_s[i];
                    work_sum += w;
                    step_max = std::max(step_max, st);
                    if (w > work_max)
                    {
                        work_max = w;
                        rest_of_max = w > 0.0 ? (w - st) / w : 0.0;
                    }
                }
                if (peers == 1)
                {
                    alone_work = work_max;
                    alone_step = step_max;
                }
                const double n = static_cast<double>(peers);
                const double work_mean = work_sum / n;
                report.add(name, level, n, "peers", "work_s_per_sim_s_max", work_max, "s/s");
                report.add(name, level, n, "peers", "work_s_per_sim_s_mean", work_mean, "s/s");
                report.add(name, level, n, "peers", "work_vs_alone_max", work_max / alone_work,
                           "1");
                report.add(name, level, n, "peers", "work_vs_alone_mean", work_mean / alone_work,
                           "1");
                report.add(name, level, n, "peers", "step_vs_alone_max", step_max / alone_step,
                           "1");
                report.add(name, level, n, "peers", "not_steps_share_max", rest_of_max, "1");
                std::printf("%5d %-8s %5d | %9.1f %6.1f | %13.2f %5.2f | %22.2f | %17.2f\n", level,
                            name, peers, 1e3 * work_max, 1e3 * work_mean, work_max / alone_work,
                            work_mean / alone_work, step_max / alone_step, rest_of_max);
                std::fflush(stdout);
            }
        }
}

/// --latency: from a grab to the change appearing on the other peers, per one-way latency,
/// level, peer count (2..4 participants plus a viewer) and coupling, in virtual time (compute is
/// not timed: all peers share one thread); each figure over four grabs a quarter of a stream
/// period apart. `enet`: in real time over ENet on 127.0.0.1 instead (run_latency_enet; four
/// grabs at whatever phase they fall). \return false if a grab did not show on some peer within
/// its run.
bool latency_suite(bench::Report& report, const std::vector<int>& levels, bool enet)
{
    bool all_seen = true;
    report.meta("network", enet ? "ENet on 127.0.0.1, one thread per peer, real time"
                                : "SimulatedNetwork, 0.5 and 5 ms one-way latency, all peers in "
                                  "one thread");
    report.meta("material", "unit sphere, T=1, rho=1, beta=0.5, k_f=1, fixed dt 1 ms");
    std::printf(
        "# from a grab to its change on the peers, ms (virtual time; wall time with --enet),\n"
        "# mean / max of 4 grabs (in virtual time a quarter stream period apart; 60 Hz streams\n"
        "# and frames, f64 leaf states); the last participant\n"
        "# pulls its own face (0.5 N, outward). grabber: its display (own leaves live) reaches\n"
        "# 1 mm; others, the latest of the other participants and a viewer: display (newest\n"
        "# states) 1 mm, view (what is drawn, interpolated) 1 mm\n");
    if (enet)
        std::printf(
            "# --enet: real time over ENet on 127.0.0.1, one thread per peer on this "
            "machine's cores (latency column 0)\n");
    std::printf(
        "latency level peers coupling | grabber 1 mm | others display 1 mm | "
        "others view 1 mm\n");
    constexpr int k_phases = 4;
    const std::vector<double> latencies =
        enet ? std::vector<double>{0.0} : std::vector<double>{0.0005, 0.005};
    for (const double latency : latencies)
        for (const int level : levels)
            for (int peers = 2; peers <= 4; ++peers)
                for (const session::Coupling coupling :
                     {session::Coupling::Exact, session::Coupling::Fast})
                {
                    // Per figure: mean and max over the phases, in ms; -1 if a peer never saw a
                    // grab within the run.
                    struct Figure
                    {
                        double sum = 0.0;
                        double max = 0.0;
                        bool missed = false;
                        void add(double t)
                        {
                            missed = missed || t < 0.0;
                            sum += t * 1e3;
                            max = std::max(max, t * 1e3);
                        }
                        [[nodiscard]] double mean() const { return missed ? -1.0 : sum / k_phases; }
                        [[nodiscard]] double worst() const { return missed ? -1.0 : max; }
                    };
                    Figure grabber, display, view;
                    for (int phase = 0; phase < k_phases; ++phase)
                    {
                        const std::vector<GrabSeen> seen =
                            enet ? run_latency_enet(level, peers, coupling)
                                 : run_latency(level, peers, coupling, latency,
                                               static_cast<double>(phase) / (60.0 * k_phases));
                        if (seen.empty())
                        {
                            std::fprintf(stderr,
                                         "pliant_bench_session: cannot set up a session "
                                         "over ENet on 127.0.0.1\n");
                            return false;
                        }
                        const auto g = static_cast<std::size_t>(peers - 1);
                        grabber.add(seen[g].display_mm);
                        double d = 0.0;
                        double v = 0.0;
                        for (std::size_t k = 0; k < seen.size(); ++k)
                            if (k != g)
                            {
                                const auto later = [](double a, double b)
                                { return a < 0.0 || b < 0.0 ? -1.0 : std::max(a, b); };
                                d = later(d, seen[k].display_mm);
                                v = later(v, seen[k].view_mm);
                            }
                        display.add(d);
                        view.add(v);
                    }
                    all_seen = all_seen && !grabber.missed && !display.missed && !view.missed;
                    const char* name = coupling == session::Coupling::Exact ? "exact" : "fast";
                    std::printf(
                        "%5.1f %7d %5d %8s | %5.1f / %4.1f | %9.1f / %5.1f | %8.1f / %5.1f\n",
                        latency * 1e3, level, peers, name, grabber.mean(), grabber.worst(),
                        display.mean(), display.worst(), view.mean(), view.worst());
                    std::fflush(stdout);
                    const double n = static_cast<double>(peers);
                    const std::string c = std::string("grab latency: ") + name +
                                          (enet              ? " over ENet loopback"
                                           : latency < 0.001 ? " at 0.5 ms one-way"
                                                             : " at 5 ms one-way");
                    report.add(c, level, n, "peers", "grabber_display_1mm_mean_ms", grabber.mean(),
                               "ms");
                    report.add(c, level, n, "peers", "others_display_1mm_mean_ms", display.mean(),
                               "ms");
                    report.add(c, level, n, "peers", "others_display_1mm_max_ms", display.worst(),
                               "ms");
                    report.add(c, level, n, "peers", "others_view_1mm_mean_ms", view.mean(), "ms");
                    report.add(c, level, n, "peers", "others_view_1mm_max_ms", view.worst(), "ms");
                }
    if (!all_seen)
        std::fprintf(stderr,
                     "pliant_bench_session: a grab did not show on every peer within its run "
                     "(-1 in the table)\n");
    return all_seen;
}

// How long a join through the impairing relay took, s from the joiners' first dial; -1: not
// within k_join_limit_s.
struct JoinTimes
{
    bool opened = false;
    double ready = -1.0;        // the last joiner holds the model
    double partitioned = -1.0;  // every peer holds the master's newest partition, which seats
                                // both participants
    double meshed = -1.0;       // and every pair is connected, every simulating peer's leaf states
                                // arriving at every other peer (the impaired test's `meshed`)
    std::uint64_t fast_retransmits = 0;
};

// A master, two participants and a viewer on ENet, every datagram through the impairing relay
// (tests/session/relay_session.h, as the impaired test), fast coupling at 4 ms steps, all pumped
// in this thread with the wall clock.
JoinTimes run_join(int level, double loss, std::uint64_t seed, const net::EnetSettings& es)
{
    JoinTimes out;
    pliant::test::RelaySession rs;
    rs.impair.loss = loss;
    rs.impair.seed = seed;
    rs.enet = es;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    sim::MembraneSettings m = material();
    m.fixed_dt = 4e-3;
    if (!rs.start(grid, m))
        return out;
    out.opened = true;
    const auto t0 = std::chrono::steady_clock::now();
    auto elapsed = [&]
    { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    for (int it = 0; it < 50'000'000 && out.meshed < 0.0; ++it)
    {
        const double now = elapsed();
        if (now > k_join_limit_s)
            break;
        for (auto& p : rs.peers)
            p->poll();
        for (auto& p : rs.peers)
            p->advance(now);
        if (out.ready < 0.0 && std::all_of(rs.peers.begin() + 1, rs.peers.end(),
                                           [](const auto& p) { return p->ready(); }))
            out.ready = now;
        if (out.partitioned < 0.0 && rs.partitioned())
            out.partitioned = now;
        if (out.partitioned >= 0.0 && rs.meshed())
            out.meshed = now;
    }
    for (const auto& t : rs.transports)
        out.fast_retransmits += net::enet_counters(*t).value().fast_retransmits;
    return out;
}

bool join_suite(bench::Report& report, const std::vector<int>& levels, double loss, int runs)
{
    struct Config
    {
        const char* name;
        bool fast_retransmit;
        std::uint32_t window;
    };
    const std::array<Config, 3> configs{{{"ENet alone", false, 0},
                                         {"fast retransmit", true, 0},
                                         {"fast retransmit + 256 KiB window", true, 256 * 1024}}};
    report.meta("network",
                "ENet on 127.0.0.1 through tests/session/impair_relay.h: 100 ms + 0-20 ms each "
                "way, 1 % duplicated, 2 % held back 20 ms");
    std::printf(
        "# a master, 2 participants and a viewer join at once through the relay, %.0f %% loss; "
        "runs per row: %d, alternating; seconds from the first dial, median / worst\n",
        loss * 100.0, runs);
    std::printf(
        "level configuration                    | joiners hold the model | all partitioned | "
        "full mesh     | not meshed | fast resends per run\n");
    bool all_meshed = true;
    for (const int level : levels)
    {
        std::array<std::vector<double>, 3> ready, parted, meshed;
        std::array<int, 3> missed{};
        std::array<std::uint64_t, 3> resent{};
        for (int run = 0; run < runs; ++run)
            for (std::size_t c = 0; c < configs.size(); ++c)
            {
                net::EnetSettings es;
                es.fast_retransmit = configs[c].fast_retransmit;
                es.reliable_window_bytes = configs[c].window;
                const JoinTimes t =
                    run_join(level, loss, 1000 + static_cast<std::uint64_t>(run), es);
                if (!t.opened)
                {
                    std::fprintf(stderr,
                                 "pliant_bench_session: cannot bind UDP sockets on 127.0.0.1\n");
                    return false;
                }
                resent[c] += t.fast_retransmits;
                if (t.meshed < 0.0)
                {
                    ++missed[c];
                    continue;
                }
                ready[c].push_back(t.ready);
                parted[c].push_back(t.partitioned);
                meshed[c].push_back(t.meshed);
            }
        for (std::size_t c = 0; c < configs.size(); ++c)
        {
            auto median = [](std::vector<double> v)
            {
                if (v.empty())
                    return -1.0;
                std::sort(v.begin(), v.end());
                const std::size_t n = v.size();
                return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
            };
            auto worst = [](const std::vector<double>& v)
            { return v.empty() ? -1.0 : *std::max_element(v.begin(), v.end()); };
            all_meshed = all_meshed && missed[c] == 0;
            const double per_run = static_cast<double>(resent[c]) / runs;
            std::printf(
                "%5d %-32s | %8.2f / %5.2f | %6.2f / %5.2f | %5.2f / %5.2f | %10d | %8.0f\n", level,
                configs[c].name, median(ready[c]), worst(ready[c]), median(parted[c]),
                worst(parted[c]), median(meshed[c]), worst(meshed[c]), missed[c], per_run);
            std::fflush(stdout);
            const std::string name = std::string("join: ") + configs[c].name;
            report.add(name, level, loss * 100.0, "% loss", "full_mesh_median_s", median(meshed[c]),
                       "s");
            report.add(name, level, loss * 100.0, "% loss", "full_mesh_worst_s", worst(meshed[c]),
                       "s");
            report.add(name, level, loss * 100.0, "% loss", "model_held_median_s", median(ready[c]),
                       "s");
            report.add(name, level, loss * 100.0, "% loss", "not_meshed", missed[c], "runs");
        }
    }
    if (!all_meshed)
        std::fprintf(stderr,
                     "pliant_bench_session: a join did not reach its full mesh within %.0f s\n",
                     k_join_limit_s);
    return all_meshed;
}

}  // namespace

int main(int argc, char** argv)
{
    bench::Report report("session");
    const bench::Usage usage(argv[0], k_usage);
    if (const auto status = report.parse_args(argc, argv, usage))
        return *status;
    enum class Mode
    {
        Sessions,
        Stream,
        Coarse,
        Steps,
        Latency,
        Cpu,
        Join
    };
    Mode mode = Mode::Sessions;
    const char* mode_option = nullptr;
    std::vector<const char*> level_args;
    const char* seconds_arg = nullptr;
    bool enet = false;
    bool copy_accept = false;
    const char* random_arg = nullptr;
    const char* loss_arg = nullptr;
    const char* runs_arg = nullptr;
    for (int k = 1; k < argc; ++k)
    {
        const std::string a = argv[k];
        const Mode m = a == "--stream"    ? Mode::Stream
                       : a == "--coarse"  ? Mode::Coarse
                       : a == "--steps"   ? Mode::Steps
                       : a == "--latency" ? Mode::Latency
                       : a == "--cpu"     ? Mode::Cpu
                       : a == "--join"    ? Mode::Join
                                          : Mode::Sessions;
        if (m != Mode::Sessions)
        {
            if (mode_option != nullptr && a != mode_option)
                return usage.error(std::string(mode_option) + " and " + a +
                                   " are separate runs: give one of them");
            mode = m;
            mode_option = argv[k];
        }
        else if (a == "--enet")
            enet = true;
        else if (a == "--copy-accept")
            copy_accept = true;
        else if (a == "--random-points")
        {
            if (k + 1 >= argc)
                return usage.error("--random-points needs a number of layouts");
            random_arg = argv[++k];
        }
        else if (a == "--loss" || a == "--runs")
        {
            if (k + 1 >= argc)
                return usage.error(a +
                                   (a == "--loss" ? " needs a probability" : " needs a number"));
            (a == "--loss" ? loss_arg : runs_arg) = argv[++k];
        }
        else if (a == "--seconds")
        {
            if (k + 1 >= argc)
                return usage.error("--seconds needs a number of seconds");
            seconds_arg = argv[++k];
        }
        else if (!a.empty() && a[0] == '-' && !bench::parse_int(a))
            return usage.unexpected(a);
        else
            level_args.push_back(argv[k]);  // a level (range-checked below, once the mode is known)
    }
    // Levels: core::TetraGrid's range; --coarse also streams 1 and 2 levels coarser
    // (subdiv::make_plans(level - 2, 2) needs level - 2 >= k_min_level).
    const int lowest = mode == Mode::Coarse ? core::k_min_level + k_coarsest : core::k_min_level;
    const std::string level_what =
        mode_option == nullptr ? std::string("level") : std::string(mode_option) + " level";
    std::vector<int> levels;
    for (const char* a : level_args)
    {
        const auto level = usage.int_in(level_what, a, lowest, core::k_max_level);
        if (!level)
            return 2;
        levels.push_back(*level);
    }
    if (enet && mode != Mode::Latency)
        return usage.error("--enet applies to --latency only");
    if (copy_accept && mode != Mode::Steps)
        return usage.error("--copy-accept applies to --steps only");
    int random_layouts = 0;
    if (random_arg != nullptr)
    {
        if (mode != Mode::Steps)
            return usage.error("--random-points applies to --steps only");
        const auto n = usage.int_in("--random-points", random_arg, 1, k_max_random_layouts);
        if (!n)
            return 2;
        random_layouts = *n;
    }
    if (mode == Mode::Stream && levels.size() > 1)
        return usage.error("--stream takes one level, got " + std::to_string(levels.size()));
    double stream_seconds = 2.0;
    if (seconds_arg != nullptr)
    {
        if (mode != Mode::Stream && mode != Mode::Coarse)
            return usage.error("--seconds applies to --stream and --coarse only");
        const auto seconds =
            usage.number_in("--seconds", seconds_arg, 0.0, k_max_seconds, /*lo_open=*/true);
        if (!seconds)
            return 2;
        stream_seconds = *seconds;
    }
    double join_loss = 0.1;
    int join_runs = 0;
    if (loss_arg != nullptr || runs_arg != nullptr)
    {
        if (mode != Mode::Join)
            return usage.error(std::string(loss_arg != nullptr ? "--loss" : "--runs") +
                               " applies to --join only");
        if (loss_arg != nullptr)
        {
            const auto loss = usage.number_in("--loss", loss_arg, 0.0, 0.5);
            if (!loss)
                return 2;
            join_loss = *loss;
        }
        if (runs_arg != nullptr)
        {
            const auto runs = usage.int_in("--runs", runs_arg, 1, k_max_join_runs);
            if (!runs)
                return 2;
            join_runs = *runs;
        }
    }
    if (mode == Mode::Join)
    {
        if (levels.empty())
            levels = report.quick() ? std::vector<int>{5} : std::vector<int>{5, 6};
        if (join_runs == 0)
            join_runs = report.quick() ? 3 : 10;
        report.set_suite("join");
        const bool meshed = join_suite(report, levels, join_loss, join_runs);
        return report.write() && meshed ? 0 : 1;
    }
    if (mode == Mode::Steps)
    {
        if (levels.empty())
            levels = report.quick() ? std::vector<int>{6} : std::vector<int>{6, 7, 8};
        report.set_suite("steps");  // `pliant bench steps`
        if (random_layouts > 0)
            random_steps_suite(report, levels, random_layouts, /*keep_outside=*/copy_accept);
        else
            steps_suite(report, levels, /*keep_outside=*/copy_accept);
        return report.write() ? 0 : 1;
    }
    if (mode == Mode::Cpu)
    {
        if (levels.empty())
            levels = report.quick() ? std::vector<int>{6} : std::vector<int>{6, 7, 8};
        report.set_suite("cpu");  // `pliant bench cpu`
        cpu_suite(report, levels);
        return report.write() ? 0 : 1;
    }
    if (mode == Mode::Latency)
    {
        if (levels.empty())
            levels = report.quick() ? std::vector<int>{6} : std::vector<int>{6, 7, 8};
        report.set_suite("latency");  // `pliant bench latency`
        const bool seen = latency_suite(report, levels, enet);
        return report.write() && seen ? 0 : 1;
    }
    if (mode == Mode::Coarse)
    {
        coarse_suite(report, levels.empty() ? std::vector<int>{6, 7} : levels, stream_seconds);
        return report.write() ? 0 : 1;
    }
    if (mode == Mode::Stream)
    {
        stream_suite(report, levels.empty() ? 6 : levels.front(), stream_seconds);
        return report.write() ? 0 : 1;
    }
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
            // The fast runs' partition (the exact runs' may be slabs where this one is not).
            const auto q = session::measure_partition(
                grid, graph,
                session::partition_leaves(grid, graph, session_seats(grid, peers, true)));
            std::size_t frags = 0;
            for (const auto& sh : q.shares)
                frags += sh.fragments;
            const double n = static_cast<double>(peers);
            report.add("partition", level, n, "peers", "imbalance", q.imbalance, "1");
            report.add("partition", level, n, "peers", "fragments", static_cast<double>(frags),
                       "1");
            report.add("partition", level, n, "peers", "border_edges",
                       static_cast<double>(q.border_edges), "1");
            const double worst = exact.worst_step();
            const double bytes = exact.total_bytes();
            std::printf(
                "%5d %5d | %9.3f %9zu %6zu | %.2f (exact)                      | %7.2f "
                "(exact)            | %.2e (exact: %.1e)\n",
                level, peers, q.imbalance, frags, q.border_edges, worst / single_s,
                bytes / static_cast<double>(peers) / sim_seconds / 1e6,
                fast.max_u > 0.0 ? fast.max_u_diff / fast.max_u : 0.0,
                exact.max_u > 0.0 ? exact.max_u_diff / exact.max_u : 0.0);
            const double fworst = fast.worst_step();
            const double fbytes = fast.total_bytes();
            std::printf(
                "%5d %5d |                            | %.2f (fast)                       "
                "| %7.2f (fast)\n",
                level, peers, fworst / single_s,
                fbytes / static_cast<double>(peers) / sim_seconds / 1e6);
            // Fast coupling with exact coupling's clearance (SessionSettings::point_clearance
            // = Inside): the bands' lower step cost against the grown shares' accuracy.
            const RunResult inside = run(level, peers, session::Coupling::Fast, ticks, &ref, 60.0,
                                         session::PointClearance::Inside);
            add_rows(report, "fast, clearance inside", level, peers, inside, single_s, sim_seconds);
            const double iworst = inside.worst_step();
            const double ibytes = inside.total_bytes();
            std::printf(
                "%5d %5d |                            | %.2f (fast, clearance inside)     "
                "| %7.2f (fast inside)     | %.2e\n",
                level, peers, iworst / single_s,
                ibytes / static_cast<double>(peers) / sim_seconds / 1e6,
                inside.max_u > 0.0 ? inside.max_u_diff / inside.max_u : 0.0);
            if (report.quick())
            {
                std::fflush(stdout);
                continue;  // quick: no 1 kHz-frame variant
            }
            const RunResult fast1k =
                run(level, peers, session::Coupling::Fast, ticks, &ref, 1000.0);
            add_rows(report, "fast 1 kHz", level, peers, fast1k, single_s, sim_seconds);
            const double kworst = fast1k.worst_step();
            const double kbytes = fast1k.total_bytes();
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
