#include "precompute/steps.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace atmos::precompute {

using namespace atmos::physics;

namespace {

// Trapezoid steps of the transmittance table's optical depth integral.
constexpr int kTransmittanceSteps = 250;
// Directions (theta x 2 theta) of the hemisphere integral of the irradiance.
constexpr int kIrradianceThetaSamples = 16;
// Gauss-Legendre nodes in mu on each side of the horizon for the density.
constexpr int kDensityMuNodes = 24;

void parallel_texels_2d(int width, int height, const std::function<void(int, int)>& body) {
  tbb::parallel_for(tbb::blocked_range<int>(0, width * height, 64), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i != range.end(); ++i) body(i % width, i / width);
  });
}

// Runs body(y, z) for every (mu, r) row of a scattering table, one r slice at a
// time so that progress can be reported from the calling thread.
void for_each_view_ray(const AtmosphereParams& a, const StepProgress& progress,
                       const std::function<void(int, int)>& body) {
  for (int z = 0; z < a.scattering_r_size; ++z) {
    tbb::parallel_for(tbb::blocked_range<int>(0, a.scattering_mu_size, 4), [&](const tbb::blocked_range<int>& range) {
      for (int y = range.begin(); y != range.end(); ++y) body(y, z);
    });
    if (progress) progress(double(z + 1) / double(a.scattering_r_size));
  }
}

// The (mu_s, tile nu) of each column x of a scattering table: they depend on
// x only (the clamping of nu, which depends on mu, is left to clamp_nu()).
struct TexelColumns {
  std::vector<float> mu_s;
  std::vector<float> tile_nu;
};

TexelColumns make_texel_columns(const AtmosphereParams& a) {
  TexelColumns c;
  const int width = a.scattering_nu_size * a.scattering_mu_s_size;
  for (int x = 0; x < width; ++x) {
    const vec4 uvwz = scattering_uvwz_from_texel(a, vec3(float(x), 0.0f, 0.0f));
    float r, mu, mu_s, nu;
    bool ground;
    r_mu_mu_s_nu_from_scattering_uvwz(a, uvwz, r, mu, mu_s, nu, ground);
    c.mu_s.push_back(mu_s);
    c.tile_nu.push_back(scattering_texel_tile_nu(a, vec3(float(x), 0.0f, 0.0f)));
  }
  return c;
}

// scattering_u_mu_s() tabulated finely over [mu_s_min, 1] (constant below,
// where the mapping clamps): it costs three square roots and four divisions,
// and the multiple scattering evaluates it for every texel and ray node.
// Linear interpolation between 8192 samples of this smooth function is exact
// to ~1e-7 of the coordinate; the kink at mu_s_min is a sample, not crossed.
class MuSCoordinate {
 public:
  explicit MuSCoordinate(const AtmosphereParams& a) : low_(a.mu_s_min), u_(kSamples + 1) {
    scale_ = float(kSamples) / (1.0f - low_);
    for (int i = 0; i <= kSamples; ++i)
      u_[size_t(i)] = scattering_u_mu_s(a, low_ + (1.0f - low_) * float(i) / float(kSamples));
  }
  float operator()(float mu_s) const {
    const float x = std::max(mu_s - low_, 0.0f) * scale_;
    const int i = std::min(int(x), kSamples - 1);
    const float f = std::min(x - float(i), 1.0f);
    return u_[size_t(i)] + (u_[size_t(i) + 1] - u_[size_t(i)]) * f;
  }

 private:
  static constexpr int kSamples = 8192;
  float low_;
  float scale_ = 1.0f;
  std::vector<float> u_;
};

