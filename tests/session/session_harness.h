// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Shared by the session tests: a sphere model, a single-process reference run with a force
// schedule, and a harness pumping several Session peers in one thread over a SimulatedNetwork.

#include <pliant/net/simulated_transport.h>
#include <pliant/session/session.h>
#include <pliant/sim/rkf45.h>

#include "grid_shapes.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace pliant::session::test
{

inline sim::MembraneSettings material()
{
    sim::MembraneSettings m;
    m.T = 1.0;
    m.rho = 1.0;
    m.beta = 0.5;
    m.k_f = 1.0;
    m.fixed_step = true;
    m.fixed_dt = 1e-3;
    m.threads = 1;
    return m;
}

/// A scheduled force list of one sender: applies from `from` (tick) on.
struct Scheduled
{
    std::uint16_t sender = 0;
    std::uint64_t from = 0;
    std::vector<net::UserForce> forces;
};

inline net::UserForce face_pull(std::uint32_t face, double fz)
{
    net::UserForce f;
    f.target.kind = net::TargetKind::Face;
    f.target.face = face;
    f.force = {0.3 * fz, 0.2 * fz, fz};
    return f;
}

inline net::UserForce point_push(double x, double y, double z, double r, double f)
{
    net::UserForce u;
    u.target.kind = net::TargetKind::Position;
    u.target.position = {x, y, z};
    u.target.radius = r;
    u.force = {-f * x, -f * y, -f * z};
    return u;
}

/// Participant k's continuous drag at time t [s] (k = 0..2): 0.5 N turning at 1 Hz on the nodes
/// within 0.3 m of its point (bench_session --stream's "strong" drag).
inline net::UserForce turning_drag(int k, double t)
{
    constexpr double pi = 3.141592653589793;
    static constexpr double points[3][3] = {{0.0, 0.0, 1.0}, {0.0, 0.0, -1.0}, {1.0, 0.0, 0.0}};
    net::UserForce f;
    f.target.kind = net::TargetKind::Position;
    f.target.position = {points[k][0], points[k][1], points[k][2]};
    f.target.radius = 0.3;
    const double a = 2.0 * pi * t + k;
    f.force = {0.5 * std::cos(a), 0.5 * std::sin(a), -0.3 * (points[k][2] + points[k][0])};
    return f;
}

/// The obvious single-process run: forces of tick t are each sender's newest list with
/// from <= t, concatenated by increasing sender id; from rest, or from `start`; forces longer
/// than `max_force` (N, 0: no limit) act at that length.
inline sim::MembraneState reference_run(int level, std::uint64_t ticks,
                                        const std::vector<Scheduled>& schedule,
                                        const sim::MembraneState* start = nullptr,
                                        double max_force = 0.0)
{
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    sim::MembraneSettings m = material();
    m.max_force = max_force;
    auto model = sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), m).value();
    sim::MembraneState state = start != nullptr ? *start : sim::MembraneState::at_rest(grid);
    sim::Rkf45Workspace ws(model, 1);
    for (std::uint64_t t = 0; t < ticks; ++t)
    {
        std::vector<sim::Force> forces;
        for (std::uint16_t sender = 0; sender < 16; ++sender)
        {
            const Scheduled* best = nullptr;
            for (const Scheduled& s : schedule)
                if (s.sender == sender && s.from <= t && (best == nullptr || s.from >= best->from))
                    best = &s;
            if (best != nullptr)
                for (const net::UserForce& f : best->forces)
                    forces.push_back(to_sim_force(f));
        }
        sim::step(model, state, ws, forces);
    }
    return state;
}

/// Largest |a - b| over canonical nodes where `mask` holds (all when empty), and max |b|.
struct Diff
{
    double max_abs = 0.0;
    double max_ref = 0.0;      ///< over every node
    std::size_t compared = 0;  ///< nodes `use` took (0: the comparison checked nothing)
    [[nodiscard]] double relative() const { return max_ref > 0.0 ? max_abs / max_ref : max_abs; }
};

inline Diff compare(const core::TetraGrid& g, const core::Field<double>& a,
                    const core::Field<double>& b, const std::function<bool(core::NodeIndex)>& use)
{
    Diff d;
    for (const core::NodeIndex n : g.node_of_unique())
    {
        const core::GridCoord c = g.coord(n);
        d.max_ref = std::max(d.max_ref, std::fabs(b.at(c.x, c.y)));
        if (!use || use(n))
        {
            d.max_abs = std::max(d.max_abs, std::fabs(a.at(c.x, c.y) - b.at(c.x, c.y)));
            ++d.compared;
        }
    }
    return d;
}

