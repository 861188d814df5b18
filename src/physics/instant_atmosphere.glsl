// atmos — the instant approximate mode (Hillaire 2020, "A Scalable and
// Production Ready Sky and Atmosphere Rendering Technique", EGSR 2020): the
// light along a view ray from the transmittance table and a 2D table of
// multiple scattering, without any 4D table. What the per-frame sky-view
// table and aerial-perspective volume of that mode hold (gpu/
// instant_sky_view.frag.glsl, gpu/instant_aerial_perspective.comp.glsl, and
// their CPU twins in gpu/instant.cpp).
//
// Needs: sky_view_table.glsl (and the parts it needs).
//
// The light scattered towards the camera at a point x of a view ray is,
// per unit solar irradiance E (Hillaire 2020, the scattering integral of
// its ray marches with the multiple-scattering term),
//   σ_R(x) T_sun(x) P_R(nu) + σ_A(x) T_sun(x) P_A(nu) + σ_s(x) Ψ_ms(x),
// single scattering plus the light scattered two or more times, which the
// method takes as isotropic at x and of strength Ψ_ms, a function of the
// altitude and the sun's zenith cosine only (its multiple-scattering LUT,
// computed by precompute/instant.cpp):
//   Ψ_ms = L_2nd F_ms,  F_ms = 1 + f_ms + f_ms² + ... = 1 / (1 - f_ms),
// with L_2nd the second order at x under an isotropic phase function p_u =
// 1/4π (the single scattering and the lit ground seen from x in every
// direction, scattered once more at x) and f_ms the fraction of a uniform
// isotropic radiance around x that the air scatters back towards x: each
// further order is the one before times f_ms, a geometric series. The view
// ray is then integrated along itself: single scattering, the multiple
// term and the transmittance, every wavelength triple with its own medium
// (as the exact mode's low-sun path), so the mode is spectral too.

// The multiple-scattering table: Ψ_ms over (mu_s, altitude) for every
// wavelength triple, the triples' tiles side by side (InstantTables).
//  - x: mu_s in [-1, 1], linear (the sun's zenith cosine at the point);
//  - y: sqrt of the altitude's fraction of the atmosphere's thickness,
//    denser near the ground, where the light changes fastest.
#define INSTANT_MS_MU_S_SIZE 32
#define INSTANT_MS_R_SIZE 32
// Intervals of a view ray of the sky-view table (nodes quadratic in the
// distance, dense near the camera).
#define INSTANT_VIEW_RAY_INTERVALS 24
// Intervals per slice of the aerial-perspective volume.
#define INSTANT_SLICE_INTERVALS 2

INLINE vec2 instant_multiple_scattering_uv(IN(AtmosphereParams) atmosphere, float r, float mu_s, int tile,
                                           int tiles) {
  float x_r = safe_sqrt(clamp((r - atmosphere.bottom_radius) / (atmosphere.top_radius - atmosphere.bottom_radius),
                              0.0f, 1.0f));
  float x_mu_s = clamp(0.5f + 0.5f * mu_s, 0.0f, 1.0f);
  return vec2((float(tile) + texture_coord_from_unit_range(x_mu_s, INSTANT_MS_MU_S_SIZE)) / float(tiles),
              texture_coord_from_unit_range(x_r, INSTANT_MS_R_SIZE));
}

// The (r, mu_s) of texel (x, y) of a tile.
INLINE void instant_multiple_scattering_r_mu_s(IN(AtmosphereParams) atmosphere, int x, int y, OUT(float) r,
                                               OUT(float) mu_s) {
  float x_mu_s = float(x) / float(INSTANT_MS_MU_S_SIZE - 1);
  float x_r = float(y) / float(INSTANT_MS_R_SIZE - 1);
  mu_s = clamp_cosine(2.0f * x_mu_s - 1.0f);
  r = atmosphere.bottom_radius + x_r * x_r * (atmosphere.top_radius - atmosphere.bottom_radius);
}

// Ψ_ms of wavelength triple `tile` of `tiles` (sr^-1, per unit solar irradiance).
INLINE vec3 instant_multiple_scattering(IN(AtmosphereParams) set, IN(sampler2D) multiple_scattering_texture,
                                        float r, float mu_s, int tile, int tiles) {
  return vec3(texture(multiple_scattering_texture, instant_multiple_scattering_uv(set, r, mu_s, tile, tiles)));
}

