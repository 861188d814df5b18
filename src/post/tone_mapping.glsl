// atmos — the post-processing formulas, defined once.
//
// Written in the common subset of GLSL 4.50 and C++ on glm (the subset of
// src/physics/definitions.glsl): compiled as C++ by post/tone_mapping_cpp.hpp
// (for write_png, the tests and the CPU side of PostProcess) and pasted into
// the compute shaders of PostProcess by post/post_process.cpp. Everything the
// tests check on the CPU is what the GPU runs.
//
// Units. "Scene" values are linear sRGB on the cd/m² scale (their luminance,
// Collienne 2013, eq. 4.27, in cd/m²). "Exposed" values are scene values times the
// exposure E = 1 / L_sat (L_sat in cd/m², see exposure_from_ev100). Display
// values are in [0, 1]: "display-linear" (proportional to the light the
// display emits) or "encoded" (what goes into an 8-bit image).

// Tone-mapping operators (PostProcess settings use the same numbers).
const int TONE_MAP_EXP = 0;       // 1 - exp(-E I): Boody n.d., §1.11; Elek & Kmoch 2010; write_png
const int TONE_MAP_REINHARD = 1;  // Bruneton's Reinhard variant: Collienne 2013, eq. 4.25-4.26
const int TONE_MAP_FILMIC = 2;    // Hejl / Burgess-Dawson: Collienne 2013, eq. 4.29
const int TONE_MAP_ACES = 3;      // Narkowicz's fit of the ACES RRT + ODT
const int TONE_MAP_LINEAR = 4;    // E I unchanged (clamped to [0, 1] in 8-bit output only)

// Relative luminance of linear sRGB, Collienne 2013, eq. 4.27 (the Y row of the
// sRGB -> XYZ matrix, IEC 61966-2-1).
INLINE float relative_luminance(vec3 rgb) { return 0.2126f * rgb.x + 0.7152f * rgb.y + 0.0722f * rgb.z; }

// The exposure E (1 / (cd/m²)) of a camera at exposure value `ev100`
// (ISO 100): E = 1 / L_sat with the saturation luminance
// L_sat = 78 / (S q) 2^EV = 1.2 * 2^EV cd/m² for S = 100 and lens/vignetting
// factor q = 0.65. The same definition as write_png (include/atmos/image.hpp).
INLINE float exposure_from_ev100(float ev100) { return 1.0f / (1.2f * exp2(ev100)); }

// The inverse: the EV100 whose exposure is E.
INLINE float ev100_from_exposure(float exposure) { return log2(1.0f / (1.2f * exposure)); }

// --- Tone-mapping curves, per channel of an exposed value x = E I ----------

// Boody n.d., §1.11 (and Elek & Kmoch 2010): display-linear 1 - exp(-x). 0 -> 0,
// increasing, tends to 1 (never reaches it).
INLINE float tone_map_exp_channel(float x) { return 1.0f - exp(-max(x, 0.0f)); }

// Collienne 2013, eq. 4.25-4.26 (Bruneton & Neyret 2008's variant of Reinhard et al.
// 2002): below the switch x < 1.413 the power law (0.38317 x)^(1/2.2)
// (eq. 4.25), above it 1 - exp(-x) (eq. 4.26). The thesis text as extracted
// prints the switch as "1.1413" and the exponent on 0.38317 alone; the two
// branches meet (to 3.4e-5) only at x = 1.413 with the exponent on the
// product, which is also Bruneton's code. The power branch includes the
// display's 2.2 gamma ("the x^2.2 factor of display gamma is also noticeable
// in the tonemapping by Reinhard", Collienne 2013, §4.6.3): the result is an
// ENCODED display value. At the switch the curve steps down by 3.4e-5 (0.009
// of an 8-bit step); otherwise it increases and tends to 1.
const float REINHARD_SWITCH = 1.413f;
INLINE float tone_map_reinhard_channel(float x) {
  x = max(x, 0.0f);
  return x < REINHARD_SWITCH ? pow(0.38317f * x, 1.0f / 2.2f) : 1.0f - exp(-x);
}

