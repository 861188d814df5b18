// Planet files: presets load, and every kind of bad input is a clear error.
#include <filesystem>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"

namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string earth_text() { return read_file(std::filesystem::path(ATMOS_SOURCE_DIR) / "data" / "planets" / "earth.json"); }

// Expects parse_atmosphere to throw an atmos::Error whose one-line message contains `needle`.
void expect_error(const std::string& text, const std::string& needle) {
  try {
    atmos::parse_atmosphere(text, "test.json");
    FAIL() << "no error for input containing: " << needle;
  } catch (const atmos::Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(needle), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "message must be one line: " << message;
    EXPECT_EQ(message.rfind("test.json", 0), 0u) << "message must name the file: " << message;
  }
}

std::string modified(const std::function<void(nlohmann::json&)>& change) {
  nlohmann::json j = nlohmann::json::parse(earth_text());
  change(j);
  return j.dump();
}

TEST(Presets, EarthAndMarsThesisLoadWithTheirValues) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  EXPECT_DOUBLE_EQ(earth.bottom_radius_m, 6371e3);
  EXPECT_DOUBLE_EQ(earth.top_radius_m, 6471e3);
  ASSERT_EQ(earth.constituents.size(), 3u);
  EXPECT_NEAR(earth.constituents[0].scattering.at(550.0), 1.1483e-5, 1e-9);
  EXPECT_EQ(earth.constituents[2].density.kind, atmos::DensityProfile::Kind::piecewise_linear);
  // ASTM E490, its 10 nm mean at 550 nm (the 1 nm rows at 549.5 and 550.5
  // nm are 1.895 and 1.862).
  EXPECT_NEAR(earth.solar_irradiance.at(550.0), 1.8727, 0.0005);

  // Collienne 2013's Mars (the physically derived dusty Mars is "mars", see presets_test.cpp).
  const atmos::Atmosphere mars = atmos::load_atmosphere("mars-thesis");
  EXPECT_EQ(mars.name, "mars-thesis");
  EXPECT_DOUBLE_EQ(mars.bottom_radius_m, 3386e3);
  EXPECT_DOUBLE_EQ(mars.top_radius_m, 3518e3);
  // Collienne 2013, §5: betaR = (0.019918, 0.01357, 0.00575) per km at (680, 550, 440) nm.
  EXPECT_NEAR(mars.constituents[0].scattering.at(680.0), 0.019918e-3, 1e-12);
  EXPECT_NEAR(mars.constituents[0].scattering.at(550.0), 0.01357e-3, 1e-12);
  EXPECT_NEAR(mars.constituents[0].scattering.at(440.0), 0.00575e-3, 1e-12);
  EXPECT_NEAR(mars.constituents[1].scattering.at(550.0), 0.003e-3, 1e-12);
  EXPECT_DOUBLE_EQ(mars.constituents[0].density.scale_height_m, 11e3);
  EXPECT_DOUBLE_EQ(mars.constituents[1].density.scale_height_m, 3.2e3);
}

TEST(Presets, UnknownNameIsAClearError) {
  try {
    atmos::load_atmosphere("jupiter");
    FAIL();
  } catch (const atmos::Error& e) {
    EXPECT_NE(std::string(e.what()).find("neither a preset"), std::string::npos);
  }
}

TEST(PlanetFile, UserFilesLoadLikePresets) {
  const atmos::Atmosphere a = atmos::parse_atmosphere(earth_text(), "copy.json");
  EXPECT_EQ(a.name, "earth");
  const atmos::Atmosphere b = atmos::load_atmosphere(std::filesystem::path(ATMOS_SOURCE_DIR) / "data" / "planets" / "mars.json");
  EXPECT_EQ(b.name, "mars");
}

