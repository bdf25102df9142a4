// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The simulated network (see simulated_transport.h for the model). Layout: one Impl holds every
// endpoint, every connection and one min-heap of packets in flight ordered by (arrival time,
// sender, per-link transmission number, copy), which makes delivery order a function of the seed
// and of each sender's own order of sends.
//
// Costs: no allocation per datagram through send() and poll_into() once the network has carried
// as many datagrams of each size class (powers of two from 64 bytes to 64 KiB) at once as it
// carries now. A datagram's bytes travel in one buffer from send() to the receiver's event;
// buffers come back to the network's free lists (`spare_buffers`, one per size class) when a packet
// is lost or dropped, or delivered to a caller of poll_into() (which swaps its previous buffer in),
// and send() and duplication draw from it; the map nodes of early reliable packets (`held`) are
// recycled the same way; the packets in flight and the event queues live in vectors that keep their
// storage.

#include <pliant/net/simulated_transport.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <mutex>
#include <utility>
#include <vector>

namespace pliant::net
{
namespace
{

std::uint64_t splitmix64(std::uint64_t& state) noexcept
{
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

std::int64_t to_us(double seconds) noexcept
{
    return std::llround(seconds * 1e6);
}

enum class PacketKind : std::uint8_t
{
    Connect,  // to_handle 0; from_handle the initiator's
    Accept,   // reliable seq 0 of channel 0 from acceptor to initiator
    Data,
    Disconnect,  // reliable on channel 0, after the data
    Timeout,     // local notice: the link gave up
};

struct Packet
{
    std::int64_t arrival_us = 0;
    int from = 0;  // endpoint ids
    int to = 0;
    std::uint64_t link_counter = 0;
    int copy = 0;
    PacketKind kind = PacketKind::Data;
    std::uint32_t from_handle = 0;
    std::uint32_t to_handle = 0;
    Channel channel = Channel::Control;
    Delivery delivery = Delivery::Reliable;
    std::uint32_t seq = 0;
    DisconnectReason reason = DisconnectReason::None;
    std::vector<std::byte> data;
};

struct LaterFirst
{
    bool operator()(const Packet& a, const Packet& b) const noexcept
    {
        return std::tie(a.arrival_us, a.from, a.link_counter, a.copy) >
               std::tie(b.arrival_us, b.from, b.link_counter, b.copy);
    }
};

struct Link
{
    LinkSettings settings;
    std::uint64_t rng = 0;
    std::uint64_t counter = 0;

    double uniform() noexcept { return static_cast<double>(splitmix64(rng) >> 11) * 0x1.0p-53; }
};

using HeldPackets = std::map<std::uint32_t, Packet>;

struct ChannelState
{
    std::uint32_t next_reliable_send = 0;
    std::uint32_t next_unreliable_send = 1;
    std::uint32_t next_reliable_recv = 0;
    HeldPackets held;  // reliable packets that arrived early
    std::uint32_t last_unreliable_recv = 0;
};

struct Connection
{
    int remote = 0;
    std::uint32_t remote_handle = 0;
    bool connected = false;
    std::array<ChannelState, k_channel_count> channels{};
    PeerStats stats;
};

// A FIFO of events on a ring that keeps its storage (std::deque frees a block and allocates
// another every few events, even when its length stays put). A popped slot is left empty: poll()
// moves its event out, poll_into() recycles the buffer it swapped in.
class EventQueue
{
public:
    [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
    [[nodiscard]] TransportEvent& front() noexcept { return slots_[head_]; }
    void push_back(TransportEvent&& ev)
    {
        if (size_ == slots_.size())
            grow();
        slots_[(head_ + size_) % slots_.size()] = std::move(ev);
        ++size_;
    }
    void pop_front() noexcept
    {
        head_ = (head_ + 1) % slots_.size();
        --size_;
    }
    void clear() noexcept
    {
        slots_.clear();
        head_ = 0;
        size_ = 0;
    }

private:
    void grow()
    {
        std::vector<TransportEvent> bigger(std::max<std::size_t>(16, 2 * slots_.size()));
        for (std::size_t k = 0; k < size_; ++k)
            bigger[k] = std::move(slots_[(head_ + k) % slots_.size()]);
        slots_ = std::move(bigger);
        head_ = 0;
    }

    std::vector<TransportEvent> slots_;
    std::size_t head_ = 0;
    std::size_t size_ = 0;
};

struct Endpoint
{
    bool open = false;
    Address address;
    std::uint32_t next_handle = 1;
    std::map<std::uint32_t, Connection> connections;
    EventQueue events;
};

}  // namespace

struct SimulatedNetwork::Impl
{
    explicit Impl(const SimulatedNetworkSettings& s) : settings(s) {}

    mutable std::mutex mutex;
    SimulatedNetworkSettings settings;
    std::int64_t now = 0;
    std::vector<Endpoint> endpoints{1};  // index 0 unused: ids start at 1
    std::map<std::pair<int, int>, Link> links;
    // A min-heap by LaterFirst, through std::push_heap and std::pop_heap as std::priority_queue
    // does (so the same order), kept as a vector so that a packet can be moved out of its top.
    std::vector<Packet> in_flight;
    SimulatedTotals totals;
    // Datagram buffers (empty, with capacity) by size class, and map nodes of `held`, for reuse:
    // the network's, since a buffer goes from the sender's send() to the receiver's caller and
    // back. Class c holds buffers of at least 2^(c + k_min_shift) bytes and less than twice
    // that, so a datagram takes a buffer less than twice its size (rounded up to 64 bytes).
    // (One pool reserved for the largest datagram so far gave every small datagram a buffer of
    // up to 64 KiB: at level 8 the model's messages set that size, and the bytes in flight were
    // spread over so much memory that `pliant_bench_session --cpu` ran up to a third slower.)
    static constexpr int k_min_shift = 6;  // 64 bytes
    static constexpr int k_classes = 11;   // 64 bytes to 64 KiB
    std::array<std::vector<std::vector<std::byte>>, k_classes> spare_buffers;
    std::vector<HeldPackets::node_type> spare_nodes;

    void push_in_flight(Packet p)
    {
        in_flight.push_back(std::move(p));
        std::push_heap(in_flight.begin(), in_flight.end(), LaterFirst{});
    }

    Packet pop_in_flight()
    {
        std::pop_heap(in_flight.begin(), in_flight.end(), LaterFirst{});
        Packet p = std::move(in_flight.back());
        in_flight.pop_back();
        return p;
    }

    [[nodiscard]] static std::size_t class_bytes(int c) noexcept
    {
        return std::size_t{1} << (c + k_min_shift);
    }

    // An empty buffer with room for `size` bytes: a spare of the least class that holds it (or
    // of the next), or a new one of that class's size. Datagrams over 64 KiB get a buffer of
    // their own size, which recycle() frees.
    std::vector<std::byte> take_buffer(std::size_t size)
    {
        int c = 0;
        while (c < k_classes && class_bytes(c) < size)
            ++c;
        std::vector<std::byte> out;
        if (c == k_classes)
        {
            out.reserve(size);
            return out;
        }
        for (int k = c; k < std::min(c + 2, k_classes); ++k)
        {
            auto& spares = spare_buffers[static_cast<std::size_t>(k)];
            if (!spares.empty())
            {
                out = std::move(spares.back());
                spares.pop_back();
                return out;
            }
        }
        out.reserve(class_bytes(c));
        return out;
    }

    // Keeps `buffer`'s storage for a later datagram, in the greatest class its capacity holds
    // (none under 64 bytes or over 64 KiB: freed); `buffer` is left empty.
    void recycle(std::vector<std::byte>& buffer)
    {
        const std::size_t room = buffer.capacity();
        if (room >= class_bytes(0) && room < 2 * class_bytes(k_classes - 1))
        {
            int c = 0;
            while (c + 1 < k_classes && class_bytes(c + 1) <= room)
                ++c;
            buffer.clear();
            spare_buffers[static_cast<std::size_t>(c)].push_back(std::move(buffer));
        }
        buffer = {};
    }

    Link& link(int from, int to)
    {
        auto it = links.find({from, to});
        if (it == links.end())
        {
            Link l;
            l.settings = settings.link;
            l.rng = settings.seed ^ (0x100000001B3ULL * static_cast<std::uint64_t>(from)) ^
                    (0xC2B2AE3D27D4EB4FULL * static_cast<std::uint64_t>(to));
            splitmix64(l.rng);
            it = links.emplace(std::pair{from, to}, l).first;
        }
        return it->second;
    }

    int endpoint_at(const Address& a) const
    {
        for (std::size_t i = 1; i < endpoints.size(); ++i)
            if (endpoints[i].open && endpoints[i].address == a)
                return static_cast<int>(i);
        return 0;
    }

    std::int64_t retransmit_us(const LinkSettings& l) const
    {
        if (settings.retransmit_s > 0.0)
            return to_us(settings.retransmit_s);
        return 2 * (to_us(l.latency_s) + to_us(l.jitter_s)) + 1000;
    }

    std::int64_t one_way_delay(Link& l, bool& reordered)
    {
        std::int64_t d = to_us(l.settings.latency_s) + to_us(l.settings.jitter_s * l.uniform());
        reordered = l.settings.reorder > 0.0 && l.uniform() < l.settings.reorder;
        if (reordered)
            d += to_us(l.settings.reorder_delay_s);
        return d;
    }

    // Puts `p` (from, to, kind, payload filled in) on the wire with its fate drawn from the link.
    // A lost packet's buffer is recycled.
    void transmit(Packet p)
    {
        Link& l = link(p.from, p.to);
        p.link_counter = l.counter++;
        std::int64_t t = now;
        ++totals.transmissions;
        if (p.delivery == Delivery::Reliable)
        {
            int attempt = 0;
            while (l.uniform() < l.settings.loss)
            {
                ++totals.lost;
                if (++attempt >= settings.max_attempts)
                {
                    give_up(p, t);
                    recycle(p.data);
                    return;
                }
                t += retransmit_us(l.settings);
                ++totals.retransmitted;
                ++totals.transmissions;
            }
        }
        else if (l.uniform() < l.settings.loss)
        {
            ++totals.lost;
            recycle(p.data);
            return;
        }
        bool reordered = false;
        p.arrival_us = t + one_way_delay(l, reordered);
        totals.reordered += reordered ? 1 : 0;
        if (l.settings.duplicate > 0.0 && l.uniform() < l.settings.duplicate)
        {
            ++totals.duplicated;
            // The header copied, the bytes into a spare buffer.
            std::vector<std::byte> bytes = std::move(p.data);
            Packet copy = p;
            p.data = std::move(bytes);
            copy.data = take_buffer(p.data.size());
            copy.data.assign(p.data.begin(), p.data.end());
            copy.copy = 1;
            bool r2 = false;
            copy.arrival_us = t + one_way_delay(l, r2);
            push_in_flight(std::move(copy));
        }
        push_in_flight(std::move(p));
    }

    // The link lost a reliable packet max_attempts times: both ends time out.
    void give_up(const Packet& p, std::int64_t t)
    {
        Packet a;
        a.kind = PacketKind::Timeout;
        a.arrival_us = t;
        a.from = p.from;
        a.to = p.from;
        a.to_handle = p.from_handle;
        push_in_flight(a);
        Packet b = a;
        b.to = p.to;
        b.to_handle = p.to_handle;
        b.copy = 1;
        if (p.to_handle != 0)
            push_in_flight(b);
    }

    void close(int ep, std::uint32_t handle, DisconnectReason reason)
    {
        Endpoint& e = endpoints[static_cast<std::size_t>(ep)];
        if (e.connections.erase(handle) == 0)
            return;
        TransportEvent ev;
        ev.kind = TransportEvent::Kind::Disconnected;
        ev.peer = PeerHandle{handle};
        ev.reason = reason;
        e.events.push_back(std::move(ev));
    }

    // Hands a reliable packet to the connection, releasing any that now come in order. The
    // connection is looked up again each time: a Disconnect released here erases it. `p` is
    // moved from unless it is a duplicate (or its connection is gone).
    void accept_reliable(int ep, std::uint32_t handle, Packet& p)
    {
        Endpoint& e = endpoints[static_cast<std::size_t>(ep)];
        const auto channel = static_cast<std::size_t>(p.channel);
        {
            auto it = e.connections.find(handle);
            if (it == e.connections.end())
                return;
            ChannelState& ch = it->second.channels[channel];
            if (p.seq < ch.next_reliable_recv || ch.held.count(p.seq) != 0)
                return;  // a duplicate
            const std::uint32_t seq = p.seq;
            if (spare_nodes.empty())
            {
                ch.held.emplace(seq, std::move(p));
            }
            else
            {
                HeldPackets::node_type node = std::move(spare_nodes.back());
                spare_nodes.pop_back();
                node.key() = seq;
                node.mapped() = std::move(p);
                ch.held.insert(std::move(node));
            }
        }
        while (true)
        {
            auto it = e.connections.find(handle);
            if (it == e.connections.end())
                return;
            ChannelState& ch = it->second.channels[channel];
            auto h = ch.held.find(ch.next_reliable_recv);
            if (h == ch.held.end())
                return;
            HeldPackets::node_type node = ch.held.extract(h);
            Packet q = std::move(node.mapped());
            spare_nodes.push_back(std::move(node));
            ++ch.next_reliable_recv;
            handle_in_order(ep, handle, q);
            recycle(q.data);
        }
    }

    // The initiator learns that its connection is accepted from the first packet the acceptor
    // sends (the Accept itself, or data that overtook it), as ENet does.
    void mark_connected(Endpoint& e, Connection& c, std::uint32_t handle, std::uint32_t remote)
    {
        if (c.connected)
            return;
        c.connected = true;
        c.remote_handle = remote;
        TransportEvent ev;
        ev.kind = TransportEvent::Kind::Connected;
        ev.peer = PeerHandle{handle};
        e.events.push_back(std::move(ev));
    }

    void handle_in_order(int ep, std::uint32_t handle, Packet& q)
    {
        Endpoint& e = endpoints[static_cast<std::size_t>(ep)];
        auto it = e.connections.find(handle);
        if (it == e.connections.end())
            return;
        Connection& c = it->second;
        if (q.kind == PacketKind::Accept)
        {
            mark_connected(e, c, handle, q.from_handle);
        }
        else if (q.kind == PacketKind::Disconnect)
        {
            close(ep, handle, q.reason);
        }
        else if (c.connected)
        {
            deliver(e, c, handle, q);
        }
    }

    // Queues `q`'s bytes (its buffer, moved) as a Received event.
    void deliver(Endpoint& e, Connection& c, std::uint32_t handle, Packet& q)
    {
        c.stats.bytes_received += q.data.size();
        ++c.stats.packets_received;
        ++totals.delivered;
        TransportEvent ev;
        ev.kind = TransportEvent::Kind::Received;
        ev.peer = PeerHandle{handle};
        ev.channel = q.channel;
        ev.data = std::move(q.data);
        e.events.push_back(std::move(ev));
    }

    // `p` is moved from if delivered or held; its caller recycles what is left.
    void arrive(Packet& p)
    {
        const int ep = p.to;
        Endpoint& e = endpoints[static_cast<std::size_t>(ep)];
        switch (p.kind)
        {
        case PacketKind::Timeout: close(ep, p.to_handle, DisconnectReason::TimedOut); return;
        case PacketKind::Connect:
        {
            if (!e.open)
                return;
            // A duplicated Connect must not open a second connection.
            for (const auto& [h, c] : e.connections)
                if (c.remote == p.from && c.remote_handle == p.from_handle)
                    return;
            const std::uint32_t handle = e.next_handle++;
            Connection c;
            c.remote = p.from;
            c.remote_handle = p.from_handle;
            c.connected = true;
            e.connections.emplace(handle, c);
            TransportEvent ev;
            ev.kind = TransportEvent::Kind::Connected;
            ev.peer = PeerHandle{handle};
            e.events.push_back(std::move(ev));
            send_control(ep, handle, PacketKind::Accept, DisconnectReason::None);
            return;
        }
        case PacketKind::Accept:
        case PacketKind::Disconnect:
        case PacketKind::Data: break;
        }
        const auto to = p.to_handle;
        auto it = e.connections.find(to);
        if (it == e.connections.end())
            return;
        Connection& c = it->second;
        mark_connected(e, c, to, p.from_handle);
        if (p.kind != PacketKind::Data)
        {
            accept_reliable(ep, to, p);
            return;
        }
        ChannelState& ch = c.channels[static_cast<std::size_t>(p.channel)];
        switch (p.delivery)
        {
        case Delivery::Reliable: accept_reliable(ep, to, p); return;
        case Delivery::Unreliable:
            if (!c.connected || p.seq <= ch.last_unreliable_recv)
            {
                ++totals.dropped_stale;
                return;
            }
            ch.last_unreliable_recv = p.seq;
            deliver(e, c, to, p);
            return;
        case Delivery::Unsequenced:
            if (c.connected)
                deliver(e, c, to, p);
            return;
        }
    }

    // Accept and Disconnect: reliable packets on channel 0 of an existing connection.
    void send_control(int ep, std::uint32_t handle, PacketKind kind, DisconnectReason reason)
    {
        Endpoint& e = endpoints[static_cast<std::size_t>(ep)];
        Connection& c = e.connections.at(handle);
        Packet p;
        p.kind = kind;
        p.from = ep;
        p.to = c.remote;
        p.from_handle = handle;
        p.to_handle = c.remote_handle;
        p.channel = Channel::Control;
        p.delivery = Delivery::Reliable;
        p.seq = c.channels[0].next_reliable_send++;
        p.reason = reason;
        transmit(std::move(p));
    }

    void deliver_due()
    {
        while (!in_flight.empty() && in_flight.front().arrival_us <= now)
        {
            Packet p = pop_in_flight();
            arrive(p);
            recycle(p.data);  // neither delivered nor held: stale, a duplicate, or no connection
        }
    }
};

namespace
{

class SimulatedTransport final : public Transport
{
public:
    SimulatedTransport(SimulatedNetwork::Impl& net, int id) : net_(net), id_(id) {}
    ~SimulatedTransport() override
    {
        const std::lock_guard lock(net_.mutex);
        Endpoint& e = self();
        // Leaving without a word: the remote ends will see the link time out.
        std::vector<std::uint32_t> handles;
        for (const auto& [h, c] : e.connections)
            handles.push_back(h);
        for (std::uint32_t h : handles)
        {
            const Connection& c = e.connections.at(h);
            if (c.remote_handle != 0)
            {
                Packet t;
                t.kind = PacketKind::Timeout;
                t.from = id_;
                t.to = c.remote;
                t.to_handle = c.remote_handle;
                t.arrival_us = net_.now + to_us(net_.settings.connect_timeout_s);
                net_.push_in_flight(t);
            }
        }
        e.connections.clear();
        e.events.clear();
        e.open = false;
    }

    core::Result<Address> open(const Address& bind) noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        Endpoint& e = self();
        if (e.open)
            return core::fail(core::ErrorCode::NetworkError,
                              "SimulatedTransport::open: already open");
        Address a;
        a.ipv4 = {10, 0, 0, static_cast<std::uint8_t>(id_ & 0xFF)};
        a.port = bind.port != 0 ? bind.port : static_cast<std::uint16_t>(40000 + id_);
        if (net_.endpoint_at(a) != 0)
            return core::fail(core::ErrorCode::NetworkError,
                              "SimulatedTransport::open: address in use: " + to_string(a));
        e.address = a;
        e.open = true;
        return a;
    }

    core::Result<PeerHandle> connect(const Address& remote) noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        Endpoint& e = self();
        if (!e.open)
            return core::fail(core::ErrorCode::NetworkError,
                              "SimulatedTransport::connect: not open");
        const std::uint32_t handle = e.next_handle++;
        Connection c;
        const int target = net_.endpoint_at(remote);
        c.remote = target;
        e.connections.emplace(handle, c);
        if (target == 0)
        {
            Packet t;
            t.kind = PacketKind::Timeout;
            t.from = id_;
            t.to = id_;
            t.to_handle = handle;
            t.arrival_us = net_.now + to_us(net_.settings.connect_timeout_s);
            net_.push_in_flight(t);
            return PeerHandle{handle};
        }
        Packet p;
        p.kind = PacketKind::Connect;
        p.from = id_;
        p.to = target;
        p.from_handle = handle;
        p.delivery = Delivery::Reliable;
        net_.transmit(std::move(p));
        return PeerHandle{handle};
    }

    core::Result<void> send(PeerHandle peer, Channel channel, std::span<const std::byte> bytes,
                            Delivery delivery) noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        Endpoint& e = self();
        auto it = e.connections.find(peer.value);
        if (it == e.connections.end() || !it->second.connected)
            return core::fail(
                core::ErrorCode::NetworkError,
                "SimulatedTransport::send: no connected peer " + std::to_string(peer.value));
        if (bytes.size() > k_max_packet)
            return core::fail(core::ErrorCode::NetworkError,
                              "SimulatedTransport::send: packet over 32 MiB");
        Connection& c = it->second;
        ChannelState& ch = c.channels[static_cast<std::size_t>(channel)];
        Packet p;
        p.kind = PacketKind::Data;
        p.from = id_;
        p.to = c.remote;
        p.from_handle = peer.value;
        p.to_handle = c.remote_handle;
        p.channel = channel;
        p.delivery = delivery;
        if (delivery == Delivery::Reliable)
            p.seq = ch.next_reliable_send++;
        else if (delivery == Delivery::Unreliable)
            p.seq = ch.next_unreliable_send++;
        p.data = net_.take_buffer(bytes.size());
        p.data.assign(bytes.begin(), bytes.end());
        c.stats.bytes_sent += bytes.size();
        ++c.stats.packets_sent;
        net_.transmit(std::move(p));
        return {};
    }

