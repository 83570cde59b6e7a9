// vitamin_e_evaluate: accuracy of an estimated trajectory against ground truth
// (associate by timestamp, Sim(3) Umeyama alignment, ATE, RPE, success rate).
//   vitamin_e_evaluate TRAJ GT [--frames N] [--max-dt S] [--body-to-camera YAML]
//                      [--se3] [--rpe-delta S] [--kitti-times FILE] [--json] [--aligned-out FILE]
//                      [--gt-out FILE] [--errors-out FILE] [--alignment-from TRAJ0 [--alignment-gt GT0]]
// TRAJ/GT: TUM, EuRoC csv or KITTI poses (auto-detected); GT may be a dataset
// folder. Prints a summary, then the JSON result as the last line (--json: JSON only).
// Bad input: one "error: ..." line on stderr, exit 2.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iostream>
#include <string>

#include "cli.h"
#include "vitamin_e/eval/metrics.h"

namespace ve = vitamin_e::eval;

namespace {

const char* const kUsage =
    "usage: vitamin_e_evaluate TRAJ GT [--frames N] [--max-dt S] [--body-to-camera SENSOR_YAML]\n"
    "                          [--se3] [--rpe-delta S] [--kitti-times FILE] [--json] [--aligned-out FILE]\n"
    "                          [--gt-out FILE] [--errors-out FILE] [--alignment-from TRAJ0 [--alignment-gt GT0]]\n"
    "  TRAJ, GT          trajectory files: TUM 't tx ty tz qx qy qz qw', EuRoC ground-truth csv,\n"
    "                    or KITTI poses (auto-detected); GT may be a dataset folder\n"
    "  --frames N        number of input frames for the success rate (default: estimate poses)\n"
    "  --max-dt S        association tolerance in seconds (default 0.02, nearest pose)\n"
    "  --body-to-camera Y  GT is the body pose: use T_w_b * T_BS (T_BS from an EuRoC sensor.yaml);\n"
    "                    automatic for mav0/state_groundtruth_estimate0/data.csv beside mav0/cam0/sensor.yaml\n"
    "  --se3             rigid alignment (scale known) instead of Sim(3)\n"
    "  --rpe-delta S     time delta of the second RPE (default 1 s)\n"
    "  --kitti-times F   timestamps for KITTI poses files (default times.txt beside them, or 0.1 s steps)\n"
    "  --json            print only the JSON line\n"
    "  --aligned-out F   write the aligned estimate (TUM) to F\n"
    "  --gt-out F        write the ground truth as used (TUM, camera poses) to F\n"
    "  --errors-out F    write 't_estimate position_error_m' per matched pose to F\n"
    "  --alignment-from TRAJ0  do not fit an alignment: apply the one fitted on TRAJ0 (e.g. the run that\n"
    "                    made a map TRAJ was localized in, same world frame) against GT0, unchanged\n"
    "  --alignment-gt GT0  ground truth for TRAJ0 (default: GT)\n";

using vitamin_e::cli::fail;

}  // namespace

