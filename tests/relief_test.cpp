// Procedural relief (src/planet/relief.hpp): determinism, the height bounds,
// the mesh error bound against bilinear interpolation on sampled grids, the
// styles' large-scale statistics, craters, continuity, invalid settings.
#include "planet/relief.hpp"
#include "planet/noise_cpp.hpp"

#include "atmos/atmosphere.hpp"

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <tuple>
#include <vector>

namespace {

using atmos::planet::Relief;
using atmos::planet::ReliefSettings;
using atmos::planet::ReliefStyle;

constexpr double kEarthRadius = 6360e3;
constexpr double kMarsRadius = 3389.5e3;

Relief make(ReliefStyle style, std::uint64_t seed = 1, double radius_m = kEarthRadius) {
  ReliefSettings s;
  s.style = style;
  s.seed = seed;
  s.radius_m = radius_m;
  return Relief(s);
}

std::vector<glm::dvec3> random_directions(std::size_t count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<glm::dvec3> directions;
  directions.reserve(count);
  while (directions.size() < count) {
    const glm::dvec3 v(normal(rng), normal(rng), normal(rng));
    const double l = glm::length(v);
    if (l > 1e-6) directions.push_back(v / l);
  }
  return directions;
}

// Two unit vectors orthogonal to d.
void tangent_frame(const glm::dvec3& d, glm::dvec3& e1, glm::dvec3& e2) {
  const glm::dvec3 a = std::abs(d.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  e1 = glm::normalize(glm::cross(d, a));
  e2 = glm::cross(d, e1);
}

const ReliefStyle kStyles[] = {ReliefStyle::earth, ReliefStyle::mars, ReliefStyle::venus, ReliefStyle::titan,
                               ReliefStyle::flat};

// The relief's noise (octave_noise: its eight corners' hashes side by side,
// in the copy the CPU runs) is the shared definition's, gradient_noise of
// noise.glsl compiled here as C++, bit for bit: at points on the lattice's
// planes, just below them, at the cells' centres, at random, near the
// planet and far from its centre (cells beyond 2^32, wrapped), with random
// keys and offsets.
TEST(Relief, OctaveNoiseIsTheSharedGradientNoise) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<std::uint32_t> word;
  int compared = 0, nonzero = 0;
  for (int k = 0; k < 200000; ++k) {
    Relief::Octave o;
    o.inv_wavelength_per_m = std::pow(2.0, -30.0 * unit(rng) + 10.0);  // wavelengths 1 mm to 1000 km
    o.offset = glm::dvec3(double(word(rng) >> 24), double(word(rng) >> 24), double(word(rng) >> 24)) / 256.0;
    o.key = glm::uvec3(word(rng), word(rng), word(rng));
    const double scale = k % 4 == 0 ? 1e10 : kEarthRadius;
    glm::dvec3 p = (glm::dvec3(unit(rng), unit(rng), unit(rng)) * 2.0 - 1.0) * scale;
    const glm::dvec3 q = p * o.inv_wavelength_per_m + o.offset;
    if (k % 5 == 1) p = (glm::floor(q) - o.offset) / o.inv_wavelength_per_m;  // on the planes (up to rounding)
    if (k % 5 == 2) p = (glm::floor(q) + 0.5 - o.offset) / o.inv_wavelength_per_m;
    if (k % 5 == 3) p = (glm::floor(q) + 1.0 - 1e-9 - o.offset) / o.inv_wavelength_per_m;
    const glm::dvec3 r = p * o.inv_wavelength_per_m + o.offset;
    const glm::dvec3 floor_r(std::floor(r.x), std::floor(r.y), std::floor(r.z));
    const glm::uvec3 cell(std::uint32_t(std::int64_t(floor_r.x)), std::uint32_t(std::int64_t(floor_r.y)),
                          std::uint32_t(std::int64_t(floor_r.z)));
    const double shared = atmos::planet::gradient_noise(cell, r - floor_r, o.key);
    const double fast = atmos::planet::octave_noise(p, o);
    ASSERT_EQ(std::memcmp(&shared, &fast, sizeof(double)), 0) << k << ": " << shared << " vs " << fast;
    ++compared;
    nonzero += shared != 0.0;
  }
  EXPECT_EQ(compared, 200000);
  EXPECT_GT(nonzero, 120000);
}

TEST(Relief, SameSeedSameHeightsOtherSeedOtherHeights) {
  const auto directions = random_directions(2000, 7);
  for (ReliefStyle style : {ReliefStyle::earth, ReliefStyle::mars, ReliefStyle::venus, ReliefStyle::titan}) {
    const Relief a = make(style, 42), b = make(style, 42), c = make(style, 43);
    int differ = 0;
    for (const auto& d : directions) {
      const double ha = a.height_m(d);
      ASSERT_EQ(ha, b.height_m(d)) << atmos::planet::relief_style_name(style);
      if (std::abs(ha - c.height_m(d)) > 1.0) ++differ;
    }
    EXPECT_GT(differ, 1800) << atmos::planet::relief_style_name(style);
  }
}

TEST(Relief, HeightsAndAlbedoStayWithinTheirBounds) {
  const auto directions = random_directions(100000, 11);
  for (ReliefStyle style : kStyles) {
    const Relief relief = make(style, 3, style == ReliefStyle::mars ? kMarsRadius : kEarthRadius);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i = 0; i < directions.size(); ++i) {
      const double h = relief.height_m(directions[i]);
      ASSERT_TRUE(std::isfinite(h));
      lo = std::min(lo, h);
      hi = std::max(hi, h);
      if (i % 50 == 0) {
        const glm::vec3 a = relief.albedo(directions[i]);
        for (int c = 0; c < 3; ++c) {
          ASSERT_GE(a[c], 0.0f);
          ASSERT_LE(a[c], 1.0f);
        }
      }
    }
    EXPECT_GE(lo, relief.min_height_m()) << atmos::planet::relief_style_name(style);
    EXPECT_LE(hi, relief.max_height_m()) << atmos::planet::relief_style_name(style);
    // The bounds are not vacuous: the sampled range reaches a quarter of
    // them (they also cover nested craters of every class).
    if (style != ReliefStyle::flat) {
      EXPECT_GT(hi - lo, (relief.max_height_m() - relief.min_height_m()) / 4.0)
          << atmos::planet::relief_style_name(style) << " sampled " << lo << ".." << hi << " bounds "
          << relief.min_height_m() << ".." << relief.max_height_m();
    }
  }
}

