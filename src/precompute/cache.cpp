// Disk cache of precomputed tables.
//
// File name: atmos-<key>.tables, where the key hashes every input of the
// tables: the atmosphere resampled at the working wavelengths, the table
// sizes, the number of orders (and with auto orders the tolerance and the tail
// solver's options), the file format version and the text of the
// shared physics sources (so that editing the physics invalidates old files).
// The file repeats the key and the sizes and ends with a checksum of all its
// bytes; anything that does not match is reported and recomputed.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "atmos/tables.hpp"
#include "data/embedded_files.hpp"
#include "precompute/cache_file.hpp"

namespace atmos {
namespace {

constexpr char kMagic[8] = {'A', 'T', 'M', 'O', 'S', 'T', 'B', 'L'};
// Bump when the meaning of the tables changes in code that is not one of the
// hashed sources (src/precompute/*.cpp).
// 5: the convergence entries hold the tail solver's entry (32 bytes each).
// 6: delta-M in the scattering density (steps.cpp), the phase ratio of the
//    spectral single aerosol table (precompute.cpp).
// 7: the multiple scattering integrates the source function J / beta_ext
//    with the linear-source rule (functions.glsl, source_integration_nodes).
// 8: a forward lobe sharper than g = 0.85 is delta-M scaled for the orders
//    >= 2, with a second transmittance tile per wavelength triple (the
//    scaled medium's) and the nu axis uniform in angle (delta_scaled_params).
// 9: the mu axis of optically thick atmospheres is warped towards log-spaced
//    distances (scattering_mu_log_weight, functions.glsl scattering_u_mu),
//    and their multiple scattering integrates the view rays with 32
//    intervals (multiple_scattering_intervals); the tail solver restarts
//    with deflation (tail.cpp).
// 10: the r axis of optically thick atmospheres follows their optical depth
//    (scattering_r_optical_depth_weight, functions.glsl
//    scattering_x_r_from_rho_fraction; set in parameters.cpp).
// 11: auto orders stop when the rest of the series, foreseen from the ratio
//    of the last two orders, is below the tolerance in every channel, in all
//    the light and in the sky light on the ground (precompute.cpp).
// 12: the multiple scattering's nodes in atmospheres of several optical
//    depths are uniform in optical depth over the first optical depths of
//    each view ray (functions.glsl source_integration_nodes,
//    AtmosphereParams.source_flat_optical_depth).
// 13: optically thick atmospheres read the source function between radius
//    rows with cubic Hermite weights (functions.glsl source_function_lookup,
//    precomputed per view ray node in steps.cpp).
// 14: auto orders hand a series that would reach the cap unconverged to the
//    tail solver from order 16 (precompute.cpp kEarliestTailHandoff).
constexpr std::uint32_t kFormatVersion = 14;
constexpr std::size_t kConvergenceEntryBytes = 4 + 4 + 3 * 8;
// Magic, version, key, 8 table sizes, orders, wavelength triples, wavelengths,
// convergence entries.
constexpr std::size_t kHeaderBytes = sizeof kMagic + 4 + 16 + 8 * 4 + 4 + 4 + 4 + 4;
constexpr std::int32_t kMaxConvergenceEntries = 100;

struct Fnv1a {
  std::uint64_t h = 1469598103934665603ull;
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h ^= p[i];
      h *= 1099511628211ull;
    }
  }
  template <typename T>
  void value(const T& v) { bytes(&v, sizeof v); }
  void text(const std::string& s) {
    value(s.size());
    bytes(s.data(), s.size());
  }
};

std::string hex(std::uint64_t v) {
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(v));
  return buffer;
}

std::size_t set_floats(const TableSizes& s) {
  const std::size_t e = std::size_t(s.irradiance_mu_s) * s.irradiance_r;
  const std::size_t sc = std::size_t(s.scattering_nu) * s.scattering_mu_s * s.scattering_mu * s.scattering_r;
  return 3 * (2 * e + 3 * sc);  // 2 irradiance, 3 scattering tables
}

// The ground albedo response (GroundAlbedoResponse): its three albedos per
// channel, then its irradiance and two scattering tables.
std::size_t response_floats(const TableSizes& s) {
  const std::size_t e = std::size_t(s.irradiance_mu_s) * s.irradiance_r;
  const std::size_t sc = std::size_t(s.scattering_nu) * s.scattering_mu_s * s.scattering_mu * s.scattering_r;
  return 3 * 3 + 3 * (e + 2 * sc);
}

