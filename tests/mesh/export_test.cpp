// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Export: import -> export -> import is the identity (OBJ and PLY), the written files are exact,
// and from_grid gives the closed genus-0 surface of DESIGN §1.

#include <pliant/core/tetra_grid.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>

#include <gtest/gtest.h>

#include "mesh/mesh_files.h"
#include "shapes.h"
#include "support/test_paths.h"

#include <cmath>
#include <cstring>

namespace pliant::mesh
{
namespace
{

void expect_equal(const TriMesh& a, const TriMesh& b)
{
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.faces.size(), b.faces.size());
    for (std::size_t i = 0; i < a.positions.size(); ++i)
        ASSERT_EQ(a.positions[i], b.positions[i]) << "vertex " << i;
    for (std::size_t i = 0; i < a.faces.size(); ++i)
        ASSERT_EQ(a.faces[i], b.faces[i]) << "face " << i;
}

class RoundTrip : public ::testing::TestWithParam<const char*>
{
};

TEST_P(RoundTrip, ImportExportImportIsTheIdentity)
{
    const auto dir = test::scratch_dir("mesh_round_trip");
    auto first = import_mesh(test::source_dir() / "tests" / "data" / "meshes" / GetParam());
    ASSERT_TRUE(first) << first.error().message;
    for (const char* ext : {".obj", ".ply"})
    {
        const auto path = dir / (std::string("out") + ext);
        ASSERT_TRUE(export_mesh(path, *first));
        auto second = import_mesh(path);
        ASSERT_TRUE(second) << second.error().message;
        expect_equal(*first, *second);
    }
}

INSTANTIATE_TEST_SUITE_P(Meshes, RoundTrip,
                         ::testing::Values("fox.ply", "spot_triangulated.obj", "cactus.off",
                                           "negative/hourglass_ico_nonmanifold_vertex.obj"),
                         [](const ::testing::TestParamInfo<const char*>& param_info) {
                             return std::string(1, param_info.param[0]) +
                                    std::to_string(param_info.index);
                         });

TEST(Export, PlyStoresDoublesBitForBit)
{
    // The PLY body is read back here by hand (not through Assimp, which narrows to float), so
    // this checks the writer alone: doubles that are not floats survive.
    const auto dir = test::scratch_dir("mesh_ply_bits");
    const TriMesh m = scenes::icosphere(1);
    ASSERT_TRUE(export_mesh(dir / "s.ply", m));
    const std::string bytes = test::read_all(dir / "s.ply");
    const std::size_t body = bytes.find("end_header\n") + 11;
    ASSERT_EQ(bytes.size(), body + m.vertex_count() * 24 + m.face_count() * 13);
    for (std::size_t i = 0; i < m.vertex_count(); ++i)
    {
        double xyz[3];
        std::memcpy(xyz, bytes.data() + body + 24 * i, 24);
        EXPECT_EQ(xyz[0], m.positions[i].x);
        EXPECT_EQ(xyz[1], m.positions[i].y);
        EXPECT_EQ(xyz[2], m.positions[i].z);
    }
}

TEST(Export, ObjWritesSeventeenDigits)
{
    const auto dir = test::scratch_dir("mesh_obj_digits");
    TriMesh m = scenes::tetrahedron();
    ASSERT_TRUE(export_mesh(dir / "t.obj", m));
    const std::string text = test::read_all(dir / "t.obj");
    double x = 0;
    double y = 0;
    double z = 0;
    const std::size_t v = text.find("\nv ");
    ASSERT_NE(v, std::string::npos);
    ASSERT_EQ(std::sscanf(text.c_str() + v + 3, "%lf %lf %lf", &x, &y, &z), 3);
    EXPECT_EQ(x, m.positions[0].x);  // strtod is exact on 17 digits
    EXPECT_EQ(y, m.positions[0].y);
    EXPECT_EQ(z, m.positions[0].z);
}

TEST(Export, ShapesSurviveUpToFloatRounding)
{
    // import_mesh reads single precision (Assimp's ai_real): a double mesh comes back rounded
    // to float, with its topology intact. Through PLY (doubles, narrowed by a cast) the rounding
    // is exact; through OBJ, Assimp's fast_atof is exact for ordinary decimals but may miss by an
    // ulp on exponent notation (seen on |x| ~ 1e-16), hence the looser bound there.
    const auto dir = test::scratch_dir("mesh_shapes_export");
    const TriMesh m = scenes::dumbbell();
    for (const char* name : {"d.ply", "d.obj"})
    {
        const bool ply = name[2] == 'p';
        ASSERT_TRUE(export_mesh(dir / name, m));
        auto back = import_mesh(dir / name);
        ASSERT_TRUE(back) << back.error().message;
        ASSERT_EQ(back->vertex_count(), m.vertex_count());
        ASSERT_EQ(back->faces, m.faces);  // dumbbell vertices are numbered in first-use order
        for (std::size_t i = 0; i < m.vertex_count(); ++i)
        {
            const double in[3] = {m.positions[i].x, m.positions[i].y, m.positions[i].z};
            const double out[3] = {back->positions[i].x, back->positions[i].y,
                                   back->positions[i].z};
            for (int k = 0; k < 3; ++k)
            {
                const double f = static_cast<double>(static_cast<float>(in[k]));
                if (ply)
                    EXPECT_EQ(out[k], f) << name << " vertex " << i;
                else
                    EXPECT_LE(std::abs(out[k] - f), 2.4e-7 * std::abs(f)) << name << " " << i;
            }
        }
    }
}

TEST(Export, UnsupportedExtensionAndUnwritablePath)
{
    const auto dir = test::scratch_dir("mesh_export_errors");
    const auto stl = export_mesh(dir / "x.stl", scenes::octahedron());
    ASSERT_FALSE(stl);
    EXPECT_EQ(stl.error().code, core::ErrorCode::UnsupportedFormat);
    const auto missing = export_mesh(dir / "no" / "such" / "x.obj", scenes::octahedron());
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, core::ErrorCode::IoError);
}

TEST(FromGrid, GivesTheClosedGenusZeroGridSurface)
{
    for (int level = 1; level <= 4; ++level)
    {
        auto grid = core::TetraGrid::create(level);
        ASSERT_TRUE(grid);
        // Positions: the grid's (x, y) lifted onto a sphere-like bump would need the remesher;
        // any injective map works for topology, e.g. node index -> distinct point.
        core::Vec3Field<double> pos{core::Field<double>(*grid, 0), core::Field<double>(*grid, 0),
                                    core::Field<double>(*grid, 0)};
        for (int y = 0; y < grid->ny(); ++y)
            for (int x = 0; x < grid->nx(); ++x)
            {
                pos[0].at(x, y) = x;
                pos[1].at(x, y) = y;
                pos[2].at(x, y) = x * 1000 + y;
            }
        const TriMesh m = from_grid(*grid, pos);
        const std::size_t w = std::size_t{1} << level;
        EXPECT_EQ(m.vertex_count(), 2 * w * w + 2);
        EXPECT_EQ(m.face_count(), 4 * w * w);
        const MeshStats s = analyze(m);
        EXPECT_EQ(s.boundary_edges, 0U);
        EXPECT_EQ(s.non_manifold_vertices, 0U);
        EXPECT_EQ(s.inconsistent_edges, 0U);
        EXPECT_EQ(s.edges, 6 * w * w);
        ASSERT_TRUE(s.genus.has_value());
        EXPECT_EQ(*s.genus, 0);
        const auto canon = grid->node_of_unique()[5];
        EXPECT_EQ(m.positions[5].z, pos[2][canon]);
    }
}

}  // namespace
}  // namespace pliant::mesh
