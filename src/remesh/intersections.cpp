// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Triangle-triangle intersection and the uniform-grid broad phase (design in
// include/pliant/remesh/intersections.h).

#include <pliant/core/assert.h>
#include <pliant/remesh/intersections.h>

#include "remesh/intersections_internal.h"
#include "remesh/obb_tree.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pliant::remesh
{
namespace
{

using core::Vec3;

#if defined(__SIZEOF_FLOAT128__)
using Wide = __float128;
#else
using Wide = long double;
#endif

/// Sign of (a − d)·((b − d) × (c − d)): positive when d lies below the plane of the
/// counter-clockwise triangle abc. Double with Shewchuk's bound for orient3d, else 113 bits.
template <bool Exact>
int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept
{
    const double adx = a.x - d.x, ady = a.y - d.y, adz = a.z - d.z;
    const double bdx = b.x - d.x, bdy = b.y - d.y, bdz = b.z - d.z;
    const double cdx = c.x - d.x, cdy = c.y - d.y, cdz = c.z - d.z;
    const double bc = bdy * cdz - bdz * cdy, ca = cdy * adz - cdz * ady, ab = ady * bdz - adz * bdy;
    const double det = adx * bc + bdx * ca + cdx * ab;
    const double permanent = (std::abs(bdy * cdz) + std::abs(bdz * cdy)) * std::abs(adx) +
                             (std::abs(cdy * adz) + std::abs(cdz * ady)) * std::abs(bdx) +
                             (std::abs(ady * bdz) + std::abs(adz * bdy)) * std::abs(cdx);
    constexpr double k_eps = std::numeric_limits<double>::epsilon() / 2.0;
    constexpr double k_bound = (7.0 + 56.0 * k_eps) * k_eps;
    if (det > k_bound * permanent)
        return 1;
    if (det < -k_bound * permanent)
        return -1;
    if constexpr (!Exact)
        return 0;
    // Two equal points (faces sharing a vertex, the usual way here to fail the filter) make
    // two rows of the determinant equal or one zero: exactly 0, without the slow 113 bits.
    if (a == d || b == d || c == d || a == b || b == c || a == c)
        return 0;
    // Four points with one coordinate equal lie in a plane parallel to an axis plane: exactly 0
    // too. A flat cap (a cylinder's end split into a fan around its centre) puts every pair of
    // its faces here: a 2,500-sided cone spent 11 s in the 113 bits below, 5,000 sides 45 s.
    if ((a.x == d.x && b.x == d.x && c.x == d.x) || (a.y == d.y && b.y == d.y && c.y == d.y) ||
        (a.z == d.z && b.z == d.z && c.z == d.z))
        return 0;
    const Wide wadx = Wide(a.x) - Wide(d.x), wady = Wide(a.y) - Wide(d.y),
               wadz = Wide(a.z) - Wide(d.z);
    const Wide wbdx = Wide(b.x) - Wide(d.x), wbdy = Wide(b.y) - Wide(d.y),
               wbdz = Wide(b.z) - Wide(d.z);
    const Wide wcdx = Wide(c.x) - Wide(d.x), wcdy = Wide(c.y) - Wide(d.y),
               wcdz = Wide(c.z) - Wide(d.z);
    const Wide w = wadx * (wbdy * wcdz - wbdz * wcdy) + wbdx * (wcdy * wadz - wcdz * wady) +
                   wcdx * (wady * wbdz - wadz * wbdy);
    return w > 0 ? 1 : (w < 0 ? -1 : 0);
}

struct P2
{
    double u = 0.0;
    double v = 0.0;
};

template <bool Exact>
int orient2d(const P2& a, const P2& b, const P2& c) noexcept
{
    const double l = (a.u - c.u) * (b.v - c.v), r = (a.v - c.v) * (b.u - c.u);
    const double det = l - r;
    constexpr double k_eps = std::numeric_limits<double>::epsilon() / 2.0;
    constexpr double k_bound = (3.0 + 16.0 * k_eps) * k_eps;
    if (std::abs(det) > k_bound * (std::abs(l) + std::abs(r)))
        return det > 0.0 ? 1 : -1;
    if constexpr (!Exact)
        return 0;
    if ((a.u == c.u && a.v == c.v) || (b.u == c.u && b.v == c.v) || (a.u == b.u && a.v == b.v))
        return 0;  // two equal points: exactly 0
    const Wide w = (Wide(a.u) - Wide(c.u)) * (Wide(b.v) - Wide(c.v)) -
                   (Wide(a.v) - Wide(c.v)) * (Wide(b.u) - Wide(c.u));
    return w > 0 ? 1 : (w < 0 ? -1 : 0);
}

/// Whether c (collinear with a and b) lies within the box of segment ab.
bool in_span(const P2& a, const P2& b, const P2& c) noexcept
{
    return std::min(a.u, b.u) <= c.u && c.u <= std::max(a.u, b.u) && std::min(a.v, b.v) <= c.v &&
           c.v <= std::max(a.v, b.v);
}

/// Closed segments ab and cd share a point.
template <bool Exact>
bool segments_meet(const P2& a, const P2& b, const P2& c, const P2& d) noexcept
{
    const int o1 = orient2d<Exact>(a, b, c), o2 = orient2d<Exact>(a, b, d);
    const int o3 = orient2d<Exact>(c, d, a), o4 = orient2d<Exact>(c, d, b);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return true;
    return (o1 == 0 && in_span(a, b, c)) || (o2 == 0 && in_span(a, b, d)) ||
           (o3 == 0 && in_span(c, d, a)) || (o4 == 0 && in_span(c, d, b));
}

/// p inside or on the closed triangle t (either orientation; a degenerate t never contains p
/// except on its edges, which segments_meet covers).
template <bool Exact>
bool in_triangle(const std::array<P2, 3>& t, const P2& p) noexcept
{
    const int o0 = orient2d<Exact>(t[0], t[1], p), o1 = orient2d<Exact>(t[1], t[2], p),
              o2 = orient2d<Exact>(t[2], t[0], p);
    const bool has_neg = o0 < 0 || o1 < 0 || o2<0, has_pos = o0> 0 || o1 > 0 || o2 > 0;
    return !(has_neg && has_pos) && (has_neg || has_pos);
}

/// The axis to drop when projecting onto the plane with normal n.
int dominant_axis(const Vec3& n) noexcept
{
    const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
    return ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
}

P2 project(const Vec3& p, int drop) noexcept
{
    return drop == 0 ? P2{p.y, p.z} : (drop == 1 ? P2{p.z, p.x} : P2{p.x, p.y});
}

/// Coplanar triangles (or a segment, as a triangle with two equal corners) overlap.
template <bool Exact>
bool coplanar_meet(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) noexcept
{
    Vec3 n = core::cross(b[1] - b[0], b[2] - b[0]);
    if (core::dot(n, n) == 0.0)
        n = core::cross(a[1] - a[0], a[2] - a[0]);
    if (core::dot(n, n) == 0.0)
    {
        // both degenerate: any plane through them; take the normal of the points' spread
        const Vec3 e = core::dot(a[1] - a[0], a[1] - a[0]) > core::dot(a[2] - a[0], a[2] - a[0])
                           ? a[1] - a[0]
                           : a[2] - a[0];
        n = core::cross(e, std::abs(e.x) < std::abs(e.y) ? Vec3{1, 0, 0} : Vec3{0, 1, 0});
    }
    const int drop = dominant_axis(n);
    std::array<P2, 3> pa, pb;
    for (int k = 0; k < 3; ++k)
    {
        pa[static_cast<std::size_t>(k)] = project(a[static_cast<std::size_t>(k)], drop);
        pb[static_cast<std::size_t>(k)] = project(b[static_cast<std::size_t>(k)], drop);
    }
    for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j)
            if (segments_meet<Exact>(pa[i], pa[(i + 1) % 3], pb[j], pb[(j + 1) % 3]))
                return true;
    return in_triangle<Exact>(pb, pa[0]) || in_triangle<Exact>(pa, pb[0]);
}

/// Whether a, b and c lie on one line (or coincide): every axis-plane projection collinear.
template <bool Exact>
bool collinear(const Vec3& a, const Vec3& b, const Vec3& c) noexcept
{
    for (int drop = 0; drop < 3; ++drop)
        if (orient2d<Exact>(project(a, drop), project(b, drop), project(c, drop)) != 0)
            return false;
    return true;
}

/// The two ends of the collinear points t: their least and greatest along the axis they spread
/// most on (exact comparisons).
std::array<Vec3, 2> ends(const std::array<Vec3, 3>& t) noexcept
{
    double Vec3::*axis = &Vec3::x;
    double spread = -1.0;
    for (double Vec3::*c : {&Vec3::x, &Vec3::y, &Vec3::z})
    {
        const double s =
            std::max({t[0].*c, t[1].*c, t[2].*c}) - std::min({t[0].*c, t[1].*c, t[2].*c});
        if (s > spread)
        {
            spread = s;
            axis = c;
        }
    }
    const auto by = [axis](const Vec3& u, const Vec3& v) { return u.*axis < v.*axis; };
    return {*std::min_element(t.begin(), t.end(), by), *std::max_element(t.begin(), t.end(), by)};
}

/// Closed segments pq and rs of space (either may be a point) share a point.
template <bool Exact>
bool segments_meet_in_space(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) noexcept
{
    if (orient3d<Exact>(p, q, r, s) != 0)
        return false;  // not in one plane
    if (collinear<Exact>(p, q, r) && collinear<Exact>(p, q, s) && collinear<Exact>(r, s, p) &&
        collinear<Exact>(r, s, q))
    {
        // on one line (or points): overlap along the axis the four spread most on
        const std::array<Vec3, 2> e = ends({p, q, r});
        const std::array<Vec3, 2> f = ends({e[0], e[1], s});
        double Vec3::*axis = &Vec3::x;
        double spread = -1.0;
        for (double Vec3::*c : {&Vec3::x, &Vec3::y, &Vec3::z})
            if (std::abs(f[1].*c - f[0].*c) > spread)
            {
                spread = std::abs(f[1].*c - f[0].*c);
                axis = c;
            }
        return std::max(std::min(p.*axis, q.*axis), std::min(r.*axis, s.*axis)) <=
               std::min(std::max(p.*axis, q.*axis), std::max(r.*axis, s.*axis));
    }
    // In one plane, not on one line: project along the axis its normal leans on most (the
    // best-conditioned of the normals the four points give).
    Vec3 n{};
    for (const Vec3& m : {core::cross(q - p, r - p), core::cross(q - p, s - p),
                          core::cross(s - r, p - r), core::cross(s - r, q - r)})
        if (core::dot(m, m) > core::dot(n, n))
            n = m;
    const int drop = dominant_axis(n);
    return segments_meet<Exact>(project(p, drop), project(q, drop), project(r, drop),
                                project(s, drop));
}

/// Closed segment pq meets closed triangle t, knowing the signs of p and q against t's plane.
template <bool Exact>
bool segment_meets_triangle(const Vec3& p, const Vec3& q, int sp, int sq,
                            const std::array<Vec3, 3>& t) noexcept
{
    if (sp * sq > 0)
        return false;

    // A degenerate t (its points on one line, every sign 0) is a segment of space: the two
    // need not lie in one plane, which coplanar_meet assumes.
    if constexpr (Exact)
        if (sp == 0 && sq == 0 && collinear<Exact>(t[0], t[1], t[2]))
        {
            const std::array<Vec3, 2> e = ends(t);
            return segments_meet_in_space<Exact>(p, q, e[0], e[1]);
        }
    if (sp == 0 && sq == 0)
        return coplanar_meet<Exact>({p, q, q}, t);
    const int o0 = orient3d<Exact>(p, q, t[0], t[1]), o1 = orient3d<Exact>(p, q, t[1], t[2]),
              o2 = orient3d<Exact>(p, q, t[2], t[0]);
    const bool has_neg = o0 < 0 || o1 < 0 || o2<0, has_pos = o0> 0 || o1 > 0 || o2 > 0;
    if (has_neg && has_pos)
        return false;
    if (has_neg || has_pos)
        return true;
    // the line pq lies in... every orientation zero: t is degenerate and collinear with pq
    return coplanar_meet<Exact>({p, q, q}, t);
}

struct Cell
{
    std::uint64_t key;
    std::uint32_t face;
};

template <bool Exact>
bool edge_meets(const Vec3& p, const Vec3& q, const std::array<Vec3, 3>& t) noexcept
{
    // Disjoint boxes (exact comparisons): no common point. Around a vertex of high valence
    // every pair of its faces passes the broad phase (their boxes share the vertex), but the
    // edges opposite it seldom reach the other face's box: a flat fan of 2,500 faces took
    // 6 million orientation tests for nothing.
    const auto apart = [&](double Vec3::*c)
    {
        const double lo = std::min(p.*c, q.*c), hi = std::max(p.*c, q.*c);
        return hi < std::min({t[0].*c, t[1].*c, t[2].*c}) ||
               lo > std::max({t[0].*c, t[1].*c, t[2].*c});
    };
    // Exact only: the double-only test errs towards "meet" within its rounding bound, and the
    // untangling, which uses it, is left as it was.
    if constexpr (Exact)
        if (apart(&Vec3::x) || apart(&Vec3::y) || apart(&Vec3::z))
            return false;
    return segment_meets_triangle<Exact>(p, q, orient3d<Exact>(t[0], t[1], t[2], p),
                                         orient3d<Exact>(t[0], t[1], t[2], q), t);
}

template <bool Exact>
bool triangles_meet(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) noexcept
{
    std::array<int, 3> sa{}, sb{};
    for (std::size_t k = 0; k < 3; ++k)
    {
        sa[k] = orient3d<Exact>(b[0], b[1], b[2], a[k]);
        sb[k] = orient3d<Exact>(a[0], a[1], a[2], b[k]);
    }
    const auto separated = [](const std::array<int, 3>& s)
    { return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0); };
    if (separated(sa) || separated(sb))
        return false;
    const bool flat_a = sa[0] == 0 && sa[1] == 0 && sa[2] == 0;
    const bool flat_b = sb[0] == 0 && sb[1] == 0 && sb[2] == 0;
    if (flat_a || flat_b)
    {
        // a lies in b's plane (or b in a's): if the other is not degenerate they are coplanar;
        // a degenerate one is a segment, which the edge tests below handle as well (each
        // edge against a degenerate face as two segments of space, segment_meets_triangle)
        if (flat_a && flat_b)
        {
            if constexpr (Exact)
                if (collinear<Exact>(a[0], a[1], a[2]) && collinear<Exact>(b[0], b[1], b[2]))
                {
                    const std::array<Vec3, 2> ea = ends(a), eb = ends(b);
                    return segments_meet_in_space<Exact>(ea[0], ea[1], eb[0], eb[1]);
                }
            return coplanar_meet<Exact>(a, b);
        }
    }
    for (std::size_t k = 0; k < 3; ++k)
    {
        const std::size_t l = (k + 1) % 3;
        if (segment_meets_triangle<Exact>(a[k], a[l], sa[k], sa[l], b))
            return true;
        if (segment_meets_triangle<Exact>(b[k], b[l], sb[k], sb[l], a))
            return true;
    }
    return false;
}

