// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A session of real ENet peers on 127.0.0.1, every datagram through one impairing relay
// (impair_relay.h): a master, participants and a viewer, for the impaired test
// (impaired_enet_test.cpp) and the join benchmark (pliant_bench_session --join).
//
// Each peer's transport binds its own port; the relay listens on another port per peer and
// forwards to it NAT-style. A peer announces its relay port (SessionSettings::listen_port), and
// the master records a joiner as the connection's source IP plus the announced port, so later
// joiners dial each other through the relay too: every datagram of the full mesh is impaired.

#include <pliant/core/tetra_grid.h>
#include <pliant/net/enet_transport.h>
#include <pliant/session/session.h>

#include "impair_relay.h"

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace pliant::test
{

struct RelaySession
{
    /// The relay's settings and the transports', before start(). The transports' connection
    /// rate limits are turned off by start(): every peer reaches the others from 127.0.0.1,
    /// which ENet's limit per source address, meant for one address per peer, would count
    /// together.
    ImpairSettings impair;
    net::EnetSettings enet;
    std::size_t participants = 2;  ///< besides the master; one viewer joins after them

    std::vector<std::unique_ptr<net::Transport>> transports;  ///< peer k's, k = 0 the master
    std::unique_ptr<ImpairRelay> relay;
    std::vector<std::unique_ptr<session::Session>> peers;  ///< master, participants, viewer
    std::string error;  ///< why start() failed: a socket that did not bind

    /// Opens the transports and the relay, hosts on `grid` (a unit sphere, `material`, fast
    /// coupling) and joins the participants, participant k declaring face k·F/3 (F the grid's
    /// faces), then the viewer. \return false (see `error`) if a UDP socket did not bind.
    bool start(const core::TetraGrid& grid, const sim::MembraneSettings& material);

    /// The peers that simulate: the master and the participants.
    [[nodiscard]] std::size_t simulating() const { return participants + 1; }
    /// Every peer holds the model and the master's newest partition, in which every participant
    /// owns leaves.
    [[nodiscard]] bool partitioned() const;
    /// The full mesh is up: every peer is connected to every other and receives every
    /// simulating peer's leaf states.
    [[nodiscard]] bool meshed() const;
};

}  // namespace pliant::test
