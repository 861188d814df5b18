// atmos — precomputed lookup tables of an atmosphere (CPU side).
#pragma once

#include <glm/vec3.hpp>

#include <functional>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/table_sizes.hpp"

namespace atmos {

// Scattering orders: a fixed count, or `auto`: orders are added until the
// last one adds less than `auto_orders_tolerance` of the light gathered so
// far, in every channel, both over the whole scattering table and in the sky
// light on the ground, and so would the rest of the series where the orders
// decay geometrically (the ratio of the last two orders foretells it); at
// most `scattering_orders`, the cap, in that case. With the tail solver
// (solve_tail, below) a series that the same ratio foretells to reach the
// cap unconverged is handed to the solver from order 16 instead (Venus,
// Titan, 10x and 100x Earth): the same light, in fewer steps.
struct PrecomputeOptions {
  TableSizes sizes;
  int scattering_orders = 4;  // K >= 1: light scattered (or reflected by the ground) at most K times
  bool auto_orders = false;
  double auto_orders_tolerance = 1e-3;
  // With auto orders, when the cap is reached before the tolerance, or from
  // order 16 when the orders foretell that it will be (an optically thick,
  // nearly conservative atmosphere such as Venus, where the light that
  // reaches the ground has been scattered hundreds of times and each order
  // adds almost as much as the one before): the light of all further orders
  // is solved for at once instead of being left out or summed — GMRES
  // with deflated restarts on the transport equation of the remaining light
  // (src/precompute/tail.cpp), until the residual of every wavelength is
  // below `tail_tolerance` of the first missing order, in at most
  // `tail_iterations` steps of about one order's cost each, keeping up to 31
  // tables of the scattering table's size (Venus at the default sizes: 16
  // orders, then 105 steps with 3 wavelengths, the light of the orders
  // after 16 being 0.70 of all of it; a tail that reaches the cap is kept,
  // with its residual in Tables::convergence).
  // Tables::convergence then ends with an entry marked `tail`. Fixed orders
  // (auto_orders false) never solve the tail: K orders mean light scattered
  // at most K times.
  bool solve_tail = true;
  double tail_tolerance = 1e-5;
  int tail_iterations = 200;
  // Also compute the tables over a second ground albedo, at each wavelength
  // 0 or 1, the far end from the planet's (Tables::ground_response), from which the run time lights the air and
  // the ground over the albedo actually below them (a regional average, not
  // the planet file's constant): tables_for_ground_albedo,
  // AtmospherePass::set_ground_albedo. The scattering orders (not the
  // transmittance or the single scattering) are computed a second time, and
  // the tables hold three more scattering-sized arrays.
  bool ground_albedo_response = false;
  // Called from the calling thread with the name of the running step and the
  // fraction of the whole precomputation done, in [0, 1].
  std::function<void(const std::string& step, double fraction)> progress;
};

// Seconds spent in one precomputation step.
struct StepTiming {
  std::string name;
  double seconds = 0.0;
};

// The render tables (one texture set, whatever the number of wavelengths).
// Their three channels are the radiance at the three working wavelengths
// (three-wavelength mode), or linear sRGB / 683 (spectral mode: every
// wavelength triple converted and summed; see physics/definitions.glsl).
struct TableSet {
  std::vector<glm::vec3> direct_irradiance;    // irradiance_mu_s x irradiance_r: sun on a horizontal surface, W m^-2 nm^-1
  std::vector<glm::vec3> indirect_irradiance;  // same layout: sky light of orders 1..K-1 on a horizontal surface
  std::vector<glm::vec3> scattering;           // 3D: single Rayleigh + (orders 2..K) / Rayleigh phase, W m^-2 sr^-1 nm^-1 per unit phase
  std::vector<glm::vec3> single_aerosol;       // 3D: single aerosol scattering without its phase function
  std::vector<glm::vec3> multiple_scattering;  // 3D: orders 2..K / Rayleigh phase (zero for K = 1), for the low-sun path
};

// Convergence of the orders: the luminance (cd/m², or its channel sum in
// three-wavelength mode) that order n adds, summed over the scattering table.
struct OrderContribution {
  int order = 0;
  double added = 0.0;     // what this order adds
  double relative = 0.0;  // added / everything up to and including this order
  // The last entry, when PrecomputeOptions::solve_tail summed the orders
  // after the explicit ones: `order` is the first of them (the last explicit
  // order + 1; the largest over the wavelength triples), `added` their
  // light, `relative` its share of all the light, `iterations` the solver's
  // steps and `residual` its largest relative residual.
  bool tail = false;
  int iterations = 0;
  double residual = 0.0;
};

// How the render tables depend on the albedo of the ground below the air:
// the same tables over a second albedo, at each wavelength 0 or 1
// (PrecomputeOptions::ground_albedo_response). Light reflected by a Lambertian ground of albedo
// a and sent back down by the air, reflected again, and so on, adds up as a
// geometric series of ratio a S, S the atmosphere's spherical albedo seen
// from below (Tanré et al. 1979; Vermote et al. 1997): every
// albedo-dependent quantity is L(a) = L(0) + a G / (1 - a S), G its part
// per unit albedo of the first reflection. Two sets (the planet's albedo
// and this one) fix S from the sky irradiance on the ground and G per
// texel; tables_for_ground_albedo applies the series at any albedo.
struct GroundAlbedoResponse {
  // The ground albedo of these tables per channel: 0 or 1 in
  // three-wavelength mode, the sunlight-weighted mean of the wavelengths'
  // 0 or 1 per sRGB channel in spectral mode.
  glm::vec3 albedo{0.0f};
  // The ground albedo of Tables::set per channel: the atmosphere's at the
  // three wavelengths, or its sunlight-weighted mean per sRGB channel in
  // spectral mode.
  glm::vec3 planet_albedo{0.0f};
  // S per channel, dimensionless in [0, 1): the fraction of the light leaving
  // a Lambertian ground upwards that the air scatters back down to it.
  glm::vec3 spherical_albedo{0.0f};
  // As TableSet, over a ground of `albedo` (the other tables do not depend on it).
  std::vector<glm::vec3> indirect_irradiance;
  std::vector<glm::vec3> scattering;
  std::vector<glm::vec3> multiple_scattering;
  bool empty() const { return scattering.empty(); }
};

struct Tables {
  TableSizes sizes;
  int scattering_orders = 0;           // the orders computed (with auto orders: where it stopped)
  std::vector<double> wavelengths_nm;  // the N working wavelengths
  TableSet set;                        // the render tables
  // The optical depth to the top of the atmosphere at every wavelength
  // triple (T = exp(-depth); see transmittance_to_top_atmosphere_boundary),
  // triple k being the k-th of ceil(N / 3) tables side by side, followed by
  // the same for the delta-M scaled medium (transmittance_tiles()):
  // (transmittance_mu * 2 ceil(N / 3)) x transmittance_r texels. The run
  // time computes every transmittance from the first half, spectrally, and
  // integrates the low-sun single scattering with the second.
  std::vector<glm::vec3> spectral_optical_depth;
  std::vector<OrderContribution> convergence;  // orders 2..K, then the tail if solved (filled by precompute_tables)
  std::vector<StepTiming> timings;             // filled by precompute_tables (empty when loaded from the cache)
  GroundAlbedoResponse ground_response;        // empty unless PrecomputeOptions::ground_albedo_response

