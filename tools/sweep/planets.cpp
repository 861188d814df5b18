// Random valid planets: the presets varied as the CLI varies them
// (--wavelengths, --density-scale, --solar), and random atmospheres over
// the ranges Atmosphere::validate() accepts, some of them written as planet
// JSON and read back through parse_atmosphere.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/planet_file.hpp"
#include "random.hpp"
#include "sweep.hpp"

namespace atmos::sweep {

namespace {

constexpr std::uint64_t kPlanetStream = 1;

// ∫ density dh over the atmosphere [0, thickness]: the column (m) that turns
// a vertical optical depth into a coefficient at the reference density.
double column_length(const DensityProfile& d, double thickness) {
  if (d.kind == DensityProfile::Kind::exponential)
    return d.scale_height_m * (1.0 - std::exp(-thickness / d.scale_height_m));
  // Trapezoids between the knots and the atmosphere's bounds (density
  // linear between knots, zero outside them).
  std::vector<double> h = {0.0, thickness};
  for (const auto& k : d.knots)
    if (k.first > 0.0 && k.first < thickness) h.push_back(k.first);
  std::sort(h.begin(), h.end());
  double sum = 0.0;
  for (size_t i = 1; i < h.size(); ++i) sum += 0.5 * (d.at(h[i - 1]) + d.at(h[i])) * (h[i] - h[i - 1]);
  return sum;
}

DensityProfile random_density(Random& r, double thickness) {
  DensityProfile d;
  if (r.chance(0.7)) {
    d.kind = DensityProfile::Kind::exponential;
    d.scale_height_m = thickness * r.log_uniform(0.01, 2.0);
    return d;
  }
  d.kind = DensityProfile::Kind::piecewise_linear;
  const int n = r.integer(2, 8);
  std::vector<double> altitudes;
  for (int i = 0; i < n; ++i) altitudes.push_back(thickness * r.uniform(-0.2, 1.2));
  std::sort(altitudes.begin(), altitudes.end());
  // Strictly increasing: each at least 1e-3 of the thickness above the last.
  for (size_t i = 1; i < altitudes.size(); ++i)
    altitudes[i] = std::max(altitudes[i], altitudes[i - 1] + 1e-3 * thickness);
  for (double a : altitudes) d.knots.emplace_back(a, r.chance(0.2) ? 0.0 : r.uniform(0.0, 1.0));
  // A layer with some density inside the atmosphere (the column must not be
  // zero for the optical depth to fix the coefficient).
  if (column_length(d, thickness) <= 1e-6 * thickness) d.knots[size_t(n / 2)] = {thickness * 0.5, 1.0};
  if (column_length(d, thickness) <= 1e-6 * thickness) {
    d.knots = {{0.0, 1.0}, {thickness, 1.0}};
  }
  return d;
}

// A coefficient spectrum (m^-1) whose value at 550 nm is `at_550`: constant,
// a power law, or random samples; every value in [0, 1] (validate's range).
Spectrum random_coefficient(Random& r, double at_550, double power_law_exponent) {
  const double v = std::min(at_550, 1.0);
  const double kind = r.uniform();
  if (kind < 0.2) return Spectrum::constant(v);
  if (kind < 0.7) {
    std::vector<double> l, values;
    for (double w = 200.0; w <= 2000.0; w += 20.0) {
      l.push_back(w);
      values.push_back(std::min(v * std::pow(w / 550.0, power_law_exponent), 1.0));
    }
    return Spectrum(l, values);
  }
  const int n = r.integer(2, 10);
  std::vector<double> l;
  for (int i = 0; i < n; ++i) l.push_back(r.uniform(300.0, 900.0));
  std::sort(l.begin(), l.end());
  l.erase(std::unique(l.begin(), l.end()), l.end());
  std::vector<double> values;
  for (size_t i = 0; i < l.size(); ++i) values.push_back(std::min(v * r.log_uniform(0.3, 3.0), 1.0));
  return Spectrum(l, values);
}

Spectrum random_fraction_spectrum(Random& r, double lo, double hi) {
  if (r.chance(0.7)) return Spectrum::constant(r.uniform(lo, hi));
  return Spectrum({r.uniform(350.0, 500.0), r.uniform(600.0, 800.0)}, {r.uniform(lo, hi), r.uniform(lo, hi)});
}

// An asymmetry parameter in (-0.999, 0.999): mostly moderate, sometimes at
// the edges of the range.
double random_g(Random& r, double lo, double hi) {
  if (r.chance(0.05)) return r.chance(0.5) ? 0.998 : -0.998;
  return r.uniform(lo, hi);
}

PhaseFunction random_aerosol_phase(Random& r) {
  const double kind = r.uniform();
  const bool spectral = r.chance(0.25);
  auto g_spectrum = [&](double lo, double hi) {
    if (!spectral) return Spectrum::constant(random_g(r, lo, hi));
    return Spectrum({400.0, 700.0}, {random_g(r, lo, hi), random_g(r, lo, hi)});
  };
  if (kind < 0.35) return PhaseFunction(PhaseFunction::Kind::henyey_greenstein, g_spectrum(-0.9, 0.97));
  if (kind < 0.7) return PhaseFunction(PhaseFunction::Kind::cornette_shanks, g_spectrum(-0.9, 0.97));
  return PhaseFunction(PhaseFunction::Kind::double_henyey_greenstein, g_spectrum(0.3, 0.97),
                       g_spectrum(-0.9, 0.2), random_fraction_spectrum(r, 0.0, 1.0));
}

std::vector<double> random_wavelengths(Random& r) {
  const double kind = r.uniform();
  if (kind < 0.55) return spectral_wavelengths(3);
  if (kind < 0.65) return {r.uniform(600.0, 830.0), r.uniform(480.0, 600.0), r.uniform(360.0, 480.0)};
  if (kind < 0.7) {
    // Any three distinct wavelengths validate() accepts, also outside the
    // CIE observer's 360-830 nm.
    std::vector<double> w;
    while (w.size() < 3) {
      const double x = r.uniform(200.0, 2000.0);
      if (std::none_of(w.begin(), w.end(), [&](double y) { return std::abs(x - y) < 1.0; })) w.push_back(x);
    }
    return w;
  }
  return spectral_wavelengths(r.chance(0.85) ? r.integer(4, 12) : r.integer(13, 48));
}

Spectrum random_solar(Random& r, std::string& recipe) {
  const double kind = r.uniform();
  if (kind < 0.4) {
    const double scale = r.log_uniform(0.01, 4.0);
    recipe += " solar=table x" + number_text(scale, 6);
    return solar_spectrum_table().scaled(scale);
  }
  if (kind < 0.8) {
    const double t = r.log_uniform(2000.0, 50000.0), total = r.log_uniform(1.0, 1e4);
    recipe += " solar=blackbody " + number_text(t, 6) + " K " + number_text(total, 6) + " W/m2";
    return blackbody_spectrum(t, total);
  }
  const double v = r.log_uniform(1e-3, 10.0);
  recipe += " solar=constant " + number_text(v, 6);
  return Spectrum::constant(v);
}

Atmosphere random_atmosphere(Random& r, const std::string& name, std::string& recipe) {
  Atmosphere a;
  a.name = name;
  a.origin = name;
  a.wavelengths_nm = random_wavelengths(r);
  a.bottom_radius_m = r.log_uniform(1e5, 1e8);
  const double thickness = a.bottom_radius_m * r.log_uniform(1e-3, 0.5);
  a.top_radius_m = a.bottom_radius_m + thickness;
  a.sun_angular_radius_rad = r.log_uniform(1e-4, 0.2);
  a.ground_albedo = random_fraction_spectrum(r, 0.0, 1.0);
  if (r.chance(0.1)) a.ground_albedo = Spectrum::constant(r.chance(0.5) ? 0.0 : 1.0);
  a.solar_irradiance = random_solar(r, recipe);
  const int count = r.integer(1, 4);
  const PhaseFunction aerosol_phase = random_aerosol_phase(r);
  for (int i = 0; i < count; ++i) {
    Constituent c;
    const bool gas = (i == 0 && r.chance(0.8)) || r.chance(0.3);
    c.name = (gas ? "gas" : "aerosol") + std::to_string(i);
    c.density = random_density(r, thickness);
    const double column = column_length(c.density, thickness);
    // Vertical optical depths at 550 nm: scattering up to 5, absorption a
    // fraction of it or none; some constituents only absorb.
    const double tau_scattering = r.chance(0.1) ? 0.0 : r.log_uniform(1e-4, 5.0);
    const double tau_absorption =
        r.chance(0.5) ? 0.0 : std::max(tau_scattering, 1e-3) * r.log_uniform(1e-3, 1.0);
    const double exponent = gas ? -4.0 : r.uniform(-4.0, 1.0);
    c.scattering = random_coefficient(r, tau_scattering / column, exponent);
    c.absorption = random_coefficient(r, tau_absorption / column, r.uniform(-3.0, 1.0));
    c.phase = gas ? PhaseFunction{} : aerosol_phase;
    a.constituents.push_back(c);
  }
  return a;
}

// Planet JSON (docs/planet-format.md) of an atmosphere built in code.
nlohmann::json spectrum_json(const Spectrum& s, const char* unit) {
  nlohmann::json q;
  if (unit != nullptr) q["unit"] = unit;
  q["wavelengths_nm"] = s.wavelengths_nm();
  q["values"] = s.values();
  return q;
}

std::string planet_json(const Atmosphere& a) {
  using nlohmann::json;
  json j;
  j["format"] = "atmos-planet-1";
  j["name"] = a.name;
  j["wavelengths"] = {{"unit", "nm"}, {"values", a.wavelengths_nm}};
  j["bottom_radius"] = {{"value", a.bottom_radius_m}, {"unit", "m"}};
  j["top_radius"] = {{"value", a.top_radius_m}, {"unit", "m"}};
  j["sun_angular_radius"] = {{"value", a.sun_angular_radius_rad}, {"unit", "rad"}};
  j["solar_irradiance"] = spectrum_json(a.solar_irradiance, "W/m^2/nm");
  j["ground_albedo"] = spectrum_json(a.ground_albedo, "1");
  json constituents = json::array();
  for (const Constituent& c : a.constituents) {
    json q;
    q["name"] = c.name;
    if (c.density.kind == DensityProfile::Kind::exponential) {
      q["density"] = {{"profile", "exponential"}, {"scale_height", {{"value", c.density.scale_height_m}, {"unit", "m"}}}};
    } else {
      json points = json::array();
      for (const auto& k : c.density.knots) points.push_back({k.first, k.second});
      q["density"] = {{"profile", "piecewise_linear"}, {"altitude_unit", "m"}, {"points", points}};
    }
    q["scattering"] = spectrum_json(c.scattering, "1/m");
    q["absorption"] = spectrum_json(c.absorption, "1/m");
    switch (c.phase.kind) {
      case PhaseFunction::Kind::rayleigh: q["phase_function"] = {{"type", "rayleigh"}}; break;
      case PhaseFunction::Kind::henyey_greenstein:
        q["phase_function"] = {{"type", "henyey_greenstein"}, {"g", spectrum_json(c.phase.g, nullptr)}};
        break;
      case PhaseFunction::Kind::cornette_shanks:
        q["phase_function"] = {{"type", "cornette_shanks"}, {"g", spectrum_json(c.phase.g, nullptr)}};
        break;
      case PhaseFunction::Kind::double_henyey_greenstein:
        q["phase_function"] = {{"type", "double_henyey_greenstein"},
                               {"g", spectrum_json(c.phase.g, nullptr)},
                               {"g_back", spectrum_json(c.phase.g_back, nullptr)},
                               {"forward_weight", spectrum_json(c.phase.forward_weight, nullptr)}};
        break;
    }
    constituents.push_back(q);
  }
  j["constituents"] = constituents;
  return j.dump();
}

double largest_coefficient(const Atmosphere& a) {
  double m = 0.0;
  for (const Constituent& c : a.constituents) {
    for (double v : c.scattering.values()) m = std::max(m, v);
    for (double v : c.absorption.values()) m = std::max(m, v);
  }
  return m;
}

// Table sizes from the minima TableSizes::validate() accepts up to about
// those of the GPU tests (tests/table_sizes.hpp).
TableSizes random_sizes(Random& r) {
  TableSizes s;
  if (r.chance(0.05)) {
    s.transmittance_mu = 4;
    s.transmittance_r = 4;
    s.irradiance_mu_s = 4;
    s.irradiance_r = 2;
    s.scattering_nu = 2;
    s.scattering_mu_s = 4;
    s.scattering_mu = 8;
    s.scattering_r = 2;
    return s;
  }
  s.transmittance_mu = r.integer(8, 64);
  s.transmittance_r = r.integer(4, 16);
  s.irradiance_mu_s = r.integer(4, 32);
  s.irradiance_r = r.integer(2, 8);
  s.scattering_nu = r.integer(2, 6);
  s.scattering_mu_s = r.integer(4, 16);
  s.scattering_mu = 2 * r.integer(4, 16);
  s.scattering_r = r.integer(2, 12);
  return s;
}

}  // namespace

PlanetCase make_planet(std::uint64_t seed, int planet) {
  Random r(derive_seed(seed, kPlanetStream, std::uint64_t(planet)));
  PlanetCase p;
  p.index = planet;
  p.options.sizes = random_sizes(r);
  if (r.chance(0.35)) {
    const std::vector<std::string> names = preset_names();
    const std::string name = names[size_t(r.integer(0, int(names.size()) - 1))];
    p.recipe = "preset " + name;
    p.atmosphere = load_atmosphere(name);
    if (r.chance(0.4)) {
      const int n = r.chance(0.8) ? r.integer(3, 12) : r.integer(13, 48);
      p.atmosphere.wavelengths_nm = spectral_wavelengths(n);
      p.recipe += " wavelengths=" + std::to_string(n);
    }
    if (r.chance(0.4)) {
      // Up to 100x, keeping every coefficient within validate()'s 1 m^-1.
      const double factor = std::min(r.log_uniform(0.01, 100.0), 1.0 / largest_coefficient(p.atmosphere));
      scale_density(p.atmosphere, factor);
      p.recipe += " density-scale=" + number_text(factor, 6);
    }
    if (r.chance(0.3)) {
      const std::string solar =
          r.chance(0.5) ? std::string("table") : "blackbody:" + number_text(std::round(r.log_uniform(1000.0, 1e5)), 6);
      set_solar_spectrum(p.atmosphere, solar);
      p.recipe += " solar=" + solar;
    }
  } else {
    const std::string name = "random-" + std::to_string(planet);
    p.recipe = "random";
    p.atmosphere = random_atmosphere(r, name, p.recipe);
    if (r.chance(0.3)) {
      p.atmosphere = parse_atmosphere(planet_json(p.atmosphere), name + ".json");
      p.recipe += " (through planet JSON)";
    }
  }
  if (r.chance(0.25)) {
    p.options.auto_orders = true;
    p.options.scattering_orders = r.integer(2, 24);
  } else {
    p.options.scattering_orders = r.integer(1, 4);
  }
  p.frame.units_per_metre = r.log_uniform(1e-4, 10.0);
  const double centre_scale = r.log_uniform(1.0, 1e7);
  p.frame.centre = glm::dvec3(r.normal(), r.normal(), r.normal()) * centre_scale;
  p.precision = r.chance(0.5) ? TexturePrecision::half : TexturePrecision::full;
  p.surfaces = r.chance(0.6) ? SurfaceMode::lit_colour : SurfaceMode::gbuffer;
  p.shadow_map = r.chance(0.25);
  p.plugin_stars = r.chance(0.3);
  p.moons = r.chance(0.4);
  p.formats = random_texture_formats(r);
  return p;
}

std::string describe(const PlanetCase& p) {
  const Atmosphere& a = p.atmosphere;
  std::ostringstream o;
  o << "planet " << p.index << ": " << p.recipe << "\n";
  o << "  radii " << number_text(a.bottom_radius_m, 6) << " .. " << number_text(a.top_radius_m, 6) << " m, sun radius "
    << number_text(a.sun_angular_radius_rad, 6) << " rad, " << a.wavelengths_nm.size() << " wavelengths";
  if (a.wavelengths_nm.size() == 3)
    o << " (" << number_text(a.wavelengths_nm[0], 6) << ", " << number_text(a.wavelengths_nm[1], 6) << ", "
      << number_text(a.wavelengths_nm[2], 6) << " nm)";
  o << "\n  ground albedo at 550 nm " << number_text(a.ground_albedo.at(550.0), 6) << ", solar irradiance at 550 nm "
    << number_text(a.solar_irradiance.at(550.0), 6) << " W/m2/nm\n";
  for (const Constituent& c : a.constituents) {
    o << "  " << c.name << ": ";
    if (c.density.kind == DensityProfile::Kind::exponential) {
      o << "exponential H " << number_text(c.density.scale_height_m, 6) << " m";
    } else {
      o << "piecewise";
      for (const auto& k : c.density.knots)
        o << " (" << number_text(k.first, 6) << " m, " << number_text(k.second, 6) << ")";
    }
    o << ", scattering(550) " << number_text(c.scattering.at(550.0), 6) << " /m, absorption(550) "
      << number_text(c.absorption.at(550.0), 6) << " /m, phase ";
    switch (c.phase.kind) {
      case PhaseFunction::Kind::rayleigh: o << "rayleigh"; break;
      case PhaseFunction::Kind::henyey_greenstein: o << "HG g(550) " << number_text(c.phase.g.at(550.0), 6); break;
      case PhaseFunction::Kind::cornette_shanks: o << "CS g(550) " << number_text(c.phase.g.at(550.0), 6); break;
      case PhaseFunction::Kind::double_henyey_greenstein:
        o << "DHG g(550) " << number_text(c.phase.g.at(550.0), 6) << " g_back "
          << number_text(c.phase.g_back.at(550.0), 6) << " w " << number_text(c.phase.forward_weight.at(550.0), 6);
        break;
    }
    o << "\n";
  }
  const TableSizes& s = p.options.sizes;
  o << "  tables: transmittance " << s.transmittance_mu << "x" << s.transmittance_r << ", irradiance "
    << s.irradiance_mu_s << "x" << s.irradiance_r << ", scattering nu " << s.scattering_nu << " mu_s "
    << s.scattering_mu_s << " mu " << s.scattering_mu << " r " << s.scattering_r << "; orders "
    << (p.options.auto_orders ? "auto (cap " + std::to_string(p.options.scattering_orders) + ")"
                              : std::to_string(p.options.scattering_orders))
    << "; texture precision " << (p.precision == TexturePrecision::half ? "half" : "full") << "\n";
  o << "  runs: plugin " << (p.surfaces == SurfaceMode::lit_colour ? "lit colour" : "G-buffer")
    << (p.shadow_map ? ", shadow map" : "") << (p.plugin_stars ? ", stars" : "")
    << (p.moons ? "; moons" : "; no moons") << "\n";
  o << "  engine frame: centre (" << number_text(p.frame.centre.x, 6) << ", " << number_text(p.frame.centre.y, 6)
    << ", " << number_text(p.frame.centre.z, 6) << "), units per metre " << number_text(p.frame.units_per_metre, 6);
  return o.str();
}

}  // namespace atmos::sweep
