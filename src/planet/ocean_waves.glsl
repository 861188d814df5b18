// The sea's displaced waves, shared by the sea's fragment shader (GLSL 4.50,
// float) and its CPU twin (planet/ocean_waves_cpp.hpp, double), written in
// the common subset of both (functions marked INLINE, parameters IN(T) and
// OUT(T), no swizzles): the waves' height at a point, each wave's weight
// from its size on the screen, and the first point where a pixel's view ray
// meets the displaced surface.
//
// The surface. With R the sea level's radius, p a point and
// h(p) = Σ_i w_i a_i sin(k_i · p + φ_i − ω_i t) the displacing waves
// (Pierson & Moskowitz 1964's bands, ocean.cpp; the wave vectors fixed in
// the planet's frame), the sea is the implicit surface |p| − R = h(p). The
// camera-relative form keeps float's precision near the camera: with o the
// offset from the camera, k_i · p = k_i · camera + k_i · o, the first term
// reduced modulo 2π in double on the CPU (wave_phase), so the
// heights are the world's and nothing swims. Along the ray o = t d, with
// r_c the camera's distance from the centre, b = r_c (up · d) and
// c = r_c² − R² (from double on the CPU), the height of the ray above the
// sphere is e(t) = q / (R + √(R² + q)), q = |p|² − R² = c + t (2b + t),
// which has no cancellation between R and |p|.
//
// The crossing (relief mapping, Policarpo & Oliveira 2005, with steps
// that cannot pass the surface, as sphere tracing's, Hart 1996).
// g(t) = e(t) − h(t d) is positive above the sea. With A = Σ w_i a_i, the
// sea lies between the spheres R − A and R + A: the ray enters the shell at
// t_in (the sphere R + A; 0 if the camera is inside it) and reaches R − A
// at t_out (or, if it misses that sphere, leaves R + A beyond its lowest
// point). On the shell −g' ≤ L = max(−(b + t_in), 0) / (R − A) + S,
// S = Σ w_i a_i |k_i · d| (e' = (b + t)/|p| grows along the ray and
// |p| ≥ R − A), and |g''| ≤ M = 1/(R − A) + Σ w_i a_i (k_i · d)²
// (e'' = (1 − e'²)/|p|). So g has no zero before t + s for s = g/L, nor
// before the first positive root of g + g' s − ½ M s² (Taylor's bound from
// g and g' at t). The short waves (a tail of amplitudes adding up to
// A_s ≤ OCEAN_SHORT_AMPLITUDE = 5 cm) move g by at most A_s: while the long
// waves' clearance g_long exceeds 2 A_s, the march evaluates the long waves
// alone and steps by the same two bounds on g_long − A_s ≤ g (with their
// own S and M: the short waves' curvature, a k² with k up to 63 rad/m,
// would otherwise hold the steps to centimetres far above the sea), then
// all the waves. Stepping by these bounds never passes the first crossing:
// a ray that grazes a crest stops on that crest rather than on the trough
// behind it, and one that passes just over a crest's top (g' ≈ 0,
// g'' ≈ M) steps √(2g/M) and leaves it. Near a crossing the Taylor step
// is a damped Newton step (g/|g'| when M g ≪ g'²). A point below the sea
// (t_out, where a step past R − A is held, or rounding) brackets the
// crossing with the last point above for the regula falsi (Illinois: the
// end kept twice in a row has its g halved). The march stops once
// |g| < OCEAN_HIT_TOLERANCE = 1 mm, after OCEAN_MARCH_STEPS = 16 steps at
// most (17 evaluations of the waves' sines and cosines, one of them where
// the long waves hand over to all), and only pixels whose ray has
// displacing waves march. From 2 m and 20 m it converges within them for
// every ray of the tests (tests/ocean_test.cpp, OceanWaves); a ray that
// has not is drawn where it stands, above the surface (a crest's outline
// widens; nothing behind it shows through).
//
// The weights (the screen's footprint; Bruneton, Neyret & Holzschuch 2010,
// §4, for the normals). A wave's phase changes across the pixel's
// footprint on the sea by Δφ = t α |(k_along / μ_v, k_across)| (α the
// pixel's angle, the footprint stretched by 1 / μ_v along the view's
// azimuth). Sampled once per pixel, the wave's height is resolved while
// Δφ < π (two pixels per wavelength, Nyquist); the normal, its derivative,
// fades between Δφ = π/4 and π/2 (8 to 4 pixels per wavelength). The
// displacement fades one octave earlier, 1 − smoothstep(π/8, π/4, Δφ)
// (16 to 8 pixels per wavelength): where a wave stops being geometry its
// normal is still whole, so the change is the position at which its slopes
// are seen, not the slopes; and a wave that is geometry spans at least 8
// pixels per wavelength, so its crests' outlines do not alias. Its height
// must also show: a displacement a along the zenith seen at θ_v from it
// moves the surface's image by a sin θ_v / t rad, a sin θ_v / (t α)
// pixels, and a wave is geometry from 2 pixels, none below 1:
// w_i = (1 − smoothstep(π/8, π/4, Δφ)) smoothstep(1, 2, a_i sin θ_v / (t α)).
// A pixel's weights are those of its ray's point on the sphere (its t and
// μ_v), one set per ray: h is the same function of p along the whole ray,
// and the weights change smoothly from pixel to pixel. Far away every
// weight is 0 and the surface is the sphere exactly.

