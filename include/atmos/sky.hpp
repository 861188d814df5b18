// atmos — CPU evaluation of a precomputed atmosphere.
//
// Runs the very functions the GPU shader runs (the GLSL of src/physics/),
// for scientists, tests and `atmos sample`. Positions are planet-centred, in
// metres; directions are unit vectors.
#pragma once

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <memory>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/tables.hpp"

namespace atmos {

class SkyModel {
 public:
  // Keeps references to both arguments: they must outlive the model.
  // Throws Error if the tables do not have exactly one wavelength triple.
  SkyModel(const Atmosphere& atmosphere, const Tables& tables);
  ~SkyModel();
  SkyModel(const SkyModel&) = delete;
  SkyModel& operator=(const SkyModel&) = delete;

  // Spectral radiance (W m^-2 sr^-1 nm^-1 at the three working wavelengths)
  // reaching `observer` from direction `view`: sky, or lit ground seen
  // through the aerial perspective, plus the sun disc if asked. With
  // `moons` (eclipse.hpp; throws atmos::Error as validate_moons does), the
  // eclipsed sky and ground, and the moons in front of the sun.
  glm::dvec3 radiance(const glm::dvec3& observer, const glm::dvec3& view, const glm::dvec3& sun,
                      bool include_sun_disc, const std::vector<Moon>& moons = {}) const;

  // Sun and sky irradiance (W m^-2 nm^-1) on a horizontal surface at `point`.
  void horizontal_irradiance(const glm::dvec3& point, const glm::dvec3& sun, glm::dvec3& sun_irradiance,
                             glm::dvec3& sky_irradiance) const;

  // Linear sRGB on the cd/m² (or lux, for irradiance) scale from spectral values.
  glm::dvec3 to_srgb(const glm::dvec3& spectral) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The planet-centred position of an observer `altitude_m` above the ground at
// the north pole, whose local frame is x = east, y = north, z = up.
glm::dvec3 observer_position(const Atmosphere& atmosphere, double altitude_m);

// Unit vector for an azimuth (degrees clockwise from north, i.e. towards
// east) and elevation (degrees above the horizontal) in that local frame.
glm::dvec3 direction_from_azimuth_elevation(double azimuth_deg, double elevation_deg);

}  // namespace atmos
