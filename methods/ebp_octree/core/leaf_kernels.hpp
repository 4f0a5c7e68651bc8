#pragma once
/// The per-block leaf kernels (DESIGN.md, "Inside: block-skipping leaf kernels", and the distance
/// search's bounds): the tests of a leaf's block boxes against a segment's or a ball's box, and
/// over one block of up to kBlockTris consecutive LeafTris the float face-plane pass of the
/// inside query's reference path and the triangle-box pass of its coherent step; the three edge
/// orientations of a segment crossing test; the distance search's squared distances to block
/// boxes and its per-block pre-filter. Two implementations, chosen
/// once at run time: AVX2 (8 lanes) when the CPU has it, else the baseline (SSE2 on x86-64,
/// plain C++ elsewhere). Every implementation evaluates the same float expressions in the same
/// order without FMA (this file is compiled with -ffp-contract=off), so their results are bit
/// for bit the same and the choice never changes an answer or a counter.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "harness/core/geometry.hpp"
#include "methods/ebp_octree/core/face_normal.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/float_round.hpp"
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

enum class LeafKernels : std::uint8_t { baseline = 0, avx2 = 1 };

/// Squared distance from p to a float box, ((0 + v0 v0) + v1 v1) + v2 v2 in double with v_a =
/// max(lo_a - p_a, 0, p_a - hi_a) (exact box; the rounding of this computation is covered by
/// the distance query's `tol`). The box_distances kernels give its bits.
inline double box_d2(const BlockBox& b, const Vec3d& p) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double v = std::max({double(b.lo[a]) - p[a], 0.0, p[a] - double(b.hi[a])});
    d2 += v * v;
  }
  return d2;
}

/// The face-plane value of t at p (in the leaf's frame): ((v0 p0 + v1 p1) + v2 p2) - d in float,
/// v = t's decoded normal (face_normal.hpp; the first form takes it decoded already); 0 for a
/// triangle with no plane (kNoPlane). Its sign is orient3d(a, b, c, p)'s where its magnitude
/// exceeds the leaf's eps. The kernels' plane_pass gives the same bits.
inline float face_plane_value(const LeafTri& t, const float v[3], const float p[3]) {
  if (t.flags() & kNoPlane) return 0.0f;
  return ((v[0] * p[0] + v[1] * p[1]) + v[2] * p[2]) - t.d;
}
inline float face_plane_value(const LeafTri& t, const float p[3]) {
  float v[3];
  decode_face_normal(t.normal, v);
  return face_plane_value(t, v, p);
}

/// |face_plane_value(t, p)| / |v|, |v| = sqrt((v0 v0 + v1 v1) + v2 v2) in float: within the
/// distance search's eps_p of the distance from p to t's plane, so a lower bound on the distance
/// to t up to that error. The kernels' distance_pass gives the same bits.
inline float face_plane_distance(const LeafTri& t, const float p[3]) {
  float v[3];
  decode_face_normal(t.normal, v);
  return std::fabs(face_plane_value(t, v, p)) / std::sqrt((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2]);
}

/// plane_pass's `ref_sides` for the leaf's own reference point: its sides are the LeafTris'
/// kRefPositive flags.
inline constexpr unsigned kRefSidesFromFlags = ~0u;

/// The kernels in use (the best the CPU supports, unless forced).
LeafKernels leaf_kernels();
/// Forces `k` (tests, measurements); avx2 on a CPU without it keeps the baseline. Returns the
/// kernels in use before the call. Not thread-safe: call before queries start.
LeafKernels set_leaf_kernels(LeafKernels k);
/// Whether this CPU can run the AVX2 kernels.
bool cpu_has_avx2();

/// What a near set's gathering tests a block's triangles against (box_pass).
struct GatherTest {
  float lo[3], hi[3];  ///< the gathering's box: a triangle is kept when its float box meets it
  /// Per axis, a slab about the boundary between the gathering's two leaf-grid cells on that
  /// axis (an empty one, lo +inf and hi -inf, where it spans one cell): a kept triangle whose
  /// box meets no slab is listed in one of the gathering's cells only, so it needs no test
  /// against the triangles kept before it.
  float seam_lo[3], seam_hi[3];
  bool with_degenerate;  ///< keep zero-area triangles too (a distance needs them; a segment crosses none)
};

