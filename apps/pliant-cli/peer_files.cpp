// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "peer_files.h"

#include <pliant/core/grid_io.h>
#include <pliant/core/sphere_domain.h>
#include <pliant/session/recording.h>

#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include "../../scenes/grid_shapes.h"
#include "cli_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

namespace pliant::cli
{

int end_status(const session::Session& peer, const std::string& command,
               const std::string& stats_error)
{
    const auto tick = peer.diverged();
    if (!tick)
    {
        if (stats_error.empty())
            return 0;
        spdlog::error("{}: {}", command, stats_error);
        return k_exit_bad_input;
    }
    spdlog::error(
        "{}: the simulation diverged at tick {}: this peer kept its last finite state (what "
        "--save writes) and left the session (the other members, if any, took its share over); "
        "leave --dt out (the host picks a stable step) or keep a force limit (--max-force)",
        command, *tick);
    return k_exit_failure;
}

core::Result<void> save_peer_state(const session::Session& peer, const std::filesystem::path& path)
{
    const sim::MembraneModel* model = peer.model();
    if (model == nullptr || peer.leaf_graph() == nullptr)
        return core::fail(
            core::ErrorCode::InvalidArgument,
            "cannot save '" + path.string() + "': this peer never received the model");
    const core::TetraGrid& grid = model->grid();
    core::Vec3Field<double> positions;
    model->positions(peer.display_u(), positions);
    core::GridFile file = core::make_geometry_file(grid, positions);
    core::Field<double> u(grid);
    core::Field<double> v(grid);
    core::Field<double> owner(grid);
    const auto owners = peer.owners();
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            u.at(x, y) = peer.display_u().at(x, y);
            v.at(x, y) = peer.display_v().at(x, y);
            const std::uint32_t leaf = peer.leaf_graph()->leaf_of(grid.index(x, y));
            owner.at(x, y) = leaf < owners.size() ? owners[leaf].value : 65535.0;
        }
    file.fields.push_back({"u", std::move(u)});
    file.fields.push_back({"v", std::move(v)});
    file.fields.push_back({"owner", std::move(owner)});
    return core::save_grid(path, file);
}

std::optional<std::string> undialable(const net::Address& master, const std::string& text,
                                      std::uint16_t own_port)
{
    if (master.ipv4 == std::array<std::uint8_t, 4>{0, 0, 0, 0})
        return text +
               " is the 'any' address, which a peer listens on but cannot dial; give 127.0.0.1:" +
               std::to_string(master.port) + " for a master on this machine";
    if (master.ipv4[0] == 127 && own_port == master.port)
        return text + " is this peer's own --port " + std::to_string(own_port) +
               ": give the master's port, or another --port";
    return std::nullopt;
}

std::optional<int> check_peer_outputs(const std::string& command, std::span<const NamedFile> inputs,
                                      const std::string& stats, const std::string& record,
                                      const std::string& save)
{
    if (!save.empty() && lower_extension(save) != ".pgrid")
        return report({core::ErrorCode::UnsupportedFormat,
                       command + ": --save " + save +
                           " must end in .pgrid: it holds the state (u, v and the owner of every "
                           "node), which no mesh format keeps; `pliant refine FILE.pgrid --levels "
                           "1 -o mesh.obj` or `pliant render` make a mesh or a picture of it"});
    const NamedFile outputs[] = {{stats, "--stats"}, {record, "--record"}, {save, "--save"}};
    for (const NamedFile& out : outputs)
        if (!out.path.empty())
            if (auto ok = check_writable(out.path, command + ": " + std::string(out.what)); !ok)
                return report(ok.error());
    if (const auto clash = file_clash(inputs, outputs))
    {
        spdlog::error("{}: {}", command, *clash);
        return k_exit_usage;
    }
    return std::nullopt;
}

std::optional<OwnerProblem> owner_channel_problem(const core::TetraGrid& grid,
                                                  const core::Field<double>& owner)
{
    for (std::uint32_t i = 0; i < grid.node_count(); ++i)
    {
        const double v = owner[core::NodeIndex{i}];
        if (is_owner_value(v))
            continue;
        const core::GridCoord c = grid.coord(core::NodeIndex{i});
        const std::string value = fmt::format("{}", v);  // the shortest text that reads back as v
        return OwnerProblem{c, v, value,
                            "channel owner: node (" + std::to_string(c.x) + ", " +
                                std::to_string(c.y) + ") holds " + value +
                                ", which is not a peer id (a whole number from -1 to 65535; -1 "
                                "and 65535: no owner)"};
    }
    return std::nullopt;
}

