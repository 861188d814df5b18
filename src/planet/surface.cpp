#include "planet/surface.hpp"

#include <glm/geometric.hpp>

#include <numbers>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "planet/raster_source.hpp"
#include "planet/shoreline_bins.hpp"

namespace atmos::planet {

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
// The open ocean's albedo, about 0.06 for the sun above 25 degrees (Payne
// 1972), slightly blue from the light the water sends back up.
const glm::vec3 kSeaAlbedo(0.045f, 0.06f, 0.08f);

// The signed distance to the coast (positive on land), m, on a grid of
// cells of equal latitude and longitude steps, from a land/sea
// classification of the cells' centres. Distances are chamfer distances
// (Borgefors 1986) with the steps of the sphere's metric at each row:
// east-west R cos(latitude) dlon, north-south R dlat, and their diagonal;
// their error is below 8 % of the distance (eight neighbours with exact
// step lengths; Borgefors 1986), far below what the coastal profile needs.
class CoastDistanceGrid {
 public:
  // land_row(latitude, longitudes, count, out): 1 where the points of one
  // parallel are land, 0 where they are sea.
  template <class LandRow>
  CoastDistanceGrid(int width, int height, double radius_m, const LandRow& land_row)
      : width_(width), height_(height), radius_m_(radius_m) {
    const std::size_t n = std::size_t(width) * std::size_t(height);
    std::vector<std::uint8_t> land(n);
    std::vector<double> longitudes(static_cast<std::size_t>(width));
    for (int i = 0; i < width; ++i) longitudes[std::size_t(i)] = -180.0 + (i + 0.5) * 360.0 / width;
    tbb::parallel_for(0, height, [&](int j) {
      const double lat = 90.0 - (j + 0.5) * 180.0 / height;
      land_row(lat, longitudes.data(), longitudes.size(), land.data() + std::size_t(j) * std::size_t(width));
    });
    const std::vector<float> to_sea = distance_to(land, 0), to_land = distance_to(land, 1);
    const double half_cell = 0.5 * radius_m * std::numbers::pi / height;
    distance_m_.resize(n);
    for (std::size_t k = 0; k < n; ++k)
      distance_m_[k] = land[k] ? float(to_sea[k] - half_cell) : float(half_cell - to_land[k]);
  }

  double cell_size_m() const { return radius_m_ * std::numbers::pi / height_; }

  // Bilinear between cell centres, wrapped in longitude.
  double operator()(const glm::dvec3& d) const {
    const double lat = std::asin(std::clamp(d.z / glm::length(d), -1.0, 1.0)) / kDegree;
    const double lon = std::atan2(d.y, d.x) / kDegree;
    const double x = (lon + 180.0) / 360.0 * width_ - 0.5, y = (90.0 - lat) / 180.0 * height_ - 0.5;
    const int i0 = int(std::floor(x)), j0 = int(std::floor(y));
    const double fx = x - i0, fy = y - j0;
    const auto at = [&](int i, int j) {
      i = ((i % width_) + width_) % width_;
      j = std::clamp(j, 0, height_ - 1);
      return double(distance_m_[std::size_t(j) * std::size_t(width_) + std::size_t(i)]);
    };
    return (1 - fy) * ((1 - fx) * at(i0, j0) + fx * at(i0 + 1, j0)) +
           fy * ((1 - fx) * at(i0, j0 + 1) + fx * at(i0 + 1, j0 + 1));
  }

