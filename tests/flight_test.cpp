// atmos view: the flight model, the recorded flights and the scripts (unit
// tests of apps/view/, built when the viewer is: ATMOS_VIEWER). The viewer
// end to end is in view_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/planet_file.hpp"
#include "cli_support.hpp"

#ifdef ATMOS_VIEWER
#include <glm/geometric.hpp>

#include "view/flight.hpp"
#include "view/script.hpp"
#include "view/state.hpp"
#endif

namespace {

namespace fs = std::filesystem;

#ifdef ATMOS_VIEWER

using atmos_view::Flight;
using atmos_view::FlightInput;

constexpr double kRadius = 6360e3;

// A bumpy ground: 0 to 2 km depending on the direction.
double bumpy(const glm::dvec3& p) { return 1000.0 + 1000.0 * std::sin(5.0 * glm::normalize(p).x); }

TEST(ViewFlight, SpeedIsProportionalToAltitude) {
  Flight flight(kRadius);
  const Flight::GroundHeight flat = [](const glm::dvec3&) { return 0.0; };
  flight.place(20.0, 30.0, 2.0, 90.0, 0.0, flat);
  EXPECT_NEAR(flight.altitude_m(flat), 2.0, 1e-6);
  EXPECT_NEAR(flight.speed_m_per_s(flat), 2.0, 1e-6);
  flight.place(20.0, 30.0, 400e3, 90.0, 0.0, flat);
  EXPECT_NEAR(flight.speed_m_per_s(flat), 400e3, 1e-3);
  // Climbing at full speed for one second multiplies the altitude by
  // about e (a step of k dt of the altitude per frame).
  FlightInput up;
  up.up = true;
  flight.place(20.0, 30.0, 100.0, 90.0, 0.0, flat);
  for (int i = 0; i < 100; ++i) flight.update(up, 0.01, flat);
  EXPECT_NEAR(flight.altitude_m(flat), 100.0 * std::pow(1.01, 100), 1e-6);
  // Below 1 m the speed stays at 1 m/s.
  flight.place(20.0, 30.0, 0.5, 90.0, 0.0, flat);
  EXPECT_NEAR(flight.speed_m_per_s(flat), 1.0, 1e-9);
}

TEST(ViewFlight, StaysAboveTheTerrainAndWithinReach) {
  Flight flight(kRadius);
  const Flight::GroundHeight ground = bumpy;
  flight.place(10.0, 40.0, 5.0, 0.0, -80.0, ground);
  FlightInput dive;
  dive.forward = true;
  dive.down = true;
  dive.speed_multiplier = 100.0;
  for (int i = 0; i < 200; ++i) {
    flight.update(dive, 0.25, ground);
    ASSERT_GE(flight.altitude_m(ground), Flight::kMinClearanceM - 1e-6) << "frame " << i;
  }
  FlightInput climb;
  climb.up = true;
  climb.speed_multiplier = 100.0;
  for (int i = 0; i < 200; ++i) flight.update(climb, 0.25, ground);
  EXPECT_NEAR(glm::length(flight.position()), Flight::kMaxDistanceRadii * kRadius, 1.0);
  // Absurd input changes nothing it should not.
  FlightInput absurd;
  absurd.look_dx = std::nan("");
  absurd.look_dy = INFINITY;
  absurd.forward = true;
  absurd.speed_multiplier = std::nan("");
  flight.update(absurd, INFINITY, ground);
  EXPECT_TRUE(std::isfinite(glm::length(flight.position())));
  EXPECT_TRUE(std::isfinite(flight.pitch_deg()));
  // The pitch stops short of the vertical.
  FlightInput look_down;
  look_down.look_dy = 1e6;
  flight.update(look_down, 0.0, ground);
  EXPECT_EQ(flight.pitch_deg(), -Flight::kPitchLimitDeg);
  const atmos_view::CameraPose pose = flight.pose();
  EXPECT_NEAR(glm::length(pose.forward), 1.0, 1e-12);
  EXPECT_NEAR(glm::dot(pose.forward, pose.up), 0.0, 1e-12);
}

TEST(ViewFlight, JumpsGoToTheirAltitudes) {
  Flight flight(kRadius);
  const Flight::GroundHeight ground = bumpy;
  flight.place(-30.0, 100.0, 50.0, 45.0, 10.0, ground);
  const glm::dvec3 direction = glm::normalize(flight.position());
  const double expected[] = {2.0, 10e3, 400e3, 2.5 * kRadius};
  for (int k = 1; k <= 4; ++k) {
    FlightInput jump;
    jump.jump = k;
    flight.update(jump, 0.0, ground);
    EXPECT_NEAR(flight.altitude_m(ground), expected[k - 1], 1e-6 * expected[k - 1]) << "key " << k;
    EXPECT_NEAR(glm::dot(glm::normalize(flight.position()), direction), 1.0, 1e-12) << "key " << k;
  }
  EXPECT_EQ(flight.pitch_deg(), -Flight::kPitchLimitDeg);  // from 2.5 radii: straight down
}

TEST(ViewFlight, RecordsRoundTripBitForBit) {
  atmos_view::FlightRecord record;
  record.globe = false;
  record.width = 33;
  record.height = 17;
  atmos_view::FrameRecord f;
  f.time_s = 1.0 / 3.0;
  f.pose.position = {6371e3 / 7.0, -1e-7 / 3.0, 6.4e6 * M_PI};
  f.pose.forward = glm::normalize(glm::dvec3(0.1, 0.7, -0.3));
  f.pose.up = glm::normalize(glm::dvec3(1.0, -0.1, 0.1 / 3.0));
  f.sun = glm::normalize(glm::dvec3(M_E, 1.0, 0.5));
  f.look.tone_mapping = atmos::ToneMapping::aces;
  f.look.bloom = 0.1 / 7.0;
  f.planet.density_scale = 1.0 / 3.0;
  f.planet.ground_albedo = 0.3;
  f.planet.constituents.resize(2);
  f.planet.constituents[1].phase_g = 0.7 / 3.0;
  f.planet.constituents[1].scale_height_m = 1234.5;
  record.frames = {f, f};
  const fs::path path = atmos_test::scratch_directory("view") / "record.json";
  atmos_view::write_flight(record, path.string());
  const atmos_view::FlightRecord back = atmos_view::read_flight(path.string());
  ASSERT_EQ(back.frames.size(), 2u);
  EXPECT_FALSE(back.globe);
  EXPECT_EQ(back.width, 33);
  const atmos_view::FrameRecord& g = back.frames[1];
  EXPECT_EQ(g.time_s, f.time_s);
  EXPECT_EQ(g.pose.position, f.pose.position);
  EXPECT_EQ(g.pose.forward, f.pose.forward);
  EXPECT_EQ(g.pose.up, f.pose.up);
  EXPECT_EQ(g.sun, f.sun);
  EXPECT_TRUE(g.look == f.look);
  EXPECT_TRUE(g.planet == f.planet);
}

TEST(ViewFlight, BadRecordsAndScriptsAreOneLineErrors) {
  const fs::path dir = atmos_test::scratch_directory("view");
  const auto expect_error = [&](const std::string& text, const std::string& message, bool script) {
    const fs::path path = dir / "bad.json";
    std::ofstream(path) << text;
    try {
      if (script)
        (void)atmos_view::Script::read(path.string());
      else
        (void)atmos_view::read_flight(path.string());
      ADD_FAILURE() << "no error for " << text;
    } catch (const atmos::Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(message), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  expect_error("{", "not valid JSON", false);
  expect_error(R"({"format": "x", "version": 1})", "format must be", false);
  expect_error(R"({"format": "atmos-flight", "version": 1, "surface": "globe", "planet_albedo": false,
                   "width": 8, "height": 8, "frames": []})",
               "frames must be a non-empty array", false);
  expect_error(R"({"events": [{"frame": 0, "key": "X"}]})", "\"key\" must be one of", true);
  expect_error(R"({"events": [{"frame": 0, "slider": "warp", "from": 0, "to": 1}]})", "unknown slider", true);
  expect_error(R"({"events": [{"frame": -1, "key": "W"}]})", "\"frame\" must be an integer >= 0", true);
  EXPECT_THROW((void)atmos_view::read_flight((dir / "missing.json").string()), atmos::Error);

  atmos_view::PlanetParams p;
  p.ground_albedo = 1.5;
  EXPECT_THROW((void)atmos_view::make_atmosphere(p), atmos::Error);
  p = {};
  p.planet = (dir / "no-such-planet.json").string();
  EXPECT_THROW((void)atmos_view::make_atmosphere(p), atmos::Error);
}

// The panel's edits of the planet: each changes what it names, and
// impossible ones are one-line errors.
TEST(ViewFlight, PlanetEditsChangeTheAtmosphere) {
  const atmos::Atmosphere earth = atmos_view::make_atmosphere({});
  atmos_view::PlanetParams p;
  p.bottom_radius_m = 3000e3;
  p.thickness_m = 100e3;
  p.ground_albedo = 0.25;
  p.constituents.resize(2);
  p.constituents[0].scattering_scale = 2.0;
  p.constituents[1].scale_height_m = 2500.0;
  p.constituents[1].phase_g = 0.5;
  const atmos::Atmosphere a = atmos_view::make_atmosphere(p);
  EXPECT_EQ(a.bottom_radius_m, 3000e3);
  EXPECT_EQ(a.top_radius_m, 3100e3);
  EXPECT_EQ(a.ground_albedo.at(500.0), 0.25);
  EXPECT_DOUBLE_EQ(a.constituents[0].scattering.at(550.0), 2.0 * earth.constituents[0].scattering.at(550.0));
  EXPECT_EQ(a.constituents[0].absorption.at(550.0), earth.constituents[0].absorption.at(550.0));
  EXPECT_EQ(a.constituents[1].density.scale_height_m, 2500.0);
  EXPECT_EQ(a.constituents[1].phase.g.at(440.0), 0.5);
  EXPECT_EQ(a.constituents[2].density.kind, earth.constituents[2].density.kind);

  const auto expect_error = [](const atmos_view::PlanetParams& bad, const std::string& message) {
    try {
      (void)atmos_view::make_atmosphere(bad);
      ADD_FAILURE() << "no error for " << message;
    } catch (const atmos::Error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  atmos_view::PlanetParams bad;
  bad.constituents.resize(1);
  bad.constituents[0].phase_g = 0.5;  // the air: Rayleigh
  expect_error(bad, "a Rayleigh phase function has no asymmetry parameter");
  bad = {};
  bad.constituents.resize(3);
  bad.constituents[2].scale_height_m = 8000.0;  // ozone: a piecewise linear layer
  expect_error(bad, "its density profile is not exponential");
  bad = {};
  bad.constituents.resize(7);
  expect_error(bad, "the planet has 3 constituents, 7 edited");
  bad = {};
  bad.thickness_m = 10.0;
  expect_error(bad, "atmosphere thickness must be in [1, 10000] km, got 0.01 km");
  bad = {};
  bad.density_scale = -1.0;
  expect_error(bad, "density scale must be in (0, 10000]");
}

// The panel's "save": the planet with its edits, as a planet file that
// reads back as that planet.
TEST(ViewFlight, SavedPlanetReadsBackWithItsEdits) {
  atmos_view::PlanetParams p;
  p.planet = "mars";
  p.density_scale = 0.5;
  p.ground_albedo = 0.3;
  p.thickness_m = 90e3;
  p.constituents.resize(2);
  p.constituents[1].phase_g = 0.8;
  const fs::path path = atmos_test::scratch_directory("view") / "saved-mars.json";
  atmos_view::save_planet(p, path.string());
  const atmos::Atmosphere want = atmos_view::make_atmosphere(p);
  const atmos::Atmosphere got = atmos::load_atmosphere(path.string());
  EXPECT_EQ(got.top_radius_m, want.top_radius_m);
  EXPECT_TRUE(got.ground_albedo == want.ground_albedo);
  ASSERT_EQ(got.constituents.size(), want.constituents.size());
  for (size_t i = 0; i < got.constituents.size(); ++i) {
    EXPECT_TRUE(got.constituents[i].scattering == want.constituents[i].scattering) << i;
    EXPECT_TRUE(got.constituents[i].phase == want.constituents[i].phase) << i;
  }
  EXPECT_TRUE(atmos::load_surface(path.string()) == atmos::load_surface("mars"));
  // Loaded again as the viewer's planet, with no edits: the same atmosphere.
  atmos_view::PlanetParams again;
  again.planet = path.string();
  EXPECT_EQ(atmos_view::make_atmosphere(again).top_radius_m, want.top_radius_m);
  p.ground_albedo = 2.0;
  EXPECT_THROW(atmos_view::save_planet(p, (path.parent_path() / "unsaved.json").string()), atmos::Error);
  EXPECT_FALSE(fs::exists(path.parent_path() / "unsaved.json"));
}

TEST(ViewFlight, ScriptsGiveTheInputOfEachFrame) {
  const fs::path path = atmos_test::scratch_directory("view") / "script.json";
  std::ofstream(path) << R"({"events": [
      {"frame": 2, "frames": 3, "key": "W"},
      {"frame": 3, "frames": 2, "mouse": [4, -2]},
      {"frame": 6, "key": "3"},
      {"frame": 7, "frames": 4, "slider": "sun_elevation", "from": 30, "to": 0}]})";
  const atmos_view::Script script = atmos_view::Script::read(path.string());
  EXPECT_FALSE(script.input(1).forward);
  EXPECT_TRUE(script.input(2).forward);
  EXPECT_TRUE(script.input(4).forward);
  EXPECT_FALSE(script.input(5).forward);
  EXPECT_EQ(script.input(3).look_dx, 4.0);
  EXPECT_EQ(script.input(5).look_dx, 0.0);
  EXPECT_EQ(script.input(6).jump, 3);
  EXPECT_FALSE(script.dragging(6));
  EXPECT_TRUE(script.dragging(10));
  EXPECT_EQ(script.length(), 11);
}

#endif  // ATMOS_VIEWER

}  // namespace
