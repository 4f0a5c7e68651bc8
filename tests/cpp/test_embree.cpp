// embree against brute_force on every mesh in ../shared/meshes and a procedural sphere, for
// each build quality, robust mode, vote and coherence variant, plus the degenerate cases (one triangle, a point on a vertex, a
// point far outside, duplicate and zero-area triangles, an all-degenerate mesh).
//
// The method keeps float32 geometry (the contract), so the reference is brute_force built on the
// same float32-rounded mesh: both then answer for the same surface, and
//  - |distance| agrees within 1e-5 of the box diagonal (in practice ~1e-15);
//  - the closest triangle is the same, or a tie: brute force's distance to it is the minimum
//    within 1e-9 of the diagonal (a shared vertex or edge);
//  - inside (and the distance's sign) is identical on the closed meshes for points farther than
//    1e-6 of the diagonal from the surface. On open meshes parity and the winding number
//    disagree by design: we only require an answer.
// Coherent variants are replayed along an ordered path and must give the same answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>

#include "mesh.hpp"
#include "registry.hpp"

using namespace bvhbench;

namespace {

#define SKIP_WITHOUT_EMBREE() \
  if (!Registry::global().find("embree")) GTEST_SKIP() << "embree method not built"

/// x rounded to float32. Through a volatile: GCC 12.2's SLP vectorizer at -O2/-O3 folds the
/// pairwise round trip `Vec3d(Vec3f(v))` in a loop to a no-op for x and y (wrong code).
double through_float(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

/// The mesh as the methods hold it: coordinates rounded to float32.
Mesh float_rounded(const Mesh& m) {
  Mesh r = m;
  for (auto& v : r.vertices) v = Vec3d(through_float(v.x), through_float(v.y), through_float(v.z));
  return r;
}

std::unique_ptr<Method> make(const std::string& spec, const Mesh& mesh,
                             QueryType q = QueryType::distance) {
  auto m = Registry::global().create(spec);
  BuildContext ctx;
  ctx.query_type = q;
  m->build(mesh, ctx);
  return m;
}

/// Icosphere of radius r: 20 * 4^level triangles, outward.
Mesh sphere(int level, double r = 1.0) {
  Mesh m;
  const double t = (1 + std::sqrt(5.0)) / 2;
  m.vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.vertices.push_back((m.vertices[a] + m.vertices[b]) * 0.5);
      return mid[key] = std::uint32_t(m.vertices.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (auto f : m.triangles) {
      std::uint32_t ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
  for (auto& v : m.vertices) v = normalized(v) * r;
  return m;
}

Mesh unit_cube() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                 {2, 3, 7}, {2, 7, 6}, {1, 2, 6}, {1, 6, 5}, {0, 4, 7}, {0, 7, 3}};
  return m;
}

/// Random points in the box enlarged by 10%, and points near the surface (a random point of a
/// random triangle moved along its normal by up to 2% of the diagonal).
std::vector<Vec3d> sample_queries(const Mesh& m, int n_random, int n_near, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0, 1);
  const Box3d b = m.bounds();
  const Vec3d lo = b.lo - b.extent() * 0.1, ext = b.extent() * 1.2;
  const double diag = b.diagonal();
  std::vector<Vec3d> q;
  for (int i = 0; i < n_random; ++i) q.push_back(lo + Vec3d(u01(rng) * ext.x, u01(rng) * ext.y, u01(rng) * ext.z));
  std::uniform_int_distribution<std::size_t> tri(0, m.triangles.size() - 1);
  for (int i = 0; i < n_near; ++i) {
    const auto& t = m.triangles[tri(rng)];
    double s = u01(rng), r = u01(rng);
    if (s + r > 1) s = 1 - s, r = 1 - r;
    const Vec3d a = m.vertices[t[0]], bb = m.vertices[t[1]], c = m.vertices[t[2]];
    const Vec3d on = a + (bb - a) * s + (c - a) * r;
    q.push_back(on + triangle_normal(a, bb, c) * ((u01(rng) * 2 - 1) * 0.02 * diag));
  }
  return q;
}

/// A haptic-like ordered path: small steps of a random walk around the surface.
std::vector<Vec3d> sample_path(const Mesh& m, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  const double diag = m.bounds().diagonal();
  std::vector<Vec3d> q;
  Vec3d p = m.vertices[m.triangles[0][0]] + Vec3d(0.01, 0.01, 0.01) * diag;
  for (int i = 0; i < n; ++i) {
    p += Vec3d(g(rng), g(rng), g(rng)) * (0.004 * diag);
    q.push_back(p);
  }
  return q;
}

double distance_to_triangle(const Mesh& m, std::int64_t t, const Vec3d& p) {
  const auto& f = m.triangles[std::size_t(t)];
  return norm(closest_point_on_triangle(p, m.vertices[f[0]], m.vertices[f[1]], m.vertices[f[2]]) - p);
}

/// Checks `spec` against brute force (on the float-rounded mesh) for the given queries.
void check_against_brute_force(const std::string& spec, const Mesh& input, bool closed,
                               const std::vector<Vec3d>& queries) {
  const Mesh ref_mesh = float_rounded(input);
  const double diag = ref_mesh.bounds().diagonal();
  auto ref = make("brute_force", ref_mesh);
  auto dist = make(spec, input, QueryType::distance);
  auto ins = make(spec, input, QueryType::inside);
  dist->reset_path();
  ins->reset_path();
  int triangle_mismatch = 0, inside_mismatch = 0;
  for (const Vec3d& p : queries) {
    const DistanceResult want = ref->distance(p);
    const DistanceResult got = dist->distance(p);
    SCOPED_TRACE(spec + " at (" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " +
                 std::to_string(p.z) + ")");
    ASSERT_GE(got.triangle, 0);
    ASSERT_LT(std::size_t(got.triangle), input.triangles.size());
    EXPECT_NEAR(std::abs(got.distance), std::abs(want.distance), 1e-5 * diag);
    EXPECT_NEAR(norm(got.closest - p), std::abs(got.distance), 1e-9 * diag);
    const double to_got = distance_to_triangle(ref_mesh, got.triangle, p);
    if (got.triangle != want.triangle && std::abs(to_got - std::abs(want.distance)) > 1e-9 * diag)
      ++triangle_mismatch;
    const auto& f = ref_mesh.triangles[std::size_t(got.triangle)];
    const Vec3d n = triangle_normal(ref_mesh.vertices[f[0]], ref_mesh.vertices[f[1]], ref_mesh.vertices[f[2]]);
    EXPECT_NEAR(norm(got.normal - n), 0.0, 1e-6);
    const bool in = ins->inside(p);
    if (closed && std::abs(want.distance) > 1e-6 * diag) {
      const bool want_in = want.distance < 0;
      if (in != want_in) ++inside_mismatch;
      EXPECT_EQ(got.distance < 0, want_in);
    }
  }
  EXPECT_EQ(triangle_mismatch, 0) << spec;
  EXPECT_EQ(inside_mismatch, 0) << spec;
}

/// The coherent variant replays an ordered path with the same answers as the plain one.
void check_coherent(const std::string& plain, const std::string& coherent, const Mesh& mesh,
                    const std::vector<Vec3d>& path) {
  const Mesh ref_mesh = float_rounded(mesh);
  const double diag = ref_mesh.bounds().diagonal();
  auto a = make(plain, mesh), b = make(coherent, mesh);
  for (int pass = 0; pass < 2; ++pass) {  // a second pass after reset_path() must not differ
    a->reset_path();
    b->reset_path();
    for (const Vec3d& p : path) {
      const DistanceResult x = a->distance(p), y = b->distance(p);
      EXPECT_NEAR(x.distance, y.distance, 1e-12 * diag);
      if (x.triangle != y.triangle) {
        EXPECT_NEAR(distance_to_triangle(ref_mesh, y.triangle, p), std::abs(x.distance), 1e-9 * diag);
      }
    }
  }
}

const char* const kVariants[] = {"embree", "embree:quality=low", "embree:quality=high",
                                 "embree:robust=false", "embree:rays=3", "embree:rays=5",
                                 "embree:coherent=true", "embree:quality=high,robust=false,coherent=true,rays=3"};

struct SharedMesh {
  const char* file;
  bool closed;
  int n_random, n_near;
};

class EmbreeSharedMesh : public ::testing::TestWithParam<SharedMesh> {};

}  // namespace

