// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "peer_files.h"

#include <pliant/core/grid_io.h>
#include <pliant/session/recording.h>

#include <string>
#include <utility>
#include <vector>

namespace pliant::cli
{

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
    if (out.covered == nodes.size())
        mask.clear();
    recording.hash_mask = std::move(mask);
    recording.final_hash =
        out.covered == 0
            ? 0
            : session::state_hash(grid, master.state().u, master.state().v, recording.hash_mask);
    if (auto saved = session::save_recording(path, recording); !saved)
        return saved.error();
    return out;
}

}  // namespace pliant::cli
