// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Coarse streaming (SessionSettings::stream_coarsen, docs/session.md §5.2) in real sessions over a
// SimulatedNetwork: what a viewer shows of every node, and what a participant shows of every node
// it does not own, equals the butterfly refinement of the owners' state restricted k levels,
// computed here independently with subdiv::restrict / subdiv::refine_levels, bit for bit; the
// received (even) nodes equal the owners' values; exact coupling still equals a single process;
// the stream's bytes fall about 4^k; refused combinations say why. Loops are bounded.

#include <pliant/subdiv/convolution_plan.h>
#include <pliant/subdiv/refine.h>

#include <gtest/gtest.h>

#include "session_harness.h"

#include <bit>
#include <string>

namespace pliant::session::test
{
namespace
{

constexpr int k_coarse_level = 5;
constexpr std::uint64_t k_coarse_ticks = 300;

SessionSettings coarse(int k, const char* name)
{
    SessionSettings s;
    s.coupling = Coupling::Exact;
    s.max_ticks = k_coarse_ticks;
    s.name = name;
    s.stream_coarsen = k;
    return s;
}

/// Master (coarsening k_master) and a participant (k_part), partitioned, both pulling, and a
/// viewer; pumps to k_coarse_ticks, then lets the frozen final states reach everybody.
void run_pulling(Harness& h, int k_master, int k_part,
                 net::ValueEncoding encoding = net::ValueEncoding::F64)
{
    SessionSettings ms = coarse(k_master, "master");
    SessionSettings ps = coarse(k_part, "part");
    ms.stream_encoding = encoding;
    ps.stream_encoding = encoding;
    h.host(k_coarse_level, ms);
    Session& p = h.join(net::Role::Participant, ps);
    p.set_points_of_interest({net::Target{net::TargetKind::Face, 600, {0, 0, 0}, 0.0}});
    h.join(net::Role::Viewer, coarse(0, "viewer"));
    ASSERT_TRUE(h.pump_until(
        [&]
        {
            const auto owners = h.peers[0]->owners();
            return p.ready() && h.peers[2]->ready() &&
                   std::find(owners.begin(), owners.end(), p.id()) != owners.end();
        },
        8000));
    EXPECT_TRUE(h.peers[0]->set_forces({point_push(0.0, 0.0, 1.0, 0.3, 0.4)}, 60));
    EXPECT_TRUE(p.set_forces({face_pull(700, 0.6)}, 80));
    ASSERT_TRUE(h.pump_until([&] { return all_at(h, k_coarse_ticks); }, 60000, 0.0005));
    for (int k = 0; k < 400; ++k)
        h.pump_once(0.0005);
}

/// The owners' integrated u or v, assembled over every leaf (twins synced).
core::Field<double> owners_field(const Harness& h, bool velocity)
{
    const Session& master = *h.peers[0];
    const core::TetraGrid& g = master.model()->grid();
    const LeafGraph& graph = *master.leaf_graph();
    const auto owners = master.owners();
    core::Field<double> f(g);
    for (std::size_t l = 0; l < graph.size(); ++l)
        for (const auto& p : h.peers)
            if (p->id() == owners[l] && p->role() != SessionRole::Viewer)
                for (const core::NodeIndex n : graph.nodes(l))
                {
                    const core::GridCoord c = g.coord(n);
                    f.at(c.x, c.y) =
                        velocity ? p->state().v.at(c.x, c.y) : p->state().u.at(c.x, c.y);
                }
    core::sync_twins(g, f);
    return f;
}

/// refine_levels(restrict^k(fine)), independently of the session's code path.
core::Field<double> coarse_then_refined(const core::Field<double>& fine, int k)
{
    const auto plans = subdiv::make_plans(fine.level() - k, k).value();
    core::Field<double> c = subdiv::restrict(plans[static_cast<std::size_t>(k - 1)], fine);
    for (int j = 2; j <= k; ++j)
        c = subdiv::restrict(plans[static_cast<std::size_t>(k - j)], c);
    return subdiv::refine_levels<double>(plans, c);
}

/// Nodes (canonical, where `use`) whose shown value differs in any bit from `expect`.
std::size_t mismatches(const core::TetraGrid& g, const core::Field<double>& shown,
                       const core::Field<double>& expect,
                       const std::function<bool(core::NodeIndex)>& use)
{
    std::size_t bad = 0;
    for (const core::NodeIndex n : g.node_of_unique())
    {
        if (use && !use(n))
            continue;
        const core::GridCoord c = g.coord(n);
        bad += same_bits(shown.at(c.x, c.y), expect.at(c.x, c.y)) ? 0 : 1;
    }
    return bad;
}

class SessionCoarseStream : public ::testing::TestWithParam<int>
{
};

TEST_P(SessionCoarseStream, ViewsAreTheButterflyRefinementOfTheOwnersStateBitForBit)
{
    const int k = GetParam();
    Harness h;
    run_pulling(h, k, k);
    const core::TetraGrid& g = h.peers[0]->model()->grid();
    const LeafGraph& graph = *h.peers[0]->leaf_graph();
    const auto owners = h.peers[0]->owners();
    for (const bool velocity : {false, true})
    {
        const core::Field<double> truth = owners_field(h, velocity);
        const core::Field<double> expect = coarse_then_refined(truth, k);
        const Session& viewer = *h.peers[2];
        const auto& shown = velocity ? viewer.display_v() : viewer.display_u();
        EXPECT_EQ(mismatches(g, shown, expect, {}), 0u) << "viewer, k " << k;
        // The received nodes are the owners' values.
        const int step = 1 << k;
        EXPECT_EQ(mismatches(g, shown, truth,
                             [&](core::NodeIndex n)
                             {
                                 const core::GridCoord c = g.coord(n);
                                 return c.x % step == 0 && c.y % step == 0;
                             }),
                  0u);
        // Refinement is visible: the odd nodes are not the owners' values.
        EXPECT_GT(mismatches(g, shown, truth, {}), 0u);
        // Participants show the others' leaves as the viewer does, and their own as they are.
        for (std::size_t i = 0; i < 2; ++i)
        {
            const Session& peer = *h.peers[i];
            const auto& own_shown = velocity ? peer.display_v() : peer.display_u();
            const net::PeerId id = peer.id();
            EXPECT_EQ(mismatches(g, own_shown, expect,
                                 [&](core::NodeIndex n) { return owners[graph.leaf_of(n)] != id; }),
                      0u)
                << "peer " << i;
            EXPECT_EQ(mismatches(g, own_shown, truth,
                                 [&](core::NodeIndex n) { return owners[graph.leaf_of(n)] == id; }),
                      0u)
                << "peer " << i;
        }
    }
    EXPECT_GT(compare(g, h.peers[2]->display_u(), owners_field(h, false), {}).max_ref, 1e-4);
    std::uint64_t rejects = 0;
    for (const auto& p : h.peers)
        rejects += p->stats().state_rejects + p->stats().bad_datagrams;
    EXPECT_EQ(rejects, 0u);

    // Display only: the lockstep still equals a single process.
    const std::vector<Scheduled> sched = {{0, 60, {point_push(0.0, 0.0, 1.0, 0.3, 0.4)}},
                                          {1, 80, {face_pull(700, 0.6)}}};
    const sim::MembraneState ref = reference_run(k_coarse_level, k_coarse_ticks, sched);
    for (std::size_t i = 0; i < 2; ++i)
    {
        const Session& peer = *h.peers[i];
        const net::PeerId id = peer.id();
        const Diff d = compare(g, peer.state().u, ref.u,
                               [&](core::NodeIndex n) { return owners[graph.leaf_of(n)] == id; });
        EXPECT_GT(d.max_ref, 1e-4);
        EXPECT_LE(d.relative(), 1e-12);
    }
}

INSTANTIATE_TEST_SUITE_P(Levels, SessionCoarseStream, ::testing::Values(1, 2));

TEST(SessionCoarseStreamMixed, AFullResolutionSenderStaysExactBesideACoarseOne)
{
    Harness h;
    run_pulling(h, 1, 0);  // the master streams one level down, the participant every node
    const core::TetraGrid& g = h.peers[0]->model()->grid();
    const LeafGraph& graph = *h.peers[0]->leaf_graph();
    const auto owners = h.peers[0]->owners();
    const net::PeerId master = h.peers[0]->id();
    const core::Field<double> truth = owners_field(h, false);
    const core::Field<double> expect = coarse_then_refined(truth, 1);
    const auto& shown = h.peers[2]->display_u();
    EXPECT_EQ(mismatches(g, shown, truth,
                         [&](core::NodeIndex n) { return owners[graph.leaf_of(n)] != master; }),
              0u);
    EXPECT_EQ(mismatches(g, shown, expect,
                         [&](core::NodeIndex n) { return owners[graph.leaf_of(n)] == master; }),
              0u);
}

TEST(SessionCoarseStreamMixed, AFinerCoarseSenderKeepsItsLevelBesideACoarserOne)
{
    Harness h;
    run_pulling(h, 2, 1);  // master two levels down, participant one
    const core::TetraGrid& g = h.peers[0]->model()->grid();
    const LeafGraph& graph = *h.peers[0]->leaf_graph();
    const auto owners = h.peers[0]->owners();
    const net::PeerId part = h.peers[1]->id();
    const core::Field<double> truth = owners_field(h, false);
    // Independently: restrict twice, refine once, put the participant's level n-1 nodes back,
    // refine again.
    const auto plans = subdiv::make_plans(k_coarse_level - 2, 2).value();
    const core::Field<double> c2 = subdiv::restrict(plans[0], subdiv::restrict(plans[1], truth));
    core::Field<double> c1 = subdiv::refine_levels<double>(std::span(plans.data(), 1), c2);
    for (std::size_t l = 0; l < graph.size(); ++l)
        if (owners[l] == part)
            for (const core::NodeIndex n : graph.nodes(l))
            {
                const core::GridCoord c = g.coord(n);
                if (c.x % 2 == 0 && c.y % 2 == 0)
                    c1.at(c.x / 2, c.y / 2) = truth.at(c.x, c.y);
            }
    core::sync_twins(plans[1].coarse_grid(), c1);
    const core::Field<double> expect =
        subdiv::refine_levels<double>(std::span(plans.data() + 1, 1), c1);
    EXPECT_EQ(mismatches(g, h.peers[2]->display_u(), expect, {}), 0u);
    // The participant's nodes on level n-1 are its own values.
    EXPECT_EQ(mismatches(g, h.peers[2]->display_u(), truth,
                         [&](core::NodeIndex n)
                         {
                             const core::GridCoord c = g.coord(n);
                             return owners[graph.leaf_of(n)] == part && c.x % 2 == 0 &&
                                    c.y % 2 == 0;
                         }),
              0u);
}

TEST(SessionCoarseStreamF32, RoundedCoarseNodesAreRefinedAsReceived)
{
    Harness h;
    run_pulling(h, 1, 1, net::ValueEncoding::F32);
    const core::TetraGrid& g = h.peers[0]->model()->grid();
    core::Field<double> rounded = owners_field(h, false);
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            rounded.at(x, y) = static_cast<double>(static_cast<float>(rounded.at(x, y)));
    EXPECT_EQ(mismatches(g, h.peers[2]->display_u(), coarse_then_refined(rounded, 1), {}), 0u);
}

/// Bytes a viewer receives from a master that owns everything, over `pumps` pumps of a frozen
/// exact session (only the 60 Hz leaf-state stream is left); `shown`, if given, gets the
/// viewer's display at the end.
std::uint64_t viewer_bytes(int k, int pumps, bool batch = true,
                           core::Field<double>* shown = nullptr)
{
    Harness h;
    SessionSettings m = coarse(k, "master");
    m.max_ticks = 20;
    m.batch_leaves = batch;
    h.host(k_coarse_level, m);
    Session& v = h.join(net::Role::Viewer, coarse(0, "viewer"));
    EXPECT_TRUE(h.pump_until([&] { return v.ready() && h.peers[0]->tick() >= 20; }, 20000));
    for (int i = 0; i < 200; ++i)
        h.pump_once(0.0005);
    const std::uint64_t before = v.stats().bytes_received;
    const std::uint64_t states = h.peers[0]->stats().leaf_states_sent;
    for (int i = 0; i < pumps; ++i)
        h.pump_once(0.0005);
    EXPECT_GT(h.peers[0]->stats().leaf_states_sent, states);
    if (shown != nullptr)
        *shown = v.display_u();
    return v.stats().bytes_received - before;
}

TEST(SessionCoarseStreamBandwidth, OneLevelCoarserCostsAtLeastThreeTimesFewerBytes)
{
    const std::uint64_t full = viewer_bytes(0, 2000);
    const std::uint64_t one = viewer_bytes(1, 2000);
    const std::uint64_t two = viewer_bytes(2, 2000);
    ASSERT_GT(one, 0u);
    EXPECT_GE(static_cast<double>(full), 3.0 * static_cast<double>(one)) << full << " " << one;
    EXPECT_LT(two, one);
}

// Coarse leaves go several to a datagram (ValueBatch) instead of one LeafState each, whose 48
// fixed bytes outweighed a two-levels-coarser leaf's 4-6 nodes; the viewer shows the same bits.
TEST(SessionCoarseStreamBandwidth, BatchedCoarseLeavesCostFewerBytesAndShowTheSame)
{
    core::Field<double> batched_view;
    core::Field<double> single_view;
    const std::uint64_t full = viewer_bytes(0, 2000);
    const std::uint64_t batched = viewer_bytes(2, 2000, true, &batched_view);
    const std::uint64_t single = viewer_bytes(2, 2000, false, &single_view);
    const std::uint64_t one_batched = viewer_bytes(1, 2000, true);
    const std::uint64_t one_single = viewer_bytes(1, 2000, false);
    std::printf(
        "viewer bytes: k = 0 %llu; k = 1 %llu batched, %llu in LeafStates; k = 2 %llu "
        "batched, %llu in LeafStates\n",
        static_cast<unsigned long long>(full), static_cast<unsigned long long>(one_batched),
        static_cast<unsigned long long>(one_single), static_cast<unsigned long long>(batched),
        static_cast<unsigned long long>(single));
    ASSERT_GT(batched, 0u);
    EXPECT_LT(static_cast<double>(batched), 0.75 * static_cast<double>(single));
    EXPECT_LT(one_batched, one_single);
    EXPECT_GE(static_cast<double>(full), 12.0 * static_cast<double>(batched));
    const core::TetraGrid g = core::TetraGrid::create(k_coarse_level).value();
    EXPECT_EQ(mismatches(g, batched_view, single_view, {}), 0u);
}

TEST(SessionCoarseStreamRefusals, BadCombinationsSayWhy)
{
    const core::TetraGrid grid = core::TetraGrid::create(k_coarse_level).value();
    const auto rest = scenes::sphere_grid(grid, 1.0);
    auto host_error = [&](const core::TetraGrid& g, const SessionSettings& s) -> std::string
    {
        net::SimulatedNetwork net;
        auto t = net.create_endpoint();
        (void)t->open({}).value();
        auto r = Session::host(*t, g, scenes::sphere_grid(g, 1.0), material(), s);
        return r ? std::string() : r.error().message;
    };
    SessionSettings s = coarse(1, "master");
    s.coupling = Coupling::Fast;
    EXPECT_NE(host_error(grid, s).find("fast coupling"), std::string::npos) << host_error(grid, s);
    s = coarse(1, "master");
    s.stream_encoding = net::ValueEncoding::QuantisedDelta;
    EXPECT_NE(host_error(grid, s).find("quantised-delta"), std::string::npos);
    s = coarse(4, "master");
    EXPECT_NE(host_error(grid, s).find("stream_coarsen is 4"), std::string::npos);
    // Leaves of 8 x 8 cells: k = 3 would leave the bottom-right leaves without a canonical node.
    s = coarse(3, "master");
    EXPECT_NE(host_error(grid, s).find("too coarse for level 5 (at most 2"), std::string::npos)
        << host_error(grid, s);
    s = coarse(-1, "master");
    EXPECT_FALSE(host_error(grid, s).empty());
    const core::TetraGrid small = core::TetraGrid::create(2).value();  // one leaf per square
    s = coarse(2, "master");
    EXPECT_NE(host_error(small, s).find("too coarse for level 2"), std::string::npos)
        << host_error(small, s);
    s = coarse(1, "master");
    EXPECT_TRUE(host_error(small, s).empty());
    (void)rest;

    // A joiner learns the coupling from the model: a participant asking for coarse streaming in a
    // fast session leaves with the reason; a viewer (which streams nothing) stays.
    Harness h;
    SessionSettings fast;
    fast.coupling = Coupling::Fast;
    fast.name = "master";
    h.host(k_coarse_level, fast);
    Session& p = h.join(net::Role::Participant, coarse(1, "part"));
    Session& v = h.join(net::Role::Viewer, coarse(1, "viewer"));
    EXPECT_TRUE(h.pump_until([&] { return p.left() && v.ready(); }, 8000));
    EXPECT_NE(p.refusal().find("fast coupling"), std::string::npos) << p.refusal();
    EXPECT_FALSE(v.left());
    EXPECT_TRUE(v.refusal().empty());
}

}  // namespace
}  // namespace pliant::session::test
