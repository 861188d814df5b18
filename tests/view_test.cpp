// atmos view end to end under Xvfb: a screenshot of sky over ground,
// scripted flying and slider drags, deterministic replays, and one-line
// errors for bad input. The flight model, the recorded flights and the
// scripts are unit-tested in flight_test.cpp. ViewCliLong (the full tier):
// new tables shown first by the instant mode, the date's sun and moon, a
// rebind over the same ground and the anaglyph.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "png_decoder.hpp"
#include "sun_disc.hpp"
#include "atmos/image.hpp"
#include "atmos/planet_file.hpp"
#include <glm/vec2.hpp>
#include <nlohmann/json.hpp>
#include <algorithm>

namespace {

namespace fs = std::filesystem;

using atmos_test::CliRun;

// ---------------------------------------------------------------------------
// The viewer end to end. Its window needs an X server: each run goes
// through xvfb-run (Debian's xvfb), and the tests skip when it is missing.

fs::path scratch() {
  static const fs::path dir = atmos_test::scratch_directory("view-cli");
  return dir;
}

bool have_xvfb() { return std::system("command -v xvfb-run > /dev/null 2>&1") == 0; }

const std::string kXvfb = "xvfb-run -a -s '-screen 0 640x480x24'";
const std::string kSmall = " --tables small --width 320 --height 180";

CliRun view(const std::string& args, bool window = true) {
  return atmos_test::run_cli(scratch(), "view" + kSmall + " " + args, "", window ? kXvfb : "");
}

bool built_with_viewer() {
  static const bool built =
      atmos_test::run_cli(scratch(), "view --frames 1 --tables small --planet " + (scratch() / "none.json").string())
          .err.find("was not built") == std::string::npos;
  return built;
}

#define SKIP_WITHOUT_VIEWER()                                                    \
  if (!built_with_viewer()) GTEST_SKIP() << "atmos was built without the viewer"; \
  if (!have_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (Debian's xvfb)"

// The number after `key` in the viewer's output (NaN if absent).
double figure(const std::string& out, const std::string& key) {
  const size_t at = out.find(key);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(out.c_str() + at + key.size(), nullptr);
}

struct Rgb {
  double r = 0, g = 0, b = 0;
};

// Mean sRGB-encoded colour of rows [y0, y1) of a PNG.
Rgb mean_rows(const fs::path& png, double y0_fraction, double y1_fraction) {
  int w = 0, h = 0, n = 0;
  unsigned char* pixels = stbi_load(png.string().c_str(), &w, &h, &n, 3);
  Rgb m;
  if (!pixels) return m;
  const int y0 = int(y0_fraction * h), y1 = int(y1_fraction * h);
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < w; ++x) {
      const unsigned char* p = pixels + (size_t(y) * size_t(w) + size_t(x)) * 3;
      m.r += p[0];
      m.g += p[1];
      m.b += p[2];
    }
  const double count = double(w) * double(y1 - y0);
  m.r /= count;
  m.g /= count;
  m.b /= count;
  stbi_image_free(pixels);
  return m;
}

TEST(ViewCli, ScreenshotShowsSkyOverGround) {
  SKIP_WITHOUT_VIEWER();
  const fs::path png = scratch() / "ground.png", exr = scratch() / "ground.exr";
  const CliRun r = view("--frames 3 --no-ui --screenshot " + png.string() + " --screenshot " + exr.string());
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(png)) << r.out;
  // The first frame's programs alone, linked on two threads before it.
  EXPECT_NE(r.out.find("(programs linked beforehand: yes)"), std::string::npos) << r.out;
  // 2 m above the Sahara (20 N, 30 E), looking east at the horizon: a blue
  // sky over yellow-brown ground.
  const Rgb sky = mean_rows(png, 0.0, 0.3), ground = mean_rows(png, 0.7, 1.0);
  EXPECT_GT(sky.b, sky.r + 10.0) << sky.r << " " << sky.g << " " << sky.b;
  EXPECT_GT(ground.r, ground.b + 10.0) << ground.r << " " << ground.g << " " << ground.b;
  EXPECT_GT(ground.r + ground.g + ground.b, 60.0);
  // The EXR is the linear image of the same view, in cd/m²: a sky of
  // thousands of cd/m² by day.
  const atmos::Image image = atmos::read_exr(exr.string());
  ASSERT_EQ(image.width, 320);
  const float* top = &image.rgb[(5 * 320 + 160) * 3];
  EXPECT_GT(top[2], top[0]);
  EXPECT_GT(top[2], 1000.0f);
}

TEST(ViewCli, ScriptFliesTheCameraAndDragsASlider) {
  SKIP_WITHOUT_VIEWER();
  const fs::path script = scratch() / "fly.json", record = scratch() / "fly-record.json";
  std::ofstream(script) << R"({"events": [
      {"frame": 1, "frames": 8, "key": "W"},
      {"frame": 9, "frames": 4, "mouse": [30, -10]},
      {"frame": 13, "key": "2"},
      {"frame": 20, "frames": 12, "slider": "sun_azimuth", "from": 180, "to": 200},
      {"frame": 33, "frames": 2, "slider": "ground_albedo", "from": 0.5, "to": 1.5},
      {"frame": 36, "save": ")" + (scratch() / "saved.json").string() + R"("},
      {"frame": 37, "save": ")" + (scratch() / "no-such-dir" / "saved.json").string() + R"("}]})";
  const CliRun r = view("--surface sphere --script " + script.string() + " --record " + record.string());
  ASSERT_EQ(r.code, 0) << r.err;
  // The planet on screen saved from the panel (the impossible albedo was
  // not kept), and a path that cannot be written: an error in the panel.
  const atmos::Atmosphere saved = atmos::load_atmosphere((scratch() / "saved.json").string());
  EXPECT_TRUE(saved.ground_albedo == atmos::load_atmosphere("earth").ground_albedo);
  EXPECT_NE(r.err.find("cannot write the planet file"), std::string::npos) << r.err;
  // W for 8 frames of 1/30 s at 2 m/s, then the jump to 10 km.
  EXPECT_NEAR(figure(r.out, "camera: altitude "), 10e3, 1.0) << r.out;
  EXPECT_NEAR(figure(r.out, "heading "), 90.0 + 4 * 30 * 0.15, 1e-6) << r.out;
  // An impossible albedo typed into the panel: a one-line error, the old
  // tables stay and the session goes on.
  EXPECT_NE(r.err.find("ground albedo must be in [0, 1], got 1.5"), std::string::npos) << r.err;
  // The frame times during the drag, against the median: printed, not
  // asserted (a shared machine's frames vary).
  const double ratio = figure(r.out, "max/median ");
  EXPECT_TRUE(std::isfinite(ratio)) << r.out;
  std::printf("slider drag: max/median frame time %.2f\n", ratio);
  // The record holds every frame drawn, the camera's path in it.
  std::ifstream in(record);
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_GE(j["frames"].size(), 35u);
  const auto& first = j["frames"].front()["position_m"];
  const auto& last = j["frames"].back()["position_m"];
  double moved = 0.0;
  for (size_t i = 0; i < 3; ++i) moved += std::pow(last[i].get<double>() - first[i].get<double>(), 2);
  EXPECT_GT(std::sqrt(moved), 9e3);
}

