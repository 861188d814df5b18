// atmos — planet files: the JSON format of docs/planet-format.md and the
// built-in presets.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"

namespace atmos {

// Built-in planets (data/planets/<name>.json, compiled in): earth, mars (a
// dusty Mars from measurements), mars-thesis (the Mars of Collienne 2013, §5), titan, venus.
std::vector<std::string> preset_names();

// `name_or_path` is a preset name or the path of a planet JSON file.
Atmosphere load_atmosphere(const std::string& name_or_path);

// Parses planet JSON text; `origin` names the source in error messages.
Atmosphere parse_atmosphere(const std::string& json_text, const std::string& origin);

// The planet's surface when no elevation data is given: a deterministic
// procedural relief in the manner of one of the presets (atmos::Globe,
// atmos/globe.hpp).
enum class SurfaceStyle {
  earth,  // continents and ocean basins, mountain belts
  mars,   // cratered southern highlands, smooth northern lowlands
  venus,  // volcanic plains and a few highlands, few large craters
  titan,  // low relief, linear dunes
  flat,   // the datum sphere (bottom_radius)
};

// The optional "surface" object of a planet file (docs/planet-format.md).
// A raster the globe reads with GDAL (any format and CRS GDAL and PROJ read).
struct SurfaceRaster {
  // A path (relative paths are relative to the planet file) or a GDAL
  // dataset description (VRT XML, /vsi… paths); "" = none.
  std::string source;
  // A CRS that replaces the raster's own ("EPSG:4326", "IAU_2015:49900",
  // WKT, a PROJ string); "" = the raster's.
  std::string crs;
  // Elevation: metres per raster unit from the planet file's "unit"
  // ("m", "km", "ft"); 0 = the raster's own unit.
  double metres_per_unit = 0.0;
  // For an image with no georeferencing (a plain equirectangular JPEG or
  // PNG): the longitudes and latitudes of its edges, degrees, west, south,
  // east, north. None: the raster's own georeferencing.
  std::optional<std::array<double, 4>> bounds_deg;

  bool operator==(const SurfaceRaster&) const = default;
};

struct PlanetSurface {
  SurfaceStyle style = SurfaceStyle::flat;
  std::uint64_t seed = 1;  // the same seed gives the same relief, bit for bit
  // Height of the sea above the datum (bottom_radius), m; none: the
  // style's (Earth: 0; the other styles have no sea).
  std::optional<double> sea_level_m;
  // Heights above the datum (one band); procedural detail of the style is
  // added below its resolution, and the style's relief fills its nodata.
  SurfaceRaster elevation;
  // The ground's colour (three bands, sRGB-encoded), used as its albedo.
  SurfaceRaster imagery;
  // Where the land is, from GMT's binned GSHHG shorelines (Wessel & Smith
  // 1996; Debian's gmt-gshhg-* packages): the style's relief is drawn
  // inside the real coastlines. "" = none.
  std::string coastline;
  // Lakes: water whose surface lies lake_level_m above the datum wherever
  // lake_mask (one band; non-zero is lake, zero or nodata is not) says so
  // and the ground is lower (atmos::Ocean draws it). Both or neither.
  SurfaceRaster lake_mask;
  std::optional<double> lake_level_m;

  bool operator==(const PlanetSurface&) const = default;
};

// The surface of a preset or planet file: its "surface" object, or the flat
// style when it has none. Throws atmos::Error as load_atmosphere does, and
// on an unknown style, a seed that is not a non-negative integer, a sea
// level that is not a finite length, or raster fields that are malformed
// or contradict each other (files are opened by the globe, not here).
PlanetSurface load_surface(const std::string& name_or_path);
PlanetSurface parse_surface(const std::string& json_text, const std::string& origin);
// "earth", "mars", "venus", "titan", "flat" (atmos::Error for another name).
SurfaceStyle surface_style_from_name(const std::string& name);

// A planet file (atmos-planet-1) of `atmosphere` and `surface` (omitted
// when it is the default, flat one): SI units, every spectrum with its own
// samples, raster paths made absolute, so that parse_atmosphere and
// parse_surface read back the same atmosphere and surface, sample for
// sample (the atmosphere's origin aside). Throws atmos::Error for an
// atmosphere that fails validate().
std::string format_planet(const Atmosphere& atmosphere, const PlanetSurface& surface = {});
// format_planet written to `path` (replaced); atmos::Error when it cannot be written.
void write_planet_file(const std::string& path, const Atmosphere& atmosphere, const PlanetSurface& surface = {});
}  // namespace atmos
