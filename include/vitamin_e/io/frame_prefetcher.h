#pragma once
// Reads a dataset's frames ahead of their use on a thread of its own: while the
// SLAM works on frame k, frames k+1.. are decoded (image decoding is a few ms
// per frame, as much as a SLAM stage). Frames come out in order, each once;
// an unreadable frame comes out with its error instead of an image.
//   FramePrefetcher ahead(dataset, first, end, stride, 3);
//   while (std::optional<PrefetchedFrame> f = ahead.next()) ...
#include <cstddef>
#include <optional>
#include <string>
#include <thread>

#include <opencv2/core.hpp>

#include "vitamin_e/common/bounded_queue.h"
#include "vitamin_e/io/dataset.h"

namespace vitamin_e::io {

struct PrefetchedFrame {
  std::size_t index = 0;  // frame index in the dataset
  double timestamp = 0.0;
  std::string timestamp_text;
  cv::Mat image;             // empty when the frame could not be read
  std::string error;         // DatasetError's message when it could not
  double load_ms = 0.0;      // wall time of loadImage on the reading thread
  double load_cpu_ms = 0.0;  // that thread's CPU time for it
};

class FramePrefetcher {
 public:
  // Frames first, first + stride, ... below end; at most `ahead` (>= 1) decoded
  // frames wait. The dataset must outlive this object and must not be read
  // by another thread meanwhile (timestamps excepted: they are read at open).
  FramePrefetcher(const Dataset& dataset, std::size_t first, std::size_t end, std::size_t stride, std::size_t ahead);
  ~FramePrefetcher();  // stops reading and joins (frames not taken are discarded)
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  // The next frame in order; nullopt after the last one. Blocks while it is read.
  std::optional<PrefetchedFrame> next();

 private:
  void readLoop(std::size_t first, std::size_t end, std::size_t stride);

  const Dataset& dataset_;
  BoundedQueue<PrefetchedFrame> ready_;
  std::thread reader_;
};

}  // namespace vitamin_e::io
