// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// SimulatedNetwork: connection life cycle, determinism for a seed, loss/duplication/reordering
// measured at the receiver against the settings, the reliable channel in order exactly once under
// 20 % loss, timeouts, endpoints on separate threads, and poll_into() (which recycles the
// datagrams' buffers) giving poll()'s events (the exchange of net/exchange_harness.h, shared with
// SecureTransport's test). Everything runs on the virtual clock.

#include <pliant/core/hash.h>
#include <pliant/net/simulated_transport.h>

#include <gtest/gtest.h>

#include "net/exchange_harness.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <thread>

namespace pliant::net
{
namespace
{

std::vector<std::byte> payload(std::uint32_t seq, std::size_t size = 16)
{
    std::vector<std::byte> d(std::max<std::size_t>(size, 4));
    std::memcpy(d.data(), &seq, 4);
    for (std::size_t i = 4; i < d.size(); ++i)
        d[i] = static_cast<std::byte>(seq + i);
    return d;
}

std::uint32_t seq_of(const std::vector<std::byte>& d)
{
    std::uint32_t s = 0;
    std::memcpy(&s, d.data(), 4);
    return s;
}

struct Pair
{
    SimulatedNetwork net;
    std::unique_ptr<Transport> a;
    std::unique_ptr<Transport> b;
    Address addr_a;
    Address addr_b;
    PeerHandle a_to_b;
    PeerHandle b_to_a;

    explicit Pair(const SimulatedNetworkSettings& s) : net(s)
    {
        a = net.create_endpoint();
        b = net.create_endpoint();
        addr_a = a->open({}).value();
        addr_b = b->open({}).value();
    }

    /// Connects a to b; both must see Connected within 10 s of virtual time.
    void connect()
    {
        a_to_b = a->connect(addr_b).value();
        bool a_up = false;
        bool b_up = false;
        for (int step = 0; step < 10000 && !(a_up && b_up); ++step)
        {
            net.advance(0.001);
            while (auto ev = a->poll())
                a_up = a_up || (ev->kind == TransportEvent::Kind::Connected && ev->peer == a_to_b);
            while (auto ev = b->poll())
                if (ev->kind == TransportEvent::Kind::Connected)
                {
                    b_up = true;
                    b_to_a = ev->peer;
                }
        }
        ASSERT_TRUE(a_up && b_up);
    }
};

TEST(SimulatedTransport, ConnectExchangeDisconnect)
{
    Pair p(SimulatedNetworkSettings{});
    ASSERT_NO_FATAL_FAILURE(p.connect());
    EXPECT_EQ(p.a->remote_address(p.a_to_b), p.addr_b);
    ASSERT_TRUE(p.a->send(p.a_to_b, Channel::Control, payload(1), Delivery::Reliable));
    ASSERT_TRUE(p.a->send(p.a_to_b, Channel::State, payload(2), Delivery::Unreliable));
    std::vector<std::pair<Channel, std::uint32_t>> got;
    for (int step = 0; step < 100 && got.size() < 2; ++step)
    {
        p.net.advance(0.001);
        while (auto ev = p.b->poll())
            if (ev->kind == TransportEvent::Kind::Received)
                got.emplace_back(ev->channel, seq_of(ev->data));
    }
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0], std::pair(Channel::Control, 1u));
    EXPECT_EQ(got[1], std::pair(Channel::State, 2u));
    const auto stats = p.a->stats(p.a_to_b).value();
    EXPECT_EQ(stats.packets_sent, 2u);
    EXPECT_EQ(stats.bytes_sent, 32u);
    EXPECT_DOUBLE_EQ(stats.rtt_s, 0.010);  // 2 x 5 ms default latency
    EXPECT_EQ(p.b->stats(p.b_to_a)->packets_received, 2u);

