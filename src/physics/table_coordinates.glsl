// atmos — the parameterisation of the precomputed tables: the mappings
// between (r, mu, mu_s, nu) and texture coordinates, both ways, of the
// transmittance table, the 4D scattering tables (tiled in a 3D texture) and
// the irradiance table.
//
// Needs: ray_geometry.glsl.
//
// The parameterisation is that of Bruneton 2017 ("Precomputed Atmospheric
// Scattering: a New Implementation"): distances to the atmosphere
// boundaries, with the horizon split of mu into rays that hit the ground and
// rays that do not. The r and mu axes of optically thick atmospheres and the
// nu axis of sharp aerosol lobes are adapted below.

// A texture of n texels holds samples at texel centres: the unit range [0, 1]
// maps to [0.5/n, 1 - 0.5/n] so that the end values are sampled exactly.
INLINE float texture_coord_from_unit_range(float x, int texture_size) {
  return 0.5f / float(texture_size) + x * (1.0f - 1.0f / float(texture_size));
}

INLINE float unit_range_from_texture_coord(float u, int texture_size) {
  return (u - 0.5f / float(texture_size)) / (1.0f - 1.0f / float(texture_size));
}

// Distance from the ground to the top along the horizontal at the ground (H)
// and from the ground to radius r along the horizon (rho).
INLINE float horizon_length_at_top(IN(AtmosphereParams) atmosphere) {
  return sqrt((atmosphere.top_radius - atmosphere.bottom_radius) * (atmosphere.top_radius + atmosphere.bottom_radius));
}

INLINE float horizon_length(IN(AtmosphereParams) atmosphere, float r) {
  return safe_sqrt((r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius));
}

// Transmittance table: (r, mu) of rays that do not hit the ground. x_r = rho / H
// puts texels densely near the ground; x_mu is the distance to the top,
// normalised between its minimum (straight up) and maximum (horizon).
INLINE vec2 transmittance_uv_from_r_mu(IN(AtmosphereParams) atmosphere, float r, float mu) {
  float H = horizon_length_at_top(atmosphere);
  float rho = horizon_length(atmosphere, r);
  float d = distance_to_top_atmosphere_boundary(atmosphere, r, mu);
  float d_min = atmosphere.top_radius - r;
  float d_max = rho + H;
  float x_mu = clamp((d - d_min) / (d_max - d_min), 0.0f, 1.0f);
  float x_r = rho / H;
  // Tile `transmittance_tile` of `transmittance_tiles` side by side: texel
  // centres map to texel centres, so linear filtering never mixes tiles.
  float u = texture_coord_from_unit_range(x_mu, atmosphere.transmittance_mu_size);
  return vec2((float(atmosphere.transmittance_tile) + u) / float(atmosphere.transmittance_tiles),
              texture_coord_from_unit_range(x_r, atmosphere.transmittance_r_size));
}

INLINE void r_mu_from_transmittance_uv(IN(AtmosphereParams) atmosphere, vec2 uv, OUT(float) r, OUT(float) mu) {
  float x_mu = unit_range_from_texture_coord(uv.x * float(atmosphere.transmittance_tiles) -
                                                 float(atmosphere.transmittance_tile),
                                             atmosphere.transmittance_mu_size);
  float x_r = unit_range_from_texture_coord(uv.y, atmosphere.transmittance_r_size);
  float H = horizon_length_at_top(atmosphere);
  float rho = H * x_r;
  r = sqrt(rho * rho + atmosphere.bottom_radius * atmosphere.bottom_radius);
  float d_min = atmosphere.top_radius - r;
  float d_max = rho + H;
  float d = d_min + x_mu * (d_max - d_min);
  // d² + 2 r mu d + r² = R_top², and R_top² - r² = H² - rho².
  mu = d == 0.0f ? 1.0f : clamp_cosine((H * H - rho * rho - d * d) / (2.0f * r * d));
}

