#include "vitamin_e/eval/trajectory.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace vitamin_e::eval {
namespace {

bool fileExists(const std::string& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

bool isDirectory(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec);
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// Numbers of one line, separated by whitespace and/or commas; false if a token
// is not a finite number.
bool parseNumbers(const std::string& line, std::vector<double>* out) {
  out->clear();
  std::string s = line;
  std::replace(s.begin(), s.end(), ',', ' ');
  std::istringstream in(s);
  std::string tok;
  while (in >> tok) {
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0' || !std::isfinite(v)) return false;
    out->push_back(v);
  }
  return true;
}

std::ifstream openOrThrow(const std::string& path) {
  std::ifstream f(path);
  if (!f.good() || isDirectory(path)) throw TrajectoryError(path + ": cannot open trajectory file");
  return f;
}

[[noreturn]] void badLine(const std::string& path, int line_no, const std::string& what) {
  throw TrajectoryError(path + ":" + std::to_string(line_no) + ": " + what);
}

Eigen::Isometry3d makePose(const Eigen::Vector3d& p, Eigen::Quaterniond q, const std::string& path, int line_no) {
  const double n = q.norm();
  if (n < 1e-6) badLine(path, line_no, "zero quaternion");
  q.coeffs() /= n;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = p;
  return T;
}

// Calls on_line(numbers, line_no) for every non-empty, non-comment line of the
// file; a line that is not all numbers, or has a count outside [min_count,
// max_count], throws naming the file, the line and `expected`.
template <typename OnLine>
void forEachNumberLine(const std::string& path, std::size_t min_count, std::size_t max_count,
                       const std::string& expected, OnLine on_line) {
  auto f = openOrThrow(path);
  std::string line;
  std::vector<double> v;
  int line_no = 0;
  while (std::getline(f, line)) {
    ++line_no;
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    if (!parseNumbers(s, &v) || v.size() < min_count || v.size() > max_count) badLine(path, line_no, expected);
    on_line(s, v, line_no);
  }
}

void sortByTime(Trajectory* traj) {
  std::stable_sort(traj->begin(), traj->end(), [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; });
}

std::string firstDataLine(const std::string& path) {
  auto f = openOrThrow(path);
  std::string line;
  while (std::getline(f, line)) {
    std::string s = trim(line);
    if (s.empty() || s[0] == '#' || s[0] == '%') continue;
    return s;
  }
  return {};
}

}  // namespace

const char* toString(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kAuto: return "auto";
    case TrajectoryFormat::kTum: return "tum";
    case TrajectoryFormat::kEurocCsv: return "euroc-csv";
    case TrajectoryFormat::kKitti: return "kitti";
  }
  return "unknown";
}

TrajectoryFormat detectTrajectoryFormat(const std::string& path) {
  const std::string line = firstDataLine(path);
  if (line.empty()) return TrajectoryFormat::kTum;  // empty: any reader gives no poses
  std::vector<double> v;
  if (!parseNumbers(line, &v)) throw TrajectoryError(path + ": first data line is not numeric: '" + line + "'");
  if (line.find(',') != std::string::npos && v.size() >= 8) return TrajectoryFormat::kEurocCsv;
  if (v.size() == 8) return TrajectoryFormat::kTum;
  if (v.size() == 12) return TrajectoryFormat::kKitti;
  throw TrajectoryError(path + ": unknown trajectory format (" + std::to_string(v.size()) +
                        " numbers per line; TUM has 8, KITTI 12, EuRoC csv >= 8 with commas)");
}

std::string resolveTrajectoryPath(const std::string& path) {
  if (!isDirectory(path)) return path;
  for (const char* rel : {"groundtruth_cam0_tum.txt", "mav0/state_groundtruth_estimate0/data.csv",
                          "state_groundtruth_estimate0/data.csv", "groundtruth.txt"}) {
    std::string p = (std::filesystem::path(path) / rel).lexically_normal().string();
    if (fileExists(p) && !isDirectory(p)) return p;
  }
  throw TrajectoryError(path + ": folder without a ground-truth file (groundtruth_cam0_tum.txt, "
                               "mav0/state_groundtruth_estimate0/data.csv, groundtruth.txt)");
}

Trajectory readTum(const std::string& path) {
  Trajectory traj;
  forEachNumberLine(
      path, 8, 8, "expected 8 numbers 't tx ty tz qx qy qz qw'",
      [&](const std::string&, const std::vector<double>& v, int line_no) {
        StampedPose sp;
        sp.t = v[0];
        sp.T_w_c = makePose({v[1], v[2], v[3]}, Eigen::Quaterniond(v[7], v[4], v[5], v[6]), path, line_no);
        traj.push_back(sp);
      });
  sortByTime(&traj);
  return traj;
}

Trajectory readEurocCsv(const std::string& path) {
  Trajectory traj;
  auto on_line = [&](const std::string& s, const std::vector<double>& v, int line_no) {
    // Integer nanoseconds: split to keep precision (1.4e18 ns exceeds a double's 53 bits).
    const std::string tok = trim(s.substr(0, s.find(',')));
    StampedPose sp;
    if (tok.size() > 9 && tok.find_first_not_of("0123456789") == std::string::npos) {
      sp.t = std::stod(tok.substr(0, tok.size() - 9)) + std::stod(tok.substr(tok.size() - 9)) * 1e-9;
    } else {
      sp.t = v[0] * 1e-9;
    }
    sp.T_w_c = makePose({v[1], v[2], v[3]}, Eigen::Quaterniond(v[4], v[5], v[6], v[7]), path, line_no);
    traj.push_back(sp);
  };
  forEachNumberLine(path, 8, std::numeric_limits<std::size_t>::max(),
                    "expected 't_ns, px, py, pz, qw, qx, qy, qz, ...'", on_line);
  sortByTime(&traj);
  return traj;
}

