// The brute-force Monte Carlo reference (see include/atmos/reference.hpp).
//
// Deliberately independent of the table code: it includes nothing but the
// public description of the atmosphere, glm and TBB.
//
// Estimator. The radiance looking along v from x is the volume rendering
// equation over the view segment [0, d] (d: ground or top of the atmosphere),
//
//   L(x, v) = ∫_0^d T(0,t) J(x + t v, v) dt + T(0,d) L_ground(x + d v)      (1)
//   J(y, v) = Σ_i σ_s,i(y) ∫_{4π} p_i(ω·v) L_in(y, ω) dω                  (2)
//   T(a,b)  = exp(-∫_a^b σ_ext(x + t v) dt),  σ_ext = Σ_i (β_s,i + β_a,i) ρ_i   (3)
//   L_ground(z) = a/π · ∫_{ω·n>0} L_in(z, ω) (ω·n) dω                       (4)
//
// with L_in(y, ω) the radiance arriving at y from direction ω (the sun disc
// seen through the atmosphere, or (1) again). The light scattered towards x
// by the segment up to a point P = x + t_P v alone (aerial perspective) is
// the first term of (1) cut at t_P, without any ground term:
//
//   L(x -> P) = ∫_0^{t_P} T(0,t) J(x + t v, v) dt                           (1')
//
// and is estimated by the same paths with the view segment ending at t_P.
// Each path:
//  - on the view segment, samples a first scattering distance t with density
//    ∝ σ_ext T, truncated to [0, d] ("forced" scattering, weight (1 - T(d))),
//    and adds the ground term T(0, d) L_ground deterministically;
//  - at every vertex does next-event estimation to a point sampled uniformly
//    in the solid angle of the sun disc (partial disc visibility near the
//    horizon, and behind moons, is then exact), weighted by the disc's
//    limb darkening (sun_weight) and, while fewer than K interactions were used,
//    continues in a direction sampled from the phase function mixture
//    (atmosphere) or the cosine-weighted hemisphere (ground);
//  - on later segments samples the distance with density σ_ext T: untruncated
//    (the path reaches the ground with probability T(d)) if the segment ends on
//    the ground, forced if it ends at the top (light escaping is worth nothing).
// Wavelengths share the geometry: a distance is drawn for one wavelength
// picked uniformly, and each wavelength is weighted by its own density over
// the mixture density (one-sample "balance heuristic"), which is unbiased for
// all of them. Forced samples are steered (without bias) by splitting a
// segment where it crosses the planet's shadow and drawing the piece first
// (shadow_plan): at twilight most optical depth is in the shadow and most
// single-scattered light comes from the small sunlit rest.
//
// Optical depth is Gauss–Legendre quadrature (4 nodes) on intervals of the ray
// delimited by its perigee and by a fixed altitude grid (steps of at most 1.5
// scale heights near the ground, growing with altitude, and every knot of the
// piecewise-linear profiles), so that each interval sees a smooth integrand.
// For speed the exponential constituents' extinction is read from a cached
// altitude table (steps of H_min/20, cubic interpolation, error < 3e-7
// relative); piecewise-linear constituents are evaluated exactly.
#include "reference/reference.hpp"
#include "reference/reference_detail.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

namespace atmos {
namespace {

using glm::dvec3;
constexpr double kPi = std::numbers::pi;
constexpr int kMaxWavelengths = 12;
using Spec = std::array<double, kMaxWavelengths>;

// Gauss–Legendre 4-point rule on [-1, 1]: ∫ f ≈ Σ w_k f(x_k), exact for
// polynomials of degree <= 7 (Abramowitz & Stegun 25.4.30).
constexpr std::array<double, 4> kGaussX = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                           0.8611363115940526};
constexpr std::array<double, 4> kGaussW = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                           0.3478548451374538};

// ---------------------------------------------------------------------------
// Phase functions, cos θ between incident and scattered propagation directions.

// Rayleigh: p(μ) = 3/(16π) (1 + μ²).
double rayleigh_phase(double mu) { return 3.0 / (16.0 * kPi) * (1.0 + mu * mu); }

// Henyey–Greenstein: p(μ) = (1 - g²) / (4π (1 + g² - 2gμ)^{3/2}).
double henyey_greenstein_phase(double g, double mu) {
  const double k = 1.0 + g * g - 2.0 * g * mu;
  return (1.0 - g * g) / (4.0 * kPi * k * std::sqrt(k));
}

// Cornette–Shanks: p(μ) = 3/(8π) (1 - g²)(1 + μ²) / ((2 + g²)(1 + g² - 2gμ)^{3/2}).
double cornette_shanks_phase(double g, double mu) {
  const double k = 1.0 + g * g - 2.0 * g * mu;
  return 3.0 / (8.0 * kPi) * (1.0 - g * g) * (1.0 + mu * mu) / ((2.0 + g * g) * k * std::sqrt(k));
}

// Henyey–Greenstein inverse CDF: with ξ uniform in [0,1),
//   μ = (1 + g² - ((1 - g²) / (1 - g + 2gξ))²) / (2g),   μ = 1 - 2ξ for g → 0
// (ξ = 0 gives μ = -1, ξ = 1 gives μ = 1).
double sample_henyey_greenstein(double g, double xi) {
  if (std::abs(g) < 1e-4) return 1.0 - 2.0 * xi;
  const double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
  return std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
}

// Rayleigh inverse CDF: F(μ) = (μ³ + 3μ + 4)/8 = ξ is the depressed cubic
// μ³ + 3μ - 2q = 0 with q = 4ξ - 2, whose real root is μ = u - 1/u with
// u = ∛(q + √(q² + 1)) (Cardano; u³ - u⁻³ = 2q).
double sample_rayleigh(double xi) {
  const double q = 4.0 * xi - 2.0;
  const double u = std::cbrt(q + std::sqrt(q * q + 1.0));
  return std::clamp(u - 1.0 / u, -1.0, 1.0);
}

// A phase function at one wavelength: its parameters sampled there.
struct PhaseAt {
  PhaseFunction::Kind kind = PhaseFunction::Kind::rayleigh;
  double g = 0.0, g_back = 0.0, forward_weight = 1.0;
};

PhaseAt phase_at(const PhaseFunction& phase, double wavelength_nm) {
  PhaseAt p;
  p.kind = phase.kind;
  if (phase.kind == PhaseFunction::Kind::rayleigh) return p;
  p.g = phase.g.at(wavelength_nm);
  if (phase.kind == PhaseFunction::Kind::double_henyey_greenstein) {
    p.g_back = phase.g_back.at(wavelength_nm);
    p.forward_weight = phase.forward_weight.at(wavelength_nm);
  }
  return p;
}

double evaluate_phase(const PhaseAt& p, double mu) {
  switch (p.kind) {
    case PhaseFunction::Kind::rayleigh: return rayleigh_phase(mu);
    case PhaseFunction::Kind::henyey_greenstein: return henyey_greenstein_phase(p.g, mu);
    case PhaseFunction::Kind::cornette_shanks: return cornette_shanks_phase(p.g, mu);
    case PhaseFunction::Kind::double_henyey_greenstein:
      return p.forward_weight * henyey_greenstein_phase(p.g, mu) +
             (1.0 - p.forward_weight) * henyey_greenstein_phase(p.g_back, mu);
  }
  return 0.0;
}

template <typename Random>
double sample_phase(const PhaseAt& p, Random& random) {
  switch (p.kind) {
    case PhaseFunction::Kind::rayleigh: return sample_rayleigh(random.uniform());
    case PhaseFunction::Kind::henyey_greenstein: return sample_henyey_greenstein(p.g, random.uniform());
    case PhaseFunction::Kind::cornette_shanks:
      // p_CS / p_HG = 3(1 + μ²) / (2(2 + g²)) <= 3/(2 + g²): accept an HG
      // sample with probability (1 + μ²)/2 (acceptance >= 1/2).
      for (;;) {
        const double mu = sample_henyey_greenstein(p.g, random.uniform());
        if (random.uniform() * 2.0 < 1.0 + mu * mu) return mu;
      }
    case PhaseFunction::Kind::double_henyey_greenstein:
      // A mixture: pick the lobe by its weight, then sample that HG exactly.
      return sample_henyey_greenstein(random.uniform() < p.forward_weight ? p.g : p.g_back, random.uniform());
  }
  return 1.0;
}

// ---------------------------------------------------------------------------
// Geometry.

// Orthonormal basis (b1, b2) completing the unit vector n (Duff et al. 2017,
// "Building an Orthonormal Basis, Revisited", JCGT 6(1)).
void basis(const dvec3& n, dvec3& b1, dvec3& b2) {
  const double sign = std::copysign(1.0, n.z);
  const double a = -1.0 / (sign + n.z);
  const double b = n.x * n.y * a;
  b1 = dvec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
  b2 = dvec3(b, sign + n.y * n.y * a, -n.y);
}

