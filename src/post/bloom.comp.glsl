// atmos — bloom (Collienne 2013, §4.6.1), GLSL only: bright pass, centred mip
// pyramid, separable Gaussian per level, upsample-and-mix from the coarsest
// level. Pasted after tone_mapping.glsl and post_common.comp.glsl with one of
// STAGE_BRIGHT, STAGE_DOWNSAMPLE, STAGE_BLUR_X, STAGE_BLUR_Y defined
// (STAGE_BRIGHT with or without WITH_REDUCTION, STAGE_BLUR_Y with or without
// HAS_COARSER), BLOOM_RADIUS (taps each side)
// and BLOOM_KERNEL (the normalised Gaussian weights 0..BLOOM_RADIUS, computed
// on the CPU by post_process.cpp with Turkowski's incremental Gaussian of
// tone_mapping.glsl).
//
// Light is conserved (see post_common.comp.glsl): the weighted downsampling,
// the Metropolis-weighted Gaussian and the linear upsampling each keep the
// sum of (value x weight) and keep uniform levels uniform, and the mix of the
// levels is convex. The tone-map pass then adds strength * (bloom - bright
// part) to each pixel: the bright part's light is redistributed, none is
// created.
//
// Every kernel computes a block of outputs per invocation from the texels
// the block shares (post_common.comp.glsl: texel reads are what costs on
// llvmpipe); the loops have constant trip counts and unroll. Blocks that
// reach past the level store nothing there (image stores outside an image
// have no effect, OpenGL 4.5 §8.26) and read zeros (weight 0) from image
// loads outside it.

// The downsampling kernels compute a 2 x 2 block of coarser texels per
// invocation from the 5 x 5 finer texels 2 first - 1 + (0..4) it shares
// (25 reads for 4 texels instead of 36). Along one axis coarser texel
// `first` takes the finer 0, 1, 2 with U = 1/2, 1, 1/2 and `first + 1` the
// finer 2, 3, 4. The outer taps are added first, so that mirrored inputs
// round alike.
#if defined(STAGE_BRIGHT) || defined(STAGE_DOWNSAMPLE)
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

vec4 tent(vec4 before, vec4 centre, vec4 after) { return 0.5 * (before + after) + centre; }

// Rows f = 0..4 of the 5 x 5 finer values (rgb: U w c, alpha: w), each
// reduced along x to the block's two columns, then along y: the block's
// sums of U U w c and U U w.
struct Rows {
  vec4 left[5];
  vec4 right[5];
};

void store_block(writeonly image2D destination, ivec2 first, Rows rows) {
  vec4 s00 = tent(rows.left[0], rows.left[1], rows.left[2]);
  vec4 s10 = tent(rows.right[0], rows.right[1], rows.right[2]);
  vec4 s01 = tent(rows.left[2], rows.left[3], rows.left[4]);
  vec4 s11 = tent(rows.right[2], rows.right[3], rows.right[4]);
  // Colour: the weighted mean; alpha: the texel's weight (pixels it stands for).
  imageStore(destination, first, vec4(s00.rgb / s00.a, s00.a));
  imageStore(destination, first + ivec2(1, 0), vec4(s10.rgb / s10.a, s10.a));
  imageStore(destination, first + ivec2(0, 1), vec4(s01.rgb / s01.a, s01.a));
  imageStore(destination, first + ivec2(1, 1), vec4(s11.rgb / s11.a, s11.a));
}
#endif

#if defined(STAGE_BRIGHT)
// Level 1 from the input: the tent over the bright parts of the pixels
// (weight 1 each), each pixel's bright part computed once per block.
//
// With WITH_REDUCTION defined the same reads give the auto exposure's
// reduction (Collienne 2013, §4.6.3, exposure.comp.glsl): each invocation also
// writes the sum of the log luminances of its own 4 x 4 pixels, 2 first + (0..3)
// (f = 1..4 of its 5 x 5; f = 0 is the neighbour's), to PartialSums. This
// saves the reduction's own read of the full-resolution image, but the
// exposure is then known only after the bright pass: the bright pass
// thresholds at the exposure in ExposureState when the frame starts, i.e.
// with auto exposure the previous frame's adapted exposure (one frame
// behind: a few percent of the way to the target at 60 frames/s, against
// 0.5 s and 2 s adaptation times). PostProcess runs STAGE_REDUCE before the
// bright pass instead for the first frame after construction or reset()
// (a still image is thresholded at its own exposure) and when bloom is off.
layout(binding = 0) uniform sampler2D source;
layout(binding = 0, rgba32f) writeonly uniform image2D destination;
layout(location = 0) uniform float nits_per_unit;
layout(location = 1) uniform float threshold;

