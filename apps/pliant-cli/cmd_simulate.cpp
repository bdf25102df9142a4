// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant simulate [GRID] --scenario FILE.toml -o DIR`: runs a membrane scenario headless
// (docs/physics.md). The scenario (TOML) names the material, the integrator, the duration, the
// frame rate and timed forces; the run writes one .pgrid (or a .ply/.obj/.gltf/.glb surface) per
// frame, energy.csv, and run.json (the inputs, every setting in effect, and how the run ended).
// TOML stays in this file: the sim library knows no file formats.
#include <pliant/core/grid_io.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/mesh/io.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <toml++/toml.h>

#include "cli_common.h"
#include "commands.h"
#include "peer_files.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace pliant::cli
{
namespace
{

// The most frames a run writes (frame_NNNNN files; a day at 10 frames per second is 864,000).
constexpr double k_max_frames = 1e6;

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
    double duration = 1.0;     ///< s
    double frame_rate = 25.0;  ///< frames per second
    int frames = 25;           ///< frames after frame 0: floor(duration * frame_rate)
    std::vector<TimedForce> forces;
    std::map<std::string, std::int64_t> lines;  ///< the line of each key the file gives
                                                ///< ("integrator.fixed_dt")
};

struct SimulateOptions
{
    std::filesystem::path grid;
    std::filesystem::path scenario;
    std::filesystem::path out;
    std::string format = "pgrid";
    int level = 6;
    double radius = 1.0;
    std::string sphere_map = "equal-area";
    int threads = -1;       ///< -j; -1: not given (the scenario's `threads`), 0: OpenMP's default
    std::string precision;  ///< --precision; empty: not given (the scenario's `precision`)
    std::filesystem::path resume;  ///< a saved state to start from instead of rest
};

std::string fmt_number(double v)
{
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%g", v);
    return buf;
}

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

    // Reads an optional number into `out`, checking the range [lo, hi].
    [[nodiscard]] std::optional<core::Error> number(const std::string& key, double& out, double lo,
                                                    double hi) const
    {
        const toml::node* node = table_.get(key);
        if (node == nullptr)
            return std::nullopt;
        const std::optional<double> v = node->value<double>();
        if (!node->is_number() || !v)
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
            const std::optional<double> v = (*arr)[k].value<double>();
            if (!(*arr)[k].is_number() || !v || !std::isfinite(*v))
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

core::Result<Scenario> parse_scenario(const std::filesystem::path& path)
{
    toml::table root;
    try
    {
        root = toml::parse_file(path.string());
    }
    catch (const toml::parse_error& e)
    {
        return core::Error{core::ErrorCode::BadScenario,
                           path.string() + ":" + std::to_string(e.source().begin.line) + ":" +
                               std::to_string(e.source().begin.column) + ": " +
                               std::string(e.description())};
    }
    Scenario sc;
    // Scenario forces are functions of time: sampled at frame (and start/end) times and held
    // linearly between them unless the file asks for the zero-order hold.
    sc.settings.force_hold = sim::ForceHold::Linear;
    const Reader top(path, root, "");
    PLIANT_TRY(top.unknown_keys({"duration", "frame_rate", "material", "integrator", "force"}));
    PLIANT_TRY(top.number("duration", sc.duration, 0.0, 1e6));
    PLIANT_TRY(top.number("frame_rate", sc.frame_rate, 1e-3, 1e4));
    top.record_lines(sc.lines);
    // Frame numbers are ints and every frame is a file: refuse runs that would write more than
    // k_max_frames (1e6 s at 1e4 frames per second would be 1e10).
    const double frame_count = std::floor(sc.duration * sc.frame_rate + 1e-9);
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
            if (!(f.end > f.start))
            {
                if (r.has("end"))
                    return scenario_error(
                        path, table.get("end")->source(), prefix + "end",
                        "= " + fmt_number(f.end) +
                            " s must be later than 'start' = " + fmt_number(f.start) + " s");
                return scenario_error(path, table.get("start")->source(), prefix + "start",
                                      "= " + fmt_number(f.start) +
                                          " s is not before 'end', which defaults to the "
                                          "duration " +
                                          fmt_number(sc.duration) + " s");
            }
            f.line = item.source().begin.line;
            if (face >= 0)
                f.face_line = table.get("face")->source().begin.line;
            f.force.face = face;
            f.force.point = point.value_or(core::Vec3{});
            f.force.vector = *vector;
            sc.forces.push_back(f);
        }
    }
    return sc;
}