#if !defined(OCEAN_WAVES_CPP)
#define OCEAN_FLOAT float
#define OCEAN_VEC2 vec2
#define OCEAN_VEC3 vec3
#define OCEAN_VEC4 vec4
#define OCEAN_MAX_WAVES 32
// The sea's waves (ocean.cpp), in increasing wavenumber: the first
// wave_count of wave_vector (xyz: k, rad/m, planet axes; w: the amplitude
// a, m), wave_in_wind (xy: k along the upwind and crosswind axes at the
// waves' anchor; z: |k|; w: a) and wave_phase (k · camera + φ − ω t,
// modulo 2π, rad).
uniform int wave_count;
uniform vec4 wave_vector[OCEAN_MAX_WAVES];
uniform vec4 wave_in_wind[OCEAN_MAX_WAVES];
uniform float wave_phase[OCEAN_MAX_WAVES];
// The pixel's displacing waves: the first ocean_wave_count of the sea's,
// each with its weighted amplitude w_i a_i (m).
float ocean_wave_amplitude[OCEAN_MAX_WAVES];
int ocean_wave_count;
#endif

#define OCEAN_MARCH_STEPS 16
#define OCEAN_HIT_TOLERANCE 1.0e-3
#define OCEAN_SHORT_AMPLITUDE 0.05

// The phase change Δφ of a wave across the pixel's footprint: `footprint`
// the pixel's angle times the distance (m), mu_v the view's cosine to the
// zenith, along_wind the unit azimuth of the view on the wind's axes
// (upwind, crosswind) and k the wave vector on the same axes (rad/m).
INLINE OCEAN_FLOAT ocean_footprint_phase(OCEAN_FLOAT footprint, OCEAN_FLOAT mu_v, OCEAN_VEC2 along_wind, OCEAN_VEC2 k) {
  OCEAN_FLOAT ka = (k.x * along_wind.x + k.y * along_wind.y) / mu_v;
  OCEAN_FLOAT kb = k.y * along_wind.x - k.x * along_wind.y;
  return footprint * sqrt(ka * ka + kb * kb);
}

// A wave's weight in the displacement for phase change `phase_change`
// across the footprint: 1 at 16 pixels per wavelength or more, 0 at 8 or
// fewer.
INLINE OCEAN_FLOAT ocean_displacement_weight(OCEAN_FLOAT phase_change) {
  return 1.0 - smoothstep(0.39269908, 0.78539816, phase_change);
}

