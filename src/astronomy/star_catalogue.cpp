#include "atmos/star_catalogue.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <limits>
#include <sstream>

#include "astronomy/angles.hpp"
#include "atmos/atmosphere.hpp"
#include "atmos/colour.hpp"
#include "physics/checks.hpp"

namespace atmos {

namespace {

using astronomy::kArcsecond;
using astronomy::kDegree;
using astronomy::wrap_360;

// The V band's effective wavelength and zero point (Bessell, Castelli & Plez
// 1998, Table A2: f_λ = 363.1e-11 erg cm⁻² s⁻¹ Å⁻¹ = 3.631e-11 W m⁻² nm⁻¹
// for V = 0).
constexpr double kVEffectiveWavelengthNm = 545.0;
constexpr double kVZeroPointWM2Nm = 3.631e-11;

// Planck's law, up to a constant factor: the spectral shape of a blackbody.
double planck_shape(double wavelength_nm, double temperature_k) {
  constexpr double h = 6.62607015e-34, c = 299792458.0, k = 1.380649e-23;
  const double l = wavelength_nm * 1e-9;
  return 1.0 / (std::pow(l, 5) * std::expm1(h * c / (l * k * temperature_k)));
}

// The stars of a text catalogue: parse_line(line, where) for each line of
// `in` that is neither blank nor a comment ('#' first), where `where` is
// "origin:line: " for error messages; an error if no line gave a star.
template <typename ParseLine>
std::vector<CatalogueStar> parse_catalogue_lines(std::istream& in, const std::string& origin, ParseLine parse_line) {
  std::vector<CatalogueStar> stars;
  std::string line;
  int number_of_line = 0;
  while (std::getline(in, line)) {
    ++number_of_line;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    stars.push_back(parse_line(line, origin + ":" + std::to_string(number_of_line) + ": "));
  }
  if (stars.empty()) throw Error(origin + ": no stars in the catalogue");
  return stars;
}

// The catalogue at `path`; `package` names the Debian package that installs it.
std::vector<CatalogueStar> load_catalogue(const std::string& path, const char* package,
                                          std::vector<CatalogueStar> (*parse)(std::istream&, const std::string&)) {
  std::ifstream in(path);
  if (!in) throw Error("cannot read the star catalogue " + path + " (Debian's " + package + " installs it there)");
  return parse(in, path);
}

}  // namespace

std::vector<CatalogueStar> parse_bright_star_catalogue(std::istream& in, const std::string& origin) {
  return parse_catalogue_lines(in, origin, [](const std::string& line, const std::string& where) {
    std::istringstream fields(line);
    double dec = 0.0, ra_hours = 0.0, v = 0.0;
    if (!(fields >> dec >> ra_hours >> v))
      throw Error(where + "expected the declination (deg), right ascension (h) and V magnitude");
    if (!std::isfinite(dec) || dec < -90.0 || dec > 90.0)
      throw Error(where + "declination " + number_text(dec) + " is outside [-90, 90] degrees");
    if (!std::isfinite(ra_hours) || ra_hours < 0.0 || ra_hours >= 24.0)
      throw Error(where + "right ascension " + number_text(ra_hours) + " is outside [0, 24) hours");
    if (!std::isfinite(v) || v < -2.0 || v > 16.0)
      throw Error(where + "V magnitude " + number_text(v) + " is outside [-2, 16]");
    CatalogueStar s;
    s.declination_deg = dec;
    s.right_ascension_deg = ra_hours * 15.0;
    s.v_magnitude = v;
    s.b_minus_v = std::numeric_limits<double>::quiet_NaN();
    // The quoted name and the Bright Star number after it, if present.
    const size_t open = line.find('"');
    if (open != std::string::npos) {
      const size_t close = line.find('"', open + 1);
      if (close == std::string::npos) throw Error(where + "unterminated star name");
      s.name = line.substr(open + 1, close - open - 1);
      std::istringstream rest(line.substr(close + 1));
      int hr = 0;
      if (rest >> hr) s.bright_star_number = hr;
    }
    return s;
  });
}

std::vector<CatalogueStar> load_bright_star_catalogue(const std::string& path) {
  return load_catalogue(path, "xplanet package (the Yale Bright Star Catalogue)", parse_bright_star_catalogue);
}

namespace {

// The number in columns [first, first + count) of `line` (1-based), or NaN
// if there is none.
double column_number(const std::string& line, size_t first, size_t count) {
  if (line.size() < first - 1 + count) return std::numeric_limits<double>::quiet_NaN();
  const std::string text = line.substr(first - 1, count);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || text.find_first_not_of(' ', size_t(end - text.c_str())) != std::string::npos)
    return std::numeric_limits<double>::quiet_NaN();
  return v;
}

// The unit vector of a right ascension and declination, degrees.
glm::dvec3 unit_vector(double ra_deg, double dec_deg) {
  const double a = ra_deg * kDegree, d = dec_deg * kDegree;
  return {std::cos(d) * std::cos(a), std::cos(d) * std::sin(a), std::sin(d)};
}

}  // namespace

