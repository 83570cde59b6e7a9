// vitamin_e_run: runs VITAMIN-E SLAM offline over a dataset, as fast as possible.
//   vitamin_e_run --dataset PATH --out DIR [--config YAML] [--calib FILE] [--topic T]
//                 [--max-frames N] [--start-frame N] [--stride N] [--quiet] [--check]
//                 [--load-map FILE [--localization-only]] [--save-map FILE]
//                 [--load-tsdf FILE] [--save-tsdf FILE]
// PATH: EuRoC ASL folder (top, mav0/ or mav0/cam0/), TUM folder, KITTI odometry
// folder, or a .bag (ROS builds). Writes DIR/trajectory.txt (TUM, T_w_c),
// DIR/stats.json and DIR/points.ply (and the map / TSDF files asked for).
// SIGINT/SIGTERM stop after the current frame and still write everything. Bad
// input (a damaged or foreign map file too): one "error: ..." line, exit code 2.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "cli.h"
#include "vitamin_e/common/allocator.h"
#include "vitamin_e/fusion/dense_mapper.h"
#include "vitamin_e/io/dataset.h"
#include "vitamin_e/io/frame_prefetcher.h"
#include "vitamin_e/io/run_report.h"
#include "vitamin_e/map/map_file.h"
#include "vitamin_e/pipeline/dense_input.h"
#include "vitamin_e/pipeline/pipelined_system.h"
#include "vitamin_e/pipeline/session.h"
#include "vitamin_e/pipeline/session_runner.h"
#include "vitamin_e/pipeline/system.h"
#ifdef VITAMIN_E_WITH_ROS
#include "vitamin_e/ros/bag_dataset.h"
#endif

namespace fs = std::filesystem;
namespace io = vitamin_e::io;
namespace pl = vitamin_e::pipeline;

