#include "world.hpp"

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <cmath>

namespace engine {

namespace {

// The world axes at the patch centre.
constexpr glm::dvec3 kEast(1.0, 0.0, 0.0);
constexpr glm::dvec3 kUp(0.0, 1.0, 0.0);
constexpr glm::dvec3 kNorth(0.0, 0.0, -1.0);

}  // namespace

glm::dvec3 LocalFrame::direction(double azimuth_deg, double elevation_deg) const {
  const double az = glm::radians(azimuth_deg), el = glm::radians(elevation_deg);
  return std::cos(el) * (std::sin(az) * east + std::cos(az) * north) + std::sin(el) * up;
}

World::World(double planet_radius_m)
    : planet_radius_(planet_radius_m * kUnitsPerMetre),
      planet_centre_(0.5 * kPatchSizeKm * kUnitsPerKm, -planet_radius_, -0.5 * kPatchSizeKm * kUnitsPerKm) {}

glm::dvec3 World::surface_point(glm::dvec2 patch_km, double height_km) const {
  const glm::dvec3 tangent_point = planet_radius_ * kUp + kUnitsPerKm * (patch_km.x * kEast + patch_km.y * kNorth);
  return planet_centre_ + (planet_radius_ + height_km * kUnitsPerKm) * glm::normalize(tangent_point);
}

LocalFrame World::local_frame(glm::dvec2 patch_km) const {
  LocalFrame f;
  f.up = glm::normalize(surface_point(patch_km, 0.0) - planet_centre_);
  f.east = glm::normalize(kEast - glm::dot(kEast, f.up) * f.up);
  f.north = glm::cross(f.up, f.east);
  return f;
}

}  // namespace engine
