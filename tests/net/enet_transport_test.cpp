// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// EnetTransport on 127.0.0.1 with ephemeral ports: two hosts connect, exchange reliable and
// unreliable messages and disconnect with a reason; bad bytes sent through ENet are dropped and
// counted and finally cut the sender off; raw UDP junk at the port does not disturb a connection;
// a handshake whose acknowledgement is lost still completes on the acceptor's side; wait() ends
// when a datagram arrives.
// Every wait is a bounded loop with a wall-clock deadline that keeps servicing both hosts
// (TESTING-NOTES: an unserviced ENet peer times out). Skipped with a reason if no socket binds.

#include <pliant/net/enet_transport.h>
#include <pliant/net/messenger.h>

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "net/sample_messages.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <functional>
#include <optional>
#include <span>
#include <thread>
#include <vector>

namespace pliant::net
{
namespace
{

using Clock = std::chrono::steady_clock;
constexpr auto k_deadline = std::chrono::seconds(10);

struct Hosts
{
    std::unique_ptr<Transport> ta = make_enet_transport();
    std::unique_ptr<Transport> tb = make_enet_transport();
    Messenger a{*ta, MessengerSettings{.bad_datagram_limit = 3}};
    Messenger b{*tb, MessengerSettings{.bad_datagram_limit = 3}};
    Address addr_b;
    PeerHandle a_to_b;
    PeerHandle b_to_a;
    std::vector<MessengerEvent> from_a;  // events seen by a
    std::vector<MessengerEvent> from_b;  // events seen by b
    std::string skip_reason;

    Hosts()
    {
        auto ra = ta->open(Address{{127, 0, 0, 1}, 0});
        auto rb = tb->open(Address{{127, 0, 0, 1}, 0});
        if (!ra || !rb)
        {
            skip_reason =
                "cannot bind UDP on 127.0.0.1: " + (!ra ? ra.error() : rb.error()).message;
            return;
        }
        addr_b = *rb;
    }

    /// Services both hosts until `done` or the deadline. \return whether `done` became true.
    bool pump(const std::function<bool()>& done)
    {
        const auto end = Clock::now() + k_deadline;
        while (Clock::now() < end)
        {
            while (auto ev = a.poll(1))
                from_a.push_back(std::move(*ev));
            while (auto ev = b.poll(1))
                from_b.push_back(std::move(*ev));
            if (done())
                return true;
        }
        return false;
    }

    static const MessengerEvent* find(const std::vector<MessengerEvent>& events,
                                      MessengerEvent::Kind kind)
    {
        for (const auto& e : events)
            if (e.kind == kind)
                return &e;
        return nullptr;
    }

    bool connect()
    {
        a_to_b = ta->connect(addr_b).value();
        const bool ok = pump(
            [this]
            {
                return find(from_a, MessengerEvent::Kind::Connected) != nullptr &&
                       find(from_b, MessengerEvent::Kind::Connected) != nullptr;
            });
        if (ok)
            b_to_a = find(from_b, MessengerEvent::Kind::Connected)->peer;
        from_a.clear();
        from_b.clear();
        return ok;
    }