// The largest |h - bilinear(h)| over sampled points of grid cells of spacing
// D laid on the sphere as in the header (normalize(d0 + (u e1 + v e2) / R)).
double sampled_interpolation_error(const Relief& relief, const glm::dvec3& d0, double spacing_m, int cells,
                                   std::mt19937_64& rng) {
  const double R = relief.settings().radius_m;
  glm::dvec3 e1, e2;
  tangent_frame(d0, e1, e2);
  auto at = [&](double u, double v) { return relief.height_m(glm::normalize(d0 + (u * e1 + v * e2) / R)); };
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst = 0;
  for (int c = 0; c < cells; ++c) {
    const double u0 = spacing_m * double(c % 4), v0 = spacing_m * double(c / 4);
    const double h00 = at(u0, v0), h10 = at(u0 + spacing_m, v0), h01 = at(u0, v0 + spacing_m),
                 h11 = at(u0 + spacing_m, v0 + spacing_m);
    for (int s = 0; s < 24; ++s) {
      const double a = unit(rng), b = unit(rng);
      const double interpolated = (h00 * (1 - a) + h10 * a) * (1 - b) + (h01 * (1 - a) + h11 * a) * b;
      worst = std::max(worst, std::abs(at(u0 + a * spacing_m, v0 + b * spacing_m) - interpolated));
    }
  }
  return worst;
}

