// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Progress reporting from long library work (remeshing, simulating a scenario) to whatever shows
/// it (a terminal bar in the CLI, a widget in the viewer). Called per phase step, never from a
/// hot loop.

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
};

/// A sink that ignores everything (the default for library calls).
class NullProgress final : public ProgressSink
{
public:
    void update(std::string_view /*phase*/, double /*fraction*/) noexcept override {}
};

}  // namespace pliant::core
