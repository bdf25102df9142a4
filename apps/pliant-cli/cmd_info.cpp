// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant info MESH|GRID|RECORDING [--json]`: imports a mesh, prints its statistics and the
// verdict of the input rules (docs/mesh.md); or reads a .pgrid grid file and prints its level,
// channels, surface and state (docs/grid-format.md); or reads a .prec recording and prints its
// model, length and force lists (docs/session.md §9). Exit 0 only for a valid closed genus-0
// mesh, a grid file whose surface the membrane accepts, or a recording `replay` can replay.
#include <pliant/core/error.h>
#include <pliant/core/grid_io.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/session/recording.h>
#include <pliant/session/session.h>
#include <pliant/sim/membrane.h>

#include <nlohmann/json.hpp>

#include "cli_common.h"
#include "commands.h"
#include "peer_files.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

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
        // Every ImportReport field (docs/mesh.md): the scene's meshes, the file's and
        // Assimp's counts, and what the merge changed.
        j["format"] = report->format;
        j["meshes"] = report->meshes;
        j["file_vertices"] = report->file_vertices;
        j["raw_vertices"] = report->raw_vertices;
        j["raw_faces"] = report->raw_faces;
        j["welded"] = report->welded;
        j["unreferenced_dropped"] = report->unreferenced_dropped;
        j["polygons_triangulated"] = report->polygons_triangulated;
        j["non_triangles_dropped"] = report->non_triangles_dropped;
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
        j["unreferenced_vertices"] = s->unreferenced_vertices;
        j["bad_index_faces"] = s->bad_index_faces;
        j["non_finite_vertices"] = s->non_finite_vertices;
        j["inconsistent_edges"] = s->inconsistent_edges;
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
    std::printf("%s (%s)\n", printable(opt.mesh.string()).c_str(), r.format.c_str());
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

// ---- grid files ----

/// The keys every `info --json` of a pliant file begins with: the file, its format and the
/// verdict.
nlohmann::ordered_json verdict_json(const InfoOptions& opt, const char* format,
                                    const std::optional<core::Error>& error, const char* valid)
{
    nlohmann::ordered_json j;
    j["file"] = opt.mesh.string();
    j["format"] = format;
    j["valid"] = !error.has_value();
    j["error_code"] = error ? nlohmann::ordered_json(std::string(core::to_string(error->code)))
                            : nlohmann::ordered_json(nullptr);
    j["error_value"] = error ? nlohmann::ordered_json(static_cast<int>(error->code))
                             : nlohmann::ordered_json(nullptr);
    j["message"] = error ? error->message : std::string(valid);
    return j;
}

/// Range of one channel over the canonical nodes, and where its largest magnitude is.
struct ChannelRange
{
    std::string name;
    double min = 0.0;
    double max = 0.0;
    double max_abs = 0.0;
    core::GridCoord at_max_abs{};
};

struct GridInfo
{
    const core::GridFile* file = nullptr;
    std::optional<core::TetraGrid> grid;
    std::optional<mesh::MeshStats> surface;   ///< of px, py, pz as a mesh (mesh::from_grid)
    std::vector<ChannelRange> ranges;         ///< every channel but px, py, pz and owner
    std::map<long long, std::size_t> owners;  ///< surface vertices per owner id
    /// The first owner value that is no whole number (ids are labels; counted rounded above).
    std::optional<OwnerProblem> bad_owner;  ///< the first owner value that is not a peer id
    std::size_t bad_owners = 0;             ///< vertices whose owner value is not a peer id
};

