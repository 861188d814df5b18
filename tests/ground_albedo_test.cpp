// The tables over a runtime ground albedo (tables_for_ground_albedo) against
// tables precomputed directly over that albedo, the series' invariants, and
// the cache of the ground response.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <glm/common.hpp>

#include <epoxy/gl.h>

#include <glm/gtc/matrix_transform.hpp>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/globe.hpp"
#include "atmos/plugin.hpp"
#include "atmos/renderer.hpp"
#include "atmos/tables.hpp"
#include "figures.hpp"
#include "table_sizes.hpp"

namespace {

atmos::PrecomputeOptions options(bool response) {
  atmos::PrecomputeOptions o;
  o.sizes = atmos_test::small_gpu_sizes();
  o.scattering_orders = 6;
  o.ground_albedo_response = response;
  return o;
}

atmos::Atmosphere with_albedo(atmos::Atmosphere a, double albedo) {
  a.ground_albedo = atmos::Spectrum::constant(albedo);
  return a;
}

// The largest relative difference of the albedo-dependent tables, over
// texels holding more than `floor` of the table's largest value per channel,
// and the difference of their sums.
struct Difference {
  double max_relative = 0.0;
  double sum_relative = 0.0;
};

Difference compare(const std::vector<glm::vec3>& got, const std::vector<glm::vec3>& want, double floor) {
  glm::dvec3 largest(0.0), sum_got(0.0), sum_want(0.0);
  for (const glm::vec3& v : want) largest = glm::max(largest, glm::dvec3(v));
  Difference d;
  for (size_t i = 0; i < want.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      sum_got[c] += got[i][c];
      sum_want[c] += want[i][c];
      if (want[i][c] > floor * largest[c])
        d.max_relative = std::max(d.max_relative, std::abs(double(got[i][c]) - want[i][c]) / want[i][c]);
    }
  for (int c = 0; c < 3; ++c)
    d.sum_relative = std::max(d.sum_relative, std::abs(sum_got[c] - sum_want[c]) / sum_want[c]);
  return d;
}

class GroundAlbedo : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    earth_ = new atmos::Atmosphere(atmos::load_atmosphere("earth"));
    tables_ = new atmos::Tables(atmos::precompute_tables(*earth_, options(true)));
  }
  static void TearDownTestSuite() {
    delete tables_;
    delete earth_;
  }
  static atmos::Atmosphere* earth_;
  static atmos::Tables* tables_;
};
atmos::Atmosphere* GroundAlbedo::earth_ = nullptr;
atmos::Tables* GroundAlbedo::tables_ = nullptr;