// The r axis of the scattering tables. Bruneton's x_r = rho / H puts the
// texels densely near the ground, where the density is highest in a thin
// atmosphere. In an optically thick one the radiance changes on the scale
// of one optical depth wherever that lies: Venus's cloud deck (optical depth
// 30 between 47 and 90 km) gets only 8 of 32 texels from rho / H, and the
// light on the ground converges slowly with their number (at 680 nm 9.3,
// 8.5, 8.2 % of the sunlight with 32, 64, 128 texels, against the
// reference's 7.8 %; with the axis below 7.1 and 7.9 % with 32 and 64
// texels, and at 550 nm 5.1 % with 32, the reference's 5.1 %). So there the
// axis is
//   x_r = (1 - w) rho / H + w (1 - tau(r) / tau(bottom)),
// tau(r) the vertical optical depth at 550 nm from r to the top and
// w = scattering_r_optical_depth_weight (make_atmosphere_params), tabulated
// at SCATTERING_R_AXIS_KNOTS values of rho / H and linear between, so that
// the inverse below is exact and cheap. w = 0 is Bruneton's axis exactly.
INLINE float scattering_x_r_from_rho_fraction(IN(AtmosphereParams) atmosphere, float s) {
  if (atmosphere.scattering_r_optical_depth_weight == 0.0f) return s;
  float f = clamp(s, 0.0f, 1.0f) * float(SCATTERING_R_AXIS_KNOTS - 1);
  int i = min(int(f), SCATTERING_R_AXIS_KNOTS - 2);
  return mix(atmosphere.scattering_r_axis[i], atmosphere.scattering_r_axis[i + 1], f - float(i));
}

INLINE float rho_fraction_from_scattering_x_r(IN(AtmosphereParams) atmosphere, float x) {
  if (atmosphere.scattering_r_optical_depth_weight == 0.0f) return x;
  // Bisection for the knot interval [lo, hi] holding x (the knots increase).
  int lo = 0;
  int hi = SCATTERING_R_AXIS_KNOTS - 1;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (atmosphere.scattering_r_axis[mid] <= x) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  float a = atmosphere.scattering_r_axis[lo];
  float b = atmosphere.scattering_r_axis[hi];
  return (float(lo) + clamp((x - a) / (b - a), 0.0f, 1.0f)) / float(SCATTERING_R_AXIS_KNOTS - 1);
}

INLINE float scattering_u_r(IN(AtmosphereParams) atmosphere, float r) {
  float s = horizon_length(atmosphere, r) / horizon_length_at_top(atmosphere);
  return texture_coord_from_unit_range(scattering_x_r_from_rho_fraction(atmosphere, s), atmosphere.scattering_r_size);
}

// The mu axis of the scattering tables, within each half: the ray's
// distance d to the boundary it reaches, normalised between its extremes,
// x = (d - d_min) / (d_max - d_min) (Bruneton 2017), then warped towards
// log d by
//   u = log(1 + k x) / log(1 + k),  k = w (d_max - d_min) / (d_min + d_0),
// with w = scattering_mu_log_weight (0: linear in d, Bruneton's mapping) and
// d_0 a floor at 1 % of the atmosphere's thickness (MU_WARP_FLOOR_FRACTION),
// so that the map stays finite where d_min is 0 (at the top for upward rays,
// on the ground for downward ones).
// Why: linear in d, the texels of a point high in a thick atmosphere crowd
// round its horizon. On Venus at 65 km (d_min = 35 km to the top, d_max =
// 1993 km along the horizon) the whole upper hemisphere from the zenith
// to 60° from it lies within 1.1 of the 64 texels of the upward half,
// yet inside the cloud deck that is where the light comes from. Log-spaced
// distances give it 11 texels, and keep 12 for the rays below the local
// horizontal. make_atmosphere_params chooses w from the comparison with the
// brute-force reference (tests/venus_accuracy.cpp).
#define MU_WARP_FLOOR_FRACTION 0.01f
INLINE float mu_warp_k(IN(AtmosphereParams) atmosphere, float d_min, float d_max) {
  float d_0 = MU_WARP_FLOOR_FRACTION * (atmosphere.top_radius - atmosphere.bottom_radius);
  return atmosphere.scattering_mu_log_weight * max(d_max - d_min, 0.0f) / (d_min + d_0);
}
INLINE float warp_mu_range(float x, float k) { return k > 1e-3f ? log(1.0f + k * x) / log(1.0f + k) : x; }
INLINE float unwarp_mu_range(float u, float k) { return k > 1e-3f ? (exp(u * log(1.0f + k)) - 1.0f) / k : u; }

