// The faces whose front is outside and back inside (face_sides.hpp).
#include "methods/ebp_octree/core/face_sides.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "harness/core/weld_table.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/float_round.hpp"
#include "methods/ebp_octree/core/leaf_kernels.hpp"
#include "methods/ebp_octree/core/parallel_for.hpp"
#include "methods/ebp_octree/core/predicates.hpp"

namespace ebp {

namespace {

/// A bit per input triangle, set from any thread.
class AtomicBits {
 public:
  explicit AtomicBits(std::size_t n) : n_((n + 63) / 64), w_(new std::atomic<std::uint64_t>[n_]) {
    for (std::size_t i = 0; i < n_; ++i) w_[i].store(0, std::memory_order_relaxed);
  }
  void set(std::uint32_t i) { w_[i >> 6].fetch_or(std::uint64_t(1) << (i & 63u), std::memory_order_relaxed); }
  bool test(std::uint32_t i) const { return (w_[i >> 6].load(std::memory_order_relaxed) >> (i & 63u)) & 1u; }
  std::uint64_t word(std::size_t w) const { return w_[w].load(std::memory_order_relaxed); }
  std::size_t words() const { return n_; }

 private:
  std::size_t n_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> w_;
};

bool same_point(const float* u, const float* v) { return u[0] == v[0] && u[1] == v[1] && u[2] == v[2]; }

/// A triangle's float box (exact: its corners are vertex coordinates).
struct TriBox {
  float lo[3], hi[3];
  explicit TriBox(const LeafTri& t) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min({t.a[a], t.b[a], t.c[a]});
      hi[a] = std::max({t.a[a], t.b[a], t.c[a]});
    }
  }
  bool meets(const TriBox& o) const {
    return !(hi[0] < o.lo[0] || o.hi[0] < lo[0] || hi[1] < o.lo[1] || o.hi[1] < lo[1] || hi[2] < o.lo[2] ||
             o.hi[2] < lo[2]);
  }
};

/// Whether a, b, c are exactly in one plane with p (the plane of a triangle and a point).
bool coplanar(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& p) { return orient3d(a, b, c, p) == 0; }

/// A point off the plane of (a, b, c) (not collinear), exactly: a's neighbour along an axis.
Vec3d off_plane(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  for (int k = 0; k < 3; ++k) {
    Vec3d w = a;
    w[k] += std::max(1.0, std::fabs(a[k]));
    if (!coplanar(a, b, c, w)) return w;
  }
  return a;  // unreachable for a triangle of nonzero area
}

/// Whether the closed segment [s0, s1], in the plane of the triangle (a, b, c), meets it, exactly:
/// they are apart iff a line separates them strictly, and for a segment and a triangle in a plane
/// one of the triangle's edge lines or the segment's own line does if any line does.
bool coplanar_segment_meets(const Vec3d& s0, const Vec3d& s1, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d w = off_plane(a, b, c);
  const Vec3d v[3] = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    const Vec3d &p = v[i], &q = v[(i + 1) % 3], &r = v[(i + 2) % 3];
    const int inner = orient3d(p, q, w, r);
    if (orient3d(p, q, w, s0) == -inner && orient3d(p, q, w, s1) == -inner) return false;
  }
  if (s0 == s1) return true;  // a point no edge line separates lies in the triangle
  const int oa = orient3d(s0, s1, w, a), ob = orient3d(s0, s1, w, b), oc = orient3d(s0, s1, w, c);
  return !(oa != 0 && oa == ob && ob == oc);
}

/// Whether the closed segment [s0, s1] meets the closed triangle (a, b, c), exactly: in its plane,
/// coplanar_segment_meets; otherwise the parity test's crossing (segment_triangle), from the
/// endpoint off the plane.
bool segment_meets(const Vec3d& s0, const Vec3d& s1, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const int o0 = orient3d(a, b, c, s0), o1 = orient3d(a, b, c, s1);
  if (o0 == o1) return o0 == 0 && coplanar_segment_meets(s0, s1, a, b, c);
  const Cross x = o1 != 0 ? segment_triangle(s0, s1, o0, o1, a, b, c) : segment_triangle(s1, s0, o1, o0, a, b, c);
  return x != Cross::none;
}

