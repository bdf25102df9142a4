// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `ConvolutionPlan`: everything one refinement step level n -> n+1 needs, computed once
/// (docs/style.md §6, "define once, compile, evaluate"): the coarse and fine grids (for their ghost
/// and twin tables) and, for every ghost width a coarse field may have, the flat offsets of the
/// eight butterfly taps of each edge direction. (`refine` itself takes the taps from the
/// constexpr masks, so that its fused row loop reads shared taps once; the offsets serve
/// per-node code and the tests, and are the same taps.)

#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/subdiv/butterfly_mask.h>

#include <array>
#include <cstddef>
#include <span>
#include <vector>

namespace pliant::subdiv
{

/// Tap offsets of one direction, in elements of a padded coarse plane, from the edge's start.
using TapOffsets = std::array<std::ptrdiff_t, k_tap_count>;

class ConvolutionPlan
{
public:
    /// Plan for refining level `coarse_level` to `coarse_level + 1`.
    /// \return ErrorCode::InvalidArgument unless 1 <= coarse_level <= 9 (the finest grid is
    /// level 10, core::k_max_level).
    static core::Result<ConvolutionPlan> create(int coarse_level);

    [[nodiscard]] int coarse_level() const noexcept { return coarse_.level(); }
    [[nodiscard]] int fine_level() const noexcept { return fine_.level(); }
    [[nodiscard]] const core::TetraGrid& coarse_grid() const noexcept { return coarse_; }
    [[nodiscard]] const core::TetraGrid& fine_grid() const noexcept { return fine_; }

    /// Offsets of the taps of direction `d` in a coarse field of ghost width `ghost`
    /// (k_refine_ghost .. core::k_max_ghost), tap order as in butterfly_mask.h.
    [[nodiscard]] const TapOffsets& offsets(EdgeDirection d, int ghost) const noexcept
    {
        PLIANT_ASSERT(ghost >= k_refine_ghost && ghost <= core::k_max_ghost,
                      "ConvolutionPlan::offsets: ghost width too small for the butterfly mask");
        return offsets_[static_cast<std::size_t>(ghost)][static_cast<std::size_t>(d)];
    }

private:
    ConvolutionPlan(core::TetraGrid coarse, core::TetraGrid fine);

    core::TetraGrid coarse_;
    core::TetraGrid fine_;
    std::array<std::array<TapOffsets, k_direction_count>, core::k_max_ghost + 1> offsets_{};
};

/// Plans for `levels` consecutive steps starting at `coarse_level` (for refine_levels).
/// \return ErrorCode::InvalidArgument if levels < 1 or coarse_level + levels > 10.
core::Result<std::vector<ConvolutionPlan>> make_plans(int coarse_level, int levels);

}  // namespace pliant::subdiv
