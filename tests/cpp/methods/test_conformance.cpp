// One conformance suite for every method in Registry::global() that is not testing-only, and for
// the coherent variant (`coherent=true`) of each method that declares coherence: a method added
// under methods/ is checked here with no change to this file.
//
// What every method must do (methods/README.md, "The interface"; docs/architecture.md, "Contracts"):
//  - answer inside and distance like brute_force on the real shared meshes, for random and haptic
//    query sets made by the harness's own generators, within what its precision allows (below);
//  - answers() (the registered capabilities, narrowed by supports()) agrees with the registered capabilities; structure_bytes() > 0 after build; the
//    work counters are deterministic (the same pass twice counts the same) and reset to zero;
//  - the coherent variant gives the default's answers along a haptic path, pass after pass;
//  - the empty mesh is refused with an InputError, or answered as documented below;
//  - the one-triangle mesh, points exactly on a vertex, an edge and a face, degenerate triangles
//    and open surfaces: no crash, and the answers below.
//
// Precision. The registry does not declare a method's precision, so the few methods whose
// precision differs from the contract's default (docs/meshes.md: methods keep float32
// coordinates) are named in declared_precision(); a new method gets the float32 checks.
//  - exact_double (brute_force): the reference itself; a fresh instance agrees bit for bit.
//  - exact_float32 (ebp_octree): exact on the float32-rounded mesh, so bit for bit with
//    brute_force built on that mesh: the same |distance|, closest point and triangle (the
//    lexicographic minimum of squared distance and index); the same inside away from the surface.
//  - float32 (cgal_aabb, embree, and any new method): the checks of expect_matches_brute_force
//    (test_support.hpp) against brute_force on the float32-rounded mesh: |distance| within 1e-5
//    of the diagonal (float32 coordinates carry 24 bits, ~6e-8 of the diagonal per coordinate; a
//    method may compute in float on them), the closest triangle or a tie, its face normal.
//  - double_library (the Python methods libigl, point_cloud_utils, gpytoolbox): the library keeps
//    the mesh in double as given, so float32's checks against brute_force on that mesh (on the
//    float32-rounded one a sliver's face normal or a near tie differs by the rounding, not by the
//    method).
//  - approximate_library (the Python methods trimesh, fcpw, open3d, warp): the mesh as given, but
//    the closest triangle is only as good as the distance: a "tie" is within the distance's own tolerance, 1e-5
//    of the diagonal, and a point on the surface is within 1e-6 of it. fcpw searches in float32
//    arithmetic; trimesh's on_surface picked a triangle up to 7e-7 farther than the closest on 1-2
//    of 2000 random points of fandisk and rocker-arm (measured), both well inside 1e-5. Open3D and
//    Warp keep the mesh in float32 and search in float32 (Embree 4, Warp's BVH): they picked a
//    triangle up to 4.9e-7 farther (4e-8 of the diagonal) than brute_force's on 1-4 of 1000 points
//    of cow, fandisk and rocker-arm (measured), and a point on the surface is 1.7e-8 from it (the
//    float32 rounding).
//  - sampled_field (openvdb): a distance field sampled on voxels, so the tolerance is in voxels
//    v, read from the built field (info(): voxel_size, its bands): see expect_field_conforms.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

// ---- the variants under test ----

/// How close a method's answers must be to brute_force's (see the file comment).
enum class Precision { exact_double, exact_float32, float32, double_library, approximate_library, sampled_field };

/// The precision a method declares in its description and documentation; float32 by default.
Precision declared_precision(const std::string& method) {
  static const std::map<std::string, Precision> declared = {
      {"brute_force", Precision::exact_double},
      {"ebp_octree", Precision::exact_float32},
      {"libigl", Precision::double_library},
      {"trimesh", Precision::approximate_library},
      {"fcpw", Precision::approximate_library},
      {"open3d", Precision::approximate_library},
      {"warp", Precision::approximate_library},
      {"point_cloud_utils", Precision::double_library},
      {"gpytoolbox", Precision::double_library},
      {"openvdb", Precision::sampled_field}};
  const auto it = declared.find(method);
  return it == declared.end() ? Precision::float32 : it->second;
}

