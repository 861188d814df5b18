// The C++ side of physics/stars.glsl (the procedural star field), in namespace
// atmos::physics on top of the parts it needs (see physics/shader_cpp.hpp).
#pragma once

#include "physics/shader_cpp.hpp"

namespace atmos::physics {

#include "physics/stars.glsl"

}  // namespace atmos::physics