GridInfo describe(const core::GridFile& file)
{
    GridInfo info;
    info.file = &file;
    auto grid = core::TetraGrid::create(file.level);
    if (!grid)
        return info;  // decode_grid accepts levels 1..10 only
    info.grid = std::move(*grid);
    const core::TetraGrid& g = *info.grid;
    if (auto positions = core::geometry_of(g, file))
        info.surface = mesh::analyze(mesh::from_grid(g, *positions));
    for (const core::NamedField& f : file.fields)
    {
        if (f.name == "px" || f.name == "py" || f.name == "pz")
            continue;
        if (f.name == "owner")
        {
            info.bad_owner = owner_channel_problem(g, f.values);
            for (const core::NodeIndex n : g.node_of_unique())
            {
                const double v = f.values[n];
                if (is_owner_value(v))
                    ++info.owners[std::llround(v)];
                else
                    ++info.bad_owners;
            }
            continue;
        }
        ChannelRange r{f.name, f.values[g.node_of_unique()[0]], f.values[g.node_of_unique()[0]]};
        for (const core::NodeIndex n : g.node_of_unique())
        {
            const double v = f.values[n];
            r.min = std::min(r.min, v);
            r.max = std::max(r.max, v);
            if (std::abs(v) > r.max_abs)
            {
                r.max_abs = std::abs(v);
                r.at_max_abs = g.coord(n);
            }
        }
        info.ranges.push_back(r);
    }
    return info;
}

/// Whether the membrane accepts the file's surface as rest geometry (what simulate, host and
/// view need): positions present, finite, a normal at every node, no zero-area triangle.
std::optional<core::Error> grid_verdict(const std::string& path, const GridInfo& info)
{
    if (!info.surface)
        return core::Error{core::ErrorCode::BadGrid,
                           path + ": no surface: the channels px, py, pz are not all there"};
    auto positions = core::geometry_of(*info.grid, *info.file);
    auto model = sim::MembraneModel::create(*info.grid, *positions, sim::MembraneSettings{});
    if (!model)
        return in_grid_file(path, model.error());
    if (info.bad_owner)
        return core::Error{core::ErrorCode::BadGrid, path + ": " + info.bad_owner->message};
    return std::nullopt;
}

constexpr const char* k_grid_valid =
    "valid: a closed surface the membrane accepts as rest geometry";
/// A state file (u and v: a simulate frame, `--save`, `replay -o`) is valid, but as a state:
/// the commands that take a rest GRID refuse it (its positions are the deformed surface).
constexpr const char* k_state_valid =
    "valid: a simulated state (u, v) on a closed surface; resume it with --resume and its rest "
    "grid (as GRID, simulate, host and view refuse a state)";

const char* grid_valid(const GridInfo& info)
{
    return info.file && holds_state(*info.file) ? k_state_valid : k_grid_valid;
}

std::string channel_names(const core::GridFile& file)
{
    std::string names;
    for (const core::NamedField& f : file.fields)
        names += (names.empty() ? "" : " ") + f.name;
    return names;
}

void print_grid_json(const InfoOptions& opt, const GridInfo* info,
                     const std::optional<core::Error>& error)
{
    nlohmann::ordered_json j =
        verdict_json(opt, "pgrid", error, info != nullptr ? grid_valid(*info) : k_grid_valid);
    if (info != nullptr && info->grid)
    {
        const core::TetraGrid& g = *info->grid;
        j["level"] = g.level();
        j["nx"] = g.nx();
        j["ny"] = g.ny();
        j["vertices"] = g.unique_count();
        j["faces"] = g.face_count();
        auto channels = nlohmann::ordered_json::array();
        for (const core::NamedField& f : info->file->fields)
            channels.push_back(f.name);
        j["channels"] = channels;
        if (info->surface)
        {
            j["bbox_min"] = vec_json(info->surface->bbox_min);
            j["bbox_max"] = vec_json(info->surface->bbox_max);
            j["bbox_diagonal"] = info->surface->bbox_diagonal;
            j["surface_area"] = info->surface->surface_area;
            j["degenerate_faces"] = info->surface->degenerate_faces;
        }
        for (const ChannelRange& r : info->ranges)
            j["ranges"][r.name] = {{"min", r.min},
                                   {"max", r.max},
                                   {"max_abs", r.max_abs},
                                   {"at", {r.at_max_abs.x, r.at_max_abs.y}}};
        if (!info->owners.empty() || info->bad_owner)
        {
            auto owners = nlohmann::ordered_json::object();
            for (const auto& [id, count] : info->owners)
                owners[std::to_string(id)] = count;
            j["owners"] = owners;
            if (info->bad_owner)
                j["owner_not_a_peer_id"] = {{"vertices", info->bad_owners},
                                            {"value", info->bad_owner->value},
                                            {"at", {info->bad_owner->at.x, info->bad_owner->at.y}}};
        }
    }
    std::cout << j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << '\n';
}