INLINE float scattering_u_mu(IN(AtmosphereParams) atmosphere, float r, float mu, bool ray_r_mu_intersects_ground) {
  float H = horizon_length_at_top(atmosphere);
  float rho = horizon_length(atmosphere, r);
  float r_mu = r * mu;
  float discriminant = r_mu * r_mu - rho * rho;
  int half_mu_size = atmosphere.scattering_mu_size / 2;
  if (ray_r_mu_intersects_ground) {
    float d = -r_mu - safe_sqrt(discriminant);
    float d_min = r - atmosphere.bottom_radius;
    float d_max = rho;
    float x = d_max == d_min ? 0.0f : clamp((d - d_min) / (d_max - d_min), 0.0f, 1.0f);
    x = warp_mu_range(x, mu_warp_k(atmosphere, d_min, d_max));
    return 0.5f - 0.5f * texture_coord_from_unit_range(x, half_mu_size);
  }
  float d = -r_mu + safe_sqrt(discriminant + H * H);
  float d_min = atmosphere.top_radius - r;
  float d_max = rho + H;
  float x = clamp((d - d_min) / (d_max - d_min), 0.0f, 1.0f);
  x = warp_mu_range(x, mu_warp_k(atmosphere, d_min, d_max));
  return 0.5f + 0.5f * texture_coord_from_unit_range(x, half_mu_size);
}

// mu_s through the distance to the top from the ground, squeezed so that
// mu_s_min maps to 0 and more texels go to the sun near the horizon, where
// the light changes fastest. Shared by the scattering and irradiance tables.
INLINE float unit_range_from_mu_s(IN(AtmosphereParams) atmosphere, float mu_s) {
  float H = horizon_length_at_top(atmosphere);
  float d = distance_to_top_atmosphere_boundary(atmosphere, atmosphere.bottom_radius, mu_s);
  float d_min = atmosphere.top_radius - atmosphere.bottom_radius;
  float d_max = H;
  float a = (d - d_min) / (d_max - d_min);
  float D = distance_to_top_atmosphere_boundary(atmosphere, atmosphere.bottom_radius, atmosphere.mu_s_min);
  float A = (D - d_min) / (d_max - d_min);
  return max(1.0f - a / A, 0.0f) / (1.0f + a);
}

INLINE float mu_s_from_unit_range(IN(AtmosphereParams) atmosphere, float x_mu_s) {
  float H = horizon_length_at_top(atmosphere);
  float d_min = atmosphere.top_radius - atmosphere.bottom_radius;
  float d_max = H;
  float D = distance_to_top_atmosphere_boundary(atmosphere, atmosphere.bottom_radius, atmosphere.mu_s_min);
  float A = (D - d_min) / (d_max - d_min);
  float a = (A - x_mu_s * A) / (1.0f + x_mu_s * A);
  float d = d_min + min(a, A) * (d_max - d_min);
  return d == 0.0f ? 1.0f : clamp_cosine((H * H - d * d) / (2.0f * atmosphere.bottom_radius * d));
}

INLINE float scattering_u_mu_s(IN(AtmosphereParams) atmosphere, float mu_s) {
  return texture_coord_from_unit_range(unit_range_from_mu_s(atmosphere, mu_s), atmosphere.scattering_mu_s_size);
}

