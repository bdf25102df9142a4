// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Writing output files whole or not at all, and checking an output path before long work.
///
/// Every writer of pliant's outputs (grids, meshes, images, recordings, reports) goes through
/// `write_files`: a failed write (disk full, a quota, a file-size limit) never leaves a
/// truncated file behind, and never destroys the file that was there before.

#include <pliant/core/result.h>

#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

namespace pliant::core
{

/// One output file: where it goes and its whole content.
struct FileContent
{
    std::filesystem::path path;
    std::span<const std::byte> bytes;
};

/// Writes every file whole, or none of them: each into a new file beside it (same folder, a
/// hidden unique name), every write checked and the file closed, and only when all of them are
/// written, each renamed over its path. On a failure the new files are removed and every path
/// keeps what it held (an earlier file stays as it was); the message names the path and the
/// system's reason ("No space left on device"). An existing file's permission bits carry over
/// to its replacement, and a symbolic link is followed (the file it names is replaced, the
/// link stays). A path that exists and is not a regular file (a device such as /dev/stdout, a
/// pipe) is written in place. `who` begins the message ("remesh: --report"; empty: the path does).
/// The data is not synced to the disk (no fsync): this guards against failed writes, not against
/// power loss.
/// Opening a FIFO waits for a reader, and writing a full pipe for the reader to take the bytes;
/// a signal whose handler does not restart system calls (sigaction without SA_RESTART, as the
/// CLI's Ctrl-C handler is installed) ends that wait with ErrorCode::Cancelled, "interrupted by
/// a signal while waiting for a reader", instead of waiting again (to a FIFO the bytes go in
/// writes of PIPE_BUF, each all or nothing, so that the signal finds one with nothing sent).
[[nodiscard]] Result<void> write_files(std::span<const FileContent> files, std::string_view who);

/// `write_files` for one file.
[[nodiscard]] Result<void> write_file(const std::filesystem::path& path,
                                      std::span<const std::byte> bytes, std::string_view who);

/// `write_file` of a text.
[[nodiscard]] Result<void> write_text_file(const std::filesystem::path& path, std::string_view text,
                                           std::string_view who);

/// Checks that an input file named by a user can be read, without opening it (a FIFO or
/// /dev/fd/N from a shell's process substitution passes and is not consumed). \return IoError
/// "`what`: PATH: no such file" (or "is a folder, not a file", "is a device, not a file" for a
/// character or block device such as /dev/zero, which has no end to read to (/dev/null, which
/// reads as an empty file, passes), or the system's
/// reason, e.g. "Permission denied"); with `what` empty the message starts with PATH.
[[nodiscard]] Result<void> check_input_file(const std::filesystem::path& path,
                                            std::string_view what = {});

/// The whole content of an input file (check_input_file first; a FIFO is read to its end), at
/// most `max_bytes`: \return IoError as check_input_file, or the system's reason for a failed
/// open or read; ParseError "PATH: more than N bytes, larger than any `what`" past `max_bytes`
/// (the read stops there; `what` names the format, e.g. "grid file").
[[nodiscard]] Result<std::vector<std::byte>> read_input_file(const std::filesystem::path& path,
                                                             std::size_t max_bytes,
                                                             std::string_view what);

/// Checks, before the work that produces it, that an output can be written at `path`, and
/// leaves nothing behind: `path` is not a folder, its folder exists, is a folder and is
/// writable, an existing `path` is writable, and the new file that write_files writes first can
/// be created beside it (tried, and removed at once: /proc or a read-only file system pass the
/// permission checks). The message reads "`what`: cannot write 'PATH': REASON".
[[nodiscard]] Result<void> check_output_path(const std::filesystem::path& path,
                                             std::string_view what);

}  // namespace pliant::core
