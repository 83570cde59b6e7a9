#include "vitamin_e/fusion/dense_mapper.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <string>
#include <utility>

#include "vitamin_e/common/thread_priority.h"
#include "vitamin_e/common/timing.h"

namespace vitamin_e::fusion {

meshing::FrameMesherConfig lenientMesherConfig() {
  meshing::FrameMesherConfig c;
  c.max_inv_depth_jump = 1.0;
  c.max_normal_angle_deg = 88.0;
  return c;
}

void DenseMapperConfig::validate() const {
  mesher.validate();
  prune.validate();
  nltgv.validate();
  integrator.validate();
  if (min_points < 3) throw std::invalid_argument("dense.min_points must be >= 3");
  if (!isNiceIncrement(nice_increment)) {
    throw std::invalid_argument("dense.nice_increment must be in [0, 19]");
  }
}

namespace {
// The members that use the configuration (the meshing thread's priority) see a checked one.
DenseMapperConfig validated(const DenseMapperConfig& config) {
  config.validate();
  return config;
}
}  // namespace

DenseMapper::DenseMapper(const DenseMapperConfig& config, const meshing::PinholeImage& image)
    : config_(validated(config)),
      image_(image),
      mesher_(config.mesher),
      pruner_(config.prune),
      denoiser_(config.nltgv) {
  image_.validate();
  integrator_ = std::make_unique<TsdfIntegrator>(config_.integrator, config_.nice_increment);
}

DenseFrameStats DenseMapper::addFrame(const DenseFrame& frame) {
  if (!frame.map_scaling.isValid()) {
    throw std::invalid_argument("DenseMapper::addFrame: the map scaling is not finite and positive");
  }
  if (frame.map_scaling != input_scaling_) {
    // What the map went through since the last frame, applied on top of the volume's scaling.
    const MapScaling step = frame.map_scaling.after(input_scaling_.inverse());
    scaling_ = step.after(scaling_);
    integrator_->submitScaling(scaling_);
    input_scaling_ = frame.map_scaling;
  }
  return addFrame(frame.ids, frame.p_c, frame.T_w_c);
}

void DenseMapper::rescale(const Eigen::Vector3d& centre, double factor) {
  if (!(factor > 0.0) || !std::isfinite(factor) || !centre.allFinite()) {
    throw std::invalid_argument("DenseMapper::rescale: the factor must be finite and positive, the centre finite");
  }
  waitMeshed();  // the frames submitted before are fused in the old scale
  scaling_ = MapScaling::about(centre, factor).after(scaling_);
  integrator_->submitScaling(scaling_);
}

DenseFrameStats DenseMapper::addFrame(const std::vector<std::uint64_t>& ids, const std::vector<Eigen::Vector3d>& p_c,
                                      const Eigen::Isometry3d& T_w_c) {
  DenseFrameStats stats;
  if (ids.size() != p_c.size()) throw std::invalid_argument("DenseMapper::addFrame: ids and points differ in size");
  if (static_cast<int>(p_c.size()) < config_.min_points || !T_w_c.matrix().allFinite()) return stats;
  auto t0 = TimingClock::now();
  meshing::FrameMesh mesh = mesher_.buildFromPoints(ids, p_c, image_);
  stats.mesh_ms = elapsedMs(t0);
  if (!config_.denoise) {
    pruner_.prune(&mesh, image_.K);
  } else if (!mesh.triangles.empty()) {
    t0 = TimingClock::now();
    denoiser_.denoise(&mesh, image_.K);
    pruner_.prune(&mesh, image_.K);  // smoothing can open new depth jumps or flip triangles
    stats.denoise_ms = elapsedMs(t0);
  }
  stats.vertices = mesh.vertices.size();
  stats.triangles = mesh.triangles.size();
  if (mesh.triangles.empty()) return stats;
  integrator_->submit(std::move(mesh), T_w_c, image_);
  stats.integrated = true;
  return stats;
}

std::size_t DenseMapper::submitFrame(DenseFrame frame, std::size_t max_waiting, WhenFull when_full) {
  if (frame.ids.size() != frame.p_c.size()) {
    throw std::invalid_argument("DenseMapper::submitFrame: ids and points differ in size");
  }
  if (!frame.map_scaling.isValid()) {
    throw std::invalid_argument("DenseMapper::submitFrame: the map scaling is not finite and positive");
  }
  {
    std::lock_guard<std::mutex> lock(work_stats_mutex_);
    ++work_stats_.submitted;
  }
  const std::size_t dropped = mesh_worker_.post(std::move(frame), max_waiting, when_full);
  if (dropped > 0) {
    std::lock_guard<std::mutex> lock(work_stats_mutex_);
    work_stats_.dropped += dropped;
  }
  return dropped;
}

void DenseMapper::meshSubmitted(const DenseFrame& frame) {
  const double cpu0 = threadCpuMs();
  DenseFrameStats s;
  std::string failure;
  try {
    s = addFrame(frame);
  } catch (const std::exception& e) {
    // Escaping the worker would end the process: the frame is lost, the caller told (workStats).
    failure = e.what();
  }
  const double cpu = threadCpuMs() - cpu0;
  std::lock_guard<std::mutex> lock(work_stats_mutex_);
  work_stats_.mesh_cpu_ms += cpu;
  if (!failure.empty()) {
    ++work_stats_.failed;
    work_stats_.last_failure = std::move(failure);
  }
  if (s.integrated) {
    ++work_stats_.meshed;
    mesh_timings_.add("mesh", s.mesh_ms + s.denoise_ms);
  }
}

void DenseMapper::waitMeshed() { mesh_worker_.waitIdle(); }

DenseWorkStats DenseMapper::workStats() const {
  std::lock_guard<std::mutex> lock(work_stats_mutex_);
  return work_stats_;
}

const StageTimings& DenseMapper::meshTimings() const { return mesh_timings_; }

void DenseMapper::flush() {
  waitMeshed();
  integrator_->flush();
}

TriangleMesh DenseMapper::extractMesh() {
  flush();
  return integrator_->extractMesh();
}

bool DenseMapper::saveMesh(const std::string& path, std::string* error) {
  flush();
  return integrator_->saveMesh(path, error);
}

bool DenseMapper::saveTsdf(const std::string& path, std::string* error) {
  waitMeshed();
  return integrator_->saveVolume(path, error);
}

void DenseMapper::loadTsdf(const std::string& path) {
  waitMeshed();
  scaling_ = integrator_->loadVolume(path);
}

MeshBlockUpdate DenseMapper::takeChangedBlocks() { return integrator_->takeChangedBlocks(); }

TsdfIntegratorStats DenseMapper::integratorStats() const { return integrator_->stats(); }

void DenseMapper::reset() {
  mesh_worker_.clear();
  waitMeshed();
  integrator_->reset();
  denoiser_.reset();
  scaling_ = MapScaling{};
  input_scaling_ = MapScaling{};
}

}  // namespace vitamin_e::fusion
