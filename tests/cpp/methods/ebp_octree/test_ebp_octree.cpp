// Tests of the EBP-Octree (methods/ebp_octree): octcodes, the triangle/box kernel, the
// distribution of triangles to leaves, containment by the bounding planes, exact point-in-solid
// and distance against a brute-force reference, coherence, open and degenerate inputs, and
// deterministic counters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "ebp_octree.hpp"
#include "harness/core/mesh.hpp"
#include "harness/io/mesh_io.hpp"
#include "leaf_blocks.hpp"
#include "octcode.hpp"
#include "predicates.hpp"
#include "tri_box.hpp"
#ifndef EBP_NO_REGISTRY
#include "harness/core/registry.hpp"
#endif

using namespace ebp;
using bvhbench::Mesh;
using Tris = std::vector<std::array<std::uint32_t, 3>>;

namespace {

std::string shared_mesh(const std::string& name) { return std::string(BVHBENCH_SHARED_DIR) + "/meshes/" + name; }

/// The brute-force reference, the same formulas as methods/brute_force (on the float-rounded
/// geometry the octree uses, so that answers are comparable to the last bit of the predicates).
struct Reference {
  std::vector<Vec3d> v;
  Tris f;
  Reference(const std::vector<Vec3d>& vin, const Tris& fin) : f(fin) {
    for (auto& p : vin) v.push_back(round_to_float(p));
  }
  double winding(const Vec3d& p) const {
    double w = 0;
    for (auto& t : f) w += bvhbench::triangle_winding(p, v[t[0]], v[t[1]], v[t[2]]);
    return w;
  }
  double dist(const Vec3d& p, std::int64_t* tri = nullptr) const {
    double best = 1e300;
    std::int64_t bi = -1;
    for (std::size_t i = 0; i < f.size(); ++i) {
      const Vec3d q = bvhbench::closest_point_on_triangle(p, v[f[i][0]], v[f[i][1]], v[f[i][2]]);
      const double d2 = squared_norm(q - p);
      if (d2 < best) { best = d2; bi = std::int64_t(i); }
    }
    if (tri) *tri = bi;
    return std::sqrt(best);
  }
  double tri_dist(const Vec3d& p, std::int64_t i) const {
    return norm(bvhbench::closest_point_on_triangle(p, v[f[i][0]], v[f[i][1]], v[f[i][2]]) - p);
  }
  Box3d bounds() const {
    Box3d b;
    for (auto& p : v) b.add(p);
    return b;
  }
};

Mesh icosphere(int subdiv, double r = 1.0, Vec3d c = {0.1, -0.2, 0.3}) {
  Mesh m;
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  Tris f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
            {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
            {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (auto& p : v) p = bvhbench::normalized(p);
  for (int s = 0; s < subdiv; ++s) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(bvhbench::normalized((v[a] + v[b]) * 0.5));
      return mid[key] = std::uint32_t(v.size() - 1);
    };
    Tris g;
    for (auto& tr : f) {
      const std::uint32_t a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]), c = midpoint(tr[2], tr[0]);
      g.push_back({tr[0], a, c});
      g.push_back({tr[1], b, a});
      g.push_back({tr[2], c, b});
      g.push_back({a, b, c});
    }
    f = g;
  }
  for (auto& p : v) m.vertices.push_back(p * r + c);
  m.triangles = f;
  return m;
}

Mesh torus(int nu, int nv, double R = 1.0, double r = 0.35) {
  Mesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, w = 2 * M_PI * j / nv;
      m.vertices.push_back({(R + r * std::cos(w)) * std::cos(u), (R + r * std::cos(w)) * std::sin(u), r * std::sin(w)});
    }
  auto id = [&](int i, int j) { return std::uint32_t(((i + nu) % nu) * nv + ((j + nv) % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

/// Query points: uniform in the box grown by 10 %, and near the surface (on random triangles,
/// pushed along the normal by up to 2 % of the diagonal either way).
std::vector<Vec3d> sample_points(const Reference& ref, int n_uniform, int n_near, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  const Box3d b = ref.bounds();
  const Vec3d e = b.extent();
  const double diag = b.diagonal();
  std::vector<Vec3d> pts;
  for (int i = 0; i < n_uniform; ++i)
    pts.push_back({b.lo.x - 0.1 * e.x + 1.2 * e.x * U(rng), b.lo.y - 0.1 * e.y + 1.2 * e.y * U(rng),
                   b.lo.z - 0.1 * e.z + 1.2 * e.z * U(rng)});
  std::uniform_int_distribution<std::size_t> T(0, ref.f.size() - 1);
  for (int i = 0; i < n_near; ++i) {
    const auto& t = ref.f[T(rng)];
    double u = U(rng), v = U(rng);
    if (u + v > 1) { u = 1 - u; v = 1 - v; }
    const Vec3d a = ref.v[t[0]], bb = ref.v[t[1]], c = ref.v[t[2]];
    const Vec3d p = a + (bb - a) * u + (c - a) * v;
    const Vec3d n = bvhbench::triangle_normal(a, bb, c);
    pts.push_back(p + n * ((U(rng) * 2 - 1) * 0.02 * diag));
  }
  return pts;
}

/// Exact-box clipping (no growth): the polygon triangle ∩ [lo - grow, hi + grow].
std::vector<Vec3d> clip_exact(const Vec3d& lo, const Vec3d& hi, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                              double grow = 0.0) {
  std::vector<Vec3d> poly = {a, b, c};
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const double bound = side == 0 ? lo[axis] - grow : hi[axis] + grow;
      std::vector<Vec3d> out;
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Vec3d P = poly[i], Q = poly[(i + 1) % poly.size()];
        auto in = [&](const Vec3d& X) { return side == 0 ? X[axis] >= bound : X[axis] <= bound; };
        if (in(P)) out.push_back(P);
        if (in(P) != in(Q)) {
          Vec3d X = P + (Q - P) * ((bound - P[axis]) / (Q[axis] - P[axis]));
          X[axis] = bound;
          out.push_back(X);
        }
      }
      poly = out;
      if (poly.empty()) return poly;
    }
  return poly;
}

Octree build(const Mesh& m, BuildParams bp = {}) { return Octree::build(m.vertices, m.triangles, bp); }

}  // namespace

