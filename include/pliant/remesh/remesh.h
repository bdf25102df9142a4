// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The remesher's entry point: a closed genus-0 mesh onto the TetraGrid (docs/design.md §2,
/// docs/remesh.md). Phases: sphere map (mesh -> sphere, fold-free), domain map (grid ->
/// sphere), sampling (grid node -> input surface), and optionally the quality measurement.

#include <pliant/core/field.h>
#include <pliant/core/progress.h>
#include <pliant/core/result.h>
#include <pliant/core/sphere_domain.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/mesh/tri_mesh.h>
#include <pliant/remesh/quality.h>
#include <pliant/remesh/sphere_map.h>
#include <pliant/remesh/untangle.h>

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::remesh
{

/// A replacement for the sampling phase, called by remesh() with exactly the inputs of
/// sample_surface (the grid, the domain map's sphere points, the outward-facing input mesh and its
/// fold-free sphere map) and held to its contract: every node's 3D position, twins equal, ghost
/// width 0; an error aborts remesh() and is returned as is. The GPU samplers
/// (render::sample_on_gpu, or render::locate_on_gpu feeding sample_surface's start faces;
/// `pliant remesh --gpu`) plug in here; remesh itself stays free of any GPU dependency.
using Sampler = std::function<core::Result<core::Vec3Field<double>>(
    const core::TetraGrid& grid, const core::Vec3Field<double>& domain, const mesh::TriMesh& mesh,
    std::span<const core::Vec3> sphere)>;

struct RemeshSettings
{
    int level = 7;  ///< grid level 1..10 (W = 2^level)
    SphereMapSettings sphere;
    /// The sphere map, the sampling and the untangling work on the input split 1-to-4 until it
    /// has at least this many faces (split_for_map: the same surface, so every sample is still a
    /// point of the input); 0 = never. Coarse inputs (fox, 622 faces) otherwise get a
    /// piecewise-linear map too stiff to keep its kinks below what folds the sampled grid
    /// (docs/remesh.md §1.3). The report's input counts are the input's own.
    std::size_t min_map_faces = 2000;
    /// Where the grid's nodes lie on the sphere (core::sphere_domain). Equal-area samples the
    /// surface more evenly (docs/remesh.md §2: on spot at level 7, area cv 0.32 instead of 0.75,
    /// PSNR +1.5 dB). On the GPU (`pliant remesh --gpu`), the gnomonic map gets the paper's
    /// colour look-up (render::sample_on_gpu) and any other map GPU point location with exact
    /// CPU interpolation (render::locate_on_gpu, docs/remesh.md §3.1).
    core::SphereMap domain_map = core::SphereMap::EqualArea;
    /// Untangle folded or intersecting output triangles after sampling (untangle_samples,
    /// docs/remesh.md §3.2); `enabled = false` still counts them for the report.
    UntangleSettings untangle;
    /// Count the input's own self-intersections for the report, so that the remesher's can be
    /// told apart from the input's (`input_self_intersections`).
    bool check_input = true;
    bool measure = true;  ///< compute the distance part of the report (takes about as long as
                          ///< the remeshing itself)
    DistanceSettings distance;
    /// Empty: the CPU sampler (sample_surface). Otherwise called in its place.
    Sampler sampler;
    /// The report's `sampler` entry when `sampler` is set (e.g. "gpu").
    std::string sampler_name = "custom";
};

struct PhaseTime
{
    std::string name;
    double seconds = 0.0;
};

/// Everything REMESH-NOTES.md §1 asks for, plus counts.
struct QualityReport
{
    int level = 0;
    std::size_t input_vertices = 0;
    std::size_t input_faces = 0;
    std::size_t output_vertices = 0;  ///< 2W^2 + 2
    std::size_t output_faces = 0;     ///< 4W^2
    bool input_flipped = false;       ///< the input faced inward and was reoriented
    std::string sphere_method;        ///< "spring-embedder" or "coarse-to-fine"
    std::size_t gnomonic_folds = 0;
    std::size_t spring_folds = 0;
    std::size_t inverted_mesh = 0;    ///< spherical triangles of the input map (always 0)
    std::size_t inverted_domain = 0;  ///< spherical triangles of the domain map (always 0)
    std::string domain_map;           ///< "equal-area" or "gnomonic"
    double rms_stretch = 0.0;
    double stretch_efficiency = 0.0;
    /// Pairs of input faces sharing no edge that meet anywhere but at a shared vertex
    /// (intersecting_pairs; pairs sharing one vertex count too); 0 when not checked
    /// (RemeshSettings::check_input).
    std::size_t input_intersections = 0;
    bool input_checked = false;
    /// Output triangles facing against the input surface at their samples (is_folded) and
    /// intersecting pairs of output triangles by the same rule as `input_intersections`: as
    /// sampled, and in the result (after untangling).
    UntangleStats untangle;
    bool measured = false;  ///< whether `distance` was computed
    SurfaceDistance distance;
    AreaSpread areas;
    /// Nodes whose walk fell back to the exhaustive scan: the CPU sampler only (0 whenever
    /// RemeshSettings::sampler is set, even one that walks on the CPU, as `pliant remesh --gpu`
    /// does on the equal-area map).
    std::size_t brute_force_locations = 0;
    std::string sampler = "cpu";  ///< "cpu", or RemeshSettings::sampler_name
    std::vector<PhaseTime> phases;
    double total_seconds = 0.0;
};

struct RemeshResult
{
    core::TetraGrid grid;
    core::Vec3Field<double> positions;  ///< the sampled surface, twins equal, ghost width 0
    QualityReport report;
};

/// Remeshes `mesh` onto a grid of `settings.level`.
/// \pre `mesh` passed mesh::validate (the CLI validates first). Inward-facing meshes are
/// accepted and reoriented.
/// \return InvalidArgument for a level outside 1..10; InvertedTriangles (with the count) when a
/// fold-free sphere map cannot be built (never a folded result); NotConverged when the
/// simplification does not reach a tetrahedron; Cancelled when `progress` asked to stop
/// (core::ProgressSink::stop_requested; polled at every progress report and between phases,
/// so a stop is honoured within a fraction of a second at any level).
core::Result<RemeshResult> remesh(const mesh::TriMesh& mesh, const RemeshSettings& settings = {},
                                  core::ProgressSink* progress = nullptr);

/// The report as a JSON object (keys documented in docs/remesh.md).
[[nodiscard]] std::string to_json(const QualityReport& report);
/// The report as readable lines.
[[nodiscard]] std::string to_text(const QualityReport& report);

}  // namespace pliant::remesh