    std::optional<TransportEvent> poll(int /*timeout_ms*/) noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        net_.deliver_due();
        Endpoint& e = self();
        if (e.events.empty())
            return std::nullopt;
        TransportEvent ev = std::move(e.events.front());
        e.events.pop_front();
        return ev;
    }

    /// As poll(), with the datagram's buffer swapped into `out.data` and `out`'s previous buffer
    /// kept by the network for a later send: nothing is allocated.
    bool poll_into(TransportEvent& out, int /*timeout_ms*/) noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        net_.deliver_due();
        Endpoint& e = self();
        if (e.events.empty())
            return false;
        TransportEvent& ev = e.events.front();
        swap_into(out, ev);
        net_.recycle(ev.data);
        e.events.pop_front();
        return true;
    }

    void flush() noexcept override {}

    void disconnect(PeerHandle peer, DisconnectReason reason) noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        Endpoint& e = self();
        auto it = e.connections.find(peer.value);
        if (it == e.connections.end())
            return;
        if (it->second.connected && it->second.remote_handle != 0)
            net_.send_control(id_, peer.value, PacketKind::Disconnect, reason);
        net_.close(id_, peer.value, reason);
    }

    std::optional<PeerStats> stats(PeerHandle peer) const noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        const Endpoint& e = net_.endpoints[static_cast<std::size_t>(id_)];
        auto it = e.connections.find(peer.value);
        if (it == e.connections.end())
            return std::nullopt;
        PeerStats s = it->second.stats;
        const LinkSettings& out = net_.link(id_, it->second.remote).settings;
        const LinkSettings& in = net_.link(it->second.remote, id_).settings;
        s.rtt_s = out.latency_s + in.latency_s + 0.5 * (out.jitter_s + in.jitter_s);
        return s;
    }

    std::optional<Address> remote_address(PeerHandle peer) const noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        const Endpoint& e = net_.endpoints[static_cast<std::size_t>(id_)];
        auto it = e.connections.find(peer.value);
        if (it == e.connections.end() || it->second.remote == 0)
            return std::nullopt;
        return net_.endpoints[static_cast<std::size_t>(it->second.remote)].address;
    }

    void report_bad_datagram(PeerHandle peer) noexcept override
    {
        const std::lock_guard lock(net_.mutex);
        Endpoint& e = self();
        auto it = e.connections.find(peer.value);
        if (it != e.connections.end())
            ++it->second.stats.bad_datagrams;
    }

    void live_peers(std::vector<PeerHandle>& out) const override
    {
        const std::lock_guard lock(net_.mutex);
        out.clear();
        for (const auto& [h, c] : net_.endpoints[static_cast<std::size_t>(id_)].connections)
            if (c.connected)
                out.push_back(PeerHandle{h});
    }

