#include "atmos/ephemeris.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "astronomy/angles.hpp"
#include "atmos/atmosphere.hpp"
#include "physics/checks.hpp"

namespace atmos {

namespace {

using astronomy::kArcsecond;
using astronomy::kDegree;
using astronomy::wrap_360;

constexpr double kJ2000 = 2451545.0;         // JD of 2000 January 1.5 TT
constexpr double kJulianCentury = 36525.0;   // days

double sin_deg(double x) { return std::sin(x * kDegree); }
double cos_deg(double x) { return std::cos(x * kDegree); }

double centuries_from_j2000(double jd) { return (jd - kJ2000) / kJulianCentury; }

bool leap_year(int year) { return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0; }

int days_in_month(int year, int month) {
  static constexpr std::array<int, 12> days = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return month == 2 && leap_year(year) ? 29 : days[size_t(month - 1)];
}

// Reads exactly `count` decimal digits at text[at].
bool read_digits(const std::string& text, size_t at, size_t count, int& value) {
  if (at + count > text.size()) return false;
  value = 0;
  for (size_t i = at; i < at + count; ++i) {
    if (text[i] < '0' || text[i] > '9') return false;
    value = value * 10 + (text[i] - '0');
  }
  return true;
}

// The periodic terms of the Moon's longitude and distance (Meeus 1998 Table
// 47.A) and latitude (Table 47.B): the multiples of D, M, M′ and F in the
// argument, and the coefficient of sin (longitude, latitude: 1e-6 degree)
// or of cos (distance: 1e-3 km). Terms with M carry the factor E^|M|.
struct LunarTerm {
  signed char d, m, m_prime, f;
  int longitude, distance;
};
struct LunarLatitudeTerm {
  signed char d, m, m_prime, f;
  int latitude;
};

constexpr std::array<LunarTerm, 60> kLunarLongitudeDistance = {{
    {0, 0, 1, 0, 6288774, -20905355}, {2, 0, -1, 0, 1274027, -3699111}, {2, 0, 0, 0, 658314, -2955968},
    {0, 0, 2, 0, 213618, -569925},    {0, 1, 0, 0, -185116, 48888},      {0, 0, 0, 2, -114332, -3149},
    {2, 0, -2, 0, 58793, 246158},     {2, -1, -1, 0, 57066, -152138},    {2, 0, 1, 0, 53322, -170733},
    {2, -1, 0, 0, 45758, -204586},    {0, 1, -1, 0, -40923, -129620},    {1, 0, 0, 0, -34720, 108743},
    {0, 1, 1, 0, -30383, 104755},     {2, 0, 0, -2, 15327, 10321},       {0, 0, 1, 2, -12528, 0},
    {0, 0, 1, -2, 10980, 79661},      {4, 0, -1, 0, 10675, -34782},      {0, 0, 3, 0, 10034, -23210},
    {4, 0, -2, 0, 8548, -21636},      {2, 1, -1, 0, -7888, 24208},       {2, 1, 0, 0, -6766, 30824},
    {1, 0, -1, 0, -5163, -8379},      {1, 1, 0, 0, 4987, -16675},        {2, -1, 1, 0, 4036, -12831},
    {2, 0, 2, 0, 3994, -10445},       {4, 0, 0, 0, 3861, -11650},        {2, 0, -3, 0, 3665, 14403},
    {0, 1, -2, 0, -2689, -7003},      {2, 0, -1, 2, -2602, 0},           {2, -1, -2, 0, 2390, 10056},
    {1, 0, 1, 0, -2348, 6322},        {2, -2, 0, 0, 2236, -9884},        {0, 1, 2, 0, -2120, 5751},
    {0, 2, 0, 0, -2069, 0},           {2, -2, -1, 0, 2048, -4950},       {2, 0, 1, -2, -1773, 4130},
    {2, 0, 0, 2, -1595, 0},           {4, -1, -1, 0, 1215, -3958},       {0, 0, 2, 2, -1110, 0},
    {3, 0, -1, 0, -892, 3258},        {2, 1, 1, 0, -810, 2616},          {4, -1, -2, 0, 759, -1897},
    {0, 2, -1, 0, -713, -2117},       {2, 2, -1, 0, -700, 2354},         {2, 1, -2, 0, 691, 0},
    {2, -1, 0, -2, 596, 0},           {4, 0, 1, 0, 549, -1423},          {0, 0, 4, 0, 537, -1117},
    {4, -1, 0, 0, 520, -1571},        {1, 0, -2, 0, -487, -1739},        {2, 1, 0, -2, -399, 0},
    {0, 0, 2, -2, -381, -4421},       {1, 1, 1, 0, 351, 0},              {3, 0, -2, 0, -340, 0},
    {4, 0, -3, 0, 330, 0},            {2, -1, 2, 0, 327, 0},             {0, 2, 1, 0, -323, 1165},
    {1, 1, -1, 0, 299, 0},            {2, 0, 3, 0, 294, 0},              {2, 0, -1, -2, 0, 8752},
}};

constexpr std::array<LunarLatitudeTerm, 60> kLunarLatitude = {{
    {0, 0, 0, 1, 5128122}, {0, 0, 1, 1, 280602}, {0, 0, 1, -1, 277693}, {2, 0, 0, -1, 173237},
    {2, 0, -1, 1, 55413},  {2, 0, -1, -1, 46271}, {2, 0, 0, 1, 32573},   {0, 0, 2, 1, 17198},
    {2, 0, 1, -1, 9266},   {0, 0, 2, -1, 8822},   {2, -1, 0, -1, 8216},  {2, 0, -2, -1, 4324},
    {2, 0, 1, 1, 4200},    {2, 1, 0, -1, -3359},  {2, -1, -1, 1, 2463},  {2, -1, 0, 1, 2211},
    {2, -1, -1, -1, 2065}, {0, 1, -1, -1, -1870}, {4, 0, -1, -1, 1828},  {0, 1, 0, 1, -1794},
    {0, 0, 0, 3, -1749},   {0, 1, -1, 1, -1565},  {1, 0, 0, 1, -1491},   {0, 1, 1, 1, -1475},
    {0, 1, 1, -1, -1410},  {0, 1, 0, -1, -1344},  {1, 0, 0, -1, -1335},  {0, 0, 3, 1, 1107},
    {4, 0, 0, -1, 1021},   {4, 0, -1, 1, 833},    {0, 0, 1, -3, 777},    {4, 0, -2, 1, 671},
    {2, 0, 0, -3, 607},    {2, 0, 2, -1, 596},    {2, -1, 1, -1, 491},   {2, 0, -2, 1, -451},
    {0, 0, 3, -1, 439},    {2, 0, 2, 1, 422},     {2, 0, -3, -1, 421},   {2, 1, -1, 1, -366},
    {2, 1, 0, 1, -351},    {4, 0, 0, 1, 331},     {2, -1, 1, 1, 315},    {2, -2, 0, -1, 302},
    {0, 0, 1, 3, -283},    {2, 1, 1, -1, -229},   {1, 1, 0, -1, 223},    {1, 1, 0, 1, 223},
    {0, 1, -2, -1, -220},  {2, 1, -1, -1, -220},  {1, 0, 1, 1, -185},    {2, -1, -2, -1, 181},
    {0, 1, 2, 1, -177},    {4, 0, -2, -1, 176},   {4, -1, -1, -1, 166},  {1, 0, 1, -1, -164},
    {4, 0, 1, -1, 132},    {1, 0, -1, -1, -119},  {4, -1, 0, -1, 115},   {2, -2, 0, 1, 107},
}};

// The IAU 1980 theory of nutation (Seidelmann 1982; Meeus 1998 Table 22.A):
// the multiples of D, M, M′, F and Ω in the argument, and the coefficients
// of Δψ (A + B T) sin and Δε (C + D T) cos, in 0.0001″, T in Julian
// centuries of TT from J2000.
struct NutationTerm {
  signed char d, m, m_prime, f, omega;
  double a, b, c, dd;
};
constexpr NutationTerm kNutation[] = {
    {0, 0, 0, 0, 1, -171996, -174.2, 92025, 8.9}, {-2, 0, 0, 2, 2, -13187, -1.6, 5736, -3.1},
    {0, 0, 0, 2, 2, -2274, -0.2, 977, -0.5}, {0, 0, 0, 0, 2, 2062, 0.2, -895, 0.5},
    {0, 1, 0, 0, 0, 1426, -3.4, 54, -0.1}, {0, 0, 1, 0, 0, 712, 0.1, -7, 0}, {-2, 1, 0, 2, 2, -517, 1.2, 224, -0.6},
    {0, 0, 0, 2, 1, -386, -0.4, 200, 0}, {0, 0, 1, 2, 2, -301, 0, 129, -0.1}, {-2, -1, 0, 2, 2, 217, -0.5, -95, 0.3},
    {-2, 0, 1, 0, 0, -158, 0, 0, 0}, {-2, 0, 0, 2, 1, 129, 0.1, -70, 0}, {0, 0, -1, 2, 2, 123, 0, -53, 0},
    {2, 0, 0, 0, 0, 63, 0, 0, 0}, {0, 0, 1, 0, 1, 63, 0.1, -33, 0}, {2, 0, -1, 2, 2, -59, 0, 26, 0},
    {0, 0, -1, 0, 1, -58, -0.1, 32, 0}, {0, 0, 1, 2, 1, -51, 0, 27, 0}, {-2, 0, 2, 0, 0, 48, 0, 0, 0},
    {0, 0, -2, 2, 1, 46, 0, -24, 0}, {2, 0, 0, 2, 2, -38, 0, 16, 0}, {0, 0, 2, 2, 2, -31, 0, 13, 0},
    {0, 0, 2, 0, 0, 29, 0, 0, 0}, {-2, 0, 1, 2, 2, 29, 0, -12, 0}, {0, 0, 0, 2, 0, 26, 0, 0, 0},
    {-2, 0, 0, 2, 0, -22, 0, 0, 0}, {0, 0, -1, 2, 1, 21, 0, -10, 0}, {0, 2, 0, 0, 0, 17, -0.1, 0, 0},
    {2, 0, -1, 0, 1, 16, 0, -8, 0}, {-2, 2, 0, 2, 2, -16, 0.1, 7, 0}, {0, 1, 0, 0, 1, -15, 0, 9, 0},
    {-2, 0, 1, 0, 1, -13, 0, 7, 0}, {0, -1, 0, 0, 1, -12, 0, 6, 0}, {0, 0, 2, -2, 0, 11, 0, 0, 0},
    {2, 0, -1, 2, 1, -10, 0, 5, 0}, {2, 0, 1, 2, 2, -8, 0, 3, 0}, {0, 1, 0, 2, 2, 7, 0, -3, 0},
    {-2, 1, 1, 0, 0, -7, 0, 0, 0}, {0, -1, 0, 2, 2, -7, 0, 3, 0}, {2, 0, 0, 2, 1, -7, 0, 3, 0},
    {2, 0, 1, 0, 0, 6, 0, 0, 0}, {-2, 0, 2, 2, 2, 6, 0, -3, 0}, {-2, 0, 1, 2, 1, 6, 0, -3, 0},
    {2, 0, -2, 0, 1, -6, 0, 3, 0}, {2, 0, 0, 0, 1, -6, 0, 3, 0}, {0, -1, 1, 0, 0, 5, 0, 0, 0},
    {-2, -1, 0, 2, 1, -5, 0, 3, 0}, {-2, 0, 0, 0, 1, -5, 0, 3, 0}, {0, 0, 2, 2, 1, -5, 0, 3, 0},
    {-2, 0, 2, 0, 1, 4, 0, 0, 0}, {-2, 1, 0, 2, 1, 4, 0, 0, 0}, {0, 0, 1, -2, 0, 4, 0, 0, 0},
    {-1, 0, 1, 0, 0, -4, 0, 0, 0}, {-2, 1, 0, 0, 0, -4, 0, 0, 0}, {1, 0, 0, 0, 0, -4, 0, 0, 0},
    {0, 0, 1, 2, 0, 3, 0, 0, 0}, {0, 0, -2, 2, 2, -3, 0, 0, 0}, {-1, -1, 1, 0, 0, -3, 0, 0, 0},
    {0, 1, 1, 0, 0, -3, 0, 0, 0}, {0, -1, 1, 2, 2, -3, 0, 0, 0}, {2, -1, -1, 2, 2, -3, 0, 0, 0},
    {0, 0, 3, 2, 2, -3, 0, 0, 0}, {2, -1, 0, 2, 2, -3, 0, 0, 0}};

// The Earth's heliocentric ecliptic longitude L, latitude B (radians) and
// radius vector R (au) of VSOP87D (Bretagnon & Francou 1988) truncated as in
// Meeus 1998 Appendix III (the tables Reda & Andreas 2004 use): each series
// Σ A cos(B + C τ), A in 1e-8, τ in Julian millennia of TT from J2000.
struct VsopTerm {
  double a, b, c;
};
constexpr VsopTerm kEarthL0[] = {
    {175347046, 0.0, 0.0}, {3341656, 4.6692568, 6283.07585}, {34894, 4.6261, 12566.1517}, {3497, 2.7441, 5753.3849},
    {3418, 2.8289, 3.5231}, {3136, 3.6277, 77713.7715}, {2676, 4.4181, 7860.4194}, {2343, 6.1352, 3930.2097},
    {1324, 0.7425, 11506.7698}, {1273, 2.0371, 529.691}, {1199, 1.1096, 1577.3435}, {990, 5.233, 5884.927},
    {902, 2.045, 26.298}, {857, 3.508, 398.149}, {780, 1.179, 5223.694}, {753, 2.533, 5507.553},
    {505, 4.583, 18849.228}, {492, 4.205, 775.523}, {357, 2.92, 0.067}, {317, 5.849, 11790.629},
    {284, 1.899, 796.298}, {271, 0.315, 10977.079}, {243, 0.345, 5486.778}, {206, 4.806, 2544.314},
    {205, 1.869, 5573.143}, {202, 2.458, 6069.777}, {156, 0.833, 213.299}, {132, 3.411, 2942.463},
    {126, 1.083, 20.775}, {115, 0.645, 0.98}, {103, 0.636, 4694.003}, {102, 0.976, 15720.839}, {102, 4.267, 7.114},
    {99, 6.21, 2146.17}, {98, 0.68, 155.42}, {86, 5.98, 161000.69}, {85, 1.3, 6275.96}, {85, 3.67, 71430.7},
    {80, 1.81, 17260.15}, {79, 3.04, 12036.46}, {75, 1.76, 5088.63}, {74, 3.5, 3154.69}, {74, 4.68, 801.82},
    {70, 0.83, 9437.76}, {62, 3.98, 8827.39}, {61, 1.82, 7084.9}, {57, 2.78, 6286.6}, {56, 4.39, 14143.5},
    {56, 3.47, 6279.55}, {52, 0.19, 12139.55}, {52, 1.33, 1748.02}, {51, 0.28, 5856.48}, {49, 0.49, 1194.45},
    {41, 5.37, 8429.24}, {41, 2.4, 19651.05}, {39, 6.17, 10447.39}, {37, 6.04, 10213.29}, {37, 2.57, 1059.38},
    {36, 1.71, 2352.87}, {36, 1.78, 6812.77}, {33, 0.59, 17789.85}, {30, 0.44, 83996.85}, {30, 2.74, 1349.87},
    {25, 3.16, 4690.48}};
constexpr VsopTerm kEarthL1[] = {
    {628331966747, 0.0, 0.0}, {206059, 2.678235, 6283.07585}, {4303, 2.6351, 12566.1517}, {425, 1.59, 3.523},
    {119, 5.796, 26.298}, {109, 2.966, 1577.344}, {93, 2.59, 18849.23}, {72, 1.14, 529.69}, {68, 1.87, 398.15},
    {67, 4.41, 5507.55}, {59, 2.89, 5223.69}, {56, 2.17, 155.42}, {45, 0.4, 796.3}, {36, 0.47, 775.52},
    {29, 2.65, 7.11}, {21, 5.34, 0.98}, {19, 1.85, 5486.78}, {19, 4.97, 213.3}, {17, 2.99, 6275.96},
    {16, 0.03, 2544.31}, {16, 1.43, 2146.17}, {15, 1.21, 10977.08}, {12, 2.83, 1748.02}, {12, 3.26, 5088.63},
    {12, 5.27, 1194.45}, {12, 2.08, 4694.0}, {11, 0.77, 553.57}, {10, 1.3, 6286.6}, {10, 4.24, 1349.87},
    {9, 2.7, 242.73}, {9, 5.64, 951.72}, {8, 5.3, 2352.87}, {6, 2.65, 9437.76}, {6, 4.67, 4690.48}};
constexpr VsopTerm kEarthL2[] = {
    {52919, 0.0, 0.0}, {8720, 1.0721, 6283.0758}, {309, 0.867, 12566.152}, {27, 0.05, 3.52}, {16, 5.19, 26.3},
    {16, 3.68, 155.42}, {10, 0.76, 18849.23}, {9, 2.06, 77713.77}, {7, 0.83, 775.52}, {5, 4.66, 1577.34},
    {4, 1.03, 7.11}, {4, 3.44, 5573.14}, {3, 5.14, 796.3}, {3, 6.05, 5507.55}, {3, 1.19, 242.73}, {3, 6.12, 529.69},
    {3, 0.31, 398.15}, {3, 2.28, 553.57}, {2, 4.38, 5223.69}, {2, 3.75, 0.98}};
constexpr VsopTerm kEarthL3[] = {
    {289, 5.844, 6283.076}, {35, 0.0, 0.0}, {17, 5.49, 12566.15}, {3, 5.2, 155.42}, {1, 4.72, 3.52},
    {1, 5.3, 18849.23}, {1, 5.97, 242.73}};
constexpr VsopTerm kEarthL4[] = {
    {114, 3.142, 0.0}, {8, 4.13, 6283.08}, {1, 3.84, 12566.15}};
constexpr VsopTerm kEarthL5[] = {
    {1, 3.14, 0.0}};
constexpr VsopTerm kEarthB0[] = {
    {280, 3.199, 84334.662}, {102, 5.422, 5507.553}, {80, 3.88, 5223.69}, {44, 3.7, 2352.87}, {32, 4.0, 1577.34}};
constexpr VsopTerm kEarthB1[] = {
    {9, 3.9, 5507.55}, {6, 1.73, 5223.69}};
constexpr VsopTerm kEarthR0[] = {
    {100013989, 0.0, 0.0}, {1670700, 3.0984635, 6283.07585}, {13956, 3.05525, 12566.1517},
    {3084, 5.1985, 77713.7715}, {1628, 1.1739, 5753.3849}, {1576, 2.8469, 7860.4194}, {925, 5.453, 11506.77},
    {542, 4.564, 3930.21}, {472, 3.661, 5884.927}, {346, 0.964, 5507.553}, {329, 5.9, 5223.694},
    {307, 0.299, 5573.143}, {243, 4.273, 11790.629}, {212, 5.847, 1577.344}, {186, 5.022, 10977.079},
    {175, 3.012, 18849.228}, {110, 5.055, 5486.778}, {98, 0.89, 6069.78}, {86, 5.69, 15720.84},
    {86, 1.27, 161000.69}, {65, 0.27, 17260.15}, {63, 0.92, 529.69}, {57, 2.01, 83996.85}, {56, 5.24, 71430.7},
    {49, 3.25, 2544.31}, {47, 2.58, 775.52}, {45, 5.54, 9437.76}, {43, 6.01, 6275.96}, {39, 5.36, 4694.0},
    {38, 2.39, 8827.39}, {37, 0.83, 19651.05}, {37, 4.9, 12139.55}, {36, 1.67, 12036.46}, {35, 1.84, 2942.46},
    {33, 0.24, 7084.9}, {32, 0.18, 5088.63}, {32, 1.78, 398.15}, {28, 1.21, 6286.6}, {28, 1.9, 6279.55},
    {26, 4.59, 10447.39}};
constexpr VsopTerm kEarthR1[] = {
    {103019, 1.10749, 6283.07585}, {1721, 1.0644, 12566.1517}, {702, 3.142, 0.0}, {32, 1.02, 18849.23},
    {31, 2.84, 5507.55}, {25, 1.32, 5223.69}, {18, 1.42, 1577.34}, {10, 5.91, 10977.08}, {9, 1.42, 6275.96},
    {9, 0.27, 5486.78}};
constexpr VsopTerm kEarthR2[] = {
    {4359, 5.7846, 6283.0758}, {124, 5.579, 12566.152}, {12, 3.14, 0.0}, {9, 3.63, 77713.77}, {6, 1.87, 5573.14},
    {3, 5.47, 18849.23}};
constexpr VsopTerm kEarthR3[] = {
    {145, 4.273, 6283.076}, {7, 3.92, 12566.15}};
constexpr VsopTerm kEarthR4[] = {
    {4, 2.56, 6283.08}};

template <size_t N>
double vsop_series(const VsopTerm (&terms)[N], double tau) {
  double sum = 0.0;
  for (const VsopTerm& k : terms) sum += k.a * std::cos(k.b + k.c * tau);
  return sum;
}

}  // namespace

// ---------------------------------------------------------------------------
// Time

void validate(const UtcTime& t) {
  char text[64];
  if (t.second == std::floor(t.second))
    std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02dZ", t.year, t.month, t.day, t.hour, t.minute,
                  int(t.second));
  else
    std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%06.3fZ", t.year, t.month, t.day, t.hour, t.minute,
                  t.second);
  if (t.year < kEphemerisFirstYear || t.year > kEphemerisLastYear)
    throw Error("date " + std::string(text) + ": the year must be in [" + std::to_string(kEphemerisFirstYear) +
                ", " + std::to_string(kEphemerisLastYear) + "] (the range of the ephemeris' delta T and theories)");
  if (t.month < 1 || t.month > 12) throw Error("date " + std::string(text) + ": no month " + std::to_string(t.month));
  if (t.day < 1 || t.day > days_in_month(t.year, t.month))
    throw Error("date " + std::string(text) + ": day " + std::to_string(t.day) + " is not in that month (it has " +
                std::to_string(days_in_month(t.year, t.month)) + " days)");
  if (t.hour < 0 || t.hour > 23 || t.minute < 0 || t.minute > 59)
    throw Error("date " + std::string(text) + ": the time must be in 00:00:00-23:59:60");
  const double last = t.hour == 23 && t.minute == 59 ? 61.0 : 60.0;  // a leap second ends a day
  if (!(t.second >= 0.0 && t.second < last))
    throw Error("date " + std::string(text) + ": the seconds must be in [0, 60) (60 only for a leap second at 23:59)");
}

