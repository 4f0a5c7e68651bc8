// The coherent path's distance (Query::unsigned_distance): what each search of a probe's path
// starts from (the previous closest triangle where the step is no jump), the certificate that
// answers searches without one (certificate.hpp), and when the path gathers a near set for the
// next searches (gather_distance_near). The search itself, one distance_bound call, is
// query_distance.cpp's.
#include <algorithm>
#include <cmath>
#include <limits>

#include "methods/ebp_octree/core/certificate.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/near_set.hpp"
#include "methods/ebp_octree/core/query.hpp"

namespace ebp {

DistanceAnswer Query::unsigned_distance(const Vec3d& p) {
  ++path_queries_;
  face_side_ = 0;
  return coherent_ && certificate_ ? certified_distance(p) : searched_distance(p);
}

bool Query::seed_pays_at(const Vec3d& p) const {
  return last_tri_ != UINT32_MAX && !is_jump(step_length(p, last_p_), last_d_, t_.cell_size(t_.leaf_level));
}

void Query::seed_from_last(const Vec3d& p, DistanceStart& s) const {
  if (!seed_pays_at(p)) return;
  s.seed_tri = last_tri_;
  s.seed_leaf = last_leaf_;
  s.seed_node = last_leaf_node_;
}

void Query::remember_closest(std::uint32_t k, std::uint32_t leaf, std::uint32_t node, const Vec3d& p, double d) {
  last_tri_ = k;
  last_leaf_ = leaf;
  last_leaf_node_ = node;
  last_p_ = p;
  last_d_ = d;
}

DistanceAnswer Query::searched_distance(const Vec3d& p) {
  DistanceBest b;
  DistanceStart s;
  if (coherent_) {
    seed_from_last(p, s);
    s.near = true;
  }
  distance_bound(p, b, s);
  DistanceAnswer r;
  if (b.k == UINT32_MAX) return r;  // cannot happen: the mesh has a triangle
  const LeafTri& t = t_.tris[b.k];
  r.distance = b.best;
  r.closest = b.closest;
  r.normal = bvhbench::triangle_normal(to_d(t.a), to_d(t.b), to_d(t.c));
  r.triangle = std::int64_t(t.tri());
  take_face_side(p, b.k, b.best, b.runner2, search_tol(p, t_.root_lo, t_.root_size));
  if (coherent_) remember_closest(b.k, b.leaf, b.node, p, r.distance);
  return r;
}

// The coherent path with a certificate (certificate.hpp): a scan of S while p is in its ball,
// else a renewal (the branch and bound relaxed into a collection, seeded like searched_distance).
// The first query of a path has no step yet: a plain search.
DistanceAnswer Query::certified_distance(const Vec3d& p) {
  TriangleSite site;
  double runner2 = 0;  // the certificate's runner-up, on an answer it served
  const DistanceAnswer r = certified_query(
      *path_, p, t_.cell_size(t_.leaf_level), t_.root_lo, t_.root_size, counters, &site, [&] { return work_of(counters); },
      [&](DistanceCertificate& cert, const Vec3d& centre) {
        DistanceBest b;
        b.collect = &cert;
        DistanceStart s;
        seed_from_last(centre, s);
        distance_bound(centre, b, s);
      },
      [&] { return searched_distance(p); }, &runner2);
  if (runner2 > 0 && site.k != UINT32_MAX) take_face_side(p, site.k, r.distance, runner2, path_->cert.tol());
  if (site.k != UINT32_MAX) remember_closest(site.k, site.leaf, site.node, p, r.distance);
  return r;
}

// A near set for the next searches of the path: a cube of half-width r + scale x (kNearBall x r
// + kNearSteps steps of the probe), centred kNearAhead steps ahead of p along the last step, so
// that the next balls (their radius at most r plus the step, the previous closest point being on
// the surface) lie in it for a few steps (callgrind on the 1M bunny's contact path, scale 1,
// instructions a search: steps 1 / 2 / 4 / 8 / 16: 1,421 / 1,282 / 1,181 / 1,266 / 1,608; ball
// 0.5 / 1 / 2: 1,201 / 1,181 / 1,167; ahead 0 / 1 / 2 / 3 / 4 / 6 steps: 1,170 / 1,125 / 1,087 /
// 1,059 / 1,048 / 1,261, and at 0.3 m/s 0 / 3 / 4: 2,249 / 2,121 / 2,430). A box that meets
// too many triangles or leaf cells gets a second attempt at a quarter of the growth and offset
// at once; the scale is the path's: halved when a box meets too many triangles (small
// triangles), doubled back (up to 1) when a set has fewer than 8 members (16 of 64, before: the
// scale went up and down, every other box overflowing; 4M bunny contact 0.2 mm, 3,407 -> 3,117
// instructions a search, 0.05 mm -6 %, 0.5 mm +4 %, 0.3 m/s within 1 %). A set gathered
// first (distance_bound) is kept around the ball (p, r), which it then serves; a set that served
// no search besides that one before the next gathering was a loss: after kNearLosses in a row
// the path gathers no set for 8 searches, doubling while the losses go on (up to 256) — a path
// far from the surface, sliding fast, or on triangles so small that no set of kNearMax holds the
// next ball, where the tree's search alone is cheaper. Attempts that fail count as gatherings.
// A set holds up to kNearMembers triangles while the path's scale is above kNearLargeBelow, and
// up to kNearMax (twice as many) below it: once boxes have overflowed down to a quarter of the
// growth, the triangles are so small that a box of kNearMembers barely holds the ball and its set
// serves a step or two before the next gathering, and after three such losses the path backs off
// to tree searches (contact 0.2 mm at 0.1 m/s, interleaved, `certificate=false`: 32M bunny
// near_served 0.38 -> 0.75, 715-818 k -> 875-876 k q/s; 32M scan-like blob 785-791 k -> 869-881
// k; 4M bunny at 0.3 m/s 863-877 k -> 889-923 k). Where the scale stays above it (the 4M bunny at
// 0.1 m/s: 3,201 -> 3,238 instructions a search, the same time) the larger sets cost more to
// gather and to serve than they save (sets of 256 at every scale: 3,563), so the limit follows
// the scale.
bool Query::gather_distance_near(const Vec3d& p, double r, bool first) {
  constexpr double kNearBall = 2.0, kNearSteps = 4.0, kNearAhead = 3.0, kMinScale = 1.0 / 64;
  constexpr double kNearLargeBelow = 0.25;  // scale
  constexpr std::uint32_t kNearMembers = kNearMax / 2;
  constexpr std::uint32_t kNearScaleUpBelow = 8;  // members
  constexpr std::uint32_t kNearLosses = 3, kNearBackoff = 8, kNearBackoffMax = 256;
  if (dnear_backoff_ > 0) {
    --dnear_backoff_;
    return false;
  }
  if (!(r < std::numeric_limits<double>::infinity())) return false;
  // The last set's outcome (after a pause, the next set is tried first). A set that other
  // queries interrupted (certificates answered them) was not given its chance: no loss.
  const bool interrupted = path_queries_ - dnear_gathered_at_ > 1 + dnear_served_;
  if (dnear_tried_ && !interrupted) {
    // (a set gathered first serves the search it was gathered for: a loss if it served no other)
    dnear_losses_ = dnear_served_ <= (dnear_first_ ? 1u : 0u) ? dnear_losses_ + 1 : 0;
    if (dnear_losses_ >= kNearLosses) {
      dnear_backoff_ = std::min(kNearBackoffMax, kNearBackoff << std::min<std::uint32_t>(dnear_losses_ - kNearLosses, 5));
      if (dnear_) dnear_->valid = false;
      dnear_tried_ = false;
      return false;
    }
  }
  dnear_served_ = 0;
  dnear_tried_ = true;
  dnear_first_ = first;
  dnear_gathered_at_ = path_queries_;
  const double step = std::max({std::fabs(dmove_.x), std::fabs(dmove_.y), std::fabs(dmove_.z)});
  NearSet& ns = allocated(dnear_);
  for (const double part : {1.0, 0.25}) {
    const double h = r + part * dnear_scale_ * (kNearBall * r + kNearSteps * step);
    // ahead of p, but not so far that the box stops holding the ball (p, r) of this search
    Vec3d c = p;
    for (int a = 0; a < 3; ++a) c[a] += std::clamp(dmove_[a] * (part * kNearAhead), r - h, h - r);
    ++counters.near_gathered;
    const std::uint32_t members = dnear_scale_ <= kNearLargeBelow ? kNearMax : kNearMembers;
    if (ns.gather(t_, c - Vec3d(h, h, h), c + Vec3d(h, h, h), UINT32_MAX, true, members)) {
      if (ns.n < kNearScaleUpBelow) dnear_scale_ = std::min(1.0, 2 * dnear_scale_);
      return true;
    }
    if (ns.overflowed) dnear_scale_ = std::max(kMinScale, 0.5 * dnear_scale_);
  }
  dnear_backoff_ = kNearBackoff;
  return false;
}

}  // namespace ebp
