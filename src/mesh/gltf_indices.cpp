// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// The indices of a glTF 2.0 file against the vertex counts of their primitives, before Assimp
// reads it (format_scan_internal.h, check_gltf_indices).
//
// Assimp 5.2's glTF reader drops a face with an index past its primitive's POSITION count and
// says so only to its logger, which import never creates: the hole then read as "not a closed
// surface". So the indices are read here the way Assimp reads them (buffer 0 of a GLB is its BIN
// chunk, an accessor's element i lies at the view's byteOffset + the accessor's byteOffset +
// i * (byteStride, or the element's size when there is none)), in the meshes Assimp puts under
// the root it returns. This check must never refuse a file Assimp reads correctly: whatever is not
// as expected leaves the primitive unchecked, to Assimp as before.

#include <nlohmann/json.hpp>
#include <sodium.h>

#include "mesh/format_scan_internal.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::mesh::detail
{

namespace
{

using core::ErrorCode;
using core::fail;
using Json = nlohmann::json;

std::string plural(std::uint64_t n, const char* word)
{
    if (std::string_view(word) == "vertex")
        return std::to_string(n) + (n == 1 ? " vertex" : " vertices");
    return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

/// `object[key]`, or nullptr when it is absent or `object` is not an object. (Pointers, not
/// iterators: comparing iterators of two JSON values throws.)
const Json* field(const Json& object, const char* key)
{
    if (!object.is_object())
        return nullptr;
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
}

/// `object[key]` when it is an unsigned integer; nothing when it is absent, of another type
/// (a float such as 6.0 too: Assimp takes only integers) or `object` is not an object.
std::optional<std::uint64_t> uint_field(const Json& object, const char* key)
{
    const Json* value = field(object, key);
    if (value == nullptr || !value->is_number_unsigned())
        return std::nullopt;
    return value->get<std::uint64_t>();
}

/// `object[key]` when it is a string, else nullptr.
const std::string* string_field(const Json& object, const char* key)
{
    const Json* value = field(object, key);
    return value != nullptr && value->is_string() ? &value->get_ref<const std::string&>() : nullptr;
}

/// As uint_field, with `fallback` when `key` is absent (glTF's default).
std::optional<std::uint64_t> uint_field_or(const Json& object, const char* key,
                                           std::uint64_t fallback)
{
    if (object.is_object() && field(object, key) == nullptr)
        return fallback;
    return uint_field(object, key);
}

/// Element `index` of the top-level array `key` of `doc` when it is an object, else nullptr.
const Json* item(const Json& doc, const char* key, std::uint64_t index)
{
    const Json* array = field(doc, key);
    if (array == nullptr || !array->is_array() || index >= array->size())
        return nullptr;
    const Json& e = (*array)[static_cast<std::size_t>(index)];
    return e.is_object() ? &e : nullptr;
}

/// The unsigned integers of the array `object[key]` (other entries are skipped, as Assimp does).
std::vector<std::uint64_t> uint_list(const Json& object, const char* key)
{
    std::vector<std::uint64_t> out;
    const Json* array = field(object, key);
    if (array != nullptr && array->is_array())
        for (const Json& v : *array)
            if (v.is_number_unsigned())
                out.push_back(v.get<std::uint64_t>());
    return out;
}

/// The meshes Assimp 5.2 puts under the root node it returns, which import walks: those of the
/// nodes that the default scene ("scene", else 0) reaches through `children`. Assimp reads no
/// other mesh (it reads objects as they are referred to), or none that import uses.
std::set<std::uint64_t> reached_meshes(const Json& doc)
{
    std::set<std::uint64_t> meshes;
    const auto scene_index = uint_field_or(doc, "scene", 0);
    const Json* scene = scene_index ? item(doc, "scenes", *scene_index) : nullptr;
    if (scene == nullptr)
        return meshes;
    std::vector<std::uint64_t> stack = uint_list(*scene, "nodes");
    std::set<std::uint64_t> seen;  // each node once: shared children, and cycles, end here
    while (!stack.empty())
    {
        const std::uint64_t n = stack.back();
        stack.pop_back();
        if (!seen.insert(n).second)
            continue;
        const Json* node = item(doc, "nodes", n);
        if (node == nullptr)
            continue;
        if (const auto mesh = uint_field(*node, "mesh"))
            meshes.insert(*mesh);
        for (const std::uint64_t child : uint_list(*node, "children"))
            stack.push_back(child);
    }
    return meshes;
}

/// The bytes of a base64 `data:` URI (`data:[<media type>];base64,<data>`), or nothing when it is
/// not base64 or does not decode whole (Assimp requires padded base64 too).
std::optional<std::string> decode_data_uri(std::string_view uri)
{
    const std::size_t comma = uri.find(',');
    if (comma == std::string_view::npos || !uri.substr(0, comma).ends_with(";base64"))
        return std::nullopt;
    const std::string_view text = uri.substr(comma + 1);
    std::string out(text.size() / 4 * 3, '\0');
    std::size_t size = 0;
    const char* end = nullptr;
    if (sodium_base642bin(reinterpret_cast<unsigned char*>(out.data()), out.size(), text.data(),
                          text.size(), nullptr, &size, &end, sodium_base64_VARIANT_ORIGINAL) != 0 ||
        end != text.data() + text.size())
        return std::nullopt;
    out.resize(size);
    return out;
}

/// The buffers of a glTF as Assimp 5.2 finds them: buffer 0 of a GLB is its BIN chunk (whatever
/// its JSON says), a `data:` URI holds its bytes, any other URI names a file in the folder of the
/// glTF, taken as written.
class Buffers
{
public:
    Buffers(const Json& doc, std::string_view bytes, const ScanResult& scan,
            const std::filesystem::path& folder)
        : doc_(doc), bytes_(bytes), scan_(scan), folder_(folder)
    {
    }

    /// The bytes of buffer `index` that can be read: its byteLength, or less where its source
    /// holds less; nothing when it has no byteLength or no source that can be read.
    std::optional<std::uint64_t> length(std::uint64_t index)
    {
        const Json* buffer = item(doc_, "buffers", index);
        const auto stated = buffer ? uint_field(*buffer, "byteLength") : std::nullopt;
        if (!stated)
            return std::nullopt;
        if (scan_.format == Format::Glb && index == 0)
            return field(*buffer, "uri") != nullptr  // not a GLB's usual buffer 0
                       ? std::nullopt
                       : std::optional(std::min<std::uint64_t>(*stated, scan_.bin_size));
        const std::string* uri = string_field(*buffer, "uri");
        if (uri == nullptr)
            return std::nullopt;
        const std::string& text = *uri;
        if (!text.starts_with("data:"))
            return *stated;  // check_gltf_buffers: a regular file of at least byteLength
        auto [decoded, fresh] = data_.try_emplace(index);
        if (fresh)
            decoded->second = decode_data_uri(text);
        if (!decoded->second)
            return std::nullopt;
        return std::min<std::uint64_t>(*stated, decoded->second->size());
    }

    /// Bytes [begin, begin + size) of buffer `index`, within its length(); nothing when they
    /// cannot be read.
    std::optional<std::string> read(std::uint64_t index, std::uint64_t begin, std::uint64_t size)
    {
        if (scan_.format == Format::Glb && index == 0)
            return std::string(bytes_.substr(scan_.bin_offset + static_cast<std::size_t>(begin),
                                             static_cast<std::size_t>(size)));
        if (const auto it = data_.find(index); it != data_.end())
            return !it->second ? std::nullopt
                               : std::optional(it->second->substr(static_cast<std::size_t>(begin),
                                                                  static_cast<std::size_t>(size)));
        const Json* buffer = item(doc_, "buffers", index);
        const std::string* file = buffer ? string_field(*buffer, "uri") : nullptr;
        if (file == nullptr)
            return std::nullopt;
        const std::filesystem::path path = folder_ / *file;
        constexpr auto k_max =
            static_cast<std::uint64_t>(std::numeric_limits<std::streamoff>::max());
        if (unreadable_file(path) || begin > k_max || size > k_max)
            return std::nullopt;
        std::ifstream in(path, std::ios::binary);
        std::string out(static_cast<std::size_t>(size), '\0');
        if (!in.seekg(static_cast<std::streamoff>(begin)) ||
            !in.read(out.data(), static_cast<std::streamsize>(size)))
            return std::nullopt;
        return out;
    }

private:
    const Json& doc_;
    std::string_view bytes_;
    const ScanResult& scan_;
    const std::filesystem::path& folder_;
    std::map<std::uint64_t, std::optional<std::string>> data_;  ///< decoded data URIs
};

/// An index that names no vertex of its primitive.
struct OutOfRange
{
    std::uint64_t index = 0;
    std::uint64_t element = 0;  ///< in the indices accessor
    std::uint64_t mode = 4;
    std::uint64_t position_accessor = 0;
    std::uint64_t vertices = 0;  ///< the POSITION accessor's count
};

/// The first index of `primitive` that Assimp turns into a face and that is not below its
/// POSITION accessor's count, or nothing (also when the primitive cannot be checked).
std::optional<OutOfRange> first_out_of_range(const Json& doc, const Json& primitive,
                                             Buffers& buffers)
{
    const auto indices = uint_field(primitive, "indices");
    const Json* attributes = field(primitive, "attributes");
    if (!indices || attributes == nullptr)
        return std::nullopt;
    const auto position = uint_field(*attributes, "POSITION");
    const auto mode = uint_field_or(primitive, "mode", 4);  // TRIANGLES
    if (!position || !mode || *mode < 4 || *mode > 6)
        return std::nullopt;  // points and lines make no triangles
    if (const Json* ext = field(primitive, "extensions");
        ext != nullptr && field(*ext, "KHR_draco_mesh_compression") != nullptr)
        return std::nullopt;  // the indices come from the compressed data
    const Json* vertices_accessor = item(doc, "accessors", *position);
    const Json* accessor = item(doc, "accessors", *indices);
    if (vertices_accessor == nullptr || accessor == nullptr ||
        field(*accessor, "sparse") != nullptr)
        return std::nullopt;
    const auto vertices = uint_field(*vertices_accessor, "count");
    const auto count = uint_field(*accessor, "count");
    const auto component = uint_field(*accessor, "componentType");
    const auto offset = uint_field_or(*accessor, "byteOffset", 0);
    const auto view_index = uint_field(*accessor, "bufferView");
    const std::string* type = string_field(*accessor, "type");
    if (!vertices || !count || *count == 0 || !component || !offset || !view_index ||
        type == nullptr || *type != "SCALAR")
        return std::nullopt;
    const std::uint64_t size = *component == 5121   ? 1
                               : *component == 5123 ? 2
                               : *component == 5125 ? 4
                                                    : 0;
    if (size == 0)
        return std::nullopt;
    const Json* view = item(doc, "bufferViews", *view_index);
    if (view == nullptr)
        return std::nullopt;
    const auto buffer = uint_field(*view, "buffer");
    const auto view_offset = uint_field_or(*view, "byteOffset", 0);
    const auto view_length = uint_field(*view, "byteLength");
    const auto byte_stride = uint_field_or(*view, "byteStride", 0);
    if (!buffer || !view_offset || !view_length || !byte_stride)
        return std::nullopt;
    const std::uint64_t stride = *byte_stride != 0 ? *byte_stride : size;
    // The view within the buffer, the accessor's `count` elements within the view (each step
    // subtracts, so nothing overflows).
    const auto buffer_length = buffers.length(*buffer);
    if (!buffer_length || *view_offset > *buffer_length ||
        *view_length > *buffer_length - *view_offset || *offset > *view_length ||
        size > *view_length - *offset || *count - 1 > (*view_length - *offset - size) / stride)
        return std::nullopt;
    const std::uint64_t extent = (*count - 1) * stride + size;
    const auto data = buffers.read(*buffer, *view_offset + *offset, extent);
    if (!data)
        return std::nullopt;
    // Assimp's faces: TRIANGLES drops a last incomplete triangle; a strip or a fan of fewer
    // than 3 elements has none.
    const std::uint64_t used = *mode == 4 ? *count - *count % 3 : *count >= 3 ? *count : 0;
    for (std::uint64_t e = 0; e < used; ++e)
    {
        const auto* p = reinterpret_cast<const unsigned char*>(data->data()) + e * stride;
        std::uint64_t v = 0;
        for (std::uint64_t k = 0; k < size; ++k)
            v |= static_cast<std::uint64_t>(p[k]) << (8 * k);  // little-endian
        if (v >= *vertices)
            return OutOfRange{.index = v,
                              .element = e,
                              .mode = *mode,
                              .position_accessor = *position,
                              .vertices = *vertices};
    }
    return std::nullopt;
}

/// " ('name')" for a mesh with a name, control bytes as \xNN; "" without.
std::string mesh_label(const Json& mesh)
{
    const std::string* name = string_field(mesh, "name");
    if (name == nullptr || name->empty())
        return "";
    std::string out = " ('";
    for (const char c : *name)
    {
        const auto u = static_cast<unsigned char>(c);
        if (u < 0x20 || u == 0x7F)
        {
            std::array<char, 8> hex{};
            std::snprintf(hex.data(), hex.size(), "\\x%02X", u);
            out += hex.data();
        }
        else
            out += c;
    }
    return out + "')";
}

}  // namespace

core::Result<void> check_gltf_indices(std::string_view bytes, const ScanResult& scan,
                                      const std::filesystem::path& folder, const std::string& name)
{
    const std::string_view json =
        bytes.substr(std::min(scan.json_offset, bytes.size()), scan.json_size);
    const Json doc = Json::parse(json.begin(), json.end(), nullptr, /*allow_exceptions=*/false);
    // glTF 1.0 (Assimp's other reader) names its objects by string; nothing to check there.
    const Json* asset = field(doc, "asset");
    const std::string* version = asset ? string_field(*asset, "version") : nullptr;
    if (version == nullptr || !version->starts_with("2"))
        return {};
    Buffers buffers(doc, bytes, scan, folder);
    for (const std::uint64_t m : reached_meshes(doc))
    {
        const Json* mesh = item(doc, "meshes", m);
        const Json* primitives = mesh ? field(*mesh, "primitives") : nullptr;
        if (primitives == nullptr || !primitives->is_array())
            continue;
        for (std::size_t p = 0; p < primitives->size(); ++p)
        {
            const auto bad = first_out_of_range(doc, (*primitives)[p], buffers);
            if (!bad)
                continue;
            const std::string where = bad->mode == 4
                                          ? ", triangle " + std::to_string(bad->element / 3)
                                      : bad->mode == 5 ? " of a triangle strip"
                                                       : " of a triangle fan";
            return fail(ErrorCode::BadIndex,
                        name + ": mesh " + std::to_string(m) + mesh_label(*mesh) + " primitive " +
                            std::to_string(p) + ": index " + std::to_string(bad->index) +
                            " (element " + std::to_string(bad->element) + where +
                            ") is out of range: its POSITION accessor " +
                            std::to_string(bad->position_accessor) + " has " +
                            plural(bad->vertices, "vertex"));
        }
    }
    return {};
}

}  // namespace pliant::mesh::detail
