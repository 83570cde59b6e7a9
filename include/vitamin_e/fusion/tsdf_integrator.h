#pragma once
// Runs TsdfVolume integration off the caller's thread: submit() enqueues a
// frame mesh with its pose into a bounded queue consumed by an owned worker
// thread (when full, the oldest queued frame is dropped, or submit() blocks if
// configured). In synchronous mode submit() integrates immediately. A change
// of the map's scaling is queued in order with the frames and never dropped.
// extractMesh() / saveMesh() / takeChangedBlocks() may be called from any thread.
#include <map>
#include <memory>
#include <mutex>

#include "vitamin_e/common/serial_worker.h"
#include "vitamin_e/fusion/tsdf_volume.h"

namespace vitamin_e::fusion {

struct TsdfIntegratorConfig {
  TsdfConfig tsdf;
  bool asynchronous = true;
  std::size_t queue_capacity = 4;
  bool block_when_full = false;  // false: drop the oldest queued frame
  void validate() const;         // throws std::invalid_argument naming the key
};

struct TsdfIntegratorStats {
  std::size_t submitted = 0;
  std::size_t integrated = 0;
  std::size_t dropped = 0;
  double last_integration_ms = 0.0;
  double integration_ms = 0.0;                         // sum over the integrated frames (wall)
  double integration_cpu_ms = 0.0;                     // the same in CPU time of the integrating thread
  std::map<int, std::size_t> raster_downscale_frames;  // frames integrated at each raster downscale
};

class TsdfIntegrator {
 public:
  // The fusion thread runs `nice_increment` nice levels below the thread that starts it
  // (lowerCurrentThreadPriority; DenseMapperConfig::nice_increment).
  explicit TsdfIntegrator(const TsdfIntegratorConfig& config = {}, int nice_increment = 0);
  ~TsdfIntegrator() = default;  // the worker finishes the queued frames, then joins
  TsdfIntegrator(const TsdfIntegrator&) = delete;
  TsdfIntegrator& operator=(const TsdfIntegrator&) = delete;

  void submit(meshing::FrameMesh mesh, const Eigen::Isometry3d& T_w_c, const meshing::PinholeImage& image);
  // TsdfVolume::setScaling after the frames submitted so far, before the later ones.
  void submitScaling(const MapScaling& volume_to_map);
  // Blocks until every submitted frame is integrated (or dropped).
  void flush();
  TriangleMesh extractMesh();
  // TsdfVolume::takeChangedBlocks of the frames fused so far (without waiting for the queue).
  MeshBlockUpdate takeChangedBlocks();
  bool saveMesh(const std::string& path, std::string* error = nullptr);
  TsdfIntegratorStats stats() const;
  void reset();  // clears the queue and the volume
  // TsdfVolume::save / load of the volume (after the queued frames are fused).
  bool saveVolume(const std::string& path, std::string* error = nullptr);
  MapScaling loadVolume(const std::string& path);  // throws TsdfFileError; returns the file's scaling

 private:
  struct Job {
    meshing::FrameMesh mesh;
    Eigen::Isometry3d T_w_c;
    meshing::PinholeImage image;
    bool is_scaling = false;  // not a frame: the volume's scaling becomes `scaling`
    MapScaling scaling;
  };
  void integrateJob(const Job& job);
  void enqueue(Job job);

  TsdfIntegratorConfig config_;
  TsdfVolume volume_;
  mutable std::mutex volume_mutex_;
  mutable std::mutex stats_mutex_;
  TsdfIntegratorStats stats_;
  // Asynchronous only; declared last: destroyed (queue finished, thread joined) before the
  // volume and the stats it writes.
  std::unique_ptr<SerialWorker<Job>> worker_;
};

}  // namespace vitamin_e::fusion
