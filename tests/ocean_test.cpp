// The sea on the globe (include/atmos/ocean.hpp) on the GPU: the glint seen
// from orbit against its CPU twin (physics/water_cpp.hpp) pixel by pixel,
// the reflected sky under a uniform sky against the rough surface's
// reflectance, the mean radiance through the waves' levels of detail
// during a dolly, the displaced waves' depth from a deck against their CPU
// twin (the twin itself: ocean_waves_test.cpp), a shallow seabed showing
// through, the terrain hiding the sea where it rises above it, a moon's
// eclipse, no NaN, and bad input.
#include <gtest/gtest.h>

#include <epoxy/gl.h>
#include <gdal.h>
#include <ogr_srs_api.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "atmos/globe.hpp"
#include "atmos/ocean.hpp"
#include "atmos/plugin.hpp"
#include "cli_support.hpp"
#include "globe_rays.hpp"
#include "globe_target.hpp"
#include "ocean_twin_ray.hpp"
#include "gpu_fixture.hpp"
#include "atmos/colour.hpp"
#include "atmos/water.hpp"
#include "physics/eclipse_cpp.hpp"
#include "physics/moons.hpp"
#include "physics/parameters.hpp"
#include "physics/view_ray_scattering_cpp.hpp"
#include "physics/water.hpp"
#include "planet/ocean_internal.hpp"
#include "runtime/table_samplers.hpp"
#include "table_sizes.hpp"

namespace {

using atmos_test::GlobeTarget;
using atmos_test::pixel_ray;
using atmos_test::TwinRay;
using atmos_test::twin_ray;
namespace planet = atmos::planet;
namespace physics = atmos::physics;

atmos::PlanetSurface flat_sea(double sea_level_m) {
  atmos::PlanetSurface s;
  s.style = atmos::SurfaceStyle::flat;
  s.sea_level_m = sea_level_m;
  return s;
}

// Restores every term after a test that drew some of them.
struct TermsGuard {
  explicit TermsGuard(unsigned mask) { planet::set_ocean_terms(mask); }
  ~TermsGuard() { planet::set_ocean_terms(planet::kOceanAllTerms); }
  void set(unsigned mask) const { planet::set_ocean_terms(mask); }
};

class OceanGpu : public atmos_test::EarthGpuTest {
 protected:
  static void SetUpTestSuite() {
    EarthGpuTest::SetUpTestSuite();
    if (context_ == nullptr) return;
    pass_ = std::make_unique<atmos::AtmospherePass>(*earth_, *tables_, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  }
  static void TearDownTestSuite() {
    pass_.reset();
    EarthGpuTest::TearDownTestSuite();
  }

  // A camera at `camera` looking along `forward`, 60 degree field of view by default.
  static atmos::GlobeView view_from(const glm::dvec3& camera, const glm::dvec3& forward, const glm::dvec3& up_hint,
                                    int width, int height, const glm::dvec3& sun, double fov_y_deg = 60.0) {
    atmos::GlobeView v;
    v.view = glm::lookAt(camera, camera + forward, up_hint);
    v.projection = atmos::reversed_z_projection(glm::radians(fov_y_deg), double(width) / height, 0.05);
    v.width = width;
    v.height = height;
    v.sun_direction = sun;
    v.nits_per_unit = 1000.0;
    return v;
  }

  static std::vector<float> draw(atmos::Ocean& ocean, const atmos::GlobeView& view, const GlobeTarget& target,
                                 double time_s = 0.0) {
    target.clear();
    ocean.draw(view, time_s);
    return target.read_colour();
  }

  // The conversion of the Earth tables' channels (its three working
  // wavelengths) to linear sRGB, the pass's ATMOS_RADIANCE_TO_SRGB.
  static glm::mat3 channels_to_srgb() {
    return atmos::radiance_to_srgb_matrix(
        {earth_->wavelengths_nm[0], earth_->wavelengths_nm[1], earth_->wavelengths_nm[2]});
  }

  // The water's parameters as the ocean makes them for the Earth tables
  // (water_optics), for the CPU twins.
  static physics::WaterParams water_params(const atmos::OceanSettings& s) {
    const atmos::WaterOptics o = atmos::water_optics(s.water, *earth_);
    physics::WaterParams p{};
    p.refractive_index = physics::vec3(o.refractive_index);
    p.absorption = physics::vec3(o.absorption_per_m);
    p.backscattering = physics::vec3(o.backscattering_per_m);
    p.diffuse_reflectance = physics::vec3(o.diffuse_reflectance);
    p.slope_variance = physics::vec2(o.slope_variance);
    return p;
  }

  // The wind's upwind axis at `point` for waves anchored below `camera`
  // (ocean.cpp's frame: azimuth clockwise from north).
  static glm::dvec3 upwind_at(const glm::dvec3& camera, const glm::dvec3& normal, double azimuth_deg) {
    const glm::dvec3 nadir = glm::normalize(camera);
    glm::dvec3 east = glm::cross(glm::dvec3(0, 0, 1), nadir);
    if (glm::length(east) < 1e-6) east = glm::cross(glm::dvec3(0, 1, 0), nadir);  // at the poles
    east = glm::normalize(east);
    const glm::dvec3 north = glm::cross(nadir, east);
    const double a = glm::radians(azimuth_deg);
    const glm::dvec3 w = std::cos(a) * north + std::sin(a) * east;
    return glm::normalize(w - glm::dot(w, normal) * normal);
  }

  // The point where pixel (x, y)'s ray meets the sphere of `radius`, if it does.
  static std::optional<glm::dvec3> sea_point(const atmos::GlobeView& view, const glm::dvec3& camera, double radius,
                                             int x, int y) {
    const glm::dvec3 d = pixel_ray(view, x, y);
    const double b = glm::dot(camera, d), c = glm::dot(camera, camera) - radius * radius;
    if (b >= 0.0 || b * b - c < 0.0) return std::nullopt;
    return camera + (-b - std::sqrt(b * b - c)) * d;
  }

  static void expect_finite(const std::vector<float>& colour, const char* what) {
    for (size_t i = 0; i < colour.size(); ++i) ASSERT_TRUE(std::isfinite(colour[i])) << what << " texel " << i / 4;
  }

  // A glint drawn by another light over `reference`'s, per channel, against
  // `ratio`: the worst relative difference over the channels where the
  // reference is above 1 % of its peak (green), `compared` of them; `dark`
  // (the scene without that light) must stay below 1e-3 of what it adds.
  static double worst_ratio(const std::vector<float>& reference, const std::vector<float>& glint,
                            const std::vector<float>& dark, const glm::dvec3& ratio, int& compared) {
    float peak = 0.0f;
    for (size_t i = 0; i < reference.size(); i += 4) peak = std::max(peak, reference[i + 1]);
    EXPECT_GT(peak, 0.0f);
    compared = 0;
    double worst = 0.0;
    for (size_t i = 0; i < reference.size(); i += 4) {
      if (reference[i] == -1.0f) continue;
      for (int c = 0; c < 3; ++c) {
        EXPECT_LT(dark[i + size_t(c)], 1e-3 * ratio[c] * peak) << "without the light, texel " << i / 4;
        if (reference[i + size_t(c)] < 0.01f * peak) continue;
        ++compared;
        worst = std::max(worst, std::abs(glint[i + size_t(c)] / reference[i + size_t(c)] / ratio[c] - 1.0));
      }
    }
    return worst;
  }

  static inline std::unique_ptr<atmos::AtmospherePass> pass_;
};

// From 2000 km, the glint of every sea pixel against the CPU twin of the
// same BRDF (water_glint_brdf) at the pixel's sphere point, times the sun's
// irradiance the shader used there (drawn with kOceanSunIrradiance, in
// linear sRGB: M E with M the tables' channels' conversion, E the
// channels, here the three working wavelengths) and the sun's cosine, per
// wavelength and converted as the shader does: M (f ⊙ M⁻¹ E_srgb) μ_s; the waves are all far below the pixels (36 km here), so the
// BRDF has Cox & Munk's whole variance about the sphere's normal.
TEST_F(OceanGpu, GlintFromOrbitMatchesTheCpuTwin) {
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 6.0;
  settings.wind_azimuth_deg = 30.0;
  settings.bathymetry_texels = 64;
  const double sea_level = 100.0;
  atmos::Ocean ocean(*earth_, flat_sea(sea_level), *pass_, settings);
  const int width = 64, height = 64;
  GlobeTarget target(width, height);
  const double radius = earth_->bottom_radius_m + sea_level;
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.3, -1.0, 0.4));
  const glm::dvec3 camera = up * (earth_->bottom_radius_m + 2000e3);
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 sun = glm::normalize(up + 0.25 * east + 0.1 * glm::cross(up, east));
  const atmos::GlobeView view = view_from(camera, -up, glm::cross(up, east), width, height, sun);
  const TermsGuard guard(planet::kOceanGlint);
  const std::vector<float> glint = draw(ocean, view, target);
  guard.set(planet::kOceanSunIrradiance);
  const std::vector<float> irradiance = draw(ocean, view, target);
  expect_finite(glint, "glint");
  const physics::WaterParams water = water_params(settings);
  const glm::dmat3 to_srgb(channels_to_srgb()), to_channels = glm::inverse(to_srgb);
  float peak = 0.0f;
  for (size_t i = 0; i < glint.size(); i += 4) peak = std::max(peak, glint[i + 1]);
  ASSERT_GT(peak, 0.0f);
  int compared = 0;
  double worst = 0.0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::optional<glm::dvec3> p = sea_point(view, camera, radius, x, y);
      const float* g = &glint[size_t(4 * (y * width + x))];
      if (!p) {
        EXPECT_EQ(g[0], -1.0f) << "drawn off the sphere at " << x << "," << y;
        continue;
      }
      ASSERT_NE(g[0], -1.0f) << "not drawn on the sphere at " << x << "," << y;
      const glm::dvec3 n = glm::normalize(*p);
      const glm::dvec3 v = glm::normalize(camera - *p);
      const physics::vec3 brdf = physics::water_glint_brdf(water, physics::vec3(n), physics::vec3(upwind_at(camera, n, 30.0)),
                                                           physics::vec3(v), physics::vec3(sun));
      const double mu_s = std::max(glm::dot(sun, n), 0.0);
      const float* e = &irradiance[size_t(4 * (y * width + x))];
      const glm::dvec3 twin = to_srgb * (glm::dvec3(brdf) * (to_channels * glm::dvec3(e[0], e[1], e[2]))) * mu_s;
      for (int c = 0; c < 3; ++c) {
        const double expected = twin[c];
        if (expected < 0.01 * peak) continue;
        ++compared;
        worst = std::max(worst, std::abs(g[c] - expected) / expected);
      }
    }
  EXPECT_GT(compared, 300);
  EXPECT_LT(worst, 3e-3) << "over " << compared << " channels";
  std::printf("glint vs CPU twin: %d channels, worst relative difference %.2e, peak %.3g\n", compared, worst, peak);
}

