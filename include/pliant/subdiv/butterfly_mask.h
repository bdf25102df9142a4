// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The modified butterfly mask (Zorin, Schröder & Sweldens 1996, "Interpolating subdivision for
/// meshes with arbitrary topology", regular case: both edge ends of valence 6) as `constexpr`
/// taps on the TetraGrid, one mask per edge direction (docs/design.md §3, docs/subdivision.md).
///
/// The new (odd) vertex on the edge a0-a1 is
///
///     1/2 (a0 + a1) + 1/8 (b0 + b1) - 1/16 (c0 + c1 + c2 + c3)
///
/// with b0, b1 the apexes of the two triangles on the edge and c0..c3 the apexes of the four
/// triangles across their outer edges. On the grid (cells split by the (1,1) diagonal) the six
/// neighbours of a node are (±1,0), (0,±1), ±(1,1); the lattice rotation by 60 degrees is the
/// integer map (x, y) -> (x - y, x), so the vertical and diagonal masks are the horizontal mask
/// rotated, which is how they are built below (and checked by static_assert).

#include <array>
#include <cstddef>

namespace pliant::subdiv
{

/// The three edge directions of the grid. The odd node of a coarse edge starting at (x, y) is
/// the fine node (2x+1, 2y) for Horizontal, (2x, 2y+1) for Vertical, (2x+1, 2y+1) for Diagonal.
enum class EdgeDirection : int
{
    Horizontal = 0,  ///< edge (x, y)-(x+1, y)
    Vertical = 1,    ///< edge (x, y)-(x, y+1)
    Diagonal = 2,    ///< edge (x, y)-(x+1, y+1)
};

inline constexpr std::size_t k_direction_count = 3;
/// Taps of the regular butterfly: a0 a1 | b0 b1 | c0 c1 c2 c3.
inline constexpr std::size_t k_tap_count = 8;

/// One tap: grid offset from the edge's start node (x, y).
struct Tap
{
    int dx = 0;
    int dy = 0;
    friend constexpr bool operator==(Tap, Tap) = default;
};

using Mask = std::array<Tap, k_tap_count>;

/// Weights of the tap classes, in sixteenths: a (taps 0-1) 8/16, b (taps 2-3) 2/16,
/// c (taps 4-7) -1/16. They sum to 1 and reproduce cubic polynomials on a regular lattice.
inline constexpr int k_weight_a_16ths = 8;
inline constexpr int k_weight_b_16ths = 2;
inline constexpr int k_weight_c_16ths = -1;

/// Weight of tap `i` as a fraction (exact in binary floating point).
[[nodiscard]] constexpr double tap_weight(std::size_t i) noexcept
{
    const int w16 = i < 2 ? k_weight_a_16ths : (i < 4 ? k_weight_b_16ths : k_weight_c_16ths);
    return static_cast<double>(w16) / 16.0;
}

/// The mask for the horizontal edge (x, y)-(x+1, y): b0 is the apex of the triangle
/// (x,y),(x+1,y),(x+1,y+1) above the edge and b1 of (x,y-1),(x+1,y),(x,y) below it.
inline constexpr Mask k_horizontal_mask{{
    {0, 0},    // a0: the edge's start
    {1, 0},    // a1: its end
    {1, 1},    // b0: apex above
    {0, -1},   // b1: apex below
    {0, 1},    // c0: across a0-b0 (the diagonal edge)
    {2, 1},    // c1: across a1-b0
    {1, -1},   // c2: across a1-b1 (the diagonal edge)
    {-1, -1},  // c3: across a0-b1
}};

/// The lattice rotation by 60 degrees: (1,0) -> (1,1) -> (0,1) -> (-1,0) -> ...
[[nodiscard]] constexpr Tap rotate60(Tap t) noexcept
{
    return Tap{t.dx - t.dy, t.dx};
}

[[nodiscard]] constexpr Mask rotate60(const Mask& m) noexcept
{
    Mask r{};
    for (std::size_t i = 0; i < k_tap_count; ++i)
        r[i] = rotate60(m[i]);
    return r;
}

/// Diagonal edge (x, y)-(x+1, y+1): the horizontal mask rotated once.
inline constexpr Mask k_diagonal_mask = rotate60(k_horizontal_mask);
/// Vertical edge (x, y)-(x, y+1): the horizontal mask rotated twice.
inline constexpr Mask k_vertical_mask = rotate60(k_diagonal_mask);

static_assert(k_diagonal_mask[1] == Tap{1, 1} && k_vertical_mask[1] == Tap{0, 1},
              "rotated masks must follow their edge");

/// The mask of one direction.
[[nodiscard]] constexpr const Mask& mask(EdgeDirection d) noexcept
{
    switch (d)
    {
    case EdgeDirection::Horizontal: return k_horizontal_mask;
    case EdgeDirection::Vertical: return k_vertical_mask;
    case EdgeDirection::Diagonal: break;
    }
    return k_diagonal_mask;
}

/// Ghost ring the masks need on the coarse field: every tap lies within one node of the
/// rectangle for every edge that starts inside it.
inline constexpr int k_refine_ghost = 1;

}  // namespace pliant::subdiv
