// Planet files: JSON with the unit of every quantity stated next to it.
// The format is documented in docs/planet-format.md.
#include "atmos/atmosphere.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "io/embedded_files.hpp"

namespace atmos {
namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& origin, const std::string& what) {
  throw Error(origin + ": " + what);
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
    if (!allowed.count(item.key())) fail(origin, "unknown key \"" + item.key() + "\" in " + path);
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
    fail(origin, path + " has unit \"" + unit + "\"; expected one of: " + accepted);
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

// Planck's law scaled so that its integral over all wavelengths is `total`
// (W m^-2): E(λ) = total · π B(λ, T) / (σ T⁴), in W m^-2 nm^-1.
double blackbody_irradiance(double wavelength_nm, double temperature, double total) {
  constexpr double h = 6.62607015e-34, c = 299792458.0, k = 1.380649e-23, sigma = 5.670374419e-8;
  const double l = wavelength_nm * 1e-9;
  const double radiance = 2.0 * h * c * c / std::pow(l, 5) / std::expm1(h * c / (l * k * temperature));
  return total * M_PI * radiance / (sigma * std::pow(temperature, 4)) * 1e-9;
}

Spectrum parse_spectrum(const json& q, const std::string& kind, const std::vector<double>& wavelengths,
                        const std::string& origin, const std::string& path);

// A coefficient (m^-1 at the reference density) from physical inputs, sampled
// every 1 nm over 200-2000 nm:
//  - {"rayleigh": {"refractive_index": n, "number_density": N, "king_factor": F}}:
//    molecular scattering, β(λ) = 8π³ (n² - 1)² F / (3 N λ⁴) (seed 004 eq. 1-2;
//    n at the reference density, taken as non-dispersive; F = 1 if omitted);
//  - {"cross_section": σ (area, a value or a spectrum), "number_density": N}:
//    β(λ) = N σ(λ), e.g. an absorber from measured cross sections;
//  - {"angstrom": {"alpha": α, "beta": β_A, "scale_height": H}}: an aerosol of
//    optical depth τ(λ) = β_A (λ / 1 µm)^-α (Ångström's law) spread over an
//    exponential layer of scale height H: β(λ) = τ(λ) / H at the ground.
Spectrum parse_physical_coefficient(const json& q, const std::string& origin, const std::string& path) {
  std::vector<double> l, v;
  auto sample = [&](auto&& f) {
    for (double w = 200.0; w <= 2000.0; w += 1.0) {
      l.push_back(w);
      v.push_back(f(w));
    }
    return Spectrum(l, v);
  };
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
    const double n2 = (n * n - 1.0) * (n * n - 1.0);
    return sample([&](double w) {
      const double lambda = w * 1e-9;
      return 8.0 * M_PI * M_PI * M_PI * n2 * king / (3.0 * number * lambda * lambda * lambda * lambda);
    });
  }
  if (q.contains("cross_section")) {
    check_keys(q, {"cross_section", "number_density"}, origin, path);
    const double number = scalar(q, "number_density", "number_density", origin, path);
    if (!(number > 0.0)) fail(origin, path + ".number_density must be positive");
    const Spectrum sigma = parse_spectrum(q.at("cross_section"), "area", {550.0}, origin, path + ".cross_section");
    return sample([&](double w) { return number * sigma.at(w); });
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
  return sample([&](double w) { return beta * std::pow(w / 1000.0, -alpha) / h; });
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
    return solar_spectrum_table().scaled(1.0 / (d * d));
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
    return blackbody_spectrum(t, total);
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
    std::vector<double> l, v;
    for (double w = 200.0; w <= 2000.0; w += 1.0) {
      l.push_back(w);
      v.push_back(value * std::pow(w / ref, e));
    }
    return Spectrum(l, v);
  }
  std::vector<double> values = number_list(q.at("values"), origin, path + ".values");
  std::vector<double> l = q.contains("wavelengths_nm")
                              ? number_list(q.at("wavelengths_nm"), origin, path + ".wavelengths_nm")
                              : wavelengths;
  if (l.size() != values.size())
    fail(origin, path + " has " + std::to_string(values.size()) + " values for " + std::to_string(l.size()) +
                     " wavelengths");
  for (size_t i = 1; i < l.size(); ++i)
    if (!(l[i] != l[i - 1])) fail(origin, path + ": wavelengths must be distinct");
  // Sort by wavelength so that files may list red first, as RGB triples often are.
  std::vector<size_t> order(l.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return l[a] < l[b]; });
  std::vector<double> ls, vs;
  for (size_t i : order) {
    ls.push_back(l[i]);
    vs.push_back(values[i] * factor);
  }
  return Spectrum(ls, vs);
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
        fail(origin, path + ": a rayleigh phase function takes no parameters (got \"" + item.key() + "\")");
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

