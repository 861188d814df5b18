// atmos view: the camera's flight over a planet — where it is, where it
// looks, and how the keys and the mouse move it.
//
// The camera is a position in planet-centred metres (the planet's world
// frame, z the polar axis) and a heading and a pitch in the local frame of
// the ground point below it (east, north, up): heading from north towards
// east, pitch above the horizontal. Its speed is proportional to its
// altitude above the surface below it (v = k max(h, 1 m)), so that one
// key press moves a walker a metre or two and a spacecraft hundreds of
// kilometres: a constant relative speed makes the time to halve or double
// the altitude the same everywhere, ln 2 / k. Every move is clamped to a
// minimum clearance above the surface and to a maximum distance from the
// planet, so no input can put the camera underground or at a position the
// renderer cannot hold.
#pragma once

#include <glm/vec3.hpp>

#include <functional>

namespace atmos_view {

// What the user does during one frame.
struct FlightInput {
  // Held keys: W/S (forward, back along the view), A/D (left, right), Q/E
  // (down, up along the local vertical).
  bool forward = false, back = false, left = false, right = false, down = false, up = false;
  double speed_multiplier = 1.0;  // Shift: x10, Ctrl: x0.1
  // Mouse look, pixels of the drag this frame (x right, y down).
  double look_dx = 0.0, look_dy = 0.0;
  // Keys 1-4: jump_ground .. jump_far; 0: none.
  int jump = 0;
};

// The jump targets (keys 1-4): altitudes above the surface below the camera.
enum Jump { jump_none = 0, jump_ground = 1, jump_10km = 2, jump_orbit = 3, jump_far = 4 };

// The camera's basis: orthonormal, right-handed (right x up = -forward, as
// glm::lookAt expects).
struct CameraPose {
  glm::dvec3 position{0.0};  // planet-centred, m
  glm::dvec3 forward{0, 1, 0};
  glm::dvec3 up{0, 0, 1};
};

class Flight {
 public:
  // Height of the surface above the datum (bottom radius) below a
  // planet-centred position, m (the globe's relief; 0 for the sphere).
  using GroundHeight = std::function<double(const glm::dvec3&)>;

  static constexpr double kMinClearanceM = 0.5;       // eye height above the surface at least
  static constexpr double kMaxDistanceRadii = 100.0;  // distance from the centre at most, planet radii
  static constexpr double kPitchLimitDeg = 89.5;      // |pitch| at most (the view never aligns with the vertical)
  static constexpr double kLookDegPerPixel = 0.15;
  static constexpr double kSpeedPerSecond = 1.0;      // k: altitude per second

  explicit Flight(double bottom_radius_m);

  // Places the camera above the ground point (latitude, longitude, degrees)
  // at `altitude_m` above its surface, looking along heading and pitch (degrees).
  void place(double latitude_deg, double longitude_deg, double altitude_m, double heading_deg, double pitch_deg,
             const GroundHeight& ground);
  // Moves the camera by one frame of input lasting dt seconds (clamped to
  // [0, 0.25] s, so that a stalled frame does not throw it far).
  void update(const FlightInput& input, double dt_s, const GroundHeight& ground);
  // Jumps 1-4: 2 m, 10 km, 400 km and 2.5 planet radii above the surface
  // below the camera, with a pitch that shows the horizon (straight down
  // from 2.5 radii).
  void jump(int which, const GroundHeight& ground);

  // A planet of another radius (new tables): the camera keeps its altitude
  // above the surface and its direction from the centre.
  void set_bottom_radius(double bottom_radius_m, double altitude_m, const GroundHeight& ground);

  CameraPose pose() const;
  glm::dvec3 position() const { return position_; }
  double heading_deg() const { return heading_deg_; }
  double pitch_deg() const { return pitch_deg_; }
  double latitude_deg() const;
  double longitude_deg() const;
  // Above the surface below the camera, m.
  double altitude_m(const GroundHeight& ground) const;
  // The speed a movement key gives now, m/s (without the multiplier).
  double speed_m_per_s(const GroundHeight& ground) const;

 private:
  // Keeps the position above the surface by the clearance, inside the
  // maximum distance, and finite; keeps the pitch within its limit.
  void clamp(const GroundHeight& ground);

  double bottom_radius_m_;
  glm::dvec3 position_{0.0};
  double heading_deg_ = 0.0;
  double pitch_deg_ = 0.0;
};

// The local frame at a planet-centred position: east, north and up (unit,
// right-handed: east x north = up). At the poles, where east is undefined,
// east is the world's +x.
void local_frame(const glm::dvec3& position, glm::dvec3& east, glm::dvec3& north, glm::dvec3& up);

}  // namespace atmos_view
