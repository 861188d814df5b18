// The terrain globe (include/atmos/globe.hpp): its tile meshes on the CPU
// (morph targets, shared edges, skirts, precision) and its sun's shadow
// cascades (fit, snapping, culling), and on the GPU a scripted descent from
// 100 planet radii to a metre with no hole in the surface, its lighting
// under the atmosphere and in an eclipse, no popping as levels change, the
// terrain's shadows, and bad input.
#include <gtest/gtest.h>

#include <epoxy/gl.h>
#include <gdal.h>
#include <ogr_srs_api.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "atmos/globe.hpp"
#include "atmos/plugin.hpp"
#include "globe_rays.hpp"
#include "fullscreen_program.hpp"
#include "globe_target.hpp"
#include "gpu_fixture.hpp"
#include "physics/eclipse_cpp.hpp"
#include "physics/moons.hpp"
#include "physics/parameters.hpp"
#include "physics/ray_integration_cpp.hpp"
#include "planet/globe_internal.hpp"
#include "planet/globe_mesh.hpp"
#include "planet/globe_shadows.hpp"
#include "runtime/table_samplers.hpp"

namespace {

using atmos::planet::kGridVertices;
using atmos::planet::kSkirtVertices;
using atmos::planet::kTileQuads;
using atmos::planet::kTileSide;
using atmos::planet::MeshBuilder;
using atmos::planet::Surface;
using atmos::planet::TileKey;
using atmos::planet::TileMesh;

constexpr double kEarthRadius = 6360e3;

atmos::PlanetSurface surface_of(atmos::SurfaceStyle style, std::uint64_t seed,
                                std::optional<double> sea_level_m = std::nullopt) {
  atmos::PlanetSurface s;
  s.style = style;
  s.seed = seed;
  s.sea_level_m = sea_level_m;
  return s;
}

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

// ---------------------------------------------------------------------------
// The GPU: the globe drawn into a small reversed-Z framebuffer.

class GlobeGpu : public atmos_test::EarthGpuTest {
 protected:
  static void SetUpTestSuite() {
    EarthGpuTest::SetUpTestSuite();
    if (context_ == nullptr) return;
    pass_ = std::make_unique<atmos::AtmospherePass>(*earth_, *tables_, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  }
  static void TearDownTestSuite() {
    pass_.reset();
    EarthGpuTest::TearDownTestSuite();
  }

  using Target = atmos_test::GlobeTarget;

  static atmos::GlobeView view_from(const glm::dvec3& camera, const glm::dvec3& forward, const glm::dvec3& up_hint,
                                    int width, int height) {
    atmos::GlobeView v;
    v.view = glm::lookAt(camera, camera + forward, up_hint);
    v.projection = atmos::reversed_z_projection(glm::radians(60.0), double(width) / height, 0.05);
    v.width = width;
    v.height = height;
    v.sun_direction = glm::normalize(glm::dvec3(0.2, 0.4, 1.0));
    v.nits_per_unit = 1000.0;
    return v;
  }

  // The same view drawn by a globe without and one with shadows.
  struct Images {
    std::vector<float> off, on, depth_off, depth_on;
  };
  static Images draw_both(atmos::Globe& off, atmos::Globe& on, const atmos::GlobeView& view, Target& target) {
    Images images;
    target.clear();
    off.draw(view);
    images.off = target.read_colour();
    images.depth_off = target.read_depth();
    target.clear();
    on.draw(view);
    images.on = target.read_colour();
    images.depth_on = target.read_depth();
    return images;
  }
  static atmos::GlobeSettings shadow_settings(int cascades) {
    atmos::GlobeSettings settings;
    settings.complete_every_frame = true;
    settings.max_screen_error_px = 0.5;
    settings.shadow_cascades = cascades;
    settings.shadow_map_size = 1024;
    settings.shadow_distance_m = 12e3;
    return settings;
  }

  static inline std::unique_ptr<atmos::AtmospherePass> pass_;
};

using atmos_test::pixel_ray;
using atmos_test::ray_hits_sphere;

// A descent from 100 planet radii to a metre above the ground, looking down
// from afar and towards the horizon near the ground: wherever a pixel's ray
// meets a sphere below all of the relief (and below the chords of the
// coarsest tiles), the globe must have drawn something. No crack between
// tiles of different levels, no hole where tiles change.
TEST_F(GlobeGpu, DescentFromOrbitToTheGroundHasNoHoles) {
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  atmos::Globe globe(*earth_, surface_of(atmos::SurfaceStyle::earth, 1), *pass_, settings);
  const int width = 160, height = 90;
  Target target(width, height);
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.2, -0.6, 0.77));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const double radius = earth_->bottom_radius_m;
  const double ground = radius + globe.height_m(up * radius);
  // Below the relief, and below the chord of a level-1 tile edge.
  const double inner = radius + globe.min_height_m() - 8e3;
  const int frames = 24;
  int holes = 0, covered = 0;
  std::string first_hole;
  for (int f = 0; f < frames; ++f) {
    const double altitude = std::exp(std::log(100.0 * radius) + (std::log(1.0) - std::log(100.0 * radius)) * f / (frames - 1));
    // Pitch from straight down (far) to 10 degrees below the horizon (near).
    const double w = std::clamp(std::log10(altitude / 1e3) / std::log10(100.0 * radius / 1e3), 0.0, 1.0);
    const double pitch = glm::radians(-10.0 + (-90.0 + 10.0) * w);
    const glm::dvec3 forward = glm::normalize(north * std::cos(pitch) + up * std::sin(pitch));
    const glm::dvec3 camera = up * (ground + altitude);
    const atmos::GlobeView view = view_from(camera, forward, std::abs(pitch) > 1.5 ? north : up, width, height);
    target.clear();
    globe.draw(view);
    ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    const std::vector<float> depth = target.read_depth();
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        if (!ray_hits_sphere(camera, pixel_ray(view, x, y), inner)) continue;
        ++covered;
        if (depth[size_t(y * width + x)] > 0.0f) continue;
        if (holes++ == 0)
          first_hole = "frame " + std::to_string(f) + " altitude " + std::to_string(altitude) + " m, pixel (" +
                       std::to_string(x) + ", " + std::to_string(y) + ")";
      }
    EXPECT_EQ(globe.last_stats().tiles_pending, 0);
  }
  EXPECT_GT(covered, frames * width * height / 4);
  EXPECT_EQ(holes, 0) << "first at " << first_hole;
}

