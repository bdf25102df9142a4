// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Loading the OpenGL 3.3 core entry points the render module calls. `OffscreenContext` does this
/// itself; a program with its own window (the viewer, through GLFW) calls `load_gl` with its
/// toolkit's GetProcAddress after making its context current. See src/render/gl_api.h for why
/// pliant loads GL itself rather than through libepoxy or glad.

#include <pliant/core/result.h>

#include <string>

namespace pliant::render
{

/// A GL function pointer as GetProcAddress functions return it.
using GlProc = void (*)();
/// `eglGetProcAddress`, `OSMesaGetProcAddress`, `glfwGetProcAddress`, ...
using GetProcAddress = GlProc (*)(const char* name);

/// Fills the process-wide GL function table from `get_proc`. \pre a GL context is current on this
/// thread. \return ErrorCode::GraphicsError naming the first missing function, or the context's
/// version when it is below 3.3.
core::Result<void> load_gl(GetProcAddress get_proc);

/// Blocks until the current context has finished every command issued (glFinish): what a
/// buffer swap waits for, used to time frames. \pre `load_gl` succeeded.
void gl_finish() noexcept;

/// "GL_RENDERER | GL_VERSION" of the current context. \pre `load_gl` succeeded.
[[nodiscard]] std::string gl_description();

}  // namespace pliant::render