UtcTime parse_utc_time(const std::string& text) {
  const std::string problem = "date \"" + text + "\" is not YYYY-MM-DDTHH:MM:SSZ (UTC, e.g. 2024-04-08T18:42:30Z)";
  UtcTime t;
  int second = 0;
  if (text.size() < 20 || !read_digits(text, 0, 4, t.year) || text[4] != '-' || !read_digits(text, 5, 2, t.month) ||
      text[7] != '-' || !read_digits(text, 8, 2, t.day) || text[10] != 'T' || !read_digits(text, 11, 2, t.hour) ||
      text[13] != ':' || !read_digits(text, 14, 2, t.minute) || text[16] != ':' ||
      !read_digits(text, 17, 2, second) || text.back() != 'Z')
    throw Error(problem);
  t.second = second;
  // An optional decimal fraction of the second between the seconds and "Z".
  if (text.size() > 20) {
    if (text[19] != '.' || text.size() == 21) throw Error(problem);
    double scale = 0.1;
    for (size_t i = 20; i + 1 < text.size(); ++i, scale *= 0.1) {
      if (text[i] < '0' || text[i] > '9') throw Error(problem);
      t.second += (text[i] - '0') * scale;
    }
  }
  validate(t);
  return t;
}

double julian_date(const UtcTime& t) {
  // Meeus 1998 eq. 7.1: January and February count as months 13 and 14 of
  // the previous year; B is the Gregorian calendar's correction.
  int y = t.year, m = t.month;
  if (m <= 2) {
    y -= 1;
    m += 12;
  }
  const int a = y / 100;
  const int b = 2 - a + a / 4;
  const double day = t.day + (t.hour + (t.minute + t.second / 60.0) / 60.0) / 24.0;
  return std::floor(365.25 * (y + 4716)) + std::floor(30.6001 * (m + 1)) + day + b - 1524.5;
}

