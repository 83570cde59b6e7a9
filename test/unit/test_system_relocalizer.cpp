// The relocalizer against a known map: keyframes of the project's room render
// at full resolution (752x480, EuRoC lens) with their true 3D points, and lost
// frames seen from elsewhere. Checks that it finds the camera 1 m away to 1 cm,
// finds an upside-down camera, and refuses a view it has never indexed.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/frame_context.h"
#include "vitamin_e/pipeline/relocalizer.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/scene.h"
#include "vitamin_e/synth/sequence.h"
#include "vitamin_e/tracking/dense_tracker.h"

namespace ve = vitamin_e;
using ve::pipeline::FrameContext;
using ve::pipeline::Relocalization;
using ve::pipeline::Relocalizer;
using ve::pipeline::RelocalizerConfig;

namespace {

// The camera at (x, y, 1.4) looking along yaw (about the world's z, up), pitched down a little.
Eigen::Isometry3d cameraAt(double x, double y, double yaw, double roll = 0.0) {
  const double pitch = -0.1;
  const Eigen::Vector3d forward(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), std::sin(pitch));
  const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0.0);
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  T_w_c.linear() << right, forward.cross(right), forward;  // optical: x right, y down, z forward
  T_w_c.translation() = Eigen::Vector3d(x, y, 1.4);
  T_w_c.linear() = T_w_c.linear() * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T_w_c;
}

struct RoomWorld {
  ve::camera::Camera camera = ve::synth::makeSequenceCamera(752, 480, true);
  ve::synth::Scene scene;
  std::unique_ptr<ve::synth::Renderer> renderer;
  RoomWorld() {
    ve::synth::SceneConfig config;
    config.seed = 21;
    config.num_boxes = 4;
    scene = ve::synth::Scene::makeRoom(config, {Eigen::Vector3d(0, 0, 1.4), Eigen::Vector3d(1.5, 0, 1.4)});
    renderer = std::make_unique<ve::synth::Renderer>(scene, camera);
  }
  cv::Mat render(const Eigen::Isometry3d& T_w_c, std::uint64_t seed, cv::Mat* depth = nullptr) const {
    ve::synth::RenderOptions options;
    options.noise_sigma = 1.0;
    options.noise_seed = seed;
    return renderer->render(T_w_c, options, depth);
  }
  // The tracks of one image (a fresh tracker: every extremum is a new track).
  FrameContext detect(const cv::Mat& image, std::uint64_t frame_index) const {
    ve::tracking::DenseTracker tracker;
    const ve::tracking::TrackerFrame tf = tracker.track(image, 0.0);
    FrameContext frame;
    frame.frame_index = frame_index;
    frame.image = image;
    for (const auto& p : tf.points) {
      ve::pipeline::FrameTrack t;
      t.id = frame_index * 100000 + p.id;  // distinct ids per image
      t.uv = p.uv;
      t.intensity = p.intensity;
      t.polarity = p.curvature >= 0.f ? 1 : -1;
      if (!camera.unprojectNormalized(p.uv.cast<double>(), &t.xy)) continue;
      frame.tracks.push_back(t);
    }
    return frame;
  }
};

const RoomWorld& world() {
  static const RoomWorld w;
  return w;
}

// A keyframe at T_w_c whose tracks are landmarks at their true 3D positions
// (ray-cast depth), indexed by the relocalizer.
void indexKeyframe(const Eigen::Isometry3d& T_w_c, std::uint64_t frame_index, ve::map::Map* map,
                   Relocalizer* relocalizer) {
  const RoomWorld& w = world();
  cv::Mat depth;
  const cv::Mat image = w.render(T_w_c, frame_index, &depth);
  FrameContext frame = w.detect(image, frame_index);
  std::size_t mapped = 0;
  for (const auto& t : frame.tracks) {
    const int u = static_cast<int>(std::lround(t.uv.x())), v = static_cast<int>(std::lround(t.uv.y()));
    const float z = depth.at<float>(v, u);
    if (!(z > 0.f)) continue;
    ve::map::NewLandmark l;
    l.id = t.id;
    l.p_w = T_w_c * (Eigen::Vector3d(t.xy.homogeneous()) * static_cast<double>(z));
    l.polarity = t.polarity;
    map->addLandmark(l);
    ++mapped;
  }
  ASSERT_GT(mapped, 1000u);
  relocalizer->addKeyframe(image, frame, *map, T_w_c);
}

