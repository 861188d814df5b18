// The tail of the series of scattering orders, solved for at once.
//
// Successive orders (Bruneton & Neyret 2008, §4; Elek & Kmoch 2010, §4.2)
// compute the light scattered exactly n times from the light scattered
// n - 1 times: a linear operator A (scattering density, then its integral
// along the view rays, and the sky irradiance on the ground for its
// reflection) applied over and over, v_{n+1} = A v_n. Their sum is the
// solution of the transport equation, (I - A) S = v_2: the orders are its
// Neumann series, i.e. a power iteration, which converges like ρ^n, ρ the
// spectral radius of A. In an optically thick, nearly conservative
// atmosphere ρ is close to 1 (on Venus the ratio of successive orders is
// about 0.995 in the green: the light that reaches the ground has been
// scattered hundreds of times), and summing the orders to convergence costs
// hundreds of orders.
//
// Krylov methods solve the same linear system in far fewer applications of
// A: GMRES (Saad & Schultz 1986) picks, among all combinations of the fields
// reachable with k applications of A, the one that minimises the residual,
// i.e. the best polynomial in A of degree k instead of the truncated series
// 1 + A + ... + A^k. For a spectrum of A in [0, ρ] its error falls like
// ((√κ - 1) / (√κ + 1))^k with κ = 1 / (1 - ρ), against ρ^k for the orders:
// for ρ = 0.98, by 10^-3 in ~25 applications instead of ~340. Transport
// codes accelerate the same slow "source iteration" this way (Adams &
// Larsen 2002, Progress in Nuclear Energy 40). tests/convergence_accuracy.cpp
// checks the solver's sum against 600 explicit orders on Venus.
//
// Here it sums the orders after K, T = Σ_{n > K} v_n, which satisfies
// (I - A) T = v_{K+1}: the K explicit orders stay what they are (light
// scattered at most K times, reported per order), and the solver adds the
// rest. A is applied to signed fields (the Krylov basis), which it handles
// since every step is linear — except the clamping of the density's ringing
// below zero, which is switched off for those fields. The three channels are
// independent problems (A does not mix wavelengths), solved side by side with
// their own Krylov coefficients through the same applications of A.
//
// The Krylov basis holds `restart` fields (tables of the size of a
// scattering table), and a plain restart forgets what the basis had learnt
// of the slowest modes, which then have to be found again at every cycle
// (restarted GMRES stalls on Venus's tables). The restart here is deflated
// (GMRES-DR, Morgan 2002, SIAM J. Sci. Comput. 24, 20): it keeps the
// approximate eigenvectors (harmonic Ritz vectors) of the `deflation`
// eigenvalues of I - A nearest 0 together with the residual, so that those
// modes stay solved for and the next cycle works on the rest of the
// spectrum.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

// LAPACK (Anderson et al. 1999) for the small dense problems of the
// restarts: least squares, LU, eigenvectors, QR; column-major storage.
#define LAPACK_COMPLEX_CPP
#include <lapacke.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>

#include "precompute/steps.hpp"

