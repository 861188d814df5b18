// Procedural relief: the styles, their sources, and the bounds the level of
// detail uses.
//
// Height = a sum of terms (a large-scale field mapped to a hypsometry, masked
// ridged octaves, fBm detail octaves, crater size classes, dunes). Every term
// t carries a TermBound: its range [low, high], a Lipschitz constant L (m/m in
// 3D) and, when it is C1 with a bounded second derivative, a curvature bound
// K (1/m). The planet's height range is the sum of the ranges; the error
// bound of a mesh is the sum of the terms' interpolation error bounds (the
// interpolation I is linear, so h - I h = sum (t - I t)).
//
// Interpolation error of one term on a grid cell of spacing D, bilinear
// weights w_c (convex) at the corners c:
//   (a) |t - I t| <= high - low (I t and t both lie in [low, high]);
//   (b) |t(x) - I t(x)| <= sum_c w_c L |x - c| <= L sqrt(sum_c w_c |x - c|^2)
//       = L D sqrt(a(1 - a) + b(1 - b)) <= L D / sqrt(2) (Jensen; a, b the
//       cell coordinates), valid for kinked terms (ridges, crater rims);
//   (c) for a C2 term, the tensor-product bound |t - I t| <= D^2/8 (|t_uu| +
//       |t_vv|) <= D^2/4 K' (e.g. Quarteroni, Sacco & Saleri 2007, §8.7),
//       where K' bounds the second derivative along the grid lines on the
//       sphere. A grid line x(u) = R normalize(q0 + u e / R) (the tangent-plane
//       grids of the tests; a cube-sphere tile's lines are gnomonic arcs of
//       the same kind) has |x'| <= 1 and |x''| <= 3 / R, so
//       |d2 t / du2| <= K + 3 L / R; 4 L / R is used.
// error(D) = sum over the terms of min(a, b, c): each of a, b, c is
// non-decreasing in D, so the bound is non-increasing with the level.
//
// Derivative bounds of the scaled gradient noise n (planet/noise.glsl) per
// lattice unit, for a unit vector e, with s the quintic fade (max s' = 15/8,
// max |s''| = 10/sqrt(3)), W_c the corner weights, L_c = g_c . (f - c),
// |L_c| <= sum_i |f_i - c_i| and sum_c W_c |f_i - c_i| <= 1/2:
//   D_e n = sum_c (D_e W_c) L_c + sum_c W_c g_c . e. Per axis j,
//   sum_c |d_j W_c| |L_c| <= s'(f_j) (1 + 2 * 2 * 1/2) = 3 s'(f_j), so the
//   first sum is <= 3 (15/8) |e|_1 <= 3 (15/8) sqrt(3) = 9.743, the second
//   <= |g| = sqrt(2); times the scale 2/3: |D_e n| <= 7.44.
//   D_e^2 n = sum_c (D_e^2 W_c) L_c + 2 sum_c (D_e W_c) g_c . e:
//   sum_c |d_jj W_c| |L_c| <= 3 |s''| <= 17.32, sum_c |d_jk W_c| |L_c| <=
//   (15/8)^2 (2 + 2 + 4 * 1/2) = 21.09 (j != k), so the first sum is
//   <= 17.32 + 2 * 21.09 = 59.5 (sum_{j != k} |e_j e_k| <= 2); the second
//   <= 2 sqrt(2) * 2 (15/8) |e|_1 <= 18.37; times 2/3: |D_e^2 n| <= 52.
#include "planet/relief.hpp"

#include "atmos/atmosphere.hpp"
#include "planet/noise_cpp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#if defined(ATMOS_KERNEL_CLONES) && defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define ATMOS_NOISE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define ATMOS_NOISE_CLONES
#endif

