#include "state.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

#include "atmos/planet_file.hpp"
#include "atmos/planet_parameters.hpp"

namespace atmos_view {

namespace {

using nlohmann::json;

}  // namespace

atmos::Atmosphere make_atmosphere(const PlanetParams& p) {
  // The planet's values against their ranges (atmos/planet_parameters.hpp),
  // named by the panel's labels.
  const auto check = [](const char* name, double value_si, const std::string& prefix = "") {
    atmos::check_planet_parameter(name, value_si, prefix + atmos::planet_parameter(name).label);
  };
  if (p.wavelengths != 0) check("wavelengths", double(p.wavelengths));
  if (p.orders < 1 || p.orders > 100) throw atmos::Error("orders must be in [1, 100], got " + std::to_string(p.orders));
  check("density_scale", p.density_scale);
  if (p.table_sizes != "default" && p.table_sizes != "small")
    throw atmos::Error("table sizes must be default or small, got \"" + p.table_sizes + "\"");
  atmos::Atmosphere a = atmos::load_atmosphere(p.planet);
  if (p.wavelengths != 0) a.wavelengths_nm = atmos::spectral_wavelengths(p.wavelengths);
  if (p.density_scale != 1.0) atmos::scale_density(a, p.density_scale);
  if (!p.solar.empty()) atmos::set_solar_spectrum(a, p.solar);
  const double thickness = p.thickness_m.value_or(a.top_radius_m - a.bottom_radius_m);
  if (p.bottom_radius_m) {
    check("bottom_radius", *p.bottom_radius_m);
    a.bottom_radius_m = *p.bottom_radius_m;
  }
  if (p.thickness_m) check("atmosphere_thickness", *p.thickness_m);
  a.top_radius_m = a.bottom_radius_m + thickness;
  if (p.ground_albedo) {
    check("ground_albedo", *p.ground_albedo);
    a.ground_albedo = atmos::Spectrum::constant(*p.ground_albedo);
  }
  if (p.constituents.size() > a.constituents.size())
    throw atmos::Error("the planet has " + std::to_string(a.constituents.size()) + " constituents, " +
                       std::to_string(p.constituents.size()) + " edited");
  for (size_t i = 0; i < p.constituents.size(); ++i) {
    const ConstituentEdit& e = p.constituents[i];
    atmos::Constituent& c = a.constituents[i];
    const std::string name = "constituent \"" + c.name + "\": ";
    if (e.scattering_scale) {
      check("constituents[].scattering_scale", *e.scattering_scale, name);
      c.scattering = c.scattering.scaled(*e.scattering_scale);
    }
    if (e.absorption_scale) {
      check("constituents[].absorption_scale", *e.absorption_scale, name);
      c.absorption = c.absorption.scaled(*e.absorption_scale);
    }
    if (e.scale_height_m) {
      if (c.density.kind != atmos::DensityProfile::Kind::exponential)
        throw atmos::Error(name + "its density profile is not exponential: it has no scale height");
      check("constituents[].density.scale_height", *e.scale_height_m, name);
      c.density.scale_height_m = *e.scale_height_m;
    }
    if (e.phase_g) {
      if (c.phase.kind == atmos::PhaseFunction::Kind::rayleigh)
        throw atmos::Error(name + "a Rayleigh phase function has no asymmetry parameter");
      check("constituents[].phase_function.g", *e.phase_g, name);
      c.phase.g = atmos::Spectrum::constant(*e.phase_g);
    }
  }
  a.validate();
  return a;
}

void save_planet(const PlanetParams& params, const std::string& path) {
  atmos::write_planet_file(path, make_atmosphere(params), atmos::load_surface(params.planet));
}

atmos::PrecomputeOptions make_precompute_options(const PlanetParams& p, bool ground_albedo_response) {
  atmos::PrecomputeOptions o;
  o.scattering_orders = p.orders;
  // The CLI's --tables small (apps/atmos/options.cpp).
  if (p.table_sizes == "small") o.sizes = atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8};
  o.ground_albedo_response = ground_albedo_response;
  return o;
}

// ---------------------------------------------------------------------------
// Recorded flights

namespace {

json vec(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }

struct Reader {
  std::string origin;

