// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// A minimal 3-vector for geometry at the boundaries (mesh import, reports). Hot loops work on
/// `Field` planes instead; heavier linear algebra uses Eigen inside the modules that need it.

#include <cmath>

namespace pliant::core
{

struct Vec3
{
    double x = 0.0;
    double y = 0.0;
    double z = 0.0;

    constexpr Vec3& operator+=(const Vec3& o) noexcept
    {
        x += o.x;
        y += o.y;
        z += o.z;
        return *this;
    }
    constexpr Vec3& operator-=(const Vec3& o) noexcept
    {
        x -= o.x;
        y -= o.y;
        z -= o.z;
        return *this;
    }
    constexpr Vec3& operator*=(double s) noexcept
    {
        x *= s;
        y *= s;
        z *= s;
        return *this;
    }
    friend constexpr bool operator==(const Vec3&, const Vec3&) = default;
};

constexpr Vec3 operator+(Vec3 a, const Vec3& b) noexcept
{
    return a += b;
}
constexpr Vec3 operator-(Vec3 a, const Vec3& b) noexcept
{
    return a -= b;
}
constexpr Vec3 operator-(const Vec3& a) noexcept
{
    return {-a.x, -a.y, -a.z};
}
constexpr Vec3 operator*(Vec3 a, double s) noexcept
{
    return a *= s;
}
constexpr Vec3 operator*(double s, Vec3 a) noexcept
{
    return a *= s;
}
constexpr Vec3 operator/(Vec3 a, double s) noexcept
{
    return a *= (1.0 / s);
}
constexpr double dot(const Vec3& a, const Vec3& b) noexcept
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr Vec3 cross(const Vec3& a, const Vec3& b) noexcept
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(const Vec3& a) noexcept
{
    return std::sqrt(dot(a, a));
}
inline Vec3 normalized(const Vec3& a) noexcept
{
    const double n = norm(a);
    return n > 0.0 ? a / n : a;
}
inline bool is_finite(const Vec3& a) noexcept
{
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

}  // namespace pliant::core
