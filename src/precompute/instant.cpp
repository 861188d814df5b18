// The tables of the instant approximate mode (atmos::InstantTables; Hillaire
// 2020, "A Scalable and Production Ready Sky and Atmosphere Rendering
// Technique", EGSR 2020): the transmittance, the 2D multiple-scattering
// table Ψ_ms and the sky irradiance on the ground that the run time lights
// surfaces with. See physics/instant_atmosphere.glsl for the model.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "atmos/tables.hpp"
#include "physics/instant_atmosphere_cpp.hpp"
#include "physics/parameters.hpp"
#include "physics/precomputation_integrands_cpp.hpp"
#include "physics/quadrature.hpp"
#include "precompute/steps.hpp"

namespace atmos {

namespace {

using physics::AtmosphereParams;
using physics::vec2;
using physics::vec3;

// Directions of the sphere integrals of Ψ_ms (Gauss-Legendre in the zenith
// cosine, midpoints in the azimuth over [0, π], the other half by the
// symmetry about the sun's vertical plane) and intervals of each ray.
// Hillaire 2020 takes 64 directions spread over the sphere; here the zenith
// cosine is split at the point's horizon, whose grazing rays are the longest
// and carry the most light, with 6 nodes on each side (nodes crowd towards
// the ends of each interval), times 4 azimuths over half the circle,
// mirrored by the symmetry: 48 rays. The clear sky's RMS error against the
// reference is 2 points lower than with 8 nodes over the whole sphere, and
// within 0.25 points of 5 azimuths with 12 intervals per ray
// (tests/instant_accuracy.cpp).
constexpr int kMultipleMuNodes = 6;
constexpr int kMultiplePhiNodes = 4;
constexpr int kMultipleRayIntervals = 10;
// The same for the sky irradiance (the upper hemisphere), and the intervals
// of each ray (nodes quadratic in the distance, as the sky-view table's).
constexpr int kIrradianceMuNodes = 6;
constexpr int kIrradiancePhiNodes = 4;
constexpr int kIrradianceRayIntervals = 8;
// Trapezoid steps of the transmittance table's optical depth (the exact
// tables take 250; the step is then at most 1/96 of a ray, 11 km for the
// Earth's horizontal ray, over which the air along it falls off by a few per
// cent).
constexpr int kTransmittanceSteps = 96;
// The least 1 - f_ms: in an optically thick, conservative atmosphere f_ms
// tends to 1 and the series to infinity; the approximation is poor there
// anyway (docs/instant.md, Venus).
constexpr double kLeastEscape = 1e-3;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void parallel_rows(int height, const std::function<void(int)>& body) {
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
    for (int y = range.begin(); y != range.end(); ++y) body(y);
  });
}

