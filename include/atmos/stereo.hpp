// atmos — stereo: the two eyes of a viewer, their off-axis frusta and
// matrices, and the two images combined for a stereo display.
//
// Each eye is a camera of its own: the renderer (atmos::Camera with its
// lens_shift) and the engine plugin (FrameInput::view and ::projection of
// that eye) trace the sky, the sun's disc and the aerial perspective from
// that eye's own position and inverse projection, so both eyes see the sun
// at infinity where their own frusta put it (one sun, fused). Units: metres,
// radians.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <array>

#include "atmos/image.hpp"
#include "atmos/renderer.hpp"

namespace atmos {

// A field of view by the angles of its four sides from the view axis,
// radians, as OpenXR's XrFovf: left and down are negative when that side
// lies left of / below the axis. A headset's eye has its own, in general
// asymmetric (narrower on the nose's side) and not the same vertically in
// the two eyes. Each in (-pi/2, pi/2), left < right, down < up.
struct FieldOfView {
  double left_rad = -0.5;
  double right_rad = 0.5;
  double up_rad = 0.5;
  double down_rad = -0.5;
};

// An eye: where it is and where it looks (planet-centred metres for the
// renderer, like Camera; the engine's world for view_matrix), and its field
// of view about `forward`, with `up` towards the up side.
struct Eye {
  glm::dvec3 position{0.0};
  glm::dvec3 forward{0.0, 1.0, 0.0};  // normalised internally
  glm::dvec3 up{0.0, 0.0, 1.0};       // up hint, not parallel to forward
  FieldOfView fov;
};

// Two eyes before a stereo screen: parallel view axes (toed-in axes would
// give the sky vertical disparities), the eyes `interpupillary_m` apart
// along the head's right axis, and each frustum shifted so that at the
// distance `convergence_m` both see the head's own window (the plane of
// zero disparity: nearer points come out of the screen, farther ones go
// behind it). A point at infinity, the sky and the sun, then has the
// horizontal disparity interpupillary_m / convergence_m in tangent units:
// (that) / (tan right - tan left) of the image width. An infinite
// convergence gives parallel frusta and the sky at zero disparity.
// Baselines wider than the eyes' (hyperstereo: metres to kilometres for
// landscapes, more for a planet from orbit) give distant relief depth.
struct StereoRig {
  double interpupillary_m = 0.064;  // in [0, 1e7]
  double convergence_m = 10.0;      // > 0, may be infinite
};

// The left and right eyes of `head`, a perspective Camera (position,
// forward, up, fov_deg and the aspect width / height; lens_shift moves both
// frusta). Throws atmos::Error on an invalid camera, a projection other
// than perspective or a rig outside its ranges.
std::array<Eye, 2> stereo_eyes(const Camera& head, const StereoRig& rig);

// The renderer's camera of an eye, width x height pixels: the field of
// view's vertical extent gives fov_deg, the centre of its extents the
// lens_shift. The renderer's pixels are square: throws atmos::Error unless
// (tan right - tan left) / width equals (tan up - tan down) / height within
// 1e-6 of it, or on an invalid field of view.
Camera eye_camera(const Eye& eye, int width, int height);

// One eye whose frustum holds both eyes' frusta: the culling and
// level-of-detail view of an engine that selects its geometry once for the
// pair (Globe::draw_views). Its axes are the mean of the eyes' (they may be
// canted, as a headset's displays), its four angles bound every corner ray
// of both frusta, and its apex lies on the axis behind the eyes' midpoint,
// by the least distance d for which each eye lies inside its frustum (an
// eye at lateral offset x from the midpoint and z along the axis is inside
// when tan left (z + d) <= x <= tan right (z + d), likewise vertically):
// about the half baseline over the tangent of the outer half-angle, 2.7 cm
// for 64 mm eyes and a 100 degree field. Throws atmos::Error on an invalid
// eye or eyes whose views do not share a hemisphere.
Eye covering_eye(const std::array<Eye, 2>& eyes);

// The engine's matrices of an eye: world -> view (rigid; the view looks
// along -z with y up, as glm::lookAt), and view -> clip from the four angles
// in OpenGL's depth convention (glm::frustum: -1 at `near`, 1 at `far`) or
// with reversed-Z and no far plane (depth 1 at `near`, 0 at infinity, for
// glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE), as the globe draws).
// Throw atmos::Error on an invalid field of view or near >= far, near <= 0.
glm::dmat4 view_matrix(const Eye& eye);
glm::dmat4 projection_matrix(const FieldOfView& fov, double near, double far);
glm::dmat4 reversed_z_projection(const FieldOfView& fov, double near);

// The two images side by side, left eye on the left (for parallel viewing
// or a side-by-side 3D display), 2 width x height.
Image side_by_side(const Image& left, const Image& right);

// A red-cyan colour anaglyph of two linear images: red from the left eye,
// green and blue from the right (filtered by red-cyan glasses, each eye
// sees its own image). Throws atmos::Error if the sizes differ.
Image anaglyph(const Image& left, const Image& right);

}  // namespace atmos
