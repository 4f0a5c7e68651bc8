// openvdb against brute_force on a closed shared mesh (homer; the others at the default voxel are
// the method-conformance suite's, tests/cpp/methods/test_conformance.cpp) and a procedural sphere,
// plus the degenerate cases (one triangle, a point on a vertex, a point far outside, collapsed
// and duplicate triangles, the voxel cap).
//
// Tolerances, in voxels v (the field is exact at voxel centres up to float rounding and the
// library's renormalisation near the surface):
//  - distance, trilinear: the sdf is 1-Lipschitz, so each of the 8 corner values differs from
//    sdf(p) by at most the corner's distance to p, and their convex blend by at most the half cell
//    diagonal sqrt(3)/2 v = 0.87 v. We assert |error| <= 1 v (0.87 v plus renormalisation slack)
//    for every query, and a mean error <= 0.15 v (smooth regions interpolate far better).
//  - distance, triquadratic: not a convex blend (it overshoots at kinks), so 1.5 v.
//  - inside: identical wherever |sdf| > 2 v (the trilinear stencil then has one sign).
//  - normal: the sdf gradient equals the closest face's normal only where the closest feature is
//    a face interior; there, 90% of the queries within 15 degrees.
//  - closest point: lies on the surface within 1 v (brute-force distance of the projected point)
//    for 95% of the queries (two gradient steps).
//  - closest triangle: the voxel stores the triangle closest to the voxel centre, so a triangle
//    whose distance to p is within ~1 v of the true one; we assert that for 99% of the queries,
//    and an exact agreement rate above 50% (most triangles here are bigger than a voxel).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

const MethodInfo* openvdb_info() { return Registry::global().find("openvdb"); }

#define SKIP_WITHOUT_OPENVDB() \
  if (!openvdb_info()) GTEST_SKIP() << "openvdb method not built"

BuildContext context(QueryType qt, const std::vector<Vec3d>& pts) {
  BuildContext ctx;
  ctx.query_type = qt;
  for (const auto& p : pts) ctx.query_bounds.add(p);
  ctx.query_kind = "random";
  return ctx;
}

double angle_deg(const Vec3d& a, const Vec3d& b) {
  const double c = dot(normalized(a), normalized(b));
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
}

struct Stats {
  int n = 0, inside_checked = 0, inside_wrong = 0;
  double max_err = 0, sum_err = 0;
  int normals_checked = 0, normals_ok = 0;
  int closest_ok = 0, tri_exact = 0, tri_near = 0;
};

/// Compares openvdb (spec) with brute_force on `pts`; errors are in voxels.
Stats compare(const Mesh& mesh, const std::string& spec, const std::vector<Vec3d>& pts) {
  auto bf = build_method("brute_force", mesh, QueryType::inside);  // BuildContext{}
  auto vin = Registry::global().create(spec);
  vin->build(mesh, context(QueryType::inside, pts));
  auto vd = Registry::global().create(spec);
  vd->build(mesh, context(QueryType::distance, pts));
  const double v = vd->info()["voxel_size"].get<double>();
  EXPECT_GT(v, 0);
  Stats s;
  for (const Vec3d& p : pts) {
    const DistanceResult ref = bf->distance(p);
    const DistanceResult got = vd->distance(p);
    ++s.n;
    if (std::abs(ref.distance) > 2 * v) {
      ++s.inside_checked;
      if (vin->inside(p) != (ref.distance < 0)) ++s.inside_wrong;
    }
    const double err = std::abs(got.distance - ref.distance) / v;
    s.max_err = std::max(s.max_err, err);
    s.sum_err += err;
    const auto& f = mesh.triangles[std::size_t(ref.triangle)];
    TriangleFeature feat;
    closest_point_on_triangle(p, mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]], &feat);
    if (feat == TriangleFeature::face && std::abs(ref.distance) > v) {
      ++s.normals_checked;
      if (angle_deg(got.normal, ref.normal) < 15) ++s.normals_ok;
    }
    if (std::abs(bf->distance(got.closest).distance) <= v) ++s.closest_ok;
    if (got.triangle == ref.triangle) ++s.tri_exact;
    if (got.triangle >= 0 && distance_to_triangle(mesh, got.triangle, p) <= std::abs(ref.distance) + 1.0 * v) ++s.tri_near;
  }
  return s;
}

