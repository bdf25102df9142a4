// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// ENet behind net::Transport: the only file that includes <enet/enet.h> (see enet_transport.h for
// the mapping). A connection's handle is stored in ENetPeer::data, so ENet's peer slots (which it
// reuses) never alias an old handle: a handle is issued once per connection and never again.
// Nothing here throws, so nothing unwinds through ENet's C frames (docs/style.md §5).
//
// Connection-attempt filter: ENet's intercept callback sees every received UDP datagram before
// ENet parses it. A datagram whose header peer id is ENET_PROTOCOL_MAXIMUM_PEER_ID is addressed
// to no peer, which ENet accepts only for a CONNECT; those pass two token buckets (per source
// address, and total) or are dropped unanswered. The callback has no user pointer, so the
// transport being serviced is found through a thread-local set around enet_host_service (a host
// is serviced by one thread at a time).

#include <pliant/net/enet_transport.h>

#include <enet/enet.h>
#include <enet/time.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <vector>

namespace pliant::net
{
namespace
{

using Clock = std::chrono::steady_clock;

// ENet's global state is initialised once per process while any transport lives.
std::mutex g_enet_mutex;
int g_enet_users = 0;

bool acquire_enet() noexcept
{
    const std::lock_guard lock(g_enet_mutex);
    if (g_enet_users == 0 && enet_initialize() != 0)
        return false;
    ++g_enet_users;
    return true;
}

void release_enet() noexcept
{
    const std::lock_guard lock(g_enet_mutex);
    if (--g_enet_users == 0)
        enet_deinitialize();
}

ENetAddress to_enet(const Address& a) noexcept
{
    ENetAddress e{};
    // ENetAddress::host is in network byte order: the bytes a.b.c.d in memory order.
    std::memcpy(&e.host, a.ipv4.data(), 4);
    e.port = a.port;
    return e;
}

Address from_enet(const ENetAddress& e) noexcept
{
    Address a;
    std::memcpy(a.ipv4.data(), &e.host, 4);
    a.port = e.port;
    return a;
}

// A token bucket: `rate` tokens per second up to `burst`; one token per attempt.
struct Bucket
{
    double tokens = 0.0;
    Clock::time_point last{};
};

void refill(Bucket& b, double rate, double burst, Clock::time_point now) noexcept
{
    const double dt = std::chrono::duration<double>(now - b.last).count();
    b.tokens = std::min(burst, b.tokens + rate * std::max(0.0, dt));
    b.last = now;
}

bool take(Bucket& b, double rate, double burst, Clock::time_point now) noexcept
{
    refill(b, rate, burst, now);
    if (b.tokens < 1.0)
        return false;
    b.tokens -= 1.0;
    return true;
}

class EnetTransport;
thread_local EnetTransport* t_servicing = nullptr;

struct Connection
{
    ENetPeer* peer = nullptr;
    bool connected = false;
    Clock::time_point started{};
    DisconnectReason local_reason = DisconnectReason::None;  // set by disconnect()
    bool hidden = false;  // refused at its CONNECT (no room): never reported, nor its end
    PeerStats stats;
};

class EnetTransport final : public Transport
{
public:
    explicit EnetTransport(const EnetSettings& settings)
        : settings_(settings), initialised_(acquire_enet())
    {
    }

    ~EnetTransport() override
    {
        if (host_ != nullptr)
        {
            for (auto& [h, c] : connections_)
                enet_peer_disconnect_now(c.peer,
                                         static_cast<enet_uint32>(DisconnectReason::Shutdown));
            enet_host_flush(host_);
            enet_host_destroy(host_);
        }
        if (initialised_)
            release_enet();
    }

    core::Result<Address> open(const Address& bind) noexcept override
    {
        if (!initialised_)
            return core::fail(core::ErrorCode::NetworkError,
                              "EnetTransport::open: enet_initialize failed");
        if (host_ != nullptr)
            return core::fail(core::ErrorCode::NetworkError, "EnetTransport::open: already open");
        const ENetAddress address = to_enet(bind);
        errno = 0;
        host_ = enet_host_create(&address, settings_.max_peers + 1, k_channel_count, 0, 0);
        if (host_ == nullptr)
        {
            // ENet keeps the socket's errno (bind's, most often EADDRINUSE).
            const int why = errno;
            std::string reason = why != 0 ? std::string(": ") + std::strerror(why) : "";
            if (why == EADDRINUSE)
                reason +=
                    " (another program, or another pliant, has this port: choose another "
                    "with --port)";
            return core::fail(core::ErrorCode::NetworkError,
                              "cannot bind UDP " + to_string(bind) + reason);
        }
        host_->intercept = &EnetTransport::intercept;
        acked_.assign(host_->peerCount, Acked{});
        total_.tokens = settings_.connect_burst_total;
        total_.last = Clock::now();
        ENetAddress bound{};
        if (enet_socket_get_address(host_->socket, &bound) != 0)
            return core::fail(core::ErrorCode::NetworkError,
                              "EnetTransport::open: cannot read the bound address");
        Address out = from_enet(bound);
        return out;
    }

