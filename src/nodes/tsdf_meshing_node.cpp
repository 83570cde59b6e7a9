// Plain node running vitamin_e/TsdfMeshingNodelet in-process (nodelet::Loader), for users
// who do not want a nodelet manager. Parameters and remappings are the nodelet's:
//   rosrun vitamin_e tsdf_meshing_node _param:=value topic:=other_topic
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "tsdf_meshing");
  nodelet::Loader loader(false);  // no load/unload services: this node runs exactly one nodelet
  const nodelet::M_string& remappings = ros::names::getRemappings();
  const nodelet::V_string nodelet_argv(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "vitamin_e/TsdfMeshingNodelet", remappings, nodelet_argv)) {
    ROS_FATAL("could not load vitamin_e/TsdfMeshingNodelet (is the package built and sourced?)");
    return 1;
  }
  ros::spin();
  return 0;
}
