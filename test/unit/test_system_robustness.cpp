// Robustness of the SLAM system: bad frames, bad timestamps, bad
// configuration files and hard content, each a case with a clear outcome and no
// crash, hang, NaN or wild jump. Frames come from the project's own renderer
// (textured room, figure-eight path) at 376x240 with the EuRoC camera scaled.
// The matrix and what each case expects: docs/ROBUSTNESS.md.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "vitamin_e/eval/alignment.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/synth/camera_path.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/scene.h"
#include "vitamin_e/synth/sequence.h"

namespace ve = vitamin_e;
namespace fs = std::filesystem;
using ve::pipeline::FrameResult;
using ve::pipeline::RelocalizationOutcome;
using ve::pipeline::StateReason;
using ve::pipeline::System;
using ve::pipeline::SystemConfig;
using ve::pipeline::TrackingState;

namespace {

constexpr int kWidth = 376;
constexpr int kHeight = 240;
constexpr double kRate = 20.0;

// One renderable world shared by the tests (the scene is built once).
struct World {
  ve::synth::SequenceConfig seq;
  ve::camera::Camera camera;
  std::unique_ptr<ve::synth::CameraPath> path;
  std::unique_ptr<ve::synth::Scene> scene;
  std::unique_ptr<ve::synth::Renderer> renderer;

  World() {
    seq.width = kWidth;
    seq.height = kHeight;
    seq.rate_hz = kRate;
    seq.seed = 5;
    seq.frames = 400;
    camera = ve::synth::makeSequenceCamera(kWidth, kHeight, true);
    path = std::make_unique<ve::synth::CameraPath>(ve::synth::makeSequencePath(seq));
    scene = std::make_unique<ve::synth::Scene>(ve::synth::makeSequenceScene(seq, *path));
    renderer = std::make_unique<ve::synth::Renderer>(*scene, camera);
  }
  // Frame i of the path (t = i / rate), with sensor noise.
  cv::Mat frame(int i) const { return render(path->T_w_c(i / kRate), i); }
  cv::Mat render(const Eigen::Isometry3d& T_w_c, int noise_index) const {
    ve::synth::RenderOptions options;
    options.noise_sigma = 1.0;
    options.noise_seed = 7000 + static_cast<std::uint64_t>(noise_index);
    return renderer->render(T_w_c, options);
  }
};

const World& world() {
  static const World w;
  return w;
}

// Pixel thresholds of the defaults are tuned at 752x480: halve them at half size.
SystemConfig lowResConfig() {
  SystemConfig c;
  c.init_min_disparity_px = 10.0;
  c.keyframe_parallax_px = 10.0;
  c.min_init_track_budget_fraction = 100.0 / c.tracker.max_points;
  return c;
}

// Feeds frames; keeps every result.
struct SlamRun {
  explicit SlamRun(const SystemConfig& config = lowResConfig()) : system(config, world().camera) {}
  const FrameResult& feed(const cv::Mat& image, double t) {
    results.push_back(system.process(image, t));
    return results.back();
  }
  int firstValid(std::size_t from = 0) const {
    for (std::size_t i = from; i < results.size(); ++i) {
      if (results[i].pose_valid) return static_cast<int>(i);
    }
    return -1;
  }
  System system;
  std::vector<FrameResult> results;
};

double frameTime(int i) { return 100.0 + i / kRate; }

// Every published pose finite and a rotation; trajectory in strict time order,
// finite, and without a jump: no step between consecutive poses longer than
// max_step (map units; the first map has median depth 1, the camera moves
// ~0.01 units per frame). A step into the first pose at or after
// unbounded_step_at (a time) is not bounded: a new map that is not anchored at
// the old one (System::reset) starts there.
void expectSaneOutput(const SlamRun& run, double max_step = 0.3,
                      double unbounded_step_at = std::numeric_limits<double>::quiet_NaN()) {
  for (const FrameResult& r : run.results) {
    if (!r.pose_valid) continue;
    EXPECT_TRUE(r.T_w_c.matrix().allFinite()) << "frame " << r.frame_index;
    const Eigen::Matrix3d R = r.T_w_c.linear();
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-6) << "frame " << r.frame_index;
    for (const auto& p : r.points) {
      if (p.has_position) {
        ASSERT_TRUE(p.p_w.allFinite()) << "frame " << r.frame_index;
      }
    }
  }
  const auto& traj = run.system.trajectory();
  for (std::size_t i = 0; i < traj.size(); ++i) {
    ASSERT_TRUE(traj[i].T_w_c.matrix().allFinite()) << "trajectory pose " << i;
    ASSERT_TRUE(std::isfinite(traj[i].timestamp));
    if (i == 0) continue;
    EXPECT_GT(traj[i].timestamp, traj[i - 1].timestamp) << "trajectory pose " << i;
    if (traj[i - 1].timestamp < unbounded_step_at && traj[i].timestamp >= unbounded_step_at) continue;
    const double step = (traj[i].T_w_c.translation() - traj[i - 1].T_w_c.translation()).norm();
    EXPECT_LT(step, max_step) << "trajectory jumps between t=" << traj[i - 1].timestamp
                              << " and t=" << traj[i].timestamp;
  }
  for (const auto& p : run.system.mapPoints()) ASSERT_TRUE(p.p_w.allFinite());
}