// Coefficients from physical inputs (Elek & Kmoch 2010, eq. 1-2): Rayleigh
// from the refractive index and number density reproduces the Earth preset's
// air at 550 nm (computed there from the same n, N and King factor); an
// absorber from its cross section; an aerosol from Ångström's law.
TEST(PlanetFile, CoefficientsFromPhysicalInputs) {
  const auto a = atmos::parse_atmosphere(modified([](nlohmann::json& j) {
    j["constituents"][0]["scattering"] = {{"rayleigh",
                                           {{"refractive_index", 1.0002778229},
                                            {"number_density", {{"value", 2.5469e25}, {"unit", "1/m^3"}}},
                                            {"king_factor", 1.0480}}}};
    j["constituents"][1]["scattering"] = {
        {"angstrom", {{"alpha", 1.3}, {"beta", 0.05}, {"scale_height", {{"value", 1.5}, {"unit", "km"}}}}}};
    j["constituents"][2]["absorption"] = {{"cross_section", {{"value", 3.5e-21}, {"unit", "cm^2"}}},
                                          {"number_density", {{"value", 5.37e12}, {"unit", "1/cm^3"}}}};
  }), "t.json");
  EXPECT_NEAR(a.constituents[0].scattering.at(550.0), 1.1483e-5, 1e-3 * 1.1483e-5);
  // λ^-4 (a non-dispersive n).
  EXPECT_NEAR(a.constituents[0].scattering.at(440.0) / a.constituents[0].scattering.at(880.0), 16.0, 1e-9);
  EXPECT_NEAR(a.constituents[1].scattering.at(1000.0), 0.05 / 1500.0, 1e-12);
  EXPECT_NEAR(a.constituents[1].scattering.at(500.0), 0.05 / 1500.0 * std::pow(2.0, 1.3), 1e-10);
  EXPECT_NEAR(a.constituents[2].absorption.at(600.0), 3.5e-25 * 5.37e18, 1e-12);

  expect_error(modified([](nlohmann::json& j) {
                 j["constituents"][0]["scattering"] = {
                     {"rayleigh", {{"refractive_index", 0.9}, {"number_density", {{"value", 1e25}, {"unit", "1/m^3"}}}}}};
               }),
               "refractive_index");
  expect_error(modified([](nlohmann::json& j) {
                 j["constituents"][1]["scattering"] = {
                     {"angstrom", {{"alpha", 1.3}, {"beta", -1.0}, {"scale_height", {{"value", 1.5}, {"unit", "km"}}}}}};
               }),
               "beta");
  expect_error(modified([](nlohmann::json& j) {
                 j["solar_irradiance"] = {{"rayleigh", {{"refractive_index", 1.0003}}}};
               }),
               "only valid for coefficients");
}

TEST(PlanetFile, UnitsAreConverted) {
  const auto a = atmos::parse_atmosphere(modified([](nlohmann::json& j) {
    j["bottom_radius"] = {{"value", 6371000}, {"unit", "m"}};
    j["sun_angular_radius"] = {{"value", 16}, {"unit", "arcmin"}};
  }), "t.json");
  EXPECT_DOUBLE_EQ(a.bottom_radius_m, 6371000.0);
  EXPECT_NEAR(a.sun_angular_radius_rad, 16.0 / 60.0 * M_PI / 180.0, 1e-12);
}

TEST(PlanetFile, BadInputsAreClearErrors) {
  expect_error("{ not json", "malformed JSON");
  expect_error("", "malformed JSON");
  expect_error(modified([](nlohmann::json& j) { j.erase("bottom_radius"); }), "missing planet.bottom_radius");
  expect_error(modified([](nlohmann::json& j) { j["bottom_radius"]["value"] = -5; }), "bottom_radius must be positive");
  expect_error(modified([](nlohmann::json& j) { j["top_radius"]["value"] = 6000; }), "top_radius must be larger");
  expect_error(modified([](nlohmann::json& j) { j["top_radius"].erase("unit"); }), "needs a \"unit\"");
  expect_error(modified([](nlohmann::json& j) { j["top_radius"]["unit"] = "furlong"; }), "expected one of");
  expect_error(modified([](nlohmann::json& j) { j["top_radius"]["value"] = "far"; }), "must be a number");
  expect_error(modified([](nlohmann::json& j) { j["colour"] = "blue"; }), "unknown key \"colour\"");
  expect_error(modified([](nlohmann::json& j) { j["constituents"][1]["phase_function"]["g"] = 1.5; }), "g must be in");
  expect_error(modified([](nlohmann::json& j) { j["constituents"][0]["scattering"]["values"][0] = -1e-5; }),
               "outside [0");
  expect_error(modified([](nlohmann::json& j) { j["constituents"][0]["density"]["scale_height"]["value"] = 0; }),
               "scale_height must be positive");
  expect_error(modified([](nlohmann::json& j) { j["constituents"] = nlohmann::json::array(); }), "non-empty");
  expect_error(modified([](nlohmann::json& j) { j["format"] = "v2"; }), "format");
  expect_error(modified([](nlohmann::json& j) { j["wavelengths"]["values"] = {500, 600}; }), "[3, 48]");
  expect_error(modified([](nlohmann::json& j) { j["ground_albedo"]["value"] = 2.0; }), "ground_albedo");
  expect_error(modified([](nlohmann::json& j) {
    j["constituents"][2]["density"]["points"] = {{25, 1}, {10, 0}};
  }), "altitudes must increase");
  expect_error(modified([](nlohmann::json& j) {
    j["constituents"][2]["phase_function"] = {{"type", "henyey_greenstein"}, {"g", 0.5}};
    j["constituents"][2]["scattering"] = {{"unit", "1/m"}, {"value", 1e-6}};
  }), "share one phase function");
  // JSON has no NaN literal; a NaN written by a program is malformed JSON.
  expect_error("{\"format\": NaN}", "malformed JSON");
}

