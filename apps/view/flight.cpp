#include "flight.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace atmos_view {

namespace {

constexpr double kDegree = M_PI / 180.0;

}  // namespace

void local_frame(const glm::dvec3& position, glm::dvec3& east, glm::dvec3& north, glm::dvec3& up) {
  up = glm::normalize(position);
  east = glm::cross(glm::dvec3(0, 0, 1), up);
  east = glm::length(east) < 1e-9 ? glm::dvec3(1, 0, 0) : glm::normalize(east);
  north = glm::cross(up, east);
}

Flight::Flight(double bottom_radius_m) : bottom_radius_m_(bottom_radius_m), position_(0, 0, bottom_radius_m) {}

void Flight::place(double latitude_deg, double longitude_deg, double altitude_m, double heading_deg, double pitch_deg,
                   const GroundHeight& ground) {
  const double lat = latitude_deg * kDegree, lon = longitude_deg * kDegree;
  const glm::dvec3 up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
  position_ = up * (bottom_radius_m_ + ground(up * bottom_radius_m_) + altitude_m);
  heading_deg_ = heading_deg;
  pitch_deg_ = pitch_deg;
  clamp(ground);
}

CameraPose Flight::pose() const {
  glm::dvec3 east, north, up;
  local_frame(position_, east, north, up);
  const double h = heading_deg_ * kDegree, p = pitch_deg_ * kDegree;
  const glm::dvec3 level = north * std::cos(h) + east * std::sin(h);
  CameraPose pose;
  pose.position = position_;
  pose.forward = glm::normalize(level * std::cos(p) + up * std::sin(p));
  // The right of the level direction is level x up for any pitch (|pitch|
  // < 90 degrees keeps forward off the vertical), so the basis has no
  // singularity until the pitch limit.
  const glm::dvec3 right = glm::normalize(glm::cross(level, up));
  pose.up = glm::cross(right, pose.forward);
  return pose;
}

double Flight::latitude_deg() const { return std::asin(std::clamp(glm::normalize(position_).z, -1.0, 1.0)) / kDegree; }

double Flight::longitude_deg() const { return std::atan2(position_.y, position_.x) / kDegree; }

double Flight::altitude_m(const GroundHeight& ground) const {
  return glm::length(position_) - bottom_radius_m_ - ground(position_);
}

double Flight::speed_m_per_s(const GroundHeight& ground) const {
  return kSpeedPerSecond * std::max(altitude_m(ground), 1.0);
}

void Flight::update(const FlightInput& input, double dt_s, const GroundHeight& ground) {
  const double dt = std::clamp(std::isfinite(dt_s) ? dt_s : 0.0, 0.0, 0.25);
  if (std::isfinite(input.look_dx) && std::isfinite(input.look_dy)) {
    heading_deg_ = std::remainder(heading_deg_ + input.look_dx * kLookDegPerPixel, 360.0);
    pitch_deg_ -= input.look_dy * kLookDegPerPixel;
  }
  const CameraPose p = pose();
  glm::dvec3 east, north, up;
  local_frame(position_, east, north, up);
  const glm::dvec3 right = glm::cross(p.forward, p.up);
  glm::dvec3 move(0.0);
  if (input.forward) move += p.forward;
  if (input.back) move -= p.forward;
  if (input.right) move += right;
  if (input.left) move -= right;
  if (input.up) move += up;
  if (input.down) move -= up;
  const double length = glm::length(move);
  const double multiplier = std::isfinite(input.speed_multiplier) ? std::clamp(input.speed_multiplier, 0.0, 100.0) : 1.0;
  if (length > 0.0) {
    // The step is a fraction k dt of the altitude: the camera approaches the
    // ground geometrically and the clamp below only catches the last step.
    const double step = speed_m_per_s(ground) * multiplier * dt;
    // Heading and pitch are relative to the local frame, which turns with
    // the position: a level flight around the planet stays level.
    position_ += move / length * step;
  }
  if (input.jump != jump_none) jump(input.jump, ground);
  clamp(ground);
}

void Flight::jump(int which, const GroundHeight& ground) {
  double altitude = 0.0, pitch = pitch_deg_;
  switch (which) {
    case jump_ground: altitude = 2.0, pitch = 0.0; break;
    case jump_10km: altitude = 10e3, pitch = -10.0; break;
    case jump_orbit: altitude = 400e3, pitch = -20.0; break;
    case jump_far: altitude = 2.5 * bottom_radius_m_, pitch = -kPitchLimitDeg; break;
    default: return;
  }
  const glm::dvec3 up = glm::normalize(position_);
  position_ = up * (bottom_radius_m_ + ground(position_) + altitude);
  pitch_deg_ = pitch;
  clamp(ground);
}

void Flight::set_bottom_radius(double bottom_radius_m, double altitude_m, const GroundHeight& ground) {
  bottom_radius_m_ = bottom_radius_m;
  const glm::dvec3 up = glm::normalize(position_);
  position_ = up * (bottom_radius_m_ + ground(up * bottom_radius_m_) + altitude_m);
  clamp(ground);
}

void Flight::clamp(const GroundHeight& ground) {
  if (!std::isfinite(position_.x) || !std::isfinite(position_.y) || !std::isfinite(position_.z) ||
      glm::length(position_) < 1e-3 * bottom_radius_m_)
    position_ = glm::dvec3(0, 0, bottom_radius_m_ + 2.0);
  if (!std::isfinite(heading_deg_)) heading_deg_ = 0.0;
  if (!std::isfinite(pitch_deg_)) pitch_deg_ = 0.0;
  pitch_deg_ = std::clamp(pitch_deg_, -kPitchLimitDeg, kPitchLimitDeg);
  const glm::dvec3 up = glm::normalize(position_);
  const double lowest = bottom_radius_m_ + ground(position_) + kMinClearanceM;
  const double highest = kMaxDistanceRadii * bottom_radius_m_;
  const double r = std::clamp(glm::length(position_), lowest, highest);
  position_ = up * r;
}

}  // namespace atmos_view
