// The cube-sphere quadtree (src/planet/cube_sphere.hpp) and the tile
// selection (src/planet/tile_selection.hpp): exact shared edges, neighbours
// across face edges, the grid bounds the ranges rely on, the CDLOD range
// inequalities on the selections themselves (one level between neighbours,
// the finer side fully morphed where the coarser one is not morphing, the
// screen-space error bound at every vertex), conservative culling, and the
// errors on bad input.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "planet/cube_sphere.hpp"
#include "planet/tile_selection.hpp"

namespace {

using atmos::planet::LodCamera;
using atmos::planet::LodSettings;
using atmos::planet::ReliefBounds;
using atmos::planet::Selection;
using atmos::planet::SelectedTile;
using atmos::planet::TileKey;
namespace planet = atmos::planet;

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadius = 6360e3;

bool same_bits(const glm::dvec3& a, const glm::dvec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

double angle_between(const glm::dvec3& a, const glm::dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

TileKey random_key(std::mt19937_64& rng, int level) {
  const std::uint32_t n = std::uint32_t(1) << level;
  std::uniform_int_distribution<int> face(0, 5);
  std::uniform_int_distribution<std::uint32_t> coord(0, n - 1);
  TileKey key{face(rng), level, coord(rng), coord(rng)};
  // Half of them on a face edge.
  if (rng() % 2 == 0) key.x = (rng() % 2 == 0) ? 0 : n - 1;
  return key;
}

// The 4 x 33 boundary vertices of a tile mesh of 32 quads per edge.
std::vector<glm::dvec3> boundary_vertices(const TileKey& key) {
  std::vector<glm::dvec3> out;
  for (int i = 0; i <= 32; ++i) {
    const double s = double(i) / 32.0;
    out.push_back(planet::tile_direction(key, s, 0.0));
    out.push_back(planet::tile_direction(key, s, 1.0));
    out.push_back(planet::tile_direction(key, 0.0, s));
    out.push_back(planet::tile_direction(key, 1.0, s));
  }
  return out;
}

glm::dvec3 edge_point(const TileKey& key, int edge, double t) {
  switch (edge) {
    case 0: return planet::tile_direction(key, 0.0, t);
    case 1: return planet::tile_direction(key, 1.0, t);
    case 2: return planet::tile_direction(key, t, 0.0);
    default: return planet::tile_direction(key, t, 1.0);
  }
}

TEST(CubeSphere, FaceEdgesAndCornersAreBitIdenticalFromEveryFace) {
  // The 8 cube corners from each of their 3 faces.
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 target(corner & 1 ? 1.0 : -1.0, corner & 2 ? 1.0 : -1.0, corner & 4 ? 1.0 : -1.0);
    std::vector<glm::dvec3> found;
    for (int face = 0; face < 6; ++face)
      for (const double u : {0.0, 1.0})
        for (const double v : {0.0, 1.0}) {
          const glm::dvec3 d = planet::cube_direction(face, u, v);
          if (glm::dot(d, target) > 0.99 * std::sqrt(3.0)) found.push_back(d);
        }
    ASSERT_EQ(found.size(), 3u) << "corner " << corner;
    EXPECT_TRUE(same_bits(found[0], found[1]) && same_bits(found[0], found[2])) << "corner " << corner;
    EXPECT_EQ(found[0].x * found[0].x + found[0].y * found[0].y + found[0].z * found[0].z > 0.999, true);
  }
  // Every vertex of a tile's edge is one of its neighbour's boundary
  // vertices, bit for bit, across face edges too.
  std::mt19937_64 rng(7);
  for (const int level : {0, 1, 2, 5, 9, 14, 20, 24, 26})
    for (int trial = 0; trial < 20; ++trial) {
      const TileKey key = random_key(rng, level);
      for (int edge = 0; edge < 4; ++edge) {
        const TileKey other = planet::neighbour(key, edge);
        const std::vector<glm::dvec3> theirs = boundary_vertices(other);
        for (int i = 0; i <= 32; ++i) {
          const glm::dvec3 p = edge_point(key, edge, double(i) / 32.0);
          const bool shared = std::any_of(theirs.begin(), theirs.end(), [&](const glm::dvec3& q) { return same_bits(p, q); });
          ASSERT_TRUE(shared) << "face " << key.face << " level " << level << " (" << key.x << ", " << key.y
                              << ") edge " << edge << " vertex " << i << " against face " << other.face;
        }
      }
    }
}

TEST(CubeSphere, DirectionsAreUnitAndFaceCoordinatesInvertThem) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const int face = int(rng() % 6);
    const double u = unit(rng), v = unit(rng);
    const glm::dvec3 d = planet::cube_direction(face, u, v);
    ASSERT_NEAR(glm::length(d), 1.0, 4e-16);
    int f2 = -1;
    double u2 = -1, v2 = -1;
    planet::face_coordinates(d * 3.7, f2, u2, v2);
    ASSERT_EQ(f2, face);
    ASSERT_NEAR(u2, u, 1e-14);
    ASSERT_NEAR(v2, v, 1e-14);
  }
  // The centre of a face is its normal, and a face edge's midpoint lies
  // at 45 degrees between two normals.
  EXPECT_TRUE(same_bits(planet::cube_direction(4, 0.5, 0.5), glm::dvec3(0, 0, 1)));
  const glm::dvec3 mid = planet::cube_direction(0, 1.0, 0.5);
  EXPECT_EQ(mid.x, mid.y);
  EXPECT_EQ(mid.z, 0.0);
  int face = 0;
  double u = 0, v = 0;
  EXPECT_THROW(planet::face_coordinates(glm::dvec3(0.0), face, u, v), atmos::Error);
  EXPECT_THROW(planet::face_coordinates(glm::dvec3(NAN, 0, 1), face, u, v), atmos::Error);
}

