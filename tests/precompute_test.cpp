// The CPU precomputation: its fast paths against the straightforward forms in
// precomputation_integrands.glsl, finiteness of every table, and the disk cache.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <string>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/tables.hpp"
#include "physics/parameters.hpp"
#include "physics/precomputation_integrands_cpp.hpp"
#include "precompute/cache_file.hpp"
#include "precompute/steps.hpp"

namespace {

using namespace atmos::physics;
using namespace atmos::precompute;

atmos::TableSizes small_sizes() { return atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8}; }

// Relative difference, with an absolute floor for values near zero.
double relative(const vec3& a, const vec3& b, float floor) {
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, double(std::abs(a[c] - b[c]) / std::max(std::abs(b[c]), floor)));
  return worst;
}

class EarthSteps : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    atmosphere_ = new atmos::Atmosphere(atmos::load_atmosphere("earth"));
    params_ = make_atmosphere_params(*atmosphere_, small_sizes(), 0);
    transmittance_ = new Table2D(compute_transmittance_table(params_));
    rayleigh_ = new Table3D();
    aerosol_ = new Table3D();
    compute_single_scattering_tables(params_, *transmittance_, *rayleigh_, *aerosol_, nullptr);
    empty_ = new Table3D(rayleigh_->width, rayleigh_->height, rayleigh_->depth);
    // Order 2: its density (from the single scattering and the ground lit by
    // the sun) and its radiance.
    density1_ = new Table3D(compute_scattering_density_table(params_, *transmittance_, *rayleigh_, *aerosol_, *empty_,
                                                             Table2D(), 1, nullptr));
    multiple2_ = new Table3D(compute_multiple_scattering_table(params_, *density1_, nullptr));
  }
  static void TearDownTestSuite() {
    delete atmosphere_;
    delete transmittance_;
    delete rayleigh_;
    delete aerosol_;
    delete empty_;
    delete density1_;
    delete multiple2_;
  }
  static atmos::Atmosphere* atmosphere_;
  static AtmosphereParams params_;
  static Table2D* transmittance_;
  static Table3D *rayleigh_, *aerosol_, *empty_, *density1_, *multiple2_;
};
atmos::Atmosphere* EarthSteps::atmosphere_ = nullptr;
AtmosphereParams EarthSteps::params_{};
Table2D* EarthSteps::transmittance_ = nullptr;
Table3D *EarthSteps::rayleigh_ = nullptr, *EarthSteps::aerosol_ = nullptr, *EarthSteps::empty_ = nullptr,
        *EarthSteps::density1_ = nullptr, *EarthSteps::multiple2_ = nullptr;

TEST_F(EarthSteps, SingleScatteringFastPathEqualsTheSharedDefinition) {
  std::mt19937 rng(3);
  for (int k = 0; k < 300; ++k) {
    const int x = int(rng() % unsigned(rayleigh_->width)), y = int(rng() % unsigned(rayleigh_->height)),
              z = int(rng() % unsigned(rayleigh_->depth));
    float r, mu, mu_s, nu;
    bool ground;
    r_mu_mu_s_nu_from_scattering_texel(params_, vec3(float(x), float(y), float(z)), r, mu, mu_s, nu, ground);
    vec3 rayleigh, aerosol;
    compute_single_scattering(params_, transmittance_->sampler(), r, mu, mu_s, nu, ground, rayleigh, aerosol);
    EXPECT_LT(relative(rayleigh_->at(x, y, z), rayleigh, 1e-6f), 1e-4) << x << " " << y << " " << z;
    EXPECT_LT(relative(aerosol_->at(x, y, z), aerosol, 1e-6f), 1e-4) << x << " " << y << " " << z;
  }
}

TEST_F(EarthSteps, TransmittanceTableMatchesDirectIntegration) {
  // At the default size (256 x 64) the interpolation error is below 0.5 %.
  const AtmosphereParams p = make_atmosphere_params(*atmosphere_, atmos::TableSizes{}, 0);
  const Table2D table_default = compute_transmittance_table(p);
  const sampler2D t = table_default.sampler();
  for (float h : {0.0f, 1000.0f, 10000.0f, 50000.0f})
    for (float mu : {1.0f, 0.6f, 0.2f, 0.05f}) {
      const float r = params_.bottom_radius + h;
      const vec3 direct = exp(-optical_depth_along_ray(params_, r, mu, 0.0f,
                                                       distance_to_top_atmosphere_boundary(params_, r, mu), 4000));
      const vec3 table = transmittance_to_top_atmosphere_boundary(p, t, r, mu);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(table[c], direct[c], 0.005f * direct[c] + 1e-5f) << h << " " << mu;
    }
  // Transmittance to a point inside the atmosphere, as a ratio of two table
  // values (it composes multiplicatively), for rays up and rays to the ground.
  for (float h : {0.0f, 2000.0f, 20000.0f})
    for (float mu : {0.8f, 0.3f, -0.3f, -0.9f}) {
      const float r = params_.bottom_radius + h;
      const bool ground = ray_intersects_ground(p, r, mu);
      if (h == 0.0f && ground) continue;
      const float d = 0.6f * distance_to_nearest_atmosphere_boundary(p, r, mu, ground);
      const vec3 direct = exp(-optical_depth_along_ray(p, r, mu, 0.0f, d, 4000));
      const vec3 table = transmittance_along_ray(p, t, r, mu, d, ground);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(table[c], direct[c], 0.005f * direct[c] + 1e-5f) << h << " " << mu;
      if (ground) {
        const vec3 to_ground = transmittance_to_ground(p, t, r, mu);
        const vec3 direct_ground = exp(-optical_depth_along_ray(
            p, r, mu, 0.0f, distance_to_bottom_atmosphere_boundary(p, r, mu), 4000));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(to_ground[c], direct_ground[c], 0.005f * direct_ground[c] + 1e-5f);
      }
    }
}

