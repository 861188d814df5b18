// atmos — light between a camera and a point: aerial perspective.
//
// Needs: view_ray_scattering.glsl (and the parts it needs). The engine
// plugin (gpu/composite.glsl) and the GLSL library for engines
// (gpu/engine_library.glsl) build on it.
//
// The 4D tables hold the light scattered towards the start of a ray along
// its whole length, up to the top of the atmosphere or the ground. The light
// scattered along a PART of the ray, up to a surface point P at distance t,
// is the difference of two table values (Schafhitzel, Falk & Ertl 2007,
// §4.2; Collienne 2013, §4.5.2; Bruneton & Neyret 2008, §4 "aerial
// perspective"):
//   S(x -> P) = S(x, v) - T(x, P) S(P, v),
// the ray from P in the same direction v being the rest of the camera's ray.
// Both lookups use the half of the table (rays that hit the ground or not)
// of the camera's ray, so that they describe the same ray.

// Transmittance between the start of the ray (r, mu) and the point at
// distance d along it, in the tables' channels: each wavelength triple's own
// transmittance, weighted by sunlight as channel_transmittance does (exact
// for sunlight, the colour of nearly everything an atmosphere attenuates).
INLINE vec3 channel_transmittance_along_ray(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                            IN(sampler2D) spectral_transmittance_texture, float r, float mu, float d,
                                            bool ray_r_mu_intersects_ground) {
  vec3 sum = vec3(0.0f);
  for (int k = 0; k < SPECTRAL_COUNT(spectral); ++k) {
    vec3 t = transmittance_along_ray(spectral.set[k], spectral_transmittance_texture, r, mu, d,
                                     ray_r_mu_intersects_ground);
    sum += spectral.to_channels[k] * (spectral.set[k].solar_irradiance * t);
  }
  return max(sum / max(atmosphere.solar_irradiance, vec3(1e-30f)), vec3(0.0f));
}

// The light scattered towards the start of a ray from its first part, in the
// form of the tables (phase-free): single Rayleigh, multiple / P_R (all
// orders >= 2, which the terrain's shadows do not cut: they are lit by the
// whole sky), and single aerosol. The split lets the plugin remove the single
// scattering of shadowed stretches (light shafts).
struct PathScattering {
  vec3 single_rayleigh;
  vec3 multiple;
  vec3 aerosol;
  vec3 transmittance;  // of the segment (tables' channels, see channel_transmittance_along_ray)
};

// The horizon fix (Bruneton 2017, GetSkyRadianceToPoint). At the horizon
// the tables switch from rays that end on the ground to rays that graze it
// and go on to space: both values are large and change fast there, and for
// a point close to the camera their difference is small — the subtraction
// amplifies the interpolation error of each lookup into a bright or dark
// line along the horizon. Rays above the horizon are therefore evaluated at
// least HORIZON_MARGIN_MU above it, where both lookups sit well inside their
// half of the table; the point moves with the ray (same distance t). The
// change is invisible: 0.004 in mu is 0.23°, over which the in-scatter of a
// near-horizontal segment hardly changes.
#define HORIZON_MARGIN_MU 0.004f

