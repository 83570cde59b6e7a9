#include "vitamin_e/ros/bag_dataset.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>
#include <vector>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>

#include "vitamin_e/ros/conversions.h"

namespace vitamin_e_ros {

using vitamin_e::io::DatasetError;

namespace {

struct BagFrame {
  ros::Time stamp;
  std::size_t message = 0;  // index into Impl::messages (MessageInstance is not assignable)
};

std::string stampText(const ros::Time& t) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%u.%09u", t.sec, t.nsec);
  return buf;
}

// Image message -> CV_8UC1: the ROS layer's one conversion (toMono8), errors as DatasetError.
cv::Mat toGray(const sensor_msgs::Image& msg, const std::string& what) {
  cv::Mat gray;
  std::string error;
  if (!toMono8(msg, &gray, &error)) throw DatasetError(what + ": " + error);
  return gray;
}

}  // namespace

struct BagDataset::Impl {
  std::string path;
  std::string topic;
  rosbag::Bag bag;
  std::vector<rosbag::MessageInstance> messages;  // bag order
  std::vector<BagFrame> frames;                   // sorted by header stamp
  vitamin_e::camera::CameraCalibration calibration;

  std::string frameName(std::size_t i) const {
    return "'" + path + "' " + topic + " message " + std::to_string(i) + " (stamp " + stampText(frames[i].stamp) + ")";
  }
  sensor_msgs::ImageConstPtr read(std::size_t i) const {
    try {
      sensor_msgs::ImageConstPtr msg = messages.at(frames.at(i).message).instantiate<sensor_msgs::Image>();
      if (!msg) throw DatasetError(frameName(i) + " is not a sensor_msgs/Image");
      return msg;
    } catch (const rosbag::BagException& e) {
      throw DatasetError(frameName(i) + " cannot be read: " + e.what());
    } catch (const ros::Exception& e) {
      throw DatasetError(frameName(i) + " cannot be read: " + e.what());
    }
  }
};

BagDataset::BagDataset(const std::string& bag_path, const vitamin_e::io::DatasetOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = bag_path;
  m.topic = options.bag_topic;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(bag_path, ec)) throw DatasetError("bag '" + bag_path + "' does not exist");
  if (options.calibration_path.empty()) {
    throw DatasetError("bag '" + bag_path + "': a calibration file is required for rosbags (--calib FILE)");
  }
  try {
    m.bag.open(bag_path, rosbag::bagmode::Read);
    rosbag::View all(m.bag);
    std::set<std::string> image_topics;
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      if (c->datatype == "sensor_msgs/Image") image_topics.insert(c->topic);
    }
    if (!image_topics.count(m.topic)) {
      std::string list;
      for (const std::string& t : image_topics) list += (list.empty() ? "" : ", ") + t;
      throw DatasetError("bag '" + bag_path + "' has no sensor_msgs/Image on topic '" + m.topic + "'" +
                         (list.empty() ? std::string(" (no image topics at all)") : " (image topics: " + list + ")"));
    }
    rosbag::View view(m.bag, rosbag::TopicQuery(m.topic));
    for (const rosbag::MessageInstance& mi : view) {
      sensor_msgs::ImageConstPtr msg = mi.instantiate<sensor_msgs::Image>();
      if (!msg) continue;
      m.frames.push_back({msg->header.stamp, m.messages.size()});
      m.messages.push_back(mi);
    }
  } catch (const rosbag::BagException& e) {
    throw DatasetError("bag '" + bag_path + "' cannot be read (truncated or not a bag?): " + e.what());
  } catch (const ros::Exception& e) {
    throw DatasetError("bag '" + bag_path + "' cannot be read: " + e.what());
  }
  if (m.frames.empty()) throw DatasetError("bag '" + bag_path + "' has no images on '" + m.topic + "'");
  std::stable_sort(m.frames.begin(), m.frames.end(),
                   [](const BagFrame& a, const BagFrame& b) { return a.stamp < b.stamp; });

  const cv::Mat first = toGray(*m.read(0), m.frameName(0));
  try {
    m.calibration = vitamin_e::camera::loadCalibration(options.calibration_path, first.cols, first.rows);
  } catch (const vitamin_e::camera::CalibrationError& e) {
    throw DatasetError(e.what());
  }
  const auto& cam = m.calibration.camera;
  if (first.cols != cam.width() || first.rows != cam.height()) {
    throw DatasetError("bag '" + bag_path + "' images are " + std::to_string(first.cols) + "x" +
                       std::to_string(first.rows) + " but the calibration '" + options.calibration_path + "' is for " +
                       std::to_string(cam.width()) + "x" + std::to_string(cam.height()));
  }
}

BagDataset::~BagDataset() = default;

std::size_t BagDataset::size() const { return impl_->frames.size(); }
double BagDataset::timestamp(std::size_t i) const { return impl_->frames.at(i).stamp.toSec(); }
std::string BagDataset::timestampText(std::size_t i) const { return stampText(impl_->frames.at(i).stamp); }
const vitamin_e::camera::CameraCalibration& BagDataset::calibration() const { return impl_->calibration; }
const std::string& BagDataset::topic() const { return impl_->topic; }

cv::Mat BagDataset::loadImage(std::size_t i) const {
  cv::Mat gray = toGray(*impl_->read(i), impl_->frameName(i));
  const auto& cam = impl_->calibration.camera;
  if (gray.cols != cam.width() || gray.rows != cam.height()) {
    throw DatasetError(impl_->frameName(i) + " is " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                       ", expected " + std::to_string(cam.width()) + "x" + std::to_string(cam.height()));
  }
  return gray;
}

std::unique_ptr<vitamin_e::io::Dataset> openAnyDataset(const std::string& path,
                                                       const vitamin_e::io::DatasetOptions& options) {
  if (vitamin_e::io::detectDatasetKind(path) == "rosbag") return std::make_unique<BagDataset>(path, options);
  return vitamin_e::io::openDataset(path, options);
}

}  // namespace vitamin_e_ros