/// One method as a suite job names it: the default, or its coherent variant.
struct Variant {
  std::string method;  ///< registered name
  std::string spec;    ///< "NAME" or "NAME:coherent=true"
  bool coherent = false;
};

void PrintTo(const Variant& v, std::ostream* os) { *os << v.spec; }

/// Every method of the registry that is not testing-only, and the coherent variant of each that
/// declares coherence, in registration order.
std::vector<Variant> registered_variants() {
  std::vector<Variant> out;
  for (const MethodInfo& m : Registry::global().methods()) {
    if (m.testing_only) continue;
    out.push_back({m.name, m.name, false});
    if (m.caps.coherence) out.push_back({m.name, m.name + ":coherent=true", true});
  }
  return out;
}

/// A test-name fragment for a spec: "cgal_aabb:coherent=true" -> "cgal_aabb_coherent_true".
std::string spec_name(const std::string& spec) {
  std::string s = spec;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

/// The small shared meshes the suite runs on (all closed), kept few to keep `make test` short.
const char* const kMeshes[] = {"cow.obj", "fandisk.obj", "rocker-arm.obj"};

/// Queries per query set: random and haptic, each this many.
constexpr std::size_t kQueriesPerSet = 500;

// ---- building and asking ----

/// `spec` built on `mesh` for `qt` questions, with the BuildContext run_job gives it: the box of
/// the query points (methods size their bands and caches from it) and the query kind.
std::unique_ptr<Method> build_for(const std::string& spec, const Mesh& mesh, QueryType qt,
                                  const std::vector<Vec3d>& queries, const std::string& kind = "random") {
  auto m = Registry::global().create(spec);
  BuildContext ctx;
  ctx.query_type = qt;
  for (const Vec3d& p : queries) ctx.query_bounds.add(p);
  ctx.query_kind = kind;
  m->build(mesh, ctx);
  return m;
}

/// A query set of `kind` ("random", "haptic") on `mesh`, as `bvhbench queries` makes it.
std::vector<Vec3d> harness_queries(const Mesh& mesh, const std::string& kind, std::size_t n, std::uint64_t seed) {
  nlohmann::json meta;
  return generate_queries(mesh, kind, n, seed, {}, &meta);
}

/// brute_force's distance answers on `ref_mesh` at `queries` (inside is the sign: brute_force
/// signs a distance by the same winding number its inside() thresholds, -0 included).
std::vector<DistanceResult> brute_force_answers(const Mesh& ref_mesh, const std::vector<Vec3d>& queries) {
  auto bf = build_method("brute_force", ref_mesh, QueryType::distance);
  std::vector<DistanceResult> out;
  out.reserve(queries.size());
  for (const Vec3d& p : queries) out.push_back(bf->distance(p));
  return out;
}

/// x with all its digits, for failure messages (a bit-for-bit check fails by one ulp).
std::string digits(double x) {
  std::ostringstream s;
  s.precision(17);
  s << x;
  return s.str();
}

/// p with all its digits.
std::string at(const Vec3d& p) { return "(" + digits(p.x) + ", " + digits(p.y) + ", " + digits(p.z) + ")"; }

/// Counts the queries where a check fails and keeps the first one's description, so a broken
/// method gives one readable failure per check instead of thousands.
struct Tally {
  int failed = 0;
  std::string first;
  void check(bool ok, const std::string& what, const Vec3d& p) {
    if (ok) return;
    if (failed++ == 0) first = what + " at " + at(p);
  }
};

#define EXPECT_NONE_FAILED(tally, name) \
  EXPECT_EQ((tally).failed, 0) << (name) << ": " << (tally).failed << " queries, first: " << (tally).first

/// The resolved parameters of `spec` (defaults filled in).
Params resolved_params(const std::string& spec) { return Registry::global().resolve(spec).params; }

// ---- the checks of each precision against brute_force ----

/// The methods that answer for the surface itself (every precision but sampled_field), against
/// brute_force on the mesh the method holds (the input for exact_double, its float32 rounding
/// otherwise):
///  - exact_double and exact_float32: bit for bit, the same |distance|, closest point, normal and
///    triangle;
///  - float32: |distance| within 1e-5 of the diagonal and |closest - p| = |distance| within 1e-9
///    of it; the same triangle or a tie (brute_force's distance to it the minimum within 1e-9 of
///    the diagonal); the normal that triangle's face normal within 1e-6.
///  - double_library and approximate_library: float32's checks on the mesh as given; approximate_library's
///    ties within 1e-5 of the diagonal.
/// Inside and the distance's sign, when `closed`: every query for exact_double (the reference
/// itself); otherwise farther than 1e-6 of the diagonal from the surface, where brute_force's
/// floating point winding number is certainly on the right side of 1/2. On an open surface a
/// parity method and the winding number disagree by design: only |distance| is owed.
void expect_surface_conforms(const Variant& v, Precision precision, const Mesh& mesh, bool closed,
                             const std::vector<Vec3d>& q, const std::string& kind) {
  const bool bit_for_bit = precision == Precision::exact_double || precision == Precision::exact_float32;
  const bool as_given = precision == Precision::exact_double || precision == Precision::double_library ||
                        precision == Precision::approximate_library;
  const Mesh ref_mesh = as_given ? mesh : float_rounded(mesh);
  const auto want = brute_force_answers(ref_mesh, q);
  const double diag = ref_mesh.bounds().diagonal();
  const double sign_margin = precision == Precision::exact_double ? -1.0 : 1e-6 * diag;
  const double tie = (precision == Precision::approximate_library ? 1e-5 : 1e-9) * diag;
  Tally distance, closest, triangle, normal, sign, inside;
  auto ins = build_for(v.spec, mesh, QueryType::inside, q, kind);
  auto dist = build_for(v.spec, mesh, QueryType::distance, q, kind);
  ins->reset_path();
  dist->reset_path();
  for (std::size_t i = 0; i < q.size(); ++i) {
    const Vec3d& p = q[i];
    const DistanceResult got = dist->distance(p);
    const bool in = ins->inside(p);
    const double want_abs = std::abs(want[i].distance);
    const std::string answered = digits(got.distance) + " (triangle " + std::to_string(got.triangle) +
                                 "), brute_force " + digits(want[i].distance) + " (triangle " +
                                 std::to_string(want[i].triangle) + ")";
    if (bit_for_bit) {
      distance.check(std::abs(got.distance) == want_abs, "|distance| " + answered, p);
      closest.check(got.closest == want[i].closest, "closest point", p);
      triangle.check(got.triangle == want[i].triangle, "triangle " + answered, p);
      normal.check(got.normal == want[i].normal, "normal", p);
    } else {
      distance.check(std::abs(std::abs(got.distance) - want_abs) <= 1e-5 * diag, "|distance| " + answered, p);
      closest.check(std::abs(norm(got.closest - p) - std::abs(got.distance)) <= 1e-9 * diag,
                    "|closest - p| is not |distance|", p);
      const bool known = got.triangle >= 0 && std::size_t(got.triangle) < mesh.triangles.size();
      triangle.check(known && (got.triangle == want[i].triangle ||
                               std::abs(distance_to_triangle(ref_mesh, got.triangle, p) - want_abs) <= tie),
                     "triangle neither brute_force's nor a tie: " + answered, p);
      if (known) {
        const auto& f = ref_mesh.triangles[std::size_t(got.triangle)];
        const Vec3d n = triangle_normal(ref_mesh.vertices[f[0]], ref_mesh.vertices[f[1]], ref_mesh.vertices[f[2]]);
        normal.check(norm(got.normal - n) <= 1e-6, "normal is not the triangle's face normal", p);
      }
    }
    if (closed && want_abs > sign_margin) {
      const bool want_in = std::signbit(want[i].distance);
      sign.check(std::signbit(got.distance) == want_in, "sign of distance " + answered, p);
      inside.check(in == want_in, std::string("inside ") + (in ? "true" : "false"), p);
    }
  }
  EXPECT_NONE_FAILED(distance, v.spec);
  EXPECT_NONE_FAILED(closest, v.spec);
  EXPECT_NONE_FAILED(triangle, v.spec);
  EXPECT_NONE_FAILED(normal, v.spec);
  EXPECT_NONE_FAILED(sign, v.spec);
  EXPECT_NONE_FAILED(inside, v.spec);
}

/// sampled_field: a signed distance field sampled at voxel centres (OpenVDB's meshToVolume) and
/// interpolated. Its tolerances come from the field as built, in voxels v (info()["voxel_size"]):
///  - distance within the band (info() ex_band_world / in_band_world, less the one voxel the
///    stencil reaches): the sdf is 1-Lipschitz, so trilinear interpolation (order=1) of the 8
///    corner values is within the half cell diagonal sqrt(3)/2 v of sdf(p): <= 1 v with the
///    library's renormalisation; triquadratic (order=2) is not a convex blend and overshoots at
///    kinks: 1.5 v. A mean error <= 0.15 v (smooth regions interpolate far better). Beyond the
///    band the field holds its background: the answer is the clamp (exterior or interior value);
///  - inside identical wherever |sdf| > 2 v (the stencil then has one sign), in or out of band;
///  - normal: the normalised gradient of the field, a unit vector (zero where the field is flat,
///    beyond the band). How close it is to the closest face's normal depends on the surface's
///    curvature against the voxel, not on a tolerance the parameters give (at the default voxel,
///    86-99% of the near-surface face-interior queries are within 15 degrees, mesh by mesh):
///    test_openvdb.cpp asserts that rate for a voxel of 1/128 of the diagonal;
///  - closest point: on the surface within 1 v for 95% of the queries (two gradient steps),
///    checked on every fourth query in the band;
///  - closest triangle: the voxel keeps the triangle closest to its centre, so one within 1 v of
///    the true distance for 99% of the queries. (How often it is the very triangle depends on
///    the triangles' size against the voxel's, not on a tolerance: test_openvdb.cpp asserts a
///    rate for a voxel smaller than the triangles.)
/// On an open surface (`closed` false) the sign means nothing: |distance| within the band is owed,
/// and none of the statistics.
void expect_field_conforms(const Variant& v, const Mesh& mesh, bool closed, const std::vector<Vec3d>& q,
                           const std::string& kind) {
  const auto want = brute_force_answers(mesh, q);
  auto ins = build_for(v.spec, mesh, QueryType::inside, q, kind);
  auto dist = build_for(v.spec, mesh, QueryType::distance, q, kind);
  ins->reset_path();
  dist->reset_path();
  const nlohmann::json info = dist->info();
  const double vox = info.at("voxel_size").get<double>();
  ASSERT_GT(vox, 0);
  const double ex_band = info.at("ex_band_world").get<double>(), in_band = info.at("in_band_world").get<double>();
  const double exterior = info.at("exterior_value").get<double>(), interior = info.at("interior_value").get<double>();
  const double tol = resolved_params(v.spec).get_int("order") == 2 ? 1.5 : 1.0;
  Tally distance, inside, normal;
  int n = 0, in_band_n = 0, closest_checked = 0, closest_ok = 0, tri_near = 0;
  double sum_err = 0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    const Vec3d& p = q[i];
    const DistanceResult got = dist->distance(p);
    const double ref = want[i].distance;
    ++n;
    if (closed && std::abs(ref) > 2 * vox) inside.check(ins->inside(p) == (ref < 0), "inside", p);
    const bool banded = ref >= 0 ? ref <= ex_band - vox : -ref <= in_band - vox;
    if (banded) {
      const double err = (closed ? std::abs(got.distance - ref) : std::abs(std::abs(got.distance) - std::abs(ref))) / vox;
      ++in_band_n;
      sum_err += err;
      distance.check(err <= tol, "distance " + digits(got.distance) + " vs " + digits(ref), p);
    } else if (closed && std::abs(ref) > (ref >= 0 ? ex_band : in_band) + vox) {
      distance.check(got.distance == (ref >= 0 ? exterior : interior), "beyond the band, not the clamp", p);
    }
    const double n_len = norm(got.normal);
    normal.check(n_len == 0 || std::abs(n_len - 1) <= 1e-9, "normal of length " + std::to_string(n_len), p);
    if (banded && i % 4 == 0) {  // a brute-force search of its own: every fourth query will do
      ++closest_checked;
      double on_surface = 1e300;
      for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        on_surface = std::min(on_surface, distance_to_triangle(mesh, std::int64_t(t), got.closest));
      if (on_surface <= vox) ++closest_ok;
    }
    if (banded) {
      if (got.triangle >= 0 && std::size_t(got.triangle) < mesh.triangles.size() &&
          distance_to_triangle(mesh, got.triangle, p) <= std::abs(ref) + vox)
        ++tri_near;
    }
  }
  EXPECT_NONE_FAILED(distance, v.spec);
  EXPECT_NONE_FAILED(inside, v.spec);
  EXPECT_NONE_FAILED(normal, v.spec);
  if (!closed) return;
  ASSERT_GT(in_band_n, n / 2) << v.spec << ": the band should reach most of the query box";
  EXPECT_LE(sum_err / in_band_n, 0.15) << v.spec;
  EXPECT_GE(closest_ok, 0.95 * closest_checked) << v.spec << ": " << closest_ok << "/" << closest_checked;
  EXPECT_GE(tri_near, 0.99 * in_band_n) << v.spec << ": " << tri_near << "/" << in_band_n;
}