/// Several peers in one thread over one simulated network with a virtual clock.
struct Harness
{
    explicit Harness(const net::SimulatedNetworkSettings& s = {}) : net(s) {}

    net::SimulatedNetwork net;
    std::vector<std::unique_ptr<net::Transport>> transports;
    std::vector<std::unique_ptr<Session>> peers;  ///< null once crashed
    std::vector<char> stopped;                    ///< per peer: stop() without resume()
    std::vector<net::Address> addresses;          ///< where each peer listens
    net::Address master_address;
    double now = 0.0;

    Session& host(int level, const SessionSettings& settings,
                  const sim::MembraneState* start = nullptr)
    {
        transports.push_back(net.create_endpoint());
        master_address = transports.back()->open({}).value();
        addresses.push_back(master_address);
        const core::TetraGrid grid = core::TetraGrid::create(level).value();
        peers.push_back(Session::host(*transports.back(), grid, scenes::sphere_grid(grid, 1.0),
                                      material(), settings, start)
                            .value());
        return *peers.back();
    }

    /// Joins through the peer listening at `via` (the master's address by default).
    Session& join(net::Role role, const SessionSettings& settings,
                  const std::optional<net::Address>& via = std::nullopt)
    {
        transports.push_back(net.create_endpoint());
        addresses.push_back(transports.back()->open({}).value());
        peers.push_back(
            Session::join(*transports.back(), via.value_or(master_address), role, settings)
                .value());
        return *peers.back();
    }

    /// Peer k vanishes without a word, as a killed process: its session and endpoint are
    /// destroyed, and the others' links to it time out.
    void crash(std::size_t k)
    {
        peers[k].reset();
        transports[k].reset();
    }

    /// Peer k stops running, as a process stopped with SIGSTOP: it is no longer polled or
    /// advanced until resume(k). `past_timeout`: long enough for the others to drop it (its
    /// links time out after the network's connect_timeout_s, SimulatedNetwork::suspend).
    void stop(std::size_t k, bool past_timeout)
    {
        stopped.resize(peers.size(), 0);
        stopped[k] = 1;
        if (past_timeout)
            net.suspend(addresses[k]);
    }
    void resume(std::size_t k) { stopped.at(k) = 0; }
    [[nodiscard]] bool running(std::size_t k) const
    {
        return peers[k] && (k >= stopped.size() || stopped[k] == 0);
    }

    void pump_once(double dt)
    {
        for (std::size_t k = 0; k < peers.size(); ++k)
            if (running(k))
                peers[k]->poll();
        for (std::size_t k = 0; k < peers.size(); ++k)
            if (running(k))
                peers[k]->advance(now);
        net.advance(dt);
        now += dt;
    }

    /// Pumps until `done` or `max_iterations` (bounded); \return whether `done` held.
    bool pump_until(const std::function<bool()>& done, int max_iterations, double dt = 0.0005)
    {
        for (int k = 0; k < max_iterations; ++k)
        {
            if (done())
                return true;
            pump_once(dt);
        }
        return done();
    }
};

/// Pumps `h` until its first `members` peers have the model and the master's partition gives
/// each of them a share (bounded by `max_iterations`); \return whether that happened.
inline bool pump_until_partitioned(Harness& h, std::size_t members, int max_iterations = 4000)
{
    return h.pump_until(
        [&]
        {
            for (std::size_t k = 1; k < members; ++k)
                if (!h.peers[k]->ready())
                    return false;
            auto owners = h.peers[0]->owners();
            std::sort(owners.begin(), owners.end());
            return static_cast<std::size_t>(std::unique(owners.begin(), owners.end()) -
                                            owners.begin()) == members;
        },
        max_iterations);
}

/// Whether two doubles have the same bits.
inline bool same_bits(double a, double b)
{
    return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

/// Whether every participant of `h` (viewers aside) has reached `tick`.
inline bool all_at(const Harness& h, std::uint64_t tick)
{
    for (const auto& p : h.peers)
        if (p->role() != SessionRole::Viewer && p->tick() < tick)
            return false;
    return true;
}

/// The forces a scripted peer set at a time (its simulated time when it set them).
struct Frame
{
    double time = 0.0;
    std::vector<sim::Force> forces;
};

}  // namespace pliant::session::test