void main() {
  ivec2 first = 2 * ivec2(gl_GlobalInvocationID.xy);
  ivec2 n = textureSize(source, 0);
  ivec2 origin = 2 * first - 1;
  float ev = exposure_state.frame_ev;
  float exposure = exposure_from_ev100(ev);
  if (gl_GlobalInvocationID.x == 0u && gl_GlobalInvocationID.y == 0u) exposure_state.bloom_ev = ev;
  Rows rows;
  float log_sum = 0.0;
  for (int fy = 0; fy < 5; ++fy) {
    vec4 t[5];
    for (int fx = 0; fx < 5; ++fx) {
      // Pixels outside the input weigh 0 (texel fetches outside a texture
      // are undefined: the coordinates are clamped and the pixel zeroed).
      ivec2 q = origin + ivec2(fx, fy);
      float inside = (q.x >= 0 && q.x < n.x && q.y >= 0 && q.y < n.y) ? 1.0 : 0.0;
      vec3 rgb = texelFetch(source, clamp(q, ivec2(0), n - 1), 0).rgb * nits_per_unit;
      t[fx] = inside * vec4(bright_part(rgb, exposure, threshold), 1.0);
#ifdef WITH_REDUCTION
      if (fx > 0 && fy > 0) log_sum += inside * log_luminance(rgb);
#endif
    }
    rows.left[fy] = tent(t[0], t[1], t[2]);
    rows.right[fy] = tent(t[2], t[3], t[4]);
  }
  store_block(destination, first, rows);
#ifdef WITH_REDUCTION
  partial_sum[gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x + gl_GlobalInvocationID.x] = log_sum;
#endif
}
#endif

#if defined(STAGE_DOWNSAMPLE)
// Level k+1 from level k: the same tent with level k's weights (alpha);
// loads outside level k give 0, weight 0.
layout(binding = 0, rgba32f) readonly uniform image2D source;
layout(binding = 1, rgba32f) writeonly uniform image2D destination;

void main() {
  ivec2 first = 2 * ivec2(gl_GlobalInvocationID.xy);
  ivec2 origin = 2 * first - 1;
  Rows rows;
  for (int fy = 0; fy < 5; ++fy) {
    vec4 t[5];
    for (int fx = 0; fx < 5; ++fx) {
      vec4 texel = imageLoad(source, origin + ivec2(fx, fy));
      t[fx] = vec4(texel.rgb * texel.a, texel.a);
    }
    rows.left[fy] = tent(t[0], t[1], t[2]);
    rows.right[fy] = tent(t[2], t[3], t[4]);
  }
  store_block(destination, first, rows);
}
#endif

#if defined(STAGE_BLUR_X) || defined(STAGE_BLUR_Y)
// Each invocation blurs BLUR_BLOCK texels in a row (x) or a 2 x BLUR_BLOCK
// column pair (y: the mix with the coarser level then reads 2 x
// (BLUR_BLOCK / 2 + 1) coarser texels for 2 x BLUR_BLOCK outputs), reading
// BLUR_BLOCK + 2 BLOOM_RADIUS texels per row or column instead of
// (2 BLOOM_RADIUS + 1) per output.
const int BLUR_BLOCK = 4;
const int BLUR_SPAN = BLUR_BLOCK + 2 * BLOOM_RADIUS;
const float KERNEL[BLOOM_RADIUS + 1] = BLOOM_KERNEL;

layout(binding = 0, rgba32f) readonly uniform image2D source;
layout(binding = 1, rgba32f) writeonly uniform image2D destination;
#ifdef HAS_COARSER
// The next coarser level, already blurred and mixed.
layout(binding = 2, rgba32f) readonly uniform image2D coarser;
layout(location = 0) uniform float coarser_weight;
#endif

