// The renderer's host code that needs no OpenGL context: half-float
// texels, the camera model (gpu/camera.glsl compiled as C++) and camera
// validation, the programs' source text, and image files. The renderer on
// the GPU against its CPU twin is in gpu_test.cpp.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

#include "png_decoder.hpp"

#include "atmos/atmosphere.hpp"
#include "atmos/colour.hpp"
#include "atmos/image.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/post.hpp"
#include "atmos/renderer.hpp"
#include "gpu/camera_cpp.hpp"
#include "gpu/gl_util.hpp"
#include "gpu/shader_source.hpp"
#include "physics/parameters.hpp"
#include "gpu_fixture.hpp"

namespace {

using atmos::Camera;
using atmos::Image;
using atmos::Projection;

constexpr double kEarthRadius = 6371e3;

// Half-float texels: the channels of the three-wavelength mode (radiances,
// never negative) are rounded to the nearest half float; linear sRGB
// channels of real light, whose CIE XYZ coordinates are never negative, stay
// so after rounding, each channel within one half-float step of its float.
// The texels are the colours of monochromatic light (the spectral locus,
// the farthest beyond the sRGB gamut light goes) and of random mixtures of
// it, from 1e-3 down to 1e-9, where half floats are subnormal and spaced
// 2^-24 apart: plain rounding to the nearest puts some of them beyond the
// locus (counted, so that the test shows the rounding it guards against).
TEST(HalfTexel, FaintLightStaysLightAfterRounding) {
  const glm::dvec3 r = atmos::srgb_to_xyz({1, 0, 0}), g = atmos::srgb_to_xyz({0, 1, 0}),
                   b = atmos::srgb_to_xyz({0, 0, 1});
  const glm::dmat3 srgb_from_xyz = glm::inverse(glm::dmat3(r, g, b));
  std::vector<glm::dvec3> spectra;
  for (double nm = 400.0; nm <= 700.0; nm += 5.0) spectra.push_back(atmos::cie_1931_color_matching(nm));
  std::uint32_t state = 12345;
  auto uniform = [&state] {
    state = state * 1664525u + 1013904223u;
    return double(state >> 8) / double(1u << 24);
  };
  for (int i = 0; i < 2000; ++i) {
    const size_t a = size_t(uniform() * double(spectra.size())) % spectra.size();
    const size_t c = size_t(uniform() * double(spectra.size())) % spectra.size();
    const double w = uniform() < 0.3 ? 1.0 : uniform();
    spectra.push_back(w * spectra[a] + (1.0 - w) * spectra[c]);
  }
  int plain_rounding_beyond_locus = 0;
  int checked = 0;
  for (const glm::dvec3& xyz : spectra) {
    for (double scale = 1e-3; scale > 1e-9; scale *= 0.1) {
      const glm::vec3 texel(srgb_from_xyz * (scale * xyz / (xyz.x + xyz.y + xyz.z)));
      const glm::dvec3 exact_xyz = atmos::srgb_to_xyz(glm::dvec3(texel));
      const glm::dvec3 floor_xyz = glm::min(exact_xyz, glm::dvec3(0.0));
      const glm::vec3 plain(glm::unpackHalf1x16(glm::packHalf1x16(texel.x)),
                            glm::unpackHalf1x16(glm::packHalf1x16(texel.y)),
                            glm::unpackHalf1x16(glm::packHalf1x16(texel.z)));
      if (!glm::all(glm::greaterThanEqual(atmos::srgb_to_xyz(glm::dvec3(plain)), floor_xyz)))
        ++plain_rounding_beyond_locus;
      const glm::vec3 rounded = atmos::gpu::half_texel(texel, true);
      const glm::dvec3 rounded_xyz = atmos::srgb_to_xyz(glm::dvec3(rounded));
      ASSERT_TRUE(glm::all(glm::greaterThanEqual(rounded_xyz, floor_xyz)))
          << "texel (" << texel.x << ", " << texel.y << ", " << texel.z << ")";
      for (int ch = 0; ch < 3; ++ch) {
        // One step of a half float at this value: 2^-10 of its binade, or the
        // subnormal spacing 2^-24.
        const double step = std::max(std::ldexp(1.0, std::ilogb(std::abs(texel[ch]) + 1e-30) - 10), 0x1.0p-24);
        EXPECT_LE(std::abs(double(rounded[ch]) - double(texel[ch])), step) << ch;
      }
      EXPECT_EQ(atmos::gpu::half_texel(glm::abs(texel), false), glm::abs(plain));
      ++checked;
    }
  }
  std::printf("[ figure ] half texels: %d checked, %d beyond the spectral locus after plain rounding, 0 after "
              "half_texel\n", checked, plain_rounding_beyond_locus);
  EXPECT_GT(plain_rounding_beyond_locus, 0);
}

// --- Camera model (gpu/camera.glsl, the same code on both sides) ----------

float angle_between(const glm::vec3& a, const glm::vec3& b) {
  return std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0f, 1.0f));
}

