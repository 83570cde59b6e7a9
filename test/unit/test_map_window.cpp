#include <gtest/gtest.h>

#include "vitamin_e/map/map.h"

using vitamin_e::map::Keyframe;
using vitamin_e::map::Map;
using vitamin_e::map::MapConfig;
using vitamin_e::map::NewLandmark;

namespace {
NewLandmark newLandmark(std::uint64_t id, const Eigen::Vector3d& p_w, std::uint8_t intensity,
                        std::uint64_t seen_frame = 0) {
  NewLandmark l;
  l.id = id;
  l.p_w = p_w;
  l.intensity = intensity;
  l.seen_frame = seen_frame;
  return l;
}

Keyframe keyframeSeeing(std::uint64_t frame, std::uint64_t first_id, std::uint64_t count) {
  Keyframe kf;
  kf.frame_index = frame;
  for (std::uint64_t id = first_id; id < first_id + count; ++id) kf.observations.emplace(id, Eigen::Vector2d(0, 0));
  return kf;
}
}  // namespace

TEST(Map, KeyframeWindowIsBoundedAndUnseenLandmarksAreArchived) {
  MapConfig cfg;
  cfg.max_keyframes = 3;
  cfg.min_observations_to_archive = 1;
  Map map(cfg);
  // Keyframe k sees landmarks [100k, 100k + 50); each landmark is seen by one keyframe.
  for (std::uint64_t k = 0; k < 10; ++k) {
    for (std::uint64_t id = 100 * k; id < 100 * k + 50; ++id) {
      map.addLandmark(newLandmark(id, Eigen::Vector3d(double(id), 0, 1), 7, k));
    }
    map.addKeyframe(keyframeSeeing(k, 100 * k, 50));
    ASSERT_LE(map.keyframes().size(), 3u);
  }
  // Only the landmarks of the last three keyframes stay active.
  EXPECT_EQ(map.landmarks().size(), 150u);
  EXPECT_EQ(map.archive().size(), 350u);
  EXPECT_EQ(map.allPoints().size(), 500u);
  EXPECT_NE(map.landmark(949), nullptr);
  EXPECT_EQ(map.landmark(50), nullptr);
}

TEST(Map, ArchiveKeepsOnePointPerVoxelAndSkipsPoorlyObserved) {
  MapConfig cfg;
  cfg.max_keyframes = 2;
  cfg.archive_voxel_m = 1.0;
  cfg.min_observations_to_archive = 2;
  Map map(cfg);
  for (std::uint64_t id = 0; id < 20; ++id) {
    NewLandmark l = newLandmark(id, Eigen::Vector3d(0.1 * double(id % 5), 0.2, 0.3), 1);
    l.prior_observations = id < 10 ? 2 : 0;  // keyframe 5 adds one: the last ten stay poorly observed
    map.addLandmark(l);
  }
  map.addKeyframe(keyframeSeeing(5, 0, 20));
  map.addKeyframe(keyframeSeeing(6, 1000, 1));
  map.addKeyframe(keyframeSeeing(7, 1000, 1));  // retires keyframe 5: all 20 landmarks unobserved
  EXPECT_TRUE(map.landmarks().empty());
  EXPECT_EQ(map.archive().size(), 1u);  // all well-observed ones fall in one 1 m voxel
}

