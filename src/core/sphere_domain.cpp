// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/sphere_domain.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace pliant::core
{
namespace
{

// Corners a, b, c, d of docs/design.md §1 (not normalised: the gnomonic formula below is the one
// the built-in sphere always used, kept bit for bit).
constexpr std::array<Vec3, 4> k_corner{Vec3{1.0, 1.0, 1.0}, Vec3{1.0, -1.0, -1.0},
                                       Vec3{-1.0, 1.0, -1.0}, Vec3{-1.0, -1.0, 1.0}};
enum Corner : int
{
    a = 0,
    b = 1,
    c = 2,
    d = 3
};

/// A node's face: its three corners and integer barycentric weights (summing to W).
struct FacePoint
{
    std::array<int, 3> corner;
    std::array<int, 3> weight;
};

FacePoint face_point(int w, int x, int y) noexcept
{
    if (x <= w)
    {
        if (y <= x)  // abc: a (0,0), b (W,0), c (W,W)
            return {{a, b, c}, {w - x, x - y, y}};
        return {{a, c, d}, {w - y, x, y - x}};  // acd: d (0,W)
    }
    const int xs = x - w;
    if (y <= xs)  // bad: b (W,0), a (2W,0), d (2W,W)
        return {{b, a, d}, {w - xs, xs - y, y}};
    return {{b, d, c}, {w - y, xs, y - xs}};  // bdc: c (W,W)
}

Vec3 gnomonic(int w, int x, int y, double radius) noexcept
{
    const Vec3& pa = k_corner[a];
    const Vec3& pb = k_corner[b];
    const Vec3& pc = k_corner[c];
    const Vec3& pd = k_corner[d];
    const double wd = w;
    Vec3 p;
    if (x <= w)
        p = y <= x ? pa + (pb - pa) * ((x - y) / wd) + (pc - pa) * (y / wd)
                   : pa + (pc - pa) * (x / wd) + (pd - pa) * ((y - x) / wd);
    else
    {
        const int xs = x - w;
        p = y <= xs ? pb + (pa - pb) * ((xs - y) / wd) + (pd - pb) * (y / wd)
                    : pb + (pd - pb) * (xs / wd) + (pc - pb) * ((y - xs) / wd);
    }
    return p * (radius / norm(p));
}

/// The equal-area map of one face (see the header). In the sub-triangle (O, v_i, v_j) of the
/// corner k with the smallest weight, the ray from the centre O through the point meets the edge
/// v_i v_j at E = (1 − t) v_i + t v_j, and the point is at fraction s of the way from O to E.
///
/// E' on the arc v_i' v_j' cuts the spherical triangle (O', v_i', E') of area A = t·π/3 (a third
/// of a face's π). That triangle has the side β = |O' v_i'| (cos β = 1/3), the angle γ = π/3 at
/// v_i' (half the spherical face's 120°) and the unknown angle α at O'. Its third angle is
/// δ = A + π − α − γ, and the polar law of cosines cos δ = −cos α cos γ + sin α sin γ cos β
/// gives, with ψ = A − γ,
///     tan α = (cos ψ − cos γ) / −(sin ψ + sin γ cos β),
/// taken in [0, 2π/3] by atan2 (α = 0 at t = 0, 2π/3 at t = 1). The point is then on the great
/// circle leaving O' at azimuth α, at 1 − cos z = s² (1 − cos |O'E'|).
Vec3 equal_area(int w, int x, int y) noexcept
{
    const FacePoint f = face_point(w, x, y);
    // the corner with the smallest weight names the sub-triangle; ties go to the first in the
    // fixed order below, and both choices give the same point (t = 0 on one side, 1 on the other)
    const std::array<int, 3> ks{0, 1, 2};
    const int k = *std::min_element(ks.begin(), ks.end(),
                                    [&f](int p, int q) { return f.weight[p] < f.weight[q]; });
    const int i = (k + 1) % 3;
    const int j = (k + 2) % 3;
    const Vec3 vi = normalized(k_corner[f.corner[i]]);
    const Vec3 vj = normalized(k_corner[f.corner[j]]);
    // the face's centre direction is minus its opposite corner (the indices sum to 0+1+2+3)
    const Vec3 centre = -normalized(k_corner[6 - f.corner[0] - f.corner[1] - f.corner[2]]);
    const int span = w - 3 * f.weight[k];  // s = span / W
    if (span == 0)
        return centre;
    const double s = static_cast<double>(span) / w;
    const double t = static_cast<double>(f.weight[j] - f.weight[k]) / span;

    constexpr double gamma = std::numbers::pi / 3.0;
    constexpr double cos_beta = 1.0 / 3.0;
    const double psi = t * (std::numbers::pi / 3.0) - gamma;
    const double alpha =
        std::atan2(std::cos(psi) - std::cos(gamma), -(std::sin(psi) + std::sin(gamma) * cos_beta));

    const Vec3 d0 = normalized(vi - centre * dot(vi, centre));
    Vec3 d1 = cross(centre, d0);
    if (dot(d1, vj) < 0.0)
        d1 = -d1;
    const Vec3 dir = d0 * std::cos(alpha) + d1 * std::sin(alpha);
    Vec3 e = normalized(cross(cross(centre, dir), cross(vi, vj)));
    if (dot(e, centre) < 0.0)
        e = -e;
    const double q = s * s * (1.0 - dot(e, centre));  // 1 − cos z
    return centre * (1.0 - q) + dir * std::sqrt(q * (2.0 - q));
}

}  // namespace

std::string_view to_string(SphereMap map) noexcept
{
    return map == SphereMap::Gnomonic ? "gnomonic" : "equal-area";
}

std::optional<SphereMap> sphere_map_from_string(std::string_view name) noexcept
{
    if (name == "equal-area")
        return SphereMap::EqualArea;
    if (name == "gnomonic")
        return SphereMap::Gnomonic;
    return std::nullopt;
}

Vec3 sphere_point(const TetraGrid& grid, int x, int y, SphereMap map) noexcept
{
    return map == SphereMap::Gnomonic ? gnomonic(grid.w(), x, y, 1.0) : equal_area(grid.w(), x, y);
}

Vec3Field<double> sphere_domain(const TetraGrid& grid, SphereMap map, double radius, int ghost)
{
    Vec3Field<double> out{Field<double>(grid, ghost), Field<double>(grid, ghost),
                          Field<double>(grid, ghost)};
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            if (!grid.is_canonical(grid.index(x, y)))
                continue;
            const Vec3 p = map == SphereMap::Gnomonic ? gnomonic(grid.w(), x, y, radius)
                                                      : equal_area(grid.w(), x, y) * radius;
            out[0].at(x, y) = p.x;
            out[1].at(x, y) = p.y;
            out[2].at(x, y) = p.z;
        }
    for (auto& f : out)
    {
        sync_twins(grid, f);
        fill_ghosts(grid, f);
    }
    return out;
}

}  // namespace pliant::core