// Under a uniform sky of radiance 1 the reflected sky is the rough surface's
// directional-hemispherical reflectance: from orbit, each pixel's against
// the CPU twin (water_sky_reflectance), and between 0.015 and 1 (the flat
// surface's 0.020 at normal incidence, less the rough surface's masking).
TEST_F(OceanGpu, ReflectedUniformSkyIsTheSurfacesReflectance) {
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 9.0;
  settings.bathymetry_texels = 64;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, settings);
  const int width = 48, height = 48;
  GlobeTarget target(width, height);
  const double radius = earth_->bottom_radius_m;
  const glm::dvec3 up(0.0, 0.0, 1.0);
  const glm::dvec3 camera = up * (radius + 800e3);
  // Looking 50 degrees off the nadir: view angles at the sea up to grazing.
  const glm::dvec3 forward = glm::normalize(-up + 1.2 * glm::dvec3(1, 0, 0));
  const atmos::GlobeView view = view_from(camera, forward, up, width, height, glm::normalize(glm::dvec3(-1, 0.3, 1)));
  const TermsGuard guard(planet::kOceanSky | planet::kOceanUniformSky | planet::kOceanDirectLight);
  const std::vector<float> sky = draw(ocean, view, target);
  guard.set(planet::kOceanSky | planet::kOceanUniformSky);
  const std::vector<float> mapped = draw(ocean, view, target);
  expect_finite(sky, "sky");
  expect_finite(mapped, "sky from the reflectance map");
  const physics::WaterParams water = water_params(settings);
  int compared = 0;
  double worst = 0.0, sum = 0.0, worst_mapped = 0.0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::optional<glm::dvec3> p = sea_point(view, camera, radius, x, y);
      if (!p) continue;
      const glm::dvec3 n = glm::normalize(*p);
      const glm::dvec3 v = glm::normalize(camera - *p);
      physics::vec3 mean_direction;
      const physics::vec3 expected = physics::water_sky_reflectance(
          water, physics::vec3(n), physics::vec3(upwind_at(camera, n, settings.wind_azimuth_deg)), physics::vec3(v),
          mean_direction);
      const double mu_v = glm::dot(v, n);
      if (mu_v < 0.05) continue;  // the last pixels before the limb: float's cosines
      for (int c = 0; c < 3; ++c) {
        const double got = sky[size_t(4 * (y * width + x) + c)];
        ASSERT_TRUE(std::isfinite(expected[c]));
        ++compared;
        sum += got;
        worst = std::max(worst, std::abs(got - expected[c]) / expected[c]);
        worst_mapped = std::max(worst_mapped, double(std::abs(mapped[size_t(4 * (y * width + x) + c)] - expected[c]) / expected[c]));
        EXPECT_GT(got, 0.015);
        EXPECT_LE(got, 1.0);
      }
    }
  EXPECT_GT(compared, 600);
  EXPECT_LT(worst, 2e-3);
  EXPECT_LT(worst_mapped, 0.01);
  std::printf("uniform sky: %d channels, worst relative difference %.2e (the reflectance map's %.2e), mean reflectance %.4f\n",
              compared, worst, worst_mapped, sum / compared);
}

// The light maps (ocean_light_maps.glsl) against the pass's functions
// evaluated at every pixel (kOceanDirectLight), term by term: the reflected
// sky, the sun's irradiance and the light from below (which carries the
// sky's irradiance), from the deck at sunset looking towards the sun and
// away from it, from 10 km by day, and from orbit over the terminator. The
// sky's radiance is interpolated over the view's elevation, the sun's and
// their azimuth, the irradiances over the sun's elevation, and the
// reflectance (in the reflected sky) over the view's elevation and the
// slopes' deviations; the maps also re-interpolate the tables' own linear
// interpolation (these tests' small tables: 0.2-0.8 % on the sun's
// irradiance). Relative errors are per pixel, against 1e-3 of the view's
// brightest where the light has all but gone; over the terminator the
// twilight's steep falloff with the sun's elevation leaves the largest.
TEST_F(OceanGpu, LightMapsMatchThePassFunctions) {
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 7.0;
  settings.bathymetry_texels = 32;
  // 1000 m of water: deep (beyond H_deep, 290 m here), where the light
  // from below is read from its map.
  const double sea_level = 1000.0;
  atmos::Ocean ocean(*earth_, flat_sea(sea_level), *pass_, settings);
  const int width = 64, height = 48;
  GlobeTarget target(width, height);
  const double radius = earth_->bottom_radius_m + sea_level;
  const glm::dvec3 up(0, 0, 1), east(1, 0, 0), north(0, 1, 0);
  struct Case {
    const char* name;
    glm::dvec3 camera, forward, sun;
    double tolerance[3];  // the sky, the sun's irradiance, the light from below
  };
  const Case cases[] = {
      {"deck, sunset, towards the sun", up * (radius + 2.0), glm::normalize(east - 0.08 * up),
       glm::normalize(east + 0.05 * up), {0.02, 0.01, 0.005}},
      {"deck, sunset, away from the sun", up * (radius + 2.0), glm::normalize(-east - 0.08 * up),
       glm::normalize(east + 0.05 * up), {0.02, 0.01, 0.005}},
      {"10 km, by day", up * (radius + 10e3), glm::normalize(north - 0.6 * up),
       glm::normalize(up + 0.8 * east + 0.3 * north), {0.025, 0.005, 0.005}},
      // Over the terminator the light from below, read from its map times
      // the irradiances from theirs, carries their error (the sun's bound).
      {"orbit, terminator", up * (radius + 1500e3), -up, glm::normalize(east + 0.1 * up), {0.12, 0.05, 0.05}},
  };
  const unsigned terms[] = {planet::kOceanSky, planet::kOceanSunIrradiance, planet::kOceanBelow};
  const char* term_names[] = {"sky", "sun irradiance", "below"};
  const TermsGuard guard(planet::kOceanAllTerms);
  double worst[3] = {0.0, 0.0, 0.0}, mean_error[3] = {0.0, 0.0, 0.0};
  int counts[3] = {0, 0, 0};
  for (const Case& c : cases) {
    const atmos::GlobeView view = view_from(c.camera, c.forward, std::abs(c.forward.z) > 0.9 ? north : up, width,
                                            height, c.sun);
    for (int t = 0; t < 3; ++t) {
      guard.set(terms[t]);
      const std::vector<float> mapped = draw(ocean, view, target);
      guard.set(terms[t] | planet::kOceanDirectLight);
      const std::vector<float> direct = draw(ocean, view, target);
      expect_finite(mapped, c.name);
      float peak = 0.0f;
      for (size_t i = 0; i < direct.size(); i += 4)
        if (direct[i] != -1.0f) peak = std::max({peak, direct[i], direct[i + 1], direct[i + 2]});
      ASSERT_GT(peak, 0.0f) << c.name << ", " << term_names[t];
      double case_worst = 0.0;
      for (size_t i = 0; i < direct.size(); i += 4) {
        ASSERT_EQ(mapped[i] == -1.0f, direct[i] == -1.0f) << c.name << " texel " << i / 4;
        if (direct[i] == -1.0f) continue;
        for (int ch = 0; ch < 3; ++ch) {
          // Relative to the pixel's value, or to 1e-3 of the view's
          // brightest where the light has all but gone (the night side).
          const double reference = std::max(double(direct[i + size_t(ch)]), 1e-3 * peak);
          const double error = std::abs(mapped[i + size_t(ch)] - direct[i + size_t(ch)]) / reference;
          case_worst = std::max(case_worst, error);
          mean_error[t] += error;
          ++counts[t];
        }
      }
      worst[t] = std::max(worst[t], case_worst);
      EXPECT_LT(case_worst, c.tolerance[t]) << c.name << ", " << term_names[t];
      std::printf("light maps, %s, %s: worst %.2e\n", c.name, term_names[t], case_worst);
    }
  }
  for (int t = 0; t < 3; ++t) mean_error[t] /= std::max(counts[t], 1);
  EXPECT_LT(mean_error[0], 0.006);
  EXPECT_LT(mean_error[1], 0.003);
  EXPECT_LT(mean_error[2], 0.003);
  std::printf("light maps: sky worst %.2e mean %.2e; sun irradiance worst %.2e mean %.2e; below worst %.2e mean %.2e\n",
              worst[0], mean_error[0], worst[1], mean_error[1], worst[2], mean_error[2]);
}

