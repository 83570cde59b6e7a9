#include "vitamin_e/tracking/brief.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>

namespace vitamin_e::tracking {
namespace {

// splitmix64: a small, platform-independent generator so that the test pattern
// is identical everywhere (std:: distributions are not).
struct SplitMix {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
  double gauss() {                                                                             // Box-Muller
    const double u1 = std::max(uniform(), 1e-12), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }
};

}  // namespace

BriefExtractor::BriefExtractor(int patch_size, std::uint32_t seed) : patch_size_(patch_size) {
  if (patch_size < 5 || patch_size % 2 == 0) {
    throw std::invalid_argument("BriefExtractor: patch_size must be odd and >= 5");
  }
  const int r = patch_size / 2;
  const double sigma = patch_size / 5.0;
  SplitMix rng{seed};
  auto draw = [&]() {
    const long v = std::lround(rng.gauss() * sigma);
    return static_cast<int>(std::clamp<long>(v, -r, r));
  };
  pairs_.reserve(256);
  while (pairs_.size() < 256) {
    std::array<int, 4> p{draw(), draw(), draw(), draw()};
    if (p[0] == p[2] && p[1] == p[3]) continue;  // a test against itself carries no information
    pairs_.push_back(p);
  }
}

BriefExtractor BriefExtractor::rotated(int quarter_turns) const {
  BriefExtractor out = *this;
  const int q = ((quarter_turns % 4) + 4) % 4;
  for (auto& p : out.pairs_) {
    for (int k = 0; k < q; ++k) {
      p = {-p[1], p[0], -p[3], p[2]};  // (x, y) -> (-y, x): 90 degrees in image coordinates (y down)
    }
  }
  return out;
}

bool BriefExtractor::describe(const cv::Mat& img, int x, int y, BriefDescriptor* d) const {
  const int r = radius();
  if (x < r || y < r || x >= img.cols - r || y >= img.rows - r) return false;
  // Each test as two offsets from the centre pixel, and each 64-bit word built without branches:
  // the same bits as testing pixel by pixel, with a third fewer instructions.
  const auto build = [&](const auto* centre, std::ptrdiff_t row) {
    for (int w = 0; w < 4; ++w) {
      std::uint64_t word = 0;
      for (int k = 0; k < 64; ++k) {
        const auto& p = pairs_[(w << 6) + k];
        const bool less = centre[p[1] * row + p[0]] < centre[p[3] * row + p[2]];
        word |= static_cast<std::uint64_t>(less) << k;
      }
      d->bits[w] = word;
    }
  };
  if (img.type() == CV_32FC1) {
    build(img.ptr<float>(y) + x, static_cast<std::ptrdiff_t>(img.step1()));
  } else if (img.type() == CV_8UC1) {
    build(img.ptr<std::uint8_t>(y) + x, static_cast<std::ptrdiff_t>(img.step1()));
  } else {
    throw std::invalid_argument("BriefExtractor::describe: image must be CV_32FC1 or CV_8UC1");
  }
  return true;
}

namespace {

// The indices 0..n-1 ordered by sign, ascending within a sign (all of them when
// there are no signs): a match is only ever between equal signs.
std::vector<int> indicesBySign(std::size_t n, const std::vector<signed char>* sign) {
  std::vector<int> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<int>(i);
  if (sign) std::stable_sort(order.begin(), order.end(), [sign](int x, int y) { return (*sign)[x] < (*sign)[y]; });
  return order;
}

}  // namespace

std::vector<std::pair<int, int>> matchBrief(const std::vector<BriefDescriptor>& a,
                                            const std::vector<BriefDescriptor>& b, const MatchConfig& c,
                                            const std::vector<signed char>* sign_a,
                                            const std::vector<signed char>* sign_b) {
  std::vector<std::pair<int, int>> out;
  if (a.empty() || b.empty()) return out;
  const bool use_sign = sign_a && sign_b && sign_a->size() == a.size() && sign_b->size() == b.size();
  const size_t na = a.size(), nb = b.size();
  // The distance matrix's blocks of equal signs, one pass each: best and second
  // best per row, best per column. Rows and columns are visited in ascending
  // index order within a block, so that ties break as in one pass over the whole
  // matrix; the other blocks are never computed (and no per-pair sign test is
  // left for the branch predictor to guess: the signs are random).
  const std::vector<int> rows = indicesBySign(na, use_sign ? sign_a : nullptr);
  const std::vector<int> cols = indicesBySign(nb, use_sign ? sign_b : nullptr);
  std::vector<int> best_a(na, -1), d1_a(na, INT_MAX), d2_a(na, INT_MAX);
  std::vector<int> best_b(nb, -1), d1_b(nb, INT_MAX);
  const auto sign_of = [use_sign](const std::vector<signed char>* sign, int i) { return use_sign ? (*sign)[i] : 0; };
  size_t r0 = 0, c0 = 0;
  while (r0 < na && c0 < nb) {
    const int sr = sign_of(sign_a, rows[r0]), sc = sign_of(sign_b, cols[c0]);
    size_t r1 = r0, c1 = c0;
    while (r1 < na && sign_of(sign_a, rows[r1]) == sr) ++r1;
    while (c1 < nb && sign_of(sign_b, cols[c1]) == sc) ++c1;
    if (sr == sc) {
      for (size_t ri = r0; ri < r1; ++ri) {
        const int i = rows[ri];
        const BriefDescriptor& da = a[static_cast<size_t>(i)];
        int best = -1, d1 = INT_MAX, d2 = INT_MAX;
        for (size_t cj = c0; cj < c1; ++cj) {
          const int j = cols[cj];
          const int d = hammingDistance(da, b[static_cast<size_t>(j)]);
          if (d < d1) {
            d2 = d1;
            d1 = d;
            best = j;
          } else if (d < d2) {
            d2 = d;
          }
          if (d < d1_b[static_cast<size_t>(j)]) {
            d1_b[static_cast<size_t>(j)] = d;
            best_b[static_cast<size_t>(j)] = i;
          }
        }
        best_a[static_cast<size_t>(i)] = best;
        d1_a[static_cast<size_t>(i)] = d1;
        d2_a[static_cast<size_t>(i)] = d2;
      }
    }
    // Advance the block with the smaller sign (both when they are equal).
    if (sr <= sc) r0 = r1;
    if (sc <= sr) c0 = c1;
  }
  for (size_t i = 0; i < na; ++i) {
    const int j = best_a[i];
    if (j < 0 || d1_a[i] > c.max_distance) continue;
    if (c.ratio < 1.0 && d2_a[i] != INT_MAX && d1_a[i] >= c.ratio * d2_a[i]) continue;
    if (c.cross_check && best_b[static_cast<size_t>(j)] != static_cast<int>(i)) continue;
    out.emplace_back(static_cast<int>(i), j);
  }
  return out;
}

}  // namespace vitamin_e::tracking
