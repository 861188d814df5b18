// The water's physics (src/physics/water.glsl through physics/water.hpp):
// the Fresnel reflectance against the textbook angle forms, the energy of the
// flat and rough surfaces, the glint BRDF's reciprocity and its agreement
// with a Monte Carlo over Cox & Munk facets, Smith's Λ against its defining
// integral, the seabed's attenuation law, the spectra against their tables,
// the validation of the inputs, and the GLSL compiled on the GPU against the
// C++ twins.
#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/colour.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/water.hpp"
#include "atmos/renderer.hpp"
#include "data/embedded_files.hpp"
#include "fullscreen_program.hpp"
#include "gpu/shader_source.hpp"
#include "physics/parameters.hpp"
#include "physics/water.hpp"

namespace {

namespace ph = atmos::physics;

const glm::vec3 kNormal(0.0f, 0.0f, 1.0f);
const glm::vec3 kUpwind(1.0f, 0.0f, 0.0f);

// The unit direction of zenith angle `zenith` and azimuth `azimuth` (radians,
// azimuth from the upwind axis) in the frame (upwind, crosswind, normal).
glm::dvec3 direction(double zenith, double azimuth) {
  return {std::sin(zenith) * std::cos(azimuth), std::sin(zenith) * std::sin(azimuth), std::cos(zenith)};
}

double radians(double degrees) { return degrees * M_PI / 180.0; }

// A water of index n (all channels) and slope variances `variance`; the
// column's coefficients are those of clear ocean water at 550 nm.
ph::WaterParams water_with(float n, glm::vec2 variance) {
  ph::WaterParams w{};
  w.refractive_index = glm::vec3(n);
  w.absorption = glm::vec3(0.06f);
  w.backscattering = glm::vec3(0.0015f);
  w.diffuse_reflectance = glm::vec3(float(ph::diffuse_fresnel_reflectance(n)));
  w.slope_variance = variance;
  return w;
}

// Fresnel's equations in the angle forms (Born & Wolf 1999, §1.5.2):
// r_s = -sin(θi - θt) / sin(θi + θt), r_p = tan(θi - θt) / tan(θi + θt), in
// double precision, for light from air onto a medium of index n.
double fresnel_angle_form(double theta_i, double n) {
  if (theta_i == 0.0) return std::pow((n - 1.0) / (n + 1.0), 2);
  const double theta_t = std::asin(std::sin(theta_i) / n);
  const double r_s = -std::sin(theta_i - theta_t) / std::sin(theta_i + theta_t);
  const double r_p = std::tan(theta_i - theta_t) / std::tan(theta_i + theta_t);
  return 0.5 * (r_s * r_s + r_p * r_p);
}

// ∫ f(view, l) μ_l dω_l over the upper hemisphere on a (θ, φ) grid, the
// directional-hemispherical reflectance of the glint BRDF, integrated over
// directions (not slopes, as water_sky_reflectance does). The view lies in
// the upwind plane, so the integrand is symmetric in φ.
double brdf_directional_reflectance(const ph::WaterParams& w, const glm::dvec3& view, int theta_steps) {
  const int phi_steps = 2 * theta_steps;
  const double d_theta = 0.5 * M_PI / theta_steps;
  const double d_phi = M_PI / phi_steps;
  double sum = 0.0;
  for (int i = 0; i < theta_steps; ++i) {
    const double theta = (i + 0.5) * d_theta;
    for (int j = 0; j < phi_steps; ++j) {
      const glm::dvec3 l = direction(theta, (j + 0.5) * d_phi);
      const glm::vec3 f = ph::water_glint_brdf(w, kNormal, kUpwind, glm::vec3(view), glm::vec3(l));
      sum += double(f.x) * std::cos(theta) * std::sin(theta);
    }
  }
  return 2.0 * sum * d_theta * d_phi;
}

TEST(WaterFresnel, MatchesTheAngleFormsAndLimits) {
  double worst = 0.0;
  for (double n : {1.333, 1.34, 1.5}) {
    for (int degrees = 0; degrees < 90; ++degrees) {
      const double theta = radians(degrees);
      const double exact = fresnel_angle_form(theta, n);
      const double shared = ph::fresnel_reflectance(float(std::cos(theta)), float(n));
      worst = std::max(worst, std::abs(shared - exact));
      EXPECT_NEAR(shared, exact, 2e-6) << "n " << n << ", " << degrees << " deg";
    }
    // Grazing incidence reflects everything; the p wave vanishes at
    // Brewster's angle, leaving r_s² / 2.
    EXPECT_NEAR(ph::fresnel_reflectance(0.0f, float(n)), 1.0f, 1e-6);
    const double brewster = std::atan(n);
    const double theta_t = std::asin(std::sin(brewster) / n);
    const double r_s = std::sin(brewster - theta_t) / std::sin(brewster + theta_t);
    EXPECT_NEAR(ph::fresnel_reflectance(float(std::cos(brewster)), float(n)), 0.5 * r_s * r_s, 1e-6);
  }
  // From inside the water: total internal reflection beyond the critical
  // angle asin(1 / 1.333) = 48.6°, and the same reflectance as from air for
  // the matching pair of angles (reciprocity of the interface).
  EXPECT_EQ(ph::fresnel_reflectance(float(std::cos(radians(50.0))), 1.0f / 1.333f), 1.0f);
  EXPECT_LT(ph::fresnel_reflectance(float(std::cos(radians(47.0))), 1.0f / 1.333f), 1.0f);
  const double theta_air = radians(60.0);
  const double theta_water = std::asin(std::sin(theta_air) / 1.333);
  EXPECT_NEAR(ph::fresnel_reflectance(float(std::cos(theta_water)), 1.0f / 1.333f),
              ph::fresnel_reflectance(float(std::cos(theta_air)), 1.333f), 2e-6);
  std::printf("Fresnel: largest difference from the angle forms %.2e\n", worst);
}

// The flat surface under a uniform sky: the bi-hemispherical reflectance
// 2 ∫ F(μ) μ dμ, about 0.066 for n = 1.333, computed three ways: the
// textbook Fresnel in double precision, diffuse_fresnel_reflectance, and
// the reflected-sky quadrature of a surface without slopes (whose
// directional-hemispherical reflectance must be F(μ_v) itself), averaged
// over the view directions.
TEST(WaterEnergy, FlatSurfaceReflectsTheIntegratedFresnel) {
  const double n = 1.333;
  constexpr int kNodes = 20000;
  double textbook = 0.0;
  for (int i = 0; i < kNodes; ++i) {
    const double x = (i + 0.5) / kNodes;  // μ², so that 2 μ dμ = dx
    textbook += fresnel_angle_form(std::acos(std::sqrt(x)), n);
  }
  textbook /= kNodes;
  const double shared = ph::diffuse_fresnel_reflectance(n);

  const ph::WaterParams flat = water_with(float(n), glm::vec2(0.0f));
  double quadrature = 0.0;
  double worst_directional = 0.0;
  constexpr int kViews = 2000;
  for (int i = 0; i < kViews; ++i) {
    const double x = (i + 0.5) / kViews;
    const double mu = std::sqrt(x);
    const glm::vec3 view(glm::dvec3(std::sqrt(1.0 - x), 0.0, mu));
    glm::vec3 mean_direction;
    const glm::vec3 r = ph::water_sky_reflectance(flat, kNormal, kUpwind, view, mean_direction);
    const double expected = fresnel_angle_form(std::acos(mu), n);
    worst_directional = std::max(worst_directional, std::abs(double(r.x) - expected) / expected);
    // The mirror direction.
    EXPECT_NEAR(mean_direction.z, view.z, 1e-5);
    EXPECT_NEAR(mean_direction.x, -view.x, 1e-5);
    quadrature += double(r.x);
  }
  quadrature /= kViews;
  std::printf("flat water, n = 1.333: bi-hemispherical reflectance %.5f (textbook), %.5f (shared), %.5f "
              "(sky quadrature); directional vs F: worst %.2e relative\n",
              textbook, shared, quadrature, worst_directional);
  EXPECT_NEAR(textbook, 0.066, 0.01 * 0.066);
  EXPECT_NEAR(shared, textbook, 1e-3 * textbook);
  EXPECT_NEAR(quadrature, textbook, 0.01 * textbook);
  EXPECT_LT(worst_directional, 1e-4);

  // From the water's side: the diffuse internal reflectance, which the
  // reciprocity of the interface ties to the external one,
  // r_i = 1 - (1 - r_e) / n².
  const double internal = ph::diffuse_fresnel_reflectance(1.0 / n);
  std::printf("diffuse internal reflectance %.5f, 1 - (1 - r_e) / n^2 = %.5f\n", internal,
              1.0 - (1.0 - textbook) / (n * n));
  EXPECT_NEAR(internal, 1.0 - (1.0 - textbook) / (n * n), 1e-3);
}

// Cox & Munk 1954's clean-surface fits: σ_u² = 3.16e-3 U, σ_c² = 0.003 +
// 1.92e-3 U, and the isotropic σ² = 0.003 + 5.12e-3 U; the slope density
// integrates to 1.
TEST(WaterGlint, SlopesFollowCoxAndMunk) {
  const glm::vec2 v = ph::cox_munk_slope_variance(10.0f);
  EXPECT_NEAR(v.x, 0.0316f, 1e-6f);
  EXPECT_NEAR(v.y, 0.0222f, 1e-6f);
  const glm::vec2 iso = ph::cox_munk_isotropic_slope_variance(10.0f);
  EXPECT_NEAR(iso.x + iso.y, 0.0542f, 1e-6f);
  EXPECT_EQ(iso.x, iso.y);
  // Calm water keeps a finite upwind variance.
  EXPECT_GT(ph::cox_munk_slope_variance(0.0f).x, 0.0f);
  double total = 0.0;
  constexpr int kGrid = 400;
  const double hx = 16.0 * std::sqrt(double(v.x)) / kGrid, hy = 16.0 * std::sqrt(double(v.y)) / kGrid;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j)
      total += ph::water_slope_pdf(glm::vec2(float((i + 0.5) * hx - 8.0 * std::sqrt(double(v.x))),
                                             float((j + 0.5) * hy - 8.0 * std::sqrt(double(v.y)))),
                                   v);
  EXPECT_NEAR(total * hx * hy, 1.0, 1e-4);
}

