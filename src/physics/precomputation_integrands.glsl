// atmos — what the precomputation tabulates, order by order: single
// scattering, the scattering density of each order (as a source function)
// and how it is read between the tables' radius rows, multiple scattering,
// and the direct and indirect irradiance of the ground.
//
// Needs: ray_integration.glsl (and the parts it needs).
//
// The model is that of Bruneton & Neyret 2008 (as set out in Collienne 2013,
// §3) with multiple scattering by successive orders (Elek & Kmoch 2010,
// §4.2): the light of order n, scattered once more at every point
// (compute_scattering_density) and carried along the view rays
// (compute_multiple_scattering), is order n + 1; the ground reflects the
// irradiance of order n into order n + 1 (incident_radiance).

// Single scattering of the ray (r, mu), up to the atmosphere's boundary,
// with the sun at (mu_s, nu), without its phase function (applied per pixel
// so that the aerosol halo stays sharp): Collienne 2013, eq. 3.13, with j
// reduced to the direct sunlight,
//   S = E_sun ∫ T(x, y) beta_s(y) T(y, sun) dy,
// for the Rayleigh and the aerosol constituents separately. T(x, y) is
// integrated along the ray itself (ray_integration_nodes), not read from the
// table. This is the form of the precomputed tables.
INLINE void compute_single_scattering(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                      float mu, float mu_s, float nu, bool ray_r_mu_intersects_ground,
                                      OUT(vec3) rayleigh, OUT(vec3) aerosol) {
  RayNodes nodes = ray_integration_nodes(atmosphere, r, mu, ray_r_mu_intersects_ground, SINGLE_SCATTERING_INTERVALS);
  single_scattering_over_nodes(atmosphere, transmittance_texture, r, mu, mu_s, nu, nodes, no_moons(), vec3(0.0f),
                               vec3(0.0f), vec3(0.0f), rayleigh, aerosol);
}

// Nodes and weights of the integral of a source function S = J / beta_ext
// along the ray (r, mu) to the nearest atmosphere boundary,
//   L = ∫ T(x, x + t v) beta_ext(t) S(t) dt ≈ Σ_i weight_i S(t_i),
// the nodes and Simpson weights of ray_integration_nodes (placed by the
// extinction that the start of the ray sees) times the extinction at the
// node, scaled so that they add up to ∫ T beta_ext dt = 1 - T(d) exactly
// (per channel): a uniform source function — the diffuse light deep in a
// conservative cloud — is then transported without gain or loss, whatever
// the optical thickness between nodes. Unscaled, the sum is off by -5..+8 %
// of 1 - T(d) on the view rays of a Venus table (5-14 optical depths of
// cloud between radius samples, up to 12 per cell of the ray map), which
// loses or creates light at every one of the hundreds of orders that reach
// its ground. (The linear-source rule of short-characteristics solvers,
// Olson & Kunasz 1987, JQSRT 38, 325, is exact for a uniform source too, but
// only of second order: on the twilight sky of the Earth, whose source
// changes along the ray with the planet's shadow, its RMS error from the
// ground with the sun 5° down is 5.5 % against 4.5 %.) On the view rays of
// the default Earth tables the scale is 0.96-1.03.
//
// In atmospheres of several optical depths the nodes are uniform in optical
// depth over the first source_flat_optical_depth optical depths of the ray
// (4 from a vertical optical depth of 10 at 550 nm, 0 below 3; see
// parameters.hpp source_flat_optical_depth) and follow the transmittance
// only beyond. The source function is not uniform there: on a ray looking up
// from deep in the atmosphere it grows towards the sunlit top faster than
// the transmittance back to the start falls (the sun's optical depth shrinks
// by 1/mu_s per optical depth climbed), so much of the integral comes from
// where T is already small, and nodes uniform in 1 - T leave a handful
// there. Against the reference on 100x Earth's air alone (3.6 optical
// depths at 680 nm, black ground), the radiance of orders 1 + 2 on the
// ground is 15-29 % too high above 20° elevation with nodes uniform in
// 1 - T, within -5..+2 % with these. The sky light on the ground of the full
// 100x Earth at 680 nm (16 optical depths) is 0.84 of the reference with 32
// radius texels and 0.74 with 64 with nodes uniform in 1 - T, an error that
// grows with the texels; with these nodes 1.16 and 1.04, converging with the
// texels (nodes uniform in 1 - T need 128 intervals, 2.6 times the
// precomputation time, for 1.12 and 1.00). More in parameters.hpp.
INLINE RayNodes source_integration_nodes(IN(AtmosphereParams) atmosphere, float r, float mu,
                                         bool ray_r_mu_intersects_ground, int intervals) {
  float d = distance_to_nearest_atmosphere_boundary(atmosphere, r, mu, ray_r_mu_intersects_ground);
  RayMap map = extinction_ray_map(atmosphere, r, mu, d, RAY_MAP_CELLS, atmosphere.source_flat_optical_depth);
  RayNodes nodes = ray_integration_nodes_from_map(d, map, 0.25f, intervals);
  vec3 sum = vec3(0.0f);
  for (int i = 0; i < nodes.count; ++i) {
    nodes.weight[i] *= extinction_at(atmosphere, clamp_radius(atmosphere, radius_along_ray(r, mu, nodes.t[i])));
    sum += nodes.weight[i];
  }
  // 1 - T(d), without cancellation for a thin ray.
  vec3 depth = map.optical_depth[map.cells];
  vec3 exact = mix(depth * (1.0f - depth * (0.5f - depth * (1.0f / 6.0f))), 1.0f - exp(-depth),
                   vec3(greaterThan(depth, vec3(0.01f))));
  vec3 scale = mix(vec3(1.0f), exact / max(sum, vec3(1e-30f)), vec3(greaterThan(sum, vec3(0.0f))));
  for (int i = 0; i < nodes.count; ++i) nodes.weight[i] *= scale;
  return nodes;
}

