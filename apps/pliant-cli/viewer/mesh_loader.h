// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Loading a surface for the viewer without freezing the window: a `.pgrid` is read as it is; any
// other file is imported, validated and remeshed onto a grid (remesh::remesh, seconds at level 6,
// minutes at level 9). The work runs on a std::thread of its own; the window polls `done()` and
// draws `progress()` each frame. The worker touches nothing but its own members: the result is
// handed over once, by `take()`, after `done()` returned true (an acquire of the flag the worker
// released), so no lock is held while remeshing. `cancel()` asks the worker to stop: the
// remeshing polls it at every progress report (core::ProgressSink::stop_requested) and ends
// within a fraction of a second with ErrorCode::Cancelled; destroying a LoadJob cancels it and
// waits for the worker, so quitting during a load does not wait for the remeshing.

#include <pliant/core/field.h>
#include <pliant/core/progress.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace pliant::viewer
{

/// A rest surface ready to simulate.
struct LoadedSurface
{
    core::TetraGrid grid;
    core::Vec3Field<double> positions;  ///< rest positions, ghost width 0
    std::string description;            ///< e.g. "spot.obj remeshed at level 6 in 3.1 s"
};

class LoadJob
{
public:
    /// Starts loading `path` (`level` applies to meshes only).
    LoadJob(std::filesystem::path path, int level);
    ~LoadJob();
    LoadJob(const LoadJob&) = delete;
    LoadJob& operator=(const LoadJob&) = delete;

    [[nodiscard]] bool done() const noexcept { return done_.load(std::memory_order_acquire); }
    /// The phase being worked on and its fraction in [0, 1].
    [[nodiscard]] std::pair<std::string, double> progress() const;
    [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
    /// The result (once). \pre done().
    [[nodiscard]] core::Result<LoadedSurface> take();
    /// Asks the worker to stop; done() follows soon, with ErrorCode::Cancelled unless the work
    /// had already ended. Safe from any thread, any number of times.
    void cancel() noexcept { cancel_.store(true, std::memory_order_relaxed); }
    [[nodiscard]] bool cancelling() const noexcept
    {
        return cancel_.load(std::memory_order_relaxed);
    }

private:
    class Sink;
    void run() noexcept;
    void load();  // run()'s work: may throw std::bad_alloc

    std::filesystem::path path_;
    int level_;
    mutable std::mutex mutex_;  // guards phase_ and fraction_
    std::string phase_ = "starting";
    double fraction_ = 0.0;
    std::optional<core::Result<LoadedSurface>> result_;
    std::atomic<bool> done_{false};
    std::atomic<bool> cancel_{false};
    std::thread thread_;
};

}  // namespace pliant::viewer
