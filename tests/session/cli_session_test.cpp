// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant host` and two `pliant join` as separate processes on 127.0.0.1 for a few seconds:
// all exit 0 and their statistics show traffic both ways. Bounded by --duration.
#include <pliant/core/grid_io.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/session/recording.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "grid_shapes.h"
#include "stats_csv.h"
#include "support/test_paths.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace
{

using namespace pliant::session::test;  // read, rows, value, column_sum (stats_csv.h)

/// The UDP port of test `slot` (0..11) in this process: below Linux's ephemeral range (32768 and
/// up), so that no joiner's OS-chosen port, in this test or one running beside it, can take it
/// (the range up to 39,990 used before overlapped it: a host that cannot bind skips its test);
/// slots 1,000 apart, so that tests running at once (close process ids) differ.
/// A test may also use the port above its own.
int test_port(int slot)
{
    return 20000 + static_cast<int>((getpid() + 1000 * slot) % 12000);
}

/// The log of the peer that wrote `NAME.log` and `NAME.rc` (its exit status; none if it was
/// killed) in `dir`, when it failed naming "bind": its UDP port is taken on this machine, and
/// the test is skipped, not failed; nothing when it ran.
std::optional<std::string> bind_failure(const std::filesystem::path& dir, const std::string& name)
{
    std::string log = read(dir / (name + ".log"));
    if (log.find("bind") == std::string::npos || read(dir / (name + ".rc")) == "0\n")
        return std::nullopt;
    return log;
}

/// Skips the calling test when the peer `name` could not bind `port` (bind_failure).
#define PLIANT_SKIP_IF_UNBOUND(dir, name, port)       \
    if (const auto unbound = bind_failure(dir, name)) \
    GTEST_SKIP() << "cannot bind UDP port " << (port) << " on this machine: " << *unbound

TEST(SessionCli, HostAndTwoJoinsAsProcessesExchangeTraffic)
{
    const auto dir = pliant::test::scratch_dir("session_cli");
    const int port = test_port(0);
    {
        std::ofstream(dir / "grab.txt") << "0.3 grab face 700 force 0 0 0.5 for 1.0\n";
    }
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv; " + "('" + exe + "' host --level 4 --port " + p +
        " --duration 3 --stats host.csv > host.log 2>&1; echo $? > host.rc) & sleep 0.3; " + "('" +
        exe + "' join 127.0.0.1:" + p +
        " --duration 2.5 --script grab.txt --stats p1.csv > p1.log 2>&1; echo $? > p1.rc) & " +
        "('" + exe + "' join 127.0.0.1:" + p +
        " --viewer --duration 2.5 --stats v.csv > v.log 2>&1; echo $? > v.rc) & wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    for (const char* name : {"host", "p1", "v"})
    {
        EXPECT_EQ(read(dir / (std::string(name) + ".rc")), "0\n")
            << name << ": " << read(dir / (std::string(name) + ".log"));
        const auto csv = dir / (std::string(name) + ".csv");
        EXPECT_GT(column_sum(csv, "bytes_in"), 1000.0) << name;
        EXPECT_GT(column_sum(csv, "packets_in"), 10.0) << name;
    }
    EXPECT_GT(column_sum(dir / "host.csv", "bytes_out"), 1000.0);
    EXPECT_GT(column_sum(dir / "p1.csv", "bytes_out"), 1000.0);  // halos and leaf states
    EXPECT_GT(column_sum(dir / "p1.csv", "steps"), 10.0);
    EXPECT_EQ(column_sum(dir / "v.csv", "steps"), 0.0);  // a viewer simulates nothing
}

// `--point-clearance` reaches the session (the host says which rule it partitions with; auto
// resolves by the coupling) and an unknown value is refused naming the allowed ones.
TEST(SessionCli, HostTakesAPointClearanceAndRefusesAnUnknownOne)
{
    const auto dir = pliant::test::scratch_dir("session_cli_clearance");
    const int port = test_port(1);
    const std::string exe = PLIANT_EXE;
    const auto host = [&](const std::string& args, const char* log)
    {
        const std::string cmd = "cd '" + dir.string() + "' && '" + exe +
                                "' host --level 3 --port " + std::to_string(port) +
                                " --duration 0.3 " + args + " > " + log + " 2>&1";
        return std::system(cmd.c_str());
    };
    const int inside = host("--mode fast --point-clearance inside", "inside.log");
    const std::string inside_log = read(dir / "inside.log");
    if (inside != 0 && inside_log.find("bind") != std::string::npos)
        GTEST_SKIP() << "cannot bind UDP port " << port << ": " << inside_log;
    EXPECT_EQ(inside, 0) << inside_log;
    EXPECT_NE(inside_log.find("fast mode, point clearance inside"), std::string::npos)
        << inside_log;
    EXPECT_EQ(host("--mode fast", "auto_fast.log"), 0);
    EXPECT_NE(read(dir / "auto_fast.log").find("fast mode, point clearance grown"),
              std::string::npos);
    EXPECT_EQ(host("--mode exact", "auto_exact.log"), 0);
    EXPECT_NE(read(dir / "auto_exact.log").find("exact mode, point clearance inside"),
              std::string::npos);
    EXPECT_NE(host("--point-clearance wide", "bad.log"), 0);
    EXPECT_NE(read(dir / "bad.log").find("wide not in {auto,grown,inside}"), std::string::npos)
        << read(dir / "bad.log");
}

// A stats file that cannot be written to its end (a full disk: /dev/full) is said at once and
// gives exit status 1 at the end; the session itself runs its course. Before, the rows were lost
// without a word and the host exited 0.
TEST(SessionCli, AStatsFileThatCannotBeWrittenEndsWithStatus1)
{
    const auto dir = pliant::test::scratch_dir("session_cli_stats_full");
    const int port = test_port(1);
    const std::string cmd = "cd '" + dir.string() + "' && '" + std::string(PLIANT_EXE) +
                            "' host --level 2 --port " + std::to_string(port) +
                            " --duration 1 --stats /dev/full > host.log 2>&1; echo $? > host.rc";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string log = read(dir / "host.log");
    EXPECT_EQ(read(dir / "host.rc"), "1\n") << log;
    EXPECT_NE(log.find("cannot write stats file /dev/full: No space left on device"),
              std::string::npos)
        << log;
    EXPECT_NE(log.find("host: 1.0 s, tick"), std::string::npos) << log;
}

// Kill -9 a participant, then the master, mid-session (fast coupling, so that the others keep
// running while ENet's timeout, at least 5 s, runs out): the remaining participant takes over as
// master, owns every node and keeps stepping, and the viewer keeps receiving. Bounded by the
// durations (about 20 s).
TEST(SessionCli, KillingAParticipantThenTheMasterLeavesTheOthersRunning)
{
    const auto dir = pliant::test::scratch_dir("session_cli_kill");
    const int port = test_port(2);
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    const std::string join = "'" + exe + "' join 127.0.0.1:" + p;
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv *.log; '" + exe +
        "' host --level 4 --mode fast --port " + p +
        " --duration 40 > host.log 2>&1 & HOST=$!; sleep 0.5; (" + join +
        " --duration 18 --stats a.csv > a.log 2>&1; echo $? > a.rc) & sleep 0.5; " + join +
        " --duration 40 > b.log 2>&1 & B=$!; sleep 0.3; (" + join +
        " --viewer --duration 18 --stats v.csv > v.log 2>&1; echo $? > v.rc) & " +
        "sleep 1.5; kill -9 $B; sleep 1.0; kill -9 $HOST; wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    EXPECT_EQ(read(dir / "a.rc"), "0\n") << read(dir / "a.log");
    EXPECT_EQ(read(dir / "v.rc"), "0\n") << read(dir / "v.log");
    EXPECT_NE(read(dir / "a.log").find("peer 1 takes over"), std::string::npos)
        << read(dir / "a.log");
    EXPECT_NE(read(dir / "v.log").find("peer 1 takes over"), std::string::npos)
        << read(dir / "v.log");
    // The successor says where later joiners find it: the port it said it listens on.
    const std::string a_log = read(dir / "a.log");
    const std::string listening = "join: listening on port ";
    const auto at = a_log.find(listening);
    ASSERT_NE(at, std::string::npos) << a_log;
    const std::string own_port = std::to_string(std::stoi(a_log.substr(at + listening.size())));
    EXPECT_NE(a_log.find("this peer (id 1) is the master now; joiners dial it on port " + own_port),
              std::string::npos)
        << a_log;
    // Level 4: 2 * 16^2 + 2 canonical nodes, all owned by the one participant left.
    const auto a = rows(dir / "a.csv");
    const auto v = rows(dir / "v.csv");
    ASSERT_GE(a.size(), 16U);
    ASSERT_GE(v.size(), 12U);  // its process may start late on a loaded machine
    // The two left are connected to each other only (the killed ones departed).
    for (std::size_t k = a.size() - 4; k < a.size() - 1; ++k)
    {
        EXPECT_EQ(value(a[k], "owned_nodes"), 514.0) << "row " << k;
        EXPECT_GT(value(a[k], "steps"), 0.0) << "row " << k;
        EXPECT_EQ(value(a[k], "peers_connected"), 1.0) << "row " << k;
    }
    for (std::size_t k = v.size() - 4; k < v.size() - 1; ++k)
    {
        EXPECT_GT(value(v[k], "bytes_in"), 1000.0) << "row " << k;
        EXPECT_EQ(value(v[k], "peers_connected"), 1.0) << "row " << k;
    }
}

// A host whose step diverges (a 1e308 N grab with --max-force 0, exact coupling) says so, leaves
// and exits 3 at once, not at its --duration; the participant takes over its share and runs to
// its own end with status 0. Bounded by the durations (host 20 s, participant 6 s).
TEST(SessionCli, ADivergingHostLeavesAndTheParticipantGoesOn)
{
    const auto dir = pliant::test::scratch_dir("session_cli_diverge");
    const int port = test_port(11);
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    {
        std::ofstream script(dir / "huge.txt");
        script << "2.0 grab face 100 force 0 0 1e308 for 30\n";
    }
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv *.log; ('" + exe + "' host --level 4 --port " + p +
        " --max-force 0 --script huge.txt --duration 20 > host.log 2>&1; echo $? > host.rc) & "
        "sleep 0.5; '" +
        exe + "' join 127.0.0.1:" + p +
        " --duration 6 --stats a.csv > a.log 2>&1; echo $? > a.rc; wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string host_log = read(dir / "host.log");
    const std::string a_log = read(dir / "a.log");
    EXPECT_EQ(read(dir / "host.rc"), "3\n") << host_log;
    EXPECT_NE(host_log.find("host: the simulation diverged at tick"), std::string::npos)
        << host_log;
    // Its summary line: "host: S s, tick T, ...", S well below its --duration of 20 s.
    const auto at = host_log.find("\nhost: ");
    ASSERT_NE(at, std::string::npos) << host_log;
    EXPECT_LT(std::stod(host_log.substr(at + 7)), 10.0) << host_log;
    EXPECT_EQ(read(dir / "a.rc"), "0\n") << a_log;
    EXPECT_NE(a_log.find("peer 1 takes over"), std::string::npos) << a_log;
    EXPECT_NE(a_log.find("took over leaves of a lost peer"), std::string::npos) << a_log;
    // Its last full rows: it owns every node (level 4: 514) and steps.
    const auto a = rows(dir / "a.csv");
    ASSERT_GE(a.size(), 4U);
    for (std::size_t k = a.size() - 3; k < a.size() - 1; ++k)
    {
        EXPECT_EQ(value(a[k], "owned_nodes"), 514.0) << "row " << k;
        EXPECT_GT(value(a[k], "steps"), 0.0) << "row " << k;
    }
}

// Ctrl-C (SIGINT) or SIGTERM ends `pliant join` and `pliant host` cleanly long before their
// --duration: the participant leaves (its summary is printed, exit 0), then the master ends the
// session, and a viewer still connected sees the end and exits 0 too. Bounded: the durations
// are 30 s, the whole run takes about 4 s, and a watchdog kills anything left after 20 s.
TEST(SessionCli, InterruptLeavesAndEndsTheSessionCleanly)
{
    const auto dir = pliant::test::scratch_dir("session_cli_interrupt");
    const int port = test_port(3);
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    // A watchdog kills anything left after 20 s (its output to /dev/null: its orphaned `sleep`
    // would otherwise hold the test's output open for 20 s after the test ends); the signals go to
    // the pliant processes themselves (`timeout` in between would relay them and report its own
    // status).
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv *.log; '" + exe + "' host --level 4 --port " + p +
        " --duration 30 > host.log 2>&1 & HOST=$!; sleep 0.3; '" + exe + "' join 127.0.0.1:" + p +
        " --duration 30 --stats a.csv > a.log 2>&1 & A=$!; '" + exe + "' join 127.0.0.1:" + p +
        " --viewer --duration 30 > v.log 2>&1 & V=$!; "
        "(sleep 20; kill -9 $HOST $A $V) > /dev/null 2>&1 & W=$!; "
        "sleep 1.5; kill -INT $A; wait $A; echo $? > a.rc; sleep 0.5; "
        "kill -TERM $HOST; wait $HOST; echo $? > host.rc; wait $V; "
        "echo $? > v.rc; kill $W 2>/dev/null; wait";
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string host_log = read(dir / "host.log");
    EXPECT_EQ(read(dir / "a.rc"), "0\n") << read(dir / "a.log");
    EXPECT_EQ(read(dir / "host.rc"), "0\n") << host_log;
    EXPECT_EQ(read(dir / "v.rc"), "0\n") << read(dir / "v.log");
    EXPECT_NE(read(dir / "a.log").find("join (id"), std::string::npos) << read(dir / "a.log");
    EXPECT_NE(host_log.find("host: "), std::string::npos) << host_log;
    EXPECT_LT(seconds, 15.0) << "the interrupts ended the peers, not their --duration";
    EXPECT_GE(rows(dir / "a.csv").size(), 1U) << "the stats file got its final row";
}

// A participant stopped with SIGSTOP (its connection stays open for ENet's 5 s at least) holds
// an exact session at one tick: every peer waits for its step. The master removes it after
// --max-barrier-wait (1.5 s here), logs whom and why, and shows the wait in its --stats
// column barrier_wait_s; the other participant steps on; the stopped one, continued 3.5 s after
// the stop, learns it was removed and exits 3 rather than taking over as master. Bounded by the
// durations (about 12 s; a watchdog kills anything left after 25 s).
TEST(SessionCli, AStoppedParticipantIsRemovedAndTheOthersGoOn)
{
    const auto dir = pliant::test::scratch_dir("session_cli_stopped");
    const int port = test_port(1);
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    const std::string join = "'" + exe + "' join 127.0.0.1:" + p;
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv *.log; ('" + exe + "' host --level 4 --port " + p +
        " --duration 11 --max-barrier-wait 1.5 --stats host.csv > host.log 2>&1; echo $? > "
        "host.rc) & sleep 0.5; (" +
        join +
        " --name steady --duration 10 --stats a.csv > a.log "
        "2>&1; echo $? > a.rc) & sleep 0.3; " +
        join +
        " --name frozen --duration 10 > b.log "
        "2>&1 & B=$!; (sleep 25; kill -9 $B) > /dev/null 2>&1 & W=$!; sleep 3; kill -STOP $B; "
        "sleep 3.5; kill -CONT $B; wait $B; echo $? > b.rc; kill $W 2>/dev/null; wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string host_log = read(dir / "host.log");
    const std::string b_log = read(dir / "b.log");
    EXPECT_EQ(read(dir / "host.rc"), "0\n") << host_log;
    EXPECT_EQ(read(dir / "a.rc"), "0\n") << read(dir / "a.log");
    EXPECT_EQ(read(dir / "b.rc"), "3\n") << b_log;
    EXPECT_NE(host_log.find("removing peer 2 (frozen) from the session"), std::string::npos)
        << host_log;
    EXPECT_NE(b_log.find("the master removed this peer"), std::string::npos) << b_log;
    EXPECT_EQ(b_log.find("takes over"), std::string::npos) << b_log;
    // The wait shows in the master's rows, and the steady participant steps to the end.
    const auto h = rows(dir / "host.csv");
    double longest = 0.0;
    for (const Row& r : h)
        longest = std::max(longest, value(r, "barrier_wait_s"));
    EXPECT_GT(longest, 0.5);
    EXPECT_EQ(column_sum(dir / "host.csv", "rejected"), 0.0);
    const auto a = rows(dir / "a.csv");
    ASSERT_GE(a.size(), 8U);
    for (std::size_t k = a.size() - 2; k < a.size(); ++k)
    {
        EXPECT_GT(value(a[k], "steps"), 100.0) << "row " << k;
        EXPECT_LT(value(a[k], "barrier_wait_s"), 0.5) << "row " << k;
    }
}

// A process stopped (SIGSTOP) for 8 s, past ENet's 5 s timeout, is dropped by the others, who go
// on without it (docs/session.md §6). Resumed, its own links time out: a participant used to take
// over as master of a second session of its own, and a master to go on alone, each until its
// --duration and with exit status 0. Now each notices the pause (SessionSettings::pause_s) and
// exits 3 within a few seconds, saying why; the others go on. Bounded by the durations (about
// 17 s) and a kill after 40 s. `stopped`: "participant" or "master".
void stop_past_the_timeout(const std::string& stopped)
{
    const auto dir = pliant::test::scratch_dir(("session_cli_paused_" + stopped).c_str());
    const int port = test_port(stopped == "master" ? 3 : 9);
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    const bool master = stopped == "master";
    const std::string join = "'" + exe + "' -v join 127.0.0.1:" + p + " --duration ";
    // The stopped process runs directly in the background (its $! is the process itself);
    // it would run 25 s, the others 16-17 s.
    const std::string host = "'" + exe + "' -v host --level 4 --port " + p +
                             " --mode fast --duration " + (master ? "25" : "17") +
                             " > host.log 2>&1";
    const std::string other = join + (master ? "16" : "25") + " --name other > b.log 2>&1";
    const std::string stopped_name = master ? "host" : "b";
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.log *.ms; " +
        (master ? host + " & V=$!; " : "(" + host + "; echo $? > host.rc) & ") + "sleep 0.5; (" +
        join + "16 --name steady > a.log 2>&1; echo $? > a.rc) & sleep 0.3; " +
        (master ? "(" + other + "; echo $? > b.rc) & " : other + " & V=$!; ") +
        "sleep 3; (sleep 40; kill -9 $V) > /dev/null 2>&1 & W=$!; kill -STOP $V; sleep 8; "
        "T0=$(date +%s%N); kill -CONT $V; wait $V; echo $? > " +
        stopped_name +
        ".rc; echo $(( ($(date +%s%N) - T0) / 1000000 )) > stopped.ms; kill $W 2>/dev/null; "
        "wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string log = read(dir / (stopped_name + ".log"));
    EXPECT_EQ(read(dir / (stopped_name + ".rc")), "3\n") << log;
    EXPECT_NE(log.find("this " + stopped + " did not run for 8."), std::string::npos) << log;
    EXPECT_NE(log.find("went on without it"), std::string::npos) << log;
    EXPECT_EQ(log.find("lost; peer"), std::string::npos) << log;  // no "... takes over" line
    // It ended soon after it was resumed, well before its --duration (14 s after the resume).
    const double ms = std::stod(read(dir / "stopped.ms"));
    EXPECT_LT(ms, 10000.0) << log;
    // The others went on without it and ended normally.
    for (const std::string& name :
         master ? std::vector<std::string>{"a", "b"} : std::vector<std::string>{"host", "a"})
        EXPECT_EQ(read(dir / (name + ".rc")), "0\n") << name << ": " << read(dir / (name + ".log"));
    if (master)
        EXPECT_NE(read(dir / "a.log").find("master 0 lost; peer 1 takes over"), std::string::npos)
            << read(dir / "a.log");
    else
        EXPECT_NE(read(dir / "host.log").find("peer 2 disconnected (timed-out)"), std::string::npos)
            << read(dir / "host.log");
}

TEST(SessionCli, AParticipantStoppedPastTheTimeoutLeavesInsteadOfTakingOver)
{
    stop_past_the_timeout("participant");
}

TEST(SessionCli, AMasterStoppedPastTheTimeoutLeavesTheSessionToItsSuccessor)
{
    stop_past_the_timeout("master");
}

// A peer that cannot keep real time says so, and why: a lone level-9 master steps the whole
// object, several milliseconds per 0.45 ms tick, so after three slow seconds it warns with its
// pace and names its steps as the cause (PaceWatch, tests/session/script_test.cpp).
TEST(SessionCli, AHostBehindRealTimeSaysSoAndWhy)
{
    const auto dir = pliant::test::scratch_dir("session_cli_pace");
    const int port = test_port(6);
    const std::string exe = PLIANT_EXE;
    const std::string cmd = "cd '" + dir.string() + "' && '" + exe + "' host --level 9 --port " +
                            std::to_string(port) +
                            " --duration 6 > host.log 2>&1; echo $? > host.rc";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string log = read(dir / "host.log");
    EXPECT_EQ(read(dir / "host.rc"), "0\n") << log;
    EXPECT_NE(log.find("warning: the simulation runs at 0."), std::string::npos) << log;
    EXPECT_NE(log.find("x real time ("), std::string::npos) << log;
    EXPECT_NE(log.find("its steps take"), std::string::npos) << log;
    EXPECT_NE(log.find("coarser level"), std::string::npos) << log;
}

// A joiner with another key file, and one with no secret, cannot join a master that has one:
// each exits 3 saying why (it used to say only "never received the model"); the master warns of
// the first refusal (at most one line per 10 s) and counts both in its --stats column
// auth_refused and its summary line. Bounded by the durations (about 6 s).
TEST(SessionCli, RefusedJoinersSayWhyAndTheMasterCountsThem)
{
    const auto dir = pliant::test::scratch_dir("session_cli_refused");
    const int port = test_port(4);
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    {
        std::ofstream(dir / "good.key") << "alpha alpha alpha\n";
        std::ofstream(dir / "other.key") << "beta beta\n";
    }
    const std::string join = "'" + exe + "' join 127.0.0.1:" + p + " --duration 4";
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv *.log; ('" + exe + "' host --level 3 --port " + p +
        " --duration 5 --key-file good.key --stats host.csv > host.log 2>&1; echo $? > host.rc) "
        "& sleep 1.5; (" +
        join + " --key-file other.key > wrong.log 2>&1; echo $? > wrong.rc); (" + join +
        " > plain.log 2>&1; echo $? > plain.rc); wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string host_log = read(dir / "host.log");
    EXPECT_EQ(read(dir / "host.rc"), "0\n") << host_log;
    const std::string wrong = read(dir / "wrong.log");
    EXPECT_EQ(read(dir / "wrong.rc"), "3\n") << wrong;
    EXPECT_NE(wrong.find("refused the connection (reason refused): it has another --passphrase"),
              std::string::npos)
        << wrong;
    const std::string plain = read(dir / "plain.log");
    EXPECT_EQ(read(dir / "plain.rc"), "3\n") << plain;
    EXPECT_NE(plain.find("the master seemingly has a --passphrase or --key-file"),
              std::string::npos)
        << plain;
    EXPECT_NE(host_log.find("secure: refused the connection from 127.0.0.1:"), std::string::npos)
        << host_log;
    EXPECT_EQ(column_sum(dir / "host.csv", "auth_refused"), 2.0);
    EXPECT_NE(host_log.find("2 connections refused"), std::string::npos) << host_log;
}

}  // namespace

namespace
{

// --stream-coarsen (docs/session.md §5.2): an exact-mode host streaming one level down feeds a
// viewer; a participant asking for it in a fast session exits non-zero with the reason, and one
// giving --ticks there exits 1 (it stopped stepping its share at that tick, silently, for the
// rest of the session). Bounded by the durations (about 3 s each).
TEST(SessionCli, StreamCoarsenFeedsAViewerAndIsRefusedInFastMode)
{
    const auto dir = pliant::test::scratch_dir("session_cli_coarse");
    const int port = test_port(5);
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    const std::string q = std::to_string(port + 1);
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv; " + "('" + exe + "' host --level 4 --port " + p +
        " --duration 2.5 --stream-coarsen 1 > host.log 2>&1; echo $? > host.rc) & sleep 0.3; " +
        "('" + exe + "' join 127.0.0.1:" + p +
        " --viewer --duration 2 --stats v.csv > v.log 2>&1; echo $? > v.rc) & " + "('" + exe +
        "' host --level 4 --mode fast --port " + q +
        " --duration 2.5 > fast.log 2>&1; echo $? > fast.rc) & sleep 0.3; " + "('" + exe +
        "' join 127.0.0.1:" + q +
        " --stream-coarsen 1 --duration 2 > refused.log 2>&1; echo $? > refused.rc) & " + "('" +
        exe + "' join 127.0.0.1:" + q +
        " --ticks 50 --duration 2 > ticks.log 2>&1; echo $? > ticks.rc) & wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string host_log = read(dir / "host.log");
    EXPECT_EQ(read(dir / "host.rc"), "0\n") << host_log;
    EXPECT_EQ(read(dir / "v.rc"), "0\n") << read(dir / "v.log");
    EXPECT_GT(column_sum(dir / "v.csv", "bytes_in"), 1000.0);
    EXPECT_NE(read(dir / "refused.rc"), "0\n");
    EXPECT_NE(read(dir / "refused.log").find("refused in fast coupling"), std::string::npos)
        << read(dir / "refused.log");
    EXPECT_EQ(read(dir / "ticks.rc"), "1\n") << read(dir / "ticks.log");
    EXPECT_NE(read(dir / "ticks.log").find("--ticks 50 is for exact sessions"), std::string::npos)
        << read(dir / "ticks.log");
}

// The check with separate processes over ENet on 127.0.0.1: a master and 1 or 2
// participants in exact coupling, each grabbing, all stop at tick 1,500 (--ticks) and save what
// they show (8 s of wall time leave room for a slow build, as under the sanitizers, to reach
// that tick); the master's recording replayed on one process (`pliant replay`) is bit-identical
// to the session, and every peer's saved u and v equal the replay's to 1e-12 (in fact exactly).
void run_exact_processes(int participants)
{
    const auto dir = pliant::test::scratch_dir(participants == 1 ? "session_cli_exact_2"
                                                                 : "session_cli_exact_3");
    const int port = test_port(5 + participants);
    {
        std::ofstream(dir / "g1.txt") << "0.2 grab face 700 force 0 0 0.5 for 0.6\n";
        std::ofstream(dir / "g2.txt") << "0.3 grab point 0 0 1 radius 0.4 force 0 0 -0.4 for 0.5\n";
    }
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    std::string cmd = "cd '" + d + "' && rm -f *.rc *.pgrid *.prec; ('" + exe +
                      "' host --level 4 --port " + p +
                      " --ticks 1500 --duration 8 --record rec.prec --save host.pgrid > host.log "
                      "2>&1; echo $? > host.rc) & sleep 0.3; ";
    for (int k = 1; k <= participants; ++k)
    {
        const std::string n = std::to_string(k);
        cmd += "('" + exe + "' join 127.0.0.1:" + p + " --ticks 1500 --duration 9 --script g" + n +
               ".txt --save p" + n + ".pgrid > p" + n + ".log 2>&1; echo $? > p" + n + ".rc) & ";
    }
    cmd +=
        "wait; '" + exe + "' replay rec.prec -o ref.pgrid > replay.log 2>&1; echo $? > replay.rc";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    std::vector<std::string> peers{"host"};
    for (int k = 1; k <= participants; ++k)
        peers.push_back("p" + std::to_string(k));
    for (const std::string& name : peers)
    {
        const std::string log = read(dir / (name + ".log"));
        ASSERT_EQ(read(dir / (name + ".rc")), "0\n") << name << ": " << log;
        // Stopped at --ticks on purpose for the rest of --duration: no "behind real time"
        // warning of a peer that makes no steps (it gave one, with wrong advice).
        EXPECT_EQ(log.find("(0 steps/s)"), std::string::npos) << name << ": " << log;
    }
    EXPECT_EQ(read(dir / "replay.rc"), "0\n") << read(dir / "replay.log");
    EXPECT_NE(read(dir / "replay.log").find("bit-identical"), std::string::npos);
    const auto ref = pliant::core::load_grid(dir / "ref.pgrid");
    ASSERT_TRUE(ref) << ref.error().message;
    const pliant::core::TetraGrid grid = pliant::core::TetraGrid::create(4).value();
    for (const std::string& name : peers)
    {
        const auto saved = pliant::core::load_grid(dir / (name + ".pgrid"));
        ASSERT_TRUE(saved) << name << ": " << saved.error().message;
        std::set<long> owners;
        for (const char* channel : {"u", "v"})
        {
            const pliant::core::Field<double>* a = saved->find(channel);
            const pliant::core::Field<double>* b = ref->find(channel);
            ASSERT_NE(a, nullptr);
            ASSERT_NE(b, nullptr);
            double diff = 0.0;
            double scale = 0.0;
            for (std::uint32_t i = 0; i < grid.node_count(); ++i)
            {
                const pliant::core::NodeIndex n{i};
                diff = std::max(diff, std::abs((*a)[n] - (*b)[n]));
                scale = std::max(scale, std::abs((*b)[n]));
            }
            EXPECT_GT(scale, 1e-3) << "the grabs moved the surface";
            EXPECT_LE(diff, 1e-12 * scale) << name << " " << channel;
            EXPECT_EQ(diff, 0.0) << name << " " << channel << ": bit for bit";
        }
        const pliant::core::Field<double>* owner = saved->find("owner");
        ASSERT_NE(owner, nullptr);
        for (std::uint32_t i = 0; i < grid.node_count(); ++i)
            owners.insert(std::lround((*owner)[pliant::core::NodeIndex{i}]));
        EXPECT_EQ(owners.size(), peers.size()) << name << ": every member owns a share";
    }
}

// `host --record` without --ticks on the participants (they stop when the master leaves, at
// other ticks than its last): the recording's hash covers the master's own nodes at its final
// tick, and the replay is bit-identical on them. Before, the hash took the participants' last
// streamed leaves too, which were of other ticks, and the replay never matched.
TEST(SessionCli, ARecordingWithoutCommonTicksReplaysBitForBitOnTheMastersNodes)
{
    const auto dir = pliant::test::scratch_dir("session_cli_record_no_ticks");
    const int port = test_port(8);
    std::ofstream(dir / "g1.txt") << "0.2 grab face 700 force 0 0 0.5 for 1.5\n";
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.prec; ('" + exe + "' host --level 4 --port " + p +
        " --duration 2.5 --record rec.prec > host.log 2>&1; echo $? > host.rc) & sleep 0.3; ('" +
        exe + "' join 127.0.0.1:" + p +
        " --duration 4 --script g1.txt > p1.log 2>&1; echo $? > p1.rc) & wait; '" + exe +
        "' replay rec.prec > replay.log 2>&1; echo $? > replay.rc";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
    const std::string host_log = read(dir / "host.log");
    ASSERT_EQ(read(dir / "host.rc"), "0\n") << host_log;
    EXPECT_NE(host_log.find("over the master's"), std::string::npos) << host_log;
    EXPECT_EQ(read(dir / "replay.rc"), "0\n") << read(dir / "replay.log");
    const std::string replay_log = read(dir / "replay.log");
    EXPECT_NE(replay_log.find("bit-identical"), std::string::npos) << replay_log;
    EXPECT_NE(replay_log.find("(the master's own)"), std::string::npos) << replay_log;
}

TEST(SessionCli, ExactTwoProcessesEqualOneProcessBitForBit)
{
    run_exact_processes(1);
}

TEST(SessionCli, ExactThreeProcessesEqualOneProcessBitForBit)
{
    run_exact_processes(2);
}

// --f32 and --stream-rate reach the stream: a viewer of a host streaming f32 leaf states at
// 30 Hz receives about a quarter of the bytes of one streaming f64 at 60 Hz (half the value
// bytes, half the rate; headers and control traffic make it a little more).
TEST(SessionCli, F32AndStreamRateCutTheStream)
{
    const auto dir = pliant::test::scratch_dir("session_cli_stream_options");
    const int port = test_port(9);
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    const std::string q = std::to_string(port + 1);
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv; ('" + exe + "' host --level 4 --port " + p +
        " --duration 3 > full.log 2>&1; echo $? > full.rc) & ('" + exe +
        "' host --level 4 --port " + q +
        " --duration 3 --f32 --stream-rate 30 > cut.log 2>&1; echo $? > cut.rc) & sleep 0.3; ('" +
        exe + "' join 127.0.0.1:" + p +
        " --viewer --duration 2 --stats vfull.csv > vfull.log 2>&1; echo $? > vfull.rc) & ('" +
        exe + "' join 127.0.0.1:" + q +
        " --viewer --duration 2 --stats vcut.csv > vcut.log 2>&1; echo $? > vcut.rc) & wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "full", port);
    for (const char* name : {"full", "cut", "vfull", "vcut"})
        ASSERT_EQ(read(dir / (std::string(name) + ".rc")), "0\n")
            << name << ": " << read(dir / (std::string(name) + ".log"));
    const double full = column_sum(dir / "vfull.csv", "bytes_in");
    const double cut = column_sum(dir / "vcut.csv", "bytes_in");
    EXPECT_GT(cut, 1000.0);
    EXPECT_LT(cut, 0.4 * full) << "f32 at 30 Hz: " << cut << " bytes, f64 at 60 Hz: " << full;
    EXPECT_GT(cut, 0.15 * full) << "f32 at 30 Hz: " << cut << " bytes, f64 at 60 Hz: " << full;
}

/// Largest |a - b| over the grid's nodes of channel `name` of two grid files, and max |b|.
struct ChannelDiff
{
    double diff = 0.0;
    double scale = 0.0;
};

ChannelDiff channel_diff(const std::filesystem::path& a_path, const std::filesystem::path& b_path,
                         const char* name)
{
    const auto a = pliant::core::load_grid(a_path);
    const auto b = pliant::core::load_grid(b_path);
    EXPECT_TRUE(a && b) << a_path << " " << b_path;
    if (!a || !b || a->find(name) == nullptr || b->find(name) == nullptr)
        return {1e300, 0.0};
    const pliant::core::TetraGrid grid = pliant::core::TetraGrid::create(a->level).value();
    ChannelDiff d;
    for (std::uint32_t i = 0; i < grid.node_count(); ++i)
    {
        const pliant::core::NodeIndex n{i};
        d.diff = std::max(d.diff, std::abs((*a->find(name))[n] - (*b->find(name))[n]));
        d.scale = std::max(d.scale, std::abs((*b->find(name))[n]));
    }
    return d;
}

// A saved state (`host --save`, a `simulate` frame) given as GRID is refused, pointing to
// --resume; with --resume, host and simulate go on from it: the host's first tick stays next to
// the saved surface (from rest it would be flat), a simulation resumed from frame 2 starts on
// frame 2's state bit for bit and, once the forces are over, reproduces the original run's later
// frame; a state of another rest geometry (the gnomonic sphere) or level is refused.
TEST(SessionCli, ASavedStateResumesInHostAndSimulateAndIsRefusedAsRestGeometry)
{
    const auto dir = pliant::test::scratch_dir("session_cli_resume");
    const int port = test_port(10);
    {
        std::ofstream(dir / "grab.txt") << "0.05 grab face 300 force 0 0 0.6 for 0.3\n";
        const char* material =
            "[material]\nbeta = 0.5\nk_f = 1.0\n"
            "[integrator]\nfixed_step = true\nfixed_dt = 0.001\n";
        std::ofstream(dir / "pull.toml")
            << "duration = 0.4\nframe_rate = 10.0\n"
            << material
            << "[[force]]\nstart = 0.0\nend = 0.1\npoint = [0.0, 0.0, 1.0]\nradius = 0.4\n"
               "vector = [0.0, 0.0, 0.5]\n";
        std::ofstream(dir / "free.toml") << "duration = 0.2\nframe_rate = 10.0\n" << material;
    }
    const std::string exe = "'" + std::string(PLIANT_EXE) + "'";
    const std::string p = " --port " + std::to_string(port);
    const auto run = [&](const std::string& name, const std::string& args)
    { return "(" + exe + " " + args + " > " + name + ".log 2>&1; echo $? > " + name + ".rc); "; };
    const std::string cmd =
        "cd '" + dir.string() + "' && rm -rf *.rc *.pgrid o1 o2; " +
        run("a", "host --level 4" + p + " --ticks 300 --duration 0.8 --script grab.txt --save " +
                     "a.pgrid") +
        run("as_rest", "host a.pgrid" + p + " --duration 0.2") +
        run("b",
            "host --level 4" + p + " --resume a.pgrid --ticks 1 --duration 0.3 --save b.pgrid") +
        run("other", "host --level 4 --sphere-map gnomonic" + p + " --resume a.pgrid") +
        run("level", "host --level 5" + p + " --resume a.pgrid") +
        run("o1", "simulate --level 4 --scenario pull.toml -o o1") +
        run("o2", "simulate --level 4 --scenario free.toml -o o2 --resume o1/frame_00002.pgrid") +
        run("frame_as_rest", "simulate o1/frame_00002.pgrid --scenario free.toml -o o3");
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    PLIANT_SKIP_IF_UNBOUND(dir, "a", port);
    for (const char* name : {"a", "b", "o1", "o2"})
        ASSERT_EQ(read(dir / (std::string(name) + ".rc")), "0\n")
            << name << ": " << read(dir / (std::string(name) + ".log"));
    for (const char* name : {"as_rest", "frame_as_rest"})
    {
        EXPECT_NE(read(dir / (std::string(name) + ".rc")), "0\n") << name;
        EXPECT_NE(read(dir / (std::string(name) + ".log")).find("holds a simulated state"),
                  std::string::npos)
            << read(dir / (std::string(name) + ".log"));
        EXPECT_NE(read(dir / (std::string(name) + ".log")).find("--resume"), std::string::npos);
    }
    EXPECT_NE(read(dir / "other.rc"), "0\n");
    EXPECT_NE(read(dir / "other.log").find("not a state of this rest geometry"), std::string::npos)
        << read(dir / "other.log");
    EXPECT_NE(read(dir / "level.rc"), "0\n");
    EXPECT_NE(read(dir / "level.log").find("a state of level 4"), std::string::npos)
        << read(dir / "level.log");

    // Host: one tick of 1 ms after the saved state.
    const ChannelDiff host = channel_diff(dir / "b.pgrid", dir / "a.pgrid", "u");
    EXPECT_GT(host.scale, 1e-3) << "the grab moved the surface";
    EXPECT_LT(host.diff, 0.05 * host.scale) << "the resumed host starts where the saved one was";
    // Simulate: frame 0 of the resumed run is the saved frame; its frame 2 (0.2 s later, no
    // force in either run by then) is the original's frame 4.
    for (const char* channel : {"u", "v"})
    {
        const ChannelDiff start = channel_diff(dir / "o2" / "frame_00000.pgrid",
                                               dir / "o1" / "frame_00002.pgrid", channel);
        EXPECT_GT(start.scale, 1e-4) << channel;
        EXPECT_EQ(start.diff, 0.0) << channel;
        const ChannelDiff later = channel_diff(dir / "o2" / "frame_00002.pgrid",
                                               dir / "o1" / "frame_00004.pgrid", channel);
        EXPECT_GT(later.scale, 1e-4) << channel;
        EXPECT_LE(later.diff, 1e-12 * later.scale) << channel;
    }
    // A state of u and v alone (no positions: pliant never writes one) cannot be checked against
    // the rest shape: it is taken as it is, with a warning that says so.
    auto frame = pliant::core::load_grid(dir / "o1" / "frame_00002.pgrid");
    ASSERT_TRUE(frame.has_value());
    std::erase_if(frame->fields,
                  [](const pliant::core::NamedField& f) { return f.name != "u" && f.name != "v"; });
    ASSERT_EQ(frame->fields.size(), 2U);
    ASSERT_TRUE(pliant::core::save_grid(dir / "uv.pgrid", *frame).has_value());
    const std::string uv_cmd = "cd '" + dir.string() + "' && rm -rf o4; " +
                               run("uv",
                                   "simulate --level 4 --scenario free.toml -o o4 --resume "
                                   "uv.pgrid");
    ASSERT_EQ(std::system(uv_cmd.c_str()), 0);
    ASSERT_EQ(read(dir / "uv.rc"), "0\n") << read(dir / "uv.log");
    EXPECT_NE(read(dir / "uv.log")
                  .find("--resume uv.pgrid: no positions (channels px, py, pz), "
                        "so the state cannot be checked against the rest shape"),
              std::string::npos)
        << read(dir / "uv.log");
    EXPECT_EQ(
        channel_diff(dir / "o4" / "frame_00000.pgrid", dir / "o1" / "frame_00002.pgrid", "u").diff,
        0.0);
}

// Ctrl-C during `pliant replay`: the replay stops within 16 steps, says at which tick, writes
// nothing at -o and exits with status 130. The recording (a million ticks at level 5, many
// seconds of replay) is made here; the signal goes once the replay's log shows progress.
// A grid file whose positions are all equal has no surface to simulate: simulate and host say
// so naming the file and the node (the model's message, without the library's function names),
// with status 1.
TEST(SessionCli, ADegenerateGridFileIsRefusedNamingTheFileAndTheNode)
{
    const auto dir = pliant::test::scratch_dir("session_cli_degenerate_grid");
    const auto grid = pliant::core::TetraGrid::create(3).value();
    pliant::core::Vec3Field<double> flat;
    for (auto& plane : flat)
        plane = pliant::core::Field<double>(grid);  // every position (0, 0, 0)
    ASSERT_TRUE(
        pliant::core::save_grid(dir / "flat.pgrid", pliant::core::make_geometry_file(grid, flat))
            .has_value());
    const int port = test_port(7);
    const std::string run = "cd '" + dir.string() + "' && '" + std::string(PLIANT_EXE) + "' ";
    ASSERT_EQ(std::system((run + "simulate flat.pgrid --scenario '" PLIANT_SOURCE_DIR
                                 "/scenes/pull.toml' -o out > simulate.log 2>&1; echo $? > "
                                 "simulate.rc")
                              .c_str()),
              0);
    ASSERT_EQ(std::system((run + "host flat.pgrid --duration 1 --port " + std::to_string(port) +
                           " > host.log 2>&1; echo $? > host.rc")
                              .c_str()),
              0);
    for (const std::string name : {"simulate", "host"})
    {
        if (name == "host")
            PLIANT_SKIP_IF_UNBOUND(dir, "host", port);
        const std::string log = read(dir / (name + ".log"));
        EXPECT_EQ(read(dir / (name + ".rc")), "1\n") << name << ": " << log;
        EXPECT_NE(log.find("error: flat.pgrid: the rest surface has no normal at node ("),
                  std::string::npos)
            << name << ": " << log;
        EXPECT_EQ(log.find("MembraneModel"), std::string::npos) << name << ": " << log;
    }
}

TEST(SessionCli, CtrlCStopsAReplayAndWritesNothing)
{
    const auto dir = pliant::test::scratch_dir("session_cli_replay_interrupted");
    const auto grid = pliant::core::TetraGrid::create(5).value();
    pliant::sim::MembraneSettings material;
    material.fixed_step = true;
    material.fixed_dt = 1e-3;
    auto model =
        pliant::sim::MembraneModel::create(grid, pliant::scenes::sphere_grid(grid, 1.0), material)
            .value();
    pliant::session::Recording rec;
    rec.model = pliant::session::encode_model(model, pliant::session::Coupling::Exact);
    rec.final_tick = 1'000'000;
    rec.forces.push_back(pliant::session::ForceRecord{
        0,
        0,
        {pliant::net::UserForce{
            pliant::net::Target{pliant::net::TargetKind::Face, 100, {0, 0, 0}, 0.0},
            0,
            {0.0, 0.0, 0.5}}}});
    ASSERT_TRUE(pliant::session::save_recording(dir / "long.prec", rec));
    const std::string cmd = "cd '" + dir.string() + "' && rm -f out.pgrid && sh '" +
                            PLIANT_INTERRUPT_SH + "' log '^replay: [0-9]+%' '" + PLIANT_EXE +
                            "' replay long.prec -o out.pgrid > replay.out 2> replay.err; " +
                            "echo $? > replay.rc";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const std::string err = read(dir / "replay.err");
    EXPECT_EQ(read(dir / "replay.rc"), "130\n") << err;
    // The message tells a stop that was heard from a process killed by the signal (also 130).
    EXPECT_NE(err.find("replay: cancelled during tick "), std::string::npos) << err;
    EXPECT_NE(err.find(" of 1000000; nothing written"), std::string::npos) << err;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.pgrid"));
}

// `pliant info RECORDING --json`: what a recording made here holds (its model's level and step,
// its length, the force lists per sender, the largest force, the final hash); a recording of an
// adaptive-step model, which replay refuses, is invalid with status 1.
TEST(SessionCli, InfoDescribesARecording)
{
    using namespace pliant;
    const auto dir = test::scratch_dir("session_cli_info_recording");
    const auto grid = core::TetraGrid::create(3).value();
    sim::MembraneSettings material;
    material.fixed_step = true;
    material.fixed_dt = 2e-3;
    auto model = sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), material).value();
    const auto force = [](std::uint32_t face, double fx, double fy)
    {
        return net::UserForce{
            net::Target{net::TargetKind::Face, face, {0, 0, 0}, 0.0}, 0, {fx, fy, 0.0}};
    };
    session::Recording rec;
    rec.model = session::encode_model(model, session::Coupling::Fast);
    rec.final_tick = 250;
    rec.final_hash = 0x1234;
    rec.forces.push_back(session::ForceRecord{1, 10, {force(5, 3.0, 4.0)}});
    rec.forces.push_back(session::ForceRecord{2, 20, {force(6, 1.0, 0.0), force(7, 0.0, 2.0)}});
    rec.forces.push_back(session::ForceRecord{2, 30, {}});
    ASSERT_TRUE(session::save_recording(dir / "r.prec", rec));
    const std::string run = "cd '" + dir.string() + "' && '" + std::string(PLIANT_EXE) + "' ";
    ASSERT_EQ(std::system((run + "info --json r.prec > r.json 2> r.err; echo $? > r.rc").c_str()),
              0);
    EXPECT_EQ(read(dir / "r.rc"), "0\n") << read(dir / "r.err");
    const auto j = nlohmann::json::parse(read(dir / "r.json"));
    EXPECT_TRUE(j["valid"].get<bool>());
    EXPECT_EQ(j["format"], "prec");
    EXPECT_EQ(j["level"].get<int>(), 3);
    EXPECT_EQ(j["vertices"].get<int>(), 130);
    EXPECT_EQ(j["coupling"], "fast");
    EXPECT_EQ(j["fixed_dt"].get<double>(), 2e-3);
    EXPECT_EQ(j["final_tick"].get<int>(), 250);
    EXPECT_DOUBLE_EQ(j["simulated_s"].get<double>(), 0.5);
    EXPECT_EQ(j["final_hash"], "0000000000001234");
    EXPECT_EQ(j["force_lists"].get<int>(), 3);
    EXPECT_EQ(j["senders"], nlohmann::json({{"1", 1}, {"2", 2}}));
    EXPECT_EQ(j["largest_force"].get<double>(), 5.0);
    EXPECT_EQ(j["hash_nodes"].get<int>(), 130);

    material.fixed_step = false;
    auto adaptive =
        sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), material).value();
    rec.model = session::encode_model(adaptive, session::Coupling::Exact);
    ASSERT_TRUE(session::save_recording(dir / "adaptive.prec", rec));
    ASSERT_EQ(std::system((run + "info adaptive.prec > a.out 2> a.err; echo $? > a.rc").c_str()),
              0);
    EXPECT_EQ(read(dir / "a.rc"), "1\n");
    EXPECT_NE(read(dir / "a.err")
                  .find("adaptive.prec: the session did not step with a fixed "
                        "step, so `replay` refuses it"),
              std::string::npos)
        << read(dir / "a.err");
    EXPECT_NE(read(dir / "a.out").find("level 3, 130 vertices; exact coupling"), std::string::npos)
        << read(dir / "a.out");
}

}  // namespace
