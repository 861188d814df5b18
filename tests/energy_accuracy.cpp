// Energy balance: a non-absorbing atmosphere (Earth without ozone
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
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"
#include "reference/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "support/reference_store.hpp"
#include "clear_sky_earth.hpp"
#include "figures.hpp"
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
      atmos_test::oracle::reference_irradiance(a, top, glm::dvec3(0.0, 0.0, -1.0), sun, reference_options);

  for (int c = 0; c < 3; ++c) {
    const double in = a.solar_irradiance.at(a.wavelengths_nm[size_t(c)]);
    std::printf("%g nm: out / in = %.4f (tables, %d orders), %.4f +- %.4f (reference)\n", a.wavelengths_nm[size_t(c)],
                up_flux[c] / in, tables.scattering_orders, reference.radiance[size_t(c)] / in,
                reference.standard_error[size_t(c)] / in);
    char nm[32];
    std::snprintf(nm, sizeof nm, "%g nm", a.wavelengths_nm[size_t(c)]);
    atmos_test::record_figure(std::string("out / in, tables, ") + nm, up_flux[c] / in, "", "[0.95, 1.0]");
    atmos_test::record_figure(std::string("out / in, reference, ") + nm, reference.radiance[size_t(c)] / in, "",
                              "");
    atmos_test::record_figure(std::string("tables / reference, ") + nm,
                              up_flux[c] / reference.radiance[size_t(c)], "", "[0.995, 1.005]");
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
// paths), 0.957 +- 0.024 (K = 8000, 1000 paths) and, as here, 1.01 +- 0.018
// (K = 6000, 2000 paths; the seed is fixed, so the test sees this value):
// 0.98 +- 0.01 pooled. The sideways spread over the sphere should take ~2 %
// of the sunlight, as on the thin Earth above.
// The tables return about 1.006 of the sunlight: over the thousands of
// orders of this case, the cubic interpolation of the source between radius
// rows (source_function_lookup in precomputation_integrands.glsl), which is not exactly
// conservative, creates a few thousandths of it. Where a transport step loses
// or creates light is measured order by order in
// tests/energy_budget_accuracy.cpp. The tail solver reaches its step cap
// here (a white ground under a conservative cloud leaves the iteration
// almost nothing to lose); more steps change out / in by less than 1e-3.
// Tolerance: the tables within [0.95, 1.05] of the reference at 550 nm
// (its 3 sigma are 5.4 %), out / in <= 1.01 at every wavelength.
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

  atmos::Atmosphere green = venus;
  green.wavelengths_nm = {549.5, 550.0, 550.5};
  atmos::ReferenceOptions reference_options;
  reference_options.scattering_orders = 6000;
  reference_options.paths = 2000;
  const glm::dvec3 top(0.0, 0.0, venus.top_radius_m - 1.0), sun(0.0, 0.0, 1.0);
  const atmos::ReferenceResult reference =
      atmos_test::oracle::reference_irradiance(green, top, glm::dvec3(0.0, 0.0, -1.0), sun, reference_options);
  const double truth = reference.radiance[1] / green.solar_irradiance.at(550.0);
  for (int c = 0; c < 3; ++c) {
    const double in = venus.solar_irradiance.at(venus.wavelengths_nm[size_t(c)]);
    std::printf("%g nm: out / in = %.4f (tables)\n", venus.wavelengths_nm[size_t(c)], up[c] / in);
    char nm[32];
    std::snprintf(nm, sizeof nm, "%g nm", venus.wavelengths_nm[size_t(c)]);
    atmos_test::record_figure(std::string("out / in, tables, ") + nm, up[c] / in, "", "<= 1.01");
    EXPECT_LE(up[c] / in, 1.01) << c;
  }
  const double tables_green = up[1] / venus.solar_irradiance.at(550.0);
  std::printf("550 nm: %.4f (tables), %.4f +- %.4f (reference): %.3f\n", tables_green, truth,
              reference.standard_error[1] / green.solar_irradiance.at(550.0), tables_green / truth);
  atmos_test::record_figure("out / in, reference, 550 nm", truth, "", "");
  atmos_test::record_figure("out / in, reference standard error, 550 nm",
                            reference.standard_error[1] / green.solar_irradiance.at(550.0), "", "");
  atmos_test::record_figure("tables / reference, 550 nm", tables_green / truth, "", "[0.95, 1.05]");
  EXPECT_GT(tables_green, 0.95 * truth);
  EXPECT_LT(tables_green, 1.05 * truth);
}

}  // namespace
