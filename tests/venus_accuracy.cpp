// Venus, the tables against the references: the light on the ground and
// reflected to space (Monte Carlo and plane-parallel references), the
// planet's spherical albedo, and the ground seen from a camera just above it.
//
// Both references put about 5 % of the sunlight at 550 nm on the preset's
// ground with the sun 40° up, where the measurements give 1.5-2.6 %
// (docs/preset-sources.md §1.2.3: Venera 8, Pioneer Venus; Titov et al.
// 2007). Those are broadband (0.4-1.0 µm and beyond, where the near-infrared
// bands of CO2 and H2O absorb and the preset does not), so this is not a
// like-for-like check; it is a question for the preset, not for the tables.
// The tables are compared with the references.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "atmos/planet_file.hpp"
#include "reference/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "support/reference_store.hpp"
#include "physics/quadrature.hpp"
#include "figures.hpp"
#include "upward_flux.hpp"

namespace {

// Default sizes (256 x 64 transmittance, 8 x 32 x 128 x 32 scattering),
// orders until converged, up to 64, then the solved tail.
atmos::PrecomputeOptions venus_options() {
  atmos::PrecomputeOptions options;
  options.auto_orders = true;
  options.scattering_orders = 64;
  return options;
}

// The tables of `options`, through the cache of $ATMOS_CACHE_DIR if it is
// set (the test command sets it: the tests of this file share one Venus).
atmos::Tables venus_tables(const atmos::Atmosphere& venus, const atmos::PrecomputeOptions& options) {
  const char* cache = std::getenv("ATMOS_CACHE_DIR");
  return cache ? atmos::load_or_precompute_tables(venus, options, cache).tables
               : atmos::precompute_tables(venus, options);
}

// The tables (default sizes, auto orders and the solved tail) against the
// Monte Carlo reference: the light on the ground (550 nm with the sun 40° and
// 70° up, 680 nm at 40°) and the light reflected to space (the upward flux at
// 99 km, 550 nm, sun 40° up). The reference runs K = 2000 interactions
// (runs with K = 1000 and 4000 agree with it within their noise) and 16000
// paths on the ground, where different seeds scatter by ~5 % at 550 nm and
// ~4 % at 680 nm, as their stated errors say; the seed is fixed, so the
// bounds catch regressions around the measured ratios (0.92-0.98 on the
// ground, 0.98 reflected).
// Tolerances: the ground within [0.85, 1.15] of the reference, [0.93, 1.15]
// at 680 nm; the reflected light within [0.93, 1.07].
TEST(VenusAccuracy, GroundLightAgainstTheReference) {
  const atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  const atmos::Tables t = venus_tables(venus, venus_options());
  const atmos::SkyModel model(venus, t);

  // The light on the ground, as a fraction of the sunlight on a horizontal
  // surface at the top, for one channel of the tables and the sun at
  // `elevation`, against the reference at that channel's wavelength (and
  // 0.5 nm either side: it needs three wavelengths, and mixing 440 and
  // 680 nm into its paths would multiply its variance).
  atmos::ReferenceOptions reference_options;
  reference_options.scattering_orders = 2000;
  reference_options.paths = 16000;
  auto ground_light = [&](const atmos::SkyModel& m, int channel, const glm::dvec3& sun) {
    glm::dvec3 ground_sun, ground_sky, top_sun, top_sky;
    m.horizontal_irradiance(atmos::observer_position(venus, 2.0), sun, ground_sun, ground_sky);
    m.horizontal_irradiance(atmos::observer_position(venus, 99e3), sun, top_sun, top_sky);
    return (ground_sun[channel] + ground_sky[channel]) / top_sun[channel];
  };
  auto check_ground = [&](int channel, double elevation, double low, double high) {
    const double nm = venus.wavelengths_nm[size_t(channel)];
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, elevation);
    const double tables = ground_light(model, channel, sun);
    atmos::Atmosphere narrow = venus;
    narrow.wavelengths_nm = {nm - 0.5, nm, nm + 0.5};
    const atmos::ReferenceResult reference = atmos_test::oracle::reference_horizontal_irradiance(
        narrow, atmos::observer_position(narrow, 0.0), sun, reference_options);
    const double in = narrow.solar_irradiance.at(nm) * std::sin(elevation * M_PI / 180.0);
    const double truth = reference.radiance[1] / in;
    std::printf("venus, %g nm, sun %g deg: ground / top %.3e (tables), %.3e +- %.1e (reference): %.3f\n", nm,
                elevation, tables, truth, reference.standard_error[1] / in, tables / truth);
    char config[64];
    std::snprintf(config, sizeof config, "%g nm, sun %g deg", nm, elevation);
    char bound[64];
    std::snprintf(bound, sizeof bound, "[%g, %g]", low, high);
    atmos_test::record_figure(std::string("ground light / sunlight, reference, ") + config, truth, "", "");
    atmos_test::record_figure(std::string("ground light / sunlight, reference standard error, ") + config,
                              reference.standard_error[1] / in, "", "");
    atmos_test::record_figure(std::string("ground light, tables / reference, ") + config, tables / truth, "",
                              bound);
    EXPECT_GT(tables, low * truth) << nm << " nm, sun " << elevation;
    EXPECT_LT(tables, high * truth) << nm << " nm, sun " << elevation;
  };
  check_ground(1, 40.0, 0.85, 1.15);
  check_ground(1, 70.0, 0.85, 1.15);
  check_ground(0, 40.0, 0.93, 1.15);

