#include "vitamin_e/ros/mesh_markers.h"

#include <algorithm>
#include <cmath>

namespace vitamin_e_ros {

namespace {

// A cyclic rainbow over heights: period map units from one blue to the next.
std_msgs::ColorRGBA heightColor(double z, double period) {
  const double t = z / period - std::floor(z / period);
  constexpr double kTwoPi = 6.283185307179586;
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(0.2 + 0.8 * (0.5 + 0.5 * std::cos(kTwoPi * (t - 0.75))));
  c.g = static_cast<float>(0.2 + 0.8 * (0.5 + 0.5 * std::cos(kTwoPi * (t - 0.45))));
  c.b = static_cast<float>(0.2 + 0.8 * (0.5 + 0.5 * std::cos(kTwoPi * (t - 0.1))));
  c.a = 1.0f;
  return c;
}

}  // namespace

MeshBlockMarkers::MeshBlockMarkers(const MeshMarkerOptions& options) : options_(options) {}

bool MeshBlockMarkers::sameSurface(const visualization_msgs::Marker& sent,
                                   const visualization_msgs::Marker& now) const {
  // Marching cubes lists a block's triangles in the same order while its cases stay the same.
  if (sent.points.size() != now.points.size()) return false;
  const double limit = options_.min_vertex_move * options_.min_vertex_move;
  for (std::size_t i = 0; i < now.points.size(); ++i) {
    const double dx = now.points[i].x - sent.points[i].x, dy = now.points[i].y - sent.points[i].y,
                 dz = now.points[i].z - sent.points[i].z;
    if (dx * dx + dy * dy + dz * dz > limit) return false;
  }
  return true;
}

visualization_msgs::Marker MeshBlockMarkers::deleteAll(const ros::Time& stamp) const {
  visualization_msgs::Marker m;
  m.header.frame_id = options_.frame_id;
  m.header.stamp = stamp;
  m.ns = options_.ns;
  m.action = visualization_msgs::Marker::DELETEALL;
  return m;
}

void MeshBlockMarkers::colour(visualization_msgs::Marker* marker) const {
  marker->colors.clear();
  if (!options_.color_by_height) return;
  marker->colors.reserve(marker->points.size());
  const double period = options_.height_color_period > 0.0 ? options_.height_color_period : 1.0;
  for (const auto& p : marker->points) marker->colors.push_back(heightColor(p.z, period));
}

visualization_msgs::MarkerArray MeshBlockMarkers::update(const vitamin_e::fusion::MeshBlockUpdate& update,
                                                         const ros::Time& stamp, std::size_t* skipped) {
  visualization_msgs::MarkerArray out;
  std::size_t bad = 0;
  if (update.replace_all) {
    out.markers.push_back(deleteAll(stamp));
    markers_.clear();
  }
  for (const vitamin_e::fusion::MeshBlock& block : update.blocks) {
    const auto key = std::make_tuple(block.index.x(), block.index.y(), block.index.z());
    const int id = ids_.emplace(key, static_cast<int>(ids_.size())).first->second;
    visualization_msgs::Marker m;
    m.header.frame_id = options_.frame_id;
    m.header.stamp = stamp;
    m.ns = options_.ns;
    m.id = id;
    m.type = visualization_msgs::Marker::TRIANGLE_LIST;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = 1.0;
    m.color.r = m.color.g = m.color.b = 0.7f;
    m.color.a = 1.0f;
    m.points.reserve(block.vertices.size());
    for (std::size_t i = 0; i + 2 < block.vertices.size(); i += 3) {
      const Eigen::Vector3f* v = &block.vertices[i];
      if (!v[0].allFinite() || !v[1].allFinite() || !v[2].allFinite()) {
        ++bad;
        continue;
      }
      for (int k = 0; k < 3; ++k) {
        geometry_msgs::Point p;
        p.x = v[k].x();
        p.y = v[k].y();
        p.z = v[k].z();
        m.points.push_back(p);
      }
    }
    if (m.points.empty()) {
      // Its surface is gone: delete the marker sent for it (after a DELETEALL there is none).
      if (markers_.erase(id) > 0) {
        m.action = visualization_msgs::Marker::DELETE;
        out.markers.push_back(m);
      }
      continue;
    }
    const auto sent = markers_.find(id);
    if (sent != markers_.end() && options_.min_vertex_move > 0.0 && sameSurface(sent->second, m)) continue;
    m.action = visualization_msgs::Marker::ADD;
    colour(&m);
    markers_[id] = m;
    out.markers.push_back(std::move(m));
  }
  last_stamp_ = stamp;
  if (skipped) *skipped = bad;
  return out;
}

visualization_msgs::MarkerArray MeshBlockMarkers::full() const {
  visualization_msgs::MarkerArray out;
  out.markers.reserve(markers_.size() + 1);
  out.markers.push_back(deleteAll(last_stamp_));
  for (const auto& [id, m] : markers_) out.markers.push_back(m);
  return out;
}

visualization_msgs::MarkerArray MeshBlockMarkers::clear(const ros::Time& stamp) {
  markers_.clear();
  ids_.clear();
  last_stamp_ = stamp;
  visualization_msgs::MarkerArray out;
  out.markers.push_back(deleteAll(stamp));
  return out;
}

bool MeshBlockMarkers::setOptions(const MeshMarkerOptions& options) {
  const bool recolour = options.color_by_height != options_.color_by_height ||
                        options.height_color_period != options_.height_color_period;
  // (min_vertex_move applies from the next update on.)
  const bool renamed = options.frame_id != options_.frame_id || options.ns != options_.ns;
  options_ = options;
  if (!recolour && !renamed) return false;
  for (auto& [id, m] : markers_) {
    m.header.frame_id = options_.frame_id;
    m.ns = options_.ns;
    if (recolour) colour(&m);
  }
  return true;
}

std::size_t MeshBlockMarkers::numTriangles() const {
  std::size_t n = 0;
  for (const auto& [id, m] : markers_) n += m.points.size() / 3;
  return n;
}

}  // namespace vitamin_e_ros