void expectNear(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth, double max_m, double max_deg) {
  EXPECT_LT((estimate.translation() - truth.translation()).norm(), max_m)
      << "estimate " << estimate.translation().transpose() << " truth " << truth.translation().transpose();
  const double angle = Eigen::AngleAxisd(estimate.linear().transpose() * truth.linear()).angle();
  EXPECT_LT(angle * 180.0 / M_PI, max_deg);
}

ve::geometry::PnpConfig pnpConfig() {
  ve::geometry::PnpConfig pnp;
  pnp.focal_px = world().camera.fx();
  return pnp;
}

}  // namespace

TEST(Relocalizer, FindsACameraOneMetreAwayToOneCentimetre) {
  ve::map::Map map;
  Relocalizer relocalizer(RelocalizerConfig{}, world().camera, pnpConfig());
  indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map, &relocalizer);
  indexKeyframe(cameraAt(0.0, 0.0, M_PI), 2, &map, &relocalizer);  // the opposite wall: a wrong candidate
  ASSERT_EQ(relocalizer.size(), 2u);
  // 1 m to the side of the first keyframe, turned 10 degrees toward where it looked.
  const Eigen::Isometry3d T_w_lost = cameraAt(0.2, -0.98, 0.17);
  const FrameContext lost = world().detect(world().render(T_w_lost, 99), 3);
  const Relocalization r = relocalizer.relocalize(lost.image, lost, map);
  ASSERT_TRUE(r.ok) << r.why;
  EXPECT_EQ(r.keyframe, 1u);
  EXPECT_EQ(r.quarter_turns, 0);
  EXPECT_GE(r.inliers, 100);
  expectNear(r.T_w_c, T_w_lost, 0.01, 0.2);
}

// The candidates are tried on OpenCV's worker threads and chosen in their order:
// one thread or several give the same answer to the bit, found or not.
TEST(Relocalizer, TheAnswerDoesNotDependOnTheThreads) {
  ve::map::Map map;
  Relocalizer relocalizer(RelocalizerConfig{}, world().camera, pnpConfig());
  indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map, &relocalizer);
  indexKeyframe(cameraAt(0.0, 0.0, M_PI), 2, &map, &relocalizer);
  indexKeyframe(cameraAt(0.4, 0.3, 0.5), 3, &map, &relocalizer);
  const FrameContext found = world().detect(world().render(cameraAt(0.2, -0.98, 0.17), 99), 3);
  const FrameContext unseen = world().detect(world().render(cameraAt(0.0, 0.0, M_PI / 2), 97), 3);
  const int threads = cv::getNumThreads();
  for (const FrameContext* lost : {&found, &unseen}) {
    cv::setNumThreads(1);
    const Relocalization one = relocalizer.relocalize(lost->image, *lost, map);
    cv::setNumThreads(4);
    const Relocalization many = relocalizer.relocalize(lost->image, *lost, map);
    cv::setNumThreads(threads);
    EXPECT_EQ(one.ok, many.ok);
    EXPECT_EQ(one.why, many.why);
    EXPECT_EQ(one.keyframe, many.keyframe);
    EXPECT_EQ(one.matches, many.matches);
    EXPECT_EQ(one.inliers, many.inliers);
    EXPECT_TRUE(one.T_w_c.matrix() == many.T_w_c.matrix());
  }
  EXPECT_TRUE(relocalizer.relocalize(found.image, found, map).ok);
}

