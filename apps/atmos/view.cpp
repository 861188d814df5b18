// atmos view: the interactive viewer (apps/view/, docs/viewer.md). A window
// with the planet drawn as an engine draws it (the terrain globe or the
// analytic sphere under the engine plugin, then the post-processing), a
// panel that changes any setting live, flying from the ground to orbit,
// screenshots, recorded flights and their headless replay.
#include <cctype>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "atmos/ephemeris.hpp"
#include "commands.hpp"
#include "options.hpp"

#ifdef ATMOS_VIEWER
#include "viewer.hpp"
#endif

namespace atmos_cli {

namespace {

struct ViewCommandOptions {
  PlanetOptions planet;
  TableOptions tables;
  CacheOptions cache;
  SurfaceOption surface;
  SunOptions sun;
  DateOptions date;
  int width = 1280, height = 720;
  double altitude = 2.0, latitude = 20.0, longitude = 30.0, heading = 90.0, pitch = 0.0;
  double exposure = 13.0, bloom = 0.0, fov = 60.0;
  bool auto_exposure = false, stars = false, no_ui = false, no_instant_preview = false;
  std::string tonemap = "exp";
  int frames = 0;
  std::vector<std::string> screenshots;
  std::string record, script, replay, output_dir, frame_format = "png";
  StereoOptions stereo;
  bool xr = false;
  std::string xr_mock;
};

bool ends_with(const std::string& s, const std::string& tail) {
  if (s.size() < tail.size()) return false;
  for (size_t i = 0; i < tail.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[s.size() - tail.size() + i])) != tail[i]) return false;
  return true;
}

void check_options(const ViewCommandOptions& o) {
  o.planet.validate();
  o.tables.validate();
  if (o.tables.orders == "auto") throw UsageError("--orders: atmos view takes a fixed number of orders, not auto");
  o.sun.validate();
  if (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192)
    throw UsageError("--width and --height must be in [16, 8192], got " + std::to_string(o.width) + "x" +
                     std::to_string(o.height));
  finite(o.altitude, "--altitude");
  if (o.altitude < 0.0 || o.altitude > 1e12)
    throw UsageError("--altitude must be in [0, 1e12] metres, got " + quote(o.altitude));
  if (!(std::abs(finite(o.latitude, "--latitude")) <= 90.0))
    throw UsageError("--latitude must be in [-90, 90] degrees, got " + quote(o.latitude));
  finite(o.longitude, "--longitude");
  finite(o.heading, "--heading");
  if (!(std::abs(finite(o.pitch, "--pitch")) <= 89.5))
    throw UsageError("--pitch must be in [-89.5, 89.5] degrees, got " + quote(o.pitch));
  finite(o.exposure, "--exposure");
  if (!(finite(o.bloom, "--bloom") >= 0.0 && o.bloom <= 1.0)) throw UsageError("--bloom must be in [0, 1], got " + quote(o.bloom));
  if (!(finite(o.fov, "--fov") >= 5.0 && o.fov <= 120.0)) throw UsageError("--fov must be in [5, 120] degrees, got " + quote(o.fov));
  if (o.frames < 0) throw UsageError("--frames must be >= 0, got " + std::to_string(o.frames));
  for (const std::string& path : o.screenshots)
    if (!ends_with(path, ".png") && !ends_with(path, ".exr"))
      throw UsageError("--screenshot must name a .png or .exr file, got \"" + path + "\"");
  if (!o.screenshots.empty() && o.frames == 0)
    throw UsageError("--screenshot needs --frames N (the frame saved is the last)");
  if (!o.replay.empty() && o.output_dir.empty()) throw UsageError("--replay needs --output-dir");
  if (!o.xr_mock.empty() && o.output_dir.empty()) throw UsageError("--xr-mock needs --output-dir");
  if (o.replay.empty() && o.xr_mock.empty() && !o.output_dir.empty())
    throw UsageError("--output-dir applies to --replay and --xr-mock");
  o.stereo.validate();
  const int headsets = int(o.xr) + int(!o.xr_mock.empty()) + int(!o.replay.empty());
  if (headsets > 1) throw UsageError("--xr, --xr-mock and --replay exclude each other");
  if ((o.xr || !o.xr_mock.empty()) && o.stereo.mode != "none")
    throw UsageError("--stereo lays out the window's two eyes; a headset (--xr, --xr-mock) shows each eye itself");
  if ((o.xr || !o.xr_mock.empty()) && (!o.screenshots.empty() || !o.record.empty() || !o.script.empty()))
    throw UsageError("--screenshot, --record and --script apply to the window, not to --xr or --xr-mock");
  if (o.frame_format != "png" && o.frame_format != "exr" && o.frame_format != "both")
    throw UsageError("--frame-format must be png, exr or both, got \"" + o.frame_format + "\"");
}

