#pragma once
// fusion::TriangleMesh -> visualization_msgs::MarkerArray of TRIANGLE_LIST
// markers (one per chunk of triangles, so no single message gets too large).
#include <cstddef>
#include <string>

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include "vitamin_e/fusion/triangle_mesh.h"

namespace vitamin_e_ros {

struct MeshMarkerOptions {
  std::string frame_id = "map";
  ros::Time stamp;
  std::string ns = "mesh";
  std::size_t triangles_per_marker = 100000;
  bool color_by_height = true;  // else flat grey
};

// Fills *out with ceil(triangles / triangles_per_marker) ADD markers (ids 0..n-1)
// and DELETE markers for ids n..previous_markers-1 (left from a larger mesh).
// Triangles with a non-finite vertex are skipped (counted in *skipped).
// Returns n.
std::size_t meshToMarkers(const vitamin_e::fusion::TriangleMesh& mesh, const MeshMarkerOptions& options,
                          std::size_t previous_markers, visualization_msgs::MarkerArray* out,
                          std::size_t* skipped = nullptr);

}  // namespace vitamin_e_ros
