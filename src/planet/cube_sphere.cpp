#include "planet/cube_sphere.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "atmos/atmosphere.hpp"

namespace atmos::planet {
namespace {

constexpr double kQuarterPi = 0.25 * std::numbers::pi;

// Right-handed frames (U x V = N), faces +x, -x, +y, -y, +z, -z.
constexpr std::array<FaceFrame, 6> kFrames = {{
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}},
    {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}},
    {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
    {{0, 0, -1}, {1, 0, 0}, {0, -1, 0}},
}};

// w_i = N_i + alpha U_i + beta V_i: each product with an integer in
// {-1, 0, 1} and each sum with at most one non-zero term is exact.
double angle_component(const FaceFrame& f, int i, double alpha, double beta) {
  if (f.normal[i] != 0) return double(f.normal[i]);
  if (f.u_axis[i] != 0) return f.u_axis[i] > 0 ? alpha : -alpha;
  return f.v_axis[i] > 0 ? beta : -beta;
}

int dot(const std::array<int, 3>& a, const std::array<int, 3>& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

double dot(const std::array<int, 3>& a, const glm::dvec3& b) {
  return double(a[0]) * b.x + double(a[1]) * b.y + double(a[2]) * b.z;
}

}  // namespace

std::uint64_t TileKey::packed() const {
  return (std::uint64_t(face) << 57) | (std::uint64_t(level) << 52) | (std::uint64_t(x) << 26) | std::uint64_t(y);
}

TileKey TileKey::unpack(std::uint64_t p) {
  constexpr std::uint64_t mask26 = (std::uint64_t(1) << 26) - 1;
  return TileKey{int(p >> 57), int((p >> 52) & 31), std::uint32_t((p >> 26) & mask26), std::uint32_t(p & mask26)};
}

void validate(const TileKey& key) {
  if (key.face < 0 || key.face > 5) throw Error("tile face " + std::to_string(key.face) + " is not in 0..5");
  if (key.level < 0 || key.level > kMaxTileLevel)
    throw Error("tile level " + std::to_string(key.level) + " is not in 0.." + std::to_string(kMaxTileLevel));
  const std::uint64_t n = std::uint64_t(1) << key.level;
  if (key.x >= n || key.y >= n)
    throw Error("tile (" + std::to_string(key.x) + ", " + std::to_string(key.y) + ") is outside level " +
                std::to_string(key.level) + "'s " + std::to_string(n) + " x " + std::to_string(n) + " tiles");
}

const FaceFrame& face_frame(int face) {
  if (face < 0 || face > 5) throw Error("cube face " + std::to_string(face) + " is not in 0..5");
  return kFrames[std::size_t(face)];
}

glm::dvec3 cube_direction(int face, double u, double v) {
  const FaceFrame& f = face_frame(face);
  const double alpha = 2.0 * u - 1.0, beta = 2.0 * v - 1.0;
  const glm::dvec3 p(equal_angle_tan(angle_component(f, 0, alpha, beta)),
                     equal_angle_tan(angle_component(f, 1, alpha, beta)),
                     equal_angle_tan(angle_component(f, 2, alpha, beta)));
  return p / std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
}

void face_coordinates(const glm::dvec3& direction, int& face, double& u, double& v) {
  const glm::dvec3 a(std::abs(direction.x), std::abs(direction.y), std::abs(direction.z));
  if (!(a.x > 0.0 || a.y > 0.0 || a.z > 0.0) || !std::isfinite(a.x + a.y + a.z))
    throw Error("face_coordinates: the direction must be finite and non-zero");
  // The dominant axis; on ties the lower face index (+x before +y before +z).
  int axis = 0;
  if (a.y > a[axis]) axis = 1;
  if (a.z > a[axis]) axis = 2;
  face = 2 * axis + (direction[axis] < 0.0 ? 1 : 0);
  const FaceFrame& f = kFrames[std::size_t(face)];
  const double w = dot(f.normal, direction);
  const double x = dot(f.u_axis, direction) / w, y = dot(f.v_axis, direction) / w;
  // a = atan(x), u = (a / (pi/4) + 1) / 2, clamped against rounding.
  u = std::clamp(0.5 * (std::atan(x) / kQuarterPi + 1.0), 0.0, 1.0);
  v = std::clamp(0.5 * (std::atan(y) / kQuarterPi + 1.0), 0.0, 1.0);
}

