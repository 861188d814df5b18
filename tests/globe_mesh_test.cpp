// The terrain globe's CPU side (src/planet/): its tile meshes (morph
// targets, shared edges, skirts, precision) and its sun's shadow cascades
// (fit, snapping, culling). The globe on the GPU is in globe_test.cpp.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "atmos/globe.hpp"
#include "planet_surfaces.hpp"
#include "planet/globe_mesh.hpp"
#include "planet/globe_shadows.hpp"

namespace {

using atmos_test::surface_of;
using atmos::planet::kGridVertices;
using atmos::planet::kSkirtVertices;
using atmos::planet::kTileQuads;
using atmos::planet::kTileSide;
using atmos::planet::MeshBuilder;
using atmos::planet::Surface;
using atmos::planet::TileKey;
using atmos::planet::TileMesh;

constexpr double kEarthRadius = 6360e3;

glm::dvec3 position_of(const TileMesh& mesh, int i, int j) {
  const auto& v = mesh.vertices[size_t(j * kTileSide + i)];
  return mesh.origin + glm::dvec3(v.position[0], v.position[1], v.position[2]);
}
glm::dvec3 morphed_position_of(const TileMesh& mesh, int i, int j) {
  const auto& v = mesh.vertices[size_t(j * kTileSide + i)];
  return position_of(mesh, i, j) + glm::dvec3(v.morph_offset[0], v.morph_offset[1], v.morph_offset[2]);
}

// The point of the parent's mesh at the parent's grid coordinates (a, b),
// possibly fractional: the parent's triangles split its quads along the
// diagonal from (i, j) to (i + 1, j + 1).
glm::dvec3 parent_surface(const TileMesh& parent, double a, double b) {
  const int i = std::min(int(std::floor(a)), kTileQuads - 1), j = std::min(int(std::floor(b)), kTileQuads - 1);
  const double s = a - i, t = b - j;
  const glm::dvec3 p00 = position_of(parent, i, j), p10 = position_of(parent, i + 1, j),
                   p11 = position_of(parent, i + 1, j + 1), p01 = position_of(parent, i, j + 1);
  if (s >= t) return p00 + s * (p10 - p00) + t * (p11 - p10);  // the triangle (00, 10, 11)
  return p00 + t * (p01 - p00) + s * (p11 - p01);               // the triangle (00, 11, 01)
}

class GlobeMesh : public ::testing::Test {
 protected:
  GlobeMesh() : surface_(surface_of(atmos::SurfaceStyle::mars, 7), 3389.5e3), builder_(surface_, 3389.5e3) {}
  Surface surface_;
  MeshBuilder builder_;
};

// A tile fully morphed is its parent's surface: every vertex moves onto the
// parent's triangles (the condition for handing a level over without a pop).
TEST_F(GlobeMesh, FullyMorphedTileIsItsParentsSurface) {
  for (const TileKey& key : {TileKey{2, 5, 13, 7}, TileKey{0, 11, 1000, 2047}, TileKey{5, 1, 1, 0}}) {
    const TileKey parent_key = atmos::planet::parent(key);
    const TileMesh tile = builder_.build(key), parent = builder_.build(parent_key);
    // Where the child's grid lies on the parent's: half its cells, offset by quadrant.
    const double offset_i = double((key.x & 1u) * (kTileQuads / 2)), offset_j = double((key.y & 1u) * (kTileQuads / 2));
    double worst = 0.0;
    for (int j = 0; j < kTileSide; ++j)
      for (int i = 0; i < kTileSide; ++i) {
        const glm::dvec3 expected = parent_surface(parent, offset_i + 0.5 * i, offset_j + 0.5 * j);
        worst = std::max(worst, glm::length(morphed_position_of(tile, i, j) - expected));
      }
    // Float storage of tile-relative positions: a few ulps of the tile's size.
    const double tile_size = builder_.spacing_m(key.level) * kTileQuads;
    EXPECT_LT(worst, 1e-5 * tile_size) << "tile face " << key.face << " level " << key.level;
  }
}

// Two tiles of one level share their edge's vertices exactly (up to the
// float storage relative to each tile's origin), across a face edge too.
TEST_F(GlobeMesh, NeighboursShareTheirEdgeVertices) {
  for (const TileKey& key : {TileKey{1, 6, 20, 31}, TileKey{4, 3, 7, 2}, TileKey{0, 2, 3, 3}}) {
    const TileMesh tile = builder_.build(key);
    const double tolerance = 1e-6 * builder_.spacing_m(key.level) * kTileQuads;
    for (int edge = 0; edge < 4; ++edge) {
      const TileKey other_key = atmos::planet::neighbour(key, edge);
      const TileMesh other = builder_.build(other_key);
      // Every edge vertex of `tile` is a vertex of the neighbour's boundary.
      // Edges (cube_sphere.hpp): 0 at s = 0, 1 at s = 1, 2 at t = 0, 3 at t = 1.
      for (int k = 0; k < kTileSide; ++k) {
        const int i = edge == 0 ? 0 : (edge == 1 ? kTileQuads : k);
        const int j = edge == 2 ? 0 : (edge == 3 ? kTileQuads : k);
        const glm::dvec3 p = position_of(tile, i, j);
        double nearest = INFINITY;
        for (int m = 0; m < kTileSide; ++m)
          for (const auto& [a, b] : {std::pair{m, 0}, std::pair{kTileQuads, m}, std::pair{m, kTileQuads}, std::pair{0, m}})
            nearest = std::min(nearest, glm::length(position_of(other, a, b) - p));
        EXPECT_LT(nearest, tolerance) << "face " << key.face << " level " << key.level << " edge " << edge << " k " << k;
      }
    }
  }
}

// Skirts hang below every edge vertex, along the vertical, deeper than the
// step to a neighbour one level coarser.
TEST_F(GlobeMesh, SkirtsHangBelowTheEdges) {
  const TileKey key{3, 9, 100, 300};
  const TileMesh tile = builder_.build(key);
  ASSERT_EQ(tile.vertices.size(), size_t(kGridVertices + kSkirtVertices));
  const double depth = builder_.skirt_depth_m(key.level);
  EXPECT_GT(depth, 2.0 * builder_.bounds().error_m(builder_.spacing_m(key.level - 1)));
  for (int k = 0; k < kSkirtVertices; ++k) {
    const auto& v = tile.vertices[size_t(kGridVertices + k)];
    const glm::dvec3 p = tile.origin + glm::dvec3(v.position[0], v.position[1], v.position[2]);
    const int edge = k / kTileSide, n = k % kTileSide;
    const int i = edge == 0 ? 0 : (edge == 1 ? kTileQuads : (edge == 4 ? kTileQuads / 2 : n));
    const int j = edge == 2 ? 0 : (edge == 3 ? kTileQuads : (edge == 5 ? kTileQuads / 2 : n));
    const glm::dvec3 top = position_of(tile, i, j);
    EXPECT_NEAR(glm::length(top) - glm::length(p), depth, 1e-3 + 1e-6 * glm::length(top));
  }
  // Every triangle index points into the tile's vertices; each quadrant
  // covers its quarter of the grid's quads and skirts along its four sides.
  for (std::uint32_t index : builder_.indices()) ASSERT_LT(index, tile.vertices.size());
  EXPECT_EQ(builder_.quadrant_index_count(), size_t(6 * (kTileQuads / 2) * (kTileQuads / 2) + 4 * 6 * (kTileQuads / 2)));
  EXPECT_EQ(builder_.tile_index_offset(), 4 * builder_.quadrant_index_count());
  EXPECT_EQ(builder_.tile_index_count(), size_t(6 * kTileQuads * kTileQuads + 4 * 6 * kTileQuads));
  EXPECT_EQ(builder_.indices().size(), builder_.tile_index_offset() + builder_.tile_index_count());
  for (int q = 0; q < 4; ++q) {
    const size_t first = size_t(q) * builder_.quadrant_index_count();
    for (size_t n = first; n < first + size_t(6 * (kTileQuads / 2) * (kTileQuads / 2)); ++n) {
      const int vertex = int(builder_.indices()[n]);
      ASSERT_LT(vertex, kGridVertices);
      const int i = vertex % kTileSide, j = vertex / kTileSide;
      EXPECT_TRUE(i >= (q & 1) * kTileQuads / 2 && i <= ((q & 1) + 1) * kTileQuads / 2) << "quadrant " << q;
      EXPECT_TRUE(j >= (q >> 1) * kTileQuads / 2 && j <= ((q >> 1) + 1) * kTileQuads / 2) << "quadrant " << q;
    }
  }
  // Winding (the globe culls back faces): on every face, the grid's
  // triangles are counter-clockwise seen from outside the planet, and each
  // skirt faces away from the area its run draws (a quadrant, or the
  // tile), where a crack's wall is seen from. Faces 1 and 5 have axes that
  // point against x and z.
  for (const TileKey& face_key : {key, TileKey{1, 9, 100, 300}, TileKey{5, 9, 300, 100}}) {
    const TileMesh mesh = builder_.build(face_key);
    const auto point = [&](std::uint32_t index) {
      const auto& v = mesh.vertices[index];
      return mesh.origin + glm::dvec3(v.position[0], v.position[1], v.position[2]);
    };
    for (int run = 0; run < 5; ++run) {
      const size_t first = size_t(run) * builder_.quadrant_index_count();
      const size_t count = run < 4 ? builder_.quadrant_index_count() : builder_.tile_index_count();
      glm::dvec3 centroid(0.0);
      int grid = 0;
      for (size_t n = first; n < first + count; ++n)
        if (builder_.indices()[n] < std::uint32_t(kGridVertices)) centroid += point(builder_.indices()[n]), ++grid;
      centroid /= double(grid);
      int skirts = 0;
      for (size_t n = first; n < first + count; n += 3) {
        const std::uint32_t a = builder_.indices()[n], b = builder_.indices()[n + 1], c = builder_.indices()[n + 2];
        const glm::dvec3 normal = glm::cross(point(b) - point(a), point(c) - point(a));
        if (std::max({a, b, c}) < std::uint32_t(kGridVertices)) {
          ASSERT_GT(glm::dot(normal, glm::normalize(point(a))), 0.0) << "grid, run " << run;
        } else {
          ++skirts;
          ASSERT_GT(glm::dot(normal, (point(a) + point(b) + point(c)) / 3.0 - centroid), 0.0) << "skirt, run " << run;
        }
      }
      EXPECT_EQ(skirts, 2 * 4 * (run < 4 ? kTileQuads / 2 : kTileQuads)) << run;
    }
  }
}

// Vertex jitter at a metre above the ground (Cozzi & Ring 2011, ch. 5): the
// vertex shader's float arithmetic (tile origin minus camera, rounded from
// double, plus the float local position, times the float camera-relative
// matrix) against the double-precision projection, for a camera moved in
// millimetre steps. The bound is a quarter of a pixel at 1080p.
TEST_F(GlobeMesh, VerticesDoNotJitterAtAMetreAboveTheGround) {
  const Surface earth(surface_of(atmos::SurfaceStyle::earth, 1), kEarthRadius);
  MeshBuilder builder(earth, kEarthRadius);
  const glm::dvec3 ground_direction = glm::normalize(glm::dvec3(0.3, 0.5, 0.8));
  int face = 0;
  double u = 0.0, v = 0.0;
  atmos::planet::face_coordinates(ground_direction, face, u, v);
  // The tiles under the camera: the finest level's, which the selection
  // draws there, and two coarser ones (drawn farther away in a frame; here
  // as a harder case: larger tile-relative coordinates).
  const int finest = atmos::planet::finest_level(builder.lod_settings(1.0), builder.bounds());
  std::vector<TileMesh> tiles;
  for (int level = finest - 2; level <= finest; ++level) {
    const double n = std::ldexp(1.0, level);
    tiles.push_back(builder.build(TileKey{face, level, std::uint32_t(u * n), std::uint32_t(v * n)}));
  }
  const double ground = kEarthRadius + builder.surface_height_m(ground_direction);
  const int width = 1920, height = 1080;
  const glm::dmat4 projection = atmos::reversed_z_projection(glm::radians(60.0), double(width) / height, 0.05);
  const glm::dvec3 up = ground_direction;
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const glm::dvec3 forward = glm::normalize(north - 0.3 * up);
  double worst_px = 0.0;
  int projected = 0;
  for (int step = 0; step < 20; ++step) {
    const glm::dvec3 camera = up * (ground + 1.0) + east * (1e-3 * step);
    const glm::dmat4 rotation = glm::lookAt(glm::dvec3(0.0), forward, up);
    const glm::dmat4 clip_from_offset = projection * rotation;
    const glm::mat4 clip_f(clip_from_offset);
    for (const TileMesh& tile : tiles) {
      const glm::dvec3 origin_d = tile.origin - camera;
      const glm::vec3 origin_f(origin_d);
      for (int j = 0; j < kTileSide; ++j)
        for (int i = 0; i < kTileSide; ++i) {
          const auto& vertex = tile.vertices[size_t(j * kTileSide + i)];
          const glm::vec3 local(vertex.position[0], vertex.position[1], vertex.position[2]);
          const glm::vec4 clip_float = clip_f * glm::vec4(origin_f + local, 1.0f);
          const glm::dvec4 clip_double = clip_from_offset * glm::dvec4(position_of(tile, i, j) - camera, 1.0);
          if (clip_double.w < 0.05) continue;  // behind the near plane
          const glm::dvec2 a = glm::dvec2(clip_float.x, clip_float.y) / double(clip_float.w);
          const glm::dvec2 b = glm::dvec2(clip_double.x, clip_double.y) / clip_double.w;
          if (std::abs(b.x) > 1.0 || std::abs(b.y) > 1.0) continue;  // off screen
          const glm::dvec2 error_px = (a - b) * 0.5 * glm::dvec2(width, height);
          worst_px = std::max(worst_px, glm::length(error_px));
          ++projected;
        }
    }
  }
  EXPECT_GT(projected, 20 * 100);  // the tiles under the camera fill much of the view
  EXPECT_LT(worst_px, 0.25);
  char figure[32];
  std::snprintf(figure, sizeof figure, "%.3g", worst_px);
  RecordProperty("worst_jitter_px", figure);
}

// ---------------------------------------------------------------------------
// The sun's cascades (src/planet/globe_shadows.hpp), on the CPU.

using atmos::planet::ShadowCascade;
using atmos::planet::ShadowLight;
using atmos::planet::ShadowView;

// A view from `camera` along `forward` (up_hint fixes the roll), with a
// symmetric 60 degree vertical field of view of the given aspect.
ShadowView shadow_view(const glm::dvec3& camera, const glm::dvec3& forward, const glm::dvec3& up_hint, double aspect,
                       const glm::dvec3& sun, double nearest_m, double distance_m) {
  ShadowView v;
  v.camera = camera;
  v.forward = glm::normalize(forward);
  v.right = glm::normalize(glm::cross(v.forward, up_hint));
  v.up = glm::cross(v.right, v.forward);
  const double t = std::tan(glm::radians(30.0));
  v.x_min = -t * aspect;
  v.x_max = t * aspect;
  v.y_min = -t;
  v.y_max = t;
  v.sun = glm::normalize(sun);
  v.nearest_depth_m = nearest_m;
  v.shadow_distance_m = distance_m;
  return v;
}

// The corner of the view's frustum at view depth d and slopes (sx, sy).
glm::dvec3 frustum_point(const ShadowView& v, double d, double sx, double sy) {
  return v.camera + v.forward * d + v.right * (sx * d) + v.up * (sy * d);
}

// The cascades' clip-space cubes hold their slices (the view depths each
// serves, its hand-over band from the previous cascade included): every
// corner of every slice, for symmetric and skewed frusta, cameras on the
// ground and high up, low and high suns and one along the planet's axis
// (where the light's frame changes its reference axis); also after the
// depth range is extended towards the sun. The slices tile the view depths
// from the nearest ground to the shadow distance.
TEST(GlobeShadowCascades, SliceCornersProjectInsideTheirClipCubes) {
  const double radius = kEarthRadius;
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.3, 0.5, 0.8));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  std::vector<ShadowView> views;
  for (const glm::dvec3& sun : {glm::normalize(north + 0.05 * up), glm::normalize(up + 0.2 * east),
                                glm::dvec3(0.01, 0.0, 0.99995), glm::normalize(-east + 0.3 * up)}) {
    views.push_back(shadow_view(up * (radius + 2.0), north - 0.1 * up, up, 16.0 / 9.0, sun, 1.3, 20e3));
    views.push_back(shadow_view(up * (radius + 10e3), north - 0.6 * up, up, 1.0, sun, 8e3, 30e3));
    ShadowView skewed = shadow_view(up * (radius + 300.0), east - 0.3 * up, up, 1.5, sun, 150.0, 5e3);
    skewed.x_min = -0.3;
    skewed.x_max = 1.2;
    skewed.y_min = -0.9;
    skewed.y_max = 0.2;
    views.push_back(skewed);
  }
  int checked = 0;
  for (const ShadowView& v : views)
    for (const int count : {1, 2, 4})
      for (const int size : {512, 2048}) {
        const ShadowLight light = atmos::planet::shadow_light(v.sun);
        std::vector<ShadowCascade> cascades = atmos::planet::fit_shadow_cascades(v, light, count, size);
        ASSERT_EQ(cascades.size(), size_t(count));
        EXPECT_LE(cascades.front().near_depth_m, v.nearest_depth_m);
        EXPECT_GT(cascades.front().near_depth_m, v.nearest_depth_m / std::exp2(0.25) - 1e-9);
        EXPECT_EQ(cascades.back().far_depth_m, v.shadow_distance_m);
        for (size_t i = 0; i < cascades.size(); ++i) {
          ShadowCascade& c = cascades[i];
          EXPECT_LT(c.near_depth_m, c.blend_start_m);
          EXPECT_LT(c.blend_start_m, c.far_depth_m);
          if (i > 0) {
            EXPECT_EQ(c.near_depth_m, cascades[i - 1].blend_start_m);
          }
          EXPECT_NEAR(c.texel_m, 2.0 * c.half_size_m / size, 1e-12 * c.half_size_m);
          for (const double extend : {0.0, 3000.0}) {
            if (extend > 0.0) atmos::planet::extend_towards_sun(c, c.z_near_m + extend, 1e6);
            const glm::dmat4 m = atmos::planet::cascade_clip_from_planet(light, c);
            for (const double d : {c.near_depth_m, c.far_depth_m})
              for (const double sx : {v.x_min, v.x_max})
                for (const double sy : {v.y_min, v.y_max}) {
                  const glm::dvec4 clip = m * glm::dvec4(frustum_point(v, d, sx, sy), 1.0);
                  EXPECT_EQ(clip.w, 1.0);
                  for (int k = 0; k < 3; ++k)
                    EXPECT_LE(std::abs(clip[k]), 1.0 + 1e-9)
                        << "cascade " << i << " of " << count << ", depth " << d << ", axis " << k;
                  ++checked;
                }
          }
        }
      }
  EXPECT_EQ(checked, 12 * (1 + 2 + 4) * 2 * 2 * 8);
}

