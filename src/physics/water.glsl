// atmos — water: the air–water interface (the exact Fresnel reflectance, the
// wind-driven slopes of Cox & Munk 1954, the sun glint and the reflected sky
// of a rough sea) and the light that leaves the water from below (the water
// column and the seabed seen through it), per working wavelength (three at a
// time, one per vec3 channel; with N working wavelengths, triple by triple:
// water_spectral_radiance below).
//
// Needs: definitions.glsl.
//
// Directions are unit vectors in any one frame: `normal` is the mean sea
// surface's upward normal (the local vertical at sea level), `upwind` a unit
// tangent of that surface along the wind, `view` points from the surface to
// the camera, `sun` and `light` from the surface to the light. Slopes are
// those of the surface height z(x, y) along the upwind (x) and crosswind (y)
// axes; a facet of slopes (s_x, s_y) has the normal (-s_x, -s_y, 1) / |.|.
//
// The radiance a renderer takes from a water surface point is the sum of
//   the sun glint       water_glint_brdf(...) * sun irradiance (normal to the sun) * dot(sun, normal),
//   the reflected sky   with q = water_sky_quadrature(...), the sum over
//                       k < WATER_SKY_SAMPLE_COUNT of
//                       water_sky_sample(q, k, direction) * sky radiance(direction),
//                       or water_sky_reflectance(..., mean_direction) * sky radiance(mean_direction),
//   the light from below water_leaving_radiance(...).

// The per-frame description of the water at three wavelengths (built on the
// CPU from physical inputs by physics/water.hpp: make_water_params).
struct WaterParams {
  vec3 refractive_index;     // of the water relative to air
  vec3 absorption;           // a, m^-1 (pure water + phytoplankton + dissolved organic matter)
  vec3 backscattering;       // b_b, m^-1 (pure water + particles)
  vec3 diffuse_reflectance;  // r_e, the flat surface's reflectance under a uniform sky
  vec2 slope_variance;       // of the slopes along the upwind and crosswind axes
};

// --- The interface -----------------------------------------------------------

// The refractive index of seawater, Quan & Fry 1995 (their empirical fit to
// the measurements of Austin & Halikas 1976; valid 400-700 nm, 0-30 °C,
// salinity 0-35 per mil; extrapolated to 300-830 nm, over which its series
// in 1/λ keeps decreasing): wavelength in nm, salinity in PSU, temperature
// in °C.
INLINE float water_refractive_index(float wavelength_nm, float salinity, float temperature) {
  float l = wavelength_nm;
  float t = temperature;
  return 1.31405f + (1.779e-4f - 1.05e-6f * t + 1.6e-8f * t * t) * salinity - 2.02e-6f * t * t +
         (15.868f + 0.01155f * salinity - 0.00423f * t) / l - 4382.0f / (l * l) + 1.1455e6f / (l * l * l);
}

// The exact reflectance of unpolarised light at a flat dielectric interface
// (Fresnel's equations; e.g. Born & Wolf 1999, §1.5.2): cos_i is the cosine
// of the angle of incidence, eta = n_t / n_i the index of the far side
// relative to that of the near side (water seen from air: n; air seen from
// water: 1 / n). With cos_t from Snell's law,
//   r_s = (cos_i - eta cos_t) / (cos_i + eta cos_t),
//   r_p = (eta cos_i - cos_t) / (eta cos_i + cos_t),   R = (r_s² + r_p²) / 2,
// and R = 1 beyond the critical angle (total internal reflection).
INLINE float fresnel_reflectance(float cos_i, float eta) {
  float c = clamp(cos_i, 0.0f, 1.0f);
  float sin_t2 = (1.0f - c * c) / (eta * eta);
  if (sin_t2 >= 1.0f) return 1.0f;
  float cos_t = sqrt(1.0f - sin_t2);
  float r_s = (c - eta * cos_t) / (c + eta * cos_t);
  float r_p = (eta * c - cos_t) / (eta * c + cos_t);
  return 0.5f * (r_s * r_s + r_p * r_p);
}

