// common/id_map.h: the flat id map against std::unordered_map on the same inserts, and its
// reuse after reset.
#include <gtest/gtest.h>

#include <random>
#include <unordered_map>

#include "vitamin_e/common/id_map.h"

using vitamin_e::common::IdMap;

TEST(IdMap, AgreesWithAnUnorderedMap) {
  std::mt19937_64 rng(9);
  IdMap<int> map;
  std::unordered_map<std::uint64_t, int> reference;
  EXPECT_EQ(map.find(42), nullptr);  // empty, never reset
  for (int k = 0; k < 5000; ++k) {
    // Consecutive ids (track ids), random 64-bit keys (edge hashes), and overwrites.
    const std::uint64_t id = k % 3 == 0 ? static_cast<std::uint64_t>(k) : k % 3 == 1 ? rng() : rng() % 100;
    map.set(id, k);
    reference[id] = k;
  }
  EXPECT_EQ(map.size(), reference.size());
  for (const auto& [id, value] : reference) {
    const int* found = map.find(id);
    ASSERT_NE(found, nullptr) << id;
    EXPECT_EQ(*found, value);
  }
  for (int k = 0; k < 1000; ++k) {
    const std::uint64_t id = rng();
    EXPECT_EQ(map.find(id) != nullptr, reference.count(id) == 1);
  }
}

TEST(IdMap, ResetEmptiesAndKeepsWorking) {
  IdMap<double> map;
  map.reset(4);
  for (std::uint64_t id = 0; id < 100; ++id) map.set(id, 0.5 * static_cast<double>(id));  // grows past 4
  EXPECT_EQ(map.size(), 100u);
  map.reset(100);
  EXPECT_TRUE(map.empty());
  EXPECT_EQ(map.find(7), nullptr);
  map.set(7, 1.0);
  map.set(7, 2.0);
  EXPECT_EQ(map.size(), 1u);
  ASSERT_NE(map.find(7), nullptr);
  EXPECT_EQ(*map.find(7), 2.0);
  map.clear();
  EXPECT_EQ(map.find(7), nullptr);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
