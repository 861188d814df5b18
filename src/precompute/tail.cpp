// The tail of the series of scattering orders, solved for at once.
//
// Successive orders (seed 004 §4.2, Bruneton & Neyret 2008 §4) compute the
// light scattered exactly n times from the light scattered n - 1 times: a
// linear operator A (scattering density, then its integral along the view
// rays, and the sky irradiance on the ground for its reflection) applied over
// and over, v_{n+1} = A v_n. Their sum is the solution of the transport
// equation, (I - A) S = v_2: the orders are its Neumann series, i.e. a power
// iteration, which converges like ρ^n, ρ the spectral radius of A. In an
// optically thick, nearly conservative atmosphere ρ is close to 1 — light
// diffuses through the deep layers for hundreds of orders (Venus: the ratio
// of successive orders is 0.98 in the green and 0.995 in the blue; the light
// that reaches the ground has been scattered hundreds of times) — and summing
// orders to convergence costs hundreds of orders.
//
// Krylov methods solve the same linear system in far fewer applications of
// A: GMRES (Saad & Schultz 1986) picks, among all combinations of the fields
// reachable with k applications of A, the one that minimises the residual,
// i.e. the best polynomial in A of degree k instead of the truncated series
// 1 + A + ... + A^k. For a spectrum of A in [0, ρ] its error falls like
// ((√κ - 1) / (√κ + 1))^k with κ = 1 / (1 - ρ), against ρ^k for the orders:
// for ρ = 0.98, by 10^-3 in ~25 applications instead of ~340. This is what
// transport codes do for the same slow "source iteration" (see the review of
// Adams & Larsen 2002, Progress in Nuclear Energy 40). Measured on Venus
// (tests/convergence_accuracy.cpp): 16 orders and 58 solver steps give the
// sum of 600 orders (and of the blue's geometric remainder) to 1e-6 in the
// red and green and 0.25 % for the blue light on the ground.
//
// Here it sums the orders after K, T = Σ_{n > K} v_n, which satisfies
// (I - A) T = v_{K+1}: the K explicit orders stay what they are (light
// scattered at most K times, reported per order), and the solver adds the
// rest. A is applied to signed fields (the Krylov basis), which it handles
// since every step is linear — except the clamping of the density's ringing
// below zero, which is switched off for those fields. The three channels are
// independent problems (A does not mix wavelengths), solved side by side with
// their own Krylov coefficients through the same applications of A.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

#include "precompute/steps.hpp"

namespace atmos::precompute {

namespace {

using glm::dvec3;

// A field of the iteration: the radiance of an order (a 4D table, as the
// multiple scattering tables: not divided by a phase function) and the sky
// irradiance on the ground that the next order reflects.
struct Field {
  Table3D radiance;
  Table2D irradiance;
};

// Per channel: Σ a b over the radiance texels, plus the irradiance texels
// weighted so that an isotropic radiance L and its irradiance π L weigh alike
// per texel, times the ratio of the texel counts: the ground's light counts
// in the residual as much as the atmosphere's.
struct InnerProduct {
  double irradiance_weight = 1.0;

  // <w, fields[k]> for k < count, then <w, w>: one sweep over the texels of
  // w (a block of it stays in cache while it meets every field).
  std::vector<dvec3> operator()(const Field& w, const Field* fields, int count) const {
    using Sums = std::vector<dvec3>;
    const std::vector<vec3>& x = w.radiance.texels;
    auto sweep = [&](const tbb::blocked_range<size_t>& range, Sums partial) {
      for (int k = 0; k <= count; ++k) {
        const vec3* y = k < count ? fields[k].radiance.texels.data() : x.data();
        dvec3 sum(0.0);
        for (size_t i = range.begin(); i != range.end(); ++i) sum += dvec3(x[i]) * dvec3(y[i]);
        partial[size_t(k)] += sum;
      }
      return partial;
    };
    Sums sums = tbb::parallel_reduce(tbb::blocked_range<size_t>(0, x.size(), 4096), Sums(size_t(count) + 1, dvec3(0.0)),
                                     sweep, [](Sums p, const Sums& q) {
                                       for (size_t k = 0; k < p.size(); ++k) p[k] += q[k];
                                       return p;
                                     });
    for (int k = 0; k <= count; ++k) {
      const std::vector<vec3>& e = k < count ? fields[k].irradiance.texels : w.irradiance.texels;
      dvec3 ground(0.0);
      for (size_t i = 0; i < e.size(); ++i) ground += dvec3(w.irradiance.texels[i]) * dvec3(e[i]);
      sums[size_t(k)] += irradiance_weight * ground;
    }
    return sums;
  }
};

// w += Σ c[k] fields[k], k < count, per channel, in one sweep over w.
void add_combination(Field& w, const std::vector<dvec3>& c, const Field* fields, int count) {
  std::vector<vec3> cf;
  for (int k = 0; k < count; ++k) cf.emplace_back(c[size_t(k)]);
  std::vector<vec3>& x = w.radiance.texels;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, x.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
    for (int k = 0; k < count; ++k) {
      const vec3* y = fields[k].radiance.texels.data();
      for (size_t i = range.begin(); i != range.end(); ++i) x[i] += cf[size_t(k)] * y[i];
    }
  });
  for (int k = 0; k < count; ++k)
    for (size_t i = 0; i < w.irradiance.texels.size(); ++i) w.irradiance.texels[i] += cf[size_t(k)] * fields[k].irradiance.texels[i];
}

