#pragma once
// The SLAM system as two owned stages on two threads, joined by bounded queues:
//   submit() -> [input queue] -> tracking thread (dense tracker, undistortion)
//            -> [tracked queue] -> mapping thread (init, pose, BA, map) -> on_result
// While frame k is being mapped, frame k+1 is already being tracked. Results
// arrive in frame order and differ slightly from System::process (deterministic,
// used by the tests): the tracker gets the mapping stage's track rejections and its
// priors later. PipelinedOptions::reproducible chooses how.
#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <opencv2/core.hpp>

#include "vitamin_e/common/bounded_queue.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/pipeline/tracked_frame.h"

namespace vitamin_e::pipeline {

struct PipelinedOptions {
  std::size_t input_capacity = 2;    // frames waiting for the tracker
  std::size_t tracked_capacity = 2;  // tracked frames waiting for the mapper (fewer: less latency, live)
  bool drop_oldest = false;          // live input: drop the oldest waiting frame instead of blocking submit()
  // true (offline): the mapping's track rejections reach the tracker one frame later than in
  // sequential mode and the tracker reads the frame before's early priors (put out at its pose):
  // a run gives the same results every time (System::trackFrame's frames_in_mapping 1), except
  // where pipeline.defer_keyframe_ba follows the load. false (live): each as soon as the mapping
  // has put it out, fresher (lower latency measured live; docs/PERFORMANCE.md) but dependent on
  // the threads' timing, as a live camera's dropped frames make a run anyway.
  bool reproducible = true;
};

class PipelinedSystem {
 public:
  using ResultCallback = std::function<void(FrameResult)>;

  // on_result is called on the mapping thread, once per processed frame, in order; on_pose
  // (optional) on the same thread before it, with the pose of a tracked frame before its
  // map work (System::PoseListener).
  PipelinedSystem(const SystemConfig& config, const camera::Camera& camera, const PipelinedOptions& options,
                  ResultCallback on_result, System::PoseListener on_pose = {});
  // The same on a System the caller owns (it must outlive this, and nothing else may
  // use it until flush() or the destructor has returned).
  PipelinedSystem(System& system, const PipelinedOptions& options, ResultCallback on_result,
                  System::PoseListener on_pose = {});
  ~PipelinedSystem();  // finishes the submitted frames, then joins both threads
  PipelinedSystem(const PipelinedSystem&) = delete;
  PipelinedSystem& operator=(const PipelinedSystem&) = delete;

  // Queues a frame (the image is shared, not copied: do not write to it
  // afterwards). Throws std::invalid_argument for a wrong image type or size,
  // like System::process. Returns false if the system is shutting down.
  bool submit(const cv::Mat& image, double timestamp, const std::string& timestamp_text = "");
  // Blocks until every submitted frame has been mapped (or dropped).
  void flush();
  // Blocks until no submitted frame waits for a stage (the tracker and the mapper may each be
  // on one): a live caller that then takes its newest frame keeps stale frames out of the
  // queues, and the latency at about one tracking plus one or two mappings.
  void waitUntilNoneWaiting();
  std::size_t droppedFrames() const;
  // CPU time [ms] the two threads spent in trackFrame and in mapFrame so far
  // (on_pose included, on_result not; the tracker's helper threads not either).
  struct StageCpu {
    double tracking_ms = 0.0;
    double mapping_ms = 0.0;
  };
  StageCpu stageCpuMs() const;

  // The underlying system, for trajectory(), mapPoints(), counters: call only
  // after flush() (the mapping thread is idle then).
  const System& system() const { return *system_; }
  // The same for changes (System::loadMap before the first submit(),
  // System::setLocalizationOnly): only while the mapping thread is idle.
  System& system() { return *system_; }

 private:
  struct Input {
    cv::Mat image;
    double timestamp;
    std::string timestamp_text;
  };
  PipelinedSystem(std::unique_ptr<System> owned, const PipelinedOptions& options, ResultCallback on_result,
                  System::PoseListener on_pose, System* borrowed = nullptr);
  void trackingLoop();
  void setBusy(bool* stage, bool busy);  // under count_mutex_, waking the waiters
  void mappingLoop();

  std::unique_ptr<System> owned_;  // null when the caller owns the System
  System* system_;
  ResultCallback on_result_;
  System::PoseListener on_pose_;
  BoundedQueue<Input> input_;
  BoundedQueue<TrackedFrame> tracked_;
  std::thread tracking_thread_, mapping_thread_;
  mutable std::mutex count_mutex_;
  std::condition_variable idle_cv_;
  std::size_t submitted_ = 0, finished_ = 0, dropped_ = 0;
  std::uint64_t handed_ = 0;                           // frames given to the mapping thread
  std::uint64_t mapped_ = 0;                           // of them, mapFrame has returned for
  const std::uint64_t frames_in_mapping_;              // System::trackFrame's (reproducible: 1, else 0)
  std::uint64_t priors_base_ = 0;                      // system_->priorsOut() before this pipeline's first frame
  bool tracking_busy_ = false, mapping_busy_ = false;  // a stage is on a frame
  StageCpu cpu_;
};

}  // namespace vitamin_e::pipeline
