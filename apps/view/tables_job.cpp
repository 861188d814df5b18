#include "tables_job.hpp"

#include <tbb/task_arena.h>

#include <chrono>
#include <filesystem>
#include <utility>

#include "atmos/planet_file.hpp"

#ifdef ATMOS_VIEW_HDF5
#include <hdf5.h>
#endif

namespace atmos_view {

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

namespace {

std::string cache_directory(const CacheConfig& cache) {
  return cache.directory.empty() ? atmos::default_cache_directory() : cache.directory;
}

}  // namespace

PlanetTables load_planet(const PlanetParams& params, bool globe) {
  PlanetTables out;
  out.params = params;
  out.planet = make_atmosphere(params);
  if (globe) {
    out.surface = atmos::load_surface(params.planet);
    out.air = atmos::extend_below_datum(out.planet, out.surface);
  } else {
    out.air = out.planet;
  }
  return out;
}

void load_tables(PlanetTables& planet, bool ground_albedo_response, const CacheConfig& cache,
                 const std::function<void(const std::string&, double)>& progress) {
  const double start = now_s();
  atmos::PrecomputeOptions options = make_precompute_options(planet.params, ground_albedo_response);
  options.progress = progress;
  if (cache.disabled) {
    planet.tables = atmos::precompute_tables(planet.air, options);
    planet.status = "computed (cache disabled)";
  } else {
    atmos::CacheResult r = atmos::load_or_precompute_tables(planet.air, options, cache_directory(cache));
    planet.status = r.status == atmos::CacheStatus::hit ? "loaded from the cache" : "computed and cached";
    planet.tables = std::move(r.tables);
  }
  planet.seconds = now_s() - start;
}

PlanetTables load_planet_tables(const PlanetParams& params, bool globe, bool ground_albedo_response,
                                const CacheConfig& cache,
                                const std::function<void(const std::string&, double)>& progress) {
  const double start = now_s();
  PlanetTables out = load_planet(params, globe);
  load_tables(out, globe && ground_albedo_response, cache, progress);
  out.seconds = now_s() - start;
  return out;
}

std::optional<PlanetTables> instant_preview(const PlanetTables& planet, bool ground_albedo_response,
                                            const CacheConfig& cache) {
  const double start = now_s();
  const atmos::PrecomputeOptions options = make_precompute_options(planet.params, ground_albedo_response);
  if (!cache.disabled && std::filesystem::exists(atmos::tables_cache_path(planet.air, options, cache_directory(cache))))
    return std::nullopt;
  PlanetTables out = planet;
  out.instant = atmos::compute_instant_tables(out.air, options.sizes);
  out.status = "instant approximation (exact tables being computed)";
  out.seconds = now_s() - start;
  return out;
}

TableJob::TableJob(CacheConfig cache, bool globe, bool ground_albedo_response, int threads, WarmUp warm_up,
                   bool instant_preview)
    : cache_(std::move(cache)),
      globe_(globe),
      ground_albedo_response_(ground_albedo_response),
      instant_preview_(instant_preview),
      threads_(threads < 1 ? 1 : threads),
      warm_up_(std::move(warm_up)),
      worker_([this] { run(); }) {}

TableJob::~TableJob() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    waiting_.reset();
  }
  wake_.notify_all();
  worker_.join();
}

void TableJob::request(const PlanetParams& params, bool warm_up) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    waiting_ = params;
    waiting_warm_up_ = warm_up;
  }
  wake_.notify_all();
}

std::optional<PlanetTables> TableJob::take_result() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<PlanetTables> out = std::move(result_);
  result_.reset();
  return out;
}

std::optional<std::string> TableJob::take_error() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<std::string> out = std::move(error_);
  error_.reset();
  return out;
}

TableJob::Progress TableJob::progress() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Progress p;
  p.busy = busy_ || waiting_.has_value();
  p.step = step_;
  p.fraction = fraction_;
  p.elapsed_s = busy_ ? now_s() - started_s_ : 0.0;
  return p;
}

void TableJob::run() {
#ifdef ATMOS_VIEW_HDF5
  // The pass's air reaches down to the globe's lowest ground
  // (extend_below_datum), which reads the surface's rasters and coastline
  // bins with GDAL on this thread. Its netCDF driver probes optional HDF5
  // attributes, and HDF5 prints each failed probe as an error stack unless
  // printing is off; that setting is per thread, and netCDF turns it off
  // only in the thread that initialised it.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
#endif
  tbb::task_arena arena(threads_);
  for (;;) {
    PlanetParams params;
    bool warm_up = true;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || waiting_.has_value(); });
      if (stop_) return;
      params = std::move(*waiting_);
      warm_up = waiting_warm_up_;
      waiting_.reset();
      busy_ = true;
      step_.clear();
      fraction_ = -1.0;
      started_s_ = now_s();
    }
    const auto progress = [this](const std::string& step, double fraction) {
      std::lock_guard<std::mutex> lock(mutex_);
      step_ = step;
      fraction_ = fraction;
    };
    // Whether tables of this request would still be shown (the viewer is
    // not closing, no newer request supersedes them).
    const auto shown = [this] {
      std::lock_guard<std::mutex> lock(mutex_);
      return !stop_ && !waiting_;
    };
    // Draws tables once in the warm-up's own context, so that their first
    // frame on screen finds its programs compiled (TableJob::WarmUp).
    const auto warm = [&](const PlanetTables& t) {
      if (!warm_up || !warm_up_ || !shown()) return;
      progress("compiling the shaders", -1.0);
      arena.execute([&] {
        try {
          warm_up_(t);
        } catch (const std::exception&) {
        }
      });
    };
    // The planet without its tables (its surface's rasters read once for
    // both kinds of tables), then the instant mode's tables first, shown
    // instead of the old ones while the exact ones are computed (not when
    // those are in the cache: reading them is as quick; nor for the first
    // tables, warm_up false, which nothing on screen waits for). An error of
    // the preview is the exact tables' too, which report it.
    const bool response = globe_ && ground_albedo_response_;
    std::optional<PlanetTables> tables;
    std::optional<std::string> error;
    arena.execute([&] {
      try {
        const double start = now_s();
        tables = load_planet(params, globe_);
        const double planet_s = now_s() - start;
        if (instant_preview_ && warm_up) {
          progress("instant approximation", -1.0);
          std::optional<PlanetTables> preview;
          try {
            preview = instant_preview(*tables, response, cache_);
          } catch (const std::exception&) {
          }
          if (preview) {
            preview->seconds += planet_s;
            warm(*preview);
            std::lock_guard<std::mutex> lock(mutex_);
            if (!stop_ && !waiting_) result_ = std::move(preview);
            step_.clear();
          }
        }
        load_tables(*tables, response, cache_, progress);
        tables->seconds += planet_s;
      } catch (const std::exception& e) {
        tables.reset();
        error = e.what();
      }
    });
    if (tables) warm(*tables);
    std::lock_guard<std::mutex> lock(mutex_);
    busy_ = false;
    // A newer request supersedes these tables: they are dropped unseen.
    if (waiting_) continue;
    if (tables) result_ = std::move(tables);
    if (error) error_ = std::move(error);
  }
}

}  // namespace atmos_view