TEST(CubeSphere, NeighboursAreMutualAndShareAnEdge) {
  std::mt19937_64 rng(11);
  std::vector<TileKey> keys;
  for (int level = 0; level <= 3; ++level) {
    const std::uint32_t n = 1u << level;
    for (int face = 0; face < 6; ++face)
      for (std::uint32_t y = 0; y < n; ++y)
        for (std::uint32_t x = 0; x < n; ++x) keys.push_back(TileKey{face, level, x, y});
  }
  for (int i = 0; i < 300; ++i) keys.push_back(random_key(rng, 4 + int(rng() % 23)));
  for (const TileKey& key : keys)
    for (int edge = 0; edge < 4; ++edge) {
      const TileKey other = planet::neighbour(key, edge);
      ASSERT_NO_THROW(planet::validate(other));
      ASSERT_EQ(other.level, key.level);
      int back = 0;
      for (int e = 0; e < 4; ++e) back += planet::neighbour(other, e) == key ? 1 : 0;
      ASSERT_EQ(back, 1) << "face " << key.face << " level " << key.level << " edge " << edge;
      // The two end points of the edge are corners of the neighbour.
      const glm::dvec3 ends[2] = {edge_point(key, edge, 0.0), edge_point(key, edge, 1.0)};
      const glm::dvec3 corners[4] = {planet::tile_direction(other, 0, 0), planet::tile_direction(other, 1, 0),
                                     planet::tile_direction(other, 0, 1), planet::tile_direction(other, 1, 1)};
      for (const glm::dvec3& end : ends)
        ASSERT_TRUE(std::any_of(std::begin(corners), std::end(corners), [&](const glm::dvec3& c) { return same_bits(c, end); }));
      // Across a face edge the neighbour is on the face the edge leads to.
      if (other.face != key.face) {
        const glm::dvec3 centre = planet::tile_direction(other, 0.5, 0.5);
        int face = -1;
        double u = 0, v = 0;
        planet::face_coordinates(centre, face, u, v);
        ASSERT_EQ(face, other.face);
      }
    }
  EXPECT_THROW(planet::neighbour(TileKey{0, 1, 0, 0}, 4), atmos::Error);
}

TEST(CubeSphere, QuadtreeLinksAndPackedKeys) {
  std::mt19937_64 rng(5);
  for (int i = 0; i < 1000; ++i) {
    const TileKey key = random_key(rng, 1 + int(rng() % 25));
    EXPECT_EQ(TileKey::unpack(key.packed()), key);
    for (int q = 0; q < 4; ++q) {
      const TileKey c = planet::child(key, q);
      EXPECT_EQ(planet::parent(c), key);
      // The child's corner q is the parent's corner q's quarter.
      const double s = (q & 1) ? 1.0 : 0.0, t = (q & 2) ? 1.0 : 0.0;
      EXPECT_TRUE(same_bits(planet::tile_direction(c, s, t), planet::tile_direction(key, s, t)));
      EXPECT_TRUE(key < c || key.face != c.face);
    }
  }
  EXPECT_TRUE((TileKey{0, 3, 1, 2} < TileKey{0, 3, 2, 0}));
  EXPECT_TRUE((TileKey{0, 9, 500, 2} < TileKey{1, 0, 0, 0}));
  EXPECT_THROW(planet::parent(TileKey{2, 0, 0, 0}), atmos::Error);
  EXPECT_THROW(planet::child(TileKey{2, planet::kMaxTileLevel, 0, 0}, 0), atmos::Error);
  EXPECT_THROW(planet::validate(TileKey{6, 0, 0, 0}), atmos::Error);
  EXPECT_THROW(planet::validate(TileKey{0, 2, 4, 0}), atmos::Error);
  EXPECT_THROW(planet::validate(TileKey{0, 27, 0, 0}), atmos::Error);
}

