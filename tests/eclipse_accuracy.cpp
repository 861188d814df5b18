// Eclipses against the brute-force reference with moons (src/reference:
// every next-event estimate towards the limb-darkened sun is blocked by the
// moon spheres it meets; nothing shared with src/physics/eclipse.glsl).
//
// Two measurements, sky seen from the ground with the sun 40° up:
//  - single scattering (tables of 1 order against the reference with K = 1):
//    the per-node eclipse of the single scattering along the view rays and
//    of the ground's direct light, which is geometry plus quadrature and
//    must agree closely — partial: RMS <= 3 %, every direction <= 8 %;
//    totality: every direction within 5 % + 3 standard errors of the
//    (noisy) reference;
//  - all orders (4 against K = 4) in totality: the documented approximation
//    of the multiple-scattered light (ray_integration.glsl:
//    diffuse_light_visible_fraction), which has no such claim — under a
//    clear sky (Earth with an aerosol of optical depth 0.005) every
//    direction within a factor of 1.5 of the reference (|ln ratio| <=
//    ln 1.5), the zenith included; under the preset's continental haze
//    (optical depth 0.15) a known shortfall, bounded so that it cannot grow
//    unnoticed.
// Directions whose reference luminance is below 1 % of the brightest of the
// configuration are not counted (as in reference_accuracy.cpp). The measured
// errors are printed and recorded as figures (figures.hpp).
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/planet_file.hpp"
#include "reference/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "support/reference_store.hpp"
#include "clear_sky_earth.hpp"
#include "figures.hpp"

