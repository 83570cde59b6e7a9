#pragma once
// The VITAMIN-E SLAM system: monocular images in, poses and a dense map out.
//   System slam(config, camera);
//   FrameResult r = slam.process(gray_image, t);
// process() is synchronous (sequential mode: deterministic). Not thread-safe:
// call it from one thread at a time.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/map/map_file.h"
#include "vitamin_e/pipeline/frame_result.h"
#include "vitamin_e/pipeline/front_end.h"
#include "vitamin_e/pipeline/system_config.h"
#include "vitamin_e/pipeline/tracked_frame.h"

namespace vitamin_e::pipeline {

struct TrajectoryEntry {
  double timestamp = 0.0;
  std::string timestamp_text;  // as the dataset gave it (may be empty)
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
};

struct MapPoint3 {
  std::uint64_t id = 0;
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  std::uint8_t intensity = 0;
};

class System {
 public:
  System(const SystemConfig& config, const camera::Camera& camera);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  // Hears a tracked frame's pose as soon as it is known, before the frame's map work
  // (a keyframe's triangulation and window BA): a live caller publishes it then, and the
  // pose's latency is not the keyframe's. Called on the thread of process() / mapFrame(),
  // at most once per frame, before they return; not for the frames that initialize a map
  // or are relocalized (their pose comes with the result only). It must not call the System.
  using PoseListener = std::function<void(const FramePose&)>;

  // Processes one frame. image: CV_8UC1 of the calibration's size (throws
  // std::invalid_argument otherwise). timestamp in seconds, increasing
  // (a frame whose stamp does not increase is skipped: state kLost, message set).
  // The results do not depend on on_pose.
  FrameResult process(const cv::Mat& image, double timestamp, const std::string& timestamp_text = "",
                      const PoseListener& on_pose = {});

  // The two stages of process(), as PipelinedSystem runs them on two threads:
  // trackFrame (tracking, undistortion) and mapFrame (initialization, pose, BA,
  // map). One thread may call each; they share only thread-safe state (the
  // timings and the tracks the mapping stage ends). process() = mapFrame(trackFrame()).
  // before_priors (optional) is called on the tracking thread once the flow has tracked the
  // frame, before the tracker reads its priors (the map points of the last mapped frame seen
  // from the predicted pose, tracker.retry_from_prior): PipelinedSystem waits there until the
  // frame before has its pose (waitForPriors), so that the priors start from that pose.
  // frames_in_mapping: 0: the tracker takes what the mapping has put out by the time it needs
  // it, the tracks it dropped and its newest priors (sequential: everything of the frame before;
  // beside a running mapping, whatever the timing made of it: PipelinedOptions::reproducible
  // false). n >= 1: up to n frames just before this one may still be mapped meanwhile (the
  // caller makes sure no older one is): the tracks the mapping of frame k dropped end before
  // frame k + 1 + n is tracked, and the priors are the ones first put out for the frame before
  // (its early ones), so that the results do not depend on the threads' timing.
  TrackedFrame trackFrame(const cv::Mat& image, double timestamp, const std::string& timestamp_text = "",
                          const std::function<void()>& before_priors = {}, std::uint64_t frames_in_mapping = 0);
  FrameResult mapFrame(TrackedFrame&& frame, const PoseListener& on_pose = {});
  // How many mapFrame calls have put out the tracker's priors for the next frame: once the
  // frame's pose is found (before its keyframe's triangulation and window BA), or at its end.
  // waitForPriors(n) blocks until n have (PipelinedSystem's before_priors). Thread-safe.
  std::uint64_t priorsOut() const;
  void waitForPriors(std::uint64_t n);

  // Forgets map and tracks; the trajectory so far is kept.
  void reset();
  // The image stream starts over (its stamps went back: a bag replayed or
  // restarted, a clock reset): the tracks end, the stamp order starts again,
  // and the camera is looked for in the existing map by relocalization, as
  // after a loss, so that its poses go on in the same world frame and scale
  // (a new map only if it is not found within relocalization.max_frames, as
  // after any loss). Returns false, and changes nothing, when there is no map
  // to relocalize in (none yet, or relocalization disabled): start over with
  // reset() or a new System then.
  bool restartTracking();

  // Map persistence (the file: map/map_file.h; src/pipeline/system_map_io.cpp).
  // exportMap: the map, the relocalizer's index, the camera and the scale as
  // plain data. loadMap: the loaded map replaces the (empty) map and the system
  // starts relocalizing in it: no initialization; the trajectory is in the
  // loaded map's frame and scale, and frame indices and track ids continue its
  // numbering. Call before the first frame. Throws std::invalid_argument
  // naming the problem (another camera, descriptors made with other
  // relocalization settings, relocalization off, an inconsistent map), and then
  // changes nothing. Without localization only, the loaded map is extended.
  // With a loaded map a loss is never given up for a new map (that would
  // discard the loaded one): the camera is looked for in it until found.
  map::MapFileContents exportMap() const;
  void loadMap(const map::MapFileContents& contents);
  // exportMap() written to a map file; false (and *error) when it cannot.
  bool saveMap(const std::string& path, std::string* error = nullptr) const;
  bool mapLoaded() const;  // loadMap() succeeded (and no reset() since)
  // Localization only: track and relocalize in the existing map without
  // changing it: no keyframe and no new point is added, the per-frame BA moves
  // the camera only, tracks are only associated with existing points, and a
  // loss is never given up for a new map. May be switched between frames.
  void setLocalizationOnly(bool on);
  bool localizationOnly() const;

  // Poses of every tracked frame so far, in time order, all in one world frame.
  const std::vector<TrajectoryEntry>& trajectory() const;
  // Current map points (world frame).
  std::vector<MapPoint3> mapPoints() const;

  std::size_t framesProcessed() const;
  std::size_t framesTracked() const;
  // Index (0 = the first frame given to process()) of the frame at which the
  // first map was built; -1 while there is none.
  long long firstInitFrame() const;
  // Frames with a pose from that frame on (the reference and in-between frames
  // localized at the initialization are not counted).
  std::size_t framesTrackedSinceInit() const;
  // Re-initializations after a loss (each a new map, placed at the last pose and scale).
  int initRetries() const;
  // Losses recovered by relocalizing in the existing map (same world frame and scale).
  int relocalizations() const;
  // Map points taken over by new tracks (map reuse, see SystemConfig::reuse_radius_px).
  std::size_t reusedMapPoints() const;
  // Retired map points kept for reuse (bounded by map.max_dormant_landmarks).
  std::size_t dormantMapPoints() const;
  const StageTimings& timings() const;
  const SystemConfig& config() const;
  const camera::Camera& camera() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The frame's triangulated points in its camera frame (p_c = T_w_c^-1 p_w) with
// their track ids: the input of the dense reconstruction. Empty unless the
// frame has a valid pose.
void framePointsInCamera(const FrameResult& result, std::vector<std::uint64_t>* ids, std::vector<Eigen::Vector3d>* p_c);

// Writers shared by the offline runner and the ROS services. Return false (and
// fill *error) when the file cannot be written.
bool saveTrajectoryTum(const std::vector<TrajectoryEntry>& trajectory, const std::string& path,
                       std::string* error = nullptr);
bool saveMapPly(const std::vector<MapPoint3>& points, const std::string& path, std::string* error = nullptr);

}  // namespace vitamin_e::pipeline