  // The light going up at 99 km (32 x 24 directions), 550 nm, sun 40° up.
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, 40.0);
  glm::dvec3 top_sun, top_sky;
  model.horizontal_irradiance(atmos::observer_position(venus, 99e3), sun, top_sun, top_sky);
  const glm::dvec3 top = atmos::observer_position(venus, 99e3);
  const double tables_up = atmos_test::upward_flux(model, top, sun, 32, 24).y / top_sun.y;
  atmos::Atmosphere green = venus;
  green.wavelengths_nm = {549.5, 550.0, 550.5};
  reference_options.paths = 4000;
  const atmos::ReferenceResult up = atmos_test::oracle::reference_irradiance(green, top, glm::dvec3(0.0, 0.0, -1.0), sun,
                                                                reference_options);
  const double in = green.solar_irradiance.at(550.0) * std::sin(40.0 * M_PI / 180.0);
  const double truth_up = up.radiance[1] / in;
  std::printf("venus, 550 nm, sun 40 deg: reflected / in %.3f (tables), %.3f +- %.3f (reference): %.3f\n",
              tables_up, truth_up, up.standard_error[1] / in, tables_up / truth_up);
  atmos_test::record_figure("reflected / sunlight, reference, 550 nm, sun 40 deg", truth_up, "", "");
  atmos_test::record_figure("reflected, tables / reference, 550 nm, sun 40 deg", tables_up / truth_up, "",
                            "[0.93, 1.07]");
  EXPECT_GT(tables_up, 0.93 * truth_up);
  EXPECT_LT(tables_up, 1.07 * truth_up);
}

