// The upward flux from the SkyModel's radiance: ∫ L(-w) mu dw over the lower
// hemisphere. At the top of the atmosphere above the subsolar point it is the
// quantity of the energy-conservation tests (what goes in at the top comes
// out at the top, minus what diffuses sideways, for a white non-absorbing
// planet); tests/venus_accuracy.cpp takes the light reflected to space with
// it.
#pragma once

#include <cmath>

#include "atmos/atmosphere.hpp"
#include "atmos/sky.hpp"

namespace atmos_test {

// ∫ L(-w) mu dw over the lower hemisphere at `point` (planet-centred, on the
// +z axis, e.g. atmos::observer_position) with the sun in `sun`; midpoint
// rule in the angle from the nadir (n_theta) and in azimuth (n_phi). Per
// channel of the model's sRGB-or-wavelength output.
inline glm::dvec3 upward_flux(const atmos::SkyModel& model, const glm::dvec3& point, const glm::dvec3& sun,
                              int n_theta, int n_phi) {
  glm::dvec3 up(0.0);
  for (int i = 0; i < n_theta; ++i) {
    const double theta = (i + 0.5) / n_theta * M_PI / 2.0;
    for (int j = 0; j < n_phi; ++j) {
      const double phi = (j + 0.5) / n_phi * 2.0 * M_PI;
      const glm::dvec3 down(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), -std::cos(theta));
      up += model.radiance(point, down, sun, false) * std::cos(theta) * std::sin(theta) * (M_PI / 2.0 / n_theta) *
            (2.0 * M_PI / n_phi);
    }
  }
  return up;
}

// upward_flux at 1 m below the top, the sun at the zenith.
inline glm::dvec3 upward_flux_at_top(const atmos::Atmosphere& a, const atmos::SkyModel& model, int n_theta,
                                     int n_phi) {
  return upward_flux(model, glm::dvec3(0.0, 0.0, a.top_radius_m - 1.0), glm::dvec3(0.0, 0.0, 1.0), n_theta, n_phi);
}

}  // namespace atmos_test
