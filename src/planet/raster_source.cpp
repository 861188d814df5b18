#include "planet/raster_source.hpp"

#include <cpl_error.h>
#include <gdal.h>
#include <numbers>
#include <ogr_srs_api.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

#include "atmos/atmosphere.hpp"

namespace atmos::planet {

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr float kInvalid = std::numeric_limits<float>::quiet_NaN();

// GDAL reports errors through a per-thread handler; this one keeps the last
// failure's message, so that it can be thrown as an atmos::Error that names
// the source, instead of GDAL printing to stderr.
struct ErrorCapture {
  std::string message;
};

void CPL_STDCALL capture_error(CPLErr error_class, CPLErrorNum, const char* message) {
  auto* capture = static_cast<ErrorCapture*>(CPLGetErrorHandlerUserData());
  if (capture != nullptr && error_class >= CE_Failure && message != nullptr) capture->message = message;
}

class ScopedErrorCapture {
 public:
  ScopedErrorCapture() { CPLPushErrorHandlerEx(capture_error, &capture_); }
  ~ScopedErrorCapture() { CPLPopErrorHandler(); }
  ScopedErrorCapture(const ScopedErrorCapture&) = delete;
  ScopedErrorCapture& operator=(const ScopedErrorCapture&) = delete;
  std::string last() const { return capture_.message.empty() ? std::string("unknown GDAL error") : capture_.message; }

