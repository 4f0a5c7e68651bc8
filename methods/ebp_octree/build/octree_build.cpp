// The EBP-Octree builder. Steps (DESIGN.md explains the why):
//   1. float geometry, bounding cube (enlarged, with exactly representable cell boundaries),
//      leaf level from the average edge length;
//   2. distribution: every triangle to every leaf cell it touches (bbox-restricted
//      rasterisation confirmed by the conservative separating-axis test), (morton, tri) pairs
//      sorted;
//   3. the node set: grey nodes (holding geometry) down to the leaf level, and the empty octants
//      of grey inner nodes as empty leaves (maximal empty cells: no merge step is needed);
//   4. leaves: triangle blocks, bounding planes (clustered face normals, offset to the support of
//      triangle ∩ cell), configuration (convex / concave / special), reference point;
//   5. inner nodes bottom-up: planes chosen among the children's, offset to the support of the
//      children's bounding volumes (vertices of cell box ∩ planes);
//   6. colouring: winding numbers of reference points and empty nodes by exact signed segment
//      crossings between adjacent cells, joined in a union-find with potentials, seeded by the
//      outside of the root (w = 0).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>
#include <tbb/enumerable_thread_specific.h>

#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/build/polytope.hpp"
#include "methods/ebp_octree/build/tri_box.hpp"
#include "methods/ebp_octree/core/leaf_blocks.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/core/reference_points.hpp"

namespace ebp {

using detail::BuildContext;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// Runs f(i) for i in [0, n), in parallel when threads > 1.
template <class F>
void par_for(int threads, std::size_t n, F&& f) {
  if (threads <= 1 || n < 64) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
  });
}

struct Pair {
  std::uint64_t m;  // leaf Morton code
  std::uint32_t t;  // triangle
  bool operator<(const Pair& o) const { return m < o.m || (m == o.m && t < o.t); }
};

/// Rounds a double up to the next float >= it.
float round_up(double d) {
  const double r = round_to_float(d);
  float f = float(r);
  if (r < d) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

double box_support(const Vec3d& lo, const Vec3d& hi, const Vec3d& n) {
  return (n.x > 0 ? n.x * hi.x : n.x * lo.x) + (n.y > 0 ? n.y * hi.y : n.y * lo.y) +
         (n.z > 0 ? n.z * hi.z : n.z * lo.z);
}

/// Union-find with potentials: off[x] = w(x) - w(parent[x]), w the winding number.
struct UnionFind {
  std::vector<std::uint32_t> parent;
  std::vector<int> off;
  std::vector<std::uint8_t> touched;
  explicit UnionFind(std::size_t n) : parent(n), off(n, 0), touched(n, 0) {
    std::iota(parent.begin(), parent.end(), 0u);
  }
  /// Root of x, and w(x) - w(root) in *pot.
  std::uint32_t find(std::uint32_t x, int* pot) {
    int acc = 0;
    std::uint32_t r = x;
    while (parent[r] != r) { acc += off[r]; r = parent[r]; }
    // Path compression: every node on the path now points at r with its full offset.
    int rest = acc;
    std::uint32_t y = x;
    while (parent[y] != y) {
      const std::uint32_t nx = parent[y];
      const int oy = off[y];
      parent[y] = r;
      off[y] = rest;
      rest -= oy;
      y = nx;
    }
    if (pot) *pot = acc;
    return r;
  }
  /// Records w(b) - w(a) = d.
  void unite(std::uint32_t a, std::uint32_t b, int d) {
    int wa, wb;
    const std::uint32_t ra = find(a, &wa), rb = find(b, &wb);
    touched[a] = touched[b] = 1;
    if (ra == rb) return;
    parent[ra] = rb;
    off[ra] = -d - wa + wb;  // w(ra) - w(rb) = (w(a) - wa) - (w(b) - wb), w(a) - w(b) = -d
  }
};

/// Makes a float plane (root frame) from a unit direction and the support of `pts` (world).
void make_plane(const BuildContext& ctx, const Vec3d& n, const std::vector<Vec3d>& pts, Plane* out) {
  const Vec3d rc = ctx.f.root_centre;
  const Vec3d nd = round_to_float(n);
  double s = -std::numeric_limits<double>::infinity();
  for (const Vec3d& v : pts) s = std::max(s, dot(nd, v - rc));
  out->n[0] = float(nd.x); out->n[1] = float(nd.y); out->n[2] = float(nd.z);
  out->d = round_up(s + ctx.plane_margin);
}
void plane_world(const BuildContext& ctx, const Plane& p, Vec3d* n, double* d) {
  *n = Vec3d(double(p.n[0]), double(p.n[1]), double(p.n[2]));
  *d = double(p.d) + dot(*n, ctx.f.root_centre);
}

}  // namespace

