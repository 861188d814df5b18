// The precomputation pipeline (seed 004 §4.2, Bruneton & Neyret 2008 §4):
// transmittance, direct irradiance and single scattering, then for each
// scattering order n = 2..K the scattering density of order n, the sky
// irradiance of order n - 1 and the multiple scattering of order n.
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <string>

#include "atmos/tables.hpp"
#include "physics/parameters.hpp"
#include "precompute/steps.hpp"

namespace atmos {

void TableSizes::validate() const {
  auto check = [](int value, int minimum, const char* name) {
    if (value < minimum || value > 4096)
      throw Error(std::string("table size ") + name + " = " + std::to_string(value) + " is outside [" +
                  std::to_string(minimum) + ", 4096]");
  };
  check(transmittance_mu, 4, "transmittance_mu");
  check(transmittance_r, 4, "transmittance_r");
  check(irradiance_mu_s, 4, "irradiance_mu_s");
  check(irradiance_r, 2, "irradiance_r");
  check(scattering_nu, 2, "scattering_nu");
  check(scattering_mu_s, 4, "scattering_mu_s");
  check(scattering_mu, 8, "scattering_mu");
  check(scattering_r, 2, "scattering_r");
  if (scattering_mu % 2 != 0) throw Error("table size scattering_mu must be even (half below, half above the horizon)");
  const double texels = double(scattering_nu) * scattering_mu_s * scattering_mu * scattering_r;
  if (texels > 64.0 * 1024 * 1024) throw Error("scattering tables of more than 64 Mi texels are not supported");
}

Tables precompute_tables(const Atmosphere& atmosphere, const PrecomputeOptions& options) {
  using namespace precompute;
  using clock = std::chrono::steady_clock;
  atmosphere.validate();
  options.sizes.validate();
  const int K = options.scattering_orders;
  if (K < 1 || K > 100) throw Error("scattering orders must be in [1, 100], got " + std::to_string(K));

  Tables tables;
  tables.sizes = options.sizes;
  tables.scattering_orders = K;
  tables.wavelengths_nm = atmosphere.wavelengths_nm;
  const int set_count = int(atmosphere.wavelengths_nm.size() / 3);

  // Relative cost of the steps, for the progress fraction.
  const double cost_single = 1.0, cost_order = 1.6;
  const double cost_set = 0.05 + cost_single + cost_order * (K - 1);
  const double cost_total = cost_set * set_count;
  double cost_done = 0.0;
  auto report = [&](const std::string& step, double step_cost, double fraction) {
    if (options.progress) options.progress(step, std::min(1.0, (cost_done + step_cost * fraction) / cost_total));
  };

  auto timed = [&](const std::string& name, double step_cost, auto&& body) {
    const auto start = clock::now();
    report(name, step_cost, 0.0);
    body([&](double f) { report(name, step_cost, f); });
    cost_done += step_cost;
    report(name, 0.0, 0.0);
    const double seconds = std::chrono::duration<double>(clock::now() - start).count();
    // Steps of all sets and orders add up under one name.
    for (auto& t : tables.timings)
      if (t.name == name) {
        t.seconds += seconds;
        return;
      }
    tables.timings.push_back({name, seconds});
  };

  for (int set = 0; set < set_count; ++set) {
    const AtmosphereParams a = physics::make_atmosphere_params(atmosphere, options.sizes, set);
    Table2D transmittance, direct_irradiance, indirect_irradiance(a.irradiance_mu_s_size, a.irradiance_r_size);
    Table2D delta_irradiance;
    Table3D single_rayleigh, single_aerosol, delta_multiple, density;

    timed("transmittance", 0.03, [&](auto&&) { transmittance = compute_transmittance_table(a); });
    timed("direct_irradiance", 0.02, [&](auto&&) {
      direct_irradiance = compute_direct_irradiance_table(a, transmittance);
    });
    timed("single_scattering", cost_single, [&](auto&& progress) {
      compute_single_scattering_tables(a, transmittance, single_rayleigh, single_aerosol, progress);
    });
    Table3D multiple(single_rayleigh.width, single_rayleigh.height, single_rayleigh.depth);
    delta_multiple = Table3D(single_rayleigh.width, single_rayleigh.height, single_rayleigh.depth);

    for (int order = 2; order <= K; ++order) {
      timed("scattering_density", cost_order * 0.45, [&](auto&& progress) {
        density = compute_scattering_density_table(a, transmittance, single_rayleigh, single_aerosol, delta_multiple,
                                                   delta_irradiance, order - 1, progress);
      });
      timed("indirect_irradiance", cost_order * 0.05, [&](auto&&) {
        delta_irradiance = compute_indirect_irradiance_table(a, transmittance, single_rayleigh, single_aerosol,
                                                             delta_multiple, order - 1);
        for (size_t i = 0; i < indirect_irradiance.texels.size(); ++i)
          indirect_irradiance.texels[i] += delta_irradiance.texels[i];
      });
      timed("multiple_scattering", cost_order * 0.5, [&](auto&& progress) {
        delta_multiple = compute_multiple_scattering_table(a, density, progress);
        // Stored divided by the Rayleigh phase function so that one lookup and
        // one phase function at run time give single Rayleigh + all multiple
        // (the `scattering` table below).
        // The division uses the nu of the texel's tile, not the clamped nu
        // the texel was computed for: the run-time interpolation between
        // tiles weights them by their tile nu, and a clamped nu there makes
        // M / P_R jump between neighbours (17 % errors in the second order
        // towards the sun, measured against the reference).
        tbb::parallel_for(0, multiple.depth, [&](int z) {
          for (int y = 0; y < multiple.height; ++y)
            for (int x = 0; x < multiple.width; ++x) {
              const float tile_nu = physics::scattering_texel_tile_nu(a, vec3(float(x), float(y), float(z)));
              multiple.at(x, y, z) += delta_multiple.at(x, y, z) / physics::rayleigh_phase_function(tile_nu);
            }
        });
      });
    }

    Table3D scattering = single_rayleigh;
    for (size_t i = 0; i < scattering.texels.size(); ++i) scattering.texels[i] += multiple.texels[i];

    TableSet out;
    out.transmittance = std::move(transmittance.texels);
    out.direct_irradiance = std::move(direct_irradiance.texels);
    out.indirect_irradiance = std::move(indirect_irradiance.texels);
    out.scattering = std::move(scattering.texels);
    out.single_aerosol = std::move(single_aerosol.texels);
    out.multiple_scattering = std::move(multiple.texels);
    tables.sets.push_back(std::move(out));
  }
  return tables;
}

}  // namespace atmos
