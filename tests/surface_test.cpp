// The globe's surface (src/planet/surface.hpp): elevation data with the
// style's detail below their resolution (the data's mean kept), the style's
// relief where the data have none, the Earth style inside real coastlines,
// imagery as the albedo, and bad input.
#include "planet/surface.hpp"

#include "atmos/atmosphere.hpp"
#include "atmos/globe.hpp"
#include "atmos/planet_file.hpp"
#include "planet/shoreline_bins.hpp"

#include <gdal.h>
#include <ogr_srs_api.h>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace {

using atmos::planet::Surface;

constexpr double kPi = 3.14159265358979323846;
constexpr double kEarthRadius = 6371e3;

glm::dvec3 direction(double lat_deg, double lon_deg) {
  const double lat = lat_deg * kPi / 180.0, lon = lon_deg * kPi / 180.0;
  return {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

class SurfaceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    GDALAllRegister();
    dir_ = std::filesystem::temp_directory_path() /
           ("atmos_surface_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A geographic Float32 GeoTIFF in metres over [west, east] x [south, north].
  std::string write(const std::string& name, int w, int h, double west, double south, double east, double north,
                    const std::function<double(double, double)>& value, const double* nodata = nullptr) {
    const std::string path = (dir_ / name).string();
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), w, h, 1, GDT_Float32, nullptr);
    double gt[6] = {west, (east - west) / w, 0.0, north, 0.0, -(north - south) / h};
    GDALSetGeoTransform(ds, gt);
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    OSRSetFromUserInput(srs, "EPSG:4326");
    GDALSetSpatialRef(ds, srs);
    OSRDestroySpatialReference(srs);
    std::vector<float> data(size_t(w) * size_t(h));
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i)
        data[size_t(j * w + i)] = float(value(gt[0] + (i + 0.5) * gt[1], gt[3] + (j + 0.5) * gt[5]));
    GDALRasterBandH band = GDALGetRasterBand(ds, 1);
    GDALSetRasterUnitType(band, "m");
    if (nodata != nullptr) GDALSetRasterNoDataValue(band, *nodata);
    EXPECT_EQ(GDALRasterIO(band, GF_Write, 0, 0, w, h, data.data(), w, h, GDT_Float32, 0, 0), CE_None);
    GDALClose(ds);
    return path;
  }

  std::filesystem::path dir_;
};

atmos::PlanetSurface style(atmos::SurfaceStyle s, std::uint64_t seed = 1) {
  atmos::PlanetSurface p;
  p.style = s;
  p.seed = seed;
  return p;
}

// Procedural detail below the data's resolution leaves the data's mean:
// over an area many data pixels wide, the mean of (surface - data) is a
// small fraction of the detail's own spread, and the detail is there.
TEST_F(SurfaceTest, DetailBelowTheDataKeepsTheDatasMean) {
  // A regional raster of 1 km pixels (0.009 deg) holding 500 m everywhere.
  atmos::PlanetSurface p = style(atmos::SurfaceStyle::mars, 3);
  p.elevation.source = write("flat.tif", 200, 200, 10.0, 40.0, 11.8, 41.8, [](double, double) { return 500.0; });
  const Surface surface(p, kEarthRadius);
  ASSERT_TRUE(surface.has_elevation_data());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double sum = 0, sum2 = 0, largest = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double h = surface.ground_height_m(direction(40.2 + 1.4 * u(rng), 10.2 + 1.4 * u(rng))) - 500.0;
    sum += h;
    sum2 += h * h;
    largest = std::max(largest, std::abs(h));
  }
  const double mean = sum / n, rms = std::sqrt(sum2 / n - mean * mean);
  EXPECT_GT(rms, 1.0) << "m: the detail below 2 km must be there";
  EXPECT_LT(std::abs(mean), 0.1 * rms) << "m: mean " << mean << ", rms " << rms;
  // The detail stays within its bound, and the bound within the surface's.
  const double bound = surface.relief().detail_bound_m(2.0 * 1.01 * 1000.0);
  EXPECT_LE(largest, bound);
  EXPECT_LE(surface.min_height_m(), 500.0 - bound);
  EXPECT_GE(surface.max_height_m(), 500.0 + bound);
  // Outside the raster the style's relief shows, without the data.
  const glm::dvec3 outside = direction(-30.0, 100.0);
  EXPECT_DOUBLE_EQ(surface.ground_height_m(outside), surface.relief().height_m(outside));
}

