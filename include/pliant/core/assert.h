// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Contract checks (docs/style.md §5, kind 1). `PLIANT_ASSERT` is on unless
/// `PLIANT_DISABLE_ASSERT` is defined (the release preset keeps it on outside hot loops; kernels
/// use `PLIANT_DEBUG_ASSERT`, which is on only without NDEBUG: in the dev and asan presets, so
/// CI's sanitizer leg runs them). The handler can be replaced, e.g. by tests.

namespace pliant::core
{

/// Called on a failed assertion; must not return normally (the default prints and aborts).
using AssertHandler = void (*)(const char* condition, const char* message, const char* file,
                               int line);

/// Replaces the handler; returns the previous one. Not thread-safe: call at start-up.
AssertHandler set_assert_handler(AssertHandler handler) noexcept;

[[noreturn]] void assert_failed(const char* condition, const char* message, const char* file,
                                int line);

}  // namespace pliant::core

#if defined(PLIANT_DISABLE_ASSERT)
#define PLIANT_ASSERT(cond, msg) static_cast<void>(0)
#else
#define PLIANT_ASSERT(cond, msg)                                           \
    do                                                                     \
    {                                                                      \
        if (!(cond)) [[unlikely]]                                          \
            ::pliant::core::assert_failed(#cond, msg, __FILE__, __LINE__); \
    } while (false)
#endif

#if defined(NDEBUG)
#define PLIANT_DEBUG_ASSERT(cond, msg) static_cast<void>(0)
#else
#define PLIANT_DEBUG_ASSERT(cond, msg) PLIANT_ASSERT(cond, msg)
#endif
