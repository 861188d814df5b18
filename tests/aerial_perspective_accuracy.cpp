// The engine plugin's aerial perspective (the light scattered into a view
// ray between the camera and a surface point, and the transmittance of that
// segment) against the independent brute-force reference
// (reference_radiance_to_point, reference_transmittance).
//
// Both ways the plugin computes it (gpu::aerial_perspective_cpu): the
// aerial-perspective volume (use_volume, what the pass uses for cameras in
// the atmosphere: composite.glsl, compute_aerial_perspective_column /
// aerial_perspective_lookup) and the exact difference of two 4D table
// lookups (scattering_to_point, Bruneton's method).
//
// Configurations: the clear-sky Earth of clear_sky_earth.hpp (3
// wavelengths, default table sizes, 4 orders; the reference counts the same K = 4 interactions), cameras at 2 m,
// 300 m, 3 km and 12 km, the sun at 60°, 20°, 5°, 0° and -3°; view rays at
// elevations -30°, -10°, -3°, -1°, 0°, 1°, 3° and 10°, each towards the sun's
// azimuth, 90° from it and away from it; points at 100 m, 1 km, 5 km, 20 km
// and 80 km along them, where they are above the ground sphere and inside
// the atmosphere, and where the rays that go down meet the ground sphere
// (terrain at sea level: 4 m to 71 km away); 408 points per sun.
//
// Error measures, per point and wavelength:
//  - in-scatter (single + multiple): (plugin - reference) / max(reference,
//    floor), floor = 1 % of the sky radiance at the horizon (elevation 0,
//    mean of the three azimuths, reference) for that camera and sun. A
//    viewer sees the in-scatter on top of the surface behind it, whose
//    radiance is of the order of the horizon sky's: an in-scatter error
//    below 1 % of that is below the eye's contrast threshold, however large
//    relative to the tiny in-scatter of a few metres of air;
//  - transmittance: plugin - reference, absolute (the surface's radiance is
//    multiplied by it: an absolute error dT is an error dT relative to the
//    surface).
//
// Tolerances (the volume; measured values in the comment of the test). The
// exact two-lookup method is printed and not asserted (see the note at the
// test).
//
// Environment: ATMOS_AP_PATHS sets the reference's paths per point by day
// (default 3000; 4x that at and below the horizon); ATMOS_ACCURACY_VERBOSE
// prints every point; the disabled DiagnoseOneCase measures one camera and
// sun (ATMOS_AP_CASE="altitude_m,sun_elevation_deg"), and with
// ATMOS_AP_SINGLE=1 single scattering only (reference with K = 1).
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "atmos/planet_file.hpp"
#include "reference/reference.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "support/reference_store.hpp"
#include "clear_sky_earth.hpp"
#include "figures.hpp"
#include "gpu/atmosphere_pass.hpp"

