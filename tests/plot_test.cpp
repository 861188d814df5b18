// `atmos plot-data` (docs/plots.md): the CSV files behind the plots exist,
// have their documented columns and finite values, say physically plausible
// things, and agree with the library's own tables; bad arguments are one-line
// errors with the exit codes of the other commands.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "atmos/plot_data.hpp"
#include "cli_support.hpp"

namespace {

namespace fs = std::filesystem;

using atmos_test::CliRun;
using atmos_test::slurp;

fs::path scratch() {
  static const fs::path dir = atmos_test::scratch_directory("plot");
  return dir;
}

// Runs the CLI in the scratch directory with its own table cache there.
CliRun atmos_cli(const std::string& args) { return atmos_test::run_cli(scratch(), args); }

int lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

// A numeric CSV file: its header names and its rows, every cell a finite number.
struct Csv {
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;

  size_t index(const std::string& name) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
  std::vector<double> column(const std::string& name) const {
    const size_t i = index(name);
    std::vector<double> out;
    for (const auto& row : rows) out.push_back(row.at(i));
    return out;
  }
  // The rows whose column `name` equals `value`.
  Csv where(const std::string& name, double value) const {
    Csv out{names, {}};
    const size_t i = index(name);
    for (const auto& row : rows)
      if (row.at(i) == value) out.rows.push_back(row);
    return out;
  }
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(cell);
  return cells;
}

Csv read_csv(const fs::path& path, const std::string& expected_header_prefix) {
  Csv csv;
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::string line;
  if (!std::getline(in, line)) {
    ADD_FAILURE() << path << " is empty";
    return csv;
  }
  EXPECT_EQ(line.rfind(expected_header_prefix, 0), 0u) << path << ": header " << line;
  csv.names = split(line);
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    const auto cells = split(line);
    EXPECT_EQ(cells.size(), csv.names.size()) << path << ":" << number;
    std::vector<double> row;
    for (const auto& c : cells) {
      size_t used = 0;
      double v = NAN;
      try {
        v = std::stod(c, &used);
      } catch (const std::exception&) {
      }
      EXPECT_TRUE(used == c.size() && std::isfinite(v)) << path << ":" << number << ": \"" << c << "\"";
      row.push_back(v);
    }
    csv.rows.push_back(row);
  }
  return csv;
}

std::map<std::string, std::string> read_info(const fs::path& path) {
  std::map<std::string, std::string> info;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "key,value");
  while (std::getline(in, line)) {
    const size_t comma = line.find(',');
    if (comma != std::string::npos) info[line.substr(0, comma)] = line.substr(comma + 1);
  }
  return info;
}

const std::string kSmall = " --tables small";

// Earth, three wavelengths, 4 orders, small tables: written once for the tests below.
const fs::path& earth_plot_data() {
  static const fs::path dir = [] {
    const fs::path d = scratch() / "earth";
    const CliRun r = atmos_cli("plot-data --out " + d.string() + kSmall);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("wrote " + (d / "sky.csv").string()), std::string::npos) << r.out;
    return d;
  }();
  return dir;
}

TEST(PlotData, WritesEveryFileWithItsHeader) {
  const fs::path& d = earth_plot_data();
  for (const char* name : {"solar.csv", "extinction.csv", "transmittance.csv", "sky.csv", "convergence.csv", "info.csv"})
    EXPECT_TRUE(fs::is_regular_file(d / name)) << name;
  const auto info = read_info(d / "info.csv");
  EXPECT_EQ(info.at("planet"), "earth");
  EXPECT_EQ(info.at("wavelengths_nm"), "680 550 440");
  EXPECT_EQ(info.at("orders"), "4");
  EXPECT_EQ(info.at("tables"), "small");
}