// The source function J / beta_ext at radius r of a scattering density J
// (0 where nothing scatters or absorbs). The multiple scattering integrates
// it with source_integration_nodes.
INLINE vec3 source_function(IN(AtmosphereParams) atmosphere, float r, vec3 density) {
  vec3 extinction = extinction_at(atmosphere, r);
  return density / max(extinction, vec3(1e-30f)) * vec3(greaterThan(extinction, vec3(0.0f)));
}

// The source function between the radius rows of optically thick
// atmospheres. The multiple scattering step reads each order's source
// function at the nodes of its view rays, between the density table's radius
// rows. Interpolated linearly in u_r there (what texture() does) it has two
// faults in an optically thick atmosphere, against the plane-parallel
// adding-doubling reference (reference_plane_parallel_fluxes) on Venus,
// default sizes, sun 40° up:
//  - where the rows are optical depths apart (Venus's cloud deck: 2-3.4),
//    the chord between two rows cuts the curvature off each order's source
//    (its rise below the sunlit top, the bump of light diffusing through),
//    and a little of every order is lost: over the hundreds of orders of a
//    nearly conservative cloud, the tables reflect 0.89 of the
//    reference's light to space;
//  - near the ground u_r follows rho ~ sqrt(altitude), so a source linear in
//    u_r rises like a square root above the ground row, too much source just
//    above the ground: in the 42 optical depths of Venus's air at 440 nm the
//    sky light on the ground is 1.55 of the reference's (linear in altitude
//    instead: 0.68 of it, on the air alone).
// In thick atmospheres the source is therefore interpolated between the rows
// around r with a cubic Hermite polynomial in source_r_coordinate: the
// optical-depth part of the r axis, 1 - tau(r) / tau(bottom) (in which the
// light diffusing through a thick medium is nearly linear), plus a share of
// the altitude that keeps rows above the medium apart; the slopes at the two
// rows are central differences with their neighbours (one-sided at the first
// and last rows). The result is blended with texture()'s linear
// interpolation by the thickness weight scattering_mu_log_weight, 0 below 10
// optical depths: thin atmospheres keep the linear interpolation exactly.
// On Venus (default sizes, sun 40° up, 680 / 550 / 440 nm; the azimuthal
// mean of the radiance leaving the top straight down, and the light on the
// ground) this reflects 0.99 / 0.99 / 0.99 of the reference, and gives the
// ground 0.96 / 1.00 / 1.10 of it (linear: 0.90 / 0.91 / 0.91 and 0.95 /
// 1.03 / 1.55). The other interpolations compare worse (with a finer r axis
// map of 129 knots, where this scheme gives 1.00 and 1.00 / 1.03 / 1.10):
// Catmull-Rom in u_r (uniform in the row index) 1.00 reflected and 1.02 /
// 1.06 / 1.20 on the ground; Hermite in altitude 1.02 and 1.18 / 1.12 /
// 1.07; linear in altitude, on the air alone, 0.98 / 0.90 / 0.68 on the
// ground.
#define SOURCE_ALTITUDE_SHARE 0.05f