TEST(Relief, ErrorBoundHoldsOnSampledGrids) {
  const double spacings[] = {300e3, 30e3, 3e3, 300.0, 30.0, 3.0, 0.3};
  for (ReliefStyle style : {ReliefStyle::earth, ReliefStyle::mars, ReliefStyle::venus, ReliefStyle::titan}) {
    const Relief relief = make(style, 5, style == ReliefStyle::mars ? kMarsRadius : kEarthRadius);
    std::mt19937_64 rng(17);
    const auto directions = random_directions(24, 19);
    double previous = std::numeric_limits<double>::infinity();
    double best_ratio = 0;
    for (double spacing : spacings) {
      const double bound = relief.error_below_spacing_m(spacing);
      EXPECT_LE(bound, previous) << "not monotone at " << spacing << " m";
      previous = bound;
      double worst = 0;
      for (const auto& d : directions) worst = std::max(worst, sampled_interpolation_error(relief, d, spacing, 8, rng));
      EXPECT_LE(worst, bound) << atmos::planet::relief_style_name(style) << " spacing " << spacing << " m";
      best_ratio = std::max(best_ratio, worst / bound);
      std::printf("  %-6s spacing %9.1f m: bound %10.4g m, sampled max %10.4g m (%.3f)\n",
                  atmos::planet::relief_style_name(style), spacing, bound, worst, worst / bound);
    }
    // Not vacuous: somewhere the sampled error reaches a few percent of the bound.
    EXPECT_GT(best_ratio, 0.02) << atmos::planet::relief_style_name(style);
  }
  EXPECT_EQ(make(ReliefStyle::flat).error_below_spacing_m(1000.0), 0.0);
}

TEST(Relief, EarthHasALandFractionNearEarthsAndABimodalHypsometry) {
  const auto directions = random_directions(50000, 23);
  for (std::uint64_t seed : {1u, 2u}) {
    const Relief relief = make(ReliefStyle::earth, seed);
    int land = 0;
    double land_sum = 0, ocean_sum = 0, highest = -1e9;
    for (const auto& d : directions) {
      const double h = relief.height_m(d);
      highest = std::max(highest, h);
      if (relief.is_ocean(d)) {
        ocean_sum += h;
      } else {
        ++land;
        land_sum += h;
      }
    }
    const double fraction = double(land) / double(directions.size());
    const double mean_land = land_sum / land, mean_ocean = ocean_sum / double(int(directions.size()) - land);
    std::printf("  seed %d: land %.3f, mean land %.0f m, mean ocean %.0f m, highest sample %.0f m\n", int(seed),
                fraction, mean_land, mean_ocean, highest);
    EXPECT_GT(fraction, 0.25);
    EXPECT_LT(fraction, 0.33);
    // Eakins & Sharman 2012: mean land 0.84 km, mean ocean depth 3.7 km.
    EXPECT_GT(mean_land, 300.0);
    EXPECT_LT(mean_land, 1500.0);
    EXPECT_GT(mean_ocean, -4500.0);
    EXPECT_LT(mean_ocean, -3000.0);
    EXPECT_GT(highest, 4000.0);
  }
}

TEST(Relief, MarsNorthernLowlandsLieBelowSouthernHighlands) {
  const auto directions = random_directions(20000, 29);
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Relief relief = make(ReliefStyle::mars, seed, kMarsRadius);
    double north = 0, south = 0;
    int n_north = 0, n_south = 0;
    for (const auto& d : directions) {
      const double h = relief.height_m(d);
      if (d.z > 0) {
        north += h;
        ++n_north;
      } else {
        south += h;
        ++n_south;
      }
    }
    north /= n_north;
    south /= n_south;
    std::printf("  seed %d: mean north %.0f m, mean south %.0f m\n", int(seed), north, south);
    EXPECT_LT(north, south - 2000.0);
  }
}

