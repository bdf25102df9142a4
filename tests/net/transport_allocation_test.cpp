// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// "No allocation per datagram" of SimulatedTransport and of SecureTransport over it: once a
// warm-up has carried datagrams as large as the later ones (and the network has held as many in
// flight at once), send() and poll_into() into one reused event allocate nothing, both ways, on
// every delivery, on a clean link and on one that loses, duplicates and reorders. Counted by a
// replaced operator new (tests/support/allocation_counter.cpp, linked into this executable only).
#include <pliant/net/secure_transport.h>
#include <pliant/net/simulated_transport.h>

#include <gtest/gtest.h>

#include "support/allocation_counter.h"

#include <cstring>
#include <memory>
#include <vector>

namespace pliant::net
{
namespace
{

constexpr std::size_t k_max_size = 407;

std::size_t size_of_datagram(std::uint32_t i)
{
    return 8 + (i * 53u) % (k_max_size - 7);
}

std::byte byte_of(std::uint32_t i, std::size_t k)
{
    return static_cast<std::byte>((i * 131u + k * 7u) & 0xFFu);
}

/// Datagram `i` into `out` (its capacity reserved once): its number in the first 4 bytes.
void fill(std::vector<std::byte>& out, std::uint32_t i)
{
    out.resize(size_of_datagram(i));
    for (std::size_t k = 4; k < out.size(); ++k)
        out[k] = byte_of(i, k);
    std::memcpy(out.data(), &i, 4);
}

bool intact(const std::vector<std::byte>& d)
{
    if (d.size() < 4)
        return false;
    std::uint32_t i = 0;
    std::memcpy(&i, d.data(), 4);
    if (d.size() != size_of_datagram(i))
        return false;
    for (std::size_t k = 4; k < d.size(); ++k)
        if (d[k] != byte_of(i, k))
            return false;
    return true;
}

const SecretKey& test_key()
{
    static const SecretKey key =
        derive_key("correct horse", k_default_key_context, KdfLimits::cheapest_for_tests()).value();
    return key;
}

/// Two endpoints (SecureTransports over them when `secure`); `a` sends, `b` echoes.
struct Rig
{
    Rig(const LinkSettings& link, bool secure) : net(settings_for(link))
    {
        a = net.create_endpoint();
        b = net.create_endpoint();
        if (secure)
        {
            SecureSettings s;
            s.clock = [this] { return net.now_us(); };
            a = std::make_unique<SecureTransport>(std::move(a), test_key(), s);
            b = std::make_unique<SecureTransport>(std::move(b), test_key(), s);
        }
        (void)a->open({}).value();
        addr_b = b->open({}).value();
        bytes.reserve(k_max_size);
    }

    static SimulatedNetworkSettings settings_for(const LinkSettings& link)
    {
        SimulatedNetworkSettings s;
        s.seed = 5;
        s.link = link;
        return s;
    }

    bool connect()
    {
        a_to_b = a->connect(addr_b).value();
        bool a_up = false;
        for (int step = 0; step < 5000 && !(a_up && b_to_a.value != 0); ++step)
        {
            net.advance(0.001);
            while (a->poll_into(ev))
                a_up = a_up || ev.kind == TransportEvent::Kind::Connected;
            while (b->poll_into(ev))
                if (ev.kind == TransportEvent::Kind::Connected)
                    b_to_a = ev.peer;
        }
        return a_up && b_to_a.value != 0;
    }

    /// `a` sends three datagrams (reliable on Control, unreliable and unsequenced on State); `b`
    /// echoes each one it receives on its channel (Control reliably, State unsequenced).
    void round(std::uint32_t i)
    {
        fill(bytes, 3 * i);
        (void)a->send(a_to_b, Channel::Control, bytes, Delivery::Reliable);
        fill(bytes, 3 * i + 1);
        (void)a->send(a_to_b, Channel::State, bytes, Delivery::Unreliable);
        fill(bytes, 3 * i + 2);
        (void)a->send(a_to_b, Channel::State, bytes, Delivery::Unsequenced);
        net.advance(0.001);
        while (b->poll_into(ev))
            if (ev.kind == TransportEvent::Kind::Received)
            {
                ++received;
                corrupt += intact(ev.data) ? 0 : 1;
                (void)b->send(
                    b_to_a, ev.channel, ev.data,
                    ev.channel == Channel::Control ? Delivery::Reliable : Delivery::Unsequenced);
            }
        net.advance(0.001);
        while (a->poll_into(ev))
            if (ev.kind == TransportEvent::Kind::Received)
            {
                ++received;
                corrupt += intact(ev.data) ? 0 : 1;
            }
            else
            {
                ++other;  // nothing but data once connected
            }
    }

    SimulatedNetwork net;
    std::unique_ptr<Transport> a;
    std::unique_ptr<Transport> b;
    Address addr_b;
    PeerHandle a_to_b;
    PeerHandle b_to_a;
    TransportEvent ev;             ///< the one event both ends poll into
    std::vector<std::byte> bytes;  ///< the datagram to send
    std::size_t received = 0;
    std::size_t corrupt = 0;
    std::size_t other = 0;
};

struct Case
{
    const char* name;
    bool secure;
    LinkSettings link;
    std::uint32_t warm_up;  ///< rounds
};

const LinkSettings k_clean{};
const LinkSettings k_bad{.latency_s = 0.003,
                         .jitter_s = 0.002,
                         .loss = 0.1,
                         .duplicate = 0.1,
                         .reorder = 0.1,
                         .reorder_delay_s = 0.004};

void check(const Case& c)
{
    SCOPED_TRACE(c.name);
    Rig rig(c.link, c.secure);
    ASSERT_TRUE(rig.connect());
    for (std::uint32_t i = 0; i < c.warm_up; ++i)
        rig.round(i);
    const std::size_t received_before = rig.received;
    constexpr std::uint32_t k_rounds = 1000;
    const std::uint64_t before = test::allocations();
    for (std::uint32_t i = c.warm_up; i < c.warm_up + k_rounds; ++i)
        rig.round(i);
    const std::uint64_t allocated = test::allocations() - before;
    EXPECT_EQ(allocated, 0u) << "in " << k_rounds << " rounds (" << rig.received - received_before
                             << " datagrams received)";
    EXPECT_EQ(rig.corrupt, 0u);
    EXPECT_EQ(rig.other, 0u);
    // Every datagram and its echo arrived on the clean link; most on the bad one.
    if (c.link.loss == 0.0)
        EXPECT_EQ(rig.received - received_before, 6u * k_rounds);
    else
        EXPECT_GT(rig.received - received_before, 4u * k_rounds);
}

// The clean link is periodic: once the largest datagram has been sent and every buffer has gone
// round, nothing grows. On the bad link the number of packets in flight at once (and of reliable
// ones held behind a lost one) is a random walk whose new peaks each cost a buffer or a map node,
// rarer and rarer: with this seed the warm-up has passed the measured rounds' peaks (a loss or a
// duplicate whose buffer were not recycled would cost hundreds here).
TEST(SimulatedTransportAllocation, SendAndPollIntoAllocateNothingOnceWarm)
{
    check({"clean link", false, k_clean, 300});
    check({"loss, duplication, reordering", false, k_bad, 4000});
}

TEST(SecureTransportAllocation, SendAndPollIntoAllocateNothingOnceWarm)
{
    check({"clean link", true, k_clean, 300});
    check({"loss, duplication, reordering", true, k_bad, 4000});
}

}  // namespace
}  // namespace pliant::net