// The light maps follow the tables of the pass the ocean is bound to: a
// pass whose tables hold the ground's response, its ground albedo changed
// from 0 to 0.8 between two draws (set_ground_albedo re-blends its
// ground-dependent tables). At each albedo the reflected sky and the light
// from below read from the maps match the pass's functions themselves
// (kOceanDirectLight; per pixel, within LightMapsMatchThePassFunctions's
// bounds for this view), and the brighter ground brightens both by more
// than those bounds: maps left as they were would fail the first check.
TEST_F(OceanGpu, LightMapsFollowThePassGroundAlbedo) {
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  options.ground_albedo_response = true;
  const atmos::Tables tables = atmos::precompute_tables(*earth_, options);
  atmos::AtmospherePass pass(*earth_, tables, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  pass.set_ground_albedo(glm::dvec3(0.0));
  atmos::OceanSettings settings;
  settings.bathymetry_texels = 16;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), pass, settings);
  const int width = 48, height = 32;
  GlobeTarget target(width, height);
  const double radius = earth_->bottom_radius_m;
  const glm::dvec3 up(0, 0, 1), east(1, 0, 0), north(0, 1, 0);
  const atmos::GlobeView view = view_from(up * (radius + 10e3), glm::normalize(north - 0.6 * up), up, width, height,
                                          glm::normalize(up + 0.8 * east + 0.3 * north));
  const unsigned terms[] = {planet::kOceanSky, planet::kOceanBelow};
  const char* names[] = {"sky", "below"};
  const TermsGuard guard(planet::kOceanAllTerms);
  double mean[2][2] = {{0.0, 0.0}, {0.0, 0.0}};  // [albedo][term], green
  for (int a = 0; a < 2; ++a) {
    if (a == 1) pass.set_ground_albedo(glm::dvec3(0.8));
    for (int t = 0; t < 2; ++t) {
      guard.set(terms[t]);
      const std::vector<float> mapped = draw(ocean, view, target);
      guard.set(terms[t] | planet::kOceanDirectLight);
      const std::vector<float> direct = draw(ocean, view, target);
      double worst = 0.0;
      int n = 0;
      for (size_t i = 0; i < direct.size(); i += 4) {
        ASSERT_EQ(mapped[i] == -1.0f, direct[i] == -1.0f) << "texel " << i / 4;
        if (direct[i] == -1.0f) continue;
        ++n;
        mean[a][t] += mapped[i + 1];
        for (int c = 0; c < 3; ++c) {
          const double d = direct[i + size_t(c)];
          ASSERT_GT(d, 0.0) << names[t] << " texel " << i / 4;
          worst = std::max(worst, std::abs(mapped[i + size_t(c)] - d) / d);
        }
      }
      ASSERT_GT(n, width * height / 2);
      mean[a][t] /= n;
      EXPECT_LT(worst, 0.025) << names[t] << " at ground albedo " << (a == 0 ? 0.0 : 0.8);
      std::printf("light maps at ground albedo %.1f, %s: worst %.2e against the pass's functions\n",
                  a == 0 ? 0.0 : 0.8, names[t], worst);
    }
  }
  for (int t = 0; t < 2; ++t) {
    EXPECT_GT(mean[1][t], 1.05 * mean[0][t]) << names[t];
    std::printf("ground albedo 0 -> 0.8: %s x %.3f (green)\n", names[t], mean[1][t] / mean[0][t]);
  }
}

