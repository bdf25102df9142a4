// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Transport's default idle wait: a sleep (transports with a socket wait on it instead).

#include <pliant/net/transport.h>

#include <chrono>
#include <thread>

namespace pliant::net
{

void Transport::wait(double max_s) noexcept
{
    if (max_s > 0.0)
        std::this_thread::sleep_for(std::chrono::duration<double>(max_s));
}

}  // namespace pliant::net
