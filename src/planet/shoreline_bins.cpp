// GMT's binned GSHHG files and the level of a point (Wessel & Smith 1996).
//
// The file layout (netCDF; every variable one-dimensional, scalars as arrays
// of one element):
//   Bin_size_in_minutes                 s, the side of a square bin, arcmin
//   N_bins_in_360_longitude_range       columns = 21600 / s
//   N_bins_in_180_degree_latitude_range rows = 10800 / s
//   N_bins_in_file, N_segments_in_file, N_points_in_file: the array lengths
// per bin b (row-major from the north-west: row b / columns spans latitudes
// 90 - (r + 1) s .. 90 - r s, column b % columns longitudes c s .. (c + 1) s
// east of Greenwich):
//   Id_of_first_segment_in_a_bin, N_segments_in_a_bin: its segments are a
//     contiguous run of the segment arrays;
//   Embedded_node_levels_in_a_bin: the levels at its four corners, 3 bits
//     each: bits 9-11 south-west, 6-8 south-east, 3-5 north-east, 0-2
//     north-west (a counter-clockwise walk round the bin). The order is read
//     off the files: in it, and in no other, every corner shared by
//     neighbouring bins has one level;
//   Embedded_node_levels_in_a_bin_ANT: the same with Antarctica bounded by
//     its grounding line;
// per segment (a piece of one polygon's boundary inside one bin):
//   Embedded_npts_levels_exit_entry_for_a_segment: bits 9 and up the vertex
//     count, bits 6-8 the level of the polygon, bits 3-5 the bin side its
//     first vertex lies on, bits 0-2 that of its last vertex (0 south, 1 east,
//     2 north, 3 west; 4: none, the segment is a whole ring inside the bin,
//     its first vertex repeated last);
//   Id_of_first_point_in_a_segment: its vertices are a contiguous run;
//   Embedded_ANT_flag: 1 on the pieces of Antarctica's ice front that are
//     not also grounding line;
// per point:
//   Relative_longitude_from_SW_corner_of_bin,
//   Relative_latitude_from_SW_corner_of_bin: 16-bit offsets from the bin's
//     south-west corner in 1/65535 of its side, stored as signed shorts (the
//     offset is the value modulo 65536).
// The GSHHG 2.3.7 files (Debian gmt-gshhg-low) have node levels 0-2 and
// segment levels 1-4 and 6; 6 marks the pieces of Antarctica's grounding line
// that are not also ice front, so that the ice front is the level-1 segments
// and the grounding line the level-1 segments without the ANT flag plus the
// level-6 ones. (GSHHG's own polygon files use 5 for the ice front; no
// binned segment carries it.)
//
// The level of a point. Let A_L be the region inside the level-L polygons.
// GSHHG's polygons do not cross (Wessel & Smith 1996; GSHHG 2.0 and later
// are checked free of crossings), those of one level are disjoint and each
// lies inside one of the level below, so A_4 ⊂ A_3 ⊂ A_2 ⊂ A_1 and
// level(p) = max{L : p ∈ A_L} (0 if none). By the Jordan curve theorem a path
// that avoids the vertices enters or leaves A_L at every crossing of a
// level-L shoreline, and inside a bin the level-L shorelines are exactly the
// bin's level-L segments (the file cuts every polygon at the bin sides). So a
// path inside the bin from its south-west corner, whose level the file gives,
// to p decides p. The path runs north at an infinitesimal distance d east of
// the west side up to p's parallel shifted north by an infinitesimal e >> d,
// then east along that parallel to p. With integer vertex coordinates it
// crosses
//   on the west leg: each edge with exactly one end on the west side (x = 0)
//     whose end there is not north of p (y <= p.y);
//   on the parallel: each edge with one end north of p (y > p.y) and the
//     other not, where it passes west of p (p lies east of the edge: the sign
//     of a cross product);
// and an edge lying in the west side is crossed by neither leg. (This is the
// even-odd rule's half-open convention for vertices on the parallel, made
// explicit.) No vertex may lie on a bin corner (checked when reading), so the
// corner's level is the level next to it inside the bin. A point on a
// shoreline gets one of its sides; a point on the west side, the level just
// inside the bin.
//
// The default file is the low resolution (10° bins): its shoreline vertices
// lie a median 12 km apart (crude 47 km, intermediate 3 km), finer than the
// 20 km pixels of the Blue Marble image the globe drapes (2048 x 1024, Debian
// xplanet-images); the intermediate file has five times the vertices and
// reads in about four times as long, for detail the image does not show.
#include "planet/shoreline_bins.hpp"

