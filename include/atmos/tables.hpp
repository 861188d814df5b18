// atmos — precomputed lookup tables of an atmosphere (CPU side).
#pragma once

#include <glm/vec3.hpp>

#include <functional>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"

namespace atmos {

// Texel counts of the tables. The 4D scattering tables are stored as 3D
// textures of (nu * mu_s) x mu x r texels.
struct TableSizes {
  int transmittance_mu = 256;
  int transmittance_r = 64;
  int irradiance_mu_s = 64;
  int irradiance_r = 16;
  int scattering_nu = 8;
  int scattering_mu_s = 32;
  int scattering_mu = 128;  // even: half for rays that hit the ground, half for the others
  int scattering_r = 32;

  // Throws Error for sizes the parameterisation cannot use (too small, odd
  // scattering_mu, more than 64 Mi texels per table).
  void validate() const;
  bool operator==(const TableSizes&) const = default;
};

struct PrecomputeOptions {
  TableSizes sizes;
  int scattering_orders = 4;  // K >= 1: light scattered (or reflected by the ground) at most K times
  // Called from the calling thread with the name of the running step and the
  // fraction of the whole precomputation done, in [0, 1].
  std::function<void(const std::string& step, double fraction)> progress;
};

// Seconds spent in one precomputation step.
struct StepTiming {
  std::string name;
  double seconds = 0.0;
};

// The tables of one triple of working wavelengths; texels are radiance or
// irradiance at those wavelengths (vec3 channel i = wavelength i).
struct TableSet {
  std::vector<glm::vec3> transmittance;        // transmittance_mu x transmittance_r: transmittance to the top
  std::vector<glm::vec3> direct_irradiance;    // irradiance_mu_s x irradiance_r: sun on a horizontal surface, W m^-2 nm^-1
  std::vector<glm::vec3> indirect_irradiance;  // same layout: sky light of orders 1..K-1 on a horizontal surface
  std::vector<glm::vec3> scattering;           // 3D: single Rayleigh + (orders 2..K) / Rayleigh phase, W m^-2 sr^-1 nm^-1 per unit phase
  std::vector<glm::vec3> single_aerosol;       // 3D: single aerosol scattering without its phase function
  std::vector<glm::vec3> multiple_scattering;  // 3D: orders 2..K / Rayleigh phase (zero for K = 1), for the low-sun path
};

struct Tables {
  TableSizes sizes;
  int scattering_orders = 0;
  std::vector<double> wavelengths_nm;  // three per set
  std::vector<TableSet> sets;          // one per wavelength triple
  std::vector<StepTiming> timings;     // filled by precompute_tables (empty when loaded from the cache)

  int scattering_width() const { return sizes.scattering_nu * sizes.scattering_mu_s; }
  int scattering_height() const { return sizes.scattering_mu; }
  int scattering_depth() const { return sizes.scattering_r; }
};

// Computes all tables on the CPU with all cores (TBB).
Tables precompute_tables(const Atmosphere& atmosphere, const PrecomputeOptions& options);

// Disk cache. The file name is a hash of every input of the tables and of the
// format version; the file itself repeats the key and carries a checksum, so a
// stale, truncated or corrupt file is detected and recomputed, never used.
enum class CacheStatus { hit, computed, recomputed_invalid };

struct CacheResult {
  Tables tables;
  CacheStatus status = CacheStatus::computed;
  std::string path;     // the cache file
  std::string problem;  // why an existing file was rejected (recomputed_invalid)
};

// Default cache directory: $ATMOS_CACHE_DIR, else $XDG_CACHE_HOME/atmos, else ~/.cache/atmos.
std::string default_cache_directory();

// Loads the tables from `directory` if a valid file exists, otherwise
// computes and stores them (a failure to write the cache is not an error:
// the tables are returned and `problem` says why they were not stored).
CacheResult load_or_precompute_tables(const Atmosphere& atmosphere, const PrecomputeOptions& options,
                                      const std::string& directory);

// The cache key of these inputs (hex), as used in the file name.
std::string tables_cache_key(const Atmosphere& atmosphere, const PrecomputeOptions& options);

}  // namespace atmos
