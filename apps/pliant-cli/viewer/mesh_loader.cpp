// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "mesh_loader.h"

#include <pliant/core/grid_io.h>
#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>
#include <pliant/remesh/remesh.h>

#include <cctype>
#include <chrono>
#include <cstdio>
#include <new>

namespace pliant::viewer
{

class LoadJob::Sink final : public core::ProgressSink
{
public:
    explicit Sink(LoadJob& job) : job_(job) {}
    void update(std::string_view phase, double fraction) noexcept override
    {
        const std::lock_guard<std::mutex> lock(job_.mutex_);
        job_.phase_.assign(phase);
        job_.fraction_ = fraction;
    }
    [[nodiscard]] bool stop_requested() const noexcept override { return job_.cancelling(); }

private:
    LoadJob& job_;
};

LoadJob::LoadJob(std::filesystem::path path, int level) : path_(std::move(path)), level_(level)
{
    thread_ = std::thread([this] { run(); });
}

LoadJob::~LoadJob()
{
    cancel();
    if (thread_.joinable())
        thread_.join();
}

std::pair<std::string, double> LoadJob::progress() const
{
    const std::lock_guard<std::mutex> lock(mutex_);
    return {phase_, fraction_};
}

core::Result<LoadedSurface> LoadJob::take()
{
    if (thread_.joinable())
        thread_.join();
    if (!result_)
        return core::fail(core::ErrorCode::InvalidArgument, "view: load result taken twice");
    core::Result<LoadedSurface> out = std::move(*result_);
    result_.reset();
    return out;
}

void LoadJob::run() noexcept
{
    // An exception leaving the thread would end the viewer: a mesh too large for the memory
    // is an error of the load, shown in the window like any other.
    try
    {
        load();
    }
    catch (const std::bad_alloc&)
    {
        // The message needs memory too; the short one fits in the string itself (no
        // allocation), so the load still ends with an error.
        try
        {
            result_.emplace(core::fail(
                core::ErrorCode::OutOfMemory,
                path_.string() + ": out of memory while loading it; choose a lower level"));
        }
        catch (const std::bad_alloc&)
        {
            result_.emplace(core::Error{core::ErrorCode::OutOfMemory, "out of memory"});
        }
        done_.store(true, std::memory_order_release);
    }
}

void LoadJob::load()
{
    const auto start = std::chrono::steady_clock::now();
    auto finish = [&](core::Result<LoadedSurface> r)
    {
        result_.emplace(std::move(r));
        done_.store(true, std::memory_order_release);
    };
    const std::string name = path_.filename().string();
    std::string extension = path_.extension().string();  // as the CLI reads it: any case
    for (char& c : extension)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (extension == ".pgrid")
    {
        Sink(*this).update("reading " + name, 0.0);
        auto file = core::load_grid(path_);
        if (!file)
            return finish(file.error());
        auto grid = core::TetraGrid::create(file->level);
        if (!grid)
            return finish(grid.error());
        auto positions = core::geometry_of(*grid, *file);
        if (!positions)
            return finish(core::Error{positions.error().code,
                                      path_.string() + ": " + positions.error().message});
        // A saved state (u and v: a --save, a simulate frame) is shown as saved; its deformed
        // surface then serves as the rest shape of the viewer's own simulation.
        const bool state = file->find("u") != nullptr && file->find("v") != nullptr;
        std::string what = name + " (level " + std::to_string(grid->level()) + " grid" +
                           (state ? "; a saved state, shown as the rest shape" : "") + ")";
        return finish(LoadedSurface{std::move(*grid), std::move(*positions), std::move(what)});
    }
    Sink sink(*this);
    sink.update("importing " + name, 0.0);
    auto mesh = mesh::import_mesh(path_);
    if (!mesh)
        return finish(mesh.error());
    if (auto ok = mesh::validate(*mesh, name); !ok)
        return finish(ok.error());
    if (cancelling())
        return finish(core::cancelled("view: loading " + name, "import"));
    remesh::RemeshSettings settings;
    settings.level = level_;
    settings.measure = false;  // the quality report is not shown; it would double the wait
    auto remeshed = remesh::remesh(*mesh, settings, &sink);
    if (!remeshed)
        return finish(remeshed.error());
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char what[256];
    std::snprintf(what, sizeof what, "%s remeshed at level %d in %.1f s", name.c_str(), level_,
                  seconds);
    finish(LoadedSurface{std::move(remeshed->grid), std::move(remeshed->positions), what});
}

}  // namespace pliant::viewer
