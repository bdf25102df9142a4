// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Stopping a remeshing (core::ProgressSink::stop_requested): in every phase the work ends at
// its next progress report with ErrorCode::Cancelled and no result, and untangling stopped
// midway leaves its inputs as they were, bit for bit. The untangling reports its progress as
// it goes (fractions inside (0, 1), never falling), so a long one does not sit at 0 %.

#include <pliant/core/field.h>
#include <pliant/core/progress.h>
#include <pliant/mesh/io.h>
#include <pliant/remesh/remesh.h>
#include <pliant/remesh/sample.h>
#include <pliant/remesh/sphere_map.h>
#include <pliant/remesh/untangle.h>

#include <gtest/gtest.h>

#include "support/fp_traps.h"
#include "support/test_paths.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pliant::remesh
{
namespace
{

mesh::TriMesh load_fox()
{
    const test::FpTrapsOff off;  // Assimp computes with inf/NaN internally
    auto r = mesh::import_mesh(test::source_dir() / "tests" / "data" / "meshes" / "fox.ply");
    EXPECT_TRUE(r) << (r ? "" : r.error().message);
    return r ? *r : mesh::TriMesh{};
}

/// Records every report; from the first report of phase `stop_at` (and the `skip` reports of
/// that phase before it) on, asks the work to stop and counts the reports that still come.
class Recorder final : public core::ProgressSink
{
public:
    explicit Recorder(std::string stop_at = {}, int skip = 0)
        : stop_at_(std::move(stop_at)), skip_(skip)
    {
    }
    void update(std::string_view phase, double fraction) noexcept override
    {
        if (stopping_)
            ++after_stop;
        reports.emplace_back(std::string(phase), fraction);
        if (!stop_at_.empty() && phase == stop_at_ && skip_-- <= 0)
            stopping_ = true;
    }
    [[nodiscard]] bool stop_requested() const noexcept override { return stopping_; }
    [[nodiscard]] bool stopping() const noexcept { return stopping_; }

    std::vector<std::pair<std::string, double>> reports;
    int after_stop = 0;

private:
    std::string stop_at_;
    int skip_;
    bool stopping_ = false;
};

RemeshSettings level(int n)
{
    RemeshSettings s;
    s.level = n;
    return s;
}

// Fox at level 5 runs every phase: its spring embedding folds, so the coarse-to-fine map
// (simplify, sphere map, sphere optimise) follows; its samples fold, so untangling sweeps; then
// the measure.
TEST(RemeshCancel, EveryPhaseStopsAtItsNextReportWithNoResult)
{
    const mesh::TriMesh fox = load_fox();
    Recorder all;
    auto full = remesh(fox, level(5), &all);
    ASSERT_TRUE(full) << full.error().message;
    std::vector<std::string> phases;
    for (const auto& [phase, fraction] : all.reports)
        if (phases.empty() || phases.back() != phase)
            phases.push_back(phase);
    for (const char* expected :
         {"spring embedder", "simplify", "sphere map", "sphere optimise", "untangle", "measure"})
        EXPECT_NE(std::find(phases.begin(), phases.end(), expected), phases.end())
            << "phase " << expected << " not reported";

    for (const std::string& phase : phases)
    {
        Recorder stop(phase);
        auto r = remesh(fox, level(5), &stop);
        ASSERT_TRUE(stop.stopping()) << phase;
        ASSERT_FALSE(r) << "stopped at " << phase << " but a result came back";
        EXPECT_EQ(r.error().code, core::ErrorCode::Cancelled) << r.error().message;
        EXPECT_NE(r.error().message.find("cancelled during"), std::string::npos)
            << r.error().message;
        // The report that asked to stop may be a phase's last (1.0): the next phase's first
        // report can follow before its first check.
        EXPECT_LE(stop.after_stop, 1) << "stopped at " << phase << ": " << r.error().message;
        EXPECT_LT(stop.reports.size(), all.reports.size()) << phase;
    }
}

TEST(RemeshCancel, StoppedUntanglingLeavesItsInputsUntouched)
{
    const mesh::TriMesh m = split_for_map(load_fox(), RemeshSettings{}.min_map_faces);
    auto map = map_to_sphere(m);
    ASSERT_TRUE(map) << map.error().message;
    const auto grid = *core::TetraGrid::create(5);
    const auto domain = core::sphere_domain(grid, core::SphereMap::EqualArea);
    auto sampled = sample_surface(grid, domain, m, map->points);
    ASSERT_TRUE(sampled);

    // Uninterrupted: the untangling moves nodes and reports inside (0, 1), never falling.
    {
        core::Vec3Field<double> points = domain;
        core::Vec3Field<double> positions = *sampled;
        Recorder progress;
        auto st = untangle_samples(grid, m, map->points, points, positions, {}, &progress);
        ASSERT_TRUE(st) << st.error().message;
        ASSERT_GT(st->moved_nodes, 0U);
        ASSERT_GE(progress.reports.size(), 3U);
        double last = 0.0;
        for (const auto& [phase, fraction] : progress.reports)
        {
            EXPECT_EQ(phase, "untangle");
            EXPECT_GE(fraction, last);
            EXPECT_LT(fraction, 1.0);
            last = fraction;
        }
        EXPECT_GT(last, 0.0);
    }
    // Stopped at its third report: Cancelled, and points and positions as they came in.
    core::Vec3Field<double> points = domain;
    core::Vec3Field<double> positions = *sampled;
    Recorder stop("untangle", 2);
    auto st = untangle_samples(grid, m, map->points, points, positions, {}, &stop);
    ASSERT_FALSE(st);
    EXPECT_EQ(st.error().code, core::ErrorCode::Cancelled);
    EXPECT_EQ(stop.after_stop, 0);
    for (std::size_t k = 0; k < 3; ++k)
        for (std::size_t i = 0; i < points[k].padded().size(); ++i)
        {
            ASSERT_EQ(points[k].padded()[i], domain[k].padded()[i]) << "plane " << k;
            ASSERT_EQ(positions[k].padded()[i], (*sampled)[k].padded()[i]) << "plane " << k;
        }
}

// The patch passes halve epsilon from start to end: settings it could never reach (an end of
// 0, a start below the end or not finite) are refused at once, with the inputs untouched; an
// end of 0 looped for ever (clang-tidy's FloatLoopCounter found it).
TEST(RemeshCancel, UnreachablePatchEpsilonsAreRefusedNotLoopedOn)
{
    const mesh::TriMesh m = split_for_map(load_fox(), RemeshSettings{}.min_map_faces);
    auto map = map_to_sphere(m);
    ASSERT_TRUE(map) << map.error().message;
    const auto grid = *core::TetraGrid::create(4);
    const auto domain = core::sphere_domain(grid, core::SphereMap::EqualArea);
    auto sampled = sample_surface(grid, domain, m, map->points);
    ASSERT_TRUE(sampled);
    const double inf = std::numeric_limits<double>::infinity();
    const std::vector<std::pair<double, double>> bad{
        {0.02, 0.0}, {0.02, -1.0}, {0.001, 0.002}, {inf, 0.0005}, {0.02, std::nan("")}};
    for (const auto& [start, end] : bad)
    {
        UntangleSettings s;
        s.patch_epsilon_start = start;
        s.patch_epsilon_end = end;
        s.enabled = false;  // the loop ran before this was looked at
        core::Vec3Field<double> points = domain;
        core::Vec3Field<double> positions = *sampled;
        auto st = untangle_samples(grid, m, map->points, points, positions, s);
        ASSERT_FALSE(st) << start << " .. " << end;
        EXPECT_EQ(st.error().code, core::ErrorCode::InvalidArgument);
        EXPECT_NE(st.error().message.find("patch_epsilon_end"), std::string::npos);
        EXPECT_EQ(points[0].padded()[0], domain[0].padded()[0]);
    }
    // Through remesh(): the same refusal.
    RemeshSettings rs;
    rs.level = 4;
    rs.untangle.patch_epsilon_end = 0.0;
    auto r = remesh(m, rs);
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error().code, core::ErrorCode::InvalidArgument);
    // Equal start and end: one epsilon, accepted.
    UntangleSettings one;
    one.patch_epsilon_end = one.patch_epsilon_start;
    core::Vec3Field<double> points = domain;
    core::Vec3Field<double> positions = *sampled;
    EXPECT_TRUE(untangle_samples(grid, m, map->points, points, positions, one));
}

}  // namespace
}  // namespace pliant::remesh
