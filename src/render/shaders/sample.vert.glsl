// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#version 330 core
// GPU re-meshing look-up (gpu_sampler.cpp): the chord mesh of the spherical map, seen from the
// origin. The clip coordinates were computed on the CPU in double (one rounding to float), so
// the shader only passes them on; the original position is the colour, interpolated
// perspective-correctly (= barycentrically on the chord triangle).

layout(location = 0) in vec4 a_clip;
layout(location = 1) in vec3 a_position;

out vec3 v_position;

void main()
{
    v_position = a_position;
    gl_Position = a_clip;
}
