// Solar eclipses in the renderers (include/atmos/eclipse.hpp): a moon in
// front of the sun darkens the sky and the ground, leaves a bright horizon
// ring, hides the sun disc; the GPU and the CPU agree; bad moons are
// errors. The geometry of the overlap itself is tested in physics_test.cpp
// (Eclipse.*), the multiple-scattering approximation against the
// brute-force reference in reference_accuracy.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/renderer.hpp"
#include "atmos/sky.hpp"
#include "gpu_fixture.hpp"
#include "physics/moons.hpp"
#include "physics/parameters.hpp"

namespace {

using atmos::Camera;
using atmos::Image;
using atmos::Moon;
using atmos_test::EarthGpuTest;

class EclipseGpu : public EarthGpuTest {
 protected:
  // A camera 2 m above the ground at the north pole.
  static glm::dvec3 observer() { return atmos::observer_position(*earth_, 2.0); }
  // A moon of angular radius `radius_deg` (the Sun's is 0.2664°) whose centre
  // is `offset_deg` from the sun's towards the zenith, seen from observer().
  static Moon moon(double sun_elevation, double radius_deg, double offset_deg = 0.0) {
    return atmos::moon_in_sky(observer(), atmos::direction_from_azimuth_elevation(150.0, sun_elevation + offset_deg),
                              radius_deg * M_PI / 180.0);
  }
  static glm::dvec3 sun(double elevation) { return atmos::direction_from_azimuth_elevation(150.0, elevation); }
};

double luminance(const Image& image, int x, int y) {
  const float* p = &image.rgb[(size_t(y) * size_t(image.width) + size_t(x)) * 3];
  return atmos::srgb_luminance(glm::dvec3(p[0], p[1], p[2]));
}

// An all-sky fisheye image looking up (the image's top towards azimuth 0).
Camera all_sky(const glm::dvec3& position, int size) {
  Camera camera;
  camera.position = position;
  camera.forward = {0.0, 0.0, 1.0};
  camera.up = {0.0, 1.0, 0.0};
  camera.projection = atmos::Projection::fisheye;
  camera.fov_deg = 180.0;
  camera.width = camera.height = size;
  return camera;
}

// A 10° view straight down at the ground.
Camera straight_down(const glm::dvec3& position, int size) {
  Camera camera = all_sky(position, size);
  camera.forward = {0.0, 0.0, -1.0};
  camera.projection = atmos::Projection::perspective;
  camera.fov_deg = 10.0;
  return camera;
}

// Totality seen from the centre of the shadow: the zenith goes down to the
// order of 1e-3..1e-4 of its daylight value (the range observed, e.g. Sharp,
// Silverman & Lloyd 1971, Appl. Opt. 10, 1207; Shaw 1975, Appl. Opt. 14, 388:
// the eclipsed sky is a few 1e-4 of the uneclipsed one overhead), and the
// horizon, where the view rays reach the sunlit air beyond the umbra, stays
// several times brighter than the zenith: the horizon ring. The GPU image
// matches the CPU's.
TEST_F(EclipseGpu, TotalityDarkensTheSkyAndLeavesAHorizonRing) {
  atmos::Renderer renderer(*earth_, *tables_);
  const int size = 49;
  const Camera camera = all_sky(observer(), size);
  const Image day = renderer.render(camera, sun(40.0));
  const std::vector<Moon> moons = {moon(40.0, 0.28)};
  renderer.set_moons(moons);
  const Image eclipse = renderer.render(camera, sun(40.0));
  const Image eclipse_cpu = atmos::render_cpu(*earth_, *tables_, camera, sun(40.0), false, moons);
  const int c = size / 2;
  const double zenith_ratio = luminance(eclipse, c, c) / luminance(day, c, c);
  // The horizon ring: the mean of the pixels 2-6° above the horizon, all round.
  double ring = 0.0;
  int ring_pixels = 0;
  double max_difference = 0.0;
  double peak = 0.0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) peak = std::max(peak, luminance(eclipse, x, y));
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double radius = std::hypot(x + 0.5 - 0.5 * size, y + 0.5 - 0.5 * size) / (0.5 * size);  // 1 at the horizon
      const double elevation = 90.0 * (1.0 - radius);
      const double l = luminance(eclipse, x, y);
      EXPECT_TRUE(std::isfinite(l) && l >= 0.0);
      if (elevation > 2.0 && elevation < 6.0) {
        ring += l;
        ++ring_pixels;
      }
      if (radius < 1.0 && l > 1e-3 * peak) {
        max_difference = std::max(max_difference, std::abs(luminance(eclipse_cpu, x, y) / l - 1.0));
      }
    }
  }
  ring /= ring_pixels;
  std::printf("totality, sun at 40 deg: zenith %.4g cd/m2 (daylight %.4g, ratio %.3g); horizon ring %.4g cd/m2 "
              "(%.1f x the zenith); GPU vs CPU max %.2g\n",
              luminance(eclipse, c, c), luminance(day, c, c), zenith_ratio, ring, ring / luminance(eclipse, c, c),
              max_difference);
  EXPECT_GT(zenith_ratio, 1e-5);
  EXPECT_LT(zenith_ratio, 2e-3);
  // The sunlit air beyond the umbra seen through the haze: 5.7x the zenith
  // with Earth's continental aerosol (its slant optical depth at 4° is ~2),
  // 26x with an aerosol 30 times thinner.
  EXPECT_GT(ring, 3.0 * luminance(eclipse, c, c));
  EXPECT_LT(max_difference, 0.01);
}