 private:
  // Chamfer distance from every cell to the nearest cell of class `target`:
  // a forward and a backward sweep, twice, so that distances also cross the
  // antimeridian.
  std::vector<float> distance_to(const std::vector<std::uint8_t>& land, std::uint8_t target) const {
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> d(land.size());
    for (std::size_t k = 0; k < land.size(); ++k) d[k] = land[k] == target ? 0.0 : inf;
    const double dlat = radius_m_ * std::numbers::pi / height_, dlon = 2.0 * std::numbers::pi / width_;
    const auto index = [&](int i, int j) {
      return std::size_t(j) * std::size_t(width_) + std::size_t(((i % width_) + width_) % width_);
    };
    const auto dx = [&](int j) { return radius_m_ * dlon * std::cos((90.0 - (j + 0.5) * 180.0 / height_) * kDegree); };
    for (int round = 0; round < 2; ++round) {
      for (int j = 0; j < height_; ++j) {
        const double x = dx(j), diagonal = std::sqrt(x * x + dlat * dlat);
        for (int i = 0; i < width_; ++i) {
          double& v = d[index(i, j)];
          v = std::min(v, d[index(i - 1, j)] + x);
          if (j > 0) {
            v = std::min(v, d[index(i, j - 1)] + dlat);
            v = std::min(v, d[index(i - 1, j - 1)] + diagonal);
            v = std::min(v, d[index(i + 1, j - 1)] + diagonal);
          }
        }
      }
      for (int j = height_ - 1; j >= 0; --j) {
        const double x = dx(j), diagonal = std::sqrt(x * x + dlat * dlat);
        for (int i = width_ - 1; i >= 0; --i) {
          double& v = d[index(i, j)];
          v = std::min(v, d[index(i + 1, j)] + x);
          if (j + 1 < height_) {
            v = std::min(v, d[index(i, j + 1)] + dlat);
            v = std::min(v, d[index(i + 1, j + 1)] + diagonal);
            v = std::min(v, d[index(i - 1, j + 1)] + diagonal);
          }
        }
      }
    }
    // A grid without a cell of the target class: infinitely far.
    const double far = 4.0 * radius_m_ * std::numbers::pi;
    std::vector<float> out(d.size());
    for (std::size_t k = 0; k < d.size(); ++k) out[k] = float(std::min(d[k], far));
    return out;
  }

  int width_, height_;
  double radius_m_;
  std::vector<float> distance_m_;
};

// Ocean in NASA's Blue Marble and similar true-colour mosaics: dark and
// blue (linear reflectance-like values: red below 0.03, blue above red).
// Used only where no coastline file is given.
bool imagery_is_sea(const glm::vec3& rgb) { return rgb.x < 0.03f && rgb.z > 1.2f * rgb.x && rgb.z > rgb.y * 0.8f; }

RasterSettings raster_settings(const SurfaceRaster& r, RasterKind kind, const char* role) {
  RasterSettings s;
  s.source = r.source;
  s.kind = kind;
  s.metres_per_unit = r.metres_per_unit;
  s.crs = r.crs;
  s.bounds_deg = r.bounds_deg;
  s.role = role;
  return s;
}

}  // namespace

double sea_level_of(const PlanetSurface& s) {
  if (s.sea_level_m) return *s.sea_level_m;
  return s.style == SurfaceStyle::earth ? 0.0 : -std::numeric_limits<double>::infinity();
}

void validate_sea_level(const PlanetSurface& surface, const Atmosphere& atmosphere, const char* who) {
  const double top_m = atmosphere.top_radius_m - atmosphere.bottom_radius_m;
  if (surface.sea_level_m && !(std::isfinite(*surface.sea_level_m) &&
                               *surface.sea_level_m > -atmosphere.bottom_radius_m && *surface.sea_level_m < top_m))
    throw Error(std::string(who) + ": the sea level " + std::to_string(*surface.sea_level_m) +
                " m lies outside the atmosphere (below the planet's centre or above its top, " +
                std::to_string(top_m) + " m)");
}

struct Surface::Data {
  std::unique_ptr<RasterSource> elevation, imagery;
  std::unique_ptr<CoastDistanceGrid> coast;
  double sea_level_m = -std::numeric_limits<double>::infinity();
};