void print_grid_text(const InfoOptions& opt, const GridInfo& info,
                     const std::optional<core::Error>& error)
{
    const auto row = [](const char* key, const std::string& value)
    { std::printf("  %-22s %s\n", key, value.c_str()); };
    const auto n = [](std::size_t v) { return std::to_string(v); };
    const auto num = [](double v)
    {
        char text[32];
        std::snprintf(text, sizeof text, "%.6g", v);
        return std::string(text);
    };
    const core::TetraGrid& g = *info.grid;
    std::printf("%s (pliant grid, level %d)\n", printable(opt.mesh.string()).c_str(), g.level());
    row("nodes", std::to_string(g.nx()) + " x " + std::to_string(g.ny()) + " = " +
                     n(static_cast<std::size_t>(g.nx()) * static_cast<std::size_t>(g.ny())) +
                     "  (" + n(g.unique_count()) + " surface vertices, " + n(g.face_count()) +
                     " faces)");
    row("channels", channel_names(*info.file));
    if (info.surface)
    {
        row("bbox diagonal", num(info.surface->bbox_diagonal));
        row("surface area", num(info.surface->surface_area));
    }
    for (const ChannelRange& r : info.ranges)
        row(r.name.c_str(), num(r.min) + " .. " + num(r.max) + "  (largest |" + r.name + "| " +
                                num(r.max_abs) + " at node (" + std::to_string(r.at_max_abs.x) +
                                ", " + std::to_string(r.at_max_abs.y) + "))");
    if (!info.owners.empty() || info.bad_owner)
    {
        // -1 and 65535 mean "no owner" (docs/grid-format.md): one entry after the peers, not
        // "peer -1".
        std::string owners;
        std::size_t unowned = 0;
        for (const auto& [id, count] : info.owners)
            if (id == -1 || id == 65535)
                unowned += count;
            else
                owners += (owners.empty() ? "" : ", ") + std::string("peer ") + std::to_string(id) +
                          ": " + n(count);
        if (unowned > 0)
            owners += (owners.empty() ? "" : ", ") + std::string("no owner: ") + n(unowned);
        if (info.bad_owner)
            owners += std::string(owners.empty() ? "" : "  ") + "(" + n(info.bad_owners) +
                      (info.bad_owners == 1 ? " vertex holds" : " vertices hold") +
                      " no peer id, e.g. " + info.bad_owner->value_text + " at node (" +
                      std::to_string(info.bad_owner->at.x) + ", " +
                      std::to_string(info.bad_owner->at.y) + "))";
        row("owner (vertices)", owners);
    }
    row("verdict", error ? "INVALID: " + error->message : std::string(grid_valid(info)));
}

int run_grid_info(const InfoOptions& opt, const GlobalOptions& global)
{
    auto file = core::load_grid(opt.mesh);
    if (!file)
    {
        if (opt.json)
            print_grid_json(opt, nullptr, file.error());
        return cli::report(file.error());
    }
    const GridInfo info = describe(*file);
    const std::optional<core::Error> error = grid_verdict(opt.mesh.string(), info);
    if (opt.json)
        print_grid_json(opt, &info, error);
    else if (!global.quiet)
        print_grid_text(opt, info, error);
    return error ? cli::report(*error) : 0;
}

// ---- recordings ----

struct RecordingInfo
{
    const session::Recording* recording = nullptr;
    std::optional<session::DecodedModel> model;
    std::map<unsigned, std::size_t> lists_per_sender;
    double largest_force = 0.0;  ///< N, over every force of every list
    std::size_t hash_nodes = 0;
};