// At the centre of the umbra no direct sunlight is left: the ground is lit
// by less than the sky light of the uneclipsed day (the irradiance at the
// umbra centre during totality is at most the sky-light level). Seen straight down from 2 m, the ground's radiance is its
// irradiance times albedo / pi; the uneclipsed ground's, scaled by the sky's
// share of the irradiance (SkyModel), is the sky-light level.
TEST_F(EclipseGpu, TheGroundInTotalityGetsLessThanTheSkyLight) {
  atmos::Renderer renderer(*earth_, *tables_);
  const Camera camera = straight_down(observer(), 9);
  const Image day = renderer.render(camera, sun(40.0));
  renderer.set_moons({moon(40.0, 0.28)});
  const Image eclipse = renderer.render(camera, sun(40.0));
  const atmos::SkyModel model(*earth_, *tables_);
  glm::dvec3 sun_irradiance, sky_irradiance;
  model.horizontal_irradiance(observer(), sun(40.0), sun_irradiance, sky_irradiance);
  const double sky_share = atmos::srgb_luminance(model.to_srgb(sky_irradiance)) /
                           atmos::srgb_luminance(model.to_srgb(sun_irradiance + sky_irradiance));
  const double sky_light_level = sky_share * luminance(day, 4, 4);
  std::printf("ground in totality %.4g cd/m2; daylight %.4g cd/m2, of which sky light %.4g cd/m2\n",
              luminance(eclipse, 4, 4), luminance(day, 4, 4), sky_light_level);
  EXPECT_GT(luminance(eclipse, 4, 4), 0.0);
  EXPECT_LT(luminance(eclipse, 4, 4), sky_light_level);
}

