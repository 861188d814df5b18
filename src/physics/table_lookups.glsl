// atmos — reading the precomputed tables: transmittance (from the table of
// optical depth, integrated directly where a difference of table values
// would lose its digits), the transmittance to the sun averaged over its
// disc, the 4D scattering tables, the irradiance table, and the radiance
// that the tables' phase-free values give.
//
// Needs: ray_geometry.glsl, medium.glsl, table_coordinates.glsl.

// The transmittance table holds the optical depth τ to the top of the
// atmosphere (Collienne 2013, eq. 3.8), T = exp(-τ). Storing τ rather than T makes
// the transmittance of part of a ray a difference of two lookups,
// exp(-(τ_a - τ_b)), instead of a ratio T_a / T_b that is 0 / 0 wherever a
// dense atmosphere (Venus, 30x Earth in the blue) makes both underflow; and τ
// is the smoother function of the two to interpolate.
INLINE vec3 optical_depth_to_top_atmosphere_boundary(IN(AtmosphereParams) atmosphere,
                                                     IN(sampler2D) transmittance_texture, float r, float mu) {
  return vec3(texture(transmittance_texture, transmittance_uv_from_r_mu(atmosphere, r, mu)));
}

INLINE vec3 transmittance_to_top_atmosphere_boundary(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                                     float r, float mu) {
  return exp(-optical_depth_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, mu));
}

// The transmittance of a part of a ray is the difference of two table
// values of the optical depth to the top (below). That difference keeps the
// interpolation error of each value, a fraction of a percent of it, and
// near the ground of a dense atmosphere the values are huge: looking 3°
// below the horizon from 2 m above Venus's ground, the ray reversed from
// the ground point to the top has an optical depth of 424 at 550 nm (626
// at the horizon), and the difference makes the transmittance of the 40 m
// to the ground jump between 0.7 and 1 from one pixel to the next
// (concentric bands on the ground). Where the larger
// value exceeds DIRECT_SEGMENT_MIN_OPTICAL_DEPTH and the segment stays
// within a band of altitude 1/16 of the atmosphere's thickness (3.75 km on
// Earth, 6 km on Venus), its optical depth is integrated directly instead:
// the extinction changes little and smoothly along such a segment, and 8
// Gauss-Legendre nodes integrate it to float precision (exponential
// profiles over up to three scale heights), at the cost of 8 evaluations
// of the medium instead of 2 table lookups. Below the threshold the
// difference is kept (within 0.5 % of the transmittance on Earth:
// precompute_test.cpp, which also tests the direct integral on Venus).
#define DIRECT_SEGMENT_MIN_OPTICAL_DEPTH 4.0f
#define DIRECT_SEGMENT_BAND_FRACTION 0.0625f

INLINE bool use_direct_optical_depth(IN(AtmosphereParams) atmosphere, vec3 larger_lookup, float r_low,
                                     float r_high) {
  return max(larger_lookup.x, max(larger_lookup.y, larger_lookup.z)) > DIRECT_SEGMENT_MIN_OPTICAL_DEPTH &&
         r_high - r_low <= DIRECT_SEGMENT_BAND_FRACTION * (atmosphere.top_radius - atmosphere.bottom_radius);
}

// Optical depth of [0, d] along the ray (r, mu): 8-node Gauss-Legendre.
INLINE vec3 optical_depth_of_segment(IN(AtmosphereParams) atmosphere, float r, float mu, float d) {
  vec3 sum = vec3(0.0f);
  for (int i = 0; i < 4; ++i) {
    // Nodes +-x and weights w of the rule on [-1, 1] (Abramowitz & Stegun, Table 25.4).
    float x = i == 0 ? 0.1834346425f : i == 1 ? 0.5255324099f : i == 2 ? 0.7966664774f : 0.9602898565f;
    float w = i == 0 ? 0.3626837834f : i == 1 ? 0.3137066459f : i == 2 ? 0.2223810345f : 0.1012285363f;
    float t_near = 0.5f * d * (1.0f - x);
    float t_far = 0.5f * d * (1.0f + x);
    sum += (extinction_at(atmosphere, clamp_radius(atmosphere, radius_along_ray(r, mu, t_near))) +
            extinction_at(atmosphere, clamp_radius(atmosphere, radius_along_ray(r, mu, t_far)))) *
           w;
  }
  return sum * (0.5f * d);
}

