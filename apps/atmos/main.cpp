// atmos — command line interface.
//
//   atmos render      render images (no arguments: the default gallery)
//   atmos precompute  build or verify the table cache, with timings
//   atmos sample      radiance for directions read as CSV (tables or --reference)
//   atmos bench       precomputation and render timings, name<TAB>value<TAB>unit
//   atmos plot-data   CSV files for scripts/plots.py (docs/plots.md)
//
// Exit codes: 0 success, 1 runtime error (bad planet file, no OpenGL, I/O),
// 2 usage error (unknown flag, bad value).
#include <CLI/CLI.hpp>
#include <epoxy/gl.h>
#include <glm/gtc/matrix_transform.hpp>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <set>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/colour.hpp"
#include "atmos/image.hpp"
#include "atmos/reference.hpp"
#include "atmos/plugin.hpp"
#include "atmos/post.hpp"
#include "atmos/renderer.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "plot_data.hpp"

namespace {

using atmos::Error;

// A bad command-line value: reported as a usage error (exit code 2).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

double finite(double v, const std::string& name) {
  if (!std::isfinite(v)) throw UsageError(name + " must be a finite number");
  return v;
}

std::vector<double> parse_numbers(const std::string& text, size_t count, const std::string& name) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size()) throw std::invalid_argument(item);
      out.push_back(finite(v, name));
    } catch (const UsageError&) {
      throw;
    } catch (const std::exception&) {
      throw UsageError(name + " expects " + std::to_string(count) + " comma-separated numbers, got \"" + text + "\"");
    }
  }
  if (out.size() != count)
    throw UsageError(name + " expects " + std::to_string(count) + " comma-separated numbers, got \"" + text + "\"");
  return out;
}

// Options shared by the commands that need tables.
struct TableOptions {
  std::string planet = "earth";
  std::string orders = "4";
  std::string tables = "default";
  std::string cache_dir;
  bool no_cache = false;
  int wavelengths = 0;  // 0: the planet file's
  double density_scale = 1.0;
  std::string solar;  // empty: the planet file's

  void add(CLI::App& app) {
    app.add_option("--planet", planet, "Preset name (" + preset_list() + ") or planet JSON file")->capture_default_str();
    app.add_option("--orders", orders,
                   "Scattering orders: K >= 1, or auto (until the orders left would add < 0.1 % of the light, "
                   "on the ground too; at most 64; where the orders foretell that cap, the rest is solved at once from order 16)")
        ->capture_default_str();
    app.add_option("--wavelengths", wavelengths,
                   "Working wavelengths N in [3, 48]: 3 = fast mode (680, 550, 440 nm), more = spectral over "
                   "360-830 nm (default: the planet file's)");
    app.add_option("--density-scale", density_scale, "Multiply the density of every constituent by X (0.1 to 100...)")
        ->capture_default_str();
    app.add_option("--solar", solar, "Solar spectrum shape: table (ASTM E490) or blackbody:T (kelvin)");
    app.add_option("--tables", tables, "Table sizes: default (256x64, 64x16, 8x32x128x32) or small (for tests)")
        ->check(CLI::IsMember({"default", "small"}))
        ->capture_default_str();
    app.add_option("--cache-dir", cache_dir, "Table cache directory (default $ATMOS_CACHE_DIR or ~/.cache/atmos)");
    app.add_flag("--no-cache", no_cache, "Always precompute; neither read nor write the cache");
  }

  static std::string preset_list() {
    std::string names;
    for (const auto& n : atmos::preset_names()) names += (names.empty() ? "" : ", ") + n;
    return names;
  }

  // The planet with the wavelength, density and solar options applied.
  atmos::Atmosphere atmosphere() const {
    if (wavelengths != 0 && (wavelengths < 3 || wavelengths > 48))
      throw UsageError("--wavelengths must be in [3, 48], got " + std::to_string(wavelengths));
    if (!(density_scale > 0.0 && density_scale <= 1e4))
      throw UsageError("--density-scale must be in (0, 10000], got " + std::to_string(density_scale));
    atmos::Atmosphere a = atmos::load_atmosphere(planet);
    if (wavelengths != 0) a.wavelengths_nm = atmos::spectral_wavelengths(wavelengths);
    if (density_scale != 1.0) atmos::scale_density(a, density_scale);
    if (!solar.empty()) {
      if (solar != "table" && solar.rfind("blackbody:", 0) != 0)
        throw UsageError("--solar must be table or blackbody:T, got \"" + solar + "\"");
      atmos::set_solar_spectrum(a, solar);
    }
    a.validate();
    return a;
  }

  // Orders for the reference (which has no auto mode).
  int fixed_orders() const {
    if (orders == "auto") throw UsageError("--orders auto applies to the tables; give the reference a number K");
    return parse_orders();
  }

  int parse_orders() const {
    char* end = nullptr;
    const long k = std::strtol(orders.c_str(), &end, 10);
    if (end == orders.c_str() || *end != '\0' || k < 1 || k > 100)
      throw UsageError("--orders must be auto or an integer in [1, 100], got \"" + orders + "\"");
    return int(k);
  }

