// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// RKF45 against the exact solution of the semi-discrete membrane ODE on a small sphere: modal
// decomposition of (K, M) with Eigen, each mode a damped oscillator solved in closed form.

// GCC 12 reports a false -Wmaybe-uninitialized inside Eigen's AVX-512 kernels (-march=native).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include <pliant/sim/rkf45.h>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "sim_test_util.h"
#include "support/fp_traps.h"

#include <cmath>
#include <cstdio>

namespace pliant::sim
{
namespace
{

using test::ode_settings;

double u0_of(const core::Vec3& p)
{
    return 0.1 * (p.x + p.y * p.y - 0.3 * p.z);
}
double v0_of(const core::Vec3& p)
{
    return 0.05 * p.z;
}

// Exact u(t), v(t) on unique vertices.
class Exact
{
public:
    explicit Exact(const MembraneModel& m)
    {
        const test::Reference ref = test::reference_assembly(m);
        const Eigen::MatrixXd K = Eigen::MatrixXd(ref.K);
        const Eigen::MatrixXd M = ref.M.asDiagonal();
        Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(K, M);
        phi_ = eig.eigenvectors();  // M-orthonormal
        lambda_ = eig.eigenvalues();
        core::Field<double> u(m.grid(), 1);
        core::Field<double> v(m.grid(), 1);
        test::set_field(m, u, u0_of);
        test::set_field(m, v, v0_of);
        q0_ = phi_.transpose() * M * test::unique_vector(m, u);
        p0_ = phi_.transpose() * M * test::unique_vector(m, v);
    }

