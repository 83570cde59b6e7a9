#pragma once
// Trajectory files for evaluation: readers for TUM (`t tx ty tz qx qy qz qw`),
// EuRoC ground-truth csv (`t_ns, px, py, pz, qw, qx, qy, qz, ...`) and KITTI
// poses (12 numbers, row-major 3x4 T_w_c per line; timestamps from times.txt or
// index * 0.1 s), with format auto-detection, a TUM writer, and the body-to-
// camera change (EuRoC ground truth is the body/IMU pose: T_w_c = T_w_b * T_b_c).
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace vitamin_e::eval {

struct TrajectoryError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct StampedPose {
  double t = 0.0;  // seconds
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
};
using Trajectory = std::vector<StampedPose>;

enum class TrajectoryFormat { kAuto, kTum, kEurocCsv, kKitti };
const char* toString(TrajectoryFormat format);

struct ReadOptions {
  TrajectoryFormat format = TrajectoryFormat::kAuto;
  // KITTI: timestamps file (one number per line). Empty: "times.txt" beside the
  // poses file if it exists, else index * kitti_period_s.
  std::string kitti_times_path;
  double kitti_period_s = 0.1;
};

// Format from the first data line: commas -> EuRoC csv; 8 numbers -> TUM;
// 12 numbers -> KITTI. Throws TrajectoryError if none fits.
TrajectoryFormat detectTrajectoryFormat(const std::string& path);

// Resolves a dataset folder to its ground-truth file: the path itself if it is a
// file; else DIR/groundtruth_cam0_tum.txt, DIR/mav0/state_groundtruth_estimate0/data.csv,
// DIR/state_groundtruth_estimate0/data.csv, DIR/groundtruth.txt (first found).
std::string resolveTrajectoryPath(const std::string& path);

// Reads a trajectory (sorted by time on return). Throws TrajectoryError with the
// file name and line number on malformed input; an empty file gives an empty
// trajectory. Quaternions are normalized.
Trajectory readTrajectory(const std::string& path, const ReadOptions& options = {});
Trajectory readTum(const std::string& path);
Trajectory readEurocCsv(const std::string& path);
Trajectory readKitti(const std::string& path, const std::string& times_path = "", double period_s = 0.1);

// TUM text, `%.9f` seconds and positions, one pose per line after a comment header.
void writeTum(const std::string& path, const Trajectory& trajectory);

// T_b_c (EuRoC T_BS) from a sensor.yaml (handles "%YAML:1.0"); throws
// TrajectoryError if the file or its T_BS (16 numbers) is missing or bad.
Eigen::Isometry3d loadBodyToCamera(const std::string& sensor_yaml);
// Every pose T_w_b -> T_w_b * T_b_c.
Trajectory applyBodyToCamera(const Trajectory& body, const Eigen::Isometry3d& T_b_c);

}  // namespace vitamin_e::eval
