// Which tiles of the cube-sphere quadtree to draw for a view: continuous
// distance-dependent level of detail (CDLOD, Strugar 2009) with frustum and
// horizon culling (Ring 2013).
//
// Ranges. A tile of level L >= 1 morphs its vertices towards its parent's
// grid as its camera distance d goes from morph_start = f r_L to
// morph_end = r_L (f = morph_start_fraction; k = clamp((d - f r_L) /
// ((1 - f) r_L), 0, 1)); beyond r_L it is its parent's surface. A node of
// level L - 1 is refined while the nearest point of its bounding volume is
// nearer than r_L; then each child nearer than r_L itself is visited, and the
// area of each other child is drawn as a quadrant of the node, at level
// L - 1 (Strugar 2009). So the geometry of level L - 1 is shown only at
// d >= f r_L, blended with level L's, and the screen-space error of a mesh
// of geometric error e at distance d, e K / d (K = viewport_height_px /
// (2 tan_half_fov_y) px per rad; Ulrich 2002), stays below tau if
//   r_L >= max(e_{L-1}, e_L / f) K / tau                        (1)
// In the morph zone the blended mesh is within (1 - k) e_L + k e_{L-1} of
// the surface at d = (f + k (1 - f)) r_L; the ratio of the two, linear in
// k, is extreme at k = 0 (e_L / (f r_L)) and k = 1 (e_{L-1} / r_L). Level
// L's own tiles beyond r_{L+1} are bounded by (1) of level L + 1.
//
// Seamless edges. Let an area A drawn at level L meet an area B drawn at
// level L - 1 along an edge. B is a quadrant of a refined node whose child
// there was not nearer than r_L, or a node that was not refined: every point
// of B, the shared edge included, is at least r_L away, and A's edge
// vertices are fully morphed to the coarser grid, which is B's. A belongs to
// a tile T of level L that was visited because it was nearer than r_L, so
// A's vertices are nearer than r_L + D_L, D the largest bounding-volume
// diameter of a level: B's vertices there are not morphing if
//   f r_{L-1} >= r_L + D_L.                                     (2)
// (2) also keeps neighbours within one level: an area of level M <= L - 2
// next to A would be nearer than r_L + D_L <= f r_{L-1} < r_{M+1}, so its
// node would have been refined and that child visited. level_ranges_m()
// takes the smallest ranges that satisfy (1) and (2), from the finest level
// up:
//   r_L = max(max(e_{L-1}, e_L / f) K / tau, (r_{L+1} + D_{L+1}) / f).
// Where (1) decides, ranges halve per level with the error; where (2)
// decides, r_L tends to c D_L with c = 1 / (2 f - 1) (2.5 for f = 0.7),
// since D halves per level. D_L is the diameter of a level-L tile's
// footprint at the planet's highest radius combined with a relief of at
// most max_tile_relief_ratio times that footprint (a tile with more relief
// than this can let its coarser neighbour start morphing: Selection counts
// such tiles, and skirts hide the gap).
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <functional>
#include <vector>

#include "planet/cube_sphere.hpp"

