// The example engine (examples/terrain, atmos_example_terrain) end to end:
// every scene with every depth encoding renders a finite, lit image; the
// three depth encodings give the same image; the G-buffer mode and the
// engine-only image work; bad input is a one-line error with the right exit
// code. Small images, small tables and a coarse terrain keep each run to a
// few seconds on llvmpipe.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/image.hpp"
#include "cli_support.hpp"
#include "png_decoder.hpp"

namespace {

namespace fs = std::filesystem;

fs::path scratch() {
  static const fs::path dir = atmos_test::scratch_directory("example");
  return dir;
}

struct ExampleRun {
  int code = -1;
  std::string out, err;
};

// Runs the example in the scratch directory with its own table cache there.
ExampleRun run_example(const std::string& args, const std::string& environment = "") {
  const fs::path out = scratch() / "stdout.txt", err = scratch() / "stderr.txt";
  const std::string command = "cd '" + scratch().string() + "' && ATMOS_CACHE_DIR='" + (scratch() / "cache").string() +
                              "' " + environment + " '" + ATMOS_EXAMPLE + "' " + args + " > '" + out.string() +
                              "' 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  ExampleRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = atmos_test::slurp(out);
  r.err = atmos_test::slurp(err);
  return r;
}

int lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

// Small and fast: 160x90, small tables, a 128x128-cell terrain, a 512² shadow map.
const std::string kFast = " --width 160 --height 90 --tables small --terrain-cells 128 --shadow-size 512";

std::vector<double> luminances(const atmos::Image& image) {
  std::vector<double> y(static_cast<size_t>(image.width) * image.height);
  for (size_t i = 0; i < y.size(); ++i)
    y[i] = atmos::srgb_luminance({image.rgb[3 * i], image.rgb[3 * i + 1], image.rgb[3 * i + 2]});
  return y;
}

// Renders `args` into an EXR in the scratch directory and reads it back.
atmos::Image render(const std::string& name, const std::string& args) {
  const fs::path path = scratch() / (name + ".exr");
  fs::remove(path);
  const ExampleRun r = run_example(args + kFast + " -o " + path.string());
  EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
  EXPECT_TRUE(fs::exists(path)) << args;
  if (r.code != 0 || !fs::exists(path)) return {};
  // The timings are reported.
  EXPECT_NE(r.out.find("engine: shadow map"), std::string::npos) << r.out;
  return atmos::read_exr(path.string());
}

// Finite, non-negative, and lit: the image is not black.
void expect_plausible(const atmos::Image& image, const std::string& what) {
  ASSERT_EQ(image.width, 160) << what;
  ASSERT_EQ(image.height, 90) << what;
  for (float v : image.rgb) {
    ASSERT_TRUE(std::isfinite(v)) << what;
    ASSERT_GE(v, 0.0f) << what;
  }
  const std::vector<double> y = luminances(image);
  double mean = 0.0;
  for (double v : y) mean += v / static_cast<double>(y.size());
  EXPECT_GT(mean, 10.0) << what << ": mean luminance " << mean << " cd/m²";
}

// How much two renders of the same view differ: the mean over pixels of
// |Ya - Yb| / (Ya + Yb + 1 cd/m²) (symmetric, bounded by 1), and the fraction
// of pixels differing by more than 2 %.
struct Difference {
  double mean = 0.0;
  double fraction_over_2_percent = 0.0;
};

Difference difference(const atmos::Image& a, const atmos::Image& b) {
  const std::vector<double> ya = luminances(a), yb = luminances(b);
  Difference d;
  for (size_t i = 0; i < ya.size(); ++i) {
    const double rel = std::abs(ya[i] - yb[i]) / (ya[i] + yb[i] + 1.0);
    d.mean += rel / static_cast<double>(ya.size());
    if (2.0 * rel > 0.02) d.fraction_over_2_percent += 1.0 / static_cast<double>(ya.size());
  }
  return d;
}

class ExampleScene : public testing::TestWithParam<const char*> {};

// Every depth encoding gives the same image. They rasterise the same pixels
// (the same clip-space x, y and w); only the depth values, and so the
// positions the plugin reconstructs from them, differ. Tolerance: 0.2 %
// mean relative difference, and at most 0.5 % of the pixels (object/terrain
// contact lines, where depth precision decides which surface wins) more than
// 2 % apart. (Measured: ~1e-7 and none: float rounding.)
TEST_P(ExampleScene, RendersTheSameImageWithEveryDepthEncoding) {
  const std::string scene = GetParam();
  const atmos::Image standard = render(scene + "-standard", "--scene " + scene + " --depth standard");
  const atmos::Image reversed = render(scene + "-reversed-z", "--scene " + scene + " --depth reversed-z");
  const atmos::Image logarithmic = render(scene + "-log", "--scene " + scene + " --depth log");
  ASSERT_FALSE(standard.rgb.empty());
  ASSERT_FALSE(reversed.rgb.empty());
  ASSERT_FALSE(logarithmic.rgb.empty());
  expect_plausible(standard, scene + " standard");
  expect_plausible(reversed, scene + " reversed-z");
  expect_plausible(logarithmic, scene + " log");
  for (const auto& [name, other] : {std::pair{"reversed-z", &reversed}, std::pair{"log", &logarithmic}}) {
    const Difference d = difference(standard, *other);
    std::printf("%s, standard vs %s: mean relative difference %.2e, %.4f of the pixels over 2 %%\n", scene.c_str(),
                name, d.mean, d.fraction_over_2_percent);
    EXPECT_LT(d.mean, 0.002) << scene << ": standard vs " << name;
    EXPECT_LT(d.fraction_over_2_percent, 0.005) << scene << ": standard vs " << name;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ExampleScene, testing::Values("noon-valley", "sunset-shafts", "orbit-400km"),
                         [](const testing::TestParamInfo<const char*>& param) {
                           std::string name = param.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(Example, InfiniteFarPlaneAndGBufferMatchTheDefault) {
  const atmos::Image standard = render("noon-default", "--scene noon-valley");
  const atmos::Image infinite = render("noon-infinite", "--scene noon-valley --infinite-far");
  const atmos::Image gbuffer = render("noon-gbuffer", "--scene noon-valley --surfaces gbuffer");
  ASSERT_FALSE(standard.rgb.empty());
  ASSERT_FALSE(infinite.rgb.empty());
  ASSERT_FALSE(gbuffer.rgb.empty());
  expect_plausible(gbuffer, "gbuffer");
  const Difference d = difference(standard, infinite);
  const Difference g = difference(standard, gbuffer);
  std::printf(
      "noon-valley, finite vs infinite far plane: mean relative difference %.2e; lit colour vs G-buffer: "
      "%.2e, %.4f of the pixels over 2 %%\n",
      d.mean, g.mean, g.fraction_over_2_percent);
  EXPECT_LT(d.mean, 0.002);
  EXPECT_LT(d.fraction_over_2_percent, 0.005);
  // The plugin lights the G-buffer with the same sun and sky irradiance and
  // the same shadow map as the engine's shader, but filters the shadows its
  // own way: close, not identical.
  EXPECT_LT(g.mean, 0.01);
  EXPECT_LT(g.fraction_over_2_percent, 0.05);
}

TEST(Example, TheAtmosphereAddsSkyAndHaze) {
  // Without the plugin the sky is the engine's black clear colour; with it,
  // the top rows (sky) are bright and the whole image is brighter (haze).
  const atmos::Image with = render("noon-with", "--scene noon-valley");
  const atmos::Image without = render("noon-without", "--scene noon-valley --no-atmosphere");
  ASSERT_FALSE(with.rgb.empty());
  ASSERT_FALSE(without.rgb.empty());
  const std::vector<double> y_with = luminances(with), y_without = luminances(without);
  double top_with = 0.0, top_without = 0.0;
  for (int x = 0; x < with.width; ++x) {
    top_with += y_with[static_cast<size_t>(x)] / with.width;
    top_without += y_without[static_cast<size_t>(x)] / with.width;
  }
  EXPECT_EQ(top_without, 0.0);
  EXPECT_GT(top_with, 1000.0);  // a clear daytime sky: several thousand cd/m²
  // Surfaces (the engine drew them: non-zero without the plugin) change:
  // attenuated and hazed by the air between them and the camera, even the
  // valley floor a few hundred metres to a few km away.
  double change = 0.0;
  int surfaces = 0;
  for (size_t i = 0; i < y_with.size(); ++i)
    if (y_without[i] > 0.0) {
      change += std::abs(y_with[i] - y_without[i]) / y_without[i];
      ++surfaces;
    }
  ASSERT_GT(surfaces, 0);
  std::printf("aerial perspective changes the surfaces by %.1f %% on average\n", 100.0 * change / surfaces);
  EXPECT_GT(change / surfaces, 0.02);
}

// A total eclipse over the valley (--moon on the sun): the engine's own
// lighting (lit colour, dimmed by its shader with the library's shared
// functions) and the plugin's G-buffer lighting darken the scene alike, by
// orders of magnitude, and neither goes black or NaN.
TEST(Example, TotalEclipseDarkensTheValleyInBothSurfaceModes) {
  const std::string sun = " --scene noon-valley --sun-elevation 40 --sun-azimuth 150";
  const atmos::Image day = render("eclipse-day", sun);
  const atmos::Image lit = render("eclipse-lit", sun + " --moon 150,40,0.28");
  const atmos::Image gbuffer = render("eclipse-gbuffer", sun + " --moon 150,40,0.28 --surfaces gbuffer");
  ASSERT_FALSE(day.rgb.empty());
  ASSERT_FALSE(lit.rgb.empty());
  ASSERT_FALSE(gbuffer.rgb.empty());
  auto mean = [](const atmos::Image& image) {
    double m = 0.0;
    for (double v : luminances(image)) m += v;
    return m / static_cast<double>(image.width * image.height);
  };
  for (float v : lit.rgb) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
  for (float v : gbuffer.rgb) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
  const std::vector<double> y_lit = luminances(lit), y_gbuffer = luminances(gbuffer);
  double largest_ratio = 0.0;  // of the two modes, over the pixels
  for (size_t i = 0; i < y_lit.size(); ++i)
    largest_ratio = std::max(largest_ratio, std::abs(std::log((y_lit[i] + 1e-3) / (y_gbuffer[i] + 1e-3))));
  std::printf("totality over the valley: mean %.4g cd/m2 (lit colour), %.4g (G-buffer), day %.4g; "
              "largest |ln ratio| of the modes %.3f\n",
              mean(lit), mean(gbuffer), mean(day), largest_ratio);
  EXPECT_LT(mean(lit), 1e-2 * mean(day));
  EXPECT_LT(mean(gbuffer), 1e-2 * mean(day));
  EXPECT_GT(mean(lit), 0.0);
  EXPECT_NEAR(mean(gbuffer) / mean(lit), 1.0, 0.01);
}

void expect_usage_error(const std::string& args, const std::string& needle) {
  const ExampleRun r = run_example(args);
  EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
  EXPECT_EQ(lines(r.err), 1) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
}

// The example's camera-like output: its PNG through atmos::PostProcess on
// the composited texture. With the exp operator it is the default PNG
// (write_png on the CPU) to within one 8-bit step; filmic with bloom, auto
// exposure and the star field runs and reports its passes.
TEST(Example, PostProcessAfterThePass) {
  const fs::path plain = scratch() / "plain.png", post = scratch() / "post.png", filmic = scratch() / "filmic.png";
  ASSERT_EQ(run_example(kFast + " -o " + plain.string()).code, 0);
  ExampleRun r = run_example(kFast + " --tonemap exp -o " + post.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("post: bloom"), std::string::npos) << r.out;
  auto load = [](const fs::path& path) {
    int w = 0, h = 0, n = 0;
    unsigned char* data = stbi_load(path.string().c_str(), &w, &h, &n, 3);
    std::vector<unsigned char> pixels;
    if (data != nullptr) pixels.assign(data, data + size_t(w) * size_t(h) * 3);
    stbi_image_free(data);
    return pixels;
  };
  const std::vector<unsigned char> a = load(plain), b = load(post);
  ASSERT_EQ(a.size(), size_t(160 * 90 * 3));
  ASSERT_EQ(b.size(), a.size());
  size_t equal = 0;
  int worst = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    equal += a[i] == b[i] ? 1 : 0;
    worst = std::max(worst, std::abs(int(a[i]) - int(b[i])));
  }
  std::printf("exp through PostProcess vs write_png: %zu of %zu bytes equal, largest difference %d\n", equal, a.size(),
              worst);
  EXPECT_LE(worst, 1);
  EXPECT_GE(double(equal) / double(a.size()), 0.999);
  r = run_example(" --scene sunset-shafts --tonemap filmic --bloom 0.05 --auto-exposure --stars" + kFast + " -o " +
                  filmic.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("auto exposure: EV100"), std::string::npos) << r.out;
  EXPECT_EQ(load(filmic).size(), a.size());
  EXPECT_EQ(run_example(kFast + " --bloom 2").code, 2);
}

TEST(Example, UsageErrorsAreOneLineWithExitCode2) {
  EXPECT_EQ(run_example("--help").code, 0);
  expect_usage_error("--frobnicate", "frobnicate");
  expect_usage_error("--scene nowhere", "--scene");
  expect_usage_error("--depth w-buffer", "--depth");
  expect_usage_error("--surfaces deferred", "--surfaces");
  expect_usage_error("--width 0", "--width");
  expect_usage_error("--look 10", "--look");
  expect_usage_error("--look 10,95", "--look");
  expect_usage_error("--sun-elevation nan", "--sun-elevation");
  expect_usage_error("--fov 180", "--fov");
  expect_usage_error("--camera-altitude -3", "--camera-altitude");
  expect_usage_error("--depth log --infinite-far", "--infinite-far");
  expect_usage_error("-o image.tiff", "image.tiff");
}

TEST(Example, RuntimeErrorsAreOneLineWithExitCode1) {
  ExampleRun r = run_example("--planet /no/such/planet.json" + kFast);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  r = run_example("-o /no/such/dir/out.png" + kFast);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("/no/such/dir/out.png"), std::string::npos) << r.err;
  // Without an EGL vendor library no OpenGL 4.5 context can be had.
  r = run_example("-o nogl.png" + kFast,
                  "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json LIBGL_DRIVERS_PATH=/nonexistent");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("OpenGL"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "nogl.png"));
}

}  // namespace
