// atmos — eclipses: how much of the (limb-darkened) solar disc a moon hides.
//
// Shared by the CPU (physics/shader_cpp.hpp) and the shaders
// (gpu/shader_source.cpp), after functions.glsl (SUN_LIMB_DARKENING_U), in
// the GLSL / C++ subset of definitions.glsl.
//
// Seen from a point, the sun and a moon are discs of angular radii a and b
// whose centres are d apart. The discs are a few tenths of a degree wide:
// they are treated as flat circles in the tangent plane (relative error ~a²,
// 2e-5 for the Sun seen from the Earth). Cases: no overlap (d >= a + b);
// total (the moon covers the sun: d <= b - a); annular (the sun rings the
// moon: d <= a - b); partial otherwise.

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

// Limb-darkened intensity at radius rho of a disc of radius a (functions.glsl:
// the linear law with u = SUN_LIMB_DARKENING_U), relative to its centre.
INLINE float limb_darkening(float rho, float a) {
  float mu = safe_sqrt(1.0f - (rho * rho) / (a * a));
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
  // The whole disc's flux: pi a² (1 - u / 3) (functions.glsl, sun_disc_radiance).
  float total = PI * a * a * (1.0f - SUN_LIMB_DARKENING_U / 3.0f);
  return clamp(1.0f - covered / total, 0.0f, 1.0f);
}
