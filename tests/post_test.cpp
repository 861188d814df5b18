// The post-processing chain on the GPU (include/atmos/post.hpp, src/post/):
// its passes against the shared CPU functions (tested on their own in
// tone_mapping_test.cpp), auto exposure's convergence and adaptation
// speeds, the bloom's light balance and symmetry, settings validation and
// the CLI flags.
//
// The GPU tests FAIL (never skip) without an OpenGL 4.5 context, like
// gpu_test.cpp: CI runs them on Mesa llvmpipe.
#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "png_decoder.hpp"

#include "atmos/atmosphere.hpp"
#include "atmos/image.hpp"
#include "atmos/post.hpp"
#include "atmos/renderer.hpp"
#include "cli_support.hpp"
#include "post/tone_mapping_cpp.hpp"

namespace {

namespace post = atmos::post;
using atmos::Image;
using atmos::PostInput;
using atmos::PostOutputFormat;
using atmos::PostProcess;
using atmos::PostSettings;
using atmos::ToneMapping;

const int kOperators[] = {post::TONE_MAP_EXP, post::TONE_MAP_REINHARD, post::TONE_MAP_FILMIC, post::TONE_MAP_ACES,
                          post::TONE_MAP_LINEAR};
const ToneMapping kToneMappings[] = {ToneMapping::exp, ToneMapping::reinhard, ToneMapping::filmic, ToneMapping::aces,
                                     ToneMapping::linear};


class PostGpu : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    try {
      context_ = atmos::GlContext::create_headless();
    } catch (const atmos::Error& e) {
      context_error_ = e.what();
    }
  }
  static void TearDownTestSuite() { context_.reset(); }
  void SetUp() override { ASSERT_TRUE(context_ != nullptr) << context_error_; }
  void TearDown() override {
    if (!textures_.empty()) glDeleteTextures(GLsizei(textures_.size()), textures_.data());
    textures_.clear();
  }

  // An RGBA32F texture holding `image` (row y of the image is texture row y).
  GLuint upload(const Image& image) {
    GLuint texture = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &texture);
    glTextureStorage2D(texture, 1, GL_RGBA32F, image.width, image.height);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(texture, 0, 0, 0, image.width, image.height, GL_RGB, GL_FLOAT, image.rgb.data());
    textures_.push_back(texture);
    return texture;
  }

  PostInput input_for(const Image& image) {
    PostInput in;
    in.colour = upload(image);
    in.width = image.width;
    in.height = image.height;
    return in;
  }

  static std::unique_ptr<atmos::GlContext> context_;
  static std::string context_error_;
  std::vector<GLuint> textures_;
};

std::unique_ptr<atmos::GlContext> PostGpu::context_;
std::string PostGpu::context_error_;

// Linear sRGB with luminances spread log-uniformly over [lo, hi] cd/m² and
// random (positive) chromaticities.
Image random_image(int width, int height, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Image image;
  image.width = width;
  image.height = height;
  image.rgb.resize(size_t(width) * size_t(height) * 3);
  for (size_t i = 0; i < size_t(width) * size_t(height); ++i) {
    const double l = lo * std::pow(hi / lo, u(rng));
    for (size_t c = 0; c < 3; ++c) image.rgb[3 * i + c] = float(l * (0.5 + u(rng)));
  }
  return image;
}

double channel_sum(const Image& image, size_t c) {
  double s = 0.0;
  for (size_t i = c; i < image.rgb.size(); i += 3) s += image.rgb[i];
  return s;
}