// Streaming: at most max_tiles_per_frame new tiles a frame, the others
// drawn by their nearest resident ancestor meanwhile, so that no hole opens
// while tiles load; the resident tiles stay under the memory cap (least
// recently drawn evicted first) while the camera descends and then pans.
// While the camera descends, each view is drawn again, 5 ms apart, until
// the background thread has nothing left to build or upload for it, so
// that what is generated (more than the cap holds) does not depend on its
// speed; while it pans, each view is drawn once.
TEST_F(GlobeGpu, StreamedTilesLeaveNoHoleAndStayUnderTheMemoryCap) {
  atmos::GlobeSettings settings;
  settings.max_tiles_per_frame = 12;
  settings.memory_cap_bytes = std::size_t(4) << 20;
  atmos::Globe globe(*earth_, surface_of(atmos::SurfaceStyle::earth, 5), *pass_, settings);
  const int width = 128, height = 72;
  Target target(width, height);
  const double radius = earth_->bottom_radius_m;
  const double inner = radius + globe.min_height_m() - 8e3;
  int holes = 0, pending_frames = 0, max_generated = 0, generated = 0;
  std::size_t max_resident = 0;
  for (int f = 0; f < 40; ++f) {
    // Down from 1000 km to 2 km over 20 frames, then around the planet.
    const double altitude = f < 20 ? 1e6 * std::pow(2e-3, f / 19.0) : 2e3;
    const double longitude = f < 20 ? 0.0 : 0.02 * (f - 19);
    const glm::dvec3 up(std::cos(longitude), std::sin(longitude), 0.0);
    const glm::dvec3 east(-std::sin(longitude), std::cos(longitude), 0.0);
    const glm::dvec3 camera = up * (radius + globe.height_m(up * radius) + altitude);
    const glm::dvec3 forward = glm::normalize(east - 0.4 * up);
    const atmos::GlobeView view = view_from(camera, forward, up, width, height);
    // Done after two draws in a row with nothing queued nor uploaded.
    const int draws = f < 20 ? 2000 : 1;
    for (int again = 0, idle = 0; again < draws && idle < 2; ++again) {
      if (again > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      target.clear();
      globe.draw(view);
      const atmos::GlobeStats& stats = globe.last_stats();
      max_generated = std::max(max_generated, stats.tiles_generated);
      generated += stats.tiles_generated;
      max_resident = std::max(max_resident, stats.resident_bytes);
      pending_frames += stats.tiles_pending > 0 ? 1 : 0;
      const std::vector<float> depth = target.read_depth();
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
          if (ray_hits_sphere(camera, pixel_ray(view, x, y), inner) && !(depth[size_t(y * width + x)] > 0.0f))
            ++holes;
      idle = stats.tiles_queued == 0 && stats.tiles_generated == 0 ? idle + 1 : 0;
    }
  }
  EXPECT_EQ(holes, 0);
  EXPECT_LE(max_generated, settings.max_tiles_per_frame);
  EXPECT_GT(pending_frames, 0);  // the bound was reached: stand-ins were drawn
  EXPECT_LE(max_resident, settings.memory_cap_bytes);
  // More tiles were made than the cap holds: eviction was exercised.
  const std::size_t tile_bytes = (kGridVertices + kSkirtVertices) * sizeof(atmos::planet::TileVertex);
  EXPECT_GT(std::size_t(generated + 6) * tile_bytes, settings.memory_cap_bytes);
}

// Lit by the atmosphere: finite, non-negative colour everywhere the globe
// drew; bright on the day side, dark on the night side.
TEST_F(GlobeGpu, DaySideIsLitAndNightSideIsDark) {
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  atmos::Globe globe(*earth_, surface_of(atmos::SurfaceStyle::earth, 3), *pass_, settings);
  const int width = 96, height = 96;
  Target target(width, height);
  const double radius = earth_->bottom_radius_m;
  const glm::dvec3 camera(0.0, -3.0 * radius, 0.0);
  atmos::GlobeView view = view_from(camera, glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1), width, height);
  view.sun_direction = glm::dvec3(1.0, 0.0, 0.0);  // the right half of the disc is day
  target.clear();
  globe.draw(view);
  const std::vector<float> colour = target.read_colour();
  double day = 0.0, night = 0.0;
  int day_pixels = 0, night_pixels = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float* c = &colour[size_t(4 * (y * width + x))];
      if (c[0] == -1.0f) continue;  // not drawn
      for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(std::isfinite(c[k]));
        ASSERT_GE(c[k], 0.0f);
      }
      const double luminance = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
      // Away from the terminator (the disc's vertical diameter).
      if (x > width / 2 + 8) day += luminance, ++day_pixels;
      if (x < width / 2 - 8) night += luminance, ++night_pixels;
    }
  ASSERT_GT(day_pixels, 100);
  ASSERT_GT(night_pixels, 100);
  // cd/m² / 1000: a sunlit ground of mean albedo ~0.12 (the earth style's
  // sea, 0.06 over 71 %, and land ~0.25) is ~10^3 cd/m² and more.
  EXPECT_GT(day / day_pixels, 0.4);
  EXPECT_LT(night / night_pixels, 1e-3 * (day / day_pixels));
}

