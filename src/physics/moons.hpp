// atmos — the moons of a frame for the shared functions (eclipse.glsl).
#pragma once

#include <vector>

#include "atmos/eclipse.hpp"
#include "physics/shader_cpp.hpp"

namespace atmos::physics {

// Validates the moons (validate_moons, against the atmosphere's top) and
// fills the Moons of the shared functions (their spheres in float).
Moons make_moons(const AtmosphereParams& params, const std::vector<Moon>& moons);

}  // namespace atmos::physics