void expect_close_to_brute_force(const Mesh& mesh, const std::string& name, const std::string& spec,
                                 double max_err_voxels, int n = 300) {
  const auto pts = random_points(mesh.bounds(), 0.1, n, 42);
  const Stats s = compare(mesh, spec, pts);
  SCOPED_TRACE(name + " " + spec);
  EXPECT_GT(s.inside_checked, n / 2);
  EXPECT_EQ(s.inside_wrong, 0);
  EXPECT_LE(s.max_err, max_err_voxels);
  EXPECT_LE(s.sum_err / s.n, 0.15);
  EXPECT_GE(s.normals_ok, 0.9 * s.normals_checked) << s.normals_ok << "/" << s.normals_checked;
  EXPECT_GE(s.closest_ok, 0.95 * s.n);
  EXPECT_GE(s.tri_near, 0.99 * s.n);
  EXPECT_GE(s.tri_exact, 0.5 * s.n);
  std::printf("%-12s %-40s max %.3f v, mean %.3f v, inside wrong %d/%d, normals %d/%d, closest %d/%d, "
              "tri exact %d near %d\n",
              name.c_str(), spec.c_str(), s.max_err, s.sum_err / s.n, s.inside_wrong, s.inside_checked,
              s.normals_ok, s.normals_checked, s.closest_ok, s.n, s.tri_exact, s.tri_near);
}

std::string coarse(const Mesh& m, const std::string& extra = "") {
  char buf[96];
  std::snprintf(buf, sizeof buf, "openvdb:voxel_abs=%.9g", m.bounds().diagonal() / 128);
  return std::string(buf) + extra;
}

}  // namespace

TEST(OpenVdb, ListedWithParameters) {
  SKIP_WITHOUT_OPENVDB();
  const MethodInfo* m = openvdb_info();
  EXPECT_TRUE(m->caps.inside);
  EXPECT_TRUE(m->caps.distance);
  for (const char* p : {"voxel", "voxel_abs", "band", "ex_band", "in_band", "order", "closest_steps", "max_voxels"})
    EXPECT_TRUE(std::any_of(m->params.begin(), m->params.end(), [&](const ParamSpec& s) { return s.name == p; })) << p;
}

TEST(OpenVdb, SphereAgainstBruteForce) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = icosphere(3);
  expect_close_to_brute_force(m, "sphere", coarse(m), 1.0);
  expect_close_to_brute_force(m, "sphere", coarse(m, ",order=2"), 1.5);
}

class OpenVdbSharedMesh : public ::testing::TestWithParam<const char*> {};

TEST_P(OpenVdbSharedMesh, AgainstBruteForce) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = load_shared_mesh(GetParam());
  expect_close_to_brute_force(m, GetParam(), coarse(m), 1.0);
}

// cow, fandisk and rocker-arm at the default voxel are the conformance suite's
// (tests/cpp/methods/test_conformance.cpp); here homer, at a voxel of 1/128 of the diagonal, with
// the rates of normals and exact closest triangles that a voxel smaller than the triangles allows.
INSTANTIATE_TEST_SUITE_P(ClosedMeshes, OpenVdbSharedMesh, ::testing::Values("homer.obj"),
                         [](const auto& info) { return mesh_stem(info.param, ""); });

TEST(OpenVdb, NarrowBandStillAnswersInsideFarFromTheSurface) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = icosphere(3);
  auto v = Registry::global().create("openvdb:voxel_abs=0.02");
  std::vector<Vec3d> pts = {{0, 0, 0}, {3, 3, 3}};
  v->build(m, context(QueryType::inside, pts));
  EXPECT_LE(v->info()["in_band_voxels"].get<double>(), 3.0);  // 1 / 0.02 = 50 voxels to the centre
  EXPECT_TRUE(v->inside({0, 0, 0}));
  EXPECT_TRUE(v->inside({0.5, -0.2, 0.1}));
  EXPECT_FALSE(v->inside({3, 3, 3}));
  EXPECT_FALSE(v->inside({0, 0, 1.2}));
}

TEST(OpenVdb, FixedBandClampsAndSaysSo) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = icosphere(3);
  auto v = Registry::global().create("openvdb:voxel_abs=0.02,band=fixed,ex_band=3,in_band=3");
  std::vector<Vec3d> pts = {{0, 0, 0}, {3, 3, 3}};
  v->build(m, context(QueryType::distance, pts));
  const auto info = v->info();
  const double ex = info["exterior_value"].get<double>();
  EXPECT_NEAR(ex, 0.06, 1e-6);
  v->reset_counters();
  DistanceResult d = v->distance({0, 0, 2});  // true distance 1, beyond the 0.06 band
  EXPECT_EQ(d.distance, ex);                  // the clamped value, not an extrapolation
  d = v->distance({0, 0, 0});                 // true distance -1
  EXPECT_NEAR(d.distance, -0.06, 1e-6);
  d = v->distance({0, 0, 1.01});              // inside the band: accurate
  EXPECT_NEAR(d.distance, 0.01, 0.02);
  EXPECT_GT(d.normal.z, 0.99);
  EXPECT_NEAR(d.closest.z, 1.0, 0.02);
  std::uint64_t clamped = 0;
  for (const auto& c : v->counters())
    if (c.name == "clamped_samples") clamped = c.value;
  EXPECT_GE(clamped, 2u);
}

