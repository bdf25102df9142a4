// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Incoming-datagram policy and typed sending over a Transport (see messenger.h). A bad datagram
// costs a decode attempt and a counter increment; it is logged at debug level, and a peer that
// keeps sending them is cut off, so a hostile peer cannot make the log or the loop expensive.

#include <pliant/net/messenger.h>

#include <spdlog/spdlog.h>

namespace pliant::net
{

std::string_view describe(const Drop& drop) noexcept
{
    switch (drop.reason)
    {
    case DropReason::Undecodable: return to_string(drop.error);
    case DropReason::WrongChannel: return "wrong-channel";
    case DropReason::WrongSession: return "wrong-session";
    case DropReason::WrongSender: return "wrong-sender";
    }
    return "unknown";
}

Unexpected<Drop> Peer::drop(DropReason reason, DecodeError error) noexcept
{
    ++bad_;
    if (reason == DropReason::Undecodable)
        ++errors_[static_cast<std::size_t>(error)];
    return Unexpected{Drop{reason, error}};
}

std::optional<Drop> Peer::accept_into(Channel channel, std::span<const std::byte> datagram,
                                      Message& out) noexcept
{
    if (auto err = decode_into(datagram, out))
        return drop(DropReason::Undecodable, *err).error;
    if (!allowed_on(out.type(), channel))
        return drop(DropReason::WrongChannel).error;
    const bool hello = out.type() == MessageType::Hello;
    if (session_ != 0 && out.header.session != session_ && !(hello && out.header.session == 0))
        return drop(DropReason::WrongSession).error;
    if (id_ != k_no_peer && out.header.sender != id_)
        return drop(DropReason::WrongSender).error;
    ++good_;
    return std::nullopt;
}

Expected<Message, Drop> Peer::accept(Channel channel, std::span<const std::byte> datagram) noexcept
{
    Message m;
    if (auto dropped = accept_into(channel, datagram, m))
        return Unexpected{*dropped};
    return m;
}

Messenger::Messenger(Transport& transport, const MessengerSettings& settings)
    : transport_(transport), settings_(settings), buffer_(k_max_datagram_size)
{
}

core::Result<void> Messenger::send_encoded(PeerHandle peer, MessageType type, std::size_t size,
                                           SendMode mode) noexcept
{
    const bool reliable = sent_reliably(type, mode);
    const Channel channel = reliable ? Channel::Control : Channel::State;
    const Delivery delivery = reliable                        ? Delivery::Reliable
                              : mode == SendMode::Unsequenced ? Delivery::Unsequenced
                                                              : Delivery::Unreliable;
    return transport_.send(peer, channel, std::span<const std::byte>(buffer_.data(), size),
                           delivery);
}

core::Result<void> Messenger::send(PeerHandle peer, const Message& message, SendMode mode) noexcept
{
    auto size = encode(message, buffer_);
    if (!size)
        return core::fail(
            core::ErrorCode::InvalidArgument,
            std::string("Messenger::send: cannot encode ") +
                std::string(to_string(message.type())) + ": " +
                std::string(to_string(size.error())) + " (" +
                std::string(to_string(validate(message).value_or(DecodeError::TooShort))) + ")");
    return send_encoded(peer, message.type(), *size, mode);
}

core::Result<void> Messenger::send(std::span<const PeerHandle> peers, const Message& message,
                                   SendMode mode) noexcept
{
    if (peers.empty())
        return {};
    auto size = encode(message, buffer_);
    if (!size)
        return core::fail(core::ErrorCode::InvalidArgument,
                          std::string("Messenger::send: cannot encode ") +
                              std::string(to_string(message.type())) + ": " +
                              std::string(to_string(size.error())));
    core::Result<void> first;
    for (const PeerHandle peer : peers)
    {
        auto r = send_encoded(peer, message.type(), *size, mode);
        if (!r && first)
            first = r;
    }
    return first;
}

core::Result<void> Messenger::broadcast(const Message& message, SendMode mode) noexcept
{
    auto size = encode(message, buffer_);
    if (!size)
        return core::fail(core::ErrorCode::InvalidArgument,
                          std::string("Messenger::broadcast: cannot encode ") +
                              std::string(to_string(message.type())));
    core::Result<void> first;
    for (const auto& [handle, p] : peers_)
    {
        auto r = send_encoded(handle, message.type(), *size, mode);
        if (!r && first)
            first = r;
    }
    return first;
}

std::optional<MessengerEvent> Messenger::poll(int timeout_ms) noexcept
{
    MessengerEvent* ev = next_event(timeout_ms);
    if (ev == nullptr)
        return std::nullopt;
    if (ev->kind != MessengerEvent::Kind::Received)
        return MessengerEvent{.kind = ev->kind,
                              .peer = ev->peer,
                              .channel = ev->channel,
                              .reason = ev->reason,
                              .message = {}};
    return std::move(*ev);
}

const MessengerEvent* Messenger::next(int timeout_ms) noexcept
{
    return next_event(timeout_ms);
}

MessengerEvent* Messenger::next_event(int timeout_ms) noexcept
{
    // A flood of bad datagrams must not keep this call from returning: stop after this many
    // dropped ones; the caller polls again on its next iteration.
    constexpr int k_max_drops_per_poll = 256;
    int wait = timeout_ms;
    int drops = 0;
    while (drops < k_max_drops_per_poll)
    {
        if (!transport_.poll_into(datagram_, wait))
            break;
        const TransportEvent* ev = &datagram_;
        wait = 0;
        switch (ev->kind)
        {
        case TransportEvent::Kind::Connected:
            peers_.insert_or_assign(ev->peer, Peer(ev->peer, session_));
            events_[0].kind = MessengerEvent::Kind::Connected;
            events_[0].peer = ev->peer;
            events_[0].channel = Channel::Control;
            events_[0].reason = DisconnectReason::None;
            return &events_[0];
        case TransportEvent::Kind::Disconnected:
            peers_.erase(ev->peer);
            events_[0].kind = MessengerEvent::Kind::Disconnected;
            events_[0].peer = ev->peer;
            events_[0].channel = Channel::Control;
            events_[0].reason = ev->reason;
            return &events_[0];
        case TransportEvent::Kind::Received: break;
        }
        auto it = peers_.find(ev->peer);
        if (it == peers_.end())
            continue;  // a straggler from a connection already cut off
        Peer& p = it->second;
        if (p.cut() || p.bad_datagrams() > settings_.bad_datagram_limit)
            continue;  // being disconnected: ignore the rest
        // The wire type (header byte 5) picks the event, so each event's message keeps one
        // type's alternative; a datagram that names no type fails to decode before its body.
        const std::size_t type =
            ev->data.size() >= k_header_size ? std::to_integer<std::size_t>(ev->data[5]) : 0;
        MessengerEvent& event = events_[type <= k_message_type_count ? type : 0];
        const std::optional<Drop> m = p.accept_into(ev->channel, ev->data, event.message);
        if (m)
        {
            ++drops;
            ++dropped_;
            transport_.report_bad_datagram(ev->peer);
            spdlog::debug("net: dropped a datagram from peer {} ({} bytes): {}", ev->peer.value,
                          ev->data.size(), describe(*m));
            // Our magic and another version (byte 4): a pliant of another version, which would
            // never be understood. Cut at once with reason 5, so that it can say so; it waited
            // for a timeout before, and was told nothing.
            if (m->reason == DropReason::Undecodable && m->error == DecodeError::BadVersion &&
                ev->data.size() > 4)
            {
                const auto address = transport_.remote_address(ev->peer);
                spdlog::warn("net: disconnected {}: it speaks protocol version {}, this build {}",
                             address ? to_string(*address) : std::string("a peer"),
                             std::to_integer<int>(ev->data[4]),
                             static_cast<int>(k_protocol_version));
                p.set_cut();
                transport_.disconnect(ev->peer, DisconnectReason::ProtocolMismatch);
                continue;
            }
            if (p.bad_datagrams() > settings_.bad_datagram_limit)
            {
                // A connection that ends on another session's datagram is told so (reason 6):
                // it belongs to another session (programs that set distinct session ids).
                const DisconnectReason why = m->reason == DropReason::WrongSession
                                                 ? DisconnectReason::WrongSession
                                                 : DisconnectReason::TooManyBadDatagrams;
                const auto address = transport_.remote_address(ev->peer);
                spdlog::warn("net: disconnected {}: {} bad datagrams (the last: {}, {} bytes)",
                             address ? to_string(*address) : std::string("a peer"),
                             p.bad_datagrams(), describe(*m), ev->data.size());
                transport_.disconnect(ev->peer, why);
            }
            continue;
        }
        event.kind = MessengerEvent::Kind::Received;
        event.peer = ev->peer;
        event.channel = ev->channel;
        event.reason = DisconnectReason::None;
        return &event;
    }
    return nullptr;
}

void Messenger::set_session(std::uint32_t session) noexcept
{
    session_ = session;
    for (auto& [h, p] : peers_)
        p.set_session(session);
}

void Messenger::bind(PeerHandle peer, PeerId id) noexcept
{
    auto it = peers_.find(peer);
    if (it != peers_.end())
        it->second.bind(id);
}

const Peer* Messenger::peer(PeerHandle handle) const noexcept
{
    auto it = peers_.find(handle);
    return it == peers_.end() ? nullptr : &it->second;
}

}  // namespace pliant::net
