// Benchmark of the dense reconstruction (Delaunay meshing, NLTGV2-L1, TSDF) on a
// render of /work/shared/tools/render_sequence.py with exact ground truth.
//   bench_fusion_dense RENDER_DIR [--config YAML] [--gt-input] [--step N] [--max-frames N]
//       [--voxel-lo M] [--voxel-hi M] [--trunc-voxels N] [--max-depth-2p5 M] [--weight-ref M] [--out DIR]
//       [--no-nltgv] [--no-warm] [--nltgv-iters N] [--warm-iters N] [--beta B] [--lambda L]
//       GT input only: [--points N] [--noise REL] [--outliers RATE]
// Default (SLAM input): runs pipeline::System (sequential, as vitamin_e_run) on
// every frame of the render with --config; every --step-th tracked frame's
// triangulated points (camera frame, map units) and pose go through the dense
// reconstruction exactly as in fusion::DenseMapper (config `dense` section:
// Delaunay -> NLTGV -> pruning), fused in two TSDF volumes. The SLAM
// trajectory is aligned to the ground truth by Sim(3) (Umeyama); its scale s
// (metres per map unit) converts the voxel sizes, truncations and depth limits
// given here in metres into map units, and the fused meshes are mapped by the
// same Sim(3) into the ground-truth frame before they are measured.
// --gt-input: ground-truth poses; points from OpenCV KLT tracks (stable ids)
// topped up with goodFeaturesToTrack, depth ray cast into the true scene and
// perturbed (REL inverse-depth noise, RATE outliers); the bench's own lenient
// build / strict prune filters.
// Depth errors: every vertex (and every 6th pixel of the rasterized mesh) is
// compared with the depth ray cast from the ground-truth pose through the same
// pinhole pixel; estimated depths are scaled by s. The 2.5 cm volume integrates
// depths <= --max-depth-2p5 (metres) and completeness is measured on surface
// points seen within that range from the ground-truth poses of the used frames.
// --max-frames N limits the input to N meshed frames (SLAM: the first N * step images).
// Prints per-stage timings and, as the last line, a JSON summary.
// The denoiser's instructions alone: run under valgrind --tool=callgrind --instr-atstart=no
// (only the NLTGV calls are instrumented; the rest runs at valgrind's uninstrumented speed).
#include <cstdio>
#include <ctime>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <unordered_map>

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "cli.h"
#include "dense_bench_scene.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/eval/alignment.h"
#include "vitamin_e/eval/trajectory.h"
#include "vitamin_e/fusion/tsdf_volume.h"
#include "vitamin_e/io/dataset.h"
#include "vitamin_e/meshing/frame_mesher.h"
#include "vitamin_e/meshing/nltgv_denoiser.h"
#include "vitamin_e/pipeline/system.h"

using namespace vitamin_e;
using dense_bench::Scene;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

struct Args {
  std::string dir, config, out;
  bool gt_input = false;
  int step = 3, max_frames = 0, points = 5000;
  double noise = 0.01, outliers = 0.02;
  bool no_nltgv = false;
  double voxel_lo = 0.15, voxel_hi = 0.025;     // metres
  double max_depth_hi = 6.0, weight_ref = 3.0;  // metres
  double trunc_voxels = 5.0;                    // truncation band half-width in voxels
  // NLTGV changes on top of the config's dense section (negative: not given).
  bool no_warm = false, warm_duals_only = false;
  int warm_iters = -1, nltgv_iters = -1;
  double beta = -1.0, lambda = -1.0;
};

const char* const kUsage =
    "usage: bench_fusion_dense RENDER_DIR [options]\n"
    "  RENDER_DIR          a render of render_sequence.py (scene.json, groundtruth_cam0_tum.txt, mav0/)\n"
    "  --config YAML       SLAM config (input and dense section)    --gt-input  ground-truth poses and depths\n"
    "  --step N            every N-th tracked frame is meshed (3)   --max-frames N  at most N meshed frames\n"
    "  --voxel-lo M, --voxel-hi M   the two TSDF voxel sizes [m] (0.15, 0.025)\n"
    "  --trunc-voxels N    truncation in voxels (5)    --max-depth-2p5 M  depth limit of the fine TSDF [m] (6)\n"
    "  --weight-ref M      depth weighting reference [m] (3)    --out DIR  write the meshes\n"
    "  --no-nltgv, --no-warm, --warm-duals-only, --warm-iters N, --nltgv-iters N, --beta B, --lambda L\n"
    "                      NLTGV changes on top of the config\n"
    "  GT input only: --points N (5000), --noise REL (0.01), --outliers RATE (0.02)\n";

