// FramePrefetcher: frames read ahead on another thread come out in order, each
// once, with their stamps; unreadable frames come out with their error; a
// consumer that stops early does not hang.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>

#include "vitamin_e/io/frame_prefetcher.h"

using namespace vitamin_e;

namespace {
// Frame i: a 4x3 image filled with i; frames in `bad` cannot be read.
class CountingDataset : public io::Dataset {
 public:
  CountingDataset(std::size_t n, std::vector<std::size_t> bad) : n_(n), bad_(std::move(bad)) {}
  std::string kind() const override { return "test"; }
  std::size_t size() const override { return n_; }
  double timestamp(std::size_t i) const override { return 0.05 * static_cast<double>(i); }
  std::string timestampText(std::size_t i) const override { return "t" + std::to_string(i); }
  cv::Mat loadImage(std::size_t i) const override {
    ++loads;
    if (std::find(bad_.begin(), bad_.end(), i) != bad_.end()) throw io::DatasetError("frame " + std::to_string(i));
    return cv::Mat(3, 4, CV_8UC1, cv::Scalar(static_cast<double>(i)));
  }
  const camera::CameraCalibration& calibration() const override { return calib_; }
  mutable std::atomic<int> loads{0};

 private:
  std::size_t n_;
  std::vector<std::size_t> bad_;
  camera::CameraCalibration calib_;
};
}  // namespace

TEST(FramePrefetcher, DeliversEveryStrideThFrameInOrder) {
  CountingDataset data(20, {});
  io::FramePrefetcher ahead(data, 3, 17, 3, 2);
  std::vector<std::size_t> seen;
  while (std::optional<io::PrefetchedFrame> f = ahead.next()) {
    ASSERT_FALSE(f->image.empty());
    EXPECT_EQ(f->image.at<std::uint8_t>(1, 2), f->index);
    EXPECT_DOUBLE_EQ(f->timestamp, 0.05 * static_cast<double>(f->index));
    EXPECT_EQ(f->timestamp_text, "t" + std::to_string(f->index));
    EXPECT_TRUE(f->error.empty());
    EXPECT_GE(f->load_ms, 0.0);
    seen.push_back(f->index);
  }
  EXPECT_EQ(seen, (std::vector<std::size_t>{3, 6, 9, 12, 15}));
  EXPECT_EQ(data.loads.load(), 5);
}

TEST(FramePrefetcher, UnreadableFramesComeOutWithTheirError) {
  CountingDataset data(5, {1, 4});
  io::FramePrefetcher ahead(data, 0, 5, 1, 1);
  std::vector<std::string> errors;
  std::size_t images = 0;
  while (std::optional<io::PrefetchedFrame> f = ahead.next()) {
    if (f->image.empty()) {
      errors.push_back(f->error);
    } else {
      ++images;
    }
  }
  EXPECT_EQ(images, 3u);
  EXPECT_EQ(errors, (std::vector<std::string>{"frame 1", "frame 4"}));
}

TEST(FramePrefetcher, StoppingEarlyReadsOnlyAFewFramesAheadAndJoins) {
  CountingDataset data(1000, {});
  {
    io::FramePrefetcher ahead(data, 0, 1000, 1, 2);
    ASSERT_TRUE(ahead.next().has_value());
  }  // the destructor must not wait for the other 999 frames
  EXPECT_LE(data.loads.load(), 5);
}

TEST(FramePrefetcher, EmptyRangeAndBadArguments) {
  CountingDataset data(3, {});
  io::FramePrefetcher none(data, 3, 3, 1, 2);
  EXPECT_FALSE(none.next().has_value());
  EXPECT_THROW(io::FramePrefetcher(data, 0, 3, 0, 2), std::invalid_argument);
  EXPECT_THROW(io::FramePrefetcher(data, 0, 3, 1, 0), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
