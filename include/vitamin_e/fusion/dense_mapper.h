#pragma once
// Dense reconstruction of a SLAM run, one frame at a time (paper section 4):
// the frame's triangulated points (camera frame) -> 2D Delaunay mesh in the
// pinhole image (meshing::FrameMesher) -> NLTGV2-L1 smoothing of the inverse
// depths (meshing::NltgvDenoiser, warm-started by track id) -> pruning of bad
// triangles -> TSDF fusion (fusion::TsdfIntegrator, on its own thread unless
// configured synchronous) -> marching cubes on demand. The one dense stage of
// the offline runner and of the ROS meshing nodelet: both give it the
// DenseFrame that pipeline::DenseInput makes of each SLAM result (the nodelet
// receives it as a vitamin_e/TrackedFrame message). addFrame() meshes on the
// caller's thread; submitFrame() hands the whole frame to the mapper's meshing
// thread (off the SLAM's critical path), in order, never dropping one. When the
// map is rescaled (a ground-scale correction) the volume is rescaled with it
// before the frame is fused: the mesh stays in one scale, the map's current one.
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "vitamin_e/common/serial_worker.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/fusion/triangle_mesh.h"
#include "vitamin_e/fusion/tsdf_integrator.h"
#include "vitamin_e/meshing/frame_mesher.h"
#include "vitamin_e/meshing/nltgv_denoiser.h"
#include "vitamin_e/meshing/pinhole_image.h"

namespace vitamin_e::fusion {

// The mesh is built with lenient filters (NLTGV needs the neighbours across
// creases and small objects), then pruned strictly after smoothing.
meshing::FrameMesherConfig lenientMesherConfig();

struct DenseMapperConfig {
  meshing::FrameMesherConfig mesher = lenientMesherConfig();  // building the frame mesh
  meshing::FrameMesherConfig prune;                           // pruning after NLTGV
  meshing::NltgvConfig nltgv;
  bool denoise = true;  // NLTGV smoothing of each frame mesh before fusion
  TsdfIntegratorConfig integrator;
  int min_points = 30;  // frames with fewer triangulated points are not meshed
  // The meshing and fusion threads run this many nice levels below the thread that starts them
  // (the SLAM's), [0, 19]: they take the time the SLAM leaves on the cores (their queues wait).
  int nice_increment = 10;
  void validate() const;  // throws std::invalid_argument naming the key
};

// One frame's input: its triangulated points in its camera frame with their
// track ids, its pose, and the map's scaling since the input began (the
// composition of the map's rescales: map coordinates now = map_scaling.apply(map
// coordinates then)), so that a frame left out does not lose a rescale.
struct DenseFrame {
  std::uint64_t frame_index = 0;
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector3d> p_c;  // p_c[i]: the point of track ids[i], camera frame, map units
  MapScaling map_scaling;
};

struct DenseFrameStats {
  bool integrated = false;
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  double mesh_ms = 0.0;     // Delaunay + pruning
  double denoise_ms = 0.0;  // NLTGV
};

// What the meshing thread did with the submitFrame() frames so far.
struct DenseWorkStats {
  std::size_t submitted = 0;
  std::size_t meshed = 0;    // frames that gave a mesh to fuse (their times: DenseMapper::meshTimings())
  std::size_t dropped = 0;   // frames dropped unmeshed (WhenFull::kDropOldest)
  std::size_t failed = 0;    // frames whose meshing threw (not fused)
  std::string last_failure;  // what the last of them threw
  double mesh_cpu_ms = 0.0;  // the meshing thread's CPU time for all frames
};

class DenseMapper {
 public:
  DenseMapper(const DenseMapperConfig& config, const meshing::PinholeImage& image);

