// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The connection-level layer the session uses: typed messages over a `Transport`.
///
/// `Peer` is what one connection knows (its bound peer id, the session, its drop counters) and the
/// policy applied to every incoming datagram: decode it, check its channel, session and sender,
/// and drop and count it if anything is wrong (docs/protocol.md §8; docs/style.md §5, kind 3). It
/// does no I/O, so it is tested without a network. `Messenger` owns one `Peer` per connection of a
/// Transport, encodes outgoing messages into one reusable buffer, reports bad datagrams to the
/// transport's counters and disconnects a peer past the threshold with
/// DisconnectReason::TooManyBadDatagrams (WrongSession when the last one was another
/// session's), or at its first datagram of another protocol version with ProtocolMismatch.
///
/// Threading: single-threaded, like the Transport it wraps.

#include <pliant/core/result.h>
#include <pliant/net/codec.h>
#include <pliant/net/transport.h>

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace pliant::net
{

/// Why an incoming datagram was dropped.
enum class DropReason : std::uint8_t
{
    Undecodable = 1,   ///< decode() failed (see `Drop::error`)
    WrongChannel = 2,  ///< a control message on the state channel
    WrongSession = 3,  ///< the session differs from the connection's
    WrongSender = 4,   ///< the sender id differs from the one the connection is bound to
};

struct Drop
{
    DropReason reason = DropReason::Undecodable;
    DecodeError error = DecodeError::TooShort;  ///< meaningful for Undecodable
};

/// What a drop says of the datagram: its decode error's name when it did not decode
/// ("bad-magic"), else "wrong-channel", "wrong-session" or "wrong-sender".
[[nodiscard]] std::string_view describe(const Drop& drop) noexcept;

/// One connection's receive policy and counters.
class Peer
{
public:
    /// Session 0: not known yet (any session is accepted until set_session()).
    explicit Peer(PeerHandle handle, std::uint32_t session = 0) noexcept
        : handle_(handle), session_(session)
    {
    }

    /// Checks and decodes one datagram that arrived on `channel`. Every rejection increments
    /// bad_datagrams(). A Hello may carry session 0 before the session is known to the sender.
    [[nodiscard]] Expected<Message, Drop> accept(Channel channel,
                                                 std::span<const std::byte> datagram) noexcept;
    /// accept() into a reused message (decode_into(): no allocation once its vectors have grown).
    /// \return the drop, or nothing when `out` holds the accepted message; after a drop `out`
    /// holds unspecified contents.
    [[nodiscard]] std::optional<Drop> accept_into(Channel channel,
                                                  std::span<const std::byte> datagram,
                                                  Message& out) noexcept;

    /// From now on datagrams must carry `session` (Hello may still carry 0).
    void set_session(std::uint32_t session) noexcept { session_ = session; }
    /// From now on datagrams must carry sender `id`.
    void bind(PeerId id) noexcept { id_ = id; }

    [[nodiscard]] PeerHandle handle() const noexcept { return handle_; }
    [[nodiscard]] PeerId id() const noexcept { return id_; }
    [[nodiscard]] std::uint64_t bad_datagrams() const noexcept { return bad_; }
    [[nodiscard]] std::uint64_t good_datagrams() const noexcept { return good_; }
    /// Being disconnected by the Messenger: the rest of its datagrams are ignored.
    [[nodiscard]] bool cut() const noexcept { return cut_; }
    void set_cut() noexcept { cut_ = true; }
    /// Drops by DecodeError (index = value), for statistics.
    [[nodiscard]] const std::array<std::uint32_t, k_decode_error_count + 1>& errors() const noexcept
    {
        return errors_;
    }

private:
    Unexpected<Drop> drop(DropReason reason, DecodeError error = DecodeError::TooShort) noexcept;

    PeerHandle handle_;
    std::uint32_t session_ = 0;
    PeerId id_ = k_no_peer;
    std::uint64_t bad_ = 0;
    std::uint64_t good_ = 0;
    bool cut_ = false;
    std::array<std::uint32_t, k_decode_error_count + 1> errors_{};
};

struct MessengerSettings
{
    /// A peer that sends more bad datagrams than this is disconnected.
    std::uint32_t bad_datagram_limit = 16;
};

struct MessengerEvent
{
    enum class Kind : std::uint8_t
    {
        Connected,
        Disconnected,
        Received,
    };
    Kind kind = Kind::Received;
    PeerHandle peer;
    Channel channel = Channel::Control;
    DisconnectReason reason = DisconnectReason::None;  ///< Disconnected only
    Message message;                                   ///< Received only
};

/// How to send a message.
enum class SendMode : std::uint8_t
{
    Default,   ///< the type's channel: control reliable on 0, state unreliable on 1
    Reliable,  ///< state types too, reliably on channel 0 (exact coupling mode)
    /// State types on channel 1 without ENet's sequencing: lost, duplicated or reordered as the
    /// network does, so that a late datagram of one leaf does not drop a newer one of another
    /// (the receiver orders states per leaf by tick). Likewise the repeats of Ready and Hello; the
    /// other control types stay reliable.
    Unsequenced,
};

/// Whether `mode` sends a message of this type reliably on channel 0 (else unreliably on 1).
[[nodiscard]] constexpr bool sent_reliably(MessageType type, SendMode mode) noexcept
{
    return mode == SendMode::Reliable || !allowed_on(type, Channel::State) ||
           (mode == SendMode::Default && default_channel(type) == Channel::Control);
}

class Messenger
{
public:
    explicit Messenger(Transport& transport, const MessengerSettings& settings = {});

    /// Encodes and sends. \return ErrorCode::InvalidArgument if the message is invalid (a bug in
    /// the caller, reported rather than asserted so a session can log it); the transport's error
    /// otherwise.
    core::Result<void> send(PeerHandle peer, const Message& message,
                            SendMode mode = SendMode::Default) noexcept;

    /// Sends the same message to each of `peers`; encodes once. \return the first error.
    core::Result<void> send(std::span<const PeerHandle> peers, const Message& message,
                            SendMode mode = SendMode::Default) noexcept;

    /// Sends to every connected peer; encodes once. \return the first error.
    core::Result<void> broadcast(const Message& message,
                                 SendMode mode = SendMode::Default) noexcept;

    /// The next connection event or good message. Bad datagrams are dropped, counted and never
    /// returned; a peer past the limit is disconnected. Polls the transport until it has nothing
    /// or 256 datagrams were dropped in this call (so a flood cannot stall the caller); only the
    /// first transport poll waits, at most `timeout_ms`.
    std::optional<MessengerEvent> poll(int timeout_ms = 0) noexcept;

    /// poll() without a copy: the next event, in an event this Messenger owns and reuses, valid
    /// until the next call of next() or poll(); nullptr when there is none. A datagram is decoded
    /// in place (decode_into()) into an event kept for its message type, so that a type's vectors
    /// keep their storage while other types come between: no allocation once they have grown.
    /// `message` is meaningful for Received only. The receive loop of a session uses this.
    [[nodiscard]] const MessengerEvent* next(int timeout_ms = 0) noexcept;

    void set_session(std::uint32_t session) noexcept;
    /// Binds a connection to the peer id it announced (Hello/Welcome); later datagrams with
    /// another sender id are dropped as spoofed.
    void bind(PeerHandle peer, PeerId id) noexcept;

    [[nodiscard]] const Peer* peer(PeerHandle handle) const noexcept;
    [[nodiscard]] Transport& transport() noexcept { return transport_; }
    /// Total datagrams dropped since creation (all peers, gone ones included).
    [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_; }

private:
    MessengerEvent* next_event(int timeout_ms) noexcept;
    core::Result<void> send_encoded(PeerHandle peer, MessageType type, std::size_t size,
                                    SendMode mode) noexcept;

    Transport& transport_;
    MessengerSettings settings_;
    std::uint32_t session_ = 0;
    std::map<PeerHandle, Peer> peers_;
    std::vector<std::byte> buffer_;
    TransportEvent datagram_;  ///< next()'s transport event, reused (Transport::poll_into)
    /// next()'s events, reused: [0] for connection events and datagrams that name no type, [t]
    /// for datagrams of wire type t (their messages keep the type's alternative and vectors).
    std::array<MessengerEvent, k_message_type_count + 1> events_;
    std::uint64_t dropped_ = 0;
};

}  // namespace pliant::net
