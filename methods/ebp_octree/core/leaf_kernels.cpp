// The inside query's per-block leaf kernels (leaf_kernels.hpp): baseline (SSE2 / plain C++) and
// AVX2 implementations of the same float expressions, and the run-time choice between them.
// Compiled with -ffp-contract=off (CMakeLists.txt): a fused multiply-add would round once where
// the other kernels round twice.
#include "methods/ebp_octree/core/leaf_kernels.hpp"

#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/predicates.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define EBP_X86 1
#endif

namespace ebp {

namespace {

static_assert(offsetof(LeafTri, b) == 12 && offsetof(LeafTri, c) == 24 && offsetof(LeafTri, normal) == 36 &&
                  offsetof(LeafTri, d) == 40 && offsetof(LeafTri, tri_flags) == 44 && sizeof(LeafTri) == 48,
              "16-byte loads at a, b, c and at byte 32 (c.z, normal, d, tri_flags) stay in the record");
/// The byte offset of the record's last row: c.z, normal, d, tri_flags.
constexpr std::size_t kPlaneRow = 32;
/// The flags' bits, moved to bit 31 by a left shift (kRefPositive is there already).
constexpr int kDegenerateShift = 1, kNoPlaneShift = 2;
static_assert(kDegenerate << kDegenerateShift == 1u << 31 && kNoPlane << kNoPlaneShift == 1u << 31 &&
                  kRefPositive == 1u << 31,
              "flags at bits 31, 30, 29 of tri_flags");
constexpr float kInf = std::numeric_limits<float>::infinity();
/// Shewchuk's first-stage error bound of orient3d, as in predicates.hpp.
constexpr double kOrientErrBoundA = 7.7715611723761027e-16;

/// The edge orientations the filter could not decide (`undecided`: bit i for edge i), by
/// orient3d_exact on the original points, into the mask of edge_signs. Out of line: rare, and
/// it keeps the kernels' hot path free of calls.
__attribute__((noinline, cold)) unsigned exact_edges(const Vec3d& p, const Vec3d& q, const float* a, const float* b,
                                                     const float* c, unsigned undecided) {
  const float* v[4] = {a, b, c, a};
  unsigned mask = 0;
  for (int i = 0; i < 3; ++i)
    if (undecided >> i & 1u) {
      ++g_orient_exact_calls;
      const int e = orient3d_exact(p, q, to_d(v[i]), to_d(v[i + 1]));
      mask |= e > 0 ? 1u << i : e < 0 ? 16u << i : 0u;
    }
  return mask;
}

inline unsigned low_bits(unsigned m) { return m >= 32 ? ~0u : (1u << m) - 1u; }

// --- baseline ---------------------------------------------------------------------------------

#if defined(__SSE2__)
/// The face-plane values of four records from their last rows, transposed (code, d, tri_flags):
/// face_plane_value's operations lane-wise.
inline __m128 face_values_sse2(__m128 code, __m128 d, __m128 fl, const float p[3]) {
  const __m128i c = _mm_castps_si128(code);
  const __m128 S = _mm_set1_ps(kOctScale), SIGN = _mm_set1_ps(-0.0f);
  const __m128 u = _mm_mul_ps(_mm_cvtepi32_ps(_mm_srai_epi32(_mm_slli_epi32(c, 16), 16)), S);
  const __m128 w = _mm_mul_ps(_mm_cvtepi32_ps(_mm_srai_epi32(c, 16)), S);
  const __m128 z = _mm_sub_ps(_mm_sub_ps(_mm_set1_ps(1.0f), _mm_andnot_ps(SIGN, u)), _mm_andnot_ps(SIGN, w));
  const __m128 t = _mm_max_ps(_mm_xor_ps(z, SIGN), _mm_setzero_ps());
  const __m128 x = _mm_sub_ps(u, _mm_or_ps(_mm_and_ps(u, SIGN), t)), y = _mm_sub_ps(w, _mm_or_ps(_mm_and_ps(w, SIGN), t));
  const __m128 val = _mm_sub_ps(
      _mm_add_ps(_mm_add_ps(_mm_mul_ps(x, _mm_set1_ps(p[0])), _mm_mul_ps(y, _mm_set1_ps(p[1]))),
                 _mm_mul_ps(z, _mm_set1_ps(p[2]))),
      d);
  const __m128 no_plane = _mm_castsi128_ps(_mm_srai_epi32(_mm_slli_epi32(_mm_castps_si128(fl), kNoPlaneShift), 31));
  return _mm_andnot_ps(no_plane, val);
}

/// The last rows of blk[j, j + 4), transposed: c.z, code, d, tri_flags.
inline void plane_rows_sse2(const LeafTri* blk, unsigned j, __m128 r[4]) {
  auto row = [&](unsigned i) { return _mm_loadu_ps(reinterpret_cast<const float*>(reinterpret_cast<const char*>(blk + i) + kPlaneRow)); };
  r[0] = row(j), r[1] = row(j + 1), r[2] = row(j + 2), r[3] = row(j + 3);
  _MM_TRANSPOSE4_PS(r[0], r[1], r[2], r[3]);
}
#endif

unsigned plane_pass_baseline(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8], unsigned ref_sides) {
  unsigned gt = 0, lt = 0, pos = 0, deg = 0;
  unsigned j = 0;
#if defined(__SSE2__)
  const __m128 EP = _mm_set1_ps(eps), EN = _mm_set1_ps(-eps);
  for (; j + 4 <= m; j += 4) {
    __m128 r[4];
    plane_rows_sse2(blk, j, r);
    const __m128 v = face_values_sse2(r[1], r[2], r[3], p);
    gt |= unsigned(_mm_movemask_ps(_mm_cmpgt_ps(v, EP))) << j;
    lt |= unsigned(_mm_movemask_ps(_mm_cmplt_ps(v, EN))) << j;
    _mm_storeu_ps(s + j, v);
  }
#endif
  for (; j < m; ++j) {
    const float v = face_plane_value(blk[j], p);
    s[j] = v;
    gt |= unsigned(v > eps) << j;
    lt |= unsigned(v < -eps) << j;
  }
  for (j = 0; j < m; ++j) {
    pos |= (blk[j].flags() & kRefPositive ? 1u : 0u) << j;
    deg |= (blk[j].flags() & kDegenerate ? 1u : 0u) << j;
  }
  if (ref_sides != kRefSidesFromFlags) pos = ref_sides;
  return ~((gt & pos) | (lt & ~pos) | deg) & low_bits(m);
}

unsigned box_pass_baseline(const LeafTri* blk, unsigned m, const GatherTest& g, BlockTriBoxes& boxes,
                           unsigned* on_seam) {
  unsigned hit = 0, seam = 0;
  for (unsigned j = 0; j < m; ++j) {
    const LeafTri& t = blk[j];
    bool meets = g.with_degenerate || !(t.flags() & kDegenerate), across = false;
    for (int a = 0; a < 3; ++a) {
      const float tl = std::min(std::min(t.a[a], t.b[a]), t.c[a]), th = std::max(std::max(t.a[a], t.b[a]), t.c[a]);
      boxes.lo[a][j] = tl;
      boxes.hi[a][j] = th;
      meets = meets && !(th < g.lo[a] || tl > g.hi[a]);
      across = across || (tl <= g.seam_hi[a] && th >= g.seam_lo[a]);
    }
    hit |= unsigned(meets) << j;
    seam |= unsigned(meets && across) << j;
  }
  *on_seam = seam;
  return hit;
}

std::uint32_t append_members_baseline(const BlockTriBoxes& boxes, unsigned keep, std::uint32_t first,
                                      std::uint32_t leaf, std::uint32_t node, const MemberColumns& out,
                                      std::uint32_t n) {
  std::uint32_t count = 0;
  for (; keep; keep &= keep - 1, ++count) {
    const unsigned j = unsigned(__builtin_ctz(keep));
    const std::uint32_t s = n + count;
    if (s >= out.slots) continue;  // past the columns' end: counted, not written
    for (int a = 0; a < 3; ++a) {
      out.lo[a][s] = boxes.lo[a][j];
      out.hi[a][s] = boxes.hi[a][j];
    }
    out.k[s] = first + j;
    out.leaf[s] = leaf;
    out.node[s] = node;
  }
  return count;
}

unsigned distance_pass_baseline(const LeafTri* blk, unsigned m, const float p[3], const float q_lo[3],
                                const float q_hi[3], float plane_lim, float box_lim, float plane_abs[8],
                                float box_d2[8]) {
  unsigned keep = 0;
  for (unsigned j = 0; j < m; ++j) {
    const LeafTri& t = blk[j];
    const float s = face_plane_distance(t, p);
    float sum = 0;
    for (int a = 0; a < 3; ++a) {
      const float lo = std::min(std::min(t.a[a], t.b[a]), t.c[a]), hi = std::max(std::max(t.a[a], t.b[a]), t.c[a]);
      const float g = std::max(std::max(lo - q_hi[a], q_lo[a] - hi), 0.0f);
      sum = sum + g * g;
    }
    plane_abs[j] = s;
    box_d2[j] = sum;
    if (!(s > plane_lim) && !(sum > box_lim)) keep |= 1u << j;
  }
  return keep;
}

std::uint64_t column_box_pass_baseline(const float* const lo[3], const float* const hi[3], std::uint32_t n,
                                       const float q_lo[3], const float q_hi[3], float box_lim, float* g2) {
  std::uint64_t within = 0;
  for (std::uint32_t j = 0; j < (n + 7) / 8 * 8; ++j) {
    float sum = 0;
    for (int a = 0; a < 3; ++a) {
      const float g = std::max(std::max(lo[a][j] - q_hi[a], q_lo[a] - hi[a][j]), 0.0f);
      sum = sum + g * g;
    }
    g2[j] = sum;
    if (j < n && sum <= box_lim) within |= std::uint64_t(1) << j;
  }
  return within;
}

void closest_points_baseline(const Vec3d& p, const LeafTri* const t[4], unsigned m, Vec3d q[4], double d2[4]) {
  for (unsigned i = 0; i < m; ++i) q[i] = exact_closest_point(p, *t[i], &d2[i]);
}

void box_distances_baseline(const BlockBox* boxes, std::uint32_t n, const Vec3d& p, double* d2) {
  for (std::uint32_t j = 0; j < n; ++j) d2[j] = box_d2(boxes[j], p);
}

unsigned block_pass_baseline(const BlockBox* boxes, unsigned m, const float lo[3], const float hi[3]) {
  unsigned hit = 0;
#if defined(__SSE2__)
  // [lo.x, lo.y, lo.z, hi.x] against the query box's hi (lane 3: +inf, never above), and
  // [lo.z, hi.x, hi.y, hi.z] against its lo (lane 0: -inf, never below): two loads inside the record.
  static_assert(sizeof(BlockBox) == 24 && offsetof(BlockBox, hi) == 12, "BlockBox: lo then hi, 6 floats");
  const __m128 QHI = _mm_setr_ps(hi[0], hi[1], hi[2], kInf), QLO = _mm_setr_ps(-kInf, lo[0], lo[1], lo[2]);
  for (unsigned j = 0; j < m; ++j) {
    const __m128 L = _mm_loadu_ps(boxes[j].lo), H = _mm_loadu_ps(boxes[j].lo + 2);
    if (_mm_movemask_ps(_mm_or_ps(_mm_cmpgt_ps(L, QHI), _mm_cmplt_ps(H, QLO))) == 0) hit |= 1u << j;
  }
#else
  for (unsigned j = 0; j < m; ++j)
    if (boxes[j].meets(lo, hi)) hit |= 1u << j;
#endif
  return hit;
}

/// Shewchuk's orient3d filter (predicates.hpp) for orient3d(p, q, x, y), as -orient3d(q, x, y, p)
/// (moving p last is an odd permutation), on the differences u = q - p, X = x - p, Y = y - p:
/// +1 / -1 when the filter decides, 0 when it cannot.
inline int edge_filter(const double u[3], const double X[3], const double Y[3]) {
  const double bdxcdy = X[0] * Y[1], cdxbdy = Y[0] * X[1];
  const double cdxady = Y[0] * u[1], adxcdy = u[0] * Y[1];
  const double adxbdy = u[0] * X[1], bdxady = X[0] * u[1];
  const double det = u[2] * (bdxcdy - cdxbdy) + X[2] * (cdxady - adxcdy) + Y[2] * (adxbdy - bdxady);
  const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * std::fabs(u[2]) +
                           (std::fabs(cdxady) + std::fabs(adxcdy)) * std::fabs(X[2]) +
                           (std::fabs(adxbdy) + std::fabs(bdxady)) * std::fabs(Y[2]);
  const double errbound = kOrientErrBoundA * permanent;
  if (det > errbound) return 1;
  if (-det > errbound) return -1;
  return 0;
}

unsigned edge_signs_baseline(const Vec3d& p, const Vec3d& q, const float a[3], const float b[3], const float c[3]) {
  const double u[3] = {q.x - p.x, q.y - p.y, q.z - p.z};
  const double D[3][3] = {{double(a[0]) - p.x, double(a[1]) - p.y, double(a[2]) - p.z},
                          {double(b[0]) - p.x, double(b[1]) - p.y, double(b[2]) - p.z},
                          {double(c[0]) - p.x, double(c[1]) - p.y, double(c[2]) - p.z}};
  unsigned mask = 0, undecided = 0;
  for (int i = 0; i < 3; ++i) {
    const int e = edge_filter(u, D[i], D[(i + 1) % 3]);
    mask |= e > 0 ? 1u << i : e < 0 ? 16u << i : 0u;
    undecided |= (e == 0 ? 1u : 0u) << i;
  }
  return undecided ? mask | exact_edges(p, q, a, b, c, undecided) : mask;
}

// --- AVX2 -------------------------------------------------------------------------------------
#if defined(EBP_X86)

#define EBP_AVX2 __attribute__((target("avx2")))

/// The tri_flags of blk[0, m) in 8 lanes (lanes >= m: 0, not read).
EBP_AVX2 inline __m256i gather_tri_flags(const LeafTri* blk, unsigned m) {
  constexpr int kStride = int(sizeof(LeafTri) / 4);  // records, in ints
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i idx = _mm256_mullo_epi32(lane, _mm256_set1_epi32(kStride));
  const __m256i live = _mm256_cmpgt_epi32(_mm256_set1_epi32(int(m)), lane);
  return _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(&blk[0].tri_flags), idx, live, 4);
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

/// Four floats at byte offset Off of 8 records, transposed: lane j of out[i] = float i of record j
/// (records j and j + 4 share a row register; a 4x4 transpose per 128-bit half).
template <std::size_t Off>
EBP_AVX2 inline void columns(const LeafTri* blk, unsigned m, __m256 out[4]) {
  const __m256 R0 = rows<Off>(blk, m, 0), R1 = rows<Off>(blk, m, 1), R2 = rows<Off>(blk, m, 2),
               R3 = rows<Off>(blk, m, 3);
  const __m256 t0 = _mm256_unpacklo_ps(R0, R1), t1 = _mm256_unpackhi_ps(R0, R1);
  const __m256 t2 = _mm256_unpacklo_ps(R2, R3), t3 = _mm256_unpackhi_ps(R2, R3);
  out[0] = _mm256_shuffle_ps(t0, t2, 0x44);
  out[1] = _mm256_shuffle_ps(t0, t2, 0xEE);
  out[2] = _mm256_shuffle_ps(t1, t3, 0x44);
  out[3] = _mm256_shuffle_ps(t1, t3, 0xEE);
}

/// The face-plane values of 8 records from their last rows' columns (code, d, tri_flags):
/// face_plane_value's operations lane-wise. v[3] (optional): the decoded normals.
EBP_AVX2 inline __m256 face_values_avx2(__m256 code, __m256 d, __m256 fl, const float p[3], __m256* v = nullptr) {
  const __m256i c = _mm256_castps_si256(code);
  const __m256 S = _mm256_set1_ps(kOctScale), SIGN = _mm256_set1_ps(-0.0f);
  const __m256 u = _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(c, 16), 16)), S);
  const __m256 w = _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srai_epi32(c, 16)), S);
  const __m256 z =
      _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(1.0f), _mm256_andnot_ps(SIGN, u)), _mm256_andnot_ps(SIGN, w));
  const __m256 t = _mm256_max_ps(_mm256_xor_ps(z, SIGN), _mm256_setzero_ps());
  const __m256 x = _mm256_sub_ps(u, _mm256_or_ps(_mm256_and_ps(u, SIGN), t));
  const __m256 y = _mm256_sub_ps(w, _mm256_or_ps(_mm256_and_ps(w, SIGN), t));
  const __m256 val = _mm256_sub_ps(
      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, _mm256_set1_ps(p[0])), _mm256_mul_ps(y, _mm256_set1_ps(p[1]))),
                    _mm256_mul_ps(z, _mm256_set1_ps(p[2]))),
      d);
  if (v) v[0] = x, v[1] = y, v[2] = z;
  const __m256 no_plane =
      _mm256_castsi256_ps(_mm256_srai_epi32(_mm256_slli_epi32(_mm256_castps_si256(fl), kNoPlaneShift), 31));
  return _mm256_andnot_ps(no_plane, val);
}

