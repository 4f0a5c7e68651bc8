#pragma once
/// The queries over a built Octree (query.cpp): the
/// per-thread query state, its work counters, the distance answer and the running best that the
/// out-of-core query carries from page to page.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "methods/ebp_octree/core/near_set.hpp"
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

/// Work counters of the queries (deterministic).
struct QueryCounters {
  std::uint64_t nodes_visited = 0, planes_tested = 0, triangles_tested = 0;
  std::uint64_t hit_white = 0, hit_black = 0, hit_convex = 0, hit_concave = 0, hit_special = 0;
  std::uint64_t exact_fallbacks = 0;  ///< parity retried with another reference point
  // the coherent distance path (certificate.hpp)
  std::uint64_t certificate_renewals = 0;  ///< relaxed branch and bounds that renewed the certificate
  std::uint64_t certificate_served = 0;    ///< distance queries answered by a scan of the certificate
  std::uint64_t signs_chained = 0;         ///< signs taken from the previous query (no inside test)
  std::uint64_t signs_from_face = 0;       ///< signs taken from the closest face (face_sides.hpp; no inside test)
  // the coherent distance's near start (near_set.hpp, DESIGN.md "Distance in contact")
  std::uint64_t near_served = 0;    ///< searches answered from the near set (no descent)
  std::uint64_t near_gathered = 0;  ///< near sets gathered or attempted (after a search the set did not hold)
  std::uint64_t near_tested = 0;    ///< near set members compared with a search's ball
};

class DistanceCertificate;
class CertifiedPath;
enum class ScanKernel;

struct DistanceAnswer {
  double distance = 0;  ///< signed, negative inside
  Vec3d closest, normal;
  std::int64_t triangle = -1;
};

/// The running best of a distance query, possibly over several trees (the out-of-core pages):
/// the lexicographic minimum of (squared distance, key), key = input triangle index.
struct DistanceBest {
  double best2 = std::numeric_limits<double>::infinity();
  double best = std::numeric_limits<double>::infinity();
  std::uint64_t key = UINT64_MAX;
  Vec3d closest;
  std::uint32_t k = UINT32_MAX;     ///< LeafTri index of the best, if the last call found it in its tree
  std::uint32_t leaf = UINT32_MAX;  ///< and the leaf it was found in
  std::uint32_t node = UINT32_MAX;  ///< and that leaf's node, if known
  /// The least squared distance of the other triangles tested (+inf if none), the best's own
  /// ties included. A search prunes only what is farther than best + tol (search_tol), so when
  /// this exceeds (best + 2 tol)^2 the best is the one triangle nearest p, strictly.
  double runner2 = std::numeric_limits<double>::infinity();
  /// A certificate's renewal (certificate.hpp): every triangle tested is offered to `collect`
  /// (found in page `collect_page`) instead of updating the best, and the prune radius is the
  /// collector's (best holds it); the caller takes the answer from the collector.
  DistanceCertificate* collect = nullptr;
  std::uint32_t collect_page = UINT32_MAX;
  /// Set by a search answered by its near start (DistanceStart::near): every triangle of the
  /// whole mesh within the best lies in the near set's box, which lies in this tree's own leaf
  /// cells, so no other tree (out-of-core page) can hold a better one.
  bool near_certified = false;
};

/// The rounding bound of a distance search at p in a tree whose root cube is (root_lo,
/// root_size): added to the best distance before a box prunes, it covers the rounding of the box
/// distance and of the exact closest point (a few ulps of the coordinates), so a box is only
/// pruned when everything in it is strictly worse than the best. The in-memory search and the
/// out-of-core top tree use the same.
inline double search_tol(const Vec3d& p, const Vec3d& root_lo, double root_size) {
  return 1e-12 * (std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) +
                  std::max({std::fabs(root_lo.x), std::fabs(root_lo.y), std::fabs(root_lo.z)}) + root_size);
}

/// Whether the cube [lo, lo + size] holds the ball (p, r) strictly inside (the narrowed starts:
/// all geometry outside such a cell is strictly farther than r).
inline bool cell_holds_ball(const Vec3d& lo, double size, const Vec3d& p, double r) {
  return p.x - lo.x > r && p.y - lo.y > r && p.z - lo.z > r && lo.x + size - p.x > r && lo.y + size - p.y > r &&
         lo.z + size - p.z > r;
}

/// Whether a step of length `step` (the largest coordinate difference) from a point at distance
/// `prev_d` from the surface is a jump on a coherent distance path: longer than the leaf cell
/// `leaf_cell` and than the distance itself. The previous closest triangle bounds the next
/// distance by the true one plus at most twice the step (triangle inequality): a tight start
/// over a short step, a loose one over a jump (random points, a path that starts again
/// elsewhere), where it would also cost the scan of its leaf and stop the located start (which
/// runs only with no bound yet). Answers do not depend on the choice.
inline bool is_jump(double step, double prev_d, double leaf_cell) { return step > std::max(leaf_cell, prev_d); }