// Where a point sliding from `a` to `b` is at fraction s: on the arc about `centre` (the rest
// surface's centroid), its direction turned at a constant rate in the plane of the two ends and
// its distance from the centre interpolated linearly. On a sphere about its centre the point stays
// on the surface (a great circle); the chord, which the scenario used before, cuts inside a
// curved surface, and where it passes more than the force's radius below it every node is out of
// reach and the whole force falls on one node. Ends seen from the centre in the same or opposite
// directions (no unique plane) slide along the chord.
core::Vec3 slide_point(const core::Vec3& a, const core::Vec3& b, double s, const core::Vec3& centre)
{
    const core::Vec3 da = a - centre;
    const core::Vec3 db = b - centre;
    const double ra = core::norm(da);
    const double rb = core::norm(db);
    const core::Vec3 chord = a + (b - a) * s;
    if (!(ra > 0.0) || !(rb > 0.0))
        return chord;
    const core::Vec3 ua = da / ra;
    const core::Vec3 ub = db / rb;
    const double angle = std::atan2(core::norm(core::cross(ua, ub)), core::dot(ua, ub));
    if (!(angle > 1e-9) || !(angle < std::numbers::pi - 1e-6))
        return chord;
    const core::Vec3 dir = ua * (std::sin((1.0 - s) * angle) / std::sin(angle)) +
                           ub * (std::sin(s * angle) / std::sin(angle));
    return centre + dir * ((1.0 - s) * ra + s * rb);
}

// The forces active over [t0, t1): those whose interval contains t0 (the caller splits frame
// intervals at every start and end); moving points are taken at the interval's midpoint.
void active_forces(const Scenario& sc, double t0, double t1, const core::Vec3& centre,
                   std::vector<sim::Force>& out)
{
    out.clear();
    const bool linear = sc.settings.force_hold == sim::ForceHold::Linear;
    for (const TimedForce& f : sc.forces)
    {
        // Zero-order hold: what acts at the interval's start, a sliding point at its middle.
        // Linear hold: the value at its end t1 (on for start < t1 <= end), which advance_to
        // reaches linearly from the previous interval's: a force ramps up over the first
        // interval after its start and down over the first after its end.
        const bool on = linear ? (t1 > f.start && t1 <= f.end) : (t0 >= f.start && t0 < f.end);
        if (!on)
            continue;
        sim::Force g = f.force;
        if (f.to)
        {
            const double t = linear ? t1 : 0.5 * (t0 + t1);
            const double s = std::clamp((t - f.start) / (f.end - f.start), 0.0, 1.0);
            g.point = slide_point(f.force.point, *f.to, s, centre);
        }
        out.push_back(g);
    }
}

// The rest surface's centroid (mean of its vertices).
core::Vec3 rest_centroid(const core::TetraGrid& grid, const core::Vec3Field<double>& rest)
{
    core::Vec3 sum{};
    for (const core::NodeIndex n : grid.node_of_unique())
        sum += core::Vec3{rest[0][n], rest[1][n], rest[2][n]};
    return sum / static_cast<double>(grid.unique_count());
}

