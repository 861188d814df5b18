// atmos — the stars of a real catalogue in the sky of a date and place.
//
// The Yale Bright Star Catalogue (5th revised edition, Hoffleit & Warren
// 1991: 9110 stars, to V ≈ 6.5) as Debian's `xplanet` package ships it
// (/usr/share/xplanet/stars/BSC): one star a line,
//   Dec RA Mag "Name" BSN HD SAO
// with the J2000 declination in degrees, the J2000 right ascension in hours
// (both to 4 decimals: 0.36″ in declination, 5.4″ cos δ in right
// ascension), the V magnitude, a quoted name, and the Bright Star, Henry
// Draper and SAO numbers; "#" starts a comment. That file has no colour
// index and no proper motions: a star read from it has no B−V (the same
// star in KStars' Hipparcos catalogue gives it one: colour_from_catalogue),
// and its place is that of J2000 (the largest proper motion among its stars,
// Groombridge 1830's 7″ a year, moves it by 3′ in a quarter century; the
// bright stars' are mostly under 0.5″ a year).
//
// Placing a star: its J2000 place is precessed to the date (IAU 1976,
// Meeus 1998 eqs. 21.2-21.4), corrected for nutation and the annual
// aberration (Meeus 1998 eqs. 23.1 and 23.2, without the 0.3″ terms in the
// eccentricity), and turned into the Earth-fixed frame by the apparent
// sidereal time (atmos/ephemeris.hpp); elevations are geometric.
//
// Brightness and colour: a star of magnitude V gives the spectral irradiance
// 3.631e-11 × 10^(−0.4 V) W m⁻² nm⁻¹ at the V band's effective wavelength,
// 545 nm (the zero point of Bessell, Castelli & Plez 1998, Table A2); its
// spectrum is taken as a blackbody of the temperature of its B−V
// (Ballesteros 2012, eq. 14), so that its colour follows from the CIE 1931
// matching functions.
#pragma once

#include <glm/vec3.hpp>

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "atmos/ephemeris.hpp"

