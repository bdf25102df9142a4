// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for session::decode_recording, the reader of `.prec` files that `pliant replay`
// takes (STYLE.md §10). A file ends in a checksum of everything before it, so, as in
// fuzz_grid_file.cpp, the first input byte mod 3 picks the mode:
// - 0: raw bytes. The rest of the input is the file.
// - 1: the rest of the input is the file without its checksum; the harness appends it.
// - 2: build -> encode -> corrupt one byte -> fix the checksum -> decode. Bytes 1..4 pick a
//   sample recording (with and without a hash mask and forces), a byte offset and an XOR mask;
//   the sample must round-trip unmodified.
// In every mode a recording that decode_recording accepts must encode to a file that decodes to
// the same recording, and a refusal must explain itself. (A version-1 file, or a force entry of
// an earlier protocol version, is read as the current one, so the bytes themselves may differ.)
// Built with libFuzzer under clang, or as a corpus replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/core/hash.h>
#include <pliant/session/recording.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>

#include "grid_shapes.h"

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
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
        std::fprintf(stderr, "fuzz_recording: %s\n", what);
        std::abort();
    }
}

void check(std::span<const std::byte> bytes)
{
    auto recording = session::decode_recording(bytes, "fuzz");
    if (!recording)
    {
        require(!recording.error().message.empty(), "a refusal without a message");
        return;
    }
    auto encoded = session::encode_recording(*recording);
    require(encoded.has_value(), "an accepted recording does not encode");
    auto again = session::decode_recording(*encoded, "fuzz");
    require(again.has_value() && *again == *recording, "an accepted recording does not round-trip");
}

void append_checksum(std::vector<std::byte>& bytes)
{
    const std::uint64_t h = core::hash_bytes(bytes);
    const auto* p = reinterpret_cast<const std::byte*>(&h);
    bytes.insert(bytes.end(), p, p + sizeof h);
}

/// A level-1 sphere in fixed steps; with k odd a hash mask and two peers' force lists (a face
/// grab, a point pull, a release).
const std::array<std::vector<std::byte>, 2>& samples()
{
    static const std::array<std::vector<std::byte>, 2> out = []
    {
        const auto grid = core::TetraGrid::create(1).value();
        sim::MembraneSettings settings;
        settings.fixed_step = true;
        const auto model =
            sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), settings).value();
        std::array<std::vector<std::byte>, 2> s;
        for (int k = 0; k < 2; ++k)
        {
            session::Recording r;
            r.model = session::encode_model(model, session::Coupling::Exact);
            r.final_tick = 100;
            if (k == 1)
            {
                r.final_hash = 0x1234'5678'9abc'def0ULL;
                r.hash_mask = {0xff, 0x0f, 0x03};
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
        const std::vector<std::byte>& sample = samples()[data[1] % 2];
        require(session::decode_recording(sample, "sample").has_value(),
                "a sample does not decode");
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