// Transmittance between the start of the ray (r, mu) and the point at
// distance d along it, from two table values (optical depth is additive
// along a ray), or integrated directly (above). Rays that hit the ground
// are reversed so that both lookups are of rays that do not.
INLINE vec3 transmittance_along_ray(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                    float mu, float d, bool ray_r_mu_intersects_ground) {
  float r_d = clamp_radius(atmosphere, radius_along_ray(r, mu, d));
  float mu_d = clamp_cosine(mu_along_ray(r, mu, d, r_d));
  vec3 larger;
  vec3 smaller;
  if (ray_r_mu_intersects_ground) {
    larger = optical_depth_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r_d, -mu_d);
    smaller = optical_depth_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, -mu);
  } else {
    larger = optical_depth_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, mu);
    smaller = optical_depth_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r_d, mu_d);
  }
  // The lowest point of the segment: its end, its start, or the ray's
  // perigee if that lies between them.
  float r_low = min(r, r_d);
  if (mu < 0.0f && -r * mu < d) r_low = min(r_low, r * safe_sqrt(1.0f - mu * mu));
  if (use_direct_optical_depth(atmosphere, larger, r_low, max(r, r_d)))
    return exp(-optical_depth_of_segment(atmosphere, r, mu, d));
  return exp(-max(larger - smaller, vec3(0.0f)));
}

// Transmittance between the start of the ray (r, mu) and the ground, for a
// ray that hits it. The end point's radius is the ground radius itself, not
// a float recomputation of it: near the ground the table coordinate
// sqrt(r² - R²) turns the 0.5 m float resolution of r into kilometres.
INLINE vec3 transmittance_to_ground(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                    float mu) {
  float d = distance_to_bottom_atmosphere_boundary(atmosphere, r, mu);
  float mu_d = clamp_cosine((r * mu + d) / atmosphere.bottom_radius);
  vec3 larger =
      optical_depth_to_top_atmosphere_boundary(atmosphere, transmittance_texture, atmosphere.bottom_radius, -mu_d);
  if (use_direct_optical_depth(atmosphere, larger, atmosphere.bottom_radius, r))
    return exp(-optical_depth_of_segment(atmosphere, r, mu, d));
  vec3 optical_depth = larger - optical_depth_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, -mu);
  return exp(-max(optical_depth, vec3(0.0f)));
}

// Fraction of the solar disc above the horizon seen from radius r: the area
// of a uniform disc above a straight edge at signed distance x (in disc
// radii) from its centre, (π/2 + x sqrt(1 - x²) + asin x) / π.
INLINE float sun_visible_fraction(IN(AtmosphereParams) atmosphere, float r, float mu_s) {
  float mu_h = horizon_mu(atmosphere, r);
  // |d mu / d angle| <= 1, so a cosine margin of one angular radius is safe.
  if (mu_s - mu_h > atmosphere.sun_angular_radius) return 1.0f;
  if (mu_s - mu_h < -atmosphere.sun_angular_radius) return 0.0f;
  float elevation_above_horizon = asin(clamp_cosine(mu_s)) - asin(clamp_cosine(mu_h));
  float x = clamp(elevation_above_horizon / atmosphere.sun_angular_radius, -1.0f, 1.0f);
  return 0.5f + (x * sqrt(1.0f - x * x) + asin(x)) / PI;
}

// Within this cosine margin above the horizon (about 6°), the transmittance
// to the sun is averaged over the solar disc instead of taken at its centre.
// Near the horizon the optical depth of the path changes by a large factor
// across the disc's 0.53°, and since exp is convex the centre value
// underestimates the mean — by 20-30 % for the grazing rays that light the
// twilight sky, and still 0.4 % at 5° (blue light at sea level: the
// relative error is about Var(elevation) (d tau / d elevation)² / 2, with
// Var = alpha² / 4 for a uniform disc). Above the margin it is below 0.3 %.
#define SUN_DISC_AVERAGE_MARGIN 0.1f
#define SUN_DISC_NODES 4

INLINE bool sun_needs_disc_average(IN(AtmosphereParams) atmosphere, float mu_s, float mu_h) {
  return mu_s - mu_h < SUN_DISC_AVERAGE_MARGIN + atmosphere.sun_angular_radius;
}

