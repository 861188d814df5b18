// The C++ side of physics/radiance_to_camera.glsl (everything that reaches a
// camera), in namespace atmos::physics on top of the parts it needs (see
// physics/shader_cpp.hpp).
#pragma once

#include "physics/stars_cpp.hpp"
#include "physics/sky_view_table_cpp.hpp"

namespace atmos::physics {

#include "physics/radiance_to_camera.glsl"

}  // namespace atmos::physics