// The nu axis: uniform in nu (Bruneton's), or, for an atmosphere whose
// aerosol has a lobe sharper than kDeltaScaledMaxG
// (scattering_nu_in_angle), uniform in the scattering angle θ = acos(nu):
// tiles 180° / (nu_size - 1) apart everywhere (25.7° with 8 tiles), where
// uniform in nu they are 41° apart next to the sun and 17° at right angles
// to it. The light scattered more than once by such a lobe (even delta-M
// scaled) changes fastest next to the sun. Against the reference, the
// "mars" dust with 6 orders and the sun 60/10/2° up has RMS errors beyond
// 20° of the sun of 9.4/8.1/11.8 % uniform in angle and 9.8/20/30 % uniform
// in nu (worst 19/31/57 % against 19/73/122 %; within 20° of the sun
// 6.5/20/26 % against 4.5/11/19 %). Earth's clear sky is better uniform in
// nu (0.45 % against 0.57 % RMS with the sun 60° up, 4.55 % against 4.91 %
// in twilight with the sun 5° down), and so is Venus's energy balance (out
// / in 1.10 against 1.15, tests/presets_test.cpp).
INLINE float nu_from_unit_range(IN(AtmosphereParams) atmosphere, float x) {
  return atmosphere.scattering_nu_in_angle != 0 ? cos(PI * (1.0f - x)) : clamp_cosine(x * 2.0f - 1.0f);
}
INLINE float unit_range_from_nu(IN(AtmosphereParams) atmosphere, float nu) {
  return atmosphere.scattering_nu_in_angle != 0 ? 1.0f - acos(clamp_cosine(nu)) / PI : (nu + 1.0f) / 2.0f;
}

// Scattering table: (r, mu, mu_s, nu) -> (u_nu, u_mu_s, u_mu, u_r) in the
// x, y, z, w components. The mu axis is split at the horizon: u_mu < 0.5 for
// rays that hit the ground, > 0.5 for the others, each half with its own
// distance normalisation, so that the discontinuity of the radiance at the
// horizon falls between texels instead of being blurred across them.
INLINE vec4 scattering_uvwz_from_r_mu_mu_s_nu(IN(AtmosphereParams) atmosphere, float r, float mu, float mu_s,
                                              float nu, bool ray_r_mu_intersects_ground) {
  return vec4(unit_range_from_nu(atmosphere, nu), scattering_u_mu_s(atmosphere, mu_s),
              scattering_u_mu(atmosphere, r, mu, ray_r_mu_intersects_ground), scattering_u_r(atmosphere, r));
}

INLINE void r_mu_mu_s_nu_from_scattering_uvwz(IN(AtmosphereParams) atmosphere, vec4 uvwz, OUT(float) r, OUT(float) mu,
                                              OUT(float) mu_s, OUT(float) nu, OUT(bool) ray_r_mu_intersects_ground) {
  float H = horizon_length_at_top(atmosphere);
  float rho = H * rho_fraction_from_scattering_x_r(atmosphere,
                                                   unit_range_from_texture_coord(uvwz.w, atmosphere.scattering_r_size));
  r = sqrt(rho * rho + atmosphere.bottom_radius * atmosphere.bottom_radius);

  int half_mu_size = atmosphere.scattering_mu_size / 2;
  if (uvwz.z < 0.5f) {
    float d_min = r - atmosphere.bottom_radius;
    float d_max = rho;
    float x = unwarp_mu_range(unit_range_from_texture_coord(1.0f - 2.0f * uvwz.z, half_mu_size),
                              mu_warp_k(atmosphere, d_min, d_max));
    float d = d_min + (d_max - d_min) * x;
    // d² + 2 r mu d + r² = R_bottom², and R_bottom² - r² = -rho².
    mu = d == 0.0f ? -1.0f : clamp_cosine(-(rho * rho + d * d) / (2.0f * r * d));
    ray_r_mu_intersects_ground = true;
  } else {
    float d_min = atmosphere.top_radius - r;
    float d_max = rho + H;
    float x = unwarp_mu_range(unit_range_from_texture_coord(2.0f * uvwz.z - 1.0f, half_mu_size),
                              mu_warp_k(atmosphere, d_min, d_max));
    float d = d_min + (d_max - d_min) * x;
    mu = d == 0.0f ? 1.0f : clamp_cosine((H * H - rho * rho - d * d) / (2.0f * r * d));
    ray_r_mu_intersects_ground = false;
  }

  mu_s = mu_s_from_unit_range(atmosphere, unit_range_from_texture_coord(uvwz.y, atmosphere.scattering_mu_s_size));

  nu = nu_from_unit_range(atmosphere, uvwz.x);
}

