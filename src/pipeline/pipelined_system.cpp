#include "vitamin_e/pipeline/pipelined_system.h"

#include <stdexcept>

#include "vitamin_e/common/timing.h"

namespace vitamin_e::pipeline {

PipelinedSystem::PipelinedSystem(const SystemConfig& config, const camera::Camera& camera,
                                 const PipelinedOptions& options, ResultCallback on_result,
                                 System::PoseListener on_pose)
    : PipelinedSystem(std::make_unique<System>(config, camera), options, std::move(on_result), std::move(on_pose)) {}

PipelinedSystem::PipelinedSystem(System& system, const PipelinedOptions& options, ResultCallback on_result,
                                 System::PoseListener on_pose)
    : PipelinedSystem(std::unique_ptr<System>(), options, std::move(on_result), std::move(on_pose), &system) {}

PipelinedSystem::PipelinedSystem(std::unique_ptr<System> owned, const PipelinedOptions& options,
                                 ResultCallback on_result, System::PoseListener on_pose, System* borrowed)
    : owned_(std::move(owned)),
      system_(owned_ ? owned_.get() : borrowed),
      on_result_(std::move(on_result)),
      on_pose_(std::move(on_pose)),
      input_(options.input_capacity, options.drop_oldest),
      tracked_(options.tracked_capacity, false),
      frames_in_mapping_(options.reproducible ? 1 : 0),
      priors_base_(system_->priorsOut()) {
  tracking_thread_ = std::thread([this] { trackingLoop(); });
  mapping_thread_ = std::thread([this] { mappingLoop(); });
}

PipelinedSystem::~PipelinedSystem() {
  input_.close();  // the tracking loop drains the input, then closes tracked_
  if (tracking_thread_.joinable()) tracking_thread_.join();
  if (mapping_thread_.joinable()) mapping_thread_.join();
}

bool PipelinedSystem::submit(const cv::Mat& image, double timestamp, const std::string& timestamp_text) {
  validateImage(image, system_->camera());
  {
    std::lock_guard<std::mutex> lock(count_mutex_);
    ++submitted_;
  }
  std::size_t dropped = 0;
  const bool queued = input_.push(Input{image, timestamp, timestamp_text}, &dropped);
  std::lock_guard<std::mutex> lock(count_mutex_);
  if (!queued) ++dropped;
  dropped_ += dropped;
  finished_ += dropped;
  idle_cv_.notify_all();
  return queued;
}

void PipelinedSystem::trackingLoop() {
  while (std::optional<Input> in = input_.pop()) {
    setBusy(&tracking_busy_, true);
    if (frames_in_mapping_ > 0) {
      // While this frame is tracked the mapping may be on the frame before it, not on an older
      // one: the tracks the older ones dropped end now, at the same frame in every run.
      std::unique_lock<std::mutex> lock(count_mutex_);
      idle_cv_.wait(lock, [this] { return mapped_ + frames_in_mapping_ >= handed_; });
    }
    TrackedFrame frame;
    const double cpu0 = threadCpuMs();
    try {
      // The tracker's priors wait for the pose of the frame before (not for its keyframe
      // work): tracks found again from the newest pose, as in the sequential mode; the flow's
      // pass, most of the tracking, runs beside that mapping.
      frame = system_->trackFrame(
          in->image, in->timestamp, in->timestamp_text,
          [this] {
            std::uint64_t handed = 0;
            {
              std::lock_guard<std::mutex> lock(count_mutex_);
              handed = handed_;
            }
            system_->waitForPriors(priors_base_ + handed);
          },
          frames_in_mapping_);
    } catch (const std::exception& e) {
      frame.skipped = true;
      frame.timestamp = in->timestamp;
      frame.message = std::string("frame skipped: ") + e.what();
    }
    const double cpu = threadCpuMs() - cpu0;
    {
      std::lock_guard<std::mutex> lock(count_mutex_);
      cpu_.tracking_ms += cpu;
      tracking_busy_ = false;  // the frame waits for the mapper now
      ++handed_;
      idle_cv_.notify_all();
    }
    tracked_.push(std::move(frame));
  }
  tracked_.close();
}

void PipelinedSystem::mappingLoop() {
  while (std::optional<TrackedFrame> frame = tracked_.pop()) {
    setBusy(&mapping_busy_, true);
    frame->mapper_behind = tracked_.size() > 0;
    frame->priors_awaited = true;  // put out at the pose (System::waitForPriors)
    const double cpu0 = threadCpuMs();
    FrameResult result = system_->mapFrame(std::move(*frame), on_pose_);
    const double cpu = threadCpuMs() - cpu0;
    {
      std::lock_guard<std::mutex> lock(count_mutex_);
      ++mapped_;
    }
    idle_cv_.notify_all();
    if (on_result_) on_result_(std::move(result));
    std::lock_guard<std::mutex> lock(count_mutex_);
    cpu_.mapping_ms += cpu;
    mapping_busy_ = false;
    ++finished_;
    idle_cv_.notify_all();
  }
}

void PipelinedSystem::flush() {
  std::unique_lock<std::mutex> lock(count_mutex_);
  idle_cv_.wait(lock, [&] { return finished_ >= submitted_; });
}

void PipelinedSystem::setBusy(bool* stage, bool busy) {
  std::lock_guard<std::mutex> lock(count_mutex_);
  *stage = busy;
  idle_cv_.notify_all();
}

void PipelinedSystem::waitUntilNoneWaiting() {
  std::unique_lock<std::mutex> lock(count_mutex_);
  idle_cv_.wait(lock, [&] {
    const std::size_t on_stage = (tracking_busy_ ? 1 : 0) + (mapping_busy_ ? 1 : 0);
    return submitted_ - finished_ <= on_stage;
  });
}

PipelinedSystem::StageCpu PipelinedSystem::stageCpuMs() const {
  std::lock_guard<std::mutex> lock(count_mutex_);
  return cpu_;
}

std::size_t PipelinedSystem::droppedFrames() const {
  std::lock_guard<std::mutex> lock(count_mutex_);
  return dropped_;
}

}  // namespace vitamin_e::pipeline