/// The checks of v's declared precision against brute_force at `q` (of `kind`) on `mesh`.
void expect_conforms(const Variant& v, const Mesh& mesh, bool closed, const std::vector<Vec3d>& q,
                     const std::string& kind) {
  SCOPED_TRACE(v.spec + ", " + kind + " queries");
  const Precision precision = declared_precision(v.method);
  if (precision == Precision::sampled_field) return expect_field_conforms(v, mesh, closed, q, kind);
  expect_surface_conforms(v, precision, mesh, closed, q, kind);
}

// ---- the suites ----

class MethodConformance : public ::testing::TestWithParam<Variant> {};

struct VariantName {
  std::string operator()(const ::testing::TestParamInfo<Variant>& info) const { return spec_name(info.param.spec); }
};

class MethodOnSharedMesh : public ::testing::TestWithParam<std::tuple<Variant, const char*>> {};

struct VariantMeshName {
  std::string operator()(const ::testing::TestParamInfo<std::tuple<Variant, const char*>>& info) const {
    return spec_name(std::get<0>(info.param).spec) + "__" + mesh_stem(std::get<1>(info.param), "_");
  }
};

}  // namespace

// Each registered method answers like brute_force on a real mesh, for random and haptic queries.
TEST_P(MethodOnSharedMesh, AnswersLikeBruteForce) {
  const Variant& v = std::get<0>(GetParam());
  const Mesh mesh = load_shared_mesh(std::get<1>(GetParam()));
  for (const char* kind : {"random", "haptic"})
    expect_conforms(v, mesh, true, harness_queries(mesh, kind, kQueriesPerSet, 1), kind);
}