// S(x -> P) from the tables alone, for the ray (r, mu) and the point at
// distance t (clamped to the ray's end, d), both lookups in the half of the
// table that `ray_r_mu_intersects_ground` says. The end point's own sun
// angle follows from the geometry (mu_s_along_ray).
INLINE PathScattering table_scattering_to_distance(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                                   IN(sampler2D) spectral_transmittance_texture,
                                                   IN(sampler3D) scattering_texture,
                                                   IN(sampler3D) single_aerosol_texture,
                                                   IN(sampler3D) multiple_scattering_texture, float r, float mu,
                                                   float mu_s, float nu, float t, bool ray_r_mu_intersects_ground,
                                                   bool split) {
  float d = distance_to_nearest_atmosphere_boundary(atmosphere, r, mu, ray_r_mu_intersects_ground);
  t = clamp(t, 0.0f, d);
  float r_t = clamp_radius(atmosphere, radius_along_ray(r, mu, t));
  float mu_t = clamp_cosine(mu_along_ray(r, mu, t, r_t));
  float mu_s_t = clamp_cosine(mu_s_along_ray(r, mu_s, nu, t, r_t));
  vec3 transmittance = channel_transmittance_along_ray(atmosphere, spectral, spectral_transmittance_texture, r, mu, t,
                                                       ray_r_mu_intersects_ground);
  vec3 scattering_0 =
      ray_scattering_lookup(atmosphere, scattering_texture, r, mu, mu_s, nu, ray_r_mu_intersects_ground);
  vec3 scattering_t =
      ray_scattering_lookup(atmosphere, scattering_texture, r_t, mu_t, mu_s_t, nu, ray_r_mu_intersects_ground);
  // Without `split`, single Rayleigh and multiple stay summed in
  // single_rayleigh (two lookups fewer; shaders pass a constant).
  vec3 multiple_0 = vec3(0.0f);
  vec3 multiple_t = vec3(0.0f);
  if (split) {
    multiple_0 =
        ray_scattering_lookup(atmosphere, multiple_scattering_texture, r, mu, mu_s, nu, ray_r_mu_intersects_ground);
    multiple_t =
        ray_scattering_lookup(atmosphere, multiple_scattering_texture, r_t, mu_t, mu_s_t, nu,
                              ray_r_mu_intersects_ground);
  }
  vec3 aerosol_0 =
      ray_scattering_lookup(atmosphere, single_aerosol_texture, r, mu, mu_s, nu, ray_r_mu_intersects_ground);
  vec3 aerosol_t =
      ray_scattering_lookup(atmosphere, single_aerosol_texture, r_t, mu_t, mu_s_t, nu, ray_r_mu_intersects_ground);
  // Light cannot be negative; interpolation noise near t = 0 can make it so.
  PathScattering s;
  s.transmittance = transmittance;
  s.multiple = max(multiple_0 - transmittance * multiple_t, vec3(0.0f));
  s.single_rayleigh =
      max((scattering_0 - multiple_0) - transmittance * (scattering_t - multiple_t), vec3(0.0f));
  s.aerosol = max(aerosol_0 - transmittance * aerosol_t, vec3(0.0f));
  return s;
}

// table_scattering_to_distance with the horizon fix above.
INLINE PathScattering horizon_safe_scattering_to_distance(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                                          IN(sampler2D) spectral_transmittance_texture,
                                                          IN(sampler3D) scattering_texture,
                                                          IN(sampler3D) single_aerosol_texture,
                                                          IN(sampler3D) multiple_scattering_texture, float r,
                                                          float mu, float mu_s, float nu, float t, bool split) {
  bool ground = ray_intersects_ground(atmosphere, r, mu);
  if (!ground) mu = max(mu, horizon_mu(atmosphere, r) + HORIZON_MARGIN_MU);
  return table_scattering_to_distance(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                      single_aerosol_texture, multiple_scattering_texture, r, mu, mu_s, nu, t, ground,
                                      split);
}