    core::Result<PeerHandle> connect(const Address& remote) noexcept override
    {
        if (host_ == nullptr)
            return core::fail(core::ErrorCode::NetworkError, "EnetTransport::connect: not open");
        const ENetAddress address = to_enet(remote);
        ENetPeer* peer = held() < settings_.max_peers
                             ? enet_host_connect(host_, &address, k_channel_count, 0)
                             : nullptr;
        if (peer == nullptr)
            return core::fail(core::ErrorCode::NetworkError,
                              "EnetTransport::connect: no free peer slot for " + to_string(remote));
        const PeerHandle handle = adopt(peer);
        connections_.at(handle.value).started = Clock::now();
        return handle;
    }

    core::Result<void> send(PeerHandle peer, Channel channel, std::span<const std::byte> bytes,
                            Delivery delivery) noexcept override
    {
        auto it = connections_.find(peer.value);
        if (it == connections_.end() || !it->second.connected)
            return core::fail(
                core::ErrorCode::NetworkError,
                "EnetTransport::send: no connected peer " + std::to_string(peer.value));
        enet_uint32 flags = 0;
        switch (delivery)
        {
        case Delivery::Reliable: flags = ENET_PACKET_FLAG_RELIABLE; break;
        case Delivery::Unreliable: flags = ENET_PACKET_FLAG_UNRELIABLE_FRAGMENT; break;
        case Delivery::Unsequenced:
            flags = ENET_PACKET_FLAG_UNSEQUENCED | ENET_PACKET_FLAG_UNRELIABLE_FRAGMENT;
            break;
        }
        ENetPacket* packet = enet_packet_create(bytes.data(), bytes.size(), flags);
        if (packet == nullptr)
            return core::fail(core::ErrorCode::NetworkError, "EnetTransport::send: out of memory");
        if (enet_peer_send(it->second.peer, static_cast<enet_uint8>(channel), packet) != 0)
        {
            enet_packet_destroy(packet);
            return core::fail(core::ErrorCode::NetworkError,
                              "EnetTransport::send: ENet refused the packet (" +
                                  std::to_string(bytes.size()) + " bytes)");
        }
        it->second.stats.bytes_sent += bytes.size();
        ++it->second.stats.packets_sent;
        return {};
    }

    std::optional<TransportEvent> poll(int timeout_ms) noexcept override
    {
        TransportEvent out;
        if (!poll_into(out, timeout_ms))
            return std::nullopt;
        return out;
    }