// Stable cascades (Valient 2008): when the camera moves by less than a
// texel or turns, each cascade keeps its texel size, and its box moves by
// whole texels of a grid fixed to the planet, so that a point of the
// ground falls at the same place within its texel (no shimmering edges).
TEST(GlobeShadowCascades, TexelGridStaysPutWhenTheCameraMovesOrTurns) {
  const double radius = kEarthRadius;
  const glm::dvec3 up = glm::normalize(glm::dvec3(-0.4, 0.7, 0.2));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const glm::dvec3 sun = glm::normalize(north + 0.3 * east + 0.2 * up);
  const glm::dvec3 camera = up * (radius + 2.0);
  const int size = 1024;
  const ShadowView base = shadow_view(camera, north - 0.15 * up, up, 16.0 / 9.0, sun, 1.5, 20e3);
  const ShadowLight light = atmos::planet::shadow_light(sun);
  const std::vector<ShadowCascade> before = atmos::planet::fit_shadow_cascades(base, light, 4, size);
  ASSERT_EQ(before.size(), 4u);
  // Ground points near the camera and far away.
  const std::vector<glm::dvec3> points = {camera + north * 30.0 - up * 2.0, camera + north * 400.0 + east * 50.0,
                                          camera + north * 3000.0 - east * 700.0, camera + north * 15e3};
  const auto texel_coordinate = [&](const ShadowCascade& c, const glm::dvec3& p) {
    const glm::dvec4 clip = atmos::planet::cascade_clip_from_planet(light, c) * glm::dvec4(p, 1.0);
    return glm::dvec2(clip.x * 0.5 + 0.5, clip.y * 0.5 + 0.5) * double(size);
  };
  std::uint64_t state = 12345;
  const auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) * 0x1.0p-53;
  };
  int moved_boxes = 0, unsnapped_fractions = 0;
  for (int trial = 0; trial < 40; ++trial) {
    ShadowView moved = base;
    if (trial < 20) {
      // A step shorter than the finest texel, in any direction.
      const glm::dvec3 direction =
          glm::normalize(glm::dvec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5) + glm::dvec3(1e-9));
      moved.camera = camera + direction * (0.95 * before[0].texel_m * uniform());
    } else {
      // A turn of the camera (yaw and pitch), in place.
      const double yaw = glm::radians(360.0 * uniform()), pitch = glm::radians(-30.0 + 40.0 * uniform());
      const glm::dvec3 forward =
          (north * std::cos(yaw) + east * std::sin(yaw)) * std::cos(pitch) + up * std::sin(pitch);
      moved = shadow_view(camera, forward, up, 16.0 / 9.0, sun, 1.5, 20e3);
    }
    const std::vector<ShadowCascade> after = atmos::planet::fit_shadow_cascades(moved, light, 4, size);
    ASSERT_EQ(after.size(), before.size());
    for (size_t i = 0; i < after.size(); ++i) {
      EXPECT_EQ(after[i].texel_m, before[i].texel_m) << "trial " << trial << " cascade " << i;
      EXPECT_EQ(after[i].half_size_m, before[i].half_size_m);
      for (const glm::dvec3& p : points) {
        const glm::dvec2 shift = texel_coordinate(after[i], p) - texel_coordinate(before[i], p);
        for (int k = 0; k < 2; ++k)
          EXPECT_NEAR(shift[k], std::round(shift[k]), 1e-6) << "trial " << trial << " cascade " << i;
        if (shift != glm::dvec2(0.0)) ++moved_boxes;
      }
      // Without the snapping the box would have followed the sphere's
      // centre, by a fraction of a texel.
      const glm::dvec3 centre_shift = after[i].centre - before[i].centre;
      const double unsnapped = glm::dot(centre_shift, light.x) / before[i].texel_m;
      if (std::abs(unsnapped - std::round(unsnapped)) > 0.01) ++unsnapped_fractions;
    }
  }
  EXPECT_GT(moved_boxes, 0);          // the boxes did move, by whole texels
  EXPECT_GT(unsnapped_fractions, 20);  // and the snapping was needed for that
}

