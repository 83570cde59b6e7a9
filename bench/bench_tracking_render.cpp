// Benchmark of the dense curvature-extrema tracker against OpenCV KLT on a
// render of /work/shared/tools/render_sequence.py, with exact ground truth:
// the 3D point behind a tracked pixel of frame k-1 (undistort, ray-cast into the
// scene's room and boxes) is projected (with distortion) into frame k; a track
// step is an inlier when it lands within 1 px of that reprojection.
//   bench_tracking_render RENDER_DIR [--start K] [--frames N] [--max-points N] [--threads N] [--per-frame 1]
//   (--help lists every option)
// --per-frame 1 prints per frame (stderr) the tracked/new counts, the frame's
// curvature scale, median strength ratio and patch gain, the losses by check and
// the steps' precision: run it on an exposure step (exposure.csv of the render)
// with --start N --frames N. --relative-strength 0 --floor-follows 0 --align-gain 0
// give the tracker of before the exposure-step handling.
// Track length is given three ways: over every track ever started (most new
// extrema end at their first step, so this median is 1-2), over the tracks that
// survived their first step, and as the median age of the tracked points of a
// frame (what the back end sees).
// Prints a table and, as the last line, a JSON summary.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "cli.h"
#include "vitamin_e/camera/camera.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/tracking/dense_tracker.h"

