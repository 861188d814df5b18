// The C++ side of physics/stars.glsl (the procedural star field), in namespace
// atmos::physics on top of the parts it needs (see physics/shader_cpp.hpp).
#pragma once

#include "physics/shader_cpp.hpp"

namespace atmos::physics {

// The C++ side of a star catalogue (stars.glsl; the shaders read the same
// from their buffers and uniforms): whether it is drawn, the rotation from
// the world's axes to its frame, and its bins (gpu/star_catalogue_bins.hpp
// builds them), which the view does not own.
struct StarCatalogueView {
  bool enabled = false;
  mat3 from_world = mat3(1.0f);
  const uint* cell_first = nullptr;  // STAR_CATALOGUE_CELLS² x 6 + 1 entries
  const vec4* records = nullptr;     // two per entry of a cell
};
#define STAR_CATALOGUE_MEMBER StarCatalogueView catalogue{};

#include "physics/stars.glsl"

}  // namespace atmos::physics