std::string describe(const SlamRun& run) {
  std::ostringstream os;
  for (const FrameResult& r : run.results) {
    os << r.frame_index << ":" << ve::pipeline::toString(r.state) << (r.pose_valid ? "+" : "") << " ";
  }
  return os.str();
}

// Expects fn to throw E with a message containing every part.
template <typename E>
void expectThrowWith(const std::function<void()>& fn, const std::vector<std::string>& parts) {
  try {
    fn();
    ADD_FAILURE() << "no exception; expected one containing '" << parts.front() << "'";
  } catch (const E& e) {
    const std::string msg = e.what();
    for (const std::string& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  }
}

}  // namespace

// ---------------------------------------------------------------- input frames

TEST(Robustness, WrongImageTypesAndSizesAreRejectedClearly) {
  SlamRun run;
  const cv::Mat good = world().frame(0);
  const auto process = [&](const cv::Mat& m) { return [&run, m] { run.system.process(m, 1.0); }; };
  cv::Mat color;
  cv::Mat channels[] = {good, good, good};
  cv::merge(channels, 3, color);
  expectThrowWith<std::invalid_argument>(process(color), {"mono8"});
  cv::Mat wide;
  good.convertTo(wide, CV_16UC1, 256.0);
  expectThrowWith<std::invalid_argument>(process(wide), {"mono8"});
  cv::Mat depth;
  good.convertTo(depth, CV_32FC1, 1.0 / 255.0);
  expectThrowWith<std::invalid_argument>(process(depth), {"mono8"});
  expectThrowWith<std::invalid_argument>(process(cv::Mat()), {"mono8"});
  expectThrowWith<std::invalid_argument>(process(cv::Mat(kHeight / 2, kWidth / 2, CV_8UC1, cv::Scalar(9))),
                                         {"188x120", "376x240"});
  // A rejected frame leaves no trace: the stream starts normally afterwards.
  EXPECT_EQ(run.system.framesProcessed(), 0u);
  const FrameResult& r = run.feed(good, 1.0);
  EXPECT_EQ(r.frame_index, 0u);
  EXPECT_EQ(r.state, TrackingState::kInitializing);
}

TEST(Robustness, MissingCalibrationIsRejected) {
  expectThrowWith<std::invalid_argument>([] { System s(SystemConfig{}, ve::camera::Camera()); }, {"calibration"});
}

// ---------------------------------------------------------------- time