// The same tables against the plane-parallel reference
// (reference_plane_parallel_fluxes: adding-doubling, deterministic, exact
// to ~1e-4 in its quadratures), every channel, the sun 40° and 70° up:
//  - the light on the ground (sun and sky), as a fraction of the sunlight
//    on a horizontal surface at the top;
//  - the azimuthal mean of the radiance leaving the top straight down (the
//    Gauss direction nearest the nadir), which the planet's curvature does
//    not change;
//  - the flux leaving the top (1 m below it). The plane-parallel slab
//    overestimates this one by ~1-2 %: from the top of a sphere the
//    directions within ~6-10° below the horizontal look through the limb
//    into space, not into the cloud (on the Earth preset the Monte Carlo
//    reference gives 0.977 of its upward flux, against 0.999 of its light
//    on the ground).
// The reference agrees with the Monte Carlo reference within the latter's
// noise here (ground at 550 nm, sun 40°: 4.83e-2 against the mean 5.08e-2
// +- 2.5 % of four seeds; 680 nm 7.95e-2 against 7.77e-2; reflected 0.912
// against 0.906 +- 2 %) and on a slab solved both ways (reference_test.cpp,
// PlaneParallelReference).
// The tables' ground light is not converged in the radius texels: with 24 /
// 48 / 64 / 128 of them instead of the default 32 it is 1.16 / 1.09 / 1.06 /
// 1.02 of the reference at 680 nm (sun 40°), moving with where the rows fall
// in the cloud; 32 is a favourable count, not a converged one. At 440 nm an
// excess of ~7 % remains with 64 and 128 texels, on Venus's air alone too
// (where the Monte Carlo reference agrees with this one within its 4.5 %).
// Part of it is the mu_s axis (Bruneton & Neyret 2008's mapping gives the
// sun between 40° and 90° up 2.1 of the 32 texels: 64 texels take the air
// alone from 1.073 to 1.055); the rest is not explained.
// Tolerances: the ground within [0.92, 1.08] at 680 and 550 nm and [0.92,
// 1.15] at 440 nm (42 optical depths of air: the rows near the ground are
// 2-6 of them apart there); the nadir radiance within 3 %; the flux within
// [0.96, 1.03].
TEST(VenusAccuracy, FluxesAgainstThePlaneParallelReference) {
  const atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  const atmos::Tables t = venus_tables(venus, venus_options());
  const atmos::SkyModel model(venus, t);
  const glm::dvec3 top = atmos::observer_position(venus, venus.top_radius_m - venus.bottom_radius_m - 1.0);
  const glm::dvec3 ground = atmos::observer_position(venus, 2.0);
  for (double elevation : {40.0, 70.0}) {
    const double mu_s = std::sin(elevation * M_PI / 180.0);
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, elevation);
    const atmos::PlaneParallelFluxes pp = atmos_test::oracle::reference_plane_parallel_fluxes(venus, mu_s);
    glm::dvec3 ground_sun, ground_sky;
    model.horizontal_irradiance(ground, sun, ground_sun, ground_sky);
    const glm::dvec3 up = atmos_test::upward_flux(model, top, sun, 64, 24);
    // The Gauss direction nearest the nadir, and the tables' azimuthal mean there.
    const size_t i = pp.mu.size() - 1;
    const double mu = pp.mu[i], s = std::sqrt(1.0 - mu * mu);
    glm::dvec3 nadir(0.0);
    constexpr int kAzimuths = 48;
    for (int k = 0; k < kAzimuths; ++k) {
      const double phi = (k + 0.5) * 2.0 * M_PI / kAzimuths;
      nadir += model.radiance(top, glm::dvec3(s * std::cos(phi), s * std::sin(phi), -mu), sun, false) / double(kAzimuths);
    }
    for (size_t c = 0; c < 3; ++c) {
      const double nm = venus.wavelengths_nm[c];
      const double in = venus.solar_irradiance.at(nm) * mu_s;
      const double ground_ratio =
          (ground_sun[int(c)] + ground_sky[int(c)]) / (pp.ground_direct[c] + pp.ground_diffuse[c]);
      const double nadir_ratio = nadir[int(c)] / pp.upward_radiance_top[c][i];
      const double flux_ratio = up[int(c)] / pp.upward_top[c];
      std::printf("venus, %g nm, sun %g deg, against the plane-parallel reference: ground %.3e of the sunlight "
                  "(%.3f), nadir radiance (%.3f), reflected %.3f (%.3f)\n",
                  nm, elevation, (ground_sun[int(c)] + ground_sky[int(c)]) / in, ground_ratio, nadir_ratio,
                  up[int(c)] / in, flux_ratio);
      char config[64];
      std::snprintf(config, sizeof config, "%g nm, sun %g deg", nm, elevation);
      atmos_test::record_figure(std::string("ground light / sunlight, tables, ") + config,
                                (ground_sun[int(c)] + ground_sky[int(c)]) / in, "", "");
      atmos_test::record_figure(std::string("ground light, tables / reference, ") + config, ground_ratio, "",
                                c == 2 ? "[0.92, 1.15]" : "[0.92, 1.08]");
      atmos_test::record_figure(std::string("nadir radiance, tables / reference, ") + config, nadir_ratio, "",
                                "[0.97, 1.03]");
      atmos_test::record_figure(std::string("reflected flux, tables / reference, ") + config, flux_ratio, "",
                                "[0.96, 1.03]");
      EXPECT_GT(ground_ratio, 0.92) << nm << " nm, sun " << elevation;
      EXPECT_LT(ground_ratio, c == 2 ? 1.15 : 1.08) << nm << " nm, sun " << elevation;
      EXPECT_NEAR(nadir_ratio, 1.0, 0.03) << nm << " nm, sun " << elevation;
      EXPECT_GT(flux_ratio, 0.96) << nm << " nm, sun " << elevation;
      EXPECT_LT(flux_ratio, 1.03) << nm << " nm, sun " << elevation;
    }
  }
}

