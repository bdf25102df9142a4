// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Untangling the sampled surface (docs/remesh.md §3.2): where the spherical parameterisation is
/// very anisotropic at the scale of a grid cell, three nodes whose sphere points form a positive
/// triangle can land on the input surface as a triangle facing the other way (a fold), and the
/// folded triangles cross their neighbours. The sphere map is fold-free; the fold comes from
/// sampling a strongly non-linear map at a few points.
///
/// The repair moves the sample points of the nodes around each folded or intersecting output
/// triangle: each moved node takes the place on the input surface nearest (in the tangent plane of
/// its input face) to the mean of its grid neighbours' surface points, reached by moving its
/// sphere point through the inverse of the face's linear map and sampling again. This is Laplacian
/// (Tutte) smoothing of the output restricted to the input surface; on a flat region with a fixed
/// convex boundary it provably untangles (Tutte 1963). Each round smooths the nodes within a few
/// grid rings of the bad triangles (Gauss-Seidel, in node order) and checks again; the ring grows
/// with the rounds. Every node stays a barycentric sample of the input surface at a point of its
/// sphere map (the same interpolation as sample_surface), twins stay equal (the work is done on
/// the grid's unique vertices), and the result does not depend on the thread count.
///
/// A star that is still folded after that (no single position raises its worst face above 0)
/// then descends a barrier energy of all its faces (Garanzha et al. 2021): the sum lets one face
/// give a little so that a folded one can turn over, where the worst face alone has no slope.
///
/// Alternatives rejected: re-optimising the sphere map for the grid (global and slow; the folds
/// are local); projecting smoothed points onto the nearest input face (may jump to the other side
/// of a thin part).

#include <pliant/core/field.h>
#include <pliant/core/progress.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant::remesh
{

struct UntangleSettings
{
    bool enabled = true;  ///< false: only measure (the *_sampled and final counts agree)
    int max_rounds = 6;   ///< rounds of smoothing and checking
    int sweeps = 3;       ///< Gauss-Seidel sweeps per round
    int rings = 2;        ///< grid rings around the bad triangles smoothed in the first round
    int patience = 4;     ///< stop after this many rounds without a lower count
    /// A node moves at most this far from its grid neighbours' mean, relative to the farthest
    /// neighbour.
    double reach = 0.8;
    /// Smoothing never takes a star (a node's faces) below this quality: signed area against
    /// the input's normal over the sum of squared edges, at most sqrt(3)/12 ~ 0.144 (an
    /// equilateral triangle on the input), so 0.02 is about a seventh of that.
    double min_quality = 0.02;
    /// Width of the barrier on the faces' quality that a star still folded after the compass
    /// search descends (its folded faces counted first, then the sum of a smoothed 1/quality);
    /// 0: no descent.
    double barrier_epsilon = 0.02;
    /// Compass steps of that descent per node and sweep.
    int barrier_steps = 12;
    /// Folds left after the rounds: passes in which the region of folded faces plus
    /// `patch_rings` grid rings descends the barrier energy together, `patch_sweeps` sweeps per
    /// epsilon, epsilon halved from `patch_epsilon_start` down to `patch_epsilon_end`; a pass is
    /// kept only if it lowers the count (folded plus crossing pairs) without adding crossings.
    /// 0: no patch passes. The epsilons must be finite with 0 < end <= start
    /// (untangle_samples returns InvalidArgument otherwise; an end of 0 never came).
    int patch_passes = 4;
    int patch_rings = 4;
    int patch_sweeps = 3;
    double patch_epsilon_start = 0.02;
    double patch_epsilon_end = 0.0005;
};

struct UntangleStats
{
    std::size_t folded_sampled = 0;  ///< folded output triangles as sampled
    /// Intersecting pairs as sampled: pairs sharing no edge (one sharing a vertex counts,
    /// docs/remesh.md §3.2).
    std::size_t intersections_sampled = 0;
    std::size_t folded = 0;         ///< after untangling
    std::size_t intersections = 0;  ///< after untangling
    std::size_t moved_nodes = 0;    ///< unique vertices whose sample point moved
    int rounds = 0;                 ///< rounds of smoothing run
    int patch_passes = 0;           ///< patch passes kept (see UntangleSettings)
};

/// Input face under each unique vertex's sample point `points` (one unit vector per grid node,
/// twins equal): vertex i of grid_surface is node `grid.node_of_unique()[i]`.
/// \pre `sphere` is a fold-free spherical map of `mesh`.
[[nodiscard]] std::vector<std::uint32_t> locate_samples(const core::TetraGrid& grid,
                                                        const core::Vec3Field<double>& points,
                                                        const mesh::TriMesh& mesh,
                                                        std::span<const core::Vec3> sphere);

/// Counts the folded and intersecting triangles of the sampled surface `positions` (sampled at
/// `points`, e.g. the domain map) and, if `settings.enabled`, untangles them by moving the sample
/// points of nearby nodes: `points` and `positions` are updated in place (canonical nodes and
/// their twins). Nodes far from any bad triangle are left untouched, bit for bit.
/// `progress` (optional) gets phase "untangle" with fractions below 1 as the sweeps go (the
/// caller reports the phase's end); if it asks to stop, the work ends within 64 nodes of a
/// sweep, at its set-up's stages or within a crossing count (intersecting_pairs) and returns
/// ErrorCode::Cancelled with `points` and `positions` untouched.
/// \pre `sphere` is a fold-free spherical map of `mesh` (outward faces); `positions` samples
/// `mesh` at `points` (any sampler).
core::Result<UntangleStats> untangle_samples(const core::TetraGrid& grid, const mesh::TriMesh& mesh,
                                             std::span<const core::Vec3> sphere,
                                             core::Vec3Field<double>& points,
                                             core::Vec3Field<double>& positions,
                                             const UntangleSettings& settings = {},
                                             core::ProgressSink* progress = nullptr);

}  // namespace pliant::remesh