// The unit vector at angle acos(μ) from the unit axis w, azimuth φ:
//   ω = μ w + √(1 - μ²)(cos φ b1 + sin φ b2).
dvec3 direction_around(const dvec3& w, double mu, double phi) {
  dvec3 b1, b2;
  basis(w, b1, b2);
  const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  return glm::normalize(mu * w + s * (std::cos(phi) * b1 + std::sin(phi) * b2));
}

// Roots of t² + 2bt + c = 0 (ray o + t d against |x| = R with b = o·d,
// c = |o|² - R² = (|o| - R)(|o| + R)), t0 <= t1, computed without cancellation:
// t = -b ∓ √(b² - c), the smaller-magnitude root as c / (larger root).
bool sphere_roots(double b, double c, double& t0, double& t1) {
  const double disc = b * b - c;
  if (disc < 0.0) return false;
  const double s = std::sqrt(disc);
  const double q = b > 0.0 ? -(b + s) : -(b - s);  // the root of larger magnitude
  if (q == 0.0) {
    t0 = t1 = 0.0;
    return true;
  }
  t0 = std::min(q, c / q);
  t1 = std::max(q, c / q);
  return true;
}

// ---------------------------------------------------------------------------
// The atmosphere, evaluated at its working wavelengths.

struct Model {
  int n = 0;                       // number of working wavelengths
  double rb = 0.0, rt = 0.0;       // radii of ground and top, m
  std::vector<DensityProfile> density;
  // Per constituent, the phase function at each working wavelength, and
  // whether it is the same at all of them (then index 0 serves them all).
  std::vector<std::array<PhaseAt, kMaxWavelengths>> phase;
  std::vector<bool> phase_varies;
  std::vector<Spec> beta_s;        // per constituent, per wavelength, m^-1 at reference density
  std::vector<Spec> beta_ext;      // β_s + β_a
  Spec albedo{};                   // a(λ)
  Spec sun_nee{};                  // L_sun · Ω_sun = E_sun · 2/(1 + cos α)
  double one_minus_cos_alpha = 0.0;  // 1 - cos α = 2 sin²(α/2)
  double cos_alpha = 1.0;            // cos α
  std::vector<double> grid;        // altitudes (m) delimiting quadrature intervals, 0 .. Rt - Rb
  // Exponential constituents' σ_ext(h_j, λ) at h_j = j Δh, j < table_rows,
  // wavelength-minor; indices of the piecewise-linear constituents.
  double table_step = 0.0;
  size_t table_rows = 0;
  std::vector<double> table;
  std::vector<size_t> linear;
  // Radius of the "effective shadow" used to steer samples (shadow_plan).
  double shadow_radius = 0.0;
};

// Altitude grid: h_0 = 0, h_{k+1} = h_k + max(1.5 H_min, h_k / 2), capped at
// (Rt - Rb)/4, plus every piecewise-linear knot inside (0, Rt - Rb). H_min is
// the smallest exponential scale height. Gauss–Legendre with 4 nodes on a
// step of 1.5 H integrates exp(-h/H) to ~3e-8 relative; where steps exceed
// 1.5 H for a constituent (h > 3 H_min) it is below e^-3 of its ground value
// and its relative error stays below 1e-5 up to steps of 3 H. Checked against
// 2e6-step Simpson integration for Earth and Mars rays from 0 to 60 km at
// elevations -60°..90°: worst absolute error 2e-6, relative 2.4e-6 (that on
// optical depths < 1e-3).
std::vector<double> altitude_grid(const Atmosphere& a) {
  const double top = a.top_radius_m - a.bottom_radius_m;
  double h_min = top / 4.0;
  for (const auto& c : a.constituents)
    if (c.density.kind == DensityProfile::Kind::exponential)
      h_min = std::min(h_min, c.density.scale_height_m);
  std::vector<double> grid;
  for (double h = 0.0; h < top;) {
    grid.push_back(h);
    h += std::min(std::max(1.5 * h_min, h / 2.0), top / 4.0);
  }
  grid.push_back(top);
  for (const auto& c : a.constituents)
    if (c.density.kind == DensityProfile::Kind::piecewise_linear)
      for (const auto& [h, rho] : c.density.knots)
        if (h > 0.0 && h < top) grid.push_back(h);
  std::sort(grid.begin(), grid.end());
  // Drop (near-)duplicates, which would make empty intervals.
  std::vector<double> out;
  for (double h : grid)
    if (out.empty() || h - out.back() > 1e-6) out.push_back(h);
  if (out.back() != top) out.back() = top;
  return out;
}

// ρ_i(h), cut at the top of the atmosphere.
double density_at(const Model& m, size_t i, double h) {
  if (h > m.rt - m.rb) return 0.0;
  return m.density[i].at(std::max(h, 0.0));
}

// Fills the altitude table of the exponential constituents' extinction,
// Σ_{i exponential} β_ext,i(λ) exp(-h/H_i) at h_j = j Δh, j = 0..N-1
// (N - 1 steps cover [0, Rt - Rb]), with Δh = H_min / 20 (64 <= N <= 100001).
// Piecewise-linear constituents are not tabulated (evaluated exactly, so
// their kinks cost nothing in accuracy).
void build_table(Model& m) {
  const double top = m.rt - m.rb;
  double h_min = top;
  for (const auto& d : m.density)
    if (d.kind == DensityProfile::Kind::exponential) h_min = std::min(h_min, d.scale_height_m);
  const double steps = std::clamp(std::ceil(top / (h_min / 20.0)), 63.0, 100000.0);
  m.table_rows = size_t(steps) + 1;
  m.table_step = top / steps;
  m.table.assign(m.table_rows * size_t(m.n), 0.0);
  for (size_t i = 0; i < m.density.size(); ++i) {
    if (m.density[i].kind != DensityProfile::Kind::exponential) {
      m.linear.push_back(i);
      continue;
    }
    for (size_t j = 0; j < m.table_rows; ++j) {
      const double rho = m.density[i].at(j + 1 == m.table_rows ? top : double(j) * m.table_step);
      for (int l = 0; l < m.n; ++l) m.table[j * size_t(m.n) + size_t(l)] += m.beta_ext[i][size_t(l)] * rho;
    }
  }
}

// acc(λ) += w · σ_ext(h, λ), σ_ext = Σ_i β_ext,i(λ) ρ_i(h), h clamped to
// [0, Rt - Rb]:
//  - exponential constituents: 4-point Lagrange (cubic) interpolation in the
//    table, on nodes s..s+3 around h (u = h/Δh - s):
//      σ ≈ Σ_k σ_{s+k} Π_{q≠k} (u - q)/(k - q);
//    the error for exp(-h/H) is at most (Δh/H)⁴ max|Π_q (u - q)| / 4! <= 2.6e-7
//    relative with Δh = H/20 (9/16 instead of 1 for centred stencils: 1.5e-7);
//  - piecewise-linear constituents: exactly, β_ext,i(λ) ρ_i(h).
// This is where the reference spends its time.
inline void add_extinction(const Model& m, double h, double w, double* acc) {
  const size_t n = size_t(m.n);
  const double x = std::clamp(h / m.table_step, 0.0, double(m.table_rows - 1));
  size_t s = size_t(x);
  s = std::min(s > 0 ? s - 1 : 0, m.table_rows - 4);
  const double u = x - double(s);
  const double l0 = -(u - 1.0) * (u - 2.0) * (u - 3.0) / 6.0;
  const double l1 = u * (u - 2.0) * (u - 3.0) / 2.0;
  const double l2 = -u * (u - 1.0) * (u - 3.0) / 2.0;
  const double l3 = u * (u - 1.0) * (u - 2.0) / 6.0;
  const double* a = &m.table[s * n];
  for (size_t l = 0; l < n; ++l)
    acc[l] += w * (l0 * a[l] + l1 * a[l + n] + l2 * a[l + 2 * n] + l3 * a[l + 3 * n]);
  for (size_t i : m.linear) {
    const double rho = density_at(m, i, h);
    if (rho != 0.0)
      for (size_t l = 0; l < n; ++l) acc[l] += w * m.beta_ext[i][l] * rho;
  }
}

// σ_ext(h, λ) for all working wavelengths (see add_extinction).
Spec extinction(const Model& m, double h) {
  Spec out{};
  add_extinction(m, h, 1.0, out.data());
  return out;
}

Spec optical_depth_spec(const Model& m, const struct Ray& ray, double t0, double t1);

// Radius Rb + h_s of the cylinder behind the planet in which sunlight is
// strongly dimmed (used only to steer samples, see shadow_plan): h_s is the
// tangent altitude at which the half tangent ray (from its tangent point
// to the top) transmits, on average over the wavelengths, kShadowT = 0.6
// (the value that gave the lowest twilight variance for Earth among 0.25,
// 0.6, 0.8, 0.95). Found by bisection on h in [0, Rt - Rb]; Rb if even the
// ground-grazing ray transmits more.
double effective_shadow_radius(const Model& m);

