#pragma once
/// 64-bit octcodes of the EBP-Octree (Aguilera, Melero, Feito 2016, Section 3.1): 57 bits of
/// Morton code (3 bits per level, up to 19 levels) and 5 bits for the level.
///
/// Layout (bit 63 first): 2 unused zero bits | 57 bits of Morton code, *left-aligned* (the digit
/// of level 1 in the top 3 bits, unused lower digits zero) | 5 bits of level.
/// Left alignment makes the integer order of codes a pre-order (depth-first) walk of the tree:
/// a node sorts before its descendants, and a subtree is one contiguous range of codes
/// [code, subtree_end(code)). That is what the node table and the future on-disk file rely on.
///
/// Morton digit at a level = (x bit) | (y bit) << 1 | (z bit) << 2 of the cell coordinates.
#include <cstdint>

namespace ebp {

using Octcode = std::uint64_t;

inline constexpr int kMaxLevel = 19;
inline constexpr int kLevelBits = 5;
inline constexpr int kMortonBits = 3 * kMaxLevel;  // 57
static_assert(kMortonBits + kLevelBits <= 64, "octcode bit budget: 57 + 5 bits must fit in 64");
static_assert((1 << kLevelBits) > kMaxLevel, "the level field must hold every level 0..19");

/// Spreads the low 19 bits of v so that bit i lands at bit 3i.
constexpr std::uint64_t spread3(std::uint32_t v) {
  std::uint64_t x = v & 0x7ffffu;
  x = (x | (x << 32)) & 0x1f00000000ffffull;
  x = (x | (x << 16)) & 0x1f0000ff0000ffull;
  x = (x | (x << 8)) & 0x100f00f00f00f00full;
  x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
  x = (x | (x << 2)) & 0x1249249249249249ull;
  return x;
}
/// Inverse of spread3.
constexpr std::uint32_t compact3(std::uint64_t x) {
  x &= 0x1249249249249249ull;
  x = (x ^ (x >> 2)) & 0x10c30c30c30c30c3ull;
  x = (x ^ (x >> 4)) & 0x100f00f00f00f00full;
  x = (x ^ (x >> 8)) & 0x1f0000ff0000ffull;
  x = (x ^ (x >> 16)) & 0x1f00000000ffffull;
  x = (x ^ (x >> 32)) & 0x7ffffull;
  return std::uint32_t(x);
}

/// Morton code of cell (x, y, z) at some level: each coordinate < 2^level, level <= 19.
constexpr std::uint64_t morton_encode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return spread3(x) | (spread3(y) << 1) | (spread3(z) << 2);
}
constexpr void morton_decode(std::uint64_t m, std::uint32_t* x, std::uint32_t* y, std::uint32_t* z) {
  *x = compact3(m);
  *y = compact3(m >> 1);
  *z = compact3(m >> 2);
}

/// The octcode of the cell with right-aligned Morton code `morton` (3*level bits) at `level`.
constexpr Octcode octcode_make(int level, std::uint64_t morton) {
  return ((morton << (3 * (kMaxLevel - level))) << kLevelBits) | Octcode(level);
}
constexpr int octcode_level(Octcode c) { return int(c & ((1u << kLevelBits) - 1)); }
/// Right-aligned Morton code (3*level bits).
constexpr std::uint64_t octcode_morton(Octcode c) {
  return (c >> kLevelBits) >> (3 * (kMaxLevel - octcode_level(c)));
}
constexpr Octcode octcode_root() { return octcode_make(0, 0); }
/// Parent of a non-root code.
constexpr Octcode octcode_parent(Octcode c) {
  return octcode_make(octcode_level(c) - 1, octcode_morton(c) >> 3);
}
/// Child `octant` (0..7, digit x | y<<1 | z<<2) of a code above the deepest level.
constexpr Octcode octcode_child(Octcode c, int octant) {
  return octcode_make(octcode_level(c) + 1, (octcode_morton(c) << 3) | std::uint64_t(octant));
}
/// Octant of a non-root code within its parent.
constexpr int octcode_octant(Octcode c) { return int(octcode_morton(c) & 7u); }
/// Cell coordinates at the code's own level.
constexpr void octcode_cell(Octcode c, std::uint32_t* x, std::uint32_t* y, std::uint32_t* z) {
  morton_decode(octcode_morton(c), x, y, z);
}
/// Code of the cell (x, y, z) at `level`.
constexpr Octcode octcode_from_cell(int level, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return octcode_make(level, morton_encode(x, y, z));
}
/// One past the last code of c's subtree: every descendant d satisfies c < d < subtree_end(c).
constexpr Octcode octcode_subtree_end(Octcode c) {
  const int l = octcode_level(c);
  const int shift = kLevelBits + 3 * (kMaxLevel - l);
  return ((c >> shift) + 1) << shift;
}
/// True if a is b or an ancestor of b.
constexpr bool octcode_contains(Octcode a, Octcode b) {
  return a <= b && b < octcode_subtree_end(a) && octcode_level(a) <= octcode_level(b);
}

}  // namespace ebp