TEST(Robustness, DuplicateBackwardAndNonFiniteStampsAreSkipped) {
  SlamRun run;
  const World& w = world();
  int i = 0;
  for (; i < 50; ++i) run.feed(w.frame(i), frameTime(i));
  ASSERT_GE(run.firstValid(), 0) << "no initialization in 50 frames: " << describe(run);
  const std::size_t processed = run.system.framesProcessed();
  const std::size_t traj = run.system.trajectory().size();
  const double last = frameTime(i - 1);
  for (const double bad :
       {last, last - 0.5, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    const FrameResult& r = run.feed(w.frame(i), bad);
    EXPECT_FALSE(r.pose_valid);
    EXPECT_EQ(r.reason, StateReason::kSkipped) << r.message;
    EXPECT_EQ(r.state, TrackingState::kTracking) << "a skipped frame keeps the system's state";
    EXPECT_NE(r.message.find("does not follow"), std::string::npos) << "the message says why: " << r.message;
  }
  EXPECT_EQ(run.system.framesProcessed(), processed);
  EXPECT_EQ(run.system.trajectory().size(), traj);
  // Tracking goes on with the next good stamp.
  for (; i < 60; ++i) {
    const FrameResult& r = run.feed(w.frame(i), frameTime(i));
    EXPECT_EQ(r.state, TrackingState::kTracking) << "frame " << i << ": " << r.message;
  }
  EXPECT_EQ(run.system.initRetries(), 0);
  expectSaneOutput(run);
}

TEST(Robustness, AGapOfSecondsInTheStampsKeepsTracking) {
  // A recording paused for 5 s (or a dropped stretch of a bag) with the same view
  // after it: time alone is no reason to lose track.
  SlamRun run;
  const World& w = world();
  for (int i = 0; i < 70; ++i) {
    const double t = frameTime(i) + (i >= 45 ? 5.0 : 0.0);
    run.feed(w.frame(i), t);
  }
  const int first = run.firstValid();
  ASSERT_GE(first, 0) << describe(run);
  ASSERT_LT(first, 45) << describe(run);
  for (int i = 45; i < 70; ++i) {
    EXPECT_EQ(run.results[i].state, TrackingState::kTracking) << "frame " << i << ": " << run.results[i].message;
  }
  EXPECT_EQ(run.system.initRetries(), 0);
  expectSaneOutput(run);
}

TEST(Robustness, BagTimeAndWallTimeGiveTheSamePoses) {
  // Stamps are only ordered: a bag recorded in 1970+100 s and a live camera in
  // 2026 give identical poses for identical images.
  const World& w = world();
  SlamRun bag, live;
  for (int i = 0; i < 45; ++i) {
    const cv::Mat img = w.frame(i);
    bag.feed(img, 100.0 + i / kRate);
    live.feed(img, 1790000000.0 + i / kRate);
  }
  const auto& a = bag.system.trajectory();
  const auto& b = live.system.trajectory();
  ASSERT_FALSE(a.empty()) << describe(bag);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_NEAR(a[k].timestamp + 1790000000.0 - 100.0, b[k].timestamp, 1e-6);
    EXPECT_LT((a[k].T_w_c.matrix() - b[k].T_w_c.matrix()).norm(), 1e-9) << "pose " << k;
  }
}

// ---------------------------------------------------------------- content

TEST(Robustness, BlackAndSaturatedFramesNeverInitialize) {
  for (const int value : {0, 255}) {
    SlamRun run;
    for (int i = 0; i < 30; ++i) {
      const FrameResult& r = run.feed(cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(value)), frameTime(i));
      EXPECT_FALSE(r.pose_valid) << "value " << value << " frame " << i;
      EXPECT_FALSE(r.message.empty());
    }
    EXPECT_TRUE(run.system.trajectory().empty()) << "value " << value;
    EXPECT_TRUE(run.system.mapPoints().empty()) << "value " << value;
  }
}

TEST(Robustness, TexturelessWallNeverInitializes) {
  // A blank wall filling the view: grey plus independent sensor noise per frame.
  SlamRun run;
  cv::Mat noise(kHeight, kWidth, CV_8UC1);
  for (int i = 0; i < 40; ++i) {
    cv::theRNG().state = 1234 + i;
    cv::randn(noise, 128, 2.0);
    const FrameResult& r = run.feed(noise, frameTime(i));
    EXPECT_FALSE(r.pose_valid) << "frame " << i << ": " << r.message;
  }
  EXPECT_TRUE(run.system.trajectory().empty());
  EXPECT_TRUE(run.system.mapPoints().empty());
}

