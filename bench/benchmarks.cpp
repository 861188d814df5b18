// Google Benchmark targets over the measurements of `atmos bench`
// (harness.hpp), for repeated runs with statistics, e.g.
//   atmos_benchmarks --benchmark_repetitions=5
// The frame benchmarks report the library's GPU times as manual time (the
// wall-clock time of the draw on llvmpipe); they share one headless OpenGL
// context and the default Earth tables, computed once.
#include <benchmark/benchmark.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <memory>

#include "atmos/eclipse.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "harness.hpp"
#include "planet/tile_selection.hpp"

namespace {

// The headless OpenGL context of every benchmark, created at the first use.
atmos::GlContext& gl_context() {
  static const std::unique_ptr<atmos::GlContext> context = atmos::GlContext::create_headless();
  return *context;
}

// The default Earth tables and the OpenGL context, built at the first use.
struct Scene {
  atmos::Atmosphere atmosphere = atmos::load_atmosphere("earth");
  atmos::Tables tables = atmos::precompute_tables(atmosphere, atmos::PrecomputeOptions{});
  atmos::GlContext& context = gl_context();
};

Scene& scene() {
  static Scene s;
  return s;
}

void BM_PrecomputeEarthDefault(benchmark::State& state) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  atmos::PrecomputeOptions options;
  options.scattering_orders = int(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(atmos::precompute_tables(earth, options));
}
BENCHMARK(BM_PrecomputeEarthDefault)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// A renderer frame (`atmos bench`'s render.WxH), arguments width and height;
// the sky-view table's part as a counter.
void BM_RenderFrame(benchmark::State& state) {
  Scene& s = scene();
  atmos::Renderer renderer(s.atmosphere, s.tables);
  const atmos::Camera camera = atmos_bench::frame_camera(s.atmosphere, int(state.range(0)), int(state.range(1)));
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(150.0, 20.0);
  (void)atmos_bench::time_frame(renderer, camera, sun);  // warm-up
  double sky_view_ms = 0.0;
  for (auto _ : state) {
    const atmos_bench::FrameTime t = atmos_bench::time_frame(renderer, camera, sun);
    state.SetIterationTime(t.frame_ms / 1000.0);
    sky_view_ms += t.sky_view_ms;
  }
  state.counters["sky_view_ms"] = benchmark::Counter(sky_view_ms, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_RenderFrame)->Args({1920, 1080})->Unit(benchmark::kMillisecond)->UseManualTime();

// The engine plugin over the synthetic engine frame (`atmos bench`'s
// plugin.WxH by day, sun 35° up); its passes' parts as counters.
void BM_PluginFrame(benchmark::State& state) {
  Scene& s = scene();
  const int w = int(state.range(0)), h = int(state.range(1));
  const atmos_bench::PluginScene plugin_scene(s.atmosphere, w, h);
  atmos::AtmospherePass pass(s.atmosphere, s.tables, atmos::PlanetFrame{});
  const atmos::FrameInput input = plugin_scene.input(35.0, false);
  pass.render(input);  // warm-up
  double sky_view_ms = 0.0, volume_ms = 0.0, composite_ms = 0.0;
  for (auto _ : state) {
    pass.render(input);
    const atmos::PassTimings& t = pass.last_timings();
    state.SetIterationTime(t.total_ms() / 1000.0);
    sky_view_ms += t.sky_view_ms;
    volume_ms += t.volume_ms;
    composite_ms += t.composite_ms;
  }
  state.counters["sky_view_ms"] = benchmark::Counter(sky_view_ms, benchmark::Counter::kAvgIterations);
  state.counters["volume_ms"] = benchmark::Counter(volume_ms, benchmark::Counter::kAvgIterations);
  state.counters["composite_ms"] = benchmark::Counter(composite_ms, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_PluginFrame)->Args({1920, 1080})->Unit(benchmark::kMillisecond)->UseManualTime();

// `atmos bench`'s figures of the instant approximate mode (harness.hpp:
// time_instant) over Earth, arguments width and height, each as a counter
// (s for the tables, ms for the pass).
void BM_InstantMode(benchmark::State& state) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  gl_context();
  for (auto _ : state)
    atmos_bench::time_instant(earth, int(state.range(0)), int(state.range(1)),
                              [&](const atmos_bench::Figure& f) { state.counters[f.name] = f.value; });
}
BENCHMARK(BM_InstantMode)->Args({1920, 1080})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// `atmos bench`'s figures of the sea over the globe (harness.hpp:
// time_water), arguments width and height, each as a counter (ms, and the
// sea's share of the frame).
void BM_Water(benchmark::State& state) {
  Scene& s = scene();
  for (auto _ : state)
    atmos_bench::time_water(s.atmosphere, s.tables, int(state.range(0)), int(state.range(1)),
                            [&](const atmos_bench::Figure& f) { state.counters[f.name] = f.value; });
}
BENCHMARK(BM_Water)->Args({1920, 1080})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// The globe's tile selection on the CPU (src/planet/tile_selection.hpp):
// Earth (6360 km, heights -430..8848 m, no per-tile height ranges), error
// 0.1 x vertex spacing plus the sagitta, 1 px at 1080 p, 60 degree field of
// view; argument the altitude in m, looking at the horizon below 1 km, 20
// degrees down at 400 km, straight down above. Counters: tiles selected and
// quadtree nodes visited.
void BM_SelectTiles(benchmark::State& state) {
  constexpr double radius = 6360e3, pi = 3.14159265358979323846;
  const double altitude = double(state.range(0));
  atmos::planet::ReliefBounds bounds;
  bounds.radius_m = radius;
  bounds.min_height_m = -430.0;
  bounds.max_height_m = 8848.0;
  bounds.error_m = [](double spacing) { return 0.1 * spacing + spacing * spacing / (8.0 * radius); };
  const double pitch = (altitude < 1e3 ? 0.0 : altitude < 1e6 ? -20.0 : -90.0) * pi / 180.0;
  const glm::dvec3 up(0.0, 0.0, 1.0), north(0.0, 1.0, 0.0);
  const glm::dvec3 forward = std::cos(pitch) * north + std::sin(pitch) * up;
  atmos::planet::LodCamera camera;
  camera.position = up * (radius + altitude);
  camera.view_projection = glm::perspective(pi / 3.0, 16.0 / 9.0, 0.05, 1e9) *
                           glm::lookAt(camera.position, camera.position + forward, pitch < -1.5 ? north : up);
  camera.viewport_height_px = 1080.0;
  camera.tan_half_fov_y = std::tan(pi / 6.0);
  atmos::planet::Selection selection;
  for (auto _ : state) {
    selection = atmos::planet::select_tiles(camera, atmos::planet::LodSettings{}, bounds);
    benchmark::DoNotOptimize(selection.tiles.data());
  }
  state.counters["tiles"] = double(selection.tiles.size());
  state.counters["nodes"] = double(selection.nodes_visited);
}
BENCHMARK(BM_SelectTiles)->Arg(1)->Arg(10000)->Arg(400000)->Arg(9540000)->Arg(15900000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