namespace atmos {

// Where Debian's xplanet package installs the catalogue.
inline constexpr const char* kXplanetBrightStarCatalogue = "/usr/share/xplanet/stars/BSC";

struct CatalogueStar {
  double right_ascension_deg = 0.0;  // J2000, [0, 360)
  double declination_deg = 0.0;      // J2000, [-90, 90]
  double v_magnitude = 0.0;          // Johnson V
  double b_minus_v = 0.0;            // Johnson B−V, magnitudes; NaN where the catalogue gives none (xplanet's)
  int bright_star_number = 0;        // the Yale catalogue's HR number (0 if absent)
  std::string name;                  // as the catalogue spells it, e.g. " 9Alp CMa"
};

// Where Debian's kstars-data package installs KStars' star catalogue, the
// source of the stars' colours.
inline constexpr const char* kKStarsStarCatalogue = "/usr/share/kstars/stars.dat";

// Reads a catalogue in xplanet's layout from `in`; `origin` names it in
// messages. Throws atmos::Error naming the line of the first malformed
// record (a missing or non-finite field, a declination outside [-90, 90], a
// right ascension outside [0, 24) hours, a magnitude outside [-2, 16]) or an
// empty catalogue.
std::vector<CatalogueStar> parse_bright_star_catalogue(std::istream& in, const std::string& origin);

// The same from a file (default: xplanet's); atmos::Error if it cannot be read.
std::vector<CatalogueStar> load_bright_star_catalogue(const std::string& path = kXplanetBrightStarCatalogue);

// Reads KStars' star catalogue (stars.dat of Debian's kstars-data: 125 982
// stars of the Hipparcos and Tycho catalogues, ESA 1997, to V ≈ 9, J2000
// places) from `in`: one star a line in fixed columns, "#" starts a comment,
//   1-9 RA hhmmss.ss, 11-19 Dec ±ddmmss.s, 21-45 proper motions and
//   parallax, 46-51 V, 52-56 B−V, 57- spectral type and names.
// Throws atmos::Error naming the line of the first malformed record (short,
// a field that is not a number, out of range as in
// parse_bright_star_catalogue, or a B−V outside [-1, 6]: Hipparcos' reddest
// reach 5.5) or an empty file. Seconds of 60.00, which the file has where
// it rounded without carrying, are accepted.
std::vector<CatalogueStar> parse_kstars_catalogue(std::istream& in, const std::string& origin);

// The same from a file (default: kstars-data's); atmos::Error if it cannot be read.
std::vector<CatalogueStar> load_kstars_catalogue(const std::string& path = kKStarsStarCatalogue);

// Gives each star of `stars` that has no B−V the B−V of the star of
// `coloured` nearest to it within `max_separation_deg`, if their V differ
// by at most `max_magnitude_difference` (the same star in both
// catalogues); returns how many stars got one. Throws atmos::Error for
// limits that are not finite and positive.
std::size_t colour_from_catalogue(std::vector<CatalogueStar>& stars, const std::vector<CatalogueStar>& coloured,
                                  double max_separation_deg = 1.0 / 60.0, double max_magnitude_difference = 0.5);

// A J2000 mean place precessed to the mean equator and equinox of the date
// jd_tt (Meeus 1998 eqs. 21.2-21.4). Distance is kept.
EquatorialPosition precess_from_j2000(const EquatorialPosition& j2000, double jd_tt);

// The apparent place of date of a J2000 mean place: precession, then
// nutation and annual aberration (Meeus 1998 ch. 23).
EquatorialPosition apparent_place(const EquatorialPosition& j2000, double jd_tt);

// Effective temperature, kelvin, of a star of colour index B−V (Ballesteros
// 2012, eq. 14: T = 4600 K (1 / (0.92 (B−V) + 1.7) + 1 / (0.92 (B−V) + 0.62))).
// Throws atmos::Error for B−V outside [-0.4, 2.0], where the formula was fitted.
double temperature_from_b_minus_v(double b_minus_v);

// The V band's spectral irradiance of a star of magnitude V, W m⁻² nm⁻¹
// (Bessell, Castelli & Plez 1998's zero point, above).
double v_band_spectral_irradiance(double v_magnitude);

// The linear sRGB irradiance of a star (on the illuminance scale: Y is in
// lux) of magnitude V and colour index B−V: a blackbody of
// temperature_from_b_minus_v(B−V) scaled to v_band_spectral_irradiance(V)
// at 545 nm, weighted by the CIE 1931 matching functions over 360-830 nm
// times 683 lm/W and converted to linear sRGB (IEC 61966-2-1). Vega
// (V = 0.03, B−V = 0.00) gives 2.5e-6 lux.
glm::dvec3 star_srgb_irradiance(double v_magnitude, double b_minus_v);

// The B−V the sky gives a star the catalogue has none for: the Sun's
// (0.653, Ramírez et al. 2012), the colour of the procedural star field.
inline constexpr double kSolarBMinusV = 0.653;

// A catalogue star in the sky of a date and place.
struct SkyStar {
  glm::dvec3 direction{0.0, 0.0, 1.0};  // Earth-fixed unit vector towards the star
  double azimuth_deg = 0.0;             // clockwise from north
  double elevation_deg = 0.0;           // geometric (no refraction)
  double v_magnitude = 0.0;
  glm::dvec3 srgb_irradiance{0.0};      // star_srgb_irradiance, linear sRGB, Y in lux
  double v_band_irradiance = 0.0;       // v_band_spectral_irradiance(V), W m⁻² nm⁻¹ at 545 nm
  double temperature_k = 0.0;           // temperature_from_b_minus_v: its blackbody spectrum
  bool colour_from_catalogue = false;   // false: the catalogue had no B−V, kSolarBMinusV was used
  int bright_star_number = 0;
};

// Every star of the catalogue placed at `instant` for `observer`, in the
// catalogue's order (above and below the horizon); a B−V outside the
// temperature fit's [-0.4, 2.0] is coloured as its nearest end.
std::vector<SkyStar> stars_in_sky(const std::vector<CatalogueStar>& catalogue, const Instant& instant,
                                  const Observer& observer);

}  // namespace atmos
