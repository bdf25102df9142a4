// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The codec against docs/protocol.md: round trips of every message type, bytes written by hand from
// the specification (independent of the encoder), every truncation and extension, one crafted
// datagram per decode error, and 100,000 random and corrupted datagrams.

#include <pliant/net/codec.h>

#include <gtest/gtest.h>

#include "net/encode_vec.h"
#include "net/sample_messages.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <set>

namespace pliant::net
{
namespace
{

using test::encode_vec;

const Message& first_of(MessageType type)
{
    static const std::vector<Message> all = samples::all();
    for (const Message& m : all)
        if (m.type() == type)
            return m;
    ADD_FAILURE() << "no sample of type " << to_string(type);
    return all.front();
}

std::vector<std::byte> bytes_of(std::initializer_list<int> values)
{
    std::vector<std::byte> out;
    for (int v : values)
        out.push_back(static_cast<std::byte>(v));
    return out;
}

void put_le(std::vector<std::byte>& d, std::size_t offset, std::uint64_t value, int n)
{
    for (int i = 0; i < n; ++i)
        d[offset + static_cast<std::size_t>(i)] = static_cast<std::byte>((value >> (8 * i)) & 0xFF);
}

DecodeError decode_error(const std::vector<std::byte>& d)
{
    auto r = decode(d);
    EXPECT_FALSE(r.has_value());
    return r ? DecodeError::TooShort : r.error();
}

TEST(Codec, SamplesCoverEveryMessageType)
{
    std::set<MessageType> types;
    for (const Message& m : samples::all())
    {
        EXPECT_FALSE(validate(m).has_value())
            << to_string(m.type()) << " " << to_string(validate(m).value_or(DecodeError::TooShort));
        types.insert(m.type());
    }
    EXPECT_EQ(types.size(), std::size_t{k_message_type_count});
}

TEST(Codec, EveryMessageRoundTrips)
{
    for (const Message& m : samples::all())
    {
        const auto bytes = encode_vec(m);
        auto back = decode(bytes);
        ASSERT_TRUE(back.has_value()) << to_string(m.type()) << ": " << to_string(back.error());
        EXPECT_EQ(*back, m) << to_string(m.type());
        EXPECT_EQ(encode_vec(*back), bytes) << "re-encoding must give the same bytes";
    }
}

TEST(Codec, LeafStatePayloadLimitsMatchTheSpecification)
{
    // docs/protocol.md §3: 73 nodes in f64, 147 in f32, body <= 1,200 bytes, and one more node
    // is refused.
    for (auto [enc, n] : {std::pair{ValueEncoding::F64, std::size_t{73}},
                          std::pair{ValueEncoding::F32, std::size_t{147}}})
    {
        Message m{samples::header(), samples::leaf_state(enc, n)};
        EXPECT_LE(encoded_size(m) - k_header_size, k_max_state_payload);
        EXPECT_FALSE(validate(m).has_value());
        Message over{samples::header(), samples::leaf_state(enc, n + 1)};
        EXPECT_EQ(validate(over), DecodeError::BadCount);
        std::vector<std::byte> buf(4096);
        auto r = encode(over, buf);
        ASSERT_FALSE(r.has_value());
        EXPECT_EQ(r.error(), EncodeError::InvalidMessage);
    }
}

TEST(Codec, PingMatchesBytesWrittenFromTheSpecification)
{
    Message m{.header = {.session = 0x04030201u,
                         .sender = PeerId{0x0605},
                         .sequence = 0x0807,
                         .tick = 0x100F0E0D0C0B0A09ULL},
              .body = Ping{.nonce = 0x14131211u, .time_us = 0x201F1E1D1C1B1A19ULL}};
    const auto expected = bytes_of({0x50, 0x4C, 0x4E, 0x54,  // "PLNT"
                                    6,    14,   0,    0,     // version, type Ping, flags, reserved
                                    0x01, 0x02, 0x03, 0x04,  // session
                                    0x05, 0x06, 0x07, 0x08,  // sender, sequence
                                    0x09, 0x0A, 0x0B, 0x0C, 0x0D, 0x0E, 0x0F, 0x10,  // tick
                                    0x11, 0x12, 0x13, 0x14, 0,    0,    0,    0,     // nonce, res.
                                    0x19, 0x1A, 0x1B, 0x1C, 0x1D, 0x1E, 0x1F, 0x20});
    EXPECT_EQ(encode_vec(m), expected);
    auto back = decode(expected);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(*back, m);
}

TEST(Codec, LeafBatchMatchesBytesWrittenFromTheSpecification)
{
    // One leaf (square 1, depth 2, ix 3, iy 1: index (1 * 4 + 1) * 4 + 3 = 23) of one node,
    // du = 0, dv = -1, Rice-packed: u's parameter 0 (5 bits) and value 0 ("0"), v's parameter 0
    // and zigzag(-1) = 1 ("10"): 13 bits, bit 11 set -> bytes 0x00 0x08. Baseline 300 -> LEB128
    // 0xAC 0x02.
    LeafBatch b;
    b.epoch = 0x01020304u;
    b.time = 0.5;
    b.u_exponent = -12;
    b.v_exponent = -8;
    BatchLeaf l;
    l.leaf = WireLeafId{.square = 1, .depth = 2, .ix = 3, .iy = 1};
    l.quantised.baseline = 300;
    l.quantised.u_exponent = -12;
    l.quantised.v_exponent = -8;
    l.quantised.extrapolated = true;
    l.quantised.packing = Packing::Rice;
    l.quantised.du = {0};
    l.quantised.dv = {-1};
    l.quantised.packed = bytes_of({0x00, 0x08});
    b.leaves.push_back(l);
    Message m{.header = {.session = 7, .sender = PeerId{2}, .sequence = 0, .tick = 9}, .body = b};
    const auto expected =
        bytes_of({0x50, 0x4C, 0x4E, 0x54, 6, 17, 0,    0,     // "PLNT" v6 LeafBatch
                  7,    0,    0,    0,    2, 0,  0,    0,     // session, sender, seq.
                  9,    0,    0,    0,    0, 0,  0,    0,     // tick
                  0x04, 0x03, 0x02, 0x01,                     // epoch
                  0,    0,    0,    0,    0, 0,  0xE0, 0x3F,  // time 0.5
                  0xF4, 0xF8, 2,    1,                        // exponents, depth, count
                  23,   0,    1,                              // index, nodes
                  0x02, 0x60,                                 // length 2, rice, extrap.
                  0xAC, 0x02,                                 // baseline 300
                  0x00, 0x08});                               // the Rice bits
    EXPECT_EQ(encode_vec(m), expected);
    auto back = decode(expected);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(*back, m);
}

TEST(Codec, ValueBatchMatchesBytesWrittenFromTheSpecification)
{
    // Two leaves at depth 1 (indices (0 * 2 + 1) * 2 + 1 = 3 and (1 * 2 + 0) * 2 + 0 = 4), f32,
    // coarsened once: one node (u 1.0, v -2.0), then two (u 0.5, 0.25; v 0, 4).
    ValueBatch b;
    b.epoch = 0x01020304u;
    b.time = 0.5;
    b.encoding = ValueEncoding::F32;
    b.coarsen = 1;
    b.leaves = {ValueLeaf{.leaf = WireLeafId{0, 1, 1, 1}, .u = {1.0}, .v = {-2.0}},
                ValueLeaf{.leaf = WireLeafId{1, 1, 0, 0}, .u = {0.5, 0.25}, .v = {0.0, 4.0}}};
    Message m{.header = {.session = 7, .sender = PeerId{2}, .sequence = 0, .tick = 9}, .body = b};
    const auto expected =
        bytes_of({0x50, 0x4C, 0x4E, 0x54, 6, 19, 0,    0,       // "PLNT" v6 ValueBatch
                  7,    0,    0,    0,    2, 0,  0,    0,       // session, sender, seq.
                  9,    0,    0,    0,    0, 0,  0,    0,       // tick
                  0x04, 0x03, 0x02, 0x01,                       // epoch
                  0,    0,    0,    0,    0, 0,  0xE0, 0x3F,    // time 0.5
                  1,    1,    1,    2,                          // f32, coarsen 1, depth 1, count 2
                  3,    0,    1,                                // index 3, one node
                  0,    0,    0x80, 0x3F,                       // u 1.0f
                  0,    0,    0,    0xC0,                       // v -2.0f
                  4,    0,    2,                                // index 4, two nodes
                  0,    0,    0,    0x3F, 0, 0,  0x80, 0x3E,    // u 0.5f, 0.25f
                  0,    0,    0,    0,    0, 0,  0x80, 0x40});  // v 0.0f, 4.0f
    EXPECT_EQ(encode_vec(m), expected);
    auto back = decode(expected);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(*back, m);
    EXPECT_TRUE(allowed_on(MessageType::ValueBatch, Channel::State));
    EXPECT_EQ(to_string(MessageType::ValueBatch), "value-batch");

    // Every field validated, on decode as on encode.
    const auto bad = [&](std::size_t at, std::uint8_t value)
    {
        auto d = expected;
        d[at] = std::byte{value};
        return decode_error(d);
    };
    EXPECT_EQ(bad(36, 3), DecodeError::BadEnum);  // encoding 3: quantised deltas go in LeafBatch
    EXPECT_EQ(bad(36, 0), DecodeError::BadEnum);
    EXPECT_EQ(bad(37, 4), DecodeError::BadRange);  // coarsen > 3
    EXPECT_EQ(bad(38, 8), DecodeError::BadRange);  // depth > 7
    EXPECT_EQ(bad(39, 0), DecodeError::BadCount);
    EXPECT_EQ(bad(40, 8), DecodeError::BadRange);      // index >= 2 * 4^1
    EXPECT_EQ(bad(42, 0), DecodeError::BadCount);      // a leaf of no nodes
    EXPECT_EQ(bad(46, 0xFF), DecodeError::NonFinite);  // u = NaN (0x7FC00000 | sign bit)
    auto shorter = expected;
    shorter.pop_back();
    EXPECT_EQ(decode_error(shorter), DecodeError::BadLength);
    auto longer = expected;
    longer.push_back(std::byte{0});
    EXPECT_EQ(decode_error(longer), DecodeError::BadLength);
    ValueBatch mixed = b;  // every leaf at the batch's depth
    mixed.leaves[1].leaf.depth = 2;
    EXPECT_TRUE(validate(Message{m.header, mixed}).has_value());
    ValueBatch uneven = b;
    uneven.leaves[0].v.push_back(1.0);
    EXPECT_EQ(validate(Message{m.header, uneven}), DecodeError::BadCount);
    ValueBatch over = b;  // more than one datagram: 16 + 10 * (3 + 2 * 73 * 8) > 1,200
    over.encoding = ValueEncoding::F64;
    over.leaves.assign(2, ValueLeaf{.leaf = WireLeafId{0, 1, 0, 0},
                                    .u = std::vector<double>(73, 0.0),
                                    .v = std::vector<double>(73, 0.0)});
    EXPECT_EQ(validate(Message{m.header, over}), DecodeError::BadCount);
}

TEST(Codec, ReadyMatchesBytesWrittenFromTheSpecification)
{
    Message m{.header = {.session = 7, .sender = PeerId{2}, .sequence = 0, .tick = 9},
              .body = Ready{}};
    const auto expected = bytes_of({0x50, 0x4C, 0x4E, 0x54, 6, 18, 0, 0,    // "PLNT" v6 Ready
                                    7,    0,    0,    0,    2, 0,  0, 0,    // session, sender, seq.
                                    9,    0,    0,    0,    0, 0,  0, 0});  // tick; no body
    EXPECT_EQ(encode_vec(m), expected);
    auto back = decode(expected);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(*back, m);
    // Reliable on the control channel by default; its repeats may come on the state channel, as
    // a dialler's Hello repeats do: the only control types allowed there.
    EXPECT_EQ(default_channel(MessageType::Ready), Channel::Control);
    EXPECT_TRUE(allowed_on(MessageType::Ready, Channel::State));
    EXPECT_EQ(default_channel(MessageType::Hello), Channel::Control);
    EXPECT_TRUE(allowed_on(MessageType::Hello, Channel::State));
    for (const MessageType t :
         {MessageType::Welcome, MessageType::Reject, MessageType::PeerJoined, MessageType::PeerLeft,
          MessageType::Blob, MessageType::Partition, MessageType::Force, MessageType::Leave})
        EXPECT_FALSE(allowed_on(t, Channel::State)) << to_string(t);
    EXPECT_TRUE(allowed_on(MessageType::LeafBatch, Channel::State));
    // Only members send it: a session id is required.
    auto d = expected;
    d[8] = std::byte{0};
    EXPECT_EQ(decode_error(d), DecodeError::BadSession);
}

TEST(Codec, AckMatchesBytesWrittenFromTheSpecification)
{
    // Two leaves at depth 1 (indices (0 * 2 + 1) * 2 + 0 = 2 and (1 * 2 + 0) * 2 + 1 = 5), ticks
    // 1000 (the newest) and 1000 - 200: ages 0 and 200 (LEB128 0xC8 0x01).
    Ack a;
    a.acks = {LeafAck{.leaf = WireLeafId{0, 1, 0, 1}, .tick = 1000},
              LeafAck{.leaf = WireLeafId{1, 1, 1, 0}, .tick = 800}};
    Message m{.header = {.session = 7, .sender = PeerId{2}, .sequence = 0, .tick = 9}, .body = a};
    const auto expected = bytes_of({0x50, 0x4C, 0x4E, 0x54, 6, 16, 0, 0,  // "PLNT" v6 Ack
                                    7,    0,    0,    0,    2, 0,  0, 0,  // session, sender, seq.
                                    9,    0,    0,    0,    0, 0,  0, 0,  // tick
                                    2,    1,    0,    0,                  // count, depth, reserved
                                    0xE8, 0x03, 0,    0,    0, 0,  0, 0,  // newest tick 1000
                                    2,    0,    0,                        // index 2, age 0
                                    5,    0,    0xC8, 0x01});             // index 5, age 200
    EXPECT_EQ(encode_vec(m), expected);
    auto back = decode(expected);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(*back, m);
    // No entry at the newest tick (ages 1 and 201): not canonical.
    auto d = expected;
    d[38] = std::byte{1};
    d[41] = std::byte{0xC9};
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    // An age beyond the newest tick.
    d = expected;
    d[41] = std::byte{0xE9};
    d[42] = std::byte{0x07};
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    // Leaves of two depths cannot share one Ack.
    a.acks[1].leaf = WireLeafId{1, 2, 1, 0};
    EXPECT_EQ(validate(Message{.header = m.header, .body = a}), DecodeError::BadRange);
}

TEST(Codec, LeafStateMatchesBytesWrittenFromTheSpecification)
{
    LeafState s;
    s.epoch = 0x01020304u;
    s.leaf = WireLeafId{.square = 1, .depth = 3, .ix = 5, .iy = 7};
    s.encoding = ValueEncoding::F32;
    s.node_offset = 2;
    s.time = 1.0;
    s.u = {1.0};
    s.v = {-2.0};
    Message m{samples::header(), s};
    const auto d = encode_vec(m);
    ASSERT_EQ(d.size(), std::size_t{24 + 24 + 8});
    const auto body = std::vector<std::byte>(d.begin() + 24, d.end());
    // f64 1.0 = 0x3FF0000000000000; f32 1.0 = 0x3F800000; f32 -2.0 = 0xC0000000.
    EXPECT_EQ(body,
              bytes_of({0x04, 0x03, 0x02, 0x01, 1, 3,    5,    0, 7, 0,    1,    0, 2, 0, 1,   0, 0,
                        0,    0,    0,    0,    0, 0xF0, 0x3F, 0, 0, 0x80, 0x3F, 0, 0, 0, 0xC0}));
    // Version 3: byte 11 is the coarsening (docs/protocol.md LeafState).
    s.coarsen = 2;
    const auto dc = encode_vec(Message{samples::header(), s});
    EXPECT_EQ(dc[24 + 11], std::byte{2});
    auto back = decode(dc);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(std::get<LeafState>(back->body).coarsen, 2);
    // Coarse states are f32/f64 only: a quantised one with coarsen != 0 is refused both ways.
    Message q{samples::header(), samples::quantised_leaf_state(16, 0, false)};
    std::get<LeafState>(q.body).coarsen = 1;
    EXPECT_EQ(validate(q), DecodeError::BadRange);
    std::get<LeafState>(q.body).coarsen = 0;
    auto dq = encode_vec(q);
    dq[24 + 11] = std::byte{1};
    EXPECT_EQ(decode_error(dq), DecodeError::BadRange);
}

TEST(Codec, EveryTruncationIsRejected)
{
    for (const Message& m : samples::all())
    {
        const auto d = encode_vec(m);
        for (std::size_t len = 0; len < d.size(); ++len)
        {
            auto r = decode(std::span(d.data(), len));
            ASSERT_FALSE(r.has_value()) << to_string(m.type()) << " length " << len;
            EXPECT_EQ(r.error(),
                      len < k_header_size ? DecodeError::TooShort : DecodeError::BadLength)
                << to_string(m.type()) << " length " << len << ": " << to_string(r.error());
        }
    }
}

TEST(Codec, EveryExtensionIsRejected)
{
    for (const Message& m : samples::all())
        for (int extra : {0x00, 0x01, 0xFF})
        {
            auto d = encode_vec(m);
            d.push_back(static_cast<std::byte>(extra));
            EXPECT_EQ(decode_error(d), DecodeError::BadLength) << to_string(m.type());
        }
}

TEST(Codec, HeaderErrors)
{
    const auto ping = encode_vec(first_of(MessageType::Ping));
    auto d = ping;
    EXPECT_EQ(decode_error(std::vector<std::byte>(d.begin(), d.begin() + 23)),
              DecodeError::TooShort);
    EXPECT_EQ(decode_error(std::vector<std::byte>(k_max_datagram_size + 1)), DecodeError::TooLarge);
    d[3] = std::byte{0x55};
    EXPECT_EQ(decode_error(d), DecodeError::BadMagic);
    d = ping;
    d[4] = std::byte{1};  // version 1 (before quantised leaf states)
    EXPECT_EQ(decode_error(d), DecodeError::BadVersion);
    d[4] = std::byte{2};  // version 2 (before coarse leaf states)
    EXPECT_EQ(decode_error(d), DecodeError::BadVersion);
    d[4] = std::byte{3};  // version 3 (before Rice packing and leaf batches)
    EXPECT_EQ(decode_error(d), DecodeError::BadVersion);
    d[4] = std::byte{4};  // version 4 (before Ready)
    EXPECT_EQ(decode_error(d), DecodeError::BadVersion);
    d[4] = std::byte{5};  // version 5 (before ValueBatch)
    EXPECT_EQ(decode_error(d), DecodeError::BadVersion);
    d[4] = std::byte{7};
    EXPECT_EQ(decode_error(d), DecodeError::BadVersion);
    for (int type : {0, 20, 255})
    {
        d = ping;
        d[5] = static_cast<std::byte>(type);
        EXPECT_EQ(decode_error(d), DecodeError::UnknownType) << type;
    }
    for (int flag = 0; flag < 8; ++flag)
    {
        d = ping;
        d[6] = static_cast<std::byte>(1 << flag);
        EXPECT_EQ(decode_error(d), DecodeError::BadFlags) << "issue 7 flags are refused in v1";
    }
    d = ping;
    d[7] = std::byte{1};
    EXPECT_EQ(decode_error(d), DecodeError::BadReserved);
    d = ping;
    put_le(d, 8, 0, 4);
    EXPECT_EQ(decode_error(d), DecodeError::BadSession);
    d = ping;
    put_le(d, 12, 0xFFFF, 2);
    EXPECT_EQ(decode_error(d), DecodeError::BadSender);
    // A Hello may come from nobody yet, with no session.
    EXPECT_TRUE(decode(encode_vec(first_of(MessageType::Hello))).has_value());
}

TEST(Codec, BodyErrorsEachHaveTheirCode)
{
    // Hello: role 3, a control character in the name, an empty name.
    auto hello = encode_vec(first_of(MessageType::Hello));
    auto d = hello;
    d[24] = std::byte{3};
    EXPECT_EQ(decode_error(d), DecodeError::BadEnum);
    d = hello;
    d[28] = std::byte{0x07};
    EXPECT_EQ(decode_error(d), DecodeError::BadName);
    d = hello;
    d[25] = std::byte{0};
    EXPECT_EQ(decode_error(d), DecodeError::BadName);

    // Leave: reasons 0 and 10 do not exist; reserved bytes must be zero.
    auto leave = encode_vec(first_of(MessageType::Leave));
    for (int reason : {0, 10, 255})
    {
        d = leave;
        d[24] = static_cast<std::byte>(reason);
        EXPECT_EQ(decode_error(d), DecodeError::BadEnum) << reason;
    }
    d = leave;
    d[27] = std::byte{1};
    EXPECT_EQ(decode_error(d), DecodeError::BadReserved);

    // LeafState (the first sample is f64 with 73 nodes).
    const auto leaf = encode_vec(first_of(MessageType::LeafState));
    d = leaf;
    d[34] = std::byte{4};  // 3 is the quantised delta
    EXPECT_EQ(decode_error(d), DecodeError::BadEnum);
    d = leaf;
    put_le(d, 38, 74, 2);
    EXPECT_EQ(decode_error(d), DecodeError::BadCount);
    d = leaf;
    d[35] = std::byte{3};  // coarsen 3 is the largest
    EXPECT_TRUE(decode(d).has_value());
    d[35] = std::byte{4};
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = leaf;
    d[30] = std::byte{16};  // ix 16 at depth 4
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = leaf;
    d[28] = std::byte{2};  // square 2
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = leaf;
    put_le(d, 36, 0xFFFF, 2);  // node offset + count > 65,535
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = leaf;
    put_le(d, 48, 0x7FF8000000000000ULL, 8);  // quiet NaN in u[0]
    EXPECT_EQ(decode_error(d), DecodeError::NonFinite);
    d = leaf;
    put_le(d, 48 + 8 * 73, 0xFFF0000000000000ULL, 8);  // -inf in v[0]
    EXPECT_EQ(decode_error(d), DecodeError::NonFinite);
    d = leaf;
    put_le(d, 40, 0xBFF0000000000000ULL, 8);  // time -1
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);

