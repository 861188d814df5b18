// atmos — the renderers' light along a view ray: the light scattered along
// it (from the tables with the sun high, integrated along the ray with the
// sun low), its transmittance in the tables' channels, the irradiance of
// surfaces, and what lies at the ray's end (view_ray_terms, the content of
// the sky-view table).
//
// Needs: ray_integration.glsl (and the parts it needs).

// The tables a renderer reads:
//  - transmittance_texture: transmittance to the top of the atmosphere;
//  - scattering_texture: single Rayleigh scattering plus all multiple
//    scattering divided by the Rayleigh phase function (so one lookup and one
//    phase function give both);
//  - single_aerosol_texture: single aerosol scattering without phase function;
//  - multiple_scattering_texture: the multiple scattering alone, divided by
//    the Rayleigh phase function (for the low-sun path of sky_radiance);
//  - irradiance_texture: indirect (sky) irradiance on a horizontal surface.

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

// What the sky-view table holds for one view ray from `camera` (in the
// atmosphere, at or above the ground): the phase-free scattering along it
// (scattering_along_ray: single Rayleigh + multiple / P_R, and single
// aerosol), and in `surface` what lies at its end — for a ray that meets the
// ground sphere, the radiance of the Lambertian ground lit by the sun and
// the sky (Collienne 2013, §4.3.3) times the transmittance to it; for the
// others, the transmittance to the top of the atmosphere, which the sun disc
// needs.
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

// Radiance scattered towards the camera along the view ray up to the top of
// the atmosphere or the ground (Collienne 2013, eq. 3.13), and the
// transmittance of that path: scattering_along_ray for the ray itself (the
// GLSL library for engines). Excludes the sun disc and the light reflected
// by the ground.
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