namespace {

struct Errors {
  double rms = 0.0;
  double worst = 0.0;           // largest |relative error|
  double worst_log_ratio = 0.0; // largest |ln(table / reference)|
  double worst_beyond_noise = 0.0;  // largest |relative error| - 3 x the reference's relative standard error
  double zenith_table = 0.0, zenith_reference = 0.0;
};

int paths_from_environment() {
  const char* v = std::getenv("ATMOS_ACCURACY_PATHS");
  return v ? std::max(100, std::atoi(v)) : 6000;
}

// The Earth preset, or (`clear`) the clear-sky Earth of clear_sky_earth.hpp.
atmos::Atmosphere earth(bool clear) { return clear ? clear_sky_earth() : atmos::load_atmosphere("earth"); }

// The sky of an observer on the ground with the sun at (200°, 40°) and a
// moon of angular radius 0.28° (the Sun's: 0.2664°) whose centre is
// `offset_deg` above the sun's: tables of `orders` orders against the
// reference with K = orders.
Errors measure(int orders, double offset_deg, int paths_factor, const char* name, bool clear = false) {
  const atmos::Atmosphere atmosphere = earth(clear);
  atmos::PrecomputeOptions options;
  options.scattering_orders = orders;
  const char* cache = std::getenv("ATMOS_CACHE_DIR");
  const atmos::Tables tables = cache ? atmos::load_or_precompute_tables(atmosphere, options, cache).tables
                                     : atmos::precompute_tables(atmosphere, options);
  const atmos::SkyModel model(atmosphere, tables);
  const glm::dvec3 observer = atmos::observer_position(atmosphere, 0.0);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(200.0, 40.0);
  const std::vector<atmos::Moon> moons = {atmos::moon_in_sky(
      observer, atmos::direction_from_azimuth_elevation(200.0, 40.0 + offset_deg), 0.28 * M_PI / 180.0)};

  std::vector<glm::dvec3> directions = {{0.0, 0.0, 1.0}};
  for (double el : {2.0, 6.0, 15.0, 30.0, 60.0})
    for (double relative_azimuth : {0.0, 90.0, 180.0})
      directions.push_back(atmos::direction_from_azimuth_elevation(200.0 + relative_azimuth, el));

  atmos::ReferenceOptions reference_options;
  reference_options.scattering_orders = orders;
  // In totality the light comes from few, long paths: the reference needs
  // many more of them.
  reference_options.paths = paths_from_environment() * paths_factor;
  reference_options.sun_limb_darkening_u = 0.6;  // the law of src/physics/eclipse.glsl
  for (const atmos::Moon& m : moons) reference_options.moons.push_back({m.centre_m, m.radius_m});

  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(atmosphere.wavelengths_nm);
  auto luminance_of_spectrum = [&](const std::vector<double>& values) {
    glm::dvec3 rgb(0.0);
    for (size_t i = 0; i < values.size(); ++i) rgb += weights[i] * values[i];
    return atmos::srgb_luminance(rgb);
  };
  std::vector<double> table(directions.size()), reference(directions.size()), noise(directions.size());
  tbb::parallel_for(size_t(0), directions.size(), [&](size_t i) {
    table[i] = atmos::srgb_luminance(model.to_srgb(model.radiance(observer, directions[i], sun, false, moons)));
    atmos::ReferenceOptions o = reference_options;
    o.seed = 3000 + i;
    const atmos::ReferenceResult r = atmos_test::oracle::reference_radiance(atmosphere, observer, directions[i], sun, o);
    reference[i] = luminance_of_spectrum(r.radiance);
    noise[i] = std::abs(luminance_of_spectrum(r.standard_error));
  });
  double brightest = 0.0;
  for (double v : reference) brightest = std::max(brightest, v);
  Errors e;
  e.zenith_table = table[0];
  e.zenith_reference = reference[0];
  double sum_sq = 0.0;
  int counted = 0;
  for (size_t i = 0; i < directions.size(); ++i) {
    EXPECT_TRUE(std::isfinite(table[i]) && table[i] >= 0.0);
    if (reference[i] < 0.01 * brightest) continue;
    const double relative = (table[i] - reference[i]) / reference[i];
    const double el = std::asin(directions[i].z) * 180.0 / M_PI;
    const double az = std::atan2(directions[i].x, directions[i].y) * 180.0 / M_PI - 200.0;
    std::printf("  %s: az-sun %6.1f el %5.1f  table %10.4g  reference %10.4g +- %5.2f %%  error %+7.2f %%\n", name,
                az, el, table[i], reference[i], 100.0 * noise[i] / reference[i], 100.0 * relative);
    sum_sq += relative * relative;
    e.worst = std::max(e.worst, std::abs(relative));
    e.worst_log_ratio = std::max(e.worst_log_ratio, std::abs(std::log(std::max(table[i], 1e-30) / reference[i])));
    e.worst_beyond_noise = std::max(e.worst_beyond_noise, std::abs(relative) - 3.0 * noise[i] / reference[i]);
    ++counted;
  }
  e.rms = std::sqrt(sum_sq / std::max(counted, 1));
  std::printf("%s: RMS %.2f %%, max %.2f %%, max |ln ratio| %.3f; zenith table %.4g reference %.4g cd/m2 (%d of %zu "
              "directions)\n",
              name, 100.0 * e.rms, 100.0 * e.worst, e.worst_log_ratio, e.zenith_table, e.zenith_reference, counted,
              directions.size());
  atmos_test::record_figure("RMS", 100.0 * e.rms, "%", "");
  atmos_test::record_figure("max", 100.0 * e.worst, "%", "");
  atmos_test::record_figure("max abs ln(tables / reference)", e.worst_log_ratio, "", "");
  atmos_test::record_figure("max beyond 3 standard errors of the reference",
                            100.0 * std::max(0.0, e.worst_beyond_noise), "%", "");
  atmos_test::record_figure("zenith, tables", e.zenith_table, "cd/m2", "");
  atmos_test::record_figure("zenith, reference", e.zenith_reference, "cd/m2", "");
  return e;
}

TEST(EclipseAccuracy, SingleScatteringInAPartialEclipse) {
  const Errors e = measure(1, 0.3, 4, "partial, single scattering");
  EXPECT_LT(e.rms, 0.03);
  EXPECT_LT(e.worst, 0.08);
}

// In totality only the rays towards the horizon see sunlit air: the
// reference, even with 50 times the paths, has 2-12 % noise there; every
// direction must agree within 5 % + 3 standard errors.
TEST(EclipseAccuracy, SingleScatteringInTotality) {
  const Errors e = measure(1, 0.0, 50, "totality, single scattering");
  EXPECT_EQ(e.zenith_table, 0.0);  // the zenith ray stays in the umbra
  EXPECT_LT(e.worst_beyond_noise, 0.05);
}

// Under a clear sky the approximation is within ~10 % at the zenith (the
// reference's noise there is 9 %); the horizon ring, where the view rays reach
// the sunlit air beyond the umbra, is its darkest part, about a quarter too
// dark. Bound: every direction within a factor of 1.5.
TEST(EclipseAccuracy, AllOrdersInTotalityWithinFiftyPercent) {
  const Errors e = measure(4, 0.0, 20, "totality, clear sky, 4 orders", true);
  EXPECT_LT(e.worst_log_ratio, std::log(1.5));
}

// Under the continental haze: a known shortfall of the approximation. It
// follows the diffuse light along horizontal lines, which the haze near the
// ground dims (optical depth ~0.7 per 8 km at 440 nm), while the real
// diffuse light also comes down along slanted paths from the sunlit air
// above the haze: every direction is too dark, by up to three quarters.
// Bound: a factor of 5, with the zenith below the reference.
TEST(EclipseAccuracy, AllOrdersInTotalityUnderHazeWithinAFactorOfFive) {
  const Errors e = measure(4, 0.0, 20, "totality, continental haze, 4 orders");
  EXPECT_LT(e.worst_log_ratio, std::log(5.0));
  EXPECT_LT(e.zenith_table, e.zenith_reference);  // the direction of the shortfall
}

}  // namespace