namespace atmos::planet {

namespace {

constexpr double kNoiseBound = 1.0;        // |n| (the octaves' value bounds below)
constexpr double kNoiseSlope = 7.44;       // |D_e n| per lattice unit (above)
constexpr double kNoiseCurvature = 52.0;   // |D_e^2 n| per lattice unit^2
constexpr double kFadeSlope = 1.875;       // max s'
constexpr double kFadeCurvature = 5.7736;  // max |s''| = 10 / sqrt(3), rounded up
constexpr double kRidgeSlope = 4.0;        // d/dn (1 - |n|)^4 <= 4 for |n| <= 1
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// The canyon, after Valles Marineris (Smith et al. 1999, MOLA): about
// 4000 km long, 150 km wide on its floor (half width 75 km, +-30 % along
// its length), walls 20 km wide, 7 km deep, its ends rising over 300 km.
constexpr double kCanyonLength_m = 4000e3, kCanyonHalfWidth_m = 75e3, kCanyonWall_m = 20e3;
constexpr double kCanyonDepth_m = 7000.0, kCanyonTaper_m = 300e3, kCanyonWobble = 0.3;
constexpr double kCanyonWobbleWavelength_m = 400e3;

// Per-octave amplitude ratios 2^-H for Hurst exponents H (fBm with spectral
// slope beta = 2H + 1; Musgrave et al. 1989), as literals so that no platform
// pow enters the heights.
constexpr double kGainHurst070 = 0.6155722066724582;  // 2^-0.70
constexpr double kGainHurst075 = 0.5946035575013605;  // 2^-0.75
constexpr double kGainHurst080 = 0.5743491774985175;  // 2^-0.80

double fade_mask(double t) { return noise_smooth_mask(t); }

uvec3 layer_key(std::uint64_t seed, std::uint32_t layer, std::uint32_t index) {
  return pcg3d(uvec3(std::uint32_t(seed), std::uint32_t(seed >> 32), layer * 65536u + index));
}

}  // namespace

// Split lattice coordinates of p / wavelength + offset: the cell (int64
// floor, wrapped to 32 bits for the hash) and the fraction in [0, 1).
// Compiled also for AVX2 (one register for the eight corners' hashes) and
// chosen at run time, as the precomputation's kernels are (ATMOS_KERNEL_CLONES);
// AVX2 without FMA, so that both copies round alike.
ATMOS_NOISE_CLONES double octave_noise(const glm::dvec3& p_m, const Relief::Octave& octave) {
  const glm::dvec3 q = p_m * octave.inv_wavelength_per_m + octave.offset;
  const glm::dvec3 floor_q(std::floor(q.x), std::floor(q.y), std::floor(q.z));
  const uvec3 cell(std::uint32_t(std::int64_t(floor_q.x)), std::uint32_t(std::int64_t(floor_q.y)),
                   std::uint32_t(std::int64_t(floor_q.z)));
  return gradient_noise_lanes(cell, q - floor_q, octave.key);
}

namespace {

// Octaves of wavelength lambda_0 2^-k (k < count), amplitude a_0 gain^k, each
// on its own lattice (key) shifted by a dyadic fraction so that the lattices
// of successive octaves do not share their zeros.
std::vector<Relief::Octave> make_octaves(std::uint64_t seed, std::uint32_t layer, double wavelength_m,
                                         double amplitude_m, double gain, int count) {
  std::vector<Relief::Octave> octaves;
  for (int k = 0; k < count; ++k) {
    Relief::Octave o;
    o.inv_wavelength_per_m = 1.0 / wavelength_m;
    o.amplitude_m = amplitude_m;
    o.key = layer_key(seed, layer, std::uint32_t(k));
    const uvec3 h = pcg3d(o.key);
    o.offset = glm::dvec3(double(h.x >> 24), double(h.y >> 24), double(h.z >> 24)) / 256.0;
    octaves.push_back(o);
    wavelength_m *= 0.5;
    amplitude_m *= gain;
  }
  return octaves;
}

// Octaves down to the first wavelength below min_wavelength_m.
int octaves_down_to(double wavelength_m, double min_wavelength_m) {
  int count = 1;
  while (wavelength_m >= min_wavelength_m) {
    wavelength_m *= 0.5;
    ++count;
  }
  return count;
}

// Sum of amplitude / wavelength^power over octaves (the derivative bounds of
// a sum of octaves).
double octave_sum(const std::vector<Relief::Octave>& octaves, int power) {
  double sum = 0;
  for (const auto& o : octaves) {
    double f = 1;
    for (int i = 0; i < power; ++i) f *= o.inv_wavelength_per_m;
    sum += o.amplitude_m * f;
  }
  return sum;
}

double amplitude_sum(const std::vector<Relief::Octave>& octaves) { return octave_sum(octaves, 0); }

// Normalise a layer's amplitudes to sum to `total`.
void normalise(std::vector<Relief::Octave>& octaves, double total) {
  const double scale = total / amplitude_sum(octaves);
  for (auto& o : octaves) o.amplitude_m *= scale;
}

// x^e on [1, 2] as 1 + e u + (2^e - 1 - e) u^2 (u = x - 1): exact at both
// ends and in slope at 1, within 0.3 % for the exponents below; avoids pow.
double power_shape(double u, double exponent, double shape) { return 1.0 + u * (exponent + shape * u); }

// Earth's hypsometry (Eakins & Sharman 2012: 29 % land, mean land height
// 0.84 km, mean ocean depth 3.7 km, shelves to about -130 m) as a C2 function
// of t = c - c_coast, c the continent field in [-1, 1]: the abyssal floor at
// -4800 m, the continental slope and rise over t in [-0.08, -0.02], the shelf
// from -120 m to +20 m over [-0.02, 0], the land rising 1400 m inland over
// [0, 0.08].
struct Step {
  double height_m, start, width;
};
constexpr Step kEarthSteps[] = {{4680.0, -0.08, 0.06}, {140.0, -0.02, 0.02}, {1400.0, 0.0, 0.08}};
constexpr double kEarthAbyss_m = -4800.0;
// With a data coast: the distance from the coast over which the continent
// coordinate changes by one (t = -0.08, the foot of the continental slope,
// lies 300 km offshore; the land reaches its mean height 300 km inland),
// and the least height of land (and depth of sea) next to the coast, m.
constexpr double kCoastProfile_m = 3750e3;
constexpr double kCoastLand_m = 2.0;

double earth_hypsometry(double t) {
  double h = kEarthAbyss_m;
  for (const Step& s : kEarthSteps) h += s.height_m * fade_mask((t - s.start) / s.width);
  return h;
}

// Garvin & Frawley 1998 (MOLA, fresh Martian craters), D and d in km:
// simple d = 0.14 D^0.90, complex d = 0.25 D^0.49; the two laws cross at
// D = 4.1 km and the depth used is the smaller, which is continuous. Rim
// height h_r = 0.036 D^1.014 (Pike 1977, fresh lunar craters), at most d/3
// (the cap binds from D = 9.7 km, where rims of complex craters stop growing
// as fast). Literals: 2^0.90, 2^0.49, 2^1.014.
constexpr double kTwoPow090 = 1.8660659830736148;
constexpr double kTwoPow049 = 1.4044448757379973;
constexpr double kTwoPow1014 = 2.0195025951933716;
constexpr double kComplexCraterDiameter_m = 8000.0;  // flat floors above (Garvin & Frawley 1998)
constexpr double kFloorFraction = 0.4;               // floor radius / rim radius of complex craters
constexpr double kEjectaReach = 2.0;                 // ejecta to two crater radii

// Crater profile in r = distance / radius (McGetchin, Settle & Head 1973:
// ejecta thickness ~ r^-3): a bowl -d + (d + h_r) phi(r), phi =
// max(0, (r - f) / (1 - f))^2 (f the flat floor's fraction), for r < 1; the
// ejecta h_r (r^-3 - 1/8) / (7/8) for 1 <= r < 2, zero beyond.
double crater_profile(double r, double depth_m, double rim_m, double floor_fraction) {
  if (r < 1.0) {
    const double a = std::max(0.0, (r - floor_fraction) / (1.0 - floor_fraction));
    return -depth_m + (depth_m + rim_m) * a * a;
  }
  if (r < kEjectaReach) return rim_m * (1.0 / (r * r * r) - 0.125) / 0.875;
  return 0.0;
}

}  // namespace

const char* relief_style_name(ReliefStyle style) {
  switch (style) {
    case ReliefStyle::earth: return "earth";
    case ReliefStyle::mars: return "mars";
    case ReliefStyle::venus: return "venus";
    case ReliefStyle::titan: return "titan";
    case ReliefStyle::flat: return "flat";
  }
  return "unknown";
}

Relief::Relief(const ReliefSettings& settings) : settings_(settings) {
  const double R = settings.radius_m;
  if (!(std::isfinite(R) && R > 0)) throw Error("relief: the radius must be finite and positive, got " + std::to_string(R) + " m");
  const std::uint64_t seed = settings.seed;
  const double min_wavelength_m = 0.5;  // the finest detail octave lies in [0.25, 0.5) m
  switch (settings.style) {
    case ReliefStyle::flat:
      break;
    case ReliefStyle::earth: {
      // Continents: fBm of wavelengths 16000..1000 km, thresholded so that 29 %
      // of the sphere is land (Eakins & Sharman 2012); the field's threshold
      // is put at 74 % because the detail noise raises about 3 % of the area
      // next to the coasts above the sea.
      large_scale_ = make_octaves(seed, 1, 16000e3, 1.0, 0.5, 5);
      normalise(large_scale_, 1.0);
      calibrate_threshold(0.74);
      // Mountain belts: a 3000 km field selects belts on and near land;
      // ridged octaves 1000..7.8 km (Musgrave et al. 1989), (1 - |n|)^4 each,
      // 3.6 km for the first: peaks of the belts to about 7-9 km.
      belt_ = make_octaves(seed, 2, 3000e3, 1.0, 0.5, 2);
      normalise(belt_, 1.0);
      ridges_ = make_octaves(seed, 3, 1000e3, 3600.0, 0.5, 8);
      // Detail: fBm with H = 0.7 from 250 km (600 m) to below 0.5 m.
      detail_ = make_octaves(seed, 4, 250e3, 600.0, kGainHurst070, octaves_down_to(250e3, min_wavelength_m));
      // A data coast's wiggle: octaves from twice the data's resolution
      // down to 100 m, each of amplitude 0.15 times its wavelength (H = 1:
      // a self-similar coast, of fractal dimension near 1.2 once the
      // data's own shape is added; Mandelbrot 1967).
      if (settings.coast_distance_m) {
        if (!(settings.coast_resolution_m > 0.0)) throw Error("relief: a data coast needs its resolution");
        const double longest = 2.0 * settings.coast_resolution_m;
        coast_wiggle_ = make_octaves(seed, 11, longest, 0.15 * longest, 0.5, octaves_down_to(longest, 100.0));
      }
      sea_level_m_ = 0.0;
      break;
    }
    case ReliefStyle::mars: {
      // The dichotomy (Smith et al. 1999, MOLA): northern lowlands near
      // -4 km, southern highlands near +1.5 km, a boundary that wanders about
      // a great circle tilted from the equator; its axis is tilted by up to
      // ~20 deg towards a seeded longitude.
      const uvec3 h = pcg3d(layer_key(seed, 5, 0));
      dichotomy_axis_ = glm::normalize(glm::dvec3((double(h.x >> 22) - 512.0) / 1400.0,
                                                  (double(h.y >> 22) - 512.0) / 1400.0, -1.0));
      large_scale_ = make_octaves(seed, 6, 3000e3, 1.0, 0.5, 3);
      normalise(large_scale_, 0.12);
      // Detail: H = 0.75, from 2000 km (1200 m) to below 0.5 m; a quarter of
      // it on the lowlands, the flattest plains known (Smith et al. 1999).
      detail_ = make_octaves(seed, 7, 2000e3, 1200.0, kGainHurst075, octaves_down_to(2000e3, min_wavelength_m));
      // Craters: diameters 256 km .. 62.5 m (13 classes); on the highlands
      // every lattice candidate is a crater, on the lowlands 12 % of them.
      for (int k = 0; k < 13; ++k) {
        CraterClass c;
        c.min_diameter_m = 256e3 / double(1 << k);
        craters_.push_back(c);
      }
      crater_presence_high_ = 1.0;
      crater_presence_low_ = 0.12;
      // The canyon: near the equator (its great circle's pole within 13 deg
      // of the north pole, towards a seeded direction), its middle at a
      // seeded longitude; one octave of noise for its width (|n| <= 1).
      {
        const uvec3 k = pcg3d(layer_key(seed, 13, 0));
        const auto unit = [](std::uint32_t v) { return double(v >> 8) / 8388608.0 - 1.0; };  // [-1, 1)
        canyon_pole_ = glm::normalize(glm::dvec3(0.17 * unit(k.x), 0.17 * unit(k.y), 1.0));
        glm::dvec3 middle(unit(k.z), unit(pcg3d(k).x), 0.0);
        if (glm::dot(middle, middle) < 1e-6) middle = glm::dvec3(1.0, 0.0, 0.0);
        canyon_centre_ = glm::normalize(middle - canyon_pole_ * glm::dot(middle, canyon_pole_));
        canyon_wobble_ = make_octaves(seed, 14, kCanyonWobbleWavelength_m, 1.0, 0.5, 1);
      }
      break;
    }
    case ReliefStyle::venus: {
      // Plains within about +-1 km and a few highlands (tessera plateaus,
      // Ishtar Terra with Maxwell Montes near +11 km; Ford & Pettengill
      // 1992): a continent field thresholded at 10 % of the area.
      large_scale_ = make_octaves(seed, 1, 8000e3, 1.0, 0.5, 5);
      normalise(large_scale_, 1.0);
      calibrate_threshold(0.90);
      ridges_ = make_octaves(seed, 3, 500e3, 3000.0, 0.5, 6);
      detail_ = make_octaves(seed, 4, 2000e3, 500.0, kGainHurst075, octaves_down_to(2000e3, min_wavelength_m));
      // About 940 craters, none below ~2 km (the thick atmosphere screens small
      // impactors; Phillips et al. 1992): classes 256..2 km, 1 % of the
      // candidates. Shapes follow the Mars laws above.
      for (int k = 0; k < 8; ++k) {
        CraterClass c;
        c.min_diameter_m = 256e3 / double(1 << k);
        craters_.push_back(c);
      }
      crater_presence_high_ = crater_presence_low_ = 0.01;
      break;
    }
    case ReliefStyle::titan: {
      // Low relief (a few hundred metres; Lorenz et al. 2013) and linear
      // dunes in the equatorial belt, crests running east-west, spacing about
      // 3 km, heights about 100 m (Lorenz et al. 2006).
      detail_ = make_octaves(seed, 4, 2000e3, 250.0, kGainHurst080, octaves_down_to(2000e3, min_wavelength_m));
      dunes_ = make_octaves(seed, 8, 3000.0, 100.0, 0.3, 2);
      break;
    }
  }
  // Crater lattices: cell S = 20 D (D the class's smallest diameter, radii
  // below D). Exclusivity (at most one crater of a class covers any point,
  // and it lies in the point's own cell): the candidate centre c is drawn in
  // the middle half of the cell, [S/4, 3S/4]^3, and kept only if
  // ||c| - R| <= S/8; its footprint on the sphere, |x - c'| < 2 radius
  // sqrt(R/|c|) <= 2 D / sqrt(1 - S/(8R)) < S/8 for S <= R (c' = R c/|c|),
  // then stays within S/4 of c: inside the cell. Classes with S > R are
  // dropped. The probability of a candidate per cell does not depend on the
  // class, so the number of craters per area scales as D^-2, the cumulative
  // size-frequency slope of the production function over ~1-100 km (Hartmann
  // 2005; Neukum, Ivanov & Hartmann 2001).
  {
    std::vector<CraterClass> kept;
    for (std::size_t k = 0; k < craters_.size(); ++k) {
      CraterClass c = craters_[k];
      c.cell_m = 20.0 * c.min_diameter_m;
      if (c.cell_m > R) continue;
      c.inv_cell_per_m = 1.0 / c.cell_m;
      // D^e at D = min_diameter (km) = (2^e)^j for D = 2^j km, by repeated
      // multiplication of the literals (j may be negative).
      const int j = 8 - int(k);
      double p090 = 1, p049 = 1, p1014 = 1;
      for (int i = 0; i < (j > 0 ? j : -j); ++i) {
        p090 *= kTwoPow090;
        p049 *= kTwoPow049;
        p1014 *= kTwoPow1014;
      }
      if (j < 0) {
        p090 = 1.0 / p090;
        p049 = 1.0 / p049;
        p1014 = 1.0 / p1014;
      }
      c.simple_depth_m = 140.0 * p090;
      c.simple_depth_shape = kTwoPow090 - 1.0 - 0.90;
      c.complex_depth_m = 250.0 * p049;
      c.complex_depth_shape = kTwoPow049 - 1.0 - 0.49;
      c.rim_m = 36.0 * p1014;
      c.rim_shape = kTwoPow1014 - 1.0 - 1.014;
      c.key = layer_key(seed, 9, std::uint32_t(k));
      const uvec3 h = pcg3d(c.key);
      c.offset = glm::dvec3(double(h.x >> 24), double(h.y >> 24), double(h.z >> 24)) / 256.0;
      kept.push_back(c);
    }
    craters_ = kept;
  }
  finish_bounds();
}

double Relief::crater_class_min_diameter_m(int size_class) const {
  return craters_.at(std::size_t(size_class)).min_diameter_m;
}

double Relief::sum_octaves(const std::vector<Octave>& octaves, const glm::dvec3& p_m) const {
  double sum = 0;
  for (const Octave& o : octaves) sum += o.amplitude_m * octave_noise(p_m, o);
  return sum;
}

double Relief::detail_m(const glm::dvec3& direction, double max_wavelength_m) const {
  const glm::dvec3 p = direction * settings_.radius_m;
  double sum = 0;
  for (const Octave& o : detail_)
    if (1.0 < o.inv_wavelength_per_m * max_wavelength_m) sum += o.amplitude_m * octave_noise(p, o);
  return sum;
}

double Relief::albedo_variation(const glm::dvec3& direction, double max_wavelength_m, double min_wavelength_m) const {
  const glm::dvec3 p = direction * settings_.radius_m;
  double sum = 0, amplitude = 0.12;
  Octave o;
  std::uint32_t k = 0;
  for (double wavelength = max_wavelength_m; wavelength >= std::max(min_wavelength_m, 1.0) && k < 24;
       wavelength *= 0.5, amplitude *= 0.5, ++k) {
    o.inv_wavelength_per_m = 1.0 / wavelength;
    o.key = layer_key(settings_.seed, 12, k);
    sum += amplitude * octave_noise(p, o);
  }
  return sum;
}

double Relief::detail_bound_m(double max_wavelength_m) const {
  double sum = 0;
  for (const Octave& o : detail_)
    if (1.0 < o.inv_wavelength_per_m * max_wavelength_m) sum += kNoiseBound * o.amplitude_m;
  return sum;
}

// The canyon's depth (<= 0): -D a(s) w(x). With c the direction of the
// canyon's middle, n the pole of its great circle and t = n x c: x =
// R |d . n| is the distance from the great circle, s = R d . t the
// position along it (both within 0.1 % of the arcs at these angles, and
// without the platform's trigonometry, which would break the bit-for-bit
// heights); a rises from 0 to 1 over the taper at each end (|s| up to half
// the length, on the hemisphere d . c > 0), w is 1 on the floor (x below
// the wobbling half width minus the wall) and falls to 0 across the wall
// (C2 masks).
double Relief::canyon_m(const glm::dvec3& direction, const glm::dvec3& p_m) const {
  if (canyon_wobble_.empty() || glm::dot(direction, canyon_centre_) <= 0.0) return 0.0;
  const double R = settings_.radius_m;
  const double along = glm::dot(direction, glm::cross(canyon_pole_, canyon_centre_)) * R;
  const double ends = fade_mask((0.5 * kCanyonLength_m - std::abs(along)) / kCanyonTaper_m);
  if (!(ends > 0.0)) return 0.0;
  const double across = std::abs(glm::dot(direction, canyon_pole_)) * R;
  const double half_width = kCanyonHalfWidth_m * (1.0 + kCanyonWobble * sum_octaves(canyon_wobble_, p_m));
  return -kCanyonDepth_m * ends * fade_mask((half_width - across) / kCanyonWall_m);
}

glm::dvec3 Relief::canyon_centre() const { return canyon_wobble_.empty() ? glm::dvec3(0.0) : canyon_centre_; }

double Relief::large_scale_field(const glm::dvec3& p_m) const { return sum_octaves(large_scale_, p_m); }

// The Mars dichotomy coordinate: the component along the (southward) axis
// plus the boundary's wobble; the highlands lie where it exceeds -0.15.
double Relief::dichotomy_coordinate(const glm::dvec3& direction, const glm::dvec3& p_m) const {
  return glm::dot(dichotomy_axis_, direction) + large_scale_field(p_m);
}

namespace {
constexpr double kDichotomyEdge = -0.15, kDichotomyWidth = 0.3;
constexpr double kLowlands_m = -4000.0, kDichotomyStep_m = 5500.0;
}  // namespace

double Relief::crater_presence(const glm::dvec3& centre_direction) const {
  const double m = fade_mask((glm::dot(dichotomy_axis_, centre_direction) - kDichotomyEdge) / kDichotomyWidth);
  return crater_presence_low_ + (crater_presence_high_ - crater_presence_low_) * m;
}

// The crater of a class in the cell of p, if the candidate exists and p lies
// within its ejecta; r = distance / radius.
bool Relief::crater_in_cell(const glm::dvec3& p_m, const CraterClass& cc, Crater& crater, double& r) const {
  const double R = settings_.radius_m;
  const glm::dvec3 q = p_m * cc.inv_cell_per_m + cc.offset;
  const glm::dvec3 floor_q(std::floor(q.x), std::floor(q.y), std::floor(q.z));
  const uvec3 cell(std::uint32_t(std::int64_t(floor_q.x)), std::uint32_t(std::int64_t(floor_q.y)),
                   std::uint32_t(std::int64_t(floor_q.z)));
  const uvec3 h = pcg3d(cell + cc.key);
  // The presence draw uses a second hash; u in [0, 1) from 24 bits each.
  const uvec3 g = pcg3d(h);
  const double to_unit = 1.0 / 16777216.0;
  const glm::dvec3 jitter(double(h.x >> 8) * to_unit, double(h.y >> 8) * to_unit, double(h.z >> 8) * to_unit);
  const glm::dvec3 centre = (floor_q + 0.25 + 0.5 * jitter - cc.offset) * cc.cell_m;
  const double centre_length = glm::length(centre);
  if (!(std::abs(centre_length - R) <= 0.125 * cc.cell_m)) return false;
  const glm::dvec3 centre_direction = centre / centre_length;
  if (double(g.x >> 8) * to_unit >= crater_presence(centre_direction)) return false;
  // Size: D = D_min (1 + u); freshness in [0.35, 1] scales depth and rim
  // (degraded craters are shallower).
  const double u = double(g.y >> 8) * to_unit;
  const double freshness = 0.35 + 0.65 * double(g.z >> 8) * to_unit;
  const double radius_m = 0.5 * cc.min_diameter_m * (1.0 + u);
  // Distance from p (on the datum sphere) to the vertical through c, scaled:
  // (|p - c|^2 - (|c| - R)^2) = (|c| / R) |p - c'|^2.
  const glm::dvec3 d = p_m - centre;
  const double height_offset = centre_length - R;
  const double r2 = std::max(0.0, glm::dot(d, d) - height_offset * height_offset) / (radius_m * radius_m);
  if (r2 >= kEjectaReach * kEjectaReach) return false;
  r = std::sqrt(r2);
  const double depth_m =
      std::min(cc.simple_depth_m * power_shape(u, 0.90, cc.simple_depth_shape),
               cc.complex_depth_m * power_shape(u, 0.49, cc.complex_depth_shape));
  crater.centre = centre_direction;
  crater.radius_m = radius_m;
  crater.depth_m = freshness * depth_m;
  crater.rim_height_m = freshness * std::min(cc.rim_m * power_shape(u, 1.014, cc.rim_shape), depth_m / 3.0);
  return true;
}

bool Relief::crater_at(const glm::dvec3& direction, int size_class, Crater& crater) const {
  if (size_class < 0 || size_class >= int(craters_.size())) return false;
  double r = 0;
  return crater_in_cell(direction * settings_.radius_m, craters_[std::size_t(size_class)], crater, r);
}

double Relief::craters_m(const glm::dvec3& p_m) const {
  double sum = 0;
  for (const CraterClass& cc : craters_) {
    Crater crater;
    double r = 0;
    if (!crater_in_cell(p_m, cc, crater, r)) continue;
    const double floor_fraction = 2.0 * crater.radius_m > kComplexCraterDiameter_m ? kFloorFraction : 0.0;
    sum += crater_profile(r, crater.depth_m, crater.rim_height_m, floor_fraction);
  }
  return sum;
}

double Relief::height_m(const glm::dvec3& direction) const {
  const glm::dvec3 p = direction * settings_.radius_m;
  switch (settings_.style) {
    case ReliefStyle::flat:
      return 0.0;
    case ReliefStyle::earth: {
      // With a data coast, the continent coordinate is the distance to the
      // coast (with its wiggle) over kCoastProfile_m: the shelf, the slope
      // and the rise of the land follow the real coastline.
      const bool data_coast = bool(settings_.coast_distance_m);
      const double coast_m = data_coast ? settings_.coast_distance_m(direction) + sum_octaves(coast_wiggle_, p) : 0.0;
      const double t = data_coast ? coast_m / kCoastProfile_m : large_scale_field(p) - threshold_;
      double h = earth_hypsometry(t);
      // Belts: a C2 mask from the belt field, restricted to land and shelves.
      const double belt = fade_mask((sum_octaves(belt_, p) - 0.1) / 0.3) * fade_mask((t + 0.05) / 0.1);
      if (belt > 0.0) {
        double ridges = 0;
        for (const Octave& o : ridges_) {
          const double r = noise_ridge(octave_noise(p, o));
          ridges += o.amplitude_m * r * r;
        }
        h += belt * ridges;
      }
      h += sum_octaves(detail_, p);
      // The data decide which side of the coast a point is on: no hill of
      // the detail noise rises out of the sea, no hollow of the land sinks
      // below it.
      if (data_coast) h = coast_m >= 0.0 ? std::max(h, kCoastLand_m) : std::min(h, -kCoastLand_m);
      return h;
    }
    case ReliefStyle::mars: {
      const double highland = fade_mask((dichotomy_coordinate(direction, p) - kDichotomyEdge) / kDichotomyWidth);
      const double h = kLowlands_m + kDichotomyStep_m * highland;
      return h + (0.25 + 0.75 * highland) * sum_octaves(detail_, p) + craters_m(p) + canyon_m(direction, p);
    }
    case ReliefStyle::venus: {
      const double t = large_scale_field(p) - threshold_;
      double h = 3500.0 * fade_mask(t / 0.08);
      const double mask = fade_mask(t / 0.1);
      if (mask > 0.0) {
        double ridges = 0;
        for (const Octave& o : ridges_) {
          const double r = noise_ridge(octave_noise(p, o));
          ridges += o.amplitude_m * r * r;
        }
        h += mask * ridges;
      }
      return h + sum_octaves(detail_, p) + craters_m(p);
    }
    case ReliefStyle::titan: {
      double h = sum_octaves(detail_, p);
      const double z = direction.z;
      const double band = fade_mask((0.3 - z * z) / 0.1);
      if (band > 0.0) {
        // Dune lattice: 10 times longer east-west than north-south.
        const glm::dvec3 stretched(p.x * 0.1, p.y * 0.1, p.z);
        for (const Octave& o : dunes_) h += band * o.amplitude_m * noise_ridge(octave_noise(stretched, o));
      }
      return h;
    }
  }
  return 0.0;
}

// Colours: linear RGB. Mars and Titan take their presets' ground_albedo
// spectra (data/planets/mars.json, titan.json) read at the dominant
// wavelengths of the sRGB primaries (611, 549, 464 nm): Mars 0.246, 0.169,
// 0.101; Titan 0.107, 0.086, 0.062. Venus: the preset's grey 0.1 (basaltic
// plains). Earth: sea floor sediment, vegetation, desert, rock, snow.
glm::vec3 Relief::albedo(const glm::dvec3& direction) const {
  const glm::dvec3 p = direction * settings_.radius_m;
  const double h = height_m(direction);
  // A slow variation (+-20 %) so that the ground is not uniform.
  Octave variation;
  variation.inv_wavelength_per_m = 1.0 / 300e3;
  variation.key = layer_key(settings_.seed, 10, 0);
  const double n = octave_noise(p, variation);
  const double vary = 1.0 + 0.2 * n;
  glm::dvec3 a(0.1);
  switch (settings_.style) {
    case ReliefStyle::flat:
      a = glm::dvec3(0.1);
      break;
    case ReliefStyle::earth: {
      if (h < sea_level_m_) {
        a = glm::dvec3(0.10, 0.09, 0.07) * vary;
        break;
      }
      const double dry = fade_mask((n + 0.2) / 0.4);
      const glm::dvec3 vegetation(0.045, 0.07, 0.03), desert(0.36, 0.28, 0.18), rock(0.16, 0.14, 0.12),
          snow(0.75, 0.76, 0.80);
      a = vegetation + (desert - vegetation) * dry;
      a += (rock - a) * fade_mask((h - 2500.0) / 1500.0);
      a += (snow - a) * fade_mask((h - 4500.0) / 800.0);
      break;
    }
    case ReliefStyle::mars: {
      // The northern plains are darker than the southern highlands.
      const double highland = fade_mask((glm::dot(dichotomy_axis_, direction) - kDichotomyEdge) / kDichotomyWidth);
      a = glm::dvec3(0.246, 0.169, 0.101) * (0.8 + 0.2 * highland) * vary;
      break;
    }
    case ReliefStyle::venus:
      a = glm::dvec3(0.1) * vary;
      break;
    case ReliefStyle::titan: {
      // The dune fields are dark (Lorenz et al. 2006).
      const double band = fade_mask((0.3 - direction.z * direction.z) / 0.1);
      a = glm::dvec3(0.107, 0.086, 0.062) * (1.0 - 0.3 * band) * vary;
      break;
    }
  }
  return glm::vec3(glm::clamp(a, 0.0, 1.0));
}

// The continent field's value below which `fraction_below` of the sphere's
// area lies: sampled on a 6 x 48 x 48 cube grid, each sample weighted by its
// solid angle du dv / (1 + u^2 + v^2)^(3/2) (gnomonic cube).
void Relief::calibrate_threshold(double fraction_below) {
  const int n = 48;
  std::vector<std::pair<double, double>> samples;
  samples.reserve(std::size_t(6 * n * n));
  double total = 0;
  for (int face = 0; face < 6; ++face) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double u = (2.0 * (i + 0.5) / n) - 1.0, v = (2.0 * (j + 0.5) / n) - 1.0;
        const double s = 1.0 + u * u + v * v;
        const double weight = 1.0 / (s * std::sqrt(s));
        glm::dvec3 d;
        const double sign = face < 3 ? 1.0 : -1.0;
        switch (face % 3) {
          case 0: d = glm::dvec3(sign, u, v); break;
          case 1: d = glm::dvec3(v, sign, u); break;
          default: d = glm::dvec3(u, v, sign); break;
        }
        d /= std::sqrt(s);
        samples.emplace_back(large_scale_field(d * settings_.radius_m), weight);
        total += weight;
      }
    }
  }
  std::sort(samples.begin(), samples.end());
  double cumulative = 0;
  threshold_ = samples.back().first;
  for (const auto& [value, weight] : samples) {
    cumulative += weight;
    if (cumulative >= fraction_below * total) {
      threshold_ = value;
      break;
    }
  }
}

