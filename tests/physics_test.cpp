// Invariants of the shared physics (the GLSL of src/physics/ compiled as C++).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"
#include "physics/parameters.hpp"
#include "physics/radiance_to_camera_cpp.hpp"
#include "precompute/steps.hpp"

namespace {

using namespace atmos::physics;
using atmos::precompute::gauss_legendre;
using atmos::precompute::legendre_moments;

// 2π ∫ P(mu) dmu over [-1, 1] with a Gauss-Legendre rule fine enough for g = 0.9.
double integrate_over_sphere(const std::function<double(double)>& phase) {
  std::vector<double> x, w;
  gauss_legendre(4096, -1.0, 1.0, x, w);
  double sum = 0.0;
  for (size_t i = 0; i < x.size(); ++i) sum += phase(x[i]) * w[i];
  return 2.0 * M_PI * sum;
}

TEST(PhaseFunctions, IntegrateToOneOverTheSphere) {
  EXPECT_NEAR(integrate_over_sphere([](double nu) { return rayleigh_phase_function(float(nu)); }), 1.0, 1e-5);
  for (float g : {0.0f, 0.3f, 0.76f, 0.8f, 0.9f, -0.5f}) {
    EXPECT_NEAR(integrate_over_sphere([g](double nu) { return henyey_greenstein_phase_function(g, float(nu)); }), 1.0,
                2e-4)
        << "Henyey-Greenstein g = " << g;
    EXPECT_NEAR(integrate_over_sphere([g](double nu) { return cornette_shanks_phase_function(g, float(nu)); }), 1.0,
                2e-4)
        << "Cornette-Shanks g = " << g;
  }
}

TEST(PhaseFunctions, CornetteShanksWithZeroGIsRayleigh) {
  // Collienne 2013, after eq. 3.5: with g = 0 the function equals Rayleigh's.
  for (float nu = -1.0f; nu <= 1.0f; nu += 0.125f)
    EXPECT_NEAR(cornette_shanks_phase_function(0.0f, nu), rayleigh_phase_function(nu), 1e-7f);
}

TEST(PhaseFunctions, LegendreMoments) {
  // 1 + nu² = 4/3 P_0 + 2/3 P_2, so the Rayleigh moments are 1, 0, 1/10, 0...
  const auto rayleigh = legendre_moments([](double nu) { return double(rayleigh_phase_function(float(nu))); }, 6);
  EXPECT_NEAR(rayleigh[0], 1.0, 1e-6);
  EXPECT_NEAR(rayleigh[1], 0.0, 1e-6);
  EXPECT_NEAR(rayleigh[2], 0.1, 1e-6);
  for (int l = 3; l <= 6; ++l) EXPECT_NEAR(rayleigh[size_t(l)], 0.0, 1e-6);
  // Henyey-Greenstein: p_l = g^l.
  const auto hg = legendre_moments([](double nu) { return double(henyey_greenstein_phase_function(0.7f, float(nu))); }, 20);
  for (int l = 0; l <= 20; ++l) EXPECT_NEAR(hg[size_t(l)], std::pow(0.7, l), 2e-5) << "l = " << l;
}

TEST(GaussLegendre, IntegratesPolynomialsExactly) {
  std::vector<double> x, w;
  gauss_legendre(8, -0.3, 2.0, x, w);
  double sum = 0.0;
  for (size_t i = 0; i < x.size(); ++i) sum += std::pow(x[i], 15) * w[i];
  EXPECT_NEAR(sum, (std::pow(2.0, 16) - std::pow(-0.3, 16)) / 16.0, 1e-9);
}

class EarthParams : public ::testing::Test {
 protected:
  void SetUp() override {
    atmosphere = atmos::load_atmosphere("earth");
    params = make_atmosphere_params(atmosphere, atmos::TableSizes{}, 0);
  }
  atmos::Atmosphere atmosphere;
  AtmosphereParams params{};
};

TEST_F(EarthParams, TransmittanceMappingRoundTrips) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 2000; ++i) {
    const float r = params.bottom_radius + u(rng) * (params.top_radius - params.bottom_radius);
    const float mu_h = horizon_mu(params, r);
    const float mu = mu_h + u(rng) * (1.0f - mu_h);  // rays that do not hit the ground
    const vec2 uv = transmittance_uv_from_r_mu(params, r, mu);
    float r2, mu2;
    r_mu_from_transmittance_uv(params, uv, r2, mu2);
    EXPECT_NEAR(r2, r, 2.0f);
    // Near straight up mu is flat in d: compare the distances instead.
    EXPECT_NEAR(distance_to_top_atmosphere_boundary(params, r2, mu2), distance_to_top_atmosphere_boundary(params, r, mu),
                20.0f)
        << "r " << r << " mu " << mu;
  }
}

// Rays (r, mu, mu_s, nu) of random directions at random altitudes map to
// texture coordinates of the scattering tables and back to the same rays;
// the lower half of the mu axis (u < 0.5) holds the rays that reach the ground.
void expect_scattering_mapping_round_trips(const AtmosphereParams& params, unsigned seed, int count) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < count; ++i) {
    const float r = params.bottom_radius + 50.0f + u(rng) * (params.top_radius - params.bottom_radius - 100.0f);
    const float mu = -1.0f + 2.0f * u(rng);
    const float mu_s = params.mu_s_min + u(rng) * (1.0f - params.mu_s_min);
    const float nu = -1.0f + 2.0f * u(rng);
    const bool ground = ray_intersects_ground(params, r, mu);
    const vec4 uvwz = scattering_uvwz_from_r_mu_mu_s_nu(params, r, mu, mu_s, nu, ground);
    ASSERT_GE(uvwz.z, 0.0f);
    ASSERT_LE(uvwz.z, 1.0f);
    EXPECT_EQ(uvwz.z < 0.5f, ground);
    float r2, mu2, mu_s2, nu2;
    bool ground2;
    r_mu_mu_s_nu_from_scattering_uvwz(params, uvwz, r2, mu2, mu_s2, nu2, ground2);
    EXPECT_EQ(ground2, ground);
    EXPECT_NEAR(r2, r, 5.0f);
    const float d = distance_to_nearest_atmosphere_boundary(params, r, mu, ground);
    EXPECT_NEAR(distance_to_nearest_atmosphere_boundary(params, r2, mu2, ground2), d, 1e-3f * d + 30.0f)
        << "r " << r << " mu " << mu;
    EXPECT_NEAR(mu_s2, mu_s, 2e-4f);
    EXPECT_NEAR(nu2, nu, 1e-5f);
  }
}