 private:
  ErrorCapture capture_;
};

void register_drivers() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

// The sRGB transfer function's inverse (IEC 61966-2-1).
float srgb_to_linear(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

long floor_to_long(double x) { return long(std::floor(x)); }
long wrap(long i, long n) { return ((i % n) + n) % n; }

glm::dvec3 direction_of(double latitude_deg, double longitude_deg) {
  const double lat = latitude_deg * kDegree, lon = longitude_deg * kDegree;
  return {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

// A grid of values, bands interleaved, NaN where invalid: a whole level in
// memory, or a window read from GDAL. Covers columns x0 .. x0 + width - 1
// (modulo the level's width when it wraps) and rows y0 .. y0 + height - 1.
struct Grid {
  long x0 = 0, y0 = 0, width = 0, height = 0;
  long level_width = 0, level_height = 0;
  bool wraps = false;
  int bands = 1;
  const float* data = nullptr;

  const float* at(long i, long j) const {
    if (wraps) {
      i = wrap(i, level_width);
      j = std::clamp(j, 0L, level_height - 1);
      i = wrap(i - x0, level_width);
    } else {
      if (i < 0 || j < 0 || i >= level_width || j >= level_height) return nullptr;
      i -= x0;
    }
    j -= y0;
    if (i < 0 || j < 0 || i >= width || j >= height) return nullptr;
    const float* v = data + (std::size_t(j) * std::size_t(width) + std::size_t(i)) * std::size_t(bands);
    return std::isnan(v[0]) ? nullptr : v;
  }

  // Bilinear between pixel centres (pixel (i, j) covers [i, i+1) x [j, j+1));
  // invalid neighbours take no weight.
  bool bilinear(double px, double py, float* out) const {
    const double x = px - 0.5, y = py - 0.5;
    const long i0 = floor_to_long(x), j0 = floor_to_long(y);
    const double fx = x - double(i0), fy = y - double(j0);
    double sum[3] = {0, 0, 0}, weight = 0;
    for (int b = 0; b <= 1; ++b)
      for (int a = 0; a <= 1; ++a) {
        const float* v = at(i0 + a, j0 + b);
        if (v == nullptr) continue;
        const double w = (a ? fx : 1.0 - fx) * (b ? fy : 1.0 - fy);
        for (int k = 0; k < bands; ++k) sum[k] += w * double(v[k]);
        weight += w;
      }
    if (!(weight > 1e-9)) return false;
    for (int k = 0; k < bands; ++k) out[k] = float(sum[k] / weight);
    return true;
  }
};

// One level of the in-memory pyramid.
struct MemoryLevel {
  long width = 0, height = 0;
  std::vector<float> values;  // bands interleaved, NaN where invalid
};

}  // namespace

struct RasterSource::Impl {
  RasterSettings settings;
  GDALDatasetH dataset = nullptr;
  OGRSpatialReferenceH crs = nullptr, geographic = nullptr;
  OGRCoordinateTransformationH to_raster = nullptr, to_geographic = nullptr;
  double angular_unit_deg = 1.0;  // degrees per unit of the raster's CRS, when geographic
  double geographic_unit_deg = 1.0;  // degrees per unit of the raster's own geographic CRS
  bool is_geographic = true;
  long width = 0, height = 0;
  int bands = 1;
  int band_index[3] = {1, 2, 3};
  double geotransform[6] = {0, 1, 0, 0, 0, 1}, inverse[6] = {0, 1, 0, 0, 0, 1};
  bool wraps = false, global = false;
  double centre_longitude = 0.0;  // of the raster's extent, geographic units
  double scale[3] = {1, 1, 1}, offset[3] = {0, 0, 0};
  double metres_per_unit = 1.0;
  double encoded_max = 1.0;        // imagery: the value of full reflectance (255 for bytes)
  std::vector<long> level_factor;  // pixels of level 0 per pixel of level l (GDAL's overviews)
  std::vector<MemoryLevel> memory; // the in-memory pyramid, if any
  double pixel_size_rad = 0.0;
  double min_value = 0.0, max_value = 0.0;
  mutable std::mutex mutex;

  std::string name() const {
    std::string s = settings.source;
    if (s.size() > 120) s = s.substr(0, 117) + "...";
    return settings.role + " source '" + s + "'";
  }
  [[noreturn]] void fail(const std::string& what) const { throw Error(name() + ": " + what); }

  ~Impl() {
    if (to_raster != nullptr) OCTDestroyCoordinateTransformation(to_raster);
    if (to_geographic != nullptr) OCTDestroyCoordinateTransformation(to_geographic);
    if (geographic != nullptr) OSRDestroySpatialReference(geographic);
    if (crs != nullptr) OSRDestroySpatialReference(crs);
    if (dataset != nullptr) GDALClose(dataset);
  }

  void open() {
    register_drivers();
    ScopedErrorCapture errors;
    if (settings.source.empty()) fail("no file given");
    dataset = GDALOpenEx(settings.source.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
    if (dataset == nullptr) fail("cannot be read: " + errors.last());
    width = GDALGetRasterXSize(dataset);
    height = GDALGetRasterYSize(dataset);
    const int count = GDALGetRasterCount(dataset);
    if (width <= 0 || height <= 0 || count <= 0) fail("has no raster band");
    bands = settings.kind == RasterKind::imagery ? 3 : 1;
    if (count < bands) fail("imagery needs three bands (red, green, blue), it has " + std::to_string(count));

    if (settings.bounds_deg) {
      const auto& b = *settings.bounds_deg;
      const double g[6] = {b[0], (b[2] - b[0]) / double(width), 0.0, b[3], 0.0, -(b[3] - b[1]) / double(height)};
      std::copy(g, g + 6, geotransform);
      if (settings.crs.empty()) settings.crs = "EPSG:4326";
    } else if (GDALGetGeoTransform(dataset, geotransform) != CE_None) {
      fail("has no georeferencing (no geotransform): give \"bounds_deg\" in the planet file, or a VRT");
    }
    if (!GDALInvGeoTransform(geotransform, inverse)) fail("has a singular geotransform");

    open_crs();
    read_band_metadata();
    choose_levels();
    measure_extent();
    if (double(width) * double(height) <= kInMemoryPixels && level_factor.size() == 1) load_into_memory();
    compute_range();
  }

  void open_crs() {
    crs = OSRNewSpatialReference(nullptr);
    if (!settings.crs.empty()) {
      if (OSRSetFromUserInput(crs, settings.crs.c_str()) != OGRERR_NONE) fail("unknown CRS '" + settings.crs + "'");
    } else {
      OGRSpatialReferenceH own = GDALGetSpatialRef(dataset);
      if (own == nullptr)
        fail("has no coordinate reference system: give one with \"crs\" in the planet file (e.g. \"EPSG:4326\")");
      OSRDestroySpatialReference(crs);
      crs = OSRClone(own);
    }
    OSRSetAxisMappingStrategy(crs, OAMS_TRADITIONAL_GIS_ORDER);
    // The raster's own geographic CRS (its datum): no datum shift, and no
    // PROJ check between celestial bodies.
    geographic = OSRCloneGeogCS(crs);
    if (geographic == nullptr) fail("its CRS has no geographic CRS (not a body-fixed CRS)");
    OSRSetAxisMappingStrategy(geographic, OAMS_TRADITIONAL_GIS_ORDER);
    geographic_unit_deg = OSRGetAngularUnits(geographic, nullptr) / kDegree;
    if (!(geographic_unit_deg > 0.0)) fail("its geographic CRS has no angular unit");
    is_geographic = OSRIsGeographic(crs) != 0;
    if (is_geographic) {
      angular_unit_deg = OSRGetAngularUnits(crs, nullptr) / kDegree;
      if (!(angular_unit_deg > 0.0)) fail("its CRS has no angular unit");
    } else {
      ScopedErrorCapture errors;
      to_raster = OCTNewCoordinateTransformation(geographic, crs);
      to_geographic = OCTNewCoordinateTransformation(crs, geographic);
      if (to_raster == nullptr || to_geographic == nullptr)
        fail("PROJ cannot transform into its CRS: " + errors.last());
    }
  }

  void read_band_metadata() {
    for (int k = 0; k < bands; ++k) {
      GDALRasterBandH band = GDALGetRasterBand(dataset, band_index[k]);
      int has = 0;
      const double s = GDALGetRasterScale(band, &has);
      scale[k] = has ? s : 1.0;
      const double o = GDALGetRasterOffset(band, &has);
      offset[k] = has ? o : 0.0;
    }
    GDALRasterBandH first = GDALGetRasterBand(dataset, 1);
    if (settings.kind == RasterKind::imagery) {
      const GDALDataType type = GDALGetRasterDataType(first);
      encoded_max = type == GDT_Byte ? 255.0 : type == GDT_UInt16 ? 65535.0 : 1.0;
      return;
    }
    if (settings.kind == RasterKind::mask) return;  // no unit
    const std::string unit = GDALGetRasterUnitType(first);
    double from_unit = 0.0;
    if (unit == "m" || unit == "metre" || unit == "meter" || unit == "metres" || unit == "meters") from_unit = 1.0;
    else if (unit == "km" || unit == "kilometre" || unit == "kilometer") from_unit = 1000.0;
    else if (unit == "ft" || unit == "foot" || unit == "feet" || unit == "US survey foot") from_unit = 0.3048;
    else if (!unit.empty()) fail("has the unknown height unit '" + unit + "': give \"unit\" in the planet file");
    const double given = settings.metres_per_unit;
    if (given > 0.0 && from_unit > 0.0 && std::abs(given - from_unit) > 1e-9 * from_unit)
      fail("its unit '" + unit + "' contradicts the planet file's unit");
    if (given > 0.0) metres_per_unit = given;
    else if (from_unit > 0.0) metres_per_unit = from_unit;
    else fail("has no height unit: give \"unit\" in the planet file (e.g. \"m\")");
  }

  void choose_levels() {
    GDALRasterBandH first = GDALGetRasterBand(dataset, 1);
    level_factor = {1};
    const int overviews = GDALGetOverviewCount(first);
    for (int l = 0; l < overviews; ++l) {
      GDALRasterBandH o = GDALGetOverview(first, l);
      const long w = GDALGetRasterBandXSize(o);
      if (w > 0) level_factor.push_back(std::max(1L, long(std::lround(double(width) / double(w)))));
    }
    if (double(width) * double(height) > kMaxPixelsWithoutOverviews && overviews == 0)
      fail("has " + std::to_string(width) + " x " + std::to_string(height) +
           " pixels and no overviews: build them first (gdaladdo -r average)");
  }

  // Pixel coordinates (level 0) -> geographic degrees; false if PROJ fails.
  bool pixel_to_geographic(double px, double py, double& lat_deg, double& lon_deg) const {
    double x = geotransform[0] + px * geotransform[1] + py * geotransform[2];
    double y = geotransform[3] + px * geotransform[4] + py * geotransform[5];
    if (!is_geographic) {
      int ok = 0;
      if (!OCTTransformEx(to_geographic, 1, &x, &y, nullptr, &ok) || !ok) return false;
      lon_deg = x * geographic_unit_deg;
      lat_deg = y * geographic_unit_deg;
      return std::isfinite(lat_deg) && std::isfinite(lon_deg);
    }
    lon_deg = x * angular_unit_deg;
    lat_deg = y * angular_unit_deg;
    return true;
  }

  void measure_extent() {
    // The size of a pixel at the raster's centre, as angles on the sphere.
    const double cx = 0.5 * double(width), cy = 0.5 * double(height);
    double lat0 = 0, lon0 = 0, lat1 = 0, lon1 = 0, lat2 = 0, lon2 = 0;
    if (!pixel_to_geographic(cx, cy, lat0, lon0) || !pixel_to_geographic(cx + 1, cy, lat1, lon1) ||
        !pixel_to_geographic(cx, cy + 1, lat2, lon2))
      fail("its centre cannot be transformed to latitude and longitude");
    const glm::dvec3 d0 = direction_of(lat0, lon0);
    const double a = std::acos(std::clamp(glm::dot(d0, direction_of(lat1, lon1)), -1.0, 1.0));
    const double b = std::acos(std::clamp(glm::dot(d0, direction_of(lat2, lon2)), -1.0, 1.0));
    pixel_size_rad = std::max(a, b);
    if (!(pixel_size_rad > 0.0)) fail("has pixels of zero size");
    centre_longitude = lon0 / angular_unit_deg;
    if (is_geographic) {
      const double span_deg = std::abs(geotransform[1]) * double(width) * angular_unit_deg;
      const double span_lat = std::abs(geotransform[5]) * double(height) * angular_unit_deg;
      wraps = std::abs(geotransform[2]) < 1e-12 && std::abs(geotransform[4]) < 1e-12 &&
              std::abs(span_deg - 360.0) < 0.5 * std::abs(geotransform[1]) * angular_unit_deg;
      global = wraps && span_lat > 180.0 - 1.01 * std::abs(geotransform[5]) * angular_unit_deg;
    }
  }

  // Decodes raw values read from GDAL (band k's scale and offset, then the
  // unit or the sRGB transfer function); NaN stays invalid.
  float decode(double raw, int k) const {
    const double v = raw * scale[k] + offset[k];
    if (settings.kind == RasterKind::imagery) return srgb_to_linear(float(v / encoded_max));
    if (settings.kind == RasterKind::mask) return std::isnan(v) ? float(v) : v != 0.0 ? 1.0f : 0.0f;
    return float(v * metres_per_unit);
  }

  // Reads columns x0 .. x0 + w - 1 (wrapped when the raster wraps) and rows
  // y0 .. y0 + h - 1 of level `level` into grid (decoded, NaN where GDAL's
  // mask says nodata). The caller holds the mutex.
  void read_window(std::size_t level, long x0, long y0, long w, long h, std::vector<float>& buffer, Grid& grid) const {
    GDALRasterBandH base = GDALGetRasterBand(dataset, band_index[0]);
    GDALRasterBandH first = level == 0 ? base : GDALGetOverview(base, int(level) - 1);
    const long lw = GDALGetRasterBandXSize(first), lh = GDALGetRasterBandYSize(first);
    grid.level_width = lw;
    grid.level_height = lh;
    grid.wraps = wraps;
    grid.bands = bands;
    if (wraps) {
      w = std::min(w, lw);
      x0 = w == lw ? 0 : wrap(x0, lw);
    } else {
      const long x1 = std::min(x0 + w, lw);
      x0 = std::max(x0, 0L);
      w = std::max(x1 - x0, 0L);
    }
    const long y1 = std::min(y0 + h, lh);
    y0 = std::max(y0, 0L);
    h = std::max(y1 - y0, 0L);
    grid.x0 = x0;
    grid.y0 = y0;
    grid.width = w;
    grid.height = h;
    buffer.assign(std::size_t(w) * std::size_t(h) * std::size_t(bands), 0.0f);
    grid.data = buffer.data();
    if (w == 0 || h == 0) return;
    std::vector<std::uint8_t> mask(std::size_t(w) * std::size_t(h), 255);
    // Up to two column runs: [x0, lw) and [0, rest) when the window wraps.
    const long first_run = std::min(w, lw - x0);
    const long runs[2][2] = {{x0, first_run}, {0, w - first_run}};
    ScopedErrorCapture errors;
    for (int k = 0; k < bands; ++k) {
      GDALRasterBandH b = GDALGetRasterBand(dataset, band_index[k]);
      if (level > 0) b = GDALGetOverview(b, int(level) - 1);
      for (int r = 0; r < 2; ++r) {
        if (runs[r][1] <= 0) continue;
        const long column = r == 0 ? 0 : first_run;
        float* destination = buffer.data() + std::size_t(column) * std::size_t(bands) + std::size_t(k);
        if (GDALRasterIO(b, GF_Read, int(runs[r][0]), int(y0), int(runs[r][1]), int(h), destination,
                         int(runs[r][1]), int(h), GDT_Float32, int(sizeof(float)) * bands,
                         int(sizeof(float)) * bands * int(w)) != CE_None)
          fail("read failed: " + errors.last());
      }
    }
    GDALRasterBandH mask_band = GDALGetMaskBand(first);
    if ((GDALGetMaskFlags(first) & GMF_ALL_VALID) == 0) {
      for (int r = 0; r < 2; ++r) {
        if (runs[r][1] <= 0) continue;
        const long column = r == 0 ? 0 : first_run;
        if (GDALRasterIO(mask_band, GF_Read, int(runs[r][0]), int(y0), int(runs[r][1]), int(h),
                         mask.data() + column, int(runs[r][1]), int(h), GDT_Byte, 1, int(w)) != CE_None)
          fail("read of its nodata mask failed: " + errors.last());
      }
    }
    for (std::size_t p = 0; p < mask.size(); ++p) {
      float* v = buffer.data() + p * std::size_t(bands);
      bool ok = mask[p] != 0;
      for (int k = 0; k < bands; ++k) ok = ok && std::isfinite(v[k]);
      for (int k = 0; k < bands; ++k) v[k] = ok ? decode(double(v[k]), k) : kInvalid;
    }
  }

  // Small rasters without overviews: decoded into memory with a pyramid of
  // 2 x 2 box averages of the valid pixels (Williams 1983).
  void load_into_memory() {
    std::lock_guard<std::mutex> lock(mutex);
    std::vector<float> buffer;
    Grid grid;
    read_window(0, 0, 0, width, height, buffer, grid);
    memory.push_back({width, height, std::move(buffer)});
    while (memory.back().width > 1 || memory.back().height > 1) {
      const MemoryLevel& fine = memory.back();
      MemoryLevel coarse;
      coarse.width = std::max(1L, (fine.width + 1) / 2);
      coarse.height = std::max(1L, (fine.height + 1) / 2);
      coarse.values.assign(std::size_t(coarse.width * coarse.height * bands), kInvalid);
      for (long j = 0; j < coarse.height; ++j)
        for (long i = 0; i < coarse.width; ++i) {
          double sum[3] = {0, 0, 0};
          int n = 0;
          for (long b = 0; b < 2; ++b)
            for (long a = 0; a < 2; ++a) {
              const long fi = std::min(2 * i + a, fine.width - 1), fj = std::min(2 * j + b, fine.height - 1);
              const float* v = fine.values.data() + std::size_t((fj * fine.width + fi) * bands);
              if (std::isnan(v[0])) continue;
              for (int k = 0; k < bands; ++k) sum[k] += v[k];
              ++n;
            }
          if (n == 0) continue;
          for (int k = 0; k < bands; ++k)
            coarse.values[std::size_t((j * coarse.width + i) * bands + k)] = float(sum[k] / n);
        }
      memory.push_back(std::move(coarse));
    }
  }

  void compute_range() {
    if (settings.kind != RasterKind::elevation) return;
    double lo = INFINITY, hi = -INFINITY;
    if (!memory.empty()) {
      for (float v : memory.front().values)
        if (!std::isnan(v)) {
          lo = std::min(lo, double(v));
          hi = std::max(hi, double(v));
        }
    } else {
      ScopedErrorCapture errors;
      double range[2] = {0, 0};
      if (GDALComputeRasterMinMax(GDALGetRasterBand(dataset, 1), TRUE, range) != CE_None)
        fail("its range of values cannot be computed: " + errors.last());
      lo = decode(range[0], 0);
      hi = decode(range[1], 0);
      if (lo > hi) std::swap(lo, hi);
    }
    if (!(lo <= hi)) fail("has no valid value");
    min_value = lo;
    max_value = hi;
  }

  // Geographic degrees -> level-0 pixel coordinates; false where PROJ fails.
  void to_pixels(const glm::dvec3* directions, std::size_t n, std::vector<double>& px, std::vector<double>& py,
                 std::vector<int>& ok) const {
    px.resize(n);
    py.resize(n);
    ok.assign(n, 1);
    for (std::size_t i = 0; i < n; ++i) {
      const glm::dvec3& d = directions[i];
      const double lat = std::asin(std::clamp(d.z / std::max(glm::length(d), 1e-300), -1.0, 1.0)) / kDegree;
      double lon = std::atan2(d.y, d.x) / kDegree;
      if (is_geographic) {
        double x = lon / angular_unit_deg;
        // The longitude nearest the raster's centre (rasters on 0..360).
        const double turn = 360.0 / angular_unit_deg;
        x -= turn * std::round((x - centre_longitude) / turn);
        px[i] = x;
        py[i] = lat / angular_unit_deg;
      } else {
        px[i] = lon / geographic_unit_deg;
        py[i] = lat / geographic_unit_deg;
      }
    }
    if (!is_geographic && n > 0) {
      // A PROJ transformation is not to be used by two threads at once.
      std::lock_guard<std::mutex> lock(mutex);
      ScopedErrorCapture errors;
      OCTTransformEx(to_raster, int(n), px.data(), py.data(), nullptr, ok.data());
    }
    for (std::size_t i = 0; i < n; ++i) {
      const double x = px[i], y = py[i];
      px[i] = inverse[0] + x * inverse[1] + y * inverse[2];
      py[i] = inverse[3] + x * inverse[4] + y * inverse[5];
      if (!std::isfinite(px[i]) || !std::isfinite(py[i])) ok[i] = 0;
    }
  }

  void sample(const glm::dvec3* directions, std::size_t n, double spacing_m, double radius_m, float* out,
              std::uint8_t* valid) const {
    std::vector<double> px, py;
    std::vector<int> ok;
    to_pixels(directions, n, px, py, ok);
    // The coarsest level whose pixel is at most half the spacing.
    const double wanted = radius_m > 0.0 && spacing_m > 0.0 ? spacing_m / (2.0 * pixel_size_rad * radius_m) : 1.0;
    const auto out_of = [&](std::size_t i) { return out + i * std::size_t(bands); };
    const auto finish = [&](const Grid& grid, double factor) {
      for (std::size_t i = 0; i < n; ++i) {
        valid[i] = 0;
        std::fill(out_of(i), out_of(i) + bands, 0.0f);
        if (!ok[i]) continue;
        valid[i] = grid.bilinear(px[i] / factor, py[i] / factor, out_of(i)) ? 1 : 0;
        if (!valid[i]) std::fill(out_of(i), out_of(i) + bands, 0.0f);
      }
    };
    if (!memory.empty()) {
      std::size_t level = 0;
      while (level + 1 < memory.size() && double(1L << (level + 1)) <= wanted) ++level;
      const MemoryLevel& m = memory[level];
      Grid grid;
      grid.width = grid.level_width = m.width;
      grid.height = grid.level_height = m.height;
      grid.wraps = wraps;
      grid.bands = bands;
      grid.data = m.values.data();
      finish(grid, double(1L << level));
      return;
    }
    std::size_t level = 0;
    while (level + 1 < level_factor.size() && double(level_factor[level + 1]) <= wanted) ++level;
    const double factor = double(level_factor[level]);
    // The window the points need, at that level; x unwrapped around the
    // first valid point so that a window across the antimeridian is one run.
    double x_min = INFINITY, x_max = -INFINITY, y_min = INFINITY, y_max = -INFINITY;
    const double level_width = std::ceil(double(width) / factor);
    double reference = NAN;
    for (std::size_t i = 0; i < n; ++i) {
      if (!ok[i]) continue;
      double x = px[i] / factor;
      if (wraps) {
        if (std::isnan(reference)) reference = x;
        x -= level_width * std::round((x - reference) / level_width);
        px[i] = x * factor;
      }
      x_min = std::min(x_min, x);
      x_max = std::max(x_max, x);
      y_min = std::min(y_min, py[i] / factor);
      y_max = std::max(y_max, py[i] / factor);
    }
    std::lock_guard<std::mutex> lock(mutex);
    std::vector<float> buffer;
    Grid grid;
    if (!(x_min <= x_max)) {
      finish(grid, factor);
      return;
    }
    const long x0 = floor_to_long(x_min - 0.5), x1 = floor_to_long(x_max - 0.5) + 2;
    const long y0 = floor_to_long(y_min - 0.5), y1 = floor_to_long(y_max - 0.5) + 2;
    const double window = double(x1 - x0) * double(y1 - y0);
    if (window <= std::max(65536.0, 16.0 * double(n))) {
      read_window(level, x0, y0, x1 - x0, y1 - y0, buffer, grid);
      finish(grid, factor);
      return;
    }
    // Points too spread for one window (a polar tile of a huge raster):
    // each point's own 2 x 2 pixels.
    for (std::size_t i = 0; i < n; ++i) {
      valid[i] = 0;
      std::fill(out_of(i), out_of(i) + bands, 0.0f);
      if (!ok[i]) continue;
      const double x = px[i] / factor - 0.5, y = py[i] / factor - 0.5;
      read_window(level, floor_to_long(x), floor_to_long(y), 2, 2, buffer, grid);
      valid[i] = grid.bilinear(px[i] / factor, py[i] / factor, out_of(i)) ? 1 : 0;
      if (!valid[i]) std::fill(out_of(i), out_of(i) + bands, 0.0f);
    }
  }
};

RasterSource::RasterSource(const RasterSettings& settings) : impl_(std::make_unique<Impl>()) {
  impl_->settings = settings;
  impl_->open();
}

RasterSource::~RasterSource() = default;

int RasterSource::bands() const { return impl_->bands; }

void RasterSource::sample(const glm::dvec3* directions, std::size_t n, double spacing_m, double radius_m, float* out,
                          std::uint8_t* valid) const {
  impl_->sample(directions, n, spacing_m, radius_m, out, valid);
}

double RasterSource::pixel_size_m(double radius_m) const { return impl_->pixel_size_rad * radius_m; }
bool RasterSource::is_global() const { return impl_->global; }
double RasterSource::min_value() const { return impl_->min_value; }
double RasterSource::max_value() const { return impl_->max_value; }
const std::string& RasterSource::source() const { return impl_->settings.source; }

glm::dvec3 RasterSource::direction_in_extent(double u, double v) const {
  double lat = 0, lon = 0;
  bool ok = false;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);  // the PROJ transformation
    ok = impl_->pixel_to_geographic(u * double(impl_->width), v * double(impl_->height), lat, lon);
  }
  if (!ok) return {0.0, 0.0, 1.0};
  return direction_of(lat, lon);
}

}  // namespace atmos::planet