int run_view(const ViewCommandOptions& o) {
  check_options(o);
#ifdef ATMOS_VIEWER
  atmos_view::ViewOptions v;
  v.planet.planet = o.planet.planet;
  v.planet.wavelengths = o.planet.wavelengths;
  v.planet.density_scale = o.planet.density_scale;
  v.planet.solar = o.planet.solar;
  v.planet.orders = o.tables.precompute_options().scattering_orders;
  v.planet.table_sizes = o.tables.sizes;
  v.cache.directory = o.cache.directory;
  v.cache.disabled = o.cache.disabled;
  v.globe = o.surface.globe(false, false);
  v.planet_albedo = o.surface.planet_albedo;
  v.instant_preview = !o.no_instant_preview;
  v.width = o.width;
  v.height = o.height;
  v.latitude_deg = o.latitude;
  v.longitude_deg = o.longitude;
  v.altitude_m = o.altitude;
  v.heading_deg = o.heading;
  v.pitch_deg = o.pitch;
  v.sun_elevation_deg = o.sun.elevation;
  v.sun_azimuth_deg = o.sun.azimuth;
  if (o.date.given()) {
    // The sun and the Moon of the date seen from the starting ground point
    // (atmos/ephemeris.hpp), as `atmos render --date` places them.
    atmos::SkyOfDate sky;
    try {
      sky = atmos::sky_of_date(atmos::parse_utc_time(o.date.date), {o.latitude, o.longitude, 0.0});
    } catch (const atmos::Error& e) {
      throw UsageError(std::string("--date: ") + e.what());
    }
    v.sun_elevation_deg = sky.sun.elevation_deg;
    v.sun_azimuth_deg = sky.sun.azimuth_deg;
    v.moon_of_date_m = sky.moon.topocentric_m;
  }
  v.look.exposure_ev = o.exposure;
  v.look.auto_exposure = o.auto_exposure;
  v.look.tone_mapping = atmos::parse_tone_mapping(o.tonemap);
  v.look.bloom = o.bloom;
  v.look.stars = o.stars;
  v.look.fov_deg = o.fov;
  v.ui = !o.no_ui;
  v.frames = o.frames;
  v.screenshots = o.screenshots;
  v.record = o.record;
  v.script = o.script;
  v.replay = o.replay;
  v.output_dir = o.output_dir;
  v.frame_format = o.frame_format;
  v.stereo.mode = o.stereo.mode == "anaglyph"       ? atmos_view::StereoSettings::Mode::anaglyph
                  : o.stereo.mode == "side-by-side" ? atmos_view::StereoSettings::Mode::side_by_side
                                                    : atmos_view::StereoSettings::Mode::none;
  v.stereo.interpupillary_m = o.stereo.ipd;
  v.stereo.convergence_m = o.stereo.convergence;
  v.xr = o.xr;
  v.xr_mock = o.xr_mock;
  if (o.xr || !o.xr_mock.empty()) return atmos_view::run_headset(v);
  return o.replay.empty() ? atmos_view::run_viewer(v) : atmos_view::run_replay(v);
#else
  throw atmos::Error(
      "atmos view was not built: libglfw3-dev and libimgui-dev were missing when atmos was configured (bash "
      "scripts/setup.sh installs them)");
#endif
}

}  // namespace

