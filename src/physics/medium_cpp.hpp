// The C++ side of physics/medium.glsl (the medium, its phase functions and the
// ground), in namespace atmos::physics on top of the parts it needs (see
// physics/shader_cpp.hpp).
#pragma once

#include "physics/ray_geometry_cpp.hpp"

namespace atmos::physics {

#include "physics/medium.glsl"

}  // namespace atmos::physics
