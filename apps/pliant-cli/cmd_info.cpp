// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant info MESH [--json]`: imports a mesh, prints its statistics and the verdict of the input
// rules (docs/mesh.md). Exit 0 only for a valid closed genus-0 mesh.
#include <pliant/core/error.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>

#include <nlohmann/json.hpp>

#include "cli_common.h"
#include "commands.h"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

namespace pliant::cli
{
namespace
{

struct InfoOptions
{
    std::filesystem::path mesh;
    bool json = false;
};

nlohmann::ordered_json vec_json(const core::Vec3& v)
{
    return nlohmann::ordered_json::array({v.x, v.y, v.z});
}

void print_json(const InfoOptions& opt, const mesh::ImportReport* report, const mesh::MeshStats* s,
                const std::optional<core::Error>& error)
{
    nlohmann::ordered_json j;
    j["file"] = opt.mesh.string();
    j["valid"] = !error.has_value();
    j["error_code"] = error ? nlohmann::ordered_json(std::string(core::to_string(error->code)))
                            : nlohmann::ordered_json(nullptr);
    j["error_value"] = error ? nlohmann::ordered_json(static_cast<int>(error->code))
                             : nlohmann::ordered_json(nullptr);
    j["message"] =
        error ? error->message : std::string("valid: closed, connected, genus-0 2-manifold");
    if (report != nullptr)
    {
        j["format"] = report->format;
        j["file_vertices"] = report->file_vertices;
        j["welded"] = report->welded;
        j["unreferenced_dropped"] = report->unreferenced_dropped;
        j["polygons_triangulated"] = report->polygons_triangulated;
    }
    if (s != nullptr)
    {
        j["vertices"] = s->vertices;
        j["faces"] = s->faces;
        j["edges"] = s->edges;
        j["components"] = s->components;
        j["boundary_edges"] = s->boundary_edges;
        j["boundary_loops"] = s->boundary_loops;
        j["non_manifold_edges"] = s->non_manifold_edges;
        j["non_manifold_vertices"] = s->non_manifold_vertices;
        j["degenerate_faces"] = s->degenerate_faces;
        j["euler_characteristic"] = s->euler_characteristic;
        j["genus"] = s->genus ? nlohmann::ordered_json(*s->genus) : nlohmann::ordered_json(nullptr);
        j["bbox_min"] = vec_json(s->bbox_min);
        j["bbox_max"] = vec_json(s->bbox_max);
        j["bbox_diagonal"] = s->bbox_diagonal;
        j["surface_area"] = s->surface_area;
    }
    // A message may quote a file's bytes that are not UTF-8: shown as U+FFFD, not thrown.
    std::cout << j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << '\n';
}

void print_text(const InfoOptions& opt, const mesh::ImportReport& r, const mesh::MeshStats& s,
                const std::optional<core::Error>& error)
{
    const auto row = [](const char* key, const std::string& value)
    { std::printf("  %-22s %s\n", key, value.c_str()); };
    const auto n = [](std::size_t v) { return std::to_string(v); };
    std::printf("%s (%s)\n", opt.mesh.string().c_str(), r.format.c_str());
    row("vertices", n(s.vertices) + "  (file " + n(r.file_vertices) + ", " + n(r.welded) +
                        " reader vertices welded" + ", unreferenced dropped " +
                        n(r.unreferenced_dropped) + ")");
    row("faces", n(s.faces) + "  (" + n(r.polygons_triangulated) + " polygons triangulated)");
    row("edges", n(s.edges));
    row("components", n(s.components));
    row("boundary edges", n(s.boundary_edges) + "  (" + n(s.boundary_loops) + " loops)");
    row("non-manifold edges", n(s.non_manifold_edges));
    row("non-manifold vertices", n(s.non_manifold_vertices));
    row("Euler characteristic", std::to_string(s.euler_characteristic));
    row("genus", s.genus ? std::to_string(*s.genus)
                         : std::string("- (defined only for a closed connected 2-manifold)"));
    char diag[64];
    std::snprintf(diag, sizeof diag, "%.6g", s.bbox_diagonal);
    row("bbox diagonal", diag);
    row("verdict", error ? "INVALID: " + error->message
                         : std::string("valid: closed, connected, genus-0 2-manifold"));
}

int run_info(const InfoOptions& opt, const GlobalOptions& global)
{
    mesh::ImportReport report;
    auto m = mesh::import_mesh(opt.mesh, &report);
    if (!m)
    {
        if (opt.json)
            print_json(opt, nullptr, nullptr, m.error());
        return cli::report(m.error());
    }
    const mesh::MeshStats stats = mesh::analyze(*m);
    const auto verdict = mesh::validate(*m, opt.mesh.filename().string());
    std::optional<core::Error> error;
    if (!verdict)
        error = verdict.error();
    if (opt.json)
        print_json(opt, &report, &stats, error);
    else if (!global.quiet)  // -q: the exit status is the answer, an error its reason
        print_text(opt, report, stats, error);
    return error ? cli::report(*error) : 0;
}

void add_info_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<InfoOptions>();
    CLI::App* cmd = app.add_subcommand(
        "info",
        "Check a mesh: counts, topology and whether pliant accepts it.\n\n"
        "Reads OBJ, OFF, PLY (ascii/binary), STL (ascii/binary) or glTF 2 (.gltf/.glb); merges\n"
        "all meshes, triangulates polygons, welds exactly coincident vertices and drops unused\n"
        "ones. Then checks, in this order: vertex indices, finite coordinates, no degenerate\n"
        "faces, every edge on at most two faces, closed (no boundary edges), no pinched vertices,\n"
        "consistent orientation, one connected component, genus 0 (Euler characteristic 2).\n"
        "The first rule that fails is the verdict (docs/mesh.md lists them all).\n\n"
        "Exit codes: 0 valid closed genus-0 mesh; 1 unreadable file or a failed rule (the\n"
        "message says which, with numbers and a location); 2 usage error. With -q only an\n"
        "error is printed (--json still prints its object).\n\n"
        "Example:\n"
        "  pliant info data/spot.obj\n"
        "  pliant info scan.ply --json | jq .genus");
    cmd->add_option("mesh", opt->mesh, "Mesh file to check")->required();
    cmd->add_flag("--json", opt->json,
                  "Print one JSON object on stdout (fields: valid, error_code, message, vertices, "
                  "faces, edges, components, boundary_edges, euler_characteristic, genus (null "
                  "when undefined), bbox_diagonal, ...)");
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_info(*opt, global); }));
}

const CommandRegistrar k_register_info{{"info", 10, &add_info_command}};

}  // namespace
}  // namespace pliant::cli