// transmittance_to_sun(a, t, r, mu_s) for one radius and many mu_s: the
// row of the transmittance table at r (its v coordinate) is interpolated
// once, and the solar disc is only averaged near the horizon.
class SunTransmittanceAtRadius {
 public:
  SunTransmittanceAtRadius(const AtmosphereParams& a, const sampler2D& t, float r)
      : a_(a), r_(r), row_(size_t(t.width)) {
    const vec2 uv = transmittance_uv_from_r_mu(a, r, 1.0f);
    int y0, y1;
    float fy;
    detail::linear_tap(uv.y, t.height, y0, y1, fy);
    for (int x = 0; x < t.width; ++x)
      row_[size_t(x)] = t.texels[size_t(y0) * size_t(t.width) + size_t(x)] * (1.0f - fy) +
                        t.texels[size_t(y1) * size_t(t.width) + size_t(x)] * fy;
    mu_h_ = horizon_mu(a, r);
  }
  vec3 operator()(float mu_s) const {
    if (!sun_needs_disc_average(a_, mu_s, mu_h_)) return at(mu_s);
    if (mu_s - mu_h_ < -a_.sun_angular_radius) return vec3(0.0f);
    vec3 sum(0.0f);
    for (int k = 0; k < SUN_DISC_NODES; ++k) {
      float weight;
      const float mu_k = sun_disc_node(a_, mu_s, mu_h_, k, weight);
      sum += weight * at(mu_k);
    }
    return sum;
  }

 private:
  vec3 at(float mu) const {
    int x0, x1;
    float fx;
    detail::linear_tap(transmittance_uv_from_r_mu(a_, r_, mu).x, int(row_.size()), x0, x1, fx);
    // The table holds optical depth (transmittance_to_top_atmosphere_boundary).
    return exp(-(row_[size_t(x0)] * (1.0f - fx) + row_[size_t(x1)] * fx));
  }

  const AtmosphereParams& a_;
  float r_;
  std::vector<vec3> row_;
  float mu_h_ = 0.0f;
};

// The 4D table `table` at one (u_mu, u_r), trilinear in those two
// coordinates exactly as texture() does: a row of (nu, mu_s) texels. Lookups
// that share (r, mu) interpolate in it instead of the whole table.
void interpolate_mu_r_row(const Table3D& table, float u_mu, float u_r, std::vector<vec3>& row) {
  int y0, y1, z0, z1;
  float fy, fz;
  detail::linear_tap(u_mu, table.height, y0, y1, fy);
  detail::linear_tap(u_r, table.depth, z0, z1, fz);
  auto at = [&](int y, int z) {
    return &table.texels[(size_t(z) * size_t(table.height) + size_t(y)) * size_t(table.width)];
  };
  const vec3 *c00 = at(y0, z0), *c10 = at(y1, z0), *c01 = at(y0, z1), *c11 = at(y1, z1);
  row.resize(size_t(table.width));
  for (int x = 0; x < table.width; ++x)
    row[size_t(x)] = (c00[x] * (1.0f - fy) + c10[x] * fy) * (1.0f - fz) + (c01[x] * (1.0f - fy) + c11[x] * fy) * fz;
}

// The nodes of the shared ray quadrature (ray_integration_nodes in
// functions.glsl) for the view ray of row (y, z), with what does not depend
// on the sun.
struct ViewRay {
  float r = 0.0f;
  float mu = 0.0f;
  bool ground = false;
  RayNodes nodes;
  std::array<float, MAX_RAY_NODES> r_t{};
  std::array<float, MAX_RAY_NODES> mu_t{};
};

ViewRay make_view_ray(const AtmosphereParams& a, int y, int z, int intervals) {
  ViewRay ray;
  float mu_s, nu;
  r_mu_mu_s_nu_from_scattering_texel(a, vec3(0.0f, float(y), float(z)), ray.r, ray.mu, mu_s, nu, ray.ground);
  ray.nodes = ray_integration_nodes(a, ray.r, ray.mu, ray.ground, intervals);
  for (int i = 0; i < ray.nodes.count; ++i) {
    ray.r_t[size_t(i)] = clamp_radius(a, radius_along_ray(ray.r, ray.mu, ray.nodes.t[i]));
    ray.mu_t[size_t(i)] = clamp_cosine(mu_along_ray(ray.r, ray.mu, ray.nodes.t[i], ray.r_t[size_t(i)]));
  }
  return ray;
}

