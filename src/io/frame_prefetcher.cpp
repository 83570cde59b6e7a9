#include "vitamin_e/io/frame_prefetcher.h"

#include <stdexcept>

#include "vitamin_e/common/timing.h"

namespace vitamin_e::io {

FramePrefetcher::FramePrefetcher(const Dataset& dataset, std::size_t first, std::size_t end, std::size_t stride,
                                 std::size_t ahead)
    : dataset_(dataset), ready_(ahead) {
  if (stride == 0) throw std::invalid_argument("FramePrefetcher: stride must be >= 1");
  if (ahead == 0) throw std::invalid_argument("FramePrefetcher: ahead must be >= 1");
  reader_ = std::thread([this, first, end, stride] { readLoop(first, end, stride); });
}

FramePrefetcher::~FramePrefetcher() {
  ready_.close();  // a reader blocked on a full queue returns: push() fails once closed
  if (reader_.joinable()) reader_.join();
}

void FramePrefetcher::readLoop(std::size_t first, std::size_t end, std::size_t stride) {
  for (std::size_t i = first; i < end; i += stride) {
    PrefetchedFrame f;
    f.index = i;
    f.timestamp = dataset_.timestamp(i);
    f.timestamp_text = dataset_.timestampText(i);
    const auto t0 = TimingClock::now();
    const double cpu0 = threadCpuMs();
    try {
      f.image = dataset_.loadImage(i);
    } catch (const DatasetError& e) {
      f.image.release();
      f.error = e.what();
    } catch (const std::exception& e) {  // a reader's bug must not end the process from this thread
      f.image.release();
      f.error = std::string("frame ") + std::to_string(i) + ": " + e.what();
    }
    f.load_cpu_ms = threadCpuMs() - cpu0;
    f.load_ms = elapsedMs(t0);
    if (!ready_.push(std::move(f))) return;  // closed: the consumer is gone
  }
  ready_.close();
}

std::optional<PrefetchedFrame> FramePrefetcher::next() { return ready_.pop(); }

}  // namespace vitamin_e::io