TEST(Map, LandmarkStillTrackedIsRetiredOnceNoLongerSeen) {
  MapConfig cfg;
  cfg.max_keyframes = 2;
  cfg.min_observations_to_archive = 1;
  Map map(cfg);
  map.addKeyframe(keyframeSeeing(0, 7, 1));
  const auto& l = map.addLandmark(newLandmark(7, Eigen::Vector3d(1, 2, 3), 1));
  ASSERT_EQ(l.observations.size(), 1u);
  map.markSeen(7, 10);  // the track lives on without new keyframes seeing it
  map.addKeyframe(keyframeSeeing(5, 100, 1));
  map.addKeyframe(keyframeSeeing(8, 100, 1));   // retires keyframe 0: landmark 7 has no observation left
  ASSERT_NE(map.landmark(7), nullptr);          // still seen at frame 10 > oldest keyframe 5
  map.addKeyframe(keyframeSeeing(12, 100, 1));  // oldest is now 8 < 10: still seen
  ASSERT_NE(map.landmark(7), nullptr);
  map.addKeyframe(keyframeSeeing(20, 100, 1));  // oldest is 12 > 10: retired to the archive
  EXPECT_EQ(map.landmark(7), nullptr);
  EXPECT_EQ(map.archive().size(), 1u);
}

TEST(Map, ArchiveStaysUnderItsCapAndKeepsEveryPlaceExplored) {
  MapConfig cfg;
  cfg.max_keyframes = 2;
  cfg.min_observations_to_archive = 1;
  cfg.max_archive_points = 1000;
  Map map(cfg);
  // A camera sweeping along x over 2,000 keyframes, each retiring 50 points
  // spread over a 1 x 1 patch of a wall at x = k / 10: 100,000 points in all.
  std::uint64_t id = 0;
  for (std::uint64_t k = 0; k < 2000; ++k) {
    for (int i = 0; i < 50; ++i, ++id) {
      const double u = double((id * 7919) % 1000) / 1000.0, v = double((id * 104729) % 997) / 997.0;
      map.addLandmark(newLandmark(id, Eigen::Vector3d(0.1 * double(k) + u, v, 3.0), 1, k));
    }
    map.addKeyframe(keyframeSeeing(k, id - 50, 50));
    ASSERT_LE(map.archive().size(), 1000u) << "keyframe " << k;
  }
  EXPECT_GT(map.archiveVoxel(), 0.0);
  EXPECT_GT(map.archive().size(), 200u);  // thinned to half the cap at most, then refilled
  // The first and the last stretch of the wall both keep points.
  int first = 0, last = 0;
  for (const auto& a : map.archive()) {
    first += a.p_w.x() < 1.0;
    last += a.p_w.x() > 198.0;
  }
  EXPECT_GT(first, 0);
  EXPECT_GT(last, 0);
}

TEST(Map, RetiredLandmarksStayDormantUpToTheirCapAndCanBeRevived) {
  MapConfig cfg;
  cfg.max_keyframes = 2;
  cfg.min_observations_to_archive = 1;
  cfg.max_dormant_landmarks = 30;
  Map map(cfg);
  for (std::uint64_t k = 0; k < 6; ++k) {
    for (std::uint64_t id = 100 * k; id < 100 * k + 20; ++id) {
      NewLandmark l = newLandmark(id, Eigen::Vector3d(double(id), 0, 1), 9);
      l.polarity = -1;
      l.prior_observations = 1;
      map.addLandmark(l);
    }
    map.addKeyframe(keyframeSeeing(k, 100 * k, 20));
  }
  // Keyframes 0-3 retired 80 landmarks; the newest 30 are dormant: all 20 of
  // keyframe 3 and 10 of keyframe 2 (in no particular order within a keyframe).
  ASSERT_EQ(map.dormant().size(), 30u);
  int from_kf3 = 0;
  for (const auto& d : map.dormant()) {
    EXPECT_TRUE(d.id >= 200 && d.id < 320 && (d.id % 100) < 20) << d.id;
    from_kf3 += d.id >= 300 ? 1 : 0;
    EXPECT_EQ(d.polarity, -1);
    EXPECT_EQ(d.p_w.x(), double(d.id));
  }
  EXPECT_EQ(from_kf3, 20);
  // Revived under a new track id: active again, flagged, with its old position.
  const double x = map.dormant().back().p_w.x();
  ASSERT_TRUE(map.reviveDormant(29, 7777, 5));
  const auto* l = map.landmark(7777);
  ASSERT_NE(l, nullptr);
  EXPECT_TRUE(l->revived);
  EXPECT_EQ(l->p_w.x(), x);
  EXPECT_EQ(l->last_seen_frame, 5u);
  EXPECT_TRUE(map.dormant().back().revived);
  EXPECT_FALSE(map.reviveDormant(29, 7778, 5));  // already taken
  EXPECT_FALSE(map.reviveDormant(28, 500, 5));   // the id is an active landmark
  // Retired again, it goes back to the dormant points but not twice into the archive.
  const std::size_t archived = map.archive().size();
  map.addKeyframe(keyframeSeeing(6, 7777, 1));
  map.addKeyframe(keyframeSeeing(7, 9000, 1));
  map.addKeyframe(keyframeSeeing(8, 9000, 1));
  EXPECT_EQ(map.landmark(7777), nullptr);
  EXPECT_EQ(map.dormant().back().id, 7777u);
  EXPECT_EQ(map.archive().size(), archived + 40);  // keyframe 4's and 5's landmarks, not 7777
  // A new map (re-initialization) has another scale: nothing dormant survives.
  map.clear();
  EXPECT_TRUE(map.dormant().empty());
}

