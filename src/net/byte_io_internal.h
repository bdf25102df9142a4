// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Little-endian byte reader and writer for the codec. The reader never reads past its span: a read
// beyond the end returns 0 and sets `short_read`, so a decoder can read a whole fixed block and
// test once. Floats are moved as bit patterns (never through the FPU), so hostile NaNs stay inert.

#include <pliant/core/assert.h>

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace pliant::net::detail
{

/// True unless the exponent bits are all ones (NaN or infinity); no floating-point operation.
[[nodiscard]] inline bool is_finite_bits(double x) noexcept
{
    return ((std::bit_cast<std::uint64_t>(x) >> 52) & 0x7FFu) != 0x7FFu;
}

class ByteReader
{
public:
    explicit ByteReader(std::span<const std::byte> bytes) noexcept : bytes_(bytes) {}

    [[nodiscard]] std::size_t remaining() const noexcept { return bytes_.size() - pos_; }
    [[nodiscard]] bool short_read() const noexcept { return short_; }

    std::uint8_t u8() noexcept { return static_cast<std::uint8_t>(take(1)); }
    std::uint16_t u16() noexcept { return static_cast<std::uint16_t>(take(2)); }
    std::uint32_t u32() noexcept { return static_cast<std::uint32_t>(take(4)); }
    std::uint64_t u64() noexcept { return take(8); }
    double f64() noexcept { return std::bit_cast<double>(take(8)); }
    /// Widens an f32 to double; a non-finite f32 becomes +infinity built from bits, so the
    /// conversion never touches a (signalling) NaN.
    double f32() noexcept
    {
        const auto bits = static_cast<std::uint32_t>(take(4));
        if (((bits >> 23) & 0xFFu) == 0xFFu)
            return std::bit_cast<double>(std::uint64_t{0x7FF0000000000000ULL});
        return static_cast<double>(std::bit_cast<float>(bits));
    }
    /// Reads `n` f64 values into `out`; on a short read sets every one to 0.
    void f64s(double* out, std::size_t n) noexcept
    {
        if (n > remaining() / 8)
        {
            short_ = true;
            pos_ = bytes_.size();
            std::fill_n(out, n, 0.0);
            return;
        }
        if constexpr (std::endian::native == std::endian::little)
        {
            if (n > 0)
                std::memcpy(out, bytes_.data() + pos_, 8 * n);
            pos_ += 8 * n;
        }
        else
            for (std::size_t i = 0; i < n; ++i)
                out[i] = f64();
    }
    /// Copies `n` bytes to `out`; on a short read copies nothing.
    void bytes(std::byte* out, std::size_t n) noexcept
    {
        if (n > remaining())
        {
            short_ = true;
            pos_ = bytes_.size();
            return;
        }
        if (n > 0)
            std::memcpy(out, bytes_.data() + pos_, n);
        pos_ += n;
    }
    void skip(std::size_t n) noexcept
    {
        if (n > remaining())
        {
            short_ = true;
            pos_ = bytes_.size();
            return;
        }
        pos_ += n;
    }

private:
    std::uint64_t take(std::size_t n) noexcept
    {
        if (n > remaining())
        {
            short_ = true;
            pos_ = bytes_.size();
            return 0;
        }
        std::uint64_t v = 0;
        for (std::size_t i = 0; i < n; ++i)
            v |= static_cast<std::uint64_t>(bytes_[pos_ + i]) << (8 * i);
        pos_ += n;
        return v;
    }

    std::span<const std::byte> bytes_;
    std::size_t pos_ = 0;
    bool short_ = false;
};

/// Writes into a buffer the caller has sized with encoded_size(); overruns are bugs.
class ByteWriter
{
public:
    explicit ByteWriter(std::span<std::byte> out) noexcept : out_(out) {}

    [[nodiscard]] std::size_t size() const noexcept { return pos_; }

    void u8(std::uint8_t v) noexcept { put(v, 1); }
    void u16(std::uint16_t v) noexcept { put(v, 2); }
    void u32(std::uint32_t v) noexcept { put(v, 4); }
    void u64(std::uint64_t v) noexcept { put(v, 8); }
    void f64(double v) noexcept { put(std::bit_cast<std::uint64_t>(v), 8); }
    /// \pre v is finite and |v| <= FLT_MAX (validate() checked it).
    void f32(double v) noexcept { put(std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4); }
    /// Writes `n` f64 values (their bit patterns, little-endian).
    void f64s(const double* in, std::size_t n) noexcept
    {
        if constexpr (std::endian::native == std::endian::little)
            bytes(reinterpret_cast<const std::byte*>(in), 8 * n);
        else
            for (std::size_t i = 0; i < n; ++i)
                f64(in[i]);
    }
    void bytes(const std::byte* in, std::size_t n) noexcept
    {
        PLIANT_DEBUG_ASSERT(pos_ + n <= out_.size(), "ByteWriter overrun");
        if (n > 0)
            std::memcpy(out_.data() + pos_, in, n);
        pos_ += n;
    }
    void zeros(std::size_t n) noexcept
    {
        PLIANT_DEBUG_ASSERT(pos_ + n <= out_.size(), "ByteWriter overrun");
        std::memset(out_.data() + pos_, 0, n);
        pos_ += n;
    }

private:
    void put(std::uint64_t v, std::size_t n) noexcept
    {
        PLIANT_DEBUG_ASSERT(pos_ + n <= out_.size(), "ByteWriter overrun");
        for (std::size_t i = 0; i < n; ++i)
            out_[pos_ + i] = static_cast<std::byte>((v >> (8 * i)) & 0xFFu);
        pos_ += n;
    }

    std::span<std::byte> out_;
    std::size_t pos_ = 0;
};

}  // namespace pliant::net::detail
