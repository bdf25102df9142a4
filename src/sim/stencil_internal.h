// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The seven-point stiffness stencil, written once so that the integrator, `apply_stiffness` and
// `energy` evaluate K u with the same operations in the same order. Opposite edges are paired
// and each pair is added first: a point reflection of the grid (docs/design.md §1 gluing) swaps the
// two terms of every pair and keeps the pair order, and IEEE addition commutes, so a twin or ghost
// node gets bit for bit the value of its canonical node.

#include <cstddef>

namespace pliant::sim::detail
{

/// (K u)_c from the centre value c and the six neighbour values; w* are the edge weights of the
/// edges to +x, -x, +y, -y, +(1,1), -(1,1). T is double, or float for the increments of a
/// mixed-precision step (rkf45.h).
template <class T>
inline T stencil(T c, T xp, T xm, T yp, T ym, T dp, T dm, T wxp, T wxm, T wyp, T wym, T wdp,
                 T wdm) noexcept
{
    return ((wxp * (c - xp) + wxm * (c - xm)) + (wyp * (c - yp) + wym * (c - ym))) +
           (wdp * (c - dp) + wdm * (c - dm));
}

/// K u at padded offset i of planes sharing one stride s.
inline double stiffness_at(const double* u, const double* wx, const double* wy, const double* wd,
                           std::ptrdiff_t i, std::ptrdiff_t s) noexcept
{
    return stencil(u[i], u[i + 1], u[i - 1], u[i + s], u[i - s], u[i + s + 1], u[i - s - 1], wx[i],
                   wx[i - 1], wy[i], wy[i - s], wd[i], wd[i - s - 1]);
}

}  // namespace pliant::sim::detail
