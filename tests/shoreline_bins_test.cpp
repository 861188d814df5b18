// GMT's binned GSHHG shorelines (src/planet/shoreline_bins.hpp): the exact
// levels of a synthetic file written by the test (nested rings of levels 1-4,
// a pinched peninsula on a bin's west side, both Antarctic coastlines); on
// Debian's GSHHG 2.3.7 files, known places, the level continuous across every
// bin side and corner (it is computed from each bin's own corner and
// segments, so a misread corner order or Antarctic selection breaks it), the
// land fraction; and every kind of bad input.
#include "planet/shoreline_bins.hpp"

#include "atmos/atmosphere.hpp"

#include <netcdf.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace {

using atmos::planet::AntarcticCoast;
using atmos::planet::ShoreLevel;
using atmos::planet::ShorelineBins;

constexpr double kPi = 3.14159265358979323846;
const std::string kLowPath = atmos::planet::kDefaultShorelineBinsPath;
const std::string kIntermediatePath = "/usr/share/gmt-gshhg/binned_GSHHS_i.nc";

// ---------------------------------------------------------------------------
// Synthetic files in GMT's binned layout (described in shoreline_bins.cpp):
// 90° bins, 2 rows x 4 columns. Bin 4 (latitudes -90..0, longitudes 0..90)
// holds nested square rings of levels 1-4 and a peninsula of two lobes
// hanging on the west side, pinched at a vertex on that side; bin 5
// (longitudes 90..180) an Antarctic ice front and grounding line hanging on
// its south side, and an island of both; bin 6 is uniform land, bin 7
// uniform lake, the others uniform ocean.

constexpr int kUnits = 65535;

struct SyntheticSegment {
  int bin = 0;
  int level = 1;
  int ant_flag = 0;
  std::vector<std::array<int, 2>> vertices;  // x, y in 1/65535 of the bin
  int first_side = -1, last_side = -1;       // -1: from the end vertices
};

struct SyntheticFile {
  int bin_minutes = 5400, columns = 4, rows = 2, bins_in_file = 8;
  std::vector<int> nodes;  // packed corner levels per bin
  std::vector<SyntheticSegment> segments;
  int extra_first_segment = 0;  // added to bin 4's first segment id
  int extra_first_point = 0;    // added to the last segment's first point id
};

int pack_corners(int south_west, int south_east, int north_east, int north_west) {
  return south_west << 9 | south_east << 6 | north_east << 3 | north_west;
}

std::vector<std::array<int, 2>> square_ring(int low, int high) {
  return {{low, low}, {high, low}, {high, high}, {low, high}, {low, low}};
}

SyntheticFile good_file() {
  SyntheticFile f;
  f.nodes.assign(8, 0);
  f.nodes[6] = pack_corners(1, 1, 1, 1);
  f.nodes[7] = pack_corners(2, 2, 2, 2);
  f.segments = {
      {4, 1, 0, square_ring(16384, 49151)},
      {4, 2, 0, square_ring(24576, 40959)},
      {4, 3, 0, square_ring(30000, 35535)},
      {4, 4, 0, square_ring(32000, 33535)},
      {4, 1, 0, {{0, 4000}, {8000, 6000}, {0, 6500}, {4000, 7000}, {0, 8000}}},
      {5, 1, 1, {{20000, 0}, {30000, 30000}, {40000, 0}}},  // ice front only
      {5, 6, 0, {{25000, 0}, {30000, 15000}, {35000, 0}}},  // grounding line only
      {5, 1, 0, square_ring(50000, 60000)},
  };
  return f;
}

int side_of(const std::array<int, 2>& v) {
  if (v[1] == 0) return 0;
  if (v[0] == kUnits) return 1;
  if (v[1] == kUnits) return 2;
  if (v[0] == 0) return 3;
  return 4;
}

void check(int status) { ASSERT_EQ(status, NC_NOERR) << nc_strerror(status); }

