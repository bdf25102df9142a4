// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// ENet behind net::Transport: the only file that includes <enet/enet.h> (see enet_transport.h for
// the mapping). A connection's handle is stored in ENetPeer::data, so ENet's peer slots (which it
// reuses) never alias an old handle: a handle is issued once per connection and never again.
// Nothing here throws, so nothing unwinds through ENet's C frames (STYLE.md §5).

#include <pliant/net/enet_transport.h>

#include <enet/enet.h>

#include <chrono>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>

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

struct Connection
{
    ENetPeer* peer = nullptr;
    bool connected = false;
    Clock::time_point started{};
    DisconnectReason local_reason = DisconnectReason::None;  // set by disconnect()
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
        host_ = enet_host_create(&address, settings_.max_peers, k_channel_count, 0, 0);
        if (host_ == nullptr)
            return core::fail(core::ErrorCode::NetworkError,
                              "EnetTransport::open: cannot bind " + to_string(bind));
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
        ENetPeer* peer = enet_host_connect(host_, &address, k_channel_count, 0);
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
        if (!pending_.empty())
            return pop_pending();
        if (host_ == nullptr)
            return std::nullopt;
        expire_connect_attempts();
        if (!pending_.empty())
            return pop_pending();
        ENetEvent ev{};
        const int r = enet_host_service(host_, &ev,
                                        timeout_ms < 0 ? 0u : static_cast<enet_uint32>(timeout_ms));
        if (r <= 0)
            return std::nullopt;
        switch (ev.type)
        {
        case ENET_EVENT_TYPE_CONNECT:
        {
            PeerHandle handle = handle_of(ev.peer);
            if (handle.value == 0)
                handle = adopt(ev.peer);  // an incoming connection
            Connection& c = connections_.at(handle.value);
            c.connected = true;
            enet_peer_timeout(ev.peer, settings_.timeout_limit, settings_.timeout_min_ms,
                              settings_.timeout_max_ms);
            TransportEvent out;
            out.kind = TransportEvent::Kind::Connected;
            out.peer = handle;
            return out;
        }
        case ENET_EVENT_TYPE_DISCONNECT:
        {
            const PeerHandle handle = handle_of(ev.peer);
            if (handle.value == 0)
                return std::nullopt;
            TransportEvent out;
            out.kind = TransportEvent::Kind::Disconnected;
            out.peer = handle;
            const Connection& c = connections_.at(handle.value);
            if (c.local_reason != DisconnectReason::None)
                out.reason = c.local_reason;
            else if (ev.data >= 1 && ev.data <= k_max_disconnect_reason)
                out.reason = static_cast<DisconnectReason>(ev.data);
            else
                out.reason = DisconnectReason::TimedOut;
            ev.peer->data = nullptr;
            connections_.erase(handle.value);
            return out;
        }
        case ENET_EVENT_TYPE_RECEIVE:
        {
            const PeerHandle handle = handle_of(ev.peer);
            auto it = connections_.find(handle.value);
            TransportEvent out;
            out.kind = TransportEvent::Kind::Received;
            out.peer = handle;
            out.channel = ev.channelID == 0 ? Channel::Control : Channel::State;
            const auto* bytes = reinterpret_cast<const std::byte*>(ev.packet->data);
            out.data.assign(bytes, bytes + ev.packet->dataLength);
            enet_packet_destroy(ev.packet);
            if (it == connections_.end())
                return std::nullopt;
            it->second.stats.bytes_received += out.data.size();
            ++it->second.stats.packets_received;
            return out;
        }
        case ENET_EVENT_TYPE_NONE: break;
        }
        return std::nullopt;
    }

    void flush() noexcept override
    {
        if (host_ != nullptr)
            enet_host_flush(host_);
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
        s.rtt_s = static_cast<double>(it->second.peer->roundTripTime) * 1e-3;
        return s;
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

    std::vector<PeerHandle> peers() const override
    {
        std::vector<PeerHandle> out;
        for (const auto& [h, c] : connections_)
            if (c.connected)
                out.push_back(PeerHandle{h});
        return out;
    }

private:
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
};

}  // namespace

std::unique_ptr<Transport> make_enet_transport(const EnetSettings& settings)
{
    return std::make_unique<EnetTransport>(settings);
}

}  // namespace pliant::net
