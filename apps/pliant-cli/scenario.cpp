// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "scenario.h"

#include <spdlog/spdlog.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>
#include <string>
#include <utility>

namespace pliant::cli
{
namespace
{

// A scenario error naming the file, the key and its line.
core::Error scenario_error(const std::filesystem::path& file, const toml::source_region& where,
                           const std::string& key, const std::string& what)
{
    return {core::ErrorCode::BadScenario,
            file.string() + ":" + std::to_string(where.begin.line) + ": '" + key + "' " + what};
}

class Reader
{
public:
    Reader(const std::filesystem::path& file, const toml::table& table, std::string prefix)
        : file_(file), table_(table), prefix_(std::move(prefix))
    {
    }

    // Rejects keys this reader does not know (typos must not be ignored silently).
    [[nodiscard]] std::optional<core::Error> unknown_keys(const std::set<std::string>& known) const
    {
        for (auto&& [key, node] : table_)
            if (known.count(std::string(key.str())) == 0)
                return scenario_error(file_, key.source(), prefix_ + std::string(key.str()),
                                      "is not a known key here (known: " + join(known) + ")");
        return std::nullopt;
    }

    // A TOML number as a double: toml++'s value<double>() gives nothing for an integer a double
    // cannot hold exactly (2^63 - 1 was "must be a number"); it is read as the nearest double,
    // which the range check then judges.
    [[nodiscard]] static std::optional<double> number_of(const toml::node& node)
    {
        if (const auto* i = node.as_integer())
            return static_cast<double>(i->get());
        if (const auto* f = node.as_floating_point())
            return f->get();
        return std::nullopt;
    }

    // Reads an optional number into `out`, checking the range [lo, hi].
    [[nodiscard]] std::optional<core::Error> number(const std::string& key, double& out, double lo,
                                                    double hi) const
    {
        const toml::node* node = table_.get(key);
        if (node == nullptr)
            return std::nullopt;
        const std::optional<double> v = number_of(*node);
        if (!v)
            return scenario_error(file_, node->source(), prefix_ + key, "must be a number");
        if (!(*v >= lo && *v <= hi))
            return scenario_error(file_, node->source(), prefix_ + key,
                                  "= " + fmt_number(*v) + " is outside [" + fmt_number(lo) + ", " +
                                      fmt_number(hi) + "]");
        out = *v;
        return std::nullopt;
    }

    [[nodiscard]] std::optional<core::Error> integer(const std::string& key, int& out, int lo,
                                                     int hi) const
    {
        const toml::node* node = table_.get(key);
        if (node == nullptr)
            return std::nullopt;
        const std::optional<std::int64_t> v = node->value_exact<std::int64_t>();
        if (!v)
            return scenario_error(file_, node->source(), prefix_ + key, "must be an integer");
        if (*v < lo || *v > hi)
            return scenario_error(file_, node->source(), prefix_ + key,
                                  "= " + std::to_string(*v) + " is outside [" + std::to_string(lo) +
                                      ", " + std::to_string(hi) + "]");
        out = static_cast<int>(*v);
        return std::nullopt;
    }

    [[nodiscard]] std::optional<core::Error> boolean(const std::string& key, bool& out) const
    {
        const toml::node* node = table_.get(key);
        if (node == nullptr)
            return std::nullopt;
        const std::optional<bool> v = node->value_exact<bool>();
        if (!v)
            return scenario_error(file_, node->source(), prefix_ + key, "must be true or false");
        out = *v;
        return std::nullopt;
    }

    // Reads an optional string that must be one of `allowed`.
    [[nodiscard]] std::optional<core::Error> choice(const std::string& key, std::string& out,
                                                    const std::set<std::string>& allowed) const
    {
        const toml::node* node = table_.get(key);
        if (node == nullptr)
            return std::nullopt;
        const std::optional<std::string> v = node->value_exact<std::string>();
        if (!v || allowed.count(*v) == 0)
            return scenario_error(file_, node->source(), prefix_ + key,
                                  "must be one of: " + join(allowed) + " (a quoted string)");
        out = *v;
        return std::nullopt;
    }