TEST(CameraModel, ProjectionConventions) {
  using atmos::physics::camera_view_ray;
  const glm::vec3 right(1, 0, 0), up(0, 0, 1), forward(0, 1, 0);
  const glm::vec2 size(200.0f, 100.0f);
  bool valid = false;
  auto ray = [&](float x, float y, float fov, int projection) {
    return camera_view_ray(glm::vec2(x, y), size, right, up, forward, fov, glm::vec2(0.0f), projection, valid);
  };
  // Perspective: the centre looks forward, the top edge fov/2 up, square pixels.
  EXPECT_LT(angle_between(ray(100, 50, 60, PROJECTION_PERSPECTIVE), forward), 1e-6f);
  EXPECT_TRUE(valid);
  const glm::vec3 top = ray(100, 0, 60, PROJECTION_PERSPECTIVE);
  EXPECT_NEAR(angle_between(top, forward), glm::radians(30.0f), 1e-6f);
  EXPECT_GT(top.z, 0.0f);
  const glm::vec3 right_edge = ray(200, 50, 60, PROJECTION_PERSPECTIVE);
  EXPECT_NEAR(right_edge.x / right_edge.y, 2.0f * std::tan(glm::radians(30.0f)), 1e-5f);
  // Fisheye (equidistant): fov/2 on the inscribed circle, invalid outside it.
  EXPECT_NEAR(angle_between(ray(100, 0, 180, PROJECTION_FISHEYE), forward), glm::radians(90.0f), 1e-5f);
  EXPECT_TRUE(valid);
  EXPECT_NEAR(angle_between(ray(125, 50, 180, PROJECTION_FISHEYE), forward), glm::radians(45.0f), 1e-5f);
  EXPECT_GT(ray(125, 50, 180, PROJECTION_FISHEYE).x, 0.0f);
  ray(1, 1, 180, PROJECTION_FISHEYE);
  EXPECT_FALSE(valid);
  // Equirectangular: forward at the centre, right at 3/4 width, up on the
  // top edge, backward on the left and right edges.
  EXPECT_LT(angle_between(ray(100, 50, 0, PROJECTION_EQUIRECT), forward), 1e-6f);
  EXPECT_TRUE(valid);
  EXPECT_LT(angle_between(ray(150, 50, 0, PROJECTION_EQUIRECT), right), 1e-6f);
  EXPECT_LT(angle_between(ray(100, 0, 0, PROJECTION_EQUIRECT), up), 1e-3f);
  EXPECT_LT(angle_between(ray(0, 50, 0, PROJECTION_EQUIRECT), -forward), 1e-6f);
}

// --- Shader source --------------------------------------------------------

TEST(ShaderSource, FloatLiteralsAreGlslFloats) {
  EXPECT_EQ(atmos::gpu::glsl_float(1.0f), "1.0");
  EXPECT_EQ(atmos::gpu::glsl_float(-2.0f), "-2.0");
  EXPECT_EQ(atmos::gpu::glsl_float(6371000.0f), "6371000.0");
  EXPECT_EQ(atmos::gpu::glsl_float(1e-05f), "9.99999975e-06");
  EXPECT_EQ(atmos::gpu::glsl_float(0.0f), "0.0");
  EXPECT_EQ(std::stof(atmos::gpu::glsl_float(0.1f)), 0.1f);
  EXPECT_THROW(atmos::gpu::glsl_float(std::numeric_limits<float>::quiet_NaN()), atmos::Error);
  EXPECT_THROW(atmos::gpu::glsl_float(std::numeric_limits<float>::infinity()), atmos::Error);
}

