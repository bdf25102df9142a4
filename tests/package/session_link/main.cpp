// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Links the session module and the transports (ENet, the encrypted one) through the installed
// package; makes an ENet transport (not opened: no socket) and a simulated network.
#include <pliant/net/enet_transport.h>
#include <pliant/net/simulated_transport.h>
#include <pliant/session/session.h>

#include <cstdio>

int main()
{
    auto transport = pliant::net::make_enet_transport();
    pliant::net::SimulatedNetwork network;
    auto* host = &pliant::session::Session::host;
    if (transport == nullptr || host == nullptr)
        return 1;
    std::printf("session, sim, subdiv and net linked\n");
    return 0;
}