// p_i(λ, μ) of constituent i at every working wavelength (evaluated once
// when it is the same at all of them).
void phase_values(const Model& m, size_t i, double mu, Spec& out) {
  if (!m.phase_varies[i]) {
    out.fill(evaluate_phase(m.phase[i][0], mu));
    return;
  }
  for (int l = 0; l < m.n; ++l) out[size_t(l)] = evaluate_phase(m.phase[i][size_t(l)], mu);
}

// `steering`: also compute the effective shadow radius (not needed for
// optical depths alone).
Model make_model(const Atmosphere& a, bool steering) {
  a.validate();
  Model m;
  if (a.wavelengths_nm.size() > size_t(kMaxWavelengths))
    throw Error(a.origin + ": the reference supports at most " + std::to_string(kMaxWavelengths) +
                " working wavelengths");
  m.n = int(a.wavelengths_nm.size());
  m.rb = a.bottom_radius_m;
  m.rt = a.top_radius_m;
  for (const auto& c : a.constituents) {
    Spec s{}, e{};
    for (int l = 0; l < m.n; ++l) {
      const double w = a.wavelengths_nm[size_t(l)];
      s[size_t(l)] = c.scattering.at(w);
      e[size_t(l)] = c.scattering.at(w) + c.absorption.at(w);
    }
    m.density.push_back(c.density);
    std::array<PhaseAt, kMaxWavelengths> phase{};
    bool varies = false;
    for (int l = 0; l < m.n; ++l) {
      phase[size_t(l)] = phase_at(c.phase, a.wavelengths_nm[size_t(l)]);
      const PhaseAt& p0 = phase[0];
      const PhaseAt& pl = phase[size_t(l)];
      varies = varies || pl.g != p0.g || pl.g_back != p0.g_back || pl.forward_weight != p0.forward_weight;
    }
    m.phase.push_back(phase);
    m.phase_varies.push_back(varies);
    m.beta_s.push_back(s);
    m.beta_ext.push_back(e);
  }
  const double alpha = a.sun_angular_radius_rad;
  m.one_minus_cos_alpha = 2.0 * std::sin(0.5 * alpha) * std::sin(0.5 * alpha);
  m.cos_alpha = std::cos(alpha);
  for (int l = 0; l < m.n; ++l) {
    const double w = a.wavelengths_nm[size_t(l)];
    m.albedo[size_t(l)] = a.ground_albedo.at(w);
    // Disc radiance L = E / (π sin²α) (so that ∫_disc L cos = E at normal
    // incidence) times the disc solid angle Ω = 2π(1 - cos α).
    m.sun_nee[size_t(l)] = a.solar_irradiance.at(w) * 2.0 / (1.0 + std::cos(alpha));
  }
  m.grid = altitude_grid(a);
  build_table(m);
  m.shadow_radius = steering ? effective_shadow_radius(m) : m.rb;
  return m;
}

// A ray o + t d (|d| = 1) with its perigee: b = o·d, the closest approach to
// the planet centre at t_p = -b, at radius² p² = |o|² - b².
struct Ray {
  dvec3 o, d;
  double b = 0.0, p2 = 0.0;
  Ray(const dvec3& origin, const dvec3& dir) : o(origin), d(dir) {
    b = glm::dot(o, d);
    p2 = std::max(0.0, glm::dot(o, o) - b * b);
  }
  // Altitude at distance t: h = √(p² + (t + b)²) - Rb.
  double altitude(double t, double rb) const { return std::sqrt(p2 + (t + b) * (t + b)) - rb; }
};

// ∫_ta^tb σ_ext(h(t)) dt by 4-node Gauss–Legendre:
//   (tb - ta)/2 · Σ_k w_k σ_ext(h((ta + tb)/2 + x_k (tb - ta)/2)).
// Adds the integral to `acc` (all wavelengths).
void integrate_interval(const Model& m, const Ray& ray, double ta, double tb, Spec& acc) {
  const double half = 0.5 * (tb - ta), mid = 0.5 * (ta + tb);
  if (half == 0.0) return;
  for (size_t k = 0; k < 4; ++k)
    add_extinction(m, ray.altitude(mid + kGaussX[k] * half, m.rb), kGaussW[k] * half, acc.data());
}

// Calls f(ta, tb) for consecutive intervals covering [t0, t1] of the ray,
// cut at the perigee t_p = -b and where the ray crosses a grid altitude h_k:
// r(t)² = p² + (t - t_p)² = (Rb + h_k)²  ⇒  t = t_p ∓ √((Rb + h_k)² - p²)
// (minus while descending, plus while ascending).
template <class F>
void for_each_interval(const Model& m, const Ray& ray, double t0, double t1, F&& f) {
  if (!(t1 > t0)) return;
  const double tp = -ray.b;
  const auto crossing = [&](double h) {
    const double r = m.rb + h;
    return std::sqrt(std::max(0.0, (r - std::sqrt(ray.p2)) * (r + std::sqrt(ray.p2))));
  };
  // Descending part [t0, min(t1, tp)]: grid altitudes strictly between the
  // end altitudes, from high to low.
  if (t0 < tp) {
    const double a = t0, c = std::min(t1, tp);
    const double ha = ray.altitude(a, m.rb), hc = ray.altitude(c, m.rb);
    double prev = a;
    auto hi = std::lower_bound(m.grid.begin(), m.grid.end(), ha);  // first grid >= ha
    auto lo = std::upper_bound(m.grid.begin(), m.grid.end(), hc);  // first grid > hc
    for (auto it = hi; it != lo;) {
      --it;
      if (*it >= ha || *it <= hc) continue;
      const double t = std::clamp(tp - crossing(*it), prev, c);
      f(prev, t);
      prev = t;
    }
    f(prev, c);
  }
  // Ascending part [max(t0, tp), t1]: from low to high.
  if (t1 > tp) {
    const double a = std::max(t0, tp), c = t1;
    const double ha = ray.altitude(a, m.rb), hc = ray.altitude(c, m.rb);
    double prev = a;
    for (auto it = std::upper_bound(m.grid.begin(), m.grid.end(), ha); it != m.grid.end() && *it < hc; ++it) {
      const double t = std::clamp(tp + crossing(*it), prev, c);
      f(prev, t);
      prev = t;
    }
    f(prev, c);
  }
}

// τ(λ) = ∫_t0^t1 σ_ext dt along the ray, for all wavelengths.
Spec optical_depth_spec(const Model& m, const Ray& ray, double t0, double t1) {
  Spec tau{};
  for_each_interval(m, ray, t0, t1, [&](double ta, double tb) { integrate_interval(m, ray, ta, tb, tau); });
  return tau;
}

double effective_shadow_radius(const Model& m) {
  const auto mean_transmittance = [&](double h) {
    const double r = m.rb + h;
    const Ray ray(dvec3(r, 0.0, 0.0), dvec3(0.0, 1.0, 0.0));
    const Spec tau = optical_depth_spec(m, ray, 0.0, std::sqrt((m.rt - r) * (m.rt + r)));
    double t = 0.0;
    for (int l = 0; l < m.n; ++l) t += std::exp(-tau[size_t(l)]) / m.n;
    return t;
  };
  constexpr double kShadowT = 0.6;
  if (mean_transmittance(0.0) >= kShadowT) return m.rb;
  double lo = 0.0, hi = m.rt - m.rb;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    (mean_transmittance(mid) < kShadowT ? lo : hi) = mid;
  }
  return m.rb + 0.5 * (lo + hi);
}

// Where a ray from o along d is inside the atmosphere: t in [t_begin, t_end]
// with t >= 0, ending on the ground if it hits the planet (then
// hits_ground). `inside` is false if the ray misses the atmosphere.
struct Extent {
  bool inside = false;
  bool hits_ground = false;
  double t_begin = 0.0, t_end = 0.0;
};

Extent extent(const Model& m, const dvec3& o, const dvec3& d) {
  Extent e;
  const double r = glm::length(o);
  const double b = glm::dot(o, d);
  double t0, t1;
  if (!sphere_roots(b, (r - m.rt) * (r + m.rt), t0, t1) || t1 <= 0.0) return e;  // misses or leaves
  e.inside = true;
  e.t_begin = std::max(0.0, t0);
  e.t_end = t1;
  // The ground is hit iff the ray goes down (b < 0) and comes within Rb of
  // the centre; the first root, from a point at or above the ground, is >= 0.
  double g0, g1;
  if (b < 0.0 && sphere_roots(b, (r - m.rb) * (r + m.rb), g0, g1)) {
    e.hits_ground = true;
    e.t_end = std::max(g0, e.t_begin);
  }
  return e;
}