// Short segments near the ground of a dense atmosphere: looking down from
// 2 m above Venus's ground, and along a level ray 10 m up. The difference of
// two table values, each an optical depth of hundreds along the grazing ray
// from the ground point to the top, would make the transmittance of a 10-300
// m path jump between 0.7 and 1; such segments are integrated directly
// (table_lookups.glsl, use_direct_optical_depth), within 0.1 % of the
// trapezoidal integral (4000 steps), and smooth.
TEST(DenseAtmosphere, TransmittanceOfShortSegmentsNearTheGround) {
  const AtmosphereParams p = make_atmosphere_params(atmos::load_atmosphere("venus"), atmos::TableSizes{}, 0);
  const Table2D table = compute_transmittance_table(p);
  const sampler2D t = table.sampler();
  const float r = p.bottom_radius + 2.0f;
  float previous = 0.0f;
  for (int i = 0; i < 200; ++i) {
    const float mu = -0.001f - 0.2f * float(i) / 199.0f;  // the ground 10 m to 2 km away
    ASSERT_TRUE(ray_intersects_ground(p, r, mu)) << mu;
    const float d = distance_to_bottom_atmosphere_boundary(p, r, mu);
    const vec3 direct = exp(-optical_depth_along_ray(p, r, mu, 0.0f, d, 4000));
    const vec3 to_ground = transmittance_to_ground(p, t, r, mu);
    const vec3 along = transmittance_along_ray(p, t, r, mu, d, true);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(to_ground[c], direct[c], 1e-3f * direct[c] + 1e-6f) << mu << " " << d;
      EXPECT_NEAR(along[c], direct[c], 1e-3f * direct[c] + 1e-6f) << mu << " " << d;
    }
    // Closer ground, more light through.
    if (i > 0) {
      EXPECT_GE(to_ground.y, previous) << mu;
    }
    previous = to_ground.y;
  }
  for (float d : {10.0f, 100.0f, 1000.0f, 5000.0f}) {
    const float level = p.bottom_radius + 10.0f;
    const vec3 direct = exp(-optical_depth_along_ray(p, level, 0.0f, 0.0f, d, 4000));
    const vec3 along = transmittance_along_ray(p, t, level, 0.0f, d, false);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(along[c], direct[c], 1e-3f * direct[c] + 1e-6f) << d;
  }
}

