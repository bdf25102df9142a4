// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once
// What `pliant host` and `pliant join` can write at the end of a session: a peer's view of the
// object (--save) and the master's recording (--record), so that a session of separate
// processes can be checked against one process (`pliant replay`, docs/session.md §9).
#include <pliant/core/result.h>
#include <pliant/session/session.h>

#include <cstddef>
#include <filesystem>

namespace pliant::cli
{

/// Writes what `peer` shows: a .pgrid with the deformed positions (px, py, pz), u and v (its
/// own leaves' state and the others' streamed states: in exact coupling, once the streams have
/// settled, the session's state everywhere) and `owner`, the id of the peer that owns each node
/// under its newest partition. \return InvalidArgument before the peer has the model; save_grid's
/// errors.
core::Result<void> save_peer_state(const session::Session& peer, const std::filesystem::path& path);

/// What the recording's final hash covers: the master's own canonical nodes, of `total`.
struct RecordedHash
{
    std::size_t covered = 0;
    std::size_t total = 0;
};

/// Writes the master's recording with the hash of its own nodes' state at its final tick (the
/// others' last streamed states may be of other ticks): `pliant replay FILE` then says whether
/// one process reproduces the session bit for bit on those nodes (docs/session.md §9).
/// \pre `master` recorded from the start (Session::start_recording succeeded).
/// \return what the hash covers (0 nodes: no hash, the master owned none); InvalidArgument
/// before the model; save_recording's errors.
core::Result<RecordedHash> save_master_recording(const session::Session& master,
                                                 const std::filesystem::path& path);

}  // namespace pliant::cli