// New tables for the same ground: a globe rebound to another pass draws
// what a new globe built with that pass draws, bit for bit, and a rebind
// it refuses (another datum) leaves it bound to the pass it had.
TEST_F(GlobeGpu, RebindDrawsAsANewGlobeWithTheNewPass) {
  atmos::Atmosphere dense = *earth_;
  atmos::scale_density(dense, 4.0);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables dense_tables = atmos::precompute_tables(dense, options);
  const atmos::AtmospherePass dense_pass(dense, dense_tables, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  const atmos::PlanetSurface surface = surface_of(atmos::SurfaceStyle::earth, 3);
  atmos::Globe globe(*earth_, surface, *pass_, settings);
  const int width = 64, height = 64;
  Target target(width, height);
  const double radius = earth_->bottom_radius_m;
  const atmos::GlobeView view =
      view_from(glm::dvec3(0.0, -3.0 * radius, 0.0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1), width, height);
  const auto draw = [&](atmos::Globe& g) {
    target.clear();
    g.draw(view);
    return target.read_colour();
  };
  const std::vector<float> thin = draw(globe);
  globe.rebind(dense, dense_pass);
  const std::vector<float> rebound = draw(globe);
  atmos::Globe fresh(dense, surface, dense_pass, settings);
  EXPECT_EQ(rebound, draw(fresh));
  // The same with the programs linked beforehand (link_rebind_programs, as
  // a thread of a shared context does); those of another pass are not taken.
  atmos::Globe prelinked(*earth_, surface, *pass_, settings);
  prelinked.link_rebind_programs(dense_pass);
  prelinked.rebind(dense, dense_pass);
  EXPECT_EQ(draw(prelinked), rebound);
  prelinked.link_rebind_programs(dense_pass);
  prelinked.rebind(*earth_, *pass_);
  EXPECT_EQ(draw(prelinked), thin);
  // The denser air dims the sunlight on the ground.
  double thin_sum = 0.0, dense_sum = 0.0;
  for (size_t k = 0; k < thin.size(); k += 4)
    if (thin[k] != -1.0f) thin_sum += thin[k + 1], dense_sum += rebound[k + 1];
  EXPECT_LT(dense_sum, 0.99 * thin_sum);

  atmos::Atmosphere other_datum = dense;
  other_datum.bottom_radius_m += 1000.0;
  other_datum.top_radius_m += 1000.0;
  EXPECT_THROW(globe.rebind(other_datum, *pass_), atmos::Error);
  EXPECT_EQ(draw(globe), rebound);
}

// Mars's lowlands lie kilometres below its datum: lit and composited by the
// pass of extend_below_datum's atmosphere, the ground there is finite and
// sunlit, and so is the final image.
TEST_F(GlobeGpu, GroundBelowTheDatumIsLitByTheExtendedAtmosphere) {
  const atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  const atmos::PlanetSurface surface = surface_of(atmos::SurfaceStyle::mars, 2);
  const atmos::Atmosphere air = atmos::extend_below_datum(mars, surface);
  ASSERT_LT(air.bottom_radius_m, mars.bottom_radius_m - 4e3);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(air, options);
  const atmos::AtmospherePass pass(air, tables, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  // A coarse mesh (4 px): the light below the datum is what is tested, and
  // the Mars style's craters make fine tiles slow to generate.
  settings.max_screen_error_px = 4.0;
  atmos::Globe globe(mars, surface, pass, settings);
  // The lowest of a few hundred points: a lowland below the datum.
  glm::dvec3 lowest(0, 0, 1);
  double lowest_height = INFINITY;
  for (int i = 0; i < 400; ++i) {
    const double z = -1.0 + (i + 0.5) / 200.0, phi = 2.399963 * i, r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const glm::dvec3 d(r * std::cos(phi), r * std::sin(phi), z);
    const double h = globe.height_m(d * mars.bottom_radius_m);
    if (h < lowest_height) {
      lowest_height = h;
      lowest = d;
    }
  }
  ASSERT_LT(lowest_height, -2000.0);
  const double radius = mars.bottom_radius_m;
  const glm::dvec3 camera = lowest * (radius + lowest_height + 3000.0);
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), lowest));
  const int width = 64, height = 48;
  atmos::GlobeView view = view_from(camera, glm::normalize(east - lowest), lowest, width, height);
  view.sun_direction = glm::normalize(lowest + 0.5 * east);
  Target target(width, height);
  target.clear();
  globe.draw(view);
  const std::vector<float> lit = target.read_colour();
  int drawn = 0;
  for (size_t k = 0; k < lit.size(); k += 4) {
    if (lit[k] == -1.0f) continue;  // not drawn
    ++drawn;
    ASSERT_TRUE(std::isfinite(lit[k]) && std::isfinite(lit[k + 1]) && std::isfinite(lit[k + 2])) << k;
    EXPECT_GT(lit[k] + lit[k + 1] + lit[k + 2], 0.0f) << k;
  }
  EXPECT_GT(drawn, width * height / 4);
}


// ---------------------------------------------------------------------------
// Sun shadows on the GPU: a plain with one mountain.

// A smooth mountain (a Gaussian kMountainHeight_m high, kMountainWidth_m in
// e-folding radius) centred at kMountainLat/Lon on an otherwise flat plain at
// the datum: a GeoTIFF in GDAL's memory file system, drawn with the flat
// style, which adds no relief of its own.
constexpr double kMountainLat = 10.0, kMountainLon = 20.0;
constexpr double kMountainHeight_m = 800.0, kMountainWidth_m = 1500.0;

glm::dvec3 geographic_direction(double lat_deg, double lon_deg) {
  const double lat = glm::radians(lat_deg), lon = glm::radians(lon_deg);
  return {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

atmos::PlanetSurface mountain_surface(double radius_m) {
  static const std::string path = [radius_m] {
    GDALAllRegister();
    const std::string p = "/vsimem/atmos_globe_test_mountain.tif";
    const int n = 256;
    const double half = 0.12;  // degrees: 27 km across
    const double west = kMountainLon - half, north = kMountainLat + half, step = 2.0 * half / n;
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), p.c_str(), n, n, 1, GDT_Float32, nullptr);
    double gt[6] = {west, step, 0.0, north, 0.0, -step};
    GDALSetGeoTransform(ds, gt);
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    OSRSetFromUserInput(srs, "EPSG:4326");
    GDALSetSpatialRef(ds, srs);
    OSRDestroySpatialReference(srs);
    const glm::dvec3 top = geographic_direction(kMountainLat, kMountainLon);
    std::vector<float> heights(size_t(n) * size_t(n));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const glm::dvec3 d = geographic_direction(north + (j + 0.5) * gt[5], west + (i + 0.5) * gt[1]);
        const double r = radius_m * std::acos(std::clamp(glm::dot(d, top), -1.0, 1.0));
        heights[size_t(j * n + i)] =
            float(kMountainHeight_m * std::exp(-(r * r) / (kMountainWidth_m * kMountainWidth_m)));
      }
    GDALRasterBandH band = GDALGetRasterBand(ds, 1);
    GDALSetRasterUnitType(band, "m");
    EXPECT_EQ(GDALRasterIO(band, GF_Write, 0, 0, n, n, heights.data(), n, n, GDT_Float32, 0, 0), CE_None);
    GDALClose(ds);
    return p;
  }();
  atmos::PlanetSurface s = surface_of(atmos::SurfaceStyle::flat, 1);
  s.elevation.source = path;
  return s;
}

// The mountain's local frame: up through its top, east, north.
struct LocalFrame {
  double radius_m;  // the datum
  glm::dvec3 up, east, north;
  explicit LocalFrame(double datum_radius_m) : radius_m(datum_radius_m) {
    up = geographic_direction(kMountainLat, kMountainLon);
    east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
    north = glm::cross(up, east);
  }
  // A point `height` m above the datum at (x east, y north) m from the top's foot.
  glm::dvec3 at(double x, double y, double height) const {
    return glm::normalize(up * radius_m + east * x + north * y) * (radius_m + height);
  }
  glm::dvec3 direction(double azimuth_deg, double elevation_deg) const {
    const double a = glm::radians(azimuth_deg), e = glm::radians(elevation_deg);
    return glm::normalize((north * std::cos(a) + east * std::sin(a)) * std::cos(e) + up * std::sin(e));
  }
};

// The sun's ray from `point` (planet-centred m; `frame`: the globe's
// pass's) over the drawn relief (Globe::height_m), in
// steps of 20 m until it is above the highest ground: the lowest clearance
// of the ray above the ground below it (m), and whether it stays above
// min(margin, 0.05 t) at every distance t (a point clearly in sunlight).
struct SunRay {
  double lowest_clearance_m = INFINITY;
  bool clear = true;
};
SunRay march_to_sun(const atmos::Globe& globe, const atmos::PlanetFrame& frame, double radius_m,
                    const glm::dvec3& point, const glm::dvec3& sun, double margin_m) {
  SunRay ray;
  for (double t = 10.0; t < 40e3; t += 20.0) {
    const glm::dvec3 x = point + sun * t;
    const double altitude = glm::length(x) - radius_m;
    if (altitude > globe.max_height_m() + 1.0) break;
    const double clearance = altitude - globe.height_m(frame.centre + x * frame.units_per_metre);
    ray.lowest_clearance_m = std::min(ray.lowest_clearance_m, clearance);
    if (clearance < std::min(margin_m, 0.05 * t)) ray.clear = false;
  }
  return ray;
}

