// atmos — planet files: the JSON format of docs/planet-format.md and the
// built-in presets.
#pragma once

#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"

namespace atmos {

// Built-in planets (data/planets/<name>.json, compiled in): earth, mars (a
// dusty Mars from measurements), mars-thesis (the Mars of Collienne 2013, §5), titan, venus.
std::vector<std::string> preset_names();

// `name_or_path` is a preset name or the path of a planet JSON file.
Atmosphere load_atmosphere(const std::string& name_or_path);

// Parses planet JSON text; `origin` names the source in error messages.
Atmosphere parse_atmosphere(const std::string& json_text, const std::string& origin);
}  // namespace atmos
