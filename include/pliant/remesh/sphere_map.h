// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Mesh -> unit sphere: a bijective spherical parameterization of a closed genus-0 mesh
/// (docs/design.md §2.2, docs/remesh.md).
///
/// Two routes, both ending in the same fold check:
/// - the reference paper's spring embedder: central (gnomonic) projection from the area
///   centroid, then relaxation toward neighbour means with the radial force taken in its stiff
///   limit (projection back onto the sphere). Enough for star-shaped meshes only.
/// - coarse to fine (Praun & Hoppe 2003): half-edge collapses down to a tetrahedron, the
///   tetrahedron on the sphere, then the vertices re-inserted in reverse order, each inside the
///   spherical kernel of its one-ring, with vertex moves that never leave the kernel. The moves
///   minimise the L2 stretch plus an inverse-stretch (symmetric Dirichlet) term and a peak
///   term, each face measured on two chord triangles split at its longest arc, with coarse
///   faces standing for the surface area their vertices absorbed, and on the final mesh a kink
///   term on the change of the Jacobian across each edge, which is what folds the sampled grid
///   (docs/remesh.md §1.2).
///   Fold-free by construction (every move is checked).
/// A result is returned only when every spherical triangle is positively oriented.
///
/// Rejected alternatives: a Tutte embedding of the mesh cut into two discs (fold-free but with
/// large distortion to remove afterwards by the same kernel-bounded moves); spherical conformal
/// maps with a Möbius correction (no fold-free guarantee in floating point).

#include <pliant/core/progress.h>
#include <pliant/core/result.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>

#include <cstddef>
#include <span>
#include <vector>

namespace pliant::remesh
{

enum class SphereMethod
{
    Auto,            ///< spring embedder when it ends fold-free, else coarse to fine
    SpringEmbedder,  ///< the paper's method only; fails with InvertedTriangles if folds remain
    CoarseToFine,    ///< always the progressive-mesh route
};

struct SphereMapSettings
{
    SphereMethod method = SphereMethod::Auto;
    /// Spring embedder: relaxation sweeps (each followed by a fold count every 10 sweeps).
    int spring_iterations = 100;
    /// Spring embedder: step toward the neighbour mean, in (0, 1].
    double relaxation = 0.5;
    /// Coarse to fine: optimisation sweeps over all present vertices each time their number
    /// has grown by `level_growth`.
    int sweeps_per_level = 2;
    double level_growth = 1.3;
    /// Stretch-optimisation sweeps on the full mesh at the end of the coarse-to-fine route
    /// (stops early when the energy improves by less than `tolerance`, relative). 60 rather
    /// than the 5 used before the kink term: with it the sweeps keep improving far longer
    /// (docs/remesh.md §1.2, §5).
    int final_sweeps = 60;
    /// Spring-embedder route: stretch-optimisation sweeps after a fold-free embedding (no
    /// hierarchy there, so local moves need many sweeps; stops early at `tolerance` / 100).
    int spring_optimise_sweeps = 200;
    /// Weight of the inverse stretch (oversampling) in the optimised energy, next to the L2
    /// stretch (undersampling); 0 = pure L2 stretch (Praun & Hoppe).
    double inverse_weight = 1.0;
    /// The same weight while the coarse-to-fine map grows; annealed (halved per round of
    /// sweeps) down to `inverse_weight` at the end.
    double coarse_inverse_weight = 3.0;
    /// Coarse to fine: give each coarse face the surface area its vertices stand for (the
    /// fine detail removed by the collapses), so thin parts get their share of the sphere
    /// before their vertices come back.
    bool represented_area = true;
    /// Weight of the peak term (per-face stretch^6): penalises small regions of extreme
    /// undersampling that the area-weighted L2 stretch barely sees. Needs `split_stretch`
    /// (without it the optimiser pays for the peaks with spherical slivers).
    double peak_weight = 0.3;
    /// Measure each face's stretch on two chord triangles split at its longest arc (Praun &
    /// Hoppe's remedy for spherical slivers, which a single chord triangle does not see).
    bool split_stretch = true;
    /// Weight of the kink term on the final mesh (coarse to fine, from the annealing sweeps on):
    /// per input edge, the surface area of its two faces times mu^2, the squared shear of
    /// J_A^-1 J_B along the edge normalised by its determinant (J_A, J_B: the Jacobians of the
    /// map from the sphere to the surface on either side, unfolded about the edge). A sampled
    /// grid triangle across the edge folds once mu exceeds about 3.5, at every grid level
    /// (the piecewise-linear map is conical at the edge); 0 = off. docs/remesh.md §1.2.
    double kink_weight = 10.0;
    double tolerance = 1e-3;
};

/// A spherical parameterization: one unit vector per input vertex.
struct SphereMap
{
    std::vector<core::Vec3> points;
    SphereMethod method_used = SphereMethod::Auto;
    std::size_t gnomonic_folds = 0;    ///< inverted faces after central projection
    std::size_t spring_folds = 0;      ///< inverted faces after the spring embedder (if run)
    std::size_t forced_collapses = 0;  ///< simplification steps that ignored the normal test
    /// Sander's L2 stretch, normalised by the area ratio (1: a uniform scaling; any shear,
    /// equal-area or not, gives more), and its efficiency 1 / rms_stretch^2 (<= 1).
    double rms_stretch = 0.0;
    double stretch_efficiency = 0.0;
};

/// Maps `mesh` onto the unit sphere without folds.
/// \pre `mesh` passed mesh::validate (closed, manifold, genus 0, consistently oriented).
/// \return InvalidArgument if the faces are oriented inward (negative signed volume);
/// InvertedTriangles (with the count) if the chosen method cannot remove every fold;
/// NotConverged if the simplification does not reach a tetrahedron.
core::Result<SphereMap> map_to_sphere(const mesh::TriMesh& mesh,
                                      const SphereMapSettings& settings = {},
                                      core::ProgressSink* progress = nullptr);

/// The same surface with every face split 1-to-4 at its edge midpoints, repeated until it has at
/// least `min_faces` faces (a copy when it already has). Original vertices keep their indices;
/// each midpoint is computed once per edge, so the result is closed and manifold when `mesh` is.
/// A coarse input gives its piecewise-linear sphere map too few vertices to turn its Jacobian
/// gradually from face to face; the split surface is identical, so its samples are samples of
/// the input (docs/remesh.md §1.3).
[[nodiscard]] mesh::TriMesh split_for_map(const mesh::TriMesh& mesh, std::size_t min_faces);

/// Number of faces whose spherical triangle is not positively oriented (det[a,b,c] <= 0).
[[nodiscard]] std::size_t count_inverted(std::span<const mesh::Face> faces,
                                         std::span<const core::Vec3> sphere) noexcept;

/// L2 stretch of a spherical map measured on the chord triangles (Sander et al. 2001; Praun &
/// Hoppe 2003): `rms_stretch`^2 = (sum A s^2 / sum A) (sum A' / sum A) over the surface areas A
/// and chord areas A', so that a uniform scaling gives 1 and any shear more, and `efficiency` =
/// 1 / rms_stretch^2 (the unnormalised form: surface area / domain area / rms^2;
/// docs/remesh.md §4).
struct StretchStats
{
    double rms_stretch = 0.0;
    double efficiency = 0.0;
};
[[nodiscard]] StretchStats measure_stretch(const mesh::TriMesh& mesh,
                                           std::span<const core::Vec3> sphere) noexcept;

/// Signed volume enclosed by the faces (positive when they face outward).
[[nodiscard]] double signed_volume(const mesh::TriMesh& mesh) noexcept;

}  // namespace pliant::remesh
