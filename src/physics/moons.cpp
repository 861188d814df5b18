// atmos — moons: from the public description (include/atmos/eclipse.hpp) to
// the Moons of the shared functions (src/physics/eclipse.glsl).
#include "physics/moons.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "atmos/atmosphere.hpp"
#include "physics/checks.hpp"

namespace atmos {

Moon moon_in_sky(const glm::dvec3& observer, const glm::dvec3& direction, double angular_radius_rad,
                 double distance_m) {
  if (!is_finite(observer)) throw Error("moon: the observer's position is not finite");
  if (!is_finite(direction) || std::abs(glm::length(direction) - 1.0) > 1e-6)
    throw Error("moon: the direction must be a finite unit vector");
  if (!(angular_radius_rad > 0.0) || angular_radius_rad > 10.0 * M_PI / 180.0)
    throw Error("moon: the angular radius must be in (0, 10] degrees, got " +
                std::to_string(angular_radius_rad * 180.0 / M_PI));
  if (!(distance_m > 0.0) || !std::isfinite(distance_m))
    throw Error("moon: the distance must be finite and > 0");
  return Moon{observer + direction * distance_m, distance_m * std::sin(angular_radius_rad)};
}

void validate_moons(const std::vector<Moon>& moons, double top_radius_m) {
  if (moons.size() > size_t(kMaxMoons))
    throw Error("at most " + std::to_string(kMaxMoons) + " moons are supported, got " + std::to_string(moons.size()));
  for (size_t i = 0; i < moons.size(); ++i) {
    const std::string which = "moon " + std::to_string(i + 1) + ": ";
    if (!is_finite(moons[i].centre_m)) throw Error(which + "its centre is not finite");
    if (!(moons[i].radius_m > 0.0) || !std::isfinite(moons[i].radius_m))
      throw Error(which + "its radius must be finite and > 0");
    // Float positions in the shaders: ~1e-7 relative; 1e12 m keeps 0.1 km.
    if (glm::length(moons[i].centre_m) > 1e12) throw Error(which + "farther than 1e12 m from the planet");
    if (glm::length(moons[i].centre_m) - moons[i].radius_m <= top_radius_m)
      throw Error(which + "it reaches into the atmosphere (a moon must be a sphere outside it)");
  }
}

namespace physics {

Moons make_moons(const AtmosphereParams& params, const std::vector<Moon>& moons) {
  validate_moons(moons, double(params.top_radius));
  Moons result = no_moons();
  result.count = int(moons.size());
  for (size_t i = 0; i < moons.size(); ++i)
    result.sphere[i] = vec4(vec3(moons[i].centre_m), float(moons[i].radius_m));
  return result;
}

bool moons_may_eclipse(const AtmosphereParams& params, const Moons& moons, const vec3& sun) {
  const double reach = double(params.top_radius) + 1000e3;  // the farthest point that matters
  const glm::dvec3 s = glm::normalize(glm::dvec3(sun));
  const double sun_radius = params.sun_angular_radius;
  for (int i = 0; i < moons.count; ++i) {
    const glm::dvec3 centre(glm::vec3(moons.sphere[i]));
    const double distance = glm::length(centre), radius = moons.sphere[i].w;
    if (distance <= reach + radius) return true;  // close enough to be anywhere in the sky of some point
    // Seen from a point within `reach` of the planet's centre, the moon's
    // centre moves by at most asin(reach / distance) from its direction
    // seen from the centre, and looks at most asin(radius / (distance -
    // reach)) wide.
    const double angle = std::atan2(glm::length(glm::cross(centre, s)), glm::dot(centre, s));
    const double parallax = std::asin(reach / distance);
    const double moon_radius = std::asin(std::min(radius / (distance - reach), 1.0));
    if (angle - parallax < sun_radius + moon_radius + 1e-4) return true;
  }
  return false;
}

}  // namespace physics

bool moons_may_eclipse(const std::vector<Moon>& moons, const glm::dvec3& sun_direction, double top_radius_m,
                       double sun_angular_radius_rad) {
  const double length = glm::length(sun_direction);
  if (!(length > 0.0) || !std::isfinite(length)) throw Error("moons_may_eclipse: zero or non-finite sun direction");
  // The two fields physics::moons_may_eclipse and make_moons read.
  physics::AtmosphereParams params{};
  params.top_radius = float(top_radius_m);
  params.sun_angular_radius = float(sun_angular_radius_rad);
  return physics::moons_may_eclipse(params, physics::make_moons(params, moons), glm::vec3(sun_direction / length));
}

}  // namespace atmos