double delta_t_s(double y) {
  // Espenak & Meeus 2006 (Five Millennium Canon of Solar Eclipses, NASA
  // TP-2006-214141, section 2.6), seconds.
  if (!(y >= kEphemerisFirstYear && y < kEphemerisLastYear + 1.0))
    throw Error("delta T: the year " + number_text(y) + " is outside [" + std::to_string(kEphemerisFirstYear) +
                ", " + std::to_string(kEphemerisLastYear + 1) + ")");
  if (y < 1860) {
    const double t = y - 1800;
    return 13.72 - 0.332447 * t + 0.0068612 * t * t + 0.0041116 * std::pow(t, 3) - 0.00037436 * std::pow(t, 4) +
           0.0000121272 * std::pow(t, 5) - 0.0000001699 * std::pow(t, 6) + 0.000000000875 * std::pow(t, 7);
  }
  if (y < 1900) {
    const double t = y - 1860;
    return 7.62 + 0.5737 * t - 0.251754 * t * t + 0.01680668 * std::pow(t, 3) - 0.0004473624 * std::pow(t, 4) +
           std::pow(t, 5) / 233174.0;
  }
  if (y < 1920) {
    const double t = y - 1900;
    return -2.79 + 1.494119 * t - 0.0598939 * t * t + 0.0061966 * std::pow(t, 3) - 0.000197 * std::pow(t, 4);
  }
  if (y < 1941) {
    const double t = y - 1920;
    return 21.20 + 0.84493 * t - 0.076100 * t * t + 0.0020936 * std::pow(t, 3);
  }
  if (y < 1961) {
    const double t = y - 1950;
    return 29.07 + 0.407 * t - t * t / 233.0 + std::pow(t, 3) / 2547.0;
  }
  if (y < 1986) {
    const double t = y - 1975;
    return 45.45 + 1.067 * t - t * t / 260.0 - std::pow(t, 3) / 718.0;
  }
  if (y < 2005) {
    const double t = y - 2000;
    return 63.86 + 0.3345 * t - 0.060374 * t * t + 0.0017275 * std::pow(t, 3) + 0.000651814 * std::pow(t, 4) +
           0.00002373599 * std::pow(t, 5);
  }
  if (y < 2050) {
    const double t = y - 2000;
    return 62.92 + 0.32217 * t + 0.005589 * t * t;
  }
  const double u = (y - 1820) / 100.0;
  if (y < 2150) return -20.0 + 32.0 * u * u - 0.5628 * (2150.0 - y);
  return -20.0 + 32.0 * u * u;
}

