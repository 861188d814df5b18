// The C++ side of the engine plugin's per-pixel work: compiles
// gpu/pixel_ray.glsl and gpu/composite.glsl on top of the shared-physics subset
// (physics/shader_cpp.hpp), in namespace atmos::physics, so that the tests
// can evaluate exactly what the pass's shader evaluates.
#pragma once

#include "physics/shader_cpp.hpp"

namespace atmos::physics {

#include "gpu/pixel_ray.glsl"
#include "gpu/composite.glsl"

}  // namespace atmos::physics
