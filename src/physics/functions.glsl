// atmos — the scattering physics, defined once.
//
// Compiled as C++ for the CPU precomputation, the CPU lookups of `atmos sample`
// and the tests (physics/shader_cpp.hpp), and as GLSL for the renderer
// (gpu/shader_source.cpp). The language subset is described at the top of
// definitions.glsl.
//
// Conventions. A ray starts at a point at distance r from the planet centre
// and has direction v; mu = cos(v, zenith), mu_s = cos(sun, zenith) at the
// point, nu = cos(v, sun). "The radiance of a ray" is the radiance arriving at
// the start point from direction v (looking along v). Radiance in
// W m^-2 sr^-1 nm^-1 per working wavelength; irradiance in W m^-2 nm^-1.
//
// The model is the one of seed 000 §3 (Bruneton & Neyret 2008) with multiple
// scattering by successive orders (seed 004 §4.2), and the table
// parameterisation of Bruneton 2017 ("Precomputed Atmospheric Scattering: a
// New Implementation"): distances to the atmosphere boundaries, with the
// horizon split of mu into rays that hit the ground and rays that do not.

// ===========================================================================
// 1. Ray geometry
// ===========================================================================

INLINE float clamp_cosine(float mu) { return clamp(mu, -1.0f, 1.0f); }

INLINE float safe_sqrt(float a) { return sqrt(max(a, 0.0f)); }

INLINE float clamp_radius(IN(AtmosphereParams) atmosphere, float r) {
  return clamp(r, atmosphere.bottom_radius, atmosphere.top_radius);
}

// Distance from radius r along mu to the top-of-atmosphere sphere (exit
// point). The discriminant r²(mu²-1) + R_top² is written as
// (r mu)² + (R_top - r)(R_top + r) so that it does not lose its digits to
// cancellation near the boundary.
INLINE float distance_to_top_atmosphere_boundary(IN(AtmosphereParams) atmosphere, float r, float mu) {
  float discriminant = (r * mu) * (r * mu) + (atmosphere.top_radius - r) * (atmosphere.top_radius + r);
  return max(-r * mu + safe_sqrt(discriminant), 0.0f);
}

// Distance from radius r along mu to the ground sphere (first hit); only
// meaningful when ray_intersects_ground().
INLINE float distance_to_bottom_atmosphere_boundary(IN(AtmosphereParams) atmosphere, float r, float mu) {
  float discriminant = (r * mu) * (r * mu) - (r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius);
  return max(-r * mu - safe_sqrt(discriminant), 0.0f);
}

INLINE bool ray_intersects_ground(IN(AtmosphereParams) atmosphere, float r, float mu) {
  return mu < 0.0f &&
         (r * mu) * (r * mu) - (r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius) >= 0.0f;
}

INLINE float distance_to_nearest_atmosphere_boundary(IN(AtmosphereParams) atmosphere, float r, float mu,
                                                     bool ray_r_mu_intersects_ground) {
  if (ray_r_mu_intersects_ground) return distance_to_bottom_atmosphere_boundary(atmosphere, r, mu);
  return distance_to_top_atmosphere_boundary(atmosphere, r, mu);
}

// Radius and cosines at distance t along the ray (r, mu), for the sun at
// (mu_s, nu): plain geometry in the plane of the ray (nu is constant along it).
INLINE float radius_along_ray(float r, float mu, float t) { return sqrt(t * t + 2.0f * r * mu * t + r * r); }
INLINE float mu_along_ray(float r, float mu, float t, float r_t) { return (r * mu + t) / r_t; }
INLINE float mu_s_along_ray(float r, float mu_s, float nu, float t, float r_t) { return (r * mu_s + t * nu) / r_t; }

// Cosine of the zenith angle of the geometric horizon seen from radius r.
INLINE float horizon_mu(IN(AtmosphereParams) atmosphere, float r) {
  return -safe_sqrt((r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius)) / r;
}

// ===========================================================================
// 2. The medium
// ===========================================================================

INLINE float profile_density(IN(DensityProfile) profile, float altitude) {
  if (profile.scale_height > 0.0f) return exp(-altitude / profile.scale_height);
  // Piecewise linear between the knots, 0 outside them: the first segment
  // that contains the altitude. A loop of constant length (DENSITY_KNOT_BOUND:
  // in shaders the most knots of the atmosphere's constituents, see
  // shader_source.cpp) without early exits. Shader compilers do not fold the
  // atmosphere's constants through the function calls, and software
  // rasterisers run every iteration and both sides of every branch anyway:
  // a loop bounded by the profile's own count, with a return inside, cost
  // the aerial-perspective volume 3x its time on llvmpipe.
  float density = 0.0f;
  bool found = false;
  for (int i = 1; i < DENSITY_KNOT_BOUND; ++i) {
    float a0 = profile.knot_altitude[i - 1];
    float a1 = profile.knot_altitude[i];
    bool inside = !found && i < profile.knot_count && altitude >= a0 && altitude <= a1;
    float t = clamp((altitude - a0) / max(a1 - a0, 1e-30f), 0.0f, 1.0f);
    density = inside ? mix(profile.knot_density[i - 1], profile.knot_density[i], t) : density;
    found = found || inside;
  }
  return density;
}

// Scattering coefficients of the Rayleigh-phase and aerosol-phase
// constituents, and the total extinction (scattering + absorption), at radius r.
INLINE void medium_at(IN(AtmosphereParams) atmosphere, float r, OUT(vec3) rayleigh_scattering,
                      OUT(vec3) aerosol_scattering, OUT(vec3) extinction) {
  rayleigh_scattering = vec3(0.0f);
  aerosol_scattering = vec3(0.0f);
  extinction = vec3(0.0f);
  float altitude = r - atmosphere.bottom_radius;
  for (int i = 0; i < CONSTITUENT_COUNT(atmosphere); ++i) {
    float density = profile_density(atmosphere.density[i], altitude);
    vec3 scattering = atmosphere.scattering[i] * density;
    if (atmosphere.is_aerosol[i] != 0) {
      aerosol_scattering += scattering;
    } else {
      rayleigh_scattering += scattering;
    }
    extinction += scattering + atmosphere.absorption[i] * density;
  }
}

INLINE vec3 extinction_at(IN(AtmosphereParams) atmosphere, float r) {
  vec3 rayleigh;
  vec3 aerosol;
  vec3 extinction;
  medium_at(atmosphere, r, rayleigh, aerosol, extinction);
  return extinction;
}

// Optical depth of the segment [t0, t1] of the ray (r, mu): trapezoidal rule
// with `steps` steps (seed 000 eq. 3.8).
INLINE vec3 optical_depth_along_ray(IN(AtmosphereParams) atmosphere, float r, float mu, float t0, float t1, int steps) {
  float dt = (t1 - t0) / float(steps);
  vec3 result = vec3(0.0f);
  for (int i = 0; i <= steps; ++i) {
    float t = t0 + float(i) * dt;
    float weight = (i == 0 || i == steps) ? 0.5f : 1.0f;
    result += extinction_at(atmosphere, clamp_radius(atmosphere, radius_along_ray(r, mu, t))) * (weight * dt);
  }
  return result;
}

// ===========================================================================
// 3. Phase functions (each integrates to 1 over the sphere)
// ===========================================================================

// Seed 000 eq. 3.2.
INLINE float rayleigh_phase_function(float nu) { return 3.0f / (16.0f * PI) * (1.0f + nu * nu); }

INLINE float henyey_greenstein_phase_function(float g, float nu) {
  float k = 1.0f + g * g - 2.0f * g * nu;
  return (1.0f - g * g) / (4.0f * PI * k * sqrt(k));
}

// Seed 000 eq. 3.5 (Cornette & Shanks 1992).
INLINE float cornette_shanks_phase_function(float g, float nu) {
  float k = 1.0f + g * g - 2.0f * g * nu;
  return 3.0f / (8.0f * PI) * (1.0f - g * g) * (1.0f + nu * nu) / ((2.0f + g * g) * k * sqrt(k));
}

// Two-term Henyey-Greenstein (Kattawar 1975): w HG(g) + (1 - w) HG(g_back).
INLINE float double_henyey_greenstein_phase_function(float g, float g_back, float w, float nu) {
  return w * henyey_greenstein_phase_function(g, nu) + (1.0f - w) * henyey_greenstein_phase_function(g_back, nu);
}

// The aerosol phase function per channel (its parameters may differ between
// the channels' wavelengths, see AtmosphereParams).
INLINE vec3 aerosol_phase_function(IN(AtmosphereParams) atmosphere, float nu) {
  vec3 p;
  for (int c = 0; c < 3; ++c) {
    float g = atmosphere.aerosol_g[c];
    if (atmosphere.aerosol_phase_kind == PHASE_CORNETTE_SHANKS) {
      p[c] = cornette_shanks_phase_function(g, nu);
    } else if (atmosphere.aerosol_phase_kind == PHASE_DOUBLE_HENYEY_GREENSTEIN) {
      p[c] = double_henyey_greenstein_phase_function(g, atmosphere.aerosol_g_back[c],
                                                     atmosphere.aerosol_forward_weight[c], nu);
    } else {
      p[c] = henyey_greenstein_phase_function(g, nu);
    }
  }
  return p;
}

// ===========================================================================
// 4. Table coordinates
// ===========================================================================

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
// ground light there converges only slowly with their number (at 680 nm
// 9.3, 8.5, 8.2 % of the sunlight with 32, 64, 128 texels, the reference
// 7.8 %; with the axis below 7.1 and 7.9 % with 32 and 64, and at 550 nm
// 5.1 % with 32 against the reference's 5.1 %). So there the axis is
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
// horizontal. Measured against the brute-force reference (tests/venus_accuracy.cpp):
// see make_atmosphere_params for the choice of w.
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
// scaled) changes fastest next to the sun. Measured on the "mars" dust
// against the reference, 6 orders, sun 60/10/2° up, RMS beyond 20° of the
// sun: 9.4/8.1/11.8 % in angle, 9.8/20/30 % uniform in nu (worst 19/31/57 %
// against 19/73/122 %; within 20° of the sun 6.5/20/26 % against
// 4.5/11/19 %). Earth's clear sky is better uniform in nu (0.45 % against
// 0.57 % RMS at sun 60°, 4.55 % against 4.91 % in twilight at sun -5°), and
// so is Venus's energy balance (out / in 1.10 against 1.15,
// tests/presets_test.cpp).
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
// texels, height = mu, depth = r (seed 004 §3, "4D table tiled in 3D").
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