TEST_F(EarthParams, ScatteringMappingRoundTrips) { expect_scattering_mapping_round_trips(params, 11, 2000); }

TEST_F(EarthParams, IrradianceMappingRoundTrips) {
  for (float r = params.bottom_radius; r <= params.top_radius; r += 5000.0f) {
    for (float mu_s = params.mu_s_min; mu_s <= 1.0f; mu_s += 0.01f) {
      float r2, mu_s2;
      r_mu_s_from_irradiance_uv(params, irradiance_uv_from_r_mu_s(params, r, mu_s), r2, mu_s2);
      EXPECT_NEAR(r2, r, 1.0f);
      EXPECT_NEAR(mu_s2, mu_s, 2e-4f);
    }
    // Below mu_s_min (no sunlight anywhere in the atmosphere) the mapping
    // clamps to the first texel centre.
    const vec2 uv = irradiance_uv_from_r_mu_s(params, r, -0.9f);
    EXPECT_FLOAT_EQ(uv.x, 0.5f / float(params.irradiance_mu_s_size));
  }
}

// Twilight gets finer texels than the high sun: the sky irradiance changes
// fastest there.
TEST_F(EarthParams, IrradianceMuSTexelsAreDensestNearTheHorizon) {
  auto texel_width_deg = [&](float elevation_deg) {
    const float e = elevation_deg * float(M_PI) / 180.0f, de = 1e-3f;
    const float du = irradiance_uv_from_r_mu_s(params, params.bottom_radius, std::sin(e + de)).x -
                     irradiance_uv_from_r_mu_s(params, params.bottom_radius, std::sin(e)).x;
    return de / (du * float(params.irradiance_mu_s_size)) * 180.0f / float(M_PI);
  };
  EXPECT_LT(texel_width_deg(-3.0f), 1.0f);
  EXPECT_LT(texel_width_deg(-3.0f), 0.5f * texel_width_deg(60.0f));
}

TEST_F(EarthParams, TextureCoordinatesSampleTexelCentres) {
  EXPECT_FLOAT_EQ(texture_coord_from_unit_range(0.0f, 64), 0.5f / 64.0f);
  EXPECT_FLOAT_EQ(texture_coord_from_unit_range(1.0f, 64), 1.0f - 0.5f / 64.0f);
  EXPECT_NEAR(unit_range_from_texture_coord(texture_coord_from_unit_range(0.37f, 16), 16), 0.37f, 1e-6f);
}

TEST_F(EarthParams, OpticalDepthComposes) {
  // Transmittance along a path equals the product over its pieces.
  for (float mu : {1.0f, 0.5f, 0.1f, 0.0f, -0.05f}) {
    const float r = params.bottom_radius + 1500.0f;
    const float d = distance_to_nearest_atmosphere_boundary(params, r, mu, ray_intersects_ground(params, r, mu));
    const vec3 whole = optical_depth_along_ray(params, r, mu, 0.0f, d, 4000);
    const vec3 pieces = optical_depth_along_ray(params, r, mu, 0.0f, 0.3f * d, 2000) +
                        optical_depth_along_ray(params, r, mu, 0.3f * d, d, 2000);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(pieces[c] / whole[c], 1.0f, 1e-4f) << "mu " << mu;
  }
}

TEST_F(EarthParams, VerticalOpticalDepthMatchesTheExponentialProfile) {
  // Straight up from the ground: the air's optical depth is beta H (1 - exp(-Z/H)).
  const float d = params.top_radius - params.bottom_radius;
  AtmosphereParams air_only = params;
  air_only.constituent_count = 1;
  const vec3 tau = optical_depth_along_ray(air_only, params.bottom_radius, 1.0f, 0.0f, d, 20000);
  const float H = params.density[0].scale_height;
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(tau[c], params.scattering[0][c] * H * (1.0f - std::exp(-d / H)), 1e-4f * tau[c]);
  // The Rayleigh optical depth at 550 nm of the Earth preset is the literature
  // value 0.0973 (Bodhaine et al. 1999, standard atmosphere) within 1 %.
  EXPECT_NEAR(tau[1], 0.0973f, 0.001f);
}

TEST_F(EarthParams, OzoneProfileIsATriangle) {
  const DensityProfile& ozone = params.density[2];
  EXPECT_FLOAT_EQ(profile_density(ozone, 5000.0f), 0.0f);
  EXPECT_FLOAT_EQ(profile_density(ozone, 25000.0f), 1.0f);
  EXPECT_NEAR(profile_density(ozone, 17500.0f), 0.5f, 1e-6f);
  EXPECT_NEAR(profile_density(ozone, 32500.0f), 0.5f, 1e-6f);
  EXPECT_FLOAT_EQ(profile_density(ozone, 45000.0f), 0.0f);
}

TEST_F(EarthParams, SunVisibleFractionAtTheHorizon) {
  const float r = params.bottom_radius;  // at the ground the horizon is at mu = 0
  EXPECT_NEAR(sun_visible_fraction(params, r, 0.0f), 0.5f, 1e-3f);
  // Higher up the horizon dips below the horizontal: more than half the disc shows.
  EXPECT_GT(sun_visible_fraction(params, r + 100.0f, 0.0f), 0.6f);
  EXPECT_FLOAT_EQ(sun_visible_fraction(params, r, 0.1f), 1.0f);
  EXPECT_FLOAT_EQ(sun_visible_fraction(params, r, -0.1f), 0.0f);
  // Monotonic through the transition.
  float previous = 0.0f;
  for (float mu_s = -0.01f; mu_s <= 0.01f; mu_s += 0.0005f) {
    const float f = sun_visible_fraction(params, r, mu_s);
    EXPECT_GE(f, previous);
    previous = f;
  }
}

