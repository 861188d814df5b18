#version 450 core
// The engine's vertex shader for the terrain and the objects (main pass).

layout(location = 0) in vec3 a_position;  // object space, engine units (km)
layout(location = 1) in vec3 a_normal;    // object space
layout(location = 2) in vec3 a_albedo;

// Camera-relative rendering: the CPU multiplies view x model in double, so
// this matrix only holds the object's offset from the camera and the float
// arithmetic below never sees planet-sized coordinates (no shimmering).
uniform mat4 u_model_view;
uniform mat4 u_projection;
// Object -> world minus the patch centre (again small numbers): the frame
// of the lighting and of the shadow map lookup.
uniform mat4 u_model_patch;
uniform mat3 u_normal_matrix;  // object -> world directions
uniform vec3 u_tint;           // the object's colour (white for the terrain)

out VertexOut {
  vec3 patch_position;  // world position relative to the patch centre, engine units
  vec3 normal;          // world frame (= the planet's axes)
  vec3 albedo;
  float view_depth;     // distance along the view axis, engine units (logarithmic depth)
} vs_out;

void main() {
  vec4 view_position = u_model_view * vec4(a_position, 1.0);
  gl_Position = u_projection * view_position;
  vs_out.patch_position = (u_model_patch * vec4(a_position, 1.0)).xyz;
  vs_out.normal = u_normal_matrix * a_normal;
  vs_out.albedo = a_albedo * u_tint;
  vs_out.view_depth = -view_position.z;
}