// Irradiance table: (r, mu_s), mu_s as in the scattering table. The sky
// irradiance falls by about ten times per 3° of sun depression in twilight;
// a linear mu_s axis (3.2° per texel at 64 texels) overestimates it there by
// up to 30 %.
//
// The r axis is linear in the altitude h (Bruneton's), except in optically
// thick atmospheres (scattering_r_optical_depth_weight w > 0). There the sky
// light changes within a few kilometres of the ground, where terrain is lit:
// with 16 linear rows, 6.7 km apart on Venus, it came out 4 / 8 / 15 % low
// at 1 km (680 / 550 / 440 nm, against 128 rows; the profile is concave).
// So there the axis is
//   x_r = (1 - w) log(1 + h / h_0) / log(1 + h_top / h_0) + w tau_part(h),
// h_0 = IRRADIANCE_R_LOG_SCALE_FRACTION of the atmosphere's thickness h_top,
// and tau_part the optical depth part of the scattering table's r axis
// (scattering_x_r_from_rho_fraction minus its rho / H part), so that the
// rows crowd near the ground without the square root of rho / H (whose
// infinite slope at the ground put a third of a row into the lowest 200 m:
// 5-15 % too much light there on Venus; tau_part keeps it only below its
// first knot, the lowest 60-100 m) and still follow the optical depth into
// a cloud deck. Venus's 16 rows now agree with 128 within 2.4 % from 200 m
// to 10 km (tests/presets_test.cpp). The inverse is a bisection (the
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

// ===========================================================================
// 5. Table lookups
// ===========================================================================

// The transmittance table holds the optical depth τ to the top of the
// atmosphere (seed 000 eq. 3.8), T = exp(-τ). Storing τ rather than T makes
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
// at the horizon), and the difference made the transmittance of the 40 m
// to the ground jump between 0.7 and 1 from one pixel to the next
// (concentric bands on the ground of the noon image). Where the larger
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

// Node k of the quadrature over the visible part of a uniform solar disc at
// zenith cosine mu_s, seen from a point whose horizon is at mu_h. Disc
// points at elevation offset x alpha from the centre (x in [-1, 1]) form a
// chord of relative length sqrt(1 - x²); with x = cos θ the visible part
// (x above the horizon) is θ in [0, θ_h] and the disc average of f is
//   (2 / π) ∫_0^θ_h sin²θ f(cos θ) dθ,
// integrated by the midpoint rule on SUN_DISC_NODES intervals — for the
// whole disc (θ_h = π) the integrand is periodic and the rule gives the
// disc's moments exactly (mean offset 0, variance alpha² / 4; 4-point
// Gauss-Legendre is off by 12 % in the variance, which is what the average
// is for); for part of the disc the weights are rescaled to sum to the exact
// visible fraction. Returns the zenith cosine of the node and its weight. The node's sine of elevation is
// sin(e + δ) = mu_s cos δ + sqrt(1 - mu_s²) sin δ with δ = alpha cos θ <= 0.3°,
// where cos δ = 1 - δ²/2 and sin δ = δ to 1e-9; and for a disc wholly above
// the horizon (the common case) cos θ and sin θ are constants: no
// trigonometry, which the precomputation calls for most texels near the
// horizon.
INLINE float sun_disc_node(IN(AtmosphereParams) atmosphere, float mu_s, float mu_h, int k, OUT(float) weight) {
  float alpha = atmosphere.sun_angular_radius;
  // cos θ_k and sin θ_k for θ_h = π: θ_k = 22.5°, 67.5°, 112.5°, 157.5°.
  bool outer = k == 0 || k == 3;
  float cos_theta = outer ? 0.9238795325f : 0.3826834324f;
  float sin_theta = outer ? 0.3826834324f : 0.9238795325f;
  if (k >= 2) cos_theta = -cos_theta;
  float theta_h = PI;
  if (mu_s - mu_h <= alpha) {
    // Part of the disc may be below the horizon (|d mu / d angle| <= 1).
    float x_h = clamp((asin(clamp_cosine(mu_h)) - asin(clamp_cosine(mu_s))) / alpha, -1.0f, 1.0f);
    theta_h = acos(x_h);
    float theta = theta_h * (float(k) + 0.5f) / float(SUN_DISC_NODES);
    cos_theta = cos(theta);
    sin_theta = sin(theta);
  }
  weight = theta_h / float(SUN_DISC_NODES) * sin_theta * sin_theta * (2.0f / PI);
  if (theta_h < PI && theta_h > 1e-4f) {
    // Rescale to the exact visible fraction, (θ_h - sin θ_h cos θ_h) / π;
    // the midpoint sum of sin² is N / 2 - sin 2θ_h / (4 sin(θ_h / N)).
    float n = float(SUN_DISC_NODES);
    float midpoint_sum = theta_h / n * (2.0f / PI) * (0.5f * n - sin(2.0f * theta_h) / (4.0f * sin(theta_h / n)));
    weight *= (theta_h - 0.5f * sin(2.0f * theta_h)) / PI / midpoint_sum;
  }
  float delta = alpha * cos_theta;
  return clamp_cosine(mu_s * (1.0f - 0.5f * delta * delta) + safe_sqrt(1.0f - mu_s * mu_s) * delta);
}

// Transmittance from radius r to the sun, including the planet's shadow:
// the mean over the solar disc of the transmittance of the unobstructed
// rays to its points (a uniform disc; seed 000 §3 uses a point sun).
INLINE vec3 transmittance_to_sun(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                 float mu_s) {
  float mu_h = horizon_mu(atmosphere, r);
  if (!sun_needs_disc_average(atmosphere, mu_s, mu_h))
    return transmittance_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, mu_s);
  if (mu_s - mu_h < -atmosphere.sun_angular_radius) return vec3(0.0f);
  vec3 sum = vec3(0.0f);
  for (int k = 0; k < SUN_DISC_NODES; ++k) {
    float weight;
    float mu_k = sun_disc_node(atmosphere, mu_s, mu_h, k, weight);
    sum += weight * transmittance_to_top_atmosphere_boundary(atmosphere, transmittance_texture, r, mu_k);
  }
  return sum;
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
// brighter for being longer. Seen from 2 m above Venus's ground the ground
// darkened towards its horizon, to 0.13 of the brute-force reference's
// radiance 4 km away, where the reference brightens into the haze as bright
// as the sky above the horizon (tests/venus_accuracy.cpp).
// Instead:
//  1. The ray of row 1 that reaches the ground after the SAME distance d
//     (same_length_ground_ray_lookup) runs through the same lowest air down
//     to the ground, so its light s_1 saturates as the ray's does.
//  2. It starts higher, and near the ground the light changes fast with
//     height: a dark ground sends little up (on Venus a ray 0.5° above
//     the horizon is 0.58 as bright from 2 m as from 330 m; reference),
//     dense haze dims the sunlight. The grazing rays of rows 0 and 1 (grazing_ray_lookup, g_0
//     and g_1) measure that change between the ground and h_1, and s_1 is
//     scaled by (g_0 / g_1)^e, with e the fraction of h_1 between where row
//     1's ray and the camera's ray collect their light: e = (1 - h / h_1)
//     (1/2 + 1/2 min(s_1 / g_1, 1)). A ray whose light is far from
//     saturated (s_1 << g_1) collects it all along its descent, around
//     h_1 / 2; a saturated one near its start, h_1.
// The ratio g_0 / g_1 is kept within [1/2, 2]. The value is continuous at
// h_1, where it is the table's own. Measured: Venus from 2 m, 20 m and 107 m,
// the ground 100 m to 4 km away: 1.00-1.07 of the reference (the plain
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
// sun, the in-scatter 115 m away was 23 % short with it, 14 % without
// (tests/aerial_perspective_accuracy.cpp), although steep rays came nearer
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

// ===========================================================================
// 6. Precomputation integrands
// ===========================================================================

// Number of Simpson intervals along a ray for single scattering (whose
// integrand has the sharp edge of the planet's shadow) and for multiple
// scattering (smooth).
#define SINGLE_SCATTERING_INTERVALS 32
#define MULTIPLE_SCATTERING_INTERVALS 16
#define MAX_RAY_NODES 41
// Cells of the piecewise-linear importance density that places the nodes.
#define RAY_MAP_CELLS 128
// The run-time integration of single scattering (scattering_along_ray):
// fewer nodes, placed by the integrand itself (sunlit_ray_map).
#define RUNTIME_SINGLE_SCATTERING_INTERVALS 16
#define RUNTIME_RAY_MAP_CELLS 32
// Array capacities of RayMap and RayNodes: the precomputation's sizes, unless
// RAY_ARRAYS_FOR_RUNTIME is defined (the shaders, which only run the run-time
// integration: every fragment holds these arrays in private memory, and a
// software rasteriser spends more time on 129-element arrays than on the
// integration itself). The integration does not depend on the capacity.
#ifdef RAY_ARRAYS_FOR_RUNTIME
#define RAY_MAP_CAPACITY RUNTIME_RAY_MAP_CELLS
#define RAY_NODES_CAPACITY (RUNTIME_SINGLE_SCATTERING_INTERVALS + 1)
#else
#define RAY_MAP_CAPACITY RAY_MAP_CELLS
#define RAY_NODES_CAPACITY MAX_RAY_NODES
#endif
// Share of the nodes of the sunlit map spread uniformly (see sunlit_ray_map).
#ifndef SUNLIT_FLOOR_FRACTION
#define SUNLIT_FLOOR_FRACTION 0.1f
#endif

// Simpson's rule weight of node i of n intervals of width dt (n even).
INLINE float simpson_weight(int i, int n, float dt) {
  float w = (i == 0 || i == n) ? 1.0f : ((i % 2 == 1) ? 4.0f : 2.0f);
  return w * dt / 3.0f;
}