    [[nodiscard]] std::optional<core::Error> vec3(const std::string& key,
                                                  std::optional<core::Vec3>& out) const
    {
        const toml::node* node = table_.get(key);
        if (node == nullptr)
            return std::nullopt;
        const toml::array* arr = node->as_array();
        if (arr == nullptr || arr->size() != 3)
            return scenario_error(file_, node->source(), prefix_ + key,
                                  "must be an array of three numbers, e.g. [0.0, 0.0, 1.0]");
        double c[3] = {};
        for (std::size_t k = 0; k < 3; ++k)
        {
            const std::optional<double> v = number_of((*arr)[k]);
            if (!v || !std::isfinite(*v))
                return scenario_error(file_, node->source(), prefix_ + key,
                                      "must be an array of three finite numbers");
            c[k] = *v;
        }
        out = core::Vec3{c[0], c[1], c[2]};
        return std::nullopt;
    }

    [[nodiscard]] bool has(const std::string& key) const { return table_.get(key) != nullptr; }

    // Records the line of every key of this table in `lines` (prefixed, as errors name them).
    void record_lines(std::map<std::string, std::int64_t>& lines) const
    {
        for (auto&& [key, node] : table_)
            lines[prefix_ + std::string(key.str())] = node.source().begin.line;
    }

    [[nodiscard]] const toml::table& table() const noexcept { return table_; }

private:
    static std::string join(const std::set<std::string>& keys)
    {
        std::string s;
        for (const std::string& k : keys)
            s += (s.empty() ? "" : ", ") + k;
        return s;
    }

