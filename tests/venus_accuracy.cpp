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
// The tables of the Venus tests (small, 32 radius samples, auto orders and
// the solved tail) give 1.33e-2 of the sunlight at 550 nm, 0.21 of the
// reference (before the multiple scattering integrated the source function,
// functions.glsl source_integration_nodes: 1.85e-3, 0.03 of it). Tolerance:
// the tables within [0.15, 1.25] of the reference: a bound against
// regressions, not an accuracy claim. What is left is the tables' resolution
// of a cloud of optical depth 30 (they also return 1.10x the light coming in
// from a conservative Venus over a white ground,
// Presets.ThickConservativeCloudConservesEnergy).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "atmos/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"

namespace {

TEST(VenusAccuracy, GroundLightAgainstTheReference) {
  const atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  atmos::PrecomputeOptions options;
  options.sizes = atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8};
  options.sizes.scattering_r = 32;
  options.auto_orders = true;
  options.scattering_orders = 64;
  const atmos::Tables t = atmos::precompute_tables(venus, options);
  const atmos::SkyModel model(venus, t);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, 40.0);
  glm::dvec3 ground_sun, ground_sky, top_sun, top_sky;
  model.horizontal_irradiance(atmos::observer_position(venus, 2.0), sun, ground_sun, ground_sky);
  model.horizontal_irradiance(atmos::observer_position(venus, 99e3), sun, top_sun, top_sky);
  const double tables = (ground_sun.y + ground_sky.y) / top_sun.y;

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
  EXPECT_GT(tables, 0.15 * truth);
  EXPECT_LT(tables, 1.25 * truth);
}

}  // namespace
