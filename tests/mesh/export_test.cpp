// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Export: import -> export -> import is the identity (OBJ, PLY, glTF, GLB), the written files are
// exact (OBJ, PLY) or exact to float (glTF: checked through Assimp's importer and through a
// small GLB reader here, independent of Assimp), and from_grid gives the closed genus-0 surface
// of docs/design.md §1.

#include <pliant/core/progress.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/remesh/sample.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "mesh/mesh_files.h"
#include "shapes.h"
#include "support/test_paths.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

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

/// One coordinate rounded to float. Kept scalar and out of line on purpose: GCC 12 at -O3
/// (-march=native) vectorised the three-coordinate version of this into a pair load that skipped
/// the float conversion of x and y (seen in the object code: only z went through vcvtsd2ss).
[[gnu::noinline]] double round_to_float(double v)
{
    return static_cast<double>(static_cast<float>(v));
}

core::Vec3 float_rounded(const core::Vec3& p)
{
    return {round_to_float(p.x), round_to_float(p.y), round_to_float(p.z)};
}

/// `back` is `original` with float-rounded positions: the same faces in the same order, each
/// corner at the float-rounded original position (vertex numbering may differ: import_mesh
/// numbers vertices in order of first use), the same vertex count, Euler characteristic and
/// genus (mesh::analyze).
void expect_same_surface_to_float(const TriMesh& original, const TriMesh& back)
{
    ASSERT_EQ(back.face_count(), original.face_count());
    const MeshStats a = analyze(original);
    const MeshStats b = analyze(back);
    EXPECT_EQ(b.vertices, a.vertices - a.unreferenced_vertices);
    EXPECT_EQ(b.euler_characteristic, a.euler_characteristic);
    EXPECT_EQ(b.genus, a.genus);
    for (std::size_t i = 0; i < original.face_count(); ++i)
        for (std::size_t k = 0; k < 3; ++k)
            ASSERT_EQ(back.positions[back.faces[i][k]],
                      float_rounded(original.positions[original.faces[i][k]]))
                << "face " << i << " corner " << k;
}

std::uint32_t le32(const std::string& bytes, std::size_t at)
{
    std::uint32_t v = 0;
    for (std::size_t k = 4; k-- > 0;)
        v = (v << 8) | static_cast<unsigned char>(bytes.at(at + k));
    return v;
}

/// A minimal GLB reader (glTF 2.0 spec §4.4: 12-byte header, JSON chunk, BIN chunk), independent
/// of Assimp: the first primitive's POSITION (float VEC3) and indices (uint16 or uint32) as a
/// TriMesh, vertices in the file's order.
TriMesh read_glb(const std::string& bytes)
{
    TriMesh m;
    EXPECT_EQ(bytes.substr(0, 4), "glTF");
    EXPECT_EQ(le32(bytes, 4), 2U);
    EXPECT_EQ(le32(bytes, 8), bytes.size());
    const std::uint32_t json_length = le32(bytes, 12);
    EXPECT_EQ(le32(bytes, 16), 0x4E4F534AU);  // "JSON"
    const auto doc = nlohmann::json::parse(bytes.substr(20, json_length));
    const std::size_t bin = 20 + json_length;
    EXPECT_EQ(le32(bytes, bin + 4), 0x004E4942U);  // "BIN\0"
    const std::size_t body = bin + 8;
    const auto& prim = doc.at("meshes").at(0).at("primitives").at(0);
    EXPECT_EQ(prim.value("mode", 4), 4);  // triangles
    auto data_of = [&](const nlohmann::json& accessor, std::size_t& count)
    {
        const auto& view = doc.at("bufferViews").at(accessor.at("bufferView").get<std::size_t>());
        count = accessor.at("count").get<std::size_t>();
        return body + view.value("byteOffset", std::size_t{0}) +
               accessor.value("byteOffset", std::size_t{0});
    };
    const auto& pos =
        doc.at("accessors").at(prim.at("attributes").at("POSITION").get<std::size_t>());
    EXPECT_EQ(pos.at("componentType").get<int>(), 5126);  // float
    EXPECT_EQ(pos.at("type").get<std::string>(), "VEC3");
    std::size_t n = 0;
    const std::size_t p0 = data_of(pos, n);
    for (std::size_t i = 0; i < n; ++i)
    {
        float xyz[3];
        std::memcpy(xyz, bytes.data() + p0 + 12 * i, 12);
        m.positions.push_back({static_cast<double>(xyz[0]), static_cast<double>(xyz[1]),
                               static_cast<double>(xyz[2])});
    }
    const auto& idx = doc.at("accessors").at(prim.at("indices").get<std::size_t>());
    const int type = idx.at("componentType").get<int>();
    EXPECT_TRUE(type == 5123 || type == 5125) << type;
    std::size_t count = 0;
    const std::size_t i0 = data_of(idx, count);
    EXPECT_EQ(count % 3, 0U);
    std::vector<std::uint32_t> flat(count);
    for (std::size_t i = 0; i < count; ++i)
    {
        if (type == 5125)
            std::memcpy(&flat[i], bytes.data() + i0 + 4 * i, 4);
        else
        {
            std::uint16_t v = 0;
            std::memcpy(&v, bytes.data() + i0 + 2 * i, 2);
            flat[i] = v;
        }
    }
    for (std::size_t i = 0; i + 2 < count; i += 3)
        m.faces.push_back({flat[i], flat[i + 1], flat[i + 2]});
    return m;
}