Args parse(int argc, char** argv) {
  namespace cli = vitamin_e::cli;
  Args a;
  cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.positional(&a.dir) || args.value("--config", &a.config) || args.flag("--gt-input", &a.gt_input) ||
        args.value("--out", &a.out) || args.value("--step", &a.step) || args.value("--max-frames", &a.max_frames) ||
        args.value("--points", &a.points) || args.value("--noise", &a.noise) || args.value("--outliers", &a.outliers) ||
        args.flag("--no-nltgv", &a.no_nltgv) || args.value("--voxel-lo", &a.voxel_lo) ||
        args.value("--voxel-hi", &a.voxel_hi) || args.value("--max-depth-2p5", &a.max_depth_hi) ||
        args.value("--weight-ref", &a.weight_ref) || args.value("--trunc-voxels", &a.trunc_voxels) ||
        args.flag("--no-warm", &a.no_warm) || args.flag("--warm-duals-only", &a.warm_duals_only) ||
        args.value("--warm-iters", &a.warm_iters) || args.value("--nltgv-iters", &a.nltgv_iters) ||
        args.value("--beta", &a.beta) || args.value("--lambda", &a.lambda)) {
      continue;
    }
    args.unknown();
  }
  if (a.dir.empty()) cli::fail("RENDER_DIR is required (see --help)");
  for (const char* f : {"/scene.json", "/groundtruth_cam0_tum.txt"}) {
    if (!std::ifstream(a.dir + f)) cli::fail(a.dir + f + " not found (not a render_sequence.py output?)");
  }
  if (a.step < 1) cli::fail("--step must be >= 1");
  if (a.max_frames < 0 || a.points < 1) cli::fail("--max-frames must be >= 0 and --points >= 1");
  if (a.noise < 0 || a.outliers < 0 || a.outliers > 1) cli::fail("--noise must be >= 0, --outliers in [0, 1]");
  if (!(a.voxel_lo > 0) || !(a.voxel_hi > 0) || !(a.trunc_voxels >= 1) || !(a.max_depth_hi > 0) || a.weight_ref < 0) {
    cli::fail("--voxel-lo, --voxel-hi, --max-depth-2p5 must be > 0, --trunc-voxels >= 1, --weight-ref >= 0");
  }
  return a;
}

void applyNltgvOptions(const Args& a, meshing::NltgvConfig* c) {
  if (a.no_warm) c->warm_start = false;
  if (a.warm_duals_only) c->warm_start_primal = false;
  if (a.warm_iters >= 0) c->warm_iterations = a.warm_iters;
  if (a.nltgv_iters >= 0) c->iterations = a.nltgv_iters;
  if (a.beta >= 0) c->beta = a.beta;
  if (a.lambda >= 0) c->lambda = a.lambda;
  c->validate();
}

// One frame's input to the dense reconstruction (what the SLAM pipeline provides).
struct FrameInput {
  double t = 0.0;
  Eigen::Isometry3d T_w_c;  // pose used for integration (map frame, map units)
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector3d> p_c;  // camera-frame points (map units)
  Eigen::Isometry3d T_w_c_true;      // ground-truth pose (evaluation only)
};

double median(std::vector<double> v) { return percentile(std::move(v), 50.0); }

