// Energy balance of the scattering orders in optically thick atmospheres.
//
// Why. Each order's light is a table of radiance at radius rows, and the next
// order's source (the density) is computed at the same rows and read linearly
// between them by the multiple scattering step. In an optically thick layer
// the rows are optical depths apart (Venus's cloud deck, 47-70 km: 2-3.4 at
// the default 32 rows), and there an order's light curves over one row
// spacing, so between the rows its interpolation holds more or less light
// than the medium truly removes: at order 1, whose light falls by e^-2.5
// from one row to the next into the cloud, the interpolated light is 1.2-1.8
// times what the flux balance of each shell between two rows says the shell
// removes; at the peak of the light the shells hold less than they remove.
// Over the whole atmosphere most of this cancels, but not all: on a
// conservative Venus (tests/energy_budget_accuracy.cpp) every order loses a
// few thousandths of its light (0.19 % of order 10, about 0.05 % of order
// 150), and over the hundreds of orders that light takes to leave the cloud
// that was a tenth of the sunlight: over a white ground the tables sent 0.90 of
// it back to space where the brute-force reference sends 0.98. More rows
// lose less (64: 0.10 % of order 10), at twice the cost of every step.
//
// What. The whole atmosphere is a closed balance. Order n removes from its
// own light
//   removed = emitted - (flux out through the top + flux into the ground),
// the fluxes taken from the radiance at the top and bottom rows, which are
// the transport's results at exactly those radii (no interpolation in r).
// Of that, the medium scatters the fraction that the tables' own radiance
// gives, ∫ beta_s ∫ L dω dV / ∫ beta_ext ∫ L dω dV (1 where nothing
// absorbs), and that is what order n + 1 must emit. The density of order
// n + 1 is scaled by one factor per channel so that it does. Measured on
// that Venus with a finer quadrature of its own (tests/energy_budget_
// accuracy.cpp): every order from 3 on then keeps within 7e-5 of its light
// what does not escape (order 1 within 0.42 %, order 2 0.09 %). The shape
// of the source is left as the tables give it.
//
// Not per shell. The same balance holds for each shell between two rows
// (flux in through the lower row, out through the upper one), and a factor
// per row could make each shell re-emit what it removed. But the shells deep
// below the light's peak receive almost all their light as flux from above,
// so their balance is a small difference of large fluxes; the row factors,
// two shells per row, propagate those errors from shell to shell, and the
// least-squares factors oscillated between -9e4 and 1e4 on Venus's order 1.
// And a shell 2.5 optical depths thick whose right amount of source sits at
// the wrong height within it still lets the wrong amount escape. Factors per
// shell that do not propagate (each shell's source scaled by its own factor
// in the transport, from the fluxes through its two rows) were tried too:
// they came out at 0.25-1.34 on Venus's orders 2-6, and over a white ground
// Venus returned 0.842 of the sunlight, less than without any balance.
//
// Only the explicit orders are balanced, not the tail solver's sum of the
// orders after them (precompute.cpp says why).
//
// Cost: about as much as the multiple scattering step itself (Venus,
// default sizes: 14 s against 14 s per wavelength triple; 28 s against
// 29 s over a white ground, 64 orders). It is off by default
// (PrecomputeOptions::balance_orders): over a white ground, Venus then
// returns 0.947 / 0.938 / 0.928 of the sunlight (680 / 550 / 440 nm)
// instead of 0.903 / 0.895 / 0.888, the reference 0.98 +- 0.01 at 550 nm
// (tests/energy_accuracy.cpp); but the real Venus gets 1.05-1.06 of the
// reference's light on the ground instead of 0.97-0.98, and reflects 0.93
// of the reference's light to space instead of 0.90 (tests/venus_
// accuracy.cpp). One factor per order puts the lost light back wherever
// the order's source is, and presumably partly below the cloud, where it
// was not lost. (Those figures are of the linear interpolation of the
// source between radius rows, which lost the light. Since the source is
// read between rows with cubic weights, functions.glsl
// source_function_lookup, the orders nearly keep their light, and the
// balance takes the white-ground Venus from 1.006 to 0.986 of the sunlight
// but lowers the real Venus: 0.96 of the reference's reflected light
// instead of 0.98, 0.90-0.96 of its light on the ground instead of
// 0.92-0.98; 2026-11-26.)
//
// The integrals are quadratures of their own: Gauss-Legendre in r between
// each pair of rows (the interpolated tables have kinks at the rows), in the
// sun zenith cosine (split at 0, from mu_s_min: the points whose sun is
// beyond the tables' range are not in the tables at all) and in the view
// zenith cosine (split at the horizon), the midpoint rule in azimuth.
#include "precompute/energy_balance.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "atmos/atmosphere.hpp"