TEST(CubeSphere, GridEdgeAndDiagonalBoundsHoldForEveryTile) {
  // Face 4 (the others are congruent): every tile of levels 0..7.
  for (int level = 0; level <= 7; ++level) {
    const std::uint32_t n = 1u << level;
    double longest_edge = 0.0, longest_diagonal = 0.0;
    for (std::uint32_t y = 0; y < n; ++y)
      for (std::uint32_t x = 0; x < n; ++x) {
        const TileKey key{4, level, x, y};
        const glm::dvec3 a = planet::tile_direction(key, 0, 0), b = planet::tile_direction(key, 1, 0),
                         c = planet::tile_direction(key, 1, 1), d = planet::tile_direction(key, 0, 1);
        longest_edge = std::max({longest_edge, angle_between(a, b), angle_between(a, d)});
        longest_diagonal = std::max({longest_diagonal, angle_between(a, c), angle_between(b, d)});
      }
    EXPECT_LE(longest_edge, planet::max_grid_edge_angle(level) * (1.0 + 1e-12)) << level;
    EXPECT_LE(longest_diagonal, planet::max_tile_diagonal_angle(level) * (1.0 + 1e-12)) << level;
    if (level >= 5) {
      // Tight: the bounds are the limits of the finest tiles.
      EXPECT_GT(longest_edge, 0.99 * planet::max_grid_edge_angle(level)) << level;
      EXPECT_GT(longest_diagonal, 0.95 * planet::max_tile_diagonal_angle(level)) << level;
    }
  }
}

// --- Selection. ---

double earth_error(double spacing_m) { return 0.1 * spacing_m + spacing_m * spacing_m / (8.0 * kRadius); }

ReliefBounds earth_bounds(double min_h = -3300.0, double max_h = 3300.0) {
  ReliefBounds b;
  b.radius_m = kRadius;
  b.min_height_m = min_h;
  b.max_height_m = max_h;
  b.error_m = earth_error;
  return b;
}

// A camera `altitude_m` above the point of direction `up`, looking at
// `pitch_deg` above the horizontal (towards `heading`), 60 degrees vertical
// field of view, 16:9, 1080 px.
LodCamera make_camera(const glm::dvec3& up_direction, double altitude_m, double pitch_deg, double heading_deg = 0.0,
                      double fov_y_deg = 60.0) {
  const glm::dvec3 up = glm::normalize(up_direction);
  const glm::dvec3 east0 = glm::normalize(glm::cross(std::abs(up.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0), up));
  const glm::dvec3 north0 = glm::cross(up, east0);
  const double h = heading_deg * kPi / 180.0, p = pitch_deg * kPi / 180.0;
  const glm::dvec3 horizontal = std::cos(h) * north0 + std::sin(h) * east0;
  const glm::dvec3 forward = std::cos(p) * horizontal + std::sin(p) * up;
  LodCamera camera;
  camera.position = up * (kRadius + altitude_m);
  const glm::dvec3 view_up = std::abs(glm::dot(forward, up)) > 0.999 ? horizontal : up;
  const glm::dmat4 view = glm::lookAt(camera.position, camera.position + forward, view_up);
  const double fov = fov_y_deg * kPi / 180.0;
  camera.view_projection = glm::perspective(fov, 16.0 / 9.0, 0.05, 1e9) * view;
  camera.viewport_height_px = 1080.0;
  camera.tan_half_fov_y = std::tan(0.5 * fov);
  return camera;
}

// A synthetic relief: two sinusoids over the sphere, 3000 m over 500 km
// and 200 m over 5 km wavelengths; its slope is at most
// sum(A k) / R = 0.29 (k = 2 pi R / wavelength, per radian).
struct SyntheticRelief {
  static constexpr double a1 = 3000.0, a2 = 200.0;
  double k1 = 2.0 * kPi * kRadius / 500e3, k2 = 2.0 * kPi * kRadius / 5e3;
  glm::dvec3 axis1 = glm::normalize(glm::dvec3(0.3, 0.5, 0.8)), axis2 = glm::normalize(glm::dvec3(-0.7, 0.2, 0.4));
  double height(const glm::dvec3& d) const {
    return a1 * std::sin(k1 * glm::dot(d, axis1)) + a2 * std::sin(k2 * glm::dot(d, axis2));
  }
  double lipschitz_per_rad() const { return a1 * k1 + a2 * k2; }
  // Range over a tile: the centre's height +- the Lipschitz bound times the
  // largest angle from the centre (a corner's).
  bool range(const TileKey& key, double& lo, double& hi) const {
    const glm::dvec3 c = planet::tile_direction(key, 0.5, 0.5);
    double angle = 0.0;
    for (const double s : {0.0, 1.0})
      for (const double t : {0.0, 1.0}) angle = std::max(angle, angle_between(c, planet::tile_direction(key, s, t)));
    const double h = height(c), spread = lipschitz_per_rad() * angle;
    lo = std::max(h - spread, -a1 - a2);
    hi = std::min(h + spread, a1 + a2);
    return true;
  }
};