namespace atmos::planet {

struct LodCamera {
  glm::dvec3 position{0.0};         // planet-centred, m
  glm::dmat4 view_projection{1.0};  // planet-centred m -> clip; only its four side planes are used for culling
  double viewport_height_px = 1080;
  double tan_half_fov_y = 0.577;    // K = viewport_height_px / (2 tan_half_fov_y), px per rad at the centre
};

struct LodSettings {
  double max_screen_error_px = 1.0;   // tau
  int tile_quads = 32;                // quads per tile edge (a power of two >= 2)
  int max_level = 24;                 // <= kMaxTileLevel
  double finest_spacing_m = 0.3;      // a tile whose vertex spacing is at most this is not refined
  double morph_start_fraction = 0.7;  // f: morph over [f r, r] of a level's range r; in (0, 1)
  // The largest relief (max - min height) of a tile the ranges allow for, as
  // a fraction of the tile's diagonal (see (2) above).
  double max_tile_relief_ratio = 0.5;
};

struct ReliefBounds {
  double radius_m = 6360e3;                  // the datum (bottom_radius)
  double min_height_m = 0, max_height_m = 0;  // lowest and highest surface on the planet
  // The largest height error of a tile mesh whose vertex spacing is spacing_m
  // against the true surface (the relief's octaves finer than the mesh, plus
  // the sagitta spacing^2/(8 R)): m. Non-decreasing in the spacing.
  std::function<double(double spacing_m)> error_m;
};

struct SelectedTile {
  TileKey key;
  // Camera distance over which vertices morph to the parent grid, m
  // (k = clamp((d - start) / (end - start), 0, 1)); level 0 does not morph
  // (start = end = infinity).
  double morph_start_m = 0, morph_end_m = 0;
  double min_height_m = 0, max_height_m = 0;  // the height range its bounds used
  // The quadrants of the tile to draw (bit q: the area of child(key, q));
  // the others are drawn by finer tiles or culled. 0xF: the whole tile.
  unsigned quadrants = 0xFu;
};

struct Selection {
  std::vector<SelectedTile> tiles;
  int nodes_visited = 0;
  // Selected tiles of level >= 2 whose bounding volume reaches beyond the
  // morph start of the level above, where a coarser neighbour may be
  // morphing (a relief beyond max_tile_relief_ratio).
  int tiles_beyond_morph_bound = 0;
};

// The height range of a tile once its mesh is known: true and [min_h, max_h]
// (m above the datum) bounding its surface at every finer level (its
// vertices' range widened by its error). False: unknown, the nearest known
// ancestor's range is used, else the planet's.
using TileHeightRange = std::function<bool(const TileKey&, double& min_h, double& max_h)>;

// The tiles to draw, each once, none an ancestor of another, in depth-first
// order. Throws atmos::Error on a non-finite camera, matrix or viewport, on
// settings out of range or an invalid ReliefBounds. A camera anywhere (inside
// the planet too) is valid.
Selection select_tiles(const LodCamera& camera, const LodSettings& settings, const ReliefBounds& bounds,
                       const TileHeightRange& known_range = {});

// --- The parts, for tests and callers that need them. ---

// The longest vertex spacing of a level-`level` tile mesh, m, at the
// planet's highest radius (R + max(max_height, 0)).
double level_spacing_m(int level, const LodSettings& settings, const ReliefBounds& bounds);

// The finest level select_tiles() refines to.
int finest_level(const LodSettings& settings, const ReliefBounds& bounds);

// r_L (m) for L = 0..finest_level(): r_0 = infinity (level 0 does not morph).
std::vector<double> level_ranges_m(const LodCamera& camera, const LodSettings& settings, const ReliefBounds& bounds);

// D_L: the largest diameter of a level-L tile's bounding volume the ranges
// allow for, m.
double level_diameter_m(int level, const LodSettings& settings, const ReliefBounds& bounds);

// The nearest distance from `camera_m` to the tile's surface between the
// radii [min_radius_m, max_radius_m] (exact: the footprint's nearest
// direction at the nearest radius), m.
double nearest_distance_m(const glm::dvec3& camera_m, const TileKey& key, double min_radius_m, double max_radius_m);

// The four side planes of a view-projection (Gribb & Hartmann 2001):
// (n, w) with |n| = 1, a point p inside all when dot(n, p) + w >= 0.
std::array<glm::dvec4, 4> frustum_side_planes(const glm::dmat4& view_projection);

// Ring 2013: whether `point` is hidden from `camera_m` behind the sphere of
// radius occluder_radius_m (beyond the camera's horizon plane and inside its
// horizon cone). False when the camera is inside the sphere.
bool horizon_hides(const glm::dvec3& camera_m, double occluder_radius_m, const glm::dvec3& point);

// Ring 2013's occludee point of the tile's surface up to max_radius_m: the
// point on the ray through the tile's centre that is hidden only if every
// point of the tile at that radius is. False when there is none (the tile
// spans too much of the sphere).
bool horizon_occludee_point(const TileKey& key, double max_radius_m, double occluder_radius_m, glm::dvec3& point);

// The largest signed distance n.p + w (m) from a plane (n, w), |n| = 1, of
// the tile's surface between the radii [min_radius_m, max_radius_m]
// (exact: the footprint's farthest direction along n at the radius that
// maximises it).
double tile_plane_max_m(const glm::dvec4& plane, const TileKey& key, double min_radius_m, double max_radius_m);

// Frustum culling (the tile between the two radii is wholly outside a side
// plane: a bounding sphere's test, then tile_plane_max_m where the sphere
// straddles the plane) and horizon culling (the occludee point at max_radius_m against the sphere
// of occluder_radius_m): true when no point of the tile can be seen.
bool tile_culled(const glm::dvec3& camera_m, const std::array<glm::dvec4, 4>& planes, const TileKey& key,
                 double min_radius_m, double max_radius_m, double occluder_radius_m);

}  // namespace atmos::planet