    std::size_t received_by_b() const
    {
        std::size_t n = 0;
        for (const auto& e : from_b)
            n += e.kind == MessengerEvent::Kind::Received ? 1 : 0;
        return n;
    }
};

TEST(EnetTransport, TwoHostsConnectExchangeAndDisconnect)
{
    Hosts h;
    if (!h.skip_reason.empty())
        GTEST_SKIP() << h.skip_reason;
    ASSERT_TRUE(h.connect());
    EXPECT_EQ(h.ta->remote_address(h.a_to_b), h.addr_b);

    // Reliable control messages arrive in order and whole (a Blob of 1,000 bytes, a Welcome);
    // unreliable state messages (LeafState of 1,224 bytes) arrive on loopback too.
    const auto all = samples::all();
    std::vector<Message> control;
    for (const Message& m : all)
    {
        ASSERT_TRUE(h.a.send(h.a_to_b, m));
        if (default_channel(m.type()) == Channel::Control)
            control.push_back(m);
    }
    // A 32 KiB blob chunk: ENet fragments and reassembles it on the reliable channel.
    Blob big{.kind = BlobKind::Model,
             .total_size = 40000,
             .offset = 0,
             .data = std::vector<std::byte>(k_max_blob_chunk, std::byte{0x5A})};
    ASSERT_TRUE(h.a.send(h.a_to_b, Message{samples::header(), big}));
    control.push_back(Message{samples::header(), big});
    ASSERT_TRUE(h.pump([&h, &all] { return h.received_by_b() >= all.size() + 1; }))
        << "received " << h.received_by_b() << " of " << all.size() + 1;
    std::vector<Message> got_control;
    for (const auto& e : h.from_b)
        if (e.kind == MessengerEvent::Kind::Received && e.channel == Channel::Control)
            got_control.push_back(e.message);
    EXPECT_EQ(got_control, control);
    EXPECT_EQ(h.b.dropped(), 0u);
    const auto stats = h.tb->stats(h.b_to_a).value();
    EXPECT_EQ(stats.packets_received, all.size() + 1);
    EXPECT_GT(stats.bytes_received, k_max_blob_chunk);
    EXPECT_EQ(h.ta->stats(h.a_to_b)->bytes_sent, stats.bytes_received);

    // Ping/pong at the application level for an RTT.
    h.from_a.clear();
    ASSERT_TRUE(h.b.send(h.b_to_a, Message{samples::header(), Ping{.nonce = 77, .time_us = 5}}));
    ASSERT_TRUE(h.pump([&h] { return Hosts::find(h.from_a, MessengerEvent::Kind::Received); }));
    const auto* ping = Hosts::find(h.from_a, MessengerEvent::Kind::Received);
    EXPECT_EQ(std::get<Ping>(ping->message.body).nonce, 77u);

    h.a.transport().disconnect(h.a_to_b, DisconnectReason::Quit);
    ASSERT_TRUE(h.pump(
        [&h]
        {
            return Hosts::find(h.from_a, MessengerEvent::Kind::Disconnected) &&
                   Hosts::find(h.from_b, MessengerEvent::Kind::Disconnected);
        }));
    EXPECT_EQ(Hosts::find(h.from_a, MessengerEvent::Kind::Disconnected)->reason,
              DisconnectReason::Quit);
    EXPECT_EQ(Hosts::find(h.from_b, MessengerEvent::Kind::Disconnected)->reason,
              DisconnectReason::Quit);
    EXPECT_TRUE(h.ta->peers().empty());
}

// A connection closed and flushed keeps its reason when the transport is destroyed right after,
// as a process that exits at once (a session master that leaves says Quit, and its peers then
// promote a successor instead of ending the session as on Shutdown: docs/session.md §6).
TEST(EnetTransport, DestroyingATransportKeepsTheReasonOfAClosedConnection)
{
    Hosts h;
    if (!h.skip_reason.empty())
        GTEST_SKIP() << h.skip_reason;
    ASSERT_TRUE(h.connect());
    h.ta->disconnect(h.a_to_b, DisconnectReason::Quit);
    h.ta->flush();
    h.ta.reset();
    const auto end = Clock::now() + k_deadline;
    while (Clock::now() < end && !Hosts::find(h.from_b, MessengerEvent::Kind::Disconnected))
        while (auto ev = h.b.poll(1))
            h.from_b.push_back(std::move(*ev));
    const auto* ev = Hosts::find(h.from_b, MessengerEvent::Kind::Disconnected);
    ASSERT_NE(ev, nullptr);
    EXPECT_EQ(ev->reason, DisconnectReason::Quit);
}

// wait() is a wait on the socket, not a sleep (docs/session.md §4.1): with nothing to read it
// takes its time (returning at once would make every idle loop spin); a datagram ends it (b
// sends 0.2 s into a wait of 30 s: a sleep would take the 30 s); and events ENet has already
// taken off the socket but not handed out end it at once (two pings in one flush: after the
// first is polled, the second waits in ENet's dispatch queue while the socket is empty).
TEST(EnetTransport, WaitEndsWhenADatagramArrivesAndOtherwiseTakesItsTime)
{
    using namespace std::chrono_literals;
    Hosts h;
    if (!h.skip_reason.empty())
        GTEST_SKIP() << h.skip_reason;
    ASSERT_TRUE(h.connect());
    while (auto ev = h.a.poll(0))  // drain; b is not serviced from here until it sends
        h.from_a.push_back(std::move(*ev));

    auto t0 = Clock::now();
    h.ta->wait(0.05);
    EXPECT_GE(Clock::now() - t0, 40ms) << "wait() returned with nothing to read";

    std::thread sender(
        [&h]
        {
            std::this_thread::sleep_for(200ms);
            (void)h.b.send(h.b_to_a, Message{samples::header(), Ping{.nonce = 1, .time_us = 1}});
            h.tb->flush();
        });
    t0 = Clock::now();
    h.ta->wait(30.0);
    const auto waited = Clock::now() - t0;
    sender.join();
    EXPECT_LT(waited, 15s) << "wait() did not end when the datagram arrived";
    ASSERT_TRUE(h.pump([&h] { return Hosts::find(h.from_a, MessengerEvent::Kind::Received); }));

    h.from_a.clear();
    while (auto ev = h.a.poll(0))
        h.from_a.push_back(std::move(*ev));
    h.from_a.clear();
    for (std::uint32_t nonce : {2U, 3U})
        ASSERT_TRUE(
            h.b.send(h.b_to_a, Message{samples::header(), Ping{.nonce = nonce, .time_us = 1}}));
    h.tb->flush();
    auto first = h.a.poll(1000);
    ASSERT_TRUE(first.has_value());
    ASSERT_EQ(first->kind, MessengerEvent::Kind::Received);
    EXPECT_EQ(std::get<Ping>(first->message.body).nonce, 2u);
    t0 = Clock::now();
    h.ta->wait(30.0);
    EXPECT_LT(Clock::now() - t0, 15s) << "wait() slept over an event ENet already held";
    auto second = h.a.poll(1000);
    ASSERT_TRUE(second.has_value());
    EXPECT_EQ(std::get<Ping>(second->message.body).nonce, 3u);
}

TEST(EnetTransport, BadBytesAreDroppedCountedAndCutTheSenderOff)
{
    Hosts h;
    if (!h.skip_reason.empty())
        GTEST_SKIP() << h.skip_reason;
    ASSERT_TRUE(h.connect());
    const std::vector<std::byte> junk(100, std::byte{0xEE});
    for (int i = 0; i < 3; ++i)
        ASSERT_TRUE(h.ta->send(h.a_to_b, Channel::Control, junk, Delivery::Reliable));
    ASSERT_TRUE(
        h.a.send(h.a_to_b, Message{samples::header(), Heartbeat{.epoch = 1}}, SendMode::Reliable));
    ASSERT_TRUE(h.pump([&h] { return h.received_by_b() == 1; }));
    EXPECT_EQ(h.tb->stats(h.b_to_a)->bad_datagrams, 3u);
    EXPECT_EQ(h.b.dropped(), 3u);

    ASSERT_TRUE(h.ta->send(h.a_to_b, Channel::Control, junk, Delivery::Reliable));
    ASSERT_TRUE(h.pump([&h] { return Hosts::find(h.from_a, MessengerEvent::Kind::Disconnected); }));
    EXPECT_EQ(Hosts::find(h.from_a, MessengerEvent::Kind::Disconnected)->reason,
              DisconnectReason::TooManyBadDatagrams);
    ASSERT_TRUE(h.pump([&h] { return Hosts::find(h.from_b, MessengerEvent::Kind::Disconnected); }));
    EXPECT_EQ(h.received_by_b(), 1u);
}

TEST(EnetTransport, RawUdpJunkDoesNotDisturbAConnection)
{
    Hosts h;
    if (!h.skip_reason.empty())
        GTEST_SKIP() << h.skip_reason;
    ASSERT_TRUE(h.connect());
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (fd < 0)
        GTEST_SKIP() << "cannot create a UDP socket";
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(h.addr_b.port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    std::uint32_t x = 12345;
    for (int i = 0; i < 200; ++i)
    {
        std::array<std::uint8_t, 256> junk{};
        const std::size_t n = 1 + static_cast<std::size_t>(i) % junk.size();
        for (std::size_t k = 0; k < n; ++k)
            junk[k] = static_cast<std::uint8_t>((x = x * 1664525u + 1013904223u) >> 24);
        (void)::sendto(fd, junk.data(), n, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
    }
    ::close(fd);
    ASSERT_TRUE(
        h.a.send(h.a_to_b, Message{samples::header(), Heartbeat{.epoch = 2}}, SendMode::Reliable));
    ASSERT_TRUE(h.pump([&h] { return h.received_by_b() == 1; }));
    EXPECT_EQ(h.b.dropped(), 0u);  // ENet itself discards what is not ENet protocol
    EXPECT_EQ(h.tb->peers().size(), 1u);
}

// A port in use is refused with the system's reason and what to do about it.
TEST(EnetTransport, APortInUseIsRefusedWithTheReason)
{
    auto first = make_enet_transport();
    auto taken = first->open(Address{{127, 0, 0, 1}, 0});
    if (!taken)
        GTEST_SKIP() << "cannot bind UDP on 127.0.0.1: " << taken.error().message;
    auto second = make_enet_transport();
    auto again = second->open(Address{{127, 0, 0, 1}, taken->port});
    ASSERT_FALSE(again);
    EXPECT_EQ(again.error().code, core::ErrorCode::NetworkError);
    EXPECT_NE(again.error().message.find(std::to_string(taken->port)), std::string::npos)
        << again.error().message;
    EXPECT_NE(again.error().message.find(std::strerror(EADDRINUSE)), std::string::npos)
        << again.error().message;
    EXPECT_NE(again.error().message.find("--port"), std::string::npos) << again.error().message;
}

// A host with no room answers: the dialer beyond max_peers, or beyond max_peers_per_source from
// one address, is disconnected with reason SessionFull within a round trip or so (ENet alone
// ignores a CONNECT when its slots are taken, and the dialer timed out after 5 s, "never
// answered"). The host reports neither that connection nor its end, counts it, and takes a new
// dialer once a slot is free again.
TEST(EnetTransport, AHostWithNoRoomSaysSoInsteadOfStayingSilent)
{
    for (const bool per_source : {false, true})
    {
        SCOPED_TRACE(per_source ? "max_peers_per_source 2" : "max_peers 2");
        EnetSettings hs;
        hs.max_peers = per_source ? 8 : 2;
        hs.max_peers_per_source = per_source ? 2 : 16;
        auto host = make_enet_transport(hs);
        auto bound = host->open(Address{{127, 0, 0, 1}, 0});
        if (!bound)
            GTEST_SKIP() << bound.error().message;
        std::vector<std::unique_ptr<Transport>> dialers;
        std::vector<std::optional<TransportEvent>> last(4);
        std::vector<TransportEvent> at_host;
        const auto pump_until = [&](const std::function<bool()>& done)
        {
            const auto end = Clock::now() + k_deadline;
            while (Clock::now() < end && !done())
            {
                while (auto ev = host->poll(1))
                    at_host.push_back(std::move(*ev));
                for (std::size_t k = 0; k < dialers.size(); ++k)
                    while (auto ev = dialers[k]->poll(0))
                        last[k] = std::move(*ev);
            }
            return done();
        };
        const auto dial = [&]
        {
            dialers.push_back(make_enet_transport());
            ASSERT_TRUE(dialers.back()->open(Address{{127, 0, 0, 1}, 0}));
            ASSERT_TRUE(dialers.back()->connect(*bound));
        };
        const auto is = [&](std::size_t k, TransportEvent::Kind kind)
        { return last[k] && last[k]->kind == kind; };
        for (int k = 0; k < 2; ++k)
            dial();
        ASSERT_TRUE(pump_until([&] { return at_host.size() == 2; }));
        ASSERT_TRUE(pump_until(
            [&] {
                return is(0, TransportEvent::Kind::Connected) &&
                       is(1, TransportEvent::Kind::Connected);
            }));
        const auto t0 = Clock::now();
        dial();
        ASSERT_TRUE(pump_until([&] { return is(2, TransportEvent::Kind::Disconnected); }));
        EXPECT_EQ(last[2]->reason, DisconnectReason::SessionFull);
        EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 2.0)
            << "answered, not timed out";
        EXPECT_EQ(at_host.size(), 2U) << "the refused connection is not reported";
        EXPECT_EQ(host->peers().size(), 2U);
        const auto counters = enet_counters(*host).value();
        EXPECT_EQ(counters.refused_full, per_source ? 0U : 1U);
        EXPECT_EQ(counters.refused_per_source, per_source ? 1U : 0U);
        // A slot freed: the next dialer gets in.
        host->disconnect(at_host[0].peer, DisconnectReason::Quit);
        ASSERT_TRUE(pump_until([&] { return is(0, TransportEvent::Kind::Disconnected); }));
        ASSERT_TRUE(pump_until([&] { return at_host.size() == 3; }));
        dial();
        ASSERT_TRUE(pump_until([&] { return is(3, TransportEvent::Kind::Connected); }));
        ASSERT_TRUE(pump_until([&] { return at_host.size() == 4; }));
        EXPECT_EQ(at_host[3].kind, TransportEvent::Kind::Connected);
        EXPECT_EQ(host->peers().size(), 2U);
    }
}

TEST(EnetTransport, ConnectingToAClosedPortTimesOut)
{
    EnetSettings s;
    s.connect_timeout_ms = 300;
    auto t = make_enet_transport(s);
    auto bound = t->open(Address{{127, 0, 0, 1}, 0});
    if (!bound)
        GTEST_SKIP() << bound.error().message;
    // A port nobody listens on: bound by a probe host, then released.
    Address nowhere;
    {
        auto probe = make_enet_transport();
        auto r = probe->open(Address{{127, 0, 0, 1}, 0});
        if (!r)
            GTEST_SKIP() << r.error().message;
        nowhere = *r;
    }
    const PeerHandle h = t->connect(nowhere).value();
    std::optional<TransportEvent> ev;
    const auto end = Clock::now() + k_deadline;
    while (!ev && Clock::now() < end)
        ev = t->poll(5);
    ASSERT_TRUE(ev.has_value());
    EXPECT_EQ(ev->kind, TransportEvent::Kind::Disconnected);
    EXPECT_EQ(ev->peer, h);
    EXPECT_EQ(ev->reason, DisconnectReason::TimedOut);
}
// ENet's handshake: the dialer's CONNECT, the acceptor's VERIFY_CONNECT (resent on ENet's timer:
// 0.5 s, then doubling, until acknowledged), the dialer's acknowledgement. The dialer is
// connected once VERIFY_CONNECT arrives; the acceptor only once the acknowledgement does, and it
// drops the dialer's data until then. HandshakeRelay sits between the two transports on
// 127.0.0.1 (two plain UDP sockets the test pumps: the dialer dials `front`, `back` talks to the
// acceptor), drops the dialer's datagrams that lead with an acknowledgement (ENet command 1)
// while `drop_ack` says so, and those `drop_forward` picks, notes the sent-time field of every
// VERIFY_CONNECT the acceptor sends (ENet stamps it from the acceptor's own clock, in ms), and
// holds every datagram `delay` before passing it on (in order: the delay is the same for all).
struct HandshakeRelay
{
    std::unique_ptr<Transport> acceptor;
    std::unique_ptr<Transport> dialer;
    int front = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0);  // the dialer's side
    int back = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0);   // the acceptor's side
    sockaddr_in to_acceptor{};
    sockaddr_in to_dialer{};
    Address front_address;
    bool ok = false;
    std::function<bool()> drop_ack;
    int acks_dropped = 0;
    /// Sees each datagram from the dialer (after drop_ack); true drops it.
    std::function<bool(std::span<const std::uint8_t>)> drop_forward;
    std::vector<std::uint16_t> verify_sent;  // sent-time fields of the VERIFY_CONNECTs relayed
    std::chrono::milliseconds delay{0};      // one way, each way
    struct Held
    {
        Clock::time_point due;
        bool to_acceptor = false;
        std::vector<std::uint8_t> bytes;
    };
    std::deque<Held> held;
    std::array<std::uint8_t, 4096> buf{};

