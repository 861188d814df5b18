// atmos — the sky of a date and place: time scales, sidereal time, and the
// Sun's and the Moon's positions seen from a point of the Earth.
//
// Low-precision analytic theories, chosen so that a real eclipse is
// reproduced by date and place (docs/ephemeris.md gives the algorithms,
// their stated accuracy and the errors the tests measure):
//   time       UTC taken as UT1 (|UT1 − UTC| < 0.9 s); TT = UT1 + ΔT with ΔT
//              from Espenak & Meeus 2006's polynomials;
//   rotation   Greenwich mean sidereal time (IAU 1982, Meeus 1998 eq. 12.4)
//              plus the equation of the equinoxes;
//   nutation   the IAU 1980 series, 63 terms (Seidelmann 1982; Meeus 1998
//              ch. 22);
//   Sun        Meeus 1998 ch. 25's "higher accuracy": the Earth's VSOP87D
//              (Bretagnon & Francou 1988) truncated as in Meeus's Appendix
//              III (about 1″), with that nutation and the annual aberration
//              (the geocentric part of Reda & Andreas 2004's SPA);
//   Moon       Meeus 1998 ch. 47: ELP-2000/82 (Chapront-Touzé & Chapront
//              1983) truncated to 60 + 60 periodic terms (10″ in
//              longitude, 4″ in latitude);
//   place      the WGS 84 ellipsoid (NIMA 2000): positions are topocentric,
//              so that the Moon's parallax (up to 1°) is in them.
//
// Frames. "Earth-fixed" is the frame of atmos::Globe and of the CLI's
// planet-centred coordinates: z towards the north pole, x towards latitude 0,
// longitude 0, y towards longitude 90° east (polar motion, under 0.5″, is
// neglected). Azimuths are clockwise from north (east is 90°); elevations
// are geometric, without atmospheric refraction: the renderer traces straight
// rays through the atmosphere, so the geometric direction is the one it needs
// (refraction_deg gives the difference an observer sees).
#pragma once

#include <glm/vec3.hpp>

#include <string>