INSTANTIATE_TEST_SUITE_P(Registered, MethodOnSharedMesh,
                         ::testing::Combine(::testing::ValuesIn(registered_variants()), ::testing::ValuesIn(kMeshes)),
                         VariantMeshName());

// answers() is what the registry says the method answers; a query it does not support throws
// UnsupportedError (the harness records `unsupported`, it never fakes an answer); coherence is
// declared as the boolean parameter `coherent`, off by default, which this suite turns on.
TEST_P(MethodConformance, SupportsWhatItRegistered) {
  const Variant& v = GetParam();
  const MethodInfo* info = Registry::global().find(v.method);
  ASSERT_NE(info, nullptr);
  if (info->caps.coherence) {
    const auto it = std::find_if(info->params.begin(), info->params.end(),
                                 [](const ParamSpec& s) { return s.name == "coherent"; });
    ASSERT_NE(it, info->params.end()) << v.method << " declares coherence without a `coherent` parameter";
    EXPECT_EQ(it->type, bvhbench::ParamType::boolean) << v.method;
    EXPECT_EQ(it->default_value, "false") << v.method << ": the default must be the plain variant";
  }
  const Mesh mesh = unit_cube();
  const std::vector<Vec3d> q = {{0.5, 0.5, 0.5}, {2, 2, 2}};
  for (QueryType qt : {QueryType::inside, QueryType::distance}) {
    SCOPED_TRACE(std::string(v.spec) + " built for " + to_string(qt));
    auto m = build_for(v.spec, mesh, qt, q);
    EXPECT_EQ(answers(*info, *m, QueryType::inside), info->caps.inside);
    EXPECT_EQ(answers(*info, *m, QueryType::distance), info->caps.distance);
    if (qt == QueryType::inside && !answers(*info, *m, QueryType::inside)) {
      EXPECT_THROW((void)m->inside(q[0]), UnsupportedError);
    }
    if (qt == QueryType::distance && !answers(*info, *m, QueryType::distance)) {
      EXPECT_THROW((void)m->distance(q[0]), UnsupportedError);
    }
    if (qt == QueryType::distance && answers(*info, *m, QueryType::distance)) {
      const DistanceResult d = m->distance(q[1]);
      if (info->caps.closest_triangle) {
        EXPECT_GE(d.triangle, 0);
        EXPECT_LT(d.triangle, 12);
      } else {
        EXPECT_EQ(d.triangle, -1) << "a method without closest_triangle reports -1";
      }
    }
  }
}

