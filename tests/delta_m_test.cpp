// The delta-M scaled medium of the multiple scattering (delta_scaled_params,
// physics/parameters.hpp): what it keeps of the phase function and the
// medium, that atmospheres without a sharp lobe are untouched, the scaled
// medium's transmittance tiles, and energy conservation with a peaked lobe.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "physics/parameters.hpp"
#include "physics/medium_cpp.hpp"
#include "precompute/steps.hpp"
#include "figures.hpp"
#include "upward_flux.hpp"

namespace {

using namespace atmos::physics;
using atmos::precompute::legendre_moments;

atmos::TableSizes small_sizes() { return atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8}; }

// Legendre moment l of channel c of the aerosol phase function of `a`.
double aerosol_moment(const AtmosphereParams& a, int c, int l) {
  return legendre_moments([&](double x) { return double(aerosol_phase_function(a, float(x))[c]); }, l)[size_t(l)];
}

// The dust of the "mars" preset (double HG, forward g 0.934-0.863) and an
// Earth whose aerosol is a Henyey-Greenstein lobe of g 0.93.
AtmosphereParams mars_params() {
  return make_atmosphere_params(atmos::load_atmosphere("mars"), small_sizes(), 0);
}

// f + (1 - f) p*_1 = p_1: the δ carries the rest of the first moment, for a
// single and a double Henyey-Greenstein; the aerosol scattering becomes
// (1 - f) beta_A, its absorption and the gas stay.
TEST(DeltaM, ScaledMediumKeepsTheFirstMomentAndTheAbsorption) {
  atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  for (atmos::Constituent& c : earth.constituents)
    if (c.phase.kind != atmos::PhaseFunction::Kind::rayleigh) {
      c.phase.kind = atmos::PhaseFunction::Kind::henyey_greenstein;
      c.phase.g = atmos::Spectrum::constant(0.93);
    }
  for (const AtmosphereParams& a : {mars_params(), make_atmosphere_params(earth, small_sizes(), 0)}) {
    vec3 f;
    const AtmosphereParams s = delta_scaled_params(a, f);
    for (int c = 0; c < 3; ++c) {
      ASSERT_GT(f[c], 0.1f) << c;
      ASSERT_LT(f[c], 0.9f) << c;
      EXPECT_FLOAT_EQ(s.aerosol_g[c], kDeltaScaledMaxG);
      const double p1 = aerosol_moment(a, c, 1), p1_scaled = aerosol_moment(s, c, 1);
      EXPECT_NEAR(f[c] + (1.0 - f[c]) * p1_scaled, p1, 2e-4) << c;
      // Still a normalised phase function.
      EXPECT_NEAR(aerosol_moment(s, c, 0), 1.0, 2e-4) << c;
    }
    for (int i = 0; i < a.constituent_count; ++i) {
      const vec3 expected = a.is_aerosol[i] != 0 ? a.scattering[i] * (vec3(1.0f) - f) : a.scattering[i];
      for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(s.scattering[i][c], expected[c]);
        EXPECT_FLOAT_EQ(s.absorption[i][c], a.absorption[i][c]);
      }
    }
  }
}

// Lobes no sharper than kDeltaScaledMaxG (Earth's Cornette-Shanks 0.64,
// Titan's and Venus's HG 0.75, the seed's Cornette-Shanks 0.8 on
// mars-thesis) are not scaled: those presets' tables are those of the true
// medium, and their scaled transmittance tiles copy the true ones.
TEST(DeltaM, PresetsWithoutASharpLobeAreUnchanged) {
  for (const char* name : {"earth", "mars-thesis", "titan", "venus"}) {
    const atmos::Atmosphere atmosphere = atmos::load_atmosphere(name);
    const AtmosphereParams a = make_atmosphere_params(atmosphere, small_sizes(), 0);
    vec3 f;
    const AtmosphereParams s = delta_scaled_params(a, f);
    EXPECT_EQ(f, vec3(0.0f)) << name;
    EXPECT_EQ(s.aerosol_g, a.aerosol_g) << name;
    for (int i = 0; i < a.constituent_count; ++i) EXPECT_EQ(s.scattering[i], a.scattering[i]) << name;
  }
  atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  earth.wavelengths_nm = atmos::spectral_wavelengths(6);
  atmos::PrecomputeOptions options;
  options.sizes = small_sizes();
  options.scattering_orders = 2;
  const atmos::Tables t = atmos::precompute_tables(earth, options);
  ASSERT_EQ(t.transmittance_tiles(), 4);
  const int tile = options.sizes.transmittance_mu, row = tile * t.transmittance_tiles();
  for (int y = 0; y < options.sizes.transmittance_r; ++y)
    for (int x = 0; x < 2 * tile; ++x)
      ASSERT_EQ(t.spectral_optical_depth[size_t(y * row + x)],
                t.spectral_optical_depth[size_t(y * row + 2 * tile + x)]);
}

