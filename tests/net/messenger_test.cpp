// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Peer and Messenger: bad datagrams (undecodable, wrong channel, wrong session, spoofed sender)
// are dropped and counted, never delivered; past the threshold the sender is disconnected with
// TooManyBadDatagrams and learns why; good messages arrive typed on the right channel.

#include <pliant/net/messenger.h>
#include <pliant/net/simulated_transport.h>

#include <gtest/gtest.h>

#include "net/encode_vec.h"
#include "net/sample_messages.h"

#include <algorithm>
#include <map>
#include <optional>
#include <utility>
#include <vector>

namespace pliant::net
{
namespace
{

using test::encode_vec;

Message ping(std::uint32_t session = 0xC0FFEE01u, PeerId sender = PeerId{3})
{
    Message m{samples::header(), Ping{.nonce = 1, .time_us = 2}};
    m.header.session = session;
    m.header.sender = sender;
    return m;
}

TEST(Peer, DropsAndCountsEveryKindOfBadDatagram)
{
    Peer peer(PeerHandle{1});
    const auto good = encode_vec(ping());
    EXPECT_TRUE(peer.accept(Channel::State, good).has_value());
    EXPECT_TRUE(peer.accept(Channel::Control, good).has_value()) << "state types may go reliably";

    auto junk = good;
    junk[0] = std::byte{0};
    auto r = peer.accept(Channel::State, junk);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().reason, DropReason::Undecodable);
    EXPECT_EQ(r.error().error, DecodeError::BadMagic);

    Message leave{samples::header(), Leave{.reason = DisconnectReason::Quit}};
    r = peer.accept(Channel::State, encode_vec(leave));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().reason, DropReason::WrongChannel);

    peer.set_session(0xC0FFEE01u);
    r = peer.accept(Channel::State, encode_vec(ping(0x1234)));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().reason, DropReason::WrongSession);
    Message hello{samples::header(), Hello{.role = Role::Viewer, .listen_port = 0, .name = "x"}};
    hello.header.session = 0;
    EXPECT_TRUE(peer.accept(Channel::Control, encode_vec(hello)).has_value())
        << "a Hello may carry no session";

    peer.bind(PeerId{3});
    EXPECT_TRUE(peer.accept(Channel::State, good).has_value());
    r = peer.accept(Channel::State, encode_vec(ping(0xC0FFEE01u, PeerId{4})));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().reason, DropReason::WrongSender);

    EXPECT_EQ(peer.bad_datagrams(), 4u);
    EXPECT_EQ(peer.good_datagrams(), 4u);
    EXPECT_EQ(peer.errors()[static_cast<std::size_t>(DecodeError::BadMagic)], 1u);
}

struct Net
{
    SimulatedNetwork net;
    std::unique_ptr<Transport> ta = net.create_endpoint();
    std::unique_ptr<Transport> tb = net.create_endpoint();
    Messenger a{*ta, MessengerSettings{.bad_datagram_limit = 5}};
    Messenger b{*tb, MessengerSettings{.bad_datagram_limit = 5}};
    PeerHandle a_to_b;
    PeerHandle b_to_a;

    Net()
    {
        EXPECT_TRUE(ta->open({}));
        const Address addr_b = tb->open({}).value();
        a_to_b = ta->connect(addr_b).value();
        bool a_up = false;
        bool b_up = false;
        for (int i = 0; i < 1000 && !(a_up && b_up); ++i)
        {
            net.advance(0.001);
            while (auto ev = a.poll())
                a_up = a_up || ev->kind == MessengerEvent::Kind::Connected;
            while (auto ev = b.poll())
                if (ev->kind == MessengerEvent::Kind::Connected)
                {
                    b_up = true;
                    b_to_a = ev->peer;
                }
        }
        EXPECT_TRUE(a_up && b_up);
    }

    /// The reason a learns when b has cut it (within 50 ms).
    std::optional<DisconnectReason> told_a()
    {
        std::optional<DisconnectReason> told;
        for (int i = 0; i < 50 && !told; ++i)
        {
            net.advance(0.001);
            while (auto ev = a.poll())
                if (ev->kind == MessengerEvent::Kind::Disconnected)
                    told = ev->reason;
        }
        return told;
    }

