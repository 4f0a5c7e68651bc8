#pragma once
/// The certificate's pre-test (certificate.hpp): for each triangle of the certificate's set S, a
/// conservative lower bound of its distance to the query point, 8 triangles at a time, in float.
/// It may only prune: a triangle whose bound is within the running best is tested exactly (in
/// double) by the caller. Two kernels, chosen at run time: AVX2 (8 lanes) where the CPU has it,
/// and a scalar loop for any x86-64 (or other) CPU. Both evaluate the same float operations in
/// the same order without fused multiply-adds, so they give the same masks bit for bit, and the
/// work counters stay the same on every machine.
#include <cstdint>

namespace ebp {

inline constexpr unsigned kScanLanes = 8;
/// Rows of one block of kScanLanes triangles (each row kScanLanes floats, one per triangle):
/// face plane nx, ny, nz, d; three edge planes mx, my, mz, f (in the face plane, unit, outward);
/// the slack of the face-plane value sh, the slack of the edge-plane values so. Coordinates are
/// relative to the certificate's centre.
inline constexpr unsigned kScanRows = 18;

enum class ScanKernel { scalar, avx2 };

/// AVX2 if this CPU has it, else scalar.
ScanKernel best_scan_kernel();
const char* to_string(ScanKernel k);

/// For block j of `blocks` (pack: blocks x kScanRows x kScanLanes floats), bit i of masks[j] is
/// set iff lane i's lower bound of the squared distance to q (relative to the centre) is <= u2.
/// Lane i's bound is 0.999998 (max(0, |n.q - d| - sh)^2 + max(0, max_e(m_e.q - f_e) - so)^2):
/// see certificate.cpp for why it is a lower bound. `k` must be supported by the CPU.
void scan_lower_bounds(ScanKernel k, const float* pack, std::uint32_t blocks, const float q[3], float u2,
                       std::uint8_t* masks);

}  // namespace ebp