double luminance(const float* c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

// The world point drawn at pixel (x, y) from the reversed-Z depth buffer of
// a view of reversed_z_projection (depth = near / view depth).
glm::dvec3 pixel_point(const atmos::GlobeView& view, int x, int y, float depth) {
  const glm::dmat4& p = view.projection;
  const double d = p[3][2] / double(depth);
  const glm::dvec4 in_view(((x + 0.5) / view.width * 2.0 - 1.0) * d / p[0][0],
                           ((y + 0.5) / view.height * 2.0 - 1.0) * d / p[1][1], -d, 1.0);
  return glm::dvec3(glm::inverse(view.view) * in_view);
}

// A mountain casts its shadow at a low sun: the ground behind it (the sun's
// ray from there passes through the mountain, by the CPU's march over
// Globe::height_m) is darker with shadows than without, by the sun's part
// of its light; the ground in full sun keeps its colour within 1 %. The
// farthest cascade, handed to the engine plugin, removes the light the
// shadowed air no longer scatters (light shafts): the air in front of the
// shadow is darker with it than without. In an engine's world of
// kilometres, the planet's centre away from its origin.
TEST_F(GlobeGpu, ShadowsOfAMountainDarkenTheGroundBehindItAtALowSun) {
  // An engine whose world is in kilometres, the planet's centre away from
  // its origin.
  atmos::PlanetFrame frame;
  frame.centre = glm::dvec3(1200.0, -300.0, 450.0);
  frame.units_per_metre = 1e-3;
  const auto world = [&](const glm::dvec3& planet_m) { return frame.centre + planet_m * frame.units_per_metre; };
  const auto planet = [&](const glm::dvec3& world_point) {
    return (world_point - frame.centre) / frame.units_per_metre;
  };
  atmos::AtmospherePass pass(*earth_, *tables_, frame, atmos::PassPrograms::none);
  const atmos::PlanetSurface surface = mountain_surface(earth_->bottom_radius_m);
  atmos::Globe off(*earth_, surface, pass, shadow_settings(0));
  atmos::Globe on(*earth_, surface, pass, shadow_settings(4));
  ASSERT_GT(on.max_height_m(), 790.0);
  const LocalFrame local(earth_->bottom_radius_m);
  // The sun 8 degrees above the eastern horizon: the shadow runs 5.7 km
  // west. The camera, 2 km up, south-west of the mountain, looks north
  // and down.
  const glm::dvec3 sun = local.direction(90.0, 8.0);
  const glm::dvec3 camera = local.at(-2500.0, -5000.0, 2000.0);
  const int width = 128, height = 96;
  atmos::GlobeView view = view_from(world(camera), glm::normalize(local.north + 0.15 * local.east - 0.45 * local.up),
                                    local.up, width, height);
  view.projection =
      atmos::reversed_z_projection(glm::radians(60.0), double(width) / height, 0.05 * frame.units_per_metre);
  view.sun_direction = sun;
  Target target(width, height);
  const Images images = draw_both(off, on, view, target);
  EXPECT_EQ(images.depth_on, images.depth_off);  // the same surface
  EXPECT_EQ(on.last_stats().shadow_cascades, 4);
  EXPECT_GT(on.last_stats().shadow_casters, 4);
  EXPECT_EQ(off.last_stats().shadow_cascades, 0);

  // Margins: the mesh's error and a few texels of the coarsest cascade.
  const atmos::GlobeShadowMap for_pass = on.shadow_map_for_pass();
  ASSERT_NE(for_pass.texture, 0u);
  const double margin = 30.0 + 3.0 * for_pass.texel_m;
  std::vector<double> shadowed_ratios, lit_ratios;
  std::vector<size_t> shadowed_pixels;
  for (int y = 0; y < height; y += 2)
    for (int x = 0; x < width; x += 2) {
      const size_t i = size_t(y * width + x);
      if (!(images.depth_on[i] > 0.0f)) continue;
      const glm::dvec3 point = planet(pixel_point(view, x, y, images.depth_on[i]));
      const SunRay ray = march_to_sun(on, frame, earth_->bottom_radius_m, point, sun, margin);
      const double ratio = luminance(&images.on[4 * i]) / luminance(&images.off[4 * i]);
      if (ray.lowest_clearance_m < -margin && on.height_m(world(point)) < 10.0) {  // the plain behind the mountain
        shadowed_ratios.push_back(ratio);
        shadowed_pixels.push_back(i);
      } else if (ray.clear) {
        lit_ratios.push_back(ratio);
      }
    }
  ASSERT_GE(shadowed_ratios.size(), 20u);
  ASSERT_GE(lit_ratios.size(), 200u);
  // In the shadow only the sky's light is left: at this low sun the sky
  // gives the plain about two thirds of its light, the sun a third.
  int dark = 0;
  for (const double r : shadowed_ratios) dark += r < 0.85 ? 1 : 0;
  EXPECT_GE(dark, int(0.95 * double(shadowed_ratios.size())));
  int unchanged = 0;
  for (const double r : lit_ratios) unchanged += std::abs(r - 1.0) <= 0.01 ? 1 : 0;
  EXPECT_EQ(unchanged, int(lit_ratios.size()));
  RecordProperty("shadowed_pixels", int(shadowed_ratios.size()));
  RecordProperty("lit_pixels", int(lit_ratios.size()));

  // The plugin's light shafts from the farthest cascade.
  atmos::FrameInput input;
  input.colour = target.colour;
  input.depth = target.depth;
  input.width = width;
  input.height = height;
  input.depth_encoding = atmos::DepthEncoding::reversed_z;
  input.view = view.view;
  input.projection = view.projection;
  input.sun_direction = sun;
  input.nits_per_unit = view.nits_per_unit;
  const auto composite = [&](bool shafts) {
    input.shadow_map = shafts ? for_pass.texture : 0u;
    input.shadow_matrix = for_pass.matrix;
    std::vector<float> out(size_t(width * height * 4));
    const GLuint texture = pass.render(input);
    glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT, GLsizei(out.size() * sizeof(float)), out.data());
    return out;
  };
  // `target` still holds the shadowed image.
  const std::vector<float> without = composite(false), with = composite(true);
  ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  double in_shadow_without = 0.0, in_shadow_with = 0.0;
  for (const size_t i : shadowed_pixels) {
    in_shadow_without += luminance(&without[4 * i]);
    in_shadow_with += luminance(&with[4 * i]);
  }
  EXPECT_LT(in_shadow_with, 0.99 * in_shadow_without);
  // The shadow map's matrix maps the shadowed ground into its clip cube.
  for (const size_t i : shadowed_pixels) {
    const int x = int(i % size_t(width)), y = int(i / size_t(width));
    const glm::dvec4 clip = for_pass.matrix * glm::dvec4(pixel_point(view, x, y, images.depth_on[i]), 1.0);
    EXPECT_LE(std::max({std::abs(clip.x), std::abs(clip.y), std::abs(clip.z)}), 1.0);
  }
}