INLINE float source_r_coordinate(IN(AtmosphereParams) atmosphere, float r) {
  float s = horizon_length(atmosphere, r) / horizon_length_at_top(atmosphere);
  float w = atmosphere.scattering_r_optical_depth_weight;
  float x = scattering_x_r_from_rho_fraction(atmosphere, s);
  float depth_part = w > 0.0f ? (x - (1.0f - w) * s) / w : x;
  return depth_part + SOURCE_ALTITUDE_SHARE * (clamp_radius(atmosphere, r) - atmosphere.bottom_radius) /
                          (atmosphere.top_radius - atmosphere.bottom_radius);
}

INLINE float source_row_coordinate(IN(AtmosphereParams) atmosphere, int row) {
  return source_r_coordinate(atmosphere, atmosphere.bottom_radius + scattering_row_height(atmosphere, row));
}

// The row below u_r as texture() finds it (z0; -1 below the first texel
// centre, n - 1 from the last) and the linear weight of the row above (f).
INLINE void source_row_tap(IN(AtmosphereParams) atmosphere, float u_r, OUT(int) z0, OUT(float) f) {
  float x = clamp(u_r, 0.0f, 1.0f) * float(atmosphere.scattering_r_size) - 0.5f;
  z0 = min(int(floor(x)), atmosphere.scattering_r_size - 1);
  f = x - float(z0);
}

// Weights of rows z0 - 1, z0, z0 + 1, z0 + 2 for the source at coordinate c
// between rows z0 and z0 + 1 (0 <= z0 < n - 1; linear weight f of row z0 + 1
// in u_r), from the coordinates of those rows (c_prev and c_next ignored
// where the row does not exist).
INLINE vec4 source_row_weights(IN(AtmosphereParams) atmosphere, int z0, float f, float c, float c_prev, float c0,
                               float c1, float c_next) {
  vec4 weights = vec4(0.0f, 1.0f - f, f, 0.0f);
  float k = atmosphere.scattering_mu_log_weight;
  if (k == 0.0f) return weights;
  bool has_prev = z0 > 0;
  bool has_next = z0 + 2 < atmosphere.scattering_r_size;
  float h = c1 - c0;
  float t = clamp((c - c0) / h, 0.0f, 1.0f);
  float h00 = (2.0f * t - 3.0f) * t * t + 1.0f;
  float h10 = ((t - 2.0f) * t + 1.0f) * t;
  float h01 = (3.0f - 2.0f * t) * t * t;
  float h11 = (t - 1.0f) * t * t;
  // Slope at row z0 times h: h (S1 - S_prev) / (c1 - c_prev), or S1 - S0.
  float a = has_prev ? h / (c1 - c_prev) : 1.0f;
  // Slope at row z0 + 1 times h: h (S_next - S0) / (c_next - c0), or S1 - S0.
  float b = has_next ? h / (c_next - c0) : 1.0f;
  vec4 hermite = vec4(has_prev ? -h10 * a : 0.0f, h00 - (has_prev ? 0.0f : h10) - b * h11,
                      h01 + h10 * a + (has_next ? 0.0f : h11), has_next ? h11 * b : 0.0f);
  return mix(weights, hermite, k);
}