// The moon hides the sun disc: its pixels go from the solar radiance to the
// sky's level in totality, and about half of them go dark when the moon
// covers half the disc.
TEST_F(EclipseGpu, TheMoonHidesTheSunDisc) {
  atmos::Renderer renderer(*earth_, *tables_);
  Camera camera;
  camera.position = observer();
  camera.forward = sun(40.0);
  camera.up = {0.0, 0.0, 1.0};
  camera.fov_deg = 1.0;
  camera.width = camera.height = 48;
  auto disc_pixels = [&](const Image& image) {
    int n = 0;
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) n += luminance(image, x, y) > 1e7 ? 1 : 0;
    return n;
  };
  const Image day = renderer.render(camera, sun(40.0));
  renderer.set_moons({moon(40.0, 0.28)});
  const Image total = renderer.render(camera, sun(40.0));
  // A moon as large as the sun, its centre one solar radius off: it covers
  // 39 % of the disc's area.
  renderer.set_moons({moon(40.0, 0.2664, 0.2664)});
  const Image partial = renderer.render(camera, sun(40.0));
  std::printf("sun disc pixels: %d by day, %d in totality, %d half covered; centre %.4g -> %.4g cd/m2\n",
              disc_pixels(day), disc_pixels(total), disc_pixels(partial), luminance(day, 24, 24),
              luminance(total, 24, 24));
  EXPECT_GT(disc_pixels(day), 200);
  EXPECT_EQ(disc_pixels(total), 0);
  EXPECT_LT(luminance(total, 24, 24), 1e-6 * luminance(day, 24, 24));
  EXPECT_NEAR(double(disc_pixels(partial)) / disc_pixels(day), 1.0 - 0.391, 0.05);
}

// The further the moon from the sun, the brighter the ground. A moon clear
// of the sun as seen from the surroundings that feed the diffuse light (up
// to 512 km away) hides nothing: at 0.6° and 0.8° the ground is as bright
// as without a moon, within the 0.3 % that separate the integrated single
// scattering (any moon that may eclipse switches the sky to it) from the
// tables'; a moon 5° off eclipses nothing at all (moons_may_eclipse) and
// the image is the moonless one, bit for bit.
TEST_F(EclipseGpu, PartialEclipsesBrightenAsTheMoonMovesOff) {
  atmos::Renderer renderer(*earth_, *tables_);
  const Camera camera = straight_down(observer(), 5);
  const double clear = luminance(renderer.render(camera, sun(40.0)), 2, 2);
  double previous = 0.0;
  for (double offset : {0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8}) {
    renderer.set_moons({moon(40.0, 0.28, offset)});
    const double l = luminance(renderer.render(camera, sun(40.0)), 2, 2);
    std::printf("moon %.1f deg off the sun: ground %.4g of its radiance without a moon\n", offset, l / clear);
    if (offset < 0.6) {
      EXPECT_GT(l, previous) << offset;
    } else {
      EXPECT_NEAR(l / clear, 1.0, 0.005) << offset;
    }
    previous = l;
  }
  renderer.set_moons({moon(40.0, 0.28, 5.0)});
  EXPECT_EQ(luminance(renderer.render(camera, sun(40.0)), 2, 2), clear);
}

// A moon far from the sun eclipses nothing: the image is the moonless one,
// bit for bit, except on the moon's own disc, where its sunlit side shows
// (a gibbous moon 140° from the sun, brighter than the sky around it).
TEST_F(EclipseGpu, AMoonAwayFromTheSunChangesOnlyItsDisc) {
  atmos::Renderer renderer(*earth_, *tables_);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(150.0, 10.0);
  const glm::dvec3 towards_moon = atmos::direction_from_azimuth_elevation(330.0, 30.0);
  Camera camera;
  camera.position = observer();
  camera.forward = towards_moon;
  camera.up = {0.0, 0.0, 1.0};
  camera.fov_deg = 4.0;
  camera.width = camera.height = 64;
  const Image without = renderer.render(camera, sun);
  renderer.set_moons({atmos::moon_in_sky(observer(), towards_moon, 0.5 * M_PI / 180.0)});
  const Image with = renderer.render(camera, sun);
  const double pixel_deg = 4.0 / 64.0;
  int changed = 0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const double from_centre_deg = std::hypot(x + 0.5 - 32.0, y + 0.5 - 32.0) * pixel_deg;
      const bool same = luminance(with, x, y) == luminance(without, x, y);
      if (from_centre_deg > 0.5 + 2.0 * pixel_deg) {
        EXPECT_TRUE(same) << x << "," << y;
      }
      changed += same ? 0 : 1;
    }
  }
  std::printf("moon 140 deg from the sun: %d pixels changed (its disc: ~%.0f), centre %.4g cd/m2 over a sky of %.4g\n",
              changed, M_PI * 0.25 / (pixel_deg * pixel_deg), luminance(with, 32, 32), luminance(without, 32, 32));
  EXPECT_GT(changed, 150);
  EXPECT_GT(luminance(with, 32, 32), 2.0 * luminance(without, 32, 32));
}