namespace {

const char* const kUsage =
    "usage: vitamin_e_run --dataset PATH --out DIR [--config YAML] [--calib FILE] [--topic T]\n"
    "                     [--max-frames N] [--start-frame N] [--stride N] [--quiet] [--check]\n"
    "                     [--load-map FILE [--localization-only]] [--save-map FILE]\n"
    "                     [--load-tsdf FILE] [--save-tsdf FILE]\n"
    "  --dataset PATH   EuRoC ASL folder (top, mav0/ or mav0/cam0/), TUM folder (rgb.txt),\n"
    "                   KITTI odometry folder (image_0/ or image_l/, calib.txt) or a .bag\n"
    "  --out DIR        output folder: trajectory.txt (TUM, T_w_c), stats.json, points.ply\n"
    "  --config YAML    system configuration (default: built-in defaults)\n"
    "  --calib FILE     calibration (EuRoC sensor.yaml, Kalibr camchain, ROS camera_info yaml,\n"
    "                   KITTI calib.txt); required for bags and TUM folders without camera.yaml\n"
    "  --topic T        image topic of a bag (default /cam0/image_raw)\n"
    "  --max-frames N   process at most N frames (with --stride: frames start .. start+N-1 of the input)\n"
    "  --start-frame N  skip the first N frames\n"
    "  --stride N       process every Nth frame only (default 1): a camera that drops frames, or a\n"
    "                   slower frame rate, with the same images\n"
    "  --quiet          no progress and no summary\n"
    "  --pipelined      tracking and mapping on two threads (frame k+1 is tracked while k is mapped),\n"
    "                   images decoded ahead, frame meshes made on a thread of their own;\n"
    "                   default: sequential, deterministic (one thread; the TSDF fusion has its own)\n"
    "  --log-frames     print one line per frame on stdout: index, time, state, tracks, mapped, ms,\n"
    "                   the frame's counters (see below), message\n"
    "  --print-config   print every SLAM parameter in force (defaults + --config), as a config file, and exit\n"
    "  --print-config-markdown  print the configuration reference (docs/CONFIG.md: every key, its\n"
    "                   default and meaning) and exit\n"
    "  --check          no SLAM: read every frame and print 'index timestamp WxH mean' lines\n"
    "                   on stdout (a dataset check; --out is not needed)\n"
    "  --load-map FILE  start in this map (a --save-map file of the same camera): the camera is found\n"
    "                   in it by relocalization, no initialization; poses are in its frame and scale.\n"
    "                   Without --localization-only the map is extended (new keyframes and points)\n"
    "  --localization-only  with --load-map: localize in the map without changing it (no keyframes,\n"
    "                   no points, points not moved; never a new map); the file is not written\n"
    "  --save-map FILE  write the map at the end (also after SIGINT), atomically; may be --load-map's\n"
    "  --load-tsdf FILE start the dense reconstruction from this TSDF (a --save-tsdf file of a run in\n"
    "                   the same map): the mesh of the mapped place is there from the start\n"
    "  --save-tsdf FILE write the TSDF voxel blocks at the end\n"
    "counters of --log-frames (pipeline::FrameDiagnostics; summarized in stats.json frame_diagnostics):\n"
    "  born=N lost=N(reason:N,...) dropped=N prior=N  tracks detected / ended by the tracker (by its\n"
    "                   check) / ended by the back end (outliers) / found again from their map point\n"
    "                   seen from the predicted pose after the flow lost them, this frame\n"
    "  prev_map=T/P left=L in_view=V(reason:N,...)  of the P map points of the previous frame T are\n"
    "                   still tracked; of the ended ones L project outside the image at this pose, V\n"
    "                   inside; all ended ones by the tracker's check (dropped: by the back end)\n"
    "  pose=I/N reuse=R P3P inliers of N map points; map points taken over by new tracks\n"
    "  kf=0|1 kf_par=PX keyframe inserted; rotation-compensated median parallax to the last keyframe [px]\n"
    "  tri=N(reason:N,...)  new map points made (and refused, by check) at the keyframe\n"
    "  cand=N/N2 cand_par=DEG kfs=K  unmapped tracks seen by an older keyframe (N2: by two or more),\n"
    "                   the median angle of their rays since the first keyframe after their detection,\n"
    "                   keyframes in the window\n"
    "  reloc=OUTCOME:I/M  relocalization tried: relocalized, not_found or did_not_hold, P3P inliers\n"
    "                   of M descriptor matches (only on relocalizing frames)\n"
    "  ground=H/I scale=F  ground.enabled, at keyframes: camera height above the road plane (map units,\n"
    "                   I road points) and the factor the map was scaled by (only when a plane was found)\n";

volatile std::sig_atomic_t g_stop = 0;
extern "C" void onSignal(int) { g_stop = 1; }

void installSignalHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sa.sa_flags = SA_RESETHAND;  // a second signal ends the process the default way
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

using vitamin_e::cli::fail;

std::string formatCounts(const std::map<std::string, int>& counts) {
  std::string out;
  for (const auto& [k, n] : counts) out += (out.empty() ? "" : ",") + k + ":" + std::to_string(n);
  return out;
}

// One frame's FrameDiagnostics as the key=value tokens of --log-frames (see kUsage).
std::string formatDiagnostics(const pl::FrameDiagnostics& d) {
  char buf[640];
  std::snprintf(
      buf, sizeof(buf),
      "born=%d lost=%d(%s) dropped=%d prior=%d prev_map=%zu/%zu left=%zu in_view=%zu(%s) pose=%d/%d reuse=%d kf=%d "
      "kf_par=%.1f tri=%d(%s) cand=%zu/%zu cand_par=%.2f kfs=%zu",
      d.tracks_born, d.tracks_lost, formatCounts(d.lost_by).c_str(), d.tracks_dropped, d.tracks_from_prior,
      d.prev_map_tracked, d.prev_map_points, d.prev_map_left_view, d.prev_map_lost_in_view,
      formatCounts(d.prev_map_lost_by).c_str(), d.pose_inliers, d.pose_points, d.reused, d.keyframe ? 1 : 0,
      d.keyframe_parallax_px, d.triangulated, formatCounts(d.triangulation_rejected_by).c_str(), d.candidates,
      d.candidates_two_keyframes, d.candidate_parallax_deg, d.keyframes);
  std::string out = buf;
  if (d.relocalization != pl::RelocalizationOutcome::kNotTried) {
    out += std::string(" reloc=") + pl::toString(d.relocalization) + ":" + std::to_string(d.relocalization_inliers) +
           "/" + std::to_string(d.relocalization_matches);
  }
  if (d.ground_height > 0.0) {
    char g[96];
    std::snprintf(g, sizeof(g), " ground=%.4f/%d scale=%.4f", d.ground_height, d.ground_inliers, d.scale_correction);
    out += g;
  }
  return out;
}

// The per-frame counters summarized in stats.json (frame_diagnostics).
void addCounters(const pl::FrameResult& r, io::RunStats* stats) {
  const pl::FrameDiagnostics& d = r.diagnostics;
  stats->addCounter("tracks_born", d.tracks_born);
  stats->addCounter("tracks_lost", d.tracks_lost);
  for (const auto& [why, n] : d.lost_by) stats->addCounter("tracks_lost_by_" + why, n);
  stats->addCounter("tracks_dropped", d.tracks_dropped);
  stats->addCounter("tracks_from_prior", d.tracks_from_prior);
  if (d.prev_map_points > 0) {
    stats->addCounter("prev_map_tracked_fraction", d.prevMapTrackedFraction());
    stats->addCounter("prev_map_left_view", static_cast<double>(d.prev_map_left_view));
    stats->addCounter("prev_map_lost_in_view", static_cast<double>(d.prev_map_lost_in_view));
    for (const auto& [why, n] : d.prev_map_lost_by) stats->addCounter("prev_map_lost_by_" + why, n);
  }
  if (d.pose_points > 0) {
    stats->addCounter("pose_points", d.pose_points);
    stats->addCounter("pose_inliers", d.pose_inliers);
  }
  if (r.pose_valid) {
    stats->addCounter("mapped_tracks", static_cast<double>(r.num_mapped));
    stats->addCounter("reused", d.reused);
    stats->addCounter("keyframe", d.keyframe ? 1.0 : 0.0);
    stats->addCounter("window_ba_deferred", d.window_ba_deferred ? 1.0 : 0.0);
    stats->addCounter("candidates", static_cast<double>(d.candidates));
    stats->addCounter("candidate_parallax_deg", d.candidate_parallax_deg);
  }
  stats->addCounter("triangulated", d.triangulated);
  for (const auto& [why, n] : d.triangulation_rejected_by) stats->addCounter("triangulation_rejected_by_" + why, n);
  if (d.relocalization != pl::RelocalizationOutcome::kNotTried) {
    stats->addCounter("relocalization_attempts", 1.0);
    stats->addCounter("relocalization_succeeded",
                      d.relocalization == pl::RelocalizationOutcome::kRelocalized ? 1.0 : 0.0);
  }
  ++stats->frames_by_state[pl::toString(r.state)];
  ++stats->frames_by_reason[pl::toString(r.reason)];
}

struct Options {
  std::string dataset, out, config, calib, topic = "/cam0/image_raw";
  std::size_t max_frames = 0;  // 0 = all
  std::size_t start_frame = 0;
  std::size_t stride = 1;
  bool quiet = false;
  bool check = false;
  bool print_config = false;
  bool print_reference = false;
  bool log_frames = false;
  bool pipelined = false;
  std::string load_map, save_map, load_tsdf, save_tsdf;
  bool localization_only = false;
};

Options parseArgs(int argc, char** argv) {
  Options o;
  vitamin_e::cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.flag("--quiet", &o.quiet) || args.flag("-q", &o.quiet) || args.flag("--check", &o.check) ||
        args.flag("--pipelined", &o.pipelined) || args.flag("--log-frames", &o.log_frames) ||
        args.flag("--print-config", &o.print_config) || args.flag("--print-config-markdown", &o.print_reference) ||
        args.flag("--localization-only", &o.localization_only) || args.value("--dataset", &o.dataset) ||
        args.value("--out", &o.out) || args.value("--config", &o.config) || args.value("--calib", &o.calib) ||
        args.value("--topic", &o.topic) || args.value("--max-frames", &o.max_frames) ||
        args.value("--start-frame", &o.start_frame) || args.value("--stride", &o.stride) ||
        args.value("--load-map", &o.load_map) || args.value("--save-map", &o.save_map) ||
        args.value("--load-tsdf", &o.load_tsdf) || args.value("--save-tsdf", &o.save_tsdf)) {
      continue;
    }
    args.unknown();
  }
  if (o.print_config || o.print_reference) return o;
  if (o.dataset.empty()) fail("--dataset PATH is required (see --help)");
  if (o.out.empty() && !o.check) fail("--out DIR is required (see --help)");
  if (o.stride == 0) fail("--stride needs a positive integer (1 = every frame)");
  if (o.localization_only && o.load_map.empty())
    fail("--localization-only needs --load-map FILE (a map to localize in)");
  if (o.localization_only && !o.save_map.empty()) {
    fail("--localization-only does not change the map: --save-map cannot be used with it");
  }
  return o;
}

