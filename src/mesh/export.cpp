// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Mesh export and the geometry-image -> TriMesh conversion.
//
// - OBJ: ascii, `v x y z` with 17 significant digits (enough to round-trip any double), 1-based
//   `f a b c`. Vertex and face order are kept. Our own writer: we control precision and order.
// - PLY: binary little-endian, `double` x y z and a `uchar`/`uint` index list: lossless for any
//   TriMesh (float would round), 8 bytes per coordinate. Our own writer too. Assimp reads both
//   back exactly for coordinates that are floats (everything `import_mesh` produced); see
//   docs/mesh.md.
// - glTF 2.0 (`.gltf`, `.glb`): through Assimp's exporter (format ids "gltf2" / "glb2"), since
//   the format (JSON + binary buffers, accessors, materials) is not worth a second writer. An
//   aiScene is built here: one node, one mesh, one plain grey material (Assimp's glTF 2 exporter
//   expects one per mesh), positions as float (glTF stores float32, so the round trip is exact
//   only to float) and area-weighted unit vertex normals (viewers shade smoothly; import_mesh
//   ignores them). Assimp always runs JoinIdenticalVertices before this exporter: vertices whose
//   float positions (and normals) agree within a few float ulps are merged and unused vertices
//   dropped; order is otherwise kept. The export goes to memory (ExportToBlob, with the blob
//   name set to the file's stem) and the files are written here: `.glb` is one file; `.gltf`
//   is the JSON plus its buffer in a side file `<stem>.bin` next to it, referenced by that
//   relative name (Assimp cannot embed a data URI, and writing through Assimp's file system
//   would put the absolute path into the URI).

#include <pliant/core/file_io.h>
#include <pliant/core/progress.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/io.h>

#include <assimp/Exporter.hpp>
#include <assimp/cexport.h>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <nlohmann/json.hpp>

#include "mesh/fp_hold_internal.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
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

/// Reports the phase "export" to `progress` (optional) every 65,536 elements of `total`, and
/// says whether it asked to stop.
class ExportPace
{
public:
    ExportPace(core::ProgressSink* progress, std::size_t total) : progress_(progress), total_(total)
    {
    }
    /// \return false when the work should stop.
    [[nodiscard]] bool at(std::size_t done) const
    {
        if (progress_ == nullptr || (done & 0xFFFFU) != 0)
            return true;
        progress_->update("export", static_cast<double>(done) / static_cast<double>(total_));
        return !progress_->stop_requested();
    }

private:
    core::ProgressSink* progress_;
    std::size_t total_;
};

/// The OBJ text; std::nullopt when `progress` asked to stop.
std::optional<std::vector<char>> obj_bytes(const TriMesh& mesh, core::ProgressSink* progress)
{
    const ExportPace pace(progress, mesh.positions.size() + mesh.faces.size());
    std::vector<char> out;
    out.reserve(mesh.positions.size() * 64 + mesh.faces.size() * 24 + 64);
    const std::string head = "# pliant: " + std::to_string(mesh.positions.size()) + " vertices, " +
                             std::to_string(mesh.faces.size()) + " faces\n";
    out.insert(out.end(), head.begin(), head.end());
    std::array<char, 128> line{};
    std::size_t done = 0;
    for (const core::Vec3& p : mesh.positions)
    {
        if (!pace.at(done++))
            return std::nullopt;
        const int n =
            std::snprintf(line.data(), line.size(), "v %.17g %.17g %.17g\n", p.x, p.y, p.z);
        out.insert(out.end(), line.data(), line.data() + n);
    }
    for (const Face& f : mesh.faces)
    {
        if (!pace.at(done++))
            return std::nullopt;
        const int n =
            std::snprintf(line.data(), line.size(), "f %u %u %u\n", f[0] + 1, f[1] + 1, f[2] + 1);
        out.insert(out.end(), line.data(), line.data() + n);
    }
    return out;
}

