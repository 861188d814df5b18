#include "options.hpp"

#include <glm/geometric.hpp>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "atmos/ephemeris.hpp"
#include "atmos/planet_parameters.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/sky.hpp"

namespace atmos_cli {

namespace {

std::string preset_list() {
  std::string names;
  for (const auto& n : atmos::preset_names()) names += (names.empty() ? "" : ", ") + n;
  return names;
}

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

int parse_orders(const std::string& orders) {
  char* end = nullptr;
  const long k = std::strtol(orders.c_str(), &end, 10);
  if (end == orders.c_str() || *end != '\0' || k < 1 || k > 100)
    throw UsageError("--orders must be auto or an integer in [1, 100], got \"" + orders + "\"");
  return int(k);
}

}  // namespace

std::string quote(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

double finite(double value, const std::string& option) {
  if (!std::isfinite(value)) throw UsageError(option + " must be a finite number, got " + quote(value));
  return value;
}

std::vector<double> parse_numbers(const std::string& text, size_t count, const std::string& option,
                                  const std::string& format) {
  const std::string expected =
      option + " expects " + format + " (" + std::to_string(count) + " comma-separated numbers), got \"" + text + "\"";
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    double v = 0.0;
    try {
      size_t used = 0;
      v = std::stod(item, &used);
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw UsageError(expected);
    }
    out.push_back(finite(v, option));
  }
  if (out.size() != count || (!text.empty() && text.back() == ',')) throw UsageError(expected);
  return out;
}

// ---------------------------------------------------------------------------
// The planet

void PlanetOptions::add(CLI::App& app) {
  app.add_option("--planet", planet, "Planet: a preset (" + preset_list() + ") or a planet JSON file")
      ->type_name("NAME|FILE")
      ->capture_default_str();
  app.add_option("--wavelengths", wavelengths,
                 "Working wavelengths, N " + atmos::valid_range_text(atmos::planet_parameter("wavelengths")) +
                     ": 3 is the fast mode (680, 550, 440 nm), more are spectral, "
                 "evenly spaced over 360-830 nm and converted to colour with the CIE 1931 2-degree observer "
                 "(default: the planet file's; 3 for the presets)")
      ->type_name("N");
  app.add_option("--density-scale", density_scale,
                 "Multiply the density of every constituent by X, " +
                     atmos::valid_range_text(atmos::planet_parameter("density_scale")))
      ->type_name("X")
      ->capture_default_str();
  app.add_option("--solar", solar,
                 "Shape of the solar spectrum, keeping its irradiance over 360-830 nm: table (ASTM E490) or "
                 "blackbody:T (T in kelvin, in [1000, 100000]) (default: the planet file's)")
      ->type_name("table|blackbody:T");
}

void PlanetOptions::validate() const {
  // The ranges of atmos/planet_parameters.hpp, as the planet files'.
  try {
    if (wavelengths != 0) atmos::check_planet_parameter("wavelengths", double(wavelengths), "--wavelengths");
    atmos::check_planet_parameter("density_scale", density_scale, "--density-scale");
  } catch (const atmos::Error& e) {
    throw UsageError(e.what());
  }
  if (!solar.empty() && solar != "table") {
    const std::string prefix = "blackbody:";
    char* end = nullptr;
    const char* t_text = solar.c_str() + prefix.size();
    const double t = solar.rfind(prefix, 0) == 0 ? std::strtod(t_text, &end) : 0.0;
    if (solar.rfind(prefix, 0) != 0 || end == t_text || *end != '\0' || !(t >= 1000.0 && t <= 100000.0))
      throw UsageError("--solar must be table or blackbody:T with T in [1000, 100000] kelvin, got \"" + solar + "\"");
  }
}

atmos::Atmosphere PlanetOptions::atmosphere() const {
  validate();
  atmos::Atmosphere a = atmos::load_atmosphere(planet);
  if (wavelengths != 0) a.wavelengths_nm = atmos::spectral_wavelengths(wavelengths);
  if (density_scale != 1.0) atmos::scale_density(a, density_scale);
  if (!solar.empty()) atmos::set_solar_spectrum(a, solar);
  a.validate();
  return a;
}

// ---------------------------------------------------------------------------
// The tables

void TableOptions::add(CLI::App& app) {
  app.add_option("--orders", orders,
                 "Scattering orders: an integer K in [1, 100], or auto: orders are added until the rest would add "
                 "less than 0.1 % of the light (in the sky and on the ground), at most 64; where the orders "
                 "foretell that cap, the rest is solved at once from order 16")
      ->type_name("K|auto")
      ->capture_default_str();
  app.add_option("--tables", sizes,
                 "Table sizes: default (transmittance 256x64, irradiance 64x16, scattering 8x32x128x32) or small "
                 "(64x16, 32x8, 4x16x32x8; for tests)")
      ->type_name("default|small")
      ->check(CLI::IsMember({"default", "small"}).description(""))
      ->capture_default_str();
}

void TableOptions::validate() const {
  if (orders != "auto") (void)parse_orders(orders);
}

atmos::PrecomputeOptions TableOptions::precompute_options() const {
  validate();
  atmos::PrecomputeOptions o;
  if (orders == "auto") {
    o.auto_orders = true;
    o.scattering_orders = 64;
  } else {
    o.scattering_orders = parse_orders(orders);
  }
  if (sizes == "small") o.sizes = atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8};
  return o;
}

