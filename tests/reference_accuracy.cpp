// The precomputed tables against the independent brute-force reference
// (src/reference, Monte Carlo path tracing capped at K interactions, sharing
// nothing with the table code but the atmosphere description).
//
// Tolerances: RMS relative luminance error <= 2 % for sun elevations 5°–90°
// and <= 5 % for -5°–5°, over a spread of directions (excluding 1° around
// the sun), for observers at 0 m, 10 km, 100 km and in space. Directions
// whose reference luminance is below 1 % of the brightest direction of the
// same configuration (deep night side, black space) are not counted: their
// relative error is meaningless and their absolute error negligible. The
// measured errors are printed and recorded as figures (figures.hpp) for
// docs/accuracy.md.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/planet_file.hpp"
#include "reference/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "support/reference_store.hpp"
#include "clear_sky_earth.hpp"
#include "figures.hpp"

namespace {

struct Observer {
  const char* name;
  double altitude_m;
};

int paths_from_environment() {
  const char* v = std::getenv("ATMOS_ACCURACY_PATHS");
  return v ? std::max(100, std::atoi(v)) : 6000;
}

// The tables of one atmosphere, their sky model and the measurement.
struct Measurement {
  atmos::Atmosphere atmosphere;
  atmos::Tables tables;
  std::unique_ptr<atmos::SkyModel> model;

  explicit Measurement(atmos::Atmosphere a, atmos::PrecomputeOptions options = {})  // default: default sizes, 4 orders
      : atmosphere(std::move(a)) {
    const char* cache = std::getenv("ATMOS_CACHE_DIR");
    tables = cache ? atmos::load_or_precompute_tables(atmosphere, options, cache).tables
                   : atmos::precompute_tables(atmosphere, options);
    model = std::make_unique<atmos::SkyModel>(atmosphere, tables);
  }
  // Given tables (e.g. blended over another ground albedo, GroundAlbedoAccuracy).
  Measurement(atmos::Atmosphere a, atmos::Tables t) : atmosphere(std::move(a)), tables(std::move(t)) {
    model = std::make_unique<atmos::SkyModel>(atmosphere, tables);
  }

  // Directions of one configuration: a spread over the sphere as seen from
  // the observer, more densely above the horizon; from space, the planet disc
  // and its limb.
  std::vector<glm::dvec3> directions(double altitude_m, const glm::dvec3& sun) const {
    std::vector<glm::dvec3> out;
    std::vector<double> elevations;
    // At the top of the atmosphere and above, what there is to see is below:
    // the planet disc, its limb and the glow above the limb.
    if (altitude_m >= 0.99 * (atmosphere.top_radius_m - atmosphere.bottom_radius_m)) {
      const double dip =
          std::acos(atmosphere.bottom_radius_m / (atmosphere.bottom_radius_m + altitude_m)) * 180.0 / M_PI;
      // From the nadir to past the limb (the atmosphere's glow above it).
      for (double f : {1.0, 0.8, 0.6, 0.4, 0.25, 0.12, 0.05, 0.01, -0.01, -0.02})
        elevations.push_back(-dip - (90.0 - dip) * f);
    } else {
      elevations = {-30.0, -4.0, 2.0, 8.0, 20.0, 40.0, 65.0, 88.0};
    }
    const double sun_azimuth = std::atan2(sun.x, sun.y) * 180.0 / M_PI;
    for (double el : elevations)
      for (double relative_azimuth : {0.0, 45.0, 90.0, 135.0, 180.0}) {
        const glm::dvec3 d = atmos::direction_from_azimuth_elevation(sun_azimuth + relative_azimuth, el);
        if (glm::dot(d, sun) > std::cos(1.0 * M_PI / 180.0)) continue;  // within 1° of the sun
        out.push_back(d);
      }
    return out;
  }