// The scaled medium is thinner: its optical depth (the tiles the single
// scattering reads) is below the true one by f tau_A,scattering, and only
// where there is dust.
TEST(DeltaM, ScaledTransmittanceTilesAreThinner) {
  atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  atmos::PrecomputeOptions options;
  options.sizes = small_sizes();
  options.scattering_orders = 2;
  const atmos::Tables t = atmos::precompute_tables(mars, options);
  ASSERT_EQ(t.transmittance_tiles(), 2);
  // The vertical optical depth from the ground: the smallest of the first
  // row (r at the ground) of each tile.
  const int tile = options.sizes.transmittance_mu;
  glm::vec3 true_depth(1e30f), scaled_depth(1e30f);
  for (int x = 0; x < tile; ++x) {
    true_depth = glm::min(true_depth, t.spectral_optical_depth[size_t(x)]);
    scaled_depth = glm::min(scaled_depth, t.spectral_optical_depth[size_t(tile + x)]);
  }
  std::printf("vertical optical depth at 680/550/440 nm: true %.4f %.4f %.4f, scaled %.4f %.4f %.4f\n", true_depth.x,
              true_depth.y, true_depth.z, scaled_depth.x, scaled_depth.y, scaled_depth.z);
  const AtmosphereParams a = make_atmosphere_params(mars, small_sizes(), 0);
  vec3 f;
  delta_scaled_params(a, f);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(true_depth[c], 0.45f) << c;  // tau 0.5 of dust, grey, plus a little gas
    EXPECT_LT(true_depth[c], 0.56f) << c;
    // The dust's scattering optical depth is omega tau, omega 0.73-0.975 (mars.json).
    EXPECT_LT(scaled_depth[c], true_depth[c] - 0.6f * f[c] * 0.5f * 0.8f) << c;
    EXPECT_GT(scaled_depth[c], true_depth[c] - f[c] * 0.51f) << c;
  }
}

// The scaled medium's single scattering (the source of its order 2) comes
// from the true medium's pass (steps.hpp): the same view-ray nodes, weighted
// by the ratio of the two media's transmittances along the ray. Against the
// scaled medium's own pass (its own nodes), relative to each texel's largest
// channel, over texels above 1e-3 of the table's largest: RMS 0.24 % /
// 0.40 % (Rayleigh / aerosol), max 10 % / 29 %, the max at rays grazing the
// horizon with the sun low, where the far, sunlit part of the ray holds
// few nodes in either pass (the run time integrates those rays itself,
// scattering_along_ray). End to end, tests/mars_accuracy.cpp's numbers
// moved by less than 0.1 %; the pass saves 2.4 s of 11.6 s (mars, 15
// wavelengths, 6 orders). Bounds: RMS 1 %, max 40 %.
TEST(DeltaM, SharedSingleScatteringPassMatchesTheScaledMediumsOwn) {
  const AtmosphereParams a = mars_params();
  vec3 f;
  const AtmosphereParams scaled = delta_scaled_params(a, f);
  using namespace atmos::precompute;
  const Table2D scaled_transmittance = compute_transmittance_table(scaled);
  Table3D rayleigh, aerosol, shared_rayleigh, shared_aerosol, own_rayleigh, own_aerosol;
  compute_single_scattering_tables(a, scaled_transmittance, rayleigh, aerosol, nullptr, scaled, shared_rayleigh,
                                   shared_aerosol);
  compute_single_scattering_tables(scaled, scaled_transmittance, own_rayleigh, own_aerosol, nullptr);
  // The true medium's tables are those of the plain pass.
  Table3D plain_rayleigh, plain_aerosol;
  compute_single_scattering_tables(a, scaled_transmittance, plain_rayleigh, plain_aerosol, nullptr);
  ASSERT_EQ(rayleigh.texels, plain_rayleigh.texels);
  ASSERT_EQ(aerosol.texels, plain_aerosol.texels);
  for (const auto& [shared, own] : {std::pair{&shared_rayleigh, &own_rayleigh}, {&shared_aerosol, &own_aerosol}}) {
    float largest = 0.0f;
    for (const vec3& v : own->texels) largest = std::max({largest, v.x, v.y, v.z});
    double worst = 0.0, sum_sq = 0.0;
    size_t worst_i = 0, n = 0;
    for (size_t i = 0; i < own->texels.size(); ++i) {
      const vec3 o = own->texels[i], s2 = shared->texels[i];
      const float scale = std::max({o.x, o.y, o.z});
      if (!(scale > 1e-3f * largest)) continue;
      for (int c = 0; c < 3; ++c) {
        const double e = double(std::abs(s2[c] - o[c]) / scale);
        sum_sq += e * e;
        ++n;
        if (e > worst) { worst = e; worst_i = i; }
      }
    }
    const size_t w = size_t(own->width), h = size_t(own->height);
    const double rms = std::sqrt(sum_sq / double(std::max<size_t>(n, 1)));
    std::printf("shared pass vs the scaled medium's own: RMS %.2e, max %.2e (texel x %zu, y %zu, z %zu)\n", rms, worst,
                worst_i % w, worst_i / w % h, worst_i / w / h);
    EXPECT_GT(n, 1000u);
    EXPECT_LT(rms, 0.01);
    EXPECT_LT(worst, 0.4);
  }
}