TEST(Map, RelabelMovesKeyframeObservationsAndRefusesClashes) {
  MapConfig cfg;
  cfg.max_keyframes = 4;
  Map map(cfg);
  Keyframe a = keyframeSeeing(1, 10, 1);
  Keyframe b = keyframeSeeing(2, 10, 1);
  b.observations.emplace(20, Eigen::Vector2d(0.5, 0.5));  // track 20 and 10 in one keyframe
  Keyframe c = keyframeSeeing(3, 30, 1);                  // a new track, 30, not yet mapped
  map.addKeyframe(a);
  map.addKeyframe(b);
  map.addKeyframe(c);
  map.addLandmark(newLandmark(10, Eigen::Vector3d(1, 2, 3), 5));
  ASSERT_EQ(map.landmark(10)->observations.size(), 2u);
  EXPECT_FALSE(map.relabelLandmark(10, 20, 4));  // both seen by keyframe 2: two different points
  EXPECT_FALSE(map.relabelLandmark(11, 30, 4));  // no such landmark
  ASSERT_TRUE(map.relabelLandmark(10, 30, 4));
  EXPECT_EQ(map.landmark(10), nullptr);
  const auto* l = map.landmark(30);
  ASSERT_NE(l, nullptr);
  EXPECT_EQ(l->id, 30u);
  ASSERT_EQ(l->observations.size(), 3u);  // keyframes 1 and 2 (moved) and 3 (its own)
  EXPECT_EQ(l->observations.front().keyframe, 1u);
  EXPECT_EQ(l->observations.back().keyframe, 3u);
  for (const auto& kf : map.keyframes()) {
    EXPECT_EQ(kf.observations.count(10), 0u);
    EXPECT_EQ(kf.observations.count(30), 1u);
  }
}

TEST(Map, RejectsBadConfig) {
  MapConfig cfg;
  cfg.max_keyframes = 1;
  EXPECT_THROW(Map{cfg}, std::invalid_argument);
  MapConfig cap;
  cap.max_archive_points = 1;
  EXPECT_THROW(Map{cap}, std::invalid_argument);
}

