// atmos — water: the spectra of pure water, phytoplankton and dissolved
// organic matter, the validation of the inputs, and the WaterParams of the
// shared functions (src/physics/water.glsl).
#include "physics/water.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "physics/parameters.hpp"
#include "data/embedded_files.hpp"

namespace atmos::physics {
namespace {

// The columns of an embedded CSV table (comment lines start with '#', the
// header with a letter), one Spectrum per value column.
std::vector<Spectrum> embedded_table(const char* path, int value_columns) {
  const char* text = data::embedded_file(path);
  if (text == nullptr) throw Error(std::string("not embedded in this build: ") + path);
  std::istringstream in(text);
  std::string line;
  std::vector<double> wavelengths;
  std::vector<std::vector<double>> values(static_cast<size_t>(value_columns));
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || std::isalpha(static_cast<unsigned char>(line[0]))) continue;
    double v[4] = {0.0, 0.0, 0.0, 0.0};
    const int read = std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3]);
    if (read != value_columns + 1) throw Error(std::string("malformed line in ") + path + ": " + line);
    wavelengths.push_back(v[0]);
    for (int c = 0; c < value_columns; ++c) values[size_t(c)].push_back(v[c + 1]);
  }
  std::vector<Spectrum> columns;
  for (const auto& column : values) columns.emplace_back(wavelengths, column);
  return columns;
}

const std::vector<Spectrum>& pure_water_table() {
  static const std::vector<Spectrum> table = embedded_table("data/spectra/pure_water.csv", 2);
  return table;
}

const std::vector<Spectrum>& phytoplankton_table() {
  static const std::vector<Spectrum> table = embedded_table("data/spectra/phytoplankton_absorption.csv", 2);
  return table;
}

void check_wavelength(double wavelength_nm) {
  if (!(wavelength_nm >= 300.0 && wavelength_nm <= 830.0))
    throw Error("water: the wavelength must be in [300, 830] nm (the pure-water table), got " +
                std::to_string(wavelength_nm));
}

void check_range(const char* what, double value, double low, double high, const char* unit) {
  if (!(value >= low && value <= high))
    throw Error(std::string("water: the ") + what + " must be in [" + std::to_string(low) + ", " +
                std::to_string(high) + "] " + unit + ", got " + std::to_string(value));
}

// The fits' lowest concentration (Bricaud et al. 1998; Morel & Maritorena 2001).
constexpr double kLowestFittedChlorophyll = 0.02;

double particle_spectral_exponent(double chlorophyll_mg_m3) {
  const double chl = std::max(chlorophyll_mg_m3, kLowestFittedChlorophyll);
  return chl < 2.0 ? 0.5 * (std::log10(chl) - 0.3) : 0.0;
}

}  // namespace

void validate_water(const Water& water) {
  check_range("wind speed", water.wind_speed_m_s, 0.0, 50.0, "m/s");
  check_range("chlorophyll concentration", water.chlorophyll_mg_m3, 0.0, 25.0, "mg m^-3");
  check_range("CDOM absorption at 440 nm", water.cdom_absorption_440_per_m, 0.0, 10.0, "m^-1");
  check_range("salinity", water.salinity_psu, 0.0, 40.0, "PSU");
  check_range("temperature", water.temperature_c, 0.0, 30.0, "degrees C");
}

void validate_seabed(double depth_m, const vec3& albedo) {
  if (!(depth_m >= 0.0))
    throw Error("water: the seabed depth must be >= 0 m (infinity for deep water), got " + std::to_string(depth_m));
  for (int c = 0; c < 3; ++c)
    if (!(albedo[c] >= 0.0f && albedo[c] <= 1.0f))
      throw Error("water: the seabed albedo must be in [0, 1], got " + std::to_string(albedo[c]));
}

double pure_water_absorption(double wavelength_nm) {
  check_wavelength(wavelength_nm);
  return pure_water_table()[0].at(wavelength_nm);
}

double water_scattering(double wavelength_nm, double salinity_psu) {
  check_wavelength(wavelength_nm);
  const double seawater = pure_water_table()[1].at(wavelength_nm);
  return seawater / 1.30 * (1.0 + 0.30 * salinity_psu / 37.0);
}

double phytoplankton_absorption(double wavelength_nm, double chlorophyll_mg_m3) {
  check_wavelength(wavelength_nm);
  if (chlorophyll_mg_m3 <= 0.0) return 0.0;
  const auto& table = phytoplankton_table();
  // Spectrum::at holds the end values beyond the table.
  return table[0].at(wavelength_nm) * std::pow(chlorophyll_mg_m3, table[1].at(wavelength_nm));
}

double cdom_absorption(double wavelength_nm, double absorption_440_per_m) {
  check_wavelength(wavelength_nm);
  return absorption_440_per_m * std::exp(-0.014 * (wavelength_nm - 440.0));
}

double particle_scattering(double wavelength_nm, double chlorophyll_mg_m3) {
  check_wavelength(wavelength_nm);
  if (chlorophyll_mg_m3 <= 0.0) return 0.0;
  return 0.416 * std::pow(chlorophyll_mg_m3, 0.766) *
         std::pow(wavelength_nm / 550.0, particle_spectral_exponent(chlorophyll_mg_m3));
}