Spectrum::Spectrum(std::vector<double> wavelengths_nm, std::vector<double> values)
    : wavelengths_nm_(std::move(wavelengths_nm)), values_(std::move(values)) {
  if (wavelengths_nm_.size() != values_.size() || values_.empty())
    throw Error("spectrum needs as many values as wavelengths");
  for (size_t i = 0; i < values_.size(); ++i) {
    if (!std::isfinite(wavelengths_nm_[i]) || !std::isfinite(values_[i]))
      throw Error("spectrum samples must be finite");
    if (i > 0 && !(wavelengths_nm_[i] > wavelengths_nm_[i - 1]))
      throw Error("spectrum wavelengths must increase");
  }
}

Spectrum Spectrum::constant(double value) { return Spectrum({550.0}, {value}); }

double Spectrum::at(double wavelength_nm) const {
  if (values_.empty()) return 0.0;
  if (wavelength_nm <= wavelengths_nm_.front()) return values_.front();
  if (wavelength_nm >= wavelengths_nm_.back()) return values_.back();
  const auto it = std::upper_bound(wavelengths_nm_.begin(), wavelengths_nm_.end(), wavelength_nm);
  const size_t i = size_t(it - wavelengths_nm_.begin());
  const double t = (wavelength_nm - wavelengths_nm_[i - 1]) / (wavelengths_nm_[i] - wavelengths_nm_[i - 1]);
  return values_[i - 1] + t * (values_[i] - values_[i - 1]);
}

double DensityProfile::at(double altitude_m) const {
  if (kind == Kind::exponential) return std::exp(-altitude_m / scale_height_m);
  if (altitude_m <= knots.front().first || altitude_m >= knots.back().first) {
    if (altitude_m == knots.front().first) return knots.front().second;
    if (altitude_m == knots.back().first) return knots.back().second;
    return 0.0;
  }
  for (size_t i = 1; i < knots.size(); ++i) {
    if (altitude_m <= knots[i].first) {
      const double t = (altitude_m - knots[i - 1].first) / (knots[i].first - knots[i - 1].first);
      return knots[i - 1].second + t * (knots[i].second - knots[i - 1].second);
    }
  }
  return 0.0;
}

PhaseFunction::PhaseFunction(Kind kind_, double g_) : kind(kind_) {
  if (kind != Kind::rayleigh) g = Spectrum::constant(g_);
}

PhaseFunction::PhaseFunction(Kind kind_, Spectrum g_, Spectrum g_back_, Spectrum forward_weight_)
    : kind(kind_), g(std::move(g_)), g_back(std::move(g_back_)), forward_weight(std::move(forward_weight_)) {}

PhaseFunction Atmosphere::aerosol_phase() const {
  for (const auto& c : constituents) {
    if (c.phase.kind == PhaseFunction::Kind::rayleigh) continue;
    for (double v : c.scattering.values())
      if (v > 0.0) return c.phase;
  }
  return PhaseFunction{PhaseFunction::Kind::henyey_greenstein, 0.0};
}

