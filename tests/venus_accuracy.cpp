// The light on the ground of Venus, tables against the brute-force reference.
//
// docs/preset-sources.md 1.2.3 gives 1.5-2.6 % of the sunlight on the ground
// (Venera 8, Pioneer Venus, Titov et al. 2007). The reference itself, on the
// preset, gives more: 5.1 % at 550 nm with the sun 40° up before the cloud's
// single-scattering albedo was fitted to Venus's measured spherical albedo
// (K = 2000 interactions, which runs at K = 1000 and 4000 found converged
// within their 12 % noise; the mean of four seeds of 16000 paths), 5.05 %
// (this test's run) after it (0.99933 at 550 nm instead of the placeholder
// 0.9995; docs/preset-sources.md 1.2.4, SphericalAlbedoIsTheMeasuredOne
// below). So the preset reflects what Venus reflects in V and B, and still
// puts twice the measured light on its ground; those measurements are
// broadband (0.4-1.0 um and more), where the near-infrared bands of CO2 and
// H2O absorb and the preset does not (UNVERIFIED as the whole explanation).
// That is a question for the preset, not for the tables. The tables are
// compared with the reference.
//
// The tables (default sizes, auto orders and the solved tail) against the
// reference, on the ground (550 nm with the sun 40° and 70° up, 680 nm at
// 40°) and for the light reflected to space (the upward flux at 99 km,
// 550 nm, sun 40° up). Measured 2026-11-27, with the cloud albedo fitted
// (it absorbs a little more than the placeholder), this test's reference
// run: ground 550 nm, sun 40°, 4.63e-2 of the sunlight, 0.92 of 5.05e-2
// (+- 5 %); sun 70°, 5.67e-2, 0.96 of 5.91e-2; 680 nm, 7.32e-2, 0.98 of
// 7.43e-2; reflected 0.887, 0.98 of 0.908 (balanced orders: 4.60e-2,
// 5.62e-2, 7.26e-2, 0.877). The figures below are from before the fit.
// Measured (2026-11-26, since the source function is
// read between radius rows with cubic weights, functions.glsl
// source_function_lookup), this test's reference runs first, then the mean
// of 3-4 seeds (16000 paths each; 8000, 4000 and 1000 for the reflected
// light):
//  - ground, 550 nm, sun 40°: 4.86e-2 of the sunlight; 0.92 of 5.27e-2
//    (+- 5 %), 0.96 of the mean 5.08e-2 (1.007 of the plane-parallel
//    reference's 4.83e-2, FluxesAgainstThePlaneParallelReference below);
//  - ground, 550 nm, sun 70°: 5.94e-2; 0.96 of 6.20e-2, 0.97 of 6.15e-2;
//  - ground, 680 nm, sun 40°: 7.63e-2; 0.98 of 7.75e-2, 0.98 of 7.77e-2;
//  - reflected to space: 0.898; 0.98 of 0.920 (+- 2 %), 0.99 of 0.906.
// Before the cubic weights (2026-11-24): 4.98e-2, 5.99e-2, 7.55e-2 and
// 0.813 (0.90 of the mean: the linear interpolation between radius rows a
// few optical depths apart lost a little of every order).
// Before the multiple scattering's nodes were uniform in optical depth over
// the first optical depths of each view ray (functions.glsl,
// source_integration_nodes): 5.07e-2, 6.10e-2, 7.14e-2 (0.92 of the mean at
// 680 nm) and 0.814.
// With 16000 paths the seeds scatter as their stated errors say (at 680 nm
// 7.39e-2 to 8.10e-2, +- 3.0e-3 each). This test used to run 2000 paths:
// that run gave 6.3e-2 at 550 nm, 1.24 of the mean (1.6 of its stated
// sigma), which made the old tables look right there and wrong in the red.
// History (default sizes):
//  - Before the mu axis of optically thick atmospheres was warped towards
//    log-spaced distances (functions.glsl scattering_u_mu): ground 3.5e-2,
//    reflected 0.714. Inside the cloud, the axis linear in the distance to
//    the top gave the whole upper hemisphere of a point 65 km up 1-2 of its
//    128 texels, and the tables lost a fifth of the light at the cloud top.
//  - With the warp and 32 intervals on the multiple scattering's view rays
//    (multiple_scattering_intervals) but Bruneton's r axis: ground 6.1e-2,
//    7.0e-2 and 9.3e-2 (1.20, 1.14 and 1.19 of the means), reflected 0.842
//    (0.93). That excess shrank with more radius texels (680 nm: 8.5e-2 with
//    64, 8.2e-2 with 128): Bruneton's r axis gives the cloud deck 8 of its 32
//    texels. The r axis of thick atmospheres now also follows the optical
//    depth (functions.glsl scattering_x_r_from_rho_fraction: 14 texels in
//    the cloud), which removed the excess but costs the reflected light 3 %
//    (parameters.hpp kScatteringROpticalDepthShare).
//  - Before the warp the tables' ground light also depended too much on the
//    sun: 3.3 times more at 70° than at 40°, against 1.2 now and 1.2 for the
//    reference.
// With the energy balance of the orders (PrecomputeOptions::balance_orders,
// src/precompute/energy_balance.cpp), made for the light the linear
// interpolation lost: on 2026-11-24 it raised the reflected light from 0.90
// to 0.93 of the reference but put 1.05-1.06 of it on the ground. With the
// cubic weights the orders nearly keep their light already, and the balance
// now lowers everything (2026-11-26, this test's references): ground
// 4.74e-2, 5.79e-2 and 7.42e-2 (0.90, 0.93 and 0.96), reflected 0.882
// (0.96). It stays off by default; its tolerances: the ground within [0.85,
// 1.15] of the reference, the reflected light below 1.1 of it.
// Tolerances: the ground within [0.85, 1.15] of the reference, [0.93, 1.15]
// at 680 nm (its scatter between seeds is ~4 %; the seed is fixed, so these
// bound regressions around the measurements; the old nodes gave 0.92 at
// 680 nm), the reflected light within [0.93, 1.07] (it was 0.88 of this
// run's reference before the cubic weights).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "atmos/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "physics/quadrature.hpp"
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

