// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant info --json` as a user runs it: the built executable on a valid and on invalid meshes,
// checking the exit code and the JSON fields (stdout must be exactly one JSON object, which also
// proves Assimp printed nothing there); and on .pgrid grid files written here with known values.

#include <pliant/core/grid_io.h>
#include <pliant/core/tetra_grid.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include "grid_shapes.h"
#include "support/test_paths.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>

namespace
{

struct CliRun
{
    int exit_code = -1;
    std::string out;
};

CliRun run_info(const std::filesystem::path& mesh)
{
    const std::string cmd =
        std::string("'") + PLIANT_EXE + "' info --json '" + mesh.string() + "' 2>/dev/null";
    CliRun r;
    FILE* pipe = popen(cmd.c_str(), "r");
    if (pipe == nullptr)
        return r;
    std::array<char, 4096> buf{};
    std::size_t n = 0;
    while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0)
        r.out.append(buf.data(), n);
    const int status = pclose(pipe);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

std::filesystem::path mesh(const char* name)
{
    return pliant::test::source_dir() / "tests" / "data" / "meshes" / name;
}

TEST(CliInfo, ValidMeshExitsZeroWithItsCounts)
{
    const CliRun r = run_info(mesh("spot_triangulated.obj"));
    EXPECT_EQ(r.exit_code, 0);
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_TRUE(j["valid"].get<bool>());
    EXPECT_TRUE(j["error_code"].is_null());
    EXPECT_EQ(j["vertices"].get<int>(), 2930);
    EXPECT_EQ(j["faces"].get<int>(), 5856);
    EXPECT_EQ(j["genus"].get<int>(), 0);
    EXPECT_EQ(j["euler_characteristic"].get<int>(), 2);
    EXPECT_NEAR(j["bbox_diagonal"].get<double>(), 2.588, 1e-3);  // README table
}

TEST(CliInfo, InvalidMeshesExitNonZeroWithTheirRule)
{
    const std::pair<const char*, const char*> cases[] = {
        {"negative/bob_small_genus1.ply", "wrong-genus"},
        {"negative/stanford-bunny_open.obj", "open-boundary"},
        {"negative/hourglass_ico_nonmanifold_vertex.obj", "non-manifold-vertex"},
        {"negative/two_cubes_shared_edge_nonmanifold_edge.obj", "non-manifold-edge"},
        {"does-not-exist.obj", "io-error"},
    };
    for (const auto& [file, code] : cases)
    {
        const CliRun r = run_info(mesh(file));
        EXPECT_NE(r.exit_code, 0) << file;
        const auto j = nlohmann::json::parse(r.out);
        EXPECT_FALSE(j["valid"].get<bool>()) << file;
        EXPECT_EQ(j["error_code"].get<std::string>(), code) << file;
        EXPECT_FALSE(j["message"].get<std::string>().empty());
    }
    const auto genus = nlohmann::json::parse(run_info(mesh("negative/bob_small_genus1.ply")).out);
    EXPECT_EQ(genus["genus"].get<int>(), 1);
    EXPECT_NE(genus["message"].get<std::string>().find("genus 1"), std::string::npos);
}

// A level-3 sphere with u = 0.1 z (equal at twins, as every field of a file must be), v = -3 at
// one inner node and 0.5 elsewhere, and an owner per hemisphere: the ranges, where the largest
// values lie and the owner counts are what the file holds, computed here from the same nodes.
TEST(CliInfo, AGridFileIsDescribedWithItsChannelsRangesAndOwners)
{
    using namespace pliant;
    const auto dir = test::scratch_dir("cli_info_grid");
    const auto grid = core::TetraGrid::create(3).value();
    const core::Vec3Field<double> sphere = scenes::sphere_grid(grid, 1.0);
    core::GridFile file = core::make_geometry_file(grid, sphere);
    core::Field<double> u(grid);
    core::Field<double> v(grid);
    core::Field<double> owner(grid);
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            const double z = sphere[2].at(x, y);
            u.at(x, y) = 0.1 * z;
            v.at(x, y) = x == 5 && y == 3 ? -3.0 : 0.5;
            owner.at(x, y) = z > 0.0 ? 1.0 : 2.0;
        }
    double u_min = 1e300;
    double u_max = -1e300;
    std::map<std::string, int> owners;
    for (const core::NodeIndex n : grid.node_of_unique())
    {
        u_min = std::min(u_min, u[n]);
        u_max = std::max(u_max, u[n]);
        ++owners[owner[n] == 1.0 ? "1" : "2"];
    }
    file.fields.push_back({"u", u});
    file.fields.push_back({"v", v});
    file.fields.push_back({"owner", owner});
    ASSERT_TRUE(core::save_grid(dir / "state.pgrid", file).has_value());