INLINE vec3 fresnel_reflectance(float cos_i, vec3 eta) {
  return vec3(fresnel_reflectance(cos_i, eta.x), fresnel_reflectance(cos_i, eta.y), fresnel_reflectance(cos_i, eta.z));
}

// The cosine, in the water, of a ray that crosses the flat surface with
// cosine mu_air in the air (Snell's law, either way).
INLINE vec3 water_refracted_cosine(float mu_air, vec3 n) {
  float m = clamp(mu_air, 0.0f, 1.0f);
  return sqrt(vec3(1.0f) - (1.0f - m * m) / (n * n));
}

// --- Wind-driven slopes --------------------------------------------------------

// The variances of the slopes along the upwind and crosswind axes of a clean
// sea surface, from the wind speed (m/s, 12.5 m above the sea), Cox & Munk
// 1954 (fits over 1-14 m/s): σ_u² = 3.16e-3 U, σ_c² = 0.003 + 1.92e-3 U.
// Their upwind intercept is 0 (± 0.004): the variance is kept above 1e-4
// (slopes of 0.01, half a degree) so that the distribution stays a function.
INLINE vec2 cox_munk_slope_variance(float wind_speed) {
  return vec2(max(3.16e-3f * wind_speed, 1e-4f), 0.003f + 1.92e-3f * wind_speed);
}

// The isotropic fit of the same data, Cox & Munk 1954: the total variance
// σ² = 0.003 + 5.12e-3 U split evenly between the two axes.
INLINE vec2 cox_munk_isotropic_slope_variance(float wind_speed) {
  float half_variance = 0.5f * (0.003f + 5.12e-3f * wind_speed);
  return vec2(half_variance, half_variance);
}

// The probability density of the slopes (per unit slope², per unit area of
// the mean surface): the Gaussian of Cox & Munk 1954 without their
// Gram-Charlier skewness and peakedness terms.
INLINE float water_slope_pdf(vec2 slope, vec2 variance) {
  vec2 v = max(variance, vec2(1e-8f));
  return exp(-0.5f * (slope.x * slope.x / v.x + slope.y * slope.y / v.y)) / (2.0f * PI * sqrt(v.x * v.y));
}

// The scaled complementary error function e^{x²} erfc(x) for x >= 0, from
// Abramowitz & Stegun 1964, eq. 7.1.26 (absolute error of erf below 1.5e-7),
// which writes erfc(x) as this polynomial in t = 1 / (1 + p x) times e^{-x²}.
INLINE float water_scaled_erfc(float x) {
  float t = 1.0f / (1.0f + 0.3275911f * x);
  return t * (0.254829592f + t * (-0.284496736f + t * (1.421413741f + t * (-1.453152027f + t * 1.061405429f))));
}

// The variance of the slopes along the azimuth of `direction` (the slope in
// the direction of azimuth φ from upwind is s_x cos φ + s_y sin φ).
INLINE float water_directional_slope_variance(vec3 normal, vec3 upwind, vec2 variance, vec3 direction) {
  vec3 crosswind = cross(normal, upwind);
  float x = dot(direction, upwind);
  float y = dot(direction, crosswind);
  float r2 = x * x + y * y;
  if (r2 <= 0.0f) return 0.5f * (variance.x + variance.y);
  return (variance.x * x * x + variance.y * y * y) / r2;
}

// Smith's masking function's Λ for Gaussian slopes of variance `variance`
// along the direction's azimuth, seen at cosine mu from the mean normal
// (Smith 1967): Λ = (1 / cot θ) ∫_{cot θ}^∞ (q - cot θ) p(q) dq, which for a
// Gaussian p is (e^{-a²} / (a √π) - erfc(a)) / 2 with a = cot θ / (√2 σ).
INLINE float water_smith_lambda(float mu, float variance) {
  if (variance <= 0.0f || mu >= 1.0f) return 0.0f;
  float c = max(mu, 1e-4f);
  float a = c / sqrt((1.0f - c * c) * 2.0f * variance);
  // erfc(a) = e^{-a²} water_scaled_erfc(a): the difference is formed before
  // the exponential, which keeps its relative accuracy where both terms are small.
  return max(0.0f, 0.5f * exp(-a * a) * (1.0f / (a * sqrt(PI)) - water_scaled_erfc(a)));
}

