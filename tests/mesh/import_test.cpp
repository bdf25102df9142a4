// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Import: the real meshes against the counts of tests/data/meshes/README.md (measured there by an
// independent Python tool), every supported format against the same mesh, welding, and every
// import error code on hostile files.

#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include "mesh/mesh_files.h"
#include "shapes.h"
#include "support/test_paths.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <ostream>
#include <random>
#include <string>
#include <type_traits>
#include <utility>

namespace pliant::mesh
{
namespace
{

using core::ErrorCode;

std::filesystem::path data(const char* name)
{
    return test::source_dir() / "tests" / "data" / "meshes" / name;
}

struct Expected
{
    const char* file;
    std::size_t vertices;
    std::size_t faces;
    long genus;  ///< -1: undefined
    ErrorCode code;
    bool ok;
};

// The test's name shows the file (gtest would print the struct's bytes, a pointer among them,
// which changes the ctest names from build to build).
void PrintTo(const Expected& e, std::ostream* os)
{
    *os << e.file;
}

// tests/data/meshes/README.md, "Positive set" and "Negative set".
const Expected k_table[] = {
    {"fox.ply", 313, 622, 0, ErrorCode::InvalidArgument, true},
    {"blub_triangulated.obj", 7106, 14208, 0, ErrorCode::InvalidArgument, true},
    {"spot_triangulated.obj", 2930, 5856, 0, ErrorCode::InvalidArgument, true},
    {"cube_minus_sphere.obj", 2066, 4128, 0, ErrorCode::InvalidArgument, true},
    {"cactus.off", 5261, 10518, 0, ErrorCode::InvalidArgument, true},
    {"negative/stanford-bunny_open.obj", 34834, 69451, -1, ErrorCode::OpenBoundary, false},
    {"negative/bob_small_genus1.ply", 250, 500, 1, ErrorCode::WrongGenus, false},
    {"negative/hourglass_ico_nonmanifold_vertex.obj", 23, 40, -1, ErrorCode::NonManifoldVertex,
     false},
    {"negative/two_cubes_shared_edge_nonmanifold_edge.obj", 14, 24, -1, ErrorCode::NonManifoldEdge,
     false},
};

class RealMesh : public ::testing::TestWithParam<Expected>
{
};

TEST_P(RealMesh, CountsGenusAndVerdictMatchTheDataTable)
{
    const Expected& e = GetParam();
    ImportReport report;
    auto mesh = import_mesh(data(e.file), &report);
    ASSERT_TRUE(mesh) << mesh.error().message;
    EXPECT_EQ(mesh->vertex_count(), e.vertices);
    EXPECT_EQ(mesh->face_count(), e.faces);
    EXPECT_EQ(report.vertices, e.vertices);
    const MeshStats s = analyze(*mesh);
    EXPECT_EQ(s.unreferenced_vertices, 0U);
    if (e.genus >= 0)
    {
        ASSERT_TRUE(s.genus.has_value());
        EXPECT_EQ(*s.genus, e.genus);
    }
    else
    {
        EXPECT_FALSE(s.genus.has_value());
    }
    const auto verdict = validate(*mesh, e.file);
    EXPECT_EQ(verdict.has_value(), e.ok);
    if (!e.ok)
    {
        EXPECT_EQ(verdict.error().code, e.code) << verdict.error().message;
        EXPECT_NE(verdict.error().message.find(e.file), std::string::npos);
    }
}

INSTANTIATE_TEST_SUITE_P(Table, RealMesh, ::testing::ValuesIn(k_table),
                         [](const ::testing::TestParamInfo<Expected>& param_info)
                         {
                             std::string n = param_info.param.file;
                             for (char& c : n)
                                 if (!std::isalnum(static_cast<unsigned char>(c)))
                                     c = '_';
                             return n;
                         });

TEST(Import, OpenBunnyDropsUnreferencedAndReportsItsHoles)
{
    ImportReport report;
    auto mesh = import_mesh(data("negative/stanford-bunny_open.obj"), &report);
    ASSERT_TRUE(mesh);
    EXPECT_EQ(report.file_vertices, 35947U);
    EXPECT_EQ(report.unreferenced_dropped, 1113U);
    const MeshStats s = analyze(*mesh);
    EXPECT_EQ(s.boundary_edges, 223U);
    EXPECT_EQ(s.boundary_loops, 5U);
    EXPECT_EQ(s.euler_characteristic, -3);
    const auto verdict = validate(*mesh, "bunny.obj");
    ASSERT_FALSE(verdict);
    EXPECT_NE(verdict.error().message.find("223 boundary edges in 5 loops"), std::string::npos)
        << verdict.error().message;
}

// Faces may name `v` records further down the file: those vertices are used, not dropped (the
// count said "unreferenced dropped 4" of a tetrahedron whose faces came first).
TEST(Import, FacesBeforeTheirVerticesLeaveNoneUnreferenced)
{
    const auto dir = test::scratch_dir("mesh_forward_references");
    test::write_bytes(dir / "faces_first.obj",
                      "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
                      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 5 5 5\n");
    ImportReport report;
    auto mesh = import_mesh(dir / "faces_first.obj", &report);
    ASSERT_TRUE(mesh) << mesh.error().message;
    EXPECT_EQ(mesh->vertex_count(), 4U);
    EXPECT_EQ(report.unreferenced_dropped, 1U);  // only the fifth record
}

TEST(Import, GenusOneMessageSaysGenusOne)
{
    auto mesh = import_mesh(data("negative/bob_small_genus1.ply"));
    ASSERT_TRUE(mesh);
    const auto verdict = validate(*mesh, "bob.ply");
    ASSERT_FALSE(verdict);
    EXPECT_NE(verdict.error().message.find("genus 1"), std::string::npos)
        << verdict.error().message;
}

TEST(Import, NonManifoldEdgeMeshHasTheREADMEsPinchCount)
{
    auto mesh = import_mesh(data("negative/two_cubes_shared_edge_nonmanifold_edge.obj"));
    ASSERT_TRUE(mesh);
    const MeshStats s = analyze(*mesh);
    EXPECT_EQ(s.non_manifold_edges, 1U);
    EXPECT_EQ(s.non_manifold_vertices, 2U);  // README: "2 non-manifold vertices"
    EXPECT_EQ(s.euler_characteristic, 3);
}

// ---- every format gives the same mesh ------------------------------------------------------

class Formats : public ::testing::Test
{
protected:
    std::filesystem::path dir_ = test::scratch_dir("mesh_formats");
    TriMesh reference_ = scenes::octahedron();

    TriMesh load(const char* name, const std::string& bytes, ImportReport* report = nullptr)
    {
        test::write_bytes(dir_ / name, bytes);
        auto mesh = import_mesh(dir_ / name, report);
        EXPECT_TRUE(mesh) << mesh.error().message;
        return mesh ? *mesh : TriMesh{};
    }
};

void expect_same(const TriMesh& a, const TriMesh& b)
{
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.faces.size(), b.faces.size());
    for (std::size_t i = 0; i < a.positions.size(); ++i)
        EXPECT_EQ(a.positions[i], b.positions[i]) << "vertex " << i;
    for (std::size_t i = 0; i < a.faces.size(); ++i)
        EXPECT_EQ(a.faces[i], b.faces[i]) << "face " << i;
}

TEST_F(Formats, EveryFormatImportsToTheSameMesh)
{
    // The octahedron's vertices are numbered in order of first use by its faces, which is what
    // import produces; its coordinates are exact in float.
    ASSERT_TRUE(export_mesh(dir_ / "ref.obj", reference_));
    auto obj = import_mesh(dir_ / "ref.obj");
    ASSERT_TRUE(obj);
    ImportReport r;
    expect_same(load("a.off", test::to_off(reference_), &r), *obj);
    EXPECT_EQ(r.format, "off");
    expect_same(load("a.ply", test::to_ply_ascii(reference_), &r), *obj);
    EXPECT_EQ(r.format, "ply-ascii");
    expect_same(load("a.stl", test::to_stl_ascii(reference_), &r), *obj);
    EXPECT_EQ(r.format, "stl-ascii");
    expect_same(load("b.stl", test::to_stl_binary(reference_), &r), *obj);
    EXPECT_EQ(r.format, "stl-binary");
    expect_same(load("a.gltf", test::to_gltf(reference_), &r), *obj);
    EXPECT_EQ(r.format, "gltf");
    ASSERT_TRUE(export_mesh(dir_ / "ref.ply", reference_));
    expect_same(load("c.ply", test::read_all(dir_ / "ref.ply"), &r), *obj);
    EXPECT_EQ(r.format, "ply-binary");
    // Every one of them is a valid genus-0 surface.
    EXPECT_TRUE(validate(*obj, "octahedron"));
}

// Assimp's OFF reader skips faces of more than 9 vertices; the import splits them first. A prism
// with two 12-gon caps reads as the same mesh from OFF and from OBJ (whose reader keeps them).
TEST_F(Formats, OffFacesOfMoreThanNineVerticesAreKept)
{
    constexpr int n = 12;
    std::string off = "OFF\n" + std::to_string(2 * n) + " " + std::to_string(n + 2) + " 0\n";
    std::string obj;
    for (int z = 0; z < 2; ++z)
        for (int i = 0; i < n; ++i)
        {
            // Coordinates exact in float, so both readers give the same numbers.
            const std::string v = std::to_string(std::lround(8 * std::cos(2 * M_PI * i / n))) +
                                  " " +
                                  std::to_string(std::lround(8 * std::sin(2 * M_PI * i / n))) +
                                  " " + std::to_string(z);
            off += v + "\n";
            obj += "v " + v + "\n";
        }
    std::string bottom = std::to_string(n);
    std::string top = std::to_string(n);
    std::string bottom_obj = "f";
    std::string top_obj = "f";
    for (int i = 0; i < n; ++i)
    {
        bottom += " " + std::to_string(n - 1 - i);
        bottom_obj += " " + std::to_string(n - i);
        top += " " + std::to_string(n + i);
        top_obj += " " + std::to_string(n + i + 1);
    }
    off += bottom + "\n" + top + "\n";
    obj += bottom_obj + "\n" + top_obj + "\n";
    for (int i = 0; i < n; ++i)
    {
        const int j = (i + 1) % n;
        off += "4 " + std::to_string(i) + " " + std::to_string(j) + " " + std::to_string(n + j) +
               " " + std::to_string(n + i) + "\n";
        obj += "f " + std::to_string(i + 1) + " " + std::to_string(j + 1) + " " +
               std::to_string(n + j + 1) + " " + std::to_string(n + i + 1) + "\n";
    }
    ImportReport r;
    const TriMesh from_off = load("prism.off", off, &r);
    EXPECT_EQ(from_off.face_count(), std::size_t{4 * n - 4});  // 2 (n - 2) + 2 n
    EXPECT_TRUE(validate(from_off, "prism.off"));
    expect_same(from_off, load("prism.obj", obj, &r));
}

TEST_F(Formats, StlCornersAreWeldedBackToSixVertices)
{
    ImportReport r;
    const TriMesh m = load("w.stl", test::to_stl_binary(reference_), &r);
    EXPECT_EQ(m.vertex_count(), 6U);
    EXPECT_EQ(m.face_count(), 8U);
    EXPECT_EQ(r.raw_vertices, 24U);
    EXPECT_EQ(r.welded, 18U);
    EXPECT_TRUE(validate(m, "w.stl"));
}

TEST_F(Formats, SeamsWithDifferentNormalsAndUVsAreWelded)
{
    // A tetrahedron whose every corner has its own texture coordinate and normal: Assimp keeps
    // them apart, pliant welds by position only.
    const std::string obj =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
        "vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvn 0 0 1\nvn 0 1 0\nvn 1 0 0\n"
        "f 1/1/1 3/2/2 2/3/3\nf 1/4/1 2/1/2 4/2/3\n"
        "f 1/3/1 4/4/2 3/1/3\nf 2/2/1 3/3/2 4/4/3\n";
    const TriMesh m = load("seam.obj", obj);
    EXPECT_EQ(m.vertex_count(), 4U);
    EXPECT_TRUE(validate(m, "seam.obj")) << validate(m, "seam.obj").error().message;
}

TEST_F(Formats, PolygonsAreFanTriangulatedAndObjectsMerged)
{
    // A cube of six quads, split over two OBJ objects.
    const std::string obj =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "o first\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\n"
        "o second\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    ImportReport r;
    const TriMesh m = load("cube.obj", obj, &r);
    EXPECT_EQ(m.vertex_count(), 8U);
    EXPECT_EQ(m.face_count(), 12U);
    EXPECT_EQ(r.polygons_triangulated, 6U);
    EXPECT_EQ(r.meshes, 2U);
    EXPECT_TRUE(validate(m, "cube.obj")) << validate(m, "cube.obj").error().message;
    EXPECT_GT(scenes::detail::signed_volume(m), 0.0);  // winding kept
}

TEST_F(Formats, GltfNodeTransformIsApplied)
{
    std::string g = test::to_gltf(reference_);
    const std::string node = R"("nodes":[{"mesh":0}])";
    g.replace(g.find(node), node.size(), R"("nodes":[{"mesh":0,"translation":[10,0,0]}])");
    const TriMesh m = load("moved.gltf", g);
    ASSERT_EQ(m.vertex_count(), 6U);
    const MeshStats s = analyze(m);
    EXPECT_EQ(s.bbox_min.x, 9.0);
    EXPECT_EQ(s.bbox_max.x, 11.0);
}

// A UTF-8 byte-order mark before the first line: Assimp 5.2's OBJ reader takes it as part of
// that line's keyword and drops the line (a tetrahedron then refers to a fourth vertex it does
// not have); the scan skipped it as no `v` line either.
TEST_F(Formats, ObjWithAUtf8ByteOrderMarkImportsLikeWithout)
{
    const std::string tet =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
        "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    const std::string bom = "\xEF\xBB\xBF";
    ImportReport plain;
    ImportReport marked;
    const TriMesh without = load("tet.obj", tet, &plain);
    const TriMesh with = load("tet_bom.obj", bom + tet, &marked);
    ASSERT_EQ(without.vertex_count(), 4U);
    expect_same(with, without);
    EXPECT_EQ(marked.file_vertices, 4U);
    EXPECT_EQ(marked.unreferenced_dropped, plain.unreferenced_dropped);
    EXPECT_EQ(marked.welded, plain.welded);
    EXPECT_TRUE(validate(with, "tet_bom.obj"));
    // The first vertex is read even when dropping it would leave every index in range.
    const TriMesh triangle = load("tri_bom.obj", bom + "v 5 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    ASSERT_EQ(triangle.vertex_count(), 3U);
    EXPECT_EQ(triangle.positions[0], (core::Vec3{5, 0, 0}));
    // Line numbers still count the marked line as line 1.
    test::write_bytes(dir_ / "idx_bom.obj", bom + "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    const auto bad = import_mesh(dir_ / "idx_bom.obj");
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, ErrorCode::BadIndex);
    EXPECT_NE(bad.error().message.find("idx_bom.obj:4: face refers to vertex 9 but the file has 3"),
              std::string::npos)
        << bad.error().message;
}

// The same mark before an ASCII STL's `solid` (and an OFF's `OFF`): imported as without it, where
// the STL was taken for a binary file whose header declared 1.8 billion triangles.
TEST_F(Formats, StlAndOffWithAUtf8ByteOrderMarkImportLikeWithout)
{
    const std::string bom = "\xEF\xBB\xBF";
    std::string stl = "solid tet\n";
    const char* facets[4] = {
        "0 0 0\nvertex 0 1 0\nvertex 1 0 0", "0 0 0\nvertex 1 0 0\nvertex 0 0 1",
        "0 0 0\nvertex 0 0 1\nvertex 0 1 0", "1 0 0\nvertex 0 1 0\nvertex 0 0 1"};
    for (const char* f : facets)
        stl += std::string("facet normal 0 0 0\nouter loop\nvertex ") + f + "\nendloop\nendfacet\n";
    stl += "endsolid tet\n";
    const std::string off =
        "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n"
        "3 1 2 3\n";
    for (const auto& [name, text] :
         {std::pair<std::string, std::string>{"tet.stl", stl}, {"tet.off", off}})
    {
        ImportReport plain;
        ImportReport marked;
        const TriMesh without = load(name.c_str(), text, &plain);
        const TriMesh with = load(("bom_" + name).c_str(), bom + text, &marked);
        ASSERT_EQ(without.face_count(), 4U) << name;
        expect_same(with, without);
        EXPECT_EQ(marked.format, plain.format) << name;
        EXPECT_TRUE(validate(with, name)) << name;
    }
}

// ---- hostile files: one error code each, no crash ------------------------------------------

class BadFiles : public ::testing::Test
{
protected:
    std::filesystem::path dir_ = test::scratch_dir("mesh_bad_files");

    core::Error error_of(const char* name, const std::string& bytes)
    {
        test::write_bytes(dir_ / name, bytes);
        auto mesh = import_mesh(dir_ / name);
        EXPECT_FALSE(mesh) << name << " imported";
        if (mesh)
            return {};
        EXPECT_NE(mesh.error().message.find(name), std::string::npos) << mesh.error().message;
        return mesh.error();
    }
};

TEST_F(BadFiles, MissingFileIsIoError)
{
    auto mesh = import_mesh(dir_ / "nope.obj");
    ASSERT_FALSE(mesh);
    EXPECT_EQ(mesh.error().code, ErrorCode::IoError);
    auto folder = import_mesh(dir_);
    ASSERT_FALSE(folder);
    EXPECT_EQ(folder.error().code, ErrorCode::IoError);
}

TEST_F(BadFiles, EmptyFilesAreEmptyInput)
{
    for (const char* name : {"e.obj", "e.off", "e.ply", "e.stl", "e.gltf", "e.glb"})
        EXPECT_EQ(error_of(name, "").code, ErrorCode::EmptyInput) << name;
    EXPECT_EQ(error_of("ws.obj", "  \n\n").code, ErrorCode::EmptyInput);
    EXPECT_EQ(error_of("points.obj", "v 0 0 0\nv 1 0 0\n").code, ErrorCode::EmptyInput);
    EXPECT_EQ(error_of("nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n").code,
              ErrorCode::EmptyInput);
    std::string stl(84, '\0');  // binary STL header declaring 0 triangles
    EXPECT_EQ(error_of("zero.stl", stl).code, ErrorCode::EmptyInput);
}

TEST_F(BadFiles, UnknownExtensionIsUnsupportedFormat)
{
    EXPECT_EQ(error_of("m.xyz", "v 0 0 0\n").code, ErrorCode::UnsupportedFormat);
    EXPECT_EQ(error_of("noext", "v 0 0 0\n").code, ErrorCode::UnsupportedFormat);
}

TEST_F(BadFiles, GarbageBytesAreParseErrors)
{
    std::mt19937 rng(12345);
    std::string garbage(4000, '\0');
    for (char& c : garbage)
        c = static_cast<char>(rng() & 0xFF);
    for (const char* name : {"g.obj", "g.off", "g.ply", "g.stl", "g.gltf", "g.glb"})
        EXPECT_EQ(error_of(name, garbage).code, ErrorCode::ParseError) << name;
    // Out of memory is told by the exception Assimp kept, not by its message, which can hold
    // the file's name: these are broken files, not a full memory (no std::bad_alloc thrown).
    for (const char* name : {"std_bad_alloc.gltf", "bad_alloc.glb", "bad_alloc.ply"})
        EXPECT_EQ(error_of(name, garbage).code, ErrorCode::ParseError) << name;
    EXPECT_EQ(error_of("t.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [").code,
              ErrorCode::ParseError);
    EXPECT_EQ(error_of("h.ply", "ply\nformat ascii 1.0\nelement vertex x\nend_header\n").code,
              ErrorCode::ParseError);
}

// A bad index or coordinate is refused with the file's line, whatever Assimp's reader would do
// with it (its OFF reader replaces a bad index with the last vertex or with 0, silently).
TEST_F(BadFiles, BadIndicesAndCoordinatesNameTheirLine)
{
    const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    const struct
    {
        const char* name;
        std::string bytes;
        ErrorCode code;
        const char* says;
    } cases[] = {
        {"idx.obj", v3 + "f 1 2 9\n", ErrorCode::BadIndex, ":4: face refers to vertex 9"},
        {"zero.obj", v3 + "f 2 3 0\n", ErrorCode::BadIndex, ":4: face 0: corner '0'"},
        {"rel.obj", v3 + "f 1 2 -4\n", ErrorCode::BadIndex, ":4: face 0: relative index -4"},
        {"two.obj", v3 + "f 1 2\n", ErrorCode::BadIndex, ":4: face 0 has 2 corners"},
        {"word.obj", v3 + "f 1 2 x/1\n", ErrorCode::BadIndex, "corner 'x/1'"},
        {"coord.obj", "v 1 abc 0\n" + v3 + "f 2 3 4\n", ErrorCode::ParseError,
         ":1: vertex record 1: coordinate 'abc'"},
        {"short.obj", v3 + "v 1 0\nf 1 2 3\n", ErrorCode::ParseError,
         ":4: vertex record 4 has 2 coordinates"},
    };
    for (const auto& c : cases)
    {
        const core::Error e = error_of(c.name, c.bytes);
        EXPECT_EQ(e.code, c.code) << c.name << ": " << e.message;
        EXPECT_NE(e.message.find(c.says), std::string::npos) << e.message;
    }
    // The OFF tetrahedron with its last face line changed; the face lines start at line 7.
    const std::string head = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n";
    const struct
    {
        const char* face;
        const char* says;
    } off_cases[] = {
        {"3 1 2 77", ":10: face 3: index '77' is not a vertex"},
        {"3 1 2 -1", ":10: face 3: index '-1'"},
        {"3 1 2 x", ":10: face 3: index 'x'"},
        {"3 1 2", ":10: face 3 declares 3 vertices but lists 2"},
        {"9 1 2 3", ":10: face 3 declares 9 vertices but lists 3"},
        {"2 1 2", ":10: face 3: vertex count '2'"},
    };
    for (const auto& c : off_cases)
    {
        const core::Error e = error_of("bad.off", head + c.face + "\n");
        EXPECT_EQ(e.code, ErrorCode::BadIndex) << c.face << ": " << e.message;
        EXPECT_NE(e.message.find(c.says), std::string::npos) << e.message;
    }
    test::write_bytes(dir_ / "good.off", head + "3 1 2 3\n");
    EXPECT_TRUE(import_mesh(dir_ / "good.off"));
    const core::Error coord = error_of("coord.off",
                                       "OFF\n4 4 0\n0 0 0\n1 0 0\n0 y 0\n0 0 1\n3 0 2 1\n3 0 1 3\n"
                                       "3 0 3 2\n3 1 2 3\n");
    EXPECT_EQ(coord.code, ErrorCode::ParseError);
    EXPECT_NE(coord.message.find(":5: vertex 2: coordinate 'y'"), std::string::npos)
        << coord.message;
}

TEST_F(BadFiles, AsciiStlMustCloseEveryFacetAndTheSolid)
{
    const std::string full = test::to_stl_ascii(scenes::tetrahedron());
    // Cut at a facet boundary: the facets read are whole, but the solid is not closed.
    const std::size_t second = full.find("facet", full.find("endfacet") + 8);
    const core::Error cut = error_of("cut.stl", full.substr(0, second));
    EXPECT_EQ(cut.code, ErrorCode::ParseError);
    EXPECT_NE(cut.message.find("no 'endsolid' after 1 facet"), std::string::npos) << cut.message;
    // A facet with two vertices.
    std::string two = full;
    const std::size_t vertex = two.find("vertex");
    two.erase(vertex, two.find('\n', vertex) + 1 - vertex);
    const core::Error e = error_of("two.stl", two);
    EXPECT_EQ(e.code, ErrorCode::ParseError);
    EXPECT_NE(e.message.find("facet 0 has 2 vertices"), std::string::npos) << e.message;
}

TEST_F(BadFiles, DevicesAndFifosAreRefusedNotRead)
{
    const auto zero = dir_ / "zero.obj";
    std::filesystem::remove(zero);
    std::filesystem::create_symlink("/dev/zero", zero);
    auto mesh = import_mesh(zero);
    ASSERT_FALSE(mesh);
    EXPECT_EQ(mesh.error().code, ErrorCode::IoError);
    EXPECT_NE(mesh.error().message.find("not a regular file"), std::string::npos)
        << mesh.error().message;
    const auto fifo = dir_ / "fifo.obj";
    std::filesystem::remove(fifo);
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    auto from_fifo = import_mesh(fifo);  // would block in a read
    ASSERT_FALSE(from_fifo);
    EXPECT_EQ(from_fifo.error().code, ErrorCode::IoError);
}

TEST_F(BadFiles, TruncatedBinaryStlIsParseError)
{
    const std::string full = test::to_stl_binary(scenes::octahedron());
    ASSERT_EQ(full.size(), 84U + 50U * 8U);
    const core::Error e = error_of("cut.stl", full.substr(0, full.size() - 30));
    EXPECT_EQ(e.code, ErrorCode::ParseError);
    EXPECT_NE(e.message.find("484"), std::string::npos) << e.message;  // 84 + 50 * 8
    EXPECT_EQ(error_of("short.stl", full.substr(0, 40)).code, ErrorCode::ParseError);
}

TEST_F(BadFiles, TruncatedPlyIsParseError)
{
    ASSERT_TRUE(export_mesh(dir_ / "full.ply", scenes::icosphere(1)));
    const std::string full = test::read_all(dir_ / "full.ply");
    // Cut inside the faces, inside the vertices, and right after the header.
    for (const std::size_t keep : {full.size() - 7, full.size() / 2, full.find("end_header") + 11})
        EXPECT_EQ(error_of("cut.ply", full.substr(0, keep)).code, ErrorCode::ParseError) << keep;
    const std::string ascii = test::to_ply_ascii(scenes::icosphere(1));
    EXPECT_EQ(error_of("cut_ascii.ply", ascii.substr(0, ascii.size() - 30)).code,
              ErrorCode::ParseError);
    const std::string off = test::to_off(scenes::icosphere(1));
    EXPECT_EQ(error_of("cut.off", off.substr(0, off.size() - 30)).code, ErrorCode::ParseError);
}

// PLY faces are read index by index too: Assimp's PLY reader reads a missing or non-numeric
// index as 0, drops extra values and faces of two vertices, and reports an out-of-range index
// without saying where, all measured with Assimp 5.2.
TEST_F(BadFiles, PlyIndicesAndValuesNameTheirLineOrByte)
{
    // The tetrahedron with its last face line changed; the face lines start at line 14.
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
        "property float y\nproperty float z\nelement face 4\n"
        "property list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n";
    const struct
    {
        const char* face;
        ErrorCode code;
        const char* says;
    } cases[] = {
        {"3 1 2 77", ErrorCode::BadIndex, ":17: face 3: index '77' is not a vertex"},
        {"3 1 2 -1", ErrorCode::BadIndex, ":17: face 3: index '-1'"},
        {"3 1 2 x", ErrorCode::BadIndex, ":17: face 3: index 'x'"},
        {"3 1 2", ErrorCode::BadIndex, ":17: face 3 declares 3 vertices but lists 2"},
        {"2 1 2", ErrorCode::BadIndex, ":17: face 3: vertex count '2'"},
        {"3 1 2 3 0", ErrorCode::ParseError, ":17: face 3 has 5 values but the header's"},
    };
    for (const auto& c : cases)
    {
        const core::Error e = error_of("bad.ply", head + c.face + "\n");
        EXPECT_EQ(e.code, c.code) << c.face << ": " << e.message;
        EXPECT_NE(e.message.find(c.says), std::string::npos) << e.message;
    }
    test::write_bytes(dir_ / "good.ply", head + "3 1 2 3\n");
    EXPECT_TRUE(import_mesh(dir_ / "good.ply"));
    std::string coord = head + "3 1 2 3\n";
    coord.replace(coord.find("0 1 0\n"), 5, "0 y 0");
    const core::Error e = error_of("coord.ply", coord);
    EXPECT_EQ(e.code, ErrorCode::ParseError);
    EXPECT_NE(e.message.find(":12: vertex 2: property 'y' value 'y' is not a number"),
              std::string::npos)
        << e.message;

    // Binary: the same tetrahedron, little-endian floats and a uchar/int index list (or, with a
    // float last index, a uchar/float list).
    const auto binary = [](auto last_index, std::uint8_t last_count)
    {
        using Index = decltype(last_index);
        std::string b = std::string(
                            "ply\nformat binary_little_endian 1.0\nelement vertex 4\n"
                            "property float x\nproperty float y\nproperty float z\n"
                            "element face 4\nproperty list uchar ") +
                        (std::is_floating_point_v<Index> ? "float" : "int") +
                        " vertex_indices\nend_header\n";
        const auto put = [&b](auto value)
        {
            char bytes[sizeof value];
            std::memcpy(bytes, &value, sizeof value);  // the test machines are little-endian
            b.append(bytes, sizeof value);
        };
        for (const float x : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f})
            put(x);
        const Index faces[4][3] = {
            {0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {Index{1}, Index{2}, last_index}};
        for (int f = 0; f < 4; ++f)
        {
            put(f == 3 ? last_count : std::uint8_t{3});
            for (int k = 0; k < (f == 3 ? last_count : 3); ++k)
                put(faces[f][k]);
        }
        return b;
    };
    // Face 3 starts at byte 169 (header) + 4 * 12 (vertices) + 3 * 13 (faces) = 256.
    test::write_bytes(dir_ / "good_binary.ply", binary(3, 3));
    EXPECT_TRUE(import_mesh(dir_ / "good_binary.ply"));
    const core::Error big = error_of("big.ply", binary(77, 3));
    EXPECT_EQ(big.code, ErrorCode::BadIndex);
    EXPECT_NE(big.message.find(": face 3 (byte 256): index '77' is not a vertex"),
              std::string::npos)
        << big.message;
    const core::Error negative = error_of("negative.ply", binary(-5, 3));
    EXPECT_NE(negative.message.find("index '-5'"), std::string::npos) << negative.message;
    const core::Error two = error_of("two.ply", binary(3, 2));
    EXPECT_EQ(two.code, ErrorCode::BadIndex);
    EXPECT_NE(two.message.find("face 3 (byte 256): vertex count 2 is less than 3"),
              std::string::npos)
        << two.message;

    // Index lists of floats are legal PLY: each index must be a whole number naming a vertex
    // (unchecked, Assimp read NaN as 0, truncated 2.5 to 2 and said 77 without the face). Face 3
    // starts 2 bytes later: the header's "float" is one letter more than "int".
    const auto float_indices = [&binary](float last_index) { return binary(last_index, 3); };
    test::write_bytes(dir_ / "good_float_indices.ply", float_indices(3.f));
    EXPECT_TRUE(import_mesh(dir_ / "good_float_indices.ply"));
    for (const float bad : {std::numeric_limits<float>::quiet_NaN(), 2.5f, 77.f, -1.f})
    {
        const core::Error index = error_of("float_index.ply", float_indices(bad));
        EXPECT_EQ(index.code, ErrorCode::BadIndex) << bad << ": " << index.message;
        EXPECT_NE(index.message.find(": face 3 (byte 258): index '"), std::string::npos)
            << index.message;
    }
}

// Assimp's PLY reader takes a missing x, y or z as 0 (the faces then degenerate, which was the
// message) and a face element without its index list as no face at all ("Mesh  contains no
// faces"); the scan refuses both with the header line of the element.
TEST_F(BadFiles, PlyVertexNeedsXYZ)
{
    const auto ply =
        [](const std::string& format, const std::string& vertex_properties, const std::string& body)
    {
        return "ply\nformat " + format + " 1.0\nelement vertex 4\n" + vertex_properties +
               "element face 4\nproperty list uchar int vertex_indices\nend_header\n" + body;
    };
    const std::string ascii = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    const struct
    {
        const char* name;
        std::string bytes;
        const char* says;
    } cases[] = {
        {"abc.ply", ply("ascii", "property float a\nproperty float b\nproperty float c\n", ascii),
         ":3: the vertex element has no property 'x' (a PLY vertex needs x, y and z)"},
        {"xy.ply", ply("ascii", "property float x\nproperty float y\nproperty float w\n", ascii),
         ":3: the vertex element has no property 'z' (a PLY vertex needs x, y and z)"},
        {"list.ply",
         ply("ascii", "property list uchar float x\nproperty float y\nproperty float z\n", ascii),
         ":3: the vertex element's property 'x' is a list"},
        // Binary: the header alone decides (these bytes would be 4 vertices of 3 floats).
        {"xy_binary.ply",
         ply("binary_little_endian", "property float x\nproperty float y\nproperty float q\n",
             std::string(4 * 12, '\0') + std::string(4 * 13, '\0')),
         ":3: the vertex element has no property 'z'"},
        {"novertex.ply",
         "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
         "end_header\n3 0 1 2\n",
         ": the PLY header has no 'vertex' element"},
        // An editor's UTF-8 byte order mark: not PLY, and said so.
        {"bom.ply",
         "\xEF\xBB\xBF" +
             ply("ascii", "property float x\nproperty float y\nproperty float z\n", ascii),
         ": not a PLY file: it does not start with 'ply' (it starts with a UTF-8 byte order mark"},
    };
    for (const auto& c : cases)
    {
        const core::Error e = error_of(c.name, c.bytes);
        EXPECT_EQ(e.code, ErrorCode::ParseError) << c.name << ": " << e.message;
        EXPECT_NE(e.message.find(std::string(c.name) + c.says), std::string::npos) << e.message;
    }
    // Any order, other properties among them: fine.
    test::write_bytes(dir_ / "zyx.ply",
                      ply("ascii",
                          "property float nx\nproperty float z\nproperty float y\n"
                          "property float x\n",
                          "9 0 0 0\n9 0 0 1\n9 0 1 0\n9 1 0 0\n3 0 2 1\n3 0 1 3\n3 0 3 2\n"
                          "3 1 2 3\n"));
    EXPECT_TRUE(import_mesh(dir_ / "zyx.ply"));
}

TEST_F(BadFiles, PlyFaceNeedsAVertexIndexList)
{
    const auto ply = [](const std::string& face_property)
    {
        return "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
               "property float z\nelement face 4\n" +
               face_property +
               "\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n"
               "3 1 2 3\n";
    };
    for (const char* property :
         {"property list uchar int corners", "property list uchar int vertex_indexes"})
    {
        const core::Error e = error_of("corners.ply", ply(property));
        EXPECT_EQ(e.code, ErrorCode::ParseError) << property << ": " << e.message;
        EXPECT_NE(e.message.find("corners.ply:7: the face element has no list property "
                                 "'vertex_indices'"),
                  std::string::npos)
            << e.message;
    }
    // A scalar of that name is not a list: the face lines then hold 3 values too many.
    const core::Error scalar = error_of("scalar.ply", ply("property int vertex_indices"));
    EXPECT_EQ(scalar.code, ErrorCode::ParseError) << scalar.message;
    EXPECT_NE(scalar.message.find("scalar.ply:7: the face element has no list property"),
              std::string::npos)
        << scalar.message;
    // Assimp accepts 'vertex_index' as well (its PlyParser's ParseSemantic): the same mesh.
    test::write_bytes(dir_ / "indices.ply", ply("property list uchar int vertex_indices"));
    test::write_bytes(dir_ / "index.ply", ply("property list uchar int vertex_index"));
    const auto indices = import_mesh(dir_ / "indices.ply");
    const auto index = import_mesh(dir_ / "index.ply");
    ASSERT_TRUE(indices) << indices.error().message;
    ASSERT_TRUE(index) << index.error().message;
    EXPECT_EQ(index->faces, indices->faces);
    EXPECT_EQ(index->positions, indices->positions);
}

// Assimp 5.2 does not recognise a .gltf whose JSON does not parse ("No suitable reader found
// for the file format"); the scan parses it first and says where it breaks or ends.
TEST_F(BadFiles, GltfJsonThatDoesNotParseSaysWhere)
{
    const std::string full = test::to_gltf(scenes::octahedron());
    const std::size_t keep = full.find("\"meshes\"") + 10;  // `"meshes":[` and no more
    const core::Error cut = error_of("cut.gltf", full.substr(0, keep));
    EXPECT_EQ(cut.code, ErrorCode::ParseError) << cut.message;
    EXPECT_NE(cut.message.find("cut.gltf: the glTF JSON does not parse at byte " +
                               std::to_string(keep) + " (line 1, column " +
                               std::to_string(keep + 1) + "), where the file ends: "),
              std::string::npos)
        << cut.message;
    EXPECT_NE(cut.message.find("unexpected end of input"), std::string::npos) << cut.message;
    // Broken inside: the place of the bad token, on its line.
    const core::Error comma =
        error_of("comma.gltf", "{\"asset\": {\"version\": \"2.0\"},\n \"meshes\": [1,, 2]}");
    EXPECT_EQ(comma.code, ErrorCode::ParseError) << comma.message;
    EXPECT_NE(comma.message.find("comma.gltf: the glTF JSON does not parse at byte 44 (line 2, "
                                 "column 15): "),
              std::string::npos)
        << comma.message;
    EXPECT_EQ(comma.message.find("where the file ends"), std::string::npos) << comma.message;
    // A byte that is not UTF-8 is quoted as \xNN: the message stays UTF-8 (for --json).
    const core::Error utf = error_of("utf.gltf", "{\"asset\": \"\xFF\"}");
    EXPECT_NE(utf.message.find("at byte 11 (line 1, column 12)"), std::string::npos) << utf.message;
    EXPECT_NE(utf.message.find("\\xFF"), std::string::npos) << utf.message;
    EXPECT_EQ(utf.message.find('\xFF'), std::string::npos) << utf.message;
}

// A .gltf names its buffers by URI, and Assimp opens them itself: a FIFO there hung the reader
// for ever, a device has no end. Each must be a regular file of at least its byteLength.
TEST_F(BadFiles, GltfBufferFilesMustBeRegularFilesOfTheirLength)
{
    ASSERT_TRUE(export_mesh(dir_ / "t.gltf", scenes::tetrahedron()));  // t.gltf and t.bin
    ASSERT_TRUE(import_mesh(dir_ / "t.gltf"));
    const std::string json = test::read_all(dir_ / "t.gltf");
    ASSERT_NE(json.find("\"t.bin\""), std::string::npos);
    const auto naming = [&](const std::string& file)
    {
        std::string j = json;
        j.replace(j.find("\"t.bin\""), 7, "\"" + file + "\"");
        return j;
    };
    const core::Error missing = error_of("missing.gltf", naming("nothere.bin"));
    EXPECT_EQ(missing.code, ErrorCode::IoError);
    EXPECT_NE(missing.message.find("buffer 0's file 'nothere.bin': no such file"),
              std::string::npos)
        << missing.message;
    const auto fifo = dir_ / "fifo.bin";
    std::filesystem::remove(fifo);
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    const core::Error piped = error_of("fifo.gltf", naming("fifo.bin"));  // blocked for ever
    EXPECT_EQ(piped.code, ErrorCode::IoError);
    EXPECT_NE(piped.message.find("buffer 0's file 'fifo.bin': not a regular file"),
              std::string::npos)
        << piped.message;
    EXPECT_EQ(error_of("zero.gltf", naming("/dev/zero")).code, ErrorCode::IoError);
    test::write_bytes(dir_ / "short.bin", "abc");
    const core::Error short_buffer = error_of("short.gltf", naming("short.bin"));
    EXPECT_EQ(short_buffer.code, ErrorCode::ParseError);
    EXPECT_NE(short_buffer.message.find("'short.bin' holds 3 bytes, the glTF declares byteLength"),
              std::string::npos)
        << short_buffer.message;
}

// A GLB's chunks must lie within its declared length: a JSON chunk declaring 4 GiB in a small
// file had Assimp's reader allocate it (4 GB, a minute) before it said "No suitable reader".
TEST_F(BadFiles, GlbChunksMustFitTheFile)
{
    ASSERT_TRUE(export_mesh(dir_ / "ok.glb", scenes::tetrahedron()));
    const std::string glb = test::read_all(dir_ / "ok.glb");
    ASSERT_GT(glb.size(), 20U);
    std::string huge = glb;
    huge[12] = '\xF0';
    huge[13] = huge[14] = huge[15] = '\xFF';  // chunk 0's length: 0xFFFFFFF0
    const core::Error past = error_of("huge.glb", huge);
    EXPECT_EQ(past.code, ErrorCode::ParseError);
    EXPECT_NE(past.message.find("GLB chunk 0 at byte 12 declares 4294967280 bytes, past the " +
                                std::to_string(glb.size()) + " bytes the file declares"),
              std::string::npos)
        << past.message;
    std::string binary_first = glb;
    binary_first.replace(16, 4, std::string("BIN\0", 4));  // chunk 0's type
    EXPECT_NE(error_of("bin.glb", binary_first).message.find("GLB chunk 0 is not JSON"),
              std::string::npos);
    std::string broken = glb;
    broken[20] = '[';  // the JSON's first byte: '{' becomes '['
    EXPECT_NE(error_of("broken.glb", broken).message.find("the glTF JSON does not parse at byte 2"),
              std::string::npos);
}

/// Where element `e` of the first primitive's indices lies in its buffer, and its size in bytes,
/// read from the glTF JSON `json` with nlohmann_json (not with pliant's check).
std::pair<std::size_t, std::size_t> index_slot(const std::string& json, std::size_t e)
{
    const auto doc = nlohmann::json::parse(json);
    const auto& primitive = doc.at("meshes").at(0).at("primitives").at(0);
    const auto& accessor = doc.at("accessors").at(primitive.at("indices").get<std::size_t>());
    const auto& view = doc.at("bufferViews").at(accessor.at("bufferView").get<std::size_t>());
    const int type = accessor.at("componentType").get<int>();
    const std::size_t size = type == 5125 ? 4 : type == 5123 ? 2 : 1;
    return {view.value("byteOffset", std::size_t{0}) +
                accessor.value("byteOffset", std::size_t{0}) + e * view.value("byteStride", size),
            size};
}

/// `text` with its first `from` replaced by `to` (which must be there).
std::string replaced(std::string text, const std::string& from, const std::string& to)
{
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

/// `bytes` with the little-endian integer of `size` bytes at `at` set to `v`.
std::string with_index(std::string bytes, std::pair<std::size_t, std::size_t> slot, std::uint32_t v)
{
    for (std::size_t k = 0; k < slot.second; ++k)
        bytes[slot.first + k] = static_cast<char>((v >> (8 * k)) & 0xFF);
    return bytes;
}

// Assimp 5.2 drops a glTF face with an index past its primitive's POSITION count, saying so only
// to a logger pliant never creates: the octahedron with one such index read as 7 faces and "not a
// closed surface: 3 boundary edges". Every index of the meshes import reads must name a vertex.
TEST_F(BadFiles, GltfIndicesMustNameAVertexOfTheirPrimitive)
{
    TriMesh m = scenes::octahedron();  // 6 vertices; face 3's second corner is element 10
    m.faces[3][1] = 6;
    const core::Error six = error_of("six.gltf", test::to_gltf(m));
    EXPECT_EQ(six.code, ErrorCode::BadIndex) << six.message;
    EXPECT_EQ(six.message, (dir_ / "six.gltf").string() +
                               ": mesh 0 primitive 0: index 6 (element 10, triangle 3) is out of "
                               "range: its POSITION accessor 0 has 6 vertices");
    TriMesh far = scenes::octahedron();
    far.faces[0][0] = 4000000000U;
    const core::Error big = error_of("far.gltf", test::to_gltf(far));
    EXPECT_EQ(big.code, ErrorCode::BadIndex) << big.message;
    EXPECT_NE(big.message.find(": mesh 0 primitive 0: index 4000000000 (element 0, triangle 0)"),
              std::string::npos)
        << big.message;
    // The mesh's name, when it has one; a strip's element.
    const std::string named =
        replaced(test::to_gltf(m), R"("meshes":[{)", R"("meshes":[{"name":"octa\n",)");
    EXPECT_NE(error_of("named.gltf", named).message.find(": mesh 0 ('octa\\x0A') primitive 0: "),
              std::string::npos);
    const std::string strip = replaced(test::to_gltf(m), R"("mode":4)", R"("mode":5)");
    EXPECT_NE(
        error_of("strip.gltf", strip).message.find("index 6 (element 10 of a triangle strip)"),
        std::string::npos);
    // A second mesh whose POSITION accessor (2) has only the first 3 vertices: refused when a node
    // of the scene reaches it (here a child), not when none does (Assimp never reads it).
    std::string two = replaced(
        test::to_gltf(scenes::octahedron()), R"("indices":1,"mode":4}]}])",
        R"("indices":1,"mode":4}]},{"primitives":[{"attributes":{"POSITION":2},"indices":1}]}])");
    two = replaced(
        two, R"("type":"SCALAR"}]})",
        R"("type":"SCALAR"},{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}]})");
    test::write_bytes(dir_ / "unused.gltf", two);
    const auto unused = import_mesh(dir_ / "unused.gltf");
    EXPECT_TRUE(unused) << unused.error().message;
    const core::Error child =
        error_of("child.gltf", replaced(two, R"("nodes":[{"mesh":0}])",
                                        R"("nodes":[{"mesh":0,"children":[1]},{"mesh":1}])"));
    EXPECT_EQ(child.code, ErrorCode::BadIndex) << child.message;
    EXPECT_NE(child.message.find(": mesh 1 primitive 0: index "), std::string::npos)
        << child.message;
    EXPECT_NE(child.message.find(": its POSITION accessor 2 has 3 vertices"), std::string::npos)
        << child.message;
}

// The same where the indices lie in a GLB's BIN chunk or in a .gltf's .bin file, as
// export_mesh writes them (one index patched; its mesh is named 'surface').
TEST_F(BadFiles, GltfIndicesInAGlbOrABinFileMustNameAVertex)
{
    ASSERT_TRUE(export_mesh(dir_ / "ok.glb", scenes::octahedron()));
    const std::string glb = test::read_all(dir_ / "ok.glb");
    ASSERT_GT(glb.size(), 28U);
    std::uint32_t json_length = 0;  // chunk 0's length (little-endian, as the test machines)
    std::memcpy(&json_length, glb.data() + 12, 4);
    auto slot = index_slot(glb.substr(20, json_length), 10);
    slot.first += 20 + json_length + 8;  // the BIN chunk's bytes
    const core::Error in_glb = error_of("bad.glb", with_index(glb, slot, 6));
    EXPECT_EQ(in_glb.code, ErrorCode::BadIndex) << in_glb.message;
    EXPECT_NE(in_glb.message.find(
                  "bad.glb: mesh 0 ('surface') primitive 0: index 6 (element 10, triangle 3) "
                  "is out of range: its POSITION accessor 0 has 6 vertices"),
              std::string::npos)
        << in_glb.message;
    test::write_bytes(dir_ / "good.glb", with_index(glb, slot, 5));
    EXPECT_TRUE(import_mesh(dir_ / "good.glb"));

    ASSERT_TRUE(export_mesh(dir_ / "t.gltf", scenes::octahedron()));  // t.gltf and t.bin
    const std::string json = test::read_all(dir_ / "t.gltf");
    const std::string bin = test::read_all(dir_ / "t.bin");
    test::write_bytes(dir_ / "t.bin", with_index(bin, index_slot(json, 10), 70000));
    const auto in_bin = import_mesh(dir_ / "t.gltf");
    ASSERT_FALSE(in_bin);
    EXPECT_EQ(in_bin.error().code, ErrorCode::BadIndex) << in_bin.error().message;
    EXPECT_NE(in_bin.error().message.find(
                  "t.gltf: mesh 0 ('surface') primitive 0: index 70000 (element 10, "
                  "triangle 3) is out of range"),
              std::string::npos)
        << in_bin.error().message;
}

// UNSIGNED_SHORT and UNSIGNED_BYTE indices: read as such, good ones import as UNSIGNED_INT ones.
TEST_F(BadFiles, GltfShortAndByteIndicesAreChecked)
{
    const TriMesh good = scenes::octahedron();
    TriMesh bad = good;
    bad.faces[7][2] = 200;  // element 23
    test::write_bytes(dir_ / "int.gltf", test::to_gltf(good));
    const auto reference = import_mesh(dir_ / "int.gltf");
    ASSERT_TRUE(reference);
    for (const auto& [bytes, name] : {std::pair{2, "short.gltf"}, std::pair{1, "byte.gltf"}})
    {
        test::write_bytes(dir_ / name, test::to_gltf(good, bytes));
        const auto read = import_mesh(dir_ / name);
        ASSERT_TRUE(read) << read.error().message;
        EXPECT_EQ(read->faces, reference->faces);
        EXPECT_EQ(read->positions, reference->positions);
        const core::Error e = error_of(name, test::to_gltf(bad, bytes));
        EXPECT_EQ(e.code, ErrorCode::BadIndex) << e.message;
        EXPECT_NE(e.message.find(": mesh 0 primitive 0: index 200 (element 23, triangle 7) is out "
                                 "of range: its POSITION accessor 0 has 6 vertices"),
                  std::string::npos)
            << e.message;
    }
}

TEST_F(BadFiles, NonFiniteCoordinatesAreReportedWithTheirFace)
{
    const core::Error nan = error_of("nan.obj",
                                     "v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\n"
                                     "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    EXPECT_EQ(nan.code, ErrorCode::NonFiniteCoordinate) << nan.message;
    EXPECT_NE(nan.message.find("face 0"), std::string::npos) << nan.message;
    TriMesh m = scenes::tetrahedron();
    m.positions[2].z = std::numeric_limits<double>::infinity();
    EXPECT_EQ(error_of("inf.stl", test::to_stl_binary(m)).code, ErrorCode::NonFiniteCoordinate);
    // Finite in the file, beyond float: the message says why it became infinite.
    const core::Error big = error_of("big.obj",
                                     "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nv 0 0 1\n"
                                     "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    EXPECT_EQ(big.code, ErrorCode::NonFiniteCoordinate) << big.message;
    EXPECT_NE(big.message.find("read as 32-bit floats: a coordinate beyond +-3.4e38"),
              std::string::npos)
        << big.message;
}

}  // namespace
}  // namespace pliant::mesh