    p.a->disconnect(p.a_to_b, DisconnectReason::Quit);
    std::optional<DisconnectReason> a_reason;
    std::optional<DisconnectReason> b_reason;
    for (int step = 0; step < 100 && !(a_reason && b_reason); ++step)
    {
        p.net.advance(0.001);
        while (auto ev = p.a->poll())
            if (ev->kind == TransportEvent::Kind::Disconnected)
                a_reason = ev->reason;
        while (auto ev = p.b->poll())
            if (ev->kind == TransportEvent::Kind::Disconnected)
                b_reason = ev->reason;
    }
    EXPECT_EQ(a_reason, DisconnectReason::Quit);
    EXPECT_EQ(b_reason, DisconnectReason::Quit);
    EXPECT_FALSE(p.a->send(p.a_to_b, Channel::Control, payload(3), Delivery::Reliable));
    EXPECT_TRUE(p.a->peers().empty());
}

/// Runs a bad-network exchange both ways and returns a hash of everything each side saw, in order,
/// with the virtual time of each event.
std::uint64_t trace(std::uint64_t seed)
{
    SimulatedNetworkSettings s;
    s.seed = seed;
    s.link = LinkSettings{.latency_s = 0.02,
                          .jitter_s = 0.01,
                          .loss = 0.2,
                          .duplicate = 0.1,
                          .reorder = 0.1,
                          .reorder_delay_s = 0.03};
    Pair p(s);
    p.connect();
    std::uint64_t h = 0;
    const auto record = [&h, &p](int who, const TransportEvent& ev)
    {
        const std::int64_t t = p.net.now_us();
        h = core::hash_span(std::span(&t, 1), h);
        const std::uint32_t k[3] = {static_cast<std::uint32_t>(who),
                                    static_cast<std::uint32_t>(ev.kind),
                                    static_cast<std::uint32_t>(ev.channel)};
        h = core::hash_span(std::span<const std::uint32_t>(k), h);
        h = core::hash_bytes(ev.data, h);
    };
    for (std::uint32_t i = 0; i < 400; ++i)
    {
        const Delivery d = i % 3 == 0 ? Delivery::Reliable
                                      : (i % 3 == 1 ? Delivery::Unreliable : Delivery::Unsequenced);
        const Channel c = d == Delivery::Reliable ? Channel::Control : Channel::State;
        (void)p.a->send(p.a_to_b, c, payload(i), d);
        (void)p.b->send(p.b_to_a, c, payload(i + 1000), d);
        p.net.advance(0.002);
        while (auto ev = p.a->poll())
            record(0, *ev);
        while (auto ev = p.b->poll())
            record(1, *ev);
    }
    return h;
}

TEST(SimulatedTransport, DeterministicForASeed)
{
    const std::uint64_t first = trace(42);
    EXPECT_EQ(trace(42), first);
    EXPECT_NE(trace(43), first);
}

/// What exchange() saw, and both ends' counters before the disconnect.
struct Exchange
{
    test::ExchangeRun run;
    SimulatedTotals totals;
    PeerStats a_stats;
    PeerStats b_stats;
};

/// test::run_exchange over a bad network (latency, jitter, 20 % loss, duplication, reordering):
/// 600 datagrams each way.
Exchange exchange(std::uint64_t seed, bool into)
{
    SimulatedNetworkSettings s;
    s.seed = seed;
    s.link = LinkSettings{.latency_s = 0.02,
                          .jitter_s = 0.01,
                          .loss = 0.2,
                          .duplicate = 0.15,
                          .reorder = 0.15,
                          .reorder_delay_s = 0.03};
    Pair p(s);
    Exchange out;
    out.run = test::run_exchange(p.net, *p.a, *p.b, p.addr_b, 600, into,
                                 [&](PeerHandle a_to_b, PeerHandle b_to_a)
                                 {
                                     out.a_stats = p.a->stats(a_to_b).value_or(PeerStats{});
                                     out.b_stats = p.b->stats(b_to_a).value_or(PeerStats{});
                                 });
    out.totals = p.net.totals();
    return out;
}

void expect_same_counts(const PeerStats& x, const PeerStats& y)
{
    EXPECT_EQ(x.bytes_sent, y.bytes_sent);
    EXPECT_EQ(x.bytes_received, y.bytes_received);
    EXPECT_EQ(x.packets_sent, y.packets_sent);
    EXPECT_EQ(x.packets_received, y.packets_received);
}