  // Returns the RMS relative luminance error over the counted directions.
  // The reference's spectrum is converted to luminance with the CIE weights
  // of the working wavelengths (three, or the spectral set).
  double rms_error(const Observer& observer, double sun_elevation) const {
    const glm::dvec3 position = atmos::observer_position(atmosphere, observer.altitude_m);
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(200.0, sun_elevation);
    const std::vector<glm::dvec3> dirs = directions(observer.altitude_m, sun);
    const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(atmosphere.wavelengths_nm);
    auto luminance_of_spectrum = [&](const std::vector<double>& values) {
      glm::dvec3 rgb(0.0);
      for (size_t i = 0; i < values.size(); ++i) rgb += weights[i] * values[i];
      return atmos::srgb_luminance(rgb);
    };
    std::vector<double> table(dirs.size()), reference(dirs.size()), noise(dirs.size());
    atmos::ReferenceOptions options;
    // Twilight light comes from few, long paths: the reference needs more of
    // them for the same noise.
    options.paths = paths_from_environment() * (sun_elevation < 0.0 ? 8 : 1);
    options.scattering_orders = tables.scattering_orders;
    tbb::parallel_for(size_t(0), dirs.size(), [&](size_t i) {
      table[i] = atmos::srgb_luminance(model->to_srgb(model->radiance(position, dirs[i], sun, false)));
      atmos::ReferenceOptions o = options;
      o.seed = 1000 + i;
      const atmos::ReferenceResult r = atmos_test::oracle::reference_radiance(atmosphere, position, dirs[i], sun, o);
      reference[i] = luminance_of_spectrum(r.radiance);
      // The standard error of a weighted sum, with the (conservative)
      // assumption of fully correlated wavelengths.
      noise[i] = std::abs(luminance_of_spectrum(r.standard_error));
    });
    double brightest = 0.0;
    for (double v : reference) brightest = std::max(brightest, v);
    double sum_sq = 0.0, worst = 0.0, noise_sq = 0.0;
    int counted = 0;
    for (size_t i = 0; i < dirs.size(); ++i) {
      EXPECT_TRUE(std::isfinite(table[i]));
      if (reference[i] < 0.01 * brightest) continue;
      const double e = (table[i] - reference[i]) / reference[i];
      if (std::getenv("ATMOS_ACCURACY_VERBOSE")) {
        const double el = std::asin(dirs[i].z) * 180.0 / M_PI;
        const double az = std::atan2(dirs[i].x, dirs[i].y) * 180.0 / M_PI - 200.0;
        std::printf("    az-sun %7.1f el %6.1f  table %10.4g  reference %10.4g +- %.2f %%  error %+6.2f %%\n", az, el,
                    table[i], reference[i], 100.0 * noise[i] / reference[i], 100.0 * e);
      }
      sum_sq += e * e;
      noise_sq += (noise[i] / reference[i]) * (noise[i] / reference[i]);
      worst = std::max(worst, std::abs(e));
      ++counted;
    }
    const double rms = std::sqrt(sum_sq / std::max(counted, 1));
    std::printf("%-8s %2zu wavelengths, sun %+5.1f deg: RMS %5.2f %%  max %5.2f %%  (reference noise RMS %4.2f %%, %d of %zu directions)\n",
                observer.name, atmosphere.wavelengths_nm.size(), sun_elevation, 100.0 * rms, 100.0 * worst,
                100.0 * std::sqrt(noise_sq / std::max(counted, 1)), counted, dirs.size());
    std::fflush(stdout);
    // The bound the calling test asserts on this RMS: 3 % under the preset's
    // haze, 5 % for the dense atmosphere and with the sun below 5°, else 2 %.
    const std::string suite = ::testing::UnitTest::GetInstance()->current_test_info()->test_suite_name();
    const char* bound = suite == "HazyAccuracy"                             ? "RMS <= 3 %"
                        : suite == "DenseAccuracy" || sun_elevation < 5.0 ? "RMS <= 5 %"
                                                                            : "RMS <= 2 %";
    char config[64];
    std::snprintf(config, sizeof config, "%s, sun %+.1f deg", observer.name, sun_elevation);
    atmos_test::record_figure(std::string("RMS, ") + config, 100.0 * rms, "%", bound);
    atmos_test::record_figure(std::string("max, ") + config, 100.0 * worst, "%", "");
    atmos_test::record_figure(std::string("reference noise RMS, ") + config,
                              100.0 * std::sqrt(noise_sq / std::max(counted, 1)), "%", "");
    EXPECT_GE(counted, 10) << "too few directions above 1 % of the brightest";
    return rms;
  }
};

class Accuracy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { setup_ = new Measurement(clear_sky_earth()); }
  static void TearDownTestSuite() { delete setup_; }
  static double rms_error(const Observer& observer, double sun_elevation) {
    return setup_->rms_error(observer, sun_elevation);
  }
  static Measurement* setup_;
};

Measurement* Accuracy::setup_ = nullptr;


const Observer kObservers[] = {{"0 m", 0.0}, {"10 km", 10e3}, {"100 km", 100e3}, {"space", 1000e3}};

