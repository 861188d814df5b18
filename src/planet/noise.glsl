// atmos planet — lattice gradient noise shared by the CPU relief (compiled as
// C++ through planet/noise_cpp.hpp, in double) and the shaders (GLSL 4.50, in
// float), written in the common subset of both languages: functions marked
// INLINE, parameters IN(T), integer arithmetic on uint (wrapping mod 2^32 in
// both), no recursion, no swizzles, no arrays.
//
// Precision. The caller passes split lattice coordinates: the integer cell
// (mod 2^32) and the fraction in [0, 1) within it. At a planet's radius a
// float position has an ulp of 0.5 m (6.4e6 m), so a float position divided
// by a wavelength of 500 m keeps only ~1e-3 of the cell; split coordinates
// keep the fraction exact to the precision of the type whatever the cell
// index, which is what makes octaves below a metre usable.
//
// NOISE_FLOAT / NOISE_VEC3 are the real type of the fraction and the result:
// float / vec3 in GLSL (the defaults below), double / dvec3 on the CPU.

#ifndef NOISE_FLOAT
#define NOISE_FLOAT float
#define NOISE_VEC3 vec3
#endif

// pcg3d (Jarzynski & Olano 2020, §3): a permuted congruential step on each
// component followed by two rounds of mixing the components into each other;
// three well-mixed 32-bit outputs from three 32-bit inputs.
INLINE uvec3 pcg3d(uvec3 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v = v ^ (v >> 16u);
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  return v;
}

// Quintic fade s(t) = 6t^5 - 15t^4 + 10t^3 (Perlin 2002): s(0) = 0, s(1) = 1,
// s' and s'' vanish at both ends, so the noise is C2 across cell faces.
// max s' = 15/8 at t = 1/2; max |s''| = 10/sqrt(3) at t = (3 -+ sqrt(3))/6.
INLINE NOISE_FLOAT noise_fade(NOISE_FLOAT t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// g . d for the lattice gradient g selected by the hash's top four bits among
// the 12 cube-edge directions (1,1,0), (1,0,1), (0,1,1) with signs, four of
// them twice (Perlin 2002, §3): every g has two components +-1 and one 0.
INLINE NOISE_FLOAT noise_gradient_dot(uint hash, NOISE_FLOAT x, NOISE_FLOAT y, NOISE_FLOAT z) {
  uint k = hash >> 28u;
  NOISE_FLOAT u = k < 8u ? x : y;
  NOISE_FLOAT v = k < 4u ? y : ((k == 12u || k == 14u) ? x : z);
  return ((k & 1u) == 0u ? u : -u) + ((k & 2u) == 0u ? v : -v);
}

INLINE NOISE_FLOAT noise_corner(IN(uvec3) cell, IN(uvec3) key, uint cx, uint cy, uint cz, IN(NOISE_VEC3) f) {
  uvec3 h = pcg3d(cell + uvec3(cx, cy, cz) + key);
  return noise_gradient_dot(h.x, f.x - NOISE_FLOAT(cx), f.y - NOISE_FLOAT(cy), f.z - NOISE_FLOAT(cz));
}

// Gradient noise (Perlin 2002) at fraction f of lattice cell `cell`, the
// lattice chosen by `key` (a hashed seed per layer and octave), scaled by 2/3
// so that |n| <= 1 holds rigorously:
//   n = sum over the 8 corners c of W_c(f) g_c . (f - c), W_c = prod_i w_i,
//   w_i = s(f_i) or 1 - s(f_i) (a partition of unity), |g_c . (f - c)| <=
//   sum_i |f_i - c_i|, and for each axis sum_c W_c |f_i - c_i| =
//   f + s(f)(1 - 2f) <= 1/2 (since (1 - 2f)(s(f) - 1/2) <= 0), so the raw
//   sum is at most 3/2.
// The bounds of its first and second directional derivatives per lattice
// unit, from the same sums, are derived in planet/relief.cpp.
INLINE NOISE_FLOAT gradient_noise(IN(uvec3) cell, IN(NOISE_VEC3) f, IN(uvec3) key) {
  NOISE_FLOAT sx = noise_fade(f.x);
  NOISE_FLOAT sy = noise_fade(f.y);
  NOISE_FLOAT sz = noise_fade(f.z);
  NOISE_FLOAT n000 = noise_corner(cell, key, 0u, 0u, 0u, f);
  NOISE_FLOAT n100 = noise_corner(cell, key, 1u, 0u, 0u, f);
  NOISE_FLOAT n010 = noise_corner(cell, key, 0u, 1u, 0u, f);
  NOISE_FLOAT n110 = noise_corner(cell, key, 1u, 1u, 0u, f);
  NOISE_FLOAT n001 = noise_corner(cell, key, 0u, 0u, 1u, f);
  NOISE_FLOAT n101 = noise_corner(cell, key, 1u, 0u, 1u, f);
  NOISE_FLOAT n011 = noise_corner(cell, key, 0u, 1u, 1u, f);
  NOISE_FLOAT n111 = noise_corner(cell, key, 1u, 1u, 1u, f);
  NOISE_FLOAT x00 = n000 + sx * (n100 - n000);
  NOISE_FLOAT x10 = n010 + sx * (n110 - n010);
  NOISE_FLOAT x01 = n001 + sx * (n101 - n001);
  NOISE_FLOAT x11 = n011 + sx * (n111 - n011);
  NOISE_FLOAT y0 = x00 + sy * (x10 - x00);
  NOISE_FLOAT y1 = x01 + sy * (x11 - x01);
  return (y0 + sz * (y1 - y0)) * (2.0 / 3.0);
}

// Ridge of a noise value, (1 - |n|)^2 in [0, 1]: crests along the zero set of
// n (Musgrave, Kolb & Mace 1989; Ebert et al. 2003, ch. 16). Continuous with a
// slope jump on the crest, Lipschitz 2 in n.
INLINE NOISE_FLOAT noise_ridge(NOISE_FLOAT n) {
  NOISE_FLOAT r = 1.0 - abs(n);
  return r * r;
}

// Quintic smoothstep clamped to [0, 1] outside [0, 1]: a C2 mask.
INLINE NOISE_FLOAT noise_smooth_mask(NOISE_FLOAT t) { return noise_fade(clamp(t, 0.0, 1.0)); }