// The 4D table is stored as a 3D texture: width = nu_size tiles of mu_s_size
// texels, height = mu, depth = r (the 4D table tiled in 3D of Elek & Kmoch
// 2010, §3).
// `texel` is the texel index (integer part) of a 3D texel centre.
INLINE vec4 scattering_uvwz_from_texel(IN(AtmosphereParams) atmosphere, vec3 texel) {
  float nu_index = floor(texel.x / float(atmosphere.scattering_mu_s_size));
  float mu_s_index = texel.x - nu_index * float(atmosphere.scattering_mu_s_size);
  return vec4(nu_index / float(atmosphere.scattering_nu_size - 1),
              (mu_s_index + 0.5f) / float(atmosphere.scattering_mu_s_size),
              (texel.y + 0.5f) / float(atmosphere.scattering_mu_size),
              (texel.z + 0.5f) / float(atmosphere.scattering_r_size));
}

// The nu of a texel's tile, before the clamping below: the abscissa that the
// linear interpolation between nu tiles assumes.
INLINE float scattering_texel_tile_nu(IN(AtmosphereParams) atmosphere, vec3 texel) {
  return nu_from_unit_range(atmosphere, scattering_uvwz_from_texel(atmosphere, texel).x);
}

// nu is bounded by the angles of the view and sun directions to the zenith:
// texels outside the possible range hold the value of the nearest possible
// geometry.
INLINE float clamp_nu(float mu, float mu_s, float nu) {
  float spread = safe_sqrt((1.0f - mu * mu) * (1.0f - mu_s * mu_s));
  return clamp(nu, mu * mu_s - spread, mu * mu_s + spread);
}

INLINE void r_mu_mu_s_nu_from_scattering_texel(IN(AtmosphereParams) atmosphere, vec3 texel, OUT(float) r,
                                               OUT(float) mu, OUT(float) mu_s, OUT(float) nu,
                                               OUT(bool) ray_r_mu_intersects_ground) {
  r_mu_mu_s_nu_from_scattering_uvwz(atmosphere, scattering_uvwz_from_texel(atmosphere, texel), r, mu, mu_s, nu,
                                    ray_r_mu_intersects_ground);
  nu = clamp_nu(mu, mu_s, nu);
}

// Height above the ground of radius row `row` of the scattering tables:
// rho_i = H rho_fraction(x_r = i / (N_r - 1)), and h_i = r_i - R_bottom =
// rho_i^2 / (r_i + R_bottom) without the cancellation of r_i - R_bottom in
// float.
INLINE float scattering_row_height(IN(AtmosphereParams) atmosphere, int row) {
  float rho = horizon_length_at_top(atmosphere) *
              rho_fraction_from_scattering_x_r(atmosphere, float(row) / float(atmosphere.scattering_r_size - 1));
  float bottom = atmosphere.bottom_radius;
  return rho * rho / (sqrt(rho * rho + bottom * bottom) + bottom);
}

// Texture coordinate u_r of radius row `row` of the scattering tables.
INLINE float scattering_row_u_r(IN(AtmosphereParams) atmosphere, int row) {
  return texture_coord_from_unit_range(float(row) / float(atmosphere.scattering_r_size - 1),
                                       atmosphere.scattering_r_size);
}