std::unique_ptr<io::Dataset> openInput(const Options& o) {
  io::DatasetOptions dopt;
  dopt.calibration_path = o.calib;
  dopt.bag_topic = o.topic;
#ifdef VITAMIN_E_WITH_ROS
  return vitamin_e_ros::openAnyDataset(o.dataset, dopt);
#else
  if (io::detectDatasetKind(o.dataset) == "rosbag")
    throw io::DatasetError("'" + o.dataset + "' is a rosbag but this build has no ROS layer");
  return io::openDataset(o.dataset, dopt);
#endif
}

pl::SystemConfig loadConfig(const std::string& path) {
  if (path.empty()) {
    pl::SystemConfig config;
    config.validate();
    return config;
  }
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw pl::ConfigError("file '" + path + "' does not exist");
  return pl::loadSystemConfig(path);
}

// Progress: a bar redrawn in place on a terminal, a plain line every ~5 s otherwise.
class Progress {
 public:
  Progress(std::size_t total, bool quiet) : total_(total), quiet_(quiet), tty_(::isatty(2) == 1) {}
  void update(std::size_t done, std::size_t tracked, bool force = false) {
    if (quiet_) return;
    const double now = vitamin_e::elapsedMs(start_) / 1000.0;
    if (!force && now - last_ < (tty_ ? 0.1 : 5.0)) return;
    last_ = now;
    const double ratio = done ? static_cast<double>(tracked) / static_cast<double>(done) : 0.0;
    if (tty_) {
      std::fprintf(stderr, "\r%s\033[K", io::formatProgress(done, total_, now, ratio, 30).c_str());
    } else {
      std::fprintf(stderr, "[vitamin_e_run] %s\n", io::formatProgress(done, total_, now, ratio, 0).c_str());
    }
    std::fflush(stderr);
  }
  void finish(std::size_t done, std::size_t tracked) {
    update(done, tracked, true);
    if (!quiet_ && tty_) std::fputc('\n', stderr);
  }
  void warn(const std::string& msg) {
    if (tty_ && !quiet_) std::fputs("\r\033[K", stderr);
    std::fprintf(stderr, "warning: %s\n", msg.c_str());
  }

