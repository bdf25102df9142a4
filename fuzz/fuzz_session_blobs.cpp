// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for the Welcome's blobs, the bytes a joining peer takes from the master
// (docs/style.md §10): session::decode_model (level, material, rest positions, the session's
// choices) and session::decode_state (u and v of every node). The first input byte picks:
// - 0 (mod 4): raw bytes, the rest of the input as a model blob;
// - 1: raw bytes as a state blob of level (byte 1 mod 2) + 1;
// - 2: build -> encode -> corrupt one byte -> decode, a sample model blob (levels 1 and 2,
//   exact and fast coupling, each clearance); bytes 1..4 pick the sample, an offset and a mask;
// - 3: the same with a sample state blob.
// Samples must round-trip unmodified. A blob that is accepted must encode back to exactly its
// bytes (a version-1 model blob, which has no clearance byte, to one that decodes to the same
// model), and a refusal must explain itself.
// Built with libFuzzer under clang, or as a corpus replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>

#include "fuzz_support.h"
#include "grid_shapes.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{

using namespace pliant;

constexpr const char* k_target = "fuzz_session_blobs";

bool same_bytes(std::span<const std::byte> a, std::span<const std::byte> b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size()) == 0;
}

void check_model(std::span<const std::byte> blob)
{
    auto decoded = session::decode_model(blob);
    if (!decoded)
    {
        fuzz::require(!decoded.error().message.empty(), k_target, "a refusal without a message");
        return;
    }
    const auto encode = [](const session::DecodedModel& d)
    {
        return d.max_barrier_wait_s
                   ? session::encode_model(d.model, d.coupling, d.clearance, *d.max_barrier_wait_s)
                   : session::encode_model(d.model, d.coupling, d.clearance);
    };
    const auto again = encode(*decoded);
    if (blob.size() > 4 && blob[4] < std::byte{4})
    {
        // Versions 1 to 3: the encoder writes version 4; that must decode to the same model.
        auto second = session::decode_model(again);
        fuzz::require(second.has_value(), k_target,
                      "an older model version re-encodes to a refused blob");
        fuzz::require(same_bytes(encode(*second), again), k_target,
                      "an older model version does not round-trip");
        return;
    }
    fuzz::require(same_bytes(again, blob), k_target,
                  "an accepted model blob encodes to other bytes");
}

const core::TetraGrid& grid_of(int level)
{
    static const std::array<core::TetraGrid, 2> grids{core::TetraGrid::create(1).value(),
                                                      core::TetraGrid::create(2).value()};
    return grids[static_cast<std::size_t>(level - 1)];
}

void check_state(const core::TetraGrid& grid, std::span<const std::byte> blob)
{
    auto decoded = session::decode_state(grid, blob);
    if (!decoded)
    {
        fuzz::require(!decoded.error().message.empty(), k_target, "a refusal without a message");
        return;
    }
    fuzz::require(std::isfinite(decoded->time), k_target,
                  "an accepted state has a non-finite time");
    fuzz::require(same_bytes(session::encode_state(grid, decoded->u, decoded->v, decoded->tick,
                                                   decoded->time),
                             blob),
                  k_target, "an accepted state blob encodes to other bytes");
}

/// Spheres of levels 1 and 2 (radius 0.5 and 1.5, adaptive and fixed steps, no force limit and
/// 2.5 N), each coupling and clearance.
const std::vector<std::vector<std::byte>>& model_samples()
{
    static const std::vector<std::vector<std::byte>> out = []
    {
        std::vector<std::vector<std::byte>> s;
        for (int level = 1; level <= 2; ++level)
        {
            const core::TetraGrid& g = grid_of(level);
            sim::MembraneSettings settings;
            settings.fixed_step = level == 2;
            settings.beta = 0.5;
            settings.max_force = level == 2 ? 2.5 : 0.0;
            const auto model =
                sim::MembraneModel::create(g, scenes::sphere_grid(g, level - 0.5), settings)
                    .value();
            for (const auto coupling : {session::Coupling::Exact, session::Coupling::Fast})
                for (const std::optional<session::PointClearance> c :
                     {std::optional<session::PointClearance>{},
                      std::optional{session::PointClearance::AsGrown},
                      std::optional{session::PointClearance::Inside}})
                    s.push_back(session::encode_model(model, coupling, c));
        }
        return s;
    }();
    return out;
}

/// A state of levels 1 and 2: u = 0.01 x, v = -0.1 z at tick 42, 0.042 s.
std::vector<std::byte> state_sample(int level)
{
    const core::TetraGrid& g = grid_of(level);
    const auto p = scenes::sphere_grid(g, 1.0);
    core::Field<double> u(g), v(g);
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            u.at(x, y) = 0.01 * p[0].at(x, y);
            v.at(x, y) = -0.1 * p[2].at(x, y);
        }
    return session::encode_state(g, u, v, 42, 0.042);
}

void corrupt(std::vector<std::byte>& blob, const std::uint8_t* data)
{
    const std::size_t at = (std::size_t{data[2]} | (std::size_t{data[3]} << 8)) % blob.size();
    blob[at] ^= static_cast<std::byte>(data[4] == 0 ? 1 : data[4]);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0)
        return 0;
    const auto* bytes = reinterpret_cast<const std::byte*>(data);
    const int mode = data[0] % 4;
    if (mode == 0)
    {
        check_model(std::span(bytes + 1, size - 1));
        return 0;
    }
    if (size < 2)
        return 0;
    const int level = 1 + data[1] % 2;
    if (mode == 1)
    {
        check_state(grid_of(level), std::span(bytes + 2, size - 2));
        return 0;
    }
    if (size < 5)
        return 0;
    if (mode == 2)
    {
        const auto& samples = model_samples();
        std::vector<std::byte> blob = samples[data[1] % samples.size()];
        fuzz::require(session::decode_model(blob).has_value(), k_target,
                      "a model sample does not decode");
        check_model(blob);
        corrupt(blob, data);
        check_model(blob);
        return 0;
    }
    std::vector<std::byte> blob = state_sample(level);
    check_state(grid_of(level), blob);
    corrupt(blob, data);
    check_state(grid_of(level), blob);
    return 0;
}