// The march along one ray, every wavelength triple at once: call
// instant_march_begin at the ray's start, then instant_march_to with
// increasing distances; the running integrals are in the tables' channels.
struct InstantMarch {
  float r;   // start of the ray, clamped to the atmosphere
  float mu;
  float mu_s;
  float nu;
  float t;   // distance reached
  // Per wavelength triple, at distance t: the optical depth from the start,
  // the extinction, and the integrands of single Rayleigh, single aerosol
  // and multiple scattering (per unit solar irradiance, without phase
  // functions; the aerosol's with its own phase function, see below).
  vec3 optical_depth[SPECTRAL_SET_CAPACITY];
  vec3 extinction[SPECTRAL_SET_CAPACITY];
  vec3 rayleigh_integrand[SPECTRAL_SET_CAPACITY];
  vec3 aerosol_integrand[SPECTRAL_SET_CAPACITY];
  vec3 multiple_integrand[SPECTRAL_SET_CAPACITY];
  // In the tables' channels (spectral.to_channels, times the solar
  // irradiance): single Rayleigh scattering without its phase function,
  // Σ_k M_k E_k S_A,k P_A,k(nu) (divided by the channels' aerosol phase
  // function at the end: the form of the single aerosol table), and the
  // multiple scattering with its isotropic radiance, all from 0 to t.
  vec3 single_rayleigh;
  vec3 aerosol;
  vec3 multiple;
};

// The medium of triple `set` at distance t along the march's ray: its
// extinction, and the three integrands without the view path's
// transmittance. The sunlight goes through the delta-M scaled medium, as the
// exact tables' single scattering (single_scattering_tile); `low_sun`:
// averaged over the solar disc with the planet's shadow (transmittance_to_sun),
// else one lookup (the sun above 10° at every point the ray reaches:
// sun_may_be_low_on_view_rays).
INLINE void instant_node(IN(AtmosphereParams) set, IN(sampler2D) transmittance_texture,
                         IN(sampler2D) multiple_scattering_texture, int tile, int tiles, IN(InstantMarch) m, float t,
                         bool low_sun, OUT(vec3) extinction, OUT(vec3) rayleigh, OUT(vec3) aerosol,
                         OUT(vec3) multiple) {
  float r_t = clamp_radius(set, radius_along_ray(m.r, m.mu, t));
  float mu_s_t = clamp_cosine(mu_s_along_ray(m.r, m.mu_s, m.nu, t, r_t));
  vec3 beta_rayleigh;
  vec3 beta_aerosol;
  medium_at(set, r_t, beta_rayleigh, beta_aerosol, extinction);
  AtmosphereParams scaled = with_scaled_transmittance(set);
  vec3 to_sun = low_sun ? transmittance_to_sun(scaled, transmittance_texture, r_t, mu_s_t)
                        : transmittance_to_top_atmosphere_boundary(scaled, transmittance_texture, r_t, mu_s_t);
  rayleigh = beta_rayleigh * to_sun;
  aerosol = beta_aerosol * to_sun;
  multiple = (beta_rayleigh + beta_aerosol) *
             instant_multiple_scattering(set, multiple_scattering_texture, r_t, mu_s_t, tile, tiles);
}

INLINE InstantMarch instant_march_begin(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                        IN(sampler2D) transmittance_texture,
                                        IN(sampler2D) multiple_scattering_texture, vec3 origin, vec3 view_ray,
                                        vec3 sun_direction, bool low_sun) {
  InstantMarch m;
  m.r = clamp_radius(atmosphere, length(origin));
  m.mu = clamp_cosine(dot(origin, view_ray) / m.r);
  m.mu_s = clamp_cosine(dot(origin, sun_direction) / m.r);
  m.nu = clamp_cosine(dot(view_ray, sun_direction));
  m.t = 0.0f;
  for (int k = 0; k < SPECTRAL_COUNT(spectral); ++k) {
    m.optical_depth[k] = vec3(0.0f);
    instant_node(spectral.set[k], transmittance_texture, multiple_scattering_texture, k, SPECTRAL_COUNT(spectral),
                 m, 0.0f, low_sun, m.extinction[k], m.rayleigh_integrand[k], m.aerosol_integrand[k],
                 m.multiple_integrand[k]);
  }
  m.single_rayleigh = vec3(0.0f);
  m.aerosol = vec3(0.0f);
  m.multiple = vec3(0.0f);
  return m;
}

