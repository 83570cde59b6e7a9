// The ROS layer's conversions on bad input, without a ROS master:
// every image encoding the nodelet may receive (converted or rejected with a
// message), malformed image messages, camera_info, and the finiteness checks
// the publishing path relies on (tf, pose, odometry, clouds never carry NaN).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "vitamin_e/ros/conversions.h"

namespace enc = sensor_msgs::image_encodings;
using vitamin_e_ros::toMono8;

namespace {

constexpr int kW = 8, kH = 6;

// An image whose pixel (x, y) has channel values {r, g, b} (or one value).
sensor_msgs::Image makeImage(const std::string& encoding, int channels, int bytes_per_channel) {
  sensor_msgs::Image m;
  m.encoding = encoding;
  m.width = kW;
  m.height = kH;
  m.is_bigendian = 0;
  m.step = kW * channels * bytes_per_channel;
  m.data.assign(static_cast<std::size_t>(m.step) * kH, 0);
  return m;
}

bool convert(const sensor_msgs::Image& m, cv::Mat* gray, std::string* error) {
  error->clear();
  return toMono8(m, gray, error);
}

}  // namespace

TEST(RosConversions, ColorEncodingsBecomeGrayWithTheRightChannelOrder) {
  // Pure red in rgb8 and pure red in bgr8 must give the same gray (0.299 * 255).
  sensor_msgs::Image rgb = makeImage(enc::RGB8, 3, 1);
  sensor_msgs::Image bgr = makeImage(enc::BGR8, 3, 1);
  for (int p = 0; p < kW * kH; ++p) {
    rgb.data[3 * p + 0] = 255;
    bgr.data[3 * p + 2] = 255;
  }
  cv::Mat a, b;
  std::string err;
  ASSERT_TRUE(convert(rgb, &a, &err)) << err;
  ASSERT_TRUE(convert(bgr, &b, &err)) << err;
  ASSERT_EQ(a.type(), CV_8UC1);
  ASSERT_EQ(a.size(), cv::Size(kW, kH));
  EXPECT_NEAR(a.at<std::uint8_t>(2, 3), 76, 1);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  // rgba8 / bgra8 too.
  sensor_msgs::Image rgba = makeImage(enc::RGBA8, 4, 1);
  for (int p = 0; p < kW * kH; ++p) rgba.data[4 * p + 1] = 200;  // green
  ASSERT_TRUE(convert(rgba, &a, &err)) << err;
  EXPECT_NEAR(a.at<std::uint8_t>(0, 0), 0.587 * 200, 1.0);
}

TEST(RosConversions, Mono16IsScaledTo8Bit) {
  for (const std::string& e : {enc::MONO16, enc::TYPE_16UC1}) {
    sensor_msgs::Image m = makeImage(e, 1, 2);
    for (int p = 0; p < kW * kH; ++p) {
      const std::uint16_t v = static_cast<std::uint16_t>(p == 0 ? 65535 : 100 * 256 + 77);
      std::memcpy(&m.data[2 * static_cast<std::size_t>(p)], &v, 2);  // little endian host
    }
    cv::Mat g;
    std::string err;
    ASSERT_TRUE(convert(m, &g, &err)) << e << ": " << err;
    ASSERT_EQ(g.type(), CV_8UC1);
    EXPECT_EQ(g.at<std::uint8_t>(0, 0), 255) << e;
    EXPECT_NEAR(g.at<std::uint8_t>(1, 1), 100, 1) << e;
  }
  sensor_msgs::Image big = makeImage(enc::MONO16, 1, 2);
  big.is_bigendian = 1;
  cv::Mat g;
  std::string err;
  EXPECT_FALSE(convert(big, &g, &err));
  EXPECT_NE(err.find("big-endian"), std::string::npos) << err;
}

