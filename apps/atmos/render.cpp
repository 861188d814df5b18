// atmos render: images from the tables, on the GPU (or the CPU with --cpu);
// with only the planet and table options, the default gallery. The ground
// is the terrain globe under the engine plugin (globe_render.hpp), or with
// --surface sphere the renderer's analytic sphere.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "atmos/globe.hpp"
#include "atmos/image.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/post.hpp"
#include "atmos/renderer.hpp"
#include "atmos/stereo.hpp"
#include "atmos/sky.hpp"
#include "atmos/star_catalogue.hpp"
#include "commands.hpp"
#include "globe_render.hpp"

namespace atmos_cli {

namespace {

struct RenderOptions {
  PlanetOptions planet;
  TableOptions tables;
  CacheOptions cache;
  ViewpointOptions viewpoint;
  SunOptions sun;
  DateOptions date;
  MoonOptions moons;
  SurfaceOption surface;
  SizeOption size{"640x360"};
  std::string look;
  double fov = 0.0;
  bool fov_given = false;  // else the projection's default
  std::string projection = "perspective";
  double exposure = 13.0;
  std::vector<std::string> outputs;
  std::string precision = "full";
  bool cpu = false;
  bool stars = false;
  // The stars of --date: the catalogue's (this file) or the procedural field.
  std::string star_catalogue = atmos::kXplanetBrightStarCatalogue;
  std::string star_colours = atmos::kKStarsStarCatalogue;  // "none": the Sun's B-V for all
  bool procedural_stars = false;
  // Camera-like PNG output (PostProcess): --tonemap, --bloom, --auto-exposure.
  std::string tonemap = "exp";
  double bloom = 0.0;
  bool auto_exposure = false;
  bool post = false;     // one of them given
  StereoOptions stereo;
  bool gallery = false;  // no option but the planet, table, cache, --surface, --precision and --cpu ones
};

struct Shot {
  std::string name;
  atmos::Camera camera;
  glm::dvec3 sun;
  double exposure;
  std::vector<atmos::Moon> moons = {};
};

atmos::Projection parse_projection(const std::string& p) {
  if (p == "perspective") return atmos::Projection::perspective;
  if (p == "fisheye") return atmos::Projection::fisheye;
  return atmos::Projection::equirect;
}

// Camera looking along (azimuth, elevation) of the local frame at the point
// below it (x = east, y = north, z = up at the north pole).
atmos::Camera make_camera(const glm::dvec3& position, double azimuth, double elevation, double fov,
                          atmos::Projection projection, int width, int height) {
  atmos::Camera c;
  c.position = position;
  c.forward = atmos::direction_from_azimuth_elevation(azimuth, elevation);
  // Straight up or down: the look azimuth is at the top of the image (north
  // for azimuth 0; looking up, east is then on the left, as on all-sky
  // cameras; looking down, on the right, as on maps).
  c.up = std::abs(elevation) > 89.9 ? atmos::direction_from_azimuth_elevation(azimuth, 0.0) : glm::dvec3(0, 0, 1);
  c.projection = projection;
  c.fov_deg = fov > 0.0 ? fov : (projection == atmos::Projection::fisheye ? 180.0 : 60.0);
  c.width = width;
  c.height = height;
  return c;
}

bool has_extension(const std::string& path, const std::string& extension) {
  if (path.size() < extension.size()) return false;
  std::string ext = path.substr(path.size() - extension.size());
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == extension;
}

void write_outputs(const atmos::Image& image, const std::vector<std::string>& outputs, double exposure) {
  for (const auto& path : outputs) {
    atmos::write_image(image, path, exposure);
    std::printf("wrote %s\n", path.c_str());
  }
}

// PNG outputs through PostProcess (tone map, bloom, auto exposure); EXR
// outputs keep the HDR values (write_image). A still has no past: with
// --auto-exposure it is exposed at the converged value directly (the first
// frame after a reset starts at its target, see AutoExposureSettings).
void write_outputs_post(atmos::PostProcess& post, const atmos::Image& image, const std::vector<std::string>& outputs,
                        const RenderOptions& o) {
  atmos::PostSettings settings;
  settings.tone_mapping = atmos::parse_tone_mapping(o.tonemap);
  settings.exposure_ev = o.exposure;
  settings.bloom.strength = o.bloom;
  settings.auto_exposure.enabled = o.auto_exposure;
  bool processed = false;
  atmos::DisplayImage display;
  for (const auto& path : outputs) {
    if (!has_extension(path, ".png")) {
      atmos::write_image(image, path, o.exposure);
    } else {
      if (!processed) {
        post.reset();
        display = post.process_image(image, settings);
        processed = true;
        if (o.auto_exposure) std::printf("auto exposure: EV100 %.2f\n", post.current_exposure_ev());
      }
      atmos::write_png(display, path);
    }
    std::printf("wrote %s\n", path.c_str());
  }
}

std::vector<Shot> gallery(const atmos::Atmosphere& a) {
  const glm::dvec3 ground = atmos::observer_position(a, 2.0);
  // Exposures are set for Earth's sunlight (ASTM E490: 1.873 W m^-2 nm^-1 at
  // 550 nm) and shifted by the planet's: Mars' sun is 1.2 stops dimmer.
  const double ev_shift = std::log2(a.solar_irradiance.at(550.0) / 1.873);
  std::vector<Shot> shots;
  shots.push_back({"noon", make_camera(ground, 0.0, 12.0, 75.0, atmos::Projection::perspective, 960, 540),
                   atmos::direction_from_azimuth_elevation(180.0, 70.0), 13.5 + ev_shift});
  shots.push_back({"sunset", make_camera(ground, 270.0, 8.0, 75.0, atmos::Projection::perspective, 960, 540),
                   atmos::direction_from_azimuth_elevation(270.0, 1.0), 10.5 + ev_shift});
  shots.push_back({"allsky", make_camera(ground, 0.0, 90.0, 180.0, atmos::Projection::fisheye, 540, 540),
                   atmos::direction_from_azimuth_elevation(135.0, 20.0), 13.0 + ev_shift});
  // The planet from 2.5 radii, looking at the centre, sun from the side.
  const double d = 2.5 * a.bottom_radius_m;
  atmos::Camera orbit;
  orbit.position = glm::dvec3(d, 0.0, 0.0);
  orbit.forward = glm::dvec3(-1.0, 0.0, 0.0);
  orbit.up = glm::dvec3(0.0, 0.0, 1.0);
  orbit.fov_deg = 50.0;
  orbit.width = 960;
  orbit.height = 540;
  shots.push_back({"orbit", orbit, glm::normalize(glm::dvec3(0.35, 1.0, 0.25)), 13.0 + ev_shift});
  return shots;
}

// The one shot of a render with options; every value is checked here, before
// the tables are loaded.
Shot single_shot(const RenderOptions& o, const atmos::Atmosphere& a) {
  const auto [w, h] = o.size.parse();
  const Viewpoint viewpoint = o.viewpoint.viewpoint(a);
  const glm::dvec3 sun = o.sun.direction(viewpoint);
  // By default the camera looks towards the sun's azimuth, 15° up; from
  // outside the atmosphere, straight down at the planet.
  double look_az = o.sun.azimuth, look_el = glm::length(viewpoint.position) > a.top_radius_m ? -90.0 : 15.0;
  if (!o.look.empty()) {
    const auto l = parse_numbers(o.look, 2, "--look", "AZ,EL");
    look_az = l[0];
    look_el = l[1];
    if (look_el < -90.0 || look_el > 90.0)
      throw UsageError("--look elevation must be in [-90, 90] degrees, got " + quote(look_el));
  }
  const atmos::Projection projection = parse_projection(o.projection);
  if (o.fov_given) {
    finite(o.fov, "--fov");
    if (projection == atmos::Projection::perspective && !(o.fov > 0.0 && o.fov < 180.0))
      throw UsageError("--fov of a perspective camera must be in (0, 180) degrees, got " + quote(o.fov));
    if (projection == atmos::Projection::fisheye && !(o.fov > 0.0 && o.fov <= 360.0))
      throw UsageError("--fov of a fisheye camera must be in (0, 360] degrees, got " + quote(o.fov));
  }
  atmos::Camera camera =
      make_camera(viewpoint.position, look_az, look_el, o.fov_given ? o.fov : 0.0, projection, w, h);
  camera.forward = viewpoint.local * camera.forward;
  camera.up = viewpoint.local * camera.up;
  atmos::validate_camera(camera);
  return {"render", camera, sun, o.exposure, o.moons.place(viewpoint, a)};
}

void check_options(const RenderOptions& o) {
  o.planet.validate();
  o.tables.validate();
  finite(o.exposure, "--exposure");
  finite(o.bloom, "--bloom");
  if (o.bloom < 0.0 || o.bloom > 1.0) throw UsageError("--bloom must be in [0, 1], got " + quote(o.bloom));
  for (const std::string& path : o.outputs)
    if (!has_extension(path, ".png") && !has_extension(path, ".exr"))
      throw UsageError("-o/--output must name a .png or .exr file, got \"" + path + "\"");
  if (o.surface.globe(o.cpu, o.precision == "half") && o.cpu)
    throw UsageError("the globe needs OpenGL: use --surface sphere with --cpu");
  if (o.surface.globe(o.cpu, o.precision == "half") && o.precision == "half")
    throw UsageError("--precision half applies to --surface sphere: the globe's atmosphere pass samples "
                     "full-precision textures");
  o.stereo.validate();
  if (o.stereo.mode != "none" && o.projection != "perspective")
    throw UsageError("--stereo needs the perspective projection, got --projection " + o.projection);
}

// The catalogue's stars in the sky of --date seen from --latitude,
// --longitude, in the planet-centred (Earth-fixed) frame of the camera:
// placed by the apparent sidereal time (atmos/star_catalogue.hpp), their
// spectra blackbodies of their B-V's temperature. xplanet's catalogue has
// no B-V: each star takes that of the same star in --star-colours (KStars'
// Hipparcos catalogue: the nearest within 1 arcminute and 0.5 magnitude),
// the Sun's where none matches or with --star-colours none.
std::vector<atmos::Star> stars_of_date(const RenderOptions& o) {
  std::vector<atmos::CatalogueStar> catalogue = atmos::load_bright_star_catalogue(o.star_catalogue);
  if (o.star_colours != "none") (void)atmos::colour_from_catalogue(catalogue, atmos::load_kstars_catalogue(o.star_colours));
  const atmos::Instant instant = atmos::instant_of(atmos::parse_utc_time(o.date.date));
  std::vector<atmos::Star> stars;
  for (const atmos::SkyStar& s :
       atmos::stars_in_sky(catalogue, instant, {o.viewpoint.latitude, o.viewpoint.longitude, 0.0}))
    stars.push_back({s.direction, s.v_band_irradiance, s.temperature_k});
  return stars;
}

int run_render(const RenderOptions& o) {
  check_options(o);
  // The catalogue is read before the slow work, so that its errors come first.
  const std::vector<atmos::Star> catalogue_stars =
      o.date.given() && !o.procedural_stars ? stars_of_date(o) : std::vector<atmos::Star>{};
  const atmos::Atmosphere atmosphere = o.planet.atmosphere();
  const std::vector<Shot> shots = o.gallery ? gallery(atmosphere) : std::vector<Shot>{single_shot(o, atmosphere)};
  // The planet file's surface is read before the slow work, so that its
  // errors come first.
  const atmos::PlanetSurface surface =
      o.surface.globe(o.cpu, o.precision == "half") ? atmos::load_surface(o.planet.planet) : atmos::PlanetSurface{};
  // The globe's pass draws the air continued down to the lowest ground
  // (Mars's lowlands lie kilometres below its datum); the globe keeps the
  // datum.
  const LoadedTables loaded =
      load_tables(o.surface.globe(o.cpu, o.precision == "half") ? atmos::extend_below_datum(atmosphere, surface)
                                                                 : atmosphere,
                  o.tables, o.cache, true, o.surface.globe(o.cpu, o.precision == "half") && !o.surface.planet_albedo);
  const atmos::Atmosphere& a = loaded.atmosphere;

  // The context outlives every GL object below (declared first, destroyed last).
  std::unique_ptr<atmos::GlContext> context;
  if (!o.cpu || o.post) context = atmos::GlContext::create_headless();
  std::unique_ptr<atmos::Renderer> renderer;
  std::unique_ptr<GlobeRenderer> globe;
  if (o.surface.globe(o.cpu, o.precision == "half"))
    globe = std::make_unique<GlobeRenderer>(atmosphere, loaded.tables, surface);
  else if (!o.cpu)
    renderer = std::make_unique<atmos::Renderer>(
        a, loaded.tables, o.precision == "half" ? atmos::TexturePrecision::half : atmos::TexturePrecision::full);
  if (globe) globe->set_star_catalogue(catalogue_stars);
  if (renderer) renderer->set_star_catalogue(catalogue_stars);
  // The post-processing runs on the GPU, also after a --cpu render.
  std::unique_ptr<atmos::PostProcess> post;
  if (o.post) post = std::make_unique<atmos::PostProcess>();
  const std::vector<std::string> outputs = o.outputs.empty() ? std::vector<std::string>{"atmos.png"} : o.outputs;
  for (const Shot& shot : shots) {
    // The star field: with --stars, and whenever the sun is below the
    // horizon of a single render (the gallery's shots are by day or from
    // space, without).
    const bool stars = !o.gallery && (o.stars || o.sun.elevation < 0.0);
    if (renderer) {
      renderer->set_stars(stars);
      renderer->set_moons(shot.moons);
    }
    auto render = [&](const atmos::Camera& camera) {
      if (o.cpu) return atmos::render_cpu(a, loaded.tables, camera, shot.sun, stars, shot.moons, catalogue_stars);
      if (globe) return globe->render(camera, shot.sun, stars, shot.moons);
      return renderer->render(camera, shot.sun);
    };
    atmos::Camera camera = shot.camera;
    // The viewpoint's altitude is above the terrain under it.
    if (globe) camera.position = globe->above_terrain(camera.position);
    atmos::Image image;
    if (o.stereo.mode == "none") {
      image = render(camera);
    } else {
      // Each eye through its own off-axis frustum, the head at the viewpoint.
      const std::array<atmos::Eye, 2> eyes = atmos::stereo_eyes(camera, o.stereo.rig());
      const atmos::Image left = render(atmos::eye_camera(eyes[0], camera.width, camera.height));
      const atmos::Image right = render(atmos::eye_camera(eyes[1], camera.width, camera.height));
      image = o.stereo.mode == "anaglyph" ? atmos::anaglyph(left, right) : atmos::side_by_side(left, right);
    }
    if (o.gallery) {
      write_outputs(image, {shot.name + ".png", shot.name + ".exr"}, shot.exposure);
    } else if (post) {
      write_outputs_post(*post, image, outputs, o);
    } else {
      write_outputs(image, outputs, o.exposure);
    }
  }
  return 0;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render an image of the sky (and of the ground and the planet) into the output files. With no option but "
      "the planet, table and cache options, --surface, --precision and --cpu: the default gallery (noon, sunset, "
      "allsky and orbit, each .png and .exr) into the current directory");
  o->planet.add(*cmd);
  o->tables.add(*cmd);
  o->cache.add(*cmd);
  o->viewpoint.add(*cmd);
  o->sun.add(*cmd);
  o->date.add(*cmd);
  o->moons.add(*cmd);
  o->surface.add(*cmd);
  cmd->add_option("--look", o->look,
                  "View direction: azimuth AZ (degrees clockwise from north) and elevation EL in [-90, 90] "
                  "(default: the sun's azimuth, 15 degrees up; from outside the atmosphere, straight down)")
      ->type_name("AZ,EL");
  auto* fov = cmd->add_option("--fov", o->fov,
                  "Field of view, degrees: vertical for perspective, in (0, 180) (default 60); the circle's for "
                  "fisheye, in (0, 360] (default 180); unused by equirect")
      ->type_name("DEG");
  cmd->add_option("--projection", o->projection,
                  "Camera model: perspective (pinhole), fisheye (equidistant) or equirect (the whole sphere, "
                  "azimuth across and elevation down the image)")
      ->type_name("perspective|fisheye|equirect")
      ->check(CLI::IsMember({"perspective", "fisheye", "equirect"}).description(""))
      ->capture_default_str();
  o->size.add(*cmd, "Image size");
  cmd->add_option("--exposure", o->exposure,
                  "Exposure value (EV100) of the PNG outputs: a pixel of L cd/m2 shows as 1 - exp(-L / (1.2 * 2^EV)) "
                  "before the sRGB encoding; any finite value")
      ->type_name("EV")
      ->capture_default_str();
  cmd->add_option("-o,--output", o->outputs,
                  "Output file: .png (8-bit sRGB, exposed) or .exr (32-bit float linear sRGB in cd/m2); repeatable "
                  "(default atmos.png)")
      ->type_name("FILE");
  cmd->add_option("--precision", o->precision,
                  "Precision of the GPU's scattering and irradiance textures: half (16-bit float) or full (32-bit "
                  "float)")
      ->type_name("half|full")
      ->check(CLI::IsMember({"half", "full"}).description(""))
      ->capture_default_str();
  cmd->add_flag("--cpu", o->cpu,
                "Render on the CPU with the same functions, with --surface sphere (no OpenGL needed unless "
                "post-processing)");
  cmd->add_flag("--stars", o->stars,
                "Draw the star field also with the sun above the horizon (it is drawn whenever the sun is below it)");
  cmd->add_option("--star-catalogue", o->star_catalogue,
                  "With --date: the star catalogue whose stars are drawn, placed for the date and place (the Yale "
                  "Bright Star Catalogue in xplanet's layout: Dec RA Mag \"Name\" ...)")
      ->type_name("FILE")
      ->needs("--date")
      ->capture_default_str();
  cmd->add_option("--star-colours", o->star_colours,
                  "With --date: the catalogue the stars' B-V colours come from (KStars' Hipparcos catalogue, "
                  "Debian's kstars-data; each star of --star-catalogue without a B-V takes that of the same star "
                  "there), or none (every star the Sun's colour)")
      ->type_name("FILE|none")
      ->needs("--date")
      ->capture_default_str();
  cmd->add_flag("--procedural-stars", o->procedural_stars,
                "With --date: draw the procedural star field instead of the catalogue's stars")
      ->needs("--date")
      ->excludes("--star-catalogue");
  auto* tonemap = cmd->add_option("--tonemap", o->tonemap,
                                  "Tone mapping of the PNG outputs through the post-processing chain: exp (the "
                                  "default curve above), reinhard, filmic or aces")
                      ->type_name("exp|reinhard|filmic|aces")
                      ->check(CLI::IsMember({"exp", "reinhard", "filmic", "aces"}).description(""))
                      ->capture_default_str();
  auto* bloom = cmd->add_option("--bloom", o->bloom,
                                "Bloom strength of the PNG outputs, in [0, 1]: the fraction of the light above "
                                "saturation spread as glare")
                    ->type_name("STRENGTH")
                    ->capture_default_str();
  auto* auto_exposure = cmd->add_flag("--auto-exposure", o->auto_exposure,
                                      "Expose the PNG outputs from the image's log-average luminance (Collienne "
                                      "2013, eq. 4.28) instead of --exposure");
  o->stereo.add(*cmd,
                 "rendered (perspective only) and combined: side-by-side (left eye on the left, twice the "
                 "width) or anaglyph (red-cyan: red from the left eye, green and blue from the right)");
  return {cmd, [o, cmd, fov, tonemap, bloom, auto_exposure] {
            o->fov_given = fov->count() > 0;
            o->post = tonemap->count() > 0 || bloom->count() > 0 || auto_exposure->count() > 0;
            // Only the planet, table and cache options, --surface,
            // --precision and --cpu keep the gallery (e.g. --planet mars
            // --wavelengths 15).
            const std::set<std::string> gallery_options = {
                "--planet",    "--orders",   "--wavelengths", "--density-scale", "--solar",  "--tables",
                "--cache-dir", "--no-cache", "--surface",     "--planet-albedo", "--precision",     "--cpu"};
            o->gallery = true;
            for (const auto* opt : cmd->get_options())
              if (opt->count() > 0 && gallery_options.count(opt->get_name()) == 0) o->gallery = false;
            o->date.apply(o->viewpoint, o->sun, o->moons);
            return run_render(*o);
          }};
}

}  // namespace atmos_cli
