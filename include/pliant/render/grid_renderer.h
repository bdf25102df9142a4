// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `GridRenderer`: draws a `TetraGrid` surface the way the reference paper does on the GPU
/// (docs/rendering.md):
/// - Positions live in an RGBA32F texture, one texel per grid node, padded by a ghost ring of
///   one node filled through the grid's ghost map; w carries a per-node scalar (the
///   displacement) for colouring.
/// - One static index buffer per level holds the 4W^2 grid triangles over *canonical* node
///   indices, so the two sides of a seam share vertices and cannot crack.
/// - Normals: after each upload, one triangle over an nx x ny RGBA32F target runs a fragment
///   shader per node that fetches the node's six neighbours by `texelFetch` and sums the six
///   face cross products into the area-weighted normal (w: the owner id). Neighbours across a
///   seam come from the ghost ring, which holds exactly the nodes on the other side, so the
///   normals are continuous there.
/// - The draw (GridNormals::PassToBuffer, the default): the inner positions texels and the
///   normal texels are copied on the GPU (`glReadPixels` into a pixel-pack buffer) into one
///   buffer object, which the draw reads as two vertex attributes per node; gl_VertexID is
///   still the node. GridNormals::PassFetch fetches both texels in the vertex shader instead,
///   GridNormals::VertexShader sums the normal in every vertex invocation (the first design).
///   All three give the same picture; docs/rendering.md compares their speed.
/// - The fragment shader shades with Phong under a head light.
/// Only positions (and owners when they change) are streamed per frame; further uploads at the
/// level of the last one allocate nothing. An upload at another level (even one uploaded before)
/// re-creates the textures, the attribute buffer and the CPU staging buffers at its size; only
/// the index buffers are kept per level.
///
/// Alternatives rejected: normals on the CPU in a second texture (another full pass and upload
/// per frame: the point of the paper's scheme is that the GPU does it); a geometry shader for
/// normals or the wireframe (slow on llvmpipe, and face normals are not smooth).
///
/// \pre every call: the OpenGL context the renderer was created in is current. Not thread-safe.

#include <pliant/core/field.h>
#include <pliant/core/result.h>
#include <pliant/render/draw_settings.h>

#include <cstdint>
#include <memory>
#include <span>

namespace pliant::render
{

/// Where the grid's normals are computed and how the vertex shader gets them. All three use
/// the same formula on the same texels and draw the same picture.
enum class GridNormals : std::uint8_t
{
    /// Default. A normal pass after each upload writes one normal per node into a texture
    /// (a fragment shader over an nx x ny target); that texture and the positions texture are
    /// then copied on the GPU into a buffer object (`glReadPixels` into a pixel-pack buffer)
    /// that the draw reads as vertex attributes: no texel fetch per vertex.
    PassToBuffer,
    /// The same normal pass; the vertex shader fetches position and normal (2 texel fetches).
    PassFetch,
    /// Every vertex-shader invocation computes its own normal (8 texel fetches per vertex):
    /// the first design, repeated for every vertex the pipeline shades more than once.
    VertexShader,
};

class GridRenderer
{
public:
    /// Compiles the shaders for `normals`. \pre a GL 3.3 context is current (`OffscreenContext` or
    /// the viewer's window, with `load_gl` done). \return GraphicsError with the compiler's log.
    static core::Result<GridRenderer> create(GridNormals normals = GridNormals::PassToBuffer);

    GridRenderer(GridRenderer&&) noexcept;
    GridRenderer& operator=(GridRenderer&&) noexcept;
    GridRenderer(const GridRenderer&) = delete;
    GridRenderer& operator=(const GridRenderer&) = delete;
    ~GridRenderer();

    /// Uploads positions (model units) and, optionally, a per-node scalar for
    /// ColorMode::Displacement. Fields may have any ghost width; only in-range nodes are read.
    /// \pre the fields were made for `grid`.
    void upload(const core::TetraGrid& grid, const core::Vec3Field<double>& positions,
                const core::Field<double>* values = nullptr);

    /// Uploads deformed positions p = P + u N (rest positions P, rest unit normals N, normal
    /// displacement u, docs/design.md §4) with u as the colouring scalar.
    void upload_displaced(const core::TetraGrid& grid, const core::Vec3Field<double>& rest,
                          const core::Vec3Field<double>& rest_normals,
                          const core::Field<double>& u);

    /// Owner id per node (row-major, `grid.node_count()` entries; `k_no_owner` for none) for
    /// ColorMode::Owner; an empty span clears the owners. \pre a grid was uploaded at the same
    /// level.
    void upload_owners(const core::TetraGrid& grid, std::span<const std::uint16_t> owners);

    /// Draws into the bound framebuffer (viewport width x height), clearing it first unless
    /// `settings.clear` is false. Except with GridNormals::VertexShader, first reruns the normal
    /// pass (and copy) if positions or owners changed since the last draw (into its own
    /// framebuffer; the caller's binding is restored). Only the framebuffer bindings are
    /// restored: the viewport, depth test, depth func (GL_LEQUAL) and depth mask, clear colour,
    /// program, vertex array (0), active texture unit (0) and the textures on units 0 and 1 stay
    /// as `draw` set them (docs/rendering.md). \pre something was uploaded.
    void draw(const DrawSettings& settings, int width, int height) const;

    /// The camera `draw` uses for these settings and this image size.
    [[nodiscard]] CameraMatrices camera(const CameraSettings& settings, int width,
                                        int height) const noexcept;
    [[nodiscard]] const Bounds& bounds() const noexcept;
    [[nodiscard]] int level() const noexcept;
    /// Triangles per draw: 4W^2.
    [[nodiscard]] std::size_t triangle_count() const noexcept;
    /// The largest |scalar| of the last upload (the default displacement colour range).
    [[nodiscard]] double max_abs_value() const noexcept;

    struct Impl;

private:
    explicit GridRenderer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace pliant::render
