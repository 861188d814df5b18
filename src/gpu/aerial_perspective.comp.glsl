// atmos — compute shader of the engine plugin's aerial-perspective volume
// (GLSL only, appended by gpu/shader_source.cpp after the physics that
// composite.glsl needs (kCompositePhysics), table_bindings.glsl and
// composite.glsl, with VARIANT_LOW_SUN defined: whether the sun may be low
// in the volume, and
// VARIANT_ECLIPSE: 1 with the frame's moons, uniform_moons() of
// table_bindings.glsl, 0 without). One invocation per direction:
// the march of composite.glsl (aerial_perspective_march_begin / _slice), each
// slice stored as it is reached. With VARIANT_SPACE (cameras above the
// atmosphere) the volume is composite.glsl's space volume instead: one
// invocation per column of a list (space_columns, from column_offset on,
// column_count of them: the regular columns, see gpu/pass_frame.cpp), each
// texel evaluated exactly (space_volume_texel), split into single Rayleigh
// and multiple with VARIANT_SPLIT.

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

#if VARIANT_SPACE

layout(location = 2) uniform mat4 inverse_projection;  // locations 2-5
layout(location = 6) uniform mat3 view_to_world;       // 6-8
layout(location = 9) uniform int depth_encoding;
layout(location = 30) uniform vec4 depth_column;
layout(location = 37) uniform float surface_shell_radius;
layout(location = 38) uniform int column_offset;
layout(location = 39) uniform int column_count;
// Column indices y * SPACE_VOLUME_WIDTH + x.
layout(std430, binding = 0) readonly buffer SpaceColumns { int space_columns[]; };

void main() {
  int k = int(gl_WorkGroupID.x * 64u + gl_LocalInvocationIndex);
  if (k >= column_count) return;
  int index = space_columns[column_offset + k];
  ivec2 column = ivec2(index % SPACE_VOLUME_WIDTH, index / SPACE_VOLUME_WIDTH);
  PassFrame frame;
  frame.camera = camera;
  frame.sun_direction = sun_direction;
  frame.inverse_projection = inverse_projection;
  frame.view_to_world = view_to_world;
  frame.depth_column = depth_column;
  frame.depth_encoding = depth_encoding;
  frame.surface_shell_radius = surface_shell_radius;
  frame.low_sun = VARIANT_LOW_SUN;
  frame.night = false;
#if VARIANT_ECLIPSE
  frame.moons = uniform_moons();
#else
  frame.moons = no_moons();
#endif
  vec3 view_ray = space_volume_view_ray(frame, column.x, column.y);
  for (int s = 0; s < SPACE_VOLUME_SLICES; ++s) {
    PathScattering p = space_volume_texel(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, scattering_texture,
                                          single_aerosol_texture, multiple_scattering_texture, frame, view_ray, s,
                                          VARIANT_LOW_SUN, VARIANT_SPLIT);
    ivec3 texel = ivec3(column, s);
    imageStore(ap_rayleigh_image, texel, vec4(p.single_rayleigh + p.multiple, 1.0));
    imageStore(ap_single_rayleigh_image, texel, vec4(p.single_rayleigh, 1.0));
    imageStore(ap_aerosol_image, texel, vec4(p.aerosol, 1.0));
    imageStore(ap_transmittance_image, texel, vec4(p.transmittance, 1.0));
  }
}

#else

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

#endif
