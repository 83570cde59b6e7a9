#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

#include "vitamin_e/camera/camera.h"

using vitamin_e::camera::CalibrationError;
using vitamin_e::camera::Camera;
using vitamin_e::camera::DistortionModel;

namespace {

Camera eurocCamera() {
  return Camera(752, 480, 458.654, 457.296, 367.215, 248.375, DistortionModel::kRadialTangential,
                {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
}
Camera radtan5Camera() {
  return Camera(640, 480, 520.0, 515.0, 322.0, 241.0, DistortionModel::kRadialTangential,
                {-0.21, 0.05, 0.0012, -0.0008, -0.004});
}
Camera fisheyeCamera() {
  return Camera(640, 480, 350.0, 349.0, 319.5, 239.5, DistortionModel::kEquidistant,
                {-0.0073, 0.0426, -0.0407, 0.0077});
}
Camera pinholeCamera() { return Camera(640, 480, 500.0, 500.0, 320.0, 240.0); }

std::vector<Camera> allCameras() { return {eurocCamera(), radtan5Camera(), fisheyeCamera(), pinholeCamera()}; }

}  // namespace

TEST(Camera, ConstructorRejectsBadValues) {
  EXPECT_THROW(Camera(0, 480, 500, 500, 320, 240), CalibrationError);
  EXPECT_THROW(Camera(640, -1, 500, 500, 320, 240), CalibrationError);
  EXPECT_THROW(Camera(640, 480, 0.0, 500, 320, 240), CalibrationError);
  EXPECT_THROW(Camera(640, 480, 500, -3.0, 320, 240), CalibrationError);
  EXPECT_THROW(Camera(640, 480, 500, 500, NAN, 240), CalibrationError);
  EXPECT_THROW(Camera(640, 480, 500, 500, 320, 240, DistortionModel::kRadialTangential, {0.1, 0.2, 0.3}),
               CalibrationError);
  EXPECT_THROW(Camera(640, 480, 500, 500, 320, 240, DistortionModel::kEquidistant, {0.1, 0.2, 0.3, 0.4, 0.5}),
               CalibrationError);
  EXPECT_THROW(Camera(640, 480, 500, 500, 320, 240, DistortionModel::kNone, {0.1}), CalibrationError);
  EXPECT_THROW(Camera(640, 480, 500, 500, 320, 240, DistortionModel::kRadialTangential, {0.1, INFINITY, 0, 0}),
               CalibrationError);
  EXPECT_NO_THROW(radtan5Camera());
  EXPECT_FALSE(Camera().valid());
}

TEST(Camera, PinholeProjectionMatchesK) {
  const Camera cam = pinholeCamera();
  Eigen::Vector2d uv;
  ASSERT_TRUE(cam.project(Eigen::Vector3d(1.0, -0.5, 2.0), &uv));
  const Eigen::Vector3d h = cam.pinhole().matrix() * Eigen::Vector3d(1.0, -0.5, 2.0);
  EXPECT_NEAR(uv.x(), h.x() / h.z(), 1e-12);
  EXPECT_NEAR(uv.y(), h.y() / h.z(), 1e-12);
  // Behind the camera: false, uv untouched.
  uv = Eigen::Vector2d(-7, -7);
  EXPECT_FALSE(cam.project(Eigen::Vector3d(0.1, 0.1, -1.0), &uv));
  EXPECT_FALSE(cam.project(Eigen::Vector3d(0.1, 0.1, 0.0), &uv));
  EXPECT_EQ(uv, Eigen::Vector2d(-7, -7));
}

TEST(Pinhole, ProjectUnprojectRayAndPointAgree) {
  const vitamin_e::camera::Pinhole K{458.0, 457.0, 367.5, 248.25};
  const Eigen::Vector2d xy(0.31, -0.22);
  const Eigen::Vector2d uv = K.project(xy);
  EXPECT_NEAR(uv.x(), 458.0 * 0.31 + 367.5, 1e-12);
  EXPECT_NEAR(uv.y(), 457.0 * -0.22 + 248.25, 1e-12);
  EXPECT_LT((K.unproject(uv) - xy).norm(), 1e-12);
  EXPECT_EQ(K.ray(uv), Eigen::Vector3d(K.unproject(uv).x(), K.unproject(uv).y(), 1.0));
  const Eigen::Vector3d p_c(0.62, -0.44, 2.0);  // = 2 * (xy, 1)
  EXPECT_LT((K.projectPoint(p_c) - uv).norm(), 1e-12);
  const Eigen::Vector3d h = K.matrix() * p_c;
  EXPECT_LT((h.hnormalized() - uv).norm(), 1e-12);
  // The camera's pinhole part is what it was built with.
  const Camera cam(752, 480, 458.0, 457.0, 367.5, 248.25);
  EXPECT_EQ(cam.pinhole(), K);
  EXPECT_NE(cam.pinhole(), (vitamin_e::camera::Pinhole{458.0, 457.0, 367.5, 248.0}));
}

TEST(Pinhole, BinningKeepsPixelCentresAndValidityIsChecked) {
  const vitamin_e::camera::Pinhole K{400.0, 410.0, 319.5, 239.5};
  // 2x2 binning: full pixels 0 and 1 become binned pixel 0, centred at full 0.5.
  const vitamin_e::camera::Pinhole B = K.binned(2.0, 2.0);
  for (const Eigen::Vector2d& full : {Eigen::Vector2d(0.5, 0.5), Eigen::Vector2d(100.5, 300.5)}) {
    const Eigen::Vector2d binned = (full - Eigen::Vector2d(0.5, 0.5)) / 2.0;
    EXPECT_LT((B.unproject(binned) - K.unproject(full)).norm(), 1e-12);
  }
  EXPECT_TRUE(K.valid());
  EXPECT_FALSE((vitamin_e::camera::Pinhole{0.0, 410.0, 319.5, 239.5}.valid()));
  EXPECT_FALSE((vitamin_e::camera::Pinhole{400.0, -1.0, 319.5, 239.5}.valid()));
  EXPECT_FALSE((vitamin_e::camera::Pinhole{400.0, 410.0, NAN, 239.5}.valid()));
}

TEST(Camera, DistortionBendsTheImageAsExpected) {
  // EuRoC's barrel distortion pulls the corners towards the centre.
  const Camera cam = eurocCamera();
  const Eigen::Vector2d xy(-0.8, -0.55);
  const Eigen::Vector2d d = cam.distortNormalized(xy);
  const Eigen::Vector2d p = cam.pinhole().project(xy);
  const Eigen::Vector2d c(cam.cx(), cam.cy());
  EXPECT_LT((d - c).norm(), (p - c).norm() - 50.0);
  // The principal point is a fixed point of every model.
  for (const Camera& k : allCameras()) {
    Eigen::Vector3d b;
    ASSERT_TRUE(k.unproject(Eigen::Vector2d(k.cx(), k.cy()), &b));
    EXPECT_NEAR((b - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-6);
  }
}

TEST(Camera, UnprojectProjectRoundTripOverTheWholeImage) {
  for (const Camera& cam : allCameras()) {
    double worst = 0.0;
    int count = 0;
    for (double v = 0.0; v <= cam.height() - 1.0; v += (cam.height() - 1.0) / 60.0) {
      for (double u = 0.0; u <= cam.width() - 1.0; u += (cam.width() - 1.0) / 90.0) {
        const Eigen::Vector2d uv(u, v);
        Eigen::Vector3d bearing;
        ASSERT_TRUE(cam.unproject(uv, &bearing)) << cam.describe() << " at " << u << "," << v;
        EXPECT_NEAR(bearing.norm(), 1.0, 1e-12);
        ASSERT_GT(bearing.z(), 0.0);
        // Along the ray at some depth, back to the same pixel.
        Eigen::Vector2d back;
        ASSERT_TRUE(cam.project(bearing * 3.7, &back));
        worst = std::max(worst, (back - uv).norm());
        ++count;
      }
    }
    EXPECT_GT(count, 5000);
    EXPECT_LT(worst, 1e-6) << cam.describe();
  }
}

TEST(Camera, ProjectUnprojectRoundTripForPointsInView) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (const Camera& cam : allCameras()) {
    int checked = 0;
    for (int i = 0; i < 2000; ++i) {
      const Eigen::Vector3d p(U(rng) * 3.0, U(rng) * 2.0, 2.0 + 3.0 * (U(rng) + 1.0));
      Eigen::Vector2d uv;
      ASSERT_TRUE(cam.project(p, &uv));
      if (!cam.inImage(uv)) continue;
      Eigen::Vector3d b;
      ASSERT_TRUE(cam.unproject(uv, &b));
      EXPECT_LT((b - p.normalized()).norm(), 1e-9) << cam.describe();
      ++checked;
    }
    EXPECT_GT(checked, 300) << cam.describe();
  }
}

TEST(Camera, ProjectionJacobianMatchesNumericDifferences) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const double h = 1e-6;
  for (const Camera& cam : allCameras()) {
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d p(U(rng) * 2.0, U(rng) * 1.5, 1.5 + U(rng));
      Eigen::Vector2d uv;
      Eigen::Matrix<double, 2, 3> J;
      ASSERT_TRUE(cam.project(p, &uv, &J));
      Eigen::Vector2d uv_plain;
      cam.project(p, &uv_plain);
      EXPECT_LT((uv - uv_plain).norm(), 1e-12);
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d dp = Eigen::Vector3d::Zero();
        dp[k] = h;
        Eigen::Vector2d a, b;
        cam.project(p + dp, &a);
        cam.project(p - dp, &b);
        const Eigen::Vector2d num = (a - b) / (2.0 * h);
        EXPECT_LT((J.col(k) - num).norm(), 1e-5 * (1.0 + num.norm())) << cam.describe() << " col " << k;
      }
    }
  }
}