// Ψ_ms at (r, mu_s) of one wavelength triple (Hillaire 2020's
// multiple-scattering LUT), in the medium `medium` (the delta-M scaled one,
// reading its own tile of the optical depth through `transmittance`): for
// every direction ω of the sphere, the ray from x = (r) along ω to the
// ground or the top,
//   L'(ω)  = ∫ σ_s T(x, y) T_sun(y) p_u dy + T(x, g) (α/π) μ_s(g) T_sun(g),
//   L_f(ω) = ∫ σ_s T(x, y) dy
// (per unit solar irradiance, p_u = 1/4π; the ground term for rays that
// meet it: the sunlit Lambertian ground), then the second order L_2nd =
// ∫ L' p_u dω, the transfer f_ms = ∫ L_f p_u dω and Ψ_ms = L_2nd / (1 -
// f_ms). Each ray is integrated as the run time's march, nodes quadratic in
// the distance, exponential segments.
glm::dvec3 multiple_scattering_texel(const AtmosphereParams& medium, const physics::sampler2D& transmittance, float r,
                                     float mu_s) {
  std::vector<double> mu_nodes, mu_weights, upper_nodes, upper_weights;
  const double mu_horizon = physics::horizon_mu(medium, r);
  physics::gauss_legendre(kMultipleMuNodes, -1.0, mu_horizon, mu_nodes, mu_weights);
  physics::gauss_legendre(kMultipleMuNodes, mu_horizon, 1.0, upper_nodes, upper_weights);
  mu_nodes.insert(mu_nodes.end(), upper_nodes.begin(), upper_nodes.end());
  mu_weights.insert(mu_weights.end(), upper_weights.begin(), upper_weights.end());
  const double p_u = 1.0 / (4.0 * M_PI);
  glm::dvec3 second_order(0.0), transfer(0.0);
  const float sin_s = std::sqrt(std::max(0.0f, 1.0f - mu_s * mu_s));
  for (size_t i = 0; i < mu_nodes.size(); ++i) {
    const float mu = float(mu_nodes[i]);
    const float sin_v = std::sqrt(std::max(0.0f, 1.0f - mu * mu));
    const bool ground = physics::ray_intersects_ground(medium, r, mu);
    const float d = physics::distance_to_nearest_atmosphere_boundary(medium, r, mu, ground);
    for (int j = 0; j < kMultiplePhiNodes; ++j) {
      const double phi = M_PI * (double(j) + 0.5) / double(kMultiplePhiNodes);
      const double weight = mu_weights[i] * 2.0 * M_PI / double(kMultiplePhiNodes);  // both halves of the azimuth
      const float nu = physics::clamp_cosine(mu * mu_s + sin_v * sin_s * float(std::cos(phi)));
      const float rayleigh_phase = physics::rayleigh_phase_function(nu);
      const vec3 aerosol_phase = physics::aerosol_phase_function(medium, nu);
      vec3 depth(0.0f), lit(0.0f), unit(0.0f);
      vec3 previous_extinction(0.0f), previous_lit(0.0f), previous_unit(0.0f);
      float previous_t = 0.0f;
      for (int k = 0; k <= kMultipleRayIntervals; ++k) {
        const float x = float(k) / float(kMultipleRayIntervals);
        const float t = d * x * x;
        const float r_t = physics::clamp_radius(medium, physics::radius_along_ray(r, mu, t));
        const float mu_s_t = physics::clamp_cosine(physics::mu_s_along_ray(r, mu_s, nu, t, r_t));
        vec3 rayleigh, aerosol, extinction;
        physics::medium_at(medium, r_t, rayleigh, aerosol, extinction);
        const float h = t - previous_t;
        if (k > 0) depth += physics::exponential_segment_integral(previous_extinction, extinction, h);
        const vec3 view = glm::exp(-depth);
        const vec3 scattering = rayleigh + aerosol;
        const vec3 lit_integrand = (rayleigh * rayleigh_phase + aerosol * aerosol_phase) * view *
                                   physics::transmittance_to_sun(medium, transmittance, r_t, mu_s_t);
        const vec3 unit_integrand = scattering * view;
        if (k > 0) {
          lit += physics::exponential_segment_integral(previous_lit, lit_integrand, h);
          unit += physics::exponential_segment_integral(previous_unit, unit_integrand, h);
        }
        previous_extinction = extinction;
        previous_lit = lit_integrand;
        previous_unit = unit_integrand;
        previous_t = t;
      }
      glm::dvec3 radiance = glm::dvec3(lit);
      if (ground) {
        const float mu_s_g = physics::clamp_cosine(physics::mu_s_at_ground(medium, r, mu_s, nu, d));
        const vec3 sun = physics::transmittance_to_sun(medium, transmittance, medium.bottom_radius, mu_s_g);
        radiance += glm::dvec3(glm::exp(-depth) * medium.ground_albedo * sun) * (std::max(mu_s_g, 0.0f) / M_PI);
      }
      second_order += radiance * (p_u * weight);
      transfer += glm::dvec3(unit) * (p_u * weight);
    }
  }
  glm::dvec3 psi;
  for (int c = 0; c < 3; ++c) psi[c] = second_order[c] / std::max(1.0 - transfer[c], kLeastEscape);
  return psi;
}

// The optical depth to the top of the atmosphere (the exact tables'
// transmittance table, precompute/steps.cpp) with kTransmittanceSteps.
precompute::Table2D transmittance_table(const AtmosphereParams& a) {
  precompute::Table2D table(a.transmittance_mu_size, a.transmittance_r_size);
  parallel_rows(table.height, [&](int y) {
    for (int x = 0; x < table.width; ++x) {
      float r, mu;
      physics::r_mu_from_transmittance_uv(
          a, vec2((float(x) + 0.5f) / float(table.width), (float(y) + 0.5f) / float(table.height)), r, mu);
      table.at(x, y) = physics::optical_depth_along_ray(a, r, mu, 0.0f,
                                                        physics::distance_to_top_atmosphere_boundary(a, r, mu),
                                                        kTransmittanceSteps);
    }
  });
  return table;
}

}  // namespace