// How far towards the sun a caster may lie: the sun's ray from any point
// of the sphere (above the lowest ground) is above the highest ground
// beyond that distance.
TEST(GlobeShadowCascades, ShellDistanceBoundsWhereTheSunsRayMeetsTheGround) {
  const double inner = kEarthRadius - 400.0, outer = kEarthRadius + 8800.0;
  std::uint64_t state = 99;
  const auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) * 0x1.0p-53;
  };
  const auto random_unit = [&] {
    const double z = 2.0 * uniform() - 1.0, phi = 6.283185307179586 * uniform(), r = std::sqrt(1.0 - z * z);
    return glm::dvec3(r * std::cos(phi), r * std::sin(phi), z);
  };
  for (int trial = 0; trial < 200; ++trial) {
    const glm::dvec3 up = random_unit();
    const double sphere_radius = std::exp2(2.0 + 14.0 * uniform());
    const glm::dvec3 centre = up * (kEarthRadius + 5000.0 * uniform() - 200.0);
    // Suns from below the horizon to the zenith.
    const glm::dvec3 sun = glm::normalize(random_unit() + up * (2.0 * uniform() - 0.5));
    const double bound = atmos::planet::sun_shell_distance_m(centre, sphere_radius, sun, inner, outer);
    for (int k = 0; k < 50; ++k) {
      const glm::dvec3 p = centre + random_unit() * (sphere_radius * std::cbrt(uniform()));
      if (glm::length(p) < inner) continue;
      // Where the ray p + t sun leaves the highest ground's sphere for good.
      const double b = glm::dot(p, sun), c = glm::dot(p, p) - outer * outer;
      const double exit = b * b - c >= 0.0 ? -b + std::sqrt(b * b - c) : 0.0;
      EXPECT_LE(exit, bound * (1.0 + 1e-9) + 1e-6) << "trial " << trial;
    }
  }
}

