// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Surface distance through a bounding-volume hierarchy (design in
// include/pliant/remesh/quality.h). The BVH is a binary tree of axis-aligned boxes built by
// median splits along the longest axis of the triangle centroids, with up to 4 triangles per
// leaf; a nearest-point query descends the nearer child first and prunes any box farther than
// the best distance so far. Alternatives rejected: a uniform grid (poor on meshes with very
// uneven triangle sizes, such as the thin fins of real models). A surface made mostly of long
// slanted slivers (a finely divided cylinder) is searched through a tree of oriented boxes
// instead (obb_tree.h): their axis-aligned boxes are far larger than they are and overlap by the
// hundred, so a query opened that many leaves.

#include <pliant/remesh/quality.h>

#include "remesh/obb_tree.h"
#include "remesh/quality_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <span>
#include <vector>

namespace pliant::remesh
{
namespace
{

using core::Vec3;

struct Box
{
    Vec3 lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
            std::numeric_limits<double>::max()};
    Vec3 hi{-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
            -std::numeric_limits<double>::max()};
    void add(const Vec3& p) noexcept
    {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    [[nodiscard]] double dist2(const Vec3& p) const noexcept
    {
        const double dx = std::max({lo.x - p.x, 0.0, p.x - hi.x});
        const double dy = std::max({lo.y - p.y, 0.0, p.y - hi.y});
        const double dz = std::max({lo.z - p.z, 0.0, p.z - hi.z});
        return dx * dx + dy * dy + dz * dz;
    }
};

struct Node
{
    Box box;
    std::uint32_t first = 0;  ///< leaf: first triangle in order_; inner: left child
    std::uint32_t count = 0;  ///< leaf: triangle count; inner: 0 (right child = left + 1)
};

Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) noexcept
{
    // Ericson, Real-Time Collision Detection, §5.1.5 (Voronoi regions of the triangle)
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = core::dot(ab, ap), d2 = core::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0)
        return a;
    const Vec3 bp = p - b;
    const double d3 = core::dot(ab, bp), d4 = core::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3)
        return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
    {
        const double den = d1 - d3;
        return den > 0.0 ? a + ab * (d1 / den) : a;
    }
    const Vec3 cp = p - c;
    const double d5 = core::dot(ab, cp), d6 = core::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6)
        return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
    {
        const double den = d2 - d6;
        return den > 0.0 ? a + ac * (d2 / den) : a;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    {
        const double den = (d4 - d3) + (d5 - d6);
        return den > 0.0 ? b + (c - b) * ((d4 - d3) / den) : b;
    }
    const double sum = va + vb + vc;
    if (!(sum > 0.0))  // degenerate triangle: nearest of its vertices
    {
        const double da = core::dot(p - a, p - a), db = core::dot(p - b, p - b),
                     dc = core::dot(p - c, p - c);
        return da <= db && da <= dc ? a : (db <= dc ? b : c);
    }
    const double v = vb / sum, w = vc / sum;
    return a + ab * v + ac * w;
}

class Bvh
{
public:
    /// `stop`: polled at every node of more than 2^16 faces; once it asks, the build ends early
    /// (the tree stays valid, but slow to search: the caller, which owns the sink, discards
    /// it).
    explicit Bvh(const mesh::TriMesh& m, const core::ProgressSink* stop = nullptr)
        : m_(m), order_(m.faces.size()), stop_(stop)
    {
        std::iota(order_.begin(), order_.end(), 0U);
        centroid_.resize(m.faces.size());
        for (std::size_t f = 0; f < m.faces.size(); ++f)
        {
            const auto& t = m.faces[f];
            centroid_[f] = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
        }
        nodes_.reserve(2 * m.faces.size() / 2 + 8);
        nodes_.push_back({});
        build(0, 0, static_cast<std::uint32_t>(order_.size()));
    }

