// Exact point-in-solid (Query::inside): the leaf holding the point (Query::locate), its colour if empty, else
// the winding number by signed segment crossings from the leaf's reference point (DESIGN.md,
// "Inside"), or, on a coherent path over a closed mesh, from the previous point.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/leaf_kernels.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/core/reference_points.hpp"

namespace ebp {


// Point location by octcode descent, with the coherent shortcut (the previous point's node when
// p is in its cell). In this file so that the compiler can inline it into inside().
std::uint32_t Query::locate(const Vec3d& p, bool* outside_root) {
  const double inv = double(std::uint64_t(1) << t_.leaf_level) / t_.root_size;
  const double G = double(std::uint64_t(1) << t_.leaf_level);
  const double rx = (p.x - t_.root_lo.x) * inv, ry = (p.y - t_.root_lo.y) * inv, rz = (p.z - t_.root_lo.z) * inv;
  if (!(rx >= 0 && ry >= 0 && rz >= 0 && rx <= G && ry <= G && rz <= G)) {
    *outside_root = true;
    return UINT32_MAX;
  }
  *outside_root = false;
  const std::uint32_t gmax = (1u << t_.leaf_level) - 1;
  const std::uint32_t x = std::min(std::uint32_t(rx), gmax), y = std::min(std::uint32_t(ry), gmax),
                      z = std::min(std::uint32_t(rz), gmax);
  if (coherent_ && last_node_ != UINT32_MAX) {
    const int sh = t_.leaf_level - last_level_;
    if ((x >> sh) == last_cell_[0] && (y >> sh) == last_cell_[1] && (z >> sh) == last_cell_[2]) {
      ++counters.nodes_visited;
      return last_node_;
    }
  }
  std::uint32_t i = 0;
  const Node* nodes = t_.nodes.data();
  const std::uint32_t* ch = t_.children.data();
  int level = 0;
  ++counters.nodes_visited;
  while (nodes[i].kind == NodeKind::inner) {
    const int shift = t_.leaf_level - level - 1;
    const std::uint32_t o = ((x >> shift) & 1u) | (((y >> shift) & 1u) << 1) | (((z >> shift) & 1u) << 2);
    i = ch[nodes[i].index + o];
    ++level;
    ++counters.nodes_visited;
  }
  if (coherent_) {
    last_node_ = i;
    last_level_ = level;
    const int sh = t_.leaf_level - level;
    last_cell_[0] = x >> sh;
    last_cell_[1] = y >> sh;
    last_cell_[2] = z >> sh;
  }
  return i;
}

bool Query::inside(const Vec3d& p) {
  bool outside_root;
  const std::uint32_t i = locate(p, &outside_root);
  if (outside_root) {
    ++counters.hit_white;
    return false;
  }
  const Node& nd = t_.nodes[i];
  switch (nd.kind) {
    case NodeKind::white: ++counters.hit_white; return false;
    case NodeKind::black: ++counters.hit_black; return true;
    default: break;
  }
  switch (nd.config) {
    case LeafConfig::convex: ++counters.hit_convex; break;
    case LeafConfig::concave: ++counters.hit_concave; break;
    default: ++counters.hit_special; break;
  }
  return classify_leaf(p, t_.leaves[nd.index], nd.index, i);
}

namespace {

/// Winding-number change w(p) - w(q) along q -> p over the leaf's triangles. `q_side(k)` gives
/// the exact side (+1 / -1, never 0) of q for triangle k. The float planes filter p's side; ties
/// go to the exact predicate. Returns false when p is on a triangle (*on_surface) or the segment
/// is degenerate (through an edge or a vertex).
template <class QSide>
bool leaf_winding(const Vec3d& p, const Vec3d& q, const LeafTri* blk, std::uint32_t n, const Leaf& lf,
                  QSide&& q_side, QueryCounters& cnt, int* delta, bool* on_surface) {
  const float pl[3] = {float(p.x - double(lf.centre[0])), float(p.y - double(lf.centre[1])),
                       float(p.z - double(lf.centre[2]))};
  const float eps = lf.eps;
  // The segment's bounding box: a triangle whose box misses it cannot be crossed (exact
  // comparisons of exact values, so this filter never changes an answer).
  const double sx0 = std::min(p.x, q.x), sx1 = std::max(p.x, q.x), sy0 = std::min(p.y, q.y),
               sy1 = std::max(p.y, q.y), sz0 = std::min(p.z, q.z), sz1 = std::max(p.z, q.z);
  int w = 0;
  cnt.planes_tested += n;
  for (std::uint32_t k = 0; k < n; ++k) {
    const LeafTri& t = blk[k];
    if (t.flags() & kDegenerate) continue;
    const float s = face_plane_value(t, pl);
    const int sq = q_side(k);
    int sp;
    if (s > eps) sp = 1;
    else if (s < -eps) sp = -1;
    else sp = orient3d(to_d(t.a), to_d(t.b), to_d(t.c), p);
    if (sp == sq) continue;
    ++cnt.triangles_tested;
    if (double(std::max({t.a[0], t.b[0], t.c[0]})) < sx0 || double(std::min({t.a[0], t.b[0], t.c[0]})) > sx1 ||
        double(std::max({t.a[1], t.b[1], t.c[1]})) < sy0 || double(std::min({t.a[1], t.b[1], t.c[1]})) > sy1 ||
        double(std::max({t.a[2], t.b[2], t.c[2]})) < sz0 || double(std::min({t.a[2], t.b[2], t.c[2]})) > sz1)
      continue;
    switch (segment_triangle(p, q, sp, sq, to_d(t.a), to_d(t.b), to_d(t.c))) {
      case Cross::none: break;
      case Cross::proper: w += sq > 0 ? 1 : -1; break;  // q outer -> p inner: entering
      case Cross::on_p: *on_surface = true; return false;
      case Cross::degenerate: return false;
    }
  }
  *delta = w;
  return true;
}

/// leaf_winding from a reference point q of the leaf, block by block: the leaf's own (its side
/// of triangle k is the kRefPositive bit; `q_sides` null) or one of its sub-references (its
/// sides are q_sides[8 b] for block b, sub_references.hpp): a block of kBlockTris triangles whose box misses the segment's box
/// (rounded outwards to float: conservative) holds no triangle the segment can cross or touch,
/// nor p, so it is skipped whole; in the others the plane pass (leaf_kernels.hpp) gives the
/// float plane values, bit for bit those of the scalar expression, and the triangles that the
/// scalar loop would not skip at once (degenerate, or float side equal to the reference's)
/// go on, one at a time, in leaf order, reusing the plane value. Same decisions as leaf_winding
/// with that q_side on the triangles of the blocks that meet the segment.
bool leaf_winding_ref(const Vec3d& p, const Vec3d& q, const LeafTri* blk, std::uint32_t n, const Leaf& lf,
                      const BlockBox* boxes, const std::uint8_t* q_sides, QueryCounters& cnt, int* delta,
                      bool* on_surface) {
  const float pl[3] = {float(p.x - double(lf.centre[0])), float(p.y - double(lf.centre[1])),
                       float(p.z - double(lf.centre[2]))};
  const float eps = lf.eps;
  float f0[3], f1[3];  // the segment's box, rounded outwards to float
  for (int a = 0; a < 3; ++a) {
    f0[a] = float_down_near(std::min(p[a], q[a]));
    f1[a] = float_up_near(std::max(p[a], q[a]));
  }
#if defined(__SSE2__)
  // Lane 3 of the triangle's vertex rows below is not a coordinate and always passes.
  const __m128 SLO = _mm_setr_ps(f0[0], f0[1], f0[2], -std::numeric_limits<float>::infinity());
  const __m128 SHI = _mm_setr_ps(f1[0], f1[1], f1[2], std::numeric_limits<float>::infinity());
#endif
  const LeafKernelTable& K = leaf_kernel_table();
  int w = 0;
  // 1: go on, 0: stop (on the surface or degenerate segment). s: the float plane value.
  auto one = [&](std::uint32_t k, float s, int sq) {
    const LeafTri& t = blk[k];
    int sp;
    if (s > eps) sp = 1;
    else if (s < -eps) sp = -1;
    else sp = orient3d(to_d(t.a), to_d(t.b), to_d(t.c), p);
    if (sp == sq) return 1;
    ++cnt.triangles_tested;
#if defined(__SSE2__)
    static_assert(offsetof(LeafTri, b) == 12 && offsetof(LeafTri, c) == 24 && offsetof(LeafTri, normal) == 36,
                  "a, b, c, normal contiguous: 16-byte loads at a, b, c stay in the record");
    const __m128 A = _mm_loadu_ps(t.a), B = _mm_loadu_ps(t.b), C = _mm_loadu_ps(t.c);
    const __m128 lo = _mm_min_ps(_mm_min_ps(A, B), C), hi = _mm_max_ps(_mm_max_ps(A, B), C);
    if (_mm_movemask_ps(_mm_or_ps(_mm_cmplt_ps(hi, SLO), _mm_cmpgt_ps(lo, SHI))) != 0) return 1;
#else
    for (int a = 0; a < 3; ++a)
      if (std::max({t.a[a], t.b[a], t.c[a]}) < f0[a] || std::min({t.a[a], t.b[a], t.c[a]}) > f1[a]) return 1;
#endif
    // segment_triangle (predicates.hpp), its three edge orientations from the kernel
    const unsigned e = K.edge_signs(p, q, t.a, t.b, t.c), pos = e & 7u, neg = e >> 4;
    if (pos && neg) return 1;  // misses
    if (sp == 0) { *on_surface = true; return 0; }
    if ((pos | neg) != 7u) return 0;  // through an edge or a vertex
    w += sq > 0 ? 1 : -1;  // a proper crossing: q outer -> p inner is entering
    return 1;
  };
  const std::uint32_t nb = block_count(n);
  for (std::uint32_t b0 = 0; b0 < nb; b0 += 8) {
    const unsigned mb = std::min(nb - b0, 8u);
    cnt.planes_tested += mb;  // the blocks' boxes
    for (unsigned hit = K.block_pass(boxes + b0, mb, f0, f1); hit; hit &= hit - 1) {
      const std::uint32_t b = b0 + unsigned(__builtin_ctz(hit)), k = b * kBlockTris;
      const unsigned m = std::min(n - k, kBlockTris);
      cnt.planes_tested += m;
      float s[kBlockTris];
      const unsigned sides = q_sides ? q_sides[8 * b] : kRefSidesFromFlags;
      for (unsigned todo = K.plane_pass(blk + k, m, pl, eps, s, sides); todo; todo &= todo - 1) {
        const unsigned j = unsigned(__builtin_ctz(todo));
        const bool q_outer = q_sides ? (sides >> j & 1u) != 0 : (blk[k + j].flags() & kRefPositive) != 0;
        if (!one(k + j, s[j], q_outer ? 1 : -1)) return false;
      }
    }
  }
  *delta = w;
  return true;
}

// A step longer than kNearInsideJump of a leaf cell on some axis is a jump, not a path: the
// reference path is cheaper than gathering the triangles of up to 8 leaves. The step's near set
// reaches ahead of p along the step, by kNearInsideAhead steps, with a margin of the larger of
// kNearInsideMargin leaf cells and kNearInsideSide steps, so that a set serves the next steps of
// a path instead of the one it was gathered for. Measured on the haptic path (20,000 points,
// seed 1), callgrind instructions per query on the 1M / 4M bunny and wall clock on the 32M one
// (the last three of 5 passes; the plain search 5.5-6.4 M q/s): without the reach (the step's
// box and 1/32 cell, jumps from 1/4 cell: 64 % of the 4M path's queries gathered a set)
// 1,166 / 1,504 (plain 1,368) / 4.4-4.8 M q/s; the reach with jumps from 1/4 cell 757 / 832 /
// 2.2-2.7 M; from 1/8 757 / 832 / 2.2-2.7 M; from 1/16 757 / 851 / 6.0-6.9 M. Ahead 4 / 8 / 12
// / 16 steps (1/4 cell, 1M): 810 / 757 / 748 / 755; 4M: - / 832 / 908 / -.
constexpr double kNearInsideJump = 1.0 / 16;
constexpr double kNearInsideMargin = 1.0 / 32;
constexpr double kNearInsideSide = 1.0;
constexpr double kNearInsideAhead = 8.0;
}  // namespace

// Coherent inside on a closed mesh (the winding number is then a function of the point):
// w(p) = w(prev) + (signed crossings of the segment prev -> p). The segment lies in its bounding
// box S; the triangles that can cross it are those whose boxes meet S (box comparisons are of
// exact values: float boxes against S rounded outwards to float, conservative), and they are all
// in the near set (gather_near) when S lies in the set's box: the query scans that short list,
// and gathers it anew around S when S has left it. Sides and crossings are exact predicates.
// Returns false (the caller takes the reference path) when the step is a jump (over
// kNearInsideJump of a leaf cell on an axis) out of the near set's box, the near set cannot be
// gathered (see gather_near), prev lies in a candidate's plane, or the segment is degenerate; p exactly
// on a triangle gives *w = 1 (the solid is closed) and leaves prev as it was.
bool Query::step_from_prev(const Vec3d& p, std::uint32_t leaf_node, int* wout) {
  const Vec3d& q = prev_p_;
  const Vec3d s0{std::min(p.x, q.x), std::min(p.y, q.y), std::min(p.z, q.z)};
  const Vec3d s1{std::max(p.x, q.x), std::max(p.y, q.y), std::max(p.z, q.z)};
  float f0[3], f1[3];  // S rounded outwards to float
  for (int a = 0; a < 3; ++a) {
    f0[a] = float_down_near(s0[a]);
    f1[a] = float_up_near(s1[a]);
  }
  // The step's near set, or the coherent distance's (it holds every triangle meeting its box
  // too, the zero-area ones included, which cross nothing), or a new step's near set.
  const NearSet* set = near_.get();
  if (!holds(near_, f0, f1)) {
    if (holds(dnear_, f0, f1)) {
      set = dnear_.get();
    } else {
      const double jump = kNearInsideJump * t_.cell_size(t_.leaf_level);
      if (s1.x - s0.x > jump || s1.y - s0.y > jump || s1.z - s0.z > jump || !gather_near(s0, s1, p - q, leaf_node))
        return false;
      set = near_.get();
    }
  }
  const NearSet& ns = *set;
  const LeafTri* tris = t_.tris.data();
  int w = prev_w_;
  auto test = [&](std::uint32_t k) {  // 1: go on, 0: p on a triangle, -1: give up
    const LeafTri& t = tris[k];
    if (t.flags() & kDegenerate) return 1;  // zero area: crosses nothing
    const Vec3d a = to_d(t.a), b = to_d(t.b), c = to_d(t.c);
    ++counters.planes_tested;
    const int sq = orient3d(a, b, c, q);
    if (sq == 0) return -1;
    const int sp = orient3d(a, b, c, p);
    if (sp == sq) return 1;
    ++counters.triangles_tested;
    switch (segment_triangle(p, q, sp, sq, a, b, c)) {
      case Cross::none: return 1;
      case Cross::proper: w += sq > 0 ? 1 : -1; return 1;
      case Cross::on_p: return 0;
      case Cross::degenerate: return -1;
    }
    return -1;
  };
  int stop = 1;  // 1: went through the near set, 0: p on a triangle, -1: give up
  ns.for_each_meeting(f0, f1, [&](std::uint32_t j) {
    stop = test(ns.k[j]);
    return stop > 0;
  });
  if (stop < 0) return false;
  if (stop == 0) { *wout = 1; return true; }
  *wout = w;
  prev_p_ = p;
  prev_w_ = w;
  return true;
}

// The near set around the box [s0, s1] of the step `step` (step_from_prev): its box is [s0, s1]
// and the point kNearInsideAhead steps ahead of p, grown by the margin below (or the step's box
// alone, if the grown box fails below), rounded outwards to float. The box must lie in the
// union of the closed leaf-grid cells [cell(lo), cell(hi)], at most 2 per axis (checked
// exactly against the exact cell boundaries of Octree::cell_box); a triangle that meets a closed cell is listed in that cell's leaf (empty nodes have none), so
// the triangles whose boxes meet the box are among those leaves' references: the leaves' blocks
// are tested by their (derived) boxes, then the triangles of the blocks that meet it by their own
// (box_pass), and an input triangle listed in two leaves is kept once. Fails (valid = false)
// when the box spans more cells, a cell is an out-of-core page's stand-in for another page (an
// empty node that is not the cell's ancestor), or more than kNearInsideMembers triangles meet it
// (NearSet::gather, near_set.hpp).
bool Query::gather_near(const Vec3d& s0, const Vec3d& s1, const Vec3d& step, std::uint32_t leaf_node) {
  const double cell = t_.cell_size(t_.leaf_level);
  const double len = std::max({std::fabs(step.x), std::fabs(step.y), std::fabs(step.z)});
  const double margin = std::max(kNearInsideMargin * cell, kNearInsideSide * len);
  // (the margin's rounding never shrinks the box: min/max with the unmargined corners)
  Vec3d g0, g1;
  for (int a = 0; a < 3; ++a) {
    const double ahead = (step[a] > 0 ? s1[a] : s0[a]) + kNearInsideAhead * step[a];  // p + k step
    g0[a] = std::min({s0[a] - margin, s0[a], ahead - margin});
    g1[a] = std::max({s1[a] + margin, s1[a], ahead + margin});
  }
  NearSet& ns = allocated(near_);
  return ns.gather(t_, g0, g1, leaf_node, false, kNearInsideMembers) ||
         ns.gather(t_, s0, s1, leaf_node, false, kNearInsideMembers);
}

bool Query::classify_leaf(const Vec3d& p, const Leaf& lf, std::uint32_t li, std::uint32_t node) {
  const LeafTri* blk = t_.tris.data() + lf.tri_begin;
  const std::uint32_t n = lf.tri_count;
  const Vec3d ref = to_d(lf.ref);
  bool on_surface = false;
  int delta;
  const bool track = coherent_ && t_.closed;
  if (track && prev_ok_) {
    if (p == prev_p_) return prev_w_ >= 1;
    int w;
    if (step_from_prev(p, node, &w)) return w >= 1;
  }
  if (lf.ref_valid) {
    const BlockBox* boxes = t_.blocks.data() + t_.leaf_block[li];
    // w(p) from a point q of the cell whose winding number w_q is known (its sides: q_sides, or
    // the kRefPositive flags): false when the segment is degenerate and p is not on a triangle.
    bool in = false;
    auto from = [&](const Vec3d& q, const std::uint8_t* q_sides, int w_q) {
      if (!leaf_winding_ref(p, q, blk, n, lf, boxes, q_sides, counters, &delta, &on_surface)) {
        in = on_surface;  // on the boundary: the solid is closed
        return on_surface;
      }
      const int w = w_q + delta;
      if (track) {
        prev_ok_ = true;
        prev_p_ = p;
        prev_w_ = w;
      }
      in = w >= 1;
      return true;
    };
    if (!t_.sub_refs.empty()) {
      // From the sub-reference of p's octant of the cell, when it has one: a shorter segment.
      const int o = leaf_octant(lf, p);
      const SubRef& sr = t_.sub_refs[std::size_t(li) * 8 + std::size_t(o)];
      if (sr.valid && from(to_d(sr.p), &t_.sub_sides[std::size_t(t_.leaf_block[li]) * 8 + std::size_t(o)], sr.winding))
        return in;
    }
    if (from(ref, nullptr, lf.ref_winding)) return in;
  }
  // Rare: ref -> p passes through an edge or a vertex. Route through another point r2 of the
  // cell: w(r2) = w(ref) - (w(ref) - w(r2)), then w(p) = w(r2) + (w(p) - w(r2)). Both segments
  // stay in the cell, so the leaf's triangles are all that can cross them.
  ++counters.exact_fallbacks;
  const double cs = t_.cell_size(t_.leaf_level);
  const Vec3d lo = t_.leaf_corner(lf);
  const Vec3d hi = lo + Vec3d(cs, cs, cs), cc = (lo + hi) * 0.5;
  int sides[64];
  for (const Vec3d& off : ref_offsets()) {
    if (!lf.ref_valid) break;
    const Vec3d r2 = round_to_float(cc + off * (0.5 * cs));
    if (!(r2.x > lo.x && r2.x < hi.x && r2.y > lo.y && r2.y < hi.y && r2.z > lo.z && r2.z < hi.z)) continue;
    bool ok = true;
    std::fill(sides, sides + 64, 0);
    auto side_r2 = [&](std::uint32_t k) {  // exact sides of r2, cached for the first 64
      if (k < 64 && sides[k] != 0) return sides[k];
      const LeafTri& t = blk[k];
      const int o = orient3d(to_d(t.a), to_d(t.b), to_d(t.c), r2);
      if (o == 0) ok = false;
      if (k < 64) sides[k] = o;
      return o == 0 ? 1 : o;
    };
    int d1, d2;
    bool on1 = false;
    if (!leaf_winding(ref, r2, blk, n, lf, side_r2, counters, &d1, &on1) || !ok) continue;
    const int w_r2 = lf.ref_winding - d1;
    if (!leaf_winding(p, r2, blk, n, lf, side_r2, counters, &d2, &on_surface)) {
      if (on_surface) return true;
      continue;
    }
    if (!ok) continue;
    return w_r2 + d2 >= 1;
  }
  return lf.ref_winding >= 1;  // no usable reference point: deterministic, documented
}

}  // namespace ebp