TEST(Embree, ListedWithParameters) {
  SKIP_WITHOUT_EMBREE();
  const MethodInfo* info = Registry::global().find("embree");
  EXPECT_TRUE(info->caps.inside && info->caps.distance && info->caps.closest_triangle && info->caps.coherence);
  std::vector<std::string> names;
  for (const auto& p : info->params) names.push_back(p.name);
  for (const char* want : {"quality", "robust", "rays", "coherent", "threads"})
    EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
}

TEST(Embree, SphereAgainstBruteForce) {
  SKIP_WITHOUT_EMBREE();
  const Mesh s = sphere(3);
  const auto q = sample_queries(s, 150, 150, 7);
  for (const char* v : kVariants) check_against_brute_force(v, s, true, q);
}

TEST_P(EmbreeSharedMesh, AgainstBruteForce) {
  SKIP_WITHOUT_EMBREE();
  const SharedMesh& sm = GetParam();
  const Mesh mesh = load_mesh(std::string(BVHBENCH_SHARED_DIR) + "/meshes/" + sm.file);
  const auto q = sample_queries(mesh, sm.n_random, sm.n_near, 11);
  check_against_brute_force("embree", mesh, sm.closed, q);
  check_against_brute_force("embree:quality=high,rays=3", mesh, sm.closed, q);
}

