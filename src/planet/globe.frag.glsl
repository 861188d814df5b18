// The globe's fragment shader (src/planet/globe.cpp): the radiance lit per
// vertex (globe.vert.glsl), interpolated, divided by nits_per_unit.

in vec3 v_radiance;

layout(location = 0) out vec4 colour;

void main() { colour = vec4(max(v_radiance, vec3(0.0)), 1.0); }
