// atmos view: scripted input — the keys, mouse drags, slider drags and
// planet changes of a session, by frame number, for tests and demos.
// docs/viewer.md, Scripts:
//   {"events": [
//     {"frame": 0,  "frames": 30, "key": "W"},                 // hold W for 30 frames
//     {"frame": 30, "frames": 10, "mouse": [4, -2]},          // drag the view 4, -2 px per frame
//     {"frame": 40, "key": "2"},                               // jump to 10 km
//     {"frame": 50, "frames": 20, "slider": "sun_elevation", "from": 30, "to": 5},
//     {"frame": 80, "planet": "mars"},
//     {"frame": 90, "save": "my-planet.json"}]}                // the panel's "save"
// A slider moves linearly from `from` (its first frame) to `to` (its last),
// as a hand drags it; a planet slider's new tables are requested at its
// last frame, as on the release of the mouse.
#pragma once

#include <string>
#include <vector>

#include "flight.hpp"

namespace atmos_view {

struct ScriptEvent {
  enum class Kind { key, mouse, slider, planet, save };
  Kind kind = Kind::key;
  int frame = 0;   // first frame
  int frames = 1;  // how many frames it lasts (>= 1)
  std::string key;  // W A S D Q E (held), 1-4 (jumps: at the first frame)
  double dx = 0.0, dy = 0.0;  // mouse, pixels per frame
  std::string slider;  // a name of slider_names()
  double from = 0.0, to = 0.0;
  std::string planet;  // a preset or a planet file
  std::string save;    // where the planet of the panel is saved
};

// The sliders a script can drag: the look and the sun (applied at once) and
// the planet's (new tables).
const std::vector<std::string>& slider_names();
bool is_planet_slider(const std::string& name);

struct Script {
  std::vector<ScriptEvent> events;

  // Throws atmos::Error naming the file and the first bad event.
  static Script read(const std::string& path);
  // The input of frame `frame`: held keys, mouse, jumps.
  FlightInput input(int frame) const;
  // Whether a slider is being dragged at `frame`.
  bool dragging(int frame) const;
  // The last frame any event touches, + 1.
  int length() const;
};

}  // namespace atmos_view