// Collienne 2013, eq. 4.29: Hejl and Burgess-Dawson's filmic curve (as
// published by Hable 2010, filmicgames.com/archives/75, without its 0.004
// black offset, which Collienne 2013 omits): x (6.2 x + 0.5) / (x (6.2 x + 1.7) + 0.06). Includes the
// display's 2.2 gamma: an ENCODED display value. 0 -> 0, increasing
// (derivative numerator 7.44 x² + 0.744 x + 0.03 > 0), tends to 1 from below
// (1 - f = (1.2 x + 0.06) / (...) > 0).
INLINE float tone_map_filmic_channel(float x) {
  x = max(x, 0.0f);
  return (x * (6.2f * x + 0.5f)) / (x * (6.2f * x + 1.7f) + 0.06f);
}

// Narkowicz 2016, "ACES Filmic Tone Mapping Curve"
// (knarkowicz.wordpress.com): a rational fit (max error 0.0138) of the ACES
// RRT + ODT for a linear display, its input pre-exposed by 0.6.
// x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clamped to [0, 1]:
// display-LINEAR. 0 -> 0, increasing (derivative numerator
// 1.408 x² + 0.7028 x + 0.0042 > 0), reaches 1 at x = 7.2417 (the root of
// 0.08 x² - 0.56 x - 0.14) and stays there.
INLINE float tone_map_aces_channel(float x) {
  x = max(x, 0.0f);
  return clamp((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f), 0.0f, 1.0f);
}

INLINE float tone_map_channel(float x, int op) {
  if (op == TONE_MAP_REINHARD) return tone_map_reinhard_channel(x);
  if (op == TONE_MAP_FILMIC) return tone_map_filmic_channel(x);
  if (op == TONE_MAP_ACES) return tone_map_aces_channel(x);
  if (op == TONE_MAP_LINEAR) return max(x, 0.0f);
  return tone_map_exp_channel(x);
}

// Whether the operator's formula includes the display gamma (2.2), i.e.
// gives encoded values (reinhard, filmic), or display-linear ones.
INLINE bool tone_map_is_encoded(int op) { return op == TONE_MAP_REINHARD || op == TONE_MAP_FILMIC; }

// The sRGB OETF (IEC 61966-2-1) of a display-linear value in [0, 1].
INLINE float srgb_encode(float linear) {
  linear = clamp(linear, 0.0f, 1.0f);
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * pow(linear, 1.0f / 2.4f) - 0.055f;
}

// The 8-bit display value of one channel of an exposed value x: the
// operator's own encoding for reinhard and filmic (Collienne 2013's formulas,
// written for a 2.2-gamma display), the sRGB OETF of the display-linear value
// otherwise (Boody n.d., §1.11, uses a 2.2 gamma; sRGB is the standard that
// write_png has always used). In [0, 1].
INLINE float display_encoded_channel(float x, int op) {
  float t = tone_map_channel(x, op);
  // (1.055 - 0.055 is 1 + 1 ulp in float: clamp after the encoding too.)
  return clamp(tone_map_is_encoded(op) ? t : srgb_encode(t), 0.0f, 1.0f);
}

// The display-linear value of one channel (for float outputs that an
// engine encodes itself): the encoded operators decoded with their 2.2
// gamma; `linear` unclamped, the others in [0, 1].
INLINE float display_linear_channel(float x, int op) {
  float t = tone_map_channel(x, op);
  return tone_map_is_encoded(op) ? pow(clamp(t, 0.0f, 1.0f), 2.2f) : t;
}

INLINE vec3 display_encoded(vec3 exposed, int op) {
  return vec3(display_encoded_channel(exposed.x, op), display_encoded_channel(exposed.y, op),
              display_encoded_channel(exposed.z, op));
}

INLINE vec3 display_linear(vec3 exposed, int op) {
  return vec3(display_linear_channel(exposed.x, op), display_linear_channel(exposed.y, op),
              display_linear_channel(exposed.z, op));
}

// --- Automatic exposure (Collienne 2013, §4.6.3) -------------------------