/// Coplanar triangles A and B (their plane's off-plane point w): whether the line of an edge
/// [P_i, P_j] of one has the other's vertices on the side away from its third vertex, those on
/// the line (a mesh made by subdividing flat triangles has many: neighbours around a vertex whose
/// edges continue one another) lying off the edge and only beyond a shared end. Then the two
/// meet only on the line: the edge, and the other's part on it, the span of its vertices there,
/// which then meets the edge only in the shared vertices. Two convex polygons apart have such a
/// line along an edge of one of them; a case this misses only leaves a face out.
bool coplanar_apart(const Vec3d* A, const float* const* av, const Vec3d* B, const float* const* bv, const Vec3d& w) {
  auto separates = [&](const Vec3d* P, const float* const* pv, const Vec3d* Q, const float* const* qv) {
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      const int o = orient3d(P[i], P[j], w, P[k]);
      if (o == 0) continue;
      // Positions along the edge's line by the coordinate it changes most (the points compared
      // are on the line, so their order there is their order on it): before P_i, beyond P_j.
      int ax = 0;
      for (int a = 1; a < 3; ++a)
        if (std::fabs(P[j][a] - P[i][a]) > std::fabs(P[j][ax] - P[i][ax])) ax = a;
      const bool up = P[j][ax] > P[i][ax];
      bool shares_i = false, shares_j = false, before = false, beyond = false, apart = true;
      for (int m = 0; m < 3 && apart; ++m) {
        if (same_point(qv[m], pv[i])) { shares_i = true; continue; }
        if (same_point(qv[m], pv[j])) { shares_j = true; continue; }
        const int om = orient3d(P[i], P[j], w, Q[m]);
        if (om == -o) continue;
        const double x = Q[m][ax];
        if (om == 0 && (up ? x < P[i][ax] : x > P[i][ax])) before = true;
        else if (om == 0 && (up ? x > P[j][ax] : x < P[j][ax])) beyond = true;
        else apart = false;  // on A's side, or on the edge itself
      }
      if (apart && !(before && (beyond || shares_j)) && !(beyond && shares_i)) return true;
    }
    return false;
  };
  return separates(A, av, B, bv) || separates(B, bv, A, av);
}

/// Whether the triangles s and t (sharing `sh`) meet at most in the vertices and the edge they
/// share (exactly; false where the tests below cannot tell, which
/// only leaves a face out):
///   - in one plane: coplanar_apart;
///   - sharing an edge uv: the planes meet in uv's line;
///   - sharing a vertex u: the triangles meet beyond u iff the edge of one opposite u meets the
///     other (their common part lies on the planes' common line through u);
///   - sharing none: disjoint when one's vertices are all strictly on one side of the other's
///     plane, or when no edge of either meets the other.
/// The vertices two triangles of a leaf share, by their ids (LeafVertices).
struct Sharing {
  int t_of_s[3] = {-1, -1, -1};  ///< for each vertex of s, the vertex of t it is, or -1
  bool t_shared[3] = {false, false, false};
  int count = 0;
  Sharing(const std::uint32_t* sid, const std::uint32_t* tid) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (!t_shared[j] && sid[i] == tid[j]) {
          t_of_s[i] = j;
          t_shared[j] = true;
          ++count;
          break;
        }
  }
};

