// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Scripted peers for tests and demos (issue 6 item 7): a small text script of timed grabs and
/// a `leave`, and the real-time loop that `pliant host` and `pliant join` run: poll, play the
/// script, advance, and write a per-second statistics CSV, bounded by a duration.
///
/// Script format (one command per line, `#` starts a comment, times in seconds from the start
/// of the process's loop):
///
///     # time  command
///     0.5  grab face 700 force 0 0 0.5 for 1.0
///     1.0  grab point 0 0 1 radius 0.3 force 0 0 -0.4 for 0.5
///     2.0  poi face 700
///     3.0  leave
///
/// A grab applies its force (N) to a face, or to the nodes within `radius` (m) of a point, for
/// `for` seconds (> 0, required); it also declares the grabbed face or point as the peer's point
/// of interest. Faces are checked against the grid once it is known (check_script).

#include <pliant/core/result.h>
#include <pliant/net/message.h>
#include <pliant/net/secure_transport.h>
#include <pliant/session/session.h>

#include <csignal>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::session
{

struct ScriptEvent
{
    enum class Kind : std::uint8_t
    {
        Grab,   ///< force on target for duration
        Poi,    ///< declare target as point of interest
        Leave,  ///< leave the session
    };
    Kind kind = Kind::Grab;
    double time = 0.0;      ///< s
    double duration = 0.0;  ///< s (grab)
    net::UserForce force;   ///< target (+ force for Grab)
    std::size_t line = 0;   ///< the script's line (1-based), for messages
};

/// Parses a script. \return ParseError naming `source` and the line (`source:LINE: why`) for
/// a malformed command, a negative or non-finite number, or a grab without a duration > 0.
core::Result<std::vector<ScriptEvent>> parse_script(std::string_view text,
                                                    std::string_view source = "script");
/// Reads and parses a script file (messages name the file). \return IoError or
/// parse_script's errors.
core::Result<std::vector<ScriptEvent>> load_script(const std::filesystem::path& path);
/// The rules a script can only be checked against once the grid is known: every face lies on
/// the grid (below `face_count`), and a viewer does not grab. \return InvalidArgument naming
/// `source`, the line and the rule. (A session drops a force that breaks them rather than
/// applying it, so a script is checked before it plays.)
core::Result<void> check_script(std::span<const ScriptEvent> script, std::int64_t face_count,
                                SessionRole role, std::string_view source);

/// One second (or so) of a simulating peer's run, for PaceWatch.
struct PaceSample
{
    double wall_s = 0.0;  ///< wall time it covers, s (> 0)
    double sim_s = 0.0;   ///< simulated time the peer advanced in it, s
    double step_s = 0.0;  ///< wall time spent in its steps, s
    std::uint64_t steps = 0;
    double bytes_out = 0.0;  ///< datagram bytes it sent
    /// The session's coupling (a joiner learns it from the welcome).
    Coupling coupling = Coupling::Exact;
    /// The machine's 1-minute load average and its cores (load < 0: unknown). A load above
    /// the cores adds to the message that other work competes for them.
    double load_average = -1.0;
    int cores = 0;
    /// Exact coupling: how long the peer has waited at its current tick when the sample was
    /// taken, and for whom (SessionStats::barrier_wait_s, barrier_peer). A wait of a second or
    /// more is a member that stopped stepping, not the traffic.
    double barrier_wait_s = 0.0;
    net::PeerId barrier_peer = net::k_no_peer;
    /// The session's limit on that wait before the master removes the member
    /// (Session::max_barrier_wait(); 0: never), named in the message.
    double max_barrier_wait_s = 10.0;
};

/// The machine's 1-minute load average (/proc/loadavg), or -1 where there is none.
[[nodiscard]] double load_average() noexcept;

/// Tells a user when their peer's simulation falls behind real time, and why (run_peer logs
/// it): after k_slow_samples samples in a row below k_slow_ratio of real time, a message with
/// the pace, the steps per second and the likely cause: its own steps (they take most of its
/// time: a coarser level or more participants would keep up), or, in exact coupling, the wait
/// for its neighbours' halos every tick (with the bytes it sends and the options that cut
/// them; or a member that publishes no step at all, named), or, in fast coupling, the wait for
/// fresh neighbour states (max_halo_age_s). At most
/// one message per k_quiet_s of samples. The coupling comes with each sample (a joiner learns it
/// from the welcome).
class PaceWatch
{
public:
    static constexpr double k_slow_ratio = 0.9;
    static constexpr int k_slow_samples = 3;
    static constexpr double k_quiet_s = 30.0;
    /// Steps taking at least this share of the wall time make the steps the cause.
    static constexpr double k_step_bound = 0.6;
    /// A sample covering more wall time than this is a process that did not run (stopped with
    /// SIGSTOP, suspended): it restarts the count instead of adding to it.
    static constexpr double k_gap_s = 2.0;

    /// Adds one sample. \return the warning to log, if it is due.
    std::optional<std::string> add(const PaceSample& sample);

private:
    int slow_ = 0;          // samples in a row below k_slow_ratio
    double quiet_for_ = 0;  // wall seconds left before another message
};

struct RunOptions
{
    double duration_s = 10.0;  ///< the loop ends after this (wall clock), > 0
    std::vector<ScriptEvent> script;
    std::string script_name = "script";  ///< names the script in messages (its file)
    std::filesystem::path stats_csv;     ///< empty: none
    /// Idle time per loop iteration unless the peer is behind real time, s: a wait on the
    /// socket that a datagram ends (Session::wait), so the loop answers within it
    double idle_sleep_s = 0.0002;
    /// When set and non-zero (a signal handler's flag: Ctrl-C), the loop ends early and winds
    /// down as at the end of the duration.
    const volatile std::sig_atomic_t* stop = nullptr;
    /// The peer's encryption layer, when it has one: its connections dropped (totals().refused:
    /// another key, too many bad datagrams, a handshake that never completed) fill the
    /// `auth_refused` column and RunSummary::auth_refused. Null: 0.
    const net::SecureTransport* secure = nullptr;
};

struct RunSummary
{
    double elapsed_s = 0.0;
    std::uint64_t final_tick = 0;
    bool left = false;  ///< the peer left (script), or the session ended (master shut it down)
    /// Wall time until the model and state were installed (a joiner's download; 0 for the
    /// master; -1 if they never arrived), s.
    double model_s = -1.0;
    SessionStats stats;
    /// Connections the encryption layer dropped (RunOptions::secure; 0 without one).
    std::uint64_t auth_refused = 0;
    /// Why the stats file could not be written to its end (a full disk), or empty: the rows
    /// stop there and the session goes on; the command reports it and exits 1 at its end.
    std::string stats_error;
};

/// Runs `session` in real time until the duration, the session's end or the script's `leave`,
/// then leaves (participants, viewers) or shuts the session down (master).
/// \return IoError if the stats file cannot be written; check_script's errors once the grid is
/// known (the peer then leaves at once).
core::Result<RunSummary> run_peer(Session& session, const RunOptions& options);

}  // namespace pliant::session