struct Tracker {  // KLT + top-up; stands in for the VITAMIN-E front end
  cv::Mat prev;
  std::vector<cv::Point2f> pts;
  std::vector<std::uint64_t> ids;
  std::uint64_t next_id = 0;
  void track(const cv::Mat& img, int max_points) {
    if (!prev.empty() && !pts.empty()) {
      std::vector<cv::Point2f> out;
      std::vector<unsigned char> st;
      std::vector<float> err;
      cv::calcOpticalFlowPyrLK(prev, img, pts, out, st, err, cv::Size(21, 21), 3);
      std::size_t k = 0;
      for (std::size_t i = 0; i < pts.size(); ++i)
        if (st[i] && out[i].x >= 0 && out[i].y >= 0 && out[i].x < static_cast<float>(img.cols) &&
            out[i].y < static_cast<float>(img.rows)) {
          pts[k] = out[i];
          ids[k++] = ids[i];
        }
      pts.resize(k);
      ids.resize(k);
    }
    if (static_cast<int>(pts.size()) < max_points) {
      cv::Mat mask(img.size(), CV_8UC1, cv::Scalar(255));
      for (const auto& p : pts) cv::circle(mask, p, 4, cv::Scalar(0), -1);
      std::vector<cv::Point2f> fresh;
      cv::goodFeaturesToTrack(img, fresh, max_points - static_cast<int>(pts.size()), 0.001, 4, mask);
      for (const auto& p : fresh) {
        pts.push_back(p);
        ids.push_back(next_id++);
      }
    }
    prev = img;
  }
};

// Triangle hash grid for point-to-mesh distances up to one cell.
struct MeshGrid {
  double cell;
  const fusion::TriangleMesh* mesh;
  std::unordered_map<std::uint64_t, std::vector<int>> cells;
  static std::uint64_t key(int x, int y, int z) {
    return (static_cast<std::uint64_t>(x + (1 << 20)) << 42) | (static_cast<std::uint64_t>(y + (1 << 20)) << 21) |
           static_cast<std::uint64_t>(z + (1 << 20));
  }
  MeshGrid(const fusion::TriangleMesh& m, double c) : cell(c), mesh(&m) {
    for (int f = 0; f < static_cast<int>(m.faces.size()); ++f) {
      Eigen::Vector3f lo = m.vertices[m.faces[f][0]], hi = lo;
      for (int k = 1; k < 3; ++k) {
        lo = lo.cwiseMin(m.vertices[m.faces[f][k]]);
        hi = hi.cwiseMax(m.vertices[m.faces[f][k]]);
      }
      const Eigen::Vector3i a = (lo.cast<double>() / cell).array().floor().cast<int>();
      const Eigen::Vector3i b = (hi.cast<double>() / cell).array().floor().cast<int>();
      for (int x = a.x(); x <= b.x(); ++x)
        for (int y = a.y(); y <= b.y(); ++y)
          for (int z = a.z(); z <= b.z(); ++z) cells[key(x, y, z)].push_back(f);
    }
  }
  double distance(const Vector3d& p) const {  // capped at `cell`
    double best = cell;
    const Eigen::Vector3i c = (p / cell).array().floor().cast<int>();
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          const auto it = cells.find(key(c.x() + x, c.y() + y, c.z() + z));
          if (it == cells.end()) continue;
          for (int f : it->second) {
            const auto& F = mesh->faces[f];
            const Vector3d q = dense_bench::closestOnTriangle(p, mesh->vertices[F[0]].cast<double>(),
                                                              mesh->vertices[F[1]].cast<double>(),
                                                              mesh->vertices[F[2]].cast<double>());
            best = std::min(best, (q - p).norm());
          }
        }
    return best;
  }
};

// Mesh in the map frame -> ground-truth frame.
fusion::TriangleMesh transformed(const fusion::TriangleMesh& m, const eval::Sim3& S) {
  fusion::TriangleMesh out = m;
  const Eigen::Matrix3f R = S.R.cast<float>();
  for (auto& v : out.vertices) v = S.apply(v.cast<double>()).cast<float>();
  for (auto& n : out.normals) n = R * n;
  return out;
}

