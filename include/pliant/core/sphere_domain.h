// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The grid's domain tetrahedron on the unit sphere (docs/design.md §2, step 3): where each grid
/// node sits on the sphere before the remesher samples a surface there, and the rest shape of the
/// built-in sphere.
///
/// Two maps, chosen by `SphereMap`:
/// - `Gnomonic`: the central projection of the flat tetrahedron (the reference paper's map). It is
///   a perspective projection, so the GPU sampler can render the parameterised mesh from the
///   centre through each face and read the nodes at pixel centres. Its cells are uneven: area
///   scale 9 at a face centre against 1/3 at a corner, and 3:1 anisotropy at the corners, so the
///   smallest cells are about 5× shorter (radially) than the mean.
/// - `EqualArea` (default): an exactly area-preserving map, face by face, built like Snyder's
///   equal-area polyhedral projection (Snyder 1992). Each face is split into the three triangles
///   (centre, v_i, v_j); a planar point is written as the ray from the centre through it, hitting
///   the edge v_i v_j at fraction t, and the fraction s along that ray. Its sphere point lies on
///   the great circle from the face centre O' through the edge point E' that cuts the spherical
///   triangle (O', v_i', v_j') at area fraction t, at the geodesic distance z where the wedge's
///   area fraction equals the plane's: 1 − cos z = s² (1 − cos |O'E'|). E' has a closed form
///   (see sphere_domain.cpp). The map is continuous across edges (the regular tetrahedron's
///   mirror symmetry about each edge) and preserves area, so grid cells converge to the mean
///   area (median deviation 0.11 % at level 8), except the cells that straddle a crease of the
///   map (the lines from each face centre to its corners, where the construction changes
///   sub-triangle) and the corner cells, which stay at 0.4–1.6 of the mean at every level. Near
///   a corner the unavoidable shear remains (a 60° face angle opened to 120°: √2 along the
///   circle, 1/√2 along the radius). This is docs/design.md's "relaxed toward equal areas", reached
///   exactly rather than by iteration. docs/remesh.md §2 has the numbers.
///
/// Both return canonical nodes computed once, twins equal to them bit for bit, and `ghost` rings
/// filled through the ghost map.

#include <pliant/core/field.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>

#include <optional>
#include <string_view>

namespace pliant::core
{

enum class SphereMap
{
    EqualArea,
    Gnomonic,
};

/// "equal-area" or "gnomonic".
[[nodiscard]] std::string_view to_string(SphereMap map) noexcept;
/// The inverse of to_string; nullopt for anything else.
[[nodiscard]] std::optional<SphereMap> sphere_map_from_string(std::string_view name) noexcept;

/// The unit-sphere point of grid node (x, y) of a rectangle node (0 <= x <= 2W, 0 <= y <= W). The
/// domain's corners a = (0,0), b = (W,0), c = (W,W), d = (0,W) go to (1,1,1)/√3, (1,−1,−1)/√3,
/// (−1,1,−1)/√3, (−1,−1,1)/√3.
[[nodiscard]] Vec3 sphere_point(const TetraGrid& grid, int x, int y, SphereMap map) noexcept;

/// Every node's point on the sphere of `radius` about the origin, as three planes with `ghost`
/// rings (twins synced, ghosts filled).
[[nodiscard]] Vec3Field<double> sphere_domain(const TetraGrid& grid, SphereMap map,
                                              double radius = 1.0, int ghost = 0);

}  // namespace pliant::core
