// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The viewer's background load (apps/pliant-cli/viewer/mesh_loader.h): a remeshing in progress
// can be cancelled, and ends with ErrorCode::Cancelled and no surface; destroying the job mid-way
// cancels it rather than waiting for the remeshing (quitting the viewer during a load). Fox at
// level 7 untangles for many seconds, so the cancel lands while the work runs; every wait is
// bounded. A load that runs out of memory ends with an error, not the process.
#include <pliant/core/error.h>

#include <gtest/gtest.h>

#include "../../apps/pliant-cli/viewer/mesh_loader.h"
#include "support/address_space.h"
#include "support/fp_traps.h"
#include "support/test_paths.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

namespace pliant::viewer
{
namespace
{

using Clock = std::chrono::steady_clock;

std::filesystem::path fox()
{
    return test::source_dir() / "tests" / "data" / "meshes" / "fox.ply";
}

/// Waits until `ready()` or `limit` has passed; whether it became ready.
template <class Ready>
bool wait_for(Ready ready, std::chrono::seconds limit)
{
    const auto end = Clock::now() + limit;
    while (!ready())
    {
        if (Clock::now() > end)
            return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
}

TEST(ViewerLoad, CancellingARemeshingEndsItWithNoSurface)
{
    const test::FpTrapsOff off;  // Assimp computes with inf/NaN internally (on the worker too)
    LoadJob job(fox(), 7);
    // Cancel once the untangling, the long phase, has begun.
    ASSERT_TRUE(wait_for([&] { return job.done() || job.progress().first == "untangle"; },
                         std::chrono::seconds(300)))
        << "no untangle phase after 300 s; last phase " << job.progress().first;
    ASSERT_FALSE(job.done()) << "the remeshing ended before it could be cancelled";
    const auto asked = Clock::now();
    job.cancel();
    EXPECT_TRUE(job.cancelling());
    ASSERT_TRUE(wait_for([&] { return job.done(); }, std::chrono::seconds(60)));
    const double seconds = std::chrono::duration<double>(Clock::now() - asked).count();
    std::printf("fox level 7: cancelled during %s, done %.3f s after the request\n",
                job.progress().first.c_str(), seconds);
    auto result = job.take();
    ASSERT_FALSE(result);
    EXPECT_EQ(result.error().code, core::ErrorCode::Cancelled) << result.error().message;
    EXPECT_NE(result.error().message.find("untangle"), std::string::npos) << result.error().message;
}

TEST(ViewerLoad, DestroyingAJobMidwayCancelsIt)
{
    const test::FpTrapsOff off;
    bool started = false;
    {
        LoadJob job(fox(), 7);
        started =
            wait_for([&] { return job.progress().first != "starting"; }, std::chrono::seconds(60));
    }  // ~LoadJob cancels and joins: with no cancel it would wait for the whole remeshing
    EXPECT_TRUE(started);
}

// A load that runs out of memory is an error of the load (shown in the viewer's window), not an
// exception leaving the worker thread, which ended the viewer (std::terminate). In a child
// process whose address space is limited to 96 MiB above what it holds: spot remeshed at level
// 10 needs far more.
TEST(ViewerLoad, RunningOutOfMemoryIsAnErrorOfTheLoad)
{
#if defined(PLIANT_TEST_ASAN)
    GTEST_SKIP() << "AddressSanitizer's shadow memory needs more address space than any limit";
#else
    const test::ThreadsafeDeathTests threadsafe;
    const auto child = []
    {
        const test::FpTrapsOff off;
        if (!test::limit_address_space(96u << 20))
            std::_Exit(3);
        LoadJob job(test::source_dir() / "data" / "spot.obj", 10);
        if (!wait_for([&] { return job.done(); }, std::chrono::seconds(120)))
            std::_Exit(4);
        auto result = job.take();
        if (result)
            std::_Exit(5);
        std::fprintf(stderr, "%s\n", result.error().message.c_str());
        std::_Exit(result.error().message.find("out of memory") != std::string::npos ? 0 : 6);
    };
    EXPECT_EXIT(child(), ::testing::ExitedWithCode(0), "spot.obj: out of memory while loading it");
#endif
}

}  // namespace
}  // namespace pliant::viewer
