// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Counts every allocation through operator new, on every thread, in a test executable that links
// allocation_counter.cpp (which replaces the global operator new): the "no allocation per step /
// per call" contracts are checked by the count around a loop.

#include <cstdint>

namespace pliant::test
{

/// Allocations through any form of operator new since the program started (all threads).
[[nodiscard]] std::uint64_t allocations() noexcept;

}  // namespace pliant::test