// True iff the planet blocks the ray from o (|o| >= Rb) along d: it goes
// down and its perigee radius² p² = |o|² - (o·d)² is below Rb².
bool blocked_by_planet(const Model& m, const dvec3& o, const dvec3& d) {
  const double b = glm::dot(o, d);
  if (b >= 0.0) return false;
  const double r = glm::length(o);
  return b * b - (r - m.rb) * (r + m.rb) >= 0.0;
}

// Uniform direction in the solid angle of the sun disc around s:
// cos θ = 1 - ξ1 (1 - cos α), φ = 2π ξ2 (density 1/Ω). Also returns, for the
// limb darkening, μ² = 1 - sin²θ/sin²α of the sample, computed without
// cancellation from c = cos θ, C = cos α, c - C = (1 - ξ1)(1 - C):
//   μ² = (c² - C²)/sin²α = (c - C)(c + C)/((1 - C)(1 + C)) = (1 - ξ1)(c + C)/(1 + C).
dvec3 sample_sun(const Model& m, const dvec3& s, reference_detail::Random& rnd, double& mu2) {
  const double xi1 = rnd.uniform();
  const double x = xi1 * m.one_minus_cos_alpha;  // 1 - cos θ, without cancellation
  const double phi = 2.0 * kPi * rnd.uniform();
  dvec3 b1, b2;
  basis(s, b1, b2);
  const double sin_theta = std::sqrt(std::max(0.0, x * (2.0 - x)));
  mu2 = (1.0 - xi1) * ((1.0 - x) + m.cos_alpha) / (1.0 + m.cos_alpha);
  return glm::normalize((1.0 - x) * s + sin_theta * (std::cos(phi) * b1 + std::sin(phi) * b2));
}

// True iff the ray o + t ω (|ω| = 1), t > 0, meets the moon's sphere
// |y - c| <= R. With q = c - o the closest approach to c is at t* = q·ω, at
// distance² |q - t* ω|² (computed from the vector, not as |q|² - t*², which
// would cancel for a moon far away): blocked iff o is inside the sphere
// (|q| <= R) or t* > 0 and |q - t* ω|² <= R² (from outside, an intersection
// in front exists iff the closest approach is in front and within R).
bool blocked_by_moon(const ReferenceMoon& moon, const dvec3& o, const dvec3& w) {
  const dvec3 q = moon.centre - o;
  const double r2 = moon.radius * moon.radius;
  if (glm::dot(q, q) <= r2) return true;
  const double t = glm::dot(q, w);
  if (!(t > 0.0)) return false;
  const dvec3 miss = q - t * w;
  return glm::dot(miss, miss) <= r2;
}

// Sun transmittance from o towards ω: exp(-τ(o → top along ω)), zero if the
// planet is in the way.
Spec sun_transmittance(const Model& m, const dvec3& o, const dvec3& w) {
  Spec t{};
  if (blocked_by_planet(m, o, w)) return t;
  const Extent e = extent(m, o, w);
  Spec tau{};
  if (e.inside) tau = optical_depth_spec(m, Ray(o, w), e.t_begin, e.t_end);
  for (int l = 0; l < m.n; ++l) t[size_t(l)] = std::exp(-tau[size_t(l)]);
  return t;
}

// A ray segment inside the atmosphere prepared for distance sampling: the
// interval boundaries t_0 = t_begin < … < t_m = t_end and the cumulative
// optical depths τ(t_k) from t_begin, for all wavelengths.
struct Segment {
  Ray ray{dvec3(0.0), dvec3(0.0, 0.0, 1.0)};
  bool inside = false, hits_ground = false;
  double t_begin = 0.0, t_end = 0.0;
  std::vector<double> t;
  std::vector<Spec> tau;
  const Spec& total() const { return tau.back(); }
};

// The cumulative optical depths of a segment whose ray, t_begin, t_end and
// `inside` are set.
void fill_segment(const Model& m, Segment& s) {
  s.t.assign(1, s.t_begin);
  s.tau.assign(1, Spec{});
  if (!s.inside) return;
  for_each_interval(m, s.ray, s.t_begin, s.t_end, [&](double ta, double tb) {
    Spec acc = s.tau.back();
    integrate_interval(m, s.ray, ta, tb, acc);
    s.t.push_back(tb);
    s.tau.push_back(acc);
  });
}

void build_segment(const Model& m, const dvec3& o, const dvec3& d, Segment& s) {
  s.ray = Ray(o, d);
  const Extent e = extent(m, o, d);
  s.inside = e.inside;
  s.hits_ground = e.hits_ground;
  s.t_begin = e.t_begin;
  s.t_end = e.inside ? e.t_end : e.t_begin;
  fill_segment(m, s);
}

// The view segment of (1'): the ray from o along d cut at t_P = `length`,
// i.e. [t_begin, min(t_end, t_P)], never ending on the ground (the caller
// has checked that the segment stays above it, so a ground hit before t_P
// can only be rounding). Empty (not inside) if the ray misses the
// atmosphere or enters it only at or beyond t_P.
void build_segment_to(const Model& m, const dvec3& o, const dvec3& d, double length, Segment& s) {
  s.ray = Ray(o, d);
  const Extent e = extent(m, o, d);
  s.inside = e.inside && e.t_begin < length;
  s.hits_ground = false;
  s.t_begin = e.t_begin;
  s.t_end = s.inside ? std::min(e.t_end, length) : e.t_begin;
  fill_segment(m, s);
}

// The point where the optical depth (for wavelength l) from t_begin reaches
// tau_target < τ(t_end): finds the interval k with τ(t_k) <= target < τ(t_k+1)
// and solves τ(t_k) + ∫_{t_k}^t σ_ext = target by safeguarded Newton
// iterations (derivative σ_ext(t), bisection when a step leaves the bracket).
// Returns t, and τ(t), σ_ext(t) for all wavelengths.
double invert_optical_depth(const Model& m, const Segment& s, int l, double target, Spec& tau_t, Spec& sigma_t) {
  const size_t li = size_t(l);
  size_t k = 0;
  {
    size_t lo = 0, hi = s.t.size() - 1;  // invariant: tau[lo] <= target < tau[hi]
    while (hi - lo > 1) {
      const size_t mid = (lo + hi) / 2;
      if (s.tau[mid][li] <= target) lo = mid;
      else hi = mid;
    }
    k = lo;
  }
  const double ta = s.t[k], tb = s.t[k + 1];
  double lo = ta, hi = tb;
  const double span = s.tau[k + 1][li] - s.tau[k][li];
  double t = span > 0.0 ? ta + (tb - ta) * (target - s.tau[k][li]) / span : 0.5 * (ta + tb);
  for (int it = 0; it < 60; ++it) {
    Spec acc = s.tau[k];
    integrate_interval(m, s.ray, ta, t, acc);
    sigma_t = extinction(m, s.ray.altitude(t, m.rb));
    tau_t = acc;
    const double f = acc[li] - target;
    if (std::abs(f) <= 1e-11 * std::max(target, 1e-300) || hi - lo <= 1e-9 * std::max(1.0, tb - ta)) break;
    if (f > 0.0) hi = t;
    else lo = t;
    double next = sigma_t[li] > 0.0 ? t - f / sigma_t[li] : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    t = next;
  }
  return t;
}

// A path vertex: position, tracing direction of the segment that reached it
// (the light leaves the vertex along -d_in towards the eye), and whether it
// is on the ground.
struct Vertex {
  dvec3 p;
  dvec3 d_in;
  bool ground = false;
};

struct Context {
  const Model& m;
  dvec3 sun;
  int max_order;
  const std::vector<ReferenceMoon>& moons;  // checked by check_options and check_moons
  double limb_u;                            // u of the limb-darkening law, in [0, 1]
};

// Weight of a sun sample ω (drawn by sample_sun, with its μ²) seen from o,
// relative to the uniform disc whose next-event estimate is L_sunΩ · (...):
//   w_sun = V_moons(o, ω) · I(μ) / ⟨I⟩,   I(μ) = 1 - u (1 - μ),   ⟨I⟩ = 1 - u/3,
// V_moons = 0 if any moon blocks the ray (blocked_by_moon), else 1.
// ⟨I⟩ is the mean of I over the sampled spherical cap weighted by cos θ,
// exactly: with c = cos θ, C = cos α, μ = √(c² - C²)/sin α,
//   ∫_C^1 μ c dc = (c² - C²)^{3/2}/(3 sin α) |_C^1 = sin²α/3,
//   ∫_C^1 c dc = sin²α/2,  so ⟨μ⟩_cos = 2/3 for every α,
// which keeps the disc's irradiance at normal incidence, E[L_sunΩ w_sun cos θ],
// exactly E_sun (L_sunΩ = E_sun / ⟨cos θ⟩). (The plain solid-angle mean,
// ⟨μ⟩_Ω = 2/3 - sin²α/30 + O(sin⁴α), would instead leave it off by
// u sin²α / (30 (1 - u/3)) relative: <= 1.1e-6 for the Sun, α = 4.65 mrad.)
// u = 0 and no moons give exactly 1 (multiplying by it changes no bit).
double sun_weight(const Context& ctx, const dvec3& o, const dvec3& w, double mu2) {
  for (const ReferenceMoon& moon : ctx.moons)
    if (blocked_by_moon(moon, o, w)) return 0.0;
  if (ctx.limb_u == 0.0) return 1.0;
  return (1.0 - ctx.limb_u * (1.0 - std::sqrt(std::max(0.0, mu2)))) / (1.0 - ctx.limb_u / 3.0);
}