template <bool Exact>
bool faces_meet(const mesh::TriMesh& mesh, std::uint32_t f, std::uint32_t g) noexcept
{
    const auto& tf = mesh.faces[f];
    const auto& tg = mesh.faces[g];
    int shared = 0;
    std::size_t kf = 0, kg = 0;
    for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j)
            if (tf[i] == tg[j])
            {
                ++shared;
                kf = i;
                kg = j;
            }
    if (shared >= 2)
        return false;
    const std::array<Vec3, 3> a{mesh.positions[tf[0]], mesh.positions[tf[1]],
                                mesh.positions[tf[2]]};
    const std::array<Vec3, 3> b{mesh.positions[tg[0]], mesh.positions[tg[1]],
                                mesh.positions[tg[2]]};
    if (shared == 0)
        return triangles_meet<Exact>(a, b);
    return edge_meets<Exact>(a[(kf + 1) % 3], a[(kf + 2) % 3], b) ||
           edge_meets<Exact>(b[(kg + 1) % 3], b[(kg + 2) % 3], a);
}

}  // namespace

bool edge_meets_triangle(const Vec3& p, const Vec3& q, const std::array<Vec3, 3>& t) noexcept
{
    return edge_meets<true>(p, q, t);
}

bool triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) noexcept
{
    return triangles_meet<true>(a, b);
}

