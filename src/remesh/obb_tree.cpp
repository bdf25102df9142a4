// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// The oriented-box tree of the self-intersection count's crowded cells (obb_tree.h).

#include "remesh/obb_tree.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace pliant::remesh::detail
{
namespace
{

using core::Vec3;

/// An orthonormal frame from the covariance of `corners`: its principal axes (Eigen's direct
/// 3×3 solver, then Gram–Schmidt, so the axes are orthonormal to rounding whatever the
/// solver's accuracy on repeated eigenvalues); the standard axes when the covariance is not
/// finite.
std::array<Vec3, 3> principal_axes(const Eigen::Matrix3d& covariance)
{
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(covariance);
    const Eigen::Matrix3d& v = solver.eigenvectors();
    // eigenvalues ascending: the longest axis first
    const Vec3 c2{v(0, 2), v(1, 2), v(2, 2)};
    const Vec3 c1{v(0, 1), v(1, 1), v(2, 1)};
    const std::array<Vec3, 3> standard{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
    if (!core::is_finite(c2) || !core::is_finite(c1) || !(core::norm(c2) > 0.5))
        return standard;
    const Vec3 a0 = core::normalized(c2);
    Vec3 a1 = c1 - a0 * core::dot(c1, a0);
    if (!(core::norm(a1) > 0.5))
    {
        // any direction across a0: the standard axis least along it
        const Vec3& s = std::fabs(a0.x) < 0.5   ? standard[0]
                        : std::fabs(a0.y) < 0.5 ? standard[1]
                                                : standard[2];
        a1 = s - a0 * core::dot(s, a0);
    }
    a1 = core::normalized(a1);
    return {a0, a1, core::cross(a0, a1)};
}

}  // namespace

bool obbs_may_overlap(const Obb& a, const Obb& b) noexcept
{
    constexpr double k_parallel = 1e-12;
    std::array<std::array<double, 3>, 3> r{};
    std::array<std::array<double, 3>, 3> ar{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
        {
            r[i][j] = core::dot(a.axis[i], b.axis[j]);
            ar[i][j] = std::fabs(r[i][j]) + k_parallel;
        }
    const Vec3 d = b.centre - a.centre;
    const std::array<double, 3> t{core::dot(d, a.axis[0]), core::dot(d, a.axis[1]),
                                  core::dot(d, a.axis[2])};
    // Every comparison below is between sums of at most a few products of numbers bounded by
    // the centres' coordinates (d's rounding is relative to them, not to |d|), the half extents
    // and 1: its rounding is below 1e-14 of their total, so a gap must exceed 1e-12 of it to
    // count.
    const auto magnitude = [](const Vec3& p) {
        return std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
    };
    const double slack = 1e-12 * (magnitude(a.centre) + magnitude(b.centre) + a.half[0] +
                                  a.half[1] + a.half[2] + b.half[0] + b.half[1] + b.half[2]);
    const auto& ha = a.half;
    const auto& hb = b.half;
    for (int i = 0; i < 3; ++i)
        if (std::fabs(t[i]) >
            ha[i] + hb[0] * ar[i][0] + hb[1] * ar[i][1] + hb[2] * ar[i][2] + slack)
            return false;
    for (int j = 0; j < 3; ++j)
        if (std::fabs(t[0] * r[0][j] + t[1] * r[1][j] + t[2] * r[2][j]) >
            ha[0] * ar[0][j] + ha[1] * ar[1][j] + ha[2] * ar[2][j] + hb[j] + slack)
            return false;
    // a.axis[i] × b.axis[j]
    for (int i = 0; i < 3; ++i)
    {
        const int i1 = (i + 1) % 3;
        const int i2 = (i + 2) % 3;
        for (int j = 0; j < 3; ++j)
        {
            const int j1 = (j + 1) % 3;
            const int j2 = (j + 2) % 3;
            const double ra = ha[i1] * ar[i2][j] + ha[i2] * ar[i1][j];
            const double rb = hb[j1] * ar[i][j2] + hb[j2] * ar[i][j1];
            if (std::fabs(t[i2] * r[i1][j] - t[i1] * r[i2][j]) > ra + rb + slack)
                return false;
        }
    }
    return true;
}

ObbTree::ObbTree(const mesh::TriMesh& mesh, std::span<const std::uint32_t> faces,
                 std::span<const std::uint8_t> flagged, const core::ProgressSink* stop)
{
    const auto n = static_cast<std::uint32_t>(faces.size());
    if (n == 0)
        return;
    order_.resize(n);
    for (std::uint32_t i = 0; i < n; ++i)
        order_[i] = i;
    nodes_.reserve(2 * ((n + k_leaf_items - 1) / k_leaf_items) + 1);
    std::vector<double> keys;
    build(mesh, faces, flagged, 0, n, keys, stop);
}

std::uint32_t ObbTree::build(const mesh::TriMesh& mesh, std::span<const std::uint32_t> faces,
                             std::span<const std::uint8_t> flagged, std::uint32_t begin,
                             std::uint32_t end, std::vector<double>& keys,
                             const core::ProgressSink* stop)
{
    const auto index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    const auto corners = [&](std::uint32_t item) -> std::array<Vec3, 3>
    {
        const auto& t = mesh.faces[faces[item]];
        return {mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
    };

    // the box: principal axes of the corners, extents from their projections
    Vec3 mean{0, 0, 0};
    bool any_flag = flagged.empty();
    for (std::uint32_t i = begin; i < end; ++i)
    {
        for (const Vec3& p : corners(order_[i]))
            mean += p;
        any_flag = any_flag || flagged[order_[i]] != 0;
    }
    mean = mean / (3.0 * static_cast<double>(end - begin));
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (std::uint32_t i = begin; i < end; ++i)
        for (const Vec3& p : corners(order_[i]))
        {
            const Eigen::Vector3d e{p.x - mean.x, p.y - mean.y, p.z - mean.z};
            covariance.noalias() += e * e.transpose();
        }
    Obb box;
    box.axis = principal_axes(covariance);
    std::array<double, 3> lo{}, hi{};
    lo.fill(std::numeric_limits<double>::max());
    hi.fill(-std::numeric_limits<double>::max());
    for (std::uint32_t i = begin; i < end; ++i)
        for (const Vec3& p : corners(order_[i]))
            for (int k = 0; k < 3; ++k)
            {
                const double s = core::dot(p - mean, box.axis[k]);
                lo[k] = std::min(lo[k], s);
                hi[k] = std::max(hi[k], s);
            }
    // The projections and the centre round to within about 1e-15 of the corners' magnitude,
    // which is at most the centre's plus the half extents: obbs_may_overlap's slack (1e-12 of
    // them) covers it.
    box.centre = mean;
    for (int k = 0; k < 3; ++k)
    {
        box.centre += box.axis[k] * (0.5 * (lo[k] + hi[k]));
        box.half[k] = 0.5 * (hi[k] - lo[k]);
    }
    {
        Node& node = nodes_[index];
        node.box = box;
        node.begin = begin;
        node.end = end;
        node.flagged = any_flag;
    }
    if (end - begin <= k_leaf_items || (end - begin > (1U << 16) && core::stop_requested(stop)))
        return index;

    // the split: the median centroid along the axis whose halves overlap least
    const std::uint32_t mid = begin + (end - begin) / 2;
    const auto order_along = [&](int k)
    {
        keys.resize(faces.size());
        for (std::uint32_t i = begin; i < end; ++i)
        {
            const auto c = corners(order_[i]);
            keys[order_[i]] = core::dot(c[0] + c[1] + c[2], box.axis[k]);
        }
        std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                         [&](std::uint32_t x, std::uint32_t y)
                         { return keys[x] != keys[y] ? keys[x] < keys[y] : x < y; });
    };
    const auto extent = [&](std::uint32_t from, std::uint32_t to, int k)
    {
        std::pair<double, double> e{std::numeric_limits<double>::max(),
                                    -std::numeric_limits<double>::max()};
        for (std::uint32_t i = from; i < to; ++i)
            for (const Vec3& p : corners(order_[i]))
            {
                const double s = core::dot(p, box.axis[k]);
                e.first = std::min(e.first, s);
                e.second = std::max(e.second, s);
            }
        return e;
    };
    int best = 0;
    double best_overlap = std::numeric_limits<double>::max();
    for (int k = 0; k < 3; ++k)
    {
        order_along(k);
        const auto l = extent(begin, mid, k);
        const auto r = extent(mid, end, k);
        const double shared =
            std::max(0.0, std::min(l.second, r.second) - std::max(l.first, r.first));
        const double overlap = shared / std::max(box.half[k], std::numeric_limits<double>::min());
        if (overlap < best_overlap)
        {
            best_overlap = overlap;
            best = k;
        }
    }
    if (best != 2)
        order_along(best);
    const std::uint32_t left = build(mesh, faces, flagged, begin, mid, keys, stop);
    const std::uint32_t right = build(mesh, faces, flagged, mid, end, keys, stop);
    nodes_[index].left = left;
    nodes_[index].right = right;
    return index;
}

std::vector<ObbTree::Job> ObbTree::jobs(std::size_t target) const
{
    std::vector<Job> out;
    if (nodes_.empty())
        return out;
    int depth = 0;
    while ((std::size_t{1} << depth) < target && depth < 30)
        ++depth;
    expand({0, 0}, 0, depth, out);
    return out;
}

void ObbTree::expand(Job job, int depth, int max_depth, std::vector<Job>& out) const
{
    const Node& a = nodes_[job.a];
    if (job.a == job.b)
    {
        if (!a.flagged)
            return;
        if (a.leaf() || depth >= max_depth)
        {
            out.push_back(job);
            return;
        }
        expand({a.left, a.left}, depth + 1, max_depth, out);
        expand({a.right, a.right}, depth + 1, max_depth, out);
        expand({a.left, a.right}, depth + 1, max_depth, out);
        return;
    }
    const Node& b = nodes_[job.b];
    if ((!a.flagged && !b.flagged) || !obbs_may_overlap(a.box, b.box))
        return;
    if ((a.leaf() && b.leaf()) || depth >= max_depth)
    {
        out.push_back(job);
        return;
    }
    if (b.leaf() || (!a.leaf() && a.size() >= b.size()))
    {
        expand({a.left, job.b}, depth + 1, max_depth, out);
        expand({a.right, job.b}, depth + 1, max_depth, out);
    }
    else
    {
        expand({job.a, b.left}, depth + 1, max_depth, out);
        expand({job.a, b.right}, depth + 1, max_depth, out);
    }
}

}  // namespace pliant::remesh::detail
