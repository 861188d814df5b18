// The stars of a catalogue drawn by the renderers (atmos::Star,
// Renderer::set_star_catalogue, render_cpu, AtmospherePass): where a star's
// image falls against the projection of its catalogue place, the ratio of
// two stars' light against their magnitudes, the photometry against the
// star's own irradiance, the atmosphere's attenuation near the horizon and
// the daylight that drowns them, the GPU against its CPU twin, and bad input.
#include <gtest/gtest.h>

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <utility>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/ephemeris.hpp"
#include "atmos/plugin.hpp"
#include "atmos/renderer.hpp"
#include "atmos/sky.hpp"
#include "atmos/star_catalogue.hpp"
#include "gpu/star_catalogue_bins.hpp"
#include "gpu_fixture.hpp"

namespace {

using atmos::Camera;
using atmos::Image;

class StarCatalogueGpu : public atmos_test::EarthGpuTest {};

constexpr double kEarthRadius = 6371e3;

double luminance(const Image& image, int x, int y) {
  const size_t i = 3 * (size_t(y) * size_t(image.width) + size_t(x));
  return atmos::srgb_luminance(glm::dvec3(image.rgb[i], image.rgb[i + 1], image.rgb[i + 2]));
}

// The pixel coordinates (x right, y down from the top-left corner, pixel
// centres at half-integers) of direction `d` in a perspective camera: the
// pinhole projection of camera.glsl, in double.
glm::dvec2 project(const Camera& c, const glm::dvec3& d) {
  const glm::dvec3 forward = glm::normalize(c.forward);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, c.up));
  const glm::dvec3 up = glm::cross(right, forward);
  const double scale = std::tan(glm::radians(c.fov_deg) * 0.5) / (0.5 * c.height);
  const double z = glm::dot(d, forward);
  return {0.5 * c.width + glm::dot(d, right) / z / scale, 0.5 * c.height - glm::dot(d, up) / z / scale};
}

// The light of a star's image: the centroid and the sum of `with - without`
// (luminance, cd/m²) over the pixels within `radius` of `around`.
struct Blob {
  glm::dvec2 centroid{0.0};
  double sum = 0.0;
};
Blob blob(const Image& with, const Image& without, const glm::dvec2& around, int radius = 4) {
  Blob b;
  glm::dvec2 weighted(0.0);
  for (int y = int(around.y) - radius; y <= int(around.y) + radius; ++y) {
    for (int x = int(around.x) - radius; x <= int(around.x) + radius; ++x) {
      if (x < 0 || y < 0 || x >= with.width || y >= with.height) continue;
      const double l = luminance(with, x, y) - luminance(without, x, y);
      b.sum += l;
      weighted += l * glm::dvec2(x + 0.5, y + 0.5);
    }
  }
  b.centroid = weighted / b.sum;
  return b;
}

// The solid angle of the pixel at the image centre of a perspective camera.
double centre_pixel_solid_angle(const Camera& c) {
  const double pixel = 2.0 * std::tan(glm::radians(c.fov_deg) * 0.5) / c.height;
  return pixel * pixel;
}

atmos::Star star_of(const glm::dvec3& direction, double v_magnitude, double temperature_k = 5772.0) {
  return {glm::normalize(direction), atmos::v_band_spectral_irradiance(v_magnitude), temperature_k};
}

