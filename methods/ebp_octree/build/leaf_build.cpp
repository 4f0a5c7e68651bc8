// One grey leaf (build_parts.hpp, build_leaf): its triangle block, bounding planes (clustered
// face normals, offset to the support of triangle ∩ cell), configuration, reference point and
// the colouring's half-edges.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <vector>

#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/build/plane_fit.hpp"
#include "methods/ebp_octree/build/polytope.hpp"
#include "methods/ebp_octree/build/tri_box.hpp"
#include "methods/ebp_octree/core/face_normal.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/leaf_blocks.hpp"
#include "methods/ebp_octree/core/leaf_kernels.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/core/reference_points.hpp"

namespace ebp::detail {
namespace {

/// A face normal that may give a bounding plane: its unit normal, area and input index.
struct Cand {
  Vec3d n;
  double area;
  std::uint32_t t;
};

/// What the triangle block tells the leaf's planes and filter: the candidate normals, the
/// vertices of triangle ∩ cell polygons, and the radius around the float centre.
struct LeafGeometry {
  std::vector<Cand> cands;
  std::vector<Vec3d> geo;
  double radius = 0;
  double normal_error = 0;  ///< the largest direction error of the block's face-normal codes
};

/// The LeafTri records out[0, n) of the leaf's triangles (in input order), with their float face
/// planes relative to the leaf's float centre `cfd`.
LeafGeometry fill_triangle_block(const Vec3d& lo, const Vec3d& hi, const Vec3d& cc, const Vec3d& cfd, double cs,
                                 std::size_t n, const std::uint32_t* tri, const float* xyz, LeafTri* out) {
  LeafGeometry g;
  g.radius = 0.5 * cs * std::sqrt(3.0) + norm(cc - cfd);
  g.geo.reserve(5 * n);  // a clipped triangle has 3-9 vertices, 3-5 typically: no regrowth
  g.cands.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t t = tri[k];
    LeafTri& r = out[k];
    const float* v = xyz + 9 * k;
    const Vec3d a{double(v[0]), double(v[1]), double(v[2])}, b{double(v[3]), double(v[4]), double(v[5])},
        c{double(v[6]), double(v[7]), double(v[8])};
    for (int q = 0; q < 3; ++q) { r.a[q] = v[q]; r.b[q] = v[3 + q]; r.c[q] = v[6 + q]; }
    r.tri_flags = t;
    const bool degen = collinear_exact(a, b, c);
    const Vec3d nrm = cross(b - a, c - a);
    const double len = norm(nrm);
    if (degen) r.tri_flags |= kDegenerate;
    double normal_err = 1;
    if (!degen && len >= 1e-6 * norm(b - a) * norm(c - a)) {
      const Vec3d nn = nrm / len;
      r.normal = encode_face_normal(nn, &normal_err);
      float v[3];
      decode_face_normal(r.normal, v);
      r.d = float(dot(to_d(v), a - cfd));
      g.cands.push_back({nn, 0.5 * len, t});
    }
    if (normal_err > kFaceNormalError) {  // no plane: every side test of this triangle goes exact
      r.tri_flags |= kNoPlane;
      r.normal = 0;
      r.d = 0.f;
    } else {
      g.normal_error = std::max(g.normal_error, normal_err);
    }
    g.radius = std::max({g.radius, norm(a - cfd), norm(b - cfd), norm(c - cfd)});
    clip_triangle_to_box(lo, hi, a, b, c, g.geo);
  }
  if (g.geo.empty()) g.geo.push_back(cc);  // touches only within the margin: bound by the cell's own centre
  return g;
}

/// Bounding planes: greedy angular cover of the face normals (largest faces first), both
/// orientations of each representative, offset to the support of the clipped geometry; those
/// that cut the cell, deepest cut first, at most max_planes.
std::vector<Plane> leaf_planes(const BuildContext& ctx, const Vec3d& lo, const Vec3d& hi, LeafGeometry& g) {
  std::sort(g.cands.begin(), g.cands.end(), [](const Cand& x, const Cand& y) {
    return x.area > y.area || (x.area == y.area && x.t < y.t);
  });
  std::vector<Vec3d> reps;
  for (const Cand& cd : g.cands) {
    if (int(reps.size()) * 2 >= ctx.max_planes) break;
    bool covered = false;
    for (const Vec3d& r : reps)
      if (std::fabs(dot(r, cd.n)) >= ctx.cos_cluster) { covered = true; break; }
    if (!covered) reps.push_back(cd.n);
  }
  struct Scored { Plane p; double cut; };
  std::vector<Scored> sc;
  for (const Vec3d& r : reps)
    for (double sgn : {1.0, -1.0}) {
      Plane p;
      make_plane(ctx, r * sgn, g.geo, &p);
      Vec3d nw; double d;
      plane_world(ctx, p, &nw, &d);
      const double cut = box_support(lo, hi, nw) - d;
      if (cut > 1e-4 * ctx.cs) sc.push_back({p, cut});
    }
  std::stable_sort(sc.begin(), sc.end(), [](const Scored& x, const Scored& y) { return x.cut > y.cut; });
  if (int(sc.size()) > ctx.max_planes) sc.resize(std::size_t(ctx.max_planes));
  std::vector<Plane> planes;
  for (const Scored& x : sc) planes.push_back(x.p);
  return planes;
}

/// The leaf's temporary: its planes and the bounding volume cell box ∩ planes.
void bound_leaf(const BuildContext& ctx, const Vec3d& lo, const Vec3d& hi, std::vector<Plane> planes, NodeTmp* tm) {
  tm->planes = std::move(planes);
  Polytope poly = Polytope::box(lo, hi);
  for (const Plane& p : tm->planes) {
    Vec3d nw; double d;
    plane_world(ctx, p, &nw, &d);
    poly.clip(nw, d);
  }
  tm->poly = poly.vertices();
  if (tm->poly.empty()) {  // numerically flat: fall back to the box corners (conservative)
    tm->poly = Polytope::box(lo, hi).vertices();
  }
  tm->volume = poly.volume();
  tm->box_volume = ctx.cs * ctx.cs * ctx.cs;
}

/// The distinct vertices of the block's non-degenerate triangles (a small hash set on the float
/// bits; the classification does not depend on their order, only on which exist).
std::vector<Vec3d> distinct_vertices(const LeafTri* blk, std::uint32_t n) {
  std::vector<Vec3d> verts;
  verts.reserve(3 * std::size_t(n));
  std::size_t cap = 16;
  while (cap < 6 * std::size_t(n)) cap <<= 1;
  struct Key { std::uint32_t x, y, z, used; };
  std::vector<Key> set(cap, Key{0, 0, 0, 0});
  for (std::uint32_t k = 0; k < n; ++k) {
    if (blk[k].flags() & kDegenerate) continue;
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
  return verts;
}

/// The configuration, on the exact face planes and the triangles' vertices: convex (every vertex
/// on the inner side of every face), concave (on the outer side), special otherwise.
LeafConfig classify_leaf(const LeafTri* blk, std::uint32_t n) {
  const std::vector<Vec3d> verts = distinct_vertices(blk, n);
  bool convex = !verts.empty(), concave = !verts.empty();
  for (std::uint32_t k = 0; k < n && (convex || concave); ++k) {
    if (blk[k].flags() & kDegenerate) continue;
    const Vec3d a = to_d(blk[k].a), b = to_d(blk[k].b), c = to_d(blk[k].c);
    for (const Vec3d& v : verts) {
      const int o = orient3d(a, b, c, v);
      if (o > 0) convex = false;
      if (o < 0) concave = false;
      if (!convex && !concave) break;
    }
  }
  return convex ? LeafConfig::convex : concave ? LeafConfig::concave : LeafConfig::special;
}

/// Reference point: strictly inside the cell, off every face plane; for convex (concave)
/// leaves, preferably on the inner (outer) side of all of them, so that the common query needs
/// no edge test. Sets lf's ref, ref_valid and the block's kRefPositive flags.
void choose_reference(const Vec3d& lo, const Vec3d& hi, const Vec3d& cc, double cs, LeafConfig config, Leaf& lf,
                      LeafTri* out) {
  const LeafTri* blk = out;
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
      if (blk[k].flags() & kDegenerate) { sides[k] = 0; continue; }
      const int o = orient3d(to_d(blk[k].a), to_d(blk[k].b), to_d(blk[k].c), r);
      if (o == 0) { ok = false; break; }
      sides[k] = o > 0;
      (o > 0 ? outer : inner)++;
    }
    if (!ok) continue;
    const int score = config == LeafConfig::convex ? inner : config == LeafConfig::concave ? outer : 0;
    if (score > best_score) {
      best_score = score;
      best_ref = r;
      best_sides = sides;
      if (config == LeafConfig::special || score == int(lf.tri_count)) break;
    }
  }
  lf.ref_valid = best_score >= 0;
  lf.ref[0] = float(best_ref.x); lf.ref[1] = float(best_ref.y); lf.ref[2] = float(best_ref.z);
  lf.ref_winding = 0;
  if (lf.ref_valid)
    for (std::uint32_t k = 0; k < lf.tri_count; ++k)
      if (best_sides[k]) out[k].tri_flags |= kRefPositive;
}

