// The exact oracle (see oracle.hpp for the definitions and the exactness argument).
//
// The only translation unit that includes CGAL: its filtered exact orientation predicates decide
// every ray/triangle crossing. Everything else is plain double arithmetic on our own BVH.
#include "harness/core/oracle.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "harness/core/mesh.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Clock = std::chrono::steady_clock;

constexpr std::uint32_t kLeafSize = 4;

// ---------------------------------------------------------------------------------------------
// Exact predicates and the symbolic perturbation p' = p + (eps^3, eps, eps^2)
// ---------------------------------------------------------------------------------------------

/// Sign of the 2D orientation of (u, v, w) in the plane of coordinates (i, j), exactly.
inline int orient2(const Vec3d& u, const Vec3d& v, const Vec3d& w, int i, int j) {
  return int(CGAL::orientation(K::Point_2(u[i], u[j]), K::Point_2(v[i], v[j]), K::Point_2(w[i], w[j])));
}

}  // namespace

bool collinear_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return CGAL::collinear(K::Point_3(a.x, a.y, a.z), K::Point_3(b.x, b.y, b.z), K::Point_3(c.x, c.y, c.z));
}

namespace {

/// Sign of det(u - p', v - p') in the (y, z) plane, p' = p + (., eps, eps^2): never 0 unless u and
/// v project to the same point. Expansion: det0 + eps (u_z - v_z) + eps^2 (v_y - u_y).
inline int sos_orient_yz(const Vec3d& u, const Vec3d& v, const Vec3d& p) {
  int s = orient2(u, v, p, 1, 2);
  if (s != 0) return s;
  if (u.z != v.z) return u.z > v.z ? 1 : -1;
  if (u.y != v.y) return v.y > u.y ? 1 : -1;
  return 0;
}

/// Signed crossing of the ray p' + t*(+x), t > 0, with triangle (a, b, c): +1 if it leaves
/// through the front (normal with n_x > 0), -1 through the back, 0 if it misses.
inline int crossing(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const int o = orient2(a, b, c, 1, 2);  // sign of n_x, n = (b - a) x (c - a)
  if (o == 0) return 0;                  // parallel to the ray: never crossed transversally
  if (sos_orient_yz(a, b, p) != o || sos_orient_yz(b, c, p) != o || sos_orient_yz(c, a, p) != o) return 0;
  // Side of p' against the plane: sign of n . (p' - a) = n.(p - a) + eps n_y + eps^2 n_z + eps^3 n_x.
  int side = int(CGAL::orientation(K::Point_3(a.x, a.y, a.z), K::Point_3(b.x, b.y, b.z),
                                   K::Point_3(c.x, c.y, c.z), K::Point_3(p.x, p.y, p.z)));
  if (side == 0) side = orient2(a, b, c, 2, 0);  // n_y
  if (side == 0) side = orient2(a, b, c, 0, 1);  // n_z
  if (side == 0) side = o;                       // n_x
  // CGAL: POSITIVE when (b-a, c-a, p-a) is a positive basis, i.e. n.(p - a) > 0. The hit is ahead
  // (t > 0) iff n.(a - p) has the sign of n_x.
  return -side == o ? o : 0;
}

// ---------------------------------------------------------------------------------------------
// Point-triangle distance, written for accuracy rather than speed
// ---------------------------------------------------------------------------------------------

/// a*b - c*d with one rounding error (Kahan, via FMA), immune to cancellation.
inline double diff_prod(double a, double b, double c, double d) {
  const double w = c * d;
  const double e = std::fma(c, d, -w);
  const double f = std::fma(a, b, -w);
  return f - e;
}
inline Vec3d xcross(const Vec3d& u, const Vec3d& v) {
  return {diff_prod(u.y, v.z, u.z, v.y), diff_prod(u.z, v.x, u.x, v.z), diff_prod(u.x, v.y, u.y, v.x)};
}

inline Vec3d closest_on_segment(const Vec3d& p, const Vec3d& u, const Vec3d& v) {
  const Vec3d e = v - u;
  const double ee = dot(e, e);
  if (!(ee > 0)) return u;
  const double t = std::clamp(dot(p - u, e) / ee, 0.0, 1.0);
  return t >= 1.0 ? v : u + e * t;
}

/// Closest point of triangle (a, b, c) to p: the projection on the plane if it falls inside the
/// triangle (tested against an accurately computed normal), else the best of the three edges.
/// Degenerate triangles reduce to their edges.
inline Vec3d closest_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d n = xcross(b - a, c - a);
  const double nn = dot(n, n);
  if (nn > 0 && std::isfinite(nn)) {
    if (dot(xcross(b - a, p - a), n) >= 0 && dot(xcross(c - b, p - b), n) >= 0 &&
        dot(xcross(a - c, p - c), n) >= 0)
      return p - n * (dot(p - a, n) / nn);
  }
  Vec3d q = closest_on_segment(p, a, b);
  double d = squared_norm(q - p);
  Vec3d q2 = closest_on_segment(p, b, c);
  double d2 = squared_norm(q2 - p);
  if (d2 < d) { q = q2; d = d2; }
  q2 = closest_on_segment(p, c, a);
  d2 = squared_norm(q2 - p);
  if (d2 < d) q = q2;
  return q;
}

