#pragma once
// Dense reconstruction of a SLAM run, one frame at a time (paper section 4):
// the frame's triangulated points (camera frame) -> 2D Delaunay mesh in the
// pinhole image (meshing::FrameMesher) -> NLTGV2-L1 smoothing of the inverse
// depths (meshing::NltgvDenoiser, warm-started by track id) -> pruning of bad
// triangles -> TSDF fusion (fusion::TsdfIntegrator, on its own thread unless
// configured synchronous) -> marching cubes on demand. The one dense stage of
// the offline runner and of the ROS meshing nodelet: both give it the
// DenseFrame that pipeline::DenseInput makes of each SLAM result (the nodelet
// receives it as a vitamin_e/TrackedFrame message). When the map is rescaled
// (a ground-scale correction) the volume is rescaled with it before the frame
// is fused: the mesh stays in one scale, the map's current one.
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

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
  int min_points = 30;    // frames with fewer triangulated points are not meshed
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
  // The map was scaled by `factor` about `centre` (map coordinates): so is the
  // TSDF, after the frames given before and before the later ones.
  void rescale(const Eigen::Vector3d& centre, double factor);
  void flush();  // waits for the queued frames to be fused
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
  DenseMapperConfig config_;
  meshing::PinholeImage image_;
  meshing::FrameMesher mesher_;
  meshing::FrameMesher pruner_;
  meshing::NltgvDenoiser denoiser_;
  std::unique_ptr<TsdfIntegrator> integrator_;
  MapScaling scaling_;        // the volume's, as submitted to the integrator
  MapScaling input_scaling_;  // DenseFrame::map_scaling of the last frame
};

}  // namespace vitamin_e::fusion