// Orion over Vienna on a winter night: the catalogue's stars in the
// renderer's frame by the sidereal time of the date (stars_in_sky), and the
// same catalogue given in the true equator and equinox of the date and
// turned into that frame by Renderer::set_star_orientation. Betelgeuse and
// Rigel fall within 0.5 px of the projection of their places, either way;
// the GPU and CPU renderers agree on their light.
TEST_F(StarCatalogueGpu, CatalogueStarsFallOnTheProjectionOfTheirPlaces) {
  const atmos::Observer vienna{48.21, 16.37, 0.0};
  const atmos::Instant instant = atmos::instant_of(atmos::parse_utc_time("2025-01-29T20:30:00Z"));
  const std::vector<atmos::CatalogueStar> catalogue = atmos::load_bright_star_catalogue();
  const std::vector<atmos::SkyStar> sky = atmos::stars_in_sky(catalogue, instant, vienna);
  const atmos::SkyOfDate of_date = atmos::sky_of_date(instant, vienna);
  ASSERT_LT(of_date.sun.elevation_deg, -18.0);
  std::vector<atmos::Star> earth_fixed, equatorial;
  const double sidereal = atmos::greenwich_apparent_sidereal_time_deg(instant);
  for (size_t i = 0; i < sky.size(); ++i) {
    earth_fixed.push_back({sky[i].direction, sky[i].v_band_irradiance, sky[i].temperature_k});
    const atmos::EquatorialPosition p = atmos::apparent_place(
        {catalogue[i].right_ascension_deg, catalogue[i].declination_deg, 0.0}, instant.jd_tt);
    const double a = glm::radians(p.right_ascension_deg), d = glm::radians(p.declination_deg);
    equatorial.push_back({{std::cos(d) * std::cos(a), std::cos(d) * std::sin(a), std::sin(d)},
                          sky[i].v_band_irradiance, sky[i].temperature_k});
  }
  // The Earth's rotation: the columns are the equator's axes in the
  // Earth-fixed frame.
  glm::dmat3 rotation;
  for (int axis = 0; axis < 3; ++axis) {
    atmos::EquatorialPosition p;
    p.right_ascension_deg = axis == 1 ? 90.0 : 0.0;
    p.declination_deg = axis == 2 ? 90.0 : 0.0;
    rotation[axis] = atmos::earth_fixed_from_equatorial(p, sidereal);
  }
  auto find = [&](int hr) {
    for (const atmos::SkyStar& s : sky)
      if (s.bright_star_number == hr) return s;
    ADD_FAILURE() << "no HR " << hr;
    return atmos::SkyStar{};
  };
  const atmos::SkyStar betelgeuse = find(2061), rigel = find(1713);
  ASSERT_GT(betelgeuse.elevation_deg, 20.0);
  ASSERT_GT(rigel.elevation_deg, 15.0);

  const atmos::LocalFrame frame = atmos::local_frame(vienna);
  Camera camera;
  camera.position = frame.up * (kEarthRadius + 2.0);
  camera.forward = glm::normalize(betelgeuse.direction + rigel.direction);
  camera.up = frame.up;
  camera.fov_deg = 40.0;
  camera.width = 240;
  camera.height = 180;
  const glm::dvec3 sun = glm::normalize(of_date.sun.topocentric_m);

  atmos::Renderer renderer(*earth_, *tables_);
  const Image without = renderer.render(camera, sun);
  renderer.set_stars(true);
  renderer.set_star_catalogue(earth_fixed);
  const Image with = renderer.render(camera, sun);
  renderer.set_star_catalogue(equatorial);
  renderer.set_star_orientation(rotation);
  const Image turned = renderer.render(camera, sun);
  const Image cpu = atmos::render_cpu(*earth_, *tables_, camera, sun, true, {}, earth_fixed);

  for (const atmos::SkyStar& star : {betelgeuse, rigel}) {
    const glm::dvec2 expected = project(camera, star.direction);
    for (const Image* image : {&with, &turned}) {
      const Blob b = blob(*image, without, expected);
      const double error = glm::length(b.centroid - expected);
      std::printf("HR %d (V %.2f, elevation %.1f deg)%s: image centroid (%.3f, %.3f), projection (%.3f, %.3f): "
                  "%.4f px apart\n",
                  star.bright_star_number, star.v_magnitude, star.elevation_deg,
                  image == &turned ? " turned by the sidereal rotation" : "", b.centroid.x, b.centroid.y,
                  expected.x, expected.y, error);
      EXPECT_LT(error, 0.5);
    }
    const double gpu_light = blob(with, without, expected).sum;
    const double cpu_light = blob(cpu, without, expected).sum;
    EXPECT_NEAR(cpu_light / gpu_light, 1.0, 0.01);
  }
}