bool faces_intersect(const mesh::TriMesh& mesh, std::uint32_t f, std::uint32_t g,
                     bool exact) noexcept
{
    return exact ? faces_meet<true>(mesh, f, g) : faces_meet<false>(mesh, f, g);
}

namespace
{

constexpr double k_two_pi = 6.283185307179586;

/// A vertex whose fan is a simple star (vertex_fan_is_star), with what the pairs' search needs.
struct Star
{
    std::uint32_t v = 0;
    Vec3 d, u, w;                      ///< the projection's direction; u, w, d right-handed
    std::vector<std::uint32_t> faces;  ///< the fan's faces (mesh ids) in turning order
    /// theta[i] .. theta[i + 1]: the angles of face i's image about v's in (u, w), within
    /// 1e-10 rad; non-decreasing, theta[n] = theta[0] + 2 pi. Empty where some edge from v is
    /// within 1e-6 of d (its image's angle is then ill-conditioned): every face is a candidate.
    std::vector<double> theta;
    /// |(x - v) . d| <= height_per_radius |image of x - v| on every face of the fan (+inf
    /// where no bound is known): a point nearer the axis than that is in none of them.
    double height_per_radius = std::numeric_limits<double>::infinity();
};

/// The angle of e's image in (u, w), or NaN when the image lies within 1e-6 |e| of the origin
/// (its angle would be uncertain by more than 1e-10 rad).
double image_angle(const Star& s, const Vec3& e) noexcept
{
    const double a = core::dot(e, s.u), b = core::dot(e, s.w);
    if (!(std::hypot(a, b) >= 1e-6 * core::norm(e)) || !(a != 0.0 || b != 0.0))
        return std::numeric_limits<double>::quiet_NaN();
    return std::atan2(b, a);
}

std::optional<Star> certify_star(const mesh::TriMesh& mesh, std::uint32_t v,
                                 std::span<const std::uint32_t> around)
{
    const std::size_t n = around.size();
    if (n < 3)
        return std::nullopt;
    // Each face as (v, a, b) in its own orientation; a cycle when every a is the b of exactly
    // one other face, followed from the first.
    struct Wedge
    {
        std::uint32_t a, b, face;
    };
    std::vector<Wedge> fan(n);
    for (std::size_t i = 0; i < n; ++i)
    {
        const auto& t = mesh.faces[around[i]];
        const int k = t[0] == v ? 0 : (t[1] == v ? 1 : (t[2] == v ? 2 : -1));
        if (k < 0)
            return std::nullopt;
        const std::uint32_t a = t[static_cast<std::size_t>((k + 1) % 3)];
        const std::uint32_t b = t[static_cast<std::size_t>((k + 2) % 3)];
        if (a == v || b == v || a == b)
            return std::nullopt;
        fan[i] = {a, b, around[i]};
    }
    std::sort(fan.begin(), fan.end(), [](const Wedge& x, const Wedge& y) { return x.a < y.a; });
    for (std::size_t i = 1; i < n; ++i)
        if (fan[i].a == fan[i - 1].a)
            return std::nullopt;  // two faces leave v along one edge on the same side
    // The successor of a face is the face whose a is its b. Returning to the first face after
    // exactly n steps, and not before, visits every face once (a path that repeated another
    // face would circle without it).
    const auto next = [&](std::size_t i) -> std::size_t
    {
        const auto it = std::lower_bound(fan.begin(), fan.end(), fan[i].b,
                                         [](const Wedge& x, std::uint32_t a) { return x.a < a; });
        return it != fan.end() && it->a == fan[i].b ? static_cast<std::size_t>(it - fan.begin())
                                                    : n;
    };
    Star star;
    star.v = v;
    star.faces.reserve(n);
    std::vector<std::uint32_t> link;  // a of each face in turning order
    link.reserve(n);
    std::size_t at = 0;
    for (std::size_t step = 1; step <= n; ++step)
    {
        star.faces.push_back(fan[at].face);
        link.push_back(fan[at].a);
        at = next(at);
        if (at == n || (at == 0) != (step == n))
            return std::nullopt;
    }
    // The direction to project along: the faces' summed normal.
    const Vec3& p = mesh.positions[v];
    Vec3 d{0.0, 0.0, 0.0};
    for (std::size_t i = 0; i < n; ++i)
        d += core::cross(mesh.positions[link[i]] - p, mesh.positions[link[(i + 1) % n]] - p);
    const double dn = core::norm(d);
    if (!(dn > 0.0) || !std::isfinite(dn))
        return std::nullopt;
    d = d / dn;
    // Every face's image turns the same way about v's, by far more than rounding can blur
    // (each difference is rounded once, so the computed s is within about 1e-15 |e1| |e2| of
    // the true one), and the images' angles make one full turn: then they tile the plane
    // around v's image once, and non-neighbours' images meet only there.
    constexpr double k_margin = 1e-10;
    double turn = 0.0;
    for (std::size_t i = 0; i < n; ++i)
    {
        const Vec3 e1 = mesh.positions[link[i]] - p, e2 = mesh.positions[link[(i + 1) % n]] - p;
        const double s = core::dot(d, core::cross(e1, e2));
        if (!(s > k_margin * core::norm(e1) * core::norm(e2)))
            return std::nullopt;
        const Vec3 q1 = e1 - d * core::dot(e1, d), q2 = e2 - d * core::dot(e2, d);
        turn += std::atan2(s, core::dot(q1, q2));
    }
    if (!(std::abs(turn - k_two_pi) < 1.0))
        return std::nullopt;
    star.d = d;
    star.u = core::normalized(
        core::cross(d, std::abs(d.x) <= std::abs(d.y) && std::abs(d.x) <= std::abs(d.z)
                           ? Vec3{1, 0, 0}
                           : (std::abs(d.y) <= std::abs(d.z) ? Vec3{0, 1, 0} : Vec3{0, 0, 1})));
    star.w = core::cross(d, star.u);
    // The wedges' angles, unwrapped: each true step is in (0, pi), so a computed drop of more
    // than pi is a wrap. Each theta is a direct atan2 (errors do not add up along the fan).
    std::vector<double> theta(n + 1);
    int wraps = 0;
    for (std::size_t i = 0; i <= n; ++i)
    {
        const double a = image_angle(star, mesh.positions[link[i % n]] - p);
        if (std::isnan(a))
            return star;  // no angular search
        theta[i] = a + k_two_pi * wraps;
        if (i > 0 && theta[i] < theta[i - 1] - 3.14159265358979)
        {
            ++wraps;
            theta[i] += k_two_pi;
        }
        if (i > 0)
            theta[i] = std::max(theta[i], theta[i - 1]);
    }
    if (wraps == 1 && theta[n] == theta[0] + k_two_pi)
        star.theta = std::move(theta);
    // On face (v, v + e1, v + e2) a point s e1 + t e2 from v (s, t >= 0, s + t <= 1) has height
    // at most (s + t) max |h_i| and image radius at least (s + t) times the distance from the
    // origin to the segment between the corners' images. Rounding: relative 1e-6 at worst (the
    // margin above keeps every segment clear of the origin); the bound is widened by 1e-4.
    double k = 0.0;
    for (std::size_t i = 0; i < n; ++i)
    {
        const Vec3 e1 = mesh.positions[link[i]] - p, e2 = mesh.positions[link[(i + 1) % n]] - p;
        const double x1 = core::dot(e1, star.u), y1 = core::dot(e1, star.w);
        const double x2 = core::dot(e2, star.u), y2 = core::dot(e2, star.w);
        const double dx = x2 - x1, dy = y2 - y1;
        const double along = -(x1 * dx + y1 * dy) / (dx * dx + dy * dy);
        const double dist = along <= 0.0   ? std::hypot(x1, y1)
                            : along >= 1.0 ? std::hypot(x2, y2)
                                           : std::abs(x1 * y2 - y1 * x2) / std::hypot(dx, dy);
        k = std::max(k, std::max(std::abs(core::dot(e1, d)), std::abs(core::dot(e2, d))) / dist);
    }
    if (std::isfinite(k))
        star.height_per_radius = k * (1.0 + 1e-4);
    return star;
}

}  // namespace

