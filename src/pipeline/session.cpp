#include "vitamin_e/pipeline/session.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace vitamin_e::pipeline {

const char* toString(TimeJumpPolicy policy) {
  switch (policy) {
    case TimeJumpPolicy::kRelocalize: return "relocalize";
    case TimeJumpPolicy::kDrop: return "drop";
  }
  return "?";
}

TimeJumpPolicy timeJumpPolicyFromString(const std::string& text) {
  if (text == "relocalize") return TimeJumpPolicy::kRelocalize;
  if (text == "drop") return TimeJumpPolicy::kDrop;
  throw std::invalid_argument("time jump policy must be relocalize or drop (got '" + text + "')");
}

void SessionConfig::validate() const {
  if (!(time_jump_threshold_s > 0.0) || !std::isfinite(time_jump_threshold_s)) {
    throw std::invalid_argument("time_jump_threshold must be > 0 s (got " + std::to_string(time_jump_threshold_s) +
                                ")");
  }
}

Session::Session(const SystemConfig& config, const camera::Camera& camera, const SessionConfig& session)
    : config_(config), camera_(camera), session_config_(session) {
  session_config_.validate();
  system_ = std::make_unique<System>(config_, camera_);
  current_.number = 1;
  current_.map = 1;
  current_.note = "start";
}

Session::~Session() = default;

SessionStamp Session::admit(double timestamp) {
  SessionStamp s;
  char text[200];
  if (!std::isfinite(timestamp)) {
    ++dropped_;
    s.dropped_why = "stamp is not finite";
    return s;
  }
  if (have_last_stamp_ && !(timestamp > last_stamp_)) {
    const double back = last_stamp_ - timestamp;
    if (session_config_.on_time_jump != TimeJumpPolicy::kRelocalize ||
        !(back > session_config_.time_jump_threshold_s)) {
      ++dropped_;
      std::snprintf(text, sizeof(text), "stamp %.9f does not increase (last %.9f)", timestamp, last_stamp_);
      s.dropped_why = text;
      return s;
    }
    std::snprintf(text, sizeof(text), "time jump: stamp jumped back by %.3f s (%.3f -> %.3f)", back, last_stamp_,
                  timestamp);
    s.time_jump = true;
    s.jump_back_s = back;
    ++time_jumps_;
    const std::string why = text;
    if (system_->restartTracking()) {
      finishSegment();
      current_.note = why + "; relocalizing in map " + std::to_string(current_.map);
    } else {
      // Nothing to relocalize in (no map yet, or relocalization off): a new map.
      reset(why + "; no map to relocalize in: a new map");
    }
  }
  have_last_stamp_ = true;
  last_stamp_ = timestamp;
  s.admitted = true;
  return s;
}

SessionFrame Session::process(const cv::Mat& image, double timestamp, const std::string& timestamp_text) {
  const SessionStamp s = admit(timestamp);
  SessionFrame f;
  f.dropped_why = s.dropped_why;
  f.time_jump = s.time_jump;
  f.jump_back_s = s.jump_back_s;
  if (!s.admitted) return f;
  f.result = system_->process(image, timestamp, timestamp_text);
  f.processed = true;
  return f;
}

void Session::finishSegment() {
  const auto& trajectory = system_->trajectory();
  TrajectorySegment done = current_;
  if (segment_begin_ < trajectory.size()) {
    done.poses.assign(trajectory.begin() + static_cast<std::ptrdiff_t>(segment_begin_), trajectory.end());
  }
  if (!done.poses.empty()) finished_.push_back(std::move(done));
  segment_begin_ = trajectory.size();
  ++current_.number;
}

void Session::reset(const std::string& why) {
  finishSegment();
  done_processed_ += system_->framesProcessed();
  done_tracked_ += system_->framesTracked();
  done_retries_ += system_->initRetries();
  done_relocalizations_ += system_->relocalizations();
  const bool localization_only = system_->localizationOnly();
  system_ = std::make_unique<System>(config_, camera_);
  system_->setLocalizationOnly(localization_only);
  segment_begin_ = 0;
  have_last_stamp_ = false;
  ++current_.map;
  current_.note = why;
}

std::vector<TrajectorySegment> Session::segments() const {
  std::vector<TrajectorySegment> all = finished_;
  TrajectorySegment current = current_;
  const auto& trajectory = system_->trajectory();
  if (segment_begin_ < trajectory.size()) {
    current.poses.assign(trajectory.begin() + static_cast<std::ptrdiff_t>(segment_begin_), trajectory.end());
  }
  if (!current.poses.empty() || all.empty()) all.push_back(std::move(current));
  return all;
}

std::size_t Session::framesProcessed() const { return done_processed_ + system_->framesProcessed(); }
std::size_t Session::framesTracked() const { return done_tracked_ + system_->framesTracked(); }
int Session::initRetries() const { return done_retries_ + system_->initRetries(); }
int Session::relocalizations() const { return done_relocalizations_ + system_->relocalizations(); }

namespace {
constexpr const char* kSegment = "# segment ";
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
  for (const TrajectorySegment& s : segments) {
    out << kSegment << s.number << " (map " << s.map << "): " << s.note << "\n";
    for (const auto& e : s.poses) {
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
      TrajectorySegment s;
      s.number = static_cast<unsigned>(segments.size() + 1);
      s.map = s.number;
      const std::size_t colon = line.find(": ");
      const std::string head = line.substr(0, colon);
      // "# segment N (map M)", or "# segment N" (written before maps were numbered).
      const char* const end = head.data() + head.size();
      unsigned number = 0, map = 0;
      const auto n = std::from_chars(head.data() + std::strlen(kSegment), end, number);
      if (n.ec == std::errc()) {
        s.number = number;
        s.map = number;
        constexpr std::string_view kMap = " (map ";
        if (std::string_view(n.ptr, static_cast<std::size_t>(end - n.ptr)).rfind(kMap, 0) == 0 &&
            std::from_chars(n.ptr + kMap.size(), end, map).ec == std::errc()) {
          s.map = map;
        }
      }
      s.note = colon == std::string::npos ? "" : line.substr(colon + 2);
      segments.push_back(std::move(s));
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    double v[8];
    int k = 0;
    while (k < 8 && ls >> v[k]) ++k;
    if (k != 8) throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected 8 numbers");
    if (segments.empty()) segments.emplace_back();
    TrajectoryEntry e;
    e.timestamp = v[0];
    e.T_w_c.translation() << v[1], v[2], v[3];
    e.T_w_c.linear() = Eigen::Quaterniond(v[7], v[4], v[5], v[6]).normalized().toRotationMatrix();
    segments.back().poses.push_back(e);
  }
  return segments;
}

}  // namespace vitamin_e::pipeline
