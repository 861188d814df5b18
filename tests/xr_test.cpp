// Stereo and head-mounted displays in atmos view (apps/view/xr.hpp): the
// frustum that covers both eyes (atmos::covering_eye), the tracking space's
// eyes on the planet, the mock headset's file (HeadsetViews); and through the
// mock headset, the path an OpenXR headset's frames take, the sun's disc in
// each eye where that eye's own four angles and pose put it; the globe's
// tiles chosen once for both eyes, and one eye's depth reprojected into the
// other (HeadsetGpu).

#include <gtest/gtest.h>

#include "atmos/stereo.hpp"

#ifdef ATMOS_VIEWER
#include <epoxy/gl.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "atmos/globe.hpp"
#include "atmos/post.hpp"
#include "atmos/plugin.hpp"
#include "figures.hpp"
#include "gpu_fixture.hpp"
#include "sun_disc.hpp"
#include "view/scene.hpp"
#include "view/xr.hpp"

namespace {

constexpr double kDegree = M_PI / 180.0;

using atmos_view::CameraPose;
using atmos_view::EyeView;

// A head at `altitude_m` above the datum sphere of radius `radius_m` at
// 20° N, 30° E, looking
// towards azimuth 180.1° (from north towards east) at elevation
// `elevation_deg`, its up towards the zenith.
CameraPose head_pose(double radius_m, double altitude_m, double elevation_deg) {
  const double lat = 20.0 * kDegree, lon = 30.0 * kDegree;
  const glm::dvec3 up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0.0, 0.0, 1.0), up));
  const glm::dvec3 north = glm::cross(up, east);
  CameraPose pose;
  pose.position = up * (radius_m + altitude_m);
  const double a = 180.1 * kDegree, e = elevation_deg * kDegree;
  pose.forward = (east * std::sin(a) + north * std::cos(a)) * std::cos(e) + up * std::sin(e);
  pose.up = glm::normalize(up - pose.forward * glm::dot(pose.forward, up));
  return pose;
}

atmos::FieldOfView degrees(double left, double right, double up, double down) {
  return {left * kDegree, right * kDegree, up * kDegree, down * kDegree};
}

// Points inside an eye's frustum: along rays through its four corners and
// centre, at distances from 1 mm to 10 km.
std::vector<glm::dvec3> points_in(const atmos::Eye& eye) {
  const glm::dvec3 f = glm::normalize(eye.forward), r = glm::normalize(glm::cross(f, eye.up)), u = glm::cross(r, f);
  std::vector<glm::dvec3> points;
  for (double x : {std::tan(eye.fov.left_rad), 0.0, std::tan(eye.fov.right_rad)})
    for (double y : {std::tan(eye.fov.down_rad), 0.0, std::tan(eye.fov.up_rad)})
      for (double d : {1e-3, 0.1, 10.0, 1e4}) points.push_back(eye.position + (f + r * x + u * y) * d);
  return points;
}

// Whether a point lies in an eye's frustum (its four side planes), with a
// relative tolerance.
bool inside(const atmos::Eye& eye, const glm::dvec3& point) {
  const glm::dvec3 f = glm::normalize(eye.forward), r = glm::normalize(glm::cross(f, eye.up)), u = glm::cross(r, f);
  const glm::dvec3 d = point - eye.position;
  const double z = glm::dot(d, f);
  if (!(z > 0.0)) return false;
  const double x = glm::dot(d, r) / z, y = glm::dot(d, u) / z, e = 1e-9;
  return x >= std::tan(eye.fov.left_rad) - e && x <= std::tan(eye.fov.right_rad) + e &&
         y >= std::tan(eye.fov.down_rad) - e && y <= std::tan(eye.fov.up_rad) + e;
}

}  // namespace

