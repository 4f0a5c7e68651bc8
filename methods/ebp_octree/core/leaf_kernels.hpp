#pragma once
/// The inside query's per-block leaf kernels (DESIGN.md, "Inside: block-skipping leaf kernels"):
/// over one block of up to kBlockTris consecutive LeafTris, the float face-plane pass of the
/// reference path and the triangle-box pass of the coherent step. Two implementations, chosen
/// once at run time: AVX2 (8 lanes) when the CPU has it, else the baseline (SSE2 on x86-64,
/// plain C++ elsewhere). Every implementation evaluates the same float expressions in the same
/// order without FMA (this file is compiled with -ffp-contract=off), so their results are bit
/// for bit the same and the choice never changes an answer or a counter.
#include <cstdint>

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

/// Plane pass of the reference path over blk[0, m), 1 <= m <= 8. p = the query point in the
/// leaf's frame (float(p - centre) per axis). Writes s[j] = ((n0 p0 + n1 p1) + n2 p2) - d in float
/// for j < m and returns the bit mask (bit j) of the triangles the exact stage must look at: not
/// kDegenerate, and not strictly on the reference's side (s > eps with kRefPositive set,
/// s < -eps with it clear).
unsigned plane_pass(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8]);

/// Box pass of the coherent step over blk[0, m), 1 <= m <= 8: the bit mask of the
/// non-degenerate triangles whose float bounding box (min/max of their float vertices: exact)
/// meets the closed box [lo, hi].
unsigned box_pass(const LeafTri* blk, unsigned m, const float lo[3], const float hi[3]);

}  // namespace ebp
