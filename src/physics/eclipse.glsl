// atmos — the solar disc and the moons that eclipse it.
//
// Needs: definitions.glsl. The single scattering along rays
// (ray_integration.glsl), the lighting of the ground and the view rays
// (view_ray_scattering.glsl, radiance_to_camera.glsl) are dimmed by the
// moons here.
//
// Seen from a point, the sun and a moon are discs of angular radii a and b
// whose centres are d apart. The discs are a few tenths of a degree wide:
// they are treated as flat circles in the tangent plane (relative error ~a²,
// 2e-5 for the Sun seen from the Earth). Cases: no overlap (d >= a + b);
// total (the moon covers the sun: d <= b - a); annular (the sun rings the
// moon: d <= a - b); partial otherwise.

// Solar limb darkening. The disc is darker towards its edge, where the line
// of sight leaves the photosphere obliquely and sees cooler, higher layers.
// The linear law I(mu) = I(1) (1 - u (1 - mu)), mu the cosine of the angle
// between the line of sight and the star's surface normal where it emerges,
// with u = 3/5: the grey atmosphere in Eddington's approximation, I(mu) ∝
// 2 + 3 mu (Milne 1921, MNRAS 81, 361; Eddington 1926, The Internal
// Constitution of the Stars, §227; e.g. Mihalas 1978, Stellar Atmospheres,
// §3-4). The limb keeps 40 % of the centre's radiance, close to what is
// measured in the visible; the measured coefficient also grows towards the
// blue (Neckel & Labs 1994, Sol. Phys. 153, 91), which this grey law leaves
// out: the limb is dimmer, not redder. Used by sun_disc_radiance
// (radiance_to_camera.glsl) and by the eclipses below.
#define SUN_LIMB_DARKENING_U 0.6f

// The area of the intersection of two circles of radii a and b whose centres
// are d apart (the lens of two circular segments).
INLINE float circle_overlap_area(float a, float b, float d) {
  if (d >= a + b) return 0.0f;
  float r = min(a, b);
  if (d <= abs(a - b)) return PI * r * r;
  float alpha = acos(clamp((d * d + a * a - b * b) / (2.0f * d * a), -1.0f, 1.0f));
  float beta = acos(clamp((d * d + b * b - a * a) / (2.0f * d * b), -1.0f, 1.0f));
  // Two circular segments, r² (theta - sin theta cos theta) each, theta
  // the half-angle at that circle's centre.
  return a * a * (alpha - 0.5f * sin(2.0f * alpha)) + b * b * (beta - 0.5f * sin(2.0f * beta));
}

// The fraction of the circle of radius rho around the sun's centre that lies
// inside the moon's disc (radius b, its centre d from the sun's).
INLINE float ring_fraction_covered(float rho, float b, float d) {
  if (rho + d <= b) return 1.0f;                         // the whole ring inside
  if (rho >= d + b || d >= rho + b || rho <= 0.0f) return 0.0f;  // none of it
  float c = (rho * rho + d * d - b * b) / (2.0f * rho * d);
  return acos(clamp(c, -1.0f, 1.0f)) / PI;
}

// Limb-darkened intensity at radius rho of a disc of radius a (the linear
// law with u = SUN_LIMB_DARKENING_U), relative to its centre.
INLINE float limb_darkening(float rho, float a) {
  float mu = sqrt(max(1.0f - (rho * rho) / (a * a), 0.0f));
  return 1.0f - SUN_LIMB_DARKENING_U * (1.0f - mu);
}

// The fraction of the sun's light (irradiance) that a moon leaves visible:
// 1 - the limb-darkened flux of the covered part over the disc's. The
// covered flux is the integral over rings of the sun, intensity x covered
// fraction of the ring x 2 pi rho; the covered fraction has kinks where the
// moon's edge starts and stops crossing the rings (rho = |d - b| and
// d + b), so the integral is split there and each piece summed with
// 8-point Gauss-Legendre: ~1e-6 of the flux.
#define ECLIPSE_GAUSS_NODES 8

// Node k (0..7) of 8-point Gauss-Legendre quadrature on [-1, 1], and its
// weight (Abramowitz & Stegun 1964, Table 25.4).
INLINE float gauss_legendre_8(int k, OUT(float) weight) {
  int i = k < 4 ? 3 - k : k - 4;  // |node| index, increasing
  float x = i == 0 ? 0.1834346425f : i == 1 ? 0.5255324099f : i == 2 ? 0.7966664774f : 0.9602898565f;
  weight = i == 0 ? 0.3626837834f : i == 1 ? 0.3137066459f : i == 2 ? 0.2223810345f : 0.1012285363f;
  return k < 4 ? -x : x;
}

INLINE float sun_visible_fraction_behind_moon(float a, float b, float d) {
  if (d >= a + b) return 1.0f;
  if (d + a <= b) return 0.0f;
  float kink_0 = min(abs(d - b), a);
  float kink_1 = min(d + b, a);
  float covered = 0.0f;
  for (int piece = 0; piece < 3; ++piece) {
    float lo = piece == 0 ? 0.0f : piece == 1 ? kink_0 : kink_1;
    float hi = piece == 0 ? kink_0 : piece == 1 ? kink_1 : a;
    float half_width = 0.5f * (hi - lo);
    float middle = 0.5f * (hi + lo);
    for (int k = 0; k < ECLIPSE_GAUSS_NODES; ++k) {
      float weight;
      float rho = middle + half_width * gauss_legendre_8(k, weight);
      covered += half_width * weight * limb_darkening(rho, a) * ring_fraction_covered(rho, b, d) * 2.0f * PI * rho;
    }
  }
  // The whole disc's flux: pi a² (1 - u / 3) (radiance_to_camera.glsl: sun_disc_radiance).
  float total = PI * a * a * (1.0f - SUN_LIMB_DARKENING_U / 3.0f);
  return clamp(1.0f - covered / total, 0.0f, 1.0f);
}