Trajectory readKitti(const std::string& path, const std::string& times_path, double period_s) {
  openOrThrow(path);  // the poses file's error comes first
  std::vector<double> times;
  std::string tpath = times_path;
  if (tpath.empty()) {
    const auto slash = path.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
    if (fileExists(dir + "/times.txt")) tpath = dir + "/times.txt";
  }
  if (!tpath.empty()) {
    forEachNumberLine(tpath, 1, 1, "expected one timestamp per line",
                      [&](const std::string&, const std::vector<double>& v, int) { times.push_back(v[0]); });
  }
  Trajectory traj;
  auto on_line = [&](const std::string&, const std::vector<double>& v, int line_no) {
    Eigen::Matrix3d R;
    R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    // Re-orthonormalize (KITTI files have ~1e-6 rounding).
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
    R = svd.matrixU() * svd.matrixV().transpose();
    if (R.determinant() < 0.5) badLine(path, line_no, "rotation part is not a rotation");
    StampedPose sp;
    const std::size_t k = traj.size();
    if (!tpath.empty()) {
      if (k >= times.size()) badLine(path, line_no, "more poses than timestamps in " + tpath);
      sp.t = times[k];
    } else {
      sp.t = period_s * static_cast<double>(k);
    }
    sp.T_w_c.linear() = R;
    sp.T_w_c.translation() = Eigen::Vector3d(v[3], v[7], v[11]);
    traj.push_back(sp);
  };
  forEachNumberLine(path, 12, 12, "expected 12 numbers (row-major 3x4 T_w_c)", on_line);
  sortByTime(&traj);
  return traj;
}

Trajectory readTrajectory(const std::string& path_in, const ReadOptions& options) {
  const std::string path = resolveTrajectoryPath(path_in);
  TrajectoryFormat fmt = options.format;
  if (fmt == TrajectoryFormat::kAuto) fmt = detectTrajectoryFormat(path);
  switch (fmt) {
    case TrajectoryFormat::kTum: return readTum(path);
    case TrajectoryFormat::kEurocCsv: return readEurocCsv(path);
    case TrajectoryFormat::kKitti: return readKitti(path, options.kitti_times_path, options.kitti_period_s);
    case TrajectoryFormat::kAuto: break;
  }
  throw TrajectoryError(path + ": no format");
}

void writeTum(const std::string& path, const Trajectory& trajectory) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw TrajectoryError(path + ": cannot write");
  std::fprintf(f, "# timestamp[s] tx ty tz qx qy qz qw\n");
  for (const auto& sp : trajectory) {
    const Eigen::Quaterniond q(sp.T_w_c.rotation());
    const Eigen::Vector3d& p = sp.T_w_c.translation();
    std::fprintf(f, "%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", sp.t, p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w());
  }
  if (std::fclose(f) != 0) throw TrajectoryError(path + ": write failed");
}

Eigen::Isometry3d loadBodyToCamera(const std::string& sensor_yaml) {
  std::ifstream f(sensor_yaml);
  if (!f.good() || isDirectory(sensor_yaml)) throw TrajectoryError(sensor_yaml + ": cannot open sensor yaml");
  std::stringstream text;
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("%YAML", 0) == 0) continue;  // OpenCV's "%YAML:1.0" is not YAML 1.2
    text << line << "\n";
  }
  std::vector<double> data;
  try {
    const YAML::Node root = YAML::Load(text.str());
    const YAML::Node T = root["T_BS"];
    if (!T) throw TrajectoryError(sensor_yaml + ": no T_BS");
    const YAML::Node d = T.IsMap() ? T["data"] : T;
    if (!d || !d.IsSequence()) throw TrajectoryError(sensor_yaml + ": T_BS has no data list");
    for (const auto& n : d) {
      if (n.IsSequence()) {
        for (const auto& m : n) data.push_back(m.as<double>());
      } else {
        data.push_back(n.as<double>());
      }
    }
  } catch (const YAML::Exception& e) {
    throw TrajectoryError(sensor_yaml + ": " + e.what());
  }
  if (data.size() != 16)
    throw TrajectoryError(sensor_yaml + ": T_BS needs 16 numbers, got " + std::to_string(data.size()));
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = data[4 * r + c];
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-3 || R.determinant() < 0.0)
    throw TrajectoryError(sensor_yaml + ": T_BS rotation is not orthonormal");
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d T_b_c = Eigen::Isometry3d::Identity();
  T_b_c.linear() = svd.matrixU() * svd.matrixV().transpose();
  T_b_c.translation() = M.topRightCorner<3, 1>();
  return T_b_c;
}

Trajectory applyBodyToCamera(const Trajectory& body, const Eigen::Isometry3d& T_b_c) {
  Trajectory out = body;
  for (auto& sp : out) sp.T_w_c = sp.T_w_c * T_b_c;
  return out;
}

}  // namespace vitamin_e::eval