bool any_positive(const Model& m, const Spec& s) {
  for (int l = 0; l < m.n; ++l)
    if (s[size_t(l)] > 0.0) return true;
  return false;
}

// τ(t) from the start of the segment, for all wavelengths: τ(t_k) of the
// interval containing t plus ∫_{t_k}^t σ_ext (Gauss–Legendre).
Spec tau_at(const Model& m, const Segment& s, double t) {
  if (s.t.size() < 2) return s.tau[0];
  // The interval [t_k, t_k+1] holding t.
  const size_t first_after = size_t(std::upper_bound(s.t.begin(), s.t.end(), t) - s.t.begin());
  const size_t k = std::clamp(first_after, size_t(1), s.t.size() - 1) - 1;
  Spec acc = s.tau[k];
  integrate_interval(m, s.ray, s.t[k], std::clamp(t, s.t[k], s.t[k + 1]), acc);
  return acc;
}

// A partition of a segment into at most 5 consecutive pieces [a, b], with
// the optical depths at their ends and the probability of drawing the first
// interaction in each. Any partition and any probabilities > 0 (where the
// integrand can be non-zero) give an unbiased estimate; they only steer the
// samples.
struct Piece {
  double a = 0.0, b = 0.0;
  Spec tau_a{}, tau_b{};
  double probability = 0.0;
};
struct Plan {
  int count = 0;
  std::array<Piece, 5> piece;
};

// The whole segment as one piece (used for all segments after the first).
Plan whole_plan(const Segment& s) {
  Plan p;
  p.count = 1;
  p.piece[0].a = s.t_begin;
  p.piece[0].b = s.t_end;
  p.piece[0].tau_b = s.total();
  p.piece[0].probability = 1.0;
  return p;
}

// The interval of t where the ray o + t d is inside the half cylinder behind
// the planet {y : y·s < 0, |y - (y·s)s| < R} (s: sun direction): the
// cylinder is |o⊥ + t d⊥|² < R² (⊥: component normal to s), a quadratic
// inequality in t, the half space (o·s) + t (d·s) < 0. False if empty.
bool cylinder_interval(const dvec3& o, const dvec3& d, const dvec3& sun, double radius, double& lo, double& hi) {
  const dvec3 o_perp = o - glm::dot(o, sun) * sun, d_perp = d - glm::dot(d, sun) * sun;
  lo = -INFINITY;
  hi = INFINITY;
  const double qa = glm::dot(d_perp, d_perp), qb = glm::dot(o_perp, d_perp);
  const double qc = (glm::length(o_perp) - radius) * (glm::length(o_perp) + radius);
  if (qa > 1e-15) {
    const double disc = qb * qb - qa * qc;
    if (disc <= 0.0) return false;
    lo = (-qb - std::sqrt(disc)) / qa;
    hi = (-qb + std::sqrt(disc)) / qa;
  } else if (qc >= 0.0) {
    return false;
  }
  const double os = glm::dot(o, sun), ds = glm::dot(d, sun);
  if (ds > 0.0) hi = std::min(hi, -os / ds);
  else if (ds < 0.0) lo = std::max(lo, -os / ds);
  else if (os >= 0.0) return false;
  return hi > lo;
}

// A segment split where it enters or leaves the planet's shadow: the half
// cylinders of radius Rb (geometric shadow of a point sun) and of the
// effective shadow radius (sunlight mostly extinct), giving up to 5 pieces.
// With the sun low, most of a ray's optical depth may be in the shadow,
// where only multiple scattering contributes, and a small part in the light:
// a defensive mixture P_j = ½ w_j/Σw + ½ [w_j > 0]/(number of such pieces),
// w_j = mean_λ T_λ(0, a_j)(1 - T_λ(a_j, b_j)) (the natural probability of an
// interaction in piece j), keeps at least half the natural share of every
// piece and lifts rare ones. Without shadow: one piece, plain forced sampling.
Plan shadow_plan(const Model& m, const Segment& s, const dvec3& sun) {
  if (!s.inside || !(s.t_end > s.t_begin)) return whole_plan(s);
  std::array<double, 6> cut{};
  int cuts = 0;
  cut[size_t(cuts++)] = s.t_begin;
  const int radii = m.shadow_radius > m.rb ? 2 : 1;
  for (int k = 0; k < radii; ++k) {
    double lo, hi;
    if (!cylinder_interval(s.ray.o, s.ray.d, sun, k == 0 ? m.rb : m.shadow_radius, lo, hi)) continue;
    for (double t : {lo, hi})
      if (t > s.t_begin && t < s.t_end) cut[size_t(cuts++)] = t;
  }
  if (cuts == 1) return whole_plan(s);
  cut[size_t(cuts++)] = s.t_end;
  for (int a = 1; a < cuts; ++a)  // insertion sort of the few cut points
    for (int b = a; b > 0 && cut[size_t(b - 1)] > cut[size_t(b)]; --b) std::swap(cut[size_t(b - 1)], cut[size_t(b)]);
  Plan p;
  double w[5] = {0.0, 0.0, 0.0, 0.0, 0.0}, w_all = 0.0;
  int nonzero = 0;
  for (int q = 0; q + 1 < cuts && p.count < 5; ++q) {
    if (!(cut[size_t(q + 1)] > cut[size_t(q)])) continue;
    Piece& piece = p.piece[size_t(p.count)];
    piece.a = cut[size_t(q)];
    piece.b = cut[size_t(q + 1)];
    piece.tau_a = q == 0 ? Spec{} : tau_at(m, s, piece.a);
    piece.tau_b = q + 2 == cuts ? s.total() : tau_at(m, s, piece.b);
    for (int l = 0; l < m.n; ++l)
      w[p.count] += std::exp(-piece.tau_a[size_t(l)]) * -std::expm1(-(piece.tau_b[size_t(l)] - piece.tau_a[size_t(l)]));
    w_all += w[p.count];
    if (w[p.count] > 0.0) ++nonzero;
    ++p.count;
  }
  if (!(w_all > 0.0)) return whole_plan(s);
  for (int j = 0; j < p.count; ++j)
    p.piece[size_t(j)].probability = w[j] > 0.0 ? 0.5 * w[j] / w_all + 0.5 / nonzero : 0.0;
  return p;
}

// Forced distance sampling on a segment: picks piece j of the plan with
// probability P_j, then a wavelength l uniformly among those with
// τ_l(a_j, b_j) > 0 (set A_j), then t in [a_j, b_j] with density
//   p_l(t) = σ_l(t) T_l(a_j, t) / (1 - T_l(a_j, b_j)),
// via τ_l(a_j, t) = -ln(1 - ξ (1 - T_l(a_j, b_j))), and multiplies β_λ by
// T_λ(0, t) / p(t), p(t) = P_j (1/|A_j|) Σ_{l∈A_j} p_l(t), so that
// β_λ J_λ(t) estimates ∫_0^d T_λ(0, t) J_λ(t) dt without bias (wavelengths
// outside A_j have σ_ext = 0, hence J = 0, on the piece). u is the
// (stratified) uniform variable that picks j, l and ξ.
// Returns false if nothing can scatter on the segment.
bool sample_forced(const Model& m, const Segment& s, const Plan& plan, double u, Spec& beta, Vertex& v) {
  int j = 0;
  double below = 0.0;
  while (j + 1 < plan.count && (plan.piece[size_t(j)].probability <= 0.0 ||
                                u >= below + plan.piece[size_t(j)].probability)) {
    below += plan.piece[size_t(j)].probability;
    ++j;
  }
  const Piece& piece = plan.piece[size_t(j)];
  if (!(piece.probability > 0.0)) return false;
  const double uj = std::clamp((u - below) / piece.probability, 0.0, 1.0);
  int active[kMaxWavelengths];
  int count = 0;
  for (int l = 0; l < m.n; ++l)
    if (piece.tau_b[size_t(l)] > piece.tau_a[size_t(l)]) active[count++] = l;
  if (count == 0) return false;
  const double scaled = uj * count;
  const int pick = std::min(int(scaled), count - 1);
  const double xi = std::clamp(scaled - pick, 0.0, 1.0 - 0x1.0p-53);
  const int l = active[pick];
  const size_t li = size_t(l);
  const double target =
      piece.tau_a[li] - std::log1p(-xi * -std::expm1(-(piece.tau_b[li] - piece.tau_a[li])));
  Spec tau_t{}, sigma_t{};
  const double t = invert_optical_depth(m, s, l, target, tau_t, sigma_t);
  double pdf = 0.0;
  for (int a = 0; a < count; ++a) {
    const size_t la = size_t(active[a]);
    pdf += sigma_t[la] * std::exp(-(tau_t[la] - piece.tau_a[la])) / -std::expm1(-(piece.tau_b[la] - piece.tau_a[la]));
  }
  pdf *= piece.probability / count;
  if (!(pdf > 0.0)) return false;
  for (int x = 0; x < m.n; ++x) beta[size_t(x)] *= std::exp(-tau_t[size_t(x)]) / pdf;
  v.p = s.ray.o + t * s.ray.d;
  v.d_in = s.ray.d;
  v.ground = false;
  return true;
}