void write_synthetic(const std::string& path, const SyntheticFile& f) {
  const int bins = static_cast<int>(f.nodes.size());
  std::vector<int> first_segment(bins, 0);
  std::vector<short> bin_segments(bins, 0), nodes(bins);
  std::vector<int> info, first_point;
  std::vector<signed char> ant_flag;
  std::vector<short> xs, ys;
  for (int b = 0; b < bins; ++b) {
    first_segment[b] = static_cast<int>(info.size());
    nodes[b] = static_cast<short>(f.nodes[b]);
    for (const SyntheticSegment& s : f.segments) {
      if (s.bin != b) continue;
      ++bin_segments[b];
      const int first = s.first_side >= 0 ? s.first_side : side_of(s.vertices.front());
      const int last = s.last_side >= 0 ? s.last_side : side_of(s.vertices.back());
      info.push_back(static_cast<int>(s.vertices.size()) << 9 | s.level << 6 | first << 3 | last);
      first_point.push_back(static_cast<int>(xs.size()));
      ant_flag.push_back(static_cast<signed char>(s.ant_flag));
      for (const auto& v : s.vertices) {
        xs.push_back(static_cast<short>(v[0]));  // modulo 2^16, as GMT stores them
        ys.push_back(static_cast<short>(v[1]));
      }
    }
  }
  first_segment[4] += f.extra_first_segment;
  first_point.back() += f.extra_first_point;

  int nc = 0;
  check(nc_create(path.c_str(), NC_CLOBBER | NC_NETCDF4, &nc));
  int scalar = 0, bin_dim = 0, segment_dim = 0, point_dim = 0;
  check(nc_def_dim(nc, "Dimension_of_scalar", 1, &scalar));
  check(nc_def_dim(nc, "Dimension_of_bin_arrays", static_cast<std::size_t>(bins), &bin_dim));
  check(nc_def_dim(nc, "Dimension_of_segment_arrays", info.size(), &segment_dim));
  check(nc_def_dim(nc, "Dimension_of_point_arrays", xs.size(), &point_dim));
  const auto define = [&](const char* name, nc_type type, int dim) {
    int id = 0;
    check(nc_def_var(nc, name, type, 1, &dim, &id));
    return id;
  };
  const int v_bin_size = define("Bin_size_in_minutes", NC_INT, scalar);
  const int v_columns = define("N_bins_in_360_longitude_range", NC_INT, scalar);
  const int v_rows = define("N_bins_in_180_degree_latitude_range", NC_INT, scalar);
  const int v_bins = define("N_bins_in_file", NC_INT, scalar);
  const int v_segments = define("N_segments_in_file", NC_INT, scalar);
  const int v_points = define("N_points_in_file", NC_INT, scalar);
  const int v_first_segment = define("Id_of_first_segment_in_a_bin", NC_INT, bin_dim);
  const int v_nodes = define("Embedded_node_levels_in_a_bin", NC_SHORT, bin_dim);
  const int v_nodes_ant = define("Embedded_node_levels_in_a_bin_ANT", NC_SHORT, bin_dim);
  const int v_bin_segments = define("N_segments_in_a_bin", NC_SHORT, bin_dim);
  const int v_info = define("Embedded_npts_levels_exit_entry_for_a_segment", NC_INT, segment_dim);
  const int v_first_point = define("Id_of_first_point_in_a_segment", NC_INT, segment_dim);
  const int v_ant = define("Embedded_ANT_flag", NC_BYTE, segment_dim);
  const int v_x = define("Relative_longitude_from_SW_corner_of_bin", NC_SHORT, point_dim);
  const int v_y = define("Relative_latitude_from_SW_corner_of_bin", NC_SHORT, point_dim);
  check(nc_enddef(nc));
  const int segment_count = static_cast<int>(info.size()), point_count = static_cast<int>(xs.size());
  check(nc_put_var_int(nc, v_bin_size, &f.bin_minutes));
  check(nc_put_var_int(nc, v_columns, &f.columns));
  check(nc_put_var_int(nc, v_rows, &f.rows));
  check(nc_put_var_int(nc, v_bins, &f.bins_in_file));
  check(nc_put_var_int(nc, v_segments, &segment_count));
  check(nc_put_var_int(nc, v_points, &point_count));
  check(nc_put_var_int(nc, v_first_segment, first_segment.data()));
  check(nc_put_var_short(nc, v_nodes, nodes.data()));
  check(nc_put_var_short(nc, v_nodes_ant, nodes.data()));
  check(nc_put_var_short(nc, v_bin_segments, bin_segments.data()));
  check(nc_put_var_int(nc, v_info, info.data()));
  check(nc_put_var_int(nc, v_first_point, first_point.data()));
  check(nc_put_var_schar(nc, v_ant, ant_flag.data()));
  check(nc_put_var_short(nc, v_x, xs.data()));
  check(nc_put_var_short(nc, v_y, ys.data()));
  check(nc_close(nc));
}

class ShorelineBinsFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("atmos_shoreline_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // The error a reader of `file` throws; fails the test when it throws none.
  static std::string error_of(const std::string& file) {
    try {
      const ShorelineBins bins(file);
    } catch (const atmos::Error& e) {
      return e.what();
    }
    ADD_FAILURE() << file << " was read without an error";
    return {};
  }

  std::filesystem::path dir_;
};

// The latitude and longitude of a point of bin `bin` of the synthetic file,
// at (x, y) in 1/65535 of the bin from its south-west corner.
std::array<double, 2> synthetic_point(int bin, double x, double y) {
  const int row = bin / 4, column = bin % 4;
  return {90.0 - (row + 1) * 90.0 + y / kUnits * 90.0, column * 90.0 + x / kUnits * 90.0};
}

TEST_F(ShorelineBinsFileTest, SyntheticLevelsAreExact) {
  const std::string file = path("synthetic.nc");
  write_synthetic(file, good_file());
  const ShorelineBins ice(file);
  const ShorelineBins grounding(file, AntarcticCoast::grounding_line);
  EXPECT_EQ(ice.bin_size_deg(), 90.0);
  EXPECT_EQ(ice.rows(), 2);
  EXPECT_EQ(ice.columns(), 4);

  const auto level = [&](const ShorelineBins& bins, int bin, double x, double y) {
    const auto p = synthetic_point(bin, x, y);
    return bins.point_level_at(p[0], p[1]);
  };
  // The nested rings (bounds 16384, 24576, 30000, 32000 and their mirrors).
  EXPECT_EQ(level(ice, 4, 32767.5, 32767.5), ShoreLevel::pond_in_island);
  EXPECT_EQ(level(ice, 4, 31000, 32767), ShoreLevel::island_in_lake);
  EXPECT_EQ(level(ice, 4, 27000, 32767), ShoreLevel::lake);
  EXPECT_EQ(level(ice, 4, 20000, 32767), ShoreLevel::land);
  EXPECT_EQ(level(ice, 4, 10000, 32767), ShoreLevel::ocean);
  EXPECT_EQ(level(ice, 4, 60000, 60000), ShoreLevel::ocean);
  EXPECT_EQ(level(ice, 4, 32767, 16384.5), ShoreLevel::land);  // just inside the island's south shore
  EXPECT_EQ(level(ice, 4, 32767, 16383.5), ShoreLevel::ocean);
  // The peninsula: lobe 1 between y = 4000 and 6500, lobe 2 between 6500 and
  // 8000, both west of their edges; the pinch vertex (0, 6500).
  EXPECT_EQ(level(ice, 4, 6000, 5800), ShoreLevel::land);   // the edge is at x = 7200
  EXPECT_EQ(level(ice, 4, 7500, 5800), ShoreLevel::ocean);
  EXPECT_EQ(level(ice, 4, 1000, 6700), ShoreLevel::land);   // the edge is at x = 1600
  EXPECT_EQ(level(ice, 4, 2000, 6700), ShoreLevel::ocean);
  EXPECT_EQ(level(ice, 4, 1000, 7600), ShoreLevel::land);   // the edge is at x = 1600
  EXPECT_EQ(level(ice, 4, 100, 6500), ShoreLevel::ocean);   // beside the pinch, on its parallel
  EXPECT_EQ(level(ice, 4, 0, 6200), ShoreLevel::land);      // on the west side, inside lobe 1
  EXPECT_EQ(level(ice, 4, 0, 6500.5), ShoreLevel::land);    // on the west side, inside lobe 2
  EXPECT_EQ(level(ice, 4, 1000, 3800), ShoreLevel::ocean);
  EXPECT_EQ(level(ice, 4, 1000, 8200), ShoreLevel::ocean);
  // The ice shelf (between the two lines) is land with the ice front only.
  EXPECT_EQ(level(ice, 5, 30000, 20000), ShoreLevel::land);
  EXPECT_EQ(level(grounding, 5, 30000, 20000), ShoreLevel::ocean);
  EXPECT_EQ(level(ice, 5, 30000, 5000), ShoreLevel::land);
  EXPECT_EQ(level(grounding, 5, 30000, 5000), ShoreLevel::land);
  EXPECT_EQ(level(ice, 5, 10000, 5000), ShoreLevel::ocean);
  EXPECT_EQ(level(grounding, 5, 10000, 5000), ShoreLevel::ocean);
  EXPECT_EQ(level(ice, 5, 55000, 55000), ShoreLevel::land);
  EXPECT_EQ(level(grounding, 5, 55000, 55000), ShoreLevel::land);

  // Bin levels: uncut bins keep their corners' level, cut ones are coastal.
  EXPECT_EQ(ice.level_at(-45, 45), ShoreLevel::coastal);
  EXPECT_EQ(ice.level_at(-45, 135), ShoreLevel::coastal);
  EXPECT_EQ(ice.level_at(-45, 225), ShoreLevel::land);
  EXPECT_EQ(ice.level_at(-45, 315), ShoreLevel::lake);
  EXPECT_EQ(ice.level_at(45, 45), ShoreLevel::ocean);
  EXPECT_EQ(ice.point_level_at(-45, 225), ShoreLevel::land);
  EXPECT_EQ(ice.level_at(-45, -45), ShoreLevel::lake);  // wrapped to 315
  EXPECT_EQ(ice.level_at(-95, 45), ice.level_at(-90, 45));
}