// The height-correlated form of Smith's masking-shadowing function,
// G₂ = 1 / (1 + Λ(view) + Λ(light)) (Heitz 2014): the fraction of
// facets that both the viewer and the light see.
INLINE float water_masking_shadowing(vec3 normal, vec3 upwind, vec2 variance, vec3 view, vec3 light) {
  float lambda_v = water_smith_lambda(dot(view, normal), water_directional_slope_variance(normal, upwind, variance, view));
  float lambda_l = water_smith_lambda(dot(light, normal), water_directional_slope_variance(normal, upwind, variance, light));
  return 1.0f / (1.0f + lambda_v + lambda_l);
}

// --- The sun glint -------------------------------------------------------------

// The BRDF of the rough surface for light from `light` seen from `view`: the
// microfacet form of a specular facet distribution (Torrance & Sparrow 1967;
// Walter et al. 2007) with the facets of Cox & Munk 1954,
//   f = F(view · h) D(h) G₂ / (4 μ_v μ_l),   D(h) = p(s) / μ_h⁴,
// h the half vector, s = -(h_x, h_y) / μ_h the facet's slopes (the slope
// density p per unit slope² becomes the density of normals per unit solid
// angle and unit area of the mean surface by dω_h = μ_h³ d²s and the facets'
// area 1 / μ_h per unit mean area). The sun's radiance reflected to `view` is
// f E_sun μ_s: the solar disc (0.27° in radius) is narrower than the spread
// of the mirrored directions (twice the facets' tilt: 1.1° for calm water
// with the upwind floor of cox_munk_slope_variance, 14° at 5 m/s), so the
// glint is not convolved with it.
// The glint's factors but for the Fresnel reflectance: p(s) G₂ / (4 μ_v μ_l μ_h⁴)
// (0 for a view or light below the surface), and in `view_half_cosine` the
// cosine v·h at which F is taken; water_glint_brdf is their product with F
// at the water's three wavelengths, water_spectral_radiance with F at every
// working wavelength of the atmosphere.
INLINE float water_glint_geometry(vec2 slope_variance, vec3 normal, vec3 upwind, vec3 view, vec3 light,
                                  OUT(float) view_half_cosine) {
  view_half_cosine = 1.0f;
  float mu_v = dot(view, normal);
  float mu_l = dot(light, normal);
  if (mu_v <= 0.0f || mu_l <= 0.0f) return 0.0f;
  vec3 h = normalize(view + light);
  float mu_h = dot(h, normal);
  vec3 crosswind = cross(normal, upwind);
  vec2 slope = -vec2(dot(h, upwind), dot(h, crosswind)) / mu_h;
  float density = water_slope_pdf(slope, slope_variance) / (mu_h * mu_h * mu_h * mu_h);
  float g = water_masking_shadowing(normal, upwind, slope_variance, view, light);
  view_half_cosine = dot(view, h);
  return density * g / (4.0f * mu_v * mu_l);
}

INLINE vec3 water_glint_brdf(IN(WaterParams) water, vec3 normal, vec3 upwind, vec3 view, vec3 light) {
  float view_half_cosine;
  float geometry = water_glint_geometry(water.slope_variance, normal, upwind, view, light, view_half_cosine);
  return fresnel_reflectance(view_half_cosine, water.refractive_index) * geometry;
}