bool vertex_fan_is_star(const mesh::TriMesh& mesh, std::uint32_t v,
                        std::span<const std::uint32_t> around)
{
    return certify_star(mesh, v, around).has_value();
}

namespace
{

/// Whether the plane of face f passes clear of the box (lo, hi) by more than rounding could
/// hide: then f has no point in the box. Any common point of two faces lies in the overlap of
/// their boxes and on both planes, so long slivers whose boxes overlap widely (a cylinder's
/// sides beside a fan-split cap) are told apart here, before the narrow phase. The computed
/// distance and radius are within about 1e-15 (|n| + |e1| |e2|) (|c - a| + |half|) of the true
/// ones; the margin is a thousand times that. A degenerate face (n = 0) never misses.
bool plane_misses_box(const mesh::TriMesh& mesh, std::uint32_t f,
                      const std::array<Vec3, 2>& box) noexcept
{
    const auto& t = mesh.faces[f];
    const Vec3& a = mesh.positions[t[0]];
    const Vec3 e1 = mesh.positions[t[1]] - a, e2 = mesh.positions[t[2]] - a;
    const Vec3 n = core::cross(e1, e2);
    // The box from a, before halving: each difference is then rounded once, relative to its
    // own size (a centre taken first is rounded relative to the coordinates, which can exceed
    // a thin overlap's size: touching faces far from the origin were dropped).
    const Vec3 from = box[0] - a, till = box[1] - a;
    const Vec3 to = (from + till) * 0.5, half = (till - from) * 0.5;
    const double dist = std::abs(core::dot(n, to));
    const double radius = std::abs(n.x) * half.x + std::abs(n.y) * half.y + std::abs(n.z) * half.z;
    const auto l1 = [](const Vec3& x) { return std::abs(x.x) + std::abs(x.y) + std::abs(x.z); };
    constexpr double k_margin = 1e-12;
    const double slack = k_margin * (l1(n) + l1(e1) * l1(e2)) * (l1(to) + l1(half));
    return dist > radius + slack;
}

/// The stars (certify_star), by ascending vertex, among the vertices of at least
/// k_star_valence faces of `subset` (empty: every face; `nf` its size). A fan is judged whole,
/// from every face of the mesh around the vertex.
std::vector<Star> find_stars(const mesh::TriMesh& mesh, std::span<const std::uint32_t> subset,
                             std::size_t nf)
{
    // Below this the fan's pairs cost less than finding it.
    constexpr std::uint32_t k_star_valence = 16;
    std::vector<Star> stars;
    if (nf < k_star_valence)
        return stars;
    std::vector<std::uint32_t> count(mesh.positions.size(), 0);
    for (std::size_t i = 0; i < nf; ++i)
        for (const std::uint32_t x : mesh.faces[subset.empty() ? i : subset[i]])
            ++count[x];
    std::vector<std::uint32_t> candidates;
    for (std::size_t x = 0; x < count.size(); ++x)
    {
        const bool many = count[x] >= k_star_valence;
        // from here on: 1 + the candidate's slot, or 0
        count[x] = many ? static_cast<std::uint32_t>(candidates.size()) + 1 : 0;
        if (many)
            candidates.push_back(static_cast<std::uint32_t>(x));
    }
    if (candidates.empty())
        return stars;
    std::vector<std::vector<std::uint32_t>> around(candidates.size());
    for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    {
        const auto& t = mesh.faces[f];
        for (std::size_t k = 0; k < 3; ++k)
            // a face holding a vertex twice is listed once (and refused by the check)
            if (count[t[k]] != 0 && (k == 0 || t[k] != t[0]) && (k < 2 || t[2] != t[1]))
                around[count[t[k]] - 1].push_back(static_cast<std::uint32_t>(f));
    }
    for (std::size_t c = 0; c < candidates.size(); ++c)
        if (auto star = certify_star(mesh, candidates[c], around[c]))
            stars.push_back(std::move(*star));
    return stars;
}

/// Calls take(k) for every face k (index into s.faces) whose image's angular range about v's
/// can share a direction with the image of the triangle (v + e[0], v + e[1], v + e[2]); every
/// k where the angles cannot tell (an image near v's, or around it).
template <typename Take>
void star_candidates(const Star& s, const std::array<Vec3, 3>& e, Take&& take)
{
    const std::size_t n = s.faces.size();
    const auto every = [&]
    {
        for (std::size_t k = 0; k < n; ++k)
            take(k);
    };
    if (s.theta.empty())
        return every();
    constexpr double k_half_turn = 3.14159265358979;
    constexpr double k_slack = 1e-8;  // a hundred times the angles' errors
    std::array<double, 3> a{};
    int near = -1;  // the corner whose image lies near the origin (its angle uncertain)
    for (std::size_t k = 0; k < 3; ++k)
    {
        a[k] = image_angle(s, e[k]);
        if (std::isnan(a[k]))
        {
            if (near >= 0)
                return every();
            near = static_cast<int>(k);
        }
    }
    double lo = 0.0, span = 0.0;
    if (near < 0)
    {
        std::sort(a.begin(), a.end());
        // The image's directions: the arc its corners span, the complement of the largest gap
        // between their angles, when that gap exceeds a half turn (else the image may hold
        // v's).
        const std::array<double, 3> gap{a[1] - a[0], a[2] - a[1], a[0] + k_two_pi - a[2]};
        const std::size_t g = gap[0] >= gap[1] && gap[0] >= gap[2] ? 0 : (gap[1] >= gap[2] ? 1 : 2);
        if (!(gap[g] > k_half_turn + 2.0 * k_slack))
            return every();
        lo = a[(g + 1) % 3] - k_slack;
        span = k_two_pi - gap[g] + 2.0 * k_slack;
    }
    else
    {
        // One corner on (or near) the axis through v, as a cap's centre below a cone's apex.
        // If the triangle keeps a height of at least H from v's plane, its points with image
        // radius under rho = H / height_per_radius are in none of the fan's faces; its image
        // lies within eps (that corner's radius) of the cone over the other two corners, so
        // every image point beyond rho lies within asin(eps / rho) < (pi / 2) eps / rho of
        // their arc.
        const auto c = static_cast<std::size_t>(near);
        const std::size_t c1 = (c + 1) % 3, c2 = (c + 2) % 3;
        const double h0 = core::dot(e[0], s.d), h1 = core::dot(e[1], s.d),
                     h2 = core::dot(e[2], s.d);
        if (!((h0 > 0.0 && h1 > 0.0 && h2 > 0.0) || (h0 < 0.0 && h1 < 0.0 && h2 < 0.0)))
            return every();
        const double height = std::min({std::abs(h0), std::abs(h1), std::abs(h2)}) * (1.0 - 1e-9);
        const double rho = height / s.height_per_radius;
        const double eps =
            std::hypot(core::dot(e[c], s.u), core::dot(e[c], s.w)) + 1e-15 * core::norm(e[c]);
        if (!(eps < 0.5 * rho))
            return every();
        double from = a[c1], to = a[c2];
        double arc = to - from;
        arc -= k_two_pi * std::floor(arc / k_two_pi);  // into [0, 2 pi)
        if (arc > k_half_turn)
        {
            std::swap(from, to);
            arc = k_two_pi - arc;
        }
        const double widen = 1.5707963267948966 * eps / rho + k_slack;
        if (!(arc + 2.0 * widen < k_half_turn))
            return every();
        lo = from - widen;
        span = arc + 2.0 * widen;
    }
    const double t0 = s.theta.front();
    lo = t0 + (lo - t0) - k_two_pi * std::floor((lo - t0) / k_two_pi);  // into [t0, t0 + 2 pi)
    const auto wedges = [&](double from, double to)
    {
        // wedges k with theta[k + 1] >= from and theta[k] <= to
        const auto first = static_cast<std::size_t>(
            std::lower_bound(s.theta.begin() + 1, s.theta.end(), from) - (s.theta.begin() + 1));
        const auto last = static_cast<std::size_t>(
            std::upper_bound(s.theta.begin(), s.theta.begin() + static_cast<std::ptrdiff_t>(n),
                             to) -
            s.theta.begin());
        for (std::size_t k = first; k < last; ++k)
            take(k);
    };
    const double hi = lo + span;
    if (hi <= t0 + k_two_pi)
        return wedges(lo, hi);
    // across the seam: the part before it, then the part after it (disjoint wedges unless the
    // two parts meet in one, which the first part ends before)
    const std::size_t before = static_cast<std::size_t>(
        std::upper_bound(s.theta.begin(), s.theta.begin() + static_cast<std::ptrdiff_t>(n),
                         hi - k_two_pi) -
        s.theta.begin());
    wedges(lo, t0 + k_two_pi);
    const auto first = static_cast<std::size_t>(
        std::lower_bound(s.theta.begin() + 1, s.theta.end(), lo) - (s.theta.begin() + 1));
    for (std::size_t k = 0; k < std::min(before, first); ++k)
        take(k);
}

/// The pairs of intersecting_pairs among the faces `subset` (ascending face ids; empty: every
/// face) with at least one face marked in `touched` (empty: all), sorted. The broad phase finds
/// every pair whose boxes overlap whatever the grid, so the result depends on the subset and
/// the two faces' positions only.
std::vector<std::array<std::uint32_t, 2>> pairs_among(const mesh::TriMesh& mesh,
                                                      std::span<const std::uint32_t> subset,
                                                      std::span<const std::uint8_t> touched,
                                                      const core::ProgressSink* stop,
                                                      std::size_t crowded_cell,
                                                      std::size_t* crowded_faces = nullptr)
{
    const std::size_t nf = subset.empty() ? mesh.faces.size() : subset.size();
    const auto face_at = [&](std::size_t i)
    { return subset.empty() ? static_cast<std::uint32_t>(i) : subset[i]; };
    std::vector<std::array<std::uint32_t, 2>> pairs;
    // Between the serial stages (a sort of a level-10 grid's cells takes a second or more).
    const auto asked = [&] { return stop != nullptr && stop->stop_requested(); };
    if (nf < 2 || asked())
        return pairs;
    // face boxes and the grid (indices i, j below are into the subset)
    std::vector<std::array<Vec3, 2>> box(nf);
    Vec3 lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
            std::numeric_limits<double>::max()};
    Vec3 hi = lo * -1.0;
    double extent = 0.0;
    for (std::size_t f = 0; f < nf; ++f)
    {
        const auto& t = mesh.faces[face_at(f)];
        const Vec3& a = mesh.positions[t[0]];
        const Vec3& b = mesh.positions[t[1]];
        const Vec3& c = mesh.positions[t[2]];
        const Vec3 bl{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}),
                      std::min({a.z, b.z, c.z})};
        const Vec3 bh{std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}),
                      std::max({a.z, b.z, c.z})};
        box[f] = {bl, bh};
        lo = {std::min(lo.x, bl.x), std::min(lo.y, bl.y), std::min(lo.z, bl.z)};
        hi = {std::max(hi.x, bh.x), std::max(hi.y, bh.y), std::max(hi.z, bh.z)};
        extent += (bh.x - bl.x) + (bh.y - bl.y) + (bh.z - bl.z);
    }
    const Vec3 size = hi - lo;
    double h = 2.0 * extent / (3.0 * static_cast<double>(nf));
    // at most about 8 cells per face overall keeps the table small on very uneven meshes
    const double max_cells = 8.0 * static_cast<double>(nf) + 64.0;
    const auto cells_at = [&](double s)
    {
        return (std::floor(size.x / s) + 1.0) * (std::floor(size.y / s) + 1.0) *
               (std::floor(size.z / s) + 1.0);
    };
    if (!(h > 0.0))
        h = std::max({size.x, size.y, size.z, 1e-300});
    while (cells_at(h) > max_cells)
        h *= 1.25;
    const auto nx = static_cast<std::uint64_t>(std::floor(size.x / h)) + 1;
    const auto ny = static_cast<std::uint64_t>(std::floor(size.y / h)) + 1;
    const auto nz = static_cast<std::uint64_t>(std::floor(size.z / h)) + 1;
    const auto cell_of = [&](double v, double l, std::uint64_t n)
    {
        const double c = std::floor((v - l) / h);
        return std::min(static_cast<std::uint64_t>(std::max(c, 0.0)), n - 1);
    };
    const auto key_of = [&](std::uint64_t i, std::uint64_t j, std::uint64_t k)
    { return (i * ny + j) * nz + k; };

    if (asked())
        return pairs;
    // Stars (certify_star): around a vertex of high valence every pair of faces passes the
    // broad phase (their boxes share the vertex), none of them meets, and long slivers around
    // it (a cone's sides, a fan-split cap) overlap the boxes of much of the mesh. A face's
    // group is its lowest star vertex. Pairs with a grouped face are found per star, by angle
    // about the star's vertex (star_candidates), not by the grid: the pass over the grid pairs
    // ungrouped faces only.
    constexpr std::uint32_t k_no_star = std::numeric_limits<std::uint32_t>::max();
    const std::vector<Star> stars = find_stars(mesh, subset, nf);
    std::vector<std::uint32_t> group;  // per subset face: index into stars, or k_no_star
    if (!stars.empty())
    {
        group.assign(nf, k_no_star);
        for (std::size_t f = 0; f < nf; ++f)
            for (const std::uint32_t x : mesh.faces[face_at(f)])
            {
                const auto it =
                    std::lower_bound(stars.begin(), stars.end(), x,
                                     [](const Star& s, std::uint32_t y) { return s.v < y; });
                if (it != stars.end() && it->v == x)
                    group[f] = std::min(group[f], static_cast<std::uint32_t>(it - stars.begin()));
            }
    }
    const auto group_of = [&](std::size_t f) { return group.empty() ? k_no_star : group[f]; };

    if (asked())
        return pairs;
    std::vector<Cell> cells;
    cells.reserve(nf * 4);
    for (std::size_t f = 0; f < nf; ++f)
    {
        const auto& [bl, bh] = box[f];
        const std::uint64_t i0 = cell_of(bl.x, lo.x, nx), i1 = cell_of(bh.x, lo.x, nx);
        const std::uint64_t j0 = cell_of(bl.y, lo.y, ny), j1 = cell_of(bh.y, lo.y, ny);
        const std::uint64_t k0 = cell_of(bl.z, lo.z, nz), k1 = cell_of(bh.z, lo.z, nz);
        for (std::uint64_t i = i0; i <= i1; ++i)
            for (std::uint64_t j = j0; j <= j1; ++j)
                for (std::uint64_t k = k0; k <= k1; ++k)
                    cells.push_back({key_of(i, j, k), static_cast<std::uint32_t>(f)});
    }
    if (asked())
        return pairs;
    std::sort(cells.begin(), cells.end(),
              [](const Cell& x, const Cell& y)
              { return x.key != y.key ? x.key < y.key : x.face < y.face; });
    if (asked())
        return pairs;
    std::vector<std::size_t> runs;
    for (std::size_t i = 0; i < cells.size(); ++i)
        if (i == 0 || cells[i].key != cells[i - 1].key)
            runs.push_back(i);
    runs.push_back(cells.size());
    const auto nruns = static_cast<std::int64_t>(runs.size()) - 1;

    // Crowded cells: more than `crowded_cell` ungrouped faces. Long slanted slivers side by side
    // (a finely divided cylinder) make the cells as large as they are long, and each close pair
    // of them shares every cell along them in any finer grid, so a cell's pairs grow as the
    // square of their density. The faces of crowded cells are paired with each other by a tree
    // of boxes oriented along them (obb_tree.h) instead; the grid pairs the rest, skipping the
    // crowded cells (every ungrouped face there is crowded) and any pair of two crowded faces.
    std::vector<std::uint8_t> crowded;  // per subset face
    std::vector<std::uint32_t> crowd;   // the crowded subset faces, ascending
    std::vector<std::uint8_t> run_crowded(runs.size(), 0);
    for (std::int64_t r = 0; r < nruns; ++r)
    {
        const auto r0 = runs[static_cast<std::size_t>(r)];
        const auto r1 = runs[static_cast<std::size_t>(r) + 1];
        std::size_t ungrouped = 0;
        for (std::size_t i = r0; i < r1; ++i)
            ungrouped += group_of(cells[i].face) == k_no_star ? 1 : 0;
        if (ungrouped <= crowded_cell)
            continue;
        run_crowded[static_cast<std::size_t>(r)] = 1;
        if (crowded.empty())
            crowded.assign(nf, 0);
        for (std::size_t i = r0; i < r1; ++i)
            if (group_of(cells[i].face) == k_no_star)
                crowded[cells[i].face] = 1;
    }
    std::optional<detail::ObbTree> tree;
    std::vector<detail::ObbTree::Job> tree_jobs;
    if (!crowded.empty())
    {
        std::vector<std::uint32_t> crowd_faces;
        std::vector<std::uint8_t> crowd_touched;
        for (std::size_t f = 0; f < nf; ++f)
            if (crowded[f] != 0)
            {
                crowd.push_back(static_cast<std::uint32_t>(f));
                crowd_faces.push_back(face_at(f));
                if (!touched.empty())
                    crowd_touched.push_back(touched[face_at(f)]);
            }
        tree.emplace(mesh, crowd_faces, crowd_touched, stop);
#ifdef _OPENMP
        const auto threads = static_cast<std::size_t>(omp_get_max_threads());
#else
        const std::size_t threads = 1;
#endif
        tree_jobs = tree->jobs(64 * threads);
    }
    if (crowded_faces != nullptr)
        *crowded_faces = crowd.size();
    const auto both_crowded = [&](std::uint32_t f, std::uint32_t g)
    { return !crowded.empty() && crowded[f] != 0 && crowded[g] != 0; };
    if (asked())
        return pairs;

    // Per star s: the faces g whose boxes overlap the box of s's faces, neither in s's group
    // nor in a lower star's (that star pairs them), from the grid's cells over that box; and
    // where each of s's faces lies in the subset.
    struct StarWork
    {
        std::vector<std::uint32_t> others;  // subset indices
        std::vector<std::uint32_t> slot;    // per face of the star: subset index or k_no_star
    };
    std::vector<StarWork> work(stars.size());
    if (!stars.empty())
    {
        std::vector<std::uint32_t> seen(nf, k_no_star);
        for (std::size_t s = 0; s < stars.size(); ++s)
        {
            const Star& star = stars[s];
            StarWork& sw = work[s];
            Vec3 sl = mesh.positions[star.v], sh = sl;
            sw.slot.assign(star.faces.size(), k_no_star);
            for (std::size_t k = 0; k < star.faces.size(); ++k)
            {
                const std::uint32_t f = star.faces[k];
                for (const std::uint32_t x : mesh.faces[f])
                {
                    const Vec3& q = mesh.positions[x];
                    sl = {std::min(sl.x, q.x), std::min(sl.y, q.y), std::min(sl.z, q.z)};
                    sh = {std::max(sh.x, q.x), std::max(sh.y, q.y), std::max(sh.z, q.z)};
                }
                if (subset.empty())
                    sw.slot[k] = f;
                else if (const auto it = std::lower_bound(subset.begin(), subset.end(), f);
                         it != subset.end() && *it == f)
                    sw.slot[k] = static_cast<std::uint32_t>(it - subset.begin());
            }
            const std::uint64_t i0 = cell_of(sl.x, lo.x, nx), i1 = cell_of(sh.x, lo.x, nx);
            const std::uint64_t j0 = cell_of(sl.y, lo.y, ny), j1 = cell_of(sh.y, lo.y, ny);
            const std::uint64_t k0 = cell_of(sl.z, lo.z, nz), k1 = cell_of(sh.z, lo.z, nz);
            for (std::uint64_t i = i0; i <= i1; ++i)
                for (std::uint64_t j = j0; j <= j1; ++j)
                {
                    // keys k0..k1 of column (i, j) are consecutive
                    auto c = std::lower_bound(cells.begin(), cells.end(), key_of(i, j, k0),
                                              [](const Cell& x, std::uint64_t key)
                                              { return x.key < key; });
                    for (; c != cells.end() && c->key <= key_of(i, j, k1); ++c)
                    {
                        const std::uint32_t g = c->face;
                        const std::uint32_t gg = group_of(g);
                        if (seen[g] == s || (gg != k_no_star && gg <= s))
                            continue;
                        seen[g] = static_cast<std::uint32_t>(s);
                        const auto& bg = box[g];
                        if (bg[1].x < sl.x || sh.x < bg[0].x || bg[1].y < sl.y || sh.y < bg[0].y ||
                            bg[1].z < sl.z || sh.z < bg[0].z)
                            continue;
                        sw.others.push_back(g);
                    }
                }
            if (asked())
                return pairs;
        }
    }

    // A stop asked of `stop` (polled by thread 0 only: a sink need not be thread-safe) ends
    // every thread's work at its next cell, face or tree node (thread 0 polls at each of the
    // tree's jobs and every 1,024 nodes it visits).
    std::atomic<bool> halt{false};
    const auto halted = [&](bool poll)
    {
        if (halt.load(std::memory_order_relaxed))
            return true;
#ifdef _OPENMP
        poll = poll && stop != nullptr && omp_get_thread_num() == 0;
#endif
        if (poll && stop != nullptr && stop->stop_requested())
            halt.store(true, std::memory_order_relaxed);
        return halt.load(std::memory_order_relaxed);
    };
    // An exception must not leave the parallel region (std::terminate): the first one (a
    // std::bad_alloc as the pairs grow) stops every thread and is thrown again after it.
    std::exception_ptr failure;
    const auto fail = [&]
    {
#pragma omp critical(pliant_remesh_intersections_failure)
        if (!failure)
            failure = std::current_exception();
        halt.store(true, std::memory_order_relaxed);
    };
    // The narrow phase of subset faces f and g whose boxes overlap.
    const auto test =
        [&](std::uint32_t f, std::uint32_t g, std::vector<std::array<std::uint32_t, 2>>& local)
    {
        const std::uint32_t mf = face_at(f), mg = face_at(g);
        if (!touched.empty() && touched[mf] == 0 && touched[mg] == 0)
            return;
        const auto& bf = box[f];
        const auto& bg = box[g];
        const std::array<Vec3, 2> overlap{
            Vec3{std::max(bf[0].x, bg[0].x), std::max(bf[0].y, bg[0].y),
                 std::max(bf[0].z, bg[0].z)},
            Vec3{std::min(bf[1].x, bg[1].x), std::min(bf[1].y, bg[1].y),
                 std::min(bf[1].z, bg[1].z)}};
        // (faces sharing a vertex: it lies in the overlap and on both planes)
        const auto& tf = mesh.faces[mf];
        const auto& tg = mesh.faces[mg];
        const bool apart =
            std::none_of(tf.begin(), tf.end(),
                         [&](std::uint32_t x) { return x == tg[0] || x == tg[1] || x == tg[2]; });
        if (apart && (plane_misses_box(mesh, mf, overlap) || plane_misses_box(mesh, mg, overlap)))
            return;
        if (faces_meet<true>(mesh, mf, mg))
            local.push_back({std::min(mf, mg), std::max(mf, mg)});
    };
    const auto boxes_apart = [&](std::uint32_t f, std::uint32_t g)
    {
        const auto& bf = box[f];
        const auto& bg = box[g];
        return bf[1].x < bg[0].x || bg[1].x < bf[0].x || bf[1].y < bg[0].y || bg[1].y < bf[0].y ||
               bf[1].z < bg[0].z || bg[1].z < bf[0].z;
    };