RecordingInfo describe(const session::Recording& recording, std::optional<core::Error>& error,
                       const std::string& path)
{
    RecordingInfo info;
    info.recording = &recording;
    for (const session::ForceRecord& r : recording.forces)
    {
        ++info.lists_per_sender[r.sender];
        for (const net::UserForce& f : r.forces)
            info.largest_force = std::max(
                info.largest_force, std::sqrt(f.force[0] * f.force[0] + f.force[1] * f.force[1] +
                                              f.force[2] * f.force[2]));
    }
    auto model = session::decode_model(recording.model);
    if (!model)
    {
        error = core::Error{model.error().code, path + ": its model: " + model.error().message};
        return info;
    }
    info.model = std::move(*model);
    info.hash_nodes = session::hash_mask_count(info.model->model.grid(), recording.hash_mask);
    if (!info.model->model.settings().fixed_step)
        error = core::Error{core::ErrorCode::InvalidArgument,
                            path +
                                ": the session did not step with a fixed step, so `replay` "
                                "refuses it"};
    return info;
}

const char* coupling_name(session::Coupling c)
{
    return c == session::Coupling::Exact ? "exact" : "fast";
}

std::string hex(std::uint64_t value)
{
    char text[20];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
    return text;
}

constexpr const char* k_recording_valid = "valid: `pliant replay` replays it";

void print_recording_json(const InfoOptions& opt, const RecordingInfo* info,
                          const std::optional<core::Error>& error)
{
    nlohmann::ordered_json j = verdict_json(opt, "prec", error, k_recording_valid);
    if (info != nullptr)
    {
        const session::Recording& r = *info->recording;
        if (info->model)
        {
            const sim::MembraneModel& m = info->model->model;
            const sim::MembraneSettings& ms = m.settings();
            j["level"] = m.grid().level();
            j["vertices"] = m.grid().unique_count();
            j["faces"] = m.grid().face_count();
            j["coupling"] = coupling_name(info->model->coupling);
            j["fixed_step"] = ms.fixed_step;
            j["fixed_dt"] = ms.fixed_dt;
            j["material"] = {{"T", ms.T},
                             {"rho", ms.rho},
                             {"beta", ms.beta},
                             {"k_f", ms.k_f},
                             {"max_force", ms.max_force}};
            j["simulated_s"] = static_cast<double>(r.final_tick) * ms.fixed_dt;
            j["hash_nodes"] = info->hash_nodes;
        }
        j["final_tick"] = r.final_tick;
        j["final_hash"] = r.final_hash == 0 ? nlohmann::ordered_json(nullptr)
                                            : nlohmann::ordered_json(hex(r.final_hash));
        j["force_lists"] = r.forces.size();
        auto senders = nlohmann::ordered_json::object();
        for (const auto& [id, count] : info->lists_per_sender)
            senders[std::to_string(id)] = count;
        j["senders"] = senders;
        j["largest_force"] = info->largest_force;
    }
    std::cout << j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << '\n';
}

void print_recording_text(const InfoOptions& opt, const RecordingInfo& info,
                          const std::optional<core::Error>& error)
{
    const auto row = [](const char* key, const std::string& value)
    { std::printf("  %-22s %s\n", key, value.c_str()); };
    const auto num = [](double v)
    {
        char text[32];
        std::snprintf(text, sizeof text, "%.6g", v);
        return std::string(text);
    };
    const session::Recording& r = *info.recording;
    std::printf("%s (pliant recording)\n", printable(opt.mesh.string()).c_str());
    if (info.model)
    {
        const sim::MembraneModel& m = info.model->model;
        const sim::MembraneSettings& ms = m.settings();
        row("model", "level " + std::to_string(m.grid().level()) + ", " +
                         std::to_string(m.grid().unique_count()) + " vertices; " +
                         coupling_name(info.model->coupling) + " coupling" +
                         (ms.fixed_step ? ", fixed step " + num(ms.fixed_dt) + " s" : ""));
        row("material", "T " + num(ms.T) + " N/m, rho " + num(ms.rho) + " kg/m^2, beta " +
                            num(ms.beta) + " 1/s, k_f " + num(ms.k_f) + " 1/s^2, force limit " +
                            (ms.max_force > 0.0 ? num(ms.max_force) + " N" : "none"));
        row("length", std::to_string(r.final_tick) + " ticks = " +
                          num(static_cast<double>(r.final_tick) * ms.fixed_dt) + " s simulated");
    }
    else
        row("length", std::to_string(r.final_tick) + " ticks");
    std::string senders;
    for (const auto& [id, count] : info.lists_per_sender)
        senders += (senders.empty() ? "" : ", ") + std::string("peer ") + std::to_string(id) +
                   ": " + std::to_string(count);
    row("force lists", std::to_string(r.forces.size()) +
                           (senders.empty() ? "" : "  (" + senders + ")") + "; largest force " +
                           num(info.largest_force) + " N");
    if (r.final_hash == 0)
        row("final state hash", "none (a replay has nothing to compare with)");
    else if (info.model)
        row("final state hash",
            hex(r.final_hash) + " over " + std::to_string(info.hash_nodes) + " of " +
                std::to_string(info.model->model.grid().unique_count()) + " vertices");
    else
        row("final state hash", hex(r.final_hash));
    row("verdict", error ? "INVALID: " + error->message : std::string(k_recording_valid));
}