void Relief::add_octave_bounds(const std::vector<Octave>& octaves) {
  for (const Octave& o : octaves) {
    TermBound b;
    b.low_m = -kNoiseBound * o.amplitude_m;
    b.high_m = kNoiseBound * o.amplitude_m;
    b.slope = o.amplitude_m * kNoiseSlope * o.inv_wavelength_per_m;
    b.curvature_per_m = o.amplitude_m * kNoiseCurvature * o.inv_wavelength_per_m * o.inv_wavelength_per_m;
    terms_.push_back(b);
  }
}

void Relief::finish_bounds() {
  const double R = settings_.radius_m;
  terms_.clear();
  // Slope and curvature of the large-scale field (a sum of octaves).
  const double field_slope = kNoiseSlope * octave_sum(large_scale_, 1);
  const double field_curvature = kNoiseCurvature * octave_sum(large_scale_, 2);
  // A mask S((f - a) / w) of a field with bounds (L, K): slope L s'/w,
  // curvature K s'/w + L^2 |s''| / w^2 (chain rule).
  auto mask_slope = [](double width, double l) { return kFadeSlope / width * l; };
  auto mask_curvature = [](double width, double l, double k) {
    return kFadeSlope / width * k + kFadeCurvature / (width * width) * l * l;
  };
  // Ridged octaves under a mask of slope Lm: |m a r| <= a, slope a (Lm + 4 kNoiseSlope / lambda).
  auto add_ridges = [&](const std::vector<Octave>& octaves, double mask_l, double ridge_slope) {
    for (const Octave& o : octaves) {
      TermBound b;
      b.low_m = 0;
      b.high_m = o.amplitude_m;
      b.slope = o.amplitude_m * (mask_l + ridge_slope * kNoiseSlope * o.inv_wavelength_per_m);
      b.curvature_per_m = -1;
      terms_.push_back(b);
    }
  };
  switch (settings_.style) {
    case ReliefStyle::flat:
      terms_.push_back(TermBound{0, 0, 0, 0});
      break;
    case ReliefStyle::earth: {
      // G(c): range [abyss, abyss + sum of steps]; slope sum |h| s'/w L_c;
      // curvature sum |h| (s''/w^2 L_c^2 + s'/w K_c).
      TermBound g;
      g.curvature_per_m = 0;
      g.low_m = kEarthAbyss_m;
      g.high_m = kEarthAbyss_m;
      for (const Step& s : kEarthSteps) {
        g.high_m += s.height_m;
        g.slope += s.height_m * mask_slope(s.width, field_slope);
        g.curvature_per_m += s.height_m * mask_curvature(s.width, field_slope, field_curvature);
      }
      terms_.push_back(g);
      // Belt mask = S1(b) S2(t): slope <= L_S1 + L_S2 (both in [0, 1]).
      const double belt_slope = kNoiseSlope * octave_sum(belt_, 1);
      const double mask_l = mask_slope(0.3, belt_slope) + mask_slope(0.1, field_slope);
      add_ridges(ridges_, mask_l, kRidgeSlope);
      add_octave_bounds(detail_);
      break;
    }
    case ReliefStyle::mars: {
      // Dichotomy: s = axis . x / R + wobble: slope 1/R + L_w, curvature K_w
      // (the linear part has none); highland mask m = S((s - e) / w).
      const double s_slope = 1.0 / R + field_slope;
      const double m_slope = mask_slope(kDichotomyWidth, s_slope);
      const double m_curvature = mask_curvature(kDichotomyWidth, s_slope, field_curvature);
      terms_.push_back(TermBound{kLowlands_m, kLowlands_m + kDichotomyStep_m, kDichotomyStep_m * m_slope,
                                 kDichotomyStep_m * m_curvature});
      // The canyon: range [-D, 0]; slope from its two masks, D s' (1/wall
      // (1 + dW/ds) + 2/taper), dW/ds = W0 wobble n' / lambda_w; kinked (the
      // distance |x| at the great circle, where the floor mask is flat,
      // and the mask of the ends where they meet).
      {
        const double dw = kCanyonHalfWidth_m * kCanyonWobble * kNoiseSlope / kCanyonWobbleWavelength_m;
        terms_.push_back(TermBound{-kCanyonDepth_m, 0.0,
                                   kCanyonDepth_m * kFadeSlope * ((1.0 + dw) / kCanyonWall_m + 2.0 / kCanyonTaper_m),
                                   -1.0});
      }
      // Detail under the factor f = 0.25 + 0.75 m (|f| <= 1): product rule,
      // (f n)' <= 0.75 Lm + n', (f n)'' <= 0.75 Km + 2 (0.75 Lm) n' + n''.
      for (const Octave& o : detail_) {
        const double a = o.amplitude_m, k = o.inv_wavelength_per_m;
        terms_.push_back(TermBound{-a, a, a * (0.75 * m_slope + kNoiseSlope * k),
                                   a * (0.75 * m_curvature + 1.5 * m_slope * kNoiseSlope * k + kNoiseCurvature * k * k)});
      }
      break;
    }
    case ReliefStyle::venus: {
      const double step_slope = mask_slope(0.08, field_slope);
      terms_.push_back(TermBound{0.0, 3500.0, 3500.0 * step_slope,
                                 3500.0 * mask_curvature(0.08, field_slope, field_curvature)});
      add_ridges(ridges_, mask_slope(0.1, field_slope), kRidgeSlope);
      add_octave_bounds(detail_);
      break;
    }
    case ReliefStyle::titan: {
      add_octave_bounds(detail_);
      // Band mask of z^2 = (x_z / R)^2: slope 2/R, so the mask's slope is
      // s'/0.1 * 2/R; dunes: a ridge (Lipschitz 2 in n) of noise whose lattice
      // has its finest spacing lambda (the stretched axes are 10x coarser).
      add_ridges(dunes_, mask_slope(0.1, 2.0 / R), 2.0);
      break;
    }
  }
  // Crater classes: one crater at most per point and class; values in
  // [-d_max, h_r max] at D = 2 D_min (u -> 1; depth and rim grow with D);
  // slope: the profile's slope in r, max(2 (d + h_r) / (1 - f), 3 h_r / (7/8)),
  // times |grad r| <= sqrt(|c| / R) / radius <= sqrt(1 + S/(8R)) / (D_min / 2).
  for (const CraterClass& cc : craters_) {
    const double depth = std::min(cc.simple_depth_m * kTwoPow090, cc.complex_depth_m * kTwoPow049);
    const double rim = std::min(cc.rim_m * kTwoPow1014, depth / 3.0);
    const double floor_fraction = 2.0 * cc.min_diameter_m > kComplexCraterDiameter_m ? kFloorFraction : 0.0;
    const double profile_slope = std::max(2.0 * (depth + rim) / (1.0 - floor_fraction), 3.0 * rim / 0.875);
    const double r_slope = std::sqrt(1.0 + cc.cell_m / (8.0 * R)) / (0.5 * cc.min_diameter_m);
    terms_.push_back(TermBound{-depth, rim, profile_slope * r_slope, -1});
  }
  min_height_m_ = 0;
  max_height_m_ = 0;
  for (const TermBound& b : terms_) {
    min_height_m_ += b.low_m;
    max_height_m_ += b.high_m;
  }
  if (settings_.style != ReliefStyle::earth) sea_level_m_ = min_height_m_ - 1.0;
  if (settings_.sea_level_m) {
    if (!std::isfinite(*settings_.sea_level_m)) throw Error("relief: the sea level must be a finite height");
    sea_level_m_ = *settings_.sea_level_m;
  }
}

double Relief::error_below_spacing_m(double spacing_m) const {
  if (!(spacing_m >= 0)) throw Error("relief: the mesh spacing must be a non-negative number of metres");
  const double R = settings_.radius_m;
  double error = 0;
  for (const TermBound& b : terms_) {
    double e = b.high_m - b.low_m;
    e = std::min(e, b.slope * spacing_m / std::sqrt(2.0));
    if (b.curvature_per_m >= 0)
      e = std::min(e, (b.curvature_per_m + 4.0 * b.slope / R) * spacing_m * spacing_m / 4.0);
    error += e;
  }
  return error;
}

}  // namespace atmos::planet