// levels_along_parallel gives point_level_at's level at every point: on the
// synthetic file's parallels through its vertices (the peninsula's pinch,
// the rings' bounds) and between them, at points on the bins' west sides,
// in every column, in one call per parallel.
TEST_F(ShorelineBinsFileTest, LevelsAlongAParallelArePointLevels) {
  const std::string file = path("synthetic.nc");
  write_synthetic(file, good_file());
  for (const AntarcticCoast coast : {AntarcticCoast::ice_front, AntarcticCoast::grounding_line}) {
    const ShorelineBins bins(file, coast);
    std::vector<double> ys = {0, 3800, 4000, 5000, 5800, 6200, 6500, 6500.5, 6700, 7600, 8000, 8200,
                              16383.5, 16384, 16384.5, 20000, 24576, 30000, 32000, 32767, 32767.5, 55000, 65535};
    for (int k = 0; k < 64; ++k) ys.push_back(k * 1023.9);
    std::vector<double> longitudes;
    for (int column = 0; column < 4; ++column)
      for (int k = 0; k <= 256; ++k) longitudes.push_back(column * 90.0 + k * 90.0 / 256.0 + (k % 3 == 1 ? 1e-3 : 0.0));
    int coastal = 0;
    for (int row = 0; row < 2; ++row)
      for (const double y : ys) {
        const double latitude = synthetic_point(row * 4, 0.0, y)[0];
        std::vector<ShoreLevel> levels(longitudes.size());
        bins.levels_along_parallel(latitude, longitudes.data(), longitudes.size(), levels.data());
        for (std::size_t i = 0; i < longitudes.size(); ++i) {
          ASSERT_EQ(levels[i], bins.point_level_at(latitude, longitudes[i])) << latitude << ", " << longitudes[i];
          coastal += bins.level_at(latitude, longitudes[i]) == ShoreLevel::coastal;
        }
      }
    EXPECT_GT(coastal, 10000);
  }
}

