// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Measured remeshing quality (REMESH-NOTES.md §1): two-sided sampled surface distance
/// (RMS, Hausdorff, PSNR relative to the input's bounding-box diagonal) and the spread of
/// triangle areas.
///
/// Distances: each surface is sampled at all its vertices plus area-weighted random points
/// (fixed seed, so results are repeatable); each sample's exact distance to the other surface
/// is found through a bounding-volume hierarchy over its triangles (exact point-triangle
/// distance, Ericson 2005 §5.1.5): axis-aligned boxes, or oriented ones for a surface made
/// mostly of slivers at a slant to the axes (a finely divided cone or cylinder), whose
/// axis-aligned boxes are loose; the same distances either way. RMS pools the squared distances of
/// both directions; the Hausdorff distance is the larger of the two directed maxima over the
/// samples.

#include <pliant/core/progress.h>
#include <pliant/mesh/tri_mesh.h>

#include <cstddef>
#include <cstdint>

namespace pliant::remesh
{

struct DistanceSettings
{
    /// Random surface points per direction (plus every vertex). 0 = automatic:
    /// clamp(3 * faces of the sampled surface, 50'000, 300'000).
    std::size_t samples = 0;
    std::uint64_t seed = 0x5eed;
};

/// Sampled distance from one surface to another.
struct DirectedDistance
{
    double rms = 0.0;  ///< file units
    double mean = 0.0;
    double max = 0.0;
    std::size_t samples = 0;
};

struct SurfaceDistance
{
    double diagonal = 0.0;      ///< bounding-box diagonal of the reference (input) surface
    double rms = 0.0;           ///< two-sided RMS, file units
    double hausdorff = 0.0;     ///< two-sided max, file units
    double rms_relative = 0.0;  ///< rms / diagonal
    double hausdorff_relative = 0.0;
    double psnr_db = 0.0;  ///< 20 log10(diagonal / rms); +inf-free: capped at 300 dB
    DirectedDistance reference_to_other;
    DirectedDistance other_to_reference;
};

/// Two-sided distance between `reference` (the input) and `other` (the remeshed surface).
/// `progress` (optional) gets phase "measure" once per block of 32,768 samples, with fractions
/// below 1 (the caller reports the end); if it asks to stop, the measure ends at the next block
/// or within a BVH build (polled at nodes of more than 2^16 faces; then only `diagonal` is
/// set) and its figures are partial (the caller discards them: remesh returns Cancelled).
/// \pre both non-empty with finite positions.
[[nodiscard]] SurfaceDistance surface_distance(const mesh::TriMesh& reference,
                                               const mesh::TriMesh& other,
                                               const DistanceSettings& settings = {},
                                               core::ProgressSink* progress = nullptr);

/// Exact distance from `p` to the closest point of triangle (a, b, c) (tests use it as the
/// obviously-correct reference for the BVH).
[[nodiscard]] double point_triangle_distance(const core::Vec3& p, const core::Vec3& a,
                                             const core::Vec3& b, const core::Vec3& c) noexcept;

/// Spread of triangle areas.
struct AreaSpread
{
    double min_over_max = 0.0;  ///< smallest area / largest area
    double cv = 0.0;            ///< coefficient of variation (standard deviation / mean)
};
[[nodiscard]] AreaSpread area_spread(const mesh::TriMesh& mesh) noexcept;

}  // namespace pliant::remesh