// The single scattering of rays to the ground from cameras below the
// tables' radius row 1 (ground_ray_scattering_below_row_1, which
// ray_scattering_lookup uses in optically thick atmospheres; this one's
// r axis is Bruneton's, so the method is called directly and the plain
// lookup must stay in use), against the same integral
// evaluated for the exact ray (compute_single_scattering, what the texels
// hold). 10 times Earth's air, aerosol and ozone, the sun 40 deg up: near the
// ground one optical depth is ~2 km at 550 nm, so the light of a ray towards
// the ground saturates with its length, and the dense aerosol makes it grow
// with the height the ray starts from (+9 % from 2 m to 105 m along 4 km).
// The plain lookup (interpolation in rho between row 0, zero for every ray to
// the ground, and row 1) gives 0.17-0.2 of the integral 4 km away from 2 m,
// and up to 5 times too much 3 m away. Measured with the method:
// at most 5.2 % further from the integral than the table itself is on row 1
// for the same distance (its own error, interpolating in mu and mu_s, is up
// to 12 % 300 m away, and the lookup below the row inherits it), 12.4 % at
// most. Tolerances: 13 % everywhere; below the row, at most 7 % more than
// the table's error on the row; continuous across the row (2 %).
// The slow test VenusAccuracy.GroundSeenFromLowCameras compares the whole
// radiance (mostly multiple scattering) with the brute-force reference.
TEST(DenseAtmosphere, SingleScatteringOfGroundRaysFromLowCameras) {
  atmos::TableSizes sizes;
  sizes.scattering_nu = 4;
  sizes.scattering_mu_s = 16;
  atmos::Atmosphere dense = atmos::load_atmosphere("earth");
  atmos::scale_density(dense, 10.0);
  const AtmosphereParams p = make_atmosphere_params(dense, sizes, 0);
  const Table2D transmittance = compute_transmittance_table(p);
  Table3D rayleigh, aerosol;
  compute_single_scattering_tables(p, transmittance, rayleigh, aerosol, nullptr);
  const float h_1 = p.scattering_row_1_height;
  EXPECT_EQ(h_1, scattering_row_height(p, 1));
  EXPECT_NEAR(h_1, 105.0f, 2.0f);  // Bruneton's r axis: rho_1 = H / 31
  const float mu_s = 0.64f;        // the sun 40 deg up
  // The ray from `height` that meets the ground after d (false if none),
  // the sun towards its azimuth, across it, or behind (nu_sign 1, 0, -1);
  // the relative error of the lookup in each channel, and of the plain one.
  auto relative_errors = [&](float height, float d, float nu_sign, vec3& error, vec3& plain_error) {
    const float r = p.bottom_radius + height;
    const float mu = -(height * (2.0f * p.bottom_radius + height) + d * d) / (2.0f * r * d);
    if (!(mu >= -1.0f) || d * d > height * (2.0f * p.bottom_radius + height)) return false;
    EXPECT_TRUE(ray_intersects_ground(p, r, mu)) << height << " " << d;
    EXPECT_NEAR(distance_to_bottom_atmosphere_boundary(p, r, mu), d, 3e-3f * d + 1.0f);
    const float nu = mu * mu_s + nu_sign * std::sqrt(1.0f - mu * mu) * std::sqrt(1.0f - mu_s * mu_s);
    vec3 exact, exact_aerosol;
    compute_single_scattering(p, transmittance.sampler(), r, mu, mu_s, nu, true, exact, exact_aerosol);
    const vec3 plain = scattering_lookup(p, rayleigh.sampler(), r, mu, mu_s, nu, true);
    const vec3 looked_up = height < h_1 ? ground_ray_scattering_below_row_1(p, rayleigh.sampler(), r, mu, mu_s, nu)
                                        : plain;
    // A thin atmosphere (Bruneton's r axis) keeps the plain lookup.
    const vec3 used = ray_scattering_lookup(p, rayleigh.sampler(), r, mu, mu_s, nu, true);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(used[c], plain[c]);
    for (int c = 0; c < 3; ++c) {
      EXPECT_GT(exact[c], 0.0f);
      EXPECT_TRUE(std::isfinite(looked_up[c]));
      error[c] = looked_up[c] / exact[c] - 1.0f;
      plain_error[c] = plain[c] / exact[c] - 1.0f;
    }
    return true;
  };
  double worst = 0.0, worst_plain = 0.0, worst_beyond_row = 0.0;
  for (float d : {3.0f, 30.0f, 100.0f, 300.0f, 1000.0f, 2000.0f, 4000.0f, 10000.0f})
    for (float nu_sign : {-1.0f, 0.0f, 1.0f}) {
      // The table's own error on the row, where the ray exists there.
      vec3 on_row(0.0f), unused;
      const bool row_ray = relative_errors(1.01f * h_1, d, nu_sign, on_row, unused);
      for (float height : {0.5f, 2.0f, 20.0f, 0.5f * h_1, 0.99f * h_1, 1.01f * h_1}) {
        vec3 e, plain;
        if (!relative_errors(height, d, nu_sign, e, plain)) continue;
        for (int c = 0; c < 3; ++c) {
          worst = std::max(worst, double(std::abs(e[c])));
          if (height < h_1) worst_plain = std::max(worst_plain, double(std::abs(plain[c])));
          const std::string where = "height " + std::to_string(height) + " m, ground " + std::to_string(d) +
                                    " m away, nu sign " + std::to_string(nu_sign) + ", channel " + std::to_string(c);
          EXPECT_LT(std::abs(e[c]), 0.13f) << where;
          if (row_ray) {
            worst_beyond_row = std::max(worst_beyond_row, double(std::abs(e[c]) - std::abs(on_row[c])));
            EXPECT_LT(std::abs(e[c]), std::abs(on_row[c]) + 0.07f) << where;
          }
          if (height == 0.99f * h_1) {
            EXPECT_NEAR(e[c], on_row[c], 0.02f) << where;
          }
        }
      }
    }
  std::printf("largest relative error %.3f, beyond the table's own on row 1 %.3f (the plain lookup below row 1: "
              "%.3f)\n",
              worst, worst_beyond_row, worst_plain);
  EXPECT_GT(worst_plain, 1.0);  // what this test guards against

  // Optically thick atmospheres use it.
  const AtmosphereParams venus = make_atmosphere_params(atmos::load_atmosphere("venus"), sizes, 0);
  EXPECT_GT(venus.scattering_r_optical_depth_weight, 0.0f);
  const float low = venus.bottom_radius + 2.0f, mu_low = -0.001f;
  const Table3D& any_table = rayleigh;  // only which branch is taken matters
  const vec3 thick = ray_scattering_lookup(venus, any_table.sampler(), low, mu_low, mu_s, 0.0f, true);
  const vec3 method = ground_ray_scattering_below_row_1(venus, any_table.sampler(), low, mu_low, mu_s, 0.0f);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(thick[c], method[c]);
}

