// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// Normal pass: one triangle covering the whole nx x ny target (drawn with glDrawArrays(0, 3),
// no attributes), so every pixel centre is one node.

void main()
{
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
