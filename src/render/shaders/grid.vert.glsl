// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// Grid vertex shader (the default, GridNormals::PassToBuffer): the inner texels of the positions
// texture and the normal pass's output, copied on the GPU into one buffer object
// (GL_PIXEL_PACK_BUFFER, then bound as GL_ARRAY_BUFFER), arrive as two attributes per node;
// gl_VertexID is still the node index (y * nx + x).

layout(location = 0) in vec4 a_position;  // xyz = position, w = the displacement scalar
layout(location = 1) in vec4 a_normal;    // xyz = unit normal, w = owner id

uniform mat4 u_view_projection;

// The outputs to phong.frag.glsl come from phong_outputs.glsl.

void main()
{
    v_world = a_position.xyz;
    v_normal = a_normal.xyz;
    v_value = a_position.w;
    v_owner = uint(a_normal.w);
    v_node = gl_VertexID;
    gl_Position = u_view_projection * vec4(a_position.xyz, 1.0);
}
