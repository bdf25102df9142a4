// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

#include <filesystem>
#include <optional>

namespace pliant::test
{

/// The project's source folder (for data/ and scenes/).
std::filesystem::path source_dir();

/// ../shared/meshes next to the project, or $PLIANT_SHARED_MESHES; nullopt when absent (users'
/// clones and CI without it): tests that need it skip with a printed reason.
std::optional<std::filesystem::path> shared_meshes_dir();

/// A fresh empty folder under the system's temporary folder for one test's output files. It is
/// removed when the test that made it passes and kept (its path printed) when the test fails, so
/// repeated runs leave nothing behind and a failure can be looked at (test_main.cpp).
std::filesystem::path scratch_dir(const char* test_name);

/// Ends the current test's scratch folders: removes them when `passed`, else prints where they
/// stay. Called by the test main after each test.
void end_scratch_dirs(bool passed);

}  // namespace pliant::test