    const std::filesystem::path& file_;
    const toml::table& table_;
    std::string prefix_;
};

#define PLIANT_TRY(expr)                          \
    do                                            \
    {                                             \
        if (auto err_ = (expr); err_.has_value()) \
            return *err_;                         \
    } while (false)

core::Error syntax_error(const std::filesystem::path& path, const toml::parse_error& e)
{
    return core::Error{core::ErrorCode::BadScenario,
                       path.string() + ":" + std::to_string(e.source().begin.line) + ":" +
                           std::to_string(e.source().begin.column) + ": " +
                           std::string(e.description())};
}

// Whether `table` holds no value but (nested) empty tables: a file of comments alone, or of
// empty sections.
bool sets_no_key(const toml::table& table)
{
    for (auto&& [key, node] : table)
        if (!node.is_table() || !sets_no_key(*node.as_table()))
            return false;
    return true;
}

// The steps a run takes at the least (duration over the largest step): more than
// k_max_steps could not end (1e-300 s steps sat at t = 0 for ever, the progress bar at 0 %);
// a fixed step longer than the duration simulates nothing (0 steps, exit 0 before); one longer
// than the frame interval repeats frames, which is said.
constexpr double k_max_steps = 1e12;

std::optional<core::Error> check_step_count(const Scenario& sc, const std::filesystem::path& path)
{
    const sim::MembraneSettings& s = sc.settings;
    if (!(sc.duration > 0.0))
        return std::nullopt;
    const char* key = s.fixed_step ? "fixed_dt" : "dt_max";
    const std::string name = std::string("integrator.") + key;
    const double largest = s.fixed_step ? s.fixed_dt : s.dt_max;
    const std::string value =
        key_at(sc, path, name) + " = " + fmt_number(largest) + " s" + default_note(sc, name);
    if (sc.duration / largest > k_max_steps)
        return core::Error{core::ErrorCode::BadScenario,
                           value + " would take over " + fmt_number(k_max_steps) +
                               " steps to cover 'duration' = " + fmt_number(sc.duration) +
                               " s; use " + key + " >= " + fmt_number(sc.duration / k_max_steps) +
                               " s"};
    if (s.fixed_step && s.fixed_dt > sc.duration)
        return core::Error{core::ErrorCode::BadScenario,
                           value + " is longer than 'duration' = " + fmt_number(sc.duration) +
                               " s: no step fits and the run would simulate nothing; use "
                               "fixed_dt <= " +
                               fmt_number(sc.duration) + " s"};
    if (s.fixed_step && s.fixed_dt * sc.frame_rate > 1.0)
        spdlog::warn(
            "{} is longer than the frame interval {} s ('frame_rate' = {}): frames "
            "without a step between them repeat the state before them",
            value, fmt_number(1.0 / sc.frame_rate), fmt_number(sc.frame_rate));
    return std::nullopt;
}

core::Result<Scenario> read_scenario(const toml::table& root, const std::filesystem::path& path)
{
    Scenario sc;
    // Scenario forces are functions of time: sampled at frame (and start/end) times and held
    // linearly between them unless the file asks for the zero-order hold.
    sc.settings.force_hold = sim::ForceHold::Linear;
    const Reader top(path, root, "");
    if (sets_no_key(root))
        spdlog::warn(
            "{} sets no key: using the defaults (duration = {} s, frame_rate = {} "
            "frames/s, no force, material T = {}, rho = {}, beta = {}, k_f = {}, "
            "adaptive steps with rtol = {}; docs/physics.md §7)",
            path.string(), fmt_number(sc.duration), fmt_number(sc.frame_rate),
            fmt_number(sc.settings.T), fmt_number(sc.settings.rho), fmt_number(sc.settings.beta),
            fmt_number(sc.settings.k_f), fmt_number(sc.settings.rtol));
    PLIANT_TRY(top.unknown_keys({"duration", "frame_rate", "material", "integrator", "force"}));
    PLIANT_TRY(top.number("duration", sc.duration, 0.0, 1e6));
    PLIANT_TRY(top.number("frame_rate", sc.frame_rate, 1e-3, 1e4));
    top.record_lines(sc.lines);
    // Frame numbers are ints and every frame is a file: refuse runs that would write more than
    // k_max_frames (1e6 s at 1e4 frames per second would be 1e10). A duration that is not a whole
    // number of frame intervals ends with a shorter one, its frame at the duration (frame_time):
    // the run simulates the whole duration (it stopped at the last whole interval before).
    const double intervals = sc.duration * sc.frame_rate;
    double frame_count = std::floor(intervals + 1e-9);
    if (intervals - frame_count > 1e-9 || (frame_count == 0.0 && intervals > 0.0))
        frame_count += 1.0;
    if (frame_count > k_max_frames)
    {
        const bool rate_given = top.has("frame_rate");
        const std::string key = rate_given ? "frame_rate" : "duration";
        const std::string what = rate_given
                                     ? "= " + fmt_number(sc.frame_rate) +
                                           " with 'duration' = " + fmt_number(sc.duration) + " s"
                                     : "= " + fmt_number(sc.duration) +
                                           " s at 'frame_rate' = " + fmt_number(sc.frame_rate);
        return scenario_error(path, root.get(key)->source(), key,
                              what + " makes " + fmt_number(frame_count) +
                                  " frames; a run writes at most " +
                                  std::to_string(static_cast<long>(k_max_frames)));
    }
    sc.frames = static_cast<int>(frame_count);

    sim::MembraneSettings& s = sc.settings;
    if (const toml::node* node = root.get("material"))
    {
        if (!node->is_table())
            return scenario_error(path, node->source(), "material", "must be a table");
        const Reader r(path, *node->as_table(), "material.");
        PLIANT_TRY(r.unknown_keys({"T", "rho", "beta", "k_f", "max_force"}));
        PLIANT_TRY(r.number("T", s.T, 1e-12, 1e12));
        PLIANT_TRY(r.number("rho", s.rho, 1e-12, 1e12));
        PLIANT_TRY(r.number("beta", s.beta, 0.0, 1e12));
        PLIANT_TRY(r.number("k_f", s.k_f, 0.0, 1e12));
        PLIANT_TRY(r.number("max_force", s.max_force, 0.0, 1e300));
        r.record_lines(sc.lines);
    }
    if (const toml::node* node = root.get("integrator"))
    {
        if (!node->is_table())
            return scenario_error(path, node->source(), "integrator", "must be a table");
        const toml::table& table = *node->as_table();
        const Reader r(path, table, "integrator.");
        PLIANT_TRY(r.unknown_keys({"rtol", "atol", "dt_min", "dt_max", "dt_initial", "safety",
                                   "max_growth", "min_shrink", "fixed_step", "fixed_dt",
                                   "reassemble_every", "threads", "force_hold", "precision"}));
        PLIANT_TRY(r.number("rtol", s.rtol, 0.0, 0.5));
        PLIANT_TRY(r.number("atol", s.atol, 1e-300, 1e6));
        PLIANT_TRY(r.number("dt_min", s.dt_min, 1e-300, 1e6));
        PLIANT_TRY(r.number("dt_max", s.dt_max, 1e-300, 1e6));
        PLIANT_TRY(r.number("dt_initial", s.dt_initial, 1e-300, 1e6));
        PLIANT_TRY(r.number("safety", s.safety, 1e-3, 1.0));
        PLIANT_TRY(r.number("max_growth", s.max_growth, 1.0 + 1e-9, 1e3));
        PLIANT_TRY(r.number("min_shrink", s.min_shrink, 1e-6, 1.0 - 1e-9));
        PLIANT_TRY(r.boolean("fixed_step", s.fixed_step));
        PLIANT_TRY(r.number("fixed_dt", s.fixed_dt, 1e-300, 1e6));
        PLIANT_TRY(r.integer("reassemble_every", s.reassemble_every, 0, 1 << 30));
        PLIANT_TRY(r.integer("threads", s.threads, 0, 1024));
        const std::string linear(sim::to_string(sim::ForceHold::Linear));
        std::string hold(sim::to_string(s.force_hold));
        PLIANT_TRY(r.choice("force_hold", hold,
                            {linear, std::string(sim::to_string(sim::ForceHold::Step))}));
        s.force_hold = hold == linear ? sim::ForceHold::Linear : sim::ForceHold::Step;
        const std::string mixed(sim::to_string(sim::Precision::Mixed));
        std::string precision(sim::to_string(s.precision));
        PLIANT_TRY(r.choice("precision", precision,
                            {std::string(sim::to_string(sim::Precision::Double)), mixed}));
        s.precision = precision == mixed ? sim::Precision::Mixed : sim::Precision::Double;
        r.record_lines(sc.lines);
        // Each message names the key the file gives and says which value is a default.
        const auto given = [&](const char* key) { return r.has(key); };
        const auto value = [&](const char* key, double v) {
            return "'" + std::string(key) + "' = " + fmt_number(v) +
                   (given(key) ? "" : " (default)");
        };
        if (s.dt_min > s.dt_max)
        {
            const bool min_given = given("dt_min");
            return scenario_error(
                path, table.get(min_given ? "dt_min" : "dt_max")->source(),
                min_given ? "integrator.dt_min" : "integrator.dt_max",
                min_given ? "= " + fmt_number(s.dt_min) + " is above " + value("dt_max", s.dt_max)
                          : "= " + fmt_number(s.dt_max) + " is below " + value("dt_min", s.dt_min));
        }
        if (!given("dt_initial"))
            s.dt_initial = std::clamp(s.dt_initial, s.dt_min, s.dt_max);  // the default fits
        else if (s.dt_initial < s.dt_min || s.dt_initial > s.dt_max)
            return scenario_error(path, table.get("dt_initial")->source(), "integrator.dt_initial",
                                  "= " + fmt_number(s.dt_initial) + " is outside [" +
                                      value("dt_min", s.dt_min) + ", " + value("dt_max", s.dt_max) +
                                      "]");
        // Keys the chosen mode ignores are warned about, not refused: a file may keep both.
        if (!s.fixed_step && given("fixed_dt"))
            spdlog::warn(
                "{}:{}: 'integrator.fixed_dt' has no effect without 'fixed_step = true' "
                "(the steps are adaptive)",
                path.string(), sc.lines["integrator.fixed_dt"]);
        if (s.fixed_step)
            for (const char* key : {"rtol", "atol", "dt_min", "dt_max", "dt_initial", "safety",
                                    "max_growth", "min_shrink"})
                if (given(key))
                    spdlog::warn(
                        "{}:{}: 'integrator.{}' has no effect with 'fixed_step = true' "
                        "(every step is fixed_dt)",
                        path.string(), sc.lines["integrator." + std::string(key)], key);
    }
    if (const toml::node* node = root.get("force"))
    {
        const toml::array* arr = node->as_array();
        if (arr == nullptr)
            return scenario_error(path, node->source(), "force",
                                  "must be an array of tables ([[force]] sections)");
        if (!arr->empty() && !(sc.duration > 0.0))
            return scenario_error(
                path, root.get("duration")->source(), "duration",
                "= " + fmt_number(sc.duration) + " s: a scenario with forces needs a duration > 0");
        for (std::size_t k = 0; k < arr->size(); ++k)
        {
            const toml::node& item = (*arr)[k];
            const std::string prefix = "force[" + std::to_string(k) + "].";
            if (!item.is_table())
                return scenario_error(path, item.source(), "force[" + std::to_string(k) + "]",
                                      "must be a table");
            const toml::table& table = *item.as_table();
            const Reader r(path, table, prefix);
            PLIANT_TRY(r.unknown_keys({"start", "end", "face", "point", "to", "radius", "vector"}));
            TimedForce f;
            f.end = sc.duration;  // documented default: the force acts until the run ends
            PLIANT_TRY(r.number("start", f.start, 0.0, 1e6));
            PLIANT_TRY(r.number("end", f.end, 0.0, 1e6));
            int face = -1;
            PLIANT_TRY(r.integer("face", face, 0, 1 << 30));
            std::optional<core::Vec3> point;
            std::optional<core::Vec3> vector;
            PLIANT_TRY(r.vec3("point", point));
            PLIANT_TRY(r.vec3("to", f.to));
            PLIANT_TRY(r.vec3("vector", vector));
            PLIANT_TRY(r.number("radius", f.force.radius, 0.0, 1e6));
            if (!vector)
                return scenario_error(path, item.source(), prefix + "vector",
                                      "is missing (the force in newtons, [fx, fy, fz])");
            if ((face >= 0) == point.has_value())
                return scenario_error(path, item.source(), prefix + "face",
                                      "or 'point' (with 'radius'): exactly one must be given");
            if (f.to && face >= 0)
                return scenario_error(path, item.source(), prefix + "to",
                                      "only applies to point forces");
            if (point && !r.has("radius"))
                return scenario_error(path, item.source(), prefix + "radius",
                                      "is missing: a point force spreads over the vertices "
                                      "within this distance [m] of its point");
            if (point && !(f.force.radius > 0.0))
                return scenario_error(path, table.get("radius")->source(), prefix + "radius",
                                      "= 0 must be > 0 for a point force (one shorter than the "
                                      "edges puts the whole force on the nearest vertex)");
            if (face >= 0 && r.has("radius"))
                spdlog::warn("{}:{}: '{}radius' has no effect on a face force", path.string(),
                             table.get("radius")->source().begin.line, prefix);
            // An 'end' given must follow 'start'; without one, 'end' is the duration, and a
            // force starting there or later is warned about below, as with an 'end' given.
            if (!(f.end > f.start) && r.has("end"))
                return scenario_error(path, table.get("end")->source(), prefix + "end",
                                      "= " + fmt_number(f.end) +
                                          " s must be later than 'start' = " + fmt_number(f.start) +
                                          " s");
            // A force that starts at or after the end never acts (on for start < t <= end with
            // the linear hold, start <= t < end with the step hold, and t <= duration).
            if (f.start >= sc.duration)
                spdlog::warn(
                    "{}:{}: '{}start' = {} s is not before 'duration' = {} s{}: the "
                    "force never acts (the run ends first)",
                    path.string(), table.get("start")->source().begin.line, prefix,
                    fmt_number(f.start), fmt_number(sc.duration),
                    top.has("duration") ? "" : " (default)");
            f.line = item.source().begin.line;
            if (face >= 0)
                f.face_line = table.get("face")->source().begin.line;
            f.force.face = face;
            f.force.point = point.value_or(core::Vec3{});
            f.force.vector = *vector;
            sc.forces.push_back(f);
        }
    }
    PLIANT_TRY(check_step_count(sc, path));
    return sc;
}

}  // namespace

double frame_time(const Scenario& sc, int frame)
{
    if (frame <= 0)
        return 0.0;
    return frame >= sc.frames ? sc.duration : frame / sc.frame_rate;
}

std::string fmt_number(double v)
{
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%g", v);
    return buf;
}

core::Result<Scenario> parse_scenario(const std::filesystem::path& path)
{
    // Read here, not by toml::parse_file, which could not open a pipe (`-s <(...)`: "File
    // could not be opened for reading"); at most 16 MiB, so that a device such as /dev/zero
    // ends.
    constexpr std::size_t k_max_bytes = std::size_t{16} << 20;
    std::ifstream in(path, std::ios::binary);
    if (!in)
        return core::fail(core::ErrorCode::IoError,
                          path.string() + ": cannot open for reading: " + std::strerror(errno));
    std::string text;
    std::array<char, 65536> buffer{};
    while (in.read(buffer.data(), buffer.size()) || in.gcount() > 0)
    {
        text.append(buffer.data(), static_cast<std::size_t>(in.gcount()));
        if (text.size() > k_max_bytes)
            return core::fail(core::ErrorCode::BadScenario,
                              path.string() +
                                  ": more than 16 MiB: not a scenario (a TOML file of a few "
                                  "lines; see scenes/pull.toml)");
    }
    if (in.bad())
        return core::fail(core::ErrorCode::IoError, path.string() + ": read failed");
    return parse_scenario_text(text, path);
}

core::Result<Scenario> parse_scenario_text(std::string_view text, const std::filesystem::path& path)
{
    try
    {
        return read_scenario(toml::parse(text, path.string()), path);
    }
    catch (const toml::parse_error& e)
    {
        return syntax_error(path, e);
    }
}

std::string key_at(const Scenario& sc, const std::filesystem::path& path, const std::string& key)
{
    const auto it = sc.lines.find(key);
    if (it == sc.lines.end())
        return path.string() + ": '" + key + "'";
    return path.string() + ":" + std::to_string(it->second) + ": '" + key + "'";
}

const char* default_note(const Scenario& sc, const std::string& key)
{
    return sc.lines.count(key) != 0 ? "" : " (default)";
}

core::Result<void> check_mixed_precision(const Scenario& sc, const std::filesystem::path& path,
                                         bool from_command_line)
{
    const sim::MembraneSettings& s = sc.settings;
    if (s.precision != sim::Precision::Mixed)
        return {};
    const std::string why = from_command_line ? "--precision mixed" : "precision = \"mixed\"";
    const auto below =
        [&](const char* key, double value, double least, const char* unit, const char* reason)
    {
        const std::string name = std::string("integrator.") + key;
        return core::Error{core::ErrorCode::BadScenario,
                           key_at(sc, path, name) + " = " + fmt_number(value) + unit +
                               default_note(sc, name) + " is below " + fmt_number(least) + unit +
                               ", the least " + why + " allows (" + reason +
                               "); raise it, or use precision = \"double\""};
    };
    const char* coefficients = "its coefficients, h^2 times the tableau's, are floats";
    if (s.fixed_step && s.fixed_dt < 1e-12)
        return below("fixed_dt", s.fixed_dt, 1e-12, " s", coefficients);
    if (!s.fixed_step && s.dt_min < 1e-12)
        return below("dt_min", s.dt_min, 1e-12, " s", coefficients);
    if (!s.fixed_step && s.atol < 1e-30)
        return below("atol", s.atol, 1e-30, "", "its error norm is a float");
    if (!s.fixed_step && s.rtol < 1e-9)
        spdlog::warn(
            "{} = {}{} with {}: the error estimate comes from float slopes, whose "
            "rounding (~1e-7 of a step's change) the step-size control follows below "
            "rtol ~1e-9: such runs can take 10-1000x the steps of precision \"double\" "
            "for no better result; use \"double\" for tolerances this tight "
            "(docs/physics.md §9)",
            key_at(sc, path, "integrator.rtol"), fmt_number(s.rtol),
            default_note(sc, "integrator.rtol"), why);
    return {};
}

}  // namespace pliant::cli
