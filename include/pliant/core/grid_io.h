// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The native grid file (`.pgrid`), read by every command that takes a GRID, and PFM export.
/// Format (little-endian, documented in docs/grid-format.md):
///
///     magic    8 bytes  "PLIANTG\0"
///     version  u32      1
///     level    u32      1..10
///     channels u32      number of named float64 planes that follow
///     per channel: name (16 bytes, NUL-padded ASCII), then nx*ny float64 values, row-major
///     checksum u64      hash_bytes of everything before it
///
/// A geometry file has channels "px", "py", "pz" (rest positions); others (for example "u" for
/// a displacement) are optional; no name appears twice. Reading validates magic, version,
/// level, sizes, the checksum, the names (printable, NUL-padded, distinct), finiteness and twin
/// equality, and gives back exactly the doubles that were written: a file it accepts encodes
/// back to the same bytes (fuzz/fuzz_grid_file.cpp checks that).

#include <pliant/core/field.h>
#include <pliant/core/result.h>

#include <cstddef>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace pliant::core
{

struct NamedField
{
    std::string name;  ///< at most 15 ASCII characters
    Field<double> values;
};

/// A grid and its fields, as stored in a `.pgrid` file.
struct GridFile
{
    int level = 0;
    std::vector<NamedField> fields;

    /// The field called `name`, or nullptr.
    [[nodiscard]] const Field<double>* find(std::string_view name) const noexcept;
};

/// The bytes of `file` as a `.pgrid` file; `source` names it in messages. \return
/// InvalidArgument for a bad or repeated name, a channel that breaks the rules above, a field
/// of another level, or a level outside 1..10 (TetraGrid::create's error, whose message does
/// not name `source`). Twins are written with their canonical
/// node's bits (a twin may hold -0 where its node holds +0; the file holds one of them).
Result<std::vector<std::byte>> encode_grid(const GridFile& file, const std::string& source);

/// Writes `file` to `path` (encode_grid), whole or not at all (core::write_file: a failed write
/// keeps an earlier file). \return encode_grid's errors; IoError if the file cannot be written.
Result<void> save_grid(const std::filesystem::path& path, const GridFile& file);

/// Reads the bytes of a `.pgrid` file; `source` (a path, "the welcome", ...) begins every
/// message. \return ParseError (truncated, bad magic, bad checksum, wrong sizes), BadGrid (level
/// out of range, a bad or repeated name, twins that differ in any bit, non-finite values).
Result<GridFile> decode_grid(std::span<const std::byte> bytes, const std::string& source);

/// Reads a `.pgrid` file (decode_grid). \return IoError if it cannot be read; decode_grid's
/// errors, naming the path.
Result<GridFile> load_grid(const std::filesystem::path& path);

/// Bundles rest positions into a grid file with channels px, py, pz.
[[nodiscard]] GridFile make_geometry_file(const TetraGrid& grid,
                                          const Vec3Field<double>& positions);

/// Extracts the positions of a geometry file (ghost width `ghost`). \return BadGrid when a
/// channel px/py/pz is missing.
Result<Vec3Field<double>> geometry_of(const TetraGrid& grid, const GridFile& file, int ghost = 0);

/// Writes positions as a colour PFM image ((2W+1) x (W+1), float32) for image tools.
Result<void> save_pfm(const std::filesystem::path& path, const Vec3Field<double>& positions);

}  // namespace pliant::core