    const CliRun r = run_info(dir / "state.pgrid");
    EXPECT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_TRUE(j["valid"].get<bool>());
    EXPECT_EQ(j["format"], "pgrid");
    EXPECT_EQ(j["level"].get<int>(), 3);
    EXPECT_EQ(j["vertices"].get<int>(), 2 * 8 * 8 + 2);
    EXPECT_EQ(j["faces"].get<int>(), 4 * 8 * 8);
    EXPECT_EQ(j["channels"], nlohmann::json({"px", "py", "pz", "u", "v", "owner"}));
    EXPECT_EQ(j["ranges"]["u"]["min"].get<double>(), u_min);
    EXPECT_EQ(j["ranges"]["u"]["max"].get<double>(), u_max);
    EXPECT_EQ(j["ranges"]["v"]["min"].get<double>(), -3.0);
    EXPECT_EQ(j["ranges"]["v"]["max"].get<double>(), 0.5);
    EXPECT_EQ(j["ranges"]["v"]["max_abs"].get<double>(), 3.0);
    EXPECT_EQ(j["ranges"]["v"]["at"], nlohmann::json({5, 3}));
    EXPECT_FALSE(j.contains("ranges") && j["ranges"].contains("owner"));
    EXPECT_EQ(j["owners"]["1"].get<int>(), owners["1"]);
    EXPECT_EQ(j["owners"]["2"].get<int>(), owners["2"]);
    EXPECT_EQ(owners["1"] + owners["2"], 130);
    // An inscribed polyhedron of the unit sphere: a little less area than 4 pi, a bounding box
    // within the cube of side 2.
    const double area = j["surface_area"].get<double>();
    EXPECT_LT(area, 4.0 * std::numbers::pi);
    EXPECT_GT(area, 0.9 * 4.0 * std::numbers::pi);
    EXPECT_LE(j["bbox_diagonal"].get<double>(), 2.0 * std::sqrt(3.0));
    // A state (u and v) is valid as a state: GRID arguments refuse it, --resume takes it.
    EXPECT_NE(j["message"].get<std::string>().find("valid: a simulated state (u, v)"),
              std::string::npos)
        << j["message"];
    // The same surface without u and v is a rest geometry.
    core::GridFile rest = core::make_geometry_file(grid, sphere);
    ASSERT_TRUE(core::save_grid(dir / "rest.pgrid", rest).has_value());
    const CliRun rr = run_info(dir / "rest.pgrid");
    EXPECT_EQ(rr.exit_code, 0) << rr.out;
    EXPECT_EQ(nlohmann::json::parse(rr.out)["message"],
              "valid: a closed surface the membrane accepts as rest geometry");
}

// A grid file whose positions are all equal decodes, but the membrane has no surface to work
// on: status 1, the node named.
TEST(CliInfo, AGridFileWithoutASurfaceIsInvalid)
{
    using namespace pliant;
    const auto dir = test::scratch_dir("cli_info_flat_grid");
    const auto grid = core::TetraGrid::create(3).value();
    core::Vec3Field<double> flat;
    for (auto& plane : flat)
        plane = core::Field<double>(grid);
    ASSERT_TRUE(
        core::save_grid(dir / "flat.pgrid", core::make_geometry_file(grid, flat)).has_value());
    const CliRun r = run_info(dir / "flat.pgrid");
    EXPECT_EQ(r.exit_code, 1) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_FALSE(j["valid"].get<bool>());
    EXPECT_EQ(j["error_code"], "degenerate-face");
    EXPECT_NE(j["message"].get<std::string>().find(
                  "flat.pgrid: the rest surface has no normal at node ("),
              std::string::npos)
        << j["message"];
    EXPECT_EQ(j["degenerate_faces"].get<int>(), 256);
}

}  // namespace
