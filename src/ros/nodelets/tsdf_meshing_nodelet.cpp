// vitamin_e/TsdfMeshingNodelet: per-frame messages of TrackingNodelet (~frame) in,
// TSDF mesh out. Each message is the dense stage's input (fusion::DenseFrame, as
// vitamin_e_run makes it: pipeline::DenseInput) and goes through fusion::DenseMapper
// (Delaunay mesh, NLTGV smoothing and pruning on its meshing thread, TSDF fusion on
// another, both dense.nice_increment below the SLAM's threads, so that in a shared
// nodelet manager the mesh never takes the tracker's core; ~queue_size frames wait
// for the meshing thread, the oldest dropped beyond; the volume follows the map's
// rescales). Every ~publish_period the voxel blocks whose
// surface changed are published as one TRIANGLE_LIST marker each (stable ids: rviz
// replaces them); a subscriber that connects gets every block at once, and
// ~republish_mesh sends them all again. The dense settings come from the "dense"
// section of ~config_file (the SLAM config, map units) alone, as in the offline
// runner. ~load_tsdf: the TSDF of an earlier run (in the same map) fused into from
// the start, its mesh published at once; ~save_tsdf: written on shutdown (and by
// the ~save_tsdf service).
#include <algorithm>
#include <cstddef>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include <dynamic_reconfigure/server.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <visualization_msgs/MarkerArray.h>
#include <pluginlib/class_list_macros.hpp>

#include "save_file_service.h"
#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackedFrame.h"
#include "vitamin_e/TsdfMeshingConfig.h"
#include "vitamin_e/common/allocator.h"
#include "vitamin_e/fusion/dense_mapper.h"
#include "vitamin_e/fusion/tsdf_volume.h"
#include "vitamin_e/pipeline/system_config.h"
#include "vitamin_e/ros/dense_frame_msg.h"
#include "vitamin_e/ros/mesh_markers.h"

namespace vitamin_e_ros {

namespace fusion = vitamin_e::fusion;
namespace meshing = vitamin_e::meshing;

class TsdfMeshingNodelet : public nodelet::Nodelet {
 public:
  ~TsdfMeshingNodelet() override {
    std::lock_guard<std::mutex> lock(mutex_);
    // A file to write waits for every frame received (saveMesh / saveTsdf flush); without one
    // the frames still waiting are dropped rather than meshed for nobody.
    if (dense_ && mesh_file_.empty() && save_tsdf_.empty()) dense_->reset();
    if (dense_ && !mesh_file_.empty()) {
      std::string message;
      saveMesh(mesh_file_, &message);
      std::fprintf(stderr, "[vitamin_e] %s\n", message.c_str());  // rosout may be gone at shutdown
    }
    if (dense_ && !save_tsdf_.empty()) {
      std::string message;
      saveTsdf(save_tsdf_, &message);
      std::fprintf(stderr, "[vitamin_e] %s\n", message.c_str());
    }
  }

