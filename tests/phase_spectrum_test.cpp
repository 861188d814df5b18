// The wavelength-dependent aerosol phase function: parsing and validation,
// normalisation, the phase ratio of the spectral single aerosol table, the
// truncation of the scattering density's Legendre expansion for peaked
// lobes (delta-M), the multiple scattering of a peaked lobe away from the sun
// and the sky near the sun against the Monte Carlo reference.
#include <filesystem>
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/planet_file.hpp"
#include "reference/reference.hpp"
#include "reference/reference_detail.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "physics/parameters.hpp"
#include "physics/precomputation_integrands_cpp.hpp"
#include "precompute/steps.hpp"

namespace {

using nlohmann::json;
using namespace atmos::physics;

atmos::TableSizes small_sizes() { return atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8}; }

// The Mars preset (gas + dust) with the dust's phase function replaced.
json mars_with_dust_phase(const json& phase) {
  std::ifstream in(std::filesystem::path(ATMOS_SOURCE_DIR) / "data" / "planets" / "mars.json");
  std::stringstream ss;
  ss << in.rdbuf();
  json doc = json::parse(ss.str());
  for (json& c : doc["constituents"])
    if (c["phase_function"]["type"] != "rayleigh") c["phase_function"] = phase;
  return doc;
}

atmos::Atmosphere parse(const json& doc) { return atmos::parse_atmosphere(doc.dump(), "test.json"); }

// The strongly wavelength-dependent dust of the brief: forward lobe
// g 0.93 (400 nm) -> 0.87 (700 nm), forward weight 0.85 -> 0.74, a weak
// backward lobe.
json dhg_spectrum() {
  return json{{"type", "double_henyey_greenstein"},
              {"g", {{"wavelengths_nm", {400, 700}}, {"values", {0.93, 0.87}}}},
              {"g_back", {{"wavelengths_nm", {400, 700}}, {"values", {-0.25, -0.35}}}},
              {"forward_weight", {{"wavelengths_nm", {400, 700}}, {"values", {0.85, 0.74}}}}};
}

// The same with every parameter fixed at its 550 nm value.
json dhg_at_550() {
  return json{{"type", "double_henyey_greenstein"}, {"g", 0.90}, {"g_back", -0.30}, {"forward_weight", 0.795}};
}

std::string error_of(const json& doc) {
  try {
    parse(doc);
  } catch (const atmos::Error& e) {
    return e.what();
  }
  return "";
}

// ---------------------------------------------------------------------------
// Parsing and validation.

TEST(PhaseSpectrum, ParsesScalarsAndSpectra) {
  const atmos::Atmosphere a = parse(mars_with_dust_phase(dhg_spectrum()));
  const atmos::PhaseFunction p = a.aerosol_phase();
  EXPECT_EQ(p.kind, atmos::PhaseFunction::Kind::double_henyey_greenstein);
  EXPECT_DOUBLE_EQ(p.g.at(400.0), 0.93);
  EXPECT_DOUBLE_EQ(p.g.at(550.0), 0.90);
  EXPECT_DOUBLE_EQ(p.g_back.at(700.0), -0.35);
  EXPECT_DOUBLE_EQ(p.forward_weight.at(550.0), 0.795);
  // A scalar is a constant spectrum; "values" alone follow the working wavelengths.
  const atmos::Atmosphere b = parse(mars_with_dust_phase({{"type", "henyey_greenstein"}, {"g", 0.69}}));
  EXPECT_EQ(b.aerosol_phase().g, atmos::Spectrum::constant(0.69));
  const atmos::Atmosphere c =
      parse(mars_with_dust_phase({{"type", "cornette_shanks"}, {"g", {{"values", {0.6, 0.7, 0.8}}}}}));
  EXPECT_DOUBLE_EQ(c.aerosol_phase().g.at(440.0), 0.8);  // Mars lists 680, 550, 440 nm
  EXPECT_DOUBLE_EQ(c.aerosol_phase().g.at(680.0), 0.6);
  // Per-channel parameters of a triple: its own wavelengths.
  const AtmosphereParams params = make_atmosphere_params(a, small_sizes(), 0);
  EXPECT_EQ(params.aerosol_phase_kind, PHASE_DOUBLE_HENYEY_GREENSTEIN);
  EXPECT_FLOAT_EQ(params.aerosol_g.x, float(0.93 - 0.06 * 280.0 / 300.0));  // 680 nm
  EXPECT_FLOAT_EQ(params.aerosol_forward_weight.z, float(0.85 - 0.11 * 40.0 / 300.0));  // 440 nm
}

