// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The `--script` format of pliant host/join: commands parse into events sorted by time, and a
// malformed line is an error naming it.
#include <pliant/session/runner.h>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace pliant::session