struct Scene {
  const char* name;
  glm::dvec3 up;
  double altitude_m, pitch_deg;
};

std::vector<Scene> scenes() {
  return {{"1 m", {0.2, 0.9, 0.1}, 1.0, 0.0},
          {"100 m", {0.7, 0.1, 0.7}, 100.0, -10.0},
          {"10 km", {1.0, 1.0, 1.0}, 10e3, 0.0},  // over a cube corner
          {"400 km", {0.0, 1.0, 1e-3}, 400e3, -20.0},  // over a face edge
          {"2.5 R", {0.3, -0.4, 0.8}, 1.5 * kRadius, -90.0}};
}

// What a selection draws: each selected tile whole, or its drawn quadrants
// (the areas of its children, at the tile's level).
struct Area {
  TileKey key;               // the area's footprint
  const SelectedTile* tile;  // the tile whose mesh covers it (level: tile->key.level)
};
std::vector<Area> drawn_areas(const std::vector<SelectedTile>& tiles) {
  std::vector<Area> areas;
  for (const SelectedTile& t : tiles) {
    if (t.quadrants == 0xFu) {
      areas.push_back({t.key, &t});
      continue;
    }
    for (int q = 0; q < 4; ++q)
      if (t.quadrants & (1u << q)) areas.push_back({planet::child(t.key, q), &t});
  }
  return areas;
}

// The drawn area holding `direction`, or nullptr.
const Area* holding(const std::vector<Area>& areas, const std::set<std::uint64_t>& keys, const glm::dvec3& direction) {
  int face = 0;
  double u = 0, v = 0;
  planet::face_coordinates(direction, face, u, v);
  for (int level = 0; level <= planet::kMaxTileLevel; ++level) {
    const double n = std::ldexp(1.0, level);
    const TileKey key{face, level, std::uint32_t(std::min(std::floor(u * n), n - 1)),
                      std::uint32_t(std::min(std::floor(v * n), n - 1))};
    if (keys.count(key.packed()))
      for (const Area& a : areas)
        if (a.key == key) return &a;
  }
  return nullptr;
}

double morph_factor(const SelectedTile& t, double d) {
  if (!std::isfinite(t.morph_end_m)) return 0.0;
  return std::clamp((d - t.morph_start_m) / (t.morph_end_m - t.morph_start_m), 0.0, 1.0);
}

TEST(GlobeLod, RangesMeetTheErrorAndMorphInequalities) {
  const ReliefBounds bounds = earth_bounds();
  const LodCamera camera = make_camera({0, 0, 1}, 100.0, 0.0);
  for (const double fraction : {0.6, 0.7, 0.9})
    for (const double tau : {0.5, 1.0, 4.0}) {
      LodSettings settings;
      settings.morph_start_fraction = fraction;
      settings.max_screen_error_px = tau;
      const std::vector<double> r = planet::level_ranges_m(camera, settings, bounds);
      const int finest = planet::finest_level(settings, bounds);
      ASSERT_EQ(int(r.size()), finest + 1);
      EXPECT_LE(planet::level_spacing_m(finest, settings, bounds), settings.finest_spacing_m);
      EXPECT_GT(planet::level_spacing_m(finest - 1, settings, bounds), settings.finest_spacing_m);
      EXPECT_TRUE(std::isinf(r[0]));
      const double k = 1080.0 / (2.0 * camera.tan_half_fov_y);
      for (int level = 1; level <= finest; ++level) {
        const double e_coarser = earth_error(planet::level_spacing_m(level - 1, settings, bounds));
        const double e_own = earth_error(planet::level_spacing_m(level, settings, bounds));
        EXPECT_GE(r[std::size_t(level)], e_coarser * k / tau * (1 - 1e-12));
        EXPECT_GE(r[std::size_t(level)], e_own / fraction * k / tau * (1 - 1e-12));
        if (level >= 2) {
          EXPECT_GE(fraction * r[std::size_t(level - 1)] * (1 + 1e-12),
                    r[std::size_t(level)] + planet::level_diameter_m(level, settings, bounds))
              << "f " << fraction << " tau " << tau << " level " << level;
        }
      }
    }
}