TEST(PhaseSpectrum, RejectsBadParametersNamingTheField) {
  json bad_g = dhg_spectrum();
  bad_g["g"]["values"] = {0.9, 1.2};
  EXPECT_NE(error_of(mars_with_dust_phase(bad_g)).find("phase_function.g at 700 nm must be in (-0.999, 0.999), got 1.2"),
            std::string::npos)
      << error_of(mars_with_dust_phase(bad_g));
  json bad_back = dhg_spectrum();
  bad_back["g_back"] = -0.9995;
  EXPECT_NE(error_of(mars_with_dust_phase(bad_back)).find("phase_function.g_back must be in (-0.999, 0.999), got -0.9995"), std::string::npos)
      << error_of(mars_with_dust_phase(bad_back));
  json heavy = dhg_spectrum();
  heavy["forward_weight"]["values"] = {1.1, 0.7};
  EXPECT_NE(error_of(mars_with_dust_phase(heavy)).find("phase_function.forward_weight at 400 nm must be in [0, 1], got 1.1"),
            std::string::npos)
      << error_of(mars_with_dust_phase(heavy));
  json missing = dhg_spectrum();
  missing.erase("g_back");
  EXPECT_NE(error_of(mars_with_dust_phase(missing)).find("missing constituents[1].phase_function.g_back"),
            std::string::npos)
      << error_of(mars_with_dust_phase(missing));
  // Unknown keys: in the phase function, and in a parameter's spectrum.
  EXPECT_NE(error_of(mars_with_dust_phase({{"type", "henyey_greenstein"}, {"g", 0.7}, {"g_back", 0.1}}))
                .find("unknown key \"g_back\" in constituents[1].phase_function"),
            std::string::npos);
  json typo = dhg_spectrum();
  typo["g"]["wavelength_nm"] = {400, 700};
  EXPECT_NE(error_of(mars_with_dust_phase(typo)).find("unknown key \"wavelength_nm\" in constituents[1].phase_function.g"),
            std::string::npos)
      << error_of(mars_with_dust_phase(typo));
  json mismatched = dhg_spectrum();
  mismatched["g"]["values"] = {0.9, 0.8, 0.7};
  EXPECT_NE(error_of(mars_with_dust_phase(mismatched)).find("phase_function.g has 3 values for 2 wavelengths"),
            std::string::npos)
      << error_of(mars_with_dust_phase(mismatched));
  // Rayleigh takes no parameters.
  json doc = mars_with_dust_phase(dhg_spectrum());
  doc["constituents"][0]["phase_function"]["g"] = 0.1;
  EXPECT_NE(error_of(doc).find("constituents[0].phase_function: a rayleigh phase function takes no parameters"),
            std::string::npos)
      << error_of(doc);
}

TEST(PhaseSpectrum, AllAerosolsShareOnePhaseFunction) {
  json doc = mars_with_dust_phase(dhg_spectrum());
  json second = doc["constituents"][1];
  second["name"] = "ice";
  doc["constituents"].push_back(second);
  EXPECT_NO_THROW(parse(doc));  // the same spectra
  doc["constituents"][2]["phase_function"]["g"]["values"] = {0.93, 0.86};
  EXPECT_NE(error_of(doc).find("constituent \"ice\" has a different aerosol phase function"), std::string::npos)
      << error_of(doc);
  // A constant spectrum written two ways is two phase functions to the
  // comparison (and to the cache key): the files must agree on the form.
  doc["constituents"][2]["phase_function"] = dhg_at_550();
  EXPECT_NE(error_of(doc).find("different aerosol phase function"), std::string::npos);
}

// ---------------------------------------------------------------------------
// Normalisation: ∫ p dω = 2π ∫ p(μ) dμ = 1 at several wavelengths, for the
// description (double), the shared functions (float, per channel) and the
// reference's sampling (mean cosine).