// The optional "surface" object (docs/planet-format.md): every preset has
// its relief style; a file without one is the flat datum sphere; a sea level
// is a length; mistakes are one-line errors naming the file and the key.
TEST(PlanetFile, SurfaceFieldsLoadAndBadOnesAreClearErrors) {
  EXPECT_EQ(atmos::load_surface("earth").style, atmos::SurfaceStyle::earth);
  EXPECT_EQ(atmos::load_surface("mars").style, atmos::SurfaceStyle::mars);
  EXPECT_EQ(atmos::load_surface("mars-thesis").style, atmos::SurfaceStyle::mars);
  EXPECT_EQ(atmos::load_surface("venus").style, atmos::SurfaceStyle::venus);
  EXPECT_EQ(atmos::load_surface("titan").style, atmos::SurfaceStyle::titan);
  const atmos::PlanetSurface none = atmos::parse_surface(modified([](nlohmann::json& j) { j.erase("surface"); }), "x");
  EXPECT_EQ(none.style, atmos::SurfaceStyle::flat);
  EXPECT_FALSE(none.sea_level_m.has_value());
  const std::string custom = modified([](nlohmann::json& j) {
    j["surface"] = {{"relief", {{"style", "mars"}, {"seed", 42}}}, {"sea_level", {{"value", -2.5}, {"unit", "km"}}}};
  });
  const atmos::PlanetSurface s = atmos::parse_surface(custom, "x");
  EXPECT_EQ(s.style, atmos::SurfaceStyle::mars);
  EXPECT_EQ(s.seed, 42u);
  ASSERT_TRUE(s.sea_level_m.has_value());
  EXPECT_DOUBLE_EQ(*s.sea_level_m, -2500.0);
  EXPECT_NO_THROW(atmos::parse_atmosphere(custom, "x"));  // the atmosphere accepts the key

  const auto expect_surface_error = [](const std::string& text, const std::string& needle) {
    try {
      atmos::parse_surface(text, "test.json");
      FAIL() << "no error for: " << needle;
    } catch (const atmos::Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(needle), std::string::npos) << message;
      EXPECT_EQ(message.rfind("test.json", 0), 0u) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  };
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"]["relief"]["style"] = "jupiter"; }),
                       "surface.relief.style");
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"]["relief"]["seed"] = -3; }), "seed");
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"]["relief"]["seed"] = 1.5; }), "seed");
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"]["relief"].erase("style"); }), "style");
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"]["rivers"] = true; }), "unknown key \"rivers\"");
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"]["sea_level"] = {{"value", 1}, {"unit", "s"}}; }),
                       "sea_level");
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"] = 3; }), "surface must be an object");
  EXPECT_THROW(atmos::surface_style_from_name("gas giant"), atmos::Error);

  // Data sources: relative paths are relative to the planet file; units,
  // CRS and bounds as given; contradictions and malformed fields are errors.
  const std::string data = modified([](nlohmann::json& j) {
    j["surface"]["elevation"] = {{"source", "dem/mola.tif"}, {"unit", "km"}, {"crs", "IAU_2015:49900"}};
    j["surface"]["imagery"] = {{"source", "/abs/colour.jpg"}, {"bounds_deg", {-180, -90, 180, 90}}};
    j["surface"]["coastline"] = {{"source", "shore.nc"}};
  });
  const atmos::PlanetSurface d = atmos::parse_surface(data, "/planets/my/earth.json");
  EXPECT_EQ(d.elevation.source, "/planets/my/dem/mola.tif");
  EXPECT_DOUBLE_EQ(d.elevation.metres_per_unit, 1000.0);
  EXPECT_EQ(d.elevation.crs, "IAU_2015:49900");
  EXPECT_EQ(d.imagery.source, "/abs/colour.jpg");
  ASSERT_TRUE(d.imagery.bounds_deg.has_value());
  EXPECT_DOUBLE_EQ((*d.imagery.bounds_deg)[2], 180.0);
  EXPECT_EQ(d.coastline, "/planets/my/shore.nc");
  EXPECT_FALSE(atmos::load_surface("earth").imagery.source.empty());
  EXPECT_FALSE(atmos::load_surface("earth").coastline.empty());
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"]["elevation"] = {{"unit", "m"}}; }),
                       "surface.elevation");
  expect_surface_error(modified([](nlohmann::json& j) { j["surface"]["elevation"] = {{"source", ""}}; }),
                       "surface.elevation.source");
  expect_surface_error(
      modified([](nlohmann::json& j) { j["surface"]["elevation"] = {{"source", "a.tif"}, {"unit", "furlong"}}; }),
      "surface.elevation.unit");
  expect_surface_error(
      modified([](nlohmann::json& j) { j["surface"]["imagery"] = {{"source", "a.jpg"}, {"unit", "m"}}; }),
      "unknown key \"unit\"");
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"]["imagery"] = {{"source", "a.jpg"}, {"bounds_deg", {10, 0, -10, 5}}};
                       }),
                       "bounds_deg");
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"]["imagery"] = {{"source", "a.jpg"}, {"bounds_deg", {-10, 0, 10}}};
                       }),
                       "bounds_deg");
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"]["relief"]["style"] = "mars";
                         j["surface"]["coastline"] = {{"source", "shore.nc"}};
                       }),
                       "coastline");
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"]["relief"]["style"] = "earth";
                         j["surface"]["coastline"] = {{"source", "shore.nc"}};
                         j["surface"]["sea_level"] = {{"value", 100}, {"unit", "m"}};
                       }),
                       "contradicts surface.sea_level");
  // Lakes: a mask (a raster without a unit) and the level of their surface,
  // which must lie above the sea level (the style's: Earth 0).
  const atmos::PlanetSurface lakes = atmos::parse_surface(modified([](nlohmann::json& j) {
    j["surface"]["lakes"] = {{"mask", {{"source", "lakes.tif"}}}, {"level", {{"value", 0.372}, {"unit", "km"}}}};
  }), "/planets/my/earth.json");
  EXPECT_EQ(lakes.lake_mask.source, "/planets/my/lakes.tif");
  ASSERT_TRUE(lakes.lake_level_m.has_value());
  EXPECT_DOUBLE_EQ(*lakes.lake_level_m, 372.0);
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"]["lakes"] = {{"mask", {{"source", "lakes.tif"}}}};
                       }),
                       "missing surface.lakes.level");
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"]["lakes"] = {{"level", {{"value", 3}, {"unit", "m"}}}};
                       }),
                       "missing surface.lakes.mask");
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"]["lakes"] = {{"mask", {{"source", "lakes.tif"}, {"unit", "m"}}},
                                                  {"level", {{"value", 3}, {"unit", "m"}}}};
                       }),
                       "unknown key \"unit\" in surface.lakes.mask");
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"]["relief"]["style"] = "earth";
                         j["surface"]["lakes"] = {{"mask", {{"source", "lakes.tif"}}},
                                                  {"level", {{"value", -28}, {"unit", "m"}}}};
                       }),
                       "surface.lakes.level");
  expect_surface_error(modified([](nlohmann::json& j) {
                         j["surface"].erase("coastline");
                         j["surface"]["sea_level"] = {{"value", 50}, {"unit", "m"}};
                         j["surface"]["lakes"] = {{"mask", {{"source", "lakes.tif"}}},
                                                  {"level", {{"value", 50}, {"unit", "m"}}}};
                       }),
                       "not above the sea level");
  // The atmosphere's reader checks the surface too: a bad file fails wherever it is read.
  EXPECT_THROW(atmos::parse_atmosphere(modified([](nlohmann::json& j) { j["surface"]["relief"]["seed"] = "x"; }),
                                       "x"),
               atmos::Error);
}