// Every selection: tiles unique, their drawn areas (whole tiles or
// quadrants) disjoint; neighbours within one level;
// where a tile meets a coarser one, its shared vertices are fully morphed
// and the coarser tile's are not morphing; the screen-space error of the
// (blended) mesh at every sampled vertex within tau.
void check_selection(const LodCamera& camera, const LodSettings& settings, const ReliefBounds& bounds,
                     const SyntheticRelief* relief, const char* name) {
  planet::TileHeightRange known;
  if (relief) known = [relief](const TileKey& k, double& lo, double& hi) { return relief->range(k, lo, hi); };
  const Selection sel = planet::select_tiles(camera, settings, bounds, known);
  ASSERT_FALSE(sel.tiles.empty()) << name;
  EXPECT_EQ(sel.tiles_beyond_morph_bound, 0) << name;
  const std::vector<double> r = planet::level_ranges_m(camera, settings, bounds);
  const int finest = planet::finest_level(settings, bounds);
  const double k_px = camera.viewport_height_px / (2.0 * camera.tan_half_fov_y);
  const double f = settings.morph_start_fraction;

  std::set<std::uint64_t> tile_keys;
  for (const SelectedTile& t : sel.tiles) {
    ASSERT_TRUE(tile_keys.insert(t.key.packed()).second) << name;
    ASSERT_NE(t.quadrants, 0u) << name << ": a selected tile draws nothing";
    ASSERT_EQ(t.quadrants & ~0xFu, 0u) << name;
  }
  const std::vector<Area> areas = drawn_areas(sel.tiles);
  std::set<std::uint64_t> keys;
  for (const Area& a : areas) ASSERT_TRUE(keys.insert(a.key.packed()).second) << name << ": an area drawn twice";
  for (const Area& area : areas)
    for (TileKey a = area.key; a.level > 0;) {
      a = planet::parent(a);
      ASSERT_EQ(keys.count(a.packed()), 0u) << name << ": an area and its ancestor are both drawn";
    }

  const auto surface = [&](const glm::dvec3& d) { return d * (bounds.radius_m + (relief ? relief->height(d) : 0.0)); };
  int coarser_edges = 0, partial_tiles = 0;
  for (const SelectedTile& t : sel.tiles) partial_tiles += t.quadrants != 0xFu ? 1 : 0;
  for (const Area& area : areas) {
    const SelectedTile& t = *area.tile;
    const int level = t.key.level;
    // Screen-space error at the area's points (every 4th of 32 steps).
    for (int j = 0; j <= 32; j += 4)
      for (int i = 0; i <= 32; i += 4) {
        const glm::dvec3 p = surface(planet::tile_direction(area.key, i / 32.0, j / 32.0));
        const double d = glm::length(p - camera.position);
        const double k = morph_factor(t, d);
        const double e_own = earth_error(planet::level_spacing_m(level, settings, bounds));
        const double e_parent = level > 0 ? earth_error(planet::level_spacing_m(level - 1, settings, bounds)) : e_own;
        if (level < finest) {
          ASSERT_LE(((1 - k) * e_own + k * e_parent) * k_px / d, settings.max_screen_error_px * (1 + 1e-9))
              << name << " level " << level;
        }
      }
    // Neighbours.
    for (int edge = 0; edge < 4; ++edge) {
      const TileKey other = planet::neighbour(area.key, edge);
      const glm::dvec3 other_centre = planet::tile_direction(other, 0.5, 0.5);
      for (const double s : {0.0625, 0.5, 0.9375}) {
        const glm::dvec3 p = edge_point(area.key, edge, s);
        const Area* n = holding(areas, keys, glm::normalize(p + 1e-3 * (other_centre - p)));
        if (!n) continue;  // culled
        const int other_level = n->tile->key.level;
        ASSERT_LE(std::abs(other_level - level), 1) << name << ": neighbours two levels apart";
        if (other_level == level - 1) {
          ++coarser_edges;
          for (int i = 0; i <= 32; ++i) {
            const double d = glm::length(surface(edge_point(area.key, edge, i / 32.0)) - camera.position);
            ASSERT_EQ(morph_factor(t, d), 1.0) << name << ": the finer tile's edge is not fully morphed";
            ASSERT_EQ(morph_factor(*n->tile, d), 0.0) << name << ": the coarser tile's edge is morphing";
            ASSERT_LE(d, f * r[std::size_t(level - 1)]);
          }
        }
      }
    }
  }
  int min_level = planet::kMaxTileLevel, max_level = 0;
  for (const SelectedTile& t : sel.tiles) {
    min_level = std::min(min_level, t.key.level);
    max_level = std::max(max_level, t.key.level);
  }
  if (max_level > min_level) {
    EXPECT_GT(partial_tiles, 0) << name << ": no tile drawn in part";
  } else {
    coarser_edges = 1;  // one level: no level change to check
  }
  EXPECT_GT(coarser_edges, 0) << name << ": no level change to check";
}

TEST(GlobeLod, SelectionsKeepNeighboursWithinOneLevelAndMorphSeamlessly) {
  LodSettings settings;
  const SyntheticRelief relief;
  for (const Scene& s : scenes()) {
    const glm::dvec3 up = glm::normalize(s.up);
    const double ground = relief.height(up);
    check_selection(make_camera(up, ground + s.altitude_m, s.pitch_deg), settings, earth_bounds(), &relief, s.name);
    // A smooth sphere, the planet's range for every tile.
    check_selection(make_camera(up, s.altitude_m, s.pitch_deg, 40.0), settings, earth_bounds(0.0, 0.0), nullptr,
                    s.name);
  }
  // Coarser settings: fewer quads, a larger error, another morph fraction.
  settings.tile_quads = 8;
  settings.max_screen_error_px = 3.0;
  settings.morph_start_fraction = 0.85;
  for (const Scene& s : scenes())
    check_selection(make_camera(glm::normalize(s.up), s.altitude_m + relief.height(glm::normalize(s.up)),
                                s.pitch_deg, 200.0),
                    settings, earth_bounds(), &relief, s.name);
}