  [[noreturn]] void fail(const std::string& what) const { throw atmos::Error(origin + ": " + what); }

  const json& field(const json& object, const char* name, const std::string& where) const {
    if (!object.is_object() || !object.contains(name)) fail(where + " has no \"" + name + "\"");
    return object.at(name);
  }
  double real(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(where + "." + name + " must be a finite number");
    return v.get<double>();
  }
  int integer(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_number_integer()) fail(where + "." + name + " must be an integer");
    return v.get<int>();
  }
  bool boolean(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_boolean()) fail(where + "." + name + " must be true or false");
    return v.get<bool>();
  }
  std::string text(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_string()) fail(where + "." + name + " must be a string");
    return v.get<std::string>();
  }
  glm::dvec3 vector(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_array() || v.size() != 3) fail(where + "." + name + " must be an array of 3 numbers");
    glm::dvec3 out;
    for (int i = 0; i < 3; ++i) {
      if (!v[size_t(i)].is_number() || !std::isfinite(v[size_t(i)].get<double>()))
        fail(where + "." + name + " must be an array of 3 finite numbers");
      out[i] = v[size_t(i)].get<double>();
    }
    return out;
  }
  std::optional<double> optional_real(const json& object, const char* name, const std::string& where) const {
    if (!object.contains(name) || object.at(name).is_null()) return std::nullopt;
    return real(object, name, where);
  }
};

json planet_json(const PlanetParams& p) {
  json j = {{"planet", p.planet},       {"wavelengths", p.wavelengths}, {"orders", p.orders},
            {"density_scale", p.density_scale}, {"solar", p.solar}, {"table_sizes", p.table_sizes}};
  j["bottom_radius_m"] = p.bottom_radius_m ? json(*p.bottom_radius_m) : json(nullptr);
  j["thickness_m"] = p.thickness_m ? json(*p.thickness_m) : json(nullptr);
  j["ground_albedo"] = p.ground_albedo ? json(*p.ground_albedo) : json(nullptr);
  const auto optional = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  json constituents = json::array();
  for (const ConstituentEdit& e : p.constituents)
    constituents.push_back({{"scattering_scale", optional(e.scattering_scale)},
                            {"absorption_scale", optional(e.absorption_scale)},
                            {"scale_height_m", optional(e.scale_height_m)},
                            {"phase_g", optional(e.phase_g)}});
  j["constituents"] = constituents;
  return j;
}

json look_json(const LookSettings& l) {
  return {{"exposure_ev", l.exposure_ev},
          {"auto_exposure", l.auto_exposure},
          {"compensation_ev", l.compensation_ev},
          {"tone_mapping", atmos::tone_mapping_name(l.tone_mapping)},
          {"bloom", l.bloom},
          {"stars", l.stars},
          {"moon", l.moon},
          {"moon_separation_deg", l.moon_separation_deg},
          {"fov_deg", l.fov_deg}};
}

}  // namespace

void write_flight(const FlightRecord& record, const std::string& path) {
  json frames = json::array();
  for (const FrameRecord& f : record.frames) {
    frames.push_back({{"time_s", f.time_s},
                      {"position_m", vec(f.pose.position)},
                      {"forward", vec(f.pose.forward)},
                      {"up", vec(f.pose.up)},
                      {"sun", vec(f.sun)},
                      {"look", look_json(f.look)},
                      {"planet", planet_json(f.planet)},
                      {"frame_ms", f.frame_ms}});
    if (f.moon_of_date_m) frames.back()["moon_of_date_m"] = vec(*f.moon_of_date_m);
  }
  const json j = {{"format", "atmos-flight"},
                  {"version", 1},
                  {"surface", record.globe ? "globe" : "sphere"},
                  {"planet_albedo", record.planet_albedo},
                  {"width", record.width},
                  {"height", record.height},
                  {"frames", frames}};
  std::ofstream out(path);
  out << j.dump(1) << '\n';
  out.close();
  if (!out) throw atmos::Error("cannot write the flight record " + path);
}