glm::dvec3 tile_direction(const TileKey& key, double s, double t) {
  const double scale = std::ldexp(1.0, -key.level);
  return cube_direction(key.face, (double(key.x) + s) * scale, (double(key.y) + t) * scale);
}

TileKey parent(const TileKey& key) {
  if (key.level <= 0) throw Error("a level-0 tile (a cube face) has no parent");
  return TileKey{key.face, key.level - 1, key.x >> 1, key.y >> 1};
}

TileKey child(const TileKey& key, int quadrant) {
  if (key.level >= kMaxTileLevel) throw Error("tiles of level " + std::to_string(kMaxTileLevel) + " have no children");
  if (quadrant < 0 || quadrant > 3) throw Error("tile quadrant " + std::to_string(quadrant) + " is not in 0..3");
  return TileKey{key.face, key.level + 1, 2 * key.x + std::uint32_t(quadrant & 1),
                 2 * key.y + std::uint32_t(quadrant >> 1)};
}

TileKey neighbour(const TileKey& key, int edge) {
  if (edge < 0 || edge > 3) throw Error("tile edge " + std::to_string(edge) + " is not in 0..3");
  const std::int64_t n = std::int64_t(1) << key.level;
  std::int64_t x = key.x, y = key.y;
  switch (edge) {
    case 0: --x; break;
    case 1: ++x; break;
    case 2: --y; break;
    default: ++y; break;
  }
  if (x >= 0 && x < n && y >= 0 && y < n) return TileKey{key.face, key.level, std::uint32_t(x), std::uint32_t(y)};

  // Across a face edge. On the cube of half-size n (in units of half a tile
  // of this level, since the equal-angle coordinates 2u - 1 map to one
  // another with signs and permutations across an edge: a' = +-b there),
  // the tile's centre is Q = n N + X U + Y V with X = 2x + 1 - n,
  // Y = 2y + 1 - n. Its neighbour's centre lies one half-tile past the edge
  // on the next face: for edge 1 (u = 1) at n N + n U + Y V - N, i.e. the
  // edge point moved by -N; likewise for the other edges.
  const FaceFrame& f = kFrames[std::size_t(key.face)];
  const std::int64_t X = 2 * std::int64_t(key.x) + 1 - n, Y = 2 * std::int64_t(key.y) + 1 - n;
  std::int64_t cu = X, cv = Y;  // the edge point's coordinates along U and V
  std::array<int, 3> across{};  // the outward axis of the edge: the next face's normal
  switch (edge) {
    case 0: cu = -n; across = {-f.u_axis[0], -f.u_axis[1], -f.u_axis[2]}; break;
    case 1: cu = n; across = f.u_axis; break;
    case 2: cv = -n; across = {-f.v_axis[0], -f.v_axis[1], -f.v_axis[2]}; break;
    default: cv = n; across = f.v_axis; break;
  }
  std::array<std::int64_t, 3> q{};
  for (int i = 0; i < 3; ++i)
    q[std::size_t(i)] = (n - 1) * f.normal[std::size_t(i)] + cu * f.u_axis[std::size_t(i)] + cv * f.v_axis[std::size_t(i)];
  int next = 0;
  for (int g = 0; g < 6; ++g)
    if (dot(kFrames[std::size_t(g)].normal, across) == 1) next = g;
  const FaceFrame& h = kFrames[std::size_t(next)];
  const std::int64_t xu = q[0] * h.u_axis[0] + q[1] * h.u_axis[1] + q[2] * h.u_axis[2];
  const std::int64_t yv = q[0] * h.v_axis[0] + q[1] * h.v_axis[1] + q[2] * h.v_axis[2];
  return TileKey{next, key.level, std::uint32_t((xu + n - 1) / 2), std::uint32_t((yv + n - 1) / 2)};
}

double equal_angle_tan(double c) {
  const double m = std::abs(c);
  const double t = m == 1.0 ? 1.0 : std::tan(m * kQuarterPi);
  return std::copysign(t, c);
}

double max_grid_edge_angle(int level) { return 0.5 * std::numbers::pi * std::ldexp(1.0, -level); }

double max_tile_diagonal_angle(int level) {
  // sigma_max sqrt(2) (pi/2) / 2^level with sigma_max = 2/sqrt(3).
  return 2.0 / std::sqrt(3.0) * std::sqrt(2.0) * max_grid_edge_angle(level);
}

}  // namespace atmos::planet
