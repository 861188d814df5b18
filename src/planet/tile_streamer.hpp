// The globe's tile meshes built in the background: one worker thread builds
// the meshes of the tiles a frame asks for (MeshBuilder::build: the relief,
// the rasters, the morph targets), and the GL thread takes the finished ones
// to upload, a bounded number a frame. A frame's CPU time then no longer
// grows with the tiles it lacks: until its tile arrives an area is drawn by
// its nearest resident ancestor.
//
// Order: coarse levels first (they stand in for the finer ones, and a tile's
// bounds tighten its descendants' culling), then the nearest to the camera.
// Each request() replaces the previous frame's requests, so the queue holds
// at most one frame's missing tiles. A finished mesh of a tile the current
// frame does not ask for is dropped, whether it waits for upload or was
// being built when the requests changed (a generation counter tells the
// worker whether they did). At most max_ready finished meshes wait for the
// GL thread: the worker pauses when they are all there, so the CPU memory
// of the streamer is bounded by max_ready + 1 meshes and one frame's
// requests.
//
// Threading: request(), take() and counts() are for one thread (the GL
// thread); the worker only reads the MeshBuilder (and the Surface and rasters
// behind it, which serialise their GDAL datasets and PROJ transformations:
// raster_source.hpp), which must outlive the streamer.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_set>
#include <vector>

#include "planet/cube_sphere.hpp"
#include "planet/globe_mesh.hpp"

namespace atmos::planet {

struct TileRequest {
  TileKey key;
  double distance_m = 0.0;  // from the camera to the tile (its priority within a level), m
};

struct ReadyTile {
  TileKey key;
  TileMesh mesh;
};

class TileStreamer {
 public:
  // Starts the worker. max_ready >= 1.
  TileStreamer(const MeshBuilder& builder, std::size_t max_ready);
  // Stops the worker once its current tile is built (the queued requests are
  // abandoned) and joins it.
  ~TileStreamer();
  TileStreamer(const TileStreamer&) = delete;
  TileStreamer& operator=(const TileStreamer&) = delete;

  // This frame's missing tiles, replacing the previous requests; the first
  // `limit` of them in the order they are built are queued (those that may
  // fit under the memory cap). Tiles being built or finished are not built
  // again; finished meshes of tiles not in `wanted` are dropped.
  void request(const std::vector<TileRequest>& wanted, std::size_t limit);

  // Up to max_count finished meshes, in the order they were finished
  // (coarse and near first). Throws atmos::Error with the worker's message
  // when a build failed since the last take() (an unreadable raster); the
  // other meshes stay for the next take().
  std::vector<ReadyTile> take(std::size_t max_count);

  struct Counts {
    std::size_t queued = 0;  // requests waiting for the worker, the one it builds included
    std::size_t ready = 0;   // finished meshes waiting for take()
  };
  Counts counts() const;

 private:
  void work();

  const MeshBuilder& builder_;
  const std::size_t max_ready_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;  // the worker waits on it for requests, room or stop
  // Under mutex_:
  std::vector<TileRequest> queue_;  // the current requests, the next one last
  std::unordered_set<std::uint64_t> wanted_;  // packed keys of the current frame's requests
  std::uint64_t generation_ = 0;    // request() calls so far
  bool building_ = false;
  TileKey building_key_;
  std::deque<ReadyTile> ready_;
  std::string error_;  // the first failed build's message since the last take()
  bool stop_ = false;
  std::thread worker_;  // last: started once the members above exist
};

}  // namespace atmos::planet
