// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The UDP transport: ENet 1.3 behind `net::Transport`. No ENet type appears here; only
/// src/net/enet_transport.cpp includes <enet/enet.h> (docs/style.md §8, checked by
/// scripts/check_includes.py).
///
/// Mapping: one ENetHost per transport (it both listens and connects, so a peer's address is the
/// one it listens on), two ENet channels (0 reliable control, 1 unreliable sequenced state),
/// Delivery::Reliable -> ENET_PACKET_FLAG_RELIABLE, Unreliable -> unsequenced-off unreliable with
/// ENET_PACKET_FLAG_UNRELIABLE_FRAGMENT (a large unreliable packet is dropped whole if a fragment
/// is lost, never silently upgraded to reliable), Unsequenced -> ENET_PACKET_FLAG_UNSEQUENCED.
/// The disconnect reason travels as ENet's disconnect data; ENet reports 0 on a timeout.
///
/// Connection attempts are rate-limited before ENet sees them (an ENet intercept callback): a
/// datagram addressed to no peer (ENet's CONNECT) passes only if a token bucket for its source
/// IPv4 address and one for the whole host both have a token; otherwise it is dropped unanswered,
/// so a flood of spoofed CONNECTs cannot make this host reflect its handshake replies at a victim
/// faster than `connect_rate_total` (docs/protocol.md §10.5). A half-open incoming connection
/// (VERIFY_CONNECT sent, no acknowledgement) is reset after `half_open_timeout_ms`, which bounds
/// ENet's retransmissions of VERIFY_CONNECT to a spoofed source; unless the dialer has sent us a
/// datagram addressed to that connection, which only VERIFY_CONNECT can have told it: then it is
/// connected on its side and only its acknowledgement was lost, and the connection is kept
/// (resetting it would leave the dialer sending into nothing until its own timeout). Such an
/// answer also makes VERIFY_CONNECT due at once (at most every `k_verify_hasten_ms`) instead
/// of at ENet's timer (500 ms on a young connection, then doubling), so that the dialer's
/// acknowledgement of the copy completes the connection within a round trip; until it does,
/// ENet drops the dialer's data here.
///
/// Lost reliable commands are resent when later ones are acknowledged (`fast_retransmit`): the
/// intercept also reads the ACKNOWLEDGE commands of each connected peer's datagrams (nothing
/// else of them), and before each service a command sent before the newest one acknowledged
/// that has waited that one's round trip plus a quarter of the estimate is made due at once,
/// instead of at ENet's timer, which doubles at every resend (docs/protocol.md §2, "Lost
/// reliable commands").
///
/// Threading: single-threaded (ENet's FAQ: an ENetHost must not be used from two threads).
/// Keep calling poll() while waiting: an unserviced host stops acknowledging, and its peers time
/// it out after `timeout_min_ms`.

#include <pliant/net/transport.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>