inline float round_down(double x) {
  float f = float(x);
  return double(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}
inline float round_up(double x) {
  float f = float(x);
  return double(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

inline double box_dist2(const Oracle::Node& n, const Vec3d& p) {
  double d = 0;
  for (int i = 0; i < 3; ++i) {
    double v = std::max({double(n.lo[i]) - p[i], 0.0, p[i] - double(n.hi[i])});
    d += v * v;
  }
  return d;
}

/// Nodes in a subtree over n primitives (median split until kLeafSize): the depth-first layout
/// puts the left child right after its parent and the right child after the left subtree.
std::size_t subtree_nodes(std::size_t n) {
  static thread_local std::map<std::size_t, std::size_t> memo;
  if (n <= kLeafSize) return 1;
  auto it = memo.find(n);
  if (it != memo.end()) return it->second;
  std::size_t r = 1 + subtree_nodes(n / 2) + subtree_nodes(n - n / 2);
  memo[n] = r;
  return r;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Build
// ---------------------------------------------------------------------------------------------
Oracle::Oracle(const Mesh& mesh, double tie_tolerance_rel, bool verbose) : mesh_(mesh) {
  if (mesh.triangles.empty()) throw InputError(mesh.path + ": empty mesh (no triangle)");
  if (mesh.triangles.size() >= (std::size_t(1) << 32) - 1)
    throw InputError(mesh.path + ": too many triangles for the oracle (2^32)");
  Box3d box;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) box.add(mesh.vertices[t[k]]);
  diagonal_ = box.diagonal();
  tie_tol_ = tie_tolerance_rel * diagonal_;
  auto t0 = Clock::now();
  find_boundary();
  auto t1 = Clock::now();
  build_bvh(verbose);
  auto t2 = Clock::now();
  if (verbose)
    std::cerr << "truth: " << mesh.triangles.size() << " triangles, " << boundary_.size()
              << " boundary edges (" << std::chrono::duration<double>(t1 - t0).count() << " s), BVH "
              << nodes_.size() << " nodes (" << std::chrono::duration<double>(t2 - t1).count() << " s)\n";
}

Oracle::~Oracle() = default;

void Oracle::find_boundary() {
  // Directed edges u->v are keyed by the unordered pair; an edge is a boundary edge |net| times,
  // net = (# u->v with u < v) - (# v->u). Two sorted key arrays instead of a hash map: 30M
  // triangles give 90M edges.
  const auto& F = mesh_.triangles;
  const std::uint64_t V = mesh_.vertices.size();
  // The edges of zero-area triangles again, apart (few): such a triangle is never crossed and
  // has no solid angle, so the edge counts that decide which definitions of inside hold
  // (odd_edges_, nonmanifold_edges_, solid_boundary_edges_) leave it out.
  std::vector<std::uint64_t> fwd, bwd, flat_fwd, flat_bwd;
  fwd.reserve(F.size() * 3 / 2 + 16);
  bwd.reserve(F.size() * 3 / 2 + 16);
  const auto& X = mesh_.vertices;
  for (const auto& t : F) {
    const bool flat = collinear_exact(X[t[0]], X[t[1]], X[t[2]]);
    for (int k = 0; k < 3; ++k) {
      std::uint64_t u = t[k], v = t[(k + 1) % 3];
      if (u < v) fwd.push_back(u * V + v);
      else if (v < u) bwd.push_back(v * V + u);
      if (flat && u < v) flat_fwd.push_back(u * V + v);
      else if (flat && v < u) flat_bwd.push_back(v * V + u);
    }
  }
  tbb::parallel_invoke([&] { tbb::parallel_sort(fwd.begin(), fwd.end()); },
                       [&] { tbb::parallel_sort(bwd.begin(), bwd.end()); });
  std::sort(flat_fwd.begin(), flat_fwd.end());
  std::sort(flat_bwd.begin(), flat_bwd.end());
  std::size_t i = 0, j = 0, fi = 0, fj = 0;
  auto add = [&](std::uint64_t key, long net) {
    std::uint64_t a = key / V, b = key % V;
    if (net < 0) std::swap(a, b), net = -net;
    for (long r = 0; r < net; ++r) boundary_.push_back({mesh_.vertices[a], mesh_.vertices[b]});
  };
  while (i < fwd.size() || j < bwd.size()) {
    std::uint64_t key = std::min(i < fwd.size() ? fwd[i] : ~0ull, j < bwd.size() ? bwd[j] : ~0ull);
    long net = 0, uses = 0;
    while (i < fwd.size() && fwd[i] == key) ++net, ++uses, ++i;
    while (j < bwd.size() && bwd[j] == key) --net, ++uses, ++j;
    if (net != 0) add(key, net);
    while (fi < flat_fwd.size() && flat_fwd[fi] == key) --net, --uses, ++fi;
    while (fj < flat_bwd.size() && flat_bwd[fj] == key) ++net, --uses, ++fj;
    solid_boundary_edges_ += std::size_t(std::abs(net));
    odd_edges_ += uses % 2;
    nonmanifold_edges_ += uses > 2;
  }
}

void Oracle::build_bvh(bool verbose) {
  const auto& F = mesh_.triangles;
  const auto& X = mesh_.vertices;
  const std::size_t n = F.size();
  prims_.resize(n);
  std::vector<Vec3f> centroid(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      prims_[i] = std::uint32_t(i);
      centroid[i] = Vec3f((X[F[i][0]] + X[F[i][1]] + X[F[i][2]]) / 3.0);
    }
  });
  nodes_.resize(subtree_nodes(n));

  // Recursive median split on the longest axis of the centroids' box; subtrees over more than
  // 32k triangles are built in parallel. Bounds come up from the leaves, rounded outward.
  struct Builder {
    Oracle& o;
    std::vector<Vec3f>& c;
    void operator()(std::size_t node, std::size_t begin, std::size_t end) const {
      Node& nd = o.nodes_[node];
      const std::size_t count = end - begin;
      if (count <= kLeafSize) {
        Box3d b;
        for (std::size_t i = begin; i < end; ++i)
          for (int k = 0; k < 3; ++k) b.add(o.mesh_.vertices[o.mesh_.triangles[o.prims_[i]][k]]);
        for (int k = 0; k < 3; ++k) {
          nd.lo[k] = round_down(b.lo[k]);
          nd.hi[k] = round_up(b.hi[k]);
        }
        nd.index = std::uint32_t(begin);
        nd.count = std::uint32_t(count);
        return;
      }
      Vec3f lo = c[o.prims_[begin]], hi = lo;
      for (std::size_t i = begin + 1; i < end; ++i) {
        lo = vmin(lo, c[o.prims_[i]]);
        hi = vmax(hi, c[o.prims_[i]]);
      }
      const Vec3f e = hi - lo;
      const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
      const std::size_t mid = begin + count / 2;
      auto* P = o.prims_.data();
      std::nth_element(P + begin, P + mid, P + end, [&](std::uint32_t a, std::uint32_t b) {
        float ca = c[a][axis], cb = c[b][axis];
        return ca < cb || (ca == cb && a < b);
      });
      const std::size_t left = node + 1, right = node + 1 + subtree_nodes(mid - begin);
      if (count > (1u << 15)) {
        tbb::parallel_invoke([&] { (*this)(left, begin, mid); }, [&] { (*this)(right, mid, end); });
      } else {
        (*this)(left, begin, mid);
        (*this)(right, mid, end);
      }
      const Node& l = o.nodes_[left];
      const Node& r = o.nodes_[right];
      for (int k = 0; k < 3; ++k) {
        nd.lo[k] = std::min(l.lo[k], r.lo[k]);
        nd.hi[k] = std::max(l.hi[k], r.hi[k]);
      }
      nd.index = std::uint32_t(right);
      nd.count = 0;
    }
  };
  Builder{*this, centroid}(0, 0, n);
  (void)verbose;
}

// ---------------------------------------------------------------------------------------------
// Queries
// ---------------------------------------------------------------------------------------------
std::vector<std::string> Oracle::definitions() const {
  std::vector<std::string> d;
  if (odd_edges_ == 0) d.push_back("ray_parity");
  if (solid_boundary_edges_ == 0) {
    d.push_back("winding_number");
    d.push_back("nonzero_winding");
  }
  d.push_back("generalized_winding_number");
  return d;
}

Oracle::RayCrossings Oracle::ray_crossings(const Vec3d& p) const {
  const auto& F = mesh_.triangles;
  const auto& X = mesh_.vertices;
  long total = 0;
  bool odd = false;
  std::uint32_t stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& nd = nodes_[stack[--sp]];
    // Closed tests on the outward-rounded box: a superset of what the perturbed ray can hit.
    if (!(p.y >= nd.lo[1] && p.y <= nd.hi[1] && p.z >= nd.lo[2] && p.z <= nd.hi[2] && p.x <= nd.hi[0]))
      continue;
    if (nd.count == 0) {
      stack[sp++] = nd.index;
      stack[sp++] = std::uint32_t(&nd - nodes_.data()) + 1;
      continue;
    }
    for (std::uint32_t i = nd.index; i < nd.index + nd.count; ++i) {
      const auto& t = F[prims_[i]];
      const Vec3d &a = X[t[0]], &b = X[t[1]], &c = X[t[2]];
      if (std::max({a.x, b.x, c.x}) < p.x) continue;
      if (std::min({a.y, b.y, c.y}) > p.y || std::max({a.y, b.y, c.y}) < p.y) continue;
      if (std::min({a.z, b.z, c.z}) > p.z || std::max({a.z, b.z, c.z}) < p.z) continue;
      const int sign = crossing(p, a, b, c);
      total += sign;
      odd ^= sign != 0;
    }
  }
  return {total, odd};
}

