// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "support/test_paths.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

namespace pliant::test
{
namespace
{

// The scratch folders made since the current test began (tests may make them from threads).
std::mutex g_scratch_mutex;
std::vector<std::filesystem::path> g_scratch_dirs;

}  // namespace

std::filesystem::path source_dir()
{
    return std::filesystem::path(PLIANT_SOURCE_DIR);
}

std::optional<std::filesystem::path> shared_meshes_dir()
{
    if (const char* env = std::getenv("PLIANT_SHARED_MESHES"); env != nullptr && *env != '\0')
    {
        if (std::filesystem::is_directory(env))
            return std::filesystem::path(env);
        return std::nullopt;
    }
    const std::filesystem::path p = source_dir().parent_path() / "shared" / "meshes";
    std::error_code ec;
    if (std::filesystem::is_directory(p, ec))
        return p;
    return std::nullopt;
}

std::filesystem::path scratch_dir(const char* test_name)
{
    std::filesystem::path p = std::filesystem::temp_directory_path() /
                              ("pliant-test-" + std::to_string(::getpid()) + "-" + test_name);
    std::error_code ec;
    std::filesystem::remove_all(p, ec);
    std::filesystem::create_directories(p);
    const std::scoped_lock lock(g_scratch_mutex);
    g_scratch_dirs.push_back(p);
    return p;
}

void end_scratch_dirs(bool passed)
{
    std::vector<std::filesystem::path> dirs;
    {
        const std::scoped_lock lock(g_scratch_mutex);
        dirs.swap(g_scratch_dirs);
    }
    for (const std::filesystem::path& p : dirs)
    {
        if (passed)
        {
            std::error_code ec;
            std::filesystem::remove_all(p, ec);
        }
        else
            std::printf("[ scratch  ] kept %s\n", p.string().c_str());
    }
}

}  // namespace pliant::test