TEST(WaterGlint, BrdfIsReciprocalAndPositive) {
  std::mt19937 rng(34);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const ph::WaterParams w = water_with(1.34f, ph::cox_munk_slope_variance(7.0f));
  double worst = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 a(direction(std::acos(uniform(rng)), 2.0 * M_PI * uniform(rng)));
    const glm::vec3 b(direction(std::acos(uniform(rng)), 2.0 * M_PI * uniform(rng)));
    const float ab = ph::water_glint_brdf(w, kNormal, kUpwind, a, b).x;
    const float ba = ph::water_glint_brdf(w, kNormal, kUpwind, b, a).x;
    ASSERT_TRUE(std::isfinite(ab));
    ASSERT_GE(ab, 0.0f);
    if (ab > 1e-6f) worst = std::max(worst, double(std::abs(ab - ba) / ab));
  }
  std::printf("glint BRDF reciprocity: worst relative difference %.2e over 2000 pairs\n", worst);
  EXPECT_LT(worst, 1e-5);
}

// Smith's Λ for Gaussian slopes against its defining integral
// Λ = (1 / c) ∫_c^∞ (q - c) p(q) dq, c = cot θ (Smith 1967), by Simpson's
// rule; and the constraint that makes G₁ = 1 / (1 + Λ) Smith's masking
// function: the visible facets' area projected towards any view equals the
// mean surface's, ∫ p(s) G₁ max(0, view · h) / (μ_v μ_h) d²s = 1 (Heitz
// 2014), on a grid of slopes.
TEST(WaterGlint, SmithLambdaMatchesItsIntegralAndProjectedArea) {
  double worst = 0.0;
  for (double variance : {0.005, 0.03, 0.1}) {
    const double sigma = std::sqrt(variance);
    for (double degrees : {20.0, 45.0, 60.0, 75.0, 85.0, 89.0}) {
      const double c = 1.0 / std::tan(radians(degrees));
      constexpr int kSteps = 4000;
      const double h = 14.0 * sigma / kSteps;
      double sum = 0.0;
      for (int i = 0; i <= kSteps; ++i) {
        const double q = c + i * h;
        const double value = (q - c) * std::exp(-q * q / (2.0 * variance)) / std::sqrt(2.0 * M_PI * variance);
        sum += value * (i == 0 || i == kSteps ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0));
      }
      const double integral = sum * h / 3.0 / c;
      const double shared = ph::water_smith_lambda(float(std::cos(radians(degrees))), float(variance));
      worst = std::max(worst, std::abs(shared - integral));
      EXPECT_NEAR(shared, integral, 2e-6 + 2e-4 * integral) << "variance " << variance << ", " << degrees << " deg";
    }
  }
  std::printf("Smith lambda: largest difference from its integral %.2e\n", worst);

  const glm::vec2 variance = ph::cox_munk_slope_variance(10.0f);
  for (double degrees : {0.0, 40.0, 70.0, 85.0}) {
    for (double azimuth : {0.0, 50.0}) {
      const glm::dvec3 view = direction(radians(degrees), radians(azimuth));
      const float lambda = ph::water_smith_lambda(
          float(view.z), ph::water_directional_slope_variance(kNormal, kUpwind, variance, glm::vec3(view)));
      const double g1 = 1.0 / (1.0 + lambda);
      constexpr int kGrid = 600;
      const double sx = 8.0 * std::sqrt(double(variance.x)), sy = 8.0 * std::sqrt(double(variance.y));
      const double dx = 2.0 * sx / kGrid, dy = 2.0 * sy / kGrid;
      double area = 0.0;
      for (int i = 0; i < kGrid; ++i) {
        for (int j = 0; j < kGrid; ++j) {
          const glm::dvec2 s(-sx + (i + 0.5) * dx, -sy + (j + 0.5) * dy);
          const glm::dvec3 normal_h = glm::normalize(glm::dvec3(-s.x, -s.y, 1.0));
          const double v_h = glm::dot(view, normal_h);
          if (v_h <= 0.0) continue;
          area += ph::water_slope_pdf(glm::vec2(s), variance) * v_h / (view.z * normal_h.z);
        }
      }
      area *= g1 * dx * dy;
      EXPECT_NEAR(area, 1.0, 2e-3) << degrees << " deg, azimuth " << azimuth;
      if (azimuth == 0.0) std::printf("visible projected area at %2.0f deg: %.5f (G1 %.4f)\n", degrees, area, g1);
    }
  }
}