double Oracle::winding(const Vec3d& p) const { return winding_from(p, crossings(p)); }

double Oracle::winding_from(const Vec3d& p, long net_crossings) const {
  double w = double(net_crossings);
  if (boundary_.empty()) return w;
  // Solid angle / 4 pi of the strip swept from each boundary edge u->v along d = -x: the
  // spherical triangle (u - p, v - p, d) (Van Oosterom and Strackee). Its determinant
  // d . ((u - p) x (v - p)) = -det_yz(u - p, v - p) takes the symbolically perturbed sign near 0, so
  // that the atan2 branch agrees with the crossing count.
  constexpr double inv_two_pi = 0.15915494309189533577;
  double sum = 0;
  for (const auto& e : boundary_) {
    const Vec3d U = e[0] - p, V = e[1] - p;
    const double lu = norm(U), lv = norm(V);
    const double dyz = U.y * V.z - U.z * V.y;
    const double bound = 1e-14 * (std::abs(U.y * V.z) + std::abs(U.z * V.y));
    double det = -dyz;
    if (!(std::abs(dyz) > bound)) {
      int s = sos_orient_yz(e[0], e[1], p);
      if (s == 0) continue;  // the edge is parallel to x: its strip has no area
      det = -double(s) * std::max(std::abs(dyz), std::numeric_limits<double>::denorm_min());
    }
    const double den = lu * lv + dot(U, V) - V.x * lu - U.x * lv;
    sum += std::atan2(det, den) * inv_two_pi;
  }
  return w + sum;
}