InstantTables compute_instant_tables(const Atmosphere& atmosphere, const TableSizes& sizes) {
  atmosphere.validate();
  sizes.validate();
  const std::vector<double>& wavelengths = atmosphere.wavelengths_nm;
  const int count = physics::spectral_set_count(wavelengths);
  if (count > SPECTRAL_SET_CAPACITY)
    throw Error("at most " + std::to_string(3 * SPECTRAL_SET_CAPACITY) + " working wavelengths are supported, got " +
                std::to_string(wavelengths.size()));
  InstantTables tables;
  tables.sizes = sizes;
  tables.wavelengths_nm = wavelengths;
  tables.multiple_scattering_mu_s = INSTANT_MS_MU_S_SIZE;
  tables.multiple_scattering_r = INSTANT_MS_R_SIZE;

  // The transmittance of every triple, true and delta-M scaled (the tiles of
  // Tables::spectral_optical_depth), and the part of the direct sunlight on
  // the ground that the scaled medium's forward δ carries, which is sky
  // light (as precompute.cpp: medium_of_orders).
  auto start = std::chrono::steady_clock::now();
  const int w = sizes.transmittance_mu, h = sizes.transmittance_r, tiles = 2 * count;
  tables.spectral_optical_depth.assign(size_t(w) * size_t(h) * size_t(tiles), glm::vec3(0.0f));
  std::vector<glm::vec3> forward_irradiance(size_t(sizes.irradiance_mu_s) * size_t(sizes.irradiance_r), glm::vec3(0.0f));
  for (int set = 0; set < count; ++set) {
    const AtmosphereParams a = physics::make_atmosphere_params(atmosphere, sizes, set);
    vec3 forward_fraction;
    const AtmosphereParams ms = physics::delta_scaled_params(a, forward_fraction);
    const bool scaled = forward_fraction.x > 0.0f || forward_fraction.y > 0.0f || forward_fraction.z > 0.0f;
    const precompute::Table2D transmittance = transmittance_table(a);
    const precompute::Table2D scaled_transmittance = scaled ? transmittance_table(ms) : transmittance;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t row = size_t(y) * size_t(w) * size_t(tiles) + size_t(x);
        tables.spectral_optical_depth[row + size_t(set) * size_t(w)] = transmittance.at(x, y);
        tables.spectral_optical_depth[row + size_t(count + set) * size_t(w)] = scaled_transmittance.at(x, y);
      }
    if (scaled) {
      const precompute::Table2D direct = precompute::compute_direct_irradiance_table(a, transmittance);
      const precompute::Table2D scaled_direct = precompute::compute_direct_irradiance_table(ms, scaled_transmittance);
      const glm::mat3 to_channels = physics::set_to_channels(wavelengths, set);
      for (size_t i = 0; i < forward_irradiance.size(); ++i)
        forward_irradiance[i] += to_channels * glm::max(scaled_direct.texels[i] - direct.texels[i], vec3(0.0f));
    }
  }
  tables.timings.push_back({"transmittance", seconds_since(start)});

  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, sizes);
  const physics::sampler2D optical_depth{w * tiles, h, tables.spectral_optical_depth.data()};

  // Ψ_ms of every triple, in its delta-M scaled medium (the medium of the
  // exact tables' orders >= 2), which reads the scaled tile.
  start = std::chrono::steady_clock::now();
  const int ms_w = INSTANT_MS_MU_S_SIZE, ms_h = INSTANT_MS_R_SIZE;
  tables.multiple_scattering.assign(size_t(ms_w) * size_t(count) * size_t(ms_h), glm::vec3(0.0f));
  for (int set = 0; set < count; ++set) {
    vec3 forward_fraction;
    AtmosphereParams medium = physics::delta_scaled_params(spectral->set[set], forward_fraction);
    medium.transmittance_tile = spectral->set[set].single_scattering_tile;
    parallel_rows(ms_h, [&](int y) {
      for (int x = 0; x < ms_w; ++x) {
        float r, mu_s;
        physics::instant_multiple_scattering_r_mu_s(medium, x, y, r, mu_s);
        tables.multiple_scattering[size_t(y) * size_t(ms_w * count) + size_t(set * ms_w + x)] =
            glm::vec3(multiple_scattering_texel(medium, optical_depth, r, mu_s));
      }
    });
  }
  tables.timings.push_back({"multiple_scattering", seconds_since(start)});

  // The sky irradiance on a horizontal surface at every (r, mu_s) of the
  // irradiance table's parameterisation: the instant mode's sky radiance
  // (its march, as the sky-view table's) times mu over the upper
  // hemisphere, plus the forward δ's light.
  start = std::chrono::steady_clock::now();
  const AtmosphereParams render = physics::make_render_params(atmosphere, sizes);
  const physics::sampler2D multiple{ms_w * count, ms_h, tables.multiple_scattering.data()};
  std::vector<double> up_nodes, up_weights;
  physics::gauss_legendre(kIrradianceMuNodes, 0.0, 1.0, up_nodes, up_weights);
  const int iw = sizes.irradiance_mu_s, ih = sizes.irradiance_r;
  tables.indirect_irradiance.assign(size_t(iw) * size_t(ih), glm::vec3(0.0f));
  parallel_rows(ih, [&](int y) {
    for (int x = 0; x < iw; ++x) {
      float r, mu_s;
      physics::r_mu_s_from_irradiance_uv(render, vec2((float(x) + 0.5f) / float(iw), (float(y) + 0.5f) / float(ih)),
                                         r, mu_s);
      const vec3 origin(0.0f, 0.0f, r);
      const vec3 sun(std::sqrt(std::max(0.0f, 1.0f - mu_s * mu_s)), 0.0f, mu_s);
      glm::dvec3 sum(0.0);
      for (size_t i = 0; i < up_nodes.size(); ++i) {
        const float mu = float(up_nodes[i]);
        const float sin_v = std::sqrt(std::max(0.0f, 1.0f - mu * mu));
        for (int j = 0; j < kIrradiancePhiNodes; ++j) {
          const float phi = float(M_PI * (double(j) + 0.5) / double(kIrradiancePhiNodes));
          const vec3 view_ray(sin_v * std::cos(phi), sin_v * std::sin(phi), mu);
          physics::InstantMarch m =
              physics::instant_march_begin(render, *spectral, optical_depth, multiple, origin, view_ray, sun, true);
          const float d = physics::distance_to_top_atmosphere_boundary(render, r, mu);
          for (int k = 1; k <= kIrradianceRayIntervals; ++k) {
            const float f = float(k) / float(kIrradianceRayIntervals);
            physics::instant_march_to(*spectral, optical_depth, multiple, m, d * f * f, 1, true);
          }
          vec3 single_rayleigh, multiple_light, aerosol, transmittance;
          physics::instant_march_light(render, *spectral, m, single_rayleigh, multiple_light, aerosol,
                                       transmittance);
          const vec3 radiance = physics::phase_weighted_scattering(render, single_rayleigh + multiple_light,
                                                                   aerosol, physics::dot(view_ray, sun));
          sum += glm::dvec3(radiance) * (double(mu) * up_weights[i] * 2.0 * M_PI / double(kIrradiancePhiNodes));
        }
      }
      const size_t index = size_t(y) * size_t(iw) + size_t(x);
      tables.indirect_irradiance[index] = glm::vec3(sum) + forward_irradiance[index];
    }
  });
  tables.timings.push_back({"sky_irradiance", seconds_since(start)});
  return tables;
}

void check_tables_match(const Atmosphere& atmosphere, const InstantTables& tables) {
  if (tables.wavelengths_nm != atmosphere.wavelengths_nm)
    throw Error("the instant tables were computed for other wavelengths than the atmosphere's");
  tables.sizes.validate();
  const TableSizes& s = tables.sizes;
  const int sets = tables.spectral_sets();
  if (tables.multiple_scattering_mu_s != INSTANT_MS_MU_S_SIZE || tables.multiple_scattering_r != INSTANT_MS_R_SIZE ||
      tables.spectral_optical_depth.size() !=
          size_t(s.transmittance_mu) * size_t(s.transmittance_r) * size_t(tables.transmittance_tiles()) ||
      tables.multiple_scattering.size() != size_t(INSTANT_MS_MU_S_SIZE) * size_t(INSTANT_MS_R_SIZE) * size_t(sets) ||
      tables.indirect_irradiance.size() != size_t(s.irradiance_mu_s) * size_t(s.irradiance_r))
    throw Error("the instant tables do not hold as many texels as their sizes say (not from compute_instant_tables?)");
}

}  // namespace atmos
