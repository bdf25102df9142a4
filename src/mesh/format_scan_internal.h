// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Structural checks of a mesh file's bytes before Assimp sees them.
//
// Assimp 5.2 is lenient where pliant must be strict: on a truncated binary STL or PLY, or an OFF
// file shorter than its header's counts, some of its readers return the part they could read (or
// reserve memory for the declared counts first); its OFF reader replaces a bad index with the
// last vertex or with 0 and skips faces of more than 9 vertices, and its OBJ reader reports a bad
// index or a bad coordinate without a line, and its PLY reader reports an out-of-range index
// without saying where. So the scanners check record boundaries in binary files, every face's
// vertex indices in PLY files (binary: with the face and its byte offset), and in the text formats
// OBJ, OFF and ASCII PLY every vertex record's values (numbers) and every face's indices
// (integers in range), with the line number in each message. Every loop advances
// through the buffer or stops, so they are bounded by the file size. They also count the file's
// vertex and face records for the ImportReport (Assimp's OBJ and STL readers expand vertices per
// face corner, so its counts do not show the file's).

#include <pliant/core/result.h>

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace pliant::mesh::detail
{

enum class Format
{
    Obj,
    Off,
    PlyAscii,
    PlyBinary,
    StlAscii,
    StlBinary,
    Gltf,
    Glb,
};

/// Short name for reports and JSON: "obj", "ply-binary", ...
[[nodiscard]] std::string_view format_name(Format format) noexcept;

/// What the scan learned. Counts are the file's records, or 0 when the format does not say.
struct ScanResult
{
    Format format = Format::Obj;
    std::size_t vertices = 0;
    std::size_t faces = 0;
    bool faces_known = false;  ///< `faces` is the file's exact face record count
    /// OBJ only: `v` records no `f` line refers to (Assimp's OBJ reader drops them silently).
    std::size_t unreferenced = 0;
    /// A copy of the file for Assimp to read instead, in the same format; empty otherwise. OFF,
    /// when a face has more than 9 vertices (Assimp's reader skips those): such faces fan-split
    /// into triangles. OBJ, when the file starts with a UTF-8 byte-order mark (Assimp's reader
    /// drops the first line then): the file without it.
    std::string rewritten{};
    /// glTF and GLB: where the JSON lies in the bytes (the whole `.gltf`; a GLB's JSON chunk).
    std::size_t json_offset = 0;
    std::size_t json_size = 0;
    /// GLB: where the BIN chunk's bytes lie (chunk 1, type "BIN"), the bytes of buffer 0 for
    /// Assimp. Only where Assimp looks for it (right after the JSON chunk, whose length is then a
    /// multiple of 4); 0 and 0 otherwise.
    std::size_t bin_offset = 0;
    std::size_t bin_size = 0;
};

/// Checks `bytes` (the whole file) against the structure of the format its lower-case extension
/// `ext` (".obj", ".stl", ...) names. `name` prefixes every message.
/// \return EmptyInput (no bytes, or a header that declares no faces), ParseError (binary bytes in
/// a text format, a bad header, a PLY vertex without x, y or z or a face element without its
/// index list, fewer records or bytes than the header declares, a `.gltf` whose JSON does not
/// parse), UnsupportedFormat (unknown extension, a PLY encoding pliant does not read).
[[nodiscard]] core::Result<ScanResult> scan_format(std::string_view bytes, std::string_view ext,
                                                   const std::string& name);

/// Why `path` cannot be read whole as a file, or nothing: "no such file", "it is a directory",
/// "not a regular file (a device, FIFO or socket)" (a FIFO blocks the reader for ever, a device
/// such as /dev/zero has no end).
[[nodiscard]] std::optional<std::string> unreadable_file(const std::filesystem::path& path);

/// The external buffers a glTF JSON (`json`, known to parse) names, in `folder`: each must be
/// a regular file (a FIFO hung the reader, a device has no end) of at least its byteLength.
/// Data URIs and a GLB's own chunk are not files. \return IoError (missing, a directory, not a
/// regular file) or ParseError (shorter than its byteLength), naming the buffer and the file.
[[nodiscard]] core::Result<void> check_gltf_buffers(std::string_view json,
                                                    const std::filesystem::path& folder,
                                                    const std::string& name);

/// Every index of a glTF 2.0 primitive that makes triangles (mode TRIANGLES, TRIANGLE_STRIP or
/// TRIANGLE_FAN) must name a vertex of its POSITION accessor: Assimp 5.2 drops a face with an
/// index past the vertex count, saying so only to its logger, and the hole then read as "not a
/// closed surface". `bytes` is the whole file, `scan` its scan (the JSON, known to parse; a GLB's
/// BIN chunk), `folder` where its buffer files lie (check_gltf_buffers checked them). Checks the
/// primitives of the meshes the default scene's node tree reaches (the ones import reads) whose
/// indices accessor is plain (SCALAR, unsigned byte, short or int, in a bufferView, not sparse)
/// and lies in a buffer it can read: a GLB's BIN chunk, a base64 `data:` URI, a file in
/// `folder`. Anything else (a missing or ill-typed field, data past its view or buffer, a buffer
/// that cannot be read or decoded) leaves that primitive to Assimp unchecked, as before.
/// \return BadIndex naming the mesh, the primitive, the index, its element and the vertex count.
[[nodiscard]] core::Result<void> check_gltf_indices(std::string_view bytes, const ScanResult& scan,
                                                    const std::filesystem::path& folder,
                                                    const std::string& name);

}  // namespace pliant::mesh::detail