// The blended tables against tables precomputed over the albedo itself.
// The series is exact at the planet's albedo and at the response's; between
// and beyond it assumes that every reflection's light has the first one's
// angular distribution. Over Earth (three wavelengths and 15) and Mars
// at albedos 0.05-0.8: the sums of every table within 1 %, the
// texels above 1e-3 of their table's largest within 1.8 % (Earth) and 3.6 %
// (Mars at albedo 0.05, where the reddish planet albedo 0.28/0.17/0.09 is
// extrapolated towards 0). Without the series (the planet's tables as they
// are) the scattering over a ground of albedo 0.8 is 40 % low over Earth.
void expect_matches_direct(const atmos::Atmosphere& planet, const std::vector<double>& albedos, double max_texel) {
  const atmos::Tables tables = atmos::precompute_tables(planet, options(true));
  const atmos::GroundAlbedoResponse& g = tables.ground_response;
  std::printf("%s, %zu wavelengths: planet albedo %.3f %.3f %.3f, response %.3f %.3f %.3f, spherical albedo "
              "%.4f %.4f %.4f\n",
              planet.name.c_str(), planet.wavelengths_nm.size(), g.planet_albedo.x, g.planet_albedo.y,
              g.planet_albedo.z, g.albedo.x, g.albedo.y, g.albedo.z, g.spherical_albedo.x, g.spherical_albedo.y,
              g.spherical_albedo.z);
  for (double a : albedos) {
    const atmos::Tables direct = atmos::precompute_tables(with_albedo(planet, a), options(false));
    const atmos::TableSet blended = atmos::tables_for_ground_albedo(tables, glm::vec3(float(a)));
    const Difference e = compare(blended.indirect_irradiance, direct.set.indirect_irradiance, 1e-3);
    const Difference s = compare(blended.scattering, direct.set.scattering, 1e-3);
    const Difference m = compare(blended.multiple_scattering, direct.set.multiple_scattering, 1e-3);
    const Difference uncorrected = compare(tables.set.scattering, direct.set.scattering, 1e-3);
    std::printf("  albedo %.2f: sky irradiance max %.4f sum %.4f | scattering max %.4f sum %.4f | multiple max "
                "%.4f sum %.4f | the planet's tables: scattering sum %.4f\n",
                a, e.max_relative, e.sum_relative, s.max_relative, s.sum_relative, m.max_relative, m.sum_relative,
                uncorrected.sum_relative);
    char config[96];
    std::snprintf(config, sizeof config, "%s %zu wavelengths, albedo %.2f", planet.name.c_str(),
                  planet.wavelengths_nm.size(), a);
    atmos_test::record_figure(std::string("largest table sum error, ") + config,
                              100.0 * std::max({e.sum_relative, s.sum_relative, m.sum_relative}), "%", "<= 1 %");
    atmos_test::record_figure(std::string("largest texel error, ") + config,
                              100.0 * std::max({e.max_relative, s.max_relative, m.max_relative}), "%",
                              "<= " + std::to_string(int(std::lround(100.0 * max_texel))) + " %");
    atmos_test::record_figure(std::string("scattering sum error without the series, ") + config,
                              100.0 * uncorrected.sum_relative, "%", "");
    for (const Difference& d : {e, s, m}) {
      EXPECT_LE(d.sum_relative, 0.01) << planet.name << " albedo " << a;
      EXPECT_LE(d.max_relative, max_texel) << planet.name << " albedo " << a;
    }
    // The correction matters: it removes most of the planet's tables' error.
    if (std::abs(a - g.planet_albedo.y) > 0.2) {
      EXPECT_LT(s.sum_relative, 0.1 * uncorrected.sum_relative) << planet.name << " albedo " << a;
    }
  }
  // Unchanged: the single scattering and the direct sunlight do not depend on the ground.
  const atmos::TableSet dark = atmos::tables_for_ground_albedo(tables, glm::vec3(0.0f));
  EXPECT_EQ(dark.single_aerosol, tables.set.single_aerosol);
  EXPECT_EQ(dark.direct_irradiance, tables.set.direct_irradiance);
}

TEST(GroundAlbedoSeries, EarthMatchesTablesPrecomputedOverThatAlbedo) {
  expect_matches_direct(atmos::load_atmosphere("earth"), {0.05, 0.3, 0.8}, 0.02);
}

TEST(GroundAlbedoSeries, MarsMatchesTablesPrecomputedOverThatAlbedo) {
  expect_matches_direct(atmos::load_atmosphere("mars"), {0.05, 0.8}, 0.04);
}

TEST(GroundAlbedoSeries, SpectralEarthMatchesTablesPrecomputedOverThatAlbedo) {
  atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  earth.wavelengths_nm = atmos::spectral_wavelengths(15);
  expect_matches_direct(earth, {0.05, 0.8}, 0.02);
}

TEST_F(GroundAlbedo, ExactAtTheTwoPrecomputedAlbedos) {
  const atmos::GroundAlbedoResponse& g = tables_->ground_response;
  EXPECT_EQ(g.planet_albedo, glm::vec3(0.1f));
  EXPECT_EQ(g.albedo, glm::vec3(1.0f));
  const atmos::TableSet planet = atmos::tables_for_ground_albedo(*tables_, g.planet_albedo);
  EXPECT_EQ(planet.scattering, tables_->set.scattering);
  EXPECT_EQ(planet.indirect_irradiance, tables_->set.indirect_irradiance);
  const atmos::TableSet response = atmos::tables_for_ground_albedo(*tables_, g.albedo);
  const Difference s = compare(response.scattering, g.scattering, 0.0);
  const Difference m = compare(response.multiple_scattering, g.multiple_scattering, 0.0);
  const Difference e = compare(response.indirect_irradiance, g.indirect_irradiance, 0.0);
  EXPECT_LE(std::max({s.max_relative, m.max_relative, e.max_relative}), 1e-5);
}