// The engine plugin draws the same stars where the renderer does: Orion's
// brightest over Vienna, through AtmospherePass over an empty engine frame
// (depth at the far plane, black colour) with the pinhole projection of the
// renderer's camera, the catalogue given in the equator of date and turned
// by FrameInput::world_from_star_catalogue. Centroids within 0.5 px of the
// projections, light within 1 % of the renderer's.
TEST_F(StarCatalogueGpu, ThePluginDrawsTheCatalogueWhereTheRendererDoes) {
  const atmos::Observer vienna{48.21, 16.37, 0.0};
  const atmos::Instant instant = atmos::instant_of(atmos::parse_utc_time("2025-01-29T20:30:00Z"));
  const std::vector<atmos::CatalogueStar> catalogue = atmos::load_bright_star_catalogue();
  const std::vector<atmos::SkyStar> sky = atmos::stars_in_sky(catalogue, instant, vienna);
  std::vector<atmos::Star> earth_fixed, equatorial;
  for (size_t i = 0; i < sky.size(); ++i) {
    earth_fixed.push_back({sky[i].direction, sky[i].v_band_irradiance, sky[i].temperature_k});
    const atmos::EquatorialPosition p = atmos::apparent_place(
        {catalogue[i].right_ascension_deg, catalogue[i].declination_deg, 0.0}, instant.jd_tt);
    const double a = glm::radians(p.right_ascension_deg), d = glm::radians(p.declination_deg);
    equatorial.push_back({{std::cos(d) * std::cos(a), std::cos(d) * std::sin(a), std::sin(d)},
                          sky[i].v_band_irradiance, sky[i].temperature_k});
  }
  const double sidereal = atmos::greenwich_apparent_sidereal_time_deg(instant);
  glm::dmat3 rotation;
  for (int axis = 0; axis < 3; ++axis) {
    atmos::EquatorialPosition p;
    p.right_ascension_deg = axis == 1 ? 90.0 : 0.0;
    p.declination_deg = axis == 2 ? 90.0 : 0.0;
    rotation[axis] = atmos::earth_fixed_from_equatorial(p, sidereal);
  }
  std::vector<atmos::SkyStar> orion;
  for (const atmos::SkyStar& s : sky)
    if (s.bright_star_number == 2061 || s.bright_star_number == 1713) orion.push_back(s);
  ASSERT_EQ(orion.size(), 2u);

  const atmos::LocalFrame frame = atmos::local_frame(vienna);
  Camera camera;
  camera.position = frame.up * (kEarthRadius + 2.0);
  camera.forward = glm::normalize(orion[0].direction + orion[1].direction);
  camera.up = frame.up;
  camera.fov_deg = 40.0;
  camera.width = 240;
  camera.height = 180;
  const glm::dvec3 sun = glm::normalize(atmos::sky_of_date(instant, vienna).sun.topocentric_m);

  // The renderer's image, with and without the stars.
  atmos::Renderer renderer(*earth_, *tables_);
  const Image without = renderer.render(camera, sun);
  renderer.set_stars(true);
  renderer.set_star_catalogue(earth_fixed);
  const Image rendered = renderer.render(camera, sun);

  // The plugin's, rows turned top-down.
  atmos::AtmospherePass pass(*earth_, *tables_, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  pass.set_star_catalogue(equatorial);
  const int w = camera.width, h = camera.height;
  GLuint depth = 0, colour = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &depth);
  glTextureStorage2D(depth, 1, GL_DEPTH_COMPONENT32F, w, h);
  const std::vector<float> far_plane(size_t(w) * size_t(h), 1.0f);
  glTextureSubImage2D(depth, 0, 0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, far_plane.data());
  glCreateTextures(GL_TEXTURE_2D, 1, &colour);
  glTextureStorage2D(colour, 1, GL_RGBA32F, w, h);
  const float black[4] = {0.0f, 0.0f, 0.0f, 1.0f};
  glClearTexImage(colour, 0, GL_RGBA, GL_FLOAT, black);
  atmos::FrameInput input;
  input.colour = colour;
  input.depth = depth;
  input.width = w;
  input.height = h;
  input.view = glm::lookAt(camera.position, camera.position + camera.forward, camera.up);
  input.projection = glm::perspective(glm::radians(camera.fov_deg), double(w) / double(h), 0.1, 1e8);
  input.sun_direction = sun;
  input.stars = true;
  input.world_from_star_catalogue = rotation;
  const GLuint output = pass.render(input);
  std::vector<float> rgba(size_t(w) * size_t(h) * 4);
  glGetTextureImage(output, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
  Image composited;
  composited.width = w;
  composited.height = h;
  composited.rgb.resize(size_t(w) * size_t(h) * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        composited.rgb[3 * (size_t(y) * size_t(w) + size_t(x)) + size_t(c)] =
            rgba[4 * (size_t(h - 1 - y) * size_t(w) + size_t(x)) + size_t(c)];
  // The plugin's star-less sky: the same frame without the stars.
  input.stars = false;
  const GLuint dark_output = pass.render(input);
  glGetTextureImage(dark_output, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
  glDeleteTextures(1, &depth);
  glDeleteTextures(1, &colour);
  Image plugin_without = composited;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        plugin_without.rgb[3 * (size_t(y) * size_t(w) + size_t(x)) + size_t(c)] =
            rgba[4 * (size_t(h - 1 - y) * size_t(w) + size_t(x)) + size_t(c)];

  for (const atmos::SkyStar& star : orion) {
    const glm::dvec2 expected = project(camera, star.direction);
    const Blob plugin = blob(composited, plugin_without, expected);
    const Blob reference = blob(rendered, without, expected);
    std::printf("HR %d through the plugin: centroid %.4f px from the projection; light %.5f of the renderer's\n",
                star.bright_star_number, glm::length(plugin.centroid - expected), plugin.sum / reference.sum);
    EXPECT_LT(glm::length(plugin.centroid - expected), 0.5);
    EXPECT_NEAR(plugin.sum / reference.sum, 1.0, 0.01);
  }
  input.world_from_star_catalogue = glm::dmat3(2.0);
  EXPECT_THROW(pass.render(input), atmos::Error);
}

// Two stars of the same colour 2.5 magnitudes apart, side by side 45° up
// (the same air in front of both), at night: their images' light is in the
// ratio 10^(-0.4 x 2.5) = 0.1 within 1 %. From above the atmosphere, one
// image's light times the pixels' solid angle is the star's own
// illuminance (star_srgb_irradiance, CIE-weighted) within 3 %: the three
// working wavelengths sample its blackbody.
TEST_F(StarCatalogueGpu, BrightnessFollowsTheMagnitudes) {
  Camera camera;
  camera.position = {0.0, 0.0, kEarthRadius + 2.0};
  camera.forward = atmos::direction_from_azimuth_elevation(0.0, 45.0);
  camera.up = {0.0, 0.0, 1.0};
  camera.fov_deg = 10.0;
  camera.width = camera.height = 128;
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, -30.0);
  const glm::dvec3 a = atmos::direction_from_azimuth_elevation(-1.5, 45.0);
  const glm::dvec3 b = atmos::direction_from_azimuth_elevation(1.5, 45.0);
  const double temperature = atmos::temperature_from_b_minus_v(0.65);
  atmos::Renderer renderer(*earth_, *tables_);
  const Image without = renderer.render(camera, sun);
  renderer.set_stars(true);
  renderer.set_star_catalogue({star_of(a, 1.0, temperature), star_of(b, 3.5, temperature)});
  const Image with = renderer.render(camera, sun);
  const double ratio = blob(with, without, project(camera, b)).sum / blob(with, without, project(camera, a)).sum;
  const double expected = std::pow(10.0, -0.4 * 2.5);
  std::printf("V 3.5 over V 1.0: %.5f (10^(-0.4 dm) = %.5f), %.3g relative error\n", ratio, expected,
              ratio / expected - 1.0);
  EXPECT_NEAR(ratio / expected, 1.0, 0.01);

  // From 200 km up, looking away from the planet: nothing in front of it.
  Camera space = camera;
  space.position = {0.0, 0.0, kEarthRadius + 200e3};
  space.forward = {0.0, 0.3, 1.0};
  const glm::dvec3 star = glm::normalize(glm::dvec3(0.01, 0.3, 1.0));
  renderer.set_star_catalogue({star_of(star, 1.0, temperature)});
  const Image alone = renderer.render(space, sun);
  renderer.set_stars(false);
  const Image dark = renderer.render(space, sun);
  const double illuminance = blob(alone, dark, project(space, star)).sum * centre_pixel_solid_angle(space);
  // The star's pixels are within 0.2° of the image centre: their solid
  // angles differ from the centre's by under 1e-5.
  const double reference = atmos::star_srgb_irradiance(1.0, 0.65).y;
  std::printf("V 1.0 from above the atmosphere: %.5g lux in its image, %.5g lux its own (%.3g relative)\n",
              illuminance, reference, illuminance / reference - 1.0);
  EXPECT_NEAR(illuminance / reference, 1.0, 0.03);

  // Colour: a red star (B-V 1.5, Betelgeuse in Hipparcos) and a blue one
  // (B-V -0.03, Rigel) from above the atmosphere: the red-to-blue ratio of
  // their images' light against that of their CIE-weighted irradiance,
  // within 8 % (the three working wavelengths' samples of the blackbody
  // through the renderer's matrix give -5.6 % and +4.2 %); the red star is
  // the redder by a factor of 4.7.
  renderer.set_stars(true);
  double red_over_blue[2] = {0.0, 0.0};
  int n = 0;
  for (double b_minus_v : {1.5, -0.03}) {
    renderer.set_star_catalogue({star_of(star, 1.0, atmos::temperature_from_b_minus_v(b_minus_v))});
    const Image coloured = renderer.render(space, sun);
    const glm::dvec2 at = project(space, star);
    glm::dvec3 sum(0.0);
    for (int y = int(at.y) - 4; y <= int(at.y) + 4; ++y)
      for (int x = int(at.x) - 4; x <= int(at.x) + 4; ++x)
        for (int c = 0; c < 3; ++c) {
          const size_t i = 3 * (size_t(y) * size_t(coloured.width) + size_t(x)) + size_t(c);
          sum[c] += double(coloured.rgb[i]) - double(dark.rgb[i]);
        }
    const glm::dvec3 own = atmos::star_srgb_irradiance(1.0, b_minus_v);
    std::printf("B-V %+.2f: red/blue %.4f in the image, %.4f of its irradiance\n", b_minus_v, sum.x / sum.z,
                own.x / own.z);
    EXPECT_NEAR((sum.x / sum.z) / (own.x / own.z), 1.0, 0.08) << "B-V " << b_minus_v;
    red_over_blue[n++] = sum.x / sum.z;
  }
  EXPECT_GT(red_over_blue[0], 4.0 * red_over_blue[1]);
}

// The atmosphere in front of a star: the same star 60° up and 3° up on a
// moonless night gives less light near the horizon (the air mass there is
// about 15 times the zenith's); by day (the sun 40° up) a star of V = -1.5
// in a 30° view adds under 1 % to the sky's light at its pixel, while at
// night (the sun 30° down) it adds more than ten times the sky's light.
TEST_F(StarCatalogueGpu, TheAtmosphereDimsStarsAtTheHorizonAndDrownsThemByDay) {
  atmos::Renderer renderer(*earth_, *tables_);
  Camera camera;
  camera.position = {0.0, 0.0, kEarthRadius + 2.0};
  camera.up = {0.0, 0.0, 1.0};
  camera.fov_deg = 30.0;
  camera.width = 160;
  camera.height = 120;
  const glm::dvec3 night = atmos::direction_from_azimuth_elevation(180.0, -30.0);
  double light[2] = {0.0, 0.0};
  int k = 0;
  for (double elevation : {60.0, 3.0}) {
    camera.forward = atmos::direction_from_azimuth_elevation(0.0, elevation);
    const glm::dvec3 star = atmos::direction_from_azimuth_elevation(0.5, elevation);
    renderer.set_stars(false);
    const Image without = renderer.render(camera, night);
    renderer.set_stars(true);
    renderer.set_star_catalogue({star_of(star, 1.0)});
    const Image with = renderer.render(camera, night);
    light[k++] = blob(with, without, project(camera, star)).sum;
  }
  std::printf("a V 1.0 star at 3 deg gives %.3g of its light at 60 deg\n", light[1] / light[0]);
  EXPECT_LT(light[1] / light[0], 0.7);
  EXPECT_GT(light[1], 0.0);

  camera.forward = atmos::direction_from_azimuth_elevation(0.0, 45.0);
  const glm::dvec3 star = atmos::direction_from_azimuth_elevation(0.5, 45.0);
  const glm::dvec2 at = project(camera, star);
  for (double sun_elevation : {-30.0, 40.0}) {
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, sun_elevation);
    renderer.set_stars(false);
    const Image without = renderer.render(camera, sun);
    renderer.set_stars(true);
    renderer.set_star_catalogue({star_of(star, -1.5)});
    const Image with = renderer.render(camera, sun);
    const int x = int(at.x), y = int(at.y);
    const double sky = luminance(without, x, y);
    const double contrast = (luminance(with, x, y) - sky) / sky;
    std::printf("V -1.5 star 45 deg up, sun %+.0f deg: contrast %.3g at its pixel\n", sun_elevation, contrast);
    if (sun_elevation > 0.0) {
      EXPECT_GT(contrast, 0.0);
      EXPECT_LT(contrast, 0.01) << "the star shows in the daylight sky";
    } else {
      EXPECT_GT(contrast, 10.0) << "the star does not stand out of the night sky";
    }
  }
}

// Bad stars and orientations are one-line errors, and the renderer keeps
// its previous catalogue; an unreadable catalogue file is named.
TEST_F(StarCatalogueGpu, RejectsBadStars) {
  atmos::Renderer renderer(*earth_, *tables_);
  const atmos::Star good = star_of({0, 0, 1}, 1.0);
  renderer.set_star_catalogue({good});
  atmos::Star nan = good, negative = good, cold = good;
  nan.direction.x = std::nan("");
  negative.v_band_irradiance = -1.0;
  cold.temperature_k = 10.0;
  for (const atmos::Star& bad : {nan, negative, cold}) {
    EXPECT_THROW(renderer.set_star_catalogue({good, bad}), atmos::Error);
    EXPECT_THROW(atmos::render_cpu(*earth_, *tables_, Camera{}, {0, 0, 1}, true, {}, {bad}), atmos::Error);
  }
  EXPECT_EQ(renderer.star_catalogue().size(), 1u);
  try {
    renderer.set_star_catalogue({good, cold});
  } catch (const atmos::Error& e) {
    EXPECT_STREQ(e.what(), "star 1: its temperature 10 K is outside [1000, 100000]");
  }
  EXPECT_THROW(renderer.set_star_orientation(glm::dmat3(2.0)), atmos::Error);
  glm::dmat3 mirror(1.0);
  mirror[0][0] = -1.0;
  EXPECT_THROW(renderer.set_star_orientation(mirror), atmos::Error);
  try {
    (void)atmos::load_bright_star_catalogue("/no/such/BSC");
    ADD_FAILURE() << "an unreadable catalogue was read";
  } catch (const atmos::Error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot read the star catalogue /no/such/BSC"), std::string::npos)
        << e.what();
  }
}

// The stars' colours: xplanet's catalogue has no B-V, KStars' (kstars-data,
// from Hipparcos) has; matched star by star (the nearest within 1' and 0.5
// mag), 98 % of the Bright Star Catalogue gets one, and the bright stars
// get the Bright Star Catalogue's own B-V (Hoffleit & Warren 1991: Sirius
// 0.00, Rigel -0.03, Arcturus 1.23, Vega 0.00) within 0.05 — except the
// variable red supergiant Betelgeuse, 1.85 there and 1.50 in Hipparcos.
// Malformed lines are errors naming the line.
TEST(StarCatalogueColours, TheBrightStarsGetTheirBMinusVFromKStars) {
  std::vector<atmos::CatalogueStar> bsc = atmos::load_bright_star_catalogue();
  const std::vector<atmos::CatalogueStar> kstars = atmos::load_kstars_catalogue();
  const size_t matched = atmos::colour_from_catalogue(bsc, kstars);
  std::printf("%zu of the %zu stars of xplanet's catalogue got a B-V from KStars' %zu\n", matched, bsc.size(),
              kstars.size());
  EXPECT_GT(double(matched), 0.97 * double(bsc.size()));
  const std::vector<std::pair<int, double>> published = {{2491, 0.00}, {1713, -0.03}, {5340, 1.23}, {7001, 0.00}};
  for (const auto& star : published) {
    const int hr = star.first;
    const double b_minus_v = star.second;
    const auto s = std::find_if(bsc.begin(), bsc.end(), [&](const atmos::CatalogueStar& c) {
      return c.bright_star_number == hr;
    });
    ASSERT_NE(s, bsc.end()) << "HR " << hr;
    std::printf("HR %d: B-V %.2f from KStars, %.2f in the Bright Star Catalogue\n", hr, s->b_minus_v, b_minus_v);
    EXPECT_NEAR(s->b_minus_v, b_minus_v, 0.05) << "HR " << hr;
  }
  const auto betelgeuse = std::find_if(bsc.begin(), bsc.end(), [](const atmos::CatalogueStar& c) {
    return c.bright_star_number == 2061;
  });
  ASSERT_NE(betelgeuse, bsc.end());
  EXPECT_NEAR(betelgeuse->b_minus_v, 1.50, 0.005);
  std::istringstream bad("064508.92 -164258.0 -000546.0-001223.100379.2 -1.44x0.01A0 1\n");
  try {
    (void)atmos::parse_kstars_catalogue(bad, "bad.dat");
    ADD_FAILURE() << "a malformed line was read";
  } catch (const atmos::Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.dat:1: B-V"), std::string::npos) << e.what();
  }
  EXPECT_THROW(atmos::load_kstars_catalogue("/no/such/stars.dat"), atmos::Error);
}

// A star's irradiance in the channels of spectral tables (linear sRGB over
// 683 lm/W, weighted over the working wavelengths like the sun's light)
// against its CIE-weighted irradiance at 1 nm (star_srgb_irradiance): within
// 1 % per channel with 15 wavelengths, for blue, solar and red stars.
TEST(StarCatalogueBins, SpectralChannelsCarryTheStarsColour) {
  const std::vector<double> wavelengths = atmos::spectral_wavelengths(15);
  for (double b_minus_v : {-0.3, 0.65, 1.5}) {
    const atmos::Star star = star_of({0, 0, 1}, 2.0, atmos::temperature_from_b_minus_v(b_minus_v));
    const glm::dvec3 channels =
        glm::dvec3(atmos::gpu::star_channel_irradiance(star, wavelengths)) * atmos::kMaxLuminousEfficacy;
    const glm::dvec3 own = atmos::star_srgb_irradiance(2.0, b_minus_v);
    std::printf("B-V %+.2f: spectral channels x 683 / CIE-weighted = (%.4f, %.4f, %.4f)\n", b_minus_v,
                channels.x / own.x, channels.y / own.y, channels.z / own.z);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(channels[c] / own[c], 1.0, 0.01) << "B-V " << b_minus_v << " channel " << c;
  }
}

// The bins (gpu/star_catalogue_bins.cpp) against brute force: every star
// within the bins' radius of a direction is in the list of that
// direction's cell, for random directions over the whole sphere and a
// catalogue of random stars (cube corners and edges included).
TEST(StarCatalogueBins, EveryStarNearADirectionIsInItsCell) {
  std::vector<glm::vec3> directions, irradiances;
  unsigned seed = 12345u;
  auto uniform = [&] {
    seed = seed * 1664525u + 1013904223u;
    return double(seed >> 8) / double(1u << 24);
  };
  auto random_direction = [&] {
    const double z = 2.0 * uniform() - 1.0, phi = 2.0 * M_PI * uniform();
    const double s = std::sqrt(1.0 - z * z);
    return glm::dvec3(s * std::cos(phi), s * std::sin(phi), z);
  };
  for (int i = 0; i < 3000; ++i) {
    directions.push_back(glm::vec3(random_direction()));
    irradiances.push_back(glm::vec3(1.0f));
  }
  directions.push_back(glm::normalize(glm::vec3(1.0f, 1.0f, 1.0f)));  // a cube corner
  irradiances.push_back(glm::vec3(1.0f));
  const double radius = atmos::gpu::star_bin_radius(2e-3);
  EXPECT_GE(radius, 1e-2);
  const atmos::gpu::StarBins bins = atmos::gpu::bin_stars(directions, irradiances, radius);
  int checked = 0;
  const double cos_radius = std::cos(radius);
  for (int i = 0; i < 20000; ++i) {
    // Half near a star (within the radius), half anywhere.
    glm::dvec3 ray = random_direction();
    if (i % 2 == 0) {
      const glm::dvec3 star(directions[size_t(i / 2) % directions.size()]);
      ray = glm::normalize(star + radius * uniform() * glm::normalize(glm::cross(star, ray)));
    }
    const int cell = atmos::physics::star_cube_cell(atmos::physics::vec3(ray), STAR_CATALOGUE_CELLS);
    for (size_t s = 0; s < directions.size(); ++s) {
      if (glm::dot(ray, glm::dvec3(directions[s])) < cos_radius) continue;
      bool found = false;
      for (std::uint32_t r = bins.cell_first[size_t(cell)]; r < bins.cell_first[size_t(cell) + 1]; ++r)
        found |= glm::length(glm::vec3(bins.records[2 * r]) - directions[s]) < 1e-6f;
      EXPECT_TRUE(found) << "star " << s << " is missing from cell " << cell;
      ++checked;
    }
  }
  std::printf("%d star-direction pairs within %.4g rad checked, %zu entries for %zu stars\n", checked, radius,
              bins.records.size() / 2, directions.size());
  EXPECT_GT(checked, 10000);
}

}  // namespace