TEST(PlotData, SolarSpectrumAndExtinction) {
  const fs::path& d = earth_plot_data();
  const Csv solar = read_csv(d / "solar.csv", "wavelength_nm,irradiance_W_m2_nm");
  ASSERT_EQ(solar.rows.size(), 471u);  // 360-830 nm in 1 nm steps
  EXPECT_EQ(solar.rows.front()[0], 360.0);
  EXPECT_EQ(solar.rows.back()[0], 830.0);
  for (const auto& row : solar.rows) EXPECT_GT(row[1], 0.0);
  EXPECT_NEAR(solar.rows[550 - 360][1], 1.85, 0.15) << "ASTM E490 near 550 nm";

  const Csv ext = read_csv(d / "extinction.csv",
                           "wavelength_nm,scattering_air_per_m,absorption_air_per_m,scattering_aerosol_per_m,"
                           "absorption_aerosol_per_m,scattering_ozone_per_m,absorption_ozone_per_m");
  ASSERT_EQ(ext.rows.size(), 95u);  // 360-830 nm in 5 nm steps
  for (const auto& row : ext.rows)
    for (double v : row) EXPECT_GE(v, 0.0);
  const auto air = ext.column("scattering_air_per_m");
  for (size_t i = 1; i < air.size(); ++i) EXPECT_LT(air[i], air[i - 1]) << "Rayleigh falls with wavelength";
  // Rayleigh ~ λ^-4 (a little steeper with the refractive index's dispersion).
  const double ratio = ext.where("wavelength_nm", 400.0).rows[0][1] / ext.where("wavelength_nm", 800.0).rows[0][1];
  EXPECT_GT(ratio, 15.0);
  EXPECT_LT(ratio, 19.0);
  // Ozone absorbs most in the Chappuis band (around 600 nm), little at 400 nm.
  const size_t ozone = ext.index("absorption_ozone_per_m");
  EXPECT_GT(ext.where("wavelength_nm", 600.0).rows[0][ozone], 50.0 * ext.where("wavelength_nm", 400.0).rows[0][ozone]);
}

TEST(PlotData, TransmittanceFallsWithZenithAngleAndAgreesWithTheTables) {
  const fs::path& d = earth_plot_data();
  const Csv t = read_csv(d / "transmittance.csv",
                         "altitude_km,view_zenith_deg,luminance,red,green,blue,transmittance_680nm,transmittance_550nm,"
                         "transmittance_440nm");
  double previous_zenith_transmittance = 0.0;
  for (double altitude : {0.0, 2.0, 10.0, 30.0}) {
    const Csv at = t.where("altitude_km", altitude);
    ASSERT_GT(at.rows.size(), 100u) << altitude;
    const auto zenith = at.column("view_zenith_deg");
    const auto luminance = at.column("luminance");
    EXPECT_EQ(zenith.front(), 0.0);
    EXPECT_GE(zenith.back(), 90.0) << "the horizontal ray reaches the top";
    if (altitude == 0.0) {
      EXPECT_EQ(zenith.back(), 90.0) << "from the ground, lower rays hit the ground";
    }
    for (size_t i = 1; i < at.rows.size(); ++i) {
      EXPECT_GT(zenith[i], zenith[i - 1]);
      EXPECT_LE(luminance[i], luminance[i - 1]) << altitude << " km, " << zenith[i] << " deg";
      for (size_t c = 2; c < at.names.size(); ++c) {
        EXPECT_GE(at.rows[i][c], 0.0);
        EXPECT_LE(at.rows[i][c], 1.0);
      }
    }
    // Blue light is attenuated more than red; higher up there is less air above.
    EXPECT_LT(at.rows[0][at.index("transmittance_440nm")], at.rows[0][at.index("transmittance_680nm")]);
    EXPECT_LT(at.rows[0][at.index("blue")], at.rows[0][at.index("red")]);
    EXPECT_GT(luminance[0], previous_zenith_transmittance);
    previous_zenith_transmittance = luminance[0];
  }
  // Straight up from the ground at 550 nm: Rayleigh optical depth 0.097,
  // aerosol 0.151 (OPAC continental average), ozone (300 DU) 0.03.
  const Csv ground = t.where("altitude_km", 0.0);
  EXPECT_NEAR(ground.rows[0][ground.index("transmittance_550nm")], std::exp(-0.278), 0.01);

  // The direct sunlight of the precomputed tables on a horizontal surface is
  // E_sun T cos(θ): the same transmittance, through the library's own table.
  atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  atmos::PrecomputeOptions options;
  options.sizes = atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8};
  options.scattering_orders = 1;
  const atmos::Tables tables = atmos::precompute_tables(earth, options);
  const atmos::SkyModel model(earth, tables);
  for (double zenith : {0.0, 60.0}) {
    glm::dvec3 sun_e, sky_e;
    model.horizontal_irradiance(atmos::observer_position(earth, 0.0),
                                atmos::direction_from_azimuth_elevation(0.0, 90.0 - zenith), sun_e, sky_e);
    const auto row = ground.where("view_zenith_deg", zenith).rows.at(0);
    const double cos_zenith = std::cos(zenith * M_PI / 180.0);
    for (int i = 0; i < 3; ++i) {
      const double lambda = earth.wavelengths_nm[size_t(i)];
      const double table = sun_e[i] / (earth.solar_irradiance.at(lambda) * cos_zenith);
      EXPECT_NEAR(row[6 + size_t(i)], table, 0.002 * table) << zenith << " deg, " << lambda << " nm";
    }
  }
}