    explicit HandshakeRelay(const EnetSettings& settings = {})
        : acceptor(make_enet_transport(settings)), dialer(make_enet_transport(settings))
    {
        auto ra = acceptor->open(Address{{127, 0, 0, 1}, 0});
        auto rd = dialer->open(Address{{127, 0, 0, 1}, 0});
        sockaddr_in any{};
        any.sin_family = AF_INET;
        any.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        if (!ra || !rd || front < 0 || back < 0 ||
            ::bind(front, reinterpret_cast<sockaddr*>(&any), sizeof(any)) != 0 ||
            ::bind(back, reinterpret_cast<sockaddr*>(&any), sizeof(any)) != 0)
            return;
        // Room for a burst of a reliable window (capped by the kernel's rmem_max unless forced,
        // which only root may; failure is harmless).
        const int room = 4 << 20;
        for (const int fd : {front, back})
            if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &room, sizeof room) != 0)
                (void)::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &room, sizeof room);
        sockaddr_in front_addr{};
        socklen_t len = sizeof(front_addr);
        ::getsockname(front, reinterpret_cast<sockaddr*>(&front_addr), &len);
        front_address = Address{{127, 0, 0, 1}, ntohs(front_addr.sin_port)};
        to_acceptor = any;
        to_acceptor.sin_port = htons(ra->port);
        to_dialer = any;
        to_dialer.sin_port = htons(rd->port);
        ok = true;
    }
    ~HandshakeRelay()
    {
        ::close(front);
        ::close(back);
    }
    HandshakeRelay(const HandshakeRelay&) = delete;
    HandshakeRelay& operator=(const HandshakeRelay&) = delete;

    // ENet header: 2 bytes (peer id and flags), 2 more (the sent time) with the sent-time flag;
    // then commands, each led by its number in the low nibble.
    [[nodiscard]] std::size_t first_command(std::size_t n) const
    {
        const std::size_t at = (buf[0] & 0x80) != 0 ? 4 : 2;
        return at < n ? at : n;
    }

    // On to the acceptor (`forward`) or back to the dialer, now or after `delay`.
    void pass(bool forward, std::size_t n)
    {
        if (delay.count() > 0)
        {
            held.push_back(Held{Clock::now() + delay,
                                forward,
                                {buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n)}});
            return;
        }
        send(forward, buf.data(), n);
    }
    void send(bool forward, const std::uint8_t* data, std::size_t n) const
    {
        const sockaddr_in& to = forward ? to_acceptor : to_dialer;
        (void)::sendto(forward ? back : front, data, n, 0, reinterpret_cast<const sockaddr*>(&to),
                       sizeof(to));
    }

    // Moves what waits on the relay's sockets, both ways, and what is due of the held.
    void pump()
    {
        for (int k = 0; k < 64; ++k)
        {
            const ssize_t n = ::recv(front, buf.data(), buf.size(), 0);
            if (n <= 0)
                break;
            const auto len = static_cast<std::size_t>(n);
            const std::size_t at = first_command(len);
            if (at < len && (buf[at] & 0x0F) == 1 && drop_ack && drop_ack())
            {
                ++acks_dropped;
                continue;
            }
            if (drop_forward && drop_forward(std::span<const std::uint8_t>(buf.data(), len)))
                continue;
            pass(true, len);
        }
        for (int k = 0; k < 64; ++k)
        {
            const ssize_t n = ::recv(back, buf.data(), buf.size(), 0);
            if (n <= 0)
                break;
            // VERIFY_CONNECT (3) follows the acknowledgement of CONNECT (8 bytes) or leads.
            std::size_t at = first_command(static_cast<std::size_t>(n));
            while (at < static_cast<std::size_t>(n) && (buf[at] & 0x0F) == 1)
                at += 8;
            if ((buf[0] & 0x80) != 0 && at < static_cast<std::size_t>(n) && (buf[at] & 0x0F) == 3)
                verify_sent.push_back(static_cast<std::uint16_t>((buf[2] << 8) | buf[3]));
            pass(false, static_cast<std::size_t>(n));
        }
        const auto now = Clock::now();
        while (!held.empty() && held.front().due <= now)
        {
            send(held.front().to_acceptor, held.front().bytes.data(), held.front().bytes.size());
            held.pop_front();
        }
    }
};