Instant instant_of(const UtcTime& time, double delta_t_seconds) {
  validate(time);
  if (!std::isfinite(delta_t_seconds) || std::abs(delta_t_seconds) > 3600.0)
    throw Error("delta T must be finite and within an hour, got " + number_text(delta_t_seconds) + " s");
  Instant i;
  i.jd_ut = julian_date(time);
  i.jd_tt = i.jd_ut + delta_t_seconds / 86400.0;
  return i;
}

Instant instant_of(const UtcTime& time) {
  validate(time);
  return instant_of(time, delta_t_s(time.year + (time.month - 0.5) / 12.0));
}

// ---------------------------------------------------------------------------
// The Earth's rotation and orientation

double greenwich_mean_sidereal_time_deg(double jd_ut) {
  const double t = centuries_from_j2000(jd_ut);
  return wrap_360(280.46061837 + 360.98564736629 * (jd_ut - kJ2000) + 0.000387933 * t * t - t * t * t / 38710000.0);
}

Nutation nutation(double jd_tt) {
  // The fundamental arguments of Meeus 1998 ch. 22, degrees: the Moon's
  // mean elongation D, the Sun's and the Moon's mean anomalies M and M′, the
  // Moon's argument of latitude F and the longitude of its ascending node Ω.
  const double t = centuries_from_j2000(jd_tt);
  const double t2 = t * t, t3 = t2 * t;
  const double d = 297.85036 + 445267.111480 * t - 0.0019142 * t2 + t3 / 189474.0;
  const double m = 357.52772 + 35999.050340 * t - 0.0001603 * t2 - t3 / 300000.0;
  const double m_prime = 134.96298 + 477198.867398 * t + 0.0086972 * t2 + t3 / 56250.0;
  const double f = 93.27191 + 483202.017538 * t - 0.0036825 * t2 + t3 / 327270.0;
  const double omega = 125.04452 - 1934.136261 * t + 0.0020708 * t2 + t3 / 450000.0;
  double psi = 0.0, eps = 0.0;
  for (const NutationTerm& k : kNutation) {
    const double argument = (k.d * d + k.m * m + k.m_prime * m_prime + k.f * f + k.omega * omega) * kDegree;
    psi += (k.a + k.b * t) * std::sin(argument);
    eps += (k.c + k.dd * t) * std::cos(argument);
  }
  Nutation n;
  n.longitude_deg = psi * 1e-4 * kArcsecond;
  n.obliquity_deg = eps * 1e-4 * kArcsecond;
  return n;
}