namespace {

constexpr double kDeg = M_PI / 180.0;

struct CameraCase {
  const char* name;
  double altitude_m;
};
const CameraCase kCameras[] = {{"2 m", 2.0}, {"300 m", 300.0}, {"3 km", 3e3}, {"12 km", 12e3}};
const double kSunElevations[] = {60.0, 20.0, 5.0, 0.0, -3.0};
const double kViewElevations[] = {-30.0, -10.0, -3.0, -1.0, 0.0, 1.0, 3.0, 10.0};
const double kRelativeAzimuths[] = {0.0, 90.0, 180.0};
const double kDistances[] = {100.0, 1e3, 5e3, 20e3, 80e3};
constexpr size_t kGround = std::size(kDistances);  // the point where the ray meets the ground sphere
constexpr size_t kDistanceClasses = kGround + 1;
constexpr double kSunAzimuth = 30.0;
constexpr double kFloorFraction = 0.01;

// Reference paths per point by day; with the sun at or below the horizon 4x
// (twilight light comes from few, long paths). ATMOS_AP_PATHS overrides.
int day_paths() {
  const char* v = std::getenv("ATMOS_AP_PATHS");
  return v ? std::max(100, std::atoi(v)) : 3000;
}

struct Point {
  double view_elevation, relative_azimuth, distance;
  size_t distance_index;  // into kDistances, or kGround
  glm::dvec3 offset;
};

// The errors of one method over a set of (point, wavelength) values.
struct Errors {
  double sum_sq = 0.0, worst = 0.0, worst_excess = 0.0;  // in-scatter, relative to max(reference, floor)
  double worst_transmittance = 0.0;                      // absolute
  int count = 0;
  void add(double relative, double noise, double transmittance) {
    sum_sq += relative * relative;
    worst = std::max(worst, std::abs(relative));
    worst_excess = std::max(worst_excess, std::abs(relative) - 3.0 * noise);
    worst_transmittance = std::max(worst_transmittance, std::abs(transmittance));
    ++count;
  }
  void merge(const Errors& o) {
    sum_sq += o.sum_sq;
    worst = std::max(worst, o.worst);
    worst_excess = std::max(worst_excess, o.worst_excess);
    worst_transmittance = std::max(worst_transmittance, o.worst_transmittance);
    count += o.count;
  }
  double rms() const { return std::sqrt(sum_sq / std::max(count, 1)); }
};

struct CaseResult {
  Errors volume, exact, noise_only;
  // Per distance (index into kDistances), for the summary.
  Errors volume_by_distance[kDistanceClasses], exact_by_distance[kDistanceClasses];
};

class AerialPerspective : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    earth_ = new atmos::Atmosphere(clear_sky_earth());
    const atmos::PrecomputeOptions options;  // default sizes, 4 orders
    const char* cache = std::getenv("ATMOS_CACHE_DIR");
    tables_ = new atmos::Tables(cache ? atmos::load_or_precompute_tables(*earth_, options, cache).tables
                                      : atmos::precompute_tables(*earth_, options));
  }
  static void TearDownTestSuite() {
    delete tables_;
    delete earth_;
  }

  static std::vector<Point> points(const glm::dvec3& camera) {
    std::vector<Point> out;
    const double rb = earth_->bottom_radius_m, rt = earth_->top_radius_m;
    for (double el : kViewElevations)
      for (double az : kRelativeAzimuths)
        for (size_t k = 0; k < kDistanceClasses; ++k) {
          const glm::dvec3 d = atmos::direction_from_azimuth_elevation(kSunAzimuth + az, el);
          double t = 0.0;
          if (k == kGround) {
            // Where a ray that goes down meets the ground sphere (terrain
            // at sea level), if it does: the root of |camera + t d| = Rb.
            const double b = glm::dot(camera, d);
            const double disc = b * b - (glm::dot(camera, camera) - rb * rb);
            if (b >= 0.0 || disc < 0.0) continue;
            t = -b - std::sqrt(disc);
          } else {
            t = kDistances[k];
          }
          const glm::dvec3 p = camera + t * d;
          const double r = glm::length(p);
          if (r < rb - 1e-4 || r > rt) continue;
          // The segment stays above the ground (its lowest point).
          const double tp = std::clamp(-glm::dot(camera, d), 0.0, t);
          if (glm::length(camera + tp * d) < rb - 1e-4) continue;
          out.push_back({el, az, t, k, t * d});
        }
    return out;
  }

  // Measures one camera and sun; prints one line (every point with
  // ATMOS_ACCURACY_VERBOSE).
  static CaseResult measure(const CameraCase& camera_case, double sun_elevation) {
    const atmos::Atmosphere& a = *earth_;
    const size_t n = a.wavelengths_nm.size();
    const glm::dvec3 camera = atmos::observer_position(a, camera_case.altitude_m);
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(kSunAzimuth, sun_elevation);
    const std::vector<Point> pts = points(camera);
    std::vector<glm::dvec3> offsets;
    for (const Point& p : pts) offsets.push_back(p.offset);
    const auto volume = atmos::gpu::aerial_perspective_cpu(a, *tables_, camera, sun, offsets, true);
    const auto exact = atmos::gpu::aerial_perspective_cpu(a, *tables_, camera, sun, offsets, false);

    // Diagnostic: ATMOS_AP_SINGLE=1 compares single scattering only (the
    // reference with K = 1, the plugin's `single`).
    const bool single_only = std::getenv("ATMOS_AP_SINGLE") != nullptr;
    atmos::ReferenceOptions options;
    options.scattering_orders = single_only ? 1 : tables_->scattering_orders;
    options.paths = day_paths() * (sun_elevation <= 0.0 ? 4 : 1);
    // The floor: 1 % of the horizon sky's radiance (mean over the azimuths).
    std::vector<double> floor(n, 0.0);
    {
      std::vector<atmos::ReferenceResult> horizon(std::size(kRelativeAzimuths));
      tbb::parallel_for(size_t(0), horizon.size(), [&](size_t i) {
        atmos::ReferenceOptions o = options;
        o.seed = 500 + i;
        horizon[i] = atmos_test::oracle::reference_radiance(
            a, camera, atmos::direction_from_azimuth_elevation(kSunAzimuth + kRelativeAzimuths[i], 0.0), sun, o);
      });
      for (const auto& h : horizon)
        for (size_t l = 0; l < n; ++l) floor[l] += kFloorFraction * h.radiance[l] / double(horizon.size());
    }
    std::vector<atmos::ReferenceResult> reference(pts.size());
    std::vector<std::vector<double>> transmittance(pts.size());
    tbb::parallel_for(size_t(0), pts.size(), [&](size_t i) {
      atmos::ReferenceOptions o = options;
      o.seed = 1000 + i;
      reference[i] = atmos_test::oracle::reference_radiance_to_point(a, camera, camera + pts[i].offset, sun, o);
      transmittance[i] = atmos_test::oracle::reference_transmittance(a, camera, camera + pts[i].offset);
    });

    CaseResult result;
    const bool verbose = std::getenv("ATMOS_ACCURACY_VERBOSE") != nullptr;
    for (size_t i = 0; i < pts.size(); ++i) {
      const size_t di = pts[i].distance_index;
      for (size_t l = 0; l < n; ++l) {
        const double ref = reference[i].radiance[l];
        const double scale = std::max(ref, floor[l]);
        const double noise = reference[i].standard_error[l] / scale;
        const double v = volume[i].single[int(l)] + (single_only ? 0.0 : volume[i].multiple[int(l)]);
        const double x = exact[i].single[int(l)] + (single_only ? 0.0 : exact[i].multiple[int(l)]);
        EXPECT_TRUE(std::isfinite(v) && std::isfinite(x) && std::isfinite(volume[i].transmittance[int(l)]) &&
                    std::isfinite(exact[i].transmittance[int(l)]));
        const double ev = (v - ref) / scale, ex = (x - ref) / scale;
        const double tv = volume[i].transmittance[int(l)] - transmittance[i][l];
        const double tx = exact[i].transmittance[int(l)] - transmittance[i][l];
        result.volume.add(ev, noise, tv);
        result.exact.add(ex, noise, tx);
        result.noise_only.add(noise, 0.0, 0.0);
        result.volume_by_distance[di].add(ev, noise, tv);
        result.exact_by_distance[di].add(ex, noise, tx);
        if (verbose)
          std::printf("    el %5.1f az-sun %5.1f t %7.0f%s  %3.0f nm  ref %10.4g +- %5.2f %% (floor %9.3g)  volume %+7.2f %%"
                      "  exact %+7.2f %%  T %.4f  dT volume %+.4f exact %+.4f\n",
                      pts[i].view_elevation, pts[i].relative_azimuth, pts[i].distance, di == kGround ? "g" : " ",
                      a.wavelengths_nm[l], ref,
                      100.0 * reference[i].standard_error[l] / std::max(ref, 1e-300), floor[l], 100.0 * ev,
                      100.0 * ex, transmittance[i][l], tv, tx);
      }
    }
    std::printf("%-6s sun %+5.1f | volume RMS %5.2f %% max %6.2f %% (beyond 3 sigma %5.2f %%) dT %.4f | exact RMS %6.2f %% "
                "max %7.2f %% dT %.4f | noise RMS %4.2f %% | %3zu points, %d paths\n",
                camera_case.name, sun_elevation, 100.0 * result.volume.rms(), 100.0 * result.volume.worst,
                100.0 * std::max(0.0, result.volume.worst_excess), result.volume.worst_transmittance,
                100.0 * result.exact.rms(), 100.0 * result.exact.worst, result.exact.worst_transmittance,
                100.0 * result.noise_only.rms(), pts.size(), options.paths);
    std::fflush(stdout);
    // The bounds the calling test asserts on the volume (see the tests).
    const bool haze = std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) ==
                      "ContinentalHazeByDay";
    const char* rms_bound = haze                  ? "RMS <= 7 %"
                            : sun_elevation >= 5.0 ? "RMS <= 2.5 %"
                            : sun_elevation >= 0.0 ? "RMS <= 3 %"
                                                   : "RMS <= 8 %";
    const char* excess_bound = haze                  ? "<= 25 %"
                               : sun_elevation >= 5.0 ? "<= 10 %"
                               : sun_elevation >= 0.0 ? "<= 12 %"
                                                      : "<= 40 %";
    char config[64];
    std::snprintf(config, sizeof config, "%s, sun %+.1f deg", camera_case.name, sun_elevation);
    atmos_test::record_figure(std::string("volume RMS, ") + config, 100.0 * result.volume.rms(), "%", rms_bound);
    atmos_test::record_figure(std::string("volume max, ") + config, 100.0 * result.volume.worst, "%", "");
    atmos_test::record_figure(std::string("volume max beyond 3 sigma, ") + config,
                              100.0 * std::max(0.0, result.volume.worst_excess), "%", excess_bound);
    atmos_test::record_figure(std::string("volume max transmittance error, ") + config,
                              result.volume.worst_transmittance, "", "<= 0.012");
    atmos_test::record_figure(std::string("exact RMS, ") + config, 100.0 * result.exact.rms(), "%", "");
    atmos_test::record_figure(std::string("reference noise RMS, ") + config, 100.0 * result.noise_only.rms(), "%",
                              "");
    return result;
  }

  static atmos::Atmosphere* earth_;
  static atmos::Tables* tables_;
};