// ---------------------------------------------------------------------------
// Moons in the scene
// ---------------------------------------------------------------------------

// The moons of a frame: opaque spheres between the sun and the planet, fixed
// for the frame (their motion during one frame is irrelevant). Centres are
// relative to the planet centre in metres, like every position here; in
// float a centre 384 400 km away is exact to ~30 m, which moves the umbra's
// edge by as much.
#define MOON_CAPACITY 4
// Bond albedo of the Moon, 0.11-0.12 (Matthews 2008, Appl. Opt. 47, H187:
// 0.11; Allen's Astrophysical Quantities, 4th ed., §12.3: 0.12): the grey
// Lambertian reflectance of every moon's lit side.
#define MOON_ALBEDO 0.12f

struct Moons {
  int count;
  vec4 sphere[MOON_CAPACITY];  // xyz: centre (m, planet-centred), w: radius (m)
};

// No moons: the precomputation and every renderer without an eclipse.
INLINE Moons no_moons() {
  Moons moons;
  moons.count = 0;
  for (int i = 0; i < MOON_CAPACITY; ++i) moons.sphere[i] = vec4(0.0f);
  return moons;
}

// The moon `sphere` seen from `point`: returns the angle d between its
// centre and the sun's (radians), and its angular radius in `b`. The angle
// comes from atan(|to x s|, to . s), which keeps its digits for the small
// angles of an eclipse (acos of a dot product would lose them). A point
// inside the moon sees it cover the sky (b = pi/2). A moon behind the point
// (away from the sun) gives d > pi/2 and covers nothing of it.
INLINE float moon_offset_from_sun(vec4 sphere, vec3 point, vec3 sun_direction, OUT(float) b) {
  vec3 to_moon = vec3(sphere) - point;
  float distance = length(to_moon);
  b = asin(min(sphere.w / distance, 1.0f));
  return atan(length(cross(to_moon, sun_direction)), dot(to_moon, sun_direction));
}

// The fraction of the sun's light (irradiance, limb-darkened) that reaches
// `point` past all the moons: the product of each moon's
// sun_visible_fraction_behind_moon, exact while at most one moon overlaps
// the sun from the point (two moons overlapping each other in front of the
// sun would count their common part twice). Planet-centred point, unit sun
// direction, the sun's angular radius `a`.
INLINE float sunlight_visible_fraction(IN(Moons) moons, float a, vec3 point, vec3 sun_direction) {
  float visible = 1.0f;
  for (int i = 0; i < moons.count; ++i) {
    float b;
    float d = moon_offset_from_sun(moons.sphere[i], point, sun_direction, b);
    visible *= sun_visible_fraction_behind_moon(a, b, d);
  }
  return visible;
}

// The same for a uniform disc (the overlap's area only): the cheap form, for
// where the limb darkening does not show (the diffuse light,
// ray_integration.glsl: diffuse_light_visible_fraction, and the placement of
// integration nodes).
INLINE float uniform_sunlight_visible_fraction(IN(Moons) moons, float a, vec3 point, vec3 sun_direction) {
  float visible = 1.0f;
  for (int i = 0; i < moons.count; ++i) {
    float b;
    float d = moon_offset_from_sun(moons.sphere[i], point, sun_direction, b);
    visible *= 1.0f - circle_overlap_area(a, b, d) / (PI * a * a);
  }
  return max(visible, 0.0f);
}

// Where a view ray from `origin` (planet-centred) along the unit `view_ray`
// first meets a moon: returns the distance (m), or -1 when it meets none.
// The perpendicular distance from the cross product keeps its digits for a
// moon hundreds of thousands of kilometres away.
INLINE float view_ray_moon_distance(IN(Moons) moons, vec3 origin, vec3 view_ray, OUT(int) which) {
  float nearest = -1.0f;
  which = -1;
  for (int i = 0; i < moons.count; ++i) {
    vec3 to_moon = vec3(moons.sphere[i]) - origin;
    float along = dot(to_moon, view_ray);
    vec3 c = cross(to_moon, view_ray);
    float radius = moons.sphere[i].w;
    float half_chord2 = radius * radius - dot(c, c);
    if (along <= 0.0f || half_chord2 < 0.0f) continue;
    float t = along - sqrt(half_chord2);
    if (nearest < 0.0f || t < nearest) {
      nearest = t;
      which = i;
    }
  }
  return nearest;
}

// Radiance of the moon seen along `view_ray` from `origin` at distance t
// (view_ray_moon_distance): its Lambertian surface (MOON_ALBEDO) lit by the
// sun above any atmosphere. Its night side is black (no earthshine), so a
// moon in front of the sun is a black disc. (`which` is clamped: shaders
// may evaluate this on lanes that met no moon, which = -1.)
INLINE vec3 moon_radiance(IN(Moons) moons, int which, vec3 origin, vec3 view_ray, float t, vec3 sun_direction,
                          vec3 solar_irradiance) {
  vec4 sphere = moons.sphere[clamp(which, 0, MOON_CAPACITY - 1)];
  vec3 normal = (origin + view_ray * t - vec3(sphere)) / sphere.w;
  return solar_irradiance * (MOON_ALBEDO / PI * max(dot(normal, sun_direction), 0.0f));
}