// ---------------------------------------------------------------------------------------------
TEST(EbpOctcode, RoundTripsAndOrder) {
  std::mt19937 rng(7);
  for (int l = 0; l <= kMaxLevel; ++l) {
    for (int k = 0; k < 200; ++k) {
      const std::uint32_t mask = l == 0 ? 0 : (1u << l) - 1;
      const std::uint32_t x = rng() & mask, y = rng() & mask, z = rng() & mask;
      const Octcode c = octcode_from_cell(l, x, y, z);
      std::uint32_t a, b, d;
      octcode_cell(c, &a, &b, &d);
      EXPECT_EQ(a, x); EXPECT_EQ(b, y); EXPECT_EQ(d, z);
      EXPECT_EQ(octcode_level(c), l);
      if (l > 0) {
        const Octcode p = octcode_parent(c);
        EXPECT_EQ(octcode_level(p), l - 1);
        EXPECT_EQ(octcode_child(p, octcode_octant(c)), c);
        EXPECT_LT(p, c);  // pre-order: the parent first
        EXPECT_TRUE(octcode_contains(p, c));
        EXPECT_LT(c, octcode_subtree_end(p));
      }
      if (l < kMaxLevel)
        for (int o = 0; o < 8; ++o) {
          const Octcode ch = octcode_child(c, o);
          EXPECT_GT(ch, c);
          EXPECT_LT(ch, octcode_subtree_end(c));
          if (o > 0) {
            EXPECT_GE(ch, octcode_subtree_end(octcode_child(c, o - 1)));
          }
        }
    }
  }
  EXPECT_EQ(octcode_level(octcode_root()), 0);
  EXPECT_EQ(morton_encode(1, 0, 0), 1u);
  EXPECT_EQ(morton_encode(0, 1, 0), 2u);
  EXPECT_EQ(morton_encode(0, 0, 1), 4u);
  const std::uint32_t big = (1u << 19) - 1;
  std::uint32_t a, b, d;
  morton_decode(morton_encode(big, 0, big), &a, &b, &d);
  EXPECT_EQ(a, big); EXPECT_EQ(b, 0u); EXPECT_EQ(d, big);
}

TEST(EbpPredicates, OrientSignConventionAndExactness) {
  const Vec3d a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  EXPECT_EQ(orient3d(a, b, c, {0, 0, 1}), 1);  // the side the right-hand normal points to
  EXPECT_EQ(orient3d(a, b, c, {0, 0, -1}), -1);
  EXPECT_EQ(orient3d(a, b, c, {0.3, 0.3, 0}), 0);
  EXPECT_EQ(orient3d_exact(a, b, c, {0, 0, 1}), 1);
  // Nearly coplanar: the filter must defer to the exact path and agree with it.
  const Vec3d p{0.1, 0.2, 1e-300};
  EXPECT_EQ(orient3d(a, b, c, p), 1);
  const Vec3d q1{0.1, 0.1, 0.1}, q2{0.7, 0.3, 0.9}, q3{0.2, 0.8, 0.4};
  const Vec3d m = (q1 + q2) * 0.5;  // rounding makes this nearly but not necessarily on the line
  EXPECT_EQ(orient3d(q1, q2, q3, m), orient3d_exact(q1, q2, q3, m));
  EXPECT_TRUE(collinear_exact({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
  EXPECT_FALSE(collinear_exact({0, 0, 0}, {1, 1, 1}, {2, 2, 2.0000001}));
}

// The overlap test against a clipping reference, on random and on touching configurations.
TEST(EbpTriBox, OverlapAgainstClippingReference) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1.5, 1.5);
  auto ref_touch = [](const Vec3d& lo, const Vec3d& hi, const Vec3d& a, const Vec3d& b, const Vec3d& c, double grow) {
    return !clip_exact(lo, hi, a, b, c, grow).empty();
  };
  const Vec3d lo{-0.5, -0.5, -0.5}, hi{0.5, 0.5, 0.5};
  int overlaps = 0;
  for (int k = 0; k < 20000; ++k) {
    Vec3d a{U(rng), U(rng), U(rng)}, b{U(rng), U(rng), U(rng)}, c{U(rng), U(rng), U(rng)};
    if (k % 4 == 1) { a.x = 0.5; }                       // a vertex on a face plane
    if (k % 4 == 2) { a = {0.5, 0.5, U(rng)}; b.x = 0.5; }  // an edge in a face plane
    if (k % 4 == 3) { a = {0.5, 0.5, 0.5}; b = b * 0.3 + Vec3d(1, 1, 1); c = c * 0.3 + Vec3d(1, 1, 1); }  // touches a corner
    const bool got = tri_box_overlap(lo, hi, a, b, c);
    if (ref_touch(lo, hi, a, b, c, 0.0)) {
      EXPECT_TRUE(got) << "missed a touching triangle, case " << k;
      ++overlaps;
    }
    if (got) {
      EXPECT_TRUE(ref_touch(lo, hi, a, b, c, 1e-6)) << "listed a triangle far from the box, case " << k;
    }
  }
  EXPECT_GT(overlaps, 1000);
  // Exactly touching, exactly separated by a hair.
  EXPECT_TRUE(tri_box_overlap(lo, hi, {0.5, 0.5, 0.5}, {1, 2, 3}, {2, 1, 3}));
  EXPECT_FALSE(tri_box_overlap(lo, hi, {0.5001, 0.5, 0.5}, {1, 2, 3}, {2, 1, 3}));
  // Degenerate triangles.
  EXPECT_TRUE(tri_box_overlap(lo, hi, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}));
  EXPECT_TRUE(tri_box_overlap(lo, hi, {-1, 0, 0}, {1, 0, 0}, {0, 0, 0}));
  EXPECT_FALSE(tri_box_overlap(lo, hi, {-1, 0.6, 0}, {1, 0.6, 0}, {0, 0.6, 0}));
}

