// The C++ side of physics/aerial_perspective.glsl (the light between a camera
// and a point), in namespace atmos::physics on top of the parts it needs (see
// physics/shader_cpp.hpp).
#pragma once

#include "physics/view_ray_scattering_cpp.hpp"

namespace atmos::physics {

#include "physics/aerial_perspective.glsl"

}  // namespace atmos::physics
