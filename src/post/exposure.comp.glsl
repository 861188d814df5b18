// atmos — automatic exposure (Collienne 2013, §4.6.3), GLSL only: the
// log-average luminance of the frame by a two-pass reduction, then the temporal
// adaptation. Pasted after tone_mapping.glsl and post_common.comp.glsl, with
// STAGE_REDUCE or STAGE_ADAPT defined.
//
// Collienne 2013 takes the plain average colour from the last mip level; the
// log average (Reinhard et al. 2002, eq. 1) of the eq. 4.27 luminance is used
// instead so that the sun's few ~1e9 cd/m² pixels do not set the exposure of
// a ~1e4 cd/m² sky on their own.

// The sums go to PartialSums (post_common.comp.glsl). With bloom, after the
// first frame, the bloom's bright pass computes them while it reads the
// image anyway, and STAGE_REDUCE does not run (bloom.comp.glsl).

#ifdef STAGE_REDUCE
// One invocation per column and strip of REDUCE_ROWS rows: it sums the log
// luminances of its REDUCE_ROWS pixels (neighbouring invocations read
// neighbouring pixels) and writes the sum to its own slot, with no
// shared-memory tree: on llvmpipe each barrier costs about as much as the
// image read itself (post_common.comp.glsl). STAGE_ADAPT adds the slots.
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform sampler2D source;
layout(location = 0) uniform float nits_per_unit;

void main() {
  ivec2 size = textureSize(source, 0);
  ivec2 origin = ivec2(gl_GlobalInvocationID.x, gl_GlobalInvocationID.y * REDUCE_ROWS);
  float sum = 0.0;
  for (int j = 0; j < REDUCE_ROWS; ++j) {
    ivec2 p = origin + ivec2(0, j);
    // Pixels beyond the image (the last column group and strip) count nothing.
    float inside = (p.x < size.x && p.y < size.y) ? 1.0 : 0.0;
    vec3 rgb = texelFetch(source, min(p, size - 1), 0).rgb * nits_per_unit;
    sum += inside * log_luminance(rgb);
  }
  partial_sum[gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x + gl_GlobalInvocationID.x] = sum;
}
#endif

#ifdef STAGE_ADAPT
// One work group adds the strips' sums (a tree over 256 invocations: the
// only barriers of the chain, in one work group), then one invocation turns the mean
// log luminance into the target EV (Collienne 2013, eq. 4.28) and adapts.
layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;
layout(location = 0) uniform int partial_count;
layout(location = 1) uniform float pixel_count;
layout(location = 2) uniform float dt_s;
layout(location = 3) uniform float key;
layout(location = 4) uniform float compensation_ev;
layout(location = 5) uniform float ev_min;
layout(location = 6) uniform float ev_max;
layout(location = 7) uniform float brightening_tau_s;
layout(location = 8) uniform float darkening_tau_s;
shared float group_sum[256];

void main() {
  uint index = gl_LocalInvocationIndex;
  float sum = 0.0;
  for (int i = int(index); i < partial_count; i += 256) sum += partial_sum[i];
  group_sum[index] = sum;
  barrier();
  for (uint half_count = 128u; half_count > 0u; half_count >>= 1) {
    if (index < half_count) group_sum[index] += group_sum[index + half_count];
    barrier();
  }
  if (index == 0u) {
    float log_average = exp(group_sum[0] / pixel_count);
    float target = exposure_target_ev(log_average, key, compensation_ev, ev_min, ev_max);
    // The first frame after a reset starts adapted (a still image, a cut).
    float ev = exposure_state.initialized != 0
                   ? adapted_ev(exposure_state.adapted_ev, target, dt_s, brightening_tau_s, darkening_tau_s)
                   : target;
    exposure_state.adapted_ev = ev;
    exposure_state.frame_ev = ev;
    exposure_state.log_average_luminance = log_average;
    exposure_state.initialized = 1;
  }
}
#endif