TEST(Camera, DistortionJacobianMatchesNumericDifferences) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const double h = 1e-7;
  for (const Camera& cam : allCameras()) {
    std::vector<Eigen::Vector2d> samples = {Eigen::Vector2d(0, 0), Eigen::Vector2d(1e-10, -2e-10)};
    for (int i = 0; i < 300; ++i) samples.emplace_back(U(rng) * 0.9, U(rng) * 0.7);
    for (const Eigen::Vector2d& xy : samples) {
      Eigen::Matrix2d J;
      cam.distortNormalized(xy, &J);
      for (int k = 0; k < 2; ++k) {
        Eigen::Vector2d d = Eigen::Vector2d::Zero();
        d[k] = h;
        const Eigen::Vector2d num = (cam.distortNormalized(xy + d) - cam.distortNormalized(xy - d)) / (2.0 * h);
        EXPECT_LT((J.col(k) - num).norm(), 2e-5 * (1.0 + num.norm()))
            << cam.describe() << " at " << xy.transpose() << " col " << k;
      }
    }
  }
}

TEST(Camera, UndistortionMapsAgreeWithUnproject) {
  for (const Camera& cam : allCameras()) {
    cv::Mat mx, my;
    cam.undistortionMaps(&mx, &my);
    ASSERT_EQ(mx.type(), CV_32FC1);
    ASSERT_EQ(mx.size(), cv::Size(cam.width(), cam.height()));
    ASSERT_EQ(my.size(), mx.size());
    double worst = 0.0;
    for (int v = 0; v < cam.height(); v += 7) {
      for (int u = 0; u < cam.width(); u += 7) {
        const Eigen::Vector2d src(mx.at<float>(v, u), my.at<float>(v, u));
        if (!cam.inImage(src)) continue;
        Eigen::Vector2d xy;
        ASSERT_TRUE(cam.unprojectNormalized(src, &xy));
        // Back through K: the output pixel (float storage: ~1e-4 px).
        worst = std::max(worst, (cam.pinhole().project(xy) - Eigen::Vector2d(u, v)).norm());
      }
    }
    EXPECT_LT(worst, 2e-3) << cam.describe();
  }
}

