// The C++ side of physics/table_lookups.glsl (reading the tables), in namespace
// atmos::physics on top of the parts it needs (see physics/shader_cpp.hpp).
#pragma once

#include "physics/medium_cpp.hpp"
#include "physics/table_coordinates_cpp.hpp"

namespace atmos::physics {

#include "physics/table_lookups.glsl"

}  // namespace atmos::physics