// Inputs a damaged or hand-edited file can hold beyond the ordinary mistakes
// (fuzz/planet_file_fuzzer.cpp writes such inputs): each must be an
// atmos::Error that names the file, like every other bad input.
TEST(PlanetFile, NumbersBeyondRangeAndDerivedSpectraAreClearErrors) {
  // A literal beyond the range of a double is malformed JSON, not another exception type.
  expect_error("{\"format\": 1e400}", "malformed JSON");
  expect_error(modified([](nlohmann::json& j) { j.erase("top_radius"); }).insert(1, "\"top_radius\": -1e309,"),
               "malformed JSON");
  // Repeated wavelengths that are not next to each other in the file.
  expect_error(modified([](nlohmann::json& j) {
                 j["ground_albedo"] = {{"unit", "1"}, {"wavelengths_nm", {500, 600, 500}}, {"values", {0.1, 0.2, 0.3}}};
               }),
               "ground_albedo: wavelengths must be distinct");
  // Spectra whose values overflow to infinity when they are computed: a power
  // law, an Angstrom aerosol, the E490 table at a tiny distance.
  expect_error(modified([](nlohmann::json& j) {
                 j["constituents"][0]["scattering"] = {
                     {"unit", "1/m"}, {"power_law", {{"value", 1e300}, {"reference_nm", 1.0}, {"exponent", 4}}}};
               }),
               "constituents[0].scattering.power_law");
  expect_error(modified([](nlohmann::json& j) {
                 j["constituents"][1]["scattering"] = {
                     {"angstrom", {{"alpha", 1.0}, {"beta", 1e300}, {"scale_height", {{"value", 1e-300}, {"unit", "m"}}}}}};
               }),
               "constituents[1].scattering.angstrom");
  expect_error(modified([](nlohmann::json& j) {
                 j["solar_irradiance"]["distance"] = {{"value", 1e-160}, {"unit", "au"}};
               }),
               "solar_irradiance");
}