void scale(Field& a, const dvec3& c) {
  const vec3 cf(c);
  for (vec3& v : a.radiance.texels) v *= cf;
  for (vec3& v : a.irradiance.texels) v *= cf;
}

Field zero_field(const AtmosphereParams& a) {
  return {Table3D(a.scattering_nu_size * a.scattering_mu_s_size, a.scattering_mu_size, a.scattering_r_size),
          Table2D(a.irradiance_mu_s_size, a.irradiance_r_size)};
}

void set_zero(Field& f) {
  std::fill(f.radiance.texels.begin(), f.radiance.texels.end(), vec3(0.0f));
  std::fill(f.irradiance.texels.begin(), f.irradiance.texels.end(), vec3(0.0f));
}

}  // namespace

ScatteringTail solve_scattering_tail(const AtmosphereParams& a, const OrderGeometry& geometry,
                                     const Table2D& transmittance, const Table3D& next_radiance,
                                     const Table2D& next_irradiance, double tolerance, int max_iterations,
                                     int restart, const StepProgress& progress) {
  restart = std::max(1, std::min(restart, max_iterations));
  const Table3D unused;
  Table3D density;
  // out = A in: one scattering order applied to a signed field.
  auto apply = [&](const Field& in, Field& out) {
    compute_scattering_density_table(a, geometry, transmittance, unused, unused, in.radiance, in.irradiance, 2,
                                     nullptr, density, false);
    out.irradiance = compute_indirect_irradiance_table(a, transmittance, unused, unused, in.radiance, 2);
    compute_multiple_scattering_table(a, geometry, density, nullptr, out.radiance);
  };
  InnerProduct dot;
  dot.irradiance_weight = double(next_radiance.texels.size()) / double(std::max<size_t>(next_irradiance.texels.size(), 1)) /
                          (M_PI * M_PI);
  auto norm = [&](const Field& f) { return sqrt(dot(f, nullptr, 0)[0]); };

  ScatteringTail tail;
  Field solution = zero_field(a);
  // The residual b - (I - A) T, T = 0 at first: b = v_{K+1}.
  Field residual{next_radiance, next_irradiance};
  const dvec3 initial_norm = norm(residual);
  dvec3 relative(0.0);
  for (int c = 0; c < 3; ++c) relative[c] = initial_norm[c] > 0.0 ? 1.0 : 0.0;

  // Restarted GMRES(restart), per channel (Saad 2003, Algorithm 6.9), with
  // classical Gram-Schmidt done again where it cancels (the DGKS criterion,
  // Daniel et al. 1976): the fields are floats, and the Krylov basis of a
  // slowly converging iteration is nearly dependent. The basis fields are
  // kept between restarts (their memory is reused).
  std::vector<Field> basis(1);
  while (tail.iterations < max_iterations && std::max({relative.x, relative.y, relative.z}) > tolerance) {
    const dvec3 beta = norm(residual);
    std::swap(basis[0], residual);
    dvec3 inverse_beta(0.0);
    for (int c = 0; c < 3; ++c) inverse_beta[c] = beta[c] > 0.0 ? 1.0 / beta[c] : 0.0;
    scale(basis[0], inverse_beta);
    // Hessenberg matrix h[j][i] (column j, row i <= j + 1), Givens rotations,
    // and the right-hand side g = beta e1 as rotated.
    std::vector<std::vector<dvec3>> h;
    std::vector<dvec3> cosine, sine, g{beta};
    int columns = 0;
    for (int j = 0; j < restart && tail.iterations < max_iterations; ++j) {
      if (basis.size() < size_t(j) + 2) basis.emplace_back();
      Field& w = basis[size_t(j) + 1];
      apply(basis[size_t(j)], w);
      ++tail.iterations;
      if (progress) progress(double(tail.iterations) / double(max_iterations));
      std::vector<dvec3> column(size_t(j) + 2, dvec3(0.0));
      for (int pass = 0; pass < 2; ++pass) {
        std::vector<dvec3> projections = dot(w, basis.data(), j + 1);
        const dvec3 before = sqrt(projections.back());
        projections.pop_back();
        std::vector<dvec3> negated;
        for (int i = 0; i <= j; ++i) {
          column[size_t(i)] += projections[size_t(i)];
          negated.push_back(-projections[size_t(i)]);
        }
        add_combination(w, negated, basis.data(), j + 1);
        column[size_t(j) + 1] = norm(w);
        // Once more only if the projection removed most of w (its remainder
        // then carries the rounding errors of what was removed).
        if (!glm::any(glm::lessThan(column[size_t(j) + 1], 0.7071 * before))) break;
      }
      dvec3 inverse(0.0);
      for (int c = 0; c < 3; ++c)
        inverse[c] = column[size_t(j) + 1][c] > 1e-12 * beta[c] ? 1.0 / column[size_t(j) + 1][c] : 0.0;
      scale(w, inverse);
      // The column in I - A: h = -(projections), plus 1 on the diagonal.
      for (int i = 0; i <= j + 1; ++i) column[size_t(i)] = -column[size_t(i)];
      column[size_t(j)] += dvec3(1.0);
      h.push_back(column);
      // Givens rotations, per channel.
      std::vector<dvec3>& hc = h.back();
      for (int i = 0; i < j; ++i) {
        const dvec3 upper = hc[size_t(i)], lower = hc[size_t(i) + 1];
        hc[size_t(i)] = cosine[size_t(i)] * upper + sine[size_t(i)] * lower;
        hc[size_t(i) + 1] = -sine[size_t(i)] * upper + cosine[size_t(i)] * lower;
      }
      dvec3 cs(1.0), sn(0.0);
      for (int c = 0; c < 3; ++c) {
        const double x = hc[size_t(j)][c], y = hc[size_t(j) + 1][c];
        const double length = std::hypot(x, y);
        if (length > 0.0) {
          cs[c] = x / length;
          sn[c] = y / length;
        }
      }
      cosine.push_back(cs);
      sine.push_back(sn);
      hc[size_t(j)] = cs * hc[size_t(j)] + sn * hc[size_t(j) + 1];
      hc[size_t(j) + 1] = dvec3(0.0);
      g.push_back(-sn * g[size_t(j)]);
      g[size_t(j)] = cs * g[size_t(j)];
      columns = j + 1;
      for (int c = 0; c < 3; ++c)
        relative[c] = initial_norm[c] > 0.0 ? std::abs(g[size_t(j) + 1][c]) / initial_norm[c] : 0.0;
      if (std::max({relative.x, relative.y, relative.z}) <= tolerance) break;
    }
    // y = R^-1 g (R the rotated Hessenberg matrix), T += V y.
    std::vector<dvec3> y(size_t(columns), dvec3(0.0));
    for (int i = columns - 1; i >= 0; --i) {
      dvec3 value = g[size_t(i)];
      for (int k = i + 1; k < columns; ++k) value -= h[size_t(k)][size_t(i)] * y[size_t(k)];
      for (int c = 0; c < 3; ++c)
        y[size_t(i)][c] = h[size_t(i)][size_t(i)][c] != 0.0 ? value[c] / h[size_t(i)][size_t(i)][c] : 0.0;
    }
    add_combination(solution, y, basis.data(), columns);
    // The new residual, V_{m+1} Q^T (0, ..., 0, g_{m+1}): the last rotated
    // component turned back into the basis, without applying A.
    std::vector<dvec3> z(size_t(columns) + 1, dvec3(0.0));
    z[size_t(columns)] = g[size_t(columns)];
    for (int i = columns - 1; i >= 0; --i) {
      const dvec3 upper = z[size_t(i)], lower = z[size_t(i) + 1];
      z[size_t(i)] = cosine[size_t(i)] * upper - sine[size_t(i)] * lower;
      z[size_t(i) + 1] = sine[size_t(i)] * upper + cosine[size_t(i)] * lower;
    }
    if (residual.radiance.texels.empty()) residual = zero_field(a);
    set_zero(residual);
    add_combination(residual, z, basis.data(), columns + 1);
  }
  tail.relative_residual = relative;
  tail.radiance = std::move(solution.radiance);
  tail.irradiance = std::move(solution.irradiance);
  return tail;
}

}  // namespace atmos::precompute
