// GDAL rasters sampled at directions (src/planet/raster_source.hpp), on
// GeoTIFFs written by the tests: bilinear interpolation is exact for a
// linear function of the raster's own coordinates, so a geographic and a
// projected raster of linear data must be reproduced to float rounding;
// nodata, overviews, the antimeridian, units, and every kind of bad input.
#include "planet/raster_source.hpp"

#include "atmos/atmosphere.hpp"

#include <cpl_conv.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace {

using atmos::planet::RasterKind;
using atmos::planet::RasterSettings;
using atmos::planet::RasterSource;

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadius = 6371e3;

glm::dvec3 direction(double lat_deg, double lon_deg) {
  const double lat = lat_deg * kPi / 180.0, lon = lon_deg * kPi / 180.0;
  return {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

class RasterSourceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    GDALAllRegister();
    dir_ = std::filesystem::temp_directory_path() /
           ("atmos_raster_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A Float32 GeoTIFF of value(x, y) at pixel centres, x and y in the CRS.
  std::string write(const std::string& name, int w, int h, const double geotransform[6], const char* crs,
                    const std::function<double(double, double)>& value, const char* unit = "m",
                    const double* nodata = nullptr, int bands = 1) {
    const std::string path = (dir_ / name).string();
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), w, h, bands, GDT_Float32, nullptr);
    EXPECT_NE(ds, nullptr);
    if (geotransform != nullptr) GDALSetGeoTransform(ds, const_cast<double*>(geotransform));
    if (crs != nullptr) {
      OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
      EXPECT_EQ(OSRSetFromUserInput(srs, crs), OGRERR_NONE);
      GDALSetSpatialRef(ds, srs);
      OSRDestroySpatialReference(srs);
    }
    std::vector<float> data(size_t(w) * size_t(h));
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        const double px = i + 0.5, py = j + 0.5;
        const double x = geotransform ? geotransform[0] + px * geotransform[1] + py * geotransform[2] : px;
        const double y = geotransform ? geotransform[3] + px * geotransform[4] + py * geotransform[5] : py;
        data[size_t(j * w + i)] = float(value(x, y));
      }
    for (int b = 1; b <= bands; ++b) {
      GDALRasterBandH band = GDALGetRasterBand(ds, b);
      if (unit != nullptr) GDALSetRasterUnitType(band, unit);
      if (nodata != nullptr) GDALSetRasterNoDataValue(band, *nodata);
      EXPECT_EQ(GDALRasterIO(band, GF_Write, 0, 0, w, h, data.data(), w, h, GDT_Float32, 0, 0), CE_None);
    }
    GDALClose(ds);
    return path;
  }

  std::filesystem::path dir_;
};

RasterSettings elevation(const std::string& source) {
  RasterSettings s;
  s.source = source;
  s.kind = RasterKind::elevation;
  return s;
}

struct Sample {
  float value = 0;
  bool valid = false;
};

Sample sample(const RasterSource& r, const glm::dvec3& d, double spacing_m = 0.0) {
  float v[3] = {0, 0, 0};
  std::uint8_t ok = 0;
  r.sample(&d, 1, spacing_m, kRadius, v, &ok);
  return {v[0], ok != 0};
}