// A cubic undershoots where the source changes by orders of magnitude from
// row to row, as the first orders of a thick atmosphere do in tables whose
// rows are many optical depths apart (100x Earth with 8 rows: from 2 m the
// cubic gives the zenith sky of 4 orders 1e-9 of what linear interpolation
// gives, most of it clamped away from negative values; the Monte Carlo
// reference gives 0.1 of the linear value there): where the two rows around
// r differ by more than SOURCE_FLOOR_RATIO, the result is kept above the
// smaller, the lowest value a source monotone between them can take (with
// the floor that sky is 0.6 of the reference). Only there: the floor adds
// light, and applied wherever the cubic dips below a row it would add 2 % to
// the green sky light on Venus's ground over 600 orders of small tables,
// more than the tail solver, which applies the same weights without any
// floor (its operator must stay linear), finds for the same orders.
#define SOURCE_FLOOR_RATIO 10.0f

INLINE vec3 source_floor(vec3 bracket0, vec3 bracket1) {
  vec3 lower = min(bracket0, bracket1);
  vec3 upper = max(bracket0, bracket1);
  return lower * vec3(greaterThan(upper, SOURCE_FLOOR_RATIO * lower));
}

// The source function of `density_texture` at (r, mu, mu_s, nu) as the
// multiple scattering of the explicit orders reads it (see above). The CPU
// precomputation computes the same weights once per view ray node
// (precompute/steps.cpp).
INLINE vec3 source_function_lookup(IN(AtmosphereParams) atmosphere, IN(sampler3D) density_texture, float r, float mu,
                                   float mu_s, float nu, bool ray_r_mu_intersects_ground) {
  vec4 uvwz = scattering_uvwz_from_r_mu_mu_s_nu(atmosphere, r, mu, mu_s, nu, ray_r_mu_intersects_ground);
  int z0;
  float f;
  source_row_tap(atmosphere, uvwz.w, z0, f);
  if (atmosphere.scattering_mu_log_weight == 0.0f || z0 < 0 || z0 >= atmosphere.scattering_r_size - 1)
    return scattering_lookup_uvwz(atmosphere, density_texture, uvwz, nu);
  float c_prev = z0 > 0 ? source_row_coordinate(atmosphere, z0 - 1) : 0.0f;
  float c_next = z0 + 2 < atmosphere.scattering_r_size ? source_row_coordinate(atmosphere, z0 + 2) : 0.0f;
  vec4 weights = source_row_weights(atmosphere, z0, f, source_r_coordinate(atmosphere, r), c_prev,
                                    source_row_coordinate(atmosphere, z0), source_row_coordinate(atmosphere, z0 + 1),
                                    c_next);
  vec3 result = vec3(0.0f);
  vec3 bracket[2];
  for (int j = 0; j < 4; ++j) {
    vec3 value = scattering_lookup_uvwz(atmosphere, density_texture,
                                        vec4(uvwz.x, uvwz.y, uvwz.z, scattering_row_u_r(atmosphere, z0 - 1 + j)), nu);
    if (j == 1 || j == 2) bracket[j - 1] = value;
    if (weights[j] != 0.0f) result += weights[j] * value;
  }
  return max(result, source_floor(bracket[0], bracket[1]));
}

// Simpson intervals of the multiple scattering's view rays: 16, and 32 in
// optically thick atmospheres (those whose mu axis is warped, see
// scattering_u_mu). One set of nodes serves the three wavelengths of a
// table, and deep in a cloud they see the light from different depths (on
// Venus the CO2 under the cloud is 7 optical depths thick at 680 nm and 42
// at 440 nm): the nodes placed for all three leave each fewer of its own,
// so thick atmospheres get twice as many, at twice the cost of the
// precomputation's multiple scattering step (tests/venus_accuracy.cpp
// compares Venus's ground light with the reference).
INLINE int multiple_scattering_intervals(IN(AtmosphereParams) atmosphere) {
  return atmosphere.scattering_mu_log_weight > 0.0f ? 2 * MULTIPLE_SCATTERING_INTERVALS
                                                    : MULTIPLE_SCATTERING_INTERVALS;
}

