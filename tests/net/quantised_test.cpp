// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The quantised-delta encoding (docs/protocol.md §5.5): quantisation bounds and exactness checked
// against ldexp, residuals against a baseline reproducing the sender's integers, the LeafState
// round trip through the codec to the same bits, and hostile zstd frames (no content size, a
// content size over the bound, trailing bytes, garbage, wrong varint counts) refused as
// BadCompression and counted by the Peer that receives them.

#include <pliant/net/codec.h>
#include <pliant/net/messenger.h>
#include <pliant/net/quantised.h>

#include <gtest/gtest.h>
#include <zstd.h>

#include "net/encode_vec.h"
#include "net/sample_messages.h"

#include <bit>
#include <cmath>
#include <limits>
#include <random>

namespace pliant::net
{
namespace
{

using test::encode_vec;

/// A zstd frame of `raw` written by the test itself (not by pack_residuals).
std::vector<std::byte> frame_of(const std::vector<std::byte>& raw, bool content_size = true)
{
    ZSTD_CCtx* c = ZSTD_createCCtx();
    ZSTD_CCtx_setParameter(c, ZSTD_c_contentSizeFlag, content_size ? 1 : 0);
    std::vector<std::byte> out(ZSTD_compressBound(raw.size()));
    const std::size_t n = ZSTD_compress2(c, out.data(), out.size(), raw.data(), raw.size());
    ZSTD_freeCCtx(c);
    EXPECT_FALSE(ZSTD_isError(n));
    out.resize(n);
    return out;
}

TEST(Quantised, ErrorIsAtMostHalfAStepAndDequantisedValuesAreExact)
{
    std::mt19937_64 rng(7);
    for (const int e : {-40, -20, -16, -12, -1, 0})
    {
        const double step = std::ldexp(1.0, e);
        std::uniform_real_distribution<double> dist(-1e6 * step, 1e6 * step);
        std::vector<double> x(1000);
        for (double& v : x)
            v = dist(rng);
        x[0] = 0.0;
        x[1] = 2.5 * step;  // a tie: away from zero
        x[2] = -2.5 * step;
        std::vector<std::int32_t> q(x.size());
        ASSERT_TRUE(quantise(x, e, q));
        EXPECT_EQ(q[1], 3);
        EXPECT_EQ(q[2], -3);
        std::vector<double> back(x.size());
        dequantise(q, e, back);
        for (std::size_t i = 0; i < x.size(); ++i)
        {
            EXPECT_LE(std::fabs(x[i] - back[i]), step / 2) << "e " << e << " x " << x[i];
            EXPECT_EQ(std::bit_cast<std::uint64_t>(back[i]),
                      std::bit_cast<std::uint64_t>(std::ldexp(static_cast<double>(q[i]), e)));
        }
        // Quantising a dequantised value gives the same integers: every peer agrees.
        std::vector<std::int32_t> again(x.size());
        ASSERT_TRUE(quantise(back, e, again));
        EXPECT_EQ(again, q);
    }
    EXPECT_EQ(quantum(-16), 1.0 / 65536.0);
}

TEST(Quantised, RefusesNonFiniteAndOutOfRangeValues)
{
    std::vector<std::int32_t> q(1);
    EXPECT_FALSE(quantise(std::vector<double>{std::numeric_limits<double>::infinity()}, -16, q));
    EXPECT_FALSE(quantise(std::vector<double>{std::bit_cast<double>(0x7FF8000000000001ULL)}, 0, q));
    EXPECT_FALSE(quantise(std::vector<double>{std::ldexp(1.0, 31)}, 0, q));
    EXPECT_TRUE(quantise(std::vector<double>{std::ldexp(1.0, 31) - 1.0}, 0, q));
    EXPECT_EQ(q[0], std::numeric_limits<std::int32_t>::max());
    EXPECT_FALSE(quantise(std::vector<double>{1.0}, -40, q)) << "2^40 does not fit int32";
}

TEST(Quantised, ResidualsAgainstABaselineReproduceTheIntegers)
{
    std::mt19937 rng(11);
    std::uniform_int_distribution<std::int32_t> wide(-(1 << 30), 1 << 30);
    for (int trial = 0; trial < 200; ++trial)
    {
        const std::size_t n = 1 + static_cast<std::size_t>(trial % 147);
        std::vector<std::int32_t> base(n), q(n), r(n), back(n);
        for (std::size_t i = 0; i < n; ++i)
        {
            base[i] = wide(rng);
            q[i] = base[i] + static_cast<std::int32_t>(rng() % 2001) - 1000;
        }
        for (const bool predicted : {false, true})
        {
            ASSERT_TRUE(make_residuals(q, base, predicted, r));
            ASSERT_TRUE(apply_residuals(r, base, predicted, back));
            EXPECT_EQ(back, q);
            ASSERT_TRUE(make_residuals(q, {}, predicted, r));  // key state
            ASSERT_TRUE(apply_residuals(r, {}, predicted, back));
            EXPECT_EQ(back, q);
        }
    }
    // Without prediction the residual is q - base, written out by hand.
    std::vector<std::int32_t> r(3);
    ASSERT_TRUE(make_residuals(std::vector<std::int32_t>{10, 20, 31},
                               std::vector<std::int32_t>{9, 20, 30}, false, r));
    EXPECT_EQ(r, (std::vector<std::int32_t>{1, 0, 1}));
    ASSERT_TRUE(make_residuals(std::vector<std::int32_t>{10, 20, 31},
                               std::vector<std::int32_t>{9, 20, 30}, true, r));
    EXPECT_EQ(r, (std::vector<std::int32_t>{1, -1, 1}));
    // Hostile residuals that would leave int32 are refused.
    constexpr std::int32_t big = std::numeric_limits<std::int32_t>::max();
    std::vector<std::int32_t> out(2);
    EXPECT_FALSE(apply_residuals(std::vector<std::int32_t>{big, big}, {}, true, out));
    EXPECT_FALSE(apply_residuals(std::vector<std::int32_t>{big, 0}, std::vector<std::int32_t>{1, 0},
                                 false, out));
    EXPECT_FALSE(make_residuals(std::vector<std::int32_t>{big, 0},
                                std::vector<std::int32_t>{-big, 0}, false, out));
}

TEST(Quantised, PredictionPaysOnSmoothDataOnly)
{
    std::vector<std::int32_t> smooth(64), rough(64);
    for (std::size_t i = 0; i < 64; ++i)
    {
        smooth[i] = 1000 + static_cast<std::int32_t>(i);
        rough[i] = i % 2 == 0 ? 50 : -50;
    }
    EXPECT_TRUE(prediction_pays(smooth, {}, smooth, {}));
    EXPECT_FALSE(prediction_pays(rough, {}, rough, {}));
}

TEST(Quantised, PackedResidualsRoundTripIncludingExtremes)
{
    std::mt19937 rng(3);
    for (const std::size_t n : {std::size_t{1}, std::size_t{72}, k_max_leaf_nodes_quantised})
    {
        std::vector<std::int32_t> du(n), dv(n);
        for (std::size_t i = 0; i < n; ++i)
        {
            du[i] = static_cast<std::int32_t>(rng() % 200) - 100;
            dv[i] = static_cast<std::int32_t>(rng() % 20) - 10;
        }
        du[0] = std::numeric_limits<std::int32_t>::min();
        dv[n - 1] = std::numeric_limits<std::int32_t>::max();
        std::vector<std::byte> packed;
        ASSERT_TRUE(pack_residuals(du, dv, k_max_packed_residuals, packed));
        std::vector<std::int32_t> bu(n), bv(n);
        EXPECT_FALSE(unpack_residuals(packed, bu, bv).has_value());
        EXPECT_EQ(bu, du);
        EXPECT_EQ(bv, dv);
        EXPECT_FALSE(pack_residuals(du, dv, 4, packed)) << "a limit below the frame is refused";
    }
}

TEST(Quantised, LeafStateRoundTripGivesTheSendersQuantisedBits)
{
    // Sender: values, their quantisation, a baseline the receiver holds, residuals, zstd.
    const std::size_t n = 72;
    const int eu = -16;
    const int ev = -12;
    std::vector<double> u(n), v(n), bu_x(n), bv_x(n);
    for (std::size_t i = 0; i < n; ++i)
    {
        const double s = static_cast<double>(i) / static_cast<double>(n);
        bu_x[i] = 0.01 * std::sin(6.0 * s);
        bv_x[i] = 0.2 * std::cos(6.0 * s);
        u[i] = bu_x[i] + 1e-4 * s;
        v[i] = bv_x[i] - 3e-3 * s * s;
    }
    std::vector<std::int32_t> qu(n), qv(n), base_u(n), base_v(n);
    ASSERT_TRUE(quantise(u, eu, qu) && quantise(v, ev, qv));
    ASSERT_TRUE(quantise(bu_x, eu, base_u) && quantise(bv_x, ev, base_v));
    for (const bool with_base : {false, true})
    {
        Message m{samples::header(), LeafState{}};
        m.header.tick = 500;
        LeafState& ls = std::get<LeafState>(m.body);
        ls.leaf = WireLeafId{.square = 1, .depth = 3, .ix = 2, .iy = 7};
        ls.encoding = ValueEncoding::QuantisedDelta;
        ls.time = 0.5;
        QuantisedDelta& q = ls.quantised;
        q.baseline = with_base ? 4 : 0;
        q.u_exponent = eu;
        q.v_exponent = ev;
        const std::span<const std::int32_t> bu =
            with_base ? base_u : std::span<const std::int32_t>{};
        const std::span<const std::int32_t> bv =
            with_base ? base_v : std::span<const std::int32_t>{};
        q.predicted = prediction_pays(qu, bu, qv, bv);
        q.du.resize(n);
        q.dv.resize(n);
        ASSERT_TRUE(make_residuals(qu, bu, q.predicted, q.du));
        ASSERT_TRUE(make_residuals(qv, bv, q.predicted, q.dv));
        ASSERT_TRUE(pack_residuals(q.du, q.dv, k_max_packed_residuals, q.packed));
        const auto bytes = encode_vec(m);
        EXPECT_EQ(bytes.size(), k_header_size + k_leaf_state_quantised_fixed + q.packed.size());
        EXPECT_LT(bytes.size(), k_header_size + k_leaf_state_fixed + 8 * n)
            << "smaller than f32 of the same leaf";

        // Receiver: decode, rebuild from the same baseline, dequantise.
        auto d = decode(bytes);
        ASSERT_TRUE(d.has_value()) << to_string(d.error());
        EXPECT_EQ(*d, m);
        const QuantisedDelta& r = std::get<LeafState>(d->body).quantised;
        std::vector<std::int32_t> ru(n), rv(n);
        ASSERT_TRUE(apply_residuals(r.du, bu, r.predicted, ru));
        ASSERT_TRUE(apply_residuals(r.dv, bv, r.predicted, rv));
        std::vector<double> su(n), sv(n), xu(n), xv(n);
        dequantise(qu, eu, su);
        dequantise(qv, ev, sv);
        dequantise(ru, r.u_exponent, xu);
        dequantise(rv, r.v_exponent, xv);
        for (std::size_t i = 0; i < n; ++i)
        {
            EXPECT_EQ(std::bit_cast<std::uint64_t>(xu[i]), std::bit_cast<std::uint64_t>(su[i]));
            EXPECT_EQ(std::bit_cast<std::uint64_t>(xv[i]), std::bit_cast<std::uint64_t>(sv[i]));
            EXPECT_LE(std::fabs(xu[i] - u[i]), quantum(eu) / 2);
            EXPECT_LE(std::fabs(xv[i] - v[i]), quantum(ev) / 2);
        }
    }
}

TEST(Quantised, LeafStateFixedFieldsMatchTheSpecification)
{
    Message m{samples::header(), samples::quantised_leaf_state(3, 0x01020304u, true)};
    const auto& q = std::get<LeafState>(m.body).quantised;
    const auto d = encode_vec(m);
    ASSERT_EQ(d.size(), 24 + 32 + q.packed.size());
    // Offset 10: encoding 3; 14: node count 3; 24: baseline u32; 28, 29: exponents -16, -12;
    // 30: packed length | 0x8000 (predicted).
    EXPECT_EQ(d[24 + 10], std::byte{3});
    EXPECT_EQ(d[24 + 14], std::byte{3});
    EXPECT_EQ(d[24 + 24], std::byte{0x04});
    EXPECT_EQ(d[24 + 27], std::byte{0x01});
    EXPECT_EQ(d[24 + 28], std::byte{0xF0});
    EXPECT_EQ(d[24 + 29], std::byte{0xF4});
    EXPECT_EQ(static_cast<std::size_t>(d[24 + 30]) | (static_cast<std::size_t>(d[24 + 31]) << 8),
              q.packed.size() | 0x8000u);
    EXPECT_TRUE(std::equal(q.packed.begin(), q.packed.end(), d.begin() + 56));
}

/// A quantised LeafState whose packed bytes are replaced by `packed` (lengths kept consistent).
std::vector<std::byte> with_packed(const std::vector<std::byte>& packed, std::size_t n = 4)
{
    Message m{samples::header(), samples::quantised_leaf_state(n, 0, false)};
    const auto good = encode_vec(m);
    const std::size_t at = k_header_size + k_leaf_state_quantised_fixed;
    std::vector<std::byte> out(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(at));
    const auto length = static_cast<std::uint16_t>(packed.size());
    out[k_header_size + 30] = static_cast<std::byte>(length & 0xFF);
    out[k_header_size + 31] = static_cast<std::byte>(length >> 8);
    out.insert(out.end(), packed.begin(), packed.end());
    return out;
}

std::vector<std::byte> zeros(std::size_t n)
{
    return std::vector<std::byte>(n, std::byte{0});
}

TEST(Quantised, HostileFramesAreRefusedAndCounted)
{
    const std::size_t n = 4;  // 2n = 8 varints, content must be 8..40 bytes
    // Sanity: a frame the test writes itself, with exactly 8 zero varints, is accepted.
    ASSERT_TRUE(decode(with_packed(frame_of(zeros(8)), n)).has_value());

    std::vector<std::vector<std::byte>> hostile;
    hostile.push_back(with_packed(frame_of(zeros(8), false), n));  // no content size
    hostile.push_back(with_packed(frame_of(zeros(41), true), n));  // over 10n: refused unread
    hostile.push_back(with_packed(frame_of(zeros(7), true), n));   // under 2n
    hostile.push_back(with_packed(frame_of(zeros(9), true), n));   // 9 varints for 8 values
    auto two = frame_of(zeros(8));
    const auto again = frame_of(zeros(8));
    two.insert(two.end(), again.begin(), again.end());
    hostile.push_back(with_packed(two, n));  // a second frame inside the packed length
    auto tail = frame_of(zeros(8));
    tail.push_back(std::byte{0});
    hostile.push_back(with_packed(tail, n));  // a trailing byte inside the packed length
    std::vector<std::byte> redundant = zeros(6);
    redundant.push_back(std::byte{0x80});  // a non-canonical varint: 0x80 0x00
    redundant.push_back(std::byte{0x00});
    hostile.push_back(with_packed(frame_of(redundant), n));
    std::vector<std::byte> huge(8, std::byte{0xFF});  // an unterminated 8-byte varint
    hostile.push_back(with_packed(frame_of(huge), n));
    std::vector<std::byte> garbage(40);
    for (std::size_t i = 0; i < garbage.size(); ++i)
        garbage[i] = static_cast<std::byte>((i * 89 + 13) & 0xFF);
    hostile.push_back(with_packed(garbage, n));
    auto cut = frame_of(zeros(8));
    cut.pop_back();
    hostile.push_back(with_packed(cut, n));  // a truncated frame (lengths consistent)
    // A frame header claiming 2^40 bytes of content: magic, descriptor with an 8-byte size.
    std::vector<std::byte> claim = {std::byte{0x28}, std::byte{0xB5}, std::byte{0x2F},
                                    std::byte{0xFD}, std::byte{0xE0}};
    for (int k = 0; k < 8; ++k)
        claim.push_back(k == 5 ? std::byte{1} : std::byte{0});
    claim.insert(claim.end(), {std::byte{1}, std::byte{0}, std::byte{0}});
    hostile.push_back(with_packed(claim, n));

    Peer peer(PeerHandle{1});
    for (std::size_t k = 0; k < hostile.size(); ++k)
    {
        auto d = decode(hostile[k]);
        ASSERT_FALSE(d.has_value()) << "case " << k;
        EXPECT_EQ(d.error(), DecodeError::BadCompression) << "case " << k;
        auto r = peer.accept(Channel::State, hostile[k]);
        ASSERT_FALSE(r.has_value());
        EXPECT_EQ(r.error().reason, DropReason::Undecodable);
    }
    EXPECT_EQ(peer.bad_datagrams(), hostile.size());
    EXPECT_EQ(peer.errors()[static_cast<std::size_t>(DecodeError::BadCompression)], hostile.size());

    // A packed length of zero or beyond the payload is a count error, an inconsistent one a
    // length error.
    auto empty = with_packed({}, n);
    EXPECT_EQ(decode(empty).error(), DecodeError::BadCount);
    auto longer = with_packed(frame_of(zeros(8)), n);
    longer[k_header_size + 30] =
        static_cast<std::byte>(static_cast<std::uint8_t>(longer[k_header_size + 30]) + 1);
    EXPECT_EQ(decode(longer).error(), DecodeError::BadLength);
}

TEST(Quantised, EncoderRefusesPackedBytesThatDisagreeWithTheResiduals)
{
    Message m{samples::header(), samples::quantised_leaf_state(8, 0, false)};
    std::get<LeafState>(m.body).quantised.du[3] += 1;
    std::vector<std::byte> out(k_max_datagram_size);
    EXPECT_EQ(encode(m, out).error(), EncodeError::InvalidMessage);
    Message bad_exponent{samples::header(), samples::quantised_leaf_state(8, 0, false)};
    std::get<LeafState>(bad_exponent.body).quantised.u_exponent = 1;
    EXPECT_EQ(validate(bad_exponent), DecodeError::BadRange);
    Message mixed{samples::header(), samples::quantised_leaf_state(8, 0, false)};
    std::get<LeafState>(mixed.body).u = {1.0};
    EXPECT_EQ(validate(mixed), DecodeError::BadCount);
    Message halo{samples::header(), samples::halo(ValueEncoding::F64, true, false)};
    std::get<Halo>(halo.body).encoding = ValueEncoding::QuantisedDelta;
    EXPECT_EQ(validate(halo), DecodeError::BadEnum) << "halos stay f32/f64";
}

// ---- Rice packing (docs/protocol.md §5.6) ----------------------------------------------------

/// Bits written by a slow, independent Rice coder: the same rule spelled out value by value.
std::size_t reference_rice_bits(const std::vector<std::int32_t>& r)
{
    std::size_t best = std::numeric_limits<std::size_t>::max();
    for (int k = 0; k <= k_max_rice_parameter; ++k)
    {
        std::size_t bits = 5;
        for (const std::int32_t x : r)
        {
            const std::uint64_t z =
                x >= 0 ? 2 * std::uint64_t(x) : 2 * std::uint64_t(-std::int64_t(x)) - 1;
            const std::uint64_t q = z >> k;
            bits += q < std::uint64_t(k_rice_escape) ? q + 1 + std::uint64_t(k)
                                                     : std::uint64_t(k_rice_escape) + 32;
        }
        best = std::min(best, bits);
    }
    return best;
}

TEST(QuantisedRice, RoundTripsIncludingExtremesInTheFewestBits)
{
    std::mt19937 rng(5);
    for (const std::size_t n : {std::size_t{1}, std::size_t{72}, k_max_leaf_nodes_quantised})
        for (const int spread : {0, 1, 40, 5000, 1 << 24})
        {
            std::vector<std::int32_t> du(n), dv(n);
            std::uniform_int_distribution<int> d(-spread, spread);
            for (std::size_t i = 0; i < n; ++i)
            {
                du[i] = d(rng);
                dv[i] = d(rng) / 3;
            }
            if (spread == 5000)
            {
                du[0] = std::numeric_limits<std::int32_t>::min();  // escapes
                dv[n - 1] = std::numeric_limits<std::int32_t>::max();
            }
            std::vector<std::byte> packed;
            ASSERT_TRUE(pack_residuals_rice(du, dv, k_max_packed_residuals, packed) ||
                        n == k_max_leaf_nodes_quantised);
            if (packed.empty())
                continue;
            EXPECT_EQ(packed.size(), rice_packed_size(du, dv));
            EXPECT_EQ(packed.size(), (reference_rice_bits(du) + reference_rice_bits(dv) + 7) / 8)
                << "n " << n << " spread " << spread;
            std::vector<std::int32_t> bu(n), bv(n);
            EXPECT_FALSE(unpack_residuals_rice(packed, bu, bv).has_value());
            EXPECT_EQ(bu, du);
            EXPECT_EQ(bv, dv);
            EXPECT_FALSE(unpack_residuals(Packing::Rice, packed, bu, bv).has_value());
            EXPECT_FALSE(pack_residuals_rice(du, dv, packed.size() - 1, packed))
                << "a limit below the bits is refused";
        }
}

TEST(QuantisedRice, SmallResidualsCostFarLessThanVarintBytes)
{
    // Residuals of magnitude <= 3 (what a well-predicted leaf sends): about 3 bits each, where
    // the varints of the zstd packing start at 8 bits before compression.
    std::mt19937 rng(9);
    std::uniform_int_distribution<int> d(-3, 3);
    std::vector<std::int32_t> du(72), dv(72);
    for (std::size_t i = 0; i < 72; ++i)
    {
        du[i] = d(rng);
        dv[i] = d(rng);
    }
    std::vector<std::byte> rice;
    std::vector<std::byte> zstd;
    ASSERT_TRUE(pack_residuals_rice(du, dv, k_max_packed_residuals, rice));
    ASSERT_TRUE(pack_residuals(du, dv, k_max_packed_residuals, zstd));
    EXPECT_LE(8.0 * static_cast<double>(rice.size()) / 144.0, 3.7);
    EXPECT_LT(rice.size(), zstd.size());
}

/// Hand-written Rice bits (least significant bit first), for the hostile cases.
std::vector<std::byte> bits_of(const std::vector<int>& bits)
{
    std::vector<std::byte> out((bits.size() + 7) / 8, std::byte{0});
    for (std::size_t i = 0; i < bits.size(); ++i)
        if (bits[i] != 0)
            out[i / 8] |= static_cast<std::byte>(1u << (i % 8));
    return out;
}

std::vector<int> parameter_bits(int k)
{
    std::vector<int> b;
    for (int i = 0; i < 5; ++i)
        b.push_back((k >> i) & 1);
    return b;
}

TEST(QuantisedRice, HostileBitsAreRefused)
{
    std::vector<std::int32_t> du(1), dv(1);
    // Sanity: k = 0 and the value 0 for u, then k = 0 and 0 for v: 12 bits.
    auto good = parameter_bits(0);
    good.push_back(0);
    auto v = parameter_bits(0);
    v.push_back(0);
    good.insert(good.end(), v.begin(), v.end());
    ASSERT_FALSE(unpack_residuals_rice(bits_of(good), du, dv).has_value());

    std::vector<std::vector<std::byte>> hostile;
    auto big_k = parameter_bits(k_max_rice_parameter + 1);  // parameter out of range
    big_k.push_back(0);
    big_k.insert(big_k.end(), 27, 0);
    big_k.insert(big_k.end(), v.begin(), v.end());
    hostile.push_back(bits_of(big_k));
    auto cut = good;  // v's parameter and value missing: its bits run past the one byte
    cut.resize(6);
    hostile.push_back(bits_of(cut));
    auto extra = bits_of(good);  // a byte too many
    extra.push_back(std::byte{0});
    hostile.push_back(extra);
    auto padding = good;  // non-zero padding after the last value
    padding.push_back(0);
    padding.push_back(1);
    hostile.push_back(bits_of(padding));
    // An escape (24 ones and 32 bits) for the value 5, which the short form holds.
    auto escape = parameter_bits(0);
    escape.insert(escape.end(), k_rice_escape, 1);
    for (int i = 0; i < 32; ++i)
        escape.push_back((5 >> i) & 1);
    escape.insert(escape.end(), v.begin(), v.end());
    hostile.push_back(bits_of(escape));
    std::vector<std::byte> ones(200, std::byte{0xFF});  // unary runs to the end
    hostile.push_back(ones);
    hostile.push_back({});
    for (std::size_t k = 0; k < hostile.size(); ++k)
        EXPECT_EQ(unpack_residuals_rice(hostile[k], du, dv), DecodeError::BadCompression)
            << "case " << k;
}

TEST(QuantisedRice, LeafStateAndBatchRoundTripAndHostileRecordsAreCounted)
{
    for (const Message& m :
         {Message{samples::header(), samples::quantised_leaf_state(72, 3, true, Packing::Rice)},
          Message{samples::header(), samples::leaf_batch(6, 3, 72)}})
    {
        const auto bytes = encode_vec(m);
        auto back = decode(bytes);
        ASSERT_TRUE(back.has_value());
        EXPECT_EQ(*back, m);
    }
    // The batch's fixed parts: 16 bytes, then 5 + varint per leaf before its packed bytes.
    const LeafBatch b = samples::leaf_batch(5, 3, 8);
    std::size_t expect = k_header_size + k_leaf_batch_fixed;
    const std::size_t varint[] = {1, 1, 1, 2, 3};
    for (std::size_t k = 0; k < 5; ++k)
        expect += k_batch_leaf_fixed + varint[k] + b.leaves[k].quantised.packed.size();
    EXPECT_EQ(encoded_size(Message{samples::header(), b}), expect);

    auto invalid = [](LeafBatch x) { return validate(Message{samples::header(), std::move(x)}); };
    LeafBatch mixed_depth = samples::leaf_batch(3, 3, 8);
    mixed_depth.leaves[1].leaf.depth = 2;
    mixed_depth.leaves[1].leaf.ix = 0;
    mixed_depth.leaves[1].leaf.iy = 0;
    EXPECT_EQ(invalid(mixed_depth), DecodeError::BadRange);
    LeafBatch mixed_exponent = samples::leaf_batch(3, 3, 8);
    mixed_exponent.leaves[2].quantised.u_exponent = -13;
    EXPECT_EQ(invalid(mixed_exponent), DecodeError::BadRange);
    LeafBatch deep = samples::leaf_batch(1, 8, 8);
    EXPECT_EQ(invalid(deep), DecodeError::BadRange) << "depth 8 leaves do not fit a u16 index";
    LeafBatch none = samples::leaf_batch(1, 3, 8);
    none.leaves.clear();
    EXPECT_EQ(invalid(none), DecodeError::BadCount);
    LeafBatch over = samples::leaf_batch(40, 3, 72);
    EXPECT_EQ(invalid(over), DecodeError::BadCount) << "over 1,200 bytes of body";
    LeafBatch disagree = samples::leaf_batch(2, 3, 8);
    disagree.leaves[1].quantised.dv[0] += 1;
    EXPECT_EQ(invalid(disagree), DecodeError::BadCompression);

    // Hostile bytes: a leaf index past the two squares, a non-canonical baseline varint, and
    // corrupt Rice bits, each dropped and counted by the receiving Peer.
    const Message one{samples::header(), samples::leaf_batch(1, 3, 8)};
    const auto good = encode_vec(one);
    const std::size_t rec = k_header_size + k_leaf_batch_fixed;
    std::vector<std::vector<std::byte>> hostile;
    auto index = good;
    index[rec] = std::byte{128};  // 2 * 8 * 8 = 128 leaves at depth 3
    hostile.push_back(index);
    // Baseline 0 written as 0x80 0x00 (two bytes): the packed length is shifted by one byte.
    auto redundant = good;
    redundant[rec + 5] = std::byte{0x80};
    redundant.insert(redundant.begin() + static_cast<std::ptrdiff_t>(rec + 6), std::byte{0});
    hostile.push_back(redundant);
    Peer peer(PeerHandle{1});
    for (const auto& h : hostile)
    {
        ASSERT_FALSE(decode(h).has_value());
        EXPECT_FALSE(peer.accept(Channel::State, h).has_value());
    }
    EXPECT_EQ(decode(hostile[0]).error(), DecodeError::BadRange);
    EXPECT_EQ(decode(hostile[1]).error(), DecodeError::BadRange);
    EXPECT_EQ(peer.bad_datagrams(), hostile.size());
}

}  // namespace
}  // namespace pliant::net
