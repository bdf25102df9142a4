// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// pliant_png_check: checks a picture written by `pliant render` (tests/apps/render.cmake).
//
//     pliant_png_check FILE [--size WxH] [--cover MIN MAX] [--saturated MIN MAX]
//                      [--min-owner-colours N]
//
// The background is the colour of the top-left pixel; object pixels differ from it by more
// than 8 of 255 in some channel. `--cover`: the object's share of the picture (fractions).
// `--saturated`: the share of the object's pixels with an HSV saturation of at least 0.5, which
// the displacement colours reach from about 55 % of the range outwards (red) and 75 % inwards
// (blue); grey (no displacement) and Phong highlights stay below it. `--min-owner-colours`:
// at least N of the 8 owner palette colours (render::owner_color) each cover 2 % of the object;
// a pixel takes the nearest palette colour by chromaticity (its channels over their largest),
// which diffuse shading does not change. Prints the figures; exits 1 when a check fails, 2 on
// bad arguments or an unreadable file.
#include <pliant/render/draw_settings.h>
#include <pliant/render/image.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

namespace
{

using pliant::render::Image;

struct Checks
{
    int width = 0;
    int height = 0;
    double cover_min = -1.0, cover_max = 2.0;
    double saturated_min = -1.0, saturated_max = 2.0;
    int min_owner_colours = 0;
};

struct Rgb
{
    double r, g, b;
};

Rgb chroma(double r, double g, double b)
{
    const double m = std::max({r, g, b});
    return m > 0.0 ? Rgb{r / m, g / m, b / m} : Rgb{1.0, 1.0, 1.0};
}

bool parse_double(const char* text, double& out)
{
    char* end = nullptr;
    out = std::strtod(text, &end);
    return end != text && *end == '\0' && std::isfinite(out);
}

int usage(const char* why)
{
    std::fprintf(stderr,
                 "pliant_png_check: %s\nusage: pliant_png_check FILE [--size WxH] [--cover MIN "
                 "MAX] [--saturated MIN MAX] [--min-owner-colours N]\n",
                 why);
    return 2;
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc < 2)
        return usage("no file");
    const std::string file = argv[1];
    Checks c;
    for (int i = 2; i < argc; ++i)
    {
        const std::string_view a = argv[i];
        const bool two = i + 2 < argc;
        if (a == "--size" && i + 1 < argc)
        {
            char x = 0;
            if (std::sscanf(argv[++i], "%d%c%d", &c.width, &x, &c.height) != 3 || x != 'x')
                return usage("--size is not WxH");
        }
        else if (a == "--cover" && two)
        {
            if (!parse_double(argv[i + 1], c.cover_min) || !parse_double(argv[i + 2], c.cover_max))
                return usage("--cover needs two numbers");
            i += 2;
        }
        else if (a == "--saturated" && two)
        {
            if (!parse_double(argv[i + 1], c.saturated_min) ||
                !parse_double(argv[i + 2], c.saturated_max))
                return usage("--saturated needs two numbers");
            i += 2;
        }
        else if (a == "--min-owner-colours" && i + 1 < argc)
            c.min_owner_colours = std::atoi(argv[++i]);
        else
            return usage(("unknown or incomplete argument " + std::string(a)).c_str());
    }

    auto loaded = pliant::render::read_png(file);
    if (!loaded)
    {
        std::fprintf(stderr, "pliant_png_check: %s\n", loaded.error().message.c_str());
        return 2;
    }
    const Image& image = *loaded;
    int failures = 0;
    auto fail = [&](const std::string& why)
    {
        std::fprintf(stderr, "pliant_png_check: %s: %s\n", file.c_str(), why.c_str());
        ++failures;
    };
    if (c.width > 0 && (image.width != c.width || image.height != c.height))
        fail("the picture is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
             ", expected " + std::to_string(c.width) + "x" + std::to_string(c.height));

    const std::uint8_t* bg = image.pixel(0, 0);
    std::array<Rgb, 8> palette{};
    for (std::uint32_t k = 0; k < 8; ++k)
    {
        const pliant::render::Rgb p = pliant::render::owner_color(k);
        palette[k] = chroma(p.r, p.g, p.b);
    }
    std::size_t object = 0;
    std::size_t saturated = 0;
    std::array<std::size_t, 8> owner_pixels{};
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
        {
            const std::uint8_t* p = image.pixel(x, y);
            bool differs = false;
            for (int k = 0; k < 3; ++k)
                differs = differs || std::abs(int{p[k]} - int{bg[k]}) > 8;
            if (!differs)
                continue;
            ++object;
            const int hi = std::max({p[0], p[1], p[2]});
            const int lo = std::min({p[0], p[1], p[2]});
            if (hi > 0 && static_cast<double>(hi - lo) >= 0.5 * hi)
                ++saturated;
            if (hi < 40)
                continue;  // too dark for its chromaticity to mean much in 8 bits
            const Rgb q = chroma(p[0], p[1], p[2]);
            std::size_t best = 0;
            double best_d = 1e9;
            for (std::size_t k = 0; k < palette.size(); ++k)
            {
                const double d =
                    std::hypot(q.r - palette[k].r, q.g - palette[k].g, q.b - palette[k].b);
                if (d < best_d)
                {
                    best_d = d;
                    best = k;
                }
            }
            if (best_d < 0.08)
                ++owner_pixels[best];
        }
    const double pixels = static_cast<double>(image.width) * static_cast<double>(image.height);
    const double cover = pixels > 0.0 ? static_cast<double>(object) / pixels : 0.0;
    const double sat =
        object > 0 ? static_cast<double>(saturated) / static_cast<double>(object) : 0.0;
    int owner_colours = 0;
    std::string owner_list;
    for (std::size_t k = 0; k < owner_pixels.size(); ++k)
        if (object > 0 &&
            static_cast<double>(owner_pixels[k]) >= 0.02 * static_cast<double>(object))
        {
            ++owner_colours;
            owner_list += " " + std::to_string(k);
        }
    std::printf(
        "%s: %dx%d, the object covers %.1f %%, %.1f %% of it saturated, %d owner colours "
        "(palette entries%s)\n",
        file.c_str(), image.width, image.height, 100.0 * cover, 100.0 * sat, owner_colours,
        owner_list.empty() ? " none" : owner_list.c_str());
    if (cover < c.cover_min || cover > c.cover_max)
        fail("the object covers " + std::to_string(100.0 * cover) + " %, expected " +
             std::to_string(100.0 * c.cover_min) + " .. " + std::to_string(100.0 * c.cover_max) +
             " %");
    if (sat < c.saturated_min || sat > c.saturated_max)
        fail(std::to_string(100.0 * sat) + " % of the object is saturated, expected " +
             std::to_string(100.0 * std::max(c.saturated_min, 0.0)) + " .. " +
             std::to_string(100.0 * std::min(c.saturated_max, 1.0)) + " %");
    if (owner_colours < c.min_owner_colours)
        fail(std::to_string(owner_colours) + " owner colours, expected at least " +
             std::to_string(c.min_owner_colours));
    return failures == 0 ? 0 : 1;
}
