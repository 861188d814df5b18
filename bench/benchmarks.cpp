// Google Benchmark targets: precomputation of the default Earth tables.
// `atmos bench` prints the per-step figures; these allow repeated runs with
// statistics (e.g. --benchmark_repetitions=5).
#include <benchmark/benchmark.h>

#include "atmos/tables.hpp"

static void BM_PrecomputeEarthDefault(benchmark::State& state) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  atmos::PrecomputeOptions options;
  options.scattering_orders = int(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(atmos::precompute_tables(earth, options));
}
BENCHMARK(BM_PrecomputeEarthDefault)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

BENCHMARK_MAIN();