// The programs' text depends on the atmosphere's structure alone
// (ParameterBlock): the same for other values, another for another number
// of wavelength triples or another profile kind.
TEST(ShaderSource, ProgramsDependOnTheAtmospheresStructureAlone) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const atmos::TableSizes sizes = atmos_test::small_gpu_sizes();
  const auto source = [&](const atmos::Atmosphere& a) {
    const atmos::physics::AtmosphereParams params = atmos::physics::make_render_params(a, sizes);
    const auto spectral = atmos::physics::make_spectral_sets(a, sizes);
    return std::pair{atmos::gpu::atmosphere_pass_fragment_shader_source(params, *spectral, {}).text,
                     atmos::gpu::parameter_block(params, *spectral, glm::mat3(1.0f)).values};
  };
  const auto [earth_text, earth_values] = source(earth);
  const auto [other_text, other_values] = source(atmos_test::other_earth_values(earth));
  EXPECT_EQ(earth_text, other_text);
  EXPECT_NE(earth_values, other_values);
  atmos::Atmosphere spectral = earth;
  spectral.wavelengths_nm = atmos::spectral_wavelengths(7);
  EXPECT_NE(source(spectral).first, earth_text);
  atmos::Atmosphere layered = earth;
  layered.constituents[0].density.kind = atmos::DensityProfile::Kind::piecewise_linear;
  layered.constituents[0].density.knots = {{0.0, 1.0}, {30e3, 0.05}, {60e3, 0.0}};
  EXPECT_NE(source(layered).first, earth_text);
}

// A parameter that GLSL cannot hold (NaN, infinity) is an error, not a
// shader that draws NaN.
TEST(ShaderSource, NonFiniteParametersAreErrors) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const atmos::TableSizes sizes = atmos_test::small_gpu_sizes();
  atmos::physics::AtmosphereParams params = atmos::physics::make_render_params(earth, sizes);
  const auto spectral = atmos::physics::make_spectral_sets(earth, sizes);
  params.solar_irradiance.y = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(atmos::gpu::parameter_block(params, *spectral, glm::mat3(1.0f)), atmos::Error);
  params = atmos::physics::make_render_params(earth, sizes);
  spectral->set[0].bottom_radius = std::numeric_limits<float>::infinity();
  EXPECT_THROW(atmos::gpu::parameter_block(params, *spectral, glm::mat3(1.0f)), atmos::Error);
  EXPECT_THROW(atmos::gpu::parameter_block(params, *atmos::physics::make_spectral_sets(earth, sizes),
                                           glm::mat3(std::numeric_limits<float>::quiet_NaN())),
               atmos::Error);
}

// --- Images ---------------------------------------------------------------