// Advances the march to distance t_next in `intervals` equal intervals,
// each integrated as an exponential (exponential_segment_integral: the
// integrands fall off about exponentially along the ray, as the density
// does with altitude).
INLINE void instant_march_to(IN(SpectralSets) spectral, IN(sampler2D) transmittance_texture,
                             IN(sampler2D) multiple_scattering_texture,
                             INOUT(InstantMarch) m, float t_next, int intervals, bool low_sun) {
  float h = (t_next - m.t) / float(intervals);
  for (int k = 0; k < SPECTRAL_COUNT(spectral); ++k) {
    vec3 rayleigh = vec3(0.0f);
    vec3 aerosol = vec3(0.0f);
    vec3 multiple = vec3(0.0f);
    for (int i = 1; i <= intervals; ++i) {
      vec3 extinction;
      vec3 rayleigh_sunlit;
      vec3 aerosol_sunlit;
      vec3 multiple_source;
      instant_node(spectral.set[k], transmittance_texture, multiple_scattering_texture, k, SPECTRAL_COUNT(spectral),
                   m, m.t + float(i) * h, low_sun, extinction, rayleigh_sunlit, aerosol_sunlit, multiple_source);
      m.optical_depth[k] += exponential_segment_integral(m.extinction[k], extinction, h);
      m.extinction[k] = extinction;
      vec3 transmittance = exp(-m.optical_depth[k]);
      vec3 rayleigh_integrand = rayleigh_sunlit * transmittance;
      vec3 aerosol_integrand = aerosol_sunlit * transmittance;
      vec3 multiple_integrand = multiple_source * transmittance;
      rayleigh += exponential_segment_integral(m.rayleigh_integrand[k], rayleigh_integrand, h);
      aerosol += exponential_segment_integral(m.aerosol_integrand[k], aerosol_integrand, h);
      multiple += exponential_segment_integral(m.multiple_integrand[k], multiple_integrand, h);
      m.rayleigh_integrand[k] = rayleigh_integrand;
      m.aerosol_integrand[k] = aerosol_integrand;
      m.multiple_integrand[k] = multiple_integrand;
    }
    vec3 sun = spectral.set[k].solar_irradiance;
    m.single_rayleigh += spectral.to_channels[k] * (sun * rayleigh);
    m.aerosol += spectral.to_channels[k] * (sun * aerosol * aerosol_phase_function(spectral.set[k], m.nu));
    m.multiple += spectral.to_channels[k] * (sun * multiple);
  }
  m.t = t_next;
}

// The march's light from its start to m.t in the form of the exact tables
// (view_ray_scattering.glsl): `rayleigh` = single Rayleigh + multiple / P_R
// and `aerosol` = single aerosol without its phase function, so that
// phase_weighted_scattering() gives the radiance; `multiple` alone (the
// isotropic radiance, not divided by P_R); `transmittance` from the start,
// sunlight-weighted as channel_transmittance.
INLINE void instant_march_light(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral, IN(InstantMarch) m,
                                OUT(vec3) single_rayleigh, OUT(vec3) multiple, OUT(vec3) aerosol,
                                OUT(vec3) transmittance) {
  single_rayleigh = m.single_rayleigh;
  multiple = m.multiple / rayleigh_phase_function(m.nu);
  aerosol = m.aerosol / aerosol_phase_function(atmosphere, m.nu);
  vec3 sum = vec3(0.0f);
  for (int k = 0; k < SPECTRAL_COUNT(spectral); ++k)
    sum += spectral.to_channels[k] * (spectral.set[k].solar_irradiance * exp(-m.optical_depth[k]));
  transmittance = max(sum / max(atmosphere.solar_irradiance, vec3(1e-30f)), vec3(0.0f));
}

// The light between `camera` (anywhere: a camera above the atmosphere is
// moved along the ray to where it enters it) and the point at distance
// `t_end` along the unit `view_ray` (t_end < 0: to the ray's end in the
// atmosphere, the ground sphere or the top), in the instant mode: the
// in-scattered radiance in the tables' channels (single scattering with
// the phase functions and the isotropic multiple scattering, for the
// atmosphere's solar irradiance) and the transmittance along the path
// (sunlight-weighted, instant_march_light). The part inside the atmosphere
// is marched in INSTANT_VIEW_RAY_INTERVALS intervals with nodes quadratic
// in the distance, as instant_view_ray_terms does, and ends at the top
// where the ray leaves the atmosphere; towards a point below the ground
// sphere (terrain below the atmosphere's bottom) the march goes on through
// the ground's medium (clamp_radius), as the volume's does.
INLINE vec3 instant_radiance_to_distance(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                         IN(sampler2D) transmittance_texture,
                                         IN(sampler2D) multiple_scattering_texture, vec3 camera, vec3 view_ray,
                                         vec3 sun_direction, float t_end, bool low_sun, OUT(vec3) transmittance) {
  transmittance = vec3(1.0f);
  vec3 start = camera;
  if (!enter_atmosphere(atmosphere, start, view_ray)) return vec3(0.0f);
  float r = clamp_radius(atmosphere, length(start));
  float mu = clamp_cosine(dot(start, view_ray) / r);
  float length_in_atmosphere =
      t_end < 0.0f ? distance_to_nearest_atmosphere_boundary(atmosphere, r, mu, ray_intersects_ground(atmosphere, r, mu))
                   : min(t_end - distance(camera, start), distance_to_top_atmosphere_boundary(atmosphere, r, mu));
  if (!(length_in_atmosphere > 0.0f)) return vec3(0.0f);
  InstantMarch m = instant_march_begin(atmosphere, spectral, transmittance_texture, multiple_scattering_texture,
                                       start, view_ray, sun_direction, low_sun);
  for (int i = 1; i <= INSTANT_VIEW_RAY_INTERVALS; ++i) {
    float x = float(i) / float(INSTANT_VIEW_RAY_INTERVALS);
    instant_march_to(spectral, transmittance_texture, multiple_scattering_texture, m, length_in_atmosphere * x * x,
                     1, low_sun);
  }
  vec3 single_rayleigh;
  vec3 multiple;
  vec3 aerosol;
  instant_march_light(atmosphere, spectral, m, single_rayleigh, multiple, aerosol, transmittance);
  return phase_weighted_scattering(atmosphere, single_rayleigh + multiple, aerosol, m.nu);
}

