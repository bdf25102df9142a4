// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Mesh import: bytes -> structural scan -> Assimp -> merge, triangulate, weld -> TriMesh.
//
// Design:
// - Assimp reads the formats, but only `aiProcess_ValidateDataStructure` is requested. Its
//   JoinIdenticalVertices keeps vertices apart that differ in normal or texture coordinate
//   (every UV seam of spot.obj would become a boundary), Triangulate hides how many polygons
//   there were, and PreTransformVertices rewrites positions even for identity transforms. So the
//   node tree is walked here (transforms applied in double, skipped when identity), polygons
//   are fan-split here (v0 v1 ... v(k-1) into the triangles (v0, vi, vi+1), the split that the
//   face counts of tests/data/meshes/README.md assume), and positions are welded here on exact
//   equality (-0 and +0 are equal).
// - Vertices are numbered in order of first use by the faces, faces keep the file's order. That
//   numbering is a function of the face list alone, so two files listing the same triangles in
//   the same order import to the same TriMesh whatever their vertex order or format, and
//   import -> export -> import is the identity.
// - Assimp (ai_real = float in Debian's build) delivers single-precision positions; they are
//   widened exactly to double.
// - Assimp's logger is never created (its default is the null logger): nothing reaches stdout.
// - Floating-point traps a caller enabled are held off while Assimp runs (it computes bounding
//   boxes and normals with whatever the file holds) and restored afterwards.

#include <pliant/mesh/io.h>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "mesh/format_scan_internal.h"
#include "mesh/fp_hold_internal.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iterator>
#include <new>
#include <sstream>
#include <string>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

namespace pliant::mesh
{

namespace
{

using core::ErrorCode;
using core::fail;

using detail::FpHold;

std::string lower(std::string s)
{
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

std::string fmt_point(const core::Vec3& p)
{
    std::array<char, 96> buf{};
    std::snprintf(buf.data(), buf.size(), "(%g, %g, %g)", p.x, p.y, p.z);
    return buf.data();
}

core::Result<std::string> read_bytes(const std::filesystem::path& path, const std::string& name)
{
    if (const auto why = detail::unreadable_file(path))
        return fail(ErrorCode::IoError, name + ": cannot open: " + *why);
    std::ifstream in(path, std::ios::binary);
    if (!in)
        return fail(ErrorCode::IoError, name + ": cannot open for reading");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad())
        return fail(ErrorCode::IoError, name + ": read error");
    return bytes;
}

/// Row-major 4x4 affine transform in double, with a flag for the identity (the common case:
/// applying it is skipped, so positions stay bit-exact).
struct Transform
{
    std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    bool identity = true;

