// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/hash.h>

namespace pliant::core
{

std::uint64_t hash_bytes(std::span<const std::byte> bytes, std::uint64_t seed) noexcept
{
    constexpr std::uint64_t k_prime = 0x100000001b3ULL;
    std::uint64_t h = seed;
    std::size_t i = 0;
    for (; i + 8 <= bytes.size(); i += 8)
    {
        // Little-endian whatever the host, so that peers and recordings agree (docs/protocol.md).
        std::uint64_t word = 0;
        for (std::size_t k = 0; k < 8; ++k)
            word |= static_cast<std::uint64_t>(bytes[i + k]) << (8 * k);
        h = (h ^ word) * k_prime;
        h ^= h >> 29;
    }
    for (; i < bytes.size(); ++i)
        h = (h ^ static_cast<std::uint64_t>(bytes[i])) * k_prime;
    // final avalanche (splitmix64 finaliser)
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ULL;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebULL;
    h ^= h >> 31;
    return h;
}

}  // namespace pliant::core