namespace atmos::precompute {

namespace {

constexpr int kRadiiPerRow = 6;   // Gauss nodes in r between two rows
constexpr int kSunCosines = 16;   // per side of the horizon
constexpr int kViewCosines = 16;  // per side of the horizon
constexpr int kAzimuths = 8;      // over [0, pi], doubled by symmetry
// The factors correct a few percent (measured on Venus's default tables at
// 550 nm: 0.94 for order 2, whose density the 8 nu tiles overestimate, then
// 1.035, 1.018, 1.010, ... 1.0019 at order 12). A factor outside this range
// means that the tables cannot represent the atmosphere, and is refused:
// with 4 nu tiles, order 2 of Venus needs 0.62 on 16 radius rows, 0.79 on
// 32 rows and 32 view cosines, 0.82 on 32 rows and 64 view cosines (0.93
// there with 8 nu tiles).
constexpr float kMinScale = 0.8f, kMaxScale = 1.25f;

void append_gauss(int n, double lo, double hi, std::vector<double>& x, std::vector<double>& w) {
  std::vector<double> nodes, weights;
  gauss_legendre(n, lo, hi, nodes, weights);
  x.insert(x.end(), nodes.begin(), nodes.end());
  w.insert(w.end(), weights.begin(), weights.end());
}

glm::dvec3 to_dvec3(const vec3& v) { return glm::dvec3(v.x, v.y, v.z); }

// ∫ f(mu, nu) dω over the directions at (r, mu_s) whose view zenith cosine
// is in [lo, hi] (which must not straddle the horizon: the radiance jumps
// there).
template <class F>
glm::dvec3 over_cosines(const std::vector<double>& view, const std::vector<double>& view_weight, double lo, double hi,
                        double mu_s, const F& f) {
  const double sin_sun = std::sqrt(std::max(0.0, 1.0 - mu_s * mu_s));
  glm::dvec3 sum(0.0);
  for (size_t i = 0; i < view.size(); ++i) {
    const double mu = lo + 0.5 * (hi - lo) * (view[i] + 1.0);
    const double weight = 0.5 * (hi - lo) * view_weight[i] * (2.0 * M_PI / kAzimuths);
    const double sin_view = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    for (int k = 0; k < kAzimuths; ++k) {
      const double nu = mu * mu_s + sin_view * sin_sun * std::cos((k + 0.5) * M_PI / kAzimuths);
      sum += weight * f(float(mu), physics::clamp_cosine(float(nu)));
    }
  }
  return sum;
}

// ∫ f(mu, nu) dω over all the directions at (r, mu_s), split at the horizon.
template <class F>
glm::dvec3 over_directions(const AtmosphereParams& a, const std::vector<double>& view,
                           const std::vector<double>& view_weight, double r, double mu_s, const F& f) {
  const double mu_h = physics::horizon_mu(a, float(r));
  return over_cosines(view, view_weight, -1.0, mu_h, mu_s, f) + over_cosines(view, view_weight, mu_h, 1.0, mu_s, f);
}

// Σ over the radius nodes of weight * per_radius(r), in parallel.
template <class F>
glm::dvec3 over_volume(const std::vector<double>& radius, const std::vector<double>& weight, const F& per_radius) {
  std::vector<glm::dvec3> terms(radius.size());
  tbb::parallel_for(size_t(0), radius.size(), [&](size_t i) { terms[i] = weight[i] * per_radius(radius[i]); });
  glm::dvec3 sum(0.0);
  for (const glm::dvec3& t : terms) sum += t;
  return sum;
}

}  // namespace

bool balances_orders(const AtmosphereParams& atmosphere) { return atmosphere.scattering_r_optical_depth_weight > 0.0f; }

OrderEnergyBalance::OrderEnergyBalance(const AtmosphereParams& atmosphere) : a_(atmosphere) {
  std::vector<double> rows;
  for (int z = 0; z < a_.scattering_r_size; ++z) {
    float r, mu, mu_s, nu;
    bool ground;
    physics::r_mu_mu_s_nu_from_scattering_texel(a_, vec3(0.0f, 0.0f, float(z)), r, mu, mu_s, nu, ground);
    rows.push_back(double(r));
  }
  rows.front() = a_.bottom_radius;
  rows.back() = a_.top_radius;
  for (size_t k = 0; k + 1 < rows.size(); ++k) append_gauss(kRadiiPerRow, rows[k], rows[k + 1], radius_, radius_weight_);
  for (size_t i = 0; i < radius_.size(); ++i) radius_weight_[i] *= 2.0 * M_PI * radius_[i] * radius_[i];
  const double mu_s_min = std::max(-1.0, double(a_.mu_s_min));
  if (mu_s_min < 0.0) append_gauss(kSunCosines, mu_s_min, 0.0, mu_s_, mu_s_weight_);
  append_gauss(kSunCosines, std::max(mu_s_min, 0.0), 1.0, mu_s_, mu_s_weight_);
  append_gauss(kViewCosines, -1.0, 1.0, view_, view_weight_);
}

void OrderEnergyBalance::set_single_scattering_emission(const Table2D& transmittance) {
  const glm::dvec3 sun = to_dvec3(a_.solar_irradiance);
  emitted_ = over_volume(radius_, radius_weight_, [&](double r) {
    vec3 rayleigh, aerosol, extinction;
    physics::medium_at(a_, float(r), rayleigh, aerosol, extinction);
    glm::dvec3 sum(0.0);
    for (size_t j = 0; j < mu_s_.size(); ++j)
      sum += mu_s_weight_[j] *
             to_dvec3(physics::transmittance_to_sun(a_, transmittance.sampler(), float(r), float(mu_s_[j])));
    return to_dvec3(rayleigh + aerosol) * sun * sum;
  });
}

void OrderEnergyBalance::measure_order(const Table2D& transmittance, const Table3D& single_rayleigh,
                                       const Table3D& single_aerosol, const Table3D& radiance,
                                       const Table2D& irradiance, int order) {
  double mu_s_now = 0.0;
  auto incident = [&](double r, double mu_s, float mu, float nu) {
    return to_dvec3(physics::incident_radiance(a_, transmittance.sampler(), single_rayleigh.sampler(),
                                               single_aerosol.sampler(), radiance.sampler(), irradiance.sampler(),
                                               float(r), mu, float(mu_s), nu, order));
  };
  // The light that leaves through the top: the flux of the radiance seen
  // looking down there (L looks along the view direction, against the
  // light's, so -mu L is the upward flux): below the horizon and between
  // it and the zenith angle 90° (the limb: light that leaves without
  // having come near the ground). Looking up from the top sees nothing.
  const double mu_h = physics::horizon_mu(a_, a_.top_radius);
  auto leaving_top = [&](float mu, float nu) { return -double(mu) * incident(a_.top_radius, mu_s_now, mu, nu); };
  // The light that goes into the ground: the flux of the radiance seen
  // looking up from it, less the ground's reflection of order - 1's light,
  // seen looking down (the ground emits part of this order).
  glm::dvec3 out_top(0.0), into_ground(0.0);
  for (size_t j = 0; j < mu_s_.size(); ++j) {
    mu_s_now = mu_s_[j];
    out_top += mu_s_weight_[j] * (over_cosines(view_, view_weight_, -1.0, mu_h, mu_s_now, leaving_top) +
                                  over_cosines(view_, view_weight_, mu_h, 0.0, mu_s_now, leaving_top));
    into_ground += mu_s_weight_[j] * over_directions(a_, view_, view_weight_, a_.bottom_radius, mu_s_now,
                                                     [&](float mu, float nu) {
                                                       return double(mu) * incident(a_.bottom_radius, mu_s_now, mu, nu);
                                                     });
  }
  const double top = a_.top_radius, bottom = a_.bottom_radius;
  const glm::dvec3 escaped = 2.0 * M_PI * (top * top * out_top + bottom * bottom * into_ground);
  // What the tables' radiance gives the medium to remove and to scatter.
  glm::dvec3 extinct(0.0), scattered(0.0);
  std::vector<glm::dvec3> terms(2 * radius_.size());
  tbb::parallel_for(size_t(0), radius_.size(), [&](size_t i) {
    const double r = radius_[i];
    vec3 rayleigh, aerosol, extinction;
    physics::medium_at(a_, float(r), rayleigh, aerosol, extinction);
    glm::dvec3 sum(0.0);
    for (size_t j = 0; j < mu_s_.size(); ++j)
      sum += mu_s_weight_[j] * over_directions(a_, view_, view_weight_, r, mu_s_[j], [&](float mu, float nu) {
               return incident(r, mu_s_[j], mu, nu);
             });
    terms[2 * i] = radius_weight_[i] * to_dvec3(extinction) * sum;
    terms[2 * i + 1] = radius_weight_[i] * to_dvec3(rayleigh + aerosol) * sum;
  });
  for (size_t i = 0; i < radius_.size(); ++i) {
    extinct += terms[2 * i];
    scattered += terms[2 * i + 1];
  }
  order_ = order;
  removed_ = emitted_ - escaped;
  for (int c = 0; c < 3; ++c) scattered_next_[c] = extinct[c] > 0.0 ? removed_[c] * scattered[c] / extinct[c] : 0.0;
}

vec3 OrderEnergyBalance::balance_density(Table3D& density) {
  const glm::dvec3 emission = over_volume(radius_, radius_weight_, [&](double r) {
    glm::dvec3 sum(0.0);
    for (size_t j = 0; j < mu_s_.size(); ++j)
      sum += mu_s_weight_[j] * over_directions(a_, view_, view_weight_, r, mu_s_[j], [&](float mu, float nu) {
               return to_dvec3(physics::scattering_lookup(a_, density.sampler(), float(r), mu, float(mu_s_[j]), nu,
                                                          physics::ray_intersects_ground(a_, float(r), mu)));
             });
    return to_dvec3(physics::extinction_at(a_, float(r))) * sum;
  });
  for (int c = 0; c < 3; ++c) {
    const double s = emission[c] > 0.0 ? scattered_next_[c] / emission[c] : 1.0;
    if (!(s >= kMinScale && s <= kMaxScale)) {
      char factor[32];
      std::snprintf(factor, sizeof factor, "%.3g", s);
      throw Error("scattering order " + std::to_string(order_ + 1) + " would have to be scaled by " + factor +
                  " to conserve energy: the tables cannot represent an atmosphere this dense; use larger tables or "
                  "a lower --density-scale");
    }
    scale_[c] = float(s);
  }
  for (vec3& v : density.texels) v *= scale_;
  emitted_ = emission * to_dvec3(scale_);
  return scale_;
}

}  // namespace atmos::precompute