TEST(Relocalizer, FindsAnUpsideDownCamera) {
  ve::map::Map map;
  Relocalizer relocalizer(RelocalizerConfig{}, world().camera, pnpConfig());
  indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map, &relocalizer);
  const Eigen::Isometry3d T_w_lost = cameraAt(0.3, -0.4, 0.1, M_PI);  // rolled 180 degrees
  const FrameContext lost = world().detect(world().render(T_w_lost, 98), 3);
  const Relocalization r = relocalizer.relocalize(lost.image, lost, map);
  ASSERT_TRUE(r.ok) << r.why;
  EXPECT_EQ(r.quarter_turns, 2);
  expectNear(r.T_w_c, T_w_lost, 0.01, 0.2);
  // Without the upside-down search it is not found.
  RelocalizerConfig upright;
  upright.upside_down = false;
  Relocalizer upright_only(upright, world().camera, pnpConfig());
  ve::map::Map map2;
  indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map2, &upright_only);
  EXPECT_FALSE(upright_only.relocalize(lost.image, lost, map2).ok);
}

TEST(Relocalizer, RefusesAViewItHasNeverIndexed) {
  ve::map::Map map;
  Relocalizer relocalizer(RelocalizerConfig{}, world().camera, pnpConfig());
  indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map, &relocalizer);
  // Facing the side wall, which the keyframe did not see.
  const FrameContext lost = world().detect(world().render(cameraAt(0.0, 0.0, M_PI / 2), 97), 3);
  const Relocalization r = relocalizer.relocalize(lost.image, lost, map);
  EXPECT_FALSE(r.ok) << "relocalized against keyframe " << r.keyframe << " with " << r.inliers << " inliers";
  EXPECT_FALSE(r.why.empty());
}

TEST(Relocalizer, PrefersTheLandmarkPositionsOfTheMapOverItsOwnCopy) {
  // The index keeps the positions of a keyframe's points as they were; a point
  // moved since (by BA) is taken from the map: moving the whole map by 0.5 m moves the pose.
  ve::map::Map map;
  Relocalizer relocalizer(RelocalizerConfig{}, world().camera, pnpConfig());
  const Eigen::Isometry3d T_w_kf = cameraAt(0.0, 0.0, 0.0);
  indexKeyframe(T_w_kf, 1, &map, &relocalizer);
  const Eigen::Vector3d shift(0.0, 0.0, 0.5);
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> moved;
  for (const auto& kv : map.landmarks()) moved.emplace_back(kv.first, kv.second.p_w + shift);
  for (const auto& m : moved) map.setLandmarkPosition(m.first, m.second);
  const Eigen::Isometry3d T_w_lost = cameraAt(0.1, -0.5, 0.05);
  const FrameContext lost = world().detect(world().render(T_w_lost, 96), 3);
  const Relocalization r = relocalizer.relocalize(lost.image, lost, map);
  ASSERT_TRUE(r.ok) << r.why;
  Eigen::Isometry3d expected = T_w_lost;
  expected.translation() += shift;
  expectNear(r.T_w_c, expected, 0.01, 0.2);
}

TEST(Relocalizer, AKeyframeRefusedForTooFewPointsDoesNotShiftTheVotesOfTheNextOnes) {
  // Entries are found in the hash tables by serial number: a keyframe that is
  // not indexed (no mapped point) must not use one, or the votes of every later
  // keyframe go to its successor.
  ve::map::Map map;
  Relocalizer relocalizer(RelocalizerConfig{}, world().camera, pnpConfig());
  indexKeyframe(cameraAt(0.0, 0.0, M_PI), 1, &map, &relocalizer);
  const FrameContext no_points = world().detect(world().render(cameraAt(0.0, 0.0, -M_PI / 2), 2), 2);
  relocalizer.addKeyframe(no_points.image, no_points, map, cameraAt(0.0, 0.0, -M_PI / 2));
  ASSERT_EQ(relocalizer.size(), 1u);
  indexKeyframe(cameraAt(0.0, 0.0, 0.0), 3, &map, &relocalizer);
  indexKeyframe(cameraAt(0.0, 0.0, M_PI / 2), 4, &map, &relocalizer);  // the newest: another wall
  const Eigen::Isometry3d T_w_lost = cameraAt(0.2, -0.98, 0.17);
  const FrameContext lost = world().detect(world().render(T_w_lost, 95), 5);
  const Relocalization r = relocalizer.relocalize(lost.image, lost, map);
  ASSERT_TRUE(r.ok) << r.why;
  EXPECT_EQ(r.keyframe, 3u);
  expectNear(r.T_w_c, T_w_lost, 0.01, 0.2);
}