/// The step from prev to p, as is_jump measures it.
inline double step_length(const Vec3d& p, const Vec3d& prev) {
  return std::max({std::fabs(p.x - prev.x), std::fabs(p.y - prev.y), std::fabs(p.z - prev.z)});
}

/// Where and how Query::distance_bound starts.
struct DistanceStart {
  const std::uint32_t* key_of = nullptr;  ///< LeafTri::tri -> key (increasing); null: key = tri
  std::uint32_t seed_tri = UINT32_MAX;    ///< a LeafTri index tested first (a valid upper bound)
  std::uint32_t seed_leaf = UINT32_MAX;   ///< a leaf scanned before the descent
  std::uint32_t seed_node = UINT32_MAX;   ///< its node, if known (its planes then bound the blocks)
  std::uint32_t node = 0;                 ///< the subtree searched (its whole geometry)
  /// The near start may answer (on a coherent query state): the caller wants the minimum over
  /// the tree's whole geometry (in memory the tree, out of core a page whose geometry is all in
  /// its subtree), not a subtree's.
  bool near = false;
};

/// Query state over a built Octree: per-query stamps, the coherent path state, counters.
/// One per thread. No allocation per query.
class Query {
 public:
  Query(const Octree& tree, bool coherent);
  ~Query();
  Query(Query&&) noexcept;
  bool inside(const Vec3d& p);
  DistanceAnswer distance(const Vec3d& p);
  /// Unsigned distance only (no inside test); fills closest/normal/triangle.
  DistanceAnswer unsigned_distance(const Vec3d& p);
  /// Branch and bound over the subtree `s.node`, starting from the running best `b` (an upper
  /// bound, ties kept: only what is strictly worse than it is pruned). `b` becomes the minimum of
  /// itself and the subtree's triangles, by (squared distance, key); b.k / b.leaf are set if one
  /// of this tree's triangles is the new best, UINT32_MAX otherwise. With the initial bound
  /// >= the true distance, the answer is the one without it, bit for bit.
  void distance_bound(const Vec3d& p, DistanceBest& b, const DistanceStart& s);
  void reset_path();
  /// Coherent distance only (both on by default): answer from a certificate while the probe
  /// stays in its ball (certificate.hpp), and take the sign from the previous query when the
  /// probe stays in the ball where no surface is (closed meshes). Answers do not change.
  void set_certificate(bool on) { certificate_ = on; }
  void set_chained_sign(bool on) { chained_sign_ = on; }
  /// Take the distance's sign from the closest face where it decides it exactly (on by
  /// default; face_sides.hpp), on searched answers and on those a certificate serves. Answers
  /// do not change.
  void set_face_sign(bool on) { face_sign_ = on; }
  /// true (default): certificates only where they cost less per query than plain searches
  /// (CertifiedPath::prefer_plain); false: always a certificate on the coherent path.
  void set_adaptive_certificate(bool on);
  /// The certificate's pre-test kernel (tests force the scalar one; must be supported).
  void set_scan_kernel(ScanKernel k);
  /// The heap this query's state holds: its stamps and scratch, its path, and room for the two
  /// near sets a coherent query allocates on first use (counted whether allocated yet or not,
  /// so that a budget that counts this is never exceeded later).
  std::size_t state_bytes() const;
  /// The coherent distance's current near set, if one was gathered (tests, diagnostics).
  const NearSet* distance_near_set() const { return dnear_.get(); }
  QueryCounters counters;