    /// Why b cut a (its only event within 50 ms), and what a was told.
    std::pair<std::optional<DisconnectReason>, std::optional<DisconnectReason>> cut_reasons()
    {
        const auto events = drain_b();
        std::optional<DisconnectReason> cut;
        if (events.size() == 1 && events[0].kind == MessengerEvent::Kind::Disconnected)
            cut = events[0].reason;
        return {cut, told_a()};
    }

    std::vector<MessengerEvent> drain_b(int ms = 50)
    {
        std::vector<MessengerEvent> out;
        for (int i = 0; i < ms; ++i)
        {
            net.advance(0.001);
            while (auto ev = b.poll())
                out.push_back(std::move(*ev));
        }
        return out;
    }
};

TEST(Messenger, DeliversTypedMessagesOnTheirChannels)
{
    Net n;
    for (const Message& m : samples::all())
        ASSERT_TRUE(n.a.send(n.a_to_b, m)) << to_string(m.type());
    const auto events = n.drain_b();
    std::vector<Message> control;
    std::vector<Message> state;
    for (const auto& ev : events)
    {
        ASSERT_EQ(ev.kind, MessengerEvent::Kind::Received);
        (ev.channel == Channel::Control ? control : state).push_back(ev.message);
        EXPECT_EQ(ev.channel, default_channel(ev.message.type()));
    }
    std::vector<Message> expected_control;
    std::vector<Message> expected_state;
    for (const Message& m : samples::all())
        (default_channel(m.type()) == Channel::Control ? expected_control : expected_state)
            .push_back(m);
    EXPECT_EQ(control, expected_control);
    EXPECT_EQ(state, expected_state);
    EXPECT_EQ(n.b.dropped(), 0u);

    // SendMode::Reliable moves a state message to the reliable control channel.
    ASSERT_TRUE(n.a.send(n.a_to_b, samples::all().back(), SendMode::Reliable));
    const auto again = n.drain_b();
    ASSERT_EQ(again.size(), 1u);
    EXPECT_EQ(again[0].channel, Channel::Control);

    // SendMode::Unsequenced moves Ready and Hello, alone of the control types, to the state
    // channel (their repeats); a Partition stays reliable.
    Message ready{samples::header(), Ready{}};
    EXPECT_TRUE(sent_reliably(MessageType::Ready, SendMode::Default));
    EXPECT_FALSE(sent_reliably(MessageType::Ready, SendMode::Unsequenced));
    EXPECT_TRUE(sent_reliably(MessageType::Hello, SendMode::Default));
    EXPECT_FALSE(sent_reliably(MessageType::Hello, SendMode::Unsequenced));
    EXPECT_TRUE(sent_reliably(MessageType::Partition, SendMode::Unsequenced));
    EXPECT_FALSE(sent_reliably(MessageType::LeafState, SendMode::Default));
    ASSERT_TRUE(n.a.send(n.a_to_b, ready, SendMode::Unsequenced));
    ASSERT_TRUE(n.a.send(n.a_to_b, ready));
    const auto readies = n.drain_b();
    ASSERT_EQ(readies.size(), 2u);
    EXPECT_NE(readies[0].channel, readies[1].channel) << "one on each channel";
    for (const auto& ev : readies)
        EXPECT_EQ(ev.message, ready);
    EXPECT_EQ(n.b.dropped(), 0u);

    // An invalid message is refused at the sender, not sent.
    Message bad = ping();
    bad.header.session = 0;
    EXPECT_FALSE(n.a.send(n.a_to_b, bad));
}

