// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Time-dependent forces (sim::ForceHold::Linear, docs/physics.md §3): every Runge-Kutta stage
// evaluates the force at its own time, checked against closed-form solutions of the
// semi-discrete ODE, and the linear hold's planes after each call.

// GCC 12 reports a false -Wmaybe-uninitialized inside Eigen's AVX-512 kernels (-march=native).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include <pliant/sim/rkf45.h>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "sim_test_util.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace pliant::sim
{
namespace
{

using test::DampedOscillator;
using test::k_ode_kf;

// The largest |u - u_exact| and |v - v_exact| over all in-range nodes, for an exact solution
// that is the same at every node.
double uniform_error(const MembraneModel& m, const MembraneState& s, const DampedOscillator& exact)
{
    double worst = 0.0;
    for (int y = 0; y < m.grid().ny(); ++y)
        for (int x = 0; x < m.grid().nx(); ++x)
            worst = std::max(
                {worst, std::fabs(s.u.at(x, y) - exact.q), std::fabs(s.v.at(x, y) - exact.p)});
    return worst;
}

// A uniform acceleration growing linearly in time, r t: K annihilates constants, so u stays
// uniform and solves u'' + beta u' + k_f u = r t exactly. Fixed steps must show the method's
// fifth order; a force frozen at each step's start (or evaluated at wrong stage times) would
// leave a first-order error.
TEST(ForceHold, StagesEvaluateARampAtTheirOwnTimesFifthOrder)
{
    constexpr double r = 0.3;  // m/s^3
    MembraneSettings set = test::ode_settings();
    set.fixed_step = true;
    MembraneModel m = test::sphere_model(2, set);
    std::vector<double> errors;
    for (const int n : {8, 16, 32, 64})
    {
        set.fixed_dt = 1.0 / n;
        ASSERT_TRUE(m.set_settings(set).has_value());
        MembraneState s = MembraneState::at_rest(m.grid());
        Rkf45Workspace ws(m, 1);
        ws.accel_rate.fill(r);  // every node, twins and ghosts included
        ws.accel_time = 0.0;
        std::fill(ws.forced_rows.begin(), ws.forced_rows.end(), 1);  // the kernels read it
        for (int k = 0; k < n; ++k)
            ASSERT_EQ(step_prepared(m, s, ws).status, StepStatus::Ok);
        DampedOscillator exact;
        exact.advance(k_ode_kf, 0.0, r, s.time);
        errors.push_back(uniform_error(m, s, exact));
        ASSERT_GT(exact.q, 1e-3);  // the ramp moved the surface
    }
    for (std::size_t k = 1; k < errors.size(); ++k)
    {
        const double slope = std::log2(errors[k - 1] / errors[k]);
        std::printf("ramp, n=%d: error %.3e, slope %.2f\n", 8 << k, errors[k], slope);
        EXPECT_GT(slope, 4.5) << errors[k - 1] << " " << errors[k];
        EXPECT_LT(slope, 5.6) << errors[k - 1] << " " << errors[k];
    }
}

// The modal solution of the semi-discrete ODE (Eigen) under a force plane g held per the
// linear hold: 0 at t = 0, ramped to g over [0, tau] (the first call), then g on [tau, 2 tau]
// (a second call with the same forces). advance_to with ForceHold::Linear must follow it to
// the integrator's tolerance; the zero-order hold (g from t = 0) is far from it.
TEST(ForceHold, LinearHoldFollowsTheRampedModalSolution)
{
    constexpr double tau = 0.25;
    MembraneSettings set = test::ode_settings();
    set.rtol = 1e-9;
    set.atol = 1e-12;
    MembraneModel m = test::sphere_model(2, set);
    const core::Vec3 p0 = test::rest(m, m.grid().index(1, 1));
    const std::vector<Force> forces = {{-1, p0, 0.6, {0.4, -0.2, 0.3}}, {5, {}, 0.0, {0, 0, 1}}};
    ASSERT_TRUE(validate_forces(m, forces).has_value());

    // Modal reference: M-orthonormal modes of (K, M); q_k'' + beta q_k' + (lambda_k + k_f) q_k
    // = phi_k^T M a.
    const test::Reference ref = test::reference_assembly(m);
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(
        Eigen::MatrixXd(ref.K), Eigen::MatrixXd(ref.M.asDiagonal()));
    Rkf45Workspace probe(m, 1);
    set_forces(m, probe, forces);
    const Eigen::VectorXd g =
        eig.eigenvectors().transpose() * ref.M.asDiagonal() * test::unique_vector(m, probe.accel);
    std::vector<DampedOscillator> modes(static_cast<std::size_t>(g.size()));
    const auto exact_u = [&]()
    {
        Eigen::VectorXd q(g.size());
        for (Eigen::Index k = 0; k < g.size(); ++k)
            q(k) = modes[static_cast<std::size_t>(k)].q;
        return Eigen::VectorXd(eig.eigenvectors() * q);
    };

    for (const ForceHold hold : {ForceHold::Linear, ForceHold::Step})
    {
        set.force_hold = hold;
        ASSERT_TRUE(m.set_settings(set).has_value());
        MembraneState s = MembraneState::at_rest(m.grid());
        Rkf45Workspace ws(m, 1);
        std::fill(modes.begin(), modes.end(), DampedOscillator{});
        double worst = 0.0;
        double scale = 0.0;
        for (int call = 1; call <= 2; ++call)
        {
            const AdvanceReport r = advance_to(m, s, ws, call * tau, forces);
            ASSERT_TRUE(r.reached);
            ASSERT_EQ(s.time, call * tau);
            for (Eigen::Index k = 0; k < g.size(); ++k)
            {
                const double w2 = eig.eigenvalues()(k) + k_ode_kf;
                DampedOscillator& o = modes[static_cast<std::size_t>(k)];
                if (call == 1)
                    o.advance(w2, 0.0, g(k) / tau, tau);
                else
                    o.advance(w2, g(k), 0.0, tau);
            }
            const Eigen::VectorXd u = exact_u();
            worst = std::max(worst, (test::unique_vector(m, s.u) - u).cwiseAbs().maxCoeff());
            scale = std::max(scale, u.cwiseAbs().maxCoeff());
        }
        ASSERT_GT(scale, 1e-3);
        if (hold == ForceHold::Linear)
            EXPECT_LT(worst, 1e-7 * scale) << "linear hold against the ramped solution";
        else
            EXPECT_GT(worst, 1e-2 * scale) << "the zero-order hold should not match the ramp";
    }
}

// After a call the planes hold the new forces exactly, with no rate and nothing left of the
// old forces; a call stopped early keeps the force reached at its time.
TEST(ForceHold, EachCallEndsOnItsForcesAndClearsTheRamp)
{
    MembraneSettings set = test::ode_settings();
    set.force_hold = ForceHold::Linear;
    MembraneModel m = test::sphere_model(4, set);
    const core::TetraGrid& g = m.grid();
    const std::vector<Force> a = {{-1, test::rest(m, g.index(0, 0)), 0.4, {0.5, 0.2, -0.3}}};
    const std::vector<Force> b = {{-1, test::rest(m, g.index(g.w(), g.w() / 2)), 0.3, {0, 1, 0}},
                                  {17, {}, 0.0, {0.2, 0.2, 0.2}}};
    const auto plane_of = [&](std::span<const Force> f)
    {
        Rkf45Workspace fresh(m, 1);
        set_forces(m, fresh, f);
        return fresh.accel;
    };
    const core::Field<double> pa = plane_of(a);
    const core::Field<double> pb = plane_of(b);
    const auto expect_rows = [&](const Rkf45Workspace& ws, const core::Field<double>& plane)
    {
        for (int y = 0; y < g.ny(); ++y)
        {
            bool any = false;
            for (int x = 0; x < g.nx(); ++x)
                any = any || plane.at(x, y) != 0.0;
            if (any)  // a row with a force must be read by the kernels
            {
                EXPECT_NE(ws.forced_rows[static_cast<std::size_t>(y)], 0) << "row " << y;
            }
        }
    };

    MembraneState s = MembraneState::at_rest(g);
    Rkf45Workspace ws(m, 1);
    const core::Field<double> zero(g, 1);
    ASSERT_TRUE(advance_to(m, s, ws, 0.05, a).reached);
    EXPECT_EQ(ws.accel, pa);
    EXPECT_EQ(ws.accel_rate, zero);
    expect_rows(ws, pa);
    ASSERT_TRUE(advance_to(m, s, ws, 0.1, b).reached);
    EXPECT_EQ(ws.accel, pb);
    EXPECT_EQ(ws.accel_rate, zero);
    expect_rows(ws, pb);
    // Stopped after one step: the force reached at that time, (1 - f) b + f a.
    const double t0 = s.time;
    const AdvanceReport r = advance_to(m, s, ws, 0.2, a, {}, 1);
    ASSERT_FALSE(r.reached);
    const double f = (s.time - t0) / (0.2 - t0);
    ASSERT_GT(f, 0.0);
    ASSERT_LT(f, 1.0);
    for (std::size_t i = 0; i < ws.accel.padded().size(); ++i)
    {
        const double want = pb.padded()[i] + f * (pa.padded()[i] - pb.padded()[i]);
        ASSERT_NEAR(ws.accel.padded()[i], want, 1e-12 * (std::fabs(want) + 1.0)) << i;
    }
    EXPECT_EQ(ws.accel_rate, zero);
    expect_rows(ws, ws.accel);
    // A finger sliding for 20 frames: the planes follow it, and what the workspace keeps (the
    // written offsets, the forced rows) is the last frame's force, not the path.
    for (int frame = 1; frame <= 20; ++frame)
    {
        const std::vector<Force> at = {
            {-1, test::rest(m, g.index(frame * g.w() / 10, g.w() / 2)), 0.3, {0.0, 0.0, 1.0}}};
        ASSERT_TRUE(advance_to(m, s, ws, 0.2 + 0.01 * frame, at).reached);
        if (frame == 20)
        {
            EXPECT_EQ(ws.accel, plane_of(at));
            std::size_t nonzero = 0;
            for (const std::int64_t off : ws.touched)
                nonzero += ws.accel.padded()[static_cast<std::size_t>(off)] != 0.0 ? 1 : 0;
            EXPECT_EQ(nonzero, ws.touched.size());
            for (int y = 0; y < g.ny(); ++y)
            {
                bool any = false;
                for (int x = 0; x < g.nx(); ++x)
                    any = any || ws.accel.at(x, y) != 0.0;
                EXPECT_EQ(ws.forced_rows[static_cast<std::size_t>(y)] != 0, any) << "row " << y;
            }
        }
    }
    // No forces: the ramp goes down to nothing, then set_forces-style planes are all zero.
    ASSERT_TRUE(advance_to(m, s, ws, 0.5, {}).reached);
    EXPECT_EQ(ws.accel, zero);
    EXPECT_EQ(ws.accel_rate, zero);
    EXPECT_EQ(ws.accel_end, zero);
}

}  // namespace
}  // namespace pliant::sim
