// The steps of the CPU precomputation (steps.hpp), their table lookups
// hoisted out of the per-texel loops, on the vectors of simd.hpp.
#include "precompute/steps.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "physics/precomputation_integrands_cpp.hpp"
#include "precompute/simd.hpp"

namespace atmos::precompute {

using namespace atmos::physics;
using namespace atmos::precompute::simd;

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

// Gives `table` these dimensions, reusing its memory (every texel is then
// written by the step): a new 12 MB table per order costs its page faults.
void resize_table(Table3D& table, int width, int height, int depth) {
  table.width = width;
  table.height = height;
  table.depth = depth;
  table.texels.resize(size_t(width) * size_t(height) * size_t(depth));
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

// unit_range_from_mu_s() (the mu_s coordinate of the scattering and
// irradiance tables) tabulated finely over [mu_s_min, 1] (constant below, where
// the mapping clamps), times `scale`: for a table of n texels along mu_s,
// scale = n - 1 gives the texel coordinate that texture() interpolates at
// (u n - 0.5 with u = texture_coord_from_unit_range(x, n)). The mapping costs
// three square roots and four divisions, and the multiple scattering
// evaluates it for every texel and ray node. Linear interpolation between
// 8192 samples of this smooth function is exact to ~1e-7 of the coordinate;
// the kink at mu_s_min is a sample, not crossed.
class MuSCoordinate {
 public:
  MuSCoordinate(const AtmosphereParams& a, float scale) : low_(a.mu_s_min), u_(kSamples + 1) {
    scale_ = float(kSamples) / (1.0f - low_);
    for (int i = 0; i <= kSamples; ++i)
      u_[size_t(i)] = unit_range_from_mu_s(a, low_ + (1.0f - low_) * float(i) / float(kSamples)) * scale;
  }
  float operator()(float mu_s) const {
    const float x = std::max(mu_s - low_, 0.0f) * scale_;
    const int i = std::min(int(x), kSamples - 1);
    const float f = std::min(x - float(i), 1.0f);
    return u_[size_t(i)] + (u_[size_t(i) + 1] - u_[size_t(i)]) * f;
  }
  // The same for eight cosines.
  ATMOS_KERNEL_INLINE v8f operator()(const v8f& mu_s) const {
    v8f x = mu_s - low_;
    x = max8(x, 0.0f) * scale_;
    const v8i i = min8(__builtin_convertvector(x, v8i), kSamples - 1);
    const v8f f = min8(x - __builtin_convertvector(i, v8f), 1.0f);
    v8f low, high;
    for (int k = 0; k < 8; ++k) {
      low[k] = u_[size_t(i[k])];
      high[k] = u_[size_t(i[k]) + 1];
    }
    return low + (high - low) * f;
  }

 private:
  static constexpr int kSamples = 8192;
  float low_;
  float scale_ = 1.0f;
  std::vector<float> u_;
};

// irradiance_lookup(a, e, bottom_radius, mu_s) for many mu_s: the ground row
// of the irradiance table is interpolated once.
class GroundIrradiance {
 public:
  GroundIrradiance(const AtmosphereParams& a, const sampler2D& e)
      : coordinate_(a, float(e.width - 1)), row_(size_t(e.width)) {
    int y0, y1;
    float fy;
    detail::linear_tap(irradiance_uv_from_r_mu_s(a, a.bottom_radius, 1.0f).y, e.height, y0, y1, fy);
    for (int x = 0; x < e.width; ++x)
      row_[size_t(x)] = e.texels[size_t(y0) * size_t(e.width) + size_t(x)] * (1.0f - fy) +
                        e.texels[size_t(y1) * size_t(e.width) + size_t(x)] * fy;
  }
  vec3 operator()(float mu_s) const {
    const float x = coordinate_(mu_s);
    const int i = std::min(int(x), int(row_.size()) - 2);
    const float f = x - float(i);
    return row_[size_t(i)] * (1.0f - f) + row_[size_t(i) + 1] * f;
  }

 private:
  MuSCoordinate coordinate_;
  std::vector<vec3> row_;
};


// transmittance_to_sun(a, t, r, mu_s) for one radius and many mu_s: the
// row of the transmittance table at r (its v coordinate) is interpolated
// once, with what transmittance_uv_from_r_mu() computes from r alone, and the
// solar disc is only averaged near the horizon.
class SunTransmittanceAtRadius {
 public:
  SunTransmittanceAtRadius(const AtmosphereParams& a, const sampler2D& t, float r) : a_(a) {
    // sun_disc_nodes() for a disc wholly above the horizon: θ_k = 22.5°,
    // 67.5°, 112.5°, 157.5°.
    for (int k = 0; k < SUN_DISC_NODES; ++k) {
      const bool outer = k == 0 || k == 3;
      float cos_theta = outer ? 0.9238795325f : 0.3826834324f;
      const float sin_theta = outer ? 0.3826834324f : 0.9238795325f;
      if (k >= 2) cos_theta = -cos_theta;
      disc_weight_[k] = PI / float(SUN_DISC_NODES) * sin_theta * sin_theta * (2.0f / PI);
      disc_delta_[k] = a.sun_angular_radius * cos_theta;
      disc_cosine_[k] = 1.0f - 0.5f * disc_delta_[k] * disc_delta_[k];
    }
    reset(t, r);
  }

  void reset(const sampler2D& t, float r) {
    const vec2 uv = transmittance_uv_from_r_mu(a_, r, 1.0f);
    int y0, y1;
    float fy;
    detail::linear_tap(uv.y, t.height, y0, y1, fy);
    row_.resize(size_t(t.width));
    for (int x = 0; x < t.width; ++x) {
      const vec3 depth = t.texels[size_t(y0) * size_t(t.width) + size_t(x)] * (1.0f - fy) +
                         t.texels[size_t(y1) * size_t(t.width) + size_t(x)] * fy;
      row_[size_t(x)] = v4f{depth.x, depth.y, depth.z, 0.0f};
    }
    mu_h_ = horizon_mu(a_, r);
    // transmittance_uv_from_r_mu(): x_mu = (d - d_min) / (d_max - d_min) with
    // d the distance to the top; texel coordinate u n - 0.5 in the table of
    // `transmittance_tiles` tiles side by side, as texture() computes it.
    r_ = r;
    top_minus_r_times_top_plus_r_ = (a_.top_radius - r) * (a_.top_radius + r);
    d_min_ = a_.top_radius - r;
    inverse_range_ = 1.0f / (horizon_length(a_, r) + horizon_length_at_top(a_) - d_min_);
    const int n = a_.transmittance_mu_size;
    texel_scale_ = float(n - 1);
    texel_offset_ = float(a_.transmittance_tile * n);
  }

  vec3 operator()(float mu_s) const {
    vec3 result;
    evaluate(&mu_s, 1, &result);
    return result;
  }

  // out[i] = transmittance_to_sun(a, t, r, mu_s[i]), i < count. The
  // transmittance is computed eight zenith cosines at a time (one vector per
  // channel): the points of the solar disc of two suns near the horizon, or
  // eight texels' suns that need no disc average.
  ATMOS_HOT_KERNEL void evaluate(const float* mu_s, int count, vec3* out) const {
    // Suns without a disc average, one lane each.
    int pending_index[8];
    v8f pending_mu{};
    int pending = 0;
    // Suns whose disc is wholly above the horizon, four lanes each.
    int disc_index[2];
    v4f disc_nodes[2];
    int discs = 0;
    std::array<v8f, 3> t;
    auto flush = [&]() __attribute__((always_inline)) {
      for (int k = pending; k < 8; ++k) pending_mu[k] = pending_mu[0];
      at8(pending_mu, t);
      for (int k = 0; k < pending; ++k) out[pending_index[k]] = vec3(t[0][k], t[1][k], t[2][k]);
      pending = 0;
    };
    // The disc average of transmittance_to_sun() from the transmittance at
    // its points (lanes 4 d .. 4 d + 3 of t).
    auto disc_average = [&](int d, v4f weights) __attribute__((always_inline)) {
      float sum[3];
      for (int c = 0; c < 3; ++c) {
        const v8f& v = t[size_t(c)];
        const v4f weighted = weights * (d == 0 ? __builtin_shufflevector(v, v, 0, 1, 2, 3)
                                               : __builtin_shufflevector(v, v, 4, 5, 6, 7));
        sum[c] = weighted[0] + weighted[1];
        sum[c] += weighted[2];
        sum[c] += weighted[3];
      }
      return vec3(sum[0], sum[1], sum[2]);
    };
    auto flush_discs = [&]() __attribute__((always_inline)) {
      if (discs == 1) disc_nodes[1] = disc_nodes[0];
      at8(concat(disc_nodes[0], disc_nodes[1]), t);
      for (int d = 0; d < discs; ++d) out[disc_index[d]] = disc_average(d, disc_weight_);
      discs = 0;
    };
    for (int i = 0; i < count; ++i) {
      const float mu = mu_s[i];
      if (!sun_needs_disc_average(a_, mu, mu_h_)) {
        pending_index[pending] = i;
        pending_mu[pending] = mu;
        if (++pending == 8) flush();
        continue;
      }
      if (mu - mu_h_ < -a_.sun_angular_radius) {
        out[i] = vec3(0.0f);
        continue;
      }
      // The disc average of transmittance_to_sun(), sun_disc_nodes() for each
      // point: for a disc wholly above the horizon its weights and offsets
      // are constants (disc_weight_, disc_delta_ and 1 - delta² / 2 in
      // disc_cosine_), with the same arithmetic.
      if (mu - mu_h_ > a_.sun_angular_radius) {
        const v4f m = splat(mu) * disc_cosine_ + splat(safe_sqrt(1.0f - mu * mu)) * disc_delta_;
        disc_index[discs] = i;
        disc_nodes[discs] = m < splat(-1.0f) ? splat(-1.0f) : (m > splat(1.0f) ? splat(1.0f) : m);
        if (++discs == 2) flush_discs();
        continue;
      }
      // A disc cut by the horizon (rare): its own nodes and weights.
      vec4 node_mu, node_weight;
      sun_disc_nodes(a_, mu, mu_h_, node_mu, node_weight);
      v4f nodes, weights;
      for (int k = 0; k < SUN_DISC_NODES; ++k) {
        nodes[k] = node_mu[k];
        weights[k] = node_weight[k];
      }
      at8(concat(nodes, nodes), t);
      out[i] = disc_average(0, weights);
    }
    if (pending > 0) flush();
    if (discs > 0) flush_discs();
  }

 private:
  static_assert(SUN_DISC_NODES == 4, "the points of the solar disc are one v4f");

  // exp(-τ) at eight zenith cosines mu (lanes), τ interpolated in the row as
  // texture() does; t[c] holds channel c.
  ATMOS_KERNEL_INLINE void at8(const v8f& mu, std::array<v8f, 3>& t) const {
    const v8f r_mu = r_ * mu;
    v8f discriminant = r_mu * r_mu + top_minus_r_times_top_plus_r_;
    discriminant = max8(discriminant, 0.0f);
    const v8f d = max8(sqrt8(discriminant) - r_mu, 0.0f);
    const v8f x_mu = clamp8((d - d_min_) * inverse_range_, 0.0f, 1.0f);
    const v8f coordinate = x_mu * texel_scale_ + texel_offset_;
    const v8i i = min8(__builtin_convertvector(coordinate, v8i), int(row_.size()) - 2);
    const v8f f = coordinate - __builtin_convertvector(i, v8f);
    // Interpolated per lane (a texel's three channels are one v4f), then
    // transposed to one vector per channel: two v4f loads per lane instead
    // of six scalar ones, the same arithmetic per element.
    std::array<v4f, 4> low_lanes, high_lanes;
    for (int k = 0; k < 4; ++k) {
      const v4f* a = &row_[size_t(i[k])];
      const v4f* b = &row_[size_t(i[k + 4])];
      low_lanes[size_t(k)] = a[0] + (a[1] - a[0]) * f[k];
      high_lanes[size_t(k)] = b[0] + (b[1] - b[0]) * f[k + 4];
    }
    transpose4(low_lanes);
    transpose4(high_lanes);
    // The table holds optical depth (transmittance_to_top_atmosphere_boundary).
    for (int c = 0; c < 3; ++c) t[size_t(c)] = exp8(-concat(low_lanes[size_t(c)], high_lanes[size_t(c)]));
  }

  const AtmosphereParams& a_;
  std::vector<v4f> row_;
  float mu_h_ = 0.0f;
  float r_ = 0.0f;
  float top_minus_r_times_top_plus_r_ = 0.0f;
  float d_min_ = 0.0f;
  float inverse_range_ = 0.0f;
  float texel_scale_ = 0.0f;
  float texel_offset_ = 0.0f;
  v4f disc_weight_, disc_delta_, disc_cosine_;
};

// A thread's buffer for a row of `width` packed vec3 texels as floats, plus
// the one float that the last texel's v4f load in spread_to_texels() reads.
std::vector<float>& flat_row(int width) {
  thread_local std::vector<float> flat;
  flat.resize(size_t(width) * 3 + 1);
  return flat;
}

// The row of packed vec3 texels `flat` as one v4f per texel (fourth lane 0),
// followed by `padding` zeros.
ATMOS_KERNEL_INLINE void spread_to_texels(const std::vector<float>& flat, int width, int padding,
                                          std::vector<v4f>& row) {
  row.resize(size_t(width + padding));
  for (int x = 0; x < width; ++x) {
    v4f texel;
    std::memcpy(&texel, &flat[size_t(x) * 3], sizeof(texel));
    row[size_t(x)] = __builtin_shufflevector(texel, splat(0.0f), 0, 1, 2, 4);
  }
  for (int x = width; x < width + padding; ++x) row[size_t(x)] = splat(0.0f);
}

// The 4D table `table` at one (u_mu, u_r), trilinear in those two
// coordinates exactly as texture() does: a row of (nu, mu_s) texels, as
// vectors of 4 floats, followed by `padding` zeros. Lookups that share
// (r, mu) interpolate in it instead of the whole table.
ATMOS_HOT_KERNEL void interpolate_mu_r_row(const Table3D& table, float u_mu, float u_r, int padding,
                                           std::vector<v4f>& row) {
  int y0, y1, z0, z1;
  float fy, fz;
  detail::linear_tap(u_mu, table.height, y0, y1, fy);
  detail::linear_tap(u_r, table.depth, z0, z1, fz);
  auto at = [&](int y, int z) {
    return &table.texels[(size_t(z) * size_t(table.height) + size_t(y)) * size_t(table.width)];
  };
  // The four rows as flat arrays of floats (vec3 texels are three packed
  // floats), interpolated 8 floats at a time, then spread to one v4f per texel.
  static_assert(sizeof(vec3) == 3 * sizeof(float), "Table3D texels are packed floats");
  const float *c00 = &at(y0, z0)->x, *c10 = &at(y1, z0)->x, *c01 = &at(y0, z1)->x, *c11 = &at(y1, z1)->x;
  const float w00 = (1.0f - fy) * (1.0f - fz), w10 = fy * (1.0f - fz), w01 = (1.0f - fy) * fz, w11 = fy * fz;
  const size_t floats = size_t(table.width) * 3;
  std::vector<float>& flat = flat_row(table.width);
  size_t j = 0;
  for (; j + 8 <= floats; j += 8)
    store8(&flat[j], load8(c00 + j) * w00 + load8(c10 + j) * w10 + load8(c01 + j) * w01 + load8(c11 + j) * w11);
  for (; j < floats; ++j) flat[j] = c00[j] * w00 + c10[j] * w10 + c01[j] * w01 + c11[j] * w11;
  spread_to_texels(flat, table.width, padding, row);
}

// interpolate_mu_r_row() for the source rows of a thick atmosphere: rows
// z0 - 1 .. z0 + 2 with `weight` (source_function_lookup), each linear in
// u_mu at the same u_mu.
ATMOS_HOT_KERNEL void interpolate_source_rows(const Table3D& table, float u_mu, int z0, const vec4& weight, bool floor,
                                              int padding, std::vector<v4f>& row) {
  int y0, y1;
  float fy;
  detail::linear_tap(u_mu, table.height, y0, y1, fy);
  auto texels = [&](int j, int y) {
    return &table.texels[(size_t(z0 - 1 + j) * size_t(table.height) + size_t(y)) * size_t(table.width)];
  };
  // As flat arrays of floats, 8 at a time (see interpolate_mu_r_row).
  const size_t floats = size_t(table.width) * 3;
  std::vector<float>& flat = flat_row(table.width);
  std::fill(flat.begin(), flat.end(), 0.0f);
  for (int j = 0; j < 4; ++j) {
    if (weight[j] == 0.0f) continue;
    const float *c0 = &texels(j, y0)->x, *c1 = &texels(j, y1)->x;
    const float w0 = weight[j] * (1.0f - fy), w1 = weight[j] * fy;
    size_t i = 0;
    for (; i + 8 <= floats; i += 8) store8(&flat[i], load8(&flat[i]) + (load8(c0 + i) * w0 + load8(c1 + i) * w1));
    for (; i < floats; ++i) flat[i] += c0[i] * w0 + c1[i] * w1;
  }
  spread_to_texels(flat, table.width, padding, row);
  if (!floor) return;
  // Where the two rows around the node differ by more than
  // SOURCE_FLOOR_RATIO, not below the smaller (see source_function_lookup).
  // Here per (nu, mu_s) texel of the rows, before the interpolation in mu_s
  // and nu that source_function_lookup's floor follows: the same wherever the
  // floor acts on all or none of the texels around the lookup.
  const vec3 *a0 = texels(1, y0), *a1 = texels(1, y1), *b0 = texels(2, y0), *b1 = texels(2, y1);
  for (int x = 0; x < table.width; ++x) {
    const vec3 bracket0 = a0[x] * (1.0f - fy) + a1[x] * fy, bracket1 = b0[x] * (1.0f - fy) + b1[x] * fy;
    const vec3 floor_value = source_floor(bracket0, bracket1);
    v4f& v = row[size_t(x)];
    for (int c = 0; c < 3; ++c) v[c] = std::max(v[c], floor_value[c]);
  }
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
  // Of the multiple scattering's rays in thick atmospheres: the radius rows
  // the source function is read from at each node (source_function_lookup:
  // rows z0 - 1 .. z0 + 2 with these weights; z0 = -1 when not used).
  std::array<int, MAX_RAY_NODES> source_row{};
  std::array<vec4, MAX_RAY_NODES> source_weight{};
};

// `source`: the weights of source_integration_nodes (the multiple
// scattering, which integrates the source function), else those of
// ray_integration_nodes (the single scattering).
// `row_coordinate`: source_row_coordinate() of every radius row, for the
// source rows of thick atmospheres (empty: not wanted).
ViewRay make_view_ray(const AtmosphereParams& a, int y, int z, int intervals, bool source,
                      const std::vector<float>& row_coordinate = {}) {
  ViewRay ray;
  float mu_s, nu;
  r_mu_mu_s_nu_from_scattering_texel(a, vec3(0.0f, float(y), float(z)), ray.r, ray.mu, mu_s, nu, ray.ground);
  ray.nodes = source ? source_integration_nodes(a, ray.r, ray.mu, ray.ground, intervals)
                     : ray_integration_nodes(a, ray.r, ray.mu, ray.ground, intervals);
  const int rows = a.scattering_r_size;
  for (int i = 0; i < ray.nodes.count; ++i) {
    const float r_t = clamp_radius(a, radius_along_ray(ray.r, ray.mu, ray.nodes.t[i]));
    ray.r_t[size_t(i)] = r_t;
    ray.mu_t[size_t(i)] = clamp_cosine(mu_along_ray(ray.r, ray.mu, ray.nodes.t[i], r_t));
    ray.source_row[size_t(i)] = -1;
    if (row_coordinate.empty()) continue;
    // As source_function_lookup() does.
    int z0;
    float f;
    source_row_tap(a, scattering_u_r(a, r_t), z0, f);
    if (z0 < 0 || z0 >= rows - 1) continue;
    auto c = [&](int row) { return row >= 0 && row < rows ? row_coordinate[size_t(row)] : 0.0f; };
    ray.source_row[size_t(i)] = z0;
    ray.source_weight[size_t(i)] =
        source_row_weights(a, z0, f, source_r_coordinate(a, r_t), c(z0 - 1), c(z0), c(z0 + 1), c(z0 + 2));
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

// compute_indirect_irradiance() of functions.glsl for every texel. Its
// directions are rings of constant mu_w: the (mu, r) part of their table
// lookups is the same for every azimuth and every mu_s of a radius, and is
// done once per ring (a row of (nu, mu_s) texels); the mu_s coordinate is the
// same for all directions of a texel.
Table2D compute_indirect_irradiance_table(const AtmosphereParams& a, const Table2D& /*transmittance*/,
                                          const Table3D& single_rayleigh, const Table3D& single_aerosol,
                                          const Table3D& multiple_scattering, int order) {
  constexpr int kThetaSamples = kIrradianceThetaSamples;
  Table2D table(a.irradiance_mu_s_size, a.irradiance_r_size);
  const int mu_s_size = a.scattering_mu_s_size;
  const MuSCoordinate texel_of_mu_s(a, float(mu_s_size - 1));
  const float d_theta = PI / 2.0f / float(kThetaSamples);
  const float d_phi = PI / float(kThetaSamples);
  tbb::parallel_for(0, table.height, [&](int y) ATMOS_HOT_KERNEL {
    std::vector<float> mu_s(static_cast<size_t>(table.width)), coordinate(static_cast<size_t>(table.width));
    const float r = irradiance_r_from_v(a, (float(y) + 0.5f) / float(table.height));
    for (int x = 0; x < table.width; ++x) {
      mu_s[size_t(x)] = irradiance_mu_s_from_u(a, (float(x) + 0.5f) / float(table.width));
      coordinate[size_t(x)] = texel_of_mu_s(mu_s[size_t(x)]);
    }
    std::vector<v4f> first, second, sum(static_cast<size_t>(table.width), splat(0.0f));
    for (int l = 0; l < kThetaSamples; ++l) {
      // The ring of compute_indirect_irradiance(): its rays never hit the ground.
      const float theta = (float(l) + 0.5f) * d_theta;
      const float mu_w = cos(theta);
      const float weight = d_theta * d_phi * sin(theta) * mu_w;
      const float u_mu = scattering_u_mu(a, r, mu_w, false), u_r = scattering_u_r(a, r);
      interpolate_mu_r_row(order == 1 ? single_rayleigh : multiple_scattering, u_mu, u_r, mu_s_size + 1, first);
      if (order == 1) interpolate_mu_r_row(single_aerosol, u_mu, u_r, mu_s_size + 1, second);
      for (int m = 0; m < 2 * kThetaSamples; ++m) {
        const vec3 w = direction_from_mu_phi(mu_w, (float(m) + 0.5f) * d_phi);
        for (int x = 0; x < table.width; ++x) {
          const vec3 sun = vec3(safe_sqrt(1.0f - mu_s[size_t(x)] * mu_s[size_t(x)]), 0.0f, mu_s[size_t(x)]);
          const float nu_w = clamp_cosine(dot(w, sun));
          // scattering_lookup() in the row: the two nu tiles around nu_w.
          float tile, lerp;
          scattering_nu_tiles(a, nu_w, tile, lerp);
          const int k = int(coordinate[size_t(x)]);
          const float f = coordinate[size_t(x)] - float(k);
          const size_t lower = size_t(int(tile) * mu_s_size + k), upper = lower + size_t(mu_s_size);
          auto lookup = [&](const std::vector<v4f>& row) {
            return (row[lower] * splat(1.0f - f) + row[lower + 1] * splat(f)) * splat(1.0f - lerp) +
                   (row[upper] * splat(1.0f - f) + row[upper + 1] * splat(f)) * splat(lerp);
          };
          const vec3 radiance = order == 1 ? phase_weighted_scattering(a, to_vec3(lookup(first)), to_vec3(lookup(second)), nu_w)
                                           : to_vec3(lookup(first));
          sum[size_t(x)] += to_v4f(radiance) * splat(weight);
        }
      }
    }
    for (int x = 0; x < table.width; ++x) table.at(x, y) = to_vec3(sum[size_t(x)]);
  });
  return table;
}

// compute_single_scattering() of functions.glsl for every texel, with the view
// ray's nodes computed once per (mu, r) row; with `scaled`, also the scaled
// medium's (see steps.hpp).
namespace {

void single_scattering_tables(const AtmosphereParams& a, const Table2D& transmittance, Table3D& rayleigh,
                              Table3D& aerosol, const StepProgress& progress, const AtmosphereParams* scaled,
                              Table3D* scaled_rayleigh, Table3D* scaled_aerosol) {
  const int width = a.scattering_nu_size * a.scattering_mu_s_size;
  rayleigh = Table3D(width, a.scattering_mu_size, a.scattering_r_size);
  aerosol = Table3D(width, a.scattering_mu_size, a.scattering_r_size);
  if (scaled) {
    *scaled_rayleigh = Table3D(width, a.scattering_mu_size, a.scattering_r_size);
    *scaled_aerosol = Table3D(width, a.scattering_mu_size, a.scattering_r_size);
  }
  const sampler2D t = transmittance.sampler();
  const TexelColumns columns = make_texel_columns(a);
  for_each_view_ray(a, progress, [&](int y, int z) ATMOS_HOT_KERNEL {
    const ViewRay ray = make_view_ray(a, y, z, SINGLE_SCATTERING_INTERVALS, false);
    // Node by node (outer loop), so that the transmittance row of the node
    // stays in the L1 cache while all texels of the view ray use it.
    std::vector<float> nu(static_cast<size_t>(width));
    for (int x = 0; x < width; ++x)
      nu[size_t(x)] = clamp_nu(ray.mu, columns.mu_s[size_t(x)], columns.tile_nu[size_t(x)]);
    std::vector<vec3> sum_rayleigh(size_t(width), vec3(0.0f)), sum_aerosol(size_t(width), vec3(0.0f));
    std::vector<vec3> scaled_sum_rayleigh, scaled_sum_aerosol;
    if (scaled) {
      scaled_sum_rayleigh.assign(size_t(width), vec3(0.0f));
      scaled_sum_aerosol.assign(size_t(width), vec3(0.0f));
    }
    SunTransmittanceAtRadius sun(a, t, ray.r);
    std::vector<float> mu_s_t(static_cast<size_t>(width));
    std::vector<vec3> sun_transmittance(static_cast<size_t>(width));
    // The optical depth the scaled medium lacks from the start of the ray to
    // the node (f beta_A): its transmittance is the true one times exp(of it).
    vec3 missing_depth(0.0f);
    for (int i = 0; i < ray.nodes.count; ++i) {
      vec3 beta_rayleigh, beta_aerosol, extinction;
      medium_at(a, ray.r_t[size_t(i)], beta_rayleigh, beta_aerosol, extinction);
      const vec3 weight = ray.nodes.weight[i];
      vec3 scaled_beta_rayleigh(0.0f), scaled_beta_aerosol(0.0f);
      if (scaled) {
        if (i > 0) {
          const float t0 = ray.nodes.t[i - 1], t1 = ray.nodes.t[i];
          missing_depth += optical_depth_along_ray(a, ray.r, ray.mu, t0, t1, 8) -
                           optical_depth_along_ray(*scaled, ray.r, ray.mu, t0, t1, 8);
        }
        vec3 scaled_extinction;
        medium_at(*scaled, ray.r_t[size_t(i)], scaled_beta_rayleigh, scaled_beta_aerosol, scaled_extinction);
        // Capped: where the true medium's weight has underflowed to 0 an
        // unbounded factor would make 0 x inf (a medium 100x Mars's dust,
        // DeltaM.DenseScaledAtmosphereStaysFinite).
        const vec3 scaled_weight = weight * exp(min(missing_depth, vec3(60.0f)));
        scaled_beta_rayleigh *= scaled_weight;
        scaled_beta_aerosol *= scaled_weight;
      }
      beta_rayleigh *= weight;
      beta_aerosol *= weight;
      sun.reset(t, ray.r_t[size_t(i)]);
      // mu_s_along_ray() as two multiply-adds.
      const float along_mu_s = ray.r / ray.r_t[size_t(i)], along_nu = ray.nodes.t[i] / ray.r_t[size_t(i)];
      for (int x = 0; x < width; ++x)
        mu_s_t[size_t(x)] = clamp_cosine(along_mu_s * columns.mu_s[size_t(x)] + along_nu * nu[size_t(x)]);
      sun.evaluate(mu_s_t.data(), width, sun_transmittance.data());
      for (int x = 0; x < width; ++x) {
        sum_rayleigh[size_t(x)] += sun_transmittance[size_t(x)] * beta_rayleigh;
        sum_aerosol[size_t(x)] += sun_transmittance[size_t(x)] * beta_aerosol;
      }
      if (scaled)
        for (int x = 0; x < width; ++x) {
          scaled_sum_rayleigh[size_t(x)] += sun_transmittance[size_t(x)] * scaled_beta_rayleigh;
          scaled_sum_aerosol[size_t(x)] += sun_transmittance[size_t(x)] * scaled_beta_aerosol;
        }
    }
    for (int x = 0; x < width; ++x) {
      rayleigh.at(x, y, z) = sum_rayleigh[size_t(x)] * a.solar_irradiance;
      aerosol.at(x, y, z) = sum_aerosol[size_t(x)] * a.solar_irradiance;
      if (scaled) {
        scaled_rayleigh->at(x, y, z) = scaled_sum_rayleigh[size_t(x)] * a.solar_irradiance;
        scaled_aerosol->at(x, y, z) = scaled_sum_aerosol[size_t(x)] * a.solar_irradiance;
      }
    }
  });
}

}  // namespace

void compute_single_scattering_tables(const AtmosphereParams& a, const Table2D& transmittance, Table3D& rayleigh,
                                      Table3D& aerosol, const StepProgress& progress) {
  single_scattering_tables(a, transmittance, rayleigh, aerosol, progress, nullptr, nullptr, nullptr);
}

void compute_single_scattering_tables(const AtmosphereParams& a, const Table2D& transmittance, Table3D& rayleigh,
                                      Table3D& aerosol, const StepProgress& progress, const AtmosphereParams& scaled,
                                      Table3D& scaled_rayleigh, Table3D& scaled_aerosol) {
  single_scattering_tables(a, transmittance, rayleigh, aerosol, progress, &scaled, &scaled_rayleigh,
                           &scaled_aerosol);
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
// is exact; the aerosol part is truncated at degree L = kDensityMaxDegree,
// where p_l = g^l for Henyey-Greenstein (0.8^28 ≈ 2e-3). The cost is one set
// of radiance samples per (r, mu_s) instead of one sphere per 4D texel.
//
// A peaked forward lobe (g ≳ 0.85: 0.93^28 = 0.13) does not fit in degree L.
// The aerosol part therefore uses the delta-M method (Wiscombe 1977, J. Atmos.
// Sci. 34, 1408): P = f δ(1 - v.w) / 2π + (1 - f) P*, where P* has
// the moments p*_l = (p_l - f) / (1 - f), l <= L, and f = p_{L+1}, i.e. the
// moments above L (a lobe's slowly decaying g^l) are replaced by the constant
// f. The δ part scatters without changing direction, so
//   ∫ P(v.w) L(w) dw = f L(v) + Σ_{l<=L} (p_l - f) L_lm Y_lm(v),
// with L(v) the incident radiance in the texel's own direction v, evaluated
// like every other radiance sample (incident_radiance()), not from the
// truncated expansion. The medium is not scaled (the usual delta-M extinction
// β_ext - f β_s): the f L(v) term keeps the forward-scattered light explicit,
// so the transmittance and single scattering tables are unchanged. f is per
// channel (the phase function may change with wavelength). Only the aerosol
// part has a δ: the Rayleigh moments vanish above degree 2 (f would be 0);
// without aerosol (beta_A = 0) the density is bit for bit the plain expansion.
//
// The sums over (l, m) are the bulk of the arithmetic; they run on 8-float
// vectors (AVX, or two SSE): for each m the coefficients of l = m..L are
// contiguous (ShLayout), the output harmonics are laid out with the view's mu fastest,
// and the azimuthal sums over the 2 (L + 1) samples use the mirror symmetry
// cos(m (π - phi)) = (-1)^m cos(m phi) to halve the products.
namespace {

constexpr int kDensityPhiSamples = kDensityMaxDegree + 2;  // over [0, π]: 2 (L + 1) over the circle
constexpr int kDensityPhiPairs = kDensityPhiSamples / 2;   // phi and π - phi
static_assert(kDensityPhiSamples % 2 == 0, "the azimuth samples pair up as phi and π - phi");
// Azimuthal orders m = 2k (even) and 2k + 1 (odd), in vectors of 4, padded
// to pairs of them (eight lanes).
constexpr int kEvenOrders = kDensityMaxDegree / 2 + 1, kOddOrders = (kDensityMaxDegree + 1) / 2;
constexpr int kEvenVectors = (kEvenOrders + 7) / 8 * 2, kOddVectors = (kOddOrders + 7) / 8 * 2;

// The output mu of a density slice in vectors of 4 (y / 4), padded to pairs
// of them (eight lanes) with harmonics 0.
inline int density_mu_vectors(int mu_size) { return (mu_size + 7) / 8 * 2; }

// Coefficient (l, m) at offset[m] + l - m; each m padded to a multiple of 8
// (one vector of eight lanes).
struct ShLayout {
  std::array<int, kDensityMaxDegree + 2> offset{};
  ShLayout() {
    for (int m = 0; m <= kDensityMaxDegree; ++m)
      offset[size_t(m) + 1] = offset[size_t(m)] + (kDensityMaxDegree - m + 8) / 8 * 8;
  }
  int size() const { return offset[kDensityMaxDegree + 1]; }
  int octets(int m) const { return (offset[size_t(m) + 1] - offset[size_t(m)]) / 8; }
};

// The part of the density's quadrature that depends on r only (and on the
// medium through the scattering coefficients): per r slice, the nodes in mu
// (below and above the horizon), the harmonics at those nodes and at the mu
// of the output texels, the scattering coefficients times the moments.
struct DensitySlice {
  float r = 0.0f;
  std::vector<double> nodes, weights;
  std::vector<v4f> node_harmonics;    // [j * sh_size / 4 + ...]: node j in ShLayout
  std::vector<float> output_mu;
  std::vector<v4f> output_harmonics;  // [(ShLayout index) * mu_vectors + y / 4][y % 4]
  std::array<std::vector<float>, 3> moment_scale;  // per channel, in ShLayout: beta_R p_R,l + beta_A (p_A,l - f)
  vec3 forward_scale{0.0f};  // beta_A f per channel: the delta-M forward peak's share of the density
};

struct DensityGeometry {
  ShLayout layout;
  std::vector<DensitySlice> slices;
  std::array<float, kDensityPhiSamples> cos_phi{};
  // Trapezoid weights of ∫_0^{2π} f(phi) cos(m phi) dphi for an even f sampled
  // on [0, π], for the first phi of each pair (phi, π - phi), m = 2k or 2k + 1
  // in lane k % 4 of vector k / 4.
  std::array<std::array<v4f, kEvenVectors>, kDensityPhiPairs> even_weight{};
  std::array<std::array<v4f, kOddVectors>, kDensityPhiPairs> odd_weight{};
  std::vector<float> tile_nu;  // the tile nu of each nu index
};

DensityGeometry make_density_geometry(const AtmosphereParams& a) {
  constexpr int L = kDensityMaxDegree;
  constexpr int kPhiIntervals = kDensityPhiSamples - 1;
  DensityGeometry g;
  const ShLayout& layout = g.layout;
  const int sh_size = layout.size();
  const int mu_size = a.scattering_mu_size;
  const int mu_vectors = density_mu_vectors(mu_size);
  const std::vector<double> rayleigh_moments =
      legendre_moments([](double x) { return double(rayleigh_phase_function(float(x))); }, L);
  // Per channel: the phase function may differ between the set's wavelengths.
  std::array<std::vector<double>, 3> aerosol_moments;
  // The delta-M forward fraction f = p_{L+1} per channel: Wiscombe's f is the
  // first moment left out of the expansion. A negative p_{L+1} (a lobe peaked
  // backwards, g < 0, whose moments alternate in sign) is not a forward peak:
  // f = 0 there leaves the plain truncation.
  vec3 forward_fraction(0.0f);
  for (int c = 0; c < 3; ++c) {
    aerosol_moments[size_t(c)] =
        legendre_moments([&](double x) { return double(aerosol_phase_function(a, float(x))[c]); }, L + 1);
    forward_fraction[c] = float(std::max(0.0, aerosol_moments[size_t(c)][size_t(L + 1)]));
  }
  for (int l = 0; l <= kPhiIntervals; ++l) g.cos_phi[size_t(l)] = float(std::cos(M_PI * l / kPhiIntervals));
  for (int l = 0; l < kDensityPhiPairs; ++l)
    for (int m = 0; m <= L; ++m) {
      const float w = float((l == 0 ? 1.0 : 2.0) * std::cos(M_PI * double(m * l) / kPhiIntervals) * M_PI / kPhiIntervals);
      if (m % 2 == 0) g.even_weight[size_t(l)][size_t(m / 2 / 4)][m / 2 % 4] = w;
      else g.odd_weight[size_t(l)][size_t(m / 2 / 4)][m / 2 % 4] = w;
    }
  for (int i = 0; i < a.scattering_nu_size; ++i)
    g.tile_nu.push_back(clamp_cosine(scattering_texel_tile_nu(a, vec3(float(i * a.scattering_mu_s_size), 0.0f, 0.0f))));

  g.slices.resize(size_t(a.scattering_r_size));
  tbb::parallel_for(0, a.scattering_r_size, [&](int z) {
    DensitySlice& slice = g.slices[size_t(z)];
    float mu_unused, mu_s_unused, nu_unused;
    bool ground_unused;
    r_mu_mu_s_nu_from_scattering_texel(a, vec3(0.0f, 0.0f, float(z)), slice.r, mu_unused, mu_s_unused, nu_unused,
                                       ground_unused);
    const double mu_h = horizon_mu(a, slice.r);
    std::vector<double> nodes_up, weights_up;
    gauss_legendre(kDensityMuNodes, -1.0, mu_h, slice.nodes, slice.weights);
    gauss_legendre(kDensityMuNodes, mu_h, 1.0, nodes_up, weights_up);
    slice.nodes.insert(slice.nodes.end(), nodes_up.begin(), nodes_up.end());
    slice.weights.insert(slice.weights.end(), weights_up.begin(), weights_up.end());
    std::array<float, kShCount> legendre;
    slice.node_harmonics.assign(slice.nodes.size() * size_t(sh_size / 4), splat(0.0f));
    for (size_t j = 0; j < slice.nodes.size(); ++j) {
      associated_legendre(slice.nodes[j], legendre);
      v4f* out = &slice.node_harmonics[j * size_t(sh_size / 4)];
      for (int m = 0; m <= L; ++m)
        for (int l = m; l <= L; ++l) {
          const int i = layout.offset[size_t(m)] + l - m;
          out[i / 4][i % 4] = legendre[size_t(sh_index(l, m))];
        }
    }
    slice.output_mu.resize(size_t(mu_size));
    slice.output_harmonics.assign(size_t(sh_size) * size_t(mu_vectors), splat(0.0f));
    for (int y = 0; y < mu_size; ++y) {
      float r_y, mu_s_y, nu_y;
      bool ground_y;
      r_mu_mu_s_nu_from_scattering_texel(a, vec3(0.0f, float(y), float(z)), r_y, slice.output_mu[size_t(y)], mu_s_y,
                                         nu_y, ground_y);
      associated_legendre(slice.output_mu[size_t(y)], legendre);
      for (int m = 0; m <= L; ++m)
        for (int l = m; l <= L; ++l)
          slice.output_harmonics[size_t(layout.offset[size_t(m)] + l - m) * size_t(mu_vectors) + size_t(y / 4)][y % 4] =
              legendre[size_t(sh_index(l, m))];
    }
    vec3 beta_rayleigh, beta_aerosol, extinction;
    medium_at(a, slice.r, beta_rayleigh, beta_aerosol, extinction);
    for (int c = 0; c < 3; ++c) {
      slice.moment_scale[size_t(c)].assign(size_t(sh_size), 0.0f);
      for (int m = 0; m <= L; ++m)
        for (int l = m; l <= L; ++l)
          slice.moment_scale[size_t(c)][size_t(layout.offset[size_t(m)] + l - m)] =
              beta_rayleigh[c] * float(rayleigh_moments[size_t(l)]) +
              beta_aerosol[c] * float(aerosol_moments[size_t(c)][size_t(l)] - double(forward_fraction[c]));
    }
    slice.forward_scale = beta_aerosol * forward_fraction;
  });
  return g;
}

}  // namespace

// What the steps of the orders share within one wavelength triple.
struct OrderGeometry {
  DensityGeometry density;
  // The view rays of the multiple scattering: their nodes depend on the
  // medium only (ray_integration_nodes() costs ~130 extinction samples per
  // ray). Row (y, z) at y + z * mu_size.
  std::vector<ViewRay> rays;
};

std::shared_ptr<const OrderGeometry> make_order_geometry(const AtmosphereParams& a) {
  auto g = std::make_shared<OrderGeometry>();
  g->density = make_density_geometry(a);
  g->rays.resize(size_t(a.scattering_mu_size) * size_t(a.scattering_r_size));
  std::vector<float> row_coordinate;
  if (a.scattering_mu_log_weight > 0.0f)
    for (int z = 0; z < a.scattering_r_size; ++z) row_coordinate.push_back(source_row_coordinate(a, z));
  tbb::parallel_for(tbb::blocked_range<int>(0, a.scattering_mu_size * a.scattering_r_size, 16),
                    [&](const tbb::blocked_range<int>& range) {
                      for (int i = range.begin(); i != range.end(); ++i)
                        g->rays[size_t(i)] = make_view_ray(a, i % a.scattering_mu_size, i / a.scattering_mu_size,
                                                           multiple_scattering_intervals(a), true, row_coordinate);
                    });
  return g;
}

Table3D compute_scattering_density_table(const AtmosphereParams& a, const Table2D& transmittance,
                                         const Table3D& single_rayleigh, const Table3D& single_aerosol,
                                         const Table3D& multiple_scattering, const Table2D& irradiance, int order,
                                         const StepProgress& progress) {
  Table3D density;
  compute_scattering_density_table(a, *make_order_geometry(a), transmittance, single_rayleigh, single_aerosol,
                                   multiple_scattering, irradiance, order, progress, density);
  return density;
}

void compute_scattering_density_table(const AtmosphereParams& a, const OrderGeometry& geometry,
                                      const Table2D& transmittance, const Table3D& single_rayleigh,
                                      const Table3D& single_aerosol, const Table3D& multiple_scattering,
                                      const Table2D& irradiance, int order, const StepProgress& progress,
                                      Table3D& density, bool clamp_ringing) {
  constexpr int L = kDensityMaxDegree;
  constexpr int kPhiIntervals = kDensityPhiSamples - 1;
  const DensityGeometry& g = geometry.density;
  const int width = a.scattering_nu_size * a.scattering_mu_s_size;
  const int mu_size = a.scattering_mu_size;
  const int mu_vectors = density_mu_vectors(mu_size);
  resize_table(density, width, mu_size, a.scattering_r_size);
  const sampler2D t = transmittance.sampler();
  const ShLayout& layout = g.layout;
  const int sh_size = layout.size();
  const auto& cos_phi = g.cos_phi;
  const auto& even_weight = g.even_weight;
  const auto& odd_weight = g.odd_weight;
  const std::vector<float>& tile_nu = g.tile_nu;
  // The ground's irradiance: the sun (order 1) or the previous order's sky.
  const SunTransmittanceAtRadius sun_at_ground(a, t, a.bottom_radius);
  std::unique_ptr<GroundIrradiance> sky_at_ground;
  if (order > 1) sky_at_ground = std::make_unique<GroundIrradiance>(a, irradiance.sampler());

  struct NodeRows {
    std::vector<v4f> first, second;  // order 1: single Rayleigh, single aerosol; else: multiple scattering
    bool ground = false;
    float ground_distance = 0.0f;
    vec3 ground_transmittance{0.0f};
  };
  // The rows of the output mu for the delta-M forward peak, their memory
  // reused from slice to slice (1 MB per slice at the default sizes).
  std::vector<NodeRows> output_rows(static_cast<size_t>(mu_size));

  for (int z = 0; z < a.scattering_r_size; ++z) {
    const DensitySlice& slice = g.slices[size_t(z)];
    const float r = slice.r;
    const std::vector<double>& nodes = slice.nodes;
    const std::vector<double>& weights = slice.weights;
    const std::vector<v4f>& node_harmonics = slice.node_harmonics;
    const std::vector<float>& output_mu = slice.output_mu;
    const std::vector<v4f>& output_harmonics = slice.output_harmonics;
    const std::array<std::vector<float>, 3>& moment_scale = slice.moment_scale;

    // incident_radiance() for all directions of node j shares the (mu, r)
    // part of its table lookups and the transmittance to the ground: do the
    // (mu, r) interpolation once, leaving rows of (nu, mu_s) texels whose
    // mu_s columns are exactly those of this step's output (NodeRows).
    auto make_rows = [&](float mu_w, NodeRows& n) {
      n.ground = ray_intersects_ground(a, r, mu_w);
      const float u_mu = scattering_u_mu(a, r, mu_w, n.ground), u_r = scattering_u_r(a, r);
      if (order == 1) {
        interpolate_mu_r_row(single_rayleigh, u_mu, u_r, 0, n.first);
        interpolate_mu_r_row(single_aerosol, u_mu, u_r, 0, n.second);
      } else {
        interpolate_mu_r_row(multiple_scattering, u_mu, u_r, 0, n.first);
      }
      if (n.ground) {
        n.ground_distance = distance_to_bottom_atmosphere_boundary(a, r, mu_w);
        n.ground_transmittance = transmittance_to_ground(a, t, r, mu_w);
      }
    };
    // incident_radiance(a, t, sr, sa, ms, e, r, mu_w, mu_s, nu_w, order) for
    // the mu_w of `n` and the mu_s of column mu_s_index, with the lookups hoisted.
    auto radiance_from_rows = [&](const NodeRows& n, int mu_s_index, float mu_s,
                                  float nu_w) __attribute__((always_inline)) {
      float tile, f;
      scattering_nu_tiles(a, nu_w, tile, f);
      const size_t x0 = size_t(int(tile) * a.scattering_mu_s_size + mu_s_index);
      const size_t x1 = size_t(std::min(int(tile) + 1, a.scattering_nu_size - 1) * a.scattering_mu_s_size + mu_s_index);
      vec3 value = to_vec3(n.first[x0] * splat(1.0f - f) + n.first[x1] * splat(f));
      if (order == 1)
        value = phase_weighted_scattering(a, value, to_vec3(n.second[x0] * splat(1.0f - f) + n.second[x1] * splat(f)),
                                          nu_w);
      if (n.ground) {
        const float mu_s_ground = mu_s_at_ground(a, r, mu_s, nu_w, n.ground_distance);
        // compute_direct_irradiance() or irradiance_lookup() at the ground.
        const vec3 ground_irradiance = order == 1 ? a.solar_irradiance * sun_at_ground(mu_s_ground) *
                                                        std::max(mu_s_ground, 0.0f)
                                                  : (*sky_at_ground)(mu_s_ground);
        value += n.ground_transmittance * ground_radiance(a, ground_irradiance);
      }
      return value;
    };
    std::vector<NodeRows> node_rows(nodes.size());
    tbb::parallel_for(size_t(0), nodes.size(), [&](size_t j) { make_rows(float(nodes[j]), node_rows[j]); });
    // The delta-M forward peak (see above) needs L(v) in each output texel's
    // own direction: the same rows, for the output mu of this slice.
    const vec3 forward_scale = slice.forward_scale;
    // The table holds the source function J / beta_ext (source_function).
    const vec3 to_source = source_function(a, r, vec3(1.0f));
    const bool forward_peak = forward_scale.x > 0.0f || forward_scale.y > 0.0f || forward_scale.z > 0.0f;
    if (forward_peak)
      tbb::parallel_for(size_t(0), output_rows.size(), [&](size_t y) { make_rows(output_mu[y], output_rows[y]); });

    tbb::parallel_for(0, a.scattering_mu_s_size, [&](int mu_s_index) ATMOS_HOT_KERNEL {
      float r_unused, mu_s, mu_unused2, nu_unused2;
      bool ground_unused2;
      r_mu_mu_s_nu_from_scattering_texel(a, vec3(float(mu_s_index), 0.0f, float(z)), r_unused, mu_unused2, mu_s,
                                         nu_unused2, ground_unused2);
      const vec3 sun(std::sqrt(std::max(0.0f, 1.0f - mu_s * mu_s)), 0.0f, mu_s);

      // L_lm per channel in ShLayout, accumulated node by node.
      std::array<std::vector<float>, 3> coefficients;
      for (auto& c : coefficients) c.assign(size_t(sh_size), 0.0f);
      std::array<std::array<float, kDensityPhiSamples>, 3> radiance{};
      for (size_t j = 0; j < nodes.size(); ++j) {
        const float mu_w = float(nodes[j]);
        const float sin_w = std::sqrt(std::max(0.0f, 1.0f - mu_w * mu_w));
        const NodeRows& n = node_rows[j];
        for (int l = 0; l <= kPhiIntervals; ++l) {
          const float nu_w = clamp_cosine(sin_w * cos_phi[size_t(l)] * sun.x + mu_w * sun.z);
          const vec3 value = radiance_from_rows(n, mu_s_index, mu_s, nu_w);
          for (int c = 0; c < 3; ++c) radiance[size_t(c)][size_t(l)] = value[c];
        }
        // ∫_0^{2π} L cos(m phi) dphi (trapezoidal rule on the symmetric
        // circle) for every m, from the sums and differences of the mirror pairs.
        const float* harmonics = reinterpret_cast<const float*>(&node_harmonics[j * size_t(sh_size / 4)]);
        const float weight = float(weights[j]);
        for (int c = 0; c < 3; ++c) {
          std::array<v8f, kEvenVectors / 2> even{};
          std::array<v8f, kOddVectors / 2> odd{};
          const std::array<float, kDensityPhiSamples>& samples = radiance[size_t(c)];
          for (int l = 0; l < kDensityPhiPairs; ++l) {
            const float sum = samples[size_t(l)] + samples[size_t(kPhiIntervals - l)];
            const float difference = samples[size_t(l)] - samples[size_t(kPhiIntervals - l)];
            const float* even_w = reinterpret_cast<const float*>(even_weight[size_t(l)].data());
            const float* odd_w = reinterpret_cast<const float*>(odd_weight[size_t(l)].data());
            for (int k = 0; k < kEvenVectors / 2; ++k) even[size_t(k)] += sum * load8(even_w + 8 * k);
            for (int k = 0; k < kOddVectors / 2; ++k) odd[size_t(k)] += difference * load8(odd_w + 8 * k);
          }
          // L_lm += w_j F_m Λ_lm(mu_j) for l = m..L.
          float* out = coefficients[size_t(c)].data();
          for (int m = 0; m <= L; ++m) {
            const v8f& orders = m % 2 == 0 ? even[size_t(m / 2 / 8)] : odd[size_t(m / 2 / 8)];
            const float fourier = orders[m / 2 % 8] * weight;
            const int begin = layout.offset[size_t(m)];
            for (int k = 0; k < layout.octets(m); ++k) {
              float* o = out + begin + 8 * k;
              store8(o, load8(o) + fourier * load8(harmonics + begin + 8 * k));
            }
          }
        }
      }

      // Scale by beta_R p_R,l + beta_A (p_A,l - f) (delta-M).
      std::array<std::vector<float>, 3> scaled;
      for (int c = 0; c < 3; ++c) {
        const std::vector<float>& coefficient = coefficients[size_t(c)];
        scaled[size_t(c)].resize(size_t(sh_size));
        for (int i = 0; i < sh_size; ++i)
          scaled[size_t(c)][size_t(i)] = coefficient[size_t(i)] * moment_scale[size_t(c)][size_t(i)];
      }
      // A_m(mu) = Σ_l L_lm p_l Λ_lm(mu) at every output mu, 8 mu at a time:
      // azimuthal[((c * (L + 1) + m) * mu_vectors + y / 4) * 4 + y % 4].
      const float* harmonics_of_mu = reinterpret_cast<const float*>(output_harmonics.data());
      std::vector<float> azimuthal(size_t(3 * (L + 1) * mu_vectors * 4), 0.0f);
      for (int m = 0; m <= L; ++m)
        for (int yv = 0; yv < mu_vectors; yv += 2) {
          v8f sum0 = splat8(0.0f), sum1 = splat8(0.0f), sum2 = splat8(0.0f);
          for (int i = layout.offset[size_t(m)]; i < layout.offset[size_t(m)] + L + 1 - m; ++i) {
            const v8f h = load8(harmonics_of_mu + (size_t(i) * size_t(mu_vectors) + size_t(yv)) * 4);
            sum0 += scaled[0][size_t(i)] * h;
            sum1 += scaled[1][size_t(i)] * h;
            sum2 += scaled[2][size_t(i)] * h;
          }
          store8(&azimuthal[size_t((0 * (L + 1) + m) * mu_vectors + yv) * 4], sum0);
          store8(&azimuthal[size_t((1 * (L + 1) + m) * mu_vectors + yv) * 4], sum1);
          store8(&azimuthal[size_t((2 * (L + 1) + m) * mu_vectors + yv) * 4], sum2);
        }

      // Evaluate at every texel of this (r, mu_s): Σ_m A_m cos(m phi) with
      // the Chebyshev recurrence for cos(m phi), phi the azimuth of the
      // texel's view from the sun's vertical plane.
      std::vector<float> cos_azimuth(static_cast<size_t>(mu_vectors * 4), 1.0f);
      std::vector<float> texel_nu(static_cast<size_t>(mu_size));  // for the delta-M forward peak
      for (int nu_index = 0; nu_index < a.scattering_nu_size; ++nu_index) {
        for (int y = 0; y < mu_size; ++y) {
          const float mu = output_mu[size_t(y)];
          const float nu = clamp_nu(mu, mu_s, tile_nu[size_t(nu_index)]);
          texel_nu[size_t(y)] = nu;
          const float spread = std::sqrt(std::max(0.0f, (1.0f - mu * mu) * (1.0f - mu_s * mu_s)));
          cos_azimuth[size_t(y)] = spread < 1e-6f ? 1.0f : clamp_cosine((nu - mu * mu_s) / spread);
        }
        const int x = nu_index * a.scattering_mu_s_size + mu_s_index;
        for (int yv = 0; yv < mu_vectors; yv += 2) {
          const v8f c = load8(&cos_azimuth[size_t(yv) * 4]);
          const v8f two_c = c + c;
          const float* a0 = &azimuthal[size_t(yv) * 4];
          const size_t channel = size_t((L + 1) * mu_vectors * 4);
          v8f c_prev = splat8(1.0f), c_m = c;
          v8f value0 = load8(a0), value1 = load8(a0 + channel), value2 = load8(a0 + 2 * channel);
          for (int m = 1; m <= L; ++m) {
            const size_t i = size_t(m * mu_vectors * 4);
            value0 += load8(a0 + i) * c_m;
            value1 += load8(a0 + channel + i) * c_m;
            value2 += load8(a0 + 2 * channel + i) * c_m;
            const v8f c_next = two_c * c_m - c_prev;
            c_prev = c_m;
            c_m = c_next;
          }
          for (int lane = 0; lane < 8 && yv * 4 + lane < mu_size; ++lane) {
            const int y = yv * 4 + lane;
            vec3 value(value0[lane], value1[lane], value2[lane]);
            // The delta-M forward peak: beta_A f L(v), v the texel's direction.
            if (forward_peak)
              value += forward_scale * radiance_from_rows(output_rows[size_t(y)], mu_s_index, mu_s, texel_nu[size_t(y)]);
            // A truncated expansion can ring slightly below zero next to sharp
            // features (not clamped for the signed fields of the tail solver).
            value *= to_source;
            density.at(x, y, z) = clamp_ringing ? max(value, vec3(0.0f)) : value;
          }
        }
      }
    });
    if (progress) progress(double(z + 1) / double(a.scattering_r_size));
  }
}

Table3D compute_multiple_scattering_table(const AtmosphereParams& a, const Table3D& density,
                                          const StepProgress& progress) {
  Table3D result;
  compute_multiple_scattering_table(a, *make_order_geometry(a), density, progress, result);
  return result;
}

// compute_multiple_scattering() of functions.glsl for every texel. For each
// node of a view ray, the (mu, r) part of the trilinear lookup of the density
// is the same for all texels of the row: it is done once, leaving a 1D row of
// (nu, mu_s) texels to interpolate per texel. Per texel and node only the
// sun's zenith cosine changes: mu_s_t = (r mu_s + t nu) / r_t is two
// multiply-adds with the node's r / r_t and t / r_t, its texel coordinate in a
// nu tile comes from a fine table (MuSCoordinate), and the lookups in the two
// nu tiles around nu share it (the tiles are mu_s_size texels apart).
void compute_multiple_scattering_table(const AtmosphereParams& a, const OrderGeometry& geometry, const Table3D& density,
                                       const StepProgress& progress, Table3D& result, bool clamp_undershoot) {
  const int width = a.scattering_nu_size * a.scattering_mu_s_size;
  const int mu_s_size = a.scattering_mu_s_size;
  resize_table(result, width, a.scattering_mu_size, a.scattering_r_size);
  const TexelColumns columns = make_texel_columns(a);
  // The texel coordinate within a nu tile, in [0, mu_s_size - 1].
  const MuSCoordinate texel_of_mu_s(a, float(mu_s_size - 1));
  // The texels in blocks of 8 (vectors of 8 lanes for the per-texel
  // coordinates); the last block is padded with columns of mu_s = nu = 1 in
  // the first nu tile, whose sums stay in `sum` (never stored).
  const int blocks = (width + 7) / 8;
  std::vector<float> column_mu_s(static_cast<size_t>(blocks * 8), 1.0f);
  std::copy(columns.mu_s.begin(), columns.mu_s.end(), column_mu_s.begin());
  for_each_view_ray(a, progress, [&](int y, int z) ATMOS_HOT_KERNEL {
    const ViewRay& ray = geometry.rays[size_t(y) + size_t(z) * size_t(a.scattering_mu_size)];
    // Per texel: nu and its tiles, as in scattering_lookup().
    std::vector<float> nu(static_cast<size_t>(blocks * 8), 1.0f), lerp(static_cast<size_t>(blocks * 8), 0.0f);
    std::vector<int> tile_start(static_cast<size_t>(blocks * 8), 0);
    for (int x = 0; x < width; ++x) {
      nu[size_t(x)] = clamp_nu(ray.mu, columns.mu_s[size_t(x)], columns.tile_nu[size_t(x)]);
      float tile;
      scattering_nu_tiles(a, nu[size_t(x)], tile, lerp[size_t(x)]);
      tile_start[size_t(x)] = int(tile) * mu_s_size;
    }
    // Node by node (outer loop): the density row of the node stays in cache.
    // The row is padded with zeros: the upper nu tile of the last tile (whose
    // weight is 0) and the texel after the last of a tile (weight 0 too).
    std::vector<v4f> row, sum(static_cast<size_t>(blocks * 8), splat(0.0f));
    for (int i = 0; i < ray.nodes.count; ++i) {
      const float r_t = ray.r_t[size_t(i)];
      const float u_mu = scattering_u_mu(a, r_t, ray.mu_t[size_t(i)], ray.ground);
      if (ray.source_row[size_t(i)] >= 0)
        interpolate_source_rows(density, u_mu, ray.source_row[size_t(i)], ray.source_weight[size_t(i)],
                                clamp_undershoot, mu_s_size + 1, row);
      else
        interpolate_mu_r_row(density, u_mu, scattering_u_r(a, r_t), mu_s_size + 1, row);
      const v4f weight = to_v4f(ray.nodes.weight[i]);
      const float along_mu_s = ray.r / r_t, along_nu = ray.nodes.t[i] / r_t;
      const v4f* values = row.data();
      for (int b = 0; b < blocks; ++b) {
        // mu_s at the node, its coordinate in a nu tile, and the bilinear
        // weights of the four texels around (mu_s, nu), eight texels at once.
        v8f mu_s_t = along_mu_s * load8(&column_mu_s[size_t(b) * 8]) + along_nu * load8(&nu[size_t(b) * 8]);
        mu_s_t = clamp8(mu_s_t, -1.0f, 1.0f);
        const v8f coordinate = texel_of_mu_s(mu_s_t);
        const v8i k = __builtin_convertvector(coordinate, v8i);
        const v8f f = coordinate - __builtin_convertvector(k, v8f), l = load8(&lerp[size_t(b) * 8]);
        const v8f w00 = (1.0f - f) * (1.0f - l), w10 = f * (1.0f - l), w01 = (1.0f - f) * l, w11 = f * l;
        for (int lane = 0; lane < 8; ++lane) {
          const size_t x = size_t(b * 8 + lane);
          const v4f* lower = values + tile_start[x] + k[lane];
          const v4f* upper = lower + mu_s_size;
          const v4f value = lower[0] * w00[lane] + lower[1] * w10[lane] + upper[0] * w01[lane] + upper[1] * w11[lane];
          sum[x] += weight * value;
        }
      }
    }
    for (int x = 0; x < width; ++x) result.at(x, y, z) = to_vec3(sum[size_t(x)]);
  });
}

}  // namespace atmos::precompute