// The SUN_DISC_NODES (= 4) nodes of the quadrature over the visible part of
// a uniform solar disc at zenith cosine mu_s, seen from a point whose
// horizon is at mu_h. Disc points at elevation offset x alpha from the
// centre (x in [-1, 1]) form a chord of relative length sqrt(1 - x²); with
// x = cos θ the visible part (x above the horizon) is θ in [0, θ_h] and the
// disc average of f is
//   (2 / π) ∫_0^θ_h sin²θ f(cos θ) dθ,
// integrated by the midpoint rule on SUN_DISC_NODES intervals — for the
// whole disc (θ_h = π) the integrand is periodic and the rule gives the
// disc's moments exactly (mean offset 0, variance alpha² / 4; 4-point
// Gauss-Legendre is off by 12 % in the variance, which is what the average
// is for); for part of the disc the weights sin²θ_k are scaled to sum to the
// exact visible fraction, (θ_h - sin θ_h cos θ_h) / π. The node angles
// θ_k = (k + ½) θ_h / 4 follow from cos θ_h = x_h by the half-angle formulas
// (cos(θ/2) = sqrt((1 + cos θ) / 2), sin(θ/2) = sin θ / (2 cos(θ/2)), without
// cancellation for a thin visible sliver) and angle addition: square roots
// instead of a sine and a cosine per node, which software rasterisers pay
// for every pixel whether or not its disc is cut. Each node's sine of
// elevation is sin(e + δ) = mu_s cos δ + sqrt(1 - mu_s²) sin δ with
// δ = alpha cos θ <= 0.3°, where cos δ = 1 - δ²/2 and sin δ = δ to 1e-9; and
// for a disc wholly above the horizon (the common case) cos θ and sin θ are
// constants: no trigonometry, which the precomputation calls for most texels
// near the horizon. `mu`: the nodes' zenith cosines, `weight`: their weights.
#if SUN_DISC_NODES != 4
#error "sun_disc_nodes halves the disc's angle three times: four nodes"
#endif
INLINE void sun_disc_nodes(IN(AtmosphereParams) atmosphere, float mu_s, float mu_h, OUT(vec4) mu,
                           OUT(vec4) weight) {
  float alpha = atmosphere.sun_angular_radius;
  // cos θ_k and sin θ_k for θ_h = π: θ_k = 22.5°, 67.5°, 112.5°, 157.5°.
  vec4 cos_theta = vec4(0.9238795325f, 0.3826834324f, -0.3826834324f, -0.9238795325f);
  vec4 sin_theta = vec4(0.3826834324f, 0.9238795325f, 0.9238795325f, 0.3826834324f);
  weight = PI / float(SUN_DISC_NODES) * sin_theta * sin_theta * (2.0f / PI);
  if (mu_s - mu_h <= alpha) {
    // Part of the disc may be below the horizon (|d mu / d angle| <= 1).
    float x_h = clamp((asin(clamp_cosine(mu_h)) - asin(clamp_cosine(mu_s))) / alpha, -1.0f, 1.0f);
    float sin_h = safe_sqrt((1.0f - x_h) * (1.0f + x_h));
    float cos_2 = safe_sqrt(0.5f * (1.0f + x_h));  // θ_h / 2
    float sin_2 = safe_sqrt(0.5f * (1.0f - x_h));
    float cos_4 = sqrt(0.5f * (1.0f + cos_2));  // θ_h / 4
    float sin_4 = sin_2 / (2.0f * cos_4);
    float cos_8 = sqrt(0.5f * (1.0f + cos_4));  // θ_h / 8
    float sin_8 = sin_4 / (2.0f * cos_8);
    cos_theta.x = cos_8;
    sin_theta.x = sin_8;
    cos_theta.y = cos_theta.x * cos_4 - sin_theta.x * sin_4;
    sin_theta.y = sin_theta.x * cos_4 + cos_theta.x * sin_4;
    cos_theta.z = cos_theta.y * cos_4 - sin_theta.y * sin_4;
    sin_theta.z = sin_theta.y * cos_4 + cos_theta.y * sin_4;
    cos_theta.w = cos_theta.z * cos_4 - sin_theta.z * sin_4;
    sin_theta.w = sin_theta.z * cos_4 + cos_theta.z * sin_4;
    vec4 sin2 = sin_theta * sin_theta;
    float sum = sin2.x + sin2.y + sin2.z + sin2.w;
    float fraction = max(acos(x_h) - sin_h * x_h, 0.0f) / PI;
    weight = sum > 0.0f ? sin2 * (fraction / sum) : vec4(0.0f);
  }
  vec4 delta = alpha * cos_theta;
  float sin_s = safe_sqrt(1.0f - mu_s * mu_s);
  mu = clamp(mu_s * (vec4(1.0f) - 0.5f * delta * delta) + sin_s * delta, vec4(-1.0f), vec4(1.0f));
}

