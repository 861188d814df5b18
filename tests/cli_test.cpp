// The `atmos` command line, end to end: exit codes, one-line errors, CSV
// output, and physically plausible images. CliRenders (the full tier): the
// projections and the CPU path, the all-sky fisheye, the eclipsed ground and
// the stereo pair, whose functions the default tier tests in the library's
// suites (Plugin, GlobeGpu, EclipseGpu, StereoGpu).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/ephemeris.hpp"
#include "atmos/image.hpp"
#include "cli_support.hpp"

namespace {

namespace fs = std::filesystem;

using atmos_test::CliRun;
using atmos_test::slurp;

fs::path scratch() {
  static const fs::path dir = atmos_test::scratch_directory("cli");
  return dir;
}

// Runs the CLI with small tables cached in the scratch directory.
CliRun atmos_cli(const std::string& args, const std::string& stdin_text = "", const std::string& environment = "") {
  return atmos_test::run_cli(scratch(), args, stdin_text, environment);
}

int lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

void expect_usage_error(const std::string& args, const std::string& needle) {
  const CliRun r = atmos_cli(args);
  EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
  EXPECT_EQ(lines(r.err), 1) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
}

void expect_runtime_error(const std::string& args, const std::string& needle) {
  const CliRun r = atmos_cli(args);
  EXPECT_EQ(r.code, 1) << args << "\n" << r.err;
  EXPECT_EQ(lines(r.err), 1) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
}

const std::string kSmall = " --tables small";

TEST(Cli, HelpEverywhere) {
  for (const char* cmd :
       {"--help", "render --help", "precompute --help", "sample --help", "bench --help", "plot-data --help"}) {
    const CliRun r = atmos_cli(cmd);
    EXPECT_EQ(r.code, 0) << cmd;
    EXPECT_NE(r.out.find("--"), std::string::npos) << cmd;
  }
  EXPECT_NE(atmos_cli("sample --help").out.find("--reference"), std::string::npos);
}

TEST(Cli, UsageErrorsAreOneLineWithExitCode2) {
  expect_usage_error("render --frobnicate", "frobnicate");
  expect_usage_error("render --size 100000x10" + kSmall, "--size");
  expect_usage_error("render --size banana" + kSmall, "--size");
  expect_usage_error("render --sun-elevation nan" + kSmall, "finite");
  expect_usage_error("render --sun-elevation 95" + kSmall, "--sun-elevation");
  expect_usage_error("render --altitude -5" + kSmall, "--altitude");
  expect_usage_error("render --look 10" + kSmall, "--look");
  expect_usage_error("render --projection orthographic" + kSmall, "projection");
  expect_usage_error("render --orders 0" + kSmall, "--orders");
  expect_usage_error("render --position 0,0,10" + kSmall, "inside the planet");
  expect_usage_error("sample --sun-elevation abc", "sun-elevation");
  expect_usage_error("precompute --wavelengths 2" + kSmall, "--wavelengths");
  expect_usage_error("precompute --wavelengths 49" + kSmall, "--wavelengths");
  expect_usage_error("precompute --orders automatic" + kSmall, "--orders");
  expect_usage_error("precompute --density-scale 0" + kSmall, "--density-scale");
  expect_usage_error("precompute --density-scale -3" + kSmall, "--density-scale");
  expect_usage_error("precompute --solar lamp" + kSmall, "--solar");
  expect_usage_error("sample --reference --orders auto" + kSmall, "--orders");
  expect_usage_error("render --moon 10,20" + kSmall, "--moon");
  expect_usage_error("render --moon 10,95,0.3" + kSmall, "--moon");
  expect_usage_error("render --moon 10,20,0" + kSmall, "--moon");
  expect_usage_error("render --moon 10,20,nan" + kSmall, "finite");
  expect_usage_error("render --moon 1,2,0.3 --moon 1,2,0.3 --moon 1,2,0.3 --moon 1,2,0.3 --moon 1,2,0.3" + kSmall,
                     "--moon");
  expect_usage_error("render --fov 0" + kSmall, "--fov");
  expect_usage_error("render --fov 180" + kSmall, "--fov");
  expect_usage_error("render -o sky.jpg" + kSmall, "-o/--output");
  expect_usage_error("render --altitude 10 --position 7e6,0,0" + kSmall, "--altitude");
  expect_usage_error("sample --paths 100" + kSmall, "--reference");
  expect_usage_error("sample --reference --sun-disc" + kSmall, "--reference");
  expect_usage_error("nosuchcommand", "nosuchcommand");
  // The globe is drawn with OpenGL only, and is the default: --cpu needs
  // --surface sphere, never a silent change of ground.
  const std::string needs_gl = "the globe needs OpenGL: use --surface sphere with --cpu";
  expect_usage_error("render --cpu --surface globe" + kSmall, needs_gl);
  expect_usage_error("render --surface x" + kSmall, "--surface");
  expect_usage_error("render --surface globe --precision half" + kSmall, "--precision half applies to --surface sphere");
}

// The help text of option `name` in `help` (CLI11's layout: the option's
// line, and its description on the next line when the names are long),
// empty if the option is not listed.
std::string option_help(const std::string& help, const std::string& name) {
  std::stringstream ss(help);
  std::string line, out;
  bool inside = false;
  while (std::getline(ss, line)) {
    if (line.empty()) inside = false;
    const bool option_line = line.rfind("  -", 0) == 0;
    if (option_line) {
      const std::string names = line.substr(2, line.find(' ', 2) - 2);
      inside = false;
      std::stringstream ns(names);
      std::string n;
      while (std::getline(ns, n, ','))
        if (n == name || n.rfind(name + "=", 0) == 0) inside = true;
    }
    if (inside) out += line + "\n";
  }
  return out;
}

// An option shared by several commands: who takes it, a bad value of it,
// and the exit code and message that value gives.
struct SharedOption {
  std::string name;
  std::vector<std::string> commands;
  std::string bad;
  int code;
  std::string message;
};

const std::vector<std::string> kAllCommands = {"render", "precompute", "sample", "bench", "plot-data"};
const std::vector<std::string> kCachedCommands = {"render", "precompute", "sample", "plot-data"};
const std::vector<std::string> kViewCommands = {"render", "sample"};

const std::vector<SharedOption>& shared_options() {
  static const std::vector<SharedOption> options = {
      {"--planet", kAllCommands, "--planet /no/such/planet.json", 1, "neither a preset"},
      {"--wavelengths", kAllCommands, "--wavelengths 2", 2, "--wavelengths must be in [3, 48], got 2"},
      {"--density-scale", kAllCommands, "--density-scale 0", 2, "--density-scale must be in (0, 10000], got 0"},
      {"--solar", kAllCommands, "--solar blackbody:10", 2, "--solar must be table or blackbody:T"},
      {"--orders", kAllCommands, "--orders 0", 2, "--orders must be auto or an integer in [1, 100]"},
      {"--tables", kAllCommands, "--tables huge", 2, "--tables"},
      {"--cache-dir", kCachedCommands, "--cache-dir cache --no-cache", 2, "--cache-dir"},
      {"--no-cache", kCachedCommands, "--no-cache --cache-dir cache", 2, "--no-cache"},
      {"--altitude", kViewCommands, "--altitude -5", 2, "--altitude must be in [0, 1e12] metres, got -5"},
      {"--position", kViewCommands, "--position 0,0,10", 2, "--position is inside the planet"},
      {"--sun-elevation", kViewCommands, "--sun-elevation 95", 2, "--sun-elevation must be in [-90, 90] degrees"},
      {"--sun-azimuth", kViewCommands, "--sun-azimuth inf", 2, "--sun-azimuth must be a finite number"},
      {"--moon", kViewCommands, "--moon 10,95,0.3", 2, "--moon elevation must be in [-90, 90] degrees, got 95"},
      {"--latitude", kViewCommands, "--latitude 91 --longitude 0", 2, "--latitude must be in [-90, 90] degrees, got 91"},
      {"--longitude", kViewCommands, "--longitude inf --latitude 0", 2, "--longitude must be a finite number"},
      {"--date", kViewCommands, "--date 2023-02-29T12:00:00Z --latitude 0 --longitude 0", 2,
       "--date: date 2023-02-29T12:00:00Z: day 29 is not in that month"},
      {"--size", {"render", "bench"}, "--size banana", 2, "--size expects WxH"},
  };
  return options;
}

// Arguments every command needs besides the option under test.
std::string required_arguments(const std::string& command) {
  return command == "plot-data" ? " --out " + (scratch() / "plot-never-written").string() : "";
}

// A shared option is taken by every command it belongs to, with one help
// text (--size: one format and range, each command its own default and
// description) and the same message for the same bad value, given before
// any slow work (bench precomputes for minutes, sample would read stdin).
TEST(Cli, SharedOptionsMeanTheSameInEveryCommand) {
  std::map<std::string, std::string> help;
  for (const std::string& command : kAllCommands) help[command] = atmos_cli(command + " --help").out;
  for (const SharedOption& option : shared_options()) {
    std::string first_help, first_error;
    for (const std::string& command : kAllCommands) {
      const std::string text = option_help(help[command], option.name);
      const bool takes = std::find(option.commands.begin(), option.commands.end(), command) != option.commands.end();
      EXPECT_EQ(!text.empty(), takes) << command << " " << option.name << "\n" << help[command];
      if (!takes) {
        const CliRun r = atmos_cli(command + " " + option.bad + required_arguments(command));
        EXPECT_EQ(r.code, 2) << command << " " << option.bad << "\n" << r.err;
        EXPECT_NE(r.err.find("not expected"), std::string::npos) << command << " " << option.bad << "\n" << r.err;
        continue;
      }
      if (option.name != "--size") {
        if (first_help.empty()) first_help = text;
        EXPECT_EQ(text, first_help) << command << " " << option.name;
      }
      const std::string tables = option.name == "--tables" ? "" : kSmall;
      const CliRun r = atmos_cli(command + " " + option.bad + required_arguments(command) + tables);
      EXPECT_EQ(r.code, option.code) << command << " " << option.bad << "\n" << r.err;
      EXPECT_EQ(lines(r.err), 1) << command << " " << option.bad << "\n" << r.err;
      EXPECT_NE(r.err.find(option.message), std::string::npos) << command << " " << option.bad << "\n" << r.err;
      if (first_error.empty()) first_error = r.err;
      EXPECT_EQ(r.err, first_error) << command << " " << option.bad;
      EXPECT_TRUE(r.out.empty()) << command << " " << option.bad << ": nothing done before the error\n" << r.out;
    }
  }
  EXPECT_FALSE(fs::exists(scratch() / "plot-never-written"));
}

// Valid, non-default values of every shared option, each command that takes
// them at once (bench only through the bad values above: it runs minutes).
TEST(Cli, EveryCommandRunsWithItsSharedOptions) {
  const std::string planet = " --planet earth --wavelengths 3 --density-scale 1.5 --solar blackbody:5800 --orders 2" +
                             kSmall + " --cache-dir " + (scratch() / "shared-cache").string();
  const std::string view = " --altitude 100 --sun-elevation 20 --sun-azimuth 90 --moon 270,30,0.3 --moon 0,60,0.5";
  CliRun r = atmos_cli("precompute" + planet);
  EXPECT_EQ(r.code, 0) << r.err;
  r = atmos_cli("render --cpu --surface sphere --size 8x8 -o " + (scratch() / "shared.exr").string() + planet + view);
  EXPECT_EQ(r.code, 0) << r.err;
  r = atmos_cli("render --cpu --surface sphere --size 8x8 -o " + (scratch() / "shared.exr").string() + planet +
                " --position 7e6,1e6,2e6 --sun-elevation 20 --moon 270,30,0.3");
  EXPECT_EQ(r.code, 0) << r.err;
  r = atmos_cli("sample" + planet + view, "azimuth_deg,elevation_deg\n0,90\n");
  EXPECT_EQ(r.code, 0) << r.err;
  r = atmos_cli("sample --position 7e6,1e6,2e6 --sun-elevation 20 --moon 270,30,0.3" + planet,
                "azimuth_deg,elevation_deg\n0,90\n");
  EXPECT_EQ(r.code, 0) << r.err;
  r = atmos_cli("plot-data --out " + (scratch() / "shared-plots").string() + planet);
  EXPECT_EQ(r.code, 0) << r.err;
}

TEST(Cli, BadPlanetFilesAreOneLineErrors) {
  const fs::path bad = scratch() / "bad.json";
  {
    std::ofstream f(bad);
    f << "{ \"format\": \"atmos-planet-1\", ";
  }
  expect_runtime_error("precompute --planet " + bad.string() + kSmall, "malformed JSON");
  {
    std::ofstream f(bad);
    f << "{ \"format\": \"atmos-planet-1\" }";
  }
  expect_runtime_error("precompute --planet " + bad.string() + kSmall, "missing");
  std::string earth = slurp(fs::path(ATMOS_SOURCE_DIR) / "data/planets/earth.json");
  const std::string from = "\"bottom_radius\": { \"value\": 6371.0";
  ASSERT_NE(earth.find(from), std::string::npos);
  earth.replace(earth.find(from), from.size(), "\"bottom_radius\": { \"value\": -6371.0");
  {
    std::ofstream f(bad);
    f << earth;
  }
  expect_runtime_error("precompute --planet " + bad.string() + kSmall, "bottom_radius must be positive");
  expect_runtime_error("precompute --planet /no/such/planet.json" + kSmall, "neither a preset");
}

TEST(Cli, UnwritableOutputIsAnError) {
  const CliRun r = atmos_cli("render --cpu --surface sphere --size 8x8 -o /no/such/dir/out.png" + kSmall);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("/no/such/dir/out.png"), std::string::npos) << r.err;
}