namespace detail {

void FrameAccumulator::add(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  bb.add(a); bb.add(b); bb.add(c);
  edge_sum += norm(b - a) + norm(c - b) + norm(a - c);
  ++triangles;
}

void Frame::cell_box(Octcode c, Vec3d* lo, Vec3d* hi) const {
  std::uint32_t x, y, z;
  octcode_cell(c, &x, &y, &z);
  const double s = cell_size(octcode_level(c));
  *lo = {root_lo.x + double(x) * s, root_lo.y + double(y) * s, root_lo.z + double(z) * s};
  *hi = {root_lo.x + double(x + 1) * s, root_lo.y + double(y + 1) * s, root_lo.z + double(z + 1) * s};
}

Frame compute_frame(const FrameAccumulator& acc, const BuildParams& prm) {
  Frame F;
  const Box3d& bb = acc.bb;
  const double avg_edge = acc.edge_sum / (3.0 * double(acc.triangles));
  const Vec3d centre = (bb.lo + bb.hi) * 0.5;
  const Vec3d ext = bb.extent();
  double m = std::max({ext.x, ext.y, ext.z});
  const double cmag = std::max({std::fabs(centre.x), std::fabs(centre.y), std::fabs(centre.z)});
  m = std::max(m, 1e-6 * (cmag + 1e-30));
  if (m == 0) m = 1e-30;
  // Enlarge by 0.1 % (a margin on every side), then round the size to 20 significant bits and
  // the corner to a multiple of size / 2^39, so that every cell boundary at every level is an
  // exactly representable double, computed exactly by cell_box().
  const double s0 = m * 1.001;
  const int j = int(std::ceil(std::log2(s0))) - 20;
  const double M = std::ceil(std::ldexp(s0, -j));
  F.root_size = std::ldexp(M, j);
  const double unit = std::ldexp(1.0, j - kMaxLevel);
  for (int k = 0; k < 3; ++k) F.root_lo[k] = std::floor((centre[k] - 0.5 * F.root_size) / unit) * unit;
  F.root_centre = F.root_lo + Vec3d(0.5, 0.5, 0.5) * F.root_size;
  const int max_level = std::clamp(prm.max_level, 1, kMaxLevel);
  int L = 1;
  const double target = prm.leaf_factor * avg_edge;
  while (L < max_level && F.root_size / double(1u << (L + 1)) >= target) ++L;
  F.leaf_level = L;
  F.average_edge = avg_edge;
  return F;
}

BuildContext::BuildContext(const Frame& frame, const BuildParams& prm)
    : f(frame),
      cs(frame.cell_size(frame.leaf_level)),
      G(1u << frame.leaf_level),
      cos_cluster(std::cos(prm.cluster_angle * M_PI / 180.0)),
      max_planes(std::max(0, prm.max_planes)),
      plane_margin(1e-9 * frame.root_size) {}

void distribute_triangle(const BuildContext& ctx, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                         std::vector<std::uint64_t>& out) {
  const double cs = ctx.cs;
  const std::uint32_t G = ctx.G;
  const Vec3d& rl = ctx.f.root_lo;
  auto cell_range = [&](double lo, double hi, double r, double ext_rel, std::uint32_t* ia, std::uint32_t* ib) {
    const double slack = 1e-6 + 2e-9 * std::max(1.0, ext_rel);
    double fa = std::floor((lo - r) / cs - slack), fb = std::floor((hi - r) / cs + slack);
    fa = std::clamp(fa, 0.0, double(G - 1));
    fb = std::clamp(fb, 0.0, double(G - 1));
    *ia = std::uint32_t(fa);
    *ib = std::uint32_t(fb);
  };
  Box3d tb;
  tb.add(a); tb.add(b); tb.add(c);
  const double ext_rel = tb.diagonal() / cs;
  std::uint32_t x0, x1, y0, y1, z0, z1;
  cell_range(tb.lo.x, tb.hi.x, rl.x, ext_rel, &x0, &x1);
  cell_range(tb.lo.y, tb.hi.y, rl.y, ext_rel, &y0, &y1);
  cell_range(tb.lo.z, tb.hi.z, rl.z, ext_rel, &z0, &z1);
  for (std::uint32_t z = z0; z <= z1; ++z)
    for (std::uint32_t y = y0; y <= y1; ++y)
      for (std::uint32_t x = x0; x <= x1; ++x) {
        const Vec3d lo{rl.x + double(x) * cs, rl.y + double(y) * cs, rl.z + double(z) * cs};
        const Vec3d hi{rl.x + double(x + 1) * cs, rl.y + double(y + 1) * cs, rl.z + double(z + 1) * cs};
        const bool single = x0 == x1 && y0 == y1 && z0 == z1;
        if (single || tri_box_overlap(lo, hi, a, b, c)) out.push_back(morton_encode(x, y, z));
      }
}

Vec3d face_portal(const Frame& f, std::uint32_t x, std::uint32_t y, std::uint32_t z, int dir) {
  const int axis = dir >> 1;
  const double cs = f.cell_size(f.leaf_level);
  const std::int64_t c[3] = {x, y, z};
  // Fixed, non-dyadic fractions of the face (a mesh vertex there is unlikely; if a triangle does
  // pass through the portal the adjacency is degenerate and skipped, as any other).
  static const double frac[3] = {0.4137, 0.5629, 0.4871};
  Vec3d p;
  for (int k = 0; k < 3; ++k) {
    if (k == axis) {
      const std::int64_t face = c[k] + ((dir & 1) ? 1 : 0);
      p[k] = f.root_lo[k] + double(face) * cs;
    } else {
      p[k] = f.root_lo[k] + (double(c[k]) + frac[k]) * cs;
    }
  }
  return p;
}

void build_leaf(const BuildContext& ctx, Octcode code, std::size_t n, const std::uint32_t* tri, const float* xyz,
                Node* ndp, Leaf* lfp, LeafTri* out, NodeTmp* tmp, LeafHalves* halves) {
  Node& nd = *ndp;
  Leaf& lf = *lfp;
  const double cs = ctx.cs;
  const int max_planes = ctx.max_planes;
  const double cos_cluster = ctx.cos_cluster;
  nd.code = code;
  nd.kind = NodeKind::leaf;
  nd.plane_begin = 0;
  nd.plane_count = 0;
  Vec3d lo, hi;
  ctx.f.cell_box(code, &lo, &hi);
  const Vec3d cc = (lo + hi) * 0.5;
  const Vec3d cfd = round_to_float(cc);
  lf.centre[0] = float(cfd.x); lf.centre[1] = float(cfd.y); lf.centre[2] = float(cfd.z);
  lf.tri_count = std::uint32_t(n);
  lf.pad = 0;
  double R = 0.5 * cs * std::sqrt(3.0) + norm(cc - cfd);
  std::vector<Vec3d> geo;  // vertices of triangle ∩ cell polygons
  struct Cand { Vec3d n; double area; std::uint32_t t; };
  std::vector<Cand> cands;
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t t = tri[k];
    LeafTri& r = out[k];
    const float* v = xyz + 9 * k;
    const Vec3d a{double(v[0]), double(v[1]), double(v[2])}, b{double(v[3]), double(v[4]), double(v[5])},
        c{double(v[6]), double(v[7]), double(v[8])};
    for (int q = 0; q < 3; ++q) { r.a[q] = v[q]; r.b[q] = v[3 + q]; r.c[q] = v[6 + q]; }
    r.tri = t;
    r.flags = 0;
    r.pad = 0;
    const bool degen = collinear_exact(a, b, c);
    const Vec3d nrm = cross(b - a, c - a);
    const double len = norm(nrm);
    if (degen) r.flags |= kDegenerate;
    if (!degen && len >= 1e-6 * norm(b - a) * norm(c - a)) {
      const Vec3d nn = nrm / len;
      const Vec3d nf = round_to_float(nn);
      r.n[0] = float(nf.x); r.n[1] = float(nf.y); r.n[2] = float(nf.z);
      r.d = float(dot(nf, a - cfd));
      cands.push_back({nn, 0.5 * len, t});
    } else {
      r.n[0] = r.n[1] = r.n[2] = 0.f;
      r.d = 0.f;
    }
    R = std::max({R, norm(a - cfd), norm(b - cfd), norm(c - cfd)});
    clip_triangle_to_box(lo, hi, a, b, c, geo);
  }
  // The LeafTri block out[0, n) is complete: put it in spatial order (leaf_blocks.hpp; the
  // distance query bounds groups of consecutive triangles). Both builds pass here.
  order_leaf_triangles(out, std::uint32_t(n));
  lf.eps = round_up(2e-6 * R);
  if (geo.empty()) {  // touches only within the margin: bound by the cell's own centre
    geo.push_back(cc);
  }
  // Bounding planes: greedy angular cover of the face normals (largest faces first), both
  // orientations of each representative, offset to the support of the clipped geometry.
  std::sort(cands.begin(), cands.end(), [](const Cand& x, const Cand& y) {
    return x.area > y.area || (x.area == y.area && x.t < y.t);
  });
  std::vector<Vec3d> reps;
  for (const Cand& cd : cands) {
    if (int(reps.size()) * 2 >= max_planes) break;
    bool covered = false;
    for (const Vec3d& r : reps)
      if (std::fabs(dot(r, cd.n)) >= cos_cluster) { covered = true; break; }
    if (!covered) reps.push_back(cd.n);
  }
  struct Scored { Plane p; double cut; };
  std::vector<Scored> sc;
  for (const Vec3d& r : reps)
    for (double sgn : {1.0, -1.0}) {
      Plane p;
      make_plane(ctx, r * sgn, geo, &p);
      Vec3d nw; double d;
      plane_world(ctx, p, &nw, &d);
      const double cut = box_support(lo, hi, nw) - d;
      if (cut > 1e-4 * cs) sc.push_back({p, cut});
    }
  std::stable_sort(sc.begin(), sc.end(), [](const Scored& x, const Scored& y) { return x.cut > y.cut; });
  if (int(sc.size()) > max_planes) sc.resize(std::size_t(max_planes));
  NodeTmp& tm = *tmp;
  tm.planes.clear();
  Polytope poly = Polytope::box(lo, hi);
  for (auto& s : sc) {
    tm.planes.push_back(s.p);
    Vec3d nw; double d;
    plane_world(ctx, s.p, &nw, &d);
    poly.clip(nw, d);
  }
  tm.poly = poly.vertices();
  if (tm.poly.empty()) {  // numerically flat: fall back to the box corners (conservative)
    tm.poly = Polytope::box(lo, hi).vertices();
  }
  tm.volume = poly.volume();
  tm.box_volume = cs * cs * cs;
  nd.plane_count = std::uint16_t(tm.planes.size());

