// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Re-assembly (`reassemble_every = R`, docs/physics.md §2): every R steps K and M are those of a
// model created from the deformed surface, bit for bit; R = 0 keeps the rest-state ones; and a
// re-assembly after the first allocates nothing (counted by the replaced operator new of
// tests/support/allocation_counter.cpp, in the executable of no_allocation_test.cpp).

#include <pliant/core/tetra_grid.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <gtest/gtest.h>

#include "grid_shapes.h"
#include "support/allocation_counter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace pliant::sim
{
namespace
{

MembraneSettings settings(int reassemble_every)
{
    MembraneSettings s;
    s.beta = 0.5;
    s.k_f = 1.0;
    s.fixed_step = true;
    s.fixed_dt = 0.01;
    s.reassemble_every = reassemble_every;
    s.threads = 1;
    return s;
}

MembraneModel sphere(int level, const MembraneSettings& s)
{
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    return MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), s).value();
}

// A strong pull on the north pole, so the surface deforms by a good fraction of its size.
Force pull()
{
    return Force{.face = -1, .point = {0.0, 0.0, 1.0}, .radius = 0.5, .vector = {0.0, 0.0, 40.0}};
}

bool same_bits(const core::Field<double>& a, const core::Field<double>& b)
{
    return a.padded().size() == b.padded().size() &&
           std::memcmp(a.padded().data(), b.padded().data(), a.padded().size_bytes()) == 0;
}

bool same_assembly(const MembraneModel& a, const MembraneModel& b)
{
    return same_bits(a.weight_x(), b.weight_x()) && same_bits(a.weight_y(), b.weight_y()) &&
           same_bits(a.weight_d(), b.weight_d()) && same_bits(a.mass(), b.mass()) &&
           same_bits(a.inverse_mass(), b.inverse_mass());
}

// The model `create` gives for rest positions P + u N.
MembraneModel created_from(const MembraneModel& m, const core::Field<double>& u)
{
    core::Vec3Field<double> p;
    m.positions(u, p);
    return MembraneModel::create(m.grid(), p, m.settings()).value();
}

TEST(MembraneReassembly, EveryRStepsGivesTheModelOfTheDeformedSurface)
{
    constexpr int k_r = 3;
    MembraneModel m = sphere(4, settings(k_r));
    const MembraneModel rest = sphere(4, settings(0));
    MembraneState s = MembraneState::at_rest(m.grid());
    Rkf45Workspace ws(m, 1);
    const Force f = pull();
    core::Field<double> u_at_last;  // u when the last re-assembly happened
    for (int k = 0; k < 3 * k_r + 1; ++k)
    {
        const std::uint64_t tick = s.tick;
        const core::Field<double> u_before = s.u;
        const StepReport r = step(m, s, ws, {&f, 1});
        ASSERT_EQ(r.status, StepStatus::Ok);
        const bool due = tick > 0 && tick % k_r == 0;
        EXPECT_EQ(r.reassembled, due) << "tick " << tick;
        if (due)
        {
            u_at_last = u_before;
            EXPECT_EQ(m.assembled_tick(), tick);
            // K and M are, bit for bit, those of a model created from the deformed surface.
            EXPECT_TRUE(same_assembly(m, created_from(m, u_before))) << "tick " << tick;
        }
    }
    ASSERT_FALSE(u_at_last.empty());
    // The deformation is large enough to change K and M: the test compares something.
    EXPECT_FALSE(same_bits(m.weight_x(), rest.weight_x()));
    EXPECT_FALSE(same_bits(m.mass(), rest.mass()));
    EXPECT_TRUE(same_assembly(m, created_from(m, u_at_last)));
    // P and N stay the rest geometry.
    for (std::size_t k = 0; k < 3; ++k)
    {
        EXPECT_TRUE(same_bits(m.rest_positions()[k], rest.rest_positions()[k]));
        EXPECT_TRUE(same_bits(m.normals()[k], rest.normals()[k]));
    }
}

TEST(MembraneReassembly, NeverWhenRIsZero)
{
    MembraneModel m = sphere(4, settings(0));
    const MembraneModel rest = sphere(4, settings(0));
    MembraneState s = MembraneState::at_rest(m.grid());
    Rkf45Workspace ws(m, 1);
    const Force f = pull();
    for (int k = 0; k < 10; ++k)
    {
        const StepReport r = step(m, s, ws, {&f, 1});
        ASSERT_EQ(r.status, StepStatus::Ok);
        EXPECT_FALSE(r.reassembled);
    }
    double largest = 0.0;
    for (const double u : s.u.padded())
        largest = std::max(largest, std::fabs(u));
    EXPECT_GT(largest, 1e-3);  // it moved
    EXPECT_TRUE(same_assembly(m, rest));
    EXPECT_EQ(m.assembled_tick(), 0U);
}