int run_recording_info(const InfoOptions& opt, const GlobalOptions& global)
{
    auto recording = session::load_recording(opt.mesh);
    if (!recording)
    {
        if (opt.json)
            print_recording_json(opt, nullptr, recording.error());
        return cli::report(recording.error());
    }
    std::optional<core::Error> error;
    const RecordingInfo info = describe(*recording, error, opt.mesh.string());
    if (opt.json)
        print_recording_json(opt, &info, error);
    else if (!global.quiet)
        print_recording_text(opt, info, error);
    return error ? cli::report(*error) : 0;
}

int run_info(const InfoOptions& opt, const GlobalOptions& global)
{
    if (lower_extension(opt.mesh) == ".pgrid")
        return run_grid_info(opt, global);
    if (lower_extension(opt.mesh) == ".prec")
        return run_recording_info(opt, global);
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
        "Check a mesh, grid file or recording: what it holds and whether pliant accepts it.\n\n"
        "Reads OBJ, OFF, PLY (ascii/binary), STL (ascii/binary) or glTF 2 (.gltf/.glb); merges\n"
        "all meshes, triangulates polygons, welds exactly coincident vertices and drops unused\n"
        "ones. Then checks, in this order: vertex indices, finite coordinates, no degenerate\n"
        "faces, every edge on at most two faces, closed (no boundary edges), no pinched vertices,\n"
        "consistent orientation, one connected component, genus 0 (Euler characteristic 2).\n"
        "The first rule that fails is the verdict (docs/mesh.md lists them all).\n\n"
        "A .pgrid grid file (remesh, refine, simulate frames, replay, demo's final.pgrid,\n"
        "host/join --save) is read and described instead: level, nodes, channels, the\n"
        "surface's size, each other channel's range (u, v) and the owner counts; the verdict is\n"
        "whether the membrane accepts its surface (docs/grid-format.md); one that holds u\n"
        "and v is a simulated state, valid to --resume but not a rest GRID.\n"
        "A .prec recording (host --record, demo's session.prec) is described too: level,\n"
        "coupling, material, length, force lists per peer, the final hash; the verdict is\n"
        "whether `pliant replay` can replay it (docs/session.md §9).\n\n"
        "Exit codes: 0 valid closed genus-0 mesh (usable grid, replayable recording);\n"
        "1 unreadable file or a failed rule (the message says which, with numbers and a\n"
        "location); 2 usage error. With -q only an error is printed (--json still prints its\n"
        "object).\n\n"
        "Example:\n"
        "  pliant info data/spot.obj\n"
        "  pliant info scan.ply --json | jq .genus\n"
        "  pliant info demo-out/final.pgrid\n"
        "  pliant info demo-out/session.prec");
    cmd->add_option("FILE", opt->mesh, "Mesh, .pgrid grid or .prec recording to check")->required();
    cmd->add_flag("--json", opt->json,
                  "Print one JSON object on stdout (fields: valid, error_code, message, vertices, "
                  "faces, edges, components, boundary_edges, euler_characteristic, genus (null "
                  "when undefined), bbox_diagonal, ...; for a grid or a recording the fields "
                  "docs/mesh.md and docs/session.md §9 list)");
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_info(*opt, global); }));
}

const CommandRegistrar k_register_info{{"info", 10, &add_info_command}};

}  // namespace
}  // namespace pliant::cli