namespace atmos::precompute {

namespace {

using glm::dvec3;

// A small dense matrix, column-major (LAPACK's layout), zero at first.
struct Matrix {
  int rows = 0, cols = 0;
  std::vector<double> v;
  Matrix() = default;
  Matrix(int r, int c) : rows(r), cols(c), v(size_t(r) * size_t(c), 0.0) {}
  double& operator()(int i, int j) { return v[size_t(j) * size_t(rows) + size_t(i)]; }
  double operator()(int i, int j) const { return v[size_t(j) * size_t(rows) + size_t(i)]; }
  // The top left r x c block.
  Matrix block(int r, int c) const {
    Matrix b(r, c);
    for (int j = 0; j < c; ++j)
      for (int i = 0; i < r; ++i) b(i, j) = (*this)(i, j);
    return b;
  }
};

using Vector = std::vector<double>;

// a x (the first a.cols entries of x).
Vector product(const Matrix& a, const Vector& x) {
  Vector y(size_t(a.rows), 0.0);
  for (int j = 0; j < a.cols; ++j)
    for (int i = 0; i < a.rows; ++i) y[size_t(i)] += a(i, j) * x[size_t(j)];
  return y;
}

// aᵀ b.
Matrix transpose_product(const Matrix& a, const Matrix& b) {
  Matrix c(a.cols, b.cols);
  for (int j = 0; j < b.cols; ++j)
    for (int i = 0; i < a.cols; ++i) {
      double sum = 0.0;
      for (int l = 0; l < a.rows; ++l) sum += a(l, i) * b(l, j);
      c(i, j) = sum;
    }
  return c;
}

// a b.
Matrix product(const Matrix& a, const Matrix& b) {
  Matrix c(a.rows, b.cols);
  for (int j = 0; j < b.cols; ++j)
    for (int l = 0; l < a.cols; ++l)
      for (int i = 0; i < a.rows; ++i) c(i, j) += a(i, l) * b(l, j);
  return c;
}

// The x that minimises |b - a x|, a of full column rank or not: QR with
// column pivoting (LAPACK dgelsy), of effective rank the largest leading
// triangle of R whose condition number stays below 1e15.
Vector least_squares(Matrix a, const Vector& b) {
  Vector x = b;
  x.resize(size_t(std::max(a.rows, a.cols)), 0.0);
  std::vector<lapack_int> pivots(size_t(a.cols), 0);
  lapack_int rank = 0;
  if (LAPACKE_dgelsy(LAPACK_COL_MAJOR, a.rows, a.cols, 1, a.v.data(), a.rows, x.data(), lapack_int(x.size()),
                     pivots.data(), 1e-15, &rank) != 0)
    std::fill(x.begin(), x.end(), 0.0);
  x.resize(size_t(a.cols));
  return x;
}

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

// basis[l] ← Σ_j P_c(j, l) basis[j] for l < new_count, j < old_count, per
// channel c, in place: texel by texel (each texel's new values depend on
// that texel's old values only), so no field is allocated.
void recombine(std::vector<Field>& basis, const std::array<Matrix, 3>& p, int old_count, int new_count) {
  std::vector<vec3> pf(size_t(old_count) * size_t(new_count));
  for (int l = 0; l < new_count; ++l)
    for (int j = 0; j < old_count; ++j)
      for (int c = 0; c < 3; ++c) pf[size_t(l) * size_t(old_count) + size_t(j)][c] = float(p[size_t(c)](j, l));
  auto texels = [&](auto member, size_t count) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1024), [&](const tbb::blocked_range<size_t>& range) {
      std::vector<vec3> old(static_cast<size_t>(old_count));
      for (size_t i = range.begin(); i != range.end(); ++i) {
        for (int j = 0; j < old_count; ++j) old[size_t(j)] = (basis[size_t(j)].*member).texels[i];
        for (int l = 0; l < new_count; ++l) {
          vec3 sum(0.0f);
          for (int j = 0; j < old_count; ++j) sum += pf[size_t(l) * size_t(old_count) + size_t(j)] * old[size_t(j)];
          (basis[size_t(l)].*member).texels[i] = sum;
        }
      }
    });
  };
  texels(&Field::radiance, basis[0].radiance.texels.size());
  texels(&Field::irradiance, basis[0].irradiance.texels.size());
}

