// The terrain globe (include/atmos/globe.hpp) on the GPU: a scripted
// descent from 100 planet radii to a metre with no hole in the surface, its
// lighting under the atmosphere and in an eclipse, no popping as levels
// change, the terrain's shadows, and bad input. Its meshes and cascades on
// the CPU are in globe_mesh_test.cpp.
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
#include "planet_surfaces.hpp"
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

using atmos_test::surface_of;
using atmos::planet::kGridVertices;
using atmos::planet::kSkirtVertices;

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

  // The descents' site (about 50° N) and its local up and north.
  struct Site {
    glm::dvec3 up, north;
  };
  static Site descent_site() {
    const glm::dvec3 up = glm::normalize(glm::dvec3(0.2, -0.6, 0.77));
    const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
    return {up, glm::cross(up, east)};
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
  const Site site = descent_site();
  const glm::dvec3 up = site.up, north = site.north;
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

// complete_every_frame: the first frame of a new globe is already the
// settled one, selected with the height ranges of resident tiles, not with
// the planet's range that a tile inherits until an ancestor is resident
// (which keeps the rings of fine tiles around a camera near the ground).
// Drawn again, 2 m above the ground towards the horizon and towards the
// sky, the view needs no new tile, draws as many and gives the same image.
TEST_F(GlobeGpu, ACompleteFrameBuildsTheTilesOfItsSettledSelection) {
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  const int width = 96, height = 64;
  Target target(width, height);
  const Site site = descent_site();
  const glm::dvec3 up = site.up, north = site.north;
  const double radius = earth_->bottom_radius_m;
  for (const double pitch_deg : {-10.0, 40.0}) {
    atmos::Globe globe(*earth_, surface_of(atmos::SurfaceStyle::earth, 1), *pass_, settings);
    const glm::dvec3 camera = up * (radius + globe.height_m(up * radius) + 2.0);
    const double pitch = glm::radians(pitch_deg);
    const atmos::GlobeView view =
        view_from(camera, glm::normalize(north * std::cos(pitch) + up * std::sin(pitch)), up, width, height);
    target.clear();
    globe.draw(view);
    const atmos::GlobeStats first = globe.last_stats();
    const std::vector<float> first_image = target.read_colour();
    target.clear();
    globe.draw(view);
    const atmos::GlobeStats second = globe.last_stats();
    std::printf("pitch %+.0f deg: first frame %d tiles built, %d drawn; second %d built, %d drawn\n", pitch_deg,
                first.tiles_generated, first.tiles_drawn, second.tiles_generated, second.tiles_drawn);
    EXPECT_EQ(first.tiles_pending, 0);
    EXPECT_EQ(second.tiles_generated, 0) << pitch_deg;
    EXPECT_EQ(second.tiles_drawn, first.tiles_drawn) << pitch_deg;
    EXPECT_TRUE(target.read_colour() == first_image) << pitch_deg;
  }
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
