// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Quantisation, residuals and the zstd packing of docs/protocol.md §5.5 (design in quantised.h).
// The only file that includes zstd (scripts/check_includes.py).

#include <pliant/net/quantised.h>

#include <zstd.h>

#include "net/byte_io_internal.h"

#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>

namespace pliant::net
{
namespace
{

constexpr std::int64_t k_int32_min = std::numeric_limits<std::int32_t>::min();
constexpr std::int64_t k_int32_max = std::numeric_limits<std::int32_t>::max();
/// zstd level 3, zstd's default (docs/protocol.md §5.5). On payloads of 150 bytes the frame comes
/// out only 8-15 % smaller than the varints (docs/results.md); the level matters little there.
constexpr int k_zstd_level = 3;

bool fits_int32(std::int64_t x) noexcept
{
    return x >= k_int32_min && x <= k_int32_max;
}

std::uint32_t zigzag(std::int32_t x) noexcept
{
    return (static_cast<std::uint32_t>(x) << 1) ^ static_cast<std::uint32_t>(x >> 31);
}

std::int32_t unzigzag(std::uint32_t z) noexcept
{
    return static_cast<std::int32_t>((z >> 1) ^ (0u - (z & 1u)));
}

std::size_t put_varint(std::uint32_t z, std::byte* out) noexcept
{
    std::size_t n = 0;
    while (z >= 0x80u)
    {
        out[n++] = static_cast<std::byte>((z & 0x7Fu) | 0x80u);
        z >>= 7;
    }
    out[n++] = static_cast<std::byte>(z);
    return n;
}

/// Reads one canonical varint (at most 5 bytes, value < 2^32, no redundant 0x80 groups).
bool get_varint(const std::byte* in, std::size_t size, std::size_t& pos, std::uint32_t& z) noexcept
{
    std::uint64_t value = 0;
    for (int k = 0; k < 5; ++k)
    {
        if (pos >= size)
            return false;
        const auto b = static_cast<std::uint8_t>(in[pos++]);
        value |= std::uint64_t{b & 0x7Fu} << (7 * k);
        if ((b & 0x80u) == 0)
        {
            // Canonical: a final byte of 0 only for the value 0 in one byte.
            if (b == 0 && k > 0)
                return false;
            if (value > 0xFFFFFFFFull)
                return false;
            z = static_cast<std::uint32_t>(value);
            return true;
        }
    }
    return false;
}

// ---- Rice coding (docs/protocol.md §5.6) ----------------------------------------------------
// Bits are written least significant first into bytes (bit i of the string is bit i % 8 of byte
// i / 8). A value z with parameter k: q = z >> k one-bits, a zero-bit, then the k low bits of z;
// if q >= k_rice_escape: k_rice_escape one-bits and the 32 bits of z instead.

class BitWriter
{
public:
    explicit BitWriter(std::vector<std::byte>& out) noexcept : out_(out) { out_.clear(); }
    /// Appends the low `count` bits of `bits` (count <= 32).
    void put(std::uint32_t bits, int count)
    {
        acc_ |= std::uint64_t{bits} << fill_;
        fill_ += count;
        while (fill_ >= 8)
        {
            out_.push_back(static_cast<std::byte>(acc_ & 0xFFu));
            acc_ >>= 8;
            fill_ -= 8;
        }
    }
    void finish()
    {
        if (fill_ > 0)
            out_.push_back(static_cast<std::byte>(acc_ & 0xFFu));
        acc_ = 0;
        fill_ = 0;
    }

private:
    std::vector<std::byte>& out_;
    std::uint64_t acc_ = 0;
    int fill_ = 0;
};

class BitReader
{
public:
    explicit BitReader(std::span<const std::byte> in) noexcept : in_(in) {}
    /// Reads `count` bits (count <= 32); false past the end.
    bool get(int count, std::uint32_t& bits) noexcept
    {
        std::uint64_t v = 0;
        for (int i = 0; i < count; ++i, ++pos_)
        {
            if (pos_ >= 8 * in_.size())
                return false;
            const auto byte = static_cast<std::uint8_t>(in_[pos_ / 8]);
            v |= std::uint64_t{(byte >> (pos_ % 8)) & 1u} << i;
        }
        bits = static_cast<std::uint32_t>(v);
        return true;
    }
    /// Counts one-bits up to the first zero-bit (consumed) or `limit` ones; false past the end.
    bool unary(int limit, int& ones) noexcept
    {
        ones = 0;
        while (ones < limit)
        {
            std::uint32_t b = 0;
            if (!get(1, b))
                return false;
            if (b == 0)
                return true;
            ++ones;
        }
        return true;
    }
    /// True if the reader is in the last byte and every bit left in it is zero.
    [[nodiscard]] bool at_clean_end() const noexcept
    {
        if ((pos_ + 7) / 8 != in_.size())
            return false;
        if (pos_ % 8 == 0)
            return true;
        const auto last = static_cast<std::uint8_t>(in_.back());
        return (last >> (pos_ % 8)) == 0;
    }

private:
    std::span<const std::byte> in_;
    std::size_t pos_ = 0;
};

constexpr int k_rice_parameter_bits = 5;

std::uint64_t rice_bits(std::uint32_t z, int k) noexcept
{
    const std::uint32_t q = z >> k;
    return q < static_cast<std::uint32_t>(k_rice_escape)
               ? std::uint64_t{q} + 1 + static_cast<std::uint64_t>(k)
               : std::uint64_t{k_rice_escape} + 32;
}

/// The parameter with the fewest bits for `r` (the smallest such), and that count.
int best_rice_parameter(std::span<const std::int32_t> r, std::uint64_t& bits) noexcept
{
    int best = 0;
    bits = std::numeric_limits<std::uint64_t>::max();
    for (int k = 0; k <= k_max_rice_parameter; ++k)
    {
        std::uint64_t total = 0;
        for (const std::int32_t x : r)
            total += rice_bits(zigzag(x), k);
        if (total < bits)
        {
            bits = total;
            best = k;
        }
    }
    return best;
}

void put_rice(BitWriter& w, std::span<const std::int32_t> r, int k)
{
    w.put(static_cast<std::uint32_t>(k), k_rice_parameter_bits);
    for (const std::int32_t x : r)
    {
        const std::uint32_t z = zigzag(x);
        const std::uint32_t q = z >> k;
        if (q < static_cast<std::uint32_t>(k_rice_escape))
        {
            w.put((1u << q) - 1u, static_cast<int>(q) + 1);  // q ones, then a zero
            if (k > 0)
                w.put(z & ((1u << k) - 1u), k);
        }
        else
        {
            w.put((1u << k_rice_escape) - 1u, k_rice_escape);
            w.put(z, 32);
        }
    }
}

bool get_rice(BitReader& in, std::span<std::int32_t> r) noexcept
{
    std::uint32_t k = 0;
    if (!in.get(k_rice_parameter_bits, k) || k > static_cast<std::uint32_t>(k_max_rice_parameter))
        return false;
    const int kk = static_cast<int>(k);
    for (std::int32_t& x : r)
    {
        int q = 0;
        if (!in.unary(k_rice_escape, q))
            return false;
        std::uint32_t z = 0;
        if (q == k_rice_escape)
        {
            // Canonical: the escape only where the short form does not fit.
            if (!in.get(32, z) || (z >> kk) < static_cast<std::uint32_t>(k_rice_escape))
                return false;
        }
        else
        {
            std::uint32_t low = 0;
            if (kk > 0 && !in.get(kk, low))
                return false;
            z = (static_cast<std::uint32_t>(q) << kk) | low;  // < 24 * 2^26: fits
        }
        x = unzigzag(z);
    }
    return true;
}

struct CctxFree
{
    void operator()(ZSTD_CCtx* c) const noexcept { ZSTD_freeCCtx(c); }
};
struct DctxFree
{
    void operator()(ZSTD_DCtx* d) const noexcept { ZSTD_freeDCtx(d); }
};

ZSTD_CCtx* cctx() noexcept
{
    thread_local std::unique_ptr<ZSTD_CCtx, CctxFree> ctx(ZSTD_createCCtx());
    return ctx.get();
}

ZSTD_DCtx* dctx() noexcept
{
    thread_local std::unique_ptr<ZSTD_DCtx, DctxFree> ctx(ZSTD_createDCtx());
    return ctx.get();
}

}  // namespace

double quantum(int exponent) noexcept
{
    return std::ldexp(1.0, exponent);
}

bool quantise(std::span<const double> x, int exponent, std::span<std::int32_t> q) noexcept
{
    const double scale = std::ldexp(1.0, -exponent);
    constexpr double limit = static_cast<double>(k_int32_max);
    for (std::size_t i = 0; i < x.size(); ++i)
    {
        if (!detail::is_finite_bits(x[i]))
            return false;
        const double r = std::round(x[i] * scale);  // exact scaling by a power of two
        if (!(std::fabs(r) <= limit))
            return false;
        q[i] = static_cast<std::int32_t>(r);
    }
    return true;
}

void dequantise(std::span<const std::int32_t> q, int exponent, std::span<double> x) noexcept
{
    const double step = std::ldexp(1.0, exponent);
    for (std::size_t i = 0; i < q.size(); ++i)
        x[i] = static_cast<double>(q[i]) * step;  // exact: |q| < 2^31 and a power-of-two step
}

bool make_residuals(std::span<const std::int32_t> q, std::span<const std::int32_t> base,
                    bool predicted, std::span<std::int32_t> r) noexcept
{
    const bool key = base.empty();
    std::int64_t previous = 0;
    for (std::size_t i = 0; i < q.size(); ++i)
    {
        const std::int64_t d = std::int64_t{q[i]} - (key ? 0 : std::int64_t{base[i]});
        const std::int64_t value = predicted ? d - previous : d;
        if (!fits_int32(value) || !fits_int32(d))
            return false;
        r[i] = static_cast<std::int32_t>(value);
        previous = d;
    }
    return true;
}

bool apply_residuals(std::span<const std::int32_t> r, std::span<const std::int32_t> base,
                     bool predicted, std::span<std::int32_t> q) noexcept
{
    const bool key = base.empty();
    std::int64_t d = 0;
    for (std::size_t i = 0; i < r.size(); ++i)
    {
        d = predicted ? d + r[i] : std::int64_t{r[i]};
        // d fits int32 at every node (make_residuals requires it), so the sums cannot overflow.
        const std::int64_t value = d + (key ? 0 : std::int64_t{base[i]});
        if (!fits_int32(value) || !fits_int32(d))
            return false;
        q[i] = static_cast<std::int32_t>(value);
    }
    return true;
}

bool prediction_pays(std::span<const std::int32_t> qu, std::span<const std::int32_t> base_u,
                     std::span<const std::int32_t> qv,
                     std::span<const std::int32_t> base_v) noexcept
{
    std::int64_t plain = 0;
    std::int64_t predicted = 0;
    auto add = [&](std::span<const std::int32_t> q, std::span<const std::int32_t> base)
    {
        std::int64_t previous = 0;
        for (std::size_t i = 0; i < q.size(); ++i)
        {
            const std::int64_t d = std::int64_t{q[i]} - (base.empty() ? 0 : std::int64_t{base[i]});
            plain += std::llabs(d);
            predicted += std::llabs(d - previous);
            previous = d;
        }
    };
    add(qu, base_u);
    add(qv, base_v);
    return predicted < plain;
}

bool pack_residuals(std::span<const std::int32_t> du, std::span<const std::int32_t> dv,
                    std::size_t max_bytes, std::vector<std::byte>& out)
{
    std::array<std::byte, k_max_unpacked_bytes> raw;
    std::size_t n = 0;
    for (const std::int32_t r : du)
        n += put_varint(zigzag(r), raw.data() + n);
    for (const std::int32_t r : dv)
        n += put_varint(zigzag(r), raw.data() + n);
    out.resize(ZSTD_compressBound(n));
    ZSTD_CCtx* ctx = cctx();
    if (ctx == nullptr)
        return false;
    const std::size_t size =
        ZSTD_compressCCtx(ctx, out.data(), out.size(), raw.data(), n, k_zstd_level);
    if (ZSTD_isError(size) || size > max_bytes)
        return false;
    out.resize(size);
    return true;
}

std::optional<DecodeError> unpack_residuals(std::span<const std::byte> packed,
                                            std::span<std::int32_t> du,
                                            std::span<std::int32_t> dv) noexcept
{
    const std::size_t n = du.size();
    if (n == 0 || n > k_max_leaf_nodes_quantised || dv.size() != n || packed.empty())
        return DecodeError::BadCompression;
    // Bound the decompressed size from the frame header before decompressing anything.
    const unsigned long long content = ZSTD_getFrameContentSize(packed.data(), packed.size());
    if (content == ZSTD_CONTENTSIZE_UNKNOWN || content == ZSTD_CONTENTSIZE_ERROR ||
        content < 2 * n || content > 10 * n)
        return DecodeError::BadCompression;
    // Exactly one frame, no trailing bytes.
    const std::size_t frame = ZSTD_findFrameCompressedSize(packed.data(), packed.size());
    if (ZSTD_isError(frame) || frame != packed.size())
        return DecodeError::BadCompression;
    ZSTD_DCtx* ctx = dctx();
    if (ctx == nullptr)
        return DecodeError::BadCompression;
    std::array<std::byte, k_max_unpacked_bytes> raw;
    const std::size_t got = ZSTD_decompressDCtx(ctx, raw.data(), static_cast<std::size_t>(content),
                                                packed.data(), packed.size());
    if (ZSTD_isError(got) || got != content)
        return DecodeError::BadCompression;
    std::size_t pos = 0;
    for (std::size_t k = 0; k < 2 * n; ++k)
    {
        std::uint32_t z = 0;
        if (!get_varint(raw.data(), got, pos, z))
            return DecodeError::BadCompression;
        (k < n ? du[k] : dv[k - n]) = unzigzag(z);
    }
    if (pos != got)
        return DecodeError::BadCompression;
    return {};
}

std::size_t rice_packed_size(std::span<const std::int32_t> du,
                             std::span<const std::int32_t> dv) noexcept
{
    std::uint64_t bu = 0;
    std::uint64_t bv = 0;
    (void)best_rice_parameter(du, bu);
    (void)best_rice_parameter(dv, bv);
    return static_cast<std::size_t>((2 * k_rice_parameter_bits + bu + bv + 7) / 8);
}

bool pack_residuals_rice(std::span<const std::int32_t> du, std::span<const std::int32_t> dv,
                         std::size_t max_bytes, std::vector<std::byte>& out)
{
    std::uint64_t bu = 0;
    std::uint64_t bv = 0;
    const int ku = best_rice_parameter(du, bu);
    const int kv = best_rice_parameter(dv, bv);
    if ((2 * k_rice_parameter_bits + bu + bv + 7) / 8 > max_bytes)
        return false;
    BitWriter w(out);
    put_rice(w, du, ku);
    put_rice(w, dv, kv);
    w.finish();
    return true;
}

std::optional<DecodeError> unpack_residuals_rice(std::span<const std::byte> packed,
                                                 std::span<std::int32_t> du,
                                                 std::span<std::int32_t> dv) noexcept
{
    const std::size_t n = du.size();
    if (n == 0 || n > k_max_leaf_nodes_quantised || dv.size() != n || packed.empty())
        return DecodeError::BadCompression;
    BitReader in(packed);
    if (!get_rice(in, du) || !get_rice(in, dv) || !in.at_clean_end())
        return DecodeError::BadCompression;
    return {};
}

std::optional<DecodeError> unpack_residuals(Packing packing, std::span<const std::byte> packed,
                                            std::span<std::int32_t> du,
                                            std::span<std::int32_t> dv) noexcept
{
    return packing == Packing::Rice ? unpack_residuals_rice(packed, du, dv)
                                    : unpack_residuals(packed, du, dv);
}

}  // namespace pliant::net
