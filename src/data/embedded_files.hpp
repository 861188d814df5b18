// Files compiled into the library by cmake/embed.cmake: the GLSL sources of
// the physics and the renderer, and the planet presets.
#pragma once

#include <string>

namespace atmos::data {

struct EmbeddedFile {
  const char* path;  // relative to the repository root, e.g. "src/physics/functions.glsl"
  const char* text;
};

extern const EmbeddedFile embedded_files[];
extern const int embedded_file_count;

// The text of an embedded file, or nullptr.
const char* embedded_file(const std::string& path);

// The JSON text of a planet preset ("earth" -> data/planets/earth.json), or nullptr.
const char* embedded_planet(const std::string& name);

}  // namespace atmos::data