/// The float bounding boxes of a block's triangles as columns (box_pass): lane j is triangle j.
struct BlockTriBoxes {
  alignas(32) float lo[3][8];
  alignas(32) float hi[3][8];
};

/// The columns a gathering appends its members to (a near set's, near_set.hpp): each member's
/// box, LeafTri index, leaf and node, `slots` long.
struct MemberColumns {
  float* lo[3];
  float* hi[3];
  std::uint32_t* k;
  std::uint32_t* leaf;
  std::uint32_t* node;
  std::uint32_t slots;
};

/// The kernels, as one table: fetch it once per query (leaf_kernel_table()) and call through it.
struct LeafKernelTable {
  /// Plane pass of the reference path over blk[0, m), 1 <= m <= 8. p = the query point in the
  /// leaf's frame (float(p - centre) per axis). Writes s[j] = face_plane_value(blk[j], p) for
  /// j < m and returns the bit mask (bit j) of the triangles the exact stage must look
  /// at: not kDegenerate, and not strictly on the reference's side (s > eps with the reference
  /// on the outer side, s < -eps with it on the inner side). `ref_sides`: bit j set when the
  /// reference is on triangle j's outer side (a sub-reference's mask, Octree::sub_sides), or
  /// kRefSidesFromFlags for the leaf's reference point (kRefPositive).
  unsigned (*plane_pass)(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8], unsigned ref_sides);
  /// Box pass of a near set's gathering over blk[0, m), 1 <= m <= 8: the bit mask of the
  /// triangles whose float bounding box (min/max of their float vertices: exact) meets the closed
  /// box [g.lo, g.hi]; the kDegenerate ones (zero area) only `g.with_degenerate`. Writes every
  /// triangle's box (j < m) to `boxes` (the gathering keeps it with the member instead of
  /// computing it again) and to *on_seam the bit mask of the kept triangles whose box meets one
  /// of g's seam slabs.
  unsigned (*box_pass)(const LeafTri* blk, unsigned m, const GatherTest& g, BlockTriBoxes& boxes, unsigned* on_seam);
  /// Appends the triangles of `keep` (a mask of lanes of `boxes`) to the columns at slot n, in
  /// lane order: box, LeafTri index first + lane, `leaf` and `node`. Returns how many `keep`
  /// holds; those that would fall past the columns' `slots` are not written (the caller's set
  /// has overflowed). Any slot from n to n + 8 within the columns may be written.
  std::uint32_t (*append_members)(const BlockTriBoxes& boxes, unsigned keep, std::uint32_t first, std::uint32_t leaf,
                                  std::uint32_t node, const MemberColumns& out, std::uint32_t n);
  /// Block pass over boxes[0, m), 1 <= m <= 8: the bit mask of the boxes that meet the closed box
  /// [lo, hi].
  unsigned (*block_pass)(const BlockBox* boxes, unsigned m, const float lo[3], const float hi[3]);
  /// Squared distances from p to boxes[0, n), any n: d2[j] = box_d2(boxes[j], p), the same bits
  /// from every kernel.
  void (*box_distances)(const BlockBox* boxes, std::uint32_t n, const Vec3d& p, double* d2);
  /// The exact signs of the three edge orientations of the segment p -> q against triangle
  /// (a, b, c) (float vertices, taken exactly as doubles; 16 bytes readable at each, as in a
  /// LeafTri): e0 = orient3d(p, q, a, b), e1 = orient3d(p, q, b, c), e2 = orient3d(p, q, c, a)
  /// (predicates.hpp), as a mask: bit i set when e_i > 0, bit 4 + i when e_i < 0 (neither: 0).
  /// The filter is orient3d's (Shewchuk's bound A) on the differences from p, computed once for
  /// the three; where it cannot decide, orient3d_exact. Exact, so every kernel gives the same.
  unsigned (*edge_signs)(const Vec3d& p, const Vec3d& q, const float a[3], const float b[3], const float c[3]);
  /// The distance query's pre-filter over blk[0, m), 1 <= m <= 8, before its per-triangle tests
  /// (query_distance.cpp): the bit mask of the triangles it keeps. It clears a triangle when its
  /// face-plane distance (face_plane_distance, p in the leaf's frame) exceeds plane_lim, or when
  /// the squared distance from the box [q_lo, q_hi] (the query point in the tree's frame rounded
  /// outwards to float) to the triangle's float box, ((0 + g0 g0) + g1 g1)
  /// + g2 g2 in float, exceeds box_lim. With the limits the caller sets
  /// (distance_prefilter_limits) every triangle cleared is strictly farther than the best they
  /// were set for. Writes the two values of triangle j to plane_abs[j] and box_d2[j] (j < m;
  /// lanes beyond may be written too), so that the per-triangle tests compare them again when
  /// the best has moved, without evaluating them again.
  unsigned (*distance_pass)(const LeafTri* blk, unsigned m, const float p[3], const float q_lo[3],
                            const float q_hi[3], float plane_lim, float box_lim, float plane_abs[8], float box_d2[8]);
  /// distance_pass's box value over n <= 64 boxes given as columns (lo[a][j], hi[a][j]; 32-byte
  /// aligned, readable and padded with empty boxes, lo +inf and hi -inf, up to n rounded up to 8):
  /// writes g2[j] = ((0 + g0 g0) + g1 g1) + g2 g2 in float, g_a = max(max(lo_a - q_hi_a,
  /// q_lo_a - hi_a), 0), for every j below n rounded up to 8, and returns the bit mask of the j < n
  /// with g2[j] <= box_lim. A near set's members, before its served search (near_set.hpp).
  std::uint64_t (*column_box_pass)(const float* const lo[3], const float* const hi[3], std::uint32_t n,
                                   const float q_lo[3], const float q_hi[3], float box_lim, float* g2);
  /// The exact closest points of p on the triangles t[0, m), 1 <= m <= 4 (their float vertices
  /// taken exactly as doubles): q[i] = closest_point_on_triangle(p, a, b, c) and d2[i] =
  /// squared_norm(q[i] - p), bit for bit (the same double operations lane by lane, the same
  /// order of the cases; a zero-area triangle that reaches the scalar's fall-back gets it). The
  /// distance search's exact tests (near start and leaf scan), four at a time.
  void (*closest_points)(const Vec3d& p, const LeafTri* const t[4], unsigned m, Vec3d q[4], double d2[4]);
  LeafKernels kind;
};

