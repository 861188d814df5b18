// The instant approximate mode (Hillaire 2020; physics/instant_atmosphere.glsl)
// against the independent brute-force reference (src/reference, Monte Carlo
// path tracing, 16 orders, which the mode's geometric series stands for):
// the sky as the instant pass draws it (gpu::instant_sky_radiance_cpu: the
// per-frame sky-view table, phase functions per ray) at a spread of views,
// and the aerial perspective in front of surfaces (its volume). The
// reference's results are stored (tests/data/reference/InstantAccuracy.json,
// support/reference_store.hpp).
//
// Earth: the clear sky of the calibrated bounds (clear_sky_earth.hpp) and
// the preset's continental haze, observers at 0 m and 10 km, the sun from
// 60° to 2.5°, the directions of reference_accuracy.cpp (8 elevations from
// -30° to 88° x 5 azimuths from the sun's, minus 1° around the sun, those
// below 1 % of the brightest not counted); RMS relative luminance error.
// Mars (the dusty preset): the ground, the sun 60° and 10° up, 6 elevations
// x 8 azimuths minus 3° around the sun; RMS relative error per sRGB channel
// within and beyond 20° of the sun (as mars_accuracy.cpp).
//
// The bounds are the measurements (docs/instant.md) with a margin: what
// is left is the method's isotropic multiple scattering (Hillaire 2020
// reports a few per cent on Earth). The exact tables' errors on the same
// views are printed beside the clear sky's.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "clear_sky_earth.hpp"
#include "figures.hpp"
#include "gpu/instant.hpp"
#include "physics/parameters.hpp"
#include "support/reference_store.hpp"

