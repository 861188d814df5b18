// The renderers' per-frame sky-view table (view_ray_scattering.glsl, sky_radiance)
// against the exact per-ray evaluation of the same functions (the CPU sky
// model, which the reference tests measure): the table only adds the error of
// interpolating over view directions, for cameras in the atmosphere.
//
// Whole equirectangular panoramas (every direction, the ground below the
// horizon included) from 2 m, 10 km and 60 km, the sun from high to 6° below
// the horizon. Pixels within 2° of the sun (its disc is the same in both) and
// pixels darker than 1 % of the brightest other pixel are not counted (as in
// reference_accuracy.cpp).
//
// Default tables, 96 x 256 sky-view texels; RMS / max relative luminance over
// the counted pixels. The largest errors are from 60 km with the sun 6° below
// the horizon, where only the thin lit band near the horizon towards the sun
// counts (about 0.5 % RMS), and at the horizon, where the sky meets the
// ground and the radiance changes fastest (a few per cent at most). Bounds:
// RMS 1 %, max 5 %.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/renderer.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "figures.hpp"
#include "gpu/camera_cpp.hpp"

namespace {

TEST(SkyView, TableMatchesPerRayEvaluation) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const atmos::PrecomputeOptions options;  // default sizes, 4 orders
  const char* cache = std::getenv("ATMOS_CACHE_DIR");
  const atmos::Tables tables = cache ? atmos::load_or_precompute_tables(earth, options, cache).tables
                                     : atmos::precompute_tables(earth, options);
  const atmos::SkyModel model(earth, tables);

  for (double altitude : {2.0, 10e3, 60e3})
    for (double sun_elevation : {30.0, 8.0, 2.0, -3.0, -6.0}) {
      atmos::Camera camera;
      camera.position = atmos::observer_position(earth, altitude);
      camera.forward = {0.0, 1.0, 0.0};
      camera.up = {0.0, 0.0, 1.0};
      camera.projection = atmos::Projection::equirect;
      camera.width = 128;
      camera.height = 64;
      const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(30.0, sun_elevation);
      const atmos::Image image = atmos::render_cpu(earth, tables, camera, sun);

      // The same rays, each evaluated exactly (the renderer's camera model).
      std::vector<double> table(size_t(camera.width) * camera.height), exact(table.size());
      double brightest = 0.0;
      for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
          bool valid = true;
          const glm::vec3 ray = atmos::physics::camera_view_ray(
              glm::vec2(float(x) + 0.5f, float(y) + 0.5f), glm::vec2(float(camera.width), float(camera.height)),
              glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(0.0f, 0.0f, 1.0f), glm::vec3(0.0f, 1.0f, 0.0f), 0.0f,
              glm::vec2(0.0f), PROJECTION_EQUIRECT, valid);
          ASSERT_TRUE(valid);
          const size_t i = size_t(y) * size_t(camera.width) + size_t(x);
          const float* rgb = &image.rgb[3 * i];
          table[i] = atmos::srgb_luminance(glm::dvec3(rgb[0], rgb[1], rgb[2]));
          exact[i] = atmos::srgb_luminance(
              model.to_srgb(model.radiance(camera.position, glm::dvec3(glm::normalize(ray)), sun, true)));
          ASSERT_TRUE(std::isfinite(table[i]));
          // Not the sun's disc (the same in both) nor its neighbourhood.
          if (glm::dot(glm::dvec3(glm::normalize(ray)), sun) > std::cos(glm::radians(2.0))) exact[i] = -1.0;
          brightest = std::max(brightest, exact[i]);
        }
      double sum_sq = 0.0, worst = 0.0;
      int counted = 0;
      for (size_t i = 0; i < table.size(); ++i) {
        if (exact[i] < 0.01 * brightest) continue;  // also the sun's pixels, marked -1
        const double e = (table[i] - exact[i]) / exact[i];
        sum_sq += e * e;
        worst = std::max(worst, std::abs(e));
        ++counted;
      }
      const double rms = std::sqrt(sum_sq / std::max(counted, 1));
      std::printf("altitude %6.0f m  sun %+5.1f deg: RMS %5.2f %%  max %5.2f %%  (%d of %zu pixels)\n", altitude,
                  sun_elevation, 100.0 * rms, 100.0 * worst, counted, table.size());
      char config[64];
      std::snprintf(config, sizeof config, "%g m, sun %+.1f deg", altitude, sun_elevation);
      atmos_test::record_figure(std::string("RMS, ") + config, 100.0 * rms, "%", "RMS <= 1 %");
      atmos_test::record_figure(std::string("max, ") + config, 100.0 * worst, "%", "max <= 5 %");
      EXPECT_GE(counted, 100);
      EXPECT_LE(rms, 0.01) << altitude << " m, sun " << sun_elevation;
      EXPECT_LE(worst, 0.05) << altitude << " m, sun " << sun_elevation;
    }
}

}  // namespace