// The rough surface: its directional-hemispherical reflectance integrated
// over directions is at most 1, close to the flat surface's Fresnel for a
// high sun and a light wind, and the reflected-sky quadrature (16 nodes over
// the slopes) gives the same reflectance under a uniform sky, to 1 %.
TEST(WaterEnergy, RoughSurfaceReflectanceIsBoundedAndMatchesTheSkyQuadrature) {
  struct Case {
    float wind;
    double view_deg;
    double quadrature_tolerance;
  };
  const Case cases[] = {{2.0f, 0.0, 0.01},  {5.0f, 0.0, 0.01},   {5.0f, 30.0, 0.01},  {5.0f, 60.0, 0.01},
                        {10.0f, 60.0, 0.01}, {10.0f, 80.0, 0.01}, {15.0f, 87.0, 0.01}, {25.0f, 45.0, 0.01}};
  for (const Case& c : cases) {
    const ph::WaterParams w = water_with(1.34f, ph::cox_munk_slope_variance(c.wind));
    const glm::dvec3 view = direction(radians(c.view_deg), 0.0);
    const double integrated = brdf_directional_reflectance(w, view, 500);
    glm::vec3 mean_direction;
    const double quadrature = ph::water_sky_reflectance(w, kNormal, kUpwind, glm::vec3(view), mean_direction).x;
    const double flat = fresnel_angle_form(radians(c.view_deg), 1.34);
    std::printf("wind %4.1f m/s, view %2.0f deg: reflectance %.5f (directions), %.5f (slope quadrature), "
                "flat Fresnel %.5f\n",
                double(c.wind), c.view_deg, integrated, quadrature, flat);
    EXPECT_LE(integrated, 1.0);
    EXPECT_GT(integrated, 0.0);
    EXPECT_NEAR(quadrature, integrated, c.quadrature_tolerance * integrated);
    if (c.wind <= 2.0f && c.view_deg <= 30.0) {
      EXPECT_NEAR(integrated, flat, 0.03 * flat);
    }
  }
  // Everywhere: at most 1, from calm to a gale and down to grazing views.
  for (float wind : {0.0f, 1.0f, 5.0f, 15.0f, 30.0f, 50.0f}) {
    const ph::WaterParams w = water_with(1.34f, ph::cox_munk_slope_variance(wind));
    for (double degrees = 0.0; degrees < 90.0; degrees += 2.5) {
      glm::vec3 mean_direction;
      const glm::vec3 r = ph::water_sky_reflectance(w, kNormal, kUpwind, glm::vec3(direction(radians(degrees), 1.0)),
                                                    mean_direction);
      EXPECT_TRUE(r.x >= 0.0f && r.x <= 1.0f) << "wind " << wind << ", " << degrees << " deg: " << r.x;
      EXPECT_GT(mean_direction.z, 0.0f);
      EXPECT_NEAR(glm::length(mean_direction), 1.0f, 1e-5f);
    }
  }
}

// The glint BRDF against a Monte Carlo over Cox & Munk facets, which knows
// nothing of microfacet BRDFs: slopes drawn from the Gaussian, each facet
// (of area 1 / μ_h per unit mean area) lit with irradiance E (sun · h) and
// mirroring F (sun · h) of it; the power that lands in a cone of half-angle
// 2.5° around a view direction, over the cone's ∫ μ dω, is the mean radiance
// there, E_sun-normalised. It ignores which facets hide others, so it is
// compared with the BRDF over G₂ (tested apart above), averaged over the
// same cone.
TEST(WaterGlint, BrdfMatchesMonteCarloOverCoxMunkFacets) {
  const float wind = 5.0f;
  const ph::WaterParams w = water_with(1.34f, ph::cox_munk_slope_variance(wind));
  const glm::dvec3 sun = direction(radians(30.0), radians(180.0));
  const double cone = radians(2.5);
  // The mirror direction of the sun and views around it, up/crosswind.
  const std::vector<glm::dvec3> views = {
      direction(radians(30.0), 0.0),          direction(radians(40.0), 0.0),          direction(radians(20.0), 0.0),
      direction(radians(30.0), radians(15.0)), direction(radians(45.0), radians(20.0)), direction(radians(15.0), 0.0)};

  // The prediction: ∫_cone f/G₂ μ dω / ∫_cone μ dω by the midpoint rule in
  // polar coordinates around each view.
  std::vector<double> predicted;
  std::vector<double> cone_mu_solid_angle;
  for (const glm::dvec3& v : views) {
    const glm::dvec3 t1 = glm::normalize(glm::cross(v, glm::dvec3(0.0, 0.0, 1.0)));
    const glm::dvec3 t2 = glm::cross(v, t1);
    double f_sum = 0.0, mu_sum = 0.0;
    constexpr int kRadial = 40, kAround = 80;
    for (int i = 0; i < kRadial; ++i) {
      const double a = (i + 0.5) * cone / kRadial;
      for (int j = 0; j < kAround; ++j) {
        const double b = (j + 0.5) * 2.0 * M_PI / kAround;
        const glm::dvec3 d = std::cos(a) * v + std::sin(a) * (std::cos(b) * t1 + std::sin(b) * t2);
        const double weight = std::sin(a) * (cone / kRadial) * (2.0 * M_PI / kAround);
        const glm::vec3 df(d), sf(sun);
        const double g = ph::water_masking_shadowing(kNormal, kUpwind, w.slope_variance, df, sf);
        const double f = ph::water_glint_brdf(w, kNormal, kUpwind, df, sf).x / g;
        f_sum += f * d.z * weight;
        mu_sum += d.z * weight;
      }
    }
    predicted.push_back(f_sum * sun.z / mu_sum);
    cone_mu_solid_angle.push_back(mu_sum);
  }

  std::mt19937_64 rng(1954);
  std::normal_distribution<double> up(0.0, std::sqrt(double(w.slope_variance.x)));
  std::normal_distribution<double> cross(0.0, std::sqrt(double(w.slope_variance.y)));
  const double cos_cone = std::cos(cone);
  constexpr long kSamples = 4000000;
  std::vector<double> power(views.size(), 0.0);
  std::vector<long> hits(views.size(), 0);
  for (long s = 0; s < kSamples; ++s) {
    const glm::dvec3 h = glm::normalize(glm::dvec3(-up(rng), -cross(rng), 1.0));
    const double s_h = glm::dot(sun, h);
    if (s_h <= 0.0) continue;
    const glm::dvec3 r = 2.0 * s_h * h - sun;
    for (size_t k = 0; k < views.size(); ++k) {
      if (glm::dot(r, views[k]) < cos_cone) continue;
      power[k] += double(ph::fresnel_reflectance(float(s_h), 1.34f)) * s_h / h.z;
      ++hits[k];
    }
  }
  double worst = 0.0;
  for (size_t k = 0; k < views.size(); ++k) {
    const double monte_carlo = power[k] / double(kSamples) / cone_mu_solid_angle[k];
    const double error = std::abs(monte_carlo - predicted[k]) / predicted[k];
    worst = std::max(worst, error);
    std::printf("glint, view %zu (zenith %.0f deg): BRDF x mu_s / G2 %.5f, Monte Carlo %.5f (%ld facets, "
                "1/sqrt %.3f), difference %.2f %%\n",
                k, std::acos(views[k].z) * 180.0 / M_PI, predicted[k], monte_carlo, hits[k],
                1.0 / std::sqrt(double(hits[k])), 100.0 * error);
    EXPECT_GT(hits[k], 5000);
    EXPECT_LT(error, 0.02);
  }
  std::printf("glint against the Monte Carlo: worst %.2f %%\n", 100.0 * worst);
}

