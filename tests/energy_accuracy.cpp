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

}  // namespace
