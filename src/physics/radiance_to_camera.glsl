// atmos — everything that reaches a camera along a view ray: the sky, or the
// lit ground seen through the aerial perspective in front of it, and beyond
// the atmosphere the sun disc with its corona, the stars and the moons.
//
// Needs: stars.glsl, sky_view_table.glsl (and the parts it needs).

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

// The light from beyond the atmosphere along a view ray from `camera` (at or
// above the ground), before the atmosphere attenuates it: the stars
// (stars.glsl), the sun disc with its corona (`include_sun_disc`), or a
// moon in front of them (moon_radiance).
INLINE vec3 radiance_beyond_atmosphere(IN(AtmosphereParams) atmosphere, vec3 camera, vec3 view_ray,
                                       vec3 sun_direction, bool include_sun_disc, IN(StarField) stars,
                                       IN(Moons) moons) {
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
  return beyond;
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
// computed with the same moons). `low_sun_path` (without the sky-view
// table): as scattering_along_ray's, false only where the sun is known to
// be high (above LOW_SUN_MU_S_TABLE) all along the ray, which drops the
// integration (shaders pass a constant); radiance_along_view_ray passes
// true.
INLINE vec3 radiance_along_view_ray_low_sun(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                            IN(sampler2D) spectral_transmittance_texture,
                                            IN(sampler3D) scattering_texture, IN(sampler3D) single_aerosol_texture,
                                            IN(sampler3D) multiple_scattering_texture,
                                            IN(sampler2D) irradiance_texture, IN(sampler2D) sky_view_rayleigh_texture,
                                            IN(sampler2D) sky_view_aerosol_texture,
                                            IN(sampler2D) sky_view_surface_texture, bool use_sky_view,
                                            IN(SkyViewFrame) sky_view, vec3 camera, vec3 view_ray,
                                            vec3 sun_direction, bool include_sun_disc, IN(StarField) stars,
                                            IN(Moons) moons, bool moons_eclipse, bool low_sun_path) {
  camera = camera_above_ground(atmosphere, camera);
  float nu = clamp_cosine(dot(view_ray, sun_direction));
  // Attenuated below like the sun.
  vec3 beyond =
      radiance_beyond_atmosphere(atmosphere, camera, view_ray, sun_direction, include_sun_disc, stars, moons);
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
                   multiple_scattering_texture, irradiance_texture, start, view_ray, sun_direction, ground,
                   low_sun_path, shadowing, rayleigh, aerosol, surface);
  }
  vec3 radiance = phase_weighted_scattering(atmosphere, rayleigh, aerosol, nu);
  if (ground) return radiance + surface;
  return radiance + surface * beyond;
}

INLINE vec3 radiance_along_view_ray(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                    IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                                    IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                                    IN(sampler2D) irradiance_texture, IN(sampler2D) sky_view_rayleigh_texture,
                                    IN(sampler2D) sky_view_aerosol_texture, IN(sampler2D) sky_view_surface_texture,
                                    bool use_sky_view, IN(SkyViewFrame) sky_view, vec3 camera, vec3 view_ray,
                                    vec3 sun_direction, bool include_sun_disc, IN(StarField) stars,
                                    IN(Moons) moons, bool moons_eclipse) {
  return radiance_along_view_ray_low_sun(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                         single_aerosol_texture, multiple_scattering_texture, irradiance_texture,
                                         sky_view_rayleigh_texture, sky_view_aerosol_texture,
                                         sky_view_surface_texture, use_sky_view, sky_view, camera, view_ray,
                                         sun_direction, include_sun_disc, stars, moons, moons_eclipse, true);
}
