// atmos — the eyes of a stereo viewer (include/atmos/stereo.hpp).
//
// Off-axis stereo (parallel axes, shifted frusta; Lipton 1982; Bourke
// 1999): the eyes sit e = interpupillary / 2 either side of the head
// on its right axis, looking along the head's forward. The head's window at
// the convergence distance c spans tangents [l, r] horizontally; seen from
// the left eye (at -e) that same window spans [l + e / c, r + e / c], from
// the right eye [l - e / c, r - e / c]. A direction at infinity with
// tangent x then falls at (x - l_eye) / (r - l) of the image width in each
// eye, (e / c - (-e / c)) / (r - l) = (2 e / c) / (r - l) apart: the
// disparity of the sky.

#include "atmos/stereo.hpp"

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "atmos/atmosphere.hpp"
#include "physics/checks.hpp"

namespace atmos {
namespace {

void validate_fov(const FieldOfView& fov, const char* what) {
  const double limit = 0.5 * M_PI;
  for (double angle : {fov.left_rad, fov.right_rad, fov.up_rad, fov.down_rad})
    if (!(std::abs(angle) < limit))
      throw Error(std::string(what) + ": field of view angle " + number_text(angle) + " rad is not in (-pi/2, pi/2)");
  if (!(fov.left_rad < fov.right_rad))
    throw Error(std::string(what) + ": field of view left " + number_text(fov.left_rad) + " rad is not left of right " +
                number_text(fov.right_rad));
  if (!(fov.down_rad < fov.up_rad))
    throw Error(std::string(what) + ": field of view down " + number_text(fov.down_rad) + " rad is not below up " +
                number_text(fov.up_rad));
}

struct Tangents {
  double left, right, down, up;
};

Tangents tangents(const FieldOfView& fov) {
  return {std::tan(fov.left_rad), std::tan(fov.right_rad), std::tan(fov.down_rad), std::tan(fov.up_rad)};
}

FieldOfView fov_of(const Tangents& t) {
  return {std::atan(t.left), std::atan(t.right), std::atan(t.up), std::atan(t.down)};
}

void validate_pair(const Image& left, const Image& right, const char* what) {
  if (left.width != right.width || left.height != right.height)
    throw Error(std::string(what) + ": the eyes' images differ in size (" + std::to_string(left.width) + "x" +
                std::to_string(left.height) + " and " + std::to_string(right.width) + "x" +
                std::to_string(right.height) + ")");
  const size_t floats = size_t(left.width) * size_t(left.height) * 3;
  if (left.width < 1 || left.height < 1 || left.rgb.size() != floats || right.rgb.size() != floats)
    throw Error(std::string(what) + ": an eye's image is empty or its pixels do not match its size");
}

}  // namespace

std::array<Eye, 2> stereo_eyes(const Camera& head, const StereoRig& rig) {
  validate_camera(head);
  if (head.projection != Projection::perspective)
    throw Error("stereo_eyes: the head camera must use the perspective projection");
  if (!(rig.interpupillary_m >= 0.0 && rig.interpupillary_m <= 1e7))
    throw Error("stereo_eyes: interpupillary distance " + number_text(rig.interpupillary_m) +
                " m is not in [0, 1e7]");
  if (!(rig.convergence_m > 0.0))
    throw Error("stereo_eyes: convergence distance " + number_text(rig.convergence_m) + " m is not > 0");

  const glm::dvec3 forward = glm::normalize(head.forward);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, head.up));
  const glm::dvec3 up = glm::cross(right, forward);
  const double t = std::tan(0.5 * head.fov_deg * M_PI / 180.0);
  const double aspect = double(head.width) / double(head.height);
  const Tangents window{-aspect * t + head.lens_shift.x, aspect * t + head.lens_shift.x, -t + head.lens_shift.y,
                        t + head.lens_shift.y};
  const double e = 0.5 * rig.interpupillary_m;
  const double shift = std::isinf(rig.convergence_m) ? 0.0 : e / rig.convergence_m;

  std::array<Eye, 2> eyes;
  for (int i = 0; i < 2; ++i) {
    const double side = i == 0 ? -1.0 : 1.0;  // left eye at -e, right at +e
    Eye& eye = eyes[size_t(i)];
    eye.position = head.position + right * (side * e);
    eye.forward = forward;
    eye.up = up;
    eye.fov = fov_of({window.left - side * shift, window.right - side * shift, window.down, window.up});
  }
  return eyes;
}

Camera eye_camera(const Eye& eye, int width, int height) {
  validate_fov(eye.fov, "eye_camera");
  const Tangents t = tangents(eye.fov);
  const double horizontal = (t.right - t.left) / double(width);
  const double vertical = (t.up - t.down) / double(height);
  if (width < 1 || height < 1 || !(std::abs(horizontal - vertical) <= 1e-6 * vertical))
    throw Error("eye_camera: " + std::to_string(width) + "x" + std::to_string(height) +
                " pixels over this field of view are not square (" + number_text(horizontal) + " and " +
                number_text(vertical) + " per pixel)");
  Camera camera;
  camera.position = eye.position;
  camera.forward = eye.forward;
  camera.up = eye.up;
  camera.projection = Projection::perspective;
  camera.fov_deg = 2.0 * std::atan(0.5 * (t.up - t.down)) * 180.0 / M_PI;
  camera.lens_shift = glm::dvec2(0.5 * (t.right + t.left), 0.5 * (t.up + t.down));
  camera.width = width;
  camera.height = height;
  validate_camera(camera);
  return camera;
}