int TableOptions::fixed_orders() const {
  if (orders == "auto") throw UsageError("--orders auto applies to the tables; give the reference a number K");
  return parse_orders(orders);
}

void CacheOptions::add(CLI::App& app) {
  auto* dir = app.add_option("--cache-dir", directory,
                             "Table cache directory (default: $ATMOS_CACHE_DIR, else $XDG_CACHE_HOME/atmos, else "
                             "~/.cache/atmos)")
                  ->type_name("DIR");
  app.add_flag("--no-cache", disabled, "Always precompute the tables; neither read nor write the cache")
      ->excludes(dir);
}

LoadedTables load_tables(const PlanetOptions& planet, const TableOptions& tables, const CacheOptions& cache,
                         bool progress, bool ground_albedo_response) {
  return load_tables(planet.atmosphere(), tables, cache, progress, ground_albedo_response);
}

LoadedTables load_tables(const atmos::Atmosphere& atmosphere, const TableOptions& tables, const CacheOptions& cache,
                         bool progress, bool ground_albedo_response) {
  LoadedTables out;
  out.atmosphere = atmosphere;
  atmos::PrecomputeOptions options = tables.precompute_options();
  options.ground_albedo_response = ground_albedo_response;
  if (progress) attach_progress(options);
  if (cache.disabled) {
    out.tables = atmos::precompute_tables(out.atmosphere, options);
    out.status = "computed (cache disabled)";
    return out;
  }
  const std::string dir = cache.directory.empty() ? atmos::default_cache_directory() : cache.directory;
  atmos::CacheResult r = atmos::load_or_precompute_tables(out.atmosphere, options, dir);
  if (!r.problem.empty()) std::fprintf(stderr, "atmos: warning: %s\n", r.problem.c_str());
  out.status = r.status == atmos::CacheStatus::hit        ? "loaded from cache " + r.path
               : r.status == atmos::CacheStatus::computed ? "computed, cached in " + r.path
                                                          : "recomputed (invalid cache), cached in " + r.path;
  out.tables = std::move(r.tables);
  return out;
}

// ---------------------------------------------------------------------------
// The viewpoint, the sun and the moons

void ViewpointOptions::add(CLI::App& app) {
  auto* a = app.add_option("--altitude", altitude,
                           "Altitude of the viewpoint above the ground, metres, in [0, 1e12]; it stands above the "
                           "north pole, whose local frame is x east, y north, z up")
                ->type_name("M")
                ->capture_default_str();
  app.add_option("--position", position,
                 "Viewpoint at X,Y,Z metres from the planet's centre (not inside the planet) instead of "
                 "--altitude; azimuths and elevations are then in the local frame (east, north, up) of the "
                 "ground point below it")
      ->type_name("X,Y,Z")
      ->excludes(a);
  latitude_option = app.add_option("--latitude", latitude,
                                   "Latitude of the viewpoint, degrees north, in [-90, 90]: it stands --altitude "
                                   "above that point of the planet (the globe's geographic coordinates), azimuths "
                                   "and elevations in its local frame (east, north, up); with --longitude")
                        ->type_name("DEG");
  auto* lon = app.add_option("--longitude", longitude,
                             "Longitude of the viewpoint, degrees east (west negative); with --latitude")
                  ->type_name("DEG");
  latitude_option->needs(lon)->excludes("--position");
  lon->needs(latitude_option)->excludes("--position");
}

void ViewpointOptions::validate() const {
  if (at_place()) {
    finite(latitude, "--latitude");
    finite(longitude, "--longitude");
    if (latitude < -90.0 || latitude > 90.0)
      throw UsageError("--latitude must be in [-90, 90] degrees, got " + quote(latitude));
  }
  if (!position.empty()) {
    (void)parse_numbers(position, 3, "--position", "X,Y,Z");
  } else {
    finite(altitude, "--altitude");
    if (!(altitude >= 0.0) || altitude > 1e12)
      throw UsageError("--altitude must be in [0, 1e12] metres, got " + quote(altitude));
  }
}