// The sun disc (sun_disc_radiance): limb-darkened by the linear law with
// u = 3/5, and its radiance integrates over the disc to the solar irradiance
// (rings of the disc, midpoint rule in theta; the normalisation's small-disc
// approximation is off by ~alpha², below 1e-4 for every preset's sun).
TEST_F(EarthParams, SunDiscIsLimbDarkenedAndCarriesTheSolarIrradiance) {
  const vec3 sun(0.0f, 0.0f, 1.0f);
  for (double alpha_deg : {0.2665, 0.1748, 0.3685, 0.02781, 2.0}) {
    AtmosphereParams p = params;
    p.sun_angular_radius = float(alpha_deg * M_PI / 180.0);
    const double alpha = p.sun_angular_radius;
    auto radiance_at = [&](double theta) {
      return sun_disc_radiance(p, vec3(float(std::sin(theta)), 0.0f, float(std::cos(theta))), sun);
    };
    const int rings = 4000;
    glm::dvec3 irradiance(0.0);
    for (int i = 0; i < rings; ++i) {
      const double theta = (i + 0.5) / rings * alpha;
      irradiance += glm::dvec3(radiance_at(theta)) * (2.0 * M_PI * std::sin(theta) * alpha / rings);
    }
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(irradiance[c] / p.solar_irradiance[c], 1.0, alpha < 0.01 ? 2e-4 : 2e-3) << alpha_deg << " deg";
    // Limb darkening: at half the radius mu = sqrt(3/4), at the edge mu -> 0.
    const vec3 centre = radiance_at(0.0);
    EXPECT_NEAR(radiance_at(std::asin(0.5 * std::sin(alpha))).y / centre.y, 1.0 - 0.6 * (1.0 - std::sqrt(0.75)), 2e-3);
    EXPECT_NEAR(radiance_at(0.9999 * alpha).y / centre.y, 0.4, 0.02);
    EXPECT_EQ(radiance_at(1.001 * alpha).y, 0.0f);
  }
}

// The solar corona (sun_corona_radiance, Baumbach's law): nothing on the
// disc or beyond 16 solar radii, 4e-6 of the disc's mean radiance at its
// limb, and in all about 1.1e-6 of the sun's light (the closed form of the
// law over rho >= 1 is 2e-6 (0.0532/0.5 + 1.425/5 + 2.565/15) = 1.125e-6;
// the fade-out beyond 8 radii removes ~2 %).
TEST_F(EarthParams, SolarCoronaFollowsBaumbachsLaw) {
  const vec3 sun(0.0f, 0.0f, 1.0f);
  const double alpha = params.sun_angular_radius;
  auto corona_at = [&](double rho) {
    const double theta = std::asin(rho * std::sin(alpha));
    return sun_corona_radiance(params, vec3(float(std::sin(theta)), 0.0f, float(std::cos(theta))), sun);
  };
  EXPECT_EQ(corona_at(0.5).y, 0.0f);
  EXPECT_EQ(corona_at(16.5).y, 0.0f);
  const double mean_disc = params.solar_irradiance.y / (4.0 * M_PI * std::pow(std::sin(0.5 * alpha), 2.0));
  EXPECT_NEAR(corona_at(1.0001).y / mean_disc, 4.04e-6, 0.01e-6);
  // Rings in rho (log-spaced), small angles: d Omega = 2 pi rho drho sin²alpha.
  double irradiance = 0.0;
  const int rings = 20000;
  for (int i = 0; i < rings; ++i) {
    const double rho0 = std::pow(16.0, double(i) / rings), rho1 = std::pow(16.0, double(i + 1) / rings);
    const double rho = 0.5 * (rho0 + rho1);
    irradiance += corona_at(rho).y * 2.0 * M_PI * rho * (rho1 - rho0) * std::sin(alpha) * std::sin(alpha);
  }
  const double fraction = irradiance / params.solar_irradiance.y;
  std::printf("corona: %.4g of the sun's irradiance\n", fraction);
  EXPECT_GT(fraction, 1.05e-6);
  EXPECT_LT(fraction, 1.125e-6);
}

// The procedural star field (stars.glsl): the real sky's counts per
// magnitude (N(V) = 10^(0.5 V + 0.7): 8900 stars brighter than 6.5, the Yale
// Bright Star Catalogue's 9110), each star inside its own cell (so a pixel
// finds it by its own cell), and each star's image integrating to its
// irradiance.
TEST_F(EarthParams, StarFieldHasTheSkysCountsAndCarriesEachStarsIrradiance) {
  const int cells = 6 * STAR_CELLS * STAR_CELLS;
  int brighter_than_6_5 = 0, brighter_than_2 = 0;
  float brightest = 100.0f;
  for (int c = 0; c < cells; ++c) {
    float magnitude;
    const vec3 star = star_of_cell(c, magnitude);
    ASSERT_NEAR(length(star), 1.0f, 1e-6f);
    ASSERT_EQ(star_cell(star), c) << "the star of cell " << c << " lies outside it";
    brighter_than_6_5 += magnitude < 6.5f ? 1 : 0;
    brighter_than_2 += magnitude < 2.0f ? 1 : 0;
    brightest = std::min(brightest, magnitude);
  }
  std::printf("%d stars brighter than V = 6.5, %d than 2, brightest %.2f\n", brighter_than_6_5, brighter_than_2,
              brightest);
  EXPECT_NEAR(brighter_than_6_5, 8900, 300);
  EXPECT_NEAR(brighter_than_2, 50, 20);
  EXPECT_LT(brightest, -0.5f);
  EXPECT_GT(brightest, -3.0f);
  // A star of cell 1234, its image 1 mrad wide: the radiance over a cap of
  // 6 sigma around it integrates to star_irradiance.
  float magnitude;
  const vec3 star = star_of_cell(1234, magnitude);
  const StarField field{true, 1e-3f};
  const vec3 side = normalize(cross(star, vec3(0.0f, 0.0f, 1.0f)));
  const vec3 up = cross(side, star);
  glm::dvec3 irradiance(0.0);
  const int rings = 600, sectors = 64;
  for (int i = 0; i < rings; ++i) {
    const double theta = (i + 0.5) / rings * 6e-3;
    for (int k = 0; k < sectors; ++k) {
      const double phi = 2.0 * M_PI * (k + 0.5) / sectors;
      const vec3 view = normalize(star * float(std::cos(theta)) +
                                  (side * float(std::cos(phi)) + up * float(std::sin(phi))) * float(std::sin(theta)));
      irradiance += glm::dvec3(star_field_radiance(params, field, view)) *
                    (std::sin(theta) * (6e-3 / rings) * (2.0 * M_PI / sectors));
    }
  }
  const vec3 expected = star_irradiance(params, magnitude);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(irradiance[c] / expected[c], 1.0, 2e-3);
  // A magnitude-0 star gives 10^(-0.4 * 26.74) of the Sun's irradiance at 1 au.
  EXPECT_NEAR(star_irradiance(params, 0.0f).y / params.solar_irradiance.y *
                  std::pow(params.sun_angular_radius / SUN_ANGULAR_RADIUS_AT_1_AU, 2.0),
              std::pow(10.0, -0.4 * 26.74), 1e-3 * std::pow(10.0, -0.4 * 26.74));
  EXPECT_EQ(star_field_radiance(params, StarField{false, 1e-3f}, star).y, 0.0f);
}