// Multiple scattering of one order along the ray (r, mu) (Collienne 2013,
// eq. 3.13):
//   L = ∫ T(x, y) J(y, v) dy = ∫ T(x, y) beta_ext(y) S(y, v) dy,
// with S = J / beta_ext the source function of that order (in
// `scattering_density_texture`, same layout as the scattering tables; see
// compute_scattering_density), read between the radius rows by
// source_function_lookup, with the nodes and weights of
// source_integration_nodes.
INLINE vec3 compute_multiple_scattering(IN(AtmosphereParams) atmosphere, IN(sampler3D) scattering_density_texture,
                                        float r, float mu, float mu_s, float nu, bool ray_r_mu_intersects_ground) {
  RayNodes nodes = source_integration_nodes(atmosphere, r, mu, ray_r_mu_intersects_ground,
                                            multiple_scattering_intervals(atmosphere));
  vec3 result = vec3(0.0f);
  for (int i = 0; i < nodes.count; ++i) {
    float r_t = clamp_radius(atmosphere, radius_along_ray(r, mu, nodes.t[i]));
    float mu_t = clamp_cosine(mu_along_ray(r, mu, nodes.t[i], r_t));
    float mu_s_t = clamp_cosine(mu_s_along_ray(r, mu_s, nu, nodes.t[i], r_t));
    result += nodes.weight[i] * source_function_lookup(atmosphere, scattering_density_texture, r_t, mu_t, mu_s_t, nu,
                                                       ray_r_mu_intersects_ground);
  }
  return result;
}

// Direct ground irradiance: the sun's irradiance on a horizontal surface at
// radius r (order 0 of the ground lighting).
INLINE vec3 compute_direct_irradiance(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                      float mu_s) {
  return atmosphere.solar_irradiance * transmittance_to_sun(atmosphere, transmittance_texture, r, mu_s) * max(mu_s, 0.0f);
}

// Radiance of scattering order `order` (>= 1) arriving at radius r from the
// direction (mu, nu) with the sun at mu_s: in-scattered light of that order
// along the ray, plus, for a ray that hits the ground, the ground's Lambertian
// reflection of the irradiance of order - 1 (`irradiance_texture`; order 0 is
// the direct sunlight) attenuated on the way.
//  - order 1: the single scattering tables, with their phase functions;
//  - order > 1: `multiple_scattering_texture`, the radiance of that order.
INLINE vec3 incident_radiance(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                              IN(sampler3D) single_rayleigh_texture, IN(sampler3D) single_aerosol_texture,
                              IN(sampler3D) multiple_scattering_texture, IN(sampler2D) irradiance_texture, float r,
                              float mu, float mu_s, float nu, int order) {
  bool ground = ray_intersects_ground(atmosphere, r, mu);
  vec3 radiance;
  // Plain lookups, not ray_scattering_lookup: r is a row of the tables here
  // (the scattering density's texels), where the two are the same.
  if (order == 1) {
    radiance = phase_weighted_scattering(atmosphere,
                                         scattering_lookup(atmosphere, single_rayleigh_texture, r, mu, mu_s, nu, ground),
                                         scattering_lookup(atmosphere, single_aerosol_texture, r, mu, mu_s, nu, ground),
                                         nu);
  } else {
    radiance = scattering_lookup(atmosphere, multiple_scattering_texture, r, mu, mu_s, nu, ground);
  }
  if (ground) {
    float d = distance_to_bottom_atmosphere_boundary(atmosphere, r, mu);
    float mu_s_ground = mu_s_at_ground(atmosphere, r, mu_s, nu, d);
    vec3 irradiance = order == 1 ? compute_direct_irradiance(atmosphere, transmittance_texture,
                                                             atmosphere.bottom_radius, mu_s_ground)
                                 : irradiance_lookup(atmosphere, irradiance_texture, atmosphere.bottom_radius,
                                                     mu_s_ground);
    radiance += transmittance_to_ground(atmosphere, transmittance_texture, r, mu) *
                ground_radiance(atmosphere, irradiance);
  }
  return radiance;
}

