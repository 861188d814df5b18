// The C++ side of the camera model: compiles gpu/camera.glsl on top of the
// shared-physics subset (physics/shader_cpp.hpp), in namespace atmos::physics,
// so that the CPU renderer traces exactly the rays of the shader.
#pragma once

#include "physics/shader_cpp.hpp"

namespace atmos::physics {

#include "gpu/camera.glsl"

}  // namespace atmos::physics
