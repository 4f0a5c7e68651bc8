// The oracle (harness/oracle.*, `bvhbench truth`) against brute_force and against hand-computed
// answers: closed and open meshes, a single triangle, rays through edges and vertices, ties; and
// compute_accuracy on the oracle file it writes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "harness/core/mesh.hpp"
#include "harness/core/oracle.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/oracle_file.hpp"
#include "harness/run/accuracy.hpp"
#include "harness/util/errors.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

/// n points uniform in the mesh's box grown by `margin` times its extent each way, drawn axis
/// by axis. Not test::random_points: its arithmetic differs, and these cases keep their points.
std::vector<Vec3d> random_points_around(const Mesh& m, std::size_t n, unsigned seed, double margin = 0.2) {
  Box3d b = m.bounds();
  Vec3d e = b.extent();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3d> pts(n);
  for (auto& p : pts)
    for (int k = 0; k < 3; ++k) p[k] = b.lo[k] - margin * e[k] + u(rng) * (1 + 2 * margin) * e[k];
  return pts;
}

/// Points on and just off the surface: triangle vertices, edge midpoints, face points, offsets.
std::vector<Vec3d> surface_points(const Mesh& m, std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double diag = m.bounds().diagonal();
  std::vector<Vec3d> pts;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& t = m.triangles[rng() % m.triangles.size()];
    Vec3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
    Vec3d nrm = triangle_normal(a, b, c);
    switch (i % 4) {
      case 0: pts.push_back(a); break;
      case 1: pts.push_back((a + b) * 0.5); break;
      default: {
        double r1 = u(rng), r2 = u(rng);
        if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
        Vec3d q = a + (b - a) * r1 + (c - a) * r2;
        pts.push_back(q + nrm * ((u(rng) - 0.5) * 1e-3 * diag));
      }
    }
  }
  return pts;
}

/// brute_force built with a default BuildContext (query type inside).
std::unique_ptr<Method> brute(const Mesh& mesh) { return build_method("brute_force", mesh, QueryType::inside); }

/// Generalized winding number by direct summation (what brute_force thresholds).
double brute_winding(const Mesh& m, const Vec3d& p) {
  double w = 0;
  for (const auto& t : m.triangles) w += triangle_winding(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]);
  return w;
}

/// Checks the oracle against brute force on these points: distance to 1e-12 of the diagonal,
/// brute force's triangle among the ties, winding number, and inside away from the surface.
void check_against_brute_force(const Mesh& mesh, const std::vector<Vec3d>& pts, bool expect_closed) {
  Oracle oracle(mesh);
  EXPECT_EQ(oracle.closed(), expect_closed);
  auto bf = brute(mesh);
  const double diag = oracle.diagonal();
  OracleAnswers a = oracle.answer(pts);
  EXPECT_EQ(a.definition, expect_closed ? "exact" : "winding_number");
  std::size_t compared_inside = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec3d& p = pts[i];
    DistanceResult d = bf->distance(p);
    ASSERT_NEAR(a.distance[i], std::abs(d.distance), 1e-12 * diag) << "query " << i;
    EXPECT_NEAR(norm(a.closest[i] - p), a.distance[i], 1e-12 * diag);
    // brute_force keeps the lowest index among exact ties; ours is among the recorded ties.
    bool found = false;
    for (int k = 0; k < kMaxTied; ++k) found |= a.tied[i * kMaxTied + k] == d.triangle;
    EXPECT_TRUE(found || a.tie_count[i] > kMaxTied) << "query " << i << " bf triangle " << d.triangle;
    EXPECT_GE(a.tie_count[i], 1);
    const double w = brute_winding(mesh, p);
    if (a.distance[i] > 1e-9 * diag) {
      EXPECT_NEAR(a.winding[i], w, 1e-8) << "query " << i;
      if (std::abs(std::abs(w) - 0.5) > 1e-6 && w > -0.5) {
        EXPECT_EQ(a.inside[i] != 0, bf->inside(p)) << "query " << i << " w=" << w;
        ++compared_inside;
      }
    }
    if (expect_closed) {
      EXPECT_EQ(a.winding[i], std::round(a.winding[i]));
    }
  }
  EXPECT_GT(compared_inside, pts.size() / 2);
}

}  // namespace

TEST(Truth, CubeAgainstBruteForce) {
  Mesh m = unit_cube();
  auto pts = random_points_around(m, 2000, 1);
  auto s = surface_points(m, 400, 2);
  pts.insert(pts.end(), s.begin(), s.end());
  check_against_brute_force(m, pts, true);
}