  atmos::PrecomputeOptions precompute_options() const {
    atmos::PrecomputeOptions o;
    if (orders == "auto") {
      o.auto_orders = true;
      o.scattering_orders = 64;
    } else {
      o.scattering_orders = parse_orders();
    }
    if (tables == "small") o.sizes = atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8};
    return o;
  }
};

// A progress bar on stderr when it is a terminal.
void attach_progress(atmos::PrecomputeOptions& options) {
  if (!isatty(STDERR_FILENO)) return;
  options.progress = [](const std::string& step, double fraction) {
    const int width = 30;
    const int filled = int(fraction * width + 0.5);
    std::fprintf(stderr, "\r[%s%s] %3d%% %-22s", std::string(size_t(filled), '#').c_str(),
                 std::string(size_t(width - filled), ' ').c_str(), int(fraction * 100.0 + 0.5), step.c_str());
    if (fraction >= 1.0) std::fprintf(stderr, "\r%*s\r", width + 30, "");
    std::fflush(stderr);
  };
}

struct LoadedTables {
  atmos::Atmosphere atmosphere;
  atmos::Tables tables;
  std::string status;
};

LoadedTables load_tables(const TableOptions& t, bool quiet = false) {
  LoadedTables out;
  out.atmosphere = t.atmosphere();
  atmos::PrecomputeOptions options = t.precompute_options();
  if (!quiet) attach_progress(options);
  if (t.no_cache) {
    out.tables = atmos::precompute_tables(out.atmosphere, options);
    out.status = "computed (cache disabled)";
    return out;
  }
  const std::string dir = t.cache_dir.empty() ? atmos::default_cache_directory() : t.cache_dir;
  atmos::CacheResult r = atmos::load_or_precompute_tables(out.atmosphere, options, dir);
  if (!r.problem.empty()) std::fprintf(stderr, "atmos: warning: %s\n", r.problem.c_str());
  out.status = r.status == atmos::CacheStatus::hit ? "loaded from cache " + r.path
               : r.status == atmos::CacheStatus::computed ? "computed, cached in " + r.path
                                                          : "recomputed (invalid cache), cached in " + r.path;
  out.tables = std::move(r.tables);
  return out;
}

// ---------------------------------------------------------------------------
// render

struct RenderOptions {
  double altitude = 2.0;
  std::string position;
  std::string look;
  double fov = 0.0;
  std::string projection = "perspective";
  double sun_elevation = 30.0;
  double sun_azimuth = 180.0;
  std::string size = "640x360";
  double exposure = 13.0;
  std::vector<std::string> outputs;
  std::string precision = "full";
  bool cpu = false;
  // Camera-like PNG output (PostProcess, include/atmos/post.hpp); without
  // any of these the PNG is write_png's exp tone map, as before.
  std::string tonemap = "exp";
  double bloom = 0.0;
  bool auto_exposure = false;
  bool post = false;  // --tonemap, --bloom or --auto-exposure given
  bool stars = false;  // --stars: the star field even with the sun up (it is on anyway at night)
  std::vector<std::string> moons;  // --moon AZ,EL,ANGULAR_RADIUS_DEG, repeatable
};

struct Shot {
  std::string name;
  atmos::Camera camera;
  glm::dvec3 sun;
  double exposure;
  std::vector<atmos::Moon> moons = {};
};

// --moon AZ,EL,ANGULAR_RADIUS_DEG: a moon at the Moon's mean distance from
// the camera, in the direction (azimuth, elevation) of the camera's local
// frame `local`, that looks ANGULAR_RADIUS_DEG wide (atmos::moon_in_sky).
atmos::Moon parse_moon(const std::string& text, const glm::dvec3& position, const glm::dmat3& local) {
  const auto v = parse_numbers(text, 3, "--moon");
  if (v[1] < -90.0 || v[1] > 90.0) throw UsageError("--moon elevation must be in [-90, 90]");
  if (!(v[2] > 0.0) || v[2] > 10.0) throw UsageError("--moon angular radius must be in (0, 10] degrees");
  return atmos::moon_in_sky(position, local * atmos::direction_from_azimuth_elevation(v[0], v[1]),
                            v[2] * M_PI / 180.0);
}

std::pair<int, int> parse_size(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  std::stringstream ss(text);
  if (!(ss >> w >> x >> h) || (x != 'x' && x != 'X') || (ss >> extra))
    throw UsageError("--size expects WxH, e.g. 1280x720, got \"" + text + "\"");
  if (w < 1 || h < 1 || w > 16384 || h > 16384) throw UsageError("--size must be between 1x1 and 16384x16384");
  return {w, h};
}

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

void write_outputs(const atmos::Image& image, const std::vector<std::string>& outputs, double exposure) {
  for (const auto& path : outputs) {
    atmos::write_image(image, path, exposure);
    std::printf("wrote %s\n", path.c_str());
  }
}