    [[nodiscard]] core::Vec3 apply(const aiVector3D& v) const
    {
        const core::Vec3 p{static_cast<double>(v.x), static_cast<double>(v.y),
                           static_cast<double>(v.z)};
        if (identity)
            return p;
        return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
                m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
    }
};

Transform compose(const Transform& parent, const aiMatrix4x4& local)
{
    const std::array<double, 16> l{local.a1, local.a2, local.a3, local.a4, local.b1, local.b2,
                                   local.b3, local.b4, local.c1, local.c2, local.c3, local.c4,
                                   local.d1, local.d2, local.d3, local.d4};
    const bool local_identity = local.IsIdentity();
    if (local_identity)
        return parent;
    if (parent.identity)
        return Transform{l, false};
    Transform t{{}, false};
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
        {
            double s = 0.0;
            for (int k = 0; k < 4; ++k)
                s += parent.m[static_cast<std::size_t>(r * 4 + k)] *
                     l[static_cast<std::size_t>(k * 4 + c)];
            t.m[static_cast<std::size_t>(r * 4 + c)] = s;
        }
    return t;
}

/// Key for exact welding: the bit patterns of the three coordinates, -0 folded onto +0.
struct PositionKey
{
    std::array<std::uint64_t, 3> bits;
    friend bool operator==(const PositionKey&, const PositionKey&) = default;
};

struct PositionKeyHash
{
    std::size_t operator()(const PositionKey& k) const noexcept
    {
        std::uint64_t h = 0x9E3779B97F4A7C15ULL;
        for (const std::uint64_t b : k.bits)
        {
            h ^= b + 0x9E3779B97F4A7C15ULL + (h << 6) + (h >> 2);
            h *= 0xFF51AFD7ED558CCDULL;
        }
        return static_cast<std::size_t>(h ^ (h >> 33));
    }
};

PositionKey key_of(const core::Vec3& p)
{
    return {{std::bit_cast<std::uint64_t>(p.x + 0.0), std::bit_cast<std::uint64_t>(p.y + 0.0),
             std::bit_cast<std::uint64_t>(p.z + 0.0)}};
}

/// Converts Assimp's scene into a welded TriMesh (see the design comment above).
core::Result<TriMesh> convert(const aiScene& scene, const std::string& name, ImportReport& rep)
{
    TriMesh out;
    std::unordered_map<PositionKey, std::uint32_t, PositionKeyHash> index_of;
    std::size_t referenced_reader_vertices = 0;
    std::size_t polygon = 0;  // file order, for messages

    // Explicit stack (no recursion on file-controlled depth) and a visit cap (no loops).
    constexpr std::size_t k_max_visits = std::size_t{1} << 20;
    std::vector<std::pair<const aiNode*, Transform>> stack;
    if (scene.mRootNode != nullptr)
        stack.emplace_back(scene.mRootNode, Transform{});
    std::size_t visits = 0;
    std::vector<std::uint32_t> local;  // reader vertex -> output vertex, per mesh instance
    while (!stack.empty())
    {
        if (++visits > k_max_visits)
            return fail(ErrorCode::ParseError, name + ": scene graph has more than " +
                                                   std::to_string(k_max_visits) +
                                                   " nodes (or a cycle)");
        const auto [node, parent] = stack.back();
        stack.pop_back();
        const Transform t = compose(parent, node->mTransformation);
        for (unsigned c = node->mNumChildren; c-- > 0;)
        {
            if (node->mChildren != nullptr && node->mChildren[c] != nullptr)
                stack.emplace_back(node->mChildren[c], t);
        }
        for (unsigned mi = 0; mi < node->mNumMeshes; ++mi)
        {
            const unsigned mesh_index = node->mMeshes[mi];
            if (mesh_index >= scene.mNumMeshes || scene.mMeshes[mesh_index] == nullptr)
                return fail(ErrorCode::ParseError, name + ": scene node refers to mesh " +
                                                       std::to_string(mesh_index) + " of " +
                                                       std::to_string(scene.mNumMeshes));
            const aiMesh& mesh = *scene.mMeshes[mesh_index];
            ++rep.meshes;
            rep.raw_vertices += mesh.mNumVertices;
            local.assign(mesh.mNumVertices, UINT32_MAX);
            for (unsigned fi = 0; fi < mesh.mNumFaces; ++fi, ++polygon)
            {
                const aiFace& face = mesh.mFaces[fi];
                if (face.mNumIndices < 3 || face.mIndices == nullptr)
                {
                    ++rep.non_triangles_dropped;
                    continue;
                }
                ++rep.raw_faces;
                if (face.mNumIndices > 3)
                    ++rep.polygons_triangulated;
                for (unsigned k = 0; k < face.mNumIndices; ++k)
                {
                    const unsigned v = face.mIndices[k];
                    if (v >= mesh.mNumVertices || mesh.mVertices == nullptr)
                        return fail(ErrorCode::ParseError,
                                    name + ": face " + std::to_string(polygon) +
                                        " refers to vertex " + std::to_string(v) + " of " +
                                        std::to_string(mesh.mNumVertices));
                    if (local[v] != UINT32_MAX)
                        continue;
                    const core::Vec3 p = t.apply(mesh.mVertices[v]);
                    if (!core::is_finite(p))
                        return fail(ErrorCode::NonFiniteCoordinate,
                                    name + ": non-finite coordinate " + fmt_point(p) +
                                        " at corner " + std::to_string(k) + " of face " +
                                        std::to_string(polygon) +
                                        (std::isinf(p.x) || std::isinf(p.y) || std::isinf(p.z)
                                             ? " (positions are read as 32-bit floats: a "
                                               "coordinate beyond +-3.4e38 in the file becomes "
                                               "infinite)"
                                             : ""));
                    ++referenced_reader_vertices;
                    const auto [it, inserted] = index_of.try_emplace(
                        key_of(p), static_cast<std::uint32_t>(out.positions.size()));
                    if (inserted)
                    {
                        if (out.positions.size() >= UINT32_MAX)
                            return fail(ErrorCode::ParseError, name + ": too many vertices");
                        out.positions.push_back(p);
                    }
                    local[v] = it->second;
                }
                // Fan split (0, i, i+1): the face counts of tests/data/meshes/README.md assume it.
                for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)
                    out.faces.push_back({local[face.mIndices[0]], local[face.mIndices[k]],
                                         local[face.mIndices[k + 1]]});
            }
        }
    }
    rep.welded = referenced_reader_vertices - out.positions.size();
    rep.unreferenced_dropped = rep.raw_vertices - referenced_reader_vertices;
    return out;
}

}  // namespace