// Luminance below which the log average stops following a pixel (cd/m²;
// about the darkest of scotopic vision): Reinhard et al. 2002's delta, which
// keeps log(0) out of the average.
const float LOG_AVERAGE_DELTA = 1e-4f;

INLINE float log_luminance(vec3 scene_rgb) { return log(LOG_AVERAGE_DELTA + max(relative_luminance(scene_rgb), 0.0f)); }

// The key of Collienne 2013 (eq. 4.28): epsilon = (1 / l) (1 / (2^2.2 - 1)) maps the
// average luminance l to the exposed value 1 / (2^2.2 - 1) = 0.27818.
const float DEFAULT_EXPOSURE_KEY = 0.27818f;

// The exposure value that maps the scene's log-average luminance
// l_avg = exp(mean(log(delta + l))) (cd/m²; Collienne 2013, eq. 4.27 per pixel,
// averaged in the log domain as Reinhard et al. 2002 eq. 1, which keeps the
// sun from setting the exposure alone) to the exposed value `key`
// (eq. 4.28: E = key / l_avg), shifted by `compensation_ev` (positive:
// brighter image, i.e. a lower EV) and clamped to [ev_min, ev_max].
// E = 1 / (1.2 2^EV)  =>  EV = log2(l_avg / (1.2 key)).
INLINE float exposure_target_ev(float log_average_luminance, float key, float compensation_ev, float ev_min,
                                float ev_max) {
  float ev = log2(log_average_luminance / (1.2f * key)) - compensation_ev;
  return clamp(ev, ev_min, ev_max);
}

// One step of temporal adaptation (Collienne 2013, §4.6.3, "dynamic exposure"): the
// exposure value relaxes exponentially towards the target,
//   EV' = target + (EV - target) exp(-dt / tau),
// with tau = brightening_tau_s when the scene got brighter than the current
// adaptation (target > EV: the exposure decreases; light adaptation, fast) and
// darkening_tau_s when it got darker (dark adaptation, slow). Working in EV
// (log luminance) makes the speed independent of the absolute level. tau = 0:
// instantaneous.
INLINE float adapted_ev(float current_ev, float target_ev, float dt_s, float brightening_tau_s,
                        float darkening_tau_s) {
  float tau = target_ev > current_ev ? brightening_tau_s : darkening_tau_s;
  float keep = tau > 0.0f ? exp(-dt_s / tau) : 0.0f;
  return target_ev + (current_ev - target_ev) * keep;
}

// --- Bloom (Collienne 2013, §4.6.1) --------------------------------------

// The part of a pixel that blooms: the scene colour scaled by the fraction of
// its exposed luminance above `threshold` (exposed units; 0: the whole
// pixel), so that the hue is kept and the bright pass is continuous. The rest
// of the pixel stays sharp. (Collienne 2013, §4.6.1, raises the colours to the 4th
// power instead, which creates light; here the bloom only moves light.)
INLINE vec3 bright_part(vec3 scene_rgb, float exposure, float threshold) {
  float l = max(relative_luminance(scene_rgb), 0.0f) * exposure;
  return l > threshold ? max(scene_rgb, vec3(0.0f)) * ((l - threshold) / l) : vec3(0.0f);
}

// Turkowski's incremental Gaussian (Turkowski 2007, GPU Gems 3 ch. 40;
// Collienne 2013, §4.6.1): the
// weights g(k) = exp(-k² / (2 sigma²)) / (sqrt(2 pi) sigma) for k = 0, 1, 2,
// ... without an exp per tap. The ratio g(k+1) / g(k) = exp(-(2k+1) /
// (2 sigma²)) is itself multiplied by the constant exp(-1 / sigma²) from one
// tap to the next: one exponential at the start, then products.
// State: x = g(k), y = g(k+1) / g(k), z = exp(-1 / sigma²).
INLINE vec3 incremental_gaussian_start(float sigma) {
  float r = exp(-0.5f / (sigma * sigma));
  return vec3(1.0f / (sqrt(2.0f * 3.14159265f) * sigma), r, r * r);
}

INLINE vec3 incremental_gaussian_next(vec3 g) { return vec3(g.x * g.y, g.y * g.z, g.z); }