// A dolly down towards the sea at 51 degrees below the horizon, from 20 km
// down, in steps of 1.25x: the waves move from the BRDF into the normals as
// their wavelengths grow past 4-8 pixels (at 48 x 32 pixels, from ~700 m
// for the longest waves down to centimetres). Each step's mean radiance of
// the sea pixels is over six instants 1.5 s apart: a view of a few metres
// holds a fraction of the longest waves (40-70 m at 7 m/s), whose tilt
// there moves the mean by a few per cent (the sea's own variation, not the
// levels').
//  - A 60 degree view to 5 m, the sun 40 degrees up to the side: the mean
//    changes by at most 1 % from one step to the next.
//  - A 20 degree view from 2 km to 2 m, the same sun: the waves also become
//    geometry as they grow past 8-16 pixels per wavelength and their
//    amplitude past 1-2 pixels (from ~60 m for the longest): the mean
//    changes by at most 1 % from one step to the next, and each step's
//    mean is within 0.5 % of the same frames' without the displaced waves
//    (kOceanUndisplaced).
//  - A 15 degree view, the sun where the view's centre mirrors it: the
//    glint's core fills the view and its brightness follows the slopes'
//    variance; down to 20 m every step's mean stays within 3 % of the
//    farthest one's, where all waves are the BRDF's (the resolved waves'
//    variance counted twice, in the normals and in the BRDF as well, dims
//    it by 7 % at 20 m).
TEST_F(OceanGpu, DollyKeepsTheMeanRadianceAcrossTheWavesLevels) {
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 7.0;
  settings.bathymetry_texels = 64;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, settings);
  const int width = 48, height = 32;
  GlobeTarget target(width, height);
  const double radius = earth_->bottom_radius_m;
  const glm::dvec3 up(0.0, 0.0, 1.0), east(1, 0, 0), north(0, 1, 0);
  const glm::dvec3 forward = glm::normalize(-up + 0.8 * east);
  const auto dolly = [&](double fov_deg, const glm::dvec3& sun, double lowest_m, double highest_m = 20e3) {
    std::vector<std::pair<double, double>> means;  // altitude, mean luminance
    for (double altitude = highest_m; altitude >= lowest_m; altitude /= 1.25) {
      const atmos::GlobeView view = view_from(up * (radius + altitude), forward, up, width, height, sun, fov_deg);
      double sum = 0.0;
      int count = 0;
      for (double time_s : {0.0, 1.5, 3.0, 4.5, 6.0, 7.5}) {
        const std::vector<float> colour = draw(ocean, view, target, time_s);
        expect_finite(colour, "dolly");
        for (size_t i = 0; i < colour.size(); i += 4) {
          if (colour[i] == -1.0f) continue;
          sum += 0.2126 * colour[i] + 0.7152 * colour[i + 1] + 0.0722 * colour[i + 2];
          ++count;
        }
      }
      EXPECT_EQ(count, 6 * width * height) << "the sea fills the view at " << altitude << " m";
      means.emplace_back(altitude, sum / count);
      if (std::getenv("OCEAN_TEST_VERBOSE")) std::printf("  %.4g m: %.6g\n", altitude, sum / count);
    }
    return means;
  };
  const glm::dvec3 side_sun = glm::normalize(up + 1.2 * north + 0.5 * east);
  const auto side = dolly(60.0, side_sun, 5.0);
  // A 20 degree view from 2 km to 2 m, with the displaced waves and without
  // them (their normals as in every frame; kOceanUndisplaced): its pixels
  // of 0.011 rad see the longest waves as geometry below about 60 m. The
  // geometry moves where the slopes are seen, not the mean.
  const auto narrow = dolly(20.0, side_sun, 2.0, 2e3);
  std::vector<std::pair<double, double>> undisplaced;
  {
    const TermsGuard guard(planet::kOceanAllTerms | planet::kOceanUndisplaced);
    undisplaced = dolly(20.0, side_sun, 2.0, 2e3);
  }
  double worst_geometry = 0.0, geometry_altitude = 0.0, worst_narrow_step = 0.0;
  for (size_t i = 0; i < narrow.size(); ++i) {
    const double change = std::abs(narrow[i].second / undisplaced[i].second - 1.0);
    if (change > worst_geometry) worst_geometry = change, geometry_altitude = narrow[i].first;
    if (i > 0)
      worst_narrow_step =
          std::max(worst_narrow_step, std::abs(narrow[i].second - narrow[i - 1].second) / narrow[i - 1].second);
  }
  EXPECT_LT(worst_geometry, 0.005) << "at " << geometry_altitude << " m";
  EXPECT_GT(worst_geometry, 1e-5) << "the waves displace nothing";
  EXPECT_LT(worst_narrow_step, 0.01);
  double worst_step = 0.0, step_altitude = 0.0;
  for (size_t i = 1; i < side.size(); ++i) {
    const double change = std::abs(side[i].second - side[i - 1].second) / side[i - 1].second;
    if (change > worst_step) worst_step = change, step_altitude = side[i].first;
  }
  EXPECT_LT(worst_step, 0.01) << "at " << step_altitude << " m";
  const auto glint = dolly(15.0, glm::normalize(up + 0.8 * east + 0.15 * north), 20.0);
  double worst_drift = 0.0, drift_altitude = 0.0;
  for (const auto& [altitude, mean] : glint) {
    const double drift = std::abs(mean - glint.front().second) / glint.front().second;
    if (drift > worst_drift) worst_drift = drift, drift_altitude = altitude;
  }
  EXPECT_LT(worst_drift, 0.03) << "at " << drift_altitude << " m";
  std::printf("dolly: largest step change %.3f %% at %.3g m (%zu steps); glint's core within %.2f %% (at %.3g m); "
              "20 degrees to 2 m: largest step change %.3f %%, displaced against undisplaced within %.3f %% (at %.3g m)\n",
              100.0 * worst_step, step_altitude, side.size(), 100.0 * worst_drift, drift_altitude,
              100.0 * worst_narrow_step, 100.0 * worst_geometry, geometry_altitude);
}

// From a deck 2 m above a flat sea at sunset, looking 6 degrees down (a
// 20 degree view, pixels of 6.5 mrad): the
// depth the sea writes, turned back into the distance t along each pixel's
// ray, against the CPU twin's crossing (ocean_waves_cpp.hpp) with the
// shader's weights, where the troughs beyond the sphere keep the sphere's
// depth and its lead (ocean.frag.glsl): near the camera the surface is
// displaced by the waves (crests up to A above the sphere), far away it is
// the sphere's. The heights are compared at the GPU's points: the twin's
// clearance g = |p| − R − h there, and |t_gpu − t_twin| in height.
TEST_F(OceanGpu, DeckDepthIsTheDisplacedSurface) {
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 7.0;
  settings.bathymetry_texels = 16;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, settings);
  const int width = 96, height = 54;
  GlobeTarget target(width, height);
  const double radius = earth_->bottom_radius_m;
  const glm::dvec3 up(0, 0, 1), camera = up * (radius + 2.0);
  const glm::dvec3 forward = glm::normalize(glm::dvec3(1, 0.3, -0.1));
  const atmos::GlobeView view =
      view_from(camera, forward, up, width, height, glm::normalize(glm::dvec3(1, 0.2, 0.03)), 20.0);
  planet::OceanWaveField field;
  const std::vector<planet::OceanWave> waves =
      planet::make_ocean_waves(7.0, atmos::water_optics(settings.water, *earth_).slope_variance);
  glm::dvec3 upwind, crosswind;
  planet::ocean_wind_axes(up, settings.wind_azimuth_deg, upwind, crosswind);
  const double pixel_angle = 2.0 / (std::abs(view.projection[1][1]) * height);
  int displaced = 0, flat = 0, crests = 0;
  double worst_clearance = 0.0, worst_height = 0.0, worst_flat = 0.0, highest = 0.0, largest_amplitude = 0.0;
  // Three instants 3 s apart: the longest waves (72 m, 10 m/s) move a
  // crest into the view's 7-30 m.
  for (double time_s : {0.0, 3.0, 6.0}) {
    target.clear();
    ocean.draw(view, time_s);
    const std::vector<float> depth = target.read_depth();
    planet::set_ocean_wave_uniforms(waves, upwind, crosswind, camera, time_s, field);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const float z = depth[size_t(y * width + x)];
        const glm::dvec3 d = pixel_ray(view, x, y);
        const TwinRay twin = twin_ray(field, camera, d, radius, pixel_angle, upwind);
        if (!twin.on_sphere) {
          EXPECT_EQ(z, 0.0f) << "pixel " << x << ", " << y << " above the horizon";
          continue;
        }
        ASSERT_GT(z, 0.0f) << "pixel " << x << ", " << y;
        const double t_gpu = 0.05 / double(z) / glm::dot(d, forward);
        const double lead = std::clamp(0.01 / (twin.t_sphere * twin.mu_v), 1e-5, 0.1);
        const double t_lead = twin.t_sphere / (1.0 + lead);
        const double sine = twin.mu_v;  // the ray's angle to the sea
        if (field.ocean_wave_count == 0) {
          ++flat;
          worst_flat = std::max(worst_flat, std::abs(t_gpu - t_lead) / twin.t_sphere);
          continue;
        }
        ASSERT_TRUE(twin.hit) << "pixel " << x << ", " << y;
        ++displaced;
        largest_amplitude = std::max(largest_amplitude, twin.amplitude);
        const double surface_height = glm::length(camera + t_gpu * d) - radius;
        // At most A above the sphere, or 1 cm where the sphere's lead is drawn.
        EXPECT_LE(surface_height, std::max(twin.amplitude, 0.01) + 1e-3) << "pixel " << x << ", " << y;
        EXPECT_GE(surface_height, -0.01) << "pixel " << x << ", " << y;
        highest = std::max(highest, surface_height);
        if (twin.t < t_lead) {
          // A crest in front of the sphere: the GPU's point is on the surface.
          ++crests;
          double rate = 0.0;
          const double r_c = glm::length(camera);
          const double g = field.ocean_ray_clearance(t_gpu, d, glm::dot(camera, d), (r_c - radius) * (r_c + radius),
                                                     radius, field.ocean_wave_count, rate);
          worst_clearance = std::max(worst_clearance, std::abs(g));
        }
        worst_height = std::max(worst_height, std::abs(t_gpu - std::min(twin.t, t_lead)) * sine);
      }
  }
  EXPECT_GT(displaced, width * height);  // a third of the pixels at each instant
  EXPECT_GT(flat, 300);
  EXPECT_GT(crests, displaced / 10);
  EXPECT_GT(highest, 0.05);
  EXPECT_LT(worst_clearance, 5e-3);
  EXPECT_LT(worst_height, 5e-3);
  EXPECT_LT(worst_flat, 1e-4);
  std::printf("deck: %d displaced pixels (%d crests in front of the sphere, up to %.3f m of A = %.3f m), %d flat; "
              "GPU against the twin: clearance %.2e m, height %.2e m; flat pixels' t within %.1e\n",
              displaced, crests, highest, largest_amplitude, flat, worst_clearance, worst_height, worst_flat);
}