namespace {

namespace vt = vitamin_e::tracking;

// ---- camera: the render's calibration through the camera module ----
struct LensModel {
  vitamin_e::camera::Camera cam;
  int w = 0, h = 0;
  Eigen::Vector2d distort(const Eigen::Vector2d& n) const { return cam.distortNormalized(n); }
  bool undistort(const Eigen::Vector2d& uv, Eigen::Vector2d* n) const { return cam.unprojectNormalized(uv, n); }
};

// ---- scene: room (seen from inside) + axis-aligned boxes (seen from outside) ----
struct Aabb {
  Eigen::Vector3d lo, hi;
};
struct Scene {
  Aabb room;
  std::vector<Aabb> boxes;
  // Distance along unit ray d from o to the nearest surface; < 0 if none.
  double cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
    double best = 1e30;
    double t_exit = 1e30;
    for (int a = 0; a < 3; ++a) {
      if (std::fabs(d[a]) < 1e-12) continue;
      const double t = d[a] > 0 ? (room.hi[a] - o[a]) / d[a] : (room.lo[a] - o[a]) / d[a];
      t_exit = std::min(t_exit, t);
    }
    if (t_exit > 0) best = t_exit;
    for (const Aabb& b : boxes) {
      double t0 = -1e30, t1 = 1e30;
      bool miss = false;
      for (int a = 0; a < 3 && !miss; ++a) {
        if (std::fabs(d[a]) < 1e-12) {
          if (o[a] < b.lo[a] || o[a] > b.hi[a]) miss = true;
          continue;
        }
        double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (!miss && t0 <= t1 && t0 > 1e-6) best = std::min(best, t0);
    }
    return best < 1e29 ? best : -1.0;
  }
};

std::vector<double> numbersAfter(const std::string& s, size_t pos, int n) {
  std::vector<double> v;
  pos = s.find('[', pos);
  while (static_cast<int>(v.size()) < n && pos != std::string::npos) {
    pos = s.find_first_of("-0123456789", pos);
    if (pos == std::string::npos) break;
    size_t used = 0;
    v.push_back(std::stod(s.substr(pos, 40), &used));
    pos += used;
  }
  if (static_cast<int>(v.size()) != n) throw std::runtime_error("scene.json: malformed numbers");
  return v;
}

Aabb aabbAt(const std::string& s, size_t pos) {
  const auto lo = numbersAfter(s, s.find("\"min\"", pos), 3);
  const auto hi = numbersAfter(s, s.find("\"max\"", pos), 3);
  return {Eigen::Vector3d(lo[0], lo[1], lo[2]), Eigen::Vector3d(hi[0], hi[1], hi[2])};
}

Scene loadScene(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot open " + path);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string s = ss.str();
  Scene sc;
  sc.room = aabbAt(s, s.find("\"room\""));
  const size_t b0 = s.find("\"boxes\""), b1 = s.find("\"lights\"");
  for (size_t p = s.find("\"min\"", b0); p != std::string::npos && p < b1; p = s.find("\"min\"", p + 5)) {
    sc.boxes.push_back(aabbAt(s, p));
  }
  return sc;
}

std::string nsOfTum(const std::string& t) {  // "1403715284.314640000" -> ns string
  const size_t dot = t.find('.');
  std::string frac = dot == std::string::npos ? "" : t.substr(dot + 1);
  frac.resize(9, '0');
  return t.substr(0, dot) + frac;
}

struct Frame {
  std::string ns, file;
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
};

std::vector<Frame> loadFrames(const std::string& dir) {
  std::map<std::string, Eigen::Isometry3d> gt;
  std::ifstream g(dir + "/groundtruth_cam0_tum.txt");
  std::string line;
  while (std::getline(g, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    std::string ts;
    double tx, ty, tz, qx, qy, qz, qw;
    is >> ts >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(tx, ty, tz);
    gt[nsOfTum(ts)] = T;
  }
  std::vector<Frame> frames;
  std::ifstream c(dir + "/mav0/cam0/data.csv");
  while (std::getline(c, line)) {
    if (line.empty() || line[0] == '#') continue;
    const size_t comma = line.find(',');
    Frame fr;
    fr.ns = line.substr(0, comma);
    fr.file = dir + "/mav0/cam0/data/" + line.substr(comma + 1);
    while (!fr.file.empty() && (fr.file.back() == '\r' || fr.file.back() == ' ')) fr.file.pop_back();
    auto it = gt.find(fr.ns);
    if (it == gt.end()) continue;
    fr.T_w_c = it->second;
    frames.push_back(fr);
  }
  return frames;
}

// Ground-truth reprojection of pixel uv of frame a into frame b; false when
// the point leaves the image, has no surface or is occluded in b.
bool reproject(const LensModel& cam, const Scene& sc, const Frame& a, const Frame& b, const Eigen::Vector2d& uv,
               Eigen::Vector2d* out) {
  Eigen::Vector2d n;
  if (!cam.undistort(uv, &n)) return false;
  const Eigen::Vector3d d = (a.T_w_c.linear() * Eigen::Vector3d(n.x(), n.y(), 1.0)).normalized();
  const Eigen::Vector3d o = a.T_w_c.translation();
  const double t = sc.cast(o, d);
  if (t <= 0) return false;
  const Eigen::Vector3d X = o + t * d;
  const Eigen::Vector3d pc = b.T_w_c.inverse() * X;
  if (pc.z() < 0.05) return false;
  const Eigen::Vector3d ob = b.T_w_c.translation();
  const double dist = (X - ob).norm();
  if (sc.cast(ob, (X - ob) / dist) < dist - 0.01) return false;  // occluded in b
  *out = cam.distort(Eigen::Vector2d(pc.x() / pc.z(), pc.y() / pc.z()));
  return out->x() >= 0 && out->y() >= 0 && out->x() <= cam.w - 1 && out->y() <= cam.h - 1;
}

struct RunStats {
  std::vector<double> points, ms, cpu, lengths;
  long inliers = 0, checked = 0;
  long drift_inliers = 0, drift_checked = 0;  // at age kDriftAge vs the birth observation
  std::vector<double> drift_err;
};

// Accumulated drift: a track aged kDriftAge frames is compared with the
// ground-truth reprojection of its first observation.
constexpr int kDriftAge = 10;

double median(std::vector<double> v) { return vitamin_e::percentile(std::move(v), 50.0); }

}  // namespace

const char* const kUsage =
    "usage: bench_tracking_render RENDER_DIR [options]\n"
    "  RENDER_DIR   a render of render_sequence.py (scene.json, mav0/cam0, ground truth)\n"
    "  --start K    skip the first K frames          --frames N   use at most N frames\n"
    "  --per-frame 0|1   one line per frame on stderr (tracked, new, flow, losses by reason)\n"
    "  --klt 0|1    also run OpenCV KLT (default 1)\n"
    "tracker settings (tracking::TrackerConfig, docs/CONFIG.md section tracker):\n"
    "  --max-points N  --threads N  --lambda X  --min-curvature X  --cell N (grid_cell_px)  --fb X\n"
    "  --sigma X (smoothing_sigma)  --ratio X (max_curvature_ratio)  --refine 0|1  --parallax 0|1\n"
    "  --ksigma X  --polish N  --adaptive 0|1  --max-sigma X  --noise-ref X  --blend X  --nms N\n"
    "  --track-sigma X  --min-track-curvature X  --per-cell N  --track-sharpness X  --extremum-weight X\n"
    "  --align-radius N  --align-iterations N  --disagree X  --confirm-max-unaligned X\n"
    "  --subpixel-strength 0|1  --relative-strength 0|1  --ratio-min-change X  --floor-follows 0|1\n"
    "  --align-gain 0|1  --align-gain-min X\n";

int main(int argc, char** argv) try {
  namespace cli = vitamin_e::cli;
  std::string dir;
  int max_frames = 1 << 30;
  int start_frame = 0;
  bool per_frame = false;
  bool run_klt = true;
  vt::TrackerConfig cfg;
  cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.positional(&dir) || args.value("--frames", &max_frames) || args.value("--start", &start_frame) ||
        args.value("--per-frame", &per_frame) || args.value("--klt", &run_klt) ||
        args.value("--max-points", &cfg.max_points) || args.value("--threads", &cfg.threads) ||
        args.value("--lambda", &cfg.lambda) || args.value("--min-curvature", &cfg.min_curvature) ||
        args.value("--cell", &cfg.grid_cell_px) || args.value("--fb", &cfg.fb_threshold_px) ||
        args.value("--sigma", &cfg.smoothing_sigma) || args.value("--ratio", &cfg.max_curvature_ratio) ||
        args.value("--refine", &cfg.refine_flow) || args.value("--parallax", &cfg.predict_parallax) ||
        args.value("--ksigma", &cfg.kappa_smoothing_sigma) || args.value("--polish", &cfg.polish_steps) ||
        args.value("--adaptive", &cfg.adaptive_smoothing) || args.value("--max-sigma", &cfg.max_smoothing_sigma) ||
        args.value("--noise-ref", &cfg.noise_reference) || args.value("--blend", &cfg.prediction_blend) ||
        args.value("--nms", &cfg.nms_radius_px) || args.value("--track-sigma", &cfg.track_sigma_px) ||
        args.value("--min-track-curvature", &cfg.min_track_curvature) || args.value("--per-cell", &cfg.max_per_cell) ||
        args.value("--track-sharpness", &cfg.min_track_sharpness) ||
        args.value("--extremum-weight", &cfg.extremum_weight) || args.value("--align-radius", &cfg.align_radius_px) ||
        args.value("--align-iterations", &cfg.align_iterations) ||
        args.value("--disagree", &cfg.max_align_disagreement_px) ||
        args.value("--confirm-max-unaligned", &cfg.confirm_max_unaligned_fraction) ||
        args.value("--subpixel-strength", &cfg.strength_at_subpixel_peak) ||
        args.value("--relative-strength", &cfg.relative_strength_change) ||
        args.value("--ratio-min-change", &cfg.strength_ratio_min_change) ||
        args.value("--floor-follows", &cfg.floor_follows_exposure) ||
        args.value("--align-gain-min", &cfg.align_gain_min_change) || args.value("--align-gain", &cfg.align_gain)) {
      continue;
    }
    args.unknown();
  }
  if (dir.empty()) cli::fail("RENDER_DIR is required (see --help)");
  if (!std::ifstream(dir + "/scene.json")) cli::fail(dir + ": not a render (no scene.json)");
  if (max_frames < 2) cli::fail("--frames must be >= 2");
  if (start_frame < 0) cli::fail("--start must be >= 0");
  try {
    cfg.validate();
  } catch (const std::exception& e) {
    cli::fail(e.what());
  }
  LensModel cam;
  cam.cam = vitamin_e::camera::loadEurocSensorYaml(dir + "/mav0/cam0/sensor.yaml").camera;
  cam.w = cam.cam.width();
  cam.h = cam.cam.height();
  const Scene scene = loadScene(dir + "/scene.json");
  std::vector<Frame> frames = loadFrames(dir);
  frames.erase(frames.begin(),
               frames.begin() + static_cast<std::ptrdiff_t>(std::min<size_t>(frames.size(), std::max(0, start_frame))));
  if (static_cast<int>(frames.size()) > max_frames) frames.resize(max_frames);
  if (frames.size() < 2) {
    std::fprintf(stderr, "need >= 2 frames with ground truth\n");
    return 2;
  }
  std::vector<cv::Mat> images;
  images.reserve(frames.size());
  for (const Frame& f : frames) images.push_back(cv::imread(f.file, cv::IMREAD_GRAYSCALE));

  // ---- dense curvature-extrema tracker ----
  RunStats ours;
  vt::DenseTracker tracker(cfg);
  std::unordered_map<std::uint64_t, Eigen::Vector2f> prev;
  std::unordered_map<std::uint64_t, std::pair<Eigen::Vector2f, size_t>> birth;
  std::unordered_map<std::uint64_t, int> life;
  std::vector<double> tracked_pf, flow_ok_pf;
  std::map<std::string, std::vector<double>> stage;
  int min_tracked = 1 << 30;
  long hist[5] = {0, 0, 0, 0, 0};
  std::map<std::string, long> lost_by, lost_new_by;
  long spawned = 0;
  std::vector<double> live_age;  // per frame: median age + 1 of its tracked points (point-weighted length)
  for (size_t k = 0; k < frames.size(); ++k) {
    const auto t0 = vitamin_e::TimingClock::now();
    const double c0 = vitamin_e::processCpuMs();
    const vt::TrackerFrame tf = tracker.track(images[k], std::stod(frames[k].ns) * 1e-9);
    const double ms = vitamin_e::elapsedMs(t0);
    ours.points.push_back(static_cast<double>(tf.points.size()));
    ours.ms.push_back(ms);
    ours.cpu.push_back(vitamin_e::processCpuMs() - c0);
    for (const auto& kv : tf.timing_ms) stage[kv.first].push_back(kv.second);
    stage["(smoothing sigma px)"].push_back(tf.smoothing_sigma);
    stage["(noise ratio)"].push_back(tf.noise_ratio);
    if (k > 0) {
      tracked_pf.push_back(tf.num_tracked);
      flow_ok_pf.push_back(tf.flow_ok);
      min_tracked = std::min(min_tracked, tf.num_tracked);
      for (const auto& kv : tf.lost_by) lost_by[kv.first] += kv.second;
      if (per_frame) {
        std::fprintf(
            stderr,
            "FRAME %zu tracked %d new %d flow_ok %d matches %d b %.1f %.1f sigma %.2f scale %.3g ratio %.3f gain %.3f:",
            k, tf.num_tracked, tf.num_new, tf.flow_ok, tf.flow_matches, tf.b.x(), tf.b.y(), tf.smoothing_sigma,
            tf.curvature_scale, tf.strength_ratio, tf.patch_gain);
        for (const auto& kv : tf.lost_by) std::fprintf(stderr, " %s %d", kv.first.c_str(), kv.second);
        std::fprintf(stderr, "\n");
      }
      for (const auto& kv : tf.lost_new_by) lost_new_by[kv.first] += kv.second;
      std::vector<double> ages;
      ages.reserve(tf.points.size());
      for (const auto& p : tf.points) {
        if (p.age > 0) ages.push_back(p.age + 1);
      }
      if (!ages.empty()) live_age.push_back(median(ages));
    }
    spawned += tf.num_new;
    long frame_checked = 0, frame_inliers = 0;
    std::vector<double> frame_err;
    std::unordered_map<std::uint64_t, Eigen::Vector2f> cur;
    for (const auto& p : tf.points) {
      cur[p.id] = p.uv;
      life[p.id] = p.age + 1;
      if (p.age == 0) birth[p.id] = {p.uv, k};
      if (p.age == kDriftAge) {
        const auto& b = birth[p.id];
        Eigen::Vector2d truth;
        if (reproject(cam, scene, frames[b.second], frames[k], b.first.cast<double>(), &truth)) {
          const double e = (p.uv.cast<double>() - truth).norm();
          ++ours.drift_checked;
          ours.drift_inliers += e <= 1.0;
          ours.drift_err.push_back(e);
        }
      }
      if (p.age == 0 || k == 0) continue;
      auto it = prev.find(p.id);
      if (it == prev.end()) continue;
      Eigen::Vector2d truth;
      if (!reproject(cam, scene, frames[k - 1], frames[k], it->second.cast<double>(), &truth)) continue;
      ++ours.checked;
      ++frame_checked;
      const double e = (p.uv.cast<double>() - truth).norm();
      if (e <= 1.0) ++ours.inliers, ++frame_inliers;
      frame_err.push_back(e);
      ++hist[e < 0.25 ? 0 : e < 0.5 ? 1 : e < 1.0 ? 2 : e < 2.0 ? 3 : 4];
    }
    if (per_frame && k > 0) {
      std::fprintf(stderr, "  steps checked %ld within 1 px %.4f median error %.3f px\n", frame_checked,
                   frame_checked ? static_cast<double>(frame_inliers) / static_cast<double>(frame_checked) : 0.0,
                   frame_err.empty() ? 0.0 : median(frame_err));
    }
    prev.swap(cur);
  }
  std::vector<double> lengths_tracked;  // tracks that survived their first step
  for (const auto& kv : life) {
    ours.lengths.push_back(kv.second);
    if (kv.second > 1) lengths_tracked.push_back(kv.second);
  }

  // ---- OpenCV KLT with the same number of points ----
  RunStats klt;
  const int n_klt = run_klt ? static_cast<int>(median(ours.points)) : 0;
  std::vector<cv::Point2f> pts;
  std::vector<int> ages;
  std::vector<std::pair<cv::Point2f, size_t>> births, next_births;
  std::vector<int> klt_life;
  for (size_t k = 0; k < frames.size(); ++k) {
    const auto t0 = vitamin_e::TimingClock::now();
    const double c0 = vitamin_e::processCpuMs();
    std::vector<cv::Point2f> next;
    std::vector<int> next_age;
    std::vector<cv::Point2f> from;
    if (k > 0 && !pts.empty()) {
      std::vector<unsigned char> st;
      std::vector<float> err;
      cv::calcOpticalFlowPyrLK(images[k - 1], images[k], pts, next, st, err, cv::Size(21, 21), 3);
      size_t j = 0;
      for (size_t i = 0; i < pts.size(); ++i) {
        const cv::Point2f q = next[i];
        if (!st[i] || q.x < 0 || q.y < 0 || q.x > static_cast<float>(cam.w - 1) ||
            q.y > static_cast<float>(cam.h - 1)) {
          klt_life.push_back(ages[i] + 1);
          continue;
        }
        next[j] = q;
        from.push_back(pts[i]);
        next_age.push_back(ages[i] + 1);
        next_births.push_back(births[i]);
        ++j;
      }
      next.resize(j);
    }
    const size_t n_tracked = next.size();
    if (static_cast<int>(next.size()) < n_klt) {
      cv::Mat mask(images[k].size(), CV_8UC1, cv::Scalar(255));
      for (const auto& q : next) cv::circle(mask, q, 3, cv::Scalar(0), -1);
      std::vector<cv::Point2f> fresh;
      cv::goodFeaturesToTrack(images[k], fresh, n_klt - static_cast<int>(next.size()), 0.001, 3, mask);
      for (const auto& q : fresh) {
        next.push_back(q);
        next_age.push_back(0);
        next_births.push_back({q, k});
      }
    }
    klt.ms.push_back(vitamin_e::elapsedMs(t0));
    klt.cpu.push_back(vitamin_e::processCpuMs() - c0);
    klt.points.push_back(static_cast<double>(next.size()));
    for (size_t i = 0; i < n_tracked; ++i) {
      Eigen::Vector2d truth;
      if (!reproject(cam, scene, frames[k - 1], frames[k], Eigen::Vector2d(from[i].x, from[i].y), &truth)) continue;
      ++klt.checked;
      if ((Eigen::Vector2d(next[i].x, next[i].y) - truth).norm() <= 1.0) ++klt.inliers;
    }
    for (size_t i = 0; i < next.size(); ++i) {
      if (next_age[i] != kDriftAge) continue;
      Eigen::Vector2d truth;
      const auto& b = next_births[i];
      if (!reproject(cam, scene, frames[b.second], frames[k], Eigen::Vector2d(b.first.x, b.first.y), &truth)) continue;
      const double e = (Eigen::Vector2d(next[i].x, next[i].y) - truth).norm();
      ++klt.drift_checked;
      klt.drift_inliers += e <= 1.0;
      klt.drift_err.push_back(e);
    }
    births.swap(next_births);
    next_births.clear();
    pts.swap(next);
    ages.swap(next_age);
  }
  for (int a : ages) klt_life.push_back(a + 1);
  for (int l : klt_life) klt.lengths.push_back(l);
  std::vector<double> klt_lengths_tracked;
  for (double l : klt.lengths) {
    if (l > 1) klt_lengths_tracked.push_back(l);
  }

  auto pct = [](std::vector<double> v, double p) { return vitamin_e::percentile(std::move(v), p); };
  const double our_ratio = ours.checked ? static_cast<double>(ours.inliers) / static_cast<double>(ours.checked) : 0.0;
  const double klt_ratio = klt.checked ? static_cast<double>(klt.inliers) / static_cast<double>(klt.checked) : 0.0;
  std::printf("render %s, %zu frames, 752x480, tracker threads=%d\n", dir.c_str(), frames.size(), cfg.threads);
  std::printf("%-34s %14s %14s\n", "", "curv.extrema", "OpenCV KLT");
  std::printf("%-34s %14.0f %14.0f\n", "points/frame median", median(ours.points), median(klt.points));
  std::printf("%-34s %14.0f %14s\n", "tracked/frame median", median(tracked_pf), "");
  std::printf("%-34s %14d %14s\n", "tracked/frame min", min_tracked, "");
  std::printf("%-34s %14.2f %14.2f\n", "ms/frame median", median(ours.ms), median(klt.ms));
  std::printf("%-34s %14.2f %14.2f\n", "ms/frame p95", pct(ours.ms, 95), pct(klt.ms, 95));
  std::printf("%-34s %14.2f %14.2f\n", "CPU ms/frame median (all threads)", median(ours.cpu), median(klt.cpu));
  std::printf("%-34s %14.0f %14.0f\n", "track length median [frames]", median(ours.lengths), median(klt.lengths));
  std::printf("%-34s %14.0f %14.0f\n", "  of tracks surviving one step", median(lengths_tracked),
              median(klt_lengths_tracked));
  std::printf("%-34s %14.0f %14s\n", "age of tracked points, median", median(live_age), "");
  std::printf("%-34s %14ld %14zu\n", "tracks started", spawned, klt.lengths.size());
  std::printf("%-34s %14.4f %14.4f\n", "track steps within 1 px", our_ratio, klt_ratio);
  std::printf("%-34s %14ld %14ld\n", "track steps checked", ours.checked, klt.checked);
  std::printf("%-34s %14.4f %14.4f\n", "after 10 frames within 1 px",
              ours.drift_checked ? (double)ours.drift_inliers / (double)ours.drift_checked : 0.0,
              klt.drift_checked ? (double)klt.drift_inliers / (double)klt.drift_checked : 0.0);
  std::printf("%-34s %14.3f %14.3f\n", "after 10 frames median error px", median(ours.drift_err),
              median(klt.drift_err));
  std::printf("%-34s %14ld %14ld\n", "tracks reaching 10 frames", ours.drift_checked, klt.drift_checked);
  std::printf("%-34s %14.3f %14s\n", "flow_ok fraction",
              flow_ok_pf.empty()
                  ? 0.0
                  : std::accumulate(flow_ok_pf.begin(), flow_ok_pf.end(), 0.0) / static_cast<double>(flow_ok_pf.size()),
              "");
  std::printf("%-34s %.3f %.3f %.3f %.3f %.3f\n", "error <.25 <.5 <1 <2 >=2 px", (double)hist[0] / (double)ours.checked,
              (double)hist[1] / (double)ours.checked, (double)hist[2] / (double)ours.checked,
              (double)hist[3] / (double)ours.checked, (double)hist[4] / (double)ours.checked);
  for (const auto& kv : lost_by) {
    std::printf("  lost by %-24s %8ld (%ld of them new)\n", kv.first.c_str(), kv.second, lost_new_by[kv.first]);
  }
  for (const auto& kv : stage) {
    std::printf("  stage %-26s %8.2f ms median %8.2f ms p95\n", kv.first.c_str(), median(kv.second),
                pct(kv.second, 95));
  }
  std::printf(
      "{\"points_per_frame_median\":%.0f,\"ms_per_frame_median\":%.3f,\"ms_per_frame_p95\":%.3f,"
      "\"track_length_median\":%.1f,\"track_length_median_surviving\":%.1f,\"tracked_age_median\":%.1f,\"klt_"
      "track_length_median\":%.1f,\"inlier_1px_ratio\":%.4f,\"tracked_per_frame_min\":%d,"
      "\"klt_points_per_frame_median\":%.0f,\"klt_ms_per_frame_median\":%.3f,\"klt_inlier_1px_ratio\":%.4f,"
      "\"cpu_ms_per_frame_median\":%.3f,\"klt_cpu_ms_per_frame_median\":%.3f,"
      "\"drift10_1px_ratio\":%.4f,\"klt_drift10_1px_ratio\":%.4f}\n",
      median(ours.points), median(ours.ms), pct(ours.ms, 95), median(ours.lengths), median(lengths_tracked),
      median(live_age), median(klt.lengths), our_ratio, min_tracked, median(klt.points), median(klt.ms), klt_ratio,
      median(ours.cpu), median(klt.cpu),
      ours.drift_checked ? static_cast<double>(ours.drift_inliers) / static_cast<double>(ours.drift_checked) : 0.0,
      klt.drift_checked ? static_cast<double>(klt.drift_inliers) / static_cast<double>(klt.drift_checked) : 0.0);
  return 0;
} catch (const std::exception& e) {
  vitamin_e::cli::fail(e.what());
}
