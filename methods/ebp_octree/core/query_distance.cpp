// Distance (Query::distance_bound): branch and bound over the tree with the bounding planes as
// lower bounds (DESIGN.md, "Distance"); the path's policy over its searches (seeds, certificates,
// when to gather a near set) is query_distance_path.cpp's. One distance_bound call is a
// DistanceSearch, in the steps the algorithm takes:
//   the coherent start   the previous closest triangle and its leaf, so that the bound is tight
//                        before the descent;
//   the near start       (coherent) the path's near set, when it holds the ball: the whole search;
//   the located start    (no bound yet) the leaf on p's own path, so that the bound is tight
//                        before the descent;
//   the narrowed start   the deepest node on p's path whose cell holds the ball (p, best + tol);
//   the descent          nodes popped nearest first, pruned by node_bound (cell box, geometry
//                        box, planes, plane and bounding sphere together);
//   the leaf scan        a leaf's blocks, nearest first, pruned by their boxes and the leaf's
//                        most separating plane; in each block the triangle tests (face plane,
//                        box, plane and bounding sphere) before the exact closest point.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>

#include "methods/ebp_octree/core/certificate.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/leaf_kernels.hpp"
#include "methods/ebp_octree/core/near_set.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/core/search_stack.hpp"

namespace ebp {

namespace {

/// A node on the descent's stack. Plain doubles, not a Vec3d: Vec3d zero-initialises, and the
/// stack (8 x 21 items) was cleared on every search (~500 instructions a query, a tenth of a
/// plain coherent search at contact on the 1M bunny).
struct StackItem {
  struct Corner {
    double x, y, z;
  } lo;
  double bound;
  std::uint32_t node;
  int level;
};
inline StackItem::Corner corner(const Vec3d& v) { return {v.x, v.y, v.z}; }

/// A leaf's most separating bounding plane at p: h its lower bound of the distance, n its
/// normal; h <= 0 for none.
struct PlaneHint {
  double h = 0, n[3] = {0, 0, 0};
};

}  // namespace

/// The state of one distance_bound call: p, the running best, and the bounds derived from them.
class Query::DistanceSearch {
 public:
  DistanceSearch(Query& q, const Vec3d& p, DistanceBest& B, const DistanceStart& s)
      : p(p), B(B), s(s), t_(q.t_), counters(q.counters), walk(q.walk_), stamp_(q.stamp_), leaf_stamp_(q.leaf_stamp_),
        order_(q.order_), block_d2_(q.block_d2_), qid(q.query_id_), tris(t_.tris.data()), key_of(s.key_of), leaves(t_.leaves.data()),
        blocks(t_.blocks.data()), planes(t_.planes.data()), nodes(t_.nodes.data()), nbox(t_.node_box.data()) {
    // Box bounds (blocks, nodes) are compared with `tol` added to the best distance (search_tol).
    tol = search_tol(p, t_.root_lo, t_.root_size);
    if (B.best < std::numeric_limits<double>::infinity()) lim2 = (B.best + tol) * (B.best + tol);
    // Plane bounds are evaluated in float in the root's frame; `slack` covers their rounding
    // (normals unit to 1e-7, float products), so that every bound stays a lower bound.
    const Vec3d pr = p - t_.root_centre;
    fx = float(pr.x);
    fy = float(pr.y);
    fz = float(pr.z);
    slack = 1e-6 * (std::max({std::fabs(pr.x), std::fabs(pr.y), std::fabs(pr.z)}) + t_.root_size);
  }

  /// The coherent start: the previous closest triangle, then its whole leaf (with its plane hint
  /// when its node is known), so that the bound is tight before the descent (answers do not
  /// depend on the order).
  void coherent_start() {
    seed_triangle();
    seed_leaf();
  }

  /// The previous closest triangle (a valid upper bound).
  void seed_triangle() {
    if (s.seed_tri >= t_.tris.size()) return;
    scan_node = seed_node_known() ? s.seed_node : UINT32_MAX;
    test_triangle(s.seed_tri, s.seed_leaf < t_.leaves.size() ? s.seed_leaf : UINT32_MAX);
  }

  /// The seed triangle's whole leaf.
  void seed_leaf() {
    if (s.seed_tri >= t_.tris.size() || s.seed_leaf >= t_.leaves.size()) return;
    const bool known = seed_node_known();
    scan_node = known ? s.seed_node : UINT32_MAX;
    scan_leaf(s.seed_leaf, known ? leaf_hint(nodes[s.seed_node]) : PlaneHint{});
  }

