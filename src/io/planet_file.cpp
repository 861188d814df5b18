// Planet files: JSON with the unit of every quantity stated next to it.
// The format is documented in docs/planet-format.md. Parsing checks every key
// and unit and names the offending one; the physics (spectra from physical
// inputs, validation) is atmosphere.hpp's.
#include "atmos/planet_file.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "atmos/planet_parameters.hpp"
#include "data/embedded_files.hpp"

namespace atmos {
namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& origin, const std::string& what) {
  throw Error(origin + ": " + what);
}

// A string of the file (a key, a unit) as JSON writes it: quoted, with its
// control characters escaped, so that a message naming it stays on one line.
std::string quoted(const std::string& text) { return json(text).dump(-1, ' ', false, json::error_handler_t::replace); }

// A planet's or constituent's name, shown in messages and reports: one line
// of printable text.
std::string name_or(const json& object, const std::string& fallback, const std::string& origin,
                    const std::string& key) {
  if (!object.contains("name") || !object.at("name").is_string()) return fallback;
  const std::string name = object.at("name").get<std::string>();
  for (const char c : name)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      fail(origin, key + " " + quoted(name) + " must be one line without control characters");
  return name;
}

// Runs a constructor of the physics layer (a spectrum from samples or from
// physical inputs, which refuses e.g. a result that overflows to infinity)
// and names the file and the key in the Error it may throw.
template <class Build>
Spectrum built(const std::string& origin, const std::string& path, Build&& build) {
  try {
    return build();
  } catch (const Error& e) {
    fail(origin, path + ": " + e.what());
  }
}

