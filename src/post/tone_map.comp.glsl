// atmos — the tone-map pass of PostProcess, GLSL only: bloom composite,
// exposure, tone-mapping operator, display encoding. Pasted after
// tone_mapping.glsl and post_common.comp.glsl with OPERATOR (a TONE_MAP_*
// constant), OUTPUT_FORMAT (the image format qualifier), ENCODED (1: 8-bit
// display values, 0: display-linear) and BLOOM (0 or 1) defined: compile-time
// constants, so that the program holds only the operator it uses (software
// rasterisers run both sides of every branch).

// Each invocation writes a 2 x 2 block of pixels: with bloom they share the
// 2 x 2 level-1 texels their linear interpolation reads (one load per pixel
// instead of four; post_common.comp.glsl).
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0) uniform sampler2D source;
layout(binding = 0, OUTPUT_FORMAT) writeonly uniform image2D destination;
layout(location = 0) uniform float nits_per_unit;
#if BLOOM
layout(binding = 1, rgba32f) readonly uniform image2D bloom_level;  // level 1, blurred and mixed
layout(location = 1) uniform float bloom_strength;
layout(location = 2) uniform float bloom_threshold;
#endif

void main() {
  ivec2 coarse = ivec2(gl_GlobalInvocationID.xy);
  ivec2 first = 2 * coarse;
  ivec2 size = textureSize(source, 0);
  float exposure = exposure_from_ev100(exposure_state.frame_ev);
#if BLOOM
  // The bright part the bloom's bright pass took (at its exposure).
  float bloom_exposure = exposure_from_ev100(exposure_state.bloom_ev);
  // Level 1 linearly interpolated at the block's pixels: [x][y], x and y
  // even (texel centre) or odd (between two texels).
  vec3 glare[2][2];
  for (int r = 0; r < 2; ++r) {
    vec3 left = imageLoad(bloom_level, coarse + ivec2(0, r)).rgb;
    vec3 right = imageLoad(bloom_level, coarse + ivec2(1, r)).rgb;
    glare[0][r] = upsampled_even(left);
    glare[1][r] = upsampled_odd(left, right);
  }
#endif
  for (int by = 0; by < 2; ++by) {
    for (int bx = 0; bx < 2; ++bx) {
      // The block's pixels beyond the image (odd sizes) read the last
      // pixel; their stores have no effect (OpenGL 4.5 §8.26).
      ivec2 p = first + ivec2(bx, by);
      vec3 scene = texelFetch(source, min(p, size - 1), 0).rgb * nits_per_unit;
#if BLOOM
      // A fraction `strength` of the bright part leaves the pixel and the same
      // fraction of the blurred bright parts arrives (Collienne 2013, §4.6.1).
      vec3 up = by == 0 ? upsampled_even(glare[bx][0]) : upsampled_odd(glare[bx][0], glare[bx][1]);
      scene += bloom_strength * (up - bright_part(scene, bloom_exposure, bloom_threshold));
#endif
      vec3 exposed = scene * exposure;
#if ENCODED
      vec3 display = display_encoded(exposed, OPERATOR);
#else
      vec3 display = display_linear(exposed, OPERATOR);
#endif
      imageStore(destination, p, vec4(display, 1.0));
    }
  }
}
