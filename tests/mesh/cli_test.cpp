// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant info --json` as a user runs it: the built executable on a valid and on invalid meshes,
// checking the exit code and the JSON fields (stdout must be exactly one JSON object, which also
// proves Assimp printed nothing there).

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include "support/test_paths.h"

#include <array>
#include <cstdio>
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

}  // namespace
