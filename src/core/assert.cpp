// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/assert.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>

namespace pliant::core
{
namespace
{

void default_handler(const char* condition, const char* message, const char* file, int line)
{
    std::fprintf(stderr, "pliant: assertion failed: %s (%s) at %s:%d\n", message, condition, file,
                 line);
    std::fflush(stderr);
    std::abort();
}

std::atomic<AssertHandler> g_handler{&default_handler};

}  // namespace

AssertHandler set_assert_handler(AssertHandler handler) noexcept
{
    return g_handler.exchange(handler != nullptr ? handler : &default_handler);
}

void assert_failed(const char* condition, const char* message, const char* file, int line)
{
    g_handler.load()(condition, message, file, line);
    std::abort();  // a handler that returns still stops the program
}

}  // namespace pliant::core