// next() delivers what poll() does from one reused event per message type: every sample, then every
// sample again in reverse order (so each type's messages come larger then smaller into the same
// message), with a bad datagram between, dropped.
TEST(Messenger, NextDeliversFromAReusedEventWhatPollDoes)
{
    Net n;
    auto all = samples::all();
    std::vector<Message> sent = all;
    sent.insert(sent.end(), all.rbegin(), all.rend());
    for (std::size_t k = 0; k < sent.size(); ++k)
    {
        ASSERT_TRUE(n.a.send(n.a_to_b, sent[k])) << to_string(sent[k].type());
        if (k == all.size())
        {
            std::vector<std::byte> junk = encode_vec(ping());
            junk[0] = std::byte{0};
            ASSERT_TRUE(n.ta->send(n.a_to_b, Channel::State, junk, Delivery::Unreliable));
        }
    }
    std::vector<Message> control;
    std::vector<Message> state;
    std::map<MessageType, const MessengerEvent*> event_of;
    for (int i = 0; i < 50; ++i)
    {
        n.net.advance(0.001);
        while (const MessengerEvent* ev = n.b.next())
        {
            const auto it = event_of.emplace(ev->message.type(), ev).first;
            EXPECT_EQ(ev, it->second) << "one event per type, reused";
            ASSERT_EQ(ev->kind, MessengerEvent::Kind::Received);
            EXPECT_EQ(ev->channel, default_channel(ev->message.type()));
            (ev->channel == Channel::Control ? control : state).push_back(ev->message);
        }
    }
    std::vector<Message> expected_control;
    std::vector<Message> expected_state;
    for (const Message& m : sent)
        (default_channel(m.type()) == Channel::Control ? expected_control : expected_state)
            .push_back(m);
    EXPECT_EQ(control, expected_control);
    EXPECT_EQ(state, expected_state);
    EXPECT_EQ(n.b.dropped(), 1u);
    EXPECT_EQ(event_of.size(), std::size_t{k_message_type_count});
}

TEST(Messenger, BadDatagramsAreDroppedCountedAndTheSenderCutOff)
{
    Net n;
    const std::vector<std::byte> junk = {std::byte{1}, std::byte{2}, std::byte{3}};
    // Below the limit: counted, never delivered, the connection stays.
    for (int i = 0; i < 5; ++i)
        ASSERT_TRUE(n.ta->send(n.a_to_b, Channel::State, junk, Delivery::Reliable));
    ASSERT_TRUE(n.a.send(n.a_to_b, ping()));
    auto events = n.drain_b();
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].message.type(), MessageType::Ping);
    EXPECT_EQ(n.tb->stats(n.b_to_a)->bad_datagrams, 5u);
    EXPECT_EQ(n.b.peer(n.b_to_a)->bad_datagrams(), 5u);
    EXPECT_EQ(n.b.peer(n.b_to_a)->errors()[static_cast<std::size_t>(DecodeError::TooShort)], 5u);

    // One more crosses the limit: b disconnects a with the reason, and a learns it.
    ASSERT_TRUE(n.ta->send(n.a_to_b, Channel::State, junk, Delivery::Reliable));
    ASSERT_TRUE(n.a.send(n.a_to_b, ping()));  // in flight behind the junk: never delivered
    events = n.drain_b();
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].kind, MessengerEvent::Kind::Disconnected);
    EXPECT_EQ(events[0].reason, DisconnectReason::TooManyBadDatagrams);
    EXPECT_EQ(n.told_a(), DisconnectReason::TooManyBadDatagrams);
    EXPECT_EQ(n.b.dropped(), 6u);
}

TEST(Messenger, SpoofedSenderAndForeignSessionAreDropped)
{
    Net n;
    n.b.set_session(0xC0FFEE01u);
    n.b.bind(n.b_to_a, PeerId{3});
    ASSERT_TRUE(n.a.send(n.a_to_b, ping(0xC0FFEE01u, PeerId{4})));  // claims to be peer 4
    ASSERT_TRUE(n.a.send(n.a_to_b, ping(0xBADBAD, PeerId{3})));     // another session
    ASSERT_TRUE(n.a.send(n.a_to_b, ping()));
    const auto events = n.drain_b();
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].message.header.sender, PeerId{3});
    EXPECT_EQ(n.b.dropped(), 2u);
}