  int spectral_sets() const { return int((wavelengths_nm.size() + 2) / 3); }
  // Tiles of spectral_optical_depth: one per wavelength triple for the true
  // medium, then one per triple for the delta-M scaled medium the single
  // scattering reads (a copy of the first where no aerosol lobe is scaled).
  int transmittance_tiles() const { return 2 * spectral_sets(); }
  int scattering_width() const { return sizes.scattering_nu * sizes.scattering_mu_s; }
  int scattering_height() const { return sizes.scattering_mu; }
  int scattering_depth() const { return sizes.scattering_r; }
};

// Computes all tables on the CPU with all cores (TBB).
Tables precompute_tables(const Atmosphere& atmosphere, const PrecomputeOptions& options);

// The tables of the instant approximate mode (Hillaire 2020): no 4D table.
// The sky and the aerial perspective are integrated along the view rays every
// frame from the transmittance and a small 2D table of multiple scattering,
// the light scattered twice or more taken as isotropic at each point
// (docs/instant.md). For a view within a frame of a parameter change while
// the exact tables are computed, and for small GPUs: 0.4 MB of tables at the
// default sizes instead of 38 MB (AtmospherePass's per-frame sky-view table
// and volume, 14 MB, are the same in both modes), and 0.2 s of precomputation
// for three wavelengths on 2 cores instead of tens of seconds
// (compute_instant_tables). Less exact than Tables: docs/instant.md gives its
// error against the reference.
struct InstantTables {
  TableSizes sizes;                    // transmittance_* and irradiance_* are used
  std::vector<double> wavelengths_nm;  // the N working wavelengths
  // As Tables::spectral_optical_depth: (transmittance_mu * 2 ceil(N / 3)) x
  // transmittance_r texels, the true medium's tiles then the delta-M scaled ones.
  std::vector<glm::vec3> spectral_optical_depth;
  // Ψ_ms, the isotropic radiance of the light scattered two or more times
  // per unit scattering coefficient and solar irradiance (sr^-1), over
  // (mu_s, altitude) at every wavelength triple: (multiple_scattering_mu_s
  // ceil(N / 3)) x multiple_scattering_r texels (physics/instant_atmosphere.glsl).
  int multiple_scattering_mu_s = 32;
  int multiple_scattering_r = 32;
  std::vector<glm::vec3> multiple_scattering;
  // The sky irradiance on a horizontal surface, as TableSet::indirect_irradiance
  // (irradiance_mu_s x irradiance_r, W m^-2 nm^-1 in the tables' channels).
  std::vector<glm::vec3> indirect_irradiance;
  std::vector<StepTiming> timings;  // transmittance, multiple_scattering, sky_irradiance