// Every triangle is listed in exactly the leaf cells it touches (by the overlap test of every
// (triangle, cell) pair around it).
TEST(EbpBuild, DistributionIsExactOnCow) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  const int L = t.leaf_level;
  EXPECT_GE(L, 1);
  std::map<std::uint32_t, std::set<std::uint64_t>> listed;
  for (const Node& nd : t.nodes) {
    if (nd.kind != NodeKind::leaf) continue;
    EXPECT_EQ(octcode_level(nd.code), L);
    const Leaf& lf = t.leaves[nd.index];
    for (std::uint32_t k = 0; k < lf.tri_count; ++k) listed[t.tris[lf.tri_begin + k].tri].insert(octcode_morton(nd.code));
  }
  const double cs = t.cell_size(L);
  const std::uint32_t G = 1u << L;
  std::size_t pairs = 0;
  for (std::uint32_t i = 0; i < m.triangles.size(); ++i) {
    Vec3d v[3];
    Box3d b;
    for (int k = 0; k < 3; ++k) {
      const Vec3d p = m.vertices[m.triangles[i][k]];
      v[k] = round_to_float(p);
      b.add(v[k]);
    }
    std::set<std::uint64_t> expect;
    auto lo_i = [&](int a) { return std::uint32_t(std::max(0.0, std::floor((b.lo[a] - t.root_lo[a]) / cs) - 1)); };
    auto hi_i = [&](int a) { return std::min(G - 1, std::uint32_t(std::floor((b.hi[a] - t.root_lo[a]) / cs) + 1)); };
    for (std::uint32_t z = lo_i(2); z <= hi_i(2); ++z)
      for (std::uint32_t y = lo_i(1); y <= hi_i(1); ++y)
        for (std::uint32_t x = lo_i(0); x <= hi_i(0); ++x) {
          Vec3d clo, chi;
          t.cell_box(octcode_from_cell(L, x, y, z), &clo, &chi);
          if (tri_box_overlap(clo, chi, v[0], v[1], v[2])) expect.insert(morton_encode(x, y, z));
        }
    pairs += expect.size();
    ASSERT_EQ(listed[i], expect) << "triangle " << i;
  }
  EXPECT_EQ(pairs, t.tris.size());
}