/// A closed genus-0 grid surface: the level-`level` domain sphere, scaled and shifted so the
/// coordinates are doubles that are not floats.
TriMesh grid_sphere(int level)
{
    auto grid = core::TetraGrid::create(level);
    EXPECT_TRUE(grid);
    core::Vec3Field<double> p = remesh::domain_sphere(*grid);
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < grid->ny(); ++y)
            for (int x = 0; x < grid->nx(); ++x)
                p[static_cast<std::size_t>(c)].at(x, y) =
                    0.37 * p[static_cast<std::size_t>(c)].at(x, y) + 0.1 * (c + 1);
    return from_grid(*grid, p);
}

class RoundTrip : public ::testing::TestWithParam<const char*>
{
};

TEST_P(RoundTrip, ImportExportImportIsTheIdentity)
{
    const auto dir = test::scratch_dir("mesh_round_trip");
    auto first = import_mesh(test::source_dir() / "tests" / "data" / "meshes" / GetParam());
    ASSERT_TRUE(first) << first.error().message;
    for (const char* ext : {".obj", ".ply", ".gltf", ".glb"})
    {
        const auto path = dir / (std::string("out") + ext);
        ASSERT_TRUE(export_mesh(path, *first));
        auto second = import_mesh(path);
        ASSERT_TRUE(second) << second.error().message;
        SCOPED_TRACE(ext);
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
    for (const char* listed : {"x.stl", ".obj", ".ply", ".gltf", ".glb"})
        EXPECT_NE(stl.error().message.find(listed), std::string::npos) << stl.error().message;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.stl"));
    const auto missing = export_mesh(dir / "no" / "such" / "x.obj", scenes::octahedron());
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, core::ErrorCode::IoError);
}

// A .gltf names its buffer in a URI: a name that would need %-escapes (which Assimp's reader
// does not decode) is refused before anything is written; the unreserved characters pass.
TEST(Export, GltfNamesNeedingUriEscapesAreRefused)
{
    const auto dir = test::scratch_dir("mesh_gltf_names");
    for (const char* name : {"my model.gltf", "a#1.gltf", "50%.gltf", "\xc3\xbc.gltf"})
    {
        const auto r = export_mesh(dir / name, scenes::octahedron());
        ASSERT_FALSE(r) << name;
        EXPECT_EQ(r.error().code, core::ErrorCode::InvalidArgument) << name;
        EXPECT_NE(r.error().message.find("%-escape"), std::string::npos) << r.error().message;
        EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
    }
    EXPECT_TRUE(export_mesh(dir / "Ok-name_1.~x.gltf", scenes::octahedron()));
    EXPECT_TRUE(std::filesystem::exists(dir / "Ok-name_1.~x.bin"));
    // Other formats take any name; a .glb holds its buffer.
    EXPECT_TRUE(export_mesh(dir / "my model.glb", scenes::octahedron()));
    EXPECT_TRUE(export_mesh(dir / "my model.obj", scenes::octahedron()));
}

/// Stops at the first report, or never; records the phases and fractions reported.
class StopSink final : public core::ProgressSink
{
public:
    explicit StopSink(bool stop) : stop_(stop) {}
    void update(std::string_view phase, double fraction) noexcept override
    {
        reports.emplace_back(std::string(phase), fraction);
    }
    [[nodiscard]] bool stop_requested() const noexcept override { return stop_; }
    std::vector<std::pair<std::string, double>> reports;

private:
    bool stop_;
};

