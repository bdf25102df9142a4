// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// Grid vertex shader, GridNormals::PassFetch: two fetches per vertex. No vertex
// attributes: the index buffer holds node indices (y * nx + x), so gl_VertexID is the node.
// - u_positions: the ghost-padded RGBA32F positions, node (x, y) at texel (x + 1, y + 1);
//   xyz = position, w = the scalar shown by displacement colouring.
// - u_normals: the unpadded RGBA32F texture the normal pass (grid_normal_pass.frag.glsl) wrote
//   this frame, node (x, y) at texel (x, y); xyz = unit normal, w = owner id.

uniform sampler2D u_positions;
uniform sampler2D u_normals;
uniform int u_nx;
uniform mat4 u_view_projection;

// The outputs to phong.frag.glsl come from phong_outputs.glsl.

void main()
{
    int node = gl_VertexID;
    ivec2 t = ivec2(node % u_nx, node / u_nx);
    vec4 centre = texelFetch(u_positions, t + ivec2(1, 1), 0);
    vec4 normal = texelFetch(u_normals, t, 0);
    v_normal = normal.xyz;
    v_world = centre.xyz;
    v_value = centre.w;
    v_owner = uint(normal.w);
    v_node = node;
    gl_Position = u_view_projection * vec4(centre.xyz, 1.0);
}