// Every bounding plane of every grey node contains its geometry: every vertex of every
// triangle ∩ cell polygon is on the inner side, with tolerance 0 (in double).
TEST(EbpBuild, BoundingPlanesContainTheGeometry) {
  for (const char* name : {"cow.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    std::size_t checked = 0;
    for (std::size_t i = 0; i < t.nodes.size(); ++i) {
      const Node& nd = t.nodes[i];
      if (nd.kind != NodeKind::leaf && nd.kind != NodeKind::inner) continue;
      Vec3d lo, hi;
      t.cell_box(nd.code, &lo, &hi);
      std::vector<Vec3d> pts;
      for (std::size_t j = i; j < nd.next; ++j) {
        if (t.nodes[j].kind != NodeKind::leaf) continue;
        const Leaf& lf = t.leaves[t.nodes[j].index];
        for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
          const LeafTri& r = t.tris[lf.tri_begin + k];
          const auto poly = clip_exact(lo, hi, {r.a[0], r.a[1], r.a[2]}, {r.b[0], r.b[1], r.b[2]}, {r.c[0], r.c[1], r.c[2]});
          pts.insert(pts.end(), poly.begin(), poly.end());
        }
      }
      for (std::uint32_t k = 0; k < nd.plane_count; ++k) {
        const Plane& pl = t.planes[nd.plane_begin + k];
        const Vec3d n{pl.n[0], pl.n[1], pl.n[2]};
        for (const Vec3d& v : pts) {
          ASSERT_LE(dot(n, v - t.root_centre), double(pl.d)) << name << " node " << i << " plane " << k;
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 1000u) << name;
    EXPECT_GT(t.stats.planes, 0u);
    EXPECT_LT(t.stats.leaf_volume, t.stats.leaf_box_volume);
  }
}

// Inside identical to the winding-number reference on closed meshes, away from the surface.
TEST(EbpQuery, InsideMatchesReferenceOnClosedMeshes) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (const char* name : {"cow.obj", "fandisk.obj", "homer.obj", "rocker-arm.obj"})
    meshes.push_back({name, bvhbench::load_mesh(shared_mesh(name))});
  meshes.push_back({"icosphere", icosphere(4)});
  meshes.push_back({"torus", torus(64, 32)});
  for (auto& [name, m] : meshes) {
    for (double lf : {5.0, 2.0}) {
      BuildParams bp;
      bp.leaf_factor = lf;
      const Octree t = build(m, bp);
      EXPECT_EQ(t.stats.colour_fallbacks, 0u) << name;
      const Reference ref(m.vertices, m.triangles);
      const double diag = ref.bounds().diagonal();
      const auto pts = sample_points(ref, lf == 5.0 ? 1000 : 200, lf == 5.0 ? 1000 : 200, 1234);
      Query q(t, false);
      int checked = 0, wrong = 0;
      for (const Vec3d& p : pts) {
        if (ref.dist(p) < 1e-6 * diag) continue;
        const bool want = ref.winding(p) > 0.5;
        if (q.inside(p) != want) ++wrong;
        ++checked;
      }
      EXPECT_EQ(wrong, 0) << name << " leaf_factor " << lf << " over " << checked;
      EXPECT_GT(q.counters.hit_convex + q.counters.hit_concave + q.counters.hit_special, 100u) << name;
    }
  }
}

TEST(EbpQuery, DistanceMatchesReference) {
  for (const char* name : {"cow.obj", "rocker-arm.obj", "stanford-bunny.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    const Reference ref(m.vertices, m.triangles);
    const double diag = ref.bounds().diagonal();
    const bool closed = std::string(name) != "stanford-bunny.obj";
    const auto pts = sample_points(ref, 150, 250, 99);
    Query q(t, false);
    for (const Vec3d& p : pts) {
      std::int64_t bt;
      const double want = ref.dist(p, &bt);
      const DistanceAnswer a = q.distance(p);
      ASSERT_NEAR(std::fabs(a.distance), want, 1e-5 * diag) << name;
      // The same triangle, or one exactly as close (ties).
      EXPECT_NEAR(ref.tri_dist(p, a.triangle), want, 1e-12 * diag) << name;
      EXPECT_NEAR(norm(a.closest - p), want, 1e-9 * diag);
      const auto& tr = ref.f[std::size_t(a.triangle)];
      const Vec3d n = bvhbench::triangle_normal(ref.v[tr[0]], ref.v[tr[1]], ref.v[tr[2]]);
      EXPECT_NEAR(norm(a.normal - n), 0.0, 1e-9);
      if (closed && want > 1e-6 * diag) {
        EXPECT_EQ(a.distance < 0, ref.winding(p) > 0.5) << name;
      }
    }
  }
}

// Coherent and non-coherent variants give identical answers along an ordered path.
TEST(EbpQuery, CoherenceChangesNothing) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("homer.obj"));
  const Octree t = build(m);
  const Reference ref(m.vertices, m.triangles);
  const double diag = ref.bounds().diagonal();
  std::mt19937_64 rng(5);
  std::normal_distribution<double> N(0, 0.004 * diag);
  auto pts = sample_points(ref, 0, 1, 17);
  Vec3d p = pts[0];
  Query a(t, false), b(t, true);
  for (int i = 0; i < 3000; ++i) {
    p += Vec3d(N(rng), N(rng), N(rng));
    if (i % 500 == 0) { b.reset_path(); }
    const DistanceAnswer x = a.distance(p), y = b.distance(p);
    ASSERT_EQ(x.distance, y.distance) << i;
    ASSERT_EQ(x.triangle, y.triangle) << i;
    ASSERT_EQ(x.closest, y.closest) << i;
    ASSERT_EQ(a.inside(p), b.inside(p)) << i;
  }
  EXPECT_LT(b.counters.nodes_visited, a.counters.nodes_visited);
  EXPECT_LT(b.counters.triangles_tested, a.counters.triangles_tested);
}

