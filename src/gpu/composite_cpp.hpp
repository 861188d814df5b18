// The C++ side of the engine plugin's per-pixel work: compiles
// gpu/pixel_ray.glsl and gpu/composite.glsl on top of the physics they use
// (radiance_to_camera.glsl, aerial_perspective.glsl and the parts those
// need), in namespace atmos::physics, so that the tests can evaluate exactly
// what the pass's shader evaluates.
#pragma once

#include "physics/aerial_perspective_cpp.hpp"
#include "physics/radiance_to_camera_cpp.hpp"

namespace atmos::physics {

#include "gpu/pixel_ray.glsl"
#include "gpu/composite.glsl"

}  // namespace atmos::physics
