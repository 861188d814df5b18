// The globe's tiles built in the background (src/planet/tile_streamer.hpp,
// GlobeSettings::complete_every_frame = false): on the CPU the streamer's
// order, its meshes (those of MeshBuilder::build, bit for bit), the requests
// it drops and keeps, its bound on finished meshes and its shutdown; on the
// GPU streamed descents from 2.5 planet radii to 2 m on Earth and Mars with
// no hole and under the memory cap, whose tiles all arrive once the camera
// stops; the caught-up image against complete_every_frame's; and a globe
// destroyed while its thread is busy.
#include <gtest/gtest.h>

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "atmos/globe.hpp"
#include "planet_surfaces.hpp"
#include "atmos/plugin.hpp"
#include "globe_rays.hpp"
#include "globe_target.hpp"
#include "gpu_fixture.hpp"
#include "planet/globe_mesh.hpp"
#include "planet/surface.hpp"
#include "planet/tile_streamer.hpp"

namespace {

using atmos_test::surface_of;
using atmos::planet::MeshBuilder;
using atmos::planet::ReadyTile;
using atmos::planet::Surface;
using atmos::planet::TileKey;
using atmos::planet::TileMesh;
using atmos::planet::TileRequest;
using atmos_test::pixel_ray;
using atmos_test::ray_hits_sphere;

constexpr double kEarthRadius = 6360e3;

// Waits (polling every millisecond, at most a minute) until `done`.
template <typename Done>
bool wait_until(Done done) {
  for (int i = 0; i < 60000; ++i) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return done();
}

bool same_mesh(const TileMesh& a, const TileMesh& b) {
  return a.origin == b.origin && a.min_height_m == b.min_height_m && a.max_height_m == b.max_height_m &&
         a.vertices.size() == b.vertices.size() &&
         std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(a.vertices[0])) == 0;
}

std::vector<TileKey> children_of(const TileKey& key) {
  std::vector<TileKey> out;
  for (std::uint32_t q = 0; q < 4; ++q)
    out.push_back({key.face, key.level + 1, 2 * key.x + (q & 1u), 2 * key.y + (q >> 1)});
  return out;
}

// ---------------------------------------------------------------------------
// The streamer on the CPU.

class StreamerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    surface_ = std::make_unique<Surface>(surface_of(atmos::SurfaceStyle::earth, 1), kEarthRadius);
    builder_ = std::make_unique<MeshBuilder>(*surface_, kEarthRadius);
  }
  static void TearDownTestSuite() {
    builder_.reset();
    surface_.reset();
  }
  static inline std::unique_ptr<Surface> surface_;
  static inline std::unique_ptr<MeshBuilder> builder_;
};
using TileStreamer = StreamerTest;

// Requests of three levels in mixed order arrive coarse levels first, the
// nearest first within a level, each mesh bit for bit MeshBuilder::build's.
TEST_F(TileStreamer, BuildsCoarseLevelsThenTheNearestAsTheBuilderDoes) {
  atmos::planet::TileStreamer streamer(*builder_, 64);
  std::vector<TileRequest> requests;
  std::map<std::uint64_t, double> distance;
  for (int level : {5, 3, 4})
    for (std::uint32_t i = 0; i < 4; ++i) {
      const TileRequest r{TileKey{1, level, i, 1}, 1000.0 * (7.0 - i)};
      requests.push_back(r);
      distance[r.key.packed()] = r.distance_m;
    }
  streamer.request(requests, requests.size());
  std::vector<ReadyTile> got;
  ASSERT_TRUE(wait_until([&] {
    for (ReadyTile& t : streamer.take(64)) got.push_back(std::move(t));
    return got.size() == requests.size();
  }));
  EXPECT_EQ(streamer.counts().queued, 0u);
  for (size_t i = 1; i < got.size(); ++i) {
    const TileKey& a = got[i - 1].key;
    const TileKey& b = got[i].key;
    EXPECT_TRUE(a.level < b.level || (a.level == b.level && distance[a.packed()] < distance[b.packed()]))
        << "tile " << i << ": level " << b.level << " after level " << a.level;
  }
  for (const ReadyTile& t : got) EXPECT_TRUE(same_mesh(t.mesh, builder_->build(t.key))) << t.key.packed();
}