  /// The located start, for a search with no bound yet (no seed, no running best): the leaf
  /// nearest p along p's own path, scanned before the descent, so that the descent starts with a
  /// tight bound instead of weighing every child of every level against an infinite one. Down
  /// p's octants from s.node while the cells are inner; where p's cell is an empty node, down
  /// the grey child whose cell is nearest p (cell boxes only) to a leaf. The walk to p's own
  /// cell is recorded (`walk`), so that the narrowed start resumes from its deepest cell that
  /// holds the ball. Any leaf gives a valid upper bound: answers do not depend on which.
  void located_start() {
    if (B.best < std::numeric_limits<double>::infinity()) return;
    std::uint32_t ni = s.node;
    Vec3d lo = t_.root_lo, hi;
    int level = 0;
    if (ni != 0) {
      t_.cell_box(nodes[ni].code, &lo, &hi);
      level = octcode_level(nodes[ni].code);
    }
    const double size = t_.cell_size(level);
    if (!cell_contains(lo, size, p))
      return;  // p outside the subtree's cell: the descent's own order is as good
    walk.root = s.node;
    walk.node[0] = ni;
    walk.lo[0] = lo;
    walk.len = 1;
    bool on_path = true;  // ni's cell holds p
    while (nodes[ni].kind == NodeKind::inner) {
      const double csz = t_.cell_size(level + 1);
      const std::uint32_t* kids = t_.children.data() + nodes[ni].index;
      int o = -1;
      if (on_path) {
        o = child_octant(p, lo, csz);
        const NodeKind k = nodes[kids[o]].kind;
        if (k != NodeKind::inner && k != NodeKind::leaf) {
          on_path = false;
          o = -1;
        }
      }
      if (o < 0) {  // p's cell is empty: the grey child nearest p (an inner node has one)
        double best_d2 = std::numeric_limits<double>::infinity();
        for (int c = 0; c < 8; ++c) {
          const NodeKind k = nodes[kids[c]].kind;
          if (k != NodeKind::inner && k != NodeKind::leaf) continue;
          const double d2 = cell_d2(child_corner(lo, csz, c), csz, p);
          if (d2 < best_d2) { best_d2 = d2; o = c; }
        }
        if (o < 0) return;
      }
      lo = child_corner(lo, csz, o);
      ni = kids[o];
      ++level;
      ++counters.nodes_visited;
      if (on_path) {
        walk.node[walk.len] = ni;
        walk.lo[walk.len] = lo;
        ++walk.len;
      }
    }
    if (nodes[ni].kind != NodeKind::leaf) return;
    scan_node = ni;
    scan_leaf(nodes[ni].index, leaf_hint(nodes[ni]));
  }

  /// Whether the seed's node is the seed leaf's (its planes then bound the leaf's blocks).
  bool seed_node_known() const {
    return s.seed_leaf < t_.leaves.size() && s.seed_node < t_.nodes.size() &&
           nodes[s.seed_node].kind == NodeKind::leaf && nodes[s.seed_node].index == s.seed_leaf;
  }

  /// The near start (after seed_triangle): when the cube about p of half-width best + tol lies
  /// in the near set's box (tol covers the rounding of its faces), every triangle within best of
  /// p is a member (near_set.hpp), so the members whose boxes are within the best of p, in set
  /// order, are the whole search: no leaf scan, no descent. Returns false (nothing done)
  /// otherwise.
  bool near_start(const NearSet& ns) {
    if (!(B.best < std::numeric_limits<double>::infinity()) || !ns.holds_cube(p, B.best + tol)) return false;
    // The seed gave a tight bound (seed_triangle runs first), so the members are taken in set
    // order, each one whose box is within the running limit tested at once: sorting them by box
    // distance first cost more than the few extra exact tests it saved. The members' boxes go
    // through the leaf scan's box pre-filter (float, with its margin: a member it prunes is
    // strictly farther than the best), all of them in one pass, and each survivor's value is
    // compared again with the limit of the best when its turn comes. The set lists each input
    // triangle once, and a served search tests nothing before it but the seed: the members need
    // no once-per-query stamp, only the seed's exclusion.
    const std::uint32_t seed = s.seed_tri < t_.tris.size() ? tris[s.seed_tri].tri() : UINT32_MAX;
    point_bounds();
    // The survivors' exact tests four at a time (ExactTests), in member order, each batch taking
    // the members still within the limit of the best the batches before it left.
    ExactTests exact;
    float g2[kNearMax];
    std::uint64_t mask[kNearMaskWords];
    const std::uint32_t words = ns.within(q_lo, q_hi, float_up(box_prefilter_limit(lim2)), g2, mask);
    for (std::uint32_t w = 0; w < words; ++w)
      for (std::uint64_t bits = mask[w]; bits; bits &= bits - 1) {
        const unsigned j = 64 * w + unsigned(__builtin_ctzll(bits));
        if (double(g2[j]) > box_prefilter_limit(lim2)) continue;  // the limit follows the best down
        const LeafTri& t = tris[ns.k[j]];
        if (t.tri() == seed) continue;
        add_exact(exact, t, ns.k[j], ns.leaf[j], ns.node[j]);
      }
    finish_exact(exact);
    ++counters.near_served;
    counters.near_tested += ns.n;
    return true;
  }