namespace {

constexpr int kReferenceOrders = 16;

struct SkyError {
  double rms = 0.0, worst = 0.0, mean = 0.0;  // mean: the signed mean relative error
  double exact_rms = -1.0;  // the exact tables' on the same views (when given)
};

// Directions of reference_accuracy.cpp's spread for an observer in the
// atmosphere.
std::vector<glm::dvec3> earth_views(const glm::dvec3& sun) {
  std::vector<glm::dvec3> out;
  const double sun_azimuth = std::atan2(sun.x, sun.y) * 180.0 / M_PI;
  for (double el : {-30.0, -4.0, 2.0, 8.0, 20.0, 40.0, 65.0, 88.0})
    for (double relative_azimuth : {0.0, 45.0, 90.0, 135.0, 180.0}) {
      const glm::dvec3 d = atmos::direction_from_azimuth_elevation(sun_azimuth + relative_azimuth, el);
      if (glm::dot(d, sun) > std::cos(1.0 * M_PI / 180.0)) continue;
      out.push_back(d);
    }
  return out;
}

// The reference's spectra at the views, in linear sRGB (CIE weights of the
// working wavelengths).
std::vector<glm::dvec3> reference_srgb(const atmos::Atmosphere& atmosphere, const glm::dvec3& observer,
                                       const std::vector<glm::dvec3>& views, const glm::dvec3& sun, int paths,
                                       int seed) {
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(atmosphere.wavelengths_nm);
  std::vector<glm::dvec3> out(views.size(), glm::dvec3(0.0));
  tbb::parallel_for(size_t(0), views.size(), [&](size_t i) {
    atmos::ReferenceOptions o;
    o.paths = paths;
    o.scattering_orders = kReferenceOrders;
    o.seed = std::uint64_t(seed) + i;
    const atmos::ReferenceResult r = atmos_test::oracle::reference_radiance(atmosphere, observer, views[i], sun, o);
    for (size_t l = 0; l < r.radiance.size(); ++l) out[i] += weights[l] * r.radiance[l];
  });
  return out;
}

SkyError earth_sky_error(const char* name, const atmos::Atmosphere& earth, const atmos::InstantTables& instant,
                         const atmos::SkyModel* exact, double altitude, double sun_elevation) {
  const glm::dvec3 observer = atmos::observer_position(earth, altitude);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(200.0, sun_elevation);
  const std::vector<glm::dvec3> views = earth_views(sun);
  const glm::dmat3 to_srgb(atmos::physics::channels_to_srgb_matrix(earth.wavelengths_nm));
  const std::vector<glm::dvec3> fast = atmos::gpu::instant_sky_radiance_cpu(earth, instant, observer, sun, views);
  const std::vector<glm::dvec3> reference = reference_srgb(earth, observer, views, sun, 6000, 1000);
  double brightest = 0.0;
  for (const glm::dvec3& r : reference) brightest = std::max(brightest, atmos::srgb_luminance(r));
  SkyError out;
  double sum_sq = 0.0, exact_sq = 0.0;
  int counted = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    const double ref = atmos::srgb_luminance(reference[i]);
    const double value = atmos::srgb_luminance(to_srgb * fast[i]);
    EXPECT_TRUE(std::isfinite(value) && value >= 0.0);
    if (ref < 0.01 * brightest) continue;
    const double e = (value - ref) / ref;
    if (std::getenv("ATMOS_ACCURACY_VERBOSE"))
      std::printf("    elevation %6.1f  azimuth from the sun %6.1f  instant %10.4g  reference %10.4g  error %+6.2f %%\n",
                  std::asin(views[i].z) * 180.0 / M_PI,
                  std::remainder(std::atan2(views[i].x, views[i].y) * 180.0 / M_PI - 200.0, 360.0), value, ref,
                  100.0 * e);
    sum_sq += e * e;
    out.mean += e;
    out.worst = std::max(out.worst, std::abs(e));
    if (exact != nullptr) {
      const double x = atmos::srgb_luminance(exact->to_srgb(exact->radiance(observer, views[i], sun, false)));
      exact_sq += (x - ref) * (x - ref) / (ref * ref);
    }
    ++counted;
  }
  out.rms = std::sqrt(sum_sq / std::max(counted, 1));
  out.mean /= std::max(counted, 1);
  if (exact != nullptr) out.exact_rms = std::sqrt(exact_sq / std::max(counted, 1));
  char config[96];
  std::snprintf(config, sizeof config, "%s, %g m, sun %+.1f deg", name, altitude, sun_elevation);
  char exact_text[48] = "";
  if (exact != nullptr) std::snprintf(exact_text, sizeof exact_text, "   exact tables RMS %5.2f %%", 100.0 * out.exact_rms);
  std::printf("%-34s instant RMS %5.2f %%  max %5.2f %%  mean %+5.2f %%%s  (%d views)\n", config, 100.0 * out.rms,
              100.0 * out.worst, 100.0 * out.mean, exact_text, counted);
  std::fflush(stdout);
  atmos_test::record_figure(std::string("instant RMS, ") + config, 100.0 * out.rms, "%", "");
  atmos_test::record_figure(std::string("instant max, ") + config, 100.0 * out.worst, "%", "");
  atmos_test::record_figure(std::string("instant mean, ") + config, 100.0 * out.mean, "%", "");
  if (exact != nullptr)
    atmos_test::record_figure(std::string("exact tables RMS, ") + config, 100.0 * out.exact_rms, "%", "");
  EXPECT_GE(counted, 10);
  return out;
}

atmos::Tables exact_tables(const atmos::Atmosphere& atmosphere) {
  const atmos::PrecomputeOptions options;
  const char* cache = std::getenv("ATMOS_CACHE_DIR");
  return cache ? atmos::load_or_precompute_tables(atmosphere, options, cache).tables
               : atmos::precompute_tables(atmosphere, options);
}

// Clear sky: measured 1.6-3.0 % RMS by day (sun 5°-60°; the exact tables
// 0.5-0.8 % on the same views), the mode 1-2 % darker on average; bound
// 4 %. With the sun 2.5° up 1.8-3.4 %: bound 5 %.
TEST(InstantAccuracy, EarthClearSky) {
  const atmos::Atmosphere earth = clear_sky_earth();
  const atmos::InstantTables instant = atmos::compute_instant_tables(earth);
  const atmos::Tables tables = exact_tables(earth);
  const atmos::SkyModel exact(earth, tables);
  for (double altitude : {0.0, 10e3}) {
    for (double sun : {60.0, 15.0, 5.0})
      EXPECT_LE(earth_sky_error("clear Earth", earth, instant, &exact, altitude, sun).rms, 0.04)
          << altitude << " m, sun " << sun;
    EXPECT_LE(earth_sky_error("clear Earth", earth, instant, &exact, altitude, 2.5).rms, 0.05) << altitude << " m";
  }
}

