// The C++ side of physics/water.glsl (the air-water interface, the sun glint,
// the reflected sky and the light from below the surface), in namespace
// atmos::physics on top of the parts it needs (see physics/shader_cpp.hpp).
#pragma once

#include "physics/shader_cpp.hpp"

namespace atmos::physics {

#include "physics/water.glsl"

}  // namespace atmos::physics
