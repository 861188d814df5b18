// atmos — the moons of a frame for the shared functions (eclipse.glsl).
#pragma once

#include <vector>

#include "atmos/eclipse.hpp"
#include "physics/eclipse_cpp.hpp"

namespace atmos::physics {

// Validates the moons (validate_moons, against the atmosphere's top) and
// fills the Moons of the shared functions (their spheres in float).
Moons make_moons(const AtmosphereParams& params, const std::vector<Moon>& moons);

// Whether any of the moons can hide part of the sun (unit direction `sun`)
// from some point of the atmosphere or of the air that feeds its diffuse
// light (diffuse_light_visible_fraction: up to 512 km beyond it; a bound of
// 1000 km is used). A moon elsewhere in the sky is drawn but eclipses
// nothing, and the renderers then skip the eclipse's integration.
bool moons_may_eclipse(const AtmosphereParams& params, const Moons& moons, const vec3& sun);

}  // namespace atmos::physics
