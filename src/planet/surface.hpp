// The planet's surface as the globe draws it: the heights and the albedo of
// the ground, from a planet file's surface (atmos/planet_file.hpp): the
// style's procedural relief, elevation and imagery rasters read with GDAL
// (raster_source.hpp), and the real coastlines (shoreline_bins.hpp), with
// the sea drawn flat at sea level.
//
// Heights (above the datum sphere of radius bottom_radius, m):
//  - where elevation data are valid: the data (bilinear, full resolution)
//    plus the style's detail octaves below twice the data's pixel size
//    (Relief::detail_m), zero-mean noise that leaves the data's mean as it
//    is;
//  - elsewhere (no data, nodata, outside a regional raster): the style's
//    relief; the Earth style with a coastline draws its land and sea inside
//    the real coast (Relief's coast_distance_m, a signed distance computed
//    here on a latitude-longitude grid).
//  The drawn surface is the ground or the sea level, whichever is higher.
// Albedo (linear RGB): the imagery where it is valid (prefiltered to the
// mesh's spacing), else the style's colours, with the open ocean's mean
// albedo on the sea.
//
// Heights do not depend on the level of detail (each vertex is a point of one
// surface), so the morph between levels is exact; the imagery does (coarse
// tiles read coarse overviews).
#pragma once

#include <glm/vec3.hpp>

#include <cstddef>
#include <memory>

#include "atmos/planet_file.hpp"
#include "planet/relief.hpp"

namespace atmos::planet {

// The sea level of `surface` above the datum, m: its own, else the style's
// (Earth's 0); -infinity without a sea.
double sea_level_of(const PlanetSurface& surface);

// Throws atmos::Error ("<who>: the sea level ... lies outside the
// atmosphere") unless the surface's own sea level, if it gives one, is
// finite, above the planet's centre and below the top of `atmosphere`.
void validate_sea_level(const PlanetSurface& surface, const Atmosphere& atmosphere, const char* who);

// The lowest drawn height of a surface, m above the datum, estimated
// (surface.cpp): the relief's sampled minimum less a margin, elevation
// data's own minimum less the detail's bound; at least the sea level.
// Surface::min_height_m is the rigorous bound (for culling), far lower.
double lowest_height_m(const PlanetSurface& surface, double radius_m);

class Surface {
 public:
  // Opens the rasters and the coastline file. atmos::Error as RasterSource
  // and ShorelineBins, naming the field (elevation, imagery, coastline).
  Surface(const PlanetSurface& surface, double radius_m);
  ~Surface();
  Surface(const Surface&) = delete;
  Surface& operator=(const Surface&) = delete;

  // The drawn surface's height above the datum, m.
  double height_m(const glm::dvec3& direction) const;
  void heights_m(const glm::dvec3* directions, std::size_t n, double* out) const;
  // The ground's height (below the sea where there is one), m.
  double ground_height_m(const glm::dvec3& direction) const;

  // Albedo at n directions for a mesh of vertex spacing spacing_m (the
  // imagery's overview), linear RGB in [0, 1].
  void albedos(const glm::dvec3* directions, std::size_t n, double spacing_m, glm::vec3* out) const;

  // The lowest drawn height as lowest_height_m estimates it, m.
  double estimated_lowest_m() const;
  // Bounds of the drawn surface's height, m.
  double min_height_m() const { return min_height_m_; }
  double max_height_m() const { return max_height_m_; }

  // A direction for (u, v, w) in [0, 1)^3 where the surface's roughness is
  // that of its data: inside the elevation raster's extent when there is
  // one (w < 1/2), anywhere otherwise (for the level errors' sample).
  glm::dvec3 sample_direction(double u, double v, double w) const;

  // The imagery's pixel on the datum sphere, m; 0 without imagery.
  double imagery_pixel_m() const;

  const Relief& relief() const { return relief_; }
  bool has_elevation_data() const;
  bool has_imagery() const;

  struct Data;  // the rasters and the coast's distance grid (surface.cpp)

 private:
  std::unique_ptr<Data> data_;  // rasters and the coast's distance grid (before relief_: it uses it)
  Relief relief_;
  double min_height_m_ = 0.0, max_height_m_ = 0.0;
  double detail_wavelength_m_ = 0.0;  // the data's detail cut-off
};

}  // namespace atmos::planet