atmos::Atmosphere* AerialPerspective::earth_ = nullptr;
atmos::Tables* AerialPerspective::tables_ = nullptr;

// A diagnostic, not a check: with --gtest_also_run_disabled_tests and
// ATMOS_AP_CASE="altitude_m,sun_elevation_deg" it measures one camera and
// sun (every point with ATMOS_ACCURACY_VERBOSE=1).
TEST_F(AerialPerspective, DISABLED_DiagnoseOneCase) {
  const char* spec = std::getenv("ATMOS_AP_CASE");
  ASSERT_NE(spec, nullptr) << "set ATMOS_AP_CASE=altitude_m,sun_elevation_deg";
  double altitude = 0.0, sun = 0.0;
  ASSERT_EQ(std::sscanf(spec, "%lf,%lf", &altitude, &sun), 2);
  measure(CameraCase{"case", altitude}, sun);
}

// Tolerances on the volume, per camera and sun (in-scatter relative to
// max(reference, 1 % of the horizon sky) over all points and wavelengths;
// "beyond 3 sigma": max |error| - 3 x the reference's standard error, so
// that the bound holds whatever the path count; transmittance absolute).
//
// Measured (3000 paths by day, 12000 at and below the horizon; the test
// prints and records them):
//  - sun 60°, 20°, 5°: RMS 0.9-1.4 %, max 3.5-8.5 % (beyond 3 sigma
//    2.3-7.3 %). The largest errors are the volume's resolution in
//    distance: 32 slices quadratic up to ap_t_far (570 km from 2 m: the
//    first at 0.56, 2.2, 5.0 km), the light interpolated linearly in t
//    between them, a few per cent off where the integrand changes fast
//    within a slice: 10° up through the haze from 2 m (-3.5 % at 1 km),
//    30° down from 12 km into the haze (+6.5 %, dT -0.006 at 20 km, between
//    the slices at 14.9 and 23.3 km);
//  - sun 0°: RMS 0.7-2.1 %, max 5.7-9.5 % (beyond 3 sigma 3.0-8.8 %); the
//    worst: from 300 m, 10° down towards the sun, the ground 1.7 km away,
//    -9.5 % at 680 nm (the exact method -0.7 %): the sunlight on the lowest
//    air changes fast with the sun on the horizon;
//  - sun -3°: RMS 3.6-6.2 %, max 22-38 % (beyond 3 sigma 15-30 %), mostly
//    the tables', not the volume's: the exact two-lookup method has nearly
//    the same errors at the same points (RMS 3.5-6.1 %, max 22-38 %). The
//    cameras up to 3 km are in the planet's shadow, where the light near
//    them is all multiple scattering, which both take from the 4D
//    multiple-scattering table: 10-35 % too bright looking towards the set
//    sun (550 nm worst), ~5 % too dark away from it. Single scattering
//    alone (ATMOS_AP_SINGLE=1) shows the volume's own twilight error: where
//    a view ray crosses the terminator within a slice (80 km away, from
//    3 km, 1° up towards the sun, between the slices at 74 and 90 km), up
//    to +90 % of the floor, while the exact method, which integrates single
//    scattering along the segment at low sun, stays within 3.6 %;
//  - |dT| <= 0.0076 everywhere (12 km, 30° down).
// Bounds: sun >= 5° RMS 2.5 %, beyond 3 sigma 10 %; sun 0° RMS 3 %, beyond
// 3 sigma 12 %; sun -3° RMS 8 %, beyond 3 sigma 40 %, and RMS at most
// 1.2 x the exact method's + 0.5 % (the volume adds little to the tables'
// own error); |dT| 0.012. A volume whose multiple scattering is 30-80 % low
// near the camera below the horizon (as when it is not continued beyond the
// ground sphere, compute_aerial_perspective_column) exceeds them.
//
// The exact two-lookup method is printed, not asserted: for short segments
// it subtracts two large, interpolated table values; from 2 m with the sun
// at 20° it is 20-60 % too bright 100 m away towards the sun (the aerosol's
// forward peak; 43 % of the floor), and its transmittance is 0.018 off
// along 80 km at the horizon. Farther away it is as good as the volume or
// better.
TEST_F(AerialPerspective, VolumeMatchesReference) {
  Errors volume_all, exact_all;
  // [sun >= 0, sun < 0][distance class]
  Errors volume_by_distance[2][kDistanceClasses], exact_by_distance[2][kDistanceClasses];
  for (const CameraCase& camera : kCameras)
    for (double sun : kSunElevations) {
      const CaseResult r = measure(camera, sun);
      const bool day = sun >= 0.0;
      const double rms_bound = sun >= 5.0 ? 0.025 : day ? 0.03 : 0.08;
      const double excess_bound = sun >= 5.0 ? 0.10 : day ? 0.12 : 0.40;
      EXPECT_LE(r.volume.rms(), rms_bound) << camera.name << ", sun " << sun;
      EXPECT_LE(r.volume.worst_excess, excess_bound) << camera.name << ", sun " << sun;
      EXPECT_LE(r.volume.worst_transmittance, 0.012) << camera.name << ", sun " << sun;
      if (!day) {
        EXPECT_LE(r.volume.rms(), 1.2 * r.exact.rms() + 0.005) << camera.name << ", sun " << sun;
      }
      volume_all.merge(r.volume);
      exact_all.merge(r.exact);
      for (size_t d = 0; d < kDistanceClasses; ++d) {
        volume_by_distance[day ? 0 : 1][d].merge(r.volume_by_distance[d]);
        exact_by_distance[day ? 0 : 1][d].merge(r.exact_by_distance[d]);
      }
    }
  for (int regime = 0; regime < 2; ++regime) {
    std::printf("by distance, sun %s:\n", regime == 0 ? ">= 0 deg" : "-3 deg");
    for (size_t d = 0; d < kDistanceClasses; ++d) {
      const Errors& v = volume_by_distance[regime][d];
      const Errors& x = exact_by_distance[regime][d];
      const std::string name = d == kGround ? "ground" : std::to_string(int(kDistances[d])) + " m";
      std::printf("  %8s | volume RMS %5.2f %% max %6.2f %% dT %.4f | exact RMS %6.2f %% max %7.2f %% dT %.4f\n",
                  name.c_str(), 100.0 * v.rms(), 100.0 * v.worst, v.worst_transmittance, 100.0 * x.rms(),
                  100.0 * x.worst, x.worst_transmittance);
    }
  }
  std::printf("all      | volume RMS %5.2f %% max %6.2f %% dT %.4f | exact RMS %6.2f %% max %7.2f %% dT %.4f\n",
              100.0 * volume_all.rms(), 100.0 * volume_all.worst, volume_all.worst_transmittance,
              100.0 * exact_all.rms(), 100.0 * exact_all.worst, exact_all.worst_transmittance);
  atmos_test::record_figure("volume RMS, all", 100.0 * volume_all.rms(), "%", "");
  atmos_test::record_figure("volume max, all", 100.0 * volume_all.worst, "%", "");
  atmos_test::record_figure("volume max transmittance error, all", volume_all.worst_transmittance, "", "<= 0.012");
  atmos_test::record_figure("exact RMS, all", 100.0 * exact_all.rms(), "%", "");
  atmos_test::record_figure("exact max, all", 100.0 * exact_all.worst, "%", "");
}