Eye covering_eye(const std::array<Eye, 2>& eyes) {
  glm::dvec3 forwards[2], ups[2];
  for (size_t i = 0; i < 2; ++i) {
    const Eye& e = eyes[i];
    validate_fov(e.fov, "covering_eye");
    if (!(glm::length(glm::cross(glm::normalize(e.forward), glm::normalize(e.up))) > 1e-6) ||
        !std::isfinite(glm::length(e.position)))
      throw Error("covering_eye: an eye's position is not finite or its forward and up are zero or parallel");
    forwards[i] = glm::normalize(e.forward);
    ups[i] = glm::normalize(e.up);
  }
  Eye cover;
  const glm::dvec3 sum = forwards[0] + forwards[1];
  if (!(glm::dot(forwards[0], forwards[1]) > 0.0)) throw Error("covering_eye: the eyes look more than 90 degrees apart");
  const glm::dvec3 forward = glm::normalize(sum);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, ups[0] + ups[1]));
  const glm::dvec3 up = glm::cross(right, forward);
  // The frusta's corner rays in the covering basis: the tangents' bounds.
  Tangents bound{INFINITY, -INFINITY, INFINITY, -INFINITY};
  for (size_t i = 0; i < 2; ++i) {
    const Tangents t = tangents(eyes[i].fov);
    const glm::dvec3 f = forwards[i], r = glm::normalize(glm::cross(f, ups[i])), u = glm::cross(r, f);
    for (double x : {t.left, t.right})
      for (double y : {t.down, t.up}) {
        const glm::dvec3 ray = f + r * x + u * y;
        const double z = glm::dot(ray, forward);
        if (!(z > 1e-9)) throw Error("covering_eye: an eye's frustum reaches behind the mean view axis");
        bound.left = std::min(bound.left, glm::dot(ray, right) / z);
        bound.right = std::max(bound.right, glm::dot(ray, right) / z);
        bound.down = std::min(bound.down, glm::dot(ray, up) / z);
        bound.up = std::max(bound.up, glm::dot(ray, up) / z);
      }
  }
  // An eye off the axis on a side the bounds do not reach needs them to:
  // a small margin, then the apex far enough back.
  const glm::dvec3 middle = 0.5 * (eyes[0].position + eyes[1].position);
  constexpr double kMargin = 1e-3;
  double back = 0.0;
  for (const Eye& e : eyes) {
    const glm::dvec3 d = e.position - middle;
    const double x = glm::dot(d, right), y = glm::dot(d, up), z = glm::dot(d, forward);
    if (x < 0.0) bound.left = std::min(bound.left, -kMargin);
    if (x > 0.0) bound.right = std::max(bound.right, kMargin);
    if (y < 0.0) bound.down = std::min(bound.down, -kMargin);
    if (y > 0.0) bound.up = std::max(bound.up, kMargin);
    back = std::max(back, -z);
    if (x < 0.0) back = std::max(back, x / bound.left - z);
    if (x > 0.0) back = std::max(back, x / bound.right - z);
    if (y < 0.0) back = std::max(back, y / bound.down - z);
    if (y > 0.0) back = std::max(back, y / bound.up - z);
  }
  cover.position = middle - forward * back;
  cover.forward = forward;
  cover.up = up;
  cover.fov = fov_of(bound);
  return cover;
}

glm::dmat4 view_matrix(const Eye& eye) {
  if (!(glm::length(glm::cross(glm::normalize(eye.forward), glm::normalize(eye.up))) > 1e-6))
    throw Error("view_matrix: the eye's forward and up are zero, not finite or parallel");
  return glm::lookAt(eye.position, eye.position + eye.forward, eye.up);
}

glm::dmat4 projection_matrix(const FieldOfView& fov, double near, double far) {
  validate_fov(fov, "projection_matrix");
  if (!(near > 0.0 && far > near && std::isfinite(far)))
    throw Error("projection_matrix: needs 0 < near < far < infinity, got " + number_text(near) + " and " +
                number_text(far));
  const Tangents t = tangents(fov);
  return glm::frustum(t.left * near, t.right * near, t.down * near, t.up * near, near, far);
}

glm::dmat4 reversed_z_projection(const FieldOfView& fov, double near) {
  validate_fov(fov, "reversed_z_projection");
  if (!(near > 0.0 && std::isfinite(near)))
    throw Error("reversed_z_projection: needs a finite near > 0, got " + number_text(near));
  const Tangents t = tangents(fov);
  // x_ndc = (2 x / -z - (r + l)) / (r - l), likewise y; depth = near / -z.
  glm::dmat4 p(0.0);
  p[0][0] = 2.0 / (t.right - t.left);
  p[2][0] = (t.right + t.left) / (t.right - t.left);
  p[1][1] = 2.0 / (t.up - t.down);
  p[2][1] = (t.up + t.down) / (t.up - t.down);
  p[3][2] = near;
  p[2][3] = -1.0;
  return p;
}

Image side_by_side(const Image& left, const Image& right) {
  validate_pair(left, right, "side_by_side");
  Image image;
  image.width = 2 * left.width;
  image.height = left.height;
  image.rgb.resize(size_t(image.width) * size_t(image.height) * 3);
  const size_t row = size_t(left.width) * 3;
  for (size_t y = 0; y < size_t(left.height); ++y) {
    std::copy_n(&left.rgb[y * row], row, &image.rgb[y * 2 * row]);
    std::copy_n(&right.rgb[y * row], row, &image.rgb[y * 2 * row + row]);
  }
  return image;
}

Image anaglyph(const Image& left, const Image& right) {
  validate_pair(left, right, "anaglyph");
  Image image = right;
  for (size_t i = 0; i < image.rgb.size(); i += 3) image.rgb[i] = left.rgb[i];
  return image;
}

}  // namespace atmos
