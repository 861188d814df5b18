// atmos plot-data: the CSV files behind scripts/plots.py (plot_data.hpp).
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "plot_data.hpp"

namespace atmos_cli {

namespace {

struct PlotDataOptions {
  PlanetOptions planet;
  TableOptions tables;
  CacheOptions cache;
  std::string out;
};

int run_plot_data(const PlotDataOptions& o) {
  namespace pd = atmos_cli::plot_data;
  // Options and the output directory first: a bad value or path is reported
  // before the precomputation.
  o.tables.validate();
  const atmos::Atmosphere atmosphere = o.planet.atmosphere();
  pd::prepare_directory(o.out);
  auto wrote = [](const std::string& path) {
    std::printf("wrote %s\n", path.c_str());
    std::fflush(stdout);
  };
  wrote(pd::write_csv(o.out, "solar.csv", [&](std::ostream& s) { pd::write_solar(s, atmosphere); }));
  wrote(pd::write_csv(o.out, "extinction.csv", [&](std::ostream& s) { pd::write_extinction(s, atmosphere); }));
  wrote(pd::write_csv(o.out, "transmittance.csv", [&](std::ostream& s) { pd::write_transmittance(s, atmosphere); }));
  const LoadedTables loaded = load_tables(o.planet, o.tables, o.cache, true);
  wrote(pd::write_csv(o.out, "sky.csv", [&](std::ostream& s) { pd::write_sky(s, loaded.atmosphere, loaded.tables); }));
  wrote(pd::write_csv(o.out, "convergence.csv", [&](std::ostream& s) { pd::write_convergence(s, loaded.tables); }));
  const std::string solar = o.planet.solar.empty() ? std::string("planet file") : o.planet.solar;
  const pd::Info info{o.planet.planet, o.tables.sizes, solar, o.planet.density_scale};
  wrote(pd::write_csv(o.out, "info.csv", [&](std::ostream& s) {
    pd::write_info(s, loaded.atmosphere, info, loaded.tables.scattering_orders);
  }));
  return 0;
}

}  // namespace

Command add_plot_data_command(CLI::App& app) {
  auto o = std::make_shared<PlotDataOptions>();
  CLI::App* cmd = app.add_subcommand(
      "plot-data",
      "Write the CSV files behind the plots into a directory: info, solar spectrum, extinction per constituent, "
      "transmittance, sky luminance in the sun's vertical plane and the convergence of the orders; "
      "scripts/plots.py draws them");
  o->planet.add(*cmd);
  o->tables.add(*cmd);
  o->cache.add(*cmd);
  cmd->add_option("--out", o->out, "Output directory (created if missing; its parent must exist)")
      ->type_name("DIR")
      ->required();
  return {cmd, [o] { return run_plot_data(*o); }};
}

}  // namespace atmos_cli