private:
    static constexpr std::size_t k_max_packet = std::size_t{32} << 20;

    Endpoint& self() { return net_.endpoints[static_cast<std::size_t>(id_)]; }

    SimulatedNetwork::Impl& net_;
    int id_;
};

}  // namespace

SimulatedNetwork::SimulatedNetwork(const SimulatedNetworkSettings& settings)
    : impl_(std::make_unique<Impl>(settings))
{
    const LinkSettings& l = settings.link;
    PLIANT_ASSERT(l.loss >= 0.0 && l.loss < 1.0 && l.duplicate >= 0.0 && l.duplicate <= 1.0 &&
                      l.reorder >= 0.0 && l.reorder <= 1.0,
                  "SimulatedNetwork: probability out of range");
    PLIANT_ASSERT(l.latency_s >= 0.0 && l.jitter_s >= 0.0 && l.reorder_delay_s >= 0.0,
                  "SimulatedNetwork: negative time");
    PLIANT_ASSERT(settings.max_attempts >= 1, "SimulatedNetwork: max_attempts < 1");
}

SimulatedNetwork::~SimulatedNetwork() = default;

std::unique_ptr<Transport> SimulatedNetwork::create_endpoint()
{
    const std::lock_guard lock(impl_->mutex);
    impl_->endpoints.emplace_back();
    return std::make_unique<SimulatedTransport>(*impl_,
                                                static_cast<int>(impl_->endpoints.size() - 1));
}