// The spherical albedo seen from below: for an optically thin atmosphere
// about the part of its optical depth that scatters (Earth's Rayleigh
// optical depth is 0.04 at 680 nm, 0.1 at 550 nm, 0.24 at 440 nm, with a
// thin aerosol), so between a few hundredths and a few tenths, and larger
// in the blue.
TEST_F(GroundAlbedo, SphericalAlbedoOfEarthIsPhysical) {
  const glm::vec3 s = tables_->ground_response.spherical_albedo;
  EXPECT_GT(s.x, 0.03f);
  EXPECT_LT(s.x, s.y);
  EXPECT_LT(s.y, s.z);
  EXPECT_LT(s.z, 0.25f);
}

// Energy: a brighter ground sends more light up through the air, and the sky
// light on the ground grows with it; all of it stays finite and positive.
TEST_F(GroundAlbedo, LightGrowsWithTheAlbedo) {
  double previous_sky = -1.0, previous_ground = -1.0;
  for (float a : {0.0f, 0.2f, 0.4f, 0.6f, 0.8f, 1.0f}) {
    const atmos::TableSet t = atmos::tables_for_ground_albedo(*tables_, glm::vec3(a));
    double sky = 0.0, ground = 0.0;
    for (const glm::vec3& v : t.scattering) {
      ASSERT_TRUE(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
      ASSERT_GE(std::min({v.x, v.y, v.z}), 0.0f);
      sky += double(v.y);
    }
    for (const glm::vec3& v : t.indirect_irradiance) ground += double(v.y);
    EXPECT_GT(sky, previous_sky) << a;
    EXPECT_GT(ground, previous_ground) << a;
    previous_sky = sky;
    previous_ground = ground;
  }
}

TEST_F(GroundAlbedo, RejectsBadInput) {
  const auto expect_error = [](const std::function<void()>& f, const std::string& part) {
    try {
      f();
      ADD_FAILURE() << "no error, expected one about " << part;
    } catch (const atmos::Error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  expect_error([&] { atmos::tables_for_ground_albedo(*tables_, glm::vec3(0.2f, 1.5f, 0.2f)); }, "[0, 1]");
  expect_error([&] { atmos::tables_for_ground_albedo(*tables_, glm::vec3(-0.1f)); }, "[0, 1]");
  expect_error([&] { atmos::tables_for_ground_albedo(*tables_, glm::vec3(std::nanf(""))); }, "[0, 1]");
  atmos::Tables plain = *tables_;
  plain.ground_response = atmos::GroundAlbedoResponse();
  expect_error([&] { atmos::tables_for_ground_albedo(plain, glm::vec3(0.3f)); }, "no ground albedo response");
  atmos::Tables truncated = *tables_;
  truncated.ground_response.scattering.pop_back();
  expect_error([&] { atmos::check_tables_match(*earth_, truncated); }, "ground albedo response");
  // A planet whose albedo spectrum crosses 0.5 inside a channel leaves no
  // second albedo far enough from its own there.
  atmos::Atmosphere striped = *earth_;
  striped.wavelengths_nm = atmos::spectral_wavelengths(15);
  std::vector<double> w, v;
  for (double l = 360.0; l <= 830.0; l += 5.0) {
    w.push_back(l);
    v.push_back(int((l - 360.0) / 5.0) % 2 == 0 ? 0.2 : 0.8);
  }
  striped.ground_albedo = atmos::Spectrum(w, v);
  expect_error([&] { atmos::precompute_tables(striped, options(true)); }, "crosses 0.5");
}

// The cache stores the response with the tables (its own key), and reads it
// back bit for bit.
TEST_F(GroundAlbedo, CacheKeepsTheResponse) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "atmos-ground-albedo-cache";
  std::filesystem::remove_all(dir);
  EXPECT_NE(atmos::tables_cache_key(*earth_, options(true)), atmos::tables_cache_key(*earth_, options(false)));
  const atmos::CacheResult first = atmos::load_or_precompute_tables(*earth_, options(true), dir.string());
  const atmos::CacheResult second = atmos::load_or_precompute_tables(*earth_, options(true), dir.string());
  EXPECT_EQ(second.status, atmos::CacheStatus::hit);
  const atmos::GroundAlbedoResponse& a = first.tables.ground_response;
  const atmos::GroundAlbedoResponse& b = second.tables.ground_response;
  EXPECT_EQ(a.albedo, b.albedo);
  EXPECT_EQ(a.planet_albedo, b.planet_albedo);
  EXPECT_EQ(a.spherical_albedo, b.spherical_albedo);
  EXPECT_EQ(a.scattering, b.scattering);
  EXPECT_EQ(a.multiple_scattering, b.multiple_scattering);
  EXPECT_EQ(a.indirect_irradiance, b.indirect_irradiance);
  // Tables without a response are another file.
  const atmos::CacheResult plain = atmos::load_or_precompute_tables(*earth_, options(false), dir.string());
  EXPECT_NE(plain.status, atmos::CacheStatus::hit);
  EXPECT_TRUE(plain.tables.ground_response.empty());
  std::filesystem::remove_all(dir);
}


// --- The engine plugin over a runtime ground albedo ------------------------

// A frame of sky and planet (nothing drawn by the engine) from 10 m above
// the ground, looking at the horizon, at 64 x 32 pixels.
std::vector<glm::vec3> render_sky(atmos::AtmospherePass& pass) {
  constexpr int kWidth = 64, kHeight = 32;
  GLuint textures[2] = {0, 0};
  glCreateTextures(GL_TEXTURE_2D, 2, textures);
  glTextureStorage2D(textures[0], 1, GL_R32F, kWidth, kHeight);
  const std::vector<float> far(size_t(kWidth) * kHeight, 1.0f);
  glTextureSubImage2D(textures[0], 0, 0, 0, kWidth, kHeight, GL_RED, GL_FLOAT, far.data());
  glTextureStorage2D(textures[1], 1, GL_RGB32F, kWidth, kHeight);
  const std::vector<glm::vec3> black(far.size(), glm::vec3(0.0f));
  glTextureSubImage2D(textures[1], 0, 0, 0, kWidth, kHeight, GL_RGB, GL_FLOAT, black.data());
  atmos::FrameInput in;
  in.depth = textures[0];
  in.colour = textures[1];
  in.width = kWidth;
  in.height = kHeight;
  const double radius = 6360e3;
  const glm::dvec3 eye(0.0, 0.0, radius + 10.0);
  in.view = glm::lookAt(eye, eye + glm::dvec3(1.0, 0.0, -0.05), glm::dvec3(0.0, 0.0, 1.0));
  in.projection = glm::perspective(glm::radians(60.0), 2.0, 1.0, 1e7);
  in.sun_direction = glm::normalize(glm::dvec3(-0.5, 0.3, 0.6));
  in.sun_disc = false;
  const GLuint out = pass.render(in);
  std::vector<float> rgba(far.size() * 4);
  glGetTextureImage(out, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
  glDeleteTextures(2, textures);
  std::vector<glm::vec3> rgb(far.size());
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = {rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]};
  return rgb;
}

class GroundAlbedoGpu : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    earth_ = new atmos::Atmosphere(atmos::load_atmosphere("earth"));
    tables_ = new atmos::Tables(atmos::precompute_tables(*earth_, options(true)));
    try {
      context_ = atmos::GlContext::create_headless().release();
    } catch (const atmos::Error& e) {
      error_ = e.what();
    }
  }
  static void TearDownTestSuite() {
    delete context_;
    delete tables_;
    delete earth_;
  }
  void SetUp() override { ASSERT_TRUE(context_ != nullptr) << error_; }
  static inline atmos::Atmosphere* earth_ = nullptr;
  static inline atmos::Tables* tables_ = nullptr;
  static inline atmos::GlContext* context_ = nullptr;
  static inline std::string error_;
};