/// The masks of the flags in the tri_flags column: kRefPositive (*pos) and kDegenerate (*deg).
EBP_AVX2 inline void flag_masks_avx2(__m256 fl, unsigned* pos, unsigned* deg) {
  *pos = unsigned(_mm256_movemask_ps(fl));
  *deg = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_slli_epi32(_mm256_castps_si256(fl), kDegenerateShift))));
}

EBP_AVX2 unsigned plane_pass_avx2(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8],
                                   unsigned ref_sides) {
  __m256 r[4];
  columns<kPlaneRow>(blk, m, r);  // c.z, code, d, tri_flags
  const __m256 v = face_values_avx2(r[1], r[2], r[3], p);
  _mm256_storeu_ps(s, v);
  const unsigned gt = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(v, _mm256_set1_ps(eps), _CMP_GT_OQ)));
  const unsigned lt = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(v, _mm256_set1_ps(-eps), _CMP_LT_OQ)));
  unsigned pos, deg;
  flag_masks_avx2(r[3], &pos, &deg);
  if (ref_sides != kRefSidesFromFlags) pos = ref_sides;
  return ~((gt & pos) | (lt & ~pos) | deg) & low_bits(m);
}

EBP_AVX2 unsigned box_pass_avx2(const LeafTri* blk, unsigned m, const GatherTest& g, BlockTriBoxes& boxes,
                               unsigned* on_seam) {
  __m256 a[4], b[4], c[4];
  columns<offsetof(LeafTri, a)>(blk, m, a);  // ax, ay, az (lane 3: bx, unused)
  columns<offsetof(LeafTri, b)>(blk, m, b);
  columns<offsetof(LeafTri, c)>(blk, m, c);
  __m256 out = _mm256_setzero_ps(), across = _mm256_setzero_ps();
  for (int k = 0; k < 3; ++k) {
    const __m256 lo = _mm256_min_ps(_mm256_min_ps(a[k], b[k]), c[k]), hi = _mm256_max_ps(_mm256_max_ps(a[k], b[k]), c[k]);
    _mm256_store_ps(boxes.lo[k], lo);
    _mm256_store_ps(boxes.hi[k], hi);
    out = _mm256_or_ps(out, _mm256_or_ps(_mm256_cmp_ps(hi, _mm256_set1_ps(g.lo[k]), _CMP_LT_OQ),
                                         _mm256_cmp_ps(lo, _mm256_set1_ps(g.hi[k]), _CMP_GT_OQ)));
    across = _mm256_or_ps(across, _mm256_and_ps(_mm256_cmp_ps(lo, _mm256_set1_ps(g.seam_hi[k]), _CMP_LE_OQ),
                                                _mm256_cmp_ps(hi, _mm256_set1_ps(g.seam_lo[k]), _CMP_GE_OQ)));
  }
  unsigned hit = ~unsigned(_mm256_movemask_ps(out)) & low_bits(m);
  if (!g.with_degenerate)
    hit &= ~unsigned(_mm256_movemask_ps(
        _mm256_castsi256_ps(_mm256_slli_epi32(gather_tri_flags(blk, m), kDegenerateShift))));
  *on_seam = hit & unsigned(_mm256_movemask_ps(across));
  return hit;
}

