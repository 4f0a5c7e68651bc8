#pragma once
/// The distance certificate of a coherent path (DESIGN.md, "Haptic distance by certificate"). A
/// renewal at p runs the branch and bound with its prune relaxed (Query::distance_bound with a
/// collector) and keeps S, every triangle within best + 2r of p, as copies of their float
/// geometry, input index and where they were found. For any q with |q - p| <= r the closest
/// triangle of the whole mesh is in S (the proof is in certificate.cpp), so the query at q is a
/// scan of S: a SIMD lower bound per triangle (certificate_scan.hpp) that only prunes, and the
/// exact closest point in double, with the same (squared distance, input index) tie rule as the
/// branch and bound, for the rest. Answers are therefore the branch and bound's, bit for bit.
///
/// The radius rule: r = min(r_max, max(kFloorFactor x step, (d_(K+1) - best) / 2)), r_max =
/// min(kStepFactor x step, kGrowth x the last certificate's r),
/// K = kNearest, step = the mean of the path's last kStepWindow steps, d_(K+1) the (K+1)-th
/// smallest triangle distance at p. The step cap keeps S small where triangles are large, the
/// K-nearest term where they are small, and the floor keeps r > 0 where K+1 triangles tie at a
/// vertex (DESIGN.md gives the measurements behind the constants).
#include <cmath>
#include <cstdint>
#include <vector>

#include "methods/ebp_octree/core/certificate_scan.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/query.hpp"

