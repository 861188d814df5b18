// The sea's displaced waves on the CPU (planet/ocean_waves_cpp.hpp, the
// twin of the sea's shader): the first crossing of a pixel's ray with the
// waves' height field against a brute-force march in double, and a ray
// grazing a crest. The sea on the GPU is tested in ocean_test.cpp.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "ocean_twin_ray.hpp"
#include "planet/ocean_internal.hpp"

namespace {

using atmos_test::TwinRay;
using atmos_test::twin_ray;
namespace planet = atmos::planet;

// The clearance |p| − R − h(p) (m) of the ray's point p = camera + t d
// above the displacing waves of `field`, from the point itself, in double.
double clearance_at(const planet::OceanWaveField& field, const glm::dvec3& camera, const glm::dvec3& d, double radius,
                    double t) {
  double h = 0.0;
  for (int i = 0; i < field.ocean_wave_count; ++i) {
    const glm::dvec3 k(field.wave_vector[size_t(i)]);
    h += field.ocean_wave_amplitude[size_t(i)] * std::sin(field.wave_phase[size_t(i)] + glm::dot(k, t * d));
  }
  return glm::length(camera + t * d) - radius - h;
}

// The brute force: the first t at which the clearance (clearance_at)
// changes sign, by steps of `step` m from where the ray is within A + 1 m
// of the sphere, then bisection to 1e-9 m. Nothing: the ray passes over.
std::optional<double> brute_force_crossing(const planet::OceanWaveField& field, const glm::dvec3& camera,
                                           const glm::dvec3& d, double radius, double amplitude, double step) {
  const auto g = [&](double t) { return clearance_at(field, camera, d, radius, t); };
  double t = 0.0;
  while (glm::length(camera + t * d) - radius > amplitude + 1.0) t += 0.5;
  if (g(t) <= 0.0) return std::nullopt;
  for (;;) {
    const double height = glm::length(camera + (t + step) * d) - radius;
    if (g(t + step) <= 0.0) break;
    t += step;
    if (height < -amplitude || (height > amplitude + 1.0 && glm::dot(camera + t * d, d) > 0.0)) return std::nullopt;
  }
  double lo = t, hi = t + step;
  while (hi - lo > 1e-9) {
    const double middle = 0.5 * (lo + hi);
    (g(middle) > 0.0 ? lo : hi) = middle;
  }
  return 0.5 * (lo + hi);
}

// The waves of a 7 m/s wind (Cox & Munk 1954's slope variances at 7 m/s,
// 3.16e-3 U and 0.003 + 1.92e-3 U, as the budget) anchored below `camera`,
// at `time_s`, into `field`; the anchor's upwind axis (wind towards the
// east, azimuth 90 degrees, OceanSettings' default).
glm::dvec3 seven_metre_waves(planet::OceanWaveField& field, const glm::dvec3& camera, double time_s) {
  const std::vector<planet::OceanWave> waves = planet::make_ocean_waves(7.0, glm::dvec2(3.16e-3 * 7.0, 0.003 + 1.92e-3 * 7.0));
  glm::dvec3 upwind, crosswind;
  planet::ocean_wind_axes(glm::normalize(camera), 90.0, upwind, crosswind);
  planet::set_ocean_wave_uniforms(waves, upwind, crosswind, camera, time_s, field);
  return upwind;
}

// From 2 m and 20 m over the sea, rays 2 to 70 degrees down in every
// azimuth, the waves weighted for a pixel of 1e-3 rad (1080 lines over
// 60 degrees): the twin's crossing (at most 17 evaluations of the waves'
// sum) against the brute force's (2 mm steps, then bisection): the same
// crossing (within 5 cm along the ray, where the displacing waves are
// 0.8 m long or more), its point within 1 mm of the surface in height
// (the brute force's clearance there; the march stops within 1 mm).
TEST(OceanWaves, CrossingMatchesABruteForceMarch) {
  const double radius = 6.36e6;
  planet::OceanWaveField field;
  int compared = 0, displaced_waves = 0;
  double worst_height = 0.0, worst_t = 0.0, largest_amplitude = 0.0;
  for (double altitude : {2.0, 20.0}) {
    const glm::dvec3 camera(0.0, 0.0, radius + altitude);
    const glm::dvec3 upwind = seven_metre_waves(field, camera, 3.7);
    for (int i = 0; i < 48; ++i) {
      const double elevation = glm::radians(-2.0 - 68.0 * std::pow(std::fmod(0.618034 * i, 1.0), 2.0));
      const double azimuth = 2.0 * 3.14159265358979 * std::fmod(0.7548777 * i, 1.0);
      const glm::dvec3 d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                         std::sin(elevation));
      const TwinRay twin = twin_ray(field, camera, d, radius, 1e-3, upwind);
      ASSERT_TRUE(twin.on_sphere);
      if (field.ocean_wave_count == 0) continue;
      // The ray's height in the camera-relative form against the point's own.
      const double r_c = glm::length(camera);
      for (double t : {0.5 * twin.t_sphere, twin.t_sphere, 1.5 * twin.t_sphere})
        ASSERT_NEAR(field.ocean_ray_height(t, glm::dot(camera, d), (r_c - radius) * (r_c + radius), radius),
                    glm::length(camera + t * d) - radius, 1e-8);
      const std::optional<double> brute = brute_force_crossing(field, camera, d, radius, twin.amplitude, 2e-3);
      ASSERT_TRUE(brute.has_value()) << "ray " << i << " from " << altitude << " m";
      ASSERT_TRUE(twin.hit) << "ray " << i << " from " << altitude << " m";
      ++compared;
      displaced_waves += field.ocean_wave_count;
      largest_amplitude = std::max(largest_amplitude, twin.amplitude);
      const double clearance = std::abs(clearance_at(field, camera, d, radius, twin.t));
      worst_t = std::max(worst_t, std::abs(twin.t - *brute));
      worst_height = std::max(worst_height, clearance);
      EXPECT_LT(std::abs(twin.t - *brute), 0.05)
          << "ray " << i << " from " << altitude << " m: twin " << twin.t << " m, brute force " << *brute << " m";
      EXPECT_LT(clearance, 1e-3) << "ray " << i << " from " << altitude << " m";
    }
  }
  EXPECT_GT(compared, 60);
  EXPECT_GT(largest_amplitude, 0.5);
  std::printf("crossing: %d rays (%.1f displacing waves each, A up to %.2f m), worst %.2e m along the ray, clearance "
              "%.2e m\n",
              compared, double(displaced_waves) / compared, largest_amplitude, worst_t, worst_height);
}