/// For each mask of 8 lanes, its set lanes in order, packed 4 bits each (the permutation that
/// moves them to the front).
constexpr std::array<std::uint32_t, 256> left_pack_table() {
  std::array<std::uint32_t, 256> t{};
  for (unsigned mask = 0; mask < 256; ++mask) {
    unsigned slot = 0;
    for (unsigned lane = 0; lane < 8; ++lane)
      if (mask >> lane & 1u) t[mask] |= lane << (4 * slot++);
  }
  return t;
}
constexpr std::array<std::uint32_t, 256> kLeftPack = left_pack_table();

EBP_AVX2 std::uint32_t append_members_avx2(const BlockTriBoxes& boxes, unsigned keep, std::uint32_t first,
                                           std::uint32_t leaf, std::uint32_t node, const MemberColumns& out,
                                           std::uint32_t n) {
  if (n + 8 > out.slots) [[unlikely]]  // the columns' end: lane by lane
    return append_members_baseline(boxes, keep, first, leaf, node, out, n);
  const __m256i lanes = _mm256_and_si256(
      _mm256_srlv_epi32(_mm256_set1_epi32(int(kLeftPack[keep & 255u])), _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28)),
      _mm256_set1_epi32(15));
  for (int a = 0; a < 3; ++a) {
    _mm256_storeu_ps(out.lo[a] + n, _mm256_permutevar8x32_ps(_mm256_load_ps(boxes.lo[a]), lanes));
    _mm256_storeu_ps(out.hi[a] + n, _mm256_permutevar8x32_ps(_mm256_load_ps(boxes.hi[a]), lanes));
  }
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out.k + n), _mm256_add_epi32(_mm256_set1_epi32(int(first)), lanes));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out.leaf + n), _mm256_set1_epi32(int(leaf)));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out.node + n), _mm256_set1_epi32(int(node)));
  return std::uint32_t(__builtin_popcount(keep & 255u));
}