namespace ebp {

inline constexpr unsigned kNearest = 32;
inline constexpr double kStepFactor = 16.0;
inline constexpr double kFloorFactor = 0.5;
inline constexpr unsigned kStepWindow = 8;
inline constexpr double kAheadFactor = 0.8;
inline constexpr double kGrowth = 2.0;

/// The path's choice between certificates and plain searches is made on *work units*, a proxy of
/// instructions from the query's own counters (input alone sets them, so the choice is the same
/// on every machine): in a search an exact triangle test ~220 instructions, a plane, box or
/// triangle pre-test ~40, a node ~80, a near set's member compared with the ball ~4, a search the
/// near set served ~300 besides those (its ball's box, the candidates' order, the seed's
/// bookkeeping: callgrind, the 1M bunny's contact path, ~630 instructions a served search) and a
/// near set gathered ~2,500 (the same path: 2,300 instructions a gathering); in a certificate's
/// scan a member's 8-wide bound ~6.
struct Work {
  std::uint64_t triangles = 0, planes = 0, nodes = 0, near_tested = 0, near_gathered = 0, near_served = 0;
  Work& operator+=(const Work& o) {
    triangles += o.triangles;
    planes += o.planes;
    nodes += o.nodes;
    near_tested += o.near_tested;
    near_gathered += o.near_gathered;
    near_served += o.near_served;
    return *this;
  }
  friend Work operator+(Work a, const Work& b) { return a += b; }
  /// The work done between two readings of the same counters (b after a).
  friend Work operator-(const Work& b, const Work& a) {
    return {b.triangles - a.triangles, b.planes - a.planes, b.nodes - a.nodes,
            b.near_tested - a.near_tested, b.near_gathered - a.near_gathered, b.near_served - a.near_served};
  }
};
inline Work work_of(const QueryCounters& c) {
  return {c.triangles_tested, c.planes_tested, c.nodes_visited, c.near_tested, c.near_gathered, c.near_served};
}
inline double search_work(const Work& a, const Work& b) {
  const Work d = b - a;
  return 220.0 * double(d.triangles) + 40.0 * double(d.planes) + 80.0 * double(d.nodes) +
         4.0 * double(d.near_tested) + 2500.0 * double(d.near_gathered) + 300.0 * double(d.near_served);
}
inline double scan_work(const Work& a, const Work& b) {
  const Work d = b - a;
  return 220.0 * double(d.triangles) + 6.0 * double(d.planes);
}
/// A renewal's collection besides its search: ~350 instructions per triangle offered (copied,
/// kept in the K-nearest heap), ~550 more per member of S (its bound's coefficients packed).
inline double collection_work(std::uint32_t offered, std::uint32_t kept) { return 350.0 * offered + 550.0 * kept; }
/// Plain searches in a row when certificates cost more per query than plain searches: the
/// first streak, and the longest (each losing trial doubles it; a winning one resets it).
inline constexpr unsigned kPlainStreakMin = 16, kPlainStreakMax = 1024;
/// The plain search's estimate is measured, not remembered: after kProbeEvery certificates in a
/// row with no plain search between them (and before the first comparison), the next kProbe
/// queries that leave a ball are plain searches whose mean replaces the estimate. Without it the
/// estimate was the path's first search (a descent from the root, ~3x a coherent one on the 1M
/// bunny), so certificates that cost twice a coherent search looked cheaper than it.
inline constexpr unsigned kProbeEvery = 16, kProbe = 4;
/// Plain streaks start when certificates cost more than kPlainMargin x a plain search per query
/// (callgrind, auto, instructions per query, margin 1 / 1.25 / 1.5: cow haptic 2,277 / 2,206 /
/// 2,202, rocker-arm haptic 2,913 / 2,796 / 2,804, 1M bunny contact 5,406 / 5,425 / 5,460).
inline constexpr double kPlainMargin = 1.25;

/// The rule's constants (a struct so that a measurement can vary them in one place).
struct CertificateRule {
  unsigned nearest = kNearest;
  double step_factor = kStepFactor, floor_factor = kFloorFactor, ahead = kAheadFactor, growth = kGrowth;
};

/// Where a triangle reference was found: the out-of-core page (UINT32_MAX in memory), its
/// LeafTri index, leaf and leaf node in that tree (the seed of the next branch and bound).
struct TriangleSite {
  std::uint32_t page = UINT32_MAX, k = UINT32_MAX, leaf = UINT32_MAX, node = UINT32_MAX;
};

/// A bound on the rounding error of a computed point-triangle distance near p, in a tree whose
/// root cube is (root_lo, root_size): 4x the branch and bound's own `tol`.
double certificate_tol(const Vec3d& p, const Vec3d& root_lo, double root_size);

/// One answer of the certificate: the winner's squared distance, closest point, input index, site.
struct CertifiedHit {
  double d2 = 0;
  Vec3d closest, normal;
  std::uint64_t key = UINT64_MAX;
  TriangleSite site;
  /// A served answer: the least squared distance of the other members tested (+inf if none).
  /// The scan prunes only members farther than the best + tol, and every other triangle is
  /// farther than that while q is covered, so past (best + 2 tol)^2 the winner is the one
  /// triangle nearest q, strictly (the sign from the closest face). 0: not known (a renewal's).
  double runner2 = 0;
};

class DistanceCertificate {
 public:
  DistanceCertificate();
  /// Forces a kernel (tests: the scalar one on an AVX2 machine). Must be supported by the CPU.
  void set_kernel(ScanKernel k) { kernel_ = k; }
  ScanKernel kernel() const { return kernel_; }
  const CertificateRule& rule() const { return rule_; }

  // --- renewal ---
  /// Starts collecting at p with the rule's radii (r_max >= r_floor >= 0) and rounding bound tol.
  void begin(const Vec3d& p, double r_max, double r_floor, double tol);
  /// A triangle the relaxed branch and bound tested exactly (squared distance d2 to p, tie key,
  /// float geometry, site); returns the prune radius from now on (it never grows): every
  /// triangle within it must still be offered.
  /// `closest` is the exact closest point the branch and bound computed (kept for the winner).
  double offer(double d2, const Vec3d& closest, std::uint64_t key, const LeafTri& t, const TriangleSite& site);
  /// The prune radius (infinite before the first offer).
  double radius() const { return prune_; }
  /// Ends the renewal: the winner (the lexicographic minimum of what was offered, which is the
  /// mesh's when nothing within the prune radius was left out), r, S packed for the scan.
  /// Returns false if nothing was offered (no certificate then).
  bool finish(CertifiedHit* winner);