// The ground seen from a camera 2 m above Venus's ground, 90° from the sun
// (40° up), 550 nm: the ground 100 m and 4 km away (its horizon is 4.9 km
// away) and the sky 0.5° above the horizon, against the reference (K = 2000,
// 8000 paths, ~9 % noise). One optical depth near the ground is a few
// kilometres, so the ground fades into the haze towards its horizon: the
// reference's ground is 3.3 times brighter 4 km away than 100 m away, and
// about as bright as the sky just above the horizon.
// Such rays end below the tables' second radius row (330 m up on Venus). In
// optically thick atmospheres their in-scattered light is read from that
// row's ray of the same length, scaled by the change of the light between
// the ground and the row that the rows' grazing rays show
// (ray_scattering_lookup in table_lookups.glsl); interpolating between the bottom
// row, where such rays have no length, and that row would darken the ground
// towards its horizon instead (to 0.13 of the reference 4 km away).
// Tolerances: the ground 4 km away at least twice as bright as 100 m away
// and within [0.75, 1.2] of the sky; both against the reference within
// [0.9, 1.5]. The ground 4 km away is measured at ~0.91 of the reference,
// within its noise; the seed is fixed, so the lower bound catches a further
// loss of light near the ground.
TEST(VenusAccuracy, GroundSeenFromLowCameras) {
  const atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  const atmos::Tables tables = venus_tables(venus, venus_options());
  const atmos::SkyModel model(venus, tables);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, 40.0);
  const glm::dvec3 camera = atmos::observer_position(venus, 2.0);
  atmos::Atmosphere green = venus;
  green.wavelengths_nm = {549.5, 550.0, 550.5};
  atmos::ReferenceOptions reference_options;
  reference_options.scattering_orders = 2000;
  reference_options.paths = 8000;
  const double e_sun = green.solar_irradiance.at(550.0);
  // The elevation (deg) of the view ray that meets the ground d metres away.
  const double r = venus.bottom_radius_m + 2.0, rb = venus.bottom_radius_m;
  auto elevation_of_ground = [&](double d) {
    return std::asin((rb * rb - r * r - d * d) / (2.0 * r * d)) * 180.0 / M_PI;
  };
  struct View {
    const char* name;
    double elevation;
    bool reference;
  };
  const View views[] = {{"ground 100 m away", elevation_of_ground(100.0), false},
                        {"ground 4 km away", elevation_of_ground(4000.0), true},
                        {"sky 0.5 deg up", 0.5, true}};
  double table_values[3], reference_values[3] = {0.0, 0.0, 0.0};
  for (int i = 0; i < 3; ++i) {
    const glm::dvec3 view = atmos::direction_from_azimuth_elevation(90.0, views[i].elevation);
    table_values[i] = model.radiance(camera, view, sun, false).y / e_sun;
    ASSERT_TRUE(std::isfinite(table_values[i]) && table_values[i] > 0.0) << views[i].name;
    std::printf("venus, 2 m up, %s (elevation %.4f deg): tables %.3e of the sunlight", views[i].name,
                views[i].elevation, table_values[i]);
    if (views[i].reference) {
      const atmos::ReferenceResult ref = atmos_test::oracle::reference_radiance(green, camera, view, sun, reference_options);
      reference_values[i] = ref.radiance[1] / e_sun;
      std::printf(", reference %.3e +- %.1e: %.3f", reference_values[i], ref.standard_error[1] / e_sun,
                  table_values[i] / reference_values[i]);
      atmos_test::record_figure(std::string("tables / reference, ") + views[i].name,
                                table_values[i] / reference_values[i], "", "[0.9, 1.5]");
      atmos_test::record_figure(std::string("reference standard error, ") + views[i].name,
                                ref.standard_error[1] / ref.radiance[1], "", "");
    }
    std::printf("\n");
  }
  // The ground brightens into the haze, up to the sky's radiance.
  EXPECT_GT(table_values[1], 2.0 * table_values[0]);
  EXPECT_GT(table_values[1], 0.75 * table_values[2]);
  EXPECT_LT(table_values[1], 1.2 * table_values[2]);
  for (int i : {1, 2}) {
    EXPECT_GT(table_values[i], 0.9 * reference_values[i]) << views[i].name;
    EXPECT_LT(table_values[i], 1.5 * reference_values[i]) << views[i].name;
  }
}