namespace {

// Grid of the coast's distance: 2048 x 1024 cells (about 20 km on Earth,
// the resolution of Debian's Blue Marble).
constexpr int kCoastGridWidth = 2048;

std::unique_ptr<Surface::Data> open_data(const PlanetSurface& s, double radius_m) {
  if (!(std::isfinite(radius_m) && radius_m > 0.0)) throw Error("surface: the radius must be finite and positive");
  auto data = std::make_unique<Surface::Data>();
  if (!s.elevation.source.empty())
    data->elevation = std::make_unique<RasterSource>(raster_settings(s.elevation, RasterKind::elevation, "elevation"));
  if (!s.imagery.source.empty())
    data->imagery = std::make_unique<RasterSource>(raster_settings(s.imagery, RasterKind::imagery, "imagery"));
  data->sea_level_m = sea_level_of(s);
  // The Earth style's land and sea from the real coast, where no elevation
  // data cover the globe: the coastline file, or the imagery's colours.
  const bool global_data = data->elevation && data->elevation->is_global();
  if (s.style == SurfaceStyle::earth && !global_data && (!s.coastline.empty() || data->imagery)) {
    const int width = kCoastGridWidth, height = kCoastGridWidth / 2;
    if (!s.coastline.empty()) {
      const ShorelineBins bins(s.coastline);
      data->coast = std::make_unique<CoastDistanceGrid>(
          width, height, radius_m, [&](double lat, const double* lons, std::size_t count, std::uint8_t* out) {
            std::vector<ShoreLevel> levels(count);
            bins.levels_along_parallel(lat, lons, count, levels.data());
            for (std::size_t i = 0; i < count; ++i) out[i] = levels[i] != ShoreLevel::ocean ? 1 : 0;
          });
    } else {
      const RasterSource& imagery = *data->imagery;
      const double spacing = radius_m * std::numbers::pi / height;
      data->coast = std::make_unique<CoastDistanceGrid>(
          width, height, radius_m, [&](double lat, const double* lons, std::size_t count, std::uint8_t* out) {
            for (std::size_t i = 0; i < count; ++i) {
              const double lon = lons[i];
              const glm::dvec3 d(std::cos(lat * kDegree) * std::cos(lon * kDegree),
                                 std::cos(lat * kDegree) * std::sin(lon * kDegree), std::sin(lat * kDegree));
              float rgb[3];
              std::uint8_t ok = 0;
              imagery.sample(&d, 1, spacing, radius_m, rgb, &ok);
              out[i] = ok != 0 && !imagery_is_sea(glm::vec3(rgb[0], rgb[1], rgb[2])) ? 1 : 0;
            }
          });
    }
  }
  return data;
}

ReliefSettings relief_settings(const PlanetSurface& s, double radius_m, const Surface::Data& data) {
  ReliefSettings r{s.style, s.seed, radius_m, s.sea_level_m, {}, 0.0};
  if (data.coast) {
    const CoastDistanceGrid* grid = data.coast.get();
    r.coast_distance_m = [grid](const glm::dvec3& d) { return (*grid)(d); };
    r.coast_resolution_m = grid->cell_size_m();
  }
  return r;
}

}  // namespace

namespace {

// The drawn surface's height range from the relief's and the data's (the
// coast only moves land and sea within the relief's range).
void height_range(const Relief& relief, const RasterSource* elevation, double detail_wavelength_m, double sea_level_m,
                  double& min_m, double& max_m) {
  double lo = relief.min_height_m(), hi = relief.max_height_m();
  if (elevation != nullptr) {
    const double detail = relief.detail_bound_m(detail_wavelength_m);
    const double data_lo = elevation->min_value() - detail, data_hi = elevation->max_value() + detail;
    // Where the data cover everything, the relief never shows.
    if (elevation->is_global()) {
      lo = data_lo;
      hi = data_hi;
    } else {
      lo = std::min(lo, data_lo);
      hi = std::max(hi, data_hi);
    }
  }
  min_m = std::max(lo, sea_level_m);
  max_m = std::max(hi, sea_level_m);
}

}  // namespace

// The relief's lowest point, estimated: the minimum over a Fibonacci
// lattice of 40000 directions (about 110 km apart on Earth, 60 km on
// Mars; González 2010) minus a tenth of the sampled range, and never
// below the rigorous bound. That bound adds every term's worst case at
// once, which no point reaches (Mars: -19 km, against -11 km sampled): an
// atmosphere extended that far would put the tables' ground, and its
// reflected light, far below any real ground.
double estimated_lowest_m(const Relief& relief) {
  constexpr int kSamples = 40000;
  constexpr double kGolden = 2.39996322972865332;  // pi (3 - sqrt 5)
  struct Range {
    double low = std::numeric_limits<double>::infinity(), high = -std::numeric_limits<double>::infinity();
  };
  const Range r = tbb::parallel_reduce(
      tbb::blocked_range<int>(0, kSamples), Range{},
      [&](const tbb::blocked_range<int>& block, Range range) {
        for (int i = block.begin(); i < block.end(); ++i) {
          const double z = 1.0 - (2.0 * i + 1.0) / kSamples, ring = std::sqrt(std::max(0.0, 1.0 - z * z));
          const double phi = kGolden * i;
          const double h = relief.height_m(glm::dvec3(ring * std::cos(phi), ring * std::sin(phi), z));
          range.low = std::min(range.low, h);
          range.high = std::max(range.high, h);
        }
        return range;
      },
      [](Range a, const Range& b) {
        a.low = std::min(a.low, b.low);
        a.high = std::max(a.high, b.high);
        return a;
      });
  return std::max(relief.min_height_m(), r.low - 0.1 * (r.high - r.low));
}

double estimated_lowest_m(const Relief& relief, const RasterSource* elevation, double sea_level_m) {
  double lo = estimated_lowest_m(relief);
  if (elevation != nullptr) {
    const double detail_wavelength = 2.0 * elevation->pixel_size_m(relief.settings().radius_m);
    const double data_lo = elevation->min_value() - relief.detail_bound_m(detail_wavelength);
    lo = elevation->is_global() ? data_lo : std::min(lo, data_lo);
  }
  return std::max(lo, sea_level_m);
}