// The acceptor is still half-open when half_open_timeout_ms (1.2 s) passes, while the dialer is
// already sending: the relay drops every acknowledgement for the first 2 s. The acceptor must
// keep the connection (the dialer's datagrams prove it received VERIFY_CONNECT) so that a later
// VERIFY_CONNECT completes it; resetting it, as for a spoofed CONNECT, would leave the dialer
// sending into nothing.
TEST(EnetTransport, AHandshakeWhoseAcknowledgementIsLostCompletes)
{
    HandshakeRelay r;
    if (!r.ok)
        GTEST_SKIP() << "cannot bind UDP on 127.0.0.1";
    const auto dialled = Clock::now();
    r.drop_ack = [&] { return Clock::now() < dialled + std::chrono::milliseconds(2000); };
    const PeerHandle h = r.dialer->connect(r.front_address).value();
    bool dialer_connected = false;
    bool sent = false;
    std::optional<PeerHandle> accepted;
    std::vector<std::byte> got;
    const std::vector<std::byte> hello{std::byte{1}, std::byte{2}, std::byte{3}};
    const auto end = Clock::now() + k_deadline;
    while (Clock::now() < end && got.empty())
    {
        r.pump();
        while (auto e = r.dialer->poll(0))
            dialer_connected =
                dialer_connected || (e->kind == TransportEvent::Kind::Connected && e->peer == h);
        if (dialer_connected && !sent)
            sent =
                static_cast<bool>(r.dialer->send(h, Channel::Control, hello, Delivery::Reliable));
        while (auto e = r.acceptor->poll(1))
        {
            if (e->kind == TransportEvent::Kind::Connected)
                accepted = e->peer;
            else if (e->kind == TransportEvent::Kind::Received)
                got = e->data;
        }
    }
    EXPECT_GE(r.acks_dropped, 1);
    EXPECT_TRUE(dialer_connected);
    EXPECT_TRUE(accepted.has_value()) << "the acceptor reset a handshake the dialer had completed";
    EXPECT_EQ(got, hello);
    const EnetCounters c = enet_counters(*r.acceptor).value();
    EXPECT_EQ(c.half_open_reset, 0u);
    EXPECT_EQ(c.half_open_kept, 1u);
}

