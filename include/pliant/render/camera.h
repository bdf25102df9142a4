// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The orbit camera: look-at + perspective around the centre of a bounding box, with the
/// distance fitted so the box's bounding sphere fills the view. Matrices are column-major
/// (OpenGL's layout). World +y is up (the convention of OBJ files such as data/spot.obj).

#include <pliant/core/vec3.h>

#include <array>
#include <optional>
#include <span>

namespace pliant::render
{

/// Axis-aligned bounding box, model units.
struct Bounds
{
    core::Vec3 lo{};
    core::Vec3 hi{};
    /// Largest distance of the points from `centre()`; 0 when unknown (a box given by hand).
    double point_radius = 0.0;

    [[nodiscard]] core::Vec3 centre() const noexcept { return (lo + hi) * 0.5; }
    /// Radius around `centre()` that holds the object: `point_radius` when known (tight for
    /// round objects), else half the box diagonal.
    [[nodiscard]] double radius() const noexcept
    {
        return point_radius > 0.0 ? point_radius : 0.5 * core::norm(hi - lo);
    }
};

/// Bounds of a point set, with `point_radius`. \pre `points` is not empty.
[[nodiscard]] Bounds bounds_of(std::span<const core::Vec3> points) noexcept;

struct CameraSettings
{
    double azimuth_deg = 30.0;    ///< rotation about +y; 0 looks from +z towards -z
    double elevation_deg = 20.0;  ///< above the xz plane, clamped to (-89.9, 89.9)
    double distance = 0.0;        ///< eye to box centre, model units; 0 fits the box
    double fov_y_deg = 35.0;      ///< vertical field of view
    /// The box to aim at and fit; empty: the drawn surface's own box. Set it to keep the camera
    /// still over a sequence of frames whose boxes change.
    std::optional<Bounds> fit_to{};
};

/// 4x4 matrix, column-major: element (row r, column c) is m[c * 4 + r].
struct Mat4
{
    std::array<double, 16> m{};
    [[nodiscard]] std::array<float, 16> to_float() const noexcept;
};

struct CameraMatrices
{
    Mat4 view;
    Mat4 projection;
    Mat4 view_projection;
    core::Vec3 eye{};
    core::Vec3 target{};
    double distance = 0.0;  ///< the distance used (fitted or given)
};

/// The distance at which a sphere of `radius` just fits a view of `fov_y_deg` and aspect
/// `width / height` (the smaller of the two angles decides), with a 15 % margin.
[[nodiscard]] double fit_distance(double radius, double fov_y_deg, int width, int height) noexcept;

/// Camera for an image of width x height pixels looking at `settings.fit_to`, else `bounds`.
/// \pre width, height > 0.
[[nodiscard]] CameraMatrices make_camera(const CameraSettings& settings, const Bounds& bounds,
                                         int width, int height) noexcept;

/// Where a point lands in a read-back image: x, y in pixels (x right, y down from the top row,
/// pixel centres at +0.5) and z the window depth in [0, 1]. Points behind the eye get z < 0.
[[nodiscard]] core::Vec3 project_to_pixel(const CameraMatrices& camera, const core::Vec3& p,
                                          int width, int height) noexcept;

}  // namespace pliant::render