// Quadrature nodes of an integral along the ray (r, mu) from its start to
// distance d, with the transmittance from the start folded into the weights:
//   ∫ T(x, x + t v) f(t) dt ≈ Σ_i weight_i f(t_i).
// Uniform nodes would waste most of their samples: the scattering medium can
// be much thinner than the ray (a 1.2 km aerosol layer under a 100 km
// atmosphere: Simpson's rule on 40 uniform intervals overestimates it by
// 6 %), and in twilight only a short, high stretch of the ray is sunlit. So
// the nodes are placed at equal steps of the cumulative integral of an
// importance density w(t) plus a uniform floor: with t = t(s) and
// dt/ds = W / w(t), the integrand in s is f / w, which is smooth wherever f
// follows w. w is piecewise linear on `cells` (<= RAY_MAP_CAPACITY) equal cells,
// and t(s) inverts its exact (piecewise quadratic) integral, so that dt/ds is
// the true derivative of the map. Two importance densities:
//  - extinction_ray_map: the extinction times the transmittance from the
//    start, for integrands that follow the medium whatever the sun (the
//    precomputation, which shares the nodes of a view ray between all sun
//    directions);
//  - sunlit_ray_map: the single-scattering integrand itself (scattering
//    coefficient x transmittance from the start x transmittance to the sun),
//    which follows the planet's shadow and the reddened grazing sunlight.
struct RayNodes {
  int count;
  float t[RAY_NODES_CAPACITY];
  vec3 weight[RAY_NODES_CAPACITY];
};

struct RayMap {
  int cells;
  float cell;  // cell length, m
  float w[RAY_MAP_CAPACITY + 1];
  // The extinction at the cell boundaries and the optical depth from the
  // start to them (exponential_segment_integral), which give the
  // transmittance at the nodes too.
  vec3 extinction[RAY_MAP_CAPACITY + 1];
  vec3 optical_depth[RAY_MAP_CAPACITY + 1];
};

// The integral over [0, h] of the exponential through (0, a) and (h, b),
// per component: h (b - a) / ln(b / a). Exact for extinctions and
// single-scattering integrands along a steep ray, where the density of each
// constituent falls exponentially with the distance; for grazing rays the
// exponent bends with the ray's curvature (relative error ~h² / (8 R H) in
// the exponent: 0.5 % over 18 km for a 1.2 km scale height). Used by the
// ray maps below and by the plugin's aerial-perspective march
// (gpu/composite.glsl). Where a and b are nearly equal
// (the limit, without 0 / 0) or one is zero (the edge of the planet's
// shadow: no exponential passes through a zero), the trapezoid.
INLINE vec3 exponential_segment_integral(vec3 a, vec3 b, float h) {
  vec3 trapezoid = 0.5f * h * (a + b);
  vec3 q = log(max(b, vec3(1e-30f)) / max(a, vec3(1e-30f)));
  vec3 exponential = h * (b - a) / max(abs(q), vec3(1e-3f)) * sign(q);
  vec3 use = vec3(greaterThan(abs(q), vec3(1e-3f))) * vec3(greaterThan(min(a, b), vec3(1e-30f)));
  return mix(trapezoid, exponential, use);
}

// The exponential through (0, a) and (1, b) at f in [0, 1], per component
// (linear where an end is zero, as exponential_segment_integral).
INLINE vec3 exponential_interpolation(vec3 a, vec3 b, float f) {
  vec3 ratio = max(b, vec3(1e-30f)) / max(a, vec3(1e-30f));
  vec3 use = vec3(greaterThan(min(a, b), vec3(1e-30f)));
  return mix(mix(a, b, f), a * pow(ratio, vec3(f)), use);
}

// The ray maps take the extinction as exponential within a cell, not linear:
// along a slanted ray the altitude grows about linearly and the constituents
// fall off exponentially with altitude. A cell of the run time's maps spans
// kilometres of altitude on a ray a few degrees up (22 km of ray, 2.3 km of
// altitude at 6°: a whole scale height of a continental aerosol), where the
// trapezoid overestimated the optical depth by 11 % and dimmed everything
// beyond it (single scattering 7-10 % low at 6-15° elevation).

INLINE RayMap extinction_ray_map(IN(AtmosphereParams) atmosphere, float r, float mu, float d, int cells,
                                 float flat_depth) {
  RayMap map;
  map.cells = cells;
  map.cell = d / float(cells);
  vec3 optical_depth = vec3(0.0f);
  for (int k = 0; k <= cells; ++k) {
    vec3 e = extinction_at(atmosphere, clamp_radius(atmosphere, radius_along_ray(r, mu, float(k) * map.cell)));
    if (k > 0) optical_depth += exponential_segment_integral(map.extinction[k - 1], e, map.cell);
    map.extinction[k] = e;
    map.optical_depth[k] = optical_depth;
    // The extinction that the start of the ray still sees: in a dense medium
    // the light scattered towards the start comes from its first optical
    // depths only, and nodes spread over the rest (each holding many optical
    // depths) would make the quadrature overestimate it by orders of
    // magnitude — energy created at every scattering order. Over the first
    // `flat_depth` optical depths the density is the extinction alone
    // (nodes uniform in optical depth), then it falls as the transmittance.
    vec3 visible = e * exp(-max(optical_depth - vec3(flat_depth), vec3(0.0f)));
    map.w[k] = visible.x + visible.y + visible.z;
  }
  return map;
}

INLINE RayMap sunlit_ray_map(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r, float mu,
                             float mu_s, float nu, float d, int cells, IN(Moons) moons, vec3 origin, vec3 view_ray,
                             vec3 sun_direction) {
  RayMap map;
  map.cells = cells;
  map.cell = d / float(cells);
  vec3 optical_depth = vec3(0.0f);
  vec3 previous_extinction = vec3(0.0f);
  for (int k = 0; k <= cells; ++k) {
    float t = float(k) * map.cell;
    float r_t = clamp_radius(atmosphere, radius_along_ray(r, mu, t));
    vec3 beta_rayleigh;
    vec3 beta_aerosol;
    vec3 extinction;
    medium_at(atmosphere, r_t, beta_rayleigh, beta_aerosol, extinction);
    if (k > 0) optical_depth += exponential_segment_integral(previous_extinction, extinction, map.cell);
    previous_extinction = extinction;
    map.extinction[k] = extinction;
    map.optical_depth[k] = optical_depth;
    vec3 f = (beta_rayleigh + beta_aerosol) * exp(-optical_depth) *
             transmittance_to_sun(atmosphere, transmittance_texture, r_t,
                                  clamp_cosine(mu_s_along_ray(r, mu_s, nu, t, r_t))) *
             uniform_sunlight_visible_fraction(moons, atmosphere.sun_angular_radius, origin + view_ray * t,
                                               sun_direction);
    map.w[k] = f.x + f.y + f.z;
  }
  return map;
}

INLINE RayNodes ray_integration_nodes_from_map(float d, IN(RayMap) map, float floor_fraction, int intervals) {
  RayNodes nodes;
  nodes.count = intervals + 1;
  if (!(d > 0.0f)) {
    // A ray of zero length (leaving the top straight away): nothing to integrate.
    for (int i = 0; i < RAY_NODES_CAPACITY; ++i) {
      nodes.t[i] = 0.0f;
      nodes.weight[i] = vec3(0.0f);
    }
    return nodes;
  }
  int cells = map.cells;
  float cell = map.cell;
  float w[RAY_MAP_CAPACITY + 1];
  float cumulative[RAY_MAP_CAPACITY + 1];
  float mean = 0.0f;
  for (int k = 0; k <= cells; ++k) mean += map.w[k] * ((k == 0 || k == cells) ? 0.5f : 1.0f) / float(cells);
  float floor_density = floor_fraction * mean + 1e-30f;
  cumulative[0] = 0.0f;
  for (int k = 0; k <= cells; ++k) {
    w[k] = map.w[k] + floor_density;
    if (k > 0) cumulative[k] = cumulative[k - 1] + 0.5f * (w[k - 1] + w[k]) * cell;
  }
  float total = cumulative[cells];
  int k = 0;
  for (int i = 0; i <= intervals; ++i) {
    float target = total * float(i) / float(intervals);
    while (k < cells - 1 && cumulative[k + 1] < target) ++k;
    // Solve cumulative[k] + w_k x + a x² / 2 = target for x in the cell.
    float a = (w[k + 1] - w[k]) / cell;
    float c = max(target - cumulative[k], 0.0f);
    float x = min(2.0f * c / (w[k] + safe_sqrt(w[k] * w[k] + 2.0f * a * c)), cell);
    float t = i == intervals ? d : float(k) * cell + x;
    float density = w[k] + a * x;
    nodes.t[i] = t;
    // The optical depth from the cells (nodes can be many cells apart where
    // w is small, e.g. the dense, dark bottom of a ray in the planet's
    // shadow: the transmittance keeps the resolution of the cells).
    vec3 e = exponential_interpolation(map.extinction[k], map.extinction[k + 1], x / cell);
    vec3 optical_depth = map.optical_depth[k] + exponential_segment_integral(map.extinction[k], e, x);
    float weight = simpson_weight(i, intervals, 1.0f / float(intervals)) * total / density;
    nodes.weight[i] = exp(-optical_depth) * weight;
  }
  return nodes;
}

// Extinction-placed nodes from the start of the ray to the nearest atmosphere
// boundary, with the full resolution of the precomputation. The floor (a
// quarter of the mean) keeps a share of the nodes where the air is thin.
INLINE RayNodes ray_integration_nodes(IN(AtmosphereParams) atmosphere, float r, float mu,
                                      bool ray_r_mu_intersects_ground, int intervals) {
  float d = distance_to_nearest_atmosphere_boundary(atmosphere, r, mu, ray_r_mu_intersects_ground);
  return ray_integration_nodes_from_map(d, extinction_ray_map(atmosphere, r, mu, d, RAY_MAP_CELLS, 0.0f), 0.25f,
                                        intervals);
}

