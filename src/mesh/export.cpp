// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Mesh export (our own writers, not Assimp's exporter: we control precision and order) and the
// geometry-image -> TriMesh conversion.
//
// - OBJ: ascii, `v x y z` with 17 significant digits (enough to round-trip any double), 1-based
//   `f a b c`. Vertex and face order are kept.
// - PLY: binary little-endian, `double` x y z and a `uchar`/`uint` index list: lossless for any
//   TriMesh (float would round), 8 bytes per coordinate. Assimp reads both back exactly for
//   coordinates that are floats (everything `import_mesh` produced); see docs/mesh.md.

#include <pliant/mesh/io.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace pliant::mesh
{

namespace
{

using core::ErrorCode;
using core::fail;

template <typename T>
void put_le(std::vector<char>& out, T value)
{
    static_assert(std::endian::native == std::endian::little ||
                  std::endian::native == std::endian::big);
    std::array<char, sizeof(T)> b{};
    std::memcpy(b.data(), &value, sizeof(T));
    if constexpr (std::endian::native == std::endian::big)
        std::reverse(b.begin(), b.end());
    out.insert(out.end(), b.begin(), b.end());
}

std::vector<char> obj_bytes(const TriMesh& mesh)
{
    std::vector<char> out;
    out.reserve(mesh.positions.size() * 64 + mesh.faces.size() * 24 + 64);
    const std::string head = "# pliant: " + std::to_string(mesh.positions.size()) + " vertices, " +
                             std::to_string(mesh.faces.size()) + " faces\n";
    out.insert(out.end(), head.begin(), head.end());
    std::array<char, 128> line{};
    for (const core::Vec3& p : mesh.positions)
    {
        const int n =
            std::snprintf(line.data(), line.size(), "v %.17g %.17g %.17g\n", p.x, p.y, p.z);
        out.insert(out.end(), line.data(), line.data() + n);
    }
    for (const Face& f : mesh.faces)
    {
        const int n =
            std::snprintf(line.data(), line.size(), "f %u %u %u\n", f[0] + 1, f[1] + 1, f[2] + 1);
        out.insert(out.end(), line.data(), line.data() + n);
    }
    return out;
}

std::vector<char> ply_bytes(const TriMesh& mesh)
{
    const std::string head =
        "ply\nformat binary_little_endian 1.0\ncomment pliant\nelement vertex " +
        std::to_string(mesh.positions.size()) +
        "\nproperty double x\nproperty double y\nproperty double z\n"
        "element face " +
        std::to_string(mesh.faces.size()) +
        "\nproperty list uchar uint vertex_indices\nend_header\n";
    std::vector<char> out(head.begin(), head.end());
    out.reserve(head.size() + mesh.positions.size() * 24 + mesh.faces.size() * 13);
    for (const core::Vec3& p : mesh.positions)
    {
        put_le(out, p.x);
        put_le(out, p.y);
        put_le(out, p.z);
    }
    for (const Face& f : mesh.faces)
    {
        put_le(out, std::uint8_t{3});
        for (const std::uint32_t v : f)
            put_le(out, v);
    }
    return out;
}

}  // namespace

core::Result<void> export_mesh(const std::filesystem::path& path, const TriMesh& mesh)
{
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    std::vector<char> bytes;
    if (ext == ".obj")
        bytes = obj_bytes(mesh);
    else if (ext == ".ply")
        bytes = ply_bytes(mesh);
    else
        return fail(ErrorCode::UnsupportedFormat, "export_mesh: " + path.string() +
                                                      ": unsupported format '" + ext +
                                                      "' (pliant writes .obj and .ply)");
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out)
        return fail(ErrorCode::IoError,
                    "export_mesh: " + path.string() + ": cannot open for writing");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out)
        return fail(ErrorCode::IoError, "export_mesh: " + path.string() + ": write failed");
    return {};
}

TriMesh from_grid(const core::TetraGrid& grid, const core::Vec3Field<double>& positions)
{
    PLIANT_ASSERT(positions[0].level() == grid.level(), "from_grid: field level differs from grid");
    TriMesh mesh;
    const auto nodes = grid.node_of_unique();
    mesh.positions.reserve(nodes.size());
    for (const core::NodeIndex n : nodes)
        mesh.positions.push_back({positions[0][n], positions[1][n], positions[2][n]});
    mesh.faces = grid.triangles();
    return mesh;
}

}  // namespace pliant::mesh