// A jump to a view whose programs the pass has not linked (orbit, from the
// ground): they are linked and compiled first on a thread of the viewer's in the
// shared context, then the camera jumps (a scripted session waits for
// them, so that its path is the script's). The full tier's: the orbit's
// programs take about 10 s to compile on llvmpipe.
TEST(ViewCliLong, JumpPreparesItsProgramsFirst) {
  SKIP_WITHOUT_VIEWER();
  const fs::path script = scratch() / "jump.json";
  std::ofstream(script) << R"({"events": [{"frame": 2, "key": "3"}, {"frame": 4, "mouse": [0, 0]}]})";
  const CliRun r = view("--surface sphere --no-ui --script " + script.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("jump 3: its programs prepared in"), std::string::npos) << r.out;
  EXPECT_NEAR(figure(r.out, "camera: altitude "), 400e3, 1.0) << r.out;
}

// --date: the sun and the Moon of that instant over the starting point. In
// the totality of 8 April 2024 at Mazatlan the sky is dark; an hour later,
// with the Moon off the sun, it is a day sky again.
TEST(ViewCliLong, DatePlacesTheSunAndTheMoonOfThatInstant) {
  SKIP_WITHOUT_VIEWER();
  const auto sky = [&](const std::string& time) {
    const fs::path png = scratch() / ("date-" + time.substr(0, 2) + ".png");
    const CliRun r = view("--surface sphere --no-ui --frames 2 --pitch 30 --latitude 25.29 --longitude -104.14 --date 2024-04-08T" +
                          time + "Z --screenshot " + png.string());
    EXPECT_EQ(r.code, 0) << r.err;
    const Rgb m = mean_rows(png, 0.0, 1.0);
    return m.r + m.g + m.b;
  };
  const double totality = sky("18:18:00"), after = sky("19:30:00");
  EXPECT_GT(after, 200.0);
  EXPECT_LT(totality, 0.1 * after);
  const CliRun r = view("--frames 1 --date 2024-04-08T18:18:00Z", false);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--latitude"), std::string::npos) << r.err;
}