    /// Squared distance from p to the surface.
    [[nodiscard]] double nearest2(const Vec3& p) const noexcept
    {
        double best = std::numeric_limits<double>::infinity();
        std::array<std::uint32_t, 128> stack{};
        std::size_t top = 0;
        stack[top++] = 0;
        while (top > 0)
        {
            const Node& n = nodes_[stack[--top]];
            if (n.box.dist2(p) >= best)
                continue;
            if (n.count > 0)
            {
                for (std::uint32_t k = 0; k < n.count; ++k)
                {
                    const auto& t = m_.faces[order_[n.first + k]];
                    const Vec3 q = closest_on_triangle(p, m_.positions[t[0]], m_.positions[t[1]],
                                                       m_.positions[t[2]]);
                    best = std::min(best, core::dot(p - q, p - q));
                }
                continue;
            }
            const std::uint32_t l = n.first, r = n.first + 1;
            const double dl = nodes_[l].box.dist2(p), dr = nodes_[r].box.dist2(p);
            // push the farther child first so the nearer one is searched first
            if (top + 2 > stack.size())
                continue;  // cannot happen: depth is bounded by log2(F) + a few
            if (dl < dr)
            {
                stack[top++] = r;
                stack[top++] = l;
            }
            else
            {
                stack[top++] = l;
                stack[top++] = r;
            }
        }
        return best;
    }

private:
    void build(std::uint32_t node, std::uint32_t begin, std::uint32_t end)
    {
        Box box, cbox;
        for (std::uint32_t i = begin; i < end; ++i)
        {
            const auto& t = m_.faces[order_[i]];
            for (const std::uint32_t v : t)
                box.add(m_.positions[v]);
            cbox.add(centroid_[order_[i]]);
        }
        nodes_[node].box = box;
        // A stop ends the build with this node a leaf of all its faces: a valid tree, slow to
        // search, that the stopped caller discards (a level-10 grid's build takes a second or
        // more).
        if (end - begin <= 4 || (end - begin > (1U << 16) && core::stop_requested(stop_)))
        {
            nodes_[node].first = begin;
            nodes_[node].count = end - begin;
            return;
        }
        const Vec3 ext = cbox.hi - cbox.lo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const std::uint32_t mid = begin + (end - begin) / 2;
        std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                         [&](std::uint32_t a, std::uint32_t b)
                         {
                             const Vec3& ca = centroid_[a];
                             const Vec3& cb = centroid_[b];
                             return axis == 0 ? ca.x < cb.x
                                              : (axis == 1 ? ca.y < cb.y : ca.z < cb.z);
                         });
        const auto left = static_cast<std::uint32_t>(nodes_.size());
        nodes_.push_back({});
        nodes_.push_back({});
        nodes_[node].first = left;
        nodes_[node].count = 0;
        build(left, begin, mid);
        build(left + 1, mid, end);
    }

    const mesh::TriMesh& m_;
    std::vector<std::uint32_t> order_;
    std::vector<Vec3> centroid_;
    std::vector<Node> nodes_;
    const core::ProgressSink* stop_;
};

/// The nearest-point search of a surface: the axis-aligned BVH, or the oriented-box tree.
class Nearest
{
public:
    Nearest(const mesh::TriMesh& m, const core::ProgressSink* stop, bool oriented) : m_(m)
    {
        if (oriented)
        {
            faces_.resize(m.faces.size());
            std::iota(faces_.begin(), faces_.end(), 0U);
            obb_.emplace(m, faces_, std::span<const std::uint8_t>{}, stop);
        }
        else
        {
            bvh_.emplace(m, stop);
        }
    }

    /// Squared distance from p to the surface.
    [[nodiscard]] double nearest2(const Vec3& p) const noexcept
    {
        if (bvh_)
            return bvh_->nearest2(p);
        return obb_->nearest2(p,
                              [&](std::uint32_t f)
                              {
                                  const auto& t = m_.faces[f];
                                  const Vec3 q =
                                      closest_on_triangle(p, m_.positions[t[0]], m_.positions[t[1]],
                                                          m_.positions[t[2]]);
                                  return core::dot(p - q, p - q);
                              });
    }

private:
    const mesh::TriMesh& m_;
    std::optional<Bvh> bvh_;
    std::vector<std::uint32_t> faces_;
    std::optional<detail::ObbTree> obb_;
};

