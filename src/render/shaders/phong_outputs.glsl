// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// What every vertex shader hands phong.frag.glsl (its inputs of the same names), inserted after
// the #version line of each (render::with_snippets).
out vec3 v_world;
out vec3 v_normal;
out float v_value;
flat out uint v_owner;
flat out int v_node;