  /// The leaf-cell search, in place of the descent from `start` (narrowed_start): when the cube
  /// about p of half-width best + tol (its faces in double; tol covers their rounding) lies in
  /// at most 2 leaf-grid cells per axis, every triangle within best of p is listed in the leaf
  /// of one of them that meets the ball (the distribution lists a triangle in every leaf whose
  /// closed cell it touches; empty nodes have none). Those leaves, nearest first, are then the
  /// whole search: each located under `start` by its cell's bits, with no node bound. Returns
  /// false (nothing done) otherwise, or when one of those cells is not under `start` (a page's
  /// subtree that does not hold the ball).
  bool leaf_cells_search(const StackItem& start) {
    if (!(B.best < std::numeric_limits<double>::infinity())) return false;
    const double r = B.best + tol;
    std::uint32_t r0[3], r1[3];
    if (!t_.leaf_cells_holding(p - Vec3d(r, r, r), p + Vec3d(r, r, r), r0, r1)) return false;
    // the cells that meet the ball, nearest first; each under `start`
    const int L = t_.leaf_level;
    const double cs = t_.cell_size(L);
    std::uint32_t sx, sy, sz;
    octcode_cell(nodes[start.node].code, &sx, &sy, &sz);
    const int below = L - start.level;
    struct Cell {
      double d2;
      std::uint32_t x, y, z;
    } cells[8];
    int nc = 0;
    for (std::uint32_t z = r0[2]; z <= r1[2]; ++z)
      for (std::uint32_t y = r0[1]; y <= r1[1]; ++y)
        for (std::uint32_t x = r0[0]; x <= r1[0]; ++x) {
          const Vec3d lo{t_.root_lo[0] + double(x) * cs, t_.root_lo[1] + double(y) * cs, t_.root_lo[2] + double(z) * cs};
          const double d2 = cell_d2(lo, cs, p);
          if (d2 > lim2) continue;
          if ((x >> below) != sx || (y >> below) != sy || (z >> below) != sz) return false;
          int i = nc++;
          for (; i > 0 && cells[i - 1].d2 > d2; --i) cells[i] = cells[i - 1];
          cells[i] = {d2, x, y, z};
        }
    for (int c = 0; c < nc; ++c) {
      if (cells[c].d2 > lim2) break;  // the best has come down
      // the cell's node under the start; the walk down counts its nodes
      const std::uint32_t ni = t_.locate_cell(cells[c].x, cells[c].y, cells[c].z, start.node);
      const Node& nd = nodes[ni];
      counters.nodes_visited += std::uint64_t(octcode_level(nd.code) - start.level);
      if (nd.kind != NodeKind::leaf || leaf_stamp_[nd.index] == qid) continue;  // empty: no triangle meets it
      scan_node = ni;
      scan_leaf(nd.index, leaf_hint(nd));
    }
    return true;
  }

  /// The radius a near set gathered now must hold: the ball (p, best + tol).
  double ball_radius() const { return B.best + tol; }

  /// Whether a node's lower bound prunes it: everything in it is farther than best + tol, so
  /// strictly farther than the best triangle's true distance (the sign from the closest face
  /// relies on that: face_sides.hpp).
  bool beyond(double bound) const { return bound > B.best + tol; }

  /// The descent: from the narrowed start, nodes popped nearest first, children ordered by bound.
  void descend() {
    StackItem stack[8 * (kMaxLevel + 2)];
    int sp = 0;
    const StackItem start = narrowed_start();
    if (leaf_cells_search(start)) return;
    stack[sp++] = start;
    while (sp > 0) {
      const StackItem it = stack[--sp];
      if (beyond(it.bound)) continue;
      const Node& nd = nodes[it.node];
      ++counters.nodes_visited;
      if (nd.kind == NodeKind::leaf) {
        if (leaf_stamp_[nd.index] == qid) continue;
        scan_node = it.node;
        scan_leaf(nd.index, leaf_hint(nd));
        continue;
      }
      if (nd.kind != NodeKind::inner) continue;
      // Inner: children ordered by bound, nearest popped first.
      const int cl = it.level + 1;
      const double csz = t_.cell_size(cl);
      StackItem kids[8];
      int nk = 0;
      for (int o = 0; o < 8; ++o) {
        const std::uint32_t ci = t_.children[nd.index + std::uint32_t(o)];
        const Node& cn = nodes[ci];
        if (cn.kind == NodeKind::white || cn.kind == NodeKind::black) continue;
        const Vec3d lo = child_corner(Vec3d{it.lo.x, it.lo.y, it.lo.z}, csz, o);
        const double b = node_bound(ci, lo, csz);
        if (beyond(b)) continue;
        kids[nk++] = {corner(lo), b, ci, cl};
      }
      push_nearest_first(kids, nk, stack, sp);
    }
  }

 private:
  /// The exact closest point of LeafTri k (found in `leaf`), once per input triangle and query;
  /// the best becomes it if it is smaller by (squared distance, key).
  void test_triangle(std::uint32_t k, std::uint32_t leaf) {
    const LeafTri& t = tris[k];
    if (first_test(t)) evaluate(t, k, leaf);
  }

  /// Whether this is the query's first test of t's input triangle (a triangle listed in several
  /// leaves is tested once); marks it tested.
  bool first_test(const LeafTri& t) {
    if (stamp_[t.tri()] == qid) return false;
    stamp_[t.tri()] = qid;
    return true;
  }

