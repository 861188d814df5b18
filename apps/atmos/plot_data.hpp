// atmos plot-data — the numbers behind the plots of docs/plots.md, as CSV.
//
// A plotting helper of the command line, not part of the library: it only
// reads the library's public API (the planet description, the tables, the
// sky model, the colour conversion) and the reference's transmittance, and
// writes what it reads as CSV files into one directory. scripts/plots.py
// turns them into PNG images. Header-only so that tests/plot_test.cpp can
// call its writers without the command line (plot_data.cpp runs them).
//
//   info.csv           key,value: planet, working wavelengths, orders, options
//   solar.csv          wavelength_nm,irradiance_W_m2_nm (360-830 nm, 1 nm steps)
//   extinction.csv     wavelength_nm,scattering_<c>_per_m,absorption_<c>_per_m
//                      for every constituent c, at its reference density
//                      (5 nm steps)
//   transmittance.csv  altitude_km,view_zenith_deg,luminance,red,green,blue,
//                      transmittance_<λ>nm for every working wavelength: the
//                      transmittance from the observer to the top of the
//                      atmosphere, 0-95 degrees (rays that hit the ground
//                      are left out); luminance, red, green and blue are
//                      those of sunlight: Y(sun x T) / Y(sun), and the same
//                      per linear sRGB channel, clamped to [0, 1]
//   sky.csv            sun_elevation_deg,relative_azimuth_deg,view_zenith_deg,
//                      luminance_cd_m2,red,green,blue: the sky in the sun's
//                      vertical plane (relative azimuth 0: towards the sun,
//                      180: away from it), seen from the ground, no sun disc
//   convergence.csv    order,added,relative,tail: Tables::convergence; tail 0:
//                      what order n adds, and that over orders 1..n;
//                      tail 1 (last row, auto orders that hit the cap): the
//                      light of all orders from `order` on, solved at once,
//                      and its share of all the light
#pragma once

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/colour.hpp"
#include "reference/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"

namespace atmos_cli::plot_data {

// What the plots say about how the data was made (info.csv).
struct Info {
  std::string planet;         // --planet as given
  std::string tables;         // default | small
  std::string solar;          // --solar, or "planet file"
  double density_scale = 1.0;
};

// Observer altitudes of transmittance.csv (km; those at or above the top of
// the atmosphere are left out) and sun elevations of sky.csv (degrees).
inline const std::vector<double> kTransmittanceAltitudesKm = {0.0, 2.0, 10.0, 30.0};
inline const std::vector<double> kSkySunElevationsDeg = {2.0, 10.0, 30.0, 60.0};

// "%g"-style number for CSV cells: 6 significant digits, as `atmos sample`.
inline std::string number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", v);
  return buffer;
}

// A constituent name as a column-name fragment: letters, digits and '_'.
inline std::string column_name(const std::string& name) {
  std::string out;
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out.empty() ? std::string("unnamed") : out;
}

// Creates `dir` if it does not exist (its parent must), so that a mistyped
// path fails at once rather than after the precomputation.
inline void prepare_directory(const std::string& dir) {
  namespace fs = std::filesystem;
  if (dir.empty()) throw atmos::Error("--out must name a directory");
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  if (fs::exists(dir, ec)) throw atmos::Error("cannot write plot data to " + dir + ": not a directory");
  if (!fs::create_directory(dir, ec) || ec)
    throw atmos::Error("cannot create the output directory " + dir + ": " + ec.message());
}

// Writes one CSV file; `body` streams the rows. Throws Error naming the file
// if it cannot be written completely. Returns the path written.
inline std::string write_csv(const std::string& dir, const std::string& name,
                             const std::function<void(std::ostream&)>& body) {
  const std::string path = (std::filesystem::path(dir) / name).string();
  std::ofstream out(path);
  if (!out) throw atmos::Error("cannot write " + path);
  body(out);
  out.close();
  if (!out) throw atmos::Error("cannot write " + path + " (write failed)");
  return path;
}

inline void write_info(std::ostream& out, const atmos::Atmosphere& a, const Info& info, int orders) {
  std::string wavelengths;
  for (double w : a.wavelengths_nm) wavelengths += (wavelengths.empty() ? "" : " ") + number(w);
  out << "key,value\n";
  out << "planet," << a.name << "\n";
  out << "planet_argument," << info.planet << "\n";
  out << "wavelengths_nm," << wavelengths << "\n";
  out << "mode," << (a.wavelengths_nm.size() == 3 ? "three wavelengths" : "spectral") << "\n";
  out << "orders," << orders << "\n";
  out << "tables," << info.tables << "\n";
  out << "solar," << info.solar << "\n";
  out << "density_scale," << number(info.density_scale) << "\n";
  out << "bottom_radius_km," << number(a.bottom_radius_m / 1000.0) << "\n";
  out << "top_radius_km," << number(a.top_radius_m / 1000.0) << "\n";
}

inline void write_solar(std::ostream& out, const atmos::Atmosphere& a) {
  out << "wavelength_nm,irradiance_W_m2_nm\n";
  for (int w = 360; w <= 830; ++w) out << w << "," << number(a.solar_irradiance.at(double(w))) << "\n";
}