std::vector<CatalogueStar> parse_kstars_catalogue(std::istream& in, const std::string& origin) {
  return parse_catalogue_lines(in, origin, [](const std::string& line, const std::string& where) {
    if (line.size() < 56) throw Error(where + "expected at least 56 columns (RA, Dec, motions, parallax, V, B-V)");
    // RA hhmmss.ss, Dec ±ddmmss.s: sexagesimal digits in fixed columns.
    // Seconds of 60 (the file rounds 59.995 up without carrying) are
    // taken as they are.
    const double ra_h = column_number(line, 1, 2), ra_m = column_number(line, 3, 2), ra_s = column_number(line, 5, 5);
    const double dec_d = column_number(line, 12, 2), dec_m = column_number(line, 14, 2),
                 dec_s = column_number(line, 16, 4);
    const char sign = line[10];
    if (!(ra_h >= 0.0 && ra_h < 24.0 && ra_m >= 0.0 && ra_m < 60.0 && ra_s >= 0.0 && ra_s <= 60.0))
      throw Error(where + "right ascension \"" + line.substr(0, 9) + "\" is not hhmmss.ss in [0, 24) hours");
    if (!(sign == '+' || sign == '-') || !(dec_d >= 0.0 && dec_d <= 90.0 && dec_m >= 0.0 && dec_m < 60.0 &&
                                           dec_s >= 0.0 && dec_s <= 60.0))
      throw Error(where + "declination \"" + line.substr(10, 9) + "\" is not ±ddmmss.s");
    const double dec = (sign == '-' ? -1.0 : 1.0) * (dec_d + dec_m / 60.0 + dec_s / 3600.0);
    if (dec < -90.0 || dec > 90.0)
      throw Error(where + "declination " + number_text(dec) + " is outside [-90, 90] degrees");
    const double v = column_number(line, 46, 6), bv = column_number(line, 52, 5);
    if (!std::isfinite(v) || v < -2.0 || v > 16.0)
      throw Error(where + "V magnitude \"" + line.substr(45, 6) + "\" is not a number in [-2, 16]");
    if (!std::isfinite(bv) || bv < -1.0 || bv > 6.0)
      throw Error(where + "B-V \"" + line.substr(51, 5) + "\" is not a number in [-1, 6]");
    CatalogueStar s;
    s.right_ascension_deg = 15.0 * (ra_h + ra_m / 60.0 + ra_s / 3600.0);
    s.declination_deg = dec;
    s.v_magnitude = v;
    s.b_minus_v = bv;
    const size_t comma = line.find(',', 56);
    if (comma != std::string::npos) s.name = line.substr(comma + 1);
    return s;
  });
}

std::vector<CatalogueStar> load_kstars_catalogue(const std::string& path) {
  return load_catalogue(path, "kstars-data package (KStars' catalogue)", parse_kstars_catalogue);
}