  // The map's scaling first (rescale by what it changed since the last frame
  // given), then the points. Throws std::invalid_argument for a bad frame
  // (ids and points of different sizes, a scaling that is not finite and positive).
  DenseFrameStats addFrame(const DenseFrame& frame);
  // ids[i] is the track id of p_c[i] (camera frame, map units).
  DenseFrameStats addFrame(const std::vector<std::uint64_t>& ids, const std::vector<Eigen::Vector3d>& p_c,
                           const Eigen::Isometry3d& T_w_c);
  // The same work as addFrame(DenseFrame) on the mapper's meshing thread
  // (started at the first call, `dense.nice_increment` below the caller):
  // returns at once unless `max_waiting` frames already wait, then blocks until
  // one is taken (kWait: none dropped) or drops the oldest waiting frame
  // (kDropOldest: a live caller that must not block); returns the number dropped.
  // Frames are meshed in submission order (the TSDF integrator's own queue rules
  // still apply). Throws like addFrame for a bad frame; what the meshing itself
  // throws is counted in workStats() (failed, last_failure), the frame not fused.
  // Do not mix with addFrame between flush()es.
  std::size_t submitFrame(DenseFrame frame, std::size_t max_waiting = 4, WhenFull when_full = WhenFull::kWait);
  DenseWorkStats workStats() const;         // cheap: a caller may poll it every frame
  const StageTimings& meshTimings() const;  // stage "mesh": mesh_ms + denoise_ms of the meshed frames
  ~DenseMapper() = default;                 // the meshing thread finishes the submitted frames, then joins
  DenseMapper(const DenseMapper&) = delete;
  DenseMapper& operator=(const DenseMapper&) = delete;
  // The map was scaled by `factor` about `centre` (map coordinates): so is the
  // TSDF, after the frames given before and before the later ones.
  void rescale(const Eigen::Vector3d& centre, double factor);
  void flush();  // waits for the submitted frames to be meshed and the queued ones to be fused
  TriangleMesh extractMesh();
  // The surface of the voxel blocks that changed since the last call, of the
  // frames fused so far (TsdfVolume::takeChangedBlocks; does not wait for the queue).
  MeshBlockUpdate takeChangedBlocks();
  bool saveMesh(const std::string& path, std::string* error = nullptr);
  // The TSDF's voxel blocks to / from a file (TsdfVolume::save / load): a run
  // that loads the file of an earlier run in the same map starts with its mesh.
  bool saveTsdf(const std::string& path, std::string* error = nullptr);
  void loadTsdf(const std::string& path);  // throws fusion::TsdfFileError
  TsdfIntegratorStats integratorStats() const;
  void reset();  // an empty volume for a new map: no surface, no scaling, DenseFrame::map_scaling from identity
  const DenseMapperConfig& config() const { return config_; }
  // Volume -> map coordinates, as submitted (identity until a rescale or a loaded TSDF with one).
  const MapScaling& scaling() const { return scaling_; }

 private:
  void meshSubmitted(const DenseFrame& frame);  // on the meshing thread
  void waitMeshed();

  DenseMapperConfig config_;
  meshing::PinholeImage image_;
  meshing::FrameMesher mesher_;
  meshing::FrameMesher pruner_;
  meshing::NltgvDenoiser denoiser_;
  std::unique_ptr<TsdfIntegrator> integrator_;
  mutable std::mutex work_stats_mutex_;
  DenseWorkStats work_stats_;
  StageTimings mesh_timings_;  // locks itself
  // Touched by whichever thread meshes (the caller's with addFrame, the meshing thread's with submitFrame).
  MapScaling scaling_;        // the volume's, as submitted to the integrator
  MapScaling input_scaling_;  // DenseFrame::map_scaling of the last frame
  // The meshing thread of submitFrame() (started at the first frame); declared last: it
  // finishes and joins before the members it uses are destroyed.
  SerialWorker<DenseFrame> mesh_worker_{[this](DenseFrame& frame) { meshSubmitted(frame); },
                                        {},
                                        config_.nice_increment};
};

}  // namespace vitamin_e::fusion
