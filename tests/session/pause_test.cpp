// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// A peer whose process stops (SIGSTOP, Ctrl-Z, a suspended machine) for longer than the others'
// timeout is dropped by them, who go on without it (docs/session.md §6). Resumed, it used to
// see every link time out and take over as master of a second session beside theirs (a
// participant), or go on alone (a master), both ending "normally". Now it notices the pause
// (SessionSettings::pause_s) and leaves with refusal() saying why. A shorter pause is only a
// pause: the peer stays a member.
#include <gtest/gtest.h>

#include "session_harness.h"

#include <algorithm>

namespace pliant::session::test
{
namespace
{

constexpr double k_dt = 0.0005;

SessionSettings pause_settings(Coupling c, const char* name)
{
    SessionSettings s;
    s.coupling = c;
    s.name = name;
    s.pause_s = 0.1;  // the network drops a silent peer after 0.2 s
    return s;
}

net::SimulatedNetworkSettings network()
{
    net::SimulatedNetworkSettings n;
    n.link.latency_s = 0.001;
    n.connect_timeout_s = 0.2;
    return n;
}

// A master and two participants, each participant with a point of interest, partitioned.
void start(Harness& h, Coupling c)
{
    h.host(5, pause_settings(c, "master"));
    for (int k = 0; k < 2; ++k)
    {
        Session& p = h.join(net::Role::Participant, pause_settings(c, "part"));
        p.set_points_of_interest({net::Target{
            net::TargetKind::Face, static_cast<std::uint32_t>(700 + 2000 * k), {0, 0, 0}, 0.0}});
    }
    ASSERT_TRUE(pump_until_partitioned(h, 3, 8000));
    ASSERT_TRUE(h.pump_until([&] { return h.peers[0]->tick() >= 50; }, 4000));
}

bool owns_any(const Session& s, net::PeerId id)
{
    const auto owners = s.owners();
    return std::find(owners.begin(), owners.end(), id) != owners.end();
}

// Peer `k` stops for `seconds` while the others run.
void stop_for(Harness& h, std::size_t k, double seconds, bool past_timeout)
{
    h.stop(k, past_timeout);
    for (int i = 0; i < static_cast<int>(seconds / k_dt); ++i)
        h.pump_once(k_dt);
    h.resume(k);
}

void participant_stopped_past_the_timeout(Coupling c)
{
    Harness h(network());
    start(h, c);
    const net::PeerId frozen = h.peers[2]->id();
    stop_for(h, 2, 0.5, true);
    // The others dropped it while it was stopped.
    EXPECT_FALSE(owns_any(*h.peers[0], frozen));
    EXPECT_FALSE(owns_any(*h.peers[1], frozen));
    ASSERT_TRUE(h.pump_until([&] { return h.peers[2]->left(); }, 400));
    const Session& p = *h.peers[2];
    EXPECT_NE(p.refusal().find("this participant did not run for 0.5 s"), std::string::npos)
        << p.refusal();
    EXPECT_NE(p.refusal().find("join again"), std::string::npos) << p.refusal();
    EXPECT_EQ(p.role(), SessionRole::Participant);  // it did not take over
    EXPECT_EQ(p.stats().promotions, 0U);
    EXPECT_EQ(p.stats().pauses, 1U);
    EXPECT_GE(p.stats().longest_pause_s, 0.5);
    // The session goes on without it.
    const std::uint64_t t0 = h.peers[1]->tick();
    ASSERT_TRUE(h.pump_until([&] { return h.peers[1]->tick() >= t0 + 100; }, 4000));
    for (const std::size_t k : {0U, 1U})
    {
        EXPECT_FALSE(h.peers[k]->left()) << k;
        EXPECT_EQ(h.peers[k]->master(), h.peers[0]->id()) << k;
        EXPECT_EQ(h.peers[k]->stats().pauses, 0U) << k;
        EXPECT_TRUE(h.peers[k]->refusal().empty()) << k;
    }
    EXPECT_EQ(h.peers[0]->role(), SessionRole::Master);
    EXPECT_EQ(h.peers[0]->owners(), h.peers[1]->owners());
}

void master_stopped_past_the_timeout(Coupling c)
{
    Harness h(network());
    start(h, c);
    stop_for(h, 0, 0.5, true);
    // A participant took over while the master was stopped.
    const std::size_t succ = h.peers[1]->id() < h.peers[2]->id() ? 1 : 2;
    EXPECT_EQ(h.peers[succ]->role(), SessionRole::Master);
    ASSERT_TRUE(h.pump_until([&] { return h.peers[0]->left(); }, 400));
    const Session& m = *h.peers[0];
    EXPECT_NE(m.refusal().find("this master did not run for 0.5 s"), std::string::npos)
        << m.refusal();
    EXPECT_NE(m.refusal().find("takes over as master"), std::string::npos) << m.refusal();
    EXPECT_EQ(m.stats().pauses, 1U);
    const std::uint64_t t0 = h.peers[succ]->tick();
    ASSERT_TRUE(h.pump_until([&] { return h.peers[1]->tick() >= t0 + 100; }, 4000));
    for (const std::size_t k : {1U, 2U})
    {
        EXPECT_FALSE(h.peers[k]->left()) << k;
        EXPECT_EQ(h.peers[k]->master(), h.peers[succ]->id()) << k;
    }
    EXPECT_EQ(h.peers[1]->owners(), h.peers[2]->owners());
}

// Stopped for less than the others' timeout: a pause, counted, and nothing else.
void participant_paused_briefly(Coupling c)
{
    Harness h(network());
    start(h, c);
    const net::PeerId paused = h.peers[2]->id();
    stop_for(h, 2, 0.15, false);
    const std::uint64_t t0 = h.peers[0]->tick();
    ASSERT_TRUE(h.pump_until([&] { return h.peers[2]->tick() >= t0 + 100; }, 8000));
    const Session& p = *h.peers[2];
    EXPECT_FALSE(p.left());
    EXPECT_TRUE(p.refusal().empty()) << p.refusal();
    EXPECT_EQ(p.stats().pauses, 1U);
    EXPECT_EQ(p.role(), SessionRole::Participant);
    EXPECT_TRUE(owns_any(*h.peers[0], paused));
    EXPECT_EQ(p.owners(), h.peers[0]->owners());
}

// A goodbye that comes while a peer is paused is a departure like any other: only a loss by
// timeout can be this peer's own removal. (Without that rule the master below left the session,
// taking the leaver's Quit for the others' silence.)
TEST(SessionPause, AParticipantLeavingWhileTheMasterIsPausedIsNoRemoval)
{
    Harness h(network());
    start(h, Coupling::Fast);
    const net::PeerId leaver = h.peers[2]->id();
    h.stop(0, false);
    for (int i = 0; i < 100; ++i)
        h.pump_once(k_dt);
    h.peers[2]->leave();
    for (int i = 0; i < 200; ++i)
        h.pump_once(k_dt);
    ASSERT_TRUE(h.peers[2]->left());
    h.resume(0);
    const std::uint64_t t0 = h.peers[0]->tick();
    ASSERT_TRUE(h.pump_until([&] { return h.peers[0]->tick() >= t0 + 100; }, 8000));
    const Session& m = *h.peers[0];
    EXPECT_FALSE(m.left()) << m.refusal();
    EXPECT_EQ(m.stats().pauses, 1U);
    EXPECT_EQ(m.role(), SessionRole::Master);
    EXPECT_FALSE(owns_any(m, leaver));
    EXPECT_TRUE(h.pump_until([&] { return h.peers[1]->owners() == m.owners(); }, 4000));
}

TEST(SessionPause, TheMasterLeavingWhileAParticipantIsPausedIsFollowed)
{
    Harness h(network());
    start(h, Coupling::Fast);
    const std::size_t paused = h.peers[1]->id() < h.peers[2]->id() ? 2 : 1;
    const std::size_t succ = 3 - paused;
    h.stop(paused, false);
    for (int i = 0; i < 100; ++i)
        h.pump_once(k_dt);
    h.peers[0]->leave();
    for (int i = 0; i < 200; ++i)
        h.pump_once(k_dt);
    ASSERT_TRUE(h.peers[0]->left());
    h.resume(paused);
    ASSERT_TRUE(
        h.pump_until([&] { return h.peers[paused]->master() == h.peers[succ]->id(); }, 4000));
    const std::uint64_t t0 = h.peers[paused]->tick();
    ASSERT_TRUE(h.pump_until([&] { return h.peers[paused]->tick() >= t0 + 100; }, 8000));
    EXPECT_FALSE(h.peers[paused]->left()) << h.peers[paused]->refusal();
    EXPECT_EQ(h.peers[paused]->stats().pauses, 1U);
    EXPECT_EQ(h.peers[succ]->role(), SessionRole::Master);
    EXPECT_TRUE(
        h.pump_until([&] { return h.peers[paused]->owners() == h.peers[succ]->owners(); }, 4000));
}

TEST(SessionPause, FastParticipantStoppedPastTheTimeoutLeavesInsteadOfTakingOver)
{
    participant_stopped_past_the_timeout(Coupling::Fast);
}

TEST(SessionPause, ExactParticipantStoppedPastTheTimeoutLeavesInsteadOfTakingOver)
{
    participant_stopped_past_the_timeout(Coupling::Exact);
}

TEST(SessionPause, FastMasterStoppedPastTheTimeoutLeavesTheSessionToItsSuccessor)
{
    master_stopped_past_the_timeout(Coupling::Fast);
}

TEST(SessionPause, ExactMasterStoppedPastTheTimeoutLeavesTheSessionToItsSuccessor)
{
    master_stopped_past_the_timeout(Coupling::Exact);
}

TEST(SessionPause, FastParticipantPausedBrieflyStaysAMember)
{
    participant_paused_briefly(Coupling::Fast);
}

TEST(SessionPause, ExactParticipantPausedBrieflyStaysAMember)
{
    participant_paused_briefly(Coupling::Exact);
}

}  // namespace
}  // namespace pliant::session::test