// Forces act as f / m on each node, m the lumped mass, which a re-assembly recomputes from the
// deformed area: forces set once and held over re-assemblies give the run in which they are set
// again right after each one (to rounding). Before, they kept the masses of the set_forces call
// (stale until the next one: a frame, in the apps), and under this strong pull the two runs'
// u differed by 0.10 m after 9 steps (largest |u| 0.66 m).
TEST(MembraneReassembly, ForcesFollowTheMassesOfAReassembly)
{
    constexpr int k_r = 2;
    MembraneModel held = sphere(4, settings(k_r));
    MembraneModel fresh = sphere(4, settings(0));  // re-assembled by hand below
    MembraneState a = MembraneState::at_rest(held.grid());
    MembraneState b = MembraneState::at_rest(fresh.grid());
    Rkf45Workspace ws_a(held, 1);
    Rkf45Workspace ws_b(fresh, 1);
    const std::vector<Force> forces{
        pull(), Force{.face = 300, .point = {}, .radius = 0.0, .vector = {5.0, -3.0, 2.0}}};
    set_forces(held, ws_a, forces);
    set_forces(fresh, ws_b, forces);
    int reassemblies = 0;
    for (int k = 0; k < 4 * k_r + 1; ++k)
    {
        if (b.tick > 0 && b.tick % k_r == 0)
        {
            fresh.sync(b.u);
            ASSERT_TRUE(fresh.reassemble(b.u));
            fresh.set_assembled_tick(b.tick);
            set_forces(fresh, ws_b, forces);  // f / m with the new masses
        }
        const StepReport r = step_prepared(held, a, ws_a);
        ASSERT_EQ(r.status, StepStatus::Ok);
        reassemblies += r.reassembled ? 1 : 0;
        ASSERT_EQ(step_prepared(fresh, b, ws_b).status, StepStatus::Ok);
    }
    EXPECT_EQ(reassemblies, 4);
    EXPECT_TRUE(same_assembly(held, fresh));
    EXPECT_FALSE(same_bits(held.mass(), sphere(4, settings(0)).mass()));  // the masses moved
    double largest = 0.0, diff = 0.0;
    for (int y = 0; y < held.grid().ny(); ++y)
        for (int x = 0; x < held.grid().nx(); ++x)
        {
            largest = std::max(largest, std::fabs(b.u.at(x, y)));
            diff = std::max({diff, std::fabs(a.u.at(x, y) - b.u.at(x, y)),
                             std::fabs(a.v.at(x, y) - b.v.at(x, y)) * held.settings().fixed_dt});
        }
    EXPECT_GT(largest, 1e-3);
    EXPECT_LE(diff, 1e-13 * largest) << "largest |u| " << largest;
}

TEST(MembraneReassembly, AllocatesNothingAfterTheFirst)
{
    MembraneModel m = sphere(4, settings(2));
    MembraneState s = MembraneState::at_rest(m.grid());
    Rkf45Workspace ws(m, 1);
    const Force f = pull();
    set_forces(m, ws, {&f, 1});
    // Ticks 0..2: the first re-assembly (before the step from tick 2) allocates its planes.
    for (int k = 0; k < 3; ++k)
        ASSERT_EQ(step_prepared(m, s, ws).status, StepStatus::Ok);
    ASSERT_EQ(m.assembled_tick(), 2U);
    const std::uint64_t before = test::allocations();
    int reassemblies = 0;
    for (int k = 0; k < 7; ++k)
    {
        const StepReport r = step_prepared(m, s, ws);
        ASSERT_EQ(r.status, StepStatus::Ok);
        reassemblies += r.reassembled ? 1 : 0;
    }
    const std::uint64_t allocations = test::allocations() - before;
    EXPECT_EQ(reassemblies, 3);  // before the steps from ticks 4, 6 and 8
    EXPECT_EQ(allocations, 0U);

    // Forces over many more nodes, and a linear hold towards them (its rate and end values are
    // rescaled too): the re-assemblies that follow still allocate nothing.
    Force wide = pull();
    wide.radius = 1.2;
    begin_force_ramp(m, ws, {&wide, 1}, s.time, s.time + 0.05);
    const std::uint64_t before_wide = test::allocations();
    for (int k = 0; k < 4; ++k)
    {
        const StepReport r = step_prepared(m, s, ws);
        ASSERT_EQ(r.status, StepStatus::Ok);
        reassemblies += r.reassembled ? 1 : 0;
    }
    EXPECT_EQ(reassemblies, 5);
    EXPECT_EQ(test::allocations() - before_wide, 0U);
}

}  // namespace
}  // namespace pliant::sim