// The covering frustum holds every point of both eyes' frusta, for a
// stereo pair and for canted, vertically different eyes, and its apex
// lies behind the eyes by the least distance that does: a point of the
// outer edge ray at the eye itself lies on its side plane.
TEST(HeadsetViews, CoveringFrustumHoldsBothEyes) {
  atmos::Camera head;
  head.position = glm::dvec3(1.0, 2.0, 3.0);
  head.forward = glm::dvec3(0.0, 1.0, 0.2);
  head.up = glm::dvec3(0.0, 0.0, 1.0);
  head.fov_deg = 90.0;
  head.width = 160;
  head.height = 100;
  std::array<atmos::Eye, 2> eyes = atmos::stereo_eyes(head, {0.064, 2.0});
  atmos::Eye cover = atmos::covering_eye(eyes);
  for (const atmos::Eye& e : eyes)
    for (const glm::dvec3& p : points_in(e)) EXPECT_TRUE(inside(cover, p)) << p.x << " " << p.y << " " << p.z;
  // Parallel axes: the apex on the axis, back by (ipd / 2) over the tangent
  // of the union's left side (the right eye's, shifted outwards by the
  // convergence), so that the left eye lies on that side plane.
  const double back = glm::dot(0.5 * (eyes[0].position + eyes[1].position) - cover.position,
                               glm::normalize(head.forward));
  EXPECT_NEAR(back, 0.032 / -std::tan(eyes[1].fov.left_rad), 1e-12);
  EXPECT_NEAR(cover.fov.left_rad, eyes[1].fov.left_rad, 1e-12);
  EXPECT_NEAR(cover.fov.right_rad, eyes[0].fov.right_rad, 1e-12);

  // A headset's eyes: canted 5° outwards, different vertically, the right
  // eye a millimetre higher.
  const glm::dvec3 f = glm::normalize(head.forward), r = glm::normalize(glm::cross(f, head.up)), u = glm::cross(r, f);
  const double cant = 5.0 * kDegree;
  eyes[0].forward = f * std::cos(cant) - r * std::sin(cant);
  eyes[1].forward = f * std::cos(cant) + r * std::sin(cant);
  eyes[0].fov = degrees(-50, 42, 45, -48);
  eyes[1].fov = degrees(-42, 50, 48, -45);
  eyes[1].position += u * 1e-3;
  cover = atmos::covering_eye(eyes);
  for (const atmos::Eye& e : eyes)
    for (const glm::dvec3& p : points_in(e)) EXPECT_TRUE(inside(cover, p)) << p.x << " " << p.y << " " << p.z;

  eyes[1].forward = -eyes[0].forward;
  EXPECT_THROW(atmos::covering_eye(eyes), atmos::Error);
}

// The tracking space's eyes on the planet: OpenXR's axes (x right, y up,
// z backwards) on the head's, a quaternion turning the eye's view.
TEST(HeadsetViews, TrackingSpaceEyesSitOnTheHead) {
  const CameraPose head = head_pose(6371e3, 2.0, 10.0);
  const glm::dvec3 right = glm::normalize(glm::cross(head.forward, head.up));
  EyeView view;
  view.position_m = glm::dvec3(-0.032, 0.01, 0.02);
  view.orientation = glm::angleAxis(0.3, glm::dvec3(0.0, 1.0, 0.0));  // turned 0.3 rad to the left
  view.fov = degrees(-40, 30, 35, -45);
  const atmos::Eye eye = atmos_view::eye_in_planet(head, view);
  const glm::dvec3 position = head.position - right * 0.032 + head.up * 0.01 - head.forward * 0.02;
  EXPECT_LT(glm::length(eye.position - position), 1e-9);
  const glm::dvec3 forward = head.forward * std::cos(0.3) - right * std::sin(0.3);
  EXPECT_LT(glm::length(glm::normalize(eye.forward) - forward), 1e-12);
  EXPECT_LT(glm::length(glm::normalize(eye.up) - head.up), 1e-12);
  EXPECT_DOUBLE_EQ(eye.fov.left_rad, view.fov.left_rad);
  EXPECT_DOUBLE_EQ(eye.fov.down_rad, view.fov.down_rad);
}

TEST(HeadsetViews, BadMockFilesAreOneLineErrors) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "atmos-xr-test";
  std::filesystem::create_directories(dir);
  const auto error_of = [&dir](const std::string& text) -> std::string {
    const std::filesystem::path path = dir / "mock.json";
    std::ofstream(path) << text;
    try {
      (void)atmos_view::MockViewProvider::read(path.string());
    } catch (const atmos::Error& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string eye = R"({"position_m": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0],
                              "fov_deg": {"left": -40, "right": 30, "up": 35, "down": -45}})";
  EXPECT_EQ(error_of(R"({"width": 8, "height": 8, "eyes": [)" + eye + "," + eye + "]}"), "no error");
  EXPECT_NE(error_of(R"({"width": 8, "height": 8, "eyes": [)" + eye + "]}").find("two eyes"), std::string::npos);
  std::string bad = eye;
  bad.replace(bad.find("-40"), 3, "-95");
  EXPECT_NE(error_of(R"({"width": 8, "height": 8, "eyes": [)" + eye + "," + bad + "]}").find("(-pi/2, pi/2)"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"width": 0, "height": 8, "eyes": [)" + eye + "," + eye + "]}").find("eye size"),
            std::string::npos);
  bad = eye;
  bad.replace(bad.find("[1, 0, 0, 0]"), 12, "[2, 0, 0, 0]");
  EXPECT_NE(error_of(R"({"width": 8, "height": 8, "eyes": [)" + eye + "," + bad + "]}").find("unit quaternion"),
            std::string::npos);
  EXPECT_NE(error_of("{").find("not JSON"), std::string::npos);
  std::filesystem::remove_all(dir);
}