// Normalised associated Legendre functions Λ_lm(mu), l <= L, 0 <= m <= l,
// such that Y_lm(mu, phi) = Λ_lm(mu) cos(m phi) are orthonormal on the sphere
// (the real, azimuth-even spherical harmonics). Stored at index l(l+1)/2 + m.
// Standard stable recurrences in l for fixed m.
inline int sh_index(int l, int m) { return l * (l + 1) / 2 + m; }
constexpr int kShCount = (kDensityMaxDegree + 1) * (kDensityMaxDegree + 2) / 2;

void associated_legendre(double mu, std::array<float, kShCount>& out) {
  const int L = kDensityMaxDegree;
  const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  double p_mm = std::sqrt(1.0 / (4.0 * M_PI));  // P̃_00
  for (int m = 0; m <= L; ++m) {
    if (m > 0) p_mm *= std::sqrt((2.0 * m + 1.0) / (2.0 * m)) * s;
    const double scale = m > 0 ? std::sqrt(2.0) : 1.0;
    out[size_t(sh_index(m, m))] = float(p_mm * scale);
    if (m == L) break;
    double p_prev = p_mm;
    double p_l = std::sqrt(2.0 * m + 3.0) * mu * p_mm;  // P̃_{m+1,m}
    out[size_t(sh_index(m + 1, m))] = float(p_l * scale);
    for (int l = m + 2; l <= L; ++l) {
      const double a = std::sqrt((4.0 * l * l - 1.0) / (double(l * l) - double(m * m)));
      const double b = std::sqrt((double((l - 1) * (l - 1)) - double(m * m)) / (4.0 * (l - 1) * (l - 1) - 1.0));
      const double p_next = a * (mu * p_l - b * p_prev);
      p_prev = p_l;
      p_l = p_next;
      out[size_t(sh_index(l, m))] = float(p_l * scale);
    }
  }
}

}  // namespace

void gauss_legendre(int n, double a, double b, std::vector<double>& nodes, std::vector<double>& weights) {
  nodes.assign(size_t(n), 0.0);
  weights.assign(size_t(n), 0.0);
  for (int i = 0; i < n; ++i) {
    // Newton iteration on P_n from Tricomi's initial guess.
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) { p1 = x; p0 = 1.0; }
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-15) break;
    }
    nodes[size_t(i)] = 0.5 * (a + b) + 0.5 * (b - a) * (-x);
    weights[size_t(i)] = (b - a) / ((1.0 - x * x) * dp * dp);
  }
}

std::vector<double> legendre_moments(const std::function<double(double)>& phase, int max_degree) {
  static const std::pair<std::vector<double>, std::vector<double>> rule = [] {
    std::pair<std::vector<double>, std::vector<double>> r;
    gauss_legendre(2048, -1.0, 1.0, r.first, r.second);
    return r;
  }();
  const std::vector<double>& x = rule.first;
  const std::vector<double>& w = rule.second;
  std::vector<double> moments(size_t(max_degree + 1), 0.0);
  for (size_t k = 0; k < x.size(); ++k) {
    const double p = phase(x[k]) * w[k] * 2.0 * M_PI;
    double p0 = 1.0, p1 = x[k];
    moments[0] += p;
    if (max_degree >= 1) moments[1] += p * p1;
    for (int l = 2; l <= max_degree; ++l) {
      const double p2 = ((2.0 * l - 1.0) * x[k] * p1 - (l - 1.0) * p0) / l;
      p0 = p1;
      p1 = p2;
      moments[size_t(l)] += p * p2;
    }
  }
  return moments;
}

