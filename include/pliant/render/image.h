// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// An 8-bit RGBA image (top row first, as image files store it) and PNG files through libpng.

#include <pliant/core/result.h>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace pliant::render
{

struct Image
{
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgba;  ///< width * height * 4 bytes, row-major, top row first

    /// Pointer to pixel (x, y), y counted from the top. \pre inside the image.
    [[nodiscard]] const std::uint8_t* pixel(int x, int y) const noexcept
    {
        return rgba.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                              static_cast<std::size_t>(x)) *
                                 4U;
    }
};

/// Writes `image` as a PNG, RGB (the alpha channel dropped) unless `keep_alpha`.
/// \return IoError when the file cannot be written; InvalidArgument for an empty image or a
/// buffer of the wrong size.
core::Result<void> write_png(const std::filesystem::path& path, const Image& image,
                             bool keep_alpha = false);

/// Reads any PNG as 8-bit RGBA (grey and palette images expanded, alpha 255 where absent).
/// \return IoError or ParseError (not a PNG, truncated) with libpng's message.
core::Result<Image> read_png(const std::filesystem::path& path);

}  // namespace pliant::render
