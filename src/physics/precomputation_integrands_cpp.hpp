// The C++ side of physics/precomputation_integrands.glsl (what the
// precomputation tabulates), in namespace atmos::physics on top of the parts it
// needs (see physics/shader_cpp.hpp).
#pragma once

#include "physics/ray_integration_cpp.hpp"

namespace atmos::physics {

#include "physics/precomputation_integrands.glsl"

}  // namespace atmos::physics