EBP_AVX2 unsigned distance_pass_avx2(const LeafTri* blk, unsigned m, const float p[3], const float q_lo[3],
                                     const float q_hi[3], float plane_lim, float box_lim, float plane_abs[8],
                                     float box_d2[8]) {
  __m256 r[4], a[4], b[4], c[4], v[3];
  columns<kPlaneRow>(blk, m, r);             // c.z, code, d, tri_flags
  columns<offsetof(LeafTri, a)>(blk, m, a);  // ax, ay, az (lane 3: bx, unused)
  columns<offsetof(LeafTri, b)>(blk, m, b);
  columns<offsetof(LeafTri, c)>(blk, m, c);
  const __m256 value = face_values_avx2(r[1], r[2], r[3], p, v);
  const __m256 len = _mm256_sqrt_ps(
      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(v[0], v[0]), _mm256_mul_ps(v[1], v[1])), _mm256_mul_ps(v[2], v[2])));
  const __m256 abs_s = _mm256_div_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), value), len);
  __m256 sum = _mm256_setzero_ps();
  for (int k = 0; k < 3; ++k) {
    const __m256 lo = _mm256_min_ps(_mm256_min_ps(a[k], b[k]), c[k]), hi = _mm256_max_ps(_mm256_max_ps(a[k], b[k]), c[k]);
    const __m256 g = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(lo, _mm256_set1_ps(q_hi[k])),
                                                 _mm256_sub_ps(_mm256_set1_ps(q_lo[k]), hi)),
                                   _mm256_setzero_ps());
    sum = _mm256_add_ps(sum, _mm256_mul_ps(g, g));
  }
  _mm256_storeu_ps(plane_abs, abs_s);
  _mm256_storeu_ps(box_d2, sum);
  const unsigned out = unsigned(_mm256_movemask_ps(_mm256_or_ps(_mm256_cmp_ps(abs_s, _mm256_set1_ps(plane_lim), _CMP_GT_OQ),
                                                                _mm256_cmp_ps(sum, _mm256_set1_ps(box_lim), _CMP_GT_OQ))));
  return ~out & low_bits(m);
}

