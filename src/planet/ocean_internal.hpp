// The sea's internal switches (src/planet/ocean.cpp), for tests: not part
// of the public API (include/atmos/ocean.hpp).
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <vector>

#include "planet/ocean_waves_cpp.hpp"

namespace atmos::planet {

// One sine wave of the sea's height: along the direction at `angle` (rad)
// from the upwind axis, wavenumber k (rad/m), amplitude (m), angular
// frequency omega (rad/s) and phase (rad).
struct OceanWave {
  double angle = 0.0, k = 0.0, amplitude = 0.0, omega = 0.0, phase = 0.0;
};

// The sea's waves for a wind of `wind_speed_m_s` whose slope variance along
// and across the wind stays within 80 % of `slope_variance` (Cox & Munk's),
// in increasing wavenumber (ocean.cpp, make_waves: the derivation).
std::vector<OceanWave> make_ocean_waves(double wind_speed_m_s, glm::dvec2 slope_variance);

// The wind's axes in the tangent plane at unit `nadir`: upwind at
// `wind_azimuth_deg` clockwise from north, crosswind = nadir × upwind.
void ocean_wind_axes(const glm::dvec3& nadir, double wind_azimuth_deg, glm::dvec3& upwind, glm::dvec3& crosswind);

// The waves' uniforms of a draw (ocean_waves.glsl's wave_count,
// wave_vector, wave_in_wind, wave_phase) into `field`, in double: the wave
// vectors on the wind's axes, and the phases k · camera + φ − ω t at
// `camera_m` (planet-centred, m) and `time_s`, reduced modulo 2π.
void set_ocean_wave_uniforms(const std::vector<OceanWave>& waves, const glm::dvec3& upwind,
                             const glm::dvec3& crosswind, const glm::dvec3& camera_m, double time_s,
                             OceanWaveField& field);

// Which terms of the sea's radiance every Ocean draws (a process-wide
// mask, all terms unless changed here), so that tests can compare each
// with its CPU twin.
enum OceanTerms : unsigned {
  kOceanGlint = 1u,       // the sun glint
  kOceanSky = 2u,         // the reflected sky
  kOceanBelow = 4u,       // the light leaving the water
  kOceanAllTerms = 7u,
  // Instead of the radiance: the sun's irradiance normal to it at the
  // point (moons' factor included), times the light scale.
  kOceanSunIrradiance = 8u,
  // The sky replaced by a uniform sky of radiance 1 (the reflected sky is
  // then the rough surface's reflectance, unscaled).
  kOceanUniformSky = 16u,
  // The sky's radiance and the irradiances from the pass's functions at
  // every pixel instead of the sea's light maps (ocean_light_maps.glsl),
  // to check the maps against them. Set when an Ocean is constructed, its
  // maps are filled at its first draw without it instead.
  kOceanDirectLight = 32u,
  // The sea-level sphere at every pixel: no displaced waves (their normals
  // as everywhere), to compare the mean radiance with and without them.
  kOceanUndisplaced = 64u,
};
void set_ocean_terms(unsigned mask);

}  // namespace atmos::planet