// The seabed's light through the column: the function against the stated
// law in double precision at several depths and wavelengths, the falloff
// between depths exactly e^{-(K_d + K_u) ΔH}, and the limits (no water:
// the seabed's own ρ_b / π; deep water: the column's r_rs^dp).
TEST(WaterColumn, SeabedFallsOffWithDepthAsTheLaw) {
  const ph::Water water;  // default: 0.1 mg m^-3, 35 PSU, 20 °C
  const std::array<std::array<double, 3>, 3> triples = {
      {{680.0, 550.0, 440.0}, {400.0, 500.0, 600.0}, {450.0, 575.0, 700.0}}};
  const glm::vec3 albedo(0.35f, 0.3f, 0.25f);
  const float mu_sun_air = float(std::cos(radians(40.0)));
  const float mu_view_air = float(std::cos(radians(20.0)));
  double worst = 0.0, worst_ratio = 0.0;
  for (const auto& wavelengths : triples) {
    const ph::WaterParams w = ph::make_water_params(water, wavelengths);
    const glm::vec3 mu_down = ph::water_refracted_cosine(mu_sun_air, w.refractive_index);
    const glm::vec3 mu_up = ph::water_refracted_cosine(mu_view_air, w.refractive_index);
    for (double depth : {0.0, 0.5, 2.0, 5.0, 10.0, 30.0, 100.0}) {
      const glm::vec3 t = ph::water_seabed_transmittance(w, mu_down, mu_up, float(depth));
      const glm::vec3 r = ph::water_subsurface_reflectance(w, mu_down, mu_up, float(depth), albedo);
      const glm::vec3 r_dark = ph::water_subsurface_reflectance(w, mu_down, mu_up, float(depth), glm::vec3(0.0f));
      for (int c = 0; c < 3; ++c) {
        const double kappa = double(w.absorption[c]) + double(w.backscattering[c]);
        const double u = double(w.backscattering[c]) / kappa;
        const double k_d = kappa / double(mu_down[c]);
        const double k_u_bottom = kappa * 1.04 * std::sqrt(1.0 + 5.4 * u) / double(mu_up[c]);
        const double k_u_column = kappa * 1.03 * std::sqrt(1.0 + 2.4 * u) / double(mu_up[c]);
        const double law = std::exp(-(k_d + k_u_bottom) * depth);
        const double deep = (0.084 + 0.170 * u) * u;
        const double expected = deep * (1.0 - std::exp(-(k_d + k_u_column) * depth)) + double(albedo[c]) / M_PI * law;
        const double seabed = double(r[c]) - double(r_dark[c]);
        if (law > 1e-20) {
          worst = std::max(worst, std::abs(double(t[c]) - law) / law);
          EXPECT_NEAR(t[c], law, 0.01 * law) << wavelengths[size_t(c)] << " nm, " << depth << " m";
          // The seabed's share alone: ρ_b / π times the law (to float
          // rounding of the sum, 1e-6 of r).
          EXPECT_NEAR(seabed, double(albedo[c]) / M_PI * law, 0.01 * double(albedo[c]) / M_PI * law + 1e-6 * r[c])
              << wavelengths[size_t(c)] << " nm, " << depth << " m";
        }
        EXPECT_NEAR(r[c], expected, 0.01 * expected) << wavelengths[size_t(c)] << " nm, " << depth << " m";
        // From one depth to the next, the seabed's light falls by
        // e^{-(K_d + K_u) ΔH}.
        const glm::vec3 t_deeper = ph::water_seabed_transmittance(w, mu_down, mu_up, float(depth + 1.0));
        if (t[c] > 1e-30f) {
          const double ratio = double(t_deeper[c]) / double(t[c]) / std::exp(-(k_d + k_u_bottom));
          worst_ratio = std::max(worst_ratio, std::abs(ratio - 1.0));
          EXPECT_NEAR(ratio, 1.0, 0.01);
        }
      }
      if (depth == 0.0) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(r[c], albedo[c] / M_PI, 1e-6);
      }
    }
    // Deep water: only the column.
    const glm::vec3 deep = ph::water_subsurface_reflectance(w, mu_down, mu_up, INFINITY, albedo);
    for (int c = 0; c < 3; ++c) {
      const double u = double(w.backscattering[c]) / (double(w.absorption[c]) + double(w.backscattering[c]));
      EXPECT_NEAR(deep[c], (0.084 + 0.170 * u) * u, 1e-6 * deep[c]);
    }
  }
  std::printf("seabed: largest relative difference from the law %.2e; per-metre falloff %.2e\n", worst, worst_ratio);
}

// The mean cosine of the sky's light below the surface: the closed form
// (uniform radiance over the critical cone) against the integral with the
// actual transmittance 1 - F, ∫ (1 - F) cos θ_w dΩ_w / ∫ (1 - F) dΩ_w.
TEST(WaterColumn, DiffuseMeanCosineMatchesTheTransmittedField) {
  for (double n : {1.333, 1.34}) {
    const double critical = std::asin(1.0 / n);
    constexpr int kSteps = 20000;
    double num = 0.0, den = 0.0;
    for (int i = 0; i < kSteps; ++i) {
      const double theta_w = (i + 0.5) * critical / kSteps;
      const double theta_air = std::asin(std::min(1.0, n * std::sin(theta_w)));
      const double t = 1.0 - fresnel_angle_form(theta_air, n);
      num += t * std::cos(theta_w) * std::sin(theta_w);
      den += t * std::sin(theta_w);
    }
    const double integral = num / den;
    const double closed = ph::water_diffuse_mean_cosine(glm::vec3(float(n))).x;
    std::printf("n %.3f: mean cosine below a uniform sky %.4f (closed form), %.4f (with 1 - F)\n", n, closed, integral);
    EXPECT_NEAR(closed, integral, 0.03 * integral);
  }
}

// Deep clear water is dark blue; a sandy seabed 2 m down makes the water
// bright and green-yellow; at 400 m the seabed no longer shows (at 100 m the
// clearest water still passes 5 % of the blue to the seabed and back).
TEST(WaterColumn, DeepWaterIsBlueAndShallowWaterShowsTheSeabed) {
  ph::Water water;
  water.chlorophyll_mg_m3 = 0.05;
  const ph::WaterParams w = ph::make_water_params(water, {680.0, 550.0, 440.0});
  const glm::vec3 sun(direction(radians(30.0), 0.0));
  const glm::vec3 view(direction(radians(20.0), radians(180.0)));
  const glm::vec3 e_sun(1.0f), e_sky(0.2f);
  const glm::vec3 sand(0.3f);
  const glm::vec3 deep = ph::water_leaving_radiance(w, kNormal, view, sun, e_sun, e_sky, INFINITY, sand);
  const glm::vec3 shallow = ph::water_leaving_radiance(w, kNormal, view, sun, e_sun, e_sky, 2.0f, sand);
  const glm::vec3 very_deep = ph::water_leaving_radiance(w, kNormal, view, sun, e_sun, e_sky, 400.0f, sand);
  std::printf("water-leaving radiance / E (680, 550, 440 nm): deep %.2e %.2e %.2e; 2 m over sand %.2e %.2e %.2e\n",
              deep.x, deep.y, deep.z, shallow.x, shallow.y, shallow.z);
  EXPECT_GT(deep.z, deep.y);
  EXPECT_GT(deep.y, deep.x);
  EXPECT_GT(deep.z, 10.0f * deep.x);
  EXPECT_GT(shallow.y, 3.0f * deep.y);
  EXPECT_GT(shallow.y, shallow.z * 0.8f);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(very_deep[c], deep[c], 0.01f * deep[c]);
  // Night: no sun, no sky, no light from below.
  const glm::vec3 dark =
      ph::water_leaving_radiance(w, kNormal, view, -sun, glm::vec3(0.0f), glm::vec3(0.0f), 2.0f, sand);
  EXPECT_EQ(dark, glm::vec3(0.0f));
}