// Coherent inside on closed meshes counts crossings from the previous point of the path (see
// DESIGN.md): along haptic-like paths (tiny steps hugging the surface, crossing it often) the
// answers equal the non-coherent ones, point by point, with far fewer plane tests.
TEST(EbpQuery, CoherentInsideFromPreviousPointIsExact) {
  for (const char* name : {"cow.obj", "homer.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    EXPECT_TRUE(t.closed) << name;
    const Reference ref(m.vertices, m.triangles);
    const double diag = ref.bounds().diagonal();
    const auto starts = sample_points(ref, 0, 20, 99);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> N(0, 2e-4 * diag);
    Query a(t, false), b(t, true);
    int n = 0;
    for (const Vec3d& s : starts) {
      Vec3d p = s;
      b.reset_path();
      for (int i = 0; i < 400; ++i, ++n) {
        p += Vec3d(N(rng), N(rng), N(rng));
        ASSERT_EQ(a.inside(p), b.inside(p)) << name << " " << n;
        if (i % 97 == 0) { const Vec3d q = p; ASSERT_EQ(a.inside(q), b.inside(q)); }  // repeated point
      }
    }
    EXPECT_LT(b.counters.planes_tested * 3, a.counters.planes_tested) << name;
  }
}

// Coherent inside from the previous point through a box of gathered triangles (one or several
// leaves): on paths that walk over the mesh grazing the surface, step exactly onto vertices,
// onto (nearly) edges and triangle planes, continue straight through them, cross cell
// boundaries and jump (steps from 1e-12 of the diagonal to several leaf cells), the coherent
// answers equal the non-coherent ones point by point, and the oracle's off the surface.
TEST(EbpQuery, CoherentInsideGrazingPathsAreExact) {
  for (const char* name : {"cow.obj", "homer.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    ASSERT_TRUE(t.closed) << name;
    const Reference ref(m.vertices, m.triangles);
    const double diag = ref.bounds().diagonal();
    const double cell = t.cell_size(t.leaf_level);
    std::vector<std::vector<std::size_t>> vt(ref.v.size());
    for (std::size_t i = 0; i < ref.f.size(); ++i)
      for (int k = 0; k < 3; ++k) vt[ref.f[i][k]].push_back(i);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> U(0, 1);
    Query a(t, false), b(t, true);
    int n = 0, checked = 0;
    for (int ep = 0; ep < 30; ++ep) {
      std::size_t ct = rng() % ref.f.size();
      Vec3d p = ref.v[ref.f[ct][0]], prev = p;
      b.reset_path();
      for (int i = 0; i < 200; ++i, ++n) {
        const auto& f = ref.f[ct];
        const Vec3d va = ref.v[f[0]], vb = ref.v[f[1]], vc = ref.v[f[2]];
        const Vec3d nrm = bvhbench::triangle_normal(va, vb, vc);
        double u = U(rng), v = U(rng);
        if (u + v > 1) { u = 1 - u; v = 1 - v; }
        const Vec3d on = va + (vb - va) * u + (vc - va) * v;
        const Vec3d last = p;
        switch (int(U(rng) * 9)) {
          case 0: p = ref.v[f[rng() % 3]]; break;                                  // a vertex, exactly
          case 1: p = va + (vb - va) * u; break;                                   // (nearly) on an edge
          case 2: p = on + nrm * ((U(rng) - 0.5) * 1e-9 * diag); break;            // grazing
          case 3: p = on; break;                                                   // (nearly) on the face
          case 4: p.x += (U(rng) - 0.5) * 1e-12 * diag; break;                     // tiny, axis-aligned
          case 5: p += Vec3d(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5) * (2.5 * cell); break;  // jump
          case 6: p = p + (p - prev); break;                                       // straight on, through
          default: p = on + nrm * ((U(rng) - 0.5) * 0.1 * cell); break;            // near the face
        }
        prev = last;
        if (U(rng) < 0.3) {  // move to a neighbouring triangle
          const auto& around = vt[f[rng() % 3]];
          ct = around[rng() % around.size()];
        }
        const bool x = a.inside(p), y = b.inside(p);
        ASSERT_EQ(x, y) << name << " " << n;
        if (ref.dist(p) < 1e-7 * diag) continue;  // on (or all but on) the surface: no oracle side
        ASSERT_EQ(y, ref.winding(p) > 0.5) << name << " " << n;
        ++checked;
      }
    }
    EXPECT_GT(checked, 1500) << name;
    EXPECT_LT(b.counters.planes_tested * 2, a.counters.planes_tested) << name;
  }
}

// Open meshes and stress inputs: no crash, no loop, deterministic answers.
TEST(EbpQuery, OpenAndDegenerateInputs) {
  for (const char* name : {"stanford-bunny.obj", "spot.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t1 = build(m), t2 = build(m);
    const Reference ref(m.vertices, m.triangles);
    const auto pts = sample_points(ref, 500, 500, 3);
    Query q1(t1, false), q2(t2, true);
    int agree = 0;
    for (const Vec3d& p : pts) {
      const bool i1 = q1.inside(p);
      EXPECT_EQ(i1, q2.inside(p));
      if (i1 == (ref.winding(p) > 0.5)) ++agree;
      EXPECT_EQ(q1.distance(p).triangle, q2.distance(p).triangle);
    }
    EXPECT_GT(agree, 900) << name;  // parity and winding differ only around the holes
  }
  // One triangle; duplicates; zero-area triangles; points on a vertex and far away.
  Mesh one;
  one.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.triangles = {{0, 1, 2}};
  Mesh dup = icosphere(2);
  const std::size_t nf = dup.triangles.size();
  for (std::size_t i = 0; i < nf; i += 3) dup.triangles.push_back(dup.triangles[i]);
  Mesh zero = icosphere(2);
  zero.vertices.push_back({0.1, -0.2, 1.3});
  zero.vertices.push_back({0.1, -0.2, 1.3});
  zero.triangles.push_back({0, 0, 0});
  zero.triangles.push_back({1, 2, 1});
  zero.triangles.push_back({std::uint32_t(zero.vertices.size() - 1), std::uint32_t(zero.vertices.size() - 2), 3});
  Mesh flat;  // every triangle degenerate
  flat.vertices = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  flat.triangles = {{0, 1, 2}, {0, 0, 1}};
  for (Mesh* mm : {&one, &dup, &zero, &flat}) {
    const Octree t = build(*mm);
    Query q(t, true);
    const Vec3d v0 = round_to_float(mm->vertices[0]);
    for (const Vec3d& p : {v0, Vec3d{1e6, -1e6, 3e5}, Vec3d{0.25, 0.25, 0.0}, Vec3d{0.1, -0.2, 0.3}, mm->vertices[1]}) {
      const DistanceAnswer a = q.distance(p);
      EXPECT_TRUE(std::isfinite(a.distance));
      EXPECT_GE(a.triangle, 0);
    }
    EXPECT_FALSE(q.inside({1e6, -1e6, 3e5}));
    EXPECT_EQ(q.distance(v0).distance, 0.0);
  }
  {  // the sphere with every third face duplicated: inside is still decided, deterministically
    const Octree t = build(zero);
    Query q(t, false);
    EXPECT_TRUE(q.inside({0.1, -0.2, 0.3}));
    EXPECT_FALSE(q.inside({0.1, -0.2, 3.3}));
  }
  EXPECT_THROW(Octree::build({}, {}, BuildParams{}), std::invalid_argument);
  EXPECT_THROW(Octree::build({{0, 0, 0}}, {{0, 0, 1}}, BuildParams{}), std::invalid_argument);
}

TEST(EbpBuild, ParallelBuildIsIdentical) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("fandisk.obj"));
  BuildParams bp;
  const Octree a = build(m, bp);
  bp.threads = 2;
  const Octree b = build(m, bp);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  ASSERT_EQ(a.tris.size(), b.tris.size());
  ASSERT_EQ(a.planes.size(), b.planes.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i) {
    ASSERT_EQ(a.nodes[i].code, b.nodes[i].code);
    ASSERT_EQ(a.nodes[i].kind, b.nodes[i].kind);
  }
  for (std::size_t i = 0; i < a.planes.size(); ++i) ASSERT_EQ(a.planes[i].d, b.planes[i].d);
}

// Leaf blocks (leaf_blocks.hpp): each block box holds its triangles, each node box holds its
// leaves' triangles within their cells, a leaf block is ordered by its set alone (the same
// triangles, and any permutation of them orders to the same block).
TEST(EbpLeafBlocks, BoxesContainTheirGeometryAndOrderIsAPermutation) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  ASSERT_TRUE(has_leaf_blocks(t));
  auto inside = [](const BlockBox& b, const float* v) {
    for (int a = 0; a < 3; ++a)
      if (!(b.lo[a] <= v[a] && v[a] <= b.hi[a])) return false;
    return true;
  };
  std::mt19937_64 rng(3);
  std::size_t ordered = 0;
  for (std::size_t li = 0; li < t.leaves.size(); ++li) {
    const Leaf& lf = t.leaves[li];
    ASSERT_EQ(t.leaf_block[li] + (lf.tri_count + kBlockTris - 1) / kBlockTris,
              li + 1 < t.leaves.size() ? t.leaf_block[li + 1] : std::uint32_t(t.blocks.size()));
    for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
      const LeafTri& r = t.tris[lf.tri_begin + k];
      const BlockBox& b = t.blocks[t.leaf_block[li] + k / kBlockTris];
      ASSERT_TRUE(inside(b, r.a) && inside(b, r.b) && inside(b, r.c)) << li << " " << k;
    }
    std::vector<LeafTri> blk(t.tris.begin() + lf.tri_begin, t.tris.begin() + lf.tri_begin + lf.tri_count);
    std::vector<LeafTri> sh = blk;
    std::shuffle(sh.begin(), sh.end(), rng);
    order_leaf_triangles(sh.data(), std::uint32_t(sh.size()));
    ASSERT_EQ(0, std::memcmp(sh.data(), blk.data(), blk.size() * sizeof(LeafTri))) << "leaf " << li;
    ordered += lf.tri_count > kBlockTris;
  }
  EXPECT_GT(ordered, 10u);
  // Node boxes: a leaf's holds every point of its triangles within its cell (checked on the
  // triangles' vertices inside the cell and on their boxes clipped to the cell); a parent's
  // holds its children's.
  for (std::size_t i = 0; i < t.nodes.size(); ++i) {
    const Node& nd = t.nodes[i];
    const BlockBox& b = t.node_box[i];
    if (nd.kind == NodeKind::leaf) {
      const Leaf& lf = t.leaves[nd.index];
      Vec3d lo, hi;
      t.cell_box(nd.code, &lo, &hi);
      for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
        const LeafTri& r = t.tris[lf.tri_begin + k];
        for (int a = 0; a < 3; ++a) {
          const double tlo = std::min({double(r.a[a]), double(r.b[a]), double(r.c[a])}),
                       thi = std::max({double(r.a[a]), double(r.b[a]), double(r.c[a])});
          const double clo = std::max(tlo, lo[a]), chi = std::min(thi, hi[a]);
          if (clo > chi) continue;  // listed within the margin only
          ASSERT_LE(double(b.lo[a]), clo) << i;
          ASSERT_GE(double(b.hi[a]), chi) << i;
        }
      }
    } else if (nd.kind == NodeKind::inner) {
      for (int o = 0; o < 8; ++o) {
        const std::uint32_t c = t.children[nd.index + o];
        if (t.nodes[c].kind != NodeKind::inner && t.nodes[c].kind != NodeKind::leaf) continue;
        for (int a = 0; a < 3; ++a) {
          ASSERT_LE(b.lo[a], t.node_box[c].lo[a]);
          ASSERT_GE(b.hi[a], t.node_box[c].hi[a]);
        }
      }
    }
  }
}

