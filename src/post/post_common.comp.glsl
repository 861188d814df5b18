// atmos — declarations shared by the compute shaders of PostProcess (GLSL
// only; post/post_process.cpp pastes it after tone_mapping.glsl and before
// exposure.comp.glsl, bloom.comp.glsl or tone_map.comp.glsl).
//
// Cost model. The kernels are written for Mesa llvmpipe (CI, machines
// without a GPU) as much as for GPUs: llvmpipe runs 8 invocations per SIMD
// instruction, executes both sides of every branch, and pays ~1.5-3 ns per
// texel fetch or image load and more per float image store, while
// arithmetic is nearly free. So every kernel computes a small block of
// outputs per invocation from the texels the block shares (each texel is
// read about once instead of once per output that uses it), uses no
// shared-memory barriers (each costs about as much as a full-screen fetch)
// and has no data-dependent branches.

// The exposure of the frame and the state of the eye adaptation. The CPU
// writes frame_ev for a manual exposure; exposure.comp.glsl writes the first
// four fields with automatic exposure. Persists across frames
// (PostProcess::reset clears `initialized`).
layout(std430, binding = 0) buffer ExposureState {
  float frame_ev;               // EV100 this frame is exposed at
  float adapted_ev;             // EV100 the eye is adapted to (auto exposure)
  float log_average_luminance;  // cd/m², of the last frame measured
  int initialized;              // 0: no frame measured since the last reset
  // EV100 of the exposure the bloom's bright pass thresholded at (written by
  // the bright pass: the frame's exposure, or with auto exposure the one the
  // frame started from, see bloom.comp.glsl); the tone-map pass takes the
  // same bright part out of each pixel, which keeps the light balance exact.
  float bloom_ev;
} exposure_state;

// The log-luminance sums of the auto-exposure reduction: one per invocation
// of exposure.comp.glsl's STAGE_REDUCE or of the bloom's bright pass, added
// up by STAGE_ADAPT.
layout(std430, binding = 1) buffer PartialSums { float partial_sum[]; };

// The bloom pyramid. Level k+1 has floor(n_k / 2) + 1 texels along each
// axis, texel i centred on texel 2i of level k (a centred pyramid: a bright
// texel anywhere spreads symmetrically about itself, which the usual 2 x 2
// box pyramid cannot do: it shifts light by half a texel per level).
//
// Light balance. Upsampling is linear interpolation (U: fine texel 2i is
// coarse texel i, 2i + 1 the mean of i and i + 1), which keeps uniform levels
// uniform. Each texel then stands for a number of full-resolution pixels, its
// weight w (4^k inside level k, less at the edges, where some of its
// interpolation partners would be outside the image): per axis
// w(k+1, i) = sum_j w(k, j) U(j, i), and a texel's weight is the product of
// its two axis weights. The weights are dyadic rationals (exact in float);
// each level stores its texels' weights in the alpha channel, so the kernels
// get them with the colour, and an image load outside the level returns 0:
// weight 0, i.e. no texel, with no bounds test. Downsampling is U's weighted
// adjoint,
//   D(i, j) = w(k, j) U(j, i) / w(k+1, i)
// (inside: the tent 1/4, 1/2, 1/4 per axis), which keeps uniform levels
// uniform (rows sum to 1) and conserves sum(w c) exactly (sum_i w(k+1, i)
// D(i, j) = w(k, j)). The blur is made to do the same by Metropolis
// weighting (bloom.comp.glsl). So the bloom neither brightens nor darkens the
// borders and conserves the light up to float rounding: no light leaves the
// image, none enters.

// The interpolation weight U(2i + d, i) of the finer texel 2i + d (d = -1, 0,
// 1) in coarser texel i.
float interpolation_weight(int d) { return d == 0 ? 1.0 : 0.5; }

// Linear interpolation of a coarser level at the finer texels 2i and 2i + 1
// from its texels i and i + 1 (one axis; the texel i + 1 always exists:
// floor(n / 2) + 1 texels cover the finer level's n).
vec3 upsampled_even(vec3 at_i) { return at_i; }
vec3 upsampled_odd(vec3 at_i, vec3 at_next) { return 0.5 * (at_i + at_next); }