  // --- serving ---
  bool valid() const { return valid_; }
  /// |q - centre| <= r: q's closest triangle is in S.
  bool covers(const Vec3d& q) const;
  /// The lexicographic minimum of (squared distance, key) over S at q (q covered), with its
  /// runner-up (CertifiedHit::runner2).
  CertifiedHit serve(const Vec3d& q, QueryCounters& c);
  /// The rounding bound the certificate was made with (certificate_tol at its centre).
  double tol() const { return tol_; }
  void clear() { valid_ = false; }
  std::uint32_t size() const { return std::uint32_t(members_.size()); }
  /// How many triangles the last renewal offered (the collection's work: each is copied, and the
  /// kept ones packed).
  std::uint32_t offered() const { return offered_; }
  double r() const { return r_; }

 private:
  struct Member {
    float a[3], b[3], c[3];
    std::uint64_t key;
    TriangleSite site;
    double d;  ///< distance at the centre (collection only)
    Vec3d normal;  ///< the face normal an answer gives (computed once, at renewal)
  };
  static bool better(double d2, std::uint64_t key, double d2b, std::uint64_t keyb) {
    return d2 < d2b || (d2 == d2b && key < keyb);
  }
  /// The directions of a triangle's bound (float face normal, outward edge normals) and its
  /// answer's normal: functions of its geometry alone, so kept from renewal to renewal (the
  /// next certificate shares most of S) in a small direct-mapped table by input index.
  struct Directions {
    std::uint64_t key = UINT64_MAX;
    bool plane = false;  ///< false: no usable plane (zero area), the bound is 0
    float n[3], m[3][3];
    Vec3d normal;
  };
  static constexpr std::size_t kDirectionSlots = 256;
  const Directions& directions(const Member& m);
  void update_prune();
  void pack(double r);
  void exact(std::uint32_t i, const Vec3d& q, CertifiedHit* hit, QueryCounters& c) const;