core::Result<TriMesh> import_mesh(const std::filesystem::path& path, ImportReport* report)
{
    const std::string name = path.string();
    const std::string ext = lower(path.extension().string());
    ImportReport rep;

    auto bytes = read_bytes(path, name);
    if (!bytes)
        return bytes.error();
    auto scan = detail::scan_format(*bytes, ext, name);
    if (!scan)
        return scan.error();
    if (scan->format == detail::Format::Gltf || scan->format == detail::Format::Glb)
    {
        if (auto ok = detail::check_gltf_buffers(
                std::string_view(*bytes).substr(scan->json_offset, scan->json_size),
                path.parent_path(), name);
            !ok)
            return ok.error();
        if (auto ok = detail::check_gltf_indices(*bytes, *scan, path.parent_path(), name); !ok)
            return ok.error();  // Assimp drops a face with such an index, saying nothing
    }
    rep.format = std::string(detail::format_name(scan->format));
    rep.file_vertices = scan->vertices;

    FpHold hold;
    Assimp::Importer importer;
    const aiScene* scene = nullptr;
    try
    {
        // The scan's copy of the file, when it made one, has the same format as the file.
        scene = scan->rewritten.empty() ? importer.ReadFile(name, aiProcess_ValidateDataStructure)
                                        : importer.ReadFileFromMemory(
                                              scan->rewritten.data(), scan->rewritten.size(),
                                              aiProcess_ValidateDataStructure,
                                              scan->format == detail::Format::Obj        ? "obj"
                                              : scan->format == detail::Format::StlAscii ? "stl"
                                                                                         : "off");
    }
    catch (const std::bad_alloc&)
    {
        throw;  // out of memory, as anywhere else: not a fault of the file
    }
    catch (const std::exception& e)
    {
        return fail(ErrorCode::ParseError, name + ": cannot parse: " + e.what());
    }
    if (scene == nullptr)
    {
        // Assimp catches what its reader throws and keeps it: running out of memory was
        // reported as "cannot parse obj: std::bad_alloc", blaming the file.
        if (const std::exception_ptr& thrown = importer.GetException(); thrown)
        {
            try
            {
                std::rethrow_exception(thrown);
            }
            catch (const std::bad_alloc&)
            {
                throw;
            }
            catch (...)  // any other: the reader's error text below says what it was
            {
            }
        }
        std::string why = importer.GetErrorString();
        if (why.empty())
            why = "the reader gave no scene";
        return fail(ErrorCode::ParseError, name + ": cannot parse " + rep.format + ": " + why);
    }

    auto mesh = convert(*scene, name, rep);
    if (!mesh)
        return mesh.error();
    if (mesh->faces.empty())
        return fail(ErrorCode::EmptyInput, name + ": no faces: the file holds " +
                                               std::to_string(rep.meshes) + " meshes with " +
                                               std::to_string(rep.raw_vertices) + " vertices and " +
                                               std::to_string(rep.non_triangles_dropped) +
                                               " points or lines, but no polygon");
    if (scan->format == detail::Format::Obj)
        rep.unreferenced_dropped += scan->unreferenced;
    if (rep.file_vertices == 0)
        rep.file_vertices = rep.raw_vertices;
    rep.vertices = mesh->vertex_count();
    rep.faces = mesh->face_count();
    if (report != nullptr)
        *report = std::move(rep);
    return mesh;
}

}  // namespace pliant::mesh
