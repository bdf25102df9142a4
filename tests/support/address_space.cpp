// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "support/address_space.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>

namespace pliant::test
{

std::size_t address_space_bytes()
{
    std::FILE* f = std::fopen("/proc/self/statm", "r");
    if (f == nullptr)
        return 0;
    unsigned long pages = 0;
    const int n = std::fscanf(f, "%lu", &pages);
    std::fclose(f);
    return n == 1 ? pages * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE)) : 0;
}

bool limit_address_space(std::size_t margin)
{
    const std::size_t held = address_space_bytes();
    if (held == 0)
        return false;
    const ::rlimit limit{held + margin, held + margin};
    return ::setrlimit(RLIMIT_AS, &limit) == 0;
}

}  // namespace pliant::test
