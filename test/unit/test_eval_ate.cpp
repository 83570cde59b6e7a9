// Trajectory evaluation: readers for the three ground-truth formats, timestamp
// association, Sim(3) alignment and ATE, checked against an independent
// computation (Horn's quaternion method) and the injected noise.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include <Eigen/Eigenvalues>

#include "vitamin_e/eval/metrics.h"

namespace ve = vitamin_e::eval;
namespace fs = std::filesystem;

namespace {

Eigen::Matrix3d rotZYX(double yaw, double pitch, double roll) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// A smooth non-planar path with changing orientation, n poses from t0 every dt.
ve::Trajectory makeGroundTruth(int n, double t0, double dt) {
  ve::Trajectory traj;
  for (int i = 0; i < n; ++i) {
    const double t = t0 + dt * i, s = dt * i;
    ve::StampedPose p;
    p.t = t;
    p.T_w_c.linear() = rotZYX(0.4 * s + 0.3 * std::sin(s), 0.2 * std::sin(0.7 * s), 0.1 * std::cos(1.3 * s));
    p.T_w_c.translation() = Eigen::Vector3d(2.0 * std::sin(0.5 * s), 1.2 * std::sin(s), 1.0 + 0.4 * std::cos(0.8 * s));
    traj.push_back(p);
  }
  return traj;
}

struct Noisy {
  ve::Trajectory estimate;
  double true_rmse = 0.0;  // RMSE of the injected noise mapped back by the true Sim(3)
};

// Estimate = S(ground truth) + Gaussian position noise (sigma per axis).
Noisy transformWithNoise(const ve::Trajectory& gt, const ve::Sim3& S, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  Noisy out;
  double sum_sq = 0.0;
  for (const auto& g : gt) {
    ve::StampedPose e;
    e.t = g.t;
    e.T_w_c = S.apply(g.T_w_c);
    const Eigen::Vector3d n(noise(rng), noise(rng), noise(rng));
    e.T_w_c.translation() += n;
    sum_sq += (n / S.scale).squaredNorm();
    out.estimate.push_back(e);
  }
  out.true_rmse = std::sqrt(sum_sq / static_cast<double>(gt.size()));
  return out;
}

ve::Sim3 knownSim3() {
  ve::Sim3 S;
  S.scale = 2.7;
  S.R = rotZYX(1.1, -0.4, 2.3);
  S.t = Eigen::Vector3d(3.0, -1.5, 0.7);
  return S;
}

// Horn (1987): rotation from the top eigenvector of the 4x4 symmetric matrix,
// then the least-squares scale and translation. Returns the RMSE after alignment.
double hornRmse(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, ve::Sim3* out) {
  const Eigen::Vector3d ms = src.rowwise().mean(), md = dst.rowwise().mean();
  const Eigen::Matrix3Xd a = src.colwise() - ms, b = dst.colwise() - md;
  const Eigen::Matrix3d M = a * b.transpose();  // M(i,j) = sum a_i b_j
  const double Sxx = M(0, 0), Sxy = M(0, 1), Sxz = M(0, 2), Syx = M(1, 0), Syy = M(1, 1), Syz = M(1, 2), Szx = M(2, 0),
               Szy = M(2, 1), Szz = M(2, 2);
  Eigen::Matrix4d N;
  N << Sxx + Syy + Szz, Syz - Szy, Szx - Sxz, Sxy - Syx,  //
      Syz - Szy, Sxx - Syy - Szz, Sxy + Syx, Szx + Sxz,   //
      Szx - Sxz, Sxy + Syx, -Sxx + Syy - Szz, Syz + Szy,  //
      Sxy - Syx, Szx + Sxz, Syz + Szy, -Sxx - Syy + Szz;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(N);
  const Eigen::Vector4d q = es.eigenvectors().col(3);
  out->R = Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized().toRotationMatrix();
  out->scale = (b.cwiseProduct(out->R * a)).sum() / a.squaredNorm();
  out->t = md - out->scale * out->R * ms;
  double sum_sq = 0.0;
  for (Eigen::Index i = 0; i < src.cols(); ++i)
    sum_sq += (out->apply(Eigen::Vector3d(src.col(i))) - dst.col(i)).squaredNorm();
  return std::sqrt(sum_sq / static_cast<double>(src.cols()));
}

double angleBetween(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return Eigen::AngleAxisd(A.transpose() * B).angle();
}

class TempDir {
 public:
  TempDir() {
    path_ =
        fs::temp_directory_path() / ("ve_eval_" + std::to_string(::getpid()) + "_" + std::to_string(instance_count++));
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
  static inline int instance_count = 0;
};

void writeEurocCsv(const std::string& path, const ve::Trajectory& traj, long long t0_ns, long long dt_ns) {
  FILE* f = std::fopen(path.c_str(), "w");
  std::fprintf(
      f, "#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n");
  for (std::size_t i = 0; i < traj.size(); ++i) {
    const Eigen::Quaterniond q(traj[i].T_w_c.rotation());
    const Eigen::Vector3d& p = traj[i].T_w_c.translation();
    std::fprintf(f, "%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,0,0,0\n", t0_ns + dt_ns * static_cast<long long>(i), p.x(),
                 p.y(), p.z(), q.w(), q.x(), q.y(), q.z());
  }
  std::fclose(f);
}

void writeKitti(const std::string& path, const ve::Trajectory& traj) {
  FILE* f = std::fopen(path.c_str(), "w");
  for (const auto& sp : traj) {
    const Eigen::Matrix<double, 3, 4> M = sp.T_w_c.matrix().topRows<3>();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) std::fprintf(f, "%.12e%s", M(r, c), (r == 2 && c == 3) ? "\n" : " ");
  }
  std::fclose(f);
}

// Reads gt back, checks poses equal the written ones, evaluates the noisy
// Sim(3)-transformed estimate (written as TUM) and checks alignment and ATE.
void checkRoundTrip(const std::string& gt_path, const ve::Trajectory& gt, ve::TrajectoryFormat expected_format,
                    const std::string& est_path) {
  SCOPED_TRACE(gt_path);
  EXPECT_EQ(ve::detectTrajectoryFormat(gt_path), expected_format);
  const ve::Trajectory gt_read = ve::readTrajectory(gt_path);
  ASSERT_EQ(gt_read.size(), gt.size());
  for (std::size_t i = 0; i < gt.size(); ++i) {
    ASSERT_NEAR(gt_read[i].t, gt[i].t, 1e-6);
    ASSERT_LT((gt_read[i].T_w_c.translation() - gt[i].T_w_c.translation()).norm(), 1e-6);
    ASSERT_LT(angleBetween(gt_read[i].T_w_c.linear(), gt[i].T_w_c.linear()), 1e-6) << "pose " << i;
  }
  const ve::Sim3 S = knownSim3();
  const double sigma = 0.02;
  const Noisy noisy = transformWithNoise(gt, S, sigma, 7);
  ve::writeTum(est_path, noisy.estimate);
  const ve::Trajectory est = ve::readTrajectory(est_path);
  EXPECT_EQ(ve::detectTrajectoryFormat(est_path), ve::TrajectoryFormat::kTum);

  ve::EvalConfig cfg;
  const ve::EvalResult r = ve::evaluate(est, gt_read, cfg);
  ASSERT_EQ(r.matched, gt.size());
  EXPECT_DOUBLE_EQ(r.success_rate, 1.0);
  // The fitted transform maps estimate -> ground truth: its inverse is S.
  const ve::Sim3 S_hat = r.alignment.inverse();
  EXPECT_NEAR(S_hat.scale, S.scale, 0.01 * S.scale);
  EXPECT_LT(angleBetween(S_hat.R, S.R), 0.2 * M_PI / 180.0);
  EXPECT_LT((S_hat.t - S.t).norm(), 0.02);
  // Independent computation of the same optimum.
  Eigen::Matrix3Xd src(3, est.size()), dst(3, est.size());
  for (Eigen::Index i = 0; i < src.cols(); ++i) {
    src.col(i) = est[i].T_w_c.translation();
    dst.col(i) = gt_read[i].T_w_c.translation();
  }
  ve::Sim3 horn;
  const double horn_rmse = hornRmse(src, dst, &horn);
  EXPECT_NEAR(r.ate.rmse, horn_rmse, 1e-9);
  EXPECT_NEAR(r.alignment.scale, horn.scale, 1e-9);
  // The optimum is at most the error under the true transform, and close to it
  // (7 of 3N degrees of freedom absorbed by the fit).
  EXPECT_LE(r.ate.rmse, noisy.true_rmse + 1e-12);
  EXPECT_GT(r.ate.rmse, 0.97 * noisy.true_rmse);
  EXPECT_NEAR(r.ate.rmse, std::sqrt(3.0) * sigma / S.scale, 0.1 * std::sqrt(3.0) * sigma / S.scale);
  EXPECT_LE(r.ate.median, r.ate.max);
  EXPECT_LE(r.ate.mean, r.ate.rmse);
}

}  // namespace

