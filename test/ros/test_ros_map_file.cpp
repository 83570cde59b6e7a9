// MapFile.* (map_file.test): the TrackingNodelet and the map file.
//  - a nodelet given ~save_map writes the map file when it unloads; another one
//    given it as ~load_map with ~localization_only localizes in it (status
//    "localizing in loaded map" / "lost in loaded map"), never initializes, and
//    does not rewrite the file at its own unload;
//  - an empty, truncated, corrupt or other-camera ~load_map is a FATAL message
//    and the nodelet does not subscribe to images.
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/Image.h>

#include "ros_test_helpers.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/camera/camera.h"
#include "vitamin_e/map/map_file.h"

using vitamin_e_test::Watcher;
using Statuses = std::vector<vitamin_e::TrackingStatus::ConstPtr>;

namespace {

std::string testParam(const std::string& name, const std::string& fallback = "") {
  std::string value;
  ros::NodeHandle("~").param(name, value, fallback);
  return value;
}

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::vector<sensor_msgs::Image::ConstPtr> bagImages() {
  std::vector<sensor_msgs::Image::ConstPtr> images;
  rosbag::Bag bag(testParam("data_dir") + "/sequence.bag");
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto img = m.instantiate<sensor_msgs::Image>()) images.push_back(img);
  }
  return images;
}

// The nodelet's "image" (public namespace: /image) on /<name>_image, as runNodelet
// shows it subscribes there when its ~load_map is good.
ros::M_string imageRemap(const std::string& name) {
  ros::M_string remap;
  remap[ros::names::resolve(name + "/image")] = name + "_image";
  remap["/image"] = name + "_image";
  return remap;
}

std::uint64_t processed(const Statuses& s) { return s.empty() ? 0 : s.back()->frames_processed; }

// Loads a TrackingNodelet `name` (its images on /<name>_image), feeds it the
// bag's images and unloads it. Returns its status messages.
Statuses runNodelet(const std::string& name, const std::vector<sensor_msgs::Image::ConstPtr>& images) {
  ros::NodeHandle nh;
  ros::param::set(name + "/calibration_file", testParam("data_dir") + "/calibration.yaml");
  ros::param::set(name + "/process_all_frames", true);
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>(name + "_image", 100);
  Watcher<vitamin_e::TrackingStatus> status(nh, name + "/status", 1000);
  nodelet::Loader loader(false);
  EXPECT_TRUE(loader.load(name, "vitamin_e/TrackingNodelet", imageRemap(name), nodelet::V_string()));
  const auto deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.02).sleep();
  EXPECT_GT(pub.getNumSubscribers(), 0u) << name << " did not subscribe";
  for (const auto& img : images) {
    pub.publish(img);
    ros::WallDuration(0.005).sleep();
  }
  EXPECT_TRUE(status.waitFor([&](const Statuses& s) { return processed(s) >= images.size(); }, 60.0))
      << name << ": frames processed " << processed(status.messages()) << " of " << images.size();
  EXPECT_TRUE(loader.unload(name));
  return status.messages();
}

}  // namespace

TEST(MapFile, SavedOnUnloadThenLocalizedInWithoutChangingIt) {
  const std::string out = testParam("output_dir", "/tmp");
  const std::string map_path = out + "/ros_map.vemap";
  std::remove(map_path.c_str());
  const auto images = bagImages();
  ASSERT_GE(images.size(), 20u);

  ros::param::set("/mapper/save_map", map_path);
  const Statuses mapping = runNodelet("/mapper", images);
  ASSERT_FALSE(mapping.empty());
  vitamin_e::map::MapFileContents saved;
  ASSERT_NO_THROW(saved = vitamin_e::map::loadMapFile(map_path)) << map_path << " not written on unload";
  ASSERT_GT(saved.keyframe_index.size(), 0u);
  const std::string bytes = readBytes(map_path);

  ros::param::set("/localizer/load_map", map_path);
  ros::param::set("/localizer/save_map", map_path);  // not written: localization only
  ros::param::set("/localizer/localization_only", true);
  const Statuses localizing = runNodelet("/localizer", images);
  std::size_t in_map = 0;
  for (const auto& s : localizing) {
    const bool found = s->message.rfind("localizing in loaded map", 0) == 0;
    EXPECT_TRUE(found || s->message.rfind("lost in loaded map", 0) == 0) << s->message;
    EXPECT_NE(s->state_name, "initializing") << s->message;
    EXPECT_EQ(s->init_retries, 0);
    in_map += found ? 1 : 0;
  }
  EXPECT_GE(in_map, images.size() / 2) << "frames localized in the loaded map";
  EXPECT_TRUE(readBytes(map_path) == bytes) << "the map file was changed in localization-only mode";
}