// Nodes and weights of the integral of a source function S = J / beta_ext
// along the ray (r, mu) to the nearest atmosphere boundary,
//   L = ∫ T(x, x + t v) beta_ext(t) S(t) dt ≈ Σ_i weight_i S(t_i),
// the nodes and Simpson weights of ray_integration_nodes (placed by the
// extinction that the start of the ray sees) times the extinction at the
// node, scaled so that they add up to ∫ T beta_ext dt = 1 - T(d) exactly
// (per channel): a uniform source function — the diffuse light deep in a
// conservative cloud — is then transported without gain or loss, whatever
// the optical thickness between nodes. Unscaled, the sum was off by -5..+8 %
// of 1 - T(d) on the view rays of a Venus table (5-14 optical depths of
// cloud between radius samples, up to 12 per cell of the ray map), which
// lost or created light at every one of the hundreds of orders that reach
// its ground. (The linear-source rule of short-characteristics solvers,
// Olson & Kunasz 1987, JQSRT 38, 325, is exact for a uniform source too, but
// only second order: the twilight sky of the Earth, whose source changes
// along the ray with the planet's shadow, came out worse with it, RMS 5.5 %
// instead of 4.5 % from the ground with the sun 5° down.) On the view rays of
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
// there. Measured against the reference on 100x Earth's air alone (3.6
// optical depths at 680 nm, black ground): the radiance of orders 1 + 2 on
// the ground was 15-29 % too high above 20° elevation with nodes uniform in
// 1 - T, within -5..+2 % with these. The sky light on the ground of the full
// 100x Earth at 680 nm (16 optical depths) was 0.84 of the reference with
// 32 radius texels and 0.74 with 64, an error that more texels made worse;
// with these nodes 1.16 and 1.04, converging with the texels (128 intervals
// with the old placement: 1.12 and 1.00, at 2.6x the precomputation time).
// More in parameters.hpp.
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
// faults in an optically thick atmosphere, measured against the
// plane-parallel adding-doubling reference (reference_plane_parallel_fluxes)
// on Venus, default sizes, sun 40° up:
//  - where the rows are optical depths apart (Venus's cloud deck: 2-3.4),
//    the chord between two rows cuts the curvature off each order's source
//    (its rise below the sunlit top, the bump of light diffusing through),
//    and a little of every order is lost: over the hundreds of orders of a
//    nearly conservative cloud, the tables reflected 0.89 of the
//    reference's light to space;
//  - near the ground u_r follows rho ~ sqrt(altitude), so a source linear in
//    u_r rises like a square root above the ground row, too much source just
//    above the ground: in the 42 optical depths of Venus's air at 440 nm the
//    sky light on the ground was 1.55 of the reference's (linear in altitude
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
// Measured (Venus, default sizes, sun 40° up, 680 / 550 / 440 nm; the
// azimuthal mean of the radiance leaving the top straight down, and the
// light on the ground): reflected 0.99 / 0.99 / 0.99 of the reference, on
// the ground 0.96 / 1.00 / 1.10 (linear: 0.90 / 0.91 / 0.91 and 0.95 / 1.03
// / 1.55). Tried (with a finer r axis map of 129 knots, where this scheme
// gave 1.00 and 1.00 / 1.03 / 1.10): Catmull-Rom in u_r (uniform in the row
// index) 1.00 reflected and 1.02 / 1.06 / 1.20 on the ground; Hermite in
// altitude 1.02 and 1.18 / 1.12 / 1.07; linear in altitude, on the air
// alone, 0.98 / 0.90 / 0.68 on the ground.
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
// zenith sky of 4 orders came out 1e-9 of what linear interpolation gives,
// most of it clamped away from negative values; the Monte Carlo reference
// gives 0.1 of the linear value there): where the two rows around r differ
// by more than SOURCE_FLOOR_RATIO, the result is kept above the smaller,
// the lowest value a source monotone between them can take (the floor
// brought that sky to 0.6 of the reference). Only there: the floor adds
// light, and applied wherever the cubic dips below a row it added 2 % to the
// green sky light on Venus's ground over 600 orders of small tables, more
// than the tail solver, which applies the same weights without any floor
// (its operator must stay linear), found for the same orders.
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

// Direct ground irradiance: the sun's irradiance on a horizontal surface at
// radius r (order 0 of the ground lighting).
INLINE vec3 compute_direct_irradiance(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                      float mu_s) {
  return atmosphere.solar_irradiance * transmittance_to_sun(atmosphere, transmittance_texture, r, mu_s) * max(mu_s, 0.0f);
}

// A documented approximation for the multiple-scattered light under an
// eclipse (eclipse.glsl). The tables hold multiple scattering for a fully
// lit planet; under a moon's shadow the light scattered more than once at a
// point was first scattered (or reflected) elsewhere, so it is dimmed by how
// much sunlight reaches the point's surroundings, not the point itself.
// Model: the light reaching `point` comes from the air around it along
// horizontal lines (the atmosphere is a layer far wider than thick). Light
// scattered at distance s along such a line arrives with a weight per
// octave of distance (a ring of area 2 pi s ds, spread over 4 pi s²) times
// the scattering coefficient there relative to the point's (the line rises
// above the curved ground: s²/2R) times the transmittance back along it.
// The visible fraction of the diffuse light is then the mean of
// uniform_sunlight_visible_fraction over the point itself (weight 1, the
// light from within the first ring) and over rings of radii
// DIFFUSE_RING_FIRST x 2^k, k < DIFFUSE_RINGS (8 to 512 km), 4 points each
// along and across the sun's azimuth, with those weights. What it gets
// right: nothing inside the umbra's core receives diffuse light from its
// surroundings at first hand, light reaches into the umbra from the
// penumbra around it over the horizontal transmittance, which is longer
// higher up, and the ground and the lower sky of a wide umbra stay lit from
// hundreds of kilometres away. What it leaves out: the direction the diffuse
// light comes from (it is dimmed as a whole, the tables' angular shape is
// kept) and the light from above and below the point's horizontal plane
// (folded into the point's own weight). Against the brute-force reference
// with moons (tests/eclipse_accuracy.cpp: Earth, totality under a 0.28°
// moon, the sun 40° up), the eclipsed sky of all orders comes out within
// -27..+13 %: the zenith +5 % (4e-4 of the daylight zenith), the horizon
// ring 12-27 % too dark.
#define DIFFUSE_RINGS 7
#define DIFFUSE_RING_FIRST 8000.0f
INLINE float diffuse_light_visible_fraction(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                            IN(Moons) moons, vec3 point, vec3 sun_direction) {
  if (moons.count == 0) return 1.0f;
  float a = atmosphere.sun_angular_radius;
  float r = clamp_radius(atmosphere, length(point));
  vec3 up = point / length(point);
  vec3 along = sun_direction - up * dot(sun_direction, up);
  if (dot(along, along) < 1e-8f) along = abs(up.x) < 0.9f ? cross(up, vec3(1.0f, 0.0f, 0.0f))
                                                          : cross(up, vec3(0.0f, 1.0f, 0.0f));
  along = normalize(along);
  vec3 across = cross(up, along);
  vec3 beta_rayleigh;
  vec3 beta_aerosol;
  vec3 extinction;
  medium_at(atmosphere, r, beta_rayleigh, beta_aerosol, extinction);
  vec3 scattering = beta_rayleigh + beta_aerosol;
  float source = scattering.x + scattering.y + scattering.z;
  float total = uniform_sunlight_visible_fraction(moons, a, point, sun_direction);
  float weights = 1.0f;
  float s = DIFFUSE_RING_FIRST;
  for (int ring = 0; ring < DIFFUSE_RINGS; ++ring) {
    float r_ring = sqrt(r * r + s * s);
    vec3 transmittance = r_ring < atmosphere.top_radius
                             ? transmittance_along_ray(atmosphere, transmittance_texture, r, 0.0f, s, false)
                             : vec3(0.0f);
    medium_at(atmosphere, clamp_radius(atmosphere, r_ring), beta_rayleigh, beta_aerosol, extinction);
    scattering = (beta_rayleigh + beta_aerosol) * transmittance;
    float weight = source > 0.0f ? (scattering.x + scattering.y + scattering.z) / source : 0.0f;
    float ring_sum = 0.0f;
    for (int j = 0; j < 4; ++j) {
      vec3 direction = j == 0 ? along : j == 1 ? -along : j == 2 ? across : -across;
      ring_sum += uniform_sunlight_visible_fraction(moons, a, point + direction * s, sun_direction);
    }
    total += weight * 0.25f * ring_sum;
    weights += weight;
    s *= 2.0f;
  }
  return total / weights;
}

// Single scattering summed over quadrature nodes along the ray (r, mu) with
// the sun at (mu_s, nu), without phase functions (see
// compute_single_scattering). With moons (eclipse.glsl; `origin` and
// `view_ray` place the ray in space, |origin| = r) each node receives the
// fraction of the sun's light they leave it (sunlight_visible_fraction).
INLINE void single_scattering_over_nodes(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                         float r, float mu, float mu_s, float nu, IN(RayNodes) nodes,
                                         IN(Moons) moons, vec3 origin, vec3 view_ray, vec3 sun_direction,
                                         OUT(vec3) rayleigh, OUT(vec3) aerosol) {
  rayleigh = vec3(0.0f);
  aerosol = vec3(0.0f);
  // Read once (C++: the outputs could alias the moons as far as the
  // compiler knows, which would reload the count at every node).
  bool eclipse = moons.count > 0;
  for (int i = 0; i < nodes.count; ++i) {
    float r_t = clamp_radius(atmosphere, radius_along_ray(r, mu, nodes.t[i]));
    float mu_s_t = clamp_cosine(mu_s_along_ray(r, mu_s, nu, nodes.t[i], r_t));
    vec3 beta_rayleigh;
    vec3 beta_aerosol;
    vec3 extinction;
    medium_at(atmosphere, r_t, beta_rayleigh, beta_aerosol, extinction);
    vec3 light = nodes.weight[i] * transmittance_to_sun(atmosphere, transmittance_texture, r_t, mu_s_t);
    if (eclipse) {
      light *= sunlight_visible_fraction(moons, atmosphere.sun_angular_radius, origin + view_ray * nodes.t[i],
                                         sun_direction);
    }
    rayleigh += light * beta_rayleigh;
    aerosol += light * beta_aerosol;
  }
  rayleigh *= atmosphere.solar_irradiance;
  aerosol *= atmosphere.solar_irradiance;
}

