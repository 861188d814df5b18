// Planet files written by write_planet_file read back as the same planet;
// the table of planet parameters (atmos/planet_parameters.hpp) agrees with
// the earth preset, the parser and docs/planet-format.md.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "atmos/planet_file.hpp"
#include "atmos/planet_parameters.hpp"
#include "cli_support.hpp"

namespace {

namespace fs = std::filesystem;

// Every field of the atmosphere but its origin (the file it was read from).
void expect_same_planet(const atmos::Atmosphere& a, const atmos::Atmosphere& b, const std::string& what) {
  EXPECT_EQ(a.name, b.name) << what;
  EXPECT_EQ(a.wavelengths_nm, b.wavelengths_nm) << what;
  EXPECT_EQ(a.bottom_radius_m, b.bottom_radius_m) << what;
  EXPECT_EQ(a.top_radius_m, b.top_radius_m) << what;
  EXPECT_EQ(a.sun_angular_radius_rad, b.sun_angular_radius_rad) << what;
  EXPECT_TRUE(a.solar_irradiance == b.solar_irradiance) << what;
  EXPECT_TRUE(a.ground_albedo == b.ground_albedo) << what;
  ASSERT_EQ(a.constituents.size(), b.constituents.size()) << what;
  for (size_t i = 0; i < a.constituents.size(); ++i) {
    const atmos::Constituent &x = a.constituents[i], &y = b.constituents[i];
    const std::string which = what + " constituent " + x.name;
    EXPECT_EQ(x.name, y.name) << which;
    EXPECT_EQ(x.density.kind, y.density.kind) << which;
    EXPECT_EQ(x.density.scale_height_m, y.density.scale_height_m) << which;
    EXPECT_EQ(x.density.knots, y.density.knots) << which;
    EXPECT_TRUE(x.scattering == y.scattering) << which;
    EXPECT_TRUE(x.absorption == y.absorption) << which;
    EXPECT_TRUE(x.phase == y.phase) << which;
  }
}

TEST(PlanetWriter, EveryPresetReadsBackEqual) {
  const fs::path dir = atmos_test::scratch_directory("planet-writer");
  for (const std::string& name : atmos::preset_names()) {
    const atmos::Atmosphere planet = atmos::load_atmosphere(name);
    const atmos::PlanetSurface surface = atmos::load_surface(name);
    const fs::path path = dir / (name + ".json");
    atmos::write_planet_file(path.string(), planet, surface);
    expect_same_planet(planet, atmos::load_atmosphere(path.string()), name);
    EXPECT_TRUE(atmos::load_surface(path.string()) == surface) << name;
    // Written twice, the same text.
    EXPECT_EQ(atmos::format_planet(atmos::load_atmosphere(path.string()), surface),
              atmos::format_planet(planet, surface))
        << name;
  }
}

// Edited values (what the viewer saves): a scaled density, another albedo,
// radii and a phase function of its own survive the round trip.
TEST(PlanetWriter, EditedPlanetReadsBackEqual) {
  atmos::Atmosphere planet = atmos::load_atmosphere("mars");
  atmos::scale_density(planet, 0.37);
  planet.ground_albedo = atmos::Spectrum::constant(0.1 / 3.0);
  planet.bottom_radius_m = 3389.5e3 + 0.1;
  planet.top_radius_m = planet.bottom_radius_m + 123.456e3;
  planet.constituents[1].phase.g = atmos::Spectrum({400.0, 700.0}, {0.91, 0.1 + 0.2});
  atmos::PlanetSurface surface;
  surface.style = atmos::SurfaceStyle::mars;
  surface.seed = 18446744073709551615ull;
  surface.sea_level_m = -2500.25;
  surface.lake_mask.source = "/data/lakes.tif";
  surface.lake_mask.crs = "IAU_2015:49900";
  surface.lake_level_m = -1200.5;
  const fs::path path = atmos_test::scratch_directory("planet-writer") / "edited.json";
  atmos::write_planet_file(path.string(), planet, surface);
  expect_same_planet(planet, atmos::load_atmosphere(path.string()), "edited mars");
  EXPECT_TRUE(atmos::load_surface(path.string()) == surface);
}

TEST(PlanetWriter, BadInputIsAnError) {
  atmos::Atmosphere planet = atmos::load_atmosphere("earth");
  planet.top_radius_m = planet.bottom_radius_m - 1.0;
  EXPECT_THROW((void)atmos::format_planet(planet), atmos::Error);
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const fs::path missing = atmos_test::scratch_directory("planet-writer") / "no-such-dir" / "x.json";
  try {
    atmos::write_planet_file(missing.string(), earth);
    ADD_FAILURE() << "no error for " << missing;
  } catch (const atmos::Error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot write the planet file"), std::string::npos) << e.what();
  }
}

// Each default is a valid value, inside its slider's range, and the earth
// preset's where the preset has the parameter.
TEST(PlanetParameters, DefaultsAreValidAndEarths) {
  for (const atmos::PlanetParameter& p : atmos::planet_parameters()) {
    EXPECT_NO_THROW(atmos::check_planet_parameter(p.name, p.default_value * p.si_per_unit, p.name)) << p.name;
    EXPECT_NO_THROW(atmos::check_planet_parameter(p.name, p.slider_min * p.si_per_unit, p.name)) << p.name;
    EXPECT_NO_THROW(atmos::check_planet_parameter(p.name, p.slider_max * p.si_per_unit, p.name)) << p.name;
    EXPECT_LE(p.slider_min, p.default_value) << p.name;
    EXPECT_GE(p.slider_max, p.default_value) << p.name;
  }
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const auto si_default = [](const char* name) {
    const atmos::PlanetParameter& p = atmos::planet_parameter(name);
    return p.default_value * p.si_per_unit;
  };
  EXPECT_EQ(double(earth.wavelengths_nm.size()), si_default("wavelengths"));
  EXPECT_DOUBLE_EQ(earth.bottom_radius_m, si_default("bottom_radius"));
  EXPECT_DOUBLE_EQ(earth.top_radius_m - earth.bottom_radius_m, si_default("atmosphere_thickness"));
  EXPECT_DOUBLE_EQ(earth.sun_angular_radius_rad, si_default("sun_angular_radius"));
  EXPECT_DOUBLE_EQ(earth.ground_albedo.at(550.0), si_default("ground_albedo"));
  EXPECT_DOUBLE_EQ(earth.constituents[0].density.scale_height_m, si_default("constituents[].density.scale_height"));
  EXPECT_DOUBLE_EQ(earth.constituents[1].phase.g.at(550.0), si_default("constituents[].phase_function.g"));
  EXPECT_THROW((void)atmos::planet_parameter("warp_factor"), atmos::Error);
}

// Values outside a range are one-line errors naming the value, the range
// and the unit; the planet-file parser gives them for its keys.
TEST(PlanetParameters, OutOfRangeValuesAreClearErrors) {
  try {
    atmos::check_planet_parameter("atmosphere_thickness", 500.0, "atmosphere thickness");
    ADD_FAILURE() << "no error";
  } catch (const atmos::Error& e) {
    EXPECT_EQ(std::string(e.what()), "atmosphere thickness must be in [1, 10000] km, got 0.5 km");
  }
  EXPECT_THROW(atmos::check_planet_parameter("ground_albedo", std::nan(""), "x"), atmos::Error);
  EXPECT_NO_THROW(atmos::check_planet_parameter("constituents[].phase_function.g", -0.5, "g"));
  EXPECT_THROW(atmos::check_planet_parameter("constituents[].phase_function.g", 0.999, "g"), atmos::Error);
  std::string text = atmos::format_planet(atmos::load_atmosphere("earth"));
  const std::string key = "\"sun_angular_radius\": {\n    \"unit\": \"rad\",\n    \"value\": ";
  const size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos) << text.substr(0, 600);
  const size_t end = text.find('\n', at + key.size());
  text.replace(at + key.size(), end - (at + key.size()), "0.5");
  try {
    (void)atmos::parse_atmosphere(text, "wide-sun.json");
    ADD_FAILURE() << "no error for a sun of 0.5 rad";
  } catch (const atmos::Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("wide-sun.json: sun_angular_radius must be in (0, ", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("deg, got 28.6479 deg"), std::string::npos) << e.what();
  }
}