// The light scattered towards the start of the ray (r, mu) by its part up to
// distance t, with the sun at (mu_s, nu): the table difference with the sun
// high, and with the sun low somewhere on the segment (see
// scattering_along_ray: the tables' interpolation in mu_s is off by tens of
// percent there) single scattering integrated along the segment itself for
// every wavelength triple, the smooth multiple scattering still from the
// tables; blended in between. `low_sun_path` false drops the integration
// (for shaders: a constant, see scattering_to_point). Eclipses, as
// scattering_along_ray: with moons (eclipse.glsl; `origin`, `view_ray`: the
// segment in space, |origin| = r; low_sun_path must then be true) single
// scattering is always integrated, node by node in the moons' shadows, and
// the table's multiple scattering is dimmed by the segment's diffuse
// visibility (ray_diffuse_visibility: a documented approximation).
INLINE PathScattering scattering_to_distance(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                             IN(sampler2D) spectral_transmittance_texture,
                                             IN(sampler3D) scattering_texture, IN(sampler3D) single_aerosol_texture,
                                             IN(sampler3D) multiple_scattering_texture, float r, float mu, float mu_s,
                                             float nu, float t, bool low_sun_path, bool split, IN(Moons) moons,
                                             vec3 origin, vec3 view_ray, vec3 sun_direction) {
  float low_sun = moons.count > 0 ? 1.0f : low_sun_weight(mu_s, mu_s_at_ray_end(r, mu, mu_s, nu, t));
  bool integrate = low_sun_path && low_sun > 0.0f;
  // The integration replaces single scattering only: it needs the split.
  // Where it does not run the result is that of low_sun_path false (the
  // split's two differences are each clamped at zero, their sum is not),
  // so that a pixel's light does not depend on whether its frame may have
  // a low sun elsewhere.
  PathScattering s = horizon_safe_scattering_to_distance(
      atmosphere, spectral, spectral_transmittance_texture, scattering_texture, single_aerosol_texture,
      multiple_scattering_texture, r, mu, mu_s, nu, t, split || integrate);
  if (integrate) {
    vec3 single_rayleigh;
    vec3 single_aerosol;
    float diffuse_visibility;  // 1 without moons
    spectral_single_scattering(atmosphere, spectral, spectral_transmittance_texture, r, mu, mu_s, nu, t, moons,
                               origin, view_ray, sun_direction, single_rayleigh, single_aerosol,
                               diffuse_visibility);
    s.single_rayleigh = mix(s.single_rayleigh, single_rayleigh, low_sun);
    s.aerosol = mix(s.aerosol, single_aerosol, low_sun);
    if (moons.count > 0) s.multiple *= diffuse_visibility;
  }
  return s;
}

// Radiance of PathScattering towards the camera, with the phase functions
// of the angle nu between the view ray and the sun.
INLINE vec3 path_radiance(IN(AtmosphereParams) atmosphere, IN(PathScattering) s, float nu) {
  return phase_weighted_scattering(atmosphere, s.single_rayleigh + s.multiple, s.aerosol, nu);
}

// The part inside the atmosphere of the segment from a camera (at or above
// the ground, relative to the planet centre) along the unit `view_ray` over
// a length t: where it starts (the camera, or where the segment enters the
// atmosphere from space), the start's (r, mu, mu_s), whether the ray meets
// the ground, and the length t of the part (at most to the ray's end on the
// ground sphere or the top). False when the segment misses the atmosphere
// or has no length in it.
struct AtmosphereSegment {
  vec3 start;
  float r;
  float mu;
  float mu_s;
  bool ground;
  float t;
};

INLINE bool atmosphere_segment(IN(AtmosphereParams) atmosphere, vec3 camera, vec3 view_ray, float t,
                               vec3 sun_direction, OUT(AtmosphereSegment) segment) {
  segment.start = camera;
  segment.r = 0.0f;
  segment.mu = 0.0f;
  segment.mu_s = 0.0f;
  segment.ground = false;
  segment.t = 0.0f;
  if (!enter_atmosphere(atmosphere, segment.start, view_ray)) return false;
  // The distance the segment runs inside the atmosphere.
  t = t - length(segment.start - camera);
  if (!(t > 0.0f)) return false;
  segment.r = clamp_radius(atmosphere, length(segment.start));
  segment.mu = clamp_cosine(dot(segment.start, view_ray) / segment.r);
  segment.mu_s = clamp_cosine(dot(segment.start, sun_direction) / segment.r);
  segment.ground = ray_intersects_ground(atmosphere, segment.r, segment.mu);
  // A point beyond the ray's end lies below the ground sphere (the engine's
  // terrain may dip below it): the tables end at the sphere.
  segment.t = min(t, distance_to_nearest_atmosphere_boundary(atmosphere, segment.r, segment.mu, segment.ground));
  return true;
}

