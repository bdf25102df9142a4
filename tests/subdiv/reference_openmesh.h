// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// OpenMesh's ModifiedButterflyT (Debian libopenmesh-dev) on a grid's surface, as the
// independent implementation for tests/subdiv and bench/subdiv (never linked into the library).
// The TriMesh is built from grid.triangles() and per-unique-vertex positions, in double.

#include <pliant/core/field.h>
#include <pliant/core/tetra_grid.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/ModifiedButterFlyT.hh>

#include <array>
#include <cstdint>
#include <vector>

namespace pliant::test
{

struct OmTraits : public OpenMesh::DefaultTraits
{
    using Point = OpenMesh::Vec3d;
    using Normal = OpenMesh::Vec3d;
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<OmTraits>;

/// The grid surface as an OpenMesh TriMesh: vertex i is unique vertex i of the grid.
inline OmMesh to_openmesh(const core::TetraGrid& grid, const core::Vec3Field<double>& positions)
{
    OmMesh mesh;
    std::vector<OmMesh::VertexHandle> vh;
    vh.reserve(grid.unique_count());
    for (const core::NodeIndex n : grid.node_of_unique())
        vh.push_back(
            mesh.add_vertex(OmMesh::Point(positions[0][n], positions[1][n], positions[2][n])));
    for (const auto& t : grid.triangles())
        mesh.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
    return mesh;
}

/// One (or more) steps of OpenMesh's modified butterfly, in place.
inline bool openmesh_butterfly(OmMesh& mesh, std::size_t steps = 1)
{
    OpenMesh::Subdivider::Uniform::ModifiedButterflyT<OmMesh, double> sub;
    if (!sub.attach(mesh))
        return false;
    const bool ok = sub(steps);
    sub.detach();
    return ok;
}

}  // namespace pliant::test
