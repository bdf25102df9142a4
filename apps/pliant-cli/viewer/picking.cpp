// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "picking.h"

#include <cmath>
#include <utility>

namespace pliant::viewer
{

std::optional<render::Mat4> invert(const render::Mat4& m) noexcept
{
    // Row-major working copy [A | I] with A(r, c) = m[c * 4 + r].
    double a[4][8] = {};
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
        {
            a[r][c] = m.m[static_cast<std::size_t>(c * 4 + r)];
            a[r][c + 4] = r == c ? 1.0 : 0.0;
        }
    for (int col = 0; col < 4; ++col)
    {
        int pivot = col;
        for (int r = col + 1; r < 4; ++r)
            if (std::abs(a[r][col]) > std::abs(a[pivot][col]))
                pivot = r;
        if (std::abs(a[pivot][col]) < 1e-300)
            return std::nullopt;
        if (pivot != col)
            for (int c = 0; c < 8; ++c)
                std::swap(a[pivot][c], a[col][c]);
        const double inv = 1.0 / a[col][col];
        for (int c = 0; c < 8; ++c)
            a[col][c] *= inv;
        for (int r = 0; r < 4; ++r)
        {
            if (r == col || a[r][col] == 0.0)
                continue;
            const double f = a[r][col];
            for (int c = 0; c < 8; ++c)
                a[r][c] -= f * a[col][c];
        }
    }
    render::Mat4 out;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            out.m[static_cast<std::size_t>(c * 4 + r)] = a[r][c + 4];
    return out;
}

namespace
{

core::Vec3 unproject(const render::Mat4& inv, double x, double y, double z) noexcept
{
    const auto& m = inv.m;
    const double X = m[0] * x + m[4] * y + m[8] * z + m[12];
    const double Y = m[1] * x + m[5] * y + m[9] * z + m[13];
    const double Z = m[2] * x + m[6] * y + m[10] * z + m[14];
    const double W = m[3] * x + m[7] * y + m[11] * z + m[15];
    return core::Vec3{X, Y, Z} / W;
}

}  // namespace

Ray pixel_ray(const render::CameraMatrices& camera, double px, double py, int width,
              int height) noexcept
{
    // Pixel -> normalised device coordinates (y up), then unproject a point on the far plane;
    // the ray starts at the eye, which a perspective camera always passes through.
    const double ndc_x = 2.0 * px / width - 1.0;
    const double ndc_y = 1.0 - 2.0 * py / height;
    const std::optional<render::Mat4> inv = invert(camera.view_projection);
    if (!inv)
        return Ray{camera.eye, core::normalized(camera.target - camera.eye)};
    const core::Vec3 far_point = unproject(*inv, ndc_x, ndc_y, 1.0);
    return Ray{camera.eye, core::normalized(far_point - camera.eye)};
}

std::optional<Hit> intersect(const Ray& ray, const core::Vec3& a, const core::Vec3& b,
                             const core::Vec3& c) noexcept
{
    const core::Vec3 e1 = b - a;
    const core::Vec3 e2 = c - a;
    const core::Vec3 p = core::cross(ray.direction, e2);
    const double det = core::dot(e1, p);
    // Relative threshold: parallel within ~1e-12 of the edge lengths' scale.
    const double scale = core::dot(e1, e1) + core::dot(e2, e2);
    if (std::abs(det) <= 1e-14 * scale)
        return std::nullopt;
    const double inv_det = 1.0 / det;
    const core::Vec3 s = ray.origin - a;
    const double b1 = core::dot(s, p) * inv_det;
    if (b1 < 0.0 || b1 > 1.0)
        return std::nullopt;
    const core::Vec3 q = core::cross(s, e1);
    const double b2 = core::dot(ray.direction, q) * inv_det;
    if (b2 < 0.0 || b1 + b2 > 1.0)
        return std::nullopt;
    const double t = core::dot(e2, q) * inv_det;
    if (!(t > 0.0))
        return std::nullopt;
    return Hit{0, t, b1, b2, ray.origin + ray.direction * t};
}

std::optional<Hit> pick(const Ray& ray, std::span<const core::Vec3> positions,
                        std::span<const std::array<std::uint32_t, 3>> faces) noexcept
{
    std::optional<Hit> best;
    for (std::size_t f = 0; f < faces.size(); ++f)
    {
        const auto& tri = faces[f];
        std::optional<Hit> hit =
            intersect(ray, positions[tri[0]], positions[tri[1]], positions[tri[2]]);
        if (hit && (!best || hit->t < best->t))
        {
            hit->face = static_cast<std::uint32_t>(f);
            best = hit;
        }
    }
    return best;
}

}  // namespace pliant::viewer