    /// Fills every field of `out` (a Received datagram into `out.data`'s storage).
    bool poll_into(TransportEvent& out, int timeout_ms) noexcept override
    {
        if (!pending_.empty())
        {
            out = pop_pending();
            return true;
        }
        if (host_ == nullptr)
            return false;
        expire_connect_attempts();
        if (!pending_.empty())
        {
            out = pop_pending();
            return true;
        }
        ENetEvent ev{};
        resend_lost();
        widen_windows();
        t_servicing = this;
        const int r = enet_host_service(host_, &ev,
                                        timeout_ms < 0 ? 0u : static_cast<enet_uint32>(timeout_ms));
        t_servicing = nullptr;
        widen_windows();  // ENet resets them on a peer's BANDWIDTH_LIMIT
        reset_half_open();
        if (r <= 0)
            return false;
        switch (ev.type)
        {
        case ENET_EVENT_TYPE_CONNECT:
        {
            PeerHandle handle = handle_of(ev.peer);
            if (handle.value == 0)
            {
                // An incoming connection, unless there is no room for it.
                const std::size_t from_source = held(ev.peer->address.host);
                const bool full = held() >= settings_.max_peers;
                handle = adopt(ev.peer);
                if (full || (settings_.max_peers_per_source > 0 &&
                             from_source >= settings_.max_peers_per_source))
                {
                    refuse(connections_.at(handle.value), full);
                    return false;
                }
            }
            Connection& c = connections_.at(handle.value);
            c.connected = true;
            enet_peer_timeout(ev.peer, settings_.timeout_limit, settings_.timeout_min_ms,
                              settings_.timeout_max_ms);
            if (!settings_.throttle_unreliable)  // the throttle starts at its scale: keep it
                enet_peer_throttle_configure(ev.peer, ENET_PEER_PACKET_THROTTLE_INTERVAL, 0, 0);
            out.kind = TransportEvent::Kind::Connected;
            out.peer = handle;
            out.channel = Channel::Control;
            out.reason = DisconnectReason::None;
            out.data.clear();
            return true;
        }
        case ENET_EVENT_TYPE_DISCONNECT:
        {
            const PeerHandle handle = handle_of(ev.peer);
            if (handle.value == 0)
                return false;
            if (connections_.at(handle.value).hidden)
            {
                ev.peer->data = nullptr;
                connections_.erase(handle.value);
                return false;
            }
            out.kind = TransportEvent::Kind::Disconnected;
            out.peer = handle;
            out.channel = Channel::Control;
            out.data.clear();
            const Connection& c = connections_.at(handle.value);
            if (c.local_reason != DisconnectReason::None)
                out.reason = c.local_reason;
            else if (ev.data >= 1 && ev.data <= k_max_disconnect_reason)
                out.reason = static_cast<DisconnectReason>(ev.data);
            else
                out.reason = DisconnectReason::TimedOut;
            ev.peer->data = nullptr;
            connections_.erase(handle.value);
            return true;
        }
        case ENET_EVENT_TYPE_RECEIVE:
        {
            const PeerHandle handle = handle_of(ev.peer);
            auto it = connections_.find(handle.value);
            if (it == connections_.end())
            {
                enet_packet_destroy(ev.packet);
                return false;
            }
            out.kind = TransportEvent::Kind::Received;
            out.peer = handle;
            out.channel = ev.channelID == 0 ? Channel::Control : Channel::State;
            out.reason = DisconnectReason::None;
            const auto* bytes = reinterpret_cast<const std::byte*>(ev.packet->data);
            out.data.assign(bytes, bytes + ev.packet->dataLength);
            enet_packet_destroy(ev.packet);
            it->second.stats.bytes_received += out.data.size();
            ++it->second.stats.packets_received;
            return true;
        }
        case ENET_EVENT_TYPE_NONE: break;
        }
        return false;
    }

    void flush() noexcept override
    {
        if (host_ != nullptr)
        {
            widen_windows();
            enet_host_flush(host_);
        }
    }

    // On the socket, to the nanosecond (ENet's own wait, enet_socket_wait, counts whole
    // milliseconds). Events already taken off the socket (ours, or ENet's dispatch queue when
    // the caller stopped polling before it was empty) end it at once.
    void wait(double max_s) noexcept override
    {
        if (max_s <= 0.0 || !pending_.empty())
            return;
        if (host_ == nullptr)
        {
            Transport::wait(max_s);
            return;
        }
        if (!enet_list_empty(&host_->dispatchQueue))
            return;
        pollfd fd{};
        fd.fd = host_->socket;
        fd.events = POLLIN;
        const double whole = std::floor(max_s);
        timespec ts{};
        ts.tv_sec = static_cast<time_t>(whole);
        ts.tv_nsec = static_cast<long>(std::min(999'999'999.0, (max_s - whole) * 1e9));
        (void)::ppoll(&fd, 1, &ts, nullptr);  // EINTR (a signal): return, the caller goes on
    }

    void disconnect(PeerHandle peer, DisconnectReason reason) noexcept override
    {
        auto it = connections_.find(peer.value);
        if (it == connections_.end() || it->second.local_reason != DisconnectReason::None)
            return;
        it->second.local_reason =
            reason == DisconnectReason::None ? DisconnectReason::Quit : reason;
        if (!it->second.connected)
        {
            // Not connected yet: ENet would wait for the handshake; drop it now instead.
            enet_peer_reset(it->second.peer);
            it->second.peer->data = nullptr;
            TransportEvent out;
            out.kind = TransportEvent::Kind::Disconnected;
            out.peer = peer;
            out.reason = it->second.local_reason;
            connections_.erase(it);
            pending_.push_back(std::move(out));
            return;
        }
        enet_peer_disconnect(it->second.peer, static_cast<enet_uint32>(it->second.local_reason));
    }

