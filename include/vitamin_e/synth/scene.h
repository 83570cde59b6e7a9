#pragma once
// A synthetic scene of axis-aligned boxes, every face carrying its own texture
// (texture.h). Two kinds: a room (an axis-aligned box seen from inside: floor,
// ceiling, four walls, plus boxes standing in it) and open scenes made of boxes
// only (the street of street.h), where a ray that hits nothing sees a flat,
// untextured sky. World frame: z up, metres.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vitamin_e/synth/texture.h"

namespace vitamin_e::synth {

struct SceneConfig {
  Eigen::Vector3d room_min{-4.0, -3.0, 0.0};
  Eigen::Vector3d room_max{4.0, 3.0, 3.0};
  int num_boxes = 6;  // placed at random, clear of keep_clear points
  double box_clearance_m = 1.0;
  double texel_m = 0.005;  // texture resolution on every face
  std::uint64_t seed = 0;
  void validate() const;  // throws std::invalid_argument naming the key
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
  int owner = -1;           // -1: room, k: boxes()[k]
  float brightness = 1.0f;  // multiplies the texture (fake shading)
  Texture texture;
  Eigen::Vector3d normal() const;
};

// A box of an open scene with the textures of its six faces, indexed
// 2 * axis + (max side ? 1 : 0). A face's texture is laid out as for Face: its
// columns run along u_axis = (axis + 1) % 3 and its rows along
// v_axis = (axis + 2) % 3, from the box's min corner.
struct SceneBox {
  AxisBox box;
  std::string kind;  // what it stands for ("building", "car", "road", ...), for scene.json
  struct Surface {
    Texture texture;
    float brightness = 1.0f;
  };
  std::array<Surface, 6> faces;
};

struct RayHit {
  double t = 0.0;  // distance along the (unit) direction
  int face = -1;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  double cos_incidence = 1.0;  // |d . n|
};

class Scene {
 public:
  // Room + boxes; boxes stay box_clearance_m away from every keep_clear point
  // (e.g. the camera path) and inside the room.
  static Scene makeRoom(const SceneConfig& config, const std::vector<Eigen::Vector3d>& keep_clear = {});
  // An open scene of boxes (no room): rays that hit no box see sky_intensity.
  // config only documents the build (seed, finest texel); extra_json, if not
  // empty, is a JSON object whose fields toJson() adds (e.g. the street layout).
  // Throws std::invalid_argument on an empty or inverted box or a face without texture.
  static Scene fromBoxes(std::vector<SceneBox> boxes, float sky_intensity, const SceneConfig& config,
                         const std::string& extra_json = "");

  // First surface hit by origin + t * dir (dir unit length), t > 1e-9.
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, RayHit* hit) const;
  // Same, testing only the boxes with box_mask[k] != 0 (null: all).
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, RayHit* hit,
                 const std::vector<char>* box_mask) const;
  // Same, testing only the boxes listed (ascending indices; null: all).
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, RayHit* hit,
                 const std::vector<int>* box_list) const;
  // Same, with the listed boxes in ascending order of near_dist[i], the distance
  // from origin to box box_list[i]: stops at the first box that cannot be nearer
  // than the hit so far. (Equal-distance hits on two boxes may then report
  // another of them than the index order would.)
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, RayHit* hit,
                 const std::vector<int>& box_list, const std::vector<double>& near_dist) const;
  // Boxes possibly seen within the cone of half-angle acos(min_cos) around
  // forward (conservative: the box's bounding sphere touches the cone).
  std::vector<char> boxesInFront(const Eigen::Vector3d& origin, const Eigen::Vector3d& forward, double min_cos) const;
  // Indices (ascending) of the boxes that may meet the pyramid with apex origin
  // bounded by the planes through origin with the given inward normals
  // (conservative: a box is left out only if it lies wholly outside one plane).
  // With near_dist: sorted by the distance from origin to each box instead
  // (filled with those distances, 0 inside a box), for the nearest-first intersect().
  void boxesInPyramid(const Eigen::Vector3d& origin, const std::array<Eigen::Vector3d, 4>& inward_normals,
                      std::vector<int>* out, std::vector<double>* near_dist = nullptr) const;
  // Intensity in [0, 1] at a hit, filtered for a pixel footprint [m].
  float shade(const RayHit& hit, double footprint_m) const;
  // Unfiltered (level-0, bilinear) intensity at a point of a face.
  float textureAt(int face, const Eigen::Vector3d& p) const;
  // True if p lies on face (within tol) inside its rectangle.
  bool onFace(int face, const Eigen::Vector3d& p, double tol = 1e-6) const;

  const SceneConfig& config() const { return config_; }
  bool hasRoom() const { return has_room_; }
  // Intensity in [0, 1] of a ray that hits nothing (open scenes; a room has no sky).
  float skyIntensity() const { return sky_; }
  // The room, or for an open scene the bounding box of all boxes.
  const AxisBox& room() const { return room_; }
  const std::vector<AxisBox>& boxes() const { return boxes_; }
  // Kind of box k ("box" in a room; see SceneBox::kind).
  const std::string& boxKind(int k) const { return box_kinds_[k]; }
  const std::vector<Face>& faces() const { return faces_; }
  // Index of the first face of box k (its faces follow: 2 * axis + (max side)).
  int boxFace(int k, int face_of_box = 0) const { return first_box_face_ + 6 * k + face_of_box; }
  // The geometry as JSON (room, boxes, faces with plane, normal, extents, texel size).
  std::string toJson() const;

 private:
  void addFace(int axis, double plane, int normal_sign, const AxisBox& extent, int owner, Rng* rng);
  // The first hit of the ray with box k if nearer than *best (slab test).
  bool hitBox(int k, const Eigen::Vector3d& o, const Eigen::Vector3d& d, const double inv[3], double* best,
              int* best_face) const;
  bool finishHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double best, int best_face, RayHit* hit) const;
  double roomExit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const double inv[3], int* best_face) const;
  SceneConfig config_;
  bool has_room_ = true;
  float sky_ = 0.0f;
  int first_box_face_ = 6;
  AxisBox room_;
  std::vector<AxisBox> boxes_;
  std::vector<std::string> box_kinds_;
  std::vector<Face> faces_;  // room faces first: index 2*axis + (max side ? 1 : 0)
  std::string extra_json_;
};

}  // namespace vitamin_e::synth
