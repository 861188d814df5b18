// The C++ side of physics/sky_view_table.glsl (the per-frame sky-view table),
// in namespace atmos::physics on top of the parts it needs (see
// physics/shader_cpp.hpp).
#pragma once

#include "physics/view_ray_scattering_cpp.hpp"

namespace atmos::physics {

#include "physics/sky_view_table.glsl"

}  // namespace atmos::physics
