// pipeline::predictTrackPositions: the map points of the last frame seen from the motion
// model's pose at the new frame's time, the tracker's priors. A point behind the camera or
// outside the image has none; after a gap of dropped frames the pose is that much farther on.
// Each prior says how much larger the point looks than in the last frame.
#include <gtest/gtest.h>

#include "vitamin_e/pipeline/track_priors.h"

namespace vp = vitamin_e::pipeline;

namespace {

vp::TrackPriorSource drivingForward() {
  // Two poses 0.1 s apart, the camera moving 1 m along its optical axis (z).
  vp::TrackPriorSource source;
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  source.motion.update(T_w_c, 0.0);
  T_w_c.translation() = Eigen::Vector3d(0.0, 0.0, 1.0);
  source.motion.update(T_w_c, 0.1);
  source.p_w_by_track = {{3, {1.0, 0.5, 11.0}},      // ahead
                         {7, {0.0, 0.0, -4.0}},      // behind the camera
                         {9, {30.0, 0.0, 3.0}},      // ahead but far outside the image
                         {12, {-2.0, -1.0, 21.0}}};  // ahead
  return source;
}

}  // namespace

TEST(TrackPriors, MapPointsSeenFromThePredictedPose) {
  const vitamin_e::camera::Camera camera(640, 480, 500.0, 500.0, 320.0, 240.0);
  const vp::TrackPriorSource source = drivingForward();
  // Next frame, 0.1 s later: the camera is at z = 2.
  const auto priors = vp::predictTrackPositions(source, camera, 0.2);
  ASSERT_EQ(priors.size(), 2u);
  EXPECT_EQ(priors[0].id, 3u);
  EXPECT_EQ(priors[1].id, 12u);
  EXPECT_NEAR(priors[0].uv.x(), 320.0 + 500.0 * 1.0 / 9.0, 1e-3);
  EXPECT_NEAR(priors[0].uv.y(), 240.0 + 500.0 * 0.5 / 9.0, 1e-3);
  EXPECT_NEAR(priors[1].uv.x(), 320.0 - 500.0 * 2.0 / 19.0, 1e-3);
  // Each point's image grows as its depth shrinks: 10 m in the last frame, 9 m now.
  EXPECT_NEAR(priors[0].scale, 10.0 / 9.0, 1e-5);
  EXPECT_NEAR(priors[1].scale, 20.0 / 19.0, 1e-5);
  // Two frames dropped: the camera is at z = 4 when the frame arrives.
  const auto later = vp::predictTrackPositions(source, camera, 0.4);
  ASSERT_EQ(later.size(), 2u);
  EXPECT_NEAR(later[0].uv.x(), 320.0 + 500.0 * 1.0 / 7.0, 1e-3);
  EXPECT_NEAR(later[0].scale, 10.0 / 7.0, 1e-5);
}

TEST(TrackPriors, NoneWithoutAMotion) {
  const vitamin_e::camera::Camera camera(640, 480, 500.0, 500.0, 320.0, 240.0);
  vp::TrackPriorSource source = drivingForward();
  source.motion.invalidate();
  EXPECT_TRUE(vp::predictTrackPositions(source, camera, 0.2).empty());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
