// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The stencil K and lumped M against a per-triangle Eigen assembly on unique vertices
// (docs/design.md §1: corner rows and masses are doubled by the ghost map), and the properties of
// K.

// GCC 12 reports a false -Wmaybe-uninitialized inside Eigen's AVX-512 kernels (-march=native).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include <pliant/sim/membrane.h>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "sim/stencil_internal.h"
#include "sim_test_util.h"
#include "support/fp_traps.h"

#include <random>

namespace pliant::sim
{
namespace
{

MembraneSettings material()
{
    MembraneSettings s;
    s.T = 2.5;
    s.rho = 0.7;
    return s;
}

// Eigen matrix built from the model's stencil weights, rows divided by the multiplicity.
Eigen::SparseMatrix<double> stencil_matrix(const MembraneModel& m)
{
    const core::TetraGrid& g = m.grid();
    static constexpr int k_dir[6][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}};
    std::vector<Eigen::Triplet<double>> trip;
    for (const core::NodeIndex n : g.node_of_unique())
    {
        const core::GridCoord c = g.coord(n);
        const double w[6] = {m.weight_x().at(c.x, c.y), m.weight_x().at(c.x - 1, c.y),
                             m.weight_y().at(c.x, c.y), m.weight_y().at(c.x, c.y - 1),
                             m.weight_d().at(c.x, c.y), m.weight_d().at(c.x - 1, c.y - 1)};
        const auto i = static_cast<Eigen::Index>(g.unique_id(n));
        const double mult = m.multiplicity(n);
        for (int k = 0; k < 6; ++k)
        {
            const auto j = static_cast<Eigen::Index>(
                g.unique_id(g.image(c.x + k_dir[k][0], c.y + k_dir[k][1])));
            trip.emplace_back(i, i, w[k] / mult);
            trip.emplace_back(i, j, -w[k] / mult);
        }
    }
    const auto n = static_cast<Eigen::Index>(g.unique_count());
    Eigen::SparseMatrix<double> A(n, n);
    A.setFromTriplets(trip.begin(), trip.end());
    return A;
}

class StiffnessByLevel : public ::testing::TestWithParam<int>
{
};

TEST_P(StiffnessByLevel, StencilEqualsPerTriangleAssembly)
{
    const MembraneModel m = test::sphere_model(GetParam(), material(), 1.3);
    const core::TetraGrid& g = m.grid();
    const test::Reference ref = test::reference_assembly(m);

    core::Field<double> u(g, 1);
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> dist(-1.0, 1.0);
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            u.at(x, y) = dist(rng);
    m.sync(u);
    core::Field<double> ku;
    apply_stiffness(m, u, ku);

    const Eigen::VectorXd expected = ref.K * test::unique_vector(m, u);
    const double scale = expected.cwiseAbs().maxCoeff();
    double worst = 0.0;
    double worst_mass = 0.0;
    const auto nodes = g.node_of_unique();
    for (std::size_t k = 0; k < nodes.size(); ++k)
    {
        const double mult = m.multiplicity(nodes[k]);
        const auto K = static_cast<Eigen::Index>(k);
        worst = std::max(worst, std::fabs(ku[nodes[k]] - mult * expected(K)));
        worst_mass =
            std::max(worst_mass, std::fabs(m.mass()[nodes[k]] - mult * ref.M(K)) / ref.M(K));
    }
    EXPECT_LE(worst, 1e-12 * scale) << "level " << GetParam();
    EXPECT_LE(worst_mass, 1e-12);
    // Total mass is rho times the mesh area.
    EXPECT_NEAR(
        ref.M.sum(),
        [&]
        {
            double s = 0.0;
            for (const auto n : nodes)
                s += m.unique_mass(n);
            return s;
        }(),
        1e-10 * ref.M.sum());
}

INSTANTIATE_TEST_SUITE_P(Levels, StiffnessByLevel, ::testing::Values(3, 4, 5, 6, 7, 8));

TEST(Stiffness, AnnihilatesConstants)
{
    for (const int level : {3, 6})
    {
        const MembraneModel m = test::sphere_model(level, material());
        core::Field<double> u(m.grid(), 1, 0.37);
        core::Field<double> ku;
        apply_stiffness(m, u, ku);
        double wmax = 0.0;
        for (const double w : m.weight_x().padded())
            wmax = std::max(wmax, std::fabs(w));
        for (int y = 0; y < m.grid().ny(); ++y)
            for (int x = 0; x < m.grid().nx(); ++x)
                ASSERT_LE(std::fabs(ku.at(x, y)), 1e-13 * wmax) << x << "," << y;
    }
}

TEST(Stiffness, StencilMatrixIsSymmetricPsdAndEqualsReference)
{
    for (const int level : {3, 4})
    {
        const MembraneModel m = test::sphere_model(level, material());
        const Eigen::SparseMatrix<double> A = stencil_matrix(m);
        const Eigen::SparseMatrix<double> At = A.transpose();
        const double norm = A.norm();
        EXPECT_LE((A - At).norm(), 1e-13 * norm);
        EXPECT_LE((A - test::reference_assembly(m).K).norm(), 1e-13 * norm);
        const Eigen::MatrixXd dense = Eigen::MatrixXd(A);
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (dense + dense.transpose()));
        ASSERT_EQ(eig.info(), Eigen::Success);
        EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-12 * norm);  // PSD
        EXPECT_GT(eig.eigenvalues()(1), 1e-6 * norm);  // one zero eigenvalue (constants) only
    }
    // Larger level: random quadratic forms.
    const MembraneModel m = test::sphere_model(7, material());
    const Eigen::SparseMatrix<double> A = stencil_matrix(m);
    EXPECT_LE((A - Eigen::SparseMatrix<double>(A.transpose())).norm(), 1e-13 * A.norm());
    std::mt19937_64 rng(7);
    std::normal_distribution<double> dist;
    for (int trial = 0; trial < 20; ++trial)
    {
        Eigen::VectorXd x(A.rows());
        for (Eigen::Index i = 0; i < x.size(); ++i)
            x(i) = dist(rng);
        EXPECT_GE(x.dot(A * x), 0.0);
    }
}

