#pragma once
// Dense reconstruction of a SLAM run, one frame at a time (paper section 4):
// the frame's triangulated points (camera frame) -> 2D Delaunay mesh in the
// pinhole image (meshing::FrameMesher) -> NLTGV2-L1 smoothing of the inverse
// depths (meshing::NltgvDenoiser, warm-started by track id) -> pruning of bad
// triangles -> TSDF fusion (fusion::TsdfIntegrator, on its own thread unless
// configured synchronous) -> marching cubes on demand. Used by the offline
// runner and the ROS meshing nodelet.
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

  // ids[i] is the track id of p_c[i] (camera frame, map units).
  DenseFrameStats addFrame(const std::vector<std::uint64_t>& ids, const std::vector<Eigen::Vector3d>& p_c,
                           const Eigen::Isometry3d& T_w_c);
  void flush();  // waits for the queued frames to be fused
  TriangleMesh extractMesh();
  bool saveMesh(const std::string& path, std::string* error = nullptr);
  // The TSDF's voxel blocks to / from a file (TsdfVolume::save / load): a run
  // that loads the file of an earlier run in the same map starts with its mesh.
  bool saveTsdf(const std::string& path, std::string* error = nullptr);
  void loadTsdf(const std::string& path);  // throws fusion::TsdfFileError
  TsdfIntegratorStats integratorStats() const;
  void reset();
  const DenseMapperConfig& config() const { return config_; }

 private:
  DenseMapperConfig config_;
  meshing::PinholeImage image_;
  meshing::FrameMesher mesher_;
  meshing::FrameMesher pruner_;
  meshing::NltgvDenoiser denoiser_;
  std::unique_ptr<TsdfIntegrator> integrator_;
};

}  // namespace vitamin_e::fusion
