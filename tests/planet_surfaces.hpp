// Procedural planet surfaces for the globe's tests (atmos::PlanetSurface:
// a relief style, its seed and an optional sea level).
#pragma once

#include <cstdint>
#include <optional>

#include "atmos/planet_file.hpp"

namespace atmos_test {

inline atmos::PlanetSurface surface_of(atmos::SurfaceStyle style, std::uint64_t seed,
                                       std::optional<double> sea_level_m = std::nullopt) {
  atmos::PlanetSurface s;
  s.style = style;
  s.seed = seed;
  s.sea_level_m = sea_level_m;
  return s;
}

}  // namespace atmos_test
