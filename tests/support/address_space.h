// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Running out of memory on purpose, in a death test's child: limit the process's address space
// to what it holds now plus a margin, so the next large allocation throws std::bad_alloc.
// AddressSanitizer's shadow memory needs more address space than any such limit: tests that
// use this skip under it (PLIANT_TEST_ASAN).
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <string>

#if defined(__SANITIZE_ADDRESS__)
#define PLIANT_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PLIANT_TEST_ASAN 1
#endif
#endif

namespace pliant::test
{

/// This process's address space in bytes (/proc/self/statm's first field, in pages); 0 if it
/// cannot be read.
[[nodiscard]] std::size_t address_space_bytes();

/// Sets RLIMIT_AS to address_space_bytes() + `margin`; whether it could.
[[nodiscard]] bool limit_address_space(std::size_t margin);

/// GoogleTest's "threadsafe" death tests for a scope (the child runs the test from the start,
/// as a process with threads needs); the style before is restored for the tests after.
class ThreadsafeDeathTests
{
public:
    ThreadsafeDeathTests() { GTEST_FLAG_SET(death_test_style, "threadsafe"); }
    ~ThreadsafeDeathTests() { GTEST_FLAG_SET(death_test_style, style_); }
    ThreadsafeDeathTests(const ThreadsafeDeathTests&) = delete;
    ThreadsafeDeathTests& operator=(const ThreadsafeDeathTests&) = delete;

private:
    std::string style_ = GTEST_FLAG_GET(death_test_style);
};

}  // namespace pliant::test
