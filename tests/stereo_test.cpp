// Stereo (atmos/stereo.hpp): the eyes' off-axis frusta, their matrices and
// renderer cameras (Stereo), and the sun's disc where each eye's own
// frustum puts it, in the renderer and in the engine plugin (StereoGpu).

#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <glm/glm.hpp>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "atmos/plugin.hpp"
#include "atmos/renderer.hpp"
#include "atmos/stereo.hpp"
#include "figures.hpp"
#include "gpu_fixture.hpp"
#include "sun_disc.hpp"

namespace {

using atmos_test::disc_centre;
using atmos_test::image_position;
using atmos_test::luminance_of;

constexpr double kEarthRadius = 6371e3;

// A head 2 m above the ground looking 20.2° up towards azimuth 180.1°
// (north = +y, east = +x, up = +z at the site), 1.6° of vertical field over
// 240 x 240 pixels, so that the sun's disc (0.27° in radius), 20° up at
// azimuth 180°, is ~80 pixels across and lies whole in both eyes, and the
// sky's disparity, 0.0064 of the image plane for the default rig (64 mm,
// 10 m), is ~55 pixels. `altitude_m` above the site.
atmos::Camera head_camera(double altitude_m = 2.0) {
  atmos::Camera c;
  c.position = glm::dvec3(0.0, 0.0, kEarthRadius + altitude_m);
  const double a = glm::radians(180.1), e = glm::radians(20.2);
  c.forward = glm::dvec3(std::cos(e) * std::sin(a), std::cos(e) * std::cos(a), std::sin(e));
  c.up = glm::dvec3(0.0, 0.0, 1.0);
  c.fov_deg = 1.6;
  c.width = 240;
  c.height = 240;
  return c;
}

glm::dvec3 sun_direction() {
  const double a = glm::radians(180.0), e = glm::radians(20.0);
  return {std::cos(e) * std::sin(a), std::cos(e) * std::cos(a), std::sin(e)};
}

}  // namespace