namespace pliant::net
{

struct EnetSettings
{
    /// Connections the host holds at once, incoming and outgoing (ENet allows 4095). One more
    /// slot is kept, so that a connection beyond them is answered and closed with reason
    /// SessionFull (the dialer learns why) instead of being ignored until its timeout.
    std::size_t max_peers = 64;
    /// Connections with one remote IPv4 address (any port) at once; one beyond them is closed
    /// with reason SessionFull (0: no limit). Bounds how many of max_peers one machine can hold
    /// (docs/protocol.md §10.5).
    std::size_t max_peers_per_source = 16;
    std::uint32_t timeout_limit = 32;      ///< ENet's unacknowledged-packet limit
    std::uint32_t timeout_min_ms = 5000;   ///< a silent peer is dropped after at least this
    std::uint32_t timeout_max_ms = 30000;  ///< and at most this
    std::uint32_t connect_timeout_ms = 5000;
    /// New connection attempts accepted per second from one source IPv4 address (any port);
    /// <= 0: no limit per source.
    double connect_rate_per_source = 2.0;
    double connect_burst_per_source = 4.0;  ///< attempts a quiet source may make at once
    /// New connection attempts accepted per second over all sources; <= 0: no limit.
    double connect_rate_total = 20.0;
    double connect_burst_total = 40.0;
    /// An incoming connection still unacknowledged after this is reset silently, ms, unless the
    /// dialer has answered (see above).
    std::uint32_t half_open_timeout_ms = 1200;
    /// ENet's packet throttle drops unreliable (and unsequenced) packets at the sender, at random,
    /// whenever a round trip is slower than its recent mean: on a jittery link it thins the
    /// state stream even when the link has room. Off by default (the throttle stays at "send
    /// everything"): the session streams newest-wins states and has its own per-peer cap
    /// (SessionSettings::bandwidth_cap_mbit_s). true: ENet's defaults.
    bool throttle_unreliable = false;
    /// Resend a reliable command as soon as a command sent after it has been acknowledged and
    /// it has waited that command's round trip plus a reordering allowance (a quarter of the
    /// round-trip estimate, at least k_reorder_min_ms), as RACK does for TCP (RFC 8985), instead
    /// of only at ENet's timer: the round-trip estimate plus four deviations (three round trips
    /// on a young connection), doubled at every resend. false: ENet's timer alone.
    bool fast_retransmit = true;
    /// Reliable data a connection may have unacknowledged, bytes. ENet's own window is at most
    /// 64 KiB (its protocol's largest), which caps a reliable transfer at 64 KiB per round trip:
    /// 0.3 MB/s at a 200 ms round trip, seconds for a Welcome's model and state at level 6 and
    /// above. A larger value here raises each connection's window to it (and keeps it there
    /// when ENet recomputes it, as it does whenever a peer comes or goes); 0 or at most 64 KiB:
    /// ENet's window. What a session queues for a joiner is bounded too (256 KiB,
    /// docs/session.md §2), so a larger window than that changes nothing there.
    std::uint32_t reliable_window_bytes = 256 * 1024;
};

/// Counters of the connection-attempt filter since open().
struct EnetCounters
{
    std::uint64_t connect_attempts = 0;       ///< datagrams addressed to no peer (CONNECTs)
    std::uint64_t connects_rate_limited = 0;  ///< of those, dropped by the rate limit
    std::uint64_t half_open_reset = 0;        ///< incoming handshakes reset unacknowledged
    /// Incoming handshakes unacknowledged past half_open_timeout_ms but kept, because the dialer
    /// answered (its acknowledgement was lost; ENet's next VERIFY_CONNECT completes them).
    std::uint64_t half_open_kept = 0;
    /// VERIFY_CONNECTs resent before ENet's timer because the dialer had answered.
    std::uint64_t verify_hastened = 0;
    /// Incoming connections closed at once with reason SessionFull: max_peers were held, or
    /// max_peers_per_source from that address.
    std::uint64_t refused_full = 0;
    std::uint64_t refused_per_source = 0;
    /// Reliable commands resent before ENet's timer because a later one was acknowledged
    /// (EnetSettings::fast_retransmit).
    std::uint64_t fast_retransmits = 0;
};

/// A half-open connection's VERIFY_CONNECT is resent early on the dialer's answer only if its
/// last copy went at least this long ago, ms: a dialer sending every frame does not make it
/// resend every frame, and a copy still on its way is not chased by another.
inline constexpr std::uint32_t k_verify_hasten_ms = 50;

/// The least reordering allowance of EnetSettings::fast_retransmit, ms.
inline constexpr std::uint32_t k_reorder_min_ms = 2;

/// The counters of a transport made by make_enet_transport(); nothing for another transport.
[[nodiscard]] std::optional<EnetCounters> enet_counters(const Transport& transport) noexcept;

/// A Transport over ENet. ENet is initialised on first use in the process (reference counted).
/// \return nullptr never; errors appear at open().
[[nodiscard]] std::unique_ptr<Transport> make_enet_transport(const EnetSettings& settings = {});

}  // namespace pliant::net