 private:
  // Every ROS parameter of the nodelet, read once here. The reconstruction
  // itself is configured by the "dense" section of ~config_file only (the same
  // keys and meaning as vitamin_e_run --config; docs/CONFIG.md).
  struct Params {
    std::string map_frame;
    std::string mesh_file;
    std::string config_file;
    std::string load_tsdf, save_tsdf;
    int queue_size = 100;
    bool reuse_freed_memory = true;  // as the tracking nodelet's (docs/ROS.md)
  };
  Params readParams(ros::NodeHandle& pnh) {
    Params p;
    pnh.param("map_frame", p.map_frame, p.map_frame);
    pnh.param("mesh_file", p.mesh_file, p.mesh_file);
    pnh.param("config_file", p.config_file, p.config_file);
    pnh.param("queue_size", p.queue_size, p.queue_size);
    pnh.param("load_tsdf", p.load_tsdf, p.load_tsdf);
    pnh.param("save_tsdf", p.save_tsdf, p.save_tsdf);
    pnh.param("reuse_freed_memory", p.reuse_freed_memory, p.reuse_freed_memory);
    // Parameters that overrode the yaml before: say where they went instead of ignoring them silently.
    for (const char* old : {"denoise", "voxel_size", "truncation", "max_weight", "min_depth", "max_depth",
                            "raster_downscale", "max_edge_px", "max_normal_angle_deg", "max_inv_depth_jump"}) {
      if (pnh.hasParam(old)) {
        NODELET_ERROR("~%s is not read: set dense.%s in ~config_file (docs/CONFIG.md)", old, old);
      }
    }
    if (pnh.hasParam("triangles_per_marker")) {
      NODELET_ERROR("~triangles_per_marker is not read: ~mesh has one marker per TSDF block (docs/ROS.md)");
    }
    return p;
  }

  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    const Params params = readParams(pnh);
    if (params.reuse_freed_memory) {
      const vitamin_e::AllocatorSetting allocator = vitamin_e::reuseFreedFrameBuffers();
      if (!allocator.applied) NODELET_WARN("~reuse_freed_memory: %s", allocator.what.c_str());
    }
    map_frame_ = params.map_frame;
    mesh_file_ = params.mesh_file;
    load_tsdf_ = params.load_tsdf;
    save_tsdf_ = params.save_tsdf;
    queue_size_ = static_cast<std::size_t>(std::max(1, params.queue_size));
    try {
      const vitamin_e::pipeline::SystemConfig config = params.config_file.empty()
                                                           ? vitamin_e::pipeline::SystemConfig{}
                                                           : vitamin_e::pipeline::loadSystemConfig(params.config_file);
      if (!config.dense_enabled) {
        NODELET_WARN("dense.enabled is false in %s: nothing is fused (no subscription)", params.config_file.c_str());
        return;
      }
      dense_config_ = config.dense;
      dense_config_.validate();
    } catch (const std::exception& e) {
      NODELET_FATAL("%s (no subscription)", e.what());
      return;
    }
    if (!load_tsdf_.empty()) {
      // Read now (a bad file is fatal before subscribing); handed to the
      // DenseMapper made at the first frame.
      loaded_tsdf_ = std::make_unique<fusion::TsdfVolume>(dense_config_.integrator.tsdf);
      try {
        loaded_tsdf_->load(load_tsdf_);
      } catch (const std::exception& e) {
        NODELET_FATAL("~load_tsdf: %s (no subscription)", e.what());
        return;
      }
      NODELET_INFO("~load_tsdf %s: %zu blocks", load_tsdf_.c_str(), loaded_tsdf_->numBlocks());
    }
    config_ok_ = true;
    const fusion::TsdfConfig& tsdf = dense_config_.integrator.tsdf;
    NODELET_INFO("TSDF voxel %.3f, truncation %.3f, depth [%.2f, %.2f] (map units), NLTGV %s", tsdf.voxel_size,
                 tsdf.truncation, tsdf.min_depth, tsdf.max_depth, dense_config_.denoise ? "on" : "off");

    // Not latched: a latched message would be the last change only. A subscriber
    // that connects gets every block instead (onMeshSubscriber).
    mesh_pub_ = pnh.advertise<visualization_msgs::MarkerArray>(
        "mesh", 100, [this](const ros::SingleSubscriberPublisher& pub) { onMeshSubscriber(pub); });
    republish_srv_ = pnh.advertiseService("republish_mesh", &TsdfMeshingNodelet::republishService, this);
    save_srv_ = pnh.advertiseService("save_mesh", &TsdfMeshingNodelet::saveMeshService, this);
    save_tsdf_srv_ = pnh.advertiseService("save_tsdf", &TsdfMeshingNodelet::saveTsdfService, this);
    reconfigure_server_ =
        std::make_unique<dynamic_reconfigure::Server<vitamin_e::TsdfMeshingConfig>>(reconfigure_mutex_, pnh);
    reconfigure_server_->setCallback(
        [this](vitamin_e::TsdfMeshingConfig& c, uint32_t level) { reconfigure(c, level); });
    if (loaded_tsdf_) {
      std::lock_guard<std::mutex> lock(mutex_);
      publishLoadedMesh();
    }
    frame_sub_ = nh.subscribe("frame", static_cast<uint32_t>(std::max(1, params.queue_size)),
                              &TsdfMeshingNodelet::frameCallback, this);
    NODELET_INFO("fusing frames from %s", frame_sub_.getTopic().c_str());
  }

  MeshMarkerOptions markerOptions() const {
    MeshMarkerOptions options;
    options.frame_id = map_frame_.empty() ? "map" : map_frame_;
    options.color_by_height = dyn_.color_by_height;
    options.height_color_period = dyn_.height_color_period;
    options.min_vertex_move = dyn_.min_vertex_move * dense_config_.integrator.tsdf.voxel_size;
    return options;
  }

