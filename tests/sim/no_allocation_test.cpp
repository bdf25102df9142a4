// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Issue 5's "no allocation per step": after a first step (which plans the workspace and an owned
// set once), steps allocate nothing, on any thread: full and restricted, adaptive and fixed, 1 and
// 2 threads, double and mixed precision, with a face force and a point force. Counted by a replaced
// operator new (tests/support/allocation_counter.cpp, linked into this executable only).
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <gtest/gtest.h>

#include "grid_shapes.h"
#include "support/allocation_counter.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pliant::sim
{
namespace
{

struct Case
{
    bool fixed;
    int threads;
    bool restricted;
    Precision precision = Precision::Double;
};

TEST(NoAllocation, StepsAllocateNothingAfterTheFirst)
{
    const core::TetraGrid grid = core::TetraGrid::create(6).value();
    const std::vector<core::Region> owned{core::Region{0, 0, grid.nx() / 2, grid.ny()}};
    for (const Case c :
         {Case{false, 1, false}, Case{true, 1, false}, Case{false, 2, false}, Case{true, 2, false},
          Case{false, 1, true}, Case{true, 2, true}, Case{false, 1, false, Precision::Mixed},
          Case{true, 2, false, Precision::Mixed}})
    {
        MembraneSettings settings;
        settings.beta = 0.5;
        settings.k_f = 1.0;
        settings.fixed_step = c.fixed;
        settings.fixed_dt = 2e-3;
        settings.threads = c.threads;
        settings.precision = c.precision;
        auto model = MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), settings).value();
        MembraneState state = MembraneState::at_rest(grid);
        Rkf45Workspace ws(model, c.threads);
        Force face;
        face.face = 100;
        face.vector = {0.0, 0.0, 0.5};
        Force point;
        point.point = {0.0, 0.0, 1.0};
        point.radius = 0.3;
        point.vector = {0.0, 0.0, -0.3};
        const std::vector<Force> forces{face, point};
        StepOptions options;
        if (c.restricted)
            options.owned = owned;
        (void)step(model, state, ws, forces, options);  // plans, once
        const std::uint64_t before = test::allocations();
        int accepted = 0;
        for (int k = 0; k < 50; ++k)
        {
            const StepReport r = step_prepared(model, state, ws, options);
            accepted += r.dt > 0.0 ? 1 : 0;
        }
        EXPECT_EQ(test::allocations() - before, 0U)
            << "fixed " << c.fixed << ", threads " << c.threads << ", restricted " << c.restricted
            << ", precision " << to_string(c.precision);
        EXPECT_EQ(accepted, 50);
        // The steps moved the surface (the forces lie in the owned half).
        double moved = 0.0;
        for (int y = 0; y < grid.ny(); ++y)
            for (int x = 0; x < grid.nx() / 2; ++x)
                moved = std::max(moved, std::abs(state.u.at(x, y)));
        EXPECT_GT(moved, 0.0);
    }
}

}  // namespace
}  // namespace pliant::sim