// A diagnostic, not a check: with --gtest_also_run_disabled_tests and
// ATMOS_ACCURACY_CASE="altitude_m,sun_elevation" it prints one configuration
// (every direction with ATMOS_ACCURACY_VERBOSE=1).
TEST_F(Accuracy, DISABLED_DiagnoseOneCase) {
  const char* spec = std::getenv("ATMOS_ACCURACY_CASE");
  ASSERT_NE(spec, nullptr) << "set ATMOS_ACCURACY_CASE=altitude_m,sun_elevation_deg";
  double altitude = 0.0, sun = 0.0;
  ASSERT_EQ(std::sscanf(spec, "%lf,%lf", &altitude, &sun), 2);
  rms_error(Observer{"case", altitude}, sun);
}

TEST_F(Accuracy, DaylightWithinTwoPercent) {
  for (const Observer& observer : kObservers)
    for (double sun : {5.0, 15.0, 35.0, 60.0, 90.0})
      EXPECT_LE(rms_error(observer, sun), 0.02) << observer.name << " " << sun;
}

TEST_F(Accuracy, TwilightSunAboveHorizonWithinFivePercent) {
  for (const Observer& observer : kObservers)
    for (double sun : {0.0, 2.5}) EXPECT_LE(rms_error(observer, sun), 0.05) << observer.name << " " << sun;
}

// With the sun below the horizon, the light reaching the low atmosphere comes
// through grazing paths whose transmittance switches on over a fraction of a
// degree of sun elevation. Two things make the tables meet the tolerance
// there: the transmittance to the sun is averaged over the solar disc near
// the horizon (transmittance_to_sun; the value at the disc's centre
// underestimates grazing sunlight by 20-30 %), and single scattering of rays
// where the sun is low is integrated along the ray with nodes placed by the
// integrand (scattering_along_ray) instead of read from the 4D table, whose
// linear interpolation between mu_s texels ~1° apart overestimates the onset
// by up to 60 %.
TEST_F(Accuracy, TwilightSunBelowHorizonWithinFivePercent) {
  for (const Observer& observer : kObservers)
    for (double sun : {-5.0, -2.5}) EXPECT_LE(rms_error(observer, sun), 0.05) << observer.name << " " << sun;
}

// The preset's continental haze (optical depth 0.15, Cornette-Shanks
// g 0.64): the tables are less accurate than on the clear sky above. Their
// multiple scattering towards the sun's azimuth near the horizon is low
// (view 0.5° up towards a sun 60° high: order 2 17-19 % low, the total
// -7 %): the linear nu axis of the 4D tables puts only 3 of its 8 samples in
// the range a grazing view can have, with the view towards the sun's azimuth
// at its edge (a parametrisation by the view's azimuth, Yusov 2013, would
// sample that range more densely). The RMS errors measured here lie between
// 1 and 2.5 %; bound 3 %.
TEST(HazyAccuracy, ContinentalHazeDaylightWithinThreePercent) {
  const Measurement m(atmos::load_atmosphere("earth"));
  for (double sun : {15.0, 60.0}) EXPECT_LE(m.rms_error(kObservers[0], sun), 0.03) << "0 m " << sun;
  for (double sun : {5.0, 15.0}) EXPECT_LE(m.rms_error(kObservers[3], sun), 0.03) << "space " << sun;
}

// The same tolerances in spectral mode: 15 wavelengths over
// 360-830 nm, the tables converted to sRGB, the reference computed at all 15
// wavelengths and converted with the same CIE weights. A spread of the
// configurations above (the reference costs 2-3x more per direction here).
class SpectralAccuracy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    atmos::Atmosphere earth = clear_sky_earth();
    earth.wavelengths_nm = atmos::spectral_wavelengths(15);
    setup_ = new Measurement(earth);
  }
  static void TearDownTestSuite() { delete setup_; }
  static Measurement* setup_;
};

Measurement* SpectralAccuracy::setup_ = nullptr;

TEST_F(SpectralAccuracy, DaylightWithinTwoPercent) {
  EXPECT_LE(setup_->rms_error(kObservers[0], 60.0), 0.02);
  EXPECT_LE(setup_->rms_error(kObservers[0], 5.0), 0.02);
  EXPECT_LE(setup_->rms_error(kObservers[3], 15.0), 0.02);
}

TEST_F(SpectralAccuracy, TwilightWithinFivePercent) {
  EXPECT_LE(setup_->rms_error(kObservers[1], 0.0), 0.05);
  EXPECT_LE(setup_->rms_error(kObservers[0], -2.5), 0.05);
  EXPECT_LE(setup_->rms_error(kObservers[2], -5.0), 0.05);
}