bool meet_only_where_shared(const LeafTri& s, const LeafTri& t, const Sharing& sh) {
  const float* sv[3] = {s.a, s.b, s.c};
  const float* tv[3] = {t.a, t.b, t.c};
  const int* t_of_s = sh.t_of_s;
  const bool* t_shared = sh.t_shared;
  const int shared = sh.count;
  if (shared == 3) return false;  // the same triangle twice
  const Vec3d S[3] = {to_d(sv[0]), to_d(sv[1]), to_d(sv[2])};
  const Vec3d T[3] = {to_d(tv[0]), to_d(tv[1]), to_d(tv[2])};
  if (shared == 2) {
    int si = 0, ti = 0;  // the vertex of each not shared
    while (t_of_s[si] >= 0) ++si;
    while (t_shared[ti]) ++ti;
    const int u = (si + 1) % 3, v = (si + 2) % 3;
    if (!coplanar(S[u], S[v], S[si], T[ti])) return true;
    return coplanar_apart(S, sv, T, tv, off_plane(S[0], S[1], S[2]));
  }
  if (shared == 1) {
    int u = 0;
    while (t_of_s[u] < 0) ++u;
    const int tu = t_of_s[u];
    const Vec3d &t1 = T[(tu + 1) % 3], &t2 = T[(tu + 2) % 3], &s1 = S[(u + 1) % 3], &s2 = S[(u + 2) % 3];
    const int o1 = orient3d(S[0], S[1], S[2], t1), o2 = orient3d(S[0], S[1], S[2], t2);
    if (o1 == o2 && o1 != 0) return true;  // t leaves s's plane at u at once
    if (o1 == 0 && o2 == 0) return coplanar_apart(S, sv, T, tv, off_plane(S[0], S[1], S[2]));
    const int p1 = orient3d(T[0], T[1], T[2], s1), p2 = orient3d(T[0], T[1], T[2], s2);
    if (p1 == p2 && p1 != 0) return true;
    return !segment_meets(t1, t2, S[0], S[1], S[2]) && !segment_meets(s1, s2, T[0], T[1], T[2]);
  }
  const int s_side[3] = {orient3d(T[0], T[1], T[2], S[0]), orient3d(T[0], T[1], T[2], S[1]),
                         orient3d(T[0], T[1], T[2], S[2])};
  const int t_side[3] = {orient3d(S[0], S[1], S[2], T[0]), orient3d(S[0], S[1], S[2], T[1]),
                         orient3d(S[0], S[1], S[2], T[2])};
  auto one_side = [](const int* o) { return o[0] != 0 && o[0] == o[1] && o[1] == o[2]; };
  if (one_side(s_side) || one_side(t_side)) return true;
  if (t_side[0] == 0 && t_side[1] == 0 && t_side[2] == 0) return coplanar_apart(S, sv, T, tv, off_plane(S[0], S[1], S[2]));
  for (int i = 0; i < 3; ++i)
    if (segment_meets(T[i], T[(i + 1) % 3], S[0], S[1], S[2]) || segment_meets(S[i], S[(i + 1) % 3], T[0], T[1], T[2]))
      return false;
  return true;
}

/// x + y, exactly, or false.
bool exact_sum(double x, double y, double* s) {
  *s = x + y;
  const double yv = *s - x;
  return (x - (*s - yv)) + (y - yv) == 0;
}

/// A leaf's distinct vertices (bvhbench::WeldTable): an id per corner of each LeafTri (equal
/// coordinates, equal id), so that shared vertices and edges are integer comparisons.
class LeafVertices {
 public:
  void index(const LeafTri* blk, std::uint32_t n) {
    weld_.reset(3 * std::uint64_t(n));
    ids_.resize(3 * std::size_t(n));
    bool added;
    for (std::uint32_t k = 0; k < n; ++k) {
      const float* v[3] = {blk[k].a, blk[k].b, blk[k].c};
      for (int i = 0; i < 3; ++i) ids_[3 * std::size_t(k) + std::size_t(i)] = weld_.insert(v[i], added);
    }
  }
  const std::uint32_t* of(std::uint32_t k) const { return &ids_[3 * std::size_t(k)]; }
  const float* point(std::uint32_t v) const { return weld_.point(v); }
  std::uint32_t count() const { return std::uint32_t(weld_.size()); }

 private:
  bvhbench::WeldTable weld_;
  std::vector<std::uint32_t> ids_;
};