TEST(WaterSpectra, RefractiveIndexAndAbsorptionFollowTheirSources) {
  // Quan & Fry 1995 at the sodium D line, 20 °C: pure water 1.3330 (the
  // standard n_D of water), seawater of 35 PSU about 0.0064 more.
  EXPECT_NEAR(ph::water_refractive_index(589.3f, 0.0f, 20.0f), 1.3330f, 2e-4f);
  EXPECT_NEAR(ph::water_refractive_index(589.3f, 35.0f, 20.0f) - ph::water_refractive_index(589.3f, 0.0f, 20.0f),
              0.0064f, 3e-4f);
  float previous = 2.0f;
  for (float l = 400.0f; l <= 700.0f; l += 10.0f) {
    const float n = ph::water_refractive_index(l, 0.0f, 20.0f);
    EXPECT_LT(n, previous) << l << " nm";  // normal dispersion
    EXPECT_TRUE(n > 1.329f && n < 1.344f) << l << " nm: " << n;
    const float sea = ph::water_refractive_index(l, 35.0f, 20.0f);
    EXPECT_TRUE(sea > 1.335f && sea < 1.351f) << l << " nm: " << sea;
    previous = n;
  }
  std::printf("n (pure water, 20 C): 400 nm %.5f, 550 nm %.5f, 700 nm %.5f; seawater 35 PSU: %.5f %.5f %.5f\n",
              ph::water_refractive_index(400.0f, 0.0f, 20.0f), ph::water_refractive_index(550.0f, 0.0f, 20.0f),
              ph::water_refractive_index(700.0f, 0.0f, 20.0f), ph::water_refractive_index(400.0f, 35.0f, 20.0f),
              ph::water_refractive_index(550.0f, 35.0f, 20.0f), ph::water_refractive_index(700.0f, 35.0f, 20.0f));

  // Pope & Fry 1997's values (m^-1), and linear between the table's rows.
  EXPECT_DOUBLE_EQ(ph::pure_water_absorption(380.0), 0.01137);
  EXPECT_DOUBLE_EQ(ph::pure_water_absorption(440.0), 0.00635);
  EXPECT_DOUBLE_EQ(ph::pure_water_absorption(550.0), 0.0565);
  EXPECT_DOUBLE_EQ(ph::pure_water_absorption(680.0), 0.465);
  EXPECT_DOUBLE_EQ(ph::pure_water_absorption(700.0), 0.624);
  EXPECT_NEAR(ph::pure_water_absorption(417.5), 0.5 * (0.00444 + 0.00454), 1e-12);
  // Smith & Baker 1981 below 380 nm, rising into the ultraviolet.
  EXPECT_DOUBLE_EQ(ph::pure_water_absorption(360.0), 0.0379);
  // Molecular scattering: seawater's 0.0029 m^-1 at 500 nm (Smith & Baker
  // 1981), pure water's 1.30 times less (Morel 1974), the λ^-4.32 law.
  EXPECT_NEAR(ph::water_scattering(500.0, 37.0), 0.00290269, 1e-8);
  EXPECT_NEAR(ph::water_scattering(500.0, 0.0), 0.00290269 / 1.30, 1e-8);
  EXPECT_NEAR(ph::water_scattering(400.0, 37.0) / ph::water_scattering(500.0, 37.0), std::pow(0.8, -4.32),
              0.02 * std::pow(0.8, -4.32));
  // Bricaud et al. 1998: a_ph(440) = 0.0378 Chl^0.627.
  EXPECT_NEAR(ph::phytoplankton_absorption(440.0, 1.0), 0.037824, 1e-9);
  EXPECT_NEAR(ph::phytoplankton_absorption(440.0, 10.0), 0.037824 * std::pow(10.0, 0.626633), 1e-9);
  EXPECT_EQ(ph::phytoplankton_absorption(440.0, 0.0), 0.0);
  // The red peak of chlorophyll a.
  EXPECT_GT(ph::phytoplankton_absorption(676.0, 1.0), 2.0 * ph::phytoplankton_absorption(600.0, 1.0));
  // Particles: b_p(550) = 0.416 Chl^0.766 (Loisel & Morel 1998).
  EXPECT_NEAR(ph::particle_scattering(550.0, 1.0), 0.416, 1e-12);
  EXPECT_NEAR(ph::particle_backscattering(550.0, 1.0), 0.416 * 0.007, 1e-12);
}