// A new request replaces the last: the tiles only the last asked for are
// dropped, whether queued, finished or being built; a finished tile the new
// request still wants is kept, not built again.
TEST_F(TileStreamer, KeepsOnlyWhatTheLatestRequestWants) {
  atmos::planet::TileStreamer streamer(*builder_, 64);
  const TileKey parent{3, 4, 5, 5};
  streamer.request({{parent, 0.0}}, 1);
  ASSERT_TRUE(wait_until([&] { return streamer.counts().ready == 1; }));
  // Coarser tiles first: the worker is busy with these when the children's
  // request replaces them.
  std::vector<TileRequest> others;
  for (std::uint32_t i = 0; i < 40; ++i) others.push_back({TileKey{2, 3, i % 8, i / 8}, double(i)});
  std::vector<TileRequest> family{{parent, 0.0}};
  for (const TileKey& c : children_of(parent)) family.push_back({c, 1.0});
  std::vector<TileRequest> both = others;
  both.insert(both.end(), family.begin(), family.end());
  streamer.request(both, both.size());
  ASSERT_TRUE(wait_until([&] { return streamer.counts().ready > 1; }));
  streamer.request(family, family.size());
  ASSERT_TRUE(wait_until([&] { return streamer.counts().queued == 0; }));
  std::set<std::uint64_t> got;
  for (const ReadyTile& t : streamer.take(64)) EXPECT_TRUE(got.insert(t.key.packed()).second) << "twice";
  std::set<std::uint64_t> expected;
  for (const TileRequest& r : family) expected.insert(r.key.packed());
  EXPECT_EQ(got, expected);
  // A request that does not want a finished tile drops it.
  streamer.request({{TileKey{4, 2, 1, 1}, 0.0}}, 1);
  ASSERT_TRUE(wait_until([&] { return streamer.counts().queued == 0; }));
  const std::vector<ReadyTile> last = streamer.take(64);
  ASSERT_EQ(last.size(), 1u);
  EXPECT_EQ(last[0].key, (TileKey{4, 2, 1, 1}));
}

// Requests beyond the limit are not built; the worker stops when max_ready
// meshes wait and goes on when they are taken; destroyed while it waits
// and while it builds, it returns (and, under the sanitizers, leaks
// nothing).
TEST_F(TileStreamer, BoundsItsQueueAndFinishedTilesAndStopsWhenDestroyed) {
  std::vector<TileRequest> requests;
  for (std::uint32_t i = 0; i < 12; ++i) requests.push_back({TileKey{0, 4, i, 3}, double(i)});
  {
    atmos::planet::TileStreamer streamer(*builder_, 3);
    streamer.request(requests, 10);
    ASSERT_TRUE(wait_until([&] { return streamer.counts().ready == 3; }));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_EQ(streamer.counts().ready, 3u);
    EXPECT_EQ(streamer.counts().queued, 7u);  // of the first 10 in order
    const std::vector<ReadyTile> first = streamer.take(2);
    ASSERT_EQ(first.size(), 2u);
    EXPECT_EQ(first[0].key, requests[0].key);
    EXPECT_EQ(first[1].key, requests[1].key);
    ASSERT_TRUE(wait_until([&] { return streamer.counts().ready == 3; }));
    EXPECT_EQ(streamer.counts().queued, 5u);
  }  // destroyed while waiting for room
  {
    std::vector<TileRequest> many;
    for (std::uint32_t i = 0; i < 400; ++i) many.push_back({TileKey{5, 9, i, 7}, double(i)});
    atmos::planet::TileStreamer streamer(*builder_, 1000);
    streamer.request(many, many.size());
    ASSERT_TRUE(wait_until([&] { return streamer.counts().ready > 0; }));
    EXPECT_GT(streamer.counts().queued, 0u);
  }  // destroyed while building
}

// ---------------------------------------------------------------------------
// The globe on the GPU.

class GlobeStreaming : public atmos_test::EarthGpuTest {
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

