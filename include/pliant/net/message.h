// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The messages pliant peers exchange, as plain structs (docs/protocol.md §6 gives their bytes).
///
/// Design: a `Message` is a header plus a `std::variant` of body structs, one per message type, in
/// type-number order (variant index + 1 is the wire type). Bodies own their variable parts
/// (`std::vector`, `std::string`), so a decoded message outlives the datagram; decode() allocates
/// a few times per datagram (per packet, never per node), decode_into() into a reused message
/// only when a vector must grow. Values are `double` in memory
/// whatever the wire encoding, so the session never sees `f32` arithmetic; with
/// `ValueEncoding::F32` the encoder rounds to nearest. Rejected alternative: views into the
/// datagram buffer (zero-copy) would tie a message's lifetime to the transport's packet and make
/// the fuzz round trip awkward; at 6,000 datagrams/s the copies cost nothing measurable.

#include <pliant/net/types.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace pliant::net
{

inline constexpr std::uint32_t k_protocol_magic = 0x544E4C50;  ///< bytes "PLNT"
inline constexpr std::uint8_t k_protocol_version = 6;
inline constexpr std::size_t k_header_size = 24;
/// The largest body of a LeafState or Halo (one leaf per datagram, no IP fragmentation).
inline constexpr std::size_t k_max_state_payload = 1200;
/// The largest datagram: a depth-7 Partition (8 + 4 * 4^7 bytes of body).
inline constexpr std::size_t k_max_datagram_size = k_header_size + 8 + 4 * 16384;
inline constexpr std::size_t k_max_name_length = 32;
inline constexpr std::size_t k_max_welcome_peers = 64;
inline constexpr std::size_t k_max_blob_chunk = 32768;
inline constexpr std::uint32_t k_max_blob_size = 256u << 20;
inline constexpr std::size_t k_max_points = 16;  ///< points of interest and forces per message
inline constexpr std::size_t k_max_halo_ranges = 32;
inline constexpr std::size_t k_max_acks = 128;
inline constexpr int k_max_partition_depth = 7;
inline constexpr int k_max_grid_level = 10;
inline constexpr std::uint32_t k_max_face_index = 4u << 20;       ///< 4 * 4^10 faces at level 10
inline constexpr std::uint32_t k_max_grid_nodes = 2049u * 1025u;  ///< nodes at level 10
inline constexpr std::uint8_t k_max_halo_stage = 6;
/// Largest LeafState `coarsen` (levels below the grid's; docs/protocol.md §6 LeafState).
inline constexpr std::uint8_t k_max_leaf_coarsen = 3;
/// Fixed bytes of a LeafState body before the values.
inline constexpr std::size_t k_leaf_state_fixed = 24;
/// Nodes (u and v each) that fit one LeafState: 73 with f64, 147 with f32.
inline constexpr std::size_t k_max_leaf_nodes_f64 = (k_max_state_payload - k_leaf_state_fixed) / 16;
inline constexpr std::size_t k_max_leaf_nodes_f32 = (k_max_state_payload - k_leaf_state_fixed) / 8;
static_assert(k_max_leaf_nodes_f64 == 73 && k_max_leaf_nodes_f32 == 147);
/// Fixed bytes of a quantised-delta LeafState body before the packed residuals (§6 LeafState).
inline constexpr std::size_t k_leaf_state_quantised_fixed = 32;
/// Nodes of one quantised-delta LeafState at most (the f32 limit, so an encoder can always fall
/// back to f32 for the same leaf).
inline constexpr std::size_t k_max_leaf_nodes_quantised = k_max_leaf_nodes_f32;
/// The largest packed residual frame of one LeafState.
inline constexpr std::size_t k_max_packed_residuals =
    k_max_state_payload - k_leaf_state_quantised_fixed;

/// Fixed bytes of a LeafBatch body, and of each of its leaves before the packed residuals
/// (docs/protocol.md §6 LeafBatch; the baseline varint comes on top, 1..5 bytes).
inline constexpr std::size_t k_leaf_batch_fixed = 16;
inline constexpr std::size_t k_batch_leaf_fixed = 5;
/// Leaves of one LeafBatch at most.
inline constexpr std::size_t k_max_batch_leaves = 128;
/// Fixed bytes of a ValueBatch body, and of each of its leaves before the values (docs/protocol.md
/// §6 ValueBatch); a leaf of n nodes adds 3 + 2 n s bytes (s = 4 or 8), at most
/// k_max_batch_leaves leaves.
inline constexpr std::size_t k_value_batch_fixed = 16;
inline constexpr std::size_t k_value_leaf_fixed = 3;

/// Wire message types (docs/protocol.md §6); the order matches `Body`.
enum class MessageType : std::uint8_t
{
    Hello = 1,  ///< control (channel 0); a dialler's repeats go on channel 1
    Welcome = 2,
    Reject = 3,
    PeerJoined = 4,
    PeerLeft = 5,
    Blob = 6,
    PointsOfInterest = 7,
    Partition = 8,
    Force = 9,
    Leave = 10,
    LeafState = 11,
    Halo = 12,
    Heartbeat = 13,
    Ping = 14,
    Pong = 15,
    Ack = 16,
    LeafBatch = 17,
    Ready = 18,  ///< control (channel 0) by default; its repeats go on channel 1
    ValueBatch = 19,
};
inline constexpr std::uint8_t k_message_type_count = 19;

/// How node values are written (docs/protocol.md §5.4).
enum class ValueEncoding : std::uint8_t
{
    F32 = 1,
    F64 = 2,
    QuantisedDelta = 3,  ///< LeafState only: integer residuals, zstd-packed (§5.5)
};

/// A quad-tree node (docs/protocol.md §5.2); the same fields as `core::LeafId`, kept separate so
/// the wire layout does not change if core's does.
struct WireLeafId
{
    std::uint8_t square = 0;
    std::uint8_t depth = 0;
    std::uint16_t ix = 0;
    std::uint16_t iy = 0;
    friend bool operator==(const WireLeafId&, const WireLeafId&) = default;
};

/// A peer as the master lists it (docs/protocol.md §5.1). IPv4 only (ENet has no IPv6).
struct PeerInfo
{
    PeerId id{0};
    Role role = Role::Participant;
    std::array<std::uint8_t, 4> ipv4{};  ///< a.b.c.d
    std::uint16_t port = 0;              ///< 1..65535
    std::string name;                    ///< 1..32 printable ASCII bytes
    friend bool operator==(const PeerInfo&, const PeerInfo&) = default;
};

struct Hello
{
    Role role = Role::Participant;
    std::uint16_t listen_port = 0;  ///< 0 = "the port you see me on"
    std::string name;
    friend bool operator==(const Hello&, const Hello&) = default;
};

struct Welcome
{
    PeerId your_id{0};
    PeerId master_id{0};
    std::uint8_t grid_level = 1;  ///< 1..10
    std::uint8_t leaf_depth = 0;  ///< 0..min(level, 7)
    std::uint32_t epoch = 0;      ///< 0 = not partitioned yet
    double time = 0.0;            ///< simulation time, s
    std::uint32_t model_size = 1;
    std::uint64_t model_hash = 0;
    std::uint32_t state_size = 0;
    std::uint64_t state_hash = 0;
    std::vector<PeerInfo> peers;  ///< every peer, the joiner included
    friend bool operator==(const Welcome&, const Welcome&) = default;
};

struct Reject
{
    DisconnectReason reason = DisconnectReason::Refused;
    friend bool operator==(const Reject&, const Reject&) = default;
};

struct PeerJoined
{
    PeerInfo peer;
    friend bool operator==(const PeerJoined&, const PeerJoined&) = default;
};

struct PeerLeft
{
    PeerId peer{0};
    DisconnectReason reason = DisconnectReason::Quit;
    friend bool operator==(const PeerLeft&, const PeerLeft&) = default;
};

enum class BlobKind : std::uint8_t
{
    Model = 1,
    State = 2,
};

/// One chunk of an opaque byte string (the session's model or state encoding).
struct Blob
{
    BlobKind kind = BlobKind::Model;
    std::uint32_t total_size = 0;
    std::uint32_t offset = 0;
    std::vector<std::byte> data;  ///< 1..32768 bytes, offset + size <= total_size
    friend bool operator==(const Blob&, const Blob&) = default;
};

enum class TargetKind : std::uint8_t
{
    Face = 1,      ///< a grid face index
    Position = 2,  ///< a point in space
};

/// Where a user acts: a face or a position, with a radius.
struct Target
{
    TargetKind kind = TargetKind::Face;
    std::uint32_t face = 0;                   ///< kind Face; 0 otherwise
    std::array<double, 3> position{0, 0, 0};  ///< m; kind Position; zero otherwise
    double radius = 0.0;                      ///< m, >= 0
    friend bool operator==(const Target&, const Target&) = default;
};

struct PointsOfInterest
{
    std::vector<Target> points;  ///< 0..16; replaces the sender's previous list
    friend bool operator==(const PointsOfInterest&, const PointsOfInterest&) = default;
};

struct Partition
{
    std::uint32_t epoch = 1;      ///< >= 1
    std::uint8_t leaf_depth = 0;  ///< 0..7
    std::vector<PeerId> owners;   ///< 2 * 4^depth, index (square * 2^d + iy) * 2^d + ix
    friend bool operator==(const Partition&, const Partition&) = default;
};

struct UserForce
{
    Target target;
    std::uint16_t grab_id = 0;
    std::array<double, 3> force{0, 0, 0};  ///< N
    friend bool operator==(const UserForce&, const UserForce&) = default;
};

struct Force
{
    std::vector<UserForce> forces;  ///< 0..16; applies from the header's tick on
    friend bool operator==(const Force&, const Force&) = default;
};

struct Leave
{
    DisconnectReason reason = DisconnectReason::Quit;
    friend bool operator==(const Leave&, const Leave&) = default;
};

/// How quantised residuals are packed (docs/protocol.md §5.5, §5.6).
enum class Packing : std::uint8_t
{
    Zstd = 0,  ///< zigzag LEB128 varints in one zstd frame (net::pack_residuals)
    Rice = 1,  ///< Rice-coded bit strings (net::pack_residuals_rice); version 4
};

/// The values of a quantised-delta LeafState (docs/protocol.md §5.5): residuals of the integers
/// q = x / 2^exponent against a baseline the receiver holds (net/quantised.h computes them). The
/// codec writes `packed` verbatim and checks on both sides that it unpacks to `du` and `dv`.
struct QuantisedDelta
{
    std::uint32_t baseline = 0;  ///< header tick minus the baseline's tick; 0: a key state
    std::int8_t u_exponent = 0;  ///< u step = 2^u_exponent, -40..0
    std::int8_t v_exponent = 0;  ///< v step = 2^v_exponent, -40..0
    bool predicted = false;      ///< residuals are differences from the previous node's
    /// The session extrapolated the baseline of u before taking differences (docs/protocol.md
    /// §5.5: u + v dt); only with a baseline. The codec only carries the flag.
    bool extrapolated = false;
    std::vector<std::int32_t> du;  ///< residual of u per node
    std::vector<std::int32_t> dv;  ///< residual of v per node, as many as du
    Packing packing = Packing::Zstd;
    std::vector<std::byte> packed;  ///< the packed residuals (`packing`), 1..1,168 bytes
    friend bool operator==(const QuantisedDelta&, const QuantisedDelta&) = default;
};

/// State of (part of) one leaf at the header's tick: `u` and `v` of the same length (encodings
/// f32 and f64), or `quantised` (encoding 3, `u` and `v` empty).
struct LeafState
{
    std::uint32_t epoch = 0;
    WireLeafId leaf;
    ValueEncoding encoding = ValueEncoding::F64;
    /// The values are of the leaf's nodes at the level `coarsen` below the grid's (0..3; 0 with
    /// encoding 3): the session's coarse streaming (docs/session.md §5.2). The codec checks the
    /// range only.
    std::uint8_t coarsen = 0;
    std::uint16_t node_offset = 0;
    double time = 0.0;         ///< s
    std::vector<double> u;     ///< m; 1..73 (f64) or 1..147 (f32) values
    std::vector<double> v;     ///< m/s; as many as u
    QuantisedDelta quantised;  ///< encoding 3 only (default-constructed otherwise)
    /// Nodes this message covers (u.size(), or quantised.du.size() with encoding 3).
    [[nodiscard]] std::size_t node_count() const noexcept
    {
        return encoding == ValueEncoding::QuantisedDelta ? quantised.du.size() : u.size();
    }
    friend bool operator==(const LeafState&, const LeafState&) = default;
};

struct NodeRange
{
    std::uint32_t first = 0;  ///< grid node index (y * nx + x)
    std::uint16_t count = 1;
    friend bool operator==(const NodeRange&, const NodeRange&) = default;
};

/// Halo values for one stage: `u` (if has_u) and `v` (if has_v) hold sum(count) values each, in
/// range order; an absent field's vector is empty.
struct Halo
{
    std::uint32_t epoch = 0;
    std::uint8_t stage = 0;  ///< 0..5 RKF45 stages, 6 the accepted step
    ValueEncoding encoding = ValueEncoding::F64;
    double time = 0.0;              ///< s
    std::vector<NodeRange> ranges;  ///< 1..32, increasing and disjoint
    bool has_u = true;
    bool has_v = false;
    std::vector<double> u;
    std::vector<double> v;
    friend bool operator==(const Halo&, const Halo&) = default;
};

struct Heartbeat
{
    std::uint32_t epoch = 0;
    friend bool operator==(const Heartbeat&, const Heartbeat&) = default;
};

struct Ping
{
    std::uint32_t nonce = 0;
    std::uint64_t time_us = 0;  ///< sender's clock
    friend bool operator==(const Ping&, const Ping&) = default;
};

struct Pong
{
    std::uint32_t nonce = 0;
    std::uint64_t time_us = 0;  ///< the Ping's clock, echoed
    friend bool operator==(const Pong&, const Pong&) = default;
};

struct LeafAck
{
    WireLeafId leaf;
    std::uint64_t tick = 0;
    friend bool operator==(const LeafAck&, const LeafAck&) = default;
};

struct Ack
{
    std::vector<LeafAck> acks;  ///< 1..128, every leaf at one depth (0..7)
    friend bool operator==(const Ack&, const Ack&) = default;
};

/// One leaf of a LeafBatch: a whole leaf's quantised delta (its exponents are the batch's).
struct BatchLeaf
{
    WireLeafId leaf;  ///< at the batch's depth
    QuantisedDelta quantised;
    friend bool operator==(const BatchLeaf&, const BatchLeaf&) = default;
};

/// Quantised-delta states of several whole leaves of one sender, at one tick and time, in one
/// datagram (docs/protocol.md §6 LeafBatch): the fixed part of a LeafState paid once per datagram
/// rather than once per leaf. Every leaf has the batch's depth and exponents.
struct LeafBatch
{
    std::uint32_t epoch = 0;
    double time = 0.0;              ///< s
    std::int8_t u_exponent = 0;     ///< -40..0, every leaf's
    std::int8_t v_exponent = 0;     ///< -40..0, every leaf's
    std::vector<BatchLeaf> leaves;  ///< 1..k_max_batch_leaves, body at most 1,200 bytes
    friend bool operator==(const LeafBatch&, const LeafBatch&) = default;
};

/// One leaf of a ValueBatch: its u and v, as many of each (the batch's encoding and coarsening).
struct ValueLeaf
{
    WireLeafId leaf;        ///< at the batch's depth
    std::vector<double> u;  ///< m
    std::vector<double> v;  ///< m/s
    friend bool operator==(const ValueLeaf&, const ValueLeaf&) = default;
};

/// f32 or f64 states of several whole leaves of one sender at one tick and time, in one datagram
/// (docs/protocol.md §6 ValueBatch, version 6): what a LeafState of encoding 1 or 2 and node
/// offset 0 carries, with its 48 fixed bytes paid once per datagram. Coarse streaming sends its
/// few nodes per leaf this way (docs/session.md §5.2). Every leaf has the batch's depth.
struct ValueBatch
{
    std::uint32_t epoch = 0;
    double time = 0.0;                            ///< s
    ValueEncoding encoding = ValueEncoding::F64;  ///< F32 or F64
    std::uint8_t coarsen = 0;                     ///< 0..3, as LeafState::coarsen
    std::vector<ValueLeaf> leaves;  ///< 1..k_max_batch_leaves, body at most 1,200 bytes
    friend bool operator==(const ValueBatch&, const ValueBatch&) = default;
};

/// The sender holds the session's model and state: leaf states may be streamed to it
/// (docs/protocol.md, Ready). No body.
struct Ready
{
    friend bool operator==(const Ready&, const Ready&) = default;
};

using Body = std::variant<Hello, Welcome, Reject, PeerJoined, PeerLeft, Blob, PointsOfInterest,
                          Partition, Force, Leave, LeafState, Halo, Heartbeat, Ping, Pong, Ack,
                          LeafBatch, Ready, ValueBatch>;
static_assert(std::variant_size_v<Body> == k_message_type_count);

/// Fields every datagram carries besides its type (docs/protocol.md §4).
struct Header
{
    std::uint32_t session = 0;  ///< 0 only in Hello and Reject
    PeerId sender = k_no_peer;  ///< k_no_peer only in Hello
    std::uint16_t sequence = 0;
    std::uint64_t tick = 0;
    friend bool operator==(const Header&, const Header&) = default;
};

struct Message
{
    Header header;
    Body body;

    [[nodiscard]] MessageType type() const noexcept
    {
        return static_cast<MessageType>(body.index() + 1);
    }
    friend bool operator==(const Message&, const Message&) = default;
};

/// The channel a message type travels on by default (docs/protocol.md §2).
[[nodiscard]] constexpr Channel default_channel(MessageType type) noexcept
{
    return type != MessageType::Ready && static_cast<std::uint8_t>(type) >=
                                             static_cast<std::uint8_t>(MessageType::LeafState)
               ? Channel::State
               : Channel::Control;
}

/// Whether a message of this type may arrive on `channel`: control types only on channel 0, except
/// the greetings Ready and Hello, whose unreliable repeats travel on channel 1; state types on
/// either (the exact coupling mode sends halos reliably).
[[nodiscard]] constexpr bool allowed_on(MessageType type, Channel channel) noexcept
{
    return channel == Channel::Control || type == MessageType::Ready ||
           type == MessageType::Hello || default_channel(type) == Channel::State;
}

/// Short stable name, e.g. "leaf-state".
[[nodiscard]] std::string_view to_string(MessageType type) noexcept;

}  // namespace pliant::net
