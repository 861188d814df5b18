// The measurements behind `atmos bench`, shared with the Google Benchmark
// binary (bench/benchmarks.cpp): the precomputation step by step, frames of
// the renderer, of the engine plugin over a synthetic engine frame and of
// the post-processing chain.
//
// Each measurement is a Figure, `atmos bench`'s line
// name<TAB>value<TAB>unit. Frame times are GPU times as the library reports
// them (Renderer::last_frame_ms, AtmospherePass::last_timings,
// PostProcess::last_timings; wall-clock times of the draw on software
// rasterisers such as llvmpipe), the median of a few frames after a warm-up
// frame that compiles the shader variant and makes the textures resident.
//
// OpenGL: the functions that take a Renderer, and PluginScene, need an
// OpenGL 4.5 context current on the calling thread (the library's rule,
// atmos/renderer.hpp); run_all creates its own.
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/plugin.hpp"
#include "atmos/renderer.hpp"
#include "atmos/tables.hpp"

namespace atmos_bench {

// One measured value: unit "s" (precomputation), "ms" (frames), "count"
// (triangles, tiles) or "ratio".
struct Figure {
  std::string name;
  double value = 0.0;
  std::string unit;
};

// `name<TAB>value<TAB>unit`: seconds and ratios with 3 decimals, milliseconds
// with 1, counts with none.
std::string format_figure(const Figure& figure);

// Receives each figure as soon as it is measured.
using FigureSink = std::function<void(const Figure&)>;

// The median (the upper one of an even count); `values` must not be empty.
double median(std::vector<double> values);

// Precomputes the tables and reports each step's time as
// `precompute.<step>` and the wall-clock total as `precompute.total`.
atmos::Tables time_precomputation(const atmos::Atmosphere& atmosphere, const atmos::PrecomputeOptions& options,
                                  const FigureSink& sink);

// The spectral precomputation: the atmosphere at 15 wavelengths with 6
// orders (the other options as given), its wall-clock time reported as
// `precompute.spectral15.orders6`. Returns the atmosphere it used in
// `spectral_atmosphere`.
atmos::Tables time_spectral_precomputation(const atmos::Atmosphere& atmosphere, const atmos::PrecomputeOptions& options,
                                           atmos::Atmosphere& spectral_atmosphere, const FigureSink& sink);

// The camera of the frame timings: 2 m above the ground, looking at
// azimuth 180°, 10° up, a 60° vertical field of view, width x height.
atmos::Camera frame_camera(const atmos::Atmosphere& atmosphere, int width, int height);

// One frame of `renderer`: its GPU time and that of its sky-view table, ms.
struct FrameTime {
  double frame_ms = 0.0;
  double sky_view_ms = 0.0;
};
FrameTime time_frame(atmos::Renderer& renderer, const atmos::Camera& camera, const glm::dvec3& sun_direction);

// A warm-up frame, then the medians of `runs` frames, reported as
// `<name>.<W>x<H>` (the frame) and `<name>.sky_view`.
void time_frames(atmos::Renderer& renderer, const atmos::Camera& camera, const glm::dvec3& sun_direction, int runs,
                 const std::string& name, const FigureSink& sink);

// A synthetic engine frame for the plugin: a camera 300 m above the ground
// looking 3° down, the engine's ground (the planet's sphere) and three round
// hills in a standard depth buffer (GL_DEPTH_COMPONENT32F) and a grey lit
// colour (RGBA16F); sky above. Owns its two textures.
class PluginScene {
 public:
  PluginScene(const atmos::Atmosphere& atmosphere, int width, int height);
  ~PluginScene();
  PluginScene(const PluginScene&) = delete;
  PluginScene& operator=(const PluginScene&) = delete;

  // The frame with the sun at (azimuth 20°, `sun_elevation_deg`) and, with
  // `eclipse`, a moon 0.28° wide in front of it (a total eclipse).
  atmos::FrameInput input(double sun_elevation_deg, bool eclipse) const;