TEST(OpenVdb, OneTriangleQueryOnVertexAndFarAway) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  for (QueryType qt : {QueryType::inside, QueryType::distance}) {
    auto v = Registry::global().create("openvdb:voxel_abs=0.05");
    std::vector<Vec3d> pts = {{-0.2, -0.2, -0.2}, {1.2, 1.2, 0.2}};
    ASSERT_NO_THROW(v->build(m, context(qt, pts)));
    const double ex = v->info()["exterior_value"].get<double>();
    // An open surface: the sign is meaningless, but the magnitude is a distance.
    DistanceResult d = v->distance({0, 0, 0});  // exactly on a vertex
    EXPECT_TRUE(std::isfinite(d.distance));
    EXPECT_LE(std::abs(d.distance), 0.05 * 1.0);
    if (qt == QueryType::distance) {
      EXPECT_EQ(d.triangle, 0);
    }
    d = v->distance({0.25, 0.25, 0.3});
    if (qt == QueryType::distance) {
      EXPECT_NEAR(std::abs(d.distance), 0.3, 0.05);  // the band reaches the query box
    } else {
      EXPECT_EQ(d.distance, ex);  // inside jobs keep a 3-voxel band: 0.3 is beyond it, clamped
    }
    for (Vec3d far : {Vec3d{1e6, -1e6, 1e6}, Vec3d{1e30, 0, 0}, Vec3d{-1e300, 1e300, 0}}) {
      d = v->distance(far);
      EXPECT_EQ(d.distance, ex);  // the background, the field's clamp
      EXPECT_EQ(d.closest, far);  // no gradient to follow
      EXPECT_EQ(d.normal, Vec3d());
      EXPECT_EQ(d.triangle, -1);
      EXPECT_FALSE(v->inside(far));
    }
  }
}

TEST(OpenVdb, QueryOnAVertexOfAClosedMesh) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = icosphere(3);
  auto v = Registry::global().create(coarse(m));
  const Vec3d p = m.vertices[m.triangles[7][1]];
  v->build(m, context(QueryType::distance, {p, p * 1.5, p * 0.5}));
  const double vox = v->info()["voxel_size"].get<double>();
  DistanceResult d = v->distance(p);
  EXPECT_LE(std::abs(d.distance), vox);
  EXPECT_LE(norm(d.closest - p), vox);
  EXPECT_GT(dot(d.normal, normalized(p)), 0.95);
  ASSERT_GE(d.triangle, 0);
  EXPECT_LE(distance_to_triangle(m, d.triangle, p), vox);
}

TEST(OpenVdb, DegenerateAndDuplicateTriangles) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = icosphere(2);
  const std::size_t n = m.triangles.size();
  for (std::size_t i = 0; i < n; i += 7) m.triangles.push_back(m.triangles[i]);  // duplicates
  m.triangles.push_back({0, 0, 1});  // zero area (collapsed edge)
  m.triangles.push_back({3, 3, 3});  // a point
  auto pts = random_points(m.bounds(), 0.1, 200, 7);
  auto bf = build_method("brute_force", m, QueryType::inside);  // BuildContext{}
  for (QueryType qt : {QueryType::inside, QueryType::distance}) {
    auto v = Registry::global().create("openvdb:voxel_abs=0.03");
    ASSERT_NO_THROW(v->build(m, context(qt, pts)));
    int wrong = 0;
    for (const auto& p : pts) {
      const double ref = bf->distance(p).distance;
      if (std::abs(ref) > 0.06 && v->inside(p) != (ref < 0)) ++wrong;
      if (qt == QueryType::distance) {
        EXPECT_LE(std::abs(v->distance(p).distance - ref), 0.03);
      }
    }
    EXPECT_EQ(wrong, 0);
  }
}