// The preset's cloud single-scattering albedo is fitted (data/planets/
// venus.json, docs/preset-sources.md 1.2.4) so that the plane-parallel
// reference gives Venus's measured spherical albedos: 0.90 in V (Mallama,
// Wang & Howard 2006) and 0.781 in B (from B-V = 0.81 against the Sun's
// 0.656), taken at 550 and 440 nm. This checks the fit (the reference within
// 0.005 of both: it fails if the preset's cloud, air or ground change
// without a new fit) and how bright the tables make the planet: their
// spherical albedo, from the flux leaving the top 1 m below it over the same
// 8 sun zenith cosines, 2 ∫ A(mu_s) mu_s dmu_s with A the plane albedo.
// Tolerances: the reference within 0.005 of the measured values, the tables
// within 5 % of them.
TEST(VenusAccuracy, SphericalAlbedoIsTheMeasuredOne) {
  const atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  // The channels below are the preset's working wavelengths: R, V, B.
  ASSERT_EQ(venus.wavelengths_nm, (std::vector<double>{680.0, 550.0, 440.0}));
  const atmos::Tables t = venus_tables(venus, venus_options());
  const atmos::SkyModel model(venus, t);
  std::vector<double> mu_s, weight;
  atmos::physics::gauss_legendre(8, 0.0, 1.0, mu_s, weight);
  const glm::dvec3 top = atmos::observer_position(venus, venus.top_radius_m - venus.bottom_radius_m - 1.0);
  glm::dvec3 reference(0.0), tables(0.0);
  for (size_t k = 0; k < mu_s.size(); ++k) {
    const atmos::PlaneParallelFluxes pp = atmos_test::oracle::reference_plane_parallel_fluxes(venus, mu_s[k]);
    const glm::dvec3 sun(std::sqrt(1.0 - mu_s[k] * mu_s[k]), 0.0, mu_s[k]);
    const glm::dvec3 up = atmos_test::upward_flux(model, top, sun, 64, 24);
    for (int c = 0; c < 3; ++c) {
      const double e_sun = venus.solar_irradiance.at(venus.wavelengths_nm[size_t(c)]);
      // upward / e_sun = A(mu_s) mu_s.
      reference[c] += 2.0 * weight[k] * pp.upward_top[size_t(c)] / e_sun;
      tables[c] += 2.0 * weight[k] * up[c] / e_sun;
    }
  }
  const double measured[3] = {0.0, 0.90, 0.90 * std::pow(10.0, -0.4 * (0.81 - 0.656))};
  for (int c = 0; c < 3; ++c) {
    std::printf("venus, %g nm: spherical albedo %.4f (plane-parallel reference), %.4f (tables, %.3f of it)",
                venus.wavelengths_nm[size_t(c)], reference[c], tables[c], tables[c] / reference[c]);
    if (c > 0) std::printf(", measured %.3f", measured[c]);
    std::printf("\n");
    char nm[32];
    std::snprintf(nm, sizeof nm, "%g nm", venus.wavelengths_nm[size_t(c)]);
    atmos_test::record_figure(std::string("spherical albedo, reference, ") + nm, reference[c], "",
                              c > 0 ? "measured +- 0.005" : "");
    atmos_test::record_figure(std::string("spherical albedo, tables, ") + nm, tables[c], "",
                              c > 0 ? "measured +- 5 %" : "");
    if (c > 0) atmos_test::record_figure(std::string("spherical albedo, measured, ") + nm, measured[c], "", "");
    if (c == 0) continue;
    EXPECT_NEAR(reference[c], measured[c], 0.005) << venus.wavelengths_nm[size_t(c)] << " nm";
    EXPECT_NEAR(tables[c] / measured[c], 1.0, 0.05) << venus.wavelengths_nm[size_t(c)] << " nm";
  }
}

}  // namespace
