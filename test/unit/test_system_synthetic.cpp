// End to end: the SLAM system on a sequence rendered by the project's own
// generator (textured room, figure-eight path, EuRoC lens distortion), scored
// against the exact ground truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <utility>

#include "vitamin_e/eval/metrics.h"
#include "vitamin_e/pipeline/pipelined_system.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/synth/camera_path.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/scene.h"
#include "vitamin_e/synth/sequence.h"

namespace ve = vitamin_e;

namespace {

struct SyntheticRun {
  std::vector<ve::pipeline::FrameResult> results;
  std::vector<ve::pipeline::TrajectoryEntry> trajectory;
  ve::eval::Trajectory ground_truth;
  std::size_t frames_tracked = 0;
  long long first_init_frame = -1;
  std::size_t tracked_since_init = 0;
  std::size_t reused_map_points = 0;
  int init_retries = 0;
  int relocalizations = 0;
};

constexpr int kFrames = 120;

// The generator's room sequence: its camera, path, and a renderer of its scene.
struct RoomSequence {
  explicit RoomSequence(const ve::synth::SequenceConfig& config)
      : seq(config),
        camera(ve::synth::makeSequenceCamera(seq.width, seq.height, true)),
        path(ve::synth::makeSequencePath(seq)),
        scene(ve::synth::makeSequenceScene(seq, path)),
        renderer(scene, camera) {}
  ve::synth::SequenceConfig seq;
  ve::camera::Camera camera;
  ve::synth::CameraPath path;
  ve::synth::Scene scene;
  ve::synth::Renderer renderer;
};

// dropped: frames not given to the system (a camera the SLAM could not keep up with).
// mapper_behind: sequential, but every frame reaches the mapping stage as if the next one
// already waited for it (TrackedFrame::mapper_behind, as PipelinedSystem marks it).
SyntheticRun runSynthetic(std::uint64_t seed, bool pipelined = false, const std::vector<int>& dropped = {},
                          bool mapper_behind = false, const ve::pipeline::SystemConfig& config = {}) {
  ve::synth::SequenceConfig config_seq;
  config_seq.frames = kFrames;
  config_seq.seed = seed;
  config_seq.noise_sigma = 1.0;
  const RoomSequence room(config_seq);
  const ve::synth::SequenceConfig& seq = room.seq;
  const ve::camera::Camera& camera = room.camera;
  const ve::synth::CameraPath& path = room.path;
  const ve::synth::Renderer& renderer = room.renderer;

  SyntheticRun run;
  std::unique_ptr<ve::pipeline::System> sequential;
  std::unique_ptr<ve::pipeline::PipelinedSystem> two_threads;
  if (pipelined) {
    two_threads = std::make_unique<ve::pipeline::PipelinedSystem>(
        config, camera, ve::pipeline::PipelinedOptions{},
        [&run](ve::pipeline::FrameResult r) { run.results.push_back(std::move(r)); });
  } else {
    sequential = std::make_unique<ve::pipeline::System>(config, camera);
  }
  for (int i = 0; i < kFrames; ++i) {
    const double t = static_cast<double>(ve::synth::frameTimestampNs(seq, i)) * 1e-9;
    const double t_path = i / seq.rate_hz;
    ve::synth::RenderOptions options;
    options.noise_sigma = seq.noise_sigma;
    options.noise_seed = seed * 100000 + static_cast<std::uint64_t>(i);
    if (std::find(dropped.begin(), dropped.end(), i) != dropped.end()) continue;
    const cv::Mat image = renderer.render(path.T_w_c(t_path), options);
    if (pipelined) {
      two_threads->submit(image, t);
    } else if (mapper_behind) {
      ve::pipeline::TrackedFrame tracked = sequential->trackFrame(image, t);
      tracked.mapper_behind = true;
      run.results.push_back(sequential->mapFrame(std::move(tracked)));
    } else {
      run.results.push_back(sequential->process(image, t));
    }
    run.ground_truth.push_back({t, path.T_w_c(t_path)});
  }
  if (pipelined) two_threads->flush();
  const ve::pipeline::System& system = pipelined ? two_threads->system() : *sequential;
  run.trajectory = system.trajectory();
  run.frames_tracked = system.framesTracked();
  run.first_init_frame = system.firstInitFrame();
  run.tracked_since_init = system.framesTrackedSinceInit();
  run.reused_map_points = system.reusedMapPoints();
  run.init_retries = system.initRetries();
  run.relocalizations = system.relocalizations();
  return run;
}

ve::eval::Trajectory toEval(const std::vector<ve::pipeline::TrajectoryEntry>& trajectory) {
  ve::eval::Trajectory out;
  for (const auto& e : trajectory) out.push_back({e.timestamp, e.T_w_c});
  return out;
}

const SyntheticRun& firstRun() {
  static const SyntheticRun run = runSynthetic(3);
  return run;
}

}  // namespace

