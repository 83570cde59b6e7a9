#include "vitamin_e/fusion/tsdf_integrator.h"

#include <stdexcept>

#include "vitamin_e/common/timing.h"

namespace vitamin_e::fusion {

void TsdfIntegratorConfig::validate() const {
  tsdf.validate();
  if (queue_capacity < 1) throw std::invalid_argument("tsdf_integrator.queue_capacity: must be >= 1");
}

TsdfIntegrator::TsdfIntegrator(const TsdfIntegratorConfig& config, int nice_increment)
    : config_(config), volume_(config.tsdf) {
  config_.validate();
  if (config_.asynchronous) {
    // Frames take the queue's places; a scaling is small and must not be lost.
    worker_ = std::make_unique<SerialWorker<Job>>([this](Job& job) { integrateJob(job); },
                                                  [](const Job& job) { return !job.is_scaling; }, nice_increment);
  }
}

void TsdfIntegrator::integrateJob(const Job& job) {
  if (job.is_scaling) {
    std::lock_guard<std::mutex> lock(volume_mutex_);
    volume_.setScaling(job.scaling);
    return;
  }
  const auto t0 = TimingClock::now();
  const double cpu0 = threadCpuMs();
  IntegrationStats frame;
  {
    std::lock_guard<std::mutex> lock(volume_mutex_);
    frame = volume_.integrate(job.mesh, job.T_w_c, job.image);
  }
  const double cpu = threadCpuMs() - cpu0;
  const double ms = elapsedMs(t0);
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.integrated;
  stats_.last_integration_ms = ms;
  stats_.integration_ms += ms;
  stats_.integration_cpu_ms += cpu;
  ++stats_.raster_downscale_frames[frame.raster_downscale];
}

void TsdfIntegrator::submit(meshing::FrameMesh mesh, const Eigen::Isometry3d& T_w_c,
                            const meshing::PinholeImage& image) {
  Job job{std::move(mesh), T_w_c, image, false, {}};
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.submitted;
  }
  enqueue(std::move(job));
}

void TsdfIntegrator::submitScaling(const MapScaling& volume_to_map) {
  if (!volume_to_map.isValid()) throw std::invalid_argument("TsdfIntegrator::submitScaling: a non-positive scale");
  Job job;
  job.is_scaling = true;
  job.scaling = volume_to_map;
  enqueue(std::move(job));
}

void TsdfIntegrator::enqueue(Job job) {
  if (!worker_) {
    integrateJob(job);
    return;
  }
  const std::size_t dropped = worker_->post(std::move(job), config_.queue_capacity,
                                            config_.block_when_full ? WhenFull::kWait : WhenFull::kDropOldest);
  if (dropped > 0) {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    stats_.dropped += dropped;
  }
}

void TsdfIntegrator::flush() {
  if (worker_) worker_->waitIdle();
}

TriangleMesh TsdfIntegrator::extractMesh() {
  std::lock_guard<std::mutex> lock(volume_mutex_);
  return volume_.extractMesh();
}

MeshBlockUpdate TsdfIntegrator::takeChangedBlocks() {
  std::lock_guard<std::mutex> lock(volume_mutex_);
  return volume_.takeChangedBlocks();
}

bool TsdfIntegrator::saveMesh(const std::string& path, std::string* error) {
  return saveMeshPly(extractMesh(), path, error);
}

bool TsdfIntegrator::saveVolume(const std::string& path, std::string* error) {
  flush();
  std::lock_guard<std::mutex> lock(volume_mutex_);
  return volume_.save(path, error);
}

MapScaling TsdfIntegrator::loadVolume(const std::string& path) {
  flush();
  std::lock_guard<std::mutex> lock(volume_mutex_);
  volume_.load(path);
  return volume_.scaling();
}

TsdfIntegratorStats TsdfIntegrator::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

void TsdfIntegrator::reset() {
  if (worker_) {
    const std::size_t dropped = worker_->clear();
    std::lock_guard<std::mutex> lock(stats_mutex_);
    stats_.dropped += dropped;
  }
  flush();
  std::lock_guard<std::mutex> lock(volume_mutex_);
  volume_.clear();
}

}  // namespace vitamin_e::fusion