TEST_F(SurfaceTest, NodataFallsBackToTheStylesRelief) {
  const double nodata = -32768.0;
  atmos::PlanetSurface p = style(atmos::SurfaceStyle::mars, 4);
  p.elevation.source = write("holes.tif", 40, 40, 0.0, 0.0, 4.0, 4.0,
                             [](double lon, double) { return lon < 2.0 ? 1000.0 : -32768.0; }, &nodata);
  const Surface surface(p, kEarthRadius);
  const glm::dvec3 in_data = direction(2.0, 1.0), in_hole = direction(2.0, 3.0);
  EXPECT_NEAR(surface.ground_height_m(in_data), 1000.0, surface.relief().detail_bound_m(2.0 * 11.2e3) + 1e-6);
  EXPECT_DOUBLE_EQ(surface.ground_height_m(in_hole), surface.relief().height_m(in_hole));
}

// The Earth style inside GSHHG's coastlines: land where GSHHG has land,
// sea where it has ocean, except within the coast's wiggle (below the
// distance grid's 20 km) of the shore.
TEST_F(SurfaceTest, EarthLandAndSeaFollowTheRealCoastlines) {
  const std::string bins_path = atmos::planet::kDefaultShorelineBinsPath;
  ASSERT_TRUE(std::filesystem::exists(bins_path)) << "scripts/setup.sh installs gmt-gshhg-low";
  atmos::PlanetSurface p = style(atmos::SurfaceStyle::earth);
  p.coastline = bins_path;
  const Surface surface(p, kEarthRadius);
  const atmos::planet::ShorelineBins bins(bins_path);
  EXPECT_GT(surface.ground_height_m(direction(23.0, 13.0)), 0.0);     // Sahara
  EXPECT_LT(surface.ground_height_m(direction(0.0, -150.0)), -1000.0); // Pacific
  EXPECT_GT(surface.ground_height_m(direction(60.0, 100.0)), 0.0);    // Siberia
  EXPECT_LT(surface.ground_height_m(direction(30.0, -40.0)), -1000.0); // mid-Atlantic
  // A 1-degree grid between 60 S and 75 N: points farther than 50 km from
  // any change of GSHHG's class (checked on a ring around them) must agree.
  int checked = 0, agree = 0;
  double land_area = 0, area = 0;
  for (double lat = -59.5; lat < 75.0; lat += 1.0)
    for (double lon = -179.5; lon < 180.0; lon += 1.0) {
      const bool land = bins.point_level_at(lat, lon) != atmos::planet::ShoreLevel::ocean;
      const bool drawn_land = surface.ground_height_m(direction(lat, lon)) >= 0.0;
      const double w = std::cos(lat * kPi / 180.0);
      area += w;
      land_area += drawn_land ? w : 0.0;
      bool interior = true;
      for (int k = 0; k < 8 && interior; ++k) {
        const double a = k * kPi / 4.0, r = 0.45;  // degrees: 50 km
        const double la = lat + r * std::sin(a), lo = lon + r * std::cos(a) / w;
        interior = (bins.point_level_at(la, lo) != atmos::planet::ShoreLevel::ocean) == land;
      }
      if (!interior) continue;
      ++checked;
      agree += land == drawn_land ? 1 : 0;
    }
  EXPECT_GT(checked, 15000);
  EXPECT_GE(double(agree) / checked, 0.999) << agree << " of " << checked;
  // Earth between 60 S and 75 N: about 30 % land (lakes count as land here).
  EXPECT_NEAR(land_area / area, 0.31, 0.04);
}

