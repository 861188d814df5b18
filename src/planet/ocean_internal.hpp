// The sea's internal switches (src/planet/ocean.cpp), for tests: not part
// of the public API (include/atmos/ocean.hpp).
#pragma once

namespace atmos::planet {

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
};
void set_ocean_terms(unsigned mask);

}  // namespace atmos::planet
