// The equal-angle cube-sphere (Ronchi, Iacono & Paolucci 1996): the sphere
// as the six faces of a cube, each face subdivided by a quadtree of tiles.
//
// Face f (0..5: +x, -x, +y, -y, +z, -z) has the outward normal N_f and the
// axes U_f, V_f (U_f x V_f = N_f). Face coordinates (u, v) in [0, 1]^2 give
// the angles a = (2u - 1) pi/4, b = (2v - 1) pi/4, and the direction
//   normalize(N_f + tan(a) U_f + tan(b) V_f).
// Lines of constant u (or v) are great circles (planes through the centre,
// as in the gnomonic map), spaced at equal angles along the face's central
// lines; the cell areas vary by a factor sqrt(2) over a face, against 5.2 for
// the gnomonic map (docs/globe.md, "Quadtree on the sphere").
//
// Shared edges are exact: the direction is computed from the "angle vector"
// w = N_f + (2u - 1) U_f + (2v - 1) V_f, whose components are exactly +-1 or
// +-(2u - 1), +-(2v - 1), as t(w) = (t(w_x), t(w_y), t(w_z)) normalised with
// t(c) = tan(c pi/4) odd by construction and t(+-1) = +-1 exactly. A point
// of a face edge or corner has the same w from every face that holds it, so
// its direction is bit-identical from each of them.
#pragma once

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>

namespace atmos::planet {

// The deepest level a key can hold: 26 bits per tile coordinate.
inline constexpr int kMaxTileLevel = 26;

struct TileKey {
  int face = 0;                // 0..5
  int level = 0;               // 0: the whole face; level L has 2^L x 2^L tiles per face
  std::uint32_t x = 0, y = 0;  // tile column (along u) and row (along v), < 2^level

  // 3 bits face, 5 bits level, 26 bits x, 26 bits y, from the most
  // significant down: ordered by face, then level, then x, then y.
  std::uint64_t packed() const;
  static TileKey unpack(std::uint64_t packed);

  friend bool operator==(const TileKey& a, const TileKey& b) {
    return a.face == b.face && a.level == b.level && a.x == b.x && a.y == b.y;
  }
  friend bool operator<(const TileKey& a, const TileKey& b) { return a.packed() < b.packed(); }
};

// Throws atmos::Error unless 0 <= face < 6, 0 <= level <= kMaxTileLevel and
// x, y < 2^level.
void validate(const TileKey& key);

// Unit direction of face coordinates (u, v) in [0, 1]^2 on `face`.
glm::dvec3 cube_direction(int face, double u, double v);

// The inverse: the face whose normal is nearest to `direction` (the lowest
// index on a tie) and the face coordinates in [0, 1]^2. `direction` need
// not be normalised but must not be zero.
void face_coordinates(const glm::dvec3& direction, int& face, double& u, double& v);

// The direction of (s, t) in [0, 1]^2 over the tile: u = (x + s) / 2^level,
// v = (y + t) / 2^level. Tile vertices at s, t = i / 2^k are exact binary
// fractions, so neighbouring tiles give bit-identical shared vertices.
glm::dvec3 tile_direction(const TileKey& key, double s, double t);

// Quadtree links. child(key, q): quadrant q in 0..3, bit 0 the column (x),
// bit 1 the row (y). parent of a level-0 key and child of a
// kMaxTileLevel key throw atmos::Error.
TileKey parent(const TileKey& key);
TileKey child(const TileKey& key, int quadrant);

// Edges of a tile: 0 at s = 0 (u min), 1 at s = 1 (u max), 2 at t = 0
// (v min), 3 at t = 1 (v max).
// The tile of the same level across `edge`, on the neighbouring face where
// the edge is a face edge.
TileKey neighbour(const TileKey& key, int edge);

// The face frame: normal N, axes U and V (integer unit vectors).
struct FaceFrame {
  std::array<int, 3> normal, u_axis, v_axis;
};
const FaceFrame& face_frame(int face);

// Bounds of the tile grid over a face at a level, as angles on the unit
// sphere (rad), from the metric of the equal-angle map:
// - the longest grid edge, (pi/2) / 2^level: along constant b the arc
//   element is ds/da = sqrt(1 + y^2)(1 + x^2) / (1 + x^2 + y^2)
//   (x = tan a, y = tan b), which is <= 1 since its square minus 1 is
//   y^2 (x^4 - 1 - y^2) / (1 + x^2 + y^2)^2 <= 0, with equality on the
//   face's central lines;
// - the longest tile diagonal, bounded by the largest singular value of the
//   map's Jacobian times the diagonal's length in (a, b): at the face's
//   corners the grid lines have ds/da = 2 sqrt(2)/3 and meet at 60 or 120
//   degrees, where the metric tensor g [[1, 1/2], [1/2, 1]] (g = 8/9) has
//   the eigenvalue 3g/2 = 4/3, so the factor is 2/sqrt(3) (the largest over
//   the face; tests/globe_lod_test.cpp checks it against every tile of
//   levels 0..6).
double max_grid_edge_angle(int level);
double max_tile_diagonal_angle(int level);

// t(c) = tan(c pi/4) of an equal-angle coordinate c = 2u - 1 in [-1, 1]: odd
// exactly (the sign applied after tan of |c|) and exactly +-1 at c = +-1,
// where tan(pi/4) rounds to 0.9999999999999999.
double equal_angle_tan(double c);

}  // namespace atmos::planet