bool has_png_extension(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".png";
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
    if (!has_png_extension(path)) {
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

int run_render(const RenderOptions& o, const TableOptions& t, bool use_gallery) {
  LoadedTables loaded = load_tables(t);
  const atmos::Atmosphere& a = loaded.atmosphere;
  std::vector<Shot> shots;
  if (use_gallery) {
    shots = gallery(a);
  } else {
    const auto [w, h] = parse_size(o.size);
    glm::dvec3 position;
    if (!o.position.empty()) {
      const auto p = parse_numbers(o.position, 3, "--position");
      position = {p[0], p[1], p[2]};
      if (glm::length(position) < a.bottom_radius_m)
        throw UsageError("--position is inside the planet (closer to its centre than the ground radius)");
    } else {
      if (!(o.altitude >= 0.0) || o.altitude > 1e12) throw UsageError("--altitude must be in [0, 1e12] metres");
      position = atmos::observer_position(a, o.altitude);
    }
    double look_az = o.sun_azimuth, look_el = 15.0;
    if (glm::length(position) > a.top_radius_m) look_el = -90.0;  // outside: look at the planet
    if (!o.look.empty()) {
      const auto l = parse_numbers(o.look, 2, "--look");
      look_az = l[0];
      look_el = l[1];
      if (look_el < -90.0 || look_el > 90.0) throw UsageError("--look elevation must be in [-90, 90]");
    }
    if (o.sun_elevation < -90.0 || o.sun_elevation > 90.0) throw UsageError("--sun-elevation must be in [-90, 90]");
    const atmos::Projection projection = parse_projection(o.projection);
    // Local frame at the point below the camera (the north pole for --altitude).
    atmos::Camera camera = make_camera(position, look_az, look_el, o.fov, projection, w, h);
    glm::dmat3 local(1.0);
    if (!o.position.empty()) {
      // Express the local (east, north, up) frame of an arbitrary position.
      const glm::dvec3 up = glm::normalize(position);
      glm::dvec3 east = glm::cross(glm::dvec3(0, 0, 1), up);
      if (glm::length(east) < 1e-9) east = glm::dvec3(1, 0, 0);
      east = glm::normalize(east);
      const glm::dvec3 north = glm::cross(up, east);
      local = glm::dmat3(east, north, up);
      camera.forward = local * camera.forward;
      camera.up = local * camera.up;
    }
    if (o.moons.size() > size_t(atmos::kMaxMoons))
      throw UsageError("--moon: at most " + std::to_string(atmos::kMaxMoons) + " moons");
    std::vector<atmos::Moon> moons;
    for (const std::string& text : o.moons) moons.push_back(parse_moon(text, position, local));
    atmos::validate_moons(moons, a.top_radius_m);
    shots.push_back({"render", camera, local * atmos::direction_from_azimuth_elevation(o.sun_azimuth, o.sun_elevation),
                     o.exposure, moons});
    atmos::validate_camera(camera);
  }

  std::unique_ptr<atmos::GlContext> context;
  std::unique_ptr<atmos::Renderer> renderer;
  if (!o.cpu) {
    context = atmos::GlContext::create_headless();
    renderer = std::make_unique<atmos::Renderer>(
        *context, a, loaded.tables, o.precision == "half" ? atmos::TexturePrecision::half : atmos::TexturePrecision::full);
  }
  // The post-processing runs on the GPU, also after a --cpu render.
  std::unique_ptr<atmos::PostProcess> post;
  if (o.post) {
    if (!context) context = atmos::GlContext::create_headless();
    post = std::make_unique<atmos::PostProcess>();
  }
  for (const Shot& shot : shots) {
    // The star field: with --stars, and whenever the sun is below the
    // horizon of a single render (the gallery's shots are by day or from
    // space, without).
    const bool stars = !use_gallery && (o.stars || o.sun_elevation < 0.0);
    if (renderer) {
      renderer->set_stars(stars);
      renderer->set_moons(shot.moons);
    }
    const atmos::Image image = o.cpu ? atmos::render_cpu(a, loaded.tables, shot.camera, shot.sun, stars, shot.moons)
                                     : renderer->render(shot.camera, shot.sun);
    if (use_gallery) {
      write_outputs(image, {shot.name + ".png", shot.name + ".exr"}, shot.exposure);
    } else if (post) {
      write_outputs_post(*post, image, o.outputs.empty() ? std::vector<std::string>{"atmos.png"} : o.outputs, o);
    } else {
      write_outputs(image, o.outputs.empty() ? std::vector<std::string>{"atmos.png"} : o.outputs, o.exposure);
    }
  }
  return 0;
}

// ---------------------------------------------------------------------------
// precompute

int run_precompute(const TableOptions& t) {
  const auto start = std::chrono::steady_clock::now();
  LoadedTables loaded = load_tables(t);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const atmos::TableSizes& s = loaded.tables.sizes;
  std::printf("planet          %s\n", loaded.atmosphere.name.c_str());
  std::printf("wavelengths     ");
  for (double w : loaded.tables.wavelengths_nm) std::printf("%g ", w);
  std::printf("nm\norders          %d\n", loaded.tables.scattering_orders);
  std::printf("transmittance   %d x %d (mu x r)\n", s.transmittance_mu, s.transmittance_r);
  std::printf("irradiance      %d x %d (mu_s x r), direct and indirect\n", s.irradiance_mu_s, s.irradiance_r);
  std::printf("scattering      %d x %d x %d x %d (nu x mu_s x mu x r), stored as 3D %d x %d x %d, Rayleigh+multiple and single aerosol\n",
              s.scattering_nu, s.scattering_mu_s, s.scattering_mu, s.scattering_r, loaded.tables.scattering_width(),
              loaded.tables.scattering_height(), loaded.tables.scattering_depth());
  std::printf("channels        %s\n", loaded.tables.wavelengths_nm.size() == 3
                                         ? "the three wavelengths"
                                         : "linear sRGB (spectral precomputation, CIE 1931 2 deg observer)");
  std::printf("cache           %s\n", loaded.status.c_str());
  for (const auto& c : loaded.tables.convergence) {
    if (c.tail)
      std::printf("orders %d+      add %.3e of all the light (solved at once: %d GMRES steps, residual %.1e)\n",
                  c.order, c.relative, c.iterations, c.residual);
    else
      std::printf("order %-3d       adds %.3e of the light gathered so far\n", c.order, c.relative);
  }
  if (loaded.tables.timings.empty()) std::printf("steps           none computed: the cache file is valid\n");
  for (const auto& step : loaded.tables.timings) std::printf("time %-22s %8.3f s\n", step.name.c_str(), step.seconds);
  std::printf("time total                   %8.3f s\n", seconds);
  return 0;
}

// ---------------------------------------------------------------------------
// sample

struct SampleOptions {
  double altitude = 0.0;
  double sun_elevation = 30.0;
  double sun_azimuth = 180.0;
  std::string directions;
  bool reference = false;
  int paths = 20000;
  bool sun_disc = false;
};

std::vector<std::pair<double, double>> read_directions(std::istream& in, const std::string& origin) {
  std::string line;
  int number = 0;
  bool header = false;
  std::vector<std::pair<double, double>> out;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      if (line.find("azimuth_deg") != 0 || line.find("elevation_deg") == std::string::npos)
        throw UsageError(origin + ":" + std::to_string(number) + ": expected the header azimuth_deg,elevation_deg");
      header = true;
      continue;
    }
    try {
      const auto v = parse_numbers(line, 2, "direction");
      if (v[1] < -90.0 || v[1] > 90.0) throw UsageError("elevation outside [-90, 90]");
      out.emplace_back(v[0], v[1]);
    } catch (const UsageError& e) {
      throw UsageError(origin + ":" + std::to_string(number) + ": " + e.what());
    }
  }
  if (!header) throw UsageError(origin + ": no header line azimuth_deg,elevation_deg");
  return out;
}