  /// Exact tests waiting to run as one batch of the closest_points kernel: its four-lane double
  /// code has none of the scalar test's data-dependent branches, whose mispredictions cost more
  /// than the instructions (4M bunny contact: 2.5 % fewer instructions, 13 % less time).
  struct ExactTests {
    const LeafTri* t[4];
    std::uint32_t k[4], leaf[4], node[4];
    unsigned m = 0;
  };

  /// Queues the exact test of LeafTri t = tris[k] (of `leaf`, under `node`); a full batch runs.
  void add_exact(ExactTests& e, const LeafTri& t, std::uint32_t k, std::uint32_t leaf, std::uint32_t node) {
    e.t[e.m] = &t;
    e.k[e.m] = k;
    e.leaf[e.m] = leaf;
    e.node[e.m] = node;
    if (++e.m == 4) finish_exact(e);
  }

  /// Runs the queued tests and offers their closest points in the order they were queued (a lone
  /// one by the scalar test, cheaper than a batch).
  void finish_exact(ExactTests& e) {
    if (e.m == 1) {
      scan_node = e.node[0];
      evaluate(*e.t[0], e.k[0], e.leaf[0]);
    } else if (e.m > 1) {
      Vec3d q[4];
      double d2[4];
      leaf_kernel_table().closest_points(p, e.t, e.m, q, d2);
      for (unsigned i = 0; i < e.m; ++i) {
        scan_node = e.node[i];
        offer(*e.t[i], e.k[i], e.leaf[i], q[i], d2[i]);
      }
    }
    e.m = 0;
  }

  /// test_triangle's work after the once-per-query check: the exact closest point, and the best
  /// or the renewal's collector. The key (a load from an array over all triangles, out of core)
  /// is read only when it can decide.
  void evaluate(const LeafTri& t, std::uint32_t k, std::uint32_t leaf) {
    double d2;
    const Vec3d q = exact_closest_point(p, t, &d2);
    offer(t, k, leaf, q, d2);
  }

  /// evaluate's work after the exact closest point q of LeafTri k (its squared distance d2).
  void offer(const LeafTri& t, std::uint32_t k, std::uint32_t leaf, const Vec3d& q, double d2) {
    ++counters.triangles_tested;
    if (B.collect) {  // a certificate's renewal: the collector keeps it and sets the prune radius
      const std::uint64_t key = key_of ? key_of[t.tri()] : t.tri();
      B.best = B.collect->offer(d2, q, key, t, TriangleSite{B.collect_page, k, leaf, scan_node});
      B.best2 = B.best * B.best;  // the prune radius, for the triangles' box test
      lim2 = (B.best + tol) * (B.best + tol);
      return;
    }
    if (!(d2 <= B.best2)) {  // (a NaN never wins, and spoils the runner-up's margin)
      if (!(d2 >= B.runner2)) B.runner2 = d2;
      return;
    }
    const std::uint64_t key = key_of ? key_of[t.tri()] : t.tri();
    if (d2 < B.best2 || key < B.key) {
      B.runner2 = std::min(B.runner2, B.best2);  // the best so far (or the bound it started from)
      B.best2 = d2;
      B.best = std::sqrt(d2);
      B.key = key;
      B.k = k;
      B.leaf = leaf;
      B.node = scan_node;
      B.closest = q;
      lim2 = (B.best + tol) * (B.best + tol);
    } else {
      B.runner2 = d2;  // a tie lost on the key
    }
  }

  /// A leaf's scan: its blocks' boxes first, nearest first, stopping at the first block whose box
  /// is strictly farther than the best (they are sorted); in a surviving block, the triangle
  /// tests, then the exact closest point. A leaf is scanned once per query (everything a scan
  /// skipped was strictly worse than the best then, and the best only decreases).
  void scan_leaf(std::uint32_t li, const PlaneHint& hn) {
    if (leaf_stamp_[li] == qid) return;
    leaf_stamp_[li] = qid;
    const Leaf& lf = leaves[li];
    const float px = float(p.x - double(lf.centre[0])), py = float(p.y - double(lf.centre[1])),
                pz = float(p.z - double(lf.centre[2]));
    // lf.eps bounds the error of a face-plane distance for points near the leaf; the error
    // grows with p's distance from the leaf centre (the rounding of px, py, pz and of the
    // products, and the quantized normal's direction: face_normal.hpp), so far points get the
    // extra term, or they could lose their closest triangle.
    const double eps_p = double(lf.eps) + kPlaneEpsGrowth * (double(std::fabs(px)) + double(std::fabs(py)) +
                                                              double(std::fabs(pz)));
    point_bounds();
    const LeafPoint lp{li, lf, {px, py, pz}, eps_p};
    // With no bound yet (the first leaf of a search without a seed), one pass of box distances,
    // then the block whose box is nearest p first: its triangles give a bound, so that the
    // other blocks, ordered from the same distances, are taken only if they can still win,
    // instead of all being ordered against an infinite bound.
    std::uint32_t first = UINT32_MAX;
    const double* pre_d2 = nullptr;
    if (!(lim2 < std::numeric_limits<double>::infinity())) {
      const std::uint32_t nb = block_count(lf.tri_count);
      const BlockBox* bb = blocks + t_.leaf_block[li];
      double* d2s = block_d2_.data();
      double nearest = std::numeric_limits<double>::infinity();
      leaf_kernel_table().box_distances(bb, nb, p, d2s);
      for (std::uint32_t j = 0; j < nb; ++j)
        if (d2s[j] < nearest) { nearest = d2s[j]; first = j; }
      counters.planes_tested += nb;
      if (first != UINT32_MAX) scan_block(lp, first);
      pre_d2 = d2s;  // the other blocks are ordered from these distances: no second pass
    }
    const std::uint32_t m = order_blocks(li, lf, hn, pre_d2, first);
    std::pair<double, std::uint32_t>* ord = order_.data();
    // The surviving blocks' triangles are usually cold (random points): ask for all of them now,
    // so that the misses overlap instead of being paid one block after the other.
    for (std::uint32_t i = 0; i < m && i < 4; ++i) {
      const char* a = reinterpret_cast<const char*>(tris + lf.tri_begin + ord[i].second * kBlockTris);
      for (std::uint32_t l = 0; l < kBlockTris; ++l) __builtin_prefetch(a + 64 * l);
    }
    for (std::uint32_t i = 0; i < m; ++i) {
      if (ord[i].first > lim2) break;
      scan_block(lp, ord[i].second);
    }
  }

