// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Small vocabulary shared by the codec and the transports: peer ids, roles, channels and the
/// enumerated disconnect reasons (docs/protocol.md §2, §5). Their numeric values are wire values.

#include <cstdint>
#include <string_view>

namespace pliant::net
{

/// A peer's id within a session, assigned by the master and never reused within that session
/// (which stands in for a generation counter). `k_no_peer` is a joiner before its Welcome.
struct PeerId
{
    std::uint16_t value = 0xFFFF;
    friend constexpr bool operator==(PeerId, PeerId) = default;
    friend constexpr auto operator<=>(PeerId, PeerId) = default;
};
inline constexpr PeerId k_no_peer{0xFFFF};

/// What a peer does in a session (docs/design.md §5).
enum class Role : std::uint8_t
{
    Participant = 1,  ///< simulates its leaves and applies forces
    Viewer = 2,       ///< only watches
};

/// The two transport channels (docs/protocol.md §2).
enum class Channel : std::uint8_t
{
    Control = 0,  ///< reliable, ordered
    State = 1,    ///< unreliable, sequenced (stale packets dropped)
};
inline constexpr int k_channel_count = 2;

/// Why a connection ended. Sent in Leave, PeerLeft, Reject and as ENet disconnect data; 0 on the
/// wire only as ENet's "timed out" data, never in a message.
enum class DisconnectReason : std::uint8_t
{
    None = 0,                 ///< not a wire value in messages; "unknown" in events
    Quit = 1,                 ///< the user left
    Shutdown = 2,             ///< the process is ending
    TimedOut = 3,             ///< no traffic within the transport's timeout
    TooManyBadDatagrams = 4,  ///< the peer sent more bad datagrams than the threshold
    ProtocolMismatch = 5,     ///< another protocol version; a joiner's refusal of the blobs
    WrongSession = 6,         ///< a datagram for another session
    Refused = 7,              ///< the master does not admit the peer
    SessionFull = 8,          ///< no room for another peer
    Kicked = 9,               ///< removed by the master
};
inline constexpr std::uint8_t k_max_disconnect_reason = 9;

/// Short stable name, e.g. "too-many-bad-datagrams".
[[nodiscard]] std::string_view to_string(DisconnectReason reason) noexcept;

}  // namespace pliant::net
