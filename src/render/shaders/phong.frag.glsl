// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// Phong shading under a head light (a point light at the eye), two-sided, with optional
// colouring by a per-node scalar (diverging map) or by owner id (palette).

in vec3 v_world;
in vec3 v_normal;
in float v_value;
flat in uint v_owner;
flat in int v_node;

uniform vec3 u_eye;
uniform int u_color_mode;  // 0 base colour, 1 displacement, 2 owner
uniform int u_shading;     // 0 Phong, 1 normals as colour
uniform int u_flat;        // 1 in the wireframe pass
uniform vec3 u_base_color;
uniform vec3 u_wire_color;
uniform vec3 u_palette[8];
uniform float u_value_range;
uniform float u_ambient;
uniform float u_specular;
uniform float u_shininess;

out vec4 frag_color;

// Moreland's cool-warm end points around a light grey.
vec3 diverging(float t)
{
    const vec3 cold = vec3(0.230, 0.299, 0.754);
    const vec3 mid = vec3(0.865, 0.865, 0.865);
    const vec3 warm = vec3(0.706, 0.016, 0.150);
    return t < 0.0 ? mix(mid, cold, -t) : mix(mid, warm, t);
}

void main()
{
    float len = length(v_normal);
    vec3 n = len > 0.0 ? v_normal / len : vec3(0.0, 0.0, 1.0);
    if (u_shading == 1)
    {
        frag_color = vec4(n * 0.5 + 0.5, float(v_node));
        return;
    }
    if (u_flat == 1)
    {
        frag_color = vec4(u_wire_color, 1.0);
        return;
    }
    vec3 base = u_base_color;
    if (u_color_mode == 1)
        base = diverging(clamp(v_value / u_value_range, -1.0, 1.0));
    else if (u_color_mode == 2 && v_owner != 0xFFFFu)
        base = u_palette[v_owner % 8u];
    vec3 v = normalize(u_eye - v_world);
    // Two-sided: the light sits at the eye, so a normal facing away is simply flipped and the
    // grid's orientation (which depends on the remeshing) never matters.
    if (dot(n, v) < 0.0)
        n = -n;
    float diffuse = max(dot(n, v), 0.0);
    vec3 r = reflect(-v, n);
    float highlight = pow(max(dot(r, v), 0.0), u_shininess);
    vec3 c = base * (u_ambient + (1.0 - u_ambient) * diffuse) + vec3(u_specular * highlight);
    frag_color = vec4(c, 1.0);
}