// poll_into() recycles the datagrams' buffers (the caller's previous one goes back to the network,
// which sends the next datagrams in it): the events, their bytes, order and timing, and every
// counter are those of poll(), which hands each buffer over for good.
TEST(SimulatedTransport, PollIntoGivesTheEventsOfPoll)
{
    for (const std::uint64_t seed : {42u, 7u})
    {
        const Exchange by_poll = exchange(seed, false);
        const Exchange by_into = exchange(seed, true);
        ASSERT_EQ(by_poll.run.events.size(), by_into.run.events.size()) << "seed " << seed;
        for (std::size_t k = 0; k < by_poll.run.events.size(); ++k)
            ASSERT_TRUE(by_poll.run.events[k] == by_into.run.events[k])
                << "seed " << seed << " event " << k;
        EXPECT_EQ(by_poll.run.corrupt, 0u);
        EXPECT_EQ(by_into.run.corrupt, 0u);
        const SimulatedTotals& x = by_poll.totals;
        const SimulatedTotals& y = by_into.totals;
        EXPECT_EQ(x.transmissions, y.transmissions);
        EXPECT_EQ(x.lost, y.lost);
        EXPECT_EQ(x.duplicated, y.duplicated);
        EXPECT_EQ(x.reordered, y.reordered);
        EXPECT_EQ(x.retransmitted, y.retransmitted);
        EXPECT_EQ(x.delivered, y.delivered);
        EXPECT_EQ(x.dropped_stale, y.dropped_stale);
        expect_same_counts(by_poll.a_stats, by_into.a_stats);
        expect_same_counts(by_poll.b_stats, by_into.b_stats);
        // The scenario did what it is for: both ends connected and disconnected, and the network
        // lost, duplicated, reordered and dropped stale packets.
        const auto kinds = [&](TransportEvent::Kind kind)
        {
            return std::count_if(by_into.run.events.begin(), by_into.run.events.end(),
                                 [kind](const test::SeenEvent& e) { return e.kind == kind; });
        };
        EXPECT_EQ(kinds(TransportEvent::Kind::Connected), 2);
        EXPECT_EQ(kinds(TransportEvent::Kind::Disconnected), 2);
        EXPECT_GT(by_into.run.received, 700u);
        EXPECT_GT(y.lost, 100u);
        EXPECT_GT(y.duplicated, 50u);
        EXPECT_GT(y.reordered, 50u);
        EXPECT_GT(y.dropped_stale, 0u);
    }
}

struct Arrivals
{
    std::size_t unique = 0;
    std::size_t duplicates = 0;
    std::size_t reordered = 0;  // first arrivals after a packet sent later
    bool increasing = true;     // every arrival has a higher sequence than the previous one
};

Arrivals measure(const LinkSettings& link, Delivery delivery, std::uint32_t n)
{
    SimulatedNetworkSettings s;
    s.seed = 7;
    s.link = link;
    Pair p(s);
    p.connect();
    Arrivals out;
    std::vector<int> seen(n, 0);
    std::int64_t highest = -1;
    std::int64_t previous = -1;
    const auto drain = [&]()
    {
        while (auto ev = p.b->poll())
        {
            if (ev->kind != TransportEvent::Kind::Received)
                continue;
            const std::uint32_t k = seq_of(ev->data);
            out.increasing = out.increasing && static_cast<std::int64_t>(k) > previous;
            previous = k;
            if (seen[k]++ > 0)
            {
                ++out.duplicates;
                continue;
            }
            ++out.unique;
            if (static_cast<std::int64_t>(k) < highest)
                ++out.reordered;
            highest = std::max<std::int64_t>(highest, k);
        }
    };
    for (std::uint32_t i = 0; i < n; ++i)
    {
        EXPECT_TRUE(p.a->send(p.a_to_b, Channel::State, payload(i), delivery));
        p.net.advance(0.001);
        drain();
    }
    for (int i = 0; i < 1000; ++i)
    {
        p.net.advance(0.001);
        drain();
    }
    return out;
}