// Warns about point forces that come farther than their radius from every rest vertex (checked at
// both ends and seven points between): there the whole force falls on the nearest vertex.
void warn_unreachable_points(const Scenario& sc, const core::TetraGrid& grid,
                             const core::Vec3Field<double>& rest, const core::Vec3& centre,
                             const std::filesystem::path& path)
{
    for (std::size_t k = 0; k < sc.forces.size(); ++k)
    {
        const TimedForce& f = sc.forces[k];
        if (f.force.face >= 0)
            continue;
        double worst = 0.0;
        const int samples = f.to ? 9 : 1;
        for (int i = 0; i < samples; ++i)
        {
            const double s = samples > 1 ? static_cast<double>(i) / (samples - 1) : 0.0;
            const core::Vec3 p =
                f.to ? slide_point(f.force.point, *f.to, s, centre) : f.force.point;
            double nearest = std::numeric_limits<double>::infinity();
            for (const core::NodeIndex n : grid.node_of_unique())
            {
                const core::Vec3 d = core::Vec3{rest[0][n], rest[1][n], rest[2][n]} - p;
                nearest = std::min(nearest, core::dot(d, d));
            }
            worst = std::max(worst, std::sqrt(nearest));
        }
        if (worst > f.force.radius)
            spdlog::warn(
                "{}:{}: force[{}]'s point comes {:.3g} m from the nearest vertex, beyond "
                "its radius {:.3g} m: there the whole force falls on that one vertex",
                path.string(), f.line, k, worst, f.force.radius);
    }
}

core::Result<void> write_frame(const SimulateOptions& opt, const sim::MembraneModel& model,
                               const sim::MembraneState& state, int frame)
{
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%05d.%s", frame, opt.format.c_str());
    const std::filesystem::path path = opt.out / name;
    core::Vec3Field<double> p;
    model.positions(state.u, p);
    if (opt.format != "pgrid")
        return mesh::export_mesh(path, mesh::from_grid(model.grid(), p));
    core::GridFile file = core::make_geometry_file(model.grid(), p);
    using Channel = std::pair<const char*, const core::Field<double>*>;
    const std::array<Channel, 2> channels = {Channel{"u", &state.u}, Channel{"v", &state.v}};
    for (const auto& [channel, field] : channels)
    {
        core::Field<double> plain(model.grid(), 0);
        for (int y = 0; y < plain.ny(); ++y)
            for (int x = 0; x < plain.nx(); ++x)
                plain.at(x, y) = field->at(x, y);
        file.fields.push_back({channel, std::move(plain)});
    }
    return core::save_grid(path, file);
}

// "file:line: 'key'" for a key the scenario gives, "file: 'key'" for a default.
std::string key_at(const Scenario& sc, const std::filesystem::path& path, const std::string& key)
{
    const auto it = sc.lines.find(key);
    if (it == sc.lines.end())
        return path.string() + ": '" + key + "'";
    return path.string() + ":" + std::to_string(it->second) + ": '" + key + "'";
}

// " (default)" when the scenario does not give `key`.
const char* default_note(const Scenario& sc, const std::string& key)
{
    return sc.lines.count(key) != 0 ? "" : " (default)";
}

// Warns when the steps the run is bound to take are above the stable step of the model
// (docs/physics.md §5): a fixed step, or an adaptive run's dt_min, which the error control cannot
// go below. Either lets the fastest modes grow at every step.
void warn_unstable_step(const Scenario& sc, const sim::MembraneModel& model,
                        const std::filesystem::path& path)
{
    const sim::MembraneSettings& s = sc.settings;
    const double stable = sim::stable_fixed_step(model);
    if (s.fixed_step && s.fixed_dt > stable)
        spdlog::warn(
            "{} = {:.3g} s{} is {:.3g} times the stable step {:.3g} s of this grid and "
            "material (sim::stable_fixed_step, docs/physics.md §5): the fastest modes "
            "grow at every step and the run will likely diverge; use fixed_dt <= {:.3g}",
            key_at(sc, path, "integrator.fixed_dt"), s.fixed_dt,
            default_note(sc, "integrator.fixed_dt"), s.fixed_dt / stable, stable, stable);
    else if (!s.fixed_step && s.dt_min > stable)
        spdlog::warn(
            "{} = {:.3g} s{} is {:.3g} times the stable step {:.3g} s of this grid and "
            "material (sim::stable_fixed_step, docs/physics.md §5): the error control "
            "cannot shrink a step below dt_min, so the run will likely diverge; use "
            "dt_min <= {:.3g}",
            key_at(sc, path, "integrator.dt_min"), s.dt_min, default_note(sc, "integrator.dt_min"),
            s.dt_min / stable, stable, stable);
}