// The factor that dims the multiple scattering along a ray under an
// eclipse: the mean of diffuse_light_visible_fraction along it, weighted by
// the light each part of the ray sends towards its start (extinction x
// transmittance, from `map`'s cells, which are uniform along the ray and
// independent of the sunlight). That fraction varies over tens of
// kilometres, so it is evaluated at the weighted centres of the
// DIFFUSE_VISIBILITY_BINS equal runs of cells only. 1 without moons.
#define DIFFUSE_VISIBILITY_BINS 2
INLINE float ray_diffuse_visibility(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                    IN(RayMap) map, IN(Moons) moons, vec3 origin, vec3 view_ray,
                                    vec3 sun_direction) {
  float total_weight = 0.0f;
  float visible = 0.0f;
  for (int b = 0; b < DIFFUSE_VISIBILITY_BINS && moons.count > 0; ++b) {
    float weight = 0.0f;
    float distance = 0.0f;
    for (int k = b * map.cells / DIFFUSE_VISIBILITY_BINS; k < (b + 1) * map.cells / DIFFUSE_VISIBILITY_BINS; ++k) {
      vec3 sent = map.extinction[k] * exp(-map.optical_depth[k]);
      float w = sent.x + sent.y + sent.z;
      weight += w;
      distance += w * (float(k) + 0.5f) * map.cell;
    }
    float t = weight > 0.0f ? distance / weight : 0.0f;
    visible += weight * diffuse_light_visible_fraction(atmosphere, transmittance_texture, moons,
                                                       origin + view_ray * t, sun_direction);
    total_weight += weight;
  }
  return total_weight > 0.0f ? visible / total_weight : 1.0f;
}

// Single scattering of the ray (r, mu), up to the atmosphere's boundary,
// with the sun at (mu_s, nu), without its phase function (applied per pixel
// so that the aerosol halo stays sharp): seed 000 eq. 3.13 with j reduced to
// the direct sunlight,
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

// Single scattering of the ray (r, mu) from its start to distance d, with
// nodes placed by the integrand itself (sunlit_ray_map, `cells` cells,
// `intervals` Simpson intervals): the run-time form, which stays accurate in
// twilight, where the lit part of the ray is short and far and the table's
// interpolation in mu_s is not (the radiance switches on over a fraction of
// a degree of sun elevation there). With moons, as single_scattering_over_nodes
// (the nodes then follow the moons' shadows too), and `diffuse_visibility`
// is ray_diffuse_visibility (1 without moons).
INLINE void integrate_single_scattering(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                        float mu, float mu_s, float nu, float d, int intervals, int cells,
                                        IN(Moons) moons, vec3 origin, vec3 view_ray, vec3 sun_direction,
                                        OUT(vec3) rayleigh, OUT(vec3) aerosol, OUT(float) diffuse_visibility) {
  RayMap map = sunlit_ray_map(atmosphere, transmittance_texture, r, mu, mu_s, nu, d, cells, moons, origin, view_ray,
                              sun_direction);
  RayNodes nodes = ray_integration_nodes_from_map(d, map, SUNLIT_FLOOR_FRACTION, intervals);
  single_scattering_over_nodes(atmosphere, transmittance_texture, r, mu, mu_s, nu, nodes, moons, origin, view_ray,
                               sun_direction, rayleigh, aerosol);
  diffuse_visibility =
      ray_diffuse_visibility(atmosphere, transmittance_texture, map, moons, origin, view_ray, sun_direction);
}

// Simpson intervals of the multiple scattering's view rays: 16, and 32 in
// optically thick atmospheres (those whose mu axis is warped, see
// scattering_u_mu). One set of nodes serves the three wavelengths of a
// table, and deep in a cloud they see the light from different depths (on
// Venus the CO2 under the cloud is 7 optical depths thick at 680 nm and 42
// at 440 nm): the nodes placed for all three leave each fewer of its own.
// Measured against the reference on Venus at 550 nm (tests/venus_accuracy.cpp,
// default sizes): with the preset's 680/550/440 nm the ground gets 0.82 of
// the reference's light with 16 intervals and 0.96 with 32 (549.5/550/550.5
// nm with 16: 1.06, +-12 %; ratios to that test's 2000-path reference of
// the time, which later runs of 16000 paths put 1.24 times too high); the
// precomputation's multiple scattering step costs twice as much (Venus at
// 15 wavelengths, auto orders: 181 s in all instead of 152 s).
INLINE int multiple_scattering_intervals(IN(AtmosphereParams) atmosphere) {
  return atmosphere.scattering_mu_log_weight > 0.0f ? 2 * MULTIPLE_SCATTERING_INTERVALS
                                                    : MULTIPLE_SCATTERING_INTERVALS;
}

// Multiple scattering of one order along the ray (r, mu): seed 000 eq. 3.13,
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

// Radiance of single scattering from the tables' values without phase
// functions (single Rayleigh, or Rayleigh + multiple / P_R, and single aerosol),
// channel by channel. In the spectral mode the aerosol value is not quite
// phase-free: it holds the ratio of the sum over wavelengths to this phase
// function (see spectral_single_scattering and precompute.cpp), so that this
// product restores each wavelength's own phase function.
INLINE vec3 phase_weighted_scattering(IN(AtmosphereParams) atmosphere, vec3 rayleigh, vec3 aerosol, float nu) {
  return rayleigh * rayleigh_phase_function(nu) + aerosol * aerosol_phase_function(atmosphere, nu);
}

// Sun zenith cosine at the ground point x + d v that the ray (r, mu) hits at
// distance d, whose normal is (x + d v) / R_bottom.
INLINE float mu_s_at_ground(IN(AtmosphereParams) atmosphere, float r, float mu_s, float nu, float d) {
  return clamp_cosine((r * mu_s + d * nu) / atmosphere.bottom_radius);
}