double finite_or_fail(const json& v, const std::string& origin, const std::string& path) {
  if (!v.is_number()) fail(origin, path + " must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(origin, path + " must be finite");
  return x;
}

// Rejects keys a planet file must not have, so a typo is an error and not a
// silently ignored parameter.
void check_keys(const json& object, const std::set<std::string>& allowed, const std::string& origin,
                const std::string& path) {
  if (!object.is_object()) fail(origin, path + " must be an object");
  for (const auto& item : object.items()) {
    if (!allowed.count(item.key())) fail(origin, "unknown key " + quoted(item.key()) + " in " + path);
  }
}

const json& require(const json& object, const std::string& key, const std::string& origin,
                    const std::string& path) {
  if (!object.contains(key)) fail(origin, "missing " + path + "." + key);
  return object.at(key);
}

std::string unit_of(const json& q, const std::string& origin, const std::string& path) {
  if (!q.contains("unit") || !q.at("unit").is_string())
    fail(origin, path + " needs a \"unit\" string");
  return q.at("unit").get<std::string>();
}

// Factor that converts a value in `unit` to SI for the given kind of quantity.
double unit_factor(const std::string& kind, const std::string& unit, const std::string& origin,
                   const std::string& path) {
  static const std::map<std::string, std::map<std::string, double>> table = {
      {"length", {{"m", 1.0}, {"km", 1e3}}},
      {"height", {{"m", 1.0}, {"km", 1e3}, {"ft", 0.3048}}},
      {"inverse_length", {{"1/m", 1.0}, {"1/km", 1e-3}, {"1/Mm", 1e-6}}},
      {"angle", {{"rad", 1.0}, {"deg", M_PI / 180.0}, {"arcmin", M_PI / 10800.0}}},
      {"spectral_irradiance", {{"W/m^2/nm", 1.0}}},
      {"irradiance", {{"W/m^2", 1.0}}},
      {"temperature", {{"K", 1.0}}},
      {"distance", {{"au", 1.495978707e11}, {"km", 1e3}, {"m", 1.0}}},
      {"number_density", {{"1/m^3", 1.0}, {"1/cm^3", 1e6}}},
      {"area", {{"m^2", 1.0}, {"cm^2", 1e-4}}},
      {"dimensionless", {{"1", 1.0}}},
  };
  const auto& units = table.at(kind);
  auto it = units.find(unit);
  if (it == units.end()) {
    std::string accepted;
    for (const auto& [name, factor] : units) accepted += (accepted.empty() ? "" : ", ") + name;
    fail(origin, path + " has unit " + quoted(unit) + "; expected one of: " + accepted);
  }
  return it->second;
}

double scalar(const json& parent, const std::string& key, const std::string& kind,
              const std::string& origin, const std::string& path) {
  const std::string p = path + "." + key;
  const json& q = require(parent, key, origin, path);
  check_keys(q, {"value", "unit"}, origin, p);
  const double factor = unit_factor(kind, unit_of(q, origin, p), origin, p);
  return finite_or_fail(require(q, "value", origin, p), origin, p + ".value") * factor;
}

std::vector<double> number_list(const json& v, const std::string& origin, const std::string& path) {
  if (!v.is_array() || v.empty()) fail(origin, path + " must be a non-empty list of numbers");
  std::vector<double> out;
  for (size_t i = 0; i < v.size(); ++i)
    out.push_back(finite_or_fail(v[i], origin, path + "[" + std::to_string(i) + "]"));
  return out;
}

Spectrum parse_spectrum(const json& q, const std::string& kind, const std::vector<double>& wavelengths,
                        const std::string& origin, const std::string& path);

// A value (SI) against the range of its parameter in planet_parameters().
// The samples of spectra (albedo, phase parameters) are checked by
// Atmosphere::validate, whose messages name the wavelength, against the
// same ranges (tests/planet_writer_test.cpp holds them equal).
void check_parameter(const char* name, double value_si, const std::string& origin, const std::string& path) {
  try {
    check_planet_parameter(name, value_si, path);
  } catch (const Error& e) {
    fail(origin, e.what());
  }
}

// A coefficient (m^-1 at the reference density) from physical inputs
// (the formulas are in atmosphere.hpp):
//  - {"rayleigh": {"refractive_index": n, "number_density": N, "king_factor": F}}
//    (F = 1 if omitted): rayleigh_scattering_spectrum;
//  - {"cross_section": σ (area, a value or a spectrum), "number_density": N}:
//    cross_section_spectrum, e.g. an absorber from measured cross sections;
//  - {"angstrom": {"alpha": α, "beta": β_A, "scale_height": H}}:
//    angstrom_aerosol_spectrum.
Spectrum parse_physical_coefficient(const json& q, const std::string& origin, const std::string& path) {
  if (q.contains("rayleigh")) {
    check_keys(q, {"rayleigh"}, origin, path);
    const json& r = q.at("rayleigh");
    const std::string p = path + ".rayleigh";
    check_keys(r, {"refractive_index", "number_density", "king_factor"}, origin, p);
    const double n = finite_or_fail(require(r, "refractive_index", origin, p), origin, p + ".refractive_index");
    const double number = scalar(r, "number_density", "number_density", origin, p);
    const double king = r.contains("king_factor") ? finite_or_fail(r.at("king_factor"), origin, p + ".king_factor") : 1.0;
    if (!(n > 1.0 && n < 2.0)) fail(origin, p + ".refractive_index must be in (1, 2)");
    if (!(number > 0.0)) fail(origin, p + ".number_density must be positive");
    if (!(king >= 1.0 && king < 2.0)) fail(origin, p + ".king_factor must be in [1, 2)");
    return built(origin, p, [&] { return rayleigh_scattering_spectrum(n, number, king); });
  }
  if (q.contains("cross_section")) {
    check_keys(q, {"cross_section", "number_density"}, origin, path);
    const double number = scalar(q, "number_density", "number_density", origin, path);
    if (!(number > 0.0)) fail(origin, path + ".number_density must be positive");
    const Spectrum sigma = parse_spectrum(q.at("cross_section"), "area", {550.0}, origin, path + ".cross_section");
    return built(origin, path, [&] { return cross_section_spectrum(sigma, number); });
  }
  check_keys(q, {"angstrom"}, origin, path);
  const json& a = q.at("angstrom");
  const std::string p = path + ".angstrom";
  check_keys(a, {"alpha", "beta", "scale_height"}, origin, p);
  const double alpha = finite_or_fail(require(a, "alpha", origin, p), origin, p + ".alpha");
  const double beta = finite_or_fail(require(a, "beta", origin, p), origin, p + ".beta");
  const double h = scalar(a, "scale_height", "length", origin, p);
  if (!(beta >= 0.0)) fail(origin, p + ".beta must be non-negative");
  if (!(alpha >= -1.0 && alpha <= 4.0)) fail(origin, p + ".alpha must be in [-1, 4]");
  if (!(h > 0.0)) fail(origin, p + ".scale_height must be positive");
  return built(origin, p, [&] { return angstrom_aerosol_spectrum(alpha, beta, h); });
}

Spectrum parse_spectrum(const json& q, const std::string& kind, const std::vector<double>& wavelengths,
                        const std::string& origin, const std::string& path) {
  if (q.is_object() && q.contains("table")) {
    // A measured spectrum at 1 au, scaled to the planet's distance (1 / d²).
    if (kind != "spectral_irradiance") fail(origin, path + ": a table is only valid for solar_irradiance");
    check_keys(q, {"table", "distance"}, origin, path);
    if (!q.at("table").is_string() || q.at("table").get<std::string>() != "astm_e490")
      fail(origin, path + ".table must be \"astm_e490\"");
    const double d = scalar(q, "distance", "distance", origin, path) / 1.495978707e11;
    if (!(d > 0.0)) fail(origin, path + ".distance must be positive");
    return built(origin, path, [&] { return solar_spectrum_table().scaled(1.0 / (d * d)); });
  }
  if (q.is_object() && (q.contains("rayleigh") || q.contains("cross_section") || q.contains("angstrom"))) {
    if (kind != "inverse_length") fail(origin, path + ": physical inputs are only valid for coefficients");
    return parse_physical_coefficient(q, origin, path);
  }
  if (q.is_object() && q.contains("blackbody")) {
    if (kind != "spectral_irradiance") fail(origin, path + ": a blackbody is only valid for solar_irradiance");
    check_keys(q, {"blackbody"}, origin, path);
    const json& b = q.at("blackbody");
    check_keys(b, {"temperature", "total_irradiance"}, origin, path + ".blackbody");
    const double t = scalar(b, "temperature", "temperature", origin, path + ".blackbody");
    const double total = scalar(b, "total_irradiance", "irradiance", origin, path + ".blackbody");
    if (t <= 0.0 || total <= 0.0) fail(origin, path + ".blackbody needs a positive temperature and total");
    return built(origin, path + ".blackbody", [&] { return blackbody_spectrum(t, total); });
  }
  check_keys(q, {"unit", "value", "values", "wavelengths_nm", "power_law"}, origin, path);
  const double factor = unit_factor(kind, unit_of(q, origin, path), origin, path);
  const int forms = int(q.contains("value")) + int(q.contains("values")) + int(q.contains("power_law"));
  if (forms != 1) fail(origin, path + " needs exactly one of \"value\", \"values\", \"power_law\"");
  if (q.contains("value")) {
    if (q.contains("wavelengths_nm")) fail(origin, path + ": \"wavelengths_nm\" goes with \"values\"");
    return Spectrum::constant(finite_or_fail(q.at("value"), origin, path + ".value") * factor);
  }
  if (q.contains("power_law")) {
    // value · (λ / reference)^exponent, e.g. exponent -4 for molecules.
    const json& p = q.at("power_law");
    check_keys(p, {"value", "reference_nm", "exponent"}, origin, path + ".power_law");
    const double value = finite_or_fail(require(p, "value", origin, path + ".power_law"), origin, path) * factor;
    const double ref = finite_or_fail(require(p, "reference_nm", origin, path + ".power_law"), origin, path);
    const double e = finite_or_fail(require(p, "exponent", origin, path + ".power_law"), origin, path);
    if (ref <= 0.0) fail(origin, path + ".power_law.reference_nm must be positive");
    return built(origin, path + ".power_law", [&] { return power_law_spectrum(value, ref, e); });
  }
  std::vector<double> values = number_list(q.at("values"), origin, path + ".values");
  std::vector<double> l = q.contains("wavelengths_nm")
                              ? number_list(q.at("wavelengths_nm"), origin, path + ".wavelengths_nm")
                              : wavelengths;
  if (l.size() != values.size())
    fail(origin, path + " has " + std::to_string(values.size()) + " values for " + std::to_string(l.size()) +
                     " wavelengths");
  // Sort by wavelength so that files may list red first, as RGB triples often are.
  std::vector<size_t> order(l.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return l[a] < l[b]; });
  std::vector<double> ls, vs;
  for (size_t i : order) {
    if (!ls.empty() && !(l[i] != ls.back())) fail(origin, path + ": wavelengths must be distinct");
    ls.push_back(l[i]);
    vs.push_back(values[i] * factor);
  }
  return built(origin, path, [&] { return Spectrum(ls, vs); });
}