// The answer is the brute-force lexicographic minimum of (squared distance, triangle index),
// bit for bit, near and far from the surface, coherent or not.
TEST(EbpQuery, DistanceIsTheLexicographicMinimumBitForBit) {
  for (const char* name : {"cow.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    const Reference ref(m.vertices, m.triangles);
    auto pts = sample_points(ref, 150, 250, 7);
    const Box3d bb = ref.bounds();
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-3, 4);
    for (int i = 0; i < 100; ++i) {  // far points
      const Vec3d e = bb.extent();
      pts.push_back({bb.lo.x + u(rng) * e.x, bb.lo.y + u(rng) * e.y, bb.lo.z + u(rng) * e.z});
    }
    for (bool coherent : {false, true}) {
      Query q(t, coherent);
      for (const Vec3d& p : pts) {
        double best2 = std::numeric_limits<double>::infinity();
        std::int64_t bi = -1;
        Vec3d bq;
        for (std::size_t i = 0; i < ref.f.size(); ++i) {
          const Vec3d c = bvhbench::closest_point_on_triangle(p, ref.v[ref.f[i][0]], ref.v[ref.f[i][1]], ref.v[ref.f[i][2]]);
          const double d2 = squared_norm(c - p);
          if (d2 < best2) { best2 = d2; bi = std::int64_t(i); bq = c; }
        }
        const DistanceAnswer a = q.unsigned_distance(p);
        ASSERT_EQ(a.triangle, bi) << name;
        ASSERT_EQ(a.distance, std::sqrt(best2)) << name;
        ASSERT_EQ(a.closest, bq) << name;
      }
    }
  }
}

