#include "planet/tile_streamer.hpp"

#include <algorithm>
#include <exception>
#include <iterator>
#include <utility>

#include "atmos/atmosphere.hpp"

namespace atmos::planet {

namespace {

// Whether request a is built before b: coarse levels first, then the
// nearest; the key orders equal ones, so that the order is deterministic.
bool built_before(const TileRequest& a, const TileRequest& b) {
  if (a.key.level != b.key.level) return a.key.level < b.key.level;
  if (a.distance_m != b.distance_m) return a.distance_m < b.distance_m;
  return a.key.packed() < b.key.packed();
}

}  // namespace

TileStreamer::TileStreamer(const MeshBuilder& builder, std::size_t max_ready)
    : builder_(builder), max_ready_(std::max<std::size_t>(max_ready, 1)) {
  // A thread of its own rather than a task in TBB's pool (a task_arena of
  // one slot): the pool has one worker per core, which tbb::parallel_for
  // (the complete_every_frame path, the surface's set-up) and the rest of
  // an application share, so a long-running task there would take a core
  // from them for as long as requests keep coming, and would itself wait
  // behind their tasks; and TBB's idle workers spin before they sleep. This
  // thread sleeps on a condition variable whenever there is nothing to
  // build or no room for what it built, and the scheduler shares the cores
  // between it, the GL thread and the rasteriser's threads.
  worker_ = std::thread([this] { work(); });
}

TileStreamer::~TileStreamer() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void TileStreamer::request(const std::vector<TileRequest>& wanted, std::size_t limit) {
  // The wanted keys and the order, outside the lock; the worker takes the
  // last request first.
  std::unordered_set<std::uint64_t> keys;
  keys.reserve(wanted.size());
  for (const TileRequest& r : wanted) keys.insert(r.key.packed());
  std::vector<TileRequest> order = wanted;
  if (order.size() > limit) {
    std::nth_element(order.begin(), order.begin() + std::ptrdiff_t(limit), order.end(), built_before);
    order.resize(limit);
  }
  std::sort(order.begin(), order.end(), [](const TileRequest& a, const TileRequest& b) { return built_before(b, a); });
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++generation_;
    wanted_.swap(keys);  // the previous frame's set is freed outside the lock
    // Finished meshes this frame does not ask for are dropped; those it asks
    // for, and the tile being built, are not queued again.
    std::unordered_set<std::uint64_t> have;
    for (auto it = ready_.begin(); it != ready_.end();) {
      if (wanted_.count(it->key.packed()) == 0) {
        it = ready_.erase(it);
      } else {
        have.insert(it->key.packed());
        ++it;
      }
    }
    if (building_) have.insert(building_key_.packed());
    queue_.clear();
    std::copy_if(order.begin(), order.end(), std::back_inserter(queue_),
                 [&](const TileRequest& r) { return have.count(r.key.packed()) == 0; });
  }
  wake_.notify_one();
}

std::vector<ReadyTile> TileStreamer::take(std::size_t max_count) {
  std::vector<ReadyTile> out;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!error_.empty()) {
      const std::string message = std::move(error_);
      error_.clear();
      throw Error(message);
    }
    const std::size_t n = std::min(max_count, ready_.size());
    out.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      out.push_back(std::move(ready_.front()));
      ready_.pop_front();
    }
  }
  // Room for the worker's next meshes.
  if (!out.empty()) wake_.notify_one();
  return out;
}

TileStreamer::Counts TileStreamer::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Counts c;
  c.queued = queue_.size() + (building_ ? 1 : 0);
  c.ready = ready_.size();
  return c;
}

void TileStreamer::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || (!queue_.empty() && ready_.size() < max_ready_); });
    if (stop_) return;
    const TileRequest next = queue_.back();
    queue_.pop_back();
    const std::uint64_t generation = generation_;
    building_ = true;
    building_key_ = next.key;
    lock.unlock();
    // The build reads the relief and the rasters only (MeshBuilder::build is
    // const, and RasterSource serialises its GDAL dataset and PROJ
    // transformation), concurrently with the GL thread's height_m queries.
    ReadyTile tile{next.key, {}};
    std::string failure;
    try {
      tile.mesh = builder_.build(next.key);
    } catch (const std::exception& e) {
      failure = e.what();
    } catch (...) {
      failure = "globe: building a tile failed";
    }
    lock.lock();
    building_ = false;
    if (!failure.empty()) {
      if (error_.empty()) error_ = failure;
      continue;
    }
    // Requests replaced while it was built: kept only if still asked for.
    if (generation != generation_ && wanted_.count(next.key.packed()) == 0) continue;
    ready_.push_back(std::move(tile));
  }
}

}  // namespace atmos::planet
