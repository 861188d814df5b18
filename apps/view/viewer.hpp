// atmos view: the interactive viewer (a GLFW window with a Dear ImGui
// panel) and the headless replay of its recorded flights. docs/viewer.md.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "state.hpp"
#include "tables_job.hpp"

namespace atmos_view {

// Stereo in the window: each eye through its own off-axis frustum
// (atmos::stereo_eyes), the two images side by side (each eye half the
// window's width) or as a red-cyan anaglyph.
struct StereoSettings {
  enum class Mode { none, side_by_side, anaglyph };
  Mode mode = Mode::none;
  double interpupillary_m = 0.064;  // (0, 1e7]
  double convergence_m = 10.0;      // > 0, may be infinite
};

struct ViewOptions {
  PlanetParams planet;
  CacheConfig cache;
  bool globe = true;           // --surface globe (else the analytic sphere)
  bool planet_albedo = false;  // --planet-albedo
  // While tables that are not in the cache are computed, draw the instant
  // mode's (computed in a fraction of a second) instead of the old ones
  // (--no-instant-preview: off).
  bool instant_preview = true;
  int width = 1280, height = 720;
  // Where the camera starts: above this ground point, looking along the
  // heading (degrees from north towards east) and pitch.
  double latitude_deg = 20.0, longitude_deg = 30.0, altitude_m = 2.0;
  double heading_deg = 90.0, pitch_deg = 0.0;
  double sun_elevation_deg = 30.0, sun_azimuth_deg = 180.0;  // at the starting ground point
  LookSettings look;
  // The Moon of a date (atmos view --date): the vector from the starting
  // ground point to its centre, m, planet frame (atmos::SkyBody::topocentric_m).
  std::optional<glm::dvec3> moon_of_date_m;
  bool ui = true;          // the panel
  int frames = 0;          // > 0: draw this many frames, then exit
  // With frames: the last frame (.png: the window as shown; .exr: the linear image).
  std::vector<std::string> screenshots;
  std::string record;      // the flight, written at exit
  std::string script;      // scripted input (docs/viewer.md, Scripts)
  std::string replay;      // a recorded flight to replay headless
  std::string output_dir;  // the replay's frames
  std::string frame_format = "png";  // the replay's: png, exr or both
  StereoSettings stereo;
  bool xr = false;      // draw for an OpenXR headset (xr.hpp) instead of the window
  std::string xr_mock;  // draw for the mock headset of this file, headless, its eyes into output_dir
};

// The viewer's window until it is closed (or `frames` are drawn). Throws
// atmos::Error for no display, no OpenGL 4.5 window, bad files.
int run_viewer(const ViewOptions& options);
// Replays options.replay headless into options.output_dir.
int run_replay(const ViewOptions& options);
// Draws for a headset (options.xr: OpenXR's, which fails with atmos::Error
// before any window opens when no runtime or headset is there;
// options.xr_mock: the mock's, headless, each eye's last image written to
// options.output_dir as eye-left and eye-right .png/.exr) until its session
// ends or options.frames are drawn.
int run_headset(const ViewOptions& options);

}  // namespace atmos_view
