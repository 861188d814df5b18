// Energy balance of the scattering orders in optically thick atmospheres
// (energy_balance.cpp explains why and how).
#pragma once

#include <glm/glm.hpp>

#include "precompute/steps.hpp"

namespace atmos::precompute {

// Whether the orders of `atmosphere` are balanced: where the scattering
// tables' radius rows follow the optical depth (the optically thick
// atmospheres, scattering_r_optical_depth_weight > 0).
bool balances_orders(const AtmosphereParams& atmosphere);

// One wavelength triple's balance, order after order:
//   OrderEnergyBalance balance(ms);
//   balance.set_single_scattering_emission(transmittance);   // order 1's source
//   for each order n >= 1, once its light is known:
//     balance.measure_order(..., n);        // what the medium removes of it
//     compute_scattering_density_table(...) // order n + 1's source
//     balance.balance_density(density);     // rescaled to re-emit that
// All integrals are over the points whose sun zenith cosine is within the
// tables' range (>= mu_s_min), like the tables themselves.
class OrderEnergyBalance {
 public:
  explicit OrderEnergyBalance(const AtmosphereParams& atmosphere);

  // Order 1's emission: the sunlight the medium scatters, ∫ beta_s T_sun E_sun dV.
  void set_single_scattering_emission(const Table2D& transmittance);

  // What the medium truly removes from the light of order `order` (its
  // radiance as incident_radiance in functions.glsl reads it: the single
  // scattering tables for order 1, `radiance` for the others, and the
  // ground's reflection of `irradiance`, the sky irradiance of order - 1):
  // the light the order emitted minus the flux of its radiance out through
  // the top of the atmosphere and into the ground; and the part of it that
  // is scattered, which order + 1 must emit.
  void measure_order(const Table2D& transmittance, const Table3D& single_rayleigh, const Table3D& single_aerosol,
                     const Table3D& radiance, const Table2D& irradiance, int order);

  // Scales the density of the next order (per channel) so that it emits what
  // the last measured order lost to scattering; returns the factors, also
  // kept in scale(). Throws atmos::Error if a factor is outside [0.8, 1.25]
  // (the tables cannot represent the atmosphere).
  vec3 balance_density(Table3D& density);

  // The factors of the last balance_density (1 before it), applied as they
  // are to the densities of the tail solver's fields.
  vec3 scale() const { return scale_; }

  // Of the current order (for tests): its emission, and what the medium
  // removes of it.
  glm::dvec3 emitted() const { return emitted_; }
  glm::dvec3 removed() const { return removed_; }

 private:
  AtmosphereParams a_;
  std::vector<double> radius_, radius_weight_;  // of dV / dmu_s: 2 pi r^2 dr
  std::vector<double> mu_s_, mu_s_weight_;
  std::vector<double> view_, view_weight_;  // Gauss-Legendre on [-1, 1], moved to each half of the sphere
  int order_ = 0;  // the last measured
  glm::dvec3 emitted_{0.0}, removed_{0.0}, scattered_next_{0.0};
  vec3 scale_{1.0f};
};

}  // namespace atmos::precompute