// A connection cut off on another session's datagram is told reason 6 (wrong session), not 4:
// the likeliest cause is a peer of an earlier session at a reused address.
TEST(Messenger, APeerOfAnotherSessionIsCutOffAsWrongSession)
{
    Net n;
    n.b.set_session(0xC0FFEE01u);
    for (int i = 0; i < 6; ++i)
        ASSERT_TRUE(n.a.send(n.a_to_b, ping(0xBADBADu, PeerId{3})));
    EXPECT_EQ(n.cut_reasons(), std::pair(std::optional{DisconnectReason::WrongSession},
                                         std::optional{DisconnectReason::WrongSession}));
    EXPECT_EQ(describe(Drop{DropReason::WrongSession}), "wrong-session");
    EXPECT_EQ(describe(Drop{DropReason::WrongChannel}), "wrong-channel");
    EXPECT_EQ(describe(Drop{DropReason::WrongSender}), "wrong-sender");
    EXPECT_EQ(describe(Drop{DropReason::Undecodable, DecodeError::BadMagic}),
              to_string(DecodeError::BadMagic));
}

// A datagram of our magic and another protocol version comes from a pliant of another
// version: cut at once with reason 5 (protocol mismatch), which the other side can report as
// such; before, it was one bad datagram among 16, and a joiner waited for a timeout.
TEST(Messenger, AnotherProtocolVersionIsCutAtOnceAsAMismatch)
{
    Net n;
    std::vector<std::byte> other = encode_vec(ping());
    other[4] = static_cast<std::byte>(k_protocol_version + 1);
    ASSERT_TRUE(n.ta->send(n.a_to_b, Channel::Control, other, Delivery::Reliable));
    EXPECT_EQ(n.cut_reasons(), std::pair(std::optional{DisconnectReason::ProtocolMismatch},
                                         std::optional{DisconnectReason::ProtocolMismatch}));
    EXPECT_EQ(n.b.dropped(), 1u);
}

/// A hub and three leaves connected to it over a simulated network, every connection event
/// polled; `handles`: the hub's handle of each leaf, `leaf_addr`: each leaf's address.
struct Star
{
    SimulatedNetwork net;
    std::unique_ptr<Transport> hub_t = net.create_endpoint();
    Address hub_addr = hub_t->open({}).value();
    Messenger hub{*hub_t};
    std::vector<std::unique_ptr<Transport>> leaves_t;
    std::vector<std::unique_ptr<Messenger>> leaves;
    std::vector<Address> leaf_addr;
    std::vector<PeerHandle> handles;  // in the order the hub saw them connect

    Star()
    {
        for (int i = 0; i < 3; ++i)
        {
            leaves_t.push_back(net.create_endpoint());
            leaf_addr.push_back(leaves_t.back()->open({}).value());
            EXPECT_TRUE(leaves_t.back()->connect(hub_addr));
            leaves.push_back(std::make_unique<Messenger>(*leaves_t.back()));
        }
        for (int i = 0; i < 100; ++i)
        {
            net.advance(0.001);
            while (auto ev = hub.poll())
                if (ev->kind == MessengerEvent::Kind::Connected)
                    handles.push_back(ev->peer);
            for (auto& l : leaves)
                while (l->poll())
                {
                }
        }
    }
};

TEST(Messenger, BroadcastReachesEveryPeer)
{
    Star star;
    ASSERT_EQ(star.handles.size(), 3U);
    ASSERT_TRUE(star.hub.broadcast(Message{samples::header(), Heartbeat{.epoch = 5}}));
    int got = 0;
    for (int i = 0; i < 100; ++i)
    {
        star.net.advance(0.001);
        for (auto& l : star.leaves)
            while (auto ev = l->poll())
                got += ev->kind == MessengerEvent::Kind::Received &&
                               std::get<Heartbeat>(ev->message.body).epoch == 5
                           ? 1
                           : 0;
    }
    EXPECT_EQ(got, 3);
}