// No self-shadowing ("acne") on sunlit ground: from 2 m above the plain,
// the sun 12 degrees up behind the camera, the plain (lit at 78 degrees from
// its normal) and the mountain's flank facing the sun keep their colour
// within 1 % in more than 99 % of the pixels the sun's ray clearly reaches,
// through every cascade and every hand-over band between them.
TEST_F(GlobeGpu, ShadowsLeaveSunlitSlopesUnchanged) {
  const atmos::PlanetSurface surface = mountain_surface(earth_->bottom_radius_m);
  atmos::Globe off(*earth_, surface, *pass_, shadow_settings(0));
  atmos::Globe on(*earth_, surface, *pass_, shadow_settings(4));
  const LocalFrame local(earth_->bottom_radius_m);
  const glm::dvec3 sun = local.direction(200.0, 12.0);
  const glm::dvec3 camera = local.at(300.0, -3500.0, on.height_m(local.at(300.0, -3500.0, 0.0)) + 2.0);
  const int width = 128, height = 96;
  atmos::GlobeView view = view_from(camera, glm::normalize(local.north + 0.08 * local.up), local.up, width, height);
  view.sun_direction = sun;
  Target target(width, height);
  const Images images = draw_both(off, on, view, target);
  EXPECT_EQ(on.last_stats().shadow_cascades, 4);
  const double margin = 30.0 + 3.0 * on.shadow_map_for_pass().texel_m;
  int lit = 0, unchanged = 0, flank = 0;
  for (int y = 0; y < height; y += 2)
    for (int x = 0; x < width; x += 2) {
      const size_t i = size_t(y * width + x);
      if (!(images.depth_on[i] > 0.0f)) continue;
      const glm::dvec3 point = pixel_point(view, x, y, images.depth_on[i]);
      if (!march_to_sun(on, atmos::PlanetFrame{}, earth_->bottom_radius_m, point, sun, margin).clear) continue;
      ++lit;
      flank += on.height_m(point) > 100.0 ? 1 : 0;
      const double ratio = luminance(&images.on[4 * i]) / luminance(&images.off[4 * i]);
      unchanged += std::abs(ratio - 1.0) <= 0.01 ? 1 : 0;
    }
  ASSERT_GE(lit, 1000);
  EXPECT_GE(flank, 100);
  EXPECT_GT(double(unchanged), 0.99 * double(lit));
  RecordProperty("lit_pixels", lit);
  RecordProperty("unchanged_pixels", unchanged);
}

// Shadows off draw the unshadowed image, bit for bit: the default settings
// (no shadows) and a globe with shadows whose view has no ground within the
// shadows' reach (from orbit, where no shadow map is drawn) draw the same
// pixels; within reach but with nothing to shadow (the plain under a high
// sun), the image with shadows differs only by float rounding (the sun's
// and the sky's light then interpolated apart; a few more ulps in the long
// triangles at the horizon).
TEST_F(GlobeGpu, ShadowsOffDrawTheUnshadowedImage) {
  const atmos::PlanetSurface surface = mountain_surface(earth_->bottom_radius_m);
  atmos::GlobeSettings defaults;
  defaults.complete_every_frame = true;
  defaults.max_screen_error_px = 0.5;
  atmos::Globe off(*earth_, surface, *pass_, defaults);
  atmos::Globe on(*earth_, surface, *pass_, shadow_settings(3));
  const LocalFrame local(earth_->bottom_radius_m);
  const int width = 96, height = 64;
  Target target(width, height);
  {
    const glm::dvec3 camera = local.up * (3.0 * earth_->bottom_radius_m);
    atmos::GlobeView view = view_from(camera, -local.up, local.north, width, height);
    view.sun_direction = local.direction(120.0, 30.0);
    const Images images = draw_both(off, on, view, target);
    EXPECT_EQ(on.last_stats().shadow_cascades, 0);
    EXPECT_EQ(on.shadow_map_for_pass().texture, 0u);
    EXPECT_EQ(images.on, images.off);
    EXPECT_EQ(images.depth_on, images.depth_off);
  }
  {
    // Far from the mountain, the sun near the zenith.
    const glm::dvec3 camera = local.at(0.0, -40e3, 50.0);
    atmos::GlobeView view = view_from(camera, glm::normalize(-local.north - 0.3 * local.up), local.up, width, height);
    view.sun_direction = local.direction(0.0, 85.0);
    const Images images = draw_both(off, on, view, target);
    EXPECT_GT(on.last_stats().shadow_cascades, 0);
    int drawn = 0;
    double worst = 0.0;
    for (size_t i = 0; i < images.depth_on.size(); ++i) {
      if (!(images.depth_on[i] > 0.0f)) continue;
      ++drawn;
      for (int k = 0; k < 3; ++k) {
        const double e = std::abs(double(images.on[4 * i + size_t(k)]) - images.off[4 * i + size_t(k)]) /
                                    std::max(double(images.off[4 * i + size_t(k)]), 1e-6);
        worst = std::max(worst, e);
      }
    }
    EXPECT_GT(drawn, width * height / 2);
    EXPECT_LT(worst, 1e-4);
  }
}

// ---------------------------------------------------------------------------
// Eclipses: GlobeView::moons.

// The sun's irradiance (returned) and the sky's (`sky`) that the pass's GLSL
// library (atmos_sun_and_sky_irradiance, what the globe lights its vertices
// with) gives a surface at `point` with normal `normal`, linear sRGB.
glm::dvec3 library_irradiance(const atmos::AtmospherePass& pass, const glm::dvec3& point, const glm::dvec3& normal,
                              const glm::dvec3& sun, glm::dvec3& sky) {
  const std::string fragment = "#version 450 core\n" + pass.glsl_library(0) + R"(
layout(location = 0) uniform vec3 point;
layout(location = 1) uniform vec3 normal;
layout(location = 2) uniform vec3 sun;
layout(location = 0) out vec4 result;
void main() {
  vec3 sky;
  vec3 direct = atmos_sun_and_sky_irradiance(point, normal, sun, sky);
  result = vec4(gl_FragCoord.x < 1.0 ? direct : sky, 1.0);
}
)";
  const GLuint program = atmos_test::fullscreen_program(fragment);
  glProgramUniform3f(program, 0, float(point.x), float(point.y), float(point.z));
  glProgramUniform3f(program, 1, float(normal.x), float(normal.y), float(normal.z));
  glProgramUniform3f(program, 2, float(sun.x), float(sun.y), float(sun.z));
  pass.bind_textures(0);
  const std::vector<float> texels = atmos_test::draw_fullscreen(program, 2, 1);
  glDeleteProgram(program);
  sky = glm::dvec3(texels[4], texels[5], texels[6]);
  return glm::dvec3(texels[0], texels[1], texels[2]);
}

