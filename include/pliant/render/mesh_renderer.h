// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `MeshRenderer`: the plain vertex-buffer path for any indexed triangle mesh (an imported file
/// before remeshing, or a grid drawn the classic way for comparison in the benchmark): positions,
/// CPU normals and a scalar per vertex in one interleaved buffer, same shading and settings as
/// `GridRenderer` (owner colouring does not apply). \pre every call: the context it was created
/// in is current. Not thread-safe.

#include <pliant/core/result.h>
#include <pliant/core/vec3.h>
#include <pliant/render/draw_settings.h>

#include <array>
#include <cstdint>
#include <memory>
#include <span>

namespace pliant::render
{

class MeshRenderer
{
public:
    /// \pre a GL 3.3 context is current. \return GraphicsError with the compiler's log.
    static core::Result<MeshRenderer> create();

    MeshRenderer(MeshRenderer&&) noexcept;
    MeshRenderer& operator=(MeshRenderer&&) noexcept;
    MeshRenderer(const MeshRenderer&) = delete;
    MeshRenderer& operator=(const MeshRenderer&) = delete;
    ~MeshRenderer();

    /// Uploads a mesh. `normals` empty: area-weighted normals computed here; `values` empty:
    /// zero. \pre faces index into positions; normals and values empty or one per vertex;
    /// positions not empty.
    void upload(std::span<const core::Vec3> positions,
                std::span<const std::array<std::uint32_t, 3>> faces,
                std::span<const core::Vec3> normals = {}, std::span<const float> values = {});

    /// New vertex data for the uploaded faces, as a simulation gives every frame: positions,
    /// normals (empty: area-weighted, computed here over the faces of the last upload) and
    /// values (empty: zero) rewrite the vertex buffer in place; the index buffer stays. No
    /// allocation after the first call. \pre something was uploaded; positions, and normals and
    /// values unless empty, one per vertex of that upload.
    void update(std::span<const core::Vec3> positions, std::span<const core::Vec3> normals = {},
                std::span<const float> values = {});

    /// Draws into the bound framebuffer. \pre something was uploaded.
    void draw(const DrawSettings& settings, int width, int height) const;

    [[nodiscard]] CameraMatrices camera(const CameraSettings& settings, int width,
                                        int height) const noexcept;
    [[nodiscard]] const Bounds& bounds() const noexcept;
    [[nodiscard]] std::size_t triangle_count() const noexcept;

    struct Impl;

private:
    explicit MeshRenderer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace pliant::render