TEST(Cli, NoOpenGlIsOneClearError) {
  // Without an EGL vendor library (glvnd) no OpenGL 4.5 context can be had:
  // one line, exit 1.
  const CliRun r = atmos_cli("render --size 8x8 -o " + (scratch() / "nogl.png").string() + kSmall, "",
                             "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json LIBGL_DRIVERS_PATH=/nonexistent");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("OpenGL"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "nogl.png"));
}

TEST(Cli, PrecomputeReportsSizesTimesAndDetectsACorruptCache) {
  const fs::path cache = scratch() / "cache-precompute";
  fs::remove_all(cache);
  const std::string args = "precompute --orders 2 --cache-dir " + cache.string() + kSmall;
  CliRun r = atmos_cli(args);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("scattering      4 x 16 x 32 x 8"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("time single_scattering"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("computed, cached"), std::string::npos) << r.out;
  r = atmos_cli(args);
  EXPECT_NE(r.out.find("loaded from cache"), std::string::npos) << r.out;
  for (const auto& entry : fs::directory_iterator(cache)) {
    std::ofstream f(entry.path(), std::ios::binary | std::ios::trunc);
    f << "garbage";
  }
  r = atmos_cli(args);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("recomputed (invalid cache)"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("rejected"), std::string::npos) << r.err;
}

std::vector<std::vector<double>> parse_csv(const std::string& text, std::string& header, std::string& trailer) {
  std::vector<std::vector<double>> rows;
  std::stringstream ss(text);
  std::string line;
  std::getline(ss, header);
  while (std::getline(ss, line)) {
    if (line.rfind("#", 0) == 0) {
      trailer = line;
      continue;
    }
    std::vector<double> row;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

TEST(Cli, SampleWritesCsvWithDocumentedColumns) {
  const std::string dirs = "azimuth_deg,elevation_deg\n0,90\n180,10\n0,-20\n";
  const CliRun r = atmos_cli("sample --sun-elevation 30 --sun-azimuth 180" + kSmall, dirs);
  ASSERT_EQ(r.code, 0) << r.err;
  std::string header, trailer;
  const auto rows = parse_csv(r.out, header, trailer);
  EXPECT_EQ(header.rfind("azimuth_deg,elevation_deg,luminance_cd_m2,red,green,blue", 0), 0u) << header;
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& row : rows) {
    ASSERT_GE(row.size(), 6u);
    for (double v : row) EXPECT_TRUE(std::isfinite(v));
    // Luminance is the sRGB-weighted sum of the colour columns.
    EXPECT_NEAR(row[2], 0.2126 * row[3] + 0.7152 * row[4] + 0.0722 * row[5], 1e-3 * row[2]);
    EXPECT_GT(row[2], 0.0);
  }
  EXPECT_GT(rows[0][5], rows[0][3]) << "zenith: blue above red";
  EXPECT_NE(trailer.find("horizontal_illuminance_lux="), std::string::npos) << trailer;

  expect_usage_error("sample --directions /dev/null" + kSmall, "header");
  const CliRun bad = atmos_cli("sample" + kSmall, "azimuth_deg,elevation_deg\n10,abc\n");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("stdin:2"), std::string::npos) << bad.err;
}

// Spectral mode from the command line: the sample columns are the
// colour ones (the tables hold colour, not per-wavelength radiance), the
// reference agrees with the tables, precompute reports the convergence of
// auto orders, and the solar and density options apply.
TEST(Cli, SpectralSampleAndPrecompute) {
  const std::string dirs = "azimuth_deg,elevation_deg\n0,90\n180,10\n";
  // The same 4 orders as the reference below (the continental aerosol makes
  // the orders after the fourth add ~3 % at the zenith).
  const CliRun tables = atmos_cli("sample --orders 4 --wavelengths 6 --sun-elevation 30" + kSmall, dirs);
  ASSERT_EQ(tables.code, 0) << tables.err;
  std::string header, trailer;
  const auto rows = parse_csv(tables.out, header, trailer);
  EXPECT_EQ(header, "azimuth_deg,elevation_deg,luminance_cd_m2,red,green,blue");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_GT(rows[0][5], rows[0][3]) << "zenith: blue above red";
  const CliRun reference =
      atmos_cli("sample --reference --paths 4000 --orders 4 --wavelengths 6 --sun-elevation 30" + kSmall, dirs);
  ASSERT_EQ(reference.code, 0) << reference.err;
  const auto reference_rows = parse_csv(reference.out, header, trailer);
  ASSERT_EQ(reference_rows.size(), 2u);
  // Small tables: a few per cent (measured: the zenith of the small tables
  // 1998 cd/m², of the default ones 1916, of the reference with 40 000 paths
  // 1917; this reference's noise is about 1 %).
  EXPECT_NEAR(rows[0][2], reference_rows[0][2], 0.07 * reference_rows[0][2]);

  const CliRun automatic = atmos_cli("precompute --orders auto --wavelengths 6 --no-cache" + kSmall);
  ASSERT_EQ(automatic.code, 0) << automatic.err;
  EXPECT_NE(automatic.out.find("channels        linear sRGB"), std::string::npos) << automatic.out;
  EXPECT_NE(automatic.out.find("order 2 "), std::string::npos) << automatic.out;

  const CliRun blackbody = atmos_cli("sample --solar blackbody:4000 --sun-elevation 30" + kSmall, dirs);
  ASSERT_EQ(blackbody.code, 0) << blackbody.err;
  const auto red_sun = parse_csv(blackbody.out, header, trailer);
  EXPECT_LT(red_sun[0][5] / red_sun[0][3], 0.8 * rows[0][5] / rows[0][3]) << "a 4000 K sun makes a less blue sky";
  const CliRun thin = atmos_cli("sample --density-scale 0.1 --sun-elevation 30" + kSmall, dirs);
  ASSERT_EQ(thin.code, 0) << thin.err;
  EXPECT_LT(parse_csv(thin.out, header, trailer)[0][2], 0.3 * rows[0][2]) << "a tenth of the air: a darker zenith";
}

TEST(Cli, SampleLooksAtTheSunWithTheSunsOwnAngles) {
  // With --sun-disc, the direction (sun azimuth, sun elevation) sees the disc.
  const CliRun r = atmos_cli("sample --sun-disc --sun-elevation 40 --sun-azimuth 123" + kSmall,
                          "azimuth_deg,elevation_deg\n123,40\n123,45\n");
  ASSERT_EQ(r.code, 0) << r.err;
  std::string header, trailer;
  const auto rows = parse_csv(r.out, header, trailer);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_GT(rows[0][2], 1e8) << "the sun's luminance is of the order of 1e9 cd/m²";
  EXPECT_LT(rows[1][2], 1e6);
}

struct Pixel {
  double r, g, b;
  double luminance() const { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
};

Pixel pixel(const atmos::Image& image, int x, int y) {
  const size_t i = 3 * (size_t(y) * size_t(image.width) + size_t(x));
  return {image.rgb[i], image.rgb[i + 1], image.rgb[i + 2]};
}

atmos::Image render(const std::string& args, const std::string& name) {
  const fs::path out = scratch() / (name + ".exr");
  const CliRun r = atmos_cli("render " + args + " -o " + out.string() + " -o " + (scratch() / (name + ".png")).string() +
                          kSmall);
  EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
  EXPECT_TRUE(fs::exists(scratch() / (name + ".png")));
  atmos::Image image = atmos::read_exr(out.string());
  for (float v : image.rgb) EXPECT_TRUE(std::isfinite(v) && v >= 0.0f);
  return image;
}

TEST(Cli, NoonZenithIsBlueAndOfTheRightBrightness) {
  // The sun 60° up: the zenith is outside the aerosol's aureole (with the sun
  // at 80° it is 10° from the sun, where the continental aerosol makes the
  // sky 16 000 cd/m² and barely blue).
  const atmos::Image image = render("--surface sphere --sun-elevation 60 --look 0,90 --fov 10 --size 16x16", "noon");
  const Pixel p = pixel(image, 8, 8);
  std::printf("noon zenith (sun at 60 deg): %.0f cd/m2, rgb %.0f %.0f %.0f\n", p.luminance(), p.r, p.g, p.b);
  EXPECT_GT(p.b, p.g);
  EXPECT_GT(p.g, p.r);
  // Clear-sky zenith luminance with the sun high: of the order of a few
  // thousand cd/m² (CIE clear sky, turbidity 2-3).
  EXPECT_GT(p.luminance(), 1000.0);
  EXPECT_LT(p.luminance(), 10000.0);
}

TEST(Cli, SunsetTowardsTheSunIsRed) {
  const atmos::Image image =
      render("--surface sphere --sun-elevation 0.5 --sun-azimuth 270 --look 270,2 --fov 20 --size 32x16", "sunset");
  // Beside the sun, above the horizon (the sun itself is at the centre).
  const Pixel p = pixel(image, 4, 2);
  std::printf("sunset sky near the sun: rgb %.1f %.1f %.1f\n", p.r, p.g, p.b);
  EXPECT_GT(p.r, p.b);
  EXPECT_GT(p.r, p.g);
}

TEST(Cli, SpaceIsBlackAndTheLitLimbBright) {
  // From 2.5 planet radii, looking at the planet with the sun to the right.
  const double d = 2.5 * 6371e3;
  const std::string position = "--position " + std::to_string(d) + ",0,0";
  // In the local frame of that position, up = +x, east = +y, north = +z;
  // the sun at azimuth 90 (east) and elevation 0 lights the planet from the side.
  const atmos::Image image = render(position + " --look 0,-90 --fov 60 --size 96x96 --sun-azimuth 90 --sun-elevation 0",
                                    "orbit");
  // Corners: space.
  const Pixel corner = pixel(image, 0, 0);
  EXPECT_EQ(corner.luminance(), 0.0);
  // Along the horizontal line through the centre, the outer 15 % of the
  // planet disc (plus the atmosphere's glow beyond it) on each side: the
  // sun is to the right, so the right limb is lit and the left one is night.
  const double radius_px = 48.0 / std::tan(30.0 * M_PI / 180.0) * std::tan(std::asin(1.0 / 2.5));
  double lit_limb = 0.0, dark_limb = 0.0;
  for (int x = 0; x < 96; ++x) {
    const double offset = std::abs(x + 0.5 - 48.0);
    if (offset < 0.85 * radius_px || offset > radius_px + 3.0) continue;
    const double l = pixel(image, x, 48).luminance();
    (x >= 48 ? lit_limb : dark_limb) = std::max(x >= 48 ? lit_limb : dark_limb, l);
  }
  std::printf("orbit: lit limb %.0f cd/m2, brightest pixel of the dark half %.3f cd/m2\n", lit_limb, dark_limb);
  EXPECT_GT(lit_limb, 500.0);
  EXPECT_LT(dark_limb, 0.01 * lit_limb);
}

// --moon in front of the sun: the sky goes dark, on the GPU and the CPU alike
// (the renderer's sphere: the CPU draws no globe).
TEST(Cli, MoonInFrontOfTheSunDarkensTheSky) {
  const std::string view = " --surface sphere --sun-elevation 40 --sun-azimuth 180 --look 180,60 --size 16x16";
  const atmos::Image day = render(view, "day");
  const atmos::Image eclipse = render(view + " --moon 180,40,0.3", "eclipse");
  const atmos::Image eclipse_cpu = render(view + " --moon 180,40,0.3 --cpu", "eclipse_cpu");
  const size_t centre = 3 * (8 * 16 + 8) + 1;  // green of pixel (8, 8)
  EXPECT_LT(eclipse.rgb[centre], 1e-2 * day.rgb[centre]);
  EXPECT_GT(eclipse.rgb[centre], 0.0f);
  EXPECT_NEAR(eclipse_cpu.rgb[centre] / eclipse.rgb[centre], 1.0, 0.01);
}

// The luminance column of every row of `sample`'s output.
std::vector<double> sample_luminances(const CliRun& r) {
  std::string header, trailer;
  std::vector<double> out;
  for (const auto& row : parse_csv(r.out, header, trailer)) out.push_back(row.at(2));
  return out;
}

// The luminance of a 1x1 CPU render looking along (azimuth, elevation): the
// ray through the image centre.
double render_luminance(const std::string& args, double azimuth, double elevation, const std::string& name) {
  const fs::path out = scratch() / (name + ".exr");
  const CliRun r = atmos_cli("render --cpu --surface sphere --size 1x1 --look " + std::to_string(azimuth) + "," +
                             std::to_string(elevation) + args + " -o " + out.string());
  EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
  const atmos::Image image = atmos::read_exr(out.string());
  return pixel(image, 0, 0).luminance();
}

// `sample --moon` eclipses the light as `render --moon` does: a moon on the
// sun darkens the sky by orders of magnitude, in both, by the same amount
// (sample evaluates the functions render_cpu runs, for the direction of the
// centre of a 1x1 image), from --altitude and from a --position whose local
// frame is not the north pole's; the reference takes the moons too.
TEST(Cli, SampleMoonInFrontOfTheSunDarkensTheSkyAsRenderDoes) {
  const std::string directions = "azimuth_deg,elevation_deg\n180,60\n0,80\n";
  for (const std::string& place : {std::string(" --altitude 2"), std::string(" --position 3891338,3891338,3210354")}) {
    const std::string light = place + " --sun-elevation 40 --sun-azimuth 180" + kSmall;
    const std::string moon = " --moon 180,40,0.3";
    const CliRun day = atmos_cli("sample" + light, directions);
    const CliRun eclipse = atmos_cli("sample" + light + moon, directions);
    ASSERT_EQ(day.code, 0) << day.err;
    ASSERT_EQ(eclipse.code, 0) << eclipse.err;
    const std::vector<double> sky = sample_luminances(day), dark = sample_luminances(eclipse);
    ASSERT_EQ(sky.size(), 2u);
    ASSERT_EQ(dark.size(), 2u);
    const double render_sky = render_luminance(light, 180.0, 60.0, "sample-day");
    const double render_dark = render_luminance(light + moon, 180.0, 60.0, "sample-eclipse");
    std::printf("%s: sky at (180, 60) %.6g cd/m2 (render %.6g), eclipsed %.6g (render %.6g)\n", place.c_str(), sky[0],
                render_sky, dark[0], render_dark);
    for (size_t i = 0; i < 2; ++i) {
      EXPECT_LT(dark[i], 1e-2 * sky[i]) << place << " row " << i;
      EXPECT_GT(dark[i], 0.0) << place << " row " << i;
    }
    // The same functions in float, rounded differently: 6e-5 of the sky by
    // day, 8e-4 of the 4e5 times fainter eclipsed one (measured).
    EXPECT_NEAR(sky[0] / render_sky, 1.0, 1e-3) << place;
    EXPECT_NEAR(dark[0] / render_dark, 1.0, 5e-3) << place;
    // With the tables, the horizontal irradiance is not eclipsed: no figure.
    EXPECT_NE(eclipse.out.find("# horizontal irradiance: not computed"), std::string::npos) << eclipse.out;
  }
  const std::string reference = " --reference --paths 2000 --orders 4 --sun-elevation 40 --sun-azimuth 180" + kSmall;
  const CliRun day = atmos_cli("sample" + reference, directions);
  const CliRun eclipse = atmos_cli("sample" + reference + " --moon 180,40,0.3", directions);
  ASSERT_EQ(day.code, 0) << day.err;
  ASSERT_EQ(eclipse.code, 0) << eclipse.err;
  const std::vector<double> sky = sample_luminances(day), dark = sample_luminances(eclipse);
  ASSERT_EQ(dark.size(), 2u);
  for (size_t i = 0; i < 2; ++i) EXPECT_LT(dark[i], 1e-2 * sky[i]) << "reference, row " << i;
}

// A bad --moon is a one-line usage error of sample, as of render, before
// stdin is read.
TEST(Cli, SampleRejectsBadMoons) {
  expect_usage_error("sample --moon 10,20" + kSmall, "--moon expects AZ,EL,ANGULAR_RADIUS_DEG");
  expect_usage_error("sample --moon 10,20,0.3,4" + kSmall, "--moon expects AZ,EL,ANGULAR_RADIUS_DEG");
  expect_usage_error("sample --moon a,b,c" + kSmall, "--moon expects AZ,EL,ANGULAR_RADIUS_DEG");
  expect_usage_error("sample --moon 10,95,0.3" + kSmall, "--moon elevation must be in [-90, 90] degrees");
  expect_usage_error("sample --moon 10,20,0" + kSmall, "--moon angular radius must be in (0, 10] degrees");
  expect_usage_error("sample --moon 10,20,11" + kSmall, "--moon angular radius must be in (0, 10] degrees");
  expect_usage_error("sample --moon 10,20,nan" + kSmall, "--moon must be a finite number");
  expect_usage_error("sample --moon 1,2,0.3 --moon 1,2,0.3 --moon 1,2,0.3 --moon 1,2,0.3 --moon 1,2,0.3" + kSmall,
                     "--moon: at most 4 moons");
  // From 384 400 km up, a moon straight down at the Moon's distance sits at
  // the planet's centre.
  expect_usage_error("sample --altitude 384400000 --moon 0,-90,0.3" + kSmall, "reaches into the atmosphere");
}

// --date, --latitude and --longitude: the sun and the Moon of a date and
// place (atmos/ephemeris.hpp). The total eclipse of 2024-04-08 seen from
// Dallas: at 18:42:30 UTC the Moon covers the Sun and the sky is dark; an
// hour earlier the eclipse is partial and the sky bright. The sun's place is
// the trailing comment, as the library computes it.
// The stars of --date come from a star catalogue, their colours from
// another: one that cannot be read is a one-line error naming it;
// --star-catalogue, --star-colours and --procedural-stars need --date.
TEST(Cli, StarCatalogueOfDate) {
  const std::string night = " --date 2025-01-29T20:30:00Z --latitude 48.21 --longitude 16.37";
  expect_runtime_error("render --surface sphere --size 8x8" + night + " --star-catalogue /no/such/BSC" + kSmall,
                       "cannot read the star catalogue /no/such/BSC");
  expect_runtime_error("render --surface sphere --size 8x8" + night + " --star-colours /no/such/stars.dat" + kSmall,
                       "cannot read the star catalogue /no/such/stars.dat");
  expect_usage_error("render --star-colours none" + kSmall, "--star-colours requires --date");
  expect_usage_error("render --star-catalogue /no/such/BSC" + kSmall, "--star-catalogue requires --date");
  expect_usage_error("render --procedural-stars" + kSmall, "--procedural-stars requires --date");
}

TEST(Cli, DateAndPlaceSetTheSunAndTheMoon) {
  const std::string dallas = " --latitude 32.7767 --longitude -96.7970";
  expect_usage_error("sample --date 2024-04-08T18:42:30Z" + kSmall, "--date requires --latitude");
  expect_usage_error("sample --date 2024-04-08T18:42:30Z --sun-elevation 10" + dallas + kSmall,
                     "--sun-elevation excludes --date");
  expect_usage_error("render --date 2024-04-08T18:42:30Z --sun-azimuth 10" + dallas + kSmall,
                     "--sun-azimuth excludes --date");
  expect_usage_error("render --date 2024-04-08 18:42:30" + dallas + kSmall, "");
  expect_usage_error("render --date 2024-04-08T18:42:30" + dallas + kSmall, "is not YYYY-MM-DDTHH:MM:SSZ");
  expect_usage_error("sample --date 2024-13-08T18:42:30Z" + dallas + kSmall, "no month 13");
  expect_usage_error("sample --date 2024-04-08T18:42:30Z --latitude -95 --longitude 0" + kSmall,
                     "--latitude must be in [-90, 90] degrees, got -95");
  expect_usage_error("sample --latitude 10" + kSmall, "--latitude requires --longitude");
  expect_usage_error("render --latitude 10 --longitude 0 --position 7e6,0,0" + kSmall, "--position excludes --latitude");

  const std::string directions = "azimuth_deg,elevation_deg\n0,90\n";
  const CliRun total = atmos_cli("sample --date 2024-04-08T18:42:30Z" + dallas + kSmall, directions);
  const CliRun partial = atmos_cli("sample --date 2024-04-08T17:40:00Z" + dallas + kSmall, directions);
  ASSERT_EQ(total.code, 0) << total.err;
  ASSERT_EQ(partial.code, 0) << partial.err;
  std::string header, trailer;
  const auto rows = parse_csv(total.out, header, trailer);
  ASSERT_EQ(rows.size(), 1u);
  double azimuth = 0.0, elevation = 0.0;
  ASSERT_EQ(std::sscanf(trailer.c_str(), "# sun_azimuth_deg=%lf sun_elevation_deg=%lf", &azimuth, &elevation), 2)
      << trailer;
  const atmos::SkyOfDate sky = atmos::sky_of_date(atmos::parse_utc_time("2024-04-08T18:42:30Z"), {32.7767, -96.7970, 0.0});
  EXPECT_NEAR(azimuth, sky.sun.azimuth_deg, 1e-5);
  EXPECT_NEAR(elevation, sky.sun.elevation_deg, 1e-5);
  // Totality: the zenith sky is orders of magnitude darker than in the
  // partial phase, and the tables give no horizontal irradiance.
  const std::vector<double> dark = sample_luminances(total), bright = sample_luminances(partial);
  ASSERT_EQ(bright.size(), 1u);
  std::printf("Dallas zenith: %.4g cd/m2 at 17:40 UTC (partial), %.4g cd/m2 at 18:42:30 (total)\n", bright[0], dark[0]);
  EXPECT_LT(dark[0], 1e-2 * bright[0]);
  EXPECT_GT(dark[0], 0.0);
  EXPECT_NE(total.out.find("# horizontal irradiance: not computed"), std::string::npos) << total.out;
  // Without a moon near the sun, the irradiance is there again (the Moon is
  // placed, far from the sun, but eclipses nothing).
  const CliRun night = atmos_cli("sample --date 2024-04-08T06:00:00Z" + dallas + kSmall, directions);
  ASSERT_EQ(night.code, 0) << night.err;
  EXPECT_NE(night.out.find("# horizontal_illuminance_lux="), std::string::npos) << night.out;
  // render takes them too.
  const CliRun r = atmos_cli("render --cpu --surface sphere --size 8x8 --date 2024-04-08T18:42:30Z" + dallas +
                             " -o " + (scratch() / "dallas.exr").string() + kSmall);
  EXPECT_EQ(r.code, 0) << r.err;
}

TEST(CliRenders, RenderProjectionsAndCpuPath) {
  for (const char* projection : {"perspective", "fisheye", "equirect"}) {
    const atmos::Image image = render(std::string("--projection ") + projection + " --size 32x16", projection);
    EXPECT_EQ(image.width, 32);
  }
  const CliRun r =
      atmos_cli("render --cpu --surface sphere --size 16x8 -o " + (scratch() / "cpu.exr").string() + kSmall);
  EXPECT_EQ(r.code, 0) << r.err;
}

// --- The terrain globe (--surface globe, the default) ---

// Mean colour of the pixels x0 <= x < x1, y0 <= y < y1.
Pixel mean_colour(const atmos::Image& image, int x0, int y0, int x1, int y1) {
  Pixel sum{0.0, 0.0, 0.0};
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const Pixel p = pixel(image, x, y);
      sum.r += p.r;
      sum.g += p.g;
      sum.b += p.b;
    }
  const double n = double(x1 - x0) * double(y1 - y0);
  return {sum.r / n, sum.g / n, sum.b / n};
}

// The detail of a region: the mean absolute luminance difference between
// horizontal neighbours over the mean luminance (0 for a uniform region,
// small for a smooth gradient).
double detail(const atmos::Image& image, int x0, int y0, int x1, int y1) {
  double differences = 0.0, sum = 0.0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x + 1 < x1; ++x) {
      differences += std::abs(pixel(image, x + 1, y).luminance() - pixel(image, x, y).luminance());
      sum += pixel(image, x, y).luminance();
    }
  return sum > 0.0 ? differences / sum : 0.0;
}