DensityProfile parse_density(const json& q, const std::string& origin, const std::string& path) {
  if (!q.is_object() || !q.contains("profile")) fail(origin, path + " needs a \"profile\"");
  DensityProfile d;
  const std::string profile = q.at("profile").is_string() ? q.at("profile").get<std::string>() : "";
  if (profile == "exponential") {
    check_keys(q, {"profile", "scale_height"}, origin, path);
    d.kind = DensityProfile::Kind::exponential;
    d.scale_height_m = scalar(q, "scale_height", "length", origin, path);
  } else if (profile == "piecewise_linear") {
    check_keys(q, {"profile", "altitude_unit", "points"}, origin, path);
    d.kind = DensityProfile::Kind::piecewise_linear;
    const std::string unit = require(q, "altitude_unit", origin, path).is_string()
                                 ? q.at("altitude_unit").get<std::string>()
                                 : "";
    const double factor = unit_factor("length", unit, origin, path + ".altitude_unit");
    const json& points = require(q, "points", origin, path);
    if (!points.is_array() || points.size() < 2) fail(origin, path + ".points needs at least two [altitude, density] pairs");
    for (size_t i = 0; i < points.size(); ++i) {
      const std::string p = path + ".points[" + std::to_string(i) + "]";
      if (!points[i].is_array() || points[i].size() != 2) fail(origin, p + " must be [altitude, density]");
      d.knots.emplace_back(finite_or_fail(points[i][0], origin, p) * factor, finite_or_fail(points[i][1], origin, p));
    }
  } else {
    fail(origin, path + ".profile must be \"exponential\" or \"piecewise_linear\"");
  }
  return d;
}