// Transmittance from radius r to the sun, including the planet's shadow:
// the mean over the solar disc of the transmittance of the unobstructed
// rays to its points (a uniform disc; Collienne 2013, §3, uses a point sun).
INLINE vec3 transmittance_to_sun(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                 float mu_s) {
  float mu_h = horizon_mu(atmosphere, r);
  if (!sun_needs_disc_average(atmosphere, mu_s, mu_h))
    return transmittance_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, mu_s);
  if (mu_s - mu_h < -atmosphere.sun_angular_radius) return vec3(0.0f);
  vec4 mu;
  vec4 weight;
  sun_disc_nodes(atmosphere, mu_s, mu_h, mu, weight);
  vec3 sum = vec3(0.0f);
  for (int k = 0; k < SUN_DISC_NODES; ++k)
    sum += weight[k] * transmittance_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, mu[k]);
  return sum;
}

// A one-lookup estimate of transmittance_to_sun, for densities that only
// place quadrature nodes (sunlit_ray_map): the visible fraction of the disc,
// taken linear in the height of its centre above the horizon (within 0.06 of
// sun_visible_fraction's), times the transmittance towards the middle of its
// visible part (the centre, or halfway between the horizon and the top of a
// setting disc). The nodes themselves weigh the exact disc average, so the
// estimate moves nodes and leaves the integrand as it is.
INLINE vec3 transmittance_to_sun_estimate(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                          float r, float mu_s) {
  float mu_h = horizon_mu(atmosphere, r);
  float alpha = atmosphere.sun_angular_radius;
  float visible = clamp(0.5f + 0.5f * (mu_s - mu_h) / alpha, 0.0f, 1.0f);
  float mu_middle = max(max(mu_s, 0.5f * (mu_s + alpha + mu_h)), mu_h);
  return visible * transmittance_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, mu_middle);
}

// `set` reading the delta-M scaled medium's optical depth instead of its own
// (single_scattering_tile): the transmittances that the single scattering's
// sunlight and the light of the planet's ground go through.
INLINE AtmosphereParams with_scaled_transmittance(IN(AtmosphereParams) set) {
  AtmosphereParams scaled = set;
  scaled.transmittance_tile = set.single_scattering_tile;
  return scaled;
}

// The two nu tiles around nu (the lower one's index) and the weight of the
// upper one, for linear interpolation between tiles. A nu within 1e-4 of a
// tile's spacing from a tile is that tile's: the axis uniform in angle does
// not give back a tile's own nu exactly (acos(cos(x)) in float), and a
// weight of 1e-7 on a neighbour whose light is 1e5 times stronger (towards
// a sun below the horizon) would be a 1 % error.
INLINE void scattering_nu_tiles(IN(AtmosphereParams) atmosphere, float nu, OUT(float) tile, OUT(float) lerp) {
  float tex_coord_x = unit_range_from_nu(atmosphere, nu) * float(atmosphere.scattering_nu_size - 1);
  float nearest = floor(tex_coord_x + 0.5f);
  tex_coord_x = abs(tex_coord_x - nearest) < 1e-4f ? nearest : tex_coord_x;
  tile = min(floor(tex_coord_x), float(atmosphere.scattering_nu_size - 1));
  lerp = tex_coord_x - tile;
}

// 4D lookup at table coordinates `uvwz` (scattering_uvwz_from_r_mu_mu_s_nu)
// with linear interpolation between the two nearest nu tiles.
INLINE vec3 scattering_lookup_uvwz(IN(AtmosphereParams) atmosphere, IN(sampler3D) scattering_texture, vec4 uvwz,
                                   float nu) {
  float tex_x;
  float lerp;
  scattering_nu_tiles(atmosphere, nu, tex_x, lerp);
  vec3 uvw0 = vec3((tex_x + uvwz.y) / float(atmosphere.scattering_nu_size), uvwz.z, uvwz.w);
  vec3 uvw1 = vec3((tex_x + 1.0f + uvwz.y) / float(atmosphere.scattering_nu_size), uvwz.z, uvwz.w);
  return vec3(texture(scattering_texture, uvw0)) * (1.0f - lerp) + vec3(texture(scattering_texture, uvw1)) * lerp;
}

