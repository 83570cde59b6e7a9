#include "vitamin_e/ros/mesh_markers.h"

#include <algorithm>
#include <limits>

namespace vitamin_e_ros {

namespace {

std_msgs::ColorRGBA heightColor(float z, float z_min, float z_max) {
  // Blue (low) -> green -> red (high).
  const float t = z_max > z_min ? std::clamp((z - z_min) / (z_max - z_min), 0.0f, 1.0f) : 0.5f;
  std_msgs::ColorRGBA c;
  c.r = std::clamp(2.0f * t - 1.0f, 0.0f, 1.0f) * 0.8f + 0.2f;
  c.g = (1.0f - std::abs(2.0f * t - 1.0f)) * 0.8f + 0.2f;
  c.b = std::clamp(1.0f - 2.0f * t, 0.0f, 1.0f) * 0.8f + 0.2f;
  c.a = 1.0f;
  return c;
}

}  // namespace

std::size_t meshToMarkers(const vitamin_e::fusion::TriangleMesh& mesh, const MeshMarkerOptions& options,
                          std::size_t previous_markers, visualization_msgs::MarkerArray* out, std::size_t* skipped) {
  out->markers.clear();
  float z_min = std::numeric_limits<float>::max(), z_max = std::numeric_limits<float>::lowest();
  for (const auto& v : mesh.vertices) {
    if (!v.allFinite()) continue;
    z_min = std::min(z_min, v.z());
    z_max = std::max(z_max, v.z());
  }
  const std::size_t per_marker = std::max<std::size_t>(1, options.triangles_per_marker);
  const int num_vertices = static_cast<int>(mesh.vertices.size());
  std::size_t bad = 0;
  visualization_msgs::Marker* marker = nullptr;
  std::size_t in_marker = 0;
  for (const auto& f : mesh.faces) {
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      ok = ok && f[k] >= 0 && f[k] < num_vertices && mesh.vertices[f[k]].allFinite();
    }
    if (!ok) {
      ++bad;
      continue;
    }
    if (!marker || in_marker == per_marker) {
      out->markers.emplace_back();
      marker = &out->markers.back();
      marker->header.frame_id = options.frame_id;
      marker->header.stamp = options.stamp;
      marker->ns = options.ns;
      marker->id = static_cast<int>(out->markers.size() - 1);
      marker->type = visualization_msgs::Marker::TRIANGLE_LIST;
      marker->action = visualization_msgs::Marker::ADD;
      marker->pose.orientation.w = 1.0;
      marker->scale.x = marker->scale.y = marker->scale.z = 1.0;
      marker->color.r = marker->color.g = marker->color.b = 0.7f;
      marker->color.a = 1.0f;
      marker->points.reserve(3 * std::min(per_marker, mesh.faces.size()));
      in_marker = 0;
    }
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f& v = mesh.vertices[f[k]];
      geometry_msgs::Point p;
      p.x = v.x();
      p.y = v.y();
      p.z = v.z();
      marker->points.push_back(p);
      if (options.color_by_height) marker->colors.push_back(heightColor(v.z(), z_min, z_max));
    }
    ++in_marker;
  }
  const std::size_t n = out->markers.size();
  for (std::size_t id = n; id < previous_markers; ++id) {
    visualization_msgs::Marker del;
    del.header.frame_id = options.frame_id;
    del.header.stamp = options.stamp;
    del.ns = options.ns;
    del.id = static_cast<int>(id);
    del.action = visualization_msgs::Marker::DELETE;
    out->markers.push_back(del);
  }
  if (skipped) *skipped = bad;
  return n;
}

}  // namespace vitamin_e_ros
