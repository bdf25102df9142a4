// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// GPU re-meshing look-up: colour = interpolated original position; alpha = triangle index + 1
// (exact in float below 2^24), so an uncovered pixel (alpha 0, the clear value) is a detectable
// hole and two passes can compare which triangle covered a pixel.

in vec3 v_position;
out vec4 frag_color;

void main()
{
    frag_color = vec4(v_position, float(gl_PrimitiveID + 1));
}
