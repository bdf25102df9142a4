// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for session::decode_recording, the reader of `.prec` files that `pliant replay`
// takes (docs/style.md §10), in the three modes of fuzz_support.h (raw bytes; the right checksum
// appended; a sample recording, with and without a hash mask and forces, with one byte changed
// and its checksum fixed). A recording that decode_recording accepts must encode to a file that
// decodes to the same recording, and a refusal must explain itself. (A version-1 file, or a force
// entry of an earlier protocol version, is read as the current one, so the bytes may differ.)
// Built with libFuzzer under clang, or as a corpus replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/session/recording.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>

#include "fuzz_support.h"
#include "grid_shapes.h"

#include <cstdint>
#include <span>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{

using namespace pliant;

constexpr const char* k_target = "fuzz_recording";

void check(std::span<const std::byte> bytes)
{
    auto recording = session::decode_recording(bytes, "fuzz");
    if (!recording)
    {
        fuzz::require(!recording.error().message.empty(), k_target, "a refusal without a message");
        return;
    }
    auto encoded = session::encode_recording(*recording);
    fuzz::require(encoded.has_value(), k_target, "an accepted recording does not encode");
    auto again = session::decode_recording(*encoded, "fuzz");
    fuzz::require(again.has_value() && *again == *recording, k_target,
                  "an accepted recording does not round-trip");
}

/// A level-1 sphere in fixed steps; with k odd a hash mask and two peers' force lists (a face
/// grab, a point pull, a release).
const std::vector<std::vector<std::byte>>& samples()
{
    static const std::vector<std::vector<std::byte>> out = []
    {
        const auto grid = core::TetraGrid::create(1).value();
        sim::MembraneSettings settings;
        settings.fixed_step = true;
        const auto model =
            sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), settings).value();
        std::vector<std::vector<std::byte>> s(2);
        for (int k = 0; k < 2; ++k)
        {
            session::Recording r;
            r.model = session::encode_model(model, session::Coupling::Exact);
            r.final_tick = 100;
            if (k == 1)
            {
                r.final_hash = 0x1234'5678'9abc'def0ULL;
                r.hash_mask = {0xff, 0x02};  // 10 canonical nodes at level 1: 9 selected
                net::UserForce face;
                face.target.face = 3;
                face.grab_id = 1;
                face.force = {0.0, 0.0, 0.5};
                net::UserForce point;
                point.target.kind = net::TargetKind::Position;
                point.target.position = {0.1, 0.2, 0.9};
                point.target.radius = 0.25;
                point.force = {-0.5, 0.0, 0.0};
                r.forces = {{2, 10, {face}}, {3, 20, {point, face}}, {2, 60, {}}};
            }
            s[static_cast<std::size_t>(k)] = session::encode_recording(r).value();
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
        [](std::span<const std::byte> b)
        { return session::decode_recording(b, "sample").has_value(); },
        k_target);
    return 0;
}