TEST(Map, RescaleMovesTheMapAboutACentreButNotTheArchive) {
  MapConfig cfg;
  cfg.max_keyframes = 2;
  cfg.min_observations_to_archive = 1;
  Map map(cfg);
  map.addLandmark(newLandmark(1, Eigen::Vector3d(0, 0, 5), 1, 0));
  map.addKeyframe(keyframeSeeing(0, 1, 1));
  map.addLandmark(newLandmark(2, Eigen::Vector3d(2, 0, 5), 1, 1));
  Keyframe kf = keyframeSeeing(1, 2, 1);
  kf.T_w_c.translation() = Eigen::Vector3d(1, 0, 0);
  map.addKeyframe(kf);
  map.addLandmark(newLandmark(3, Eigen::Vector3d(4, 0, 5), 1, 2));
  map.addKeyframe(keyframeSeeing(2, 3, 1));  // keyframe 0 and landmark 1 retire
  ASSERT_EQ(map.archive().size(), 1u);
  ASSERT_EQ(map.dormant().size(), 1u);
  const Eigen::Vector3d centre(1, 0, 0);
  map.rescale(centre, 2.0);
  EXPECT_TRUE(map.landmark(2)->p_w.isApprox(Eigen::Vector3d(3, 0, 10)));
  EXPECT_TRUE(map.landmark(3)->p_w.isApprox(Eigen::Vector3d(7, 0, 10)));
  EXPECT_TRUE(map.keyframes().front().T_w_c.translation().isApprox(centre));  // at the centre: unmoved
  EXPECT_TRUE(map.keyframes().back().T_w_c.translation().isApprox(Eigen::Vector3d(-1, 0, 0)));
  EXPECT_TRUE(map.dormant().front().p_w.isApprox(Eigen::Vector3d(-1, 0, 10)));
  EXPECT_TRUE(map.archive().front().p_w.isApprox(Eigen::Vector3d(0, 0, 5)));  // exported as it was made
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

namespace {
Keyframe keyframeAt(std::uint64_t frame, double x) {
  Keyframe kf = keyframeSeeing(frame, 1000 * frame, 1);
  kf.T_w_c.translation() = Eigen::Vector3d(x, 0, 0);
  return kf;
}
std::vector<std::uint64_t> windowFrames(const Map& map) {
  std::vector<std::uint64_t> f;
  for (const Keyframe& kf : map.keyframes()) f.push_back(kf.frame_index);
  return f;
}

// A keyframe at camera centre c (no rotation: looking along +z) that observes the
// given landmarks by projection.
Keyframe keyframeObserving(std::uint64_t frame, const Eigen::Vector3d& c,
                           const std::vector<std::pair<std::uint64_t, Eigen::Vector3d>>& points) {
  Keyframe kf;
  kf.frame_index = frame;
  kf.T_w_c.translation() = c;
  for (const auto& p : points) {
    const Eigen::Vector3d p_c = p.second - c;
    if (p_c.z() > 0.1) kf.observations.emplace(p.first, p_c.hnormalized());
  }
  return kf;
}

// The window after a turn: keyframes of frames 0 and turn_start 1 m apart, then six keyframes
// 2 cm apart (frames turn_start + 1 ...), every one seeing the same 40 points ahead.
std::vector<std::uint64_t> windowAfterTurn(const MapConfig& cfg, std::uint64_t turn_start) {
  Map map(cfg);
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> points;
  points.reserve(40);
  for (std::uint64_t i = 0; i < 40; ++i) {
    points.emplace_back(i, Eigen::Vector3d(-2.0 + 0.1 * double(i), 0.5 * double(i % 3) - 0.5, 8.0));
  }
  for (const auto& p : points) map.addLandmark(newLandmark(p.first, p.second, 1));
  map.addKeyframe(keyframeObserving(0, Eigen::Vector3d(0, 0, 0), points));
  map.addKeyframe(keyframeObserving(turn_start, Eigen::Vector3d(1, 0, 0), points));
  for (std::uint64_t k = turn_start + 1; k < turn_start + 7; ++k) {
    map.addKeyframe(keyframeObserving(k, Eigen::Vector3d(1.0 + 0.02 * double(k - turn_start), 0, 0), points));
  }
  return windowFrames(map);
}
}  // namespace

TEST(Map, ATurnRetiresACrowdedKeyframeNotTheWideOne) {
  // The oldest keyframe gives the points their widest parallax; a crowded one between its
  // neighbours gives them nothing the others do not.
  MapConfig cfg;
  cfg.max_keyframes = 5;
  const std::vector<std::uint64_t> f = windowAfterTurn(cfg, 1);
  ASSERT_EQ(f.size(), 5u);
  EXPECT_EQ(f[0], 0u);  // the wide baseline stays (retiring the oldest would have dropped it first)
  EXPECT_EQ(f[2], 5u);  // the newest three are kept
  EXPECT_EQ(f[4], 7u);
}

TEST(Map, BeyondTheFrameSpanTheOldestLeavesEvenWhenItIsTheWideOne) {
  // The turn above, but keyframe 0 is 100 frames old: with the span limited to 50 frames the
  // oldest leaves as it would without the parallax rule; the crowded keyframes go after that.
  MapConfig cfg;
  cfg.max_keyframes = 5;
  cfg.retire_oldest_beyond_frames = 50;
  const std::vector<std::uint64_t> f = windowAfterTurn(cfg, 100);
  ASSERT_EQ(f.size(), 5u);
  EXPECT_EQ(f[0], 100u);  // frame 0 left at once: the window spanned more than 50 frames
  EXPECT_EQ(f[4], 106u);
  cfg.retire_oldest_beyond_frames = 0;
  EXPECT_EQ(windowAfterTurn(cfg, 100)[0], 0u);  // without the limit the wide baseline stays
  EXPECT_THROW(
      [] {
        MapConfig bad;
        bad.retire_oldest_beyond_frames = -1;
        bad.validate();
      }(),
      std::invalid_argument);
}

TEST(Map, AtSpeedTheKeyframesThatSeeNoCurrentPointLeaveFirst) {
  // Driving fast and slowing down: the gaps between keyframes shrink from 8 m to 1 m,
  // and each point is seen only from the keyframes of the last few metres. The old,
  // widely spaced keyframes see none of the current points: they leave, oldest first,
  // instead of holding the window while the keyframes that see the current points go.
  MapConfig cfg;
  cfg.max_keyframes = 5;
  Map map(cfg);
  const std::vector<double> centres = {0, 8, 15, 21, 26, 30, 33, 35, 36};
  std::uint64_t next_id = 0;
  for (std::size_t k = 0; k < centres.size(); ++k) {
    // Points 6-9 m ahead of this keyframe: seen by the keyframes within about 5 m of it.
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d p(-1.0 + 0.1 * i, 0.3 * (i % 4), centres[k] + 6.0 + 0.15 * i);
      map.addLandmark(newLandmark(next_id++, p, 1, k));
    }
    // The new keyframe sees its own points and those of the keyframes close behind it.
    std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> visible;
    for (const auto& kv : map.landmarks()) {
      if (kv.second.p_w.z() - centres[k] < 10.0) visible.emplace_back(kv.first, kv.second.p_w);
    }
    map.addKeyframe(keyframeObserving(k, Eigen::Vector3d(0, 0, centres[k]), visible));
  }
  EXPECT_EQ(windowFrames(map), (std::vector<std::uint64_t>{4, 5, 6, 7, 8}));
}

