// The vector layer of the precomputation's inner loops (steps.cpp): vectors
// of 4 floats (a texel's three channels and a zero) and of 8 floats (eight
// texels, view directions, spherical harmonics or points of two solar discs
// at a time), their loads, stores and per-lane helpers, and an exponential of
// eight floats. Everything here is inlined into the kernels that use it
// (ATMOS_KERNEL_INLINE), so that it is compiled for each copy of a kernel
// (ATMOS_HOT_KERNEL), and has internal linkage (static), as the kernels'
// own helpers have: GCC then allocates the kernels' registers as it would
// with the helpers written in the kernels' file.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstring>

#include "physics/shader_cpp.hpp"

// The hot loops of the steps are compiled twice, for x86-64-v3 (AVX2 and
// FMA: three-operand vector instructions, fused multiply-adds in the
// interpolations and exp8's polynomial) and for the baseline, and the first
// call picks the one the CPU supports (GCC's target_clones, an ifunc). The
// fused multiply-adds of the v3 copy round once instead of twice, so the
// tables of the two copies differ by float rounding only. The option
// ATMOS_KERNEL_CLONES=OFF (CMake; the sanitizer build) leaves only the
// baseline code, which tests it.
#if defined(ATMOS_KERNEL_CLONES) && defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define ATMOS_HOT_KERNEL __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define ATMOS_HOT_KERNEL
#endif
// Inlined into each copy of a kernel (compiled for the copy's target).
#define ATMOS_KERNEL_INLINE inline __attribute__((always_inline))

// Eight lanes are one AVX register in the x86-64-v3 copy of the kernels and
// two SSE registers (the same instructions as two v4f) in the baseline copy.
// They only pass between functions that are inlined (ATMOS_KERNEL_INLINE), so
// the calling convention GCC warns about (-Wpsabi: returned in memory without
// AVX) never applies; parameters are references, which GCC does not note. The
// warning stays off for the rest of the including file, whose own inlined
// helpers return v8f too.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace atmos::precompute::simd {

using v4f = float __attribute__((vector_size(16)));  // GCC/Clang vector extension: SSE on x86-64
using v8f = float __attribute__((vector_size(32)));
using v8i = int __attribute__((vector_size(32)));

static ATMOS_KERNEL_INLINE v4f splat(float x) { return v4f{x, x, x, x}; }
static ATMOS_KERNEL_INLINE v8f splat8(float x) { return v8f{} + x; }