// A phase function parameter: a number (the same at every wavelength) or a
// dimensionless spectrum in the form of the coefficients,
// {"wavelengths_nm": [...], "values": [...]} ("unit" optional, "1").
Spectrum parse_phase_parameter(const json& parent, const std::string& key, const std::vector<double>& wavelengths,
                               const std::string& origin, const std::string& path) {
  const std::string p = path + "." + key;
  const json& q = require(parent, key, origin, path);
  if (q.is_number()) return Spectrum::constant(finite_or_fail(q, origin, p));
  if (!q.is_object()) fail(origin, p + " must be a number or {\"wavelengths_nm\": [...], \"values\": [...]}");
  check_keys(q, {"unit", "value", "values", "wavelengths_nm"}, origin, p);
  json with_unit = q;
  if (!with_unit.contains("unit")) with_unit["unit"] = "1";
  return parse_spectrum(with_unit, "dimensionless", wavelengths, origin, p);
}

PhaseFunction parse_phase(const json& q, const std::vector<double>& wavelengths, const std::string& origin,
                          const std::string& path) {
  if (!q.is_object() || !q.contains("type") || !q.at("type").is_string())
    fail(origin, path + " needs a \"type\"");
  const std::string type = q.at("type").get<std::string>();
  PhaseFunction p;
  if (type == "rayleigh") {
    for (const auto& item : q.items())
      if (item.key() != "type")
        fail(origin, path + ": a rayleigh phase function takes no parameters (got " + quoted(item.key()) + ")");
    p.kind = PhaseFunction::Kind::rayleigh;
    return p;
  }
  if (type == "double_henyey_greenstein") {
    check_keys(q, {"type", "g", "g_back", "forward_weight"}, origin, path);
    p.kind = PhaseFunction::Kind::double_henyey_greenstein;
    p.g = parse_phase_parameter(q, "g", wavelengths, origin, path);
    p.g_back = parse_phase_parameter(q, "g_back", wavelengths, origin, path);
    p.forward_weight = parse_phase_parameter(q, "forward_weight", wavelengths, origin, path);
    return p;
  }
  if (type == "henyey_greenstein") p.kind = PhaseFunction::Kind::henyey_greenstein;
  else if (type == "cornette_shanks") p.kind = PhaseFunction::Kind::cornette_shanks;
  else fail(origin, path + ".type must be rayleigh, henyey_greenstein, cornette_shanks or double_henyey_greenstein");
  check_keys(q, {"type", "g"}, origin, path);
  p.g = parse_phase_parameter(q, "g", wavelengths, origin, path);
  return p;
}

}  // namespace