double mean_obliquity_deg(double jd_tt) {
  const double t = centuries_from_j2000(jd_tt);
  return 23.0 + 26.0 / 60.0 + (21.448 - 46.8150 * t - 0.00059 * t * t + 0.001813 * t * t * t) * kArcsecond;
}

double greenwich_apparent_sidereal_time_deg(const Instant& instant) {
  const Nutation n = nutation(instant.jd_tt);
  const double epsilon = mean_obliquity_deg(instant.jd_tt) + n.obliquity_deg;
  return wrap_360(greenwich_mean_sidereal_time_deg(instant.jd_ut) + n.longitude_deg * cos_deg(epsilon));
}

EquatorialPosition ecliptic_to_equatorial(const EclipticPosition& e, double obliquity_deg) {
  const double l = e.longitude_deg * kDegree, b = e.latitude_deg * kDegree, eps = obliquity_deg * kDegree;
  EquatorialPosition q;
  q.right_ascension_deg =
      wrap_360(std::atan2(std::sin(l) * std::cos(eps) - std::tan(b) * std::sin(eps), std::cos(l)) / kDegree);
  q.declination_deg =
      std::asin(std::sin(b) * std::cos(eps) + std::cos(b) * std::sin(eps) * std::sin(l)) / kDegree;
  q.distance_m = e.distance_m;
  return q;
}