// A moon centred on the sun as seen from the ground under the camera (0.8
// times the sun's angular radius: an annular eclipse) dims the globe's
// ground there as the pass dims its G-buffer surfaces: the sun's part of
// the light by the fraction of the limb-darkened sun the moon leaves
// (sunlight_visible_fraction, 0.29 here) and the sky's by the diffuse
// light's approximation (diffuse_light_visible_fraction, near the uniform
// disc's 1 - 0.8² = 0.36), both from their CPU twins. The parts come from
// the GLSL library's irradiance at the point (the flat style's ground: the
// datum, its normal the vertical), so that the expected colour is
// U (f_sun s + f_sky (1 - s)) per channel, U the uneclipsed colour and s the
// sun's share of its light. Applying either factor to both parts would be
// off by (f_sky - f_sun) times the other part's share, 3 % and more of the
// expected value here; the tolerance, 3e-3, allows for the vertices'
// interpolated light (the pixel's point is not a vertex) and float
// rounding. The terrain's shadows change nothing on this flat ground; a
// moon far from the sun leaves the image as without moons; a moon with a
// negative radius throws, nothing drawn.
TEST_F(GlobeGpu, MoonOnTheSunDimsTheGroundByTheEclipseFactors) {
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  atmos::Globe globe(*earth_, surface_of(atmos::SurfaceStyle::flat, 1), *pass_, settings);
  const double radius = earth_->bottom_radius_m;
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const glm::dvec3 ground = up * (radius + globe.height_m(up * radius));
  // 33 x 33: the centre pixel's ray is the view axis, straight down to `ground`.
  const int size = 33, centre = 16;
  Target target(size, size);
  atmos::GlobeView view = view_from(ground + up * 2000.0, -up, north, size, size);
  view.sun_direction = glm::normalize(up * std::sin(glm::radians(60.0)) + east * std::cos(glm::radians(60.0)));
  const glm::dvec3 sun = view.sun_direction;
  const auto draw = [&](const std::vector<atmos::Moon>& moons) {
    atmos::GlobeView v = view;
    v.moons = moons;
    target.clear();
    globe.draw(v);
    return target.read_colour();
  };
  const std::vector<float> day = draw({});
  const double a = earth_->sun_angular_radius_rad;
  const atmos::Moon moon = atmos::moon_in_sky(ground, sun, 0.8 * a);
  const std::vector<float> eclipse = draw({moon});
  ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));

  // The CPU twins of the factors at the ground point.
  using namespace atmos::physics;
  const AtmosphereParams params = make_render_params(*earth_, tables_->sizes);
  const Moons moons = make_moons(params, {moon});
  const std::unique_ptr<SpectralSets> spectral = make_spectral_sets(*earth_, tables_->sizes);
  const atmos::runtime::TableSamplers samplers = atmos::runtime::make_samplers(*tables_);
  const double sun_factor = sunlight_visible_fraction(moons, float(a), vec3(ground), vec3(sun));
  const double sky_factor = diffuse_light_visible_fraction(spectral->set[0], samplers.spectral_optical_depth, moons,
                                                           vec3(ground), vec3(sun));
  glm::dvec3 sky(0.0);
  const glm::dvec3 direct = library_irradiance(*pass_, ground, up, sun, sky);
  std::printf("annular eclipse at the ground point: sun factor %.4f, sky factor %.4f\n", sun_factor, sky_factor);
  EXPECT_NEAR(sun_factor, 0.288, 0.01);  // 1 - the covered flux of the limb-darkened disc, 0.712
  EXPECT_GT(sky_factor - sun_factor, 0.03);
  for (int c = 0; c < 3; ++c) {
    const size_t i = size_t(4 * (centre * size + centre) + c);
    const double share = direct[c] / (direct[c] + sky[c]);
    const double expected = day[i] * (sun_factor * share + sky_factor * (1.0 - share));
    std::printf("channel %d: day %.5g, eclipse %.5g, expected %.5g (sun's share %.3f)\n", c, double(day[i]),
                double(eclipse[i]), expected, share);
    EXPECT_GT(share, 0.5);
    EXPECT_LT(share, 0.97);
    EXPECT_NEAR(eclipse[i] / expected, 1.0, 3e-3) << c;
  }

  // With the terrain's shadows (the shadowed eclipse variant) the flat
  // ground, which casts none, is the same to float rounding.
  {
    atmos::Globe shadowed(*earth_, surface_of(atmos::SurfaceStyle::flat, 1), *pass_, shadow_settings(2));
    atmos::GlobeView v = view;
    v.moons = {moon};
    target.clear();
    shadowed.draw(v);
    EXPECT_GT(shadowed.last_stats().shadow_cascades, 0);
    const std::vector<float> shadowed_eclipse = target.read_colour();
    for (size_t i = 0; i < eclipse.size(); ++i)
      ASSERT_NEAR(shadowed_eclipse[i], eclipse[i], 1e-4 * std::abs(eclipse[i])) << i;
  }
  // A moon 30 degrees from the sun eclipses nothing: the uneclipsed light
  // (to float rounding: consecutive draws of one view may pick other tiles
  // as the resident tiles' heights tighten the selection's bounds).
  const atmos::Moon aside = atmos::moon_in_sky(ground, up, 0.8 * a);
  const std::vector<float> aside_image = draw({aside});
  for (size_t i = 0; i < day.size(); ++i) ASSERT_NEAR(aside_image[i], day[i], 1e-5 * std::abs(day[i])) << i;
  // An invalid moon: an error, nothing drawn.
  atmos::Moon bad = moon;
  bad.radius_m = -1.0;
  atmos::GlobeView invalid = view;
  invalid.moons = {bad};
  target.clear();
  EXPECT_THROW(globe.draw(invalid), atmos::Error);
  const std::vector<float> untouched = target.read_colour();
  EXPECT_TRUE(std::all_of(untouched.begin(), untouched.end(), [](float v) { return v == -1.0f; }));
}

// ---------------------------------------------------------------------------
// Popping: a slow dolly over Mars's relief.

// One frame of a camera path: its view, colour and reversed-Z depth.
struct PathFrame {
  atmos::GlobeView view;
  std::vector<float> colour, depth;
};