double lowest_height_m(const PlanetSurface& surface, double radius_m) {
  const Relief relief(ReliefSettings{surface.style, surface.seed, radius_m, surface.sea_level_m, {}, 0.0});
  std::unique_ptr<RasterSource> elevation;
  if (!surface.elevation.source.empty())
    elevation = std::make_unique<RasterSource>(raster_settings(surface.elevation, RasterKind::elevation, "elevation"));
  return estimated_lowest_m(relief, elevation.get(), sea_level_of(surface));
}

double Surface::estimated_lowest_m() const {
  return planet::estimated_lowest_m(relief_, data_->elevation.get(), data_->sea_level_m);
}

Surface::Surface(const PlanetSurface& surface, double radius_m)
    : data_(open_data(surface, radius_m)), relief_(relief_settings(surface, radius_m, *data_)) {
  if (data_->elevation) detail_wavelength_m_ = 2.0 * data_->elevation->pixel_size_m(radius_m);
  height_range(relief_, data_->elevation.get(), detail_wavelength_m_, data_->sea_level_m, min_height_m_,
               max_height_m_);
}

Surface::~Surface() = default;

bool Surface::has_elevation_data() const { return bool(data_->elevation); }
bool Surface::has_imagery() const { return bool(data_->imagery); }

double Surface::imagery_pixel_m() const {
  return data_->imagery ? data_->imagery->pixel_size_m(relief_.settings().radius_m) : 0.0;
}

void Surface::heights_m(const glm::dvec3* directions, std::size_t n, double* out) const {
  if (data_->elevation) {
    std::vector<float> values(n);
    std::vector<std::uint8_t> valid(n);
    data_->elevation->sample(directions, n, 0.0, relief_.settings().radius_m, values.data(), valid.data());
    for (std::size_t i = 0; i < n; ++i)
      out[i] = valid[i] ? double(values[i]) + relief_.detail_m(directions[i], detail_wavelength_m_)
                        : relief_.height_m(directions[i]);
  } else {
    for (std::size_t i = 0; i < n; ++i) out[i] = relief_.height_m(directions[i]);
  }
  for (std::size_t i = 0; i < n; ++i) out[i] = std::max(out[i], data_->sea_level_m);
}

double Surface::ground_height_m(const glm::dvec3& direction) const {
  if (data_->elevation) {
    float value = 0;
    std::uint8_t valid = 0;
    data_->elevation->sample(&direction, 1, 0.0, relief_.settings().radius_m, &value, &valid);
    if (valid) return double(value) + relief_.detail_m(direction, detail_wavelength_m_);
  }
  return relief_.height_m(direction);
}

double Surface::height_m(const glm::dvec3& direction) const {
  return std::max(ground_height_m(direction), data_->sea_level_m);
}

void Surface::albedos(const glm::dvec3* directions, std::size_t n, double spacing_m, glm::vec3* out) const {
  std::vector<float> rgb;
  std::vector<std::uint8_t> valid(n, 0);
  if (data_->imagery) {
    rgb.resize(3 * n);
    data_->imagery->sample(directions, n, spacing_m, relief_.settings().radius_m, rgb.data(), valid.data());
  }
  // Below the imagery's pixel, down to twice the mesh's spacing (finer
  // would alias between vertices), the style's brightness variation.
  const double pixel = imagery_pixel_m();
  for (std::size_t i = 0; i < n; ++i) {
    if (valid[i]) {
      const double variation = pixel > 4.0 * spacing_m
                                   ? relief_.albedo_variation(directions[i], 0.5 * pixel, 2.0 * spacing_m)
                                   : 0.0;
      out[i] = glm::clamp(glm::vec3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]) * float(1.0 + variation), 0.0f, 1.0f);
    } else if (ground_height_m(directions[i]) < data_->sea_level_m) {
      out[i] = kSeaAlbedo;
    } else {
      out[i] = relief_.albedo(directions[i]);
    }
  }
}

glm::dvec3 Surface::sample_direction(double u, double v, double w) const {
  if (data_->elevation && w < 0.5) return data_->elevation->direction_in_extent(u, v);
  // Uniform on the sphere (Archimedes: z uniform in [-1, 1]).
  const double z = 2.0 * u - 1.0, phi = 2.0 * std::numbers::pi * v, r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

}  // namespace atmos::planet