// ---------------------------------------------------------------------------
// The Sun

namespace {

// The Sun's geometric geocentric position of the mean equinox of date
// (Meeus 1998 ch. 25, "higher accuracy"): the Earth's heliocentric L, B, R
// from the truncated VSOP87D, turned around (longitude L + 180°, latitude
// −B), then to the FK5 frame (Meeus 1998 eq. 32.3: λ′ = λ − 1.397° T −
// 0.00031° T², Δλ = −0.09033″, Δβ = 0.03916″ (cos λ′ − sin λ′)).
struct SolarPosition {
  double longitude_deg;
  double latitude_deg;
  double radius_au;
};

SolarPosition solar_position(double jd_tt) {
  const double tau = centuries_from_j2000(jd_tt) / 10.0;
  const double l = vsop_series(kEarthL0, tau) +
                   tau * (vsop_series(kEarthL1, tau) +
                          tau * (vsop_series(kEarthL2, tau) +
                                 tau * (vsop_series(kEarthL3, tau) +
                                        tau * (vsop_series(kEarthL4, tau) + tau * vsop_series(kEarthL5, tau)))));
  const double b = vsop_series(kEarthB0, tau) + tau * vsop_series(kEarthB1, tau);
  const double r = vsop_series(kEarthR0, tau) +
                   tau * (vsop_series(kEarthR1, tau) +
                          tau * (vsop_series(kEarthR2, tau) +
                                 tau * (vsop_series(kEarthR3, tau) + tau * vsop_series(kEarthR4, tau))));
  const double t = centuries_from_j2000(jd_tt);
  const double longitude = l * 1e-8 / kDegree + 180.0;
  const double latitude = -b * 1e-8 / kDegree;
  const double fk5 = longitude - 1.397 * t - 0.00031 * t * t;
  return {wrap_360(longitude - 0.09033 * kArcsecond),
          latitude + 0.03916 * kArcsecond * (cos_deg(fk5) - sin_deg(fk5)), r * 1e-8};
}

}  // namespace