/// One leaf as the face sides read it: its triangles and their boxes, its blocks' boxes, its
/// cell, and its reference points (the leaf's, and one per octant where the tree has them).
struct LeafView {
  const Octree& t;
  std::size_t li;
  const Leaf& lf;
  const LeafTri* blk;
  std::uint32_t n;
  const BlockBox* blocks;
  Vec3d lo;
  double size;

  LeafView(const Octree& tree, std::size_t leaf)
      : t(tree), li(leaf), lf(tree.leaves[leaf]), blk(tree.tris.data() + lf.tri_begin), n(lf.tri_count),
        blocks(tree.blocks.data() + tree.leaf_block[leaf]), lo(tree.leaf_corner(lf)), size(tree.cell_size(tree.leaf_level)) {}

  /// Whether x3 = scale * x lies in the cell (half-open at the top, so that each point is in
  /// one leaf, or closed).
  bool holds(const Vec3d& x3, double scale, bool upper_open) const {
    for (int a = 0; a < 3; ++a) {
      const double l = scale * lo[a], h = scale * (lo[a] + size);
      if (!(x3[a] >= l && (upper_open ? x3[a] < h : x3[a] <= h))) return false;
    }
    return true;
  }

  /// Whether vertex v lies in the closed cell (exactly: the cell bounds are doubles).
  bool in_closed_cell(const float* v) const {
    for (int a = 0; a < 3; ++a)
      if (!(double(v[a]) >= lo[a] && double(v[a]) <= lo[a] + size)) return false;
    return true;
  }
  /// Whether vertex v belongs to this leaf: in its cell, half-open at the top but on the root's
  /// upper faces, so that each vertex belongs to one leaf (the leaf whose cell holds it: a
  /// triangle touching it touches that cell, so that leaf lists every triangle with v).
  bool owns(const float* v) const {
    for (int a = 0; a < 3; ++a) {
      const double x = double(v[a]), h = lo[a] + size;
      if (!(x >= lo[a] && (x < h || (x == h && h == t.root_lo[a] + t.root_size)))) return false;
    }
    return true;
  }

  /// w(x) for x3 = scale * x (exactly) in the cell: the winding number of the reference point of
  /// x's octant (the leaf's own where the octant has none) plus the signed crossings of the
  /// segment from it to x by the leaf's triangles but `skip` (one x lies on), exactly (scaling
  /// changes no orientation). The segment lies in the cell, so the leaf's triangles are all that
  /// can cross it; a block or triangle whose box misses the segment's (rounded outwards) cannot.
  /// False where the segment passes through an edge or a vertex or x lies on a counted triangle.
  /// *skip_side: the reference point's side of triangle `skip` (+1 its outer side), if one.
  bool winding_at(const Vec3d& x3, double scale, std::uint32_t skip, int* w, int* skip_side = nullptr) const {
    const Vec3d x = x3 * (1.0 / scale);  // within rounding of x: the float filter's and boxes' point
    Vec3d r = to_d(lf.ref);
    int wr = lf.ref_winding;
    const std::uint8_t* sides = nullptr;  // the octant's sides of the leaf's triangles, by block
    if (!t.sub_refs.empty()) {
      const int o = leaf_octant(lf, x);
      const SubRef& sr = t.sub_refs[li * 8 + std::size_t(o)];
      if (sr.valid) {
        r = to_d(sr.p);
        wr = sr.winding;
        sides = &t.sub_sides[std::size_t(t.leaf_block[li]) * 8 + std::size_t(o)];
      }
    }
    const Vec3d r3 = r * scale;
    const float pl[3] = {float(x.x - double(lf.centre[0])), float(x.y - double(lf.centre[1])),
                         float(x.z - double(lf.centre[2]))};
    float s0[3], s1[3];  // the segment's box, rounded outwards to float (far beyond x's rounding)
    for (int a = 0; a < 3; ++a) {
      s0[a] = float_down_near(std::min(x[a], r[a]));
      s1[a] = float_up_near(std::max(x[a], r[a]));
    }
    auto misses = [&](const float* blo, const float* bhi) {
      return bhi[0] < s0[0] || blo[0] > s1[0] || bhi[1] < s0[1] || blo[1] > s1[1] || bhi[2] < s0[2] || blo[2] > s1[2];
    };
    auto ref_side = [&](std::uint32_t k) {
      return sides ? (((sides[(k / kBlockTris) * 8] >> (k % kBlockTris)) & 1u) ? 1 : -1)
                   : ((blk[k].flags() & kRefPositive) ? 1 : -1);
    };
    if (skip_side && skip < n) *skip_side = ref_side(skip);
    int delta = 0;
    for (std::uint32_t j = 0; j * kBlockTris < n; ++j) {
      if (misses(blocks[j].lo, blocks[j].hi)) continue;
      for (std::uint32_t k = j * kBlockTris; k < std::min(n, (j + 1) * kBlockTris); ++k) {
        const LeafTri& tr = blk[k];
        if (k == skip || (tr.flags() & kDegenerate)) continue;
        const TriBox tb(tr);
        if (misses(tb.lo, tb.hi)) continue;
        const int sq = ref_side(k);
        const Vec3d A = to_d(tr.a) * scale, B = to_d(tr.b) * scale, C = to_d(tr.c) * scale;
        const float v = face_plane_value(tr, pl);
        const int sp = v > lf.eps ? 1 : v < -lf.eps ? -1 : orient3d(A, B, C, x3);
        switch (segment_triangle(x3, r3, sp, sq, A, B, C)) {
          case Cross::none: break;
          case Cross::proper: delta += sq > 0 ? 1 : -1; break;  // reference outer -> x inner: entering
          default: return false;
        }
      }
    }
    *w = wr + delta;
    return true;
  }
};

