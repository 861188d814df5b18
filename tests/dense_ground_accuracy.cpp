// The sky light on the ground under 100x Earth's atmosphere (slow), tables
// against the plane-parallel reference (reference_plane_parallel_fluxes:
// deterministic; its 1.441e-3 of the sunlight agrees with the Monte Carlo
// reference's 1.425e-3 +- 2.6 %, 20000 paths, and 1.495e-3 +- 4 %, 8000
// paths), at 680 nm with the sun 40° up: 16 optical depths (Rayleigh 3.6,
// the rest the preset's absorbing continental aerosol and ozone), so the
// light on the ground has been scattered dozens of times and the direct sun
// is 1e-11 of it.
//
// What it guards: the tables must converge to the reference as their radius
// texels are refined. Two parts of the multiple scattering make them do so
// in thick atmospheres (precomputation_integrands.glsl): the nodes along each view ray are
// uniform in optical depth over its first optical depths
// (source_integration_nodes), because the source function grows towards the
// sunlit top of a ray looking up; and the source is read between radius rows
// with cubic weights in the optical depth (source_function_lookup), because
// near the ground the texture coordinate follows the square root of the
// altitude, and a source linear in it rises too steeply above the ground.
// Measured: ~1.05 of the reference with 32 radius texels (the default), 1.00
// with 64.
// Tolerances: 64 texels within 3 %, 32 texels within [0.95, 1.10], and 64
// closer to the reference than 32.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "atmos/planet_file.hpp"
#include "reference/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "support/reference_store.hpp"
#include "figures.hpp"

namespace {

// The light on the ground (sun + sky, horizontal surface) over the sunlight
// on a horizontal surface at the top, in the 680 nm channel.
double ground_over_top(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables, const glm::dvec3& sun) {
  const atmos::SkyModel model(atmosphere, tables);
  glm::dvec3 ground_sun, ground_sky, top_sun, top_sky;
  model.horizontal_irradiance(atmos::observer_position(atmosphere, 0.0), sun, ground_sun, ground_sky);
  model.horizontal_irradiance(
      atmos::observer_position(atmosphere, atmosphere.top_radius_m - atmosphere.bottom_radius_m - 1.0), sun, top_sun,
      top_sky);
  return (ground_sun.x + ground_sky.x) / top_sun.x;
}

TEST(DenseGroundAccuracy, HundredTimesEarthConvergesToTheReferenceWithRadiusTexels) {
  atmos::Atmosphere dense = atmos::load_atmosphere("earth");
  atmos::scale_density(dense, 100.0);
  ASSERT_EQ(dense.wavelengths_nm[0], 680.0);
  const double elevation = 40.0;
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, elevation);

  atmos::PrecomputeOptions options;
  options.auto_orders = true;
  options.scattering_orders = 64;
  const double coarse = ground_over_top(dense, atmos::precompute_tables(dense, options), sun);
  options.sizes.scattering_r = 64;
  const double fine = ground_over_top(dense, atmos::precompute_tables(dense, options), sun);

  const double mu_s = std::sin(elevation * M_PI / 180.0);
  const atmos::PlaneParallelFluxes pp = atmos_test::oracle::reference_plane_parallel_fluxes(dense, mu_s);
  const double truth = (pp.ground_direct[0] + pp.ground_diffuse[0]) / (dense.solar_irradiance.at(680.0) * mu_s);
  std::printf("100x Earth, 680 nm, sun 40 deg: ground / top %.4e (32 radius texels), %.4e (64), %.4e "
              "(plane-parallel reference): %.3f, %.3f\n",
              coarse, fine, truth, coarse / truth, fine / truth);
  atmos_test::record_figure("ground light / sunlight, plane-parallel reference", truth, "", "");
  atmos_test::record_figure("ground light, tables / reference, 32 radius texels", coarse / truth, "", "[0.95, 1.10]");
  atmos_test::record_figure("ground light, tables / reference, 64 radius texels", fine / truth, "", "[0.97, 1.03]");
  EXPECT_NEAR(fine / truth, 1.0, 0.03);
  EXPECT_GT(coarse, 0.95 * truth);
  EXPECT_LT(coarse, 1.10 * truth);
  EXPECT_LT(std::abs(fine - truth), std::abs(coarse - truth));
}

}  // namespace