// Analog distance sampling on a segment ending on the ground: wavelength l
// uniform among all n, τ* = -ln(1 - ξ); the ground is reached if
// τ* >= τ_l(d), with mixture probability P = (1/n) Σ_λ T_λ(d), and then
// β_λ *= T_λ(d) / P; otherwise the interaction is where τ_l(t) = τ*, with
// mixture density p(t) = (1/n) Σ_λ σ_λ(t) T_λ(t), and β_λ *= T_λ(t) / p(t).
// Estimates ∫_0^d T J dt + T(d) L_ground with one of the two terms.
bool sample_analog(const Model& m, const Segment& s, reference_detail::Random& rnd, Spec& beta, Vertex& v) {
  const int l = std::min(int(rnd.uniform() * m.n), m.n - 1);
  const double target = -std::log1p(-rnd.uniform());
  if (target >= s.total()[size_t(l)]) {
    double p = 0.0;
    for (int x = 0; x < m.n; ++x) p += std::exp(-s.total()[size_t(x)]);
    p /= m.n;
    for (int x = 0; x < m.n; ++x) beta[size_t(x)] *= std::exp(-s.total()[size_t(x)]) / p;
    // Snap onto the sphere |z| = Rb, the ground point of the ray.
    v.p = glm::normalize(s.ray.o + s.t_end * s.ray.d) * m.rb;
    v.d_in = s.ray.d;
    v.ground = true;
    return true;
  }
  Spec tau_t{}, sigma_t{};
  const double t = invert_optical_depth(m, s, l, target, tau_t, sigma_t);
  double pdf = 0.0;
  for (int x = 0; x < m.n; ++x) pdf += sigma_t[size_t(x)] * std::exp(-tau_t[size_t(x)]);
  pdf /= m.n;
  if (!(pdf > 0.0)) return false;
  for (int x = 0; x < m.n; ++x) beta[size_t(x)] *= std::exp(-tau_t[size_t(x)]) / pdf;
  v.p = s.ray.o + t * s.ray.d;
  v.d_in = s.ray.d;
  v.ground = false;
  return true;
}

// Follows a path from vertex v (interaction number `order`, throughput β)
// and adds its contributions to `out`:
//  atmosphere (2):  NEE  β · L_sunΩ · w_sun(ω) · T_sun(ω) · Σ_i σ_s,i p_i(ω·d_in), ω on the disc;
//                   then ω' ~ q(ω') = Σ_i c_i p_i(ω'·d_in), c_i ∝ Σ_λ σ_s,i(λ),
//                   β *= Σ_i σ_s,i p_i(ω'·d_in) / q(ω');
//  ground (4):      NEE  β · a/π · L_sunΩ · w_sun(ω) · (n·ω) · T_sun(ω);
//                   then ω' cosine-weighted about n (density (n·ω')/π), β *= a;
// and then samples the next vertex on the segment along ω' (analog if it
// ends on the ground, forced if it leaves through the top), until the path
// has used max_order interactions. w_sun: sun_weight (moons, limb darkening).
void follow_path(const Context& ctx, Vertex v, Spec beta, int order, reference_detail::Random& rnd, Segment& seg,
                 Spec& out) {
  const Model& m = ctx.m;
  const size_t nc = m.density.size();
  for (;;) {
    dvec3 next_dir;
    if (v.ground) {
      if (!any_positive(m, m.albedo)) return;  // a black ground reflects nothing
      const dvec3 normal = glm::normalize(v.p);
      double mu2 = 0.0;
      const dvec3 w = sample_sun(m, ctx.sun, rnd, mu2);
      const double cos_n = glm::dot(normal, w);
      const double sw = cos_n > 0.0 ? sun_weight(ctx, v.p, w, mu2) : 0.0;
      if (sw > 0.0) {
        const Spec t = sun_transmittance(m, v.p, w);
        for (int l = 0; l < m.n; ++l)
          out[size_t(l)] +=
              beta[size_t(l)] * m.albedo[size_t(l)] / kPi * m.sun_nee[size_t(l)] * sw * cos_n * t[size_t(l)];
      }
      if (order >= ctx.max_order) return;
      // Cosine-weighted hemisphere: cos θ = √ξ1, φ = 2π ξ2.
      const double mu = std::sqrt(rnd.uniform());
      next_dir = direction_around(normal, mu, 2.0 * kPi * rnd.uniform());
      if (glm::dot(next_dir, normal) <= 0.0) return;  // rounding at grazing angles
      for (int l = 0; l < m.n; ++l) beta[size_t(l)] *= m.albedo[size_t(l)];
    } else {
      const double h = glm::length(v.p) - m.rb;
      std::array<Spec, 4> sigma_s{};  // validate() allows at most 4 constituents
      std::array<double, 4> c{};
      double c_total = 0.0;
      for (size_t i = 0; i < nc; ++i) {
        const double rho = density_at(m, i, h);
        for (int l = 0; l < m.n; ++l) {
          sigma_s[i][size_t(l)] = m.beta_s[i][size_t(l)] * rho;
          c[i] += sigma_s[i][size_t(l)];
        }
        c_total += c[i];
      }
      if (!(c_total > 0.0)) return;
      // Next-event estimation to the sun disc.
      double mu2 = 0.0;
      const dvec3 w = sample_sun(m, ctx.sun, rnd, mu2);
      const double sw = blocked_by_planet(m, v.p, w) ? 0.0 : sun_weight(ctx, v.p, w, mu2);
      if (sw > 0.0) {
        const Spec t = sun_transmittance(m, v.p, w);
        const double mu = glm::dot(w, v.d_in);
        // Each wavelength with its own phase function (dust's forward lobe
        // narrows towards the blue).
        std::array<Spec, 4> p{};
        for (size_t i = 0; i < nc; ++i) phase_values(m, i, mu, p[i]);
        for (int l = 0; l < m.n; ++l) {
          double j = 0.0;
          for (size_t i = 0; i < nc; ++i) j += sigma_s[i][size_t(l)] * p[i][size_t(l)];
          out[size_t(l)] += beta[size_t(l)] * m.sun_nee[size_t(l)] * sw * t[size_t(l)] * j;
        }
      }
      if (order >= ctx.max_order) return;
      // Continue: pick constituent i with probability c_i / Σc, then cos θ from p_i.
      // A phase function that changes with wavelength: pick (i, λ) with
      // probability σ_s,i(λ) / Σc (the rest of the same uniform number),
      // then cos θ from p_i,λ. The density of the direction is the mixture
      // q = Σ_i,λ σ_s,i(λ) p_i,λ / Σc (one-sample balance heuristic over the
      // wavelengths the path carries), the same for every wavelength.
      double pick = rnd.uniform() * c_total;
      size_t chosen = 0;
      for (size_t i = 0; i < nc; ++i) {
        if (c[i] <= 0.0) continue;
        chosen = i;
        if (pick < c[i]) break;
        pick -= c[i];
      }
      size_t chosen_l = 0;
      if (m.phase_varies[chosen]) {
        for (int l = 0; l < m.n; ++l) {
          if (sigma_s[chosen][size_t(l)] <= 0.0) continue;
          chosen_l = size_t(l);
          if (pick < sigma_s[chosen][size_t(l)]) break;
          pick -= sigma_s[chosen][size_t(l)];
        }
      }
      const double mu_s = sample_phase(m.phase[chosen][chosen_l], rnd);
      next_dir = direction_around(v.d_in, mu_s, 2.0 * kPi * rnd.uniform());
      const double mu = glm::dot(next_dir, v.d_in);
      std::array<Spec, 4> p{};
      double q = 0.0;
      for (size_t i = 0; i < nc; ++i) {
        phase_values(m, i, mu, p[i]);
        if (!m.phase_varies[i]) {
          q += c[i] / c_total * p[i][0];
        } else {
          for (int l = 0; l < m.n; ++l) q += sigma_s[i][size_t(l)] / c_total * p[i][size_t(l)];
        }
      }
      if (!(q > 0.0)) return;
      for (int l = 0; l < m.n; ++l) {
        double f = 0.0;
        for (size_t i = 0; i < nc; ++i) f += sigma_s[i][size_t(l)] * p[i][size_t(l)];
        beta[size_t(l)] *= f / q;
      }
    }
    build_segment(m, v.p, next_dir, seg);
    if (!seg.inside) return;
    Vertex next;
    const bool ok = seg.hits_ground ? sample_analog(m, seg, rnd, beta, next)
                                    : sample_forced(m, seg, shadow_plan(m, seg, ctx.sun), rnd.uniform(), beta, next);
    if (!ok) return;
    v = next;
    ++order;
  }
}