 private:
  atmos::FrameInput input_;
  glm::dvec3 camera_{0.0};
  std::uint32_t textures_[2] = {0, 0};
};

// The plugin over PluginScene by day (sun 35° up: `plugin.*`), at sunset (4°:
// `plugin.sunset.*`, the low-sun variant) and in a total eclipse (35°:
// `plugin.eclipse.*`): the frame (`.<W>x<H>`) and its sky-view, volume and
// composite passes, medians of 5 frames.
void time_plugin(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables, int width, int height,
                 const FigureSink& sink);

// The instant approximate mode (InstantTables): precompute.instant (s,
// compute_instant_tables of `atmosphere` at the default sizes, median of 3),
// precompute.instant.spectral15 (the same at 15 wavelengths),
// plugin.instant.create (ms, the pass's construction: the upload and the
// compilation of its first variants) and the plugin over PluginScene by day
// and at sunset as time_plugin (`plugin.instant.*`, `plugin.instant.sunset.*`).
void time_instant(const atmos::Atmosphere& atmosphere, int width, int height, const FigureSink& sink);

// The post-processing chain over a frame of `renderer` (sun 12° up): the
// filmic operator, bloom (strength 0.05) and auto exposure, each pass's GPU
// time the median of 5 frames (`post.bloom.<W>x<H>`, `post.exposure.*`,
// `post.tonemap.*`).
// The tables' ground albedo response: precompute.ground_albedo_response
// (s, the tables with their response, never from the cache) and
// plugin.ground_albedo (ms, median of AtmospherePass::set_ground_albedo
// moving between two albedos: the CPU blend and the upload).
void time_ground_albedo(const atmos::Atmosphere& atmosphere, const atmos::PrecomputeOptions& options,
                        const FigureSink& sink);

void time_post(atmos::Renderer& renderer, const atmos::Camera& camera, const FigureSink& sink);

// The terrain globe (atmos::Globe, Earth style) under the atmosphere's
// plugin at width x height, from 2 m, 10 km, 400 km and 2.5 planet radii
// above the ground (`globe.2m.*`, `globe.10km.*`, `globe.400km.*`,
// `globe.2.5R.*`): the whole frame (the globe's draw and the pass,
// wall-clock up to glFinish), the terrain's draw alone, the CPU selection
// (the quadtree traversal and culling), drawn triangles and tiles; medians
// of 3 frames after one that generates the tiles. With the terrain's sun
// shadows (4 cascades of 2048^2 over 20 km) and the pass's light shafts
// from the farthest cascade, from 2 m and 10 km (`globe.2m.shadows.*`,
// `globe.10km.shadows.*`): the frame, the terrain (shadow maps included),
// the CPU time of the cascades' selections, and the triangles and tile
// draws into the shadow maps. Then a descent of 40 frames from 2.5 radii to
// 2 m with tiles streamed by the globe's background thread (at most
// GlobeSettings::max_tiles_per_frame uploads a frame) and the pass's
// programs for the flight linked and compiled by
// AtmospherePass::link_programs (ProgramScope::flight) in a context of
// `context`'s share group on another thread, the viewer's way:
// `globe.descent.first` (the new globe's first frame, with the driver's
// compilation of its programs), then over the other 39
// `globe.descent.median`, `.max` and `.max_over_median`.
void time_globe(atmos::GlContext& context, const atmos::Atmosphere& atmosphere, const atmos::Tables& tables,
                int width, int height, const FigureSink& sink);

// The sea (atmos::Ocean, Earth) over the globe at width x height, over the
// Pacific at 0°, 150° W from 2 m, 1 km and 400 km above the sea level
// (`water.2m.*`, `water.1km.*`, `water.400km.*`): the frame with the sea,
// the sea's own draw, the frame without it and the sea's share,
// frame / frame_without_sea - 1 (`.overhead`); medians of 3 frames after one
// that generates the tiles and compiles the programs.
void time_water(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables, int width, int height,
                const FigureSink& sink);

// Everything `atmos bench` reports, in its order: the precomputation of
// `atmosphere` with `options`, the spectral one, the renderer (sun 20° up;
// a total eclipse, sun 40° up, seen from the centre of the shadow; twilight
// with the spectral tables, sun 3° below the horizon), the plugin, the
// post-processing, the globe and the sea, frames of width x height. Creates a headless OpenGL
// context (atmos::Error without one).
void run_all(const atmos::Atmosphere& atmosphere, const atmos::PrecomputeOptions& options, int width, int height,
             const FigureSink& sink);

}  // namespace atmos_bench