/// The winding number just in front of face f of the leaf (the side its normal points to).
/// Measured at f's centroid c, scaled by 3 so that it is the exact sum of f's vertices, as
/// reached from the reference point's side of f; where that sum rounds (a vertex coordinate far
/// smaller than another's), at the rounded point q off f's plane, after checking that a short
/// step across f from q crosses f in its interior and meets no other triangle (q then lies on
/// one side of f with nothing between). False if the point is not in the leaf's half-open cell
/// (each face is measured in one leaf) or where an exact test meets an edge, a vertex or a plane.
bool front_winding(const LeafView& L, std::uint32_t f, int* w_front) {
  const LeafTri& F = L.blk[f];
  const Vec3d A = to_d(F.a), B = to_d(F.b), C = to_d(F.c);
  Vec3d c3;
  bool exact = true;
  for (int a = 0; a < 3; ++a) {
    double ab;
    exact &= exact_sum(A[a], B[a], &ab);
    exact &= exact_sum(ab, C[a], &c3[a]);
  }
  int w;
  if (exact) {
    int ref_side = 0;
    if (!L.holds(c3, 3.0, true) || !L.winding_at(c3, 3.0, f, &w, &ref_side)) return false;
    *w_front = ref_side > 0 ? w : w - 1;  // c reached from the reference's side of f; w_back = w_front + 1
    return true;
  }
  const Vec3d q = c3 * (1.0 / 3.0);
  const int side = orient3d(A, B, C, q);
  if (side == 0 || !L.holds(q, 1.0, true)) return false;
  // q2: q moved along the axis of f's normal's largest part, a few ulps at a time, until it is
  // on the other side of f
  const Vec3d nrm = bvhbench::triangle_normal(A, B, C);
  int ax = 0;
  for (int a = 1; a < 3; ++a)
    if (std::fabs(nrm[a]) > std::fabs(nrm[ax])) ax = a;
  const double dir = (nrm[ax] > 0) == (side > 0) ? -1.0 : 1.0;
  Vec3d q2 = q;
  double step = std::max({std::fabs(A[ax]), std::fabs(B[ax]), std::fabs(C[ax])}) * 0x1p-52;
  for (int i = 0; i < 64 && orient3d(A, B, C, q2) != -side; ++i, step *= 2) q2[ax] = q[ax] + dir * step;
  if (orient3d(A, B, C, q2) != -side || !L.holds(q2, 1.0, false)) return false;
  if (segment_triangle(q, q2, side, -side, A, B, C) != Cross::proper) return false;
  for (std::uint32_t k = 0; k < L.n; ++k)
    if (k != f && !(L.blk[k].flags() & kDegenerate) &&
        segment_meets(q, q2, to_d(L.blk[k].a), to_d(L.blk[k].b), to_d(L.blk[k].c)))
      return false;
  if (!L.winding_at(q, 1.0, UINT32_MAX, &w)) return false;  // at q, on f's `side`
  *w_front = side > 0 ? w : w - 1;
  return true;
}