void Atmosphere::validate() const {
  auto bad = [&](const std::string& what) { throw Error(origin + ": " + what); };
  if (wavelengths_nm.empty()) bad("no working wavelengths");
  if (wavelengths_nm.size() < 3 || wavelengths_nm.size() > 48) bad("the number of working wavelengths must be in [3, 48]");
  for (double w : wavelengths_nm)
    if (!std::isfinite(w) || w < 200.0 || w > 2000.0) bad("wavelength " + std::to_string(w) + " nm is outside 200-2000 nm");
  if (!std::isfinite(bottom_radius_m) || bottom_radius_m <= 0.0) bad("bottom_radius must be positive");
  if (!std::isfinite(top_radius_m) || top_radius_m <= bottom_radius_m)
    bad("top_radius must be larger than bottom_radius");
  if (top_radius_m > 1.5 * bottom_radius_m) bad("top_radius must be at most 1.5 x bottom_radius");
  if (constituents.empty()) bad("no constituents");
  if (constituents.size() > 4) bad("at most 4 constituents are supported");
  if (!std::isfinite(sun_angular_radius_rad) || sun_angular_radius_rad <= 0.0 || sun_angular_radius_rad > 0.2)
    bad("sun_angular_radius must be in (0, 0.2] rad");
  // A spectrum's samples may lie at any finite wavelength, beyond the range of an int.
  auto nm = [](double wavelength) {
    std::ostringstream o;
    o << wavelength;
    return o.str();
  };
  auto check_spectrum = [&](const Spectrum& s, const std::string& what, double max) {
    if (s.empty()) bad(what + " is missing");
    for (size_t i = 0; i < s.values().size(); ++i) {
      const double v = s.values()[i];
      if (!std::isfinite(v) || v < 0.0 || v > max)
        bad(what + " at " + nm(s.wavelengths_nm()[i]) + " nm is " + std::to_string(v) +
            ", outside [0, " + std::to_string(max) + "]");
    }
    for (double w : wavelengths_nm) {
      const double v = s.at(w);
      if (!std::isfinite(v) || v < 0.0 || v > max)
        bad(what + " at " + nm(w) + " nm is " + std::to_string(v) + ", outside [0, " +
            std::to_string(max) + "]");
    }
  };
  check_spectrum(ground_albedo, "ground_albedo", 1.0);
  check_spectrum(solar_irradiance, "solar_irradiance", 1e4);
  bool aerosol_seen = false;
  PhaseFunction aerosol;
  for (const auto& c : constituents) {
    const std::string n = "constituent \"" + c.name + "\"";
    check_spectrum(c.scattering, n + " scattering", 1.0);
    check_spectrum(c.absorption, n + " absorption", 1.0);
    if (c.density.kind == DensityProfile::Kind::exponential) {
      if (!std::isfinite(c.density.scale_height_m) || c.density.scale_height_m <= 0.0)
        bad(n + " scale_height must be positive");
    } else {
      if (c.density.knots.size() < 2 || c.density.knots.size() > 8) bad(n + " needs 2 to 8 density points");
      for (size_t i = 0; i < c.density.knots.size(); ++i) {
        if (!std::isfinite(c.density.knots[i].first) || !std::isfinite(c.density.knots[i].second) ||
            c.density.knots[i].second < 0.0)
          bad(n + " density points must be finite and not negative");
        if (i > 0 && !(c.density.knots[i].first > c.density.knots[i - 1].first))
          bad(n + " density altitudes must increase");
      }
    }
    if (c.phase.kind == PhaseFunction::Kind::rayleigh) {
      if (!c.phase.g.empty() || !c.phase.g_back.empty() || !c.phase.forward_weight.empty())
        bad(n + " phase_function: a rayleigh phase function takes no parameters");
    } else {
      // Every sample (the interpolation between them stays inside the bounds).
      auto check_parameter = [&](const Spectrum& s, const std::string& field, double lo, double hi, bool open) {
        if (s.empty()) bad(n + " phase_function." + field + " is missing");
        for (size_t i = 0; i < s.values().size(); ++i) {
          const double v = s.values()[i];
          if (!(open ? (v > lo && v < hi) : (v >= lo && v <= hi))) {
            auto num = [](double x) {
              std::ostringstream o;
              o << x;
              return o.str();
            };
            const std::string where = s.values().size() == 1 ? "" : " at " + num(s.wavelengths_nm()[i]) + " nm";
            bad(n + " phase_function." + field + where + " must be in " + (open ? "(" : "[") + num(lo) + ", " +
                num(hi) + (open ? ")" : "]") + ", got " + num(v));
          }
        }
      };
      check_parameter(c.phase.g, "g", -0.999, 0.999, true);
      if (c.phase.kind == PhaseFunction::Kind::double_henyey_greenstein) {
        check_parameter(c.phase.g_back, "g_back", -0.999, 0.999, true);
        check_parameter(c.phase.forward_weight, "forward_weight", 0.0, 1.0, false);
      } else if (!c.phase.g_back.empty() || !c.phase.forward_weight.empty()) {
        bad(n + " phase_function: g_back and forward_weight are only for double_henyey_greenstein");
      }
      if (aerosol_seen && !(c.phase == aerosol))
        bad(n + " has a different aerosol phase function than an earlier constituent; all non-Rayleigh "
                "constituents of a planet must share one phase function");
      aerosol_seen = true;
      aerosol = c.phase;
    }
  }
}

