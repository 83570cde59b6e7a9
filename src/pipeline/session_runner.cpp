#include "vitamin_e/pipeline/session_runner.h"

#include <stdexcept>

#include "vitamin_e/common/timing.h"

namespace vitamin_e::pipeline {

SessionRunner::SessionRunner(const SystemConfig& config, const camera::Camera& camera, const SessionConfig& session,
                             const RunnerOptions& options, ResultCallback on_result, PoseCallback on_pose)
    : session_(config, camera, session),
      options_(options),
      on_result_(std::move(on_result)),
      on_pose_(std::move(on_pose)) {
  if (options_.queue_frames == 0) throw std::invalid_argument("SessionRunner: queue_frames must be >= 1");
  if (options_.pipelined) startPipeline();
}

SessionRunner::~SessionRunner() { stopPipeline(); }

void SessionRunner::stopPipeline() {
  if (!pipeline_) return;
  const PipelinedSystem::StageCpu cpu = pipeline_->stageCpuMs();
  pipeline_.reset();  // its frames finished first
  stopped_cpu_.tracking_ms += cpu.tracking_ms;
  stopped_cpu_.mapping_ms += cpu.mapping_ms;
}

PipelinedSystem::StageCpu SessionRunner::stageCpuMs() const {
  PipelinedSystem::StageCpu cpu = stopped_cpu_;
  if (pipeline_) {
    const PipelinedSystem::StageCpu running = pipeline_->stageCpuMs();
    cpu.tracking_ms += running.tracking_ms;
    cpu.mapping_ms += running.mapping_ms;
  }
  return cpu;
}

void SessionRunner::startPipeline() {
  // Blocking queues: every frame given to process() comes out, in order, so that the
  // tickets match the results; a live caller drops frames before process().
  PipelinedOptions p;
  p.input_capacity = options_.queue_frames;
  p.tracked_capacity = options_.queue_frames;
  p.drop_oldest = false;
  p.reproducible = options_.reproducible;
  System::PoseListener on_pose;
  if (on_pose_) on_pose = [this](const FramePose& pose) { onPipelinePose(pose); };
  pipeline_ = std::make_unique<PipelinedSystem>(
      session_.system(), p, [this](FrameResult result) { onPipelineResult(std::move(result)); }, std::move(on_pose));
}

SessionStamp SessionRunner::admit(double timestamp) {
  if (!pipeline_ || !session_.stampGoesBack(timestamp)) return session_.admit(timestamp);
  // A time jump may restart the tracking or replace the System (Session::reset): the
  // pipeline is emptied and stopped first, and started again on the session's System.
  stopPipeline();
  SessionStamp s = session_.admit(timestamp);
  startPipeline();
  return s;
}

bool SessionRunner::process(const cv::Mat& image, double timestamp, const std::string& timestamp_text,
                            std::uint64_t ticket) {
  if (!pipeline_) {
    System::PoseListener on_pose;
    if (on_pose_) on_pose = [this, ticket](const FramePose& pose) { on_pose_(pose, ticket); };
    // System::process, its two stages timed apart.
    System& system = session_.system();
    const double cpu0 = threadCpuMs();
    TrackedFrame tracked = system.trackFrame(image, timestamp, timestamp_text);
    const double cpu1 = threadCpuMs();
    FrameResult result = system.mapFrame(std::move(tracked), on_pose);
    stopped_cpu_.tracking_ms += cpu1 - cpu0;
    stopped_cpu_.mapping_ms += threadCpuMs() - cpu1;
    if (on_result_) on_result_(std::move(result), ticket);
    return true;
  }
  {
    // Before submit(): its result may come before submit() returns.
    std::lock_guard<std::mutex> lock(tickets_mutex_);
    tickets_.push_back(ticket);
  }
  bool queued = false;
  try {
    queued = pipeline_->submit(image, timestamp, timestamp_text);
  } catch (...) {
    std::lock_guard<std::mutex> lock(tickets_mutex_);
    tickets_.pop_back();  // not queued: no result takes it (earlier frames take the front)
    throw;
  }
  if (!queued) {
    std::lock_guard<std::mutex> lock(tickets_mutex_);
    tickets_.pop_back();
  }
  return queued;
}

void SessionRunner::onPipelineResult(FrameResult&& result) {
  std::uint64_t ticket = 0;
  {
    std::lock_guard<std::mutex> lock(tickets_mutex_);
    ticket = tickets_.front();
    tickets_.pop_front();
  }
  if (on_result_) on_result_(std::move(result), ticket);
}

void SessionRunner::onPipelinePose(const FramePose& pose) {
  std::uint64_t ticket = 0;
  {
    // The frame being mapped is the oldest without a result.
    std::lock_guard<std::mutex> lock(tickets_mutex_);
    ticket = tickets_.front();
  }
  on_pose_(pose, ticket);
}

void SessionRunner::flush() {
  if (pipeline_) pipeline_->flush();
}

void SessionRunner::waitUntilNoneWaiting() {
  if (pipeline_) pipeline_->waitUntilNoneWaiting();
}

void SessionRunner::reset(const std::string& why) {
  if (!pipeline_) {
    session_.reset(why);
    return;
  }
  stopPipeline();  // its System is replaced
  session_.reset(why);
  startPipeline();
}

std::size_t SessionRunner::inFlight() const {
  std::lock_guard<std::mutex> lock(tickets_mutex_);
  return tickets_.size();
}

}  // namespace vitamin_e::pipeline
