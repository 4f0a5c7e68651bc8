#pragma once
/// The inside query's per-block leaf kernels (DESIGN.md, "Inside: block-skipping leaf kernels"):
/// the tests of a leaf's block boxes against a segment's box, and over one block of up to
/// kBlockTris consecutive LeafTris the float face-plane pass of the reference path and the
/// triangle-box pass of the coherent step; the three edge orientations of a segment crossing
/// test. Two implementations, chosen
/// once at run time: AVX2 (8 lanes) when the CPU has it, else the baseline (SSE2 on x86-64,
/// plain C++ elsewhere). Every implementation evaluates the same float expressions in the same
/// order without FMA (this file is compiled with -ffp-contract=off), so their results are bit
/// for bit the same and the choice never changes an answer or a counter.
#include <cstdint>

#include "harness/core/geometry.hpp"
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

enum class LeafKernels : std::uint8_t { baseline = 0, avx2 = 1 };

/// The kernels in use (the best the CPU supports, unless forced).
LeafKernels leaf_kernels();
/// Forces `k` (tests, measurements); avx2 on a CPU without it keeps the baseline. Returns the
/// kernels in use before the call. Not thread-safe: call before queries start.
LeafKernels set_leaf_kernels(LeafKernels k);
/// Whether this CPU can run the AVX2 kernels.
bool cpu_has_avx2();

/// The kernels, as one table: fetch it once per query (leaf_kernel_table()) and call through it.
struct LeafKernelTable {
  /// Plane pass of the reference path over blk[0, m), 1 <= m <= 8. p = the query point in the
  /// leaf's frame (float(p - centre) per axis). Writes s[j] = ((n0 p0 + n1 p1) + n2 p2) - d in
  /// float for j < m and returns the bit mask (bit j) of the triangles the exact stage must look
  /// at: not kDegenerate, and not strictly on the reference's side (s > eps with kRefPositive
  /// set, s < -eps with it clear).
  unsigned (*plane_pass)(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8]);
  /// Box pass of the coherent step over blk[0, m), 1 <= m <= 8: the bit mask of the
  /// non-degenerate triangles whose float bounding box (min/max of their float vertices: exact)
  /// meets the closed box [lo, hi].
  unsigned (*box_pass)(const LeafTri* blk, unsigned m, const float lo[3], const float hi[3]);
  /// Block pass over boxes[0, m), 1 <= m <= 8: the bit mask of the boxes that meet the closed box
  /// [lo, hi].
  unsigned (*block_pass)(const BlockBox* boxes, unsigned m, const float lo[3], const float hi[3]);
  /// The exact signs of the three edge orientations of the segment p -> q against triangle
  /// (a, b, c) (float vertices, taken exactly as doubles; 16 bytes readable at each, as in a
  /// LeafTri): e0 = orient3d(p, q, a, b), e1 = orient3d(p, q, b, c), e2 = orient3d(p, q, c, a)
  /// (predicates.hpp), as a mask: bit i set when e_i > 0, bit 4 + i when e_i < 0 (neither: 0).
  /// The filter is orient3d's (Shewchuk's bound A) on the differences from p, computed once for
  /// the three; where it cannot decide, orient3d_exact. Exact, so every kernel gives the same.
  unsigned (*edge_signs)(const Vec3d& p, const Vec3d& q, const float a[3], const float b[3], const float c[3]);
  LeafKernels kind;
};

/// The kernels in use.
const LeafKernelTable& leaf_kernel_table();

}  // namespace ebp
