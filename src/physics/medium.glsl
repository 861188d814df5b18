// atmos — the medium: the density profiles of the constituents, their
// scattering and extinction coefficients, the optical depth along a ray, the
// phase functions, and the Lambertian ground that bounds the medium.
//
// Needs: ray_geometry.glsl.

// The density of a constituent at `altitude`, relative to its reference
// density (DensityProfile).
INLINE float profile_density(IN(DensityProfile) profile, float altitude) {
  if (profile.knot_count == 0) return exp(-altitude / profile.scale_height);
  // Piecewise linear between the knots, 0 outside them: the first segment
  // that contains the altitude. A loop of constant length (DENSITY_KNOT_BOUND:
  // in shaders the most knots of the atmosphere's constituents, see
  // shader_source.cpp) without early exits, which the compiler can unroll;
  // the profile's knot count is a literal there, which removes the
  // iterations beyond it. A loop bounded by that count with a return inside
  // could not be unrolled, and software rasterisers run every iteration and
  // both sides of every branch anyway.
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
// with `steps` steps (Collienne 2013, eq. 3.8).
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

// --- Phase functions (each integrates to 1 over the sphere) ------------------

// Collienne 2013, eq. 3.2.
INLINE float rayleigh_phase_function(float nu) { return 3.0f / (16.0f * PI) * (1.0f + nu * nu); }

// Henyey & Greenstein 1941, with asymmetry parameter g = <cos θ>.
INLINE float henyey_greenstein_phase_function(float g, float nu) {
  float k = 1.0f + g * g - 2.0f * g * nu;
  return (1.0f - g * g) / (4.0f * PI * k * sqrt(k));
}

// Cornette & Shanks 1992 (Collienne 2013, eq. 3.5).
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

// Radiance of the Lambertian ground under `irradiance`.
INLINE vec3 ground_radiance(IN(AtmosphereParams) atmosphere, vec3 irradiance) {
  return atmosphere.ground_albedo * (1.0f / PI) * irradiance;
}