// A sample out of bounds at a wavelength beyond the range of an int:
// validate()'s message gives the wavelength as it is (converting it to int
// would be undefined behaviour).
TEST(PlanetFile, SampleOutOfBoundsAtAHugeWavelengthIsNamedAsItIs) {
  expect_error(modified([](nlohmann::json& j) {
                 j["ground_albedo"] = {{"unit", "1"}, {"wavelengths_nm", {1e300}}, {"values", {2.0}}};
               }),
               "ground_albedo at 1e+300 nm is 2");
}

// Strings of the file that a message repeats (keys, units) are escaped as
// JSON writes them, and names, which messages and reports show, are one line:
// a newline in the file never splits a message.
TEST(PlanetFile, MessagesStayOnOneLineWhateverTheStringsOfTheFile) {
  expect_error(modified([](nlohmann::json& j) { j["constituents"][0]["scattering"]["bad\nkey"] = 1; }),
               "unknown key \"bad\\nkey\"");
  expect_error(modified([](nlohmann::json& j) { j["top_radius"]["unit"] = "k\nm"; }), "has unit \"k\\nm\"");
  expect_error(modified([](nlohmann::json& j) { j["constituents"][0]["phase_function"]["g\r"] = 0.5; }),
               "takes no parameters (got \"g\\r\")");
  expect_error(modified([](nlohmann::json& j) { j["name"] = "earth\nsecond line"; }), "name \"earth\\nsecond line\"");
  expect_error(modified([](nlohmann::json& j) { j["constituents"][1]["name"] = "aero\tsol"; }),
               "constituents[1].name");
}

}  // namespace
