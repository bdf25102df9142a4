// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Compressed leaf states (docs/protocol.md §5.5) in real sessions over a SimulatedNetwork: every
// peer's view equals each owner's quantised state bit for bit (fast mode: the owner's integrated
// state too, since it adopts what it sends), quiescent leaves send no LeafState, a late viewer
// and lossy links get key states and converge, and exact mode stays equal to a single process
// (the stream is display-only there). All loops are bounded by iteration counts.

#include <pliant/net/quantised.h>
#include <pliant/session/partition.h>

#include <gtest/gtest.h>

#include "session_harness.h"

#include <bit>
#include <cmath>
#include <cstdio>

namespace pliant::session::test
{
namespace
{

constexpr int k_compression_level = 5;
constexpr std::uint64_t k_compression_ticks = 400;

SessionSettings compressed(Coupling c, const char* name)
{
    SessionSettings s;
    s.coupling = c;
    s.max_ticks = k_compression_ticks;
    s.name = name;
    s.stream_encoding = net::ValueEncoding::QuantisedDelta;
    return s;
}

bool on_grid(double x, int exponent)
{
    std::int32_t q = 0;
    if (!net::quantise(std::span(&x, 1), exponent, std::span(&q, 1)))
        return false;
    double back = 0.0;
    net::dequantise(std::span(&q, 1), exponent, std::span(&back, 1));
    return same_bits(back, x);
}

/// Every peer shows, on every leaf, exactly the owner's quantised values. With `adopted` (fast
/// coupling) the owner's integrated u equals them on its border nodes (those with a grid
/// neighbour of another owner: its neighbours' Dirichlet values) and lies within half a step of
/// them elsewhere, as v does everywhere (docs/session.md §5.1). \return the number of mismatching
/// nodes.
std::size_t view_mismatches(const Harness& h, bool adopted)
{
    const Session& master = *h.peers[0];
    const auto owners = master.owners();
    const LeafGraph& graph = *master.leaf_graph();
    const core::TetraGrid& g = master.model()->grid();
    const SessionSettings defaults;
    const double half_u = 0.5 * net::quantum(defaults.u_step_exponent);
    const double half_v = 0.5 * net::quantum(defaults.v_step_exponent);
    std::size_t bad = 0;
    for (std::size_t l = 0; l < graph.size(); ++l)
    {
        const Session* owner = nullptr;
        for (const auto& p : h.peers)
            if (p->id() == owners[l])
                owner = p.get();
        if (owner == nullptr)
            return graph.size() * 1000;
        for (const core::NodeIndex n : graph.nodes(l))
        {
            const core::GridCoord c = g.coord(n);
            const double u = owner->display_u().at(c.x, c.y);
            const double v = owner->display_v().at(c.x, c.y);
            bool ok = on_grid(u, defaults.u_step_exponent) && on_grid(v, defaults.v_step_exponent);
            if (adopted)
            {
                bool border = false;
                for (const core::NodeIndex m : core::grid_neighbours(g, c.x, c.y))
                    border = border || owners[graph.leaf_of(m)] != owners[l];
                const double su = owner->state().u.at(c.x, c.y);
                const double sv = owner->state().v.at(c.x, c.y);
                ok = ok && (border ? same_bits(su, u) : std::fabs(su - u) <= half_u) &&
                     std::fabs(sv - v) <= half_v;
            }
            for (const auto& p : h.peers)
                ok = ok && same_bits(p->display_u().at(c.x, c.y), u) &&
                     same_bits(p->display_v().at(c.x, c.y), v);
            bad += ok ? 0 : 1;
        }
    }
    return bad;
}

/// Master and one participant, partitioned, pulling from tick ~50 on; pumps to k_compression_ticks.
/// Both stream with `packing`, in LeafBatch datagrams if `batch`.
void run_pulling(Harness& h, Coupling c, net::Packing packing = net::Packing::Rice,
                 bool batch = true)
{
    SessionSettings ms = compressed(c, "master");
    SessionSettings ps = compressed(c, "part");
    ms.stream_packing = ps.stream_packing = packing;
    ms.batch_leaves = ps.batch_leaves = batch;
    h.host(k_compression_level, ms);
    Session& p = h.join(net::Role::Participant, ps);
    p.set_points_of_interest({net::Target{net::TargetKind::Face, 600, {0, 0, 0}, 0.0}});
    h.peers[0]->set_points_of_interest({point_push(0.0, 0.0, 1.0, 0.3, 0.4).target});
    ASSERT_TRUE(h.pump_until(
        [&]
        {
            const auto owners = h.peers[0]->owners();
            return p.ready() && std::find(owners.begin(), owners.end(), p.id()) != owners.end();
        },
        8000));
    EXPECT_TRUE(h.peers[0]->set_forces({point_push(0.0, 0.0, 1.0, 0.3, 0.4)}, 100));
    EXPECT_TRUE(p.set_forces({face_pull(700, 0.6)}, 150));
    ASSERT_TRUE(h.pump_until([&] { return all_at(h, k_compression_ticks); }, 60000, 0.0005));
}

std::uint64_t total(const Harness& h, std::uint64_t SessionStats::*field)
{
    std::uint64_t sum = 0;
    for (const auto& p : h.peers)
        sum += p->stats().*field;
    return sum;
}

TEST(SessionCompression, FastModeViewsEqualTheOwnersQuantisedStateAndQuiescentLeavesAreFree)
{
    Harness h;
    run_pulling(h, Coupling::Fast);
    // The simulation is frozen at k_compression_ticks; let the last states and their acks through.
    for (int k = 0; k < 1000; ++k)
        h.pump_once(0.0005);
    EXPECT_EQ(view_mismatches(h, true), 0u);
    const std::uint64_t sent = total(h, &SessionStats::leaf_states_sent);
    const std::uint64_t keys = total(h, &SessionStats::key_states_sent);
    EXPECT_GT(keys, 0u);
    EXPECT_GT(sent, 2 * keys) << "most states are deltas against an acknowledged baseline";
    EXPECT_EQ(total(h, &SessionStats::baseline_misses), 0u);
    EXPECT_EQ(total(h, &SessionStats::state_rejects), 0u);
    EXPECT_EQ(total(h, &SessionStats::bad_datagrams), 0u);
    // Nothing changes any more: no LeafState at all, only skips.
    const std::uint64_t skips = total(h, &SessionStats::quiescent_skips);
    for (int k = 0; k < 600; ++k)
        h.pump_once(0.0005);
    EXPECT_EQ(total(h, &SessionStats::leaf_states_sent), sent);
    EXPECT_GT(total(h, &SessionStats::quiescent_skips), skips);

    // A late viewer has no baseline: it gets key states and then shows the same bits.
    const std::uint64_t keys_before = total(h, &SessionStats::key_states_sent);
    SessionSettings vs = compressed(Coupling::Fast, "viewer");
    Session& viewer = h.join(net::Role::Viewer, vs);
    ASSERT_TRUE(h.pump_until([&] { return viewer.ready(); }, 8000));
    for (int k = 0; k < 1000; ++k)
        h.pump_once(0.0005);
    EXPECT_GE(total(h, &SessionStats::key_states_sent) - keys_before, viewer.leaf_graph()->size());
    EXPECT_EQ(view_mismatches(h, true), 0u);
    EXPECT_EQ(total(h, &SessionStats::baseline_misses), 0u);
}

TEST(SessionCompression, RiceBatchesZstdAndPerLeafStatesCarryTheSameBits)
{
    // The packing and the batching change the bytes, never the values: the same scene run with
    // version 3's coding (zstd, one LeafState per leaf), Rice per leaf, and Rice in LeafBatch
    // datagrams ends in bit-identical states on every peer; batches need far fewer datagrams.
    struct Run
    {
        net::Packing packing;
        bool batch;
        std::vector<std::uint64_t> u;
        std::uint64_t packets = 0, bytes = 0, states = 0;
    };
    std::vector<Run> runs = {{net::Packing::Zstd, false, {}},
                             {net::Packing::Rice, false, {}},
                             {net::Packing::Rice, true, {}}};
    for (Run& r : runs)
    {
        Harness h;
        run_pulling(h, Coupling::Fast, r.packing, r.batch);
        for (int k = 0; k < 1000; ++k)
            h.pump_once(0.0005);
        EXPECT_EQ(view_mismatches(h, true), 0u);
        EXPECT_EQ(total(h, &SessionStats::baseline_misses), 0u);
        EXPECT_EQ(total(h, &SessionStats::state_rejects), 0u);
        EXPECT_EQ(total(h, &SessionStats::bad_datagrams), 0u);
        const core::TetraGrid& g = h.peers[0]->model()->grid();
        for (const auto& p : h.peers)
            for (const core::NodeIndex n : g.node_of_unique())
            {
                const core::GridCoord c = g.coord(n);
                r.u.push_back(std::bit_cast<std::uint64_t>(p->display_u().at(c.x, c.y)));
            }
        r.packets = total(h, &SessionStats::packets_sent);
        r.bytes = total(h, &SessionStats::bytes_sent);
        r.states = total(h, &SessionStats::leaf_states_sent);
        std::printf("%s %s: %llu leaf states, %llu datagrams, %llu bytes\n",
                    r.packing == net::Packing::Rice ? "rice" : "zstd",
                    r.batch ? "batched" : "per leaf", static_cast<unsigned long long>(r.states),
                    static_cast<unsigned long long>(r.packets),
                    static_cast<unsigned long long>(r.bytes));
    }
    EXPECT_EQ(runs[0].u, runs[1].u);
    EXPECT_EQ(runs[0].u, runs[2].u);
    EXPECT_LT(runs[1].bytes, runs[0].bytes) << "Rice beats zstd-packed varints";
    EXPECT_LT(runs[2].bytes, runs[1].bytes) << "batches save the per-leaf fixed part";
    EXPECT_LT(2 * runs[2].packets, runs[1].packets) << "several leaves per datagram";
}

// A compressed fast session of a master and one partitioned participant, no force, stepping
// without a tick limit; `refresh` is both peers' quiescent_refresh_s. \return partitioned.
bool start_at_rest(Harness& h, double refresh)
{
    SessionSettings ms = compressed(Coupling::Fast, "master");
    SessionSettings ps = compressed(Coupling::Fast, "part");
    ms.quiescent_refresh_s = ps.quiescent_refresh_s = refresh;
    ms.max_ticks = ps.max_ticks = 0;
    h.host(k_compression_level, ms);
    Session& p = h.join(net::Role::Participant, ps);
    p.set_points_of_interest({net::Target{net::TargetKind::Face, 600, {0, 0, 0}, 0.0}});
    return h.pump_until([&] { return p.ready() && h.peers[0]->epoch() >= 1; }, 8000);
}

TEST(SessionCompression, QuiescentObjectSendsNoLeafStateAfterItsKeyStates)
{
    // quiescent_refresh_s = 0: a leaf at rest costs nothing at all once acknowledged.
    Harness h;
    ASSERT_TRUE(start_at_rest(h, 0.0));
    const Session& p = *h.peers[1];
    // No force: the object stays at rest. Give keys and acks time, then count.
    for (int k = 0; k < 400; ++k)
        h.pump_once(0.0005);
    const std::uint64_t sent = total(h, &SessionStats::leaf_states_sent);
    EXPECT_GT(sent, 0u);
    EXPECT_LE(sent, 4 * p.leaf_graph()->size()) << "about one key state per leaf and receiver";
    for (int k = 0; k < 2000; ++k)
        h.pump_once(0.0005);
    EXPECT_EQ(total(h, &SessionStats::leaf_states_sent), sent);
    EXPECT_GT(total(h, &SessionStats::quiescent_skips), 0u);
    EXPECT_EQ(view_mismatches(h, true), 0u);
}

TEST(SessionCompression, QuiescentLeavesCostOnlyARefreshThatKeepsTheHaloAgeBounded)
{
    // The default: a leaf at rest is re-sent every quiescent_refresh_s (0.25 s) as an all-zero
    // delta of a few bytes, so the receivers' halo age stays bounded (docs/session.md §5.1).
    Harness h;
    ASSERT_TRUE(start_at_rest(h, SessionSettings{}.quiescent_refresh_s));
    const Session& p = *h.peers[1];
    for (int k = 0; k < 1000; ++k)
        h.pump_once(0.0005);
    const std::uint64_t sent = total(h, &SessionStats::leaf_states_sent);
    const std::uint64_t bytes = total(h, &SessionStats::bytes_sent);
    const std::uint64_t packets = total(h, &SessionStats::packets_sent);
    for (int k = 0; k < 4000; ++k)  // 2 s
        h.pump_once(0.0005);
    // Each peer sends each of its leaves to the other 8 times in 2 s (every 0.25 s), give or
    // take one per leaf at the window's ends.
    const auto leaves = static_cast<std::uint64_t>(p.leaf_graph()->size());
    const std::uint64_t refreshes = total(h, &SessionStats::leaf_states_sent) - sent;
    EXPECT_GE(refreshes, 7 * leaves);
    EXPECT_LE(refreshes, 9 * leaves);
    // And they are small: all bytes sent (acks included) per refresh, against ~1,050 bytes for
    // the leaf's state in f64 (64 nodes).
    const double per_refresh = static_cast<double>(total(h, &SessionStats::bytes_sent) - bytes) /
                               static_cast<double>(refreshes);
    std::printf("quiescent refresh: %.1f bytes per leaf and receiver, acks included\n",
                per_refresh);
    EXPECT_LT(per_refresh, 128.0);
    EXPECT_GT(total(h, &SessionStats::packets_sent), packets);
    for (const auto& peer : h.peers)
        EXPECT_LT(peer->stats().halo_age_s, 0.3) << "age <= refresh + latency + a period";
    EXPECT_EQ(view_mismatches(h, true), 0u);
}

// With two receivers per leaf the same holds: a viewer that joins later acknowledges other
// states than the participant, and a leaf at rest went to whichever receiver lagged each
// period (each all-zero delta pushed a new entry the other had not acknowledged): about every
// other stream period instead of every 0.25 s, and the refresh never came due.
TEST(SessionCompression, QuiescentLeavesCostOnlyARefreshWithTwoReceiversToo)
{
    Harness h;
    ASSERT_TRUE(start_at_rest(h, SessionSettings{}.quiescent_refresh_s));
    for (int k = 0; k < 1000; ++k)
        h.pump_once(0.0005);
    Session& viewer = h.join(net::Role::Viewer, compressed(Coupling::Fast, "viewer"));
    ASSERT_TRUE(h.pump_until([&] { return viewer.ready(); }, 8000));
    for (int k = 0; k < 1000; ++k)  // its key states, their acks
        h.pump_once(0.0005);
    const std::uint64_t sent = total(h, &SessionStats::leaf_states_sent);
    for (int k = 0; k < 4000; ++k)  // 2 s
        h.pump_once(0.0005);
    // Every leaf goes to its two receivers 8 times in 2 s, give or take one at the window's ends.
    const auto leaves = static_cast<std::uint64_t>(viewer.leaf_graph()->size());
    const std::uint64_t refreshes = total(h, &SessionStats::leaf_states_sent) - sent;
    EXPECT_GE(refreshes, 2 * 7 * leaves);
    EXPECT_LE(refreshes, 2 * 9 * leaves);
    EXPECT_EQ(view_mismatches(h, true), 0u);
}

TEST(SessionCompression, LossyDuplicatingLinksStillConvergeToTheOwnersBits)
{
    net::SimulatedNetworkSettings ns;
    ns.seed = 42;
    ns.link.loss = 0.2;
    ns.link.duplicate = 0.1;
    ns.link.reorder = 0.1;
    ns.link.jitter_s = 0.004;
    Harness h(ns);
    run_pulling(h, Coupling::Fast);
    for (int k = 0; k < 3000; ++k)
        h.pump_once(0.0005);
    EXPECT_EQ(view_mismatches(h, true), 0u);
    EXPECT_EQ(total(h, &SessionStats::state_rejects), 0u);
    EXPECT_EQ(total(h, &SessionStats::bad_datagrams), 0u);
}

TEST(SessionCompression, BandwidthCapHoldsAndEveryLeafStillArrives)
{
    Harness h;
    const double cap_mbit = 0.2;  // binds for both peers (each sends 0.24-0.38 uncapped)
    SessionSettings ms = compressed(Coupling::Fast, "master");
    SessionSettings ps = compressed(Coupling::Fast, "part");
    ms.bandwidth_cap_mbit_s = ps.bandwidth_cap_mbit_s = cap_mbit;
    ms.max_ticks = ps.max_ticks = 1500;  // still simulating while measuring
    h.host(k_compression_level, ms);
    Session& p = h.join(net::Role::Participant, ps);
    p.set_points_of_interest({net::Target{net::TargetKind::Face, 600, {0, 0, 0}, 0.0}});
    h.peers[0]->set_points_of_interest({point_push(0.0, 0.0, 1.0, 0.3, 0.4).target});
    ASSERT_TRUE(h.pump_until(
        [&]
        {
            const auto owners = h.peers[0]->owners();
            return p.ready() && std::find(owners.begin(), owners.end(), p.id()) != owners.end();
        },
        8000));
    EXPECT_TRUE(h.peers[0]->set_forces({point_push(0.0, 0.0, 1.0, 0.3, 0.4)}));
    EXPECT_TRUE(p.set_forces({face_pull(700, 0.6)}));
    for (int k = 0; k < 400; ++k)
        h.pump_once(0.0005);
    std::vector<SessionStats> before;
    for (const auto& peer : h.peers)
        before.push_back(peer->stats());
    const double window = 0.5;
    for (int k = 0; k < 1000; ++k)
        h.pump_once(0.0005);
    for (std::size_t k = 0; k < h.peers.size(); ++k)
    {
        const SessionStats st = h.peers[k]->stats();
        const double mbit =
            8.0 * static_cast<double>(st.bytes_sent - before[k].bytes_sent) / window / 1e6;
        std::printf("peer %zu: %.3f Mbit/s under a %.2f cap, %llu postponed\n", k, mbit, cap_mbit,
                    static_cast<unsigned long long>(st.capped_skips - before[k].capped_skips));
        // The cap covers leaf states and acks; the rest (Force, Heartbeat) is small. Slack: the
        // bucket's second period and one datagram of overshoot.
        EXPECT_LE(mbit, cap_mbit * 1.1 + 0.05);
        EXPECT_GT(st.capped_skips, before[k].capped_skips) << "the cap binds in this scene";
    }
    EXPECT_LT(h.peers[0]->tick(), 1500u) << "measured while the object moved";
    // Frozen, every leaf reaches every peer despite the cap (priorities grow while waiting).
    ASSERT_TRUE(h.pump_until([&] { return all_at(h, 1500); }, 20000));
    for (int k = 0; k < 4000; ++k)
        h.pump_once(0.0005);
    EXPECT_EQ(view_mismatches(h, true), 0u);
}

TEST(SessionCompression, ExactModeIntegratesUnquantisedAndShowsQuantised)
{
    Harness h;
    run_pulling(h, Coupling::Exact);
    for (int k = 0; k < 1000; ++k)
        h.pump_once(0.0005);
    EXPECT_EQ(view_mismatches(h, false), 0u);
    // The integrated state is not quantised: the lockstep is the uncompressed one.
    const std::vector<Scheduled> sched = {{0, 100, {point_push(0.0, 0.0, 1.0, 0.3, 0.4)}},
                                          {1, 150, {face_pull(700, 0.6)}}};
    const sim::MembraneState ref = reference_run(k_compression_level, k_compression_ticks, sched);
    const core::TetraGrid& g = h.peers[0]->model()->grid();
    for (const auto& peer : h.peers)
    {
        const auto owners = peer->owners();
        const LeafGraph* lg = peer->leaf_graph();
        const net::PeerId id = peer->id();
        const Diff d = compare(g, peer->state().u, ref.u,
                               [&](core::NodeIndex n) { return owners[lg->leaf_of(n)] == id; });
        EXPECT_GT(d.max_ref, 1e-4);
        EXPECT_LE(d.relative(), 1e-12);
    }
}

}  // namespace
}  // namespace pliant::session::test
