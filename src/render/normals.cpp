// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/render/normals.h>

#include <algorithm>

namespace pliant::render
{

std::vector<core::Vec3> mesh_normals(std::span<const core::Vec3> positions,
                                     std::span<const std::array<std::uint32_t, 3>> faces)
{
    std::vector<core::Vec3> normals(positions.size());
    mesh_normals(positions, faces, normals);
    return normals;
}

void mesh_normals(std::span<const core::Vec3> positions,
                  std::span<const std::array<std::uint32_t, 3>> faces, std::span<core::Vec3> sum)
{
    PLIANT_ASSERT(sum.size() == positions.size(), "mesh_normals: one normal per vertex");
    std::fill(sum.begin(), sum.end(), core::Vec3{});
    for (const auto& f : faces)
    {
        // Per face, in a per-frame loop, over faces the library built: checked in debug builds.
        PLIANT_DEBUG_ASSERT(
            f[0] < positions.size() && f[1] < positions.size() && f[2] < positions.size(),
            "mesh_normals: face index out of range");
        const core::Vec3& a = positions[f[0]];
        const core::Vec3 n = core::cross(positions[f[1]] - a, positions[f[2]] - a);
        for (const std::uint32_t v : f)
            sum[v] += n;
    }
    for (core::Vec3& n : sum)
        n = core::normalized(n);
}

core::Vec3Field<double> grid_normals(const core::TetraGrid& grid,
                                     const core::Vec3Field<double>& positions)
{
    PLIANT_ASSERT(positions[0].level() == grid.level(), "grid_normals: field of another level");
    const auto nodes = grid.node_of_unique();
    std::vector<core::Vec3> points(nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i)
        points[i] = {positions[0][nodes[i]], positions[1][nodes[i]], positions[2][nodes[i]]};
    const std::vector<core::Vec3> unique_normals = mesh_normals(points, grid.triangles());

    core::Vec3Field<double> normals{core::Field<double>(grid), core::Field<double>(grid),
                                    core::Field<double>(grid)};
    for (std::uint32_t i = 0; i < grid.node_count(); ++i)
    {
        const core::NodeIndex n{i};
        const core::Vec3& v = unique_normals[grid.unique_id(n)];
        normals[0][n] = v.x;
        normals[1][n] = v.y;
        normals[2][n] = v.z;
    }
    return normals;
}

}  // namespace pliant::render
