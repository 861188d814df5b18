// atmos — fragment shader of the instant mode's sky-view pass (GLSL only,
// appended by gpu/shader_source.cpp after the definitions, the parameter
// block, the physics up to instant_atmosphere.glsl and
// table_bindings.glsl, of which it reads the optical depth (unit 0) and the
// sky irradiance (unit 3)). The exact mode's sky-view pass
// (sky_view.frag.glsl) with the view rays marched through the
// multiple-scattering table (compute_instant_sky_view_texel) instead of
// read from the 4D tables; the same target, texels and readers.
// INSTANT_LOW_SUN (true or false, the program variant): whether the sun may
// be low on the camera's view rays (sun_may_be_low_on_view_rays).

// Ψ_ms of every wavelength triple (InstantTables::multiple_scattering).
layout(binding = 8) uniform sampler2D instant_multiple_scattering_texture;

layout(location = 0) uniform vec3 camera;         // m, planet-centred
layout(location = 7) uniform vec3 sun_direction;  // unit vector towards the sun

layout(location = 0) out vec4 rayleigh_out;
layout(location = 1) out vec4 aerosol_out;
layout(location = 2) out vec4 surface_out;

void main() {
  vec2 uv = gl_FragCoord.xy / vec2(float(SKY_VIEW_WIDTH), float(SKY_VIEW_HEIGHT));
  vec3 rayleigh;
  vec3 aerosol;
  vec3 surface;
  compute_instant_sky_view_texel(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture,
                                 instant_multiple_scattering_texture, irradiance_texture, uniform_sky_view_frame(),
                                 camera, sun_direction, uv, INSTANT_LOW_SUN, rayleigh, aerosol, surface);
  rayleigh_out = vec4(rayleigh, 1.0);
  aerosol_out = vec4(aerosol, 1.0);
  surface_out = vec4(surface, 1.0);
}
