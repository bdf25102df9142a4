// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for core::decode_grid, the reader of `.pgrid` files (docs/style.md §10), in the three
// modes of fuzz_support.h (raw bytes; the right checksum appended; a sample file with one byte
// changed and its checksum fixed; the samples: levels 1 and 2, with and without a displacement
// channel). A file that decode_grid accepts must encode back to exactly its bytes (the format is
// canonical), and a refusal must explain itself.
// Built with libFuzzer under clang, or as a corpus replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/core/grid_io.h>

#include "fuzz_support.h"
#include "grid_shapes.h"

#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{

using namespace pliant;

constexpr const char* k_target = "fuzz_grid_file";

void check(std::span<const std::byte> bytes)
{
    auto file = core::decode_grid(bytes, "fuzz");
    if (!file)
    {
        fuzz::require(!file.error().message.empty(), k_target, "a refusal without a message");
        return;
    }
    auto again = core::encode_grid(*file, "fuzz");
    fuzz::require(again.has_value(), k_target, "an accepted file does not encode");
    fuzz::require(again->size() == bytes.size() &&
                      std::memcmp(again->data(), bytes.data(), bytes.size()) == 0,
                  k_target, "an accepted file encodes to other bytes");
}

/// Levels 1 and 2, each as geometry only and with a displacement channel "u".
const std::vector<std::vector<std::byte>>& samples()
{
    static const std::vector<std::vector<std::byte>> out = []
    {
        std::vector<std::vector<std::byte>> s;
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
            s.push_back(core::encode_grid(file, "sample").value());
        }
        return s;
    }();
    return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    fuzz::checksummed_modes(
        data, size, samples(), check,
        [](std::span<const std::byte> b) { return core::decode_grid(b, "sample").has_value(); },
        k_target);
    return 0;
}