/// The winding-number change from the reference point `ra` to the portal `q`, over the block
/// out[0, n); false if the segment passes through an edge or a vertex.
/// This is segment_winding(ref, portal) with the reference's exact sides already known (every
/// non-degenerate plane, nonzero) and the portal's side filtered by the leaf's float planes
/// (|s| > eps decides, as in the queries; otherwise orient3d): the same result, cheaper.
bool half_edge(const Leaf& lf, const LeafTri* out, std::size_t n, const Vec3d& ra, const Vec3d& q, int* winding) {
  const float ql[3] = {float(q.x - double(lf.centre[0])), float(q.y - double(lf.centre[1])),
                       float(q.z - double(lf.centre[2]))};
  const float eps = lf.eps;
  int w = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const LeafTri& t = out[k];
    if (t.flags() & kDegenerate) continue;
    const int sp = (t.flags() & kRefPositive) ? 1 : -1;
    const float s = face_plane_value(t, ql);
    int sq;
    if (s > eps) sq = 1;
    else if (s < -eps) sq = -1;
    else sq = orient3d(to_d(t.a), to_d(t.b), to_d(t.c), q);
    if (sq == sp) continue;
    const Vec3d a = to_d(t.a), b = to_d(t.b), c = to_d(t.c);
    const Cross r = sq != 0 ? segment_triangle(ra, q, sp, sq, a, b, c) : segment_triangle(q, ra, sq, sp, a, b, c);
    if (r == Cross::degenerate || r == Cross::on_p) return false;
    if (r == Cross::proper) w += sp;
  }
  *winding = w;
  return true;
}