// 4D lookup with linear interpolation between the two nearest nu tiles.
INLINE vec3 scattering_lookup(IN(AtmosphereParams) atmosphere, IN(sampler3D) scattering_texture, float r, float mu,
                              float mu_s, float nu, bool ray_r_mu_intersects_ground) {
  return scattering_lookup_uvwz(
      atmosphere, scattering_texture,
      scattering_uvwz_from_r_mu_mu_s_nu(atmosphere, r, mu, mu_s, nu, ray_r_mu_intersects_ground), nu);
}

// The light of the ray of the tables' radius row 1 (h_1 above the ground)
// that reaches the ground after distance d, read exactly on the row; for d
// below h_1, where no such ray exists, that of the row's vertical ray (length
// h_1) times d / h_1. mu_1 from R^2 = r_1^2 + d^2 + 2 r_1 mu_1 d, with
// R^2 - r_1^2 = -h_1 (R + r_1) against the cancellation.
INLINE vec3 same_length_ground_ray_lookup(IN(AtmosphereParams) atmosphere, IN(sampler3D) scattering_texture,
                                          float h_1, float d, float mu_s, float nu) {
  float r_1 = atmosphere.bottom_radius + h_1;
  float d_1 = max(d, h_1);
  float mu_1 = clamp_cosine(-(h_1 * (atmosphere.bottom_radius + r_1) + d_1 * d_1) / (2.0f * r_1 * d_1));
  vec4 uvwz = vec4(0.0f, scattering_u_mu_s(atmosphere, mu_s), scattering_u_mu(atmosphere, r_1, mu_1, true),
                   scattering_row_u_r(atmosphere, 1));
  return scattering_lookup_uvwz(atmosphere, scattering_texture, uvwz, nu) * min(d / h_1, 1.0f);
}

// The light of the grazing ray of radius row `row` (level at the start,
// tangent to the ground: the upper half of mu at x = 1, see
// scattering_u_mu), read exactly on the row.
INLINE vec3 grazing_ray_lookup(IN(AtmosphereParams) atmosphere, IN(sampler3D) scattering_texture, int row,
                               float mu_s, float nu) {
  vec4 uvwz = vec4(0.0f, scattering_u_mu_s(atmosphere, mu_s),
                   0.5f + 0.5f * texture_coord_from_unit_range(1.0f, atmosphere.scattering_mu_size / 2),
                   scattering_row_u_r(atmosphere, row));
  return scattering_lookup_uvwz(atmosphere, scattering_texture, uvwz, nu);
}