/// The binary PLY; std::nullopt when `progress` asked to stop.
std::optional<std::vector<char>> ply_bytes(const TriMesh& mesh, core::ProgressSink* progress)
{
    const ExportPace pace(progress, mesh.positions.size() + mesh.faces.size());
    const std::string head =
        "ply\nformat binary_little_endian 1.0\ncomment pliant\nelement vertex " +
        std::to_string(mesh.positions.size()) +
        "\nproperty double x\nproperty double y\nproperty double z\n"
        "element face " +
        std::to_string(mesh.faces.size()) +
        "\nproperty list uchar uint vertex_indices\nend_header\n";
    std::vector<char> out(head.begin(), head.end());
    out.reserve(head.size() + mesh.positions.size() * 24 + mesh.faces.size() * 13);
    std::size_t done = 0;
    for (const core::Vec3& p : mesh.positions)
    {
        if (!pace.at(done++))
            return std::nullopt;
        put_le(out, p.x);
        put_le(out, p.y);
        put_le(out, p.z);
    }
    for (const Face& f : mesh.faces)
    {
        if (!pace.at(done++))
            return std::nullopt;
        put_le(out, std::uint8_t{3});
        for (const std::uint32_t v : f)
            put_le(out, v);
    }
    return out;
}

using detail::FpHold;

std::span<const std::byte> bytes_of(std::string_view text)
{
    return std::as_bytes(std::span<const char>(text.data(), text.size()));
}

/// Every vertex coordinate finite: a file with nan or inf in it is one no reader takes back
/// (pliant's own import refuses it).
core::Result<void> check_finite(const std::filesystem::path& path, const TriMesh& mesh)
{
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    {
        const core::Vec3& p = mesh.positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return fail(ErrorCode::NonFiniteCoordinate,
                        path.string() + ": vertex " + std::to_string(i) +
                            " has a coordinate that is not finite; nothing written");
    }
    return {};
}

/// Area-weighted vertex normals (the sum of the unnormalised face normals), unit length; a vertex
/// with no face or only degenerate ones gets +z (glTF requires unit normals).
std::vector<core::Vec3> vertex_normals(const TriMesh& mesh)
{
    std::vector<core::Vec3> n(mesh.positions.size(), core::Vec3{0.0, 0.0, 0.0});
    for (const Face& f : mesh.faces)
    {
        const core::Vec3& a = mesh.positions[f[0]];
        const core::Vec3 c = core::cross(mesh.positions[f[1]] - a, mesh.positions[f[2]] - a);
        for (const std::uint32_t v : f)
            n[v] += c;
    }
    for (core::Vec3& v : n)
    {
        const double len = core::norm(v);
        v = len > 0.0 && std::isfinite(len) ? v * (1.0 / len) : core::Vec3{0.0, 0.0, 1.0};
    }
    return n;
}