// The eyes: ipd apart on the head's right axis, parallel to the head, their
// frusta shifted by -+ (ipd / 2) / convergence so that both frame the head's
// window at the convergence distance; their renderer cameras and their
// matrices put a point where the eye's four angles put it.
TEST(Stereo, EyesFrameTheHeadsWindowAtTheConvergenceDistance) {
  const atmos::Camera head = head_camera();
  const atmos::StereoRig rig;  // 64 mm, 10 m
  const std::array<atmos::Eye, 2> eyes = atmos::stereo_eyes(head, rig);
  const glm::dvec3 forward = glm::normalize(head.forward);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, head.up));
  EXPECT_NEAR(glm::distance(eyes[0].position, eyes[1].position), 0.064, 1e-9);
  EXPECT_NEAR(glm::dot(eyes[1].position - eyes[0].position, right), 0.064, 1e-9);
  EXPECT_NEAR(glm::length(0.5 * (eyes[0].position + eyes[1].position) - head.position), 0.0, 1e-9);
  // A point on the head's axis at the convergence distance: the image centre
  // of both eyes (zero disparity); one at 5 m comes out of the screen
  // (crossed: left of centre in the right eye), the sun at infinity goes
  // behind it by ipd / convergence of the image plane.
  const glm::dvec3 on_screen = head.position + forward * rig.convergence_m;
  for (const atmos::Eye& eye : eyes) {
    const glm::dvec2 p = image_position(eye, glm::normalize(on_screen - eye.position), head.width, head.height);
    EXPECT_NEAR(p.x, 0.5 * head.width, 1e-6);
    EXPECT_NEAR(p.y, 0.5 * head.height, 1e-6);
  }
  const glm::dvec3 near_point = head.position + forward * 5.0;
  const double near_disparity =
      image_position(eyes[1], glm::normalize(near_point - eyes[1].position), head.width, head.height).x -
      image_position(eyes[0], glm::normalize(near_point - eyes[0].position), head.width, head.height).x;
  EXPECT_LT(near_disparity, 0.0);
  const double pixels_per_tangent = head.height / (2.0 * std::tan(glm::radians(0.5 * head.fov_deg)));
  const double sky_disparity = image_position(eyes[1], sun_direction(), head.width, head.height).x -
                               image_position(eyes[0], sun_direction(), head.width, head.height).x;
  EXPECT_NEAR(sky_disparity, 0.064 / 10.0 * pixels_per_tangent, 1e-6);

  // The renderer's camera of each eye traces, through the pixel where the
  // eye's angles put a direction, that direction (camera.glsl in double).
  for (const atmos::Eye& eye : eyes) {
    const atmos::Camera camera = atmos::eye_camera(eye, head.width, head.height);
    EXPECT_NE(camera.lens_shift.x, 0.0);
    const glm::dvec2 p = image_position(eye, sun_direction(), head.width, head.height);
    const double scale = std::tan(glm::radians(0.5 * camera.fov_deg)) / (0.5 * camera.height);
    const glm::dvec3 cam_forward = glm::normalize(camera.forward);
    const glm::dvec3 cam_right = glm::normalize(glm::cross(cam_forward, camera.up));
    const glm::dvec3 cam_up = glm::cross(cam_right, cam_forward);
    const glm::dvec3 ray = glm::normalize(
        cam_forward + cam_right * ((p.x - 0.5 * camera.width) * scale + camera.lens_shift.x) +
        cam_up * ((0.5 * camera.height - p.y) * scale + camera.lens_shift.y));
    EXPECT_LT(std::acos(std::min(1.0, glm::dot(ray, sun_direction()))), 1e-9);
    // The engine's matrices: the sun at infinity lands at the same pixel,
    // through the OpenGL and the reversed-Z projections alike.
    for (const glm::dmat4& projection :
         {atmos::projection_matrix(eye.fov, 0.1, 1e4), atmos::reversed_z_projection(eye.fov, 0.1)}) {
      const glm::dvec4 clip = projection * atmos::view_matrix(eye) * glm::dvec4(sun_direction(), 0.0);
      const glm::dvec2 ndc = glm::dvec2(clip) / clip.w;
      EXPECT_NEAR((0.5 * ndc.x + 0.5) * head.width, p.x, 1e-6);
      EXPECT_NEAR((0.5 - 0.5 * ndc.y) * head.height, p.y, 1e-6);
    }
  }
  // An infinite convergence: parallel frusta, the sky at zero disparity.
  const std::array<atmos::Eye, 2> parallel = atmos::stereo_eyes(head, {0.064, INFINITY});
  EXPECT_NEAR(image_position(parallel[1], sun_direction(), head.width, head.height).x -
                  image_position(parallel[0], sun_direction(), head.width, head.height).x,
              0.0, 1e-9);
}

// A point's depth in one eye, carried into the other: unprojected through
// the left eye's inverse view-projection (reversed-Z depth of a point 37 m
// away) and projected by the right eye's matrices, it lands where the right
// eye's own angles put the point, at the depth of its distance along that
// eye's axis.
TEST(Stereo, DepthReprojectsFromOneEyeIntoTheOther) {
  const atmos::Camera head = head_camera();
  const std::array<atmos::Eye, 2> eyes = atmos::stereo_eyes(head, {0.064, 3.0});
  const glm::dvec3 point = head.position + glm::normalize(head.forward + glm::dvec3(0.004, 0.0, -0.003)) * 37.0;
  const double near = 0.05;
  const glm::dmat4 left = atmos::reversed_z_projection(eyes[0].fov, near) * atmos::view_matrix(eyes[0]);
  const glm::dmat4 right = atmos::reversed_z_projection(eyes[1].fov, near) * atmos::view_matrix(eyes[1]);
  const glm::dvec4 clip = left * glm::dvec4(point, 1.0);
  const glm::dvec3 ndc = glm::dvec3(clip) / clip.w;  // what the left eye's depth buffer holds
  const glm::dvec4 world = glm::inverse(left) * glm::dvec4(ndc, 1.0);
  const glm::dvec4 into_right = right * (world / world.w);
  const glm::dvec3 right_ndc = glm::dvec3(into_right) / into_right.w;
  const glm::dvec2 expected = image_position(eyes[1], glm::normalize(point - eyes[1].position), head.width, head.height);
  EXPECT_NEAR((0.5 * right_ndc.x + 0.5) * head.width, expected.x, 1e-6);
  EXPECT_NEAR((0.5 - 0.5 * right_ndc.y) * head.height, expected.y, 1e-6);
  const double axial = glm::dot(point - eyes[1].position, glm::normalize(eyes[1].forward));
  EXPECT_NEAR(right_ndc.z, near / axial, 1e-12);
  // The disparity of that point, 37 m away with the screen at 3 m, is
  // behind the screen and less than the sky's.
  const double disparity = expected.x - image_position(eyes[0], glm::normalize(point - eyes[0].position),
                                                       head.width, head.height).x;
  const double pixels_per_tangent = head.height / (2.0 * std::tan(glm::radians(0.5 * head.fov_deg)));
  EXPECT_NEAR(disparity, 0.064 * (1.0 / 3.0 - 1.0 / axial) * pixels_per_tangent, 0.01);
}

