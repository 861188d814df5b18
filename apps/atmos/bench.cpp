// atmos bench: precomputation and frame times as name<TAB>value<TAB>unit
// lines, measured by the benchmark harness (bench/harness.hpp).
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "harness.hpp"
#include "view_bench.hpp"

namespace atmos_cli {

namespace {

struct BenchOptions {
  PlanetOptions planet;
  TableOptions tables;
  SizeOption size{"1920x1080"};
};

int run_bench(const BenchOptions& o) {
  o.planet.validate();
  o.tables.validate();
  const auto [w, h] = o.size.parse();
  const atmos::Atmosphere atmosphere = o.planet.atmosphere();
  const auto print = [](const atmos_bench::Figure& figure) {
    std::printf("%s\n", atmos_bench::format_figure(figure).c_str());
    std::fflush(stdout);
  };
  atmos_bench::run_all(atmosphere, o.tables.precompute_options(), w, h, print);
  view_bench(o.planet.planet, print);
  return 0;
}

}  // namespace

Command add_bench_command(CLI::App& app) {
  auto o = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Time the library and print name<TAB>value<TAB>unit lines: each precomputation step of the tables "
      "(precompute.*, s; always computed, never from the cache), 15-wavelength tables with 6 orders, and the GPU "
      "times (ms, medians after a warm-up) of the renderer's frames (by day, in a total eclipse, at twilight with "
      "the spectral tables), of the engine plugin (by day, at sunset, in a total eclipse) and of its instant "
      "approximate mode (plugin.instant.*; its tables: precompute.instant.*), of the post-processing passes, and of "
      "the terrain globe under the plugin (globe.*: the frame, the terrain, the CPU selection, triangles and "
      "tiles from 2 m, 10 km, 400 km and 2.5 planet radii; the longest over the "
      "median frame of a streamed descent) and of the sea over it (water.*: the sea's draw and the frame with and "
      "without it from 2 m, 1 km and 400 km), and of the viewer at 1280x720 (view.*: its median frame over the "
      "analytic sphere and the globe, its first frame with a cold shader cache)");
  o->planet.add(*cmd);
  o->tables.add(*cmd);
  o->size.add(*cmd, "Size of the timed frames (the frame figures are named after it)");
  return {cmd, [o] { return run_bench(*o); }};
}

}  // namespace atmos_cli
