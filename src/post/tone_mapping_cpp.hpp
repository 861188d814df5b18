// The C++ side of the post-processing formulas: compiles post/tone_mapping.glsl
// (the subset of GLSL 4.50 and C++ described in src/physics/definitions.glsl)
// on top of glm, in namespace atmos::post. The compute shaders of PostProcess
// embed the same file (post/post_process.cpp), write_png calls it for its
// 1 - exp tone map.
#pragma once

#include <glm/glm.hpp>

#include "physics/glsl_subset_cpp.hpp"

namespace atmos::post {

using namespace glm;

#include "post/tone_mapping.glsl"

}  // namespace atmos::post
