// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The value side of the quantised-delta encoding (docs/protocol.md §5.5): quantisation to a
/// power-of-two step, residuals against a baseline with optional left-neighbour prediction, and
/// the zstd packing of residuals. The net module knows no physics: these functions see integers,
/// values and a step exponent; the session decides what is quantised, with which step, and which
/// baseline the receiver holds.
///
/// Design: the step is 2^e with an integer exponent e, so q * 2^e is exact in `double` for every
/// representable q (|q| < 2^31), and dequantise(quantise(x)) is the same bits on every peer.
/// Rejected alternative: an arbitrary `f64` step, whose products round differently from the
/// quotient and would need the step on the wire as 8 bytes per datagram.
///
/// Thread safety: all functions may run concurrently; the zstd contexts are per thread.

#include <pliant/net/codec.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace pliant::net
{

/// Valid step exponents: a step of 2^-40 (about 1e-12) to 1.
inline constexpr int k_min_step_exponent = -40;
inline constexpr int k_max_step_exponent = 0;
/// Bytes of the unpacked residuals at most: 2 values per node, at most 5 bytes each (LEB128 of a
/// 32-bit zigzag value).
inline constexpr std::size_t k_max_unpacked_bytes = 2 * k_max_leaf_nodes_quantised * 5;

/// Largest Rice parameter (low bits per value) of pack_residuals_rice.
inline constexpr int k_max_rice_parameter = 26;
/// Unary length at which a Rice-coded value escapes to 32 raw bits.
inline constexpr int k_rice_escape = 24;

/// The step 2^exponent.
[[nodiscard]] double quantum(int exponent) noexcept;

/// q[i] = x[i] / 2^exponent rounded to nearest (ties away from zero), so |x - q 2^e| <= 2^e / 2.
/// \pre q.size() == x.size(). \return false (q unspecified) if some x is not finite or its q
/// does not fit `int32_t`.
[[nodiscard]] bool quantise(std::span<const double> x, int exponent,
                            std::span<std::int32_t> q) noexcept;

/// x[i] = q[i] * 2^exponent (exact). \pre x.size() == q.size().
void dequantise(std::span<const std::int32_t> q, int exponent, std::span<double> x) noexcept;

/// Residuals of `q` against `base` (an empty base is a key state: d = q, else d = q - base);
/// with `predicted`, r[i] = d[i] - d[i-1] (d[-1] = 0), else r = d.
/// \pre r.size() == q.size() and base is empty or as long. \return false if d or a residual does
/// not fit `int32_t` (r unspecified).
[[nodiscard]] bool make_residuals(std::span<const std::int32_t> q,
                                  std::span<const std::int32_t> base, bool predicted,
                                  std::span<std::int32_t> r) noexcept;

/// Inverse of make_residuals. Residuals may be hostile: \return false if a value does not fit
/// `int32_t` (q unspecified).
[[nodiscard]] bool apply_residuals(std::span<const std::int32_t> r,
                                   std::span<const std::int32_t> base, bool predicted,
                                   std::span<std::int32_t> q) noexcept;

/// Whether left-neighbour prediction pays: sum |d[i] - d[i-1]| < sum |d[i]| over both fields,
/// with d as in make_residuals (a cheap proxy for the packed size).
[[nodiscard]] bool prediction_pays(std::span<const std::int32_t> qu,
                                   std::span<const std::int32_t> base_u,
                                   std::span<const std::int32_t> qv,
                                   std::span<const std::int32_t> base_v) noexcept;

/// Packs residuals as one zstd frame (content size in the header) of 2n zigzag LEB128 varints,
/// du then dv. \pre du.size() == dv.size() in 1..k_max_leaf_nodes_quantised. \return false if
/// the frame would exceed `max_bytes` (the caller sends another encoding), `out` unspecified.
[[nodiscard]] bool pack_residuals(std::span<const std::int32_t> du,
                                  std::span<const std::int32_t> dv, std::size_t max_bytes,
                                  std::vector<std::byte>& out);

/// Packs residuals as two Rice-coded bit strings (docs/protocol.md §5.6), du then dv, each with
/// its own Rice parameter chosen for the fewest bits. Sub-byte: a residual of magnitude m costs
/// about log2(m) + 2 bits, where the varints of pack_residuals cost at least 8. \pre du.size()
/// == dv.size() in 1..k_max_leaf_nodes_quantised. \return false if the bits would exceed
/// `max_bytes`, `out` unspecified.
[[nodiscard]] bool pack_residuals_rice(std::span<const std::int32_t> du,
                                       std::span<const std::int32_t> dv, std::size_t max_bytes,
                                       std::vector<std::byte>& out);

/// Bytes pack_residuals_rice would write (without writing them).
[[nodiscard]] std::size_t rice_packed_size(std::span<const std::int32_t> du,
                                           std::span<const std::int32_t> dv) noexcept;

/// Unpacks bits written by pack_residuals_rice into du and dv (n values each). Hostile bytes:
/// parameters above k_max_rice_parameter, a value that does not fit 32 bits, an escape where the
/// short form fits, bits past the end, a byte too many or non-zero padding are all
/// DecodeError::BadCompression; the work is bounded by 2n values of at most 56 bits (an
/// escape: 24 + 32).
[[nodiscard]] std::optional<DecodeError> unpack_residuals_rice(std::span<const std::byte> packed,
                                                               std::span<std::int32_t> du,
                                                               std::span<std::int32_t> dv) noexcept;

/// Unpacks `packed` by `packing` (either function above).
[[nodiscard]] std::optional<DecodeError> unpack_residuals(Packing packing,
                                                          std::span<const std::byte> packed,
                                                          std::span<std::int32_t> du,
                                                          std::span<std::int32_t> dv) noexcept;

/// Unpacks a frame written by pack_residuals into du and dv (n = du.size() = dv.size() values
/// each). Hostile bytes: the content size is read from the frame header and must lie in
/// 2n..10n before anything is decompressed (into a stack buffer), the frame must span `packed`
/// exactly, and it must hold exactly 2n canonical varints. \return DecodeError::BadCompression
/// for any violation; nothing on success.
[[nodiscard]] std::optional<DecodeError> unpack_residuals(std::span<const std::byte> packed,
                                                          std::span<std::int32_t> du,
                                                          std::span<std::int32_t> dv) noexcept;

}  // namespace pliant::net