void SimulatedNetwork::set_link(const Address& from, const Address& to, const LinkSettings& link)
{
    const std::lock_guard lock(impl_->mutex);
    const int a = impl_->endpoint_at(from);
    const int b = impl_->endpoint_at(to);
    PLIANT_ASSERT(a != 0 && b != 0, "SimulatedNetwork::set_link: address not open");
    PLIANT_ASSERT(link.loss >= 0.0 && link.loss < 1.0, "SimulatedNetwork::set_link: loss");
    impl_->link(a, b).settings = link;
}

void SimulatedNetwork::suspend(const Address& a)
{
    const std::lock_guard lock(impl_->mutex);
    const int ep = impl_->endpoint_at(a);
    PLIANT_ASSERT(ep != 0, "SimulatedNetwork::suspend: address not open");
    const std::int64_t at = impl_->now + to_us(impl_->settings.connect_timeout_s);
    for (const auto& [h, c] : impl_->endpoints[static_cast<std::size_t>(ep)].connections)
    {
        Packet own;
        own.kind = PacketKind::Timeout;
        own.arrival_us = at;
        own.from = c.remote;
        own.to = ep;
        own.to_handle = h;
        impl_->push_in_flight(own);
        if (c.remote_handle != 0)
        {
            Packet far = own;
            far.from = ep;
            far.to = c.remote;
            far.to_handle = c.remote_handle;
            impl_->push_in_flight(far);
        }
    }
}

void SimulatedNetwork::advance(double seconds)
{
    PLIANT_ASSERT(seconds >= 0.0, "SimulatedNetwork::advance: negative time");
    const std::lock_guard lock(impl_->mutex);
    impl_->now += to_us(seconds);
}

void SimulatedNetwork::deliver_due()
{
    const std::lock_guard lock(impl_->mutex);
    impl_->deliver_due();
}

bool SimulatedNetwork::advance_to_next_arrival()
{
    const std::lock_guard lock(impl_->mutex);
    if (impl_->in_flight.empty())
        return false;
    impl_->now = std::max(impl_->now, impl_->in_flight.front().arrival_us);
    return true;
}

std::int64_t SimulatedNetwork::now_us() const
{
    const std::lock_guard lock(impl_->mutex);
    return impl_->now;
}

SimulatedTotals SimulatedNetwork::totals() const
{
    const std::lock_guard lock(impl_->mutex);
    return impl_->totals;
}

}  // namespace pliant::net