int run_sample(const SampleOptions& o, const TableOptions& t) {
  // Options first, so that a bad flag is reported before stdin is read.
  if (o.reference) (void)t.fixed_orders();
  const atmos::Atmosphere atmosphere = t.atmosphere();
  if (!(o.altitude >= 0.0) || o.altitude > 1e12) throw UsageError("--altitude must be in [0, 1e12] metres");
  if (o.sun_elevation < -90.0 || o.sun_elevation > 90.0) throw UsageError("--sun-elevation must be in [-90, 90]");
  if (o.paths < 2 || o.paths > 100000000) throw UsageError("--paths must be in [2, 1e8]");
  std::vector<std::pair<double, double>> directions;
  if (o.directions.empty()) {
    directions = read_directions(std::cin, "stdin");
  } else {
    std::ifstream in(o.directions);
    if (!in) throw Error("cannot read directions file " + o.directions);
    directions = read_directions(in, o.directions);
  }
  const glm::dvec3 observer = atmos::observer_position(atmosphere, o.altitude);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(o.sun_azimuth, o.sun_elevation);
  const auto& w = atmosphere.wavelengths_nm;
  // Three wavelengths: the tables' channels are the radiance at them, printed
  // as radiance_<λ>nm columns. Spectral: the tables hold colour; the
  // reference gives every wavelength, converted with the same CIE weights.
  const bool three = w.size() == 3;
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(w);
  auto srgb_of_spectrum = [&](const std::vector<double>& values) {
    glm::dvec3 rgb(0.0);
    for (size_t i = 0; i < values.size(); ++i) rgb += weights[i] * values[i];
    return rgb;
  };

  std::optional<LoadedTables> loaded;
  std::unique_ptr<atmos::SkyModel> model;
  atmos::ReferenceOptions ref;
  ref.paths = o.paths;
  if (!o.reference) {
    loaded = load_tables(t, true);
    model = std::make_unique<atmos::SkyModel>(atmosphere, loaded->tables);
  } else {
    ref.scattering_orders = t.fixed_orders();
  }

  std::printf("azimuth_deg,elevation_deg,luminance_cd_m2,red,green,blue");
  if (three)
    for (double l : w) std::printf(",radiance_%gnm", l);
  std::printf("\n");
  for (const auto& [az, el] : directions) {
    const glm::dvec3 view = atmos::direction_from_azimuth_elevation(az, el);
    glm::dvec3 rgb, spectral(0.0);
    if (o.reference) {
      const atmos::ReferenceResult r = atmos::reference_radiance(atmosphere, observer, view, sun, ref);
      rgb = srgb_of_spectrum(r.radiance);
      if (three) spectral = {r.radiance[0], r.radiance[1], r.radiance[2]};
    } else {
      const glm::dvec3 channels = model->radiance(observer, view, sun, o.sun_disc);
      rgb = model->to_srgb(channels);
      spectral = channels;
    }
    std::printf("%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", az, el, atmos::srgb_luminance(rgb), rgb.x, rgb.y, rgb.z);
    if (three) std::printf(",%.6g,%.6g,%.6g", spectral.x, spectral.y, spectral.z);
    std::printf("\n");
  }
  // Irradiance on a horizontal surface at the observer, as a trailing comment.
  glm::dvec3 sun_rgb, sky_rgb, sun_e(0.0), sky_e(0.0);
  if (o.reference) {
    atmos::ReferenceOptions direct = ref;
    direct.scattering_orders = 1;
    const atmos::ReferenceResult total = atmos::reference_horizontal_irradiance(atmosphere, observer, sun, ref);
    const atmos::ReferenceResult sun_only = atmos::reference_horizontal_irradiance(atmosphere, observer, sun, direct);
    std::vector<double> sky(w.size());
    for (size_t i = 0; i < w.size(); ++i) sky[i] = total.radiance[i] - sun_only.radiance[i];
    sun_rgb = srgb_of_spectrum(sun_only.radiance);
    sky_rgb = srgb_of_spectrum(sky);
    if (three) {
      sun_e = {sun_only.radiance[0], sun_only.radiance[1], sun_only.radiance[2]};
      sky_e = {sky[0], sky[1], sky[2]};
    }
  } else {
    model->horizontal_irradiance(observer, sun, sun_e, sky_e);
    sun_rgb = model->to_srgb(sun_e);
    sky_rgb = model->to_srgb(sky_e);
  }
  const double sun_lux = atmos::srgb_luminance(sun_rgb), sky_lux = atmos::srgb_luminance(sky_rgb);
  std::printf("# horizontal_illuminance_lux=%.6g sun_lux=%.6g sky_lux=%.6g", sun_lux + sky_lux, sun_lux, sky_lux);
  if (three)
    std::printf(" irradiance_W_m2_nm=%.6g;%.6g;%.6g", sun_e.x + sky_e.x, sun_e.y + sky_e.y, sun_e.z + sky_e.z);
  std::printf("\n");
  return 0;
}

