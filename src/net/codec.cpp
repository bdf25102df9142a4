// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The codec of docs/protocol.md. Each message type has three functions kept side by side so that
// a layout change touches one place: body_size (bytes), write_body and read_body. The semantic
// rules live in check_* and run on both sides (see codec.h).

#include <pliant/net/codec.h>
#include <pliant/net/quantised.h>

#include "net/byte_io_internal.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cfloat>
#include <cmath>
#include <type_traits>

namespace pliant::net
{
namespace
{

using detail::ByteReader;
using detail::ByteWriter;
using detail::is_finite_bits;
using Err = std::optional<DecodeError>;

constexpr std::size_t k_peer_info_fixed = 24;
constexpr std::size_t k_target_size = 40;
constexpr std::size_t k_force_size = 64;
constexpr std::size_t k_range_size = 8;
constexpr std::size_t k_ack_fixed = 12;
constexpr std::size_t k_halo_fixed = 16;

std::size_t value_size(ValueEncoding e) noexcept
{
    return e == ValueEncoding::F32 ? 4 : 8;
}

/// f32 or f64 (Halo); LeafState also takes 3, quantised delta.
bool valid_encoding(std::uint8_t e) noexcept
{
    return e == 1 || e == 2;
}
bool valid_leaf_encoding(std::uint8_t e) noexcept
{
    return e >= 1 && e <= 3;
}
bool valid_exponent(int e) noexcept
{
    return e >= k_min_step_exponent && e <= k_max_step_exponent;
}
bool valid_role(std::uint8_t r) noexcept
{
    return r == 1 || r == 2;
}
bool valid_reason(std::uint8_t r) noexcept
{
    return r >= 1 && r <= k_max_disconnect_reason;
}

std::size_t max_leaf_nodes(ValueEncoding e) noexcept
{
    if (e == ValueEncoding::QuantisedDelta)
        return k_max_leaf_nodes_quantised;
    return e == ValueEncoding::F32 ? k_max_leaf_nodes_f32 : k_max_leaf_nodes_f64;
}

// ---- semantic checks (shared by encode and decode) -------------------------------------------

Err check_value(double x, ValueEncoding e) noexcept
{
    if (!is_finite_bits(x))
        return DecodeError::NonFinite;
    // Only an encoder can meet this: a decoded f32 is always in range.
    if (e == ValueEncoding::F32 && std::fabs(x) > static_cast<double>(FLT_MAX))
        return DecodeError::NonFinite;
    return {};
}

Err check_values(const std::vector<double>& values, ValueEncoding e) noexcept
{
    // A branch-free pass over every value first (it vectorises: every value of a leaf state or
    // halo is checked by its encoder and its decoder), the first offender's error only if one
    // fails. On the bits, so that a NaN raises no floating-point exception: |x|'s bits order as
    // |x| does, and NaNs and infinities lie above the largest finite value's.
    const std::uint64_t limit = std::bit_cast<std::uint64_t>(
        e == ValueEncoding::F32 ? static_cast<double>(FLT_MAX) : DBL_MAX);
    unsigned bad = 0;
    for (const double x : values)
        bad |= (std::bit_cast<std::uint64_t>(x) & 0x7FFF'FFFF'FFFF'FFFFu) > limit ? 1u : 0u;
    if (bad == 0)
        return {};
    for (double x : values)
        if (auto err = check_value(x, e))
            return err;
    return {};
}

Err check_time(double t) noexcept
{
    if (!is_finite_bits(t))
        return DecodeError::NonFinite;
    if (t < 0.0)
        return DecodeError::BadRange;
    return {};
}

Err check_name(const std::string& name) noexcept
{
    if (!is_valid_name(name))
        return DecodeError::BadName;
    return {};
}

Err check_peer_info(const PeerInfo& p) noexcept
{
    if (p.id == k_no_peer)
        return DecodeError::BadRange;
    if (!valid_role(static_cast<std::uint8_t>(p.role)))
        return DecodeError::BadEnum;
    if (p.port == 0)
        return DecodeError::BadRange;
    return check_name(p.name);
}

Err check_leaf(const WireLeafId& leaf) noexcept
{
    if (leaf.square > 1 || leaf.depth > k_max_grid_level)
        return DecodeError::BadRange;
    const std::uint32_t side = 1u << leaf.depth;
    if (leaf.ix >= side || leaf.iy >= side)
        return DecodeError::BadRange;
    return {};
}

Err check_target(const Target& t) noexcept
{
    const auto kind = static_cast<std::uint8_t>(t.kind);
    if (kind != 1 && kind != 2)
        return DecodeError::BadEnum;
    for (double x : t.position)
        if (!is_finite_bits(x))
            return DecodeError::NonFinite;
    if (!is_finite_bits(t.radius))
        return DecodeError::NonFinite;
    if (t.kind == TargetKind::Face)
    {
        if (t.face >= k_max_face_index)
            return DecodeError::BadRange;
        for (double x : t.position)
            if (x != 0.0)
                return DecodeError::BadRange;
    }
    else if (t.face != 0)
    {
        return DecodeError::BadRange;
    }
    if (t.radius < 0.0)
        return DecodeError::BadRange;
    return {};
}

Err check(const Hello& m) noexcept
{
    if (!valid_role(static_cast<std::uint8_t>(m.role)))
        return DecodeError::BadEnum;
    return check_name(m.name);
}

Err check(const Welcome& m) noexcept
{
    if (m.peers.empty() || m.peers.size() > k_max_welcome_peers)
        return DecodeError::BadCount;
    if (m.grid_level < 1 || m.grid_level > k_max_grid_level)
        return DecodeError::BadRange;
    if (m.leaf_depth > std::min<int>(m.grid_level, k_max_partition_depth))
        return DecodeError::BadRange;
    if (auto err = check_time(m.time))
        return err;
    if (m.model_size < 1 || m.model_size > k_max_blob_size || m.state_size > k_max_blob_size)
        return DecodeError::BadRange;
    bool has_you = false;
    bool has_master = false;
    for (std::size_t i = 0; i < m.peers.size(); ++i)
    {
        if (auto err = check_peer_info(m.peers[i]))
            return err;
        for (std::size_t j = 0; j < i; ++j)
            if (m.peers[j].id == m.peers[i].id)
                return DecodeError::Duplicate;
        has_you = has_you || m.peers[i].id == m.your_id;
        has_master = has_master || m.peers[i].id == m.master_id;
    }
    if (m.your_id == k_no_peer || !has_you || !has_master)
        return DecodeError::BadRange;
    return {};
}

Err check(const Reject& m) noexcept
{
    return valid_reason(static_cast<std::uint8_t>(m.reason)) ? Err{} : DecodeError::BadEnum;
}

Err check(const PeerJoined& m) noexcept
{
    return check_peer_info(m.peer);
}

Err check(const PeerLeft& m) noexcept
{
    if (m.peer == k_no_peer)
        return DecodeError::BadRange;
    return valid_reason(static_cast<std::uint8_t>(m.reason)) ? Err{} : DecodeError::BadEnum;
}

Err check(const Blob& m) noexcept
{
    const auto kind = static_cast<std::uint8_t>(m.kind);
    if (kind != 1 && kind != 2)
        return DecodeError::BadEnum;
    if (m.data.empty() || m.data.size() > k_max_blob_chunk)
        return DecodeError::BadCount;
    if (m.total_size > k_max_blob_size ||
        std::uint64_t{m.offset} + m.data.size() > std::uint64_t{m.total_size})
        return DecodeError::BadRange;
    return {};
}

Err check(const PointsOfInterest& m) noexcept
{
    if (m.points.size() > k_max_points)
        return DecodeError::BadCount;
    for (const Target& t : m.points)
        if (auto err = check_target(t))
            return err;
    return {};
}

Err check(const Partition& m) noexcept
{
    if (m.epoch == 0 || m.leaf_depth > k_max_partition_depth)
        return DecodeError::BadRange;
    if (m.owners.size() != (std::size_t{2} << (2 * m.leaf_depth)))
        return DecodeError::BadCount;
    for (PeerId p : m.owners)
        if (p == k_no_peer)
            return DecodeError::BadRange;
    return {};
}

Err check(const Force& m) noexcept
{
    if (m.forces.size() > k_max_points)
        return DecodeError::BadCount;
    for (const UserForce& f : m.forces)
    {
        if (auto err = check_target(f.target))
            return err;
        for (double x : f.force)
            if (!is_finite_bits(x))
                return DecodeError::NonFinite;
    }
    return {};
}

Err check(const Leave& m) noexcept
{
    return valid_reason(static_cast<std::uint8_t>(m.reason)) ? Err{} : DecodeError::BadEnum;
}

Err check_quantised(const LeafState& m) noexcept
{
    const QuantisedDelta& q = m.quantised;
    if (!m.u.empty() || !m.v.empty())
        return DecodeError::BadCount;
    if (q.du.empty() || q.du.size() != q.dv.size() || q.du.size() > k_max_leaf_nodes_quantised)
        return DecodeError::BadCount;
    if (q.packed.empty() || q.packed.size() > k_max_packed_residuals)
        return DecodeError::BadCount;
    if (std::size_t{m.node_offset} + q.du.size() > 0xFFFFu)
        return DecodeError::BadRange;
    if (!valid_exponent(q.u_exponent) || !valid_exponent(q.v_exponent))
        return DecodeError::BadRange;
    if (q.extrapolated && q.baseline == 0)
        return DecodeError::BadRange;
    return check_time(m.time);
}

/// Encoder side of encoding 3: `packed` must unpack to exactly `du` and `dv` (the decoder
/// unpacks while reading, so it needs no second pass).
Err check_packed(const QuantisedDelta& q) noexcept
{
    std::array<std::int32_t, k_max_leaf_nodes_quantised> du{};
    std::array<std::int32_t, k_max_leaf_nodes_quantised> dv{};
    const std::size_t n = q.du.size();
    if (auto err =
            unpack_residuals(q.packing, q.packed, std::span(du.data(), n), std::span(dv.data(), n)))
        return err;
    if (!std::equal(q.du.begin(), q.du.end(), du.begin()) ||
        !std::equal(q.dv.begin(), q.dv.end(), dv.begin()))
        return DecodeError::BadCompression;
    return {};
}

Err check(const LeafState& m) noexcept
{
    if (auto err = check_leaf(m.leaf))
        return err;
    if (!valid_leaf_encoding(static_cast<std::uint8_t>(m.encoding)))
        return DecodeError::BadEnum;
    if (m.coarsen > k_max_leaf_coarsen ||
        (m.coarsen != 0 && m.encoding == ValueEncoding::QuantisedDelta))
        return DecodeError::BadRange;
    if (m.encoding == ValueEncoding::QuantisedDelta)
        return check_quantised(m);
    if (m.quantised != QuantisedDelta{})
        return DecodeError::BadCount;
    if (m.u.empty() || m.u.size() != m.v.size() || m.u.size() > max_leaf_nodes(m.encoding))
        return DecodeError::BadCount;
    if (std::size_t{m.node_offset} + m.u.size() > 0xFFFFu)
        return DecodeError::BadRange;
    if (auto err = check_time(m.time))
        return err;
    if (auto err = check_values(m.u, m.encoding))
        return err;
    return check_values(m.v, m.encoding);
}

std::size_t halo_nodes(const std::vector<NodeRange>& ranges) noexcept
{
    std::size_t n = 0;
    for (const NodeRange& r : ranges)
        n += r.count;
    return n;
}

Err check(const Halo& m) noexcept
{
    if (m.stage > k_max_halo_stage)
        return DecodeError::BadRange;
    if (!valid_encoding(static_cast<std::uint8_t>(m.encoding)) || (!m.has_u && !m.has_v))
        return DecodeError::BadEnum;
    if (m.ranges.empty() || m.ranges.size() > k_max_halo_ranges)
        return DecodeError::BadCount;
    std::uint64_t next_free = 0;
    for (const NodeRange& r : m.ranges)
    {
        if (r.count == 0 || r.first < next_free ||
            std::uint64_t{r.first} + r.count > k_max_grid_nodes)
            return DecodeError::BadRange;
        next_free = std::uint64_t{r.first} + r.count;
    }
    const std::size_t n = halo_nodes(m.ranges);
    const std::size_t fields = (m.has_u ? 1u : 0u) + (m.has_v ? 1u : 0u);
    if (k_halo_fixed + k_range_size * m.ranges.size() + fields * n * value_size(m.encoding) >
        k_max_state_payload)
        return DecodeError::BadCount;
    if (m.u.size() != (m.has_u ? n : 0) || m.v.size() != (m.has_v ? n : 0))
        return DecodeError::BadCount;
    if (auto err = check_time(m.time))
        return err;
    if (auto err = check_values(m.u, m.encoding))
        return err;
    return check_values(m.v, m.encoding);
}

Err check(const Heartbeat&) noexcept
{
    return {};
}
Err check(const Ready&) noexcept
{
    return {};
}
Err check(const Ping&) noexcept
{
    return {};
}
Err check(const Pong&) noexcept
{
    return {};
}

Err check(const Ack& m) noexcept
{
    if (m.acks.empty() || m.acks.size() > k_max_acks)
        return DecodeError::BadCount;
    const std::uint8_t depth = m.acks.front().leaf.depth;
    if (depth > k_max_partition_depth)
        return DecodeError::BadRange;
    for (const LeafAck& a : m.acks)
    {
        if (auto err = check_leaf(a.leaf))
            return err;
        if (a.leaf.depth != depth)
            return DecodeError::BadRange;
    }
    return {};
}

std::size_t body_size(const LeafBatch& m) noexcept;

Err check(const LeafBatch& m) noexcept
{
    if (m.leaves.empty() || m.leaves.size() > k_max_batch_leaves)
        return DecodeError::BadCount;
    if (!valid_exponent(m.u_exponent) || !valid_exponent(m.v_exponent))
        return DecodeError::BadRange;
    const std::uint8_t depth = m.leaves.front().leaf.depth;
    if (depth > k_max_partition_depth)
        return DecodeError::BadRange;
    for (const BatchLeaf& l : m.leaves)
    {
        const QuantisedDelta& q = l.quantised;
        if (auto err = check_leaf(l.leaf))
            return err;
        if (l.leaf.depth != depth)
            return DecodeError::BadRange;
        if (q.du.empty() || q.du.size() != q.dv.size() || q.du.size() > k_max_leaf_nodes_quantised)
            return DecodeError::BadCount;
        if (q.packed.empty() || q.packed.size() > k_max_packed_residuals)
            return DecodeError::BadCount;
        if (q.u_exponent != m.u_exponent || q.v_exponent != m.v_exponent)
            return DecodeError::BadRange;
        if (q.extrapolated && q.baseline == 0)
            return DecodeError::BadRange;
    }
    if (body_size(m) > k_max_state_payload)
        return DecodeError::BadCount;
    return check_time(m.time);
}

std::size_t body_size(const ValueBatch& m) noexcept;

Err check(const ValueBatch& m) noexcept
{
    if (m.leaves.empty() || m.leaves.size() > k_max_batch_leaves)
        return DecodeError::BadCount;
    if (!valid_encoding(static_cast<std::uint8_t>(m.encoding)))
        return DecodeError::BadEnum;
    if (m.coarsen > k_max_leaf_coarsen)
        return DecodeError::BadRange;
    const std::uint8_t depth = m.leaves.front().leaf.depth;
    if (depth > k_max_partition_depth)
        return DecodeError::BadRange;
    for (const ValueLeaf& l : m.leaves)
    {
        if (auto err = check_leaf(l.leaf))
            return err;
        if (l.leaf.depth != depth)
            return DecodeError::BadRange;
        if (l.u.empty() || l.u.size() != l.v.size() || l.u.size() > max_leaf_nodes(m.encoding))
            return DecodeError::BadCount;
        if (auto err = check_values(l.u, m.encoding))
            return err;
        if (auto err = check_values(l.v, m.encoding))
            return err;
    }
    if (body_size(m) > k_max_state_payload)
        return DecodeError::BadCount;
    return check_time(m.time);
}

Err check_header(const Header& h, MessageType type) noexcept
{
    if (h.session == 0 && type != MessageType::Hello && type != MessageType::Reject)
        return DecodeError::BadSession;
    if (h.sender == k_no_peer && type != MessageType::Hello)
        return DecodeError::BadSender;
    return {};
}

// ---- sizes -----------------------------------------------------------------------------------

std::size_t peer_info_size(const PeerInfo& p) noexcept
{
    return k_peer_info_fixed + p.name.size();
}

std::size_t body_size(const Hello& m) noexcept
{
    return 4 + m.name.size();
}
std::size_t body_size(const Welcome& m) noexcept
{
    std::size_t n = 44;
    for (const PeerInfo& p : m.peers)
        n += peer_info_size(p);
    return n;
}
std::size_t body_size(const Reject&) noexcept
{
    return 4;
}
std::size_t body_size(const PeerJoined& m) noexcept
{
    return peer_info_size(m.peer);
}
std::size_t body_size(const PeerLeft&) noexcept
{
    return 4;
}
std::size_t body_size(const Blob& m) noexcept
{
    return 12 + m.data.size();
}
std::size_t body_size(const PointsOfInterest& m) noexcept
{
    return 4 + k_target_size * m.points.size();
}
std::size_t body_size(const Partition& m) noexcept
{
    return 8 + 2 * m.owners.size();
}
std::size_t body_size(const Force& m) noexcept
{
    return 4 + k_force_size * m.forces.size();
}
std::size_t body_size(const Leave&) noexcept
{
    return 4;
}
std::size_t body_size(const LeafState& m) noexcept
{
    if (m.encoding == ValueEncoding::QuantisedDelta)
        return k_leaf_state_quantised_fixed + m.quantised.packed.size();
    return k_leaf_state_fixed + (m.u.size() + m.v.size()) * value_size(m.encoding);
}
std::size_t body_size(const Halo& m) noexcept
{
    return k_halo_fixed + k_range_size * m.ranges.size() +
           (m.u.size() + m.v.size()) * value_size(m.encoding);
}
std::size_t body_size(const Heartbeat&) noexcept
{
    return 4;
}
std::size_t body_size(const Ready&) noexcept
{
    return 0;
}
std::size_t body_size(const Ping&) noexcept
{
    return 16;
}
std::size_t body_size(const Pong&) noexcept
{
    return 16;
}
std::size_t varint_size(std::uint64_t v) noexcept;
std::uint64_t newest_tick(const Ack& m) noexcept
{
    std::uint64_t t = 0;
    for (const LeafAck& a : m.acks)
        t = std::max(t, a.tick);
    return t;
}
std::size_t body_size(const Ack& m) noexcept
{
    const std::uint64_t newest = newest_tick(m);
    std::size_t n = k_ack_fixed;
    for (const LeafAck& a : m.acks)
        n += 2 + varint_size(newest - a.tick);
    return n;
}
std::size_t varint_size(std::uint64_t v) noexcept
{
    std::size_t n = 1;
    while (v >= 0x80u)
    {
        v >>= 7;
        ++n;
    }
    return n;
}
std::size_t body_size(const LeafBatch& m) noexcept
{
    std::size_t n = k_leaf_batch_fixed;
    for (const BatchLeaf& l : m.leaves)
        n += batch_leaf_size(l);
    return n;
}
std::size_t body_size(const ValueBatch& m) noexcept
{
    std::size_t n = k_value_batch_fixed;
    for (const ValueLeaf& l : m.leaves)
        n += value_leaf_size(l, m.encoding);
    return n;
}

// ---- writers ---------------------------------------------------------------------------------

void write_name(ByteWriter& w, const std::string& name) noexcept
{
    w.bytes(reinterpret_cast<const std::byte*>(name.data()), name.size());
}

void write_peer_info(ByteWriter& w, const PeerInfo& p) noexcept
{
    w.u16(p.id.value);
    w.u8(static_cast<std::uint8_t>(p.role));
    w.u8(4);
    for (std::uint8_t b : p.ipv4)
        w.u8(b);
    w.zeros(12);
    w.u16(p.port);
    w.u8(static_cast<std::uint8_t>(p.name.size()));
    w.u8(0);
    write_name(w, p.name);
}

void write_leaf(ByteWriter& w, const WireLeafId& l) noexcept
{
    w.u8(l.square);
    w.u8(l.depth);
    w.u16(l.ix);
    w.u16(l.iy);
}

void write_target(ByteWriter& w, const Target& t, std::uint16_t grab_id, bool is_force) noexcept
{
    w.u8(static_cast<std::uint8_t>(t.kind));
    if (is_force)
    {
        w.u8(0);
        w.u16(grab_id);
    }
    else
    {
        w.zeros(3);
    }
    w.u32(t.face);
    for (double x : t.position)
        w.f64(x);
    w.f64(t.radius);
}

void write_values(ByteWriter& w, const std::vector<double>& values, ValueEncoding e) noexcept
{
    if (e == ValueEncoding::F32)
        for (double x : values)
            w.f32(x);
    else
        w.f64s(values.data(), values.size());
}

void write_body(ByteWriter& w, const Hello& m) noexcept
{
    w.u8(static_cast<std::uint8_t>(m.role));
    w.u8(static_cast<std::uint8_t>(m.name.size()));
    w.u16(m.listen_port);
    write_name(w, m.name);
}
void write_body(ByteWriter& w, const Welcome& m) noexcept
{
    w.u16(m.your_id.value);
    w.u16(m.master_id.value);
    w.u8(m.grid_level);
    w.u8(m.leaf_depth);
    w.u8(static_cast<std::uint8_t>(m.peers.size()));
    w.u8(0);
    w.u32(m.epoch);
    w.f64(m.time);
    w.u32(m.model_size);
    w.u64(m.model_hash);
    w.u32(m.state_size);
    w.u64(m.state_hash);
    for (const PeerInfo& p : m.peers)
        write_peer_info(w, p);
}
void write_body(ByteWriter& w, const Reject& m) noexcept
{
    w.u8(static_cast<std::uint8_t>(m.reason));
    w.zeros(3);
}
void write_body(ByteWriter& w, const PeerJoined& m) noexcept
{
    write_peer_info(w, m.peer);
}
void write_body(ByteWriter& w, const PeerLeft& m) noexcept
{
    w.u16(m.peer.value);
    w.u8(static_cast<std::uint8_t>(m.reason));
    w.u8(0);
}
void write_body(ByteWriter& w, const Blob& m) noexcept
{
    w.u8(static_cast<std::uint8_t>(m.kind));
    w.u8(0);
    w.u16(static_cast<std::uint16_t>(m.data.size()));
    w.u32(m.total_size);
    w.u32(m.offset);
    w.bytes(m.data.data(), m.data.size());
}
void write_body(ByteWriter& w, const PointsOfInterest& m) noexcept
{
    w.u8(static_cast<std::uint8_t>(m.points.size()));
    w.zeros(3);
    for (const Target& t : m.points)
        write_target(w, t, 0, false);
}
void write_body(ByteWriter& w, const Partition& m) noexcept
{
    w.u32(m.epoch);
    w.u8(m.leaf_depth);
    w.zeros(3);
    for (PeerId p : m.owners)
        w.u16(p.value);
}
void write_body(ByteWriter& w, const Force& m) noexcept
{
    w.u8(static_cast<std::uint8_t>(m.forces.size()));
    w.zeros(3);
    for (const UserForce& f : m.forces)
    {
        write_target(w, f.target, f.grab_id, true);
        for (double x : f.force)
            w.f64(x);
    }
}
void write_body(ByteWriter& w, const Leave& m) noexcept
{
    w.u8(static_cast<std::uint8_t>(m.reason));
    w.zeros(3);
}
/// The u16 after a quantised delta's exponents: length c in bits 0..10, bits 11..12 reserved,
/// bit 13 Rice packing, bit 14 extrapolated, bit 15 predicted.
std::uint16_t packed_word(const QuantisedDelta& q) noexcept
{
    return static_cast<std::uint16_t>(q.packed.size() | (q.predicted ? 0x8000u : 0u) |
                                      (q.extrapolated ? 0x4000u : 0u) |
                                      (q.packing == Packing::Rice ? 0x2000u : 0u));
}

void write_body(ByteWriter& w, const LeafState& m) noexcept
{
    w.u32(m.epoch);
    write_leaf(w, m.leaf);
    w.u8(static_cast<std::uint8_t>(m.encoding));
    w.u8(m.coarsen);
    w.u16(m.node_offset);
    w.u16(static_cast<std::uint16_t>(m.node_count()));
    w.f64(m.time);
    if (m.encoding == ValueEncoding::QuantisedDelta)
    {
        const QuantisedDelta& q = m.quantised;
        w.u32(q.baseline);
        w.u8(static_cast<std::uint8_t>(q.u_exponent));
        w.u8(static_cast<std::uint8_t>(q.v_exponent));
        w.u16(packed_word(q));
        w.bytes(q.packed.data(), q.packed.size());
        return;
    }
    write_values(w, m.u, m.encoding);
    write_values(w, m.v, m.encoding);
}
void write_body(ByteWriter& w, const Halo& m) noexcept
{
    w.u32(m.epoch);
    w.u8(m.stage);
    w.u8(static_cast<std::uint8_t>(m.encoding));
    w.u8(static_cast<std::uint8_t>((m.has_u ? 1u : 0u) | (m.has_v ? 2u : 0u)));
    w.u8(static_cast<std::uint8_t>(m.ranges.size()));
    w.f64(m.time);
    for (const NodeRange& r : m.ranges)
    {
        w.u32(r.first);
        w.u16(r.count);
        w.u16(0);
    }
    write_values(w, m.u, m.encoding);
    write_values(w, m.v, m.encoding);
}
void write_body(ByteWriter& w, const Heartbeat& m) noexcept
{
    w.u32(m.epoch);
}
void write_body(ByteWriter&, const Ready&) noexcept {}
void write_body(ByteWriter& w, const Ping& m) noexcept
{
    w.u32(m.nonce);
    w.u32(0);
    w.u64(m.time_us);
}
void write_body(ByteWriter& w, const Pong& m) noexcept
{
    w.u32(m.nonce);
    w.u32(0);
    w.u64(m.time_us);
}
void write_varint(ByteWriter& w, std::uint64_t v) noexcept
{
    while (v >= 0x80u)
    {
        w.u8(static_cast<std::uint8_t>((v & 0x7Fu) | 0x80u));
        v >>= 7;
    }
    w.u8(static_cast<std::uint8_t>(v));
}
std::uint16_t leaf_index(const WireLeafId& l) noexcept
{
    const std::uint32_t side = 1u << l.depth;
    return static_cast<std::uint16_t>((l.square * side + l.iy) * side + l.ix);
}
void write_body(ByteWriter& w, const LeafBatch& m) noexcept
{
    w.u32(m.epoch);
    w.f64(m.time);
    w.u8(static_cast<std::uint8_t>(m.u_exponent));
    w.u8(static_cast<std::uint8_t>(m.v_exponent));
    w.u8(m.leaves.front().leaf.depth);
    w.u8(static_cast<std::uint8_t>(m.leaves.size()));
    for (const BatchLeaf& l : m.leaves)
    {
        const QuantisedDelta& q = l.quantised;
        w.u16(leaf_index(l.leaf));
        w.u8(static_cast<std::uint8_t>(q.du.size()));
        w.u16(packed_word(q));
        write_varint(w, q.baseline);
        w.bytes(q.packed.data(), q.packed.size());
    }
}
void write_body(ByteWriter& w, const ValueBatch& m) noexcept
{
    w.u32(m.epoch);
    w.f64(m.time);
    w.u8(static_cast<std::uint8_t>(m.encoding));
    w.u8(m.coarsen);
    w.u8(m.leaves.front().leaf.depth);
    w.u8(static_cast<std::uint8_t>(m.leaves.size()));
    for (const ValueLeaf& l : m.leaves)
    {
        w.u16(leaf_index(l.leaf));
        w.u8(static_cast<std::uint8_t>(l.u.size()));
        write_values(w, l.u, m.encoding);
        write_values(w, l.v, m.encoding);
    }
}
void write_body(ByteWriter& w, const Ack& m) noexcept
{
    const std::uint64_t newest = newest_tick(m);
    w.u8(static_cast<std::uint8_t>(m.acks.size()));
    w.u8(m.acks.front().leaf.depth);
    w.u16(0);
    w.u64(newest);
    for (const LeafAck& a : m.acks)
    {
        w.u16(leaf_index(a.leaf));
        write_varint(w, newest - a.tick);
    }
}

// ---- readers ---------------------------------------------------------------------------------
// Each returns an error found while reading the structure (reserved bytes, wire-only enums,
// counts that bound what follows); `r.short_read()` is tested by the caller afterwards.

Err read_name(ByteReader& r, std::string& name, std::size_t n) noexcept
{
    if (n > r.remaining())
    {
        r.skip(n);
        return {};
    }
    name.resize(n);
    r.bytes(reinterpret_cast<std::byte*>(name.data()), n);
    return {};
}

Err read_peer_info(ByteReader& r, PeerInfo& p) noexcept
{
    p.id = PeerId{r.u16()};
    p.role = static_cast<Role>(r.u8());
    const std::uint8_t family = r.u8();
    for (std::uint8_t& b : p.ipv4)
        b = r.u8();
    bool reserved_ok = true;
    for (int i = 0; i < 12; ++i)
        reserved_ok = (r.u8() == 0) && reserved_ok;
    p.port = r.u16();
    const std::uint8_t name_length = r.u8();
    const std::uint8_t reserved = r.u8();
    if (r.short_read())
        return {};
    if (family != 4)
        return DecodeError::BadEnum;
    if (!reserved_ok || reserved != 0)
        return DecodeError::BadReserved;
    if (name_length == 0 || name_length > k_max_name_length)
        return DecodeError::BadName;
    return read_name(r, p.name, name_length);
}

void read_leaf(ByteReader& r, WireLeafId& l) noexcept
{
    l.square = r.u8();
    l.depth = r.u8();
    l.ix = r.u16();
    l.iy = r.u16();
}

Err read_reserved(ByteReader& r, std::size_t n) noexcept
{
    bool ok = true;
    for (std::size_t i = 0; i < n; ++i)
        ok = (r.u8() == 0) && ok;
    return (ok || r.short_read()) ? Err{} : DecodeError::BadReserved;
}

/// Reads a target; for a force entry the 3 bytes after kind hold (reserved u8, grab id u16).
Err read_target(ByteReader& r, Target& t, std::uint16_t* grab_id) noexcept
{
    t.kind = static_cast<TargetKind>(r.u8());
    if (grab_id != nullptr)
    {
        if (auto err = read_reserved(r, 1))
            return err;
        *grab_id = r.u16();
    }
    else if (auto err = read_reserved(r, 3))
    {
        return err;
    }
    t.face = r.u32();
    for (double& x : t.position)
        x = r.f64();
    t.radius = r.f64();
    return {};
}

/// Reads `n` values; the caller has checked that n * size bytes remain.
void read_values(ByteReader& r, std::vector<double>& out, std::size_t n, ValueEncoding e) noexcept
{
    out.resize(n);
    if (e == ValueEncoding::F32)
        for (double& x : out)
            x = r.f32();
    else
        r.f64s(out.data(), n);
}

Err read_body(ByteReader& r, Hello& m) noexcept
{
    m.role = static_cast<Role>(r.u8());
    const std::uint8_t n = r.u8();
    m.listen_port = r.u16();
    if (r.short_read())
        return {};
    if (n == 0 || n > k_max_name_length)
        return DecodeError::BadName;
    return read_name(r, m.name, n);
}

Err read_body(ByteReader& r, Welcome& m) noexcept
{
    m.your_id = PeerId{r.u16()};
    m.master_id = PeerId{r.u16()};
    m.grid_level = r.u8();
    m.leaf_depth = r.u8();
    const std::uint8_t count = r.u8();
    if (auto err = read_reserved(r, 1))
        return err;
    m.epoch = r.u32();
    m.time = r.f64();
    m.model_size = r.u32();
    m.model_hash = r.u64();
    m.state_size = r.u32();
    m.state_hash = r.u64();
    if (r.short_read())
        return {};
    if (count == 0 || count > k_max_welcome_peers)
        return DecodeError::BadCount;
    m.peers.resize(count);
    for (PeerInfo& p : m.peers)
    {
        if (auto err = read_peer_info(r, p))
            return err;
        if (r.short_read())
            return {};
    }
    return {};
}

Err read_body(ByteReader& r, Reject& m) noexcept
{
    m.reason = static_cast<DisconnectReason>(r.u8());
    return read_reserved(r, 3);
}

Err read_body(ByteReader& r, PeerJoined& m) noexcept
{
    return read_peer_info(r, m.peer);
}

Err read_body(ByteReader& r, PeerLeft& m) noexcept
{
    m.peer = PeerId{r.u16()};
    m.reason = static_cast<DisconnectReason>(r.u8());
    return read_reserved(r, 1);
}

Err read_body(ByteReader& r, Blob& m) noexcept
{
    m.kind = static_cast<BlobKind>(r.u8());
    if (auto err = read_reserved(r, 1))
        return err;
    const std::uint16_t n = r.u16();
    m.total_size = r.u32();
    m.offset = r.u32();
    if (r.short_read())
        return {};
    if (n == 0 || n > k_max_blob_chunk)
        return DecodeError::BadCount;
    if (n > r.remaining())
    {
        r.skip(n);
        return {};
    }
    m.data.resize(n);
    r.bytes(m.data.data(), n);
    return {};
}

Err read_body(ByteReader& r, PointsOfInterest& m) noexcept
{
    const std::uint8_t count = r.u8();
    if (auto err = read_reserved(r, 3))
        return err;
    if (r.short_read())
        return {};
    if (count > k_max_points)
        return DecodeError::BadCount;
    m.points.resize(count);
    for (Target& t : m.points)
        if (auto err = read_target(r, t, nullptr))
            return err;
    return {};
}

Err read_body(ByteReader& r, Partition& m) noexcept
{
    m.epoch = r.u32();
    m.leaf_depth = r.u8();
    if (auto err = read_reserved(r, 3))
        return err;
    if (r.short_read())
        return {};
    if (m.leaf_depth > k_max_partition_depth)
        return DecodeError::BadRange;
    const std::size_t n = std::size_t{2} << (2 * m.leaf_depth);
    if (2 * n > r.remaining())
    {
        r.skip(2 * n);
        return {};
    }
    m.owners.resize(n);
    for (PeerId& p : m.owners)
        p = PeerId{r.u16()};
    return {};
}

Err read_body(ByteReader& r, Force& m) noexcept
{
    const std::uint8_t count = r.u8();
    if (auto err = read_reserved(r, 3))
        return err;
    if (r.short_read())
        return {};
    if (count > k_max_points)
        return DecodeError::BadCount;
    m.forces.resize(count);
    for (UserForce& f : m.forces)
    {
        if (auto err = read_target(r, f.target, &f.grab_id))
            return err;
        for (double& x : f.force)
            x = r.f64();
    }
    return {};
}

Err read_body(ByteReader& r, Leave& m) noexcept
{
    m.reason = static_cast<DisconnectReason>(r.u8());
    return read_reserved(r, 3);
}

/// The flags, and the packed residuals of n nodes, of a quantised delta whose u16 word (length and
/// flags) has been read; unpacks them (hostile bytes: BadCompression).
Err read_packed(ByteReader& r, std::uint16_t word, std::size_t n, QuantisedDelta& q) noexcept
{
    if ((word & 0x1800u) != 0)
        return DecodeError::BadReserved;
    q.predicted = (word & 0x8000u) != 0;
    q.extrapolated = (word & 0x4000u) != 0;
    q.packing = (word & 0x2000u) != 0 ? Packing::Rice : Packing::Zstd;
    const std::size_t c = word & 0x07FFu;
    if (c == 0 || c > k_max_packed_residuals)
        return DecodeError::BadCount;
    if (c > r.remaining())
    {
        r.skip(c);
        return {};
    }
    q.packed.resize(c);
    r.bytes(q.packed.data(), c);
    q.du.resize(n);
    q.dv.resize(n);
    return unpack_residuals(q.packing, q.packed, q.du, q.dv);
}

/// A default-constructed QuantisedDelta's values, keeping the vectors' storage.
void clear(QuantisedDelta& q) noexcept
{
    q.baseline = 0;
    q.u_exponent = 0;
    q.v_exponent = 0;
    q.predicted = false;
    q.extrapolated = false;
    q.du.clear();
    q.dv.clear();
    q.packing = Packing::Zstd;
    q.packed.clear();
}

Err read_body(ByteReader& r, LeafState& m) noexcept
{
    m.epoch = r.u32();
    read_leaf(r, m.leaf);
    const std::uint8_t encoding = r.u8();
    m.coarsen = r.u8();
    m.node_offset = r.u16();
    const std::uint16_t n = r.u16();
    m.time = r.f64();
    if (r.short_read())
        return {};
    if (!valid_leaf_encoding(encoding))
        return DecodeError::BadEnum;
    m.encoding = static_cast<ValueEncoding>(encoding);
    if (m.coarsen > k_max_leaf_coarsen ||
        (m.coarsen != 0 && m.encoding == ValueEncoding::QuantisedDelta))
        return DecodeError::BadRange;
    if (n == 0 || n > max_leaf_nodes(m.encoding))
        return DecodeError::BadCount;
    if (m.encoding == ValueEncoding::QuantisedDelta)
    {
        // A reused message: the other encoding's fields as a fresh one has them.
        m.u.clear();
        m.v.clear();
        QuantisedDelta& q = m.quantised;
        q.baseline = r.u32();
        q.u_exponent = static_cast<std::int8_t>(r.u8());
        q.v_exponent = static_cast<std::int8_t>(r.u8());
        const std::uint16_t packed = r.u16();
        if (r.short_read())
            return {};
        return read_packed(r, packed, n, q);
    }
    clear(m.quantised);
    if (2 * std::size_t{n} * value_size(m.encoding) > r.remaining())
    {
        r.skip(r.remaining() + 1);
        return {};
    }
    read_values(r, m.u, n, m.encoding);
    read_values(r, m.v, n, m.encoding);
    return {};
}

Err read_body(ByteReader& r, Halo& m) noexcept
{
    m.epoch = r.u32();
    m.stage = r.u8();
    const std::uint8_t encoding = r.u8();
    const std::uint8_t fields = r.u8();
    const std::uint8_t count = r.u8();
    m.time = r.f64();
    if (r.short_read())
        return {};
    if (!valid_encoding(encoding) || fields == 0 || fields > 3)
        return DecodeError::BadEnum;
    m.encoding = static_cast<ValueEncoding>(encoding);
    m.has_u = (fields & 1u) != 0;
    m.has_v = (fields & 2u) != 0;
    if (count == 0 || count > k_max_halo_ranges)
        return DecodeError::BadCount;
    m.ranges.resize(count);
    for (NodeRange& range : m.ranges)
    {
        range.first = r.u32();
        range.count = r.u16();
        if (auto err = read_reserved(r, 2))
            return err;
    }
    if (r.short_read())
        return {};
    // Bound the value count before allocating: hostile ranges could claim millions of nodes.
    const std::size_t n = halo_nodes(m.ranges);
    const std::size_t nf = (m.has_u ? 1u : 0u) + (m.has_v ? 1u : 0u);
    const std::size_t values_bytes = nf * n * value_size(m.encoding);
    if (k_halo_fixed + k_range_size * count + values_bytes > k_max_state_payload)
        return DecodeError::BadCount;
    if (values_bytes > r.remaining())
    {
        r.skip(r.remaining() + 1);
        return {};
    }
    if (m.has_u)
        read_values(r, m.u, n, m.encoding);
    else
        m.u.clear();
    if (m.has_v)
        read_values(r, m.v, n, m.encoding);
    else
        m.v.clear();
    return {};
}

Err read_body(ByteReader& r, Heartbeat& m) noexcept
{
    m.epoch = r.u32();
    return {};
}

Err read_body(ByteReader&, Ready&) noexcept
{
    return {};
}

Err read_body(ByteReader& r, Ping& m) noexcept
{
    m.nonce = r.u32();
    if (auto err = read_reserved(r, 4))
        return err;
    m.time_us = r.u64();
    return {};
}

Err read_body(ByteReader& r, Pong& m) noexcept
{
    m.nonce = r.u32();
    if (auto err = read_reserved(r, 4))
        return err;
    m.time_us = r.u64();
    return {};
}

/// The leaf with index (square * 2^depth + iy) * 2^depth + ix; \pre index < 2 * 4^depth.
WireLeafId leaf_of_index(std::uint16_t index, std::uint8_t depth) noexcept
{
    const std::uint32_t side = 1u << depth;
    return WireLeafId{static_cast<std::uint8_t>(index / (side * side)), depth,
                      static_cast<std::uint16_t>(index % side),
                      static_cast<std::uint16_t>((index / side) % side)};
}

/// A canonical LEB128 varint of a value up to `max` (no redundant final 0x00 group, at most
/// 10 bytes; a short read leaves `value` unspecified and the reader short).
Err read_varint(ByteReader& r, std::uint64_t& value, std::uint64_t max) noexcept
{
    std::uint64_t v = 0;
    for (int k = 0; k < 10; ++k)
    {
        const std::uint8_t b = r.u8();
        if (r.short_read())
            return {};
        const std::uint64_t group = b & 0x7Fu;
        if (k == 9 && group > 1)  // bits beyond 64
            return DecodeError::BadRange;
        v |= group << (7 * k);
        if ((b & 0x80u) == 0)
        {
            if ((b == 0 && k > 0) || v > max)
                return DecodeError::BadRange;
            value = v;
            return {};
        }
    }
    return DecodeError::BadRange;
}

Err read_body(ByteReader& r, LeafBatch& m) noexcept
{
    m.epoch = r.u32();
    m.time = r.f64();
    m.u_exponent = static_cast<std::int8_t>(r.u8());
    m.v_exponent = static_cast<std::int8_t>(r.u8());
    const std::uint8_t depth = r.u8();
    const std::uint8_t count = r.u8();
    if (r.short_read())
        return {};
    if (count == 0 || count > k_max_batch_leaves)
        return DecodeError::BadCount;
    if (depth > k_max_partition_depth)
        return DecodeError::BadRange;
    const std::uint32_t side = 1u << depth;
    m.leaves.resize(count);
    for (BatchLeaf& l : m.leaves)
    {
        const std::uint16_t index = r.u16();
        const std::uint8_t n = r.u8();
        const std::uint16_t word = r.u16();
        if (r.short_read())
            return {};
        if (index >= 2 * side * side)
            return DecodeError::BadRange;
        l.leaf = leaf_of_index(index, depth);
        if (n == 0 || n > k_max_leaf_nodes_quantised)
            return DecodeError::BadCount;
        QuantisedDelta& q = l.quantised;
        q.u_exponent = m.u_exponent;
        q.v_exponent = m.v_exponent;
        std::uint64_t baseline = 0;
        if (auto err = read_varint(r, baseline, 0xFFFFFFFFu))
            return err;
        q.baseline = static_cast<std::uint32_t>(baseline);
        if (r.short_read())
            return {};
        if (auto err = read_packed(r, word, n, q))
            return err;
        if (r.short_read())
            return {};
    }
    return {};
}

Err read_body(ByteReader& r, ValueBatch& m) noexcept
{
    m.epoch = r.u32();
    m.time = r.f64();
    const std::uint8_t encoding = r.u8();
    m.coarsen = r.u8();
    const std::uint8_t depth = r.u8();
    const std::uint8_t count = r.u8();
    if (r.short_read())
        return {};
    if (!valid_encoding(encoding))
        return DecodeError::BadEnum;
    m.encoding = static_cast<ValueEncoding>(encoding);
    if (m.coarsen > k_max_leaf_coarsen || depth > k_max_partition_depth)
        return DecodeError::BadRange;
    if (count == 0 || count > k_max_batch_leaves)
        return DecodeError::BadCount;
    const std::uint32_t side = 1u << depth;
    m.leaves.resize(count);
    for (ValueLeaf& l : m.leaves)
    {
        const std::uint16_t index = r.u16();
        const std::uint8_t n = r.u8();
        if (r.short_read())
            return {};
        if (index >= 2 * side * side)
            return DecodeError::BadRange;
        l.leaf = leaf_of_index(index, depth);
        if (n == 0 || n > max_leaf_nodes(m.encoding))
            return DecodeError::BadCount;
        if (2 * std::size_t{n} * value_size(m.encoding) > r.remaining())
        {
            r.skip(r.remaining() + 1);
            return {};
        }
        read_values(r, l.u, n, m.encoding);
        read_values(r, l.v, n, m.encoding);
    }
    return {};
}

Err read_body(ByteReader& r, Ack& m) noexcept
{
    const std::uint8_t count = r.u8();
    const std::uint8_t depth = r.u8();
    if (auto err = read_reserved(r, 2))
        return err;
    const std::uint64_t newest = r.u64();
    if (r.short_read())
        return {};
    if (count == 0 || count > k_max_acks)
        return DecodeError::BadCount;
    if (depth > k_max_partition_depth)
        return DecodeError::BadRange;
    const std::uint32_t side = 1u << depth;
    m.acks.resize(count);
    bool newest_named = false;
    for (LeafAck& a : m.acks)
    {
        const std::uint16_t index = r.u16();
        std::uint64_t age = 0;
        if (auto err = read_varint(r, age, newest))
            return err;
        if (r.short_read())
            return {};
        if (index >= 2 * side * side)
            return DecodeError::BadRange;
        a.leaf = leaf_of_index(index, depth);
        a.tick = newest - age;
        newest_named = newest_named || age == 0;
    }
    // Canonical: the newest tick is an entry's (one of the ages is 0).
    return newest_named ? Err{} : DecodeError::BadRange;
}

/// Makes `body` hold the alternative of index `index` (wire type - 1): a default-constructed one,
/// unless it holds that alternative already, which is kept with its vectors' storage (every
/// read_body then sets each of its fields).
template <std::size_t I = 0>
void prepare_body(Body& body, std::size_t index) noexcept
{
    if constexpr (I + 1 < std::variant_size_v<Body>)
    {
        if (index != I)
        {
            prepare_body<I + 1>(body, index);
            return;
        }
    }
    if (body.index() != I)
        body.emplace<I>();
}

}  // namespace

bool is_valid_name(std::string_view name) noexcept
{
    if (name.empty() || name.size() > k_max_name_length)
        return false;
    return std::all_of(name.begin(), name.end(), [](char c) { return c >= 0x20 && c <= 0x7E; });
}

std::optional<DecodeError> validate(const Message& message) noexcept
{
    if (auto err = check_header(message.header, message.type()))
        return err;
    if (auto err = std::visit([](const auto& body) { return check(body); }, message.body))
        return err;
    if (const auto* ls = std::get_if<LeafState>(&message.body);
        ls != nullptr && ls->encoding == ValueEncoding::QuantisedDelta)
        return check_packed(ls->quantised);
    if (const auto* b = std::get_if<LeafBatch>(&message.body))
        for (const BatchLeaf& l : b->leaves)
            if (auto err = check_packed(l.quantised))
                return err;
    return {};
}

std::size_t value_leaf_size(const ValueLeaf& leaf, ValueEncoding encoding) noexcept
{
    return k_value_leaf_fixed + (leaf.u.size() + leaf.v.size()) * value_size(encoding);
}

std::size_t batch_leaf_size(const BatchLeaf& leaf) noexcept
{
    return k_batch_leaf_fixed + varint_size(leaf.quantised.baseline) + leaf.quantised.packed.size();
}

std::size_t encoded_size(const Message& message) noexcept
{
    return k_header_size +
           std::visit([](const auto& body) { return body_size(body); }, message.body);
}

Expected<std::size_t, EncodeError> encode(const Message& message, std::span<std::byte> out) noexcept
{
    if (validate(message))
        return Unexpected{EncodeError::InvalidMessage};
    const std::size_t size = encoded_size(message);
    PLIANT_ASSERT(size <= k_max_datagram_size,
                  "encode: a valid message exceeds the datagram limit");
    if (out.size() < size)
        return Unexpected{EncodeError::BufferTooSmall};
    ByteWriter w(out);
    w.u32(k_protocol_magic);
    w.u8(k_protocol_version);
    w.u8(static_cast<std::uint8_t>(message.type()));
    w.u8(0);  // flags: reserved
    w.u8(0);
    w.u32(message.header.session);
    w.u16(message.header.sender.value);
    w.u16(message.header.sequence);
    w.u64(message.header.tick);
    std::visit([&w](const auto& body) { write_body(w, body); }, message.body);
    PLIANT_ASSERT(w.size() == size, "encode: body_size and write_body disagree");
    return w.size();
}

std::optional<DecodeError> decode_into(std::span<const std::byte> datagram, Message& out) noexcept
{
    if (datagram.size() < k_header_size)
        return DecodeError::TooShort;
    if (datagram.size() > k_max_datagram_size)
        return DecodeError::TooLarge;
    ByteReader r(datagram);
    if (r.u32() != k_protocol_magic)
        return DecodeError::BadMagic;
    if (r.u8() != k_protocol_version)
        return DecodeError::BadVersion;
    const std::uint8_t type = r.u8();
    if (type == 0 || type > k_message_type_count)
        return DecodeError::UnknownType;
    if (r.u8() != 0)
        return DecodeError::BadFlags;
    if (r.u8() != 0)
        return DecodeError::BadReserved;
    prepare_body(out.body, type - 1u);
    out.header.session = r.u32();
    out.header.sender = PeerId{r.u16()};
    out.header.sequence = r.u16();
    out.header.tick = r.u64();
    if (auto err = check_header(out.header, out.type()))
        return err;
    if (auto err = std::visit([&r](auto& body) { return read_body(r, body); }, out.body))
        return err;
    if (r.short_read() || r.remaining() != 0)
        return DecodeError::BadLength;
    return std::visit([](const auto& body) { return check(body); }, out.body);
}

Expected<Message, DecodeError> decode(std::span<const std::byte> datagram) noexcept
{
    Message message;
    if (auto err = decode_into(datagram, message))
        return Unexpected{*err};
    return message;
}

}  // namespace pliant::net
