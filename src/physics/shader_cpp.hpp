// The C++ side of the shared physics: the C++ meaning of the GLSL subset
// (definitions.glsl) on top of glm, and definitions.glsl itself, in namespace
// atmos::physics. The parts of the physics (the other src/physics/*.glsl)
// are compiled by physics/<part>_cpp.hpp, each of which includes the headers
// of the parts it needs: a translation unit includes those of the parts it
// uses.
//
// GLSL constructs map as follows:
//   IN(T) -> const T&,  OUT(T)/INOUT(T) -> T&,  INLINE -> inline,
//   sampler2D / sampler3D -> read-only views of CPU tables, sampled by
//   texture() with the exact arithmetic of GL_LINEAR + GL_CLAMP_TO_EDGE;
//   sampler2DShadow -> the same with depth comparison (PCF).
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <cstddef>
#include <vector>

#include "physics/glsl_subset_cpp.hpp"

namespace atmos::physics {

using namespace glm;

// Loop bounds: in C++ the structures' own counts (and the largest knot
// count); in shaders compile-time constants of the atmosphere (see
// gpu/shader_source.cpp), which let the compiler unroll the loops.
#define SPECTRAL_COUNT(s) ((s).count)
#define CONSTITUENT_COUNT(a) ((a).constituent_count)
#define DENSITY_KNOT_BOUND MAX_DENSITY_KNOTS

// A 2D table of RGB texels, row-major (x fastest). Texel (x, y) has its centre
// at texture coordinate ((x + 0.5) / width, (y + 0.5) / height).
struct sampler2D {
  int width = 0;
  int height = 0;
  const vec3* texels = nullptr;
};

// A 3D table of RGB texels, x fastest, then y, then z.
struct sampler3D {
  int width = 0;
  int height = 0;
  int depth = 0;
  const vec3* texels = nullptr;
};

namespace detail {
// Index and weight of the lower texel for coordinate u over n texels, clamped
// to the edges as GL_CLAMP_TO_EDGE does (clamping u to [0, 1] first gives the
// same taps, and keeps x > -1 so that truncation is a floor: std::floor is a
// library call on baseline x86-64).
inline void linear_tap(float u, int n, int& i0, int& i1, float& w1) {
  u = u < 0.0f ? 0.0f : (u > 1.0f ? 1.0f : u);
  const float x = u * float(n) - 0.5f;
  const int i = int(x + 1.0f) - 1;
  w1 = x - float(i);
  i0 = i < 0 ? 0 : i;
  i1 = i + 1 >= n ? n - 1 : i + 1;
}
}  // namespace detail

inline vec4 texture(const sampler2D& s, vec2 uv) {
  int x0, x1, y0, y1;
  float fx, fy;
  detail::linear_tap(uv.x, s.width, x0, x1, fx);
  detail::linear_tap(uv.y, s.height, y0, y1, fy);
  const vec3* row0 = s.texels + std::size_t(y0) * std::size_t(s.width);
  const vec3* row1 = s.texels + std::size_t(y1) * std::size_t(s.width);
  vec3 a = row0[x0] * (1.0f - fx) + row0[x1] * fx;
  vec3 b = row1[x0] * (1.0f - fx) + row1[x1] * fx;
  return vec4(a * (1.0f - fy) + b * fy, 1.0f);
}

// A depth texture read with comparison (GL_COMPARE_REF_TO_TEXTURE,
// GL_LEQUAL, GL_LINEAR, GL_CLAMP_TO_EDGE; depth in x): texture(s, vec3(uv,
// reference)) weights the results of the four texels of bilinear filtering
// (1 where reference <= the texel's depth) with the bilinear weights, the
// percentage-closer filtering that GL 4.5 §8.22.1 describes and llvmpipe
// implements (GPUs may round the weights to fewer bits).
struct sampler2DShadow {
  int width = 0;
  int height = 0;
  const vec3* texels = nullptr;
};

inline float texture(const sampler2DShadow& s, vec3 p) {
  int x0, x1, y0, y1;
  float fx, fy;
  detail::linear_tap(p.x, s.width, x0, x1, fx);
  detail::linear_tap(p.y, s.height, y0, y1, fy);
  auto lit = [&](int x, int y) {
    return p.z <= s.texels[std::size_t(y) * std::size_t(s.width) + std::size_t(x)].x ? 1.0f : 0.0f;
  };
  float a = lit(x0, y0) * (1.0f - fx) + lit(x1, y0) * fx;
  float b = lit(x0, y1) * (1.0f - fx) + lit(x1, y1) * fx;
  return a * (1.0f - fy) + b * fy;
}

inline vec4 texture(const sampler3D& s, vec3 uvw) {
  int x0, x1, y0, y1, z0, z1;
  float fx, fy, fz;
  detail::linear_tap(uvw.x, s.width, x0, x1, fx);
  detail::linear_tap(uvw.y, s.height, y0, y1, fy);
  detail::linear_tap(uvw.z, s.depth, z0, z1, fz);
  auto at = [&](int x, int y, int z) {
    return s.texels[(std::size_t(z) * std::size_t(s.height) + std::size_t(y)) * std::size_t(s.width) + std::size_t(x)];
  };
  vec3 c00 = at(x0, y0, z0) * (1.0f - fx) + at(x1, y0, z0) * fx;
  vec3 c10 = at(x0, y1, z0) * (1.0f - fx) + at(x1, y1, z0) * fx;
  vec3 c01 = at(x0, y0, z1) * (1.0f - fx) + at(x1, y0, z1) * fx;
  vec3 c11 = at(x0, y1, z1) * (1.0f - fx) + at(x1, y1, z1) * fx;
  vec3 c0 = c00 * (1.0f - fy) + c10 * fy;
  vec3 c1 = c01 * (1.0f - fy) + c11 * fy;
  return vec4(c0 * (1.0f - fz) + c1 * fz, 1.0f);
}

#include "physics/definitions.glsl"

}  // namespace atmos::physics