#ifdef STAGE_BLUR_X
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
const ivec2 AXIS = ivec2(1, 0);
const int COLUMNS = 1;  // texels across the axis per invocation
#else
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
const ivec2 AXIS = ivec2(0, 1);
const int COLUMNS = 2;
#endif
const ivec2 ACROSS = ivec2(1, 1) - AXIS;

// Metropolis weighting of the Gaussian g (Hastings 1970): texel i takes
// g(i - j) min(1, w_j / w_i) of its neighbour j's value and keeps the rest of
// its own (taps outside the level, weight 0, give theirs to the centre).
// Then w_i G'(i, j) = g(i - j) min(w_i, w_j) is symmetric: G' keeps sum(w c)
// (detailed balance) and its rows sum to 1 (uniform stays uniform), for the
// texels of different weight at the edges as well. Inside a level all
// weights are equal and G' is the plain Gaussian. Arithmetic, not the loads,
// bounds this kernel on llvmpipe: each tap costs one scalar weight
// g min(w_i, w_j) and one vec3 multiply-add,
//   G' c (i) = c_i + (sum_j g min(w_i, w_j) c_j - c_i sum_j g min(w_i, w_j)) / w_i.
vec3 blurred(vec4 centre, vec4 taps[BLUR_SPAN], int at) {
  vec3 sum = vec3(0.0);
  float weight_sum = 0.0;
  for (int k = 1; k <= BLOOM_RADIUS; ++k) {
    vec4 before = taps[at - k], after = taps[at + k];
    float w_before = KERNEL[k] * min(centre.a, before.a), w_after = KERNEL[k] * min(centre.a, after.a);
    sum += w_before * before.rgb + w_after * after.rgb;
    weight_sum += w_before + w_after;
  }
  return centre.rgb + (sum - weight_sum * centre.rgb) / centre.a;
}

void main() {
  ivec2 first = ivec2(gl_GlobalInvocationID.xy) * (BLUR_BLOCK * AXIS + COLUMNS * ACROSS);
  vec3 result[COLUMNS][BLUR_BLOCK];
  float weight[COLUMNS][BLUR_BLOCK];
  for (int c = 0; c < COLUMNS; ++c) {
    vec4 taps[BLUR_SPAN];
    for (int s = 0; s < BLUR_SPAN; ++s) taps[s] = imageLoad(source, first + c * ACROSS + (s - BLOOM_RADIUS) * AXIS);
    for (int o = 0; o < BLUR_BLOCK; ++o) {
      result[c][o] = blurred(taps[o + BLOOM_RADIUS], taps, o + BLOOM_RADIUS);
      weight[c][o] = taps[o + BLOOM_RADIUS].a;
    }
  }
#ifdef HAS_COARSER
  // The level's own blur mixed with the coarser level linearly interpolated
  // (post_common.comp.glsl): `first` is even along both axes, so column
  // c = 0 is coarser column first.x / 2 and c = 1 the mean of it and the next;
  // rows alike.
  const int COARSER_ROWS = BLUR_BLOCK / 2 + 1;
  ivec2 coarse_first = first / 2;
  vec3 coarse[COARSER_ROWS][2];
  for (int r = 0; r < COARSER_ROWS; ++r) {
    vec3 left = imageLoad(coarser, coarse_first + ivec2(0, r)).rgb;
    coarse[r][0] = upsampled_even(left);
    coarse[r][1] = upsampled_odd(left, imageLoad(coarser, coarse_first + ivec2(1, r)).rgb);
  }
  for (int c = 0; c < COLUMNS; ++c) {
    for (int o = 0; o < BLUR_BLOCK; ++o) {
      vec3 up = (o % 2 == 0) ? upsampled_even(coarse[o / 2][c]) : upsampled_odd(coarse[o / 2][c], coarse[o / 2 + 1][c]);
      result[c][o] = (1.0 - coarser_weight) * result[c][o] + coarser_weight * up;
    }
  }
#endif
  for (int c = 0; c < COLUMNS; ++c)
    for (int o = 0; o < BLUR_BLOCK; ++o)
      imageStore(destination, first + c * ACROSS + o * AXIS, vec4(result[c][o], weight[c][o]));
}
#endif