  int spectral_sets() const { return int((wavelengths_nm.size() + 2) / 3); }
  int transmittance_tiles() const { return 2 * spectral_sets(); }
};

// Computes the instant mode's tables on the CPU with all cores (TBB), at
// `sizes`' transmittance and irradiance sizes (the others are unused).
// Throws Error on an invalid atmosphere or sizes.
InstantTables compute_instant_tables(const Atmosphere& atmosphere, const TableSizes& sizes = {});

// Throws Error unless `tables` were computed for the wavelengths of
// `atmosphere` and hold as many texels as their sizes say.
void check_tables_match(const Atmosphere& atmosphere, const InstantTables& tables);

// The render tables over a Lambertian ground of albedo `albedo` per channel
// (dimensionless, in [0, 1]; the three working wavelengths' in
// three-wavelength mode, linear sRGB in spectral mode): Tables::set with its
// sky irradiance and multiple scattering moved along the series of
// GroundAlbedoResponse. Exact at the planet's albedo and at the response's;
// between and beyond, as exact as the series' premise that every
// reflection's light has the first one's angular distribution
// (docs/accuracy.md, The ground's albedo at run time). Throws Error when `tables` have no
// ground response or the albedo is not in [0, 1].
TableSet tables_for_ground_albedo(const Tables& tables, const glm::vec3& albedo);

// Throws Error unless `tables` were computed for the wavelengths of
// `atmosphere` and hold as many texels as their sizes say (what the renderers
// and the sky model check before reading them).
void check_tables_match(const Atmosphere& atmosphere, const Tables& tables);

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
// The file in `directory` that load_or_precompute_tables reads these
// tables from (whether it exists says whether they are cached; a file
// there may still prove stale or corrupt when read).
std::string tables_cache_path(const Atmosphere& atmosphere, const PrecomputeOptions& options,
                              const std::string& directory);

}  // namespace atmos
