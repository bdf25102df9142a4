// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant simulate [GRID] --scenario FILE.toml -o DIR`: runs a membrane scenario headless
// (docs/physics.md). The scenario (TOML) names the material, the integrator, the duration, the
// frame rate and timed forces; the run writes one .pgrid (or a .ply/.obj/.gltf/.glb surface) per
// frame, energy.csv, and run.json (the inputs, every setting in effect, and how the run ended).
// The scenario reader is scenario.cpp (TOML): the sim library knows no file formats.
#include <pliant/core/file_io.h>
#include <pliant/core/grid_io.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/mesh/io.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <fcntl.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <unistd.h>

#include "cli_common.h"
#include "commands.h"
#include "peer_files.h"
#include "scenario.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <numbers>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pliant::cli
{
namespace
{

/// The most steps one sim::advance_to call takes; a frame that needs more goes on with further
/// calls (the call is a unit of work, not a limit of the frame).
constexpr std::uint64_t k_steps_per_call = 1'000'000;

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

// Whether `name` is a frame's file as a run names them: frame_ and at least five digits, then
// .pgrid, .ply, .obj, .gltf (with its buffer .bin) or .glb.
bool is_frame_file(const std::string& name)
{
    constexpr std::string_view prefix = "frame_";
    if (name.rfind(prefix, 0) != 0)
        return false;
    std::size_t i = prefix.size();
    while (i < name.size() && name[i] >= '0' && name[i] <= '9')
        ++i;
    if (i - prefix.size() < 5 || i == name.size() || name[i] != '.')
        return false;
    const std::string ext = name.substr(i + 1);
    return ext == "pgrid" || ext == "ply" || ext == "obj" || ext == "gltf" || ext == "glb" ||
           ext == "bin";
}

// The frames an earlier run left in `dir`: its regular files that is_frame_file names (never a
// folder, a link or any other file). None when `dir` does not exist.
std::vector<std::filesystem::path> earlier_frames(const std::filesystem::path& dir)
{
    std::vector<std::filesystem::path> found;
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
        return found;
    for (auto it = std::filesystem::directory_iterator(dir, ec);
         !ec && it != std::filesystem::directory_iterator(); it.increment(ec))
        if (it->is_regular_file(ec) && !it->is_symlink(ec) &&
            is_frame_file(it->path().filename().string()))
            found.push_back(it->path());
    std::sort(found.begin(), found.end());
    return found;
}

std::filesystem::path frame_path(const SimulateOptions& opt, int frame)
{
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%05d.%s", frame, opt.format.c_str());
    return opt.out / name;
}

// After frame 0: warns when the frames to come, at frame 0's size, need more than the free
// space where they go (a run of a million level-10 frames, 80 TB, started without a word; it
// stops with an error naming the frame when the disk fills, keeping the frames before).
void warn_if_frames_outgrow_the_disk(const SimulateOptions& opt, int frames)
{
    std::error_code ec;
    const auto one = std::filesystem::file_size(frame_path(opt, 0), ec);
    if (ec)
        return;
    const std::filesystem::space_info space = std::filesystem::space(opt.out, ec);
    if (ec)
        return;
    const double need = static_cast<double>(one) * static_cast<double>(frames);
    if (need <= static_cast<double>(space.available))
        return;
    const auto gb = [](double bytes)
    {
        const char* units[] = {"bytes", "kB", "MB", "GB", "TB", "PB"};
        std::size_t u = 0;
        for (; u + 1 < std::size(units) && bytes >= 1000.0; ++u)
            bytes /= 1000.0;
        char text[32];
        std::snprintf(text, sizeof(text), "%.3g %s", bytes, units[u]);
        return std::string(text);
    };
    spdlog::warn(
        "{}: the {} frames to come need about {} ({} each, as frame 0), but {} is free "
        "there: the run will stop when the disk is full, keeping the frames written; "
        "lower 'frame_rate' or the level, or write elsewhere",
        opt.out.string(), frames, gb(need), gb(static_cast<double>(one)),
        gb(static_cast<double>(space.available)));
}

// The bar while a frame is computed: advance_to polls stop_requested() before every step,
// which here also moves the bar by the simulated time within the frame (at most 10 times a
// second), so that a frame of many steps (a small step at a high level) shows progress.
class InFrameProgress final : public core::ProgressSink
{
public:
    InFrameProgress(ProgressBar& bar, const sim::MembraneState& state, double t_start, double t_end,
                    int frame, int frames)
        : bar_(bar), state_(state), t_start_(t_start), t_end_(t_end), frame_(frame), frames_(frames)
    {
    }
    void update(std::string_view phase, double fraction) noexcept override
    {
        bar_.update(phase, fraction);
    }
    [[nodiscard]] bool stop_requested() const noexcept override
    {
        const auto now = std::chrono::steady_clock::now();
        if (frames_ > 0 && t_end_ > t_start_ && now - last_ >= std::chrono::milliseconds(100))
        {
            last_ = now;
            const double within =
                std::clamp((state_.time - t_start_) / (t_end_ - t_start_), 0.0, 1.0);
            bar_.update("simulate", (frame_ - 1 + within) / frames_);
        }
        return bar_.stop_requested();
    }

private:
    ProgressBar& bar_;
    const sim::MembraneState& state_;
    double t_start_;
    double t_end_;
    int frame_;
    int frames_;
    mutable std::chrono::steady_clock::time_point last_{};
};

core::Result<void> write_frame(const SimulateOptions& opt, const sim::MembraneModel& model,
                               const sim::MembraneState& state, int frame)
{
    const std::filesystem::path path = frame_path(opt, frame);
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
            "material (docs/physics.md §5): the fastest modes "
            "grow at every step and the run will likely diverge; use fixed_dt <= {:.3g}",
            key_at(sc, path, "integrator.fixed_dt"), s.fixed_dt,
            default_note(sc, "integrator.fixed_dt"), s.fixed_dt / stable, stable, stable);
    else if (!s.fixed_step && s.dt_min > stable)
        spdlog::warn(
            "{} = {:.3g} s{} is {:.3g} times the stable step {:.3g} s of this grid and "
            "material (docs/physics.md §5): the error control "
            "cannot shrink a step below dt_min, so the run will likely diverge; use "
            "dt_min <= {:.3g}",
            key_at(sc, path, "integrator.dt_min"), s.dt_min, default_note(sc, "integrator.dt_min"),
            s.dt_min / stable, stable, stable);
}

/// An advisory lock (flock) on a folder, held while the object lives.
class FolderLock
{
public:
    explicit FolderLock(const std::filesystem::path& folder)
        : fd_(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC))
    {
        if (fd_ >= 0 && ::flock(fd_, LOCK_EX | LOCK_NB) != 0)
        {
            elsewhere_ = errno == EWOULDBLOCK;
            ::close(fd_);
            fd_ = -1;
        }
    }
    FolderLock(const FolderLock&) = delete;
    FolderLock& operator=(const FolderLock&) = delete;
    ~FolderLock()
    {
        if (fd_ >= 0)
            ::close(fd_);
    }
    /// Whether another process holds it (a folder that cannot be opened or locked for another
    /// reason is not refused here: its writes say what is wrong).
    [[nodiscard]] bool held_elsewhere() const noexcept { return elsewhere_; }

private:
    int fd_ = -1;
    bool elsewhere_ = false;
};