// The bases of a deflated restart, per channel: P ((m + 1) x (k + 1),
// orthonormal columns), the harmonic Ritz vectors of the k eigenvalues of
// I - A nearest 0 (Morgan 2002: the eigenvectors of H_m + h² H_m^-T e_m e_mᵀ,
// H_m the square part of H and h its last subdiagonal entry), a complex
// pair as its real and imaginary parts, then the residual r. k is the same
// for every channel (the fields carry the three together): the largest
// k <= k_wanted that splits no complex pair in any channel. Returns k, 0
// when no such k > 1 exists or a channel's H_m is singular (then a plain
// restart).
int harmonic_ritz_bases(const std::array<Matrix, 3>& h, const std::array<Vector, 3>& r, const bool active[3], int m,
                        int k_wanted, std::array<Matrix, 3>& p) {
  using complex = std::complex<double>;
  std::array<std::vector<complex>, 3> values;
  std::array<Matrix, 3> vectors;  // LAPACK dgeev's: a complex pair as its real then imaginary parts
  std::array<std::vector<int>, 3> order;
  for (int c = 0; c < 3; ++c) {
    if (!active[c]) continue;
    const Matrix hm = h[size_t(c)].block(m, m);
    const double last = h[size_t(c)](m, m - 1);
    // H_mᵀ and its 1-norm (largest column sum), for the LU's conditioning.
    Matrix lu(m, m);
    double norm1 = 0.0;
    for (int j = 0; j < m; ++j) {
      double column = 0.0;
      for (int i = 0; i < m; ++i) {
        lu(i, j) = hm(j, i);
        column += std::abs(lu(i, j));
      }
      norm1 = std::max(norm1, column);
    }
    std::vector<lapack_int> pivots(static_cast<size_t>(m));
    if (LAPACKE_dgetrf(LAPACK_COL_MAJOR, m, m, lu.v.data(), m, pivots.data()) != 0) return 0;
    // The determinant of a 30 x 30 matrix under- or overflows long before
    // the matrix is singular: ask for its conditioning instead.
    double rcond = 0.0;
    if (LAPACKE_dgecon(LAPACK_COL_MAJOR, '1', m, lu.v.data(), m, norm1, &rcond) != 0 || !(rcond > 1e-14)) return 0;
    Vector f(size_t(m), 0.0);
    f[size_t(m) - 1] = 1.0;
    if (LAPACKE_dgetrs(LAPACK_COL_MAJOR, 'N', m, 1, lu.v.data(), m, pivots.data(), f.data(), m) != 0) return 0;
    Matrix harmonic = hm;
    for (int i = 0; i < m; ++i) harmonic(i, m - 1) += last * last * f[size_t(i)];
    for (double x : harmonic.v)
      if (!std::isfinite(x)) return 0;
    Vector re(static_cast<size_t>(m)), im(static_cast<size_t>(m));
    Matrix& v = vectors[size_t(c)];
    v = Matrix(m, m);
    if (LAPACKE_dgeev(LAPACK_COL_MAJOR, 'N', 'V', m, harmonic.v.data(), m, re.data(), im.data(), nullptr, 1,
                      v.v.data(), m) != 0)
      return 0;
    for (int i = 0; i < m; ++i) values[size_t(c)].emplace_back(re[size_t(i)], im[size_t(i)]);
    std::vector<int>& o = order[size_t(c)];
    for (int i = 0; i < m; ++i) o.push_back(i);
    // By distance from 0; a conjugate pair (same modulus) with its positive
    // imaginary part first, so that the two stay next to each other.
    std::stable_sort(o.begin(), o.end(), [&](int x, int z) {
      const complex vx = values[size_t(c)][size_t(x)], vz = values[size_t(c)][size_t(z)];
      if (std::abs(vx) != std::abs(vz)) return std::abs(vx) < std::abs(vz);
      return vx.imag() > vz.imag();
    });
  }
  auto splits_a_pair = [&](int c, int k) {
    // The k-th value is complex and its conjugate comes after it.
    const complex v = values[size_t(c)][size_t(order[size_t(c)][size_t(k) - 1])];
    return v.imag() > 0.0;
  };
  int k = k_wanted;
  for (; k > 1; --k) {
    bool ok = true;
    for (int c = 0; c < 3; ++c) ok = ok && (!active[c] || !splits_a_pair(c, k));
    if (ok) break;
  }
  if (k <= 1) return 0;
  for (int c = 0; c < 3; ++c) {
    Matrix& pc = p[size_t(c)];
    pc = Matrix(m + 1, k + 1);
    if (!active[c]) {
      for (int i = 0; i <= k; ++i) pc(i, i) = 1.0;
      continue;
    }
    // dgeev stores the eigenvector of λ_j = re_j + i im_j, im_j > 0, as
    // columns j (its real part) and j + 1 (its imaginary part), and
    // λ_{j+1} is the conjugate: column `index` is the real part of the
    // first of a pair and (up to sign) the imaginary part of the second.
    for (int i = 0; i < k; ++i) {
      const int index = order[size_t(c)][size_t(i)];
      for (int row = 0; row < m; ++row) pc(row, i) = vectors[size_t(c)](row, index);
    }
    for (int row = 0; row <= m; ++row) pc(row, k) = r[size_t(c)][size_t(row)];
    // Orthonormal columns (the residual's last, so that it spans what the
    // Ritz vectors do not): Householder QR, thin Q (LAPACK dgeqrf, dorgqr).
    Vector tau(size_t(k) + 1);
    if (LAPACKE_dgeqrf(LAPACK_COL_MAJOR, m + 1, k + 1, pc.v.data(), m + 1, tau.data()) != 0 ||
        LAPACKE_dorgqr(LAPACK_COL_MAJOR, m + 1, k + 1, k + 1, pc.v.data(), m + 1, tau.data()) != 0)
      return 0;
  }
  return k;
}

}  // namespace