Table2D compute_transmittance_table(const AtmosphereParams& a) {
  Table2D table(a.transmittance_mu_size, a.transmittance_r_size);
  parallel_texels_2d(table.width, table.height, [&](int x, int y) {
    float r, mu;
    r_mu_from_transmittance_uv(a, vec2((float(x) + 0.5f) / float(table.width), (float(y) + 0.5f) / float(table.height)),
                               r, mu);
    const float d = distance_to_top_atmosphere_boundary(a, r, mu);
    // The optical depth, not its exponential: see transmittance_to_top_atmosphere_boundary.
    table.at(x, y) = optical_depth_along_ray(a, r, mu, 0.0f, d, kTransmittanceSteps);
  });
  return table;
}

Table2D compute_direct_irradiance_table(const AtmosphereParams& a, const Table2D& transmittance) {
  Table2D table(a.irradiance_mu_s_size, a.irradiance_r_size);
  const sampler2D t = transmittance.sampler();
  parallel_texels_2d(table.width, table.height, [&](int x, int y) {
    float r, mu_s;
    r_mu_s_from_irradiance_uv(a, vec2((float(x) + 0.5f) / float(table.width), (float(y) + 0.5f) / float(table.height)),
                              r, mu_s);
    table.at(x, y) = compute_direct_irradiance(a, t, r, mu_s);
  });
  return table;
}

Table2D compute_indirect_irradiance_table(const AtmosphereParams& a, const Table2D& transmittance,
                                          const Table3D& single_rayleigh, const Table3D& single_aerosol,
                                          const Table3D& multiple_scattering, int order) {
  Table2D table(a.irradiance_mu_s_size, a.irradiance_r_size);
  const sampler2D t = transmittance.sampler();
  const sampler3D sr = single_rayleigh.sampler(), sa = single_aerosol.sampler(), ms = multiple_scattering.sampler();
  parallel_texels_2d(table.width, table.height, [&](int x, int y) {
    float r, mu_s;
    r_mu_s_from_irradiance_uv(a, vec2((float(x) + 0.5f) / float(table.width), (float(y) + 0.5f) / float(table.height)),
                              r, mu_s);
    table.at(x, y) = compute_indirect_irradiance(a, t, sr, sa, ms, r, mu_s, order, kIrradianceThetaSamples);
  });
  return table;
}

// compute_single_scattering() of functions.glsl for every texel, with the view
// ray's nodes computed once per (mu, r) row.
void compute_single_scattering_tables(const AtmosphereParams& a, const Table2D& transmittance, Table3D& rayleigh,
                                      Table3D& aerosol, const StepProgress& progress) {
  const int width = a.scattering_nu_size * a.scattering_mu_s_size;
  rayleigh = Table3D(width, a.scattering_mu_size, a.scattering_r_size);
  aerosol = Table3D(width, a.scattering_mu_size, a.scattering_r_size);
  const sampler2D t = transmittance.sampler();
  const TexelColumns columns = make_texel_columns(a);
  for_each_view_ray(a, progress, [&](int y, int z) {
    const ViewRay ray = make_view_ray(a, y, z, SINGLE_SCATTERING_INTERVALS);
    // Node by node (outer loop), so that the transmittance row of the node
    // stays in the L1 cache while all texels of the view ray use it.
    std::vector<float> nu(static_cast<size_t>(width));
    for (int x = 0; x < width; ++x)
      nu[size_t(x)] = clamp_nu(ray.mu, columns.mu_s[size_t(x)], columns.tile_nu[size_t(x)]);
    std::vector<vec3> sum_rayleigh(size_t(width), vec3(0.0f)), sum_aerosol(size_t(width), vec3(0.0f));
    for (int i = 0; i < ray.nodes.count; ++i) {
      vec3 beta_rayleigh, beta_aerosol, extinction;
      medium_at(a, ray.r_t[size_t(i)], beta_rayleigh, beta_aerosol, extinction);
      beta_rayleigh *= ray.nodes.weight[i];
      beta_aerosol *= ray.nodes.weight[i];
      const SunTransmittanceAtRadius sun(a, t, ray.r_t[size_t(i)]);
      for (int x = 0; x < width; ++x) {
        const float mu_s_t = clamp_cosine(
            mu_s_along_ray(ray.r, columns.mu_s[size_t(x)], nu[size_t(x)], ray.nodes.t[i], ray.r_t[size_t(i)]));
        const vec3 sun_transmittance = sun(mu_s_t);
        sum_rayleigh[size_t(x)] += sun_transmittance * beta_rayleigh;
        sum_aerosol[size_t(x)] += sun_transmittance * beta_aerosol;
      }
    }
    for (int x = 0; x < width; ++x) {
      rayleigh.at(x, y, z) = sum_rayleigh[size_t(x)] * a.solar_irradiance;
      aerosol.at(x, y, z) = sum_aerosol[size_t(x)] * a.solar_irradiance;
    }
  });
}

