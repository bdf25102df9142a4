// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/render/framebuffer.h>

#include "render/gl_api.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <string>
#include <utility>

namespace pliant::render
{
namespace
{

GLenum internal_format(PixelFormat format)
{
    return format == PixelFormat::Rgba8 ? GL_RGBA8 : GL_RGBA32F;
}

bool attach(GLuint fbo, GLuint colour, GLuint depth)
{
    gl::glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl::glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour);
    if (depth != 0U)
        gl::glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    return gl::glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
}

GLuint make_renderbuffer(GLenum format, int samples, int width, int height)
{
    GLuint rb = 0;
    gl::glGenRenderbuffers(1, &rb);
    gl::glBindRenderbuffer(GL_RENDERBUFFER, rb);
    if (samples > 1)
        gl::glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, format, width, height);
    else
        gl::glRenderbufferStorage(GL_RENDERBUFFER, format, width, height);
    return rb;
}

}  // namespace

core::Result<Framebuffer> Framebuffer::create(int width, int height, PixelFormat format,
                                              int samples)
{
    PLIANT_ASSERT(gl::is_loaded(), "Framebuffer::create: no GL context (call load_gl)");
    constexpr int k_max_size = 16384;
    if (width < 1 || height < 1 || width > k_max_size || height > k_max_size)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "Framebuffer: size " + std::to_string(width) + "x" +
                              std::to_string(height) + " outside 1..16384");
    GLint max_samples = 1;
    gl::glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    Framebuffer fb;
    fb.width_ = width;
    fb.height_ = height;
    fb.format_ = format;
    fb.samples_ = std::clamp(samples, 1, std::max(1, static_cast<int>(max_samples)));

    gl::glGenFramebuffers(1, &fb.fbo_);
    fb.colour_ = make_renderbuffer(internal_format(format), fb.samples_, width, height);
    fb.depth_ = make_renderbuffer(GL_DEPTH_COMPONENT24, fb.samples_, width, height);
    bool complete = attach(fb.fbo_, fb.colour_, fb.depth_);
    if (complete && fb.samples_ > 1)
    {
        gl::glGenFramebuffers(1, &fb.resolve_fbo_);
        fb.resolve_colour_ = make_renderbuffer(internal_format(format), 1, width, height);
        complete = attach(fb.resolve_fbo_, fb.resolve_colour_, 0U);
    }
    gl::glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (!complete)
    {
        // The usual reason on a software renderer is memory: say how much it asked for. Colour
        // (up to 16 bytes a pixel for RGBA32F) and depth (4) per sample, and the resolve target.
        const double bytes = static_cast<double>(width) * static_cast<double>(height) *
                             ((format == PixelFormat::Rgba8 ? 4.0 : 16.0) *
                                  (fb.samples_ + (fb.samples_ > 1 ? 1 : 0)) +
                              4.0 * fb.samples_);
        char need[32];
        std::snprintf(need, sizeof(need), "%.2g GB", bytes / 1e9);
        return core::fail(
            core::ErrorCode::GraphicsError,
            "Framebuffer: " + std::to_string(width) + "x" + std::to_string(height) + " with " +
                std::to_string(fb.samples_) + " samples is incomplete (it needs about " + need +
                " of memory: out of memory? a smaller size or fewer samples may fit)");
    }
    return fb;
}

Framebuffer::Framebuffer(Framebuffer&& o) noexcept
{
    *this = std::move(o);
}

Framebuffer& Framebuffer::operator=(Framebuffer&& o) noexcept
{
    if (this != &o)
    {
        release();
        width_ = o.width_;
        height_ = o.height_;
        samples_ = o.samples_;
        format_ = o.format_;
        fbo_ = std::exchange(o.fbo_, 0U);
        colour_ = std::exchange(o.colour_, 0U);
        depth_ = std::exchange(o.depth_, 0U);
        resolve_fbo_ = std::exchange(o.resolve_fbo_, 0U);
        resolve_colour_ = std::exchange(o.resolve_colour_, 0U);
    }
    return *this;
}

Framebuffer::~Framebuffer()
{
    release();
}

void Framebuffer::release() noexcept
{
    const std::array<GLuint, 2> fbos{fbo_, resolve_fbo_};
    const std::array<GLuint, 3> rbs{colour_, depth_, resolve_colour_};
    if (fbo_ != 0U)
    {
        gl::glDeleteFramebuffers(2, fbos.data());
        gl::glDeleteRenderbuffers(3, rbs.data());
    }
    fbo_ = colour_ = depth_ = resolve_fbo_ = resolve_colour_ = 0U;
}

void Framebuffer::bind() const noexcept
{
    gl::glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    gl::glViewport(0, 0, width_, height_);
}

unsigned Framebuffer::resolved() const noexcept
{
    if (samples_ <= 1)
        return fbo_;
    gl::glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    gl::glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
    gl::glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT,
                          GL_NEAREST);
    return resolve_fbo_;
}

Image Framebuffer::read_rgba8() const
{
    Image image;
    image.width = width_;
    image.height = height_;
    const std::size_t row = static_cast<std::size_t>(width_) * 4U;
    std::vector<std::uint8_t> bottom_up(row * static_cast<std::size_t>(height_));
    gl::glBindFramebuffer(GL_READ_FRAMEBUFFER, resolved());
    gl::glReadBuffer(GL_COLOR_ATTACHMENT0);
    gl::glPixelStorei(GL_PACK_ALIGNMENT, 1);
    gl::glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, bottom_up.data());
    // GL's first row is the bottom one; image files start at the top.
    image.rgba.resize(bottom_up.size());
    for (int y = 0; y < height_; ++y)
        std::copy_n(bottom_up.data() + static_cast<std::size_t>(height_ - 1 - y) * row, row,
                    image.rgba.data() + static_cast<std::size_t>(y) * row);
    gl::glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    return image;
}

std::vector<float> Framebuffer::read_rgba32f() const
{
    const std::size_t row = static_cast<std::size_t>(width_) * 4U;
    std::vector<float> bottom_up(row * static_cast<std::size_t>(height_));
    gl::glBindFramebuffer(GL_READ_FRAMEBUFFER, resolved());
    gl::glReadBuffer(GL_COLOR_ATTACHMENT0);
    gl::glPixelStorei(GL_PACK_ALIGNMENT, 4);
    gl::glReadPixels(0, 0, width_, height_, GL_RGBA, GL_FLOAT, bottom_up.data());
    std::vector<float> out(bottom_up.size());
    for (int y = 0; y < height_; ++y)
        std::copy_n(bottom_up.data() + static_cast<std::size_t>(height_ - 1 - y) * row, row,
                    out.data() + static_cast<std::size_t>(y) * row);
    gl::glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    return out;
}

}  // namespace pliant::render
