// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The codec against docs/protocol.md for the 13 message types that codec_test.cpp only round-trips
// (Hello, Welcome, Reject, PeerJoined, PeerLeft, Blob, PointsOfInterest, Partition, Force, Leave,
// Halo, Heartbeat, Pong). Each test writes one datagram by hand, field by field, from the
// specification's tables (the header of §4, the structures and codes of §5, the type's table in
// §6), with a little-endian byte writer of this file's own (not the codec's ByteWriter), and
// proves that encode() gives exactly those bytes and that decode() of those bytes gives the
// message back. Field values are distinct and non-zero, so a swapped, mis-sized or mis-ordered
// field fails here even where an encoder and decoder that agree with each other round-trip it;
// floats are written from IEEE-754 bit patterns worked out by hand (checked against the values).

#include <pliant/net/codec.h>

#include <gtest/gtest.h>

#include "net/encode_vec.h"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <ios>
#include <string_view>
#include <vector>

namespace pliant::net::codec_spec
{
namespace
{

/// Bytes written field by field, every integer and float little-endian (docs/protocol.md §1).
/// Floats are given as their bit patterns, worked out by hand; f32()/f64() also check that the
/// pattern is the value's, so a slip in the hand arithmetic is reported as such.
class SpecBytes
{
public:
    SpecBytes& u8(std::uint64_t v) { return le(v, 1); }
    SpecBytes& u16(std::uint64_t v) { return le(v, 2); }
    SpecBytes& u32(std::uint64_t v) { return le(v, 4); }
    SpecBytes& u64(std::uint64_t v) { return le(v, 8); }
    SpecBytes& zeros(std::size_t n)
    {
        bytes_.insert(bytes_.end(), n, std::byte{0});
        return *this;
    }
    /// Bytes in the order given (an address in network order, opaque blob bytes).
    SpecBytes& u8s(std::initializer_list<int> values)
    {
        for (const int v : values)
            u8(static_cast<std::uint64_t>(v));
        return *this;
    }
    SpecBytes& text(std::string_view s)
    {
        for (const char c : s)
            bytes_.push_back(static_cast<std::byte>(c));
        return *this;
    }
    /// binary32: `value` must be exact in f32 and have the bits `hand_bits`.
    SpecBytes& f32(double value, std::uint32_t hand_bits)
    {
        const auto f = static_cast<float>(value);
        EXPECT_EQ(static_cast<double>(f), value) << "test value not exact in f32";
        EXPECT_EQ(std::bit_cast<std::uint32_t>(f), hand_bits)
            << "hand-written f32 bits of " << value;
        return le(hand_bits, 4);
    }
    /// binary64: `value` must have the bits `hand_bits`.
    SpecBytes& f64(double value, std::uint64_t hand_bits)
    {
        EXPECT_EQ(std::bit_cast<std::uint64_t>(value), hand_bits)
            << "hand-written f64 bits of " << value;
        return le(hand_bits, 8);
    }
    [[nodiscard]] const std::vector<std::byte>& bytes() const noexcept { return bytes_; }
    [[nodiscard]] std::size_t size() const noexcept { return bytes_.size(); }

private:
    SpecBytes& le(std::uint64_t v, int n)
    {
        if (n < 8 && (v >> (8 * n)) != 0)
            ADD_FAILURE() << "test bug: " << v << " does not fit " << n << " bytes";
        for (int i = 0; i < n; ++i)
            bytes_.push_back(static_cast<std::byte>((v >> (8 * i)) & 0xFFu));
        return *this;
    }
    std::vector<std::byte> bytes_;
};

/// The 24-byte header (docs/protocol.md §4), `type` the number from §6's table.
SpecBytes spec_header(std::uint8_t type, const Header& h)
{
    SpecBytes b;
    b.u8s({0x50, 0x4C, 0x4E, 0x54})  // 0: protocol id 0x544E4C50, bytes 50 4C 4E 54 ("PLNT")
        .u8(6)                       // 4: version = 6
        .u8(type)                    // 5: message type
        .u8(0)                       // 6: flags, reserved
        .u8(0)                       // 7: reserved
        .u32(h.session)              // 8: session id
        .u16(h.sender.value)         // 12: sender peer id
        .u16(h.sequence)             // 14: sequence
        .u64(h.tick);                // 16: tick
    EXPECT_EQ(b.size(), std::size_t{24});
    return b;
}

std::vector<std::byte> byte_vector(std::initializer_list<int> values)
{
    std::vector<std::byte> out;
    for (const int v : values)
        out.push_back(static_cast<std::byte>(v));
    return out;
}

/// (a) encode(m) is exactly `expected` (reporting the first differing offset), and (b) decode()
/// of `expected` gives back m's header and every field of its body (the body structs' defaulted
/// operator== compares each field).
void expect_matches_spec(const Message& m, const SpecBytes& spec, std::size_t spec_body_size)
{
    const std::vector<std::byte>& expected = spec.bytes();
    ASSERT_EQ(expected.size(), k_header_size + spec_body_size)
        << "test bug: the hand-written body does not have the size §6's table gives";
    const std::vector<std::byte> actual = test::encode_vec(m);
    EXPECT_EQ(actual.size(), expected.size()) << "encoded datagram length";
    const auto [a, e] =
        std::mismatch(actual.begin(), actual.end(), expected.begin(), expected.end());
    if (a != actual.end() && e != expected.end())
    {
        const auto at = static_cast<std::size_t>(a - actual.begin());
        ADD_FAILURE() << "encode() differs from docs/protocol.md at datagram offset " << at
                      << (at >= k_header_size ? " (body offset " : " (header offset ")
                      << (at >= k_header_size ? at - k_header_size : at) << "): encoded 0x"
                      << std::hex << std::to_integer<int>(*a) << ", specified 0x"
                      << std::to_integer<int>(*e);
    }
    auto back = decode(expected);
    ASSERT_TRUE(back.has_value()) << "decode of the specified bytes: " << to_string(back.error());
    EXPECT_EQ(back->type(), m.type());
    EXPECT_EQ(back->header, m.header);
    EXPECT_TRUE(back->body == m.body) << "decode of the specified bytes gives another body";
}

TEST(CodecSpec, HelloMatchesBytesWrittenFromTheSpecification)
{
    // A joiner's first Hello: session 0 and sender 0xFFFF, allowed in Hello only (§4, rows
    // "8 | u32 | session id" and "12 | u16 | sender peer id").
    const Message m{.header = {.session = 0,
                               .sender = k_no_peer,
                               .sequence = 0x1357,
                               .tick = 0x0102030405060708ULL},
                    .body = Hello{.role = Role::Viewer, .listen_port = 0xC351, .name = "Ann-3 ~x"}};
    SpecBytes d = spec_header(1, m.header);  // §6: type 1 Hello
    d.u8(2)                                  // 0: role, 2 viewer
        .u8(8)                               // 1: name length n
        .u16(0xC351)        // 2: listen port, a u16 (§6 Hello, row "2 | u16 | listen port")
        .text("Ann-3 ~x");  // 4: name
    expect_matches_spec(m, d, 4 + 8);  // §6 table: body 4 + n
}

TEST(CodecSpec, WelcomeMatchesBytesWrittenFromTheSpecification)
{
    Welcome w{.your_id = PeerId{0x0312},
              .master_id = PeerId{0x0007},
              .grid_level = 9,
              .leaf_depth = 6,
              .epoch = 0x11223344u,
              .time = 2.25,
              .model_size = 0x00ABCDEFu,
              .model_hash = 0x8877665544332211ULL,
              .state_size = 0x00123456u,
              .state_hash = 0x0FEDCBA987654321ULL,
              .peers = {PeerInfo{.id = PeerId{0x0007},
                                 .role = Role::Participant,
                                 .ipv4 = {10, 20, 30, 40},
                                 .port = 0xA1B2,
                                 .name = "M"},
                        PeerInfo{.id = PeerId{0x0312},
                                 .role = Role::Viewer,
                                 .ipv4 = {198, 51, 100, 77},
                                 .port = 0x1F90,
                                 .name = "Joe~ 1"}}};
    const Message m{.header = {.session = 0x8A7B6C5Du,
                               .sender = PeerId{0x0007},
                               .sequence = 0x2468,
                               .tick = 0x00000A0B0C0D0E0FULL},
                    .body = w};
    SpecBytes d = spec_header(2, m.header);  // §6: type 2 Welcome
    d.u16(0x0312)                            // 0: your peer id
        .u16(0x0007)                         // 2: master peer id
        .u8(9)                               // 4: grid level
        .u8(6)                               // 5: leaf depth
        .u8(2)                               // 6: peer count p
        .u8(0)                               // 7: reserved
        .u32(0x11223344)                     // 8: partition epoch
        // 12: simulation time, an f64 (§6 Welcome, row "12 | f64 | simulation time, s").
        .f64(2.25, 0x4002000000000000ULL)
        .u32(0x00ABCDEF)              // 20: model blob size, a u32
        .u64(0x8877665544332211ULL)   // 24: model blob hash, a u64
        .u32(0x00123456)              // 32: state blob size, a u32
        .u64(0x0FEDCBA987654321ULL);  // 36: state blob hash, a u64
    // 44: PeerInfo[p] (§5.1); the master first.
    d.u16(0x0007)                 // 0: peer id
        .u8(1)                    // 2: role, 1 participant
        .u8(4)                    // 3: address family 4
        .u8s({10, 20, 30, 40})    // 4: IPv4 a.b.c.d in network order (10.20.30.40)
        .zeros(12)                //    address bytes 4..15 zero
        .u16(0xA1B2)              // 20: port, a u16 (§5.1, row "20 | u16 | port")
        .u8(1)                    // 22: name length n
        .u8(0)                    // 23: reserved
        .text("M");               // 24: name
    d.u16(0x0312)                 // 0: peer id (the joiner)
        .u8(2)                    // 2: role, 2 viewer
        .u8(4)                    // 3: address family 4
        .u8s({198, 51, 100, 77})  // 4: 198.51.100.77
        .zeros(12)
        .u16(0x1F90)  // 20: port
        .u8(6)        // 22: name length n
        .u8(0)        // 23: reserved
        .text("Joe~ 1");
    expect_matches_spec(m, d, 44 + (24 + 1) + (24 + 6));  // §6 table: 44 + Σ PeerInfo
}

TEST(CodecSpec, RejectMatchesBytesWrittenFromTheSpecification)
{
    // Session 0 is allowed in Reject (§4, row "8 | u32 | session id").
    const Message m{.header = {.session = 0,
                               .sender = PeerId{0x0009},
                               .sequence = 0x0A0B,
                               .tick = 0x1112131415161718ULL},
                    .body = Reject{.reason = DisconnectReason::SessionFull}};
    SpecBytes d = spec_header(3, m.header);  // §6: type 3 Reject
    d.u8(8)                                  // 0: reason, 8 session full (§5.3)
        .zeros(3);                           // 1: reserved
    expect_matches_spec(m, d, 4);
}

TEST(CodecSpec, PeerJoinedMatchesBytesWrittenFromTheSpecification)
{
    const Message m{.header = {.session = 0x0BADF00Du,
                               .sender = PeerId{0x0004},
                               .sequence = 0x0102,
                               .tick = 0x2122232425262728ULL},
                    .body = PeerJoined{.peer = PeerInfo{.id = PeerId{0x0A0B},
                                                        .role = Role::Viewer,
                                                        .ipv4 = {203, 0, 113, 9},
                                                        .port = 0xD431,
                                                        .name = "dave@lab"}}};
    SpecBytes d = spec_header(4, m.header);  // §6: type 4 PeerJoined, one PeerInfo (§5.1)
    d.u16(0x0A0B)                            // 0: peer id, a u16
        .u8(2)                               // 2: role, 2 viewer
        .u8(4)                               // 3: address family 4 (IPv4)
        .u8s({203, 0, 113, 9})               // 4: IPv4 in bytes 0..3, network order (203.0.113.9)
        .zeros(12)                           //    bytes 4..15 of the address zero
        .u16(0xD431)                         // 20: port, a u16 (§5.1, row "20 | u16 | port")
        .u8(8)                               // 22: name length n
        .u8(0)                               // 23: reserved
        .text("dave@lab");
    expect_matches_spec(m, d, 24 + 8);  // §5.1: 24 + name bytes
}

TEST(CodecSpec, PeerLeftMatchesBytesWrittenFromTheSpecification)
{
    const Message m{.header = {.session = 0x31415926u,
                               .sender = PeerId{0x0005},
                               .sequence = 0x0304,
                               .tick = 0x3132333435363738ULL},
                    .body = PeerLeft{.peer = PeerId{0x0C0D}, .reason = DisconnectReason::Kicked}};
    SpecBytes d = spec_header(5, m.header);  // §6: type 5 PeerLeft
    d.u16(0x0C0D)  // 0: peer id, a u16 (§6 PeerLeft, "0 | u16 | peer id")
        .u8(9)     // 2: reason, 9 kicked (§5.3)
        .u8(0);    // 3: reserved
    expect_matches_spec(m, d, 4);
}

TEST(CodecSpec, BlobMatchesBytesWrittenFromTheSpecification)
{
    const Message m{.header = {.session = 0x27182818u,
                               .sender = PeerId{0x0006},
                               .sequence = 0x0506,
                               .tick = 0x4142434445464748ULL},
                    .body = Blob{.kind = BlobKind::State,
                                 .total_size = 0x00054321u,
                                 .offset = 0x00012340u,
                                 .data = byte_vector({0xDE, 0xAD, 0xBE, 0xEF, 0x01})}};
    SpecBytes d = spec_header(6, m.header);  // §6: type 6 Blob
    d.u8(2)                                  // 0: kind, 2 state
        .u8(0)                               // 1: reserved
        // 2: chunk length, a u16 (§6 Blob, row "2 | u16 | chunk length len").
        .u16(5)
        .u32(0x00054321)                       // 4: total size, a u32
        .u32(0x00012340)                       // 8: offset of this chunk, a u32
        .u8s({0xDE, 0xAD, 0xBE, 0xEF, 0x01});  // 12: the bytes
    expect_matches_spec(m, d, 12 + 5);         // §6 table: 12 + len
}

TEST(CodecSpec, PointsOfInterestMatchesBytesWrittenFromTheSpecification)
{
    const Message m{.header = {.session = 0x16180339u,
                               .sender = PeerId{0x0011},
                               .sequence = 0x0708,
                               .tick = 0x5152535455565758ULL},
                    .body = PointsOfInterest{.points = {Target{.kind = TargetKind::Face,
                                                               .face = 0x00123456u,
                                                               .position = {0.0, 0.0, 0.0},
                                                               .radius = 0.75},
                                                        Target{.kind = TargetKind::Position,
                                                               .face = 0,
                                                               .position = {1.5, -0.375, 2.25},
                                                               .radius = 0.125}}}};
    SpecBytes d = spec_header(7, m.header);  // §6: type 7 PointsOfInterest
    d.u8(2)                                  // 0: count k
        .zeros(3);                           // 1: reserved
    // 4: entry[k], 40 bytes each. Position and radius are f64s (§6 PointsOfInterest, rows
    // "+8 | f64[3] | position" and "+32 | f64 | radius").
    d.u8(1)                                  // +0: kind, 1 face
        .zeros(3)                            // +1: reserved
        .u32(0x00123456)                     // +4: face index, a u32
        .zeros(24)                           // +8: position, all zero for a face
        .f64(0.75, 0x3FE8000000000000ULL);   // +32: radius
    d.u8(2)                                  // +0: kind, 2 position
        .zeros(3)                            // +1: reserved
        .u32(0)                              // +4: face index, 0 for a position
        .f64(1.5, 0x3FF8000000000000ULL)     // +8: x
        .f64(-0.375, 0xBFD8000000000000ULL)  // +16: y
        .f64(2.25, 0x4002000000000000ULL)    // +24: z
        .f64(0.125, 0x3FC0000000000000ULL);  // +32: radius
    expect_matches_spec(m, d, 4 + 40 * 2);   // §6 table: 4 + 40 k
}

TEST(CodecSpec, PartitionMatchesBytesWrittenFromTheSpecification)
{
    Partition p{.epoch = 0x0A0B0C0Du, .leaf_depth = 1, .owners = {}};
    for (std::uint16_t i = 0; i < 8; ++i)  // 2 * 4^1 leaves: owners 0x0001, 0x0102, ..., 0x0708
        p.owners.push_back(PeerId{static_cast<std::uint16_t>((i << 8) | (i + 1))});
    const Message m{.header = {.session = 0x14142135u,
                               .sender = PeerId{0x0000},
                               .sequence = 0x090A,
                               .tick = 0x6162636465666768ULL},
                    .body = p};
    SpecBytes d = spec_header(8, m.header);  // §6: type 8 Partition
    d.u32(0x0A0B0C0D)                        // 0: epoch
        .u8(1)                               // 4: leaf depth d
        .zeros(3);                           // 5: reserved
    // 8: owner of each leaf, 2 * 4^d u16s in leaf-index order (§6 Partition, row
    // "8 | u16[2·4^d] | owner of each leaf").
    for (const std::uint64_t owner :
         {0x0001u, 0x0102u, 0x0203u, 0x0304u, 0x0405u, 0x0506u, 0x0607u, 0x0708u})
        d.u16(owner);
    expect_matches_spec(m, d, 8 + 4 * 4);  // §6 table: 8 + 4·4^depth
}

TEST(CodecSpec, ForceMatchesBytesWrittenFromTheSpecification)
{
    const Message m{
        .header = {.session = 0x17320508u,
                   .sender = PeerId{0x0012},
                   .sequence = 0x0B0C,
                   .tick = 0x7172737475767778ULL},
        .body = Force{.forces = {UserForce{.target = Target{.kind = TargetKind::Face,
                                                            .face = 0x0003A0B1u,
                                                            .position = {0.0, 0.0, 0.0},
                                                            .radius = 0.75},
                                           .grab_id = 0xBEEF,
                                           .force = {1.5, -6.5, 12.25}},
                                 UserForce{.target = Target{.kind = TargetKind::Position,
                                                            .face = 0,
                                                            .position = {-0.375, 2.25, 1.5},
                                                            .radius = 0.125},
                                           .grab_id = 0x0102,
                                           .force = {-0.375, 0.75, -6.5}}}}};
    SpecBytes d = spec_header(9, m.header);  // §6: type 9 Force
    d.u8(2)                                  // 0: count k
        .zeros(3);                           // 1: reserved
    // 4: entry[k], 64 bytes each. The grab id is a u16 at +2 after one reserved byte (§6 Force,
    // rows "+1 | u8 | reserved" and "+2 | u16 | grab id"); position, radius and force are f64s
    // (rows "+8 | f64[3]", "+32 | f64", "+40 | f64[3] | force, N").
    d.u8(1)                                  // +0: kind, 1 face
        .u8(0)                               // +1: reserved
        .u16(0xBEEF)                         // +2: grab id
        .u32(0x0003A0B1)                     // +4: face index
        .zeros(24)                           // +8: position, zero for a face
        .f64(0.75, 0x3FE8000000000000ULL)    // +32: radius
        .f64(1.5, 0x3FF8000000000000ULL)     // +40: force x
        .f64(-6.5, 0xC01A000000000000ULL)    // +48: force y
        .f64(12.25, 0x4028800000000000ULL);  // +56: force z
    d.u8(2)                                  // +0: kind, 2 position
        .u8(0)                               // +1: reserved
        .u16(0x0102)                         // +2: grab id
        .u32(0)                              // +4: face index, 0 for a position
        .f64(-0.375, 0xBFD8000000000000ULL)  // +8: x
        .f64(2.25, 0x4002000000000000ULL)    // +16: y
        .f64(1.5, 0x3FF8000000000000ULL)     // +24: z
        .f64(0.125, 0x3FC0000000000000ULL)   // +32: radius
        .f64(-0.375, 0xBFD8000000000000ULL)  // +40: force x
        .f64(0.75, 0x3FE8000000000000ULL)    // +48: force y
        .f64(-6.5, 0xC01A000000000000ULL);   // +56: force z
    expect_matches_spec(m, d, 4 + 64 * 2);   // §6 table: 4 + 64 k
}

TEST(CodecSpec, LeaveMatchesBytesWrittenFromTheSpecification)
{
    const Message m{.header = {.session = 0x22360679u,
                               .sender = PeerId{0x0013},
                               .sequence = 0x0D0E,
                               .tick = 0x8182838485868788ULL},
                    .body = Leave{.reason = DisconnectReason::Shutdown}};
    SpecBytes d = spec_header(10, m.header);  // §6: type 10 Leave
    d.u8(2)                                   // 0: reason, 2 shutdown (§5.3)
        .zeros(3);                            // 1: reserved
    expect_matches_spec(m, d, 4);
}

TEST(CodecSpec, HaloMatchesBytesWrittenFromTheSpecification)
{
    const Header h{.session = 0x26457513u,
                   .sender = PeerId{0x0014},
                   .sequence = 0x0F10,
                   .tick = 0x9192939495969798ULL};
    {
        // What the session sends (§6 Halo): stage 6, f64, u and v.
        const Message m{.header = h,
                        .body = Halo{.epoch = 0x13579BDFu,
                                     .stage = 6,
                                     .encoding = ValueEncoding::F64,
                                     .time = 12.25,
                                     .ranges = {NodeRange{.first = 0x00012345u, .count = 2},
                                                NodeRange{.first = 0x001F0000u, .count = 1}},
                                     .has_u = true,
                                     .has_v = true,
                                     .u = {1.5, -0.375, 2.25},
                                     .v = {-6.5, 0.75, 0.125}}};
        SpecBytes d = spec_header(12, h);  // §6: type 12 Halo
        d.u32(0x13579BDF)                  // 0: partition epoch
            .u8(6)                         // 4: stage, 6 the accepted step
            .u8(2)                         // 5: encoding, 2 f64 (§5.4)
            .u8(3)                         // 6: fields, bit 0 u | bit 1 v
            .u8(2)                         // 7: range count r
            // 8: simulation time, an f64 whatever the encoding (§6 Halo, "8 | f64 | simulation
            // time").
            .f64(12.25, 0x4028800000000000ULL);
        // 16: range[r], 8 bytes each: u32 first, u16 count, u16 reserved (§6 Halo, row "16 |
        // range[r]").
        d.u32(0x00012345).u16(2).u16(0);
        d.u32(0x001F0000).u16(1).u16(0);
        // 16 + 8 r: u of all ranges, then v, each value of the encoding's size: 8 bytes for f64
        // (§5.4; §6 Halo, row "16 + 8 r | s[N] per field").
        d.f64(1.5, 0x3FF8000000000000ULL)
            .f64(-0.375, 0xBFD8000000000000ULL)
            .f64(2.25, 0x4002000000000000ULL);
        d.f64(-6.5, 0xC01A000000000000ULL)
            .f64(0.75, 0x3FE8000000000000ULL)
            .f64(0.125, 0x3FC0000000000000ULL);
        expect_matches_spec(m, d, 16 + 8 * 2 + 2 * 3 * 8);  // §6 table: 16 + 8 r + f N s
    }
    {
        // f32 and v alone: valid on the wire (§6 Halo), if not what pliant sends.
        const Message m{.header = h,
                        .body = Halo{.epoch = 0x02468ACEu,
                                     .stage = 2,
                                     .encoding = ValueEncoding::F32,
                                     .time = 0.75,
                                     .ranges = {NodeRange{.first = 0x00000305u, .count = 2}},
                                     .has_u = false,
                                     .has_v = true,
                                     .u = {},
                                     .v = {-1.75, 2.5}}};
        SpecBytes d = spec_header(12, h);
        d.u32(0x02468ACE)                      // 0: partition epoch
            .u8(2)                             // 4: stage 2
            .u8(1)                             // 5: encoding, 1 f32 (§5.4)
            .u8(2)                             // 6: fields, bit 1 v only
            .u8(1)                             // 7: range count r
            .f64(0.75, 0x3FE8000000000000ULL)  // 8: simulation time, still an f64
            .u32(0x00000305)
            .u16(2)
            .u16(0);  // 16: the range
        // 24: v only, 4 bytes per value with f32 (§5.4: 1 f32; §6 table: s is 4 for f32).
        d.f32(-1.75, 0xBFE00000u).f32(2.5, 0x40200000u);
        expect_matches_spec(m, d, 16 + 8 * 1 + 1 * 2 * 4);
    }
}

TEST(CodecSpec, HeartbeatMatchesBytesWrittenFromTheSpecification)
{
    const Message m{.header = {.session = 0x44948974u,
                               .sender = PeerId{0x0015},
                               .sequence = 0x1112,
                               .tick = 0xA1A2A3A4A5A6A7A8ULL},
                    .body = Heartbeat{.epoch = 0x89ABCDEFu}};
    SpecBytes d = spec_header(13, m.header);  // §6: type 13 Heartbeat
    // 0: the partition epoch the sender uses, a u32 (§6 Heartbeat, row "0 | u32 | partition
    // epoch the sender uses"); the tick it reports is the header's.
    d.u32(0x89ABCDEF);
    expect_matches_spec(m, d, 4);
}

TEST(CodecSpec, PongMatchesBytesWrittenFromTheSpecification)
{
    const Message m{.header = {.session = 0x57721566u,
                               .sender = PeerId{0x0016},
                               .sequence = 0x1314,
                               .tick = 0xB1B2B3B4B5B6B7B8ULL},
                    .body = Pong{.nonce = 0x31323334u, .time_us = 0x4142434445464748ULL}};
    SpecBytes d = spec_header(15, m.header);  // §6: type 15 Pong (14 is Ping)
    // §6 Ping and Pong: "0 | u32 | nonce", "4 | u32 | reserved", "8 | u64 | ... the echoed Ping
    // clock".
    d.u32(0x31323334)                 // 0: nonce, echoed from the Ping
        .u32(0)                       // 4: reserved
        .u64(0x4142434445464748ULL);  // 8: the Ping's clock, µs
    expect_matches_spec(m, d, 16);
}

}  // namespace
}  // namespace pliant::net::codec_spec
