// The C++ side of physics/instant_atmosphere.glsl (the instant approximate
// mode), in namespace atmos::physics on top of the parts it needs (see
// physics/shader_cpp.hpp).
#pragma once

#include "physics/sky_view_table_cpp.hpp"

namespace atmos::physics {

#include "physics/instant_atmosphere.glsl"

}  // namespace atmos::physics
