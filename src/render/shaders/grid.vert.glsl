// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// Grid vertex shader: no vertex attributes. The index buffer holds node indices (y * nx + x), so
// gl_VertexID is the node; its position is texel (x + 1, y + 1) of the ghost-padded RGBA32F
// texture (xyz = position, w = the scalar shown by displacement colouring). The ghost ring was
// filled from the ghost map, so the six neighbour fetches need no seam or corner branch.

uniform sampler2D u_positions;
uniform usampler2D u_owners;
uniform int u_nx;
uniform mat4 u_view_projection;

out vec3 v_world;
out vec3 v_normal;
out float v_value;
flat out uint v_owner;
flat out int v_node;

vec3 position_at(ivec2 t)
{
    return texelFetch(u_positions, t, 0).xyz;
}

void main()
{
    int node = gl_VertexID;
    ivec2 t = ivec2(node % u_nx, node / u_nx) + ivec2(1, 1);
    vec4 centre = texelFetch(u_positions, t, 0);
    vec3 p = centre.xyz;
    // The six neighbours counter-clockwise in the grid (cells are split along (x,y)-(x+1,y+1)):
    // the incident faces are (p, r_k, r_k+1), so the sum of their cross products is the
    // area-weighted normal. At a tetrahedron corner every real face appears twice, which keeps
    // the direction.
    vec3 r0 = position_at(t + ivec2(1, 0)) - p;
    vec3 r1 = position_at(t + ivec2(1, 1)) - p;
    vec3 r2 = position_at(t + ivec2(0, 1)) - p;
    vec3 r3 = position_at(t + ivec2(-1, 0)) - p;
    vec3 r4 = position_at(t + ivec2(-1, -1)) - p;
    vec3 r5 = position_at(t + ivec2(0, -1)) - p;
    vec3 n = cross(r0, r1) + cross(r1, r2) + cross(r2, r3) + cross(r3, r4) + cross(r4, r5) +
             cross(r5, r0);
    float len = length(n);
    v_normal = len > 0.0 ? n / len : vec3(0.0);
    v_world = p;
    v_value = centre.w;
    v_owner = texelFetch(u_owners, t, 0).r;
    v_node = node;
    gl_Position = u_view_projection * vec4(p, 1.0);
}
