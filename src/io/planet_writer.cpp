// Planet files written back (atmos/planet_file.hpp, write_planet_file):
// every quantity in SI units with each spectrum's samples as they are, so
// that parse_atmosphere reads back the same atmosphere, sample for sample
// (unit factors of 1 and the shortest decimal that reads back as the same
// double, as nlohmann::json prints numbers).
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "atmos/planet_file.hpp"

namespace atmos {

namespace {

using nlohmann::json;

json spectrum(const Spectrum& s, const char* unit) {
  return json{{"unit", unit}, {"wavelengths_nm", s.wavelengths_nm()}, {"values", s.values()}};
}

json scalar(double value, const char* unit) { return json{{"value", value}, {"unit", unit}}; }

const char* style_name(SurfaceStyle style) {
  switch (style) {
    case SurfaceStyle::earth: return "earth";
    case SurfaceStyle::mars: return "mars";
    case SurfaceStyle::venus: return "venus";
    case SurfaceStyle::titan: return "titan";
    case SurfaceStyle::flat: return "flat";
  }
  return "flat";
}

// A raster's source as a path that holds from any directory: absolute
// (relative paths were relative to the working directory once resolved
// against the planet file's), GDAL's descriptions as they are.
std::string portable_source(const std::string& source) {
  if (source.empty() || source.front() == '<' || source.rfind("/vsi", 0) == 0) return source;
  return std::filesystem::absolute(source).lexically_normal().string();
}

json raster(const SurfaceRaster& r, bool elevation) {
  json out{{"source", portable_source(r.source)}};
  if (!r.crs.empty()) out["crs"] = r.crs;
  if (elevation && r.metres_per_unit != 0.0) {
    if (r.metres_per_unit == 1.0) out["unit"] = "m";
    else if (r.metres_per_unit == 1e3) out["unit"] = "km";
    else if (r.metres_per_unit == 0.3048) out["unit"] = "ft";
    else throw Error("write_planet_file: elevation unit of " + std::to_string(r.metres_per_unit) +
                     " m has no name in the format (m, km, ft)");
  }
  if (r.bounds_deg) out["bounds_deg"] = *r.bounds_deg;
  return out;
}

json phase(const PhaseFunction& p) {
  const auto parameter = [](const Spectrum& s) {
    return json{{"wavelengths_nm", s.wavelengths_nm()}, {"values", s.values()}};
  };
  switch (p.kind) {
    case PhaseFunction::Kind::rayleigh: return json{{"type", "rayleigh"}};
    case PhaseFunction::Kind::henyey_greenstein: return json{{"type", "henyey_greenstein"}, {"g", parameter(p.g)}};
    case PhaseFunction::Kind::cornette_shanks: return json{{"type", "cornette_shanks"}, {"g", parameter(p.g)}};
    case PhaseFunction::Kind::double_henyey_greenstein:
      return json{{"type", "double_henyey_greenstein"},
                  {"g", parameter(p.g)},
                  {"g_back", parameter(p.g_back)},
                  {"forward_weight", parameter(p.forward_weight)}};
  }
  return json{{"type", "rayleigh"}};
}

json density(const DensityProfile& d) {
  if (d.kind == DensityProfile::Kind::exponential)
    return json{{"profile", "exponential"}, {"scale_height", scalar(d.scale_height_m, "m")}};
  json points = json::array();
  for (const auto& [altitude, value] : d.knots) points.push_back(json::array({altitude, value}));
  return json{{"profile", "piecewise_linear"}, {"altitude_unit", "m"}, {"points", points}};
}

}  // namespace

std::string format_planet(const Atmosphere& a, const PlanetSurface& surface) {
  a.validate();
  json doc;
  doc["format"] = "atmos-planet-1";
  doc["name"] = a.name;
  doc["wavelengths"] = json{{"unit", "nm"}, {"values", a.wavelengths_nm}};
  doc["bottom_radius"] = scalar(a.bottom_radius_m, "m");
  doc["top_radius"] = scalar(a.top_radius_m, "m");
  doc["sun_angular_radius"] = scalar(a.sun_angular_radius_rad, "rad");
  doc["solar_irradiance"] = spectrum(a.solar_irradiance, "W/m^2/nm");
  doc["ground_albedo"] = spectrum(a.ground_albedo, "1");
  json constituents = json::array();
  for (const Constituent& c : a.constituents)
    constituents.push_back(json{{"name", c.name},
                                {"density", density(c.density)},
                                {"scattering", spectrum(c.scattering, "1/m")},
                                {"absorption", spectrum(c.absorption, "1/m")},
                                {"phase_function", phase(c.phase)}});
  doc["constituents"] = constituents;
  if (!(surface == PlanetSurface{})) {
    json s;
    s["relief"] = json{{"style", style_name(surface.style)}, {"seed", surface.seed}};
    if (surface.sea_level_m) s["sea_level"] = scalar(*surface.sea_level_m, "m");
    if (!surface.elevation.source.empty()) s["elevation"] = raster(surface.elevation, true);
    if (!surface.imagery.source.empty()) s["imagery"] = raster(surface.imagery, false);
    if (!surface.coastline.empty()) s["coastline"] = json{{"source", portable_source(surface.coastline)}};
    if (!surface.lake_mask.source.empty() && surface.lake_level_m)
      s["lakes"] = json{{"mask", raster(surface.lake_mask, false)}, {"level", scalar(*surface.lake_level_m, "m")}};
    else if (!surface.lake_mask.source.empty() || surface.lake_level_m)
      throw Error("write_planet_file: a surface's lakes need both lake_mask and lake_level_m");
    doc["surface"] = s;
  }
  return doc.dump(2) + "\n";
}

void write_planet_file(const std::string& path, const Atmosphere& atmosphere, const PlanetSurface& surface) {
  const std::string text = format_planet(atmosphere, surface);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw Error("cannot write the planet file \"" + path + "\"");
  out << text;
  out.close();
  if (!out) throw Error("cannot write the planet file \"" + path + "\" (disk full?)");
}

}  // namespace atmos
