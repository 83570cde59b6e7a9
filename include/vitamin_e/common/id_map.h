#pragma once
// A map from 64-bit ids to small values, rebuilt every frame (the NLTGV warm start: ~10^4
// entries per frame): open addressing with linear probing in one array, so that clearing and
// refilling it allocates nothing once it has grown (std::unordered_map allocates a node per
// entry, which cost more than the lookups themselves).
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vitamin_e::common {

template <typename Value>
class IdMap {
 public:
  // Empties the map and makes room for `count` entries without growing.
  void reset(std::size_t count) {
    std::size_t capacity = 16;
    while (capacity < 2 * count) capacity *= 2;
    if (slots_.size() != capacity) slots_.resize(capacity);
    for (Slot& s : slots_) s.used = false;
    size_ = 0;
  }
  void clear() { reset(0); }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  // Inserts or overwrites.
  void set(std::uint64_t id, const Value& value) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    Slot& s = slots_[probe(id)];
    if (!s.used) {
      s.used = true;
      s.id = id;
      ++size_;
    }
    s.value = value;
  }
  // nullptr when the id is absent.
  const Value* find(std::uint64_t id) const {
    if (slots_.empty()) return nullptr;
    const Slot& s = slots_[probe(id)];
    return s.used ? &s.value : nullptr;
  }

 private:
  struct Slot {
    std::uint64_t id = 0;
    Value value{};
    bool used = false;
  };
  // The slot holding id, or the empty slot where it would go (the table is never full).
  std::size_t probe(std::uint64_t id) const {
    const std::size_t mask = slots_.size() - 1;
    // Fibonacci hashing: consecutive track ids spread over the table.
    std::size_t i = static_cast<std::size_t>((id * 0x9E3779B97F4A7C15ULL) >> 32) & mask;
    while (slots_[i].used && slots_[i].id != id) i = (i + 1) & mask;
    return i;
  }
  void grow() {
    std::vector<Slot> old;
    old.swap(slots_);
    reset(old.size() < 16 ? 8 : old.size());
    for (const Slot& s : old)
      if (s.used) set(s.id, s.value);
  }
  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

}  // namespace vitamin_e::common