EBP_AVX2 std::uint64_t column_box_pass_avx2(const float* const lo[3], const float* const hi[3], std::uint32_t n,
                                            const float q_lo[3], const float q_hi[3], float box_lim, float* g2) {
  __m256 QLO[3], QHI[3];
  for (int a = 0; a < 3; ++a) {
    QLO[a] = _mm256_set1_ps(q_lo[a]);
    QHI[a] = _mm256_set1_ps(q_hi[a]);
  }
  const __m256 LIM = _mm256_set1_ps(box_lim);
  std::uint64_t within = 0;
  for (std::uint32_t j = 0; j < n; j += 8) {
    __m256 sum = _mm256_setzero_ps();
    for (int a = 0; a < 3; ++a) {
      const __m256 g = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(_mm256_load_ps(lo[a] + j), QHI[a]),
                                                   _mm256_sub_ps(QLO[a], _mm256_load_ps(hi[a] + j))),
                                     _mm256_setzero_ps());
      sum = _mm256_add_ps(sum, _mm256_mul_ps(g, g));
    }
    _mm256_storeu_ps(g2 + j, sum);
    within |= std::uint64_t(unsigned(_mm256_movemask_ps(_mm256_cmp_ps(sum, LIM, _CMP_LE_OQ)))) << j;
  }
  return n >= 64 ? within : within & ((std::uint64_t(1) << n) - 1);
}

/// Lane-wise dot product in dot()'s order: (x0 y0 + x1 y1) + x2 y2.
EBP_AVX2 inline __m256d dot_pd(const __m256d x[3], const __m256d y[3]) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x[0], y[0]), _mm256_mul_pd(x[1], y[1])), _mm256_mul_pd(x[2], y[2]));
}

// Ordered comparisons (false on NaN, as in C++) and their conjunction, lane-wise.
EBP_AVX2 inline __m256d le(__m256d x, __m256d y) { return _mm256_cmp_pd(x, y, _CMP_LE_OQ); }
EBP_AVX2 inline __m256d ge(__m256d x, __m256d y) { return _mm256_cmp_pd(x, y, _CMP_GE_OQ); }
EBP_AVX2 inline __m256d gt(__m256d x, __m256d y) { return _mm256_cmp_pd(x, y, _CMP_GT_OQ); }
EBP_AVX2 inline __m256d all(__m256d x, __m256d y) { return _mm256_and_pd(x, y); }