// Eclipse geometry (eclipse.glsl). The overlap of two discs against the
// analytic areas of the four cases, and against a fine grid; the visible
// fraction of the limb-darkened sun against closed forms (no overlap, total,
// centred annular) and a fine grid of the disc (partial), in units of the
// sun's angular radius.
TEST(Eclipse, OverlapAndVisibleLightOfTheLimbDarkenedSun) {
  const float a = 4.65e-3f;  // the Sun's angular radius from the Earth (rad)
  // No overlap, total, annular: the closed forms.
  EXPECT_EQ(circle_overlap_area(a, 1.1f * a, 2.2f * a), 0.0f);
  EXPECT_NEAR(circle_overlap_area(a, 1.1f * a, 0.05f * a) / (PI * a * a), 1.0, 1e-6);
  EXPECT_NEAR(circle_overlap_area(a, 0.9f * a, 0.05f * a) / (PI * a * a), 0.81, 1e-5);
  EXPECT_EQ(sun_visible_fraction_behind_moon(a, 1.1f * a, 2.2f * a), 1.0f);
  EXPECT_EQ(sun_visible_fraction_behind_moon(a, 1.1f * a, 0.05f * a), 0.0f);
  // Centred annular: the flux inside radius r of the law 1 - u (1 - mu) is
  // pi r² (1 - u) + u (2 pi a² / 3) (1 - (1 - r²/a²)^(3/2)).
  for (double r_over_a : {0.3, 0.6, 0.9, 0.97}) {
    const double u = SUN_LIMB_DARKENING_U, r = r_over_a;
    const double inside = M_PI * r * r * (1.0 - u) + u * (2.0 * M_PI / 3.0) * (1.0 - std::pow(1.0 - r * r, 1.5));
    const double total = M_PI * (1.0 - u / 3.0);
    EXPECT_NEAR(sun_visible_fraction_behind_moon(a, float(r_over_a) * a, 0.0f), 1.0 - inside / total, 2e-5)
        << "annular, moon " << r_over_a;
  }
  // Partial (and the other cases again) against a grid of 2000 x 2000 points
  // of the sun's disc: the overlap area (uniform disc) and the visible light
  // (limb-darkened).
  const int n = 2000;
  for (const auto& [b_over_a, d_over_a] : {std::pair<double, double>{1.03, 1.2}, {1.03, 0.5}, {0.5, 0.9}, {0.5, 0.2},
                                           {2.0, 2.5}, {0.95, 0.02}}) {
    double covered_area = 0.0, covered_light = 0.0, total_light = 0.0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double x = (i + 0.5) / n * 2.0 - 1.0, y = (j + 0.5) / n * 2.0 - 1.0;
        const double rho2 = x * x + y * y;
        if (rho2 >= 1.0) continue;
        const double intensity = 1.0 - SUN_LIMB_DARKENING_U * (1.0 - std::sqrt(1.0 - rho2));
        const bool in_moon = (x - d_over_a) * (x - d_over_a) + y * y < b_over_a * b_over_a;
        total_light += intensity;
        if (in_moon) {
          covered_light += intensity;
          covered_area += 1.0;
        }
      }
    const double cell = 4.0 / (double(n) * n);
    const float b = float(b_over_a) * a, d = float(d_over_a) * a;
    EXPECT_NEAR(circle_overlap_area(a, b, d) / (a * a), covered_area * cell, 2e-3)
        << "moon " << b_over_a << " at " << d_over_a;
    EXPECT_NEAR(sun_visible_fraction_behind_moon(a, b, d), 1.0 - covered_light / total_light, 2e-3)
        << "moon " << b_over_a << " at " << d_over_a;
  }
  // The visible light grows as the moon moves off the sun.
  float previous = 0.0f;
  for (float d = 0.0f; d <= 2.2f * a; d += 0.01f * a) {
    const float visible = sun_visible_fraction_behind_moon(a, 1.03f * a, d);
    EXPECT_GE(visible, previous - 1e-6f) << d / a;
    previous = visible;
  }
  EXPECT_EQ(previous, 1.0f);
}

