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

/// A fresh empty folder under the build's temporary area for one test's output files.
std::filesystem::path scratch_dir(const char* test_name);

}  // namespace pliant::test