TEST(Umeyama, RecoversExactSim3AndSe3) {
  const ve::Trajectory gt = makeGroundTruth(50, 0.0, 0.1);
  const ve::Sim3 S = knownSim3();
  Eigen::Matrix3Xd src(3, gt.size()), dst(3, gt.size());
  for (Eigen::Index i = 0; i < src.cols(); ++i) {
    src.col(i) = gt[i].T_w_c.translation();
    dst.col(i) = S.apply(Eigen::Vector3d(src.col(i)));
  }
  const ve::Sim3 fit = ve::umeyamaAlignment(src, dst, true);
  EXPECT_NEAR(fit.scale, 2.7, 1e-9);
  EXPECT_LT(angleBetween(fit.R, S.R), 1e-9);
  EXPECT_LT((fit.t - S.t).norm(), 1e-9);
  // SE(3) on scale-free data.
  ve::Sim3 rigid = S;
  rigid.scale = 1.0;
  for (Eigen::Index i = 0; i < src.cols(); ++i) dst.col(i) = rigid.apply(Eigen::Vector3d(src.col(i)));
  const ve::Sim3 fit_se3 = ve::umeyamaAlignment(src, dst, false);
  EXPECT_DOUBLE_EQ(fit_se3.scale, 1.0);
  EXPECT_LT(angleBetween(fit_se3.R, S.R), 1e-9);
  EXPECT_THROW(ve::umeyamaAlignment(src.leftCols(2), dst.leftCols(2), true), std::invalid_argument);
}

