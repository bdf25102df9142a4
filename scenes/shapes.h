// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Procedural test shapes shared by tests, benchmarks and the viewer (docs/style.md §10),
/// header-only.
///
/// Valid inputs (closed, 2-manifold, connected, genus 0, outward counter-clockwise faces):
/// `tetrahedron()`, `octahedron()`, `icosphere(n)`, `ellipsoid(a, b, c, n)`, `dumbbell()`.
/// Named invalid inputs, each failing exactly one rule of `mesh::validate` (docs/mesh.md):
/// `torus()` (χ = 0, WrongGenus), `open_cone()` (OpenBoundary), `two_spheres()` (NotConnected),
/// `non_manifold_vertex()` (NonManifoldVertex).
///
/// Every shape is built with a consistent face winding and then flipped as a whole if its signed
/// volume is negative, so orientation is right by construction rather than by hand-checked index
/// lists. Sizes are in metres (unit radius unless stated).

#include <pliant/mesh/tri_mesh.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace pliant::scenes
{

namespace detail
{

inline constexpr double k_pi = 3.14159265358979323846;

/// Signed volume enclosed by the faces (divergence theorem, about the origin); positive when the
/// faces of a closed surface are outward counter-clockwise.
inline double signed_volume(const mesh::TriMesh& m)
{
    double v = 0.0;
    for (const auto& f : m.faces)
    {
        const core::Vec3& a = m.positions[f[0]];
        const core::Vec3& b = m.positions[f[1]];
        const core::Vec3& c = m.positions[f[2]];
        v += core::dot(a, core::cross(b, c)) / 6.0;
    }
    return v;
}

/// Flips every face when the (consistently wound) surface encloses a negative volume.
inline void orient_outward(mesh::TriMesh& m)
{
    if (signed_volume(m) < 0.0)
    {
        for (auto& f : m.faces)
            std::swap(f[1], f[2]);
    }
}

/// Appends `b` to `a` (vertex indices of `b` shifted).
inline void append(mesh::TriMesh& a, const mesh::TriMesh& b)
{
    const auto offset = static_cast<std::uint32_t>(a.positions.size());
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    for (const auto& f : b.faces)
        a.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
}

inline void translate(mesh::TriMesh& m, const core::Vec3& t)
{
    for (auto& p : m.positions)
        p += t;
}

/// A closed surface of revolution about the x axis: a pole at each end and `rings` (x, r) pairs
/// in between (ordered from the +x pole to the -x pole), each ring with `segments` vertices.
inline mesh::TriMesh revolve_x(double x_first_pole, double x_last_pole,
                               const std::vector<std::pair<double, double>>& rings, int segments)
{
    mesh::TriMesh m;
    const auto s = static_cast<std::uint32_t>(segments);
    m.positions.push_back({x_first_pole, 0.0, 0.0});
    for (const auto& [x, r] : rings)
    {
        for (std::uint32_t j = 0; j < s; ++j)
        {
            const double phi = 2.0 * k_pi * static_cast<double>(j) / static_cast<double>(s);
            m.positions.push_back({x, r * std::cos(phi), r * std::sin(phi)});
        }
    }
    m.positions.push_back({x_last_pole, 0.0, 0.0});
    const auto n_rings = static_cast<std::uint32_t>(rings.size());
    const auto ring = [s](std::uint32_t i, std::uint32_t j) { return 1 + i * s + (j % s); };
    const auto last_pole = static_cast<std::uint32_t>(m.positions.size() - 1);
    for (std::uint32_t j = 0; j < s; ++j)
        m.faces.push_back({0, ring(0, j), ring(0, j + 1)});
    for (std::uint32_t i = 0; i + 1 < n_rings; ++i)
    {
        for (std::uint32_t j = 0; j < s; ++j)
        {
            m.faces.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
            m.faces.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        }
    }
    for (std::uint32_t j = 0; j < s; ++j)
        m.faces.push_back({last_pole, ring(n_rings - 1, j + 1), ring(n_rings - 1, j)});
    orient_outward(m);
    return m;
}

}  // namespace detail

/// Regular tetrahedron inscribed in the unit sphere: 4 vertices, 4 faces.
inline mesh::TriMesh tetrahedron()
{
    const double s = 1.0 / std::sqrt(3.0);
    mesh::TriMesh m;
    m.positions = {{s, s, s}, {s, -s, -s}, {-s, s, -s}, {-s, -s, s}};
    m.faces = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
    detail::orient_outward(m);
    return m;
}

/// Regular octahedron with vertices at ±x, ±y, ±z (unit radius): 6 vertices, 8 faces.
inline mesh::TriMesh octahedron()
{
    mesh::TriMesh m;
    m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
               {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    detail::orient_outward(m);
    return m;
}

/// Icosahedron subdivided `subdivisions` times (each triangle into four, new vertices pushed onto
/// the unit sphere): 10·4^n + 2 vertices, 20·4^n faces. \pre 0 <= subdivisions <= 7.
inline mesh::TriMesh icosphere(int subdivisions = 2)
{
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    mesh::TriMesh m;
    m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    m.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
               {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
               {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (auto& p : m.positions)
        p = core::normalized(p);
    for (int level = 0; level < subdivisions; ++level)
    {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;
        const auto mid = [&](std::uint32_t a, std::uint32_t b)
        {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            const auto it = midpoint.find(key);
            if (it != midpoint.end())
                return it->second;
            const auto index = static_cast<std::uint32_t>(m.positions.size());
            m.positions.push_back(core::normalized(m.positions[a] + m.positions[b]));
            midpoint.emplace(key, index);
            return index;
        };
        std::vector<mesh::Face> faces;
        faces.reserve(m.faces.size() * 4);
        for (const auto& f : m.faces)
        {
            const std::uint32_t ab = mid(f[0], f[1]);
            const std::uint32_t bc = mid(f[1], f[2]);
            const std::uint32_t ca = mid(f[2], f[0]);
            faces.push_back({f[0], ab, ca});
            faces.push_back({f[1], bc, ab});
            faces.push_back({f[2], ca, bc});
            faces.push_back({ab, bc, ca});
        }
        m.faces = std::move(faces);
    }
    detail::orient_outward(m);
    return m;
}

/// Axis-aligned ellipsoid with semi-axes a, b, c (metres) along x, y, z: `icosphere(n)` scaled.
/// \pre a, b, c > 0.
inline mesh::TriMesh ellipsoid(double a = 2.0, double b = 1.0, double c = 0.5, int subdivisions = 2)
{
    mesh::TriMesh m = icosphere(subdivisions);
    for (auto& p : m.positions)
        p = {p.x * a, p.y * b, p.z * c};
    return m;
}

/// A closed frustum of `sides` sides: rings of radius 1 at z = 0 and `top` at z = 1, the top one
/// turned by `twist` radians, and fan caps around (0, 0, 0) and (0, 0, 1). For many sides its
/// sides are long slivers at a slant to the axes, side by side, and its caps fans of slivers.
inline mesh::TriMesh frustum(std::uint32_t sides, double top = 0.5, double twist = 0.3)
{
    mesh::TriMesh m;
    m.positions = {core::Vec3{0, 0, 0}, core::Vec3{0, 0, 1}};
    for (std::uint32_t k = 0; k < sides; ++k)
    {
        const double a = 2.0 * 3.14159265358979323846 * k / sides;
        m.positions.push_back(core::Vec3{std::cos(a), std::sin(a), 0.0});
    }
    for (std::uint32_t k = 0; k < sides; ++k)
    {
        const double a = 2.0 * 3.14159265358979323846 * k / sides + twist;
        m.positions.push_back(core::Vec3{top * std::cos(a), top * std::sin(a), 1.0});
    }
    for (std::uint32_t k = 0; k < sides; ++k)
    {
        const std::uint32_t b0 = 2 + k, b1 = 2 + (k + 1) % sides;
        const std::uint32_t t0 = b0 + sides, t1 = b1 + sides;
        m.faces.push_back({0, b1, b0});
        m.faces.push_back({1, t0, t1});
        m.faces.push_back({b0, b1, t1});
        m.faces.push_back({b0, t1, t0});
    }
    return m;
}

/// Two unit balls (centres at x = ±1.5) joined by a cylindrical neck of radius 0.3 along the x
/// axis: closed genus 0, and not star-shaped about any point (rays leaving the neck re-enter a
/// ball). `segments` vertices per ring; 2 + segments·rings vertices.
inline mesh::TriMesh dumbbell(int segments = 24)
{
    constexpr double k_centre = 1.5;
    constexpr double k_neck = 0.3;
    const int ball_rings = segments / 2;
    const int neck_rings = segments / 3;
    // The ball meets the neck where sin(theta) = neck radius, on the inner side.
    const double theta_join = detail::k_pi - std::asin(k_neck);
    const double x_join = k_centre + std::cos(theta_join);  // > 0
    std::vector<std::pair<double, double>> rings;
    for (int k = 1; k <= ball_rings; ++k)
    {
        const double theta = theta_join * static_cast<double>(k) / static_cast<double>(ball_rings);
        rings.emplace_back(k_centre + std::cos(theta), std::sin(theta));
    }
    for (int k = 1; k < neck_rings; ++k)
    {
        const double x =
            x_join - 2.0 * x_join * static_cast<double>(k) / static_cast<double>(neck_rings);
        rings.emplace_back(x, k_neck);
    }
    for (int k = ball_rings; k >= 1; --k)
    {
        const double theta = theta_join * static_cast<double>(k) / static_cast<double>(ball_rings);
        rings.emplace_back(-(k_centre + std::cos(theta)), std::sin(theta));
    }
    return detail::revolve_x(k_centre + 1.0, -(k_centre + 1.0), rings, segments);
}

/// Invalid: a torus (major radius R, minor radius r, axis z), closed 2-manifold with χ = 0, so
/// `validate` reports WrongGenus (genus 1). u·v vertices, 2·u·v faces.
inline mesh::TriMesh torus(double major = 1.0, double minor = 0.35, int u = 24, int v = 12)
{
    mesh::TriMesh m;
    const auto nu = static_cast<std::uint32_t>(u);
    const auto nv = static_cast<std::uint32_t>(v);
    for (std::uint32_t i = 0; i < nu; ++i)
    {
        const double a = 2.0 * detail::k_pi * static_cast<double>(i) / static_cast<double>(nu);
        for (std::uint32_t j = 0; j < nv; ++j)
        {
            const double b = 2.0 * detail::k_pi * static_cast<double>(j) / static_cast<double>(nv);
            const double rr = major + minor * std::cos(b);
            m.positions.push_back({rr * std::cos(a), rr * std::sin(a), minor * std::sin(b)});
        }
    }
    const auto id = [nu, nv](std::uint32_t i, std::uint32_t j) { return (i % nu) * nv + (j % nv); };
    for (std::uint32_t i = 0; i < nu; ++i)
    {
        for (std::uint32_t j = 0; j < nv; ++j)
        {
            m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    }
    detail::orient_outward(m);
    return m;
}

/// Invalid: the side of a cone (apex at z = height, base circle of unit radius at z = 0) without
/// its base disc: one boundary loop of `segments` edges, so `validate` reports OpenBoundary.
inline mesh::TriMesh open_cone(int segments = 16, double height = 1.0)
{
    mesh::TriMesh m;
    const auto s = static_cast<std::uint32_t>(segments);
    m.positions.push_back({0.0, 0.0, height});
    for (std::uint32_t j = 0; j < s; ++j)
    {
        const double phi = 2.0 * detail::k_pi * static_cast<double>(j) / static_cast<double>(s);
        m.positions.push_back({std::cos(phi), std::sin(phi), 0.0});
    }
    for (std::uint32_t j = 0; j < s; ++j)
        m.faces.push_back({0, 1 + j, 1 + (j + 1) % s});
    // The missing base lies in the plane z = 0 through the origin, so the signed volume of the
    // side alone is the cone's volume and still tells outward from inward.
    detail::orient_outward(m);
    return m;
}

/// Invalid: two disjoint unit icospheres (centres x = ±1.5): each closed genus 0, together two
/// components, so `validate` reports NotConnected.
inline mesh::TriMesh two_spheres(int subdivisions = 1)
{
    mesh::TriMesh a = icosphere(subdivisions);
    mesh::TriMesh b = a;
    detail::translate(a, {-1.5, 0.0, 0.0});
    detail::translate(b, {1.5, 0.0, 0.0});
    detail::append(a, b);
    return a;
}

/// Invalid: two tetrahedra sharing one vertex (the origin), mirrored through it: every edge has
/// two faces and there is no boundary, but the shared vertex's faces form two fans (a pinch), so
/// `validate` reports NonManifoldVertex. 7 vertices, 8 faces, χ = 3.
inline mesh::TriMesh non_manifold_vertex()
{
    mesh::TriMesh a;
    a.positions = {{0, 0, 0}, {1, 0.2, 0.1}, {0.3, 1, 0.2}, {0.4, 0.3, 1}};
    a.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    detail::orient_outward(a);
    mesh::TriMesh b = a;
    for (auto& p : b.positions)
        p = -p;
    detail::orient_outward(b);  // point reflection reverses orientation
    // Concatenate, then let b's copy of the origin become a's vertex 0.
    mesh::TriMesh m = a;
    for (std::size_t i = 1; i < b.positions.size(); ++i)
        m.positions.push_back(b.positions[i]);
    for (const auto& f : b.faces)
    {
        mesh::Face g{};
        for (int k = 0; k < 3; ++k)
            g[static_cast<std::size_t>(k)] =
                f[static_cast<std::size_t>(k)] == 0 ? 0u : f[static_cast<std::size_t>(k)] + 3u;
        m.faces.push_back(g);
    }
    return m;
}

}  // namespace pliant::scenes