#include "atmos/atmosphere.hpp"

#include <netcdf.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <string>

namespace atmos::planet {

namespace {

constexpr int kVertexUnits = 65535;  // a bin's side in vertex units
constexpr int kSideSouth = 0, kSideEast = 1, kSideNorth = 2, kSideWest = 3, kSideNone = 4;
constexpr int kMaxNodeLevel = 4;
constexpr int kGroundingLineLevel = 6;

// The side of the bin a vertex lies on, in the order the file's side codes
// use; kSideNone for an interior vertex. A vertex on a corner is on two
// sides and is rejected before this is asked.
int side_of(int x, int y) {
  if (y == 0) return kSideSouth;
  if (x == kVertexUnits) return kSideEast;
  if (y == kVertexUnits) return kSideNorth;
  if (x == 0) return kSideWest;
  return kSideNone;
}

// An open netCDF file, closed on every path out of the reader.
class NetcdfFile {
 public:
  explicit NetcdfFile(const std::string& path) : path_(path) {
    const int status = nc_open(path.c_str(), NC_NOWRITE, &id_);
    if (status == NC_ENOTNC) throw Error("shoreline bins " + path + " is not a netCDF file");
    if (status != NC_NOERR) throw Error("cannot read shoreline bins " + path + ": " + nc_strerror(status));
  }
  ~NetcdfFile() { nc_close(id_); }
  NetcdfFile(const NetcdfFile&) = delete;
  NetcdfFile& operator=(const NetcdfFile&) = delete;

  [[noreturn]] void fail(const std::string& what) const {
    throw Error("shoreline bins " + path_ + ": " + what);
  }

  // A one-dimensional integer variable of `length` values (>= 0), converted
  // to int by netCDF.
  std::vector<int> ints(const char* name, int length) const {
    int variable = 0;
    if (nc_inq_varid(id_, name, &variable) != NC_NOERR) {
      fail(std::string("no variable ") + name + " (not a GMT binned GSHHG file)");
    }
    nc_type type = NC_NAT;
    int dimensions = 0;
    if (nc_inq_vartype(id_, variable, &type) != NC_NOERR || nc_inq_varndims(id_, variable, &dimensions) != NC_NOERR) {
      fail(std::string("cannot read variable ") + name);
    }
    if (type != NC_BYTE && type != NC_SHORT && type != NC_INT && type != NC_USHORT) {
      fail(std::string("variable ") + name + " is not an integer array");
    }
    if (dimensions != 1) fail(std::string("variable ") + name + " is not one-dimensional");
    int dimension = 0;
    std::size_t size = 0;
    if (nc_inq_vardimid(id_, variable, &dimension) != NC_NOERR || nc_inq_dimlen(id_, dimension, &size) != NC_NOERR) {
      fail(std::string("cannot read variable ") + name);
    }
    if (size != static_cast<std::size_t>(length)) {
      fail(std::string("variable ") + name + " has " + std::to_string(size) + " values, expected " +
           std::to_string(length));
    }
    std::vector<int> values(size);
    if (size > 0) {
      const int status = nc_get_var_int(id_, variable, values.data());
      if (status != NC_NOERR) fail(std::string("cannot read variable ") + name + ": " + nc_strerror(status));
    }
    return values;
  }