ScatteringTail solve_scattering_tail(const AtmosphereParams& a, const OrderGeometry& geometry,
                                     const Table2D& transmittance, const Table3D& next_radiance,
                                     const Table2D& next_irradiance, double tolerance, int max_iterations,
                                     int restart, int deflation, const StepProgress& progress) {
  const int m = std::max(1, std::min(restart, max_iterations));
  // At most m - 2 vectors kept, so that each cycle still adds Krylov
  // vectors (0 or 1: plain restarts).
  const int k_wanted = std::max(0, std::min(deflation, m - 2));
  const Table3D unused;
  Table3D density;
  // out = A in: one scattering order applied to a signed field.
  auto apply = [&](const Field& in, Field& out) {
    compute_scattering_density_table(a, geometry, transmittance, unused, unused, in.radiance, in.irradiance, 2,
                                     nullptr, density, false);
    out.irradiance = compute_indirect_irradiance_table(a, transmittance, unused, unused, in.radiance, 2);
    compute_multiple_scattering_table(a, geometry, density, nullptr, out.radiance, false);
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
  bool active[3];
  for (int c = 0; c < 3; ++c) {
    active[c] = initial_norm[c] > 0.0;
    relative[c] = active[c] ? 1.0 : 0.0;
  }
  auto converged = [&] { return std::max({relative.x, relative.y, relative.z}) <= tolerance; };

  // Per channel: H, the matrix of I - A in the basis (column j: (I - A) v_j
  // = Σ_i H(i, j) v_i, (m + 1) x m), and g, the coordinates of the residual
  // at the start of the cycle.
  std::array<Matrix, 3> h;
  std::array<Vector, 3> g;
  std::vector<Field> basis(1);
  int k = 0;  // basis vectors carried over from the last cycle (then basis[k] is the residual's direction)
  while (tail.iterations < max_iterations && !converged()) {
    if (k == 0) {
      // A plain (re)start: v_0 = r / |r|.
      const dvec3 beta = norm(residual);
      std::swap(basis[0], residual);
      dvec3 inverse_beta(0.0);
      for (int c = 0; c < 3; ++c) inverse_beta[c] = beta[c] > 0.0 ? 1.0 / beta[c] : 0.0;
      scale(basis[0], inverse_beta);
      for (int c = 0; c < 3; ++c) {
        h[size_t(c)] = Matrix(m + 1, m);
        g[size_t(c)].assign(size_t(m) + 1, 0.0);
        g[size_t(c)][0] = beta[c];
      }
    }
    // Arnoldi from column k, with classical Gram-Schmidt done again where it
    // cancels (the DGKS criterion, Daniel et al. 1976): the fields are
    // floats, and the Krylov basis of a slowly converging iteration is
    // nearly dependent.
    std::array<Vector, 3> y;
    int columns = k;
    for (int j = k; j < m && tail.iterations < max_iterations; ++j) {
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
        inverse[c] = column[size_t(j) + 1][c] > 1e-12 * initial_norm[c] ? 1.0 / column[size_t(j) + 1][c] : 0.0;
      scale(w, inverse);
      columns = j + 1;
      // (I - A) v_j = v_j - Σ projections_i v_i - |w| v_{j+1}.
      for (int c = 0; c < 3; ++c) {
        for (int i = 0; i <= j + 1; ++i) h[size_t(c)](i, j) = -column[size_t(i)][c];
        h[size_t(c)](j, j) += 1.0;
      }
      // The least-squares problem min |g - H y| of each channel, solved
      // again at each step (H is (j + 2) x (j + 1), at most 31 x 30: a few
      // microseconds, against about a second for the step).
      for (int c = 0; c < 3; ++c) {
        if (!active[c]) {
          y[size_t(c)].assign(size_t(columns), 0.0);
          continue;
        }
        const Matrix hc = h[size_t(c)].block(columns + 1, columns);
        const Vector gc(g[size_t(c)].begin(), g[size_t(c)].begin() + columns + 1);
        y[size_t(c)] = least_squares(hc, gc);
        const Vector hy = product(hc, y[size_t(c)]);
        double squares = 0.0;
        for (int i = 0; i <= columns; ++i) squares += (gc[size_t(i)] - hy[size_t(i)]) * (gc[size_t(i)] - hy[size_t(i)]);
        relative[c] = std::sqrt(squares) / initial_norm[c];
      }
      if (converged()) break;
    }
    // T += V y.
    std::vector<dvec3> coefficients(size_t(columns), dvec3(0.0));
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < columns; ++i) coefficients[size_t(i)][c] = y[size_t(c)][size_t(i)];
    add_combination(solution, coefficients, basis.data(), columns);
    if (converged() || tail.iterations >= max_iterations) break;

    // The residual's coordinates in the basis, g - H y.
    std::array<Vector, 3> r;
    for (int c = 0; c < 3; ++c) {
      r[size_t(c)].assign(size_t(columns) + 1, 0.0);
      if (!active[c]) continue;
      const Vector hy = product(h[size_t(c)].block(columns + 1, columns), y[size_t(c)]);
      for (int i = 0; i <= columns; ++i) r[size_t(c)][size_t(i)] = g[size_t(c)][size_t(i)] - hy[size_t(i)];
    }
    // Deflated restart (see the top of the file): keep the harmonic Ritz
    // vectors of the k eigenvalues of I - A nearest 0, i.e. the slowest
    // modes of the orders (the light diffusing through a thick, nearly
    // conservative layer: eigenvalues of A near 1).
    std::array<Matrix, 3> p;
    const int kept = columns == m ? harmonic_ritz_bases(h, r, active, m, k_wanted, p) : 0;
    if (kept == 0) {
      // A plain restart from the residual V r.
      if (residual.radiance.texels.empty()) residual = zero_field(a);
      set_zero(residual);
      std::vector<dvec3> rc(size_t(columns) + 1, dvec3(0.0));
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i <= columns; ++i) rc[size_t(i)][c] = r[size_t(c)][size_t(i)];
      add_combination(residual, rc, basis.data(), columns + 1);
      k = 0;
      continue;
    }
    // The new basis V P (kept + 1 fields: the Ritz vectors and the residual's
    // direction), H ← Pᵀ H P, g ← Pᵀ r.
    recombine(basis, p, m + 1, kept + 1);
    for (int c = 0; c < 3; ++c) {
      const Matrix& pc = p[size_t(c)];
      const Matrix small = transpose_product(pc, product(h[size_t(c)], pc.block(m, kept)));
      Matrix rc(m + 1, 1);
      rc.v = r[size_t(c)];
      const Matrix gc = transpose_product(pc, rc);
      h[size_t(c)] = Matrix(m + 1, m);
      for (int j = 0; j < kept; ++j)
        for (int i = 0; i <= kept; ++i) h[size_t(c)](i, j) = small(i, j);
      g[size_t(c)].assign(size_t(m) + 1, 0.0);
      for (int i = 0; i <= kept; ++i) g[size_t(c)][size_t(i)] = gc(i, 0);
    }
    k = kept;
  }
  tail.relative_residual = relative;
  tail.radiance = std::move(solution.radiance);
  tail.irradiance = std::move(solution.irradiance);
  return tail;
}

}  // namespace atmos::precompute