// New tables over the same ground are swapped in by rebinding the scene
// (their pass built on one frame, its programs and the globe's linked on
// the scene's thread in a shared context while the old tables are drawn,
// then Globe::rebind: the globe, its rasters and tiles kept), and the
// session runs on past the swap to measure it. The programs of the frame
// on screen are all linked before the swap, so that none is compiled on
// the viewer's thread. The swap's frames against the median are printed,
// not asserted: the first draws with the new programs still compile their
// machine code on llvmpipe (docs/viewer.md).
TEST(ViewCliLong, TablesOverTheSameGroundRebindTheGlobe) {
  SKIP_WITHOUT_VIEWER();
  const fs::path script = scratch() / "reswap.json";
  std::ofstream(script) << R"({"events": [{"frame": 2, "planet": "earth"}]})";
  const CliRun r = view("--surface globe --script " + script.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("ms to rebind the scene; programs linked beforehand: yes)"), std::string::npos) << r.out;
  const double ratio = figure(r.out, "swap max/median ");
  EXPECT_TRUE(std::isfinite(ratio)) << r.out;
  // The frames from the swap on: the new pass's, those while its programs
  // are linked, the rebind's and five more.
  EXPECT_GE(figure(r.out, "swap: "), 7.0) << r.out;
  std::printf("swap over the globe: max/median frame time %.2f\n", ratio);
}

// A planet slider released over the globe, with tables the cache does not
// hold (a density scale of 1.37): the instant mode's tables
// (compute_instant_tables) are swapped in first, the globe rebound to their
// pass and lit through its GLSL library, while the exact tables are
// computed; then the exact ones replace them. With --no-instant-preview
// the old tables stay until the exact ones are there.
TEST(ViewCliLong, NewTablesShowTheInstantApproximationFirst) {
  SKIP_WITHOUT_VIEWER();
  const fs::path script = scratch() / "instant.json";
  std::ofstream(script) << R"({"events": [{"frame": 2, "frames": 2, "slider": "density_scale", "from": 1.2, "to": 1.37}]})";
  const fs::path cache = scratch() / "instant-cache";
  fs::remove_all(cache);
  const std::string args = "--surface globe --cache-dir " + cache.string() + " --script " + script.string();
  const CliRun r = view(args);
  ASSERT_EQ(r.code, 0) << r.err;
  const size_t instant = r.out.find("tables: instant approximation (exact tables being computed)");
  const size_t exact = r.out.find("tables: computed and cached", instant == std::string::npos ? 0 : instant);
  ASSERT_NE(instant, std::string::npos) << r.out;
  ASSERT_NE(exact, std::string::npos) << r.out;
  const double instant_frame = figure(r.out.substr(instant), "swapped in at frame ");
  const double exact_frame = figure(r.out.substr(exact), "swapped in at frame ");
  std::printf("density scale released at frame 3: the instant approximation on screen at frame %.0f, the exact "
              "tables at frame %.0f\n", instant_frame, exact_frame);
  EXPECT_LT(instant_frame, exact_frame);
  fs::remove_all(cache);
  const CliRun off = view(args + " --no-instant-preview");
  ASSERT_EQ(off.code, 0) << off.err;
  EXPECT_EQ(off.out.find("instant approximation"), std::string::npos) << off.out;
  EXPECT_NE(off.out.find("tables: computed and cached"), std::string::npos) << off.out;
}

// The centre of the sun's disc in one channel of a linear image (cd/m²).
glm::dvec2 channel_disc_centre(const atmos::Image& image, int channel) {
  std::vector<double> values(size_t(image.width) * size_t(image.height));
  for (size_t i = 0; i < values.size(); ++i) values[i] = image.rgb[3 * i + size_t(channel)];
  return atmos_test::disc_centre(values, image.width, image.height);
}

