// The certificate's pre-test kernels (certificate_scan.hpp). The AVX2 one is compiled for AVX2
// only through a target attribute (the project builds for plain x86-64) and called only when the
// CPU reports AVX2. No FMA on purpose: a fused multiply-add rounds differently from the scalar
// kernel's multiply then add, and the masks (hence the work counters) must not depend on the
// machine. This file is compiled with -ffp-contract=off (CMakeLists.txt) so that no compiler
// contracts the scalar loop either, even under -march=native.
#include "methods/ebp_octree/core/certificate_scan.hpp"

#include <cmath>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define EBP_HAVE_AVX2_KERNEL 1
#endif

namespace ebp {

namespace {

/// maxps semantics (a > b ? a : b, the second operand when either is NaN), so that the scalar
/// kernel agrees with the AVX2 one on every input.
inline float max_ps(float a, float b) { return a > b ? a : b; }

void scan_scalar(const float* pack, std::uint32_t blocks, const float q[3], float u2, std::uint8_t* masks) {
  const float qx = q[0], qy = q[1], qz = q[2];
  for (std::uint32_t j = 0; j < blocks; ++j) {
    const float* r = pack + std::size_t(j) * kScanRows * kScanLanes;
    unsigned m = 0;
    for (unsigned i = 0; i < kScanLanes; ++i) {
      auto row = [&](unsigned k) { return r[k * kScanLanes + i]; };
      const float h = row(0) * qx + row(1) * qy + row(2) * qz - row(3);
      const float o1 = row(4) * qx + row(5) * qy + row(6) * qz - row(7);
      const float o2 = row(8) * qx + row(9) * qy + row(10) * qz - row(11);
      const float o3 = row(12) * qx + row(13) * qy + row(14) * qz - row(15);
      const float hh = max_ps(0.0f, std::fabs(h) - row(16));
      const float oo = max_ps(0.0f, max_ps(max_ps(o1, o2), o3) - row(17));
      const float l2 = (hh * hh + oo * oo) * 0.999998f;
      if (l2 <= u2) m |= 1u << i;
    }
    masks[j] = std::uint8_t(m);
  }
}

#ifdef EBP_HAVE_AVX2_KERNEL
// The scalar kernel's operations, lane by lane, in the same order: ((a x + b y) + c z) - d, for
// the plane in rows k..k+3 of a block. (Helpers, not lambdas: a lambda does not inherit the
// target attribute.)
__attribute__((target("avx2"), always_inline)) inline __m256 plane_avx2(const float* r, unsigned k, __m256 qx,
                                                                       __m256 qy, __m256 qz) {
  __m256 v = _mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(r + k * kScanLanes), qx),
                           _mm256_mul_ps(_mm256_loadu_ps(r + (k + 1) * kScanLanes), qy));
  v = _mm256_add_ps(v, _mm256_mul_ps(_mm256_loadu_ps(r + (k + 2) * kScanLanes), qz));
  return _mm256_sub_ps(v, _mm256_loadu_ps(r + (k + 3) * kScanLanes));
}

__attribute__((target("avx2"))) void scan_avx2(const float* pack, std::uint32_t blocks, const float q[3], float u2,
                                                std::uint8_t* masks) {
  const __m256 qx = _mm256_set1_ps(q[0]), qy = _mm256_set1_ps(q[1]), qz = _mm256_set1_ps(q[2]);
  const __m256 zero = _mm256_setzero_ps(), vu2 = _mm256_set1_ps(u2), shrink = _mm256_set1_ps(0.999998f);
  const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  for (std::uint32_t j = 0; j < blocks; ++j) {
    const float* r = pack + std::size_t(j) * kScanRows * kScanLanes;
    const __m256 h = plane_avx2(r, 0, qx, qy, qz), o1 = plane_avx2(r, 4, qx, qy, qz),
                 o2 = plane_avx2(r, 8, qx, qy, qz), o3 = plane_avx2(r, 12, qx, qy, qz);
    const __m256 sh = _mm256_loadu_ps(r + 16 * kScanLanes), so = _mm256_loadu_ps(r + 17 * kScanLanes);
    const __m256 hh = _mm256_max_ps(zero, _mm256_sub_ps(_mm256_and_ps(h, absmask), sh));
    const __m256 oo = _mm256_max_ps(zero, _mm256_sub_ps(_mm256_max_ps(_mm256_max_ps(o1, o2), o3), so));
    const __m256 l2 = _mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(hh, hh), _mm256_mul_ps(oo, oo)), shrink);
    masks[j] = std::uint8_t(_mm256_movemask_ps(_mm256_cmp_ps(l2, vu2, _CMP_LE_OQ)));
  }
}
#endif

}  // namespace

ScanKernel best_scan_kernel() {
#ifdef EBP_HAVE_AVX2_KERNEL
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2")) return ScanKernel::avx2;
#endif
  return ScanKernel::scalar;
}

const char* to_string(ScanKernel k) { return k == ScanKernel::avx2 ? "avx2" : "scalar"; }

void scan_lower_bounds(ScanKernel k, const float* pack, std::uint32_t blocks, const float q[3], float u2,
                       std::uint8_t* masks) {
#ifdef EBP_HAVE_AVX2_KERNEL
  if (k == ScanKernel::avx2) {
    scan_avx2(pack, blocks, q, u2, masks);
    return;
  }
#endif
  scan_scalar(pack, blocks, q, u2, masks);
}

}  // namespace ebp