// Moons in space (eclipse.glsl): from a point on the line from the sun
// through a moon's centre the moon is centred on the sun, with the angular
// radius of its distance; a moon behind the point or far off the sun hides
// nothing; two moons over different parts of the sun multiply; a view ray
// meets the nearest moon, whose lit side has the Lambertian radiance and
// whose night side is black.
TEST(Eclipse, MoonsInSpace) {
  const float a = 4.65e-3f;
  const vec3 sun = normalize(vec3(0.3f, -0.4f, 1.0f));
  const vec3 point(0.0f, 0.0f, 6371e3f);
  const float distance = 384400e3f, radius = 1900e3f;
  Moons moons = no_moons();
  moons.count = 1;
  moons.sphere[0] = vec4(point + sun * distance, radius);
  float b;
  EXPECT_NEAR(moon_offset_from_sun(moons.sphere[0], point, sun, b), 0.0f, 1e-6f);
  EXPECT_NEAR(b, std::asin(radius / distance), 1e-7f);
  EXPECT_EQ(sunlight_visible_fraction(moons, a, point, sun), 0.0f);  // b > a: total
  EXPECT_EQ(uniform_sunlight_visible_fraction(moons, a, point, sun), 0.0f);
  // 100 km across the shadow's axis: still in the umbra, (b - a) D = 91 km?
  const vec3 across = normalize(cross(sun, vec3(0.0f, 0.0f, 1.0f)));
  const float umbra = (std::asin(radius / distance) - a) * distance;
  EXPECT_EQ(sunlight_visible_fraction(moons, a, point + across * (0.9f * umbra), sun), 0.0f);
  const float penumbra = sunlight_visible_fraction(moons, a, point + across * (2.0f * umbra), sun);
  EXPECT_GT(penumbra, 0.0f);
  EXPECT_LT(penumbra, 0.1f);
  // Behind the point (the moon on the night side) or 1° off the sun: nothing hidden.
  Moons behind = moons;
  behind.sphere[0] = vec4(point - sun * distance, radius);
  EXPECT_EQ(sunlight_visible_fraction(behind, a, point, sun), 1.0f);
  Moons off = moons;
  off.sphere[0] = vec4(point + normalize(sun + across * 0.0175f) * distance, radius);
  EXPECT_EQ(sunlight_visible_fraction(off, a, point, sun), 1.0f);
  // Two small moons on opposite sides of the sun, each hiding its own part.
  Moons two = no_moons();
  two.count = 2;
  const float small = 0.5f * a * distance;
  two.sphere[0] = vec4(point + normalize(sun + across * (0.6f * a)) * distance, small);
  two.sphere[1] = vec4(point + normalize(sun - across * (0.6f * a)) * distance, small);
  const float each = sun_visible_fraction_behind_moon(a, 0.5f * a, 0.6f * a);
  EXPECT_NEAR(sunlight_visible_fraction(two, a, point, sun), each * each, 1e-4f);
  // A view ray towards the moon meets it ~1900 km before its centre; one
  // beside it misses it.
  int which;
  const float t = view_ray_moon_distance(moons, point, sun, which);
  EXPECT_EQ(which, 0);
  EXPECT_NEAR(t / (distance - radius), 1.0f, 1e-5f);
  EXPECT_LT(view_ray_moon_distance(moons, point, normalize(sun + across * 0.01f), which), 0.0f);
  EXPECT_EQ(which, -1);
  // Seen from the sun's side, its lit centre is albedo / pi x E; from the
  // point (night side, a new moon) it is black.
  const vec3 e(1.0f, 2.0f, 3.0f);
  const vec3 beyond = point + sun * (2.0f * distance);
  const float t_back = view_ray_moon_distance(moons, beyond, -sun, which);
  EXPECT_NEAR(moon_radiance(moons, which, beyond, -sun, t_back, sun, e).z, MOON_ALBEDO / PI * 3.0f, 1e-4f);
  EXPECT_EQ(moon_radiance(moons, 0, point, sun, t, sun, e).z, 0.0f);
}

// The quadrature over the solar disc (sun_disc_nodes): its weights add up to
// the visible fraction of the disc, and for a disc wholly in view it has the
// moments of a uniform disc (mean elevation offset 0, variance alpha² / 4).
TEST_F(EarthParams, SunDiscQuadratureHasTheDiscsMoments) {
  const float alpha = params.sun_angular_radius;
  for (float r : {params.bottom_radius, params.bottom_radius + 20e3f, params.top_radius}) {
    const float mu_h = horizon_mu(params, r);
    for (float offset = -1.5f; offset <= 3.0f; offset += 0.05f) {
      const float mu_s = std::sin(std::asin(mu_h) + offset * alpha);
      vec4 node_mu, w;
      sun_disc_nodes(params, mu_s, mu_h, node_mu, w);
      float sum = 0.0f;
      for (int k = 0; k < SUN_DISC_NODES; ++k) {
        EXPECT_GE(w[k], 0.0f);
        // The nodes that weigh lie on the visible part of the disc.
        if (w[k] > 0.0f) {
          EXPECT_GE(std::asin(double(node_mu[k])), std::asin(double(mu_h)) - 1e-5) << r << " " << offset;
        }
        EXPECT_LE(std::abs(std::asin(double(node_mu[k])) - std::asin(double(mu_s))), 1.0001 * alpha);
        sum += w[k];
      }
      EXPECT_NEAR(sum, sun_visible_fraction(params, r, mu_s), 2e-3f) << r << " " << offset;
    }
    const float mu_s = 0.05f;  // 2.9°: the whole disc above every horizon
    double mean = 0.0, variance = 0.0;
    vec4 node_mu, w;
    sun_disc_nodes(params, mu_s, mu_h, node_mu, w);
    for (int k = 0; k < SUN_DISC_NODES; ++k) {
      const double x = (std::asin(double(node_mu[k])) - std::asin(double(mu_s))) / alpha;
      mean += w[k] * x;
      variance += w[k] * x * x;
    }
    EXPECT_NEAR(mean, 0.0, 1e-3);
    EXPECT_NEAR(variance, 0.25, 2e-3);
  }
}

// transmittance_to_sun is the mean over the solar disc: against a fine grid
// of points on the disc (each with its own transmittance, none below the
// horizon). Near the horizon that mean exceeds the centre value (exp is
// convex), and the average fades out above SUN_DISC_AVERAGE_MARGIN without a
// step.
TEST_F(EarthParams, SunTransmittanceIsTheDiscAverage) {
  const atmos::precompute::Table2D transmittance = atmos::precompute::compute_transmittance_table(params);
  const sampler2D t = transmittance.sampler();
  const float alpha = params.sun_angular_radius;
  for (float r : {params.bottom_radius, params.bottom_radius + 15e3f}) {
    const double e_h = std::asin(double(horizon_mu(params, r)));
    for (double offset : {-0.5, 0.0, 0.5, 1.5, 4.0, 10.0}) {  // sun centre above the horizon, in disc radii
      const double e = e_h + offset * alpha;
      glm::dvec3 sum(0.0);
      const int n = 400;
      int inside = 0;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const double x = (2.0 * i + 1.0) / n - 1.0, y = (2.0 * j + 1.0) / n - 1.0;
          if (x * x + y * y > 1.0) continue;
          ++inside;
          if (e + x * alpha <= e_h) continue;
          sum += glm::dvec3(transmittance_to_top_atmosphere_boundary(params, t, r, float(std::sin(e + x * alpha))));
        }
      const glm::dvec3 expected = sum / double(inside);
      const vec3 actual = transmittance_to_sun(params, t, r, float(std::sin(e)));
      // 0.5 % for the whole disc; 2 % for a disc cut by the horizon, where
      // 4 nodes follow a transmittance that changes by orders of magnitude
      // across it (measured 1.2 % at 15 km, 0.3 % on the ground).
      const double tolerance = offset >= 1.0 ? 5e-3 : 2e-2;
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(actual[c], expected[c], tolerance * expected[c] + 1e-7) << r << " " << offset << " " << c;
    }
  }
  const float r = params.bottom_radius;
  const float low = std::sin(0.02f);  // sun centre 1.1° up: blue transmittance ~3e-3
  EXPECT_GT(transmittance_to_sun(params, t, r, low).z,
            1.01f * transmittance_to_top_atmosphere_boundary(params, t, r, low).z);
  const float edge = SUN_DISC_AVERAGE_MARGIN + alpha;
  const float below = transmittance_to_sun(params, t, r, edge - 1e-4f).z;
  const float above = transmittance_to_sun(params, t, r, edge + 1e-4f).z;
  // Continuous across the margin where the disc average starts, to 0.6 %
  // (measured 0.51 % with the continental aerosol, whose blue transmittance
  // changes fastest there).
  EXPECT_NEAR(below / above, 1.0f, 6e-3f);
  EXPECT_EQ(transmittance_to_sun(params, t, r, -0.1f), vec3(0.0f));
}