// structure_bytes() > 0 once built; counters are zero after reset_counters() and the same pass
// counts the same work twice (CI gates them exactly).
TEST_P(MethodConformance, BytesAndDeterministicCounters) {
  const Variant& v = GetParam();
  const Mesh mesh = load_shared_mesh("cow.obj");
  for (const char* kind : {"random", "haptic"}) {
    const auto q = harness_queries(mesh, kind, 300, 2);
    for (QueryType qt : {QueryType::inside, QueryType::distance}) {
      SCOPED_TRACE(v.spec + " " + to_string(qt) + ", " + kind + " queries");
      auto m = build_for(v.spec, mesh, qt, q, kind);
      if (!m->supports(qt)) continue;
      EXPECT_GT(m->structure_bytes(), 0u);
      std::vector<std::vector<Counter>> passes;
      for (int pass = 0; pass < 2; ++pass) {
        m->reset_path();
        m->reset_counters();
        for (const Counter& c : m->counters()) EXPECT_EQ(c.value, 0u) << c.name << " after reset_counters()";
        for (const Vec3d& p : q) {
          if (qt == QueryType::inside)
            (void)m->inside(p);
          else
            (void)m->distance(p);
        }
        passes.push_back(m->counters());
      }
      ASSERT_EQ(passes[0].size(), passes[1].size());
      for (std::size_t i = 0; i < passes[0].size(); ++i) {
        EXPECT_EQ(passes[0][i].name, passes[1][i].name);
        EXPECT_EQ(passes[0][i].value, passes[1][i].value) << passes[0][i].name;
      }
    }
  }
}