  int scalar(const char* name) const { return ints(name, 1)[0]; }

 private:
  std::string path_;
  int id_ = -1;
};

// The level in bits [shift, shift + 3) of a packed corner-levels value.
int node_level(int packed, int shift) {
  return static_cast<int>((static_cast<unsigned>(packed) >> shift) & 7u);
}

}  // namespace

ShorelineBins::ShorelineBins(const std::string& path, AntarcticCoast antarctic_coast) {
  const NetcdfFile file(path);

  const int bin_minutes = file.scalar("Bin_size_in_minutes");
  columns_ = file.scalar("N_bins_in_360_longitude_range");
  rows_ = file.scalar("N_bins_in_180_degree_latitude_range");
  const int bin_count = file.scalar("N_bins_in_file");
  const int segment_count = file.scalar("N_segments_in_file");
  const int point_count = file.scalar("N_points_in_file");
  if (bin_minutes <= 0 || columns_ <= 0 || rows_ <= 0 || static_cast<long long>(bin_minutes) * columns_ != 360 * 60 ||
      static_cast<long long>(bin_minutes) * rows_ != 180 * 60) {
    file.fail("bins of " + std::to_string(bin_minutes) + "' in " + std::to_string(rows_) + " rows and " +
              std::to_string(columns_) + " columns do not tile the sphere");
  }
  if (bin_count != rows_ * columns_) {
    file.fail(std::to_string(bin_count) + " bins, expected rows x columns = " + std::to_string(rows_ * columns_));
  }
  if (segment_count < 0 || point_count < 0) file.fail("negative segment or point count");
  bin_size_deg_ = bin_minutes / 60.0;

  const bool grounding_line = antarctic_coast == AntarcticCoast::grounding_line;
  const std::vector<int> first_segment = file.ints("Id_of_first_segment_in_a_bin", bin_count);
  const std::vector<int> bin_segments = file.ints("N_segments_in_a_bin", bin_count);
  const std::vector<int> nodes =
      file.ints(grounding_line ? "Embedded_node_levels_in_a_bin_ANT" : "Embedded_node_levels_in_a_bin", bin_count);
  const std::vector<int> segment_info = file.ints("Embedded_npts_levels_exit_entry_for_a_segment", segment_count);
  const std::vector<int> first_point = file.ints("Id_of_first_point_in_a_segment", segment_count);
  const std::vector<int> ice_front_flag =
      grounding_line ? file.ints("Embedded_ANT_flag", segment_count) : std::vector<int>(segment_count, 0);
  const std::vector<int> x = file.ints("Relative_longitude_from_SW_corner_of_bin", point_count);
  const std::vector<int> y = file.ints("Relative_latitude_from_SW_corner_of_bin", point_count);

  bin_levels_.resize(bin_count);
  south_west_levels_.resize(bin_count);
  first_segment_.assign(1, 0);
  first_segment_.reserve(static_cast<std::size_t>(bin_count) + 1);
  segments_.reserve(segment_count);
  vertices_.reserve(point_count);

  for (int b = 0; b < bin_count; ++b) {
    const std::string bin_name = "bin " + std::to_string(b);
    if (nodes[b] < 0 || nodes[b] >= (1 << 12)) file.fail(bin_name + " has corner levels out of range");
    int corner[4];  // south-west, south-east, north-east, north-west
    for (int k = 0; k < 4; ++k) {
      corner[k] = node_level(nodes[b], 9 - 3 * k);
      if (corner[k] > kMaxNodeLevel) file.fail(bin_name + " has a corner level " + std::to_string(corner[k]));
    }
    if (first_segment[b] < 0 || bin_segments[b] < 0 ||
        static_cast<long long>(first_segment[b]) + bin_segments[b] > segment_count) {
      file.fail(bin_name + "'s segments are out of range");
    }

    for (int s = first_segment[b]; s < first_segment[b] + bin_segments[b]; ++s) {
      const std::string segment_name = "segment " + std::to_string(s);
      if (segment_info[s] < 0) file.fail(segment_name + " has a negative packed header");
      const auto info = static_cast<unsigned>(segment_info[s]);
      const auto vertex_count = static_cast<long long>(info >> 9);
      int level = static_cast<int>((info >> 6) & 7u);
      const int first_side = static_cast<int>((info >> 3) & 7u);
      const int last_side = static_cast<int>(info & 7u);
      if (level == kGroundingLineLevel) {
        if (!grounding_line) continue;
        level = 1;
      } else if (level < 1 || level > kMaxNodeLevel) {
        file.fail(segment_name + " has level " + std::to_string(level));
      } else if (ice_front_flag[s] == 1) {
        continue;  // ice front only, and the grounding line bounds the land
      }
      if (first_side > kSideNone || last_side > kSideNone || (first_side == kSideNone) != (last_side == kSideNone)) {
        file.fail(segment_name + " has bin sides " + std::to_string(first_side) + " and " + std::to_string(last_side));
      }
      if (first_point[s] < 0 || vertex_count < 2 || first_point[s] + vertex_count > point_count) {
        file.fail(segment_name + "'s points are out of range");
      }

      Segment segment;
      segment.first_vertex = static_cast<std::uint32_t>(vertices_.size());
      segment.vertex_count = static_cast<std::uint32_t>(vertex_count);
      segment.level = static_cast<std::uint8_t>(level);
      for (long long i = first_point[s]; i < first_point[s] + vertex_count; ++i) {
        if (x[i] < -32768 || x[i] > kVertexUnits || y[i] < -32768 || y[i] > kVertexUnits) {
          file.fail("point " + std::to_string(i) + " is outside its bin");
        }
        // The offset is the stored short modulo 2^16 (well defined for the
        // conversion to an unsigned type).
        const Vertex vertex{static_cast<std::uint16_t>(x[i]), static_cast<std::uint16_t>(y[i])};
        if ((vertex.x == 0 || vertex.x == kVertexUnits) && (vertex.y == 0 || vertex.y == kVertexUnits)) {
          file.fail("point " + std::to_string(i) + " lies on a corner of " + bin_name);
        }
        vertices_.push_back(vertex);
      }
      const Vertex& first = vertices_[segment.first_vertex];
      const Vertex& last = vertices_.back();
      if (first_side == kSideNone) {
        if (first.x != last.x || first.y != last.y) file.fail(segment_name + " is a ring that does not close");
      } else if (side_of(first.x, first.y) != first_side || side_of(last.x, last.y) != last_side) {
        file.fail(segment_name + "'s ends do not lie on the bin sides it names");
      }
      segments_.push_back(segment);
    }

    const auto segments_in_bin = static_cast<std::uint32_t>(segments_.size()) - first_segment_.back();
    first_segment_.push_back(static_cast<std::uint32_t>(segments_.size()));
    south_west_levels_[b] = static_cast<std::uint8_t>(corner[0]);
    if (segments_in_bin > 0) {
      bin_levels_[b] = static_cast<std::uint8_t>(ShoreLevel::coastal);
    } else if (corner[1] != corner[0] || corner[2] != corner[0] || corner[3] != corner[0]) {
      file.fail(bin_name + " has no shoreline but corners of different levels");
    } else {
      bin_levels_[b] = static_cast<std::uint8_t>(corner[0]);
    }
  }
}

ShorelineBins::BinCell ShorelineBins::locate(double latitude_deg, double longitude_deg) const {
  if (!std::isfinite(latitude_deg) || !std::isfinite(longitude_deg)) {
    throw Error("shoreline level at (" + std::to_string(latitude_deg) + ", " + std::to_string(longitude_deg) +
                "): the latitude and longitude must be finite");
  }
  const double latitude = std::clamp(latitude_deg, -90.0, 90.0);
  const double longitude = longitude_deg - 360.0 * std::floor(longitude_deg / 360.0);  // [0, 360], 360 by rounding
  const double row_position = (90.0 - latitude) / bin_size_deg_;
  const double column_position = longitude / bin_size_deg_;
  const int row = std::clamp(static_cast<int>(row_position), 0, rows_ - 1);
  const int column = std::clamp(static_cast<int>(column_position), 0, columns_ - 1);
  BinCell cell;
  cell.bin = row * columns_ + column;
  cell.x = std::clamp((column_position - column) * kVertexUnits, 0.0, double{kVertexUnits});
  cell.y = std::clamp((row + 1 - row_position) * kVertexUnits, 0.0, double{kVertexUnits});
  return cell;
}

ShoreLevel ShorelineBins::level_at(double latitude_deg, double longitude_deg) const {
  return static_cast<ShoreLevel>(bin_levels_[locate(latitude_deg, longitude_deg).bin]);
}

ShoreLevel ShorelineBins::point_level_at(double latitude_deg, double longitude_deg) const {
  ShoreLevel level = ShoreLevel::ocean;
  levels_along_parallel(latitude_deg, &longitude_deg, 1, &level);
  return level;
}

// The path's crossings (the level of a point, above), split by what depends
// on the point's x: those of the west leg depend on the parallel alone, and
// an edge can pass west of the point only if it crosses the parallel. Bit L
// of `inside` says whether the point is in A_L: set for L <= the corner's
// level, then flipped at each crossing of a level-L segment.
void ShorelineBins::levels_along_parallel(double latitude_deg, const double* longitudes_deg, std::size_t count,
                                          ShoreLevel* out) const {
  struct Crossing {
    Vertex low, high;
    unsigned bit = 0;
  };
  std::vector<Crossing> crossings;
  unsigned west_toggles = 0;  // bits of the segments with an odd count of west-side flips below y
  int run_bin = -1;
  double run_y = 0.0;
  for (std::size_t k = 0; k < count; ++k) {
    const BinCell cell = locate(latitude_deg, longitudes_deg[k]);
    const auto uniform = static_cast<ShoreLevel>(bin_levels_[cell.bin]);
    if (uniform != ShoreLevel::coastal) {
      out[k] = uniform;
      continue;
    }
    const double px = cell.x, py = cell.y;
    if (cell.bin != run_bin || py != run_y) {
      run_bin = cell.bin;
      run_y = py;
      crossings.clear();
      west_toggles = 0;
      for (std::uint32_t s = first_segment_[cell.bin]; s < first_segment_[cell.bin + 1]; ++s) {
        const Segment& segment = segments_[s];
        const unsigned bit = 1u << segment.level;
        const Vertex* vertex = vertices_.data() + segment.first_vertex;
        for (std::uint32_t i = 0; i + 1 < segment.vertex_count; ++i) {
          const Vertex& a = vertex[i];
          const Vertex& b = vertex[i + 1];
          const bool a_west = a.x == 0, b_west = b.x == 0;
          if (a_west != b_west && (a_west ? a.y : b.y) <= py) west_toggles ^= bit;
          const bool a_north = a.y > py, b_north = b.y > py;
          if (a_north != b_north && !(a_west && b_west)) crossings.push_back({a_north ? b : a, a_north ? a : b, bit});
        }
      }
    }
    unsigned inside = ((2u << south_west_levels_[cell.bin]) - 2u) ^ west_toggles;
    for (const Crossing& c : crossings) {
      const double cross = (static_cast<double>(c.high.x) - c.low.x) * (py - c.low.y) -
                           (static_cast<double>(c.high.y) - c.low.y) * (px - c.low.x);
      if (cross < 0) inside ^= c.bit;
    }
    inside &= ~1u;
    out[k] = static_cast<ShoreLevel>(inside == 0 ? 0 : std::bit_width(inside) - 1);
  }
}

}  // namespace atmos::planet