// transmittance_to_sun_estimate, which only places the low-sun path's
// nodes (sunlit_ray_map), is transmittance_to_sun where the sun needs no disc
// average, zero where the whole disc is below the horizon, and of the same
// order near the horizon wherever the light is above 1e-3 of the sun's:
// measured between 0.09 (a disc just above the horizon seen from the top of
// the atmosphere, whose lower half grazes the dense air) and 1.07 times the
// disc average. The integrals' accuracy with the nodes it places is that of
// the accuracy suite, against the reference (reference_accuracy.cpp,
// aerial_perspective_accuracy.cpp).
TEST_F(EarthParams, SunTransmittanceEstimateFollowsTheDiscAverage) {
  const atmos::precompute::Table2D transmittance = atmos::precompute::compute_transmittance_table(params);
  const sampler2D t = transmittance.sampler();
  const float alpha = params.sun_angular_radius;
  for (float r : {params.bottom_radius, params.bottom_radius + 15e3f, params.top_radius - 1e3f}) {
    const float mu_h = horizon_mu(params, r);
    const double e_h = std::asin(double(mu_h));
    for (double offset = -1.5; offset <= 40.0; offset += 0.05) {  // sun centre above the horizon, in disc radii
      const float mu_s = float(std::sin(e_h + offset * alpha));
      const vec3 exact = transmittance_to_sun(params, t, r, mu_s);
      const vec3 estimate = transmittance_to_sun_estimate(params, t, r, mu_s);
      for (int c = 0; c < 3; ++c) {
        if (mu_s - mu_h < -alpha) {
          EXPECT_EQ(estimate[c], 0.0f) << r << " " << offset;
        } else if (!sun_needs_disc_average(params, mu_s, mu_h)) {
          EXPECT_EQ(estimate[c], exact[c]) << r << " " << offset;
        } else if (exact[c] > 1e-3f) {
          EXPECT_GT(estimate[c], exact[c] / 15.0f) << r << " " << offset << " " << c;
          EXPECT_LT(estimate[c], 1.25f * exact[c]) << r << " " << offset << " " << c;
        }
      }
    }
  }
}

TEST(Geometry, RaySphereDistances) {
  AtmosphereParams a{};
  a.bottom_radius = 6360e3f;
  a.top_radius = 6420e3f;
  EXPECT_NEAR(distance_to_top_atmosphere_boundary(a, 6360e3f, 1.0f), 60e3f, 1.0f);
  EXPECT_NEAR(distance_to_bottom_atmosphere_boundary(a, 6370e3f, -1.0f), 10e3f, 1.0f);
  EXPECT_TRUE(ray_intersects_ground(a, 6370e3f, -0.5f));
  EXPECT_FALSE(ray_intersects_ground(a, 6370e3f, 0.0f));
  // Horizontal ray from the ground to the top: sqrt(R_top² - R²).
  EXPECT_NEAR(distance_to_top_atmosphere_boundary(a, 6360e3f, 0.0f), std::sqrt(6420e3 * 6420e3 - 6360e3 * 6360e3), 2.0f);
}

// The warp of the scattering tables' mu axis (scattering_u_mu,
// scattering_mu_log_weight): by vertical optical depth at 550 nm, so that
// only optically thick atmospheres get it. The presets' depths are those of
// their data files (docs/preset-sources.md): Earth's Rayleigh 0.098, ozone
// and continental aerosol 0.27 in all; Venus's cloud deck 30 over 17 of CO2.
TEST(MuWarp, OnlyOpticallyThickAtmospheresAreWarped) {
  auto depth_and_weight = [](const atmos::Atmosphere& a) {
    const AtmosphereParams p = make_atmosphere_params(a, atmos::TableSizes{}, 0);
    const double tau = vertical_optical_depth_550(a, p);
    EXPECT_EQ(double(p.scattering_mu_log_weight), double(float(scattering_mu_log_weight(tau))));
    return std::pair<double, double>(tau, p.scattering_mu_log_weight);
  };
  for (const char* name : {"earth", "mars", "mars-thesis", "titan"}) {
    const auto [tau, w] = depth_and_weight(atmos::load_atmosphere(name));
    EXPECT_LT(tau, kMuLogWarpOpticalDepth[0]) << name;
    EXPECT_EQ(w, 0.0) << name;
  }
  const auto [earth_tau, earth_w] = depth_and_weight(atmos::load_atmosphere("earth"));
  EXPECT_GT(earth_tau, 0.2);
  EXPECT_LT(earth_tau, 0.35);
  const auto [venus_tau, venus_w] = depth_and_weight(atmos::load_atmosphere("venus"));
  EXPECT_GT(venus_tau, 40.0);
  EXPECT_LT(venus_tau, 55.0);
  EXPECT_EQ(venus_w, 1.0);
  // 100x Earth: 100 times the column, partly warped.
  atmos::Atmosphere dense = atmos::load_atmosphere("earth");
  atmos::scale_density(dense, 100.0);
  const auto [dense_tau, dense_w] = depth_and_weight(dense);
  EXPECT_NEAR(dense_tau, 100.0 * earth_tau, 1e-3 * dense_tau);
  EXPECT_GT(dense_w, 0.9);
  EXPECT_LT(dense_w, 1.0);
  // The weight is a smoothstep in log τ: 0 and 1 at the ends, 1/2 at their
  // geometric mean, monotonic.
  EXPECT_EQ(scattering_mu_log_weight(kMuLogWarpOpticalDepth[0]), 0.0);
  EXPECT_EQ(scattering_mu_log_weight(kMuLogWarpOpticalDepth[1]), 1.0);
  EXPECT_NEAR(scattering_mu_log_weight(std::sqrt(kMuLogWarpOpticalDepth[0] * kMuLogWarpOpticalDepth[1])), 0.5, 1e-12);
  for (double tau = 1.0; tau < 100.0; tau *= 1.1)
    EXPECT_LE(scattering_mu_log_weight(tau), scattering_mu_log_weight(tau * 1.1));
}