  // Configuration, on the exact face planes and the triangles' vertices.
  // The distinct vertices (a small hash set on the float bits; the classification below does not
  // depend on their order, only on which exist).
  const LeafTri* blk = out;
  std::vector<Vec3d> verts;
  {
    std::size_t cap = 16;
    while (cap < 6 * std::size_t(lf.tri_count)) cap <<= 1;
    struct Key { std::uint32_t x, y, z, used; };
    std::vector<Key> set(cap, Key{0, 0, 0, 0});
    for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
      if (blk[k].flags & kDegenerate) continue;
      for (const float* f : {blk[k].a, blk[k].b, blk[k].c}) {
        Key key{0, 0, 0, 1};
        std::memcpy(&key.x, &f[0], 4);
        std::memcpy(&key.y, &f[1], 4);
        std::memcpy(&key.z, &f[2], 4);
        std::uint64_t h = (std::uint64_t(key.x) * 0x9E3779B97F4A7C15ull) ^ (std::uint64_t(key.y) * 0xC2B2AE3D27D4EB4Full) ^
                          (std::uint64_t(key.z) * 0x165667B19E3779F9ull);
        h ^= h >> 29;
        for (std::size_t i = std::size_t(h) & (cap - 1);; i = (i + 1) & (cap - 1)) {
          Key& e = set[i];
          if (!e.used) {
            e = key;
            verts.push_back(to_d(f));
            break;
          }
          if (e.x == key.x && e.y == key.y && e.z == key.z) break;
        }
      }
    }
  }
  bool convex = !verts.empty(), concave = !verts.empty();
  for (std::uint32_t k = 0; k < lf.tri_count && (convex || concave); ++k) {
    if (blk[k].flags & kDegenerate) continue;
    const Vec3d a = to_d(blk[k].a), b = to_d(blk[k].b), c = to_d(blk[k].c);
    for (const Vec3d& v : verts) {
      const int o = orient3d(a, b, c, v);
      if (o > 0) convex = false;
      if (o < 0) concave = false;
      if (!convex && !concave) break;
    }
  }
  nd.config = convex ? LeafConfig::convex : concave ? LeafConfig::concave : LeafConfig::special;

  // Reference point: strictly inside the cell, off every face plane; for convex (concave)
  // leaves, preferably on the inner (outer) side of all of them, so that the common query needs
  // no edge test.
  const double half = 0.5 * cs;
  int best_score = -1;
  std::vector<std::uint8_t> sides(lf.tri_count), best_sides;
  Vec3d best_ref = cc;
  for (const Vec3d& off : ref_offsets()) {
    const Vec3d r0 = cc + off * half;
    const Vec3d r = round_to_float(r0);
    if (!(r.x > lo.x && r.x < hi.x && r.y > lo.y && r.y < hi.y && r.z > lo.z && r.z < hi.z)) continue;
    bool ok = true;
    int inner = 0, outer = 0;
    for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
      if (blk[k].flags & kDegenerate) { sides[k] = 0; continue; }
      const int o = orient3d(to_d(blk[k].a), to_d(blk[k].b), to_d(blk[k].c), r);
      if (o == 0) { ok = false; break; }
      sides[k] = o > 0;
      (o > 0 ? outer : inner)++;
    }
    if (!ok) continue;
    const int score = nd.config == LeafConfig::convex ? inner : nd.config == LeafConfig::concave ? outer : 0;
    if (score > best_score) {
      best_score = score;
      best_ref = r;
      best_sides = sides;
      if (nd.config == LeafConfig::special || score == int(lf.tri_count)) break;
    }
  }
  lf.ref_valid = best_score >= 0;
  lf.ref[0] = float(best_ref.x); lf.ref[1] = float(best_ref.y); lf.ref[2] = float(best_ref.z);
  lf.ref_winding = 0;
  if (lf.ref_valid)
    for (std::uint32_t k = 0; k < lf.tri_count; ++k)
      if (best_sides[k]) out[k].flags |= kRefPositive;

  // Colouring half-edges: reference point -> portal of each face, over this leaf's triangles
  // only (the segment lies in the closed cell, and every triangle meeting the closed cell is in
  // the block: the distribution is conservative).
  // This is segment_winding(ref, portal) with the reference's exact sides already known (every
  // non-degenerate plane, nonzero) and the portal's side filtered by the leaf's float planes
  // (|s| > eps decides, as in the queries; otherwise orient3d): the same result, cheaper.
  for (int dir = 0; dir < 6; ++dir) halves->h[dir] = kDegenerateHalf;
  if (lf.ref_valid) {
    std::uint32_t x, y, z;
    octcode_cell(code, &x, &y, &z);
    const Vec3d ra = to_d(lf.ref);
    const float eps = lf.eps;
    for (int dir = 0; dir < 6; ++dir) {
      const Vec3d q = face_portal(ctx.f, x, y, z, dir);
      const float qx = float(q.x - double(lf.centre[0])), qy = float(q.y - double(lf.centre[1])),
                  qz = float(q.z - double(lf.centre[2]));
      int w = 0;
      bool ok = true;
      for (std::size_t k = 0; k < n && ok; ++k) {
        const LeafTri& t = out[k];
        if (t.flags & kDegenerate) continue;
        const int sp = (t.flags & kRefPositive) ? 1 : -1;
        const float s = t.n[0] * qx + t.n[1] * qy + t.n[2] * qz - t.d;
        int sq;
        if (s > eps) sq = 1;
        else if (s < -eps) sq = -1;
        else sq = orient3d(to_d(t.a), to_d(t.b), to_d(t.c), q);
        if (sq == sp) continue;
        const Vec3d a = to_d(t.a), b = to_d(t.b), c = to_d(t.c);
        const Cross r = sq != 0 ? segment_triangle(ra, q, sp, sq, a, b, c) : segment_triangle(q, ra, sq, sp, a, b, c);
        if (r == Cross::degenerate || r == Cross::on_p) ok = false;
        else if (r == Cross::proper) w += sp;
      }
      if (ok) halves->h[dir] = w;
    }
  }
}

