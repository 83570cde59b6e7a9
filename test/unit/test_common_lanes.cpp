// common/lanes.h: each four-lane operation against its lane-by-lane meaning, and the SSE2
// type (x86-64) against the portable one that other CPUs compile.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "vitamin_e/common/lanes.h"

using vitamin_e::common::Lanes;
using vitamin_e::common::PortableLanes;

namespace {

template <typename L>
void expectLanes(const L& l, float a, float b, float c, float d) {
  EXPECT_EQ(l[0], a);
  EXPECT_EQ(l[1], b);
  EXPECT_EQ(l[2], c);
  EXPECT_EQ(l[3], d);
}

template <typename L>
void checkMeaning() {
  const L x = L::of(1.5f, -2.0f, 0.25f, 4.0f), y = L::of(0.5f, 3.0f, -1.0f, 2.0f);
  expectLanes(x + y, 2.0f, 1.0f, -0.75f, 6.0f);
  expectLanes(x - y, 1.0f, -5.0f, 1.25f, 2.0f);
  expectLanes(x * y, 0.75f, -6.0f, -0.25f, 8.0f);
  L z = x;
  z += y;
  expectLanes(z, 2.0f, 1.0f, -0.75f, 6.0f);
  z -= y;
  expectLanes(z, 1.5f, -2.0f, 0.25f, 4.0f);
  expectLanes(x.clamp(L::of(1.0f, 1.0f, 0.0f, 5.0f)), 1.0f, -1.0f, 0.0f, 4.0f);
  expectLanes(x.withFirst(y), 0.5f, -2.0f, 0.25f, 4.0f);
  expectLanes(x.broadcastFirst(), 1.5f, 1.5f, 1.5f, 1.5f);
  expectLanes(x.sumInAll(), 3.75f, 3.75f, 3.75f, 3.75f);
  expectLanes(L::all(-3.0f), -3.0f, -3.0f, -3.0f, -3.0f);
}

}  // namespace

TEST(Lanes, PortableOperationsMeanWhatTheySay) { checkMeaning<PortableLanes>(); }
TEST(Lanes, CompiledOperationsMeanWhatTheySay) { checkMeaning<Lanes>(); }

// The same bits from both types on random values: the NLTGV iteration gives the same meshes
// on every CPU (up to the compiler's own contraction of multiply-adds).
TEST(Lanes, CompiledAndPortableAgreeToTheBit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(-3.0f, 3.0f);
  for (int trial = 0; trial < 1000; ++trial) {
    float a[4], b[4];
    for (int k = 0; k < 4; ++k) a[k] = U(rng), b[k] = std::abs(U(rng));
    const Lanes x = Lanes::of(a[0], a[1], a[2], a[3]), y = Lanes::of(b[0], b[1], b[2], b[3]);
    const PortableLanes px = PortableLanes::of(a[0], a[1], a[2], a[3]), py = PortableLanes::of(b[0], b[1], b[2], b[3]);
    const auto same = [](const Lanes& l, const PortableLanes& p) {
      for (int k = 0; k < 4; ++k) ASSERT_EQ(l[k], p[k]) << "lane " << k;
    };
    same(x + y, px + py);
    same(x - y, px - py);
    same(x * y, px * py);
    same(x.clamp(y), px.clamp(py));
    same(x.withFirst(y), px.withFirst(py));
    same(x.broadcastFirst(), px.broadcastFirst());
    same(x.sumInAll(), px.sumInAll());
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