 private:
  std::size_t total_;
  bool quiet_, tty_;
  vitamin_e::TimingClock::time_point start_ = vitamin_e::TimingClock::now();
  double last_ = -1e9;
};

// --check: reads every frame of [begin, end) and prints one line per frame.
int checkFrames(const io::Dataset& dataset, std::size_t begin, std::size_t end) {
  std::size_t bad = 0;
  for (std::size_t i = begin; i < end && !g_stop; ++i) {
    try {
      const cv::Mat img = dataset.loadImage(i);
      std::printf("%zu %s %dx%d %.2f\n", i, dataset.timestampText(i).c_str(), img.cols, img.rows, cv::mean(img)[0]);
    } catch (const io::DatasetError& e) {
      std::fprintf(stderr, "warning: %s (frame %zu)\n", e.what(), i);
      ++bad;
    }
  }
  std::fflush(stdout);
  std::fprintf(stderr, "[vitamin_e_run] %s: %zu frames checked, %zu unreadable; calibration (%s): %s\n",
               dataset.kind().c_str(), end - begin, bad, dataset.calibration().format.c_str(),
               dataset.calibration().camera.describe().c_str());
  return 0;
}

int run(const Options& o) {
  if (o.print_reference) {
    std::cout << pl::configReferenceMarkdown();
    return 0;
  }
  const pl::SystemConfig config = o.check ? pl::SystemConfig{} : loadConfig(o.config);
  if (o.print_config) {
    std::cout << config.describe();
    return 0;
  }
  const std::unique_ptr<io::Dataset> dataset = openInput(o);
  if (o.start_frame >= dataset->size()) {
    fail("--start-frame " + std::to_string(o.start_frame) + " is past the end of '" + o.dataset + "' (" +
         std::to_string(dataset->size()) + " frames)");
  }
  std::size_t end = dataset->size();
  if (o.max_frames > 0) end = std::min(end, o.start_frame + o.max_frames);
  if (o.check) return checkFrames(*dataset, o.start_frame, end);

  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec || !fs::is_directory(o.out, ec)) fail("cannot create output folder '" + o.out + "'");
  const std::string traj_path = (fs::path(o.out) / "trajectory.txt").string();
  const std::string stats_path = (fs::path(o.out) / "stats.json").string();
  const std::string ply_path = (fs::path(o.out) / "points.ply").string();
  if (!std::ofstream(stats_path)) fail("output folder '" + o.out + "' is not writable");

  const vitamin_e::camera::CameraCalibration& calib = dataset->calibration();
  if (!o.quiet) {
    std::fprintf(stderr, "[vitamin_e_run] %s dataset '%s': %zu frames, processing %zu..%zu%s\n",
                 dataset->kind().c_str(), o.dataset.c_str(), dataset->size(), o.start_frame, end - 1,
                 o.stride > 1 ? (", every " + std::to_string(o.stride) + "th").c_str() : "");
    std::fprintf(stderr, "[vitamin_e_run] camera (%s): %s\n", calib.format.c_str(), calib.camera.describe().c_str());
  }
  std::unique_ptr<vitamin_e::fusion::DenseMapper> dense;
  if (config.dense_enabled) {
    dense = std::make_unique<vitamin_e::fusion::DenseMapper>(config.dense,
                                                             vitamin_e::meshing::pinholeImageOf(calib.camera));
  }
  if ((!o.load_tsdf.empty() || !o.save_tsdf.empty()) && !dense) {
    fail("--load-tsdf / --save-tsdf need the dense reconstruction (dense_enabled is false in the config)");
  }
  if (!o.load_tsdf.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      dense->loadTsdf(o.load_tsdf);
    } catch (const vitamin_e::fusion::TsdfFileError& e) {
      fail(e.what());
    }
    if (!o.quiet) {
      std::fprintf(stderr, "[vitamin_e_run] TSDF '%s' loaded in %.0f ms\n", o.load_tsdf.c_str(),
                   vitamin_e::elapsedMs(t0));
    }
  }
  pl::DenseInput dense_input;

  io::RunStats stats;
  stats.dataset = o.dataset;
  stats.dataset_kind = dataset->kind();
  stats.config = o.config;
  stats.loaded_map = o.load_map;
  stats.localization_only = o.localization_only;
  stats.stride = o.stride;
  const std::size_t frames_to_process = (end - o.start_frame + o.stride - 1) / o.stride;
  Progress progress(frames_to_process, o.quiet);
  const auto t_start = vitamin_e::TimingClock::now();
  std::size_t attempted = 0;
  // CPU time of each stage on its thread [ms, summed over the run]: stats.json cpu_ms.
  double cpu_load = 0.0, cpu_mesh = 0.0;
  // Everything done with a frame's result: stats, progress, per-frame log, dense
  // mapping. Runs on the main thread (sequential) or the mapping thread
  // (--pipelined), never on both.
  std::mutex result_mutex;
  auto handle_result = [&](const pl::FrameResult& r) {
    const double cpu0 = vitamin_e::threadCpuMs();
    std::lock_guard<std::mutex> lock(result_mutex);
    std::vector<std::pair<std::string, double>> stages(r.timing_ms.begin(), r.timing_ms.end());
    const double total_ms = r.timing_ms.count("total") ? r.timing_ms.at("total") : 0.0;
    if (o.log_frames) {
      std::printf("%llu %.9f %s %zu %zu %.1f %s %s\n", static_cast<unsigned long long>(r.frame_index), r.timestamp,
                  pl::toString(r.state), r.num_tracked, r.num_mapped, total_ms,
                  formatDiagnostics(r.diagnostics).c_str(), r.message.c_str());
    }
    addCounters(r, &stats);
    if (dense) {
      // Sequential: per-frame mesh + NLTGV here. Pipelined: on the dense mapper's
      // meshing thread, off the SLAM's. TSDF fusion runs on the integrator's thread.
      // Every result goes in, points or not: it carries the map's rescales.
      if (o.pipelined) {
        dense->submitFrame(dense_input.next(r));
      } else {
        const vitamin_e::fusion::DenseFrameStats ds = dense->addFrame(dense_input.next(r));
        if (ds.integrated) stages.emplace_back("mesh", ds.mesh_ms + ds.denoise_ms);
      }
    }
    stats.addFrame(r.pose_valid, r.num_tracked, r.num_mapped, stages, total_ms);
    progress.update(stats.frames, stats.tracked_frames);
    // Sequential: the mesh is made here on the main thread (with the stats' bookkeeping).
    if (!o.pipelined) cpu_mesh += vitamin_e::threadCpuMs() - cpu0;
  };
  // A session, as the ROS tracker runs it (stamps jumping back, e.g. a bag of two recordings,
  // start a new trajectory segment relocalized in the same map), on this thread or pipelined.
  pl::RunnerOptions runner_options;
  runner_options.pipelined = o.pipelined;
  runner_options.queue_frames = 2;  // a frame waiting for each stage: the reader never drops one
  pl::SessionRunner runner(config, calib.camera, {}, runner_options,
                           [&](pl::FrameResult&& r, std::uint64_t) { handle_result(r); });
  if (!o.load_map.empty()) {
    // Before the first frame: the system starts relocalizing in the loaded map.
    pl::System& system = runner.system();
    const auto t0 = std::chrono::steady_clock::now();
    vitamin_e::map::MapFileContents contents;
    try {
      contents = vitamin_e::map::loadMapFile(o.load_map);
      system.loadMap(contents);
    } catch (const vitamin_e::map::MapFileError& e) {
      fail(e.what());
    } catch (const std::invalid_argument& e) {
      fail("map file '" + o.load_map + "': " + e.what());
    }
    system.setLocalizationOnly(o.localization_only);
    if (!o.quiet) {
      std::fprintf(stderr, "[vitamin_e_run] %s: %s, loaded in %.0f ms%s\n", o.load_map.c_str(),
                   vitamin_e::map::mapFileHeader(contents).c_str(), vitamin_e::elapsedMs(t0),
                   o.localization_only ? " (localization only)" : "");
    }
  }
  auto skip_unreadable = [&](const std::string& why, std::size_t i) {
    std::lock_guard<std::mutex> lock(result_mutex);
    progress.warn(why + " (frame " + std::to_string(i) + " skipped)");
    ++stats.skipped_frames;
  };
  unsigned dense_map = runner.session().map();
  // A frame to the session: its stamp checked (a time jump starts a trajectory segment), then the
  // SLAM. A frame out of order goes on to the system, which skips it and says so in its result.
  auto process = [&](const cv::Mat& image, std::size_t i, double t, const std::string& text) {
    const pl::SessionStamp stamp = runner.admit(t);  // a time jump finishes the frames before it
    if (stamp.time_jump) {
      if (runner.session().map() != dense_map) {  // a new map: its own world and scale
        dense_map = runner.session().map();
        dense_input.reset();
        if (dense) dense->reset();
      }
      if (!o.quiet) {
        std::lock_guard<std::mutex> lock(result_mutex);
        progress.warn(runner.session().segmentNote() + ": trajectory segment " +
                      std::to_string(runner.session().segment()));
      }
    }
    runner.process(image, t, text, i);
  };
  if (o.pipelined) {
    // The images are decoded ahead on a thread of their own.
    io::FramePrefetcher ahead(*dataset, o.start_frame, end, o.stride, 3);
    while (!g_stop) {
      std::optional<io::PrefetchedFrame> f = ahead.next();
      if (!f) break;
      ++attempted;
      cpu_load += f->load_cpu_ms;
      if (f->image.empty()) {
        skip_unreadable(f->error, f->index);
        continue;
      }
      {
        std::lock_guard<std::mutex> lock(result_mutex);
        stats.timing.add("image_load", f->load_ms);
      }
      process(f->image, f->index, f->timestamp, f->timestamp_text);
    }
  } else {
    for (std::size_t i = o.start_frame; i < end && !g_stop; i += o.stride) {
      ++attempted;
      cv::Mat image;
      const auto t_load = vitamin_e::TimingClock::now();
      const double cpu0 = vitamin_e::threadCpuMs();
      try {
        image = dataset->loadImage(i);
      } catch (const io::DatasetError& e) {
        skip_unreadable(e.what(), i);
        continue;
      }
      stats.timing.add("image_load", vitamin_e::elapsedMs(t_load));
      cpu_load += vitamin_e::threadCpuMs() - cpu0;
      process(image, i, dataset->timestamp(i), dataset->timestampText(i));
    }
  }
  runner.flush();
  // The run ends when the dense reconstruction has caught up with the SLAM.
  if (dense) dense->flush();
  const pl::System& system = runner.system();
  progress.finish(attempted, stats.tracked_frames);
  stats.interrupted = g_stop != 0;
  stats.wall_time_s = vitamin_e::elapsedMs(t_start) / 1000.0;
  if (dense) {
    const vitamin_e::fusion::DenseWorkStats work = dense->workStats();
    if (work.failed > 0) {
      progress.warn(std::to_string(work.failed) + " frame(s) not meshed (the last: " + work.last_failure + ")");
    }
    stats.timing.addStage("mesh", dense->meshTimings());
    cpu_mesh += work.mesh_cpu_ms;
    const vitamin_e::fusion::TsdfIntegratorStats fused = dense->integratorStats();
    stats.dense_fused = fused.integrated;
    stats.dense_dropped = fused.dropped;
    stats.dense_raster_downscale = fused.raster_downscale_frames;
    if (fused.integrated > 0) stats.cpu_ms["tsdf"] = fused.integration_cpu_ms;
    if (o.pipelined) stats.cpu_ms["mesh"] = cpu_mesh;
  }
  stats.cpu_ms["image_load"] = cpu_load;
  const pl::PipelinedSystem::StageCpu cpu = runner.stageCpuMs();
  stats.cpu_ms["tracking"] = cpu.tracking_ms;
  stats.cpu_ms["mapping"] = cpu.mapping_ms;
  if (!o.pipelined && dense) stats.cpu_ms["mesh"] = cpu_mesh;
  for (auto& [stage, ms] : stats.cpu_ms) ms /= static_cast<double>(std::max<std::size_t>(1, stats.frames));
  stats.init_retries = runner.session().initRetries();
  stats.relocalizations = runner.session().relocalizations();
  // Frames seen while initializing are localized once the map exists: the
  // system's count (= trajectory poses) is the number of tracked frames.
  stats.tracked_frames = runner.session().framesTracked();
  stats.first_init_frame = system.firstInitFrame();
  stats.tracked_since_init = system.framesTrackedSinceInit();
  stats.reused_map_points = system.reusedMapPoints();

  std::string err;
  const std::vector<pl::MapPoint3> points = system.mapPoints();
  stats.map_points = points.size();
  // One segment: the plain TUM file; more (time jumps): each after its "# segment" line.
  const std::vector<pl::TrajectorySegment> segments = runner.session().segments();
  bool ok = segments.size() > 1 ? pl::saveSegmentsTum(segments, "T_w_c", traj_path, &err)
                                : pl::saveTrajectoryTum(system.trajectory(), traj_path, &err);
  if (ok) ok = pl::saveMapPly(points, ply_path, &err);
  const std::string mesh_path = (fs::path(o.out) / "mesh.ply").string();
  if (ok && dense) ok = dense->saveMesh(mesh_path, &err);
  if (ok && !o.save_tsdf.empty()) ok = dense->saveTsdf(o.save_tsdf, &err);
  if (ok && !o.save_map.empty()) ok = system.saveMap(o.save_map, &err);
  stats.peak_rss_mb = io::peakRssMb();
  if (ok) ok = io::writeRunStats(stats, stats_path, &err);
  if (!ok) fail(err);

  if (!o.quiet) {
    if (stats.interrupted) std::fprintf(stderr, "[vitamin_e_run] interrupted: outputs hold the frames so far\n");
    std::fprintf(stderr,
                 "[vitamin_e_run] %zu frames, %zu tracked (%.1f%%), %zu skipped, %d init retries, %d relocalizations, "
                 "%zu map points\n",
                 stats.frames, stats.tracked_frames, 100.0 * stats.successRate(), stats.skipped_frames,
                 stats.init_retries, stats.relocalizations, stats.map_points);
    std::fprintf(stderr, "%s", stats.timing.table(io::reportStages(stats.timing)).c_str());
    std::fprintf(stderr, "[vitamin_e_run] wrote %s, %s, %s%s%s (peak RSS %.0f MB)\n", traj_path.c_str(),
                 stats_path.c_str(), ply_path.c_str(), dense ? ", " : "", dense ? mesh_path.c_str() : "",
                 stats.peak_rss_mb);
    if (!o.save_map.empty()) {
      std::fprintf(stderr, "[vitamin_e_run] map: %s written to %s\n",
                   vitamin_e::map::mapFileHeader(system.exportMap()).c_str(), o.save_map.c_str());
    }
    if (!o.save_tsdf.empty()) std::fprintf(stderr, "[vitamin_e_run] TSDF written to %s\n", o.save_tsdf.c_str());
  }
  if (stats.frames == 0 && !stats.interrupted) {
    fail("no frame of '" + o.dataset + "' could be read (" + std::to_string(stats.skipped_frames) + " skipped)");
  }
  if (stats.frames > 0 && stats.tracked_frames == 0) {
    std::fprintf(stderr, "warning: no frame was tracked: %s is empty\n", traj_path.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parseArgs(argc, argv);
  installSignalHandlers();
  const vitamin_e::AllocatorSetting allocator = vitamin_e::reuseFreedFrameBuffers();
  if (!allocator.applied && !options.quiet) std::fprintf(stderr, "warning: %s\n", allocator.what.c_str());
  try {
    return run(options);
  } catch (const io::DatasetError& e) {
    fail(e.what());
  } catch (const vitamin_e::camera::CalibrationError& e) {
    fail(e.what());
  } catch (const pl::ConfigError& e) {
    fail(std::string("config: ") + e.what());
  } catch (const std::exception& e) {
    fail(e.what());
  }
}
