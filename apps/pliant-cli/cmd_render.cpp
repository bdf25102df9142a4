// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant render GRID|MESH -o shot.png`: a Phong-shaded picture with no display, through an
// offscreen OpenGL context (EGL surfaceless, else OSMesa; docs/rendering.md). A GRID (.pgrid) is
// drawn by the texture path (positions in a float texture, normals from a GPU normal pass), after
// optional butterfly refinement for display (--level-up); any other file is imported as a mesh
// and drawn from a vertex buffer with CPU normals. --frames DIR renders every .pgrid of a folder
// (simulation output) into a numbered PNG sequence with one still camera.
#include <pliant/core/grid_io.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/io.h>
#include <pliant/render/framebuffer.h>
#include <pliant/render/grid_renderer.h>
#include <pliant/render/mesh_renderer.h>
#include <pliant/render/normals.h>
#include <pliant/render/offscreen_context.h>
#include <pliant/subdiv/convolution_plan.h>
#include <pliant/subdiv/refine.h>

#include <spdlog/spdlog.h>

#include "cli_common.h"
#include "commands.h"
#include "peer_files.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace pliant::cli
{
namespace
{

namespace fs = std::filesystem;
using core::ErrorCode;

struct RenderOptions
{
    fs::path input;
    fs::path out;
    fs::path frames;
    std::string size = "1280x720";
    std::string camera;
    std::string color = "none";
    std::string backend = "auto";
    int level_up = 0;
    int samples = 4;
    int owner_depth = 1;
    bool owner_depth_given = false;  ///< --owner-depth on the line (it applies to --color owner)
    double color_range = 0.0;  ///< m; 0: the largest |u| (of the file, or of the whole sequence)
    bool wireframe = false;
};

/// Owner ids per node, and where they came from (printed with --color owner).
struct Owners
{
    std::vector<std::uint16_t> ids;
    std::string source;
};

/// A grid ready to draw: positions (displaced from the rest grid when the file has only "u"),
/// the displacement for colouring, owners per node.
struct GridScene
{
    core::TetraGrid grid;
    core::Vec3Field<double> positions;
    std::optional<core::Field<double>> u;
    std::vector<std::uint16_t> owners;
    std::string owner_source;
};

core::Result<std::array<int, 2>> parse_size(const std::string& text)
{
    int w = 0;
    int h = 0;
    char x = 0;
    int used = 0;  // the whole text must be read: "64x64junk" is not a size
    if (std::sscanf(text.c_str(), "%d%c%d%n", &w, &x, &h, &used) != 3 ||
        static_cast<std::size_t>(used) != text.size() || (x != 'x' && x != 'X') || w < 16 ||
        h < 16 || w > 8192 || h > 8192)
        return core::fail(ErrorCode::InvalidArgument,
                          "render: --size " + text + " is not WxH with 16 <= W, H <= 8192");
    return std::array<int, 2>{w, h};
}

core::Result<render::CameraSettings> parse_camera(const std::string& text)
{
    render::CameraSettings camera;
    if (text.empty())
        return camera;
    double az = 0.0;
    double el = 0.0;
    double dist = 0.0;
    int used2 = 0;  // the whole text must be read, as two numbers or three
    int used3 = 0;
    const int n2 = std::sscanf(text.c_str(), "%lf,%lf%n", &az, &el, &used2);
    const int n3 = std::sscanf(text.c_str(), "%lf,%lf,%lf%n", &az, &el, &dist, &used3);
    const bool three = n3 == 3 && static_cast<std::size_t>(used3) == text.size();
    const bool two = !three && n2 == 2 && static_cast<std::size_t>(used2) == text.size();
    if (!three)
        dist = 0.0;
    if ((!two && !three) || !std::isfinite(az) || !std::isfinite(el) || !std::isfinite(dist) ||
        dist < 0.0)
        return core::fail(ErrorCode::InvalidArgument,
                          "render: --camera " + text +
                              " is not AZIMUTH,ELEVATION[,DISTANCE] (degrees, degrees, model "
                              "units >= 0; 0 fits the object)");
    if (el < -90.0 || el > 90.0)
        return core::fail(ErrorCode::InvalidArgument,
                          "render: --camera " + text +
                              ": the elevation must lie in -90..90 degrees (90: from above)");
    camera.azimuth_deg = az;
    camera.elevation_deg = el;
    camera.distance = dist;
    return camera;
}

/// Owners from a channel "owner" (the owning peer's id per node, rounded; written by
/// `pliant demo` into final.pgrid and by `pliant host/join --save`, docs/grid-format.md), or the
/// quad-tree leaves at `depth` (docs/design.md §5) as a stand-in partition: each canonical node
/// belongs to exactly one leaf, twins follow it.
Owners owners_of(const core::TetraGrid& grid, const core::GridFile& file, int depth)
{
    Owners owners{std::vector<std::uint16_t>(grid.node_count(), render::k_no_owner), {}};
    if (const core::Field<double>* channel = file.find("owner"); channel != nullptr)
    {
        std::vector<std::uint16_t> seen;
        for (std::uint32_t i = 0; i < grid.node_count(); ++i)
        {
            // Whole numbers from -1 to 65535 (owner_channel_problem, checked for --color
            // owner): -1 and 65535 are no owner.
            const double v = (*channel)[core::NodeIndex{i}];
            const std::uint16_t id = v >= 0.0 && v < 65535.0
                                         ? static_cast<std::uint16_t>(std::lround(v))
                                         : render::k_no_owner;
            owners.ids[i] = id;
            if (id != render::k_no_owner && std::find(seen.begin(), seen.end(), id) == seen.end())
                seen.push_back(id);
        }
        std::sort(seen.begin(), seen.end());
        std::string list;
        for (const std::uint16_t id : seen)
            list += (list.empty() ? "" : ", ") + std::to_string(id);
        owners.source = seen.empty()
                            ? std::string(
                                  "the channel \"owner\": no node has an owner "
                                  "(all -1 or 65535), drawn in the base colour")
                            : "the channel \"owner\": " + std::to_string(seen.size()) + " peer" +
                                  (seen.size() == 1 ? "" : "s") + " (ids " + list + ")";
        return owners;
    }
    const int d = std::clamp(depth, 0, grid.level());
    const std::vector<core::LeafId> leaves = grid.leaves(d);
    for (std::size_t k = 0; k < leaves.size(); ++k)
    {
        const core::Region r = grid.leaf_region(leaves[k]);
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x)
                if (grid.is_canonical(grid.index(x, y)))
                    owners.ids[grid.index(x, y).value] = static_cast<std::uint16_t>(k);
    }
    for (const core::TwinPair& t : grid.twins())
        owners.ids[t.twin.value] = owners.ids[t.canonical.value];
    owners.source = "no channel \"owner\": the " + std::to_string(leaves.size()) +
                    " quad-tree leaves at depth " + std::to_string(d) + " stand in for peers";
    return owners;
}

/// --level-up on a grid of `level` stays within the finest level.
core::Result<void> check_level_up(const fs::path& path, int level, int level_up)
{
    if (level + level_up <= core::k_max_level)
        return {};
    return core::fail(ErrorCode::InvalidArgument,
                      "render: " + path.string() + " is level " + std::to_string(level) +
                          "; level " + std::to_string(level) + " + --level-up " +
                          std::to_string(level_up) + " = " + std::to_string(level + level_up) +
                          " exceeds the finest level " + std::to_string(core::k_max_level) +
                          " (use --level-up " + std::to_string(core::k_max_level - level) +
                          " or fewer)");
}

/// Positions the GPU can draw and the camera can frame: finite, within float range with room
/// for the transforms (|coordinate| <= 1e30), not all at one point. A picture of anything else
/// came out blank, and said nothing.
core::Result<void> check_drawable(const fs::path& path, const core::TetraGrid& grid,
                                  const core::Vec3Field<double>& p)
{
    constexpr double k_limit = 1e30;
    bool first = true;
    core::Vec3 lo{}, hi{};
    for (const core::NodeIndex n : grid.node_of_unique())
    {
        const core::GridCoord c = grid.coord(n);
        const core::Vec3 q{p[0].at(c.x, c.y), p[1].at(c.x, c.y), p[2].at(c.x, c.y)};
        for (const double v : {q.x, q.y, q.z})
            if (!(std::abs(v) <= k_limit))
                return core::fail(ErrorCode::NonFiniteCoordinate,
                                  "render: " + path.string() +
                                      fmt::format(": node ({}, {}) lies at ({:g}, {:g}, {:g})", c.x,
                                                  c.y, q.x, q.y, q.z) +
                                      ", which cannot be drawn (a coordinate beyond 1e30 or not "
                                      "finite; `pliant info` checks the file)");
        lo = first ? q : core::Vec3{std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
        hi = first ? q : core::Vec3{std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
        first = false;
    }
    if (!(core::norm(hi - lo) > 0.0))
        return core::fail(ErrorCode::DegenerateFace,
                          "render: " + path.string() +
                              ": every node lies at one point: there is no surface to draw "
                              "(`pliant info` checks the file)");
    return {};
}

/// Loads a grid file; `rest` supplies positions for a frame that carries only "u".
core::Result<GridScene> load_grid_scene(const fs::path& path, const RenderOptions& opt,
                                        const core::GridFile* rest)
{
    auto file = core::load_grid(path);
    if (!file)
        return file.error();
    auto grid = core::TetraGrid::create(file->level);
    if (!grid)
        return grid.error();
    if (auto ok = check_level_up(path, file->level, opt.level_up); !ok)
        return ok.error();
    // `pliant simulate` frames carry deformed positions px/py/pz plus "u" (docs/physics.md):
    // u only colours them. A frame with "u" alone is displaced from the rest grid.
    const core::GridFile* geometry_file = &*file;
    const bool displace = file->find("px") == nullptr && rest != nullptr;
    if (displace)
    {
        if (rest->level != file->level)
            return core::fail(ErrorCode::BadGrid, "render: " + path.string() + " is level " +
                                                      std::to_string(file->level) +
                                                      " but the rest grid is level " +
                                                      std::to_string(rest->level));
        geometry_file = rest;
    }
    auto rest_positions = core::geometry_of(*grid, *geometry_file);
    if (!rest_positions)
        return core::fail(ErrorCode::BadGrid,
                          "render: " + path.string() +
                              " has no positions px/py/pz (for frames that carry only \"u\", "
                              "give the rest geometry .pgrid as GRID)");
    std::optional<core::Field<double>> u;
    if (const core::Field<double>* channel = file->find("u"); channel != nullptr)
        u = *channel;
    if (const core::Field<double>* channel = file->find("owner");
        channel != nullptr && opt.color == "owner")
        if (const auto bad = owner_channel_problem(*grid, *channel))
            return core::fail(ErrorCode::BadGrid, "render: " + path.string() + ": " + bad->message +
                                                      " (`--color owner`)");
    Owners owner_info = owners_of(*grid, *file, opt.owner_depth);
    std::vector<std::uint16_t> owners = std::move(owner_info.ids);

    core::TetraGrid display = *grid;
    core::Vec3Field<double> p = std::move(*rest_positions);
    if (opt.level_up > 0)
    {
        auto plans = subdiv::make_plans(grid->level(), opt.level_up);
        if (!plans)
            return plans.error();
        p = subdiv::refine_levels<double>(*plans, p);
        if (u)
            u = subdiv::refine_levels<double>(*plans, *u);
        display = plans->back().fine_grid();
        // Owners are labels, not smooth fields: a fine node takes the owner of the coarse node
        // at its rounded-down coarse position.
        std::vector<std::uint16_t> fine(display.node_count());
        const int shift = opt.level_up;
        for (int y = 0; y < display.ny(); ++y)
            for (int x = 0; x < display.nx(); ++x)
                fine[display.index(x, y).value] = owners[grid->index(x >> shift, y >> shift).value];
        owners = std::move(fine);
    }
    if (u && displace)
    {
        // p = P + u N with rest normals N (docs/design.md §4).
        const core::Vec3Field<double> n = render::grid_normals(display, p);
        for (std::size_t c = 0; c < 3; ++c)
            for (int y = 0; y < display.ny(); ++y)
                for (int x = 0; x < display.nx(); ++x)
                    p[c].at(x, y) += u->at(x, y) * n[c].at(x, y);
    }
    if (auto ok = check_drawable(path, display, p); !ok)
        return ok.error();
    return GridScene{std::move(display), std::move(p), std::move(u), std::move(owners),
                     std::move(owner_info.source)};
}

struct Target
{
    render::Framebuffer framebuffer;
    int width;
    int height;
};

core::Result<void> save(const Target& target, const fs::path& path)
{
    std::error_code ec;
    if (path.has_parent_path())
        fs::create_directories(path.parent_path(), ec);  // a failure shows up in write_png
    return render::write_png(path, target.framebuffer.read_rgba8());
}

/// The first pass over a sequence: every frame read and checked as the drawing pass will
/// (load_grid_scene: its owner channel with `--color owner`, check_drawable) before any PNG is
/// written, so a bad frame stops the run with nothing written, not with part of an earlier
/// sequence removed; and the largest |u| over the "u" channels (0 when none has one), so that
/// one colour range serves every frame.
core::Result<double> check_frames(const std::vector<fs::path>& files, const RenderOptions& opt,
                                  const core::GridFile* rest)
{
    double largest = 0.0;
    for (const fs::path& path : files)
    {
        auto file = core::load_grid(path);
        if (!file)
            return file.error();
        if (auto ok = check_level_up(path, file->level, opt.level_up); !ok)
            return ok.error();
        const bool positions = file->find("px") != nullptr && file->find("py") != nullptr &&
                               file->find("pz") != nullptr;
        if (!positions && rest == nullptr)
            return core::fail(ErrorCode::BadGrid,
                              "render: " + path.string() +
                                  " has no positions px/py/pz (for frames that carry only \"u\", "
                                  "give the rest geometry .pgrid as GRID)");
        if (!positions && rest->level != file->level)
            return core::fail(ErrorCode::BadGrid, "render: " + path.string() + " is level " +
                                                      std::to_string(file->level) +
                                                      " but the rest grid is level " +
                                                      std::to_string(rest->level));
        if (const core::Field<double>* u = file->find("u"); u != nullptr)
            for (int y = 0; y < u->ny(); ++y)
                for (int x = 0; x < u->nx(); ++x)
                    largest = std::max(largest, std::abs(u->at(x, y)));
        if (auto scene = load_grid_scene(path, opt, rest); !scene)
            return scene.error();
    }
    return largest;
}

/// Frame i of the sequence written as `dir/stem_NNNN.png` (four digits, more from 10,000).
fs::path frame_path(const fs::path& dir, const std::string& stem, std::size_t i)
{
    std::array<char, 32> number{};
    std::snprintf(number.data(), number.size(), "_%04zu.png", i);
    return dir / (stem + number.data());
}

/// "full colour at |u| = ... m (...)" for the summary line.
std::string range_note(double range, const std::string& origin)
{
    std::array<char, 32> number{};
    std::snprintf(number.data(), number.size(), "%.3e", range);
    return "displacement colours full at |u| = " + std::string(number.data()) + " m (" + origin +
           ")";
}

int run_frames(const RenderOptions& opt, render::DrawSettings settings, Target& target,
               const GlobalOptions& global)
{
    std::error_code ec;
    if (!fs::is_directory(opt.frames, ec))
        return report(
            {ErrorCode::IoError, "render: --frames " + opt.frames.string() + " is not a folder"});
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(opt.frames, ec))
        if (entry.is_regular_file() && lower_extension(entry.path()) == ".pgrid")
            files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    if (files.empty())
        return report({ErrorCode::EmptyInput, "render: no .pgrid files in " + opt.frames.string()});

    const fs::path dir = opt.out.parent_path();
    const std::string stem = opt.out.stem().string();

    std::optional<core::GridFile> rest;
    if (!opt.input.empty())
    {
        auto loaded = core::load_grid(opt.input);
        if (!loaded)
            return report(loaded.error());
        rest = std::move(*loaded);
    }
    // One colour range for the whole sequence, so that colours compare across frames: the
    // largest |u| of any frame (frame 0 of `pliant simulate` is the rest state, whose own
    // largest |u| is 0), or --color-range.
    std::string note;
    auto checked = check_frames(files, opt, rest ? &*rest : nullptr);
    if (!checked)
        return report(checked.error());
    const double largest = *checked;
    // The sequence's folder is made if missing (a sequence usually gets a folder of its own),
    // then every frame's file is checked writable (no folder or device in the way), before an
    // earlier sequence goes and before any drawing.
    if (!dir.empty())
    {
        fs::create_directories(dir, ec);
        if (ec)
            return report({ErrorCode::IoError, "render: -o: cannot make the folder " +
                                                   dir.string() + ": " + ec.message()});
    }
    for (std::size_t i = 0; i < files.size(); ++i)
        if (auto ok = check_writable(frame_path(dir, stem, i), "render: -o"); !ok)
            return report(ok.error());
    auto renderer = render::GridRenderer::create();
    if (!renderer)
        return report(renderer.error());

    // An earlier sequence's frames under the same name go first (regular files only), so that a
    // shorter run leaves no frames of a longer one after its own.
    std::size_t removed = 0;
    for (const auto& entry : fs::directory_iterator(dir.empty() ? fs::path(".") : dir, ec))
    {
        const std::string name = entry.path().filename().string();
        const bool frame = name.size() >= stem.size() + 9 && name.starts_with(stem + "_") &&
                           name.ends_with(".png") &&
                           std::all_of(name.begin() + static_cast<std::ptrdiff_t>(stem.size()) + 1,
                                       name.end() - 4, [](char c) { return c >= '0' && c <= '9'; });
        if (frame && !entry.is_symlink(ec) && entry.is_regular_file(ec) &&
            fs::remove(entry.path(), ec))
            ++removed;
    }
    if (removed > 0)
        spdlog::info("render: removed {} frame(s) {}_NNNN.png of an earlier run from {}", removed,
                     stem, dir.empty() ? std::string(".") : dir.string());
    ProgressBar progress(global);
    // Ctrl-C or SIGTERM: stop after the frame being written (every PNG written stays whole).
    const volatile std::sig_atomic_t* interrupted = install_interrupt_flag();
    for (std::size_t i = 0; i < files.size(); ++i)
    {
        if (*interrupted != 0)
        {
            spdlog::error("render: interrupted after {} of {} frames{}", i, files.size(),
                          i == 0 ? std::string()
                                 : " (" + frame_path(dir, stem, 0).string() + " to " +
                                       frame_path(dir, stem, i - 1).string() + ")");
            return k_exit_interrupted;
        }
        auto scene = load_grid_scene(files[i], opt, rest ? &*rest : nullptr);
        if (!scene)
            return report(scene.error());
        renderer->upload(scene->grid, scene->positions, scene->u ? &*scene->u : nullptr);
        renderer->upload_owners(scene->grid, scene->owners);
        if (i == 0)
        {
            // One still camera for the whole sequence: aimed at the first frame's box.
            settings.camera.fit_to = renderer->bounds();
            if (settings.color == render::ColorMode::Displacement)
            {
                if (opt.color_range > 0.0)
                {
                    settings.displacement_range = static_cast<float>(opt.color_range);
                    note = range_note(opt.color_range, "--color-range");
                }
                else
                {
                    // A sequence at rest throughout: any small range shows grey.
                    const double range =
                        std::max(largest, 1e-9 * std::max(renderer->bounds().radius(), 1e-30));
                    settings.displacement_range = static_cast<float>(range);
                    note = range_note(range, largest > 0.0
                                                 ? "the largest |u| over the " +
                                                       std::to_string(files.size()) + " frames"
                                                 : "no frame is displaced: a floor of 1e-9 of the "
                                                   "object's size; every frame shows grey");
                }
            }
            else if (settings.color == render::ColorMode::Owner)
                note = "owners from " + scene->owner_source;
        }
        target.framebuffer.bind();
        renderer->draw(settings, target.width, target.height);
        if (auto saved = save(target, frame_path(dir, stem, i)); !saved)
            return report(saved.error());
        progress.update("render", static_cast<double>(i + 1) / static_cast<double>(files.size()));
    }
    if (!global.quiet)
        std::printf("%zu frames from %s -> %s%s%s\n", files.size(), opt.frames.string().c_str(),
                    (dir / (stem + "_NNNN.png")).string().c_str(), note.empty() ? "" : "; ",
                    note.c_str());
    return 0;
}

int run_render(const RenderOptions& opt, const GlobalOptions& global)
{
    const auto start = std::chrono::steady_clock::now();
    // Usage errors (exit 2), before any file is read.
    const auto usage = [](const std::string& message)
    {
        spdlog::error("{}", message);
        return k_exit_usage;
    };
    auto size = parse_size(opt.size);
    if (!size)
        return usage(size.error().message);
    auto camera = parse_camera(opt.camera);
    if (!camera)
        return usage(camera.error().message);
    if (opt.frames.empty() && opt.input.empty())
        return usage("render: give GRID or MESH, or --frames DIR");
    if (lower_extension(opt.out) != ".png")  // bad input (1), as remesh's and refine's -o
        return report({ErrorCode::UnsupportedFormat,
                       "render: output " + opt.out.string() + " must end in .png"});
    // Before any drawing: an output that cannot be written fails now (nothing is created).
    if (opt.frames.empty())
        if (auto ok = check_writable(opt.out, "render: -o"); !ok)
            return report(ok.error());
    if (opt.frames.empty())
    {
        std::error_code ec;
        const fs::file_status st = fs::status(opt.input, ec);
        if (!fs::exists(st))
            return report({ErrorCode::IoError, "render: " + opt.input.string() + ": no such file"});
        if (!fs::is_regular_file(st))
            return report({ErrorCode::IoError,
                           "render: " + opt.input.string() + ": not a regular file (" +
                               (fs::is_directory(st) ? "a folder" : "a device, pipe or socket") +
                               ")"});
    }

    render::DrawSettings settings;
    settings.camera = *camera;
    settings.wireframe = opt.wireframe;
    settings.color = opt.color == "displacement" ? render::ColorMode::Displacement
                     : opt.color == "owner"      ? render::ColorMode::Owner
                                                 : render::ColorMode::None;

    if (opt.color_range > 0.0 && settings.color != render::ColorMode::Displacement)
        spdlog::warn("render: --color-range applies to --color displacement only");
    if (opt.owner_depth_given && settings.color != render::ColorMode::Owner)
        spdlog::warn("render: --owner-depth applies to --color owner only");

    const render::GlBackend backend = opt.backend == "egl"      ? render::GlBackend::Egl
                                      : opt.backend == "osmesa" ? render::GlBackend::OsMesa
                                                                : render::GlBackend::Auto;
    // No OpenGL is a failure of the machine, not of the input: exit 3, as `remesh --gpu`.
    const auto no_gl = [](const core::Error& e)
    {
        (void)report(e);
        return k_exit_failure;
    };
    auto context = render::OffscreenContext::create(backend);
    if (!context)
        return no_gl(context.error());
    spdlog::debug("render: {} context, {}", render::to_string(context->backend()),
                  context->description());
    auto fb = render::Framebuffer::create((*size)[0], (*size)[1], render::PixelFormat::Rgba8,
                                          opt.samples);
    if (!fb)
        return no_gl(fb.error());
    Target target{std::move(*fb), (*size)[0], (*size)[1]};

    if (!opt.frames.empty())
        return run_frames(opt, settings, target, global);

    std::string what;
    std::string note;
    if (lower_extension(opt.input) == ".pgrid")
    {
        auto scene = load_grid_scene(opt.input, opt, nullptr);
        if (!scene)
            return report(scene.error());
        if (settings.color == render::ColorMode::Displacement && !scene->u)
            spdlog::warn("render: {} has no displacement channel \"u\"; colouring by zero",
                         opt.input.string());
        auto renderer = render::GridRenderer::create();
        if (!renderer)
            return report(renderer.error());
        renderer->upload(scene->grid, scene->positions, scene->u ? &*scene->u : nullptr);
        renderer->upload_owners(scene->grid, scene->owners);
        if (settings.color == render::ColorMode::Displacement)
        {
            const double range = opt.color_range > 0.0 ? opt.color_range
                                                       : std::max(renderer->max_abs_value(), 1e-12);
            settings.displacement_range = static_cast<float>(range);
            note = range_note(range, opt.color_range > 0.0             ? "--color-range"
                                     : renderer->max_abs_value() > 0.0 ? "its largest |u|"
                                                                       : "it is not displaced: a "
                                                                         "floor of 1e-12 m; it "
                                                                         "shows grey");
        }
        else if (settings.color == render::ColorMode::Owner)
            note = "owners from " + scene->owner_source;
        target.framebuffer.bind();
        renderer->draw(settings, target.width, target.height);
        what = "level " + std::to_string(scene->grid.level()) + " grid, " +
               std::to_string(renderer->triangle_count()) + " triangles";
    }
    else
    {
        if (opt.level_up > 0)
            return report({ErrorCode::InvalidArgument, "render: --level-up refines grids; remesh " +
                                                           opt.input.string() +
                                                           " first (`pliant remesh`)"});
        auto mesh = mesh::import_mesh(opt.input);
        if (!mesh)
            return report(mesh.error());
        if (settings.color != render::ColorMode::None)
            spdlog::warn("render: --color {} applies to grids; drawing the mesh plain", opt.color);
        auto renderer = render::MeshRenderer::create();
        if (!renderer)
            return report(renderer.error());
        renderer->upload(mesh->positions, mesh->faces);
        target.framebuffer.bind();
        renderer->draw(settings, target.width, target.height);
        what = "mesh, " + std::to_string(renderer->triangle_count()) + " triangles";
    }
    if (auto saved = save(target, opt.out); !saved)
        return report(saved.error());
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (global.quiet)
        return 0;
    std::printf("%s: %dx%d, %s (%s) in %.2f s -> %s\n", opt.input.string().c_str(), target.width,
                target.height, what.c_str(), render::to_string(context->backend()), seconds,
                opt.out.string().c_str());
    if (!note.empty())
        std::printf("%s\n", note.c_str());
    return 0;
}

void add_render_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand(
        "render", "Render a grid or mesh to a PNG with no display (offscreen OpenGL).");
    cmd->footer(
        "GRID (.pgrid) is drawn with positions in a float texture and normals computed on the\n"
        "GPU; its positions px/py/pz are drawn as stored (`pliant simulate` frames hold deformed\n"
        "ones) and a channel \"u\" feeds --color displacement. Any other file is imported as a\n"
        "mesh. Uses EGL (surfaceless, Mesa) or OSMesa: no window, no X server.\n"
        "--frames DIR renders every DIR/*.pgrid in name order to OUT_0000.png, OUT_0001.png, ...\n"
        "with the camera of the first frame and one displacement colour range for them all: the\n"
        "largest |u| of any frame (read in a first pass), or --color-range. GRID, if given,\n"
        "supplies the rest positions P of frames that carry only \"u\" (drawn at P + u N).\n"
        "Ctrl-C stops after the frame being written (exit status 130).\n"
        "Owner colours come from a channel \"owner\" (the owning peer per node: `pliant demo`\n"
        "writes it into final.pgrid) or, without one, from the quad-tree leaves at\n"
        "--owner-depth as stand-ins; the summary line says which.\n\n"
        "Examples:\n"
        "  pliant render spot.pgrid -o spot.png\n"
        "  pliant render spot.pgrid -o spot.png --size 800x800 --camera 40,25 --level-up 1\n"
        "  pliant render spot.pgrid -o owners.png --color owner --wireframe\n"
        "  pliant render data/spot.obj -o mesh.png\n"
        "  pliant render demo-out/final.pgrid -o peers.png --color owner\n"
        "  pliant render --frames out/spot -o frames/f.png --color displacement\n"
        "  pliant render --frames out/spot -o frames/f.png --color displacement --color-range "
        "0.05");
    cmd->add_option("GRID_OR_MESH", opt->input,
                    "A .pgrid grid file or a mesh file (.obj, .ply, "
                    "...)");
    cmd->add_option("-o,--output", opt->out, "Output .png (with --frames: the name pattern)")
        ->required();
    cmd->add_option("--size", opt->size, "Image size WxH in pixels")->capture_default_str();
    cmd->add_option("--camera", opt->camera,
                    "AZIMUTH,ELEVATION[,DISTANCE]: degrees about +y and above the horizon, "
                    "distance in model units (default 30,20 and fitted)");
    cmd->add_option("--level-up", opt->level_up,
                    "Refine a grid K levels by butterfly subdivision for display")
        ->check(whole_number_in(0, 9))
        ->capture_default_str();
    cmd->add_option("--color", opt->color, "Colouring: none, displacement or owner")
        ->check(CLI::IsMember({"none", "displacement", "owner"}))
        ->capture_default_str();
    cmd->add_option("--color-range", opt->color_range,
                    "|u| in metres shown at full colour by --color displacement (default: the "
                    "largest |u| of the file, or of every frame with --frames)")
        // The shader takes it as a float: below about 1e-38 it became 0, and the largest |u|
        // was used while the summary named the value given.
        ->check(number_in(1e-30, 1e30));
    cmd->add_flag("--wireframe", opt->wireframe, "Draw the triangle edges over the surface");
    cmd->add_option("--frames", opt->frames, "Render every .pgrid in this folder (a sequence)");
    cmd->add_option("--samples", opt->samples, "Multisampling (1 = off)")
        ->check(whole_number_in(1, 16))
        ->capture_default_str();
    cmd->add_option("--owner-depth", opt->owner_depth,
                    "Quad-tree depth of the stand-in owners (no \"owner\" channel)")
        ->check(whole_number_in(0, 10))
        ->capture_default_str();
    cmd->add_option("--backend", opt->backend,
                    "OpenGL set-up: auto (EGL, then OSMesa), egl, osmesa")
        ->check(CLI::IsMember({"auto", "egl", "osmesa"}))
        ->capture_default_str();
    cmd->callback(command_callback(global,
                                   [opt, &global, cmd]() -> int
                                   {
                                       opt->owner_depth_given = cmd->count("--owner-depth") > 0;
                                       return run_render(*opt, global);
                                   }));
}

const CommandRegistrar k_register_render{{"render", 60, &add_render_command}};

}  // namespace
}  // namespace pliant::cli