TEST(MapFile, BadMapFilesAreFatalTheLoadFailsNothingIsSubscribed) {
  const std::string out = testParam("output_dir", "/tmp");
  // A valid file to damage, and one from another camera size.
  vitamin_e::map::MapFileContents c;
  c.camera = vitamin_e::camera::loadCalibration(testParam("data_dir") + "/calibration.yaml").camera;
  c.scale_convention = "test";
  c.descriptors = {31, 2.0};
  c.keyframe_index.resize(1);
  c.keyframe_index[0].points.resize(50);
  const std::string good = out + "/bad_good.vemap";
  ASSERT_TRUE(vitamin_e::map::saveMapFile(c, good));
  const std::string bytes = readBytes(good);
  std::vector<std::pair<std::string, std::string>> files;  // path, expected words
  files.emplace_back(out + "/bad_empty.vemap", "empty");
  std::ofstream(files.back().first, std::ios::binary).flush();
  files.emplace_back(out + "/bad_cut.vemap", "truncated");
  std::ofstream(files.back().first, std::ios::binary) << bytes.substr(0, bytes.size() - 40);
  files.emplace_back(out + "/bad_flip.vemap", "corrupt");
  std::string flipped = bytes;
  flipped[bytes.size() - 30] ^= 0x04;
  std::ofstream(files.back().first, std::ios::binary) << flipped;
  files.emplace_back(out + "/bad_camera.vemap", "camera is");
  c.camera = vitamin_e::camera::Camera(c.camera.width() / 2 + 1, c.camera.height(), 100.0, 100.0, 40.0, 30.0);
  ASSERT_TRUE(vitamin_e::map::saveMapFile(c, files.back().first));

  ros::NodeHandle nh;
  Watcher<rosgraph_msgs::Log> rosout(nh, "/rosout", 1000);
  ASSERT_TRUE(rosout.waitForPublisher(10.0));
  int k = 0;
  for (const auto& file : files) {
    const std::string& path = file.first;
    const std::string& words = file.second;  // a lambda cannot capture a structured binding in C++17
    const std::string name = "/badmap" + std::to_string(k++);
    ros::param::set(name + "/calibration_file", testParam("data_dir") + "/calibration.yaml");
    ros::param::set(name + "/load_map", path);
    ros::Publisher pub = nh.advertise<sensor_msgs::Image>(name + "_image", 1);
    nodelet::Loader loader(false);
    // The load fails (onInit throws after its FATAL): `nodelet load` and roslaunch report it.
    EXPECT_FALSE(loader.load(name, "vitamin_e/TrackingNodelet", imageRemap(name), nodelet::V_string()))
        << name << " loaded with a bad ~load_map";
    const bool fatal = rosout.waitFor(
        [&](const std::vector<rosgraph_msgs::Log::ConstPtr>& logs) {
          for (const auto& log : logs) {
            if (log->level == rosgraph_msgs::Log::FATAL && log->msg.find(path) != std::string::npos &&
                log->msg.find(words) != std::string::npos) {
              return true;
            }
          }
          return false;
        },
        20.0);
    EXPECT_TRUE(fatal) << "no FATAL naming " << path << " and '" << words << "'";
    ros::WallDuration(0.5).sleep();  // a subscription would have connected by now
    EXPECT_EQ(pub.getNumSubscribers(), 0u) << name << " subscribed to images with a bad ~load_map";
    loader.unload(name);
  }
}
