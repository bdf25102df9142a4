// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The `--script` format of pliant host/join: commands parse into events sorted by time, and a
// malformed line is an error naming it. PaceWatch, run_peer's behind-real-time warning: when it
// speaks, how often, and which cause it names.
#include <pliant/session/runner.h>

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <utility>

namespace pliant::session
{
namespace
{

TEST(Script, ParsesGrabsPointsOfInterestAndLeaveSortedByTime)
{
    const auto events = parse_script(
        "# demo\n"
        "3.0 leave\n"
        "0.5 grab face 700 force 0 0 0.5 for 1.0   # pull\n"
        "\n"
        "1.0 grab point 0 0 1 radius 0.3 force 0 0 -0.4 for 0.5\n"
        "2 poi face 12\n");
    ASSERT_TRUE(events.has_value()) << events.error().message;
    ASSERT_EQ(events->size(), 4U);
    const auto& e = *events;
    EXPECT_EQ(e[0].kind, ScriptEvent::Kind::Grab);
    EXPECT_EQ(e[0].time, 0.5);
    EXPECT_EQ(e[0].force.target.kind, net::TargetKind::Face);
    EXPECT_EQ(e[0].force.target.face, 700U);
    EXPECT_EQ(e[0].force.force[2], 0.5);
    EXPECT_EQ(e[0].duration, 1.0);
    EXPECT_EQ(e[1].force.target.kind, net::TargetKind::Position);
    EXPECT_EQ(e[1].force.target.position[2], 1.0);
    EXPECT_EQ(e[1].force.target.radius, 0.3);
    EXPECT_EQ(e[1].force.force[2], -0.4);
    EXPECT_EQ(e[2].kind, ScriptEvent::Kind::Poi);
    EXPECT_EQ(e[2].force.target.face, 12U);
    EXPECT_EQ(e[3].kind, ScriptEvent::Kind::Leave);
    EXPECT_EQ(e[3].time, 3.0);
}

TEST(Script, MalformedLinesAreErrorsNamingTheLine)
{
    for (const char* bad :
         {"x grab face 1", "-1 leave", "1 jump", "1 grab face -3", "1 grab face 1.5",
          "1 grab point 0 0", "1 grab face 1 force 0 0", "1 grab face 1 for -2",
          "1 grab face 1 colour red", "1 poi face 1 for 2", "1 grab edge 3", "nan leave",
          "1 grab face 1 force 0 0 1", "1 grab face 1 force 0 0 1 for 0"})
    {
        const auto r = parse_script(std::string("0 leave\n") + bad + "\n", "grabs.txt");
        ASSERT_FALSE(r.has_value()) << bad;
        EXPECT_EQ(r.error().code, core::ErrorCode::ParseError);
        EXPECT_EQ(r.error().message.rfind("grabs.txt:2: ", 0), 0U) << r.error().message;
    }
}

// Each message says what was expected and what was found: a number that is not finite is told
// as that, not as a missing one; hexadecimal is not a time; 'leave' takes nothing after it.
TEST(Script, MessagesSayWhatWasExpectedAndWhatWasFound)
{
    const std::pair<const char*, const char*> cases[] = {
        {"0.5 grab face 1 force 0 0 1e400 for 1",
         "expected three force components after 'force', got '1e400' (not a finite number)"},
        {"0.5 grab face 1 force 0 nan 1 for 1",
         "expected three force components after 'force', got 'nan' (not a finite number)"},
        {"0.5 grab face 1 force 0 0 1 for inf",
         "expected a duration in seconds > 0 after 'for', got 'inf' (not a finite number)"},
        {"0.5 grab face 1 radius nan force 0 0 1 for 1",
         "expected a radius >= 0 after 'radius', got 'nan' (not a finite number)"},
        {"0x1 leave", "expected a time in seconds >= 0, got '0x1' (not a number)"},
        {"-1 leave", "expected a time in seconds >= 0, got '-1'"},
        {"0.5 leave now", "unexpected 'now' after 'leave' (it takes nothing)"},
        {"1 grab face 1.5 force 0 0 1 for 1",
         "expected a face index (a whole number from 0), got '1.5'"},
        {"1 grab point 0 0", "expected three coordinates after 'point', got nothing"},
    };
    for (const auto& [line, message] : cases)
    {
        const auto r = parse_script(std::string(line) + "\n", "s.txt");
        ASSERT_FALSE(r.has_value()) << line;
        EXPECT_EQ(r.error().message, std::string("s.txt:1: ") + message);
    }
    // A word that begins with a NUL byte is not time 0.
    const auto nul = parse_script(std::string("\0 leave\n", 8), "s.txt");
    ASSERT_FALSE(nul.has_value());
    EXPECT_EQ(nul.error().message,
              "s.txt:1: expected a time in seconds >= 0, got '?' (not a number)");
    // "+1" is a number, as in the scenario files.
    const auto plus = parse_script("+1 leave\n", "s.txt");
    ASSERT_TRUE(plus.has_value()) << plus.error().message;
    EXPECT_EQ(plus->front().time, 1.0);
}

// What needs the grid is checked once it is known: a face beyond it, and a viewer's grab, are
// errors naming the file and the line (a session would drop such a force without a word).
TEST(Script, FacesBeyondTheGridAndAViewersGrabsAreErrorsNamingTheLine)
{
    const auto events = parse_script(
        "0.5 poi face 12\n"
        "1 grab face 255 force 0 0 1 for 1\n"
        "2 grab face 256 force 0 0 1 for 1\n");
    ASSERT_TRUE(events.has_value()) << events.error().message;
    const auto beyond = check_script(*events, 256, SessionRole::Participant, "grabs.txt");
    ASSERT_FALSE(beyond.has_value());
    EXPECT_EQ(beyond.error().message.rfind("grabs.txt:3: face 256 is not on this grid", 0), 0U)
        << beyond.error().message;
    EXPECT_TRUE(check_script(*events, 257, SessionRole::Participant, "grabs.txt").has_value());
    const auto viewer = check_script(*events, 257, SessionRole::Viewer, "grabs.txt");
    ASSERT_FALSE(viewer.has_value());
    EXPECT_EQ(viewer.error().message.rfind("grabs.txt:2: a viewer cannot grab", 0), 0U)
        << viewer.error().message;
}

// Three slow seconds in a row, then a warning naming the pace and the steps per second; then
// silence for 30 s of samples; a second at real time starts the count over.
TEST(PaceWatch, WarnsAfterThreeSlowSecondsInARowThenKeepsQuietForThirty)
{
    PaceWatch watch;
    // Compute-bound: 0.25 s simulated per s, 250 steps of 3.6 ms (90 % of the time).
    const PaceSample slow{
        .wall_s = 1.0, .sim_s = 0.25, .step_s = 0.9, .steps = 250, .bytes_out = 1e6};
    const PaceSample on_time{
        .wall_s = 1.0, .sim_s = 1.0, .step_s = 0.5, .steps = 1000, .bytes_out = 1e6};
    EXPECT_FALSE(watch.add(slow));
    EXPECT_FALSE(watch.add(slow));
    EXPECT_FALSE(watch.add(on_time));  // the count starts over
    EXPECT_FALSE(watch.add(slow));
    EXPECT_FALSE(watch.add(slow));
    const auto w = watch.add(slow);
    ASSERT_TRUE(w.has_value());
    EXPECT_NE(w->find("0.25x real time (250 steps/s)"), std::string::npos) << *w;
    EXPECT_NE(w->find("its steps take 90 % of this peer's time (3.60 ms each)"), std::string::npos)
        << *w;
    EXPECT_NE(w->find("coarser level"), std::string::npos) << *w;
    for (int k = 0; k < 29; ++k)
        EXPECT_FALSE(watch.add(slow)) << "second " << k + 1 << " after the warning";
    EXPECT_TRUE(watch.add(slow).has_value());  // 30 s on, still slow: said again
    // Keeping up never warns.
    PaceWatch fine;
    for (int k = 0; k < 100; ++k)
        EXPECT_FALSE(fine.add(on_time));
}

// What a fresh PaceWatch says after k_slow_samples of `sample` in a row.
std::optional<std::string> warning_after_slow_run(const PaceSample& sample)
{
    PaceWatch watch;
    std::optional<std::string> said;
    for (int k = 0; k < PaceWatch::k_slow_samples; ++k)
        said = watch.add(sample);
    return said;
}

// The cause named: a peer whose steps take little of its time waits on the network; in exact
// coupling for the halos of every tick (with the bytes it sends and the options that cut them),
// in fast coupling for fresh neighbour states; and a machine whose load exceeds its cores.
TEST(PaceWatch, NamesTheWaitForTheNeighboursWhenTheStepsAreNotTheCause)
{
    const PaceSample waiting{
        .wall_s = 1.0, .sim_s = 0.4, .step_s = 0.2, .steps = 400, .bytes_out = 66.8e6};
    PaceSample waiting_fast = waiting;
    waiting_fast.coupling = Coupling::Fast;
    const std::optional<std::string> we = warning_after_slow_run(waiting);
    const std::optional<std::string> wf = warning_after_slow_run(waiting_fast);
    ASSERT_TRUE(we.has_value());
    ASSERT_TRUE(wf.has_value());
    EXPECT_NE(we->find("0.40x real time (400 steps/s)"), std::string::npos) << *we;
    EXPECT_NE(we->find("waits for them (its steps take 20 % of its time; it sends 66.8 MB/s)"),
              std::string::npos)
        << *we;
    EXPECT_NE(we->find("--compress or --f32"), std::string::npos) << *we;
    EXPECT_EQ(we->find("coarser level"), std::string::npos) << *we;
    EXPECT_NE(wf->find("--max-halo-age"), std::string::npos) << *wf;
    EXPECT_EQ(wf->find("--compress"), std::string::npos) << *wf;
    EXPECT_EQ(we->find("busy"), std::string::npos) << *we;  // load unknown: nothing said

    // A load above the cores is named; at or below them, not.
    PaceSample busy = waiting;
    busy.load_average = 5.2;
    busy.cores = 2;
    PaceSample calm = waiting;
    calm.load_average = 1.5;
    calm.cores = 2;
    const std::optional<std::string> wb = warning_after_slow_run(busy);
    const std::optional<std::string> wc = warning_after_slow_run(calm);
    ASSERT_TRUE(wb.has_value() && wc.has_value());
    EXPECT_NE(wb->find("; this machine is also busy (load average 5.2 on 2 cores)"),
              std::string::npos)
        << *wb;
    EXPECT_EQ(wc->find("busy"), std::string::npos) << *wc;
}

// A member that publishes no step at all (exact coupling, a wait of a second or more at one
// tick) is named as the cause, not the traffic; a sample over seconds of wall time (this process
// was stopped) restarts the count instead of warning.
TEST(PaceWatch, NamesAMemberThatStoppedSteppingAndIgnoresAStoppedProcess)
{
    PaceSample stuck{.wall_s = 1.0, .sim_s = 0.0, .step_s = 0.0, .steps = 0, .bytes_out = 2e3};
    stuck.barrier_wait_s = 2.5;
    stuck.barrier_peer = net::PeerId{7};
    const std::optional<std::string> w = warning_after_slow_run(stuck);
    ASSERT_TRUE(w.has_value());
    EXPECT_NE(w->find("it has waited 2.5 s at one tick for peer 7 to publish it"),
              std::string::npos)
        << *w;
    EXPECT_NE(w->find("publishes no step for 10 s, this session's --max-barrier-wait"),
              std::string::npos)
        << *w;
    EXPECT_EQ(w->find("--compress"), std::string::npos) << *w;
    // The session's own limit, not the default (it said "10 s by default" whatever it was).
    stuck.max_barrier_wait_s = 3.0;
    const std::optional<std::string> w3 = warning_after_slow_run(stuck);
    ASSERT_TRUE(w3.has_value());
    EXPECT_NE(w3->find("publishes no step for 3 s"), std::string::npos) << *w3;
    stuck.max_barrier_wait_s = 0.0;
    const std::optional<std::string> w0 = warning_after_slow_run(stuck);
    ASSERT_TRUE(w0.has_value());
    EXPECT_NE(w0->find("--max-barrier-wait 0 never removes it"), std::string::npos) << *w0;

    PaceWatch watch;
    const PaceSample slow{
        .wall_s = 1.0, .sim_s = 0.25, .step_s = 0.9, .steps = 250, .bytes_out = 1e6};
    const PaceSample stopped{.wall_s = 3.5, .sim_s = 0.0, .step_s = 0.0, .steps = 0};
    EXPECT_FALSE(watch.add(slow));
    EXPECT_FALSE(watch.add(slow));
    EXPECT_FALSE(watch.add(stopped));  // not a third slow second: the count starts over
    EXPECT_FALSE(watch.add(slow));
    EXPECT_FALSE(watch.add(slow));
    EXPECT_TRUE(watch.add(slow).has_value());
}

}  // namespace
}  // namespace pliant::session