// Every data/planets/<name>.json compiled into the library.
std::vector<std::string> preset_names() {
  const std::string prefix = "data/planets/", suffix = ".json";
  std::vector<std::string> names;
  for (int i = 0; i < data::embedded_file_count; ++i) {
    const std::string path = data::embedded_files[i].path;
    if (path.rfind(prefix, 0) == 0 && path.size() > prefix.size() + suffix.size() &&
        path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0)
      names.push_back(path.substr(prefix.size(), path.size() - prefix.size() - suffix.size()));
  }
  std::sort(names.begin(), names.end());
  return names;
}

// The JSON of a planet file. A syntax error (json::parse_error) or a number
// beyond the range of a double (json::out_of_range) is reported on one line
// (nlohmann's message names the byte position).
json parse_json(const std::string& json_text, const std::string& origin) {
  try {
    return json::parse(json_text);
  } catch (const json::exception& e) {
    fail(origin, std::string("malformed JSON: ") + e.what());
  }
}

// A source path relative to the planet file's directory (a preset's sources
// are absolute); GDAL dataset descriptions (XML, /vsi paths) as they are.
std::string resolve_source(const std::string& source, const std::string& origin) {
  if (source.empty() || source.front() == '<' || source.rfind("/vsi", 0) == 0) return source;
  const std::filesystem::path path(source);
  if (path.is_absolute() || origin.find('/') == std::string::npos) return source;
  return (std::filesystem::path(origin).parent_path() / path).string();
}

// {"source": …, "crs": …, "unit": "m" | "km" | "ft" (elevation only),
//  "bounds_deg": [west, south, east, north]}
SurfaceRaster surface_raster(const json& r, bool elevation, const std::string& origin, const std::string& path) {
  if (elevation) check_keys(r, {"source", "crs", "unit", "bounds_deg"}, origin, path);
  else check_keys(r, {"source", "crs", "bounds_deg"}, origin, path);
  SurfaceRaster raster;
  const json& source = require(r, "source", origin, path);
  if (!source.is_string() || source.get<std::string>().empty()) fail(origin, path + ".source must be a non-empty string");
  raster.source = resolve_source(source.get<std::string>(), origin);
  if (r.contains("crs")) {
    if (!r.at("crs").is_string() || r.at("crs").get<std::string>().empty())
      fail(origin, path + ".crs must be a non-empty string");
    raster.crs = r.at("crs").get<std::string>();
  }
  if (r.contains("unit")) {
    if (!r.at("unit").is_string()) fail(origin, path + ".unit must be a string");
    raster.metres_per_unit = unit_factor("height", r.at("unit").get<std::string>(), origin, path + ".unit");
  }
  if (r.contains("bounds_deg")) {
    const std::vector<double> b = number_list(r.at("bounds_deg"), origin, path + ".bounds_deg");
    if (b.size() != 4) fail(origin, path + ".bounds_deg must be [west, south, east, north] in degrees");
    if (!(b[0] < b[2] && b[2] - b[0] <= 360.0 && b[1] < b[3] && b[1] >= -90.0 && b[3] <= 90.0))
      fail(origin, path + ".bounds_deg must have west < east (at most 360 degrees apart) and -90 <= south < north <= 90");
    raster.bounds_deg = std::array<double, 4>{b[0], b[1], b[2], b[3]};
  }
  return raster;
}

