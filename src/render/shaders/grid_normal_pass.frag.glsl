// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// Normal pass: pixel (x, y) of the nx x ny RGBA32F target is node (x, y). It gets the node's
// unit area-weighted normal from its six neighbour texels (grid_normal.glsl, inserted after the
// #version line; ghost texels across the seams) and, in w, the owner id (exact in a float).

uniform sampler2D u_positions;
uniform usampler2D u_owners;

out vec4 frag_color;

void main()
{
    ivec2 t = ivec2(gl_FragCoord.xy) + ivec2(1, 1);
    vec3 n = grid_normal(u_positions, t, texelFetch(u_positions, t, 0).xyz);
    frag_color = vec4(n, float(texelFetch(u_owners, t, 0).r));
}
