// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/error.h>
#include <pliant/core/result.h>

#include <string>

namespace pliant::core
{

std::string_view to_string(ErrorCode code) noexcept
{
    switch (code)
    {
    case ErrorCode::InvalidArgument: return "invalid-argument";
    case ErrorCode::IoError: return "io-error";
    case ErrorCode::UnsupportedFormat: return "unsupported-format";
    case ErrorCode::ParseError: return "parse-error";
    case ErrorCode::EmptyInput: return "empty-input";
    case ErrorCode::Cancelled: return "cancelled";
    case ErrorCode::OutOfMemory: return "out-of-memory";
    case ErrorCode::NonFiniteCoordinate: return "non-finite-coordinate";
    case ErrorCode::DegenerateFace: return "degenerate-face";
    case ErrorCode::NotConnected: return "not-connected";
    case ErrorCode::OpenBoundary: return "open-boundary";
    case ErrorCode::NonManifoldEdge: return "non-manifold-edge";
    case ErrorCode::NonManifoldVertex: return "non-manifold-vertex";
    case ErrorCode::WrongGenus: return "wrong-genus";
    case ErrorCode::InconsistentOrientation: return "inconsistent-orientation";
    case ErrorCode::BadIndex: return "bad-index";
    case ErrorCode::InvertedTriangles: return "inverted-triangles";
    case ErrorCode::NotConverged: return "not-converged";
    case ErrorCode::BadGrid: return "bad-grid";
    case ErrorCode::BadScenario: return "bad-scenario";
    case ErrorCode::NetworkError: return "network-error";
    case ErrorCode::GraphicsError: return "graphics-error";
    }
    return "unknown";
}

void value_of_error(const Error& error, const char* file, int line)
{
    const std::string message =
        "Result::value() on an error: " + std::string(to_string(error.code)) + ": " + error.message;
    assert_failed("has_value()", message.c_str(), file, line);
}

}  // namespace pliant::core
