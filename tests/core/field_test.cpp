// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/field.h>

#include <gtest/gtest.h>

namespace pliant::core
{
namespace
{

TEST(Field, LayoutHasAGhostRingAroundRowMajorNodes)
{
    const TetraGrid g = TetraGrid::create(3).value();
    Field<float> f(g, 2, 0.0F);
    EXPECT_EQ(f.stride(), g.nx() + 4);
    EXPECT_EQ(f.padded().size(), static_cast<std::size_t>((g.nx() + 4) * (g.ny() + 4)));
    f.at(5, 3) = 7.0F;
    EXPECT_EQ(f.origin()[f.offset(5, 3)], 7.0F);
    EXPECT_EQ(f[g.index(5, 3)], 7.0F);
}

TEST(Field, FillGhostsCopiesTheImageOfEveryGhost)
{
    for (int level = 1; level <= 6; ++level)
    {
        const TetraGrid g = TetraGrid::create(level).value();
        for (int width = 1; width <= k_max_ghost; ++width)
        {
            Field<double> f(g, width, -1.0);
            for (int y = 0; y < g.ny(); ++y)
                for (int x = 0; x < g.nx(); ++x)
                    f.at(x, y) = static_cast<double>(g.canonical(g.index(x, y)).value);
            fill_ghosts(g, f);
            for (int y = -width; y < g.ny() + width; ++y)
                for (int x = -width; x < g.nx() + width; ++x)
                    ASSERT_EQ(f.at(x, y), static_cast<double>(g.image(x, y).value))
                        << "level " << level << " width " << width << " at " << x << "," << y;
        }
    }
}

TEST(Field, SyncTwinsMakesTwinsEqual)
{
    const TetraGrid g = TetraGrid::create(4).value();
    Field<double> f(g, 1);
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            f.at(x, y) = x * 100.0 + y;
    EXPECT_GT(max_twin_mismatch(g, f), 0.0);
    sync_twins(g, f);
    EXPECT_EQ(max_twin_mismatch(g, f), 0.0);
    EXPECT_EQ(f.at(2 * g.w(), 3), f.at(0, 3));
}

}  // namespace
}  // namespace pliant::core