/// A vertex (3 floats at byte offset Off) of 4 records as 3 columns of doubles (exact): a row of 4
/// floats from each record (inside it: the static_assert above), a 4x4 transpose, widened.
template <std::size_t Off>
EBP_AVX2 inline void vertex_columns(const LeafTri* const r[4], __m256d out[3]) {
  auto row = [&](int i) { return _mm_loadu_ps(reinterpret_cast<const float*>(reinterpret_cast<const char*>(r[i]) + Off)); };
  __m128 r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);  // x, y, z of the four (r3: the next field, unused)
  out[0] = _mm256_cvtps_pd(r0);
  out[1] = _mm256_cvtps_pd(r1);
  out[2] = _mm256_cvtps_pd(r2);
}

/// Lanes where mask is set take `a`, the others keep `b`.
EBP_AVX2 inline void select3(__m256d mask, const __m256d a[3], __m256d b[3]) {
  for (int k = 0; k < 3; ++k) b[k] = _mm256_blendv_pd(b[k], a[k], mask);
}

EBP_AVX2 void closest_points_avx2(const Vec3d& p, const LeafTri* const t[4], unsigned m, Vec3d q[4], double d2[4]) {
  // The 4 records' vertices as columns of doubles; missing lanes repeat the first triangle.
  const LeafTri* r[4];
  for (unsigned i = 0; i < 4; ++i) r[i] = t[i < m ? i : 0];
  __m256d A[3], B[3], C[3];
  vertex_columns<offsetof(LeafTri, a)>(r, A);
  vertex_columns<offsetof(LeafTri, b)>(r, B);
  vertex_columns<offsetof(LeafTri, c)>(r, C);
  const __m256d P[3] = {_mm256_set1_pd(p.x), _mm256_set1_pd(p.y), _mm256_set1_pd(p.z)};
  __m256d ab[3], ac[3], ap[3], bp[3], cp[3], cb[3];
  for (int k = 0; k < 3; ++k) {
    ab[k] = _mm256_sub_pd(B[k], A[k]);
    ac[k] = _mm256_sub_pd(C[k], A[k]);
    ap[k] = _mm256_sub_pd(P[k], A[k]);
    bp[k] = _mm256_sub_pd(P[k], B[k]);
    cp[k] = _mm256_sub_pd(P[k], C[k]);
    cb[k] = _mm256_sub_pd(C[k], B[k]);
  }
  // closest_point_on_triangle's values, then its cases as masks (ordered comparisons: false on NaN, as in C++)
  const __m256d d1 = dot_pd(ab, ap), d2_ = dot_pd(ac, ap), d3 = dot_pd(ab, bp), d4 = dot_pd(ac, bp);
  const __m256d d5 = dot_pd(ab, cp), d6 = dot_pd(ac, cp);
  const __m256d vc = _mm256_sub_pd(_mm256_mul_pd(d1, d4), _mm256_mul_pd(d3, d2_));
  const __m256d vb = _mm256_sub_pd(_mm256_mul_pd(d5, d2_), _mm256_mul_pd(d1, d6));
  const __m256d va = _mm256_sub_pd(_mm256_mul_pd(d3, d6), _mm256_mul_pd(d5, d4));
  const __m256d Z = _mm256_setzero_pd();
  const __m256d d13 = _mm256_sub_pd(d1, d3), d26 = _mm256_sub_pd(d2_, d6);
  const __m256d d43 = _mm256_sub_pd(d4, d3), d56 = _mm256_sub_pd(d5, d6), d4356 = _mm256_add_pd(d43, d56);
  const __m256d in_a = all(le(d1, Z), le(d2_, Z));
  const __m256d in_b = all(ge(d3, Z), le(d4, d3));
  const __m256d in_ab = all(all(le(vc, Z), ge(d1, Z)), all(le(d3, Z), gt(d13, Z)));
  const __m256d in_c = all(ge(d6, Z), le(d5, d6));
  const __m256d in_ca = all(all(le(vb, Z), ge(d2_, Z)), all(le(d6, Z), gt(d26, Z)));
  const __m256d in_bc = all(all(le(va, Z), ge(d43, Z)), all(ge(d56, Z), gt(d4356, Z)));
  const __m256d denom = _mm256_add_pd(_mm256_add_pd(va, vb), vc);
  // the face, then each earlier case over it, last the first: the scalar's order of tests
  const __m256d v = _mm256_div_pd(vb, denom), w = _mm256_div_pd(vc, denom);
  const __m256d s_ab = _mm256_div_pd(d1, d13), s_ca = _mm256_div_pd(d2_, d26), s_bc = _mm256_div_pd(d43, d4356);
  __m256d Q[3], X[3];
  for (int k = 0; k < 3; ++k) Q[k] = _mm256_add_pd(_mm256_add_pd(A[k], _mm256_mul_pd(ab[k], v)), _mm256_mul_pd(ac[k], w));
  for (int k = 0; k < 3; ++k) X[k] = _mm256_add_pd(B[k], _mm256_mul_pd(cb[k], s_bc));
  select3(in_bc, X, Q);
  for (int k = 0; k < 3; ++k) X[k] = _mm256_add_pd(A[k], _mm256_mul_pd(ac[k], s_ca));
  select3(in_ca, X, Q);
  select3(in_c, C, Q);
  for (int k = 0; k < 3; ++k) X[k] = _mm256_add_pd(A[k], _mm256_mul_pd(ab[k], s_ab));
  select3(in_ab, X, Q);
  select3(in_b, B, Q);
  select3(in_a, A, Q);
  __m256d E[3];
  for (int k = 0; k < 3; ++k) E[k] = _mm256_sub_pd(Q[k], P[k]);
  const __m256d D2 = dot_pd(E, E);
  alignas(32) double qx[4], qy[4], qz[4], dd[4];
  _mm256_store_pd(qx, Q[0]);
  _mm256_store_pd(qy, Q[1]);
  _mm256_store_pd(qz, Q[2]);
  _mm256_store_pd(dd, D2);
  // a zero-area triangle past every case (denom not > 0): the scalar's fall-back over its edges
  const __m256d any_case = _mm256_or_pd(_mm256_or_pd(_mm256_or_pd(in_a, in_b), _mm256_or_pd(in_ab, in_c)),
                                        _mm256_or_pd(in_ca, in_bc));
  const unsigned fallback =
      unsigned(_mm256_movemask_pd(_mm256_andnot_pd(any_case, _mm256_cmp_pd(denom, Z, _CMP_NGT_UQ))));
  for (unsigned i = 0; i < m; ++i) {
    if (fallback >> i & 1u) {
      q[i] = exact_closest_point(p, *r[i], &d2[i]);
    } else {
      q[i] = Vec3d(qx[i], qy[i], qz[i]);
      d2[i] = dd[i];
    }
  }
}