// A dense atmosphere with a scaled lobe: the dust of "mars" at 100x its
// density (vertical optical depth 50). The true medium's node weights
// underflow to 0 deep along the rays while the scaled medium's factor
// exp(f tau) grows; uncapped that was 0 x inf, a NaN sky. Every texel must
// be finite and non-negative.
TEST(DeltaM, DenseScaledAtmosphereStaysFinite) {
  atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  atmos::scale_density(mars, 100.0);
  atmos::PrecomputeOptions options;
  options.sizes = small_sizes();
  options.scattering_orders = 6;
  const atmos::Tables t = atmos::precompute_tables(mars, options);
  for (const auto* texels : {&t.set.scattering, &t.set.single_aerosol, &t.set.multiple_scattering,
                             &t.set.direct_irradiance, &t.set.indirect_irradiance, &t.spectral_optical_depth})
    for (const glm::vec3& v : *texels)
      ASSERT_TRUE(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && v.x >= 0.0f && v.y >= 0.0f &&
                  v.z >= 0.0f);
  const atmos::SkyModel model(mars, t);
  const glm::dvec3 zenith = model.radiance(atmos::observer_position(mars, 0.0), glm::dvec3(0.0, 0.0, 1.0),
                                           atmos::direction_from_azimuth_elevation(180.0, 30.0), false);
  EXPECT_TRUE(std::isfinite(zenith.x) && std::isfinite(zenith.y) && std::isfinite(zenith.z));
}

// Energy with a peaked lobe: Mars with nothing absorbing over a white ground,
// the sun at the zenith. The light the scaled medium carries in the δ must
// reach the ground (added to the sky irradiance) and come back out (the
// ground's light through the scaled medium, PATH_TO_GROUND_SCALED). Nothing
// absorbs, so the upward flux at the top is the incoming flux minus what
// diffuses sideways (Earth's clear sky: 0.97, tests/energy_accuracy.cpp).
// Measured: 0.98-1.01 at 680, 550, 440 nm; the true transmittance instead of
// the scaled one for the ground's light would give 0.82-0.94. Bounds
// [0.95, 1.02].
TEST(DeltaM, PeakedLobeOverAWhiteGroundConservesEnergy) {
  atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  for (atmos::Constituent& c : mars.constituents) {
    c.scattering = atmos::Spectrum::constant(c.scattering.at(550.0) + c.absorption.at(550.0));
    c.absorption = atmos::Spectrum::constant(0.0);
  }
  mars.ground_albedo = atmos::Spectrum::constant(1.0);
  atmos::PrecomputeOptions options;
  options.sizes = small_sizes();
  options.auto_orders = true;
  options.scattering_orders = 30;
  const atmos::Tables t = atmos::precompute_tables(mars, options);
  const glm::dvec3 up = atmos_test::upward_flux_at_top(mars, atmos::SkyModel(mars, t), 100, 8);
  for (int c = 0; c < 3; ++c) {
    const double in = mars.solar_irradiance.at(mars.wavelengths_nm[size_t(c)]);
    std::printf("%g nm: out / in = %.4f\n", mars.wavelengths_nm[size_t(c)], up[c] / in);
    atmos_test::record_figure("out / in, " + std::to_string(int(mars.wavelengths_nm[size_t(c)])) + " nm", up[c] / in,
                              "", "[0.95, 1.02]");
    EXPECT_GT(up[c] / in, 0.95) << c;
    EXPECT_LT(up[c] / in, 1.02) << c;
  }
}

}  // namespace