TEST(Map, KeyframesThatSeeNoPointLeaveOldestFirst) {
  MapConfig cfg;
  cfg.max_keyframes = 3;
  Map map(cfg);
  map.addKeyframe(keyframeAt(0, 0.0));
  map.addKeyframe(keyframeAt(1, 1.0));
  for (std::uint64_t k = 2; k < 6; ++k) map.addKeyframe(keyframeAt(k, 1.0 + 0.01 * double(k)));
  EXPECT_EQ(windowFrames(map), (std::vector<std::uint64_t>{3, 4, 5}));
}

TEST(Map, TheAnchorRuleRetiresTheOldestOfAnEvenChainButNotAWideBaseline) {
  // Experimental map.retire_oldest_unless_anchor. Keyframes 1 m apart, all seeing the same
  // points: without the oldest the points keep 4/5 of their widest angle, so it leaves (the
  // parallax rule keeps it and retires keyframe 1, which costs nothing). Keyframes 1 m apart
  // and then 2 cm apart (a turn): without the oldest the points keep a tenth of their angle, so
  // it stays and a crowded one leaves, as with the parallax rule.
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> points;
  points.reserve(40);
  for (std::uint64_t i = 0; i < 40; ++i) {
    points.emplace_back(i, Eigen::Vector3d(-2.0 + 0.1 * double(i), 0.5 * double(i % 3) - 0.5, 8.0));
  }
  for (bool anchor : {false, true}) {
    MapConfig cfg;
    cfg.max_keyframes = 5;
    cfg.retire_oldest_unless_anchor = anchor;
    Map chain(cfg), turn(cfg);
    for (const auto& p : points) {
      chain.addLandmark(newLandmark(p.first, p.second, 1));
      turn.addLandmark(newLandmark(p.first, p.second, 1));
    }
    for (std::uint64_t k = 0; k < 6; ++k)
      chain.addKeyframe(keyframeObserving(k, Eigen::Vector3d(double(k), 0, 0), points));
    turn.addKeyframe(keyframeObserving(0, Eigen::Vector3d(0, 0, 0), points));
    for (std::uint64_t k = 1; k < 6; ++k) {
      turn.addKeyframe(keyframeObserving(k, Eigen::Vector3d(1.0 + 0.02 * double(k - 1), 0, 0), points));
    }
    const std::vector<std::uint64_t> chain_expected =
        anchor ? std::vector<std::uint64_t>{1, 2, 3, 4, 5} : std::vector<std::uint64_t>{0, 2, 3, 4, 5};
    EXPECT_EQ(windowFrames(chain), chain_expected) << (anchor ? "anchor rule" : "parallax rule");
    EXPECT_EQ(windowFrames(turn).front(), 0u) << (anchor ? "anchor rule" : "parallax rule");
  }
}

