// The globe's tile meshes (CPU, double precision): a grid of
// (kTileQuads + 1)^2 vertices over a cube-sphere tile with the relief's
// heights, each vertex with the offset that morphs it onto its parent's
// mesh, and a skirt hanging from the four edges.
#pragma once

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "planet/cube_sphere.hpp"
#include "planet/surface.hpp"
#include "planet/tile_selection.hpp"

namespace atmos::planet {

inline constexpr int kTileQuads = 16;              // quads per tile edge
inline constexpr int kTileSide = kTileQuads + 1;   // vertices per tile edge
inline constexpr int kGridVertices = kTileSide * kTileSide;
// Skirts along the four edges and along the two midlines (s = 1/2, t = 1/2),
// which bound a quadrant drawn without its neighbour (tile_selection.hpp).
inline constexpr int kSkirtVertices = 6 * kTileSide;

// One vertex as the vertex shader reads it (globe.vert.glsl).
struct TileVertex {
  float position[3];       // m, from the tile's origin
  float morph_offset[3];   // m, from the position to the parent's surface
  float normal[3];         // unit
  float parent_normal[3];  // unit (not normalised after interpolation)
  float albedo[3];         // linear reflectance
};

struct TileMesh {
  glm::dvec3 origin{0.0};      // planet-centred m: the tile's centre on the datum
  std::vector<TileVertex> vertices;  // kGridVertices grid (row-major, s fastest), then kSkirtVertices (indices())
  double min_height_m = 0.0;   // over the grid's vertices, m above the datum
  double max_height_m = 0.0;
};

class MeshBuilder {
 public:
  MeshBuilder(const Surface& surface, double radius_m);
  MeshBuilder(const MeshBuilder&) = delete;
  MeshBuilder& operator=(const MeshBuilder&) = delete;

  // The mesh of one tile. Vertices shared by two tiles (their common edge,
  // at the same level, or the even vertices of a finer one) get bit-identical
  // planet-centred positions: a vertex's direction comes from its integer
  // grid coordinates on the face (tile_direction), its height from the relief.
  //
  // Morph targets (Strugar 2009): a vertex of the parent's grid (even
  // indices) stays; a vertex on a parent's edge (one odd index) goes to the
  // midpoint of that edge; a vertex inside a parent's quad (both odd) to
  // the midpoint of the quad's diagonal from (i-1, j-1) to (i+1, j+1). Every
  // quad is split along that same diagonal at every level, so the fully
  // morphed triangles of a tile lie in the planes of its parent's triangles:
  // the morphed tile is the parent's surface.
  TileMesh build(const TileKey& key) const;

  // Triangles of every tile: four equal runs, one per quadrant (bit 0: the
  // upper half in s, bit 1: in t), each the quadrant's grid (two triangles
  // per quad split from (i, j) to (i + 1, j + 1)) and skirts along its four
  // sides (two on the tile's edges, two on its midlines); then the whole
  // tile's run, its grid and skirts along its four edges. Skirt vertex k of
  // line e (0: s = 0, 1: s = 1, 2: t = 0, 3: t = 1, 4: s = 1/2, 5: t = 1/2)
  // is vertex kGridVertices + e * kTileSide + k.
  const std::vector<std::uint32_t>& indices() const { return indices_; }
  std::size_t quadrant_index_count() const { return quadrant_run_; }
  std::size_t tile_index_offset() const { return 4 * quadrant_run_; }  // the whole tile's run
  std::size_t tile_index_count() const { return indices_.size() - 4 * quadrant_run_; }
  std::size_t vertex_count() const { return std::size_t(kGridVertices + kSkirtVertices); }

  // The relief's bounds and per-spacing error for the selection. The error
  // of a mesh of spacing s is measured, not bounded: the largest deviation
  // of the relief from a mesh cell's two triangles over a fixed sample of
  // cells spread over the planet, times a margin (measure_level_errors).
  // The rigorous bound of the relief (Relief::error_below_spacing_m) sums
  // each octave's worst case and exceeds the deviations it bounds 30 to
  // 1000 times, which would refine the mesh as many times too far.
  const ReliefBounds& bounds() const { return bounds_; }
  LodSettings lod_settings(double max_screen_error_px) const;

  // The height of the drawn surface above the datum, m (Surface: the
  // ground, or the sea level where the ground lies below it; until water is
  // drawn the sea is a Lambertian surface of the ocean's albedo).
  double surface_height_m(const glm::dvec3& direction) const { return surface_.height_m(direction); }
  double min_surface_height_m() const { return bounds_.min_height_m; }
  double max_surface_height_m() const { return bounds_.max_height_m; }

  // Mean vertex spacing of a level, m (at the datum).
  double spacing_m(int level) const;
  // How far the skirts of a level's tiles hang below their edges, m.
  double skirt_depth_m(int level) const;

 private:
  // The albedo of the grid's vertices of a tile (row-major): the
  // surface's, averaged over each vertex's cell on coarse levels.
  std::vector<glm::vec3> vertex_albedos(const TileKey& key) const;

  // The measured error of each level's mesh at its mean spacing, m,
  // non-increasing with the level.
  void measure_level_errors();
  double measured_error_m(double spacing) const;

  const Surface& surface_;
  double radius_m_;
  std::vector<double> level_errors_m_;
  ReliefBounds bounds_;
  std::vector<std::uint32_t> indices_;
  std::size_t quadrant_run_ = 0;
};

}  // namespace atmos::planet