// The mean, over the pixels of frame b, of the change of the globe's
// luminance at the surface point they show since frame a: b's points (from
// its depth) projected into a, whose colour is interpolated bilinearly
// there (pixels whose four neighbours in a are all drawn).
double mean_change_at_the_same_points(const PathFrame& a, const PathFrame& b) {
  const int width = a.view.width, height = a.view.height;
  const glm::dmat4 clip_from_world = a.view.projection * a.view.view;
  double sum = 0.0;
  int count = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y * width + x);
      if (!(b.depth[i] > 0.0f)) continue;
      const glm::dvec4 c = clip_from_world * glm::dvec4(pixel_point(b.view, x, y, b.depth[i]), 1.0);
      const double px = (c.x / c.w * 0.5 + 0.5) * width - 0.5, py = (c.y / c.w * 0.5 + 0.5) * height - 0.5;
      const int x0 = int(std::floor(px)), y0 = int(std::floor(py));
      if (!(c.w > 0.0) || x0 < 0 || y0 < 0 || x0 + 1 >= width || y0 + 1 >= height) continue;
      const size_t i00 = size_t(y0 * width + x0), i10 = i00 + 1, i01 = i00 + size_t(width), i11 = i01 + 1;
      if (!(a.depth[i00] > 0.0f && a.depth[i10] > 0.0f && a.depth[i01] > 0.0f && a.depth[i11] > 0.0f)) continue;
      const double fx = px - x0, fy = py - y0;
      const double before = (luminance(&a.colour[4 * i00]) * (1.0 - fx) + luminance(&a.colour[4 * i10]) * fx) * (1.0 - fy) +
                            (luminance(&a.colour[4 * i01]) * (1.0 - fx) + luminance(&a.colour[4 * i11]) * fx) * fy;
      sum += std::abs(luminance(&b.colour[4 * i]) - before);
      ++count;
    }
  EXPECT_GT(count, width * height / 2);
  return sum / std::max(count, 1);
}

// The largest of the frame-to-frame changes over their median.
double largest_over_median(std::vector<double> changes) {
  const double largest = *std::max_element(changes.begin(), changes.end());
  std::nth_element(changes.begin(), changes.begin() + std::ptrdiff_t(changes.size() / 2), changes.end());
  return largest / changes[changes.size() / 2];
}

