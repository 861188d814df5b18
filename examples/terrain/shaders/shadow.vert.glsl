#version 450 core
// Depth from the sun (shadow map pass).

layout(location = 0) in vec3 a_position;  // object space, engine units

// Light projection x light view x model, multiplied in double on the CPU.
uniform mat4 u_shadow_from_model;

void main() { gl_Position = u_shadow_from_model * vec4(a_position, 1.0); }
