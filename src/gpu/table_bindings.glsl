// atmos — the texture units of the precomputed tables and of this frame's
// sky-view table, and the uniforms of the sky-view table's frame (GLSL only;
// gpu/gl_util.hpp: TableUnit, kSkyViewFrameLocation). Appended by
// gpu/shader_source.cpp to every program that reads the tables, so that the
// units are declared once.

// The optical depth of every wavelength triple (SPECTRAL), side by side.
layout(binding = 0) uniform sampler2D spectral_transmittance_texture;
layout(binding = 1) uniform sampler3D scattering_texture;
layout(binding = 2) uniform sampler3D single_aerosol_texture;
layout(binding = 3) uniform sampler2D irradiance_texture;
layout(binding = 4) uniform sampler3D multiple_scattering_texture;
// This frame's sky-view table (sky_view.frag.glsl; view_ray_scattering.glsl:
// view_ray_terms), for cameras in the atmosphere.
layout(binding = 5) uniform sampler2D sky_view_rayleigh_texture;
layout(binding = 6) uniform sampler2D sky_view_aerosol_texture;
layout(binding = 7) uniform sampler2D sky_view_surface_texture;

// The table's frame (sky_view_table.glsl: sky_view_frame), computed once per
// frame on the CPU (GpuTables::sky_view_frame).
layout(location = 40) uniform vec3 sky_view_zenith;
layout(location = 41) uniform vec3 sky_view_sun_side;
layout(location = 42) uniform vec3 sky_view_across;
layout(location = 43) uniform float sky_view_theta_horizon;
layout(location = 44) uniform bool sky_view_full_azimuth;

SkyViewFrame uniform_sky_view_frame() {
  return SkyViewFrame(sky_view_zenith, sky_view_sun_side, sky_view_across, sky_view_theta_horizon,
                      sky_view_full_azimuth);
}

// The frame's moons (eclipse.glsl: Moons), for the programs that draw
// eclipses (gl_util: set_moons_uniforms).
layout(location = 45) uniform int moon_count;
layout(location = 46) uniform vec4 moon_spheres[MOON_CAPACITY];  // 46..49

Moons uniform_moons() {
  Moons moons;
  moons.count = moon_count;
  for (int i = 0; i < MOON_CAPACITY; ++i) moons.sphere[i] = moon_spheres[i];
  return moons;
}
