// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// PNG through libpng's simplified API (png_image, libpng >= 1.6), which reports errors through
// a message buffer instead of longjmp, so no setjmp crosses C++ frames.
#include <pliant/core/file_io.h>
#include <pliant/render/image.h>

#include <png.h>

#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

namespace pliant::render
{

core::Result<void> write_png(const std::filesystem::path& path, const Image& image, bool keep_alpha)
{
    const std::size_t pixels =
        static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
    if (image.width <= 0 || image.height <= 0 || image.rgba.size() != pixels * 4U)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "write_png: image of " + std::to_string(image.width) + "x" +
                              std::to_string(image.height) + " with " +
                              std::to_string(image.rgba.size()) + " bytes");
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    png.width = static_cast<png_uint_32>(image.width);
    png.height = static_cast<png_uint_32>(image.height);
    png.format = keep_alpha ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;

    std::vector<std::uint8_t> rgb;
    const void* buffer = image.rgba.data();
    if (!keep_alpha)
    {
        rgb.resize(pixels * 3U);
        for (std::size_t i = 0; i < pixels; ++i)
            for (std::size_t c = 0; c < 3; ++c)
                rgb[i * 3U + c] = image.rgba[i * 4U + c];
        buffer = rgb.data();
    }
    // Encoded in memory, then written whole (core::write_file): a failed write leaves no
    // truncated PNG and keeps an earlier file.
    png_alloc_size_t size = 0;
    if (png_image_write_to_memory(&png, nullptr, &size, 0, buffer, 0, nullptr) == 0)
    {
        const std::string message = png.message;
        png_image_free(&png);
        return core::fail(core::ErrorCode::IoError, path.string() + ": " + message);
    }
    std::vector<std::byte> encoded(size);
    if (png_image_write_to_memory(&png, encoded.data(), &size, 0, buffer, 0, nullptr) == 0)
    {
        const std::string message = png.message;
        png_image_free(&png);
        return core::fail(core::ErrorCode::IoError, path.string() + ": " + message);
    }
    encoded.resize(size);
    return core::write_file(path, encoded, "");
}

core::Result<Image> read_png(const std::filesystem::path& path)
{
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (file == nullptr)
        return core::fail(core::ErrorCode::IoError, "read_png: cannot open " + path.string());
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    if (png_image_begin_read_from_stdio(&png, file) == 0)
    {
        const std::string message = png.message;
        png_image_free(&png);
        std::fclose(file);
        return core::fail(core::ErrorCode::ParseError,
                          "read_png: " + path.string() + ": " + message);
    }
    png.format = PNG_FORMAT_RGBA;
    Image image;
    image.width = static_cast<int>(png.width);
    image.height = static_cast<int>(png.height);
    image.rgba.resize(PNG_IMAGE_SIZE(png));
    const int ok = png_image_finish_read(&png, nullptr, image.rgba.data(), 0, nullptr);
    std::fclose(file);
    if (ok == 0)
    {
        const std::string message = png.message;
        png_image_free(&png);
        return core::fail(core::ErrorCode::ParseError,
                          "read_png: " + path.string() + ": " + message);
    }
    return image;
}

}  // namespace pliant::render