  /// What a leaf's scan knows of p: the leaf, p in its frame, and the bound of a face-plane
  /// value's float error there.
  struct LeafPoint {
    std::uint32_t li;
    const Leaf& lf;
    float pl[3];
    double eps_p;
  };

  /// Block j of a leaf: its triangles go through the pre-filter (8 at a time: face plane and box
  /// in float, with margins), each survivor's two values are compared again with the limits of
  /// the best as it is when its turn comes (the block's earlier triangles may have lowered it),
  /// and the rest get the exact closest point. A sharper bound per triangle (the face plane with
  /// the vertices' bounding sphere, as node_bound has for nodes) pruned a few more triangles but
  /// cost more than their exact closest points (HISTORY.md, "The triangle's sphere bound").
  void scan_block(const LeafPoint& lp, std::uint32_t j) {
    const std::uint32_t k0 = lp.lf.tri_begin + j * kBlockTris;
    const std::uint32_t k1 = std::min(k0 + kBlockTris, lp.lf.tri_begin + lp.lf.tri_count);
    counters.planes_tested += k1 - k0;
    update_limits(lp.eps_p);
    float plane_abs[8], box_d2[8];
    unsigned bits = leaf_kernel_table().distance_pass(tris + k0, k1 - k0, lp.pl, q_lo, q_hi, plane_lim_, box_lim_,
                                                      plane_abs, box_d2);
    if (!(B.best < std::numeric_limits<double>::infinity())) {
      // No bound yet (the first block of a search without one; the pass kept every triangle):
      // the triangle nearest p by its box, then by its face plane, first, so that its exact
      // distance lets the others be pruned by the values the pass computed.
      unsigned i0 = 0;
      for (unsigned i = 1; i < k1 - k0; ++i)
        if (box_d2[i] < box_d2[i0] || (box_d2[i] == box_d2[i0] && plane_abs[i] < plane_abs[i0])) i0 = i;
      test_triangle(k0 + i0, lp.li);
      bits &= ~(1u << i0);
    }
    // the survivors' exact tests in batches (ExactTests), once per input triangle and query
    ExactTests exact;
    for (; bits; bits &= bits - 1) {
      const unsigned i = unsigned(__builtin_ctz(bits));
      update_limits(lp.eps_p);
      if (plane_abs[i] > plane_lim_ || box_d2[i] > box_lim_) continue;
      const LeafTri& t = tris[k0 + i];
      if (first_test(t)) add_exact(exact, t, k0 + i, lp.li, scan_node);
    }
    finish_exact(exact);
  }

  /// q_lo, q_hi: once per search, and only for a search that tests boxes by them (a page's
  /// search often does not).
  void point_bounds() {
    if (q_bounds_) return;
    for (int a = 0; a < 3; ++a) float_bounds_near(p[a], &q_lo[a], &q_hi[a]);
    q_bounds_ = true;
  }

  /// The pre-filter's limits (distance_prefilter_limits) for the best as it is now and the
  /// leaf's face-plane error bound eps_p, computed again only when either has moved.
  void update_limits(double eps_p) {
    if (B.best == limits_for_ && eps_p == limits_eps_) return;
    distance_prefilter_limits(B.best + tol, lim2, eps_p, &plane_lim_, &box_lim_);
    limits_for_ = B.best;
    limits_eps_ = eps_p;
  }