#pragma omp parallel
    {
        std::vector<std::array<std::uint32_t, 2>> local;
#pragma omp for schedule(dynamic, 64) nowait
        for (std::int64_t r = 0; r < nruns; ++r)
        {
            if (halted((r & 63) == 0) || run_crowded[static_cast<std::size_t>(r)] != 0)
                continue;
            try
            {
                const auto r0 = runs[static_cast<std::size_t>(r)];
                const auto r1 = runs[static_cast<std::size_t>(r) + 1];
                const std::uint64_t key = cells[r0].key;
                // f ungrouped, g any: test each pair once, in the cell of the low corner of the
                // boxes' overlap
                const auto pair_up = [&](std::uint32_t f, std::uint32_t g)
                {
                    if (group_of(g) != k_no_star || both_crowded(f, g) || boxes_apart(f, g))
                        return;
                    const auto& bf = box[f];
                    const auto& bg = box[g];
                    const std::uint64_t own = key_of(cell_of(std::max(bf[0].x, bg[0].x), lo.x, nx),
                                                     cell_of(std::max(bf[0].y, bg[0].y), lo.y, ny),
                                                     cell_of(std::max(bf[0].z, bg[0].z), lo.z, nz));
                    if (own == key)
                        test(f, g, local);
                };
                for (std::size_t i = r0; i < r1 && !halted(((i - r0) & 255U) == 255U); ++i)
                    if (group_of(cells[i].face) == k_no_star)
                        for (std::size_t j = i + 1; j < r1; ++j)
                            pair_up(cells[i].face, cells[j].face);
            }
            catch (...)
            {
                fail();
            }
        }
        // The crowded faces with each other, by the tree.
        const auto njobs = static_cast<std::int64_t>(tree_jobs.size());
#pragma omp for schedule(dynamic, 1) nowait
        for (std::int64_t q = 0; q < njobs; ++q)
        {
            if (halted(true))
                continue;
            try
            {
                tree->visit(
                    tree_jobs[static_cast<std::size_t>(q)],
                    [&](std::uint32_t i, std::uint32_t j)
                    {
                        const std::uint32_t f = crowd[i];
                        const std::uint32_t g = crowd[j];
                        if (!boxes_apart(f, g))
                            test(f, g, local);
                    },
                    [&, visits = std::uint32_t{0}]() mutable
                    { return halted((++visits & 1023U) == 0); });
            }
            catch (...)
            {
                fail();
            }
        }
        // Each star's faces against the others it gathered: only the faces whose wedges
        // share a direction with the other's image can meet it (certify_star).
        for (std::size_t s = 0; s < stars.size(); ++s)
        {
            const Star& star = stars[s];
            const StarWork& sw = work[s];
            const auto nothers = static_cast<std::int64_t>(sw.others.size());
#pragma omp for schedule(dynamic, 64) nowait
            for (std::int64_t o = 0; o < nothers; ++o)
            {
                if (halted((o & 63) == 0))
                    continue;
                try
                {
                    const std::uint32_t g = sw.others[static_cast<std::size_t>(o)];
                    const auto& tg = mesh.faces[face_at(g)];
                    const Vec3& p = mesh.positions[star.v];
                    const std::array<Vec3, 3> e{mesh.positions[tg[0]] - p,
                                                mesh.positions[tg[1]] - p,
                                                mesh.positions[tg[2]] - p};
                    star_candidates(
                        star, e,
                        [&](std::size_t k)
                        {
                            const std::uint32_t f = sw.slot[k];
                            if (f != k_no_star && group_of(f) == s && !boxes_apart(f, g))
                                test(f, g, local);
                        });
                }
                catch (...)
                {
                    fail();
                }
            }
        }
#pragma omp critical(pliant_remesh_intersections)
        try
        {
            pairs.insert(pairs.end(), local.begin(), local.end());
        }
        catch (...)
        {
            fail();
        }
    }
    if (failure)
        std::rethrow_exception(failure);
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

}  // namespace