// --- The reflected sky ---------------------------------------------------------
//
// The sky radiance reflected to `view` is ∫ f(view, l) L(l) μ_l dω_l over
// the sky. With l the mirror image of `view` about each facet
// (dω_l = 4 (view · h) dω_h) and the slopes as variable,
//   L_r = ∫ p(s) F(view · h) G₂ (view · h) / (μ_v μ_h) L(l) d²s,
// over the facets that face the viewer and reflect it into the sky (the
// others' share is what G₂ and the surface itself hide). The factor
// (view · h) / (μ_v μ_h) weights each facet by its area projected towards
// the viewer; its mean over the slopes is 1.
//
// The quadrature. In the frame of the view's azimuth (`along` it, `across`
// it) the slopes are Gaussian with the rotated covariance (v_a, c_ab, v_b);
// with two standard normal variables, s_a = √v_a z_a and
// s_b = (c_ab / √v_a) z_a + √(v_b - c_ab² / v_a) z_b (Cholesky). A facet
// tilted away from the viewer by more than (90° - θ_v) / 2, that is
// s_a > s* = tan(45° - θ_v / 2) = μ_v / (1 + sin θ_v), mirrors the view below
// the horizon: the integrand drops to 0 there (G₂ -> 0 on the way), a kink
// that a Gauss-Hermite rule over all slopes misses by 3-20 % from 60° on. The
// z_a axis is therefore integrated by an 8-point Gauss-Legendre rule over
// [-4.5, min(s* / √v_a, 4.5)] with the Gaussian density as a factor, its
// weights scaled so that they sum to the Gaussian's mass Φ(upper end) (which
// gives the rule's small error on the bell and the 3e-6 beyond -4.5 to the
// nodes); z_b by the two-point Gauss-Hermite rule (z_b = ±1, weights ½,
// exact for cubics). 16 nodes: against a fine grid over the slopes, within
// 0.1 % up to 10 m/s and 0.7 % up to 25 m/s at all view angles, 2 % at 40 m/s.
#define WATER_SKY_SAMPLE_COUNT 16
#define WATER_SKY_Z_LIMIT 4.5f

// The 8-point Gauss-Legendre rule on [-1, 1] (Abramowitz & Stegun 1964,
// Table 25.4): node i (ascending) and its weight.
INLINE float water_legendre_node(int i) {
  int m = i < 4 ? 3 - i : i - 4;
  float x = m == 0 ? 0.183434642495649805f
                   : (m == 1 ? 0.525532409916328986f : (m == 2 ? 0.796666477413626740f : 0.960289856497536232f));
  return i < 4 ? -x : x;
}

INLINE float water_legendre_weight(int i) {
  int m = i < 4 ? 3 - i : i - 4;
  return m == 0 ? 0.362683783378361983f
                : (m == 1 ? 0.313706645877887287f : (m == 2 ? 0.222381034453374471f : 0.101228536290376259f));
}

// What the nodes of one view share: the frame, the slopes' transform, the
// interval of z_a and the scale of the weights.
struct WaterSkyQuadrature {
  vec3 normal;
  vec3 upwind;
  vec3 view;
  vec3 along;
  vec3 across;
  vec3 refractive_index;
  vec2 slope_variance;
  float mu_v;
  float z_mid;         // centre and half width of the z_a interval
  float z_half;
  float sigma_along;   // √v_a
  float coupling;      // c_ab / √v_a
  float sigma_across;  // √(v_b - c_ab² / v_a)
  float weight_scale;  // Φ(upper end) / Σ_i w_i φ(z_i)
};

INLINE float water_standard_normal_density(float z) { return exp(-0.5f * z * z) * 0.398942280401432678f; }

