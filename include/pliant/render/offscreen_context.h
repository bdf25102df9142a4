// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `OffscreenContext`: an OpenGL 3.3 core context with no window and no display server, for the
/// `render` command, tests and benchmarks. Draw into a `Framebuffer` (framebuffer.h).
///
/// Tried in order (GlBackend::Auto):
/// 1. EGL on Mesa's surfaceless platform
/// (`eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA)`,
///    a context with no config and no surface: EGL_KHR_no_config_context and
///    EGL_KHR_surfaceless_context). Uses the GPU's render node when there is one, llvmpipe
///    otherwise.
/// 2. OSMesa (Mesa's off-screen library, always software), made current on a tiny client-memory
///    buffer that is never drawn to.
/// The environment variable PLIANT_GL_BACKEND=egl|osmesa forces one of them under Auto; any
/// other non-empty value makes create() fail with InvalidArgument (it was ignored).

#include <pliant/core/result.h>

#include <cstdint>
#include <memory>
#include <string>

namespace pliant::render
{

enum class GlBackend : std::uint8_t
{
    Auto,    ///< EGL surfaceless, then OSMesa (or PLIANT_GL_BACKEND)
    Egl,     ///< EGL surfaceless only
    OsMesa,  ///< OSMesa only
};

/// "egl", "osmesa" or "auto".
[[nodiscard]] const char* to_string(GlBackend backend) noexcept;

class OffscreenContext
{
public:
    /// Creates the context, makes it current on this thread and loads the GL functions.
    /// \return GraphicsError naming what failed for each backend tried and the Debian packages
    /// to install (libegl-mesa0 libgl1-mesa-dri, libosmesa6).
    static core::Result<OffscreenContext> create(GlBackend backend = GlBackend::Auto);

    OffscreenContext(OffscreenContext&&) noexcept;
    OffscreenContext& operator=(OffscreenContext&&) noexcept;
    OffscreenContext(const OffscreenContext&) = delete;
    OffscreenContext& operator=(const OffscreenContext&) = delete;
    /// Releases the context. Destroy every renderer and framebuffer made in it first.
    ~OffscreenContext();

    /// Makes this context current on the calling thread and reloads the GL function table (a
    /// process may hold an EGL and an OSMesa context, whose entry points differ).
    [[nodiscard]] core::Result<void> make_current() const;

    /// The backend that was made (Egl or OsMesa).
    [[nodiscard]] GlBackend backend() const noexcept;
    /// "GL_RENDERER | GL_VERSION", e.g. "llvmpipe (LLVM 15.0.6, 256 bits) | 4.5 (Core Profile)".
    [[nodiscard]] const std::string& description() const noexcept;

    struct Impl;

private:
    explicit OffscreenContext(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace pliant::render