// The spherical-harmonic density `density` of order `order` + 1 against the
// direct sphere quadrature of compute_scattering_density() from the same
// inputs, at 120 random texels: RMS and largest error on the green channel,
// relative to the density's scale at the texel's altitude.
void expect_density_matches_the_sphere_quadrature(const AtmosphereParams& p, const Table2D& transmittance,
                                                  const Table3D& rayleigh, const Table3D& aerosol,
                                                  const Table3D& multiple, const Table2D& irradiance, int order,
                                                  const Table3D& density, unsigned seed) {
  std::mt19937 rng(seed);
  double sum_sq = 0.0, worst = 0.0;
  int n = 0;
  for (int k = 0; k < 120; ++k) {
    const int x = int(rng() % unsigned(density.width)), y = int(rng() % unsigned(density.height)),
              z = int(rng() % unsigned(density.depth));
    float r, mu, mu_s, nu;
    bool ground;
    r_mu_mu_s_nu_from_scattering_texel(p, vec3(float(x), float(y), float(z)), r, mu, mu_s, nu, ground);
    auto direct = [&](float mu_v, float mu_s_v, float nu_v, int samples) {
      return compute_scattering_density(p, transmittance.sampler(), rayleigh.sampler(), aerosol.sampler(),
                                        multiple.sampler(), irradiance.sampler(), r, mu_v, mu_s_v, nu_v, order, samples);
    };
    const vec3 reference = direct(mu, mu_s, nu, 128);
    const double scale = std::max(double(reference.y), 1e-3 * double(direct(1.0f, 1.0f, 1.0f, 32).y));
    const double e = std::abs(double(density.at(x, y, z).y) - double(reference.y)) / scale;
    sum_sq += e * e;
    worst = std::max(worst, e);
    ++n;
  }
  const double rms = std::sqrt(sum_sq / n);
  std::printf("scattering density of order %d, SH vs sphere quadrature: RMS %.3f %%, max %.3f %%\n", order + 1,
              100 * rms, 100 * worst);
  EXPECT_LT(rms, 0.02);
  EXPECT_LT(worst, 0.10);
}

// Order 2, from the single scattering and the ground lit by the sun.
TEST_F(EarthSteps, ScatteringDensityMatchesTheSphereQuadrature) {
  expect_density_matches_the_sphere_quadrature(params_, *transmittance_, *rayleigh_, *aerosol_, *empty_, Table2D(), 1,
                                               *density1_, 5);
}

// Order 3, from the multiple scattering of order 2 and the ground lit by the
// sky of order 1 (irradiance_lookup() at the ground, which the fast path
// reads from a row of the irradiance table).
TEST_F(EarthSteps, ScatteringDensityOfOrderThreeMatchesTheSphereQuadrature) {
  const Table3D& multiple2 = *multiple2_;
  const Table2D irradiance1 =
      compute_indirect_irradiance_table(params_, *transmittance_, *rayleigh_, *aerosol_, *empty_, 1);
  const Table3D density2 = compute_scattering_density_table(params_, *transmittance_, *rayleigh_, *aerosol_, multiple2,
                                                            irradiance1, 2, nullptr);
  expect_density_matches_the_sphere_quadrature(params_, *transmittance_, *rayleigh_, *aerosol_, multiple2, irradiance1,
                                               2, density2, 7);
}

// The sky irradiance table (rings of directions that share their (mu, r)
// lookups) against compute_indirect_irradiance() of precomputation_integrands.glsl, from the
// single scattering (order 1) and from an order of multiple scattering.
TEST_F(EarthSteps, IndirectIrradianceFastPathEqualsTheSharedDefinition) {
  for (int order : {1, 2}) {
    SCOPED_TRACE(order);
    const Table3D& ms = order == 1 ? *empty_ : *multiple2_;
    const Table2D table = compute_indirect_irradiance_table(params_, *transmittance_, *rayleigh_, *aerosol_, ms, order);
    float largest = 0.0f;
    for (const vec3& v : table.texels) largest = std::max(largest, v.y);
    for (int y = 0; y < table.height; ++y)
      for (int x = 0; x < table.width; ++x) {
        float r, mu_s;
        r_mu_s_from_irradiance_uv(
            params_, vec2((float(x) + 0.5f) / float(table.width), (float(y) + 0.5f) / float(table.height)), r, mu_s);
        // 16: the theta samples of the precomputation (kIrradianceThetaSamples).
        const vec3 direct = compute_indirect_irradiance(params_, transmittance_->sampler(), rayleigh_->sampler(),
                                                        aerosol_->sampler(), ms.sampler(), r, mu_s, order, 16);
        EXPECT_LT(relative(const_cast<Table2D&>(table).at(x, y), direct, 1e-6f * largest), 1e-4) << x << " " << y;
      }
  }
}

// compute_multiple_scattering() of precomputation_integrands.glsl at 300 random texels of
// `multiple`, the fast path's table from `density`: relative difference
// below 2e-3, with an absolute floor of `floor`.
void expect_multiple_scattering_matches_the_shared_definition(const AtmosphereParams& p, const Table3D& density,
                                                              const Table3D& multiple, float floor, unsigned seed) {
  std::mt19937 rng(seed);
  for (int k = 0; k < 300; ++k) {
    const int x = int(rng() % unsigned(multiple.width)), y = int(rng() % unsigned(multiple.height)),
              z = int(rng() % unsigned(multiple.depth));
    float r, mu, mu_s, nu;
    bool ground;
    r_mu_mu_s_nu_from_scattering_texel(p, vec3(float(x), float(y), float(z)), r, mu, mu_s, nu, ground);
    const vec3 direct = compute_multiple_scattering(p, density.sampler(), r, mu, mu_s, nu, ground);
    EXPECT_LT(relative(const_cast<Table3D&>(multiple).at(x, y, z), direct, floor), 2e-3) << x << " " << y << " " << z;
  }
}

