// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// A 64-bit hash of bytes for golden-hash determinism tests and file checksums (FNV-1a over
/// little-endian 8-byte words with a final avalanche; the same on every platform).

#include <cstddef>
#include <cstdint>
#include <span>

namespace pliant::core
{

/// Hashes `bytes`, continuing from `seed` (pass a previous result to chain several buffers).
[[nodiscard]] std::uint64_t hash_bytes(std::span<const std::byte> bytes,
                                       std::uint64_t seed = 0xcbf29ce484222325ULL) noexcept;

/// Hashes the bytes of a span of trivially copyable values.
template <typename T>
[[nodiscard]] std::uint64_t hash_span(std::span<const T> values,
                                      std::uint64_t seed = 0xcbf29ce484222325ULL) noexcept
{
    return hash_bytes(std::as_bytes(values), seed);
}

}  // namespace pliant::core