TEST(SystemSynthetic, InitializesAndTracksEveryFrameAfterwards) {
  const SyntheticRun& run = firstRun();
  std::size_t first_tracked = run.results.size();
  for (std::size_t i = 0; i < run.results.size(); ++i) {
    if (run.results[i].pose_valid) {
      first_tracked = i;
      break;
    }
  }
  ASSERT_LT(first_tracked, 40u) << "no initialization within the first 2 s";
  for (std::size_t i = first_tracked; i < run.results.size(); ++i) {
    EXPECT_EQ(run.results[i].state, ve::pipeline::TrackingState::kTracking)
        << "frame " << i << ": " << run.results[i].message;
    EXPECT_TRUE(run.results[i].T_w_c.matrix().allFinite());
  }
  EXPECT_EQ(run.init_retries, 0);
  // Frames seen while initializing are localized afterwards: the trajectory covers
  // at least every frame from the first keyframe on.
  EXPECT_GE(run.trajectory.size(), run.results.size() - first_tracked);
  // The first map is built at the first frame that returns a pose, and every
  // frame from there on is tracked.
  EXPECT_EQ(run.first_init_frame, static_cast<long long>(first_tracked));
  EXPECT_EQ(run.tracked_since_init, run.results.size() - first_tracked);
  EXPECT_GT(run.frames_tracked, run.tracked_since_init);  // plus the reference frame
  EXPECT_GT(run.results.back().num_mapped, 1000u);
  // Tracks end and new ones start on the same texture: some take over map points.
  EXPECT_GT(run.reused_map_points, 0u);
}