TEST(Umeyama, NeverReturnsAReflection) {
  // A mirror image of a noisy, nearly planar cloud: the unconstrained optimum
  // is a reflection; the answer must still be a rotation, and the best one.
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix3Xd src(3, 40), dst(3, 40);
  for (int i = 0; i < 40; ++i) {
    src.col(i) = Eigen::Vector3d(n(rng), n(rng), 0.05 * n(rng));
    dst.col(i) = Eigen::Vector3d(src(0, i), -src(1, i), src(2, i)) + 0.01 * Eigen::Vector3d(n(rng), n(rng), n(rng));
  }
  const ve::Sim3 fit = ve::umeyamaAlignment(src, dst, true);
  EXPECT_NEAR(fit.R.determinant(), 1.0, 1e-9);
  ve::Sim3 horn;
  hornRmse(src, dst, &horn);
  EXPECT_LT(angleBetween(fit.R, horn.R), 1e-6);
  EXPECT_NEAR(fit.scale, horn.scale, 1e-9);
}

TEST(Evaluate, TumGroundTruth) {
  TempDir dir;
  const ve::Trajectory gt = makeGroundTruth(600, 1403715274.302142, 0.05);
  ve::writeTum(dir.file("gt.txt"), gt);
  checkRoundTrip(dir.file("gt.txt"), gt, ve::TrajectoryFormat::kTum, dir.file("est.txt"));
}

TEST(Evaluate, EurocCsvGroundTruthQuaternionWFirst) {
  TempDir dir;
  const long long t0_ns = 1403715274302142976LL, dt_ns = 50000000LL;
  const ve::Trajectory gt = makeGroundTruth(600, 1403715274.302142976, 0.05);
  fs::create_directories(dir.file("mav0/state_groundtruth_estimate0"));
  const std::string csv = dir.file("mav0/state_groundtruth_estimate0/data.csv");
  writeEurocCsv(csv, gt, t0_ns, dt_ns);
  checkRoundTrip(csv, gt, ve::TrajectoryFormat::kEurocCsv, dir.file("est.txt"));
  // A dataset folder resolves to its ground truth.
  EXPECT_EQ(ve::resolveTrajectoryPath(dir.file("")), csv);
}

TEST(Evaluate, KittiGroundTruthWithImplicitAndExplicitTimes) {
  TempDir dir;
  const ve::Trajectory gt = makeGroundTruth(400, 0.0, 0.1);
  writeKitti(dir.file("poses.txt"), gt);
  checkRoundTrip(dir.file("poses.txt"), gt, ve::TrajectoryFormat::kKitti, dir.file("est.txt"));
  // times.txt beside the poses wins over index * 0.1 s.
  FILE* f = std::fopen(dir.file("times.txt").c_str(), "w");
  for (std::size_t i = 0; i < gt.size(); ++i) std::fprintf(f, "%.6e\n", 5.0 + 0.1 * static_cast<double>(i));
  std::fclose(f);
  const ve::Trajectory timed = ve::readTrajectory(dir.file("poses.txt"));
  ASSERT_EQ(timed.size(), gt.size());
  EXPECT_NEAR(timed[10].t, 6.0, 1e-9);
}

