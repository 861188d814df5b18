// atmos — fragment shaders of the engine plugin's pass (GLSL only, appended
// by gpu/shader_source.cpp after the physics that composite.glsl needs
// (kCompositePhysics), table_bindings.glsl and composite.glsl). Each
// draws one full-screen triangle over the engine's image; the program
// variant (gpu/shader_source.cpp) defines VARIANT_PIXELS and the constants
// SKY_VIEW_CAMERA, VARIANT_SURFACE_MODE, VARIANT_LOW_SUN, VARIANT_SHADOWS,
// VARIANT_VOLUME, VARIANT_BLEND, VARIANT_SPACE_VOLUME, VARIANT_NIGHT,
// VARIANT_STARS and VARIANT_ECLIPSE (1: the frame's moons from the uniforms of
// table_bindings.glsl, uniform_moons; 0: no_moons(), whose code folds
// away).
//
// Why several programs. Software rasterisers run both sides of every
// branch, so one program for every pixel would charge each pixel for the sky
// AND for a surface, and for the work of the rarest pixels. But they do skip
// blocks of pixels (llvmpipe: 4x4) that fail the stencil test before
// shading. So the pass first sorts the pixels into classes in a stencil
// buffer, one bit per question, each by a cheap program that discards the
// pixels whose answer is no (PIXELS_CLASSIFY*: a depth read, a little
// geometry):
//  - bit 0, PIXELS_CLASSIFY: the engine drew nothing here (sky);
//  - bit 1, PIXELS_CLASSIFY_LOW_SUN (frames that may have a low sun, see
//    make_pass_frame): the pixel's light needs the low-sun integration
//    (composite.glsl: pixel_needs_low_sun_path), a few pixels around the
//    terminator where the whole frame would otherwise pay for it;
//  - bit 2, PIXELS_CLASSIFY_SPACE (cameras above the atmosphere): a sky
//    pixel whose ray misses the atmosphere (sky_ray_misses_atmosphere).
//  - bit 3, PIXELS_CLASSIFY_SPACE_VOLUME (cameras above the atmosphere): a
//    surface that the space volume covers (composite.glsl:
//    space_volume_covers), drawn by the program with VARIANT_SPACE_VOLUME;
//    the exact programs draw the other surfaces.
//  - bit 4 (with PIXELS_CLASSIFY_ALL only): a low-sun surface whose segment
//    lies in the planet's shadow, where the integration gives zero single
//    scattering: drawn by the program without it, with VARIANT_NIGHT.
// The draw of bit 2 runs on the sky pixels only (the stencil test on bit
// 0).
// Where the driver can export a fragment's stencil value
// (GL_ARB_shader_stencil_export), one draw instead, PIXELS_CLASSIFY_ALL,
// answers every question of the frame at each pixel and writes the bits:
// a classifying draw discards, so the rasteriser cannot test the stencil
// before shading and runs it over every pixel of the image; one pass
// instead of up to four pays that, and the depth read and the ray, once.
// Then each class is drawn by its own program where the stencil holds its
// bits: the sky (PIXELS_SKY) and the surfaces (PIXELS_SURFACE), each with
// and without the low-sun integration (VARIANT_LOW_SUN), and the space
// beside the planet (PIXELS_SPACE: stars, sun and moons alone). Every pixel
// pays for its own kind only (GPUs, which branch per warp, lose nothing).
#define PIXELS_CLASSIFY 0
#define PIXELS_SKY 1
#define PIXELS_SURFACE 2
#define PIXELS_SPACE 3
#define PIXELS_CLASSIFY_LOW_SUN 4
#define PIXELS_CLASSIFY_SPACE 5
#define PIXELS_CLASSIFY_SPACE_VOLUME 6
#define PIXELS_CLASSIFY_ALL 7
#define PIXELS_INSTANT_SPACE 8

