// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Cross-check against OpenMesh, an independent reader and halfedge structure: for each real
// manifold mesh, OpenMesh's own file reader and its topology must agree with import_mesh +
// analyze on vertices (those used by faces), faces, edges and boundary edges; and a halfedge
// mesh built from our TriMesh must accept every face (consistent orientation, manifold).

#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <gtest/gtest.h>

#include "support/fp_traps.h"
#include "support/test_paths.h"

#include <string>

namespace pliant::mesh
{
namespace
{

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

struct OmCounts
{
    std::size_t used_vertices = 0;
    std::size_t faces = 0;
    std::size_t edges = 0;
    std::size_t boundary_edges = 0;
};

OmCounts counts(const OmMesh& om)
{
    OmCounts c;
    for (const auto v : om.vertices())
        if (!om.is_isolated(v))
            ++c.used_vertices;
    c.faces = om.n_faces();
    c.edges = om.n_edges();
    for (const auto e : om.edges())
        if (om.is_boundary(e))
            ++c.boundary_edges;
    return c;
}

class OpenMeshCheck : public ::testing::TestWithParam<const char*>
{
};

TEST_P(OpenMeshCheck, ReaderAndTopologyAgreeWithAnalyze)
{
    const auto path = test::source_dir() / "tests" / "data" / "meshes" / GetParam();
    auto ours = import_mesh(path);
    ASSERT_TRUE(ours) << ours.error().message;
    const MeshStats s = analyze(*ours);

    OmMesh from_file;
    {
        test::FpTrapsOff traps;  // third-party reader
        ASSERT_TRUE(OpenMesh::IO::read_mesh(from_file, path.string()));
    }
    const OmCounts f = counts(from_file);
    EXPECT_EQ(f.used_vertices, s.vertices);
    EXPECT_EQ(f.faces, s.faces);
    EXPECT_EQ(f.edges, s.edges);
    EXPECT_EQ(f.boundary_edges, s.boundary_edges);

    // Our TriMesh into a halfedge mesh: every face must be accepted.
    OmMesh built;
    std::vector<OmMesh::VertexHandle> vh;
    for (const auto& p : ours->positions)
        vh.push_back(built.add_vertex(OmMesh::Point(
            static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z))));
    for (const auto& face : ours->faces)
        ASSERT_TRUE(built.add_face(vh[face[0]], vh[face[1]], vh[face[2]]).is_valid());
    const OmCounts b = counts(built);
    EXPECT_EQ(b.used_vertices, s.vertices);
    EXPECT_EQ(b.edges, s.edges);
    EXPECT_EQ(b.boundary_edges, s.boundary_edges);
    const long chi = static_cast<long>(b.used_vertices) - static_cast<long>(b.edges) +
                     static_cast<long>(b.faces);
    EXPECT_EQ(chi, s.euler_characteristic);
}

INSTANTIATE_TEST_SUITE_P(RealMeshes, OpenMeshCheck,
                         ::testing::Values("fox.ply", "blub_triangulated.obj",
                                           "spot_triangulated.obj", "cube_minus_sphere.obj",
                                           "cactus.off", "negative/stanford-bunny_open.obj",
                                           "negative/bob_small_genus1.ply"),
                         [](const ::testing::TestParamInfo<const char*>& param_info)
                         {
                             std::string n = param_info.param;
                             for (char& c : n)
                                 if (!std::isalnum(static_cast<unsigned char>(c)))
                                     c = '_';
                             return n;
                         });

}  // namespace
}  // namespace pliant::mesh
