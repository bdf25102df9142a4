// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Progress reporting from long library work (remeshing, simulating a scenario) to whatever shows
/// it (a terminal bar in the CLI, a widget in the viewer), and the way back: the sink may ask the
/// work to stop. update() is called per phase step, never from a hot loop; stop_requested() may
/// also be polled within long loops (every few thousand items), from the calling thread only.

#include <pliant/core/error.h>

#include <string>
#include <string_view>

namespace pliant::core
{

/// Receives progress; implementations must be cheap and must not throw.
class ProgressSink
{
public:
    virtual ~ProgressSink() = default;
    /// `fraction` in [0, 1] of the named phase; called with 1.0 once when the phase ends.
    virtual void update(std::string_view phase, double fraction) noexcept = 0;
    /// Whether the work should stop (a user cancelled it; may be called from the working
    /// thread while another sets it). Once true, it must stay true for the rest of the work:
    /// a function that ends early on it (the self-intersection count) returns what it had,
    /// and its caller asks again to know that the result is partial. Work that takes a sink
    /// polls this wherever it reports progress and between phases, and then returns
    /// ErrorCode::Cancelled without a result (nothing half-done is returned or written by the
    /// phase functions: remesh, untangle_samples, session::replay). Default: never.
    [[nodiscard]] virtual bool stop_requested() const noexcept { return false; }
};

/// Whether `progress` (may be null) asks the work to stop.
[[nodiscard]] inline bool stop_requested(const ProgressSink* progress) noexcept
{
    return progress != nullptr && progress->stop_requested();
}

/// The error long work returns when stopped: "<what>: cancelled during <phase>".
[[nodiscard]] inline Error cancelled(std::string_view what, std::string_view phase)
{
    return Error{ErrorCode::Cancelled,
                 std::string(what) + ": cancelled during " + std::string(phase)};
}

/// A sink that ignores everything (the default for library calls).
class NullProgress final : public ProgressSink
{
public:
    void update(std::string_view /*phase*/, double /*fraction*/) noexcept override {}
};

}  // namespace pliant::core