// The dialer's answer on a half-open connection also makes the acceptor resend VERIFY_CONNECT
// at once (k_verify_hasten_ms after the last copy at the earliest), not at ENet's timer. The
// relay drops the first two acknowledgements; the dialer, once connected, sends a datagram
// every 10 ms, as a session's repeated greeting does. ENet never resends sooner than 500 ms on
// a connection with no round-trip sample, and doubles that at each resend, so two consecutive
// VERIFY_CONNECTs less than 500 ms apart on the acceptor's own clock were hastened. Two
// chances, so one scheduler stall past ENet's timer cannot hide it.
TEST(EnetTransport, ADialersAnswerBringsTheNextVerifyForward)
{
    HandshakeRelay r;
    if (!r.ok)
        GTEST_SKIP() << "cannot bind UDP on 127.0.0.1";
    r.drop_ack = [&] { return r.acks_dropped < 2; };
    const PeerHandle h = r.dialer->connect(r.front_address).value();
    bool dialer_connected = false;
    std::optional<PeerHandle> accepted;
    std::size_t received = 0;
    const std::vector<std::byte> hello{std::byte{4}, std::byte{5}};
    auto next_send = Clock::now();
    const auto end = Clock::now() + k_deadline;
    while (Clock::now() < end && received == 0)
    {
        r.pump();
        while (auto e = r.dialer->poll(0))
            dialer_connected =
                dialer_connected || (e->kind == TransportEvent::Kind::Connected && e->peer == h);
        if (dialer_connected && Clock::now() >= next_send)
        {
            (void)r.dialer->send(h, Channel::State, hello, Delivery::Unsequenced);
            r.dialer->flush();
            next_send = Clock::now() + std::chrono::milliseconds(10);
        }
        while (auto e = r.acceptor->poll(1))
        {
            if (e->kind == TransportEvent::Kind::Connected)
                accepted = e->peer;
            else if (e->kind == TransportEvent::Kind::Received && e->data == hello)
                ++received;
        }
    }
    EXPECT_EQ(r.acks_dropped, 2);
    ASSERT_TRUE(dialer_connected);
    ASSERT_TRUE(accepted.has_value());
    EXPECT_GE(received, 1u);
    const EnetCounters c = enet_counters(*r.acceptor).value();
    EXPECT_GE(c.verify_hastened, 1u);
    ASSERT_GE(r.verify_sent.size(), 2u);
    std::uint32_t shortest = 1U << 16U;
    for (std::size_t k = 1; k < r.verify_sent.size(); ++k)
        shortest = std::min<std::uint32_t>(
            shortest, static_cast<std::uint16_t>(r.verify_sent[k] - r.verify_sent[k - 1]));
    EXPECT_LT(shortest, 500u) << r.verify_sent.size() << " VERIFY_CONNECTs";
    EXPECT_GE(shortest, k_verify_hasten_ms) << "resent sooner than the rate limit";
}