// The empty mesh: refused with an InputError naming the method (status rejected_input), never
// another exception; or, for a method that accepts it, nothing is inside and no triangle is the
// closest. (The mesh readers refuse an empty mesh before any method sees it; this is the
// method's own guard, for callers of the interface.)
TEST_P(MethodConformance, EmptyMeshIsRefusedCleanly) {
  const Variant& v = GetParam();
  const Mesh empty;
  const std::vector<Vec3d> q = {{0, 0, 0}, {1, 1, 1}};
  for (QueryType qt : {QueryType::inside, QueryType::distance}) {
    SCOPED_TRACE(v.spec + " built for " + to_string(qt));
    std::unique_ptr<Method> m;
    try {
      m = build_for(v.spec, empty, qt, q);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(v.method), std::string::npos) << "the refusal names the method: " << e.what();
      continue;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "refused with an exception that is not an InputError: " << e.what();
      continue;
    }
    // Accepted (a method may document answers for it): nothing is inside, and no triangle is
    // the closest.
    if (m->supports(QueryType::inside)) {
      EXPECT_FALSE(m->inside(q[0]));
    }
    if (m->supports(QueryType::distance)) {
      EXPECT_EQ(m->distance(q[1]).triangle, -1);
    }
  }
}

// The one-triangle mesh (an open surface): a point on a vertex, on an edge and on the face is on
// the surface; above the face, the distance and the normal; far away, the closest vertex and
// outside.
TEST_P(MethodConformance, OneTriangle) {
  const Variant& v = GetParam();
  const Precision precision = declared_precision(v.method);
  // The triangle's diagonal is ~1.4: on the surface within 1e-6 for an approximate library.
  if (precision == Precision::approximate_library) return expect_one_triangle_answers(v.spec, 1e-6);
  if (precision != Precision::sampled_field) return expect_one_triangle_answers(v.spec);
  // A field: within a voxel of the triangle, the clamp far away.
  const Mesh m = one_triangle();
  const std::vector<Vec3d> box = {{-0.2, -0.2, -0.2}, {1.2, 1.2, 0.4}};
  auto d = build_for(v.spec, m, QueryType::distance, box), in = build_for(v.spec, m, QueryType::inside, box);
  const double vox = d->info().at("voxel_size").get<double>();
  for (Vec3d p : {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0.5, 0.5, 0}, Vec3d{0.2, 0.2, 0}}) {
    const DistanceResult r = d->distance(p);
    EXPECT_LE(std::abs(r.distance), vox) << at(p);
    EXPECT_EQ(r.triangle, 0) << at(p);
    (void)in->inside(p);  // on the surface: any answer, but an answer
  }
  const DistanceResult far = d->distance({1e6, -1e6, 1e6});
  EXPECT_EQ(far.distance, d->info().at("exterior_value").get<double>());
  EXPECT_FALSE(in->inside({1e6, -1e6, 1e6}));
}