void build_inner(const BuildContext& ctx, Octcode code, NodeTmp* const children[8], NodeTmp* tmp) {
  Vec3d lo, hi;
  ctx.f.cell_box(code, &lo, &hi);
  const double csl = hi.x - lo.x;
  std::vector<Vec3d> pts;
  std::vector<Vec3d> cand;
  for (int o = 0; o < 8; ++o) {
    NodeTmp* ct = children[o];
    if (!ct) continue;
    pts.insert(pts.end(), ct->poly.begin(), ct->poly.end());
    for (const Plane& p : ct->planes) cand.push_back({double(p.n[0]), double(p.n[1]), double(p.n[2])});
    std::vector<Vec3d>().swap(ct->poly);  // children's volumes are no longer needed
  }
  struct Scored { Plane p; double cut; Vec3d n; };
  std::vector<Scored> sc;
  for (const Vec3d& nn : cand) {
    Plane p;
    make_plane(ctx, nn, pts, &p);
    Vec3d nw; double d;
    plane_world(ctx, p, &nw, &d);
    const double cut = box_support(lo, hi, nw) - d;
    if (cut > 1e-4 * csl) sc.push_back({p, cut, nw});
  }
  std::stable_sort(sc.begin(), sc.end(), [](const Scored& x, const Scored& y) { return x.cut > y.cut; });
  NodeTmp& tm = *tmp;
  tm.planes.clear();
  std::vector<Vec3d> chosen;
  for (const Scored& s : sc) {
    if (int(tm.planes.size()) >= ctx.max_planes) break;
    bool close = false;
    for (const Vec3d& c : chosen)
      if (dot(c, s.n) >= ctx.cos_cluster) { close = true; break; }
    if (close) continue;
    chosen.push_back(s.n);
    tm.planes.push_back(s.p);
  }
  Polytope poly = Polytope::box(lo, hi);
  for (const Plane& p : tm.planes) {
    Vec3d nw; double d;
    plane_world(ctx, p, &nw, &d);
    poly.clip(nw, d);
  }
  tm.poly = poly.vertices();
  if (tm.poly.empty()) tm.poly = Polytope::box(lo, hi).vertices();
  tm.volume = poly.volume();
  tm.box_volume = csl * csl * csl;
}

