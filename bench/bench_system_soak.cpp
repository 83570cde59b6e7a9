// Soak test of the SLAM system: the project's synthetic room at low
// resolution, rendered in-process frame after frame along the figure-eight path
// (no PNGs), fed to pipeline::System for a given wall-clock time. Samples the
// resident memory (/proc/self/statm) every N frames, prints the curve and a
// verdict: is memory flat after warm-up (slope over the second half)?
//   bench_system_soak [--minutes M] [--sample-every N] [--width W --height H]
//                     [--archive-voxel V] [--max-frames F] [--seed S] [--realtime]
// --realtime paces the frames at the camera rate (20 Hz), as a robot's camera
// would: an hour of wall time is then an hour of sequence, at a fraction of a core.
// Run by ./scripts/bench_soak.sh (not part of the tests). Last line: JSON.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "cli.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/synth/camera_path.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/scene.h"
#include "vitamin_e/synth/sequence.h"

namespace ve = vitamin_e;

namespace {

double rssMb() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0.0;
  return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

struct Sample {
  std::uint64_t frame = 0;
  double wall_min = 0.0;
  double seq_min = 0.0;
  double rss_mb = 0.0;
  std::size_t map_points = 0;
  std::size_t dormant = 0;  // retired points kept for map reuse (a FIFO capped by map.max_dormant_landmarks)
  std::size_t trajectory = 0;
  double trajectory_mb = 0.0;  // the trajectory's buffer: capacity x entry (+ heap stamp strings)
  int init_retries = 0;
  double ms_per_frame = 0.0;  // mean since the previous sample
};

// Least-squares slope of y over x.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  if (n < 2) return 0.0;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= static_cast<double>(n);
  my /= static_cast<double>(n);
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxx > 0 ? sxy / sxx : 0.0;
}

const char* const kUsage = "usage: bench_system_soak [--minutes M] [--sample-every N] [--width W --height H]\n"
                           "                         [--archive-voxel V] [--max-frames F] [--seed S] [--realtime]\n"
                           "  --minutes M        wall-clock minutes to run (default 60)\n"
                           "  --sample-every N   frames between memory samples (default 200)\n"
                           "  --width W --height H  image size (default 376x240)\n"
                           "  --archive-voxel V  map.archive_voxel_m (default: the shipped default)\n"
                           "  --max-frames F     stop after F frames (0: no limit)\n"
                           "  --seed S           scene and noise seed\n"
                           "  --realtime         pace the frames at 20 Hz, as a camera\n";

}  // namespace

