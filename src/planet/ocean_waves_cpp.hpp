// The C++ side of planet/ocean_waves.glsl (the sea's displaced waves and the
// ray's crossing with them), in double: the shader's globals (the pixel's
// displacing waves) are the members of OceanWaveField, and the GLSL
// functions its member functions, compiled from the same text. The scalar
// built-ins the text calls are the class's static members below, on double.
//
//   IN(T) -> const T&,  OUT(T) -> T&,  INLINE -> inline.
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#ifndef IN
#define IN(T) const T&
#endif
#ifndef OUT
#define OUT(T) T&
#endif
#ifndef INLINE
#define INLINE inline
#endif

namespace atmos::planet {

struct OceanWaveField {
  // The sea's waves, as the shader's uniforms (ocean_waves.glsl): wave
  // vectors (rad/m, planet axes) and amplitudes (m), the same on the wind's
  // axes, phases at the camera (rad); and the pixel's displacing waves.
  static constexpr int kMaxWaves = 32;
  int wave_count = 0;
  std::array<glm::dvec4, kMaxWaves> wave_vector{}, wave_in_wind{};
  std::array<double, kMaxWaves> wave_phase{};
  std::array<double, kMaxWaves> ocean_wave_amplitude{};
  int ocean_wave_count = 0;

  static double sin(double x) { return std::sin(x); }
  static double sqrt(double x) { return std::sqrt(x); }
  static double abs(double x) { return std::abs(x); }
  static double min(double a, double b) { return std::min(a, b); }
  static double max(double a, double b) { return std::max(a, b); }
  static double clamp(double x, double lo, double hi) { return std::clamp(x, lo, hi); }
  static double smoothstep(double lo, double hi, double x) {
    const double s = std::clamp((x - lo) / (hi - lo), 0.0, 1.0);
    return s * s * (3.0 - 2.0 * s);
  }

#define OCEAN_WAVES_CPP 1
#define OCEAN_FLOAT double
#define OCEAN_VEC2 glm::dvec2
#define OCEAN_VEC3 glm::dvec3
#define OCEAN_VEC4 glm::dvec4
#include "planet/ocean_waves.glsl"
#undef OCEAN_WAVES_CPP
#undef OCEAN_FLOAT
#undef OCEAN_VEC2
#undef OCEAN_VEC3
#undef OCEAN_VEC4
};

}  // namespace atmos::planet