// A reliable message whose first four copies are lost, among messages sent every 10 ms through a
// relay that holds every datagram 60 ms each way (a 120 ms round trip).
struct RepeatedLoss
{
    bool connected = false;
    std::vector<std::uint32_t> received;  // message numbers, in the order they arrived
    std::vector<std::uint16_t> copies;    // sent-time fields of the watched message's datagrams
    std::uint64_t fast_retransmits = 0;
};

constexpr std::uint32_t k_loss_messages = 100;
constexpr std::uint32_t k_loss_watched = 30;  // after 30 round-trip samples
constexpr std::size_t k_loss_dropped = 4;

std::vector<std::byte> numbered(std::uint32_t k)
{
    std::vector<std::byte> m(64, std::byte{0});
    const char tag[4] = {'L', 'O', 'S', 'T'};
    std::memcpy(m.data(), tag, 4);
    std::memcpy(m.data() + 4, &k, 4);
    return m;
}

RepeatedLoss lose_one_message_repeatedly(bool fast_retransmit)
{
    EnetSettings settings;
    settings.fast_retransmit = fast_retransmit;
    HandshakeRelay r(settings);
    RepeatedLoss out;
    if (!r.ok)
        return out;
    r.delay = std::chrono::milliseconds(60);
    std::vector<std::uint8_t> watched(64);
    std::memcpy(watched.data(), numbered(k_loss_watched).data(), watched.size());
    r.drop_forward = [&](std::span<const std::uint8_t> b)
    {
        if (std::search(b.begin(), b.end(), watched.begin(), watched.end()) == b.end())
            return false;
        out.copies.push_back((b[0] & 0x80) != 0 ? static_cast<std::uint16_t>((b[2] << 8) | b[3])
                                                : std::uint16_t{0});
        return out.copies.size() <= k_loss_dropped;
    };
    const PeerHandle h = r.dialer->connect(r.front_address).value();
    std::uint32_t sent = 0;
    auto next_send = Clock::now();
    const auto end = Clock::now() + k_deadline;
    while (Clock::now() < end && out.received.size() < k_loss_messages)
    {
        r.pump();
        while (auto e = r.dialer->poll(0))
            out.connected =
                out.connected || (e->kind == TransportEvent::Kind::Connected && e->peer == h);
        if (out.connected && sent < k_loss_messages && Clock::now() >= next_send)
        {
            (void)r.dialer->send(h, Channel::Control, numbered(sent++), Delivery::Reliable);
            r.dialer->flush();
            next_send += std::chrono::milliseconds(10);
        }
        while (auto e = r.acceptor->poll(1))
            if (e->kind == TransportEvent::Kind::Received && e->data.size() == 64)
            {
                std::uint32_t k = 0;
                std::memcpy(&k, e->data.data() + 4, 4);
                out.received.push_back(k);
            }
    }
    out.fast_retransmits = enet_counters(*r.dialer).value().fast_retransmits;
    return out;
}

