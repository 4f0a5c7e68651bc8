// The inside query's leaf kernels (core/leaf_kernels.hpp): the AVX2 and baseline kernels give
// the same bits as the plain float expressions, and the inside answers and counters do not
// depend on which one runs, coherent or not, on real, grazing and stress-style inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/io/mesh_io.hpp"
#include "methods/ebp_octree/core/leaf_kernels.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

namespace {

/// Restores the kernels in use when it goes out of scope.
struct KernelsGuard {
  LeafKernels before = leaf_kernels();
  ~KernelsGuard() { set_leaf_kernels(before); }
};

/// The face plane value, written out: the octahedral code's halves as signed 16-bit fixed point,
/// folded on the lower hemisphere, dotted with p in order, minus d; 0 without a plane.
float plane_value_spelled_out(const LeafTri& t, const float p[3]) {
  if (t.flags() & kNoPlane) return 0.0f;
  const std::int16_t iu = std::int16_t(t.normal & 0xFFFFu), iv = std::int16_t(t.normal >> 16);
  const float u = float(iu) * (1.0f / 32767.0f), w = float(iv) * (1.0f / 32767.0f);
  const float z = 1.0f - std::fabs(u) - std::fabs(w);
  const float fold = z < 0 ? -z : 0.0f;
  const float x = u < 0 ? u + fold : u - fold, y = w < 0 ? w + fold : w - fold;
  float v = x * p[0];
  v = v + y * p[1];
  v = v + z * p[2];
  return v - t.d;
}

/// The length of the decoded normal, written out.
float normal_length_spelled_out(const LeafTri& t) {
  float v[3];
  decode_face_normal(t.normal, v);
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/// The kernels' promise, written out one triangle at a time.
/// ref_sides: as plane_pass's (kRefSidesFromFlags: the kRefPositive flags).
unsigned plane_mask_spelled_out(const LeafTri* blk, unsigned m, const float p[3], float eps, float s[8],
                                unsigned ref_sides = kRefSidesFromFlags) {
  unsigned mask = 0;
  for (unsigned j = 0; j < m; ++j) {
    const LeafTri& t = blk[j];
    const float v = plane_value_spelled_out(t, p);
    s[j] = v;
    const bool ref_pos = ref_sides == kRefSidesFromFlags ? (t.flags() & kRefPositive) != 0 : (ref_sides >> j & 1u) != 0;
    const bool skip = (t.flags() & kDegenerate) || (ref_pos && v > eps) || (!ref_pos && v < -eps);
    if (!skip) mask |= 1u << j;
  }
  return mask;
}
unsigned box_mask_spelled_out(const LeafTri* blk, unsigned m, const float lo[3], const float hi[3], bool with_degenerate) {
  unsigned mask = 0;
  for (unsigned j = 0; j < m; ++j) {
    const LeafTri& t = blk[j];
    bool meets = with_degenerate || !(t.flags() & kDegenerate);
    for (int a = 0; a < 3; ++a)
      meets = meets && std::max({t.a[a], t.b[a], t.c[a]}) >= lo[a] && std::min({t.a[a], t.b[a], t.c[a]}) <= hi[a];
    if (meets) mask |= 1u << j;
  }
  return mask;
}

/// The triangles of blk[0, m) whose box meets one of the slabs [seam_lo[a], seam_hi[a]] on axis a.
unsigned seam_mask_spelled_out(const LeafTri* blk, unsigned m, const float seam_lo[3], const float seam_hi[3]) {
  unsigned mask = 0;
  for (unsigned j = 0; j < m; ++j) {
    const LeafTri& t = blk[j];
    bool across = false;
    for (int a = 0; a < 3; ++a)
      across = across || (std::max({t.a[a], t.b[a], t.c[a]}) >= seam_lo[a] && std::min({t.a[a], t.b[a], t.c[a]}) <= seam_hi[a]);
    if (across) mask |= 1u << j;
  }
  return mask;
}

unsigned block_mask_spelled_out(const BlockBox* boxes, unsigned m, const float lo[3], const float hi[3]) {
  unsigned mask = 0;
  for (unsigned j = 0; j < m; ++j) {
    bool meets = true;
    for (int a = 0; a < 3; ++a) meets = meets && boxes[j].hi[a] >= lo[a] && boxes[j].lo[a] <= hi[a];
    if (meets) mask |= 1u << j;
  }
  return mask;
}

Mesh reversed(Mesh m) {
  for (auto& f : m.triangles) std::swap(f[1], f[2]);
  return m;
}
Mesh joined(const Mesh& a, const Mesh& b) {
  Mesh m = a;
  const auto off = std::uint32_t(m.vertices.size());
  m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto f : b.triangles) m.triangles.push_back({f[0] + off, f[1] + off, f[2] + off});
  return m;
}

/// Query points that graze the structure: the triangles' vertices exactly, points on their edges
/// and faces, points on leaf-cell boundaries, and a haptic-like walk of small steps over the
/// surface with jumps, besides uniform and near-surface samples.
std::vector<Vec3d> grazing_points(const Octree& t, const Reference& ref, std::uint32_t seed) {
  std::vector<Vec3d> pts = sample_points(ref, 200, 200, seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  const double cell = t.cell_size(t.leaf_level), diag = ref.bounds().diagonal();
  Vec3d p = ref.v[ref.f[0][0]];
  for (int i = 0; i < 1500; ++i) {
    const auto& f = ref.f[rng() % ref.f.size()];
    const Vec3d a = ref.v[f[0]], b = ref.v[f[1]], c = ref.v[f[2]];
    const double u = U(rng), v = U(rng) * (1 - u);
    switch (i % 6) {
      case 0: p = ref.v[f[rng() % 3]]; break;                        // a vertex
      case 1: p = a + (b - a) * u; break;                            // an edge
      case 2: p = a + (b - a) * u + (c - a) * v; break;              // a face
      case 3: {                                                      // a leaf-cell boundary
        const int ax = int(rng() % 3);
        p[ax] = t.root_lo[ax] + std::round((p[ax] - t.root_lo[ax]) / cell) * cell;
        break;
      }
      case 4: p += Vec3d(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5) * (2.5 * cell); break;  // a jump
      default: p += Vec3d(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5) * (1e-3 * diag); break;  // a step
    }
    pts.push_back(p);
  }
  return pts;
}

struct Answers {
  std::vector<char> inside;
  QueryCounters c;
};
Answers run(const Octree& t, bool coherent, LeafKernels k, const std::vector<Vec3d>& pts) {
  KernelsGuard g;
  set_leaf_kernels(k);
  Query q(t, coherent);
  Answers r;
  for (const Vec3d& p : pts) r.inside.push_back(q.inside(p));
  r.c = q.counters;
  return r;
}
std::string counters(const QueryCounters& c) {
  return std::to_string(c.nodes_visited) + " " + std::to_string(c.planes_tested) + " " +
         std::to_string(c.triangles_tested) + " " + std::to_string(c.exact_fallbacks);
}

}  // namespace

// Each kernel gives, on every block of real leaves (full and partial), the bits of the float
// expressions written out: plane values, masks, triangle and block box masks (boxes that touch
// triangle coordinates exactly included), and orient3d's signs for the edge orientations
// (segments from a vertex through another: exact zeros).
TEST(EbpLeafKernels, EachKernelGivesTheSpelledOutBits) {
  KernelsGuard g;
  std::vector<LeafKernels> kinds{LeafKernels::baseline};
  if (cpu_has_avx2()) kinds.push_back(LeafKernels::avx2);
  for (const char* name : {"cow.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    std::mt19937_64 rng(21);
    std::uniform_real_distribution<double> U(-1, 1);
    std::size_t blocks = 0, partial = 0, nonzero = 0, edge_zero = 0, degenerate_met = 0, seam_met = 0, j0 = 0;
    for (const Leaf& lf : t.leaves) {
      const double half = 0.5 * t.cell_size(t.leaf_level);
      for (std::uint32_t k = 0; k < lf.tri_count; k += kBlockTris) {
        const LeafTri* blk = t.tris.data() + lf.tri_begin + k;
        const unsigned n = std::min(lf.tri_count - k, kBlockTris);
        ++blocks;
        partial += n < kBlockTris;
        for (int i = 0; i < 8; ++i) {
          // a point of the cell, or a vertex of the block (its plane value is tiny: the exact stage)
          float p[3], lo[3], hi[3];
          const LeafTri& v = blk[rng() % n];
          for (int a = 0; a < 3; ++a) {
            p[a] = i < 6 ? float(U(rng) * half) : v.a[a] - lf.centre[a];
            lo[a] = i % 2 ? v.b[a] : float(lf.centre[a] + U(rng) * half);
            hi[a] = i % 2 ? v.b[a] : lo[a] + float(0.3 * half);
          }
          float want_s[8], s[8];
          const unsigned want = plane_mask_spelled_out(blk, n, p, lf.eps, want_s);
          const unsigned sides = unsigned(rng() & 0xFF);  // a sub-reference's sides, any
          float want_s2[8], s2[8];
          const unsigned want_sides = plane_mask_spelled_out(blk, n, p, lf.eps, want_s2, sides);
          // the block again with some triangles flagged zero-area (the meshes have none): the box
          // pass leaves them out unless asked for them
          LeafTri flagged[kBlockTris];
          std::copy(blk, blk + n, flagged);
          const unsigned deg_mask = unsigned(rng() & 0xFF);
          for (unsigned j = 0; j < n; ++j)
            if (deg_mask >> j & 1u) flagged[j].tri_flags |= kDegenerate;
          const unsigned want_box[2] = {box_mask_spelled_out(flagged, n, lo, hi, false),
                                        box_mask_spelled_out(flagged, n, lo, hi, true)};
          degenerate_met += want_box[0] != want_box[1];
          // a seam slab on one axis, through the box (GatherTest); none on the others
          float seam_lo[3], seam_hi[3];
          const int seam_axis = int(rng() % 3);
          for (int a = 0; a < 3; ++a) {
            seam_lo[a] = a == seam_axis ? lo[a] + 0.4f * (hi[a] - lo[a]) : std::numeric_limits<float>::infinity();
            seam_hi[a] = a == seam_axis ? lo[a] + 0.6f * (hi[a] - lo[a]) : -std::numeric_limits<float>::infinity();
          }
          const unsigned want_seam = seam_mask_spelled_out(flagged, n, seam_lo, seam_hi);
          seam_met += (want_box[1] & want_seam) != 0 && (want_box[1] & ~want_seam) != 0;
          nonzero += want != 0;
          const unsigned nb = std::min(block_count(lf.tri_count - k), 8u);
          const BlockBox* boxes = t.blocks.data() + t.leaf_block[&lf - t.leaves.data()] + k / kBlockTris;
          const unsigned want_blocks = block_mask_spelled_out(boxes, nb, lo, hi);
          // a segment from a vertex of the block (often through its edges: exact ties)
          const Vec3d sp = to_d(v.a), sq = i < 4 ? to_d(v.c) : Vec3d(lf.centre[0] + U(rng) * half, lf.centre[1] + U(rng) * half,
                                                                      lf.centre[2] + U(rng) * half);
          const LeafTri& e = blk[(j0++) % n];
          // squared distances from a double point (of the cell, or a corner of a block box: zero
          // gaps) to all the leaf's block boxes (any count: a tail of fewer than four)
          const std::uint32_t nall = block_count(lf.tri_count);
          const BlockBox* all = t.blocks.data() + t.leaf_block[&lf - t.leaves.data()];
          const BlockBox& corner = all[rng() % nall];
          const double pd[3] = {i < 6 ? lf.centre[0] + U(rng) * 2 * half : double(corner.lo[0]),
                                i < 6 ? lf.centre[1] + U(rng) * 2 * half : double(corner.hi[1]),
                                i < 6 ? lf.centre[2] + U(rng) * 2 * half : double(corner.lo[2]) + 0.25 * half};
          std::vector<double> want_d2(nall), d2(nall);
          for (std::uint32_t b = 0; b < nall; ++b) {
            double sum = 0;
            for (int a = 0; a < 3; ++a) {
              const double gap = std::max(std::max(double(all[b].lo[a]) - pd[a], 0.0), pd[a] - double(all[b].hi[a]));
              sum += gap * gap;
            }
            want_d2[b] = sum;
          }
          const int want_e[3] = {orient3d(sp, sq, to_d(e.a), to_d(e.b)), orient3d(sp, sq, to_d(e.b), to_d(e.c)),
                                 orient3d(sp, sq, to_d(e.c), to_d(e.a))};
          for (LeafKernels kind : kinds) {
            set_leaf_kernels(kind);
            ASSERT_EQ(leaf_kernels(), kind);
            const LeafKernelTable& K = leaf_kernel_table();
            ASSERT_EQ(K.kind, kind);
            ASSERT_EQ(K.plane_pass(blk, n, p, lf.eps, s, kRefSidesFromFlags), want) << name << " kernel " << int(kind);
            ASSERT_EQ(0, std::memcmp(s, want_s, n * sizeof(float))) << name << " kernel " << int(kind);
            ASSERT_EQ(K.plane_pass(blk, n, p, lf.eps, s2, sides), want_sides) << name << " kernel " << int(kind);
            ASSERT_EQ(0, std::memcmp(s2, want_s2, n * sizeof(float))) << name << " kernel " << int(kind);
            for (const bool with_degenerate : {false, true}) {
              GatherTest gt;
              for (int a = 0; a < 3; ++a) {
                gt.lo[a] = lo[a];
                gt.hi[a] = hi[a];
                gt.seam_lo[a] = seam_lo[a];
                gt.seam_hi[a] = seam_hi[a];
              }
              gt.with_degenerate = with_degenerate;
              BlockTriBoxes tb;
              unsigned on_seam = ~0u;
              const unsigned got = K.box_pass(flagged, n, gt, tb, &on_seam);
              ASSERT_EQ(got, want_box[with_degenerate])
                  << name << " kernel " << int(kind) << " with_degenerate " << with_degenerate;
              ASSERT_EQ(on_seam, got & want_seam) << name << " kernel " << int(kind);
              for (unsigned j = 0; j < n; ++j)  // each triangle's box: the min and max of its vertices
                for (int a = 0; a < 3; ++a) {
                  const LeafTri& f = flagged[j];
                  ASSERT_EQ(tb.lo[a][j], std::min({f.a[a], f.b[a], f.c[a]})) << name << " kernel " << int(kind);
                  ASSERT_EQ(tb.hi[a][j], std::max({f.a[a], f.b[a], f.c[a]})) << name << " kernel " << int(kind);
                }
              // the kept triangles appended at slot `at`, in lane order; the slots before it untouched
              const std::uint32_t at = std::uint32_t(rng() % 9);
              alignas(32) float clo[3][24], chi[3][24];
              std::uint32_t ck[24], cleaf[24], cnode[24];
              for (int a = 0; a < 3; ++a) {
                std::fill(clo[a], clo[a] + 24, -1.0f);
                std::fill(chi[a], chi[a] + 24, -1.0f);
              }
              std::fill(ck, ck + 24, 7u);
              const MemberColumns cols{{clo[0], clo[1], clo[2]}, {chi[0], chi[1], chi[2]}, ck, cleaf, cnode, 24u};
              const std::uint32_t first = lf.tri_begin + k;
              ASSERT_EQ(K.append_members(tb, got, first, 11u, 13u, cols, at), std::uint32_t(__builtin_popcount(got)))
                  << name << " kernel " << int(kind);
              for (std::uint32_t i = 0; i < at; ++i) ASSERT_EQ(ck[i], 7u) << name << " kernel " << int(kind);
              std::uint32_t slot = at;
              for (unsigned j = 0; j < n; ++j) {
                if (!(got >> j & 1u)) continue;
                ASSERT_EQ(ck[slot], first + j) << name << " kernel " << int(kind);
                ASSERT_EQ(cleaf[slot], 11u);
                ASSERT_EQ(cnode[slot], 13u);
                for (int a = 0; a < 3; ++a) {
                  ASSERT_EQ(clo[a][slot], tb.lo[a][j]) << name << " kernel " << int(kind);
                  ASSERT_EQ(chi[a][slot], tb.hi[a][j]) << name << " kernel " << int(kind);
                }
                ++slot;
              }
              // columns that end two slots past `at`: the count still, and nothing written past the end
              std::fill(ck, ck + 24, 7u);
              const MemberColumns shortcols{{clo[0], clo[1], clo[2]}, {chi[0], chi[1], chi[2]}, ck, cleaf, cnode, at + 2};
              ASSERT_EQ(K.append_members(tb, got, first, 11u, 13u, shortcols, at), std::uint32_t(__builtin_popcount(got)))
                  << name << " kernel " << int(kind);
              for (std::uint32_t i = 0; i < 24; ++i) {
                if (i < at || i >= at + std::min(2u, unsigned(__builtin_popcount(got)))) {
                  ASSERT_EQ(ck[i], 7u) << name << " kernel " << int(kind) << " slot " << i;
                }
              }
            }
            ASSERT_EQ(K.block_pass(boxes, nb, lo, hi), want_blocks) << name << " kernel " << int(kind);
            K.box_distances(all, nall, Vec3d(pd[0], pd[1], pd[2]), d2.data());
            ASSERT_EQ(0, std::memcmp(d2.data(), want_d2.data(), nall * sizeof(double))) << name << " kernel " << int(kind);
            const unsigned es = K.edge_signs(sp, sq, e.a, e.b, e.c);
            for (int i = 0; i < 3; ++i)
              ASSERT_EQ(int(es >> i & 1u) - int(es >> (4 + i) & 1u), want_e[i]) << name << " kernel " << int(kind);
            edge_zero += ((es | es >> 4) & 7u) != 7u;
          }
        }
      }
    }
    EXPECT_GT(partial, 10u) << name;
    EXPECT_GT(edge_zero, 100u) << name;  // segments through vertices: the exact fallback ran
    EXPECT_GT(nonzero, blocks) << name;
    EXPECT_GT(degenerate_met, 100u) << name;  // flagged triangles in the box: the two modes differ
    EXPECT_GT(seam_met, 20u) << name;  // blocks with kept triangles on and off the seam
  }
  if (!cpu_has_avx2()) GTEST_SKIP() << "no AVX2 on this CPU: the baseline kernel alone was checked";
}

// The distance pre-filter: both kernels give the same mask, and a triangle it clears is strictly
// farther than the best it was given (exact closest point in double), for points in and around
// the leaf, on vertices, and bests from 0 to beyond the block's nearest triangle.
TEST(EbpLeafKernels, DistancePrefilterClearsOnlyTrianglesFartherThanTheBest) {
  KernelsGuard g;
  std::vector<LeafKernels> kinds{LeafKernels::baseline};
  if (cpu_has_avx2()) kinds.push_back(LeafKernels::avx2);
  std::size_t cleared = 0, kept = 0;
  for (const char* name : {"cow.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    std::mt19937_64 rng(23);
    std::uniform_real_distribution<double> U(-1.5, 1.5);
    for (const Leaf& lf : t.leaves) {
      const double half = 0.5 * t.cell_size(t.leaf_level);
      for (std::uint32_t k = 0; k < lf.tri_count; k += kBlockTris) {
        const LeafTri* blk = t.tris.data() + lf.tri_begin + k;
        const unsigned n = std::min(lf.tri_count - k, kBlockTris);
        for (int i = 0; i < 4; ++i) {
          const Vec3d c = to_d(lf.centre);
          const Vec3d q = i < 3 ? c + Vec3d(U(rng), U(rng), U(rng)) * half : to_d(blk[rng() % n].b);
          double d[8], nearest = std::numeric_limits<double>::infinity();
          for (unsigned j = 0; j < n; ++j) {
            d[j] = norm(bvhbench::closest_point_on_triangle(q, to_d(blk[j].a), to_d(blk[j].b), to_d(blk[j].c)) - q);
            nearest = std::min(nearest, d[j]);
          }
          // p in the leaf's frame and eps_p as the distance search computes them
          const float p[3] = {float(q.x - double(lf.centre[0])), float(q.y - double(lf.centre[1])),
                              float(q.z - double(lf.centre[2]))};
          const double eps_p = double(lf.eps) + 1e-6 * (double(std::fabs(p[0])) + double(std::fabs(p[1])) +
                                                        double(std::fabs(p[2])));
          float q_lo[3], q_hi[3];
          for (int a = 0; a < 3; ++a) float_bounds(q[a], &q_lo[a], &q_hi[a]);
          for (double best : {0.0, 0.5 * nearest, nearest, 1.5 * nearest + 0.1 * half}) {
            float plane_lim, box_lim;
            distance_prefilter_limits(best, best * best, eps_p, &plane_lim, &box_lim);
            unsigned first = 0;
            float first_plane[8], first_box[8];
            for (LeafKernels kind : kinds) {
              set_leaf_kernels(kind);
              float plane_abs[8], box_d2[8];
              const unsigned mask =
                  leaf_kernel_table().distance_pass(blk, n, p, q_lo, q_hi, plane_lim, box_lim, plane_abs, box_d2);
              if (kind == kinds.front()) {
                first = mask;
                std::memcpy(first_plane, plane_abs, sizeof plane_abs);
                std::memcpy(first_box, box_d2, sizeof box_d2);
              }
              ASSERT_EQ(mask, first) << name << ": the kernels differ";
              ASSERT_EQ(mask & ~((1u << n) - 1u), 0u);
              for (unsigned j = 0; j < n; ++j) {
                ASSERT_EQ(std::memcmp(&plane_abs[j], &first_plane[j], 4), 0) << name << ": the plane values differ";
                ASSERT_EQ(std::memcmp(&box_d2[j], &first_box[j], 4), 0) << name << ": the box distances differ";
                // the values the mask was decided on, as the per-triangle tests read them
                ASSERT_EQ(bool(mask >> j & 1u), !(plane_abs[j] > plane_lim) && !(box_d2[j] > box_lim)) << name;
                const float s = std::fabs(plane_value_spelled_out(blk[j], p)) / normal_length_spelled_out(blk[j]);
                ASSERT_EQ(plane_abs[j], s) << name;
              }
            }
            for (unsigned j = 0; j < n; ++j) {
              if (first >> j & 1u) {
                ++kept;
              } else {
                ++cleared;
                ASSERT_GT(d[j], best) << name << ": cleared a triangle within the best";
              }
            }
          }
        }
      }
    }
  }
  EXPECT_GT(cleared, kept / 4);  // the filter does clear (the test is not vacuous)
  EXPECT_GT(kept, 0u);
  if (!cpu_has_avx2()) GTEST_SKIP() << "no AVX2 on this CPU: the baseline kernel alone was checked";
}

TEST(EbpLeafKernels, FloatBoundsAreTheNearestFloatsOutwards) {
  // float_bounds steps on the float's bits: the same as std::nextafter towards -+infinity where
  // rounding went the other way, at zero, subnormals, the largest finite float and beyond.
  const float fmax = std::numeric_limits<float>::max(), tiny = std::numeric_limits<float>::denorm_min();
  std::vector<double> xs = {0.0, -0.0, 1e-300, -1e-300, 1e-45, -1e-45, double(tiny), 0.1, -0.1, 1.0 / 3,
                            -1.0 / 3, 1e30, -1e30, double(fmax), double(fmax) * (1 + 1e-12), -double(fmax) * 1.5,
                            1e300, -1e300, std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity()};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 2000; ++i) xs.push_back(u(rng) * std::pow(10.0, int(rng() % 80) - 40));
  const float inf = std::numeric_limits<float>::infinity();
  for (double x : xs) {
    float lo, hi;
    float_bounds(x, &lo, &hi);
    const float f = float(x);
    const float want_lo = double(f) > x ? std::nextafter(f, -inf) : f;
    const float want_hi = double(f) < x ? std::nextafter(f, inf) : f;
    EXPECT_EQ(std::memcmp(&lo, &want_lo, 4), 0) << x;
    EXPECT_EQ(std::memcmp(&hi, &want_hi, 4), 0) << x;
    EXPECT_LE(double(lo), x);
    EXPECT_GE(double(hi), x);
  }
}

// float_bounds_near, the branch-free bounds about a query point: lo <= x <= hi always, at most
// three floats outside float_bounds' tightest ones, on the same values.
TEST(EbpLeafKernels, NearFloatBoundsHoldTheValueWithinThreeFloats) {
  const float fmax = std::numeric_limits<float>::max(), tiny = std::numeric_limits<float>::denorm_min();
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<double> xs = {0.0, -0.0, 1e-300, -1e-300, 1e-45, -1e-45, double(tiny), -double(tiny), 1e-40, 0.1,
                            -0.1, 1.0 / 3, -1.0 / 3, 1.0, 1e30, -1e30, double(fmax), -double(fmax),
                            double(fmax) * (1 + 1e-12), -double(fmax) * 1.5, 1e300, -1e300,
                            std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 20000; ++i) xs.push_back(u(rng) * std::pow(10.0, int(rng() % 90) - 45));
  for (int i = 0; i < 2000; ++i) xs.push_back(double(float(u(rng))));  // floats themselves
  std::size_t looser = 0;
  for (double x : xs) {
    float lo, hi, tight_lo, tight_hi;
    float_bounds_near(x, &lo, &hi);
    float_bounds(x, &tight_lo, &tight_hi);
    ASSERT_LE(double(lo), x) << x;
    ASSERT_GE(double(hi), x) << x;
    float floor = tight_lo, ceiling = tight_hi;
    for (int step = 0; step < 3; ++step) {
      floor = std::nextafter(floor, -inf);
      ceiling = std::nextafter(ceiling, inf);
    }
    ASSERT_GE(lo, floor) << x;
    ASSERT_LE(hi, ceiling) << x;
    looser += lo != tight_lo || hi != tight_hi;
  }
  EXPECT_GT(looser, xs.size() / 4);  // it is the cheaper bound, not float_bounds again
}

// The near set's pre-filter kernel: every kernel gives the spelled-out box values, bit for bit,
// over whole columns (the padding's empty boxes included) and the same mask, with no bit at or
// beyond n, for set sizes from 0 to 64, query boxes inside, touching and away from the boxes,
// and limits from 0 to beyond every value.
TEST(EbpLeafKernels, ColumnBoxPassGivesTheSpelledOutBits) {
  KernelsGuard g;
  std::vector<LeafKernels> kinds{LeafKernels::baseline};
  if (cpu_has_avx2()) kinds.push_back(LeafKernels::avx2);
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<float> U(-1, 1);
  alignas(32) float lo[3][64], hi[3][64];
  std::size_t within = 0, outside = 0;
  for (std::uint32_t n : {0u, 1u, 3u, 7u, 8u, 9u, 31u, 33u, 63u, 64u}) {
    for (int round = 0; round < 50; ++round) {
      const std::uint32_t padded = (n + 7) / 8 * 8;
      for (std::uint32_t j = 0; j < 64; ++j)
        for (int a = 0; a < 3; ++a) {
          const float x = U(rng), y = U(rng);
          lo[a][j] = j < n ? std::min(x, y) : std::numeric_limits<float>::infinity();
          hi[a][j] = j < n ? std::max(x, y) : -std::numeric_limits<float>::infinity();
        }
      float q_lo[3], q_hi[3];
      for (int a = 0; a < 3; ++a) {
        // a point box, or a box corner (a zero gap on that axis), or a wider box
        const float c = (round % 3 == 1 && n > 0) ? hi[a][rng() % n] : U(rng) * 1.5f;
        q_lo[a] = c;
        q_hi[a] = round % 3 == 2 ? c + 0.1f : c;
      }
      float want[64];
      for (std::uint32_t j = 0; j < padded; ++j) {
        float sum = 0;
        for (int a = 0; a < 3; ++a) {
          const float gap = std::max(std::max(lo[a][j] - q_hi[a], q_lo[a] - hi[a][j]), 0.0f);
          sum = sum + gap * gap;
        }
        want[j] = sum;
      }
      const float median = n > 0 ? want[rng() % n] : 0.0f;
      for (float box_lim : {0.0f, median, std::numeric_limits<float>::max()}) {
        std::uint64_t want_mask = 0;
        for (std::uint32_t j = 0; j < n; ++j)
          if (want[j] <= box_lim) want_mask |= std::uint64_t(1) << j;
        within += std::uint64_t(__builtin_popcountll(want_mask));
        outside += n - std::uint64_t(__builtin_popcountll(want_mask));
        const float* const L[3] = {lo[0], lo[1], lo[2]};
        const float* const H[3] = {hi[0], hi[1], hi[2]};
        for (LeafKernels kind : kinds) {
          set_leaf_kernels(kind);
          float g2[64];
          std::fill(g2, g2 + 64, -1.0f);
          ASSERT_EQ(leaf_kernel_table().column_box_pass(L, H, n, q_lo, q_hi, box_lim, g2), want_mask)
              << "kernel " << int(kind) << " n " << n;
          ASSERT_EQ(0, std::memcmp(g2, want, padded * sizeof(float))) << "kernel " << int(kind) << " n " << n;
        }
      }
    }
  }
  EXPECT_GT(within, 1000u);
  EXPECT_GT(outside, 1000u);
  if (!cpu_has_avx2()) GTEST_SKIP() << "no AVX2 on this CPU: the baseline kernel alone was checked";
}

// The near start's exact tests, four at a time: every kernel gives closest_point_on_triangle's
// point and squared distance bit for bit, in every one of its cases (vertices, edges, the face),
// on the meshes' triangles, slivers and collapsed triangles, for points near and on them, for any
// batch size and position in the batch; a point with no value gives none.
TEST(EbpLeafKernels, ClosestPointsGiveTheScalarBits) {
  KernelsGuard g;
  std::vector<LeafKernels> kinds{LeafKernels::baseline};
  if (cpu_has_avx2()) kinds.push_back(LeafKernels::avx2);
  std::vector<LeafTri> tris;
  for (const char* name : {"cow.obj", "fandisk.obj"}) {
    const Octree t = build(bvhbench::load_mesh(shared_mesh(name)));
    for (std::size_t k = 0; k < t.tris.size(); k += 7) tris.push_back(t.tris[k]);
  }
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<float> U(-1, 1);
  auto with_vertices = [](LeafTri t, const float a[3], const float b[3], const float c[3]) {
    std::copy(a, a + 3, t.a);
    std::copy(b, b + 3, t.b);
    std::copy(c, c + 3, t.c);
    return t;
  };
  for (int i = 0; i < 2000; ++i) {  // slivers, collinear and collapsed triangles
    const float a[3] = {U(rng), U(rng), U(rng)}, b[3] = {U(rng), U(rng), U(rng)};
    float mid[3], near_mid[3];
    for (int k = 0; k < 3; ++k) {
      mid[k] = 0.5f * (a[k] + b[k]);
      near_mid[k] = mid[k] + (k == 0 ? 1e-6f : 0.0f);
    }
    const LeafTri& base = tris[rng() % tris.size()];
    tris.push_back(with_vertices(base, a, b, i % 3 == 0 ? a : i % 3 == 1 ? mid : near_mid));
    tris.push_back(with_vertices(base, a, a, a));
  }
  std::size_t features[7] = {}, zero_area = 0;
  for (std::size_t n = 0; n < 60000; ++n) {
    const unsigned m = 1 + unsigned(rng() % 4);
    const LeafTri* batch[4];
    for (unsigned i = 0; i < m; ++i) batch[i] = &tris[rng() % tris.size()];
    // p: near the first triangle (a random offset from a point of it, on a vertex, on an edge's
    // midpoint, or on its plane), or anywhere
    const LeafTri& t0 = *batch[0];
    const Vec3d a = to_d(t0.a), b = to_d(t0.b), c = to_d(t0.c);
    const double scale = std::sqrt(squared_norm(b - a)) + 1e-3;
    const int kind = int(n % 6);
    Vec3d p = kind == 0 ? a : kind == 1 ? (a + b) * 0.5 : kind == 2 ? (a + b + c) / 3.0 : Vec3d(U(rng), U(rng), U(rng));
    if (kind == 2 || kind == 3) p = p + Vec3d(U(rng), U(rng), U(rng)) * scale;
    // a point with no value, which passes no case of the scalar's (every comparison is false) and
    // takes its fall-back: the kernels must give no value either (only values beyond the doubles
    // reach the fall-back; zero-area triangles with finite points all meet an earlier case)
    if (kind == 5) p = Vec3d(std::numeric_limits<double>::quiet_NaN(), U(rng), U(rng));
    Vec3d want_q[4];
    double want_d2[4];
    for (unsigned i = 0; i < m; ++i) {
      bvhbench::TriangleFeature f;
      want_q[i] = bvhbench::closest_point_on_triangle(p, to_d(batch[i]->a), to_d(batch[i]->b), to_d(batch[i]->c), &f);
      want_d2[i] = squared_norm(want_q[i] - p);
      ++features[int(f)];
      const Vec3d ab = to_d(batch[i]->b) - to_d(batch[i]->a), ac = to_d(batch[i]->c) - to_d(batch[i]->a);
      zero_area += squared_norm(bvhbench::cross(ab, ac)) == 0;
    }
    for (LeafKernels kind_used : kinds) {
      set_leaf_kernels(kind_used);
      Vec3d q[4];
      double d2[4];
      leaf_kernel_table().closest_points(p, batch, m, q, d2);
      for (unsigned i = 0; i < m; ++i) {
        if (kind == 5) {
          ASSERT_TRUE(std::isnan(want_d2[i]));
          ASSERT_TRUE(std::isnan(d2[i])) << "kernel " << int(kind_used) << " lane " << i;
          continue;
        }
        ASSERT_EQ(0, std::memcmp(&q[i], &want_q[i], sizeof(Vec3d))) << "kernel " << int(kind_used) << " lane " << i;
        ASSERT_EQ(0, std::memcmp(&d2[i], &want_d2[i], sizeof(double))) << "kernel " << int(kind_used) << " lane " << i;
      }
    }
  }
  for (int f = 0; f < 7; ++f) EXPECT_GT(features[f], 100u) << "feature " << f << " not exercised";
  EXPECT_GT(zero_area, 1000u);
  if (!cpu_has_avx2()) GTEST_SKIP() << "no AVX2 on this CPU: the baseline kernel alone was checked";
}

// Inside answers and every counter are the same with either kernel, coherent or not, on closed
// meshes, an open one, and stress-style meshes (duplicated faces, zero-area faces, nested shells
// of both orientations); off the surface the answers are the oracle's on the closed ones.
TEST(EbpLeafKernels, InsideIsTheSameWithEitherKernel) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (const char* name : {"cow.obj", "fandisk.obj", "rocker-arm.obj", "spot.obj"})
    meshes.push_back({name, bvhbench::load_mesh(shared_mesh(name))});
  Mesh dup = icosphere(3);
  for (std::size_t i = 0, nf = dup.triangles.size(); i < nf; i += 3) dup.triangles.push_back(dup.triangles[i]);
  meshes.push_back({"duplicated faces", dup});
  Mesh zero = icosphere(3);
  zero.triangles.push_back({0, 0, 0});
  zero.triangles.push_back({1, 2, 1});
  meshes.push_back({"zero-area faces", zero});
  meshes.push_back({"nested shells", joined(icosphere(3, 1.0), icosphere(3, 0.5))});
  meshes.push_back({"hollow shell", joined(icosphere(3, 1.0), reversed(icosphere(3, 0.5)))});
  const bool avx2 = cpu_has_avx2();
  for (auto& [name, m] : meshes) {
    const Octree t = build(m);
    const Reference ref(m.vertices, m.triangles);
    const double diag = ref.bounds().diagonal();
    const std::vector<Vec3d> pts = grazing_points(t, ref, 5);
    std::vector<int> oracle(pts.size(), -1);  // -1: on (or all but on) the surface, or open
    if (t.closed)
      for (std::size_t i = 0; i < pts.size(); ++i)
        if (ref.dist(pts[i]) >= 1e-7 * diag) oracle[i] = ref.winding(pts[i]) > 0.5;
    if (name != "spot.obj" && name != "duplicated faces") {
      ASSERT_TRUE(t.closed) << name;  // then the oracle applies
    }
    if (t.closed) {
      EXPECT_GT(std::count_if(oracle.begin(), oracle.end(), [](int o) { return o >= 0; }), 500) << name;
    }
    for (bool coherent : {false, true}) {
      const Answers base = run(t, coherent, LeafKernels::baseline, pts);
      if (avx2) {
        const Answers fast = run(t, coherent, LeafKernels::avx2, pts);
        ASSERT_TRUE(base.inside == fast.inside) << name << " coherent " << coherent;
        EXPECT_EQ(counters(base.c), counters(fast.c)) << name << " coherent " << coherent;
      }
      for (std::size_t i = 0; i < pts.size(); ++i)
        if (oracle[i] >= 0) {
          ASSERT_EQ(int(base.inside[i]), oracle[i]) << name << " coherent " << coherent << " point " << i;
        }
    }
  }
}