// A closed mesh, queried exactly on its surface: on a vertex, an edge, a face.
TEST_P(MethodConformance, PointsOnTheSurfaceOfAClosedMesh) {
  const Variant& v = GetParam();
  if (declared_precision(v.method) != Precision::sampled_field) return expect_cube_surface_answers(v.spec);
  // A field: within a voxel, on an icosphere (the cube is a voxel or two at the default size).
  const Mesh m = icosphere(3);
  const auto& t = m.triangles[7];
  const Vec3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
  const std::vector<Vec3d> on = {a, (a + b) * 0.5, (a + b + c) * (1.0 / 3)};
  auto d = build_for(v.spec, m, QueryType::distance, {a * 1.5, a * 0.5});
  auto in = build_for(v.spec, m, QueryType::inside, {a * 1.5, a * 0.5});
  const double vox = d->info().at("voxel_size").get<double>();
  for (const Vec3d& p : on) {
    const DistanceResult r = d->distance(p);
    EXPECT_LE(std::abs(r.distance), vox) << at(p);
    EXPECT_LE(norm(r.closest - p), vox) << at(p);
    EXPECT_GT(dot(r.normal, normalized(p)), 0.95) << at(p);
    ASSERT_GE(r.triangle, 0) << at(p);
    EXPECT_LE(distance_to_triangle(m, r.triangle, p), vox) << at(p);
    (void)in->inside(p);  // must terminate
  }
  EXPECT_TRUE(in->inside({0, 0, 0}));
  EXPECT_FALSE(in->inside({3, 3, 3}));
}

// Zero-area, collapsed and duplicate triangles are valid input (docs/architecture.md, "Contracts"): inside stays
// right and distances match brute force; a mesh of nothing but zero-area triangles is a segment.
TEST_P(MethodConformance, DegenerateTriangles) {
  const Variant& v = GetParam();
  if (declared_precision(v.method) == Precision::sampled_field) {
    // A field of a degenerate sphere: within its tolerance of brute force (the checks of a field).
    Mesh m = icosphere(2);
    const std::size_t n = m.triangles.size();
    for (std::size_t i = 0; i < n; i += 7) m.triangles.push_back(m.triangles[i]);  // duplicates
    m.triangles.push_back({0, 0, 1});  // zero area (collapsed edge)
    m.triangles.push_back({3, 3, 3});  // a point
    const auto q = sample_queries(m, 100, 100, 7);
    expect_field_conforms(v, m, true, q, "random");
    return;
  }
  expect_degenerate_triangle_answers(v.spec);
  expect_all_degenerate_answers(v.spec);
}