FlightRecord read_flight(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw atmos::Error("cannot read the flight record " + path);
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    throw atmos::Error(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  const Reader r{path};
  if (r.text(j, "format", "the record") != "atmos-flight") r.fail("format must be \"atmos-flight\"");
  if (r.integer(j, "version", "the record") != 1) r.fail("version must be 1");
  FlightRecord record;
  const std::string surface = r.text(j, "surface", "the record");
  if (surface != "globe" && surface != "sphere") r.fail("surface must be globe or sphere, got \"" + surface + "\"");
  record.globe = surface == "globe";
  record.planet_albedo = r.boolean(j, "planet_albedo", "the record");
  record.width = r.integer(j, "width", "the record");
  record.height = r.integer(j, "height", "the record");
  if (record.width < 1 || record.height < 1 || record.width > 16384 || record.height > 16384)
    r.fail("width and height must be in [1, 16384]");
  const json& frames = r.field(j, "frames", "the record");
  if (!frames.is_array() || frames.empty()) r.fail("frames must be a non-empty array");
  for (size_t i = 0; i < frames.size(); ++i) {
    const std::string where = "frame " + std::to_string(i);
    const json& f = frames[i];
    FrameRecord out;
    out.time_s = r.real(f, "time_s", where);
    out.pose.position = r.vector(f, "position_m", where);
    out.pose.forward = r.vector(f, "forward", where);
    out.pose.up = r.vector(f, "up", where);
    out.sun = r.vector(f, "sun", where);
    if (f.contains("moon_of_date_m")) out.moon_of_date_m = r.vector(f, "moon_of_date_m", where);
    const json& look = r.field(f, "look", where);
    const std::string lw = where + ".look";
    out.look.exposure_ev = r.real(look, "exposure_ev", lw);
    out.look.auto_exposure = r.boolean(look, "auto_exposure", lw);
    out.look.compensation_ev = r.real(look, "compensation_ev", lw);
    try {
      out.look.tone_mapping = atmos::parse_tone_mapping(r.text(look, "tone_mapping", lw));
    } catch (const atmos::Error& e) {
      r.fail(lw + ".tone_mapping: " + e.what());
    }
    out.look.bloom = r.real(look, "bloom", lw);
    out.look.stars = r.boolean(look, "stars", lw);
    out.look.moon = r.boolean(look, "moon", lw);
    out.look.moon_separation_deg = r.real(look, "moon_separation_deg", lw);
    out.look.fov_deg = r.real(look, "fov_deg", lw);
    if (!(out.look.fov_deg > 1.0 && out.look.fov_deg < 150.0)) r.fail(lw + ".fov_deg must be in (1, 150)");
    const json& planet = r.field(f, "planet", where);
    const std::string pw = where + ".planet";
    out.planet.planet = r.text(planet, "planet", pw);
    out.planet.wavelengths = r.integer(planet, "wavelengths", pw);
    out.planet.orders = r.integer(planet, "orders", pw);
    out.planet.density_scale = r.real(planet, "density_scale", pw);
    out.planet.solar = r.text(planet, "solar", pw);
    out.planet.table_sizes = r.text(planet, "table_sizes", pw);
    out.planet.bottom_radius_m = r.optional_real(planet, "bottom_radius_m", pw);
    out.planet.thickness_m = r.optional_real(planet, "thickness_m", pw);
    out.planet.ground_albedo = r.optional_real(planet, "ground_albedo", pw);
    if (planet.contains("constituents")) {
      const json& list = planet.at("constituents");
      if (!list.is_array()) r.fail(pw + ".constituents must be an array");
      for (size_t k = 0; k < list.size(); ++k) {
        const std::string cw = pw + ".constituents[" + std::to_string(k) + "]";
        if (!list[k].is_object()) r.fail(cw + " must be an object");
        ConstituentEdit e;
        e.scattering_scale = r.optional_real(list[k], "scattering_scale", cw);
        e.absorption_scale = r.optional_real(list[k], "absorption_scale", cw);
        e.scale_height_m = r.optional_real(list[k], "scale_height_m", cw);
        e.phase_g = r.optional_real(list[k], "phase_g", cw);
        out.planet.constituents.push_back(e);
      }
    }
    record.frames.push_back(out);
  }
  return record;
}

}  // namespace atmos_view