/// A leaf's clean faces joined where the winding number just in front of one is that in front of
/// the other: two clean faces (no triangle anywhere meets either but where they share) that share
/// an edge in opposite directions, the edge an edge of no other triangle (the leaf lists every
/// triangle that touches its closed cell, so every triangle with the edge where the edge has an
/// endpoint in the cell). A triangle that touches the open edge without having it as an edge is
/// not clean with either face; so only the two faces touch it, and their fronts are one wedge of
/// space around it. A clean face's front is one region over the whole face, so the relation is
/// transitive. Union-find over the leaf's positions.
class FrontComponents {
 public:
  void join_across_edges(const LeafView& L, const LeafVertices& V, const std::vector<std::uint8_t>& clean) {
    parent_.resize(L.n);
    for (std::uint32_t k = 0; k < L.n; ++k) parent_[k] = k;
    edges_.clear();
    for (std::uint32_t k = 0; k < L.n; ++k) {
      const std::uint32_t* v = V.of(k);
      for (int i = 0; i < 3; ++i) edges_.push_back(Edge::of(v[i], v[(i + 1) % 3], k));
    }
    std::sort(edges_.begin(), edges_.end());
    for (std::size_t i = 0; i < edges_.size();) {
      std::size_t j = i + 1;
      while (j < edges_.size() && edges_[j].ends == edges_[i].ends) ++j;
      const Edge &e = edges_[i], &f = edges_[i + 1];
      if (j - i == 2 && e.forward != f.forward && clean[e.tri] && clean[f.tri] &&
          (L.in_closed_cell(V.point(std::uint32_t(e.ends >> 32))) || L.in_closed_cell(V.point(std::uint32_t(e.ends)))))
        unite(e.tri, f.tri);
      i = j;
    }
  }
  std::uint32_t find(std::uint32_t k) {
    while (parent_[k] != k) k = parent_[k] = parent_[parent_[k]];
    return k;
  }

 private:
  /// An edge by its endpoints' ids (the lower in the high half), and its direction in `tri`.
  struct Edge {
    std::uint64_t ends;
    std::uint32_t tri;
    bool forward;
    static Edge of(std::uint32_t u, std::uint32_t v, std::uint32_t tri) {
      return u < v ? Edge{std::uint64_t(u) << 32 | v, tri, true} : Edge{std::uint64_t(v) << 32 | u, tri, false};
    }
    bool operator<(const Edge& o) const { return ends != o.ends ? ends < o.ends : tri < o.tri; }
  };
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }
  std::vector<std::uint32_t> parent_;
  std::vector<Edge> edges_;
};

