// atmos — moons that eclipse the sun.
//
// A moon is an opaque sphere between the sun and the planet. Every point of
// the atmosphere and of the ground receives the part of the limb-darkened
// solar disc that the moons leave visible from there (circle-circle overlap,
// src/physics/eclipse.glsl), so the sunlight fades in the penumbra and goes
// out in the umbra — on the ground, in the single-scattered sky light (node
// by node along each view ray) and, by a documented approximation, in the
// multiple-scattered light (diffuse_light_visible_fraction); a moon in
// front of the sun hides its disc and the stars, and shows its own lit side.
// Renderer::set_moons, render_cpu and the CLI's --moon take them.
#pragma once

#include <glm/vec3.hpp>

#include <vector>

namespace atmos {

struct Moon {
  glm::dvec3 centre_m{0.0};  // planet-centred, metres (the frame of the camera and the sun direction)
  double radius_m = 0.0;
};

// The most moons a frame can have.
constexpr int kMaxMoons = 4;

// The Moon's mean distance from the Earth (384 400 km) and its radius
// (1737.4 km; IAU/IAG Working Group on Cartographic Coordinates, Archinal
// et al. 2018, Celest. Mech. Dyn. Astr. 130:22).
constexpr double kMoonDistanceM = 384400e3;
constexpr double kMoonRadiusM = 1737.4e3;

// A moon placed in the sky of `observer` (planet-centred, m): its centre at
// `distance_m` from the observer in the unit direction `direction`
// (planet-centred frame), with the radius that makes it look
// `angular_radius_rad` wide (sin of it times the distance). The CLI's
// `--moon AZ,EL,ANGULAR_RADIUS_DEG` is this with the direction from
// direction_from_azimuth_elevation in the observer's local frame and the
// Moon's distance. Throws atmos::Error for a non-unit or non-finite
// direction, an angular radius outside (0, 10°] or a distance that is not
// finite and > 0.
Moon moon_in_sky(const glm::dvec3& observer, const glm::dvec3& direction, double angular_radius_rad,
                 double distance_m = kMoonDistanceM);

// Throws atmos::Error with one line naming the first problem: more than
// kMaxMoons moons, a non-finite centre, a radius that is not finite and
// > 0, or a moon that reaches into the atmosphere (its centre closer to the
// planet's centre than top_radius_m + its radius).
void validate_moons(const std::vector<Moon>& moons, double top_radius_m);

// Whether any of `moons` can hide part of the sun (a disc of angular radius
// sun_angular_radius_rad in the direction `sun_direction`, normalised here)
// from some point of an atmosphere of top radius top_radius_m or of the air
// up to 1000 km beyond it that feeds its diffuse light: the test by which
// AtmospherePass and Globe drop, for a frame, moons that eclipse nothing
// (their eclipse then costs nothing). An engine lighting its own surfaces
// with atmos_eclipse (AtmospherePass::glsl_library) can skip it likewise.
// Throws atmos::Error as validate_moons does, or for a zero or non-finite
// sun direction.
bool moons_may_eclipse(const std::vector<Moon>& moons, const glm::dvec3& sun_direction, double top_radius_m,
                       double sun_angular_radius_rad);

}  // namespace atmos