    // f32 signalling NaN: classified by bits, no floating-point trap (the test main enables them).
    Message f32{samples::header(), samples::leaf_state(ValueEncoding::F32, 4)};
    d = encode_vec(f32);
    put_le(d, 48, 0x7F800001u, 4);
    EXPECT_EQ(decode_error(d), DecodeError::NonFinite);

    // Halo: overlapping ranges, no fields.
    const auto halo = encode_vec(first_of(MessageType::Halo));
    d = halo;
    put_le(d, 48, 101, 4);  // second range starts inside the first (100..104)
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = halo;
    d[30] = std::byte{0};
    EXPECT_EQ(decode_error(d), DecodeError::BadEnum);
    d = halo;
    d[28] = std::byte{7};
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = halo;
    put_le(d, 44, 2000, 2);  // 2,000 nodes cannot fit 1,200 bytes
    EXPECT_EQ(decode_error(d), DecodeError::BadCount);

    // Counts and ranges elsewhere.
    d = encode_vec(first_of(MessageType::PointsOfInterest));
    d[24] = std::byte{17};
    EXPECT_EQ(decode_error(d), DecodeError::BadCount);
    d = encode_vec(first_of(MessageType::Blob));
    put_le(d, 26, 0, 2);
    EXPECT_EQ(decode_error(d), DecodeError::BadCount);
    d = encode_vec(first_of(MessageType::Blob));
    put_le(d, 32, 4500, 4);  // offset 4500 + 1000 > total 5000
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = encode_vec(first_of(MessageType::Partition));
    put_le(d, 24, 0, 4);
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = encode_vec(first_of(MessageType::Partition));
    put_le(d, 32, 0xFFFF, 2);  // an unowned leaf
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = encode_vec(first_of(MessageType::PeerLeft));
    put_le(d, 24, 0xFFFF, 2);
    EXPECT_EQ(decode_error(d), DecodeError::BadRange);
    d = encode_vec(first_of(MessageType::Ack));
    d[24] = std::byte{0};
    EXPECT_EQ(decode_error(d), DecodeError::BadCount);