/// The faces of a leaf that are not clean, as far as this leaf can tell: its pairs of triangles
/// whose boxes meet, swept by their boxes' lower x. Every pair of triangles that meet anywhere is
/// tested in some leaf: a pair sharing a vertex in the leaf that owns the vertex (LeafView::owns),
/// which lists both; a pair sharing none in every leaf that lists both (a point where they meet is
/// in a leaf's cell, which lists both).
void mark_unclean(const LeafView& L, AtomicBits& unclean) {
  thread_local LeafVertices V;
  thread_local std::vector<std::pair<TriBox, std::uint32_t>> box;
  thread_local std::vector<std::uint8_t> owned;  // by vertex id
  V.index(L.blk, L.n);
  owned.resize(V.count());
  for (std::uint32_t v = 0; v < V.count(); ++v) owned[v] = L.owns(V.point(v));
  box.clear();
  for (std::uint32_t i = 0; i < L.n; ++i) box.push_back({TriBox(L.blk[i]), i});
  std::sort(box.begin(), box.end(), [](const auto& x, const auto& y) { return x.first.lo[0] < y.first.lo[0]; });
  for (std::uint32_t a = 0; a < L.n; ++a) {
    const std::uint32_t i = box[a].second;
    const std::uint32_t* si = V.of(i);
    if (L.blk[i].flags() & kDegenerate) unclean.set(L.blk[i].tri());  // no plane to take a side of
    for (std::uint32_t b = a + 1; b < L.n && box[b].first.lo[0] <= box[a].first.hi[0]; ++b) {
      if (!box[a].first.meets(box[b].first)) continue;
      const std::uint32_t j = box[b].second;
      const std::uint32_t* sj = V.of(j);
      const Sharing sh(si, sj);
      bool here = sh.count == 0;
      for (int x = 0; x < 3; ++x) here |= sh.t_of_s[x] >= 0 && owned[si[x]];
      if (!here) continue;  // another leaf's pair
      if (!meet_only_where_shared(L.blk[i], L.blk[j], sh)) {
        unclean.set(L.blk[i].tri());
        unclean.set(L.blk[j].tri());
      }
    }
  }
}

/// The clean faces of a leaf whose front has winding number 0: measured once per component of
/// faces with one front (FrontComponents), from its first member whose centroid can measure it
/// (front_winding).
void mark_outside_fronts(const LeafView& L, const AtomicBits& unclean, AtomicBits& outside_front) {
  if (!L.lf.ref_valid) return;
  thread_local LeafVertices V;
  thread_local FrontComponents comps;
  thread_local std::vector<std::uint8_t> clean;       // by position
  thread_local std::vector<std::int8_t> comp_front;   // by root: kUnmeasured, 0 outside, 1 not
  constexpr std::int8_t kUnmeasured = -1;
  V.index(L.blk, L.n);
  clean.resize(L.n);
  for (std::uint32_t f = 0; f < L.n; ++f) clean[f] = !unclean.test(L.blk[f].tri());
  comps.join_across_edges(L, V, clean);
  comp_front.assign(L.n, kUnmeasured);
  for (std::uint32_t f = 0; f < L.n; ++f) {
    int w;
    std::int8_t& front = comp_front[comps.find(f)];
    if (clean[f] && front == kUnmeasured && front_winding(L, f, &w)) front = w == 0 ? 0 : 1;
  }
  for (std::uint32_t f = 0; f < L.n; ++f)
    if (clean[f] && comp_front[comps.find(f)] == 0) outside_front.set(L.blk[f].tri());
}

}  // namespace

void compute_face_sides(Octree& t, int threads) {
  t.front_outside.clear();
  t.stats.front_outside_faces = 0;
  if (!t.closed) {
    t.front_outside.shrink_to_fit();
    return;
  }
  // Two passes: a face's cleanliness is known once every leaf has tested its pairs.
  AtomicBits unclean(t.num_triangles), outside_front(t.num_triangles);
  const std::size_t nl = t.leaves.size();
  par_for(threads, nl, [&](std::size_t li) { mark_unclean(LeafView(t, li), unclean); }, 64);
  par_for(threads, nl, [&](std::size_t li) { mark_outside_fronts(LeafView(t, li), unclean, outside_front); }, 64);
  t.front_outside.resize(unclean.words());
  std::size_t count = 0;
  for (std::size_t w = 0; w < unclean.words(); ++w) {
    t.front_outside[w] = outside_front.word(w) & ~unclean.word(w);
    count += std::size_t(__builtin_popcountll(t.front_outside[w]));
  }
  t.stats.front_outside_faces = count;
}

}  // namespace ebp