TEST_F(EarthSteps, MultipleScatteringFastPathEqualsTheSharedDefinition) {
  expect_multiple_scattering_matches_the_shared_definition(params_, *density1_, *multiple2_, 1e-7f, 9);
}

// The vectorised loops of the steps work on blocks of 8 texels of a row
// (nu x mu_s columns) and of 8 output mu (the scattering density), padded at
// the end: tables whose sizes are not multiples of 8 (15 columns, 10 mu rows)
// must give every texel what the shared definitions give.
TEST(OddTableSizes, FastPathsEqualTheSharedDefinitionsInEveryTexel) {
  atmos::TableSizes sizes = small_sizes();
  sizes.scattering_nu = 3;
  sizes.scattering_mu_s = 5;
  sizes.scattering_mu = 10;
  sizes.scattering_r = 4;
  const AtmosphereParams p = make_atmosphere_params(atmos::load_atmosphere("earth"), sizes, 0);
  const Table2D transmittance = compute_transmittance_table(p);
  Table3D rayleigh, aerosol;
  compute_single_scattering_tables(p, transmittance, rayleigh, aerosol, nullptr);
  ASSERT_EQ(rayleigh.width, 15);
  const Table3D empty(rayleigh.width, rayleigh.height, rayleigh.depth);
  const Table3D density =
      compute_scattering_density_table(p, transmittance, rayleigh, aerosol, empty, Table2D(), 1, nullptr);
  const Table3D multiple = compute_multiple_scattering_table(p, density, nullptr);
  for (int z = 0; z < rayleigh.depth; ++z)
    for (int y = 0; y < rayleigh.height; ++y)
      for (int x = 0; x < rayleigh.width; ++x) {
        float r, mu, mu_s, nu;
        bool ground;
        r_mu_mu_s_nu_from_scattering_texel(p, vec3(float(x), float(y), float(z)), r, mu, mu_s, nu, ground);
        vec3 single_rayleigh, single_aerosol;
        compute_single_scattering(p, transmittance.sampler(), r, mu, mu_s, nu, ground, single_rayleigh,
                                  single_aerosol);
        EXPECT_LT(relative(rayleigh.at(x, y, z), single_rayleigh, 1e-6f), 1e-4) << x << " " << y << " " << z;
        EXPECT_LT(relative(aerosol.at(x, y, z), single_aerosol, 1e-6f), 1e-4) << x << " " << y << " " << z;
        const vec3 direct = compute_multiple_scattering(p, density.sampler(), r, mu, mu_s, nu, ground);
        EXPECT_LT(relative(multiple.at(x, y, z), direct, 1e-7f), 2e-3) << x << " " << y << " " << z;
      }
  expect_density_matches_the_sphere_quadrature(p, transmittance, rayleigh, aerosol, empty, Table2D(), 1, density, 13);
}

// Optically thick atmospheres read the source function between radius rows
// with cubic Hermite weights (source_function_lookup in precomputation_integrands.glsl). The
// CPU fast path precomputes them per view ray node; it must give what the
// shared definition gives, on Venus's order-2 density (small tables).
TEST(DenseAtmosphere, MultipleScatteringFastPathEqualsTheSharedDefinition) {
  const AtmosphereParams p = make_atmosphere_params(atmos::load_atmosphere("venus"), small_sizes(), 0);
  ASSERT_EQ(p.scattering_mu_log_weight, 1.0f);
  const Table2D transmittance = compute_transmittance_table(p);
  Table3D rayleigh, aerosol;
  compute_single_scattering_tables(p, transmittance, rayleigh, aerosol, nullptr);
  const Table3D empty(rayleigh.width, rayleigh.height, rayleigh.depth);
  const Table3D density =
      compute_scattering_density_table(p, transmittance, rayleigh, aerosol, empty, Table2D(), 1, nullptr);
  const Table3D multiple = compute_multiple_scattering_table(p, density, nullptr);
  float largest = 0.0f;
  for (const vec3& v : multiple.texels) largest = std::max(largest, v.y);
  expect_multiple_scattering_matches_the_shared_definition(p, density, multiple, 1e-5f * largest, 11);
}