TEST(PhaseSpectrum, IntegratesToOneAtEveryWavelength) {
  const atmos::Atmosphere dhg = parse(mars_with_dust_phase(dhg_spectrum()));
  const atmos::Atmosphere hg = parse(mars_with_dust_phase(
      {{"type", "henyey_greenstein"}, {"g", {{"wavelengths_nm", {400, 550, 700}}, {"values", {0.93, 0.5, -0.4}}}}}));
  for (const atmos::Atmosphere* a : {&dhg, &hg}) {
    const atmos::PhaseFunction p = a->aerosol_phase();
    for (double w : {400.0, 470.0, 550.0, 640.0, 700.0}) {
      // Simpson in μ, 4·10^5 intervals (the g = 0.93 lobe is 4° wide).
      const int n = 400000;
      double norm = 0.0, mean = 0.0;
      for (int i = 0; i <= n; ++i) {
        const double mu = -1.0 + 2.0 * i / n;
        const double weight = (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * (2.0 / n) / 3.0 * 2.0 * M_PI;
        norm += weight * atmos::reference_detail::phase_function(p, w, mu);
        mean += weight * mu * atmos::reference_detail::phase_function(p, w, mu);
      }
      EXPECT_NEAR(norm, 1.0, 1e-9) << int(p.kind) << " at " << w << " nm";
      const double expected_mean =
          p.kind == atmos::PhaseFunction::Kind::henyey_greenstein
              ? p.g.at(w)
              : p.forward_weight.at(w) * p.g.at(w) + (1.0 - p.forward_weight.at(w)) * p.g_back.at(w);
      EXPECT_NEAR(mean, expected_mean, 1e-8) << int(p.kind) << " at " << w << " nm";
    }
    // The shared (float) functions, channel by channel of a spectral triple.
    atmos::Atmosphere spectral = *a;
    spectral.wavelengths_nm = atmos::spectral_wavelengths(15);
    for (int set = 0; set < 5; ++set) {
      const AtmosphereParams params = make_atmosphere_params(spectral, small_sizes(), set);
      const int n = 400000;
      glm::dvec3 norm(0.0);
      for (int i = 0; i <= n; ++i) {
        const double mu = -1.0 + 2.0 * i / n;
        const double weight = (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * (2.0 / n) / 3.0 * 2.0 * M_PI;
        norm += weight * glm::dvec3(aerosol_phase_function(params, float(mu)));
      }
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(norm[c], 1.0, 2e-5) << "set " << set << " channel " << c;
    }
  }
}

// The reference samples the double HG by picking a lobe by its weight: the
// sampled mean cosine is w g + (1 - w) g_back within 5 standard errors.
TEST(PhaseSpectrum, ReferenceSamplesTheDoubleHenyeyGreenstein) {
  const atmos::PhaseFunction p = parse(mars_with_dust_phase(dhg_spectrum())).aerosol_phase();
  for (double w : {400.0, 700.0}) {
    atmos::reference_detail::Random random(7);
    const int n = 400000;
    double sum = 0.0, sum2 = 0.0, forward = 0.0;
    for (int i = 0; i < n; ++i) {
      const double mu = atmos::reference_detail::sample_phase_cosine(p, w, random);
      sum += mu;
      sum2 += mu * mu;
      forward += mu > 0.99 ? 1.0 : 0.0;
    }
    const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
    const double expected = p.forward_weight.at(w) * p.g.at(w) + (1.0 - p.forward_weight.at(w)) * p.g_back.at(w);
    EXPECT_NEAR(mean, expected, 5.0 * se) << w;
    // The share within 8° of the forward direction: 2π ∫_{0.99}^{1} p dμ.
    double exact = 0.0;
    for (int i = 0; i < 10000; ++i) exact += 2.0 * M_PI * atmos::reference_detail::phase_function(p, w, 0.99 + 0.01 * (i + 0.5) / 10000) * 0.01 / 10000;
    const double share = forward / n;
    EXPECT_NEAR(share, exact, 5.0 * std::sqrt(exact * (1.0 - exact) / n)) << w;
    std::printf("DHG at %.0f nm: mean cosine %.4f (expected %.4f), within 8 deg %.4f (expected %.4f)\n", w, mean,
                expected, share, exact);
  }
}

// ---------------------------------------------------------------------------
// A constant g spectrum and the scalar g: bit-identical tables, with three
// wavelengths and in spectral mode.

TEST(PhaseSpectrum, ConstantSpectrumGivesTheScalarTables) {
  const json scalar = {{"type", "henyey_greenstein"}, {"g", 0.69}};
  const json constant = {{"type", "henyey_greenstein"},
                         {"g", {{"wavelengths_nm", {400, 550, 700}}, {"values", {0.69, 0.69, 0.69}}}}};
  for (int count : {3, 15}) {
    atmos::Atmosphere a = parse(mars_with_dust_phase(scalar));
    atmos::Atmosphere b = parse(mars_with_dust_phase(constant));
    a.wavelengths_nm = b.wavelengths_nm = atmos::spectral_wavelengths(count);
    atmos::PrecomputeOptions options;
    options.sizes = small_sizes();
    options.scattering_orders = 3;
    const atmos::Tables ta = atmos::precompute_tables(a, options);
    const atmos::Tables tb = atmos::precompute_tables(b, options);
    EXPECT_TRUE(ta.set.single_aerosol == tb.set.single_aerosol) << count;
    EXPECT_TRUE(ta.set.scattering == tb.set.scattering) << count;
    EXPECT_TRUE(ta.set.multiple_scattering == tb.set.multiple_scattering) << count;
    EXPECT_TRUE(ta.set.indirect_irradiance == tb.set.indirect_irradiance) << count;
    // Different spectra never share a cache entry.
    EXPECT_NE(atmos::tables_cache_key(a, options), atmos::tables_cache_key(b, options));
  }
}

// ---------------------------------------------------------------------------
// The phase ratio of the spectral single aerosol table: at the table's nu
// samples, the run-time product (lookup x the channel's phase function)
// equals the sum over the wavelengths of each one's own phase-weighted single
// scattering, Σ_k M_k (S_k ⊙ P_k(nu)).

TEST(PhaseSpectrum, SingleAerosolTableHoldsThePhaseRatio) {
  atmos::Atmosphere a = parse(mars_with_dust_phase(dhg_spectrum()));
  a.wavelengths_nm = atmos::spectral_wavelengths(9);
  atmos::PrecomputeOptions options;
  options.sizes = small_sizes();
  options.scattering_orders = 1;
  const atmos::Tables tables = atmos::precompute_tables(a, options);
  const AtmosphereParams render = make_render_params(a, options.sizes);
  // The render parameters' phase: the spectra at 680, 550, 440 nm.
  EXPECT_FLOAT_EQ(render.aerosol_g.y, 0.90f);
  EXPECT_FLOAT_EQ(render.aerosol_g.z, float(0.93 - 0.06 * 40.0 / 300.0));
  const int sets = spectral_set_count(a.wavelengths_nm);
  std::vector<AtmosphereParams> params;
  std::vector<atmos::precompute::Table3D> single(static_cast<size_t>(sets));
  std::vector<glm::mat3> to_channels;
  for (int k = 0; k < sets; ++k) {
    params.push_back(make_atmosphere_params(a, options.sizes, k));
    to_channels.push_back(set_to_channels(a.wavelengths_nm, k));
    // The table's single scattering: the true medium, its sunlight through
    // the delta-M scaled medium (precompute.cpp).
    vec3 f;
    const AtmosphereParams scaled = delta_scaled_params(params.back(), f);
    atmos::precompute::Table3D rayleigh;
    compute_single_scattering_tables(params.back(), atmos::precompute::compute_transmittance_table(scaled), rayleigh,
                                     single[size_t(k)], nullptr);
  }
  const int width = tables.scattering_width(), height = tables.scattering_height(), depth = tables.scattering_depth();
  // The direct sum at every texel, at its tile nu.
  atmos::precompute::Table3D direct(width, height, depth);
  double worst_texel = 0.0, largest_ratio_change = 0.0;
  for (int z = 0; z < depth; ++z)
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const float tile_nu = scattering_texel_tile_nu(render, vec3(float(x), float(y), float(z)));
        vec3 sum(0.0f), phase_free(0.0f);
        for (int k = 0; k < sets; ++k) {
          sum += to_channels[size_t(k)] *
                 (single[size_t(k)].at(x, y, z) * aerosol_phase_function(params[size_t(k)], tile_nu));
          phase_free += to_channels[size_t(k)] * single[size_t(k)].at(x, y, z);
        }
        direct.at(x, y, z) = sum;
        const float scale = std::max({sum.x, sum.y, sum.z});
        if (!(scale > 0.0f)) continue;
        const vec3 p_ref = aerosol_phase_function(render, tile_nu);
        const vec3 texel =
            tables.set.single_aerosol[(size_t(z) * size_t(height) + size_t(y)) * size_t(width) + size_t(x)];
        for (int c = 0; c < 3; ++c) {
          worst_texel = std::max(worst_texel, double(std::abs(texel[c] * p_ref[c] - sum[c]) / scale));
          largest_ratio_change = std::max(
              largest_ratio_change,
              double(std::abs(texel[c] - phase_free[c]) / std::max({phase_free.x, phase_free.y, phase_free.z})));
        }
      }
  // The run-time lookup at random (r, mu, mu_s) and the table's nu values:
  // lookup x P_ref(nu) against the same lookup in the direct sums (the
  // interpolation in r, mu, mu_s is linear in the texels, and at a table nu
  // the tile's P_ref is the one the texels were divided by).
  const sampler3D table{width, height, depth, tables.set.single_aerosol.data()};
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  double worst_lookup = 0.0;
  int checked = 0;
  for (int i = 0; i < 4000 && checked < 1000; ++i) {
    const float r = render.bottom_radius + unit(rng) * (render.top_radius - render.bottom_radius);
    const float mu = 2.0f * unit(rng) - 1.0f;
    const float mu_s = render.mu_s_min + unit(rng) * (1.0f - render.mu_s_min);
    const int tile = int(rng() % unsigned(options.sizes.scattering_nu));
    const float nu = scattering_texel_tile_nu(render, vec3(float(tile * options.sizes.scattering_mu_s), 0.0f, 0.0f));
    if (clamp_nu(mu, mu_s, nu) != nu) continue;
    const bool ground = ray_intersects_ground(render, r, mu);
    const vec3 runtime = scattering_lookup(render, table, r, mu, mu_s, nu, ground) * aerosol_phase_function(render, nu);
    const vec3 expected = scattering_lookup(render, direct.sampler(), r, mu, mu_s, nu, ground);
    const float scale = std::max({expected.x, expected.y, expected.z});
    if (!(scale > 0.0f)) continue;
    for (int c = 0; c < 3; ++c) worst_lookup = std::max(worst_lookup, double(std::abs(runtime[c] - expected[c]) / scale));
    ++checked;
  }
  std::printf("phase ratio: texel x P_ref vs direct sum %.2e, lookup %.2e (%d lookups); the ratio changes the table by up to %.1f %%\n",
              worst_texel, worst_lookup, checked, 100.0 * largest_ratio_change);
  EXPECT_LT(worst_texel, 1e-5);
  EXPECT_GT(checked, 200);
  EXPECT_LT(worst_lookup, 1e-5);
  // It does something: the phase-free sum is not what the table holds.
  EXPECT_GT(largest_ratio_change, 0.05);
}

// ---------------------------------------------------------------------------
// The scattering density of order 2 through the Legendre expansion (degree
// kDensityMaxDegree, delta-M for the aerosol) against the direct sphere
// quadrature of compute_scattering_density, for lobes of increasing
// sharpness. Printed: the RMS and largest error relative to the density's
// scale at the texel's altitude, as precompute_test.cpp's check.

void measure_density_truncation(const json& phase, const char* label, double rms_bound, double max_bound) {
  const atmos::Atmosphere a = parse(mars_with_dust_phase(phase));
  const AtmosphereParams p = make_atmosphere_params(a, small_sizes(), 0);
  using namespace atmos::precompute;
  const Table2D transmittance = compute_transmittance_table(p);
  Table3D rayleigh, aerosol;
  compute_single_scattering_tables(p, transmittance, rayleigh, aerosol, nullptr);
  const Table3D empty(rayleigh.width, rayleigh.height, rayleigh.depth);
  const Table3D density =
      compute_scattering_density_table(p, transmittance, rayleigh, aerosol, empty, Table2D(), 1, nullptr);
  const int n = 48;
  std::vector<double> errors(n), towards_sun(n);
  tbb::parallel_for(0, n, [&](int k) {
    std::mt19937 local(unsigned(5 + k));
    const int x = int(local() % unsigned(density.width)), y = int(local() % unsigned(density.height)),
              z = int(local() % unsigned(density.depth));
    float r, mu, mu_s, nu;
    bool ground;
    r_mu_mu_s_nu_from_scattering_texel(p, vec3(float(x), float(y), float(z)), r, mu, mu_s, nu, ground);
    auto direct = [&](float mu_v, float mu_s_v, float nu_v, int samples) {
      return compute_scattering_density(p, transmittance.sampler(), rayleigh.sampler(), aerosol.sampler(),
                                        empty.sampler(), Table2D().sampler(), r, mu_v, mu_s_v, nu_v, 1, samples);
    };
    // 384 x 768 directions (0.47°): fine enough for the g = 0.93 lobe (~4°).
    const vec3 reference = direct(mu, mu_s, nu, 384);
    const double scale = std::max(double(reference.y), 1e-3 * double(direct(1.0f, 1.0f, 1.0f, 64).y));
    errors[size_t(k)] = std::abs(double(density.at(x, y, z).y) - double(reference.y)) / scale;
    towards_sun[size_t(k)] = nu;
  });
  double sum_sq = 0.0, worst = 0.0, worst_nu = 0.0;
  for (int k = 0; k < n; ++k) {
    sum_sq += errors[size_t(k)] * errors[size_t(k)];
    if (errors[size_t(k)] > worst) {
      worst = errors[size_t(k)];
      worst_nu = towards_sun[size_t(k)];
    }
  }
  const double rms = std::sqrt(sum_sq / n);
  std::printf("density of order 2, %s: Legendre (degree %d) vs sphere quadrature: RMS %.3f %%, max %.3f %% (nu %.2f)\n",
              label, atmos::precompute::kDensityMaxDegree, 100 * rms, 100 * worst, worst_nu);
  EXPECT_LT(rms, rms_bound) << label;
  EXPECT_LT(worst, max_bound) << label;
}

// Measured (green channel, 48 texels), delta-M (steps.cpp) against a plain
// truncation of the expansion at degree 28:
//                              delta-M                plain truncation
//   HG g 0.69                  RMS 0.24 %, max 1.0 %  RMS 0.24 %, max 1.0 %
//   the DHG lobe below (green: RMS 0.48 %, max 1.5 %  RMS 3.1 %, max 12 %
//     g 0.90, w 0.795)
//   HG g 0.93                  RMS 3.9 %, max 18 %    RMS 87 %, max 506 %
// Degree 28 cannot resolve a 4° lobe (p_l = g^l: 0.93^28 = 0.13); delta-M
// scatters the moments' constant part f = p_29 straight ahead (its integral,
// f L(v), is exact). What
// remains for g 0.93 is the part of the lobe between degree 28 and the δ
// (moments g^l - f, l > 28), largest relative to the small backscattered
// density (the worst texel is at nu -0.96). g 0.69 has f = 0.69^29 ≈ 2e-5:
// unchanged. The bounds fail without delta-M, and without its f L(v) term
// alone (moments p_l - f but no forward peak: DHG RMS 3.6 %, max 14 %; HG
// g 0.93 RMS 8.5 %, max 26 %).
TEST(PhaseSpectrum, DensityTruncationForPeakedLobes) {
  measure_density_truncation({{"type", "henyey_greenstein"}, {"g", 0.69}}, "HG g 0.69", 0.005, 0.02);
  measure_density_truncation(dhg_spectrum(), "DHG g 0.93-0.87", 0.01, 0.03);
  measure_density_truncation({{"type", "henyey_greenstein"}, {"g", 0.93}}, "HG g 0.93", 0.06, 0.25);
}

// ---------------------------------------------------------------------------
// The sky near the sun against the spectral Monte Carlo reference.

// sRGB of the SkyModel (the tables and the run time) and of the reference
// (15 wavelengths converted with the same CIE weights) at directions 3-15°
// from the sun; returns the RMS relative error over the directions and the
// three channels, and prints the worst.
struct NearSunResult {
  double rms = 0.0, worst = 0.0, noise = 0.0;
};

NearSunResult near_sun_error(const atmos::Atmosphere& tables_atmosphere, const atmos::Atmosphere& truth,
                             const atmos::TableSizes& sizes, const char* label) {
  atmos::PrecomputeOptions options;
  options.sizes = sizes;
  options.scattering_orders = 4;
  const atmos::Tables tables = atmos::precompute_tables(tables_atmosphere, options);
  const atmos::SkyModel model(tables_atmosphere, tables);
  const glm::dvec3 position = atmos::observer_position(truth, 0.0);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(200.0, 30.0);
  const glm::dvec3 e1 = glm::normalize(glm::cross(sun, glm::dvec3(0.0, 0.0, 1.0)));
  const glm::dvec3 e2 = glm::cross(sun, e1);
  std::vector<glm::dvec3> dirs;
  for (double angle : {3.0, 5.0, 8.0, 11.0, 15.0})
    for (double around : {0.0, 90.0, 180.0, 270.0}) {
      const double t = glm::radians(angle), f = glm::radians(around);
      dirs.push_back(std::cos(t) * sun + std::sin(t) * (std::cos(f) * e1 + std::sin(f) * e2));
    }
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(truth.wavelengths_nm);
  std::vector<glm::dvec3> table(dirs.size()), reference(dirs.size()), noise(dirs.size());
  tbb::parallel_for(size_t(0), dirs.size(), [&](size_t i) {
    table[i] = model.to_srgb(model.radiance(position, dirs[i], sun, false));
    atmos::ReferenceOptions o;
    o.paths = 3000;
    o.scattering_orders = tables.scattering_orders;
    o.seed = 500 + i;
    const atmos::ReferenceResult r = atmos::reference_radiance(truth, position, dirs[i], sun, o);
    for (size_t l = 0; l < r.radiance.size(); ++l) {
      reference[i] += weights[l] * r.radiance[l];
      noise[i] += glm::abs(weights[l]) * r.standard_error[l];  // fully correlated: conservative
    }
  });
  NearSunResult out;
  double sum_sq = 0.0, noise_sq = 0.0;
  for (size_t i = 0; i < dirs.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double e = (table[i][c] - reference[i][c]) / reference[i][c];
      sum_sq += e * e;
      noise_sq += (noise[i][c] / reference[i][c]) * (noise[i][c] / reference[i][c]);
      out.worst = std::max(out.worst, std::abs(e));
    }
  out.rms = std::sqrt(sum_sq / double(3 * dirs.size()));
  out.noise = std::sqrt(noise_sq / double(3 * dirs.size()));
  std::printf("%-34s near the sun (3-15 deg), sRGB channels: RMS %5.2f %%  max %5.2f %%  (reference noise RMS %.2f %%)\n",
              label, 100.0 * out.rms, 100.0 * out.worst, 100.0 * out.noise);
  for (size_t i = 0; i < dirs.size(); i += 4)
    std::printf("    %4.1f deg: table %.4g %.4g %.4g  reference %.4g %.4g %.4g\n",
                glm::degrees(std::acos(glm::dot(dirs[i], sun))), table[i].x, table[i].y, table[i].z, reference[i].x,
                reference[i].y, reference[i].z);
  std::fflush(stdout);
  return out;
}

// Measured (seeds fixed, 3000 paths per direction, reference noise RMS
// 1.3 %), RMS / max over 20 directions x 3 channels, with 64 nu tiles (the
// other sizes small): DHG spectrum 9.9 / 26 %, fixed at 550 nm 17.5 / 39 %.
// The tables are exact at their nu samples only (the phase ratio test); in
// between, the ratio P_λ/P_c of lobes 4-8° wide is interpolated linearly
// between tiles 2.9° apart. The lobe is delta-M scaled (g 0.93-0.87 >
// kDeltaScaledMaxG): the light scattered more than once keeps no narrow
// forward peak (the part of the sunlight scattered into the peak before
// reaching the point is in the single scattering, see precompute.cpp).
// Bounds: 13 % RMS, 34 % max, and the fixed phase at least 1.5x worse.
// Near the sun, a phase function that changes this much with wavelength
// needs many nu samples; with the default 8 expect errors of ~20 % there.
TEST(PhaseSpectrumAccuracy, SkyNearTheSunMatchesTheSpectralReference) {
  atmos::Atmosphere truth = parse(mars_with_dust_phase(dhg_spectrum()));
  atmos::Atmosphere fixed = parse(mars_with_dust_phase(dhg_at_550()));
  truth.wavelengths_nm = fixed.wavelengths_nm = atmos::spectral_wavelengths(15);
  atmos::TableSizes sizes = small_sizes();
  sizes.scattering_nu = 64;
  const NearSunResult exact = near_sun_error(truth, truth, sizes, "DHG spectrum");
  const NearSunResult at_550 = near_sun_error(fixed, truth, sizes, "DHG fixed at 550 nm");
  EXPECT_LT(exact.rms, 0.13);
  EXPECT_LT(exact.worst, 0.34);
  EXPECT_GT(at_550.rms, 1.5 * exact.rms);
}

// ---------------------------------------------------------------------------
// Multiple scattering of a peaked lobe end to end: Earth (three wavelengths)
// with its aerosol replaced by Henyey-Greenstein g 0.93 at twice its optical
// depth (0.30 at 550 nm), the SkyModel against the Monte Carlo reference at
// directions more than 30° from the sun, where the aerosol's single
// scattering no longer dominates and the light scattered again matters.

atmos::Atmosphere earth_with_peaked_aerosol() {
  std::ifstream in(std::filesystem::path(ATMOS_SOURCE_DIR) / "data" / "planets" / "earth.json");
  std::stringstream ss;
  ss << in.rdbuf();
  json doc = json::parse(ss.str());
  for (json& c : doc["constituents"])
    if (c["name"] == "aerosol") {
      c["phase_function"] = {{"type", "henyey_greenstein"}, {"g", 0.93}};
      for (const char* key : {"scattering", "absorption"})
        for (json& v : c[key]["values"]) v = 2.0 * v.get<double>();
    }
  return parse(doc);
}

struct AwayFromSunResult {
  double rms = 0.0, worst = 0.0, total_rms = 0.0, noise = 0.0;
};

// The light scattered 2-4 times, as the radiance of 4 orders minus that of 1
// (the same run-time path adds the single scattering to both), for the
// tables and for the reference (the same seed: a sky ray's first interaction
// uses the same random numbers whatever the order cap, so the difference is
// the estimate of orders 2-4 from the same paths).
AwayFromSunResult away_from_sun_error(const atmos::Atmosphere& a, const atmos::TableSizes& sizes, int paths) {
  atmos::PrecomputeOptions options;
  options.sizes = sizes;
  options.scattering_orders = 4;
  const atmos::Tables tables = atmos::precompute_tables(a, options);
  options.scattering_orders = 1;
  const atmos::Tables single_tables = atmos::precompute_tables(a, options);
  const atmos::SkyModel model(a, tables), single_model(a, single_tables);
  const glm::dvec3 position = atmos::observer_position(a, 0.0);
  struct Case {
    glm::dvec3 sun, view;
  };
  std::vector<Case> cases;
  for (double sun_elevation : {10.0, 40.0}) {
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(200.0, sun_elevation);
    for (double elevation : {3.0, 15.0, 40.0})
      for (double azimuth : {60.0, 100.0, 140.0, 180.0}) {
        const glm::dvec3 view = atmos::direction_from_azimuth_elevation(200.0 + azimuth, elevation);
        if (glm::dot(view, sun) < std::cos(glm::radians(30.0))) cases.push_back({sun, view});
      }
  }
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(a.wavelengths_nm);
  const size_t n = cases.size();
  std::vector<glm::dvec3> table(n), table_single(n), reference(n), reference_single(n), noise(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    table[i] = model.to_srgb(model.radiance(position, cases[i].view, cases[i].sun, false));
    table_single[i] = single_model.to_srgb(single_model.radiance(position, cases[i].view, cases[i].sun, false));
    atmos::ReferenceOptions o;
    o.paths = paths;
    o.seed = 900 + i;
    o.scattering_orders = 4;
    const atmos::ReferenceResult r = atmos::reference_radiance(a, position, cases[i].view, cases[i].sun, o);
    o.scattering_orders = 1;
    const atmos::ReferenceResult r1 = atmos::reference_radiance(a, position, cases[i].view, cases[i].sun, o);
    for (size_t l = 0; l < r.radiance.size(); ++l) {
      reference[i] += weights[l] * r.radiance[l];
      reference_single[i] += weights[l] * r1.radiance[l];
      noise[i] += glm::abs(weights[l]) * r.standard_error[l];
    }
  });
  AwayFromSunResult out;
  double sum_sq = 0.0, total_sq = 0.0, noise_sq = 0.0;
  for (size_t i = 0; i < n; ++i) {
    glm::dvec3 e, total;
    for (int c = 0; c < 3; ++c) {
      const double multiple = reference[i][c] - reference_single[i][c];
      e[c] = (table[i][c] - table_single[i][c] - multiple) / multiple;
      total[c] = (table[i][c] - reference[i][c]) / reference[i][c];
      sum_sq += e[c] * e[c];
      total_sq += total[c] * total[c];
      noise_sq += (noise[i][c] / multiple) * (noise[i][c] / multiple);
      out.worst = std::max(out.worst, std::abs(e[c]));
    }
    std::printf("    sun el %4.1f, %5.1f deg from it: orders 2-4 are %4.1f %% (green); their error %+6.2f %+6.2f %+6.2f %%"
                " (noise %.2f %%), total %+6.2f %+6.2f %+6.2f %%\n",
                glm::degrees(std::asin(cases[i].sun.z)), glm::degrees(std::acos(glm::dot(cases[i].view, cases[i].sun))),
                100 * (reference[i].y - reference_single[i].y) / reference[i].y, 100 * e.x, 100 * e.y, 100 * e.z,
                100 * noise[i].y / (reference[i].y - reference_single[i].y), 100 * total.x, 100 * total.y, 100 * total.z);
  }
  out.rms = std::sqrt(sum_sq / double(3 * n));
  out.total_rms = std::sqrt(total_sq / double(3 * n));
  out.noise = std::sqrt(noise_sq / double(3 * n));
  std::printf("HG g 0.93 aerosol, > 30 deg from the sun, %zu directions x 3 sRGB channels: orders 2-4 RMS %.2f %%, "
              "max %.2f %% (reference noise RMS %.2f %%); all orders RMS %.2f %%\n",
              n, 100 * out.rms, 100 * out.worst, 100 * out.noise, 100 * out.total_rms);
  std::fflush(stdout);
  return out;
}

