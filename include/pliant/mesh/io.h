// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Reading meshes from files (through Assimp), writing them back (our own OBJ / PLY writers,
/// Assimp's glTF 2 exporter), and turning a geometry image back into a `TriMesh`. docs/mesh.md
/// describes the formats, the welding and the error messages.

#include <pliant/core/field.h>
#include <pliant/core/progress.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/mesh/tri_mesh.h>

#include <cstddef>
#include <filesystem>
#include <string>

namespace pliant::mesh
{

/// What `import_mesh` did to the file's data on its way to a `TriMesh`.
struct ImportReport
{
    std::string format;                     ///< e.g. "obj", "ply-binary", "stl-ascii", "gltf"
    std::size_t meshes = 0;                 ///< mesh instances in the file's scene (all merged)
    std::size_t file_vertices = 0;          ///< vertex records in the file (OBJ `v` lines, OFF and
                                            ///< PLY header counts, 3 per STL facet; glTF: as read)
    std::size_t raw_vertices = 0;           ///< vertices as Assimp delivered them (OBJ and STL:
                                            ///< one per face corner)
    std::size_t raw_faces = 0;              ///< polygons in the file (before triangulation)
    std::size_t polygons_triangulated = 0;  ///< faces with more than 3 corners, fan-split
    std::size_t welded = 0;                 ///< used vertices merged into an equal position
    std::size_t unreferenced_dropped = 0;   ///< vertex records no face uses (removed)
    std::size_t vertices = 0;               ///< vertices of the result
    std::size_t faces = 0;                  ///< triangles of the result
    std::size_t non_triangles_dropped = 0;  ///< points and lines (faces with < 3 corners), ignored
};

/// Reads a surface mesh: OBJ, OFF, PLY (ascii and binary), STL (ascii and binary), glTF 2 (.gltf,
/// .glb), chosen by extension (case-insensitive). All meshes of the file are merged (node
/// transforms applied), polygons are triangulated, vertices with bit-identical positions are
/// welded (seams split only by normals or texture coordinates disappear), and positions no face
/// uses are dropped. The result is not validated: call `validate` for the docs/design.md §2.1
/// rules.
///
/// \return the mesh, or an error whose message names the file:
///   - IoError: the file is missing or unreadable;
///   - EmptyInput: an empty file (0 bytes, whatever the extension, since the file is read
///     first; only white space in an .obj, .off or .gltf), or a file with no faces;
///   - UnsupportedFormat: a non-empty file with an extension not listed above;
///   - ParseError: malformed or truncated content (e.g. a binary STL whose size is not
///     84 + 50·n bytes, a binary PLY shorter than its header's counts);
///   - NonFiniteCoordinate: a vertex position with NaN or infinity (the message says which).
/// Running out of memory throws std::bad_alloc, as any allocation does (also where Assimp's
/// reader caught it). Thread-safe (each call owns its Assimp importer); Assimp's own logging
/// never reaches stdout.
[[nodiscard]] core::Result<TriMesh> import_mesh(const std::filesystem::path& path,
                                                ImportReport* report = nullptr);

/// Writes `mesh` by extension (case-insensitive):
///   - `.obj` (ascii, every coordinate with 17 significant digits) or `.ply` (binary
///     little-endian, double-precision coordinates, uint32 indices): vertex and face order are
///     kept and the file holds the doubles exactly. Since Assimp reads floats, a double mesh
///     comes back from `import_mesh` rounded to float: exactly so through PLY, within one float
///     ulp through OBJ (Assimp's fast_atof on exponent notation).
///   - `.gltf` / `.glb` (glTF 2.0, through Assimp's exporter): one mesh with float32 positions,
///     unit vertex normals (area-weighted) and one plain material. `.gltf` writes its buffer to
///     a side file `<stem>.bin` in the same folder (referenced by that relative name; keep the
///     two together); `.glb` is self-contained. Positions are rounded to float; Assimp merges
///     vertices whose float positions agree within a few ulps and drops unused ones, otherwise
///     order is kept: `import_mesh` gives back the same faces with the float-rounded positions.
/// `import_mesh` of what `import_mesh` produced gives the identical mesh back through every
/// format (tested on the data meshes). docs/mesh.md has the details.
/// `progress` (optional) gets phase "export" with fractions below 1 while an OBJ or PLY is
/// formatted (seconds for millions of faces); if it asks to stop, nothing is written and the
/// result is ErrorCode::Cancelled (glTF is looked at once, before Assimp's exporter runs).
/// \return IoError when a file cannot be written or Assimp's exporter fails (the message names
///   the file and carries Assimp's); UnsupportedFormat for another extension (the message lists
///   the four); NonFiniteCoordinate for a vertex with NaN or infinity, used or not (nothing is
///   written; for glTF also a coordinate beyond the float range); for glTF also InvalidArgument
///   (a name check_export_name refuses), EmptyInput (no faces) and BadIndex (a face index >=
///   vertex count).
[[nodiscard]] core::Result<void> export_mesh(const std::filesystem::path& path, const TriMesh& mesh,
                                             core::ProgressSink* progress = nullptr);

/// Whether `path` can be exported under its name: a `.gltf` names its buffer `<stem>.bin` in a
/// URI, which must then hold only characters a URI need not escape (letters, digits, `-`, `.`,
/// `_`, `~`), since Assimp's reader (and so pliant's) does not decode %-escapes and other
/// readers would misread the raw name (a `#` starts a fragment, a space is no URI). Other
/// formats take any name. \return InvalidArgument naming the file and the first such character.
[[nodiscard]] core::Result<void> check_export_name(const std::filesystem::path& path);

/// The surface of a geometry image: vertex i is the position of node `grid.node_of_unique()[i]`
/// (2W²+2 vertices), faces are `grid.triangles()` (4W² faces).
/// \pre positions made for `grid` (same level).
[[nodiscard]] TriMesh from_grid(const core::TetraGrid& grid,
                                const core::Vec3Field<double>& positions);

}  // namespace pliant::mesh