// set_ground_albedo uploads exactly tables_for_ground_albedo's tables: the
// frame equals that of a pass built from them, a bright ground brightens the
// sky, and going back to the planet's albedo gives the first frame again.
TEST_F(GroundAlbedoGpu, PassFollowsTheGroundAlbedo) {
  const atmos::PlanetFrame frame;
  atmos::AtmospherePass pass(*earth_, *tables_, frame, atmos::PassPrograms::none);
  EXPECT_EQ(pass.ground_albedo(), glm::dvec3(glm::vec3(0.1f)));
  const std::vector<glm::vec3> planet = render_sky(pass);
  pass.set_ground_albedo(glm::dvec3(0.8));
  EXPECT_EQ(pass.ground_albedo(), glm::dvec3(0.8));
  const std::vector<glm::vec3> snow = render_sky(pass);

  atmos::Tables blended = *tables_;
  blended.set = atmos::tables_for_ground_albedo(*tables_, glm::vec3(0.8f));
  blended.ground_response = atmos::GroundAlbedoResponse();
  atmos::AtmospherePass direct(*earth_, blended, frame, atmos::PassPrograms::none);
  EXPECT_EQ(render_sky(direct), snow);

  double planet_sum = 0.0, snow_sum = 0.0;
  for (size_t i = 0; i < planet.size(); ++i) {
    planet_sum += double(planet[i].y);
    snow_sum += double(snow[i].y);
  }
  std::printf("sky and planet over a ground of albedo 0.8: %.1f %% brighter than over the planet's 0.1\n",
              100.0 * (snow_sum / planet_sum - 1.0));
  EXPECT_GT(snow_sum, 1.05 * planet_sum);

  pass.set_ground_albedo(glm::dvec3(glm::vec3(0.1f)));
  EXPECT_EQ(render_sky(pass), planet);
  // Changes of 0.001 or less keep the tables.
  pass.set_ground_albedo(glm::dvec3(0.1005));
  EXPECT_EQ(render_sky(pass), planet);

  EXPECT_THROW(pass.set_ground_albedo(glm::dvec3(0.2, 1.2, 0.2)), atmos::Error);
  EXPECT_THROW(direct.set_ground_albedo(glm::dvec3(0.3)), atmos::Error);  // no response
}