bool holds_state(const core::GridFile& file)
{
    return file.find("u") != nullptr && file.find("v") != nullptr;
}

core::Error state_as_rest_error(const std::string& command, const std::string& path,
                                const std::string& resume)
{
    const std::string what = resume.empty() ? "this file" : "your state";
    return {core::ErrorCode::InvalidArgument,
            command + ": " + path +
                " holds a simulated state (channels u and v): its positions are the deformed "
                "surface, not a rest shape. Give the grid it was simulated on as GRID and " +
                what + " to --resume (`pliant " + command + " REST.pgrid --resume " +
                (resume.empty() ? path : resume) + "`)"};
}

core::Result<RestGeometry> load_rest_geometry(const std::string& command, const std::string& path,
                                              int level, double radius,
                                              const std::string& sphere_map,
                                              const std::string& resume)
{
    if (path.empty())
    {
        auto grid = core::TetraGrid::create(level);
        if (!grid)
            return grid.error();
        auto positions = scenes::sphere_grid(
            *grid, radius, 0,
            core::sphere_map_from_string(sphere_map).value_or(core::SphereMap::EqualArea));
        return RestGeometry{std::move(*grid), std::move(positions)};
    }
    auto file = core::load_grid(path);
    if (!file)
        return file.error();
    if (holds_state(*file))
        return state_as_rest_error(command, path, resume);
    auto grid = core::TetraGrid::create(file->level);
    if (!grid)
        return grid.error();
    auto positions = core::geometry_of(*grid, *file);
    if (!positions)
        return core::fail(positions.error().code, path + ": " + positions.error().message);
    return RestGeometry{std::move(*grid), std::move(*positions)};
}

