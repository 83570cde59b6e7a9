// pipeline::applyMapUpdate: the one writer of the stages' changes to the map (poses, positions,
// reassociations, offenders), and what it reports back.
#include <gtest/gtest.h>

#include "vitamin_e/pipeline/map_update.h"

namespace ve = vitamin_e;
using ve::pipeline::applyMapUpdate;
using ve::pipeline::MapUpdate;
using ve::pipeline::OffencePolicy;
using ve::pipeline::Reassociation;

namespace {

// Two keyframes (frames 0 and 1) seeing tracks 1..4; landmarks 1..4.
ve::map::Map makeMap(const ve::map::MapConfig& config = {}) {
  ve::map::Map map(config);
  for (std::uint64_t f = 0; f < 2; ++f) {
    ve::map::Keyframe kf;
    kf.frame_index = f;
    kf.T_w_c.translation() = Eigen::Vector3d(0.1 * static_cast<double>(f), 0.0, 0.0);
    for (std::uint64_t id = 1; id <= 4; ++id)
      kf.observations.emplace(id, Eigen::Vector2d(0.01 * static_cast<double>(id), 0.0));
    map.addKeyframe(kf);
  }
  for (std::uint64_t id = 1; id <= 4; ++id) {
    ve::map::NewLandmark l;
    l.id = id;
    l.p_w = Eigen::Vector3d(0.0, 0.0, 1.0 + static_cast<double>(id));
    l.seen_frame = 1;
    map.addLandmark(l);
  }
  return map;
}

}  // namespace

TEST(MapUpdate, MovesKeyframesAndPoints) {
  ve::map::Map map = makeMap();
  MapUpdate u;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(5.0, 0.0, 0.0);
  u.keyframe_poses.emplace_back(1, T);
  u.positions.emplace_back(2, Eigen::Vector3d(1.0, 2.0, 3.0));
  u.positions.emplace_back(99, Eigen::Vector3d(1.0, 2.0, 3.0));  // gone meanwhile: ignored
  const auto applied = applyMapUpdate(u, OffencePolicy{}, &map);
  EXPECT_TRUE(applied.removed.empty());
  EXPECT_EQ(applied.reassociated, 0);
  EXPECT_EQ(map.keyframes()[1].T_w_c.translation().x(), 5.0);
  EXPECT_EQ(map.keyframes()[0].T_w_c.translation().x(), 0.0);
  EXPECT_EQ(map.landmark(2)->p_w, Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_EQ(map.landmark(3)->p_w, Eigen::Vector3d(0.0, 0.0, 4.0));
}

TEST(MapUpdate, OffendersLeaveAtTheLimitAndTheirIdsComeBack) {
  ve::map::Map map = makeMap();
  OffencePolicy policy;
  policy.max_outlier_count = 2;
  MapUpdate u;
  u.offenders = {1, 3};
  EXPECT_TRUE(applyMapUpdate(u, policy, &map).removed.empty()) << "one offence each: below the limit";
  u.offenders = {3, 4};
  const auto applied = applyMapUpdate(u, policy, &map);
  EXPECT_EQ(applied.removed, std::vector<std::uint64_t>{3});
  EXPECT_EQ(map.landmark(3), nullptr);
  EXPECT_NE(map.landmark(1), nullptr);
  EXPECT_NE(map.landmark(4), nullptr);
  EXPECT_EQ(map.dormant().size(), 0u) << "removed, not retired";
}

TEST(MapUpdate, LocalizationOnlyDetachesOffendersInsteadOfRemovingThem) {
  ve::map::MapConfig config;
  config.min_observations_to_archive = 1;
  ve::map::Map map = makeMap(config);
  OffencePolicy policy;
  policy.max_outlier_count = 1;
  policy.localization_only = true;
  MapUpdate u;
  u.offenders = {2};
  const auto applied = applyMapUpdate(u, policy, &map);
  EXPECT_EQ(applied.removed, std::vector<std::uint64_t>{2});
  EXPECT_EQ(map.landmark(2), nullptr);
  ASSERT_EQ(map.dormant().size(), 1u) << "the point is kept as a dormant landmark";
  EXPECT_EQ(map.dormant()[0].id, 2u);
}

TEST(MapUpdate, ReassociationsCountWhatTheMapAccepted) {
  ve::map::Map map = makeMap();
  MapUpdate u;
  Reassociation to_new;  // landmark 1 taken over by the new track 7
  to_new.track_id = 7;
  to_new.landmark_id = 1;
  to_new.frame_index = 2;
  Reassociation clash = to_new;  // track 2 is a landmark already: refused
  clash.track_id = 2;
  clash.landmark_id = 3;
  u.reassociations = {to_new, clash};
  const auto applied = applyMapUpdate(u, OffencePolicy{}, &map);
  EXPECT_EQ(applied.reassociated, 1);
  EXPECT_EQ(map.landmark(1), nullptr);
  ASSERT_NE(map.landmark(7), nullptr);
  EXPECT_EQ(map.landmark(7)->last_seen_frame, 2u);
  EXPECT_NE(map.landmark(3), nullptr);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