    [[nodiscard]] std::pair<Eigen::VectorXd, Eigen::VectorXd> at(double t) const
    {
        Eigen::VectorXd q(q0_.size());
        Eigen::VectorXd p(q0_.size());
        for (Eigen::Index k = 0; k < q0_.size(); ++k)
        {
            test::DampedOscillator o{q0_(k), p0_(k)};
            o.advance(lambda_(k) + test::k_ode_kf, 0.0, 0.0, t);
            q(k) = o.q;
            p(k) = o.p;
        }
        return {phi_ * q, phi_ * p};
    }

private:
    Eigen::MatrixXd phi_;
    Eigen::VectorXd lambda_, q0_, p0_;
};

/// The ODE test's settings with steps of 10 ms, fixed or adaptive, on a level-3 sphere.
MembraneModel model_in_steps_of_10_ms(bool fixed = true)
{
    MembraneSettings set = ode_settings();
    set.fixed_step = fixed;
    set.fixed_dt = 0.01;
    return test::sphere_model(3, set);
}

MembraneState initial_state(const MembraneModel& m)
{
    MembraneState s = MembraneState::at_rest(m.grid());
    test::set_field(m, s.u, u0_of);
    test::set_field(m, s.v, v0_of);
    return s;
}

double max_error(const MembraneModel& m, const MembraneState& s, const Exact& exact)
{
    const auto [u, v] = exact.at(s.time);
    return std::max((test::unique_vector(m, s.u) - u).cwiseAbs().maxCoeff(),
                    (test::unique_vector(m, s.v) - v).cwiseAbs().maxCoeff());
}

double slope(double e_coarse, double e_fine)
{
    return std::log2(e_coarse / e_fine);
}

TEST(Rkf45, GlobalErrorIsFifthOrder)
{
    MembraneSettings set = ode_settings();
    set.fixed_step = true;
    MembraneModel m = test::sphere_model(2, set);
    const Exact exact(m);
    std::vector<double> errors;
    for (const int n : {32, 64, 128, 256})
    {
        set.fixed_dt = 1.0 / n;
        ASSERT_TRUE(m.set_settings(set).has_value());
        MembraneState s = initial_state(m);
        Rkf45Workspace ws(m, 1);
        for (int k = 0; k < n; ++k)
            ASSERT_EQ(step(m, s, ws, {}).status, StepStatus::Ok);
        EXPECT_NEAR(s.time, 1.0, 1e-12);
        errors.push_back(max_error(m, s, exact));
    }
    for (std::size_t k = 1; k < errors.size(); ++k)
    {
        std::printf("global error n=%d: %.3e\n", 32 << k, errors[k]);
        EXPECT_GT(slope(errors[k - 1], errors[k]), 4.6) << errors[k - 1] << " " << errors[k];
        EXPECT_LT(slope(errors[k - 1], errors[k]), 5.6) << errors[k - 1] << " " << errors[k];
    }
}

TEST(Rkf45, LocalErrorsShowOrdersFiveAndFour)
{
    // One step from the same state: the propagated (5th-order) solution's local error is
    // O(h^6); the embedded estimate (the 4th-order solution's local error) is O(h^5).
    MembraneSettings set = ode_settings();
    set.fixed_step = true;
    set.rtol = 0.0;
    set.atol = 1.0;  // the reported error norm is then max |y5 - y4|
    MembraneModel m = test::sphere_model(2, set);
    const Exact exact(m);
    std::vector<double> local;
    std::vector<double> estimate;
    for (const double h : {0.04, 0.02, 0.01})
    {
        set.fixed_dt = h;
        ASSERT_TRUE(m.set_settings(set).has_value());
        MembraneState s = initial_state(m);
        Rkf45Workspace ws(m, 1);
        const StepReport r = step(m, s, ws, {});
        local.push_back(max_error(m, s, exact));
        estimate.push_back(r.error);
    }
    for (std::size_t k = 1; k < local.size(); ++k)
    {
        EXPECT_NEAR(slope(local[k - 1], local[k]), 6.0, 0.5) << local[k - 1] << " " << local[k];
        EXPECT_NEAR(slope(estimate[k - 1], estimate[k]), 5.0, 0.4)
            << estimate[k - 1] << " " << estimate[k];
    }
}

TEST(Rkf45, AdaptiveStepMeetsItsTolerance)
{
    MembraneSettings set = ode_settings();
    MembraneModel m0 = test::sphere_model(2, set);
    const Exact exact(m0);
    double previous = 1.0;
    for (const double rtol : {1e-4, 1e-6, 1e-8})
    {
        set.rtol = rtol;
        set.atol = rtol * 1e-2;
        MembraneModel m = test::sphere_model(2, set);
        MembraneState s = initial_state(m);
        Rkf45Workspace ws(m, 1);
        const AdvanceReport r = advance_to(m, s, ws, 2.0, {});
        EXPECT_TRUE(r.reached);
        EXPECT_EQ(s.time, 2.0);
        EXPECT_FALSE(has_flag(r.status, StepStatus::MinStepReached));
        const double err = max_error(m, s, exact);
        // Solution magnitude ~0.2: the global error stays within a small multiple of the local
        // tolerance and falls with it.
        EXPECT_LT(err, 20.0 * rtol * 0.2) << "rtol " << rtol << " steps " << r.steps;
        EXPECT_LT(err, previous);
        previous = err;
    }
}

TEST(Rkf45, RejectsAndShrinksAnOversizedStep)
{
    MembraneSettings set = ode_settings();
    set.rtol = 1e-8;
    set.atol = 1e-10;
    set.dt_initial = 0.05;
    MembraneModel m = test::sphere_model(3, set);
    MembraneState s = initial_state(m);
    Rkf45Workspace ws(m, 1);
    const StepReport r = step(m, s, ws, {});
    EXPECT_TRUE(has_flag(r.status, StepStatus::Rejected));
    EXPECT_GT(r.rejections, 0U);
    EXPECT_LT(r.dt, 0.05);
    EXPECT_LE(r.error, 1.0);
    EXPECT_EQ(s.tick, 1U);
    EXPECT_EQ(s.time, r.dt);
}

// Rejections go on until dt_min, however many it takes: with min_shrink 0.95 each retry shrinks h
// by 0.9, so 1 ms to 1e-13 s takes 219 of them; a cap of 200 ended the step as NonFinite, the
// state finite (pliant simulate said "the state became non-finite" and stopped).
TEST(Rkf45, ManyRejectionsEndAtDtMinNotAsNonFinite)
{
    MembraneSettings set = ode_settings();
    set.rtol = 0.0;
    set.atol = 1e-300;  // no trial meets it: every one is rejected down to dt_min
    set.min_shrink = 0.95;
    set.dt_initial = set.dt_max = 1e-3;
    set.dt_min = 1e-13;
    MembraneModel m = test::sphere_model(3, set);
    MembraneState s = initial_state(m);
    s.u.at(5, 3) = 1e-3;  // a displacement, so the error is not 0
    m.sync(s.u);
    Rkf45Workspace ws(m, 1);
    const StepReport r = step(m, s, ws, {});
    EXPECT_FALSE(has_flag(r.status, StepStatus::NonFinite));
    EXPECT_TRUE(has_flag(r.status, StepStatus::MinStepReached));
    EXPECT_GT(r.rejections, 200U);
    EXPECT_EQ(r.dt, 1e-13);
    EXPECT_EQ(s.tick, 1U);
}

// AdvanceReport::at_min_steps counts the accepted steps flagged MinStepReached (pliant simulate
// reports them): every one with dt_min = dt_max and a tolerance no step of that size meets, none
// with a free step size.
TEST(Rkf45, AdvanceCountsTheStepsAtDtMin)
{
    MembraneSettings set = ode_settings();
    set.rtol = 1e-10;
    set.atol = 1e-12;
    set.dt_min = set.dt_initial = set.dt_max = 0.02;
    MembraneModel m = test::sphere_model(3, set);
    MembraneState s = initial_state(m);
    Rkf45Workspace ws(m, 1);
    const AdvanceReport r = advance_to(m, s, ws, 0.1, {});
    EXPECT_TRUE(has_flag(r.status, StepStatus::MinStepReached));
    EXPECT_EQ(r.steps, 5U);
    EXPECT_EQ(r.at_min_steps, 5U);

    set = ode_settings();
    MembraneModel free = test::sphere_model(3, set);
    MembraneState s2 = initial_state(free);
    Rkf45Workspace ws2(free, 1);
    const AdvanceReport r2 = advance_to(free, s2, ws2, 0.1, {});
    EXPECT_GT(r2.steps, 0U);
    EXPECT_EQ(r2.at_min_steps, 0U);
}

TEST(Rkf45, NonFiniteTrialKeepsTheLastGoodState)
{
    pliant::test::FpTrapsOff traps_off;
    MembraneModel m = model_in_steps_of_10_ms();
    MembraneState s = initial_state(m);
    s.u.at(5, 3) = 1e308;  // K u overflows
    m.sync(s.u);
    const std::uint64_t before = s.hash();
    Rkf45Workspace ws(m, 1);
    const StepReport r = step(m, s, ws, {});
    EXPECT_TRUE(has_flag(r.status, StepStatus::NonFinite));
    EXPECT_EQ(s.hash(), before);
    EXPECT_EQ(s.tick, 0U);
}

TEST(Rkf45, FixedStepAdvanceTakesWholeSteps)
{
    MembraneModel m = model_in_steps_of_10_ms();
    MembraneState s = initial_state(m);
    Rkf45Workspace ws(m, 1);
    AdvanceReport r = advance_to(m, s, ws, 0.105, {});
    EXPECT_EQ(r.steps, 10U);
    EXPECT_EQ(s.tick, 10U);
    r = advance_to(m, s, ws, 0.2, {});
    EXPECT_EQ(s.tick, 20U);
    EXPECT_NEAR(s.time, 0.2, 1e-12);
}

// A target already passed takes no step and leaves the state where it is; a non-finite target is
// a contract failure (it would step until max_steps), said as such.
TEST(Rkf45, AdvanceToAnEarlierTargetTakesNoStepAndANonFiniteOneIsRefused)
{
    MembraneModel m = model_in_steps_of_10_ms();
    MembraneState s = initial_state(m);
    Rkf45Workspace ws(m, 1);
    (void)advance_to(m, s, ws, 0.1, {});
    const double time = s.time;
    const AdvanceReport earlier = advance_to(m, s, ws, 0.05, {});
    EXPECT_TRUE(earlier.reached);
    EXPECT_EQ(earlier.steps, 0U);
    EXPECT_EQ(s.time, time);
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_DEATH((void)advance_to(m, s, ws, std::nan(""), {}),
                 "advance_to: the target time is not finite");
    EXPECT_DEATH((void)energy(m, MembraneState::at_rest(core::TetraGrid::create(2).value())),
                 "energy: the state's u and v are not ghost-1 planes of the model's level");
}

// A fixed step far below the time rounding slack (1e-15 s against 1e-12 s): advance_to takes
// the whole steps that fit, 3,000 to 3e-12 s and none to 0, where an absolute slack took a
// thousand more (and `pliant simulate`'s frame 0, the rest state, came out 1e-12 s in).
TEST(Rkf45, AFixedStepBelowTheRoundingSlackTakesOnlyTheStepsThatFit)
{
    MembraneSettings set = ode_settings();
    set.fixed_step = true;
    set.fixed_dt = 1e-15;
    MembraneModel m = test::sphere_model(3, set);
    MembraneState s = initial_state(m);
    Rkf45Workspace ws(m, 1);
    const AdvanceReport none = advance_to(m, s, ws, 0.0, {});
    EXPECT_TRUE(none.reached);
    EXPECT_EQ(none.steps, 0U);
    const AdvanceReport some = advance_to(m, s, ws, 3e-12, {});
    EXPECT_TRUE(some.reached);
    EXPECT_EQ(some.steps, 3000U);
    EXPECT_NEAR(s.time, 3e-12, 1e-18);
}

// A stop asked for between steps (Ctrl-C in `pliant simulate`) ends advance_to before its next
// step: the state is that of the last whole step, the same as that many steps without a stop.
TEST(Rkf45, AdvanceStopsBeforeTheStepAfterAStopIsAsked)
{
    struct StopAfterPolls final : core::ProgressSink
    {
        mutable int polls = 0;
        int allowed = 0;
        void update(std::string_view, double) noexcept override {}
        bool stop_requested() const noexcept override { return ++polls > allowed; }
    };
    for (const bool fixed : {true, false})
    {
        MembraneModel m = model_in_steps_of_10_ms(fixed);
        MembraneState s = initial_state(m);
        Rkf45Workspace ws(m, 1);
        StopAfterPolls stop;
        stop.allowed = 4;
        const AdvanceReport r = advance_to(m, s, ws, 1.0, {}, {}, 10'000'000, &stop);
        EXPECT_TRUE(r.stopped);
        EXPECT_FALSE(r.reached);
        EXPECT_EQ(r.steps, 4U);
        EXPECT_EQ(s.tick, 4U);
        EXPECT_EQ(stop.polls, 5);
        // The same four steps, unstopped, one advance each.
        MembraneState ref = initial_state(m);
        Rkf45Workspace ws_ref(m, 1);
        for (int k = 0; k < 4; ++k)
            (void)step(m, ref, ws_ref, {});
        EXPECT_EQ(s.hash(), ref.hash()) << (fixed ? "fixed" : "adaptive");
        EXPECT_EQ(s.time, ref.time);
    }
}

double largest_omega(const MembraneModel& m)
{
    // The exact largest frequency: omega^2 = largest eigenvalue of (K + k_f M, M).
    const test::Reference ref = test::reference_assembly(m);
    const Eigen::MatrixXd M = ref.M.asDiagonal();
    const Eigen::MatrixXd K = Eigen::MatrixXd(ref.K) + m.settings().k_f * M;
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(K, M, Eigen::EigenvaluesOnly);
    return std::sqrt(eig.eigenvalues().maxCoeff());
}

/// Energy after `steps` fixed steps of `dt` from a start holding every mode, over the start's.
double energy_growth(MembraneModel& m, double dt, int steps)
{
    MembraneSettings s = m.settings();
    s.fixed_step = true;
    s.fixed_dt = dt;
    EXPECT_TRUE(m.set_settings(s));
    MembraneState st = MembraneState::at_rest(m.grid());
    test::set_field(m, st.u,
                    [](const core::Vec3& p)
                    { return 1e-3 * std::sin(40.0 * p.x + 31.0 * p.y + 17.0 * p.z); });
    Rkf45Workspace ws(m, 1);
    const double e0 = energy(m, st).total();
    double e = e0;
    for (int k = 1; k <= steps && e < 1e6 * e0; ++k)
    {
        (void)step(m, st, ws, {});
        if (k % 100 == 0 || k == steps)
            e = energy(m, st).total();
    }
    return e / e0;
}

TEST(Rkf45, StableFixedStepHoldsWithDampingAndWithout)
{
    for (const double beta : {0.0, 0.2, 2.0})
    {
        MembraneSettings set = ode_settings();
        set.beta = beta;
        MembraneModel m = test::sphere_model(3, set);
        const double omega = largest_omega(m);
        const double dt = stable_fixed_step(m);
        std::printf("beta %.1f: omega_max %.2f, stable step %.4g s, omega_max dt %.3f\n", beta,
                    omega, dt, omega * dt);
        // Without damping the bound keeps the growth below 1e-7 per step (energy: twice that).
        EXPECT_LE(energy_growth(m, dt, 3000), beta > 0.0 ? 1.0 : 1.0 + 3000 * 2.2e-7) << beta;
        // Far beyond it every explicit 6-stage method is unstable (|omega dt| > 5).
        EXPECT_GT(energy_growth(m, 5.5 / omega, 3000), 1e3) << beta;
        if (beta >= 2.0)
        {
            // With real damping the bound is not needlessly small: |omega dt| near 3, where
            // Fehlberg's region ends (3.5 at most on these rays); at 4.5 the top modes grow.
            EXPECT_GE(omega * dt, 2.0);
            EXPECT_GT(energy_growth(m, 4.5 / omega, 3000), 1.0);
        }
    }
}

}  // namespace
}  // namespace pliant::sim