std::vector<std::array<std::uint32_t, 2>> intersecting_pairs(const mesh::TriMesh& mesh,
                                                             const core::ProgressSink* stop)
{
    return pairs_among(mesh, {}, {}, stop, detail::k_crowded_cell);
}

namespace
{

std::vector<std::array<std::uint32_t, 2>> pairs_touching(const mesh::TriMesh& mesh,
                                                         std::span<const std::uint8_t> touched,
                                                         const core::ProgressSink* stop,
                                                         std::size_t crowded_cell,
                                                         std::size_t* crowded_faces = nullptr)
{
    PLIANT_ASSERT(touched.size() == mesh.faces.size(),
                  "intersecting_pairs_touching: one flag per face");
    // The touched faces, and every face whose box meets theirs' union (the only ones that can
    // meet a touched face).
    Vec3 lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
            std::numeric_limits<double>::max()};
    Vec3 hi = lo * -1.0;
    bool any = false;
    for (std::size_t f = 0; f < mesh.faces.size(); ++f)
        if (touched[f] != 0)
        {
            any = true;
            for (const std::uint32_t v : mesh.faces[f])
            {
                const Vec3& p = mesh.positions[v];
                lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
                hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
            }
        }
    if (!any)
        return {};
    std::vector<std::uint32_t> subset;
    for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    {
        if (touched[f] == 0)
        {
            const auto& t = mesh.faces[f];
            const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]],
                       &c = mesh.positions[t[2]];
            if (std::max({a.x, b.x, c.x}) < lo.x || hi.x < std::min({a.x, b.x, c.x}) ||
                std::max({a.y, b.y, c.y}) < lo.y || hi.y < std::min({a.y, b.y, c.y}) ||
                std::max({a.z, b.z, c.z}) < lo.z || hi.z < std::min({a.z, b.z, c.z}))
                continue;
        }
        subset.push_back(static_cast<std::uint32_t>(f));
    }
    return pairs_among(mesh, subset, touched, stop, crowded_cell, crowded_faces);
}

}  // namespace