TEST(GlobeLod, SelectionRefinesTowardsTheCameraAndStopsAtTheFinestLevel) {
  const LodSettings settings;
  const ReliefBounds bounds = earth_bounds(0.0, 0.0);
  const Selection near = planet::select_tiles(make_camera({0, 1, 0}, 1.0, -30.0), settings, bounds);
  const Selection far = planet::select_tiles(make_camera({0, 1, 0}, 99.0 * kRadius, -90.0), settings, bounds);
  int deepest = 0;
  for (const SelectedTile& t : near.tiles) deepest = std::max(deepest, t.key.level);
  EXPECT_EQ(deepest, planet::finest_level(settings, bounds));
  // From 100 radii the faces facing the camera, unrefined; the far side is
  // behind the horizon.
  ASSERT_FALSE(far.tiles.empty());
  EXPECT_LT(far.tiles.size(), 6u);
  for (const SelectedTile& t : far.tiles) EXPECT_EQ(t.key.level, 0);
  // A camera looking away from the planet from 400 km sees nothing of it.
  const Selection away = planet::select_tiles(make_camera({1, 0, 0}, 400e3, 80.0), settings, bounds);
  EXPECT_TRUE(away.tiles.empty());
}

TEST(GlobeLod, CullingIsConservative) {
  // Random cameras and tiles near their horizon and frustum edges: whenever
  // a point of a dense sample of the tile at its maximum height is above
  // the horizon of the occluder sphere and inside the frustum, the tile must
  // be kept.
  std::mt19937_64 rng(2013);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double r_occluder = kRadius - 430.0;
  int kept_needed = 0, culled = 0;
  for (int trial = 0; trial < 100000; ++trial) {
    const glm::dvec3 up = glm::normalize(glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5));
    const double altitude = std::exp(std::log(1.0) + unit(rng) * (std::log(100.0 * kRadius) - std::log(1.0)));
    const double rho = kRadius + altitude;
    // A tile near the horizon (angle acos(r / rho) from the nadir).
    const double horizon = std::acos(std::min(r_occluder / rho, 1.0));
    const double angle = std::clamp(horizon * (0.7 + 0.6 * unit(rng)) + 0.02 * (unit(rng) - 0.5), 0.0, kPi);
    const glm::dvec3 side = glm::normalize(glm::cross(up, glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5)));
    const glm::dvec3 target = std::cos(angle) * up + std::sin(angle) * side;
    int face = 0;
    double u = 0, v = 0;
    planet::face_coordinates(target, face, u, v);
    const int level = 1 + int(rng() % 20);
    const double n = std::ldexp(1.0, level);
    const TileKey key{face, level, std::uint32_t(std::min(std::floor(u * n), n - 1)),
                      std::uint32_t(std::min(std::floor(v * n), n - 1))};
    const double h_max = 9000.0 * unit(rng), h_min = h_max - 2000.0 * unit(rng);
    // A view towards the tile, turned by up to 40 degrees.
    const glm::dvec3 camera = up * rho;
    const glm::dvec3 to_tile = glm::normalize(target * (kRadius + h_max) - camera);
    const glm::dvec3 jitter = glm::normalize(glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5));
    const glm::dvec3 forward = glm::normalize(to_tile + 0.7 * unit(rng) * jitter);
    const glm::dvec3 view_up = std::abs(glm::dot(forward, up)) > 0.99 ? side : up;
    const double fov = (20.0 + 80.0 * unit(rng)) * kPi / 180.0;
    const glm::dmat4 vp = glm::perspective(fov, 1.0 + unit(rng), 0.05, 1e9) *
                          glm::lookAt(camera, camera + forward, view_up);
    const std::array<glm::dvec4, 4> planes = planet::frustum_side_planes(vp);
    const bool is_culled = planet::tile_culled(camera, planes, key, kRadius + h_min, kRadius + h_max, r_occluder);
    culled += is_culled ? 1 : 0;
    bool visible = false;
    for (int j = 0; j <= 8 && !visible; ++j)
      for (int i = 0; i <= 8 && !visible; ++i) {
        const glm::dvec3 p = planet::tile_direction(key, i / 8.0, j / 8.0) * (kRadius + h_max);
        bool inside = true;
        for (const glm::dvec4& plane : planes) inside = inside && glm::dot(glm::dvec3(plane), p) + plane.w >= 0.0;
        if (!inside) continue;
        // Above the horizon: the segment camera -> p misses the open ball.
        const glm::dvec3 seg = p - camera;
        const double t = std::clamp(-glm::dot(camera, seg) / glm::dot(seg, seg), 0.0, 1.0);
        visible = glm::length(camera + t * seg) >= r_occluder;
      }
    if (visible) {
      ++kept_needed;
      ASSERT_FALSE(is_culled) << "trial " << trial << ": a visible tile was culled (level " << level << ", altitude "
                              << altitude << " m)";
    }
  }
  // Both outcomes occur often: the test exercises the culling.
  EXPECT_GT(kept_needed, 10000);
  EXPECT_GT(culled, 10000);
}

