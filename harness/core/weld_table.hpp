#pragma once
/// Exact welding of float positions into vertex indices (a binary STL's facet corners, a leaf's
/// triangle corners): header-only, so that the EBP-Octree's core can use it too.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace bvhbench {

/// Exact weld of float positions: equal values (so -0 == +0) get one index, in order of first
/// insertion. Open addressing over a power-of-two table of (index + 1), at most half full.
class WeldTable {
 public:
  static constexpr std::uint32_t kAbsent = 0xFFFFFFFFu;

  explicit WeldTable(std::uint64_t expected = 0) { rehash(std::max<std::uint64_t>(expected, 512)); }

  /// Index of the vertex at p, added if new (`added` says which).
  std::uint32_t insert(const float* p, bool& added) {
    std::size_t s = slot_of(p);
    if (slots_[s] != 0) {
      added = false;
      return slots_[s] - 1;
    }
    added = true;
    const std::uint32_t id = std::uint32_t(size());
    xyz_.insert(xyz_.end(), p, p + 3);
    slots_[s] = id + 1;
    if (2 * size() > slots_.size()) rehash(2 * slots_.size());
    return id;
  }

  /// Index of the vertex at p, kAbsent if none.
  std::uint32_t find(const float* p) const {
    const std::uint32_t v = slots_[slot_of(p)];
    return v == 0 ? kAbsent : v - 1;
  }

  /// The position of vertex `id`.
  const float* point(std::uint32_t id) const { return &xyz_[3 * std::size_t(id)]; }
  /// Empty again, sized for about `expected` vertices (the storage is reused).
  void reset(std::uint64_t expected) {
    xyz_.clear();
    rehash(2 * std::max<std::uint64_t>(expected, 8));
  }

  std::uint64_t size() const { return xyz_.size() / 3; }
  std::size_t bytes() const { return xyz_.capacity() * sizeof(float) + slots_.capacity() * sizeof(std::uint32_t); }

 private:
  static std::uint32_t key_bits(float f) {
    if (f == 0.0f) f = 0.0f;  // -0 and +0 weld: hash them alike
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
  }
  static std::uint64_t hash(const float* p) {
    std::uint64_t h = (std::uint64_t(key_bits(p[0])) << 32 | key_bits(p[1])) * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) ^ std::uint64_t(key_bits(p[2])) * 0xBF58476D1CE4E5B9ull;
    h *= 0x94D049BB133111EBull;
    return h ^ (h >> 31);
  }
  /// The slot holding p, or the empty slot where it would go.
  std::size_t slot_of(const float* p) const {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = std::size_t(hash(p)) & mask;; s = (s + 1) & mask) {
      const std::uint32_t v = slots_[s];
      if (v == 0) return s;
      const float* q = &xyz_[3 * std::size_t(v - 1)];
      if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) return s;
    }
  }
  void rehash(std::uint64_t want) {
    std::size_t cap = 1;
    while (cap < want) cap <<= 1;
    slots_.assign(cap, 0);
    const std::size_t mask = cap - 1;
    for (std::uint32_t id = 0; id < size(); ++id) {
      std::size_t s = std::size_t(hash(&xyz_[3 * std::size_t(id)])) & mask;
      while (slots_[s] != 0) s = (s + 1) & mask;
      slots_[s] = id + 1;
    }
  }

  std::vector<float> xyz_;
  std::vector<std::uint32_t> slots_;
};

}  // namespace bvhbench