std::uint32_t Skeleton::locate_cell(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
  std::uint32_t i = 0;
  while (kind[i] == NodeKind::inner) {
    const int shift = leaf_level - octcode_level(code[i]) - 1;
    const int o = int((x >> shift) & 1u) | int(((y >> shift) & 1u) << 1) | int(((z >> shift) & 1u) << 2);
    i = children[index[i] + std::uint32_t(o)];
  }
  return i;
}

std::size_t Skeleton::bytes() const {
  return code.capacity() * sizeof(Octcode) + kind.capacity() + index.capacity() * 4 + children.capacity() * 4 +
         leaf_node.capacity() * 4 + leaf_ref.capacity() * 12 + leaf_ref_valid.capacity() +
         leaf_halves.capacity() * sizeof(LeafHalves);
}

Colouring colour(const Frame& F, Skeleton& sk, const WindingBatch& winding_at) {
  Colouring C;
  const std::size_t N = sk.code.size();
  const std::size_t nleaves = sk.leaf_node.size();
  const int L = sk.leaf_level;
  const std::uint32_t G = 1u << L;
  C.ref_winding.assign(nleaves, 0);
  const std::uint32_t OUT = std::uint32_t(N);
  UnionFind uf(N + 1);
  // Empty nodes touching the root's boundary are outside: the root is larger than the model's
  // bounding box on every side.
  for (std::size_t i = 0; i < N; ++i) {
    if (sk.kind[i] != NodeKind::white) continue;
    std::uint32_t x, y, z;
    octcode_cell(sk.code[i], &x, &y, &z);
    const std::uint32_t last = (1u << octcode_level(sk.code[i])) - 1;
    if (x == 0 || y == 0 || z == 0 || x == last || y == last || z == last) uf.unite(std::uint32_t(i), OUT, 0);
  }
  // Adjacencies of leaves, in leaf order: w(target) - w(ref_A) from the two half-edges through the
  // portal of the shared face (ref_A -> portal over A's triangles, portal -> ref_B over B's), or
  // the one half-edge to the portal when the target is an empty node or the outside.
  for (std::size_t li = 0; li < nleaves; ++li) {
    if (!sk.leaf_ref_valid[li]) continue;
    const std::uint32_t ni = sk.leaf_node[li];
    std::uint32_t c[3];
    octcode_cell(sk.code[ni], &c[0], &c[1], &c[2]);
    for (int dir = 0; dir < 6; ++dir) {
      const int axis = dir >> 1;
      const bool pos = dir & 1;
      std::uint32_t nb[3] = {c[0], c[1], c[2]};
      std::uint32_t target;
      bool to_leaf = false;
      if ((!pos && c[axis] == 0) || (pos && c[axis] == G - 1)) {
        target = OUT;
      } else {
        nb[axis] = pos ? c[axis] + 1 : c[axis] - 1;
        target = sk.locate_cell(nb[0], nb[1], nb[2]);
        to_leaf = sk.kind[target] == NodeKind::leaf;
        if (to_leaf && !sk.leaf_ref_valid[sk.index[target]]) continue;
      }
      int pa, pb;
      if (uf.find(ni, &pa) == uf.find(target, &pb)) continue;
      const std::int32_t ha = sk.leaf_halves[li].h[dir];
      const std::int32_t hb = to_leaf ? sk.leaf_halves[sk.index[target]].h[dir ^ 1] : 0;
      if (ha == kDegenerateHalf || hb == kDegenerateHalf) { ++C.degenerate_edges; continue; }
      // w(portal) - w(ref_A) = ha, w(portal) - w(ref_B) = hb.
      uf.unite(ni, target, ha - hb);
    }
  }
  // Empty nodes not yet joined: probe the cells just across their faces for joined empty nodes.
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t i = 0; i < N; ++i) {
      if (sk.kind[i] != NodeKind::white || uf.touched[i]) continue;
      std::uint32_t c[3];
      octcode_cell(sk.code[i], &c[0], &c[1], &c[2]);
      const int l = octcode_level(sk.code[i]);
      const std::uint32_t span = 1u << (L - l);
      bool done = false;
      for (int dir = 0; dir < 6 && !done; ++dir) {
        const int axis = dir >> 1;
        const bool pos = dir & 1;
        for (int qd = 0; qd < 4 && !done; ++qd) {
          std::uint32_t p[3];
          for (int k = 0; k < 3; ++k) p[k] = c[k] * span;
          const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
          p[a1] += (qd & 1) ? (3 * span) / 4 : span / 4;
          p[a2] += (qd & 2) ? (3 * span) / 4 : span / 4;
          if (pos) p[axis] += span; else if (p[axis] == 0) continue; else p[axis] -= 1;
          if (p[axis] >= G) continue;
          const std::uint32_t k = sk.locate_cell(p[0], p[1], p[2]);
          if (k != i && sk.kind[k] == NodeKind::white && uf.touched[k]) {
            uf.unite(std::uint32_t(i), k, 0);
            done = changed = true;
          }
        }
      }
    }
  }
  // Windings. OUT has w = 0. Components not joined to the outside (only when every edge of a
  // region was degenerate) take the generalized winding number of one of their points (the first
  // node of the component in node order), computed for all such components in one batch.
  int pout;
  const std::uint32_t rout = uf.find(OUT, &pout);
  std::vector<int> comp_w(N + 1, 0);
  std::vector<std::uint8_t> comp_known(N + 1, 0);
  comp_w[rout] = -pout;  // w(root) = w(OUT) - (w(OUT) - w(root))
  comp_known[rout] = 1;
  std::vector<Vec3d> fb_pts;
  std::vector<std::pair<std::uint32_t, int>> fb_comp;  // root, pot of the point
  auto point_of = [&](std::size_t i) {
    if (sk.kind[i] == NodeKind::white) {
      Vec3d lo, hi;
      F.cell_box(sk.code[i], &lo, &hi);
      return (lo + hi) * 0.5;
    }
    const auto& r = sk.leaf_ref[sk.index[i]];
    return Vec3d(double(r[0]), double(r[1]), double(r[2]));
  };
  auto needs_colour = [&](std::size_t i) {
    return sk.kind[i] == NodeKind::white || (sk.kind[i] == NodeKind::leaf && sk.leaf_ref_valid[sk.index[i]]);
  };
  for (std::size_t i = 0; i < N; ++i) {
    if (!needs_colour(i)) continue;
    int pot;
    const std::uint32_t r = uf.find(std::uint32_t(i), &pot);
    if (comp_known[r]) continue;
    comp_known[r] = 2;  // pending
    fb_pts.push_back(point_of(i));
    fb_comp.push_back({r, pot});
  }
  if (!fb_pts.empty()) {
    const std::vector<int> w = winding_at(fb_pts);
    for (std::size_t k = 0; k < fb_comp.size(); ++k) {
      comp_w[fb_comp[k].first] = w[k] - fb_comp[k].second;
      comp_known[fb_comp[k].first] = 1;
    }
    C.colour_fallbacks = fb_pts.size();
  }
  for (std::size_t i = 0; i < N; ++i) {
    if (sk.kind[i] == NodeKind::white) {
      int pot;
      const std::uint32_t r = uf.find(std::uint32_t(i), &pot);
      if (comp_w[r] + pot >= 1) C.black.push_back(std::uint32_t(i));
    } else if (sk.kind[i] == NodeKind::leaf) {
      const std::uint32_t li = sk.index[i];
      if (sk.leaf_ref_valid[li]) {
        int pot;
        const std::uint32_t r = uf.find(std::uint32_t(i), &pot);
        C.ref_winding[li] = std::int16_t(std::clamp(comp_w[r] + pot, -32768, 32767));
      } else {
        ++C.invalid_refs;
      }
    }
  }
  return C;
}

}  // namespace detail

