// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/session/runner.h>

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <thread>

namespace pliant::session
{

namespace
{

core::Unexpected bad_line(std::string_view source, std::size_t line, const std::string& why)
{
    return core::fail(core::ErrorCode::ParseError,
                      std::string(source) + ":" + std::to_string(line) + ": " + why);
}

/// A word as it may be shown in a message: at most 32 characters, control bytes as '?'.
std::string shown(std::string_view word)
{
    std::string out(word.substr(0, 32));
    for (char& c : out)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            c = '?';
    return "'" + out + (word.size() > 32 ? "...'" : "'");
}

/// Reads the next word as a finite decimal number into `out`. \return empty when it is one,
/// else what was found instead, for "expected X, got ...": "nothing", "'abc' (not a number)",
/// "'inf' (not a finite number)". Hexadecimal ("0x1") is not a number here.
std::string read_number(std::istringstream& in, double& out)
{
    std::string word;
    if (!(in >> word))
        return "nothing";
    const char* begin = word.data();
    const char* end = begin + word.size();
    if (begin != end && *begin == '+')
        ++begin;
    const auto [ptr, ec] = std::from_chars(begin, end, out, std::chars_format::general);
    if (ec == std::errc::result_out_of_range)
        return shown(word) + " (not a finite number)";
    if (ec != std::errc() || ptr != end)
        return shown(word) + " (not a number)";
    if (!std::isfinite(out))
        return shown(word) + " (not a finite number)";
    return {};
}

}  // namespace

core::Result<std::vector<ScriptEvent>> parse_script(std::string_view text, std::string_view source)
{
    std::vector<ScriptEvent> events;
    std::istringstream lines{std::string(text)};
    std::string raw;
    std::size_t number = 0;
    while (std::getline(lines, raw))
    {
        ++number;
        if (const auto hash = raw.find('#'); hash != std::string::npos)
            raw.erase(hash);
        std::istringstream in(raw);
        std::string first;
        if (!(in >> first))
            continue;
        ScriptEvent e;
        e.line = number;
        // "expected WHAT, got ..." for a number that is missing, not one, not finite, or
        // breaks its rule (`ok`).
        const auto need = [&](std::istringstream& from, double& v, const std::string& what,
                              bool (*ok)(double)) -> std::optional<core::Unexpected>
        {
            std::string why = read_number(from, v);
            if (why.empty() && !ok(v))
            {
                std::ostringstream value;
                value << v;
                why = "'" + value.str() + "'";
            }
            if (why.empty())
                return std::nullopt;
            return bad_line(source, number, "expected " + what + ", got " + why);
        };
        const auto any = [](double) { return true; };
        const auto non_negative = [](double v) { return v >= 0.0; };
        const auto positive = [](double v) { return v > 0.0; };
        {
            std::istringstream t(first);
            if (auto bad = need(t, e.time, "a time in seconds >= 0", non_negative))
                return *bad;
        }
        std::string cmd;
        in >> cmd;
        if (cmd == "leave")
        {
            e.kind = ScriptEvent::Kind::Leave;
            if (std::string extra; in >> extra)
                return bad_line(source, number,
                                "unexpected " + shown(extra) + " after 'leave' (it takes nothing)");
        }
        else if (cmd == "grab" || cmd == "poi")
        {
            e.kind = cmd == "grab" ? ScriptEvent::Kind::Grab : ScriptEvent::Kind::Poi;
            std::string what;
            in >> what;
            if (what == "face")
            {
                double f = 0.0;
                if (auto bad = need(in, f, "a face index (a whole number from 0)",
                                    [](double v) {
                                        return v >= 0.0 && v < net::k_max_face_index &&
                                               v == std::floor(v);
                                    }))
                    return *bad;
                e.force.target.kind = net::TargetKind::Face;
                e.force.target.face = static_cast<std::uint32_t>(f);
            }
            else if (what == "point")
            {
                e.force.target.kind = net::TargetKind::Position;
                for (double& c : e.force.target.position)
                    if (auto bad = need(in, c, "three coordinates after 'point'", any))
                        return *bad;
            }
            else
                return bad_line(source, number, "expected 'face' or 'point' after '" + cmd + "'");
            std::string key;
            while (in >> key)
            {
                if (key == "radius")
                {
                    if (auto bad = need(in, e.force.target.radius, "a radius >= 0 after 'radius'",
                                        non_negative))
                        return *bad;
                }
                else if (key == "force" && e.kind == ScriptEvent::Kind::Grab)
                {
                    for (double& c : e.force.force)
                        if (auto bad = need(in, c, "three force components after 'force'", any))
                            return *bad;
                }
                else if (key == "for" && e.kind == ScriptEvent::Kind::Grab)
                {
                    if (auto bad =
                            need(in, e.duration, "a duration in seconds > 0 after 'for'", positive))
                        return *bad;
                }
                else
                    return bad_line(source, number, "unknown key " + shown(key));
            }
        }
        else
            return bad_line(source, number, "unknown command " + shown(cmd));
        if (e.kind == ScriptEvent::Kind::Grab && !(e.duration > 0.0))
            return bad_line(source, number, "a grab needs 'for SECONDS' with a duration > 0");
        events.push_back(e);
    }
    std::stable_sort(events.begin(), events.end(),
                     [](const ScriptEvent& a, const ScriptEvent& b) { return a.time < b.time; });
    return events;
}

core::Result<std::vector<ScriptEvent>> load_script(const std::filesystem::path& path)
{
    std::ifstream in(path);
    if (!in)
        return core::fail(core::ErrorCode::IoError, "cannot read script " + path.string());
    std::stringstream ss;
    ss << in.rdbuf();
    return parse_script(ss.str(), path.string());
}

core::Result<void> check_script(std::span<const ScriptEvent> script, std::int64_t face_count,
                                SessionRole role, std::string_view source)
{
    for (const ScriptEvent& e : script)
    {
        const std::string where = std::string(source) + ":" + std::to_string(e.line) + ": ";
        if (e.kind == ScriptEvent::Kind::Grab && role == SessionRole::Viewer)
            return core::fail(core::ErrorCode::InvalidArgument,
                              where +
                                  "a viewer cannot grab (join as a participant to apply "
                                  "forces)");
        if (e.kind != ScriptEvent::Kind::Leave && e.force.target.kind == net::TargetKind::Face &&
            static_cast<std::int64_t>(e.force.target.face) >= face_count)
            return core::fail(core::ErrorCode::InvalidArgument,
                              where + "face " + std::to_string(e.force.target.face) +
                                  " is not on this grid (faces 0.." +
                                  std::to_string(face_count - 1) + ")");
    }
    return {};
}

std::optional<std::string> PaceWatch::add(const PaceSample& sample)
{
    quiet_for_ -= sample.wall_s;
    if (sample.wall_s <= 0.0)
        return std::nullopt;
    if (sample.wall_s > k_gap_s)
    {
        // The process itself did not run (stopped, suspended): nothing to say of its pace.
        slow_ = 0;
        return std::nullopt;
    }
    const double pace = sample.sim_s / sample.wall_s;
    slow_ = pace < k_slow_ratio ? slow_ + 1 : 0;
    if (slow_ < k_slow_samples || quiet_for_ > 0.0)
        return std::nullopt;
    quiet_for_ = k_quiet_s;
    const double steps_per_s = static_cast<double>(sample.steps) / sample.wall_s;
    const double load = sample.step_s / sample.wall_s;
    std::string out = fmt::format(
        "the simulation runs at {:.2f}x real time ({:.0f} steps/s): ", pace, steps_per_s);
    if (load >= k_step_bound)
        out += fmt::format(
            "its steps take {:.0f} % of this peer's time ({:.2f} ms each); a coarser level, or "
            "more participants sharing the object, would keep up",
            100.0 * load,
            sample.steps > 0 ? 1e3 * sample.step_s / static_cast<double>(sample.steps) : 0.0);
    else if (sample.coupling == Coupling::Exact && sample.barrier_wait_s >= 1.0)
        out += fmt::format(
            "it has waited {:.1f} s at one tick for peer {} to publish it (exact coupling steps "
            "every member together; {})",
            sample.barrier_wait_s, sample.barrier_peer.value,
            sample.max_barrier_wait_s > 0.0
                ? fmt::format("the master removes a member that publishes no step for {:g} s, "
                              "this session's --max-barrier-wait",
                              sample.max_barrier_wait_s)
                : std::string("this session's --max-barrier-wait 0 never removes it"));
    else if (sample.coupling == Coupling::Exact)
        out += fmt::format(
            "exact coupling steps once per round of halos with the neighbours, and this peer "
            "waits for them (its steps take {:.0f} % of its time; it sends {:.1f} MB/s); "
            "--compress or --f32 on every peer cut the leaf-state traffic, and --mode fast does "
            "not wait every step",
            100.0 * load, sample.bytes_out / sample.wall_s / 1e6);
    else
        out += fmt::format(
            "this peer holds its clock for its neighbours' states (fast coupling's bound on "
            "their age, --max-halo-age; its steps take {:.0f} % of its time)",
            100.0 * load);
    if (sample.cores > 0 && sample.load_average > static_cast<double>(sample.cores))
        out += fmt::format("; this machine is also busy (load average {:.1f} on {} cores)",
                           sample.load_average, sample.cores);
    return out;
}

double load_average() noexcept
{
    std::ifstream in("/proc/loadavg");
    double load = -1.0;
    if (!(in >> load))
        return -1.0;
    return load;
}

core::Result<RunSummary> run_peer(Session& session, const RunOptions& options)
{
    std::ofstream csv;
    if (!options.stats_csv.empty())
    {
        csv.open(options.stats_csv);
        if (!csv)
            return core::fail(core::ErrorCode::IoError,
                              "cannot write stats file " + options.stats_csv.string());
        csv << "time_s,bytes_in,bytes_out,packets_in,packets_out,drops,steps,step_ms,"
               "owned_nodes,halo_age_s,tick,peers,border_age_s,stalled_s,view_delay_s,"
               "stale_states,stale_frames,peers_connected,auth_refused,rejected,"
               "barrier_wait_s\n";
    }
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(clock::now() - t0).count(); };
    std::size_t next_event = 0;
    struct ActiveGrab
    {
        double until;
        net::UserForce force;
    };
    std::vector<ActiveGrab> grabs;
    bool leave_asked = false;
    core::Result<void> script_error;
    SessionStats last{};
    auto auth_refused = [&]
    { return options.secure != nullptr ? options.secure->totals().refused : std::uint64_t{0}; };
    std::uint64_t last_refused = 0;
    double next_row = 1.0;
    double next_wait_note = 5.0;  // a joiner's note while its model is still arriving
    bool warned_grabs = false;    // more grabs at once than one Force message holds
    RunSummary summary;
    PaceWatch pace;
    double last_row_t = 0.0;
    double last_sim_t = session.time();
    bool pace_from_here = false;  // the next row starts a sample (the peer simulates, has a model)
    // A stats file that cannot be written (a full disk) stops the rows, not the session; the
    // summary carries the error so that the command's exit status tells it.
    auto stats_failed = [&](const std::string& why)
    {
        if (!summary.stats_error.empty())
            return;
        summary.stats_error = "cannot write stats file " + options.stats_csv.string() + ": " + why +
                              "; the rows from here on are lost";
        spdlog::error("{}", summary.stats_error);
        csv.close();
    };
    auto write_row = [&](double t)
    {
        const SessionStats s = session.stats();
        const std::uint64_t refused = auth_refused();
        // Behind real time: say so, and why (a joiner's clock jumps to the master's with the
        // model, so samples start one row after it simulates). A peer that reached its
        // --ticks stops stepping on purpose: not slow.
        const bool simulating = session.ready() && session.role() != SessionRole::Viewer &&
                                s.owned_nodes > 0 && !session.left() && !session.at_max_ticks();
        if (simulating && pace_from_here)
        {
            const PaceSample sample{
                .wall_s = t - last_row_t,
                .sim_s = session.time() - last_sim_t,
                .step_s = s.step_seconds - last.step_seconds,
                .steps = s.steps - last.steps,
                .bytes_out = static_cast<double>(s.bytes_sent - last.bytes_sent),
                .coupling = session.coupling(),
                .load_average = load_average(),
                .cores = static_cast<int>(std::thread::hardware_concurrency()),
                .barrier_wait_s = s.barrier_wait_s,
                .barrier_peer = s.barrier_peer,
                .max_barrier_wait_s = session.max_barrier_wait()};
            if (auto warning = pace.add(sample))
                spdlog::warn("{}", *warning);
        }
        pace_from_here = simulating;
        last_row_t = t;
        last_sim_t = session.time();
        if (csv.is_open())
        {
            const double step_ms = s.steps > last.steps
                                       ? 1e3 * (s.step_seconds - last.step_seconds) /
                                             static_cast<double>(s.steps - last.steps)
                                       : 0.0;
            csv << t << ',' << s.bytes_received - last.bytes_received << ','
                << s.bytes_sent - last.bytes_sent << ','
                << s.packets_received - last.packets_received << ','
                << s.packets_sent - last.packets_sent << ',' << s.bad_datagrams - last.bad_datagrams
                << ',' << s.steps - last.steps << ',' << step_ms << ',' << s.owned_nodes << ','
                << s.halo_age_s << ',' << session.tick() << ',' << session.peers().size() << ','
                << s.border_age_s << ',' << s.stalled_s - last.stalled_s << ',' << s.view_delay_s
                << ',' << s.stale_states - last.stale_states << ','
                << s.stale_frames - last.stale_frames << ',' << s.peers_connected << ','
                << refused - last_refused << ',' << s.rejected_messages() - last.rejected_messages()
                << ',' << s.barrier_wait_s << '\n';
            csv.flush();
            if (!csv)  // a full disk: said once, the session goes on without its statistics
                stats_failed(std::strerror(errno));
        }
        last = s;
        last_refused = refused;
    };
    // Bounded by the duration (wall clock) and by an iteration cap.
    for (std::uint64_t iteration = 0; iteration < 1'000'000'000ULL; ++iteration)
    {
        double now = elapsed();
        if (now >= options.duration_s || session.left())
            break;
        if (options.stop != nullptr && *options.stop != 0)
        {
            spdlog::info("interrupted: {}", session.role() == SessionRole::Master
                                                ? "ending the session"
                                                : "leaving the session");
            break;
        }
        session.poll();
        // Read again after poll(): a stop of the process within it must show as a gap in
        // advance() (SessionSettings::pause_s), or the departures poll() found then would be
        // taken for the others' (docs/session.md §6).
        now = elapsed();
        if (now >= options.duration_s)
            break;  // as at the top: the last row then covers the last second and the wind-down
        if (summary.model_s < 0.0 && !session.ready() && now >= next_wait_note)
        {
            // A large model (level 10: ~100 MB with its state) takes a while: say it is coming.
            spdlog::info("waiting for the model and state: {:.1f} MB received in {:.0f} s",
                         static_cast<double>(session.stats().bytes_received) / 1e6, now);
            next_wait_note = now + 5.0;
        }
        if (summary.model_s < 0.0 && session.ready())
        {
            summary.model_s = now;
            // The grid is known from here on (a joiner learns it from the welcome).
            const auto faces = static_cast<std::int64_t>(session.model()->grid().face_count());
            script_error = check_script(options.script, faces, session.role(), options.script_name);
            // A tick to stop at is a lockstep's (the coupling is known only now): a fast peer
            // stopped there leaves its share unstepped while the others step on against it.
            if (script_error && session.role() != SessionRole::Viewer &&
                session.coupling() == Coupling::Fast && session.max_ticks() != 0)
                script_error = core::fail(
                    core::ErrorCode::InvalidArgument,
                    "--ticks " + std::to_string(session.max_ticks()) +
                        " is for exact sessions, and this session's coupling is fast: its peers "
                        "step on their own clocks, and this one would leave its share unstepped "
                        "from that tick on while the others step on; leave out --ticks");
            if (!script_error)
                break;
        }
        bool forces_changed = false;
        while (next_event < options.script.size() && options.script[next_event].time <= now &&
               session.ready())
        {
            const ScriptEvent& e = options.script[next_event++];
            switch (e.kind)
            {
            case ScriptEvent::Kind::Grab:
                grabs.push_back({now + e.duration, e.force});
                session.set_points_of_interest({e.force.target});
                forces_changed = true;
                break;
            case ScriptEvent::Kind::Poi: session.set_points_of_interest({e.force.target}); break;
            case ScriptEvent::Kind::Leave:
                leave_asked = true;
                session.leave();
                break;
            }
        }
        const std::size_t before = grabs.size();
        std::erase_if(grabs, [&](const ActiveGrab& g) { return g.until <= now; });
        if (forces_changed || grabs.size() != before)
        {
            std::vector<net::UserForce> list;
            for (std::size_t k = 0; k < grabs.size() && k < net::k_max_points; ++k)
            {
                list.push_back(grabs[k].force);
                list.back().grab_id = static_cast<std::uint16_t>(k);
            }
            if (grabs.size() > net::k_max_points && !warned_grabs)
            {
                warned_grabs = true;  // once: the list changes at every grab's start and end
                spdlog::warn("script: {} grabs at once; the first {} act (one Force message)",
                             grabs.size(), net::k_max_points);
            }
            if (auto ok = session.set_forces(std::move(list)); !ok)
                spdlog::warn("script: {}", ok.error().message);
        }
        session.advance(now);
        if (now >= next_row + 1.0)
        {
            // The loop did not run for over a second (the process was stopped, suspended or
            // starved): one row covers the gap, rather than a burst of rows of nothing.
            write_row(now);
            next_row = std::floor(now) + 1.0;
        }
        else if (now >= next_row)
        {
            write_row(next_row);
            next_row += 1.0;
        }
        if (options.idle_sleep_s > 0.0 && !session.behind())
            session.wait(options.idle_sleep_s);
    }
    // Wind down: a participant or viewer leaves (and waits, bounded, for the hand-over); the
    // master shuts the session down.
    if (session.role() == SessionRole::Master)
        session.shutdown();
    else
    {
        if (!leave_asked)
            session.leave();
        const double stop = elapsed() + 3.0;
        while (!session.left() && elapsed() < stop)
        {
            session.poll();
            session.advance(elapsed());
            session.wait(200e-6);
        }
    }
    if (!script_error)
        return core::fail(script_error.error().code, script_error.error().message);
    summary.elapsed_s = elapsed();
    write_row(summary.elapsed_s);
    if (csv.is_open())
    {
        csv.close();
        if (!csv)
            stats_failed(std::strerror(errno));
    }
    summary.final_tick = session.tick();
    summary.left = session.left();
    summary.stats = session.stats();
    summary.auth_refused = auth_refused();
    return summary;
}

}  // namespace pliant::session