Command add_view_command(CLI::App& app) {
  auto o = std::make_shared<ViewCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "view",
      "Interactive viewer: fly from the ground to orbit and change any setting live (a window; keys in "
      "docs/viewer.md); --frames N --screenshot FILE for a still, --record/--replay for flights");
  o->planet.add(*cmd);
  o->tables.add(*cmd);
  o->cache.add(*cmd);
  o->surface.add(*cmd);
  o->sun.add(*cmd);
  cmd->add_option("--width", o->width, "Window width, pixels, in [16, 8192]")->capture_default_str();
  cmd->add_option("--height", o->height, "Window height, pixels, in [16, 8192]")->capture_default_str();
  cmd->add_option("--altitude", o->altitude,
                  "Starting altitude above the ground (the terrain or the sea with the globe), metres, in [0, 1e12]; "
                  "the camera stays 0.5 m above the ground and within 100 planet radii of its centre")
      ->type_name("M")
      ->capture_default_str();
  cmd->add_option("--latitude", o->latitude, "Latitude of the starting ground point, degrees, in [-90, 90]")
      ->capture_default_str();
  cmd->add_option("--longitude", o->longitude, "Longitude of the starting ground point, degrees east")
      ->capture_default_str();
  o->date.add(*cmd);
  cmd->add_option("--heading", o->heading, "Starting view direction, degrees clockwise from north")->capture_default_str();
  cmd->add_option("--pitch", o->pitch, "Starting view elevation, degrees, in [-89.5, 89.5]")->capture_default_str();
  cmd->add_option("--fov", o->fov, "Vertical field of view, degrees, in [5, 120]")->capture_default_str();
  cmd->add_option("--exposure", o->exposure, "Exposure value (EV100)")->type_name("EV")->capture_default_str();
  cmd->add_flag("--auto-exposure", o->auto_exposure, "Expose from the image's log-average luminance (eye adaptation)");
  cmd->add_option("--tonemap", o->tonemap, "Tone mapping: exp, reinhard, filmic, aces or linear")
      ->check(CLI::IsMember({"exp", "reinhard", "filmic", "aces", "linear"}).description(""))
      ->capture_default_str();
  cmd->add_option("--bloom", o->bloom, "Bloom strength in [0, 1]")->capture_default_str();
  cmd->add_flag("--stars", o->stars, "Draw the star field also by day");
  cmd->add_flag("--no-ui", o->no_ui, "Hide the panel");
  cmd->add_flag("--no-instant-preview", o->no_instant_preview,
                "While new tables are computed, keep the old ones on screen instead of the instant approximation");
  cmd->add_option("--frames", o->frames, "Draw N frames, then exit (0: until the window is closed)")
      ->type_name("N")
      ->capture_default_str();
  cmd->add_option("--screenshot", o->screenshots,
                  "With --frames: save the last frame, .png (the window as shown) or .exr (the linear image, cd/m²); "
                  "repeatable")
      ->type_name("FILE");
  cmd->add_option("--record", o->record, "Write the flight (camera, sun, settings per frame) to FILE.json at exit")
      ->type_name("FILE");
  cmd->add_option("--script", o->script, "Scripted input: timed keys, mouse drags, sliders (docs/viewer.md)")
      ->type_name("FILE");
  cmd->add_option("--replay", o->replay, "Replay a recorded flight headless (no window) into --output-dir")
      ->type_name("FILE");
  cmd->add_option("--output-dir", o->output_dir,
                  "The replay's frames, frame-00000.png ...; --xr-mock's eyes, eye-left.png, eye-right.png")
      ->type_name("DIR");
  cmd->add_option("--frame-format", o->frame_format, "The replay's frames: png, exr or both")->capture_default_str();
  o->stereo.add(*cmd,
                 "in the window: side-by-side (each eye half the width, left eye on the left) or anaglyph "
                 "(red-cyan: red from the left eye, green and blue from the right); the panel changes them live");
  cmd->add_flag("--xr", o->xr,
                "Draw for an OpenXR head-mounted display (each eye's pose and field of view from the runtime), "
                "the camera's place and view as the tracking space's origin; --frames N stops after N frames");
  cmd->add_option("--xr-mock", o->xr_mock,
                  "Draw for a mock headset with fixed eyes (a JSON file, docs/viewer.md), headless, through the "
                  "path of --xr; each eye's last image into --output-dir")
      ->type_name("FILE");
  return {cmd, [o] { return run_view(*o); }};
}

}  // namespace atmos_cli