// The session streams each leaf state to a chosen set of peers (those holding the model), encoded
// once: exactly those peers receive it, bit for bit; no peer is no send; an invalid message is
// refused before anything goes out.
TEST(Messenger, SendToAChosenSetReachesExactlyThoseItNames)
{
    Star star;
    ASSERT_EQ(star.handles.size(), 3U);
    // Which leaf each handle is: the address the hub sees is the leaf's own.
    std::vector<int> leaf_of(3, -1);
    for (std::size_t h = 0; h < 3; ++h)
        for (std::size_t k = 0; k < 3; ++k)
            if (star.hub_t->remote_address(star.handles[h]) == star.leaf_addr[k])
                leaf_of[h] = static_cast<int>(k);
    ASSERT_TRUE(std::all_of(leaf_of.begin(), leaf_of.end(), [](int k) { return k >= 0; }));

    const Message state{samples::header(), samples::halo(ValueEncoding::F64, true, true)};
    const std::vector<PeerHandle> chosen{star.handles[0], star.handles[2]};
    ASSERT_TRUE(star.hub.send(chosen, state, SendMode::Unsequenced));
    ASSERT_TRUE(star.hub.send(std::span<const PeerHandle>{}, state));  // nobody: nothing sent
    Message bad = state;
    std::get<Halo>(bad.body).ranges.clear();  // a halo covers at least one node range
    EXPECT_FALSE(star.hub.send(chosen, bad));
    std::vector<int> got(3, 0);
    for (int i = 0; i < 100; ++i)
    {
        star.net.advance(0.001);
        for (std::size_t k = 0; k < star.leaves.size(); ++k)
            while (auto ev = star.leaves[k]->poll())
                if (ev->kind == MessengerEvent::Kind::Received)
                {
                    EXPECT_EQ(ev->message.body, state.body);
                    ++got[k];
                }
    }
    EXPECT_EQ(got[static_cast<std::size_t>(leaf_of[0])], 1);
    EXPECT_EQ(got[static_cast<std::size_t>(leaf_of[1])], 0);
    EXPECT_EQ(got[static_cast<std::size_t>(leaf_of[2])], 1);
}

// Leaf states are sent unsequenced (docs/protocol.md §2): with jitter, a burst of state datagrams
// arrives out of order; the default (ENet's sequenced unreliable delivery) drops every one older
// than one already delivered, Unsequenced delivers them all and leaves the ordering to the
// receiver.
TEST(Messenger, UnsequencedStateSurvivesReorderingThatSequencedDeliveryDrops)
{
    auto run = [](SendMode mode)
    {
        SimulatedNetworkSettings set;
        set.seed = 7;
        set.link.latency_s = 0.005;
        set.link.jitter_s = 0.020;  // a 60-datagram burst spreads over 20 ms: mostly reordered
        SimulatedNetwork net(set);
        auto ta = net.create_endpoint();
        auto tb = net.create_endpoint();
        Messenger a{*ta};
        Messenger b{*tb};
        EXPECT_TRUE(ta->open({}));
        const PeerHandle to_b = ta->connect(tb->open({}).value()).value();
        bool up = false;
        for (int i = 0; i < 1000 && !up; ++i)
        {
            net.advance(0.001);
            while (auto ev = a.poll())
                up = up || ev->kind == MessengerEvent::Kind::Connected;
            while (b.poll())
            {
            }
        }
        EXPECT_TRUE(up);
        std::vector<std::uint64_t> ticks;
        for (std::uint64_t t = 1; t <= 60; ++t)
        {
            Message m{samples::header(), samples::leaf_state(ValueEncoding::F64, 8)};
            m.header.tick = t;
            EXPECT_TRUE(a.send(to_b, m, mode));
        }
        for (int i = 0; i < 100; ++i)
        {
            net.advance(0.001);
            while (auto ev = b.poll())
                if (ev->kind == MessengerEvent::Kind::Received)
                {
                    EXPECT_EQ(ev->channel, Channel::State);
                    ticks.push_back(ev->message.header.tick);
                }
        }
        return ticks;
    };
    const auto sequenced = run(SendMode::Default);
    const auto unsequenced = run(SendMode::Unsequenced);
    EXPECT_TRUE(std::is_sorted(sequenced.begin(), sequenced.end()));
    EXPECT_LT(sequenced.size(), 30u) << "sequenced delivery drops the late ones";
    ASSERT_EQ(unsequenced.size(), 60u) << "every datagram arrives, none lost on this link";
    EXPECT_FALSE(std::is_sorted(unsequenced.begin(), unsequenced.end())) << "and out of order";
}

}  // namespace
}  // namespace pliant::net