// The scattering density through spherical harmonics. At a point (r, mu_s)
// the incident radiance L(w) is projected on the real spherical harmonics
// Y_lm (azimuth-even: the field is symmetric about the sun's vertical plane),
//   L_lm = ∫ L(w) Y_lm(w) dw,
// by Gauss-Legendre quadrature in mu split at the horizon (where L is
// discontinuous) and the trapezoidal rule in azimuth (exact for trigonometric
// polynomials). By the addition theorem, a phase function with Legendre
// moments p_l turns this into
//   ∫ P(v.w) L(w) dw = Σ_lm p_l L_lm Y_lm(v)
// (Funk-Hecke). The Rayleigh phase function has only p_0 and p_2, so its part
// is exact; the aerosol part is truncated at degree kDensityMaxDegree, where
// p_l = g^l for Henyey-Greenstein (0.8^32 ≈ 8e-4). The cost is one set of
// radiance samples per (r, mu_s) instead of one sphere per 4D texel.
Table3D compute_scattering_density_table(const AtmosphereParams& a, const Table2D& transmittance,
                                         const Table3D& single_rayleigh, const Table3D& single_aerosol,
                                         const Table3D& multiple_scattering, const Table2D& irradiance, int order,
                                         const StepProgress& progress) {
  constexpr int L = kDensityMaxDegree;
  constexpr int kPhiIntervals = L + 1;  // over [0, π]; 2 (L + 1) over the circle
  const int width = a.scattering_nu_size * a.scattering_mu_s_size;
  Table3D density(width, a.scattering_mu_size, a.scattering_r_size);
  const sampler2D t = transmittance.sampler(), e = irradiance.sampler();

  const std::vector<double> rayleigh_moments =
      legendre_moments([](double x) { return double(rayleigh_phase_function(float(x))); }, L);
  const std::vector<double> aerosol_moments =
      legendre_moments([&](double x) { return double(aerosol_phase_function(a, float(x))); }, L);

  std::array<float, kPhiIntervals + 1> cos_phi{};
  for (int l = 0; l <= kPhiIntervals; ++l) cos_phi[size_t(l)] = float(std::cos(M_PI * l / kPhiIntervals));
  // Trapezoid weights of ∫_0^{2π} f(phi) cos(m phi) dphi for an even f sampled on [0, π].
  std::vector<float> fourier_weight(size_t((L + 1) * (kPhiIntervals + 1)));
  for (int m = 0; m <= L; ++m)
    for (int l = 0; l <= kPhiIntervals; ++l)
      fourier_weight[size_t(m * (kPhiIntervals + 1) + l)] =
          float((l == 0 || l == kPhiIntervals ? 1.0 : 2.0) * std::cos(M_PI * double(m * l) / kPhiIntervals) * M_PI /
                kPhiIntervals);

  for (int z = 0; z < a.scattering_r_size; ++z) {
    // Everything that depends on r only: the quadrature nodes in mu (below
    // and above the horizon), the harmonics at those nodes and at the mu of
    // the output texels.
    float r, mu_unused, mu_s_unused, nu_unused;
    bool ground_unused;
    r_mu_mu_s_nu_from_scattering_texel(a, vec3(0.0f, 0.0f, float(z)), r, mu_unused, mu_s_unused, nu_unused,
                                       ground_unused);
    const double mu_h = horizon_mu(a, r);
    std::vector<double> nodes, weights, nodes_up, weights_up;
    gauss_legendre(kDensityMuNodes, -1.0, mu_h, nodes, weights);
    gauss_legendre(kDensityMuNodes, mu_h, 1.0, nodes_up, weights_up);
    nodes.insert(nodes.end(), nodes_up.begin(), nodes_up.end());
    weights.insert(weights.end(), weights_up.begin(), weights_up.end());
    std::vector<std::array<float, kShCount>> node_harmonics(nodes.size());
    for (size_t j = 0; j < nodes.size(); ++j) associated_legendre(nodes[j], node_harmonics[j]);
    std::vector<float> output_mu(size_t(a.scattering_mu_size));
    std::vector<std::array<float, kShCount>> output_harmonics(output_mu.size());
    for (int y = 0; y < a.scattering_mu_size; ++y) {
      float r_y, mu_s_y, nu_y;
      bool ground_y;
      r_mu_mu_s_nu_from_scattering_texel(a, vec3(0.0f, float(y), float(z)), r_y, output_mu[size_t(y)], mu_s_y, nu_y,
                                         ground_y);
      associated_legendre(output_mu[size_t(y)], output_harmonics[size_t(y)]);
    }

    // incident_radiance() for all directions of node j shares the (mu, r)
    // part of its table lookups and the transmittance to the ground: do the
    // (mu, r) interpolation once, leaving rows of (nu, mu_s) texels whose
    // mu_s columns are exactly those of this step's output.
    struct NodeRows {
      std::vector<vec3> first, second;  // order 1: single Rayleigh, single aerosol; else: multiple scattering
      bool ground = false;
      float ground_distance = 0.0f;
      vec3 ground_transmittance{0.0f};
    };
    std::vector<NodeRows> node_rows(nodes.size());
    tbb::parallel_for(size_t(0), nodes.size(), [&](size_t j) {
      NodeRows& n = node_rows[j];
      const float mu_w = float(nodes[j]);
      n.ground = ray_intersects_ground(a, r, mu_w);
      const float u_mu = scattering_u_mu(a, r, mu_w, n.ground), u_r = scattering_u_r(a, r);
      if (order == 1) {
        interpolate_mu_r_row(single_rayleigh, u_mu, u_r, n.first);
        interpolate_mu_r_row(single_aerosol, u_mu, u_r, n.second);
      } else {
        interpolate_mu_r_row(multiple_scattering, u_mu, u_r, n.first);
      }
      if (n.ground) {
        n.ground_distance = distance_to_bottom_atmosphere_boundary(a, r, mu_w);
        n.ground_transmittance = transmittance_to_ground(a, t, r, mu_w);
      }
    });

    tbb::parallel_for(0, a.scattering_mu_s_size, [&](int mu_s_index) {
      float r_unused, mu_s, mu_unused2, nu_unused2;
      bool ground_unused2;
      r_mu_mu_s_nu_from_scattering_texel(a, vec3(float(mu_s_index), 0.0f, float(z)), r_unused, mu_unused2, mu_s,
                                         nu_unused2, ground_unused2);
      const vec3 sun(std::sqrt(std::max(0.0f, 1.0f - mu_s * mu_s)), 0.0f, mu_s);

      // L_lm, accumulated node by node.
      std::vector<vec3> coefficients(size_t(kShCount), vec3(0.0f));
      std::array<vec3, kPhiIntervals + 1> radiance{};
      for (size_t j = 0; j < nodes.size(); ++j) {
        const float mu_w = float(nodes[j]);
        const float sin_w = std::sqrt(std::max(0.0f, 1.0f - mu_w * mu_w));
        const NodeRows& n = node_rows[j];
        for (int l = 0; l <= kPhiIntervals; ++l) {
          // incident_radiance(a, t, sr, sa, ms, e, r, mu_w, mu_s, nu_w, order), with the lookups hoisted.
          const float nu_w = clamp_cosine(sin_w * cos_phi[size_t(l)] * sun.x + mu_w * sun.z);
          float tile, f;
          scattering_nu_tiles(a, nu_w, tile, f);
          const size_t x0 = size_t(int(tile) * a.scattering_mu_s_size + mu_s_index);
          const size_t x1 = size_t(std::min(int(tile) + 1, a.scattering_nu_size - 1) * a.scattering_mu_s_size + mu_s_index);
          vec3 value = n.first[x0] * (1.0f - f) + n.first[x1] * f;
          if (order == 1) value = phase_weighted_scattering(a, value, n.second[x0] * (1.0f - f) + n.second[x1] * f, nu_w);
          if (n.ground) {
            const float mu_s_ground = mu_s_at_ground(a, r, mu_s, nu_w, n.ground_distance);
            const vec3 ground_irradiance = order == 1 ? compute_direct_irradiance(a, t, a.bottom_radius, mu_s_ground)
                                                      : irradiance_lookup(a, e, a.bottom_radius, mu_s_ground);
            value += n.ground_transmittance * ground_radiance(a, ground_irradiance);
          }
          radiance[size_t(l)] = value;
        }
        const std::array<float, kShCount>& legendre = node_harmonics[j];
        for (int m = 0; m <= L; ++m) {
          // ∫_0^{2π} L cos(m phi) dphi, trapezoidal rule on the symmetric circle.
          const float* fw = &fourier_weight[size_t(m * (kPhiIntervals + 1))];
          vec3 fourier(0.0f);
          for (int l = 0; l <= kPhiIntervals; ++l) fourier += radiance[size_t(l)] * fw[l];
          fourier *= float(weights[j]);
          for (int l = m; l <= L; ++l) coefficients[size_t(sh_index(l, m))] += fourier * legendre[size_t(sh_index(l, m))];
        }
      }

      // Scale by beta_s p_l of both phase functions.
      vec3 beta_rayleigh, beta_aerosol, extinction;
      medium_at(a, r, beta_rayleigh, beta_aerosol, extinction);
      for (int l = 0; l <= L; ++l) {
        const vec3 c = beta_rayleigh * float(rayleigh_moments[size_t(l)]) + beta_aerosol * float(aerosol_moments[size_t(l)]);
        for (int m = 0; m <= l; ++m) coefficients[size_t(sh_index(l, m))] *= c;
      }

      // Evaluate at every texel of this (r, mu_s).
      std::array<vec3, L + 1> azimuthal{};
      for (int y = 0; y < a.scattering_mu_size; ++y) {
        float r_v, mu = output_mu[size_t(y)], mu_s_v, nu;
        bool ground;
        const std::array<float, kShCount>& legendre = output_harmonics[size_t(y)];
        for (int m = 0; m <= L; ++m) {
          vec3 sum(0.0f);
          for (int l = m; l <= L; ++l) sum += coefficients[size_t(sh_index(l, m))] * legendre[size_t(sh_index(l, m))];
          azimuthal[size_t(m)] = sum;
        }
        const float spread = std::sqrt(std::max(0.0f, (1.0f - mu * mu) * (1.0f - mu_s * mu_s)));
        for (int nu_index = 0; nu_index < a.scattering_nu_size; ++nu_index) {
          const int x = nu_index * a.scattering_mu_s_size + mu_s_index;
          r_mu_mu_s_nu_from_scattering_texel(a, vec3(float(x), float(y), float(z)), r_v, mu, mu_s_v, nu, ground);
          const float c = spread < 1e-6f ? 1.0f : clamp_cosine((nu - mu * mu_s) / spread);
          // Σ_m A_m cos(m phi) with the Chebyshev recurrence for cos(m phi).
          float c_prev = 1.0f, c_m = c;
          vec3 value = azimuthal[0];
          for (int m = 1; m <= L; ++m) {
            value += azimuthal[size_t(m)] * c_m;
            const float c_next = 2.0f * c * c_m - c_prev;
            c_prev = c_m;
            c_m = c_next;
          }
          // A truncated expansion can ring slightly below zero next to sharp features.
          density.at(x, y, z) = max(value, vec3(0.0f));
        }
      }
    });
    if (progress) progress(double(z + 1) / double(a.scattering_r_size));
  }
  return density;
}