// The "surface" object of a parsed planet file (the flat style without one).
PlanetSurface surface_of(const json& doc, const std::string& origin) {
  PlanetSurface surface;
  if (!doc.is_object() || !doc.contains("surface")) return surface;
  const json& s = doc.at("surface");
  check_keys(s, {"relief", "sea_level", "elevation", "imagery", "coastline", "lakes"}, origin, "surface");
  if (s.contains("elevation")) surface.elevation = surface_raster(s.at("elevation"), true, origin, "surface.elevation");
  if (s.contains("imagery")) surface.imagery = surface_raster(s.at("imagery"), false, origin, "surface.imagery");
  if (s.contains("coastline")) {
    const json& c = s.at("coastline");
    check_keys(c, {"source"}, origin, "surface.coastline");
    const json& source = require(c, "source", origin, "surface.coastline");
    if (!source.is_string() || source.get<std::string>().empty())
      fail(origin, "surface.coastline.source must be a non-empty string");
    surface.coastline = resolve_source(source.get<std::string>(), origin);
  }
  if (s.contains("relief")) {
    const json& relief = s.at("relief");
    check_keys(relief, {"style", "seed"}, origin, "surface.relief");
    const json& style = require(relief, "style", origin, "surface.relief");
    if (!style.is_string()) fail(origin, "surface.relief.style must be a string");
    try {
      surface.style = surface_style_from_name(style.get<std::string>());
    } catch (const Error& e) {
      fail(origin, std::string("surface.relief.style: ") + e.what());
    }
    if (relief.contains("seed")) {
      const json& seed = relief.at("seed");
      if (!seed.is_number_unsigned()) fail(origin, "surface.relief.seed must be a non-negative integer");
      surface.seed = seed.get<std::uint64_t>();
    }
  }
  if (s.contains("sea_level")) surface.sea_level_m = scalar(s, "sea_level", "length", origin, "surface");
  if (s.contains("lakes")) {
    const json& lakes = s.at("lakes");
    check_keys(lakes, {"mask", "level"}, origin, "surface.lakes");
    // A mask has no unit: surface_raster without elevation refuses "unit".
    surface.lake_mask = surface_raster(require(lakes, "mask", origin, "surface.lakes"), false, origin, "surface.lakes.mask");
    surface.lake_level_m = scalar(lakes, "level", "length", origin, "surface.lakes");
    // The sea covers all ground below its level (the style's: Earth's is 0,
    // the other styles have none), so lakes at or below it would lie under it.
    const std::optional<double> sea =
        surface.sea_level_m ? surface.sea_level_m
                            : (surface.style == SurfaceStyle::earth ? std::optional<double>(0.0) : std::nullopt);
    if (sea && !(*surface.lake_level_m > *sea))
      fail(origin, "surface.lakes.level (" + std::to_string(*surface.lake_level_m) +
                       " m) is not above the sea level (" + std::to_string(*sea) +
                       " m): the sea covers all ground below it");
  }
  if (!surface.coastline.empty() && surface.style != SurfaceStyle::earth)
    fail(origin, "surface.coastline draws the earth style's land and sea: it needs surface.relief.style \"earth\"");
  if (!surface.coastline.empty() && surface.sea_level_m && *surface.sea_level_m != 0.0)
    fail(origin, "surface.coastline is the coast at sea level 0: it contradicts surface.sea_level");
  return surface;
}