// The row weights of the thick-atmosphere source: they add up to 1 (a
// uniform source stays uniform), reproduce a source linear in the
// coordinate exactly (Hermite with difference slopes), end on the rows
// themselves, and are texture()'s linear weights for thin atmospheres.
TEST(DenseAtmosphere, SourceRowWeightsReproduceLinearSources) {
  const AtmosphereParams p = make_atmosphere_params(atmos::load_atmosphere("venus"), atmos::TableSizes{}, 0);
  const int n = p.scattering_r_size;
  std::vector<float> c(static_cast<size_t>(n));
  for (int z = 0; z < n; ++z) c[size_t(z)] = source_row_coordinate(p, z);
  for (int z = 1; z < n; ++z) ASSERT_GT(c[size_t(z)], c[size_t(z - 1)]) << z;
  auto at = [&](int z) { return z >= 0 && z < n ? c[size_t(z)] : 0.0f; };
  for (int z0 = 0; z0 + 1 < n; ++z0)
    for (float f : {0.0f, 0.3f, 0.7f, 1.0f}) {
      // The coordinate at linear weight f between the rows, as a radius.
      const float r = p.bottom_radius + (1.0f - f) * scattering_row_height(p, z0) + f * scattering_row_height(p, z0 + 1);
      const float cr = source_r_coordinate(p, r);
      const vec4 w = source_row_weights(p, z0, f, cr, at(z0 - 1), at(z0), at(z0 + 1), at(z0 + 2));
      EXPECT_NEAR(w.x + w.y + w.z + w.w, 1.0f, 1e-5f) << z0 << " " << f;
      const float linear = w.x * at(z0 - 1) + w.y * at(z0) + w.z * at(z0 + 1) + w.w * at(z0 + 2);
      EXPECT_NEAR(linear, cr, 1e-4f * (at(z0 + 1) - at(z0)) + 1e-6f) << z0 << " " << f;
      if (z0 == 0) {
        EXPECT_EQ(w.x, 0.0f);
      }
      if (z0 + 2 == n) {
        EXPECT_EQ(w.w, 0.0f);
      }
    }
  const vec4 at_row = source_row_weights(p, 5, 0.0f, at(5), at(4), at(5), at(6), at(7));
  EXPECT_NEAR(at_row.y, 1.0f, 1e-6f);
  EXPECT_NEAR(at_row.x, 0.0f, 1e-6f);
  EXPECT_NEAR(at_row.z, 0.0f, 1e-6f);
  const AtmosphereParams earth = make_atmosphere_params(atmos::load_atmosphere("earth"), atmos::TableSizes{}, 0);
  ASSERT_EQ(earth.scattering_mu_log_weight, 0.0f);
  const vec4 thin = source_row_weights(earth, 3, 0.25f, 0.5f, 0.1f, 0.2f, 0.9f, 1.0f);
  EXPECT_EQ(thin, vec4(0.0f, 0.75f, 0.25f, 0.0f));
}

void expect_finite(const std::vector<vec3>& texels, const char* name) {
  for (const auto& t : texels)
    ASSERT_TRUE(std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z) && t.x >= 0 && t.y >= 0 && t.z >= 0)
        << name;
}

TEST(Tables, AllTablesFiniteAndNonNegative) {
  for (const char* planet : {"earth", "mars"}) {
    atmos::PrecomputeOptions options;
    options.sizes = small_sizes();
    options.scattering_orders = 4;
    const atmos::Tables tables = atmos::precompute_tables(atmos::load_atmosphere(planet), options);
    const auto& s = tables.set;
    expect_finite(s.direct_irradiance, "direct_irradiance");
    expect_finite(s.indirect_irradiance, "indirect_irradiance");
    expect_finite(s.scattering, "scattering");
    expect_finite(s.single_aerosol, "single_aerosol");
    expect_finite(s.multiple_scattering, "multiple_scattering");
    expect_finite(tables.spectral_optical_depth, "spectral_optical_depth");
    // The transmittance exp(-depth) is in [0, 1]: the optical depth is >= 0
    // (expect_finite). Two tiles: the true and the delta-M scaled medium.
    EXPECT_EQ(tables.spectral_optical_depth.size(),
              2 * size_t(options.sizes.transmittance_mu) * size_t(options.sizes.transmittance_r));
  }
}

TEST(Tables, MoreOrdersAddLight) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  atmos::PrecomputeOptions options;
  options.sizes = small_sizes();
  double previous = -1.0;
  for (int k : {1, 2, 4}) {
    options.scattering_orders = k;
    const atmos::Tables t = atmos::precompute_tables(earth, options);
    double sum = 0.0;
    for (const auto& v : t.set.scattering) sum += v.y;
    EXPECT_GT(sum, previous) << "K = " << k;
    previous = sum;
    double irradiance = 0.0;
    for (const auto& v : t.set.indirect_irradiance) irradiance += v.y;
    if (k == 1) EXPECT_EQ(irradiance, 0.0);  // one order: no sky light on the ground yet
    else EXPECT_GT(irradiance, 0.0);
  }
}

TEST(Tables, RejectsBadOptions) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  atmos::PrecomputeOptions options;
  options.sizes = small_sizes();
  options.scattering_orders = 0;
  EXPECT_THROW(atmos::precompute_tables(earth, options), atmos::Error);
  options.scattering_orders = 2;
  options.sizes.scattering_mu = 33;
  EXPECT_THROW(atmos::precompute_tables(earth, options), atmos::Error);
  options.sizes = small_sizes();
  options.sizes.transmittance_mu = 1;
  EXPECT_THROW(atmos::precompute_tables(earth, options), atmos::Error);
}

