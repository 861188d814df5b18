// atmos — fragment shader of the sky-view pass (GLSL only, appended by
// gpu/shader_source.cpp after the shared definitions, the ATMOSPHERE constant
// and functions.glsl). One full-screen triangle over a SKY_VIEW_WIDTH x
// SKY_VIEW_HEIGHT target with two colour attachments; each fragment is one
// texel of the sky-view table of functions.glsl for this frame's camera and
// sun (compute_sky_view_texel), read by the render pass.

layout(binding = 0) uniform sampler2D spectral_transmittance_texture;
layout(binding = 1) uniform sampler3D scattering_texture;
layout(binding = 2) uniform sampler3D single_aerosol_texture;
layout(binding = 4) uniform sampler3D multiple_scattering_texture;

layout(location = 0) uniform vec3 camera;         // m, planet-centred
layout(location = 7) uniform vec3 sun_direction;  // unit vector towards the sun

// Phase-free: single Rayleigh + multiple / P_R, and single aerosol.
layout(location = 0) out vec4 rayleigh_out;
layout(location = 1) out vec4 aerosol_out;

void main() {
  // gl_FragCoord is the texel centre; row 0 is the first row of the table.
  vec2 uv = gl_FragCoord.xy / vec2(float(SKY_VIEW_WIDTH), float(SKY_VIEW_HEIGHT));
  vec3 rayleigh;
  vec3 aerosol;
  compute_sky_view_texel(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, scattering_texture,
                         single_aerosol_texture,
                         multiple_scattering_texture, camera, sun_direction, uv, rayleigh, aerosol);
  rayleigh_out = vec4(rayleigh, 1.0);
  aerosol_out = vec4(aerosol, 1.0);
}