    std::optional<PeerStats> stats(PeerHandle peer) const noexcept override
    {
        auto it = connections_.find(peer.value);
        if (it == connections_.end())
            return std::nullopt;
        PeerStats s = it->second.stats;
        const ENetPeer* p = it->second.peer;
        s.rtt_s = static_cast<double>(p->roundTripTime) * 1e-3;
        // ENet keeps the host's clock of the last datagram from the peer (its pings come every
        // 0.5 s when nothing else is sent).
        s.silent_s =
            static_cast<double>(ENET_TIME_DIFFERENCE(enet_time_get(), p->lastReceiveTime)) * 1e-3;
        return s;
    }

    // ENet's queue of commands not yet sent (reliable and unreliable, each fragment's bytes)
    // and its reliable bytes in flight, not yet acknowledged.
    std::size_t queued_bytes(PeerHandle peer) const noexcept override
    {
        auto it = connections_.find(peer.value);
        if (it == connections_.end())
            return 0;
        ENetPeer* p = it->second.peer;
        std::size_t n = p->reliableDataInTransit;
        for (ENetListIterator c = enet_list_begin(&p->outgoingCommands);
             c != enet_list_end(&p->outgoingCommands); c = enet_list_next(c))
            n += reinterpret_cast<const ENetOutgoingCommand*>(c)->fragmentLength;
        return n;
    }

    std::optional<Address> remote_address(PeerHandle peer) const noexcept override
    {
        auto it = connections_.find(peer.value);
        if (it == connections_.end())
            return std::nullopt;
        return from_enet(it->second.peer->address);
    }

    void report_bad_datagram(PeerHandle peer) noexcept override
    {
        auto it = connections_.find(peer.value);
        if (it != connections_.end())
            ++it->second.stats.bad_datagrams;
    }

    void live_peers(std::vector<PeerHandle>& out) const override
    {
        out.clear();
        for (const auto& [h, c] : connections_)
            if (c.connected)
                out.push_back(PeerHandle{h});
    }

    [[nodiscard]] EnetCounters counters() const noexcept { return counters_; }

    static int ENET_CALLBACK intercept(ENetHost* host, ENetEvent* /*event*/)
    {
        EnetTransport* self = t_servicing;
        if (self == nullptr || self->host_ != host || host->receivedDataLength < 2)
            return 0;  // ENet drops what it cannot parse
        // Header: u16 big-endian: flags (2 bits), session (2 bits), peer id (12 bits).
        const unsigned peer_id =
            ((static_cast<unsigned>(host->receivedData[0]) << 8) | host->receivedData[1]) &
            ~static_cast<unsigned>(ENET_PROTOCOL_HEADER_FLAG_MASK |
                                   ENET_PROTOCOL_HEADER_SESSION_MASK) &
            0xFFFFu;
        if (peer_id != ENET_PROTOCOL_MAXIMUM_PEER_ID)
        {
            const unsigned session =
                (((static_cast<unsigned>(host->receivedData[0]) << 8) | host->receivedData[1]) &
                 ENET_PROTOCOL_HEADER_SESSION_MASK) >>
                ENET_PROTOCOL_HEADER_SESSION_SHIFT;
            self->note_answer(peer_id, session, host->receivedAddress);
            self->note_acks(peer_id, session);
            return 0;
        }
        return self->admit(host->receivedAddress) ? 0 : 1;  // 1: consumed, never answered
    }

private:
    bool admit(const ENetAddress& from) noexcept
    {
        ++counters_.connect_attempts;
        const auto now = Clock::now();
        bool ok = true;
        if (settings_.connect_rate_per_source > 0.0)
        {
            constexpr std::size_t k_max_sources = 4096;
            // A full table is swept at most every 100 ms: a flood of CONNECTs from spoofed
            // sources keeps it full, and sweeping it for each one cost 4,096 refills a datagram.
            // Until the next sweep a new source gets no bucket (the total limit still applies).
            if (sources_.size() >= k_max_sources &&
                now - last_sweep_ >= std::chrono::milliseconds(100))
            {
                last_sweep_ = now;
                for (auto it = sources_.begin(); it != sources_.end();)
                {
                    // A bucket that refilled completely holds no information: forget it.
                    refill(it->second, settings_.connect_rate_per_source,
                           settings_.connect_burst_per_source, now);
                    if (it->second.tokens >= settings_.connect_burst_per_source)
                        it = sources_.erase(it);
                    else
                        ++it;
                }
            }
            auto it = sources_.find(from.host);
            if (it == sources_.end() && sources_.size() < k_max_sources)
                it = sources_.emplace(from.host, Bucket{settings_.connect_burst_per_source, now})
                         .first;
            if (it != sources_.end())
                ok = take(it->second, settings_.connect_rate_per_source,
                          settings_.connect_burst_per_source, now);
        }
        if (ok && settings_.connect_rate_total > 0.0)
            ok = take(total_, settings_.connect_rate_total, settings_.connect_burst_total, now);
        if (!ok)
        {
            ++counters_.connects_rate_limited;
            if (now - last_warning_ > std::chrono::seconds(10))
            {
                last_warning_ = now;
                spdlog::warn("net: connection attempts rate-limited ({} so far, latest from {})",
                             counters_.connects_rate_limited, to_string(from_enet(from)));
            }
        }
        return ok;
    }

