// Land and water on the Earth from the GSHHG shorelines (Wessel & Smith 1996)
// as GMT distributes them: "binned" netCDF files (Debian's gmt-gshhg-low:
// /usr/share/gmt-gshhg/binned_GSHHS_{c,l,i}.nc, crude 20°, low 10° and
// intermediate 5° bins).
//
// GSHHG describes the shorelines as a hierarchy of closed polygons: level 1
// the ocean's shore (continents, islands), level 2 the shores of lakes on
// level-1 land, level 3 islands in those lakes, level 4 ponds on those
// islands. A point's level is that of the innermost polygon around it (0
// outside all: the ocean). Level 2 includes GSHHG's river-lakes, the wide
// parts of large rivers. Antarctica has two shorelines in GSHHG 2.3: the
// ice front (the seaward edge of the ice shelves) and the grounding line
// (where the ice sheet comes afloat).
//
// The binned files cut the polygons along a regular latitude–longitude grid
// of square bins and store, per bin, the level at its four corners and the
// pieces of shoreline ("segments") inside it; their layout is described in
// shoreline_bins.cpp, with the checks made when a file is read.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace atmos::planet {

enum class ShoreLevel : std::uint8_t {
  ocean = 0,
  land = 1,
  lake = 2,
  island_in_lake = 3,
  pond_in_island = 4,
  coastal = 255,  // a bin that a shoreline crosses (ShorelineBins::level_at only)
};

// Which of GSHHG's Antarctic shorelines bounds Antarctica's land: the ice
// front (ice shelves are land; what the eye sees from space, GMT's default)
// or the grounding line (ice shelves are ocean).
enum class AntarcticCoast : std::uint8_t { ice_front, grounding_line };

// GSHHG's low resolution (10° bins): see the choice in shoreline_bins.cpp.
inline constexpr const char* kDefaultShorelineBinsPath = "/usr/share/gmt-gshhg/binned_GSHHS_l.nc";

// One binned GSHHG file in memory: per bin its uniform level or "coastal",
// and, for the coastal bins, the level at a corner and the shoreline
// segments, enough to classify any point exactly (point_level_at). Read-only
// after construction; the queries are safe to call from several threads. The
// constructor calls netCDF, which is not thread-safe: construct one at a time.
class ShorelineBins {
 public:
  // Reads one binned GSHHG file. atmos::Error, with a one-line message naming
  // the file, for a missing or unreadable file, a file that is not netCDF, a
  // netCDF file without the variables of the binned format, and inconsistent
  // contents (a bin count other than rows × columns, segment or point ids out
  // of range, levels outside GSHHG's, a segment whose ends do not lie on the
  // bin sides it names, an uncut bin whose corners disagree).
  explicit ShorelineBins(const std::string& path,
                         AntarcticCoast antarctic_coast = AntarcticCoast::ice_front);

  double bin_size_deg() const { return bin_size_deg_; }
  int rows() const { return rows_; }        // bins along latitude, row 0 at the north pole
  int columns() const { return columns_; }  // bins along longitude, column 0 east of 0°

  // The level of the bin holding (latitude, longitude), in degrees: its
  // uniform level when no shoreline crosses it, ShoreLevel::coastal when one
  // does. Any longitude (wrapped); latitude clamped to [-90, 90]. atmos::Error
  // for a coordinate that is not finite.
  ShoreLevel level_at(double latitude_deg, double longitude_deg) const;

  // The level at the point itself (never coastal): the bin's level when it
  // is uncut, otherwise the level found from the bin's segments. A point on a
  // shoreline gets the level of one of its two sides. Same coordinates and
  // errors as level_at. Cost: linear in the coastal bin's vertex count (at
  // most 2040 in the low file, 8351 in the intermediate one).
  ShoreLevel point_level_at(double latitude_deg, double longitude_deg) const;

  // point_level_at of `count` points on one parallel, the same levels: for
  // each run of points in one coastal bin the bin's vertices are read once,
  // to find the edges that cross the points' parallel, and each point then
  // tests those edges alone. Cost: linear in the vertex count of each
  // coastal bin met, plus the crossing edges per point.
  void levels_along_parallel(double latitude_deg, const double* longitudes_deg, std::size_t count,
                             ShoreLevel* out) const;

 private:
  // A segment's vertex, in 1/65535 of the bin's side from its south-west
  // corner (x eastwards, y northwards).
  struct Vertex {
    std::uint16_t x = 0, y = 0;
  };
  struct Segment {
    std::uint32_t first_vertex = 0;
    std::uint32_t vertex_count = 0;
    std::uint8_t level = 0;  // 1..4: the level inside the polygon it bounds
  };
  struct BinCell {
    int bin = 0;
    double x = 0, y = 0;  // in vertex units (0..65535) from the south-west corner
  };
  BinCell locate(double latitude_deg, double longitude_deg) const;

  double bin_size_deg_ = 0;
  int rows_ = 0, columns_ = 0;
  std::vector<std::uint8_t> bin_levels_;          // ShoreLevel of each bin (uniform or coastal)
  std::vector<std::uint8_t> south_west_levels_;   // level at each bin's south-west corner
  std::vector<std::uint32_t> first_segment_;      // per bin, and one past the last bin
  std::vector<Segment> segments_;
  std::vector<Vertex> vertices_;
};

}  // namespace atmos::planet