  // A camera `altitude_m` above the ground at latitude 20°, longitude 30°,
  // looking at the planet's centre from 2.5 radii and 8° below the horizon
  // from 1 km down, as the benchmark's descent (bench/harness.cpp).
  static atmos::GlobeView descent_view(const atmos::Globe& globe, double radius, double altitude_m, int width,
                                       int height) {
    const double lat = glm::radians(20.0), lon = glm::radians(30.0);
    const glm::dvec3 up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
    const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
    const glm::dvec3 north = glm::cross(up, east);
    const double w = std::clamp(std::log10(altitude_m / 1e3) / std::log10(2.5 * radius / 1e3), 0.0, 1.0);
    const double pitch = glm::radians(-8.0 + (-90.0 + 8.0) * w);
    const glm::dvec3 forward = glm::normalize(north * std::cos(pitch) + up * std::sin(pitch));
    const glm::dvec3 camera = up * (radius + globe.height_m(up * radius) + altitude_m);
    atmos::GlobeView v;
    v.view = glm::lookAt(camera, camera + forward, std::abs(pitch) > 1.5 ? north : up);
    v.projection = atmos::reversed_z_projection(glm::radians(60.0), double(width) / height, 0.05);
    v.width = width;
    v.height = height;
    v.sun_direction = glm::normalize(north * std::cos(glm::radians(25.0)) + up * std::sin(glm::radians(25.0)));
    v.nits_per_unit = 1000.0;
    return v;
  }

  // A streamed descent of 40 frames from 2.5 radii to 2 m, then the last
  // view again, 5 ms apart, until every selected tile is resident. After
  // every draw: a drawn pixel wherever the pixel's ray meets a sphere
  // below all of the relief (no hole while tiles load), the resident tiles
  // under the memory cap, at most max_tiles_per_frame uploads.
  static void descend(atmos::Globe& globe, const atmos::GlobeSettings& settings, double radius) {
    const int width = 320, height = 180;
    Target target(width, height);
    const double inner = radius + globe.min_height_m() - 8e3;
    int holes = 0, covered = 0, frames = 0;
    std::string first_hole;
    const auto draw = [&](const atmos::GlobeView& view, const std::string& name) {
      target.clear();
      globe.draw(view);
      ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));
      ++frames;
      const atmos::GlobeStats& stats = globe.last_stats();
      EXPECT_LE(stats.resident_bytes, settings.memory_cap_bytes) << name;
      EXPECT_LE(stats.tiles_generated, settings.max_tiles_per_frame) << name;
      const glm::dvec3 camera(glm::inverse(view.view)[3]);
      const std::vector<float> depth = target.read_depth();
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
          if (!ray_hits_sphere(camera, pixel_ray(view, x, y), inner)) continue;
          ++covered;
          if (depth[size_t(y * width + x)] > 0.0f) continue;
          if (holes++ == 0) first_hole = name + ", pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")";
        }
    };
    const int steps = 40;
    atmos::GlobeView view;
    int pending_during_descent = 0;
    for (int f = 0; f < steps; ++f) {
      const double altitude =
          std::exp(std::log(2.5 * radius) + (std::log(2.0) - std::log(2.5 * radius)) * f / (steps - 1));
      view = descent_view(globe, radius, altitude, width, height);
      draw(view, "frame " + std::to_string(f) + " at " + std::to_string(altitude) + " m");
      pending_during_descent += globe.last_stats().tiles_pending;
    }
    EXPECT_GT(pending_during_descent, 0);  // the stand-ins were drawn
    // The camera stops: every tile arrives within a bounded number of frames.
    int waited = 0;
    while (globe.last_stats().tiles_pending > 0 && waited < 4000) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      draw(view, "frame " + std::to_string(steps + waited) + " (stopped)");
      ++waited;
    }
    std::printf("all tiles resident %d frames after the camera stopped\n", waited);
    EXPECT_EQ(globe.last_stats().tiles_pending, 0) << "after " << waited << " frames";
    EXPECT_EQ(globe.last_stats().tiles_queued, 0);
    EXPECT_GT(covered, frames * width * height / 4);
    EXPECT_EQ(holes, 0) << "first at " << first_hole;
  }

  static inline std::unique_ptr<atmos::AtmospherePass> pass_;
};

TEST_F(GlobeStreaming, EarthDescentLeavesNoHoleAndItsTilesAllArrive) {
  atmos::GlobeSettings settings;
  settings.memory_cap_bytes = std::size_t(32) << 20;
  atmos::Globe globe(*earth_, surface_of(atmos::SurfaceStyle::earth, 1), *pass_, settings);
  descend(globe, settings, earth_->bottom_radius_m);
}

// Its own suite: the Mars style's relief takes minutes under the sanitizers
// (tests/CMakeLists.txt, ATMOS_SLOW_UNIT_SUITES).
class GlobeStreamingMars : public GlobeStreaming {};

