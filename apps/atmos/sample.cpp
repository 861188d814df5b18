// atmos sample: the radiance reaching the viewpoint from directions read as
// CSV, from the tables (atmos::SkyModel, the functions the renderer runs) or
// from the brute-force Monte Carlo reference (--reference), under the same
// light options as `atmos render`.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/sky.hpp"
#include "commands.hpp"
#include "reference/reference.hpp"

namespace atmos_cli {

namespace {

struct SampleOptions {
  PlanetOptions planet;
  TableOptions tables;
  CacheOptions cache;
  ViewpointOptions viewpoint;
  SunOptions sun;
  DateOptions date;
  MoonOptions moons;
  std::string directions;
  bool reference = false;
  int paths = 20000;
  bool sun_disc = false;
};

// The linear limb-darkening coefficient of the sun of the tables
// (src/physics/eclipse.glsl: u = 3/5, Eddington's grey atmosphere), given to
// the reference when moons cover part of the disc. Without moons it changes
// no expected value (the reference never sees the disc itself), only the
// variance, and the reference keeps its uniform disc.
constexpr double kSunLimbDarkeningU = 0.6;

std::vector<std::pair<double, double>> read_directions(std::istream& in, const std::string& origin) {
  std::string line;
  int number = 0;
  bool header = false;
  std::vector<std::pair<double, double>> out;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      if (line.find("azimuth_deg") != 0 || line.find("elevation_deg") == std::string::npos)
        throw UsageError(origin + ":" + std::to_string(number) + ": expected the header azimuth_deg,elevation_deg");
      header = true;
      continue;
    }
    try {
      const auto v = parse_numbers(line, 2, "direction", "azimuth_deg,elevation_deg");
      if (v[1] < -90.0 || v[1] > 90.0) throw UsageError("elevation outside [-90, 90]");
      out.emplace_back(v[0], v[1]);
    } catch (const UsageError& e) {
      throw UsageError(origin + ":" + std::to_string(number) + ": " + e.what());
    }
  }
  if (!header) throw UsageError(origin + ": no header line azimuth_deg,elevation_deg");
  return out;
}