TEST(Evaluate, BodyToCameraFromSensorYaml) {
  TempDir dir;
  Eigen::Isometry3d T_b_c = Eigen::Isometry3d::Identity();
  T_b_c.linear() = rotZYX(1.57, 0.02, -0.03);
  T_b_c.translation() = Eigen::Vector3d(-0.0216, -0.0647, 0.0098);
  FILE* f = std::fopen(dir.file("sensor.yaml").c_str(), "w");
  std::fprintf(f, "%%YAML:1.0\nsensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [");
  const Eigen::Matrix4d M = T_b_c.matrix();
  for (int i = 0; i < 16; ++i) std::fprintf(f, "%.15g%s", M(i / 4, i % 4), i < 15 ? ", " : "]\n");
  std::fprintf(f, "rate_hz: 20\n");
  std::fclose(f);
  const Eigen::Isometry3d loaded = ve::loadBodyToCamera(dir.file("sensor.yaml"));
  EXPECT_LT((loaded.matrix() - M).norm(), 1e-9);

  const ve::Trajectory cam = makeGroundTruth(100, 100.0, 0.05);
  ve::Trajectory body = cam;
  for (auto& p : body) p.T_w_c = p.T_w_c * T_b_c.inverse();
  const ve::Trajectory back = ve::applyBodyToCamera(body, loaded);
  for (std::size_t i = 0; i < cam.size(); ++i) EXPECT_LT((back[i].T_w_c.matrix() - cam[i].T_w_c.matrix()).norm(), 1e-9);
  EXPECT_THROW(ve::loadBodyToCamera(dir.file("missing.yaml")), ve::TrajectoryError);
}

TEST(Associate, MismatchedRatesAndSuccessRate) {
  // Ground truth at 200 Hz; estimate at 20 Hz, 3 ms late, for frames 0..99 of
  // 150, plus 10 poses after the ground truth ends.
  const ve::Trajectory gt = makeGroundTruth(1000, 10.0, 0.005);  // 10.000 .. 14.995 s
  ve::Trajectory est;
  for (int i = 0; i < 110; ++i) {
    ve::StampedPose p;
    p.t = 10.003 + 0.05 * i;
    const int k = std::min(999, static_cast<int>(std::lround((p.t - 10.0) / 0.005)));
    p.T_w_c = gt[k].T_w_c;
    est.push_back(p);
  }
  const ve::Association a = ve::associate(est, gt, 0.02);
  ASSERT_EQ(a.size(), 101u);  // 10.003 .. 15.003 (15.003 - 14.995 = 8 ms) match
  for (const auto& [i, j] : a) EXPECT_LE(std::abs(est[i].t - gt[j].t), (i < 100 ? 0.0025 : 0.008) + 1e-9);
  EXPECT_TRUE(ve::associate(est, gt, 0.001).empty());

  ve::EvalConfig cfg;
  cfg.frames = 150;
  const ve::EvalResult r = ve::evaluate(est, gt, cfg);
  EXPECT_EQ(r.matched, 101u);
  EXPECT_NEAR(r.success_rate, 101.0 / 150.0, 1e-12);
  EXPECT_LT(r.ate.rmse, 0.01);  // poses are the ground truth's at most 2.5 ms apart
  EXPECT_LT(r.rpe_frame.rmse, 0.01);
  EXPECT_GT(r.rpe_delta.count, 50u);

  // A ground-truth pose is used once: of two estimates nearest to the same gt
  // pose, the closer one keeps it.
  ve::Trajectory twins = {est[0], est[0]};
  twins[0].t = 10.0012;
  twins[1].t = 10.0004;
  const ve::Association tw = ve::associate(twins, gt, 0.02);
  ASSERT_EQ(tw.size(), 1u);
  EXPECT_EQ(tw[0].first, 1u);
  EXPECT_EQ(tw[0].second, 0u);
}

TEST(Evaluate, RelativeErrorIsScaleFreeAndSeesAJump) {
  const ve::Trajectory gt = makeGroundTruth(200, 0.0, 0.05);
  const ve::Sim3 S = knownSim3();
  ve::Trajectory est = transformWithNoise(gt, S, 0.0, 1).estimate;
  ve::EvalResult r = ve::evaluate(est, gt);
  EXPECT_LT(r.ate.rmse, 1e-9);
  EXPECT_LT(r.rpe_frame.rmse, 1e-9);
  EXPECT_LT(r.rpe_delta.rmse, 1e-9);
  // Shift the second half by 27 cm in the estimate's frame = 10 cm in gt's:
  // exactly one 1-frame relative motion is 10 cm wrong.
  for (std::size_t i = 100; i < est.size(); ++i) est[i].T_w_c.translation() += Eigen::Vector3d(0.27, 0.0, 0.0);
  r = ve::evaluate(est, gt);
  EXPECT_NEAR(r.rpe_frame.max, 0.1, 0.01);
  EXPECT_NEAR(r.rpe_frame.rmse, 0.1 / std::sqrt(199.0), 0.002);
  ve::EvalConfig se3;
  se3.align_scale = false;
  EXPECT_DOUBLE_EQ(ve::evaluate(est, gt, se3).alignment.scale, 1.0);
}