aiVector3D to_float(const core::Vec3& p)
{
    return {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
}

/// The aiScene Assimp's glTF 2 exporter gets: root node -> mesh 0 -> material 0.
/// \pre every face index < vertex count.
std::unique_ptr<aiScene> make_scene(const TriMesh& mesh)
{
    auto scene = std::make_unique<aiScene>();
    scene->mRootNode = new aiNode("pliant");
    scene->mRootNode->mNumMeshes = 1;
    scene->mRootNode->mMeshes = new unsigned[1]{0};

    auto* material = new aiMaterial();
    const aiString material_name("pliant-surface");
    material->AddProperty(&material_name, AI_MATKEY_NAME);
    const aiColor4D grey(0.8F, 0.8F, 0.8F, 1.0F);
    material->AddProperty(&grey, 1, AI_MATKEY_COLOR_DIFFUSE);
    scene->mNumMaterials = 1;
    scene->mMaterials = new aiMaterial* [1] { material };

    auto* m = new aiMesh();
    scene->mNumMeshes = 1;
    scene->mMeshes = new aiMesh* [1] { m };
    m->mName = aiString("surface");
    m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    m->mMaterialIndex = 0;
    const std::vector<core::Vec3> normals = vertex_normals(mesh);
    m->mNumVertices = static_cast<unsigned>(mesh.positions.size());
    m->mVertices = new aiVector3D[mesh.positions.size()];
    m->mNormals = new aiVector3D[mesh.positions.size()];
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    {
        m->mVertices[i] = to_float(mesh.positions[i]);
        m->mNormals[i] = to_float(normals[i]);
    }
    m->mNumFaces = static_cast<unsigned>(mesh.faces.size());
    m->mFaces = new aiFace[mesh.faces.size()];
    for (std::size_t i = 0; i < mesh.faces.size(); ++i)
    {
        aiFace& face = m->mFaces[i];
        face.mNumIndices = 3;
        face.mIndices = new unsigned[3]{mesh.faces[i][0], mesh.faces[i][1], mesh.faces[i][2]};
    }
    return scene;
}

/// Checks what Assimp would otherwise read out of bounds or write as garbage.
core::Result<void> check_for_gltf(const std::filesystem::path& path, const TriMesh& mesh)
{
    const std::string name = path.string();
    if (mesh.faces.empty())
        return fail(ErrorCode::EmptyInput, name + ": no faces to write");
    if (mesh.positions.size() > std::numeric_limits<std::uint32_t>::max() / 2 ||
        mesh.faces.size() > std::numeric_limits<std::uint32_t>::max() / 4)
        return fail(ErrorCode::InvalidArgument, name + ": too large for glTF through Assimp");
    for (std::size_t i = 0; i < mesh.faces.size(); ++i)
        for (const std::uint32_t v : mesh.faces[i])
            if (v >= mesh.positions.size())
                return fail(ErrorCode::BadIndex, name + ": face " + std::to_string(i) +
                                                     " refers to vertex " + std::to_string(v) +
                                                     " but there are " +
                                                     std::to_string(mesh.positions.size()));
    constexpr double k_float_max = static_cast<double>(std::numeric_limits<float>::max());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    {
        const core::Vec3& p = mesh.positions[i];
        for (const double c : {p.x, p.y, p.z})
            if (!(std::abs(c) <= k_float_max))
                return fail(ErrorCode::NonFiniteCoordinate,
                            name + ": vertex " + std::to_string(i) +
                                " has a coordinate that is not a finite float (glTF stores "
                                "float32)");
    }
    return {};
}

/// Assimp 5.2's glTF exporter lists KHR_materials_volume and FB_ngon_encoding in
/// `extensionsUsed` whatever the scene uses, which validators flag. Drops the names that appear
/// nowhere else in the document (and the list when none is left). \return the JSON text.
std::string without_unused_extensions(std::string_view json_text, int indent)
{
    nlohmann::ordered_json doc = nlohmann::ordered_json::parse(json_text);
    auto used = doc.find("extensionsUsed");
    if (used == doc.end() || !used->is_array())
        return std::string(json_text);
    nlohmann::ordered_json rest = doc;
    rest.erase("extensionsUsed");
    const std::string others = rest.dump();
    nlohmann::ordered_json kept = nlohmann::ordered_json::array();
    for (const auto& name : *used)
        if (name.is_string() &&
            others.find('"' + name.get<std::string>() + '"') != std::string::npos)
            kept.push_back(name);
    if (kept.empty())
        doc.erase("extensionsUsed");
    else
        *used = kept;
    return doc.dump(indent);
}

/// The .glb container (glTF 2.0 §4.4) with its JSON chunk replaced by `json_text` (padded with
/// spaces to 4 bytes), the binary chunk kept. Empty if `glb` is not a well-formed container.
std::string with_json_chunk(std::string_view glb, std::string json_text)
{
    const auto u32 = [&](std::size_t at)
    {
        std::uint32_t v = 0;
        std::memcpy(&v, glb.data() + at, 4);
        return v;
    };
    if (glb.size() < 20 || glb.substr(0, 4) != "glTF" || u32(16) != 0x4E4F534Au)  // "JSON"
        return {};
    const std::size_t json_end = 20 + std::size_t{u32(12)};
    if (json_end > glb.size())
        return {};
    while (json_text.size() % 4 != 0)
        json_text.push_back(' ');
    std::string out(glb.substr(0, 12));
    const auto put = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    put(static_cast<std::uint32_t>(json_text.size()));
    put(0x4E4F534Au);
    out += json_text;
    out += glb.substr(json_end);  // the BIN chunk, unchanged
    const auto total = static_cast<std::uint32_t>(out.size());
    std::memcpy(out.data() + 8, &total, 4);
    return out;
}

core::Result<void> write_gltf(const std::filesystem::path& path, const TriMesh& mesh, bool binary)
{
    if (auto ok = check_export_name(path); !ok)
        return ok;
    if (auto ok = check_for_gltf(path, mesh); !ok)
        return ok;
    const std::string name = path.string();
    // The blob name is the stem: the exporter names the .gltf's buffer "<stem>.bin" after it.
    const std::string stem = path.stem().string();
    const std::unique_ptr<aiScene> scene = make_scene(mesh);
    FpHold hold;
    Assimp::Exporter exporter;
    Assimp::ExportProperties properties;
    properties.SetPropertyString(AI_CONFIG_EXPORT_BLOB_NAME, stem);
    const aiExportDataBlob* blob = nullptr;
    try
    {
        blob = exporter.ExportToBlob(scene.get(), binary ? "glb2" : "gltf2", 0U, &properties);
    }
    catch (const std::exception& e)
    {
        return fail(ErrorCode::IoError, name + ": Assimp's glTF exporter failed: " + e.what());
    }
    if (blob == nullptr)
    {
        std::string why = exporter.GetErrorString();
        if (why.empty())
            why = "no output and no message";
        return fail(ErrorCode::IoError, name + ": Assimp's glTF exporter failed: " + why);
    }
    // The side files (the buffer) and the .gltf are written together, all or none, so that a
    // .gltf never names a missing or mismatched buffer.
    std::vector<core::FileContent> files;
    for (const aiExportDataBlob* side = blob->next; side != nullptr; side = side->next)
    {
        const std::filesystem::path side_name(side->name.C_Str());
        if (side_name.empty() || side_name.has_parent_path() || side_name == path.filename())
            return fail(ErrorCode::IoError,
                        name + ": Assimp's glTF exporter produced an unexpected side file '" +
                            side_name.string() + "'");
        files.push_back(
            {path.parent_path() / side_name,
             std::span<const std::byte>(static_cast<const std::byte*>(side->data), side->size)});
    }
    const std::string_view written(static_cast<const char*>(blob->data), blob->size);
    std::string cleaned;
    try
    {
        if (binary)
        {
            std::uint32_t json_size = 0;
            if (written.size() >= 20)
                std::memcpy(&json_size, written.data() + 12, 4);
            if (written.size() >= 20 + std::size_t{json_size})
                cleaned = with_json_chunk(
                    written, without_unused_extensions(written.substr(20, json_size), -1));
        }
        else
            cleaned = without_unused_extensions(written, 4);
    }
    catch (const nlohmann::json::exception& e)
    {
        return fail(ErrorCode::IoError,
                    name + ": Assimp's glTF exporter wrote JSON that does not parse: " + e.what());
    }
    if (cleaned.empty())
        return fail(ErrorCode::IoError, name + ": Assimp's glTF exporter wrote a malformed .glb");
    files.push_back({path, bytes_of(cleaned)});
    return core::write_files(files, "");
}

}  // namespace

