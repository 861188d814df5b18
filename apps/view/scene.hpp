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

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/globe.hpp"
#include "atmos/image.hpp"
#include "atmos/post.hpp"
#include "atmos/plugin.hpp"
#include "atmos/stereo.hpp"
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
  // The instant mode's tables (Hillaire 2020, docs/instant.md) instead of
  // `tables` (then empty): what a scene draws while the exact tables are
  // computed.
  std::optional<atmos::InstantTables> instant;
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
  // `programs`: which of the pass's programs are compiled before the
  // constructor returns (atmos::PassPrograms; the others at their first
  // draw, or by link_programs beforehand).
  // `early`: a frame whose pass programs are linked on a thread of the
  // scene's own, in a context that shares the scene's objects, from the
  // moment the pass exists (while the globe is built on this thread) until
  // join_linker().
  struct EarlyLink {
    // Makes that context current on the calling thread (true), or none (false).
    std::function<void(bool current)> make_current;
    SceneFrame frame;
  };
  Scene(const PlanetTables& tables, bool globe, bool regional_albedo, bool complete_tiles,
        atmos::PassPrograms programs = atmos::PassPrograms::common, const EarlyLink* early = nullptr);
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
  // With `early`, prepare_rebind builds the new pass without programs and
  // links those of early->frame on the scene's thread (as the
  // constructor's `early`); finish_rebind waits for it (see linking()).
  bool prepare_rebind(const PlanetTables& tables, const EarlyLink* early = nullptr);
  bool rebind_pending() const { return next_pass_ != nullptr; }
  void finish_rebind();
  // Whether the scene's thread is still linking programs (the early link
  // of the constructor or of prepare_rebind).
  bool linking() const { return linking_.load(); }
  // Whether the pass that draws from the next frame on (the rebind's, if
  // one is pending) has linked every program of `frame`.
  bool programs_linked(const SceneFrame& frame) const;

  // Links the pass's programs that render(frame) draws with, without
  // drawing (atmos::AtmospherePass::link_programs): callable from several
  // threads at once, each with a current context that shares objects with
  // the scene's, while no thread draws the scene.
  void link_programs(const SceneFrame& frame) const;
  // The pass's input of `frame` for link_programs on another thread: its
  // textures (read on this thread, the GL one) are the scene's targets
  // where they have the frame's size, so that the programs are compiled for
  // their formats (AtmospherePass::link_programs).
  atmos::FrameInput link_input(const SceneFrame& frame) const;
  void link_programs(const atmos::FrameInput& input) const;
  // Waits for the early link's thread; rethrows its error.
  void join_linker();

  // Draws the frame; returns the composited HDR texture (RGBA32F, valid
  // until the next render or the scene's destruction).
  GLuint render(const SceneFrame& frame);
  // Draws the frame for two eyes, each frame.width x frame.height pixels
  // through its own pose and four angles (frame.pose and fov_deg are not
  // used): the globe's tiles chosen once for both, from the frustum that
  // covers them (atmos::covering_eye, Globe::draw_views), then the pass in
  // each eye, whose sky, sun and aerial perspective follow that eye's
  // inverse projection. The regional albedo is taken at the eyes' midpoint.
  // Returns each eye's composited HDR texture (as render()'s).
  std::array<GLuint, 2> render_eyes(const SceneFrame& frame, const std::array<atmos::Eye, 2>& eyes);
  // The reversed-Z depth of the last render (eye 0) or render_eyes (eye 0,
  // 1): GL_DEPTH_COMPONENT32F, the globe's (0 where no ground was drawn).
  GLuint depth_texture(int eye) const { return targets_[size_t(eye)].depth; }
  // The projection's near plane, m (reversed-Z: depth = near / distance
  // along the view axis).
  static constexpr double kNearM = 0.05;

  // Height of the ground above the datum below a planet-centred position, m.
  double ground_height_m(const glm::dvec3& position) const;
  double bottom_radius_m() const { return planet_.bottom_radius_m; }
  double top_radius_m() const { return planet_.top_radius_m; }
  const atmos::Atmosphere& planet() const { return planet_; }
  const PlanetParams& params() const { return params_; }
  bool has_globe() const { return globe_ != nullptr; }
  // Whether the scene draws with the instant mode's tables.
  bool instant() const { return pass_->instant(); }
  const atmos::GlobeStats* globe_stats() const;

  // GPU time of the terrain (a GL_TIME_ELAPSED query, read back a few
  // frames later so that it never waits), ms; NaN until the first result.
  double terrain_ms() const { return terrain_ms_; }
  const atmos::PassTimings& pass_timings() const;

 private:
  // An eye's render targets: the engine's colour and depth, the pass's output.
  struct Targets {
    int width = 0, height = 0;
    GLuint colour = 0, depth = 0, output = 0, framebuffer = 0;
  };
  void ensure_targets(Targets& t, int width, int height);
  void release_targets(Targets& t);
  // Reads the oldest timer query of the ring, then times the next globe draw.
  GLuint next_query();
  GLuint composite(const SceneFrame& f, Targets& t, const glm::dmat4& view, const glm::dmat4& projection);

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
  std::array<Targets, 2> targets_;
  // A ring of timer queries: query i is read once the frame after next
  // has begun, when the GPU has long finished it.
  static constexpr int kQueries = 4;
  std::array<GLuint, kQueries> queries_{};
  std::array<bool, kQueries> query_pending_{};
  int query_next_ = 0;
  double terrain_ms_;
  // Links the programs of early.frame in `pass` on linker_, and with
  // `globe_programs` the globe's for a rebind to `pass`.
  void start_linker(atmos::AtmospherePass& pass, const EarlyLink& early, bool globe_programs);
  // The early link's thread, whether it runs, and its error.
  std::thread linker_;
  std::atomic<bool> linking_{false};
  std::exception_ptr linker_error_;
};

// Reverses the order of the rows of an RGB image (GL's rows are
// bottom-up, atmos::Image's and DisplayImage's top-down).
template <typename T>
void flip_rows(std::vector<T>& rgb, int width, int height) {
  const size_t row = size_t(width) * 3;
  for (size_t y = 0; y < size_t(height) / 2; ++y)
    std::swap_ranges(rgb.begin() + std::ptrdiff_t(y * row), rgb.begin() + std::ptrdiff_t((y + 1) * row),
                     rgb.begin() + std::ptrdiff_t((size_t(height) - 1 - y) * row));
}

// A scene's HDR texture as an image in cd/m², rows top-down.
atmos::Image read_hdr(GLuint texture, int width, int height);
// An srgb8 texture (PostProcess's output) as a display image, rows top-down.
atmos::DisplayImage read_display(GLuint texture, int width, int height);

}  // namespace atmos_view