// The multiple scattering's nodes are uniform in optical depth over the
// first optical depths of each view ray (source_integration_nodes) in
// atmospheres of several optical depths only: Earth, both Mars and 10x Earth
// keep nodes that follow the transmittance (bit for bit: 0), Titan, Venus
// and 100x Earth get (nearly) the full kSourceFlatOpticalDepth, and the
// weight rises monotonically in between.
TEST(SourceNodes, UniformInOpticalDepthOnlyWhereTheAtmosphereIsThick) {
  auto flat = [](const atmos::Atmosphere& a) {
    const AtmosphereParams p = make_atmosphere_params(a, atmos::TableSizes{}, 0);
    EXPECT_EQ(double(p.source_flat_optical_depth),
              double(float(source_flat_optical_depth(vertical_optical_depth_550(a, p)))));
    return double(p.source_flat_optical_depth);
  };
  for (const char* name : {"earth", "mars", "mars-thesis"}) EXPECT_EQ(flat(atmos::load_atmosphere(name)), 0.0) << name;
  atmos::Atmosphere ten = atmos::load_atmosphere("earth");
  atmos::scale_density(ten, 10.0);
  EXPECT_EQ(flat(ten), 0.0);
  atmos::Atmosphere hundred = atmos::load_atmosphere("earth");
  atmos::scale_density(hundred, 100.0);
  EXPECT_EQ(flat(hundred), kSourceFlatOpticalDepth);
  EXPECT_EQ(flat(atmos::load_atmosphere("venus")), kSourceFlatOpticalDepth);
  EXPECT_GT(flat(atmos::load_atmosphere("titan")), 0.95 * kSourceFlatOpticalDepth);
  EXPECT_EQ(source_flat_optical_depth(kSourceFlatOpticalDepthRange[0]), 0.0);
  EXPECT_EQ(source_flat_optical_depth(kSourceFlatOpticalDepthRange[1]), kSourceFlatOpticalDepth);
  for (double tau = 1.0; tau < 20.0; tau *= 1.1)
    EXPECT_LE(source_flat_optical_depth(tau), source_flat_optical_depth(tau * 1.1));
}

// The r axis follows the optical depth in the same atmospheres, and only in
// them: elsewhere it is Bruneton's x_r = rho / H, bit for bit.
TEST(RAxis, OnlyOpticallyThickAtmospheresFollowTheOpticalDepth) {
  for (const char* name : {"earth", "mars", "mars-thesis", "titan"}) {
    const AtmosphereParams p = make_atmosphere_params(atmos::load_atmosphere(name), atmos::TableSizes{}, 0);
    EXPECT_EQ(p.scattering_r_optical_depth_weight, 0.0f) << name;
    for (float s = 0.0f; s <= 1.0f; s += 1.0f / 97.0f) {
      EXPECT_EQ(scattering_x_r_from_rho_fraction(p, s), s) << name;
      EXPECT_EQ(rho_fraction_from_scattering_x_r(p, s), s) << name;
    }
  }
  atmos::Atmosphere dense = atmos::load_atmosphere("earth");
  atmos::scale_density(dense, 100.0);
  for (const atmos::Atmosphere& a : {atmos::load_atmosphere("venus"), dense}) {
    const AtmosphereParams p = make_atmosphere_params(a, atmos::TableSizes{}, 0);
    EXPECT_FLOAT_EQ(p.scattering_r_optical_depth_weight,
                    float(kScatteringROpticalDepthShare * p.scattering_mu_log_weight));
    EXPECT_GT(p.scattering_r_optical_depth_weight, 0.4f);
  }
}

class VenusParams : public ::testing::Test {
 protected:
  void SetUp() override {
    params = make_atmosphere_params(atmos::load_atmosphere("venus"), atmos::TableSizes{}, 0);
    ASSERT_EQ(params.scattering_mu_log_weight, 1.0f);
  }
  AtmosphereParams params{};
};

// Venus's r axis: from 0 at the ground to 1 at the top, increasing, its
// inverse exact, and the cloud deck (47-90 km, optical depth 30 of 47) gets
// 14 of the 32 texels instead of Bruneton's 8: the texels of rho / H crowd
// near the ground, those of the optical depth into the cloud, and the axis
// mixes the two half and half.
TEST_F(VenusParams, RAxisGivesTheCloudDeckTexels) {
  const float w = params.scattering_r_optical_depth_weight;
  ASSERT_EQ(w, float(kScatteringROpticalDepthShare));
  EXPECT_EQ(params.scattering_r_axis[0], 0.0f);
  EXPECT_EQ(params.scattering_r_axis[SCATTERING_R_AXIS_KNOTS - 1], 1.0f);
  for (int i = 1; i < SCATTERING_R_AXIS_KNOTS; ++i) {
    // At least the rho / H part of each step: the optical depth only adds.
    EXPECT_GE(params.scattering_r_axis[i] - params.scattering_r_axis[i - 1],
              0.999f * (1.0f - w) / float(SCATTERING_R_AXIS_KNOTS - 1))
        << i;
  }
  for (float x = 0.0f; x <= 1.0f; x += 1.0f / 1013.0f) {
    const float s = rho_fraction_from_scattering_x_r(params, x);
    EXPECT_NEAR(scattering_x_r_from_rho_fraction(params, s), x, 2e-6f) << x;
  }
  AtmosphereParams bruneton = params;
  bruneton.scattering_r_optical_depth_weight = 0.0f;
  auto texels = [&](const AtmosphereParams& p, float low_m, float high_m) {
    return (scattering_u_r(p, p.bottom_radius + high_m) - scattering_u_r(p, p.bottom_radius + low_m)) *
           float(p.scattering_r_size);
  };
  const float cloud = texels(params, 47e3f, 90e3f), cloud_bruneton = texels(bruneton, 47e3f, 90e3f);
  std::printf("cloud deck (47-90 km): %.1f texels (Bruneton's %.1f) of %d\n", double(cloud), double(cloud_bruneton),
              params.scattering_r_size);
  EXPECT_LT(cloud_bruneton, 9.0f);
  EXPECT_GT(cloud, 13.0f);
  // The lowest kilometre keeps texels below 1 km (rho / H: 3 of 32).
  EXPECT_GT(texels(params, 0.0f, 1e3f), 1.0f);
}