// Sets the pixel's displacing waves (ocean_wave_count, ocean_wave_amplitude)
// for its ray's point on the sphere: `footprint` its distance times the
// pixel's angle (m), mu_v and along_wind as ocean_footprint_phase's. Each
// wave's weight is the footprint's (ocean_displacement_weight) times its
// amplitude's size on the screen, smoothstep(1, 2, a sin θ_v / footprint)
// (above). The waves come in increasing
// wavenumber and Δφ ≥ footprint |k|: once that reaches π/4 this wave and
// the shorter ones have weight 0.
INLINE void ocean_select_displacing_waves(OCEAN_FLOAT footprint, OCEAN_FLOAT mu_v, OCEAN_VEC2 along_wind) {
  ocean_wave_count = 0;
  OCEAN_FLOAT amplitude = 0.0;
  OCEAN_FLOAT pixels_per_metre = sqrt(max(1.0 - mu_v * mu_v, 0.0)) / footprint;
  for (int i = 0; i < wave_count; ++i) {
    if (footprint * wave_in_wind[i].z >= 0.78539816) break;
    OCEAN_VEC2 k = OCEAN_VEC2(wave_in_wind[i].x, wave_in_wind[i].y);
    OCEAN_FLOAT w = ocean_displacement_weight(ocean_footprint_phase(footprint, mu_v, along_wind, k)) *
                    smoothstep(1.0, 2.0, wave_vector[i].w * pixels_per_metre);
    ocean_wave_amplitude[i] = w * wave_vector[i].w;
    if (w > 0.0) ocean_wave_count = i + 1;
    amplitude += ocean_wave_amplitude[i];
  }
  // Within OCEAN_HIT_TOLERANCE of the sphere the surface is the sphere.
  if (amplitude < OCEAN_HIT_TOLERANCE) ocean_wave_count = 0;
}

// The height e(t) (m) above the sphere of radius `radius` of the ray's point
// at distance t, for b = r_c (up · d) and c = r_c² − radius².
INLINE OCEAN_FLOAT ocean_ray_height(OCEAN_FLOAT t, OCEAN_FLOAT b, OCEAN_FLOAT c, OCEAN_FLOAT radius) {
  OCEAN_FLOAT q = c + t * (2.0 * b + t);
  return q / (radius + sqrt(max(radius * radius + q, 0.0)));
}

// g(t) = e(t) − h(t d) over the first `count` displacing waves, positive
// above their surface, and its derivative along the ray
// g'(t) = (b + t) / |p| − Σ w_i a_i cos(·) (k_i · d).
INLINE OCEAN_FLOAT ocean_ray_clearance(OCEAN_FLOAT t, OCEAN_VEC3 d, OCEAN_FLOAT b, OCEAN_FLOAT c, OCEAN_FLOAT radius,
                                       int count, OUT(OCEAN_FLOAT) rate) {
  OCEAN_FLOAT e = ocean_ray_height(t, b, c, radius);
  OCEAN_FLOAT h = 0.0;
  rate = (b + t) / (radius + e);
  for (int i = 0; i < count; ++i) {
    OCEAN_FLOAT kd = dot(OCEAN_VEC3(wave_vector[i]), d);
    OCEAN_FLOAT phase = wave_phase[i] + t * kd;
    h += ocean_wave_amplitude[i] * sin(phase);
    rate -= ocean_wave_amplitude[i] * cos(phase) * kd;
  }
  return e - h;
}

// The least s > 0 at which the lower bound g + g' s − ½ M s² of a function
// with value g > 0, derivative g' and |g''| ≤ M reaches 0 (written without
// cancellation for g' < 0).
INLINE OCEAN_FLOAT ocean_safe_step(OCEAN_FLOAT g, OCEAN_FLOAT rate, OCEAN_FLOAT curvature) {
  OCEAN_FLOAT root = sqrt(rate * rate + 2.0 * curvature * g);
  return rate < 0.0 ? 2.0 * g / (root - rate) : (rate + root) / curvature;
}

