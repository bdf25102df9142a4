// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Two and three peers over real ENet on 127.0.0.1, pumped in one thread: exact coupling equals
// the single-process run after 500 steps. Skipped with a reason if no loopback socket binds.
// (Separate processes: tests/session/cli_session_test.cpp; threads: threaded_session_test.cpp.)
#include <pliant/net/enet_transport.h>
#include <pliant/net/messenger.h>

#include <gtest/gtest.h>

#include "session_harness.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
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
        EXPECT_TRUE(peers[s.sender]->set_forces(s.forces, s.from));
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
        EXPECT_GT(d.compared, 0U) << "peer " << p->id().value << " owns no node";
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

// A joiner that says Hello and then reads nothing (a stalled or hostile one): the master fed it
// the Welcome's model and state blobs all at once (about 1.3 MB at level 7, 5.3 MB at level 8,
// held in ENet's queue for as long as the joiner's connection lived). Now it sends chunks while
// the connection holds less than 256 KiB, so that joiner costs at most that; once it reads again
// the rest follows, every byte of both blobs.
TEST(SessionEnet, AJoinerThatReadsNothingHoldsAtMostTheFeedWindow)
{
    auto master_wire = net::make_enet_transport();
    auto silent_wire = net::make_enet_transport();
    auto ma = master_wire->open(net::Address{{127, 0, 0, 1}, 0});
    auto sa = silent_wire->open(net::Address{{127, 0, 0, 1}, 0});
    if (!ma || !sa)
        GTEST_SKIP() << "cannot bind a UDP socket on 127.0.0.1";
    constexpr int level = 7;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    SessionSettings set;
    set.name = "master";
    set.max_ticks = 1;  // the test is about the welcome, not the steps
    auto master =
        Session::host(*master_wire, grid, scenes::sphere_grid(grid, 1.0), material(), set).value();
    net::Messenger silent(*silent_wire);
    const auto t0 = std::chrono::steady_clock::now();
    const auto elapsed = [&]
    { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    const auto pump_master = [&]
    {
        master->poll();
        master->advance(elapsed());
    };
    // Connect and say Hello, then stop reading.
    const net::PeerHandle to_master = silent_wire->connect(*ma).value();
    bool connected = false;
    while (!connected && elapsed() < 10.0)
    {
        pump_master();
        while (auto ev = silent.poll(1))
            connected = connected || ev->kind == net::MessengerEvent::Kind::Connected;
    }
    ASSERT_TRUE(connected);
    net::Message hello;
    hello.header.sender = net::k_no_peer;
    net::Hello h;
    h.role = net::Role::Viewer;
    h.name = "silent";
    hello.body = h;
    ASSERT_TRUE(silent.send(to_master, hello));
    silent_wire->flush();
    std::size_t most = 0;
    const double quiet_until = elapsed() + 2.0;
    while (elapsed() < quiet_until)
    {
        pump_master();
        for (const net::PeerHandle p : master_wire->peers())
            most = std::max(most, master_wire->queued_bytes(p));
    }
    const std::size_t blobs =
        encode_model(*master->model(), Coupling::Exact).size() + 16 + grid.node_count() * 16;
    std::printf("blobs %zu bytes; the most queued for the silent joiner %zu bytes\n", blobs, most);
    EXPECT_GT(blobs, 1'000'000U);
    EXPECT_GT(most, 0U) << "the Hello was admitted and something was sent";
    EXPECT_LE(most, 256U * 1024U + 40U * 1024U) << "at most the window and one chunk";
    // It reads again: the rest of both blobs arrives.
    std::size_t model_bytes = 0;
    std::size_t state_bytes = 0;
    const double read_until = elapsed() + 20.0;
    while (elapsed() < read_until && model_bytes + state_bytes < blobs)
    {
        pump_master();
        while (auto ev = silent.poll(1))
            if (ev->kind == net::MessengerEvent::Kind::Received &&
                ev->message.type() == net::MessageType::Blob)
            {
                const auto& b = std::get<net::Blob>(ev->message.body);
                (b.kind == net::BlobKind::Model ? model_bytes : state_bytes) += b.data.size();
            }
    }
    EXPECT_EQ(model_bytes + state_bytes, blobs);
    EXPECT_EQ(state_bytes, 16 + grid.node_count() * 16);
}

}  // namespace
}  // namespace pliant::session::test