// A dense atmosphere (Elek & Kmoch 2010, Fig. 4): 10x Earth, auto orders
// (the reference gets the same count). Many orders and
// optically thick rays: the quadrature follows the visible extinction
// (extinction_ray_map). Tolerance 5 % RMS in daylight (measured: see the
// printout; individual directions near the horizon are lowest, where the
// tables underestimate by a few per cent).
TEST(DenseAccuracy, TenTimesEarthWithinFivePercent) {
  atmos::Atmosphere dense = clear_sky_earth();
  atmos::scale_density(dense, 10.0);
  atmos::PrecomputeOptions options;
  options.auto_orders = true;
  options.scattering_orders = 64;
  const Measurement m(dense, options);
  EXPECT_LE(m.rms_error(kObservers[0], 30.0), 0.05);
  EXPECT_LE(m.rms_error(kObservers[1], 10.0), 0.05);
}

// The sky over a dark (0.05, sea) and a bright (0.8, fresh snow) ground
// from the tables of the preset's albedo 0.1 moved to that albedo at run
// time (tables_for_ground_albedo), against the reference run over that
// ground: the same 2 % RMS as the tables precomputed for their albedo
// (Accuracy above), and the sky light on the ground within 2 % of the
// reference's (its standard error is about 0.5 % of it).
class GroundAlbedoAccuracy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    atmos::PrecomputeOptions options;
    options.ground_albedo_response = true;
    const char* cache = std::getenv("ATMOS_CACHE_DIR");
    tables_ = new atmos::Tables(cache ? atmos::load_or_precompute_tables(clear_sky_earth(), options, cache).tables
                                      : atmos::precompute_tables(clear_sky_earth(), options));
  }
  static void TearDownTestSuite() { delete tables_; }

  static void check(double albedo) {
    atmos::Atmosphere ground = clear_sky_earth();
    ground.ground_albedo = atmos::Spectrum::constant(albedo);
    atmos::Tables t = *tables_;
    t.set = atmos::tables_for_ground_albedo(*tables_, glm::vec3(float(albedo)));
    t.ground_response = atmos::GroundAlbedoResponse();
    const Measurement m(ground, std::move(t));
    for (const Observer& observer : {kObservers[0], kObservers[1]})
      for (double sun : {15.0, 60.0}) EXPECT_LE(m.rms_error(observer, sun), 0.02) << observer.name << " " << sun;

    // The sky light on the ground, 550 nm (the reference at 549.5-550.5 nm).
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(200.0, 35.0);
    glm::dvec3 tables_sun, tables_sky;
    m.model->horizontal_irradiance(atmos::observer_position(ground, 0.0), sun, tables_sun, tables_sky);
    atmos::Atmosphere narrow = ground;
    narrow.wavelengths_nm = {549.5, 550.0, 550.5};
    atmos::ReferenceOptions o;
    o.paths = 4 * paths_from_environment();
    o.scattering_orders = m.tables.scattering_orders;
    const atmos::ReferenceResult r = atmos_test::oracle::reference_horizontal_irradiance(
        narrow, atmos::observer_position(narrow, 0.0), sun, o);
    // The sky's part: the reference's sun and sky less the tables' direct
    // sun (the attenuated disc, which does not depend on the ground and
    // which the transmittance tests check).
    const double reference_sky = r.radiance[1] - tables_sun[1];
    const double error = tables_sky[1] / reference_sky - 1.0;
    std::printf("ground albedo %.2f: sky light on the ground at 550 nm %.4g (tables), %.4g +- %.2g (reference): "
                "%+.2f %%\n",
                albedo, tables_sky[1], reference_sky, r.standard_error[1], 100.0 * error);
    char config[64];
    std::snprintf(config, sizeof config, "ground albedo %.2f, sun 35 deg", albedo);
    atmos_test::record_figure(std::string("sky irradiance error, ") + config, 100.0 * error, "%", "|e| <= 2 %");
    EXPECT_LE(std::abs(error), 0.02);
  }
  static inline atmos::Tables* tables_ = nullptr;
};

TEST_F(GroundAlbedoAccuracy, DarkGroundWithinTwoPercent) { check(0.05); }
TEST_F(GroundAlbedoAccuracy, BrightGroundWithinTwoPercent) { check(0.8); }

}  // namespace
