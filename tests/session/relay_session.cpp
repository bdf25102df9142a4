// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "relay_session.h"

#include "grid_shapes.h"

#include <algorithm>
#include <cstdint>

namespace pliant::test
{

bool RelaySession::start(const core::TetraGrid& grid, const sim::MembraneSettings& material)
{
    enet.connect_rate_per_source = 0.0;
    enet.connect_rate_total = 0.0;
    relay = std::make_unique<ImpairRelay>(impair);
    std::vector<std::uint16_t> relay_port;
    for (std::size_t k = 0; k <= simulating(); ++k)
    {
        transports.push_back(net::make_enet_transport(enet));
        const auto a = transports.back()->open(net::Address{{127, 0, 0, 1}, 0});
        if (!a)
        {
            error = a.error().message;
            return false;
        }
        relay_port.push_back(relay->add_target(a->port));
        if (relay_port.back() == 0)
        {
            error = relay->error();
            return false;
        }
    }
    if (!relay->start())
    {
        error = "the relay did not start";
        return false;
    }
    const auto faces = static_cast<std::uint32_t>(grid.face_count());
    session::SessionSettings set;
    set.coupling = session::Coupling::Fast;
    set.name = "master";
    set.listen_port = relay_port[0];
    peers.push_back(
        session::Session::host(*transports[0], grid, scenes::sphere_grid(grid, 1.0), material, set)
            .value());
    const net::Address master{{127, 0, 0, 1}, relay_port[0]};
    for (std::size_t k = 1; k <= simulating(); ++k)
    {
        const bool viewer = k == simulating();
        set.name = viewer ? "viewer" : "part";
        set.listen_port = relay_port[k];
        peers.push_back(session::Session::join(*transports[k], master,
                                               viewer ? net::Role::Viewer : net::Role::Participant,
                                               set)
                            .value());
        if (!viewer)
            peers.back()->set_points_of_interest(
                {net::Target{net::TargetKind::Face,
                             static_cast<std::uint32_t>(k) * faces / 3U,
                             {0, 0, 0},
                             0.0}});
    }
    return true;
}

bool RelaySession::partitioned() const
{
    const auto owners = peers[0]->owners();
    for (std::size_t k = 1; k < peers.size(); ++k)
    {
        if (!peers[k]->ready() || peers[k]->epoch() != peers[0]->epoch())
            return false;
        if (k < simulating() &&
            std::find(owners.begin(), owners.end(), peers[k]->id()) == owners.end())
            return false;
    }
    return true;
}

bool RelaySession::meshed() const
{
    for (std::size_t k = 0; k < peers.size(); ++k)
        for (std::size_t j = 0; j < peers.size(); ++j)
        {
            if (j == k)
                continue;
            bool ok = false;
            for (const session::PeerStatus& o : peers[k]->peer_status())
                if (o.id == peers[j]->id())
                    ok = o.connected && (j >= simulating() || o.streams_to_us);
            if (!ok)
                return false;
        }
    return true;
}

}  // namespace pliant::test