core::Result<void> check_export_name(const std::filesystem::path& path)
{
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext != ".gltf")
        return {};
    const std::string stem = path.stem().string();
    for (const char c : stem)
    {
        const auto u = static_cast<unsigned char>(c);
        if (std::isalnum(u) != 0 && u < 0x80)
            continue;
        if (c == '-' || c == '.' || c == '_' || c == '~')
            continue;
        const std::string shown = u < 0x80 && std::isprint(u) != 0
                                      ? "'" + std::string(1, c) + "'"
                                      : std::string("a non-ASCII character");
        return fail(ErrorCode::InvalidArgument,
                    path.string() + ": the .gltf names its buffer " + stem +
                        ".bin in a URI, where " + shown +
                        " would need a %-escape that Assimp's reader (and pliant's) does not "
                        "decode; use letters, digits, '-', '_', '.' and '~' in the name, or "
                        "write a self-contained .glb");
    }
    return {};
}

core::Result<void> export_mesh(const std::filesystem::path& path, const TriMesh& mesh,
                               core::ProgressSink* progress)
{
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext != ".obj" && ext != ".ply" && ext != ".gltf" && ext != ".glb")
        return fail(ErrorCode::UnsupportedFormat,
                    path.string() + ": unsupported format '" + ext +
                        "' (pliant writes .obj, .ply, .gltf and .glb)");
    const auto stopped = [&] { return progress != nullptr && progress->stop_requested(); };
    if (stopped())
        return core::cancelled("export " + path.string(), "export");
    if (ext == ".gltf" || ext == ".glb")
        return write_gltf(path, mesh, ext == ".glb");  // Assimp's: not stopped part-way
    if (auto ok = check_finite(path, mesh); !ok)
        return ok;
    const std::optional<std::vector<char>> bytes =
        ext == ".obj" ? obj_bytes(mesh, progress) : ply_bytes(mesh, progress);
    if (!bytes)
        return core::cancelled("export " + path.string(), "export");
    return core::write_file(path, bytes_of(std::string_view(bytes->data(), bytes->size())), "");
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