double sun_true_longitude_deg(double jd_tt) { return solar_position(jd_tt).longitude_deg; }

EquatorialPosition sun_apparent_equatorial(double jd_tt) {
  const SolarPosition geometric = solar_position(jd_tt);
  // Apparent: the nutation in longitude, and the annual aberration
  // −20.4898″ / R (Meeus 1998 eq. 25.10).
  const Nutation n = nutation(jd_tt);
  EclipticPosition apparent;
  apparent.longitude_deg =
      wrap_360(geometric.longitude_deg + n.longitude_deg - 20.4898 * kArcsecond / geometric.radius_au);
  apparent.latitude_deg = geometric.latitude_deg;
  apparent.distance_m = geometric.radius_au * kAstronomicalUnitM;
  return ecliptic_to_equatorial(apparent, mean_obliquity_deg(jd_tt) + n.obliquity_deg);
}

// ---------------------------------------------------------------------------
// The Moon

EclipticPosition moon_mean_ecliptic(double jd_tt) {
  // Meeus 1998 ch. 47: the Moon's mean longitude L′, mean elongation D, the
  // Sun's mean anomaly M, the Moon's mean anomaly M′ and argument of latitude
  // F (eqs. 47.1-47.5), degrees; A1 (Venus), A2 (Jupiter) and A3 the
  // additive terms' arguments; E the decrease of the Earth's orbital
  // eccentricity (eq. 47.6).
  const double t = centuries_from_j2000(jd_tt);
  const double t2 = t * t, t3 = t2 * t, t4 = t3 * t;
  const double l_prime = 218.3164477 + 481267.88123421 * t - 0.0015786 * t2 + t3 / 538841.0 - t4 / 65194000.0;
  const double d = 297.8501921 + 445267.1114034 * t - 0.0018819 * t2 + t3 / 545868.0 - t4 / 113065000.0;
  const double m = 357.5291092 + 35999.0502909 * t - 0.0001536 * t2 + t3 / 24490000.0;
  const double m_prime = 134.9633964 + 477198.8675055 * t + 0.0087414 * t2 + t3 / 69699.0 - t4 / 14712000.0;
  const double f = 93.2720950 + 483202.0175233 * t - 0.0036539 * t2 - t3 / 3526000.0 + t4 / 863310000.0;
  const double a1 = 119.75 + 131.849 * t;
  const double a2 = 53.09 + 479264.290 * t;
  const double a3 = 313.45 + 481266.484 * t;
  const double e = 1.0 - 0.002516 * t - 0.0000074 * t2;
  const double e_power[3] = {1.0, e, e * e};

  double sum_l = 0.0, sum_r = 0.0, sum_b = 0.0;
  for (const LunarTerm& k : kLunarLongitudeDistance) {
    const double argument = (k.d * d + k.m * m + k.m_prime * m_prime + k.f * f) * kDegree;
    const double w = e_power[std::abs(k.m)];
    sum_l += k.longitude * w * std::sin(argument);
    sum_r += k.distance * w * std::cos(argument);
  }
  for (const LunarLatitudeTerm& k : kLunarLatitude) {
    const double argument = (k.d * d + k.m * m + k.m_prime * m_prime + k.f * f) * kDegree;
    sum_b += k.latitude * e_power[std::abs(k.m)] * std::sin(argument);
  }
  // The additive terms (Meeus 1998 ch. 47): Venus, Jupiter and the Earth's
  // flattening.
  sum_l += 3958.0 * sin_deg(a1) + 1962.0 * sin_deg(l_prime - f) + 318.0 * sin_deg(a2);
  sum_b += -2235.0 * sin_deg(l_prime) + 382.0 * sin_deg(a3) + 175.0 * sin_deg(a1 - f) + 175.0 * sin_deg(a1 + f) +
           127.0 * sin_deg(l_prime - m_prime) - 115.0 * sin_deg(l_prime + m_prime);

  EclipticPosition p;
  p.longitude_deg = wrap_360(l_prime + sum_l * 1e-6);
  p.latitude_deg = sum_b * 1e-6;
  p.distance_m = (385000.56 + sum_r * 1e-3) * 1e3;
  return p;
}

