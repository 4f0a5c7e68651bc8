#pragma once
/// The triangles near a coherent path (DESIGN.md, "Near sets"): every triangle whose float
/// bounding box meets a float box [lo, hi], gathered from the grey leaves whose closed cells meet
/// the box, each input triangle once, with its box (SoA, padded to 8 with empty boxes). Any
/// triangle that meets [lo, hi] is in the set (the distribution lists a triangle in every leaf
/// whose closed cell it touches, and no triangle touches an empty node), which is what makes
/// the set a certificate for whatever lies in its box:
///   - the inside query's coherent step: a segment inside the box crosses only members;
///   - the distance search's near start: a ball inside the box meets only members.
/// A cache of derived data: answers never depend on it.
#include <cstdint>

#include "methods/ebp_octree/core/float_round.hpp"
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

/// The most members a set can hold: 256. Each gathering names its own limit (at most this): the
/// inside query's sets hold up to 128, the distance's 128 or 256 by the path's scale
/// (Query::gather_distance_near).
inline constexpr std::uint32_t kNearMax = 256;
/// The 64-bit words of a mask with one bit per member.
inline constexpr std::uint32_t kNearMaskWords = kNearMax / 64;

struct NearSet {
  bool valid = false;
  bool overflowed = false;  ///< the last gather failed because more than its max_members triangles meet its box
  float lo[3], hi[3];
  std::uint32_t n = 0;  ///< triangles; slots [n, n rounded up to 8) hold empty boxes
  // (columns of kNearMax whatever the limit: each member's slots are at constant offsets from
  // the set; columns allocated to each set's own limit cost 2 % more instructions a search, the
  // gathering's nine column pointers spilled to the stack)
  alignas(32) float blo[3][kNearMax];
  alignas(32) float bhi[3][kNearMax];
  std::uint32_t k[kNearMax];     ///< LeafTri index
  std::uint32_t leaf[kNearMax];  ///< the leaf it was gathered from
  std::uint32_t node[kNearMax];  ///< and that leaf's node

  /// Whether the closed box [f0, f1] lies in the set's box.
  bool holds(const float f0[3], const float f1[3]) const {
    return valid && lo[0] <= f0[0] && lo[1] <= f0[1] && lo[2] <= f0[2] && f1[0] <= hi[0] && f1[1] <= hi[1] &&
           f1[2] <= hi[2];
  }

  /// Whether the cube about p of half-width r, its faces p +- r computed in double, lies in the
  /// set's box: it then holds the ball (p, r - e) for any e above the rounding of p +- r (the
  /// distance search's tol).
  bool holds_cube(const Vec3d& p, double r) const {
    return valid && double(lo[0]) <= p.x - r && double(lo[1]) <= p.y - r && double(lo[2]) <= p.z - r &&
           p.x + r <= double(hi[0]) && p.y + r <= double(hi[1]) && p.z + r <= double(hi[2]);
  }

  /// Gathers the set of [glo, ghi] (rounded outwards to float). The box must lie in the union of
  /// at most 2 closed leaf-grid cells per axis (checked exactly against the cell boundaries) and
  /// meet at most max_members (<= kNearMax) triangles; otherwise returns false and the set is
  /// invalid.
  /// `leaf_node`, if not UINT32_MAX, is the node of the leaf-grid cell holding glo (saves a
  /// descent when the box lies in one cell). with_degenerate: zero-area triangles too (they
  /// cross nothing, so the inside query leaves them out; a distance does not).
  bool gather(const Octree& t, const Vec3d& glo, const Vec3d& ghi, std::uint32_t leaf_node, bool with_degenerate,
              std::uint32_t max_members);

  /// Calls f(j) for every member j whose box meets the closed box [f0, f1], in member order;
  /// stops early (returning false) when f returns false.
  template <class F>
  bool for_each_meeting(const float f0[3], const float f1[3], F&& f) const;

  /// The distance search's box pre-filter over every member at once (leaf_kernels.hpp,
  /// column_box_pass, 64 members a call): writes each member's box value from [q_lo, q_hi] to g2
  /// and the bit mask of those within box_lim to `mask` (member j: bit j % 64 of word j / 64);
  /// returns the words written, ceil(n / 64).
  std::uint32_t within(const float q_lo[3], const float q_hi[3], float box_lim, float g2[kNearMax],
                       std::uint64_t mask[kNearMaskWords]) const;
};

static_assert(kNearMax % 64 == 0, "members padded to 8 in columns; one bit each in 64-bit words");

}  // namespace ebp

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ebp {

template <class F>
bool NearSet::for_each_meeting(const float f0[3], const float f1[3], F&& f) const {
#if defined(__SSE2__)
  const __m128 ax = _mm_set1_ps(f0[0]), ay = _mm_set1_ps(f0[1]), az = _mm_set1_ps(f0[2]);
  const __m128 bx = _mm_set1_ps(f1[0]), by = _mm_set1_ps(f1[1]), bz = _mm_set1_ps(f1[2]);
  for (std::uint32_t j = 0; j < n; j += 4) {
    __m128 m = _mm_and_ps(_mm_cmpge_ps(_mm_load_ps(bhi[0] + j), ax), _mm_cmple_ps(_mm_load_ps(blo[0] + j), bx));
    m = _mm_and_ps(m, _mm_and_ps(_mm_cmpge_ps(_mm_load_ps(bhi[1] + j), ay), _mm_cmple_ps(_mm_load_ps(blo[1] + j), by)));
    m = _mm_and_ps(m, _mm_and_ps(_mm_cmpge_ps(_mm_load_ps(bhi[2] + j), az), _mm_cmple_ps(_mm_load_ps(blo[2] + j), bz)));
    for (unsigned bits = unsigned(_mm_movemask_ps(m)); bits; bits &= bits - 1)
      if (!f(j + unsigned(__builtin_ctz(bits)))) return false;
  }
#else
  for (std::uint32_t j = 0; j < n; ++j) {
    if (bhi[0][j] < f0[0] || blo[0][j] > f1[0] || bhi[1][j] < f0[1] || blo[1][j] > f1[1] || bhi[2][j] < f0[2] ||
        blo[2][j] > f1[2])
      continue;
    if (!f(j)) return false;
  }
#endif
  return true;
}

}  // namespace ebp
