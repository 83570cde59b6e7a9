#pragma once
// In-house BRIEF (Calonder et al. 2010): 256 binary intensity comparisons
// between point pairs drawn once from an isotropic Gaussian over a square patch
// of a smoothed image; Hamming-distance matching with a cross-check and a ratio
// test. Used on the shrunk image to get coarse correspondences for the
// dominant flow.
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace vitamin_e::tracking {

struct BriefDescriptor {
  std::array<std::uint64_t, 4> bits{};  // 256 tests
};

inline int hammingDistance(const BriefDescriptor& a, const BriefDescriptor& b) {
  int d = 0;
  for (int i = 0; i < 4; ++i) d += __builtin_popcountll(a.bits[i] ^ b.bits[i]);
  return d;
}

class BriefExtractor {
 public:
  // patch_size: odd side of the test window [px]; the pattern is a fixed
  // function of (patch_size, seed).
  explicit BriefExtractor(int patch_size = 15, std::uint32_t seed = 0x5eed1234u);
  int patchSize() const { return patch_size_; }
  int radius() const { return patch_size_ / 2; }
  // Describes the patch centred at integer (x, y) of a smoothed CV_32FC1 or
  // CV_8UC1 image. False if the patch leaves the image.
  bool describe(const cv::Mat& smoothed, int x, int y, BriefDescriptor* d) const;
  // The same tests turned quarter_turns times by (x, y) -> (-y, x) about the
  // patch centre (exact: integer offsets). Describing an image turned the same
  // way gives the descriptors of the original (2: an upside-down camera).
  BriefExtractor rotated(int quarter_turns) const;

 private:
  int patch_size_;
  std::vector<std::array<int, 4>> pairs_;  // (x1, y1, x2, y2) offsets
};

struct MatchConfig {
  int max_distance = 70;    // accept only Hamming distance <= this
  double ratio = 0.9;       // best < ratio * second best (1 = off)
  bool cross_check = true;  // best in both directions
};

// Matches a (query) to b (train); returns (index in a, index in b) pairs.
// `sign_a`/`sign_b` (optional, same sizes) restrict matches to equal signs.
std::vector<std::pair<int, int>> matchBrief(const std::vector<BriefDescriptor>& a,
                                            const std::vector<BriefDescriptor>& b, const MatchConfig& config,
                                            const std::vector<signed char>* sign_a = nullptr,
                                            const std::vector<signed char>* sign_b = nullptr);

}  // namespace vitamin_e::tracking