// The regional albedo of Earth's default surface (Blue Marble imagery,
// GSHHG coasts): the Sahara is bright, the open Pacific dark, the
// Antarctic ice brightest; from 2.5 radii the cap is the visible
// hemisphere, between the extremes. The pass takes it.
TEST_F(GroundAlbedoGpu, GlobeRegionalAlbedoFollowsTheGround) {
  const atmos::PlanetFrame frame;
  atmos::AtmospherePass pass(*earth_, *tables_, frame, atmos::PassPrograms::none);
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  const atmos::Globe globe(*earth_, atmos::load_surface("earth"), pass, settings);
  const auto above = [&](double lat_deg, double lon_deg, double altitude_m) {
    const double lat = glm::radians(lat_deg), lon = glm::radians(lon_deg);
    const glm::dvec3 up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
    return up * (earth_->bottom_radius_m + altitude_m);
  };
  const glm::dvec3 sahara = globe.regional_albedo(above(23.0, 12.0, 2.0));
  const glm::dvec3 pacific = globe.regional_albedo(above(-5.0, -140.0, 2.0));
  const glm::dvec3 antarctica = globe.regional_albedo(above(-82.0, 60.0, 10e3));
  const glm::dvec3 far = globe.regional_albedo(above(23.0, 12.0, 2.5 * earth_->bottom_radius_m));
  std::printf("regional albedo: Sahara %.3f %.3f %.3f, Pacific %.3f %.3f %.3f, Antarctica %.3f %.3f %.3f, "
              "2.5 radii above the Sahara %.3f %.3f %.3f\n",
              sahara.x, sahara.y, sahara.z, pacific.x, pacific.y, pacific.z, antarctica.x, antarctica.y,
              antarctica.z, far.x, far.y, far.z);
  EXPECT_GT(sahara.x, 0.25);
  EXPECT_GT(sahara.x, sahara.z);  // reddish sand
  EXPECT_LT(pacific.y, 0.1);
  EXPECT_GT(antarctica.y, 0.5);
  EXPECT_GT(far.y, pacific.y);
  EXPECT_LT(far.y, sahara.y);
  pass.set_ground_albedo(sahara);
  EXPECT_EQ(pass.ground_albedo(), sahara);
  EXPECT_THROW(globe.regional_albedo(glm::dvec3(NAN, 0.0, 0.0)), atmos::Error);
}
}  // namespace
