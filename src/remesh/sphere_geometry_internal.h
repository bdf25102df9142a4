// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Small geometric kernels shared by the remesher's stages: spherical orientation, the chord
// (planar) stretch of a triangle, and vertex-face adjacency. Everything here is inline and
// allocation-free so the optimiser's inner loop can call it per face.

#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace pliant::remesh::detail
{

using core::Vec3;

/// det[a, b, c] for points on the unit sphere: positive when the spherical triangle abc is
/// counter-clockwise seen from outside. Written as a·((b−a)×(c−a)), which equals a·(b×c) but
/// keeps the relative precision of small triangles (the differences are nearly exact).
inline double orient(const Vec3& a, const Vec3& b, const Vec3& c) noexcept
{
    return core::dot(a, core::cross(b - a, c - a));
}

/// Squared L2 stretch (Sander et al. 2001) of the affine map from the planar chord triangle
/// (q0, q1, q2) to the surface triangle (p0, p1, p2), times the surface area: the triangle's term
/// of the area-weighted stretch energy. Returns +inf when the chord triangle is not positively
/// oriented on the sphere, which makes the energy a barrier against folds.
///
/// ||J||_F^2 = sum_i dot_i |p_j − p_k|^2 / (4 A^2) with dot_i = (q_j−q_i)·(q_k−q_i) and A the
/// chord triangle's area (the cotangent formula of the Dirichlet energy).
inline double stretch_term(const Vec3& q0, const Vec3& q1, const Vec3& q2, double l0sq, double l1sq,
                           double l2sq, double area3d) noexcept
{
    const Vec3 e1 = q1 - q0;
    const Vec3 e2 = q2 - q0;
    const Vec3 n = core::cross(e1, e2);
    if (core::dot(q0, n) <= 0.0)
        return std::numeric_limits<double>::infinity();
    const double a2x4 = core::dot(n, n);  // (2A)^2
    if (!(a2x4 > 0.0))
        return std::numeric_limits<double>::infinity();
    const Vec3 e12 = q2 - q1;
    const double d0 = core::dot(e1, e2);
    const double d1 = -core::dot(e1, e12);
    const double d2 = core::dot(e2, e12);
    // ||J||^2 = (d0 l0 + d1 l1 + d2 l2) / (4 A^2) = (...) / a2x4; energy = area3d ||J||^2 / 2
    return area3d * (d0 * l0sq + d1 * l1sq + d2 * l2sq) / (2.0 * a2x4);
}

/// Faces incident to each vertex, as one flat CSR table.
struct VertexFaces
{
    std::vector<std::uint32_t> offsets;  ///< size V+1
    std::vector<std::uint32_t> faces;

    [[nodiscard]] std::span<const std::uint32_t> of(std::uint32_t v) const noexcept
    {
        return {faces.data() + offsets[v], faces.data() + offsets[v + 1]};
    }
};

inline VertexFaces vertex_faces(std::size_t vertex_count, std::span<const mesh::Face> faces)
{
    VertexFaces vf;
    vf.offsets.assign(vertex_count + 1, 0);
    for (const auto& f : faces)
        for (const std::uint32_t v : f)
            ++vf.offsets[v + 1];
    for (std::size_t i = 0; i < vertex_count; ++i)
        vf.offsets[i + 1] += vf.offsets[i];
    vf.faces.resize(vf.offsets.back());
    std::vector<std::uint32_t> fill(vf.offsets.begin(), vf.offsets.end() - 1);
    for (std::size_t f = 0; f < faces.size(); ++f)
        for (const std::uint32_t v : faces[f])
            vf.faces[fill[v]++] = static_cast<std::uint32_t>(f);
    return vf;
}

}  // namespace pliant::remesh::detail