TEST(WaterParameters, BadInputGetsAClearError) {
  auto throws_with = [](const ph::Water& water, const std::string& words) {
    try {
      ph::validate_water(water);
      ADD_FAILURE() << "no error for " << words;
    } catch (const atmos::Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(words), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  };
  ph::Water water;
  EXPECT_NO_THROW(ph::validate_water(water));
  water.wind_speed_m_s = -1.0;
  throws_with(water, "wind speed");
  water.wind_speed_m_s = NAN;
  throws_with(water, "wind speed");
  water = ph::Water{};
  water.chlorophyll_mg_m3 = 30.0;
  throws_with(water, "chlorophyll");
  water.chlorophyll_mg_m3 = -0.1;
  throws_with(water, "chlorophyll");
  water = ph::Water{};
  water.salinity_psu = 50.0;
  throws_with(water, "salinity");
  water = ph::Water{};
  water.temperature_c = -5.0;
  throws_with(water, "temperature");
  water = ph::Water{};
  water.cdom_absorption_440_per_m = INFINITY;
  throws_with(water, "CDOM");
  water = ph::Water{};
  water.wind_speed_m_s = -3.0;
  EXPECT_THROW(ph::make_water_params(water, {680.0, 550.0, 440.0}), atmos::Error);
  EXPECT_THROW(ph::make_water_params(ph::Water{}, {680.0, 550.0, 1000.0}), atmos::Error);

  EXPECT_NO_THROW(ph::validate_seabed(0.0, glm::vec3(0.3f)));
  EXPECT_NO_THROW(ph::validate_seabed(INFINITY, glm::vec3(0.3f)));
  EXPECT_THROW(ph::validate_seabed(-1.0, glm::vec3(0.3f)), atmos::Error);
  EXPECT_THROW(ph::validate_seabed(NAN, glm::vec3(0.3f)), atmos::Error);
  EXPECT_THROW(ph::validate_seabed(5.0, glm::vec3(0.3f, 1.5f, 0.3f)), atmos::Error);
  try {
    ph::validate_seabed(-2.0, glm::vec3(0.3f));
  } catch (const atmos::Error& e) {
    EXPECT_NE(std::string(e.what()).find("depth"), std::string::npos) << e.what();
  }
}

// The GLSL: water.glsl compiled with definitions.glsl and the subset macros
// in a full-screen fragment shader on the GPU, evaluating the functions at
// the same inputs as their C++ twins.
// --- At the atmosphere's working wavelengths (water_spectral_radiance) ---------

atmos::Atmosphere earth_at(int wavelengths) {
  atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  if (wavelengths != 3) earth.wavelengths_nm = atmos::spectral_wavelengths(wavelengths);
  return earth;
}

// The sun's irradiance at wavelength λ after a vertical path through a
// Rayleigh atmosphere of optical depth 0.1 at 550 nm (a smooth stand-in for
// the tables' transmittance), per triple of `spectrum`'s wavelengths.
double test_sun(const atmos::Atmosphere& a, double l) {
  return a.solar_irradiance.at(l) * std::exp(-0.1 * std::pow(550.0 / l, 4.0));
}

// With three working wavelengths the channels are the wavelengths: one
// triple, the identity both ways, the water at those wavelengths, and the
// spectral sum is water_leaving_radiance and F g E_sun themselves.
TEST(WaterSpectral, ThreeWavelengthsAreTheChannels) {
  const atmos::Atmosphere earth = earth_at(3);
  ph::Water water;
  water.chlorophyll_mg_m3 = 0.5;
  const std::unique_ptr<ph::WaterSpectrum> s = ph::make_water_spectrum(water, earth);
  ASSERT_EQ(s->count, 1);
  const ph::WaterParams w = ph::make_water_params(water, ph::water_channel_wavelengths(earth));
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) {
      EXPECT_EQ(s->to_channels[0][c][r], c == r ? 1.0f : 0.0f);
      EXPECT_EQ(s->from_channels[0][c][r], c == r ? 1.0f : 0.0f);
    }
  EXPECT_EQ(s->set[0].absorption, w.absorption);
  EXPECT_EQ(s->set[0].refractive_index, w.refractive_index);
  const glm::vec3 view = glm::vec3(direction(radians(40.0), 0.3)), sun = glm::vec3(direction(radians(30.0), 2.9));
  const glm::vec3 e_sun(1.6f, 1.8f, 1.9f), e_sky(0.2f, 0.3f, 0.5f), albedo(0.4f, 0.35f, 0.3f);
  ph::vec3 sun_sets[SPECTRAL_SET_CAPACITY] = {};
  sun_sets[0] = e_sun;
  for (float depth : {0.5f, 4.0f, 1e4f}) {
    glm::vec3 glint;
    const glm::vec3 below = ph::water_spectral_radiance(*s, sun_sets, e_sky, 0.7f, 0.9f, kNormal, view, sun, depth,
                                                        albedo, glint);
    const glm::vec3 expected = ph::water_leaving_radiance(w, kNormal, view, sun, e_sun, e_sky, depth, albedo);
    const glm::vec3 expected_glint = ph::fresnel_reflectance(0.9f, w.refractive_index) * 0.7f * e_sun;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(below[c], expected[c], 2e-6 * expected[c]) << depth << " " << c;
      EXPECT_NEAR(glint[c], expected_glint[c], 2e-6 * expected_glint[c]) << c;
    }
  }
}

// At 14 working wavelengths (five triples, the last padded), the spectral
// sum against its definition evaluated wavelength by wavelength in double:
// the water's optics at each λ_j alone, E_sky(λ_j) = E_0(λ_j) times the
// channels' sky-to-sun ratio interpolated linearly in ln λ between 680, 550
// and 440 nm, the seabed's albedo likewise, and the channels
// Σ_j w_j L(λ_j) / 683 with the atmosphere's own weights w_j
// (spectral_to_srgb_weights, the CIE 1931 functions to linear sRGB).
TEST(WaterSpectral, EveryWavelengthIsConvertedAsTheAtmosphere) {
  const atmos::Atmosphere earth = earth_at(14);
  ph::Water water;
  water.chlorophyll_mg_m3 = 1.0;
  const std::unique_ptr<ph::WaterSpectrum> s = ph::make_water_spectrum(water, earth);
  ASSERT_EQ(s->count, 5);
  const std::vector<double>& lambda = earth.wavelengths_nm;
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(lambda);
  ph::vec3 sun_sets[SPECTRAL_SET_CAPACITY] = {};
  glm::dvec3 solar(0.0);
  for (size_t j = 0; j < lambda.size(); ++j) {
    sun_sets[j / 3][int(j % 3)] = float(test_sun(earth, lambda[j]));
    solar += weights[j] * earth.solar_irradiance.at(lambda[j]) / atmos::kMaxLuminousEfficacy;
  }
  for (int i = int(lambda.size()); i < 15; ++i) sun_sets[4][i % 3] = sun_sets[4][1];  // the padding's
  const glm::dvec3 sky = 0.12 * solar * glm::dvec3(0.7, 0.9, 1.3);
  const glm::dvec3 albedo(0.45, 0.3, 0.15);
  // Linear in ln λ between the channels' 680, 550, 440 nm, held beyond.
  const auto interpolate = [](double l, const glm::dvec3& v) {
    if (l >= 680.0) return v.x;
    if (l <= 440.0) return v.z;
    if (l >= 550.0) return v.y + (v.x - v.y) * std::log(l / 550.0) / std::log(680.0 / 550.0);
    return v.z + (v.y - v.z) * std::log(l / 440.0) / std::log(550.0 / 440.0);
  };
  const glm::vec3 view = glm::vec3(direction(radians(25.0), 0.3)), sun = glm::vec3(direction(radians(35.0), 2.9));
  for (float depth : {0.5f, 3.0f, 30.0f, 1e4f}) {
    glm::vec3 glint;
    const glm::vec3 below = ph::water_spectral_radiance(*s, sun_sets, glm::vec3(sky), 0.6f, 0.8f, kNormal, view, sun,
                                                        depth, glm::vec3(albedo), glint);
    glm::dvec3 expected(0.0), expected_glint(0.0);
    for (size_t j = 0; j < lambda.size(); ++j) {
      const double l = std::clamp(lambda[j], 300.0, 830.0);
      const ph::WaterParams w = ph::make_water_params(water, {l, l, l});
      const double e_sun = test_sun(earth, lambda[j]);
      const double e_sky = earth.solar_irradiance.at(lambda[j]) * std::exp(interpolate(lambda[j], glm::log(sky / solar)));
      const double a = interpolate(lambda[j], albedo);
      const double radiance = ph::water_leaving_radiance(w, kNormal, view, sun, glm::vec3(float(e_sun)),
                                                         glm::vec3(float(e_sky)), depth, glm::vec3(float(a)))
                                  .x;
      expected += weights[j] * radiance / atmos::kMaxLuminousEfficacy;
      expected_glint += weights[j] * double(ph::fresnel_reflectance(0.8f, w.refractive_index.x)) * 0.6 * e_sun /
                        atmos::kMaxLuminousEfficacy;
    }
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(below[c], expected[c], 1e-4 * std::abs(expected[c])) << "depth " << depth << " channel " << c;
      EXPECT_NEAR(glint[c], expected_glint[c], 1e-4 * std::abs(expected_glint[c])) << c;
    }
  }
}