// The same view from 500 m over a sea 3 m deep and one 3 km deep on a flat
// planet: the sandy seabed shows through the shallow water, brighter in the
// green than the deep water, which is bluer.
TEST_F(OceanGpu, ShallowSeabedShowsThrough) {
  atmos::OceanSettings settings;
  settings.bathymetry_texels = 32;
  atmos::Ocean shallow(*earth_, flat_sea(3.0), *pass_, settings), deep(*earth_, flat_sea(3000.0), *pass_, settings);
  EXPECT_NEAR(shallow.depth_m(glm::dvec3(0, 0, 1)), 3.0, 1e-9);
  EXPECT_NEAR(deep.depth_m(glm::dvec3(0, 1, 0)), 3000.0, 1e-9);
  const int width = 32, height = 32;
  GlobeTarget target(width, height);
  const glm::dvec3 up(0.0, 1.0, 0.0);
  const glm::dvec3 sun = glm::normalize(up + 0.6 * glm::dvec3(0, 0, 1));
  const auto mean_of = [&](atmos::Ocean& ocean, double sea_level) {
    const glm::dvec3 camera = up * (earth_->bottom_radius_m + sea_level + 500.0);
    const std::vector<float> colour =
        draw(ocean, view_from(camera, glm::normalize(-up + 0.3 * glm::dvec3(1, 0, 0)), glm::dvec3(0, 0, 1), width,
                              height, sun),
             target);
    glm::dvec3 sum(0.0);
    for (size_t i = 0; i < colour.size(); i += 4) {
      EXPECT_NE(colour[i], -1.0f);
      sum += glm::dvec3(colour[i], colour[i + 1], colour[i + 2]);
    }
    return sum / double(width * height);
  };
  const glm::dvec3 a = mean_of(shallow, 3.0), b = mean_of(deep, 3000.0);
  EXPECT_GT(a.y, 2.0 * b.y) << "shallow " << a.y << " deep " << b.y;
  EXPECT_GT(b.z / b.y, a.z / a.y);
  std::printf("green: shallow %.4g, deep %.4g (x %.2f)\n", a.y, b.y, a.y / b.y);
  // The light from below 3 m of water, from its map (interpolated in
  // depth between layers 0.73 m apart there) against the function at every
  // pixel (kOceanDirectLight): the view's mean per channel.
  const TermsGuard guard(planet::kOceanBelow);
  const glm::dvec3 mapped = mean_of(shallow, 3.0);
  guard.set(planet::kOceanBelow | planet::kOceanDirectLight);
  const glm::dvec3 direct = mean_of(shallow, 3.0);
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(mapped[c] / direct[c] - 1.0));
  EXPECT_LT(worst, 0.01);
  std::printf("light from below 3 m of water, map against the function: mean rgb %.4g %.4g %.4g, worst channel %.2e\n",
              direct.x, direct.y, direct.z, worst);
}

// Earth from 3000 km over its oceans, the terrain drawn first: the sea
// covers the terrain's flat sea (whose chords sag up to a few metres below
// the sea's sphere from this far), and every pixel whose terrain point lies
// more than 30 m above sea level keeps the terrain's colour.
TEST_F(OceanGpu, TerrainAboveTheSeaHidesIt) {
  atmos::PlanetSurface earth_surface;
  earth_surface.style = atmos::SurfaceStyle::earth;
  earth_surface.seed = 1;
  atmos::GlobeSettings globe_settings;
  globe_settings.complete_every_frame = true;
  atmos::Globe globe(*earth_, earth_surface, *pass_, globe_settings);
  atmos::OceanSettings settings;
  settings.bathymetry_texels = 64;
  atmos::Ocean ocean(*earth_, earth_surface, *pass_, settings);
  const int width = 96, height = 96;
  GlobeTarget target(width, height);
  const glm::dvec3 up = glm::normalize(glm::dvec3(1.0, 0.2, 0.3));
  const glm::dvec3 camera = up * (earth_->bottom_radius_m + 3000e3);
  const atmos::GlobeView view = view_from(camera, -up, glm::dvec3(0, 0, 1), width, height, up);
  target.clear();
  globe.draw(view);
  const std::vector<float> terrain = target.read_colour();
  const std::vector<float> depth = target.read_depth();
  ocean.draw(view);
  const std::vector<float> both = target.read_colour();
  expect_finite(both, "terrain and sea");
  int land = 0, sea = 0, land_kept = 0;
  const glm::dvec3 forward = -up;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y * width + x);
      if (depth[i] <= 0.0f) continue;
      const glm::dvec3 d = pixel_ray(view, x, y);
      const glm::dvec3 point = camera + d * (0.05 / depth[i] / glm::dot(d, forward));
      const double height_m = glm::length(point) - earth_->bottom_radius_m;
      const bool changed = both[4 * i] != terrain[4 * i] || both[4 * i + 1] != terrain[4 * i + 1];
      if (height_m > 30.0) {
        ++land;
        if (!changed) ++land_kept;
      }
      if (changed) ++sea;
    }
  EXPECT_GT(land, 200);
  EXPECT_GT(sea, 1000);
  EXPECT_EQ(land_kept, land);
  std::printf("terrain and sea: %d land pixels kept of %d, %d sea pixels drawn\n", land_kept, land, sea);
}

// From the deck 2 m up at sunset, looking 6 degrees down towards the sun,
// the terrain's flat sea (a flat planet: the datum sphere, at sea level)
// drawn first: the sea covers it at every pixel whose ray meets the
// sphere, crests and troughs near the camera as the horizon (no specks of
// the terrain's sea through the water), and the sky above the horizon
// keeps the terrain's colour.
TEST_F(OceanGpu, DeckSeaCoversTheTerrainsFlatSea) {
  atmos::GlobeSettings globe_settings;
  globe_settings.complete_every_frame = true;
  atmos::Globe globe(*earth_, flat_sea(0.0), *pass_, globe_settings);
  atmos::OceanSettings settings;
  settings.bathymetry_texels = 16;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, settings);
  const int width = 96, height = 54;
  GlobeTarget target(width, height);
  const glm::dvec3 up(0, 0, 1), camera = up * (earth_->bottom_radius_m + 2.0);
  const atmos::GlobeView view = view_from(camera, glm::normalize(glm::dvec3(1, 0.3, -0.1)), up, width, height,
                                          glm::normalize(glm::dvec3(1, 0.2, 0.03)));
  target.clear();
  globe.draw(view);
  const std::vector<float> terrain = target.read_colour();
  ocean.draw(view, 2.5);
  const std::vector<float> both = target.read_colour();
  int sea = 0, covered = 0, sky = 0, sky_kept = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = 4 * size_t(y * width + x);
      const bool changed = both[i] != terrain[i] || both[i + 1] != terrain[i + 1] || both[i + 2] != terrain[i + 2];
      if (atmos_test::ray_hits_sphere(camera, pixel_ray(view, x, y), earth_->bottom_radius_m)) {
        ++sea;
        if (changed) ++covered;
      } else {
        ++sky;
        if (!changed) ++sky_kept;
      }
    }
  EXPECT_GT(sea, width * height / 3);
  EXPECT_EQ(covered, sea);
  EXPECT_EQ(sky_kept, sky);
  std::printf("deck over the terrain's flat sea: %d of %d sea pixels drawn by the water, %d of %d sky pixels kept\n",
              covered, sea, sky_kept, sky);
}

// From 2 m above the sea at sunset and from orbit over the night side: finite,
// non-negative radiance everywhere.
TEST_F(OceanGpu, NoNanFromTheDeckAtSunsetNorOnTheNightSide) {
  atmos::OceanSettings settings;
  settings.bathymetry_texels = 32;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, settings);
  const int width = 64, height = 36;
  GlobeTarget target(width, height);
  const glm::dvec3 up(0, 0, 1);
  const glm::dvec3 camera = up * (earth_->bottom_radius_m + 2.0);
  const glm::dvec3 sun = glm::normalize(glm::dvec3(1, 0, 0.03));
  for (const glm::dvec3& forward : {glm::normalize(glm::dvec3(1, 0, -0.05)), glm::normalize(glm::dvec3(0, 1, -0.2))}) {
    const std::vector<float> colour = draw(ocean, view_from(camera, forward, up, width, height, sun), target, 12.5);
    int drawn = 0;
    for (size_t i = 0; i < colour.size(); i += 4) {
      if (colour[i] == -1.0f) continue;
      ++drawn;
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(std::isfinite(colour[i + size_t(c)]));
        ASSERT_GE(colour[i + size_t(c)], 0.0f);
      }
    }
    EXPECT_GT(drawn, width * height / 3);
  }
  const glm::dvec3 orbit = glm::dvec3(0, 0, earth_->bottom_radius_m + 1000e3);
  const std::vector<float> night =
      draw(ocean, view_from(orbit, -up, glm::dvec3(0, 1, 0), width, height, glm::dvec3(0, 0, -1)), target);
  for (size_t i = 0; i < night.size(); i += 4) {
    if (night[i] == -1.0f) continue;
    for (int c = 0; c < 3; ++c) {
      ASSERT_TRUE(std::isfinite(night[i + size_t(c)]));
      ASSERT_LT(night[i + size_t(c)], 1e-4f);
    }
  }
}