// The preset's continental haze (Cornette-Shanks g 0.64, optical depth
// 0.15): the aerosol's multiple scattering is peaked forward, not isotropic
// as the method takes it, so the sky within 60° of the sun is too dark (up
// to 25 % 45° from it near the horizon with the sun 15° up) and the sky
// opposite it too bright. Measured 4.9 % RMS with the sun 60° up and 9.3 %
// with it 15° up (the exact tables: 1-2.5 %, reference_accuracy.cpp);
// bounds 7 % and 12 %.
TEST(InstantAccuracy, EarthHaze) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const atmos::InstantTables instant = atmos::compute_instant_tables(earth);
  EXPECT_LE(earth_sky_error("hazy Earth", earth, instant, nullptr, 0.0, 60.0).rms, 0.07);
  EXPECT_LE(earth_sky_error("hazy Earth", earth, instant, nullptr, 0.0, 15.0).rms, 0.12);
}

// The dusty Mars sky, per sRGB channel within / beyond 20° of the sun. The
// dust's forward lobe (g 0.86-0.93) is far from the method's isotropic
// multiple scattering. Measured: sun 60°, 6.0 % / 15.2 %; sun 10°, 48.3 % /
// 26.3 % (the exact tables 6.6 % / 9.2 % and 20.7 % / 8.4 %,
// mars_accuracy.cpp). Bounds: the measurements + 30 %, rounded.
TEST(InstantAccuracy, MarsDust) {
  const atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  const atmos::InstantTables instant = atmos::compute_instant_tables(mars);
  const glm::dmat3 to_srgb(atmos::physics::channels_to_srgb_matrix(mars.wavelengths_nm));
  const glm::dvec3 observer = atmos::observer_position(mars, 0.0);
  struct Bound {
    double sun, near, far;
  };
  for (const Bound& b : {Bound{60.0, 0.08, 0.20}, Bound{10.0, 0.62, 0.33}}) {
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, b.sun);
    std::vector<glm::dvec3> views;
    for (double elevation : {3.0, 8.0, 15.0, 30.0, 60.0, 85.0})
      for (double azimuth : {0.0, 60.0, 120.0, 165.0, 180.0, 195.0, 240.0, 300.0}) {
        const glm::dvec3 v = atmos::direction_from_azimuth_elevation(azimuth, elevation);
        if (glm::dot(v, sun) < std::cos(glm::radians(3.0))) views.push_back(v);
      }
    const std::vector<glm::dvec3> fast = atmos::gpu::instant_sky_radiance_cpu(mars, instant, observer, sun, views);
    const std::vector<glm::dvec3> reference = reference_srgb(mars, observer, views, sun, 6000, 700);
    double near_sq = 0.0, far_sq = 0.0, worst = 0.0;
    int near_n = 0, far_n = 0;
    for (size_t i = 0; i < views.size(); ++i) {
      const glm::dvec3 value = to_srgb * fast[i];
      const bool near = glm::dot(views[i], sun) > std::cos(glm::radians(20.0));
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(std::isfinite(value[c]));
        const double e = (value[c] - reference[i][c]) / reference[i][c];
        (near ? near_sq : far_sq) += e * e;
        ++(near ? near_n : far_n);
        worst = std::max(worst, std::abs(e));
      }
    }
    const double near_rms = std::sqrt(near_sq / std::max(near_n, 1));
    const double far_rms = std::sqrt(far_sq / std::max(far_n, 1));
    std::printf("mars, sun %4.1f deg: instant RMS within 20 deg of the sun %5.1f %%, beyond %5.1f %%, worst %5.1f %%\n",
                b.sun, 100.0 * near_rms, 100.0 * far_rms, 100.0 * worst);
    char config[64];
    std::snprintf(config, sizeof config, "Mars, 0 m, sun %g deg", b.sun);
    atmos_test::record_figure(std::string("instant RMS within 20 deg of the sun, ") + config, 100.0 * near_rms, "%",
                              "");
    atmos_test::record_figure(std::string("instant RMS beyond 20 deg of the sun, ") + config, 100.0 * far_rms, "%",
                              "");
    atmos_test::record_figure(std::string("instant max, ") + config, 100.0 * worst, "%", "");
    EXPECT_LE(near_rms, b.near) << b.sun;
    EXPECT_LE(far_rms, b.far) << b.sun;
  }
}

}  // namespace