// ---------------------------------------------------------------------------
// bench

// The engine plugin over a synthetic engine frame: a camera 300 m above the
// ground looking 3° down, the engine's ground (the sphere) and a few round
// hills in its depth buffer (standard depth, as a GL_DEPTH_COMPONENT32F
// texture) and a grey lit colour; sky above. Median GPU times of 5 frames
// after a warm-up, by day and at sunset (sun 4° high: the low-sun variant).
void bench_plugin(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables, int w, int h) {
  const double R = atmosphere.bottom_radius_m;
  const glm::dvec3 camera(0.0, 0.0, R + 300.0);
  const glm::dvec3 forward = glm::normalize(glm::dvec3(0.0, 1.0, -std::tan(glm::radians(3.0))));
  atmos::FrameInput input;
  input.width = w;
  input.height = h;
  input.view = glm::lookAt(camera, camera + forward, glm::dvec3(0.0, 0.0, 1.0));
  input.projection = glm::perspective(glm::radians(60.0), double(w) / double(h), 0.5, 1e7);
  input.timed = true;
  struct Sphere {
    glm::dvec3 centre;
    double radius;
  };
  const std::vector<Sphere> scene = {{{0.0, 0.0, 0.0}, R},
                                     {{-3e3, 12e3, R - 4e3}, 5e3},
                                     {{9e3, 30e3, R - 8e3}, 10e3},
                                     {{-20e3, 60e3, R - 15e3}, 18e3}};
  std::vector<float> depth(size_t(w) * size_t(h), 1.0f);
  const glm::dmat4 view_projection = input.projection * input.view;
  const glm::dmat4 inverse = glm::inverse(view_projection);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const glm::dvec4 p = inverse * glm::dvec4((x + 0.5) / w * 2.0 - 1.0, (y + 0.5) / h * 2.0 - 1.0, -1.0, 1.0);
      const glm::dvec3 ray = glm::normalize(glm::dvec3(p) / p.w - camera);
      double nearest = -1.0;
      for (const Sphere& sphere : scene) {
        const glm::dvec3 oc = camera - sphere.centre;
        const double b = glm::dot(oc, ray), c = glm::dot(oc, oc) - sphere.radius * sphere.radius;
        const double disc = b * b - c;
        if (disc < 0.0) continue;
        const double t = -b - std::sqrt(disc);
        if (t > 0.0 && (nearest < 0.0 || t < nearest)) nearest = t;
      }
      if (nearest < 0.0) continue;
      const glm::dvec4 clip = view_projection * glm::dvec4(camera + ray * nearest, 1.0);
      depth[size_t(y) * size_t(w) + size_t(x)] = float(0.5 * clip.z / clip.w + 0.5);
    }
  const std::vector<float> colour(size_t(w) * size_t(h) * 4, 400.0f);
  GLuint textures[2] = {0, 0};
  glCreateTextures(GL_TEXTURE_2D, 2, textures);
  glTextureStorage2D(textures[0], 1, GL_DEPTH_COMPONENT32F, w, h);
  glTextureSubImage2D(textures[0], 0, 0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  glTextureStorage2D(textures[1], 1, GL_RGBA16F, w, h);
  glTextureSubImage2D(textures[1], 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, colour.data());
  input.depth = textures[0];
  input.colour = textures[1];
  atmos::AtmospherePass pass(atmosphere, tables, atmos::PlanetFrame{});
  // The last line: a total eclipse (a moon 0.28° wide on the sun, 35° up).
  for (const auto& [name, elevation] : {std::pair<const char*, double>{"plugin", 35.0}, {"plugin.sunset", 4.0},
                                        {"plugin.eclipse", 35.0}}) {
    input.sun_direction = atmos::direction_from_azimuth_elevation(20.0, elevation);
    input.moons.clear();
    if (std::string(name) == "plugin.eclipse")
      input.moons = {atmos::moon_in_sky(camera, input.sun_direction, 0.28 * M_PI / 180.0)};
    pass.render(input);  // warm-up: compiles this variant
    std::vector<double> total, sky_view, volume, composite;
    for (int i = 0; i < 5; ++i) {
      pass.render(input);
      const atmos::PassTimings& t = pass.last_timings();
      total.push_back(t.total_ms());
      sky_view.push_back(t.sky_view_ms);
      volume.push_back(t.volume_ms);
      composite.push_back(t.composite_ms);
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    std::printf("%s.%dx%d\t%.1f\tms\n", name, w, h, median(total));
    std::printf("%s.sky_view\t%.1f\tms\n", name, median(sky_view));
    std::printf("%s.volume\t%.1f\tms\n", name, median(volume));
    std::printf("%s.composite\t%.1f\tms\n", name, median(composite));
    std::fflush(stdout);
  }
  glDeleteTextures(2, textures);
}

// The post-processing chain (PostProcess) over a rendered sky at w x h: the
// filmic operator, bloom (strength 0.05) and auto exposure, each pass's GPU
// time the median of 5 frames after a warm-up (shader compilation, the
// pyramid's textures).
void bench_post(atmos::Renderer& renderer, const atmos::Camera& camera, int w, int h) {
  const atmos::Image hdr = renderer.render(camera, atmos::direction_from_azimuth_elevation(180.0, 12.0));
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  glTextureStorage2D(texture, 1, GL_RGBA32F, w, h);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage2D(texture, 0, 0, 0, w, h, GL_RGB, GL_FLOAT, hdr.rgb.data());
  atmos::PostProcess post;
  atmos::PostSettings settings;
  settings.tone_mapping = atmos::ToneMapping::filmic;
  settings.bloom.strength = 0.05;
  settings.auto_exposure.enabled = true;
  atmos::PostInput input;
  input.colour = texture;
  input.width = w;
  input.height = h;
  input.dt_s = 1.0 / 60.0;
  input.timed = true;
  // The warm-up frame also starts the eye adaptation: in the timed frames the
  // bloom's bright pass does the exposure's reduction (post.bloom includes
  // it, post.exposure is the adaptation alone; docs/post.md).
  post.process(input, settings);
  std::vector<double> bloom, exposure, tone_map;
  for (int i = 0; i < 5; ++i) {
    post.process(input, settings);
    bloom.push_back(post.last_timings().bloom_ms);
    exposure.push_back(post.last_timings().exposure_ms);
    tone_map.push_back(post.last_timings().tone_map_ms);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf("post.bloom.%dx%d\t%.1f\tms\n", w, h, median(bloom));
  std::printf("post.exposure.%dx%d\t%.1f\tms\n", w, h, median(exposure));
  std::printf("post.tonemap.%dx%d\t%.1f\tms\n", w, h, median(tone_map));
  std::fflush(stdout);
  glDeleteTextures(1, &texture);
}

int run_bench(const TableOptions& t, const std::string& size) {
  const atmos::Atmosphere atmosphere = t.atmosphere();
  atmos::PrecomputeOptions options = t.precompute_options();
  const auto start = std::chrono::steady_clock::now();
  const atmos::Tables tables = atmos::precompute_tables(atmosphere, options);
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const auto& step : tables.timings) std::printf("precompute.%s\t%.3f\ts\n", step.name.c_str(), step.seconds);
  std::printf("precompute.total\t%.3f\ts\n", total);
  std::fflush(stdout);
  // The spectral figure of issue 3: 15 wavelengths, 6 orders, default sizes.
  atmos::Atmosphere spectral_atmosphere = atmosphere;
  spectral_atmosphere.wavelengths_nm = atmos::spectral_wavelengths(15);
  atmos::PrecomputeOptions spectral_options = options;
  spectral_options.scattering_orders = 6;
  spectral_options.auto_orders = false;
  const auto spectral_start = std::chrono::steady_clock::now();
  const atmos::Tables spectral_tables = atmos::precompute_tables(spectral_atmosphere, spectral_options);
  std::printf("precompute.spectral15.orders6\t%.3f\ts\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - spectral_start).count());
  std::fflush(stdout);

  const auto [w, h] = parse_size(size);
  auto context = atmos::GlContext::create_headless();
  atmos::Renderer renderer(*context, atmosphere, tables);
  atmos::Camera camera = make_camera(atmos::observer_position(atmosphere, 2.0), 180.0, 10.0, 60.0,
                                     atmos::Projection::perspective, w, h);
  // Median frame and sky-view pass times over `runs` frames after a warm-up
  // (shader compilation, texture residency), printed as `name`.
  auto time_frames = [&](atmos::Renderer& r, const glm::dvec3& sun_direction, int runs, const std::string& name) {
    r.render(camera, sun_direction);
    std::vector<double> frame, sky_view;
    for (int i = 0; i < runs; ++i) {
      r.render(camera, sun_direction);
      frame.push_back(r.last_frame_ms());
      sky_view.push_back(r.last_sky_view_ms());
    }
    std::sort(frame.begin(), frame.end());
    std::sort(sky_view.begin(), sky_view.end());
    std::printf("%s.%dx%d\t%.1f\tms\n", name.c_str(), w, h, frame[frame.size() / 2]);
    std::printf("%s.sky_view\t%.1f\tms\n", name.c_str(), sky_view[sky_view.size() / 2]);
    std::fflush(stdout);
  };
  time_frames(renderer, atmos::direction_from_azimuth_elevation(150.0, 20.0), 5, "render");
  // A total eclipse seen from the centre of the shadow: the sky-view pass
  // integrates single scattering along every view ray, eclipsed node by node.
  {
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(150.0, 40.0);
    renderer.set_moons({atmos::moon_in_sky(camera.position, sun, 0.27 * M_PI / 180.0)});
    time_frames(renderer, sun, 3, "render.eclipse");
    renderer.set_moons({});
  }
  // Twilight with the spectral tables: the sky-view pass integrates the low
  // sun's single scattering at all 15 wavelengths.
  atmos::Renderer spectral_renderer(*context, spectral_atmosphere, spectral_tables);
  time_frames(spectral_renderer, atmos::direction_from_azimuth_elevation(150.0, -3.0), 3, "render.spectral15.twilight");
  bench_plugin(atmosphere, tables, w, h);
  bench_post(renderer, camera, w, h);
  return 0;
}

// ---------------------------------------------------------------------------
// plot-data

int run_plot_data(const TableOptions& t, const std::string& out) {
  namespace pd = atmos_cli::plot_data;
  // Options and the output directory first: a bad value or path is reported
  // before the precomputation.
  const atmos::Atmosphere atmosphere = t.atmosphere();
  (void)t.precompute_options();
  pd::prepare_directory(out);
  auto wrote = [](const std::string& path) {
    std::printf("wrote %s\n", path.c_str());
    std::fflush(stdout);
  };
  wrote(pd::write_csv(out, "solar.csv", [&](std::ostream& o) { pd::write_solar(o, atmosphere); }));
  wrote(pd::write_csv(out, "extinction.csv", [&](std::ostream& o) { pd::write_extinction(o, atmosphere); }));
  wrote(pd::write_csv(out, "transmittance.csv", [&](std::ostream& o) { pd::write_transmittance(o, atmosphere); }));
  const LoadedTables loaded = load_tables(t);
  wrote(pd::write_csv(out, "sky.csv", [&](std::ostream& o) { pd::write_sky(o, loaded.atmosphere, loaded.tables); }));
  wrote(pd::write_csv(out, "convergence.csv", [&](std::ostream& o) { pd::write_convergence(o, loaded.tables); }));
  const pd::Info info{t.planet, t.tables, t.solar.empty() ? std::string("planet file") : t.solar, t.density_scale};
  wrote(pd::write_csv(out, "info.csv", [&](std::ostream& o) {
    pd::write_info(o, loaded.atmosphere, info, loaded.tables.scattering_orders);
  }));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"atmos: physically based rendering of planetary atmospheres"};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for all commands");

  TableOptions table_options;
  RenderOptions render;
  auto* render_cmd = app.add_subcommand("render", "Render images; with no arguments, the default gallery");
  table_options.add(*render_cmd);
  render_cmd->add_option("--altitude", render.altitude, "Camera altitude above the ground, metres")->capture_default_str();
  render_cmd->add_option("--position", render.position, "Camera position X,Y,Z in metres from the planet centre");
  render_cmd->add_option("--look", render.look, "View direction AZ,EL in degrees (azimuth from north towards east)");
  render_cmd->add_option("--fov", render.fov, "Field of view, degrees (perspective: vertical, default 60; fisheye: default 180)");
  render_cmd->add_option("--projection", render.projection, "perspective|fisheye|equirect")
      ->check(CLI::IsMember({"perspective", "fisheye", "equirect"}))
      ->capture_default_str();
  render_cmd->add_option("--sun-elevation", render.sun_elevation, "Sun elevation, degrees")->capture_default_str();
  render_cmd->add_option("--sun-azimuth", render.sun_azimuth, "Sun azimuth, degrees from north towards east")->capture_default_str();
  render_cmd->add_option("--size", render.size, "Image size WxH")->capture_default_str();
  render_cmd->add_option("--exposure", render.exposure, "Exposure value EV100 for PNG output")->capture_default_str();
  render_cmd->add_option("-o,--output", render.outputs, "Output file (.png or .exr), repeatable (default atmos.png)");
  render_cmd->add_option("--precision", render.precision, "GPU table precision: half|full")
      ->check(CLI::IsMember({"half", "full"}))
      ->capture_default_str();
  render_cmd->add_flag("--cpu", render.cpu, "Render on the CPU with the same functions (no OpenGL)");
  render_cmd->add_flag("--stars", render.stars,
                       "Draw the star field also with the sun above the horizon (it is drawn whenever the sun is "
                       "below it)");
  render_cmd->add_option("--moon", render.moons,
                         "A moon AZ,EL,ANGULAR_RADIUS_DEG in the camera's sky (degrees; at the Moon's distance, "
                         "384 400 km): it eclipses the sun where it covers it; repeatable (at most 4)");
  auto* tonemap_opt = render_cmd->add_option("--tonemap", render.tonemap, "PNG tone mapping: exp|reinhard|filmic|aces")
                          ->check(CLI::IsMember({"exp", "reinhard", "filmic", "aces"}))
                          ->capture_default_str();
  auto* bloom_opt = render_cmd->add_option("--bloom", render.bloom,
                                           "Bloom strength in [0, 1]: the fraction of the light above saturation "
                                           "spread as glare (PNG)")
                        ->capture_default_str();
  auto* auto_exposure_opt =
      render_cmd->add_flag("--auto-exposure", render.auto_exposure,
                           "Expose the PNG from the image's log-average luminance (seed 000 eq. 4.28) instead of --exposure");

  TableOptions precompute_options;
  auto* precompute_cmd = app.add_subcommand("precompute", "Build or verify the table cache; print sizes and timings");
  precompute_options.add(*precompute_cmd);

  TableOptions sample_tables;
  SampleOptions sample;
  auto* sample_cmd = app.add_subcommand(
      "sample", "Radiance for directions read as CSV (azimuth_deg,elevation_deg) from stdin or --directions");
  sample_tables.add(*sample_cmd);
  sample_cmd->add_option("--altitude", sample.altitude, "Observer altitude above the ground, metres")->capture_default_str();
  sample_cmd->add_option("--sun-elevation", sample.sun_elevation, "Sun elevation, degrees")->capture_default_str();
  sample_cmd->add_option("--sun-azimuth", sample.sun_azimuth, "Sun azimuth, degrees from north towards east")->capture_default_str();
  sample_cmd->add_option("--directions", sample.directions, "CSV file of directions (default: stdin)");
  sample_cmd->add_flag("--reference", sample.reference, "Use the brute-force Monte Carlo reference instead of the tables");
  sample_cmd->add_option("--paths", sample.paths, "Monte Carlo paths per direction with --reference")->capture_default_str();
  sample_cmd->add_flag("--sun-disc", sample.sun_disc, "Include the sun disc in the radiance (tables only)");

  TableOptions bench_options;
  std::string bench_size = "1920x1080";
  auto* bench_cmd = app.add_subcommand("bench", "Print precomputation and render timings as name<TAB>value<TAB>unit");
  bench_options.add(*bench_cmd);
  bench_cmd->add_option("--size", bench_size, "Render size WxH")->capture_default_str();

  TableOptions plot_options;
  std::string plot_out;
  auto* plot_cmd = app.add_subcommand(
      "plot-data", "Write the CSV files behind the plots (solar spectrum, extinction, transmittance, sky, "
                   "convergence) into a directory; scripts/plots.py draws them");
  plot_options.add(*plot_cmd);
  plot_cmd->add_option("--out", plot_out, "Output directory (created if missing; its parent must exist)")->required();

  if (argc > 1 && argv[1][0] != '-') {
    const std::string command = argv[1];
    if (command != "render" && command != "precompute" && command != "sample" && command != "bench" &&
        command != "plot-data") {
      std::fprintf(stderr,
                   "atmos: error: unknown command \"%s\" (expected render, precompute, sample, bench or plot-data)\n",
                   command.c_str());
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "atmos: error: %s\n", e.what());
    return 2;
  }

  try {
    for (double* v : {&render.altitude, &render.fov, &render.sun_elevation, &render.sun_azimuth, &render.exposure,
                      &sample.altitude, &sample.sun_elevation, &sample.sun_azimuth, &render.bloom})
      finite(*v, "numeric option");
    render.post = tonemap_opt->count() > 0 || bloom_opt->count() > 0 || auto_exposure_opt->count() > 0;
    if (render.bloom < 0.0 || render.bloom > 1.0) throw UsageError("--bloom must be in [0, 1]");
    if (*render_cmd) {
      // Only the planet and table options (and --precision, --cpu) may be
      // given for the gallery (e.g. --planet mars --wavelengths 15).
      const std::set<std::string> gallery_options = {"--planet",  "--orders",    "--wavelengths", "--density-scale",
                                                     "--solar",   "--tables",    "--cache-dir",   "--no-cache",
                                                     "--precision", "--cpu"};
      bool gallery = true;
      for (const auto* opt : render_cmd->get_options())
        if (opt->count() > 0 && gallery_options.count(opt->get_name()) == 0) gallery = false;
      return run_render(render, table_options, gallery);
    }
    if (*precompute_cmd) return run_precompute(precompute_options);
    if (*sample_cmd) return run_sample(sample, sample_tables);
    if (*bench_cmd) return run_bench(bench_options, bench_size);
    if (*plot_cmd) return run_plot_data(plot_options, plot_out);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "atmos: error: %s\n", e.what());
    return 2;
  } catch (const atmos::Error& e) {
    std::fprintf(stderr, "atmos: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "atmos: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