// Every operator, both output kinds, at every pixel of an image spanning 10
// stops around the exposure: the GPU gives the shared CPU function's value
// (display-linear within 2e-6 + 2e-5 relative; 8-bit within one step, and
// exact at >= 99 % of the pixels: the GPU's exp and pow round differently).
TEST_F(PostGpu, ToneMappingEqualsTheSharedCpuFunction) {
  const Image image = random_image(37, 23, 10.0, 1e5, 1);  // odd sizes: partial work groups
  PostProcess pp;
  PostInput in = input_for(image);
  for (size_t k = 0; k < std::size(kToneMappings); ++k) {
    const ToneMapping op = kToneMappings[k];
    const int constant = kOperators[k];
    PostSettings s;
    s.tone_mapping = op;
    s.exposure_ev = 10.0;
    const float exposure = post::exposure_from_ev100(10.0f);

    s.output_format = PostOutputFormat::linear_float;
    const Image linear = atmos::read_linear_image(pp.process(in, s), in.width, in.height);
    double worst = 0.0;
    for (size_t i = 0; i < image.rgb.size(); ++i) {
      const float expected = post::display_linear_channel(image.rgb[i] * exposure, constant);
      worst = std::max(worst, std::abs(double(linear.rgb[i]) - expected) / (2e-6 + 2e-5 * std::abs(expected)));
    }
    EXPECT_LE(worst, 1.0) << atmos::tone_mapping_name(op) << ": worst error in units of the tolerance";

    s.output_format = PostOutputFormat::srgb8;
    const atmos::DisplayImage display = atmos::read_display_image(pp.process(in, s), in.width, in.height);
    int exact = 0, worst_step = 0;
    for (size_t i = 0; i < image.rgb.size(); ++i) {
      const int expected = int(std::lround(post::display_encoded_channel(image.rgb[i] * exposure, constant) * 255.0f));
      worst_step = std::max(worst_step, std::abs(int(display.rgb[i]) - expected));
      exact += int(display.rgb[i]) == expected;
    }
    EXPECT_LE(worst_step, 1) << atmos::tone_mapping_name(op);
    EXPECT_GE(double(exact), 0.99 * double(image.rgb.size())) << atmos::tone_mapping_name(op);
  }
}

// `--tonemap exp` through PostProcess against write_png's PNG for the same EV.
TEST_F(PostGpu, ExpOperatorReproducesWritePng) {
  const Image image = random_image(64, 40, 1.0, 1e5, 2);
  const auto dir = atmos_test::scratch_directory("post");
  const std::string path = (dir / "exp.png").string();
  atmos::write_png(image, path, 12.0);
  int w = 0, h = 0, channels = 0;
  unsigned char* png = stbi_load(path.c_str(), &w, &h, &channels, 3);
  ASSERT_NE(png, nullptr);
  PostProcess pp;
  PostSettings s;
  s.exposure_ev = 12.0;
  const atmos::DisplayImage display = pp.process_image(image, s);
  int exact = 0, worst = 0;
  for (size_t i = 0; i < display.rgb.size(); ++i) {
    worst = std::max(worst, std::abs(int(display.rgb[i]) - int(png[i])));
    exact += display.rgb[i] == png[i];
  }
  stbi_image_free(png);
  EXPECT_LE(worst, 1);
  EXPECT_GE(double(exact), 0.99 * double(display.rgb.size()));
  std::printf("exp via PostProcess vs write_png: %d of %zu bytes equal, max difference %d\n", exact,
              display.rgb.size(), worst);
}

// The log-average luminance of the test images, in double on the CPU
// (Reinhard et al. 2002, eq. 1, with Collienne 2013, eq. 4.27 per pixel).
double log_average(const Image& image) {
  double sum = 0.0;
  const size_t n = size_t(image.width) * size_t(image.height);
  for (size_t i = 0; i < n; ++i) {
    const double l = 0.2126 * image.rgb[3 * i] + 0.7152 * image.rgb[3 * i + 1] + 0.0722 * image.rgb[3 * i + 2];
    sum += std::log(1e-4 + l);
  }
  return std::exp(sum / double(n));
}

Image scaled(Image image, float factor) {
  for (float& v : image.rgb) v *= factor;
  return image;
}

