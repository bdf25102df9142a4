// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// Mesh vertex shader: the plain vertex-buffer path (positions and CPU normals as attributes).

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_value;

uniform mat4 u_view_projection;

// The outputs to phong.frag.glsl come from phong_outputs.glsl.

void main()
{
    v_world = a_position;
    v_normal = a_normal;
    v_value = a_value;
    v_owner = 0xFFFFu;
    v_node = gl_VertexID;
    gl_Position = u_view_projection * vec4(a_position, 1.0);
}
