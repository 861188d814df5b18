// atmos — compute shader of the engine plugin's aerial-perspective volume
// (GLSL only, appended by gpu/shader_source.cpp after the physics that
// composite.glsl needs (kCompositePhysics), table_bindings.glsl and
// composite.glsl, with VARIANT_LOW_SUN defined: whether the sun may be low
// in the volume, and
// VARIANT_ECLIPSE: 1 with the frame's moons, uniform_moons() of
// table_bindings.glsl, 0 without). One invocation per direction:
// the march of composite.glsl (aerial_perspective_march_begin / _slice), each
// slice stored as it is reached.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

// The tables: table_bindings.glsl (units 0-4 read here).

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
  frame.sky_view = uniform_sky_view_frame();
  frame.low_sun = VARIANT_LOW_SUN;
#if VARIANT_ECLIPSE
  frame.moons = uniform_moons();
#else
  frame.moons = no_moons();
#endif
  AerialPerspectiveMarch march = aerial_perspective_march_begin(
      ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, multiple_scattering_texture, frame, column.x, column.y);
  for (int s = 0; s < AP_SLICES; ++s) {
    AerialPerspectiveSlice slice = aerial_perspective_march_slice(
        ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, multiple_scattering_texture, frame, march, s);
    ivec3 texel = ivec3(column, s);
    imageStore(ap_rayleigh_image, texel, vec4(slice.single_rayleigh + slice.multiple, 1.0));
    imageStore(ap_single_rayleigh_image, texel, vec4(slice.single_rayleigh, 1.0));
    imageStore(ap_aerosol_image, texel, vec4(slice.aerosol, 1.0));
    imageStore(ap_transmittance_image, texel, vec4(slice.transmittance, 1.0));
  }
}
