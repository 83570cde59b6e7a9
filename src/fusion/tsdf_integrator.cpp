#include "vitamin_e/fusion/tsdf_integrator.h"

#include <algorithm>
#include <stdexcept>

#include "vitamin_e/common/timing.h"

namespace vitamin_e::fusion {

void TsdfIntegratorConfig::validate() const {
  tsdf.validate();
  if (queue_capacity < 1) throw std::invalid_argument("tsdf_integrator.queue_capacity: must be >= 1");
}

TsdfIntegrator::TsdfIntegrator(const TsdfIntegratorConfig& config) : config_(config), volume_(config.tsdf) {
  config_.validate();
  if (config_.asynchronous) worker_ = std::thread([this] { run(); });
}

TsdfIntegrator::~TsdfIntegrator() {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stop_ = true;
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void TsdfIntegrator::integrateJob(const Job& job) {
  if (job.is_scaling) {
    std::lock_guard<std::mutex> lock(volume_mutex_);
    volume_.setScaling(job.scaling);
    return;
  }
  const auto t0 = TimingClock::now();
  const double cpu0 = threadCpuMs();
  {
    std::lock_guard<std::mutex> lock(volume_mutex_);
    volume_.integrate(job.mesh, job.T_w_c, job.image);
  }
  const double cpu = threadCpuMs() - cpu0;
  const double ms = elapsedMs(t0);
  std::lock_guard<std::mutex> lock(queue_mutex_);
  ++stats_.integrated;
  stats_.last_integration_ms = ms;
  stats_.integration_ms += ms;
  stats_.integration_cpu_ms += cpu;
}

void TsdfIntegrator::submit(meshing::FrameMesh mesh, const Eigen::Isometry3d& T_w_c,
                            const meshing::PinholeImage& image) {
  Job job{std::move(mesh), T_w_c, image};
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
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
  if (!config_.asynchronous) {
    integrateJob(job);
    return;
  }
  {
    std::unique_lock<std::mutex> lock(queue_mutex_);
    // Frames count against the capacity; a scaling is small and must not be lost.
    const auto frames = [this] {
      return static_cast<std::size_t>(
          std::count_if(queue_.begin(), queue_.end(), [](const Job& j) { return !j.is_scaling; }));
    };
    if (!job.is_scaling && frames() >= config_.queue_capacity) {
      if (config_.block_when_full) {
        idle_cv_.wait(lock, [&] { return frames() < config_.queue_capacity || stop_; });
      } else {
        queue_.erase(std::find_if(queue_.begin(), queue_.end(), [](const Job& j) { return !j.is_scaling; }));
        ++stats_.dropped;
      }
    }
    queue_.push_back(std::move(job));
  }
  queue_cv_.notify_one();
}

void TsdfIntegrator::run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stop_ and nothing left
      job = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
    }
    idle_cv_.notify_all();
    integrateJob(job);
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      busy_ = false;
    }
    idle_cv_.notify_all();
  }
}

void TsdfIntegrator::flush() {
  if (!config_.asynchronous) return;
  std::unique_lock<std::mutex> lock(queue_mutex_);
  idle_cv_.wait(lock, [this] { return queue_.empty() && !busy_; });
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
  std::lock_guard<std::mutex> lock(queue_mutex_);
  return stats_;
}

void TsdfIntegrator::reset() {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stats_.dropped += static_cast<std::size_t>(
        std::count_if(queue_.begin(), queue_.end(), [](const Job& j) { return !j.is_scaling; }));
    queue_.clear();
  }
  flush();
  std::lock_guard<std::mutex> lock(volume_mutex_);
  volume_.clear();
}

}  // namespace vitamin_e::fusion