TEST(RosConversions, Mono8WithPaddedRowsKeepsItsStep) {
  sensor_msgs::Image m = makeImage(enc::MONO8, 1, 1);
  m.step = kW + 4;
  m.data.assign(static_cast<std::size_t>(m.step) * kH, 0);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) m.data[y * m.step + x] = static_cast<std::uint8_t>(10 * y + x);
    for (int x = kW; x < static_cast<int>(m.step); ++x) m.data[y * m.step + x] = 255;  // padding
  }
  cv::Mat g;
  std::string err;
  ASSERT_TRUE(convert(m, &g, &err)) << err;
  EXPECT_EQ(g.at<std::uint8_t>(3, 5), 35);
  double maxv = 0;
  cv::minMaxLoc(g, nullptr, &maxv);
  EXPECT_LT(maxv, 255.0) << "row padding read as pixels";
}

TEST(RosConversions, BayerFloatAndUnknownEncodingsAreRejectedWithTheirName) {
  struct Case {
    std::string encoding;
    int channels, bytes;
  };
  for (const Case& c : {Case{enc::BAYER_RGGB8, 1, 1}, Case{enc::BAYER_GRBG16, 1, 2}, Case{enc::TYPE_32FC1, 1, 4},
                        Case{enc::TYPE_64FC1, 1, 8}, Case{enc::YUV422, 2, 1}, Case{"jpeg", 1, 1}, Case{"", 1, 1}}) {
    const sensor_msgs::Image m = makeImage(c.encoding, c.channels, c.bytes);
    cv::Mat g;
    std::string err;
    EXPECT_FALSE(convert(m, &g, &err)) << c.encoding;
    EXPECT_NE(err.find("unsupported image encoding '" + c.encoding + "'"), std::string::npos) << err;
    EXPECT_NE(err.find("mono8"), std::string::npos) << "the message lists what is supported: " << err;
  }
}

TEST(RosConversions, MalformedImageMessagesAreRejectedNotRead) {
  cv::Mat g;
  std::string err;
  sensor_msgs::Image short_data = makeImage(enc::MONO8, 1, 1);
  short_data.data.resize(short_data.data.size() - 1);
  EXPECT_FALSE(convert(short_data, &g, &err));
  EXPECT_NE(err.find("malformed"), std::string::npos) << err;

  sensor_msgs::Image small_step = makeImage(enc::RGB8, 3, 1);
  small_step.step = kW;  // one byte per pixel for 3-byte pixels
  EXPECT_FALSE(convert(small_step, &g, &err));
  EXPECT_NE(err.find("malformed"), std::string::npos) << err;

  sensor_msgs::Image empty = makeImage(enc::MONO8, 1, 1);
  empty.width = 0;
  EXPECT_FALSE(convert(empty, &g, &err));

  sensor_msgs::Image huge = makeImage(enc::MONO16, 1, 2);
  huge.height = 1u << 30;  // claims far more rows than it carries
  EXPECT_FALSE(convert(huge, &g, &err));
  EXPECT_NE(err.find("malformed"), std::string::npos) << err;
}