Viewpoint ViewpointOptions::viewpoint(const atmos::Atmosphere& atmosphere) const {
  validate();
  Viewpoint v;
  if (at_place()) {
    // The local frame of the point at (latitude, longitude) of the sphere:
    // up along its radius, east along the parallel, north along the meridian.
    const atmos::LocalFrame frame = atmos::local_frame({latitude, longitude, 0.0});
    v.position = frame.up * (atmosphere.bottom_radius_m + altitude);
    v.local = glm::dmat3(frame.east, frame.north, frame.up);
    v.from_position = true;
    return v;
  }
  if (position.empty()) {
    v.position = atmos::observer_position(atmosphere, altitude);
    return v;
  }
  const auto p = parse_numbers(position, 3, "--position", "X,Y,Z");
  v.position = {p[0], p[1], p[2]};
  v.from_position = true;
  if (glm::length(v.position) < atmosphere.bottom_radius_m)
    throw UsageError("--position is inside the planet (closer to its centre than the ground radius, " +
                     quote(atmosphere.bottom_radius_m) + " m)");
  // The local (east, north, up) frame of the point below; east is +x where
  // the up direction is the polar axis.
  const glm::dvec3 up = glm::normalize(v.position);
  glm::dvec3 east = glm::cross(glm::dvec3(0, 0, 1), up);
  if (glm::length(east) < 1e-9) east = glm::dvec3(1, 0, 0);
  east = glm::normalize(east);
  const glm::dvec3 north = glm::cross(up, east);
  v.local = glm::dmat3(east, north, up);
  return v;
}

void SunOptions::add(CLI::App& app) {
  app.add_option("--sun-elevation", elevation, "Sun elevation above the horizon, degrees, in [-90, 90]")
      ->type_name("DEG")
      ->capture_default_str();
  app.add_option("--sun-azimuth", azimuth, "Sun azimuth, degrees clockwise from north (east is 90), any finite value")
      ->type_name("DEG")
      ->capture_default_str();
}

void SunOptions::validate() const {
  finite(elevation, "--sun-elevation");
  finite(azimuth, "--sun-azimuth");
  if (elevation < -90.0 || elevation > 90.0)
    throw UsageError("--sun-elevation must be in [-90, 90] degrees, got " + quote(elevation));
}

void StereoOptions::add(CLI::App& app, const std::string& layouts) {
  app.add_option("--stereo", mode, "Both eyes, each through its own off-axis frustum, " + layouts)
      ->type_name("none|side-by-side|anaglyph")
      ->check(CLI::IsMember({"none", "side-by-side", "anaglyph"}).description(""))
      ->capture_default_str();
  app.add_option("--ipd", ipd,
                 "With --stereo: the distance between the eyes, metres, in (0, 1e7] (wider than a person's for "
                 "distant relief: hyperstereo)")
      ->type_name("M")
      ->capture_default_str();
  app.add_option("--convergence", convergence,
                 "With --stereo: the distance at which the eyes' images coincide (the screen's plane), metres, > 0 "
                 "(inf: the sky at zero disparity)")
      ->type_name("M")
      ->capture_default_str();
}

void StereoOptions::validate() const {
  finite(ipd, "--ipd");
  if (!(ipd > 0.0 && ipd <= 1e7)) throw UsageError("--ipd must be in (0, 1e7] metres, got " + quote(ipd));
  if (!(convergence > 0.0)) throw UsageError("--convergence must be > 0 metres, got " + quote(convergence));
}

glm::dvec3 SunOptions::direction(const Viewpoint& viewpoint) const {
  validate();
  return viewpoint.local * atmos::direction_from_azimuth_elevation(azimuth, elevation);
}

namespace {

struct MoonInSky {
  double azimuth, elevation, angular_radius_deg;
};

MoonInSky parse_moon(const std::string& text) {
  const auto v = parse_numbers(text, 3, "--moon", "AZ,EL,ANGULAR_RADIUS_DEG");
  if (v[1] < -90.0 || v[1] > 90.0)
    throw UsageError("--moon elevation must be in [-90, 90] degrees, got " + quote(v[1]));
  if (!(v[2] > 0.0) || v[2] > 10.0)
    throw UsageError("--moon angular radius must be in (0, 10] degrees, got " + quote(v[2]));
  return {v[0], v[1], v[2]};
}

}  // namespace

void MoonOptions::add(CLI::App& app) {
  app.add_option("--moon", moons,
                 "A moon in the viewpoint's sky: azimuth AZ and elevation EL in [-90, 90] (degrees, as the sun's), "
                 "angular radius in (0, 10] degrees (the Moon's is about 0.26), at the Moon's mean distance "
                 "(384 400 km); an opaque sphere that eclipses the sun where it covers it. Repeatable, at most " +
                     std::to_string(atmos::kMaxMoons))
      ->type_name("AZ,EL,ANGULAR_RADIUS_DEG");
}