// The instant mode's view_ray_terms (view_ray_scattering.glsl): what its
// sky-view table holds for one view ray from `camera` (in the atmosphere,
// at or above the ground), ending at the ground sphere (`ground`) or the
// top. The ray is marched in INSTANT_VIEW_RAY_INTERVALS intervals, the
// node i at distance d (i / n)²; `surface` is the lit ground times the
// transmittance to it, or the transmittance to the top (the sun disc), as
// in the exact mode, from the instant mode's sky irradiance table.
INLINE void instant_view_ray_terms(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                   IN(sampler2D) transmittance_texture, IN(sampler2D) multiple_scattering_texture,
                                   IN(sampler2D) irradiance_texture, vec3 camera, vec3 view_ray, vec3 sun_direction,
                                   bool ground, bool low_sun, OUT(vec3) rayleigh, OUT(vec3) aerosol,
                                   OUT(vec3) surface) {
  InstantMarch m = instant_march_begin(atmosphere, spectral, transmittance_texture, multiple_scattering_texture,
                                       camera, view_ray, sun_direction, low_sun);
  float d = distance_to_nearest_atmosphere_boundary(atmosphere, m.r, m.mu, ground);
  for (int i = 1; i <= INSTANT_VIEW_RAY_INTERVALS; ++i) {
    float x = float(i) / float(INSTANT_VIEW_RAY_INTERVALS);
    instant_march_to(spectral, transmittance_texture, multiple_scattering_texture, m, d * x * x, 1, low_sun);
  }
  vec3 single_rayleigh;
  vec3 multiple;
  vec3 transmittance;
  instant_march_light(atmosphere, spectral, m, single_rayleigh, multiple, aerosol, transmittance);
  rayleigh = single_rayleigh + multiple;
  if (ground) {
    vec3 point = camera + view_ray * d;
    vec3 normal = point / length(point);
    vec3 sky_irradiance;
    vec3 sun_irradiance = sun_and_sky_irradiance_at(atmosphere, spectral, transmittance_texture, irradiance_texture,
                                                    atmosphere.bottom_radius, normal, normal, sun_direction,
                                                    sky_irradiance);
    surface = channel_transmittance(atmosphere, spectral, transmittance_texture, PATH_TO_GROUND_SCALED, m.r, m.mu) *
              ground_radiance(atmosphere, sun_irradiance + sky_irradiance);
  } else {
    surface = channel_transmittance(atmosphere, spectral, transmittance_texture, PATH_TO_TOP, m.r, m.mu);
  }
}

// One texel of the instant mode's sky-view table (sky_view_table.glsl: the
// same parameterisation, frame and texel centres as the exact mode's).
INLINE void compute_instant_sky_view_texel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                           IN(sampler2D) transmittance_texture,
                                           IN(sampler2D) multiple_scattering_texture,
                                           IN(sampler2D) irradiance_texture, IN(SkyViewFrame) frame, vec3 camera,
                                           vec3 sun_direction, vec2 uv, bool low_sun, OUT(vec3) rayleigh,
                                           OUT(vec3) aerosol, OUT(vec3) surface) {
  camera = camera_above_ground(atmosphere, camera);
  bool ground;
  vec3 view_ray = sky_view_direction(frame, uv, ground);
  instant_view_ray_terms(atmosphere, spectral, transmittance_texture, multiple_scattering_texture,
                         irradiance_texture, camera, view_ray, sun_direction, ground, low_sun, rayleigh, aerosol,
                         surface);
}