    // A datagram addressed to one of our peers, before ENet reads it. If that peer is a half-open
    // incoming connection and the datagram comes from its address with its session bits, the
    // dialer has received our VERIFY_CONNECT (only that tells it our peer id) and is connected
    // on its side: its acknowledgement was lost. Such a peer is kept past half_open_timeout_ms,
    // so that ENet's next VERIFY_CONNECT is acknowledged and the connection completes here too;
    // resetting it would leave the dialer sending into a connection we no longer have until its
    // own timeout (5-30 s). A spoofed CONNECT's source never sees VERIFY_CONNECT, so it cannot
    // send this. The next VERIFY_CONNECT is also made due now (hasten_verify).
    void note_answer(unsigned peer_id, unsigned session, const ENetAddress& from) noexcept
    {
        if (peer_id >= host_->peerCount)
            return;
        ENetPeer* p = &host_->peers[peer_id];
        if (p->state == ENET_PEER_STATE_ACKNOWLEDGING_CONNECT && p->address.host == from.host &&
            p->address.port == from.port && session == p->incomingSessionID)
        {
            answered_[p] = p->connectID;
            hasten_verify(*p);
        }
    }

    // ENet resends VERIFY_CONNECT when its timer runs out: the peer's round-trip estimate, 500 ms
    // on a connection with no sample yet, doubled at each resend. The dialer's answer says it is
    // connected, so its acknowledgement was lost (or comes in this very datagram, which then
    // removes the command before ENet's check), and waiting for the timer only keeps the
    // connection half-open here (ENet drops the dialer's data meanwhile, and a session's greeting
    // with it). Makes the command due at ENet's next check (after this datagram is read, in this
    // enet_host_service or the next): its timeout is set to the time since it was sent
    // (ENet doubles that at the resend), unless it went less than k_verify_hasten_ms ago or is
    // due anyway. Only fields of <enet/enet.h>'s public structures are touched, as ENet's own
    // check reads them (its protocol.c, enet_protocol_check_timeouts).
    void hasten_verify(ENetPeer& p) noexcept
    {
        for (ENetListIterator it = enet_list_begin(&p.sentReliableCommands);
             it != enet_list_end(&p.sentReliableCommands); it = enet_list_next(it))
        {
            auto* c = reinterpret_cast<ENetOutgoingCommand*>(it);
            if ((c->command.header.command & ENET_PROTOCOL_COMMAND_MASK) !=
                ENET_PROTOCOL_COMMAND_VERIFY_CONNECT)
                continue;
            const enet_uint32 since = ENET_TIME_DIFFERENCE(host_->serviceTime, c->sentTime);
            if (since < k_verify_hasten_ms || since >= c->roundTripTimeout)
                return;
            c->roundTripTimeout = since;
            p.nextTimeout = host_->serviceTime;
            ++counters_.verify_hastened;
            return;
        }
    }

    // The newest transmission a peer has acknowledged (EnetSettings::fast_retransmit): its ENet
    // sent time, and the channel and reliable sequence number of the command acknowledged, which
    // order the commands of one datagram or of one millisecond's burst (ENet numbers a channel's
    // reliable commands in the order it sends them). Kept per ENet peer slot, for one connection
    // (connect_id).
    struct Acked
    {
        enet_uint32 connect_id = 0;
        bool valid = false;
        enet_uint32 sent = 0;  // ENet time, ms
        enet_uint32 rtt = 0;   // ms, from that transmission to its acknowledgement
        enet_uint8 channel = 0;
        enet_uint16 sequence = 0;
    };

    // Was `c` sent before the newest transmission acknowledged, `a`?
    static bool sent_before(const ENetOutgoingCommand& c, const Acked& a) noexcept
    {
        if (ENET_TIME_LESS(c.sentTime, a.sent))
            return true;
        return c.sentTime == a.sent && c.command.header.channelID == a.channel &&
               static_cast<std::int16_t>(
                   static_cast<std::uint16_t>(c.reliableSequenceNumber - a.sequence)) < 0;
    }