TEST(VenusAccuracy, GroundLightAgainstTheReference) {
  const atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  atmos::PrecomputeOptions options = venus_options();
  const atmos::Tables t = venus_tables(venus, options);
  const atmos::SkyModel model(venus, t);
  // The same with the energy balance of the orders (experimental, off by
  // default: PrecomputeOptions::balance_orders).
  options.balance_orders = true;
  const atmos::Tables balanced_tables = atmos::precompute_tables(venus, options);
  const atmos::SkyModel balanced(venus, balanced_tables);

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
    const double tables = ground_light(model, channel, sun), with_balance = ground_light(balanced, channel, sun);
    atmos::Atmosphere narrow = venus;
    narrow.wavelengths_nm = {nm - 0.5, nm, nm + 0.5};
    const atmos::ReferenceResult reference = atmos::reference_horizontal_irradiance(
        narrow, atmos::observer_position(narrow, 0.0), sun, reference_options);
    const double in = narrow.solar_irradiance.at(nm) * std::sin(elevation * M_PI / 180.0);
    const double truth = reference.radiance[1] / in;
    std::printf("venus, %g nm, sun %g deg: ground / top %.3e (tables), %.3e (balanced orders), %.3e +- %.1e "
                "(reference): %.3f, %.3f\n",
                nm, elevation, tables, with_balance, truth, reference.standard_error[1] / in, tables / truth,
                with_balance / truth);
    EXPECT_GT(tables, low * truth) << nm << " nm, sun " << elevation;
    EXPECT_LT(tables, high * truth) << nm << " nm, sun " << elevation;
    EXPECT_GT(with_balance, 0.85 * truth) << nm << " nm, sun " << elevation;
    EXPECT_LT(with_balance, 1.15 * truth) << nm << " nm, sun " << elevation;
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
  const double balanced_up = atmos_test::upward_flux(balanced, top, sun, 32, 24).y / top_sun.y;
  atmos::Atmosphere green = venus;
  green.wavelengths_nm = {549.5, 550.0, 550.5};
  reference_options.paths = 4000;
  const atmos::ReferenceResult up = atmos::reference_irradiance(green, top, glm::dvec3(0.0, 0.0, -1.0), sun,
                                                                reference_options);
  const double in = green.solar_irradiance.at(550.0) * std::sin(40.0 * M_PI / 180.0);
  const double truth_up = up.radiance[1] / in;
  std::printf("venus, 550 nm, sun 40 deg: reflected / in %.3f (tables), %.3f (balanced orders), %.3f +- %.3f "
              "(reference): %.3f, %.3f\n",
              tables_up, balanced_up, truth_up, up.standard_error[1] / in, tables_up / truth_up,
              balanced_up / truth_up);
  EXPECT_GT(tables_up, 0.93 * truth_up);
  EXPECT_LT(tables_up, 1.07 * truth_up);
  EXPECT_LT(balanced_up, 1.1 * truth_up);
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
// The reference itself agrees with the Monte Carlo reference within the
// latter's noise here (ground at 550 nm, sun 40°: 4.83e-2 against the mean
// 5.08e-2 +- 2.5 % of four seeds; 680 nm 7.95e-2 against 7.77e-2; reflected
// 0.912 against 0.906 +- 2 %) and on a slab solved both ways
// (reference_test.cpp, PlaneParallelReference).
// Measured (2026-11-27, default sizes, the cloud albedo fitted to Venus's
// spherical albedo), tables / reference at 680 / 550 / 440 nm:
//  - sun 40°: ground 0.961 / 1.010 / 1.120, nadir radiance 0.991 / 0.992 /
//    0.987, flux 0.981 / 0.983 / 0.977;
//  - sun 70°: ground 0.957 / 0.995 / 1.090, nadir radiance 1.013 / 1.012 /
//    1.007, flux 1.003 / 1.004 / 0.997.
// (With the placeholder albedo, 2026-11-26: sun 40° ground 0.956 / 1.003 /
// 1.102, sun 70° 0.955 / 0.992 / 1.076; the rest within 0.003. The
// experiments below are from before the fit.)
// Before the source function was interpolated with cubic weights between
// radius rows (functions.glsl source_function_lookup): sun 40° ground
// 0.949 / 1.033 / 1.552, nadir radiance 0.904 / 0.903 / 0.908, flux 0.890 /
// 0.890 / 0.892.
// Not converged in the radius texels (measured outside the tests, sun 40°,
// ground and flux at 680 / 550 / 440 nm): 24 texels 1.157 / 1.145 / 1.138
// and 1.010 / 1.014 / 1.002; 48: 1.085 / 1.077 / 1.083 and 0.944 / 0.944 /
// 0.942; 64: 1.064 / 1.066 / 1.094; 128: 1.021 / 1.042 / 1.116 and 0.981 /
// 0.981 / 0.981. The default 32 is a favourable count, not a converged one.
// Venus's air alone (no cloud), ground at 680 / 550 / 440 nm: 32 texels
// 1.011 / 1.037 / 1.146, 48 texels 1.010 / 1.030 / 1.109, 64 texels 1.010 /
// 1.024 / 1.073, 128 texels 1.011 / 1.026 / 1.072: it falls with the row
// spacing up to 64 texels and then stays ~7 % high in the blue (the Monte
// Carlo reference, K = 4000, 16000 paths, on the air alone: 1.017 +- 0.045
// of the plane-parallel reference at 440 nm, 1.015 +- 0.027 at 550 nm).
// At 440 nm with 32 texels: 256 mu texels 1.161, 64 view ray
// intervals 1.160; each row read at its own mu, or no floor under the
// cubic: unchanged; a smooth optical-depth coordinate for the cubic 1.181;
// the first interval's ground-facing nodes extrapolated from rows 1-2
// 1.130. The whole Venus over a black ground: the same ratios as over its
// 0.1 albedo (2026-11-26, scratch experiments, not kept). Air alone, 64
// radius texels (2026-11-27): 64 mu_s texels instead of 32 give 1.002 /
// 1.013 / 1.055 (Bruneton's mu_s axis leaves the sun between 40° and 90° up
// 2.1 texels of 32), an axis linear in mu_s 1.000 / 1.010 / 1.048 (not
// kept: it spends the sunset's texels), 16 nu texels 1.010 / 1.025 / 1.073
// (unchanged).
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
    const atmos::PlaneParallelFluxes pp = atmos::reference_plane_parallel_fluxes(venus, mu_s);
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
// 8000 paths). One optical depth near the ground is a few kilometres, so the
// ground fades into the haze towards its horizon: the reference's ground is
// 3.3 times brighter 4 km away than 100 m away, and as bright as the sky just
// above the horizon (1.04 of it; 16000 paths, seed 7: 4.66e-3 +- 6 % of the
// sunlight at 4 km).
// Before ray_scattering_lookup (functions.glsl) the tables darkened the
// ground towards the horizon instead: 0.85, 0.27 and 0.13 of the reference
// 100 m, 1 km and 4 km away, as the plain lookup interpolated between the
// bottom radius row (zero for rays to the ground) and the second (330 m up).
// Measured (2026-11-24, this test's 8000 paths): the ground 100 m away
// 1.385e-3 of the sunlight (tables only), 4 km away 4.648e-3, 0.97 of the
// reference's 4.81e-3 +- 9 %; the sky 5.40e-3, 1.10 of 4.90e-3. Since the
// source is read between radius rows with cubic weights (2026-11-26; less
// sky light just above the ground, where the linear interpolation rose like
// the square root of the altitude): the ground 1.329e-3 and 4.392e-3, 0.91
// of the reference (0.94 of the 16000-path run above), the sky 5.04e-3,
// 1.03. Ground 4 km away / ground 100 m away 3.30; / sky 0.87 (reference
// 0.98). With the cloud albedo fitted to Venus's spherical albedo
// (2026-11-27): the ground 1.266e-3 and 4.186e-3, 0.91 of the reference's
// 4.59e-3, the sky 4.80e-3, 1.03 of 4.66e-3.
// Tolerances: the ground 4 km away at least twice as bright as 100 m away
// and within [0.75, 1.2] of the sky; both against the reference within
// [0.9, 1.5] (before: 0.13 for the ground; the ground's 0.91 now is close
// to the lower bound, within the reference's 9 % noise: the seed is fixed,
// so the bound catches a further loss of light near the ground).
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
      const atmos::ReferenceResult ref = atmos::reference_radiance(green, camera, view, sun, reference_options);
      reference_values[i] = ref.radiance[1] / e_sun;
      std::printf(", reference %.3e +- %.1e: %.3f", reference_values[i], ref.standard_error[1] / e_sun,
                  table_values[i] / reference_values[i]);
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
// Measured (2026-11-27, default sizes): reference 0.9000 (550 nm), 0.7811
// (440 nm) and 0.8783 (680 nm); tables 1.005, 0.999 and 1.004 of it
// (closer than their flux with the sun 40° up, 0.98 of the reference's in
// FluxesAgainstThePlaneParallelReference; why they agree better over all
// sun angles was not analysed). Tolerances: the tables within 5 % of the
// measured values.
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
    const atmos::PlaneParallelFluxes pp = atmos::reference_plane_parallel_fluxes(venus, mu_s[k]);
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
    if (c == 0) continue;
    EXPECT_NEAR(reference[c], measured[c], 0.005) << venus.wavelengths_nm[size_t(c)] << " nm";
    EXPECT_NEAR(tables[c] / measured[c], 1.0, 0.05) << venus.wavelengths_nm[size_t(c)] << " nm";
  }
}

}  // namespace