// 2 m above the ground at noon, in the Sahara (20° N, 30° E: --position 2 m
// above the datum sphere, which the globe puts 2 m above its terrain),
// looking north at the horizon: the lower half of the image is ground, with
// the globe as with the sphere, and they differ: the globe's ground has the
// imagery's colour (sand, far less blue than the sphere's grey ground in the
// same light) and the relief's shading.
TEST(Cli, GlobeGroundFromTwoMetres) {
  const double r = 6371e3 + 2.0, lat = 20.0 * M_PI / 180.0, lon = 30.0 * M_PI / 180.0;
  const std::string position = "--position " + std::to_string(r * std::cos(lat) * std::cos(lon)) + "," +
                               std::to_string(r * std::cos(lat) * std::sin(lon)) + "," +
                               std::to_string(r * std::sin(lat));
  const std::string view = position + " --sun-elevation 70 --sun-azimuth 180 --look 0,0 --fov 40 --size 320x180";
  const atmos::Image globe = render(view + " --surface globe", "globe-ground");
  const atmos::Image sphere = render(view + " --surface sphere", "sphere-ground");
  for (const atmos::Image* image : {&globe, &sphere}) {
    const bool is_globe = image == &globe;
    const Pixel sky = mean_colour(*image, 0, 0, 320, 40);
    const Pixel ground = mean_colour(*image, 0, 100, 320, 180);
    std::printf("%s: sky rgb %.0f %.0f %.0f, ground rgb %.0f %.0f %.0f, ground detail %.4f\n",
                is_globe ? "globe" : "sphere", sky.r, sky.g, sky.b, ground.r, ground.g, ground.b,
                detail(*image, 0, 100, 320, 180));
    // Over the globe's sand (the regional albedo: red 0.98, blue 0.31 in
    // the imagery) the ground's reflections whiten the sky; over the
    // sphere's grey 0.1 it is bluer.
    EXPECT_GT(sky.b, (is_globe ? 1.2 : 1.5) * sky.r) << (is_globe ? "globe" : "sphere") << ": the sky is blue";
    EXPECT_LT(ground.b / ground.r, 0.8 * sky.b / sky.r) << (is_globe ? "globe" : "sphere") << ": not the sky";
    EXPECT_GT(ground.luminance(), 100.0) << (is_globe ? "globe" : "sphere") << ": lit ground";
  }
  const Pixel g = mean_colour(globe, 0, 100, 320, 180), s = mean_colour(sphere, 0, 100, 320, 180);
  EXPECT_LT(g.b / g.r, 0.7 * s.b / s.r) << "the globe's sand, the sphere's grey";
  // The air over the sand: brighter and less blue than over the grey ground.
  const Pixel globe_sky = mean_colour(globe, 0, 0, 320, 40), sphere_sky = mean_colour(sphere, 0, 0, 320, 40);
  EXPECT_GT(globe_sky.luminance(), 1.2 * sphere_sky.luminance());
  EXPECT_LT(globe_sky.b / globe_sky.r, sphere_sky.b / sphere_sky.r);
  EXPECT_GT(detail(globe, 0, 100, 320, 180), 3.0 * detail(sphere, 0, 100, 320, 180)) << "the globe's relief";
}