  /// The groups of leaf li whose boxes meet the box [lo, hi], a bit each (a leaf of more than 32
  /// groups has them all taken as live).
  unsigned group_pass(std::uint32_t li, std::uint32_t ng, const float lo[3], const float hi[3]) {
    if (ng > 32) return ~0u;
    const BlockBox* gb = t_.groups.data() + t_.leaf_group[li];
    const LeafKernelTable& kt = leaf_kernel_table();
    unsigned live = 0;
    for (std::uint32_t g0 = 0; g0 < ng; g0 += 8)
      live |= kt.block_pass(gb + g0, std::min<std::uint32_t>(8, ng - g0), lo, hi) << g0;
    counters.planes_tested += ng;
    return live;
  }

  /// The blocks of leaf `li` not pruned by their box (and the leaf's plane hint), into order_ by
  /// ascending (bound, block): a deterministic order. Returns how many. `pre_d2`, if given, holds
  /// every block's squared box distance already (the located start's first pass), and block
  /// `skip` is left out (scanned already).
  std::uint32_t order_blocks(std::uint32_t li, const Leaf& lf, const PlaneHint& hn, const double* pre_d2 = nullptr,
                             std::uint32_t skip = UINT32_MAX) {
    const std::uint32_t nb = block_count(lf.tri_count);
    const BlockBox* bb = blocks + t_.leaf_block[li];
    std::pair<double, std::uint32_t>* ord = order_.data();
    std::uint32_t m = 0;
    auto consider = [&](std::uint32_t j, double d2) {
      if (d2 > lim2) return;
      if (hn.h > 0) {
        // The leaf's plane and the block box's bounding sphere (as node_bound does for nodes):
        // a bound of the distance to the block's triangles within this leaf's cell, which is
        // all this leaf stands for.
        const BlockBox& x = bb[j];
        const double ex = double(x.hi[0]) - double(x.lo[0]), ey = double(x.hi[1]) - double(x.lo[1]),
                     ez = double(x.hi[2]) - double(x.lo[2]);
        const double rho = 0.5 * std::sqrt(ex * ex + ey * ey + ez * ez) * (1.0 + 1e-12);
        const double qx = p.x - 0.5 * (double(x.lo[0]) + double(x.hi[0])), qy = p.y - 0.5 * (double(x.lo[1]) + double(x.hi[1])),
                     qz = p.z - 0.5 * (double(x.lo[2]) + double(x.hi[2]));
        const double q2 = qx * qx + qy * qy + qz * qz, qn = qx * hn.n[0] + qy * hn.n[1] + qz * hn.n[2];
        const double tan2 = q2 - qn * qn * (1.0 + 1e-6);  // |n|^2 >= 1 - 1e-6, as for triangles
        if (tan2 > rho * rho) {
          const double tl = std::sqrt(tan2) - rho;
          const double cb = std::sqrt(hn.h * hn.h + tl * tl) - (1e-6 * (std::sqrt(q2) + rho) + tol);
          if (cb > 0) d2 = std::max(d2, cb * cb);
          if (d2 > lim2) return;
        }
      }
      // insertion, ascending (distance, block): a deterministic order
      std::uint32_t i = m++;
      while (i > 0 && ord[i - 1].first > d2) { ord[i] = ord[i - 1]; --i; }
      ord[i] = {d2, j};
    };
    if (pre_d2) {
      for (std::uint32_t j = 0; j < nb; ++j)
        if (j != skip) consider(j, pre_d2[j]);
      return m;
    }
    counters.planes_tested += nb;
    // With a finite best, the blocks first go 8 at a time through the block-box kernel against
    // the box of the ball (p, best + tol) rounded outwards to float: a block outside it is
    // farther than best + tol on one axis, so the scalar bound below would prune it too (up to
    // a tie at exactly best + tol, where pruning is still exact). The scalar bound then runs on
    // the few blocks near p only.
    const bool cull = lim2 < std::numeric_limits<double>::infinity();
    float ball_lo[3], ball_hi[3];
    bool small_ball = false;  // under the leaf cell: a group can be apart from it (far balls meet all)
    if (cull) {
      const double r = B.best + tol;
      small_ball = r < t_.cell_size(t_.leaf_level);
      float unused;
      for (int a = 0; a < 3; ++a) {
        float_bounds(p[a] - r, &ball_lo[a], &unused);
        float_bounds(p[a] + r, &unused, &ball_hi[a]);
      }
    }
    const LeafKernelTable& kt = leaf_kernel_table();
    // A leaf of more than a group's blocks: its groups' boxes first, against the same box.
    static_assert(kGroupBlocks == 8, "a group's blocks are one pass of the block kernel");
    const std::uint32_t ng = group_count(nb);
    const unsigned live_groups = small_ball && ng > 1 && !t_.leaf_group.empty() ? group_pass(li, ng, ball_lo, ball_hi) : ~0u;
    for (std::uint32_t j0 = 0; j0 < nb; j0 += 8) {
      const std::uint32_t g = j0 / kGroupBlocks;
      if (g < 32 && !((live_groups >> g) & 1u)) continue;
      const unsigned w = std::min<std::uint32_t>(8, nb - j0);
      for (unsigned live = cull ? kt.block_pass(bb + j0, w, ball_lo, ball_hi) : (1u << w) - 1; live;
           live &= live - 1) {
        const std::uint32_t j = j0 + unsigned(__builtin_ctz(live));
        consider(j, box_d2(bb[j], p));
      }
    }
    return m;
  }

