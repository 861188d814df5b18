#include "data/embedded_files.hpp"

namespace atmos::data {

const char* embedded_file(const std::string& path) {
  for (int i = 0; i < embedded_file_count; ++i)
    if (path == embedded_files[i].path) return embedded_files[i].text;
  return nullptr;
}

const char* embedded_planet(const std::string& name) {
  if (name.empty() || name.find_first_of("/\\.") != std::string::npos) return nullptr;
  return embedded_file("data/planets/" + name + ".json");
}

}  // namespace atmos::data