TEST(Truth, CubeRaysThroughEdgesAndVertices) {
  // Coordinates on the cube's vertex/edge lines make the +x ray graze edges and vertices (and
  // the diagonals of the face triangulations): the symbolic perturbation must still count right.
  Mesh cube = unit_cube();
  Oracle o(cube);
  const double vals[] = {-0.5, 0.0, 0.25, 0.5, 1.0, 1.5};
  int checked = 0;
  for (double x : vals)
    for (double y : vals)
      for (double z : vals) {
        auto in01 = [](double v) { return v > 0 && v < 1; };
        auto on01 = [](double v) { return v >= 0 && v <= 1; };
        const bool inside = in01(x) && in01(y) && in01(z);
        const bool on_surface = !inside && on01(x) && on01(y) && on01(z);
        if (on_surface) continue;
        EXPECT_EQ(o.winding({x, y, z}), inside ? 1.0 : 0.0) << x << " " << y << " " << z;
        ++checked;
      }
  EXPECT_GT(checked, 100);
  // Diagonal rays: y == z runs along the face diagonals {0,2}/{0,6}...
  for (double t : {0.1, 0.5, 0.9}) {
    EXPECT_EQ(o.winding({0.5, t, t}), 1.0);
    EXPECT_EQ(o.winding({0.5, t, 1 - t}), 1.0);
    EXPECT_EQ(o.winding({-3, t, t}), 0.0);
  }
}

TEST(Truth, InvertedCubeIsStillSolid) {
  Mesh m = unit_cube();
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  Oracle o(m);
  EXPECT_TRUE(o.closed());
  EXPECT_EQ(o.winding({0.5, 0.5, 0.5}), -1.0);
  EXPECT_TRUE(o.inside_from_winding(o.winding({0.5, 0.5, 0.5})));
  EXPECT_FALSE(o.inside_from_winding(o.winding({1.5, 0.5, 0.5})));
}

TEST(Truth, OpenCupAgainstBruteForce) {
  Mesh m = open_cup();
  auto pts = random_points_around(m, 2000, 3);
  auto s = surface_points(m, 400, 4);
  pts.insert(pts.end(), s.begin(), s.end());
  check_against_brute_force(m, pts, false);
  Oracle o(m);
  EXPECT_EQ(o.boundary_edge_count(), 4u);
  // Deep in the cup, the winding number is close to 1; above the opening it falls below 1/2.
  EXPECT_GT(o.winding({0.5, 0.5, 0.05}), 0.9);
  EXPECT_LT(o.winding({0.5, 0.5, 1.5}), 0.5);
}

TEST(Truth, SingleTriangle) {
  Mesh m = one_triangle();
  auto pts = random_points_around(m, 500, 5, 1.0);
  pts.push_back({0, 0, 0});
  pts.push_back({0.25, 0.25, 0});
  pts.push_back({0.25, 0.25, 1e-9});
  pts.push_back({2, 2, 0});
  check_against_brute_force(m, pts, false);
  Oracle o(m);
  OracleNearest r = o.nearest({0.25, 0.25, 2});
  EXPECT_DOUBLE_EQ(r.distance, 2);
  EXPECT_EQ(r.triangle, 0);
  EXPECT_EQ(r.tie_count, 1);
  EXPECT_DOUBLE_EQ(r.normal.z, 1);
}

TEST(Truth, Ties) {
  Mesh cube = unit_cube();
  Oracle o(cube);
  // The centre is 0.5 from every face, and each face's two triangles share the face centre.
  OracleNearest c = o.nearest({0.5, 0.5, 0.5});
  EXPECT_DOUBLE_EQ(c.distance, 0.5);
  EXPECT_EQ(c.tie_count, 12);
  EXPECT_EQ(c.triangle, 0);
  // Beyond the corner (1,1,1): every triangle using vertex 6 is tied.
  OracleNearest v = o.nearest({2, 2, 2});
  EXPECT_DOUBLE_EQ(v.distance, std::sqrt(3.0));
  int uses6 = 0;
  for (auto& t : cube.triangles) uses6 += t[0] == 6 || t[1] == 6 || t[2] == 6;
  EXPECT_EQ(v.tie_count, uses6);
  // Off the middle of a face, away from its diagonal: no tie.
  OracleNearest f = o.nearest({0.8, 0.3, 1.5});
  EXPECT_EQ(f.tie_count, 1);
  EXPECT_DOUBLE_EQ(f.distance, 0.5);
  EXPECT_DOUBLE_EQ(f.normal.z, 1);
}

