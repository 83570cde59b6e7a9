// What pipeline::DenseInput relies on, on a SLAM run whose map is rescaled by the
// ground-scale corrections (a driving clip of the street scene, config/kitti.yaml,
// corrections forced on every keyframe): each correction scales the map about the
// camera centre of its frame (FrameResult::T_w_c) before that frame's points are
// read, and DenseInput composes them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "driving_clip.h"
#include "vitamin_e/pipeline/dense_input.h"

namespace ve = vitamin_e;
using Eigen::Vector3d;

namespace {

struct CorrectedRun {
  ve::camera::Camera camera;
  ve::test::DrivingRun run;
};

// The turn at walking speed, its first 70 frames, with a correction at every keyframe.
const CorrectedRun& correctedRun() {
  static const CorrectedRun run = [] {
    ve::test::ClipSpec spec;
    spec.path = "turn";
    spec.frames = 70;
    ve::pipeline::SystemConfig config = ve::test::drivingConfig();
    config.ground.tolerance = 0.0;
    config.ground.gain = 1.0;
    config.ground.window = 1;
    const ve::test::DrivingClip clip = ve::test::renderDrivingClip(spec);
    return CorrectedRun{clip.camera, ve::test::runDrivingClip(clip, config)};
  }();
  return run;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

// Frame k corrected by f: its points are the previous frame's scaled by f about
// its camera centre (up to the BA's own small moves).
TEST(SystemDense, AScaleCorrectionScalesTheMapAboutTheFrameCentreBeforeItsPoints) {
  const auto& results = correctedRun().run.results;
  int checked = 0;
  for (std::size_t k = 1; k < results.size(); ++k) {
    const double f = results[k].diagnostics.scale_correction;
    if (f == 1.0 || !results[k].pose_valid || !results[k - 1].pose_valid) continue;
    std::map<std::uint64_t, Vector3d> before;
    for (const auto& p : results[k - 1].points)
      if (p.has_position) before[p.track_id] = p.p_w;
    const Vector3d c = results[k].T_w_c.translation();
    std::vector<double> scaled_error, moved;
    for (const auto& p : results[k].points) {
      const auto it = before.find(p.track_id);
      if (!p.has_position || it == before.end()) continue;
      scaled_error.push_back((p.p_w - (c + f * (it->second - c))).norm());
      moved.push_back((p.p_w - it->second).norm());
    }
    if (moved.size() < 50 || std::abs(f - 1.0) < 0.01) continue;
    ++checked;
    // Measured: at most 0.22 of the move for a 1 % correction (the keyframe's BA moves the points too).
    EXPECT_LT(median(scaled_error), 0.35 * median(moved))
        << "frame " << k << " scaled by " << f << ": its points are not the previous ones scaled about its centre";
  }
  EXPECT_GE(checked, 3) << "too few corrections of 1 % or more to check";
}

// DenseInput: each correction composed onto the scaling so far, the same in any
// rigid frame (the ROS nodelet works in the map frame, T_map_w * the core's world),
// a frame without a pose keeping the scaling, the points those of framePointsInCamera.
TEST(SystemDense, DenseInputComposesTheCorrectionsInAnyRigidFrame) {
  const auto& results = correctedRun().run.results;
  Eigen::Isometry3d T_map_w = Eigen::Isometry3d::Identity();
  T_map_w.linear() = Eigen::AngleAxisd(0.7, Vector3d(0.2, -1.0, 0.4).normalized()).toRotationMatrix();
  T_map_w.translation() = Vector3d(3.0, -1.0, 0.5);
  ve::pipeline::DenseInput world, map, no_points;
  ve::fusion::MapScaling previous;
  int corrections = 0;
  const std::vector<Vector3d> probes = {Vector3d(0.0, 0.0, 0.0), Vector3d(1.0, -2.0, 5.0), Vector3d(-3.0, 0.5, 2.0)};
  for (const auto& r : results) {
    ve::pipeline::FrameResult in_map = r;
    in_map.T_w_c = T_map_w * r.T_w_c;
    for (auto& p : in_map.points) p.p_w = T_map_w * p.p_w;
    const ve::fusion::DenseFrame a = world.next(r), b = map.next(in_map);
    const double f = r.diagnostics.scale_correction;
    if (f != 1.0) {
      ++corrections;
      EXPECT_NEAR(a.map_scaling.scale, previous.scale * f, 1e-12);
      const Vector3d centre = r.T_w_c.translation();
      EXPECT_LT(
          (a.map_scaling.apply(Vector3d::Zero()) - (centre + f * (previous.apply(Vector3d::Zero()) - centre))).norm(),
          1e-9);
    } else {
      EXPECT_EQ(a.map_scaling, previous);
    }
    previous = a.map_scaling;
    for (const Vector3d& q : probes) {
      EXPECT_LT((b.map_scaling.apply(T_map_w * q) - T_map_w * a.map_scaling.apply(q)).norm(), 1e-9);
    }
    std::vector<std::uint64_t> ids;
    std::vector<Vector3d> p_c;
    ve::pipeline::framePointsInCamera(r, &ids, &p_c);
    ASSERT_EQ(a.ids, ids);
    ASSERT_EQ(b.ids, ids);
    for (std::size_t i = 0; i < p_c.size(); ++i) {
      EXPECT_EQ(a.p_c[i], p_c[i]);
      EXPECT_LT((b.p_c[i] - p_c[i]).norm(), 1e-9);
    }
    // Without the points (nobody listens): the scaling all the same.
    const ve::fusion::DenseFrame c = no_points.next(r, false);
    EXPECT_TRUE(c.p_c.empty());
    EXPECT_EQ(c.map_scaling, a.map_scaling);
  }
  EXPECT_GE(corrections, 10);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