TEST(Relocalizer, ExportedEntriesImportedIntoAnotherRelocalizerFindTheSameCamera) {
  ve::map::Map map;
  Relocalizer relocalizer(RelocalizerConfig{}, world().camera, pnpConfig());
  indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map, &relocalizer);
  indexKeyframe(cameraAt(0.0, 0.0, M_PI), 2, &map, &relocalizer);
  const std::vector<ve::map::IndexedKeyframe> entries = relocalizer.exportEntries();
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_GT(entries[0].points.size(), 500u);
  Relocalizer copy(RelocalizerConfig{}, world().camera, pnpConfig());
  copy.importEntries(entries);
  ASSERT_EQ(copy.size(), 2u);
  const Eigen::Isometry3d T_w_lost = cameraAt(0.2, -0.98, 0.17);
  const FrameContext lost = world().detect(world().render(T_w_lost, 99), 3);
  // An empty map: the positions come from the index alone.
  const Relocalization a = relocalizer.relocalize(lost.image, lost, ve::map::Map());
  const Relocalization b = copy.relocalize(lost.image, lost, ve::map::Map());
  ASSERT_TRUE(a.ok && b.ok) << a.why << " / " << b.why;
  EXPECT_EQ(a.keyframe, b.keyframe);
  EXPECT_EQ(a.matches, b.matches);
  EXPECT_TRUE(a.T_w_c.matrix() == b.T_w_c.matrix());
  // A relocalizer keeping fewer keyframes takes the newest.
  RelocalizerConfig small;
  small.max_keyframes = 1;
  Relocalizer one(small, world().camera, pnpConfig());
  one.importEntries(entries);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one.exportEntries().front().frame_index, 2u);
}

TEST(Relocalizer, ARescaleMovesTheIndexedKeyframesAndPointsWithTheMap) {
  // A map rescaled about a centre (ground.enabled's correction): the index
  // follows, so that a lost camera is found where it is in the rescaled map,
  // also from the index's own positions alone (an empty map).
  ve::map::Map map;
  Relocalizer relocalizer(RelocalizerConfig{}, world().camera, pnpConfig());
  indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map, &relocalizer);
  const std::vector<ve::map::IndexedKeyframe> before = relocalizer.exportEntries();
  const Eigen::Vector3d centre(0.5, -0.2, 1.0);
  const double factor = 1.3;
  auto scaled = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return centre + factor * (x - centre); };
  map.rescale(centre, factor);
  relocalizer.rescale(centre, factor);

  const std::vector<ve::map::IndexedKeyframe> after = relocalizer.exportEntries();
  ASSERT_EQ(after.size(), 1u);
  ASSERT_EQ(after[0].points.size(), before[0].points.size());
  EXPECT_LT((after[0].T_w_c.translation() - scaled(before[0].T_w_c.translation())).norm(), 1e-12);
  EXPECT_TRUE(after[0].T_w_c.linear() == before[0].T_w_c.linear()) << "a rescale does not turn a keyframe";
  for (std::size_t i = 0; i < after[0].points.size(); ++i) {
    EXPECT_LT((after[0].points[i].p_w - scaled(before[0].points[i].p_w)).norm(), 1e-12) << "point " << i;
  }

  const Eigen::Isometry3d T_w_lost = cameraAt(0.2, -0.98, 0.17);
  Eigen::Isometry3d expected = T_w_lost;
  expected.translation() = scaled(T_w_lost.translation());
  const FrameContext lost = world().detect(world().render(T_w_lost, 94), 3);
  for (const bool with_map : {true, false}) {
    const Relocalization r = relocalizer.relocalize(lost.image, lost, with_map ? map : ve::map::Map());
    ASSERT_TRUE(r.ok) << r.why;
    expectNear(r.T_w_c, expected, 0.01 * factor, 0.2);
  }
}

