// The C++ side of physics/ray_geometry.glsl (ray geometry in a spherical
// atmosphere), in namespace atmos::physics on top of the parts it needs (see
// physics/shader_cpp.hpp).
#pragma once

#include "physics/shader_cpp.hpp"

namespace atmos::physics {

#include "physics/ray_geometry.glsl"

}  // namespace atmos::physics
