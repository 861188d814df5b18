// A raster read with GDAL (any format GDAL reads: GeoTIFF, COG, VRT, JPEG
// with a VRT around it …, in any coordinate reference system), sampled at
// directions from the planet's centre: elevation (one band, metres),
// imagery (three bands, linear reflectance decoded from sRGB) or a mask
// (one band, non-zero is 1).
//
// Sampling: a direction d (planet frame: z towards the north pole, x
// towards longitude 0) is the point of planetocentric latitude asin(d.z) and
// longitude atan2(d.y, d.x) in the raster's own geographic CRS (the datum of
// the raster; the atmosphere's planet is a sphere, so Earth's geodetic
// latitudes are placed as they are), transformed with PROJ into the
// raster's CRS, then into pixel coordinates by the inverse geotransform, and
// interpolated bilinearly between pixel centres. Pixels that are nodata
// (the band's nodata value, a per-dataset mask or an alpha band: GDAL's
// mask band) take no weight; the weights of the valid ones are renormalised,
// and a point with no valid neighbour is invalid (the caller falls back to
// the next source: the procedural relief). A raster that spans 360 degrees
// of longitude wraps around the antimeridian.
//
// Resolution: sample() takes the spacing of the points it is asked for and
// reads the coarsest overview whose pixel is at most half that spacing
// (GDAL's own rule for overviews), so coarse tiles are prefiltered, not
// aliased. A raster of up to kInMemoryPixels pixels without overviews is
// copied into memory at open, decoded to linear values, and given a box
// filtered pyramid there.
//
// Thread safety: a RasterSource may be sampled from several threads (a
// mutex serialises GDAL's dataset and the PROJ transformations, which are
// not thread-safe).
#pragma once

#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace atmos::planet {

// mask: one band, a yes or no per pixel (non-zero is yes), sampled as the
// fraction of yes among the valid neighbours (0 or 1 on a pixel centre).
enum class RasterKind { elevation, imagery, mask };

struct RasterSettings {
  // A path, or anything GDALOpenEx accepts (VRT XML text, /vsi paths).
  std::string source;
  RasterKind kind = RasterKind::elevation;
  // Elevation: metres per raster unit (after the band's scale and offset).
  // 0: from the band's unit ("m", "ft", "km" …); a raster with no unit
  // then is an error. A value that contradicts a known unit is an error.
  double metres_per_unit = 0.0;
  // The CRS to use instead of the raster's own (any string PROJ accepts:
  // "EPSG:4326", "IAU_2015:49900", WKT, PROJ strings); "" = the raster's.
  std::string crs;
  // For an image with no georeferencing: its edges' longitudes and
  // latitudes, degrees (west, south, east, north); it is then a plate
  // carree in `crs`, or in EPSG:4326 when that is "". None: the raster's
  // own georeferencing.
  std::optional<std::array<double, 4>> bounds_deg;
  // What the planet file calls this source, for error messages.
  std::string role = "elevation";
};

// Rasters larger than this (pixels) with no overviews are refused: a
// coarse tile would read gigapixels. gdaladdo builds the overviews.
inline constexpr double kMaxPixelsWithoutOverviews = 268435456.0;  // 16384^2
// Rasters up to this size with no overviews are decoded into memory at open
// and given their overviews there.
inline constexpr double kInMemoryPixels = 16777216.0;  // 4096^2

class RasterSource {
 public:
  // Opens the raster. atmos::Error, with a one-line message that names the
  // source, for: a missing or unreadable file, a format GDAL does not know
  // or a corrupt file, no georeferencing, an unknown CRS or one PROJ cannot
  // transform into, imagery with fewer than three bands, an elevation with
  // no unit (and none given) or a unit that contradicts the given one, and a
  // raster over kMaxPixelsWithoutOverviews pixels with no overviews.
  explicit RasterSource(const RasterSettings& settings);
  ~RasterSource();
  RasterSource(const RasterSource&) = delete;
  RasterSource& operator=(const RasterSource&) = delete;

  int bands() const;  // values per point: 1 (elevation) or 3 (imagery)

  // Samples the raster at n unit directions for points spaced spacing_m apart
  // on a sphere of radius radius_m (0: the full resolution). out receives
  // bands() values per point (metres, or linear RGB reflectance), valid 1 or
  // 0 per point (an invalid point's values are 0). Reads GDAL's data; an
  // I/O error while reading throws atmos::Error.
  void sample(const glm::dvec3* directions, std::size_t n, double spacing_m, double radius_m, float* out,
              std::uint8_t* valid) const;

  // The length of a full-resolution pixel on a sphere of radius radius_m, m
  // (the larger of its two sides, at the raster's centre).
  double pixel_size_m(double radius_m) const;
  // Whether the raster spans every longitude and latitude.
  bool is_global() const;
  // The range of the raster's valid values (elevation: metres), from its
  // coarsest overview (GDAL's approximate statistics).
  double min_value() const;
  double max_value() const;
  // A direction inside the raster's extent for (u, v) in [0, 1)^2 (uniform
  // in the raster's pixel grid), for sampling the data's roughness.
  glm::dvec3 direction_in_extent(double u, double v) const;

  const std::string& source() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace atmos::planet