const eval::StampedPose* nearestPose(const eval::Trajectory& tr, double t) {
  auto it = std::lower_bound(tr.begin(), tr.end(), t, [](const eval::StampedPose& p, double x) { return p.t < x; });
  const eval::StampedPose* best = nullptr;
  for (auto c : {it, it == tr.begin() ? it : it - 1})
    if (c != tr.end() && std::abs(c->t - t) < 0.005 && (!best || std::abs(c->t - t) < std::abs(best->t - t)))
      best = &*c;
  return best;
}

}  // namespace

int main(int argc, char** argv) try {
  const Args args = parse(argc, argv);
  const Scene scene = dense_bench::loadScene(args.dir + "/scene.json");
  const eval::Trajectory gt = eval::readTum(args.dir + "/groundtruth_cam0_tum.txt");
  meshing::PinholeImage image{{scene.K(0, 0), scene.K(1, 1), scene.K(0, 2), scene.K(1, 2)}, scene.width, scene.height};
  const camera::Pinhole& K = image.K;

  std::vector<FrameInput> frames;
  eval::Sim3 S;  // map -> ground-truth frame (identity for --gt-input)
  double ate_rmse = 0.0, slam_wall_ms = 0.0, slam_cpu_ms = 0.0;
  std::size_t slam_frames = 0, slam_tracked = 0;
  meshing::FrameMesherConfig build_cfg, prune_cfg;
  meshing::NltgvConfig nltgv_cfg;
  bool denoise = !args.no_nltgv;
  fusion::TsdfConfig run_tsdf;
  StageTimings timings;
  if (!args.gt_input) {
    // ---- SLAM input: the offline runner's sequence, frame by frame ----
    pipeline::SystemConfig config;
    if (!args.config.empty()) config = pipeline::loadSystemConfig(args.config);
    config.validate();
    const auto dataset = io::openDataset(args.dir);
    const camera::Camera& camera = dataset->calibration().camera;
    image = meshing::pinholeImageOf(camera);
    build_cfg = config.dense.mesher;
    prune_cfg = config.dense.prune;
    nltgv_cfg = config.dense.nltgv;
    denoise = denoise && config.dense.denoise;
    run_tsdf = config.dense.integrator.tsdf;
    pipeline::System slam(config, camera);
    std::size_t n = dataset->size();
    if (args.max_frames > 0) n = std::min(n, static_cast<std::size_t>(args.max_frames) * args.step);
    for (std::size_t i = 0; i < n; ++i) {
      const cv::Mat img = dataset->loadImage(i);
      const auto t0 = TimingClock::now();
      const double c0 = processCpuMs();
      const pipeline::FrameResult r = slam.process(img, dataset->timestamp(i), dataset->timestampText(i));
      slam_cpu_ms += processCpuMs() - c0;
      slam_wall_ms += elapsedMs(t0);
      ++slam_frames;
      slam_tracked += r.pose_valid;
      if (!r.pose_valid || i % args.step != 0) continue;
      const eval::StampedPose* g = nearestPose(gt, r.timestamp);
      if (!g) continue;
      FrameInput in;
      in.t = r.timestamp;
      in.T_w_c = r.T_w_c;
      in.T_w_c_true = g->T_w_c;
      pipeline::framePointsInCamera(r, &in.ids, &in.p_c);
      if (static_cast<int>(in.ids.size()) < config.dense.min_points) continue;
      frames.push_back(std::move(in));
    }
    // Sim(3) of the final trajectory onto the ground truth.
    eval::Trajectory est;
    for (const auto& e : slam.trajectory()) est.push_back({e.timestamp, e.T_w_c});
    const eval::Association assoc = eval::associate(est, gt, 0.005);
    Eigen::Matrix3Xd src(3, assoc.size()), dst(3, assoc.size());
    for (std::size_t k = 0; k < assoc.size(); ++k) {
      const auto col = static_cast<Eigen::Index>(k);
      src.col(col) = est[assoc[k].first].T_w_c.translation();
      dst.col(col) = gt[assoc[k].second].T_w_c.translation();
    }
    S = eval::umeyamaAlignment(src, dst, true);
    double se = 0.0;
    for (Eigen::Index k = 0; k < src.cols(); ++k) se += (S.apply(Vector3d(src.col(k))) - dst.col(k)).squaredNorm();
    ate_rmse = std::sqrt(se / static_cast<double>(std::max<std::size_t>(1, assoc.size())));
  } else {
    // ---- ground-truth poses, KLT tracks, ray-cast noisy depth ----
    build_cfg.max_edge_px = 40.0;  // lenient: NLTGV repairs outliers, prune() cuts afterwards
    build_cfg.max_inv_depth_jump = 1.0;
    build_cfg.max_normal_angle_deg = 88.0;
    build_cfg.max_depth = 20.0;
    prune_cfg = build_cfg;
    prune_cfg.max_inv_depth_jump = 0.15;
    prune_cfg.max_normal_angle_deg = 80.0;
    const cv::Mat Kcv = (cv::Mat_<double>(3, 3) << K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
    const cv::Mat dist(scene.dist, true);
    std::vector<std::pair<double, std::string>> images;  // mav0/cam0/data.csv: timestamp_ns,filename
    {
      std::ifstream csv(args.dir + "/mav0/cam0/data.csv");
      std::string line;
      while (std::getline(csv, line)) {
        if (line.empty() || line[0] == '#') continue;
        const auto comma = line.find(',');
        std::string name = line.substr(comma + 1);
        name.erase(name.find_last_not_of(" \r\n") + 1);
        images.emplace_back(std::stod(line.substr(0, comma)) * 1e-9, args.dir + "/mav0/cam0/data/" + name);
      }
    }
    if (images.empty()) throw std::runtime_error("no images in " + args.dir + "/mav0/cam0/data.csv");
    Tracker tracker;
    std::mt19937 rng(42);
    std::normal_distribution<double> N(0.0, 1.0);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    for (std::size_t f = 0; f < images.size(); f += args.step) {
      if (args.max_frames > 0 && static_cast<int>(frames.size()) >= args.max_frames) break;
      const eval::StampedPose* g = nearestPose(gt, images[f].first);
      if (!g) continue;
      const cv::Mat img = cv::imread(images[f].second, cv::IMREAD_GRAYSCALE);
      if (img.empty()) throw std::runtime_error("cannot read " + images[f].second);
      {
        ScopedTimer t(&timings, "klt_tracking (input)");
        tracker.track(img, args.points);
      }
      FrameInput in;
      in.t = images[f].first;
      in.T_w_c = in.T_w_c_true = g->T_w_c;
      std::vector<cv::Point2f> und;
      cv::undistortPoints(tracker.pts, und, Kcv, dist, cv::noArray(), Kcv);
      const Vector3d o = in.T_w_c_true.translation();
      for (std::size_t i = 0; i < und.size(); ++i) {
        const Vector2d uv(und[i].x, und[i].y);
        const double z = dense_bench::rayCast(scene, o, in.T_w_c_true.linear() * K.ray(uv));
        if (!std::isfinite(z) || !image.inImage(uv)) continue;
        double inv = (1.0 / z) * (1.0 + args.noise * N(rng));
        if (U(rng) < args.outliers) inv = (1.0 / z) * std::exp(1.4 * U(rng) - 0.7);
        in.ids.push_back(tracker.ids[i]);
        in.p_c.push_back(K.ray(uv) * (1.0 / inv));
      }
      frames.push_back(std::move(in));
    }
  }
  applyNltgvOptions(args, &nltgv_cfg);
  if (frames.empty()) throw std::runtime_error("no frame to reconstruct (SLAM never tracked?)");

  // Metric sizes -> map units (s metres per map unit).
  const double s = S.scale;
  fusion::TsdfConfig c15, c25;
  c15.voxel_size = args.voxel_lo / s, c15.truncation = args.trunc_voxels * args.voxel_lo / s, c15.block_voxels = 8;
  c25.voxel_size = args.voxel_hi / s, c25.truncation = args.trunc_voxels * args.voxel_hi / s, c25.block_voxels = 8;
  c15.min_depth = c25.min_depth = 0.1 / s;
  c15.max_depth = 20.0 / s;
  c25.max_depth = args.max_depth_hi / s;
  c15.weight_depth_ref = c25.weight_depth_ref = args.weight_ref / s;
  fusion::TsdfVolume tsdf15(c15), tsdf25(c25);
  // SLAM input: also the volume vitamin_e_run fuses (config dense section, map units).
  std::unique_ptr<fusion::TsdfVolume> tsdf_run;
  if (!args.gt_input) tsdf_run = std::make_unique<fusion::TsdfVolume>(run_tsdf);
  const meshing::FrameMesher mesher(build_cfg), pruner(prune_cfg);
  meshing::NltgvDenoiser nltgv(nltgv_cfg);

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<double> nltgv_iters;  // iterations run per denoised frame
  std::vector<double> raw_err, smooth_err, raw_dense, smooth_dense, mesh_ms, t15_ms, t25_ms, mesh_cpu, t15_cpu, t25_cpu,
      verts;
  std::vector<Vector3d> seen;  // points on true surfaces the camera saw (completeness)
  for (const FrameInput& in : frames) {
    // ---- the dense reconstruction of one frame (as fusion::DenseMapper::addFrame) ----
    const auto t0 = TimingClock::now();
    const double c0 = threadCpuMs();
    meshing::FrameMesh mesh;
    {
      ScopedTimer t(&timings, "delaunay_mesh");
      mesh = mesher.buildFromPoints(in.ids, in.p_c, image);
    }
    const meshing::FrameMesh raw = mesh;
    if (denoise && !mesh.triangles.empty()) {
      ScopedTimer t(&timings, "nltgv");
      CALLGRIND_START_INSTRUMENTATION;
      const meshing::NltgvStats st = nltgv.denoise(&mesh, K);
      CALLGRIND_STOP_INSTRUMENTATION;
      nltgv_iters.push_back(st.iterations);
    }
    {
      ScopedTimer t(&timings, "prune");
      pruner.prune(&mesh, K);
    }
    mesh_ms.push_back(elapsedMs(t0));
    const double c1 = threadCpuMs();
    mesh_cpu.push_back(c1 - c0);
    meshing::FrameMesh raw_pruned = raw;
    pruner.prune(&raw_pruned, K);
    verts.push_back(static_cast<double>(mesh.vertices.size()));
    const auto t1 = TimingClock::now();
    const double c1b = threadCpuMs();
    tsdf15.integrate(mesh, in.T_w_c, image);
    tsdf15.updateMesh();
    t15_ms.push_back(elapsedMs(t1));
    const double c2 = threadCpuMs();
    t15_cpu.push_back(c2 - c1b);
    const auto t2 = TimingClock::now();
    tsdf25.integrate(mesh, in.T_w_c, image);
    const double int25 = elapsedMs(t2);
    tsdf25.updateMesh();
    t25_ms.push_back(elapsedMs(t2));
    t25_cpu.push_back(threadCpuMs() - c2);
    if (tsdf_run) tsdf_run->integrate(mesh, in.T_w_c, image);
    timings.add("tsdf15_integrate+mc", t15_ms.back());
    timings.add("tsdf2.5_integrate", int25);
    timings.add("tsdf2.5_mc", t25_ms.back() - int25);
    // ---- evaluation: depths along the same pinhole pixel from the true pose ----
    const Vector3d o = in.T_w_c_true.translation();
    const Eigen::Matrix3d R = in.T_w_c_true.linear();
    auto true_z = [&](const Vector2d& uv) { return dense_bench::rayCast(scene, o, R * K.ray(uv)); };
    auto vertex_err = [&](const meshing::FrameMesh& m, std::vector<double>* out) {
      for (const auto& v : m.vertices) {
        const double z = true_z(v.uv);
        if (std::isfinite(z) && v.inv_depth > 0.0) out->push_back(std::abs(s / v.inv_depth - z) / z);
      }
    };
    vertex_err(raw, &raw_err);
    vertex_err(mesh, &smooth_err);
    const auto d_raw = fusion::TsdfVolume::rasterizeDepth(raw_pruned, image);
    const auto d_smooth = fusion::TsdfVolume::rasterizeDepth(mesh, image);
    for (int v = 0; v < image.height; v += 6)
      for (int u = 0; u < image.width; u += 6) {
        const std::size_t idx = static_cast<std::size_t>(v) * image.width + u;
        const double z = true_z(Vector2d(u, v));
        if (!std::isfinite(z)) continue;
        if (d_raw[idx] > 0 && d_smooth[idx] > 0) {  // pixels covered by both meshes
          raw_dense.push_back(std::abs(s * d_raw[idx] - z) / z);
          smooth_dense.push_back(std::abs(s * d_smooth[idx] - z) / z);
        }
        if (z <= args.max_depth_hi && U(rng) < 0.05) seen.push_back(o + R * K.ray(Vector2d(u, v)) * z);
      }
  }
  // ---- final meshes (map frame -> ground-truth frame) and metrics ----
  fusion::TriangleMesh m15, m25;
  {
    ScopedTimer t(&timings, "assemble_mesh_15cm (once)");
    m15 = tsdf15.extractMesh();
  }
  {
    ScopedTimer t(&timings, "assemble_mesh_2.5cm (once)");
    m25 = tsdf25.extractMesh();
  }
  m15 = transformed(m15, S);
  m25 = transformed(m25, S);
  fusion::TriangleMesh mrun;
  if (tsdf_run) mrun = transformed(tsdf_run->extractMesh(), S);
  auto accuracy = [&](const fusion::TriangleMesh& m) {
    std::vector<double> d;
    d.reserve(m.vertices.size());
    for (const auto& p : m.vertices) d.push_back(dense_bench::surfaceDistance(scene, p.cast<double>()));
    return d;
  };
  auto completeness = [&](const fusion::TriangleMesh& m) {
    const MeshGrid grid(m, 0.05);
    std::size_t hit = 0;
    for (const auto& p : seen) hit += grid.distance(p) < 0.05;
    return seen.empty() ? 0.0 : static_cast<double>(hit) / static_cast<double>(seen.size());
  };
  const auto acc25 = accuracy(m25), acc15 = accuracy(m15);
  const double comp25 = completeness(m25), comp15 = completeness(m15);
  const auto accrun = accuracy(mrun);
  const double comprun = tsdf_run ? completeness(mrun) : 0.0;
  if (!args.out.empty()) {  // in the ground-truth frame (metres)
    fusion::saveMeshPly(m15, args.out + "/mesh_15cm.ply");
    fusion::saveMeshPly(m25, args.out + "/mesh_2p5cm.ply");
    if (tsdf_run) fusion::saveMeshPly(mrun, args.out + "/mesh_runner.ply");
  }
  auto min_of = [](const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); };
  if (args.gt_input) {
    std::printf("input: ground-truth poses, KLT points <= %d, ray-cast depth, noise %.3g, outliers %.3g\n", args.points,
                args.noise, args.outliers);
  } else {
    std::printf("input: SLAM (%s), %zu frames, %zu tracked; SLAM %.1f ms wall / %.1f ms process CPU per frame\n",
                args.config.empty() ? "built-in config" : args.config.c_str(), slam_frames, slam_tracked,
                slam_wall_ms / static_cast<double>(std::max<std::size_t>(1, slam_frames)),
                slam_cpu_ms / static_cast<double>(std::max<std::size_t>(1, slam_frames)));
    std::printf("Sim(3) to ground truth: scale %.4f m per map unit, ATE rmse %.4f m; voxels %.4f / %.4f map units\n", s,
                ate_rmse, c15.voxel_size, c25.voxel_size);
  }
  double nltgv_iters_mean = 0.0;
  for (double v : nltgv_iters) nltgv_iters_mean += v / static_cast<double>(nltgv_iters.size());
  std::printf("frames meshed: %zu (every %d), vertices/frame median %.0f, nltgv %s (%d iters, %d warm; ran %.1f per "
              "frame on average)\n",
              frames.size(), args.step, median(verts), denoise ? "on" : "off", nltgv_cfg.iterations,
              nltgv_cfg.warm_iterations, nltgv_iters_mean);
  std::printf("%s", timings.table().c_str());
  std::printf("wall ms/frame (min / median), thread CPU ms/frame (min / median):\n");
  std::printf("  mesh (delaunay+nltgv+prune): %7.2f / %7.2f   cpu %7.2f / %7.2f\n", min_of(mesh_ms), median(mesh_ms),
              min_of(mesh_cpu), median(mesh_cpu));
  std::printf("  tsdf 15cm integrate+mc:      %7.2f / %7.2f   cpu %7.2f / %7.2f\n", min_of(t15_ms), median(t15_ms),
              min_of(t15_cpu), median(t15_cpu));
  std::printf("  tsdf 2.5cm integrate+mc:     %7.2f / %7.2f   cpu %7.2f / %7.2f\n", min_of(t25_ms), median(t25_ms),
              min_of(t25_cpu), median(t25_cpu));
  std::printf("vertex rel. depth error: raw median %.4f p90 %.4f | nltgv median %.4f p90 %.4f\n", median(raw_err),
              percentile(raw_err, 90), median(smooth_err), percentile(smooth_err, 90));
  std::printf("dense rel. depth error:  raw median %.4f p90 %.4f | nltgv median %.4f p90 %.4f (%zu px)\n",
              median(raw_dense), percentile(raw_dense, 90), median(smooth_dense), percentile(smooth_dense, 90),
              raw_dense.size());
  std::printf("mesh 15cm: %zu vertices %zu faces; accuracy median %.4f p90 %.4f m; completeness(5cm) %.3f\n",
              m15.vertices.size(), m15.faces.size(), median(acc15), percentile(acc15, 90), comp15);
  std::printf("mesh 2.5cm: %zu vertices %zu faces; accuracy median %.4f p90 %.4f m; completeness(5cm) %.3f (%zu pts)\n",
              m25.vertices.size(), m25.faces.size(), median(acc25), percentile(acc25, 90), comp25, seen.size());
  if (tsdf_run)
    std::printf("mesh as vitamin_e_run (voxel %.4g map units = %.1f mm): %zu faces; accuracy median %.4f p90 %.4f m; "
                "completeness(5cm) %.3f\n",
                run_tsdf.voxel_size, 1e3 * run_tsdf.voxel_size * s, mrun.faces.size(), median(accrun),
                percentile(accrun, 90), comprun);
  std::printf(
      "{\"accuracy_median_m\":%.4f,\"accuracy_p90_m\":%.4f,\"completeness_5cm\":%.4f,\"raw_depth_err_median\":%.5f,"
      "\"nltgv_depth_err_median\":%.5f,\"mesh_ms_per_frame\":%.2f,\"tsdf_ms_15cm\":%.2f,\"tsdf_ms_2p5cm\":%.2f,"
      "\"raw_dense_depth_err_median\":%.5f,\"nltgv_dense_depth_err_median\":%.5f,\"mesh_cpu_ms_per_frame\":%.2f,"
      "\"tsdf_cpu_ms_15cm\":%.2f,\"tsdf_cpu_ms_2p5cm\":%.2f,\"accuracy_median_15cm_m\":%.4f,"
      "\"completeness_5cm_15cm\":%.4f,\"input\":\"%s\",\"sim3_scale\":%.5f,\"ate_rmse_m\":%.5f,\"frames\":%zu,"
      "\"accuracy_median_runner_m\":%.4f,\"completeness_5cm_runner\":%.4f,\"nltgv_iterations_mean\":%.2f}\n",
      median(acc25), percentile(acc25, 90), comp25, median(raw_err), median(smooth_err), median(mesh_ms),
      median(t15_ms), median(t25_ms), median(raw_dense), median(smooth_dense), median(mesh_cpu), median(t15_cpu),
      median(t25_cpu), median(acc15), comp15, args.gt_input ? "gt" : "slam", s, ate_rmse, frames.size(),
      accrun.empty() ? 0.0 : median(accrun), comprun, nltgv_iters_mean);
  return 0;
} catch (const std::exception& e) {
  vitamin_e::cli::fail(e.what());
}
