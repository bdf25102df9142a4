// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for the scenario reader of `pliant simulate --scenario FILE.toml`
// (docs/style.md §10): the input is the TOML text. A refusal must name the file and its line; an
// accepted scenario must hold only what the reader promises (docs/physics.md §7): duration and
// frame rate in their ranges, at most 1,000,000 frames, forces with a finite vector, an end after
// the start, a face or a point with a positive radius (and a slide target only for points), the
// line of each; and settings that the sim library accepts once the mixed-precision check has
// passed, so that no value the reader lets through is refused later without its file and line.
// Built with libFuzzer under clang, or as a corpus replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/sim/membrane.h>

#include <spdlog/spdlog.h>

#include "fuzz_support.h"
#include "scenario.h"

#include <cmath>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{

using namespace pliant;

constexpr const char* k_target = "fuzz_scenario";

bool finite(const core::Vec3& v)
{
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void check_refusal(const core::Error& e)
{
    fuzz::require(e.code == core::ErrorCode::BadScenario, k_target,
                  "a refusal of another kind than BadScenario");
    fuzz::require(e.message.rfind("fuzz.toml:", 0) == 0, k_target,
                  "a refusal that does not name the file and line");
}

void check(const cli::Scenario& sc)
{
    fuzz::require(sc.duration >= 0.0 && sc.duration <= 1e6, k_target, "duration out of range");
    fuzz::require(sc.frame_rate >= 1e-3 && sc.frame_rate <= 1e4, k_target,
                  "frame rate out of range");
    fuzz::require(sc.frames >= 0 && sc.frames <= cli::k_max_frames, k_target,
                  "a frame count beyond the limit");
    for (const cli::TimedForce& f : sc.forces)
    {
        fuzz::require(f.start >= 0.0 && f.end > f.start && std::isfinite(f.end), k_target,
                      "a force whose end is not after its start");
        fuzz::require(finite(f.force.vector), k_target, "a non-finite force vector");
        fuzz::require(f.line >= 1, k_target, "a force without its line");
        if (f.force.face >= 0)
            fuzz::require(!f.to && f.face_line >= 1, k_target,
                          "a face force with a slide target or without the face's line");
        else
            fuzz::require(finite(f.force.point) && f.force.radius > 0.0 &&
                              std::isfinite(f.force.radius) && (!f.to || finite(*f.to)),
                          k_target, "a point force with a bad point, radius or target");
    }
    if (auto mixed = cli::check_mixed_precision(sc, "fuzz.toml", false); !mixed)
        return check_refusal(mixed.error());
    fuzz::require(sim::validate(sc.settings).has_value(), k_target,
                  "settings the reader accepted but the sim library refuses");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static const bool quiet = []
    {
        spdlog::set_level(spdlog::level::off);  // the reader's warnings about ignored keys
        return true;
    }();
    (void)quiet;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    auto scenario = cli::parse_scenario_text(text, "fuzz.toml");
    if (!scenario)
        check_refusal(scenario.error());
    else
        check(*scenario);
    return 0;
}