// One wave (1 m, 20 m long) with a crest 30 m from a camera 1.9 m up (the
// rays 1.7 degrees down, less steep than the crest's back, which curves
// down by ½ a k² x²): a ray aimed 1 cm below the crest's top stops on the
// crest's near face, as the brute force does; one aimed 1 cm above it
// passes over and meets the sea beyond the crest.
TEST(OceanWaves, GrazingRayStopsOnTheCrest) {
  const double radius = 6.36e6, k = 2.0 * 3.14159265358979 / 20.0, crest = 30.0;
  planet::OceanWaveField field;
  field.wave_count = 1;
  field.wave_vector[0] = glm::dvec4(k, 0.0, 0.0, 1.0);
  field.wave_in_wind[0] = glm::dvec4(k, 0.0, k, 1.0);
  field.wave_phase[0] = 0.5 * 3.14159265358979 - k * crest;
  field.ocean_wave_count = 1;
  field.ocean_wave_amplitude[0] = 1.0;
  const glm::dvec3 camera(0.0, 0.0, radius + 1.9);
  for (double below : {0.01, -0.01}) {
    // The crest's top: 1 m above the sphere at 30 m along x.
    const double angle = crest / radius;
    const glm::dvec3 top = (radius + 1.0 - below) * glm::dvec3(std::sin(angle), 0.0, std::cos(angle));
    const glm::dvec3 d = glm::normalize(top - camera);
    const double r_c = glm::length(camera);
    double t = 0.0;
    const bool hit = field.ocean_displaced_hit(d, glm::dot(camera, d), (r_c - radius) * (r_c + radius), radius, t);
    const std::optional<double> brute = brute_force_crossing(field, camera, d, radius, 1.0, 1e-4);
    ASSERT_TRUE(hit);
    ASSERT_TRUE(brute.has_value());
    const double x = (camera + t * d).x;
    EXPECT_LT(std::abs(t - *brute) * -d.z, 1e-3) << (below > 0.0 ? "below" : "above") << " the crest";
    if (below > 0.0)
      EXPECT_TRUE(x > crest - 5.0 && x < crest) << "stopped at x = " << x << " m";
    else
      EXPECT_GT(x, crest + 5.0) << "stopped at x = " << x << " m";
    std::printf("ray %s the crest: x = %.4f m (brute force %.4f m)\n", below > 0.0 ? "below" : "above", x,
                (camera + *brute * d).x);
  }
}

// The sea's draw skips the displaced waves' selection and march when the
// camera is so high that no wave's amplitude spans a pixel anywhere
// (ocean.cpp, waves_can_displace: max a_i <= h α, h the camera's height
// above the level). Just above that height, every ray of the view, from
// straight down to grazing, selects no displacing wave; well below it some
// ray does (the gate is not always shut).
TEST(OceanWaves, NoWaveDisplacesAboveTheHeightWhereNoAmplitudeSpansAPixel) {
  const double radius = 6.36e6, pixel_angle = 1e-3;
  const std::vector<planet::OceanWave> waves =
      planet::make_ocean_waves(12.0, glm::dvec2(3.16e-3 * 12.0, 0.003 + 1.92e-3 * 12.0));
  double largest = 0.0;
  for (const planet::OceanWave& w : waves) largest = std::max(largest, w.amplitude);
  ASSERT_GT(largest, 0.0);
  const double gate_height = largest / pixel_angle;
  for (double factor : {1.001, 0.25}) {
    const glm::dvec3 camera(0.0, 0.0, radius + factor * gate_height);
    planet::OceanWaveField field;
    glm::dvec3 upwind, crosswind;
    planet::ocean_wind_axes(glm::normalize(camera), 90.0, upwind, crosswind);
    planet::set_ocean_wave_uniforms(waves, upwind, crosswind, camera, 0.0, field);
    int displacing = 0;
    for (int i = 0; i < 400; ++i) {
      const double down = glm::radians(0.05 + 89.9 * double(i % 20) / 19.0), azimuth = glm::radians(18.0 * (i / 20));
      const glm::dvec3 d(std::cos(down) * std::cos(azimuth), std::cos(down) * std::sin(azimuth), -std::sin(down));
      const TwinRay twin = twin_ray(field, camera, d, radius, pixel_angle, upwind);
      displacing += twin.on_sphere && field.ocean_wave_count > 0;
    }
    std::printf("camera at %.3f of the gate's height (%.0f m): %d of 400 rays with displacing waves\n", factor,
                gate_height, displacing);
    if (factor > 1.0)
      EXPECT_EQ(displacing, 0);
    else
      EXPECT_GT(displacing, 0);
  }
}

}  // namespace
