// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `net::Transport`: moves opaque datagrams between connected peers on two channels
/// (docs/protocol.md §2). Implementations: `EnetTransport` (UDP through ENet; the only code that
/// sees ENet) and `SimulatedTransport` (an in-process network with seeded latency, jitter, loss,
/// duplication and reordering, for tests).
///
/// Design: one virtual call per packet or event (docs/style.md §6 allows it here); no callbacks,
/// the owner polls, so the session's loop decides when network work happens. The transport knows
/// no messages: decoding, bad-datagram detection and disconnect policy live in `net::Messenger`,
/// which reports bad datagrams back here so that all per-peer counters live in one `PeerStats`.
///
/// Threading contract: a Transport is single-threaded. All calls on one instance must come from
/// one thread at a time (ENet's FAQ: an ENetHost is not thread-safe; yojimbo and netcode are
/// single-threaded by design). Different instances may run on different threads (peers as
/// threads of one process); `SimulatedNetwork` locks its shared state for that.
///
/// Everything is noexcept; errors at the boundary are `core::Result`.

#include <pliant/core/result.h>
#include <pliant/net/types.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace pliant::net
{

/// An IPv4 address and UDP port (ENet 1.3 has no IPv6).
struct Address
{
    std::array<std::uint8_t, 4> ipv4{127, 0, 0, 1};  ///< a.b.c.d
    std::uint16_t port = 0;                          ///< 0 when binding: any free port

    friend bool operator==(const Address&, const Address&) = default;
};

/// Formats "a.b.c.d:port".
[[nodiscard]] std::string to_string(const Address& address);

/// Parses "a.b.c.d:port" or "localhost:port" (port 1..65535). \return
/// ErrorCode::InvalidArgument if malformed.
[[nodiscard]] core::Result<Address> parse_address(std::string_view text);
/// As parse_address, and "hostname:port" through the system's resolver (IPv4, the first address
/// found). Blocks on the look-up: for the command line, before a session starts. \return
/// ErrorCode::InvalidArgument if malformed (as parse_address, or an IPv6 address), and
/// ErrorCode::NetworkError naming the host when the look-up finds no IPv4 address.
[[nodiscard]] core::Result<Address> resolve_address(std::string_view text);

/// A connection as one Transport instance sees it. Handles are never reused by an instance, so
/// a stale handle is detected rather than aliased to a new peer.
struct PeerHandle
{
    std::uint32_t value = 0;  ///< 0 is never a live handle
    friend constexpr bool operator==(PeerHandle, PeerHandle) = default;
    friend constexpr auto operator<=>(PeerHandle, PeerHandle) = default;
};

/// How a packet is delivered.
enum class Delivery : std::uint8_t
{
    Reliable,     ///< exactly once, in order within the channel (retransmitted)
    Unreliable,   ///< at most once, in order: a packet older than one already delivered is dropped
    Unsequenced,  ///< no guarantee: may be lost, duplicated or reordered (ENet's unsequenced)
};

/// Counters per connection. Bytes are datagram payload bytes (not UDP/IP or ENet headers).
struct PeerStats
{
    double rtt_s = 0.0;  ///< smoothed round-trip time, s (ENet's mean RTT; the simulated link's)
    std::uint64_t bytes_sent = 0;
    std::uint64_t bytes_received = 0;
    std::uint64_t packets_sent = 0;
    std::uint64_t packets_received = 0;
    std::uint64_t bad_datagrams =
        0;  ///< received and dropped by the Messenger (report_bad_datagram)
    /// Seconds since anything came on the connection (data, an acknowledgement, a ping: a live
    /// process's transport answers even when it sends no data); 0 where the transport cannot
    /// tell (the simulated one).
    double silent_s = 0.0;
};

struct TransportEvent
{
    enum class Kind : std::uint8_t
    {
        Connected,     ///< a connection (incoming or the one connect() started) is ready
        Disconnected,  ///< the connection ended; `reason` says why (None if unknown)
        Received,      ///< `data` arrived on `channel`
    };
    Kind kind = Kind::Received;
    PeerHandle peer;
    Channel channel = Channel::Control;
    DisconnectReason reason = DisconnectReason::None;
    std::vector<std::byte> data;
};

/// Hands a queued event to a caller of Transport::poll_into: copies `from`'s fields into `out`
/// and swaps their data vectors, so `out` gets the datagram and `from.data` holds `out`'s
/// previous buffer, for the transport to keep for a later datagram.
inline void swap_into(TransportEvent& out, TransportEvent& from) noexcept
{
    out.kind = from.kind;
    out.peer = from.peer;
    out.channel = from.channel;
    out.reason = from.reason;
    out.data.swap(from.data);
}

class Transport
{
public:
    virtual ~Transport() = default;
    Transport() = default;
    Transport(const Transport&) = delete;
    Transport& operator=(const Transport&) = delete;

    /// Binds to `bind` (port 0: any free port) and accepts connections from then on.
    /// \return the bound address; ErrorCode::NetworkError if the socket cannot bind or the
    /// transport is already open.
    virtual core::Result<Address> open(const Address& bind) noexcept = 0;

    /// Starts connecting to `remote` (open() first). A Connected or Disconnected(TimedOut) event
    /// for the returned handle follows. \return ErrorCode::NetworkError if not open or no room.
    virtual core::Result<PeerHandle> connect(const Address& remote) noexcept = 0;

    /// Queues `bytes` to `peer` on `channel`. \return ErrorCode::NetworkError for an unknown or
    /// disconnected peer or a packet over the transport's limit.
    virtual core::Result<void> send(PeerHandle peer, Channel channel,
                                    std::span<const std::byte> bytes,
                                    Delivery delivery) noexcept = 0;

    /// Does network work and returns the next event, if any, waiting at most `timeout_ms` for one
    /// (SimulatedTransport never waits: its clock is the network's). Keep calling it while
    /// waiting for anything: ENet times out a peer whose host is not serviced for seconds.
    virtual std::optional<TransportEvent> poll(int timeout_ms = 0) noexcept = 0;

    /// poll() into a caller's event, for a receive loop that allocates nothing per datagram:
    /// EnetTransport copies a datagram into `out.data`'s storage (ENet itself still allocates a
    /// packet per datagram); SimulatedTransport and SecureTransport (beyond its inner transport)
    /// swap the datagram's vector into `out.data` and keep `out`'s previous vector for a later
    /// datagram, so once their buffers have grown they allocate nothing per datagram, sent or
    /// received. \return whether an event came (`out` then equals what poll() would have
    /// returned; otherwise its contents are unspecified). The default moves poll()'s event into
    /// `out`.
    virtual bool poll_into(TransportEvent& out, int timeout_ms = 0) noexcept;

    /// Sends queued packets now (poll() also does).
    virtual void flush() noexcept = 0;

    /// Blocks until a datagram may be ready for poll(), for at most `max_s` seconds: the idle
    /// time of a caller's loop. Unlike a sleep it ends as soon as data arrives, so a lockstep
    /// peer waiting for its neighbours' halos steps as soon as they are in instead of at the end
    /// of its nap. It does no network work (poll() does): call it after poll() returned nothing.
    /// It may return early (any datagram wakes it, ENet's acknowledgements too). The default
    /// sleeps `max_s` (SimulatedTransport: its clock is the network's, not the wall's).
    virtual void wait(double max_s) noexcept;

    /// Ends the connection gracefully; the remote side sees `reason`; a Disconnected event for
    /// `peer` follows here. Unknown handles are ignored.
    virtual void disconnect(PeerHandle peer, DisconnectReason reason) noexcept = 0;

    /// Counters of a live connection; nothing for an unknown handle.
    [[nodiscard]] virtual std::optional<PeerStats> stats(PeerHandle peer) const noexcept = 0;

    /// The remote address of a live connection.
    [[nodiscard]] virtual std::optional<Address> remote_address(PeerHandle peer) const noexcept = 0;

    /// Counts one bad datagram received from `peer` (called by whoever decodes).
    virtual void report_bad_datagram(PeerHandle peer) noexcept = 0;

    /// Handles of the live connections, in increasing order, into `out` (cleared first; its
    /// capacity is kept, for callers that ask on every poll).
    virtual void live_peers(std::vector<PeerHandle>& out) const = 0;
    /// As live_peers, returned.
    [[nodiscard]] std::vector<PeerHandle> peers() const;

    /// Bytes queued to `peer` and not yet sent, or sent reliably and not yet acknowledged: what
    /// a sender that feeds a large transfer (the Welcome's blobs) keeps bounded. 0 for an
    /// unknown handle, and from a transport that does not know (the default).
    [[nodiscard]] virtual std::size_t queued_bytes(PeerHandle peer) const noexcept;
};

}  // namespace pliant::net
