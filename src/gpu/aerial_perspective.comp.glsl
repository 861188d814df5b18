// atmos — compute shader of the engine plugin's aerial-perspective volume
// (GLSL only, appended by gpu/shader_source.cpp after the shared
// definitions, functions.glsl, aerial_perspective.glsl and composite.glsl,
// with VARIANT_LOW_SUN defined: whether the sun may be low in the volume). One invocation per direction:
// compute_aerial_perspective_column of composite.glsl, stored slice by slice.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(binding = 0) uniform sampler2D spectral_transmittance_texture;
layout(binding = 4) uniform sampler3D multiple_scattering_texture;

layout(binding = 0, rgba32f) writeonly uniform image3D ap_rayleigh_image;
layout(binding = 1, rgba32f) writeonly uniform image3D ap_single_rayleigh_image;
layout(binding = 2, rgba32f) writeonly uniform image3D ap_aerosol_image;
layout(binding = 3, rgba32f) writeonly uniform image3D ap_transmittance_image;

layout(location = 0) uniform vec3 camera;
layout(location = 1) uniform vec3 sun_direction;
layout(location = 24) uniform float ap_t_far;
layout(location = 25) uniform float ap_t_min;

void main() {
  ivec2 column = ivec2(gl_GlobalInvocationID.xy);
  if (column.x >= AP_WIDTH || column.y >= AP_HEIGHT) return;
  PassFrame frame;
  frame.camera = camera;
  frame.sun_direction = sun_direction;
  frame.ap_t_far = ap_t_far;
  frame.ap_t_min = ap_t_min;
  frame.low_sun = VARIANT_LOW_SUN;
  AerialPerspectiveColumn c = compute_aerial_perspective_column(
      ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, multiple_scattering_texture, frame, column.x, column.y);
  for (int s = 0; s < AP_SLICES; ++s) {
    ivec3 texel = ivec3(column, s);
    imageStore(ap_rayleigh_image, texel, vec4(c.single_rayleigh[s] + c.multiple[s], 1.0));
    imageStore(ap_single_rayleigh_image, texel, vec4(c.single_rayleigh[s], 1.0));
    imageStore(ap_aerosol_image, texel, vec4(c.aerosol[s], 1.0));
    imageStore(ap_transmittance_image, texel, vec4(c.transmittance[s], 1.0));
  }
}