// The parameters whose samples Atmosphere::validate checks (spectra) have
// the table's ranges there too: a value at each bound, and just beyond it,
// is accepted or refused alike.
TEST(PlanetParameters, SpectrumRangesAreThoseOfValidate) {
  const auto accepted = [](const char* name, double value) {
    atmos::Atmosphere a = atmos::load_atmosphere("mars");  // a double Henyey-Greenstein dust
    atmos::PhaseFunction& dust = a.constituents[1].phase;
    const atmos::Spectrum v = atmos::Spectrum::constant(value);
    const std::string n = name;
    if (n == "ground_albedo") a.ground_albedo = v;
    if (n == "constituents[].phase_function.g") dust.g = v;
    if (n == "constituents[].phase_function.g_back") dust.g_back = v;
    if (n == "constituents[].phase_function.forward_weight") dust.forward_weight = v;
    try {
      a.validate();
      return true;
    } catch (const atmos::Error&) {
      return false;
    }
  };
  ASSERT_EQ(atmos::load_atmosphere("mars").constituents[1].phase.kind,
            atmos::PhaseFunction::Kind::double_henyey_greenstein);
  for (const char* name : {"ground_albedo", "constituents[].phase_function.g", "constituents[].phase_function.g_back",
                           "constituents[].phase_function.forward_weight"}) {
    const atmos::PlanetParameter& p = atmos::planet_parameter(name);
    const double step = 1e-9;
    EXPECT_EQ(accepted(name, p.min), p.min_inclusive) << name;
    EXPECT_EQ(accepted(name, p.max), p.max_inclusive) << name;
    EXPECT_TRUE(accepted(name, p.min + step)) << name;
    EXPECT_TRUE(accepted(name, p.max - step)) << name;
    EXPECT_FALSE(accepted(name, p.min - step)) << name;
    EXPECT_FALSE(accepted(name, p.max + step)) << name;
  }
}

// docs/planet-format.md's table lists every parameter with its unit and range.
TEST(PlanetParameters, DocumentedInThePlanetFormat) {
  const std::filesystem::path doc =
      std::filesystem::path(ATMOS_SOURCE_DIR) / "docs" / "planet-format.md";
  std::ifstream in(doc);
  ASSERT_TRUE(in) << doc;
  std::stringstream text;
  text << in.rdbuf();
  for (const atmos::PlanetParameter& p : atmos::planet_parameters()) {
    const std::string row = std::string("| `") + p.name + "` | " + p.unit + " | " + atmos::valid_range_text(p);
    EXPECT_NE(text.str().find(row), std::string::npos) << "docs/planet-format.md has no row starting " << row;
  }
}

}  // namespace