class HeadsetGpu : public atmos_test::EarthGpuTest {
 protected:
  // Earth's tables over the analytic sphere, or under the globe of the
  // earth style's relief (seed 3).
  static atmos_view::PlanetTables planet_tables(bool relief = false) {
    atmos_view::PlanetTables t;
    t.planet = *earth_;
    t.air = *earth_;
    t.tables = *tables_;
    if (relief) {
      t.surface.style = atmos::SurfaceStyle::earth;
      t.surface.seed = 3;
    }
    return t;
  }
};

// Through the mock headset, as an OpenXR headset's frames go: each eye's
// own pose (the right eye turned 0.05° to the left, a millimetre lower) and
// four angles, asymmetric and different vertically in the two eyes, 1.6°
// wide over 200 x 180 pixels. From 2000 km (above the air: the limb
// darkening alone shapes the disc) the centre of the sun's disc in each eye
// lies within 0.05 px of where that eye's angles put the sun.
TEST_F(HeadsetGpu, SunDiscCentreInEachEyeIsWhereItsOwnAnglesPutIt) {
  atmos_view::Scene scene(planet_tables(), false, false, true);
  atmos::PostProcess post;
  std::array<EyeView, 2> views;
  views[0].position_m = glm::dvec3(-0.032, 0.0, 0.0);
  views[0].fov = degrees(-0.9, 0.7, 0.75, -0.65);
  views[1].position_m = glm::dvec3(0.032, -0.001, 0.0);
  const double yaw = 0.05 * kDegree;
  views[1].orientation = glm::angleAxis(yaw, glm::dvec3(0.0, 1.0, 0.0));
  views[1].fov = degrees(-0.7, 0.9, 0.65, -0.75);
  const int w = 200, h = 180;
  atmos_view::MockViewProvider mock(views, w, h, 1);

  atmos_view::SceneFrame frame;
  frame.pose = head_pose(earth_->bottom_radius_m, 2e6, 20.2);
  const glm::dvec3 right = glm::normalize(glm::cross(frame.pose.forward, frame.pose.up));
  frame.sun = glm::normalize(frame.pose.forward + right * 0.002 + frame.pose.up * 0.001);
  atmos_view::HeadsetRenderer headset;
  ASSERT_TRUE(headset.frame(mock, scene, post, frame, atmos::PostSettings{}, 0.0));
  EXPECT_EQ(mock.frames_ended(), 1);
  EXPECT_FALSE(headset.frame(mock, scene, post, frame, atmos::PostSettings{}, 0.0));  // the mock's one frame

  // The eyes as the test places them, not through eye_in_planet.
  std::array<atmos::Eye, 2> eyes;
  eyes[0].position = frame.pose.position - right * 0.032;
  eyes[0].forward = frame.pose.forward;
  eyes[0].up = frame.pose.up;
  eyes[0].fov = views[0].fov;
  eyes[1].position = frame.pose.position + right * 0.032 - frame.pose.up * 0.001;
  eyes[1].forward = frame.pose.forward * std::cos(yaw) - right * std::sin(yaw);
  eyes[1].up = frame.pose.up;
  eyes[1].fov = views[1].fov;
  glm::dvec2 centres[2];
  for (int i = 0; i < 2; ++i) {
    const glm::dvec2 expected = atmos_test::image_position(eyes[size_t(i)], frame.sun, w, h);
    centres[i] = atmos_test::disc_centre(atmos_test::luminance_of(mock.hdr(i)), w, h);
    const double error = glm::length(centres[i] - expected);
    std::printf("%s eye: sun disc centre (%.3f, %.3f), its angles' (%.3f, %.3f): off by %.4f px\n",
                i == 0 ? "left" : "right", centres[i].x, centres[i].y, expected.x, expected.y, error);
    atmos_test::record_figure(std::string("headset: sun disc centre error, ") + (i == 0 ? "left" : "right") + " eye",
                              error, "px", "<= 0.05");
    EXPECT_LT(error, 0.05) << "eye " << i;
  }
  // The two eyes' discs are not at the same place (the angles differ by
  // 0.2° horizontally and 0.1° vertically): two suns unless each eye's own
  // projection draws it.
  EXPECT_GT(glm::length(centres[1] - centres[0]), 10.0);
}