/// run.json in the output folder: what was run (the inputs and every setting in effect, the
/// command line's and the scenario's merged) and how it ended. Written before the first step
/// with status "running", and again when the run completes, diverges, fails (an output that
/// cannot be written) or is interrupted, each time whole (core::write_text_file: a new file
/// renamed over it, none left behind when that fails).
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
        // A path that is not UTF-8 (a Latin-1 name) is written with U+FFFD for its bad
        // bytes: dump() would throw, and the process end.
        return core::write_text_file(
            path_,
            json_.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + '\n',
            "simulate");
    }

private:
    std::filesystem::path path_;
    nlohmann::ordered_json json_;
};

int run_simulate(const SimulateOptions& opt, const GlobalOptions& global)
{
    if (opt.out.empty())
    {
        spdlog::error("simulate: -o is empty; give the folder for the frames");
        return k_exit_usage;
    }
    // The run clears -o of an earlier run's frames (below): an input among them would go too.
    const std::vector<std::filesystem::path> stale = earlier_frames(opt.out);
    using Input = std::pair<const std::filesystem::path*, const char*>;
    for (const auto& [input, what] : std::array<Input, 3>{
             {{&opt.resume, "--resume"}, {&opt.grid, "GRID"}, {&opt.scenario, "--scenario"}}})
    {
        std::error_code ec;
        for (const std::filesystem::path& f : stale)
            if (!input->empty() && std::filesystem::equivalent(*input, f, ec))
            {
                spdlog::error(
                    "simulate: {} {} is a frame of an earlier run in -o's folder {}, which this "
                    "run clears of such frames before it writes its own; copy the file out of "
                    "{} first, or give another -o",
                    what, input->string(), opt.out.string(), opt.out.string());
                return k_exit_usage;
            }
    }

    auto scenario = parse_scenario(opt.scenario);
    if (!scenario)
        return report(scenario.error());
    Scenario& sc = *scenario;
    if (opt.threads >= 0)
        sc.settings.threads = opt.threads;  // -j 0: OpenMP's default, as threads = 0 in the file
    warn_if_more_threads_than_cores(sc.settings.threads,
                                    opt.threads >= 0
                                        ? std::string("-j")
                                        : key_at(sc, opt.scenario, "integrator.threads") + " =");
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
        return report(in_grid_file(opt.grid.string(), model.error()));
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
    // One run per folder: a second run into it would clear the first's frames and splice its
    // own among them, energy.csv and run.json too, both ending "complete". An advisory lock
    // on the folder, held until this process ends (released by the system if it is killed).
    const FolderLock lock(opt.out);
    if (lock.held_elsewhere())
        return report({core::ErrorCode::IoError,
                       "simulate: another run is writing to " + opt.out.string() +
                           " (a pliant simulate started before this one); wait for it to end, "
                           "or give another -o"});
    // The folder holds one run: an earlier run's frames go (those this run writes and those
    // beyond its last, which were left beside its frames and counted by nobody), and nothing
    // else does (a file or folder that does not match frame_NNNNN.EXT stays).
    if (!stale.empty())
    {
        std::size_t removed = 0;
        for (const std::filesystem::path& f : stale)
        {
            if (!std::filesystem::remove(f, ec) && ec)
                return report({core::ErrorCode::IoError,
                               "simulate: cannot remove " + f.string() +
                                   " (a frame of an earlier run): " + ec.message()});
            removed += f.extension() != ".bin" ? 1 : 0;  // a .gltf's buffer is part of its frame
        }
        spdlog::info("simulate: removed {} frame{} of an earlier run from {}", removed,
                     removed == 1 ? "" : "s", opt.out.string());
    }
    RunRecord record(opt, sc, grid);
    if (auto ok = record.write(); !ok)
        return report(ok.error());
    // energy.csv grows a row per frame (an interrupted or diverged run keeps the rows of its
    // frames), each flushed and checked: a write that fails (a full disk) stops the run.
    const std::filesystem::path csv_path = opt.out / "energy.csv";
    std::ofstream csv(csv_path, std::ios::binary | std::ios::trunc);
    const auto csv_error = [&](int err)
    {
        return core::Error{core::ErrorCode::IoError,
                           "simulate: " + csv_path.string() + ": write failed" +
                               (err != 0 ? ": " + std::string(std::strerror(err)) : "")};
    };
    // Flushes the rows written so far: nothing, or the errno of the failure (0 when unknown).
    const auto csv_flush = [&]() -> std::optional<int>
    {
        errno = 0;
        csv.flush();
        if (csv)
            return std::nullopt;
        return errno;
    };
    // Before the first frame: run.json says "failed" and why, with nothing written.
    const auto failed_to_start = [&](const core::Error& error)
    {
        record.end("failed", 0, 0.0, 0.0, {});
        record.set_reason(error.message);
        if (auto ok = record.write(); !ok)
            spdlog::warn("{}", ok.error().message);
        return report(error);
    };
    if (!csv)
        return failed_to_start(
            {core::ErrorCode::IoError,
             "simulate: cannot write " + csv_path.string() + ": " + std::strerror(errno)});
    csv << "frame,time,kinetic,strain,foundation,total,steps,rejections,flags\n";
    csv.precision(17);
    if (const std::optional<int> err = csv_flush())
        return failed_to_start(csv_error(*err));

    std::uint64_t total_steps = 0;
    std::uint64_t total_rejections = 0;
    std::uint64_t total_at_min = 0;
    const auto start = std::chrono::steady_clock::now();
    const auto seconds_since_start = [&]
    { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
    // The frames written (0 to last_written) and the time of the last, for run.json when the
    // run ends early.
    int last_written = -1;
    double t_written = resumed ? resumed->time : 0.0;
    bool completed = false;  // run.json says "complete"
    // Running out of memory (the workspace, a frame's bytes) ends the run: run.json says
    // "failed" with the frames written, not "running", before command_callback reports it.
    try
    {
        sim::MembraneState state =
            resumed ? std::move(*resumed) : sim::MembraneState::at_rest(grid);
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
        const auto stopped = [&](int last)
        {
            record.end("interrupted", last + 1, t_written, seconds_since_start(),
                       {total_steps, total_rejections, total_at_min});
            if (auto ok = record.write(); !ok)
                spdlog::warn("{}", ok.error().message);
            if (last < 0)
                spdlog::error(
                    "{}: interrupted at t = {} s, before frame 0 was written; {} holds no "
                    "frame of this run",
                    opt.scenario.string(), fmt_number(t_written), opt.out.string());
            else
                spdlog::error("{}: interrupted at t = {} s; frames 0 to {} of 0 to {} are in {}",
                              opt.scenario.string(), fmt_number(t_written), last, frames,
                              opt.out.string());
            return k_exit_interrupted;
        };
        // An output that cannot be written (a frame, energy.csv) with frames 0 to `last` written:
        // run.json says "failed" and why before the error is reported.
        const auto failed = [&](const core::Error& error, int last)
        {
            record.end("failed", last + 1, t_written, seconds_since_start(),
                       {total_steps, total_rejections, total_at_min});
            record.set_reason(error.message);
            if (auto ok = record.write(); !ok)
                spdlog::warn("{}", ok.error().message);
            return report(error);
        };
        for (int frame = 0; frame <= frames; ++frame)
        {
            // The last frame at the duration, after a shorter interval when the duration is not a
            // whole number of frame intervals.
            const double t_frame = frame_time(sc, frame);
            sim::AdvanceReport rep;
            // Advances to t_next with the forces of [state.time, t_next), adding to the frame's
            // report.
            const InFrameProgress in_frame(bar, state, state.time, t_frame, frame, frames);
            const auto advance = [&](double t_next)
            {
                active_forces(sc, state.time, t_next, centre, forces);
                const sim::AdvanceReport r = sim::advance_to(*model, state, ws, t_next, forces, {},
                                                             k_steps_per_call, &in_frame);
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
                // start or end inside the frame splits it at the last boundary at or before it
                // (at it, when it lies on one), so that the step containing it is a piece of its
                // own: the linear hold ramps the force over that step only (split at the first
                // boundary after it, the ramp began at the piece's start, up to a frame before
                // the force's start).
                for (;;)
                {
                    const double t = state.time;
                    // Rounding slack: of the times, but below a step (a step of 1e-15 s with an
                    // absolute 1e-12 s took a thousand steps into frame 0, the rest state).
                    const double slack =
                        std::min(1e-12 * std::max(1.0, std::fabs(t_frame)), 1e-3 * h);
                    double n = std::floor((t_frame - t + slack) / h);
                    if (!(n >= 1.0))
                        break;
                    double t_next = t_frame;
                    for (const TimedForce& f : sc.forces)
                        for (const double e : {f.start, f.end})
                            if (e > t + slack)
                                if (const double n_e =
                                        std::max(1.0, std::floor((e - t + slack) / h));
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
                    // No whole step fitted after all (rounding): the next frame takes it.
                    if (r.steps == 0)
                        break;
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
                    const double before = state.time;
                    const sim::AdvanceReport r = advance(t_next);
                    if (sim::has_flag(r.status, sim::StepStatus::NonFinite))
                        return diverged("the state became non-finite", frame - 1);
                    if (r.stopped)
                        return stopped(frame - 1);
                    // A call ends after k_steps_per_call steps; the frame goes on with the next
                    // (it was written there, early, and the run still said "complete"). Steps
                    // that no longer move the clock (dt_min below its resolution) end the run.
                    if (!r.reached && !(state.time > before))
                        return failed({core::ErrorCode::InvalidArgument,
                                       opt.scenario.string() +
                                           ": the steps no longer advance "
                                           "the time at t = " +
                                           fmt_number(state.time) +
                                           " s (dt_min is below its resolution); raise dt_min"},
                                      frame - 1);
                }
            }
            if (auto ok = write_frame(opt, *model, state, frame); !ok)
                return failed(ok.error(), frame - 1);
            last_written = frame;
            t_written = state.time;
            if (frame == 0)
                warn_if_frames_outgrow_the_disk(opt, frames);
            total_steps += rep.steps;
            total_rejections += rep.rejections;
            total_at_min += rep.at_min_steps;
            const sim::Energy e = sim::energy(*model, state);
            csv << frame << ',' << state.time << ',' << e.kinetic << ',' << e.strain << ','
                << e.foundation << ',' << e.total() << ',' << rep.steps << ',' << rep.rejections
                << ',' << static_cast<std::uint32_t>(rep.status) << '\n';
            if (const std::optional<int> err = csv_flush())
                return failed(csv_error(*err), frame);
            if (!std::isfinite(e.total()))
                return diverged("the energy became non-finite", frame);
            bar.update("simulate", frames > 0 ? static_cast<double>(frame) / frames : 1.0);
            if (*interrupted != 0 && frame < frames)
                return stopped(frame);
        }
        csv.close();
        if (!csv)
            return failed(csv_error(0), frames);
        const double wall = seconds_since_start();
        record.end("complete", frames + 1, state.time, wall,
                   {total_steps, total_rejections, total_at_min});
        if (auto ok = record.write(); !ok)
            return report(ok.error());
        completed = true;
        if (!global.quiet)  // -q: errors only
            std::printf(
                "%d frames, %.3f s simulated in %.3f s wall (%.2fx real time), level %d, %zu "
                "vertices, %llu steps, %llu rejections, %d thread(s), %s precision -> %s\n",
                frames + 1, state.time, wall, wall > 0.0 ? state.time / wall : 0.0, grid.level(),
                grid.unique_count(), static_cast<unsigned long long>(total_steps),
                static_cast<unsigned long long>(total_rejections), ws.max_threads,
                std::string(sim::to_string(sc.settings.precision)).c_str(),
                opt.out.string().c_str());
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
    catch (const std::bad_alloc&)
    {
        if (completed)  // run.json already says "complete", rightly
            throw;
        try
        {
            record.end("failed", last_written + 1, t_written, seconds_since_start(),
                       {total_steps, total_rejections, total_at_min});
            record.set_reason("out of memory");
            (void)record.write();  // memory is short: it may fail too
        }
        catch (const std::bad_alloc&)
        {
        }
        throw;  // command_callback says "out of memory", exit 3
    }
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
        "force_hold, precision = \"double\" or \"mixed\"), duration [s] (default 1),\n"
        "frame_rate [1/s] (default 25) and timed forces ([[force]]: start, end (default: the\n"
        "duration), face, or point + radius [m] with an optional 'to' for a point sliding over\n"
        "the surface, vector [N]); see scenes/pull.toml and docs/physics.md. A file that sets\n"
        "no key is warned about. The run simulates the whole duration: when it is not a whole\n"
        "number of frame intervals, the last frame comes after a shorter one, at the duration.\n"
        "Errors name the key and its line; a force that starts at or after the duration is\n"
        "warned about (it never acts). Forces are sampled at frame times and ramp linearly\n"
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
        "line's and the scenario's), and the result (status running, complete, diverged,\n"
        "failed (an output could not be written; exit status 1, the reason in run.json) or\n"
        "interrupted, frames written, simulated and wall seconds, steps). DIR holds one run:\n"
        "the frames of an earlier run there (frame_NNNNN.pgrid, .ply, .obj, .gltf, .bin, .glb)\n"
        "are removed before the first step (an info line says how many), and nothing else;\n"
        "a --resume frame among them is refused (exit status 2). Ctrl-C stops before the\n"
        "next step, keeps the frames written and exits with status 130.\n\n"
        "Examples:\n"
        "  pliant simulate --scenario scenes/pull.toml -o out/pull            # sphere, level 6\n"
        "  pliant remesh data/spot.obj --level 6 -o spot.pgrid\n"
        "  pliant simulate spot.pgrid --scenario scenes/spot.toml -o out/spot\n"
        "  pliant simulate spot.pgrid --scenario scenes/spot.toml -o out/more \\\n"
        "      --resume out/spot/frame_00060.pgrid        # go on from a frame (time starts at 0)\n"
        "  pliant simulate spot.pgrid --scenario scenes/spot.toml -o out/spot-ply --format ply\n"
        "      # frames as meshes, for other tools (only .pgrid frames can be resumed)");
    cmd->add_option("GRID", opt->grid,
                    "Rest geometry (.pgrid from `pliant remesh`); omitted: a sphere of --level");
    cmd->add_option("-s,--scenario", opt->scenario, "Scenario file (.toml)")
        ->required()
        ->check(existing_input_file("--scenario"));
    cmd->add_option("-o,--output", opt->out,
                    "Output folder (created if missing; an earlier run's frames in it are removed)")
        ->required();
    cmd->add_option("--format", opt->format, "Frame format: pgrid, ply, obj, gltf or glb")
        ->check(CLI::IsMember({"pgrid", "ply", "obj", "gltf", "glb"}))
        ->capture_default_str();
    CLI::Option* level =
        cmd->add_option("-l,--level", opt->level, "Sphere level when GRID is omitted")
            ->check(whole_number_in(1, 10))
            ->capture_default_str();
    // Bounded so that the sphere's areas, masses and forces stay finite in double precision
    // (1e308 gave "the rest surface has no normal at node (1, 1)", not naming --radius).
    CLI::Option* radius =
        cmd->add_option("--radius", opt->radius, "Sphere radius [m] when GRID is omitted")
            ->check(number_in(1e-6, 1e6))
            ->capture_default_str();
    CLI::Option* sphere_map =
        cmd->add_option("--sphere-map", opt->sphere_map,
                        "How the sphere's grid lies on it when GRID is omitted: equal-area (even "
                        "cells, about twice the stable step) or gnomonic (the paper's central "
                        "projection)")
            ->check(CLI::IsMember({"equal-area", "gnomonic"}))
            ->capture_default_str();
    cmd->add_option("--resume", opt->resume,
                    "Start from a saved state of GRID (a frame of an earlier run, a --save of "
                    "`host`/`join`, demo's final.pgrid, `replay -o`) instead of at rest; the "
                    "scenario's time starts at 0")
        ->check(existing_input_file("--resume"));
    cmd->add_option("-j,--threads", opt->threads,
                    "Threads (overrides the scenario's; 0: OpenMP's default; results are "
                    "identical for any count)")
        ->check(whole_number_in(0, 1024));
    cmd->add_option("--precision", opt->precision,
                    "Arithmetic of the steps (overrides the scenario's): double, or mixed (float "
                    "increments over the double state, ~1.6x faster on big grids; "
                    "docs/physics.md §9)")
        ->check(CLI::IsMember({"double", "mixed"}));
    cmd->callback(command_callback(
        global,
        [opt, &global, level, radius, sphere_map]() -> int
        {
            // The sphere's options with a GRID: said, not silently ignored.
            if (!opt->grid.empty())
                for (const CLI::Option* o : {level, radius, sphere_map})
                    if (o->count() > 0)
                        spdlog::warn(
                            "simulate: {} shapes the sphere used when GRID is omitted; "
                            "{} keeps its own surface and level",
                            o->get_name(), opt->grid.string());
            return run_simulate(*opt, global);
        }));
}

const CommandRegistrar k_register_simulate{{"simulate", 40, &add_simulate_command}};

}  // namespace
}  // namespace pliant::cli
