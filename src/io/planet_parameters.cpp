// The table of the planet's adjustable parameters (atmos/planet_parameters.hpp).
// Valid ranges are those Atmosphere::validate and the precomputation accept
// (a scale height or radius must be positive, |g| < 0.999 keeps the
// Henyey-Greenstein lobe finite, the tables take 3 to 48 wavelengths); the
// edits' ranges (density and coefficient factors, the thickness) are what
// the viewer lets a user type.
#include "atmos/planet_parameters.hpp"

#include <cmath>
#include <limits>

#include "atmos/atmosphere.hpp"
#include "physics/checks.hpp"

namespace atmos {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDegree = M_PI / 180.0;

}  // namespace

const std::vector<PlanetParameter>& planet_parameters() {
  static const std::vector<PlanetParameter> table = {
      {"wavelengths", "wavelengths", "1", 1.0, 3, 48, true, true, 3, 3, 48, false,
       "the number of working wavelengths (3: the fast mode; more: spectral)"},
      {"bottom_radius", "ground radius", "km", 1e3, 0, kInf, false, false, 6371, 1000, 20000, true,
       "the ground's radius, the globe's datum"},
      {"atmosphere_thickness", "atmosphere thickness", "km", 1e3, 1, 1e4, true, true, 100, 10, 1000, true,
       "top_radius - bottom_radius (top_radius is at most 1.5 x bottom_radius)"},
      {"sun_angular_radius", "sun's angular radius", "deg", kDegree, 0, 0.2 / kDegree, false, true, 0.2665, 0.05, 2,
       true, "the apparent radius of the sun's disc"},
      {"ground_albedo", "ground albedo", "1", 1.0, 0, 1, true, true, 0.1, 0, 1, false,
       "Lambertian reflectance of the ground (each sample)"},
      {"density_scale", "density scale", "1", 1.0, 0, 1e4, false, true, 1, 0.05, 20, true,
       "factor on every constituent's number density (--density-scale)"},
      {"constituents[].scattering_scale", "scattering x", "1", 1.0, 0, 100, true, true, 1, 0.01, 100, true,
       "factor on a constituent's scattering coefficients"},
      {"constituents[].absorption_scale", "absorption x", "1", 1.0, 0, 100, true, true, 1, 0.01, 100, true,
       "factor on a constituent's absorption coefficients"},
      {"constituents[].density.scale_height", "scale height", "km", 1e3, 0, kInf, false, false, 8.44, 0.1, 100, true,
       "H of an exponential density profile exp(-h / H)"},
      {"constituents[].phase_function.g", "phase g", "1", 1.0, -0.999, 0.999, false, false, 0.64, -0.95, 0.95, false,
       "asymmetry parameter of a non-Rayleigh phase function (of the forward lobe of a double HG)"},
      {"constituents[].phase_function.g_back", "phase g back", "1", 1.0, -0.999, 0.999, false, false, 0, -0.95, 0.95,
       false, "asymmetry parameter of a double Henyey-Greenstein's second lobe"},
      {"constituents[].phase_function.forward_weight", "forward weight", "1", 1.0, 0, 1, true, true, 1, 0, 1, false,
       "weight of a double Henyey-Greenstein's first lobe"},
  };
  return table;
}

const PlanetParameter& planet_parameter(const std::string& name) {
  for (const PlanetParameter& p : planet_parameters())
    if (name == p.name) return p;
  throw Error("no planet parameter \"" + name + "\"");
}

std::string valid_range_text(const PlanetParameter& p) {
  if (p.min == 0 && !p.min_inclusive && std::isinf(p.max)) return "positive";
  const std::string unit = std::string(p.unit) == "1" ? "" : std::string(" ") + p.unit;
  return "in " + std::string(p.min_inclusive ? "[" : "(") + number_text(p.min) + ", " + number_text(p.max) +
         (p.max_inclusive ? "]" : ")") + unit;
}

void check_planet_parameter(const std::string& name, double value_si, const std::string& what) {
  const PlanetParameter& p = planet_parameter(name);
  const double v = value_si / p.si_per_unit;
  const bool above = p.min_inclusive ? v >= p.min : v > p.min;
  const bool below = p.max_inclusive ? v <= p.max : v < p.max;
  if (!(std::isfinite(v) && above && below)) {
    const std::string unit = std::string(p.unit) == "1" ? "" : std::string(" ") + p.unit;
    throw Error(what + " must be " + valid_range_text(p) + ", got " + number_text(v) + unit);
  }
}

}  // namespace atmos