TEST(Truth, DegenerateTrianglesAreHarmless) {
  Mesh m = unit_cube();
  // A zero-area triangle (collinear) and a collapsed one (repeated index) inside a closed cube.
  m.vertices.push_back({0.5, 0.5, 0.5});
  m.triangles.push_back({0, 6, 6});
  m.triangles.push_back({0, 8, 6});
  m.triangles.push_back({6, 8, 0});  // its reverse: the surface stays a closed cycle
  Oracle o(m);
  EXPECT_TRUE(o.closed());
  EXPECT_EQ(o.winding({0.5, 0.2, 0.7}), 1.0);
  EXPECT_EQ(o.winding({1.5, 0.5, 0.5}), 0.0);
  EXPECT_EQ(o.winding({0.25, 0.25, 0.25}), 1.0);  // on the degenerate triangles' line
}

TEST(Truth, CowAgainstBruteForce) {
  Mesh m = load_shared_mesh("cow.obj");
  auto pts = random_points_around(m, 600, 7, 0.1);
  auto s = surface_points(m, 200, 8);
  pts.insert(pts.end(), s.begin(), s.end());
  check_against_brute_force(m, pts, true);
}

TEST(Truth, BunnyOpenAgainstBruteForce) {
  Mesh m = load_shared_mesh("stanford-bunny.obj");
  auto pts = random_points_around(m, 150, 9, 0.1);
  auto s = surface_points(m, 50, 10);
  pts.insert(pts.end(), s.begin(), s.end());
  check_against_brute_force(m, pts, false);
}

TEST(Truth, OracleFileAndAccuracy) {
  Mesh m = load_shared_mesh("cow.obj");
  auto pts = random_points_around(m, 300, 11, 0.1);
  Oracle o(m);
  OracleAnswers oa = o.answer(pts);
  const std::string path =
      (std::filesystem::temp_directory_path() / ("bvhbench_truth_test_" + std::to_string(::getpid()) + ".npz")).string();
  write_oracle_npz(path, oa, m.sha256, "q-sha");
  const double diag = m.bounds().diagonal();

  auto bf = brute(m);
  Answers in, dist;
  in.resize(QueryType::inside, pts.size());
  dist.resize(QueryType::distance, pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    in.inside[i] = bf->inside(pts[i]);
    DistanceResult d = bf->distance(pts[i]);
    dist.distance[i] = d.distance;
    dist.closest[i] = d.closest;
    dist.normal[i] = d.normal;
    dist.triangle[i] = d.triangle;
  }
  auto ai = compute_accuracy(in, path, diag, "q-sha", m.sha256);
  EXPECT_EQ(ai["definition"], "exact");
  EXPECT_EQ(ai["inside"]["wrong_far"], 0);
  auto ad = compute_accuracy(dist, path, diag, "q-sha");
  EXPECT_LT(ad["distance"]["abs_error"]["max"].get<double>(), 1e-12 * diag);
  EXPECT_EQ(ad["distance"]["sign_wrong"], 0);
  EXPECT_EQ(ad["distance"]["triangle_agreement"].get<double>(), 1.0);
  EXPECT_LT(ad["distance"]["normal_angle_deg"]["max"].get<double>(), 1e-4);  // acos near 1

  // Wrong answers are measured, not rejected; NaN is counted apart.
  dist.distance[0] = -dist.distance[0] + 1.0;
  dist.distance[1] = std::nan("");
  in.inside[2] = !in.inside[2];
  auto bad = compute_accuracy(dist, path, diag);
  EXPECT_EQ(bad["distance"]["non_finite"], 1);
  EXPECT_GE(bad["distance"]["abs_error"]["max"].get<double>(), 1.0);
  EXPECT_EQ(compute_accuracy(in, path, diag)["inside"]["wrong"], 1);

  // An oracle for another query set or mesh is refused.
  EXPECT_THROW(compute_accuracy(in, path, diag, "other-sha"), InputError);
  EXPECT_THROW(compute_accuracy(in, path, diag, "", "other-mesh"), InputError);
  Answers short_in;
  short_in.resize(QueryType::inside, 5);
  EXPECT_THROW(compute_accuracy(short_in, path, diag), InputError);
  std::remove(path.c_str());
}