// The engine's textures (texelFetch: one texel per pixel). Colour and albedo
// share a unit: a surface mode reads one of them.
layout(binding = 8) uniform sampler2D engine_depth;
#if VARIANT_SURFACE_MODE == SURFACE_GBUFFER
layout(binding = 9) uniform sampler2D engine_albedo;
layout(binding = 10) uniform sampler2D engine_normal;
#else
layout(binding = 9) uniform sampler2D engine_colour;
#endif
// The sun's shadow map, read with comparison and linear filtering (the
// pass's sampler object): percentage-closer filtering in one fetch.
layout(binding = 11) uniform sampler2DShadow shadow_map;
// This frame's aerial-perspective volume (aerial_perspective.comp.glsl).
layout(binding = 12) uniform sampler3D ap_rayleigh;
layout(binding = 13) uniform sampler3D ap_single_rayleigh;
layout(binding = 14) uniform sampler3D ap_aerosol;
layout(binding = 15) uniform sampler3D ap_transmittance;
// The space volume's regular columns (composite.glsl: space_volume_covers).
layout(binding = 16) uniform sampler2D space_volume_regular_columns;

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
layout(location = 24) uniform float ap_t_far;
layout(location = 25) uniform float ap_t_min;
layout(location = 27) uniform float shadow_depth_bias;
layout(location = 28) uniform float volume_weight;
layout(location = 29) uniform vec3 inverse_sun_srgb;
layout(location = 30) uniform vec4 depth_column;
layout(location = 31) uniform float depth_column_view_z;
layout(location = 32) uniform float star_sigma;
layout(location = 33) uniform mat4 world_to_clip;       // 33-36
layout(location = 37) uniform float surface_shell_radius;
// The sky-view frame: locations 40-44, the moons: 45-49 (table_bindings.glsl).

// The pixel's PixelRay, interpolated from the vertex shader's corners
// (atmosphere_pass.vert.glsl).
layout(location = 0) noperspective in vec4 ray_world;
layout(location = 1) noperspective in float ray_view_z;

layout(location = 0) out vec4 frag_color;

// This frame's PassFrame, from the uniforms and the variant's constants.
PassFrame pass_frame_from_uniforms() {
  PassFrame frame;
  frame.camera = camera;
  frame.sun_direction = sun_direction;
  frame.inverse_projection = inverse_projection;
  frame.view_to_world = view_to_world;
  frame.depth_column = depth_column;
  frame.depth_column_view_z = depth_column_view_z;
  frame.depth_encoding = depth_encoding;
  frame.log2_depth_far = log2_depth_far;
  frame.surface_mode = VARIANT_SURFACE_MODE;
  frame.radiance_to_srgb = radiance_to_srgb;
  frame.inverse_sun_srgb = inverse_sun_srgb;
  frame.sky_view = uniform_sky_view_frame();
  frame.light_scale = light_scale;
  frame.sun_disc = sun_disc;
  frame.stars = StarField(VARIANT_STARS, star_sigma);
  frame.volume = VARIANT_VOLUME;
  // A constant 1 unless the camera is in the blend band (VARIANT_BLEND).
  frame.volume_weight = VARIANT_BLEND ? volume_weight : 1.0;
  frame.ap_t_far = ap_t_far;
  frame.ap_t_min = ap_t_min;
  frame.space_volume = VARIANT_SPACE_VOLUME;
  frame.world_to_clip = world_to_clip;
  frame.surface_shell_radius = surface_shell_radius;
  frame.low_sun = VARIANT_LOW_SUN;
  frame.night = VARIANT_NIGHT;
  frame.shadows = VARIANT_SHADOWS;
  frame.shadow_steps = shadow_steps;
  frame.shadow_matrix = shadow_matrix;
  frame.shadow_depth_bias = shadow_depth_bias;
#if VARIANT_ECLIPSE
  frame.moons = uniform_moons();
#else
  frame.moons = no_moons();
#endif
  return frame;
}

#if VARIANT_PIXELS == PIXELS_CLASSIFY

// Keeps the sky pixels (the draw's stencil operation marks them).
void main() {
  if (!depth_is_sky(texelFetch(engine_depth, ivec2(gl_FragCoord.xy), 0).r, depth_encoding)) discard;
  frag_color = vec4(0.0);
}

#elif VARIANT_PIXELS == PIXELS_CLASSIFY_LOW_SUN || VARIANT_PIXELS == PIXELS_CLASSIFY_SPACE || \
    VARIANT_PIXELS == PIXELS_CLASSIFY_SPACE_VOLUME

// Keeps the pixels that need the low-sun integration, the sky pixels whose
// rays miss the atmosphere, or the surfaces the space volume covers (the
// draw's stencil operation marks them).
// Only the frame's geometry is read: one program for every variant.
void main() {
  PassFrame frame = pass_frame_from_uniforms();
  PixelRay ray;
  ray.world = ray_world;
  ray.view_z = ray_view_z;
  float depth = texelFetch(engine_depth, ivec2(gl_FragCoord.xy), 0).r;
#if VARIANT_PIXELS == PIXELS_CLASSIFY_LOW_SUN
  if (!pixel_needs_low_sun_path(ATMOSPHERE, frame, ray, depth)) discard;
#elif VARIANT_PIXELS == PIXELS_CLASSIFY_SPACE_VOLUME
  if (depth_is_sky(depth, depth_encoding) || !space_volume_covers(frame, space_volume_regular_columns, ray)) discard;
#else
  if (!depth_is_sky(depth, depth_encoding) || !sky_ray_misses_atmosphere(ATMOSPHERE, frame, ray)) discard;
#endif
  frag_color = vec4(0.0);
}