// Measured (seeds fixed, 16000 paths per direction, so the numbers are
// repeatable; tables 32 x 16 x 64 x 16, 4 orders; 24 directions x 3 sRGB
// channels): all orders 14.6 % RMS; orders 2-4 as split here 20.8 % RMS,
// max 41 %, with a reference noise of ~4.6 % RMS on them. The lobe
// (g 0.93 > kDeltaScaledMaxG) is delta-M scaled (delta_scaled_params), and
// the split is no longer the tables' own: their single scattering carries
// the sunlight scattered into the forward peak on its way (the scaled
// transmittance to the sun), which the reference counts as order 2. What is
// left: the views 3° above the horizon are 20-47 % too bright (the scaled
// medium keeps the light forward-scattered along a long grazing view ray on
// the ray), the others 1-15 % too dark. Scaling only the density's
// expansion would fit this case better, but not the Mars dust, whose aerosol
// dominates its sky (tests/mars_accuracy.cpp): the expansion of the single
// scattering's sharp aureole rings into the density far from the sun.
// Bounds: all orders 19 % RMS, orders 2-4 27 % RMS, max 55 %.
TEST(PhaseSpectrum, PeakedLobeMultipleScatteringMatchesTheReference) {
  atmos::TableSizes sizes = small_sizes();
  sizes.scattering_nu = 32;
  sizes.scattering_mu = 64;
  sizes.scattering_r = 16;
  const AwayFromSunResult r = away_from_sun_error(earth_with_peaked_aerosol(), sizes, 16000);
  EXPECT_LT(r.total_rms, 0.19);
  EXPECT_LT(r.rms, 0.27);
  EXPECT_LT(r.worst, 0.55);
}

}  // namespace