// What the working wavelengths change. Deep clear water (0.05 mg m^-3)
// under the sun's spectrum above the atmosphere, seen from the zenith with
// the sun 30 degrees from it, at 15 wavelengths against the three-channel
// evaluation (the water's optics at 680, 550 and 440 nm applied to the
// sRGB of the same light, water_optics). Its light is a spectrum that falls
// by 100x from 440 to 600 nm; at 15 wavelengths its sRGB red is negative:
// the colour lies outside the sRGB gamut, beyond the blue-green edge
// (chromaticity printed), which three positive channels cannot show, and
// where pure water's absorption grows eightfold across the red channel
// (580-700 nm; Pope & Fry 1997) the red at 680 nm alone is no measure of
// it. The blue, where absorption is flat, agrees within 10 %; the glint,
// whose Fresnel reflectance changes by 0.4 % per channel, within 1 %.
TEST(WaterSpectral, DeepWaterDiffersWhereAbsorptionChangesAcrossAChannel) {
  const atmos::Atmosphere earth = earth_at(15);
  ph::Water water;
  water.chlorophyll_mg_m3 = 0.05;
  const std::unique_ptr<ph::WaterSpectrum> s = ph::make_water_spectrum(water, earth);
  const std::vector<double>& lambda = earth.wavelengths_nm;
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(lambda);
  ph::vec3 sun_sets[SPECTRAL_SET_CAPACITY] = {};
  glm::dvec3 solar(0.0);
  for (size_t j = 0; j < lambda.size(); ++j) {
    sun_sets[j / 3][int(j % 3)] = float(earth.solar_irradiance.at(lambda[j]));
    solar += weights[j] * earth.solar_irradiance.at(lambda[j]) / atmos::kMaxLuminousEfficacy;
  }
  const glm::vec3 view = kNormal, sun = glm::vec3(direction(radians(30.0), 0.0));
  const glm::vec3 sky(0.0f), albedo(0.0f);
  glm::vec3 glint;
  const glm::vec3 spectral =
      ph::water_spectral_radiance(*s, sun_sets, sky, 0.5f, 0.95f, kNormal, view, sun, 1e4f, albedo, glint);
  const atmos::WaterOptics o = atmos::water_optics(water, earth);
  ph::WaterParams w = ph::make_water_params(water, o.wavelengths_nm);
  const glm::vec3 three =
      ph::water_leaving_radiance(w, kNormal, view, sun, glm::vec3(solar), sky, 1e4f, albedo);
  const glm::vec3 three_glint = ph::fresnel_reflectance(0.95f, w.refractive_index) * 0.5f * glm::vec3(solar);
  const glm::vec3 ratio = spectral / three, glint_ratio = glint / three_glint;
  // CIE xy from linear sRGB (IEC 61966-2-1's matrix).
  const auto xy = [](const glm::vec3& rgb) {
    const glm::dvec3 c(rgb);
    const glm::dvec3 xyz(0.4124 * c.x + 0.3576 * c.y + 0.1805 * c.z, 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z,
                         0.0193 * c.x + 0.1192 * c.y + 0.9505 * c.z);
    return glm::dvec2(xyz.x, xyz.y) / (xyz.x + xyz.y + xyz.z);
  };
  const glm::dvec2 xy_spectral = xy(spectral), xy_three = xy(three);
  std::printf("deep water, 15 wavelengths over 3 channels: rgb %.4f %.4f %.4f (xy %.3f %.3f against %.3f %.3f); "
              "glint %.4f %.4f %.4f\n",
              ratio.x, ratio.y, ratio.z, xy_spectral.x, xy_spectral.y, xy_three.x, xy_three.y, glint_ratio.x,
              glint_ratio.y, glint_ratio.z);
  EXPECT_LT(spectral.x, 0.0f);
  EXPECT_GT(three.x, 0.0f);
  EXPECT_NEAR(ratio.z, 1.0f, 0.1f);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(glint_ratio[c], 1.0f, 0.01f) << c;
  // Still blue: blue over green over red.
  EXPECT_GT(spectral.z, spectral.y);
  EXPECT_GT(spectral.y, spectral.x);
}

class WaterGpu : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    try {
      context_ = atmos::GlContext::create_headless();
    } catch (const atmos::Error& e) {
      error_ = e.what();
    }
  }
  static void TearDownTestSuite() { context_.reset(); }
  void SetUp() override { ASSERT_TRUE(context_ != nullptr) << error_; }

  static inline std::unique_ptr<atmos::GlContext> context_;
  static inline std::string error_;
};

std::string glsl_vec3(const glm::vec3& v) {
  return "vec3(" + atmos::gpu::glsl_float(v.x) + ", " + atmos::gpu::glsl_float(v.y) + ", " +
         atmos::gpu::glsl_float(v.z) + ")";
}

std::string glsl_params(const ph::WaterParams& w) {
  return "WaterParams(" + glsl_vec3(w.refractive_index) + ", " + glsl_vec3(w.absorption) + ", " +
         glsl_vec3(w.backscattering) + ", " + glsl_vec3(w.diffuse_reflectance) + ", vec2(" +
         atmos::gpu::glsl_float(w.slope_variance.x) + ", " + atmos::gpu::glsl_float(w.slope_variance.y) + "))";
}

std::string glsl_mat3(const glm::mat3& m) {
  return "mat3(" + glsl_vec3(m[0]) + ", " + glsl_vec3(m[1]) + ", " + glsl_vec3(m[2]) + ")";
}

// A WaterSpectrum as a GLSL constant, and an array of vec3 per triple.
std::string glsl_spectrum(const ph::WaterSpectrum& s) {
  std::string params, solar, to, from;
  for (int k = 0; k < SPECTRAL_SET_CAPACITY; ++k) {
    const std::string comma = k + 1 < SPECTRAL_SET_CAPACITY ? ", " : "";
    params += glsl_params(s.set[k]) + comma;
    solar += glsl_vec3(s.solar_irradiance[k]) + comma;
    to += glsl_mat3(s.to_channels[k]) + comma;
    from += glsl_mat3(s.from_channels[k]) + comma;
  }
  const std::string n = std::to_string(SPECTRAL_SET_CAPACITY);
  return "const WaterSpectrum SPECTRUM = WaterSpectrum(" + std::to_string(s.count) + ", WaterParams[" + n + "](" +
         params + "), vec3[" + n + "](" + solar + "), mat3[" + n + "](" + to + "), mat3[" + n + "](" + from + "));\n";
}

std::string glsl_vec3_array(const ph::vec3* v, const char* name) {
  std::string text = "const vec3 " + std::string(name) + "[" + std::to_string(SPECTRAL_SET_CAPACITY) + "] = vec3[](";
  for (int k = 0; k < SPECTRAL_SET_CAPACITY; ++k) text += glsl_vec3(v[k]) + (k + 1 < SPECTRAL_SET_CAPACITY ? ", " : ");\n");
  return text;
}

// The inputs of pixel (x, y) of the twin test, computed the same way on
// both sides: view zenith from x, azimuth from y, a fixed sun, a depth from y.
constexpr int kTwinWidth = 16;
constexpr int kTwinHeight = 8;
const char* const kTwinInputs = R"(
vec3 twin_direction(float zenith, float azimuth) {
  return vec3(sin(zenith) * cos(azimuth), sin(zenith) * sin(azimuth), cos(zenith));
}
void twin_inputs(int x, int y, OUT(vec3) view, OUT(vec3) sun, OUT(float) depth) {
  view = twin_direction((float(x) + 0.5f) / 16.0f * 1.48f, float(y) * 0.7f);
  sun = twin_direction(0.6f, 3.3f);
  depth = 0.25f + 2.0f * float(y);
}
)";

// The same inputs in C++, in the same float arithmetic.
void twin_inputs(int x, int y, glm::vec3& view, glm::vec3& sun, float& depth) {
  auto twin_direction = [](float zenith, float azimuth) {
    return glm::vec3(std::sin(zenith) * std::cos(azimuth), std::sin(zenith) * std::sin(azimuth), std::cos(zenith));
  };
  view = twin_direction((float(x) + 0.5f) / 16.0f * 1.48f, float(y) * 0.7f);
  sun = twin_direction(0.6f, 3.3f);
  depth = 0.25f + 2.0f * float(y);
}

