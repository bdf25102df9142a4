// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `Framebuffer`: an off-screen render target (colour + 24-bit depth renderbuffers), optionally
/// multisampled, read back as an `Image` (RGBA8) or as floats (RGBA32F, for measurements such
/// as the normals test). \pre every call: the context it was made in is current.

#include <pliant/core/result.h>
#include <pliant/render/image.h>

#include <cstdint>
#include <vector>

namespace pliant::render
{

enum class PixelFormat : std::uint8_t
{
    Rgba8,    ///< 8 bits per channel, for pictures
    Rgba32f,  ///< 32-bit float per channel, unclamped, for measurements
};

class Framebuffer
{
public:
    /// \return InvalidArgument for a size outside 1..16384; GraphicsError when the driver
    /// refuses the attachments. `samples` > 1 asks for multisampling (clamped to GL_MAX_SAMPLES),
    /// resolved at read-back. \pre a current GL context whose functions `load_gl` loaded (an
    /// OffscreenContext does both); a PLIANT_ASSERT failure otherwise, as for the renderers.
    static core::Result<Framebuffer> create(int width, int height,
                                            PixelFormat format = PixelFormat::Rgba8,
                                            int samples = 1);
    Framebuffer(Framebuffer&& o) noexcept;
    Framebuffer& operator=(Framebuffer&& o) noexcept;
    Framebuffer(const Framebuffer&) = delete;
    Framebuffer& operator=(const Framebuffer&) = delete;
    ~Framebuffer();

    /// Makes this the draw target and sets the viewport to the whole buffer.
    void bind() const noexcept;
    [[nodiscard]] int width() const noexcept { return width_; }
    [[nodiscard]] int height() const noexcept { return height_; }
    [[nodiscard]] int samples() const noexcept { return samples_; }

    /// The pixels as 8-bit RGBA, top row first (waits for drawing to finish).
    [[nodiscard]] Image read_rgba8() const;
    /// The pixels as floats, 4 per pixel, top row first.
    [[nodiscard]] std::vector<float> read_rgba32f() const;

private:
    Framebuffer() = default;
    void release() noexcept;
    /// The FBO holding single-sampled pixels (resolving the multisampled one first).
    [[nodiscard]] unsigned resolved() const noexcept;

    int width_ = 0;
    int height_ = 0;
    int samples_ = 1;
    PixelFormat format_ = PixelFormat::Rgba8;
    unsigned fbo_ = 0;
    unsigned colour_ = 0;
    unsigned depth_ = 0;
    unsigned resolve_fbo_ = 0;  // only when multisampled
    unsigned resolve_colour_ = 0;
};

}  // namespace pliant::render
