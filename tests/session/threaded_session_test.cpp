// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Peers as threads of one process over the SimulatedTransport (issue 6, "Checked by"): each
// Session lives on its own thread and polls and advances against a virtual clock that the test
// thread moves forward; exact coupling with 2 and 3 peers equals the single-process run of the
// same forces after 500 steps, whatever the threads' interleaving. Bounded in wall time.
#include <gtest/gtest.h>

#include "session_harness.h"

#include <atomic>
#include <chrono>
#include <thread>

namespace pliant::session::test
{
namespace
{

constexpr int k_threaded_level = 5;
constexpr std::uint64_t k_threaded_ticks = 500;

void run_exact_threads(int participants)
{
    SessionSettings set;
    set.coupling = Coupling::Exact;
    set.max_ticks = k_threaded_ticks;
    set.name = "master";
    Harness h;
    h.host(k_threaded_level, set);
    for (int k = 0; k < participants; ++k)
    {
        set.name = "part";
        Session& p = h.join(net::Role::Participant, set);
        p.set_points_of_interest({net::Target{
            net::TargetKind::Face, 600 + 2500 * static_cast<std::uint32_t>(k), {0, 0, 0}, 0.0}});
    }
    std::vector<Scheduled> sched{{0, 100, {point_push(0.0, 0.0, 1.0, 0.3, 0.4)}},
                                 {1, 150, {face_pull(700, 0.6)}},
                                 {1, 350, {}}};
    if (participants >= 2)
        sched.push_back({2, 200, {point_push(0.0, 0.0, -1.0, 0.25, 0.5)}});
    for (const Scheduled& s : sched)
        EXPECT_TRUE(h.peers[s.sender]->set_forces(s.forces, s.from));
    const std::size_t members = h.peers.size();
    // Everyone joins and is partitioned first, on this thread (the lockstep waits for them).
    ASSERT_TRUE(pump_until_partitioned(h, members));
    ASSERT_LT(h.peers[0]->tick(), 100U);

    // Then one thread per peer; this thread moves the virtual clock and the network.
    std::atomic<double> clock{h.now};
    std::atomic<bool> stop{false};
    std::vector<std::atomic<bool>> done(members);
    std::vector<std::thread> threads;
    for (std::size_t k = 0; k < members; ++k)
        threads.emplace_back(
            [&, k]
            {
                Session& p = *h.peers[k];
                while (!stop.load())
                {
                    p.poll();
                    p.advance(clock.load());
                    if (p.tick() >= k_threaded_ticks)
                        done[k].store(true);
                    std::this_thread::yield();
                }
            });
    const auto t0 = std::chrono::steady_clock::now();
    const auto all_done = [&]
    { return std::all_of(done.begin(), done.end(), [](const auto& d) { return d.load(); }); };
    while (!all_done() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120))
    {
        h.net.advance(0.0005);
        clock.store(clock.load() + 0.0005);
        std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
    stop.store(true);
    for (std::thread& t : threads)
        t.join();
    ASSERT_TRUE(all_done()) << "not every peer reached tick " << k_threaded_ticks
                            << " within 120 s";

    const sim::MembraneState ref = reference_run(k_threaded_level, k_threaded_ticks, sched);
    const core::TetraGrid& g = h.peers[0]->model()->grid();
    for (std::size_t k = 0; k < members; ++k)
    {
        const Session& p = *h.peers[k];
        ASSERT_EQ(p.tick(), k_threaded_ticks);
        const auto owners = p.owners();
        const LeafGraph* graph = p.leaf_graph();
        const auto mine = [&](core::NodeIndex n) { return owners[graph->leaf_of(n)] == p.id(); };
        const Diff du = compare(g, p.state().u, ref.u, mine);
        const Diff dv = compare(g, p.state().v, ref.v, mine);
        EXPECT_GT(du.compared, 0U) << "peer " << k << " owns no node";
        EXPECT_GT(du.max_ref, 1e-4) << "the forces did something";
        EXPECT_LE(du.relative(), 1e-12) << "peer " << k;
        EXPECT_LE(dv.relative(), 1e-12) << "peer " << k;
        EXPECT_EQ(du.max_abs, 0.0) << "peer " << k << ": bit for bit";
    }
}

TEST(SessionThreads, TwoPeersAsThreadsEqualSingleProcess)
{
    run_exact_threads(1);
}

TEST(SessionThreads, ThreePeersAsThreadsEqualSingleProcess)
{
    run_exact_threads(2);
}

}  // namespace
}  // namespace pliant::session::test
