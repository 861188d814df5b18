// The atmosphere's description: spectra, density profiles, phase functions,
// validation, and spectra built from physical inputs.
#include "atmos/atmosphere.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "data/embedded_files.hpp"

namespace atmos {
namespace {

// Planck's law scaled so that its integral over all wavelengths is `total`
// (W m^-2): E(λ) = total · π B(λ, T) / (σ T⁴), in W m^-2 nm^-1.
double blackbody_irradiance(double wavelength_nm, double temperature, double total) {
  constexpr double h = 6.62607015e-34, c = 299792458.0, k = 1.380649e-23, sigma = 5.670374419e-8;
  const double l = wavelength_nm * 1e-9;
  const double radiance = 2.0 * h * c * c / std::pow(l, 5) / std::expm1(h * c / (l * k * temperature));
  return total * M_PI * radiance / (sigma * std::pow(temperature, 4)) * 1e-9;
}

// Samples f every 1 nm over 200-2000 nm, the range validate() accepts for
// working wavelengths: linear interpolation between the samples is then exact
// to well below 0.1 % for the smooth laws below.
template <class F>
Spectrum sampled_spectrum(F&& f) {
  std::vector<double> l, v;
  for (double w = 200.0; w <= 2000.0; w += 1.0) {
    l.push_back(w);
    v.push_back(f(w));
  }
  return Spectrum(l, v);
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

Spectrum rayleigh_scattering_spectrum(double refractive_index, double number_density_m3, double king_factor) {
  if (!(refractive_index > 1.0 && refractive_index < 2.0) || !(number_density_m3 > 0.0) ||
      !(king_factor >= 1.0 && king_factor < 2.0))
    throw Error("Rayleigh scattering needs a refractive index in (1, 2), a positive number density and a King "
                "factor in [1, 2)");
  const double n2 = (refractive_index * refractive_index - 1.0) * (refractive_index * refractive_index - 1.0);
  return sampled_spectrum([&](double w) {
    const double lambda = w * 1e-9;
    return 8.0 * M_PI * M_PI * M_PI * n2 * king_factor / (3.0 * number_density_m3 * lambda * lambda * lambda * lambda);
  });
}

Spectrum cross_section_spectrum(const Spectrum& cross_section_m2, double number_density_m3) {
  if (!(number_density_m3 > 0.0) || cross_section_m2.empty())
    throw Error("a coefficient from a cross section needs the cross section and a positive number density");
  return sampled_spectrum([&](double w) { return number_density_m3 * cross_section_m2.at(w); });
}

Spectrum angstrom_aerosol_spectrum(double alpha, double beta, double scale_height_m) {
  if (!(alpha >= -1.0 && alpha <= 4.0) || !(beta >= 0.0) || !(scale_height_m > 0.0))
    throw Error("an Angstrom aerosol needs alpha in [-1, 4], beta >= 0 and a positive scale height");
  return sampled_spectrum([&](double w) { return beta * std::pow(w / 1000.0, -alpha) / scale_height_m; });
}

Spectrum power_law_spectrum(double value, double reference_nm, double exponent) {
  if (!std::isfinite(value) || !(reference_nm > 0.0) || !std::isfinite(exponent))
    throw Error("a power law needs a finite value and exponent and a positive reference wavelength");
  return sampled_spectrum([&](double w) { return value * std::pow(w / reference_nm, exponent); });
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
    const char* text = data::embedded_file("data/spectra/solar_irradiance.csv");
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

}  // namespace atmos