EBP_AVX2 inline __m256d abs_pd(__m256d v) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), v); }

EBP_AVX2 unsigned block_pass_avx2(const BlockBox* boxes, unsigned m, const float lo[3], const float hi[3]) {
  // As the baseline, two boxes per register: j in the low half, j + 4 in the high half.
  const __m128 qhi = _mm_setr_ps(hi[0], hi[1], hi[2], kInf), qlo = _mm_setr_ps(-kInf, lo[0], lo[1], lo[2]);
  const __m256 QHI = _mm256_insertf128_ps(_mm256_castps128_ps256(qhi), qhi, 1);
  const __m256 QLO = _mm256_insertf128_ps(_mm256_castps128_ps256(qlo), qlo, 1);
  auto half = [&](unsigned i, int off) {
    return i < m ? _mm_loadu_ps(boxes[i].lo + off) : _mm_setzero_ps();
  };
  unsigned miss = 0;
  for (unsigned j = 0; j < 4 && j < m; ++j) {
    const __m256 L = _mm256_insertf128_ps(_mm256_castps128_ps256(half(j, 0)), half(j + 4, 0), 1);
    const __m256 H = _mm256_insertf128_ps(_mm256_castps128_ps256(half(j, 2)), half(j + 4, 2), 1);
    const unsigned out = unsigned(_mm256_movemask_ps(_mm256_or_ps(_mm256_cmp_ps(L, QHI, _CMP_GT_OQ),
                                                                  _mm256_cmp_ps(H, QLO, _CMP_LT_OQ))));
    miss |= ((out & 15u) ? 1u : 0u) << j;
    miss |= ((out >> 4) ? 1u : 0u) << (j + 4);
  }
  return ~miss & low_bits(m);
}

/// Per lane, the squared gap of [lo, hi] (float, widened) to P on one axis.
EBP_AVX2 inline __m256d axis_gap2(__m128 lo, __m128 hi, __m256d P) {
  const __m256d v = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(_mm256_cvtps_pd(lo), P), _mm256_setzero_pd()),
                                  _mm256_sub_pd(P, _mm256_cvtps_pd(hi)));
  return _mm256_mul_pd(v, v);
}

EBP_AVX2 void box_distances_avx2(const BlockBox* boxes, std::uint32_t n, const Vec3d& p, double* d2) {
  // Four boxes at a time: their [lo.x, lo.y, lo.z, hi.x] and [lo.z, hi.x, hi.y, hi.z] rows
  // (two loads inside each record, as in block_pass) transposed into one column per
  // coordinate, widened to double: the baseline's operations on exactly the same values (a max
  // of the three terms in another order gives the same value; 0 + x = x), so the same bits.
  const __m256d P0 = _mm256_set1_pd(p.x), P1 = _mm256_set1_pd(p.y), P2 = _mm256_set1_pd(p.z);
  std::uint32_t j = 0;
  for (; j + 4 <= n; j += 4) {
    __m128 l0 = _mm_loadu_ps(boxes[j].lo), l1 = _mm_loadu_ps(boxes[j + 1].lo), l2 = _mm_loadu_ps(boxes[j + 2].lo),
           l3 = _mm_loadu_ps(boxes[j + 3].lo);
    __m128 h0 = _mm_loadu_ps(boxes[j].lo + 2), h1 = _mm_loadu_ps(boxes[j + 1].lo + 2),
           h2 = _mm_loadu_ps(boxes[j + 2].lo + 2), h3 = _mm_loadu_ps(boxes[j + 3].lo + 2);
    _MM_TRANSPOSE4_PS(l0, l1, l2, l3);  // lo.x, lo.y, lo.z, hi.x of the four
    _MM_TRANSPOSE4_PS(h0, h1, h2, h3);  // lo.z, hi.x, hi.y, hi.z of the four
    _mm256_storeu_pd(d2 + j, _mm256_add_pd(_mm256_add_pd(axis_gap2(l0, h1, P0), axis_gap2(l1, h2, P1)),
                                           axis_gap2(l2, h3, P2)));
  }
  for (; j < n; ++j) d2[j] = box_d2(boxes[j], p);
}

