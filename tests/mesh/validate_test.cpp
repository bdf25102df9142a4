// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// analyze() and validate(): the shapes of scenes/shapes.h (counts known in closed form, one
// ErrorCode per invalid shape), and each remaining rule on a hand-broken mesh.

#include <pliant/mesh/validate.h>

#include <gtest/gtest.h>

#include "shapes.h"

#include <cmath>
#include <limits>
#include <string>

namespace pliant::mesh
{
namespace
{

using core::ErrorCode;

ErrorCode code_of(const TriMesh& m)
{
    const auto r = validate(m, "shape");
    EXPECT_FALSE(r) << "expected an error";
    return r ? ErrorCode::InvalidArgument : r.error().code;
}

std::string message_of(const TriMesh& m)
{
    const auto r = validate(m, "shape.obj");
    return r ? std::string() : r.error().message;
}

TEST(Shapes, ValidShapesAreClosedGenusZeroAndOutward)
{
    const TriMesh shapes[] = {scenes::tetrahedron(), scenes::octahedron(), scenes::icosphere(0),
                              scenes::icosphere(3),  scenes::ellipsoid(),  scenes::dumbbell()};
    for (const TriMesh& m : shapes)
    {
        const MeshStats s = analyze(m);
        const auto r = validate(m, "shape");
        EXPECT_TRUE(r) << r.error().message;
        EXPECT_EQ(s.euler_characteristic, 2);
        ASSERT_TRUE(s.genus.has_value());
        EXPECT_EQ(*s.genus, 0);
        EXPECT_EQ(2 * s.edges, 3 * s.faces);  // closed triangle mesh
        EXPECT_GT(scenes::detail::signed_volume(m), 0.0);
    }
}

TEST(Shapes, IcosphereCountsAndGeometry)
{
    double previous_area = 0.0;
    for (int n = 0; n <= 4; ++n)
    {
        const TriMesh m = scenes::icosphere(n);
        const std::size_t p = std::size_t{1} << (2 * n);  // 4^n
        EXPECT_EQ(m.vertex_count(), 10 * p + 2);
        EXPECT_EQ(m.face_count(), 20 * p);
        for (const auto& v : m.positions)
            EXPECT_NEAR(core::norm(v), 1.0, 1e-15);
        // Inscribed polyhedra approach the sphere from inside: the area grows towards 4 pi;
        // level 0 is the icosahedron, area 5 sqrt(3) a^2 with edge a = 1 / sin(2 pi / 5).
        const MeshStats s = analyze(m);
        EXPECT_LT(s.surface_area, 4.0 * M_PI);
        EXPECT_GT(s.surface_area, previous_area);
        previous_area = s.surface_area;
        if (n == 0)
        {
            const double a = 1.0 / std::sin(2.0 * M_PI / 5.0);
            EXPECT_NEAR(s.surface_area, 5.0 * std::sqrt(3.0) * a * a, 1e-12);
        }
        EXPECT_NEAR(s.bbox_diagonal, 2.0 * std::sqrt(3.0), 0.7);
    }
}

TEST(Shapes, EllipsoidVerticesLieOnTheEllipsoid)
{
    const TriMesh m = scenes::ellipsoid(3.0, 2.0, 1.0, 2);
    for (const auto& p : m.positions)
        EXPECT_NEAR(p.x * p.x / 9.0 + p.y * p.y / 4.0 + p.z * p.z, 1.0, 1e-12);
    const MeshStats s = analyze(m);
    EXPECT_LE(s.bbox_max.x, 3.0);
    EXPECT_GT(s.bbox_max.x, 2.9);
}

TEST(Shapes, DumbbellIsNotStarShapedAboutItsCentre)
{
    // A ray from the centroid must leave and re-enter the surface: some face seen from the
    // origin faces inward (its normal points towards the origin).
    const TriMesh m = scenes::dumbbell();
    int inward = 0;
    for (const auto& f : m.faces)
    {
        const core::Vec3 n = core::cross(m.positions[f[1]] - m.positions[f[0]],
                                         m.positions[f[2]] - m.positions[f[0]]);
        if (core::dot(n, m.positions[f[0]]) < 0.0)
            ++inward;
    }
    EXPECT_GT(inward, 0);
}

TEST(Shapes, EachInvalidShapeHasItsOwnErrorCode)
{
    EXPECT_EQ(code_of(scenes::torus()), ErrorCode::WrongGenus);
    EXPECT_EQ(code_of(scenes::open_cone()), ErrorCode::OpenBoundary);
    EXPECT_EQ(code_of(scenes::two_spheres()), ErrorCode::NotConnected);
    EXPECT_EQ(code_of(scenes::non_manifold_vertex()), ErrorCode::NonManifoldVertex);
}

TEST(Shapes, InvalidShapeStatistics)
{
    const MeshStats torus = analyze(scenes::torus());
    EXPECT_EQ(torus.euler_characteristic, 0);
    ASSERT_TRUE(torus.genus.has_value());
    EXPECT_EQ(*torus.genus, 1);
    EXPECT_NE(message_of(scenes::torus()).find("genus 1"), std::string::npos);

    const MeshStats cone = analyze(scenes::open_cone(16));
    EXPECT_EQ(cone.boundary_edges, 16U);
    EXPECT_EQ(cone.boundary_loops, 1U);
    EXPECT_FALSE(cone.genus.has_value());
    EXPECT_EQ(cone.euler_characteristic, 1);  // a disc

    const MeshStats two = analyze(scenes::two_spheres());
    EXPECT_EQ(two.components, 2U);
    EXPECT_EQ(two.euler_characteristic, 4);
    EXPECT_NE(message_of(scenes::two_spheres()).find("2 components"), std::string::npos);

    const MeshStats pinch = analyze(scenes::non_manifold_vertex());
    EXPECT_EQ(pinch.non_manifold_vertices, 1U);
    EXPECT_EQ(pinch.non_manifold_edges, 0U);
    EXPECT_EQ(pinch.boundary_edges, 0U);
    EXPECT_EQ(pinch.euler_characteristic, 3);
    EXPECT_NE(message_of(scenes::non_manifold_vertex()).find("vertex 0 (0, 0, 0)"),
              std::string::npos)
        << message_of(scenes::non_manifold_vertex());
}

TEST(Validate, OpenBoundaryMessageNamesCountLoopsAndAVertex)
{
    TriMesh m = scenes::icosphere(1);
    m.faces.erase(m.faces.begin());  // one triangular hole
    m.faces.erase(m.faces.begin() + 40);
    const std::string msg = message_of(m);
    EXPECT_EQ(code_of(m), ErrorCode::OpenBoundary);
    EXPECT_EQ(msg.rfind("shape.obj: not a closed surface: 6 boundary edges in 2 loops (first at "
                        "vertex ",
                        0),
              0U)
        << msg;
}

TEST(Validate, BadIndexIsCheckedFirst)
{
    TriMesh m = scenes::octahedron();
    m.faces[3][1] = 99;
    m.positions[0].x = std::numeric_limits<double>::quiet_NaN();  // also broken, reported later
    EXPECT_EQ(code_of(m), ErrorCode::BadIndex);
    EXPECT_NE(message_of(m).find("face 3 refers to vertex 99"), std::string::npos) << message_of(m);
    EXPECT_EQ(analyze(m).bad_index_faces, 1U);
}

TEST(Validate, NonFiniteVertexIsNamed)
{
    TriMesh m = scenes::octahedron();
    m.positions[4].y = std::numeric_limits<double>::infinity();
    EXPECT_EQ(code_of(m), ErrorCode::NonFiniteCoordinate);
    EXPECT_NE(message_of(m).find("vertex 4"), std::string::npos) << message_of(m);
    EXPECT_EQ(analyze(m).non_finite_vertices, 1U);
}

TEST(Validate, DegenerateFacesRepeatedIndexAndZeroArea)
{
    TriMesh repeated = scenes::octahedron();
    repeated.faces[2] = {1, 1, 4};
    EXPECT_EQ(code_of(repeated), ErrorCode::DegenerateFace);
    EXPECT_NE(message_of(repeated).find("face 2"), std::string::npos);

    TriMesh flat = scenes::octahedron();
    flat.positions.push_back({0.5, 0.5, 0.0});
    flat.faces.push_back({0, 2, 6});  // (1,0,0), (0,1,0), (0.5,0.5,0): collinear
    EXPECT_EQ(code_of(flat), ErrorCode::DegenerateFace);
    EXPECT_NE(message_of(flat).find("zero area"), std::string::npos) << message_of(flat);
    EXPECT_EQ(message_of(flat).find("far from the origin"), std::string::npos) << message_of(flat);

    // A sliver: not collinear, but its height is 1e-7 of its longest edge. The message gives the
    // ratio and the rule (it said "zero area").
    TriMesh sliver = scenes::octahedron();
    sliver.positions.push_back({0.5 + 1e-7, 0.5 + 1e-7, 0.0});
    sliver.faces.push_back({0, 2, 6});
    EXPECT_EQ(code_of(sliver), ErrorCode::DegenerateFace);
    EXPECT_NE(message_of(sliver).find("almost no area: its height is 1e-07 of its longest edge, "
                                      "below the 1e-06 a face needs"),
              std::string::npos)
        << message_of(sliver);

    // Tiny: positions read as floats resolve nothing below 1e-38; the message says so.
    TriMesh tiny = repeated;
    for (core::Vec3& p : tiny.positions)
        p = p * 1e-40;
    EXPECT_EQ(code_of(tiny), ErrorCode::DegenerateFace);
    EXPECT_NE(message_of(tiny).find("the mesh is tiny (coordinates up to 1e-40)"),
              std::string::npos)
        << message_of(tiny);

    // The same far from the origin: the message points at float rounding and says where.
    for (core::Vec3& p : repeated.positions)
        p = p + core::Vec3{1e5, -2e5, 3e5};
    EXPECT_EQ(code_of(repeated), ErrorCode::DegenerateFace);
    const std::string far = message_of(repeated);
    EXPECT_NE(far.find("far from the origin (coordinates up to 300001"), std::string::npos) << far;
    EXPECT_NE(far.find("at (99999, -200000, 300000)"), std::string::npos) << far;
}

TEST(Validate, FlippedFaceIsInconsistentOrientation)
{
    TriMesh m = scenes::icosphere(1);
    std::swap(m.faces[7][1], m.faces[7][2]);
    EXPECT_EQ(code_of(m), ErrorCode::InconsistentOrientation);
    EXPECT_EQ(analyze(m).inconsistent_edges, 3U);
}

TEST(Validate, NonManifoldEdgeComesBeforeBoundary)
{
    // A fin: an extra triangle on an edge of a closed octahedron makes one edge with three faces
    // and two boundary edges; the edge rule is the more basic one.
    TriMesh m = scenes::octahedron();
    m.positions.push_back({2.0, 2.0, 2.0});
    m.faces.push_back({m.faces[0][0], m.faces[0][1], 6});
    EXPECT_EQ(code_of(m), ErrorCode::NonManifoldEdge);
    EXPECT_NE(message_of(m).find("with 3 faces"), std::string::npos) << message_of(m);
    const MeshStats s = analyze(m);
    EXPECT_EQ(s.boundary_edges, 2U);
    EXPECT_EQ(s.non_manifold_edges, 1U);
}

TEST(Validate, EmptyMeshAndUnusedVertices)
{
    EXPECT_EQ(code_of(TriMesh{}), ErrorCode::EmptyInput);
    TriMesh m = scenes::octahedron();
    m.positions.push_back({5, 5, 5});  // unused: allowed, not counted in χ or the bbox
    EXPECT_TRUE(validate(m, "x"));
    const MeshStats s = analyze(m);
    EXPECT_EQ(s.unreferenced_vertices, 1U);
    EXPECT_EQ(s.euler_characteristic, 2);
    EXPECT_EQ(s.bbox_max.x, 1.0);
}

TEST(Validate, OctahedronStatisticsInClosedForm)
{
    const MeshStats s = analyze(scenes::octahedron());
    EXPECT_EQ(s.vertices, 6U);
    EXPECT_EQ(s.faces, 8U);
    EXPECT_EQ(s.edges, 12U);
    EXPECT_EQ(s.components, 1U);
    EXPECT_DOUBLE_EQ(s.bbox_diagonal, 2.0 * std::sqrt(3.0));
    EXPECT_DOUBLE_EQ(s.surface_area, 8.0 * std::sqrt(3.0) / 2.0);  // 8 faces of side sqrt(2)
}

}  // namespace
}  // namespace pliant::mesh
