#include "script.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "atmos/atmosphere.hpp"

namespace atmos_view {

const std::vector<std::string>& slider_names() {
  static const std::vector<std::string> names = {
      "sun_elevation", "sun_azimuth",   "time_of_day",   "exposure_ev", "compensation_ev", "bloom",
      "fov_deg",       "moon_separation_deg", "density_scale", "ground_albedo", "wavelengths",     "orders",
      "bottom_radius_km", "thickness_km", "interpupillary_m", "convergence_m"};
  return names;
}

bool is_planet_slider(const std::string& name) {
  return name == "density_scale" || name == "ground_albedo" || name == "wavelengths" || name == "orders" ||
         name == "bottom_radius_km" || name == "thickness_km";
}

Script Script::read(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw atmos::Error("cannot read the script " + path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw atmos::Error(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  if (!j.is_object() || !j.contains("events") || !j["events"].is_array())
    throw atmos::Error(path + ": expected an object with an \"events\" array");
  Script script;
  const auto& events = j["events"];
  for (size_t i = 0; i < events.size(); ++i) {
    const auto& e = events[i];
    const std::string where = path + ": event " + std::to_string(i) + ": ";
    if (!e.is_object() || !e.contains("frame") || !e["frame"].is_number_integer() || e["frame"].get<int>() < 0)
      throw atmos::Error(where + "\"frame\" must be an integer >= 0");
    ScriptEvent ev;
    ev.frame = e["frame"].get<int>();
    if (e.contains("frames")) {
      if (!e["frames"].is_number_integer() || e["frames"].get<int>() < 1 || e["frames"].get<int>() > 1000000)
        throw atmos::Error(where + "\"frames\" must be an integer in [1, 1000000]");
      ev.frames = e["frames"].get<int>();
    }
    const auto number = [&](const nlohmann::json& v, const std::string& name) {
      if (!v.is_number() || !std::isfinite(v.get<double>())) throw atmos::Error(where + name + " must be a finite number");
      return v.get<double>();
    };
    if (e.contains("key")) {
      ev.kind = ScriptEvent::Kind::key;
      ev.key = e["key"].is_string() ? e["key"].get<std::string>() : "";
      static const std::string keys = "WASDQE1234";
      if (ev.key.size() != 1 || keys.find(ev.key[0]) == std::string::npos)
        throw atmos::Error(where + "\"key\" must be one of W A S D Q E 1 2 3 4");
    } else if (e.contains("mouse")) {
      ev.kind = ScriptEvent::Kind::mouse;
      if (!e["mouse"].is_array() || e["mouse"].size() != 2) throw atmos::Error(where + "\"mouse\" must be [dx, dy]");
      ev.dx = number(e["mouse"][0], "mouse dx");
      ev.dy = number(e["mouse"][1], "mouse dy");
    } else if (e.contains("slider")) {
      ev.kind = ScriptEvent::Kind::slider;
      ev.slider = e["slider"].is_string() ? e["slider"].get<std::string>() : "";
      const auto& names = slider_names();
      if (std::find(names.begin(), names.end(), ev.slider) == names.end()) {
        std::string list;
        for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
        throw atmos::Error(where + "unknown slider \"" + ev.slider + "\" (expected " + list + ")");
      }
      if (!e.contains("from") || !e.contains("to")) throw atmos::Error(where + "a slider needs \"from\" and \"to\"");
      ev.from = number(e["from"], "from");
      ev.to = number(e["to"], "to");
    } else if (e.contains("planet")) {
      ev.kind = ScriptEvent::Kind::planet;
      if (!e["planet"].is_string() || e["planet"].get<std::string>().empty())
        throw atmos::Error(where + "\"planet\" must be a preset name or a file");
      ev.planet = e["planet"].get<std::string>();
    } else if (e.contains("save")) {
      ev.kind = ScriptEvent::Kind::save;
      if (!e["save"].is_string() || e["save"].get<std::string>().empty())
        throw atmos::Error(where + "\"save\" must be the path of a planet file to write");
      ev.save = e["save"].get<std::string>();
    } else {
      throw atmos::Error(where + "expected one of \"key\", \"mouse\", \"slider\", \"planet\", \"save\"");
    }
    script.events.push_back(ev);
  }
  return script;
}

FlightInput Script::input(int frame) const {
  FlightInput in;
  for (const ScriptEvent& e : events) {
    if (frame < e.frame || frame >= e.frame + e.frames) continue;
    if (e.kind == ScriptEvent::Kind::mouse) {
      in.look_dx += e.dx;
      in.look_dy += e.dy;
    } else if (e.kind == ScriptEvent::Kind::key) {
      const char k = e.key[0];
      if (k >= '1' && k <= '4') {
        if (frame == e.frame) in.jump = k - '0';
      } else {
        in.forward |= k == 'W';
        in.back |= k == 'S';
        in.left |= k == 'A';
        in.right |= k == 'D';
        in.down |= k == 'Q';
        in.up |= k == 'E';
      }
    }
  }
  return in;
}

bool Script::dragging(int frame) const {
  for (const ScriptEvent& e : events)
    if (e.kind == ScriptEvent::Kind::slider && frame >= e.frame && frame < e.frame + e.frames) return true;
  return false;
}

int Script::length() const {
  int n = 0;
  for (const ScriptEvent& e : events) n = std::max(n, e.frame + e.frames);
  return n;
}

}  // namespace atmos_view