std::size_t colour_from_catalogue(std::vector<CatalogueStar>& stars, const std::vector<CatalogueStar>& coloured,
                                  double max_separation_deg, double max_magnitude_difference) {
  if (!(std::isfinite(max_separation_deg) && max_separation_deg > 0.0 && max_separation_deg < 90.0) ||
      !(std::isfinite(max_magnitude_difference) && max_magnitude_difference > 0.0))
    throw Error("colour_from_catalogue: the separation must be in (0, 90) degrees and the magnitude difference > 0");
  // The coloured stars in bands of declination as wide as the separation:
  // a star's match lies in its own band or a neighbour.
  const double band_width = max_separation_deg;
  const int bands = int(std::ceil(180.0 / band_width)) + 1;
  auto band_of = [&](double dec) { return std::clamp(int((dec + 90.0) / band_width), 0, bands - 1); };
  std::vector<std::vector<size_t>> band(static_cast<size_t>(bands));
  for (size_t i = 0; i < coloured.size(); ++i)
    if (std::isfinite(coloured[i].b_minus_v)) band[size_t(band_of(coloured[i].declination_deg))].push_back(i);
  const double cos_max = std::cos(max_separation_deg * kDegree);
  size_t matched = 0;
  for (CatalogueStar& s : stars) {
    if (std::isfinite(s.b_minus_v)) continue;
    const glm::dvec3 u = unit_vector(s.right_ascension_deg, s.declination_deg);
    const int b = band_of(s.declination_deg);
    double best = cos_max;
    const CatalogueStar* match = nullptr;
    for (int k = std::max(b - 1, 0); k <= std::min(b + 1, bands - 1); ++k) {
      for (size_t i : band[size_t(k)]) {
        const CatalogueStar& c = coloured[i];
        if (std::abs(c.v_magnitude - s.v_magnitude) > max_magnitude_difference) continue;
        const double cosine = glm::dot(u, unit_vector(c.right_ascension_deg, c.declination_deg));
        if (cosine >= best) {
          best = cosine;
          match = &c;
        }
      }
    }
    if (match != nullptr) {
      s.b_minus_v = match->b_minus_v;
      ++matched;
    }
  }
  return matched;
}

EquatorialPosition precess_from_j2000(const EquatorialPosition& p, double jd_tt) {
  // Meeus 1998 eqs. 21.2-21.4 (IAU 1976 precession, Lieske et al. 1977) from
  // J2000, t in Julian centuries of TT: ζ, z and θ in arcseconds.
  const double t = (jd_tt - 2451545.0) / 36525.0;
  const double zeta = (2306.2181 * t + 0.30188 * t * t + 0.017998 * t * t * t) * kArcsecond * kDegree;
  const double z = (2306.2181 * t + 1.09468 * t * t + 0.018203 * t * t * t) * kArcsecond * kDegree;
  const double theta = (2004.3109 * t - 0.42665 * t * t - 0.041833 * t * t * t) * kArcsecond * kDegree;
  const double a0 = p.right_ascension_deg * kDegree, d0 = p.declination_deg * kDegree;
  const double a = std::cos(d0) * std::sin(a0 + zeta);
  const double b = std::cos(theta) * std::cos(d0) * std::cos(a0 + zeta) - std::sin(theta) * std::sin(d0);
  const double c = std::sin(theta) * std::cos(d0) * std::cos(a0 + zeta) + std::cos(theta) * std::sin(d0);
  EquatorialPosition q;
  q.right_ascension_deg = wrap_360((std::atan2(a, b) + z) / kDegree);
  // asin loses precision near the poles; the hypotenuse of A and B does not.
  q.declination_deg = std::atan2(c, std::hypot(a, b)) / kDegree;
  q.distance_m = p.distance_m;
  return q;
}

EquatorialPosition apparent_place(const EquatorialPosition& j2000, double jd_tt) {
  EquatorialPosition p = precess_from_j2000(j2000, jd_tt);
  const double cos_dec = std::cos(p.declination_deg * kDegree);
  // At the celestial poles right ascension is undefined: the corrections in
  // it are dropped there (they move the star by less than 1e-7″).
  if (cos_dec < 1e-12) return p;
  const Nutation n = nutation(jd_tt);
  const double eps = (mean_obliquity_deg(jd_tt) + n.obliquity_deg) * kDegree;
  const double alpha = p.right_ascension_deg * kDegree, delta = p.declination_deg * kDegree;
  const double tan_dec = std::tan(delta);
  // Nutation (Meeus 1998 eq. 23.1).
  const double d_alpha_1 = (std::cos(eps) + std::sin(eps) * std::sin(alpha) * tan_dec) * n.longitude_deg -
                           std::cos(alpha) * tan_dec * n.obliquity_deg;
  const double d_delta_1 = std::sin(eps) * std::cos(alpha) * n.longitude_deg + std::sin(alpha) * n.obliquity_deg;
  // Annual aberration (Meeus 1998 eq. 23.2, the terms in κ = 20.49552″; the
  // terms in the eccentricity, under 0.35″, are left out).
  const double kappa = 20.49552 * kArcsecond;
  const double sun = sun_true_longitude_deg(jd_tt) * kDegree;
  const double d_alpha_2 =
      -kappa * (std::cos(alpha) * std::cos(sun) * std::cos(eps) + std::sin(alpha) * std::sin(sun)) / cos_dec;
  const double d_delta_2 =
      -kappa * (std::cos(sun) * std::cos(eps) * (std::tan(eps) * cos_dec - std::sin(alpha) * std::sin(delta)) +
                std::cos(alpha) * std::sin(delta) * std::sin(sun));
  p.right_ascension_deg = wrap_360(p.right_ascension_deg + d_alpha_1 + d_alpha_2);
  p.declination_deg += d_delta_1 + d_delta_2;
  return p;
}