TEST(Relief, MarsHasCratersOfManySizesWithBowlsAndRims) {
  const Relief relief = make(ReliefStyle::mars, 1, kMarsRadius);
  ASSERT_GE(relief.crater_class_count(), 10);
  // Craters hit by random points, per class (a crater is identified by its centre).
  const auto directions = random_directions(40000, 31);
  std::vector<std::set<std::tuple<double, double, double>>> found(std::size_t(relief.crater_class_count()));
  std::vector<Relief::Crater> examples;
  for (const auto& d : directions) {
    for (int k = 0; k < relief.crater_class_count(); ++k) {
      Relief::Crater crater;
      if (!relief.crater_at(d, k, crater)) continue;
      const double D = 2.0 * crater.radius_m, D_min = relief.crater_class_min_diameter_m(k);
      ASSERT_GE(D, D_min);
      ASSERT_LT(D, 2.0 * D_min);
      if (found[std::size_t(k)].insert({crater.centre.x, crater.centre.y, crater.centre.z}).second &&
          D > 2000.0 && D < 64e3 && examples.size() < 40)
        examples.push_back(crater);
    }
  }
  int classes_with_craters = 0;
  for (const auto& f : found)
    if (f.size() >= 3) ++classes_with_craters;
  EXPECT_GE(classes_with_craters, 6);
  ASSERT_GE(examples.size(), 10u);
  // In the heights: the centre lies below the rim by most of depth + rim
  // height (the detail noise and other craters perturb it by less).
  int bowls = 0;
  for (const auto& c : examples) {
    glm::dvec3 e1, e2;
    tangent_frame(c.centre, e1, e2);
    const double h_centre = relief.height_m(c.centre);
    double h_rim = 0;
    for (int i = 0; i < 8; ++i) {
      const double a = 0.785398 * i;
      h_rim += relief.height_m(glm::normalize(c.centre * kMarsRadius +
                                              c.radius_m * (std::cos(a) * e1 + std::sin(a) * e2))) / 8.0;
    }
    if (h_rim - h_centre > 0.6 * (c.depth_m + c.rim_height_m)) ++bowls;
    // Garvin & Frawley 1998: depth / diameter between about 0.02 (large
    // degraded) and 0.2 (small fresh).
    const double ratio = c.depth_m / (2.0 * c.radius_m);
    EXPECT_GT(ratio, 0.01);
    EXPECT_LT(ratio, 0.2);
  }
  EXPECT_GE(bowls, int(examples.size()) * 8 / 10);
  // Size-frequency N ~ D^-2 per class: a random point lies in a crater of
  // class k with probability ~ N_k D_k^2, so the distinct craters found
  // (rarely hit twice at these sizes) estimate N_k D_k^2, and the number per
  // area of the smallest class over the class four halvings larger (D 16
  // times larger) is (found_small / found_large) x 16^2, expected 16^2.
  const std::size_t smallest = found.size() - 1;
  ASSERT_GT(found[smallest - 4].size(), 20u);
  const double density_ratio = double(found[smallest].size()) / double(found[smallest - 4].size()) * 256.0;
  EXPECT_GT(density_ratio, 128.0);
  EXPECT_LT(density_ratio, 512.0);
}

TEST(Relief, NoJumpsBeyondTheLipschitzBound) {
  for (ReliefStyle style : {ReliefStyle::earth, ReliefStyle::mars, ReliefStyle::venus, ReliefStyle::titan}) {
    const double R = style == ReliefStyle::mars ? kMarsRadius : kEarthRadius;
    const Relief relief = make(style, 9, R);
    double lipschitz = 0;
    for (const auto& b : relief.term_bounds()) lipschitz += b.slope;
    const auto directions = random_directions(3000, 37);
    std::mt19937_64 rng(41);
    std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
    double worst = 0;
    for (std::size_t i = 0; i < directions.size(); ++i) {
      const double step_m = i % 3 == 0 ? 0.05 : (i % 3 == 1 ? 1.0 : 50.0);
      glm::dvec3 e1, e2;
      tangent_frame(directions[i], e1, e2);
      const double a = angle(rng);
      const glm::dvec3 p = directions[i] * R;
      const glm::dvec3 q = glm::normalize(p + step_m * (std::cos(a) * e1 + std::sin(a) * e2));
      const double chord = glm::length(q * R - p);
      const double ratio = std::abs(relief.height_m(q) - relief.height_m(directions[i])) / (lipschitz * chord);
      worst = std::max(worst, ratio);
    }
    EXPECT_LE(worst, 1.0) << atmos::planet::relief_style_name(style);
    std::printf("  %-6s Lipschitz bound %.3g m/m, largest sampled fraction of it %.3f\n",
                atmos::planet::relief_style_name(style), lipschitz, worst);
  }
}

TEST(Relief, DetailIsResolvedBelowAMetreAtEarthsRadius) {
  // Octaves below a metre vary over 10 cm at Earth's radius: split lattice
  // coordinates keep them; a float position (0.5 m ulp) would not.
  const Relief relief = make(ReliefStyle::earth, 1);
  const auto directions = random_directions(200, 43);
  int varied = 0;
  for (const auto& d : directions) {
    glm::dvec3 e1, e2;
    tangent_frame(d, e1, e2);
    const double h0 = relief.height_m(d);
    const double h1 = relief.height_m(glm::normalize(d * kEarthRadius + 0.1 * e1));
    if (std::abs(h1 - h0) > 1e-4) ++varied;
  }
  EXPECT_GT(varied, 190);
  EXPECT_LT(relief.error_below_spacing_m(0.3), 1.0);
  EXPECT_GT(relief.error_below_spacing_m(0.3), 0.0);
}

