// Energy balance (issue 3): a non-absorbing atmosphere (Earth without ozone
// and with a non-absorbing aerosol) over a white ground, sun at the zenith.
// Nothing absorbs, so all sunlight that enters leaves again through the top
// of the atmosphere; above the subsolar point, the upward flux at the top
// (the radiance of every downward view direction, cosine weighted) is the
// incoming flux minus what travels sideways in the atmosphere and leaves
// elsewhere on the sphere.
//
// The brute-force reference conserves energy by construction (a path either
// leaves the atmosphere or is still scattering after K interactions; with
// K = 24 the truncated part is below 1e-4): it measures that sideways part at
// 3.0-3.1 % of the incoming flux. The tables, summed over the orders until
// the last adds less than 1e-5, must give the same upward flux within 0.5 %
// per wavelength, and the balance within [0.95, 1.0].
//
// Measured (default tables): out / in = 0.9702, 0.9708, 0.9719 (tables) and
// 0.9692, 0.9693, 0.9701 (reference, ± 0.07 %) at 680, 550, 440 nm.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "atmos/atmosphere.hpp"
#include "atmos/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "clear_sky_earth.hpp"
#include "upward_flux.hpp"

namespace {

TEST(Energy, WhiteGroundNonAbsorbingAtmosphereConservesEnergy) {
  atmos::Atmosphere a = clear_sky_earth();
  ASSERT_EQ(a.constituents.back().name, "ozone");
  a.constituents.pop_back();
  ASSERT_EQ(a.constituents[1].name, "aerosol");
  a.constituents[1].absorption = atmos::Spectrum::constant(0.0);
  a.ground_albedo = atmos::Spectrum::constant(1.0);

  atmos::PrecomputeOptions options;
  options.auto_orders = true;
  options.scattering_orders = 64;
  options.auto_orders_tolerance = 1e-5;
  const char* cache = std::getenv("ATMOS_CACHE_DIR");
  const atmos::Tables tables =
      cache ? atmos::load_or_precompute_tables(a, options, cache).tables : atmos::precompute_tables(a, options);
  const atmos::SkyModel model(a, tables);
  const glm::dvec3 up_flux = atmos_test::upward_flux_at_top(a, model, 200, 16);
  const glm::dvec3 top(0.0, 0.0, a.top_radius_m - 1.0), sun(0.0, 0.0, 1.0);

  atmos::ReferenceOptions reference_options;
  reference_options.scattering_orders = 24;
  reference_options.paths = 100000;
  // The irradiance on a surface facing down at the top: the upward flux.
  const atmos::ReferenceResult reference =
      atmos::reference_irradiance(a, top, glm::dvec3(0.0, 0.0, -1.0), sun, reference_options);

  for (int c = 0; c < 3; ++c) {
    const double in = a.solar_irradiance.at(a.wavelengths_nm[size_t(c)]);
    std::printf("%g nm: out / in = %.4f (tables, %d orders), %.4f +- %.4f (reference)\n", a.wavelengths_nm[size_t(c)],
                up_flux[c] / in, tables.scattering_orders, reference.radiance[size_t(c)] / in,
                reference.standard_error[size_t(c)] / in);
    EXPECT_NEAR(up_flux[c], reference.radiance[size_t(c)], 0.005 * reference.radiance[size_t(c)]) << c;
    EXPECT_GT(up_flux[c] / in, 0.95) << c;
    EXPECT_LE(up_flux[c] / in, 1.0) << c;
  }
}

// The same balance in an optically thick, conservative cloud: Venus with
// nothing absorbing (gas and cloud scatter only) over a white ground, the
// sun at the zenith, default tables with auto orders and the solved tail
// (src/precompute/tail.cpp). Light that reaches the ground is trapped
// between it and the cloud deck, and the reference needs thousands of
// interactions per path: at 550 nm it gives 0.950 +- 0.024 (K = 3000, 1000
// paths), 0.957 +- 0.024 (K = 8000, 1000 paths) and, as here, 1.010 +-
// 0.018 (K = 6000, 2000 paths; the seed is fixed, so the test sees this
// value): 0.98 +- 0.01 pooled.
//
// Measured with the linear interpolation between radius rows (before
// 2026-11-26; default tables, 680/550/440 nm): out / in = 0.900, 0.898, 0.895
// (re-read on 2026-11-25; the other figures here, and those of the balanced
// orders, predate the changes of 2026-11-24 to the near-ground
// transmittance and ground lookups), 0.89 of this reference run (0.91 of the
// pooled value); 0.903, 0.895, 0.888 before those changes; 0.905, 0.897, 0.889
// before the multiple scattering's nodes in thick atmospheres were uniform
// in optical depth over the first optical depths (functions.glsl,
// source_integration_nodes); 0.888, 0.886,
// 0.881 with Bruneton's r axis (before it followed the optical depth,
// functions.glsl scattering_x_r_from_rho_fraction). Before the mu axis of
// thick atmospheres was warped (functions.glsl scattering_u_mu) the same
// tables returned 1.35 of the incoming light. The tail stops at the
// 100-step cap with a residual of 9.3e-4 here (a white ground under a
// conservative cloud leaves the iteration almost nothing to lose), but that
// is not what is left: 200 steps of GMRES(100) (residual 1.3e-5) give the
// same out / in to 1e-3. Where the missing light goes is measured order by
// order in tests/energy_budget_accuracy.cpp: the multiple scattering step
// loses 0.17-0.23 % of the light of orders 8-12, in the cloud, where the
// radius rows are 2-3.4 optical depths apart.
// Since 2026-11-26 the source function is read between radius rows with
// cubic weights (functions.glsl source_function_lookup): out / in =
// 1.0072 / 1.0058 / 1.0022, 0.996 of this reference run (1.03 of the
// pooled value): the orders no longer lose light between the rows of the
// cloud; over the thousands of orders of this case they create 0.2-0.7 %
// of the sunlight, where the sideways spread should take 2 %. The tail
// solver reaches its cap of 200 steps here (residual 3.0e-4). With the
// energy balance of the orders: 0.9869 / 0.9857 / 0.9826 (0.976 of this
// run, 1.006 of the pooled value).
// Measured 2026-11-27 (the orders hand over to the tail solver at order 16,
// and the cloud's scattering coefficient is 0.02-0.1 % lower since its albedo
// was fitted; its absorption is removed here): 1.0067 / 1.0054 / 1.0018,
// 0.999 of this test's reference run (1.0062 +- 0.0181); the tail reaches
// its cap of 200 steps (residual 1.3e-4); with the energy balance 0.9967 /
// 0.9954 / 0.9919.
// Tolerance: the tables within [0.95, 1.05] of the reference at 550 nm
// (its 3 sigma are 5.4 %), out / in <= 1.01 at every wavelength (<= 1
// with the energy balance of the orders, which is within [0.95, 1.05] of
// the reference too).
TEST(Energy, ThickConservativeCloudOverAWhiteGround) {
  atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  for (atmos::Constituent& c : venus.constituents) c.absorption = atmos::Spectrum::constant(0.0);
  venus.ground_albedo = atmos::Spectrum::constant(1.0);
  atmos::PrecomputeOptions options;
  options.auto_orders = true;
  options.scattering_orders = 64;
  const atmos::Tables tables = atmos::precompute_tables(venus, options);
  ASSERT_TRUE(tables.convergence.back().tail);
  std::printf("tail: %d solver steps, residual %.1e\n", tables.convergence.back().iterations,
              tables.convergence.back().residual);
  const glm::dvec3 up = atmos_test::upward_flux_at_top(venus, atmos::SkyModel(venus, tables), 100, 8);
  options.balance_orders = true;
  const atmos::Tables balanced_tables = atmos::precompute_tables(venus, options);
  const glm::dvec3 balanced =
      atmos_test::upward_flux_at_top(venus, atmos::SkyModel(venus, balanced_tables), 100, 8);

  atmos::Atmosphere green = venus;
  green.wavelengths_nm = {549.5, 550.0, 550.5};
  atmos::ReferenceOptions reference_options;
  reference_options.scattering_orders = 6000;
  reference_options.paths = 2000;
  const glm::dvec3 top(0.0, 0.0, venus.top_radius_m - 1.0), sun(0.0, 0.0, 1.0);
  const atmos::ReferenceResult reference =
      atmos::reference_irradiance(green, top, glm::dvec3(0.0, 0.0, -1.0), sun, reference_options);
  const double truth = reference.radiance[1] / green.solar_irradiance.at(550.0);
  for (int c = 0; c < 3; ++c) {
    const double in = venus.solar_irradiance.at(venus.wavelengths_nm[size_t(c)]);
    std::printf("%g nm: out / in = %.4f (tables), %.4f (balanced orders)\n", venus.wavelengths_nm[size_t(c)],
                up[c] / in, balanced[c] / in);
    EXPECT_LE(up[c] / in, 1.01) << c;
    EXPECT_LE(balanced[c] / in, 1.0) << c;
  }
  const double tables_green = up[1] / venus.solar_irradiance.at(550.0);
  const double balanced_green = balanced[1] / venus.solar_irradiance.at(550.0);
  std::printf("550 nm: %.4f (tables), %.4f (balanced orders), %.4f +- %.4f (reference): %.3f, %.3f\n",
              tables_green, balanced_green, truth, reference.standard_error[1] / green.solar_irradiance.at(550.0),
              tables_green / truth, balanced_green / truth);
  EXPECT_GT(tables_green, 0.95 * truth);
  EXPECT_LT(tables_green, 1.05 * truth);
  // The energy balance of the orders (PrecomputeOptions::balance_orders,
  // src/precompute/energy_balance.cpp): with the linear interpolation
  // between rows it took out / in from 0.895 to 0.938 at 550 nm; now it
  // takes away the little light the orders create.
  EXPECT_GT(balanced_green, 0.95 * truth);
  EXPECT_LT(balanced_green, 1.05 * truth);
}

}  // namespace
