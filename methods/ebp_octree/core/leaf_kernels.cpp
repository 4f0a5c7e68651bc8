// The inside query's per-block leaf kernels (leaf_kernels.hpp): baseline (SSE2 / plain C++) and
// AVX2 implementations of the same float expressions, and the run-time choice between them.
// Compiled with -ffp-contract=off (CMakeLists.txt): a fused multiply-add would round once where
// the other kernels round twice.
#include "methods/ebp_octree/core/leaf_kernels.hpp"

#include <algorithm>
#include <cstddef>
#include <limits>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define EBP_X86 1
#endif

namespace ebp {

namespace {

static_assert(offsetof(LeafTri, b) == 12 && offsetof(LeafTri, c) == 24 && offsetof(LeafTri, n) == 36 &&
                  offsetof(LeafTri, d) == 48 && offsetof(LeafTri, flags) == 56,
              "16-byte loads at a, b, c, n stay in the record; n, d contiguous");
constexpr float kInf = std::numeric_limits<float>::infinity();

inline unsigned low_bits(unsigned m) { return m >= 32 ? ~0u : (1u << m) - 1u; }

// --- baseline ---------------------------------------------------------------------------------

unsigned plane_pass_baseline(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8]) {
  const float px = p[0], py = p[1], pz = p[2];
  unsigned gt = 0, lt = 0, pos = 0, deg = 0;
  unsigned j = 0;
#if defined(__SSE2__)
  const __m128 PX = _mm_set1_ps(px), PY = _mm_set1_ps(py), PZ = _mm_set1_ps(pz);
  const __m128 EP = _mm_set1_ps(eps), EN = _mm_set1_ps(-eps);
  for (; j + 4 <= m; j += 4) {
    __m128 r0 = _mm_loadu_ps(blk[j].n), r1 = _mm_loadu_ps(blk[j + 1].n), r2 = _mm_loadu_ps(blk[j + 2].n),
           r3 = _mm_loadu_ps(blk[j + 3].n);
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);  // nx, ny, nz, d of the four
    const __m128 v = _mm_sub_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(r0, PX), _mm_mul_ps(r1, PY)), _mm_mul_ps(r2, PZ)), r3);
    gt |= unsigned(_mm_movemask_ps(_mm_cmpgt_ps(v, EP))) << j;
    lt |= unsigned(_mm_movemask_ps(_mm_cmplt_ps(v, EN))) << j;
    _mm_storeu_ps(s + j, v);
  }
#endif
  for (; j < m; ++j) {
    const LeafTri& t = blk[j];
    const float v = t.n[0] * px + t.n[1] * py + t.n[2] * pz - t.d;
    s[j] = v;
    gt |= unsigned(v > eps) << j;
    lt |= unsigned(v < -eps) << j;
  }
  for (j = 0; j < m; ++j) {
    pos |= (blk[j].flags & kRefPositive ? 1u : 0u) << j;
    deg |= (blk[j].flags & kDegenerate ? 1u : 0u) << j;
  }
  return ~((gt & pos) | (lt & ~pos) | deg) & low_bits(m);
}

unsigned box_pass_baseline(const LeafTri* blk, unsigned m, const float lo[3], const float hi[3]) {
  unsigned hit = 0;
#if defined(__SSE2__)
  // Lane 3 of the vertex rows is not a coordinate: the box's lane 3 lets it always pass.
  const __m128 LO = _mm_setr_ps(lo[0], lo[1], lo[2], -kInf), HI = _mm_setr_ps(hi[0], hi[1], hi[2], kInf);
  for (unsigned j = 0; j < m; ++j) {
    const LeafTri& t = blk[j];
    if (t.flags & kDegenerate) continue;
    const __m128 A = _mm_loadu_ps(t.a), B = _mm_loadu_ps(t.b), C = _mm_loadu_ps(t.c);
    const __m128 tlo = _mm_min_ps(_mm_min_ps(A, B), C), thi = _mm_max_ps(_mm_max_ps(A, B), C);
    if (_mm_movemask_ps(_mm_or_ps(_mm_cmplt_ps(thi, LO), _mm_cmpgt_ps(tlo, HI))) == 0) hit |= 1u << j;
  }
#else
  for (unsigned j = 0; j < m; ++j) {
    const LeafTri& t = blk[j];
    if (t.flags & kDegenerate) continue;
    bool meets = true;
    for (int a = 0; a < 3; ++a) {
      const float tl = std::min(std::min(t.a[a], t.b[a]), t.c[a]), th = std::max(std::max(t.a[a], t.b[a]), t.c[a]);
      meets = meets && !(th < lo[a] || tl > hi[a]);
    }
    if (meets) hit |= 1u << j;
  }
#endif
  return hit;
}

// --- AVX2 -------------------------------------------------------------------------------------
#if defined(EBP_X86)

#define EBP_AVX2 __attribute__((target("avx2")))

/// The flags of blk[0, m) in 8 lanes (lanes >= m: 0, not read).
EBP_AVX2 inline __m256i gather_flags(const LeafTri* blk, unsigned m) {
  const __m256i idx = _mm256_setr_epi32(0, 16, 32, 48, 64, 80, 96, 112);  // 64-byte records, in ints
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i live = _mm256_cmpgt_epi32(_mm256_set1_epi32(int(m)), lane);
  return _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(&blk[0].flags), idx, live, 4);
}