  /// A leaf's most separating plane at p, for the block bounds of its scan.
  PlaneHint leaf_hint(const Node& nd) {
    PlaneHint hn;
    float m = -std::numeric_limits<float>::infinity();
    const Plane* pl = planes + nd.plane_begin;
    for (std::uint32_t k = 0; k < nd.plane_count; ++k) {
      const float v = pl[k].n[0] * fx + pl[k].n[1] * fy + pl[k].n[2] * fz - pl[k].d;
      if (v > m) {
        m = v;
        hn.n[0] = double(pl[k].n[0]); hn.n[1] = double(pl[k].n[1]); hn.n[2] = double(pl[k].n[2]);
      }
    }
    counters.planes_tested += nd.plane_count;
    hn.h = double(m) - slack;
    return hn;
  }

  /// A node's lower bound: its cell box, then the box of its geometry, then its planes; each
  /// stage only when the previous ones do not already prune it.
  double node_bound(std::uint32_t ni, const Vec3d& lo, double size) {
    const double d2 = cell_d2(lo, size, p);
    double b = d2 > 0 ? std::sqrt(d2) : 0.0;
    if (beyond(b)) return b;  // pruned by the box alone: the planes could only raise the bound
    const double g2 = box_d2(nbox[ni], p);
    if (g2 > d2) {
      b = std::max(b, std::sqrt(g2) - tol);
      if (beyond(b)) return b;
    }
    const Node& nd = nodes[ni];
    float m = -std::numeric_limits<float>::infinity();
    std::uint32_t km = 0;
    const Plane* pl = planes + nd.plane_begin;
    for (std::uint32_t k = 0; k < nd.plane_count; ++k) {
      const float v = pl[k].n[0] * fx + pl[k].n[1] * fy + pl[k].n[2] * fz - pl[k].d;
      if (v > m) { m = v; km = k; }
    }
    counters.planes_tested += nd.plane_count;
    const double h = double(m) - slack;
    b = std::max(b, h);
    if (beyond(b) || h <= 0) return b;
    // The most separating plane and the node box's bounding sphere (centre c, radius rho)
    // together: every point y of the geometry has n.(p - y) >= h and |y - c| <= rho, so its
    // component of p - y across n is >= |tangential part of (p - c)| - rho, and
    // |p - y|^2 >= h^2 + that^2. On a flat or gently curved patch seen from afar (every plane
    // and box bound about the distance) this is the bound that grows away from the foot of p.
    // `h` already carries the plane's slack; the rest (float normal not exactly unit, the
    // rounding of this double computation) is covered by 1e-6 (|p - c| + rho) + tol.
    const BlockBox& bx = nbox[ni];
    const double cx = 0.5 * (double(bx.lo[0]) + double(bx.hi[0])), cy = 0.5 * (double(bx.lo[1]) + double(bx.hi[1])),
                 cz = 0.5 * (double(bx.lo[2]) + double(bx.hi[2]));
    const double ex = double(bx.hi[0]) - double(bx.lo[0]), ey = double(bx.hi[1]) - double(bx.lo[1]),
                 ez = double(bx.hi[2]) - double(bx.lo[2]);
    if (!(ex >= 0 && ey >= 0 && ez >= 0) || !std::isfinite(ex + ey + ez)) return b;  // empty / no box
    const double rho = 0.5 * std::sqrt(ex * ex + ey * ey + ez * ez);
    const double nx = double(pl[km].n[0]), ny = double(pl[km].n[1]), nz = double(pl[km].n[2]);
    const double qx = p.x - cx, qy = p.y - cy, qz = p.z - cz;
    const double q2 = qx * qx + qy * qy + qz * qz, qn = qx * nx + qy * ny + qz * nz;
    const double tan2 = q2 - qn * qn * (1.0 + 1e-6);  // |n|^2 >= 1 - 1e-6: a lower bound, no division
    if (!(tan2 > rho * rho)) return b;
    const double tl = std::sqrt(tan2) - rho;
    return std::max(b, std::sqrt(h * h + tl * tl) - (1e-6 * (std::sqrt(q2) + rho) + tol));
  }