// One sample of the radiance (1) along a prepared view segment with at most
// max_order interactions: a forced first interaction (stratified variable u,
// pieces of `plan`) plus, if the segment ends on the ground, the ground term
// T(0,d) L_ground.
Spec radiance_sample(const Context& ctx, const Segment& view, const Plan& plan, double u,
                     reference_detail::Random& rnd, Segment& scratch) {
  Spec out{};
  if (!view.inside || ctx.max_order < 1) return out;
  Spec beta;
  beta.fill(1.0);
  Vertex v;
  if (sample_forced(ctx.m, view, plan, u, beta, v)) follow_path(ctx, v, beta, 1, rnd, scratch, out);
  if (view.hits_ground) {
    beta.fill(0.0);
    for (int l = 0; l < ctx.m.n; ++l) beta[size_t(l)] = std::exp(-view.total()[size_t(l)]);
    Vertex g;
    g.p = glm::normalize(view.ray.o + view.t_end * view.ray.d) * ctx.m.rb;
    g.d_in = view.ray.d;
    g.ground = true;
    follow_path(ctx, g, beta, 1, rnd, scratch, out);
  }
  return out;
}

// Seed of path i: two rounds of the SplitMix64 mixer over (seed, i), so that
// the streams of different paths start at unrelated points.
std::uint64_t path_seed(std::uint64_t seed, std::uint64_t i) {
  reference_detail::Random a(seed);
  reference_detail::Random b(a.next_u64() ^ (i * 0xd1342543de82ef95ull));
  return b.next_u64();
}

// Per-thread scratch segments (reused to avoid allocations).
struct Workspace {
  Segment path;  // segments of follow_path
  Segment first; // the first segment of an irradiance sample
};

// Mean and standard error of the mean over N = `paths` samples
// f_i = sample(u_i, random_i, workspace), u_i = (i + ξ_i)/N stratified:
//   mean = Σ f_i / N,   SE² = Σ (f_i - mean)² / (N (N - 1)).
// Paths run in parallel in fixed blocks of 64; each block keeps its count,
// mean and Σ(f - mean_block)², and the blocks are merged in order (Chan,
// Golub & LeVeque: M2 = M2_a + M2_b + δ² n_a n_b / (n_a + n_b)), so the
// result does not depend on the number of threads and memory stays small.
template <class F>
ReferenceResult estimate(const Model& m, const ReferenceOptions& o, F&& sample) {
  constexpr int kBlock = 64;
  const int paths = o.paths;
  const int blocks = (paths + kBlock - 1) / kBlock;
  struct Stats {
    Spec mean{}, m2{};
    int count = 0;
  };
  std::vector<Stats> stats(static_cast<size_t>(blocks));
  tbb::parallel_for(tbb::blocked_range<int>(0, blocks, 1), [&](const tbb::blocked_range<int>& range) {
    Workspace ws;
    std::array<Spec, kBlock> f;
    for (int blk = range.begin(); blk != range.end(); ++blk) {
      Stats& st = stats[size_t(blk)];
      const int first = blk * kBlock, last = std::min(paths, first + kBlock);
      st.count = last - first;
      for (int i = first; i < last; ++i) {
        reference_detail::Random rnd(path_seed(o.seed, std::uint64_t(i)));
        const double u = (i + rnd.uniform()) / paths;
        f[size_t(i - first)] = sample(u, rnd, ws);
      }
      for (int l = 0; l < m.n; ++l) {
        double sum = 0.0;
        for (int k = 0; k < st.count; ++k) sum += f[size_t(k)][size_t(l)];
        const double mean = sum / st.count;
        double m2 = 0.0;
        for (int k = 0; k < st.count; ++k) m2 += (f[size_t(k)][size_t(l)] - mean) * (f[size_t(k)][size_t(l)] - mean);
        st.mean[size_t(l)] = mean;
        st.m2[size_t(l)] = m2;
      }
    }
  });
  ReferenceResult r;
  for (int l = 0; l < m.n; ++l) {
    double n = 0.0, mean = 0.0, m2 = 0.0;
    for (const Stats& st : stats) {
      const double nb = st.count, delta = st.mean[size_t(l)] - mean;
      mean += delta * nb / (n + nb);
      m2 += st.m2[size_t(l)] + delta * delta * n * nb / (n + nb);
      n += nb;
    }
    r.radiance.push_back(mean);
    r.standard_error.push_back(std::sqrt(m2 / (n * (n - 1.0))));
  }
  return r;
}

constexpr size_t kMaxMoons = 8;

// The options alone: K, paths, u in [0, 1], at most kMaxMoons moons, each
// with a finite centre and a finite radius > 0.
void check_options(const ReferenceOptions& o) {
  if (o.scattering_orders < 1) throw Error("reference: scattering_orders must be >= 1");
  if (o.paths < 2) throw Error("reference: paths must be >= 2");
  if (!(o.sun_limb_darkening_u >= 0.0 && o.sun_limb_darkening_u <= 1.0))
    throw Error("reference: sun_limb_darkening_u must be in [0, 1]");
  if (o.moons.size() > kMaxMoons)
    throw Error("reference: at most " + std::to_string(kMaxMoons) + " moons (got " + std::to_string(o.moons.size()) +
                ")");
  for (size_t k = 0; k < o.moons.size(); ++k) {
    const ReferenceMoon& moon = o.moons[k];
    if (!std::isfinite(moon.centre.x) || !std::isfinite(moon.centre.y) || !std::isfinite(moon.centre.z))
      throw Error("reference: moon " + std::to_string(k) + ": centre is not finite");
    if (!std::isfinite(moon.radius) || !(moon.radius > 0.0))
      throw Error("reference: moon " + std::to_string(k) + ": radius must be finite and > 0");
  }
}

// Every moon entirely outside the atmosphere: |centre| - radius > Rt.
void check_moons(const Model& m, const ReferenceOptions& o) {
  for (size_t k = 0; k < o.moons.size(); ++k)
    if (!(glm::length(o.moons[k].centre) - o.moons[k].radius > m.rt))
      throw Error("reference: moon " + std::to_string(k) +
                  " intersects the atmosphere (|centre| - radius must exceed the top radius)");
}

dvec3 check_unit(const dvec3& v, const char* what) {
  const double len = glm::length(v);
  if (!std::isfinite(len) || std::abs(len - 1.0) > 1e-6)
    throw Error(std::string("reference: ") + what + " must be a unit vector");
  return v / len;
}

// A position at or above the ground; within 1 mm below it is snapped onto it.
dvec3 check_position(const Model& m, const dvec3& x, const char* what) {
  const double r = glm::length(x);
  if (!std::isfinite(r)) throw Error(std::string("reference: ") + what + " is not finite");
  if (r < m.rb - 1e-3) throw Error(std::string("reference: ") + what + " is below the ground");
  return r < m.rb ? x * (m.rb / r) : x;
}

// Throws unless the straight segment from `from` to `to` (length `len` > 0,
// unit direction of ray) stays above the ground: the altitude at its point
// closest to the centre, t = clamp(-o·d, 0, len), is >= -1 mm.
void check_above_ground(const Model& m, const Ray& ray, double len) {
  const double tp = std::clamp(-ray.b, 0.0, len);
  if (ray.altitude(tp, m.rb) < -1e-3) throw Error("reference: segment passes below the ground");
}

// τ(λ) = ∫ σ_ext ds along the straight segment from `from` to `to`, for all
// wavelengths, counting only the part inside the atmosphere |x| <= Rt:
// the ray clipped to the roots of |from + t d| = Rt and to [0, |to - from|].
Spec segment_optical_depth(const Model& m, const dvec3& from, const dvec3& to) {
  const double len = glm::length(to - from);
  if (!(len > 0.0)) return Spec{};
  const Ray ray(from, (to - from) / len);
  check_above_ground(m, ray, len);
  double t0, t1;
  const double r = glm::length(from);
  if (!sphere_roots(ray.b, (r - m.rt) * (r + m.rt), t0, t1)) return Spec{};
  const double a0 = std::max(0.0, t0), a1 = std::min(len, t1);
  if (!(a1 > a0)) return Spec{};
  return optical_depth_spec(m, ray, a0, a1);
}

}  // namespace

