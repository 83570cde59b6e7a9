#pragma once
// A synthetic room: an axis-aligned box seen from inside (floor, ceiling, four
// walls) plus axis-aligned boxes standing in it, every face carrying its own
// procedural texture (texture.h). World frame: z up, metres.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vitamin_e/synth/texture.h"

namespace vitamin_e::synth {

struct SceneConfig {
  Eigen::Vector3d room_min{-4.0, -3.0, 0.0};
  Eigen::Vector3d room_max{4.0, 3.0, 3.0};
  int num_boxes = 6;           // placed at random, clear of keep_clear points
  double box_clearance_m = 1.0;
  double texel_m = 0.005;      // texture resolution on every face
  std::uint64_t seed = 0;
  void validate() const;       // throws std::invalid_argument naming the key
};

struct AxisBox {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
};

// One planar rectangle: points with p[axis] == plane and (p[u_axis], p[v_axis])
// in [lo, hi]; normal = normal_sign * e_axis (pointing into free space).
struct Face {
  int axis = 0;
  int u_axis = 1, v_axis = 2;
  double plane = 0.0;
  int normal_sign = 1;
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();
  int owner = -1;          // -1: room, k: boxes()[k]
  float brightness = 1.0f; // multiplies the texture (fake shading)
  Texture texture;
  Eigen::Vector3d normal() const;
};

struct RayHit {
  double t = 0.0;       // distance along the (unit) direction
  int face = -1;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  double cos_incidence = 1.0;  // |d . n|
};

class Scene {
 public:
  // Room + boxes; boxes stay box_clearance_m away from every keep_clear point
  // (e.g. the camera path) and inside the room.
  static Scene makeRoom(const SceneConfig& config, const std::vector<Eigen::Vector3d>& keep_clear = {});

  // First surface hit by origin + t * dir (dir unit length), t > 1e-9.
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, RayHit* hit) const;
  // Same, testing only the boxes with box_mask[k] != 0 (null: all).
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, RayHit* hit,
                 const std::vector<char>* box_mask) const;
  // Boxes possibly seen within the cone of half-angle acos(min_cos) around
  // forward (conservative: the box's bounding sphere touches the cone).
  std::vector<char> boxesInFront(const Eigen::Vector3d& origin, const Eigen::Vector3d& forward, double min_cos) const;
  // Intensity in [0, 1] at a hit, filtered for a pixel footprint [m].
  float shade(const RayHit& hit, double footprint_m) const;
  // Unfiltered (level-0, bilinear) intensity at a point of a face.
  float textureAt(int face, const Eigen::Vector3d& p) const;
  // True if p lies on face (within tol) inside its rectangle.
  bool onFace(int face, const Eigen::Vector3d& p, double tol = 1e-6) const;

  const SceneConfig& config() const { return config_; }
  const AxisBox& room() const { return room_; }
  const std::vector<AxisBox>& boxes() const { return boxes_; }
  const std::vector<Face>& faces() const { return faces_; }
  // The geometry as JSON (room, boxes, faces with plane, normal, extents, texel size).
  std::string toJson() const;

 private:
  void addFace(int axis, double plane, int normal_sign, const AxisBox& extent, int owner, Rng* rng);
  SceneConfig config_;
  AxisBox room_;
  std::vector<AxisBox> boxes_;
  std::vector<Face> faces_;  // room faces first: index 2*axis + (max side ? 1 : 0)
};

}  // namespace vitamin_e::synth