/// Vertices plus `count` area-weighted random points of `m`.
std::vector<Vec3> sample_points(const mesh::TriMesh& m, std::size_t count, std::uint64_t seed)
{
    std::vector<Vec3> pts(m.positions);
    std::vector<double> cdf(m.faces.size());
    double acc = 0.0;
    for (std::size_t f = 0; f < m.faces.size(); ++f)
    {
        const auto& t = m.faces[f];
        acc += core::norm(core::cross(m.positions[t[1]] - m.positions[t[0]],
                                      m.positions[t[2]] - m.positions[t[0]]));
        cdf[f] = acc;
    }
    if (!(acc > 0.0))
        return pts;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    pts.reserve(pts.size() + count);
    for (std::size_t i = 0; i < count; ++i)
    {
        const double r = uni(rng) * acc;
        const auto it = std::upper_bound(cdf.begin(), cdf.end(), r);
        const std::size_t f =
            std::min<std::size_t>(static_cast<std::size_t>(it - cdf.begin()), cdf.size() - 1);
        double s = uni(rng), t = uni(rng);
        if (s + t > 1.0)
        {
            s = 1.0 - s;
            t = 1.0 - t;
        }
        const auto& tri = m.faces[f];
        const Vec3& a = m.positions[tri[0]];
        pts.push_back(a + (m.positions[tri[1]] - a) * s + (m.positions[tri[2]] - a) * t);
    }
    return pts;
}

/// `progress` gets the fraction done mapped onto [base, base + span], once per block of samples
/// (reported between parallel loops, from the calling thread).
DirectedDistance directed(const mesh::TriMesh& from, const Nearest& to, const DistanceSettings& s,
                          double& sum_sq, core::ProgressSink* progress, double base, double span)
{
    const std::size_t n =
        s.samples > 0 ? s.samples : std::clamp<std::size_t>(3 * from.faces.size(), 50'000, 300'000);
    const std::vector<Vec3> pts = sample_points(from, n, s.seed);
    double sq = 0.0, sum = 0.0, mx = 0.0;
    const auto count = static_cast<std::ptrdiff_t>(pts.size());
    constexpr std::ptrdiff_t k_block = 32'768;
    for (std::ptrdiff_t b0 = 0; b0 < count && !core::stop_requested(progress); b0 += k_block)
    {
        const std::ptrdiff_t b1 = std::min(count, b0 + k_block);
        double bsq = 0.0, bsum = 0.0, bmx = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : bsq, bsum) reduction(max : bmx)
        for (std::ptrdiff_t i = b0; i < b1; ++i)
        {
            const double d2 = to.nearest2(pts[static_cast<std::size_t>(i)]);
            const double d = std::sqrt(d2);
            bsq += d2;
            bsum += d;
            bmx = std::max(bmx, d);
        }
        sq += bsq;
        sum += bsum;
        mx = std::max(mx, bmx);
        if (progress != nullptr && b1 < count)
            progress->update("measure",
                             base + span * static_cast<double>(b1) / static_cast<double>(count));
    }
    sum_sq = sq;
    DirectedDistance out;
    out.samples = pts.size();
    out.rms = pts.empty() ? 0.0 : std::sqrt(sq / static_cast<double>(pts.size()));
    out.mean = pts.empty() ? 0.0 : sum / static_cast<double>(pts.size());
    out.max = mx;
    return out;
}

}  // namespace

double point_triangle_distance(const core::Vec3& p, const core::Vec3& a, const core::Vec3& b,
                               const core::Vec3& c) noexcept
{
    return core::norm(p - closest_on_triangle(p, a, b, c));
}