// Ctrl-C while a big OBJ or PLY is formatted (seconds for millions of faces): an export asked
// to stop writes nothing and says Cancelled; one not asked reports its progress below 1.
TEST(Export, AnExportAskedToStopWritesNothing)
{
    const auto dir = test::scratch_dir("mesh_export_stop");
    const TriMesh m = scenes::icosphere(6);  // 40,962 vertices + 81,920 faces: 2 reports
    for (const char* name : {"s.obj", "s.ply", "s.gltf"})
    {
        StopSink stop(true);
        const auto r = export_mesh(dir / name, m, &stop);
        ASSERT_FALSE(r) << name;
        EXPECT_EQ(r.error().code, core::ErrorCode::Cancelled) << name;
        EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
    }
    for (const char* name : {"s.obj", "s.ply"})
    {
        StopSink go(false);
        ASSERT_TRUE(export_mesh(dir / name, m, &go)) << name;
        ASSERT_EQ(go.reports.size(), 2U) << name;
        for (const auto& [phase, fraction] : go.reports)
        {
            EXPECT_EQ(phase, "export");
            EXPECT_LT(fraction, 1.0);
        }
        const auto back = import_mesh(dir / name);
        ASSERT_TRUE(back) << back.error().message;
        EXPECT_EQ(back->faces.size(), m.faces.size());
    }
}

// A small mesh far from the origin: read as floats, its nearby vertices merge and the topology
// breaks (spot moved by 300,000 reads as edges with more than two faces); the error says why.
TEST(Export, AMeshFarFromTheOriginIsToldAsSuchInTopologyErrors)
{
    const auto dir = test::scratch_dir("mesh_far_topology");
    auto spot = import_mesh(test::source_dir() / "data" / "spot.obj");
    ASSERT_TRUE(spot) << spot.error().message;
    for (core::Vec3& p : spot->positions)
        p = p + core::Vec3{3e5, 0.0, 0.0};
    ASSERT_TRUE(export_mesh(dir / "far.obj", *spot));
    const auto far = import_mesh(dir / "far.obj");
    ASSERT_TRUE(far) << far.error().message;
    const auto verdict = validate(*far, "far.obj");
    ASSERT_FALSE(verdict);
    EXPECT_NE(verdict.error().code, core::ErrorCode::DegenerateFace) << verdict.error().message;
    EXPECT_NE(verdict.error().message.find("far from the origin"), std::string::npos)
        << verdict.error().message;
    EXPECT_NE(verdict.error().message.find("move it near the origin"), std::string::npos);
}

TEST(Export, GltfAndGlbGiveTheFacesBackWithFloatRoundedPositions)
{
    // Double meshes (the icosphere's and dumbbell's coordinates are not floats) through both
    // glTF flavours, read back by Assimp (import_mesh).
    const auto dir = test::scratch_dir("mesh_gltf_shapes");
    for (const TriMesh& m : {scenes::icosphere(3), scenes::dumbbell(), scenes::tetrahedron()})
        for (const char* name : {"s.gltf", "s.glb"})
        {
            SCOPED_TRACE(std::string(name) + ", " + std::to_string(m.vertex_count()) + " vertices");
            ASSERT_TRUE(export_mesh(dir / name, m));
            auto back = import_mesh(dir / name);
            ASSERT_TRUE(back) << back.error().message;
            expect_same_surface_to_float(m, *back);
        }
}

TEST(Export, GridSurfaceThroughGltfAndGlb)
{
    // TetraGrid surfaces, closed genus 0 (χ = 2): level 6 through .gltf, level 8 through .glb
    // (2W^2+2 = 131,074 vertices, more than 16-bit indices hold; 4W^2 = 262,144 faces).
    const auto dir = test::scratch_dir("mesh_gltf_grid");
    for (const auto& [name, level] : {std::pair{"g.gltf", 6}, std::pair{"g.glb", 8}})
    {
        SCOPED_TRACE(name);
        const TriMesh m = grid_sphere(level);
        const std::size_t w = std::size_t{1} << level;
        ASSERT_EQ(m.vertex_count(), 2 * w * w + 2);
        ASSERT_TRUE(export_mesh(dir / name, m));
        auto back = import_mesh(dir / name);
        ASSERT_TRUE(back) << back.error().message;
        expect_same_surface_to_float(m, *back);
        const MeshStats s = analyze(*back);
        EXPECT_EQ(s.faces, 4 * w * w);
        EXPECT_EQ(s.euler_characteristic, 2);
        ASSERT_TRUE(s.genus.has_value());
        EXPECT_EQ(*s.genus, 0);
    }
}