/// Row j of 8 records at byte offset `off` (16 bytes), zero for j >= m (never read past the block).
template <std::size_t Off>
EBP_AVX2 inline __m256 rows(const LeafTri* blk, unsigned m, unsigned j) {
  auto row = [&](unsigned i) {
    return i < m ? _mm_loadu_ps(reinterpret_cast<const float*>(reinterpret_cast<const char*>(blk + i) + Off))
                 : _mm_setzero_ps();
  };
  return _mm256_insertf128_ps(_mm256_castps128_ps256(row(j)), row(j + 4), 1);
}

EBP_AVX2 unsigned plane_pass_avx2(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8]) {
  // Records j and j + 4 share a row register; the 4x4 transpose per 128-bit half gives lane j =
  // triangle j.
  const __m256 R0 = rows<offsetof(LeafTri, n)>(blk, m, 0), R1 = rows<offsetof(LeafTri, n)>(blk, m, 1),
               R2 = rows<offsetof(LeafTri, n)>(blk, m, 2), R3 = rows<offsetof(LeafTri, n)>(blk, m, 3);
  const __m256 t0 = _mm256_unpacklo_ps(R0, R1), t1 = _mm256_unpackhi_ps(R0, R1);
  const __m256 t2 = _mm256_unpacklo_ps(R2, R3), t3 = _mm256_unpackhi_ps(R2, R3);
  const __m256 nx = _mm256_shuffle_ps(t0, t2, 0x44), ny = _mm256_shuffle_ps(t0, t2, 0xEE);
  const __m256 nz = _mm256_shuffle_ps(t1, t3, 0x44), d = _mm256_shuffle_ps(t1, t3, 0xEE);
  const __m256 v = _mm256_sub_ps(
      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, _mm256_set1_ps(p[0])), _mm256_mul_ps(ny, _mm256_set1_ps(p[1]))),
                    _mm256_mul_ps(nz, _mm256_set1_ps(p[2]))),
      d);
  _mm256_storeu_ps(s, v);
  const unsigned gt = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(v, _mm256_set1_ps(eps), _CMP_GT_OQ)));
  const unsigned lt = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(v, _mm256_set1_ps(-eps), _CMP_LT_OQ)));
  const __m256i fl = gather_flags(blk, m);
  const unsigned pos = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_slli_epi32(fl, 31))));  // kRefPositive
  const unsigned deg = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_slli_epi32(fl, 30))));  // kDegenerate
  return ~((gt & pos) | (lt & ~pos) | deg) & low_bits(m);
}

EBP_AVX2 unsigned box_pass_avx2(const LeafTri* blk, unsigned m, const float lo[3], const float hi[3]) {
  // Two triangles per register (j in the low half, j + 4 in the high half); lane 3 of each half
  // is not a coordinate and always passes.
  const __m128 lo4 = _mm_setr_ps(lo[0], lo[1], lo[2], -kInf), hi4 = _mm_setr_ps(hi[0], hi[1], hi[2], kInf);
  const __m256 LO = _mm256_insertf128_ps(_mm256_castps128_ps256(lo4), lo4, 1);
  const __m256 HI = _mm256_insertf128_ps(_mm256_castps128_ps256(hi4), hi4, 1);
  unsigned miss = 0;
  for (unsigned j = 0; j < 4 && j < m; ++j) {
    const __m256 A = rows<offsetof(LeafTri, a)>(blk, m, j), B = rows<offsetof(LeafTri, b)>(blk, m, j),
                 C = rows<offsetof(LeafTri, c)>(blk, m, j);
    const __m256 tlo = _mm256_min_ps(_mm256_min_ps(A, B), C), thi = _mm256_max_ps(_mm256_max_ps(A, B), C);
    const unsigned out = unsigned(_mm256_movemask_ps(_mm256_or_ps(_mm256_cmp_ps(thi, LO, _CMP_LT_OQ),
                                                                  _mm256_cmp_ps(tlo, HI, _CMP_GT_OQ))));
    miss |= ((out & 15u) ? 1u : 0u) << j;
    miss |= ((out >> 4) ? 1u : 0u) << (j + 4);
  }
  const unsigned deg = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_slli_epi32(gather_flags(blk, m), 30))));
  return ~(miss | deg) & low_bits(m);
}

#endif  // EBP_X86

// --- the choice -------------------------------------------------------------------------------

struct Kernels {
  unsigned (*plane)(const LeafTri*, unsigned, const float*, float, float*);
  unsigned (*box)(const LeafTri*, unsigned, const float*, const float*);
  LeafKernels kind;
};

Kernels make(LeafKernels k) {
#if defined(EBP_X86)
  if (k == LeafKernels::avx2 && cpu_has_avx2()) return {plane_pass_avx2, box_pass_avx2, LeafKernels::avx2};
#endif
  (void)k;
  return {plane_pass_baseline, box_pass_baseline, LeafKernels::baseline};
}

Kernels& current() {
  static Kernels k = make(LeafKernels::avx2);
  return k;
}

}  // namespace

bool cpu_has_avx2() {
#if defined(EBP_X86)
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has;
#else
  return false;
#endif
}

LeafKernels leaf_kernels() { return current().kind; }

LeafKernels set_leaf_kernels(LeafKernels k) {
  const LeafKernels before = current().kind;
  current() = make(k);
  return before;
}

unsigned plane_pass(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8]) {
  return current().plane(blk, m, p, eps, s);
}

unsigned box_pass(const LeafTri* blk, unsigned m, const float lo[3], const float hi[3]) {
  return current().box(blk, m, lo, hi);
}

}  // namespace ebp
