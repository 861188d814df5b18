// The C++ side of planet/noise.glsl: the GLSL subset's constructs on top of
// glm, with the noise's real type double (the relief's vertices are computed
// in double on the CPU), in namespace atmos::planet.
//
//   IN(T) -> const T&,  OUT(T) / INOUT(T) -> T&,  INLINE -> inline,
//   uint -> std::uint32_t (wrapping mod 2^32 as GLSL's uint does),
//   abs / clamp -> glm's (in GLSL, the built-ins).
#pragma once

#include <glm/glm.hpp>

#include <cstdint>

#ifndef IN
#define IN(T) const T&
#endif
#ifndef OUT
#define OUT(T) T&
#endif
#ifndef INOUT
#define INOUT(T) T&
#endif
#ifndef INLINE
#define INLINE inline
#endif

namespace atmos::planet {

using glm::abs;
using glm::clamp;
using glm::uvec3;
using uint = std::uint32_t;

#define NOISE_FLOAT double
#define NOISE_VEC3 glm::dvec3
#include "planet/noise.glsl"
#undef NOISE_FLOAT
#undef NOISE_VEC3

// gradient_noise (noise.glsl) on the CPU with the hashes of its eight
// corners (pcg3d) computed side by side, one corner per 32-bit lane of a
// GCC vector (SSE: two registers; AVX2: one), and the rest as
// gradient_noise computes it: the same value, bit for bit (the integer
// arithmetic is exact and the floating-point operations are the same, in
// the same order). tests/relief_test.cpp compares the two.
inline double gradient_noise_lanes(const uvec3& cell, const glm::dvec3& f, const uvec3& key) {
  using lanes = std::uint32_t __attribute__((vector_size(32)));
  const lanes corner_x = {0, 1, 0, 1, 0, 1, 0, 1}, corner_y = {0, 0, 1, 1, 0, 0, 1, 1};
  const lanes corner_z = {0, 0, 0, 0, 1, 1, 1, 1};
  lanes x = cell.x + corner_x + key.x, y = cell.y + corner_y + key.y, z = cell.z + corner_z + key.z;
  // pcg3d, whose last two lines (y and z) gradient_noise does not read.
  x = x * 1664525u + 1013904223u;
  y = y * 1664525u + 1013904223u;
  z = z * 1664525u + 1013904223u;
  x += y * z;
  y += z * x;
  z += x * y;
  x ^= x >> 16u;
  y ^= y >> 16u;
  z ^= z >> 16u;
  x += y * z;
  double n[8];
  for (int c = 0; c < 8; ++c)
    n[c] = noise_gradient_dot(x[c], f.x - double(c & 1), f.y - double((c >> 1) & 1), f.z - double(c >> 2));
  const double sx = noise_fade(f.x), sy = noise_fade(f.y), sz = noise_fade(f.z);
  const double x00 = n[0] + sx * (n[1] - n[0]);
  const double x10 = n[2] + sx * (n[3] - n[2]);
  const double x01 = n[4] + sx * (n[5] - n[4]);
  const double x11 = n[6] + sx * (n[7] - n[6]);
  const double y0 = x00 + sy * (x10 - x00);
  const double y1 = x01 + sy * (x11 - x01);
  return (y0 + sz * (y1 - y0)) * (2.0 / 3.0);
}

}  // namespace atmos::planet