  void reconfigure(vitamin_e::TsdfMeshingConfig& config, uint32_t) {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool period_changed = config.publish_period != dyn_.publish_period || !timer_.isValid();
    dyn_ = config;
    if (markers_.setOptions(markerOptions()) && mesh_pub_.getNumSubscribers() > 0) {
      mesh_pub_.publish(markers_.full());  // recoloured
    }
    if (!period_changed) return;
    timer_.stop();
    if (dyn_.publish_period > 0.0) {
      timer_ = getNodeHandle().createWallTimer(ros::WallDuration(dyn_.publish_period),
                                               &TsdfMeshingNodelet::publishTimer, this);
    }
  }

  void frameCallback(const vitamin_e::TrackedFrameConstPtr& msg) {
    fusion::DenseFrame frame;
    meshing::PinholeImage image;
    std::string why;
    if (!fromTrackedFrameMsg(*msg, &frame, &image, &why)) {
      NODELET_ERROR_THROTTLE(2.0, "frame %lu dropped: %s", static_cast<unsigned long>(msg->frame_index), why.c_str());
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (!config_ok_) return;
    if (map_frame_.empty()) {
      map_frame_ = msg->header.frame_id.empty() ? "map" : msg->header.frame_id;
      markers_.setOptions(markerOptions());
    }
    if (dense_ && msg->segment != segment_) {
      // The tracker started a new map (~reset, a time jump with nothing to relocalize in): a new volume.
      NODELET_INFO("tracking map %u: a new map, the TSDF starts over (%zu frames fused before)", msg->segment,
                   framesFused());
      dense_->reset();  // the frames of the old map still waiting are dropped, not meshed
      dense_.reset();
      reported_ = fusion::DenseWorkStats{};
      if (mesh_pub_.getNumSubscribers() > 0) {
        mesh_pub_.publish(markers_.clear(ros::Time::now()));
      } else {
        markers_.clear(ros::Time::now());
      }
    }
    segment_ = msg->segment;
    try {
      if (!dense_) {
        dense_ = std::make_unique<fusion::DenseMapper>(dense_config_, image);
        dense_image_ = image;
        if (loaded_tsdf_) {
          dense_->loadTsdf(load_tsdf_);  // the file checked at start-up
          loaded_tsdf_.reset();
        }
      } else if (image != dense_image_) {
        NODELET_ERROR_THROTTLE(2.0, "frame %lu has other intrinsics than the first frame: not fused",
                               static_cast<unsigned long>(msg->frame_index));
        return;
      }
      dense_->submitFrame(std::move(frame), queue_size_, vitamin_e::WhenFull::kDropOldest);
    } catch (const std::exception& e) {
      NODELET_ERROR_THROTTLE(2.0, "frame %lu not fused: %s", static_cast<unsigned long>(msg->frame_index), e.what());
    }
    reportMeshingLosses();
  }

  // Frames of this map fused so far (meshed on the meshing thread; the TSDF thread's own queue may still hold some).
  std::size_t framesFused() const { return dense_ ? dense_->workStats().meshed : 0; }

  // What the meshing thread lost since the last report: frames dropped (it fell ~queue_size
  // frames behind) and frames whose meshing failed.
  void reportMeshingLosses() {
    if (!dense_) return;
    const fusion::DenseWorkStats now = dense_->workStats();
    if (now.dropped > reported_.dropped) {
      NODELET_WARN_THROTTLE(5.0, "meshing %zu frame(s) behind: %zu dropped unmeshed so far", queue_size_, now.dropped);
    }
    if (now.failed > reported_.failed) {
      NODELET_ERROR_THROTTLE(2.0, "%zu frame(s) not fused so far: %s", now.failed, now.last_failure.c_str());
    }
    reported_.dropped = now.dropped;
    reported_.failed = now.failed;
  }

  // The blocks changed since the last publication. While nobody listens they
  // wait in the volume (a subscriber gets the markers kept so far on connecting,
  // then this).
  void publishTimer(const ros::WallTimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    reportMeshingLosses();
    if (!dense_ || mesh_pub_.getNumSubscribers() == 0) return;
    publishUpdate(dense_->takeChangedBlocks());
  }

  void publishUpdate(const fusion::MeshBlockUpdate& update) {
    std::size_t skipped = 0;
    visualization_msgs::MarkerArrayPtr markers(new visualization_msgs::MarkerArray);
    *markers = markers_.update(update, ros::Time::now(), &skipped);
    if (skipped > 0) NODELET_ERROR_THROTTLE(2.0, "%zu non-finite triangles not published", skipped);
    if (markers->markers.empty()) return;
    mesh_pub_.publish(visualization_msgs::MarkerArrayConstPtr(markers));
    NODELET_DEBUG("mesh: %zu changed blocks sent; %zu blocks, %zu triangles in all; %zu frames fused",
                  update.blocks.size(), markers_.numMarkers(), markers_.numTriangles(), framesFused());
  }

  // A new subscriber (a late rviz): every block sent so far, to it alone.
  void onMeshSubscriber(const ros::SingleSubscriberPublisher& pub) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (markers_.numMarkers() == 0) return;
    pub.publish(markers_.full());
    NODELET_DEBUG("mesh: %zu blocks sent to %s", markers_.numMarkers(), pub.getSubscriberName().c_str());
  }