    // A datagram addressed to peer slot `peer_id`, before ENet reads it: notes the newest
    // transmission its ACKNOWLEDGE commands name. Only a connected peer's datagrams from its
    // address with its session bits count (ENet's own test before it takes an acknowledgement);
    // the commands are walked as ENet walks them (sizes from enet_protocol_command_size, data
    // lengths from their headers), stopping at anything ENet would stop at. Nothing is written
    // to ENet's state here.
    void note_acks(unsigned peer_id, unsigned session) noexcept
    {
        if (!settings_.fast_retransmit || peer_id >= acked_.size())
            return;
        const ENetPeer& p = host_->peers[peer_id];
        const ENetAddress& from = host_->receivedAddress;
        if ((p.state != ENET_PEER_STATE_CONNECTED && p.state != ENET_PEER_STATE_DISCONNECT_LATER) ||
            from.host != p.address.host || from.port != p.address.port ||
            session != p.incomingSessionID)
            return;
        const enet_uint8* data = host_->receivedData;
        const std::size_t length = host_->receivedDataLength;
        const unsigned flags = ((static_cast<unsigned>(data[0]) << 8) | data[1]) &
                               static_cast<unsigned>(ENET_PROTOCOL_HEADER_FLAG_MASK);
        if ((flags & ENET_PROTOCOL_HEADER_FLAG_COMPRESSED) != 0)
            return;  // pliant sets no compressor: ENet drops it
        std::size_t at = (flags & ENET_PROTOCOL_HEADER_FLAG_SENT_TIME) != 0
                             ? sizeof(ENetProtocolHeader)
                             : offsetof(ENetProtocolHeader, sentTime);
        if (host_->checksum != nullptr)
            at += sizeof(enet_uint32);
        Acked& a = acked_[peer_id];
        if (a.connect_id != p.connectID)
            a = Acked{p.connectID};
        const enet_uint32 now = host_->serviceTime;
        for (int guard = 0; guard < ENET_PROTOCOL_MAXIMUM_PACKET_COMMANDS &&
                            at + sizeof(ENetProtocolCommandHeader) <= length;
             ++guard)
        {
            ENetProtocol c{};
            std::memcpy(&c, data + at, std::min(sizeof(c), length - at));
            const unsigned number = c.header.command & ENET_PROTOCOL_COMMAND_MASK;
            const std::size_t size = number < ENET_PROTOCOL_COMMAND_COUNT
                                         ? enet_protocol_command_size(c.header.command)
                                         : 0;
            if (size == 0 || at + size > length)
                return;
            at += size;
            switch (number)
            {
            case ENET_PROTOCOL_COMMAND_ACKNOWLEDGE:
            {
                // The 16 low bits of our clock when we sent it, widened as ENet widens them.
                enet_uint32 sent = ENET_NET_TO_HOST_16(c.acknowledge.receivedSentTime);
                sent |= now & 0xFFFF0000u;
                if ((sent & 0x8000u) > (now & 0x8000u))
                    sent -= 0x10000u;
                if (ENET_TIME_LESS(now, sent))
                    break;  // from the future: ENet ignores it too
                const enet_uint16 sequence =
                    ENET_NET_TO_HOST_16(c.acknowledge.receivedReliableSequenceNumber);
                const bool newer = !a.valid || ENET_TIME_GREATER(sent, a.sent) ||
                                   (sent == a.sent && c.header.channelID == a.channel &&
                                    static_cast<std::int16_t>(
                                        static_cast<std::uint16_t>(sequence - a.sequence)) > 0);
                if (newer)
                {
                    a.valid = true;
                    a.sent = sent;
                    a.rtt = ENET_TIME_DIFFERENCE(now, sent);
                    a.channel = c.header.channelID;
                    a.sequence = sequence;
                }
                break;
            }
            case ENET_PROTOCOL_COMMAND_SEND_RELIABLE:
                at += ENET_NET_TO_HOST_16(c.sendReliable.dataLength);
                break;
            case ENET_PROTOCOL_COMMAND_SEND_UNRELIABLE:
                at += ENET_NET_TO_HOST_16(c.sendUnreliable.dataLength);
                break;
            case ENET_PROTOCOL_COMMAND_SEND_UNSEQUENCED:
                at += ENET_NET_TO_HOST_16(c.sendUnsequenced.dataLength);
                break;
            case ENET_PROTOCOL_COMMAND_SEND_FRAGMENT:
            case ENET_PROTOCOL_COMMAND_SEND_UNRELIABLE_FRAGMENT:
                at += ENET_NET_TO_HOST_16(c.sendFragment.dataLength);
                break;
            default: break;
            }
        }
    }

