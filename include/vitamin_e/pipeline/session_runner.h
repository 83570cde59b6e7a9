#pragma once
// A Session whose admitted frames run either sequentially (System::process on the
// caller's thread: deterministic, as the tests and the evaluation want) or pipelined
// (a PipelinedSystem on the session's System: frame k+1 is tracked while frame k is
// mapped, for a live camera on two cores). Either way the results reach on_result
// once per processed frame, in order, with the caller's ticket for the frame:
//   sequential: before process() returns, on the caller's thread;
//   pipelined:  later, on the pipeline's mapping thread.
// on_pose (optional) hears a tracked frame's pose before its map work, on the same thread
// and with the same ticket, before that frame's on_result (System::PoseListener).
// Whatever reads or changes the session or its System (segments, counters, maps,
// localization only, reset) waits for the pipeline first: flush(), or the calls
// here that flush themselves (admit() of a stamp going back, reset()).
//   SessionRunner runner(config, camera, session_config, {true}, on_result);
//   SessionStamp s = runner.admit(t);        // the stamp: time jump, out of order
//   if (s.admitted) runner.process(image, t, text, ticket);
// One thread calls admit(), process(), flush(), reset() and system().
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include <opencv2/core.hpp>

#include "vitamin_e/pipeline/pipelined_system.h"
#include "vitamin_e/pipeline/session.h"

namespace vitamin_e::pipeline {

struct RunnerOptions {
  bool pipelined = false;
  // Frames between the caller and the mapper (pipelined): one waiting for the tracker and
  // one tracked frame waiting for the mapper; process() blocks when they are taken.
  std::size_t queue_frames = 1;
  bool reproducible = true;  // PipelinedOptions::reproducible (false: live, fresher hand-overs)
};

class SessionRunner {
 public:
  using ResultCallback = std::function<void(FrameResult&& result, std::uint64_t ticket)>;
  using PoseCallback = std::function<void(const FramePose& pose, std::uint64_t ticket)>;

  SessionRunner(const SystemConfig& config, const camera::Camera& camera, const SessionConfig& session,
                const RunnerOptions& options, ResultCallback on_result, PoseCallback on_pose = {});
  ~SessionRunner();  // the submitted frames are finished (their on_result called) first
  SessionRunner(const SessionRunner&) = delete;
  SessionRunner& operator=(const SessionRunner&) = delete;

  // Session::admit; a stamp going back (a time jump changes the System) waits for the
  // frames before it first.
  SessionStamp admit(double timestamp);
  // Runs an admitted frame (the image is shared, not copied: do not write to it
  // afterwards). Throws std::invalid_argument for a wrong image type or size, like
  // System::process (no result comes then); false when the frame is not processed
  // (shutting down).
  bool process(const cv::Mat& image, double timestamp, const std::string& timestamp_text, std::uint64_t ticket);
  // Blocks until every processed frame's on_result has returned.
  void flush();
  // Pipelined: blocks until no frame waits for a stage (PipelinedSystem::waitUntilNoneWaiting),
  // the moment for a live caller to take its newest frame. Sequential: returns at once.
  void waitUntilNoneWaiting();
  // Session::reset after flush().
  void reset(const std::string& why);

  bool pipelined() const { return options_.pipelined; }
  // CPU time [ms] spent so far in the SLAM's two stages (System::trackFrame, mapFrame), on
  // whichever thread ran them, over every pipeline this runner started (on_pose included,
  // on_result not). Pipelined: exact after flush().
  PipelinedSystem::StageCpu stageCpuMs() const;
  // Frames given to process() not handed to on_result yet.
  std::size_t inFlight() const;
  // flush() first: the pipeline's mapping thread writes the session's System.
  // (on_result may read them: it runs where the System is written.)
  const Session& session() const { return session_; }
  System& system() { return session_.system(); }

 private:
  void onPipelineResult(FrameResult&& result);
  void onPipelinePose(const FramePose& pose);
  void startPipeline();
  void stopPipeline();  // finishes its frames; its stage CPU is kept

  Session session_;
  RunnerOptions options_;
  ResultCallback on_result_;
  PoseCallback on_pose_;
  // The tickets of the frames in the pipeline, in order (it keeps every frame and its order).
  mutable std::mutex tickets_mutex_;
  std::deque<std::uint64_t> tickets_;
  PipelinedSystem::StageCpu stopped_cpu_;      // sequential frames, and the pipelines stopped
  std::unique_ptr<PipelinedSystem> pipeline_;  // last: its threads end before the rest goes
};

}  // namespace vitamin_e::pipeline