// From 2.5 planet radii above 0° N 0° E, the sun 60° up there: the
// planet's disc, the same size with the globe as with the sphere, in black
// space. The pass would draw its own sphere where the globe drew nothing;
// the globe's disc shows the continents' edges (Africa and the Atlantic),
// the sphere's is smooth.
// Mars's globe from 2.5 radii: its lowlands and basins lie kilometres below
// the datum (Hellas, the northern plains), so the pass draws the air
// continued down to the lowest ground (atmos::extend_below_datum) while the
// globe keeps the datum; the planet fills its disc.
TEST(Cli, GlobeOfMarsReachesBelowItsDatum) {
  const double radius = 3389.5e3;
  const atmos::Image mars =
      render("--planet mars --position " + std::to_string(2.5 * radius) +
                 ",0,0 --look 0,-90 --fov 60 --size 48x48 --sun-azimuth 90 --sun-elevation 60 --exposure 12",
             "globe-mars-orbit");
  const double radius_px = 24.0 / std::tan(30.0 * M_PI / 180.0) * std::tan(std::asin(1.0 / 2.5));
  int lit = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 48; ++x) lit += pixel(mars, x, y).luminance() > 10.0;
  std::printf("Mars's globe from 2.5 radii: %d lit pixels, disc %.0f\n", lit, M_PI * radius_px * radius_px);
  EXPECT_GT(lit, 0.8 * M_PI * radius_px * radius_px);
}

