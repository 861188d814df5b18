// atmos precompute: build the tables (or find them valid in the cache) and
// print what they are and how long each step took.
#include <chrono>
#include <cstdio>
#include <memory>

#include "commands.hpp"

namespace atmos_cli {

namespace {

struct PrecomputeCommandOptions {
  PlanetOptions planet;
  TableOptions tables;
  CacheOptions cache;
};

int run_precompute(const PrecomputeCommandOptions& o) {
  o.planet.validate();
  o.tables.validate();
  const auto start = std::chrono::steady_clock::now();
  const LoadedTables loaded = load_tables(o.planet, o.tables, o.cache, true);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const atmos::TableSizes& s = loaded.tables.sizes;
  std::printf("planet          %s\n", loaded.atmosphere.name.c_str());
  std::printf("wavelengths     ");
  for (double w : loaded.tables.wavelengths_nm) std::printf("%g ", w);
  std::printf("nm\norders          %d\n", loaded.tables.scattering_orders);
  std::printf("transmittance   %d x %d (mu x r)\n", s.transmittance_mu, s.transmittance_r);
  std::printf("irradiance      %d x %d (mu_s x r), direct and indirect\n", s.irradiance_mu_s, s.irradiance_r);
  std::printf("scattering      %d x %d x %d x %d (nu x mu_s x mu x r), stored as 3D %d x %d x %d, Rayleigh+multiple and single aerosol\n",
              s.scattering_nu, s.scattering_mu_s, s.scattering_mu, s.scattering_r, loaded.tables.scattering_width(),
              loaded.tables.scattering_height(), loaded.tables.scattering_depth());
  std::printf("channels        %s\n", loaded.tables.wavelengths_nm.size() == 3
                                         ? "the three wavelengths"
                                         : "linear sRGB (spectral precomputation, CIE 1931 2 deg observer)");
  std::printf("cache           %s\n", loaded.status.c_str());
  for (const auto& c : loaded.tables.convergence) {
    if (c.tail)
      std::printf("orders %d+      add %.3e of all the light (solved at once: %d GMRES steps, residual %.1e)\n",
                  c.order, c.relative, c.iterations, c.residual);
    else
      std::printf("order %-3d       adds %.3e of the light gathered so far\n", c.order, c.relative);
  }
  if (loaded.tables.timings.empty()) std::printf("steps           none computed: the cache file is valid\n");
  for (const auto& step : loaded.tables.timings) std::printf("time %-22s %8.3f s\n", step.name.c_str(), step.seconds);
  std::printf("time total                   %8.3f s\n", seconds);
  return 0;
}

}  // namespace

Command add_precompute_command(CLI::App& app) {
  auto o = std::make_shared<PrecomputeCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "precompute",
      "Build the tables, or find them valid in the cache, and print the planet, the working wavelengths, the table "
      "sizes, the cache status, what each scattering order added and the time of each step");
  o->planet.add(*cmd);
  o->tables.add(*cmd);
  o->cache.add(*cmd);
  return {cmd, [o] { return run_precompute(*o); }};
}

}  // namespace atmos_cli
