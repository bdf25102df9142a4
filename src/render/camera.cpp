// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/render/camera.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pliant::render
{
namespace
{

constexpr double k_deg = std::numbers::pi / 180.0;

Mat4 multiply(const Mat4& a, const Mat4& b) noexcept
{
    Mat4 r;
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row)
        {
            double s = 0.0;
            for (int k = 0; k < 4; ++k)
                s += a.m[static_cast<std::size_t>(k * 4 + row)] *
                     b.m[static_cast<std::size_t>(c * 4 + k)];
            r.m[static_cast<std::size_t>(c * 4 + row)] = s;
        }
    return r;
}

Mat4 look_at(const core::Vec3& eye, const core::Vec3& target, const core::Vec3& up) noexcept
{
    const core::Vec3 f = core::normalized(target - eye);
    const core::Vec3 s = core::normalized(core::cross(f, up));
    const core::Vec3 u = core::cross(s, f);
    Mat4 r;
    r.m = {s.x,
           u.x,
           -f.x,
           0.0,
           s.y,
           u.y,
           -f.y,
           0.0,
           s.z,
           u.z,
           -f.z,
           0.0,
           -core::dot(s, eye),
           -core::dot(u, eye),
           core::dot(f, eye),
           1.0};
    return r;
}

Mat4 perspective(double fov_y, double aspect, double near, double far) noexcept
{
    const double f = 1.0 / std::tan(0.5 * fov_y);
    Mat4 r;
    r.m[0] = f / aspect;
    r.m[5] = f;
    r.m[10] = (far + near) / (near - far);
    r.m[11] = -1.0;
    r.m[14] = 2.0 * far * near / (near - far);
    return r;
}

}  // namespace

std::array<float, 16> Mat4::to_float() const noexcept
{
    std::array<float, 16> r{};
    for (std::size_t i = 0; i < 16; ++i)
        r[i] = static_cast<float>(m[i]);
    return r;
}

Bounds bounds_of(std::span<const core::Vec3> points) noexcept
{
    Bounds b{points.front(), points.front()};
    for (const core::Vec3& p : points)
    {
        b.lo = {std::min(b.lo.x, p.x), std::min(b.lo.y, p.y), std::min(b.lo.z, p.z)};
        b.hi = {std::max(b.hi.x, p.x), std::max(b.hi.y, p.y), std::max(b.hi.z, p.z)};
    }
    const core::Vec3 c = b.centre();
    double r2 = 0.0;
    for (const core::Vec3& p : points)
        r2 = std::max(r2, core::dot(p - c, p - c));
    b.point_radius = std::sqrt(r2);
    return b;
}

double fit_distance(double radius, double fov_y_deg, int width, int height) noexcept
{
    const double half_y = 0.5 * fov_y_deg * k_deg;
    const double aspect = static_cast<double>(width) / static_cast<double>(height);
    const double half_x = std::atan(std::tan(half_y) * aspect);
    const double half = std::min(half_y, half_x);
    return 1.15 * radius / std::sin(half);
}

CameraMatrices make_camera(const CameraSettings& settings, const Bounds& surface_bounds, int width,
                           int height) noexcept
{
    const Bounds& bounds = settings.fit_to ? *settings.fit_to : surface_bounds;
    CameraMatrices cam;
    const double radius = std::max(bounds.radius(), 1e-9);
    cam.target = bounds.centre();
    cam.distance = settings.distance > 0.0
                       ? settings.distance
                       : fit_distance(radius, settings.fov_y_deg, width, height);
    const double az = settings.azimuth_deg * k_deg;
    const double el = std::clamp(settings.elevation_deg, -89.9, 89.9) * k_deg;
    const core::Vec3 dir{std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az)};
    cam.eye = cam.target + dir * cam.distance;
    cam.view = look_at(cam.eye, cam.target, {0.0, 1.0, 0.0});
    // The box's sphere spans [distance - radius, distance + radius] along the view direction;
    // a near plane at 1 % of the distance keeps depth precision when the eye is inside it.
    const double near = std::max(cam.distance - 1.5 * radius, 0.01 * cam.distance);
    const double far = cam.distance + 1.5 * radius;
    cam.projection =
        perspective(settings.fov_y_deg * k_deg,
                    static_cast<double>(width) / static_cast<double>(height), near, far);
    cam.view_projection = multiply(cam.projection, cam.view);
    return cam;
}

core::Vec3 project_to_pixel(const CameraMatrices& camera, const core::Vec3& p, int width,
                            int height) noexcept
{
    const auto& m = camera.view_projection.m;
    const double cx = m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12];
    const double cy = m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13];
    const double cz = m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14];
    const double cw = m[3] * p.x + m[7] * p.y + m[11] * p.z + m[15];
    if (cw <= 0.0)
        return {0.0, 0.0, -1.0};
    const double nx = cx / cw;
    const double ny = cy / cw;
    const double nz = cz / cw;
    return {(nx * 0.5 + 0.5) * width, (1.0 - (ny * 0.5 + 0.5)) * height, nz * 0.5 + 0.5};
}

}  // namespace pliant::render
