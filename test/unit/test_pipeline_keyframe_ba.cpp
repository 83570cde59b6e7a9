// The keyframe BA's free keyframes (Mapper::optimizeWindow): which keyframes of a
// full window it moves (pipeline.ba_free_keyframes, pipeline.ba_fixed_keyframes,
// pipeline.ba_free_min_shared).
// A keyframe the window keeps for its parallax sits behind the newest ones: held
// fixed, it keeps whatever pose (and scale) it had when it was made; freed, the
// BA moves it to agree with its points (docs/ROBUSTNESS.md, "How many keyframes
// the keyframe BA frees").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/mapper.h"
#include "vitamin_e/pipeline/system_config.h"

namespace ve = vitamin_e;

namespace {

const ve::camera::Camera kCamera(640, 480, 500.0, 500.0, 320.0, 240.0);
constexpr int kKeyframes = 10;

Eigen::Vector3d keyframeCentre(int k) { return Eigen::Vector3d(0.25 * k, 0.02 * (k % 3), 0.0); }

// A wall of points 6-8 m ahead, seen by every keyframe of a sideways pass (no rotation).
std::vector<Eigen::Vector3d> wall() {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 12; ++j) {
      points.emplace_back(-1.5 + 0.28 * i, -1.4 + 0.25 * j, 6.0 + 0.5 * ((i * 7 + j * 3) % 5));
    }
  }
  return points;
}

// A full window of exact keyframes, then keyframe `perturbed`'s stored pose is moved by `offset`.
ve::map::Map windowWithOneKeyframeOff(int perturbed, const Eigen::Vector3d& offset, const ve::map::MapConfig& cfg) {
  ve::map::Map map(cfg);
  const std::vector<Eigen::Vector3d> points = wall();
  for (std::size_t i = 0; i < points.size(); ++i) {
    ve::map::NewLandmark l;
    l.id = i;
    l.p_w = points[i];
    l.intensity = 100;
    map.addLandmark(l);
  }
  for (int k = 0; k < kKeyframes; ++k) {
    ve::map::Keyframe kf;
    kf.frame_index = 10 * static_cast<std::uint64_t>(k);
    kf.T_w_c.translation() = keyframeCentre(k);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d p_c = points[i] - keyframeCentre(k);
      const Eigen::Vector2d px = kCamera.pinhole().project(p_c.hnormalized());
      if (px.x() >= 0 && px.y() >= 0 && px.x() < 640 && px.y() < 480) kf.observations.emplace(i, p_c.hnormalized());
    }
    map.addKeyframe(kf);
  }
  Eigen::Isometry3d T_w_c = map.keyframes()[static_cast<std::size_t>(perturbed)].T_w_c;
  T_w_c.translation() += offset;
  map.setKeyframePose(static_cast<std::size_t>(perturbed), T_w_c);
  return map;
}

const Eigen::Isometry3d* movedPose(const ve::pipeline::MapUpdate& u, std::size_t index) {
  for (const auto& [k, T_w_c] : u.keyframe_poses) {
    if (k == index) return &T_w_c;
  }
  return nullptr;
}

}  // namespace

TEST(KeyframeBa, AFreedKeyframeBehindTheNewestOnesIsMovedTowardsItsPoints) {
  ve::pipeline::SystemConfig config;
  ASSERT_EQ(config.map.max_keyframes, kKeyframes);
  config.ba_free_keyframes = kKeyframes - config.ba_fixed_keyframes;  // every keyframe but the gauge
  const Eigen::Vector3d offset(0.04, -0.03, 0.05);                    // 7 cm: about 5 px at 7 m
  const ve::map::Map map = windowWithOneKeyframeOff(3, offset, config.map);
  ASSERT_EQ(map.keyframes().size(), static_cast<std::size_t>(kKeyframes));
  const ve::pipeline::MapUpdate u = ve::pipeline::Mapper(config, kCamera).optimizeWindow(map);
  const Eigen::Isometry3d* T_w_c = movedPose(u, 3);
  ASSERT_NE(T_w_c, nullptr) << "keyframe 3 of 10 was held fixed";
  const double error_before = offset.norm();
  const double error_after = (T_w_c->translation() - keyframeCentre(3)).norm();
  EXPECT_LT(error_after, 0.3 * error_before);
}

