// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Modified butterfly refinement level n -> n+1 as three convolutions of the ghost-padded
/// coarse grid (docs/design.md §3), and its exact inverse on the coarse nodes, `restrict`.
///
/// Contract of `refine(plan, in, out)` (docs/subdivision.md):
/// - `in` is a level-n field with a ghost ring of at least `k_refine_ghost` (1) whose ghosts the
///   CALLER has filled (`core::fill_ghosts(plan.coarse_grid(), in)`) after the last change to
///   `in`; twins of `in` must be equal (as every field from a `.pgrid` file or from `refine` is).
///   `refine` never writes to `in`, so one prepared coarse field can be refined many times and by
///   several threads.
/// - `out` is a level-(n+1) field of any ghost width (0..4), allocated by the caller. `refine`
///   writes every in-range node: even nodes (2x, 2y) are copies of in(x, y) bit for bit, odd nodes
///   get the mask of their edge direction; if `out` has a ghost ring, it fills it. So `out` is
///   ready to be refined again. Twins of `out` are equal bit for bit: the sums are grouped so
///   that the gluing maps only permute commutative pairs, and the input's twins are equal
///   (tests/subdiv/refine_test.cpp checks every twin of the outputs of levels 2..10, refined from
///   levels 1..9; no copy pass is made).
/// - No allocation, no logging, no exceptions. `threads` > 1 splits the rows between OpenMP
///   threads (at most one per 65,536 fine nodes: smaller grids run on one thread); every node is
///   computed by the same code whatever the thread count, so results are bit-identical for any
///   `threads`.
///
/// The corners need no special rule: seen through the ghost map every node has six neighbours
/// (the corners' three edges appear twice each, docs/design.md §1), so the regular mask applies
/// everywhere. docs/subdivision.md explains what that means at the corners and how it differs
/// from OpenMesh's ModifiedButterflyT there.

#include <pliant/core/field.h>
#include <pliant/subdiv/convolution_plan.h>

#include <span>

namespace pliant::subdiv
{

/// Refines one scalar field by one level (T = float or double).
/// \pre in.level() == plan.coarse_level(), in.ghost() >= k_refine_ghost with ghosts filled;
/// out.level() == plan.fine_level(); threads >= 1. Violations are PLIANT_ASSERT failures.
template <typename T>
void refine(const ConvolutionPlan& plan, const core::Field<T>& in, core::Field<T>& out,
            int threads = 1) noexcept;

/// The OpenMP threads `refine` with `plan` uses when asked for `threads`: at most one per
/// 65,536 fine nodes (a level-7 output runs on one, level 8 on up to 2, level 9 on up to 8),
/// at least one.
[[nodiscard]] int refine_threads(const ConvolutionPlan& plan, int threads) noexcept;

/// Refines three planes (positions, normals) with the same contract per plane.
template <typename T>
void refine(const ConvolutionPlan& plan, const core::Vec3Field<T>& in, core::Vec3Field<T>& out,
            int threads = 1) noexcept;

/// Takes the even nodes: coarse(x, y) = fine(2x, 2y), bit for bit, then fills coarse's ghosts
/// if it has any. The exact inverse of `refine` on the coarse nodes.
/// \pre fine.level() == plan.fine_level(), coarse.level() == plan.coarse_level().
template <typename T>
void restrict(const ConvolutionPlan& plan, const core::Field<T>& fine,
              core::Field<T>& coarse) noexcept;

/// Allocating convenience: a new level-n field (ghost width `ghost`) from a level-(n+1) one.
template <typename T>
[[nodiscard]] core::Field<T> restrict(const ConvolutionPlan& plan, const core::Field<T>& fine,
                                      int ghost = 0);

/// Refines `plans.size()` levels in a row (plans from `make_plans`, consecutive levels). Unlike
/// `refine`, this fills `in`'s ghosts itself: `in` is any level-n field with equal twins (any
/// ghost width, ghosts need not be valid; twins are not synced here, so unequal twins in give
/// unequal twins out: `core::sync_twins` first). Allocates the intermediate and result fields; the
/// result has ghost width `out_ghost` (ghosts filled).
template <typename T>
[[nodiscard]] core::Field<T> refine_levels(std::span<const ConvolutionPlan> plans,
                                           const core::Field<T>& in, int out_ghost = 0,
                                           int threads = 1);

/// `refine_levels` for three planes.
template <typename T>
[[nodiscard]] core::Vec3Field<T> refine_levels(std::span<const ConvolutionPlan> plans,
                                               const core::Vec3Field<T>& in, int out_ghost = 0,
                                               int threads = 1);

/// One-shot convenience: builds the plans for `levels` steps from `in.level()` and refines.
/// \return ErrorCode::InvalidArgument if levels < 1 or in.level() + levels > 10.
template <typename T>
[[nodiscard]] core::Result<core::Field<T>> refine_levels(const core::Field<T>& in, int levels,
                                                         int out_ghost = 0);

/// One-shot convenience for three planes (e.g. positions from `core::geometry_of`).
template <typename T>
[[nodiscard]] core::Result<core::Vec3Field<T>> refine_levels(const core::Vec3Field<T>& in,
                                                             int levels, int out_ghost = 0);

}  // namespace pliant::subdiv