// A moon that leaves an annulus of the sun (0.8 of its radius) over the sea
// point below the camera: the sun's irradiance the shader uses there (drawn
// with kOceanSunIrradiance) is the uneclipsed one times the CPU twin of the
// eclipse's sun factor (sunlight_visible_fraction), and the sea's radiance
// drops.
TEST_F(OceanGpu, MoonOnTheSunDimsTheSea) {
  atmos::OceanSettings settings;
  settings.bathymetry_texels = 16;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, settings);
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const glm::dvec3 sea = up * earth_->bottom_radius_m;
  // 33 x 33: the centre pixel's ray is the view axis, straight down to `sea`.
  const int size = 33, centre = 16;
  GlobeTarget target(size, size);
  const glm::dvec3 sun = glm::normalize(up * std::sin(glm::radians(60.0)) + east * std::cos(glm::radians(60.0)));
  atmos::GlobeView view = view_from(sea + up * 2000.0, -up, north, size, size, sun);
  const double a = earth_->sun_angular_radius_rad;
  const atmos::Moon moon = atmos::moon_in_sky(sea, sun, 0.8 * a);
  const TermsGuard guard(planet::kOceanSunIrradiance);
  const std::vector<float> day = draw(ocean, view, target);
  view.moons = {moon};
  const std::vector<float> eclipse = draw(ocean, view, target);
  guard.set(planet::kOceanAllTerms);
  const std::vector<float> eclipse_radiance = draw(ocean, view, target);
  view.moons.clear();
  const std::vector<float> day_radiance = draw(ocean, view, target);
  const physics::AtmosphereParams params = physics::make_render_params(*earth_, tables_->sizes);
  const physics::Moons moons = physics::make_moons(params, {moon});
  const double sun_factor = physics::sunlight_visible_fraction(moons, float(a), physics::vec3(sea), physics::vec3(sun));
  EXPECT_NEAR(sun_factor, 0.288, 0.01);
  for (int c = 0; c < 3; ++c) {
    const size_t i = size_t(4 * (centre * size + centre) + c);
    EXPECT_NEAR(eclipse[i], day[i] * sun_factor, 2e-3 * day[i]) << "channel " << c;
    EXPECT_TRUE(std::isfinite(eclipse_radiance[i]));
    EXPECT_LT(eclipse_radiance[i], 0.6 * day_radiance[i]) << "channel " << c;
  }
  std::printf("eclipse on the sea: sun factor %.4f; green %.4g of %.4g (day), radiance %.4g of %.4g\n", sun_factor,
              double(eclipse[size_t(4 * (centre * size + centre) + 1)]), double(day[size_t(4 * (centre * size + centre) + 1)]),
              double(eclipse_radiance[size_t(4 * (centre * size + centre) + 1)]),
              double(day_radiance[size_t(4 * (centre * size + centre) + 1)]));
}

// Lakes (PlanetSurface::lake_mask, lake_level_m) over flat ground: a mask
// in EPSG:4326 of 5-degree pixels, lake over longitudes 0-90 and latitudes
// -45-45 degrees, its level 5 m above the ground. From 3000 km above its
// east edge (latitude 0, longitude 90), the water is drawn at the lakes'
// sphere on the mask's side of the edge and nowhere beyond the mask (3
// degrees either side of its edges are the bathymetry's 1.4-degree texels'
// interpolation); the light from below shows the seabed through 5 m of
// water. A mask that cannot be read is an error that names the file.
TEST_F(OceanGpu, LakesAreDrawnWhereTheMaskSays) {
  GDALAllRegister();
  const std::string path = (atmos_test::scratch_directory("ocean-lakes") / "lakes.tif").string();
  const int w = 72, h = 36;
  GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), w, h, 1, GDT_Byte, nullptr);
  ASSERT_NE(ds, nullptr);
  double gt[6] = {-180.0, 5.0, 0.0, 90.0, 0.0, -5.0};
  GDALSetGeoTransform(ds, gt);
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRSetFromUserInput(srs, "EPSG:4326");
  GDALSetSpatialRef(ds, srs);
  OSRDestroySpatialReference(srs);
  std::vector<std::uint8_t> mask(size_t(w) * size_t(h));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double lon = gt[0] + (i + 0.5) * gt[1], lat = gt[3] + (j + 0.5) * gt[5];
      mask[size_t(j * w + i)] = lon > 0.0 && lon < 90.0 && std::abs(lat) < 45.0 ? 1 : 0;
    }
  ASSERT_EQ(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, w, h, mask.data(), w, h, GDT_Byte, 0, 0), CE_None);
  GDALClose(ds);

  atmos::PlanetSurface surface;
  surface.style = atmos::SurfaceStyle::flat;
  surface.lake_mask.source = path;
  surface.lake_level_m = 5.0;
  atmos::OceanSettings settings;
  settings.bathymetry_texels = 64;
  atmos::Ocean ocean(*earth_, surface, *pass_, settings);
  EXPECT_FALSE(ocean.has_sea());
  ASSERT_TRUE(ocean.has_lakes());
  EXPECT_DOUBLE_EQ(ocean.lake_level_m(), 5.0);
  const int width = 64, height = 64;
  GlobeTarget target(width, height);
  const glm::dvec3 up(0.0, 1.0, 0.0);
  const glm::dvec3 camera = up * (earth_->bottom_radius_m + 3000e3);
  const glm::dvec3 sun = glm::normalize(up + glm::dvec3(0.3, 0.0, 0.2));
  const atmos::GlobeView view = view_from(camera, -up, glm::dvec3(0, 0, 1), width, height, sun);
  const TermsGuard guard(planet::kOceanAllTerms);
  const std::vector<float> colour = draw(ocean, view, target);
  guard.set(planet::kOceanBelow);
  const std::vector<float> below = draw(ocean, view, target);
  expect_finite(colour, "lakes");
  const double radius = earth_->bottom_radius_m + 5.0;
  int lake = 0, dry = 0, wrong = 0;
  glm::dvec3 below_sum(0.0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::optional<glm::dvec3> p = sea_point(view, camera, radius, x, y);
      if (!p) continue;
      const glm::dvec3 d = glm::normalize(*p);
      const double lon = glm::degrees(std::atan2(d.y, d.x)), lat = glm::degrees(std::asin(d.z));
      const size_t i = size_t(4 * (y * width + x));
      const bool drawn = colour[i] != -1.0f;
      if (lon > 3.0 && lon < 87.0 && std::abs(lat) < 42.0) {
        ++lake;
        wrong += drawn ? 0 : 1;
        below_sum += glm::dvec3(below[i], below[i + 1], below[i + 2]);
      } else if (lon > 93.0 || lon < -3.0 || std::abs(lat) > 48.0) {
        ++dry;
        wrong += drawn ? 1 : 0;
      }
    }
  EXPECT_GT(lake, 500);
  EXPECT_GT(dry, 500);
  EXPECT_EQ(wrong, 0) << "of " << lake << " lake and " << dry << " dry pixels";
  // 5 m of clear water over sand: the seabed's light, its red more than a
  // quarter of its green (deep clear water's red is 6 % of its green at
  // 680 and 550 nm, and below 0 in sRGB at 15 wavelengths: WaterColumn's
  // and WaterSpectral's colour tests).
  EXPECT_GT(below_sum.x, 0.25 * below_sum.y);
  std::printf("lakes: %d lake pixels drawn, %d dry ones not (wrong %d); light from below rgb %.3g %.3g %.3g\n", lake,
              dry, wrong, below_sum.x / lake, below_sum.y / lake, below_sum.z / lake);

  surface.lake_mask.source = path + ".missing.tif";
  try {
    atmos::Ocean unread(*earth_, surface, *pass_, settings);
    ADD_FAILURE() << "no error for an unreadable lake mask";
  } catch (const atmos::Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(surface.lake_mask.source), std::string::npos) << m;
    EXPECT_NE(m.find("lake mask"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
  surface.lake_mask.source = path;
  surface.lake_level_m.reset();
  EXPECT_THROW({ atmos::Ocean rejected(*earth_, surface, *pass_, settings); }, atmos::Error);
  surface.lake_level_m = 200e3;
  EXPECT_THROW({ atmos::Ocean rejected(*earth_, surface, *pass_, settings); }, atmos::Error);
  surface.lake_level_m = -5.0;
  surface.sea_level_m = 0.0;
  EXPECT_THROW({ atmos::Ocean rejected(*earth_, surface, *pass_, settings); }, atmos::Error);
}

// A full moon mirrored by the waves: the moon's light through the glint's
// BRDF. From 2000 km by night (the sun 60 degrees below the horizon at the
// point below the camera), a moon in direction s 60 degrees up opposite
// the sun (full: phase angle 0), far enough (1e10 m) that its direction
// is the same from every sea point, against the sun's glint by day with
// the sun in the same direction s: pixel by pixel the moon's glint is the
// sun's times (2/3) A (rho/d)^2, the full Lambert sphere's irradiance over
// the sun's (the BRDF, the cosines and the transmittance along s cancel).
TEST_F(OceanGpu, FullMoonGlintIsTheSunsScaledByTheMoonsIrradiance) {
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 6.0;
  settings.bathymetry_texels = 16;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, settings);
  const int width = 48, height = 48;
  GlobeTarget target(width, height);
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.2, 0.5, 0.8));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 s = glm::normalize(up * std::sin(glm::radians(60.0)) + east * std::cos(glm::radians(60.0)));
  const glm::dvec3 camera = up * (earth_->bottom_radius_m + 2000e3);
  atmos::GlobeView view = view_from(camera, -up, glm::cross(up, east), width, height, s);
  const TermsGuard guard(planet::kOceanGlint);
  const std::vector<float> sun_glint = draw(ocean, view, target);
  const double distance = 1e10, radius = 2e7;
  view.sun_direction = -s;
  view.moons = {atmos::Moon{camera + s * distance, radius}};
  const std::vector<float> moon_glint = draw(ocean, view, target);
  view.moons.clear();
  const std::vector<float> dark = draw(ocean, view, target);
  expect_finite(moon_glint, "moon glint");
  const double expected = 2.0 / 3.0 * 0.12 * (radius / distance) * (radius / distance);  // MOON_ALBEDO 0.12
  int compared = 0;
  const double worst = worst_ratio(sun_glint, moon_glint, dark, glm::dvec3(expected), compared);
  EXPECT_GT(compared, 300);
  EXPECT_LT(worst, 0.02) << "over " << compared << " channels";
  std::printf("full moon's glint / sun's: %d channels, worst %.2e from (2/3) A (rho/d)^2 = %.3e\n", compared, worst,
              expected);
}

