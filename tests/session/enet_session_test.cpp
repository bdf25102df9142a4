// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Two peers over real ENet on 127.0.0.1, pumped in one thread: exact coupling equals the
// single-process run. Skipped with a reason if no loopback socket binds.
#include <pliant/net/enet_transport.h>

#include <gtest/gtest.h>

#include "session_harness.h"

#include <chrono>

namespace pliant::session::test
{
namespace
{

TEST(SessionEnet, TwoPeersOverLoopbackEqualSingleProcess)
{
    auto tm = net::make_enet_transport();
    auto tp = net::make_enet_transport();
    auto am = tm->open(net::Address{{127, 0, 0, 1}, 0});
    auto ap = tp->open(net::Address{{127, 0, 0, 1}, 0});
    if (!am || !ap)
        GTEST_SKIP() << "cannot bind a UDP socket on 127.0.0.1: "
                     << (!am ? am.error().message : ap.error().message);
    constexpr int level = 4;
    constexpr std::uint64_t ticks = 300;
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    SessionSettings set;
    set.max_ticks = ticks;
    set.name = "master";
    auto master = Session::host(*tm, grid, scenes::sphere_grid(grid, 1.0), material(), set).value();
    set.name = "part";
    set.listen_port = ap->port;
    auto part = Session::join(*tp, *am, net::Role::Participant, set).value();
    const std::vector<Scheduled> sched{{0, 20, {point_push(0.0, 0.0, 1.0, 0.4, 0.5)}},
                                       {1, 60, {face_pull(100, 0.7)}},
                                       {1, 200, {}}};
    for (const Scheduled& s : sched)
        (s.sender == 0 ? *master : *part).set_forces(s.forces, s.from);
    // The clock stands still until the participant is partitioned, then runs in real time.
    const auto t0 = std::chrono::steady_clock::now();
    auto elapsed = [&]
    { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    double started = -1.0;
    while (elapsed() < 30.0 && (master->tick() < ticks || part->tick() < ticks))
    {
        master->poll();
        part->poll();
        if (started < 0.0)
        {
            const auto owners = master->owners();
            if (part->ready() &&
                std::find(owners.begin(), owners.end(), part->id()) != owners.end())
                started = elapsed();
        }
        const double now = started < 0.0 ? 0.0 : elapsed() - started;
        master->advance(now);
        part->advance(now);
    }
    ASSERT_GE(started, 0.0) << "ready " << part->ready() << " id " << part->id().value << " epoch "
                            << master->epoch() << " peers " << master->peers().size();
    ASSERT_EQ(master->tick(), ticks);
    ASSERT_EQ(part->tick(), ticks);
    const sim::MembraneState ref = reference_run(level, ticks, sched);
    for (const Session* p : {master.get(), part.get()})
    {
        const auto owners = p->owners();
        const LeafGraph* g = p->leaf_graph();
        const Diff d = compare(grid, p->state().u, ref.u,
                               [&](core::NodeIndex n) { return owners[g->leaf_of(n)] == p->id(); });
        EXPECT_EQ(d.max_abs, 0.0);
        EXPECT_GT(d.max_ref, 1e-4);
        EXPECT_GT(p->stats().bytes_sent, 0U);
    }
}

}  // namespace
}  // namespace pliant::session::test
