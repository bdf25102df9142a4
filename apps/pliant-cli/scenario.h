// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once
// The scenario files of `pliant simulate` (TOML, docs/physics.md §7): material, integrator,
// duration, frame rate and timed forces. Read here, in the application: the sim library knows no
// file formats. Every refusal names the file, the line and the key (`file:line: 'key' ...`).
#include <pliant/core/result.h>
#include <pliant/core/vec3.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::cli
{

// The most frames a run writes (frame_NNNNN files; a day at 10 frames per second is 864,000).
inline constexpr double k_max_frames = 1e6;

struct TimedForce
{
    double start = 0.0;  ///< s
    double end = 0.0;    ///< s (the linear hold acts on start < t <= end, the step hold on
                         ///< [start, end)); the run's duration when the file gives none
    sim::Force force;
    std::optional<core::Vec3> to;  ///< a point force slides to here by `end` (slide_point)
    std::int64_t line = 0;         ///< where the [[force]] table starts in the file
    std::int64_t face_line = 0;    ///< where its `face` key is (face forces)
};

struct Scenario
{
    sim::MembraneSettings settings;
    double duration = 1.0;     ///< s (the default when the file gives none)
    double frame_rate = 25.0;  ///< frames per second (the default when the file gives none)
    int frames = 25;           ///< frames after frame 0: ceil(duration * frame_rate), the last
                               ///< one at `duration` (frame_time)
    std::vector<TimedForce> forces;
    std::map<std::string, std::int64_t> lines;  ///< the line of each key the file gives
                                                ///< ("integrator.fixed_dt")
};

/// When frame `frame` (0 .. sc.frames) is due: frame / frame_rate, and the last frame at the
/// duration itself, after a shorter interval when the duration is not a whole number of them.
[[nodiscard]] double frame_time(const Scenario& sc, int frame);

/// `v` as printf's %g.
[[nodiscard]] std::string fmt_number(double v);

/// Reads the scenario file `path`. \return BadScenario naming the file, line and key for a TOML
/// syntax error, an unknown key, a wrong type, a value out of range or values that contradict
/// each other (a force's end before its start, dt_min above dt_max, ...); warns about keys the
/// chosen step mode ignores, forces that start at or after the end of the run, and a file that
/// sets no key at all (the defaults in use).
[[nodiscard]] core::Result<Scenario> parse_scenario(const std::filesystem::path& path);

/// The same for the scenario text `text`, named `path` in messages (tests, the fuzz target).
[[nodiscard]] core::Result<Scenario> parse_scenario_text(std::string_view text,
                                                         const std::filesystem::path& path);

/// "file:line: 'key'" for a key the scenario gives, "file: 'key'" for a default.
[[nodiscard]] std::string key_at(const Scenario& sc, const std::filesystem::path& path,
                                 const std::string& key);

/// " (default)" when the scenario does not give `key`, else "".
[[nodiscard]] const char* default_note(const Scenario& sc, const std::string& key);

/// Mixed precision (docs/physics.md §9): the values of the step mode in use below the float
/// range are refused here, naming the key and its line (the library refuses them too, without
/// them); tolerances tight enough for the float rounding of the slopes to steer the step size
/// are warned about. `from_command_line`: the precision came from --precision.
[[nodiscard]] core::Result<void> check_mixed_precision(const Scenario& sc,
                                                       const std::filesystem::path& path,
                                                       bool from_command_line);

}  // namespace pliant::cli
