// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// The remesh driver: runs the phases, times them, and assembles the report. Holds no
// algorithm of its own.

#include <pliant/remesh/intersections.h>
#include <pliant/remesh/remesh.h>
#include <pliant/remesh/sample.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

namespace pliant::remesh
{
namespace
{

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string method_name(SphereMethod m)
{
    switch (m)
    {
    case SphereMethod::SpringEmbedder: return "spring-embedder";
    case SphereMethod::CoarseToFine: return "coarse-to-fine";
    case SphereMethod::Auto: break;
    }
    return "auto";
}

std::string num(double v)
{
    if (!std::isfinite(v))
        return "null";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return buf;
}

}  // namespace

core::Result<RemeshResult> remesh(const mesh::TriMesh& input, const RemeshSettings& settings,
                                  core::ProgressSink* progress)
{
    const auto start = Clock::now();
    auto grid = core::TetraGrid::create(settings.level);
    if (!grid)
        return grid.error();
    QualityReport report;
    report.level = settings.level;
    report.input_vertices = input.positions.size();
    report.input_faces = input.faces.size();

    // the sphere map needs outward faces; an inward-facing (but consistent) mesh is flipped
    const mesh::TriMesh* m = &input;
    mesh::TriMesh flipped;
    if (signed_volume(input) < 0.0)
    {
        flipped = input;
        for (auto& f : flipped.faces)
            std::swap(f[1], f[2]);
        m = &flipped;
        report.input_flipped = true;
    }

    auto t0 = Clock::now();
    // a coarse input is mapped, sampled and untangled split into more faces (the same surface)
    mesh::TriMesh split;
    const mesh::TriMesh* mm = m;
    if (m->faces.size() < settings.min_map_faces)
    {
        split = split_for_map(*m, settings.min_map_faces);
        mm = &split;
    }
    auto map = map_to_sphere(*mm, settings.sphere, progress);
    if (!map)
        return map.error();
    report.phases.push_back({"sphere map", seconds_since(t0)});
    report.sphere_method = method_name(map->method_used);
    report.gnomonic_folds = map->gnomonic_folds;
    report.spring_folds = map->spring_folds;
    report.inverted_mesh = count_inverted(mm->faces, map->points);
    report.rms_stretch = map->rms_stretch;
    report.stretch_efficiency = map->stretch_efficiency;

    t0 = Clock::now();
    const core::Vec3Field<double> domain = core::sphere_domain(*grid, settings.domain_map);
    report.domain_map = std::string(core::to_string(settings.domain_map));
    report.inverted_domain = count_inverted_domain(*grid, domain);
    report.phases.push_back({"domain map", seconds_since(t0)});
    if (report.inverted_mesh > 0 || report.inverted_domain > 0)
        return core::fail(core::ErrorCode::InvertedTriangles,
                          "remesh: " + std::to_string(report.inverted_mesh) +
                              " inverted mesh triangles, " +
                              std::to_string(report.inverted_domain) +
                              " inverted domain triangles on the sphere");

    if (core::stop_requested(progress))
        return core::cancelled("remesh", "domain map");
    t0 = Clock::now();
    SampleStats stats;
    auto positions = settings.sampler ? settings.sampler(*grid, domain, *mm, map->points)
                                      : sample_surface(*grid, domain, *mm, map->points, &stats);
    if (!positions)
        return positions.error();
    report.brute_force_locations = stats.brute_force;
    report.sampler = settings.sampler ? settings.sampler_name : std::string("cpu");
    report.phases.push_back({"sample", seconds_since(t0)});
    if (progress != nullptr)
        progress->update("sample", 1.0);

    // folds and intersections the sampling made, repaired by moving sample points
    t0 = Clock::now();
    if (progress != nullptr)
        progress->update("untangle", 0.0);
    core::Vec3Field<double> points = domain;
    auto untangled =
        untangle_samples(*grid, *mm, map->points, points, *positions, settings.untangle, progress);
    if (!untangled)
        return untangled.error();
    report.untangle = *untangled;
    if (settings.check_input)
    {
        report.input_intersections = count_self_intersections(*m, progress);
        report.input_checked = true;
    }
    if (core::stop_requested(progress))
        return core::cancelled("remesh", "untangle");
    report.phases.push_back({"untangle", seconds_since(t0)});
    if (progress != nullptr)
        progress->update("untangle", 1.0);

    const mesh::TriMesh out = grid_surface(*grid, *positions);
    report.output_vertices = out.positions.size();
    report.output_faces = out.faces.size();
    report.areas = area_spread(out);
    if (settings.measure)
    {
        t0 = Clock::now();
        if (progress != nullptr)
            progress->update("measure", 0.0);
        report.distance = surface_distance(*m, out, settings.distance, progress);
        if (core::stop_requested(progress))
            return core::cancelled("remesh", "measure");
        report.measured = true;
        report.phases.push_back({"measure", seconds_since(t0)});
        if (progress != nullptr)
            progress->update("measure", 1.0);
    }
    report.total_seconds = seconds_since(start);
    return RemeshResult{std::move(*grid), std::move(*positions), std::move(report)};
}

std::string to_json(const QualityReport& r)
{
    std::string s = "{\n";
    auto kv = [&s](const char* k, const std::string& v, bool comma = true)
    { s += std::string("  \"") + k + "\": " + v + (comma ? ",\n" : "\n"); };
    kv("level", std::to_string(r.level));
    kv("input_vertices", std::to_string(r.input_vertices));
    kv("input_faces", std::to_string(r.input_faces));
    kv("output_vertices", std::to_string(r.output_vertices));
    kv("output_faces", std::to_string(r.output_faces));
    kv("input_flipped", r.input_flipped ? "true" : "false");
    kv("sphere_method", "\"" + r.sphere_method + "\"");
    kv("gnomonic_folds", std::to_string(r.gnomonic_folds));
    kv("spring_folds", std::to_string(r.spring_folds));
    kv("inverted_mesh_triangles", std::to_string(r.inverted_mesh));
    kv("inverted_domain_triangles", std::to_string(r.inverted_domain));
    kv("domain_map", "\"" + r.domain_map + "\"");
    kv("rms_stretch", num(r.rms_stretch));
    kv("l2_stretch_efficiency", num(r.stretch_efficiency));
    if (r.input_checked)
        kv("input_self_intersections", std::to_string(r.input_intersections));
    kv("folded_triangles_sampled", std::to_string(r.untangle.folded_sampled));
    kv("self_intersections_sampled", std::to_string(r.untangle.intersections_sampled));
    kv("folded_triangles", std::to_string(r.untangle.folded));
    kv("self_intersections", std::to_string(r.untangle.intersections));
    kv("untangle_moved_nodes", std::to_string(r.untangle.moved_nodes));
    kv("untangle_rounds", std::to_string(r.untangle.rounds));
    kv("untangle_patch_passes", std::to_string(r.untangle.patch_passes));
    if (r.measured)
    {
        const SurfaceDistance& d = r.distance;
        kv("bbox_diagonal", num(d.diagonal));
        kv("rms_distance", num(d.rms));
        kv("hausdorff_distance", num(d.hausdorff));
        kv("rms_relative", num(d.rms_relative));
        kv("hausdorff_relative", num(d.hausdorff_relative));
        kv("psnr_db", num(d.psnr_db));
        kv("samples_input_to_output", std::to_string(d.reference_to_other.samples));
        kv("samples_output_to_input", std::to_string(d.other_to_reference.samples));
        kv("rms_input_to_output", num(d.reference_to_other.rms));
        kv("rms_output_to_input", num(d.other_to_reference.rms));
        kv("max_input_to_output", num(d.reference_to_other.max));
        kv("max_output_to_input", num(d.other_to_reference.max));
    }
    kv("area_min_over_max", num(r.areas.min_over_max));
    kv("area_cv", num(r.areas.cv));
    kv("brute_force_locations", std::to_string(r.brute_force_locations));
    kv("sampler", "\"" + r.sampler + "\"");
    std::string phases = "{";
    for (std::size_t i = 0; i < r.phases.size(); ++i)
        phases += (i ? ", \"" : "\"") + r.phases[i].name + "\": " + num(r.phases[i].seconds);
    phases += "}";
    kv("phase_seconds", phases);
    kv("total_seconds", num(r.total_seconds), false);
    s += "}\n";
    return s;
}

std::string to_text(const QualityReport& r)
{
    char buf[512];
    std::string s;
    std::snprintf(buf, sizeof buf,
                  "level %d: %zu vertices, %zu faces (input %zu vertices, %zu faces)\n", r.level,
                  r.output_vertices, r.output_faces, r.input_vertices, r.input_faces);
    s += buf;
    if (r.input_flipped)
        s += "input: its faces face inward; the output faces outward (input_flipped)\n";
    std::snprintf(buf, sizeof buf,
                  "sphere map: %s (gnomonic folds %zu), domain map: %s, inverted triangles: mesh "
                  "%zu, domain %zu\n",
                  r.sphere_method.c_str(), r.gnomonic_folds, r.domain_map.c_str(), r.inverted_mesh,
                  r.inverted_domain);
    s += buf;
    std::snprintf(buf, sizeof buf, "rms stretch %.4f, L2 stretch efficiency %.4f\n", r.rms_stretch,
                  r.stretch_efficiency);
    s += buf;
    std::snprintf(buf, sizeof buf,
                  "output: %zu folded triangles, %zu intersecting triangle pairs (as sampled %zu "
                  "and %zu; untangling moved %zu nodes in %d rounds)",
                  r.untangle.folded, r.untangle.intersections, r.untangle.folded_sampled,
                  r.untangle.intersections_sampled, r.untangle.moved_nodes, r.untangle.rounds);
    s += buf;
    if (r.input_checked)
    {
        std::snprintf(buf, sizeof buf, "; input: %zu intersecting pairs", r.input_intersections);
        s += buf;
    }
    s += "\n";
    if (r.measured)
    {
        std::snprintf(buf, sizeof buf,
                      "distance: RMS %.4g%% of diagonal, Hausdorff %.4g%%, PSNR %.2f dB\n",
                      100.0 * r.distance.rms_relative, 100.0 * r.distance.hausdorff_relative,
                      r.distance.psnr_db);
        s += buf;
    }
    std::snprintf(buf, sizeof buf, "triangle areas: min/max %.4g, cv %.4f\n", r.areas.min_over_max,
                  r.areas.cv);
    s += buf;
    s += "sampler: " + r.sampler + "\n";
    s += "time:";
    for (const PhaseTime& p : r.phases)
    {
        std::snprintf(buf, sizeof buf, " %s %.3f s,", p.name.c_str(), p.seconds);
        s += buf;
    }
    std::snprintf(buf, sizeof buf, " total %.3f s\n", r.total_seconds);
    s += buf;
    return s;
}

}  // namespace pliant::remesh