// The per-frame counters (FrameDiagnostics) add up: the previous frame's tracks
// are this frame's old tracks plus the ended ones, every map point of the
// previous frame is still tracked or ended for a named reason, P3P's inliers are
// among its points, points are made only at keyframes (and at every keyframe of
// this translating camera), and the candidates gain parallax between keyframes.
TEST(SystemSynthetic, FrameDiagnosticsAddUp) {
  const SyntheticRun& run = firstRun();
  int keyframes = 0, triangulated = 0, with_candidates = 0, init_frames = 0, dropped = 0;
  int intervals = 0, grew = 0;  // keyframe intervals, those over which the candidates' parallax grew
  int interval_frames = 0;      // frames with candidates since the last keyframe
  double interval_start = 0.0, interval_end = 0.0;
  std::vector<double> survival;
  for (std::size_t i = 0; i < run.results.size(); ++i) {
    const ve::pipeline::FrameResult& r = run.results[i];
    const ve::pipeline::FrameDiagnostics& d = r.diagnostics;
    int lost = 0;
    for (const auto& kv : d.lost_by) lost += kv.second;
    EXPECT_EQ(lost, d.tracks_lost) << "frame " << i;
    dropped += d.tracks_dropped;
    if (i == 0) {
      EXPECT_EQ(static_cast<std::size_t>(d.tracks_born), r.num_tracked);
      EXPECT_EQ(d.tracks_lost + d.tracks_dropped, 0);
    } else {
      EXPECT_EQ(run.results[i - 1].num_tracked,
                r.num_tracked - static_cast<std::size_t>(d.tracks_born) + d.tracks_lost + d.tracks_dropped)
          << "frame " << i;
    }
    EXPECT_LE(d.prev_map_tracked, d.prev_map_points) << "frame " << i;
    std::size_t ended = 0;
    for (const auto& kv : d.prev_map_lost_by) ended += static_cast<std::size_t>(kv.second);
    EXPECT_EQ(d.prev_map_tracked + ended, d.prev_map_points) << "frame " << i;
    EXPECT_LE(d.prev_map_left_view + d.prev_map_lost_in_view, ended) << "frame " << i;
    EXPECT_LE(d.pose_inliers, d.pose_points) << "frame " << i;
    EXPECT_LE(d.candidates_two_keyframes, d.candidates) << "frame " << i;
    EXPECT_GE(d.candidate_parallax_deg, 0.0);
    EXPECT_LT(d.candidate_parallax_deg, 30.0);
    EXPECT_EQ(d.relocalization, ve::pipeline::RelocalizationOutcome::kNotTried) << "frame " << i;  // never lost here
    if (!d.keyframe) {
      EXPECT_EQ(d.triangulated, 0) << "frame " << i;
      EXPECT_TRUE(d.triangulation_rejected_by.empty()) << "frame " << i;
    }
    if (r.state == ve::pipeline::TrackingState::kTracking && (i == 0 || !run.results[i - 1].pose_valid)) {
      // the first map: made from this frame
      ++init_frames;
      EXPECT_TRUE(d.keyframe);
      EXPECT_EQ(d.keyframes, 2u);
      EXPECT_GT(d.triangulated, 100);
      EXPECT_EQ(d.prev_map_points, 0u);
    }
    if (i > 0 && r.state == ve::pipeline::TrackingState::kTracking && run.results[i - 1].pose_valid) {
      EXPECT_EQ(d.prev_map_points, run.results[i - 1].num_mapped) << "frame " << i;
      EXPECT_GE(d.pose_inliers, 30) << "frame " << i;
      EXPECT_LE(d.keyframes, 10u);
      EXPECT_GE(d.keyframes, 2u);
      survival.push_back(d.prevMapTrackedFraction());
      with_candidates += d.candidates > 0 ? 1 : 0;
      if (d.keyframe) {
        ++keyframes;
        triangulated += d.triangulated;
        EXPECT_GT(d.triangulated, 0) << "keyframe " << i;
        EXPECT_GT(d.keyframe_parallax_px, 0.0) << "frame " << i;
        // The candidates waited since the last keyframe: their parallax on
        // the frame before this one against the first frame after that keyframe
        // (at a keyframe the ones triangulated leave the candidates).
        if (interval_frames >= 2) {
          ++intervals;
          grew += interval_end > interval_start ? 1 : 0;
        }
        interval_frames = 0;
      } else if (d.candidates > 0) {
        if (interval_frames++ == 0) interval_start = d.candidate_parallax_deg;
        interval_end = d.candidate_parallax_deg;
      }
    }
  }
  std::printf("keyframes %d, triangulated %d, dropped %d, parallax grew in %d of %d keyframe intervals\n", keyframes,
              triangulated, dropped, grew, intervals);
  EXPECT_EQ(init_frames, 1);
  ASSERT_GT(survival.size(), 50u);
  std::sort(survival.begin(), survival.end());
  EXPECT_GT(survival[survival.size() / 2], 0.8);
  EXPECT_GT(keyframes, 2);
  EXPECT_GT(triangulated, 100);
  EXPECT_GT(with_candidates, 10);
  ASSERT_GE(intervals, 2);
  EXPECT_GE(grew, intervals - intervals / 5);
}

TEST(SystemSynthetic, TrajectoryMatchesGroundTruthAfterSim3Alignment) {
  const SyntheticRun& run = firstRun();
  ve::eval::EvalConfig cfg;
  cfg.frames = kFrames;
  const ve::eval::EvalResult r = ve::eval::evaluate(toEval(run.trajectory), run.ground_truth, cfg);
  // The path covers about 2.4 m in 6 s; measured 0.047 cm RMSE, 0.084 cm max on
  // these exact renders. The bounds (1.5x) catch a loss of accuracy in tracking,
  // BA or scale long before a broken pose or frame convention would.
  EXPECT_GE(r.matched, static_cast<std::size_t>(0.8 * kFrames));
  EXPECT_LT(r.ate.rmse, 0.00075) << ve::eval::summary(r, cfg);
  EXPECT_LT(r.ate.max, 0.0013) << ve::eval::summary(r, cfg);
}