TEST_F(ShorelineBinsFileTest, InconsistentFilesAreRejected) {
  struct Mutation {
    const char* what;
    const char* message;  // a fragment of the expected message
    std::function<void(SyntheticFile&)> apply;
  };
  const Mutation mutations[] = {
      {"bins that do not tile the sphere", "do not tile the sphere", [](SyntheticFile& f) { f.bin_minutes = 5000; }},
      {"bin count other than rows x columns", "7 bins", [](SyntheticFile& f) { f.bins_in_file = 7; }},
      {"segment ids out of range", "bin 4's segments are out of range",
       [](SyntheticFile& f) { f.extra_first_segment = 100; }},
      {"point ids out of range", "segment 7's points are out of range",
       [](SyntheticFile& f) { f.extra_first_point = 1000; }},
      {"segment level 5", "segment 1 has level 5", [](SyntheticFile& f) { f.segments[1].level = 5; }},
      {"corner level 7", "corner level 7", [](SyntheticFile& f) { f.nodes[4] = pack_corners(7, 0, 0, 0); }},
      {"an end off its named side", "segment 4's ends do not lie on the bin sides",
       [](SyntheticFile& f) { f.segments[4].first_side = 0; }},
      {"a ring that does not close", "segment 0 is a ring that does not close",
       [](SyntheticFile& f) { f.segments[0].vertices.pop_back(); }},
      {"a vertex on a corner", "lies on a corner of bin 5",
       [](SyntheticFile& f) { f.segments[5].vertices[1] = {kUnits, kUnits}; }},
      {"an uncut bin with unequal corners", "bin 0 has no shoreline but corners of different levels",
       [](SyntheticFile& f) { f.nodes[0] = pack_corners(0, 1, 0, 0); }},
  };
  for (const Mutation& mutation : mutations) {
    SyntheticFile f = good_file();
    mutation.apply(f);
    const std::string file = path("bad.nc");
    write_synthetic(file, f);
    const std::string message = error_of(file);
    EXPECT_NE(message.find(file), std::string::npos) << mutation.what << ": " << message;
    EXPECT_NE(message.find(mutation.message), std::string::npos) << mutation.what << ": " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << mutation.what << ": " << message;
  }
}

TEST_F(ShorelineBinsFileTest, UnreadableFilesAreRejected) {
  const std::string missing = path("missing.nc");
  const std::string missing_error = error_of(missing);
  EXPECT_NE(missing_error.find(missing), std::string::npos) << missing_error;
  EXPECT_NE(missing_error.find("No such file"), std::string::npos) << missing_error;

  const std::string text = path("text.nc");
  std::ofstream(text) << "not a netCDF file\n";
  const std::string text_error = error_of(text);
  EXPECT_NE(text_error.find(text), std::string::npos) << text_error;
  EXPECT_NE(text_error.find("not a netCDF file"), std::string::npos) << text_error;

  // A valid netCDF file without the binned layout's variables.
  const std::string other = path("other.nc");
  int nc = 0, dim = 0, var = 0;
  check(nc_create(other.c_str(), NC_CLOBBER | NC_NETCDF4, &nc));
  check(nc_def_dim(nc, "x", 3, &dim));
  check(nc_def_var(nc, "elevation", NC_FLOAT, 1, &dim, &var));
  check(nc_enddef(nc));
  const float values[3] = {1, 2, 3};
  check(nc_put_var_float(nc, var, values));
  check(nc_close(nc));
  const std::string other_error = error_of(other);
  EXPECT_NE(other_error.find(other), std::string::npos) << other_error;
  EXPECT_NE(other_error.find("Bin_size_in_minutes"), std::string::npos) << other_error;
}

// ---------------------------------------------------------------------------
// Debian's GSHHG 2.3.7 (gmt-gshhg-low, installed by scripts/setup.sh).

class ShorelineBinsGshhgTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!std::filesystem::exists(kLowPath) || !std::filesystem::exists(kIntermediatePath)) return;
    low_ = std::make_unique<ShorelineBins>(kLowPath);
    low_grounding_ = std::make_unique<ShorelineBins>(kLowPath, AntarcticCoast::grounding_line);
    intermediate_ = std::make_unique<ShorelineBins>(kIntermediatePath);
  }
  static void TearDownTestSuite() {
    low_.reset();
    low_grounding_.reset();
    intermediate_.reset();
  }
  void SetUp() override {
    if (!low_) GTEST_SKIP() << "GSHHG bins not installed (Debian gmt-gshhg-low)";
  }

  static std::unique_ptr<ShorelineBins> low_, low_grounding_, intermediate_;
};

std::unique_ptr<ShorelineBins> ShorelineBinsGshhgTest::low_;
std::unique_ptr<ShorelineBins> ShorelineBinsGshhgTest::low_grounding_;
std::unique_ptr<ShorelineBins> ShorelineBinsGshhgTest::intermediate_;

TEST_F(ShorelineBinsGshhgTest, BinGrids) {
  EXPECT_EQ(low_->bin_size_deg(), 10.0);
  EXPECT_EQ(low_->rows(), 18);
  EXPECT_EQ(low_->columns(), 36);
  EXPECT_EQ(intermediate_->bin_size_deg(), 5.0);
  EXPECT_EQ(intermediate_->rows(), 36);
  EXPECT_EQ(intermediate_->columns(), 72);
}

TEST_F(ShorelineBinsGshhgTest, KnownPlaces) {
  struct Place {
    const char* name;
    double latitude_deg, longitude_deg;
    ShoreLevel level;
  };
  // Each at least 20 km from the nearest shoreline of both files, except the
  // lake-island pair (8 and 3.5 km; the files' vertices are exact to 17 m).
  const Place places[] = {
      {"central Sahara", 23, 13, ShoreLevel::land},
      {"central Pacific", 0, -150, ShoreLevel::ocean},
      {"mid-Atlantic", 30, -40, ShoreLevel::ocean},
      {"Siberia", 60, 100, ShoreLevel::land},
      {"Caspian Sea", 42, 51, ShoreLevel::lake},
      {"Antarctic interior", -80, 0, ShoreLevel::land},
      {"north pole", 90, 0, ShoreLevel::ocean},
      {"south pole", -90, 0, ShoreLevel::land},
      {"Greenland's ice sheet", 72, -40, ShoreLevel::land},
      {"Lake Superior", 47.7, -87.5, ShoreLevel::lake},
      {"Lake Victoria", -1, 33, ShoreLevel::lake},
      {"Lake Baikal", 53.5, 108.2, ShoreLevel::lake},
      {"Manitoulin Island (Lake Huron)", 45.68, -82.14, ShoreLevel::island_in_lake},
      {"Lake Manitou (Manitoulin Island)", 45.76, -81.96, ShoreLevel::pond_in_island},
      {"Paris", 48.86, 2.35, ShoreLevel::land},
      {"Madrid", 40.4, -3.7, ShoreLevel::land},
      {"Bay of Biscay", 45.5, -4, ShoreLevel::ocean},
      {"Black Sea", 43, 34, ShoreLevel::ocean},
      {"Hudson Bay", 60, -85, ShoreLevel::ocean},
      {"Ross Ice Shelf", -81, -175, ShoreLevel::land},
  };
  for (const Place& p : places) {
    EXPECT_EQ(low_->point_level_at(p.latitude_deg, p.longitude_deg), p.level) << p.name;
    EXPECT_EQ(intermediate_->point_level_at(p.latitude_deg, p.longitude_deg), p.level) << p.name;
    // Any longitude, wrapped.
    EXPECT_EQ(low_->point_level_at(p.latitude_deg, p.longitude_deg + 720), p.level) << p.name;
    EXPECT_EQ(low_->point_level_at(p.latitude_deg, p.longitude_deg - 360), p.level) << p.name;
  }
  // Under the ice shelf the grounding line leaves ocean.
  EXPECT_EQ(low_grounding_->point_level_at(-81, -175), ShoreLevel::ocean);
  EXPECT_EQ(low_grounding_->point_level_at(-80, 0), ShoreLevel::land);

  // Bins that no shoreline crosses at 10°, and coastal ones.
  EXPECT_EQ(low_->level_at(23, 13), ShoreLevel::land);
  EXPECT_EQ(low_->level_at(30, -40), ShoreLevel::ocean);
  EXPECT_EQ(low_->level_at(-80, 0), ShoreLevel::land);
  EXPECT_EQ(low_->level_at(90, 0), ShoreLevel::ocean);
  EXPECT_EQ(low_->level_at(72, -40), ShoreLevel::land);
  EXPECT_EQ(intermediate_->level_at(0, -150), ShoreLevel::ocean);
  for (const auto& [latitude, longitude] : {std::array<double, 2>{42, 51}, {47.7, -87.5}, {48.86, 2.35}}) {
    EXPECT_EQ(low_->level_at(latitude, longitude), ShoreLevel::coastal) << latitude << ", " << longitude;
    EXPECT_EQ(intermediate_->level_at(latitude, longitude), ShoreLevel::coastal) << latitude << ", " << longitude;
  }
}