TEST_P(EmbreeSharedMesh, CoherentPathSameAnswers) {
  SKIP_WITHOUT_EMBREE();
  const Mesh mesh = load_mesh(std::string(BVHBENCH_SHARED_DIR) + "/meshes/" + GetParam().file);
  const auto path = sample_path(mesh, 300, 3);
  check_coherent("embree", "embree:coherent=true", mesh, path);
  check_coherent("embree:quality=high", "embree:coherent=true,quality=high", mesh, path);
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, EmbreeSharedMesh,
                         ::testing::Values(SharedMesh{"cow.obj", true, 150, 150},
                                           SharedMesh{"fandisk.obj", true, 150, 150},
                                           SharedMesh{"homer.obj", true, 150, 150},
                                           SharedMesh{"rocker-arm.obj", true, 150, 150},
                                           SharedMesh{"spot.obj", false, 150, 150},
                                           SharedMesh{"stanford-bunny.obj", false, 60, 60}),
                         [](const auto& info) {
                           std::string n = info.param.file;
                           n = n.substr(0, n.find('.'));
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

TEST(Embree, OneTriangleQueryOnVertexAndFarAway) {
  SKIP_WITHOUT_EMBREE();
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  for (const char* v : kVariants) {
    auto d = make(v, m), in = make(v, m, QueryType::inside);
    for (Vec3d p : {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0.5, 0.5, 0}, Vec3d{0.2, 0.2, 0}}) {
      DistanceResult r = d->distance(p);
      EXPECT_NEAR(r.distance, 0.0, 1e-15) << v;
      EXPECT_NEAR(norm(r.closest - p), 0.0, 1e-15) << v;
      EXPECT_EQ(r.triangle, 0);
      (void)in->inside(p);  // on the surface: any answer, but an answer
    }
    DistanceResult r = d->distance({0.25, 0.25, 3});
    EXPECT_NEAR(r.distance, 3.0, 1e-12) << v;
    EXPECT_NEAR(r.normal.z, 1.0, 1e-12) << v;
    r = d->distance({-1e6, -1e6, 1e6});
    EXPECT_NEAR(r.distance, std::sqrt(3.0) * 1e6, 1e-6) << v;
    EXPECT_EQ(r.closest, Vec3d(0, 0, 0)) << v;
    EXPECT_FALSE(in->inside({0.25, 0.25, 0.5})) << v;
    EXPECT_FALSE(in->inside({-1e6, -1e6, 1e6})) << v;
  }
}

TEST(Embree, QueryOnAVertexOfAClosedMesh) {
  SKIP_WITHOUT_EMBREE();
  for (const char* v : kVariants) {
    auto d = make(v, unit_cube()), in = make(v, unit_cube(), QueryType::inside);
    for (Vec3d p : {Vec3d{1, 1, 1}, Vec3d{0, 0, 0}, Vec3d{0.5, 0, 0}, Vec3d{0.5, 0.5, 0}}) {
      DistanceResult r = d->distance(p);
      EXPECT_EQ(r.distance, 0.0) << v;
      EXPECT_EQ(r.closest, p) << v;
      (void)in->inside(p);  // must terminate
    }
    EXPECT_TRUE(in->inside({0.5, 0.5, 0.5})) << v;
    EXPECT_TRUE(in->inside({0.999, 0.001, 0.5})) << v;
    EXPECT_FALSE(in->inside({1e6, 1e6, 1e6})) << v;
    DistanceResult r = d->distance({0.5, 0.5, 0.2});
    EXPECT_NEAR(r.distance, -0.2, 1e-7) << v;
    r = d->distance({1e6, 1e6, 1e6});
    EXPECT_NEAR(r.distance, std::sqrt(3.0) * (1e6 - 1), 1e-6) << v;
    EXPECT_EQ(r.closest, Vec3d(1, 1, 1)) << v;
  }
}

TEST(Embree, DuplicateAndZeroAreaTriangles) {
  SKIP_WITHOUT_EMBREE();
  Mesh m = unit_cube();
  // zero-area: a sliver along an edge, a collapsed triangle, a triangle with a repeated index
  m.vertices.push_back({0.5, 0, 0});
  m.triangles.push_back({0, 1, 8});
  m.triangles.push_back({3, 3, 3});
  m.triangles.push_back({6, 6, 2});
  Mesh with_duplicates = m;
  with_duplicates.triangles.push_back(m.triangles[2]);  // a duplicate of the top face's half
  for (const char* v : kVariants) {
    // Degenerate triangles alone do not change parity: inside stays right.
    auto in = make(v, m, QueryType::inside);
    EXPECT_TRUE(in->inside({0.5, 0.5, 0.5})) << v;
    EXPECT_TRUE(in->inside({0.25, 0.1, 0.3})) << v;
    EXPECT_FALSE(in->inside({0.5, 0.5, 1.5})) << v;
    const auto q = sample_queries(unit_cube(), 40, 40, 5);
    check_against_brute_force(v, with_duplicates, false, q);
  }
}

TEST(Embree, AllDegenerateMeshDoesNotCrash) {
  SKIP_WITHOUT_EMBREE();
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {3, 3, 3}, {0, 0, 1}};
  for (const char* v : kVariants) {
    auto d = make(v, m), in = make(v, m, QueryType::inside);
    DistanceResult r = d->distance({1.5, 1, 0});
    EXPECT_NEAR(r.distance, 1.0, 1e-12) << v;
    EXPECT_FALSE(in->inside({1, 0.5, 0})) << v;
    EXPECT_FALSE(in->inside({1, 0, 0})) << v;
  }
}