TEST_F(GlobeStreamingMars, DescentLeavesNoHoleAndItsTilesAllArrive) {
  const atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  const atmos::PlanetSurface surface = surface_of(atmos::SurfaceStyle::mars, 2);
  const atmos::Atmosphere air = atmos::extend_below_datum(mars, surface);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(air, options);
  const atmos::AtmospherePass pass(air, tables, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  atmos::GlobeSettings settings;
  settings.memory_cap_bytes = std::size_t(32) << 20;
  // Coarser than on Earth: the Mars style's craters make fine tiles slow to build.
  settings.max_screen_error_px = 2.0;
  atmos::Globe globe(mars, surface, pass, settings);
  descend(globe, settings, mars.bottom_radius_m);
}

// The tiles the background thread builds are those draw() builds with
// complete_every_frame: once the streamed globe has caught up with a view,
// its image is the complete one, bit for bit. Both globes start with the
// same resident tiles (the roots): which tiles a view selects depends on the
// heights of those resident (tile_selection.hpp), and those the stream
// passed through on its way would tighten them.
TEST_F(GlobeStreaming, CaughtUpImageIsTheCompleteImage) {
  const int width = 160, height = 90;
  const double radius = earth_->bottom_radius_m;
  atmos::GlobeSettings streamed_settings;
  atmos::Globe streamed(*earth_, surface_of(atmos::SurfaceStyle::earth, 4), *pass_, streamed_settings);
  atmos::GlobeSettings complete_settings;
  complete_settings.complete_every_frame = true;
  atmos::Globe complete(*earth_, surface_of(atmos::SurfaceStyle::earth, 4), *pass_, complete_settings);
  const atmos::GlobeView view = descent_view(streamed, radius, 5e3, width, height);
  Target target(width, height);

  int frames = 0;
  do {
    if (frames > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    target.clear();
    streamed.draw(view);
    ++frames;
  } while ((streamed.last_stats().tiles_pending > 0 || streamed.last_stats().tiles_queued > 0) && frames < 4000);
  ASSERT_EQ(streamed.last_stats().tiles_pending, 0);
  EXPECT_GT(frames, 1);  // streamed: not all there at the first draw
  const std::vector<float> streamed_colour = target.read_colour();
  const std::vector<float> streamed_depth = target.read_depth();

  int complete_draws = 0;
  do {
    target.clear();
    complete.draw(view);
    ++complete_draws;
  } while (complete.last_stats().tiles_generated > 0 && complete_draws < 10);
  EXPECT_EQ(complete.last_stats().tiles_pending, 0);
  EXPECT_EQ(complete.last_stats().tiles_drawn, streamed.last_stats().tiles_drawn);
  EXPECT_EQ(complete.last_stats().triangles, streamed.last_stats().triangles);
  const std::vector<float> complete_colour = target.read_colour();
  const std::vector<float> complete_depth = target.read_depth();
  int differing = 0, drawn = 0;
  for (size_t i = 0; i < complete_depth.size(); ++i) {
    drawn += complete_depth[i] > 0.0f ? 1 : 0;
    const bool same = complete_depth[i] == streamed_depth[i] &&
                      std::memcmp(&complete_colour[4 * i], &streamed_colour[4 * i], 4 * sizeof(float)) == 0;
    differing += same ? 0 : 1;
  }
  EXPECT_GT(drawn, width * height / 4);
  EXPECT_EQ(differing, 0);
}

// Destroyed right after a draw that queued a few thousand tiles: the
// destructor stops the thread after the tile it builds (no leak under the
// sanitizers), and a new globe draws on.
TEST_F(GlobeStreaming, GlobeDestroyedWhileItsThreadIsBusy) {
  const int width = 320, height = 180;
  const double radius = earth_->bottom_radius_m;
  Target target(width, height);
  {
    atmos::Globe globe(*earth_, surface_of(atmos::SurfaceStyle::earth, 6), *pass_);
    target.clear();
    globe.draw(descent_view(globe, radius, 2.0, width, height));
    EXPECT_GT(globe.last_stats().tiles_queued, 100);
  }
  atmos::Globe again(*earth_, surface_of(atmos::SurfaceStyle::earth, 6), *pass_);
  target.clear();
  again.draw(descent_view(again, radius, 2.0, width, height));
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  EXPECT_GT(again.last_stats().tiles_drawn, 0);
}

}  // namespace