bool Oracle::inside_from_winding(double w) const {
  return boundary_.empty() ? w != 0.0 : std::abs(w) > 0.5;
}

OracleNearest Oracle::nearest(const Vec3d& p) const {
  const auto& F = mesh_.triangles;
  const auto& X = mesh_.vertices;
  struct Cand {
    double d;
    std::uint32_t tri;
    Vec3d q;
  };
  thread_local std::vector<Cand> cands;
  cands.clear();
  double best = std::numeric_limits<double>::infinity();
  double lim2 = best;
  struct Item {
    std::uint32_t node;
    double d2;
  };
  Item stack[128];
  int sp = 0;
  stack[sp++] = {0, box_dist2(nodes_[0], p)};
  while (sp > 0) {
    const Item it = stack[--sp];
    if (it.d2 > lim2) continue;
    const Node& nd = nodes_[it.node];
    if (nd.count == 0) {
      const std::uint32_t l = it.node + 1, r = nd.index;
      const double dl = box_dist2(nodes_[l], p), dr = box_dist2(nodes_[r], p);
      if (dl <= dr) {
        if (dr <= lim2) stack[sp++] = {r, dr};
        if (dl <= lim2) stack[sp++] = {l, dl};
      } else {
        if (dl <= lim2) stack[sp++] = {l, dl};
        if (dr <= lim2) stack[sp++] = {r, dr};
      }
      continue;
    }
    for (std::uint32_t i = nd.index; i < nd.index + nd.count; ++i) {
      const std::uint32_t tri = prims_[i];
      const auto& t = F[tri];
      const Vec3d q = closest_on_triangle(p, X[t[0]], X[t[1]], X[t[2]]);
      const double d = norm(q - p);
      if (d <= best + tie_tol_) {
        cands.push_back({d, tri, q});
        if (d < best) {
          best = d;
          const double lim = best + tie_tol_;
          lim2 = lim * lim * (1 + 1e-12);  // margin for the rounding of box distances
        }
      }
    }
  }
  OracleNearest r;
  const Cand* b = nullptr;
  for (const Cand& c : cands)
    if (!b || c.d < b->d || (c.d == b->d && c.tri < b->tri)) b = &c;
  r.distance = b->d;
  r.closest = b->q;
  r.tied.fill(-1);
  std::vector<std::uint32_t> tied;
  for (const Cand& c : cands)
    if (c.d <= b->d + tie_tol_) tied.push_back(c.tri);
  std::sort(tied.begin(), tied.end());
  tied.erase(std::unique(tied.begin(), tied.end()), tied.end());
  r.tie_count = std::int64_t(tied.size());
  for (std::size_t k = 0; k < tied.size() && k < std::size_t(kMaxTied); ++k) r.tied[k] = tied[k];
  // The reported triangle is the lowest index among the ties (brute force's rule), with its own
  // closest point (the same point up to the tolerance).
  r.triangle = tied.front();
  if (std::uint32_t(r.triangle) != b->tri)
    for (const Cand& c : cands)
      if (c.tri == std::uint32_t(r.triangle)) { r.closest = c.q; r.distance = std::min(r.distance, c.d); break; }
  const auto& t = F[r.triangle];
  const Vec3d nrm = xcross(X[t[1]] - X[t[0]], X[t[2]] - X[t[0]]);
  r.normal = normalized(nrm);
  return r;
}

