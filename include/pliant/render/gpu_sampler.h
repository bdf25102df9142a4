// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The reference paper's GPU re-meshing look-up (§3.1.3), made exact: the spherically
/// parameterised input mesh is rendered with its original 3D positions as colours into a float
/// framebuffer, and every grid node reads its surface point from the pixel that lies on its ray.
///
/// Why this equals the CPU sampler (remesh::sample_surface): the CPU interpolates the input's
/// positions with the barycentric coordinates of the node's sphere point p centrally projected
/// onto the chord triangle (vertices = the triangle's sphere points) that p's ray crosses. A
/// perspective camera at the origin renders exactly that: draw the chord mesh with colour =
/// original position, and GL's perspective-correct interpolation gives at each pixel the
/// barycentric interpolation at the point where the pixel's ray hits the chord triangle. A
/// fold-free spherical map's chord polyhedron is star-shaped from the origin, so each ray hits
/// exactly one triangle (no depth test needed; `GpuSampleStats::overlaps` checks it).
///
/// Views: remesh::domain_sphere puts every node on a face of a regular tetrahedron (the four
/// grid corners) and normalises. One view per tetrahedron face, with an off-axis projection
/// whose window coordinates are an affine function of the face's barycentric coordinates,
/// chosen so that face node (i, j) (lattice units along two edges) lands exactly on the centre
/// of pixel (k·i, k·j), k = `pixels_per_cell`. The clip coordinates are computed on the CPU in
/// double and uploaded as floats, so a GPU sample differs from the CPU one only by float32
/// rounding and the rasteriser's sub-pixel snapping of vertices (docs/remesh.md, "GPU
/// sampling"). A node whose sphere point is not at a lattice point of some face (a domain map
/// other than the gnomonic tetrahedron) is refused, never approximated.
///
/// Any other domain map (the equal-area one, remesh's default) puts nodes between pixel
/// centres, where a colour would be the neighbouring ray's. For those, locate_on_gpu does the
/// GPU's share only: the same views with the triangle id in alpha give, for every node, the
/// triangle that covers the pixel its ray passes through, and the CPU sampler starts its walk
/// there and interpolates exactly (remesh::sample_surface with start faces): the same result
/// as the CPU alone, with the point location done by the rasteriser.

#include <pliant/core/field.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant::render
{

struct GpuSamplerSettings
{
    /// Pixels per grid cell along a face edge (k above): each view is k·W + 1 pixels square.
    /// Larger k shrinks the effect of the rasteriser's sub-pixel vertex snapping (1/256 pixel
    /// on llvmpipe and most GPUs) relative to the node spacing. 0 = automatic:
    /// clamp(1024 / W, 1, 64), views of about 1025 pixels (levels 4-10), where the snapping
    /// error on spot has fallen to float32's (docs/remesh.md, "GPU sampling").
    int pixels_per_cell = 0;
    /// Render each view twice (first fragment wins / last fragment wins) and count the nodes
    /// whose covering triangle differs: a check that every node's ray hits one triangle only.
    bool check_overlaps = true;
};

struct GpuSampleStats
{
    int views = 0;                ///< rendered views (4: one per tetrahedron face)
    int viewport = 0;             ///< side of each view in pixels
    int pixels_per_cell = 0;      ///< k actually used
    std::size_t samples = 0;      ///< canonical nodes read back
    std::size_t overlaps = 0;     ///< nodes covered by two triangles (0 for a fold-free map;
                                  ///< sample_on_gpu only)
    double seconds_render = 0.0;  ///< drawing and read-back, wall clock
};

/// Samples the input surface at every grid node on the GPU: the same result as
/// remesh::sample_surface up to float32 rounding (docs/remesh.md gives the measured tolerance).
/// \param grid the grid to fill.
/// \param domain_sphere every node's unit-sphere point, from remesh::domain_sphere(grid).
/// \param sphere_vertices the input's fold-free spherical map, one unit vector per vertex.
/// \param original_positions the input's 3D positions (model units), one per vertex.
/// \param faces the input's triangles, counter-clockwise from outside.
/// \pre an OpenGL 3.3 core context is current on this thread and its functions are loaded
/// (OffscreenContext::create, or load_gl with a window toolkit's context).
/// \return the positions at every node (twins equal, ghost width 0), in model units.
/// InvalidArgument when sizes disagree, there are more than 2^24 faces, or a node's sphere
/// point is not a lattice point of the domain tetrahedron; GraphicsError when no GL functions
/// are loaded, the framebuffer or shaders are refused, or a node's pixel was not covered by
/// any triangle (a hole is reported, never left as zero).
core::Result<core::Vec3Field<double>> sample_on_gpu(
    const core::TetraGrid& grid, const core::Vec3Field<double>& domain_sphere,
    std::span<const core::Vec3> sphere_vertices, std::span<const core::Vec3> original_positions,
    std::span<const std::array<std::uint32_t, 3>> faces, const GpuSamplerSettings& settings = {},
    GpuSampleStats* stats = nullptr);

/// GPU point location for any fold-free domain map: for every grid node, the input triangle
/// that covers the pixel its sphere point's ray passes through, in the view of the domain
/// tetrahedron's face whose cone holds the point most centrally. The pixel's centre ray is
/// within half a pixel (1/(2k) of a grid cell, before the sphere's curvature) of the node's, so
/// the triangle is the node's own or one near it; remesh::sample_surface, given these as start
/// faces, walks the rest and interpolates in double, so the result does not depend on the GPU's
/// precision. Same inputs and preconditions as sample_on_gpu, without the positions.
/// \return per node index (grid.node_count() entries, twins as their canonical node) a face
/// index; InvalidArgument for bad sizes or a non-finite sphere point, GraphicsError as
/// sample_on_gpu (a node whose pixel no triangle covered is reported).
core::Result<std::vector<std::uint32_t>> locate_on_gpu(
    const core::TetraGrid& grid, const core::Vec3Field<double>& domain_sphere,
    std::span<const core::Vec3> sphere_vertices,
    std::span<const std::array<std::uint32_t, 3>> faces, const GpuSamplerSettings& settings = {},
    GpuSampleStats* stats = nullptr);

}  // namespace pliant::render