TEST(SystemSynthetic, SequentialRunsAreIdentical) {
  const SyntheticRun& a = firstRun();
  const SyntheticRun b = runSynthetic(3);
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  for (std::size_t i = 0; i < a.trajectory.size(); ++i) {
    EXPECT_EQ(a.trajectory[i].timestamp, b.trajectory[i].timestamp);
    EXPECT_TRUE(a.trajectory[i].T_w_c.matrix() == b.trajectory[i].T_w_c.matrix()) << "pose " << i << " differs";
  }
  ASSERT_EQ(a.results.size(), b.results.size());
  for (std::size_t i = 0; i < a.results.size(); ++i) {
    EXPECT_EQ(a.results[i].num_tracked, b.results[i].num_tracked);
    EXPECT_EQ(a.results[i].num_mapped, b.results[i].num_mapped);
  }
}

TEST(SystemSynthetic, PipelinedModeDeliversEveryFrameInOrderAndTracks) {
  const SyntheticRun run = runSynthetic(3, true);
  ASSERT_EQ(run.results.size(), static_cast<std::size_t>(kFrames));
  for (std::size_t i = 0; i < run.results.size(); ++i) EXPECT_EQ(run.results[i].frame_index, i);
  EXPECT_EQ(run.init_retries, 0);
  ve::eval::EvalConfig cfg;
  cfg.frames = kFrames;
  const ve::eval::EvalResult r = ve::eval::evaluate(toEval(run.trajectory), run.ground_truth, cfg);
  std::printf("[pipelined] ATE rmse %.4f cm\n", 100.0 * r.ate.rmse);
  // Measured 0.045 cm: the sequential run's bound holds (the frame a dropped track ends at
  // depends on the threads' timing, not the accuracy).
  EXPECT_GE(r.matched, static_cast<std::size_t>(0.8 * kFrames));
  EXPECT_LT(r.ate.rmse, 0.00075) << ve::eval::summary(r, cfg);
}

// A pipelined run's results do not depend on the threads' timing: the same frames given all at
// once (the tracker always a frame ahead, the mapper behind) or one at a time (each frame mapped
// before the next one is tracked) give the same poses to the bit. The deferral of a keyframe's BA
// when the mapper is behind is the one choice that follows the load: off here. (Checked: with
// the tracker's drops taken as soon as they are there, or with the newest priors instead of the
// early ones, poses differ.)
TEST(SystemSynthetic, PipelinedRunsDoNotDependOnTheThreadsTiming) {
  ve::synth::SequenceConfig seq;
  seq.frames = kFrames;
  seq.seed = 3;
  seq.noise_sigma = 1.0;
  seq.speed = 1.2;  // 3x the default: the flow loses map tracks that the priors find again
  const RoomSequence room(seq);
  std::vector<std::pair<cv::Mat, double>> frames;
  for (int i = 0; i < seq.frames; ++i) {
    ve::synth::RenderOptions options;
    options.noise_sigma = seq.noise_sigma;
    options.noise_seed = seq.seed * 100000 + static_cast<std::uint64_t>(i);
    frames.emplace_back(room.renderer.render(room.path.T_w_c(i / seq.rate_hz), options),
                        static_cast<double>(ve::synth::frameTimestampNs(seq, i)) * 1e-9);
  }
  ve::pipeline::SystemConfig config;
  config.defer_keyframe_ba = false;
  const auto run = [&](bool one_at_a_time) {
    std::vector<ve::pipeline::FrameResult> results;
    ve::pipeline::PipelinedSystem pipelined(
        config, room.camera, ve::pipeline::PipelinedOptions{},
        [&results](ve::pipeline::FrameResult r) { results.push_back(std::move(r)); });
    for (const auto& [image, t] : frames) {
      pipelined.submit(image, t);
      if (one_at_a_time) pipelined.flush();
    }
    pipelined.flush();
    return std::make_pair(pipelined.system().trajectory(), results);
  };
  const auto [all_at_once, all_results] = run(false);
  const auto [one_by_one, one_results] = run(true);
  ASSERT_GE(all_at_once.size(), static_cast<std::size_t>(kFrames / 2));
  ASSERT_EQ(all_at_once.size(), one_by_one.size());
  for (std::size_t i = 0; i < all_at_once.size(); ++i) {
    EXPECT_TRUE(all_at_once[i].T_w_c.matrix() == one_by_one[i].T_w_c.matrix()) << "pose " << i << " differs";
  }
  ASSERT_EQ(all_results.size(), one_results.size());
  int dropped = 0, from_prior = 0;
  for (std::size_t i = 0; i < all_results.size(); ++i) {
    EXPECT_EQ(all_results[i].num_tracked, one_results[i].num_tracked) << "frame " << i;
    EXPECT_EQ(all_results[i].num_mapped, one_results[i].num_mapped) << "frame " << i;
    EXPECT_EQ(all_results[i].diagnostics.tracks_dropped, one_results[i].diagnostics.tracks_dropped) << "frame " << i;
    EXPECT_EQ(all_results[i].diagnostics.tracks_from_prior, one_results[i].diagnostics.tracks_from_prior)
        << "frame " << i;
    dropped += all_results[i].diagnostics.tracks_dropped;
    from_prior += all_results[i].diagnostics.tracks_from_prior;
  }
  // Both hand-overs are exercised: when the mapping's drops take effect, which priors are read.
  EXPECT_GT(dropped, 0) << "no track was dropped by the mapping";
  EXPECT_GT(from_prior, 0) << "no track was found again from a prior";
}