TEST(Robustness, PureRotationAtStartDoesNotInitialize) {
  // The camera turns on the spot (yaw 25 deg/s, 60 deg in all): no parallax, no
  // map. Afterwards it moves along the path and must initialize then.
  const World& w = world();
  SlamRun run;
  const Eigen::Isometry3d T0 = w.path->T_w_c(0.0);
  const int turn = 48;
  for (int i = 0; i < turn; ++i) {
    Eigen::Isometry3d T = T0;
    // Rotation about the world vertical through the camera centre.
    T.linear() = Eigen::AngleAxisd(0.44 * i / kRate, Eigen::Vector3d::UnitZ()).toRotationMatrix() * T0.linear();
    const FrameResult& r = run.feed(w.render(T, i), frameTime(i));
    EXPECT_FALSE(r.pose_valid) << "initialized from a pure rotation at frame " << i << ": " << r.message;
  }
  EXPECT_TRUE(run.system.trajectory().empty());
  expectSaneOutput(run);
}

namespace {
// Tracking, then 2 s (40 frames) of black (lens cap, tunnel), then the view
// again from where the camera went meanwhile.
constexpr int kBlackBegin = 60, kBlackEnd = 100, kBlackoutRunEnd = 170;
void runBlackout(SlamRun* run) {
  const World& w = world();
  const cv::Mat black(kHeight, kWidth, CV_8UC1, cv::Scalar(0));
  for (int i = 0; i < kBlackoutRunEnd; ++i) {
    run->feed(i >= kBlackBegin && i < kBlackEnd ? black : w.frame(i), frameTime(i));
  }
  const int first = run->firstValid();
  ASSERT_GE(first, 0) << describe(*run);
  ASSERT_LT(first, kBlackBegin) << describe(*run);
  EXPECT_EQ(run->results[kBlackBegin - 1].state, TrackingState::kTracking) << run->results[kBlackBegin - 1].message;
  EXPECT_EQ(run->results[kBlackBegin].state, TrackingState::kLost) << run->results[kBlackBegin].message;
  EXPECT_EQ(run->results[kBlackBegin].reason, StateReason::kPoseFailed) << run->results[kBlackBegin].message;
  for (int i = kBlackBegin; i < kBlackEnd; ++i) EXPECT_FALSE(run->results[i].pose_valid) << "frame " << i;
  // The trajectory holds poses on both sides of the blackout.
  const auto& traj = run->system.trajectory();
  ASSERT_FALSE(traj.empty());
  EXPECT_LT(traj.front().timestamp, frameTime(kBlackBegin));
  EXPECT_GT(traj.back().timestamp, frameTime(kBlackEnd));
}

// Sim(3)-aligned ATE RMSE [m] of the whole trajectory against the path: one
// similarity for all of it, so a change of scale or frame at a loss shows.
double wholeTrajectoryAte(const System& system) {
  const auto& traj = system.trajectory();
  Eigen::Matrix3Xd est(3, traj.size()), gt(3, traj.size());
  for (Eigen::Index k = 0; k < est.cols(); ++k) {
    est.col(k) = traj[k].T_w_c.translation();
    gt.col(k) = world().path->T_w_c(traj[k].timestamp - frameTime(0)).translation();
  }
  const ve::eval::Sim3 s = ve::eval::umeyamaAlignment(est, gt, true);
  double sum = 0.0;
  for (Eigen::Index k = 0; k < est.cols(); ++k) sum += (s.apply(Eigen::Vector3d(est.col(k))) - gt.col(k)).squaredNorm();
  return std::sqrt(sum / static_cast<double>(traj.size()));
}
}  // namespace