void MoonOptions::validate() const {
  if (moons.size() + (moon_of_date_m ? 1 : 0) > size_t(atmos::kMaxMoons))
    throw UsageError("--moon: at most " + std::to_string(atmos::kMaxMoons) + " moons" +
                     (moon_of_date_m ? std::string(" with the Moon of --date") : std::string()) + ", got " +
                     std::to_string(moons.size()) + " --moon");
  for (const std::string& text : moons) (void)parse_moon(text);
}

std::vector<atmos::Moon> MoonOptions::place(const Viewpoint& viewpoint, const atmos::Atmosphere& atmosphere) const {
  validate();
  std::vector<atmos::Moon> out;
  for (const std::string& text : moons) {
    const MoonInSky m = parse_moon(text);
    out.push_back(atmos::moon_in_sky(
        viewpoint.position, viewpoint.local * atmos::direction_from_azimuth_elevation(m.azimuth, m.elevation),
        m.angular_radius_deg * M_PI / 180.0));
    try {
      atmos::validate_moons({out.back()}, atmosphere.top_radius_m);
    } catch (const atmos::Error& e) {
      throw UsageError("--moon " + text + ": " + e.what());
    }
  }
  if (moon_of_date_m) {
    // The ephemeris' topocentric vector from the ground point below the
    // viewpoint: the Moon stands where an observer there sees it (the
    // parallax of the real Earth's ellipsoid, not of the planet's sphere).
    const glm::dvec3 ground = glm::normalize(viewpoint.position) * atmosphere.bottom_radius_m;
    out.push_back({ground + *moon_of_date_m, atmos::kMoonRadiusM});
    atmos::validate_moons({out.back()}, atmosphere.top_radius_m);
  }
  return out;
}

void DateOptions::add(CLI::App& app) {
  app.add_option("--date", date,
                 "UTC date and time YYYY-MM-DDTHH:MM:SSZ (years 1800-2199): the sun and the Moon (an eclipsing "
                 "sphere of its real size and distance) of that instant seen from --latitude, --longitude "
                 "(solar position: VSOP87 as Meeus 1998 ch. 25; Moon: Meeus 1998 ch. 47), instead of "
                 "--sun-elevation and --sun-azimuth")
      ->type_name("YYYY-MM-DDTHH:MM:SSZ")
      ->needs("--latitude")
      ->needs("--longitude")
      ->excludes("--sun-elevation")
      ->excludes("--sun-azimuth");
}

void DateOptions::apply(const ViewpointOptions& viewpoint, SunOptions& sun, MoonOptions& moons) const {
  if (!given()) return;
  viewpoint.validate();
  atmos::SkyOfDate sky;
  try {
    sky = atmos::sky_of_date(atmos::parse_utc_time(date), {viewpoint.latitude, viewpoint.longitude, 0.0});
  } catch (const atmos::Error& e) {
    throw UsageError(std::string("--date: ") + e.what());
  }
  sun.azimuth = sky.sun.azimuth_deg;
  sun.elevation = sky.sun.elevation_deg;
  moons.moon_of_date_m = sky.moon.topocentric_m;
}

// ---------------------------------------------------------------------------
// The ground

void SurfaceOption::add(CLI::App& app) {
  app.add_option("--surface", surface,
                 "The ground: globe (the planet file's terrain: relief, imagery and coastlines drawn by atmos::Globe "
                 "and composited by the engine plugin; the viewpoint's altitude is then above the terrain below it; "
                 "needs OpenGL) or sphere (the analytic sphere of the bottom radius with the planet's ground albedo, "
                 "the altitude above it; the only ground of --cpu and --precision half). Default: globe, or sphere "
                 "with --cpu or --precision half")
      ->type_name("globe|sphere")
      ->check(CLI::IsMember({"globe", "sphere"}).description(""));
  app.add_flag("--planet-albedo", planet_albedo,
               "With the globe: light the air and the sky light with the planet file's constant ground albedo "
               "instead of the mean albedo of the globe's ground around the camera (its regional albedo; the "
               "tables then hold their ground albedo response)");
}

// ---------------------------------------------------------------------------
// The image size

void SizeOption::add(CLI::App& app, const std::string& what) {
  app.add_option("--size", size, what + ", WxH in pixels, each in [1, 16384]")->type_name("WxH")->capture_default_str();
}

std::pair<int, int> SizeOption::parse() const {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  std::stringstream ss(size);
  if (!(ss >> w >> x >> h) || (x != 'x' && x != 'X') || (ss >> extra))
    throw UsageError("--size expects WxH, e.g. 1280x720, got \"" + size + "\"");
  if (w < 1 || h < 1 || w > 16384 || h > 16384)
    throw UsageError("--size must be between 1x1 and 16384x16384, got " + size);
  return {w, h};
}

}  // namespace atmos_cli
