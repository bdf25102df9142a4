// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// One or more valid messages of every type, shared by the codec tests, the fuzz target (its
// build -> encode -> corrupt mode and seed corpus) and the codec benchmark. Values are chosen to be
// exact in f32 where the encoding is f32, so round trips compare equal.

#include <pliant/net/message.h>
#include <pliant/net/quantised.h>

#include <cmath>
#include <cstddef>
#include <vector>

namespace pliant::net::samples
{

inline Header header(std::uint64_t tick = 1234567890123ULL)
{
    return Header{.session = 0xC0FFEE01u, .sender = PeerId{3}, .sequence = 0xBEEF, .tick = tick};
}

inline PeerInfo peer_info(std::uint16_t id, const char* name)
{
    return PeerInfo{.id = PeerId{id},
                    .role = id % 2 == 0 ? Role::Participant : Role::Viewer,
                    .ipv4 = {192, 168, 1, static_cast<std::uint8_t>(id)},
                    .port = static_cast<std::uint16_t>(40000 + id),
                    .name = name};
}

/// A LeafState with n nodes; values exact in f32 (multiples of 1/1024).
inline LeafState leaf_state(ValueEncoding encoding, std::size_t n)
{
    LeafState s;
    s.epoch = 7;
    s.leaf = WireLeafId{.square = 1, .depth = 4, .ix = 15, .iy = 3};
    s.encoding = encoding;
    s.node_offset = 0;
    s.time = 12.5;
    for (std::size_t i = 0; i < n; ++i)
    {
        const double k = static_cast<double>(i);
        s.u.push_back((k - 30.0) / 1024.0);
        s.v.push_back(-k / 256.0 + 0.125);
    }
    if (encoding == ValueEncoding::F64 && n > 1)
        s.u[1] = 1.0 / 3.0;  // not exact in f32: f64 must keep every bit
    return s;
}

/// A quantised-delta LeafState of n nodes (docs/protocol.md §5.5): smooth integers, residuals
/// against nothing (key) or against a baseline `baseline` ticks back, packed with zstd.
inline LeafState quantised_leaf_state(std::size_t n, std::uint32_t baseline, bool predicted,
                                      Packing packing = Packing::Zstd)
{
    LeafState s;
    s.epoch = 8;
    s.leaf = WireLeafId{.square = 0, .depth = 3, .ix = 5, .iy = 2};
    s.encoding = ValueEncoding::QuantisedDelta;
    s.time = 1.25;
    QuantisedDelta& q = s.quantised;
    q.baseline = baseline;
    q.u_exponent = -16;
    q.v_exponent = -12;
    q.predicted = predicted;
    for (std::size_t i = 0; i < n; ++i)
    {
        const auto k = static_cast<std::int32_t>(i);
        q.du.push_back(predicted ? 3 - (k % 5) : 1000 * k - 20000);
        q.dv.push_back(predicted ? (k % 3) - 1 : -7 * k);
    }
    q.packing = packing;
    const bool packed = packing == Packing::Rice
                            ? pack_residuals_rice(q.du, q.dv, k_max_packed_residuals, q.packed)
                            : pack_residuals(q.du, q.dv, k_max_packed_residuals, q.packed);
    if (!packed)
        q.packed.clear();
    return s;
}

/// A LeafBatch of `count` leaves at depth `depth` (indices spread over both squares), baselines
/// 0, 1, 127, 128, 300000, ... (varints of 1 to 3 bytes), packings alternating.
inline LeafBatch leaf_batch(std::size_t count, std::uint8_t depth, std::size_t n)
{
    LeafBatch b;
    b.epoch = 12;
    b.time = 2.5;
    b.u_exponent = -12;
    b.v_exponent = -8;
    const std::uint32_t side = 1u << depth;
    const std::uint32_t baselines[] = {0, 1, 127, 128, 300000};
    for (std::size_t k = 0; k < count; ++k)
    {
        const std::uint32_t index = static_cast<std::uint32_t>((k * 7919) % (2 * side * side));
        LeafState s = quantised_leaf_state(n, baselines[k % 5], k % 2 == 0,
                                           k % 3 == 0 ? Packing::Zstd : Packing::Rice);
        s.quantised.u_exponent = b.u_exponent;
        s.quantised.v_exponent = b.v_exponent;
        s.quantised.extrapolated = s.quantised.baseline != 0 && k % 4 == 1;
        BatchLeaf l;
        l.leaf = WireLeafId{static_cast<std::uint8_t>(index / (side * side)), depth,
                            static_cast<std::uint16_t>(index % side),
                            static_cast<std::uint16_t>((index / side) % side)};
        l.quantised = s.quantised;
        b.leaves.push_back(l);
    }
    return b;
}

/// A ValueBatch of `count` leaves of `n` nodes at depth `depth` (indices spread over both
/// squares), coarsened `coarsen` levels.
inline ValueBatch value_batch(ValueEncoding encoding, std::uint8_t coarsen, std::uint8_t depth,
                              std::size_t count, std::size_t n)
{
    ValueBatch b;
    b.epoch = 21;
    b.time = 1.75;
    b.encoding = encoding;
    b.coarsen = coarsen;
    const std::uint32_t side = 1u << depth;
    for (std::size_t k = 0; k < count; ++k)
    {
        const std::uint32_t index = static_cast<std::uint32_t>((k * 7919) % (2 * side * side));
        ValueLeaf l;
        l.leaf = WireLeafId{static_cast<std::uint8_t>(index / (side * side)), depth,
                            static_cast<std::uint16_t>(index % side),
                            static_cast<std::uint16_t>((index / side) % side)};
        for (std::size_t i = 0; i < n; ++i)
        {
            l.u.push_back(0.125 * static_cast<double>(i + k));
            l.v.push_back(-0.5 * static_cast<double>(i));
        }
        b.leaves.push_back(l);
    }
    return b;
}

inline Halo halo(ValueEncoding encoding, bool has_u, bool has_v)
{
    Halo h;
    h.epoch = 9;
    h.stage = 3;
    h.encoding = encoding;
    h.time = 0.25;
    // The last range ends exactly at level 10's node count (the largest valid index); it is
    // shorter when the values would not fit the 1,200-byte payload (16 + 24 + fields * n * size).
    const bool wide = encoding == ValueEncoding::F64 || (has_u && has_v);
    const std::uint16_t last = wide ? 25 : 225;
    h.ranges = {NodeRange{.first = 100, .count = 5}, NodeRange{.first = 200, .count = 3},
                NodeRange{.first = k_max_grid_nodes - last, .count = last}};
    const std::size_t nodes = 5 + 3 + std::size_t{last};
    h.has_u = has_u;
    h.has_v = has_v;
    for (std::size_t i = 0; i < nodes; ++i)
    {
        if (has_u)
            h.u.push_back(static_cast<double>(i) * 0.5);
        if (has_v)
            h.v.push_back(-static_cast<double>(i) * 0.25);
    }
    return h;
}

inline std::vector<Message> all()
{
    std::vector<Message> out;
    const auto add = [&out](Body body, Header h = header())
    { out.push_back(Message{.header = h, .body = std::move(body)}); };
    Header joiner = header(0);
    joiner.session = 0;
    joiner.sender = k_no_peer;
    add(Hello{.role = Role::Participant, .listen_port = 0, .name = "alice"}, joiner);
    add(Hello{.role = Role::Viewer, .listen_port = 40123, .name = "Viewer #2 ~ (lab)"});
    Welcome w;
    w.your_id = PeerId{5};
    w.master_id = PeerId{0};
    w.grid_level = 6;
    w.leaf_depth = 3;
    w.epoch = 2;
    w.time = 3.75;
    w.model_size = 1234567;
    w.model_hash = 0x0123456789ABCDEFULL;
    w.state_size = 65536;
    w.state_hash = 0xFEDCBA9876543210ULL;
    w.peers = {peer_info(0, "master"), peer_info(2, "bob"), peer_info(5, "carol the joiner")};
    add(w);
    Header reject = header();
    reject.session = 0;
    add(Reject{.reason = DisconnectReason::SessionFull}, reject);
    add(PeerJoined{.peer = peer_info(6, "dave")});
    add(PeerLeft{.peer = PeerId{2}, .reason = DisconnectReason::TimedOut});
    std::vector<std::byte> blob(1000);
    for (std::size_t i = 0; i < blob.size(); ++i)
        blob[i] = static_cast<std::byte>((i * 37) & 0xFF);
    add(Blob{.kind = BlobKind::Model, .total_size = 5000, .offset = 4000, .data = blob});
    add(Blob{.kind = BlobKind::State, .total_size = 1, .offset = 0, .data = {std::byte{42}}});
    add(PointsOfInterest{});
    add(PointsOfInterest{
        .points = {
            Target{.kind = TargetKind::Face, .face = 12345, .position = {0, 0, 0}, .radius = 0.02},
            Target{.kind = TargetKind::Position,
                   .face = 0,
                   .position = {0.1, -0.2, 0.3},
                   .radius = 0.0}}});
    Partition p;
    p.epoch = 3;
    p.leaf_depth = 2;
    for (std::size_t i = 0; i < 32; ++i)
        p.owners.push_back(
            PeerId{static_cast<std::uint16_t>(i % 3 == 0 ? 0 : (i % 3 == 1 ? 2 : 5))});
    add(p);
    add(Partition{.epoch = 1, .leaf_depth = 0, .owners = {PeerId{0}, PeerId{7}}});
    add(Force{});
    add(Force{
        .forces = {UserForce{
            .target =
                Target{.kind = TargetKind::Face, .face = 77, .position = {0, 0, 0}, .radius = 0.05},
            .grab_id = 9,
            .force = {1.5, -2.0, 1e-3}}}});
    add(Leave{.reason = DisconnectReason::Quit});
    add(leaf_state(ValueEncoding::F64, k_max_leaf_nodes_f64));
    add(leaf_state(ValueEncoding::F32, k_max_leaf_nodes_f32));
    add(leaf_state(ValueEncoding::F64, 1));
    add(halo(ValueEncoding::F32, true, false));
    add(halo(ValueEncoding::F64, true, true));
    add(halo(ValueEncoding::F32, false, true));
    add(Heartbeat{.epoch = 4});
    add(Ping{.nonce = 0xA5A5A5A5u, .time_us = 123456789});
    add(Pong{.nonce = 0xA5A5A5A5u, .time_us = 123456789});
    add(Ack{.acks = {LeafAck{.leaf = WireLeafId{0, 3, 7, 7}, .tick = 99},
                     LeafAck{.leaf = WireLeafId{1, 3, 0, 0}, .tick = 0xFFFFFFFFFFFFULL},
                     LeafAck{.leaf = WireLeafId{1, 3, 2, 5}, .tick = 0xFFFFFFFFFFF0ULL}}});
    add(Ack{.acks = {LeafAck{.leaf = WireLeafId{1, 0, 0, 0}, .tick = 0}}});
    // Appended after the version-1 samples so that the fuzz corpus's sample indices stay valid.
    add(quantised_leaf_state(72, 0, true));
    add(quantised_leaf_state(k_max_leaf_nodes_quantised, 6, false));
    add(quantised_leaf_state(1, 1, false));
    // Version 3: a leaf streamed one level down (docs/protocol.md LeafState `coarsen`).
    {
        LeafState coarse = leaf_state(ValueEncoding::F64, 16);  // a leaf streamed one level down
        coarse.coarsen = 1;
        add(coarse);
    }
    // Version 4: Rice-packed residuals and batches of leaves.
    add(quantised_leaf_state(72, 3, true, Packing::Rice));
    add(quantised_leaf_state(k_max_leaf_nodes_quantised, 0, false, Packing::Rice));
    add(leaf_batch(1, 0, 1));
    add(leaf_batch(5, 3, 72));
    add(leaf_batch(9, 7, 20));
    // Version 5: a joiner's readiness for leaf states.
    add(Ready{});
    // Version 6: f32 / f64 states of several whole leaves (coarse streaming).
    add(value_batch(ValueEncoding::F64, 2, 1, 4, 4));
    add(value_batch(ValueEncoding::F32, 1, 7, 1, 1));
    add(value_batch(ValueEncoding::F32, 0, 3, 8, 16));
    return out;
}

}  // namespace pliant::net::samples