    // Welcome: infinite time; the third peer (id 5 = your id) renamed to the first's id.
    const auto welcome = encode_vec(first_of(MessageType::Welcome));
    d = welcome;
    put_le(d, 36, 0x7FF0000000000000ULL, 8);
    EXPECT_EQ(decode_error(d), DecodeError::NonFinite);
    d = welcome;
    const std::size_t third = 24 + 44 + (24 + 6) + (24 + 3);
    put_le(d, third, 0, 2);
    EXPECT_EQ(decode_error(d), DecodeError::Duplicate);
    d = welcome;
    d[third + 3] = std::byte{6};  // IPv6 is reserved
    EXPECT_EQ(decode_error(d), DecodeError::BadEnum);
    d = welcome;
    d[third + 10] = std::byte{1};  // bytes 4..15 of an IPv4 address must be zero
    EXPECT_EQ(decode_error(d), DecodeError::BadReserved);
}

TEST(Codec, EncoderRefusesWhatTheDecoderWouldRefuse)
{
    std::vector<std::byte> buf(k_max_datagram_size);
    Message m = first_of(MessageType::LeafState);
    std::get<LeafState>(m.body).u[0] = std::bit_cast<double>(0x7FF8000000000000ULL);
    EXPECT_EQ(encode(m, buf).error(), EncodeError::InvalidMessage);

    m = first_of(MessageType::LeafState);
    std::get<LeafState>(m.body).v.pop_back();  // u and v of different lengths
    EXPECT_EQ(validate(m), DecodeError::BadCount);

    Message f32{samples::header(), samples::leaf_state(ValueEncoding::F32, 2)};
    std::get<LeafState>(f32.body).u[0] = 1e39;  // beyond FLT_MAX
    EXPECT_EQ(encode(f32, buf).error(), EncodeError::InvalidMessage);
    std::get<LeafState>(f32.body).encoding = ValueEncoding::F64;
    EXPECT_TRUE(encode(f32, buf).has_value());

    m = first_of(MessageType::Ping);
    m.header.sender = k_no_peer;
    EXPECT_EQ(validate(m), DecodeError::BadSender);

    m = first_of(MessageType::Welcome);
    std::get<Welcome>(m.body).your_id = PeerId{42};  // not in the list
    EXPECT_EQ(validate(m), DecodeError::BadRange);

    m = first_of(MessageType::Partition);
    std::get<Partition>(m.body).owners.pop_back();
    EXPECT_EQ(validate(m), DecodeError::BadCount);

    m = first_of(MessageType::Ping);
    std::vector<std::byte> small(encoded_size(m) - 1);
    EXPECT_EQ(encode(m, small).error(), EncodeError::BufferTooSmall);
}

TEST(Codec, AValueOutOfItsEncodingAnywhereIsRefused)
{
    // Every position of u and v of a full leaf state, in both encodings: a NaN, an infinity
    // and, in f32, a finite value beyond FLT_MAX (the checks run over whole vectors at once).
    std::vector<std::byte> buf(k_max_datagram_size);
    const double nan = std::bit_cast<double>(0x7FF8000000000001ULL);
    const double inf = -std::numeric_limits<double>::infinity();
    for (const ValueEncoding e : {ValueEncoding::F64, ValueEncoding::F32})
    {
        const std::size_t n = e == ValueEncoding::F64 ? k_max_leaf_nodes_f64 : k_max_leaf_nodes_f32;
        const Message good{samples::header(), samples::leaf_state(e, n)};
        ASSERT_TRUE(encode(good, buf).has_value());
        for (std::size_t k = 0; k < 2 * n; ++k)
            for (const double bad : {nan, inf, 1e39})
            {
                if (e == ValueEncoding::F64 && std::isfinite(bad))
                    continue;  // any finite double is an f64 value
                Message m = good;
                auto& ls = std::get<LeafState>(m.body);
                (k < n ? ls.u[k] : ls.v[k - n]) = bad;
                ASSERT_EQ(validate(m), DecodeError::NonFinite) << "value " << k << " = " << bad;
                ASSERT_EQ(encode(m, buf).error(), EncodeError::InvalidMessage);
            }
    }
}

TEST(Codec, F32EncodingRoundsToNearest)
{
    Message m{samples::header(), samples::leaf_state(ValueEncoding::F32, 3)};
    std::get<LeafState>(m.body).u = {0.1, -1.0 / 3.0, 1e-40};
    auto back = decode(encode_vec(m));
    ASSERT_TRUE(back.has_value());
    const auto& u = std::get<LeafState>(back->body).u;
    EXPECT_EQ(u[0], static_cast<double>(0.1f));
    EXPECT_EQ(u[1], static_cast<double>(-1.0f / 3.0f));
    EXPECT_EQ(u[2], static_cast<double>(static_cast<float>(1e-40)));  // a subnormal f32
}

/// One datagram of RandomAndCorruptedDatagramsAreRejectedOrCanonical's mix (iteration `i`):
/// random bytes, a valid header before a random body, an encoded sample with 1 to 4 corrupted
/// bytes, or one truncated or extended.
std::vector<std::byte> random_datagram(std::mt19937_64& rng,
                                       const std::vector<std::vector<std::byte>>& encoded, int i)
{
    std::vector<std::byte> d;
    const auto& base = encoded[rng() % encoded.size()];
    switch (i % 4)
    {
    case 0:  // random bytes
        d.resize(rng() % 200);
        for (auto& b : d)
            b = static_cast<std::byte>(rng());
        break;
    case 1:  // a valid header, a random body
        d.assign(base.begin(), base.begin() + k_header_size);
        d.resize(k_header_size + rng() % 300);
        for (std::size_t k = k_header_size; k < d.size(); ++k)
            d[k] = static_cast<std::byte>(rng());
        break;
    case 2:  // 1 to 4 corrupted bytes (bit flips or random values)
    {
        d = base;
        const int n = 1 + static_cast<int>(rng() % 4);
        for (int k = 0; k < n; ++k)
        {
            const std::size_t at = rng() % d.size();
            if (rng() % 2 == 0)
                d[at] ^= static_cast<std::byte>(1u << (rng() % 8));
            else
                d[at] = static_cast<std::byte>(rng());
        }
        break;
    }
    default:  // truncated or extended
        d = base;
        d.resize(rng() % (base.size() + 8));
        break;
    }
    return d;
}

// 100,000 datagrams: random bytes, random bodies behind a valid header, valid messages with
// random bytes corrupted, random truncations. None may crash (ASan+UBSan in CI); every one that
// decodes must re-encode to exactly the same bytes, so the decoder accepts only canonical
// datagrams and the encoder's rules match the decoder's.
TEST(Codec, RandomAndCorruptedDatagramsAreRejectedOrCanonical)
{
    const auto messages = samples::all();
    std::vector<std::vector<std::byte>> encoded;
    for (const Message& m : messages)
        encoded.push_back(encode_vec(m));
    std::mt19937_64 rng(20260601);
    std::vector<std::byte> buf(k_max_datagram_size);
    std::size_t accepted = 0;
    std::set<DecodeError> seen;
    constexpr int k_iterations = 100000;
    for (int i = 0; i < k_iterations; ++i)
    {
        const std::vector<std::byte> d = random_datagram(rng, encoded, i);
        auto r = decode(d);
        if (!r)
        {
            seen.insert(r.error());
            continue;
        }
        ++accepted;
        auto size = encode(*r, buf);
        ASSERT_TRUE(size.has_value()) << "decoded message does not encode, iteration " << i;
        ASSERT_EQ(*size, d.size()) << "iteration " << i;
        ASSERT_TRUE(std::equal(d.begin(), d.end(), buf.begin())) << "iteration " << i;
    }
    // Not vacuous: corruptions of value bytes decode, and most error kinds occur.
    EXPECT_GT(accepted, std::size_t{1000});
    EXPECT_GE(seen.size(), std::size_t{12});
}

// decode_into() into a message that held another one: every sample after every sample (the same
// type with more nodes, leaves, ranges, peers or optional parts, and every other type) gives what
// decode() gives, so no read_body leaves a field of the message before.
TEST(Codec, DecodeIntoAReusedMessageMatchesAFreshDecode)
{
    const auto messages = samples::all();
    std::vector<std::vector<std::byte>> encoded;
    for (const Message& m : messages)
        encoded.push_back(encode_vec(m));
    int same_type = 0;
    for (std::size_t a = 0; a < messages.size(); ++a)
        for (std::size_t b = 0; b < messages.size(); ++b)
        {
            Message reused;
            ASSERT_FALSE(decode_into(encoded[a], reused).has_value());
            ASSERT_EQ(reused, messages[a]) << to_string(messages[a].type());
            const auto err = decode_into(encoded[b], reused);
            ASSERT_FALSE(err.has_value()) << to_string(*err);
            ASSERT_EQ(reused, messages[b]) << to_string(messages[a].type()) << " #" << a << " then "
                                           << to_string(messages[b].type()) << " #" << b;
            ASSERT_EQ(encode_vec(reused), encoded[b]);
            same_type += messages[a].type() == messages[b].type() && a != b ? 1 : 0;
        }
    EXPECT_GE(same_type, 40);  // pairs of samples of one type, both orders

    // Per-leaf vectors of a batch of fewer leaves, and a LeafState of the other encodings.
    const LeafBatch big = samples::leaf_batch(9, 7, 20);
    const LeafBatch small = samples::leaf_batch(2, 7, 3);
    Message reused;
    ASSERT_FALSE(decode_into(encode_vec(Message{samples::header(), big}), reused).has_value());
    const auto small_bytes = encode_vec(Message{samples::header(), small});
    ASSERT_FALSE(decode_into(small_bytes, reused).has_value());
    EXPECT_EQ(reused, decode(small_bytes).value());
    EXPECT_EQ(std::get<LeafBatch>(reused.body), small);
}

// Random and corrupted datagrams (RandomAndCorruptedDatagramsAreRejectedOrCanonical's mix)
// decoded into one reused message, which holds the previous datagram's message or whatever a
// failed decode left, or a valid sample of the datagram's type: the same value or error as
// decode().
TEST(Codec, DecodeIntoAReusedMessageMatchesDecodeOnCorruptedDatagrams)
{
    const auto messages = samples::all();
    std::vector<std::vector<std::byte>> encoded;
    for (const Message& m : messages)
        encoded.push_back(encode_vec(m));
    std::mt19937_64 rng(20261207);
    Message reused;
    std::size_t accepted = 0;
    constexpr int k_iterations = 40000;
    for (int i = 0; i < k_iterations; ++i)
    {
        const std::vector<std::byte> d = random_datagram(rng, encoded, i);
        if (rng() % 2 == 0)
        {
            // A valid message of the datagram's type (if it names one) first.
            const std::size_t pick = rng() % encoded.size();
            for (std::size_t k = 0; k < encoded.size(); ++k)
            {
                const auto& e = encoded[(pick + k) % encoded.size()];
                if (d.size() > 5 && e[5] == d[5])
                {
                    ASSERT_FALSE(decode_into(e, reused).has_value());
                    break;
                }
            }
        }
        const auto fresh = decode(d);
        const auto err = decode_into(d, reused);
        ASSERT_EQ(fresh.has_value(), !err.has_value()) << "iteration " << i;
        if (err)
        {
            ASSERT_EQ(fresh.error(), *err) << "iteration " << i;
            continue;
        }
        ++accepted;
        ASSERT_EQ(reused, *fresh) << "iteration " << i;
    }
    EXPECT_GT(accepted, std::size_t{400});
}

}  // namespace
// The fuzz seed corpus's raw datagrams (fuzz/corpus/net_decode/raw_*.bin: a mode byte, then
// one datagram) carry this build's protocol version: seeds of an older version stop at the
// version byte and never reach a body (38 of 41 did after version 6). Each decodes, or is
// refused by a body rule, never by its header's version.
TEST(Codec, FuzzSeedCorpusSpeaksThisProtocolVersion)
{
    const std::filesystem::path dir =
        std::filesystem::path(PLIANT_SOURCE_DIR) / "fuzz" / "corpus" / "net_decode";
    int seeds = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir))
    {
        const std::string name = entry.path().filename().string();
        if (name.rfind("raw_", 0) != 0)
            continue;
        std::ifstream in(entry.path(), std::ios::binary);
        const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                      std::istreambuf_iterator<char>());
        ASSERT_GT(bytes.size(), 1U) << name;
        const auto decoded = decode(
            std::span(reinterpret_cast<const std::byte*>(bytes.data()) + 1, bytes.size() - 1));
        if (!decoded)
        {
            EXPECT_NE(decoded.error(), DecodeError::BadVersion) << name;
            EXPECT_NE(decoded.error(), DecodeError::BadMagic) << name;
        }
        ++seeds;
    }
    EXPECT_GE(seeds, 40);
}

}  // namespace pliant::net