bool detail::mostly_slanted_slivers(const mesh::TriMesh& m) noexcept
{
    // A face's box surface against its area: about 4 for a triangle lying in an axis plane, up
    // to about 10 for one at a slant, 2L/w for a sliver of length L and width w at a slant (a
    // sliver along an axis keeps a tight box).
    std::size_t loose = 0;
    for (const auto& t : m.faces)
    {
        const Vec3& a = m.positions[t[0]];
        const Vec3& b = m.positions[t[1]];
        const Vec3& c = m.positions[t[2]];
        const double area = 0.5 * core::norm(core::cross(b - a, c - a));
        const double dx = std::max({a.x, b.x, c.x}) - std::min({a.x, b.x, c.x});
        const double dy = std::max({a.y, b.y, c.y}) - std::min({a.y, b.y, c.y});
        const double dz = std::max({a.z, b.z, c.z}) - std::min({a.z, b.z, c.z});
        loose += 2.0 * (dx * dy + dy * dz + dz * dx) > 64.0 * area ? 1 : 0;
    }
    return 4 * loose > m.faces.size();
}

SurfaceDistance detail::surface_distance_with(const mesh::TriMesh& reference,
                                              const mesh::TriMesh& other,
                                              const DistanceSettings& settings,
                                              core::ProgressSink* progress, SearchBoxes boxes)
{
    SurfaceDistance out;
    if (reference.positions.empty() || other.positions.empty() || reference.faces.empty() ||
        other.faces.empty())
        return out;
    Vec3 lo = reference.positions[0], hi = lo;
    for (const Vec3& p : reference.positions)
    {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    out.diagonal = core::norm(hi - lo);
    const auto oriented = [&](const mesh::TriMesh& m)
    {
        return boxes == SearchBoxes::Oriented ||
               (boxes == SearchBoxes::Auto && mostly_slanted_slivers(m));
    };
    const Nearest ref_bvh(reference, progress, oriented(reference));
    if (core::stop_requested(progress))
        return out;  // the caller was stopped: its result is not used
    const Nearest other_bvh(other, progress, oriented(other));
    if (core::stop_requested(progress))
        return out;
    double sq_a = 0.0, sq_b = 0.0;
    out.reference_to_other = directed(reference, other_bvh, settings, sq_a, progress, 0.0, 0.5);
    if (core::stop_requested(progress))
        return out;  // the caller was stopped: its result is not used
    if (progress != nullptr)
        progress->update("measure", 0.5);
    out.other_to_reference = directed(other, ref_bvh, settings, sq_b, progress, 0.5, 0.5);
    const double n =
        static_cast<double>(out.reference_to_other.samples + out.other_to_reference.samples);
    out.rms = std::sqrt((sq_a + sq_b) / n);
    out.hausdorff = std::max(out.reference_to_other.max, out.other_to_reference.max);
    if (out.diagonal > 0.0)
    {
        out.rms_relative = out.rms / out.diagonal;
        out.hausdorff_relative = out.hausdorff / out.diagonal;
        out.psnr_db =
            out.rms > out.diagonal * 1e-15 ? 20.0 * std::log10(out.diagonal / out.rms) : 300.0;
    }
    return out;
}

SurfaceDistance surface_distance(const mesh::TriMesh& reference, const mesh::TriMesh& other,
                                 const DistanceSettings& settings, core::ProgressSink* progress)
{
    return detail::surface_distance_with(reference, other, settings, progress,
                                         detail::SearchBoxes::Auto);
}

AreaSpread area_spread(const mesh::TriMesh& mesh) noexcept
{
    AreaSpread s;
    if (mesh.faces.empty())
        return s;
    double mn = std::numeric_limits<double>::infinity(), mx = 0.0, sum = 0.0, sum2 = 0.0;
    for (const auto& t : mesh.faces)
    {
        const double a = 0.5 * core::norm(core::cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                                                      mesh.positions[t[2]] - mesh.positions[t[0]]));
        mn = std::min(mn, a);
        mx = std::max(mx, a);
        sum += a;
        sum2 += a * a;
    }
    const double n = static_cast<double>(mesh.faces.size());
    const double mean = sum / n;
    s.min_over_max = mx > 0.0 ? mn / mx : 0.0;
    s.cv = mean > 0.0 ? std::sqrt(std::max(0.0, sum2 / n - mean * mean)) / mean : 0.0;
    return s;
}

}  // namespace pliant::remesh
