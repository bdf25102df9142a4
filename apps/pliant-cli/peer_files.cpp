// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "peer_files.h"

#include <pliant/core/grid_io.h>
#include <pliant/session/recording.h>

#include <string>
#include <utility>

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

core::Result<void> save_master_recording(const session::Session& master,
                                         const std::filesystem::path& path)
{
    if (master.model() == nullptr)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "cannot save '" + path.string() + "': the session has no model");
    session::Recording recording = master.recording();
    recording.final_hash =
        session::state_hash(master.model()->grid(), master.display_u(), master.display_v());
    return session::save_recording(path, recording);
}

}  // namespace pliant::cli
