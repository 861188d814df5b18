// The dusty Mars sky ("mars": dust of optical depth 0.5 whose forward lobe
// narrows towards the blue, g 0.934 at 388 nm to 0.863 at 800 nm), tables
// against the brute-force reference: the case the delta-M scaled multiple
// scattering exists for (delta_scaled_params, physics/parameters.hpp).
//
// Three wavelengths, default table sizes, 6 orders, the observer on the
// ground, 72 directions (6 elevations x 12 azimuths) minus those within 3°
// of the sun, 20000 reference paths each. Measured, sRGB channels, RMS
// within / beyond 20° of the sun (worst):
//   sun 60°:  6.6 % /  9.2 %  (18 %)
//   sun 10°: 20.7 % /  8.4 %  (31 %)
//   sun  2°: 26.7 % / 10.4 %  (39 %)
// What is left is the delta-M approximation itself (Wiscombe 1977): the light scattered into the truncated
// forward peak is carried on in its direction. On the sun's side by day the
// tables are 5-15 % too dark (the light forward-scattered along the view
// ray after its scattering towards it, which precompute.cpp leaves out), and
// the glow around the setting sun is too bright within 2° of it and too
// faint 5-15° from it. Bounds: the measurements + 30 %.
//
// The blue sunset: with the sun 2° up, the reference's sky 2° from the sun
// is bluer than red (blue / red 1.28; the tables 1.58), the rest of the sky
// red (0.4-0.6); the tables must show both.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <glm/glm.hpp>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/planet_file.hpp"
#include "reference/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "support/reference_store.hpp"
#include "figures.hpp"

namespace {

struct MarsSkyError {
  double near_rms = 0.0, far_rms = 0.0, worst = 0.0;
  glm::dvec3 table_at_sun{0.0}, reference_at_sun{0.0};  // 2° above the sun, sRGB
};

MarsSkyError mars_sky_error(const atmos::Atmosphere& mars, const atmos::SkyModel& model, double sun_elevation) {
  const glm::dvec3 observer = atmos::observer_position(mars, 0.0);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(180.0, sun_elevation);
  std::vector<glm::dvec3> views;
  for (double elevation : {3.0, 8.0, 15.0, 30.0, 60.0, 85.0})
    for (double azimuth : {0.0, 60.0, 120.0, 150.0, 165.0, 172.0, 180.0, 188.0, 195.0, 210.0, 240.0, 300.0}) {
      const glm::dvec3 v = atmos::direction_from_azimuth_elevation(azimuth, elevation);
      if (glm::dot(v, sun) < std::cos(glm::radians(3.0))) views.push_back(v);
    }
  views.push_back(atmos::direction_from_azimuth_elevation(180.0, sun_elevation + 2.0));
  const std::vector<glm::dvec3> weights = atmos::spectral_to_srgb_weights(mars.wavelengths_nm);
  const size_t n = views.size();
  std::vector<glm::dvec3> table(n), reference(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    table[i] = model.to_srgb(model.radiance(observer, views[i], sun, false));
    atmos::ReferenceOptions o;
    o.paths = 20000;
    o.scattering_orders = 6;
    o.seed = 700 + i;
    const atmos::ReferenceResult r = atmos_test::oracle::reference_radiance(mars, observer, views[i], sun, o);
    for (size_t l = 0; l < r.radiance.size(); ++l) reference[i] += weights[l] * r.radiance[l];
  });
  MarsSkyError out;
  double near_sq = 0.0, far_sq = 0.0;
  int near_n = 0, far_n = 0;
  for (size_t i = 0; i + 1 < n; ++i) {
    const bool near = glm::dot(views[i], sun) > std::cos(glm::radians(20.0));
    for (int c = 0; c < 3; ++c) {
      const double e = (table[i][c] - reference[i][c]) / reference[i][c];
      (near ? near_sq : far_sq) += e * e;
      ++(near ? near_n : far_n);
      out.worst = std::max(out.worst, std::abs(e));
    }
  }
  out.near_rms = std::sqrt(near_sq / std::max(near_n, 1));
  out.far_rms = std::sqrt(far_sq / std::max(far_n, 1));
  out.table_at_sun = table[n - 1];
  out.reference_at_sun = reference[n - 1];
  std::printf("mars, sun %4.1f deg: within 20 deg of the sun RMS %5.1f %%, beyond %5.1f %%, worst %5.1f %%; "
              "2 deg above the sun blue / red %.2f (reference %.2f)\n",
              sun_elevation, 100 * out.near_rms, 100 * out.far_rms, 100 * out.worst,
              out.table_at_sun.z / out.table_at_sun.x, out.reference_at_sun.z / out.reference_at_sun.x);
  std::fflush(stdout);
  char sun_text[32];
  std::snprintf(sun_text, sizeof sun_text, "sun %g deg", sun_elevation);
  atmos_test::record_figure(std::string("RMS within 20 deg of the sun, ") + sun_text, 100.0 * out.near_rms, "%", "");
  atmos_test::record_figure(std::string("RMS beyond 20 deg of the sun, ") + sun_text, 100.0 * out.far_rms, "%", "");
  atmos_test::record_figure(std::string("max, ") + sun_text, 100.0 * out.worst, "%", "");
  atmos_test::record_figure(std::string("blue / red 2 deg above the sun, tables, ") + sun_text,
                            out.table_at_sun.z / out.table_at_sun.x, "", "");
  atmos_test::record_figure(std::string("blue / red 2 deg above the sun, reference, ") + sun_text,
                            out.reference_at_sun.z / out.reference_at_sun.x, "", "");
  return out;
}

TEST(MarsAccuracy, DustySkyAgainstTheReference) {
  const atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  atmos::PrecomputeOptions options;
  options.scattering_orders = 6;
  const atmos::Tables tables = atmos::precompute_tables(mars, options);
  const atmos::SkyModel model(mars, tables);
  struct Bound {
    double sun, near, far, worst;
  };
  for (const Bound& b : {Bound{60.0, 0.086, 0.12, 0.24}, Bound{10.0, 0.27, 0.11, 0.41},
                         Bound{2.0, 0.35, 0.135, 0.51}}) {
    const MarsSkyError e = mars_sky_error(mars, model, b.sun);
    EXPECT_LT(e.near_rms, b.near) << b.sun;
    EXPECT_LT(e.far_rms, b.far) << b.sun;
    EXPECT_LT(e.worst, b.worst) << b.sun;
    if (b.sun == 2.0) {
      EXPECT_GT(e.reference_at_sun.z, 1.1 * e.reference_at_sun.x);  // the physics: a blue sunset
      EXPECT_GT(e.table_at_sun.z, 1.1 * e.table_at_sun.x);          // the tables show it
    }
  }
}

}  // namespace
