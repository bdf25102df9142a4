// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The bad-network exchange behind the transports' poll_into() tests (simulated_transport_test.cpp,
// secure_transport_test.cpp): two transports over one SimulatedNetwork, from connect to
// disconnect, both ways, every delivery on both channels, every event drained with poll() or with
// poll_into() into one reused event. A test runs it both ways on the same seed and compares.
// Everything runs on the network's virtual clock; every loop is bounded in count.

#pragma once

#include <pliant/net/simulated_transport.h>
#include <pliant/net/transport.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <vector>

namespace pliant::test
{

/// One event as the caller saw it, with who polled it (0: a, 1: b) and the virtual time.
struct SeenEvent
{
    int who = 0;
    std::int64_t t_us = 0;
    net::TransportEvent::Kind kind = net::TransportEvent::Kind::Received;
    net::PeerHandle peer;
    net::Channel channel = net::Channel::Control;
    net::DisconnectReason reason = net::DisconnectReason::None;
    std::vector<std::byte> data;
    friend bool operator==(const SeenEvent&, const SeenEvent&) = default;
};

/// Datagram `i` of run_exchange(): 4..303 bytes (the size varies with i), i in its first 4 bytes,
/// then bytes that depend on i and their offset.
inline std::vector<std::byte> numbered_datagram(std::uint32_t i)
{
    std::vector<std::byte> d(4 + (i * 53U) % 300U);
    std::memcpy(d.data(), &i, 4);
    for (std::size_t k = 4; k < d.size(); ++k)
        d[k] = static_cast<std::byte>(i * 7U + k);
    return d;
}

/// What run_exchange() saw.
struct ExchangeRun
{
    std::vector<SeenEvent> events;
    std::size_t received = 0;
    std::size_t corrupt = 0;  ///< Received datagrams whose bytes are not numbered_datagram's
};

/// `a` (opened) connects to `b` at `addr_b` and both wait for Connected (at most 3 s of virtual
/// time); then `sends` datagrams each way, 2 ms apart: a's i-th is numbered_datagram(i), b's
/// numbered_datagram(i + 1000), Reliable, Unreliable and Unsequenced in turn, on Control and
/// State alternately; 1 s of quiet; `before_disconnect(a_to_b, b_to_a)` if given; a disconnects;
/// 2 s more. Every event of either end is recorded as it is drained, with poll() or, when
/// `into`, with poll_into().
inline ExchangeRun run_exchange(
    net::SimulatedNetwork& network, net::Transport& a, net::Transport& b,
    const net::Address& addr_b, std::uint32_t sends, bool into,
    const std::function<void(net::PeerHandle, net::PeerHandle)>& before_disconnect = {})
{
    ExchangeRun out;
    net::TransportEvent reused;
    net::PeerHandle b_to_a;
    bool a_up = false;
    const auto drain = [&](int who, net::Transport& t)
    {
        for (int k = 0; k < 100000; ++k)
        {
            if (into)
            {
                if (!t.poll_into(reused))
                    return;
            }
            else
            {
                auto ev = t.poll();
                if (!ev)
                    return;
                reused = std::move(*ev);
            }
            out.events.push_back(SeenEvent{who, network.now_us(), reused.kind, reused.peer,
                                           reused.channel, reused.reason, reused.data});
            if (reused.kind == net::TransportEvent::Kind::Connected && who == 0)
                a_up = true;
            if (reused.kind == net::TransportEvent::Kind::Connected && who == 1)
                b_to_a = reused.peer;
            if (reused.kind != net::TransportEvent::Kind::Received)
                continue;
            ++out.received;
            std::uint32_t i = 0;
            if (reused.data.size() >= 4)
                std::memcpy(&i, reused.data.data(), 4);
            if (reused.data != numbered_datagram(i))
                ++out.corrupt;
        }
    };
    const auto pass = [&](double dt)
    {
        network.advance(dt);
        drain(0, a);
        drain(1, b);
    };
    const net::PeerHandle a_to_b = a.connect(addr_b).value();
    for (int step = 0; step < 3000 && !(a_up && b_to_a.value != 0); ++step)
        pass(0.001);
    for (std::uint32_t i = 0; i < sends; ++i)
    {
        const net::Delivery d =
            i % 3 == 0 ? net::Delivery::Reliable
                       : (i % 3 == 1 ? net::Delivery::Unreliable : net::Delivery::Unsequenced);
        const net::Channel c = i % 2 == 0 ? net::Channel::Control : net::Channel::State;
        (void)a.send(a_to_b, c, numbered_datagram(i), d);
        (void)b.send(b_to_a, c, numbered_datagram(i + 1000), d);
        pass(0.002);
    }
    for (int step = 0; step < 500; ++step)
        pass(0.002);
    if (before_disconnect)
        before_disconnect(a_to_b, b_to_a);
    a.disconnect(a_to_b, net::DisconnectReason::Quit);
    for (int step = 0; step < 1000; ++step)
        pass(0.002);
    return out;
}

}  // namespace pliant::test