TEST_F(RasterSourceTest, GeographicLinearDataIsReproducedExactly) {
  // 64 x 64 pixels over longitudes 10..20 and latitudes 40..50 degrees.
  const double gt[6] = {10.0, 10.0 / 64, 0.0, 50.0, 0.0, -10.0 / 64};
  const auto f = [](double lon, double lat) { return 100.0 * (lon - 15.0) + 37.0 * (lat - 45.0); };
  RasterSource r(elevation(write("linear.tif", 64, 64, gt, "EPSG:4326", f)));
  EXPECT_EQ(r.bands(), 1);
  EXPECT_FALSE(r.is_global());
  EXPECT_NEAR(r.pixel_size_m(kRadius), 10.0 / 64 * kPi / 180 * kRadius, 0.01 * 17e3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> dirs;
  std::vector<double> expected;
  for (int i = 0; i < 500; ++i) {
    // Inside the pixel centres' hull (10 + half a pixel ...): bilinear there.
    const double lon = 10.1 + 9.8 * u(rng), lat = 40.1 + 9.8 * u(rng);
    dirs.push_back(direction(lat, lon));
    expected.push_back(f(lon, lat));
  }
  std::vector<float> out(dirs.size());
  std::vector<std::uint8_t> ok(dirs.size());
  r.sample(dirs.data(), dirs.size(), 0.0, kRadius, out.data(), ok.data());
  double worst = 0;
  for (size_t i = 0; i < dirs.size(); ++i) {
    ASSERT_TRUE(ok[i]);
    worst = std::max(worst, std::abs(double(out[i]) - expected[i]));
  }
  EXPECT_LT(worst, 2e-3) << "m, for values up to 685 m";
  // Outside the raster: invalid, the caller's next source takes over.
  EXPECT_FALSE(sample(r, direction(30.0, 15.0)).valid);
  EXPECT_FALSE(sample(r, direction(45.0, -165.0)).valid);
  EXPECT_NEAR(r.min_value(), f(10 + 10.0 / 128, 40 + 10.0 / 128), 1e-2);
  EXPECT_NEAR(r.max_value(), f(20 - 10.0 / 128, 50 - 10.0 / 128), 1e-2);
}

TEST_F(RasterSourceTest, ProjectedLinearDataIsReproducedExactly) {
  // UTM zone 32 N (EPSG:32632), 100 m pixels around (500 km E, 5000 km N).
  const double gt[6] = {496800.0, 100.0, 0.0, 5003200.0, 0.0, -100.0};
  const auto f = [](double x, double y) { return 0.01 * (x - 500000.0) + 0.02 * (y - 5000000.0); };
  RasterSource r(elevation(write("utm.tif", 64, 64, gt, "EPSG:32632", f)));
  EXPECT_NEAR(r.pixel_size_m(kRadius), 100.0, 2.0);  // the sphere is not the ellipsoid: within 2 %
  // Expected values: the same transform PROJ does, from the raster's own
  // geographic CRS (WGS 84) to UTM.
  OGRSpatialReferenceH utm = OSRNewSpatialReference(nullptr), wgs = OSRNewSpatialReference(nullptr);
  OSRSetFromUserInput(utm, "EPSG:32632");
  OSRSetFromUserInput(wgs, "EPSG:4326");
  OSRSetAxisMappingStrategy(utm, OAMS_TRADITIONAL_GIS_ORDER);
  OSRSetAxisMappingStrategy(wgs, OAMS_TRADITIONAL_GIS_ORDER);
  OGRCoordinateTransformationH ct = OCTNewCoordinateTransformation(wgs, utm);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0;
  int inside = 0;
  for (int i = 0; i < 300; ++i) {
    const double lon = 8.96 + 0.08 * u(rng), lat = 45.13 + 0.04 * u(rng);
    double x = lon, y = lat;
    ASSERT_TRUE(OCTTransform(ct, 1, &x, &y, nullptr));
    if (x < 496850 || x > 503150 || y < 4996850 || y > 5003150) continue;
    ++inside;
    const Sample s = sample(r, direction(lat, lon));
    ASSERT_TRUE(s.valid);
    worst = std::max(worst, std::abs(double(s.value) - f(x, y)));
  }
  OCTDestroyCoordinateTransformation(ct);
  OSRDestroySpatialReference(utm);
  OSRDestroySpatialReference(wgs);
  EXPECT_GT(inside, 100);
  EXPECT_LT(worst, 2e-3) << "m";
}

TEST_F(RasterSourceTest, NodataTakesNoWeightAndFallsThrough) {
  const double gt[6] = {0.0, 1.0, 0.0, 10.0, 0.0, -1.0};
  const double nodata = -9999.0;
  // Columns 4 and 5 are nodata; the rest is 50 m.
  const auto f = [](double lon, double) { return (lon > 4.0 && lon < 6.0) ? -9999.0 : 50.0; };
  RasterSource r(elevation(write("nodata.tif", 10, 10, gt, "EPSG:4326", f, "m", &nodata)));
  EXPECT_FALSE(sample(r, direction(5.0, 5.0)).valid);      // between two nodata centres
  const Sample edge = sample(r, direction(5.0, 4.2));       // between 50 m and nodata
  ASSERT_TRUE(edge.valid);
  EXPECT_FLOAT_EQ(edge.value, 50.0f);  // renormalised: no pull towards -9999
  EXPECT_FLOAT_EQ(float(r.min_value()), 50.0f);
}

TEST_F(RasterSourceTest, CoarseSpacingReadsTheOverview) {
  // A raster with an overview whose values differ from the full resolution
  // (written by hand): a coarse spacing must read the overview.
  const double gt[6] = {0.0, 0.01, 0.0, 1.0, 0.0, -0.01};
  const std::string path = write("overview.tif", 100, 100, gt, "EPSG:4326", [](double, double) { return 10.0; });
  GDALDatasetH ds = GDALOpen(path.c_str(), GA_Update);
  int factor = 2;
  ASSERT_EQ(GDALBuildOverviews(ds, "AVERAGE", 1, &factor, 0, nullptr, nullptr, nullptr), CE_None);
  GDALRasterBandH overview = GDALGetOverview(GDALGetRasterBand(ds, 1), 0);
  std::vector<float> values(50 * 50, 70.0f);
  ASSERT_EQ(GDALRasterIO(overview, GF_Write, 0, 0, 50, 50, values.data(), 50, 50, GDT_Float32, 0, 0), CE_None);
  GDALClose(ds);
  RasterSource r(elevation(path));
  const glm::dvec3 d = direction(0.5, 0.5);
  const double pixel = r.pixel_size_m(kRadius);
  EXPECT_FLOAT_EQ(sample(r, d, 0.0).value, 10.0f);
  EXPECT_FLOAT_EQ(sample(r, d, 3.9 * pixel).value, 10.0f);   // overview pixel 2 > spacing / 2
  EXPECT_FLOAT_EQ(sample(r, d, 4.1 * pixel).value, 70.0f);   // overview pixel 2 <= spacing / 2
}

TEST_F(RasterSourceTest, GlobalRasterWrapsAroundTheAntimeridian) {
  // 36 x 18 pixels of 10 degrees, value = the column's centre longitude's
  // cosine (continuous across the antimeridian).
  const double gt[6] = {-180.0, 10.0, 0.0, 90.0, 0.0, -10.0};
  const auto f = [](double lon, double) { return 1000.0 * std::cos(lon * kPi / 180.0); };
  RasterSource r(elevation(write("global.tif", 36, 18, gt, "EPSG:4326", f)));
  EXPECT_TRUE(r.is_global());
  // At 180 degrees: halfway between the centres at 175 and -175.
  const double expected = 1000.0 * std::cos(175.0 * kPi / 180.0);
  EXPECT_NEAR(sample(r, direction(0.0, 180.0)).value, expected, 1e-3);
  EXPECT_NEAR(sample(r, direction(0.0, -179.0)).value, expected, 1e-3);
  EXPECT_NEAR(sample(r, direction(0.0, 179.0)).value, expected, 1e-3);
  // A batch across the antimeridian reads one wrapped window.
  std::vector<glm::dvec3> dirs = {direction(3, 172), direction(3, 178), direction(3, -178), direction(3, -172)};
  float out[4];
  std::uint8_t ok[4];
  r.sample(dirs.data(), 4, 1e5, kRadius, out, ok);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ok[i]) << i;
  EXPECT_NEAR(out[1], out[2], 1e-3);
  // The poles: clamped rows, valid.
  EXPECT_TRUE(sample(r, direction(90.0, 0.0)).valid);
  EXPECT_TRUE(sample(r, direction(-90.0, 0.0)).valid);
}