TEST(GlobeLod, TilePlaneMaximumIsTheSampledMaximum) {
  // Random tiles and planes through points near them: the exact largest
  // signed distance bounds a dense sample of the tile between its radii
  // from above, and exceeds it by no more than the sample's spacing.
  std::mt19937_64 rng(2001);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const TileKey key = random_key(rng, int(rng() % 16));
    const double lo = kRadius - 500.0 - 9000.0 * unit(rng), hi = kRadius + 9000.0 * unit(rng);
    const glm::dvec3 n = glm::normalize(glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5));
    const glm::dvec3 through = planet::tile_direction(key, 1.4 * unit(rng) - 0.2, 1.4 * unit(rng) - 0.2) *
                               (lo + (hi - lo) * unit(rng));
    const glm::dvec4 plane(n, -glm::dot(n, through));
    const double exact = planet::tile_plane_max_m(plane, key, lo, hi);
    double sampled = -INFINITY;
    for (int j = 0; j <= 32; ++j)
      for (int i = 0; i <= 32; ++i)
        for (const double s : {lo, hi})
          sampled = std::max(sampled, glm::dot(n, planet::tile_direction(key, i / 32.0, j / 32.0) * s) + plane.w);
    const double rounding = 1e-9 * (hi + std::abs(plane.w));
    ASSERT_GE(exact, sampled - rounding) << trial;
    ASSERT_LE(exact, sampled + hi * planet::max_tile_diagonal_angle(key.level) / 32.0 + rounding) << trial;
  }
}

TEST(GlobeLod, EveryDrawnAreaReachesIntoEverySidePlane) {
  // Every tile known to lie between 0 and 1 m, the camera 2 m above it,
  // a 10 degree field: towards the horizon and 40 degrees up (no ground in
  // view but the tiles around the camera's foot). Each drawn area (a
  // selected tile's quadrant, with the tile's height range) has a point on
  // the inner side of each of the four side planes, to within the sample's
  // spacing: no area is kept that one plane alone excludes, as bounding
  // spheres of the tiles near the camera, whose planes pass through it,
  // would keep.
  const LodSettings settings;
  const ReliefBounds bounds = earth_bounds();
  const planet::TileHeightRange flat = [](const TileKey&, double& lo, double& hi) {
    lo = 0.0;
    hi = 1.0;
    return true;
  };
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.3, 0.8, 0.5));
  for (const double pitch : {-5.0, 40.0}) {
    const LodCamera camera = make_camera(up, 2.0, pitch, 30.0, 10.0);
    const std::array<glm::dvec4, 4> planes = planet::frustum_side_planes(camera.view_projection);
    const Selection selection = planet::select_tiles(camera, settings, bounds, flat);
    if (pitch < 0.0) {
      EXPECT_GT(selection.tiles.size(), 50u);
    } else {
      EXPECT_LE(selection.tiles.size(), 4u);
    }
    for (const SelectedTile& t : selection.tiles)
      for (int q = 0; q < 4; ++q) {
        if ((t.quadrants & (1u << q)) == 0) continue;
        const TileKey area = planet::child(t.key, q);
        const double lo = kRadius + t.min_height_m, hi = kRadius + t.max_height_m;
        const double spacing = hi * planet::max_tile_diagonal_angle(area.level) / 16.0;
        for (const glm::dvec4& plane : planes) {
          double sampled = -INFINITY;
          for (int j = 0; j <= 16; ++j)
            for (int i = 0; i <= 16; ++i)
              for (const double s : {lo, hi})
                sampled = std::max(sampled, glm::dot(glm::dvec3(plane), planet::tile_direction(area, i / 16.0, j / 16.0) * s) + plane.w);
          ASSERT_GE(sampled, -spacing - 1e-9 * (hi + std::abs(plane.w)))
              << "pitch " << pitch << ": level " << t.key.level << " quadrant " << q << " lies outside a side plane";
        }
      }
  }
}