// Mixed precision (docs/physics.md §9): the values of the step mode in use below the float
// range are refused here, naming the key and its line (the library refuses them too, without
// them); tolerances tight enough for the float rounding of the slopes to steer the step size
// are warned about.
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

/// run.json in the output folder: what was run (the inputs and every setting in effect, the
/// command line's and the scenario's merged) and how it ended. Written before the first step
/// with status "running", and again when the run completes, diverges or is interrupted, each
/// time through a temporary file renamed over it, so the file is always whole.
class RunRecord
{
public:
    RunRecord(const SimulateOptions& opt, const Scenario& sc, const core::TetraGrid& grid)
        : path_(opt.out / "run.json")
    {
        const sim::MembraneSettings& m = sc.settings;
        json_["program"] = "pliant simulate";
        json_["scenario"] = opt.scenario.string();
        json_["grid"] = opt.grid.empty() ? nlohmann::ordered_json(nullptr)
                                         : nlohmann::ordered_json(opt.grid.string());
        if (opt.grid.empty())
            json_["sphere"] = {{"radius", opt.radius}, {"map", opt.sphere_map}};
        json_["level"] = grid.level();
        json_["vertices"] = grid.unique_count();
        json_["resume"] = opt.resume.empty() ? nlohmann::ordered_json(nullptr)
                                             : nlohmann::ordered_json(opt.resume.string());
        json_["format"] = opt.format;
        json_["material"] = {{"T", m.T},
                             {"rho", m.rho},
                             {"beta", m.beta},
                             {"k_f", m.k_f},
                             {"max_force", m.max_force}};
        nlohmann::ordered_json integrator;
        integrator["precision"] = std::string(sim::to_string(m.precision));
        integrator["fixed_step"] = m.fixed_step;
        if (m.fixed_step)
            integrator["fixed_dt"] = m.fixed_dt;
        else
        {
            integrator["rtol"] = m.rtol;
            integrator["atol"] = m.atol;
            integrator["dt_min"] = m.dt_min;
            integrator["dt_max"] = m.dt_max;
            integrator["dt_initial"] = m.dt_initial;
            integrator["safety"] = m.safety;
            integrator["max_growth"] = m.max_growth;
            integrator["min_shrink"] = m.min_shrink;
        }
        integrator["reassemble_every"] = m.reassemble_every;
        integrator["force_hold"] = std::string(sim::to_string(m.force_hold));
        integrator["threads"] = m.threads;
        json_["integrator"] = integrator;
        json_["duration_s"] = sc.duration;
        json_["frame_rate"] = sc.frame_rate;
        json_["frames"] = sc.frames + 1;
        json_["forces"] = sc.forces.size();
        end("running", 0, 0.0, 0.0, {});
    }

    /// Sets the result: the status, the frames written, the simulated and wall seconds, and the
    /// step counts.
    void end(const char* status, int frames_written, double simulated_s, double wall_s,
             const std::array<std::uint64_t, 3>& steps_rejections_at_min)
    {
        json_["result"] = {{"status", status},
                           {"frames_written", frames_written},
                           {"simulated_s", simulated_s},
                           {"wall_s", wall_s},
                           {"steps", steps_rejections_at_min[0]},
                           {"rejections", steps_rejections_at_min[1]},
                           {"steps_at_dt_min", steps_rejections_at_min[2]}};
    }
    void set_reason(const std::string& reason) { json_["result"]["reason"] = reason; }