INLINE WaterSkyQuadrature water_sky_quadrature(IN(WaterParams) water, vec3 normal, vec3 upwind, vec3 view) {
  WaterSkyQuadrature q;
  q.normal = normal;
  q.upwind = upwind;
  q.view = view;
  q.refractive_index = water.refractive_index;
  q.slope_variance = water.slope_variance;
  q.mu_v = dot(view, normal);
  vec3 tangent = view - q.mu_v * normal;
  float tangent_length = length(tangent);
  q.along = tangent_length > 1e-6f ? tangent / tangent_length : upwind;
  q.across = cross(normal, q.along);
  vec3 crosswind = cross(normal, upwind);
  vec2 a = vec2(dot(q.along, upwind), dot(q.along, crosswind));
  vec2 b = vec2(dot(q.across, upwind), dot(q.across, crosswind));
  vec2 v = water.slope_variance;
  float v_a = max(v.x * a.x * a.x + v.y * a.y * a.y, 1e-12f);
  float v_b = v.x * b.x * b.x + v.y * b.y * b.y;
  float c_ab = v.x * a.x * b.x + v.y * a.y * b.y;
  q.sigma_along = sqrt(v_a);
  q.coupling = c_ab / q.sigma_along;
  q.sigma_across = sqrt(max(v_b - c_ab * c_ab / v_a, 0.0f));
  float mu = clamp(q.mu_v, 1e-6f, 1.0f);
  float s_max = mu / (1.0f + sqrt(1.0f - mu * mu));
  float upper = min(s_max / q.sigma_along, WATER_SKY_Z_LIMIT);
  q.z_mid = 0.5f * (upper - WATER_SKY_Z_LIMIT);
  q.z_half = 0.5f * (upper + WATER_SKY_Z_LIMIT);
  float sum = 0.0f;
  for (int i = 0; i < 8; ++i) {
    sum += water_legendre_weight(i) * water_standard_normal_density(q.z_mid + q.z_half * water_legendre_node(i));
  }
  // Φ(upper) = 1 - erfc(upper / √2) / 2, upper >= 0.
  float x = upper * 0.707106781186547524f;
  float mass = 1.0f - 0.5f * water_scaled_erfc(x) * exp(-x * x);
  q.weight_scale = mass / sum;
  return q;
}

// Node k (0 <= k < WATER_SKY_SAMPLE_COUNT) of the reflected sky: the
// direction of the sky it reflects and its weight per channel, so that
// Σ_k weight_k L_sky(direction_k) is the sky radiance the surface reflects
// to the quadrature's view. Nodes that face away or reflect below the
// horizon have weight 0 (their direction is the mirror direction about the
// mean normal).
INLINE vec3 water_sky_sample(IN(WaterSkyQuadrature) q, int k, OUT(vec3) direction) {
  int i = k / 2;
  float z_a = q.z_mid + q.z_half * water_legendre_node(i);
  float z_b = (k - 2 * i) == 0 ? -1.0f : 1.0f;
  float s_a = q.sigma_along * z_a;
  float s_b = q.coupling * z_a + q.sigma_across * z_b;
  vec3 h = normalize(q.normal - s_a * q.along - s_b * q.across);
  float v_h = dot(q.view, h);
  vec3 l = 2.0f * v_h * h - q.view;
  float mu_l = dot(l, q.normal);
  direction = 2.0f * q.mu_v * q.normal - q.view;
  if (q.mu_v <= 0.0f || v_h <= 0.0f || mu_l <= 0.0f) return vec3(0.0f);
  direction = l;
  float g = water_masking_shadowing(q.normal, q.upwind, q.slope_variance, q.view, l);
  float weight = q.weight_scale * water_legendre_weight(i) * water_standard_normal_density(z_a) * 0.5f * g * v_h /
                 (q.mu_v * dot(h, q.normal));
  return fresnel_reflectance(v_h, q.refractive_index) * weight;
}

// The cheap path: the reflectance of the rough surface under a uniform sky
// (its directional-hemispherical reflectance, Σ_k weight_k), and the mean of
// the reflected directions weighted by the channels' mean weight, in which a
// single sky lookup stands for the sum.
INLINE vec3 water_sky_reflectance(IN(WaterParams) water, vec3 normal, vec3 upwind, vec3 view,
                                  OUT(vec3) mean_direction) {
  WaterSkyQuadrature q = water_sky_quadrature(water, normal, upwind, view);
  vec3 reflectance = vec3(0.0f);
  vec3 sum = vec3(0.0f);
  for (int k = 0; k < WATER_SKY_SAMPLE_COUNT; ++k) {
    vec3 direction;
    vec3 weight = water_sky_sample(q, k, direction);
    reflectance += weight;
    sum += direction * ((weight.x + weight.y + weight.z) / 3.0f);
  }
  float length_sum = length(sum);
  mean_direction = length_sum > 0.0f ? sum / length_sum : 2.0f * dot(view, normal) * normal - view;
  return reflectance;
}

