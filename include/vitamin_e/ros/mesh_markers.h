#pragma once
// The ~mesh stream of TsdfMeshingNodelet: the TSDF's surface as one TRIANGLE_LIST
// marker per voxel block (fusion::MeshBlock), each with an id of its own for the
// volume's life, so that a MarkerArray carries only the blocks that changed and
// rviz replaces those (as voxblox streams its mesh blocks). The markers sent so
// far are kept: full() sends them again, to a subscriber that joins late.
#include <cstddef>
#include <map>
#include <string>
#include <tuple>

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include "vitamin_e/fusion/tsdf_volume.h"

namespace vitamin_e_ros {

struct MeshMarkerOptions {
  std::string frame_id = "map";
  std::string ns = "mesh";
  bool color_by_height = true;  // else flat grey
  // Height colours repeat every this along z (map units): a vertex's colour
  // depends on its height alone, so a block keeps its colours when others change.
  double height_color_period = 1.0;
  // A changed block is sent again only when a vertex moved farther than this
  // from the marker sent (map units), or its triangles are others: a surface
  // seen again converges by tiny steps that nobody sees. 0: every change.
  double min_vertex_move = 0.0;
};

class MeshBlockMarkers {
 public:
  explicit MeshBlockMarkers(const MeshMarkerOptions& options = {});

  // The changed blocks -> markers: ADD (the block's triangles) or DELETE (it lost
  // them), after a DELETEALL when the update replaces everything; a block whose
  // vertices all stayed within min_vertex_move of its marker is left out (the
  // marker kept is what the viewers have). Triangles with a non-finite vertex are
  // left out (counted in *skipped). Empty when nothing changed.
  visualization_msgs::MarkerArray update(const vitamin_e::fusion::MeshBlockUpdate& update, const ros::Time& stamp,
                                         std::size_t* skipped = nullptr);
  // DELETEALL, then the marker of every block with triangles.
  visualization_msgs::MarkerArray full() const;
  // No block any more (a new map): the markers are forgotten, the DELETEALL to send.
  visualization_msgs::MarkerArray clear(const ros::Time& stamp);
  // New colours: every kept marker recoloured (publish full() then). False when nothing changed.
  bool setOptions(const MeshMarkerOptions& options);

  std::size_t numMarkers() const { return markers_.size(); }
  std::size_t numTriangles() const;

 private:
  visualization_msgs::Marker deleteAll(const ros::Time& stamp) const;
  bool sameSurface(const visualization_msgs::Marker& sent, const visualization_msgs::Marker& now) const;
  void colour(visualization_msgs::Marker* marker) const;

  MeshMarkerOptions options_;
  std::map<std::tuple<int, int, int>, int> ids_;       // block index -> marker id
  std::map<int, visualization_msgs::Marker> markers_;  // the ADD markers sent, by id
  ros::Time last_stamp_;
};

}  // namespace vitamin_e_ros