// A bright star mirrored by the waves (Ocean::set_stars): the pass's
// catalogue holds a star like Sirius (9940 K) in direction s 60 degrees up
// at the point below the camera, and 20 dim ones below every horizon of
// the view, of which only 16 are kept (the bright one among them). From
// 2000 km by night (the sun opposite s), against the sun's glint by day
// with the sun in s: per pixel and channel of the tables the star's glint
// over the sun's is E_star / E_sun, E the irradiances above the atmosphere
// in the tables' channels (the BRDF, the cosines and the transmittance
// along s cancel channel by channel; the pixels are taken back from linear
// sRGB to the channels with M⁻¹, M the shader's conversion); without the
// stars the night's glint is dark.
TEST_F(OceanGpu, BrightStarGlintIsTheSunsScaledByItsIrradiance) {
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 6.0;
  settings.bathymetry_texels = 16;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, settings);
  const int width = 48, height = 48;
  GlobeTarget target(width, height);
  const glm::dvec3 up = glm::normalize(glm::dvec3(-0.4, 0.3, 0.7));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 s = glm::normalize(up * std::sin(glm::radians(60.0)) + east * std::cos(glm::radians(60.0)));
  const glm::dvec3 camera = up * (earth_->bottom_radius_m + 2000e3);
  atmos::GlobeView view = view_from(camera, -up, glm::cross(up, east), width, height, s);
  const TermsGuard guard(planet::kOceanGlint);
  const std::vector<float> sun_glint = draw(ocean, view, target);
  atmos::Star bright;
  bright.direction = s;
  bright.v_band_irradiance = 1.4e-10;  // W m^-2 nm^-1: V = -1.46 (Vega's 3.6e-11 at V = 0)
  bright.temperature_k = 9940.0;
  std::vector<atmos::Star> catalogue(20);
  for (atmos::Star& dim : catalogue) {
    dim.direction = -up;
    dim.v_band_irradiance = 1e-13;
  }
  catalogue.insert(catalogue.begin() + 7, bright);
  pass_->set_star_catalogue(catalogue);
  ocean.set_stars(true);
  view.sun_direction = -s;
  const std::vector<float> star_glint = draw(ocean, view, target);
  ocean.set_stars(false);
  const std::vector<float> dark = draw(ocean, view, target);
  pass_->set_star_catalogue({});
  EXPECT_THROW(ocean.set_stars(true, glm::dmat3(2.0)), atmos::Error);
  expect_finite(star_glint, "star glint");
  const physics::AtmosphereParams params = physics::make_render_params(*earth_, tables_->sizes);
  const glm::vec3 sun_channels = glm::vec3(params.solar_irradiance);
  const glm::vec3 star_channels = atmos::star_channel_irradiance(bright, earth_->wavelengths_nm);
  const glm::mat3 to_channels = glm::inverse(channels_to_srgb());
  const auto channels = [&](std::vector<float> image) {
    for (size_t i = 0; i < image.size(); i += 4) {
      if (image[i] == -1.0f) continue;  // not drawn
      const glm::vec3 c = to_channels * glm::vec3(image[i], image[i + 1], image[i + 2]);
      for (int k = 0; k < 3; ++k) image[i + size_t(k)] = c[k];
    }
    return image;
  };
  int compared = 0;
  const double worst = worst_ratio(channels(sun_glint), channels(star_glint), channels(dark),
                                   glm::dvec3(star_channels) / glm::dvec3(sun_channels), compared);
  EXPECT_GT(compared, 300);
  EXPECT_LT(worst, 0.02) << "over " << compared << " channels";
  std::printf("star's glint / sun's: %d channels, worst %.2e from the irradiances' ratio (green %.3e)\n", compared,
              worst, double(star_channels[1] / sun_channels[1]));
}

// At 15 working wavelengths (small tables of their own, five triples): from
// 2000 km by day, every sea pixel's sun glint and light from below against
// the CPU twin water_spectral_radiance at the pixel's sphere point, lit by
// the sun's irradiance of each triple (its solar irradiance times the
// transmittance of its tile) and the sky's irradiance from the tables'
// CPU samplers, converted to colour as the pass does (linear sRGB = 683
// times the channels). Drawn with the pass's functions (kOceanDirectLight)
// rather than the light maps, which the ocean then does not fill: at 15
// wavelengths the sky's map alone takes minutes on llvmpipe.
// A suite of its own, in the full tier only: its programs at five triples
// take longer to compile than the rest of OceanGpu together. The default
// tier checks the same functions at 15 wavelengths in WaterGpu (GLSL
// against the C++) and WaterSpectral (against their definition).
class OceanSpectralGpu : public OceanGpu {};

