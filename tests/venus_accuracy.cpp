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
// reference, on the ground and for the light reflected to space (the upward
// flux at 99 km), 550 nm, sun 40° up. Measured (session of 2026-11-23):
//  - ground: 3.5e-2 of the sunlight, 0.56 of the reference's 6.3e-2
//    (+- 12 %); reflected to space: 0.714, 0.81 of the reference's 0.885
//    (+- 4 %). (The same tables for the wavelengths 549.5/550/550.5 nm put
//    4.4e-2 on the ground, 0.71 of the reference: the auto orders and the
//    tail see the other channels too; not looked into.)
//  - The tables of this test used to be tiny (a 64 x 16 transmittance table,
//    32 mu texels): those gave 1.33e-2 on the ground, 0.21 of the reference,
//    and that figure was the tables' transmittance across the cloud top
//    (3.6e-2 of the sun at 70 km against the reference's 0.125) more than
//    their multiple scattering.
//  - What is left at default sizes was traced to the mu axis: with 512 mu
//    texels instead of 128 (and 549.5/550/550.5 nm, a 256 x 256
//    transmittance table) the reflected light is 0.99 of the reference and
//    the ground light 1.05 (+- 16 %); inside the cloud the upward hemisphere of a
//    point 65 km up falls within 1-2 texels of the upper half of the axis,
//    which is linear in the distance to the top. A log warp of that axis
//    for optically thick atmospheres gives the same as 512 texels at 128
//    (branch venus-mu-warp, not merged: the small-table tests of the tail
//    and of energy conservation still need reworking). A cloud alone
//    (conservative, black ground) shows a second, smaller error that needs
//    128 radius samples: see the issue 3 notes.
// Tolerances: a bound against regressions around the measurements, not an
// accuracy claim: the ground within [0.4, 1.25] of the reference, the
// reflected light within [0.7, 1.1].
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
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, 40.0);
  glm::dvec3 ground_sun, ground_sky, top_sun, top_sky;
  model.horizontal_irradiance(atmos::observer_position(venus, 2.0), sun, ground_sun, ground_sky);
  model.horizontal_irradiance(atmos::observer_position(venus, 99e3), sun, top_sun, top_sky);
  const double tables = (ground_sun.y + ground_sky.y) / top_sun.y;
  // The light going up at 99 km (32 x 24 directions).
  const glm::dvec3 top = atmos::observer_position(venus, 99e3);
  const double tables_up = atmos_test::upward_flux(model, top, sun, 32, 24).y / top_sun.y;

  // The reference at 550 nm (and 0.5 nm either side: it needs three
  // wavelengths, and mixing 440 and 680 nm into its paths would multiply its
  // variance), on the ground, the sunlight at the top being E_sun sin 40°.
  atmos::Atmosphere green = venus;
  green.wavelengths_nm = {549.5, 550.0, 550.5};
  atmos::ReferenceOptions reference_options;
  reference_options.scattering_orders = 2000;
  reference_options.paths = 2000;
  const atmos::ReferenceResult reference = atmos::reference_horizontal_irradiance(
      green, atmos::observer_position(green, 0.0), sun, reference_options);
  const double in = green.solar_irradiance.at(550.0) * std::sin(40.0 * M_PI / 180.0);
  const double truth = reference.radiance[1] / in;
  std::printf("venus, 550 nm, sun 40 deg: ground / top %.3e (tables), %.3e +- %.1e (reference): %.3f\n", tables,
              truth, reference.standard_error[1] / in, tables / truth);
  EXPECT_GT(tables, 0.4 * truth);
  EXPECT_LT(tables, 1.25 * truth);
  reference_options.paths = 1000;
  const atmos::ReferenceResult up = atmos::reference_irradiance(green, top, glm::dvec3(0.0, 0.0, -1.0), sun,
                                                                reference_options);
  const double truth_up = up.radiance[1] / in;
  std::printf("venus, 550 nm, sun 40 deg: reflected / in %.3f (tables), %.3f +- %.3f (reference): %.3f\n", tables_up,
              truth_up, up.standard_error[1] / in, tables_up / truth_up);
  EXPECT_GT(tables_up, 0.7 * truth_up);
  EXPECT_LT(tables_up, 1.1 * truth_up);
}

}  // namespace
