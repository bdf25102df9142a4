// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// How a surface is drawn: camera, colouring, wireframe, Phong parameters. Shared by
/// `GridRenderer` (positions in a texture) and `MeshRenderer` (plain vertex buffers).

#include <pliant/render/camera.h>

#include <cstdint>

namespace pliant::render
{

/// Linear RGB, each channel in [0, 1].
struct Rgb
{
    float r = 0.0F;
    float g = 0.0F;
    float b = 0.0F;
};

enum class ColorMode : std::uint8_t
{
    None,          ///< `DrawSettings::base_color` everywhere
    Displacement,  ///< diverging map: blue (inwards) - grey (0) - red (outwards)
    Owner,         ///< the palette colour of owner id % 8 (`GridRenderer::upload_owners`)
};

enum class Shading : std::uint8_t
{
    Phong,    ///< ambient + diffuse + specular under a head light (a light at the eye)
    Normals,  ///< colour = unit normal * 0.5 + 0.5, alpha = node index (for measurements)
};

struct DrawSettings
{
    CameraSettings camera{};
    ColorMode color = ColorMode::None;
    Shading shading = Shading::Phong;
    bool wireframe = false;  ///< draw the edges over the shaded surface
    bool points = false;     ///< draw one point per grid node instead of triangles (tests)
    bool clear = true;       ///< clear colour and depth to `background` first
    Rgb background{1.0F, 1.0F, 1.0F};
    Rgb base_color{0.78F, 0.74F, 0.66F};
    Rgb wire_color{0.12F, 0.12F, 0.14F};
    /// |displacement| shown at full colour (model units); 0 uses the largest |u| uploaded.
    float displacement_range = 0.0F;
    float ambient = 0.15F;    ///< fraction of the colour lit without the light
    float specular = 0.35F;   ///< strength of the white highlight
    float shininess = 40.0F;  ///< Phong exponent
};

/// The owner palette (8 colours, owner id modulo 8): the same colours the shader uses, for
/// legends and tests.
[[nodiscard]] Rgb owner_color(std::uint32_t owner) noexcept;

/// The owner id meaning "no owner" (drawn in the base colour).
inline constexpr std::uint16_t k_no_owner = 0xFFFF;

}  // namespace pliant::render