// A directory of this test process, removed when the process exits.
std::filesystem::path temp_dir() {
  struct Directory {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("atmos_gpu_test_" + std::to_string(::getpid()));
    Directory() { std::filesystem::create_directories(path); }
    ~Directory() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Directory directory;
  return directory.path;
}

Image test_image() {
  Image image;
  image.width = 37;  // not a multiple of anything, and wider than 16 (tinyexr compresses from 16 up)
  image.height = 21;
  image.rgb.resize(size_t(image.width) * size_t(image.height) * 3);
  for (size_t i = 0; i < image.rgb.size(); ++i)
    image.rgb[i] = float(std::pow(1.37, double(i % 97) - 40.0)) * (i % 5 == 0 ? -1.0f : 1.0f);
  return image;
}

TEST(ImageIo, ExrRoundTripIsExact) {
  const Image image = test_image();
  const std::string path = (temp_dir() / "round_trip.exr").string();
  atmos::write_exr(image, path);
  const Image back = atmos::read_exr(path);
  ASSERT_EQ(back.width, image.width);
  ASSERT_EQ(back.height, image.height);
  EXPECT_EQ(back.rgb, image.rgb);
  // Also through write_image, by extension, in any case.
  const std::string upper = (temp_dir() / "ROUND_TRIP.EXR").string();
  atmos::write_image(image, upper, 0.0);
  EXPECT_EQ(atmos::read_exr(upper).rgb, image.rgb);
}

TEST(ImageIo, PngIsWritten) {
  Image image;
  image.width = 4;
  image.height = 2;
  // Luminance 0, the saturation luminance at EV 0 (1.2 cd/m²), and far above.
  image.rgb = {0, 0, 0, 1.2f, 1.2f, 1.2f, 1e6f, 1e6f, 1e6f, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const std::string path = (temp_dir() / "tone_mapped.png").string();
  atmos::write_image(image, path, 0.0);
  std::ifstream file(path, std::ios::binary);
  ASSERT_TRUE(file.good());
  unsigned char signature[8] = {};
  file.read(reinterpret_cast<char*>(signature), 8);
  EXPECT_EQ(signature[1], 'P');
  EXPECT_EQ(signature[2], 'N');
  EXPECT_EQ(signature[3], 'G');
  int width = 0;
  int height = 0;
  int channels = 0;
  unsigned char* pixels = stbi_load(path.c_str(), &width, &height, &channels, 3);
  ASSERT_NE(pixels, nullptr);
  EXPECT_EQ(width, 4);
  EXPECT_EQ(height, 2);
  EXPECT_EQ(pixels[0], 0);  // black
  // L = L_sat: 1 - 1/e = 0.632 on the display, sRGB-encoded 0.8174 -> 208.
  EXPECT_EQ(pixels[3], 208);
  EXPECT_EQ(pixels[6], 255);  // saturated
  EXPECT_EQ(pixels[9], 0);    // negative (out of gamut) clamps to black
  stbi_image_free(pixels);
  // Two stops more exposure value: L_sat = 4.8 cd/m², 1.2 cd/m² is darker.
  atmos::write_png(image, path, 2.0);
  pixels = stbi_load(path.c_str(), &width, &height, &channels, 3);
  ASSERT_NE(pixels, nullptr);
  EXPECT_EQ(pixels[3], int(std::lround(255.0 * (1.055 * std::pow(1.0 - std::exp(-0.25), 1.0 / 2.4) - 0.055))));
  stbi_image_free(pixels);
}

TEST(ImageIo, UnwritablePathThrows) {
  const Image image = test_image();
  const std::string missing_dir = (temp_dir() / "no_such_dir" / "image.exr").string();
  try {
    atmos::write_exr(image, missing_dir);
    FAIL() << "no error";
  } catch (const atmos::Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(missing_dir), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_THROW(atmos::write_png(image, (temp_dir() / "no_such_dir" / "image.png").string(), 0.0), atmos::Error);
  EXPECT_THROW(atmos::read_exr((temp_dir() / "missing.exr").string()), atmos::Error);
}

TEST(ImageIo, UnsupportedFormatThrows) {
  try {
    atmos::write_image(test_image(), (temp_dir() / "image.jpg").string(), 0.0);
    FAIL() << "no error";
  } catch (const atmos::Error& e) {
    EXPECT_NE(std::string(e.what()).find("unsupported output format"), std::string::npos) << e.what();
  }
}

TEST(ImageIo, NonFiniteImagesAreNeverWritten) {
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    Image image = test_image();
    image.rgb[100] = bad;
    const auto exr = temp_dir() / "bad.exr";
    const auto png = temp_dir() / "bad.png";
    EXPECT_THROW(atmos::write_exr(image, exr.string()), atmos::Error);
    EXPECT_THROW(atmos::write_png(image, png.string(), 0.0), atmos::Error);
    EXPECT_FALSE(std::filesystem::exists(exr));
    EXPECT_FALSE(std::filesystem::exists(png));
  }
  Image inconsistent = test_image();
  inconsistent.rgb.pop_back();
  EXPECT_THROW(atmos::write_exr(inconsistent, (temp_dir() / "short.exr").string()), atmos::Error);
}

// --- Cameras --------------------------------------------------------------

void expect_invalid(const Camera& camera, const std::string& expected_words) {
  try {
    atmos::validate_camera(camera);
    ADD_FAILURE() << "accepted a camera that should fail with: " << expected_words;
  } catch (const atmos::Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(expected_words), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(CameraValidation, AcceptsDefaultsAndEdgeCases) {
  Camera camera;
  camera.position = {0.0, 0.0, kEarthRadius};
  EXPECT_NO_THROW(atmos::validate_camera(camera));
  camera.up = {0.0, 0.3, 1.0};  // not orthogonal to forward: only a hint
  EXPECT_NO_THROW(atmos::validate_camera(camera));
  camera.projection = Projection::fisheye;
  camera.fov_deg = 360.0;
  EXPECT_NO_THROW(atmos::validate_camera(camera));
  camera.projection = Projection::equirect;
  camera.fov_deg = 0.0;  // ignored
  camera.width = 1;
  camera.height = 16384;
  EXPECT_NO_THROW(atmos::validate_camera(camera));
}

TEST(CameraValidation, RejectsBadCameras) {
  Camera good;
  good.position = {0.0, 0.0, kEarthRadius};
  Camera c = good;
  c.position.x = std::nan("");
  expect_invalid(c, "position");
  c = good;
  c.forward = {0.0, 0.0, 0.0};
  expect_invalid(c, "forward");
  c = good;
  c.up = {0.0, std::numeric_limits<double>::infinity(), 0.0};
  expect_invalid(c, "up");
  c = good;
  c.up = {0.0, -2.0, 0.0};
  expect_invalid(c, "parallel");
  c = good;
  c.width = 0;
  expect_invalid(c, "image size");
  c = good;
  c.height = 16385;
  expect_invalid(c, "image size");
  c = good;
  c.fov_deg = 180.0;
  expect_invalid(c, "fov");
  c.fov_deg = 0.0;
  expect_invalid(c, "fov");
  c.fov_deg = std::nan("");
  expect_invalid(c, "fov");
  c = good;
  c.projection = Projection::fisheye;
  c.fov_deg = 361.0;
  expect_invalid(c, "fov");
}

}  // namespace