// ENet alone resends a lost reliable command when its timer runs out (at least a round trip),
// and doubles that timer at every resend: four losses of one command cost at least
// 1 + 2 + 4 + 8 round trips, 1.8 s here. With fast_retransmit each copy is resent once
// commands sent after it are acknowledged and it has waited a round trip and a quarter: about
// 4 x 150 ms. Both runs must deliver every message, in order; the gap from the first copy to the
// one that got through, on the sender's own clock (ENet's sent-time field), tells them apart
// with room for a slow machine either way.
TEST(EnetTransport, AReliableCommandLostRepeatedlyIsResentOnLaterAcknowledgements)
{
    std::vector<std::uint32_t> all(k_loss_messages);
    for (std::uint32_t k = 0; k < k_loss_messages; ++k)
        all[k] = k;
    for (const bool fast : {true, false})
    {
        const RepeatedLoss run = lose_one_message_repeatedly(fast);
        if (!run.connected && run.copies.empty())
            GTEST_SKIP() << "cannot bind UDP on 127.0.0.1, or no connection through the relay";
        SCOPED_TRACE(fast ? "fast_retransmit" : "ENet's timer alone");
        EXPECT_EQ(run.received, all);
        ASSERT_GT(run.copies.size(), k_loss_dropped);
        const auto gap = static_cast<std::uint16_t>(run.copies[k_loss_dropped] - run.copies[0]);
        std::printf("%s: copy %zu of the message went %u ms after the first (%llu fast resends)\n",
                    fast ? "fast_retransmit" : "ENet's timer", k_loss_dropped + 1,
                    static_cast<unsigned>(gap),
                    static_cast<unsigned long long>(run.fast_retransmits));
        if (fast)
        {
            EXPECT_LT(gap, 1200u) << run.copies.size() << " copies";
            EXPECT_GE(run.fast_retransmits, 2u);
        }
        else
        {
            EXPECT_GE(gap, 1200u) << run.copies.size() << " copies";
            EXPECT_EQ(run.fast_retransmits, 0u);
        }
    }
}

// The transport reads the ACKNOWLEDGE commands of every datagram from a connected peer's address
// before ENet does (fast_retransmit). Mangled copies of the dialer's real datagrams (its peer id
// and session bits kept, so they pass as its own; random bytes laid out as commands, below, up to
// 1,400 bytes) reach the acceptor, 16 per real datagram once 20 messages have gone through (both
// sides connected), 2,048 in all. The reading must stay within each datagram whatever its
// commands claim (AddressSanitizer in the sanitizer build), and the acceptor must go on polling.
// ENet takes the mangled bytes too, and may take a forged acknowledgement for a real command
// (the channel then stalls), so only the reading is checked, and that the connection was up for
// it: a smoke test of hostile bytes, as the decoder's fuzz target is for pliant's own.
TEST(EnetTransport, MangledDatagramsFromAConnectedPeerAreReadSafely)
{
    HandshakeRelay r;
    if (!r.ok)
        GTEST_SKIP() << "cannot bind UDP on 127.0.0.1";
    std::uint32_t x = 2026;
    auto next = [&x] { return (x = x * 1664525u + 1013904223u) >> 8; };
    int mangled = 0;
    bool connected = false;
    std::size_t received = 0;  // 20 first: both sides connected, acknowledgements flowing
    std::vector<std::uint8_t> copy(1400);
    r.drop_forward = [&](std::span<const std::uint8_t> b)
    {
        for (int k = 0; k < 16 && received >= 20 && mangled < 2048 && b.size() >= 2; ++k, ++mangled)
        {
            const std::size_t head = (b[0] & 0x80) != 0 ? 4 : 2;
            const std::size_t n = head + 24 + next() % (copy.size() - head - 24);
            copy[0] = b[0];
            copy[1] = b[1];
            for (std::size_t i = 2; i < n; ++i)
                copy[i] = static_cast<std::uint8_t>(next());
            // Laid out as commands that look right to the end: acknowledgements, and data
            // commands whose lengths lie, on channels the peer does not have (ENet stops
            // reading the datagram at the first of those, the transport's reading goes on);
            // never a DISCONNECT, which would end the connection and the reading with it.
            constexpr std::array<std::uint8_t, 5> numbers{1, 6, 7, 8, 9};
            constexpr std::array<std::size_t, 10> sizes{0, 8, 0, 0, 0, 0, 6, 8, 24, 8};
            for (std::size_t at = head; at + 24 <= n;)
            {
                const std::uint8_t number = numbers[next() % numbers.size()];
                copy[at] = static_cast<std::uint8_t>(number | (next() & 0xC0));
                copy[at + 1] = number == 1 ? static_cast<std::uint8_t>(next())
                                           : static_cast<std::uint8_t>(2 + next() % 250);
                at += sizes[number] + (number == 1 ? 0 : next() % 64);
                if (at + 24 > n && at + 6 <= n)
                {
                    copy[at] = 6;  // the rest behind a command ENet stops at
                    copy[at + 1] = 7;
                }
            }
            r.send(true, copy.data(), n);
        }
        return false;
    };
    const PeerHandle h = r.dialer->connect(r.front_address).value();
    int sent = 0;
    bool closed = false;
    const auto end = Clock::now() + std::chrono::seconds(3);
    while (Clock::now() < end && (mangled < 2048 || sent < 300))
    {
        r.pump();
        while (auto e = r.dialer->poll(0))
            connected = connected || (e->kind == TransportEvent::Kind::Connected && e->peer == h);
        if (connected && sent < 300)
        {
            (void)r.dialer->send(h, Channel::Control, numbered(static_cast<std::uint32_t>(sent++)),
                                 Delivery::Reliable);
            r.dialer->flush();
        }
        while (auto e = r.acceptor->poll(1))
        {
            received += e->kind == TransportEvent::Kind::Received ? 1 : 0;
            closed = closed || e->kind == TransportEvent::Kind::Disconnected;
        }
    }
    EXPECT_TRUE(connected);
    EXPECT_GE(received, 20u);
    EXPECT_FALSE(closed) << "a mangled datagram closed the connection: the rest were not read";
    EXPECT_EQ(mangled, 2048) << "the relay saw too few of the dialer's datagrams";
    std::printf("%d mangled datagrams; %d messages sent, %zu received; the connection %s\n",
                mangled, sent, received, closed ? "closed" : "stayed");
}