EquatorialPosition moon_apparent_equatorial(double jd_tt) {
  // Apparent: the nutation in longitude added to λ, the true obliquity
  // (Meeus 1998 example 47.a). The Moon's aberration (light time 1.3 s,
  // 0.7″) is not applied, as in Meeus.
  EclipticPosition p = moon_mean_ecliptic(jd_tt);
  const Nutation n = nutation(jd_tt);
  p.longitude_deg = wrap_360(p.longitude_deg + n.longitude_deg);
  return ecliptic_to_equatorial(p, mean_obliquity_deg(jd_tt) + n.obliquity_deg);
}

// ---------------------------------------------------------------------------
// The observer

void validate(const Observer& o) {
  if (!std::isfinite(o.latitude_deg) || o.latitude_deg < -90.0 || o.latitude_deg > 90.0)
    throw Error("latitude must be in [-90, 90] degrees, got " + number_text(o.latitude_deg));
  if (!std::isfinite(o.longitude_deg)) throw Error("longitude must be a finite number of degrees");
  if (!std::isfinite(o.height_m) || o.height_m < -1e4 || o.height_m > 1e8)
    throw Error("the observer's height must be in [-1e4, 1e8] metres, got " + number_text(o.height_m));
}

glm::dvec3 earth_fixed_position(const Observer& o) {
  validate(o);
  // WGS 84 (NIMA 2000): the prime vertical's radius of curvature
  // N = a / sqrt(1 − e² sin² φ), e² = f (2 − f).
  constexpr double a = 6378137.0, f = 1.0 / 298.257223563;
  constexpr double e2 = f * (2.0 - f);
  const double phi = o.latitude_deg * kDegree, lambda = o.longitude_deg * kDegree;
  const double n = a / std::sqrt(1.0 - e2 * std::sin(phi) * std::sin(phi));
  return {(n + o.height_m) * std::cos(phi) * std::cos(lambda), (n + o.height_m) * std::cos(phi) * std::sin(lambda),
          (n * (1.0 - e2) + o.height_m) * std::sin(phi)};
}

LocalFrame local_frame(const Observer& o) {
  validate(o);
  const double phi = o.latitude_deg * kDegree, lambda = o.longitude_deg * kDegree;
  LocalFrame f;
  f.east = {-std::sin(lambda), std::cos(lambda), 0.0};
  f.north = {-std::sin(phi) * std::cos(lambda), -std::sin(phi) * std::sin(lambda), std::cos(phi)};
  f.up = {std::cos(phi) * std::cos(lambda), std::cos(phi) * std::sin(lambda), std::sin(phi)};
  return f;
}

glm::dvec3 earth_fixed_from_equatorial(const EquatorialPosition& p, double sidereal_time_deg) {
  // The hour angle from Greenwich is θ − α: a body on the Greenwich meridian
  // (α = θ) lies in the x-z plane.
  const double h = (sidereal_time_deg - p.right_ascension_deg) * kDegree;
  const double dec = p.declination_deg * kDegree;
  const double r = p.distance_m > 0.0 ? p.distance_m : 1.0;
  return r * glm::dvec3(std::cos(dec) * std::cos(h), -std::cos(dec) * std::sin(h), std::sin(dec));
}

HorizontalPosition horizontal(const glm::dvec3& direction, const LocalFrame& frame) {
  const double length = glm::length(direction);
  if (!(length > 0.0) || !std::isfinite(length)) throw Error("horizontal: the direction must be nonzero and finite");
  const glm::dvec3 d = direction / length;
  HorizontalPosition h;
  h.azimuth_deg = wrap_360(std::atan2(glm::dot(d, frame.east), glm::dot(d, frame.north)) / kDegree);
  h.elevation_deg = std::asin(std::clamp(glm::dot(d, frame.up), -1.0, 1.0)) / kDegree;
  return h;
}

double angular_separation_deg(const glm::dvec3& a, const glm::dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)) / kDegree;
}

double refraction_deg(double h) {
  if (!std::isfinite(h) || h < -2.0) return 0.0;
  return 1.02 / std::tan((h + 10.3 / (h + 5.11)) * kDegree) / 60.0;
}

// ---------------------------------------------------------------------------
// The sky of a date and place

SkyOfDate sky_of_date(const Instant& instant, const Observer& observer) {
  validate(observer);
  SkyOfDate sky;
  sky.instant = instant;
  sky.sidereal_time_deg = greenwich_apparent_sidereal_time_deg(instant);
  const glm::dvec3 here = earth_fixed_position(observer);
  const LocalFrame frame = local_frame(observer);
  auto body = [&](const EquatorialPosition& geocentric, double radius_m) {
    SkyBody b;
    b.topocentric_m = earth_fixed_from_equatorial(geocentric, sky.sidereal_time_deg) - here;
    b.distance_m = glm::length(b.topocentric_m);
    const HorizontalPosition h = horizontal(b.topocentric_m, frame);
    b.azimuth_deg = h.azimuth_deg;
    b.elevation_deg = h.elevation_deg;
    b.angular_radius_deg = std::asin(radius_m / b.distance_m) / kDegree;
    return b;
  };
  sky.sun = body(sun_apparent_equatorial(instant.jd_tt), kSunRadiusM);
  sky.moon = body(moon_apparent_equatorial(instant.jd_tt), kMoonMeanRadiusM);
  return sky;
}

SkyOfDate sky_of_date(const UtcTime& time, const Observer& observer) {
  return sky_of_date(instant_of(time), observer);
}

}  // namespace atmos
