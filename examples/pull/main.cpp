// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// pull: the library's stages in one program (docs/library.md). Reads a closed genus-0 mesh,
// remeshes it onto the tetrahedral grid, pulls the face that lies farthest along +x outward for
// half a second of simulated time, and writes the deformed surface, refined one level by
// butterfly subdivision, as a mesh file.
//
//   pull INPUT OUTPUT [LEVEL]     e.g. pull spot.obj pulled.obj 5
#include <pliant/core/vec3.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/remesh/remesh.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>
#include <pliant/subdiv/refine.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace
{

int fail(const pliant::core::Error& error)
{
    std::fprintf(stderr, "pull: %s\n", error.message.c_str());
    return 1;
}

}  // namespace

int main(int argc, char** argv)
{
    using namespace pliant;
    if (argc < 3 || argc > 4)
    {
        std::fprintf(stderr, "usage: pull INPUT OUTPUT [LEVEL]\n");
        return 2;
    }
    const std::string input = argv[1];
    const std::string output = argv[2];
    const int level = argc == 4 ? std::atoi(argv[3]) : 5;

    // 1. Import and check the mesh: the library trusts what passed `validate`.
    auto mesh = mesh::import_mesh(input);
    if (!mesh)
        return fail(mesh.error());
    if (auto ok = mesh::validate(*mesh, input); !ok)
        return fail(ok.error());

    // 2. Remesh onto the grid (the report's distance measurement is skipped: it takes as long
    //    as the remeshing).
    remesh::RemeshSettings settings;
    settings.level = level;
    settings.measure = false;
    auto remeshed = remesh::remesh(*mesh, settings);
    if (!remeshed)
        return fail(remeshed.error());
    const core::TetraGrid& grid = remeshed->grid;
    std::printf("remeshed %s: %zu faces -> level %d, %zu vertices\n", input.c_str(),
                mesh->face_count(), grid.level(), grid.unique_count());

    // 3. A membrane on the grid: tension 1 N/m, density 1 kg/m^2, some damping.
    sim::MembraneSettings material;
    material.beta = 2.0;
    auto model = sim::MembraneModel::create(grid, remeshed->positions, material);
    if (!model)
        return fail(model.error());
    sim::MembraneState state = sim::MembraneState::at_rest(grid);
    sim::Rkf45Workspace workspace(*model);

    // 4. Pull the face farthest along +x outward for 0.5 s.
    const auto faces = grid.triangles();
    const auto nodes = grid.node_of_unique();
    const auto& rest = model->rest_positions();
    std::size_t pulled = 0;
    double best = -1e300;
    core::Vec3 outward{};
    for (std::size_t f = 0; f < faces.size(); ++f)
    {
        core::Vec3 centre{};
        for (const std::uint32_t v : faces[f])
        {
            const core::NodeIndex n = nodes[v];
            centre += core::Vec3{rest[0][n], rest[1][n], rest[2][n]};
        }
        if (centre.x > best)
        {
            best = centre.x;
            pulled = f;
            outward = core::normalized(centre / 3.0);
        }
    }
    const sim::Force pull{static_cast<std::int64_t>(pulled), {}, 0.0, outward * 0.5};
    const sim::AdvanceReport run = sim::advance_to(*model, state, workspace, 0.5, {&pull, 1});
    if (!run.reached)
    {
        std::fprintf(stderr, "pull: the simulation stopped at t = %g s\n", state.time);
        return 1;
    }
    double largest = 0.0;
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
            largest = std::max(largest, std::abs(state.u.at(x, y)));
    std::printf("pulled face %zu with 0.5 N for 0.5 s: %llu steps, largest displacement %.6g m\n",
                pulled, static_cast<unsigned long long>(run.steps), largest);

    // 5. The deformed surface p = P + u N, one level finer by butterfly subdivision.
    core::Vec3Field<double> deformed;
    model->positions(state.u, deformed);
    auto fine = subdiv::refine_levels(deformed, 1);
    if (!fine)
        return fail(fine.error());
    auto fine_grid = core::TetraGrid::create(level + 1);
    if (!fine_grid)
        return fail(fine_grid.error());
    const mesh::TriMesh surface = mesh::from_grid(*fine_grid, *fine);
    if (auto ok = mesh::export_mesh(output, surface); !ok)
        return fail(ok.error());
    std::printf("wrote %s: %zu vertices, %zu faces (level %d)\n", output.c_str(),
                surface.vertex_count(), surface.face_count(), level + 1);
    return 0;
}