// The first distance t (m) at which the ray from the camera along unit d
// meets the displaced sea (above), for b = r_c (up · d), c = r_c² − R² and
// R = `radius`. False when the ray passes over every wave (or the camera is
// under the water's surface: no underwater view).
INLINE bool ocean_displaced_hit(OCEAN_VEC3 d, OCEAN_FLOAT b, OCEAN_FLOAT c, OCEAN_FLOAT radius, OUT(OCEAN_FLOAT) t) {
  // A, S and M over all the waves; the long waves: the first `split`,
  // after which the rest's amplitudes add up to A_s ≤ OCEAN_SHORT_AMPLITUDE,
  // and their S and M.
  OCEAN_FLOAT amplitude = 0.0, slope = 0.0, curvature = 0.0, long_slope = 0.0, long_curvature = 0.0;
  int split = ocean_wave_count;
  OCEAN_FLOAT short_amplitude = 0.0;
  for (int i = ocean_wave_count - 1; i >= 0; --i) {
    OCEAN_FLOAT kd = dot(OCEAN_VEC3(wave_vector[i]), d);
    OCEAN_FLOAT a = abs(ocean_wave_amplitude[i]);
    amplitude += a;
    slope += a * abs(kd);
    curvature += a * kd * kd;
    if (split == i + 1 && short_amplitude + a <= OCEAN_SHORT_AMPLITUDE) {
      short_amplitude += a;
      split = i;
    } else {
      long_slope += a * abs(kd);
      long_curvature += a * kd * kd;
    }
  }
  // The shell's bounds: c_hi = r_c² − (R + A)², c_lo = r_c² − (R − A)².
  OCEAN_FLOAT c_hi = c - amplitude * (2.0 * radius + amplitude);
  OCEAN_FLOAT c_lo = c + amplitude * (2.0 * radius - amplitude);
  OCEAN_FLOAT disc_hi = b * b - c_hi, disc_lo = b * b - c_lo;
  t = 0.0;
  if (c_hi > 0.0) {
    if (b >= 0.0 || disc_hi < 0.0) return false;
    t = c_hi / (-b + sqrt(disc_hi));
  }
  bool floor_hit = b < 0.0 && disc_lo >= 0.0;
  OCEAN_FLOAT t_out = floor_hit ? c_lo / (-b + sqrt(disc_lo)) : -b + sqrt(max(disc_hi, 0.0));
  // The bounds of −g' and |g''| on the shell: e' = (b + t)/|p| grows
  // along the ray, e'' = (1 − e'²)/|p| ≤ 1/(R − A).
  OCEAN_FLOAT descent = max(-(b + t), 0.0) / (radius - amplitude);
  curvature += 1.0 / (radius - amplitude);
  long_curvature += 1.0 / (radius - amplitude);
  // Above the sea at t_lo (g_lo > 0); below it at t_hi (g_hi ≤ 0) once a
  // point there is known (t_hi ≥ 0); `side` the end the last regula falsi
  // step moved (Illinois: the other end's g is halved when one end moves
  // twice in a row). `full`: g over all the waves, else over the long ones.
  OCEAN_FLOAT t_lo = t, g_lo = 0.0, t_hi = -1.0, g_hi = 0.0;
  int side = 0;
  bool full = split == 0;
  for (int k = 0; k < OCEAN_MARCH_STEPS; ++k) {
    OCEAN_FLOAT rate;
    OCEAN_FLOAT g = ocean_ray_clearance(t, d, b, c, radius, full ? ocean_wave_count : split, rate);
    if (!full) {
      // The sea's clearance is at least the long waves' less A_s: the
      // bounds on that lower bound (its derivative g', |g''| ≤ M_long).
      OCEAN_FLOAT lower = g - short_amplitude;
      if (lower > short_amplitude) {
        t += max(lower / (descent + long_slope), ocean_safe_step(lower, rate, long_curvature));
        if (t > t_out) {
          if (!floor_hit) return false;
          t = t_out;
        }
        continue;
      }
      full = true;
      g = ocean_ray_clearance(t, d, b, c, radius, ocean_wave_count, rate);
    }
    // Below the sea where the ray enters the shell: the camera is under
    // the water (t = 0), or the ray meets a crest's top (within rounding).
    if (k == 0 && g <= 0.0) return t > 0.0;
    if (abs(g) < OCEAN_HIT_TOLERANCE) return true;
    if (g > 0.0) {
      if (side > 0) g_hi *= 0.5;
      t_lo = t;
      g_lo = g;
      side = t_hi >= 0.0 ? 1 : 0;
    } else {
      if (side < 0) g_lo *= 0.5;
      t_hi = t;
      g_hi = g;
      side = -1;
    }
    if (t_hi >= 0.0) {
      t = t_lo + g_lo * (t_hi - t_lo) / (g_lo - g_hi);
    } else {
      // The larger of the two steps that cannot pass a zero of g (g/L,
      // Taylor's bound).
      t += max(g / (descent + slope), ocean_safe_step(g, rate, curvature));
      // Past R − A the ray is below every wave (a step that reaches it
      // lands there, within rounding); past the shell's far side without
      // meeting R − A it has passed over them.
      if (t > t_out) {
        if (!floor_hit) return false;
        t = t_out;
      }
    }
  }
  return true;
}
