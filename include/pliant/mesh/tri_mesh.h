// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `TriMesh`: an indexed triangle mesh, the mesh module's one data type. Positions and faces are
/// separate arrays (structure of arrays); every face refers to three distinct vertex indices.

#include <pliant/core/vec3.h>

#include <array>
#include <cstdint>
#include <vector>

namespace pliant::mesh
{

using Face = std::array<std::uint32_t, 3>;

struct TriMesh
{
    std::vector<core::Vec3> positions;  ///< metres (or the file's units), one per vertex
    std::vector<Face> faces;            ///< counter-clockwise seen from outside

    [[nodiscard]] std::size_t vertex_count() const noexcept { return positions.size(); }
    [[nodiscard]] std::size_t face_count() const noexcept { return faces.size(); }
};

}  // namespace pliant::mesh