  bool republishService(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (dense_) {
      const fusion::MeshBlockUpdate update = dense_->takeChangedBlocks();
      markers_.update(update, ros::Time::now());  // the changes since the last publication, into the copy
    }
    mesh_pub_.publish(markers_.full());
    res.success = true;
    res.message = std::to_string(markers_.numMarkers()) + " blocks (" + std::to_string(markers_.numTriangles()) +
                  " triangles) sent to " + std::to_string(mesh_pub_.getNumSubscribers()) + " subscribers";
    return true;
  }

  bool saveMesh(const std::string& path, std::string* message) {
    const fusion::TriangleMesh mesh = dense_->extractMesh();  // after every frame received
    std::string error;
    if (!fusion::saveMeshPly(mesh, path, &error)) {
      *message = "cannot write mesh " + path + ": " + error;
      return false;
    }
    *message = "mesh (" + std::to_string(mesh.vertices.size()) + " vertices, " + std::to_string(mesh.faces.size()) +
               " triangles, " + std::to_string(framesFused()) + " frames, PLY) written to " + path;
    return true;
  }

  // The mesh of ~load_tsdf, published before any frame arrives (and kept for
  // subscribers that connect later).
  void publishLoadedMesh() {
    markers_.setOptions(markerOptions());
    publishUpdate(loaded_tsdf_->takeChangedBlocks());
    NODELET_INFO("mesh of %s published: %zu triangles in %zu blocks", load_tsdf_.c_str(), markers_.numTriangles(),
                 markers_.numMarkers());
  }

  bool saveTsdf(const std::string& path, std::string* message) {
    std::string error;
    if (!dense_->saveTsdf(path, &error)) {  // after every frame received
      *message = "cannot write TSDF " + path + ": " + error;
      return false;
    }
    *message = "TSDF (" + std::to_string(framesFused()) + " frames fused) written to " + path;
    return true;
  }

  // Why a save is refused before a path is looked at ("": it is not).
  std::string saveRefusal() const {
    return !config_ok_ ? "no TSDF (bad configuration or dense.enabled false)" : !dense_ ? "no frame fused yet" : "";
  }

  bool saveTsdfService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto save = [this](const std::string& path, std::string* message) { return saveTsdf(path, message); };
    if (answerSaveFile(req, save_tsdf_, "save_tsdf", saveRefusal(), &res, save)) {
      NODELET_INFO("%s", res.message.c_str());
    }
    return true;
  }

  bool saveMeshService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto save = [this](const std::string& path, std::string* message) { return saveMesh(path, message); };
    if (answerSaveFile(req, mesh_file_, "mesh_file", saveRefusal(), &res, save)) {
      NODELET_INFO("%s", res.message.c_str());
    }
    return true;
  }

  std::string map_frame_;
  std::string mesh_file_;
  std::string load_tsdf_, save_tsdf_;
  std::unique_ptr<fusion::TsdfVolume> loaded_tsdf_;  // ~load_tsdf until the first frame
  std::mutex mutex_;
  vitamin_e::TsdfMeshingConfig dyn_;
  fusion::DenseMapperConfig dense_config_;
  bool config_ok_ = false;
  std::unique_ptr<fusion::DenseMapper> dense_;  // made at the first frame (its intrinsics)
  meshing::PinholeImage dense_image_;
  std::size_t queue_size_ = 100;     // frames waiting for the meshing thread at most (~queue_size)
  fusion::DenseWorkStats reported_;  // the losses reported so far (dropped, failed)
  MeshBlockMarkers markers_;         // the blocks published so far
  unsigned segment_ = 0;             // the tracker's map (TrackedFrame::segment) of the frames fused
  ros::Subscriber frame_sub_;
  ros::Publisher mesh_pub_;
  ros::ServiceServer save_srv_, save_tsdf_srv_, republish_srv_;
  ros::WallTimer timer_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<vitamin_e::TsdfMeshingConfig>> reconfigure_server_;
};

}  // namespace vitamin_e_ros

PLUGINLIB_EXPORT_CLASS(vitamin_e_ros::TsdfMeshingNodelet, nodelet::Nodelet)
