// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The grid's area-weighted normal at texel t of the ghost-padded positions texture (no #version:
// the renderer inserts this after the #version line of the shaders that use it). The ghost ring
// was filled from the ghost map, so the six neighbour fetches need no seam or corner branch.

// The six neighbours counter-clockwise in the grid (cells are split along (x,y)-(x+1,y+1)): the
// incident faces are (p, r_k, r_k+1), so the sum of their cross products is the area-weighted
// normal. At a tetrahedron corner every real face appears twice, which keeps the direction.
// Returns the unit normal, or 0 for a degenerate neighbourhood.
vec3 grid_normal(sampler2D positions, ivec2 t, vec3 p)
{
    vec3 r0 = texelFetch(positions, t + ivec2(1, 0), 0).xyz - p;
    vec3 r1 = texelFetch(positions, t + ivec2(1, 1), 0).xyz - p;
    vec3 r2 = texelFetch(positions, t + ivec2(0, 1), 0).xyz - p;
    vec3 r3 = texelFetch(positions, t + ivec2(-1, 0), 0).xyz - p;
    vec3 r4 = texelFetch(positions, t + ivec2(-1, -1), 0).xyz - p;
    vec3 r5 = texelFetch(positions, t + ivec2(0, -1), 0).xyz - p;
    vec3 n = cross(r0, r1) + cross(r1, r2) + cross(r2, r3) + cross(r3, r4) + cross(r4, r5) +
             cross(r5, r0);
    float len = length(n);
    return len > 0.0 ? n / len : vec3(0.0);
}