int main(int argc, char** argv) {
  ve::EvalConfig cfg;
  std::string body_to_camera, aligned_out, gt_out, errors_out, alignment_from, alignment_gt;
  ve::ReadOptions gt_options;
  bool json_only = false;
  std::string traj_path, gt_arg;
  bool se3 = false;
  vitamin_e::cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.value("--frames", &cfg.frames) || args.value("--max-dt", &cfg.max_dt) ||
        args.value("--rpe-delta", &cfg.rpe_delta_s) || args.value("--body-to-camera", &body_to_camera) ||
        args.value("--kitti-times", &gt_options.kitti_times_path) || args.value("--aligned-out", &aligned_out) ||
        args.value("--gt-out", &gt_out) || args.value("--errors-out", &errors_out) ||
        args.value("--alignment-from", &alignment_from) || args.value("--alignment-gt", &alignment_gt) ||
        args.flag("--se3", &se3) || args.flag("--json", &json_only) || args.positional(&traj_path) ||
        args.positional(&gt_arg)) {
      continue;
    }
    args.unknown();
  }
  if (se3) cfg.align_scale = false;
  if (gt_arg.empty()) fail("expected TRAJ and GT (see --help)");
  if (!alignment_gt.empty() && alignment_from.empty()) fail("--alignment-gt needs --alignment-from");
  try {
    cfg.validate();
  } catch (const std::exception& e) {
    fail(e.what());
  }

  try {
    const ve::Trajectory est = ve::readTrajectory(traj_path);
    if (est.empty()) fail(traj_path + ": empty trajectory (no poses)");
    // Ground truth as camera poses: EuRoC ground truth is the body (IMU) pose,
    // turned into the camera's with the dataset's own T_BS.
    const std::string forced_body_to_camera = body_to_camera;
    std::string gt_path;
    auto read_ground_truth = [&](const std::string& arg) {
      const std::string path = ve::resolveTrajectoryPath(arg);
      ve::Trajectory gt = ve::readTrajectory(path, gt_options);
      if (gt.empty()) fail(path + ": empty ground truth (no poses)");
      std::string yaml = forced_body_to_camera;
      const std::string euroc_suffix = "state_groundtruth_estimate0/data.csv";
      if (yaml.empty() && path.size() > euroc_suffix.size() &&
          path.compare(path.size() - euroc_suffix.size(), euroc_suffix.size(), euroc_suffix) == 0) {
        const std::string candidate = path.substr(0, path.size() - euroc_suffix.size()) + "cam0/sensor.yaml";
        if (std::ifstream(candidate).good()) yaml = candidate;
      }
      if (!yaml.empty()) gt = ve::applyBodyToCamera(gt, ve::loadBodyToCamera(yaml));
      body_to_camera = yaml;
      gt_path = path;
      return gt;
    };
    if (!alignment_from.empty()) {
      const ve::Trajectory est0 = ve::readTrajectory(alignment_from);
      if (est0.empty()) fail(alignment_from + ": empty trajectory (no poses)");
      const ve::Trajectory gt0 = read_ground_truth(alignment_gt.empty() ? gt_arg : alignment_gt);
      ve::EvalConfig cfg0 = cfg;
      cfg0.frames = 0;
      const ve::EvalResult r0 = ve::evaluate(est0, gt0, cfg0);
      cfg.given_alignment = r0.alignment;
      if (!json_only) {
        std::cout << "alignment fitted on " << alignment_from << " against " << gt_path << " (ATE "
                  << 100.0 * r0.ate.rmse << " cm over " << r0.matched << " poses), applied unchanged\n";
      }
    }
    const ve::Trajectory gt = read_ground_truth(gt_arg);
    const ve::EvalResult r = ve::evaluate(est, gt, cfg);
    if (!aligned_out.empty()) ve::writeTum(aligned_out, r.aligned);
    if (!gt_out.empty()) ve::writeTum(gt_out, gt);
    if (!errors_out.empty()) {
      FILE* f = std::fopen(errors_out.c_str(), "w");
      if (!f) fail(errors_out + ": cannot write");
      std::fprintf(f, "# t_estimate[s] position_error[m]\n");
      for (std::size_t k = 0; k < r.pairs.size(); ++k)
        std::fprintf(f, "%.9f %.9f\n", est[r.pairs[k].first].t, r.errors[k]);
      std::fclose(f);
    }
    if (!json_only) {
      std::cout << "estimate: " << traj_path << " (" << ve::toString(ve::detectTrajectoryFormat(traj_path))
                << ")\nground truth: " << gt_path << " ("
                << ve::toString(gt_options.format == ve::TrajectoryFormat::kAuto ? ve::detectTrajectoryFormat(gt_path)
                                                                                 : gt_options.format)
                << (body_to_camera.empty() ? "" : ", body -> camera with " + body_to_camera) << ")\n"
                << ve::summary(r, cfg);
      if (!aligned_out.empty()) std::cout << "aligned estimate written to " << aligned_out << "\n";
    }
    std::cout << ve::toJson(r, cfg) << '\n';
  } catch (const std::exception& e) {
    fail(e.what());
  }
  return 0;
}
