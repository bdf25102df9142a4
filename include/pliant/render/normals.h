// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Area-weighted vertex normals on the CPU: each face adds its cross product (twice its area
/// times its unit normal) to its three vertices, then the sums are normalised. Used for meshes
/// (the vertex-buffer path), for rest normals when a grid file carries a displacement, and by
/// the tests as the reference for the normals the grid vertex shader computes.

#include <pliant/core/field.h>
#include <pliant/core/vec3.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant::render
{

/// Unit normals of the grid surface at every node (twins equal to their canonical node), over
/// the real faces `grid.triangles()`. A vertex whose faces have zero total area gets (0, 0, 0).
/// \pre positions made for `grid`.
[[nodiscard]] core::Vec3Field<double> grid_normals(const core::TetraGrid& grid,
                                                   const core::Vec3Field<double>& positions);

/// Unit normals per vertex of an indexed triangle mesh. \pre every index < positions.size().
[[nodiscard]] std::vector<core::Vec3> mesh_normals(
    std::span<const core::Vec3> positions, std::span<const std::array<std::uint32_t, 3>> faces);

/// The same into `out`, which it overwrites (no allocation: for a mesh that moves every frame).
/// \pre every index < positions.size(); out.size() == positions.size().
void mesh_normals(std::span<const core::Vec3> positions,
                  std::span<const std::array<std::uint32_t, 3>> faces, std::span<core::Vec3> out);

}  // namespace pliant::render