// distance_bound: an initial bound >= the true distance changes nothing; the true answer as the
// initial bound is kept (nothing is strictly better); a subtree search finds the best of its
// leaves' triangles.
TEST(EbpQuery, DistanceBoundEntryPoint) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  const Reference ref(m.vertices, m.triangles);
  const auto pts = sample_points(ref, 100, 150, 5);
  Query q(t, false);
  for (const Vec3d& p : pts) {
    const DistanceAnswer a = q.unsigned_distance(p);
    for (double f : {1.0, 1.0 + 1e-9, 2.0}) {
      DistanceBest b;
      b.best = a.distance * f;
      b.best2 = b.best * b.best;
      if (f == 1.0) b.best2 = squared_norm(a.closest - p);
      b.key = UINT64_MAX;  // any triangle at exactly the bound wins the tie
      q.distance_bound(p, b, DistanceStart{});
      ASSERT_NE(b.k, UINT32_MAX);
      ASSERT_EQ(std::int64_t(t.tris[b.k].tri), a.triangle);
      ASSERT_EQ(b.best, a.distance);
      ASSERT_EQ(b.closest, a.closest);
    }
    DistanceBest b;  // the answer itself: nothing is strictly better
    b.best2 = squared_norm(a.closest - p);
    b.best = std::sqrt(b.best2);
    b.key = std::uint64_t(a.triangle);
    q.distance_bound(p, b, DistanceStart{});
    EXPECT_EQ(b.k, UINT32_MAX);
    EXPECT_EQ(b.key, std::uint64_t(a.triangle));
  }
  // Subtrees: the root's grey children, each against brute force over its leaves' triangles.
  int inside_cell = 0;
  const Node& root = t.nodes[0];
  ASSERT_EQ(root.kind, NodeKind::inner);
  for (int o = 0; o < 8; ++o) {
    const std::uint32_t c = t.children[root.index + o];
    if (t.nodes[c].kind != NodeKind::inner && t.nodes[c].kind != NodeKind::leaf) continue;
    std::set<std::uint32_t> sub;
    for (std::uint32_t i = c; i < t.nodes[c].next; ++i)
      if (t.nodes[i].kind == NodeKind::leaf) {
        const Leaf& lf = t.leaves[t.nodes[i].index];
        for (std::uint32_t k = 0; k < lf.tri_count; ++k) sub.insert(t.tris[lf.tri_begin + k].tri);
      }
    for (std::size_t j = 0; j < pts.size(); j += 5) {
      const Vec3d& p = pts[j];
      double best2 = std::numeric_limits<double>::infinity();
      std::uint32_t bi = 0;
      for (std::uint32_t i : sub) {
        const auto& f = ref.f[i];
        const double d2 = squared_norm(bvhbench::closest_point_on_triangle(p, ref.v[f[0]], ref.v[f[1]], ref.v[f[2]]) - p);
        if (d2 < best2) { best2 = d2; bi = i; }
      }
      DistanceBest b;
      DistanceStart s;
      s.node = c;
      q.distance_bound(p, b, s);
      ASSERT_NE(b.k, UINT32_MAX);
      ASSERT_TRUE(sub.count(t.tris[b.k].tri));
      // The subtree stands for its triangles within its cell: at least the best listed one, and
      // exactly it when its closest point is in the cell.
      ASSERT_GE(b.best2, best2);
      const auto& f = ref.f[bi];
      const Vec3d cp = bvhbench::closest_point_on_triangle(p, ref.v[f[0]], ref.v[f[1]], ref.v[f[2]]);
      Vec3d lo, hi;
      t.cell_box(t.nodes[c].code, &lo, &hi);
      if (cp.x >= lo.x && cp.y >= lo.y && cp.z >= lo.z && cp.x <= hi.x && cp.y <= hi.y && cp.z <= hi.z) {
        ASSERT_EQ(t.tris[b.k].tri, bi);
        ASSERT_EQ(b.best2, best2);
        ++inside_cell;
      }
    }
  }
  EXPECT_GT(inside_cell, 10);
}