TEST(PlotData, SkyLuminanceAndConvergence) {
  const fs::path& d = earth_plot_data();
  const Csv sky =
      read_csv(d / "sky.csv", "sun_elevation_deg,relative_azimuth_deg,view_zenith_deg,luminance_cd_m2,red,green,blue");
  ASSERT_EQ(sky.rows.size(), 4u * 2u * 91u);
  for (const auto& row : sky.rows) {
    EXPECT_GT(row[3], 0.0);
    EXPECT_NEAR(row[3], 0.2126 * row[4] + 0.7152 * row[5] + 0.0722 * row[6], 1e-3 * row[3]);
  }
  auto zenith_luminance = [&](double sun_elevation) {
    const Csv s = sky.where("sun_elevation_deg", sun_elevation).where("view_zenith_deg", 0.0);
    EXPECT_EQ(s.rows.size(), 2u);
    EXPECT_NEAR(s.rows[0][3], s.rows[1][3], 1e-3 * s.rows[0][3]) << "the zenith seen from both sides";
    return s.rows.at(0)[3];
  };
  EXPECT_GT(zenith_luminance(60.0), 2.0 * zenith_luminance(2.0));
  EXPECT_GT(zenith_luminance(30.0), zenith_luminance(10.0));
  // Clear noon sky at the zenith: a few thousand cd/m².
  EXPECT_GT(zenith_luminance(60.0), 1000.0);
  EXPECT_LT(zenith_luminance(60.0), 10000.0);
  // A low sun: the horizon towards it is brighter than the horizon away from it.
  const Csv low = sky.where("sun_elevation_deg", 10.0).where("view_zenith_deg", 85.0);
  EXPECT_GT(low.where("relative_azimuth_deg", 0.0).rows.at(0)[3], 2.0 * low.where("relative_azimuth_deg", 180.0).rows.at(0)[3]);

  const Csv conv = read_csv(d / "convergence.csv", "order,added,relative");
  ASSERT_EQ(conv.rows.size(), 3u);  // orders 2..4
  for (size_t i = 0; i < conv.rows.size(); ++i) {
    EXPECT_EQ(conv.rows[i][0], double(i + 2));
    EXPECT_GT(conv.rows[i][1], 0.0);
    EXPECT_GT(conv.rows[i][2], 0.0);
    EXPECT_LT(conv.rows[i][2], 0.5);
    if (i > 0) {
      EXPECT_LT(conv.rows[i][1], conv.rows[i - 1][1]) << "each order adds less";
      EXPECT_LT(conv.rows[i][2], conv.rows[i - 1][2]);
    }
  }
}

