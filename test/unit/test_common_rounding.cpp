// common/rounding.h: roundHalfAway gives std::lround's result, ties and negatives included, for
// doubles and floats over the range of pixel coordinates.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "vitamin_e/common/rounding.h"

using vitamin_e::common::roundHalfAway;

TEST(Rounding, TiesGoAwayFromZeroAsLround) {
  for (double x : {0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 0.49999999999999994, -0.49999999999999994, 1e9 + 0.5, -1e9 - 0.5,
                   0.0, -0.0, 2147483646.5}) {
    EXPECT_EQ(roundHalfAway(x), std::lround(x)) << x;
  }
  for (float x : {0.5f, -0.5f, 1.5f, -1.5f, 1240.5f, -3.5f, 0.49999997f, -0.49999997f, 8388607.5f, 16777216.f}) {
    EXPECT_EQ(roundHalfAway(x), std::lround(x)) << x;
  }
}

TEST(Rounding, MatchesLroundOnRandomCoordinates) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> wide(-5000.0, 5000.0);
  std::uniform_int_distribution<int> whole(-5000, 5000);
  for (int k = 0; k < 200000; ++k) {
    // Half of them exactly on or next to a tie.
    double x = wide(rng);
    if (k % 2) x = whole(rng) + (k % 4 == 1 ? 0.5 : std::nextafter(0.5, 0.0));
    ASSERT_EQ(roundHalfAway(x), std::lround(x)) << x;
    const float xf = static_cast<float>(x);
    ASSERT_EQ(roundHalfAway(xf), std::lround(xf)) << xf;
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
