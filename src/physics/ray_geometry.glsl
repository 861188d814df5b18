// atmos — ray geometry in a spherical atmosphere: distances along a ray to
// the ground and to the top of the atmosphere, and the radius and the sun's
// zenith angle along it.
//
// Needs: definitions.glsl (which lists the parts of the physics in order).
//
// Conventions. A ray starts at a point at distance r from the planet centre
// and has direction v; mu = cos(v, zenith), mu_s = cos(sun, zenith) at the
// point, nu = cos(v, sun). "The radiance of a ray" is the radiance arriving at
// the start point from direction v (looking along v). Radiance in
// W m^-2 sr^-1 nm^-1 per working wavelength; irradiance in W m^-2 nm^-1.

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

// Zenith cosine of the sun at the far end (distance d) of the ray (r, mu).
INLINE float mu_s_at_ray_end(float r, float mu, float mu_s, float nu, float d) {
  return mu_s_along_ray(r, mu_s, nu, d, radius_along_ray(r, mu, d));
}

// Sun zenith cosine at the ground point x + d v that the ray (r, mu) hits at
// distance d, whose normal is (x + d v) / R_bottom.
INLINE float mu_s_at_ground(IN(AtmosphereParams) atmosphere, float r, float mu_s, float nu, float d) {
  return clamp_cosine((r * mu_s + d * nu) / atmosphere.bottom_radius);
}

// Direction with zenith cosine mu and azimuth phi from the sun's vertical
// plane, in a frame where the zenith is z and the sun is in the x-z plane.
INLINE vec3 direction_from_mu_phi(float mu, float phi) {
  float s = safe_sqrt(1.0f - mu * mu);
  return vec3(s * cos(phi), s * sin(phi), mu);
}

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

// A camera below the ground counts as standing on it (as in
// radiance_along_view_ray): moved out along its radius to the surface. At
// the centre itself (r so small that bottom_radius / r would overflow a
// float) no radius has a direction; the camera stands at the pole on +z.
INLINE vec3 camera_above_ground(IN(AtmosphereParams) atmosphere, vec3 camera) {
  float r = length(camera);
  if (r >= atmosphere.bottom_radius) return camera;
  if (r > 1e-30f * atmosphere.bottom_radius) return camera * (atmosphere.bottom_radius / r);
  return vec3(0.0f, 0.0f, atmosphere.bottom_radius);
}