TEST_F(OceanSpectralGpu, GlintAndLightFromBelowMatchTheCpuTwin) {
  atmos::Atmosphere earth = *earth_;
  earth.wavelengths_nm = atmos::spectral_wavelengths(15);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(earth, options);
  atmos::AtmospherePass pass(earth, tables, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 6.0;
  settings.water.chlorophyll_mg_m3 = 0.3;
  settings.wind_azimuth_deg = 30.0;
  settings.bathymetry_texels = 16;
  const double sea_level = 20.0;  // 20 m of water over the flat ground: the seabed shows
  const TermsGuard guard(planet::kOceanGlint | planet::kOceanBelow | planet::kOceanDirectLight);
  atmos::Ocean ocean(earth, flat_sea(sea_level), pass, settings);
  const int width = 40, height = 40;
  GlobeTarget target(width, height);
  const double radius = earth.bottom_radius_m + sea_level;
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.3, -1.0, 0.4));
  const glm::dvec3 camera = up * (earth.bottom_radius_m + 2000e3);
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 sun = glm::normalize(up + 0.25 * east + 0.1 * glm::cross(up, east));
  const atmos::GlobeView view = view_from(camera, -up, glm::cross(up, east), width, height, sun);
  const std::vector<float> colour = draw(ocean, view, target);
  expect_finite(colour, "spectral sea");

  namespace ph = physics;
  const ph::AtmosphereParams params = ph::make_render_params(earth, tables.sizes);
  const std::unique_ptr<ph::SpectralSets> sets = ph::make_spectral_sets(earth, tables.sizes);
  const std::unique_ptr<ph::WaterSpectrum> spectrum = ph::make_water_spectrum(settings.water, earth);
  ASSERT_EQ(spectrum->count, 5);
  const atmos::runtime::TableSamplers samplers = atmos::runtime::make_samplers(tables);
  const glm::vec3 albedo(settings.seabed_albedo);
  float peak = 0.0f;
  for (size_t i = 0; i < colour.size(); i += 4) peak = std::max(peak, colour[i + 1]);
  ASSERT_GT(peak, 0.0f);
  int compared = 0;
  double worst = 0.0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::optional<glm::dvec3> p = sea_point(view, camera, radius, x, y);
      const float* g = &colour[size_t(4 * (y * width + x))];
      if (!p) continue;
      ASSERT_NE(g[0], -1.0f) << "not drawn on the sphere at " << x << "," << y;
      const glm::vec3 n(glm::normalize(*p)), v(glm::normalize(camera - *p)), s(sun);
      const glm::vec3 point(*p);
      const float r = ph::clamp_radius(params, float(radius)), mu_s = ph::clamp_cosine(glm::dot(n, s));
      ph::vec3 sun_sets[SPECTRAL_SET_CAPACITY] = {};
      for (int k = 0; k < spectrum->count; ++k)
        sun_sets[k] = sets->set[k].solar_irradiance *
                      ph::transmittance_to_sun(sets->set[k], samplers.spectral_optical_depth, r, mu_s);
      ph::vec3 sky;
      ph::sun_and_sky_irradiance(params, *sets, samplers.spectral_optical_depth, samplers.indirect_irradiance, point,
                                 n, s, sky);
      float cosine;
      const float factor =
          ph::water_glint_geometry(spectrum->set[0].slope_variance, n, glm::vec3(upwind_at(camera, *p / glm::length(*p), 30.0)),
                                   v, s, cosine) *
          std::max(glm::dot(s, n), 0.0f);
      glm::vec3 glint;
      const glm::vec3 below = ph::water_spectral_radiance(*spectrum, sun_sets, sky, factor, cosine, n, v, s,
                                                          float(sea_level), albedo, glint);
      const glm::vec3 expected = float(atmos::kMaxLuminousEfficacy / view.nits_per_unit) * (glint + below);
      for (int c = 0; c < 3; ++c) {
        if (expected[c] < 0.01f * peak) continue;
        ++compared;
        worst = std::max(worst, std::abs(double(g[c]) - double(expected[c])) / double(expected[c]));
      }
    }
  EXPECT_GT(compared, 300);
  EXPECT_LT(worst, 2e-3) << "over " << compared << " channels";
  std::printf("15 wavelengths, glint and light from below vs CPU twin: %d channels, worst relative difference %.2e\n",
              compared, worst);
}

// The sea over a pass of the instant mode (the viewer's pass while exact
// tables are computed): its light maps are filled through the instant
// pass's GLSL library (the sky's radiance marched along each ray,
// engine_library.glsl with ATMOS_INSTANT), and the sea seen from 10 km by
// day is finite, non-negative and within 8 % of the same sea over the exact
// pass in the mean, 25 % at its worst pixel: the bounds of the instant
// mode's own sky under the preset's haze, whose forward-scattered light an
// isotropic multiple scattering cannot follow (docs/instant.md: RMS 4.9-9.3 %,
// worst 14.6-25 % against the reference).
TEST_F(OceanGpu, LitByAnInstantPass) {
  const atmos::InstantTables instant_tables = atmos::compute_instant_tables(*earth_, tables_->sizes);
  atmos::AtmospherePass instant_pass(*earth_, instant_tables, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  atmos::OceanSettings settings;
  settings.water.wind_speed_m_s = 7.0;
  settings.bathymetry_texels = 32;
  const double sea_level = 1000.0;
  atmos::Ocean exact(*earth_, flat_sea(sea_level), *pass_, settings);
  atmos::Ocean instant(*earth_, flat_sea(sea_level), instant_pass, settings);
  const int width = 48, height = 32;
  GlobeTarget target(width, height);
  const glm::dvec3 up(0, 0, 1), east(1, 0, 0), north(0, 1, 0);
  const double radius = earth_->bottom_radius_m + sea_level;
  const atmos::GlobeView view = view_from(up * (radius + 10e3), glm::normalize(north - 0.6 * up), up, width, height,
                                          glm::normalize(up + 0.8 * east + 0.3 * north));
  const std::vector<float> from_exact = draw(exact, view, target);
  const std::vector<float> from_instant = draw(instant, view, target);
  expect_finite(from_instant, "instant");
  double sum = 0.0, worst = 0.0;
  int count = 0;
  for (size_t i = 0; i < from_exact.size(); i += 4) {
    ASSERT_EQ(from_exact[i] == -1.0f, from_instant[i] == -1.0f) << "pixel " << i / 4;
    if (from_exact[i] == -1.0f) continue;
    for (size_t c = 0; c < 3; ++c) {
      ASSERT_GE(from_instant[i + c], 0.0f) << "pixel " << i / 4;
      const double error = std::abs(from_instant[i + c] / from_exact[i + c] - 1.0);
      sum += error;
      worst = std::max(worst, error);
      ++count;
    }
  }
  ASSERT_GT(count, 0);
  std::printf("instant against exact pass: %d sea channels, mean %.4f, worst %.4f\n", count, sum / count, worst);
  EXPECT_LE(sum / count, 0.08);
  EXPECT_LE(worst, 0.25);
}

TEST_F(OceanGpu, RejectsBadInput) {
  const auto message = [&](const atmos::PlanetSurface& surface, const atmos::OceanSettings& s) {
    try {
      atmos::Ocean ocean(*earth_, surface, *pass_, s);
    } catch (const atmos::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  atmos::OceanSettings s;
  s.water.wind_speed_m_s = -1.0;
  std::string m = message(flat_sea(0.0), s);
  EXPECT_NE(m.find("wind"), std::string::npos) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  s = {};
  s.water.wind_speed_m_s = std::nan("");
  EXPECT_NE(message(flat_sea(0.0), s).find("wind"), std::string::npos);
  s = {};
  m = message(flat_sea(200e3), s);
  EXPECT_NE(m.find("sea level"), std::string::npos) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  EXPECT_NE(message(flat_sea(-7000e3), s).find("sea level"), std::string::npos);
  s.water.chlorophyll_mg_m3 = 30.0;
  EXPECT_NE(message(flat_sea(0.0), s).find("chlorophyll"), std::string::npos);
  s = {};
  s.seabed_albedo = glm::dvec3(0.5, 1.5, 0.5);
  EXPECT_NE(message(flat_sea(0.0), s).find("albedo"), std::string::npos);
  s = {};
  s.bathymetry_texels = 4;
  EXPECT_NE(message(flat_sea(0.0), s).find("bathymetry_texels"), std::string::npos);

  s = {};
  s.bathymetry_texels = 16;
  atmos::Ocean ocean(*earth_, flat_sea(0.0), *pass_, s);
  atmos::GlobeView view = view_from(glm::dvec3(0, 0, 7e6), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0), 8, 8,
                                    glm::dvec3(0, 0, 1));
  EXPECT_THROW(ocean.draw(view, std::nan("")), atmos::Error);
  // The view checks the planet layer shares (planet::check_view_matrices).
  const auto draw_message = [&](const atmos::GlobeView& v) {
    try {
      ocean.draw(v);
    } catch (const atmos::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  atmos::GlobeView bad = view;
  bad.width = 0;
  EXPECT_EQ(draw_message(bad), "ocean view: empty viewport");
  bad = view;
  bad.view = glm::dmat4(0.0);
  EXPECT_EQ(draw_message(bad), "ocean view: singular view matrix");
  bad = view;
  bad.projection[1][1] = 0.0;
  EXPECT_EQ(draw_message(bad), "ocean view: degenerate projection");
  view.sun_direction = glm::dvec3(0.0);
  EXPECT_THROW(ocean.draw(view), atmos::Error);
  // A surface without a sea: an ocean that draws nothing.
  atmos::PlanetSurface mars;
  mars.style = atmos::SurfaceStyle::mars;
  atmos::Ocean dry(*earth_, mars, *pass_, s);
  EXPECT_FALSE(dry.has_sea());
  EXPECT_TRUE(std::isnan(dry.sea_level_m()));
}

}  // namespace