TEST(Camera, RemapProducesTheUndistortedImage) {
  // A smooth pattern defined on normalized coordinates, rendered through the
  // lens; undistorting it must give the pattern rendered by an ideal pinhole.
  const Camera cam = eurocCamera();
  auto pattern = [](const Eigen::Vector2d& xy) {
    return 128.0 + 90.0 * std::sin(7.0 * xy.x()) * std::cos(6.0 * xy.y());
  };
  cv::Mat distorted(cam.height(), cam.width(), CV_32FC1);
  for (int v = 0; v < cam.height(); ++v)
    for (int u = 0; u < cam.width(); ++u) {
      Eigen::Vector2d xy;
      ASSERT_TRUE(cam.unprojectNormalized(Eigen::Vector2d(u, v), &xy));
      distorted.at<float>(v, u) = static_cast<float>(pattern(xy));
    }
  cv::Mat mx, my, undistorted;
  cam.undistortionMaps(&mx, &my);
  cv::remap(distorted, undistorted, mx, my, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(-1000));
  double sum = 0.0;
  int n = 0;
  for (int v = 0; v < cam.height(); ++v)
    for (int u = 0; u < cam.width(); ++u) {
      const float got = undistorted.at<float>(v, u);
      if (got < -1.0) continue;  // outside the lens' view
      const Eigen::Vector2d xy((u - cam.cx()) / cam.fx(), (v - cam.cy()) / cam.fy());
      sum += std::abs(got - pattern(xy));
      ++n;
    }
  ASSERT_GT(n, cam.width() * cam.height() / 2);
  EXPECT_LT(sum / n, 0.2);
}

TEST(Camera, InImageAndDescribe) {
  const Camera cam = eurocCamera();
  EXPECT_TRUE(cam.inImage(Eigen::Vector2d(0, 0)));
  EXPECT_TRUE(cam.inImage(Eigen::Vector2d(751, 479)));
  EXPECT_FALSE(cam.inImage(Eigen::Vector2d(751.5, 10)));
  EXPECT_FALSE(cam.inImage(Eigen::Vector2d(5, 5), 8.0));
  EXPECT_TRUE(cam.inImage(Eigen::Vector2d(8, 8), 8.0));
  const std::string d = cam.describe();
  EXPECT_NE(d.find("752x480"), std::string::npos);
  EXPECT_NE(d.find("radial-tangential"), std::string::npos);
  EXPECT_NE(d.find("458.654"), std::string::npos);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
