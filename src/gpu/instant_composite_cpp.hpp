// The C++ side of gpu/instant_composite.glsl (the instant mode's
// aerial-perspective volume), in namespace atmos::physics on top of
// composite.glsl and the instant mode's physics, for the CPU twin.
#pragma once

#include "gpu/composite_cpp.hpp"
#include "physics/instant_atmosphere_cpp.hpp"

namespace atmos::physics {

#include "gpu/instant_composite.glsl"

}  // namespace atmos::physics