class Cache : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = std::filesystem::temp_directory_path() /
          ("atmos-cache-test-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir);
    options.sizes = small_sizes();
    options.scattering_orders = 2;
    earth = atmos::load_atmosphere("earth");
  }
  void TearDown() override { std::filesystem::remove_all(dir); }
  std::filesystem::path dir;
  atmos::PrecomputeOptions options;
  atmos::Atmosphere earth;
};

// The first call computes and stores the tables at tables_cache_path (not
// there before), the second reads them back.
TEST_F(Cache, ComputesThenHits) {
  const std::string path = atmos::tables_cache_path(earth, options, dir.string());
  EXPECT_FALSE(std::filesystem::exists(path));
  const auto first = atmos::load_or_precompute_tables(earth, options, dir.string());
  EXPECT_EQ(first.status, atmos::CacheStatus::computed);
  EXPECT_EQ(first.path, path);
  EXPECT_TRUE(std::filesystem::exists(first.path));
  const auto second = atmos::load_or_precompute_tables(earth, options, dir.string());
  EXPECT_EQ(second.status, atmos::CacheStatus::hit);
  EXPECT_EQ(second.tables.set.scattering, first.tables.set.scattering);
  EXPECT_EQ(second.tables.set.indirect_irradiance, first.tables.set.indirect_irradiance);
}

TEST_F(Cache, KeyChangesWithEveryInput) {
  const std::string key = atmos::tables_cache_key(earth, options);
  auto other = earth;
  other.constituents[1].phase.g = atmos::Spectrum::constant(0.7);
  EXPECT_NE(atmos::tables_cache_key(other, options), key);
  other = earth;
  other.top_radius_m += 1.0;
  EXPECT_NE(atmos::tables_cache_key(other, options), key);
  auto o2 = options;
  o2.scattering_orders = 3;
  EXPECT_NE(atmos::tables_cache_key(earth, o2), key);
  o2 = options;
  o2.sizes.scattering_r = 10;
  EXPECT_NE(atmos::tables_cache_key(earth, o2), key);
  // Auto orders: the tolerance and the tail solver's options.
  o2 = options;
  o2.auto_orders = true;
  const std::string auto_key = atmos::tables_cache_key(earth, o2);
  EXPECT_NE(auto_key, key);
  for (auto change : {+[](atmos::PrecomputeOptions& o) { o.auto_orders_tolerance = 1e-4; },
                      +[](atmos::PrecomputeOptions& o) { o.solve_tail = false; },
                      +[](atmos::PrecomputeOptions& o) { o.tail_tolerance = 1e-4; },
                      +[](atmos::PrecomputeOptions& o) { o.tail_iterations = 10; }}) {
    auto o3 = o2;
    change(o3);
    EXPECT_NE(atmos::tables_cache_key(earth, o3), auto_key);
  }
  // Fixed orders never solve the tail: its options are not part of the key.
  o2 = options;
  o2.solve_tail = false;
  EXPECT_EQ(atmos::tables_cache_key(earth, o2), key);
}

// The convergence report, with the entry of a solved tail, comes back from
// the cache as it was computed.
TEST_F(Cache, ConvergenceReportWithTheTailRoundTrips) {
  options.auto_orders = true;
  options.scattering_orders = 2;  // Earth is not converged after 2 orders: the tail is solved
  const auto first = atmos::load_or_precompute_tables(earth, options, dir.string());
  ASSERT_EQ(first.status, atmos::CacheStatus::computed);
  ASSERT_EQ(first.tables.convergence.size(), 2u);
  ASSERT_TRUE(first.tables.convergence.back().tail);
  const auto second = atmos::load_or_precompute_tables(earth, options, dir.string());
  ASSERT_EQ(second.status, atmos::CacheStatus::hit);
  ASSERT_EQ(second.tables.convergence.size(), first.tables.convergence.size());
  for (size_t i = 0; i < first.tables.convergence.size(); ++i) {
    const atmos::OrderContribution &a = first.tables.convergence[i], &b = second.tables.convergence[i];
    EXPECT_EQ(a.order, b.order);
    EXPECT_EQ(a.added, b.added);
    EXPECT_EQ(a.relative, b.relative);
    EXPECT_EQ(a.tail, b.tail);
    EXPECT_EQ(a.iterations, b.iterations);
    EXPECT_EQ(a.residual, b.residual);
  }
  EXPECT_EQ(second.tables.set.scattering, first.tables.set.scattering);
}

TEST_F(Cache, CorruptAndTruncatedFilesAreRecomputed) {
  const auto first = atmos::load_or_precompute_tables(earth, options, dir.string());
  const auto size = std::filesystem::file_size(first.path);
  {  // Flip one byte in the middle.
    std::fstream f(first.path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(size / 2));
    char c;
    f.read(&c, 1);
    f.seekp(std::streamoff(size / 2));
    c = char(c ^ 0x5a);
    f.write(&c, 1);
  }
  auto again = atmos::load_or_precompute_tables(earth, options, dir.string());
  EXPECT_EQ(again.status, atmos::CacheStatus::recomputed_invalid);
  EXPECT_NE(again.problem.find("checksum"), std::string::npos) << again.problem;
  EXPECT_EQ(again.tables.set.scattering, first.tables.set.scattering);
  // Truncate.
  std::filesystem::resize_file(first.path, size - 100);
  again = atmos::load_or_precompute_tables(earth, options, dir.string());
  EXPECT_EQ(again.status, atmos::CacheStatus::recomputed_invalid);
  EXPECT_NE(again.problem.find("truncated"), std::string::npos) << again.problem;
  // Garbage.
  {
    std::ofstream f(first.path, std::ios::binary | std::ios::trunc);
    f << "not a table";
  }
  again = atmos::load_or_precompute_tables(earth, options, dir.string());
  EXPECT_EQ(again.status, atmos::CacheStatus::recomputed_invalid);
  // And the rewritten file is good again.
  EXPECT_EQ(atmos::load_or_precompute_tables(earth, options, dir.string()).status, atmos::CacheStatus::hit);
}