// Level of detail once for both eyes, 50 m above flat ground, 20 m apart
// (hyperstereo): Globe::draw_views from the covering view selects the
// tiles that a single draw() of that view selects (the same nodes visited,
// the same tiles) and draws them in each eye (twice the triangles), with
// one selection; and each left-eye pixel's depth, reprojected into the
// right eye by the eyes' own matrices, lands where the right eye's depth
// says the ground is (the median and 99th percentile of the relative
// distance error, 8e-8 and 3e-6 here; an eye drawn through the other's
// matrices would be off by ~0.2).
TEST_F(HeadsetGpu, GlobeChoosesTheTilesOnceAndEachEyesDepthReprojects) {
  atmos::AtmospherePass pass(*earth_, *tables_, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  atmos::Globe globe(*earth_, atmos::PlanetSurface{}, pass, settings);
  const CameraPose pose = head_pose(earth_->bottom_radius_m, 50.0, -10.0);
  atmos::Camera head;
  head.position = pose.position;
  head.forward = pose.forward;
  head.up = pose.up;
  head.fov_deg = 60.0;
  head.width = 96;
  head.height = 64;
  const std::array<atmos::Eye, 2> eyes = atmos::stereo_eyes(head, {20.0, 100.0});
  const atmos::Eye cover = atmos::covering_eye(eyes);
  const auto view_of = [&](const atmos::Eye& e, int width, int height) {
    atmos::GlobeView v;
    v.view = atmos::view_matrix(e);
    v.projection = atmos::reversed_z_projection(e.fov, 0.05);
    v.width = width;
    v.height = height;
    v.sun_direction = glm::dvec3(0.0, 0.0, 1.0);
    return v;
  };
  // One target per eye (reversed-Z depth cleared to 0, the sky).
  const int w = 96, h = 64;
  std::array<GLuint, 2> colour{}, depth{}, framebuffer{};
  glCreateTextures(GL_TEXTURE_2D, 2, colour.data());
  glCreateTextures(GL_TEXTURE_2D, 2, depth.data());
  glCreateFramebuffers(2, framebuffer.data());
  for (size_t i = 0; i < 2; ++i) {
    glTextureStorage2D(colour[i], 1, GL_RGBA32F, 160, 80);
    glTextureStorage2D(depth[i], 1, GL_DEPTH_COMPONENT32F, 160, 80);
    glNamedFramebufferTexture(framebuffer[i], GL_COLOR_ATTACHMENT0, colour[i], 0);
    glNamedFramebufferTexture(framebuffer[i], GL_DEPTH_ATTACHMENT, depth[i], 0);
    const float zero = 0.0f;
    glClearNamedFramebufferfv(framebuffer[i], GL_DEPTH, 0, &zero);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer[0]);
  const atmos::GlobeView lod = view_of(cover, 160, 80);
  // The selection bounds resident tiles by their own heights (tighter than
  // the planet's): the first draw makes them resident, the second is the
  // selection of the covering view with them.
  globe.draw(lod);
  globe.draw(lod);
  const atmos::GlobeStats mono = globe.last_stats();
  for (size_t i = 0; i < 2; ++i) {
    const float zero = 0.0f;
    glClearNamedFramebufferfv(framebuffer[i], GL_DEPTH, 0, &zero);
  }
  int bound = 0;
  globe.draw_views(lod, {view_of(eyes[0], w, h), view_of(eyes[1], w, h)},
                   [&bound, &framebuffer](std::size_t i) {
                     glBindFramebuffer(GL_FRAMEBUFFER, framebuffer[i]);
                     ++bound;
                   });
  const atmos::GlobeStats stereo = globe.last_stats();
  std::array<std::vector<float>, 2> depths;
  for (size_t i = 0; i < 2; ++i) {
    std::vector<float> all(160 * 80);
    glGetTextureImage(depth[i], 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(all.size() * sizeof(float)), all.data());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) depths[i].push_back(all[size_t(y) * 160 + size_t(x)]);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer[0]);
  globe.draw(lod);
  EXPECT_EQ(globe.last_stats().nodes_visited, mono.nodes_visited) << "the covering view's selection is not steady";
  globe.draw(view_of(eyes[0], w, h));
  const atmos::GlobeStats left_alone = globe.last_stats();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(2, framebuffer.data());
  glDeleteTextures(2, colour.data());
  glDeleteTextures(2, depth.data());

  // Each left-eye pixel's depth, unprojected by the left eye's matrices and
  // projected by the right eye's, against the right eye's own depth there
  // (bilinear between its pixel centres: reversed-Z depth, near / distance
  // along the axis, is linear across a triangle on the screen).
  std::array<glm::dmat4, 2> clip_from_world;
  for (size_t i = 0; i < 2; ++i)
    clip_from_world[i] = atmos::reversed_z_projection(eyes[i].fov, 0.05) * atmos::view_matrix(eyes[i]);
  const glm::dmat4 world_from_left = glm::inverse(clip_from_world[0]);
  std::vector<double> errors;
  int ground = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float d = depths[0][size_t(y) * size_t(w) + size_t(x)];
      if (!(d > 0.0f)) continue;  // sky
      ++ground;
      // GL's rows bottom-up; window depth = NDC depth (glClipControl zero to one).
      glm::dvec4 world = world_from_left * glm::dvec4(2.0 * (x + 0.5) / w - 1.0, 2.0 * (y + 0.5) / h - 1.0, double(d), 1.0);
      world /= world.w;
      const glm::dvec4 clip = clip_from_world[1] * world;
      const double rx = (0.5 * clip.x / clip.w + 0.5) * w - 0.5, ry = (0.5 * clip.y / clip.w + 0.5) * h - 0.5;
      const int x0 = int(std::floor(rx)), y0 = int(std::floor(ry));
      if (x0 < 0 || y0 < 0 || x0 + 1 >= w || y0 + 1 >= h) continue;
      double corners[4];
      bool all_ground = true;
      for (int k = 0; k < 4; ++k) {
        corners[k] = depths[1][size_t(y0 + k / 2) * size_t(w) + size_t(x0 + k % 2)];
        all_ground = all_ground && corners[k] > 0.0;
      }
      if (!all_ground) continue;
      const double fx = rx - x0, fy = ry - y0;
      const double right_depth = (corners[0] * (1 - fx) + corners[1] * fx) * (1 - fy) +
                                 (corners[2] * (1 - fx) + corners[3] * fx) * fy;
      errors.push_back(std::abs(right_depth / (clip.z / clip.w) - 1.0));  // of the distance near / depth
    }
  std::sort(errors.begin(), errors.end());
  ASSERT_GT(errors.size(), size_t(w * h / 4)) << ground << " ground pixels in the left eye";
  const double median = errors[errors.size() / 2], p99 = errors[errors.size() * 99 / 100];
  std::printf("depth reprojected from the left eye into the right over %zu of %d ground pixels: relative distance "
              "error median %.3g, 99th percentile %.3g, max %.3g\n",
              errors.size(), ground, median, p99, errors.back());
  atmos_test::record_figure("headset: depth reprojection, median relative distance error", median, "1", "<= 1e-6");
  atmos_test::record_figure("headset: depth reprojection, 99th percentile relative distance error", p99, "1",
                            "<= 1e-4");
  EXPECT_LE(median, 1e-6);
  EXPECT_LE(p99, 1e-4);

  std::printf("covering view: %d nodes, %d tiles, %lld triangles; both eyes: %d selection, %d nodes, %d tiles, %lld "
              "triangles; the left eye alone: %d nodes, %d tiles\n",
              mono.nodes_visited, mono.tiles_drawn, mono.triangles, stereo.view_selections, stereo.nodes_visited,
              stereo.tiles_drawn, stereo.triangles, left_alone.nodes_visited, left_alone.tiles_drawn);
  EXPECT_EQ(bound, 2);
  EXPECT_EQ(stereo.view_selections, 1);
  EXPECT_EQ(stereo.nodes_visited, mono.nodes_visited);
  EXPECT_EQ(stereo.tiles_drawn, mono.tiles_drawn);
  EXPECT_EQ(stereo.triangles, 2 * mono.triangles);
  EXPECT_GT(mono.tiles_drawn, 4);
  // The covering view holds more than an eye's: its selection is not one eye's.
  EXPECT_GT(mono.tiles_drawn, left_alone.tiles_drawn);
}

#endif  // ATMOS_VIEWER
