// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/render/gl_loader.h>

#include "render/gl_api.h"

#include <string>

namespace pliant::render
{
namespace gl
{

#define PLIANT_GL_DEFINE(type, name) type name = nullptr;
PLIANT_GL_FUNCTIONS(PLIANT_GL_DEFINE)
#undef PLIANT_GL_DEFINE

namespace
{
bool g_loaded = false;
}  // namespace

bool is_loaded() noexcept
{
    return g_loaded;
}

}  // namespace gl

core::Result<void> load_gl(GetProcAddress get_proc)
{
    gl::g_loaded = false;
    const char* missing = nullptr;
    // reinterpret_cast between function pointer types is how every GL loader works: the
    // GetProcAddress contract is that the pointer has the named function's real type.
#define PLIANT_GL_LOAD(type, name)                      \
    gl::name = reinterpret_cast<type>(get_proc(#name)); \
    if (gl::name == nullptr && missing == nullptr)      \
        missing = #name;
    PLIANT_GL_FUNCTIONS(PLIANT_GL_LOAD)
#undef PLIANT_GL_LOAD
    if (missing != nullptr)
        return core::fail(core::ErrorCode::GraphicsError,
                          std::string("load_gl: the context has no ") + missing);

    GLint major = 0;
    GLint minor = 0;
    gl::glGetIntegerv(GL_MAJOR_VERSION, &major);
    gl::glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 33)
        return core::fail(core::ErrorCode::GraphicsError,
                          "load_gl: OpenGL " + std::to_string(major) + "." + std::to_string(minor) +
                              " context, need 3.3 core");
    gl::g_loaded = true;
    return {};
}

void gl_finish() noexcept
{
    gl::glFinish();
}

std::string gl_description()
{
    const auto* renderer = reinterpret_cast<const char*>(gl::glGetString(GL_RENDERER));
    const auto* version = reinterpret_cast<const char*>(gl::glGetString(GL_VERSION));
    return std::string(renderer != nullptr ? renderer : "?") + " | " +
           (version != nullptr ? version : "?");
}

}  // namespace pliant::render