core::Result<sim::MembraneState> load_saved_state(const std::filesystem::path& path,
                                                  const sim::MembraneModel& model)
{
    const std::string name = path.string();
    // By its name where it has one; a name without an extension (a pipe, `<(...)`, /dev/fd/N)
    // is read, and the grid file's own header says whether it is one.
    const std::string ext = lower_extension(path);
    if (!ext.empty() && ext != ".pgrid")
        return core::fail(core::ErrorCode::InvalidArgument,
                          "--resume " + name +
                              ": a state is resumed from a .pgrid frame (u and v), not from a "
                              "mesh; `simulate` writes them with --format pgrid, the default");
    auto file = core::load_grid(path);
    if (!file)
        return file.error();
    const core::TetraGrid& grid = model.grid();
    const auto bad = [&](const std::string& why)
    { return core::fail(core::ErrorCode::BadGrid, "--resume " + name + ": " + why); };
    if (file->level != grid.level())
        return bad("a state of level " + std::to_string(file->level) + ", but the rest grid is " +
                   "of level " + std::to_string(grid.level()));
    const core::Field<double>* u = file->find("u");
    const core::Field<double>* v = file->find("v");
    if (u == nullptr)
        return bad(
            "no channel 'u' (not a saved state: `host --save`, `demo`'s final.pgrid, "
            "`replay -o` and `simulate` frames hold one)");
    sim::MembraneState state = sim::MembraneState::at_rest(grid);
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            state.u.at(x, y) = u->at(x, y);
            state.v.at(x, y) = v != nullptr ? v->at(x, y) : 0.0;
            if (!std::isfinite(state.u.at(x, y)) || !std::isfinite(state.v.at(x, y)))
                return bad("a non-finite value at node (" + std::to_string(x) + ", " +
                           std::to_string(y) + ")");
        }
    model.sync(state.u);
    model.sync(state.v);
    if (file->find("px") == nullptr)
    {
        // pliant's own states always hold positions; a file of u and v alone is taken on trust.
        spdlog::warn(
            "--resume {}: no positions (channels px, py, pz), so the state cannot be "
            "checked against the rest shape of GRID; taken as it is",
            name);
        return state;
    }
    auto saved = core::geometry_of(grid, *file);
    if (!saved)
        return bad(saved.error().message);
    core::Vec3Field<double> expected;
    model.positions(state.u, expected);
    const core::Vec3Field<double>& P = model.rest_positions();
    double lo[3] = {P[0].at(0, 0), P[1].at(0, 0), P[2].at(0, 0)};
    double hi[3] = {lo[0], lo[1], lo[2]};
    double worst = -1.0;
    int wx = 0;
    int wy = 0;
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            double d2 = 0.0;
            for (std::size_t k = 0; k < 3; ++k)
            {
                const double p = P[k].at(x, y);
                lo[k] = std::min(lo[k], p);
                hi[k] = std::max(hi[k], p);
                const double d = (*saved)[k].at(x, y) - expected[k].at(x, y);
                d2 += d * d;
            }
            if (d2 > worst)
            {
                worst = d2;
                wx = x;
                wy = y;
            }
        }
    const double size = core::norm(core::Vec3{hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    if (std::sqrt(worst) > 1e-9 * size)
    {
        const auto at = [&](const core::Vec3Field<double>& f)
        {
            char text[96];
            std::snprintf(text, sizeof text, "(%.6g, %.6g, %.6g)", f[0].at(wx, wy), f[1].at(wx, wy),
                          f[2].at(wx, wy));
            return std::string(text);
        };
        char gap[48];
        std::snprintf(gap, sizeof gap, "%.3g", std::sqrt(worst));
        return bad("not a state of this rest geometry: at node (" + std::to_string(wx) + ", " +
                   std::to_string(wy) + ") the file's surface is at " + at(*saved) +
                   " but the rest grid displaced by the file's u puts it at " + at(expected) +
                   ", " + gap + " away; give the grid the state was simulated on");
    }
    return state;
}

core::Result<RecordedHash> save_master_recording(const session::Session& master,
                                                 const std::filesystem::path& path)
{
    if (master.model() == nullptr)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "cannot save '" + path.string() + "': the session has no model");
    const core::TetraGrid& grid = master.model()->grid();
    session::Recording recording = master.recording();
    // The master's own nodes are the session's state at its final tick; the others' are what
    // their owners last streamed, which may be older (a participant without --ticks stops when
    // the master leaves, some ticks later or earlier). So the hash covers the master's nodes.
    // In exact coupling every node's state reaches them through the halos, one ring per stage,
    // so a difference anywhere shows in them within a few ticks.
    const auto owners = master.state_owners();
    const auto nodes = grid.node_of_unique();
    RecordedHash out{.covered = 0, .total = nodes.size()};
    std::vector<std::uint8_t> mask((nodes.size() + 7) / 8, 0);
    for (std::size_t k = 0; k < nodes.size(); ++k)
    {
        const std::uint32_t leaf = master.leaf_graph()->leaf_of(nodes[k]);
        if (leaf < owners.size() && owners[leaf] == master.id())
        {
            mask[k / 8] = static_cast<std::uint8_t>(mask[k / 8] | (1U << (k % 8)));
            ++out.covered;
        }
    }
    if (out.covered == nodes.size() || out.covered == 0)
        mask.clear();  // every node; or none, with hash 0 (unknown)
    recording.hash_mask = std::move(mask);
    recording.final_hash =
        out.covered == 0
            ? 0
            : session::state_hash(grid, master.state().u, master.state().v, recording.hash_mask);
    if (auto saved = session::save_recording(path, recording); !saved)
        return saved.error();
    return out;
}

/// docs/operations.md: 32 random bytes, as `head -c 32 /dev/urandom` writes.
constexpr std::uintmax_t k_key_file_advised_bytes = 32;