  ScanKernel kernel_;
  CertificateRule rule_;
  bool valid_ = false;
  Vec3d centre_;
  double r_ = 0, r2_ = 0, r_max_ = 0, r_floor_ = 0, tol_ = 0;
  double prune_ = 0, best_ = 0;
  CertifiedHit win_;          ///< the collection's lexicographic minimum so far
  std::uint32_t win_index_ = 0;
  std::vector<double> heap_;  ///< max-heap of the kNearest + 1 smallest distances offered
  std::vector<Member> members_;
  /// kDirectionSlots of them, allocated at the first renewal: a query that never renews one (an
  /// out-of-core page's, searched by the pages' branch and bound) holds none.
  std::vector<Directions> directions_;
  std::vector<float> pack_;  ///< blocks x kScanRows x kScanLanes
  std::vector<std::uint8_t> masks_;
  std::uint32_t offered_ = 0;
  std::uint32_t current_ = 0;  ///< S's last winner: tested first, its distance the running best
};

/// The path state a coherent distance needs besides the tree's: the mean step of the probe and
/// the certificate, and the previous query's sign and distance (the chained sign).
class CertifiedPath {
 public:
  /// A new path: forget the steps, the certificate and the sign.
  void reset();
  /// Records q as the path's next point (before answering it).
  void step_to(const Vec3d& q);
  /// Where the next certificate is centred for a renewal at q (the current point): ahead of q
  /// along the last step, by kAheadFactor x the last certificate's radius, so that the probe
  /// crosses the ball instead of starting at its centre (fewer renewals on a straight slide).
  Vec3d ahead(const Vec3d& q) const;
  /// Records the renewal just finished (its radius sets the next offset); its account opens.
  void renewed() {
    last_r_ = cert.r();
    account_open_ = true;
    ++certs_since_plain_;
  }
  /// The work of one query the current certificate answered (its renewal's included).
  void certificate_answered(double work) {
    account_work_ += work;
    ++account_queries_;
  }
  /// The work of one plain search (a probe's mean replaces the estimate; others move it by 1/8).
  void plain_answered(double work);
  /// When p has left the certificate's ball: whether to answer it by a plain search instead of a
  /// renewal. Certificates lose where the probe leaves each ball within a few queries (a
  /// jittery walk; triangles a few steps wide, whose renewal costs several searches): while
  /// their work per query answered exceeds a plain search's, the path runs streaks of plain
  /// searches (16, doubling up to 1024), each followed by one trial certificate.
  bool prefer_plain();
  /// The middle of a plain streak (more than kStepWindow + 1 searches left in it): q is answered
  /// by a plain search that nothing of the choice needs, so the path only takes q as its last
  /// point, without its step, its work or the certificate's test (the streak's last kStepWindow
  /// searches measure the step and the plain estimate for its trial). Counts the search.
  bool quiet_plain(const Vec3d& q) {
    if (plain_left_ <= kStepWindow + 1 || !adaptive_) return false;
    --plain_left_;
    prev_ = q;
    have_prev_ = true;
    return true;
  }
  /// false: a renewal whenever p leaves the ball (no plain streaks; tests of the certificate).
  void set_adaptive(bool on) { adaptive_ = on; }
  bool adaptive() const { return adaptive_; }
  /// r_max, r_floor for a renewal at the current point; false while no step is known.
  bool radii(double* r_max, double* r_floor) const;
  /// The mean length of the last kStepWindow steps (0 while none is known): a renewal's scale.
  double mean_step() const;
  /// Whether the path jumps at the current point, so that certificate_policy=auto renews no
  /// certificate there: the last step (as step_length measures it, the largest coordinate
  /// difference) or mean_step() is longer than a leaf cell of edge leaf_cell. false while no step
  /// is known. A renewal's ball follows the path's mean step: one jump in its window is enough to
  /// skip renewals.
  bool jumped(double leaf_cell) const;
  /// q's sign is the previous query's when |q - q_prev| < |best(q_prev)| + |best(q)| (less the
  /// rounding bound tol for each): the open balls of those radii about q_prev and q hold no
  /// surface point, and together they cover the segment between the two points when it is that
  /// short, so the winding number is the same at both ends. `distance` is q's unsigned distance.
  /// Only on closed meshes (elsewhere the sign is not a function of the winding number).
  bool sign_chained(const Vec3d& q, double distance, double tol, bool* inside) const;
  /// The point of the last answered() (meaningful once sign_chained has returned true).
  const Vec3d& sign_point() const { return sign_p_; }
  /// Records q's answer (unsigned distance, sign) for the next sign_chained.
  void answered(const Vec3d& q, double distance, bool inside);

  DistanceCertificate cert;