int run_sample(const SampleOptions& o) {
  // Every option first, so that a bad value is reported before stdin is read.
  o.planet.validate();
  o.tables.validate();
  if (o.reference) (void)o.tables.fixed_orders();
  if (o.paths < 2 || o.paths > 100000000)
    throw UsageError("--paths must be in [2, 1e8], got " + std::to_string(o.paths));
  const atmos::Atmosphere atmosphere = o.planet.atmosphere();
  const Viewpoint viewpoint = o.viewpoint.viewpoint(atmosphere);
  const glm::dvec3 sun = o.sun.direction(viewpoint);
  const std::vector<atmos::Moon> moons = o.moons.place(viewpoint, atmosphere);

  std::vector<std::pair<double, double>> directions;
  if (o.directions.empty()) {
    directions = read_directions(std::cin, "stdin");
  } else {
    std::ifstream in(o.directions);
    if (!in) throw atmos::Error("cannot read directions file " + o.directions);
    directions = read_directions(in, o.directions);
  }
  const glm::dvec3& observer = viewpoint.position;
  const auto& w = atmosphere.wavelengths_nm;
  // Three wavelengths: the tables' channels are the radiance at them, printed
  // as radiance_<λ>nm columns. Spectral: the tables hold colour; the
  // reference gives every wavelength, converted with the same CIE weights.
  const bool three = w.size() == 3;
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(w);
  auto srgb_of_spectrum = [&](const std::vector<double>& values) {
    glm::dvec3 rgb(0.0);
    for (size_t i = 0; i < values.size(); ++i) rgb += weights[i] * values[i];
    return rgb;
  };

  std::optional<LoadedTables> loaded;
  std::unique_ptr<atmos::SkyModel> model;
  atmos::ReferenceOptions ref;
  ref.paths = o.paths;
  if (!o.reference) {
    loaded = load_tables(o.planet, o.tables, o.cache, false);
    model = std::make_unique<atmos::SkyModel>(atmosphere, loaded->tables);
  } else {
    ref.scattering_orders = o.tables.fixed_orders();
    for (const atmos::Moon& m : moons) ref.moons.push_back({m.centre_m, m.radius_m});
    if (!moons.empty()) ref.sun_limb_darkening_u = kSunLimbDarkeningU;
  }

  std::printf("azimuth_deg,elevation_deg,luminance_cd_m2,red,green,blue");
  if (three)
    for (double l : w) std::printf(",radiance_%gnm", l);
  std::printf("\n");
  for (const auto& [az, el] : directions) {
    const glm::dvec3 view = viewpoint.local * atmos::direction_from_azimuth_elevation(az, el);
    glm::dvec3 rgb, spectral(0.0);
    if (o.reference) {
      const atmos::ReferenceResult r = atmos::reference_radiance(atmosphere, observer, view, sun, ref);
      rgb = srgb_of_spectrum(r.radiance);
      if (three) spectral = {r.radiance[0], r.radiance[1], r.radiance[2]};
    } else {
      const glm::dvec3 channels = model->radiance(observer, view, sun, o.sun_disc, moons);
      rgb = model->to_srgb(channels);
      spectral = channels;
    }
    std::printf("%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", az, el, atmos::srgb_luminance(rgb), rgb.x, rgb.y, rgb.z);
    if (three) std::printf(",%.6g,%.6g,%.6g", spectral.x, spectral.y, spectral.z);
    std::printf("\n");
  }
  // With --date, the sun's place of the date closes the output.
  auto print_sun_of_date = [&] {
    if (o.date.given())
      std::printf("# sun_azimuth_deg=%.6f sun_elevation_deg=%.6f\n", o.sun.azimuth, o.sun.elevation);
  };
  // Irradiance on a horizontal surface at the observer, as a trailing comment.
  if (!o.reference && !moons.empty() &&
      atmos::moons_may_eclipse(moons, sun, atmosphere.top_radius_m, atmosphere.sun_angular_radius_rad)) {
    // SkyModel::horizontal_irradiance has no eclipse: rather than the light
    // of the uneclipsed sun, no figure.
    std::printf("# horizontal irradiance: not computed from the tables with --moon (use --reference)\n");
    print_sun_of_date();
    return 0;
  }
  glm::dvec3 sun_rgb, sky_rgb, sun_e(0.0), sky_e(0.0);
  if (o.reference) {
    atmos::ReferenceOptions direct = ref;
    direct.scattering_orders = 1;
    const atmos::ReferenceResult total = atmos::reference_horizontal_irradiance(atmosphere, observer, sun, ref);
    const atmos::ReferenceResult sun_only = atmos::reference_horizontal_irradiance(atmosphere, observer, sun, direct);
    std::vector<double> sky(w.size());
    for (size_t i = 0; i < w.size(); ++i) sky[i] = total.radiance[i] - sun_only.radiance[i];
    sun_rgb = srgb_of_spectrum(sun_only.radiance);
    sky_rgb = srgb_of_spectrum(sky);
    if (three) {
      sun_e = {sun_only.radiance[0], sun_only.radiance[1], sun_only.radiance[2]};
      sky_e = {sky[0], sky[1], sky[2]};
    }
  } else {
    model->horizontal_irradiance(observer, sun, sun_e, sky_e);
    sun_rgb = model->to_srgb(sun_e);
    sky_rgb = model->to_srgb(sky_e);
  }
  const double sun_lux = atmos::srgb_luminance(sun_rgb), sky_lux = atmos::srgb_luminance(sky_rgb);
  std::printf("# horizontal_illuminance_lux=%.6g sun_lux=%.6g sky_lux=%.6g", sun_lux + sky_lux, sun_lux, sky_lux);
  if (three)
    std::printf(" irradiance_W_m2_nm=%.6g;%.6g;%.6g", sun_e.x + sky_e.x, sun_e.y + sky_e.y, sun_e.z + sky_e.z);
  std::printf("\n");
  print_sun_of_date();
  return 0;
}

}  // namespace

Command add_sample_command(CLI::App& app) {
  auto o = std::make_shared<SampleOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sample",
      "Radiance reaching the viewpoint from directions read as CSV (header azimuth_deg,elevation_deg; degrees in "
      "the viewpoint's frame, as --look) from stdin or --directions. Prints azimuth_deg,elevation_deg, "
      "luminance_cd_m2, red, green, blue (linear sRGB, cd/m2) and, with 3 wavelengths, radiance_<nm>nm (W m-2 "
      "sr-1 nm-1) per direction, then a comment with the irradiance on a horizontal surface there. The light of "
      "the atmosphere and the ground, as `atmos render` draws it without the star field");
  o->planet.add(*cmd);
  o->tables.add(*cmd);
  o->cache.add(*cmd);
  o->viewpoint.add(*cmd);
  o->sun.add(*cmd);
  o->date.add(*cmd);
  o->moons.add(*cmd);
  cmd->add_option("--directions", o->directions, "CSV file of directions (default: stdin)")->type_name("FILE");
  auto* reference = cmd->add_flag("--reference", o->reference,
                                  "Compute with the brute-force Monte Carlo reference instead of the tables (slow; "
                                  "needs --orders K, not auto; the table and cache options are then unused)");
  cmd->add_option("--paths", o->paths, "Monte Carlo paths per direction with --reference, in [2, 1e8]")
      ->type_name("N")
      ->capture_default_str()
      ->needs(reference);
  cmd->add_flag("--sun-disc", o->sun_disc,
                "Add the sun disc (limb-darkened, attenuated, hidden where a moon covers it) to the radiance of "
                "the directions that see it; the tables only (the reference never includes it)")
      ->excludes(reference);
  return {cmd, [o] {
            o->date.apply(o->viewpoint, o->sun, o->moons);
            return run_sample(*o);
          }};
}

}  // namespace atmos_cli
