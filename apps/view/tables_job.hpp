// atmos view: the tables of a planet, loaded from the cache or precomputed
// on a thread of their own while the viewer keeps drawing the old ones.
//
// The precomputation (atmos::precompute_tables) runs on the CPU with TBB;
// the job runs it in a task arena of `threads` workers so that the
// viewer's frames (the software rasteriser's threads) keep a core. The
// newest request wins: a request made while another is computed replaces
// any request still waiting, and runs when the current one ends.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "scene.hpp"
#include "state.hpp"

namespace atmos_view {

// Seconds on the steady clock, for durations (its epoch is unspecified).
double now_s();

struct CacheConfig {
  std::string directory;  // "": atmos::default_cache_directory()
  bool disabled = false;  // always precompute, neither read nor write
};

// The planet of `params` and its tables, from the cache or computed (the
// tables of the pass's air: the planet continued below its datum to the
// globe's lowest ground). `progress` as PrecomputeOptions::progress.
// Throws atmos::Error for bad parameters or an unreadable planet file.
PlanetTables load_planet_tables(const PlanetParams& params, bool globe, bool ground_albedo_response,
                                const CacheConfig& cache,
                                const std::function<void(const std::string&, double)>& progress = {});

// The planet of `params` without its tables (`tables` empty): its
// atmosphere, its surface (with `globe`) and the pass's air. Throws
// atmos::Error for bad parameters or an unreadable planet file.
PlanetTables load_planet(const PlanetParams& params, bool globe);
// Its exact tables, from the cache or computed (load_planet_tables).
void load_tables(PlanetTables& planet, bool ground_albedo_response, const CacheConfig& cache,
                 const std::function<void(const std::string&, double)>& progress = {});
// A copy of `planet` with the instant mode's tables (Hillaire 2020,
// atmos::compute_instant_tables: a fraction of a second), or nothing when
// its exact tables are in the cache.
std::optional<PlanetTables> instant_preview(const PlanetTables& planet, bool ground_albedo_response,
                                            const CacheConfig& cache);

class TableJob {
 public:
  // Run on the job's thread after each set of tables is ready, before it is
  // handed over: the viewer compiles the new scene's programs there in a
  // context of its own (they differ with the atmosphere, and compiling them
  // takes seconds on a software rasteriser), which fills the driver's
  // shader cache so that the swap on the viewer's thread finds them
  // compiled. Its exceptions are ignored (the swap then compiles them).
  using WarmUp = std::function<void(const PlanetTables&)>;

  // `instant_preview`: each request made with `warm_up` (tables that
  // replace others on screen) first hands over the instant mode's tables
  // (instant_preview), then the exact ones.
  TableJob(CacheConfig cache, bool globe, bool ground_albedo_response, int threads, WarmUp warm_up = {},
           bool instant_preview = false);
  // Waits for the tables being computed (the precomputation cannot be
  // interrupted; their warm-up is skipped) and drops any waiting request.
  ~TableJob();
  TableJob(const TableJob&) = delete;
  TableJob& operator=(const TableJob&) = delete;

  // `warm_up`: run the WarmUp once the tables are ready (the first tables,
  // with nothing on screen yet, need not).
  void request(const PlanetParams& params, bool warm_up = true);
  // The newest finished tables, once (then empty until the next ones): a
  // request's instant preview, then its exact tables.
  std::optional<PlanetTables> take_result();
  // The error of the newest failed request, once.
  std::optional<std::string> take_error();

  struct Progress {
    bool busy = false;
    std::string step;       // the running step ("" while loading or before the first step)
    double fraction = -1.0;  // of the whole, [0, 1]; < 0: unknown (a cache look-up)
    double elapsed_s = 0.0;
  };
  Progress progress() const;

 private:
  void run();

  CacheConfig cache_;
  bool globe_, ground_albedo_response_, instant_preview_;
  int threads_;
  WarmUp warm_up_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<PlanetParams> waiting_;
  bool waiting_warm_up_ = true;
  std::optional<PlanetTables> result_;
  std::optional<std::string> error_;
  bool busy_ = false, stop_ = false;
  std::string step_;
  double fraction_ = -1.0;
  double started_s_ = 0.0;
  std::thread worker_;
};

}  // namespace atmos_view