namespace reference_detail {

double phase_function(const PhaseFunction& phase, double wavelength_nm, double cos_theta) {
  return evaluate_phase(phase_at(phase, wavelength_nm), cos_theta);
}

double sample_phase_cosine(const PhaseFunction& phase, double wavelength_nm, Random& random) {
  return sample_phase(phase_at(phase, wavelength_nm), random);
}

double optical_depth(const Atmosphere& atmosphere, double wavelength_nm, const glm::dvec3& from,
                     const glm::dvec3& to) {
  Atmosphere a = atmosphere;
  a.wavelengths_nm = {wavelength_nm, wavelength_nm, wavelength_nm};  // validate() wants triples
  const Model m = make_model(a, false);
  return segment_optical_depth(m, from, to)[0];
}

}  // namespace reference_detail

namespace {

// More wavelengths than one model holds: the estimate in balanced chunks of
// at most kMaxWavelengths (each its own paths, from the same seed), joined.
template <typename F>
ReferenceResult in_wavelength_chunks(const Atmosphere& atmosphere, F&& estimate_chunk) {
  const size_t n = atmosphere.wavelengths_nm.size();
  if (n <= size_t(kMaxWavelengths)) return estimate_chunk(atmosphere);
  const size_t chunks = (n + size_t(kMaxWavelengths) - 1) / size_t(kMaxWavelengths);
  ReferenceResult out;
  for (size_t c = 0; c < chunks; ++c) {
    Atmosphere part = atmosphere;
    part.wavelengths_nm.assign(atmosphere.wavelengths_nm.begin() + std::ptrdiff_t(c * n / chunks),
                               atmosphere.wavelengths_nm.begin() + std::ptrdiff_t((c + 1) * n / chunks));
    const ReferenceResult r = estimate_chunk(part);
    out.radiance.insert(out.radiance.end(), r.radiance.begin(), r.radiance.end());
    out.standard_error.insert(out.standard_error.end(), r.standard_error.begin(), r.standard_error.end());
  }
  return out;
}

ReferenceResult radiance_chunk(const Atmosphere& atmosphere, const glm::dvec3& observer, const glm::dvec3& view,
                               const glm::dvec3& sun, const ReferenceOptions& options) {
  check_options(options);
  const Model m = make_model(atmosphere, true);
  check_moons(m, options);
  const dvec3 x = check_position(m, observer, "observer");
  const Context ctx{m, check_unit(sun, "sun"), options.scattering_orders, options.moons,
                    options.sun_limb_darkening_u};
  Segment view_segment;
  build_segment(m, x, check_unit(view, "view"), view_segment);
  const Plan plan = shadow_plan(m, view_segment, ctx.sun);
  return estimate(m, options, [&](double u, reference_detail::Random& rnd, Workspace& ws) {
    return radiance_sample(ctx, view_segment, plan, u, rnd, ws.path);
  });
}

// (1') for observer x and point P: paths as radiance_chunk's, on the view
// segment cut at P (build_segment_to), which never ends on the ground, so
// radiance_sample adds no ground term.
ReferenceResult radiance_to_point_chunk(const Atmosphere& atmosphere, const glm::dvec3& observer,
                                        const glm::dvec3& point, const glm::dvec3& sun,
                                        const ReferenceOptions& options) {
  check_options(options);
  const Model m = make_model(atmosphere, true);
  check_moons(m, options);
  const dvec3 x = check_position(m, observer, "observer");
  const dvec3 p = check_position(m, point, "point");
  const Context ctx{m, check_unit(sun, "sun"), options.scattering_orders, options.moons,
                    options.sun_limb_darkening_u};
  const double len = glm::length(p - x);
  // observer == point: an empty segment (any direction, length 0), every
  // sample 0.
  const dvec3 v = len > 0.0 ? (p - x) / len : dvec3(0.0, 0.0, 1.0);
  check_above_ground(m, Ray(x, v), len);
  Segment view_segment;
  build_segment_to(m, x, v, len, view_segment);
  const Plan plan = shadow_plan(m, view_segment, ctx.sun);
  return estimate(m, options, [&](double u, reference_detail::Random& rnd, Workspace& ws) {
    return radiance_sample(ctx, view_segment, plan, u, rnd, ws.path);
  });
}

ReferenceResult irradiance_chunk(const Atmosphere& atmosphere, const glm::dvec3& point, const glm::dvec3& normal,
                                 const glm::dvec3& sun, const ReferenceOptions& options) {
  check_options(options);
  const Model m = make_model(atmosphere, true);
  check_moons(m, options);
  const dvec3 x = check_position(m, point, "point");
  const dvec3 n = check_unit(normal, "normal");
  // Light reaching the surface has used at most K - 1 interactions.
  const Context ctx{m, check_unit(sun, "sun"), options.scattering_orders - 1, options.moons,
                    options.sun_limb_darkening_u};
  return estimate(m, options, [&](double u, reference_detail::Random& rnd, Workspace& ws) {
    Spec out{};
    // Direct sun: L_sunΩ · w_sun(ω) · (n·ω) · T_sun(ω), ω uniform on the
    // disc, w_sun = sun_weight (moons, limb darkening).
    double mu2 = 0.0;
    const dvec3 w = sample_sun(m, ctx.sun, rnd, mu2);
    const double cos_n = glm::dot(n, w);
    const double sw = cos_n > 0.0 ? sun_weight(ctx, x, w, mu2) : 0.0;
    if (sw > 0.0) {
      const Spec t = sun_transmittance(m, x, w);
      for (int l = 0; l < m.n; ++l) out[size_t(l)] = m.sun_nee[size_t(l)] * sw * cos_n * t[size_t(l)];
    }
    if (ctx.max_order < 1) return out;
    // Sky: ω' cosine-weighted about n (density (n·ω')/π, stratified in cos²θ),
    // estimate π · L(x, ω').
    const double mu = std::sqrt(u);
    const dvec3 d = direction_around(n, mu, 2.0 * kPi * rnd.uniform());
    build_segment(m, x, d, ws.first);
    const Spec l_sky = radiance_sample(ctx, ws.first, shadow_plan(m, ws.first, ctx.sun), rnd.uniform(), rnd, ws.path);
    for (int l = 0; l < m.n; ++l) out[size_t(l)] += kPi * l_sky[size_t(l)];
    return out;
  });
}

}  // namespace

ReferenceResult reference_radiance(const Atmosphere& atmosphere, const glm::dvec3& observer, const glm::dvec3& view,
                                   const glm::dvec3& sun, const ReferenceOptions& options) {
  return in_wavelength_chunks(
      atmosphere, [&](const Atmosphere& part) { return radiance_chunk(part, observer, view, sun, options); });
}

ReferenceResult reference_radiance_to_point(const Atmosphere& atmosphere, const glm::dvec3& observer,
                                            const glm::dvec3& point, const glm::dvec3& sun,
                                            const ReferenceOptions& options) {
  return in_wavelength_chunks(atmosphere, [&](const Atmosphere& part) {
    return radiance_to_point_chunk(part, observer, point, sun, options);
  });
}

// T(λ) = exp(-τ(λ)), τ by segment_optical_depth, in chunks of at most
// kMaxWavelengths wavelengths (one model each).
std::vector<double> reference_transmittance(const Atmosphere& atmosphere, const glm::dvec3& from,
                                            const glm::dvec3& to) {
  if (!std::isfinite(glm::length(from)) || !std::isfinite(glm::length(to)))
    throw Error("reference: transmittance end points must be finite");
  const ReferenceResult r = in_wavelength_chunks(atmosphere, [&](const Atmosphere& part) {
    const Model m = make_model(part, false);
    const Spec tau = segment_optical_depth(m, from, to);
    ReferenceResult out;
    for (int l = 0; l < m.n; ++l) {
      out.radiance.push_back(std::exp(-tau[size_t(l)]));
      out.standard_error.push_back(0.0);
    }
    return out;
  });
  return r.radiance;
}

ReferenceResult reference_irradiance(const Atmosphere& atmosphere, const glm::dvec3& point, const glm::dvec3& normal,
                                     const glm::dvec3& sun, const ReferenceOptions& options) {
  return in_wavelength_chunks(
      atmosphere, [&](const Atmosphere& part) { return irradiance_chunk(part, point, normal, sun, options); });
}

ReferenceResult reference_horizontal_irradiance(const Atmosphere& atmosphere, const glm::dvec3& point,
                                                const glm::dvec3& sun, const ReferenceOptions& options) {
  const double r = glm::length(point);
  if (!(r > 0.0) || !std::isfinite(r)) throw Error("reference: point must be away from the planet centre");
  return reference_irradiance(atmosphere, point, point / r, sun, options);
}

}  // namespace atmos