    [[nodiscard]] core::Result<void> write() const
    {
        const std::filesystem::path tmp = path_.string() + ".tmp";
        {
            std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
            f << json_.dump(2) << '\n';
            if (!f)
                return core::fail(core::ErrorCode::IoError,
                                  "simulate: cannot write " + tmp.string());
        }
        std::error_code ec;
        std::filesystem::rename(tmp, path_, ec);
        if (ec)
            return core::fail(core::ErrorCode::IoError,
                              "simulate: cannot write " + path_.string() + ": " + ec.message());
        return {};
    }

private:
    std::filesystem::path path_;
    nlohmann::ordered_json json_;
};

int run_simulate(const SimulateOptions& opt, const GlobalOptions& global)
{
    auto scenario = parse_scenario(opt.scenario);
    if (!scenario)
        return report(scenario.error());
    Scenario& sc = *scenario;
    if (opt.threads >= 0)
        sc.settings.threads = opt.threads;  // -j 0: OpenMP's default, as threads = 0 in the file
    if (!opt.precision.empty())
        sc.settings.precision = opt.precision == sim::to_string(sim::Precision::Mixed)
                                    ? sim::Precision::Mixed
                                    : sim::Precision::Double;
    if (auto ok = check_mixed_precision(sc, opt.scenario, !opt.precision.empty()); !ok)
        return report(ok.error());

    // Rest geometry: a grid file, or a sphere.
    auto geometry = load_rest_geometry("simulate", opt.grid.string(), opt.level, opt.radius,
                                       opt.sphere_map, opt.resume.string());
    if (!geometry)
        return report(geometry.error());
    const core::TetraGrid& grid = geometry->grid;
    const core::Vec3Field<double>& rest = geometry->positions;
    const core::Vec3 centre = rest_centroid(grid, rest);
    auto model = sim::MembraneModel::create(grid, rest, sc.settings);
    if (!model)
        return report(model.error());
    // Forces against this grid, each error naming its key and line like the parser's.
    const auto faces = static_cast<std::int64_t>(grid.face_count());
    for (std::size_t k = 0; k < sc.forces.size(); ++k)
    {
        const TimedForce& f = sc.forces[k];
        const std::string name = "force[" + std::to_string(k) + "]";
        if (f.force.face >= faces)
            return report({core::ErrorCode::BadScenario,
                           opt.scenario.string() + ":" + std::to_string(f.face_line) + ": '" +
                               name + ".face' = " + std::to_string(f.force.face) +
                               " is not below the grid's " + std::to_string(faces) +
                               " faces (level " + std::to_string(grid.level()) + ")"});
        if (auto ok = sim::validate_forces(*model, std::span<const sim::Force>(&f.force, 1)); !ok)
        {
            // "force 0: what": keep what.
            const std::string& msg = ok.error().message;
            const std::size_t colon = msg.find(": ");
            return report({core::ErrorCode::BadScenario,
                           opt.scenario.string() + ":" + std::to_string(f.line) + ": '" + name +
                               "' " + (colon == std::string::npos ? msg : msg.substr(colon + 2))});
        }
    }

    std::optional<sim::MembraneState> resumed;
    if (!opt.resume.empty())
    {
        auto saved = load_saved_state(opt.resume, *model);
        if (!saved)
            return report(saved.error());
        resumed = std::move(*saved);
    }
    warn_unreachable_points(sc, grid, rest, centre, opt.scenario);
    warn_unstable_step(sc, *model, opt.scenario);

    std::error_code ec;
    std::filesystem::create_directories(opt.out, ec);
    if (ec)
        return report({core::ErrorCode::IoError,
                       "simulate: cannot create " + opt.out.string() + ": " + ec.message()});
    std::ofstream csv(opt.out / "energy.csv");
    if (!csv)
        return report({core::ErrorCode::IoError,
                       "simulate: cannot write " + (opt.out / "energy.csv").string()});
    csv << "frame,time,kinetic,strain,foundation,total,steps,rejections,flags\n";
    csv.precision(17);
    RunRecord record(opt, sc, grid);
    if (auto ok = record.write(); !ok)
        return report(ok.error());

    sim::MembraneState state = resumed ? std::move(*resumed) : sim::MembraneState::at_rest(grid);
    sim::Rkf45Workspace ws(*model, sc.settings.threads);
    const int frames = sc.frames;
    const bool fixed = sc.settings.fixed_step;
    const double h = sc.settings.fixed_dt;
    ProgressBar bar(global);
    // Ctrl-C or SIGTERM: stop before the next step, keeping every frame written (the frame
    // being computed is dropped; at high levels with small steps a frame can take seconds).
    const volatile std::sig_atomic_t* interrupted = install_interrupt_flag();
    bar.stop_on(interrupted);
    std::vector<sim::Force> forces;
    std::uint64_t total_steps = 0;
    std::uint64_t total_rejections = 0;
    std::uint64_t total_at_min = 0;
    const auto start = std::chrono::steady_clock::now();
    const auto seconds_since_start = [&]
    { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
    // A diverged run stops with the frames written so far (energy.csv keeps their rows).
    const auto diverged = [&](const std::string& what, int frame)
    {
        record.end("diverged", frame + 1, state.time, seconds_since_start(),
                   {total_steps, total_rejections, total_at_min});
        record.set_reason(what);
        if (auto ok = record.write(); !ok)
            spdlog::warn("{}", ok.error().message);
        spdlog::error(
            "{}: {} at t = {} s: the run diverged and stops (frames 0 to {} are in {}); "
            "lower {} or the forces",
            opt.scenario.string(), what, fmt_number(state.time), frame, opt.out.string(),
            fixed ? "fixed_dt" : "dt_min and dt_max");
        return k_exit_failure;
    };
    // Stopped by Ctrl-C with frames 0 to `last` written (the last at t_written).
    double t_written = state.time;
    const auto stopped = [&](int last)
    {
        record.end("interrupted", last + 1, t_written, seconds_since_start(),
                   {total_steps, total_rejections, total_at_min});
        if (auto ok = record.write(); !ok)
            spdlog::warn("{}", ok.error().message);
        spdlog::error("{}: interrupted at t = {} s; frames 0 to {} of 0 to {} are in {}",
                      opt.scenario.string(), fmt_number(t_written), last, frames, opt.out.string());
        return k_exit_interrupted;
    };
    for (int frame = 0; frame <= frames; ++frame)
    {
        const double t_frame = frame / sc.frame_rate;
        sim::AdvanceReport rep;
        // Advances to t_next with the forces of [state.time, t_next), adding to the frame's
        // report.
        const auto advance = [&](double t_next)
        {
            active_forces(sc, state.time, t_next, centre, forces);
            const sim::AdvanceReport r =
                sim::advance_to(*model, state, ws, t_next, forces, {}, 10'000'000, &bar);
            rep.status = rep.status | r.status;
            rep.steps += r.steps;
            rep.rejections += r.rejections;
            rep.at_min_steps += r.at_min_steps;
            return r;
        };
        if (fixed)
        {
            // Whole steps only: the frame is written at the last step boundary at or before its
            // time and the remainder waits for the next frame (docs/physics.md §7). A force's
            // start or end inside the frame splits it at the first boundary at or after it (at
            // it, when it lies on one).
            for (;;)
            {
                const double t = state.time;
                const double slack = 1e-12 * std::max(1.0, std::fabs(t_frame));
                double n = std::floor((t_frame - t + slack) / h);
                if (!(n >= 1.0))
                    break;
                double t_next = t_frame;
                for (const TimedForce& f : sc.forces)
                    for (const double e : {f.start, f.end})
                        if (e > t + slack)
                            if (const double n_e = std::max(1.0, std::ceil((e - t - slack) / h));
                                n_e < n)
                            {
                                n = n_e;
                                t_next = e;
                            }
                if (const double boundary = t + n * h; std::fabs(boundary - t_next) > slack)
                    t_next = boundary;
                const sim::AdvanceReport r = advance(t_next);
                if (sim::has_flag(r.status, sim::StepStatus::NonFinite))
                    return diverged("the state became non-finite", frame - 1);
                if (r.stopped)
                    return stopped(frame - 1);
                if (r.steps == 0)
                    break;  // no whole step fitted after all (rounding): the next frame takes it
            }
        }
        else
        {
            // Split the interval at force start/end times so each piece has one force set.
            while (state.time < t_frame - 1e-12 * std::max(1.0, t_frame))
            {
                double t_next = t_frame;
                for (const TimedForce& f : sc.forces)
                    for (const double e : {f.start, f.end})
                        if (e > state.time + 1e-12 && e < t_next)
                            t_next = e;
                const sim::AdvanceReport r = advance(t_next);
                if (sim::has_flag(r.status, sim::StepStatus::NonFinite))
                    return diverged("the state became non-finite", frame - 1);
                if (r.stopped)
                    return stopped(frame - 1);
                if (!r.reached)
                    break;  // max_steps: the remainder waits for the next frame
            }
        }
        total_steps += rep.steps;
        total_rejections += rep.rejections;
        total_at_min += rep.at_min_steps;
        if (auto ok = write_frame(opt, *model, state, frame); !ok)
            return report(ok.error());
        const sim::Energy e = sim::energy(*model, state);
        csv << frame << ',' << state.time << ',' << e.kinetic << ',' << e.strain << ','
            << e.foundation << ',' << e.total() << ',' << rep.steps << ',' << rep.rejections << ','
            << static_cast<std::uint32_t>(rep.status) << '\n';
        if (!std::isfinite(e.total()))
            return diverged("the energy became non-finite", frame);
        bar.update("simulate", frames > 0 ? static_cast<double>(frame) / frames : 1.0);
        t_written = state.time;
        if (*interrupted != 0 && frame < frames)
            return stopped(frame);
    }
    const double wall = seconds_since_start();
    record.end("complete", frames + 1, state.time, wall,
               {total_steps, total_rejections, total_at_min});
    if (auto ok = record.write(); !ok)
        return report(ok.error());
    std::printf(
        "%d frames, %.3f s simulated in %.3f s wall (%.2fx real time), level %d, %zu "
        "vertices, %llu steps, %llu rejections, %d thread(s), %s precision -> %s\n",
        frames + 1, state.time, wall, wall > 0.0 ? state.time / wall : 0.0, grid.level(),
        grid.unique_count(), static_cast<unsigned long long>(total_steps),
        static_cast<unsigned long long>(total_rejections), ws.max_threads,
        std::string(sim::to_string(sc.settings.precision)).c_str(), opt.out.string().c_str());
    if (total_at_min > 0)
        spdlog::warn(
            "{} = {:.3g} s{}: {} of {} steps were taken at dt_min with the error above "
            "the tolerance (flag 2 in energy.csv): the results may be inaccurate, or "
            "diverging; {}",
            key_at(sc, opt.scenario, "integrator.dt_min"), sc.settings.dt_min,
            default_note(sc, "integrator.dt_min"), total_at_min, total_steps,
            sc.settings.precision == sim::Precision::Mixed
                ? "with precision \"mixed\" a tight rtol makes the float rounding of the "
                  "slopes look like error (docs/physics.md §9): use precision \"double\", or "
                  "lower dt_min (down to 1e-12 s)"
                : "lower dt_min");
    return 0;
}

void add_simulate_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<SimulateOptions>();
    CLI::App* cmd = app.add_subcommand(
        "simulate",
        "Simulate a grid as a membrane under tension (linear FEM, RKF45) following a scenario "
        "file, headless.");
    cmd->footer(
        "The scenario (TOML) sets the material (T N/m, rho kg/m^2, beta 1/s, k_f 1/s^2), the\n"
        "integrator (adaptive: rtol, atol, dt_min, dt_max, dt_initial [s], safety, max_growth,\n"
        "min_shrink; or fixed_step = true with fixed_dt [s]; reassemble_every, threads,\n"
        "force_hold, precision = \"double\" or \"mixed\"), duration [s], frame_rate [1/s] and\n"
        "timed forces ([[force]]: start, end (default: the duration), face, or point + radius\n"
        "[m] with an optional 'to' for a point sliding over the surface, vector [N]); see\n"
        "scenes/pull.toml and docs/physics.md.\n"
        "Errors name the key and its line. Forces are sampled at frame times and ramp linearly\n"
        "between samples (force_hold = \"linear\", the default: a force acts for\n"
        "start < t <= end, ramping up over the frame after its start and down over the frame\n"
        "after its end); force_hold = \"step\" holds each sample for the whole frame (a force\n"
        "acts for start <= t < end). Fixed steps are whole: a frame is written at the last step\n"
        "at or before its time. A fixed_dt (or dt_min) above the grid's stable step is warned\n"
        "about; a run whose state becomes non-finite stops with exit status 3.\n\n"
        "DIR receives frame_NNNNN.pgrid per frame (channels px py pz = deformed positions\n"
        "P + u N, u [m], v [m/s]; or surfaces with --format ply, obj, gltf or glb) and\n"
        "energy.csv (frame, time, kinetic, strain, foundation, total energy [J], steps,\n"
        "rejections, flags), and run.json: the inputs, every setting in effect (the command\n"
        "line's and the scenario's), and the result (status running, complete, diverged or\n"
        "interrupted, frames written, simulated and wall seconds, steps). Ctrl-C stops before\n"
        "the next step, keeps the frames written and exits with status 130.\n\n"
        "Examples:\n"
        "  pliant simulate --scenario scenes/pull.toml -o out/pull            # sphere, level 6\n"
        "  pliant simulate spot.pgrid --scenario scenes/spot.toml -o out/spot --format ply\n"
        "  pliant simulate spot.pgrid --scenario scenes/spot.toml -o out/more \\\n"
        "      --resume out/spot/frame_00060.pgrid        # go on from a frame (time starts at 0)");
    cmd->add_option("GRID", opt->grid,
                    "Rest geometry (.pgrid from `pliant remesh`); omitted: a sphere of --level");
    cmd->add_option("-s,--scenario", opt->scenario, "Scenario file (.toml)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("-o,--output", opt->out, "Output folder (created if missing)")->required();
    cmd->add_option("--format", opt->format, "Frame format: pgrid, ply, obj, gltf or glb")
        ->check(CLI::IsMember({"pgrid", "ply", "obj", "gltf", "glb"}))
        ->capture_default_str();
    cmd->add_option("-l,--level", opt->level, "Sphere level when GRID is omitted")
        ->check(CLI::Range(1, 10))
        ->capture_default_str();
    cmd->add_option("--radius", opt->radius, "Sphere radius [m] when GRID is omitted")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--sphere-map", opt->sphere_map,
                    "How the sphere's grid lies on it when GRID is omitted: equal-area (even "
                    "cells, twice the stable step) or gnomonic (the paper's central projection)")
        ->check(CLI::IsMember({"equal-area", "gnomonic"}))
        ->capture_default_str();
    cmd->add_option("--resume", opt->resume,
                    "Start from a saved state of GRID (a frame of an earlier run, a --save of "
                    "`host`/`join`, demo's final.pgrid, `replay -o`) instead of at rest; the "
                    "scenario's time starts at 0")
        ->check(CLI::ExistingFile);
    cmd->add_option("-j,--threads", opt->threads,
                    "Threads (overrides the scenario's; 0: OpenMP's default; results are "
                    "identical for any count)")
        ->check(CLI::Range(0, 1024));
    cmd->add_option("--precision", opt->precision,
                    "Arithmetic of the steps (overrides the scenario's): double, or mixed (float "
                    "increments over the double state, ~1.6x faster on big grids; "
                    "docs/physics.md §9)")
        ->check(CLI::IsMember({"double", "mixed"}));
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_simulate(*opt, global); }));
}

const CommandRegistrar k_register_simulate{{"simulate", 40, &add_simulate_command}};

}  // namespace
}  // namespace pliant::cli