// The length of a file of tables of sizes `s` at `wavelengths` working
// wavelengths with `convergence` report entries (and a ground albedo
// response or not): the header, the wavelengths, the report, the texels and
// the checksum.
std::size_t file_bytes(const TableSizes& s, std::size_t wavelengths, std::size_t convergence, bool ground_response) {
  const std::size_t sets = (wavelengths + 2) / 3;
  const std::size_t transmittance_floats = 3 * std::size_t(s.transmittance_mu) * s.transmittance_r;
  std::size_t floats = set_floats(s) + transmittance_floats * 2 * sets;
  if (ground_response) floats += response_floats(s);
  return kHeaderBytes + wavelengths * 8 + convergence * kConvergenceEntryBytes + floats * 4 + 8;
}

void write_sizes(Fnv1a& h, const TableSizes& s) {
  for (int v : {s.transmittance_mu, s.transmittance_r, s.irradiance_mu_s, s.irradiance_r, s.scattering_nu,
                s.scattering_mu_s, s.scattering_mu, s.scattering_r})
    h.value(std::int32_t(v));
}

}  // namespace

std::string tables_cache_key(const Atmosphere& a, const PrecomputeOptions& options) {
  Fnv1a h;
  h.value(kFormatVersion);
  // The physics the precomputation runs, and the colour matching functions
  // that convert spectral tables to sRGB.
  for (const char* source :
       {"src/physics/definitions.glsl", "src/physics/eclipse.glsl", "src/physics/ray_geometry.glsl",
        "src/physics/medium.glsl", "src/physics/table_coordinates.glsl", "src/physics/table_lookups.glsl",
        "src/physics/ray_integration.glsl", "src/physics/precomputation_integrands.glsl",
        "data/spectra/cie1931_2deg.csv"}) {
    const char* text = data::embedded_file(source);
    h.text(text ? text : "");
  }
  write_sizes(h, options.sizes);
  h.value(std::int32_t(options.scattering_orders));
  h.value(options.auto_orders);
  if (options.auto_orders) {
    h.value(options.auto_orders_tolerance);
    h.value(options.solve_tail);
    if (options.solve_tail) {
      h.value(options.tail_tolerance);
      h.value(std::int32_t(options.tail_iterations));
    }
  }
  if (options.ground_albedo_response) h.value(options.ground_albedo_response);
  h.value(a.bottom_radius_m);
  h.value(a.top_radius_m);
  h.value(a.sun_angular_radius_rad);
  h.value(a.wavelengths_nm.size());
  for (double w : a.wavelengths_nm) {
    h.value(w);
    h.value(a.ground_albedo.at(w));
    h.value(a.solar_irradiance.at(w));
    for (const auto& c : a.constituents) {
      h.value(c.scattering.at(w));
      h.value(c.absorption.at(w));
    }
  }
  for (const auto& c : a.constituents) {
    h.value(int(c.density.kind));
    h.value(c.density.scale_height_m);
    h.value(c.density.knots.size());
    for (const auto& [altitude, density] : c.density.knots) {
      h.value(altitude);
      h.value(density);
    }
    // Every sample of the phase function's spectra (not their values at the
    // working wavelengths only: the render parameters sample them at 680,
    // 550 and 440 nm too).
    h.value(int(c.phase.kind));
    for (const Spectrum* s : {&c.phase.g, &c.phase.g_back, &c.phase.forward_weight}) {
      h.value(s->values().size());
      for (size_t i = 0; i < s->values().size(); ++i) {
        h.value(s->wavelengths_nm()[i]);
        h.value(s->values()[i]);
      }
    }
  }
  return hex(h.h);
}