// The preset's continental haze, two cameras by day: the volume inherits the
// tables' shortfall of multiple scattering towards the sun's azimuth near
// the horizon (see HazyAccuracy in reference_accuracy.cpp; single
// scattering alone, ATMOS_AP_SINGLE=1, is within 1.5 % RMS from 2 m with the
// sun at 60°). Measured: volume RMS about 5 %. Bounds: RMS 7 %, beyond
// 3 sigma 25 %, |dT| 0.012.
TEST_F(AerialPerspective, ContinentalHazeByDay) {
  atmos::Atmosphere* clear = earth_;
  atmos::Tables* clear_tables = tables_;
  atmos::Atmosphere hazy = atmos::load_atmosphere("earth");
  const atmos::PrecomputeOptions options;
  const char* cache = std::getenv("ATMOS_CACHE_DIR");
  atmos::Tables hazy_tables = cache ? atmos::load_or_precompute_tables(hazy, options, cache).tables
                                    : atmos::precompute_tables(hazy, options);
  earth_ = &hazy;
  tables_ = &hazy_tables;
  for (const auto& [camera, sun] : {std::pair{kCameras[0], 60.0}, std::pair{kCameras[1], 20.0}}) {
    const CaseResult r = measure(camera, sun);
    EXPECT_LE(r.volume.rms(), 0.07) << camera.name << ", sun " << sun;
    EXPECT_LE(r.volume.worst_excess, 0.25) << camera.name << ", sun " << sun;
    EXPECT_LE(r.volume.worst_transmittance, 0.012) << camera.name << ", sun " << sun;
  }
  earth_ = clear;
  tables_ = clear_tables;
}

}  // namespace