// A file longer than any file of these tables is refused from its length,
// before it is read (a sparse file of 1 GiB: reading it would allocate 1 GiB).
TEST_F(Cache, FileLongerThanAnyTableFileIsNotRead) {
  const auto first = atmos::load_or_precompute_tables(earth, options, dir.string());
  std::filesystem::resize_file(first.path, std::uintmax_t(1) << 30);
  const auto again = atmos::load_or_precompute_tables(earth, options, dir.string());
  EXPECT_EQ(again.status, atmos::CacheStatus::recomputed_invalid);
  EXPECT_NE(again.problem.find("more than"), std::string::npos) << again.problem;
  EXPECT_EQ(again.tables.set.scattering, first.tables.set.scattering);
}

// Fields of a cache file (src/precompute/cache.cpp, write_cache) that the
// decoder tests below change.
constexpr std::size_t kSizesOffset = 28, kSetsOffset = 64, kWavelengthsOffset = 68, kConvergenceOffset = 72,
                      kFirstWavelengthOffset = 76;

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

template <class T>
void put(std::string& file, std::size_t offset, T value) {
  std::memcpy(file.data() + offset, &value, sizeof value);
}

// The file's last 8 bytes: the 64-bit FNV-1a hash (Fowler, Noll & Vo) of
// the bytes before them, recomputed so that a changed field passes the
// checksum and reaches the check of its own.
void recompute_checksum(std::string& file) {
  const std::size_t body = file.size() - 8;
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < body; ++i) {
    h ^= static_cast<unsigned char>(file[i]);
    h *= 1099511628211ull;
  }
  put(file, body, h);
}

// Files that pass the key and the checksum but were not written for these
// tables: other working wavelengths, a non-finite convergence report, and a
// header claiming tables and counts far beyond the options' (refused before
// anything of their size is allocated). Each is refused with its reason.
TEST_F(Cache, DecoderRefusesFieldsThatDisagreeWithThePlanet) {
  options.auto_orders = true;  // a convergence report with a tail entry
  const auto first = atmos::load_or_precompute_tables(earth, options, dir.string());
  ASSERT_FALSE(first.tables.convergence.empty());
  const std::string key = atmos::tables_cache_key(earth, options);
  const std::string good = file_bytes(first.path);
  atmos::Tables tables;
  ASSERT_EQ(atmos::read_tables_file(good, key, options, earth, tables), "");
  EXPECT_EQ(tables.set.scattering, first.tables.set.scattering);

  auto problem_of = [&](const std::function<void(std::string&)>& change) {
    std::string file = good;
    change(file);
    recompute_checksum(file);
    atmos::Tables t;
    return atmos::read_tables_file(file, key, options, earth, t);
  };
  std::string problem = problem_of([](std::string& f) { put(f, kFirstWavelengthOffset, 681.0); });
  EXPECT_NE(problem.find("wavelengths"), std::string::npos) << problem;
  problem = problem_of([](std::string& f) { put(f, kFirstWavelengthOffset, std::nan("")); });
  EXPECT_NE(problem.find("wavelengths"), std::string::npos) << problem;
  // The first convergence entry follows the 3 wavelengths: order, iterations (int32), then `added`.
  const std::size_t added = kFirstWavelengthOffset + 3 * 8 + 4 + 4;
  problem = problem_of([&](std::string& f) { put(f, added, std::numeric_limits<double>::infinity()); });
  EXPECT_NE(problem.find("convergence"), std::string::npos) << problem;
  problem = problem_of([](std::string& f) {
    for (std::size_t i = 0; i < 8; ++i) put(f, kSizesOffset + 4 * i, std::int32_t(4096));
    put(f, kSetsOffset, std::numeric_limits<std::int32_t>::max());
    put(f, kWavelengthsOffset, std::numeric_limits<std::int32_t>::max());
    put(f, kConvergenceOffset, std::numeric_limits<std::int32_t>::max());
  });
  EXPECT_EQ(problem, "parameters mismatch");
}

TEST_F(Cache, UnwritableDirectoryStillReturnsTables) {
  const auto result = atmos::load_or_precompute_tables(earth, options, "/proc/atmos-cannot-write-here");
  EXPECT_EQ(result.status, atmos::CacheStatus::computed);
  EXPECT_FALSE(result.problem.empty());
  EXPECT_FALSE(result.tables.set.scattering.empty());
}

}  // namespace
