// The C++ side of physics/table_coordinates.glsl (the tables'
// parameterisation), in namespace atmos::physics on top of the parts it needs
// (see physics/shader_cpp.hpp).
#pragma once

#include "physics/ray_geometry_cpp.hpp"

namespace atmos::physics {

#include "physics/table_coordinates.glsl"

}  // namespace atmos::physics