// A globe over a pass of the instant mode (the viewer's pass while exact
// tables are computed): the ground is lit through the instant pass's GLSL
// library, from its own transmittance and sky irradiance tables. The flat
// ground 2 km below the camera, the sun 60 degrees up: each channel of the
// centre pixel over the exact pass's globe's is the ratio of the two
// libraries' sun + sky irradiance at the ground point (the same albedo and
// geometry), to 3e-3; the instant mode's irradiance is within 5 % of the
// exact mode's (its sky light comes from its approximate multiple
// scattering; the sun's transmittance is the same function).
TEST_F(GlobeGpu, LitByAnInstantPass) {
  const atmos::InstantTables instant_tables = atmos::compute_instant_tables(*earth_, tables_->sizes);
  atmos::AtmospherePass instant_pass(*earth_, instant_tables, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  const std::string library = instant_pass.glsl_library(0);
  EXPECT_NE(library.find("#define ATMOS_INSTANT 1"), std::string::npos);
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  const atmos::PlanetSurface surface = surface_of(atmos::SurfaceStyle::flat, 1);
  atmos::Globe exact_globe(*earth_, surface, *pass_, settings);
  atmos::Globe instant_globe(*earth_, surface, instant_pass, settings);
  const double radius = earth_->bottom_radius_m;
  const glm::dvec3 up = glm::normalize(glm::dvec3(-0.4, 0.5, 0.77));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const glm::dvec3 ground = up * (radius + exact_globe.height_m(up * radius));
  const int size = 33, centre = 16;
  Target target(size, size);
  atmos::GlobeView view = view_from(ground + up * 2000.0, -up, north, size, size);
  view.sun_direction = glm::normalize(up * std::sin(glm::radians(60.0)) + east * std::cos(glm::radians(60.0)));
  const auto draw = [&](atmos::Globe& globe) {
    target.clear();
    globe.draw(view);
    return target.read_colour();
  };
  const std::vector<float> exact = draw(exact_globe);
  const std::vector<float> instant = draw(instant_globe);
  ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  glm::dvec3 exact_sky(0.0), instant_sky(0.0);
  const glm::dvec3 exact_direct = library_irradiance(*pass_, ground, up, view.sun_direction, exact_sky);
  const glm::dvec3 instant_direct = library_irradiance(instant_pass, ground, up, view.sun_direction, instant_sky);
  double worst_ratio_error = 0.0, worst_irradiance_difference = 0.0;
  for (int c = 0; c < 3; ++c) {
    const size_t i = size_t(4 * (centre * size + centre) + c);
    ASSERT_GT(exact[i], 0.0f) << c;
    ASSERT_TRUE(std::isfinite(instant[i])) << c;
    const double exact_total = exact_direct[c] + exact_sky[c];
    const double instant_total = instant_direct[c] + instant_sky[c];
    const double expected = instant_total / exact_total;
    const double ratio = double(instant[i]) / double(exact[i]);
    std::printf("channel %d: exact globe %.5g, instant globe %.5g, ratio %.5f, irradiance ratio %.5f (sky %.4f)\n", c,
                double(exact[i]), double(instant[i]), ratio, expected, instant_sky[c] / exact_sky[c]);
    worst_ratio_error = std::max(worst_ratio_error, std::abs(ratio / expected - 1.0));
    worst_irradiance_difference = std::max(worst_irradiance_difference, std::abs(expected - 1.0));
  }
  EXPECT_LE(worst_ratio_error, 3e-3);
  EXPECT_LE(worst_irradiance_difference, 0.05);
}

// No popping: a camera dollies straight down from 30 km to 300 m over the
// Mars style's craters (60 frames, 320 x 180, the sun 68 degrees up), each
// frame 8 % nearer the ground than the last, and the change of the ground
// between consecutive frames is measured where it is not the camera's
// motion. The globe's colour is the Lambertian ground lit per vertex by the
// sun and the sky, which do not depend on the view: a surface point keeps
// its colour from one frame to the next unless the mesh under it changes.
// So frame f + 1's pixels, reprojected to their points in frame f (depth
// buffer), are compared with frame f's colour there; what differs is the
// mesh's own change, a level handing over to another, plus the
// interpolation's error. (The plain per-pixel difference of consecutive
// frames is dominated by the image's 8 % zoom per frame and does not see
// the level changes: its largest over its median is the same, 1.5-3, with
// and without the morph.) With the morph (Strugar 2009) a level's change
// of positions and normals is spread over the frames the camera takes to
// cross its morph zone, from 0.7 to 1 times the level's range: ln(1/0.7) /
// ln(1.081), 4.5 frames of this dolly; without it, the change lands in the
// frame where the selection switches levels, a spike. The largest change
// over the median is at most K = 4 with the morph (2.3 here; 2.3-2.8 at
// four other places on Mars) and above K with the morph switched off
// (set_globe_morph, src/planet/globe_internal.hpp: 6.1 here; 7.4-8.6
// elsewhere): the test sees the popping it guards against. The first view
// is drawn twice: a globe's first draw selects its tiles with the relief's
// global bounds, the next ones with the resident tiles' own heights, which
// can select other levels there.
TEST_F(GlobeGpu, SlowDollyOverMarsDoesNotPop) {
  const atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  const atmos::PlanetSurface surface = surface_of(atmos::SurfaceStyle::mars, 2);
  const atmos::Atmosphere air = atmos::extend_below_datum(mars, surface);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(air, options);
  const atmos::AtmospherePass pass(air, tables, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  atmos::Globe globe(mars, surface, pass, settings);
  const double radius = mars.bottom_radius_m;
  const glm::dvec3 up = glm::normalize(glm::dvec3(0.5, 0.6, 0.3));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const double ground = radius + globe.height_m(up * radius);
  const int width = 320, height = 180, frames = 60;
  Target target(width, height);
  struct Morph {
    explicit Morph(bool on) { atmos::planet::set_globe_morph(on); }
    ~Morph() { atmos::planet::set_globe_morph(true); }
  };
  // The frame-to-frame changes of one dolly; the same tiles serve both.
  const auto dolly = [&](bool morph) {
    const Morph switched(morph);
    std::vector<double> changes;
    PathFrame previous;
    for (int f = 0; f < frames; ++f) {
      PathFrame frame;
      const double altitude = 30e3 * std::pow(300.0 / 30e3, f / double(frames - 1));
      frame.view = view_from(up * (ground + altitude), -up, north, width, height);
      frame.view.sun_direction = glm::normalize(up + 0.35 * east + 0.2 * north);
      for (int draws = f == 0 ? 2 : 1; draws > 0; --draws) {
        target.clear();
        globe.draw(frame.view);
      }
      EXPECT_EQ(globe.last_stats().tiles_pending, 0);
      frame.colour = target.read_colour();
      frame.depth = target.read_depth();
      if (f > 0) changes.push_back(mean_change_at_the_same_points(previous, frame));
      previous = std::move(frame);
    }
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    return largest_over_median(changes);
  };
  const double morphed = dolly(true);
  const double unmorphed = dolly(false);
  std::printf("largest frame-to-frame change of the ground over the median: %.2f with the morph, %.2f without\n",
              morphed, unmorphed);
  const double k = 4.0;
  EXPECT_LE(morphed, k);
  EXPECT_GT(unmorphed, k);
}

TEST_F(GlobeGpu, RejectsBadInput) {
  atmos::GlobeSettings bad;
  bad.max_screen_error_px = 0.0;
  EXPECT_THROW(atmos::Globe(*earth_, atmos::PlanetSurface{}, *pass_, bad), atmos::Error);
  bad = {};
  bad.memory_cap_bytes = 1000;
  EXPECT_THROW(atmos::Globe(*earth_, atmos::PlanetSurface{}, *pass_, bad), atmos::Error);
  // Shadows: 0 to 4 cascades, an even map size in 64..16384 texels, a
  // positive shadow distance.
  for (const int cascades : {-1, 5}) {
    bad = {};
    bad.shadow_cascades = cascades;
    EXPECT_THROW(atmos::Globe(*earth_, atmos::PlanetSurface{}, *pass_, bad), atmos::Error) << cascades;
  }
  for (const int size : {32, 65, 20000}) {
    bad = {};
    bad.shadow_cascades = 2;
    bad.shadow_map_size = size;
    EXPECT_THROW(atmos::Globe(*earth_, atmos::PlanetSurface{}, *pass_, bad), atmos::Error) << size;
  }
  for (const double distance : {0.0, -1.0, std::numeric_limits<double>::infinity(),
                                std::numeric_limits<double>::quiet_NaN()}) {
    bad = {};
    bad.shadow_cascades = 2;
    bad.shadow_distance_m = distance;
    EXPECT_THROW(atmos::Globe(*earth_, atmos::PlanetSurface{}, *pass_, bad), atmos::Error) << distance;
  }
  // A sea level above the top of the atmosphere, or below the planet's centre.
  for (const double sea : {earth_->top_radius_m - earth_->bottom_radius_m + 1.0, -earth_->bottom_radius_m - 1.0,
                           std::numeric_limits<double>::infinity()})
    EXPECT_THROW(atmos::Globe(*earth_, surface_of(atmos::SurfaceStyle::earth, 1, sea), *pass_, {}),
                 atmos::Error)
        << sea;

  // Ground below the bottom of the pass's atmosphere (the Mars style's
  // lowlands on Earth's datum): the pass must come from extend_below_datum.
  try {
    atmos::Globe below(*earth_, surface_of(atmos::SurfaceStyle::mars, 1), *pass_, {});
    ADD_FAILURE() << "no error for ground below the pass's atmosphere";
  } catch (const atmos::Error& e) {
    EXPECT_NE(std::string(e.what()).find("extend_below_datum"), std::string::npos) << e.what();
  }

  atmos::Globe globe(*earth_, surface_of(atmos::SurfaceStyle::flat, 1), *pass_, {});
  const double radius = earth_->bottom_radius_m;
  atmos::GlobeView view = view_from(glm::dvec3(0, -2 * radius, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1), 32, 32);
  atmos::GlobeView nan_view = view;
  nan_view.view[3][0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(globe.draw(nan_view), atmos::Error);
  atmos::GlobeView no_sun = view;
  no_sun.sun_direction = glm::dvec3(0.0);
  EXPECT_THROW(globe.draw(no_sun), atmos::Error);
  atmos::GlobeView empty = view;
  empty.width = 0;
  EXPECT_THROW(globe.draw(empty), atmos::Error);
  atmos::GlobeView singular = view;
  singular.view = glm::dmat4(0.0);
  EXPECT_THROW(globe.draw(singular), atmos::Error);
  EXPECT_THROW(globe.height_m(glm::dvec3(std::numeric_limits<double>::infinity(), 0, 0)), atmos::Error);
  EXPECT_THROW(atmos::reversed_z_projection(0.0, 1.0, 1.0), atmos::Error);
  // The cascades slice a perspective frustum: with shadows, an
  // orthographic projection is refused, nothing drawn.
  {
    atmos::GlobeSettings shadowed;
    shadowed.shadow_cascades = 2;
    shadowed.shadow_map_size = 64;
    atmos::Globe with_shadows(*earth_, surface_of(atmos::SurfaceStyle::flat, 1), *pass_, shadowed);
    atmos::GlobeView orthographic = view_from(glm::dvec3(0, -radius - 100.0, 0), glm::dvec3(0, 1, 0),
                                              glm::dvec3(0, 0, 1), 32, 32);
    orthographic.projection = glm::ortho(-100.0, 100.0, -100.0, 100.0, 0.1, 1000.0);
    Target small(32, 32);
    small.clear();
    EXPECT_THROW(with_shadows.draw(orthographic), atmos::Error);
    EXPECT_NO_THROW(globe.draw(orthographic));
  }
  // A camera at the planet's centre: nothing to see of the surface from
  // inside, but no crash and no error.
  atmos::GlobeView centre = view_from(glm::dvec3(0.0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1), 32, 32);
  Target target(32, 32);
  target.clear();
  EXPECT_NO_THROW(globe.draw(centre));
}

}  // namespace
