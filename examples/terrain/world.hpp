// The example engine's world frame — deliberately NOT atmos's own, to show
// that atmos::PlanetFrame maps any engine convention onto the planet:
//
//  - one engine unit is one kilometre (PlanetFrame::units_per_metre = 0.001);
//  - y is up at the centre of the terrain patch, x points east and z south
//    (right-handed, the usual "y-up" game convention), whereas atmos works in
//    metres with the planet's centre at the origin;
//  - the origin is the south-west corner of the patch at sea level, so the
//    planet's centre sits at (40, -R, -40) km, far from the origin.
//
// The terrain patch is an 80 km x 80 km square on the sphere, addressed by
// "patch coordinates" (east, north) in kilometres from its centre; a patch
// point maps onto the sphere along the direction of the corresponding point
// of the tangent plane (gnomonic projection: straight lines stay great
// circles, and the distortion over ±40 km is below 0.01 %).
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <atmos/plugin.hpp>

namespace engine {

// Engine units (kilometres) per metre, and per kilometre (the unit of patch
// coordinates and terrain heights, whatever the engine unit).
inline constexpr double kUnitsPerMetre = 0.001;
inline constexpr double kUnitsPerKm = 1000.0 * kUnitsPerMetre;

// An orthonormal frame on the planet: east, north and up (radial).
struct LocalFrame {
  glm::dvec3 east;
  glm::dvec3 north;
  glm::dvec3 up;

  // Unit vector for an azimuth (degrees from north towards east) and an
  // elevation (degrees above the horizontal), the convention of the atmos CLI.
  glm::dvec3 direction(double azimuth_deg, double elevation_deg) const;
};

class World {
 public:
  static constexpr double kPatchSizeKm = 80.0;

  explicit World(double planet_radius_m);

  double planet_radius() const { return planet_radius_; }  // engine units
  glm::dvec3 planet_centre() const { return planet_centre_; }

  // What the plugin needs to know about this frame.
  atmos::PlanetFrame planet_frame() const { return {planet_centre_, kUnitsPerMetre}; }

  // The patch's centre at sea level: the origin of the terrain mesh's
  // vertices (see terrain.hpp) and of the sun's shadow map.
  glm::dvec3 patch_centre() const { return planet_centre_ + glm::dvec3(0.0, planet_radius_, 0.0); }

  // The point `height_km` above sea level at patch coordinates (east, north).
  glm::dvec3 surface_point(glm::dvec2 patch_km, double height_km) const;

  // East, north and up at patch coordinates (up is radial, so it tilts by
  // up to 0.5° across the patch: objects stand perpendicular to the sphere).
  LocalFrame local_frame(glm::dvec2 patch_km) const;

 private:
  double planet_radius_;
  glm::dvec3 planet_centre_;
};

}  // namespace engine