// The window in red-cyan stereo over the globe: the sun ahead, 5° up,
// falls in the left eye's image (the red channel) and the right eye's
// (green) ipd / convergence apart in tangent units, 0.01 m / 2 m x 2062 px
// per unit of tangent (180 px over 5°, where the disc is 19 px across):
// 10.31 px, at the same height. The PNG is the window as shown, with the
// panel's Stereo section.
TEST(ViewCliLong, AnaglyphPutsEachEyesSunWhereItsFrustumDoes) {
  SKIP_WITHOUT_VIEWER();
  const fs::path png = scratch() / "anaglyph.png", exr = scratch() / "anaglyph.exr";
  const CliRun r = view("--frames 2 --stereo anaglyph --ipd 0.01 --convergence 2 --fov 5 --pitch 5 "
                        "--sun-azimuth 90 --sun-elevation 5 --screenshot " + png.string() + " --screenshot " +
                        exr.string());
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(png)) << r.out;
  const atmos::Image image = atmos::read_exr(exr.string());
  ASSERT_EQ(image.width, 320);
  ASSERT_EQ(image.height, 180);
  const glm::dvec2 left = channel_disc_centre(image, 0), right = channel_disc_centre(image, 1);
  const double expected = 0.01 / 2.0 * 180.0 / (2.0 * std::tan(2.5 * M_PI / 180.0));
  std::printf("anaglyph: the sun at (%.3f, %.3f) in the left eye, (%.3f, %.3f) in the right: disparity %.3f px "
              "(expected %.3f)\n", left.x, left.y, right.x, right.y, right.x - left.x, expected);
  // The red and the green discs of a sun 5° up are reddened unevenly across
  // them by the air: their centroids differ by hundredths of a pixel.
  EXPECT_NEAR(right.x - left.x, expected, 0.15);
  EXPECT_NEAR(right.y, left.y, 0.1);
  const CliRun bad = view("--frames 1 --stereo anaglyph --convergence 0", false);
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--convergence must be > 0"), std::string::npos) << bad.err;
}

// atmos view --xr without an OpenXR runtime: a one-line error before any
// window opens (built without OpenXR: that it was). The mock headset goes
// the same way, headless, and writes each eye.
TEST(ViewCli, HeadsetsWithoutARuntimeAndTheMock) {
  SKIP_WITHOUT_VIEWER();
  CliRun r = atmos_test::run_cli(scratch(), "view --xr --frames 1" + kSmall, "", "env -u XR_RUNTIME_JSON");
  EXPECT_EQ(r.code, 1) << r.out;
  const bool openxr = r.err.find("built without OpenXR") == std::string::npos;
  if (openxr) {
    EXPECT_NE(r.err.find("no OpenXR runtime is installed/active (XR_ERROR_"), std::string::npos) << r.err;
  }
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  const fs::path mock = scratch() / "headset.json", eyes = scratch() / "eyes";
  std::ofstream(mock) << R"({"width": 64, "height": 48, "frames": 2, "eyes": [
    {"position_m": [-0.032, 0, 0], "orientation_wxyz": [1, 0, 0, 0],
     "fov_deg": {"left": -45, "right": 38, "up": 30, "down": -34}},
    {"position_m": [0.032, 0, 0], "orientation_wxyz": [1, 0, 0, 0],
     "fov_deg": {"left": -38, "right": 45, "up": 34, "down": -30}}]})";
  r = view("--surface sphere --xr-mock " + mock.string() + " --frame-format both --output-dir " + eyes.string(), false);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("headset: 2 frames of 64x48 per eye"), std::string::npos) << r.out;
  const atmos::Image left = atmos::read_exr((eyes / "eye-left.exr").string());
  const atmos::Image right = atmos::read_exr((eyes / "eye-right.exr").string());
  ASSERT_EQ(left.width, 64);
  ASSERT_EQ(right.height, 48);
  EXPECT_TRUE(fs::exists(eyes / "eye-left.png"));
  EXPECT_NE(left.rgb, right.rgb);  // their angles differ
  r = view("--xr-mock " + mock.string() + " --stereo anaglyph --output-dir " + eyes.string(), false);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("a headset (--xr, --xr-mock) shows each eye itself"), std::string::npos) << r.err;
}