// compute_multiple_scattering() of functions.glsl for every texel. For each
// node of a view ray, the (mu, r) part of the trilinear lookup of the density
// is the same for all texels of the row: it is done once, leaving a 1D row of
// (nu, mu_s) texels to interpolate per texel.
Table3D compute_multiple_scattering_table(const AtmosphereParams& a, const Table3D& density,
                                          const StepProgress& progress) {
  const int width = a.scattering_nu_size * a.scattering_mu_s_size;
  Table3D result(width, a.scattering_mu_size, a.scattering_r_size);
  const TexelColumns columns = make_texel_columns(a);
  const MuSCoordinate u_of_mu_s(a);
  for_each_view_ray(a, progress, [&](int y, int z) {
    const ViewRay ray = make_view_ray(a, y, z, MULTIPLE_SCATTERING_INTERVALS);
    // Per texel: nu and its tiles, as in scattering_lookup().
    std::vector<float> nu(static_cast<size_t>(width)), tile(static_cast<size_t>(width)), lerp(static_cast<size_t>(width));
    for (int x = 0; x < width; ++x) {
      nu[size_t(x)] = clamp_nu(ray.mu, columns.mu_s[size_t(x)], columns.tile_nu[size_t(x)]);
      scattering_nu_tiles(a, nu[size_t(x)], tile[size_t(x)], lerp[size_t(x)]);
    }
    // Node by node (outer loop): the density row of the node stays in cache.
    std::vector<vec3> row, sum(static_cast<size_t>(width), vec3(0.0f));
    const float inverse_nu_size = 1.0f / float(a.scattering_nu_size);
    for (int i = 0; i < ray.nodes.count; ++i) {
      interpolate_mu_r_row(density, scattering_u_mu(a, ray.r_t[size_t(i)], ray.mu_t[size_t(i)], ray.ground),
                           scattering_u_r(a, ray.r_t[size_t(i)]), row);
      const vec3 weight = ray.nodes.weight[i];
      for (int x = 0; x < width; ++x) {
        const float mu_s_t = clamp_cosine(
            mu_s_along_ray(ray.r, columns.mu_s[size_t(x)], nu[size_t(x)], ray.nodes.t[i], ray.r_t[size_t(i)]));
        const float u_mu_s = u_of_mu_s(mu_s_t);
        int x0, x1;
        float fx;
        detail::linear_tap((tile[size_t(x)] + u_mu_s) * inverse_nu_size, width, x0, x1, fx);
        vec3 value = (row[size_t(x0)] * (1.0f - fx) + row[size_t(x1)] * fx) * (1.0f - lerp[size_t(x)]);
        detail::linear_tap((tile[size_t(x)] + 1.0f + u_mu_s) * inverse_nu_size, width, x0, x1, fx);
        value += (row[size_t(x0)] * (1.0f - fx) + row[size_t(x1)] * fx) * lerp[size_t(x)];
        sum[size_t(x)] += weight * value;
      }
    }
    for (int x = 0; x < width; ++x) result.at(x, y, z) = sum[size_t(x)];
  });
  return result;
}

}  // namespace atmos::precompute
