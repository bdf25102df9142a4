// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Shared by the fuzz targets: a check that stops the run naming the target, and the three modes
// of the readers whose files end in a checksum of everything before it (fuzz_grid_file,
// fuzz_recording), chosen by the first input byte mod 3:
// - 0: raw bytes. The rest of the input is the file (random bytes almost never pass the
//   checksum, so this mode tries the checks before it);
// - 1: the rest of the input is the file without its checksum; the right one is appended;
// - 2: build -> encode -> corrupt one byte -> fix the checksum. Bytes 1..4 pick a sample file,
//   a byte offset and an XOR mask; the sample must be accepted unmodified.

#include <pliant/core/hash.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <vector>

namespace pliant::fuzz
{

/// Stops the run (a finding) when `ok` is false.
inline void require(bool ok, const char* target, const char* what)
{
    if (!ok)
    {
        std::fprintf(stderr, "%s: %s\n", target, what);
        std::abort();
    }
}

inline void append_checksum(std::vector<std::byte>& bytes)
{
    const std::uint64_t h = core::hash_bytes(bytes);
    const auto* p = reinterpret_cast<const std::byte*>(&h);
    bytes.insert(bytes.end(), p, p + sizeof h);
}

/// Runs one input through the three modes above. `check(bytes)` reads a file and checks what it
/// gives; `accepts(bytes)` says whether a sample is read at all; `samples` are whole files.
template <typename Check, typename Accepts>
void checksummed_modes(const std::uint8_t* data, std::size_t size,
                       const std::vector<std::vector<std::byte>>& samples, const Check& check,
                       const Accepts& accepts, const char* target)
{
    if (size == 0)
        return;
    const auto* bytes = reinterpret_cast<const std::byte*>(data);
    if (data[0] % 3 == 0)
    {
        check(std::span<const std::byte>(bytes + 1, size - 1));
        return;
    }
    if (data[0] % 3 == 1)
    {
        std::vector<std::byte> file(bytes + 1, bytes + size);
        append_checksum(file);
        check(std::span<const std::byte>(file));
        return;
    }
    if (size < 5)
        return;
    const std::vector<std::byte>& sample = samples[data[1] % samples.size()];
    require(accepts(std::span<const std::byte>(sample)), target, "a sample is refused");
    std::vector<std::byte> file(sample.begin(), sample.end() - 8);
    const std::size_t at = (std::size_t{data[2]} | (std::size_t{data[3]} << 8)) % file.size();
    file[at] ^= static_cast<std::byte>(data[4] == 0 ? 1 : data[4]);
    append_checksum(file);
    check(std::span<const std::byte>(file));
}

}  // namespace pliant::fuzz