TEST(Embree, CountersAndBytes) {
  SKIP_WITHOUT_EMBREE();
  const Mesh s = sphere(3);
  auto d = make("embree", s);
  EXPECT_GT(d->structure_bytes(), s.triangles.size() * 12 + s.vertices.size() * 12);  // + the BVH
  d->reset_counters();
  for (const Vec3d& p : sample_queries(s, 20, 0, 1)) (void)d->distance(p);
  std::map<std::string, std::uint64_t> c;
  for (const auto& x : d->counters()) c[x.name] = x.value;
  EXPECT_GT(c["triangles_tested"], 0u);
  EXPECT_EQ(c["point_queries"], 20u);
  EXPECT_LT(c["triangles_tested"], 20u * s.triangles.size());  // the tree prunes
  // Deterministic: the same pass counts the same work.
  const auto first = d->counters();
  d->reset_counters();
  for (const Vec3d& p : sample_queries(s, 20, 0, 1)) (void)d->distance(p);
  const auto second = d->counters();
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i].value, second[i].value) << first[i].name;
}

TEST(Embree, VotesShootOneRayEachAtLeast) {
  SKIP_WITHOUT_EMBREE();
  const Mesh s = sphere(2);
  for (int rays : {1, 3, 5}) {
    auto in = make("embree:rays=" + std::to_string(rays), s, QueryType::inside);
    in->reset_counters();
    EXPECT_TRUE(in->inside({0.1, 0.2, 0.3}));
    EXPECT_FALSE(in->inside({0.9, 0.9, 0.9}));  // in the box, outside the sphere: rays needed
    std::map<std::string, std::uint64_t> c;
    for (const auto& x : in->counters()) c[x.name] = x.value;
    EXPECT_GE(c["rays_shot"], 2u * unsigned(rays));
    EXPECT_EQ(c["undecided"], 0u);
  }
}
