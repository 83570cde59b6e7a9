#pragma once
// A SLAM run over one image stream that may start over: the System, the stream's
// stamp order and the trajectory in segments. A segment is a stretch of poses in
// time order; a new one begins
//   - when the stamps jump back by more than SessionConfig::time_jump_threshold_s
//     (a bag played with --loop or restarted, a clock reset): the camera is looked
//     for in the same map (System::restartTracking), so the new segment's poses are
//     in the same world frame and scale as the earlier ones;
//   - on reset(): a new map (a fresh System), its own world frame and scale.
// A stamp going back by less is a frame out of order: dropped, and said so. Used by
// the tracking nodelet and by vitamin_e_run alike.
//   Session session(config, camera);
//   SessionFrame f = session.process(gray, t);
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/map/map_file.h"
#include "vitamin_e/pipeline/frame_result.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline {

// What a stamp jumping back by more than the threshold does.
enum class TimeJumpPolicy {
  kRelocalize,  // a new segment in the same map: the camera is relocalized in it
  kDrop,        // the frame is dropped like any frame out of order
};
const char* toString(TimeJumpPolicy policy);
// "relocalize" or "drop"; throws std::invalid_argument naming the valid values.
TimeJumpPolicy timeJumpPolicyFromString(const std::string& text);

struct SessionConfig {
  double time_jump_threshold_s = 1.0;  // > 0
  TimeJumpPolicy on_time_jump = TimeJumpPolicy::kRelocalize;
  void validate() const;  // throws std::invalid_argument naming the key
};

struct TrajectorySegment {
  unsigned number = 1;                 // 1, 2, ... over the session
  unsigned map = 1;                    // the map its poses are in (1, 2, ...: a new one after reset())
  std::string note;                    // why it began (one line)
  std::vector<TrajectoryEntry> poses;  // T_w_c in its map's world, time order
};

// A stamp checked by Session::admit.
struct SessionStamp {
  bool admitted = false;  // false: the frame is dropped before the SLAM (see dropped_why)
  std::string dropped_why;
  bool time_jump = false;  // this frame begins a new segment after the stamps went back
  double jump_back_s = 0.0;
};

// One frame given to Session::process.
struct SessionFrame {
  bool processed = false;  // false: dropped before the SLAM (see dropped_why)
  std::string dropped_why;
  bool time_jump = false;  // this frame began a new segment after the stamps went back
  double jump_back_s = 0.0;
  FrameResult result;  // when processed
};

class Session {
 public:
  Session(const SystemConfig& config, const camera::Camera& camera, const SessionConfig& session = {});
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // Checks the stamp (time jump, out of order) and runs the SLAM on the frame.
  // Throws what System::process throws (a wrong image type or size).
  SessionFrame process(const cv::Mat& image, double timestamp, const std::string& timestamp_text = "");
  // process() without running the SLAM: the stamp checked and a time jump
  // handled (a new segment); an admitted frame must then be given to system()
  // (process(), or trackFrame() and mapFrame() when the caller times them apart).
  SessionStamp admit(double timestamp);
  // admit(timestamp) would not simply go on: the stamp is not after the last one (a time
  // jump, or a frame out of order). Changes nothing.
  bool stampGoesBack(double timestamp) const { return have_last_stamp_ && !(timestamp > last_stamp_); }
  // A new segment with a new map (a fresh System with the same configuration;
  // localization-only carries over, a loaded map does not): why is its note.
  void reset(const std::string& why);

  System& system() { return *system_; }
  const System& system() const { return *system_; }
  const SessionConfig& config() const { return session_config_; }

  unsigned segment() const { return current_.number; }
  unsigned map() const { return current_.map; }
  // Why the current segment began.
  const std::string& segmentNote() const { return current_.note; }
  // The finished segments (poses final: in their map's world).
  const std::vector<TrajectorySegment>& finishedSegments() const { return finished_; }
  // Index in system().trajectory() of the current segment's first pose.
  std::size_t segmentBegin() const { return segment_begin_; }
  // Every segment, the current one last (a copy of all poses).
  std::vector<TrajectorySegment> segments() const;

  // Counts over every map of the session (the System's own start at each reset()).
  std::size_t framesProcessed() const;
  std::size_t framesTracked() const;
  int initRetries() const;
  int relocalizations() const;
  std::size_t timeJumps() const { return time_jumps_; }
  std::size_t framesDropped() const { return dropped_; }  // out of order (not processed)

 private:
  void finishSegment();

  SystemConfig config_;
  camera::Camera camera_;
  SessionConfig session_config_;
  std::unique_ptr<System> system_;
  bool have_last_stamp_ = false;
  double last_stamp_ = 0.0;
  TrajectorySegment current_;  // number, map and note (its poses are the System's, from segment_begin_)
  std::size_t segment_begin_ = 0;
  std::vector<TrajectorySegment> finished_;
  // Counts of the maps before the current one.
  std::size_t done_processed_ = 0, done_tracked_ = 0;
  int done_retries_ = 0, done_relocalizations_ = 0;
  std::size_t time_jumps_ = 0, dropped_ = 0;
};

// The trajectory file of a session: one TUM file, every segment after a
// comment line that names it, its map and why it began:
//   # timestamp tx ty tz qx qy qz qw (HEADER)
//   # segment 1 (map 1): start
//   <t> <tx> ... <qw>
//   # segment 2 (map 1): time jump: stamp jumped back by 8.000 s (...)
// TUM readers skip the '#' lines. Returns false (and sets *error) when the file
// cannot be written. Non-finite poses are skipped.
bool saveSegmentsTum(const std::vector<TrajectorySegment>& segments, const std::string& header, const std::string& path,
                     std::string* error = nullptr);
// Reads such a file back (a file without segment lines is one segment; a
// segment line without "(map M)" has its own map). Throws std::runtime_error.
std::vector<TrajectorySegment> readSegmentsTum(const std::string& path);

}  // namespace vitamin_e::pipeline