// --stereo: each eye through its own off-axis frustum, the eyes' images side
// by side (twice the width) or as a red-cyan anaglyph (red from the left
// eye, green and blue from the right: atmos/stereo.hpp). Looking at the sun
// 20° up with a 64 mm baseline converged at 1 m, the sun's disc (at
// infinity) lies ipd / convergence = 0.064 of the image plane further right
// in the right eye than in the left: 35.1 px in a 10° field 96 px tall
// (bound 0.5 px: the disc is 5 px wide, its centroid sampled at pixel
// centres).
TEST(CliRenders, StereoRendersEachEyeThroughItsOwnFrustum) {
  const std::string view = "--altitude 2 --sun-elevation 20 --sun-azimuth 180 --look 180,20 --fov 10 --size 96x96";
  const atmos::Image pair = render(view + " --stereo side-by-side --ipd 0.064 --convergence 1", "stereo-pair");
  ASSERT_EQ(pair.width, 192);
  ASSERT_EQ(pair.height, 96);
  auto sun_x = [&](int x0) {
    double sum = 0.0, sx = 0.0;
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 96; ++x) {
        const double l = pixel(pair, x0 + x, y).luminance();
        if (l < 1e8) continue;  // the disc: ~1e9 cd/m², the sky ~1e4
        sum += l;
        sx += l * (x + 0.5);
      }
    return sum > 0.0 ? sx / sum : -1.0;
  };
  const double left = sun_x(0), right = sun_x(96);
  const double expected = 0.064 / 1.0 * 96.0 / (2.0 * std::tan(5.0 * M_PI / 180.0));
  std::printf("stereo pair: the sun at x = %.2f (left eye), %.2f (right eye): disparity %.2f px, expected %.2f\n",
              left, right, right - left, expected);
  EXPECT_NEAR(right - left, expected, 0.5);
  const atmos::Image red_cyan = render(view + " --stereo anaglyph --ipd 0.064 --convergence 1", "stereo-anaglyph");
  ASSERT_EQ(red_cyan.width, 96);
  for (int y = 0; y < 96; y += 7)
    for (int x = 0; x < 96; x += 5) {
      EXPECT_DOUBLE_EQ(pixel(red_cyan, x, y).r, pixel(pair, x, y).r);
      EXPECT_DOUBLE_EQ(pixel(red_cyan, x, y).b, pixel(pair, 96 + x, y).b);
    }
  expect_usage_error("render --stereo anaglyph --projection fisheye" + kSmall, "--stereo needs the perspective");
  expect_usage_error("render --stereo anaglyph --ipd 0" + kSmall, "--ipd must be in (0, 1e7] metres");
  expect_usage_error("render --stereo anaglyph --convergence -1" + kSmall, "--convergence must be > 0 metres");
}

