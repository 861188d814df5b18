// The sky of a date and place (atmos/ephemeris.hpp, atmos/star_catalogue.hpp)
// against published values: Meeus 1998's worked examples, Reda & Andreas
// 2004's solar position example, NASA's eclipse predictions (Espenak), and
// the catalogue's own coordinates turned into the local sky by a separate
// textbook formula. Each test prints its error.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/colour.hpp"
#include "atmos/ephemeris.hpp"
#include "atmos/star_catalogue.hpp"

namespace {

constexpr double kDeg = M_PI / 180.0;

double hms_deg(double h, double m, double s) { return 15.0 * (h + m / 60.0 + s / 3600.0); }
double dms_deg(double d, double m, double s) { return (d < 0 ? -1.0 : 1.0) * (std::abs(d) + m / 60.0 + s / 3600.0); }

// The signed difference a − b of two angles, degrees, in (−180, 180].
double angle_difference(double a, double b) {
  double d = std::fmod(a - b, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d <= -180.0) d += 360.0;
  return d;
}

glm::dvec3 unit_vector(double ra_deg, double dec_deg) {
  return {std::cos(dec_deg * kDeg) * std::cos(ra_deg * kDeg), std::cos(dec_deg * kDeg) * std::sin(ra_deg * kDeg),
          std::sin(dec_deg * kDeg)};
}

// ---------------------------------------------------------------------------
// Time

TEST(Ephemeris, ParsesUtcTimes) {
  const atmos::UtcTime t = atmos::parse_utc_time("2024-04-08T18:42:30Z");
  EXPECT_EQ(t.year, 2024);
  EXPECT_EQ(t.month, 4);
  EXPECT_EQ(t.day, 8);
  EXPECT_EQ(t.hour, 18);
  EXPECT_EQ(t.minute, 42);
  EXPECT_EQ(t.second, 30.0);
  EXPECT_NEAR(atmos::parse_utc_time("2024-04-08T18:42:30.25Z").second, 30.25, 1e-12);
  EXPECT_NO_THROW(atmos::parse_utc_time("2024-02-29T12:00:00Z"));   // a leap year
  EXPECT_NO_THROW(atmos::parse_utc_time("2016-12-31T23:59:60Z"));   // a leap second
  EXPECT_NO_THROW(atmos::parse_utc_time("2000-02-29T00:00:00Z"));   // divisible by 400
}

TEST(Ephemeris, RejectsMalformedAndImpossibleDates) {
  for (const char* text :
       {"", "2024-04-08", "2024-04-08 18:42:30Z", "2024-04-08T18:42:30", "2024-4-08T18:42:30Z",
        "2024-04-08T18:42:30+01:00", "2024-04-08T18:42:30.Z", "2024-04-08T18:42:3xZ", "x024-04-08T18:42:30Z",
        "2024-13-01T00:00:00Z", "2024-00-10T00:00:00Z", "2024-04-31T00:00:00Z", "2023-02-29T00:00:00Z",
        "1900-02-29T00:00:00Z", "2024-04-00T00:00:00Z", "2024-04-08T24:00:00Z", "2024-04-08T12:60:00Z",
        "2024-04-08T12:00:60Z", "1700-01-01T00:00:00Z", "2200-01-01T00:00:00Z"}) {
    try {
      atmos::parse_utc_time(text);
      ADD_FAILURE() << "accepted \"" << text << "\"";
    } catch (const atmos::Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      EXPECT_NE(message.find("date"), std::string::npos) << message;
    }
  }
}

TEST(Ephemeris, JulianDatesOfMeeusChapter7) {
  // Meeus 1998 example 7.a and the table after it.
  EXPECT_NEAR(atmos::julian_date({1957, 10, 4, 19, 26, 24.0}), 2436116.31, 1e-9);
  EXPECT_NEAR(atmos::julian_date({2000, 1, 1, 12, 0, 0.0}), 2451545.0, 1e-9);
  EXPECT_NEAR(atmos::julian_date({1987, 1, 27, 0, 0, 0.0}), 2446822.5, 1e-9);
  EXPECT_NEAR(atmos::julian_date({1988, 6, 19, 12, 0, 0.0}), 2447332.0, 1e-9);
  EXPECT_NEAR(atmos::julian_date({1900, 1, 1, 0, 0, 0.0}), 2415020.5, 1e-9);
}

TEST(Ephemeris, DeltaTPolynomialsJoin) {
  // Espenak & Meeus 2006: 63.86 s at 2000.0; their polynomials meet at the
  // ends of their intervals (within 1 s, the spread of the data they fit).
  EXPECT_NEAR(atmos::delta_t_s(2000.0), 63.86, 1e-9);
  for (double year : {1860.0, 1900.0, 1920.0, 1941.0, 1961.0, 1986.0, 2005.0, 2050.0, 2150.0}) {
    const double before = atmos::delta_t_s(year - 1e-9), after = atmos::delta_t_s(year);
    EXPECT_NEAR(before, after, 1.0) << year;
  }
  // The measured ΔT (IERS) was 33.2 s in mid-1960, 56.9 s in mid-1990 and 69.2 s in 2024.
  EXPECT_NEAR(atmos::delta_t_s(1960.5), 33.2, 1.5);
  EXPECT_NEAR(atmos::delta_t_s(1990.5), 56.9, 1.5);
  EXPECT_NEAR(atmos::delta_t_s(2024.5), 69.2, 5.5);
  EXPECT_THROW(atmos::delta_t_s(1700.0), atmos::Error);
  EXPECT_THROW(atmos::delta_t_s(std::nan("")), atmos::Error);
}

TEST(Ephemeris, SiderealTimeOfMeeusExamples12) {
  // Example 12.a: 1987 April 10, 0h UT: mean 13h10m46.3668s, apparent
  // 13h10m46.1351s.
  const atmos::Instant a = atmos::instant_of({1987, 4, 10, 0, 0, 0.0});
  const double mean_a = atmos::greenwich_mean_sidereal_time_deg(a.jd_ut);
  const double apparent_a = atmos::greenwich_apparent_sidereal_time_deg(a);
  // Example 12.b: 1987 April 10, 19h21m00s UT: mean 8h34m57.0896s.
  const atmos::Instant b = atmos::instant_of({1987, 4, 10, 19, 21, 0.0});
  const double mean_b = atmos::greenwich_mean_sidereal_time_deg(b.jd_ut);
  const double s = 1.0 / 240.0;  // one second of time, degrees
  std::printf("sidereal time errors: 12.a mean %.4f s, apparent %.4f s; 12.b mean %.4f s\n",
              angle_difference(mean_a, hms_deg(13, 10, 46.3668)) / s,
              angle_difference(apparent_a, hms_deg(13, 10, 46.1351)) / s,
              angle_difference(mean_b, hms_deg(8, 34, 57.0896)) / s);
  EXPECT_NEAR(angle_difference(mean_a, hms_deg(13, 10, 46.3668)), 0.0, 0.0005 * s);
  EXPECT_NEAR(angle_difference(mean_b, hms_deg(8, 34, 57.0896)), 0.0, 0.0005 * s);
  // The four-term nutation is good to 0.5″ in Δψ: 0.03 s in the equation of the equinoxes.
  EXPECT_NEAR(angle_difference(apparent_a, hms_deg(13, 10, 46.1351)), 0.0, 0.04 * s);
}

// ---------------------------------------------------------------------------
// The Sun

TEST(Ephemeris, SunOfMeeusExample25) {
  // 1992 October 13.0 TD. Meeus 1998 example 25.b (VSOP87, the full theory):
  // apparent α = 13h13m30.749s, δ = −7°47′01.74″ (example 25.a's low-accuracy
  // result, 13h13m31.4s and −7°47′06″, is what this theory aims at), and
  // R = 0.99760775 au.
  const atmos::EquatorialPosition p = atmos::sun_apparent_equatorial(2448908.5);
  const double expected_ra = hms_deg(13, 13, 30.749), expected_dec = dms_deg(-7, 47, 1.74);
  const double error = atmos::angular_separation_deg(unit_vector(p.right_ascension_deg, p.declination_deg),
                                                     unit_vector(expected_ra, expected_dec));
  std::printf("Sun, Meeus 25.b: error %.5f deg (%.1f arcsec); vs 25.a's low-accuracy result %.5f deg\n", error,
              error * 3600.0,
              atmos::angular_separation_deg(unit_vector(p.right_ascension_deg, p.declination_deg),
                                            unit_vector(hms_deg(13, 13, 31.4), dms_deg(-7, 47, 6))));
  EXPECT_LT(error, 0.01);
  EXPECT_NEAR(p.distance_m / atmos::kAstronomicalUnitM, 0.99760775, 2e-4);
}

TEST(Ephemeris, SunOfRedaAndAndreas2004) {
  // Reda & Andreas 2004 (NREL SPA), the example of their Table A4.1 and
  // results A5.1: 2003 October 17, 12:30:30 local time (−7 h), ΔT = 67 s,
  // 39.742476° N, 105.1786° W, 1830.14 m: topocentric azimuth 194.34024°
  // (from north), zenith angle 50.11162° with their refraction for 820 hPa
  // and 11 °C, i.e. the geometric elevation 39.872046°.
  const atmos::Instant instant = atmos::instant_of({2003, 10, 17, 19, 30, 30.0}, 67.0);
  const atmos::SkyOfDate sky = atmos::sky_of_date(instant, {39.742476, -105.1786, 1830.14});
  const double d_az = angle_difference(sky.sun.azimuth_deg, 194.34024);
  const double d_el = sky.sun.elevation_deg - 39.872046;
  std::printf("Sun, Reda & Andreas 2004: azimuth error %.5f deg, elevation error %.5f deg\n", d_az, d_el);
  EXPECT_NEAR(d_az, 0.0, 0.02);
  EXPECT_NEAR(d_el, 0.0, 0.02);
  // The refraction an observer would add there: 0.016° (their 0.016332°
  // for 820 hPa and 11 °C is the same formula scaled by pressure and
  // temperature, (820/1010) (283/284)).
  EXPECT_NEAR(atmos::refraction_deg(39.872046) * (820.0 / 1010.0) * (283.0 / 284.0), 0.016332, 0.0003);
}

TEST(Ephemeris, HorizontalCoordinatesOfMeeusExample13b) {
  // Venus from the US Naval Observatory, 1987 April 10, 19h21m00s UT:
  // α = 23h09m16.641s, δ = −6°43′11.61″, apparent sidereal time at
  // Greenwich 8h34m56.853s, 38°55′17″ N, 77°03′56″ W: azimuth 68.0337°
  // from the south (248.0337° from north), elevation 15.1249°.
  atmos::EquatorialPosition venus;
  venus.right_ascension_deg = hms_deg(23, 9, 16.641);
  venus.declination_deg = dms_deg(-6, 43, 11.61);
  const atmos::Observer washington{dms_deg(38, 55, 17), -dms_deg(77, 3, 56), 0.0};
  const atmos::HorizontalPosition h = atmos::horizontal(
      atmos::earth_fixed_from_equatorial(venus, hms_deg(8, 34, 56.853)), atmos::local_frame(washington));
  EXPECT_NEAR(angle_difference(h.azimuth_deg, 248.0337), 0.0, 2e-4);  // Meeus rounds to 1e-4
  EXPECT_NEAR(h.elevation_deg, 15.1249, 1e-4);
}

// ---------------------------------------------------------------------------
// The Moon

TEST(Ephemeris, MoonOfMeeusExample47a) {
  // 1992 April 12, 0h TD: λ = 133.162655°, β = −3.229126°, Δ = 368409.7 km;
  // apparent α = 134.688470°, δ = 13.768368° (with the full nutation).
  const atmos::EclipticPosition e = atmos::moon_mean_ecliptic(2448724.5);
  std::printf("Moon, Meeus 47.a: dlambda %.2e deg, dbeta %.2e deg, ddistance %.3f km\n",
              angle_difference(e.longitude_deg, 133.162655), e.latitude_deg + 3.229126,
              e.distance_m / 1e3 - 368409.7);
  EXPECT_NEAR(angle_difference(e.longitude_deg, 133.162655), 0.0, 2e-6);
  EXPECT_NEAR(e.latitude_deg, -3.229126, 2e-6);
  EXPECT_NEAR(e.distance_m / 1e3, 368409.7, 0.1);
  const atmos::EquatorialPosition q = atmos::moon_apparent_equatorial(2448724.5);
  const double error = atmos::angular_separation_deg(unit_vector(q.right_ascension_deg, q.declination_deg),
                                                     unit_vector(134.688470, 13.768368));
  std::printf("Moon, Meeus 47.a apparent: error %.5f deg (%.2f arcsec)\n", error, error * 3600.0);
  EXPECT_LT(error, 0.5 / 3600.0);
}

// NASA's points of greatest eclipse of two total solar eclipses (Espenak,
// NASA GSFC eclipse web site): there the shadow's axis passes at the
// instant of greatest eclipse, so the points lie on the central line. Seen
// from each, the Sun's and the Moon's centres must pass over one another
// some time around that instant: the smallest separation the ephemeris
// finds in a ±3 min window is its error across the path, in arcseconds.
struct GreatestEclipse {
  const char* name;
  atmos::UtcTime around;  // UTC
  double latitude_deg, longitude_deg;
};

TEST(Ephemeris, CentralAtNasasPointsOfGreatestEclipse) {
  const GreatestEclipse eclipses[] = {
      {"2017-08-21", {2017, 8, 21, 18, 25, 0.0}, dms_deg(36, 58.0, 0), -dms_deg(87, 40.3, 0)},
      {"2024-04-08", {2024, 4, 8, 18, 17, 0.0}, dms_deg(25, 17.4, 0), -dms_deg(104, 8.3, 0)},
  };
  for (const GreatestEclipse& g : eclipses) {
    const atmos::Instant start = atmos::instant_of(g.around);
    double smallest = 1e9, at = 0.0, margin = 0.0;
    for (double dt = -180.0; dt <= 180.0; dt += 0.5) {
      atmos::Instant i = start;
      i.jd_ut += dt / 86400.0;
      i.jd_tt += dt / 86400.0;
      const atmos::SkyOfDate sky = atmos::sky_of_date(i, {g.latitude_deg, g.longitude_deg, 0.0});
      const double separation = atmos::angular_separation_deg(sky.sun.topocentric_m, sky.moon.topocentric_m);
      if (separation < smallest) {
        smallest = separation;
        at = dt;
        margin = sky.moon.angular_radius_deg - sky.sun.angular_radius_deg;
      }
    }
    const double seconds = at + g.around.minute * 60.0;
    std::printf("eclipse %s at NASA's point of greatest eclipse: smallest Sun-Moon separation %.2f arcsec at "
                "%02d:%02d:%04.1f UTC (Moon - Sun radius %.1f arcsec)\n",
                g.name, smallest * 3600.0, g.around.hour, int(seconds) / 60, std::fmod(seconds, 60.0),
                margin * 3600.0);
    EXPECT_LT(smallest * 3600.0, 5.0) << g.name;
    EXPECT_GT(std::abs(at), 0.0) << g.name;  // a minimum inside the window, not at its edge
    EXPECT_LT(std::abs(at), 179.0) << g.name;
    EXPECT_GT(margin, 0.0) << g.name;  // total: the Moon looks larger than the Sun
  }
}

TEST(Ephemeris, TotalEclipseOf2024SeenFromDallas) {
  // Dallas (32.7767° N, 96.7970° W): totality at 18:42:30 UTC (NASA: 18:40:40
  // to 18:44:31), partial an hour earlier (first contact 17:23).
  const atmos::Observer dallas{32.7767, -96.7970, 0.0};
  const atmos::SkyOfDate total = atmos::sky_of_date(atmos::parse_utc_time("2024-04-08T18:42:30Z"), dallas);
  const double s_total = atmos::angular_separation_deg(total.sun.topocentric_m, total.moon.topocentric_m);
  const double difference = total.moon.angular_radius_deg - total.sun.angular_radius_deg;
  std::printf("Dallas 18:42:30 UTC: separation %.1f arcsec, radii %.1f (Moon) and %.1f (Sun) arcsec, sun at az %.2f "
              "el %.2f deg\n",
              s_total * 3600.0, total.moon.angular_radius_deg * 3600.0, total.sun.angular_radius_deg * 3600.0,
              total.sun.azimuth_deg, total.sun.elevation_deg);
  EXPECT_LT(s_total, difference);
  const atmos::SkyOfDate partial = atmos::sky_of_date(atmos::parse_utc_time("2024-04-08T17:40:00Z"), dallas);
  const double s_partial = atmos::angular_separation_deg(partial.sun.topocentric_m, partial.moon.topocentric_m);
  std::printf("Dallas 17:40:00 UTC: separation %.1f arcsec\n", s_partial * 3600.0);
  EXPECT_GT(s_partial, partial.moon.angular_radius_deg - partial.sun.angular_radius_deg);
  EXPECT_LT(s_partial, partial.moon.angular_radius_deg + partial.sun.angular_radius_deg);
  // Totality's ends from the ephemeris, by bisection on the inner contact
  // separation = r_moon − r_sun, against NASA's 18:40:40 and 18:44:31.
  auto inner_gap = [&](double seconds_after_1840) {
    atmos::UtcTime t{2024, 4, 8, 18, 40, 0.0};
    const atmos::Instant base = atmos::instant_of(t);
    atmos::Instant i = base;
    i.jd_ut += seconds_after_1840 / 86400.0;
    i.jd_tt += seconds_after_1840 / 86400.0;
    const atmos::SkyOfDate s = atmos::sky_of_date(i, dallas);
    return atmos::angular_separation_deg(s.sun.topocentric_m, s.moon.topocentric_m) -
           (s.moon.angular_radius_deg - s.sun.angular_radius_deg);
  };
  auto contact = [&](double inside, double outside) {
    for (int k = 0; k < 40; ++k) {
      const double mid = 0.5 * (inside + outside);
      (inner_gap(mid) < 0.0 ? inside : outside) = mid;
    }
    return inside;
  };
  const double second = contact(150.0, 0.0), third = contact(150.0, 300.0);
  std::printf("Dallas totality from the ephemeris: 18:40:%05.2f to 18:%02d:%05.2f UTC (NASA 18:40:40 to 18:44:31)\n",
              second, 40 + int(third) / 60, std::fmod(third, 60.0));
  EXPECT_NEAR(second, 40.0, 15.0);
  EXPECT_NEAR(third, 271.0, 15.0);
}

// ---------------------------------------------------------------------------
// Stars

TEST(Ephemeris, PrecessionAndApparentPlaceOfMeeusExamples21bAnd23a) {
  // θ Persei: J2000 α = 2h44m11.986s, δ = +49°13′42.48″, proper motion
  // +0.03425 s and −0.0895″ a year, to 2028 November 13.19 TD (JDE
  // 2462088.69): mean place 2h46m11.331s, +49°20′54.54″ (example 21.b),
  // apparent place 2h46m14.390s, +49°21′07.45″ (example 23.a).
  const double jde = 2462088.69, years = (jde - 2451545.0) / 365.25;
  atmos::EquatorialPosition j2000;
  j2000.right_ascension_deg = hms_deg(2, 44, 11.986 + 0.03425 * years);
  j2000.declination_deg = dms_deg(49, 13, 42.48 - 0.0895 * years);
  const atmos::EquatorialPosition mean = atmos::precess_from_j2000(j2000, jde);
  const double mean_error = atmos::angular_separation_deg(
      unit_vector(mean.right_ascension_deg, mean.declination_deg), unit_vector(hms_deg(2, 46, 11.331), dms_deg(49, 20, 54.54)));
  const atmos::EquatorialPosition apparent = atmos::apparent_place(j2000, jde);
  const double apparent_error =
      atmos::angular_separation_deg(unit_vector(apparent.right_ascension_deg, apparent.declination_deg),
                                    unit_vector(hms_deg(2, 46, 14.390), dms_deg(49, 21, 7.45)));
  std::printf("theta Persei: precession error %.3f arcsec, apparent place error %.3f arcsec\n", mean_error * 3600.0,
              apparent_error * 3600.0);
  EXPECT_LT(mean_error * 3600.0, 0.02);
  EXPECT_LT(apparent_error * 3600.0, 1.0);
}

std::vector<atmos::CatalogueStar> xplanet_catalogue() {
  return atmos::load_bright_star_catalogue();  // scripts/setup.sh installs xplanet
}

TEST(Ephemeris, ReadsXplanetsBrightStarCatalogue) {
  const std::vector<atmos::CatalogueStar> stars = xplanet_catalogue();
  EXPECT_GT(stars.size(), 9000u);
  // Sirius, HR 2491: J2000 6h45m08.9s, −16°42′58″, V = −1.46 (Hoffleit & Warren 1991).
  const atmos::CatalogueStar* sirius = nullptr;
  for (const auto& s : stars)
    if (s.bright_star_number == 2491) sirius = &s;
  ASSERT_NE(sirius, nullptr);
  EXPECT_NEAR(sirius->right_ascension_deg, hms_deg(6, 45, 8.9), 0.002);
  EXPECT_NEAR(sirius->declination_deg, dms_deg(-16, 42, 58), 0.0005);
  EXPECT_EQ(sirius->v_magnitude, -1.46);
  EXPECT_TRUE(std::isnan(sirius->b_minus_v));
  EXPECT_NE(sirius->name.find("CMa"), std::string::npos);
}

TEST(Ephemeris, RejectsMalformedCatalogues) {
  for (const char* text : {"", "# only a comment\n", "-16.7 6.75\n", "-96.0 6.75 1.0 \"x\" 1\n",
                           "10.0 24.5 1.0 \"x\" 1\n", "10.0 6.75 nan \"x\" 1\n", "10.0 6.75 1.0 \"x 1\n"}) {
    std::istringstream in(text);
    try {
      atmos::parse_bright_star_catalogue(in, "test");
      ADD_FAILURE() << "accepted \"" << text << "\"";
    } catch (const atmos::Error& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
      EXPECT_EQ(std::string(e.what()).rfind("test", 0), 0u) << e.what();
    }
  }
  EXPECT_THROW(atmos::load_bright_star_catalogue("/nonexistent/BSC"), atmos::Error);
}

TEST(Ephemeris, StarsPlacedBySiderealTimeMatchTheSphericalFormulas) {
  // Sirius (HR 2491), Vega (7001), Betelgeuse (2061) and Polaris (424) seen
  // from Dallas on 2024-12-01 at 04:00 UTC, against the hour angle and
  // Meeus 1998 eqs. 13.5-13.6 computed here from the catalogue's J2000 place
  // brought to the date.
  const std::vector<atmos::CatalogueStar> catalogue = xplanet_catalogue();
  const atmos::Observer dallas{32.7767, -96.7970, 0.0};
  const atmos::Instant instant = atmos::instant_of(atmos::parse_utc_time("2024-12-01T04:00:00Z"));
  const std::vector<atmos::SkyStar> sky = atmos::stars_in_sky(catalogue, instant, dallas);
  ASSERT_EQ(sky.size(), catalogue.size());
  const double theta = atmos::greenwich_apparent_sidereal_time_deg(instant);
  double worst = 0.0;
  for (int hr : {2491, 7001, 2061, 424}) {
    size_t k = 0;
    while (k < catalogue.size() && catalogue[k].bright_star_number != hr) ++k;
    ASSERT_LT(k, catalogue.size()) << hr;
    atmos::EquatorialPosition j2000;
    j2000.right_ascension_deg = catalogue[k].right_ascension_deg;
    j2000.declination_deg = catalogue[k].declination_deg;
    const atmos::EquatorialPosition p = atmos::apparent_place(j2000, instant.jd_tt);
    const double hour_angle = (theta + dallas.longitude_deg - p.right_ascension_deg) * kDeg;
    const double phi = dallas.latitude_deg * kDeg, delta = p.declination_deg * kDeg;
    const double elevation =
        std::asin(std::sin(phi) * std::sin(delta) + std::cos(phi) * std::cos(delta) * std::cos(hour_angle)) / kDeg;
    const double azimuth_from_south = std::atan2(
        std::sin(hour_angle), std::cos(hour_angle) * std::sin(phi) - std::tan(delta) * std::cos(phi)) / kDeg;
    const double azimuth = azimuth_from_south + 180.0;
    const double d_el = sky[k].elevation_deg - elevation;
    const double d_az = angle_difference(sky[k].azimuth_deg, azimuth) * std::cos(elevation * kDeg);
    worst = std::max({worst, std::abs(d_el), std::abs(d_az)});
    EXPECT_NEAR(d_el, 0.0, 1e-7) << hr;
    EXPECT_NEAR(d_az, 0.0, 1e-7) << hr;
    // The direction is a unit vector.
    EXPECT_NEAR(glm::length(sky[k].direction), 1.0, 1e-12);
  }
  std::printf("stars vs the spherical formulas: largest difference %.2e deg\n", worst);
  // Polaris stands within its polar distance (0.64° in 2024) of the
  // latitude.
  size_t polaris = 0;
  while (catalogue[polaris].bright_star_number != 424) ++polaris;
  EXPECT_NEAR(sky[polaris].elevation_deg, dallas.latitude_deg, 0.7);
}

TEST(Ephemeris, StarColourAndBrightness) {
  // Ballesteros 2012: B−V = 0 gives 10 125 K; the Sun's B−V (0.653) gives
  // 5767 K, 5 K from the Sun's 5772 K (IAU 2015 nominal).
  EXPECT_NEAR(atmos::temperature_from_b_minus_v(0.0), 4600.0 * (1.0 / 1.7 + 1.0 / 0.62), 1e-9);
  EXPECT_NEAR(atmos::temperature_from_b_minus_v(atmos::kSolarBMinusV), 5772.0, 20.0);
  EXPECT_THROW(atmos::temperature_from_b_minus_v(3.0), atmos::Error);
  EXPECT_THROW(atmos::temperature_from_b_minus_v(std::nan("")), atmos::Error);
  // Vega (V = 0.03, B−V = 0.00): about 2.5e-6 lux (a V = 0 star gives
  // 2.54e-6 lux, Allen's Astrophysical Quantities, Cox 2000).
  const glm::dvec3 vega = atmos::star_srgb_irradiance(0.03, 0.0);
  const double vega_lux = atmos::srgb_luminance(vega);
  std::printf("Vega: %.3g lux, linear sRGB (%.3f, %.3f, %.3f) of its luminance\n", vega_lux, vega.x / vega_lux,
              vega.y / vega_lux, vega.z / vega_lux);
  EXPECT_NEAR(vega_lux, 2.54e-6 * std::pow(10.0, -0.4 * 0.03), 0.25e-6);
  // Five magnitudes are a factor 100.
  EXPECT_NEAR(atmos::srgb_luminance(atmos::star_srgb_irradiance(5.03, 0.0)) / vega_lux, 0.01, 1e-12);
  // Hot stars are blue, cool ones red.
  const glm::dvec3 hot = atmos::star_srgb_irradiance(1.0, -0.3), cool = atmos::star_srgb_irradiance(1.0, 1.6);
  EXPECT_GT(hot.z, hot.x);
  EXPECT_GT(cool.x, 2.0 * cool.z);
  EXPECT_NEAR(atmos::v_band_spectral_irradiance(0.0), 3.631e-11, 1e-16);
}

TEST(Ephemeris, RejectsBadObservers) {
  EXPECT_THROW(atmos::sky_of_date(atmos::UtcTime{}, {91.0, 0.0, 0.0}), atmos::Error);
  EXPECT_THROW(atmos::sky_of_date(atmos::UtcTime{}, {-90.5, 0.0, 0.0}), atmos::Error);
  EXPECT_THROW(atmos::sky_of_date(atmos::UtcTime{}, {0.0, std::nan(""), 0.0}), atmos::Error);
  EXPECT_THROW(atmos::instant_of(atmos::UtcTime{}, std::nan("")), atmos::Error);
  EXPECT_NO_THROW(atmos::sky_of_date(atmos::UtcTime{}, {90.0, 720.0, 0.0}));
}

}  // namespace