// The irradiance rows of an optically thick atmosphere (irradiance_x_r):
// the bottom row is the ground and the top row the top, the axis increases
// and its inverse (a bisection) round-trips, the lowest 3 km, where terrain
// is lit and the sky light changes most, get several rows instead of half of
// one, and the cloud deck keeps at least the rows of the linear axis (its
// optical depth part). Earth's rows stay linear in altitude.
TEST_F(VenusParams, IrradianceRowsCrowdNearTheGroundAndFollowTheCloud) {
  const int n = params.irradiance_r_size;
  const float top = params.top_radius - params.bottom_radius;
  auto row = [&](const AtmosphereParams& p, float altitude_m) {
    return irradiance_uv_from_r_mu_s(p, p.bottom_radius + altitude_m, 0.5f).y * float(n) - 0.5f;
  };
  EXPECT_EQ(row(params, 0.0f), 0.0f);
  EXPECT_NEAR(row(params, top), float(n - 1), 1e-4f);
  float previous = -1.0f;
  for (float h = 0.0f; h <= top; h += 250.0f) {
    const float x = irradiance_x_r(params, params.bottom_radius + h);
    EXPECT_GT(x, previous) << h;
    previous = x;
    for (float mu_s : {params.mu_s_min + 0.01f, 0.0f, 0.3f, 1.0f}) {
      float r2, mu_s2;
      r_mu_s_from_irradiance_uv(params, irradiance_uv_from_r_mu_s(params, params.bottom_radius + h, mu_s), r2, mu_s2);
      EXPECT_NEAR(r2 - params.bottom_radius, h, 1.0f) << h;
      EXPECT_NEAR(mu_s2, mu_s, 2e-4f) << h;
    }
  }
  // The texel centres the precomputation computes map back to their rows.
  for (int y = 0; y < n; ++y) {
    float r, mu_s;
    r_mu_s_from_irradiance_uv(params, vec2(0.5f, (float(y) + 0.5f) / float(n)), r, mu_s);
    EXPECT_NEAR(row(params, r - params.bottom_radius), float(y), 1e-3f) << y;
  }
  AtmosphereParams linear = params;
  linear.scattering_r_optical_depth_weight = 0.0f;
  std::printf("rows below 3 km: %.2f (linear %.2f); in the cloud deck (47-75 km): %.2f (linear %.2f) of %d\n",
              double(row(params, 3e3f)), double(row(linear, 3e3f)), double(row(params, 75e3f) - row(params, 47e3f)),
              double(row(linear, 75e3f) - row(linear, 47e3f)), n);
  EXPECT_NEAR(row(linear, 3e3f), 3e3f / top * float(n - 1), 1e-4f);
  EXPECT_GT(row(params, 3e3f), 4.0f * row(linear, 3e3f));
  EXPECT_GT(row(params, 75e3f) - row(params, 47e3f), row(linear, 75e3f) - row(linear, 47e3f));
  const AtmosphereParams earth = make_atmosphere_params(atmos::load_atmosphere("earth"), atmos::TableSizes{}, 0);
  ASSERT_EQ(earth.scattering_r_optical_depth_weight, 0.0f);
  EXPECT_FLOAT_EQ(row(earth, 30e3f), 30e3f / (earth.top_radius - earth.bottom_radius) * float(n - 1));
}

// The warped axis still maps texture coordinates back to the rays they came
// from, up and down, at every altitude.
TEST_F(VenusParams, WarpedScatteringMappingRoundTrips) { expect_scattering_mapping_round_trips(params, 13, 4000); }

// What the warp is for: at 65 km, inside Venus's cloud deck, the directions
// from the zenith to 60° from it get one texel of Bruneton's axis (linear in
// the distance to the top) and many of the warped one. Each half of the axis
// stays monotonic: u falls from the nadir (0.5) to the horizon (0), then
// from the zenith (0.5) to the horizon (1) as the distance grows.
TEST_F(VenusParams, WarpGivesTheUpperHemisphereTexelsInsideTheCloud) {
  const float r = params.bottom_radius + 65e3f;
  AtmosphereParams linear = params;
  linear.scattering_mu_log_weight = 0.0f;
  auto texels = [&](const AtmosphereParams& p, float mu_a, float mu_b) {
    const bool ground = ray_intersects_ground(p, r, mu_a);
    return std::abs(scattering_u_mu(p, r, mu_b, ground) - scattering_u_mu(p, r, mu_a, ground)) *
           float(p.scattering_mu_size);
  };
  const float linear_texels = texels(linear, 0.5f, 1.0f), warped_texels = texels(params, 0.5f, 1.0f);
  std::printf("zenith to 60 deg at 65 km: %.2f texels (linear), %.2f (warped) of %d\n", double(linear_texels),
              double(warped_texels), params.scattering_mu_size);
  EXPECT_LT(linear_texels, 2.0f);
  EXPECT_GT(warped_texels, 8.0f);
  // The half of the axis below the horizontal keeps texels too.
  const float mu_h = horizon_mu(params, r);
  EXPECT_GT(texels(params, mu_h + 1e-4f, 0.0f), 8.0f);
  float previous[2] = {1.0f, 1.0f};  // the last u of each half (0: above the horizon, 1: below)
  for (float mu = -1.0f; mu <= 1.0f; mu += 1.0f / 512.0f) {
    const bool ground = ray_intersects_ground(params, r, mu);
    const float u_mu = scattering_u_mu(params, r, mu, ground);
    EXPECT_EQ(u_mu < 0.5f, ground) << "mu " << mu;
    EXPECT_LE(u_mu, previous[ground ? 1 : 0]) << "mu " << mu;
    previous[ground ? 1 : 0] = u_mu;
  }
}

}  // namespace