#ifndef EBP_NO_REGISTRY
// The method through the registry, against the brute_force method, as the harness runs them.
TEST(EbpMethod, RegistryAdapterMatchesBruteForce) {
  const bvhbench::Registry& reg = bvhbench::Registry::global();
  ASSERT_NE(reg.find("ebp_octree"), nullptr);
  Mesh m = bvhbench::load_mesh(shared_mesh("fandisk.obj"));
  auto ebp = reg.create("ebp_octree:coherent=true,leaf_factor=4");
  auto bf = reg.create("brute_force");
  bvhbench::BuildContext ctx;
  ebp->build(m, ctx);
  bf->build(m, ctx);
  const Reference ref(m.vertices, m.triangles);
  const double diag = ref.bounds().diagonal();
  m = Mesh{};  // the harness releases the mesh after build
  ebp->reset_path();
  ebp->reset_counters();
  int n = 0;
  for (const Vec3d& p : sample_points(ref, 100, 200, 8)) {
    const bvhbench::DistanceResult want = bf->distance(p);
    if (std::fabs(want.distance) < 1e-6 * diag) continue;
    EXPECT_EQ(ebp->inside(p), bf->inside(p));
    const bvhbench::DistanceResult got = ebp->distance(p);
    EXPECT_NEAR(got.distance, want.distance, 1e-5 * diag);
    EXPECT_NEAR(ref.tri_dist(p, got.triangle), std::fabs(want.distance), 1e-5 * diag);
    ++n;
  }
  EXPECT_GT(n, 250);
  EXPECT_GT(ebp->structure_bytes(), 0u);
  EXPECT_TRUE(ebp->info().contains("tightness"));
  bool has_nodes = false;
  for (auto& c : ebp->counters()) has_nodes |= c.name == "nodes_visited" && c.value > 0;
  EXPECT_TRUE(has_nodes);
}
#endif

// Work counters are deterministic: exact values on a fixture (the cow, default parameters, 200
// uniform + 200 near-surface points of seed 42; inside then distance, not coherent).
// To regenerate after an intended change: run this test, read the values it prints on failure,
// and paste them below.
TEST(EbpQuery, CountersAreDeterministic) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  const Reference ref(m.vertices, m.triangles);
  Query q(t, false);
  const auto pts = sample_points(ref, 200, 200, 42);
  for (const Vec3d& p : pts) q.inside(p);
  const QueryCounters in = q.counters;
  q.counters = {};
  for (const Vec3d& p : pts) q.distance(p);
  const QueryCounters di = q.counters;
  auto str = [](const QueryCounters& c) {
    return std::to_string(c.nodes_visited) + ", " + std::to_string(c.planes_tested) + ", " +
           std::to_string(c.triangles_tested) + ", " + std::to_string(c.hit_white) + ", " +
           std::to_string(c.hit_black) + ", " + std::to_string(c.hit_convex) + ", " +
           std::to_string(c.hit_concave) + ", " + std::to_string(c.hit_special) + ", " +
           std::to_string(c.exact_fallbacks);
  };
  EXPECT_EQ(str(in), "1419, 48350, 16764, 114, 0, 0, 0, 286, 0") << "inside counters";
  EXPECT_EQ(str(di), "3964, 149845, 20796, 114, 0, 0, 0, 286, 0") << "distance counters";
}
