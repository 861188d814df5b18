// The C++ side of physics/ray_integration.glsl (integrals along a ray and
// single scattering), in namespace atmos::physics on top of the parts it needs
// (see physics/shader_cpp.hpp).
#pragma once

#include "physics/eclipse_cpp.hpp"
#include "physics/table_lookups_cpp.hpp"

namespace atmos::physics {

#include "physics/ray_integration.glsl"

}  // namespace atmos::physics