TEST_F(SurfaceTest, ImageryIsTheAlbedoAndBadSourcesAreNamed) {
  atmos::PlanetSurface p = atmos::load_surface("earth");
  ASSERT_FALSE(p.imagery.source.empty());
  const Surface surface(p, kEarthRadius);
  EXPECT_TRUE(surface.has_imagery());
  EXPECT_NEAR(surface.imagery_pixel_m(), 2.0 * kPi * kEarthRadius / 2048.0, 1.0);
  const glm::dvec3 d[2] = {direction(23.0, 13.0), direction(0.0, -150.0)};
  glm::vec3 albedo[2];
  surface.albedos(d, 2, 0.0, albedo);
  EXPECT_GT(albedo[0].x, 0.2f);  // the Sahara
  EXPECT_LT(albedo[1].x, 0.05f); // the Pacific

  const auto expect_error = [&](const atmos::PlanetSurface& bad, const std::string& fragment) {
    try {
      Surface s(bad, kEarthRadius);
      ADD_FAILURE() << "no error for " << fragment;
    } catch (const atmos::Error& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  atmos::PlanetSurface missing = style(atmos::SurfaceStyle::earth);
  missing.imagery.source = (dir_ / "no_such_image.jpg").string();
  expect_error(missing, "imagery");
  missing = style(atmos::SurfaceStyle::earth);
  missing.elevation.source = (dir_ / "no_such_dem.tif").string();
  expect_error(missing, "elevation");
  missing = style(atmos::SurfaceStyle::earth);
  missing.coastline = (dir_ / "no_such_bins.nc").string();
  expect_error(missing, "no_such_bins.nc");
}

// extend_below_datum: the air above the datum is unchanged, the profiles
// continue below it (exponential analytically, piecewise linear at their
// lowest density), and the vertical optical depth from a point 7 km below
// the datum is the analytic column of the continued profile.
TEST(ExtendBelowDatum, AirAboveTheDatumIsUnchangedAndContinuesBelow) {
  const atmos::Atmosphere mars = atmos::load_atmosphere("mars");
  const atmos::PlanetSurface surface = style(atmos::SurfaceStyle::mars, 2);
  const double lowest = atmos::lowest_surface_height_m(surface, mars.bottom_radius_m);
  ASSERT_LT(lowest, -4000.0);
  const atmos::Atmosphere air = atmos::extend_below_datum(mars, surface);
  const double depth = mars.bottom_radius_m - air.bottom_radius_m;
  EXPECT_NEAR(depth, -lowest, 1e-6);
  EXPECT_DOUBLE_EQ(air.top_radius_m, mars.top_radius_m);
  ASSERT_EQ(air.constituents.size(), mars.constituents.size());
  const double wavelength = 550.0;
  for (size_t c = 0; c < mars.constituents.size(); ++c) {
    const atmos::Constituent &a = mars.constituents[c], &b = air.constituents[c];
    const auto extinction = [&](const atmos::Constituent& k, double altitude) {
      return (k.scattering.at(wavelength) + k.absorption.at(wavelength)) * k.density.at(altitude);
    };
    for (double h = 0.0; h <= mars.top_radius_m - mars.bottom_radius_m; h += 997.0)
      EXPECT_NEAR(extinction(b, h + depth), extinction(a, h), 1e-12 * extinction(a, 0.0) + 1e-9 * extinction(a, h))
          << a.name << " at " << h << " m";
    // Below the datum.
    const double below = -7000.0;
    if (a.density.kind == atmos::DensityProfile::Kind::exponential) {
      EXPECT_NEAR(extinction(b, below + depth), extinction(a, 0.0) * std::exp(7000.0 / a.density.scale_height_m),
                  1e-9 * extinction(b, below + depth));
      // The vertical column from 7 km below the datum to the top, by the
      // trapezoid rule on the extended profile, against H (e^{7/H} - e^{-top/H}).
      const double top = mars.top_radius_m - mars.bottom_radius_m, H = a.density.scale_height_m;
      double column = 0.0;
      const int n = 20000;
      for (int i = 0; i < n; ++i) {
        const double h0 = below + (top - below) * i / n, h1 = below + (top - below) * (i + 1) / n;
        column += 0.5 * (b.density.at(h0 + depth) + b.density.at(h1 + depth)) * (h1 - h0);
      }
      const double scale = (b.scattering.at(wavelength) + b.absorption.at(wavelength)) /
                           (a.scattering.at(wavelength) + a.absorption.at(wavelength));
      EXPECT_NEAR(column * scale, H * (std::exp(7000.0 / H) - std::exp(-top / H)), 1e-5 * H);
    } else if (a.density.knots.front().first <= 0.0) {
      EXPECT_DOUBLE_EQ(b.density.at(below + depth), a.density.knots.front().second);
    }
  }
  // A surface that stays above the datum leaves the atmosphere as it is.
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const atmos::Atmosphere same = atmos::extend_below_datum(earth, style(atmos::SurfaceStyle::earth));
  EXPECT_EQ(same.bottom_radius_m, earth.bottom_radius_m);
  EXPECT_EQ(atmos::lowest_surface_height_m(style(atmos::SurfaceStyle::earth), earth.bottom_radius_m), 0.0);
}

}  // namespace