// The same from space, where every pixel evaluates its own view ray (no
// sky-view table): a moon that cannot hide the sun (behind the camera, 120°
// from the sun) leaves the planet's image as without it, the rays keeping
// the tables' single scattering instead of integrating an eclipse that
// cannot happen (the program is the eclipse variant, compiled apart: equal
// to float rounding, not bit for bit).
TEST_F(EclipseGpu, FromSpaceAMoonAwayFromTheSunChangesNothing) {
  atmos::Renderer renderer(*earth_, *tables_);
  const glm::dvec3 up(0.0, 0.0, 1.0);
  const glm::dvec3 sun = glm::normalize(glm::dvec3(1.0, 0.0, 0.3));
  Camera camera;
  camera.position = glm::dvec3(0.0, 0.0, earth_->bottom_radius_m + 4.0e6);
  camera.forward = -up;
  camera.up = {0.0, 1.0, 0.0};
  camera.fov_deg = 90.0;
  camera.width = camera.height = 48;
  const Image without = renderer.render(camera, sun);
  const glm::dvec3 behind = glm::normalize(glm::dvec3(-0.5, 0.0, 1.0));  // up and away from the sun
  renderer.set_moons({atmos::moon_in_sky(camera.position, behind, 0.28 * M_PI / 180.0)});
  const Image with = renderer.render(camera, sun);
  ASSERT_EQ(with.rgb.size(), without.rgb.size());
  double lit = 0.0;
  for (float v : without.rgb) lit = std::max(lit, double(v));
  EXPECT_GT(lit, 0.0);  // the planet's lit side is in view
  double worst = 0.0;
  for (size_t i = 0; i < with.rgb.size(); ++i)
    worst = std::max(worst, std::abs(double(with.rgb[i]) - double(without.rgb[i])) / (double(without.rgb[i]) + 1e-3 * lit));
  std::printf("from space, a moon away from the sun: largest change %.2e\n", worst);
  EXPECT_LT(worst, 1e-5);
}

// Bad moons are errors that keep the renderer's previous moons.
TEST_F(EclipseGpu, RejectsBadMoons) {
  atmos::Renderer renderer(*earth_, *tables_);
  const Moon good = moon(40.0, 0.28);
  renderer.set_moons({good});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::vector<Moon>> bad = {
      std::vector<Moon>(5, good),
      {Moon{{0.0, 0.0, 6371e3 + 50e3}, 1000.0}},  // inside the atmosphere
      {Moon{{0.0, 0.0, 7e6}, 1e6}},                // reaching into it
      {Moon{{nan, 0.0, 4e8}, 1.7e6}},
      {Moon{{0.0, 0.0, 4e8}, 0.0}},
      {Moon{{0.0, 0.0, 4e8}, -1.0}},
  };
  for (const auto& moons : bad) {
    EXPECT_THROW(renderer.set_moons(moons), atmos::Error);
    EXPECT_THROW(atmos::render_cpu(*earth_, *tables_, all_sky(observer(), 4), sun(40.0), false, moons), atmos::Error);
  }
  ASSERT_EQ(renderer.moons().size(), 1u);
  EXPECT_EQ(renderer.moons()[0].centre_m, good.centre_m);
  EXPECT_THROW(atmos::moon_in_sky(observer(), {0.0, 0.0, 2.0}, 0.01), atmos::Error);
  EXPECT_THROW(atmos::moon_in_sky(observer(), {0.0, 0.0, 1.0}, 0.0), atmos::Error);
  EXPECT_THROW(atmos::moon_in_sky(observer(), {0.0, 0.0, 1.0}, 0.01, -5.0), atmos::Error);
}

}  // namespace
