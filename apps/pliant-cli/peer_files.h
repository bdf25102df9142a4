// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once
// What `pliant host` and `pliant join` can write at the end of a session: a peer's view of the
// object (--save) and the master's recording (--record), so that a session of separate
// processes can be checked against one process (`pliant replay`, docs/session.md §9).
#include <pliant/core/grid_io.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>
#include <pliant/net/secure_transport.h>
#include <pliant/net/transport.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>

#include "cli_common.h"

#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>

namespace pliant::cli
{

/// Writes what `peer` shows: a .pgrid with the deformed positions (px, py, pz), u and v (its
/// own leaves' state and the others' streamed states: in exact coupling, once the streams have
/// settled, the session's state everywhere) and `owner`, the id of the peer that owns each node
/// under its newest partition. \return InvalidArgument before the peer has the model; save_grid's
/// errors.
core::Result<void> save_peer_state(const session::Session& peer, const std::filesystem::path& path);

/// The output options of `host` and `join` (`command`), checked before the session starts:
/// `--save` must end in .pgrid (it holds the state: u, v and owners, which no mesh format
/// keeps); --stats, --record and --save must be writable (check_writable); and none may replace
/// one of `inputs` (GRID, --script) or another output (file_clash). Logs the refusal. \return
/// the exit status to end with (k_exit_bad_input, or k_exit_usage for a clash), or nothing.
[[nodiscard]] std::optional<int> check_peer_outputs(const std::string& command,
                                                    std::span<const NamedFile> inputs,
                                                    const std::string& stats,
                                                    const std::string& record,
                                                    const std::string& save);

/// Why `master` (given as `text`) cannot be dialled by a peer listening on `own_port` (0: any),
/// or nothing: 0.0.0.0 is the address a peer listens on, not one to dial (ENet matched no reply
/// to it: "never answered"), and a loopback address at `own_port` is this peer itself. For
/// join, view HOST:PORT and the viewer's Session panel alike.
[[nodiscard]] std::optional<std::string> undialable(const net::Address& master,
                                                    const std::string& text,
                                                    std::uint16_t own_port);

/// The exit status of a peer whose run is over: 0; k_exit_failure with an error naming
/// `command` and the tick when the peer's state diverged (Session::diverged; what it holds and
/// saves is the last finite state); else k_exit_bad_input when its stats file could not be
/// written to the end (`stats_error`, RunSummary::stats_error).
[[nodiscard]] int end_status(const session::Session& peer, const std::string& command,
                             const std::string& stats_error);

/// Whether a grid file holds a simulated state (channels u and v): what `host`/`join --save`,
/// `demo`'s final.pgrid, `replay -o` and `simulate`'s frames write. Their px/py/pz are the
/// deformed surface P + uN, not a rest shape.
[[nodiscard]] bool holds_state(const core::GridFile& file);

/// Whether `v` is a value of a channel `owner`: a whole number from -1 to 65535 (-1 and 65535: no
/// owner; docs/grid-format.md).
[[nodiscard]] constexpr bool is_owner_value(double v) noexcept
{
    return v >= -1.0 && v <= 65535.0 && v == static_cast<double>(static_cast<long>(v));
}

/// Where a channel `owner` (docs/grid-format.md) holds something that is not a peer id: the
/// first node, in node order, whose value is not a whole number from -1 to 65535 (-1 and 65535:
/// no owner), and the message "channel owner: node (x, y) holds V, which is not a peer id ...";
/// nothing when every value is one.
struct OwnerProblem
{
    core::GridCoord at;
    double value = 0.0;
    std::string value_text;  ///< the shortest text that reads back as `value`
    std::string message;
};
[[nodiscard]] std::optional<OwnerProblem> owner_channel_problem(const core::TetraGrid& grid,
                                                                const core::Field<double>& owner);

/// The refusal for a state file given where a rest geometry is expected (`command`'s GRID). Its
/// suggested command resumes from `resume` when the user gave one, else from `path`.
[[nodiscard]] core::Error state_as_rest_error(const std::string& command, const std::string& path,
                                              const std::string& resume = {});

/// The rest geometry a physics command (`host`, `simulate`) starts from.
struct RestGeometry
{
    core::TetraGrid grid;
    core::Vec3Field<double> positions;  ///< ghost 0
};

/// Loads GRID's rest positions (a state file is refused: `state_as_rest_error`), or, when `path`
/// is empty, a sphere of `radius` at `level` laid out by `sphere_map` ("equal-area" or
/// "gnomonic"). `command` prefixes the refusal; `resume` is the command's --resume file, if any
/// (for the refusal's suggestion). \return load_grid's and geometry_of's errors (the latter
/// prefixed with the path); InvalidArgument for a state file or a bad level.
core::Result<RestGeometry> load_rest_geometry(const std::string& command, const std::string& path,
                                              int level, double radius,
                                              const std::string& sphere_map,
                                              const std::string& resume = {});

/// Reads the state saved in `path` (channels u and, when present, v; v = 0 otherwise) for
/// `--resume`, checking it belongs to `model`: same level and, when the file has positions,
/// P + uN of the model within 1e-9 of its size at every node (the writers compute them with the
/// same formula, so a state of this rest geometry matches to rounding). \return IoError,
/// ParseError, BadGrid from `load_grid`; BadGrid for another level, no u, a non-finite value,
/// or positions that `model` displaced by u does not give (another rest geometry), naming the
/// farthest node.
core::Result<sim::MembraneState> load_saved_state(const std::filesystem::path& path,
                                                  const sim::MembraneModel& model);

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

/// The session's shared secret: from `passphrase`, else the file `key_file`, else the
/// environment's PLIANT_PASSPHRASE (docs/operations.md); warns of a key file shorter than 32
/// bytes or readable by others. nullopt when none is given. \return InvalidArgument for a set
/// but empty PLIANT_PASSPHRASE; derive_key's and key_from_file's errors. For `host`, `join`
/// and `view`.
[[nodiscard]] core::Result<std::optional<net::SecretKey>> session_secret(
    const std::string& passphrase, const std::string& key_file);

/// `inner` wrapped in net::SecureTransport under `secret`, or, with none, `inner` itself and a
/// warning that the session is neither encrypted nor authenticated.
[[nodiscard]] std::unique_ptr<net::Transport> secure_or_plain(
    std::unique_ptr<net::Transport> inner, const std::optional<net::SecretKey>& secret);

/// secure_or_plain under session_secret(passphrase, key_file): `pliant host` and `pliant join`.
[[nodiscard]] core::Result<std::unique_ptr<net::Transport>> secure_or_plain(
    std::unique_ptr<net::Transport> inner, const std::string& passphrase,
    const std::string& key_file);

/// What a joiner's user can do about a connection to the master that ended before the Welcome
/// (docs/operations.md, "What failures look like"): "join: MASTER ..." with the reason and the
/// remedy. `secured`: this peer has a secret (`pliant join`, and the viewer's join).
[[nodiscard]] std::string join_failure_message(const std::string& master,
                                               const session::JoinFailure& f, bool secured);

}  // namespace pliant::cli