TEST(SimulatedTransport, LossAndDuplicationMatchTheSettings)
{
    constexpr std::uint32_t n = 20000;
    const auto a = measure(LinkSettings{.latency_s = 0.01, .loss = 0.2, .duplicate = 0.1},
                           Delivery::Unsequenced, n);
    // Binomial standard deviations: 0.0028 (loss), 0.0024 (duplication); allow 5 of them.
    EXPECT_NEAR(static_cast<double>(a.unique) / n, 0.8, 0.015);
    EXPECT_NEAR(static_cast<double>(a.duplicates) / static_cast<double>(a.unique), 0.1, 0.012);
    EXPECT_EQ(a.reordered, 0u);  // no jitter, no reordering: nothing overtakes
}

TEST(SimulatedTransport, ReorderingMatchesTheSettings)
{
    constexpr std::uint32_t n = 20000;
    const auto r = measure(LinkSettings{.latency_s = 0.01, .reorder = 0.1, .reorder_delay_s = 0.02},
                           Delivery::Unsequenced, n);
    EXPECT_EQ(r.unique, n);
    EXPECT_EQ(r.duplicates, 0u);
    // A held-back packet (20 ms) arrives after the ~20 sent after it (1 ms apart).
    EXPECT_NEAR(static_cast<double>(r.reordered) / n, 0.1, 0.012);
}

TEST(SimulatedTransport, UnreliableChannelIsSequenced)
{
    constexpr std::uint32_t n = 5000;
    const auto r = measure(
        LinkSettings{
            .latency_s = 0.01, .jitter_s = 0.005, .loss = 0.1, .duplicate = 0.2, .reorder = 0.2},
        Delivery::Unreliable, n);
    EXPECT_TRUE(r.increasing);
    EXPECT_EQ(r.duplicates, 0u);
    EXPECT_EQ(r.reordered, 0u);
    EXPECT_LT(r.unique, std::size_t{n} * 9 / 10);  // loss plus stale packets dropped
    EXPECT_GT(r.unique, std::size_t{n} / 2);
}

TEST(SimulatedTransport, ReliableChannelInOrderExactlyOnceUnderLoss)
{
    SimulatedNetworkSettings s;
    s.seed = 99;
    s.link = LinkSettings{.latency_s = 0.03,
                          .jitter_s = 0.02,
                          .loss = 0.2,
                          .duplicate = 0.1,
                          .reorder = 0.1,
                          .reorder_delay_s = 0.05};
    Pair p(s);
    ASSERT_NO_FATAL_FAILURE(p.connect());
    constexpr std::uint32_t n = 2000;
    std::vector<std::uint32_t> control;
    std::size_t state = 0;
    for (std::uint32_t i = 0; i < n; ++i)
    {
        ASSERT_TRUE(
            p.a->send(p.a_to_b, Channel::Control, payload(i, 1 + i % 300), Delivery::Reliable));
        ASSERT_TRUE(p.a->send(p.a_to_b, Channel::State, payload(i), Delivery::Unreliable));
        if (i % 4 == 0)
            p.net.advance(0.001);
        while (auto ev = p.b->poll())
            if (ev->kind == TransportEvent::Kind::Received)
                (ev->channel == Channel::Control ? (void)control.push_back(seq_of(ev->data))
                                                 : (void)++state);
    }
    for (int i = 0; i < 20000 && control.size() < n; ++i)
    {
        p.net.advance(0.001);
        while (auto ev = p.b->poll())
        {
            ASSERT_NE(ev->kind, TransportEvent::Kind::Disconnected);
            if (ev->kind == TransportEvent::Kind::Received && ev->channel == Channel::Control)
                control.push_back(seq_of(ev->data));
        }
    }
    ASSERT_EQ(control.size(), n);
    for (std::uint32_t i = 0; i < n; ++i)
        ASSERT_EQ(control[i], i);
    const auto totals = p.net.totals();
    EXPECT_GT(totals.retransmitted, 300u);  // the loss really happened
    EXPECT_GT(totals.duplicated, 100u);
    EXPECT_LT(state, std::size_t{n});
}

