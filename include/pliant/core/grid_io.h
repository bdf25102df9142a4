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
/// a displacement) are optional. Reading validates magic, version, level, sizes, the checksum,
/// finiteness and twin equality, and gives back exactly the doubles that were written.

#include <pliant/core/field.h>
#include <pliant/core/result.h>

#include <filesystem>
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

/// Writes `file` to `path`. \return IoError if the file cannot be written; InvalidArgument for
/// a bad name or a field of another level.
Result<void> save_grid(const std::filesystem::path& path, const GridFile& file);

/// Reads a `.pgrid` file. \return IoError, ParseError (truncated, bad magic, bad checksum),
/// BadGrid (level out of range, twins that differ, non-finite values).
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