/// The kernels in use.
const LeafKernelTable& leaf_kernel_table();

/// The exact closest point of p on LeafTri t (its float vertices taken exactly as doubles), and
/// its squared distance from p in *d2: the scalar test that closest_points gives lane by lane.
inline Vec3d exact_closest_point(const Vec3d& p, const LeafTri& t, double* d2) {
  const Vec3d q = bvhbench::closest_point_on_triangle(p, to_d(t.a), to_d(t.b), to_d(t.c));
  *d2 = squared_norm(q - p);
  return q;
}

/// The limit on distance_pass's box value for a running best distance whose square is best2:
/// a box value above it (or above it rounded up to float) is strictly farther than the best.
/// The margin covers the float rounding of the box sum (< 3e-7 relative).
inline double box_prefilter_limit(double best2) { return best2 * (1 + 4e-6); }

/// distance_pass's limits for a running best distance `best` (its square best2) and the leaf's
/// face-plane error bound at p, eps_p: plane_lim >= (best + eps_p)(1 + 1e-9), box_lim >= best2
/// (1 + 4e-6), both rounded up to float. The margins cover the float rounding of the box sum
/// (< 3e-7 relative), so a triangle whose value exceeds a limit is strictly farther than best:
/// the distance search prunes it without an exact test.
void distance_prefilter_limits(double best, double best2, double eps_p, float* plane_lim, float* box_lim);

}  // namespace ebp