// Auto exposure at 30 frames/s with tau 0.5 s (brightening) and 2 s
// (darkening), between a scene and the same scene 4 EV brighter.
// - The first frame is exposed at its target: the GPU's log average equals
//   the CPU's within 0.1 % and exposes to the key within 0.5 %.
// - Half way (2 EV) after ceil(tau ln 2 / dt) frames: ceil(10.40) = 11
//   brightening, ceil(41.59) = 42 darkening (measured: the same).
// - Within 0.01 EV of the target (the exposed log average within 0.7 % of
//   the key) after ceil(tau / dt ln(4 / 0.01)) frames: 90 brightening, 360
//   darkening.
TEST_F(PostGpu, AutoExposureConvergesWithSeparateSpeeds) {
  const Image dark = random_image(64, 48, 20.0, 2000.0, 3);
  const Image bright = scaled(dark, 16.0f);
  PostProcess pp;
  PostInput dark_in = input_for(dark), bright_in = input_for(bright);
  dark_in.dt_s = bright_in.dt_s = 1.0 / 30.0;
  PostSettings s;
  s.auto_exposure.enabled = true;
  s.auto_exposure.brightening_tau_s = 0.5;
  s.auto_exposure.darkening_tau_s = 2.0;
  s.auto_exposure.min_ev = -6.0;
  s.auto_exposure.max_ev = 24.0;
  const double key = s.auto_exposure.key;
  EXPECT_TRUE(std::isnan(pp.current_exposure_ev()));

  pp.process(dark_in, s);
  const double l_dark = log_average(dark);
  EXPECT_NEAR(pp.last_log_average_luminance(), l_dark, 1e-3 * l_dark);
  const double ev_dark = pp.current_exposure_ev();
  EXPECT_NEAR(post::exposure_from_ev100(float(ev_dark)) * l_dark, key, 5e-3 * key);

  // Brightening: frames until half way, then until converged.
  const double ev_bright = ev_dark + 4.0;
  int half = 0, converged = 0;
  for (int frame = 1; frame <= 200; ++frame) {
    pp.process(bright_in, s);
    const double ev = pp.current_exposure_ev();
    if (half == 0 && ev >= ev_dark + 2.0) half = frame;
    if (converged == 0 && ev >= ev_bright - 0.01) converged = frame;
  }
  EXPECT_EQ(half, 11);
  EXPECT_EQ(converged, 90);
  EXPECT_NEAR(post::exposure_from_ev100(float(pp.current_exposure_ev())) * log_average(bright), key, 2e-3 * key);

  // Darkening back: four times slower.
  int dark_half = 0, dark_converged = 0;
  for (int frame = 1; frame <= 400; ++frame) {
    pp.process(dark_in, s);
    const double ev = pp.current_exposure_ev();
    if (dark_half == 0 && ev <= ev_bright - 2.0) dark_half = frame;
    if (dark_converged == 0 && ev <= ev_dark + 0.01) dark_converged = frame;
  }
  EXPECT_EQ(dark_half, 42);
  EXPECT_EQ(dark_converged, 360);
  std::printf("auto exposure: EV %.3f / %.3f; half way in %d (brightening) and %d (darkening) frames\n", ev_dark,
              ev_bright, half, dark_half);

  // Compensation and the clamp act on the target; reset() forgets the state.
  pp.reset();
  EXPECT_TRUE(std::isnan(pp.current_exposure_ev()));
  s.auto_exposure.compensation_ev = 1.5;
  pp.process(dark_in, s);
  EXPECT_NEAR(pp.current_exposure_ev(), ev_dark - 1.5, 2e-3);
  pp.reset();
  s.auto_exposure.max_ev = ev_dark - 3.0;
  pp.process(dark_in, s);
  EXPECT_NEAR(pp.current_exposure_ev(), ev_dark - 3.0, 1e-5);
  // Manual exposure leaves the adaptation state alone.
  s.auto_exposure.enabled = false;
  s.exposure_ev = 3.0;
  pp.process(dark_in, s);
  EXPECT_EQ(pp.current_exposure_ev(), 3.0);
}

// The bloomed scene (operator `linear`, float output, so the output is
// exposure x scene).
Image bloomed(PostProcess& pp, const PostInput& in, double strength, double threshold, double ev) {
  PostSettings s;
  s.tone_mapping = ToneMapping::linear;
  s.output_format = PostOutputFormat::linear_float;
  s.exposure_ev = ev;
  s.bloom.strength = strength;
  s.bloom.threshold = threshold;
  Image out = atmos::read_linear_image(pp.process(in, s), in.width, in.height);
  const float exposure = post::exposure_from_ev100(float(ev));
  for (float& v : out.rgb) v /= exposure;
  return out;
}

// The light the bloom moves: strength x the bright parts (threshold in
// exposed units), summed over the image, per channel.
double moved_light(const Image& image, size_t c, double strength, double threshold, double ev) {
  const float exposure = post::exposure_from_ev100(float(ev));
  double sum = 0.0;
  for (size_t i = 0; i < image.rgb.size(); i += 3) {
    const glm::vec3 rgb(image.rgb[i], image.rgb[i + 1], image.rgb[i + 2]);
    sum += post::bright_part(rgb, exposure, float(threshold))[int(c)];
  }
  return strength * sum;
}