// Frames dropped after the initialization (gaps of 2, 3 and 4 frame intervals):
// the motion model and the tracks' parallax prediction carry the motion across
// the gap, so every frame given to the system keeps its pose, with no loss.
TEST(SystemSynthetic, TracksAcrossDroppedFrames) {
  const std::vector<int> dropped = {50, 70, 71, 90, 91, 92};
  const SyntheticRun run = runSynthetic(3, false, dropped);
  ASSERT_EQ(run.results.size(), static_cast<std::size_t>(kFrames) - dropped.size());
  ASSERT_GE(run.first_init_frame, 0);
  ASSERT_LT(run.first_init_frame, 40);
  for (std::size_t i = static_cast<std::size_t>(run.first_init_frame); i < run.results.size(); ++i) {
    EXPECT_EQ(run.results[i].state, ve::pipeline::TrackingState::kTracking)
        << "frame " << i << ": " << run.results[i].message;
  }
  EXPECT_EQ(run.init_retries, 0);
  EXPECT_EQ(run.relocalizations, 0);
  ve::eval::EvalConfig cfg;
  cfg.frames = kFrames;
  const ve::eval::EvalResult r = ve::eval::evaluate(toEval(run.trajectory), run.ground_truth, cfg);
  // Measured 0.042 cm RMSE, 0.083 cm max (0.047 and 0.084 with every frame): bounds at 1.5x.
  EXPECT_GE(r.matched, static_cast<std::size_t>(0.8 * (kFrames - static_cast<int>(dropped.size()))));
  EXPECT_LT(r.ate.rmse, 0.00063) << ve::eval::summary(r, cfg);
  EXPECT_LT(r.ate.max, 0.00125) << ve::eval::summary(r, cfg);
}

// A mapper that is behind (the next frame already waits when it takes one) leaves every other
// keyframe's window BA to the next keyframe, never two in a row; the frames keep their poses, and
// the trajectory its accuracy. A sequential run is never behind.
TEST(SystemSynthetic, MapperBehindDefersEveryOtherWindowBa) {
  for (const auto& r : firstRun().results) EXPECT_FALSE(r.diagnostics.window_ba_deferred);
  const SyntheticRun run = runSynthetic(3, false, {}, true);
  ASSERT_GE(run.first_init_frame, 0);
  ASSERT_LT(run.first_init_frame, 40);
  int keyframes = 0, deferred = 0;
  bool last_deferred = false;
  for (std::size_t i = static_cast<std::size_t>(run.first_init_frame); i < run.results.size(); ++i) {
    const ve::pipeline::FrameResult& r = run.results[i];
    EXPECT_EQ(r.state, ve::pipeline::TrackingState::kTracking) << "frame " << i << ": " << r.message;
    EXPECT_TRUE(!r.diagnostics.window_ba_deferred || r.diagnostics.keyframe) << "frame " << i;
    if (!r.diagnostics.keyframe) continue;
    ++keyframes;
    if (r.diagnostics.window_ba_deferred) {
      ++deferred;
      EXPECT_FALSE(last_deferred) << "two keyframes in a row deferred their BA, frame " << i;
    }
    last_deferred = r.diagnostics.window_ba_deferred;
  }
  EXPECT_GE(keyframes, 6);
  EXPECT_GE(2 * deferred, keyframes - 2);  // every other one (the first map's keyframes never defer)
  EXPECT_EQ(run.init_retries, 0);
  EXPECT_EQ(run.relocalizations, 0);
  ve::eval::EvalConfig cfg;
  cfg.frames = kFrames;
  const ve::eval::EvalResult r = ve::eval::evaluate(toEval(run.trajectory), run.ground_truth, cfg);
  std::printf("[mapper behind] ATE rmse %.4f cm, %d of %d window BAs deferred\n", 100.0 * r.ate.rmse, deferred,
              keyframes);
  EXPECT_GE(r.matched, static_cast<std::size_t>(0.8 * kFrames));
  EXPECT_LT(r.ate.rmse, 0.00075) << ve::eval::summary(r, cfg);
}