// Every triangle collapsed to the one point (1,1,1): the field is built (not refused) at the
// fallback voxel size 1 (no edge length, no extent to size it by), and is the distance to that
// point, sampled at voxel centres: exact up to float rounding along the axes and the diagonal
// through it; beyond the band, the clamp. A point has no inside.
TEST(OpenVdb, AllDegenerateMeshIsTheDistanceToAPoint) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m;
  m.vertices = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
  m.triangles = {{0, 1, 2}, {0, 0, 0}};
  const std::vector<Vec3d> pts = {{0, 0, 0}, {2, 2, 2}};
  for (QueryType qt : {QueryType::inside, QueryType::distance}) {
    SCOPED_TRACE(to_string(qt));
    auto v = Registry::global().create("openvdb");
    ASSERT_NO_THROW(v->build(m, context(qt, pts)));
    const auto info = v->info();
    EXPECT_EQ(info["voxel_size"].get<double>(), 1.0);
    DistanceResult d = v->distance({1.5, 1, 1});
    EXPECT_NEAR(d.distance, 0.5, 1e-6);
    EXPECT_NEAR(norm(d.normal), 1.0, 1e-6);  // a gradient, over a voxel as wide as the distance
    EXPECT_GT(d.normal.x, 0.5);                // pointing away from the point
    for (Vec3d p : pts) {
      d = v->distance(p);
      EXPECT_NEAR(d.distance, std::sqrt(3.0), 1e-6);
      EXPECT_NEAR(norm(d.closest - Vec3d(1, 1, 1)), 0.0, 1e-6);
      if (qt == QueryType::distance) {
        EXPECT_TRUE(d.triangle == 0 || d.triangle == 1) << d.triangle;  // both are the point
      } else {
        EXPECT_EQ(d.triangle, -1);  // inside jobs keep no polygon-index grid
      }
      EXPECT_FALSE(v->inside(p));
    }
    EXPECT_FALSE(v->inside({1.5, 1, 1}));
    d = v->distance({1e6, 0, 0});
    EXPECT_EQ(d.distance, info["exterior_value"].get<double>());
    EXPECT_EQ(d.triangle, -1);
    EXPECT_FALSE(v->inside({1e6, 0, 0}));
  }
}

TEST(OpenVdb, RefusesOverTheVoxelCap) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = icosphere(2);
  auto v = Registry::global().create("openvdb:voxel_abs=0.001,max_voxels=1000000,fit=false");
  std::vector<Vec3d> pts = {{-1.2, -1.2, -1.2}, {1.2, 1.2, 1.2}};
  try {
    v->build(m, context(QueryType::distance, pts));
    FAIL() << "expected a refusal";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("max_voxels"), std::string::npos) << e.what();
  }
}

TEST(OpenVdb, CoarsensToFitTheVoxelCapByDefault) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = icosphere(2);
  auto v = Registry::global().create("openvdb:voxel_abs=0.001,max_voxels=1000000");
  std::vector<Vec3d> pts = {{-1.2, -1.2, -1.2}, {1.2, 1.2, 1.2}};
  v->build(m, context(QueryType::distance, pts));
  const auto info = v->info();
  EXPECT_TRUE(info["voxel_coarsened_to_fit"].get<bool>());
  EXPECT_GT(info["voxel_size"].get<double>(), 0.001);
  EXPECT_LE(info["estimated_voxels"].get<double>(), 1e6);
  // Still a distance field: the sphere's centre is about one radius inside.
  EXPECT_NEAR(v->distance({0, 0, 0}).distance, -1.0, 2 * info["voxel_size"].get<double>());
}

TEST(OpenVdb, BandAutoCoversTheQueryBoxForDistance) {
  SKIP_WITHOUT_OPENVDB();
  Mesh m = icosphere(3);
  auto v = Registry::global().create("openvdb:voxel_abs=0.1");
  std::vector<Vec3d> pts = {{-3, -3, -3}, {3, 3, 3}};
  v->build(m, context(QueryType::distance, pts));
  // The farthest query point, a corner, is sqrt(27) - 1 = 4.2 from the sphere.
  EXPECT_GE(v->info()["ex_band_world"].get<double>(), 4.2);
  DistanceResult d = v->distance({3, 3, 3});
  EXPECT_NEAR(d.distance, std::sqrt(27.0) - 1, 0.1);
  EXPECT_NEAR(norm(d.closest), 1.0, 0.1);
  d = v->distance({0, 0, 0});
  EXPECT_NEAR(d.distance, -1.0, 0.1);
  EXPECT_LT(v->structure_bytes(), std::size_t(200) << 20);
}
