// The globe's vertex shader (src/planet/globe.cpp). Positions are relative to
// the camera: each tile's vertices are stored in float relative to the
// tile's origin, and the origin's offset from the camera is computed in
// double on the CPU for every draw (Cozzi & Ring 2011, ch. 5), so that no
// large coordinate reaches the GPU.
//
// Continuous level of detail (Strugar 2009): every vertex also stores the
// offset to where the parent tile's mesh passes (its own position on the
// parent's grid points, the midpoint of the parent's edge or diagonal
// otherwise), and moves there as its distance d from the camera goes from
// morph_range.x to morph_range.y: k = clamp((d - x) / (y - x), 0, 1). A tile
// fully morphed is its parent's surface, so a level hands over to the next
// without a visible change, and an edge shared with a coarser neighbour
// (always fully morphed there, tile_selection.hpp) matches it.

layout(location = 0) in vec3 local_position;  // m, from the tile's origin
layout(location = 1) in vec3 morph_offset;    // m, to the parent's surface
layout(location = 2) in vec3 normal;          // unit, this level's mesh
layout(location = 3) in vec3 parent_normal;   // unit, the parent's mesh
layout(location = 4) in vec3 albedo;          // linear reflectance

uniform vec3 origin_from_camera;  // m, the tile's origin minus the camera (planet axes)
uniform vec2 morph_range;         // m: where the morph starts and ends
uniform mat4 clip_from_offset;    // projection x view rotation x (engine units per metre)

out vec3 v_offset;  // m, from the camera to the vertex (planet axes)
out vec3 v_normal;
out vec3 v_albedo;

void main() {
  vec3 offset = origin_from_camera + local_position;
  float k = clamp((length(offset) - morph_range.x) / max(morph_range.y - morph_range.x, 1e-30), 0.0, 1.0);
  offset += k * morph_offset;
  v_offset = offset;
  v_normal = mix(normal, parent_normal, k);
  v_albedo = albedo;
  gl_Position = clip_from_offset * vec4(offset, 1.0);
}