 private:
  bool have_prev_ = false;
  Vec3d prev_;  ///< the last point
  double last_r_ = 0;
  /// Closes the current certificate's account: its work per query into cert_work_.
  void close_account();
  // the choice between certificates and plain searches (prefer_plain): estimates of the work
  // per query (-1: none yet), the open certificate's account, the plain streak
  double plain_work_ = -1, cert_work_ = -1, account_work_ = 0;
  unsigned account_queries_ = 0;
  bool account_open_ = false, trial_ = false, fresh_ = false, adaptive_ = true;
  unsigned plain_left_ = 0, streak_ = kPlainStreakMin;
  // the plain estimate's probe (kProbeEvery, kProbe): certificates since the last plain search,
  // the probe's searches still to come, its searches so far and their work
  unsigned certs_since_plain_ = 0, probe_left_ = 0, probe_n_ = kProbe;
  double probe_sum_ = 0;
  // the last kStepWindow steps (q - q_prev), a ring; their lengths and the last one's direction
  // are taken when a renewal asks (radii, ahead), not at every query
  Vec3d moves_[kStepWindow];
  unsigned nsteps_ = 0, next_ = 0;
  bool sign_ok_ = false, sign_in_ = false;
  Vec3d sign_p_;
  double sign_best_ = 0;
};

/// One coherent unsigned distance query on the certificate path, in memory or out of core: a
/// scan of S when it covers p; else, once the path has a step, a renewal at the centre
/// path.ahead(p): begin(), then `renew(cert, centre)` runs the tree's branch and bound at the
/// centre with `cert` as its collector, then finish(), and p is served from the new certificate
/// (or, if its ball turned out too small to hold p, answered by `plain()`); else (the path's
/// first point, a plain streak: CertifiedPath::prefer_plain (its middle, CertifiedPath::quiet_plain,
/// before anything else), or under that adaptive policy a
/// jump: CertifiedPath::jumped, the last step or the path's mean step longer than a leaf cell of
/// edge leaf_cell) `plain()`, the branch and bound alone. A jump's renewal would collect a ball
/// of the jump's size (its radius follows the steps): on random points one trial certificate
/// cost as much as thousands of plain searches. `work_now()` gives the Work counted so far by
/// every search and scan of this query state (the choice between certificates and plain searches
/// weighs it). On a certified answer *site is where its triangle was found (the next renewal's
/// seed) and *runner2, if given, the scan's runner-up (CertifiedHit::runner2; left as it was on
/// an answer of `plain()`). The tree's root cube: root_lo, root_size.
template <class WorkNow, class Renew, class Plain>
DistanceAnswer certified_query(CertifiedPath& path, const Vec3d& p, double leaf_cell, const Vec3d& root_lo,
                               double root_size, QueryCounters& c, TriangleSite* site, WorkNow&& work_now,
                               Renew&& renew, Plain&& plain, double* runner2 = nullptr) {
  if (path.quiet_plain(p)) return plain();
  path.step_to(p);
  const Work w0 = work_now();
  auto searched = [&] {
    const DistanceAnswer a = plain();
    path.plain_answered(search_work(w0, work_now()));
    return a;
  };
  CertifiedHit h;
  double r_max, r_floor;
  if (path.cert.covers(p)) {
    ++c.certificate_served;
    h = path.cert.serve(p, c);
    path.certificate_answered(scan_work(w0, work_now()));
  } else if (path.prefer_plain()) {
    return searched();
  } else if (path.radii(&r_max, &r_floor)) {
    // (a jump's plain search is not what one costs on the path: not in the estimate)
    if (path.adaptive() && path.jumped(leaf_cell)) return plain();
    const Vec3d centre = path.ahead(p);
    path.cert.begin(centre, r_max, r_floor, certificate_tol(centre, root_lo, root_size));
    renew(path.cert, centre);
    ++c.certificate_renewals;
    if (!path.cert.finish(&h)) return DistanceAnswer{};  // cannot happen: the mesh has a triangle
    path.renewed();
    const double collected = collection_work(path.cert.offered(), path.cert.size());
    // This query's work, the renewal's included, is the new certificate's, however p is answered.
    auto renewal_answered = [&] { path.certificate_answered(search_work(w0, work_now()) + collected); };
    if (!(centre == p)) {
      if (!path.cert.covers(p)) {
        const DistanceAnswer a = plain();
        renewal_answered();
        return a;
      }
      h = path.cert.serve(p, c);
    }
    renewal_answered();
  } else {
    // The path's first point: a descent from the root, not what a plain search costs on the
    // path, so it is not in the estimate.
    path.cert.clear();
    return plain();
  }
  *site = h.site;
  if (runner2) *runner2 = h.runner2;
  DistanceAnswer r;
  r.distance = std::sqrt(h.d2);
  r.closest = h.closest;
  r.normal = h.normal;
  r.triangle = std::int64_t(h.key);
  return r;
}

}  // namespace ebp