TEST(Export, GlbReadByAnIndependentReader)
{
    // The .glb parsed here (not by Assimp): float positions equal to the float-rounded input in
    // the input's order (the mesh has no duplicate or unused vertex), the same index triples.
    const auto dir = test::scratch_dir("mesh_glb_reader");
    for (const TriMesh& m : {scenes::icosphere(2), grid_sphere(3)})
    {
        ASSERT_TRUE(export_mesh(dir / "r.glb", m));
        const TriMesh back = read_glb(test::read_all(dir / "r.glb"));
        ASSERT_EQ(back.vertex_count(), m.vertex_count());
        for (std::size_t i = 0; i < m.vertex_count(); ++i)
            ASSERT_EQ(back.positions[i], float_rounded(m.positions[i])) << "vertex " << i;
        EXPECT_EQ(back.faces, m.faces);
    }
}

// Assimp's exporter declares two extensions it does not use (validators warn); pliant's files
// declare none, as the surface uses none, and the .glb container stays well formed (the reader
// above parses it).
TEST(Export, GltfAndGlbDeclareNoUnusedExtension)
{
    const auto dir = test::scratch_dir("mesh_gltf_extensions");
    const TriMesh m = scenes::octahedron();
    ASSERT_TRUE(export_mesh(dir / "e.gltf", m));
    ASSERT_TRUE(export_mesh(dir / "e.glb", m));
    EXPECT_EQ(test::read_all(dir / "e.gltf").find("extensions"), std::string::npos);
    const std::string glb = test::read_all(dir / "e.glb");
    EXPECT_EQ(glb.find("extensions"), std::string::npos);
    EXPECT_EQ(read_glb(glb).faces, m.faces);
    auto back = import_mesh(dir / "e.gltf");
    ASSERT_TRUE(back) << back.error().message;
    expect_same_surface_to_float(m, *back);
}

TEST(Export, GltfBufferIsASideFileNamedRelatively)
{
    // s.gltf names its buffer "s.bin" (no folder), so the pair still imports after a move.
    const auto dir = test::scratch_dir("mesh_gltf_side_file");
    std::filesystem::create_directories(dir / "a");
    std::filesystem::create_directories(dir / "b");
    const TriMesh m = scenes::octahedron();
    ASSERT_TRUE(export_mesh(dir / "a" / "s.gltf", m));
    ASSERT_TRUE(std::filesystem::exists(dir / "a" / "s.bin"));
    const std::string json = test::read_all(dir / "a" / "s.gltf");
    EXPECT_NE(json.find("\"s.bin\""), std::string::npos) << json;
    EXPECT_EQ(json.find(dir.string()), std::string::npos) << json;
    for (const char* f : {"s.gltf", "s.bin"})
        std::filesystem::rename(dir / "a" / f, dir / "b" / f);
    auto back = import_mesh(dir / "b" / "s.gltf");
    ASSERT_TRUE(back) << back.error().message;
    expect_same_surface_to_float(m, *back);
    // A .glb is one file.
    ASSERT_TRUE(export_mesh(dir / "a" / "t.glb", m));
    EXPECT_FALSE(std::filesystem::exists(dir / "a" / "t.bin"));
}

TEST(Export, GltfRefusesWhatItCannotWrite)
{
    const auto dir = test::scratch_dir("mesh_gltf_errors");
    const auto empty = export_mesh(dir / "e.glb", TriMesh{});
    ASSERT_FALSE(empty);
    EXPECT_EQ(empty.error().code, core::ErrorCode::EmptyInput);
    TriMesh bad = scenes::tetrahedron();
    bad.faces[2][1] = 17;
    const auto index = export_mesh(dir / "i.gltf", bad);
    ASSERT_FALSE(index);
    EXPECT_EQ(index.error().code, core::ErrorCode::BadIndex);
    TriMesh huge = scenes::tetrahedron();
    huge.positions[1].y = 1e39;  // not a finite float
    const auto overflow = export_mesh(dir / "h.glb", huge);
    ASSERT_FALSE(overflow);
    EXPECT_EQ(overflow.error().code, core::ErrorCode::NonFiniteCoordinate);
    const auto missing = export_mesh(dir / "no" / "such" / "x.glb", scenes::octahedron());
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, core::ErrorCode::IoError);
    EXPECT_NE(missing.error().message.find("x.glb"), std::string::npos);
    EXPECT_FALSE(std::filesystem::exists(dir / "e.glb"));
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
