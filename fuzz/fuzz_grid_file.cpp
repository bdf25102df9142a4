// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for core::decode_grid, the reader of `.pgrid` files (STYLE.md §10). A file ends in
// a checksum of everything before it, which random bytes almost never match, so two of the
// three modes (the first input byte mod 3) append the right checksum to reach the parser:
// - 0: raw bytes. The rest of the input is the file.
// - 1: the rest of the input is the file without its checksum; the harness appends it.
// - 2: build -> encode -> corrupt one byte -> fix the checksum -> decode. Bytes 1..4 pick a
//   sample grid file (levels 1 and 2, with and without a displacement channel), a byte offset
//   and an XOR mask; the sample must round-trip unmodified.
// In every mode a file that decode_grid accepts must encode back to exactly its bytes (the
// format is canonical), and a refusal must explain itself.
// Built with libFuzzer under clang, or as a corpus replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/core/grid_io.h>
#include <pliant/core/hash.h>

#include "grid_shapes.h"

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{

using namespace pliant;

void require(bool ok, const char* what)
{
    if (!ok)
    {
        std::fprintf(stderr, "fuzz_grid_file: %s\n", what);
        std::abort();
    }
}

void check(std::span<const std::byte> bytes)
{
    auto file = core::decode_grid(bytes, "fuzz");
    if (!file)
    {
        require(!file.error().message.empty(), "a refusal without a message");
        return;
    }
    auto again = core::encode_grid(*file, "fuzz");
    require(again.has_value(), "an accepted file does not encode");
    require(again->size() == bytes.size() &&
                std::memcmp(again->data(), bytes.data(), bytes.size()) == 0,
            "an accepted file encodes to other bytes");
}

void append_checksum(std::vector<std::byte>& bytes)
{
    const std::uint64_t h = core::hash_bytes(bytes);
    const auto* p = reinterpret_cast<const std::byte*>(&h);
    bytes.insert(bytes.end(), p, p + sizeof h);
}

/// Levels 1 and 2, each as geometry only and with a displacement channel "u".
const std::array<std::vector<std::byte>, 4>& samples()
{
    static const std::array<std::vector<std::byte>, 4> out = []
    {
        std::array<std::vector<std::byte>, 4> s;
        for (int k = 0; k < 4; ++k)
        {
            const auto grid = core::TetraGrid::create(1 + k / 2).value();
            core::GridFile file = core::make_geometry_file(grid, scenes::sphere_grid(grid, 1.0));
            if (k % 2 == 1)
            {
                core::Field<double> u(grid);
                for (std::uint32_t i = 0; i < grid.node_count(); ++i)
                    u[core::NodeIndex{i}] = 0.01 * (*file.find("px"))[core::NodeIndex{i}];
                file.fields.push_back({"u", std::move(u)});
            }
            s[static_cast<std::size_t>(k)] = core::encode_grid(file, "sample").value();
        }
        return s;
    }();
    return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0)
        return 0;
    const auto* bytes = reinterpret_cast<const std::byte*>(data);
    switch (data[0] % 3)
    {
    case 0: check(std::span(bytes + 1, size - 1)); break;
    case 1:
    {
        std::vector<std::byte> file(bytes + 1, bytes + size);
        append_checksum(file);
        check(file);
        break;
    }
    default:
    {
        if (size < 5)
            return 0;
        const std::vector<std::byte>& sample = samples()[data[1] % 4];
        auto decoded = core::decode_grid(sample, "sample");
        require(decoded.has_value(), "a sample does not decode");
        std::vector<std::byte> file(sample.begin(), sample.end() - 8);
        const std::size_t at = (std::size_t{data[2]} | (std::size_t{data[3]} << 8)) % file.size();
        file[at] ^= static_cast<std::byte>(data[4] == 0 ? 1 : data[4]);
        append_checksum(file);
        check(file);
        break;
    }
    }
    return 0;
}