int main(int argc, char** argv) try {
  double minutes = 60.0;
  int sample_every = 200;
  int width = 376, height = 240;
  double archive_voxel = ve::map::MapConfig{}.archive_voxel_m;  // the shipped default
  long long max_frames = 0;
  std::uint64_t seed = 0;
  bool realtime = false;
  namespace cli = ve::cli;
  cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.flag("--realtime", &realtime) || args.value("--minutes", &minutes) ||
        args.value("--sample-every", &sample_every) || args.value("--width", &width) ||
        args.value("--height", &height) || args.value("--archive-voxel", &archive_voxel) ||
        args.value("--max-frames", &max_frames) || args.value("--seed", &seed)) {
      continue;
    }
    args.unknown();
  }
  if (!(minutes > 0)) cli::fail("--minutes must be > 0");
  if (sample_every < 1) cli::fail("--sample-every must be >= 1");
  if (width < 64 || height < 48) cli::fail("--width/--height must be at least 64x48");
  if (archive_voxel < 0) cli::fail("--archive-voxel must be >= 0");
  if (max_frames < 0) cli::fail("--max-frames must be >= 0");

  // The scene is built around two laps of the path; the path is periodic in
  // position, so boxes stay clear of it for the whole run.
  ve::synth::SequenceConfig seq;
  seq.width = width;
  seq.height = height;
  seq.seed = seed;
  seq.noise_sigma = 1.0;
  const ve::camera::Camera camera = ve::synth::makeSequenceCamera(width, height, true);
  const ve::synth::CameraPath path(ve::synth::makeSequencePath(seq));
  const double lap_s = 2.0 * M_PI / path.angularRate();
  seq.frames = static_cast<int>(std::ceil(2.0 * lap_s * seq.rate_hz));
  const auto t_scene = ve::TimingClock::now();
  const ve::synth::Scene scene = ve::synth::makeSequenceScene(seq, path);
  const ve::synth::Renderer renderer(scene, camera);

  // Pixel thresholds of the defaults are tuned at 752x480: scale them.
  ve::pipeline::SystemConfig config;
  const double s = width / 752.0;
  config.init_min_disparity_px *= s;
  config.keyframe_parallax_px *= s;
  config.min_init_track_budget_fraction =
      std::max(50.0 / config.tracker.max_points, config.min_init_track_budget_fraction * s);
  config.map.archive_voxel_m = archive_voxel;
  ve::pipeline::System system(config, camera);

  std::printf("# soak: %dx%d, %.0f Hz%s, lap %.1f s, %.1f wall minutes, sample every %d frames, archive voxel %.3f, "
              "archive cap %zu points, dormant cap %zu points\n",
              width, height, seq.rate_hz, realtime ? " paced in real time" : "", lap_s, minutes, sample_every,
              archive_voxel, config.map.max_archive_points, config.map.max_dormant_landmarks);
  std::printf("# scene built in %.1f s; RSS at start %.1f MB\n", ve::elapsedMs(t_scene) / 1000.0, rssMb());
  std::printf("%8s %9s %9s %9s %10s %8s %10s %8s %9s\n", "frame", "wall_min", "seq_min", "rss_mb", "map_pts", "dormant",
              "traj", "retries", "ms/frame");
  std::fflush(stdout);

  std::vector<Sample> samples;
  const auto start = ve::TimingClock::now();
  auto wall_minutes = [&] { return ve::elapsedMs(start) / 60000.0; };
  auto last_sample_time = start;
  std::uint64_t tracked = 0, nonfinite = 0;
  double max_step = 0.0;
  std::uint64_t frame = 0;
  for (;; ++frame) {
    const double t = static_cast<double>(frame) / seq.rate_hz;
    if (realtime) std::this_thread::sleep_until(start + std::chrono::duration<double>(t));
    ve::synth::RenderOptions options;
    options.noise_sigma = seq.noise_sigma;
    options.noise_seed = seed * 1000003 + frame;
    const cv::Mat image = renderer.render(path.T_w_c(t), options);
    const ve::pipeline::FrameResult r = system.process(image, 1600000000.0 + t);
    if (r.pose_valid) {
      ++tracked;
      if (!r.T_w_c.matrix().allFinite()) ++nonfinite;
    }
    const bool done =
        wall_minutes() >= minutes || (max_frames > 0 && frame + 1 >= static_cast<std::uint64_t>(max_frames));
    if ((frame + 1) % sample_every == 0 || done) {
      const auto now = ve::TimingClock::now();
      Sample smp;
      smp.frame = frame + 1;
      smp.wall_min = wall_minutes();
      smp.seq_min = static_cast<double>(frame + 1) / seq.rate_hz / 60.0;
      smp.rss_mb = rssMb();
      smp.map_points = system.mapPoints().size();
      smp.dormant = system.dormantMapPoints();
      const auto& tr = system.trajectory();
      smp.trajectory = tr.size();
      double traj_bytes = static_cast<double>(tr.capacity()) * sizeof(ve::pipeline::TrajectoryEntry);
      if (!tr.empty() && tr.back().timestamp_text.capacity() > 15) {  // beyond the small-string buffer
        traj_bytes += static_cast<double>(tr.size()) * static_cast<double>(tr.back().timestamp_text.capacity() + 17);
      }
      smp.trajectory_mb = traj_bytes / (1024.0 * 1024.0);
      smp.init_retries = system.initRetries();
      const std::uint64_t since = samples.empty() ? frame + 1 : frame + 1 - samples.back().frame;
      smp.ms_per_frame =
          std::chrono::duration<double, std::milli>(now - last_sample_time).count() / static_cast<double>(since);
      last_sample_time = now;
      samples.push_back(smp);
      std::printf("%8llu %9.2f %9.2f %9.2f %10zu %8zu %10zu %8d %9.1f\n", static_cast<unsigned long long>(smp.frame),
                  smp.wall_min, smp.seq_min, smp.rss_mb, smp.map_points, smp.dormant, smp.trajectory, smp.init_retries,
                  smp.ms_per_frame);
      std::fflush(stdout);
    }
    if (done) break;
  }
  const std::uint64_t frames = frame + 1;
  const auto& traj = system.trajectory();
  for (std::size_t i = 1; i < traj.size(); ++i) {
    max_step = std::max(max_step, (traj[i].T_w_c.translation() - traj[i - 1].T_w_c.translation()).norm());
    if (!traj[i].T_w_c.matrix().allFinite()) ++nonfinite;
  }

  // Verdict: slope of RSS over the second half of the samples (warm-up = first half),
  // with the growth the design allows shown next to it: the trajectory's buffer
  // (one TrajectoryEntry per tracked frame; it grows by doubling, and glibc keeps
  // the old buffer as free heap, so RSS steps with its capacity) and one archived
  // point per new voxel, and the dormant points kept for reuse until their cap.
  std::vector<double> x, y, ym, yt, yd;
  for (std::size_t i = samples.size() / 2; i < samples.size(); ++i) {
    x.push_back(samples[i].wall_min);
    y.push_back(samples[i].rss_mb);
    ym.push_back(static_cast<double>(samples[i].map_points));
    yt.push_back(samples[i].trajectory_mb);
    yd.push_back(static_cast<double>(samples[i].dormant));
  }
  const double rss_slope = slope(x, y);      // MB per wall minute
  const double points_slope = slope(x, ym);  // map points per wall minute
  const double traj_mb_per_min = slope(x, yt);
  const double points_mb_per_min = points_slope * 64.0 / (1024.0 * 1024.0);  // ~64 B per point (archive + voxel index)
  // A dormant point: the struct plus the deque's share of its blocks.
  const double dormant_mb_per_min = slope(x, yd) * (sizeof(ve::map::DormantLandmark) + 8.0) / (1024.0 * 1024.0);
  const double unexplained =
      rss_slope - traj_mb_per_min - std::max(0.0, points_mb_per_min) - std::max(0.0, dormant_mb_per_min);
  const double rss_end = samples.back().rss_mb;
  const double span_min = x.empty() ? 0.0 : x.back() - x.front();
  // Flat: the second half grew by less than max(1 MB, 1 % of RSS).
  const bool enough = samples.size() >= 6;
  const double growth_mb = rss_slope * span_min;
  const bool flat = enough && growth_mb < std::max(1.0, 0.01 * rss_end);
  const bool explained = enough && !flat && unexplained * span_min < std::max(1.0, 0.01 * rss_end);
  std::printf("\n# %llu frames (%.1f sequence minutes) in %.1f wall minutes, %llu tracked (%.1f %%), %d init "
              "retries, %llu non-finite poses, largest trajectory step %.3f map units\n",
              static_cast<unsigned long long>(frames), static_cast<double>(frames) / seq.rate_hz / 60.0,
              samples.back().wall_min, static_cast<unsigned long long>(tracked),
              100.0 * static_cast<double>(tracked) / static_cast<double>(frames), system.initRetries(),
              static_cast<unsigned long long>(nonfinite), max_step);
  std::printf("# RSS: start %.1f MB, second-half start %.1f MB, end %.1f MB; second-half slope %.3f MB/min "
              "(trajectory growth %.3f MB/min, map points %+.0f /min ~ %.3f MB/min, dormant points %.3f MB/min, "
              "unexplained %.3f MB/min)\n",
              samples.front().rss_mb, y.empty() ? 0.0 : y.front(), rss_end, rss_slope, traj_mb_per_min, points_slope,
              points_mb_per_min, dormant_mb_per_min, unexplained);
  std::printf("# verdict: %s (second half: %+.2f MB over %.1f min)\n",
              !enough     ? "too few samples for a verdict (run longer or sample more often)"
              : flat      ? "memory FLAT after warm-up"
              : explained ? "memory GROWING after warm-up, as designed (trajectory + map archive and dormant "
                            "points, bounded by map.max_archive_points and map.max_dormant_landmarks)"
                          : "memory GROWING after warm-up beyond the trajectory and the map archive (leak?)",
              growth_mb, span_min);
  std::printf("{\"frames\": %llu, \"wall_minutes\": %.2f, \"tracked\": %llu, \"init_retries\": %d, "
              "\"nonfinite_poses\": %llu, \"max_step\": %.4f, \"rss_start_mb\": %.1f, \"rss_end_mb\": %.1f, "
              "\"rss_slope_mb_per_min\": %.4f, \"unexplained_mb_per_min\": %.4f, \"map_points\": %zu, \"flat\": %s, "
              "\"growth_explained\": %s}\n",
              static_cast<unsigned long long>(frames), samples.back().wall_min,
              static_cast<unsigned long long>(tracked), system.initRetries(),
              static_cast<unsigned long long>(nonfinite), max_step, samples.front().rss_mb, rss_end, rss_slope,
              unexplained, samples.back().map_points, flat ? "true" : "false", flat || explained ? "true" : "false");
  return nonfinite > 0 ? 1 : 0;
} catch (const std::exception& e) {
  vitamin_e::cli::fail(e.what());
}
