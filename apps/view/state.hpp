// atmos view: what the viewer's panel edits and its recorded flights hold —
// the planet and its tables (a change means new tables), the look of the
// image (applied from the next frame), and a frame of a flight.
#pragma once

#include <glm/vec3.hpp>

#include <optional>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/post.hpp"
#include "atmos/tables.hpp"
#include "flight.hpp"

namespace atmos_view {

// Changes to one constituent of the planet file (by its place in the
// file's list); none: the file's values.
struct ConstituentEdit {
  std::optional<double> scattering_scale;  // multiplies its scattering coefficients, [0, 100]
  std::optional<double> absorption_scale;  // multiplies its absorption coefficients, [0, 100]
  std::optional<double> scale_height_m;    // of an exponential density profile, [10 m, 1000 km]
  // The asymmetry parameter of its phase function (Henyey-Greenstein,
  // Cornette-Shanks, or the forward lobe of a double Henyey-Greenstein),
  // constant over wavelength, |g| < 0.999.
  std::optional<double> phase_g;

  bool operator==(const ConstituentEdit&) const = default;
};

// The planet and how its tables are computed: any change needs new tables.
struct PlanetParams {
  std::string planet = "earth";  // a preset or a planet file
  int wavelengths = 0;           // 0: the planet file's; else 3..48 (atmos::spectral_wavelengths)
  int orders = 4;                // scattering orders, 1..100
  double density_scale = 1.0;    // (0, 10000] (atmos::scale_density)
  std::string solar;             // "": the planet file's; "table" or "blackbody:T"
  std::string table_sizes = "default";  // "default" or "small" (the CLI's --tables)
  // Values replacing the planet file's; none: the file's.
  std::optional<double> bottom_radius_m;  // the ground's radius, m
  std::optional<double> thickness_m;      // top radius - bottom radius, m
  std::optional<double> ground_albedo;    // a constant over wavelength, [0, 1]
  std::vector<ConstituentEdit> constituents;  // by the file's order; fewer than it has: the rest unchanged

  bool operator==(const PlanetParams&) const = default;
};

// The atmosphere of `params`, validated. Throws atmos::Error with one line
// naming the first bad value (an unreadable planet file, a density scale or
// radius out of range, an albedo outside [0, 1], ...).
atmos::Atmosphere make_atmosphere(const PlanetParams& params);
// Writes the planet of `params` (its planet file with the edits applied,
// and the file's surface) as a planet file (atmos::write_planet_file) that
// reads back as that planet. atmos::Error as make_atmosphere, or when the
// file cannot be written.
void save_planet(const PlanetParams& params, const std::string& path);
// The precomputation options of `params` (fixed orders, the table sizes).
atmos::PrecomputeOptions make_precompute_options(const PlanetParams& params, bool ground_albedo_response);

// The look of the image: post-processing, sky content, camera lens.
struct LookSettings {
  double exposure_ev = 13.0;  // EV100 without auto exposure
  bool auto_exposure = false;
  double compensation_ev = 0.0;  // with auto exposure
  atmos::ToneMapping tone_mapping = atmos::ToneMapping::exp;
  double bloom = 0.0;  // strength, [0, 1]
  bool stars = false;  // also by day (always drawn with the sun below the horizon)
  // A moon of the Moon's apparent size (0.26 degrees) at this angular
  // separation from the sun's centre, on the side of the local zenith: an
  // eclipse when the separation is below the sum of the two radii.
  bool moon = false;
  double moon_separation_deg = 0.1;
  double fov_deg = 60.0;  // vertical field of view, (1, 150)

  bool operator==(const LookSettings&) const = default;
};

// One frame of a recorded flight: what is on screen.
struct FrameRecord {
  double time_s = 0.0;  // since the first frame
  CameraPose pose;
  glm::dvec3 sun{0, 0, 1};  // towards the sun, planet frame
  LookSettings look;
  PlanetParams planet;  // the planet of the tables on screen
  // The Moon of `atmos view --date`: its centre, planet-centred m (none:
  // no Moon of a date; the look's moon is placed apart).
  std::optional<glm::dvec3> moon_of_date_m;
  double frame_ms = 0.0;  // how long the viewer took to draw it (informative; a replay ignores it)
};

struct FlightRecord {
  bool globe = true;           // the ground: the globe or the analytic sphere
  bool planet_albedo = false;  // the air over the planet file's albedo, not the globe's regional albedo
  int width = 0, height = 0;   // pixels
  std::vector<FrameRecord> frames;
};

// JSON (docs/viewer.md, Recorded flights). Numbers are written with enough
// digits to be read back bit for bit, so that a replay renders exactly the
// recorded views. read_flight throws atmos::Error naming the file and the
// first missing or bad field.
void write_flight(const FlightRecord& record, const std::string& path);
FlightRecord read_flight(const std::string& path);

}  // namespace atmos_view
