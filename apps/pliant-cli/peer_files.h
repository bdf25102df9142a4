// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once
// What `pliant host` and `pliant join` can write at the end of a session: a peer's view of the
// object (--save) and the master's recording (--record), so that a session of separate
// processes can be checked against one process (`pliant replay`, docs/session.md §9).
#include <pliant/core/result.h>
#include <pliant/session/session.h>

#include <filesystem>

namespace pliant::cli
{

/// Writes what `peer` shows: a .pgrid with the deformed positions (px, py, pz), u and v (its
/// own leaves' state and the others' streamed states: in exact coupling, once the streams have
/// settled, the session's state everywhere) and `owner`, the id of the peer that owns each node
/// under its newest partition. \return InvalidArgument before the peer has the model; save_grid's
/// errors.
core::Result<void> save_peer_state(const session::Session& peer, const std::filesystem::path& path);

/// Writes the master's recording with the hash of the state it shows as the final state: `pliant
/// replay FILE` then says whether one process reproduces the session bit for bit.
/// \pre `master` recorded from the start (Session::start_recording succeeded).
/// \return save_recording's errors.
core::Result<void> save_master_recording(const session::Session& master,
                                         const std::filesystem::path& path);

}  // namespace pliant::cli