// With bloom, auto exposure's reduction is done by the bloom's bright pass
// from the second frame on (bloom.comp.glsl), which thresholds at the
// exposure the frame starts from. On an image whose sides are not multiples
// of the passes' blocks: the same log average (every pixel counted once) and
// exposures as without bloom, and the light balance holds while the
// exposure changes (the tone map takes out the bright part at the bright
// pass's exposure).
TEST_F(PostGpu, AutoExposureWithBloomMeasuresInTheBrightPass) {
  const Image dark = random_image(67, 45, 20.0, 2000.0, 8);
  const Image bright = scaled(dark, 16.0f);
  PostProcess plain, with_bloom;
  PostInput dark_in = input_for(dark), bright_in = input_for(bright);
  dark_in.dt_s = bright_in.dt_s = 1.0 / 30.0;
  PostSettings s;
  s.auto_exposure.enabled = true;
  s.auto_exposure.max_ev = 24.0;
  PostSettings b = s;
  b.tone_mapping = ToneMapping::linear;
  b.output_format = PostOutputFormat::linear_float;
  b.bloom.strength = 0.5;
  b.bloom.threshold = 0.3;
  for (int frame = 0; frame < 6; ++frame) {
    const PostInput& in = frame == 0 ? dark_in : bright_in;
    const Image& image = frame == 0 ? dark : bright;
    const double ev_before = frame == 0 ? 0.0 : with_bloom.current_exposure_ev();
    plain.process(in, s);
    const Image out = atmos::read_linear_image(with_bloom.process(in, b), in.width, in.height);
    const double l = log_average(image);
    EXPECT_NEAR(with_bloom.last_log_average_luminance(), l, 1e-3 * l) << frame;
    EXPECT_NEAR(with_bloom.last_log_average_luminance(), plain.last_log_average_luminance(), 1e-5 * l) << frame;
    const double ev = with_bloom.current_exposure_ev();
    EXPECT_NEAR(ev, plain.current_exposure_ev(), 1e-4) << frame;
    // The first frame thresholds at its own exposure, the others at the
    // previous frame's.
    const double bloom_ev = frame == 0 ? ev : ev_before;
    const float exposure = post::exposure_from_ev100(float(ev));
    for (size_t c = 0; c < 3; ++c) {
      double after = 0.0;
      for (size_t i = c; i < out.rgb.size(); i += 3) after += double(out.rgb[i] / exposure);
      const double before = channel_sum(image, c);
      const double moved = moved_light(image, c, b.bloom.strength, b.bloom.threshold, bloom_ev);
      EXPECT_GT(moved, 1e-3 * before) << frame;
      EXPECT_NEAR(after, before, 1e-4 * moved) << "frame " << frame << " channel " << c;
    }
    if (frame > 0) {
      EXPECT_GT(ev, ev_before + 0.05) << "the exposure adapts: " << frame;
    }
  }
}

// Light is moved, not made: the total of each channel changes by less than
// 1e-4 of the light the bloom moves, also with a spot on the border (the
// weighted pyramid of post_common.comp.glsl is exact; measured: < 1e-6, float
// rounding).
TEST_F(PostGpu, BloomConservesTotalLight) {
  for (bool border_spot : {false, true}) {
    Image image = random_image(97, 64, 0.05, 3.0, 4);  // cd/m² at EV 0: L_sat = 1.2
    auto set = [&](int x, int y, float v) {
      for (size_t c = 0; c < 3; ++c)
        image.rgb[3 * (size_t(y) * size_t(image.width) + size_t(x)) + c] = v * (1.0f + 0.2f * float(c));
    };
    set(40, 30, 5000.0f);
    set(41, 30, 3000.0f);
    set(70, 12, 800.0f);
    if (border_spot) set(0, 50, 2000.0f);
    PostProcess pp;
    const PostInput in = input_for(image);
    const Image out = bloomed(pp, in, 0.5, 1.0, 0.0);
    for (size_t c = 0; c < 3; ++c) {
      const double before = channel_sum(image, c), after = channel_sum(out, c);
      const double moved = moved_light(image, c, 0.5, 1.0, 0.0);
      EXPECT_NEAR(after, before, 1e-4 * moved) << "channel " << c << (border_spot ? ", spot on the border" : "");
      std::printf("bloom%s, channel %zu: total %.9g -> %.9g, %+.2e of the %.6g moved\n",
                  border_spot ? " (spot on the border)" : "", c, before, after, (after - before) / moved,
                  moved);
    }
    // The bright spot lost light to its surroundings.
    const size_t spot = 3 * (30 * size_t(image.width) + 40);
    EXPECT_LT(out.rgb[spot], 0.7f * image.rgb[spot]);
    const size_t near_spot = 3 * (30 * size_t(image.width) + 46);
    EXPECT_GT(out.rgb[near_spot], image.rgb[near_spot] + 5.0f);
  }
}