TEST(Cli, GlobeFromOrbitShowsThePlanet) {
  const std::string view = "--position " + std::to_string(2.5 * 6371e3) +
                           ",0,0 --look 0,-90 --fov 60 --size 96x96 --sun-azimuth 90 --sun-elevation 60";
  const atmos::Image globe = render(view, "globe-orbit");
  const atmos::Image sphere = render(view + " --surface sphere", "sphere-orbit");
  const double radius_px = 48.0 / std::tan(30.0 * M_PI / 180.0) * std::tan(std::asin(1.0 / 2.5));
  auto disc_pixels = [&](const atmos::Image& image) {
    int n = 0;
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 96; ++x) n += pixel(image, x, y).luminance() > 10.0;
    return n;
  };
  const int g = disc_pixels(globe), s = disc_pixels(sphere);
  const double inner = 0.6 * radius_px / std::sqrt(2.0);
  const int x0 = int(48 - inner), x1 = int(48 + inner);
  std::printf("orbit: disc %d px with the globe, %d with the sphere (pi r^2 = %.0f); detail %.4f and %.4f\n", g, s,
              M_PI * radius_px * radius_px, detail(globe, x0, x0, x1, x1), detail(sphere, x0, x0, x1, x1));
  EXPECT_EQ(pixel(globe, 0, 0).luminance(), 0.0);
  EXPECT_EQ(pixel(globe, 95, 95).luminance(), 0.0);
  EXPECT_GT(pixel(globe, 48, 48).luminance(), 100.0);
  EXPECT_NEAR(double(g) / double(s), 1.0, 0.03);
  EXPECT_GT(g, int(0.7 * M_PI * radius_px * radius_px));
  EXPECT_GT(detail(globe, x0, x0, x1, x1), 3.0 * detail(sphere, x0, x0, x1, x1));
}