// The casters' culling is conservative: a sphere that holds a point of
// the sun's ray from a point of the frustum's part (or of a receiving
// sphere), before the shell distance, is kept; spheres off to the side of
// the sun's rays, or behind the part, are culled.
TEST(GlobeShadowCascades, CasterCullingKeepsEverySphereOnASunRay) {
  const double radius = kEarthRadius;
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.6, -0.2, 0.77));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  std::uint64_t state = 7;
  const auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) * 0x1.0p-53;
  };
  const auto random_unit = [&] {
    const double z = 2.0 * uniform() - 1.0, phi = 6.283185307179586 * uniform(), r = std::sqrt(1.0 - z * z);
    return glm::dvec3(r * std::cos(phi), r * std::sin(phi), z);
  };
  int kept_on_rays = 0, culled_aside = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const glm::dvec3 sun = glm::normalize(random_unit() + up * (0.3 + uniform()));
    const double heading = 6.0 * uniform();
    const glm::dvec3 forward =
        glm::normalize(north * std::cos(heading) + east * std::sin(heading) - up * (0.3 * uniform()));
    const ShadowView v = shadow_view(up * (radius + 2.0 + 500.0 * uniform()), forward, up, 1.7, sun, 1.0, 20e3);
    const ShadowLight light = atmos::planet::shadow_light(sun);
    const double a = 10.0 * std::exp2(8.0 * uniform()), b = a * (1.5 + 4.0 * uniform());
    const double shell = 5000.0 * uniform();
    const atmos::planet::ShadowFootprint frustum = atmos::planet::shadow_footprint(v, light, a, b);
    // Receivers: a few spheres inside the part.
    std::vector<glm::dvec4> receivers;
    for (int k = 0; k < 6; ++k)
      receivers.emplace_back(frustum_point(v, a + (b - a) * uniform(), v.x_min + (v.x_max - v.x_min) * uniform(),
                                           v.y_min + (v.y_max - v.y_min) * uniform()),
                             5.0 + 50.0 * uniform());
    const atmos::planet::ShadowFootprint spheres = atmos::planet::sphere_footprint(light, receivers);
    for (int k = 0; k < 100; ++k) {
      const double t = shell * uniform();
      // A point of the part, and one of a receiving sphere.
      const glm::dvec3 p = frustum_point(v, a + (b - a) * uniform(), v.x_min + (v.x_max - v.x_min) * uniform(),
                                         v.y_min + (v.y_max - v.y_min) * uniform());
      const glm::dvec4& r = receivers[size_t(k) % receivers.size()];
      const glm::dvec3 q = glm::dvec3(r) + random_unit() * (r.w * uniform());
      const double caster_radius = 1.0 + 100.0 * uniform();
      const glm::dvec3 offset = random_unit() * (caster_radius * uniform());
      EXPECT_TRUE(atmos::planet::may_cast_onto(frustum, light, p + sun * t + offset, caster_radius, 0.0, shell))
          << "trial " << trial << " point " << k;
      EXPECT_TRUE(atmos::planet::may_cast_onto(spheres, light, q + sun * t + offset, caster_radius, 0.0, shell))
          << "trial " << trial << " point " << k;
      kept_on_rays += 2;
      // Across the sun, well beyond the part and the receivers.
      const glm::dvec3 across = glm::normalize(glm::cross(sun, random_unit()));
      const glm::dvec3 aside = p + across * (3.0 * b + 4.0 * b * uniform() + 300.0) + sun * t;
      if (!atmos::planet::may_cast_onto(frustum, light, aside, caster_radius, 0.0, shell)) ++culled_aside;
      // Behind the part, away from the sun.
      EXPECT_FALSE(atmos::planet::may_cast_onto(frustum, light, p - sun * (3.0 * b + 4.0 * caster_radius + 1.0),
                                                caster_radius, 0.0, shell));
    }
  }
  EXPECT_EQ(kept_on_rays, 40 * 100 * 2);
  EXPECT_GT(culled_aside, 40 * 100 * 9 / 10);
}

// Zhang et al. 2006's practical split at its two ends: logarithmic and uniform.
TEST(GlobeShadowCascades, PracticalSplitsBlendLogarithmicAndUniform) {
  const std::vector<double> log_split = atmos::planet::practical_splits(2.0, 2e4, 4, 1.0);
  const std::vector<double> uniform_split = atmos::planet::practical_splits(2.0, 2e4, 4, 0.0);
  const std::vector<double> half = atmos::planet::practical_splits(2.0, 2e4, 4, 0.5);
  ASSERT_EQ(log_split.size(), 5u);
  for (int i = 0; i <= 4; ++i) {
    EXPECT_NEAR(log_split[size_t(i)], 2.0 * std::pow(1e4, i / 4.0), 1e-9 * log_split[size_t(i)]);
    EXPECT_NEAR(uniform_split[size_t(i)], 2.0 + (2e4 - 2.0) * i / 4.0, 1e-9);
    EXPECT_NEAR(half[size_t(i)], 0.5 * (log_split[size_t(i)] + uniform_split[size_t(i)]), 1e-9);
  }
}


}  // namespace