// One bright pixel at the centre of a black 65 x 65 image, all of it
// blooming (threshold 0, strength 1): the glare is the same left, right, up
// and down (to 1e-5 relative), falls off with distance and keeps the light
// (to 1e-5).
TEST_F(PostGpu, BloomOfOnePixelIsSymmetric) {
  Image image;
  image.width = image.height = 65;
  image.rgb.assign(65 * 65 * 3, 0.0f);
  const size_t centre = 3 * (32 * 65 + 32);
  image.rgb[centre] = image.rgb[centre + 1] = image.rgb[centre + 2] = 1e4f;
  PostProcess pp;
  const Image out = bloomed(pp, input_for(image), 1.0, 0.0, 0.0);
  auto at = [&](int x, int y) { return double(out.rgb[3 * (size_t(y) * 65 + size_t(x))]); };
  for (int d = 1; d <= 30; ++d) {
    const double right = at(32 + d, 32), left = at(32 - d, 32), up = at(32, 32 - d), down = at(32, 32 + d);
    const double tolerance = 1e-5 * right + 1e-9;
    EXPECT_NEAR(left, right, tolerance) << d;
    EXPECT_NEAR(up, right, tolerance) << d;
    EXPECT_NEAR(down, right, tolerance) << d;
    EXPECT_LT(right, at(32 + d - 1, 32)) << d;
    EXPECT_GT(right, 0.0) << d;
  }
  EXPECT_NEAR(channel_sum(out, 0), 1e4, 1e-5 * 1e4);
  std::printf("one pixel of 1e4: total after bloom %.9g\n", channel_sum(out, 0));
}

// A uniform bright image stays uniform (no bright or dark rims at the
// borders, which mirrored or zero-padded pyramids give), to 1e-5.
TEST_F(PostGpu, BloomOfAUniformImageIsUniform) {
  Image image;
  image.width = 50;
  image.height = 31;
  image.rgb.assign(50 * 31 * 3, 10.0f);
  PostProcess pp;
  const Image out = bloomed(pp, input_for(image), 1.0, 0.5, 0.0);
  for (size_t i = 0; i < out.rgb.size(); ++i) ASSERT_NEAR(out.rgb[i], 10.0f, 1e-4f) << "pixel " << i / 3;
}

// Strength 0 is the identity (no bloom pass runs); a small strength changes
// only what is above the threshold and its neighbourhood.
TEST_F(PostGpu, BloomStrengthZeroIsIdentity) {
  const Image image = random_image(40, 30, 0.01, 50.0, 5);
  PostProcess pp;
  const PostInput in = input_for(image);
  const Image off = bloomed(pp, in, 0.0, 1.0, 0.0);
  for (size_t i = 0; i < image.rgb.size(); ++i) ASSERT_NEAR(off.rgb[i], image.rgb[i], 1e-6f * image.rgb[i]) << i;
  const Image on = bloomed(pp, in, 0.01, 1.0, 0.0);
  double changed = 0.0;
  for (size_t i = 0; i < image.rgb.size(); ++i) changed = std::max(changed, double(std::abs(on.rgb[i] - image.rgb[i])));
  EXPECT_GT(changed, 1e-3);
}