std::vector<std::array<std::uint32_t, 2>> intersecting_pairs_touching(
    const mesh::TriMesh& mesh, std::span<const std::uint8_t> touched,
    const core::ProgressSink* stop)
{
    return pairs_touching(mesh, touched, stop, detail::k_crowded_cell);
}

detail::PairsWith detail::intersecting_pairs_with(const mesh::TriMesh& mesh,
                                                  std::span<const std::uint8_t> touched,
                                                  std::size_t crowded_cell,
                                                  const core::ProgressSink* stop)
{
    PairsWith out;
    out.pairs = touched.empty() ? pairs_among(mesh, {}, {}, stop, crowded_cell, &out.crowded)
                                : pairs_touching(mesh, touched, stop, crowded_cell, &out.crowded);
    return out;
}

std::size_t count_self_intersections(const mesh::TriMesh& mesh, const core::ProgressSink* stop)
{
    return intersecting_pairs(mesh, stop).size();
}

bool is_folded(const mesh::TriMesh& output, std::size_t f, const mesh::TriMesh& input,
               std::span<const std::uint32_t> sample_faces) noexcept
{
    const auto& t = output.faces[f];
    const Vec3 n = core::cross(output.positions[t[1]] - output.positions[t[0]],
                               output.positions[t[2]] - output.positions[t[0]]);
    bool against_all = true;
    for (const std::uint32_t v : t)
    {
        const auto& s = input.faces[sample_faces[v]];
        const Vec3 m = core::cross(input.positions[s[1]] - input.positions[s[0]],
                                   input.positions[s[2]] - input.positions[s[0]]);
        against_all = against_all && core::dot(n, m) < 0.0;
    }
    return against_all;
}

std::size_t count_folded(const mesh::TriMesh& output, const mesh::TriMesh& input,
                         std::span<const std::uint32_t> sample_faces) noexcept
{
    std::size_t n = 0;
    for (std::size_t f = 0; f < output.faces.size(); ++f)
        n += is_folded(output, f, input, sample_faces) ? 1 : 0;
    return n;
}

}  // namespace pliant::remesh