TEST(Stiffness, TwinsAndGhostsComputeBitIdenticalValues)
{
    const MembraneModel m = test::sphere_model(5, material());
    const core::TetraGrid& g = m.grid();
    core::Field<double> u(g, 1);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> dist(-1.0, 1.0);
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            u.at(x, y) = dist(rng);
    m.sync(u);
    // Stencil evaluated at a twin (no sync afterwards) equals its canonical node bit for bit.
    const std::ptrdiff_t s = u.stride();
    const auto k_at = [&](core::NodeIndex n)
    {
        const core::GridCoord c = g.coord(n);
        return detail::stiffness_at(u.origin(), m.weight_x().origin(), m.weight_y().origin(),
                                    m.weight_d().origin(), u.offset(c.x, c.y), s);
    };
    for (const core::TwinPair& t : g.twins())
        ASSERT_EQ(k_at(t.twin), k_at(t.canonical));
    // Normals and masses too (normals are never synced: equality comes from the formulas).
    for (int k = 0; k < 3; ++k)
        EXPECT_EQ(core::max_twin_mismatch(g, m.normals()[static_cast<std::size_t>(k)]), 0.0);
    EXPECT_EQ(core::max_twin_mismatch(g, m.mass()), 0.0);
    // Normals point outward on the sphere.
    for (const core::NodeIndex n : g.node_of_unique())
    {
        const core::GridCoord c = g.coord(n);
        const core::Vec3 N{m.normals()[0].at(c.x, c.y), m.normals()[1].at(c.x, c.y),
                           m.normals()[2].at(c.x, c.y)};
        ASSERT_GT(core::dot(N, test::rest(m, n)), 0.9);
    }
}

TEST(Stiffness, RejectsBadSettingsAndDegenerateGeometry)
{
    const core::TetraGrid grid = core::TetraGrid::create(3).value();
    MembraneSettings s;
    s.T = -1.0;
    auto bad = MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), s);
    ASSERT_FALSE(bad.has_value());
    EXPECT_EQ(bad.error().code, core::ErrorCode::InvalidArgument);
    EXPECT_NE(bad.error().message.find("T "), std::string::npos);

    auto flat = scenes::sphere_grid(grid, 1.0);
    for (auto& f : flat)
        f.fill(0.5);  // every triangle collapsed to a point
    auto degenerate = MembraneModel::create(grid, flat, MembraneSettings{});
    ASSERT_FALSE(degenerate.has_value());
    EXPECT_EQ(degenerate.error().code, core::ErrorCode::DegenerateFace);

    // One node far away (its triangles' cotangents overflow): the message says where.
    auto far = scenes::sphere_grid(grid, 1.0);
    far[0].at(5, 2) = 1e300;
    auto overflow = MembraneModel::create(grid, far, MembraneSettings{});
    ASSERT_FALSE(overflow.has_value());
    EXPECT_EQ(overflow.error().code, core::ErrorCode::DegenerateFace);
    EXPECT_NE(overflow.error().message.find("at node ("), std::string::npos)
        << overflow.error().message;

    // A whole sphere scaled so far that the normals' products overflow or underflow: said as
    // the scale's fault ("span no area" sent the user looking at the shape).
    EXPECT_NE(degenerate.error().message.find("span no area"), std::string::npos)
        << degenerate.error().message;
    for (const double scale : {1e300, 1e-300})
    {
        pliant::test::FpTrapsOff traps_off;  // the products overflow and underflow, as said
        auto scaled = scenes::sphere_grid(grid, 1.0);
        for (auto& f : scaled)
            for (int y = 0; y < grid.ny(); ++y)
                for (int x = 0; x < grid.nx(); ++x)
                    f.at(x, y) *= scale;
        auto r = MembraneModel::create(grid, scaled, MembraneSettings{});
        ASSERT_FALSE(r.has_value()) << scale;
        EXPECT_EQ(r.error().code, core::ErrorCode::DegenerateFace);
        EXPECT_NE(r.error().message.find(scale > 1.0 ? "too large" : "too small"),
                  std::string::npos)
            << r.error().message;
    }
}

}  // namespace
}  // namespace pliant::sim
