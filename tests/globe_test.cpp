// The terrain globe (include/atmos/globe.hpp): its tile meshes on the CPU
// (morph targets, shared edges, skirts, precision), and on the GPU a
// scripted descent from 100 planet radii to a metre with no hole in the
// surface, its lighting under the atmosphere, and bad input.
#include <gtest/gtest.h>

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "atmos/globe.hpp"
#include "atmos/plugin.hpp"
#include "gpu_fixture.hpp"
#include "planet/globe_mesh.hpp"

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
// The GPU: the globe drawn into a small reversed-Z framebuffer.

class GlobeGpu : public atmos_test::EarthGpuTest {
 protected:
  static void SetUpTestSuite() {
    EarthGpuTest::SetUpTestSuite();
    if (context_ == nullptr) return;
    pass_ = std::make_unique<atmos::AtmospherePass>(*earth_, *tables_, atmos::PlanetFrame{});
  }
  static void TearDownTestSuite() {
    pass_.reset();
    EarthGpuTest::TearDownTestSuite();
  }

  struct Target {
    GLuint colour = 0, depth = 0, framebuffer = 0;
    int width = 0, height = 0;
    Target(int w, int h) : width(w), height(h) {
      glCreateTextures(GL_TEXTURE_2D, 1, &colour);
      glTextureStorage2D(colour, 1, GL_RGBA32F, w, h);
      glCreateTextures(GL_TEXTURE_2D, 1, &depth);
      glTextureStorage2D(depth, 1, GL_DEPTH_COMPONENT32F, w, h);
      glCreateFramebuffers(1, &framebuffer);
      glNamedFramebufferTexture(framebuffer, GL_COLOR_ATTACHMENT0, colour, 0);
      glNamedFramebufferTexture(framebuffer, GL_DEPTH_ATTACHMENT, depth, 0);
    }
    ~Target() {
      glDeleteFramebuffers(1, &framebuffer);
      glDeleteTextures(1, &colour);
      glDeleteTextures(1, &depth);
    }
    // Clears colour to a sentinel and depth to 0 (reversed-Z: infinitely far).
    void clear() const {
      const float sentinel[4] = {-1.0f, -1.0f, -1.0f, -1.0f};
      const float far_depth = 0.0f;
      glClearNamedFramebufferfv(framebuffer, GL_COLOR, 0, sentinel);
      glClearNamedFramebufferfv(framebuffer, GL_DEPTH, 0, &far_depth);
      glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    }
    std::vector<float> read_depth() const {
      std::vector<float> d(size_t(width * height));
      glGetTextureImage(depth, 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(d.size() * sizeof(float)), d.data());
      return d;
    }
    std::vector<float> read_colour() const {
      std::vector<float> c(size_t(width * height * 4));
      glGetTextureImage(colour, 0, GL_RGBA, GL_FLOAT, GLsizei(c.size() * sizeof(float)), c.data());
      return c;
    }
  };

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

  static inline std::unique_ptr<atmos::AtmospherePass> pass_;
};

// The ray through pixel (x, y) of `view` (world = planet-centred metres here).
glm::dvec3 pixel_ray(const atmos::GlobeView& view, int x, int y) {
  const glm::dmat4 inverse = glm::inverse(view.projection * view.view);
  const double nx = (x + 0.5) / view.width * 2.0 - 1.0, ny = (y + 0.5) / view.height * 2.0 - 1.0;
  const glm::dvec4 near = inverse * glm::dvec4(nx, ny, 1.0, 1.0), far = inverse * glm::dvec4(nx, ny, 0.5, 1.0);
  return glm::normalize(glm::dvec3(far) / far.w - glm::dvec3(near) / near.w);
}

bool ray_hits_sphere(const glm::dvec3& origin, const glm::dvec3& ray, double radius) {
  const double b = glm::dot(origin, ray);
  const double c = glm::dot(origin, origin) - radius * radius;
  if (c < 0.0) return true;
  return b < 0.0 && b * b - c >= 0.0;
}

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
        if (ray_hits_sphere(camera, pixel_ray(view, x, y), inner) && !(depth[size_t(y * width + x)] > 0.0f)) ++holes;
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
  const atmos::AtmospherePass pass(air, tables, atmos::PlanetFrame{});
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

TEST_F(GlobeGpu, RejectsBadInput) {
  atmos::GlobeSettings bad;
  bad.max_screen_error_px = 0.0;
  EXPECT_THROW(atmos::Globe(*earth_, atmos::PlanetSurface{}, *pass_, bad), atmos::Error);
  bad = {};
  bad.memory_cap_bytes = 1000;
  EXPECT_THROW(atmos::Globe(*earth_, atmos::PlanetSurface{}, *pass_, bad), atmos::Error);
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
  EXPECT_THROW(globe.height_m(glm::dvec3(std::numeric_limits<double>::infinity(), 0, 0)), atmos::Error);
  EXPECT_THROW(atmos::reversed_z_projection(0.0, 1.0, 1.0), atmos::Error);
  // A camera at the planet's centre: nothing to see of the surface from
  // inside, but no crash and no error.
  atmos::GlobeView centre = view_from(glm::dvec3(0.0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1), 32, 32);
  Target target(32, 32);
  target.clear();
  EXPECT_NO_THROW(globe.draw(centre));
}

}  // namespace