// With one free keyframe the next keyframe's BA would not optimize a deferred one: nothing defers.
TEST(SystemSynthetic, MapperBehindDefersNothingWithOneFreeKeyframe) {
  ve::pipeline::SystemConfig config;
  config.ba_free_keyframes = 1;
  const SyntheticRun run = runSynthetic(3, false, {}, true, config);
  int keyframes = 0;
  for (const auto& r : run.results) {
    keyframes += r.diagnostics.keyframe ? 1 : 0;
    EXPECT_FALSE(r.diagnostics.window_ba_deferred) << "frame " << r.frame_index;
  }
  EXPECT_GE(keyframes, 6);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

// The pipelined tracker reads its priors once the frame before has its pose (System::waitForPriors,
// before the keyframe work): one count per mapped frame, a skipped one (a stamp that does not
// increase) too, so that no frame leaves the tracker waiting; put out early only for a tracker
// that waits for them.
TEST(SystemSynthetic, PriorsAreOutOncePerMappedFrameSkippedOnesToo) {
  ve::synth::SequenceConfig seq;
  seq.frames = 40;
  seq.seed = 3;
  const RoomSequence room(seq);
  const ve::camera::Camera& camera = room.camera;
  std::vector<std::pair<cv::Mat, double>> frames;
  for (int i = 0; i < seq.frames; ++i) {
    const double t = static_cast<double>(ve::synth::frameTimestampNs(seq, i)) * 1e-9;
    frames.emplace_back(room.renderer.render(room.path.T_w_c(i / seq.rate_hz), {}), t);
    if (i == 30) frames.emplace_back(frames.back().first, t);  // the same stamp again: skipped
  }

  // Sequential: out at each frame's end. A frame whose next one waits for its priors (as
  // PipelinedSystem marks them): out by the time its pose is heard, before its keyframe work.
  for (const bool awaited : {false, true}) {
    ve::pipeline::System system({}, camera);
    std::size_t poses_heard = 0, heard_with_priors_out = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      ve::pipeline::TrackedFrame tracked = system.trackFrame(frames[i].first, frames[i].second);
      tracked.priors_awaited = awaited;
      system.mapFrame(std::move(tracked), [&](const ve::pipeline::FramePose&) {
        ++poses_heard;  // priorsOut() is a thread-safe count, not a call into the mapping
        heard_with_priors_out += system.priorsOut() == i + 1 ? 1 : 0;
      });
      EXPECT_EQ(system.priorsOut(), i + 1) << "frame " << i;
    }
    EXPECT_GE(system.framesTrackedSinceInit(), 10u);
    ASSERT_GE(poses_heard, 10u);
    EXPECT_EQ(heard_with_priors_out, awaited ? poses_heard : 0u) << "awaited " << awaited;
  }

  std::size_t delivered = 0;
  ve::pipeline::PipelinedSystem pipelined({}, camera, ve::pipeline::PipelinedOptions{},
                                          [&delivered](const ve::pipeline::FrameResult&) { ++delivered; });
  for (const auto& [image, t] : frames) pipelined.submit(image, t);
  pipelined.flush();
  EXPECT_EQ(delivered, frames.size());
  EXPECT_EQ(pipelined.system().priorsOut(), frames.size());
  EXPECT_EQ(pipelined.system().relocalizations(), 0);
}