// Open surfaces: |distance| is owed as on a closed mesh; inside is an answer (parity and the
// winding number disagree by design), the same when asked again, and false far away.
TEST_P(MethodConformance, OpenSurfaces) {
  const Variant& v = GetParam();
  for (const Mesh& m : {open_cup(), torus(48, 16, 1.0, 0.35, true)}) {
    const auto q = sample_queries(m, 150, 150, 9);
    expect_conforms(v, m, false, q, "random");
    auto in = build_for(v.spec, m, QueryType::inside, q);
    if (!in->supports(QueryType::inside)) continue;
    in->reset_path();
    std::vector<bool> first;
    for (const Vec3d& p : q) first.push_back(in->inside(p));
    in->reset_path();
    int changed = 0;
    for (std::size_t i = 0; i < q.size(); ++i) changed += in->inside(q[i]) != first[i];
    EXPECT_EQ(changed, 0) << v.spec << ": inside changed between two passes";
    const Box3d b = m.bounds();
    EXPECT_FALSE(in->inside(b.hi + b.extent() * 3.0)) << v.spec;
    EXPECT_FALSE(in->inside(b.lo - b.extent() * 3.0)) << v.spec;
  }
}

INSTANTIATE_TEST_SUITE_P(Registered, MethodConformance, ::testing::ValuesIn(registered_variants()), VariantName());

// ---- the coherent variants ----

namespace {

class CoherentVariant : public ::testing::TestWithParam<std::tuple<Variant, const char*>> {};

std::vector<Variant> coherent_variants() {
  std::vector<Variant> out;
  for (const Variant& v : registered_variants())
    if (v.coherent) out.push_back(v);
  return out;
}

}  // namespace

// Along a haptic path, pass after pass (reset_path() between), the coherent variant answers what
// the default does: bit for bit for the exact methods; for the others the same distance within
// 1e-12 of the diagonal and the same triangle or a tie within 1e-9 of it. Inside is identical.
TEST_P(CoherentVariant, AnswersLikeTheDefaultOnAHapticPath) {
  const Variant& v = std::get<0>(GetParam());
  const Mesh mesh = load_shared_mesh(std::get<1>(GetParam()));
  const auto path = harness_queries(mesh, "haptic", 1000, 3);
  const Precision precision = declared_precision(v.method);
  const bool exact = precision == Precision::exact_double || precision == Precision::exact_float32;
  const Mesh ref_mesh = float_rounded(mesh);
  const double diag = ref_mesh.bounds().diagonal();
  for (QueryType qt : {QueryType::inside, QueryType::distance}) {
    auto plain = build_for(v.method, mesh, qt, path, "haptic");
    auto coherent = build_for(v.spec, mesh, qt, path, "haptic");
    if (!coherent->supports(qt)) continue;
    Tally distance, triangle, closest, inside;
    for (int pass = 0; pass < 2; ++pass) {
      plain->reset_path();
      coherent->reset_path();
      for (const Vec3d& p : path) {
        if (qt == QueryType::inside) {
          inside.check(plain->inside(p) == coherent->inside(p), "inside", p);
          continue;
        }
        const DistanceResult x = plain->distance(p), y = coherent->distance(p);
        if (exact) {
          distance.check(x.distance == y.distance, "distance", p);
          closest.check(x.closest == y.closest && x.normal == y.normal, "closest point or normal", p);
          triangle.check(x.triangle == y.triangle, "triangle", p);
        } else {
          distance.check(std::abs(x.distance - y.distance) <= 1e-12 * diag, "distance", p);
          triangle.check(x.triangle == y.triangle ||
                             (y.triangle >= 0 && std::size_t(y.triangle) < mesh.triangles.size() &&
                              std::abs(distance_to_triangle(ref_mesh, y.triangle, p) - std::abs(x.distance)) <= 1e-9 * diag),
                         "triangle, not a tie", p);
        }
      }
    }
    EXPECT_NONE_FAILED(distance, v.spec);
    EXPECT_NONE_FAILED(closest, v.spec);
    EXPECT_NONE_FAILED(triangle, v.spec);
    EXPECT_NONE_FAILED(inside, v.spec);
  }
}

INSTANTIATE_TEST_SUITE_P(Registered, CoherentVariant,
                         ::testing::Combine(::testing::ValuesIn(coherent_variants()), ::testing::ValuesIn(kMeshes)),
                         VariantMeshName());
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(CoherentVariant);