 private:
  class DistanceSearch;  // one distance_bound call, step by step (query_distance.cpp)
  DistanceAnswer searched_distance(const Vec3d& p);  // the branch and bound, seeded on a coherent path
  DistanceAnswer certified_distance(const Vec3d& p);  // from the certificate, or renewing it
  std::uint32_t locate(const Vec3d& p, bool* outside_root);
  bool classify_leaf(const Vec3d& p, const Leaf& leaf, std::uint32_t leaf_index, std::uint32_t node);
  const Octree& t_;
  bool coherent_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t query_id_ = 0;
  // coherent inside (closed meshes): the last point of the path whose winding number is known
  // exactly (see classify_leaf and DESIGN.md), and the triangles near the path: those whose
  // boxes meet the float box [lo, hi] around it, from every leaf whose cell meets it, each once,
  // with their boxes (near_set.hpp). A cache of derived data: answers do not depend on it.
  bool step_from_prev(const Vec3d& p, std::uint32_t leaf_node, int* w);
  bool gather_near(const Vec3d& s0, const Vec3d& s1, const Vec3d& step, std::uint32_t leaf_node);
  // The near sets are allocated on first use: an out-of-core page has a Query of its own, and
  // most pages never need one (9.2 KB each).
  static NearSet& allocated(std::unique_ptr<NearSet>& s) {
    if (!s) s = std::make_unique<NearSet>();
    return *s;
  }
  // A step's set holds up to 128 triangles, the limit it was measured with; the distance's up to
  // kNearMax (gather_distance_near: its limit follows the path's scale).
  static constexpr std::uint32_t kNearInsideMembers = 128;
  static bool holds(const std::unique_ptr<NearSet>& s, const float f0[3], const float f1[3]) {
    return s && s->holds(f0, f1);
  }
  std::unique_ptr<NearSet> near_;
  bool prev_ok_ = false;
  Vec3d prev_p_;
  int prev_w_ = 0;
  // coherent state
  std::uint32_t last_node_ = UINT32_MAX;
  std::uint32_t last_cell_[3] = {0, 0, 0};
  int last_level_ = 0;
  std::uint32_t last_tri_ = UINT32_MAX;  // LeafTri index of the previous closest triangle
  std::uint32_t last_leaf_ = UINT32_MAX;  // and the leaf where it was found
  std::uint32_t last_leaf_node_ = UINT32_MAX;  // and that leaf's node
  Vec3d last_p_;                             // the point it was closest to
  double last_d_ = 0;                        // at this distance
  /// Whether the search at p seeds from last_tri_: the step from last_p_ is no jump (is_jump).
  bool seed_pays_at(const Vec3d& p) const;
  /// The previous closest triangle (and its leaf and node) as the seed of a search at p, where
  /// that pays (seed_pays_at); `s` untouched otherwise.
  void seed_from_last(const Vec3d& p, DistanceStart& s) const;
  /// The path's last answer: triangle k, found in `leaf` of `node`, closest to p at distance d.
  void remember_closest(std::uint32_t k, std::uint32_t leaf, std::uint32_t node, const Vec3d& p, double d);
  // distance: the last narrowed start's walk (query_distance.cpp): from the subtree root `root`,
  // the node and cell corner at each level below it, so that the next search of a coherent path
  // resumes from the deepest of those cells that holds its ball instead of walking down from the
  // root again. A cache of the tree's own nodes: any node whose cell holds the ball is a valid
  // start, so answers do not depend on it.
  struct Walk {
    std::uint32_t root = UINT32_MAX;
    int len = 0;
    std::uint32_t node[kMaxLevel + 2];
    Vec3d lo[kMaxLevel + 2];
  };
  Walk walk_;
  // coherent distance: the near start's set, the triangles whose boxes meet a box about the last
  // gathering's ball (p, best) grown by the probe's step; a search whose ball lies in that box
  // tests only the members the ball's box meets, with no descent (DESIGN.md, "Distance in
  // contact"). A cache of the tree's own triangles: answers do not depend on it.
  bool gather_distance_near(const Vec3d& p, double r, bool first);
  std::unique_ptr<NearSet> dnear_;
  bool dprev_ok_ = false;
  Vec3d dprev_p_;
  Vec3d dmove_;                      ///< the last step of the path
  // the gathering's policy (gather_distance_near): the box's scale, the searches the current
  // set served, the sets in a row that served none, searches left before the next gathering
  double dnear_scale_ = 1.0;
  std::uint32_t dnear_served_ = 0, dnear_losses_ = 0;
  bool dnear_tried_ = false;
  bool dnear_first_ = false;  ///< the current set was gathered before its search's tree search (and served it)
  // queries of the path so far (in-memory unsigned_distance calls; an out-of-core page's
  // Query sees only its own searches) and their count when the current set was gathered
  std::uint64_t path_queries_ = 0, dnear_gathered_at_ = 0;
  std::uint32_t dnear_backoff_ = 0;
  // distance: leaves already scanned by this query, scratch for the block order and for the
  // blocks' box distances (the located start's leaf)
  std::vector<std::uint32_t> leaf_stamp_;
  std::vector<std::pair<double, std::uint32_t>> order_;
  std::vector<double> block_d2_;
  // coherent distance: the certificate, the probe's steps and the previous sign
  bool certificate_ = true, chained_sign_ = true;
  std::unique_ptr<CertifiedPath> path_;
  // the sign from the closest face: on; and the last unsigned distance's side of its closest
  // face where that face decides the sign (+1 outside, -1 inside), else 0
  bool face_sign_ = true;
  int face_side_ = 0;
  void take_face_side(const Vec3d& p, std::uint32_t k, double d, double runner2, double tol);
  /// The sign of p's distance (inside?) after its unsigned distance: from the closest face, the
  /// previous query's sign (chained) or the inside query.
  bool sign_after_distance(const Vec3d& p, double distance);
};

}  // namespace ebp
