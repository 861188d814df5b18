// atmos view: one planet drawn as an engine draws it with atmos — the
// terrain globe (atmos::Globe) or nothing (the engine plugin's analytic
// sphere) into an HDR colour and reversed-Z depth target, then
// atmos::AtmospherePass for the aerial perspective, the sky, the sun, the
// stars and the moons. Only the public API of include/atmos is used.
//
// A Scene holds one set of tables; new tables (computed on another
// thread, tables_job.hpp) are swapped in by prepare_rebind() and
// finish_rebind() over the same ground, else by a new Scene. Construct, use and destroy it with the viewer's
// OpenGL 4.5 context current.
#pragma once

#include <epoxy/gl.h>

#include <array>
#include <memory>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/globe.hpp"
#include "atmos/plugin.hpp"
#include "atmos/tables.hpp"
#include "flight.hpp"
#include "state.hpp"

namespace atmos_view {

// The tables of one planet and what they were computed for: the product
// of a TableJob, the input of a Scene.
struct PlanetTables {
  PlanetParams params;
  atmos::Atmosphere planet;  // the planet's atmosphere (the globe's datum is its bottom radius)
  atmos::Atmosphere air;     // the pass's: `planet` continued below the datum to the lowest ground
  atmos::PlanetSurface surface;
  atmos::Tables tables;
  double seconds = 0.0;  // to load or compute them
  std::string status;    // "loaded from cache ..." or "computed ..."
};

// The inputs of one frame.
struct SceneFrame {
  CameraPose pose;
  double fov_deg = 60.0;
  int width = 0, height = 0;
  glm::dvec3 sun{0, 0, 1};
  bool stars = false;
  std::vector<atmos::Moon> moons;
  bool timed = false;  // GPU times of the pass (waits for the GPU at its end)
};

class Scene {
 public:
  // The engine's colour is radiance in cd/m² divided by this.
  static constexpr double kNitsPerUnit = 1000.0;

  // `globe`: the planet file's terrain globe (else the analytic sphere);
  // `regional_albedo`: the air lit by the globe's ground around the camera
  // (the tables must hold their ground albedo response);
  // `complete_tiles`: every tile a view needs is built before it is drawn
  // (stills, replays: the image does not depend on the machine's speed),
  // else the globe streams them from its thread.
  Scene(const PlanetTables& tables, bool globe, bool regional_albedo, bool complete_tiles);
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // New tables of the same ground (the same surface on the same datum
  // radius) are taken without a new globe, in two steps on two frames so
  // that no frame pays for both: prepare_rebind builds their pass (the
  // scene still draws with the old one), finish_rebind binds the globe to it
  // (atmos::Globe::rebind, its tiles kept) and the scene draws with it from
  // then on. prepare_rebind returns false, with the scene unchanged, when
  // the ground differs or the scene has no globe (build a new Scene then);
  // both throw atmos::Error as the constructor, leaving the old tables.
  bool prepare_rebind(const PlanetTables& tables);
  bool rebind_pending() const { return next_pass_ != nullptr; }
  void finish_rebind();

  // Draws the frame; returns the composited HDR texture (RGBA32F, valid
  // until the next render or the scene's destruction).
  GLuint render(const SceneFrame& frame);

  // Height of the ground above the datum below a planet-centred position, m.
  double ground_height_m(const glm::dvec3& position) const;
  double bottom_radius_m() const { return planet_.bottom_radius_m; }
  double top_radius_m() const { return planet_.top_radius_m; }
  const atmos::Atmosphere& planet() const { return planet_; }
  const PlanetParams& params() const { return params_; }
  bool has_globe() const { return globe_ != nullptr; }
  const atmos::GlobeStats* globe_stats() const;

  // GPU time of the terrain (a GL_TIME_ELAPSED query, read back a few
  // frames later so that it never waits), ms; NaN until the first result.
  double terrain_ms() const { return terrain_ms_; }
  const atmos::PassTimings& pass_timings() const;

 private:
  void ensure_targets(int width, int height);
  void release_targets();

  PlanetParams params_;
  atmos::Atmosphere planet_;
  atmos::PlanetSurface surface_;
  std::unique_ptr<atmos::AtmospherePass> pass_;
  // A prepared rebind: the new tables' pass and what goes with it.
  std::unique_ptr<atmos::AtmospherePass> next_pass_;
  PlanetParams next_params_;
  atmos::Atmosphere next_planet_;
  bool next_regional_albedo_ = false;
  std::unique_ptr<atmos::Globe> globe_;
  bool regional_albedo_requested_ = false, regional_albedo_ = false;
  int width_ = 0, height_ = 0;
  GLuint colour_ = 0, depth_ = 0, output_ = 0, framebuffer_ = 0;
  // A ring of timer queries: query i is read once the frame after next
  // has begun, when the GPU has long finished it.
  static constexpr int kQueries = 4;
  std::array<GLuint, kQueries> queries_{};
  std::array<bool, kQueries> query_pending_{};
  int query_next_ = 0;
  double terrain_ms_;
};

}  // namespace atmos_view
