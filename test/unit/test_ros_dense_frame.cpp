// The offline runner and the ROS nodelets go through one dense stage: a SLAM run
// whose map is rescaled by ground-scale corrections, fused (a) as vitamin_e_run
// does (pipeline::DenseInput -> fusion::DenseMapper) and (b) as the nodelets do
// (DenseInput -> toTrackedFrameMsg in TrackingNodelet -> serialized, as between
// two processes -> fromTrackedFrameMsg in TsdfMeshingNodelet -> DenseMapper),
// gives the same TSDF mesh, bit for bit. Malformed messages are refused with a reason.
#include <gtest/gtest.h>

#include <ros/serialization.h>

#include "driving_clip.h"
#include "vitamin_e/fusion/dense_mapper.h"
#include "vitamin_e/pipeline/dense_input.h"
#include "vitamin_e/ros/dense_frame_msg.h"

namespace ve = vitamin_e;
using vitamin_e_ros::fromTrackedFrameMsg;
using vitamin_e_ros::toTrackedFrameMsg;

namespace {

// The message as the meshing node of another process receives it.
vitamin_e::TrackedFrame throughTheWire(const vitamin_e::TrackedFrame& msg) {
  namespace ser = ros::serialization;
  const std::uint32_t size = ser::serializationLength(msg);
  std::vector<std::uint8_t> buffer(size);
  ser::OStream out(buffer.data(), size);
  ser::serialize(out, msg);
  vitamin_e::TrackedFrame back;
  ser::IStream in(buffer.data(), size);
  ser::deserialize(in, back);
  return back;
}

}  // namespace

TEST(RosDenseFrame, RunnerAndNodeletsFuseTheSameMesh) {
  ve::test::ClipSpec spec;
  spec.path = "turn";
  spec.frames = 60;
  const ve::test::DrivingClip clip = ve::test::renderDrivingClip(spec);
  ve::pipeline::SystemConfig config = ve::test::drivingConfig();
  config.ground.tolerance = 0.0;  // a correction at every keyframe
  config.ground.gain = 1.0;
  config.ground.window = 1;
  const ve::test::DrivingRun run = ve::test::runDrivingClip(clip, config);

  ve::fusion::DenseMapperConfig dense = config.dense;
  dense.integrator.asynchronous = false;
  const ve::meshing::PinholeImage image = ve::meshing::pinholeImageOf(clip.camera);
  ve::fusion::DenseMapper runner(dense, image), nodelet(dense, image);
  ve::pipeline::DenseInput runner_input, tracking_input;
  int corrections = 0, fused = 0;
  for (const auto& result : run.results) {
    corrections += result.diagnostics.scale_correction != 1.0;
    // (a) vitamin_e_run's handle_result
    runner.addFrame(runner_input.next(result));
    // (b) TrackingNodelet::publishResult / publishFrame, then TsdfMeshingNodelet::frameCallback
    const ve::fusion::DenseFrame sent = tracking_input.next(result, result.pose_valid);
    if (!result.pose_valid) continue;
    vitamin_e::TrackedFrame msg;
    toTrackedFrameMsg(sent, clip.camera, &msg);
    ve::fusion::DenseFrame received;
    ve::meshing::PinholeImage received_image;
    std::string why;
    ASSERT_TRUE(fromTrackedFrameMsg(throughTheWire(msg), &received, &received_image, &why)) << why;
    EXPECT_TRUE(received_image == image);
    fused += nodelet.addFrame(received).integrated;
  }
  ASSERT_GE(corrections, 5) << "the run should rescale its map";
  ASSERT_GT(fused, 20);
  EXPECT_EQ(nodelet.scaling(), runner.scaling());
  EXPECT_FALSE(runner.scaling().isIdentity());
  const ve::fusion::TriangleMesh a = runner.extractMesh(), b = nodelet.extractMesh();
  ASSERT_GT(a.faces.size(), 1000u);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.faces.size(), b.faces.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i) ASSERT_EQ(a.vertices[i], b.vertices[i]) << "vertex " << i;
  for (std::size_t i = 0; i < a.faces.size(); ++i) ASSERT_EQ(a.faces[i], b.faces[i]) << "face " << i;
}

TEST(RosDenseFrame, MalformedMessagesAreRefusedWithAReason) {
  ve::fusion::DenseFrame frame;
  frame.ids = {1, 2};
  frame.p_c = {{0.0, 0.0, 1.0}, {0.1, 0.0, 1.2}};
  frame.map_scaling = ve::fusion::MapScaling::about({1.0, 2.0, 3.0}, 1.05);
  const ve::camera::Camera camera(640, 480, 400.0, 400.0, 320.0, 240.0);
  vitamin_e::TrackedFrame msg;
  toTrackedFrameMsg(frame, camera, &msg);
  ve::fusion::DenseFrame back;
  ve::meshing::PinholeImage image;
  std::string why;
  ASSERT_TRUE(fromTrackedFrameMsg(msg, &back, &image, &why)) << why;
  EXPECT_EQ(back.map_scaling, frame.map_scaling);
  EXPECT_EQ(back.ids, frame.ids);
  auto refused = [&](const vitamin_e::TrackedFrame& m, const std::string& reason) {
    std::string error;
    EXPECT_FALSE(fromTrackedFrameMsg(m, &back, &image, &error));
    EXPECT_NE(error.find(reason), std::string::npos) << error;
  };
  vitamin_e::TrackedFrame m = msg;
  m.ids.pop_back();
  refused(m, "1 ids but 2 points");
  m = msg;
  m.width = 0;
  refused(m, "image size");
  m = msg;
  m.points_c[1].z = std::nan("");
  refused(m, "non-finite point");
  m = msg;
  m.T_w_c.position.x = std::nan("");
  refused(m, "non-finite pose");
  m = msg;
  m.map_scale = 0.0;  // a message of a tracker that does not fill it
  refused(m, "map scale");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