  /// The node the descent starts from: s.node, or, with a finite best (a seed, or the bound
  /// passed in), the deepest node on p's path whose cell holds the ball (p, best + tol) strictly
  /// inside: all geometry outside that cell is strictly farther than the best, so nothing it
  /// could win is lost.
  StackItem narrowed_start() {
    std::uint32_t start = s.node;
    Vec3d lo = t_.root_lo, hi;
    double size = t_.root_size;
    int level = 0;
    if (start != 0) {
      t_.cell_box(nodes[start].code, &lo, &hi);
      level = octcode_level(nodes[start].code);
      size = t_.cell_size(level);
    }
    if (B.best < std::numeric_limits<double>::infinity()) {
      const double r = B.best + tol;
      auto holds = [&](const Vec3d& c, double sz) { return cell_holds_ball(c, sz, p, r); };
      if (holds(lo, size)) {
        // The last walk from this subtree root, resumed at its deepest cell that holds the ball
        // (on a coherent path, usually the seed leaf's cell or its parent's): the levels above
        // are not walked again. Then down from there as far as the cells hold it.
        int depth = 0;
        if (walk.root == s.node) {
          for (int i = walk.len - 1; i >= 1; --i)
            if (holds(walk.lo[i], t_.cell_size(level + i))) {
              depth = i;
              break;
            }
          if (depth > 0) {
            start = walk.node[depth];
            lo = walk.lo[depth];
            level += depth;
            size = t_.cell_size(level);
          }
        } else {
          walk.root = s.node;
          walk.node[0] = s.node;
          walk.lo[0] = lo;
        }
        walk.len = depth + 1;
        while (nodes[start].kind == NodeKind::inner) {
          const double csz = t_.cell_size(level + 1);
          const int o = child_octant(p, lo, csz);
          const Vec3d clo = child_corner(lo, csz, o);
          const std::uint32_t ci = t_.children[nodes[start].index + std::uint32_t(o)];
          const NodeKind ck = nodes[ci].kind;
          if ((ck != NodeKind::inner && ck != NodeKind::leaf) || !holds(clo, csz)) break;
          ++counters.nodes_visited;
          start = ci;
          lo = clo;
          size = csz;
          ++level;
          walk.node[walk.len] = ci;
          walk.lo[walk.len] = clo;
          ++walk.len;
        }
      }
    }
    return {corner(lo), node_bound(start, lo, size), start, level};
  }

  const Vec3d& p;
  DistanceBest& B;
  const DistanceStart& s;
  const Octree& t_;
  QueryCounters& counters;
  Walk& walk;
  std::vector<std::uint32_t>& stamp_;
  std::vector<std::uint32_t>& leaf_stamp_;
  std::vector<std::pair<double, std::uint32_t>>& order_;
  std::vector<double>& block_d2_;
  const std::uint32_t qid;
  const LeafTri* const tris;
  const std::uint32_t* const key_of;
  const Leaf* const leaves;
  const BlockBox* const blocks;
  const Plane* const planes;
  const Node* const nodes;
  const BlockBox* const nbox;
  double tol = 0;
  double lim2 = std::numeric_limits<double>::infinity();  ///< (best + tol)^2
  float fx = 0, fy = 0, fz = 0;  ///< p in the root's frame, in float (the planes' frame)
  float q_lo[3], q_hi[3];        ///< floats about p, at most 3 beyond the tightest (the pre-filter's boxes)
  bool q_bounds_ = false;        ///< q_lo, q_hi computed
  // the triangle pre-filter's limits (distance_prefilter_limits), for the best and the leaf
  // (eps_p) they were computed for
  double limits_for_ = -1, limits_eps_ = -1;
  float plane_lim_ = 0, box_lim_ = 0;
  double slack = 0;
  std::uint32_t scan_node = UINT32_MAX;  ///< the node of the leaf being scanned, if known
};

void Query::distance_bound(const Vec3d& p, DistanceBest& B, const DistanceStart& s) {
  if (++query_id_ == 0) {  // wrapped: forget every stamp
    std::fill(stamp_.begin(), stamp_.end(), 0u);
    std::fill(leaf_stamp_.begin(), leaf_stamp_.end(), 0u);
    query_id_ = 1;
  }
  B.k = B.leaf = B.node = UINT32_MAX;
  DistanceSearch search(*this, p, B, s);
  // The near start: a coherent search of this tree's whole geometry for its own best (not a
  // renewal's collection, whose prune radius is the collector's).
  B.near_certified = false;
  const bool near = coherent_ && s.near && !B.collect;
  bool gathered_first = false;
  if (near) {
    dmove_ = dprev_ok_ ? p - dprev_p_ : Vec3d(0, 0, 0);
    dprev_p_ = p;
    dprev_ok_ = true;
    search.seed_triangle();
    if (dnear_ && search.near_start(*dnear_)) {
      ++dnear_served_;
      B.near_certified = true;
      return;
    }
    // Not held, while the path's sets serve (the last one served a search besides the one it
    // was gathered for): a new set about the seed's ball (the previous closest triangle bounds
    // this search's distance, so the ball holds the answer), and the search from it, before
    // any tree search. Otherwise (the path's first sets, or sets that did not serve: far from
    // the surface, or jumping) the tree search first, and a set about its ball after it.
    gathered_first = dnear_served_ > (dnear_first_ ? 1u : 0u);
    if (gathered_first && gather_distance_near(p, search.ball_radius(), true) && search.near_start(*dnear_)) {
      ++dnear_served_;
      B.near_certified = true;
      return;
    }
    search.seed_leaf();
  } else {
    search.coherent_start();
  }
  search.located_start();
  search.descend();
  if (near && !gathered_first) gather_distance_near(p, search.ball_radius(), false);
}

}  // namespace ebp