// Every data/planets/<name>.json compiled into the library.
std::vector<std::string> preset_names() {
  const std::string prefix = "data/planets/", suffix = ".json";
  std::vector<std::string> names;
  for (int i = 0; i < io::embedded_file_count; ++i) {
    const std::string path = io::embedded_files[i].path;
    if (path.rfind(prefix, 0) == 0 && path.size() > prefix.size() + suffix.size() &&
        path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0)
      names.push_back(path.substr(prefix.size(), path.size() - prefix.size() - suffix.size()));
  }
  std::sort(names.begin(), names.end());
  return names;
}

Atmosphere parse_atmosphere(const std::string& json_text, const std::string& origin) {
  json doc;
  try {
    doc = json::parse(json_text);
  } catch (const json::parse_error& e) {
    // nlohmann's message names the byte position; keep it on one line.
    fail(origin, std::string("malformed JSON: ") + e.what());
  }
  check_keys(doc, {"format", "name", "description", "sources", "wavelengths", "bottom_radius", "top_radius",
                   "sun_angular_radius", "solar_irradiance", "ground_albedo", "constituents"},
             origin, "the planet file");
  const json& format = require(doc, "format", origin, "the planet file");
  if (!format.is_string() || format.get<std::string>() != "atmos-planet-1")
    fail(origin, "\"format\" must be \"atmos-planet-1\"");

  Atmosphere a;
  a.origin = origin;
  a.name = doc.contains("name") && doc.at("name").is_string() ? doc.at("name").get<std::string>() : origin;
  const json& w = require(doc, "wavelengths", origin, "the planet file");
  check_keys(w, {"unit", "values"}, origin, "wavelengths");
  if (unit_of(w, origin, "wavelengths") != "nm") fail(origin, "wavelengths must be given in nm");
  a.wavelengths_nm = number_list(require(w, "values", origin, "wavelengths"), origin, "wavelengths.values");

  a.bottom_radius_m = scalar(doc, "bottom_radius", "length", origin, "planet");
  a.top_radius_m = scalar(doc, "top_radius", "length", origin, "planet");
  a.sun_angular_radius_rad = scalar(doc, "sun_angular_radius", "angle", origin, "planet");
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
    k.name = c.contains("name") && c.at("name").is_string() ? c.at("name").get<std::string>() : path;
    k.density = parse_density(require(c, "density", origin, path), origin, path + ".density");
    k.scattering = parse_spectrum(require(c, "scattering", origin, path), "inverse_length", a.wavelengths_nm, origin,
                                  path + ".scattering");
    k.absorption = parse_spectrum(require(c, "absorption", origin, path), "inverse_length", a.wavelengths_nm, origin,
                                  path + ".absorption");
    k.phase = parse_phase(require(c, "phase_function", origin, path), a.wavelengths_nm, origin,
                          path + ".phase_function");
    a.constituents.push_back(std::move(k));
  }
  a.validate();
  return a;
}

Spectrum Spectrum::scaled(double factor) const {
  std::vector<double> v = values_;
  for (double& x : v) x *= factor;
  return Spectrum(wavelengths_nm_, v);
}

double Spectrum::integral(double from_nm, double to_nm) const {
  // Trapezoids on the samples inside, plus the pieces up to the bounds.
  std::vector<double> points = {from_nm};
  for (double l : wavelengths_nm_)
    if (l > from_nm && l < to_nm) points.push_back(l);
  points.push_back(to_nm);
  double sum = 0.0;
  for (size_t i = 1; i < points.size(); ++i) sum += 0.5 * (at(points[i - 1]) + at(points[i])) * (points[i] - points[i - 1]);
  return sum;
}