TEST(KeyframeBa, TheGaugeKeyframesNeverMove) {
  ve::pipeline::SystemConfig config;
  config.ba_free_keyframes = 100;  // more than the window: still not the gauge
  const ve::map::Map map = windowWithOneKeyframeOff(5, Eigen::Vector3d(0.05, 0.0, 0.0), config.map);
  const ve::pipeline::MapUpdate u = ve::pipeline::Mapper(config, kCamera).optimizeWindow(map);
  for (int k = 0; k < config.ba_fixed_keyframes; ++k) {
    EXPECT_EQ(movedPose(u, static_cast<std::size_t>(k)), nullptr) << "gauge keyframe " << k << " moved";
  }
  EXPECT_NE(movedPose(u, 5), nullptr);
}

TEST(KeyframeBa, FreeKeyframesCanBeLimitedToTheNewest) {
  // pipeline.ba_free_keyframes 4: the keyframes behind the newest 4 keep their poses.
  ve::pipeline::SystemConfig config;
  config.ba_free_keyframes = 4;
  const ve::map::Map map = windowWithOneKeyframeOff(3, Eigen::Vector3d(0.05, 0.0, 0.0), config.map);
  const ve::pipeline::MapUpdate u = ve::pipeline::Mapper(config, kCamera).optimizeWindow(map);
  EXPECT_EQ(movedPose(u, 3), nullptr);
  for (std::size_t k = kKeyframes - 4; k < static_cast<std::size_t>(kKeyframes); ++k)
    EXPECT_NE(movedPose(u, k), nullptr);
}

TEST(KeyframeBa, WithASharedViewRuleAKeyframeThatSeesTooLittleOfTheNewestOneStaysFixed) {
  // pipeline.ba_free_min_shared: a keyframe is free when it sees at least that share of the
  // newest keyframe's map points. Keyframe 3 is made to see only a fifth of them.
  ve::pipeline::SystemConfig config;
  config.ba_free_min_shared = 0.5;
  ve::map::Map map = windowWithOneKeyframeOff(3, Eigen::Vector3d(0.05, 0.0, 0.0), config.map);
  const auto& newest = map.keyframes().back().observations;
  ve::map::Keyframe sparse = map.keyframes()[3];
  std::size_t kept = 0;
  for (auto it = sparse.observations.begin(); it != sparse.observations.end();) {
    if (newest.count(it->first) && kept++ % 5 != 0) {
      it = sparse.observations.erase(it);
    } else {
      ++it;
    }
  }
  ve::map::Map thinned(config.map);
  for (const auto& [id, l] : map.landmarks()) {
    ve::map::NewLandmark n;
    n.id = id;
    n.p_w = l.p_w;
    n.intensity = l.intensity;
    thinned.addLandmark(n);
  }
  for (std::size_t k = 0; k < map.keyframes().size(); ++k) thinned.addKeyframe(k == 3 ? sparse : map.keyframes()[k]);
  const ve::pipeline::MapUpdate u = ve::pipeline::Mapper(config, kCamera).optimizeWindow(thinned);
  EXPECT_EQ(movedPose(u, 3), nullptr) << "keyframe 3 sees a fifth of the newest keyframe's points but was freed";
  for (std::size_t k = config.ba_fixed_keyframes; k < static_cast<std::size_t>(kKeyframes); ++k) {
    if (k != 3) {
      EXPECT_NE(movedPose(u, k), nullptr) << "keyframe " << k << " shares the view but was held";
    }
  }
  for (int k = 0; k < config.ba_fixed_keyframes; ++k) EXPECT_EQ(movedPose(u, static_cast<std::size_t>(k)), nullptr);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