OracleAnswers Oracle::answer(const std::vector<Vec3d>& pts) const {
  const std::size_t n = pts.size();
  OracleAnswers a;
  a.definition = closed() ? "exact" : "winding_number";
  a.definitions = definitions();
  a.odd_edges = odd_edges_;
  a.solid_boundary_edges = solid_boundary_edges_;
  a.nonmanifold_edges = nonmanifold_edges_;
  a.parity.resize(n);
  a.tie_tolerance = tie_tol_;
  a.boundary_edges = boundary_.size();
  a.inside.resize(n);
  a.winding.resize(n);
  a.distance.resize(n);
  a.closest.resize(n);
  a.normal.resize(n);
  a.triangle.resize(n);
  a.tie_count.resize(n);
  a.tied.resize(n * kMaxTied);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const RayCrossings rc = ray_crossings(pts[i]);
      const double w = winding_from(pts[i], rc.net);
      a.winding[i] = w;
      a.parity[i] = rc.odd ? 1 : 0;
      a.inside[i] = inside_from_winding(w) ? 1 : 0;
      OracleNearest nn = nearest(pts[i]);
      a.distance[i] = nn.distance;
      a.closest[i] = nn.closest;
      a.normal[i] = nn.normal;
      a.triangle[i] = nn.triangle;
      a.tie_count[i] = nn.tie_count;
      std::copy(nn.tied.begin(), nn.tied.end(), a.tied.begin() + std::ptrdiff_t(i * kMaxTied));
    }
  });
  return a;
}

// ---------------------------------------------------------------------------------------------
// The oracle file
// ---------------------------------------------------------------------------------------------
}  // namespace bvhbench