/// Colouring half-edges: reference point -> portal of each face, over this leaf's triangles
/// only (the segment lies in the closed cell, and every triangle meeting the closed cell is in
/// the block: the distribution is conservative).
void colouring_halves(const BuildContext& ctx, Octcode code, const Leaf& lf, const LeafTri* out, std::size_t n,
                      LeafHalves* halves) {
  for (int dir = 0; dir < 6; ++dir) halves->h[dir] = kDegenerateHalf;
  if (!lf.ref_valid) return;
  std::uint32_t x, y, z;
  octcode_cell(code, &x, &y, &z);
  const Vec3d ra = to_d(lf.ref);
  for (int dir = 0; dir < 6; ++dir) {
    int w = 0;
    if (half_edge(lf, out, n, ra, face_portal(ctx.f, x, y, z, dir), &w)) halves->h[dir] = w;
  }
}

}  // namespace

void build_leaf(const BuildContext& ctx, Octcode code, std::size_t n, const std::uint32_t* tri, const float* xyz,
                Node* nd, Leaf* lf, LeafTri* out, NodeTmp* tmp, LeafHalves* halves) {
  nd->code = code;
  nd->kind = NodeKind::leaf;
  nd->plane_begin = 0;
  nd->plane_count = 0;
  Vec3d lo, hi;
  ctx.f.cell_box(code, &lo, &hi);
  const Vec3d cc = (lo + hi) * 0.5;
  const Vec3d cfd = round_to_float(cc);
  lf->centre[0] = float(cfd.x); lf->centre[1] = float(cfd.y); lf->centre[2] = float(cfd.z);
  lf->tri_count = std::uint32_t(n);
  lf->pad = 0;

  LeafGeometry g = fill_triangle_block(lo, hi, cc, cfd, ctx.cs, n, tri, xyz, out);
  // The LeafTri block out[0, n) is complete: put it in spatial order (leaf_blocks.hpp; the
  // distance query bounds groups of consecutive triangles). Both builds pass here.
  order_leaf_triangles(out, std::uint32_t(n));
  lf->eps = round_up(leaf_plane_eps(g.radius, g.normal_error));
  bound_leaf(ctx, lo, hi, leaf_planes(ctx, lo, hi, g), tmp);
  nd->plane_count = std::uint16_t(tmp->planes.size());
  nd->config = classify_leaf(out, lf->tri_count);
  choose_reference(lo, hi, cc, ctx.cs, nd->config, *lf, out);
  colouring_halves(ctx, code, *lf, out, n, halves);
}

}  // namespace ebp::detail