TEST(Stereo, BadInputIsAClearError) {
  auto expect_error = [](auto&& call, const std::string& fragment) {
    try {
      call();
      ADD_FAILURE() << "no error, expected: " << fragment;
    } catch (const atmos::Error& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  atmos::Camera head = head_camera();
  expect_error([&] { atmos::stereo_eyes(head, {-0.01, 10.0}); }, "interpupillary distance -0.01 m");
  expect_error([&] { atmos::stereo_eyes(head, {0.064, 0.0}); }, "convergence distance 0 m");
  expect_error([&] { atmos::stereo_eyes(head, {0.064, NAN}); }, "convergence distance nan m");
  atmos::Camera fisheye = head;
  fisheye.projection = atmos::Projection::fisheye;
  fisheye.fov_deg = 180.0;
  expect_error([&] { atmos::stereo_eyes(fisheye, {}); }, "perspective");
  atmos::Eye eye = atmos::stereo_eyes(head, {})[0];
  expect_error([&] { atmos::eye_camera(eye, 480, 240); }, "not square");
  eye.fov.left_rad = 2.0;
  expect_error([&] { atmos::eye_camera(eye, 240, 240); }, "not in (-pi/2, pi/2)");
  expect_error([&] { atmos::projection_matrix(atmos::FieldOfView{}, 1.0, 0.5); }, "0 < near < far");
  expect_error([&] { atmos::reversed_z_projection(atmos::FieldOfView{0.3, -0.3, 0.5, -0.5}, 0.1); },
               "not left of right");
  head.lens_shift = glm::dvec2(NAN, 0.0);
  expect_error([&] { atmos::stereo_eyes(head, {}); }, "lens_shift");
  atmos::Image a, b;
  a.width = a.height = 2;
  a.rgb.assign(12, 1.0f);
  b.width = 3;
  b.height = 2;
  b.rgb.assign(18, 0.0f);
  expect_error([&] { atmos::anaglyph(a, b); }, "differ in size");
  expect_error([&] { atmos::side_by_side(a, b); }, "differ in size");
}

TEST(Stereo, AnaglyphAndSideBySideKeepEachEyesPixels) {
  atmos::Image left, right;
  left.width = right.width = 2;
  left.height = right.height = 1;
  left.rgb = {1, 2, 3, 4, 5, 6};
  right.rgb = {7, 8, 9, 10, 11, 12};
  const atmos::Image red_cyan = atmos::anaglyph(left, right);
  EXPECT_EQ(red_cyan.rgb, (std::vector<float>{1, 8, 9, 4, 11, 12}));
  const atmos::Image pair = atmos::side_by_side(left, right);
  EXPECT_EQ(pair.width, 4);
  EXPECT_EQ(pair.rgb, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}));
}

class StereoGpu : public atmos_test::EarthGpuTest {};