TEST_F(WaterGpu, GlslCompilesAndMatchesTheCppTwins) {
  const char* definitions = atmos::data::embedded_file("src/physics/definitions.glsl");
  const char* water_glsl = atmos::data::embedded_file("src/physics/water.glsl");
  ASSERT_NE(definitions, nullptr);
  ASSERT_NE(water_glsl, nullptr);
  ph::Water water;
  water.wind_speed_m_s = 6.0;
  water.chlorophyll_mg_m3 = 0.3;
  const ph::WaterParams w = ph::make_water_params(water, {680.0, 550.0, 440.0});
  const glm::vec3 upwind = glm::normalize(glm::vec3(1.0f, 0.3f, 0.0f));
  const std::string params = "const WaterParams WATER = WaterParams(" + glsl_vec3(w.refractive_index) + ", " +
                             glsl_vec3(w.absorption) + ", " + glsl_vec3(w.backscattering) + ", " +
                             glsl_vec3(w.diffuse_reflectance) + ", vec2(" + atmos::gpu::glsl_float(w.slope_variance.x) +
                             ", " + atmos::gpu::glsl_float(w.slope_variance.y) + "));\n";
  // The water at 15 working wavelengths (five triples), lit by the sun
  // through a Rayleigh-like transmittance and a sky of the channels.
  const atmos::Atmosphere earth = earth_at(15);
  const std::unique_ptr<ph::WaterSpectrum> spectrum = ph::make_water_spectrum(water, earth);
  ph::vec3 sun_sets[SPECTRAL_SET_CAPACITY] = {};
  for (size_t j = 0; j < earth.wavelengths_nm.size(); ++j)
    sun_sets[j / 3][int(j % 3)] = float(test_sun(earth, earth.wavelengths_nm[j]));
  glm::vec3 solar(0.0f);
  for (int k = 0; k < spectrum->count; ++k) solar += spectrum->to_channels[k] * spectrum->solar_irradiance[k];
  const glm::vec3 sky = 0.15f * solar * glm::vec3(0.6f, 0.8f, 1.2f);
  const std::string fragment = std::string("#version 450 core\n") +
                               "#define IN(T) in T\n#define OUT(T) out T\n#define INOUT(T) inout T\n#define INLINE\n" +
                               definitions + water_glsl + params + glsl_spectrum(*spectrum) +
                               glsl_vec3_array(sun_sets, "SUN_SETS") + "const vec3 SKY = " + glsl_vec3(sky) + ";\n" +
                               kTwinInputs + R"(
layout(location = 0) uniform int which;
layout(location = 0) out vec4 result;
void main() {
  vec3 view;
  vec3 sun;
  float depth;
  twin_inputs(int(gl_FragCoord.x), int(gl_FragCoord.y), view, sun, depth);
  const vec3 normal = vec3(0.0, 0.0, 1.0);
  const vec3 upwind = )" + glsl_vec3(upwind) + R"(;
  vec3 value = vec3(0.0);
  vec3 mean_direction;
  if (which == 0) value = water_glint_brdf(WATER, normal, upwind, view, sun);
  if (which == 1) value = water_sky_reflectance(WATER, normal, upwind, view, mean_direction);
  if (which == 2) { water_sky_reflectance(WATER, normal, upwind, view, mean_direction); value = mean_direction; }
  if (which == 3) value = water_leaving_radiance(WATER, normal, view, sun, vec3(1.9, 1.8, 1.7), vec3(0.3, 0.4, 0.5),
                                                 depth, vec3(0.3, 0.25, 0.2));
  if (which == 4) value = fresnel_reflectance(view.z, WATER.refractive_index);
  if (which == 5 || which == 6) {
    float cosine;
    float factor = water_glint_geometry(WATER.slope_variance, normal, upwind, view, sun, cosine) * sun.z;
    vec3 glint;
    value = water_spectral_radiance(SPECTRUM, SUN_SETS, SKY, factor, cosine, normal, view, sun, depth,
                                    vec3(0.3, 0.25, 0.2), glint);
    if (which == 6) value = glint;
  }
  result = vec4(value, 1.0);
}
)";
  const GLuint program = atmos_test::fullscreen_program(fragment);
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  ASSERT_TRUE(linked);

  const char* names[] = {"glint BRDF",      "sky reflectance", "mean sky direction", "water-leaving radiance",
                         "Fresnel",         "water-leaving radiance at 15 wavelengths",
                         "glint at 15 wavelengths"};
  for (int which = 0; which < 7; ++which) {
    glProgramUniform1i(program, 0, which);
    const std::vector<float> pixels = atmos_test::draw_fullscreen(program, kTwinWidth, kTwinHeight);
    double worst = 0.0, largest = 0.0;
    for (int y = 0; y < kTwinHeight; ++y) {
      for (int x = 0; x < kTwinWidth; ++x) {
        glm::vec3 view, sun;
        float depth;
        twin_inputs(x, y, view, sun, depth);
        glm::vec3 mean_direction;
        glm::vec3 cpu(0.0f);
        if (which == 0) cpu = ph::water_glint_brdf(w, kNormal, upwind, view, sun);
        if (which == 1) cpu = ph::water_sky_reflectance(w, kNormal, upwind, view, mean_direction);
        if (which == 2) {
          ph::water_sky_reflectance(w, kNormal, upwind, view, mean_direction);
          cpu = mean_direction;
        }
        if (which == 3)
          cpu = ph::water_leaving_radiance(w, kNormal, view, sun, glm::vec3(1.9f, 1.8f, 1.7f),
                                           glm::vec3(0.3f, 0.4f, 0.5f), depth, glm::vec3(0.3f, 0.25f, 0.2f));
        if (which == 4) cpu = ph::fresnel_reflectance(view.z, w.refractive_index);
        if (which == 5 || which == 6) {
          float cosine;
          const float factor = ph::water_glint_geometry(w.slope_variance, kNormal, upwind, view, sun, cosine) * sun.z;
          glm::vec3 glint;
          cpu = ph::water_spectral_radiance(*spectrum, sun_sets, sky, factor, cosine, kNormal, view, sun, depth,
                                            glm::vec3(0.3f, 0.25f, 0.2f), glint);
          if (which == 6) cpu = glint;
        }
        const float* gpu = &pixels[size_t((y * kTwinWidth + x) * 4)];
        for (int c = 0; c < 3; ++c) {
          ASSERT_TRUE(std::isfinite(gpu[c])) << names[which] << " at " << x << ", " << y;
          const double scale = std::max(std::abs(double(cpu[c])), 1e-6);
          const double difference = std::abs(double(gpu[c]) - double(cpu[c])) / scale;
          worst = std::max(worst, difference);
          largest = std::max(largest, std::abs(double(cpu[c])));
          EXPECT_LT(difference, 2e-3) << names[which] << " at " << x << ", " << y << " channel " << c << ": GPU "
                                      << gpu[c] << ", CPU " << cpu[c];
        }
      }
    }
    std::printf("GPU vs CPU, %s: worst relative difference %.2e (largest value %.3g)\n", names[which], worst, largest);
    EXPECT_GT(largest, 0.0) << names[which];
  }
  glDeleteProgram(program);
}

}  // namespace