inline void write_extinction(std::ostream& out, const atmos::Atmosphere& a) {
  out << "wavelength_nm";
  for (const auto& c : a.constituents)
    out << ",scattering_" << column_name(c.name) << "_per_m,absorption_" << column_name(c.name) << "_per_m";
  out << "\n";
  for (int w = 360; w <= 830; w += 5) {
    out << w;
    for (const auto& c : a.constituents)
      out << "," << number(c.scattering.at(double(w))) << "," << number(c.absorption.at(double(w)));
    out << "\n";
  }
}

// Transmittance from `altitude_m` to the top of the atmosphere along a view
// zenith angle, at every working wavelength; empty if the ray hits the ground.
// The reference's transmittance, which reads nothing but the planet
// description.
inline std::vector<double> transmittance_to_top(const atmos::Atmosphere& a, double altitude_m, double zenith_deg) {
  const double r = a.bottom_radius_m + altitude_m;
  const double mu = std::cos(zenith_deg * M_PI / 180.0);
  const double rb = a.bottom_radius_m, rt = a.top_radius_m;
  // Ray x = r·up + t·v: hits the ground if it descends and |x| reaches rb.
  if (mu < 0.0 && r * r * (mu * mu - 1.0) + rb * rb > 0.0) return {};
  const double to_top = -r * mu + std::sqrt(std::max(0.0, r * r * (mu * mu - 1.0) + rt * rt));
  const glm::dvec3 from(0.0, 0.0, r);
  const glm::dvec3 view(std::sin(zenith_deg * M_PI / 180.0), 0.0, mu);
  const glm::dvec3 to = from + view * to_top;
  return atmos::reference_transmittance(a, from, to);
}

inline void write_transmittance(std::ostream& out, const atmos::Atmosphere& a) {
  const auto& wl = a.wavelengths_nm;
  // Sunlight-weighted colour of the transmittance, as the tables define it in
  // spectral mode: sRGB(sun x T) / sRGB(sun), per channel and for luminance.
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(wl);
  glm::dvec3 sun_rgb(0.0);
  for (size_t i = 0; i < wl.size(); ++i) sun_rgb += weights[i] * a.solar_irradiance.at(wl[i]);
  const double sun_luminance = atmos::srgb_luminance(sun_rgb);

  out << "altitude_km,view_zenith_deg,luminance,red,green,blue";
  for (double w : wl) out << ",transmittance_" << number(w) << "nm";
  out << "\n";
  for (double altitude_km : kTransmittanceAltitudesKm) {
    if (altitude_km * 1000.0 >= a.top_radius_m - a.bottom_radius_m) continue;
    // 0 to 85 degrees in 0.5 degree steps, then to 95 in 0.1 degree steps.
    for (int step = 0; step <= 270; ++step) {
      const double zenith = step <= 170 ? 0.5 * step : double(680 + step) / 10.0;
      const std::vector<double> t = transmittance_to_top(a, altitude_km * 1000.0, zenith);
      if (t.empty()) continue;
      glm::dvec3 rgb(0.0);
      for (size_t i = 0; i < wl.size(); ++i) rgb += weights[i] * a.solar_irradiance.at(wl[i]) * t[i];
      // A deeply reddened sun falls outside the sRGB gamut (a negative
      // blue): clamped to [0, 1], as in the tables.
      const glm::dvec3 channels = glm::clamp(rgb / sun_rgb, 0.0, 1.0);
      out << number(altitude_km) << "," << number(zenith) << "," << number(atmos::srgb_luminance(rgb) / sun_luminance)
          << "," << number(channels.x) << "," << number(channels.y) << "," << number(channels.z);
      for (double v : t) out << "," << number(v);
      out << "\n";
    }
  }
}

inline void write_sky(std::ostream& out, const atmos::Atmosphere& a, const atmos::Tables& tables) {
  const atmos::SkyModel model(a, tables);
  const glm::dvec3 observer = atmos::observer_position(a, 0.0);
  const double sun_azimuth = 180.0;
  out << "sun_elevation_deg,relative_azimuth_deg,view_zenith_deg,luminance_cd_m2,red,green,blue\n";
  for (double sun_elevation : kSkySunElevationsDeg) {
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(sun_azimuth, sun_elevation);
    for (double relative_azimuth : {180.0, 0.0}) {
      for (int zenith = 0; zenith <= 90; ++zenith) {
        const glm::dvec3 view = atmos::direction_from_azimuth_elevation(sun_azimuth + relative_azimuth, 90.0 - zenith);
        const glm::dvec3 rgb = model.to_srgb(model.radiance(observer, view, sun, false));
        out << number(sun_elevation) << "," << number(relative_azimuth) << "," << zenith << ","
            << number(atmos::srgb_luminance(rgb)) << "," << number(rgb.x) << "," << number(rgb.y) << ","
            << number(rgb.z) << "\n";
      }
    }
  }
}

inline void write_convergence(std::ostream& out, const atmos::Tables& tables) {
  out << "order,added,relative,tail\n";
  for (const auto& c : tables.convergence)
    out << c.order << "," << number(c.added) << "," << number(c.relative) << "," << (c.tail ? 1 : 0) << "\n";
}

}  // namespace atmos_cli::plot_data
