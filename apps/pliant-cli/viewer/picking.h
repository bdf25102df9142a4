// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Picking for the viewer: a ray through a window pixel (from the camera the renderer draws
// with) and a CPU ray cast against triangles (SurfaceView::pick casts against the display
// surface with `intersect`). Brute force over every triangle with the Moller-Trumbore test: 262K
// triangles take a few milliseconds, and a cast happens only on a mouse press, so a BVH
// (rebuilt every frame as the surface moves) would cost more than it saves.

#include <pliant/core/vec3.h>
#include <pliant/render/camera.h>

#include <array>
#include <cstdint>
#include <optional>
#include <span>

namespace pliant::viewer
{

struct Ray
{
    core::Vec3 origin{};
    core::Vec3 direction{};  ///< unit length
};

/// Inverse of a 4x4 matrix (Gauss-Jordan with partial pivoting); nullopt when singular.
[[nodiscard]] std::optional<render::Mat4> invert(const render::Mat4& m) noexcept;

/// The ray from the eye through window pixel (px, py) (x right, y down from the top, in the same
/// units as width and height; pixel centres at +0.5), the inverse of render::project_to_pixel.
/// \pre width, height > 0 and the camera's view-projection is invertible.
[[nodiscard]] Ray pixel_ray(const render::CameraMatrices& camera, double px, double py, int width,
                            int height) noexcept;

struct Hit
{
    std::uint32_t face = 0;  ///< index into `faces`
    double t = 0.0;          ///< distance along the ray
    double b1 = 0.0;         ///< barycentric weight of the face's second vertex
    double b2 = 0.0;         ///< barycentric weight of the face's third vertex
    core::Vec3 point{};      ///< origin + t direction
};

/// Ray / triangle intersection (Moller-Trumbore, both sides): the distance t > 0 and the
/// barycentric weights of b and c, or nullopt for a miss or a ray parallel to the triangle.
[[nodiscard]] std::optional<Hit> intersect(const Ray& ray, const core::Vec3& a, const core::Vec3& b,
                                           const core::Vec3& c) noexcept;

/// The nearest hit of `ray` over all `faces` (indices into `positions`), or nullopt.
[[nodiscard]] std::optional<Hit> pick(const Ray& ray, std::span<const core::Vec3> positions,
                                      std::span<const std::array<std::uint32_t, 3>> faces) noexcept;

}  // namespace pliant::viewer
