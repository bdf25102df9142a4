// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Transport's defaults: the idle wait, a sleep (transports with a socket wait on it instead),
// and queued bytes, unknown (0).

#include <pliant/net/transport.h>

#include <chrono>
#include <thread>

namespace pliant::net
{

bool Transport::poll_into(TransportEvent& out, int timeout_ms) noexcept
{
    auto ev = poll(timeout_ms);
    if (!ev)
        return false;
    out = std::move(*ev);
    return true;
}

void Transport::wait(double max_s) noexcept
{
    if (max_s > 0.0)
        std::this_thread::sleep_for(std::chrono::duration<double>(max_s));
}

std::vector<PeerHandle> Transport::peers() const
{
    std::vector<PeerHandle> out;
    live_peers(out);
    return out;
}

std::size_t Transport::queued_bytes(PeerHandle /*peer*/) const noexcept
{
    return 0;
}

}  // namespace pliant::net
