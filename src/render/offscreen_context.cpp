// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Offscreen OpenGL contexts: EGL surfaceless (Mesa), then OSMesa. The EGL display is shared by
// every context of the process, so it is terminated only when the last context goes (a
// reference count; contexts are made and destroyed on one thread).
#include <pliant/render/gl_loader.h>
#include <pliant/render/offscreen_context.h>

#include <EGL/egl.h>
#include <EGL/eglext.h>
#if defined(PLIANT_HAVE_OSMESA)
#include <GL/osmesa.h>
#endif

#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace pliant::render
{

struct OffscreenContext::Impl
{
    GlBackend backend = GlBackend::Auto;
    std::string description;
    EGLDisplay egl_display = EGL_NO_DISPLAY;
    EGLContext egl_context = EGL_NO_CONTEXT;
#if defined(PLIANT_HAVE_OSMESA)
    OSMesaContext osmesa = nullptr;
#endif
    std::vector<std::uint8_t> osmesa_buffer;  // OSMesa needs a current colour buffer

    Impl() = default;
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;
    ~Impl();
};

namespace
{

int g_egl_users = 0;

std::string egl_error_name(EGLint code)
{
    switch (code)
    {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: break;
    }
    std::array<char, 32> text{};
    std::snprintf(text.data(), text.size(), "EGL error 0x%04x", static_cast<unsigned>(code));
    return text.data();
}

bool has_extension(const char* list, const char* name)
{
    if (list == nullptr)
        return false;
    const std::size_t n = std::strlen(name);
    for (const char* p = std::strstr(list, name); p != nullptr; p = std::strstr(p + n, name))
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0'))
            return true;
    return false;
}

GlProc egl_get_proc(const char* name)
{
    return eglGetProcAddress(name);
}

/// Makes an EGL surfaceless context; on failure returns the reason (and leaves nothing open).
std::string try_egl(OffscreenContext::Impl& impl)
{
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!has_extension(client, "EGL_MESA_platform_surfaceless"))
        return "libEGL offers no EGL_MESA_platform_surfaceless (not Mesa's EGL)";
    const auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_platform_display == nullptr)
        return "eglGetPlatformDisplayEXT is missing";
    EGLDisplay display =
        get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display == EGL_NO_DISPLAY)
        return "eglGetPlatformDisplayEXT(surfaceless): " + egl_error_name(eglGetError());
    EGLint major = 0;
    EGLint minor = 0;
    if (eglInitialize(display, &major, &minor) == EGL_FALSE)
        return "eglInitialize: " + egl_error_name(eglGetError());
    ++g_egl_users;
    impl.egl_display = display;  // from here on ~Impl releases the display
    const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
    if (!has_extension(extensions, "EGL_KHR_surfaceless_context"))
        return "the EGL display has no EGL_KHR_surfaceless_context";
    if (eglBindAPI(EGL_OPENGL_API) == EGL_FALSE)
        return "eglBindAPI(EGL_OPENGL_API): " + egl_error_name(eglGetError());

    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!has_extension(extensions, "EGL_KHR_no_config_context"))
    {
        const std::array<EGLint, 3> wanted{EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLint count = 0;
        if (eglChooseConfig(display, wanted.data(), &config, 1, &count) == EGL_FALSE || count == 0)
            return "no EGL config renders OpenGL";
    }
    const std::array<EGLint, 7> attributes{EGL_CONTEXT_MAJOR_VERSION,
                                           3,
                                           EGL_CONTEXT_MINOR_VERSION,
                                           3,
                                           EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                           EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                           EGL_NONE};
    impl.egl_context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes.data());
    if (impl.egl_context == EGL_NO_CONTEXT)
        return "eglCreateContext(OpenGL 3.3 core): " + egl_error_name(eglGetError());
    if (eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl.egl_context) == EGL_FALSE)
        return "eglMakeCurrent: " + egl_error_name(eglGetError());
    auto loaded = load_gl(&egl_get_proc);
    if (!loaded)
        return loaded.error().message;
    impl.backend = GlBackend::Egl;
    return {};
}

#if defined(PLIANT_HAVE_OSMESA)
GlProc osmesa_get_proc(const char* name)
{
    return OSMesaGetProcAddress(name);
}

