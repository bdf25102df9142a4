// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// Grid vertex shader, GridNormals::VertexShader: every vertex invocation computes its normal
// from its six neighbour texels (grid_normal.glsl and phong_outputs.glsl, inserted after the #version line). No vertex
// attributes: the index buffer holds node indices (y * nx + x), so gl_VertexID is the node; its
// position is texel (x + 1, y + 1) of the ghost-padded RGBA32F texture (xyz = position, w = the
// scalar shown by displacement colouring).

uniform sampler2D u_positions;
uniform usampler2D u_owners;
uniform int u_nx;
uniform mat4 u_view_projection;

// The outputs to phong.frag.glsl come from phong_outputs.glsl.

void main()
{
    int node = gl_VertexID;
    ivec2 t = ivec2(node % u_nx, node / u_nx) + ivec2(1, 1);
    vec4 centre = texelFetch(u_positions, t, 0);
    v_normal = grid_normal(u_positions, t, centre.xyz);
    v_world = centre.xyz;
    v_value = centre.w;
    v_owner = texelFetch(u_owners, t, 0).r;
    v_node = node;
    gl_Position = u_view_projection * vec4(centre.xyz, 1.0);
}