// A flight replayed twice, headless, gives the same files byte for byte.
TEST(ViewCli, ReplaysAreDeterministic) {
  if (!built_with_viewer()) GTEST_SKIP() << "atmos was built without the viewer";
  const fs::path record = scratch() / "replay.json";
  // Two frames over the globe, 2 m above the ground looking at the
  // horizon: the sun high, then low with the stars, another tone mapper
  // and the eye adapting.
  std::ofstream(record) << R"({"format": "atmos-flight", "version": 1, "surface": "globe", "planet_albedo": false,
    "width": 96, "height": 54, "frames": [
    {"time_s": 0, "position_m": [5200000.0, 3002000.0, 2175300.0], "forward": [-0.5, 0.866025403784, 0.0],
     "up": [0.8137976813, 0.4698463104, 0.3420201433], "sun": [0.2, 0.9, 0.38],
     "look": {"exposure_ev": 12, "auto_exposure": true, "compensation_ev": 0, "tone_mapping": "filmic",
              "bloom": 0.05, "stars": false, "moon": false, "moon_separation_deg": 0.1, "fov_deg": 60},
     "planet": {"planet": "earth", "wavelengths": 0, "orders": 4, "density_scale": 1, "solar": "",
                "table_sizes": "small", "bottom_radius_m": null, "thickness_m": null, "ground_albedo": null}},
    {"time_s": 0.5, "position_m": [5200000.0, 3002000.0, 2175300.0], "forward": [-0.5, 0.866025403784, 0.0],
     "up": [0.8137976813, 0.4698463104, 0.3420201433], "sun": [0.5, 0.8, 0.1],
     "look": {"exposure_ev": 11, "auto_exposure": true, "compensation_ev": 0.5, "tone_mapping": "aces",
              "bloom": 0.1, "stars": true, "moon": false, "moon_separation_deg": 0.2, "fov_deg": 60},
     "planet": {"planet": "earth", "wavelengths": 0, "orders": 4, "density_scale": 1, "solar": "",
                "table_sizes": "small", "bottom_radius_m": null, "thickness_m": null, "ground_albedo": null}}]})";
  for (const char* dir : {"replay-a", "replay-b"}) {
    const CliRun r = atmos_test::run_cli(scratch(), "view --replay " + record.string() + " --frame-format both --output-dir " +
                                                        (scratch() / dir).string());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  for (const char* name : {"frame-00000.png", "frame-00000.exr", "frame-00001.png", "frame-00001.exr"}) {
    const fs::path a = scratch() / "replay-a" / name, b = scratch() / "replay-b" / name;
    ASSERT_TRUE(fs::exists(a)) << a;
    EXPECT_EQ(atmos_test::slurp(a), atmos_test::slurp(b)) << name;
  }
  // The frames differ (the sun moved).
  EXPECT_NE(atmos_test::slurp(scratch() / "replay-a" / "frame-00000.exr"),
            atmos_test::slurp(scratch() / "replay-a" / "frame-00001.exr"));
}

TEST(ViewCli, BadInputIsAOneLineError) {
  if (!built_with_viewer()) GTEST_SKIP() << "atmos was built without the viewer";
  // No display: neither DISPLAY nor WAYLAND_DISPLAY.
  CliRun r = atmos_test::run_cli(scratch(), "view --frames 1" + kSmall, "", "env -u DISPLAY -u WAYLAND_DISPLAY");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no display"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // An unreadable planet file, before any window opens.
  r = view("--frames 1 --planet " + (scratch() / "no-such-planet.json").string(), false);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no-such-planet.json"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // A missing record, a bad script.
  r = atmos_test::run_cli(scratch(), "view --replay " + (scratch() / "none.json").string() + " --output-dir out");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("cannot read the flight record"), std::string::npos) << r.err;
  std::ofstream(scratch() / "bad-script.json") << R"({"events": [{"frame": 0, "slider": "warp", "from": 0, "to": 1}]})";
  r = view("--script " + (scratch() / "bad-script.json").string(), false);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("unknown slider \"warp\""), std::string::npos) << r.err;
  // Usage errors: exit code 2, before any work.
  r = view("--screenshot shot.png", false);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--screenshot needs --frames"), std::string::npos) << r.err;
  r = view("--frames 1 --orders auto", false);
  EXPECT_EQ(r.code, 2);
  r = view("--frames 1 --altitude -5", false);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--altitude must be in [0, 1e12] metres, got -5"), std::string::npos) << r.err;
}

}  // namespace