TEST(Robustness, BlackoutOfTwoSecondsRelocalizesInTheSameMap) {
  // Lost at the first black frame; after it the camera is found again in the
  // map it left: no new map, the same world frame and scale.
  SlamRun run;
  runBlackout(&run);
  const int again = run.firstValid(kBlackEnd);
  ASSERT_GE(again, 0) << "never tracked again after the blackout: " << describe(run);
  EXPECT_LT(again, kBlackEnd + 5) << describe(run);
  EXPECT_EQ(run.system.initRetries(), 0);
  EXPECT_GE(run.system.relocalizations(), 1);
  EXPECT_EQ(run.results.back().relocalizations, run.system.relocalizations());
  EXPECT_EQ(run.results[again].reason, StateReason::kRelocalized) << run.results[again].message;
  // The counters tell the attempts apart: the frames after the loss tried and
  // failed, the frame found again says so with its matches.
  const ve::pipeline::FrameDiagnostics& found = run.results[again].diagnostics;
  EXPECT_EQ(found.relocalization, RelocalizationOutcome::kRelocalized);
  EXPECT_GE(found.relocalization_inliers, 30);
  EXPECT_LE(found.relocalization_inliers, found.relocalization_matches);
  EXPECT_TRUE(found.keyframe);  // a relocalized frame becomes a keyframe
  EXPECT_EQ(run.results[kBlackBegin - 1].diagnostics.relocalization, RelocalizationOutcome::kNotTried);
  // What the search cost is the frame's stage "relocalize" (stats.json timing_ms), only where it ran.
  EXPECT_EQ(run.results[again].timing_ms.count("relocalize"), 1u);
  EXPECT_EQ(run.results[kBlackBegin - 1].timing_ms.count("relocalize"), 0u);
  EXPECT_EQ(run.results.front().timing_ms.count("init"), 1u);
  for (int i = kBlackBegin + 1; i < again; ++i) {
    const RelocalizationOutcome outcome = run.results[i].diagnostics.relocalization;
    EXPECT_TRUE(outcome == RelocalizationOutcome::kNotFound || outcome == RelocalizationOutcome::kDidNotHold)
        << "frame " << i << ": '" << toString(outcome) << "'";
    EXPECT_EQ(run.results[i].state, TrackingState::kRelocalizing) << "frame " << i;
    EXPECT_EQ(run.results[i].reason, StateReason::kNotRelocalized) << "frame " << i;
  }
  for (int i = again; i < kBlackoutRunEnd; ++i) {
    EXPECT_TRUE(run.results[i].pose_valid) << "frame " << i << ": " << run.results[i].message;
  }
  const double ate = wholeTrajectoryAte(run.system);
  std::printf("[blackout] whole-trajectory Sim(3) ATE %.4f cm\n", 100.0 * ate);
  EXPECT_LT(ate, 0.0025);  // measured 0.169 cm: one frame and scale on both sides of the loss
  expectSaneOutput(run, 0.3);
}

TEST(Robustness, AJumpBackInTheStreamHasAPoseOnItsFirstFrame) {
  // The stream jumps 5 s back along the path (a bag spliced, a replayed
  // buffer): the place is in the map. The frame of the jump is either tracked
  // across it (the dominant flow bridges the views: the SLAM's tracker does) or
  // relocalized itself (a tracker whose tracks end there), so no frame goes
  // without a pose, and the pose is the place of 5 s before, not the last one.
  const World& w = world();
  SlamRun run;
  const int jump = 140, back = 100, end = 170;
  for (int i = 0; i < end; ++i) run.feed(w.frame(i < jump ? i : i - back), frameTime(i));
  const int first = run.firstValid();
  ASSERT_GE(first, 0) << describe(run);
  ASSERT_LT(first, jump - back) << describe(run);
  const FrameResult& at = run.results[jump];
  EXPECT_TRUE(at.pose_valid) << at.message;
  EXPECT_EQ(at.state, TrackingState::kTracking) << at.message;
  EXPECT_TRUE(at.reason == StateReason::kTracked || at.reason == StateReason::kRelocalized) << at.message;
  EXPECT_EQ(run.results[jump - 1].reason, StateReason::kTracked);
  EXPECT_EQ(run.system.initRetries(), 0);
  EXPECT_LE(run.system.relocalizations(), 1);
  for (int i = first; i < end; ++i) EXPECT_TRUE(run.results[i].pose_valid) << "frame " << i;
  // The same place as 5 s before: within 5 % of the way driven since.
  const Eigen::Vector3d then = run.results[jump - back].T_w_c.translation();
  const double driven = (run.results[jump - 1].T_w_c.translation() - then).norm();
  EXPECT_LT((at.T_w_c.translation() - then).norm(), 0.05 * driven);
  expectSaneOutput(run, 0.3, frameTime(jump));  // the jump itself is the one long step
}

