// The CPU twin of a pixel's ray over the displaced sea (shared by the
// OceanWaves suite, ocean_waves_test.cpp, and the sea's GPU tests,
// ocean_test.cpp).
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>

#include "planet/ocean_internal.hpp"

namespace atmos_test {

// The CPU twin (planet/ocean_waves_cpp.hpp) of a pixel's ray from `camera`
// along unit `d` over the sea sphere of `radius`, with the shader's
// per-pixel weights (ocean.frag.glsl: the sphere point's footprint
// t α, μ_v and the view's azimuth on the wind's axes, `upwind` the
// anchor's): `field` holds the sea's waves and gets the pixel's displacing
// ones.
struct TwinRay {
  bool on_sphere = false;   // the ray meets the sphere
  double t_sphere = 0.0;    // m
  double mu_v = 0.0;        // at the sphere point
  double amplitude = 0.0;   // A = Σ w_i a_i, m
  bool hit = false;         // the displaced surface (with displacing waves)
  double t = 0.0;           // m, the crossing
};

inline TwinRay twin_ray(atmos::planet::OceanWaveField& field, const glm::dvec3& camera, const glm::dvec3& d, double radius,
                 double pixel_angle, const glm::dvec3& wind_upwind) {
  TwinRay r;
  const double r_c = glm::length(camera);
  const double b = glm::dot(camera, d), c = (r_c - radius) * (r_c + radius);
  field.ocean_wave_count = 0;
  if (b >= 0.0 || b * b - c < 0.0) return r;
  r.on_sphere = true;
  r.t_sphere = c / (-b + std::sqrt(b * b - c));
  const glm::dvec3 n = glm::normalize(camera + r.t_sphere * d), view = -d;
  const glm::dvec3 upwind = glm::normalize(wind_upwind - glm::dot(wind_upwind, n) * n);
  const glm::dvec3 crosswind = glm::cross(n, upwind);
  r.mu_v = std::max(glm::dot(view, n), 1e-4);
  const glm::dvec3 along = glm::normalize(view - glm::dot(view, n) * n);
  field.ocean_select_displacing_waves(r.t_sphere * pixel_angle, r.mu_v,
                                      glm::dvec2(glm::dot(along, upwind), glm::dot(along, crosswind)));
  for (int i = 0; i < field.ocean_wave_count; ++i) r.amplitude += field.ocean_wave_amplitude[size_t(i)];
  if (field.ocean_wave_count > 0) r.hit = field.ocean_displaced_hit(d, b, c, radius, r.t);
  return r;
}

}  // namespace atmos_test
