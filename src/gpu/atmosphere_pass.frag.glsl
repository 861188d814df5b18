// atmos — fragment shader of the engine plugin's pass (GLSL only, appended by
// gpu/shader_source.cpp after the shared definitions, functions.glsl,
// aerial_perspective.glsl and composite.glsl). One full-screen triangle over
// the engine's image; each fragment reads the engine's buffers at its pixel
// and writes composite_pixel(). The program variant (gpu/shader_source.cpp)
// defines SKY_VIEW_CAMERA, VARIANT_SURFACE_MODE, VARIANT_LOW_SUN,
// VARIANT_SHADOWS, VARIANT_VOLUME and VARIANT_BLEND as constants.

layout(binding = 0) uniform sampler2D spectral_transmittance_texture;
layout(binding = 1) uniform sampler3D scattering_texture;
layout(binding = 2) uniform sampler3D single_aerosol_texture;
layout(binding = 3) uniform sampler2D irradiance_texture;
layout(binding = 4) uniform sampler3D multiple_scattering_texture;
layout(binding = 5) uniform sampler2D sky_view_rayleigh_texture;
layout(binding = 6) uniform sampler2D sky_view_aerosol_texture;
// The engine's textures (texelFetch: one texel per pixel).
layout(binding = 7) uniform sampler2D engine_colour;
layout(binding = 8) uniform sampler2D engine_depth;
layout(binding = 9) uniform sampler2D engine_albedo;
layout(binding = 10) uniform sampler2D engine_normal;
// The sun's shadow map, read as depth (a sampler object without comparison).
layout(binding = 11) uniform sampler2D shadow_map;
// This frame's aerial-perspective volume (aerial_perspective.comp.glsl).
layout(binding = 12) uniform sampler3D ap_rayleigh;
layout(binding = 13) uniform sampler3D ap_single_rayleigh;
layout(binding = 14) uniform sampler3D ap_aerosol;
layout(binding = 15) uniform sampler3D ap_transmittance;

layout(location = 0) uniform vec3 camera;
layout(location = 1) uniform vec3 sun_direction;
layout(location = 2) uniform mat4 inverse_projection;  // locations 2-5
layout(location = 6) uniform mat3 view_to_world;       // 6-8
layout(location = 9) uniform int depth_encoding;
layout(location = 10) uniform float log2_depth_far;
layout(location = 12) uniform mat3 radiance_to_srgb;   // 12-14
layout(location = 15) uniform float light_scale;
layout(location = 16) uniform bool sun_disc;
layout(location = 18) uniform int shadow_steps;
layout(location = 19) uniform mat4 shadow_matrix;      // 19-22
layout(location = 23) uniform vec2 image_size;
layout(location = 24) uniform float ap_t_far;
layout(location = 25) uniform float ap_t_min;
layout(location = 26) uniform vec2 shadow_map_size;
layout(location = 27) uniform float shadow_depth_bias;
layout(location = 28) uniform float volume_weight;

layout(location = 0) out vec4 frag_color;

void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  PassFrame frame;
  frame.camera = camera;
  frame.sun_direction = sun_direction;
  frame.inverse_projection = inverse_projection;
  frame.view_to_world = view_to_world;
  frame.depth_encoding = depth_encoding;
  frame.log2_depth_far = log2_depth_far;
  frame.surface_mode = VARIANT_SURFACE_MODE;
  frame.radiance_to_srgb = radiance_to_srgb;
  frame.light_scale = light_scale;
  frame.sun_disc = sun_disc;
  frame.volume = VARIANT_VOLUME;
  // A constant 1 unless the camera is in the blend band (VARIANT_BLEND).
  frame.volume_weight = VARIANT_BLEND ? volume_weight : 1.0;
  frame.ap_t_far = ap_t_far;
  frame.ap_t_min = ap_t_min;
  frame.low_sun = VARIANT_LOW_SUN;
  frame.shadows = VARIANT_SHADOWS;
  frame.shadow_steps = shadow_steps;
  frame.shadow_matrix = shadow_matrix;
  frame.shadow_map_size = shadow_map_size;
  frame.shadow_depth_bias = shadow_depth_bias;
  float depth = texelFetch(engine_depth, pixel, 0).r;
  vec3 colour = vec3(0.0);
  vec3 albedo = vec3(0.0);
  vec3 normal = vec3(0.0, 0.0, 1.0);
  if (VARIANT_SURFACE_MODE == SURFACE_GBUFFER) {
    albedo = texelFetch(engine_albedo, pixel, 0).rgb;
    normal = texelFetch(engine_normal, pixel, 0).rgb;
  } else {
    colour = texelFetch(engine_colour, pixel, 0).rgb;
  }
  vec2 ndc = gl_FragCoord.xy / image_size * 2.0 - 1.0;
  vec3 rgb = composite_pixel(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, scattering_texture,
                             single_aerosol_texture, multiple_scattering_texture, irradiance_texture,
                             sky_view_rayleigh_texture, sky_view_aerosol_texture, SKY_VIEW_CAMERA, ap_rayleigh,
                             ap_single_rayleigh, ap_aerosol, ap_transmittance, frame, shadow_map,
                             ndc, depth, colour, albedo, normal, pixel_dither(gl_FragCoord.xy));
  frag_color = vec4(rgb, 1.0);
}