double particle_backscattering(double wavelength_nm, double chlorophyll_mg_m3) {
  if (chlorophyll_mg_m3 <= 0.0) return 0.0;
  const double chl = std::max(chlorophyll_mg_m3, kLowestFittedChlorophyll);
  const double ratio = 0.002 + 0.01 * (0.5 - 0.25 * std::log10(chl)) *
                                   std::pow(wavelength_nm / 550.0, particle_spectral_exponent(chl));
  return ratio * particle_scattering(wavelength_nm, chlorophyll_mg_m3);
}

double diffuse_fresnel_reflectance(double eta) {
  // 2 ∫ F(μ) μ dμ = ∫ F(√x) dx with x = μ²: the midpoint rule in x.
  constexpr int kNodes = 4096;
  double sum = 0.0;
  for (int i = 0; i < kNodes; ++i) {
    const double x = (double(i) + 0.5) / kNodes;
    sum += double(fresnel_reflectance(float(std::sqrt(x)), float(eta)));
  }
  return sum / kNodes;
}

WaterParams make_water_params(const Water& water, const std::array<double, 3>& wavelengths_nm) {
  validate_water(water);
  WaterParams p{};
  for (int c = 0; c < 3; ++c) {
    const double l = wavelengths_nm[size_t(c)];
    check_wavelength(l);
    const double n = double(water_refractive_index(float(l), float(water.salinity_psu), float(water.temperature_c)));
    const double a = pure_water_absorption(l) + phytoplankton_absorption(l, water.chlorophyll_mg_m3) +
                     cdom_absorption(l, water.cdom_absorption_440_per_m);
    const double b_b = 0.5 * water_scattering(l, water.salinity_psu) +
                       particle_backscattering(l, water.chlorophyll_mg_m3);
    p.refractive_index[c] = float(n);
    p.absorption[c] = float(a);
    p.backscattering[c] = float(b_b);
    p.diffuse_reflectance[c] = float(diffuse_fresnel_reflectance(n));
  }
  p.slope_variance = cox_munk_slope_variance(float(water.wind_speed_m_s));
  return p;
}

std::array<double, 3> water_channel_wavelengths(const Atmosphere& atmosphere) {
  if (atmosphere.wavelengths_nm.size() == 3)
    return {atmosphere.wavelengths_nm[0], atmosphere.wavelengths_nm[1], atmosphere.wavelengths_nm[2]};
  return kRenderPhaseWavelengths;
}

std::unique_ptr<WaterSpectrum> make_water_spectrum(const Water& water, const Atmosphere& atmosphere) {
  const int count = spectral_set_count(atmosphere.wavelengths_nm);
  if (count < 1 || count > SPECTRAL_SET_CAPACITY)
    throw Error("water: " + std::to_string(atmosphere.wavelengths_nm.size()) +
                " working wavelengths, not 1 to " + std::to_string(3 * SPECTRAL_SET_CAPACITY));
  const std::array<double, 3> channels = water_channel_wavelengths(atmosphere);
  // The channels in increasing wavelength, for the interpolation.
  std::array<int, 3> order = {0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int a, int b) { return channels[size_t(a)] < channels[size_t(b)]; });
  // w_c(λ): linear in ln λ between the neighbouring channels' wavelengths.
  const auto weights = [&](double l) {
    glm::dvec3 w(0.0);
    const double lo = channels[size_t(order[0])], hi = channels[size_t(order[2])];
    if (l <= lo) {
      w[order[0]] = 1.0;
    } else if (l >= hi) {
      w[order[2]] = 1.0;
    } else {
      const int i = l <= channels[size_t(order[1])] ? 0 : 1;
      const double a = channels[size_t(order[size_t(i)])], b = channels[size_t(order[size_t(i) + 1])];
      const double t = b > a ? std::log(l / a) / std::log(b / a) : 0.0;
      w[order[size_t(i)]] = 1.0 - t;
      w[order[size_t(i) + 1]] = t;
    }
    return w;
  };
  auto spectrum = std::make_unique<WaterSpectrum>();
  *spectrum = WaterSpectrum{};
  spectrum->count = count;
  for (int k = 0; k < count; ++k) {
    const std::array<double, 3> w = set_wavelengths(atmosphere.wavelengths_nm, k);
    const std::array<double, 3> clamped = {std::clamp(w[0], 300.0, 830.0), std::clamp(w[1], 300.0, 830.0),
                                           std::clamp(w[2], 300.0, 830.0)};
    spectrum->set[k] = make_water_params(water, clamped);
    spectrum->solar_irradiance[k] = vec3(float(atmosphere.solar_irradiance.at(w[0])),
                                         float(atmosphere.solar_irradiance.at(w[1])),
                                         float(atmosphere.solar_irradiance.at(w[2])));
    spectrum->to_channels[k] = set_to_channels(atmosphere.wavelengths_nm, k);
    mat3 from(0.0f);
    for (int i = 0; i < 3; ++i) {
      const glm::dvec3 wi = weights(w[size_t(i)]);
      for (int c = 0; c < 3; ++c) from[c][i] = float(wi[c]);
    }
    spectrum->from_channels[k] = from;
  }
  return spectrum;
}

}  // namespace atmos::physics
