// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// two_peers: a collaborative session of two peers in one program (docs/library.md). A master
// and a participant share a sphere over the simulated network in exact coupling; the
// participant pulls a face for 1,000 ticks. At the end both show the same object, and the
// master's recording replayed on one process gives it bit for bit.
//
//   two_peers [LEVEL]     (default 4)
#include <pliant/core/sphere_domain.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/net/simulated_transport.h>
#include <pliant/session/recording.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace
{

constexpr std::uint64_t k_ticks = 1000;

/// Largest |a - b| over the surface's vertices.
double largest_difference(const pliant::core::TetraGrid& grid, const pliant::core::Field<double>& a,
                          const pliant::core::Field<double>& b)
{
    double d = 0.0;
    for (const pliant::core::NodeIndex n : grid.node_of_unique())
        d = std::max(d, std::abs(a[n] - b[n]));
    return d;
}

}  // namespace

int main(int argc, char** argv)
{
    using namespace pliant;
    const int level = argc > 1 ? std::atoi(argv[1]) : 4;
    auto grid = core::TetraGrid::create(level);
    if (!grid)
    {
        std::fprintf(stderr, "two_peers: %s\n", grid.error().message.c_str());
        return 2;
    }
    const core::Vec3Field<double> rest =
        core::sphere_domain(*grid, core::SphereMap::EqualArea, 1.0, 0);

    // The simulated network: 0.5 ms one way (the default 5 ms slows the lockstep).
    net::SimulatedNetworkSettings ns;
    ns.link.latency_s = 0.0005;
    net::SimulatedNetwork network(ns);
    auto ta = network.create_endpoint();
    const net::Address master = ta->open({}).value();
    auto tb = network.create_endpoint();
    (void)tb->open({}).value();

    // The material, and a common step below the grid's stability bound (as `pliant host`: 1 ms
    // or 0.9 of the bound, whichever is smaller).
    sim::MembraneSettings material;
    material.beta = 0.5;
    material.k_f = 1.0;
    material.fixed_dt = std::min(
        1e-3,
        0.9 * sim::stable_fixed_step(sim::MembraneModel::create(*grid, rest, material).value()));
    session::SessionSettings settings;  // exact coupling
    settings.max_ticks = k_ticks;
    auto a = session::Session::host(*ta, *grid, rest, material, settings).value();
    if (auto recording = a->start_recording(); !recording)
    {
        std::fprintf(stderr, "two_peers: %s\n", recording.error().message.c_str());
        return 1;
    }
    auto b = session::Session::join(*tb, master, net::Role::Participant, settings).value();
    if (auto ok = b->set_forces(
            {net::UserForce{{net::TargetKind::Face, 100, {}, 0.0}, 0, {0.0, 0.0, 0.5}}});
        !ok)
    {
        std::fprintf(stderr, "two_peers: %s\n", ok.error().message.c_str());
        return 1;
    }

    // The caller's clock, here virtual: a quarter of a step per round, so that the lockstep's
    // exchanges (0.5 ms each way) fit.
    const double round = std::min(0.0005, material.fixed_dt / 4.0);
    double now = 0.0;
    const auto pump = [&]
    {
        a->poll();
        b->poll();
        a->advance(now);
        b->advance(now);
        network.advance(round);
        now += round;
    };
    const auto bound = static_cast<int>(8 * k_ticks * std::ceil(material.fixed_dt / round));
    for (int k = 0; k < bound && (a->tick() < k_ticks || b->tick() < k_ticks); ++k)
        pump();
    for (int k = 0; k < 400; ++k)  // the last leaf states arrive
        pump();
    if (a->tick() != k_ticks || b->tick() != k_ticks)
    {
        std::fprintf(stderr, "two_peers: stopped at ticks %llu and %llu\n",
                     static_cast<unsigned long long>(a->tick()),
                     static_cast<unsigned long long>(b->tick()));
        return 1;
    }

    const double between = largest_difference(*grid, a->display_u(), b->display_u());
    auto replayed = session::replay(a->recording());
    if (!replayed)
    {
        std::fprintf(stderr, "two_peers: %s\n", replayed.error().message.c_str());
        return 1;
    }
    const double against_replay = largest_difference(*grid, a->display_u(), replayed->state.u);
    double largest_u = 0.0;
    for (const core::NodeIndex n : grid->node_of_unique())
        largest_u = std::max(largest_u, std::abs(a->display_u()[n]));
    const auto owners = a->owners();
    std::printf("level %d, %llu ticks of %.3g ms; participant's share %zu of %zu leaves\n", level,
                static_cast<unsigned long long>(k_ticks), 1e3 * material.fixed_dt,
                static_cast<std::size_t>(std::count(owners.begin(), owners.end(), b->id())),
                owners.size());
    std::printf(
        "largest displacement %.6g m; the peers' displays differ by %g, the replay of "
        "the master's recording by %g\n",
        largest_u, between, against_replay);
    return between == 0.0 && against_replay == 0.0 && largest_u > 0.0 ? 0 : 1;
}