// --- Below the surface ---------------------------------------------------------
//
// The water column and the seabed, in the semi-analytical shallow-water model
// of Lee et al. 1998 and 1999: with κ = a + b_b and
// u = b_b / κ, the radiance just below the surface over the downwelling
// irradiance there is
//   r_rs = r_rs^dp [1 - e^{-(K_d + K_u^C) H}] + (ρ_b / π) e^{-(K_d + K_u^B) H},
//   r_rs^dp = (0.084 + 0.170 u) u                       (the deep column; Gordon et al. 1988's form),
//   K_d = κ / μ_d,  K_u^C = κ D_u^C / μ_u,  K_u^B = κ D_u^B / μ_u,
//   D_u^C = 1.03 √(1 + 2.4 u),  D_u^B = 1.04 √(1 + 5.4 u),
// μ_d and μ_u the cosines in the water of the light going down and of the
// view ray, H the depth of the seabed and ρ_b its (Lambertian) albedo. The
// seabed's light is attenuated on the way down and up by e^{-(K_d + K_u^B) H},
// the two-flow law of Maritorena, Morel & Gentili 1994 (their
// R(H) = R_∞ + (A - R_∞) e^{-2 K H}) with diffuse attenuations for each way.
// Deep water keeps r_rs^dp, of the colour of b_b / (a + b_b): blue in clear
// water, where a grows towards the red; shallow water shows the seabed.

// The depths beyond which nothing changes in float (e^{-κ H} < 1e-30 for the
// clearest water's κ > 0.005 m^-1 needs H ~ 1.4e4 m): deeper is the same.
#define WATER_DEPTH_LIMIT 1.0e4f

// The seabed's two-way attenuation e^{-(K_d + K_u^B) H} through a depth H (m)
// of water, for light going down at cosine mu_down (in the water) and up at
// cosine mu_up.
INLINE vec3 water_seabed_transmittance(IN(WaterParams) water, vec3 mu_down, vec3 mu_up, float depth) {
  vec3 kappa = water.absorption + water.backscattering;
  vec3 u = water.backscattering / kappa;
  vec3 d_bottom = 1.04f * sqrt(1.0f + 5.4f * u);
  float h = clamp(depth, 0.0f, WATER_DEPTH_LIMIT);
  return exp(-kappa * (1.0f / mu_down + d_bottom / mu_up) * h);
}

// r_rs just below the surface (sr^-1), Lee et al. 1999, for light going down
// at cosine mu_down and the view ray at cosine mu_up (both in the water), a
// seabed of albedo seabed_albedo at depth `depth` (m; negative is 0).
INLINE vec3 water_subsurface_reflectance(IN(WaterParams) water, vec3 mu_down, vec3 mu_up, float depth,
                                         vec3 seabed_albedo) {
  vec3 kappa = water.absorption + water.backscattering;
  vec3 u = water.backscattering / kappa;
  vec3 deep = (0.084f + 0.170f * u) * u;
  vec3 d_column = 1.03f * sqrt(1.0f + 2.4f * u);
  float h = clamp(depth, 0.0f, WATER_DEPTH_LIMIT);
  vec3 column = deep * (1.0f - exp(-kappa * (1.0f / mu_down + d_column / mu_up) * h));
  return column + seabed_albedo * (1.0f / PI) * water_seabed_transmittance(water, mu_down, mu_up, depth);
}