TEST(RosConversions, CameraInfoWithAnUnknownModelIsRejected) {
  sensor_msgs::CameraInfo info;
  info.width = 160;
  info.height = 120;
  info.K = {150.0, 0.0, 80.0, 0.0, 150.0, 60.0, 0.0, 0.0, 1.0};
  info.distortion_model = "plumb_bob";
  info.D = {0.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(vitamin_e_ros::cameraFromInfo(info).width(), 160);
  info.distortion_model = "mystery";
  info.D = {0.1, 0.0, 0.0, 0.0};
  EXPECT_THROW(vitamin_e_ros::cameraFromInfo(info), vitamin_e::camera::CalibrationError);
  // All-zero K (an uncalibrated camera_info): rejected, not a camera with f = 0.
  sensor_msgs::CameraInfo zero;
  zero.width = 160;
  zero.height = 120;
  bool rejected = false;
  try {
    const auto cam = vitamin_e_ros::cameraFromInfo(zero);
    rejected = !cam.valid();
  } catch (const std::exception&) {
    rejected = true;
  }
  EXPECT_TRUE(rejected) << "a camera_info with K = 0 gave a valid camera";
  // image_publisher without camera_info_url: K = [1 0 w/2; 0 1 h/2], refused by name.
  sensor_msgs::CameraInfo placeholder = zero;
  placeholder.K = {1.0, 0.0, 80.0, 0.0, 1.0, 60.0, 0.0, 0.0, 1.0};
  placeholder.P = {1.0, 0.0, 80.0, 0.0, 0.0, 1.0, 60.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  placeholder.distortion_model = "plumb_bob";
  placeholder.D = {0.0, 0.0, 0.0, 0.0, 0.0};
  for (bool rectified : {false, true}) {
    try {
      vitamin_e_ros::cameraFromInfo(placeholder, rectified);
      ADD_FAILURE() << "a placeholder camera_info (fx = 1) was accepted";
    } catch (const vitamin_e::camera::CalibrationError& e) {
      EXPECT_NE(std::string(e.what()).find("placeholder"), std::string::npos) << e.what();
    }
  }
  // A wide real lens is kept: a 180 deg fisheye on 160 px, f = 160 / pi.
  placeholder.K[0] = placeholder.K[4] = 51.0;
  placeholder.distortion_model = "equidistant";
  placeholder.D = {0.01, 0.0, 0.0, 0.0};
  EXPECT_EQ(vitamin_e_ros::cameraFromInfo(placeholder).width(), 160);
}

TEST(RosConversions, FinitenessChecksCatchEveryBadPose) {
  using vitamin_e_ros::isFinite;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << 1, 2, 3;
  EXPECT_TRUE(isFinite(T));
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      for (const double bad : {nan, inf, -inf}) {
        Eigen::Isometry3d B = T;
        B.matrix()(r, c) = bad;
        EXPECT_FALSE(isFinite(B)) << r << "," << c;
      }
    }
  }
  Eigen::Isometry3d scaled = T;
  scaled.linear() *= 1.01;  // not a rotation: a quaternion from it is meaningless
  EXPECT_FALSE(isFinite(scaled));
  EXPECT_FALSE(isFinite(Eigen::Vector3d(0, nan, 0)));
  EXPECT_TRUE(isFinite(Eigen::Vector3d(0, 1e30, 0)));

  // A valid pose round-trips through Pose and Transform with a unit quaternion.
  Eigen::Isometry3d R = Eigen::Isometry3d::Identity();
  R.linear() = Eigen::AngleAxisd(3.1, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  R.translation() << -4, 5, 0.5;
  const geometry_msgs::Pose p = vitamin_e_ros::toPoseMsg(R);
  const double qn = std::sqrt(p.orientation.w * p.orientation.w + p.orientation.x * p.orientation.x +
                              p.orientation.y * p.orientation.y + p.orientation.z * p.orientation.z);
  EXPECT_NEAR(qn, 1.0, 1e-12);
  EXPECT_LT((vitamin_e_ros::fromPoseMsg(p).matrix() - R.matrix()).norm(), 1e-9);
  EXPECT_LT((vitamin_e_ros::fromTransformMsg(vitamin_e_ros::toTransformMsg(R)).matrix() - R.matrix()).norm(), 1e-9);
}

TEST(RosConversions, CloudsHoldExactlyThePointsGiven) {
  std_msgs::Header h;
  h.frame_id = "map";
  const std::vector<Eigen::Vector3f> pts = {{1, 2, 3}, {-1, 0.5f, 7}};
  sensor_msgs::PointCloud2 cloud;
  vitamin_e_ros::fillCloud(h, pts, {10, 20}, &cloud);
  EXPECT_EQ(cloud.width * cloud.height, 2u);
  EXPECT_TRUE(cloud.is_dense);
  sensor_msgs::PointCloud2ConstIterator<float> x(cloud, "x"), i(cloud, "intensity");
  EXPECT_EQ(*x, 1.0f);
  EXPECT_EQ(*i, 10.0f);
  sensor_msgs::PointCloud2 empty;
  vitamin_e_ros::fillCloud(h, {}, {}, &empty);
  EXPECT_EQ(empty.width * empty.height, 0u);
}


// A rectified stream takes P and no distortion; rational_polynomial is
// refused when k4..k6 are not zero; binning and ROI give the image's own intrinsics.
TEST(RosConversions, CameraInfoRectifiedRationalBinningAndRoi) {
  using vitamin_e::camera::DistortionModel;
  sensor_msgs::CameraInfo info;
  info.width = 752;
  info.height = 480;
  info.K = {458.0, 0.0, 367.0, 0.0, 457.0, 248.0, 0.0, 0.0, 1.0};
  info.P = {380.0, 0.0, 370.0, 0.0, 0.0, 381.0, 240.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  info.distortion_model = "plumb_bob";
  info.D = {-0.28, 0.07, 0.0002, 0.00002, 0.0};
  const auto raw = vitamin_e_ros::cameraFromInfo(info, false);
  EXPECT_EQ(raw.model(), DistortionModel::kRadialTangential);
  EXPECT_DOUBLE_EQ(raw.fx(), 458.0);
  EXPECT_EQ(raw.distortion().size(), 4u);
  const auto rect = vitamin_e_ros::cameraFromInfo(info, true);
  EXPECT_EQ(rect.model(), DistortionModel::kNone);
  EXPECT_DOUBLE_EQ(rect.fx(), 380.0);
  EXPECT_DOUBLE_EQ(rect.fy(), 381.0);
  EXPECT_DOUBLE_EQ(rect.cx(), 370.0);
  EXPECT_DOUBLE_EQ(rect.cy(), 240.0);
  // P = 0 (camera_info of an uncalibrated camera) cannot describe a rectified image.
  sensor_msgs::CameraInfo no_p = info;
  no_p.P.fill(0.0);
  EXPECT_THROW(vitamin_e_ros::cameraFromInfo(no_p, true), vitamin_e::camera::CalibrationError);

  EXPECT_TRUE(vitamin_e_ros::isRectifiedTopic("/cam0/image_rect"));
  EXPECT_TRUE(vitamin_e_ros::isRectifiedTopic("/cam0/image_rect_color"));
  EXPECT_TRUE(vitamin_e_ros::isRectifiedTopic("image_rect"));
  EXPECT_FALSE(vitamin_e_ros::isRectifiedTopic("/cam0/image_raw"));
  EXPECT_FALSE(vitamin_e_ros::isRectifiedTopic("/image_rect/image_raw"));

  // rational_polynomial: zeros beyond k3 are fine, anything else is refused by name.
  sensor_msgs::CameraInfo rational = info;
  rational.distortion_model = "rational_polynomial";
  rational.D = {-0.28, 0.07, 0.0002, 0.00002, 0.01, 0.0, 0.0, 0.0};
  EXPECT_EQ(vitamin_e_ros::cameraFromInfo(rational).distortion().size(), 5u);
  rational.D[5] = 0.3;
  try {
    vitamin_e_ros::cameraFromInfo(rational);
    ADD_FAILURE() << "rational_polynomial with k4 != 0 accepted";
  } catch (const vitamin_e::camera::CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("D[5]"), std::string::npos) << e.what();
  }
  // The rectified stream does not use D at all.
  EXPECT_NO_THROW(vitamin_e_ros::cameraFromInfo(rational, true));

  // ROI 400x300 at (100, 60), binning 2: a 200x150 image; the principal point moves with the
  // window and the binned pixel centres.
  sensor_msgs::CameraInfo binned = info;
  binned.roi.x_offset = 100;
  binned.roi.y_offset = 60;
  binned.roi.width = 400;
  binned.roi.height = 300;
  binned.binning_x = binned.binning_y = 2;
  const auto b = vitamin_e_ros::cameraFromInfo(binned);
  EXPECT_EQ(b.width(), 200);
  EXPECT_EQ(b.height(), 150);
  EXPECT_DOUBLE_EQ(b.fx(), 229.0);
  EXPECT_DOUBLE_EQ(b.fy(), 228.5);
  EXPECT_DOUBLE_EQ(b.cx(), (367.0 - 100.0 + 0.5) / 2.0 - 0.5);
  EXPECT_DOUBLE_EQ(b.cy(), (248.0 - 60.0 + 0.5) / 2.0 - 0.5);
  // A full-resolution point projects to the binned pixel that covers it.
  const Eigen::Vector3d p_c(0.3, -0.2, 2.0);
  Eigen::Vector2d uv_full, uv_binned;
  ASSERT_TRUE(raw.project(p_c, &uv_full));
  ASSERT_TRUE(b.project(p_c, &uv_binned));
  EXPECT_NEAR(uv_binned.x(), (uv_full.x() - 100.0 + 0.5) / 2.0 - 0.5, 1e-9);
  EXPECT_NEAR(uv_binned.y(), (uv_full.y() - 60.0 + 0.5) / 2.0 - 0.5, 1e-9);
  binned.roi.width = 700;  // 100 + 700 > 752
  EXPECT_THROW(vitamin_e_ros::cameraFromInfo(binned), vitamin_e::camera::CalibrationError);
}

TEST(RosConversions, CompressedImagesDecodeToTheSameGray) {
  cv::Mat gray(48, 64, CV_8UC1);
  cv::randu(gray, 0, 255);
  sensor_msgs::CompressedImage png;
  png.format = "mono8; png compressed ";
  std::vector<std::uint8_t> buf;
  ASSERT_TRUE(cv::imencode(".png", gray, buf));
  png.data = buf;
  cv::Mat out;
  std::string err;
  ASSERT_TRUE(vitamin_e_ros::compressedToMono8(png, &out, &err)) << err;
  EXPECT_EQ(cv::norm(out, gray, cv::NORM_INF), 0.0);  // png is lossless
  // Colour JPEG (bgr8): converted to gray like a raw bgr8 image, up to JPEG's loss.
  cv::Mat bgr;
  cv::cvtColor(gray, bgr, cv::COLOR_GRAY2BGR);
  cv::GaussianBlur(bgr, bgr, cv::Size(5, 5), 1.5);
  cv::Mat expect;
  cv::cvtColor(bgr, expect, cv::COLOR_BGR2GRAY);
  sensor_msgs::CompressedImage jpeg;
  jpeg.format = "bgr8; jpeg compressed bgr8";
  ASSERT_TRUE(cv::imencode(".jpg", bgr, buf, {cv::IMWRITE_JPEG_QUALITY, 95}));
  jpeg.data = buf;
  ASSERT_TRUE(vitamin_e_ros::compressedToMono8(jpeg, &out, &err)) << err;
  ASSERT_EQ(out.type(), CV_8UC1);
  EXPECT_LT(cv::norm(out, expect, cv::NORM_L1) / out.total(), 3.0);
  // Garbage and depth images are refused with a message.
  sensor_msgs::CompressedImage bad = jpeg;
  bad.data.assign(100, 7);
  EXPECT_FALSE(vitamin_e_ros::compressedToMono8(bad, &out, &err));
  EXPECT_NE(err.find("cannot decode"), std::string::npos) << err;
  bad.format = "16UC1; compressedDepth";
  EXPECT_FALSE(vitamin_e_ros::compressedToMono8(bad, &out, &err));
  sensor_msgs::CompressedImage empty;
  EXPECT_FALSE(vitamin_e_ros::compressedToMono8(empty, &out, &err));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