// Radiance of the Lambertian ground under `irradiance`.
INLINE vec3 ground_radiance(IN(AtmosphereParams) atmosphere, vec3 irradiance) {
  return atmosphere.ground_albedo * (1.0f / PI) * irradiance;
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

// Direction with zenith cosine mu and azimuth phi from the sun's vertical
// plane, in a frame where the zenith is z and the sun is in the x-z plane.
INLINE vec3 direction_from_mu_phi(float mu, float phi) {
  float s = safe_sqrt(1.0f - mu * mu);
  return vec3(s * cos(phi), s * sin(phi), mu);
}

// Straightforward scattering density of order `order` + 1 at radius r for the
// direction (mu, nu) with the sun at mu_s (seed 000 eq. 3.14):
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

// ===========================================================================
// 7. Rendering: radiance reaching a camera
// ===========================================================================

// The tables a renderer reads:
//  - transmittance_texture: transmittance to the top of the atmosphere;
//  - scattering_texture: single Rayleigh scattering plus all multiple
//    scattering divided by the Rayleigh phase function (so one lookup and one
//    phase function give both);
//  - single_aerosol_texture: single aerosol scattering without phase function;
//  - multiple_scattering_texture: the multiple scattering alone, divided by
//    the Rayleigh phase function (for the low-sun path of sky_radiance);
//  - irradiance_texture: indirect (sky) irradiance on a horizontal surface.

// Moves a camera outside the atmosphere to where its view ray enters it.
// Returns false when the ray misses the atmosphere. `camera` is relative to
// the planet centre. The ray-sphere test uses the perpendicular distance of
// the ray to the centre, which keeps its precision for cameras at hundreds of
// planet radii.
INLINE bool enter_atmosphere(IN(AtmosphereParams) atmosphere, INOUT(vec3) camera, vec3 view_ray) {
  float r = length(camera);
  if (r <= atmosphere.top_radius) return true;
  float rmu = dot(camera, view_ray);
  vec3 closest = camera - view_ray * rmu;
  float discriminant = atmosphere.top_radius * atmosphere.top_radius - dot(closest, closest);
  if (rmu >= 0.0f || discriminant < 0.0f) return false;
  float distance_to_top = -rmu - sqrt(discriminant);
  camera = camera + view_ray * distance_to_top;
  return true;
}

// The low-sun path. The 4D tables interpolate linearly in mu_s between
// texels about 1° of sun elevation apart near the horizon, and with the sun
// low on some part of a view ray its single scattering switches on over a
// fraction of a degree (the planet's shadow and the grazing, reddened
// sunlight): the interpolation is then off by up to 60 %. Where the sun is
// lower than LOW_SUN_MU_S_TABLE at some point of the view ray, single
// scattering is integrated along the ray instead (integrate_single_scattering,
// nodes placed by the integrand), and only the smooth multiple scattering is
// read from its table; between LOW_SUN_MU_S_MARCHED and LOW_SUN_MU_S_TABLE the
// two are blended so that no seam appears when the sun moves. Above, the
// tables agree with the reference to about 1 %.
#define LOW_SUN_MU_S_MARCHED 0.1045285f  // sin 6°
#define LOW_SUN_MU_S_TABLE 0.1736482f    // sin 10°

// Zenith cosine of the sun at the far end (distance d) of the ray (r, mu).
INLINE float mu_s_at_ray_end(float r, float mu, float mu_s, float nu, float d) {
  return mu_s_along_ray(r, mu_s, nu, d, radius_along_ray(r, mu, d));
}

// Weight of the low-sun path for a ray whose ends see the sun at mu_s and
// mu_s_end: 1 when the sun is below 6° somewhere on it, 0 above 10°
// everywhere. The sun elevation is lowest at one end of the ray: with
// mu_s(t) = N(t) / r(t), N linear and r(t) convex, N - c r is concave for
// c >= 0, so its minimum is at an end.
INLINE float low_sun_weight(float mu_s, float mu_s_end) {
  return 1.0f - smoothstep(LOW_SUN_MU_S_MARCHED, LOW_SUN_MU_S_TABLE, min(mu_s, mu_s_end));
}

// Whether no point of a ray whose ends see the sun below mu_s_min is lit:
// such points are in the planet's shadow cylinder (the sun more than 2°
// below the horizon of any point of the atmosphere, see mu_s_min), and a
// segment between two points of a convex set stays in it.
INLINE bool ray_in_planet_shadow(IN(AtmosphereParams) atmosphere, float mu_s, float mu_s_end) {
  return max(mu_s, mu_s_end) < atmosphere.mu_s_min;
}

// Single scattering of the ray (r, mu) up to distance d, integrated along
// it (integrate_single_scattering) for every wavelength triple of `spectral`
// and converted to the tables' channels: the run-time low-sun path. Nothing
// to integrate on the night side (ray_in_planet_shadow). With moons
// (eclipse.glsl), as integrate_single_scattering; `diffuse_visibility` is
// then the mean of the triples' (1 without moons, and on the night side).
// The aerosol phase function may change with wavelength inside a channel:
// `aerosol` is, per channel c, the phase-weighted sum over the wavelengths
// divided by the channel's phase function (that of `atmosphere`, the render
// parameters),
//   aerosol_c = Σ_λ M_cλ S_λ P_λ(nu) / P_c(nu),
// so that phase_weighted_scattering() gives Σ_λ M_cλ S_λ P_λ(nu) exactly (the
// form of the single aerosol table, precompute.cpp). In the three-wavelength
// mode P_λ = P_c and this is S itself.
INLINE void spectral_single_scattering(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                       IN(sampler2D) spectral_transmittance_texture, float r, float mu, float mu_s,
                                       float nu, float d, IN(Moons) moons, vec3 origin, vec3 view_ray,
                                       vec3 sun_direction, OUT(vec3) rayleigh, OUT(vec3) aerosol,
                                       OUT(float) diffuse_visibility) {
  rayleigh = vec3(0.0f);
  aerosol = vec3(0.0f);
  diffuse_visibility = 1.0f;
  if (ray_in_planet_shadow(atmosphere, mu_s, mu_s_at_ray_end(r, mu, mu_s, nu, d))) return;
  float visibility_sum = 0.0f;
  for (int k = 0; k < SPECTRAL_COUNT(spectral); ++k) {
    vec3 set_rayleigh;
    vec3 set_aerosol;
    float set_visibility;
    // Sunlight through the delta-M scaled medium.
    integrate_single_scattering(with_scaled_transmittance(spectral.set[k]), spectral_transmittance_texture, r, mu, mu_s, nu, d,
                                RUNTIME_SINGLE_SCATTERING_INTERVALS, RUNTIME_RAY_MAP_CELLS, moons, origin, view_ray,
                                sun_direction, set_rayleigh, set_aerosol, set_visibility);
    rayleigh += spectral.to_channels[k] * set_rayleigh;
    aerosol += spectral.to_channels[k] * (set_aerosol * aerosol_phase_function(spectral.set[k], nu));
    visibility_sum += set_visibility;
  }
  aerosol /= aerosol_phase_function(atmosphere, nu);
  diffuse_visibility = visibility_sum / float(SPECTRAL_COUNT(spectral));
}

// The light scattered towards the start of the ray (r, mu) along it up to
// the ground or the top (d is that distance), without phase functions, in
// the form of the tables: `rayleigh` = single Rayleigh + multiple / P_R,
// `aerosol` = single aerosol; phase_weighted_scattering() gives the radiance.
// From the 4D tables with the sun high, integrated along the ray (single
// scattering) with the sun low, blended in between. The integration runs
// once per wavelength triple of `spectral` (each with its own medium and
// tile of `spectral_transmittance_texture`) and is converted to the tables'
// channels, so that twilight colours are those of the spectrum, not of three
// samples of it. `low_sun_path` false drops the integration (shaders pass a
// constant, see sun_may_be_low_on_view_rays: software rasterisers run both
// sides of every branch); it must be true wherever the sun may be low.
// Eclipses: with moons (eclipse.glsl; `origin`, `view_ray`: the ray in
// space, |origin| = r) single scattering is always integrated, node by node
// in the moons' shadows (low_sun_path must then be true), and the table's
// multiple scattering is dimmed by the ray's diffuse visibility (see
// ray_diffuse_visibility and diffuse_light_visible_fraction: a documented
// approximation).
INLINE void scattering_along_ray(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                 IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                                 IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                                 float r, float mu, float mu_s, float nu, bool ray_r_mu_intersects_ground, float d,
                                 bool low_sun_path, IN(Moons) moons, vec3 origin, vec3 view_ray,
                                 vec3 sun_direction, OUT(vec3) rayleigh, OUT(vec3) aerosol) {
  float mu_s_end = mu_s_at_ray_end(r, mu, mu_s, nu, d);
  float low_sun = low_sun_path ? (moons.count > 0 ? 1.0f : low_sun_weight(mu_s, mu_s_end)) : 0.0f;
  rayleigh = vec3(0.0f);
  aerosol = vec3(0.0f);
  if (low_sun < 1.0f) {
    rayleigh = (1.0f - low_sun) *
               ray_scattering_lookup(atmosphere, scattering_texture, r, mu, mu_s, nu, ray_r_mu_intersects_ground);
    aerosol = (1.0f - low_sun) *
              ray_scattering_lookup(atmosphere, single_aerosol_texture, r, mu, mu_s, nu, ray_r_mu_intersects_ground);
  }
  if (low_sun_path && low_sun > 0.0f) {
    vec3 single_rayleigh;
    vec3 single_aerosol;
    float diffuse_visibility;
    spectral_single_scattering(atmosphere, spectral, spectral_transmittance_texture, r, mu, mu_s, nu, d, moons,
                               origin, view_ray, sun_direction, single_rayleigh, single_aerosol, diffuse_visibility);
    vec3 multiple =
        ray_scattering_lookup(atmosphere, multiple_scattering_texture, r, mu, mu_s, nu, ray_r_mu_intersects_ground);
    rayleigh += low_sun * (single_rayleigh + diffuse_visibility * multiple);
    aerosol += low_sun * single_aerosol;
  }
}

// Transmittance in the tables' channels, from each wavelength triple's own
// (exact, multiplicative) transmittance T_k weighted by sunlight:
//   T_c = Σ_k (M_k (E_k ⊙ T_k))_c / (Σ_k M_k E_k)_c,
// with M_k = spectral.to_channels[k] and E_k the solar irradiance at triple
// k's wavelengths. In the three-wavelength mode this is T itself; in the
// spectral mode it is the factor that turns the sun's colour into the
// colour of the transmitted sun exactly (its disc, and its direct light on
// the ground), and approximates the attenuation of other colours (the lit
// ground behind the aerial perspective) by that of sunlight, as the tables'
// three channels must. It is a weighted mean of per-wavelength values, not a
// ratio of means (which a path split in two would need, and which is
// undefined where a reddened sun's blue falls out of the sRGB gamut); it is
// clamped at 0 for that case. `path`: to the top of the atmosphere (mu: a
// ray that does not hit the ground), to the ground (a ray that does), or to
// the sun (mu = mu_s; averaged over the solar disc, with the planet's
// shadow), or to the ground through the delta-M scaled medium (see
// single_scattering_tile): the transmittance of the light of the planet's
// ground, an extended source whose light scattered into the aerosol's
// forward peak stays in the beam (as the orders >= 2 assume; with the true
// transmittance the light the ground reflects would be partly lost, 6-18 %
// of the sunlight on white ground under the "mars" dust).
#define PATH_TO_TOP 0
#define PATH_TO_GROUND 1
#define PATH_TO_SUN 2
#define PATH_TO_GROUND_SCALED 3

INLINE vec3 channel_transmittance(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                  IN(sampler2D) spectral_transmittance_texture, int path, float r, float mu) {
  vec3 sum = vec3(0.0f);
  for (int k = 0; k < SPECTRAL_COUNT(spectral); ++k) {
    vec3 t;
    if (path == PATH_TO_GROUND) {
      t = transmittance_to_ground(spectral.set[k], spectral_transmittance_texture, r, mu);
    } else if (path == PATH_TO_GROUND_SCALED) {
      t = transmittance_to_ground(with_scaled_transmittance(spectral.set[k]), spectral_transmittance_texture, r, mu);
    } else if (path == PATH_TO_SUN) {
      t = transmittance_to_sun(spectral.set[k], spectral_transmittance_texture, r, mu);
    } else {
      t = transmittance_to_top_atmosphere_boundary(spectral.set[k], spectral_transmittance_texture, r, mu);
    }
    sum += spectral.to_channels[k] * (spectral.set[k].solar_irradiance * t);
  }
  return max(sum / max(atmosphere.solar_irradiance, vec3(1e-30f)), vec3(0.0f));
}

// The sky-view table: scattering_along_ray for one camera and sun, over view
// directions, recomputed every frame (the idea of Hillaire 2020's sky-view
// LUT). Integrating a low-sun ray costs ~50 evaluations of the medium and of
// the transmittance to the sun — seconds per frame for a full screen on a
// software rasteriser. But for a given camera and sun a view ray is fixed by
// its direction, so a small 2D table over directions holds the result, with
// mu_s exact; the render pass then reads 2 texels per pixel instead of the
// 4 (3D) texels of the 4D tables. Parameterisation:
//  - x: azimuth phi in [0, π] from the sun's vertical plane (the radiance is
//    symmetric about it), linear; in [-π, π] for an eclipse, which breaks
//    the symmetry (SkyViewFrame.full_azimuth);
//  - y: view zenith angle, split at the ground's horizon like the scattering
//    table's mu (ground rays below 0.5, the others above, so that the
//    discontinuity falls between texels), each half with texels concentrated
//    towards the horizon (x = sqrt of the normalised angle from it), between
//    the nadir and the horizon for ground rays and between the horizon and
//    the zenith for the others.
// Texels hold view_ray_terms: the phase-free values of scattering_along_ray
// (phase functions are applied per pixel, so the sun's aerosol halo stays
// sharp) and what is at the ray's end (the lit ground sphere, or the
// transmittance to space for the sun disc), in three textures.
// Used for cameras in the atmosphere: from space, the lit atmosphere near the
// terminator spans a few degrees of view and the table blurs it (30 % errors
// at 2 planet radii), so rays are evaluated one by one there.
#define SKY_VIEW_WIDTH 96
#define SKY_VIEW_HEIGHT 256

struct SkyViewFrame {
  vec3 zenith;          // unit vector from the planet centre to the camera
  vec3 sun_side;        // horizontal unit vector towards the sun's azimuth
  vec3 across;          // zenith x sun_side
  float theta_horizon;  // view zenith angle of the ground's horizon
  // x spans the azimuth from -pi to pi instead of 0 to pi: for an eclipse,
  // whose moons' shadows are not symmetric about the sun's vertical plane
  // (at half the azimuthal resolution).
  bool full_azimuth;
};

// Whether a camera (relative to the planet centre) uses the sky-view table.
INLINE bool camera_uses_sky_view(IN(AtmosphereParams) atmosphere, vec3 camera) {
  return length(camera) <= atmosphere.top_radius;
}

// `camera` relative to the planet centre, at or above the ground.
INLINE SkyViewFrame sky_view_frame(IN(AtmosphereParams) atmosphere, vec3 camera, vec3 sun_direction) {
  SkyViewFrame frame;
  float r = length(camera);
  frame.zenith = camera / r;
  vec3 side = sun_direction - frame.zenith * dot(sun_direction, frame.zenith);
  if (dot(side, side) < 1e-10f) {
    // Sun at the zenith or nadir: every azimuth is the same, pick one.
    side = abs(frame.zenith.x) < 0.9f ? cross(frame.zenith, vec3(1.0f, 0.0f, 0.0f))
                                      : cross(frame.zenith, vec3(0.0f, 1.0f, 0.0f));
  }
  frame.sun_side = normalize(side);
  frame.across = cross(frame.zenith, frame.sun_side);
  // pi/2 + the horizon's dip, asin(rho / r): accurate near the ground, where
  // asin(R / r) ~ asin(1 - 3e-7) would lose most of its digits.
  frame.theta_horizon = 0.5f * PI + asin(horizon_length(atmosphere, r) / r);
  frame.full_azimuth = false;
  return frame;
}

// Texture coordinates of a view direction in a table of width x height
// texels with this parameterisation; `ground` says which half (the
// caller's ray_intersects_ground, so that both agree at the horizon). The
// engine plugin's aerial-perspective volume (gpu/composite.glsl) uses it
// with its own size.
INLINE vec2 sky_view_uv_of_size(IN(SkyViewFrame) frame, vec3 view_ray, bool ground, int width, int height) {
  float theta = acos(clamp_cosine(dot(view_ray, frame.zenith)));
  float across = dot(view_ray, frame.across);
  float x_phi = frame.full_azimuth ? 0.5f + 0.5f * atan(across, dot(view_ray, frame.sun_side)) / PI
                                   : atan(abs(across), dot(view_ray, frame.sun_side)) / PI;
  float v;
  if (ground) {
    float x = safe_sqrt((theta - frame.theta_horizon) / max(PI - frame.theta_horizon, 1e-7f));
    v = 0.5f - 0.5f * texture_coord_from_unit_range(min(x, 1.0f), height / 2);
  } else {
    float x = safe_sqrt((frame.theta_horizon - theta) / frame.theta_horizon);
    v = 0.5f + 0.5f * texture_coord_from_unit_range(min(x, 1.0f), height / 2);
  }
  return vec2(texture_coord_from_unit_range(x_phi, width), v);
}

INLINE vec2 sky_view_uv(IN(SkyViewFrame) frame, vec3 view_ray, bool ground) {
  return sky_view_uv_of_size(frame, view_ray, ground, SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT);
}

// The view direction of texture coordinates uv in a table of width x
// height texels, and whether its ray is in the ground half.
INLINE vec3 sky_view_direction_of_size(IN(SkyViewFrame) frame, vec2 uv, int width, int height, OUT(bool) ground) {
  float theta;
  ground = uv.y < 0.5f;
  if (ground) {
    float x = unit_range_from_texture_coord(1.0f - 2.0f * uv.y, height / 2);
    theta = frame.theta_horizon + x * x * (PI - frame.theta_horizon);
  } else {
    float x = unit_range_from_texture_coord(2.0f * uv.y - 1.0f, height / 2);
    theta = frame.theta_horizon * (1.0f - x * x);
  }
  float x_phi = unit_range_from_texture_coord(uv.x, width);
  float phi = frame.full_azimuth ? PI * (2.0f * x_phi - 1.0f) : PI * x_phi;
  return frame.zenith * cos(theta) + (frame.sun_side * cos(phi) + frame.across * sin(phi)) * sin(theta);
}

INLINE vec3 sky_view_direction(IN(SkyViewFrame) frame, vec2 uv, OUT(bool) ground) {
  return sky_view_direction_of_size(frame, uv, SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT, ground);
}

// A camera below the ground counts as standing on it (as in
// radiance_along_view_ray).
INLINE vec3 camera_above_ground(IN(AtmosphereParams) atmosphere, vec3 camera) {
  float r = length(camera);
  return r < atmosphere.bottom_radius ? camera * (atmosphere.bottom_radius / r) : camera;
}

// Irradiance on a surface at radius r whose local zenith is `up`, with
// normal `normal`: returns the sun's, and the sky's in `sky_irradiance`
// (the horizontal sky irradiance scaled by the fraction of the sky the
// surface sees, (1 + n.up) / 2).
INLINE vec3 sun_and_sky_irradiance_at(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                      IN(sampler2D) spectral_transmittance_texture,
                                      IN(sampler2D) irradiance_texture, float r, vec3 up, vec3 normal,
                                      vec3 sun_direction, OUT(vec3) sky_irradiance) {
  r = clamp_radius(atmosphere, r);
  float mu_s = clamp_cosine(dot(up, sun_direction));
  sky_irradiance = irradiance_lookup(atmosphere, irradiance_texture, r, mu_s) * (1.0f + dot(normal, up)) * 0.5f;
  return atmosphere.solar_irradiance *
         channel_transmittance(atmosphere, spectral, spectral_transmittance_texture, PATH_TO_SUN, r, mu_s) *
         max(dot(normal, sun_direction), 0.0f);
}

// The same for a surface at `point` (relative to the planet centre).
INLINE vec3 sun_and_sky_irradiance(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                   IN(sampler2D) spectral_transmittance_texture,
                                   IN(sampler2D) irradiance_texture, vec3 point, vec3 normal, vec3 sun_direction,
                                   OUT(vec3) sky_irradiance) {
  float r = length(point);
  return sun_and_sky_irradiance_at(atmosphere, spectral, spectral_transmittance_texture, irradiance_texture, r,
                                   point / r, normal,
                                   sun_direction, sky_irradiance);
}

// Solar limb darkening: SUN_LIMB_DARKENING_U, the linear law (eclipse.glsl).

// Radiance of the solar disc in direction `view_ray` (0 outside the disc;
// unit vectors). At angle theta from the disc's centre the line of sight
// meets the star where mu = sqrt(1 - sin²theta / sin²alpha) (alpha the
// angular radius; exact for a sphere). The centre's radiance makes the
// disc's radiance integrate to the solar irradiance: over the disc's solid
// angle Omega = 4 pi sin²(alpha/2), the law's mean is 1 - u/3 (the small-disc
// limit, relative error ~alpha²: 2e-5 for the Sun seen from the Earth).
// Rendered per pixel from each eye's own view ray, so stereo views get each
// their own correct disc.
INLINE vec3 sun_disc_radiance(IN(AtmosphereParams) atmosphere, vec3 view_ray, vec3 sun_direction) {
  float alpha = atmosphere.sun_angular_radius;
  // sin²theta from the cross product: cos theta against cos alpha (or
  // 1 - cos²theta) would lose the digits of a disc a few milliradians wide
  // (0.5 % of its area at the Earth's 4.65 mrad in float).
  vec3 c = cross(view_ray, sun_direction);
  float sin_alpha = sin(alpha);
  float rho2 = dot(c, c) / (sin_alpha * sin_alpha);  // (sin theta / sin alpha)²
  if (!(rho2 < 1.0f) || dot(view_ray, sun_direction) <= 0.0f) return vec3(0.0f);
  float mu = safe_sqrt(1.0f - rho2);
  float s = sin(0.5f * alpha);
  float centre = 1.0f / (4.0f * PI * s * s * (1.0f - SUN_LIMB_DARKENING_U / 3.0f));
  return atmosphere.solar_irradiance * (centre * (1.0f - SUN_LIMB_DARKENING_U * (1.0f - mu)));
}

// Radiance of the solar corona in direction `view_ray` (0 on the disc
// itself and in the other hemisphere): the white-light (K + F) corona of
// Baumbach (1937, Astron. Nachr. 263, 121; Allen's Astrophysical
// Quantities, 4th ed., §14.4), relative to the disc's mean radiance,
//   B(rho) / B_sun = 1e-6 (0.0532 rho^-2.5 + 1.425 rho^-7 + 2.565 rho^-17),
// rho the angular distance from the sun's centre in solar radii: 4e-6 at
// the limb, 1.1e-6 of the sun's light in all. The law is fitted out to a
// few solar radii; beyond, the F corona merges into the zodiacal light,
// which is not modelled: the corona fades out between 8 and 16 solar radii
// (where it is 3e-10 of the disc's radiance). It is always there, but the
// sky's own light drowns it except in totality, when a moon hides the disc
// (and the corona behind the moon itself: see radiance_along_view_ray).
// Coloured as the sun (the K corona is scattered photospheric light).
INLINE vec3 sun_corona_radiance(IN(AtmosphereParams) atmosphere, vec3 view_ray, vec3 sun_direction) {
  float alpha = atmosphere.sun_angular_radius;
  float sin_alpha = sin(alpha);
  vec3 c = cross(view_ray, sun_direction);
  float rho = sqrt(dot(c, c)) / sin_alpha;  // sin theta / sin alpha
  if (!(rho >= 1.0f) || !(rho < 16.0f) || dot(view_ray, sun_direction) <= 0.0f) return vec3(0.0f);
  float s = sin(0.5f * alpha);
  float mean_disc = 1.0f / (4.0f * PI * s * s);  // the disc's mean radiance per unit irradiance
  float relative = 1e-6f * (0.0532f * pow(rho, -2.5f) + 1.425f * pow(rho, -7.0f) + 2.565f * pow(rho, -17.0f)) *
                   (1.0f - smoothstep(8.0f, 16.0f, rho));
  return atmosphere.solar_irradiance * (mean_disc * relative);
}

// Whether the sun may be low (below LOW_SUN_MU_S_TABLE, where
// scattering_along_ray integrates single scattering) at some point of the
// view rays of a camera in the atmosphere. The sun's zenith angle at a point
// differs from the one above the camera by at most the angle between them
// seen from the planet centre, which for the points of the atmosphere the
// camera sees is at most acos(R / r) + acos(R / R_top) (the camera's horizon
// on the ground sphere plus the top's), here with 0.01 rad to spare for
// rounding. The sky-view table of a camera for which this is false needs no
// integration (a program variant without it: by day, the table in half the
// time).
INLINE bool sun_may_be_low_on_view_rays(IN(AtmosphereParams) atmosphere, vec3 camera, vec3 sun_direction) {
  float r = max(length(camera), atmosphere.bottom_radius);
  float reach = acos(atmosphere.bottom_radius / r) + acos(atmosphere.bottom_radius / atmosphere.top_radius);
  float sun_zenith = acos(clamp_cosine(dot(camera / r, sun_direction)));
  return sun_zenith + reach + 0.01f >= acos(LOW_SUN_MU_S_TABLE);
}

// What the sky-view table holds for one view ray from `camera` (in the
// atmosphere, at or above the ground): the phase-free scattering along it
// (scattering_along_ray: single Rayleigh + multiple / P_R, and single
// aerosol), and in `surface` what lies at its end — for a ray that meets the
// ground sphere, the radiance of the Lambertian ground lit by the sun and
// the sky (seed 000 §4.3.3) times the transmittance to it; for the others,
// the transmittance to the top of the atmosphere, which the sun disc needs.
// Everything that depends on the direction only, so that a sky pixel is
// three texture reads (radiance_along_view_ray) instead of the ~15 lookups
// of the transmittance and irradiance it would otherwise need per pixel.
// With moons (eclipse.glsl; low_sun_path must then be true) the scattering
// is eclipsed as scattering_along_ray says, and the ground receives the
// fraction of the sunlight the moons leave its point and the fraction
// diffuse_light_visible_fraction of the sky's light.
INLINE void view_ray_terms(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                           IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                           IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                           IN(sampler2D) irradiance_texture, vec3 camera, vec3 view_ray, vec3 sun_direction,
                           bool ground, bool low_sun_path, IN(Moons) moons, OUT(vec3) rayleigh, OUT(vec3) aerosol,
                           OUT(vec3) surface) {
  float r = clamp_radius(atmosphere, length(camera));
  float mu = clamp_cosine(dot(camera, view_ray) / r);
  float mu_s = clamp_cosine(dot(camera, sun_direction) / r);
  float nu = clamp_cosine(dot(view_ray, sun_direction));
  float d = distance_to_nearest_atmosphere_boundary(atmosphere, r, mu, ground);
  scattering_along_ray(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                       single_aerosol_texture, multiple_scattering_texture, r, mu, mu_s, nu, ground, d, low_sun_path,
                       moons, camera, view_ray, sun_direction, rayleigh, aerosol);
  if (ground) {
    vec3 point = camera + view_ray * d;
    vec3 normal = point / length(point);
    vec3 sky_irradiance;
    vec3 sun_irradiance = sun_and_sky_irradiance_at(atmosphere, spectral, spectral_transmittance_texture,
                                                    irradiance_texture, atmosphere.bottom_radius, normal, normal,
                                                    sun_direction, sky_irradiance);
    if (moons.count > 0) {
      vec3 ground_point = normal * atmosphere.bottom_radius;
      sun_irradiance *= sunlight_visible_fraction(moons, atmosphere.sun_angular_radius, ground_point, sun_direction);
      // The medium of the first wavelength triple (the render parameters of
      // the spectral mode have none: see make_render_params).
      sky_irradiance *= diffuse_light_visible_fraction(spectral.set[0], spectral_transmittance_texture, moons,
                                                       ground_point, sun_direction);
    }
    surface = channel_transmittance(atmosphere, spectral, spectral_transmittance_texture, PATH_TO_GROUND_SCALED, r,
                                    mu) *
              ground_radiance(atmosphere, sun_irradiance + sky_irradiance);
  } else {
    surface = channel_transmittance(atmosphere, spectral, spectral_transmittance_texture, PATH_TO_TOP, r, mu);
  }
}

// One texel of the sky-view table (uv at the texel centre) of the camera
// whose frame is `frame` (sky_view_frame, computed once per frame on the
// CPU, so that the table and its readers agree on the directions to the
// last bit): view_ray_terms of its view direction. `low_sun_path`:
// sun_may_be_low_on_view_rays for the camera (a constant in shaders), or
// true with moons, whose table must also span the full azimuth (the
// eclipse breaks the symmetry about the sun's vertical: see SkyViewFrame).
INLINE void compute_sky_view_texel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                   IN(sampler2D) spectral_transmittance_texture,
                                   IN(sampler3D) scattering_texture, IN(sampler3D) single_aerosol_texture,
                                   IN(sampler3D) multiple_scattering_texture, IN(sampler2D) irradiance_texture,
                                   IN(SkyViewFrame) frame, vec3 camera, vec3 sun_direction, vec2 uv,
                                   bool low_sun_path, IN(Moons) moons, OUT(vec3) rayleigh, OUT(vec3) aerosol,
                                   OUT(vec3) surface) {
  camera = camera_above_ground(atmosphere, camera);
  bool ground;
  vec3 view_ray = sky_view_direction(frame, uv, ground);
  // The half of the table decides, not the ray's own test: at the horizon
  // both must agree with the readers' ray_intersects_ground, which chose
  // this half.
  view_ray_terms(atmosphere, spectral, spectral_transmittance_texture, scattering_texture, single_aerosol_texture,
                 multiple_scattering_texture, irradiance_texture, camera, view_ray, sun_direction, ground,
                 low_sun_path, moons, rayleigh, aerosol, surface);
}