using namespace detail;

Octree Octree::build(const std::vector<Vec3d>& vin, const std::vector<std::array<std::uint32_t, 3>>& tin,
                     const BuildParams& prm, const std::function<void(double)>& progress) {
  const auto t_start = Clock::now();
  auto report = [&](double f) { if (progress) progress(f); };
  if (tin.empty()) throw std::invalid_argument("ebp_octree: the mesh has no triangle");
  if (tin.size() >= (1ull << 31)) throw std::invalid_argument("ebp_octree: more than 2^31 triangles");
  const int threads = std::max(1, prm.threads);

  Octree T;
  T.num_triangles = std::uint32_t(tin.size());
  const std::size_t nt = tin.size();

  // ---- 1. geometry in float (the structure's geometry), cube, leaf level ----
  std::vector<Vec3d> V(vin.size());
  for (std::size_t i = 0; i < vin.size(); ++i) {
    const Vec3d& v = vin[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      throw std::invalid_argument("ebp_octree: non-finite vertex coordinate");
    V[i] = round_to_float(v);
  }
  FrameAccumulator acc;
  for (const auto& t : tin) {
    for (int k = 0; k < 3; ++k)
      if (t[k] >= V.size()) throw std::invalid_argument("ebp_octree: vertex index out of range");
    acc.add(V[t[0]], V[t[1]], V[t[2]]);
  }
  const Frame F = compute_frame(acc, prm);
  const BuildContext ctx(F, prm);
  T.root_lo = F.root_lo;
  T.root_centre = F.root_centre;
  T.root_size = F.root_size;
  T.leaf_level = F.leaf_level;
  const int L = F.leaf_level;
  const double cs = ctx.cs;
  Stats& S = T.stats;
  S.leaf_level = L;
  S.root_size = T.root_size;
  S.leaf_size = cs;
  S.average_edge = F.average_edge;
  S.triangles = nt;
  report(0.02);

  // ---- 2. distribution ----
  auto t0 = Clock::now();
  std::vector<Pair> pairs;
  {
    auto distribute = [&](std::size_t t, std::vector<Pair>& out, std::vector<std::uint64_t>& ms) {
      ms.clear();
      distribute_triangle(ctx, V[tin[t][0]], V[tin[t][1]], V[tin[t][2]], ms);
      for (std::uint64_t m : ms) out.push_back({m, std::uint32_t(t)});
    };
    if (threads <= 1) {
      pairs.reserve(nt * 2);
      std::vector<std::uint64_t> ms;
      for (std::size_t t = 0; t < nt; ++t) distribute(t, pairs, ms);
      std::sort(pairs.begin(), pairs.end());
    } else {
      tbb::enumerable_thread_specific<std::vector<Pair>> local;
      tbb::enumerable_thread_specific<std::vector<std::uint64_t>> local_ms;
      tbb::task_arena arena(threads);
      arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
          auto& out = local.local();
          auto& ms = local_ms.local();
          for (std::size_t t = r.begin(); t != r.end(); ++t) distribute(t, out, ms);
        });
        std::size_t total = 0;
        for (auto& v : local) total += v.size();
        pairs.reserve(total);
        for (auto& v : local) pairs.insert(pairs.end(), v.begin(), v.end());
        tbb::parallel_sort(pairs.begin(), pairs.end());
      });
    }
  }
  S.seconds_distribute = since(t0);
  S.triangle_refs = pairs.size();
  report(0.25);

  // ---- 3. the node set ----
  // Leaves: unique Morton codes, with their pair ranges.
  std::vector<std::uint64_t> leaf_m;
  std::vector<std::uint32_t> leaf_begin;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (i == 0 || pairs[i].m != pairs[i - 1].m) {
      leaf_m.push_back(pairs[i].m);
      leaf_begin.push_back(std::uint32_t(i));
    }
  leaf_begin.push_back(std::uint32_t(pairs.size()));
  const std::size_t nleaves = leaf_m.size();
  // Grey prefixes per level.
  std::vector<std::vector<std::uint64_t>> grey(L + 1);
  grey[L] = leaf_m;
  for (int l = L - 1; l >= 0; --l) {
    for (std::uint64_t mm : grey[l + 1]) {
      const std::uint64_t p = mm >> 3;
      if (grey[l].empty() || grey[l].back() != p) grey[l].push_back(p);
    }
  }
  std::vector<Octcode> codes;
  for (int l = 0; l <= L; ++l)
    for (std::uint64_t g : grey[l]) codes.push_back(octcode_make(l, g));
  for (int l = 0; l < L; ++l)
    for (std::uint64_t g : grey[l])
      for (std::uint64_t o = 0; o < 8; ++o) {
        const std::uint64_t c = (g << 3) | o;
        if (!std::binary_search(grey[l + 1].begin(), grey[l + 1].end(), c)) codes.push_back(octcode_make(l + 1, c));
      }
  std::sort(codes.begin(), codes.end());
  if (codes.size() >= 0xffffffffull) throw std::runtime_error("ebp_octree: too many nodes");
  const std::size_t N = codes.size();
  T.nodes.resize(N);
  auto index_of = [&](Octcode c) {
    return std::uint32_t(std::lower_bound(codes.begin(), codes.end(), c) - codes.begin());
  };
  std::size_t ninner = 0;
  for (int l = 0; l < L; ++l) ninner += grey[l].size();
  T.children.resize(ninner * 8);
  T.leaves.resize(nleaves);
  std::vector<std::uint32_t> leaf_node(nleaves);
  {
    std::uint32_t next_child = 0, next_leaf = 0;
    for (std::size_t i = 0; i < N; ++i) {
      Node& nd = T.nodes[i];
      nd.code = codes[i];
      nd.plane_begin = 0;
      nd.plane_count = 0;
      nd.config = LeafConfig::special;
      nd.next = index_of(octcode_subtree_end(codes[i]));
      const int l = octcode_level(codes[i]);
      const std::uint64_t mm = octcode_morton(codes[i]);
      const bool is_grey = std::binary_search(grey[l].begin(), grey[l].end(), mm);
      if (!is_grey) {
        nd.kind = NodeKind::white;  // coloured in step 6
        nd.index = 0;
      } else if (l < L) {
        nd.kind = NodeKind::inner;
        nd.index = next_child;
        for (int o = 0; o < 8; ++o) T.children[next_child + o] = index_of(octcode_child(codes[i], o));
        next_child += 8;
      } else {
        nd.kind = NodeKind::leaf;
        nd.index = next_leaf;  // leaves are met in Morton order = leaf_m order
        leaf_node[next_leaf] = std::uint32_t(i);
        ++next_leaf;
      }
    }
  }
  report(0.3);

  // ---- 4. leaves ----
  t0 = Clock::now();
  std::vector<NodeTmp> tmp(N);
  std::vector<LeafHalves> halves(nleaves);
  T.tris.resize(pairs.size());
  par_for(threads, nleaves, [&](std::size_t li) {
    const std::uint32_t ni = leaf_node[li];
    Node& nd = T.nodes[ni];
    Leaf& lf = T.leaves[li];
    const std::uint32_t b = leaf_begin[li], e = leaf_begin[li + 1];
    std::vector<std::uint32_t> tri(e - b);
    std::vector<float> xyz(9 * std::size_t(e - b));
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t t = pairs[k].t;
      tri[k - b] = t;
      for (int q = 0; q < 3; ++q)
        for (int ax = 0; ax < 3; ++ax) xyz[9 * std::size_t(k - b) + 3 * q + ax] = float(V[tin[t][q]][ax]);
    }
    const std::uint32_t next = nd.next, index = nd.index;
    build_leaf(ctx, nd.code, e - b, tri.data(), xyz.data(), &nd, &lf, &T.tris[b], &tmp[ni], &halves[li]);
    nd.next = next;
    nd.index = index;
    lf.tri_begin = b;
  });
  S.seconds_leaves = since(t0);
  report(0.6);

  // ---- 5. inner nodes, bottom-up ----
  t0 = Clock::now();
  {
    std::vector<std::vector<std::uint32_t>> inner_at(L);
    for (std::size_t i = 0; i < N; ++i)
      if (T.nodes[i].kind == NodeKind::inner) inner_at[octcode_level(T.nodes[i].code)].push_back(std::uint32_t(i));
    for (int l = L - 1; l >= 0; --l) {
      const auto& list = inner_at[l];
      par_for(threads, list.size(), [&](std::size_t q) {
        const std::uint32_t ni = list[q];
        const Node& nd = T.nodes[ni];
        NodeTmp* ch[8];
        for (int o = 0; o < 8; ++o) {
          const std::uint32_t ci = T.children[nd.index + o];
          const NodeKind k = T.nodes[ci].kind;
          ch[o] = (k == NodeKind::inner || k == NodeKind::leaf) ? &tmp[ci] : nullptr;
        }
        build_inner(ctx, nd.code, ch, &tmp[ni]);
      });
    }
  }
  // Plane pool in node order.
  for (std::size_t i = 0; i < N; ++i) {
    Node& nd = T.nodes[i];
    nd.plane_begin = std::uint32_t(T.planes.size());
    nd.plane_count = std::uint16_t(tmp[i].planes.size());
    T.planes.insert(T.planes.end(), tmp[i].planes.begin(), tmp[i].planes.end());
    S.max_planes_per_node = std::max<std::size_t>(S.max_planes_per_node, tmp[i].planes.size());
    if (nd.kind == NodeKind::leaf) {
      S.leaf_planes += tmp[i].planes.size();
      S.leaf_volume += tmp[i].volume;
      S.leaf_box_volume += tmp[i].box_volume;
    } else if (nd.kind == NodeKind::inner) {
      S.inner_planes += tmp[i].planes.size();
      S.inner_volume += tmp[i].volume;
      S.inner_box_volume += tmp[i].box_volume;
    }
  }
  std::vector<NodeTmp>().swap(tmp);
  S.seconds_inner = since(t0);
  report(0.8);

  // ---- 6. colouring ----
  t0 = Clock::now();
  {
    Skeleton sk;
    sk.leaf_level = L;
    sk.code.resize(N);
    sk.kind.resize(N);
    sk.index.resize(N);
    for (std::size_t i = 0; i < N; ++i) {
      sk.code[i] = T.nodes[i].code;
      sk.kind[i] = T.nodes[i].kind;
      sk.index[i] = T.nodes[i].index;
    }
    sk.children = T.children;
    sk.leaf_node = leaf_node;
    sk.leaf_ref.resize(nleaves);
    sk.leaf_ref_valid.resize(nleaves);
    for (std::size_t li = 0; li < nleaves; ++li) {
      for (int k = 0; k < 3; ++k) sk.leaf_ref[li][k] = T.leaves[li].ref[k];
      sk.leaf_ref_valid[li] = T.leaves[li].ref_valid;
    }
    sk.leaf_halves = std::move(halves);
    auto winding_at = [&](const std::vector<Vec3d>& pts) {
      std::vector<int> out;
      for (const Vec3d& p : pts) {
        double w = 0;
        for (const auto& t : tin) w += bvhbench::triangle_winding(p, V[t[0]], V[t[1]], V[t[2]]);
        out.push_back(int(std::lround(w)));
      }
      return out;
    };
    const Colouring C = colour(F, sk, winding_at);
    for (std::uint32_t i : C.black) T.nodes[i].kind = NodeKind::black;
    for (std::size_t li = 0; li < nleaves; ++li) T.leaves[li].ref_winding = C.ref_winding[li];
    S.colour_fallbacks = C.colour_fallbacks;
    S.degenerate_edges = C.degenerate_edges;
    S.invalid_refs = C.invalid_refs;
  }
  S.seconds_colour = since(t0);

  // ---- stats ----
  S.nodes = N;
  S.leaves = nleaves;
  S.inner = ninner;
  S.planes = T.planes.size();
  S.nodes_per_level.assign(L + 1, 0);
  for (const Node& nd : T.nodes) {
    S.nodes_per_level[octcode_level(nd.code)]++;
    if (nd.kind == NodeKind::white) ++S.white;
    if (nd.kind == NodeKind::black) ++S.black;
    if (nd.kind == NodeKind::leaf) {
      if (nd.config == LeafConfig::convex) ++S.convex;
      else if (nd.config == LeafConfig::concave) ++S.concave;
      else ++S.special;
    }
  }
  for (const Leaf& lf : T.leaves) S.max_refs_per_leaf = std::max<std::size_t>(S.max_refs_per_leaf, lf.tri_count);
  // ---- closedness (by vertex index): every undirected edge is used as often in each direction.
  // Then the winding number is a function of the point, so a coherent query may count crossings
  // from the previous point instead of the leaf's reference (same integer, exactly).
  if (vin.size() < (std::size_t(1) << 31)) {
    std::vector<std::uint64_t> keys;
    keys.reserve(3 * nt);
    for (const auto& t : tin)
      for (int k = 0; k < 3; ++k) {
        const std::uint64_t u = t[k], v = t[(k + 1) % 3];
        if (u == v) continue;
        keys.push_back(u < v ? (u << 33 | v << 1 | 0u) : (v << 33 | u << 1 | 1u));
      }
    std::sort(keys.begin(), keys.end());
    bool closed = true;
    for (std::size_t i = 0; i < keys.size() && closed;) {
      std::size_t j = i;
      long bal = 0;
      while (j < keys.size() && (keys[j] >> 1) == (keys[i] >> 1)) bal += (keys[j++] & 1u) ? -1 : 1;
      closed = bal == 0;
      i = j;
    }
    T.closed = closed;
  }
  compute_leaf_blocks(T);  // derived boxes (leaf_blocks.hpp)
  S.build_seconds = since(t_start);
  // (Hook: the tree is complete here.)
  report(1.0);
  return T;
}

}  // namespace ebp