// The gallery's all-sky camera (a 180° fisheye looking up, the sun at
// azimuth 135°, 20° up) through the globe's cube map: over the planet
// file's ground albedo (--planet-albedo) the sky is the sphere renderer's
// at the zenith and at 45° elevation towards the four cardinal points
// (which fixes the image's orientation: the sky is brighter towards the
// sun), and outside the image circle is black. Over the globe's own ground
// (the north pole's sea ice, albedo about 0.8) the whole sky is brighter.
TEST(CliRenders, GlobeFisheyeAllSkyMatchesTheSphereSky) {
  const std::string view = "--projection fisheye --look 0,90 --sun-azimuth 135 --sun-elevation 20 --size 96x96";
  const atmos::Image globe = render(view + " --planet-albedo", "globe-allsky");
  const atmos::Image ice = render(view, "globe-allsky-ice");
  const atmos::Image sphere = render(view + " --surface sphere", "sphere-allsky");
  // Looking up with north at the top, east is on the left: 45° from the
  // zenith is 24 px from the centre.
  const std::vector<std::pair<int, int>> points = {{48, 48}, {48, 24}, {24, 48}, {48, 72}, {72, 48}};
  for (const auto& [x, y] : points) {
    const Pixel g = pixel(globe, x, y), s = pixel(sphere, x, y);
    std::printf("allsky (%d, %d): globe %.1f cd/m2, sphere %.1f cd/m2\n", x, y, g.luminance(), s.luminance());
    EXPECT_NEAR(g.luminance() / s.luminance(), 1.0, 0.01) << x << ", " << y;
    EXPECT_NEAR(g.b / g.r, s.b / s.r, 0.01 * s.b / s.r) << x << ", " << y;
  }
  EXPECT_GT(pixel(globe, 24, 72).luminance(), 1.5 * pixel(globe, 72, 24).luminance()) << "brighter towards the sun";
  for (const auto& [x, y] : points) EXPECT_GT(pixel(ice, x, y).luminance(), 1.1 * pixel(globe, x, y).luminance());
  EXPECT_EQ(pixel(globe, 0, 0).luminance(), 0.0);
  EXPECT_EQ(pixel(globe, 95, 0).luminance(), 0.0);
}