std::string default_cache_directory() {
  if (const char* dir = std::getenv("ATMOS_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/atmos";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/atmos";
  return ".atmos-cache";
}

std::string read_tables_file(std::string_view data, const std::string& key, const PrecomputeOptions& options,
                             const Atmosphere& atmosphere, Tables& tables) {
  if (data.size() < kHeaderBytes + 8) return "truncated header";
  std::size_t pos = 0;
  auto take = [&](void* out, std::size_t n) {
    std::memcpy(out, data.data() + pos, n);
    pos += n;
  };
  char magic[8];
  take(magic, 8);
  if (std::memcmp(magic, kMagic, 8) != 0) return "not an atmos table file";
  std::uint32_t version;
  take(&version, 4);
  if (version != kFormatVersion) return "format version " + std::to_string(version);
  char file_key[16];
  take(file_key, 16);
  if (std::string(file_key, 16) != key) return "key mismatch";
  std::int32_t sizes[8], orders, sets, wavelengths, convergence;
  take(sizes, sizeof sizes);
  take(&orders, 4);
  take(&sets, 4);
  take(&wavelengths, 4);
  take(&convergence, 4);
  TableSizes s{sizes[0], sizes[1], sizes[2], sizes[3], sizes[4], sizes[5], sizes[6], sizes[7]};
  const bool orders_match = options.auto_orders ? orders >= 1 && orders <= options.scattering_orders
                                                : orders == options.scattering_orders;
  if (!(s == options.sizes) || !orders_match || wavelengths != std::int32_t(atmosphere.wavelengths_nm.size()) ||
      sets != (wavelengths + 2) / 3 || convergence < 0 || convergence > kMaxConvergenceEntries)
    return "parameters mismatch";
  const std::size_t expected =
      file_bytes(s, std::size_t(wavelengths), std::size_t(convergence), options.ground_albedo_response);
  if (data.size() != expected)
    return "size " + std::to_string(data.size()) + " bytes, expected " + std::to_string(expected) + " (truncated?)";
  Fnv1a check;
  check.bytes(data.data(), data.size() - 8);
  std::uint64_t stored;
  std::memcpy(&stored, data.data() + data.size() - 8, 8);
  if (stored != check.h) return "checksum mismatch (corrupt file)";

  tables = Tables();
  tables.sizes = s;
  tables.scattering_orders = orders;
  tables.wavelengths_nm.resize(std::size_t(wavelengths));
  take(tables.wavelengths_nm.data(), std::size_t(wavelengths) * 8);
  if (tables.wavelengths_nm != atmosphere.wavelengths_nm) return "working wavelengths differ from the planet's";
  for (int i = 0; i < convergence; ++i) {
    OrderContribution c;
    std::int32_t order, iterations;  // iterations < 0: an order, not the tail
    take(&order, 4);
    take(&iterations, 4);
    take(&c.added, 8);
    take(&c.relative, 8);
    take(&c.residual, 8);
    c.order = order;
    c.tail = iterations >= 0;
    c.iterations = std::max(iterations, std::int32_t(0));
    if (!std::isfinite(c.added) || !std::isfinite(c.relative) || !std::isfinite(c.residual))
      return "non-finite convergence report";
    tables.convergence.push_back(c);
  }
  auto take_vec3 = [&](std::vector<glm::vec3>& v, std::size_t count) {
    v.resize(count);
    take(v.data(), count * sizeof(glm::vec3));
    for (const auto& x : v)
      if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) return false;
    return true;
  };
  const std::size_t t = std::size_t(s.transmittance_mu) * s.transmittance_r;
  const std::size_t e = std::size_t(s.irradiance_mu_s) * s.irradiance_r;
  const std::size_t sc = std::size_t(s.scattering_nu) * s.scattering_mu_s * s.scattering_mu * s.scattering_r;
  TableSet& set = tables.set;
  if (!take_vec3(set.direct_irradiance, e) ||
      !take_vec3(set.indirect_irradiance, e) || !take_vec3(set.scattering, sc) || !take_vec3(set.single_aerosol, sc) ||
      !take_vec3(set.multiple_scattering, sc) || !take_vec3(tables.spectral_optical_depth, t * std::size_t(2 * sets)))
    return "non-finite texels";
  if (options.ground_albedo_response) {
    GroundAlbedoResponse& g = tables.ground_response;
    std::vector<glm::vec3> albedos;
    if (!take_vec3(albedos, 3) || !take_vec3(g.indirect_irradiance, e) || !take_vec3(g.scattering, sc) ||
        !take_vec3(g.multiple_scattering, sc))
      return "non-finite texels";
    for (const glm::vec3& v : albedos)
      for (int c = 0; c < 3; ++c)
        if (!(v[c] >= 0.0f && v[c] <= 1.0f)) return "ground albedo response outside [0, 1]";
    g.albedo = albedos[0];
    g.planet_albedo = albedos[1];
    g.spherical_albedo = albedos[2];
  }
  return "";
}

namespace {

// Reads and checks a cache file. Returns an empty string on success, else why
// the file is unusable. A file longer than any file of these tables is
// refused before it is read, so that its length never sizes an allocation.
std::string read_cache(const std::string& path, const std::string& key, const PrecomputeOptions& options,
                       const Atmosphere& atmosphere, Tables& tables) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return "cannot open";
  const std::size_t longest =
      file_bytes(options.sizes, atmosphere.wavelengths_nm.size(), std::size_t(kMaxConvergenceEntries),
                 options.ground_albedo_response);
  if (size > longest)
    return "size " + std::to_string(size) + " bytes, more than the " + std::to_string(longest) +
           " of any file of these tables";
  std::ifstream in(path, std::ios::binary);
  if (!in) return "cannot open";
  std::string data(std::size_t(size), '\0');
  if (!in.read(data.data(), std::streamsize(data.size()))) return "cannot read " + std::to_string(size) + " bytes";
  return read_tables_file(data, key, options, atmosphere, tables);
}

// Writes atomically: a temporary file renamed over the final name, so that a
// crash never leaves a half-written file under the cache name.
std::string write_cache(const std::string& path, const std::string& key, const Tables& tables) {
  std::string data(kMagic, 8);
  auto put = [&](const void* p, std::size_t n) { data.append(static_cast<const char*>(p), n); };
  put(&kFormatVersion, 4);
  put(key.data(), 16);
  const TableSizes& s = tables.sizes;
  const std::int32_t sizes[8] = {s.transmittance_mu, s.transmittance_r, s.irradiance_mu_s, s.irradiance_r,
                                 s.scattering_nu,    s.scattering_mu_s, s.scattering_mu,   s.scattering_r};
  put(sizes, sizeof sizes);
  const std::int32_t orders = tables.scattering_orders, sets = std::int32_t(tables.spectral_sets()),
                     wavelengths = std::int32_t(tables.wavelengths_nm.size()),
                     convergence = std::int32_t(tables.convergence.size());
  put(&orders, 4);
  put(&sets, 4);
  put(&wavelengths, 4);
  put(&convergence, 4);
  put(tables.wavelengths_nm.data(), tables.wavelengths_nm.size() * 8);
  for (const OrderContribution& c : tables.convergence) {
    const std::int32_t order = c.order, iterations = c.tail ? c.iterations : -1;
    put(&order, 4);
    put(&iterations, 4);
    put(&c.added, 8);
    put(&c.relative, 8);
    put(&c.residual, 8);
  }
  const TableSet& set = tables.set;
  for (const auto* v : {&set.direct_irradiance, &set.indirect_irradiance, &set.scattering,
                        &set.single_aerosol, &set.multiple_scattering, &tables.spectral_optical_depth})
    put(v->data(), v->size() * sizeof(glm::vec3));
  if (const GroundAlbedoResponse& g = tables.ground_response; !g.empty()) {
    for (const glm::vec3* v : {&g.albedo, &g.planet_albedo, &g.spherical_albedo}) put(v, sizeof(glm::vec3));
    for (const auto* v : {&g.indirect_irradiance, &g.scattering, &g.multiple_scattering})
      put(v->data(), v->size() * sizeof(glm::vec3));
  }
  Fnv1a check;
  check.bytes(data.data(), data.size());
  put(&check.h, 8);

  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  // Unique per process and call, so that concurrent writers never share a file.
  static std::atomic<int> counter{0};
  const std::string temporary = path + ".tmp" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) return "cannot write " + temporary;
    out.write(data.data(), std::streamsize(data.size()));
    if (!out) return "write failed for " + temporary;
  }
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    return "cannot rename into " + path;
  }
  return "";
}

}  // namespace

std::string tables_cache_path(const Atmosphere& atmosphere, const PrecomputeOptions& options,
                              const std::string& directory) {
  return (std::filesystem::path(directory) / ("atmos-" + tables_cache_key(atmosphere, options) + ".tables")).string();
}

CacheResult load_or_precompute_tables(const Atmosphere& atmosphere, const PrecomputeOptions& options,
                                      const std::string& directory) {
  atmosphere.validate();
  options.sizes.validate();
  CacheResult result;
  const std::string key = tables_cache_key(atmosphere, options);
  result.path = tables_cache_path(atmosphere, options, directory);
  if (std::filesystem::exists(result.path)) {
    const std::string problem = read_cache(result.path, key, options, atmosphere, result.tables);
    if (problem.empty()) {
      result.status = CacheStatus::hit;
      return result;
    }
    result.status = CacheStatus::recomputed_invalid;
    result.problem = "cache file " + result.path + " rejected: " + problem;
  }
  result.tables = precompute_tables(atmosphere, options);
  const std::string write_problem = write_cache(result.path, key, result.tables);
  if (!write_problem.empty())
    result.problem += (result.problem.empty() ? "" : "; ") + std::string("cache not stored: ") + write_problem;
  return result;
}

}  // namespace atmos
