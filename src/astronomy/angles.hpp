// Angles shared by the ephemeris and the star catalogue.
#pragma once

#include <cmath>
#include <numbers>

namespace atmos::astronomy {

inline constexpr double kDegree = std::numbers::pi / 180.0;  // rad
inline constexpr double kArcsecond = 1.0 / 3600.0;           // degrees

// x reduced to [0, 360).
inline double wrap_360(double x) {
  const double r = std::fmod(x, 360.0);
  return r < 0.0 ? r + 360.0 : r;
}

}  // namespace atmos::astronomy