// The weight of the low-sun path on a segment (scattering_to_distance,
// scattering_along_ray: low_sun_weight at its two ends); nu: the cosine
// between the view ray and the sun.
INLINE float segment_low_sun_weight(IN(AtmosphereSegment) segment, float nu) {
  return low_sun_weight(segment.mu_s, mu_s_at_ray_end(segment.r, segment.mu, segment.mu_s, nu, segment.t));
}

// The light between a camera and a point: in-scattered radiance and
// transmittance (returned in `transmittance`). `camera` is relative to the
// planet centre (m); `offset` goes from the camera to the point (m), which
// keeps its float precision however far the camera is from the centre. A
// camera outside the atmosphere starts where the segment enters it; a
// segment that misses the atmosphere has no in-scatter and transmittance 1.
// A camera below the ground counts as standing on it, a point below it as
// lying on it (the tables end there). `low_sun_path`: whether the sun may be
// low on the segment (see scattering_to_distance); shaders pass a constant
// for the frame: software rasterisers run both sides of every branch, and
// the integration would cost every pixel at noon too. `split`: whether
// single_rayleigh must exclude the multiple scattering (else it holds both,
// and `multiple` is 0 — two lookups fewer); always split where the
// low-sun integration runs.
// With moons (eclipse.glsl; low_sun_path must then be true) the segment's
// light is eclipsed as scattering_to_distance says; with no_moons() (a
// constant in shaders) the cost is that of scattering_to_point.
INLINE PathScattering eclipsed_scattering_to_point(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                                   IN(sampler2D) spectral_transmittance_texture,
                                                   IN(sampler3D) scattering_texture,
                                                   IN(sampler3D) single_aerosol_texture,
                                                   IN(sampler3D) multiple_scattering_texture, vec3 camera,
                                                   vec3 offset, vec3 sun_direction, bool low_sun_path, bool split,
                                                   IN(Moons) moons, OUT(vec3) transmittance, OUT(float) nu) {
  PathScattering s;
  s.single_rayleigh = vec3(0.0f);
  s.multiple = vec3(0.0f);
  s.aerosol = vec3(0.0f);
  s.transmittance = vec3(1.0f);
  transmittance = vec3(1.0f);
  camera = camera_above_ground(atmosphere, camera);
  float t = length(offset);
  vec3 view_ray = t > 0.0f ? offset / t : vec3(0.0f, 0.0f, 1.0f);
  nu = clamp_cosine(dot(view_ray, sun_direction));
  AtmosphereSegment segment;
  if (!atmosphere_segment(atmosphere, camera, view_ray, t, sun_direction, segment)) return s;
  // (The segment's transmittance comes with the table values, see
  // table_scattering_to_distance.)
  s = scattering_to_distance(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                             single_aerosol_texture, multiple_scattering_texture, segment.r, segment.mu,
                             segment.mu_s, nu, segment.t, low_sun_path, split, moons, segment.start, view_ray,
                             sun_direction);
  transmittance = s.transmittance;
  return s;
}

// The same without moons.
INLINE PathScattering scattering_to_point(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                          IN(sampler2D) spectral_transmittance_texture,
                                          IN(sampler3D) scattering_texture, IN(sampler3D) single_aerosol_texture,
                                          IN(sampler3D) multiple_scattering_texture, vec3 camera, vec3 offset,
                                          vec3 sun_direction, bool low_sun_path, bool split,
                                          OUT(vec3) transmittance, OUT(float) nu) {
  return eclipsed_scattering_to_point(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                      single_aerosol_texture, multiple_scattering_texture, camera, offset,
                                      sun_direction, low_sun_path, split, no_moons(), transmittance, nu);
}