    // Before each service: every reliable command still unacknowledged that was sent before the
    // newest transmission its peer acknowledged, and has waited that transmission's round trip
    // plus the reordering allowance, is taken as lost and made due at ENet's next check, as
    // hasten_verify does (its timeout set to the time since it was sent; ENet doubles that at
    // the resend). ENet keeps sentReliableCommands in the order it sent them, so the walk stops
    // at the first command too young or sent after the acknowledged one.
    void resend_lost() noexcept
    {
        if (!settings_.fast_retransmit)
            return;
        const enet_uint32 now = enet_time_get();
        for (auto& [h, conn] : connections_)
        {
            ENetPeer* p = conn.peer;
            if (!conn.connected || p == nullptr)
                continue;
            const auto slot = static_cast<std::size_t>(p - host_->peers);
            const Acked& a = acked_[slot];
            if (!a.valid || a.connect_id != p->connectID)
                continue;
            const enet_uint32 wait =
                a.rtt + std::max<enet_uint32>(k_reorder_min_ms, p->roundTripTime / 4);
            for (ENetListIterator it = enet_list_begin(&p->sentReliableCommands);
                 it != enet_list_end(&p->sentReliableCommands); it = enet_list_next(it))
            {
                auto* c = reinterpret_cast<ENetOutgoingCommand*>(it);
                if (ENET_TIME_GREATER(c->sentTime, a.sent))
                    break;
                const enet_uint32 since = ENET_TIME_DIFFERENCE(now, c->sentTime);
                if (since < wait)
                    break;
                if (!sent_before(*c, a) || since >= c->roundTripTimeout)
                    continue;  // not known lost, or due at ENet's timer anyway
                c->roundTripTimeout = std::max<enet_uint32>(since, 1);
                p->nextTimeout = now;
                ++counters_.fast_retransmits;
            }
        }
    }

    // Raises every connection's reliable window to reliable_window_bytes. ENet sets it at the
    // handshake and again on each BANDWIDTH_LIMIT command (which every peer sends to all its
    // peers whenever one comes or goes), from the hosts' bandwidth limits, at most
    // ENET_PROTOCOL_MAXIMUM_WINDOW_SIZE; it is read only by ENet's own sender, against the
    // reliable data in transit (its protocol.c, enet_protocol_check_outgoing_commands), and
    // travels nowhere. So it is set again before each service and flush and after each service.
    void widen_windows() noexcept
    {
        const enet_uint32 w = settings_.reliable_window_bytes;
        if (w <= ENET_PROTOCOL_MAXIMUM_WINDOW_SIZE)
            return;
        for (auto& [h, c] : connections_)
            if (c.connected && c.peer != nullptr && c.peer->windowSize < w)
                c.peer->windowSize = w;
    }

    // Resets incoming handshakes that were never acknowledged (spoofed or dead sources), so ENet
    // stops retransmitting VERIFY_CONNECT to them, unless the dialer has answered (note_answer):
    // those are left to ENet, whose VERIFY_CONNECT retransmissions (500 ms, then doubling) go on
    // until acknowledged or until ENet's own timeout. Scans the peer array at most every 100 ms.
    void reset_half_open()
    {
        const auto now = Clock::now();
        if (now - last_scan_ < std::chrono::milliseconds(100))
            return;
        last_scan_ = now;
        const auto limit = std::chrono::milliseconds(settings_.half_open_timeout_ms);
        for (std::size_t k = 0; k < host_->peerCount; ++k)
        {
            ENetPeer* p = &host_->peers[k];
            if (p->state != ENET_PEER_STATE_ACKNOWLEDGING_CONNECT)
            {
                half_open_.erase(p);
                answered_.erase(p);
                continue;
            }
            auto [it, fresh] = half_open_.try_emplace(p, HalfOpen{now, p->connectID, false});
            if (!fresh && it->second.connect_id != p->connectID)
                it->second = HalfOpen{now, p->connectID, false};  // the slot holds a new attempt
            if (fresh || now - it->second.since <= limit)
                continue;
            const auto a = answered_.find(p);
            if (a != answered_.end() && a->second == p->connectID)
            {
                if (!it->second.kept)
                    ++counters_.half_open_kept;
                it->second.kept = true;
                continue;
            }
            enet_peer_reset(p);
            half_open_.erase(it);
            answered_.erase(p);
            ++counters_.half_open_reset;
        }
    }

