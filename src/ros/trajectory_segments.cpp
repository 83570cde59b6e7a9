#include "vitamin_e/ros/trajectory_segments.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace vitamin_e_ros {

namespace {
const char* kSegment = "# segment ";
}

bool saveSegmentsTum(const std::vector<TrajectorySegment>& segments, const std::string& header, const std::string& path,
                     std::string* error) {
  std::ofstream out(path);
  if (!out) {
    if (error) *error = "cannot write trajectory to '" + path + "': " + std::strerror(errno);
    return false;
  }
  out << "# timestamp tx ty tz qx qy qz qw (" << header << ")\n";
  char line[256];
  for (std::size_t k = 0; k < segments.size(); ++k) {
    out << kSegment << (k + 1) << ": " << segments[k].note << "\n";
    for (const auto& e : segments[k].poses) {
      const Eigen::Vector3d t = e.T_w_c.translation();
      Eigen::Quaterniond q(e.T_w_c.rotation());
      q.normalize();
      if (!t.allFinite() || !q.coeffs().allFinite()) continue;  // never write a non-finite pose
      std::string stamp = e.timestamp_text;
      if (stamp.empty()) {
        char buf[64];
        std::snprintf(buf, sizeof(buf), "%.9f", e.timestamp);
        stamp = buf;
      }
      std::snprintf(line, sizeof(line), " %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", t.x(), t.y(), t.z(), q.x(), q.y(),
                    q.z(), q.w());
      out << stamp << line;
    }
  }
  out.flush();
  if (!out) {
    if (error) *error = "error while writing trajectory to '" + path + "'";
    return false;
  }
  return true;
}

std::vector<TrajectorySegment> readSegmentsTum(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read '" + path + "'");
  std::vector<TrajectorySegment> segments;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.rfind(kSegment, 0) == 0) {
      segments.emplace_back();
      const std::size_t colon = line.find(": ");
      segments.back().note = colon == std::string::npos ? "" : line.substr(colon + 2);
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    double v[8];
    int k = 0;
    while (k < 8 && ls >> v[k]) ++k;
    if (k != 8) throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected 8 numbers");
    if (segments.empty()) segments.emplace_back();
    vitamin_e::pipeline::TrajectoryEntry e;
    e.timestamp = v[0];
    e.T_w_c.translation() << v[1], v[2], v[3];
    e.T_w_c.linear() = Eigen::Quaterniond(v[7], v[4], v[5], v[6]).normalized().toRotationMatrix();
    segments.back().poses.push_back(e);
  }
  return segments;
}

}  // namespace vitamin_e_ros
