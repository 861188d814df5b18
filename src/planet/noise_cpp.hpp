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

}  // namespace atmos::planet