    /// Connections held (connected or connecting, not being closed by us), all of them or those
    /// with the remote IPv4 address `host`.
    [[nodiscard]] std::size_t held(std::optional<enet_uint32> host = std::nullopt) const
    {
        std::size_t n = 0;
        for (const auto& [h, c] : connections_)
            if (!c.hidden && c.local_reason == DisconnectReason::None &&
                (!host || c.peer->address.host == *host))
                ++n;
        return n;
    }

    /// Closes an incoming connection at its CONNECT, with reason SessionFull: the dialer learns
    /// why at once. Neither its connection nor its end is reported.
    void refuse(Connection& c, bool full)
    {
        c.hidden = true;
        c.local_reason = DisconnectReason::SessionFull;
        ++(full ? counters_.refused_full : counters_.refused_per_source);
        const auto now = Clock::now();
        if (now - last_full_warning_ > std::chrono::seconds(10))
        {
            last_full_warning_ = now;
            const std::string from = to_string(from_enet(c.peer->address));
            if (full)
                spdlog::warn(
                    "net: refused the connection from {}: all {} peer slots are taken "
                    "(reason session-full)",
                    from, settings_.max_peers);
            else
                spdlog::warn(
                    "net: refused the connection from {}: that address holds {} "
                    "connections already (reason session-full)",
                    from, settings_.max_peers_per_source);
        }
        enet_peer_disconnect(c.peer, static_cast<enet_uint32>(DisconnectReason::SessionFull));
    }

    PeerHandle adopt(ENetPeer* peer)
    {
        const std::uint32_t handle = next_handle_++;
        peer->data = reinterpret_cast<void*>(static_cast<std::uintptr_t>(handle));
        Connection c;
        c.peer = peer;
        connections_.emplace(handle, c);
        return PeerHandle{handle};
    }

    static PeerHandle handle_of(const ENetPeer* peer) noexcept
    {
        return PeerHandle{static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(peer->data))};
    }

    // ENet retries a connect for as long as its timeout allows; give up at connect_timeout_ms.
    void expire_connect_attempts()
    {
        const auto now = Clock::now();
        for (auto it = connections_.begin(); it != connections_.end();)
        {
            Connection& c = it->second;
            if (!c.connected && c.local_reason == DisconnectReason::None &&
                now - c.started > std::chrono::milliseconds(settings_.connect_timeout_ms))
            {
                enet_peer_reset(c.peer);
                c.peer->data = nullptr;
                TransportEvent out;
                out.kind = TransportEvent::Kind::Disconnected;
                out.peer = PeerHandle{it->first};
                out.reason = DisconnectReason::TimedOut;
                pending_.push_back(std::move(out));
                it = connections_.erase(it);
            }
            else
            {
                ++it;
            }
        }
    }

    TransportEvent pop_pending()
    {
        TransportEvent ev = std::move(pending_.front());
        pending_.pop_front();
        return ev;
    }

    EnetSettings settings_;
    bool initialised_ = false;
    ENetHost* host_ = nullptr;
    std::uint32_t next_handle_ = 1;
    std::map<std::uint32_t, Connection> connections_;
    std::deque<TransportEvent> pending_;
    std::map<enet_uint32, Bucket> sources_;
    Bucket total_;
    struct HalfOpen
    {
        Clock::time_point since;  // first seen half-open
        enet_uint32 connect_id = 0;
        bool kept = false;  // answered and kept past the timeout (counted once)
    };
    std::map<const ENetPeer*, HalfOpen> half_open_;
    std::map<const ENetPeer*, enet_uint32> answered_;  // half-open, the dialer answered: connect id
    std::vector<Acked> acked_;                         // by ENet peer slot (fast_retransmit)
    Clock::time_point last_scan_{};
    Clock::time_point last_sweep_{};  ///< of sources_, when full (admit)
    Clock::time_point last_warning_{};
    Clock::time_point last_full_warning_{};
    EnetCounters counters_;
};

}  // namespace

std::optional<EnetCounters> enet_counters(const Transport& transport) noexcept
{
    const auto* t = dynamic_cast<const EnetTransport*>(&transport);
    if (t == nullptr)
        return std::nullopt;
    return t->counters();
}

std::unique_ptr<Transport> make_enet_transport(const EnetSettings& settings)
{
    return std::make_unique<EnetTransport>(settings);
}

}  // namespace pliant::net