TEST_F(PostGpu, BadSettingsAndInputsAreOneLineErrors) {
  const Image image = random_image(8, 8, 1.0, 10.0, 6);
  PostProcess pp;
  const PostInput good = input_for(image);
  auto expect_error = [&](const PostInput& in, const PostSettings& s, const std::string& words) {
    try {
      pp.process(in, s);
      ADD_FAILURE() << "no error for: " << words;
    } catch (const atmos::Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(words), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PostSettings s;
  s.exposure_ev = nan;
  expect_error(good, s, "exposure_ev must be a finite number");
  s = PostSettings{};
  s.bloom.strength = -0.5;
  expect_error(good, s, "bloom strength must be in [0, 1]");
  s.bloom.strength = 1.5;
  expect_error(good, s, "bloom strength must be in [0, 1]");
  s = PostSettings{};
  s.bloom.threshold = -1.0;
  expect_error(good, s, "bloom threshold must be >= 0");
  s = PostSettings{};
  s.auto_exposure.min_ev = 10.0;
  s.auto_exposure.max_ev = 5.0;
  expect_error(good, s, "min_ev (10) is above max_ev (5)");
  s = PostSettings{};
  s.auto_exposure.key = 0.0;
  expect_error(good, s, "key must be > 0");
  s = PostSettings{};
  s.auto_exposure.darkening_tau_s = -1.0;
  expect_error(good, s, "time constants must be >= 0");
  s = PostSettings{};
  s.auto_exposure.compensation_ev = std::numeric_limits<double>::infinity();
  expect_error(good, s, "exposure compensation must be a finite number");
  s = PostSettings{};
  PostInput in = good;
  in.width = 0;
  expect_error(in, s, "image size must be at least 1x1");
  in = good;
  in.colour = 0;
  expect_error(in, s, "input colour texture is 0");
  in.colour = 987654;
  expect_error(in, s, "is not a texture name");
  in = good;
  in.width = 9;
  expect_error(in, s, "input colour texture is 8x8, expected 9x8");
  in = good;
  in.nits_per_unit = 0.0;
  expect_error(in, s, "nits_per_unit must be > 0");
  in = good;
  in.dt_s = -0.1;
  expect_error(in, s, "dt_s must be >= 0");
  in = good;
  GLuint wrong = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &wrong);
  glTextureStorage2D(wrong, 1, GL_RGBA16F, 8, 8);
  textures_.push_back(wrong);
  in.output = wrong;
  expect_error(in, s, "expected GL_RGBA8");
  // A correct caller-owned output is written and returned.
  s.output_format = PostOutputFormat::linear_half;
  EXPECT_EQ(pp.process(in, s), wrong);
}

// The CLI flags: a PNG through the chain (EXR untouched), usage errors, and
// `--tonemap exp` giving the default PNG.
TEST(PostCli, RenderFlags) {
  const auto dir = atmos_test::scratch_directory("post-cli");
  const std::string common = "render --tables small --size 48x32 --sun-elevation 5 --look 180,5 --exposure 11 ";
  auto r = atmos_test::run_cli(dir, common + "--tonemap filmic --bloom 0.1 --auto-exposure -o post.png -o post.exr");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("auto exposure: EV100 "), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "post.png"));
  const Image exr = atmos::read_exr((dir / "post.exr").string());
  r = atmos_test::run_cli(dir, common + "-o plain.exr -o plain.png");
  ASSERT_EQ(r.code, 0) << r.err;
  const Image plain = atmos::read_exr((dir / "plain.exr").string());
  EXPECT_EQ(exr.rgb, plain.rgb) << "EXR output is the HDR image whatever the PNG options";
  r = atmos_test::run_cli(dir, common + "--tonemap exp -o exp.png");
  ASSERT_EQ(r.code, 0) << r.err;
  int w = 0, h = 0, n = 0;
  unsigned char* a = stbi_load((dir / "plain.png").string().c_str(), &w, &h, &n, 3);
  unsigned char* b = stbi_load((dir / "exp.png").string().c_str(), &w, &h, &n, 3);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  int worst = 0;
  for (int i = 0; i < w * h * 3; ++i) worst = std::max(worst, std::abs(int(a[i]) - int(b[i])));
  stbi_image_free(a);
  stbi_image_free(b);
  EXPECT_LE(worst, 1);
  for (const char* bad : {"--tonemap hable", "--bloom -0.5", "--bloom 2", "--bloom nan"}) {
    r = atmos_test::run_cli(dir, common + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("error"), std::string::npos) << bad;
  }
}

}  // namespace