// The light scattered along a ray (r, mu) to the ground that starts below
// the tables' radius row 1 (h_1 above the ground: 105 m on Earth, 330 m on
// Venus with the default 32 rows), from one of the tables of in-scattered
// light (single Rayleigh + multiple, single aerosol, multiple); used by
// ray_scattering_lookup below.
// Why: row 0 holds zero for every ray to the ground (they have no length
// there), so between rows 0 and 1 the plain lookup is row 1's value times
// the camera's fraction of the way up in rho (linear interpolation in u_r).
// That is right where the air is optically thin (row 1's ray at the same
// u_mu is longer in the same proportion, and its light grows with its
// length), and wrong where it is not: a ray whose light has saturated (one
// optical depth near Venus's ground is a few kilometres at 550 nm) is not
// brighter for being longer. Seen from 2 m above Venus's ground, the plain
// lookup darkens the ground towards its horizon, to 0.13 of the brute-force
// reference's radiance 4 km away, where the reference brightens into the
// haze as bright as the sky above the horizon (tests/venus_accuracy.cpp).
// Instead:
//  1. The ray of row 1 that reaches the ground after the SAME distance d
//     (same_length_ground_ray_lookup) runs through the same lowest air down
//     to the ground, so its light s_1 saturates as the ray's does.
//  2. It starts higher, and near the ground the light changes fast with
//     height: a dark ground sends little up (on Venus a ray 0.5° above
//     the horizon is 0.58 as bright from 2 m as from 330 m; reference),
//     dense haze dims the sunlight. The grazing rays of rows 0 and 1
//     (grazing_ray_lookup, g_0 and g_1) measure that change between the
//     ground and h_1, and s_1 is scaled by (g_0 / g_1)^e, with e the
//     fraction of h_1 between where row 1's ray and the camera's ray
//     collect their light: e = (1 - h / h_1)
//     (1/2 + 1/2 min(s_1 / g_1, 1)). A ray whose light is far from
//     saturated (s_1 << g_1) collects it all along its descent, around
//     h_1 / 2; a saturated one near its start, h_1.
// The ratio g_0 / g_1 is kept within [1/2, 2]. The value is continuous at
// h_1, where it is the table's own. Against the reference, Venus from 2 m,
// 20 m and 107 m, the ground 100 m to 4 km away: 1.00-1.07 of it (the plain
// lookup 0.13-0.85); single scattering in 10 times Earth's air (where it
// can be integrated exactly, tests/precompute_test.cpp): at most 5.2 %
// beyond the table's own interpolation error on row 1, 12.4 % in all (the
// plain lookup up to 4.4 times off).
// Not for the tables of the scattering density (compute_multiple_scattering):
// the density is a property of a point, not of a ray, and row 0 holds it.
INLINE vec3 ground_ray_scattering_below_row_1(IN(AtmosphereParams) atmosphere, IN(sampler3D) scattering_texture,
                                              float r, float mu, float mu_s, float nu) {
  float h_1 = atmosphere.scattering_row_1_height;
  float height = r - atmosphere.bottom_radius;
  float d = distance_to_bottom_atmosphere_boundary(atmosphere, r, mu);
  vec3 s_1 = same_length_ground_ray_lookup(atmosphere, scattering_texture, h_1, d, mu_s, nu);
  vec3 g_0 = grazing_ray_lookup(atmosphere, scattering_texture, 0, mu_s, nu);
  vec3 g_1 = grazing_ray_lookup(atmosphere, scattering_texture, 1, mu_s, nu);
  float below = 1.0f - max(height, 0.0f) / h_1;
  vec3 ratio = vec3(1.0f);
  vec3 exponent = vec3(0.0f);
  for (int c = 0; c < 3; ++c) {
    if (g_0[c] > 0.0f && g_1[c] > 0.0f) {
      ratio[c] = clamp(g_0[c] / g_1[c], 0.5f, 2.0f);
      exponent[c] = below * (0.5f + 0.5f * min(s_1[c] / g_1[c], 1.0f));
    }
  }
  return s_1 * pow(ratio, exponent);
}

// Only in optically thick atmospheres (those whose r axis follows the
// optical depth, scattering_r_optical_depth_weight > 0: Venus, Titan, 100
// times Earth). In thin ones the plain lookup is right in the limit that
// matters there, and the ray of row 1 with the same length is a poor proxy
// for a short, nearly level ray: it is steep (105 m down in 115 m), and
// the multiple scattering of a hazy sky depends on the direction. In
// Earth's continental haze from 2 m, the sun 60° up, 1° down towards the
// sun, the in-scatter 115 m away is 23 % short with it, 14 % without
// (tests/aerial_perspective_accuracy.cpp), although steep rays come nearer
// the reference (within 0.5 % 4-12 m away, 3-12 % too bright without).
INLINE vec3 ray_scattering_lookup(IN(AtmosphereParams) atmosphere, IN(sampler3D) scattering_texture, float r,
                                  float mu, float mu_s, float nu, bool ray_r_mu_intersects_ground) {
  if (ray_r_mu_intersects_ground && atmosphere.scattering_r_optical_depth_weight > 0.0f &&
      r - atmosphere.bottom_radius < atmosphere.scattering_row_1_height)
    return ground_ray_scattering_below_row_1(atmosphere, scattering_texture, r, mu, mu_s, nu);
  return scattering_lookup(atmosphere, scattering_texture, r, mu, mu_s, nu, ray_r_mu_intersects_ground);
}

INLINE vec3 irradiance_lookup(IN(AtmosphereParams) atmosphere, IN(sampler2D) irradiance_texture, float r, float mu_s) {
  return vec3(texture(irradiance_texture, irradiance_uv_from_r_mu_s(atmosphere, r, mu_s)));
}

// Radiance of single scattering from the tables' values without phase
// functions (single Rayleigh, or Rayleigh + multiple / P_R, and single aerosol),
// channel by channel. In the spectral mode the aerosol value is not quite
// phase-free: it holds the ratio of the sum over wavelengths to this phase
// function (see spectral_single_scattering and precompute.cpp), so that this
// product restores each wavelength's own phase function.
INLINE vec3 phase_weighted_scattering(IN(AtmosphereParams) atmosphere, vec3 rayleigh, vec3 aerosol, float nu) {
  return rayleigh * rayleigh_phase_function(nu) + aerosol * aerosol_phase_function(atmosphere, nu);
}