TEST(SimulatedTransport, ConnectingToNobodyTimesOut)
{
    SimulatedNetworkSettings s;
    s.connect_timeout_s = 2.0;
    SimulatedNetwork net(s);
    auto a = net.create_endpoint();
    ASSERT_TRUE(a->open({}));
    const PeerHandle h = a->connect(Address{{10, 0, 0, 99}, 1234}).value();
    std::optional<TransportEvent> ev;
    for (int step = 0; step < 30 && !ev; ++step)
    {
        net.advance(0.1);
        ev = a->poll();
    }
    ASSERT_TRUE(ev.has_value());
    EXPECT_EQ(ev->kind, TransportEvent::Kind::Disconnected);
    EXPECT_EQ(ev->peer, h);
    EXPECT_EQ(ev->reason, DisconnectReason::TimedOut);
    EXPECT_GE(net.now_us(), 2000000);
}

TEST(SimulatedTransport, ALinkThatLosesEverythingTimesOutBothEnds)
{
    SimulatedNetworkSettings s;
    s.max_attempts = 3;
    Pair p(s);
    ASSERT_NO_FATAL_FAILURE(p.connect());
    p.net.set_link(p.addr_a, p.addr_b, LinkSettings{.loss = 0.999999});
    ASSERT_TRUE(p.a->send(p.a_to_b, Channel::Control, payload(1), Delivery::Reliable));
    int down = 0;
    for (int step = 0; step < 1000 && down < 2; ++step)
    {
        p.net.advance(0.001);
        for (Transport* t : {p.a.get(), p.b.get()})
            while (auto ev = t->poll())
                if (ev->kind == TransportEvent::Kind::Disconnected)
                {
                    EXPECT_EQ(ev->reason, DisconnectReason::TimedOut);
                    ++down;
                }
    }
    EXPECT_EQ(down, 2);
}

// Endpoints on their own threads (peers as threads of one process) while the main thread drives
// the clock: every reliable message arrives in order, received with poll() and with poll_into()
// (whose buffers go back to the network and on to the sender's thread). Run under TSan to check
// the locking.
TEST(SimulatedTransport, EndpointsOnSeparateThreads)
{
    for (const bool into : {false, true})
    {
        SCOPED_TRACE(into ? "poll_into" : "poll");
        SimulatedNetworkSettings s;
        s.link = LinkSettings{.latency_s = 0.002, .jitter_s = 0.001, .loss = 0.1};
        Pair p(s);
        ASSERT_NO_FATAL_FAILURE(p.connect());
        constexpr std::uint32_t n = 500;
        std::atomic<bool> done{false};
        std::vector<std::uint32_t> got;
        std::thread receiver(
            [&]()
            {
                TransportEvent reused;
                for (int spin = 0; spin < 5000000 && got.size() < n; ++spin)
                {
                    bool any = false;
                    if (into)
                    {
                        any = p.b->poll_into(reused);
                    }
                    else if (auto ev = p.b->poll())
                    {
                        any = true;
                        reused = std::move(*ev);
                    }
                    if (!any)
                        std::this_thread::yield();
                    else if (reused.kind == TransportEvent::Kind::Received)
                        got.push_back(seq_of(reused.data));
                }
                done = true;
            });
        std::thread sender(
            [&]()
            {
                for (std::uint32_t i = 0; i < n; ++i)
                    (void)p.a->send(p.a_to_b, Channel::Control, payload(i), Delivery::Reliable);
            });
        sender.join();
        for (int step = 0; step < 100000 && !done; ++step)
        {
            p.net.advance(0.001);
            std::this_thread::yield();
        }
        done = true;
        receiver.join();
        ASSERT_EQ(got.size(), n);
        for (std::uint32_t i = 0; i < n; ++i)
            EXPECT_EQ(got[i], i);
    }
}

}  // namespace
}  // namespace pliant::net
