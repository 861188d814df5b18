// atmos — fragment shader of the sky-view pass (GLSL only, appended by
// gpu/shader_source.cpp after the definitions, the parameter block, the
// physics up to sky_view_table.glsl (kSkyViewPhysics) and
// table_bindings.glsl). One full-screen triangle over a
// SKY_VIEW_WIDTH x SKY_VIEW_HEIGHT target with three colour attachments;
// each fragment is one texel of the sky-view table (sky_view_table.glsl) for
// this frame's camera and sun (compute_sky_view_texel), read by the render
// passes. (Its own textures, units 5-7, are unbound while it runs.)
// SKY_VIEW_LOW_SUN (true or false, the program variant): whether the sun may
// be low on the camera's view rays (sun_may_be_low_on_view_rays).
// SKY_VIEW_ECLIPSE (1 or 0): the table of an eclipse, with the moons of
// table_bindings.glsl (then SKY_VIEW_LOW_SUN is true and the frame spans the
// full azimuth); 0 passes no moons, which the compiler folds away.

layout(location = 0) uniform vec3 camera;         // m, planet-centred
layout(location = 7) uniform vec3 sun_direction;  // unit vector towards the sun

// Phase-free: single Rayleigh + multiple / P_R, and single aerosol; the ray's end.
layout(location = 0) out vec4 rayleigh_out;
layout(location = 1) out vec4 aerosol_out;
layout(location = 2) out vec4 surface_out;

void main() {
  // gl_FragCoord is the texel centre; row 0 is the first row of the table.
  vec2 uv = gl_FragCoord.xy / vec2(float(SKY_VIEW_WIDTH), float(SKY_VIEW_HEIGHT));
  vec3 rayleigh;
  vec3 aerosol;
  vec3 surface;
#if SKY_VIEW_ECLIPSE
  Moons moons = uniform_moons();
#else
  Moons moons = no_moons();
#endif
  compute_sky_view_texel(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, scattering_texture,
                         single_aerosol_texture, multiple_scattering_texture, irradiance_texture,
                         uniform_sky_view_frame(), camera, sun_direction, uv, SKY_VIEW_LOW_SUN, moons, rayleigh,
                         aerosol, surface);
  rayleigh_out = vec4(rayleigh, 1.0);
  aerosol_out = vec4(aerosol, 1.0);
  surface_out = vec4(surface, 1.0);
}