// The level on either side of every bin side, 1e-9° away, and round every
// inner corner: each bin's level comes from its own south-west corner and
// segments, so the two sides agree only if the corner order, the segment
// sides and the Antarctic selection are read right (a shoreline passing
// between two points 2e-9° apart is negligibly likely at these sample points).
void expect_continuous(const ShorelineBins& bins, const char* name) {
  constexpr double kOffset = 1e-9;
  const double s = bins.bin_size_deg();
  int compared = 0, different = 0;
  for (int row = 0; row < bins.rows(); ++row) {
    for (int column = 0; column < bins.columns(); ++column) {
      const double south = 90.0 - (row + 1) * s, west = column * s;
      for (int k = 0; k < 8; ++k) {
        const double along = (k + 0.37) / 8 * s;
        ++compared;  // the west side (the east side of the column before, wrapped)
        different += bins.point_level_at(south + along, west - kOffset) !=
                     bins.point_level_at(south + along, west + kOffset);
        if (row > 0) {  // the north side
          ++compared;
          different += bins.point_level_at(south + s - kOffset, west + along) !=
                       bins.point_level_at(south + s + kOffset, west + along);
        }
      }
      if (row > 0) {  // the north-west corner
        const ShoreLevel level = bins.point_level_at(south + s - kOffset, west - kOffset);
        ++compared;
        different += bins.point_level_at(south + s - kOffset, west + kOffset) != level ||
                     bins.point_level_at(south + s + kOffset, west - kOffset) != level ||
                     bins.point_level_at(south + s + kOffset, west + kOffset) != level;
      }
    }
  }
  EXPECT_EQ(different, 0) << name << ": " << different << " of " << compared << " pairs differ";
}

TEST_F(ShorelineBinsGshhgTest, LevelIsContinuousAcrossBins) {
  expect_continuous(*low_, "low, ice front");
  expect_continuous(*low_grounding_, "low, grounding line");
  expect_continuous(*intermediate_, "intermediate, ice front");
}