#elif VARIANT_PIXELS == PIXELS_INSTANT_SPACE

// The instant mode's multiple-scattering table (gpu/gl_util.hpp:
// kInstantMultipleScatteringUnit is 8 in its own programs; here 8 is the
// engine's depth).
layout(binding = 17) uniform sampler2D instant_multiple_scattering_texture;

void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  PassFrame frame = pass_frame_from_uniforms();
  PixelRay ray;
  ray.world = ray_world;
  ray.view_z = ray_view_z;
  float depth = texelFetch(engine_depth, pixel, 0).r;
  vec3 colour = vec3(0.0);
  vec3 albedo = vec3(0.0);
  vec3 normal = vec3(0.0, 0.0, 1.0);
#if VARIANT_SURFACE_MODE == SURFACE_GBUFFER
  albedo = texelFetch(engine_albedo, pixel, 0).rgb;
  normal = texelFetch(engine_normal, pixel, 0).rgb;
#else
  colour = texelFetch(engine_colour, pixel, 0).rgb;
#endif
  frag_color = vec4(instant_space_pixel(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture,
                                        instant_multiple_scattering_texture, irradiance_texture, frame, ray, depth,
                                        colour, albedo, normal),
                    1.0);
}

#elif VARIANT_PIXELS == PIXELS_CLASSIFY_ALL

// The stencil bits of every class of the frame: the low-sun class with
// VARIANT_LOW_SUN (and among its surfaces, bit 4, those in the planet's
// shadow), the space beside the atmosphere for cameras above it
// (!SKY_VIEW_CAMERA), the space volume's surfaces with VARIANT_SPACE_VOLUME;
// each as its own classifying program decides.
void main() {
  PassFrame frame = pass_frame_from_uniforms();
  PixelRay ray;
  ray.world = ray_world;
  ray.view_z = ray_view_z;
  float depth = texelFetch(engine_depth, ivec2(gl_FragCoord.xy), 0).r;
  bool sky = depth_is_sky(depth, depth_encoding);
  int bits = sky ? 1 : 0;
  bool night;
  if (VARIANT_LOW_SUN && pixel_low_sun_classes(ATMOSPHERE, frame, ray, depth, night)) {
    bits |= 2;
    if (night && !sky) bits |= 16;
  }
  if (!SKY_VIEW_CAMERA && sky && sky_ray_misses_atmosphere(ATMOSPHERE, frame, ray)) bits |= 4;
  if (VARIANT_SPACE_VOLUME && !sky && space_volume_covers(frame, space_volume_regular_columns, ray)) bits |= 8;
  gl_FragStencilRefARB = bits;
  frag_color = vec4(0.0);
}

#else

void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  PassFrame frame = pass_frame_from_uniforms();
  PixelRay ray;
  ray.world = ray_world;
  ray.view_z = ray_view_z;
  float dither = pixel_dither(gl_FragCoord.xy);
#if VARIANT_PIXELS == PIXELS_SPACE
  vec3 rgb = composite_space_pixel(ATMOSPHERE, frame, ray);
#elif VARIANT_PIXELS == PIXELS_SKY
  vec3 rgb = composite_sky_pixel(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, scattering_texture,
                                 single_aerosol_texture, multiple_scattering_texture, irradiance_texture,
                                 sky_view_rayleigh_texture, sky_view_aerosol_texture, sky_view_surface_texture,
                                 SKY_VIEW_CAMERA, ap_rayleigh, ap_single_rayleigh, ap_aerosol, ap_transmittance,
                                 frame, shadow_map, ray, dither);
#else
  float depth = texelFetch(engine_depth, pixel, 0).r;
  vec3 colour = vec3(0.0);
  vec3 albedo = vec3(0.0);
  vec3 normal = vec3(0.0, 0.0, 1.0);
#if VARIANT_SURFACE_MODE == SURFACE_GBUFFER
  albedo = texelFetch(engine_albedo, pixel, 0).rgb;
  normal = texelFetch(engine_normal, pixel, 0).rgb;
#else
  colour = texelFetch(engine_colour, pixel, 0).rgb;
#endif
  vec3 rgb = composite_surface_pixel(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, scattering_texture,
                                     single_aerosol_texture, multiple_scattering_texture, irradiance_texture,
                                     ap_rayleigh, ap_single_rayleigh, ap_aerosol, ap_transmittance, frame, shadow_map,
                                     ray, depth, colour, albedo, normal, dither);
#endif
  frag_color = vec4(rgb, 1.0);
}

#endif