core::Result<std::optional<net::SecretKey>> session_secret(const std::string& passphrase,
                                                           const std::string& key_file)
{
    std::optional<core::Result<net::SecretKey>> key;
    const char* env = std::getenv("PLIANT_PASSPHRASE");
    if (!passphrase.empty())
        key = net::derive_key(passphrase);
    else if (!key_file.empty())
    {
        key = net::key_from_file(key_file);
        std::error_code ec;
        const auto size = std::filesystem::file_size(key_file, ec);
        if (*key && !ec && size < k_key_file_advised_bytes)
            spdlog::warn(
                "{}: a key of {} bytes is easy to guess; a key file should hold {} "
                "random bytes (head -c 32 /dev/urandom > {})",
                key_file, size, k_key_file_advised_bytes, key_file);
        // As ssh does for private keys, though only as a warning: whoever can read the file
        // can join the session and read its traffic.
        struct ::stat st
        {
        };
        if (*key && ::stat(key_file.c_str(), &st) == 0 && (st.st_mode & 077) != 0)
            spdlog::warn(
                "{}: the key file can be read by {} (mode {:04o}): whoever can read it "
                "can join the session and read its traffic; chmod 600 {}",
                key_file, (st.st_mode & 007) != 0 ? "every user" : "its group", st.st_mode & 07777,
                key_file);
    }
    else if (env != nullptr && *env == '\0')
        return core::fail(core::ErrorCode::InvalidArgument,
                          "PLIANT_PASSPHRASE is set but empty: that would leave the session open "
                          "to anyone; give it a value, or unset it");
    else if (env != nullptr)
        key = net::derive_key(env);
    if (!key)
        return std::optional<net::SecretKey>();
    if (!*key)
        return core::fail((*key).error().code, (*key).error().message);
    return std::optional<net::SecretKey>(**key);
}

std::unique_ptr<net::Transport> secure_or_plain(std::unique_ptr<net::Transport> inner,
                                                const std::optional<net::SecretKey>& secret)
{
    if (!secret)
    {
        spdlog::warn(
            "no --passphrase, --key-file or PLIANT_PASSPHRASE: the session is neither "
            "encrypted nor authenticated");
        return inner;
    }
    spdlog::info("datagrams are authenticated and encrypted (ChaCha20-Poly1305)");
    return std::make_unique<net::SecureTransport>(std::move(inner), *secret);
}

core::Result<std::unique_ptr<net::Transport>> secure_or_plain(std::unique_ptr<net::Transport> inner,
                                                              const std::string& passphrase,
                                                              const std::string& key_file)
{
    auto secret = session_secret(passphrase, key_file);
    if (!secret)
        return core::fail(secret.error().code, secret.error().message);
    return secure_or_plain(std::move(inner), *secret);
}

std::string join_failure_message(const std::string& master, const session::JoinFailure& f,
                                 bool secured)
{
    const std::string why = std::string(" (reason ") + std::string(net::to_string(f.reason)) + ")";
    const std::string head = "join: " + master + " ";
    switch (f.reason)
    {
    case net::DisconnectReason::Refused:
        return head + "refused the connection" + why +
               (secured ? ": it has another --passphrase or --key-file (or PLIANT_PASSPHRASE)"
                        : ": it may need a --passphrase or --key-file (or PLIANT_PASSPHRASE)") +
               ", or it is a peer of the session but not its master (join the master's address;"
               " after a failover, the lowest-id participant's), or no pliant session listens"
               " there (another program answers that port)";
    case net::DisconnectReason::TooManyBadDatagrams:
        return head + "and this peer could not read each other's datagrams" + why +
               (secured ? ": this peer has a secret and the master seemingly none; give both"
                          " the same --passphrase or --key-file, or neither"
                        : ": the master seemingly has a --passphrase or --key-file and this peer"
                          " none; give this peer the same one (or PLIANT_PASSPHRASE)");
    case net::DisconnectReason::TimedOut:
        if (f.connected)
            return head + "stopped answering before it welcomed this peer" + why +
                   ": it may have crashed, or be no longer the master";
        return head + "never answered" + why +
               ": check the address and port, that `pliant host` runs there (after a failover,"
               " join the new master), and that no firewall drops UDP to it" +
               (secured ? ", and that the master has the same --passphrase or --key-file" : "");
    case net::DisconnectReason::ProtocolMismatch:
        return head + "speaks another protocol" + why +
               ": run the same pliant version on every peer";
    case net::DisconnectReason::WrongSession:
        return head + "took this peer's datagrams for another session's" + why +
               ": it may be a new session at the same address; start this peer again to join it";
    case net::DisconnectReason::SessionFull:
        return head + "has no room for another peer" + why +
               ": all its peer slots (64) are taken, or this machine's address holds 16 "
               "connections to it already; try again when a peer has left";
    case net::DisconnectReason::Shutdown: return head + "was ending the session" + why;
    default: return head + "closed the connection before the model arrived" + why;
    }
}

}  // namespace pliant::cli