EBP_AVX2 unsigned edge_signs_avx2(const Vec3d& p, const Vec3d& q, const float a[3], const float b[3], const float c[3]) {
  // Lane i = edge i: X = (a, b, c) - p, Y = (b, c, a) - p, the filter of edge_filter lane-wise
  // (same operations; lane 3 is zero and ignored).
  // [p.x, p.y, p.z, 0] by two loads (a lane-wise set compiles to a VEX vmovq that valgrind 3.19
  // cannot decode, and callgrind measures this code).
  static_assert(sizeof(Vec3d) == 24 && offsetof(Vec3d, z) == 16, "Vec3d: x, y, z contiguous");
  const __m256d P = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&p.x)), _mm_load_sd(&p.z), 1);
  const __m256d A = _mm256_sub_pd(_mm256_cvtps_pd(_mm_loadu_ps(a)), P);  // lane 3: junk
  const __m256d B = _mm256_sub_pd(_mm256_cvtps_pd(_mm_loadu_ps(b)), P);
  const __m256d C = _mm256_sub_pd(_mm256_cvtps_pd(_mm_loadu_ps(c)), P);
  const __m256d Z = _mm256_setzero_pd();
  const __m256d t0 = _mm256_unpacklo_pd(A, B), t1 = _mm256_unpackhi_pd(A, B);  // [Ax Bx Az Bz], [Ay By . .]
  const __m256d t2 = _mm256_unpacklo_pd(C, Z), t3 = _mm256_unpackhi_pd(C, Z);  // [Cx 0 Cz 0], [Cy 0 . .]
  const __m256d Xx = _mm256_permute2f128_pd(t0, t2, 0x20), Xy = _mm256_permute2f128_pd(t1, t3, 0x20),
                Xz = _mm256_permute2f128_pd(t0, t2, 0x31);
  const __m256d Yx = _mm256_permute4x64_pd(Xx, _MM_SHUFFLE(3, 0, 2, 1)),
                Yy = _mm256_permute4x64_pd(Xy, _MM_SHUFFLE(3, 0, 2, 1)),
                Yz = _mm256_permute4x64_pd(Xz, _MM_SHUFFLE(3, 0, 2, 1));
  const __m256d ux = _mm256_set1_pd(q.x - p.x), uy = _mm256_set1_pd(q.y - p.y), uz = _mm256_set1_pd(q.z - p.z);
  const __m256d bdxcdy = _mm256_mul_pd(Xx, Yy), cdxbdy = _mm256_mul_pd(Yx, Xy);
  const __m256d cdxady = _mm256_mul_pd(Yx, uy), adxcdy = _mm256_mul_pd(ux, Yy);
  const __m256d adxbdy = _mm256_mul_pd(ux, Xy), bdxady = _mm256_mul_pd(Xx, uy);
  const __m256d det = _mm256_add_pd(
      _mm256_add_pd(_mm256_mul_pd(uz, _mm256_sub_pd(bdxcdy, cdxbdy)), _mm256_mul_pd(Xz, _mm256_sub_pd(cdxady, adxcdy))),
      _mm256_mul_pd(Yz, _mm256_sub_pd(adxbdy, bdxady)));
  const __m256d sign = _mm256_set1_pd(-0.0);  // -det below
  const __m256d perm = _mm256_add_pd(
      _mm256_add_pd(_mm256_mul_pd(_mm256_add_pd(abs_pd(bdxcdy), abs_pd(cdxbdy)), abs_pd(uz)),
                    _mm256_mul_pd(_mm256_add_pd(abs_pd(cdxady), abs_pd(adxcdy)), abs_pd(Xz))),
      _mm256_mul_pd(_mm256_add_pd(abs_pd(adxbdy), abs_pd(bdxady)), abs_pd(Yz)));
  const __m256d err = _mm256_mul_pd(_mm256_set1_pd(kOrientErrBoundA), perm);
  const unsigned pos = unsigned(_mm256_movemask_pd(_mm256_cmp_pd(det, err, _CMP_GT_OQ))) & 7u;
  const unsigned neg = unsigned(_mm256_movemask_pd(_mm256_cmp_pd(_mm256_xor_pd(det, sign), err, _CMP_GT_OQ))) & 7u;
  const unsigned undecided = ~(pos | neg) & 7u;
  return undecided ? pos | neg << 4 | exact_edges(p, q, a, b, c, undecided) : pos | neg << 4;
}

#endif  // EBP_X86

// --- the choice -------------------------------------------------------------------------------

LeafKernelTable make(LeafKernels k) {
#if defined(EBP_X86)
  if (k == LeafKernels::avx2 && cpu_has_avx2())
    return {plane_pass_avx2,      box_pass_avx2,     append_members_avx2,  block_pass_avx2,
            box_distances_avx2,   edge_signs_avx2,   distance_pass_avx2,   column_box_pass_avx2,
            closest_points_avx2,  LeafKernels::avx2};
#endif
  (void)k;
  return {plane_pass_baseline,    box_pass_baseline,      append_members_baseline,  block_pass_baseline,
          box_distances_baseline, edge_signs_baseline,    distance_pass_baseline,   column_box_pass_baseline,
          closest_points_baseline, LeafKernels::baseline};
}

LeafKernelTable& current() {
  static LeafKernelTable k = make(LeafKernels::avx2);
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

const LeafKernelTable& leaf_kernel_table() { return current(); }

void distance_prefilter_limits(double best, double best2, double eps_p, float* plane_lim, float* box_lim) {
  float lo;
  float_bounds((best + eps_p) * (1 + 1e-9), &lo, plane_lim);
  float_bounds(box_prefilter_limit(best2), &lo, box_lim);
}

}  // namespace ebp