// levels_along_parallel gives point_level_at's level at every point of the
// surface's coast grid (2048 points per parallel), on 97 parallels, in the
// low and the intermediate files.
TEST_F(ShorelineBinsGshhgTest, LevelsAlongAParallelArePointLevels) {
  std::vector<double> longitudes(2048);
  for (std::size_t i = 0; i < longitudes.size(); ++i) longitudes[i] = -180.0 + (double(i) + 0.5) * 360.0 / 2048.0;
  for (const ShorelineBins* bins : {low_.get(), low_grounding_.get(), intermediate_.get()}) {
    int land = 0, coastal = 0;
    for (int j = 0; j < 97; ++j) {
      const double latitude = 89.0 - j * 178.0 / 96.0 + 0.013;
      std::vector<ShoreLevel> levels(longitudes.size());
      bins->levels_along_parallel(latitude, longitudes.data(), longitudes.size(), levels.data());
      for (std::size_t i = 0; i < longitudes.size(); ++i) {
        ASSERT_EQ(levels[i], bins->point_level_at(latitude, longitudes[i])) << latitude << ", " << longitudes[i];
        land += levels[i] != ShoreLevel::ocean;
        coastal += bins->level_at(latitude, longitudes[i]) == ShoreLevel::coastal;
      }
    }
    EXPECT_GT(land, 20000);
    EXPECT_GT(coastal, 40000);
  }
}

bool is_land(ShoreLevel level) { return level == ShoreLevel::land || level == ShoreLevel::island_in_lake; }

// Earth's surface above the oceans is 29 % of the sphere (Eakins & Sharman
// 2012, ETOPO1's hypsometry). GSHHG's (lakes included, Antarctica to its ice
// front) is compared with a tolerance of 1 % of the sphere (5 Mkm^2: the ice
// shelves are 0.3 %, the lakes 0.5 %).
TEST_F(ShorelineBinsGshhgTest, LandFraction) {
  constexpr double kEarth = 0.29, kTolerance = 0.01;
  constexpr int kColumns = 720, kRows = 360;  // cell centres of a 0.5° grid
  double sphere = 0, above_ocean = 0, land = 0, lakes = 0;
  for (int j = 0; j < kRows; ++j) {
    const double latitude = 90.0 - (j + 0.5) * 180.0 / kRows;
    const double weight = std::cos(latitude * kPi / 180.0);
    for (int i = 0; i < kColumns; ++i) {
      const ShoreLevel level = low_->point_level_at(latitude, (i + 0.5) * 360.0 / kColumns);
      sphere += weight;
      above_ocean += level != ShoreLevel::ocean ? weight : 0;
      land += is_land(level) ? weight : 0;
      lakes += level == ShoreLevel::lake ? weight : 0;
    }
  }
  EXPECT_NEAR(above_ocean / sphere, kEarth, kTolerance);
  EXPECT_GT(lakes / sphere, 0.002);  // the Caspian Sea alone is 0.07 %
  EXPECT_LT(lakes / sphere, 0.01);
  EXPECT_NEAR(land / sphere, above_ocean / sphere - lakes / sphere, 1e-3);

  // From the bins alone, coastal bins counted half: off by at most half the
  // coastal bins' area.
  for (const ShorelineBins* bins : {low_.get(), intermediate_.get()}) {
    const double s = bins->bin_size_deg();
    double estimate = 0, coastal = 0;
    for (int row = 0; row < bins->rows(); ++row) {
      const double north = 90.0 - row * s, south = north - s;
      // The bin's share of the sphere: (sin north - sin south) / 2 / columns.
      const double area = (std::sin(north * kPi / 180.0) - std::sin(south * kPi / 180.0)) / 2.0 / bins->columns();
      for (int column = 0; column < bins->columns(); ++column) {
        const ShoreLevel level = bins->level_at(south + s / 2, (column + 0.5) * s);
        if (level == ShoreLevel::coastal) {
          estimate += area / 2;
          coastal += area;
        } else if (level != ShoreLevel::ocean) {
          estimate += area;
        }
      }
    }
    EXPECT_NEAR(estimate, kEarth, kTolerance + coastal / 2) << bins->bin_size_deg() << "° bins";
  }
}

TEST_F(ShorelineBinsGshhgTest, NonFiniteCoordinatesAreRejected) {
  const double nan = std::nan("");
  EXPECT_THROW(low_->level_at(nan, 0), atmos::Error);
  EXPECT_THROW(low_->point_level_at(0, std::numeric_limits<double>::infinity()), atmos::Error);
  EXPECT_EQ(low_->point_level_at(1e9, 0), low_->point_level_at(90, 0));
}

}  // namespace