std::string try_osmesa(OffscreenContext::Impl& impl)
{
    const std::array<int, 13> attributes{OSMESA_FORMAT,
                                         OSMESA_RGBA,
                                         OSMESA_DEPTH_BITS,
                                         24,
                                         OSMESA_PROFILE,
                                         OSMESA_CORE_PROFILE,
                                         OSMESA_CONTEXT_MAJOR_VERSION,
                                         3,
                                         OSMESA_CONTEXT_MINOR_VERSION,
                                         3,
                                         0,
                                         0,
                                         0};
    impl.osmesa = OSMesaCreateContextAttribs(attributes.data(), nullptr);
    if (impl.osmesa == nullptr)
        return "OSMesaCreateContextAttribs(OpenGL 3.3 core) returned null";
    constexpr int k_size = 4;
    impl.osmesa_buffer.assign(k_size * k_size * 4, 0);
    if (OSMesaMakeCurrent(impl.osmesa, impl.osmesa_buffer.data(), GL_UNSIGNED_BYTE, k_size,
                          k_size) == GL_FALSE)
        return "OSMesaMakeCurrent failed";
    auto loaded = load_gl(&osmesa_get_proc);
    if (!loaded)
        return loaded.error().message;
    impl.backend = GlBackend::OsMesa;
    return {};
}
#else
std::string try_osmesa(OffscreenContext::Impl& /*impl*/)
{
    return "pliant was built without OSMesa (install libosmesa6-dev and reconfigure)";
}
#endif

}  // namespace

OffscreenContext::Impl::~Impl()
{
#if defined(PLIANT_HAVE_OSMESA)
    if (osmesa != nullptr)
        OSMesaDestroyContext(osmesa);
#endif
    if (egl_display != EGL_NO_DISPLAY)
    {
        if (egl_context != EGL_NO_CONTEXT)
        {
            if (eglGetCurrentContext() == egl_context)
                eglMakeCurrent(egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            eglDestroyContext(egl_display, egl_context);
        }
        if (--g_egl_users == 0)
            eglTerminate(egl_display);
    }
}

const char* to_string(GlBackend backend) noexcept
{
    switch (backend)
    {
    case GlBackend::Auto: return "auto";
    case GlBackend::Egl: return "egl";
    case GlBackend::OsMesa: return "osmesa";
    }
    return "?";
}

core::Result<OffscreenContext> OffscreenContext::create(GlBackend backend)
{
    if (backend == GlBackend::Auto)
    {
        const char* forced = std::getenv("PLIANT_GL_BACKEND");
        if (forced != nullptr && std::strcmp(forced, "egl") == 0)
            backend = GlBackend::Egl;
        else if (forced != nullptr && std::strcmp(forced, "osmesa") == 0)
            backend = GlBackend::OsMesa;
        else if (forced != nullptr && forced[0] != '\0')
            return core::fail(core::ErrorCode::InvalidArgument,
                              std::string("PLIANT_GL_BACKEND=") + forced +
                                  " is neither egl nor osmesa (unset it to try EGL, then "
                                  "OSMesa)");
    }
    std::string reasons;
    if (backend == GlBackend::Auto || backend == GlBackend::Egl)
    {
        auto impl = std::make_unique<Impl>();
        const std::string why = try_egl(*impl);
        if (why.empty())
        {
            impl->description = gl_description();
            return OffscreenContext(std::move(impl));
        }
        reasons += "EGL surfaceless: " + why;
    }
    if (backend == GlBackend::Auto || backend == GlBackend::OsMesa)
    {
        auto impl = std::make_unique<Impl>();
        const std::string why = try_osmesa(*impl);
        if (why.empty())
        {
            impl->description = gl_description();
            return OffscreenContext(std::move(impl));
        }
        reasons += (reasons.empty() ? "" : "; ") + std::string("OSMesa: ") + why;
    }
    return core::fail(core::ErrorCode::GraphicsError,
                      "OffscreenContext: no OpenGL 3.3 core context (" + reasons +
                          "). Install Mesa's drivers: apt-get install libegl-mesa0 "
                          "libgl1-mesa-dri libosmesa6");
}

OffscreenContext::OffscreenContext(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OffscreenContext::OffscreenContext(OffscreenContext&&) noexcept = default;
OffscreenContext& OffscreenContext::operator=(OffscreenContext&&) noexcept = default;
OffscreenContext::~OffscreenContext() = default;

core::Result<void> OffscreenContext::make_current() const
{
    PLIANT_ASSERT(impl_ != nullptr, "OffscreenContext: used after move");
    if (impl_->backend == GlBackend::Egl)
    {
        if (eglMakeCurrent(impl_->egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE,
                           impl_->egl_context) == EGL_FALSE)
            return core::fail(core::ErrorCode::GraphicsError,
                              "OffscreenContext: eglMakeCurrent: " + egl_error_name(eglGetError()));
        return load_gl(&egl_get_proc);
    }
#if defined(PLIANT_HAVE_OSMESA)
    constexpr int k_size = 4;
    if (OSMesaMakeCurrent(impl_->osmesa, impl_->osmesa_buffer.data(), GL_UNSIGNED_BYTE, k_size,
                          k_size) == GL_FALSE)
        return core::fail(core::ErrorCode::GraphicsError,
                          "OffscreenContext: OSMesaMakeCurrent failed");
    return load_gl(&osmesa_get_proc);
#else
    return core::fail(core::ErrorCode::GraphicsError, "OffscreenContext: no backend");
#endif
}

GlBackend OffscreenContext::backend() const noexcept
{
    return impl_->backend;
}

const std::string& OffscreenContext::description() const noexcept
{
    return impl_->description;
}

}  // namespace pliant::render
