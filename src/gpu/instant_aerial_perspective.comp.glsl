// atmos — compute shader of the instant mode's aerial-perspective volume
// (GLSL only, appended by gpu/shader_source.cpp after the physics up to
// instant_atmosphere.glsl, table_bindings.glsl, composite.glsl and
// instant_composite.glsl, with VARIANT_LOW_SUN defined: whether the sun may be
// low in the volume). One invocation per direction, each slice stored as it
// is reached; the same four images as the exact mode's volume
// (aerial_perspective.comp.glsl).

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(binding = 8) uniform sampler2D instant_multiple_scattering_texture;

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
  frame.night = false;
  frame.moons = no_moons();
  InstantMarch march = instant_volume_begin(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture,
                                            instant_multiple_scattering_texture, frame, column.x, column.y);
  for (int s = 0; s < AP_SLICES; ++s) {
    AerialPerspectiveSlice slice = instant_volume_slice(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture,
                                                        instant_multiple_scattering_texture, frame, march, s);
    ivec3 texel = ivec3(column, s);
    imageStore(ap_rayleigh_image, texel, vec4(slice.single_rayleigh + slice.multiple, 1.0));
    imageStore(ap_single_rayleigh_image, texel, vec4(slice.single_rayleigh, 1.0));
    imageStore(ap_aerosol_image, texel, vec4(slice.aerosol, 1.0));
    imageStore(ap_transmittance_image, texel, vec4(slice.transmittance, 1.0));
  }
}
