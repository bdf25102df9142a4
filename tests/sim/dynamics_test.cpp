// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Physics of the membrane against analytic results: Y_lm frequencies on a sphere, energy
// conservation without damping, monotone decay with damping, and a pull that relaxes back.

#include <pliant/sim/rkf45.h>

#include <gtest/gtest.h>

#include "sim_test_util.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace pliant::sim
{
namespace
{

constexpr double k_pi = 3.14159265358979323846;

// Mass-weighted projection of u on the zonal harmonic of degree l.
double amplitude(const MembraneModel& m, const core::Field<double>& u, int l)
{
    double num = 0.0;
    double den = 0.0;
    for (const core::NodeIndex n : m.grid().node_of_unique())
    {
        const double y = test::zonal(l, test::rest(m, n));
        num += m.unique_mass(n) * u[n] * y;
        den += m.unique_mass(n) * y * y;
    }
    return num / den;
}

// Both precisions of a full step (Precision, docs/physics.md §9) pass the physics checks.
class DynamicsIn : public ::testing::TestWithParam<Precision>
{
};

INSTANTIATE_TEST_SUITE_P(Precision, DynamicsIn,
                         ::testing::Values(Precision::Double, Precision::Mixed),
                         [](const ::testing::TestParamInfo<Precision>& p)
                         { return std::string(to_string(p.param)); });

TEST_P(DynamicsIn, SphericalHarmonicFrequencies)
{
    // r = 1.5 m, T = 2 N/m, rho = 0.5 kg/m^2 (wave speed 2 m/s), k_f = 0.5 1/s^2.
    MembraneSettings set;
    set.precision = GetParam();
    set.T = 2.0;
    set.rho = 0.5;
    set.k_f = 0.5;
    // Fixed steps of 2.5 ms, below the explicit limit (~0.9 h_e / c, docs/physics.md §5): the
    // time-stepping phase error is ~(omega dt)^4 / 1000, far below the 0.5 % asked.
    set.fixed_step = true;
    set.fixed_dt = 0.0025;
    const double r = 1.5;
    MembraneModel m = test::sphere_model(7, set, r);
    // All four modes in one run (they are linear and nearly orthogonal in the mass inner
    // product; the projection on Y_l0 sees the others only at the discretisation level).
    double omega[5] = {};
    double period[5] = {};
    for (int l = 1; l <= 4; ++l)
    {
        omega[l] = std::sqrt(set.T * l * (l + 1) / (set.rho * r * r) + set.k_f);
        period[l] = 2.0 * k_pi / omega[l];
    }
    MembraneState s = MembraneState::at_rest(m.grid());
    test::set_field(m, s.u,
                    [](const core::Vec3& p)
                    {
                        double u = 0.0;
                        for (int l = 1; l <= 4; ++l)
                            u += 0.01 * test::zonal(l, p);
                        return u;
                    });
    Rkf45Workspace ws(m);
    // cos(omega t) crosses zero at T/4 and 3T/4: sample until 0.85 T of the slowest mode, 48+
    // samples per period of the fastest, and interpolate the crossings linearly (the half
    // period between them cancels any common offset).
    std::vector<double> crossings[5];
    double t_prev = 0.0;
    double a_prev[5] = {};
    for (int l = 1; l <= 4; ++l)
        a_prev[l] = amplitude(m, s.u, l);
    const int samples = 120;
    for (int k = 1; k <= samples; ++k)
    {
        const double t = 0.85 * period[1] * k / samples;
        ASSERT_TRUE(advance_to(m, s, ws, t, {}).reached);
        const double ts = s.time;  // whole fixed steps: at most one step short of t
        for (int l = 1; l <= 4; ++l)
        {
            const double a = amplitude(m, s.u, l);
            if ((a_prev[l] > 0.0) != (a > 0.0))
                crossings[l].push_back(t_prev + (ts - t_prev) * a_prev[l] / (a_prev[l] - a));
            a_prev[l] = a;
        }
        t_prev = ts;
    }
    for (int l = 1; l <= 4; ++l)
    {
        ASSERT_GE(crossings[l].size(), 2U) << "l = " << l;
        const double measured = k_pi / (crossings[l][1] - crossings[l][0]);
        std::printf("l = %d: omega %.6f, expected %.6f, ratio %.5f\n", l, measured, omega[l],
                    measured / omega[l]);
        EXPECT_NEAR(measured / omega[l], 1.0, 0.005) << "l = " << l;
    }
}

MembraneState two_mode_state(const MembraneModel& m)
{
    MembraneState s = MembraneState::at_rest(m.grid());
    test::set_field(
        m, s.u, [](const core::Vec3& p) { return 0.02 * test::zonal(2, p) + 0.01 * p.x * p.y; });
    test::set_field(m, s.v, [](const core::Vec3& p) { return 0.01 * test::zonal(3, p); });
    return s;
}

TEST_P(DynamicsIn, EnergyIsConservedWithoutDamping)
{
    MembraneSettings set;
    set.precision = GetParam();
    set.k_f = 0.3;
    set.rtol = 1e-7;
    set.atol = 1e-10;
    MembraneModel m = test::sphere_model(4, set);
    MembraneState s = two_mode_state(m);
    Rkf45Workspace ws(m);
    const double e0 = energy(m, s).total();
    ASSERT_GT(e0, 0.0);
    const double period = 2.0 * k_pi / std::sqrt(6.0 + set.k_f);  // the l = 2 mode
    double worst = 0.0;
    for (int k = 1; k <= 100; ++k)
    {
        ASSERT_TRUE(advance_to(m, s, ws, 20.0 * period * k / 100, {}).reached);
        worst = std::max(worst, std::fabs(energy(m, s).total() - e0) / e0);
    }
    std::printf("largest relative energy change over 20 periods: %.3e (%llu steps)\n", worst,
                static_cast<unsigned long long>(s.tick));
    EXPECT_LT(worst, 1e-4);
}

TEST_P(DynamicsIn, EnergyDecreasesMonotonicallyWithDamping)
{
    MembraneSettings set;
    set.precision = GetParam();
    set.k_f = 0.3;
    set.beta = 0.3;
    set.rtol = 1e-6;
    MembraneModel m = test::sphere_model(5, set);
    MembraneState s = two_mode_state(m);
    Rkf45Workspace ws(m);
    double previous = energy(m, s).total();
    const double e0 = previous;
    for (int k = 1; k <= 100; ++k)
    {
        ASSERT_TRUE(advance_to(m, s, ws, 0.1 * k, {}).reached);
        const double e = energy(m, s).total();
        ASSERT_LT(e, previous) << "t = " << s.time;
        previous = e;
    }
    // Energy decays at least like exp(-beta t) for the slowest part (kinetic share ~1/2).
    EXPECT_LT(previous, 0.5 * e0);
}

TEST(Dynamics, ZeroForceAtRestStaysAtRest)
{
    MembraneSettings set;
    set.k_f = 1.0;
    MembraneModel m = test::sphere_model(4, set);
    MembraneState s = MembraneState::at_rest(m.grid());
    Rkf45Workspace ws(m);
    ASSERT_TRUE(advance_to(m, s, ws, 1.0, {}).reached);
    for (const double value : s.u.padded())
        ASSERT_EQ(value, 0.0);
    EXPECT_EQ(energy(m, s).total(), 0.0);
}

TEST(Dynamics, PullMovesTheFaceOutwardAndRelaxes)
{
    MembraneSettings set;
    set.k_f = 1.0;
    set.beta = 2.0;
    set.rtol = 1e-5;
    MembraneModel m = test::sphere_model(5, set);
    const core::TetraGrid& g = m.grid();
    const int w = g.w();
    const std::int64_t face =
        2 * (static_cast<std::int64_t>(w / 4) * 2 * w + w / 2);  // cell (W/2, W/4)
    const core::NodeIndex corner = g.index(w / 2, w / 4);
    const core::Vec3 outward = test::rest(m, corner) * 0.5;  // |P| = 1: 0.5 N outward
    const Force pull{face, {}, 0.0, outward};
    ASSERT_TRUE(validate_forces(m, std::span<const Force>(&pull, 1)).has_value());

    MembraneState s = MembraneState::at_rest(g);
    Rkf45Workspace ws(m);
    ASSERT_TRUE(advance_to(m, s, ws, 1.0, std::span<const Force>(&pull, 1)).reached);
    const double pulled = s.u[corner];
    EXPECT_GT(pulled, 0.0);
    // Far from the face (over 1 m away on the unit sphere) the displacement is much smaller.
    double far = 0.0;
    for (const core::NodeIndex n : g.node_of_unique())
        if (core::norm(test::rest(m, n) - test::rest(m, corner)) > 1.0)
            far = std::max(far, std::fabs(s.u[n]));
    EXPECT_LT(far, 0.1 * pulled);

    ASSERT_TRUE(advance_to(m, s, ws, 16.0, {}).reached);
    double rest_u = 0.0;
    double rest_v = 0.0;
    for (const core::NodeIndex n : g.node_of_unique())
    {
        rest_u = std::max(rest_u, std::fabs(s.u[n]));
        rest_v = std::max(rest_v, std::fabs(s.v[n]));
    }
    EXPECT_LT(rest_u, 1e-3 * pulled);
    EXPECT_LT(rest_v, 1e-3 * pulled);
}

TEST(Dynamics, PointForceSpreadsOverTheRadius)
{
    MembraneSettings set;
    set.k_f = 1.0;
    MembraneModel m = test::sphere_model(4, set);
    const core::Vec3 point{0.0, 0.0, 1.0};
    const Force f{-1, point, 0.3, {0.0, 0.0, 2.0}};
    Rkf45Workspace ws(m);
    set_forces(m, ws, std::span<const Force>(&f, 1));
    // The nodal forces m_i a_i add up to F . N summed with the weights: for a radial force on a
    // sphere near the pole that is close to |F|, all applied within the radius.
    double total = 0.0;
    for (const core::NodeIndex n : m.grid().node_of_unique())
    {
        const double a = ws.accel[n];
        if (a != 0.0)
        {
            EXPECT_LT(core::norm(test::rest(m, n) - point), 0.3);
        }
        total += a * m.unique_mass(n);
    }
    EXPECT_GT(total, 0.9 * 2.0);
    EXPECT_LE(total, 2.0 + 1e-12);
    // A second set replaces the first.
    set_forces(m, ws, {});
    for (const double a : ws.accel.padded())
        ASSERT_EQ(a, 0.0);
}

// MembraneSettings::max_force: a force longer than the limit acts as the same direction at the
// limit's length (the nodal forces are those of the scaled force, to rounding), a shorter one
// acts bit for bit as without a limit, and a force near the double range's end (1e300 N, whose
// squared length overflows) is still scaled, not dropped or turned into inf.
TEST(Dynamics, AForceAboveTheLimitActsAtTheLimit)
{
    EXPECT_EQ(limit_force({3.0, 4.0, 0.0}, 10.0).x, 3.0);       // shorter: the same bits
    EXPECT_EQ(limit_force({3e300, 4e300, 0.0}, 0.0).y, 4e300);  // 0: no limit
    const core::Vec3 huge = limit_force({3e300, -4e300, 0.0}, 2.5);
    EXPECT_NEAR(huge.x, 1.5, 1e-15);
    EXPECT_NEAR(huge.y, -2.0, 1e-15);
    EXPECT_EQ(huge.z, 0.0);

    MembraneSettings set;
    set.k_f = 1.0;
    set.max_force = 2.0;
    MembraneModel limited = test::sphere_model(4, set);
    set.max_force = 0.0;
    MembraneModel free = test::sphere_model(4, set);
    const core::Vec3 point{0.0, 0.0, 1.0};
    const auto accel = [](const MembraneModel& m, const Force& f)
    {
        Rkf45Workspace ws(m);
        set_forces(m, ws, std::span<const Force>(&f, 1));
        return ws.accel;
    };
    const Force below{-1, point, 0.3, {0.0, 0.6, 1.8}};  // |F| = 1.897 N
    const auto a = accel(limited, below);
    const auto b = accel(free, below);
    for (std::size_t k = 0; k < a.padded().size(); ++k)
        ASSERT_EQ(a.padded()[k], b.padded()[k]);
    for (const double scale : {1.0e3, 1.0e200, 1.0e300})
    {
        const Force above{-1, point, 0.3, {0.0, 0.6 * scale, 1.8 * scale}};
        const Force at{-1, point, 0.3, below.vector * (2.0 / core::norm(below.vector))};
        const auto c = accel(limited, above);
        const auto d = accel(free, at);
        double largest = 0.0;
        for (std::size_t k = 0; k < c.padded().size(); ++k)
        {
            ASSERT_TRUE(std::isfinite(c.padded()[k]));
            EXPECT_NEAR(c.padded()[k], d.padded()[k], 1e-13 * std::abs(d.padded()[k]))
                << "scale " << scale << " at " << k;
            largest = std::max(largest, std::abs(c.padded()[k]));
        }
        EXPECT_GT(largest, 0.0);
    }
}

// The default limit of sessions (sim::default_max_force): on a sphere of radius r the bounding
// box's half-diagonal is R = sqrt(3) r, and the limit (rho pi (R/10)^2 k_f + 2 pi T) 2R.
TEST(Dynamics, TheDefaultForceLimitFollowsItsFormula)
{
    MembraneSettings set;
    set.T = 2.0;
    set.rho = 0.5;
    set.k_f = 3.0;
    const double r = 1.5;
    const MembraneModel m = test::sphere_model(5, set, r);
    const double limit = default_max_force(m.grid(), m.rest_positions(), m.settings());
    // The grid's nodes reach the sphere's extreme points (the octahedron's vertices).
    const double big_r = std::sqrt(3.0) * r;
    const double expect =
        (0.5 * k_pi * (0.1 * big_r) * (0.1 * big_r) * 3.0 + 2.0 * k_pi * 2.0) * 2.0 * big_r;
    EXPECT_NEAR(limit, expect, 1e-12 * expect);
}

}  // namespace
}  // namespace pliant::sim