Atmosphere parse_atmosphere(const std::string& json_text, const std::string& origin) {
  const json doc = parse_json(json_text, origin);
  check_keys(doc, {"format", "name", "description", "sources", "wavelengths", "bottom_radius", "top_radius",
                   "sun_angular_radius", "solar_irradiance", "ground_albedo", "constituents", "surface"},
             origin, "the planet file");
  const json& format = require(doc, "format", origin, "the planet file");
  if (!format.is_string() || format.get<std::string>() != "atmos-planet-1")
    fail(origin, "\"format\" must be \"atmos-planet-1\"");

  Atmosphere a;
  a.origin = origin;
  a.name = name_or(doc, origin, origin, "name");
  const json& w = require(doc, "wavelengths", origin, "the planet file");
  check_keys(w, {"unit", "values"}, origin, "wavelengths");
  if (unit_of(w, origin, "wavelengths") != "nm") fail(origin, "wavelengths must be given in nm");
  a.wavelengths_nm = number_list(require(w, "values", origin, "wavelengths"), origin, "wavelengths.values");

  check_parameter("wavelengths", double(a.wavelengths_nm.size()), origin, "the number of wavelengths");
  a.bottom_radius_m = scalar(doc, "bottom_radius", "length", origin, "planet");
  check_parameter("bottom_radius", a.bottom_radius_m, origin, "bottom_radius");
  a.top_radius_m = scalar(doc, "top_radius", "length", origin, "planet");
  a.sun_angular_radius_rad = scalar(doc, "sun_angular_radius", "angle", origin, "planet");
  check_parameter("sun_angular_radius", a.sun_angular_radius_rad, origin, "sun_angular_radius");
  a.solar_irradiance = parse_spectrum(require(doc, "solar_irradiance", origin, "planet"), "spectral_irradiance",
                                      a.wavelengths_nm, origin, "solar_irradiance");
  a.ground_albedo = parse_spectrum(require(doc, "ground_albedo", origin, "planet"), "dimensionless",
                                   a.wavelengths_nm, origin, "ground_albedo");
  const json& cs = require(doc, "constituents", origin, "planet");
  if (!cs.is_array() || cs.empty()) fail(origin, "constituents must be a non-empty list");
  for (size_t i = 0; i < cs.size(); ++i) {
    const std::string path = "constituents[" + std::to_string(i) + "]";
    const json& c = cs[i];
    check_keys(c, {"name", "density", "scattering", "absorption", "phase_function", "sources"}, origin, path);
    Constituent k;
    k.name = name_or(c, path, origin, path + ".name");
    k.density = parse_density(require(c, "density", origin, path), origin, path + ".density");
    k.scattering = parse_spectrum(require(c, "scattering", origin, path), "inverse_length", a.wavelengths_nm, origin,
                                  path + ".scattering");
    k.absorption = parse_spectrum(require(c, "absorption", origin, path), "inverse_length", a.wavelengths_nm, origin,
                                  path + ".absorption");
    k.phase = parse_phase(require(c, "phase_function", origin, path), a.wavelengths_nm, origin,
                          path + ".phase_function");
    if (k.density.kind == DensityProfile::Kind::exponential)
      check_parameter("constituents[].density.scale_height", k.density.scale_height_m, origin,
                      path + ".density.scale_height");
    a.constituents.push_back(std::move(k));
  }
  a.validate();
  surface_of(doc, origin);  // a planet file's surface is checked wherever the file is read
  return a;
}

namespace {

// The text of a preset or of a planet file.
std::string planet_text(const std::string& name_or_path) {
  if (const char* text = data::embedded_planet(name_or_path)) return text;
  std::ifstream in(name_or_path, std::ios::binary);
  if (!in) {
    std::string names;
    for (const auto& n : preset_names()) names += (names.empty() ? "" : ", ") + n;
    throw Error("planet \"" + name_or_path + "\" is neither a preset (" + names + ") nor a readable file");
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

Atmosphere load_atmosphere(const std::string& name_or_path) {
  return parse_atmosphere(planet_text(name_or_path), name_or_path);
}

SurfaceStyle surface_style_from_name(const std::string& name) {
  if (name == "earth") return SurfaceStyle::earth;
  if (name == "mars") return SurfaceStyle::mars;
  if (name == "venus") return SurfaceStyle::venus;
  if (name == "titan") return SurfaceStyle::titan;
  if (name == "flat") return SurfaceStyle::flat;
  throw Error("surface style \"" + name + "\" is not one of earth, mars, venus, titan, flat");
}

PlanetSurface parse_surface(const std::string& json_text, const std::string& origin) {
  const json doc = parse_json(json_text, origin);
  return surface_of(doc, origin);
}

PlanetSurface load_surface(const std::string& name_or_path) {
  return parse_surface(planet_text(name_or_path), name_or_path);
}

}  // namespace atmos