std::vector<double> spectral_wavelengths(int count) {
  if (count < 3 || count > 48) throw Error("the number of wavelengths must be in [3, 48], got " + std::to_string(count));
  if (count == 3) return {680.0, 550.0, 440.0};
  std::vector<double> out;
  for (int i = 0; i < count; ++i) out.push_back(360.0 + (830.0 - 360.0) * double(i) / double(count - 1));
  return out;
}

void scale_density(Atmosphere& atmosphere, double factor) {
  if (!std::isfinite(factor) || factor <= 0.0 || factor > 1e4)
    throw Error("the density scale must be in (0, 10000], got " + std::to_string(factor));
  for (Constituent& c : atmosphere.constituents) {
    c.scattering = c.scattering.scaled(factor);
    c.absorption = c.absorption.scaled(factor);
  }
}

Spectrum solar_spectrum_table() {
  static const Spectrum table = [] {
    const char* text = io::embedded_file("data/spectra/solar_irradiance.csv");
    if (text == nullptr) throw Error("the solar spectrum is not embedded in this build");
    std::istringstream in(text);
    std::string line;
    std::vector<double> l, v;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#' || line[0] == 'w') continue;
      double a, b;
      if (std::sscanf(line.c_str(), "%lf,%lf", &a, &b) != 2) throw Error("malformed solar spectrum line: " + line);
      l.push_back(a);
      v.push_back(b);
    }
    // The table resolves Fraunhofer lines (the Ca II K line halves the
    // irradiance at 393.4 nm): point samples at a few working wavelengths
    // would pick lines at random. The spectrum the precomputation samples is
    // the 10 nm running mean (the resolution of the bins of measured
    // cross sections, e.g. data/spectra/ozone_cross_section.csv), every 5 nm.
    const Spectrum raw(l, v);
    std::vector<double> ls, vs;
    for (double w = 290.0; w <= 2490.0; w += 5.0) {
      ls.push_back(w);
      vs.push_back(raw.integral(w - 5.0, w + 5.0) / 10.0);
    }
    return Spectrum(ls, vs);
  }();
  return table;
}

Spectrum blackbody_spectrum(double temperature_k, double total_irradiance_w_m2) {
  if (!(temperature_k > 0.0 && temperature_k < 1e6) || !(total_irradiance_w_m2 > 0.0))
    throw Error("a blackbody needs a positive temperature and total irradiance");
  std::vector<double> l, v;
  // Sampled over the whole range validate() accepts for working wavelengths.
  for (double w = 200.0; w <= 2000.0; w += 2.0) {
    l.push_back(w);
    v.push_back(blackbody_irradiance(w, temperature_k, total_irradiance_w_m2));
  }
  return Spectrum(l, v);
}

void set_solar_spectrum(Atmosphere& atmosphere, const std::string& spec) {
  Spectrum shape;
  if (spec == "table") {
    shape = solar_spectrum_table();
  } else if (spec.rfind("blackbody:", 0) == 0) {
    char* end = nullptr;
    const double t = std::strtod(spec.c_str() + 10, &end);
    if (end == spec.c_str() + 10 || *end != '\0' || !(t >= 1000.0 && t <= 100000.0))
      throw Error("--solar blackbody:T needs a temperature T in [1000, 100000] K, got \"" + spec + "\"");
    shape = blackbody_spectrum(t, 1.0);
  } else {
    throw Error("the solar spectrum must be \"table\" or \"blackbody:T\", got \"" + spec + "\"");
  }
  const double visible = atmosphere.solar_irradiance.integral(360.0, 830.0);
  atmosphere.solar_irradiance = shape.scaled(visible / shape.integral(360.0, 830.0));
}

Atmosphere load_atmosphere(const std::string& name_or_path) {
  if (const char* text = io::embedded_planet(name_or_path)) return parse_atmosphere(text, name_or_path);
  std::ifstream in(name_or_path, std::ios::binary);
  if (!in) {
    std::string names;
    for (const auto& n : preset_names()) names += (names.empty() ? "" : ", ") + n;
    throw Error("planet \"" + name_or_path + "\" is neither a preset (" + names + ") nor a readable file");
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_atmosphere(ss.str(), name_or_path);
}

}  // namespace atmos