TEST(Robustness, BlackoutWithoutRelocalizationReinitializes) {
  // relocalization.enabled false: the old behaviour, a new map placed at the
  // last pose and scale; the trajectory goes on without NaN or jump.
  SystemConfig config = lowResConfig();
  config.relocalization.enabled = false;
  SlamRun run(config);
  runBlackout(&run);
  const int again = run.firstValid(kBlackEnd);
  ASSERT_GE(again, 0) << "never re-initialized after the blackout: " << describe(run);
  EXPECT_LT(again, kBlackEnd + 50) << describe(run);
  EXPECT_GE(run.system.initRetries(), 1);
  EXPECT_EQ(run.system.relocalizations(), 0);
  EXPECT_EQ(run.results.back().init_retries, run.system.initRetries());
  for (int i = again; i < kBlackoutRunEnd; ++i) {
    EXPECT_TRUE(run.results[i].pose_valid) << "frame " << i << ": " << run.results[i].message;
  }
  expectSaneOutput(run);
}

TEST(Robustness, SuddenHalfTurnLosesThenReinitializes) {
  // The view flips by 180 degrees between two frames (a camera swapped, a bag
  // spliced): lost, counted in initRetries(), re-initialized on the new view.
  const World& w = world();
  SlamRun run;
  const int flip = 60, end = 150;
  const Eigen::Isometry3d half_turn(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()));
  for (int i = 0; i < end; ++i) {
    const Eigen::Isometry3d T = w.path->T_w_c(i / kRate);
    run.feed(i < flip ? w.frame(i) : w.render(T * half_turn, i), frameTime(i));
  }
  const int first = run.firstValid();
  ASSERT_GE(first, 0) << describe(run);
  ASSERT_LT(first, flip) << describe(run);
  EXPECT_EQ(run.results[flip - 1].state, TrackingState::kTracking);
  EXPECT_EQ(run.results[flip].state, TrackingState::kLost) << run.results[flip].message;
  EXPECT_FALSE(run.results[flip].pose_valid);
  EXPECT_GE(run.system.initRetries(), 1);
  const int again = run.firstValid(flip);
  ASSERT_GE(again, 0) << "never re-initialized after the flip: " << describe(run);
  EXPECT_LT(again, flip + 60) << describe(run);
  expectSaneOutput(run);
}

TEST(Robustness, ResetKeepsTheTrajectoryAndReinitializes) {
  const World& w = world();
  SlamRun run;
  for (int i = 0; i < 50; ++i) run.feed(w.frame(i), frameTime(i));
  ASSERT_GE(run.firstValid(), 0) << describe(run);
  const std::size_t before = run.system.trajectory().size();
  // Map points with an id are the active map; the archive (id 0) stays for export.
  auto count = [&](bool active) {
    std::size_t n = 0;
    for (const auto& p : run.system.mapPoints()) n += (p.id != 0) == active ? 1 : 0;
    return n;
  };
  const std::size_t archived = count(false);
  ASSERT_GT(count(true), 100u) << "no map before the reset";
  run.system.reset();
  EXPECT_EQ(count(true), 0u) << "the active map survived reset()";
  EXPECT_EQ(count(false), archived) << "reset() changed the archive";
  EXPECT_EQ(run.system.trajectory().size(), before);
  const std::size_t n = run.results.size();
  for (int i = 50; i < 110; ++i) run.feed(w.frame(i), frameTime(i));
  // Frames after the reset initialize a new map from scratch.
  EXPECT_EQ(run.results[n].state, TrackingState::kInitializing) << run.results[n].message;
  EXPECT_EQ(run.results[n].map_size, 0u);
  EXPECT_FALSE(run.results[n].pose_valid);
  EXPECT_GE(run.firstValid(n), 0) << describe(run);
  // The step bound of every other test, except into the first pose of the new
  // map, which is not anchored at the old one.
  expectSaneOutput(run, 0.3, frameTime(50));
}

