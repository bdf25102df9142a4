// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Helpers shared by the sim tests: sphere models, fields from functions of the rest position,
// and the slow reference assembly of K and M triangle by triangle over unique vertices (Eigen).

#include <pliant/core/tetra_grid.h>
#include <pliant/sim/membrane.h>

#include <Eigen/Sparse>

#include "grid_shapes.h"

#include <cmath>
#include <vector>

namespace pliant::sim::test
{

inline MembraneModel sphere_model(int level, const MembraneSettings& settings, double radius = 1.0)
{
    const core::TetraGrid grid = core::TetraGrid::create(level).value();
    auto model = MembraneModel::create(grid, scenes::sphere_grid(grid, radius), settings);
    return std::move(model).value();
}

inline core::Vec3 rest(const MembraneModel& m, core::NodeIndex n)
{
    const core::GridCoord c = m.grid().coord(n);
    return {m.rest_positions()[0].at(c.x, c.y), m.rest_positions()[1].at(c.x, c.y),
            m.rest_positions()[2].at(c.x, c.y)};
}

/// Sets f at every in-range node to fn(rest position) and syncs twins and ghosts.
template <typename Fn>
void set_field(const MembraneModel& m, core::Field<double>& f, Fn fn)
{
    const core::TetraGrid& g = m.grid();
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            f.at(x, y) = fn(rest(m, g.index(x, y)));
    m.sync(f);
}

/// Unique-vertex vector of a field.
inline Eigen::VectorXd unique_vector(const MembraneModel& m, const core::Field<double>& f)
{
    const auto nodes = m.grid().node_of_unique();
    Eigen::VectorXd out(static_cast<Eigen::Index>(nodes.size()));
    for (std::size_t k = 0; k < nodes.size(); ++k)
        out(static_cast<Eigen::Index>(k)) = f[nodes[k]];
    return out;
}

/// K (cotangent, T/2 (cot a + cot b)) and lumped M (rho/3 of the incident areas), assembled
/// triangle by triangle over the 4W^2 faces on unique vertices: the slow obvious reference.
struct Reference
{
    Eigen::SparseMatrix<double> K;
    Eigen::VectorXd M;
};

inline Reference reference_assembly(const MembraneModel& m)
{
    const core::TetraGrid& g = m.grid();
    const auto nodes = g.node_of_unique();
    const auto n = static_cast<Eigen::Index>(nodes.size());
    const double T = m.settings().T;
    const double rho = m.settings().rho;
    std::vector<Eigen::Triplet<double>> trip;
    Reference ref;
    ref.M = Eigen::VectorXd::Zero(n);
    for (const auto& t : g.triangles())
    {
        const core::Vec3 p[3] = {rest(m, nodes[t[0]]), rest(m, nodes[t[1]]), rest(m, nodes[t[2]])};
        const double area2 = core::norm(core::cross(p[1] - p[0], p[2] - p[0]));
        for (int k = 0; k < 3; ++k)
        {
            const int i = (k + 1) % 3;
            const int j = (k + 2) % 3;
            const core::Vec3 a = p[i] - p[k];
            const core::Vec3 b = p[j] - p[k];
            const double w = 0.5 * T * core::dot(a, b) / core::norm(core::cross(a, b));
            const auto I = static_cast<Eigen::Index>(t[static_cast<std::size_t>(i)]);
            const auto J = static_cast<Eigen::Index>(t[static_cast<std::size_t>(j)]);
            trip.emplace_back(I, I, w);
            trip.emplace_back(J, J, w);
            trip.emplace_back(I, J, -w);
            trip.emplace_back(J, I, -w);
            ref.M(static_cast<Eigen::Index>(t[static_cast<std::size_t>(k)])) +=
                rho * 0.5 * area2 / 3.0;
        }
    }
    ref.K.resize(n, n);
    ref.K.setFromTriplets(trip.begin(), trip.end());
    return ref;
}

/// The material of the tests against closed-form solutions of the semi-discrete ODE: T = rho = 1,
/// beta = 0.2, k_f = 0.5 (every mode underdamped), one thread.
inline constexpr double k_ode_beta = 0.2;
inline constexpr double k_ode_kf = 0.5;

inline MembraneSettings ode_settings()
{
    MembraneSettings s;
    s.T = 1.0;
    s.rho = 1.0;
    s.beta = k_ode_beta;
    s.k_f = k_ode_kf;
    s.threads = 1;
    return s;
}

/// One mode of it: q'' + beta q' + w2 q = c0 + c1 t from (q, p) at t = 0, in closed form
/// (w2 > beta^2 / 4): the particular solution A t + B plus the damped oscillation that meets the
/// initial values.
struct DampedOscillator
{
    double q = 0.0;
    double p = 0.0;

    void advance(double w2, double c0, double c1, double t, double beta = k_ode_beta)
    {
        const double A = c1 / w2;
        const double B = (c0 - beta * A) / w2;
        const double a = q - B;
        const double wd = std::sqrt(w2 - 0.25 * beta * beta);
        const double b = ((p - A) + 0.5 * beta * a) / wd;
        const double e = std::exp(-0.5 * beta * t);
        const double c = std::cos(wd * t);
        const double s = std::sin(wd * t);
        q = A * t + B + e * (a * c + b * s);
        p = A + e * ((-0.5 * beta) * (a * c + b * s) + (-a * wd * s + b * wd * c));
    }
};

/// Real zonal spherical harmonic Y_l0 (unnormalised: the Legendre polynomial of cos theta) at
/// the direction of p.
inline double zonal(int l, const core::Vec3& p)
{
    const double z = p.z / core::norm(p);
    switch (l)
    {
    case 1: return z;
    case 2: return 0.5 * (3.0 * z * z - 1.0);
    case 3: return 0.5 * (5.0 * z * z * z - 3.0 * z);
    default: return (35.0 * z * z * z * z - 30.0 * z * z + 3.0) / 8.0;
    }
}

}  // namespace pliant::sim::test