TEST(Map, TheReliantRuleRetiresTheKeyframeFewestPointsNeed) {
  // A camera going back and forth. Keyframe 0 widens the angle of 40 points a little (the
  // newest keyframes see them from far enough apart); keyframe 1 is the only wide view of 2
  // points. The parallax rule keeps keyframe 0 for the angle the 40 points would lose; the
  // reliant rule keeps keyframe 1, which the 2 points cannot do without.
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> many, few;
  for (std::uint64_t i = 0; i < 40; ++i) {
    many.emplace_back(i, Eigen::Vector3d(-1.0 + 0.1 * double(i), 0.5 * double(i % 3) - 0.5, 8.0));
  }
  for (std::uint64_t i = 0; i < 2; ++i) few.emplace_back(100 + i, Eigen::Vector3d(0.5 + 0.5 * double(i), 1.0, 8.0));
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> all = many;
  all.insert(all.end(), few.begin(), few.end());
  for (bool reliant : {false, true}) {
    MapConfig cfg;
    cfg.max_keyframes = 4;
    cfg.retire_fewest_reliant = reliant;
    Map map(cfg);
    for (const auto& p : all) map.addLandmark(newLandmark(p.first, p.second, 1));
    map.addKeyframe(keyframeObserving(0, Eigen::Vector3d(0, 0, 0), many));
    map.addKeyframe(keyframeObserving(1, Eigen::Vector3d(1.0, 0, 0), few));
    map.addKeyframe(keyframeObserving(2, Eigen::Vector3d(0.3, 0, 0), many));
    map.addKeyframe(keyframeObserving(3, Eigen::Vector3d(0.35, 0, 0), many));
    map.addKeyframe(keyframeObserving(4, Eigen::Vector3d(2.0, 0, 0), all));
    const std::vector<std::uint64_t> expected =
        reliant ? std::vector<std::uint64_t>{1, 2, 3, 4} : std::vector<std::uint64_t>{0, 2, 3, 4};
    EXPECT_EQ(windowFrames(map), expected) << (reliant ? "reliant rule" : "parallax rule");
  }
}