// ---------------------------------------------------------------- config files

namespace {
class ConfigFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("ve_robust_cfg_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  void expectConfigError(const std::string& path, const std::vector<std::string>& parts) {
    std::vector<std::string> all = parts;
    all.insert(all.begin(), path);
    expectThrowWith<ve::pipeline::ConfigError>([&] { ve::pipeline::loadSystemConfig(path); }, all);
  }
  fs::path dir_;
};
}  // namespace

TEST_F(ConfigFiles, MalformedYamlGivesAConfigErrorNamingTheFileAndKey) {
  expectConfigError((dir_ / "missing.yaml").string(), {"cannot read"});
  expectConfigError(write("syntax.yaml", "pipeline:\n  min_pose_inliers: [1, 2\n    : {\n"), {"not valid yaml"});
  expectConfigError(write("list.yaml", "- 1\n- 2\n"), {"expected a map"});
  expectConfigError(write("scalar.yaml", "hello\n"), {"expected a map"});
  expectConfigError(write("section.yaml", "pipeline: 3\n"), {"pipeline", "must be a map"});
  expectConfigError(write("unknown.yaml", "pipeline:\n  min_pose_inlier: 30\n"), {"pipeline.min_pose_inlier"});
  expectConfigError(write("section2.yaml", "pipelines:\n  min_pose_inliers: 30\n"), {"pipelines.min_pose_inliers"});
  expectConfigError(write("word.yaml", "pipeline:\n  min_pose_inliers: thirty\n"),
                    {"pipeline.min_pose_inliers", "thirty"});
  expectConfigError(write("float.yaml", "pipeline:\n  min_pose_inliers: 30.5\n"), {"pipeline.min_pose_inliers"});
  expectConfigError(write("huge.yaml", "pipeline:\n  min_pose_inliers: 1e30\n"),
                    {"pipeline.min_pose_inliers", "range"});
  expectConfigError(write("nan.yaml", "pipeline:\n  max_reprojection_px: .nan\n"), {"pipeline.max_reprojection_px"});
  expectConfigError(write("range.yaml", "pipeline:\n  max_reprojection_px: -1\n"), {"pipeline.max_reprojection_px"});
  expectConfigError(write("seq.yaml", "pipeline:\n  max_reprojection_px: [1, 2]\n"), {"pipeline.max_reprojection_px"});
  // Truncated in the middle of a section: still a clear error or the values read so far.
  try {
    ve::pipeline::loadSystemConfig(write("cut.yaml", "pipeline:\n  min_pose_inliers: 3"));
    ADD_FAILURE() << "min_pose_inliers 3 accepted";
  } catch (const ve::pipeline::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("min_pose_inliers"), std::string::npos) << e.what();
  }
  // Empty file and empty sections: the defaults.
  EXPECT_NO_THROW(ve::pipeline::loadSystemConfig(write("empty.yaml", "")));
  EXPECT_NO_THROW(ve::pipeline::loadSystemConfig(write("comment.yaml", "# nothing\n")));
}

TEST_F(ConfigFiles, NonStringKeysAreConfigErrors) {
  // Keys that are not scalars must not escape as yaml-cpp exceptions.
  try {
    ve::pipeline::loadSystemConfig(write("key.yaml", "? [a, b]\n: {x: 1}\n"));
    ADD_FAILURE() << "no error";
  } catch (const ve::pipeline::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("key.yaml"), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a ConfigError: " << e.what();
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