// A car's keyframes a metre apart see most of the same points: indexing each of them costs a
// blur and BRIEF per keyframe and fills the index with near copies. A keyframe that still sees
// most of the newest entry's points is left out; one that sees other points is indexed.
TEST(Relocalizer, AKeyframeThatStillSeesMostOfTheNewestEntryIsNotIndexed) {
  for (const double max_shared : {1.0, 0.7}) {
    RelocalizerConfig config;
    config.max_shared_points = max_shared;
    ve::map::Map map;
    Relocalizer relocalizer(config, world().camera, pnpConfig());
    indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map, &relocalizer);
    ASSERT_EQ(relocalizer.size(), 1u);
    // The same view again: the same tracks, so every point of the newest entry.
    const FrameContext again = world().detect(world().render(cameraAt(0.0, 0.0, 0.0), 1), 1);
    const bool indexed = relocalizer.addKeyframe(again.image, again, map, cameraAt(0.0, 0.0, 0.0));
    EXPECT_EQ(indexed, max_shared == 1.0) << max_shared;
    EXPECT_EQ(relocalizer.size(), max_shared == 1.0 ? 2u : 1u) << max_shared;
    // The opposite wall: none of the newest entry's points.
    indexKeyframe(cameraAt(0.0, 0.0, M_PI), 2, &map, &relocalizer);
    EXPECT_EQ(relocalizer.size(), max_shared == 1.0 ? 3u : 2u) << max_shared;
  }
}

// The share is of the newest entry's points (at most points_per_keyframe of a frame's mapped
// ones), not of the keyframe's own: the same view with every 10th / every 2nd track gone still
// sees about 90 % / 50 % of the entry, and only the second is new enough to be indexed at 0.7.
TEST(Relocalizer, TheShareIsOfTheNewestEntrysPoints) {
  for (const int keep_of_ten : {9, 5}) {
    RelocalizerConfig config;
    config.max_shared_points = 0.7;
    ve::map::Map map;
    Relocalizer relocalizer(config, world().camera, pnpConfig());
    indexKeyframe(cameraAt(0.0, 0.0, 0.0), 1, &map, &relocalizer);
    ASSERT_EQ(relocalizer.size(), 1u);
    FrameContext part = world().detect(world().render(cameraAt(0.0, 0.0, 0.0), 1), 1);
    ASSERT_GT(part.tracks.size(), static_cast<std::size_t>(config.points_per_keyframe));  // the entry holds a part
    std::vector<ve::pipeline::FrameTrack> kept;
    for (std::size_t i = 0; i < part.tracks.size(); ++i) {
      if (static_cast<int>(i % 10) < keep_of_ten) kept.push_back(part.tracks[i]);
    }
    part.tracks = kept;
    EXPECT_EQ(relocalizer.addKeyframe(part.image, part, map, cameraAt(0.0, 0.0, 0.0)), keep_of_ten == 5) << keep_of_ten;
  }
}

TEST(Relocalizer, RejectsBadConfig) {
  RelocalizerConfig c;
  c.patch_size = 8;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = RelocalizerConfig{};
  c.max_frames = 0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = RelocalizerConfig{};
  c.ratio = 0.0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = RelocalizerConfig{};
  c.max_shared_points = 1.5;
  EXPECT_THROW(c.validate(), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