// A partial eclipse dims the globe's ground as it dims the sphere's: the
// globe lights its ground under the moons (GlobeView::moons: the moons'
// factors for the sun's and the sky's light, atmos_eclipse). The ground 4 m
// away (the north pole's flat sea ice and the flat sphere) has
// the same mix of sun and sky light in both.
TEST(CliRenders, GlobeGroundDimsInAnEclipse) {
  const std::string view = " --sun-elevation 40 --sun-azimuth 180 --look 180,-30 --fov 20 --size 32x32";
  const std::string moon = " --moon 180,40.3,0.3";
  double ratio[2] = {0.0, 0.0};
  for (int globe = 0; globe < 2; ++globe) {
    const std::string surface = globe ? " --surface globe" : " --surface sphere";
    const atmos::Image day = render(view + surface, std::string("day-ground") + (globe ? "-globe" : ""));
    const atmos::Image eclipse = render(view + surface + moon, std::string("eclipse-ground") + (globe ? "-globe" : ""));
    ratio[globe] = mean_colour(eclipse, 0, 0, 32, 32).luminance() / mean_colour(day, 0, 0, 32, 32).luminance();
  }
  std::printf("eclipsed ground over day ground: sphere %.3g, globe %.3g\n", ratio[0], ratio[1]);
  EXPECT_LT(ratio[0], 0.8);
  EXPECT_GT(ratio[0], 0.05);
  EXPECT_NEAR(ratio[1] / ratio[0], 1.0, 0.02);
}

}  // namespace