double temperature_from_b_minus_v(double bv) {
  if (!std::isfinite(bv) || bv < -0.4 || bv > 2.0)
    throw Error("B-V colour index must be in [-0.4, 2.0] magnitudes, got " + number_text(bv));
  return 4600.0 * (1.0 / (0.92 * bv + 1.7) + 1.0 / (0.92 * bv + 0.62));
}

double v_band_spectral_irradiance(double v_magnitude) {
  if (!std::isfinite(v_magnitude)) throw Error("a star's V magnitude must be finite");
  return kVZeroPointWM2Nm * std::pow(10.0, -0.4 * v_magnitude);
}

glm::dvec3 star_srgb_irradiance(double v_magnitude, double b_minus_v) {
  const double temperature = temperature_from_b_minus_v(b_minus_v);
  const double scale = v_band_spectral_irradiance(v_magnitude) / planck_shape(kVEffectiveWavelengthNm, temperature);
  // CIE 1931 XYZ by the 1 nm rectangle rule over 360-830 nm (the matching
  // functions' table step), Y in lux.
  glm::dvec3 xyz(0.0);
  for (double l = 360.0; l <= 830.0; l += 1.0)
    xyz += cie_1931_color_matching(l) * (scale * planck_shape(l, temperature));
  xyz *= kMaxLuminousEfficacy;
  // XYZ to linear sRGB: the inverse of srgb_to_xyz's matrix.
  const glm::dmat3 to_xyz(srgb_to_xyz({1, 0, 0}), srgb_to_xyz({0, 1, 0}), srgb_to_xyz({0, 0, 1}));
  return glm::inverse(to_xyz) * xyz;
}

std::vector<SkyStar> stars_in_sky(const std::vector<CatalogueStar>& catalogue, const Instant& instant,
                                  const Observer& observer) {
  validate(observer);
  const double sidereal = greenwich_apparent_sidereal_time_deg(instant);
  const LocalFrame frame = local_frame(observer);
  std::vector<SkyStar> out;
  out.reserve(catalogue.size());
  for (const CatalogueStar& c : catalogue) {
    EquatorialPosition j2000;
    j2000.right_ascension_deg = c.right_ascension_deg;
    j2000.declination_deg = c.declination_deg;
    SkyStar s;
    s.direction = earth_fixed_from_equatorial(apparent_place(j2000, instant.jd_tt), sidereal);
    const HorizontalPosition h = horizontal(s.direction, frame);
    s.azimuth_deg = h.azimuth_deg;
    s.elevation_deg = h.elevation_deg;
    s.v_magnitude = c.v_magnitude;
    s.colour_from_catalogue = std::isfinite(c.b_minus_v);
    const double b_minus_v = s.colour_from_catalogue ? std::clamp(c.b_minus_v, -0.4, 2.0) : kSolarBMinusV;
    s.srgb_irradiance = star_srgb_irradiance(c.v_magnitude, b_minus_v);
    s.v_band_irradiance = v_band_spectral_irradiance(c.v_magnitude);
    s.temperature_k = temperature_from_b_minus_v(b_minus_v);
    s.bright_star_number = c.bright_star_number;
    out.push_back(s);
  }
  return out;
}

}  // namespace atmos
