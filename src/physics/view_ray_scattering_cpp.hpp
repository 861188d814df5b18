// The C++ side of physics/view_ray_scattering.glsl (the renderers' light along
// a view ray), in namespace atmos::physics on top of the parts it needs (see
// physics/shader_cpp.hpp).
#pragma once

#include "physics/ray_integration_cpp.hpp"

namespace atmos::physics {

#include "physics/view_ray_scattering.glsl"

}  // namespace atmos::physics