// Eight floats from memory, and back. v8f is not kept in memory that the
// kernels share with each other or with the heap: its alignment is 32 in the
// x86-64-v3 copy and 16 (what std::allocator gives) in the baseline's view of
// the type.
static ATMOS_KERNEL_INLINE v8f load8(const float* p) {
  v8f v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
static ATMOS_KERNEL_INLINE void store8(float* p, const v8f& v) { std::memcpy(p, &v, sizeof(v)); }

// A vec3 as a vector of 4 floats (the fourth 0), and back.
static ATMOS_KERNEL_INLINE v4f to_v4f(const physics::vec3& v) { return v4f{v.x, v.y, v.z, 0.0f}; }
static ATMOS_KERNEL_INLINE physics::vec3 to_vec3(v4f v) { return physics::vec3(v[0], v[1], v[2]); }

// Per-lane max, min and clamp, as loops over the lanes: GCC vectorises these
// for either copy (maxps / vmaxps), while its conditional ?: on eight lanes
// becomes a branch per lane when AVX is not available (GCC 12).
static ATMOS_KERNEL_INLINE v8f max8(const v8f& a, float b) {
  v8f r;
  for (int k = 0; k < 8; ++k) r[k] = a[k] < b ? b : a[k];
  return r;
}
static ATMOS_KERNEL_INLINE v8f min8(const v8f& a, float b) {
  v8f r;
  for (int k = 0; k < 8; ++k) r[k] = a[k] > b ? b : a[k];
  return r;
}
static ATMOS_KERNEL_INLINE v8f clamp8(const v8f& x, float low, float high) { return min8(max8(x, low), high); }
static ATMOS_KERNEL_INLINE v8i min8(const v8i& a, int b) {
  v8i r;
  for (int k = 0; k < 8; ++k) r[k] = a[k] > b ? b : a[k];
  return r;
}

// sqrt per lane (-fno-math-errno: one vector square root).
static ATMOS_KERNEL_INLINE v8f sqrt8(const v8f& x) {
  v8f r;
  for (int k = 0; k < 8; ++k) r[k] = std::sqrt(x[k]);
  return r;
}

// exp(x) of eight floats: the Cephes expf (Moshier 1989), as in its SSE
// versions. Range reduction x = n ln 2 + g with ln 2 in two parts
// (0.693359375, whose products with n are exact, and -2.12194440e-4), a degree-5 polynomial for e^g on |g| <= ln 2 / 2, and the
// factor 2^n built in the exponent bits. Over every float in [-87.3, 0] it
// is within 0.98 ulp of the exact exponential, 1.01 with the fused
// multiply-adds of the x86-64-v3 copy (libm's expf: 0.5); below -87.3, where
// expf is denormal or 0, it is 0 (an optical depth of 87 transmits nothing).
static ATMOS_KERNEL_INLINE v8f exp8(const v8f& argument) {
  v8f x = clamp8(argument, -87.3365447f, 88.3762626f);
  // n = floor(x / ln 2 + 1/2)
  const v8f fx = x * 1.44269504088896341f + 0.5f;
  v8f n = __builtin_convertvector(__builtin_convertvector(fx, v8i), v8f);
  // Truncation rounded a negative fx up: one less there. The comparison's
  // lanes are -1 (true) or 0, added as floats: a vector compare and add, where
  // the same select written as a loop over the lanes becomes a scalar loop
  // through memory (GCC 12).
  n += __builtin_convertvector(n > fx, v8f);
  x = x - n * 0.693359375f + n * 2.12194440e-4f;
  v8f y = splat8(1.9875691500e-4f);
  y = y * x + 1.3981999507e-3f;
  y = y * x + 8.3334519073e-3f;
  y = y * x + 4.1665795894e-2f;
  y = y * x + 1.6666665459e-1f;
  y = y * x + 5.0000001201e-1f;
  y = y * (x * x) + x + 1.0f;
  const v8i bits = (__builtin_convertvector(n, v8i) + 127) << 23;
  y = y * std::bit_cast<v8f>(bits);
  for (int k = 0; k < 8; ++k) y[k] = argument[k] < -87.3365447f ? 0.0f : y[k];
  return y;
}

// The 4 x 4 matrix of floats m (rows m[k]) transposed in place.
static ATMOS_KERNEL_INLINE void transpose4(std::array<v4f, 4>& m) {
  const v4f a = __builtin_shufflevector(m[0], m[1], 0, 4, 1, 5), b = __builtin_shufflevector(m[2], m[3], 0, 4, 1, 5);
  const v4f c = __builtin_shufflevector(m[0], m[1], 2, 6, 3, 7), d = __builtin_shufflevector(m[2], m[3], 2, 6, 3, 7);
  m[0] = __builtin_shufflevector(a, b, 0, 1, 4, 5);
  m[1] = __builtin_shufflevector(a, b, 2, 3, 6, 7);
  m[2] = __builtin_shufflevector(c, d, 0, 1, 4, 5);
  m[3] = __builtin_shufflevector(c, d, 2, 3, 6, 7);
}

// The eight lanes of two v4f.
static ATMOS_KERNEL_INLINE v8f concat(v4f low, v4f high) {
  return __builtin_shufflevector(low, high, 0, 1, 2, 3, 4, 5, 6, 7);
}

}  // namespace atmos::precompute::simd
