// The C++ side of physics/eclipse.glsl (the solar disc and the moons that
// eclipse it), in namespace atmos::physics on top of the parts it needs (see
// physics/shader_cpp.hpp).
#pragma once

#include "physics/shader_cpp.hpp"

namespace atmos::physics {

#include "physics/eclipse.glsl"

}  // namespace atmos::physics