// Radiance scattered towards the camera along the view ray up to the top of
// the atmosphere or the ground (seed 000 eq. 3.13), and the transmittance of
// that path: scattering_along_ray for the ray itself (the GLSL library for
// engines). Excludes the sun disc and the light reflected by the ground.
INLINE vec3 sky_radiance(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                         IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                         IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                         vec3 camera, vec3 view_ray, vec3 sun_direction, OUT(vec3) transmittance) {
  transmittance = vec3(1.0f);
  vec3 start = camera;
  if (!enter_atmosphere(atmosphere, start, view_ray)) return vec3(0.0f);
  float r = clamp_radius(atmosphere, length(start));
  float mu = clamp_cosine(dot(start, view_ray) / r);
  float mu_s = clamp_cosine(dot(start, sun_direction) / r);
  float nu = clamp_cosine(dot(view_ray, sun_direction));
  bool ground = ray_intersects_ground(atmosphere, r, mu);
  transmittance = channel_transmittance(atmosphere, spectral, spectral_transmittance_texture,
                                        ground ? PATH_TO_GROUND : PATH_TO_TOP, r, mu);
  vec3 rayleigh;
  vec3 aerosol;
  scattering_along_ray(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                       single_aerosol_texture, multiple_scattering_texture, r, mu, mu_s, nu, ground,
                       distance_to_nearest_atmosphere_boundary(atmosphere, r, mu, ground), true, no_moons(), start,
                       view_ray, sun_direction, rayleigh, aerosol);
  return phase_weighted_scattering(atmosphere, rayleigh, aerosol, nu);
}