// The mean cosine, in the water, of the light of a uniform sky transmitted by
// the flat surface: the refracted directions fill the cone of the critical
// angle θ_c (sin θ_c = 1 / n) with about uniform radiance (the transmittance
// varies by a few per cent up to grazing incidence), so
// μ̄ = ∫ cos sin dθ / ∫ sin dθ over [0, θ_c] = (1 / (2 n²)) / (1 - √(1 - 1 / n²)).
INLINE vec3 water_diffuse_mean_cosine(vec3 n) {
  vec3 inv_n2 = 1.0f / (n * n);
  return 0.5f * inv_n2 / (1.0f - sqrt(1.0f - inv_n2));
}

// The radiance leaving the water towards `view` (above the surface), from the
// sun (sun_irradiance: on a plane normal to the sun, at the surface) and the
// sky (sky_irradiance: on the horizontal surface), over a seabed of albedo
// seabed_albedo at depth `depth` (m). The irradiance that enters the water is
// E_d = E_sun μ_s (1 - F(μ_s)) + E_sky (1 - r_e); the water sends back
// L_u = r_rs E_d with r_rs for each light's cosine in the water; light that
// goes up is reflected down again by the surface from below with the
// diffuse internal reflectance r_i = 1 - (1 - r_e) / n² (the
// reciprocity of the flat interface under diffuse light), which multiplies
// L_u by 1 / (1 - r_i π r_rs) (E_u = π L_u for an isotropic upwelling
// field); the radiance crosses the surface with the transmittance 1 - F(μ_v)
// and the n² law of radiance, L_w = L_u (1 - F(μ_v)) / n² (Mobley 1994).
// These are the factors 0.52 and 1.5-1.7 that Lee et al. 1999
// and 2002 fit for R_rs = 0.52 r_rs / (1 - 1.7 r_rs).
INLINE vec3 water_leaving_radiance(IN(WaterParams) water, vec3 normal, vec3 view, vec3 sun, vec3 sun_irradiance,
                                   vec3 sky_irradiance, float depth, vec3 seabed_albedo) {
  vec3 n = water.refractive_index;
  float mu_s = max(dot(sun, normal), 0.0f);
  float mu_v = max(dot(view, normal), 0.0f);
  vec3 e_sun = sun_irradiance * mu_s * (1.0f - fresnel_reflectance(mu_s, n));
  vec3 e_sky = sky_irradiance * (1.0f - water.diffuse_reflectance);
  vec3 mu_up = water_refracted_cosine(mu_v, n);
  vec3 r_sun = water_subsurface_reflectance(water, water_refracted_cosine(mu_s, n), mu_up, depth, seabed_albedo);
  vec3 r_sky = water_subsurface_reflectance(water, water_diffuse_mean_cosine(n), mu_up, depth, seabed_albedo);
  vec3 e_d = e_sun + e_sky;
  vec3 upwelling = e_sun * r_sun + e_sky * r_sky;
  vec3 r_mean = upwelling / max(e_d, vec3(1e-30f));
  vec3 internal = 1.0f - (1.0f - water.diffuse_reflectance) / (n * n);
  upwelling = upwelling / (1.0f - internal * PI * r_mean);
  return upwelling * (1.0f - fresnel_reflectance(mu_v, n)) / (n * n);
}