// Straightforward scattering density of order `order` + 1 at radius r for the
// direction (mu, nu) with the sun at mu_s (Collienne 2013, eq. 3.14):
//   J = sum_i beta_s,i(r) ∫ P_i(v . w) L_order(w) dw,
// by the midpoint rule over `theta_samples` x 2 `theta_samples` directions,
// returned as the source function J / beta_ext(r) (source_function): the
// quantity the density tables hold and interpolate in r, smooth where the
// medium's density changes by orders of magnitude between table samples.
// The CPU precomputation computes the same integral through the spherical
// harmonic structure of the phase functions (precompute/scattering_density.cpp);
// this form is the definition it is tested against.
INLINE vec3 compute_scattering_density(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                       IN(sampler3D) single_rayleigh_texture, IN(sampler3D) single_aerosol_texture,
                                       IN(sampler3D) multiple_scattering_texture, IN(sampler2D) irradiance_texture,
                                       float r, float mu, float mu_s, float nu, int order, int theta_samples) {
  vec3 view = direction_from_mu_phi(mu, 0.0f);
  float sun_x = view.x == 0.0f ? 0.0f : (nu - mu * mu_s) / view.x;
  vec3 sun = vec3(sun_x, safe_sqrt(1.0f - sun_x * sun_x - mu_s * mu_s), mu_s);
  vec3 beta_rayleigh;
  vec3 beta_aerosol;
  vec3 extinction;
  medium_at(atmosphere, r, beta_rayleigh, beta_aerosol, extinction);
  float d_theta = PI / float(theta_samples);
  float d_phi = PI / float(theta_samples);
  vec3 result = vec3(0.0f);
  for (int l = 0; l < theta_samples; ++l) {
    float theta = (float(l) + 0.5f) * d_theta;
    float mu_w = cos(theta);
    float solid_angle = d_theta * d_phi * sin(theta);
    for (int m = 0; m < 2 * theta_samples; ++m) {
      vec3 w = direction_from_mu_phi(mu_w, (float(m) + 0.5f) * d_phi);
      float nu_w = clamp_cosine(dot(w, sun));
      vec3 radiance = incident_radiance(atmosphere, transmittance_texture, single_rayleigh_texture,
                                        single_aerosol_texture, multiple_scattering_texture, irradiance_texture, r,
                                        mu_w, mu_s, nu_w, order);
      float cos_theta = clamp_cosine(dot(view, w));
      result += radiance * (beta_rayleigh * rayleigh_phase_function(cos_theta) +
                            beta_aerosol * aerosol_phase_function(atmosphere, cos_theta)) *
                solid_angle;
    }
  }
  return source_function(atmosphere, r, result);
}

// Sky irradiance of order `order` on a horizontal surface at radius r:
//   E = ∫_{mu > 0} L_order(w) mu dw,
// Gauss-free midpoint rule over `theta_samples` x 2 `theta_samples` directions
// of the upper hemisphere (whose rays never hit the ground).
INLINE vec3 compute_indirect_irradiance(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                        IN(sampler3D) single_rayleigh_texture, IN(sampler3D) single_aerosol_texture,
                                        IN(sampler3D) multiple_scattering_texture, float r, float mu_s, int order,
                                        int theta_samples) {
  vec3 sun = vec3(safe_sqrt(1.0f - mu_s * mu_s), 0.0f, mu_s);
  float d_theta = PI / 2.0f / float(theta_samples);
  float d_phi = PI / float(theta_samples);
  vec3 result = vec3(0.0f);
  for (int l = 0; l < theta_samples; ++l) {
    float theta = (float(l) + 0.5f) * d_theta;
    float mu_w = cos(theta);
    float weight = d_theta * d_phi * sin(theta) * mu_w;
    for (int m = 0; m < 2 * theta_samples; ++m) {
      vec3 w = direction_from_mu_phi(mu_w, (float(m) + 0.5f) * d_phi);
      float nu_w = clamp_cosine(dot(w, sun));
      // The upper hemisphere never sees the ground: the irradiance texture is not read.
      result += incident_radiance(atmosphere, transmittance_texture, single_rayleigh_texture, single_aerosol_texture,
                                  multiple_scattering_texture, transmittance_texture, r, mu_w, mu_s, nu_w, order) *
                weight;
    }
  }
  return result;
}