// Hands ENet 20 reliable messages of 32 KiB at once, to a peer 100 ms away each way, and
// returns the datagram bytes the relay saw from the sender within 100 ms of the first large
// one: no acknowledgement can be back by then, so that is what the reliable window let out
// unacknowledged. `all_arrived`: every message, whole and in order.
std::size_t first_flight_bytes(std::uint32_t window, bool& all_arrived)
{
    EnetSettings settings;
    settings.reliable_window_bytes = window;
    HandshakeRelay r(settings);
    all_arrived = false;
    if (!r.ok)
        return 0;
    r.delay = std::chrono::milliseconds(100);
    std::size_t bytes = 0;
    std::optional<Clock::time_point> first;
    r.drop_forward = [&](std::span<const std::uint8_t> b)
    {
        const auto now = Clock::now();
        if (b.size() > 1000 && !first)
            first = now;
        if (first && now - *first < std::chrono::milliseconds(100))
            bytes += b.size();
        return false;
    };
    constexpr std::size_t k_messages = 20;
    std::vector<std::vector<std::byte>> sent;
    for (std::size_t k = 0; k < k_messages; ++k)
    {
        sent.emplace_back(32 * 1024);
        for (std::size_t i = 0; i < sent.back().size(); ++i)
            sent.back()[i] = static_cast<std::byte>((i * 7 + k * 13) & 0xFF);
    }
    const PeerHandle h = r.dialer->connect(r.front_address).value();
    bool connected = false;
    bool accepted = false;
    std::vector<std::vector<std::byte>> got;
    const auto end = Clock::now() + k_deadline;
    while (Clock::now() < end && got.size() < k_messages)
    {
        r.pump();
        while (auto e = r.dialer->poll(0))
            if (e->kind == TransportEvent::Kind::Connected && e->peer == h && !connected)
            {
                connected = true;
                for (const auto& m : sent)
                    (void)r.dialer->send(h, Channel::Control, m, Delivery::Reliable);
                r.dialer->flush();
            }
        while (auto e = r.acceptor->poll(1))
        {
            accepted = accepted || e->kind == TransportEvent::Kind::Connected;
            if (e->kind == TransportEvent::Kind::Received)
                got.push_back(e->data);
        }
    }
    all_arrived = connected && accepted && got == sent;
    return bytes;
}

// ENet lets at most 64 KiB of reliable data go unacknowledged (its protocol's largest window):
// 0.3 MB/s at a 200 ms round trip. EnetSettings::reliable_window_bytes (256 KiB by default)
// raises that, and a transfer through the wider window still arrives whole and in order.
TEST(EnetTransport, TheReliableWindowIsWiderThanENets)
{
    bool wide_ok = false;
    bool enet_ok = false;
    const std::size_t wide = first_flight_bytes(256 * 1024, wide_ok);
    const std::size_t enet = first_flight_bytes(0, enet_ok);
    if (wide == 0 && enet == 0 && !wide_ok && !enet_ok)
        GTEST_SKIP() << "cannot bind UDP on 127.0.0.1, or no connection through the relay";
    std::printf("first flight: %zu bytes with a 256 KiB window, %zu with ENet's\n", wide, enet);
    EXPECT_TRUE(wide_ok);
    EXPECT_TRUE(enet_ok);
    EXPECT_GT(enet, 48u * 1024u);
    EXPECT_LT(enet, 72u * 1024u);  // 64 KiB of fragments and their headers
    EXPECT_GT(wide, 192u * 1024u);
    EXPECT_LT(wide, 288u * 1024u);
}

}  // namespace
}  // namespace pliant::net