namespace atmos {

// A date and time of Coordinated Universal Time, proleptic Gregorian calendar.
struct UtcTime {
  int year = 2000;
  int month = 1;        // 1-12
  int day = 1;          // 1-31
  int hour = 12;        // 0-23
  int minute = 0;       // 0-59
  double second = 0.0;  // [0, 60), or [60, 61) for a leap second at 23:59
};

// The years the ephemeris accepts: those of Espenak & Meeus 2006's ΔT
// polynomials used here, and a few centuries around J2000 where the
// truncated theories keep their stated accuracy.
inline constexpr int kEphemerisFirstYear = 1800;
inline constexpr int kEphemerisLastYear = 2199;

// Parses "YYYY-MM-DDTHH:MM:SSZ" (ISO 8601 UTC; the seconds may have a
// decimal fraction, "…:05.25Z"). Throws atmos::Error with one line for a
// malformed text, an impossible date (2023-02-29, month 13, hour 24) or a
// year outside [kEphemerisFirstYear, kEphemerisLastYear].
UtcTime parse_utc_time(const std::string& text);

// Throws atmos::Error as parse_utc_time does for a UtcTime built by hand.
void validate(const UtcTime& time);

// Julian date of the instant, days (Meeus 1998 eq. 7.1, Gregorian calendar),
// on the time scale of `time` (here UTC, taken as UT1).
double julian_date(const UtcTime& time);

// ΔT = TT − UT1, seconds, at a decimal year (year + (month − 0.5) / 12):
// Espenak & Meeus 2006's polynomials for 1800-2150, their parabola
// −20 + 32 u², u = (year − 1820) / 100, after 2150. Throws atmos::Error
// outside [kEphemerisFirstYear, kEphemerisLastYear + 1).
double delta_t_s(double decimal_year);

// An instant on the two time scales the theories need.
struct Instant {
  double jd_ut = 0.0;  // Julian date, UT1 (the Earth's rotation), days
  double jd_tt = 0.0;  // Julian Ephemeris Date, TT (the theories' argument), days
};

// The instant of a UTC time with ΔT from delta_t_s, or with a given ΔT
// (seconds), e.g. one an almanac states.
Instant instant_of(const UtcTime& time);
Instant instant_of(const UtcTime& time, double delta_t_seconds);

// Greenwich mean sidereal time, degrees in [0, 360) (IAU 1982; Meeus 1998
// eq. 12.4): 280.46061837° + 360.98564736629° (JD − 2451545.0)
// + 0.000387933° T² − T³ / 38710000, T in Julian centuries of UT1 from J2000.
double greenwich_mean_sidereal_time_deg(double jd_ut);

// Greenwich apparent sidereal time, degrees in [0, 360): the mean sidereal
// time plus the equation of the equinoxes Δψ cos ε (Meeus 1998 ch. 12).
double greenwich_apparent_sidereal_time_deg(const Instant& instant);

// Nutation in longitude (Δψ) and in obliquity (Δε), degrees.
struct Nutation {
  double longitude_deg = 0.0;
  double obliquity_deg = 0.0;
};
// At a Julian Ephemeris Date: the IAU 1980 series (Meeus 1998 Table 22.A).
Nutation nutation(double jd_tt);

// Mean obliquity of the ecliptic ε0, degrees (IAU 1980; Meeus 1998 eq. 22.2).
double mean_obliquity_deg(double jd_tt);

// A geocentric position on the ecliptic of date.
struct EclipticPosition {
  double longitude_deg = 0.0;  // λ, [0, 360)
  double latitude_deg = 0.0;   // β
  double distance_m = 0.0;     // from the Earth's centre
};

// A geocentric position on the equator of date.
struct EquatorialPosition {
  double right_ascension_deg = 0.0;  // α, [0, 360)
  double declination_deg = 0.0;      // δ
  double distance_m = 0.0;           // from the Earth's centre (0: a direction only)
};

// The Moon's geocentric position referred to the mean equinox of date
// (Meeus 1998 ch. 47: λ, β, Δ as the chapter's example 47.a gives them,
// without nutation).
EclipticPosition moon_mean_ecliptic(double jd_tt);

// The Sun's true geometric longitude ☉, referred to the mean equinox of
// date, degrees in [0, 360) (Meeus 1998 ch. 25, from VSOP87D): the argument
// of the stars' annual aberration.
double sun_true_longitude_deg(double jd_tt);

// The Sun's and the Moon's apparent geocentric positions (true equinox and
// equator of date: with nutation, and for the Sun the annual aberration).
EquatorialPosition sun_apparent_equatorial(double jd_tt);
EquatorialPosition moon_apparent_equatorial(double jd_tt);

// Ecliptic to equatorial coordinates for an obliquity ε (Meeus 1998 eqs.
// 13.3, 13.4).
EquatorialPosition ecliptic_to_equatorial(const EclipticPosition& ecliptic, double obliquity_deg);

// A point of the Earth: geodetic latitude and longitude on the WGS 84
// ellipsoid, height above it.
struct Observer {
  double latitude_deg = 0.0;   // [-90, 90], north positive
  double longitude_deg = 0.0;  // any finite value, east positive
  double height_m = 0.0;       // above the ellipsoid, [-1e4, 1e8]
};

// Throws atmos::Error with one line naming the first bad field.
void validate(const Observer& observer);

// The observer's Earth-fixed position, metres (WGS 84: a = 6 378 137 m,
// f = 1 / 298.257223563).
glm::dvec3 earth_fixed_position(const Observer& observer);

// The local frame of the observer, Earth-fixed unit vectors: east, north and
// up (the ellipsoid's normal, the direction of the geodetic latitude).
struct LocalFrame {
  glm::dvec3 east{1, 0, 0};
  glm::dvec3 north{0, 1, 0};
  glm::dvec3 up{0, 0, 1};
};
LocalFrame local_frame(const Observer& observer);

// The Earth-fixed vector of an equatorial position of date: the equator's
// frame turned by the Greenwich apparent sidereal time about the pole.
// A position of distance 0 gives a unit vector.
glm::dvec3 earth_fixed_from_equatorial(const EquatorialPosition& position, double sidereal_time_deg);

// Azimuth (clockwise from north, [0, 360)) and elevation (geometric,
// [-90, 90]) of a nonzero Earth-fixed direction in the observer's frame.
struct HorizontalPosition {
  double azimuth_deg = 0.0;
  double elevation_deg = 0.0;
};
HorizontalPosition horizontal(const glm::dvec3& direction, const LocalFrame& frame);

// The Sun or the Moon seen from the observer.
struct SkyBody {
  glm::dvec3 topocentric_m{0.0};  // Earth-fixed vector from the observer to the body's centre, metres
  double azimuth_deg = 0.0;       // clockwise from north
  double elevation_deg = 0.0;     // geometric (no refraction)
  double distance_m = 0.0;        // from the observer
  double angular_radius_deg = 0.0;
};

struct SkyOfDate {
  Instant instant;
  double sidereal_time_deg = 0.0;  // Greenwich apparent sidereal time
  SkyBody sun;
  SkyBody moon;
};

// The Sun's radius (IAU 2015 nominal solar radius, Prša et al. 2016) and the
// Moon's (the same 1737.4 km as atmos::kMoonRadiusM), metres.
inline constexpr double kSunRadiusM = 695700e3;
inline constexpr double kMoonMeanRadiusM = 1737.4e3;
// The astronomical unit, metres (IAU 2012 Resolution B2).
inline constexpr double kAstronomicalUnitM = 149597870700.0;

// The Sun and the Moon seen from `observer` at `instant` (topocentric:
// the geocentric positions less the observer's Earth-fixed position).
// Throws atmos::Error for an invalid observer.
SkyOfDate sky_of_date(const Instant& instant, const Observer& observer);
SkyOfDate sky_of_date(const UtcTime& time, const Observer& observer);

// The angle between two nonzero vectors, degrees (atan2 of the cross and
// the dot product: accurate at small angles).
double angular_separation_deg(const glm::dvec3& a, const glm::dvec3& b);

// Atmospheric refraction, degrees, at a geometric elevation (degrees) for
// 1010 hPa and 10 °C: Sæmundsson 1986's formula R = 1.02′ / tan(h + 10.3 /
// (h + 5.11)) (Meeus 1998 eq. 16.4); 0.48° at the horizon, 0.017° at 45°.
// Below −2° (where it is undefined) it returns 0.
double refraction_deg(double geometric_elevation_deg);

}  // namespace atmos
