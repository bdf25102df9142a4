// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// A two-peer exact session whose transports are wrapped in SecureTransport (issue 7 item 4)
// reaches the single-process state bit for bit, as the unencrypted session does: the encryption
// layer is invisible to the session. Level 3, 200 ticks, over a SimulatedNetwork.
#include <pliant/net/enet_transport.h>
#include <pliant/net/secure_transport.h>

#include <gtest/gtest.h>

#include "session_harness.h"

#include <chrono>
#include <thread>

namespace pliant::session::test
{
namespace
{

TEST(SecureSession, TwoPeersThroughSecureTransportEqualSingleProcess)
{
    constexpr int k_secure_level = 3;
    constexpr std::uint64_t k_secure_ticks = 200;
    const net::SecretKey key = net::derive_key("a session passphrase", net::k_default_key_context,
                                               net::KdfLimits::cheapest_for_tests())
                                   .value();
    net::SimulatedNetwork network;
    net::SecureSettings secure;
    secure.clock = [&network] { return network.now_us(); };
    net::SecureTransport master_transport(network.create_endpoint(), key, secure);
    net::SecureTransport peer_transport(network.create_endpoint(), key, secure);
    const net::Address master_address = master_transport.open({}).value();
    (void)peer_transport.open({}).value();

    SessionSettings settings;
    settings.coupling = Coupling::Exact;
    settings.max_ticks = k_secure_ticks;
    settings.name = "master";
    const core::TetraGrid grid = core::TetraGrid::create(k_secure_level).value();
    auto master =
        Session::host(master_transport, grid, scenes::sphere_grid(grid, 1.0), material(), settings)
            .value();
    settings.name = "part";
    auto peer =
        Session::join(peer_transport, master_address, net::Role::Participant, settings).value();
    const std::vector<Scheduled> schedule = {{0, 40, {point_push(0.0, 0.0, 1.0, 0.4, 0.4)}},
                                             {1, 60, {face_pull(20, 0.6)}}};
    for (const Scheduled& s : schedule)
        EXPECT_TRUE((s.sender == 0 ? *master : *peer).set_forces(s.forces, s.from));

    double now = 0.0;
    const auto pump_until = [&](const std::function<bool()>& done, int max_iterations)
    {
        for (int k = 0; k < max_iterations; ++k)
        {
            if (done())
                return true;
            master->poll();
            peer->poll();
            master->advance(now);
            peer->advance(now);
            network.advance(0.0005);
            now += 0.0005;
        }
        return done();
    };
    ASSERT_TRUE(pump_until([&] { return peer->ready() && master->tick() > 0; }, 4000));
    EXPECT_LT(master->tick(), 40U) << "joined before the first force";
    ASSERT_TRUE(pump_until(
        [&] { return master->tick() >= k_secure_ticks && peer->tick() >= k_secure_ticks; }, 40000));
    for (int k = 0; k < 200; ++k)
        pump_until([] { return false; }, 1);

    const sim::MembraneState ref = reference_run(k_secure_level, k_secure_ticks, schedule);
    const core::TetraGrid& g = master->model()->grid();
    for (const Session* s : {master.get(), peer.get()})
    {
        ASSERT_EQ(s->tick(), k_secure_ticks);
        const Diff du = compare(g, s->display_u(), ref.u, {});
        EXPECT_EQ(du.max_abs, 0.0) << "bit-exact, as without encryption";
        EXPECT_GT(du.max_ref, 1e-5) << "the forces did something";
    }
    const net::SecureStats totals = master_transport.totals();
    EXPECT_GT(totals.opened, 100U);
    EXPECT_EQ(totals.auth_failures + totals.malformed + totals.replayed + totals.too_old, 0U);
}

// A joiner whose connection to the master ends before the Welcome keeps why
// (Session::join_failure), which `pliant join` turns into its message (it used to say only
// "never received the model", whatever the cause). Over ENet on 127.0.0.1: a joiner with
// another passphrase is refused at once, before any session traffic, and the master counts it.
TEST(SecureSession, AJoinerWithAnotherPassphraseLearnsItWasRefused)
{
    const auto cheap = net::KdfLimits::cheapest_for_tests();
    const net::SecretKey alpha =
        net::derive_key("alpha alpha alpha", net::k_default_key_context, cheap).value();
    const net::SecretKey beta =
        net::derive_key("beta beta", net::k_default_key_context, cheap).value();
    net::SecureTransport master_transport(net::make_enet_transport(), alpha);
    net::SecureTransport joiner_transport(net::make_enet_transport(), beta);
    const auto master_address = master_transport.open(net::Address{{127, 0, 0, 1}, 0});
    if (!master_address || !joiner_transport.open(net::Address{{127, 0, 0, 1}, 0}))
        GTEST_SKIP() << "cannot bind UDP on 127.0.0.1";
    SessionSettings settings;
    settings.coupling = Coupling::Fast;
    const core::TetraGrid grid = core::TetraGrid::create(3).value();
    auto master =
        Session::host(master_transport, grid, scenes::sphere_grid(grid, 1.0), material(), settings)
            .value();
    auto joiner =
        Session::join(joiner_transport, *master_address, net::Role::Participant, settings).value();
    const auto t0 = std::chrono::steady_clock::now();
    const auto elapsed = [&]
    { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    while (!joiner->left() && elapsed() < 10.0)
    {
        master->poll();
        joiner->poll();
        master->advance(elapsed());
        joiner->advance(elapsed());
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ASSERT_TRUE(joiner->left());
    EXPECT_LT(elapsed(), 2.0) << "refused at once, not after a timeout";
    EXPECT_FALSE(joiner->ready());
    const auto failure = joiner->join_failure();
    ASSERT_TRUE(failure.has_value());
    EXPECT_EQ(failure->reason, net::DisconnectReason::Refused);
    EXPECT_FALSE(failure->connected) << "the key check never passed";
    EXPECT_GE(master_transport.totals().refused, 1U);
    EXPECT_FALSE(master->join_failure().has_value()) << "not a joiner";
    EXPECT_TRUE(master->peers().empty()) << "the session never heard of it";
}

// Nobody listening: the connection attempt times out, and the joiner says so.
TEST(SecureSession, AJoinerNobodyAnswersLearnsItTimedOut)
{
    net::SimulatedNetworkSettings ns;
    ns.connect_timeout_s = 0.5;
    Harness h(ns);
    const net::Address nobody = h.net.create_endpoint()->open({}).value();  // closed at once
    h.master_address = nobody;
    Session& joiner = h.join(net::Role::Participant, SessionSettings{});
    ASSERT_TRUE(h.pump_until([&] { return joiner.left(); }, 4000));
    const auto failure = joiner.join_failure();
    ASSERT_TRUE(failure.has_value());
    EXPECT_EQ(failure->reason, net::DisconnectReason::TimedOut);
    EXPECT_FALSE(failure->connected);
}

}  // namespace
}  // namespace pliant::session::test