TEST(GlobeLod, HorizonTestAgreesWithTheSphere) {
  const double r = kRadius;
  const glm::dvec3 camera(0, 0, r + 1000.0);
  // Straight below, through the planet: hidden; on the near side: visible.
  EXPECT_TRUE(planet::horizon_hides(camera, r, glm::dvec3(0, 0, -r)));
  EXPECT_FALSE(planet::horizon_hides(camera, r, glm::dvec3(0, 0, r)));
  // A point on the sphere just before and beyond the horizon distance.
  const double horizon = std::acos(r / (r + 1000.0));
  EXPECT_FALSE(planet::horizon_hides(camera, r, r * glm::dvec3(std::sin(0.99 * horizon), 0, std::cos(0.99 * horizon))));
  EXPECT_TRUE(planet::horizon_hides(camera, r, r * glm::dvec3(std::sin(1.01 * horizon), 0, std::cos(1.01 * horizon))));
  // A camera inside the sphere culls nothing.
  EXPECT_FALSE(planet::horizon_hides(glm::dvec3(0, 0, 0.5 * r), r, glm::dvec3(0, 0, -r)));
  // Occludee points exist for small tiles, not for a whole face.
  glm::dvec3 q;
  EXPECT_TRUE(planet::horizon_occludee_point(TileKey{0, 8, 3, 100}, r + 9000.0, r, q));
  EXPECT_GE(glm::length(q), r + 9000.0);
  EXPECT_FALSE(planet::horizon_occludee_point(TileKey{0, 0, 0, 0}, 3.0 * r, r, q));
}

TEST(GlobeLod, NearestDistanceIsTheSampledMinimum) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 400; ++trial) {
    const TileKey key = random_key(rng, 2 + int(rng() % 10));
    const glm::dvec3 centre = planet::tile_direction(key, 0.5, 0.5);
    const glm::dvec3 offset(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    const double spread = std::ldexp(1.0, -key.level) * 4.0;
    const glm::dvec3 camera =
        glm::normalize(centre + spread * offset) * (kRadius + std::exp(unit(rng) * std::log(1e7)) - 1.0);
    const double lo = kRadius - 500.0, hi = kRadius + 3000.0;
    const double d = planet::nearest_distance_m(camera, key, lo, hi);
    double sampled = INFINITY;
    for (int j = 0; j <= 32; ++j)
      for (int i = 0; i <= 32; ++i)
        for (const double s : {lo, hi, std::clamp(glm::length(camera), lo, hi)})
          sampled = std::min(sampled, glm::length(planet::tile_direction(key, i / 32.0, j / 32.0) * s - camera));
    ASSERT_LE(d, sampled * (1 + 1e-9) + 1e-6) << trial;
    // Within the sampling's resolution of the true minimum.
    ASSERT_GE(d, sampled - planet::max_tile_diagonal_angle(key.level) * hi / 32.0) << trial;
  }
}

TEST(GlobeLod, BadInputThrowsAndAnyCameraPositionIsValid) {
  const LodSettings settings;
  const ReliefBounds bounds = earth_bounds();
  LodCamera camera = make_camera({0, 0, 1}, 10.0, 0.0);
  auto expect_error = [&](LodCamera c, LodSettings s, ReliefBounds b) {
    EXPECT_THROW(planet::select_tiles(c, s, b), atmos::Error);
  };
  LodCamera c = camera;
  c.position.x = NAN;
  expect_error(c, settings, bounds);
  c = camera;
  c.position.z = INFINITY;
  expect_error(c, settings, bounds);
  c = camera;
  c.view_projection[2][1] = NAN;
  expect_error(c, settings, bounds);
  c = camera;
  c.viewport_height_px = 0.0;
  expect_error(c, settings, bounds);
  c = camera;
  c.tan_half_fov_y = NAN;
  expect_error(c, settings, bounds);
  LodSettings s = settings;
  s.max_screen_error_px = 0.0;
  expect_error(camera, s, bounds);
  s = settings;
  s.tile_quads = 24;
  expect_error(camera, s, bounds);
  s = settings;
  s.max_level = planet::kMaxTileLevel + 1;
  expect_error(camera, s, bounds);
  s = settings;
  s.morph_start_fraction = 1.0;
  expect_error(camera, s, bounds);
  ReliefBounds b = bounds;
  b.error_m = nullptr;
  expect_error(camera, settings, b);
  b = bounds;
  b.error_m = [](double) { return NAN; };
  expect_error(camera, settings, b);
  b = bounds;
  b.min_height_m = 1.0;
  b.max_height_m = 0.0;
  expect_error(camera, settings, b);
  EXPECT_THROW(planet::select_tiles(camera, settings, bounds,
                                    [](const TileKey&, double& lo, double& hi) {
                                      lo = NAN;
                                      hi = 0.0;
                                      return true;
                                    }),
               atmos::Error);

  // Inside the planet, at its centre and far away: valid, no crash.
  for (const double radius : {0.0, 0.5 * kRadius, kRadius - 10.0, 100.0 * kRadius}) {
    c = camera;
    c.position = glm::dvec3(0.0, 0.0, radius);
    const Selection sel = planet::select_tiles(c, settings, bounds);
    for (const SelectedTile& t : sel.tiles) EXPECT_NO_THROW(planet::validate(t.key));
  }
}

}  // namespace