TEST(Evaluate, PathLengthIsTheGroundTruthsOverTheMatchedPoses) {
  // A straight line at 1 m per pose; the estimate misses the last 5 poses.
  ve::Trajectory gt, est;
  for (int i = 0; i < 20; ++i) {
    ve::StampedPose p;
    p.t = 0.1 * i;
    p.T_w_c.translation() = Eigen::Vector3d(double(i), 0.0, 0.0);
    gt.push_back(p);
    if (i < 15) {
      p.T_w_c.translation() = Eigen::Vector3d(0.5 * i, 0.1 * (i % 2), 0.0);
      est.push_back(p);
    }
  }
  const ve::EvalResult r = ve::evaluate(est, gt);
  EXPECT_NEAR(r.path_length_m, 14.0, 1e-9);
  const std::string json = ve::toJson(r, ve::EvalConfig{});
  char expected[64];
  std::snprintf(expected, sizeof(expected), "\"ate_path_percent\":%.6f", 100.0 * r.ate.rmse / 14.0);
  EXPECT_NE(json.find(expected), std::string::npos) << json;
  EXPECT_NE(json.find("\"path_length_m\":14.000000"), std::string::npos) << json;
}

TEST(Evaluate, AGivenAlignmentIsAppliedUnchanged) {
  // A second run in the first run's map: the first run's alignment holds for
  // it; a second run in a frame of its own is caught (it would not be if the
  // alignment were fitted again).
  const ve::Trajectory gt = makeGroundTruth(300, 0.0, 0.05);
  const ve::Sim3 S = knownSim3();
  const ve::Trajectory first(gt.begin(), gt.begin() + 150), second_gt(gt.begin() + 150, gt.end());
  const ve::Trajectory first_est = transformWithNoise(first, S.inverse(), 0.001, 2).estimate;
  const ve::EvalResult r0 = ve::evaluate(first_est, first);
  ve::EvalConfig given;
  given.given_alignment = r0.alignment;
  const Noisy second = transformWithNoise(second_gt, S.inverse(), 0.001, 3);
  const ve::EvalResult same_map = ve::evaluate(second.estimate, second_gt, given);
  EXPECT_LT(same_map.ate.rmse, 1.2 * second.true_rmse);
  EXPECT_EQ(same_map.alignment.scale, r0.alignment.scale);
  ve::Sim3 other = S.inverse();
  other.t += Eigen::Vector3d(0.05, 0.0, 0.0);  // 5 cm away in the estimate's units
  const ve::Trajectory elsewhere = transformWithNoise(second_gt, other, 0.0, 4).estimate;
  EXPECT_NEAR(ve::evaluate(elsewhere, second_gt, given).ate.rmse, 0.05 * S.scale, 1e-3);
  EXPECT_LT(ve::evaluate(elsewhere, second_gt).ate.rmse, 1e-6);
  given.given_alignment->scale = 0.0;
  EXPECT_THROW(given.validate(), std::invalid_argument);
}

TEST(Readers, RejectBadInput) {
  TempDir dir;
  FILE* f = std::fopen(dir.file("bad.txt").c_str(), "w");
  std::fprintf(f, "# header\n1.0 2.0 3.0\n");
  std::fclose(f);
  EXPECT_THROW(ve::readTrajectory(dir.file("bad.txt")), ve::TrajectoryError);
  f = std::fopen(dir.file("bad2.txt").c_str(), "w");
  std::fprintf(f, "1 0 0 0 0 0 0 1\n2 0 0 0 0 x 0 1\n");
  std::fclose(f);
  EXPECT_THROW(ve::readTrajectory(dir.file("bad2.txt")), ve::TrajectoryError);
  EXPECT_THROW(ve::readTrajectory(dir.file("nope.txt")), ve::TrajectoryError);
  f = std::fopen(dir.file("empty.txt").c_str(), "w");
  std::fclose(f);
  EXPECT_TRUE(ve::readTrajectory(dir.file("empty.txt")).empty());
  EXPECT_THROW(ve::evaluate({}, makeGroundTruth(10, 0.0, 0.1)), ve::TrajectoryError);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