TEST(Relief, AlbedoFollowsThePresetsGroundColours) {
  const auto directions = random_directions(4000, 47);
  auto mean_albedo = [&](const Relief& relief) {
    glm::dvec3 sum(0.0);
    for (const auto& d : directions) sum += glm::dvec3(relief.albedo(d));
    return sum / double(directions.size());
  };
  // data/planets/mars.json: 0.17 at 550 nm, 0.24 at 600 nm, 0.09 at 450 nm; red > green > blue.
  const glm::dvec3 mars = mean_albedo(make(ReliefStyle::mars, 1, kMarsRadius));
  EXPECT_NEAR(mars.y, 0.17, 0.04);
  EXPECT_GT(mars.x, mars.y);
  EXPECT_GT(mars.y, mars.z);
  const glm::dvec3 titan = mean_albedo(make(ReliefStyle::titan, 1, 2575e3));
  EXPECT_NEAR(titan.y, 0.08, 0.03);
  const glm::dvec3 venus = mean_albedo(make(ReliefStyle::venus, 1, 6051.8e3));
  EXPECT_NEAR(venus.y, 0.1, 0.03);
  // Earth: the sea floor and land differ; snow only high up.
  const Relief earth = make(ReliefStyle::earth, 1);
  for (const auto& d : directions) {
    const glm::vec3 a = earth.albedo(d);
    if (a.x > 0.6f) {
      EXPECT_GT(earth.height_m(d), 3700.0);
    }
  }
}

// The Mars style's canyon (after Valles Marineris): near the equator, its
// floor ~7 km below the plateau on either side, and only in the Mars style.
TEST(Relief, MarsHasAValleyDeeperThanItsSurroundings) {
  const Relief mars = make(ReliefStyle::mars, 1, kMarsRadius);
  const glm::dvec3 c = mars.canyon_centre();
  ASSERT_NEAR(glm::length(c), 1.0, 1e-12);
  EXPECT_LT(std::abs(c.z), std::sin(15.0 * M_PI / 180.0));
  // Across the canyon: the normal to c in the plane of c and the pole.
  const glm::dvec3 across = glm::normalize(glm::dvec3(0, 0, 1) - c * c.z);
  const auto h = [&](double offset_m) {
    return mars.height_m(glm::normalize(c + across * (offset_m / kMarsRadius)));
  };
  // Means over a few points (the detail and craters vary by hundreds of m).
  double floor = 0, plateau = 0;
  for (int k = -2; k <= 2; ++k) {
    floor += h(k * 5e3) / 5.0;
    plateau += (h(300e3 + k * 5e3) + h(-300e3 + k * 5e3)) / 10.0;
  }
  EXPECT_LT(floor - plateau, -5000.0) << "floor " << floor << " m, plateau " << plateau << " m";
  EXPECT_EQ(make(ReliefStyle::earth).canyon_centre(), glm::dvec3(0.0));
}

TEST(Relief, InvalidSettingsAreReported) {
  for (double radius : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()})
    EXPECT_THROW(make(ReliefStyle::earth, 1, radius), atmos::Error);
  EXPECT_THROW(atmos::surface_style_from_name("pluto"), atmos::Error);
  EXPECT_EQ(atmos::surface_style_from_name("mars"), ReliefStyle::mars);
  EXPECT_THROW(make(ReliefStyle::earth).error_below_spacing_m(-1.0), atmos::Error);
  EXPECT_THROW(make(ReliefStyle::earth).error_below_spacing_m(std::numeric_limits<double>::quiet_NaN()), atmos::Error);
  // A small body keeps only the crater classes whose lattice fits.
  const Relief small = make(ReliefStyle::mars, 1, 50e3);
  EXPECT_LT(small.crater_class_count(), make(ReliefStyle::mars, 1, kMarsRadius).crater_class_count());
  for (const auto& d : random_directions(1000, 53)) ASSERT_TRUE(std::isfinite(small.height_m(d)));
}

}  // namespace
