// The light on the ground of Venus, tables against the brute-force reference.
//
// docs/preset-sources.md 1.2.3 gives 1.5-2.6 % of the sunlight on the ground
// (Venera 8, Pioneer Venus, Titov et al. 2007). The reference itself, on the
// preset as it is, gives more: 6.3 % at 550 nm with the sun 40° up (K = 2000
// interactions, converged: 5.8 % at K = 1000, 6.3 % at K = 4000; ± 12 % with
// 2000 paths), so reaching the measured band is a question for the preset
// (its cloud single-scattering albedo of 0.9995 above 500 nm is a
// placeholder, docs/preset-sources.md 1.2.4), not for the tables. The tables
// are compared with the reference.
//
// The tables (default sizes, auto orders and the solved tail) against the
// reference, on the ground (550 nm with the sun 40° and 70° up, 680 nm at
// 40°) and for the light reflected to space (the upward flux at 99 km,
// 550 nm, sun 40° up). Measured (2026-11-23):
//  - ground, 550 nm, sun 40°: 6.1e-2 of the sunlight, 0.96 of the
//    reference's 6.3e-2 (+- 12 %); sun 70°: 7.0e-2, 0.91 of 7.7e-2 (+- 10 %);
//    680 nm, sun 40°: 9.3e-2, 1.26 of 7.4e-2 (+- 10 %);
//  - reflected to space: 0.842, 0.95 of the reference's 0.885 (+- 4 %).
//  - Before the mu axis of optically thick atmospheres was warped towards
//    log-spaced distances (functions.glsl scattering_u_mu): ground 3.5e-2
//    (0.56), reflected 0.714 (0.81). Inside the cloud, the axis linear in
//    the distance to the top gave the whole upper hemisphere of a point
//    65 km up 1-2 of its 128 texels, and the tables lost a fifth of the
//    light at the cloud top; 512 texels or the warp at 128 both remove that.
//  - With the warp but 16 intervals on the multiple scattering's view rays
//    instead of 32 (multiple_scattering_intervals): ground 0.82, reflected
//    0.97 (and 1.06 / 0.99 for the wavelengths 549.5/550/550.5 nm: one set
//    of nodes serves the three wavelengths of the table).
//  - The tables of this test used to be tiny (a 64 x 16 transmittance table,
//    32 mu texels): those gave 0.21 of the reference on the ground, mostly
//    through the transmittance across the cloud top.
//  - What is left: the red's excess (1.26), not explained yet. The cloud
//    deck alone (over vacuum, conservative, black ground, 550 nm) against a
//    plane-parallel Monte Carlo (R 0.853, T 0.147): reflected 0.86, 0.94,
//    0.98, 0.99 and transmitted 0.72, 0.64, 1.10, 1.04 of it with 32, 64,
//    128, 256 radius samples (outside the tests; with 16 intervals the
//    transmission stayed 16-22 % high at 128-256).
//  - Before the warp the tables' ground light also depended too much on the
//    sun: 3.3 times more at 70° than at 40° (550 and 680 nm, from atmos
//    sample), against 1.7 with the warp and 1.8 for the reference (this
//    test's two sun elevations at 550 nm). The red's excess is the cloud's
//    transmission above.
// Tolerances: the ground within [0.75, 1.25] of the reference at 550 nm and
// [0.9, 1.45] at 680 nm (the reference's noise is fixed by the seed, so
// these are bounds against regressions around the measurements), the
// reflected light within [0.9, 1.1] (4 %).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "atmos/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "upward_flux.hpp"

namespace {

TEST(VenusAccuracy, GroundLightAgainstTheReference) {
  const atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  atmos::PrecomputeOptions options;
  // Default sizes: 256 x 64 transmittance, 8 x 32 x 128 x 32 scattering.
  options.auto_orders = true;
  options.scattering_orders = 64;
  const atmos::Tables t = atmos::precompute_tables(venus, options);
  const atmos::SkyModel model(venus, t);

  // The light on the ground, as a fraction of the sunlight on a horizontal
  // surface at the top, for one channel of the tables and the sun at
  // `elevation`, against the reference at that channel's wavelength (and
  // 0.5 nm either side: it needs three wavelengths, and mixing 440 and
  // 680 nm into its paths would multiply its variance).
  atmos::ReferenceOptions reference_options;
  reference_options.scattering_orders = 2000;
  reference_options.paths = 2000;
  auto check_ground = [&](int channel, double elevation, double low, double high) {
    const double nm = venus.wavelengths_nm[size_t(channel)];
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, elevation);
    glm::dvec3 ground_sun, ground_sky, top_sun, top_sky;
    model.horizontal_irradiance(atmos::observer_position(venus, 2.0), sun, ground_sun, ground_sky);
    model.horizontal_irradiance(atmos::observer_position(venus, 99e3), sun, top_sun, top_sky);
    const double tables = (ground_sun[channel] + ground_sky[channel]) / top_sun[channel];
    atmos::Atmosphere narrow = venus;
    narrow.wavelengths_nm = {nm - 0.5, nm, nm + 0.5};
    const atmos::ReferenceResult reference = atmos::reference_horizontal_irradiance(
        narrow, atmos::observer_position(narrow, 0.0), sun, reference_options);
    const double in = narrow.solar_irradiance.at(nm) * std::sin(elevation * M_PI / 180.0);
    const double truth = reference.radiance[1] / in;
    std::printf("venus, %g nm, sun %g deg: ground / top %.3e (tables), %.3e +- %.1e (reference): %.3f\n", nm,
                elevation, tables, truth, reference.standard_error[1] / in, tables / truth);
    EXPECT_GT(tables, low * truth) << nm << " nm, sun " << elevation;
    EXPECT_LT(tables, high * truth) << nm << " nm, sun " << elevation;
  };
  check_ground(1, 40.0, 0.75, 1.25);
  check_ground(1, 70.0, 0.75, 1.25);
  check_ground(0, 40.0, 0.9, 1.45);

  // The light going up at 99 km (32 x 24 directions), 550 nm, sun 40° up.
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, 40.0);
  glm::dvec3 top_sun, top_sky;
  model.horizontal_irradiance(atmos::observer_position(venus, 99e3), sun, top_sun, top_sky);
  const glm::dvec3 top = atmos::observer_position(venus, 99e3);
  const double tables_up = atmos_test::upward_flux(model, top, sun, 32, 24).y / top_sun.y;
  atmos::Atmosphere green = venus;
  green.wavelengths_nm = {549.5, 550.0, 550.5};
  reference_options.paths = 1000;
  const atmos::ReferenceResult up = atmos::reference_irradiance(green, top, glm::dvec3(0.0, 0.0, -1.0), sun,
                                                                reference_options);
  const double in = green.solar_irradiance.at(550.0) * std::sin(40.0 * M_PI / 180.0);
  const double truth_up = up.radiance[1] / in;
  std::printf("venus, 550 nm, sun 40 deg: reflected / in %.3f (tables), %.3f +- %.3f (reference): %.3f\n", tables_up,
              truth_up, up.standard_error[1] / in, tables_up / truth_up);
  EXPECT_GT(tables_up, 0.9 * truth_up);
  EXPECT_LT(tables_up, 1.1 * truth_up);
}

}  // namespace
