// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Recording and deterministic replay of a session's inputs (issue 9 item 4, docs/session.md §9).
///
/// Design
/// - In exact coupling the session's state is a pure function of the model and of every peer's
///   force lists with the ticks they apply from (tests/session: a distributed run equals the
///   single-process run bit for bit). So a recording holds only those inputs: the model blob
///   (`encode_model`: level, material, rest positions) and each force list as the wire's own
///   `Force` datagram (sender id in the header, apply tick in the header's tick). Reading a
///   recording therefore reuses the wire codec's validation of every field; nothing else is
///   trusted.
/// - Replay steps one process from rest with the session's rule for combining forces (each
///   sender's newest list whose tick has come, senders in increasing id, a force the model
///   refuses left out and the others kept: `append_valid_forces`) and reproduces the session's
///   final state bit for bit.
/// - Fast coupling depends on timing (who saw which streamed state when), so its recordings
///   replay the same inputs on one process but the result differs; `replay` says so by
///   returning the coupling, and `pliant replay` warns.
///
/// File (`.prec`, little-endian): magic, version, final tick and hash, hash mask, model blob,
/// Force entries, checksum; every byte and check: docs/session.md §9.1 to §9.3.

#include <pliant/core/field.h>
#include <pliant/core/progress.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/net/message.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace pliant::session
{

/// One force list of one sender, applying from `apply_tick` on (until that sender's next list).
struct ForceRecord
{
    std::uint16_t sender = 0;
    std::uint64_t apply_tick = 0;
    std::vector<net::UserForce> forces;  ///< 0..net::k_max_points
    friend bool operator==(const ForceRecord&, const ForceRecord&) = default;
};

/// A session's inputs from its start (tick 0, at rest) to `final_tick`.
struct Recording
{
    std::vector<std::byte> model;  ///< encode_model's blob
    std::uint64_t final_tick = 0;
    std::uint64_t final_hash = 0;  ///< state_hash of the session's final state; 0: unknown
    /// The canonical nodes `final_hash` covers, one bit per node in `node_of_unique()` order
    /// (bit k of byte k / 8); empty: every node. A master of separate processes knows only its
    /// own nodes exactly at its final tick (docs/session.md §9).
    std::vector<std::uint8_t> hash_mask;
    std::vector<ForceRecord> forces;  ///< in the order the recorder saw them
    friend bool operator==(const Recording&, const Recording&) = default;
};

/// The bytes of `recording` as a file. \return InvalidArgument if a force list breaks the wire's
/// rules.
core::Result<std::vector<std::byte>> encode_recording(const Recording& recording);

/// Writes `recording` to `path` (encode_recording). \return its errors; IoError if the file
/// cannot be written.
core::Result<void> save_recording(const std::filesystem::path& path, const Recording& recording);

/// Reads the bytes of a recording; `source` begins every message. \return ParseError naming the
/// source and the byte offset for a wrong magic or version, a truncated or corrupted file
/// (checksum), a force entry the wire codec refuses, or trailing bytes. The model blob is
/// checked when it is used (decode_model, in replay). What it accepts encodes to a file that
/// decodes to the same recording (fuzz/fuzz_recording.cpp checks that).
core::Result<Recording> decode_recording(std::span<const std::byte> bytes,
                                         const std::string& source);

/// Reads a recording from `path` (decode_recording). \return IoError if unreadable;
/// decode_recording's errors, naming the path.
core::Result<Recording> load_recording(const std::filesystem::path& path);

/// The forces of tick `tick` under the session's rule (see the file comment).
[[nodiscard]] std::vector<sim::Force> forces_at(const sim::MembraneModel& model,
                                                const std::vector<ForceRecord>& records,
                                                std::uint64_t tick);

/// What a replay produced.
struct ReplayResult
{
    sim::MembraneModel model;
    Coupling coupling = Coupling::Exact;
    sim::MembraneState state;  ///< at recording.final_tick (at `diverged` when it is set)
    /// The tick whose step gave non-finite values (a recording that no session made: crafted,
    /// or from another build); the replay stopped there and `state` is the last finite one.
    std::optional<std::uint64_t> diverged;
};

/// Replays `recording` on one process with `threads` threads (the result does not depend on it)
/// up to tick `until` (unset: the recording's final tick; 0: the rest state it starts from),
/// reporting progress as phase "replay".
/// A step that gives non-finite values ends the replay there (ReplayResult::diverged).
/// \return decode_model's errors; InvalidArgument if the model is not fixed-step; Cancelled
/// ("replay: cancelled during tick T of N") within 16 steps of `progress` asking to stop.
core::Result<ReplayResult> replay(const Recording& recording, int threads = 1,
                                  std::optional<std::uint64_t> until = std::nullopt,
                                  core::ProgressSink* progress = nullptr);

/// A hash of u and v over the canonical nodes (bit-exact identity of a state); with a
/// non-empty `mask` (Recording::hash_mask's layout), over the nodes whose bit is set.
[[nodiscard]] std::uint64_t state_hash(const core::TetraGrid& grid, const core::Field<double>& u,
                                       const core::Field<double>& v,
                                       std::span<const std::uint8_t> mask = {});

/// How many canonical nodes `mask` covers (every node when empty).
[[nodiscard]] std::size_t hash_mask_count(const core::TetraGrid& grid,
                                          std::span<const std::uint8_t> mask);

}  // namespace pliant::session