TEST_F(RasterSourceTest, UnitsComeFromTheBandOrThePlanetFile) {
  const double gt[6] = {0.0, 1.0, 0.0, 10.0, 0.0, -1.0};
  const auto f = [](double, double) { return 100.0; };
  RasterSource feet(elevation(write("feet.tif", 10, 10, gt, "EPSG:4326", f, "ft")));
  EXPECT_NEAR(sample(feet, direction(5, 5)).value, 30.48, 1e-4);
  const std::string no_unit = write("nounit.tif", 10, 10, gt, "EPSG:4326", f, nullptr);
  EXPECT_THROW(RasterSource r(elevation(no_unit)), atmos::Error);
  RasterSettings km = elevation(no_unit);
  km.metres_per_unit = 1000.0;
  EXPECT_NEAR(sample(RasterSource(km), direction(5, 5)).value, 1e5, 1e-2);
  RasterSettings contradiction = elevation(write("metres.tif", 10, 10, gt, "EPSG:4326", f, "m"));
  contradiction.metres_per_unit = 0.3048;
  EXPECT_THROW(RasterSource r(contradiction), atmos::Error);
}

// The message names the source and says what is wrong.
void expect_error(const RasterSettings& settings, const std::string& fragment) {
  try {
    RasterSource r(settings);
    ADD_FAILURE() << "no error for " << settings.source;
  } catch (const atmos::Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(settings.role), std::string::npos) << m;
    EXPECT_NE(m.find(fragment), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

TEST_F(RasterSourceTest, BadInputGivesAClearError) {
  expect_error(elevation((dir_ / "missing.tif").string()), "missing.tif");
  // A truncated GeoTIFF.
  const double gt[6] = {0.0, 1.0, 0.0, 10.0, 0.0, -1.0};
  const std::string good = write("good.tif", 64, 64, gt, "EPSG:4326", [](double, double) { return 1.0; });
  const std::string corrupt = (dir_ / "corrupt.tif").string();
  {
    std::ifstream in(good, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream out(corrupt, std::ios::binary);
    out.write(bytes.data(), 200);
  }
  expect_error(elevation(corrupt), "corrupt.tif");
  // Not a raster at all.
  const std::string text = (dir_ / "notes.tif").string();
  std::ofstream(text) << "not a raster\n";
  expect_error(elevation(text), "cannot be read");
  // No georeferencing.
  expect_error(elevation(write("plain.tif", 8, 8, nullptr, nullptr, [](double, double) { return 1.0; })),
               "georeferencing");
  // Georeferenced but without a CRS, and an unknown CRS given for it.
  const std::string no_crs = write("nocrs.tif", 8, 8, gt, nullptr, [](double, double) { return 1.0; });
  expect_error(elevation(no_crs), "coordinate reference system");
  RasterSettings unknown = elevation(no_crs);
  unknown.crs = "EPSG:999999";
  expect_error(unknown, "unknown CRS");
  // Absurdly large: 10^6 x 10^6 pixels (a VRT: nothing is allocated) without overviews.
  const std::string huge =
      "<VRTDataset rasterXSize=\"1000000\" rasterYSize=\"1000000\"><SRS>EPSG:4326</SRS>"
      "<GeoTransform>-180, 0.00036, 0, 90, 0, -0.00018</GeoTransform>"
      "<VRTRasterBand dataType=\"Float32\" band=\"1\"><UnitType>m</UnitType></VRTRasterBand></VRTDataset>";
  expect_error(elevation(huge), "overviews");
  // Imagery needs three bands.
  RasterSettings grey = elevation(good);
  grey.kind = RasterKind::imagery;
  grey.role = "imagery";
  expect_error(grey, "three bands");
}

TEST_F(RasterSourceTest, BlueMarbleImageryIsPlacedOnTheRightLongitudes) {
  // xplanet-images' Blue Marble through a VRT that georeferences it: its
  // left edge is 180 degrees west. Ocean is dark and blue, the Sahara
  // bright and red-brown, Antarctica white.
  const std::string path = "/usr/share/xplanet/images/earth.jpg";
  ASSERT_TRUE(std::filesystem::exists(path)) << "scripts/setup.sh installs xplanet-images";
  const std::string vrt =
      "<VRTDataset rasterXSize=\"2048\" rasterYSize=\"1024\"><SRS>EPSG:4326</SRS>"
      "<GeoTransform>-180, 0.17578125, 0, 90, 0, -0.17578125</GeoTransform>"
      "<VRTRasterBand dataType=\"Byte\" band=\"1\"><SimpleSource><SourceFilename>" + path +
      "</SourceFilename><SourceBand>1</SourceBand></SimpleSource></VRTRasterBand>"
      "<VRTRasterBand dataType=\"Byte\" band=\"2\"><SimpleSource><SourceFilename>" + path +
      "</SourceFilename><SourceBand>2</SourceBand></SimpleSource></VRTRasterBand>"
      "<VRTRasterBand dataType=\"Byte\" band=\"3\"><SimpleSource><SourceFilename>" + path +
      "</SourceFilename><SourceBand>3</SourceBand></SimpleSource></VRTRasterBand></VRTDataset>";
  RasterSettings s;
  s.source = vrt;
  s.kind = RasterKind::imagery;
  s.role = "imagery";
  RasterSource r(s);
  EXPECT_EQ(r.bands(), 3);
  EXPECT_TRUE(r.is_global());
  const auto rgb = [&](double lat, double lon) {
    const glm::dvec3 d = direction(lat, lon);
    float v[3];
    std::uint8_t ok = 0;
    r.sample(&d, 1, 0.0, kRadius, v, &ok);
    EXPECT_TRUE(ok);
    return glm::vec3(v[0], v[1], v[2]);
  };
  const glm::vec3 pacific = rgb(0.0, -150.0), sahara = rgb(23.0, 13.0), antarctica = rgb(-82.0, 40.0);
  EXPECT_LT(pacific.x, 0.05f);
  EXPECT_GT(pacific.z, pacific.x);
  EXPECT_GT(sahara.x, 0.2f);
  EXPECT_GT(sahara.x, sahara.z);
  EXPECT_GT(antarctica.y, 0.5f);
  // Mirror check: 13 degrees west of Greenwich is the Atlantic, dark.
  EXPECT_LT(rgb(0.0, -13.0).x, 0.05f);
}

}  // namespace
