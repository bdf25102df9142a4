// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Two and three peers over real ENet on 127.0.0.1, pumped in one thread: exact coupling equals
// the single-process run after 500 steps. Skipped with a reason if no loopback socket binds.
// (Separate processes: tests/session/cli_session_test.cpp; threads: threaded_session_test.cpp.)
#include <pliant/net/enet_transport.h>

#include <gtest/gtest.h>

#include "session_harness.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

namespace pliant::session::test
{
namespace
{

void run_over_loopback(int participants)
{
    std::vector<std::unique_ptr<net::Transport>> transports;
    std::vector<net::Address> addresses;
    for (int k = 0; k <= participants; ++k)
    {
        transports.push_back(net::make_enet_transport());
        auto a = transports.back()->open(net::Address{{127, 0, 0, 1}, 0});
        if (!a)
            GTEST_SKIP() << "cannot bind a UDP socket on 127.0.0.1: " << a.error().message;
        addresses.push_back(*a);
    }
    constexpr int level = 4;
    constexpr std::uint64_t ticks = 500;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    SessionSettings set;
    set.max_ticks = ticks;
    set.name = "master";
    std::vector<std::unique_ptr<Session>> peers;
    peers.push_back(
        Session::host(*transports[0], grid, scenes::sphere_grid(grid, 1.0), material(), set)
            .value());
    for (int k = 1; k <= participants; ++k)
    {
        set.name = "part";
        set.listen_port = addresses[static_cast<std::size_t>(k)].port;
        peers.push_back(Session::join(*transports[static_cast<std::size_t>(k)], addresses[0],
                                      net::Role::Participant, set)
                            .value());
    }
    std::vector<Scheduled> sched{{0, 20, {point_push(0.0, 0.0, 1.0, 0.4, 0.5)}},
                                 {1, 60, {face_pull(100, 0.7)}},
                                 {1, 200, {}}};
    if (participants >= 2)
        sched.push_back({2, 120, {point_push(0.0, 0.0, -1.0, 0.4, 0.4)}});
    for (const Scheduled& s : sched)
        peers[s.sender]->set_forces(s.forces, s.from);
    // The clock stands still until every participant is partitioned, then runs in real time.
    const auto t0 = std::chrono::steady_clock::now();
    auto elapsed = [&]
    { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    const auto all_at_end = [&]
    {
        return std::all_of(peers.begin(), peers.end(),
                           [&](const auto& p) { return p->tick() >= ticks; });
    };
    double started = -1.0;
    while (elapsed() < 60.0 && !all_at_end())
    {
        for (auto& p : peers)
            p->poll();
        if (started < 0.0)
        {
            const auto owners = peers[0]->owners();
            if (std::all_of(peers.begin() + 1, peers.end(),
                            [&](const auto& p) {
                                return p->ready() && std::find(owners.begin(), owners.end(),
                                                               p->id()) != owners.end();
                            }))
                started = elapsed();
        }
        const double now = started < 0.0 ? 0.0 : elapsed() - started;
        for (auto& p : peers)
            p->advance(now);
    }
    ASSERT_GE(started, 0.0) << "not every participant was partitioned within 60 s (epoch "
                            << peers[0]->epoch() << ", peers " << peers[0]->peers().size() << ")";
    const sim::MembraneState ref = reference_run(level, ticks, sched);
    for (const auto& p : peers)
    {
        ASSERT_EQ(p->tick(), ticks);
        const auto owners = p->owners();
        const LeafGraph* g = p->leaf_graph();
        const Diff d = compare(grid, p->state().u, ref.u,
                               [&](core::NodeIndex n) { return owners[g->leaf_of(n)] == p->id(); });
        EXPECT_EQ(d.max_abs, 0.0);
        EXPECT_LE(d.relative(), 1e-12);
        EXPECT_GT(d.max_ref, 1e-4);
        EXPECT_GT(p->stats().bytes_sent, 0U);
    }
}

TEST(SessionEnet, TwoPeersOverLoopbackEqualSingleProcess)
{
    run_over_loopback(1);
}

TEST(SessionEnet, ThreePeersOverLoopbackEqualSingleProcess)
{
    run_over_loopback(2);
}

}  // namespace
}  // namespace pliant::session::test
