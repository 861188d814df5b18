// The options several `atmos` commands share, each defined once: its name,
// help text, default and validation are the same in every command that
// registers it. Validation throws UsageError (exit code 2) with one line that
// names the option; commands validate every option before any slow work
// (reading stdin, the precomputation).
#pragma once

#include <CLI/CLI.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/stereo.hpp"
#include "atmos/tables.hpp"

namespace atmos_cli {

// A bad command-line value: reported as a usage error (exit code 2).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// One subcommand: its CLI11 app and what runs it once it was parsed (throws
// UsageError for bad values, atmos::Error or another exception at run time).
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

// A number as the messages quote it: "%g" (1e12, 0.25, nan).
std::string quote(double value);

// `value` if it is finite, else UsageError "<option> must be a finite number".
double finite(double value, const std::string& option);

// `count` comma-separated finite numbers, e.g. "10,20,0.3"; `format` names
// them in the message (e.g. "AZ,EL").
std::vector<double> parse_numbers(const std::string& text, size_t count, const std::string& option,
                                  const std::string& format);

// --planet, --wavelengths, --density-scale, --solar: which atmosphere
// (render, precompute, sample, bench, plot-data).
struct PlanetOptions {
  std::string planet = "earth";
  int wavelengths = 0;  // 0: the planet file's
  double density_scale = 1.0;
  std::string solar;  // empty: the planet file's

  void add(CLI::App& app);
  // Checks the values (UsageError); an invalid planet file is atmos::Error.
  void validate() const;
  // The planet with the wavelength, density and solar options applied.
  atmos::Atmosphere atmosphere() const;
};

// --orders, --tables: how the tables are computed (render, precompute,
// sample, bench, plot-data).
struct TableOptions {
  std::string orders = "4";
  std::string sizes = "default";

  void add(CLI::App& app);
  void validate() const;
  atmos::PrecomputeOptions precompute_options() const;
  // A fixed number of orders (the reference has no auto mode).
  int fixed_orders() const;
};

// --cache-dir, --no-cache: the table cache (render, precompute, sample,
// plot-data; bench always precomputes, which is what it times).
struct CacheOptions {
  std::string directory;  // empty: atmos::default_cache_directory()
  bool disabled = false;

  void add(CLI::App& app);
};

// The atmosphere and its tables, from the cache or precomputed, and how they
// were obtained ("loaded from cache …", "computed, cached in …").
struct LoadedTables {
  atmos::Atmosphere atmosphere;
  atmos::Tables tables;
  std::string status;
};

// `progress`: a progress bar on stderr while precomputing, if it is a terminal.
// `ground_albedo_response`: the tables' response to the ground albedo too
// (the globe's regional albedo, PrecomputeOptions::ground_albedo_response).
LoadedTables load_tables(const PlanetOptions& planet, const TableOptions& tables, const CacheOptions& cache,
                         bool progress, bool ground_albedo_response = false);
// The same for an atmosphere already loaded (e.g. the globe's, continued
// below the datum: atmos::extend_below_datum).
LoadedTables load_tables(const atmos::Atmosphere& atmosphere, const TableOptions& tables, const CacheOptions& cache,
                         bool progress, bool ground_albedo_response = false);

// Where the camera (render) or the observer (sample) is, and its local frame:
// the columns of `local` are east, north and up at the point of the ground
// below it. Azimuths and elevations of the view, the sun and the moons are
// in that frame.
struct Viewpoint {
  glm::dvec3 position{0.0};  // planet-centred, metres
  glm::dmat3 local{1.0};
  bool from_position = false;  // --position given (else --altitude, above the north pole)
};

// --altitude, --position, --latitude, --longitude (render, sample).
struct ViewpointOptions {
  double altitude = 2.0;
  std::string position;
  double latitude = 0.0;   // --latitude, degrees north
  double longitude = 0.0;  // --longitude, degrees east
  CLI::Option* latitude_option = nullptr;

  void add(CLI::App& app);
  // --latitude and --longitude given: the viewpoint stands above that point
  // of the planet (planet-centred frame: z towards the north pole, x towards
  // longitude 0, as atmos::Globe's), not above the north pole.
  bool at_place() const { return latitude_option != nullptr && latitude_option->count() > 0; }
  void validate() const;
  // Throws UsageError if --position is inside the planet.
  Viewpoint viewpoint(const atmos::Atmosphere& atmosphere) const;
};

// --sun-elevation, --sun-azimuth (render, sample).
struct SunOptions {
  double elevation = 30.0;
  double azimuth = 180.0;

  void add(CLI::App& app);
  void validate() const;
  // Unit vector towards the sun, planet-centred.
  glm::dvec3 direction(const Viewpoint& viewpoint) const;
};

// --stereo, --ipd, --convergence: both eyes, each through its own off-axis
// frustum (atmos/stereo.hpp), and how they are combined (render, view).
struct StereoOptions {
  std::string mode = "none";  // none, side-by-side or anaglyph
  double ipd = 0.064;         // the eyes' distance, m
  double convergence = 10.0;  // the distance of zero disparity, m

  // `layouts`: what side-by-side and anaglyph give in this command.
  void add(CLI::App& app, const std::string& layouts);
  void validate() const;
  atmos::StereoRig rig() const { return {ipd, convergence}; }
};

// --moon AZ,EL,ANGULAR_RADIUS_DEG, repeatable (render, sample).
struct MoonOptions {
  std::vector<std::string> moons;
  // The Moon of --date (DateOptions::apply): the Earth-fixed vector from the
  // viewpoint's ground point to the Moon's centre, metres; placed after the
  // --moon moons.
  std::optional<glm::dvec3> moon_of_date_m;

  void add(CLI::App& app);
  // Checks the numbers and their count, without placing the moons.
  void validate() const;
  // The moons in the sky of `viewpoint`, at the Moon's mean distance
  // (atmos::moon_in_sky); UsageError if one reaches into the atmosphere.
  std::vector<atmos::Moon> place(const Viewpoint& viewpoint, const atmos::Atmosphere& atmosphere) const;
};

// --date YYYY-MM-DDTHH:MM:SSZ (render, sample): the sun and the Moon of that
// UTC instant seen from the viewpoint's --latitude and --longitude
// (atmos/ephemeris.hpp), instead of --sun-elevation and --sun-azimuth.
struct DateOptions {
  std::string date;

  // After ViewpointOptions::add and SunOptions::add: --date needs
  // --latitude and --longitude and excludes the sun's options.
  void add(CLI::App& app);
  bool given() const { return !date.empty(); }
  // With --date: the sun's geometric azimuth and elevation of the date in
  // `sun`, the Moon in `moons`. UsageError for a bad date or place.
  void apply(const ViewpointOptions& viewpoint, SunOptions& sun, MoonOptions& moons) const;
};

// --surface globe|sphere (render): what the ground under the atmosphere is.
// Not given: the globe, except with --cpu or --precision half, which only
// the sphere supports.
struct SurfaceOption {
  std::string surface;  // "" = not given
  bool planet_albedo = false;  // --planet-albedo: the air over the globe lit by the planet file's albedo

  void add(CLI::App& app);
  bool globe(bool cpu, bool half_precision) const {
    return surface.empty() ? !(cpu || half_precision) : surface == "globe";
  }
};

// --size WxH (render, bench: the same format and range, each command its
// own default and description of what is that size).
struct SizeOption {
  std::string size;

  explicit SizeOption(std::string default_size) : size(std::move(default_size)) {}
  void add(CLI::App& app, const std::string& what);
  std::pair<int, int> parse() const;
};

}  // namespace atmos_cli