// Everything that reaches a camera along a view ray, for a spherical planet:
// the sky, or the Lambertian ground lit by sun and sky seen through the
// aerial perspective in front of it, plus (optionally) the sun disc with
// its corona, and the stars.
// `camera` is relative to the planet centre; a camera below the ground is
// treated as standing on it. With `use_sky_view` (the renderers, for a
// camera in the atmosphere: see camera_uses_sky_view) the view ray's terms
// come from this frame's sky-view table (three texture reads; `sky_view`:
// the table's frame); otherwise view_ray_terms evaluates them for the ray
// (the CPU sky model; cameras in space, from where the lit atmosphere near
// the terminator spans a few degrees that the table would blur). Shaders
// pass a constant, so that the compiler drops the path not taken: software
// rasterisers run both sides of a branch. With moons (eclipse.glsl) a moon
// in front hides the sun disc and the stars behind it and shows its own lit
// side (moon_radiance); with `moons_eclipse` (moons_may_eclipse) they also
// eclipse the view ray's terms (view_ray_terms; a sky-view table must be
// computed with the same moons).
INLINE vec3 radiance_along_view_ray(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                    IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                                    IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                                    IN(sampler2D) irradiance_texture, IN(sampler2D) sky_view_rayleigh_texture,
                                    IN(sampler2D) sky_view_aerosol_texture, IN(sampler2D) sky_view_surface_texture,
                                    bool use_sky_view, IN(SkyViewFrame) sky_view, vec3 camera, vec3 view_ray,
                                    vec3 sun_direction, bool include_sun_disc, IN(StarField) stars,
                                    IN(Moons) moons, bool moons_eclipse) {
  camera = camera_above_ground(atmosphere, camera);
  float nu = clamp_cosine(dot(view_ray, sun_direction));
  // The light from beyond the atmosphere along the ray: the sun disc and the
  // stars (stars.glsl), or a moon in front of them; attenuated below like
  // the sun.
  vec3 beyond = star_field_radiance(atmosphere, stars, view_ray);
  if (include_sun_disc) {
    beyond += sun_disc_radiance(atmosphere, view_ray, sun_direction) +
              sun_corona_radiance(atmosphere, view_ray, sun_direction);
  }
  int moon;
  float moon_distance = view_ray_moon_distance(moons, camera, view_ray, moon);
  if (moon >= 0) {
    beyond = moon_radiance(moons, moon, camera, view_ray, moon_distance, sun_direction, atmosphere.solar_irradiance);
  }
  vec3 start = camera;
  // Outside the atmosphere and missing it: only what is beyond.
  if (!enter_atmosphere(atmosphere, start, view_ray)) return beyond;
  float r = clamp_radius(atmosphere, length(start));
  bool ground = ray_intersects_ground(atmosphere, r, clamp_cosine(dot(start, view_ray) / r));
  vec3 rayleigh;
  vec3 aerosol;
  vec3 surface;
  if (use_sky_view) {
    vec2 uv = sky_view_uv(sky_view, view_ray, ground);
    rayleigh = vec3(texture(sky_view_rayleigh_texture, uv));
    aerosol = vec3(texture(sky_view_aerosol_texture, uv));
    surface = vec3(texture(sky_view_surface_texture, uv));
  } else {
    // Moons that cannot hide the sun from any point of the atmosphere
    // (moons_may_eclipse, decided per frame) are drawn but shadow nothing:
    // with none, view_ray_terms keeps the tables' single scattering.
    Moons shadowing = no_moons();
    if (moons_eclipse) shadowing = moons;
    view_ray_terms(atmosphere, spectral, spectral_transmittance_texture, scattering_texture, single_aerosol_texture,
                   multiple_scattering_texture, irradiance_texture, start, view_ray, sun_direction, ground, true,
                   shadowing, rayleigh, aerosol, surface);
  }
  vec3 radiance = phase_weighted_scattering(atmosphere, rayleigh, aerosol, nu);
  if (ground) return radiance + surface;
  return radiance + surface * beyond;
}
