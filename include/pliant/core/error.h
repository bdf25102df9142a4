// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Errors for bad input at a boundary (docs/style.md §5, kind 2). One enumerator per rule, so
/// callers and tests can tell the failures apart; the message names the function or file, the rule
/// and the numbers.

#include <cstdint>
#include <string>
#include <string_view>

namespace pliant::core
{

/// Every error pliant reports. Grouped by the stage that raises them; the numeric values are
/// stable (they are process exit codes' detail in `pliant info --json`).
enum class ErrorCode : std::uint16_t
{
    // generic
    InvalidArgument = 1,    ///< a setting or argument outside its documented range
    IoError = 2,            ///< a file could not be opened, read or written
    UnsupportedFormat = 3,  ///< file extension / content not a format pliant reads or writes
    ParseError = 4,         ///< a file's content is malformed (truncated, bad header, bad number)
    EmptyInput = 5,         ///< a file with no vertices or no faces
    Cancelled = 6,          ///< long work stopped on request (core::ProgressSink)
    OutOfMemory = 7,  ///< an allocation failed (std::bad_alloc caught where it must not escape)

    // mesh validation (docs/design.md §2.1)
    NonFiniteCoordinate = 20,      ///< a vertex coordinate is NaN or infinite
    DegenerateFace = 21,           ///< a face with repeated vertices or zero area
    NotConnected = 22,             ///< more than one connected component
    OpenBoundary = 23,             ///< boundary edges (a face on one side only)
    NonManifoldEdge = 24,          ///< an edge with more than two incident faces
    NonManifoldVertex = 25,        ///< a vertex whose faces form more than one fan (a pinch)
    WrongGenus = 26,               ///< closed 2-manifold, but genus != 0
    InconsistentOrientation = 27,  ///< neighbouring faces traverse their shared edge the same way
    BadIndex = 28,                 ///< a face refers to a vertex that does not exist

    // remesh
    InvertedTriangles = 40,  ///< a spherical map with folded triangles (never written out)
    NotConverged = 41,       ///< an iterative method ran out of iterations

    // grid files
    BadGrid = 60,  ///< a grid file whose dimensions are not (2^(n+1)+1) x (2^n+1)

    // scenarios and settings
    BadScenario = 80,  ///< a scenario file with a missing or out-of-range key

    // network (session level; the codec uses its own DecodeError)
    NetworkError = 100,

    // render
    GraphicsError = 120,  ///< no OpenGL 3.3 context could be made, or GL refused a resource
};

/// Short stable name of a code, e.g. "open-boundary"; used in JSON output and logs.
[[nodiscard]] std::string_view to_string(ErrorCode code) noexcept;

/// An error at a boundary: a code for programs, a message for people.
struct Error
{
    ErrorCode code = ErrorCode::InvalidArgument;
    std::string message;
};

}  // namespace pliant::core