// --- At the atmosphere's working wavelengths -----------------------------------
//
// The atmosphere works at N wavelengths in triples (definitions.glsl,
// SpectralSets) and converts each triple's radiance to the tables' channels
// with its matrix `to_channels` (the identity with three wavelengths, a
// share of linear sRGB / 683 otherwise; parameters.hpp, set_to_channels);
// the renderer then takes the channels to colour with one matrix
// (radiance_to_srgb). The water does the same: its optics at every working
// wavelength, triple by triple, its radiance summed into the channels
// through the same matrices.
//
// The light the water receives is known per wavelength where the tables
// keep it so: the sun's irradiance (the solar spectrum times the
// transmittance of triple k's tile, the caller's `sun_irradiance[k]`). The
// sky's irradiance is kept in the channels only; at wavelength λ it is taken
// as the solar spectrum above the atmosphere times the sky-to-sun ratio of
// the channels, interpolated linearly in ln λ between the channels'
// wavelengths (ln E_sky(λ) / E_0(λ) = Σ_c w_c(λ) ln (E_sky,c / E_0,c), a
// power law in λ between them, as Rayleigh's λ⁻⁴ sky is): `from_channels`
// holds those weights, the identity with three wavelengths, where the
// channels are the wavelengths and the sky's light is exact. The seabed's
// albedo, given per channel, is interpolated with the same weights.
// The loops over the triples run to WATER_SET_COUNT(water): its `count` by
// default; a shader whose count is a constant defines it as that constant
// (the sea's: SPECTRAL_SET_CAPACITY, the pass's count), which lets the
// compiler unroll them and index the arrays with constants.
#ifndef WATER_SET_COUNT
#define WATER_SET_COUNT(w) ((w).count)
#endif
struct WaterSpectrum {
  int count;                                      // triples of working wavelengths
  WaterParams set[SPECTRAL_SET_CAPACITY];         // the water at triple k's wavelengths
  vec3 solar_irradiance[SPECTRAL_SET_CAPACITY];   // E_0 above the atmosphere at them (the tables' units)
  mat3 to_channels[SPECTRAL_SET_CAPACITY];        // triple k's radiance -> the tables' channels
  mat3 from_channels[SPECTRAL_SET_CAPACITY];      // channel values -> triple k's wavelengths (weights w_c(λ))
};

// The sun's glint in the tables' channels, summed over the working
// wavelengths: per triple k, F(v·h, n_k) g E_sun,k, and Σ_k to_channels[k]
// of it. `glint_factor` g is water_glint_geometry's factor times the
// facet's cosine to the sun, `view_half_cosine` its v·h; `sun_irradiance[k]`
// the sun's irradiance normal to it at triple k's wavelengths.
INLINE vec3 water_spectral_glint(IN(WaterSpectrum) water, vec3 sun_irradiance[SPECTRAL_SET_CAPACITY],
                                 float glint_factor, float view_half_cosine) {
  vec3 glint = vec3(0.0f);
  for (int k = 0; k < WATER_SET_COUNT(water); ++k)
    glint += water.to_channels[k] *
             (fresnel_reflectance(view_half_cosine, water.set[k].refractive_index) * glint_factor * sun_irradiance[k]);
  return glint;
}

// The sun's glint (water_spectral_glint) and (returned) the light leaving
// the water, in the tables' channels, summed over the working wavelengths:
// per triple k, below_k = water_leaving_radiance(water_k, E_sun,k, E_sky,k),
// and Σ_k to_channels[k] below_k. `sky_irradiance` is the sky's irradiance
// on the horizontal and `seabed_albedo` the seabed's, in the channels.
INLINE vec3 water_spectral_radiance(IN(WaterSpectrum) water, vec3 sun_irradiance[SPECTRAL_SET_CAPACITY],
                                    vec3 sky_irradiance, float glint_factor, float view_half_cosine, vec3 normal,
                                    vec3 view, vec3 sun, float depth, vec3 seabed_albedo, OUT(vec3) glint) {
  vec3 solar = vec3(0.0f);
  for (int k = 0; k < WATER_SET_COUNT(water); ++k) solar += water.to_channels[k] * water.solar_irradiance[k];
  vec3 sky_ratio = log(max(sky_irradiance, vec3(1e-30f)) / max(solar, vec3(1e-30f)));
  vec3 below = vec3(0.0f);
  for (int k = 0; k < WATER_SET_COUNT(water); ++k) {
    vec3 sky_k = water.solar_irradiance[k] * exp(water.from_channels[k] * sky_ratio);
    vec3 albedo_k = clamp(water.from_channels[k] * seabed_albedo, vec3(0.0f), vec3(1.0f));
    below += water.to_channels[k] *
             water_leaving_radiance(water.set[k], normal, view, sun, sun_irradiance[k], sky_k, depth, albedo_k);
  }
  glint = water_spectral_glint(water, sun_irradiance, glint_factor, view_half_cosine);
  return below;
}