// The sun's disc in each eye, drawn by the renderer through the eye's
// off-axis camera (lens_shift) and by the engine plugin through the eye's
// own view and off-axis projection matrices, from 2 m above the ground and
// from 2000 km: the two eyes' discs ipd / convergence of the image plane
// apart (0.1 px), at the same height (0.05 px), and, from space, the disc's
// centre within 0.05 px of where the eye's four angles put the sun (one
// sun, fused, not two). Seen through the air the centroid of the disc's
// light lies ~0.08 px above its centre: its lower limb shines through more
// air (at 20° up the air mass grows by 0.04 across the disc's radius, ~1 %
// of the light in the green), so the centres are checked from above the
// atmosphere, where the limb darkening alone shapes the disc symmetrically.
TEST_F(StereoGpu, SunDiscCentreInEachEyeIsWhereItsFrustumPutsIt) {
  for (double altitude : {2.0, 2e6}) {
  SCOPED_TRACE(altitude);
  const bool space = altitude > 1e6;
  const atmos::Camera head = head_camera(altitude);
  const atmos::StereoRig rig;
  const std::array<atmos::Eye, 2> eyes = atmos::stereo_eyes(head, rig);
  const int w = head.width, h = head.height;
  atmos::Renderer renderer(*earth_, *tables_);
  atmos::PlanetFrame frame;  // the engine's world in planet-centred metres
  atmos::AtmospherePass pass(*earth_, *tables_, frame, atmos::PassPrograms::none);

  GLuint colour = 0, depth = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &colour);
  glTextureStorage2D(colour, 1, GL_RGBA32F, w, h);
  const std::vector<float> black(size_t(w) * size_t(h) * 4, 0.0f);
  glTextureSubImage2D(colour, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, black.data());
  glCreateTextures(GL_TEXTURE_2D, 1, &depth);
  glTextureStorage2D(depth, 1, GL_R32F, w, h);
  const std::vector<float> far(size_t(w) * size_t(h), 1.0f);  // sky everywhere
  glTextureSubImage2D(depth, 0, 0, 0, w, h, GL_RED, GL_FLOAT, far.data());

  glm::dvec2 centres[2][2];  // [renderer, plugin][eye]
  for (int i = 0; i < 2; ++i) {
    const atmos::Eye& eye = eyes[size_t(i)];
    const glm::dvec2 expected = image_position(eye, sun_direction(), w, h);

    const atmos::Image image = renderer.render(atmos::eye_camera(eye, w, h), sun_direction());
    centres[0][i] = disc_centre(luminance_of(image), w, h);

    atmos::FrameInput input;
    input.colour = colour;
    input.depth = depth;
    input.width = w;
    input.height = h;
    input.view = atmos::view_matrix(eye);
    input.projection = atmos::projection_matrix(eye.fov, 0.05, 1e5);
    input.sun_direction = sun_direction();
    const GLuint out = pass.render(input);
    std::vector<float> rgba(size_t(w) * size_t(h) * 4);
    glGetTextureImage(out, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
    std::vector<double> luminance(size_t(w) * size_t(h));
    for (int y = 0; y < h; ++y)  // the texture's rows are bottom-up
      for (int x = 0; x < w; ++x) {
        const float* p = &rgba[4 * (size_t(h - 1 - y) * size_t(w) + size_t(x))];
        luminance[size_t(y) * size_t(w) + size_t(x)] = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
      }
    centres[1][i] = disc_centre(luminance, w, h);

    for (int path = 0; path < 2; ++path) {
      const char* name = path == 0 ? "renderer" : "plugin";
      const glm::dvec2 error = centres[path][i] - expected;
      std::printf("%s, %s, %s eye: sun disc centre (%.3f, %.3f), its frustum's (%.3f, %.3f): off by %.4f px\n",
                  space ? "from 2000 km" : "from 2 m", name, i == 0 ? "left" : "right", centres[path][i].x,
                  centres[path][i].y, expected.x, expected.y, glm::length(error));
      if (!space) continue;
      atmos_test::record_figure(std::string("stereo: sun disc centre error, ") + name + ", " +
                                    (i == 0 ? "left" : "right") + " eye",
                                glm::length(error), "px", "<= 0.05");
      EXPECT_LT(glm::length(error), 0.05) << name << " eye " << i;
    }
  }
  glDeleteTextures(1, &colour);
  glDeleteTextures(1, &depth);
  const double pixels_per_tangent = h / (2.0 * std::tan(glm::radians(0.5 * head.fov_deg)));
  const double expected_disparity = rig.interpupillary_m / rig.convergence_m * pixels_per_tangent;
  for (int path = 0; path < 2; ++path) {
    const double disparity = centres[path][1].x - centres[path][0].x;
    std::printf("%s: sky disparity %.3f px (ipd / convergence: %.3f px), vertical %.4f px\n",
                path == 0 ? "renderer" : "plugin", disparity, expected_disparity,
                centres[path][1].y - centres[path][0].y);
    EXPECT_NEAR(disparity, expected_disparity, 0.1);
    EXPECT_NEAR(centres[path][1].y, centres[path][0].y, 0.05);
  }
  }
}
