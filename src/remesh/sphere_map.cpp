// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Spherical parameterization (design in include/pliant/remesh/sphere_map.h, docs/remesh.md).
//
// The coarse-to-fine embedder keeps one invariant from the first tetrahedron to the last
// vertex: every present face is positively oriented on the sphere. Vertex moves evaluate the
// area-weighted L2 stretch of the vertex's faces, which is +inf for a non-positive face, and a
// move is accepted only when the energy decreases, so a move can never leave the kernel of the
// one-ring. A re-inserted vertex starts at a point of its one-ring's kernel found by a search
// that provably ends (points close enough to the vertex it was split from, inside the wedge of
// the two new faces, are in the kernel).

#include <pliant/remesh/sphere_map.h>

#include "remesh/locate_internal.h"
#include "remesh/progressive_mesh.h"
#include "remesh/sphere_geometry_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace pliant::remesh
{
namespace
{

using core::Vec3;
using detail::orient;

constexpr double k_inf = std::numeric_limits<double>::infinity();

Vec3 area_centroid(const mesh::TriMesh& m)
{
    Vec3 c{};
    double total = 0.0;
    for (const auto& f : m.faces)
    {
        const Vec3& a = m.positions[f[0]];
        const Vec3& b = m.positions[f[1]];
        const Vec3& d = m.positions[f[2]];
        const double area = 0.5 * core::norm(core::cross(b - a, d - a));
        c += (a + b + d) * (area / 3.0);
        total += area;
    }
    return total > 0.0 ? c / total : c;
}

double surface_area(const mesh::TriMesh& m)
{
    double a = 0.0;
    for (const auto& f : m.faces)
        a += 0.5 * core::norm(core::cross(m.positions[f[1]] - m.positions[f[0]],
                                          m.positions[f[2]] - m.positions[f[0]]));
    return a;
}

std::vector<Vec3> gnomonic(const mesh::TriMesh& m)
{
    const Vec3 c = area_centroid(m);
    std::vector<Vec3> q(m.positions.size());
    for (std::size_t i = 0; i < q.size(); ++i)
    {
        const Vec3 d = m.positions[i] - c;
        // a vertex exactly at the centre has no direction: any fixed one, the fold count decides
        q[i] = core::dot(d, d) > 0.0 ? core::normalized(d) : Vec3{0.0, 0.0, 1.0};
    }
    return q;
}

/// Tangent basis at a unit vector.
void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2) noexcept
{
    const Vec3 a = std::abs(n.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    t1 = core::normalized(core::cross(n, a));
    t2 = core::cross(n, t1);
}

/// The paper's spring embedder on the gnomonic projection (see the header). Returns the folds
/// left.
std::size_t spring_embed(const mesh::TriMesh& m, const SphereMapSettings& s,
                         const detail::VertexFaces& vf, std::vector<Vec3>& q,
                         core::ProgressSink& progress)
{
    const std::size_t n = q.size();
    // one-ring neighbour lists (each neighbour once per incident face: the weights double
    // evenly, so the mean is the plain neighbour mean)
    std::size_t folds = count_inverted(m.faces, q);
    for (int it = 0; it < s.spring_iterations && folds > 0; ++it)
    {
        for (std::uint32_t i = 0; i < n; ++i)
        {
            Vec3 mean{};
            int count = 0;
            for (const std::uint32_t f : vf.of(i))
                for (const std::uint32_t w : m.faces[f])
                    if (w != i)
                    {
                        mean += q[w];
                        ++count;
                    }
            // relaxation toward the neighbour mean (paper eq. 3.3); the radial force
            // (1-|x|) x̂ in its stiff limit is the projection back onto the sphere
            const Vec3 x = q[i] * (1.0 - s.relaxation) + mean * (s.relaxation / count);
            if (core::dot(x, x) > 0.0)
                q[i] = core::normalized(x);
        }
        // keep the centroid of the points at the origin, so relaxation cannot drift everything
        // toward one pole (the degenerate fixed point of neighbour averaging)
        Vec3 c{};
        for (const Vec3& p : q)
            c += p;
        c = c / static_cast<double>(n);
        for (Vec3& p : q)
        {
            const Vec3 d = p - c;
            if (core::dot(d, d) > 0.0)
                p = core::normalized(d);
        }
        if (it % 10 == 9)
        {
            if (progress.stop_requested())
                break;  // map_to_sphere returns Cancelled
            folds = count_inverted(m.faces, q);
            progress.update("spring embedder",
                            static_cast<double>(it + 1) / static_cast<double>(s.spring_iterations));
        }
    }
    progress.update("spring embedder", 1.0);
    return count_inverted(m.faces, q);
}

/// A point well inside the spherical kernel of vertex u's one-ring: the kernel is convex, so in
/// the gnomonic chart of the tangent plane at `centre` (a point of the kernel's closure) it is
/// the intersection of half-planes, one per face; the polygon is clipped from a square and its
/// area centroid returned. Empty optional when the clipped polygon has no area.
std::optional<Vec3> kernel_point(const std::vector<mesh::Face>& faces,
                                 const std::vector<std::uint32_t>& fs, const std::vector<Vec3>& q,
                                 std::uint32_t u, const Vec3& centre)
{
    Vec3 t1, t2;
    tangent_basis(centre, t1, t2);
    struct P2
    {
        double s, r;
    };
    std::vector<P2> poly{{-2.0, -2.0}, {2.0, -2.0}, {2.0, 2.0}, {-2.0, 2.0}}, next;
    for (const std::uint32_t f : fs)
    {
        const auto& t = faces[f];
        std::size_t k = 0;
        while (t[k] != u)
            ++k;
        // det[x, b, c] = x·(b×c) > 0 with x = centre + s t1 + r t2
        const Vec3 m = core::cross(q[t[(k + 1) % 3]], q[t[(k + 2) % 3]]);
        const double c0 = core::dot(m, centre), cs = core::dot(m, t1), cr = core::dot(m, t2);
        next.clear();
        for (std::size_t i = 0; i < poly.size(); ++i)
        {
            const P2 a = poly[i], b = poly[(i + 1) % poly.size()];
            const double da = c0 + cs * a.s + cr * a.r, db = c0 + cs * b.s + cr * b.r;
            if (da >= 0.0)
                next.push_back(a);
            if ((da >= 0.0) != (db >= 0.0))
            {
                const double w = da / (da - db);
                next.push_back({a.s + w * (b.s - a.s), a.r + w * (b.r - a.r)});
            }
        }
        poly.swap(next);
        if (poly.size() < 3)
            return std::nullopt;
    }
    double area = 0.0, cs = 0.0, cr = 0.0;
    for (std::size_t i = 0; i < poly.size(); ++i)
    {
        const P2 a = poly[i], b = poly[(i + 1) % poly.size()];
        const double cr2 = a.s * b.r - b.s * a.r;
        area += cr2;
        cs += (a.s + b.s) * cr2;
        cr += (a.r + b.r) * cr2;
    }
    if (!(area > 0.0))
        return std::nullopt;
    return core::normalized(centre + t1 * (cs / (3.0 * area)) + t2 * (cr / (3.0 * area)));
}

/// Stretch-minimising vertex moves inside the one-ring kernel, on a mesh whose faces change
/// (coarse to fine) or not (final sweeps).
class StretchOptimizer
{
public:
    StretchOptimizer(const std::vector<Vec3>& pos, std::vector<mesh::Face>& faces,
                     std::vector<std::vector<std::uint32_t>>& vf, std::vector<Vec3>& q)
        : pos_(pos), faces_(faces), vf_(vf), q_(q), step_(pos.size(), 0.0)
    {
    }

    /// Scales the surface so that its area equals the sphere's (4 pi), which makes the
    /// symmetric term's balance point an area-preserving map; `inverse_weight` weighs the
    /// inverse stretch (oversampling) against the stretch (undersampling).
    void set_metric(double surface_area, double inverse_weight, double peak_weight) noexcept
    {
        peak_weight_ = peak_weight;
        scale2_ = surface_area > 0.0 ? 4.0 * 3.14159265358979323846 / surface_area : 1.0;
        inverse_weight_ = inverse_weight;
    }

    /// Energy of vertex i's faces with i at `x`.
    [[nodiscard]] double energy(std::uint32_t i, const Vec3& x) const noexcept
    {
        double e = 0.0;
        for (const std::uint32_t f : vf_[i])
        {
            const auto& t = faces_[f];
            std::array<Vec3, 3> qq{q_[t[0]], q_[t[1]], q_[t[2]]};
            for (std::size_t k = 0; k < 3; ++k)
                if (t[k] == i)
                    qq[k] = x;
            e += face_energy(t, qq);
            if (e == k_inf)
                return e;
        }
        if (kink_weight_ > 0.0 && !kink_.empty())
            for (const std::uint32_t f : vf_[i])
                for (std::uint32_t slot = 0; slot < 3; ++slot)
                {
                    const Kink& kk = kink_[3 * f + slot];
                    const auto& tg = faces_[kk.other];
                    // an edge between two faces of the star is met from both: count it once
                    if ((tg[0] == i || tg[1] == i || tg[2] == i) && kk.other < f)
                        continue;
                    const auto& t = faces_[f];
                    const auto at = [&](std::uint32_t v) -> const Vec3&
                    { return v == i ? x : q_[v]; };
                    e += kink_energy(kk, at(t[slot]), at(t[(slot + 1) % 3]), at(t[(slot + 2) % 3]),
                                     at(kk.opposite));
                    if (e == k_inf)
                        return e;
                }
        return e;
    }

    /// Surface side of the kink of the edge in slot `slot` of face f: the edge (t[slot],
    /// t[slot+1]) of face A = f, opposite vertex t[slot+2]; face B = other, opposite vertex
    /// `opposite`. Both surface triangles unfolded into the plane about the edge: length lp,
    /// the opposite vertices at (ci, gi) on A's side and (cl, -gl) on B's.
    struct Kink
    {
        std::uint32_t other = 0, opposite = 0;
        double lp = 0.0, ci = 0.0, gi = 0.0, cl = 0.0, gl = 0.0, area = 0.0;
    };

    /// Kink term of one edge (see enable_kink): the shear of J_A^-1 J_B along the edge in the
    /// domain, normalised by the square root of its determinant.
    ///
    /// In the edge frame (j at the origin, k on the x axis) of both unfolded quadrilaterals, the
    /// chord side has k at (lq, 0), i at (ai, hi), l at (al, -hl), and the surface side the
    /// Kink's coordinates. Both Jacobians map the x axis to itself with scale s = lp / lq, so
    /// J_A = [[s, uA], [0, vA]] with uA = (ci - s ai) / hi, vA = gi / hi, and J_B likewise with
    /// uB = (s al - cl) / hl, vB = gl / hl. Then K = J_A^-1 J_B = [[1, beta], [0, gamma]] with
    /// beta = (uB vA - uA vB) / (s vA), gamma = vB / vA, and
    ///   mu^2 = beta^2 / gamma = (al gi + ai gl - (cl gi + ci gl) / s)^2 / (gi gl hi hl),
    /// symmetric in A and B, 0 when the two faces share one affine map. A sampled grid
    /// triangle across the edge can fold once mu exceeds about 3.5 (docs/remesh.md §1.2).
    [[nodiscard]] double kink_energy(const Kink& kk, const Vec3& qj, const Vec3& qk, const Vec3& qi,
                                     const Vec3& ql) const noexcept
    {
        const Vec3 t = qk - qj;
        const double lq2 = core::dot(t, t);
        if (!(lq2 > 0.0))
            return k_inf;
        const double lq = std::sqrt(lq2);
        const Vec3 ri = qi - qj, rl = ql - qj;
        const double ai = core::dot(ri, t) / lq, al = core::dot(rl, t) / lq;
        const double hi = core::norm(core::cross(ri, t)) / lq;
        const double hl = core::norm(core::cross(rl, t)) / lq;
        if (!(hi > 0.0) || !(hl > 0.0))
            return k_inf;
        const double s = kk.lp / lq;
        const double num = al * kk.gi + ai * kk.gl - (kk.cl * kk.gi + kk.ci * kk.gl) / s;
        const double mu2 = num * num / (kk.gi * kk.gl * hi * hl);
        return kink_weight_ * kk.area * mu2;
    }

    [[nodiscard]] double face_energy(const mesh::Face& t,
                                     const std::array<Vec3, 3>& qq) const noexcept
    {
        const Vec3& p0 = pos_[t[0]];
        const Vec3& p1 = pos_[t[1]];
        const Vec3& p2 = pos_[t[2]];
        const Vec3 a = p2 - p1, b = p0 - p2, c = p1 - p0;
        double area3d = 0.5 * core::norm(core::cross(c, p2 - p0));
        double la = core::dot(a, a), lb = core::dot(b, b), lc = core::dot(c, c);
        if (!represented_.empty())
        {
            // coarse level: the face stands for the fine surface its vertices absorbed; keep
            // its shape, give it that area (an equilateral shape for a degenerate face)
            double target = 0.0;
            for (const std::uint32_t v : t)
                target += represented_[v] / static_cast<double>(vf_[v].size());
            if (area3d * 100.0 > target)
            {
                const double k = target / area3d;
                la *= k;
                lb *= k;
                lc *= k;
            }
            else
                la = lb = lc = 4.0 / std::sqrt(3.0) * target;
            area3d = target;
        }
        area3d *= scale2_;
        la *= scale2_;
        lb *= scale2_;
        lc *= scale2_;
        if (!split_)
            return chord_energy(qq[0], qq[1], qq[2], la, lb, lc, area3d);
        if (!(orient(qq[0], qq[1], qq[2]) > 0.0))
            return k_inf;
        // Split at the point of the longest arc nearest to the opposite vertex (Praun & Hoppe's
        // remedy for the "accordion" effect): a spherical sliver whose vertices lie near one
        // great circle keeps a chord triangle of fair area, so the chord stretch alone does not
        // see it; its two halves are slivers in the chord sense too.
        const std::array<double, 3> l2{la, lb, lc};  // squared surface edge opposite vertex k
        const std::array<double, 3> e2{core::dot(qq[1] - qq[2], qq[1] - qq[2]),
                                       core::dot(qq[2] - qq[0], qq[2] - qq[0]),
                                       core::dot(qq[0] - qq[1], qq[0] - qq[1])};
        const std::size_t i = e2[0] > e2[1] ? (e2[0] > e2[2] ? 0 : 2) : (e2[1] > e2[2] ? 1 : 2);
        const std::size_t j = (i + 1) % 3, k = (i + 2) % 3;
        const Vec3 n = core::cross(qq[j], qq[k]);
        const double nn = core::dot(n, n);
        if (!(nn > 0.0))
            return k_inf;
        const Vec3 foot = qq[i] - n * (core::dot(n, qq[i]) / nn);
        const double fn = core::dot(foot, foot);
        if (!(fn > 0.0))
            return k_inf;
        const Vec3 d = foot * (1.0 / std::sqrt(fn));
        // d = alpha q_j + beta q_k; the chord point w q_j + (1 - w) q_k lies on d's ray
        const double alpha = core::dot(core::cross(d, qq[k]), n);
        const double beta = core::dot(core::cross(qq[j], d), n);
        if (!(alpha > 0.0) || !(beta > 0.0))
            return chord_energy(qq[0], qq[1], qq[2], la, lb, lc, area3d);
        const double w = alpha / (alpha + beta);
        // surface point P = w p_j + (1 - w) p_k; |P - p_i|^2 by Stewart's theorem
        const double lpi = std::max(0.0, w * l2[k] + (1.0 - w) * l2[j] - w * (1.0 - w) * l2[i]);
        // halves (d, q_i, q_j) ~ (P, p_i, p_j), area (1 - w) A, and (d, q_k, q_i) ~ (P, p_k,
        // p_i), area w A
        const double ea = chord_energy(d, qq[i], qq[j], l2[k], (1.0 - w) * (1.0 - w) * l2[i], lpi,
                                       (1.0 - w) * area3d);
        if (!(ea < k_inf))
            return k_inf;
        return ea + chord_energy(d, qq[k], qq[i], l2[j], lpi, w * w * l2[i], w * area3d);
    }

    /// Energy of one chord triangle against a surface triangle given by its squared edge
    /// lengths (opposite each vertex) and area, all already scaled.
    [[nodiscard]] double chord_energy(const Vec3& q0, const Vec3& q1, const Vec3& q2, double l0,
                                      double l1, double l2, double area3d) const noexcept
    {
        const double e = detail::stretch_term(q0, q1, q2, l0, l1, l2, area3d);
        if (!(e < k_inf) || !(area3d > 0.0))
            return e;
        // symmetric term: ||J^-1||^2 = ||J||^2 / det(J)^2 with det(J) = A3d / A_param
        const double ap = 0.5 * core::norm(core::cross(q1 - q0, q2 - q0));
        const double r = ap / area3d;
        // peak term ("anti-cruft", after Praun & Hoppe): the face's squared stretch s^2 =
        // e / A3d to the third power, so a small region of extreme undersampling costs more
        // than its area share
        const double s2 = e / area3d;
        return e * (1.0 + inverse_weight_ * r * r) + peak_weight_ * area3d * s2 * s2 * s2;
    }

    /// Total energy over the given faces.
    [[nodiscard]] double total(std::span<const std::uint8_t> alive) const noexcept
    {
        double e = 0.0;
        for (std::size_t f = 0; f < faces_.size(); ++f)
            if (alive.empty() || alive[f])
            {
                const auto& t = faces_[f];
                e += face_energy(t, {q_[t[0]], q_[t[1]], q_[t[2]]});
                if (kink_weight_ > 0.0 && !kink_.empty())
                    for (std::uint32_t slot = 0; slot < 3; ++slot)
                    {
                        const Kink& kk = kink_[3 * f + slot];
                        if (kk.other < f)
                            continue;
                        e += kink_energy(kk, q_[t[slot]], q_[t[(slot + 1) % 3]],
                                         q_[t[(slot + 2) % 3]], q_[kk.opposite]);
                    }
            }
        return e;
    }

    /// Adds the kink term on the final mesh (faces fixed from here on).
    void enable_kink(double weight)
    {
        kink_weight_ = weight;
        const auto nb = detail::face_neighbours(faces_);
        kink_.assign(faces_.size() * 3, Kink{});
        const auto unfold = [](const Vec3& o, const Vec3& k, const Vec3& x, double& a, double& h)
        {
            const Vec3 t = core::normalized(k - o);
            const Vec3 r = x - o;
            a = core::dot(r, t);
            h = core::norm(core::cross(r, t));
        };
        for (std::uint32_t f = 0; f < faces_.size(); ++f)
            for (std::uint32_t slot = 0; slot < 3; ++slot)
            {
                const auto& t = faces_[f];
                Kink& kk = kink_[3 * f + slot];
                kk.other = nb[3 * f + slot];
                const auto& tb = faces_[kk.other];
                const std::uint32_t j = t[slot], k = t[(slot + 1) % 3], i = t[(slot + 2) % 3];
                kk.opposite =
                    tb[0] != j && tb[0] != k ? tb[0] : (tb[1] != j && tb[1] != k ? tb[1] : tb[2]);
                const double sc = std::sqrt(scale2_);
                kk.lp = core::norm(pos_[k] - pos_[j]) * sc;
                unfold(pos_[j], pos_[k], pos_[i], kk.ci, kk.gi);
                unfold(pos_[j], pos_[k], pos_[kk.opposite], kk.cl, kk.gl);
                kk.ci *= sc;
                kk.gi *= sc;
                kk.cl *= sc;
                kk.gl *= sc;
                const auto area = [&](const mesh::Face& g) {
                    return 0.5 * core::norm(
                                     core::cross(pos_[g[1]] - pos_[g[0]], pos_[g[2]] - pos_[g[0]]));
                };
                kk.area = 0.5 * (area(t) + area(tb)) * scale2_;
                if (!(kk.gi > 0.0) || !(kk.gl > 0.0))
                {
                    // a degenerate surface face has no Jacobian to compare: no term
                    kk.area = 0.0;
                    kk.gi = kk.gl = 1.0;
                }
            }
    }

    /// One descent step for vertex i: finite-difference gradient in the tangent plane, then a
    /// backtracking line search along the great circle. Never accepts a non-decrease, hence
    /// never a fold.
    void optimize(std::uint32_t i) noexcept
    {
        const Vec3 x0 = q_[i];
        const double e0 = energy(i, x0);
        if (!(e0 < k_inf))
            return;  // cannot happen while the invariant holds; leave the vertex alone
        double rmin = k_inf, rsum = 0.0;
        int rcount = 0;
        for (const std::uint32_t f : vf_[i])
            for (const std::uint32_t w : faces_[f])
                if (w != i)
                {
                    const double d = core::norm(q_[w] - x0);
                    rmin = std::min(rmin, d);
                    rsum += d;
                    ++rcount;
                }
        if (!(rmin > 0.0) || rmin == k_inf)
            return;
        const double rmean = rsum / rcount;
        // Move 1: toward the centroid of the one-ring's kernel. The kernel is convex in the
        // gnomonic chart, so the whole chord from x0 to the centroid stays inside it: this move
        // can jump out of a thin corner of the kernel where gradient steps crawl.
        if (const auto kc = kernel_point(faces_, vf_[i], q_, i, x0))
        {
            double best = e0;
            Vec3 bx = x0;
            double t = 1.0;
            for (int k = 0; k < 6; ++k, t *= 0.5)
            {
                const Vec3 x = core::normalized(x0 + (*kc - x0) * t);
                const double e = energy(i, x);
                if (e < best)
                {
                    best = e;
                    bx = x;
                }
                else if (best < e0)
                    break;
            }
            if (best < e0)
            {
                q_[i] = bx;
                return;
            }
        }
        Vec3 t1, t2;
        tangent_basis(x0, t1, t2);
        double h = 1e-4 * rmin;
        double g1 = 0.0, g2 = 0.0;
        bool ok = false;
        for (int tries = 0; tries < 4 && !ok; ++tries, h *= 0.05)
        {
            const double a = energy(i, core::normalized(x0 + t1 * h));
            const double b = energy(i, core::normalized(x0 - t1 * h));
            const double c = energy(i, core::normalized(x0 + t2 * h));
            const double d = energy(i, core::normalized(x0 - t2 * h));
            if (a < k_inf && b < k_inf && c < k_inf && d < k_inf)
            {
                g1 = (a - b) / (2.0 * h);
                g2 = (c - d) / (2.0 * h);
                ok = true;
            }
        }
        const double gn = std::sqrt(g1 * g1 + g2 * g2);
        if (!ok || !(gn > 0.0))
            return;
        const Vec3 dir = (t1 * g1 + t2 * g2) * (-1.0 / gn);
        // Backtrack from the last successful step (at most the ring's mean radius) to the first
        // decrease, then expand while doubling still decreases: the energy is a barrier (~1/d^2
        // near a fold), so a vertex squeezed against a neighbour needs steps many orders of
        // magnitude larger than its current distance, which expansion finds in log steps.
        double s = step_[i] > 0.0 ? std::min(step_[i], rmean) : 0.25 * rmean;
        double e = k_inf;
        Vec3 x;
        int k = 0;
        for (; k < 40; ++k, s *= 0.5)
        {
            x = core::normalized(x0 + dir * s);
            e = energy(i, x);
            if (e < e0)
                break;
        }
        if (k == 40)
        {
            step_[i] = 0.0;
            return;
        }
        if (k == 0)
        {
            for (int j = 0; j < 20 && 2.0 * s <= rmean; ++j)
            {
                const Vec3 x2 = core::normalized(x0 + dir * (2.0 * s));
                const double e2 = energy(i, x2);
                if (!(e2 < e))
                    break;
                s *= 2.0;
                x = x2;
                e = e2;
            }
        }
        q_[i] = x;
        step_[i] = 2.0 * s;
    }

private:
    const std::vector<Vec3>& pos_;
    std::vector<mesh::Face>& faces_;
    std::vector<std::vector<std::uint32_t>>& vf_;
    std::vector<Vec3>& q_;
    std::vector<double> step_;
    double scale2_ = 1.0;
    double inverse_weight_ = 0.0;
    double peak_weight_ = 0.0;
    double kink_weight_ = 0.0;
    std::vector<Kink> kink_;

public:
    /// Measure each face as two chord triangles split at its longest arc (see face_energy).
    bool split_ = true;
    /// Surface area each present vertex stands for (its own third of its input faces plus
    /// that of every vertex collapsed into it); empty = use the faces' own geometry.
    std::vector<double> represented_;
};

bool faces_positive(const std::vector<mesh::Face>& faces, const std::vector<std::uint32_t>& fs,
                    const std::vector<Vec3>& q, std::uint32_t i, const Vec3& x)
{
    for (const std::uint32_t f : fs)
    {
        std::array<Vec3, 3> qq{q[faces[f][0]], q[faces[f][1]], q[faces[f][2]]};
        for (std::size_t k = 0; k < 3; ++k)
            if (faces[f][k] == i)
                qq[k] = x;
        if (!(orient(qq[0], qq[1], qq[2]) > 0.0))
            return false;
    }
    return true;
}

/// Runs optimisation sweeps over `order` until the relative improvement is below `tol`.
void sweeps(StretchOptimizer& opt, std::span<const std::uint32_t> order, int count, double tol,
            std::span<const std::uint8_t> alive, core::ProgressSink* progress,
            std::string_view phase)
{
    double before = tol > 0.0 ? opt.total(alive) : 0.0;
    for (int k = 0; k < count && !core::stop_requested(progress); ++k)
    {
        for (const std::uint32_t v : order)
            opt.optimize(v);
        if (progress != nullptr)
            progress->update(phase, static_cast<double>(k + 1) / static_cast<double>(count));
        if (tol > 0.0)
        {
            const double after = opt.total(alive);
            if (before - after < tol * before)
                break;
            before = after;
        }
    }
}

core::Result<std::vector<Vec3>> coarse_to_fine(const mesh::TriMesh& m, const SphereMapSettings& s,
                                               core::ProgressSink& progress, std::size_t& forced)
{
    auto pm_result = detail::build_progressive_mesh(m, progress);
    if (!pm_result)
        return pm_result.error();
    const detail::ProgressiveMesh& pm = *pm_result;
    forced = pm.forced_collapses;

    const std::size_t nv = m.positions.size();
    std::vector<Vec3> q(nv, Vec3{0.0, 0.0, 1.0});
    std::vector<mesh::Face> faces = pm.coarse_faces;
    std::vector<std::uint8_t> alive = pm.coarse_alive;
    std::vector<std::vector<std::uint32_t>> vf(nv);
    for (std::uint32_t f = 0; f < faces.size(); ++f)
        if (alive[f])
            for (const std::uint32_t v : faces[f])
                vf[v].push_back(f);

    // the base tetrahedron on a regular tetrahedron's directions, oriented like the mesh
    const double r = 1.0 / std::sqrt(3.0);
    const std::array<Vec3, 4> tet{Vec3{r, r, r}, Vec3{r, -r, -r}, Vec3{-r, r, -r}, Vec3{-r, -r, r}};
    for (std::size_t k = 0; k < 4; ++k)
        q[pm.base_vertices[k]] = tet[k];
    {
        std::uint32_t f0 = 0;
        while (!alive[f0])
            ++f0;
        if (orient(q[faces[f0][0]], q[faces[f0][1]], q[faces[f0][2]]) < 0.0)
            std::swap(q[pm.base_vertices[0]], q[pm.base_vertices[1]]);
    }
    std::vector<std::uint32_t> present(pm.base_vertices.begin(), pm.base_vertices.end());
    present.reserve(nv);

    StretchOptimizer opt(m.positions, faces, vf, q);
    opt.split_ = s.split_stretch;
    const double area = surface_area(m);
    opt.set_metric(area, s.coarse_inverse_weight, s.peak_weight);
    if (s.represented_area)
    {
        opt.represented_.assign(nv, 0.0);
        for (const auto& f : m.faces)
        {
            const double a3 = core::norm(core::cross(m.positions[f[1]] - m.positions[f[0]],
                                                     m.positions[f[2]] - m.positions[f[0]])) /
                              6.0;
            for (const std::uint32_t v : f)
                opt.represented_[v] += a3;
        }
        for (const detail::Collapse& c : pm.collapses)
            opt.represented_[c.kept] += opt.represented_[c.removed];
    }
    std::vector<std::uint32_t> ring_scratch;
    double next_level = 4.0 * s.level_growth;
    const std::size_t total = pm.collapses.size();
    for (std::size_t k = total; k-- > 0;)
    {
        if ((k & 1023U) == 0 && progress.stop_requested())
            return core::cancelled("remesh", "sphere map");
        const detail::Collapse& c = pm.collapses[k];
        const std::uint32_t u = c.removed, v = c.kept;
        if (!opt.represented_.empty())
            opt.represented_[v] -= opt.represented_[u];
        for (std::uint32_t j = 0; j < c.modified_count; ++j)
        {
            const std::uint32_t f = pm.modified_faces[c.first_modified + j];
            for (auto& w : faces[f])
                if (w == v)
                    w = u;
            std::erase(vf[v], f);
            vf[u].push_back(f);
        }
        std::uint32_t apex_a = v, apex_b = v;  // faces (u, v, a) and (v, u, b)
        for (const std::uint32_t f : c.killed_faces)
        {
            alive[f] = 1;
            for (const std::uint32_t w : faces[f])
                vf[w].push_back(f);
            const auto& t = faces[f];
            std::size_t iu = 0;
            while (t[iu] != u)
                ++iu;
            if (t[(iu + 1) % 3] == v)
                apex_a = t[(iu + 2) % 3];
            else
                apex_b = t[(iu + 1) % 3];
        }
        // start point: the ring's mean direction if it is in the kernel, else a point close to
        // v inside the wedge left of v->a and right of v->b (always in the kernel, see top)
        Vec3 ring{};
        for (const std::uint32_t f : vf[u])
            for (const std::uint32_t w : faces[f])
                if (w != u)
                    ring += q[w];
        Vec3 x = core::normalized(ring);
        bool placed = core::dot(ring, ring) > 0.0 && faces_positive(faces, vf[u], q, u, x);
        if (!placed)
        {
            const auto kp = kernel_point(faces, vf[u], q, u, q[v]);
            if (kp && faces_positive(faces, vf[u], q, u, *kp))
            {
                x = *kp;
                placed = true;
            }
        }
        if (!placed)
        {
            const Vec3 n = q[v];
            Vec3 da = q[apex_a] - q[v];
            Vec3 db = q[apex_b] - q[v];
            da = core::normalized(da - n * core::dot(da, n));
            db = core::normalized(db - n * core::dot(db, n));
            Vec3 g = core::cross(n, da) - core::cross(n, db);
            if (!(core::dot(g, g) > 1e-30))
                g = core::cross(n, da);  // a and b in the same direction: any side of it
            g = core::normalized(g);
            double len = 0.5 * std::min(core::norm(q[apex_a] - q[v]), core::norm(q[apex_b] - q[v]));
            bool found = false;
            for (int it = 0; it < 200 && !found; ++it, len *= 0.5)
            {
                x = core::normalized(n + g * len);
                found = faces_positive(faces, vf[u], q, u, x);
            }
            if (!found)
                return core::fail(core::ErrorCode::InvertedTriangles,
                                  "remesh: no fold-free position for re-inserted vertex " +
                                      std::to_string(u) + " (numerical underflow)");
        }
        q[u] = x;
        present.push_back(u);
        opt.optimize(u);
        // the one-ring too (Praun & Hoppe): it widens the kernels of the next insertions
        ring_scratch.clear();
        for (const std::uint32_t f : vf[u])
            for (const std::uint32_t w : faces[f])
                if (w != u &&
                    std::find(ring_scratch.begin(), ring_scratch.end(), w) == ring_scratch.end())
                    ring_scratch.push_back(w);
        for (const std::uint32_t w : ring_scratch)
            opt.optimize(w);
        opt.optimize(u);
        if (static_cast<double>(present.size()) >= next_level)
        {
            if (progress.stop_requested())
                return core::cancelled("remesh", "sphere map");
            sweeps(opt, present, s.sweeps_per_level, 0.0, {}, nullptr, {});
            next_level *= s.level_growth;
            progress.update("sphere map",
                            static_cast<double>(total - k) / static_cast<double>(total + 1));
        }
    }
    PLIANT_ASSERT(faces == m.faces,
                  "coarse_to_fine: undoing the collapses did not restore the mesh");
    // all vertices present: the faces' own geometry from here on
    opt.represented_.clear();
    // and, from here on, the kink term (§1.2): it needs the final faces and their neighbours
    if (s.kink_weight > 0.0)
        opt.enable_kink(s.kink_weight);
    // anneal the inverse-stretch weight from the coarse value down to the final one: the
    // coarse value keeps the growing map isotropic (no sheared zones that local moves cannot
    // undo later), the final one trades some of that for lower L2 stretch
    for (double w = s.coarse_inverse_weight; w > s.inverse_weight;)
    {
        if (progress.stop_requested())
            return core::cancelled("remesh", "sphere map");
        w = std::max(s.inverse_weight, w * 0.5);
        opt.set_metric(area, w, s.peak_weight);
        sweeps(opt, present, s.sweeps_per_level, 0.0, {}, nullptr, {});
    }
    opt.set_metric(area, s.inverse_weight, s.peak_weight);
    progress.update("sphere map", 1.0);
    sweeps(opt, present, s.final_sweeps, s.tolerance, {}, &progress, "sphere optimise");
    if (progress.stop_requested())
        return core::cancelled("remesh", "sphere optimise");
    progress.update("sphere optimise", 1.0);
    return q;
}

}  // namespace

mesh::TriMesh split_for_map(const mesh::TriMesh& mesh, std::size_t min_faces)
{
    mesh::TriMesh out = mesh;
    while (out.faces.size() < min_faces && !out.faces.empty())
    {
        // one midpoint per undirected edge: the edges sorted by (low, high) end
        std::vector<std::array<std::uint32_t, 3>> edges;  // low, high, face * 3 + slot
        edges.reserve(out.faces.size() * 3);
        for (std::uint32_t f = 0; f < out.faces.size(); ++f)
            for (std::uint32_t k = 0; k < 3; ++k)
            {
                const std::uint32_t a = out.faces[f][k], b = out.faces[f][(k + 1) % 3];
                edges.push_back({std::min(a, b), std::max(a, b), 3 * f + k});
            }
        std::sort(edges.begin(), edges.end());
        std::vector<std::uint32_t> mid(out.faces.size() * 3);
        for (std::size_t e = 0; e < edges.size(); ++e)
        {
            if (e == 0 || edges[e][0] != edges[e - 1][0] || edges[e][1] != edges[e - 1][1])
                out.positions.push_back((out.positions[edges[e][0]] + out.positions[edges[e][1]]) *
                                        0.5);
            mid[edges[e][2]] = static_cast<std::uint32_t>(out.positions.size() - 1);
        }
        std::vector<mesh::Face> faces;
        faces.reserve(out.faces.size() * 4);
        for (std::uint32_t f = 0; f < out.faces.size(); ++f)
        {
            const auto& t = out.faces[f];
            const std::uint32_t m01 = mid[3 * f], m12 = mid[3 * f + 1], m20 = mid[3 * f + 2];
            faces.push_back({t[0], m01, m20});
            faces.push_back({m01, t[1], m12});
            faces.push_back({m20, m12, t[2]});
            faces.push_back({m01, m12, m20});
        }
        out.faces = std::move(faces);
    }
    return out;
}

std::size_t count_inverted(std::span<const mesh::Face> faces,
                           std::span<const core::Vec3> sphere) noexcept
{
    std::size_t n = 0;
    for (const auto& f : faces)
        if (!(orient(sphere[f[0]], sphere[f[1]], sphere[f[2]]) > 0.0))
            ++n;
    return n;
}

double signed_volume(const mesh::TriMesh& mesh) noexcept
{
    double v = 0.0;
    for (const auto& f : mesh.faces)
        v += core::dot(mesh.positions[f[0]],
                       core::cross(mesh.positions[f[1]], mesh.positions[f[2]]));
    return v / 6.0;
}

StretchStats measure_stretch(const mesh::TriMesh& mesh, std::span<const core::Vec3> sphere) noexcept
{
    double energy = 0.0, area3d = 0.0, area_param = 0.0;
    for (const auto& t : mesh.faces)
    {
        const Vec3& p0 = mesh.positions[t[0]];
        const Vec3& p1 = mesh.positions[t[1]];
        const Vec3& p2 = mesh.positions[t[2]];
        const Vec3 a = p2 - p1, b = p0 - p2, c = p1 - p0;
        const double a3 = 0.5 * core::norm(core::cross(c, p2 - p0));
        energy += detail::stretch_term(sphere[t[0]], sphere[t[1]], sphere[t[2]], core::dot(a, a),
                                       core::dot(b, b), core::dot(c, c), a3);
        area3d += a3;
        area_param +=
            0.5 * core::norm(core::cross(sphere[t[1]] - sphere[t[0]], sphere[t[2]] - sphere[t[0]]));
    }
    StretchStats s;
    if (!(area3d > 0.0) || !(energy < k_inf))
        return s;
    // raw rms^2 = energy / area3d; normalised by the area ratio so that uniform scaling is 1
    const double rms2 = energy / area3d * area_param / area3d;
    s.rms_stretch = std::sqrt(rms2);
    s.efficiency = 1.0 / rms2;
    return s;
}

core::Result<SphereMap> map_to_sphere(const mesh::TriMesh& mesh, const SphereMapSettings& settings,
                                      core::ProgressSink* progress)
{
    core::NullProgress null_progress;
    core::ProgressSink& sink = progress != nullptr ? *progress : null_progress;
    if (mesh.positions.size() < 4 || mesh.faces.size() < 4)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "map_to_sphere: a closed mesh needs at least 4 vertices and 4 faces");
    if (!(signed_volume(mesh) > 0.0))
        return core::fail(core::ErrorCode::InvalidArgument,
                          "map_to_sphere: faces are oriented inward (signed volume <= 0)");

    SphereMap out;
    out.points = gnomonic(mesh);
    out.gnomonic_folds = count_inverted(mesh.faces, out.points);

    bool need_robust = settings.method == SphereMethod::CoarseToFine;
    if (settings.method != SphereMethod::CoarseToFine)
    {
        const detail::VertexFaces vf = detail::vertex_faces(mesh.positions.size(), mesh.faces);
        out.spring_folds = spring_embed(mesh, settings, vf, out.points, sink);
        if (sink.stop_requested())
            return core::cancelled("remesh", "spring embedder");
        if (out.spring_folds > 0)
        {
            if (settings.method == SphereMethod::SpringEmbedder)
                return core::fail(core::ErrorCode::InvertedTriangles,
                                  "map_to_sphere: the spring embedder left " +
                                      std::to_string(out.spring_folds) + " of " +
                                      std::to_string(mesh.faces.size()) +
                                      " spherical triangles inverted");
            need_robust = true;
        }
        else
        {
            // fold-free: improve stretch with the same kernel-bounded moves as below
            std::vector<mesh::Face> faces = mesh.faces;
            std::vector<std::vector<std::uint32_t>> adj(mesh.positions.size());
            for (std::uint32_t f = 0; f < faces.size(); ++f)
                for (const std::uint32_t v : faces[f])
                    adj[v].push_back(f);
            StretchOptimizer opt(mesh.positions, faces, adj, out.points);
            opt.split_ = settings.split_stretch;
            opt.set_metric(surface_area(mesh), settings.inverse_weight, settings.peak_weight);
            std::vector<std::uint32_t> order(mesh.positions.size());
            for (std::uint32_t i = 0; i < order.size(); ++i)
                order[i] = i;
            // no hierarchy here: local moves need many more sweeps to spread stretch globally
            sweeps(opt, order, settings.spring_optimise_sweeps, settings.tolerance * 0.01, {},
                   &sink, "sphere optimise");
            if (sink.stop_requested())
                return core::cancelled("remesh", "sphere optimise");
            out.method_used = SphereMethod::SpringEmbedder;
        }
    }
    if (need_robust)
    {
        auto q = coarse_to_fine(mesh, settings, sink, out.forced_collapses);
        if (!q)
            return q.error();
        out.points = std::move(*q);
        out.method_used = SphereMethod::CoarseToFine;
    }

    const std::size_t folds = count_inverted(mesh.faces, out.points);
    if (folds > 0)
        return core::fail(core::ErrorCode::InvertedTriangles,
                          "map_to_sphere: " + std::to_string(folds) + " of " +
                              std::to_string(mesh.faces.size()) +
                              " spherical triangles inverted after the embedding");
    const StretchStats st = measure_stretch(mesh, out.points);
    out.rms_stretch = st.rms_stretch;
    out.stretch_efficiency = st.efficiency;
    return out;
}

}  // namespace pliant::remesh