// Irradiance table: (r, mu_s), mu_s as in the scattering table. The sky
// irradiance falls by about ten times per 3° of sun depression in twilight;
// a linear mu_s axis (3.2° per texel at 64 texels) overestimates it there by
// up to 30 %.
//
// The r axis is linear in the altitude h (Bruneton's), except in optically
// thick atmospheres (scattering_r_optical_depth_weight w > 0). There the sky
// light changes within a few kilometres of the ground, where terrain is lit:
// 16 linear rows, 6.7 km apart on Venus, give it 4 / 8 / 15 % too low at
// 1 km (680 / 550 / 440 nm, against 128 rows; the profile is concave).
// So there the axis is
//   x_r = (1 - w) log(1 + h / h_0) / log(1 + h_top / h_0) + w tau_part(h),
// h_0 = IRRADIANCE_R_LOG_SCALE_FRACTION of the atmosphere's thickness h_top,
// and tau_part the optical depth part of the scattering table's r axis
// (scattering_x_r_from_rho_fraction minus its rho / H part), so that the
// rows crowd near the ground without the square root of rho / H (whose
// infinite slope at the ground puts a third of a row into the lowest 200 m:
// 5-15 % too much light there on Venus; tau_part keeps it only below its
// first knot, the lowest 60-100 m) and still follow the optical depth into
// a cloud deck: Venus's 16 rows agree with 128 within 2.4 % from 200 m to
// 10 km (tests/presets_test.cpp). The inverse is a bisection (the
// precomputation's texel centres only).
#define IRRADIANCE_R_LOG_SCALE_FRACTION 0.01f

INLINE float irradiance_x_r(IN(AtmosphereParams) atmosphere, float r) {
  float thickness = atmosphere.top_radius - atmosphere.bottom_radius;
  float w = atmosphere.scattering_r_optical_depth_weight;
  if (w == 0.0f) return (r - atmosphere.bottom_radius) / thickness;
  float h = clamp(r - atmosphere.bottom_radius, 0.0f, thickness);
  float s = clamp(horizon_length(atmosphere, r) / horizon_length_at_top(atmosphere), 0.0f, 1.0f);
  float log_part = log(1.0f + h / (IRRADIANCE_R_LOG_SCALE_FRACTION * thickness)) /
                   log(1.0f + 1.0f / IRRADIANCE_R_LOG_SCALE_FRACTION);
  return (1.0f - w) * log_part + (scattering_x_r_from_rho_fraction(atmosphere, s) - (1.0f - w) * s);
}

INLINE float irradiance_r_from_x_r(IN(AtmosphereParams) atmosphere, float x_r) {
  float thickness = atmosphere.top_radius - atmosphere.bottom_radius;
  if (atmosphere.scattering_r_optical_depth_weight == 0.0f) return atmosphere.bottom_radius + x_r * thickness;
  float lo = 0.0f;
  float hi = thickness;
  for (int i = 0; i < 32; ++i) {
    float mid = 0.5f * (lo + hi);
    if (irradiance_x_r(atmosphere, atmosphere.bottom_radius + mid) < x_r) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return atmosphere.bottom_radius + 0.5f * (lo + hi);
}

INLINE vec2 irradiance_uv_from_r_mu_s(IN(AtmosphereParams) atmosphere, float r, float mu_s) {
  return vec2(texture_coord_from_unit_range(unit_range_from_mu_s(atmosphere, mu_s), atmosphere.irradiance_mu_s_size),
              texture_coord_from_unit_range(irradiance_x_r(atmosphere, r), atmosphere.irradiance_r_size));
}

// The two axes of the irradiance table are independent: r depends on the
// texture's v only and mu_s on its u only, so a precomputation can take the r
// of a row once (for thick atmospheres it is a bisection).
INLINE float irradiance_r_from_v(IN(AtmosphereParams) atmosphere, float v) {
  return irradiance_r_from_x_r(atmosphere, unit_range_from_texture_coord(v, atmosphere.irradiance_r_size));
}

INLINE float irradiance_mu_s_from_u(IN(AtmosphereParams) atmosphere, float u) {
  return mu_s_from_unit_range(atmosphere, unit_range_from_texture_coord(u, atmosphere.irradiance_mu_s_size));
}

INLINE void r_mu_s_from_irradiance_uv(IN(AtmosphereParams) atmosphere, vec2 uv, OUT(float) r, OUT(float) mu_s) {
  r = irradiance_r_from_v(atmosphere, uv.y);
  mu_s = irradiance_mu_s_from_u(atmosphere, uv.x);
}
