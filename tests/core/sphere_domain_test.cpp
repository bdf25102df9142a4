// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The domain tetrahedron on the unit sphere (core::sphere_domain): both maps put every node on the
// sphere with twins equal and no triangle inverted; the equal-area map's cells converge to equal
// areas (checked with the spherical-triangle area formula, independent of the map's
// construction), and its face-centre fans cut exact area fractions; the gnomonic map's do not.

#include <pliant/core/sphere_domain.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace pliant::core
{
namespace
{

Vec3 at(const Vec3Field<double>& f, NodeIndex n)
{
    return {f[0][n], f[1][n], f[2][n]};
}

// Area of the spherical triangle a, b, c (unit vectors; Van Oosterom & Strackee 1983), signed by
// the orientation det(a, b, c).
double spherical_area(const Vec3& a, const Vec3& b, const Vec3& c)
{
    const double det = dot(a, cross(b, c));
    return 2.0 * std::atan2(det, 1.0 + dot(a, b) + dot(b, c) + dot(c, a));
}

struct AreaStats
{
    double sum = 0.0;
    double min = 1e300;
    double max = 0.0;
};

AreaStats areas(const TetraGrid& grid, const Vec3Field<double>& f)
{
    AreaStats s;
    const auto nodes = grid.node_of_unique();
    for (const auto& t : grid.triangles())
    {
        const double a = spherical_area(at(f, nodes[t[0]]), at(f, nodes[t[1]]), at(f, nodes[t[2]]));
        s.sum += a;
        s.min = std::min(s.min, a);
        s.max = std::max(s.max, a);
    }
    return s;
}

constexpr SphereMap k_maps[] = {SphereMap::Gnomonic, SphereMap::EqualArea};

TEST(SphereDomain, NamesRoundTripAndUnknownNamesAreRefused)
{
    for (const SphereMap m : k_maps)
        EXPECT_EQ(sphere_map_from_string(to_string(m)), m);
    EXPECT_FALSE(sphere_map_from_string("equal_area").has_value());
    EXPECT_FALSE(sphere_map_from_string("").has_value());
}

TEST(SphereDomain, CornersUnitLengthTwinsAndGhosts)
{
    const double r = 1.0 / std::sqrt(3.0);
    const Vec3 corner[4] = {{r, r, r}, {r, -r, -r}, {-r, r, -r}, {-r, -r, r}};
    for (const SphereMap m : k_maps)
        for (int level = 1; level <= 6; ++level)
        {
            const TetraGrid grid = TetraGrid::create(level).value();
            const auto c = grid.corners();
            for (int k = 0; k < 4; ++k)
            {
                const GridCoord g = grid.coord(c[static_cast<std::size_t>(k)]);
                const Vec3 p = sphere_point(grid, g.x, g.y, m);
                EXPECT_LT(norm(p - corner[k]), 1e-15) << to_string(m) << " corner " << k;
            }
            const double radius = 2.5;
            const Vec3Field<double> f = sphere_domain(grid, m, radius, 2);
            for (int y = -2; y < grid.ny() + 2; ++y)
                for (int x = -2; x < grid.nx() + 2; ++x)
                {
                    const NodeIndex n = grid.image(x, y);
                    for (int k = 0; k < 3; ++k)
                        ASSERT_EQ(f[static_cast<std::size_t>(k)].at(x, y),
                                  f[static_cast<std::size_t>(k)][grid.canonical(n)])
                            << to_string(m) << " level " << level << " (" << x << ", " << y << ")";
                    if (x >= 0 && y >= 0 && x < grid.nx() && y < grid.ny())
                    {
                        ASSERT_NEAR(norm(at(f, grid.index(x, y))), radius, 1e-14);
                    }
                }
        }
}

TEST(SphereDomain, NoInvertedTriangleAndTheAreasCoverTheSphere)
{
    for (const SphereMap m : k_maps)
        for (int level = 1; level <= 7; ++level)
        {
            const TetraGrid grid = TetraGrid::create(level).value();
            const AreaStats s = areas(grid, sphere_domain(grid, m));
            EXPECT_GT(s.min, 0.0) << to_string(m) << " level " << level;
            EXPECT_NEAR(s.sum, 4.0 * std::numbers::pi, 1e-11) << to_string(m) << " level " << level;
        }
}

// An area-preserving map gives a grid triangle 4 pi / (4 W^2) up to the O(h) bending of its
// image, except where the triangle straddles a crease of the map: the lines from each face centre
// to its corners (where the construction switches sub-triangle) and the corners themselves. There
// the straight-edged cell is a poor sample of a bent image, at every level, so the median and the
// 90th percentile of the deviation must halve per level while the worst cells stay bounded. The
// gnomonic map's cells keep a spread of about 1:27 at every level (area scale 9 at a face centre,
// 1/3 at a corner).
TEST(SphereDomain, EqualAreaCellsConvergeToEqualAreasOffTheCreases)
{
    double previous_median = 1e300;
    double previous_p90 = 1e300;
    for (int level = 4; level <= 8; ++level)
    {
        const TetraGrid grid = TetraGrid::create(level).value();
        const double mean = 4.0 * std::numbers::pi / static_cast<double>(grid.face_count());
        const auto f = sphere_domain(grid, SphereMap::EqualArea);
        const auto nodes = grid.node_of_unique();
        std::vector<double> dev;
        for (const auto& t : grid.triangles())
            dev.push_back(std::fabs(
                spherical_area(at(f, nodes[t[0]]), at(f, nodes[t[1]]), at(f, nodes[t[2]])) / mean -
                1.0));
        std::sort(dev.begin(), dev.end());
        const double median = dev[dev.size() / 2];
        const double p90 = dev[dev.size() * 9 / 10];
        std::printf(
            "level %d: equal-area cells' deviation from the mean area: median %.4f, "
            "90th percentile %.4f, max %.4f\n",
            level, median, p90, dev.back());
        EXPECT_LT(median, previous_median * 0.6) << "level " << level;
        EXPECT_LT(p90, previous_p90 * 0.6) << "level " << level;
        EXPECT_LT(dev.back(), 0.65) << "level " << level;
        previous_median = median;
        previous_p90 = p90;
        const AreaStats gn = areas(grid, sphere_domain(grid, SphereMap::Gnomonic));
        EXPECT_GT(gn.max / gn.min, 10.0) << "level " << level;
    }
    EXPECT_LT(previous_median, 0.002);
}

// The construction's defining property, checked with the area formula: the face-centre fan to the
// edge nodes of each face cuts the sphere's face into areas proportional to the edge parameter.
// Face abc is the grid's triangle a (0,0), b (W,0), c (W,W); its centre is -d.
TEST(SphereDomain, EqualAreaFanToEdgeNodesCutsExactAreaFractions)
{
    const TetraGrid grid = TetraGrid::create(5).value();
    const int w = grid.w();
    const Vec3 centre = normalized(Vec3{1.0, 1.0, -1.0});
    const Vec3 a = sphere_point(grid, 0, 0, SphereMap::EqualArea);
    for (int k = 0; k <= w; ++k)
    {
        // edge a -> b: node (k, 0)
        const Vec3 e = sphere_point(grid, k, 0, SphereMap::EqualArea);
        const double fraction = spherical_area(centre, a, e) / (std::numbers::pi / 3.0);
        EXPECT_NEAR(fraction, static_cast<double>(k) / w, 1e-13) << "k = " << k;
        // the gnomonic map's edge points are evenly spaced chords instead: not area fractions
        if (k == w / 4)
        {
            const Vec3 g = sphere_point(grid, k, 0, SphereMap::Gnomonic);
            EXPECT_GT(std::fabs(spherical_area(centre, a, g) / (std::numbers::pi / 3.0) - 0.25),
                      0.01);
        }
    }
}

}  // namespace
}  // namespace pliant::core