// Spectral mode and another planet: one transmittance column per working
// wavelength, the planet's own constituents.
TEST(PlotData, SpectralAndMars) {
  const fs::path spectral = scratch() / "spectral";
  CliRun r = atmos_cli("plot-data --wavelengths 6 --orders 2 --out " + spectral.string() + kSmall);
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv t = read_csv(spectral / "transmittance.csv", "altitude_km,view_zenith_deg,luminance,red,green,blue");
  EXPECT_EQ(t.names.size(), 6u + 6u);
  EXPECT_EQ(t.names[6], "transmittance_360nm");
  EXPECT_EQ(t.names[11], "transmittance_830nm");
  EXPECT_EQ(read_info(spectral / "info.csv").at("mode"), "spectral");
  EXPECT_EQ(read_csv(spectral / "convergence.csv", "order,added,relative").rows.size(), 1u);

  const fs::path mars = scratch() / "mars";
  r = atmos_cli("plot-data --planet mars --orders 2 --out " + mars.string() + kSmall);
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv ext = read_csv(mars / "extinction.csv", "wavelength_nm,scattering_");
  const atmos::Atmosphere planet = atmos::load_atmosphere("mars");
  ASSERT_EQ(ext.names.size(), 1 + 2 * planet.constituents.size());
  for (size_t i = 0; i < planet.constituents.size(); ++i) {
    const atmos::Constituent& c = planet.constituents[i];
    EXPECT_EQ(ext.names[1 + 2 * i], "scattering_" + c.name + "_per_m");
    EXPECT_NEAR(ext.where("wavelength_nm", 550.0).rows.at(0)[1 + 2 * i], c.scattering.at(550.0),
                1e-5 * c.scattering.at(550.0));
  }
  EXPECT_EQ(read_csv(mars / "sky.csv", "sun_elevation_deg").rows.size(), 4u * 2u * 91u);
  EXPECT_EQ(read_info(mars / "info.csv").at("planet"), "mars");
}

TEST(PlotData, BadArgumentsAreOneLineErrors) {
  // An output path below a regular file, and one whose parent does not exist:
  // runtime errors (exit 1) naming the path, before any precomputation.
  const fs::path file = scratch() / "a-file";
  {
    std::ofstream f(file);
    f << "x";
  }
  for (const std::string& out : {(file / "plots").string(), file.string(), std::string("/no/such/dir/plots")}) {
    const CliRun r = atmos_cli("plot-data --out " + out + kSmall);
    EXPECT_EQ(r.code, 1) << out << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1) << out << "\n" << r.err;
    EXPECT_NE(r.err.find(out), std::string::npos) << r.err;
    EXPECT_EQ(r.err.rfind("atmos: error: ", 0), 0u) << r.err;
  }
  EXPECT_FALSE(fs::exists("/no/such/dir"));
  // Usage errors (exit 2): no --out, a bad table option, an unknown flag.
  for (const std::string& args : {std::string("plot-data") + kSmall,
                                 "plot-data --wavelengths 2 --out " + (scratch() / "unused").string() + kSmall,
                                 "plot-data --orders 0 --out " + (scratch() / "unused").string() + kSmall,
                                 "plot-data --frobnicate --out " + (scratch() / "unused").string()}) {
    const CliRun r = atmos_cli(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1) << args << "\n" << r.err;
  }
  EXPECT_FALSE(fs::exists(scratch() / "unused")) << "usage errors are reported before anything is written";
  const CliRun help = atmos_cli("plot-data --help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("--out"), std::string::npos);
  EXPECT_NE(help.out.find("--wavelengths"), std::string::npos);
}

}  // namespace

// The tail of auto orders (all orders after the cap, solved at once) is
// marked as such in convergence.csv, not written as one more order.
TEST(PlotData, ConvergenceMarksTheTail) {
  atmos::Tables tables;
  atmos::OrderContribution second;
  second.order = 2;
  second.added = 0.5;
  second.relative = 0.25;
  atmos::OrderContribution tail;
  tail.order = 65;
  tail.added = 3.0;
  tail.relative = 0.6;
  tail.tail = true;
  tail.iterations = 12;
  tables.convergence = {second, tail};
  std::ostringstream out;
  atmos_cli::plot_data::write_convergence(out, tables);
  EXPECT_EQ(out.str(), "order,added,relative,tail\n2,0.5,0.25,0\n65,3,0.6,1\n");
}
