// The coherent distance's certificate and chained sign (core/certificate.hpp): answers bit for
// bit those of the branch and bound without them (and of brute force, by the lexicographic
// (squared distance, input index) rule), in memory and out of core, on real meshes along the
// harness's haptic paths, on grazing paths (through vertices, along edges, on octree cell
// boundaries) and on stress meshes; the AVX2 and scalar pre-test kernels agree lane for lane.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/core/query_set.hpp"
#include "harness/io/mesh_io.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/core/certificate.hpp"
#include "methods/ebp_octree/core/certificate_scan.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

using namespace ebp_test;

namespace {

bool bits_eq(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool bits_eq(const Vec3d& a, const Vec3d& b) { return bits_eq(a.x, b.x) && bits_eq(a.y, b.y) && bits_eq(a.z, b.z); }

/// Where two answers differ ("" when they are the same bit for bit, sign and -0 included).
std::string differs(const DistanceAnswer& a, const DistanceAnswer& b) {
  if (!bits_eq(a.distance, b.distance)) return "distance";
  if (a.triangle != b.triangle) return "triangle";
  if (!bits_eq(a.closest, b.closest)) return "closest";
  if (!bits_eq(a.normal, b.normal)) return "normal";
  return "";
}

/// The brute-force lexicographic minimum of (squared distance, index) on the float geometry.
struct Brute {
  double d2 = std::numeric_limits<double>::infinity();
  std::int64_t tri = -1;
  Vec3d closest;
};
Brute brute(const Reference& ref, const Vec3d& p) {
  Brute b;
  for (std::size_t i = 0; i < ref.f.size(); ++i) {
    const Vec3d c = bvhbench::closest_point_on_triangle(p, ref.v[ref.f[i][0]], ref.v[ref.f[i][1]], ref.v[ref.f[i][2]]);
    const double d2 = squared_norm(c - p);
    if (d2 < b.d2) { b.d2 = d2; b.tri = std::int64_t(i); b.closest = c; }
  }
  return b;
}

/// Along `path`: the coherent query with certificate and chained sign (`cert`, the default; the
/// sign from the closest face only if `face_sign`, so that the chained sign is what gives the
/// signs it does not) against the same without any (`plain`), answer by answer; optionally
/// against brute force. Returns the certified query's counters.
QueryCounters expect_certified_path(const Octree& t, const std::vector<Vec3d>& path, const std::string& what,
                                    const Reference* ref = nullptr, ScanKernel kernel = best_scan_kernel(),
                                    bool face_sign = false) {
  Query cert(t, true), plain(t, true);
  cert.set_scan_kernel(kernel);
  cert.set_adaptive_certificate(false);  // the certificate at every renewal: it is what is tested
  cert.set_face_sign(face_sign);
  plain.set_certificate(false);
  plain.set_chained_sign(false);
  plain.set_face_sign(false);
  for (std::size_t i = 0; i < path.size(); ++i) {
    const DistanceAnswer a = cert.distance(path[i]), b = plain.distance(path[i]);
    const std::string d = differs(a, b);
    EXPECT_EQ(d, "") << what << " query " << i;
    if (!d.empty()) break;
    if (ref) {
      const Brute w = brute(*ref, path[i]);
      EXPECT_EQ(a.triangle, w.tri) << what << " query " << i;
      EXPECT_TRUE(bits_eq(std::fabs(a.distance), std::sqrt(w.d2))) << what << " query " << i;
      EXPECT_TRUE(bits_eq(a.closest, w.closest)) << what << " query " << i;
      if (a.triangle != w.tri) break;
    }
  }
  return cert.counters;
}

/// The harness's haptic path of n points on `m` (seed 1), as `bvhbench queries --kind haptic`.
std::vector<Vec3d> haptic(const Mesh& m, std::size_t n) {
  nlohmann::json meta;
  return bvhbench::generate_queries(m, "haptic", n, 1, {}, &meta);
}

/// A path of small steps through given waypoints (`per` points per leg, ends included).
std::vector<Vec3d> through(const std::vector<Vec3d>& way, int per) {
  std::vector<Vec3d> out;
  for (std::size_t i = 0; i + 1 < way.size(); ++i)
    for (int k = 0; k < per; ++k) out.push_back(way[i] + (way[i + 1] - way[i]) * (double(k) / per));
  out.push_back(way.back());
  return out;
}

}  // namespace

// The harness's haptic paths on the shared meshes: bit-identical answers, and the certificate
// and chained sign actually serve most queries; with the sign from the closest face, that gives
// most signs, from the certificate's answers too.
TEST(EbpCertificate, HapticPathsOnRealMeshesAreBitIdentical) {
  for (const char* name : {"cow.obj", "fandisk.obj", "rocker-arm.obj", "stanford-bunny.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    const auto path = haptic(m, 3000);
    const QueryCounters c = expect_certified_path(t, path, name);
    EXPECT_GT(c.certificate_renewals, 0u) << name;
    EXPECT_GT(c.certificate_served, path.size() / 2) << name;
    if (t.closed) {
      EXPECT_GT(c.signs_chained, path.size() / 2) << name;
    }
    const QueryCounters f = expect_certified_path(t, path, name, nullptr, best_scan_kernel(), true);
    if (t.closed) {
      EXPECT_GT(f.signs_from_face, path.size() / 2) << name;
    }
  }
}

// The chained sign holds where the open balls about the previous point and the current one, of
// their distances less the rounding bound, cover the step between them: no surface there, so the
// same winding number at both ends.
TEST(EbpCertificate, TheChainedSignHoldsWhereTheTwoEmptyBallsCoverTheStep) {
  CertifiedPath path;
  path.reset();
  bool in = false;
  EXPECT_FALSE(path.sign_chained({0, 0, 0}, 1.0, 0.0, &in)) << "nothing answered yet";
  path.answered({0, 0, 0}, 1.0, true);
  EXPECT_TRUE(path.sign_chained({0.9, 0, 0}, 0.0, 0.0, &in)) << "inside the previous ball alone";
  EXPECT_TRUE(in);
  EXPECT_TRUE(path.sign_chained({1.7, 0, 0}, 0.8, 0.0, &in)) << "the two balls cover the step";
  EXPECT_FALSE(path.sign_chained({1.9, 0, 0}, 0.8, 0.0, &in)) << "a gap between the balls";
  EXPECT_FALSE(path.sign_chained({1.7, 0, 0}, 0.8, 0.05, &in)) << "each ball less twice the rounding bound";
  path.answered({0, 0, 0}, 0.0, false);  // a point on the surface chains nothing
  EXPECT_FALSE(path.sign_chained({0.5, 0, 0}, 0.5, 0.0, &in));  // its distance is at most the step
}

// The harness's contact paths (a probe sliding within +-0.2 mm, crossing the surface again and
// again, at 0.1 and 0.3 m/s): bit-identical answers, the sign chained on many queries.
TEST(EbpCertificate, ContactPathsAreBitIdentical) {
  for (const char* name : {"cow.obj", "stanford-bunny.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    for (const double speed : {0.1, 0.3}) {
      nlohmann::json meta;
      const auto path = bvhbench::generate_queries(m, "contact", 3000, 1, {{"band_mm", 0.2}, {"slide_speed", speed}}, &meta);
      const QueryCounters c = expect_certified_path(t, path, std::string(name) + " contact");
      const QueryCounters f =
          expect_certified_path(t, path, std::string(name) + " contact, face sign", nullptr, best_scan_kernel(), true);
      if (t.closed) {
        EXPECT_GT(c.signs_chained, path.size() / 4) << name << " " << speed;
        EXPECT_GT(f.signs_from_face, path.size() / 2) << name << " " << speed;
      }
    }
  }
}

// The choice between certificates and plain searches (certificate_policy auto, the default): on
// a slide (the harness's haptic path) certificates answer most queries; on a path that jumps
// between two far places at every query, every certificate is lost at once, and plain streaks
// answer most queries with a fraction of the renewals that a certificate at every renewal makes;
// the answers are the plain search's either way, and the choice, made on counters, is the same
// pass after pass.
TEST(EbpCertificate, AutoPolicyUsesCertificatesWhereTheyPay) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  {
    const auto slide = haptic(m, 3000);
    Query q(t, true);
    for (const Vec3d& p : slide) q.distance(p);
    EXPECT_GT(q.counters.certificate_served, slide.size() * 8 / 10);
  }
  const Reference ref(m.vertices, m.triangles);
  const Vec3d a = ref.v[ref.f[0][0]], b = ref.v[ref.f[ref.f.size() / 2][1]];
  const double cell = t.cell_size(t.leaf_level);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.05 * cell, 0.05 * cell);
  std::vector<Vec3d> jumps;
  for (int i = 0; i < 2000; ++i) jumps.push_back((i % 2 ? a : b) + Vec3d(u(rng), u(rng), u(rng)));
  Query autop(t, true), always(t, true), plain(t, true);
  always.set_adaptive_certificate(false);
  plain.set_certificate(false);
  QueryCounters first;
  for (int pass = 0; pass < 2; ++pass) {
    autop.reset_path();
    autop.counters = {};
    always.reset_path();
    plain.reset_path();
    for (std::size_t i = 0; i < jumps.size(); ++i) {
      const DistanceAnswer x = autop.distance(jumps[i]), y = always.distance(jumps[i]), z = plain.distance(jumps[i]);
      ASSERT_EQ(differs(x, z), "") << "auto, query " << i;
      ASSERT_EQ(differs(y, z), "") << "always, query " << i;
    }
    if (pass == 0) {
      first = autop.counters;
      EXPECT_LT(autop.counters.certificate_renewals * 4, always.counters.certificate_renewals);
      EXPECT_GT(always.counters.certificate_renewals, jumps.size() / 2);
    } else {
      EXPECT_EQ(autop.counters.certificate_renewals, first.certificate_renewals);
      EXPECT_EQ(autop.counters.triangles_tested, first.triangles_tested);
      EXPECT_EQ(autop.counters.planes_tested, first.planes_tested);
    }
  }
}

// Uniform random points are jumps, not a path: a coherent query (default policy) neither seeds
// its search from the previous answer nor renews a certificate there, so it does the work of a
// search without coherence (a trial certificate over a jump collects a ball of the jump's size:
// it cost over 10x a plain search's planes a query on the 1M bunny), in memory and out of core,
// with the same answers.
TEST(EbpCertificate, RandomPointsCostWhatPlainSearchesDo) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  BuildParams bp;
  bp.threads = 1;
  const Octree t = build_octree(m.vertices, m.triangles, bp);
  nlohmann::json meta;
  const auto points = bvhbench::generate_queries(m, "random", 2000, 1, {}, &meta);
  bvhbench::test::TmpDir d("ebp_jump_test");
  StoreWriteOptions o;
  o.page_target = 4096;
  write_store_atomic(t, d.file("c.ebp"), o);
  Query coherent(t, true), plain(t, false);
  OutOfCore ooc_coherent(d.file("c.ebp"), 64 << 20, true, false), ooc_plain(d.file("c.ebp"), 64 << 20, false, false);
  for (const Vec3d& p : points) {
    const DistanceAnswer a = coherent.unsigned_distance(p), b = plain.unsigned_distance(p);
    ASSERT_EQ(differs(a, b), "");
    ASSERT_EQ(differs(ooc_coherent.unsigned_distance(p), b), "");
    ASSERT_EQ(differs(ooc_plain.unsigned_distance(p), b), "");
  }
  EXPECT_EQ(coherent.counters.certificate_renewals, 0u);
  EXPECT_EQ(ooc_coherent.counters().certificate_renewals, 0u);
  // (the near set's gathering attempts, which fail at once on a jump's box, count a few planes)
  EXPECT_LT(double(coherent.counters.planes_tested), 1.05 * double(plain.counters.planes_tested));
  EXPECT_LT(double(coherent.counters.triangles_tested), 1.05 * double(plain.counters.triangles_tested));
  EXPECT_LT(double(ooc_coherent.counters().triangles_tested), 1.05 * double(ooc_plain.counters().triangles_tested));
}

// Grazing paths in small steps: through vertices exactly, along edges, in a face's plane, on
// the octree's leaf-cell boundary planes, against brute force and the plain branch and bound.
TEST(EbpCertificate, GrazingPathsAreExact) {
  for (const char* name : {"cow.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    const Reference ref(m.vertices, m.triangles);
    const double cell = t.cell_size(t.leaf_level);
    std::mt19937_64 rng(3);
    std::vector<Vec3d> way;
    for (int leg = 0; leg < 12; ++leg) {
      const auto& f = ref.f[rng() % ref.f.size()];
      const Vec3d a = ref.v[f[0]], b = ref.v[f[1]], c = ref.v[f[2]];
      const Vec3d n = bvhbench::triangle_normal(a, b, c);
      way.push_back(a + n * (0.3 * cell));  // off the surface, then exactly onto a vertex
      way.push_back(a);
      way.push_back(b);  // along an edge
      way.push_back((a + b + c) / 3.0);  // across the face, in its plane
      way.push_back(c - n * (0.2 * cell));  // through it
    }
    std::vector<Vec3d> path = through(way, 25);
    // On a leaf-cell boundary plane (x fixed on the grid), sliding in y.
    const Vec3d s = ref.v[ref.f[0][0]];
    const double x0 = t.root_lo.x + std::round((s.x - t.root_lo.x) / cell) * cell;
    for (int k = 0; k < 300; ++k) path.push_back({x0, s.y + (k - 150) * 0.01 * cell, s.z});
    const QueryCounters c = expect_certified_path(t, path, std::string(name) + " grazing", &ref);
    EXPECT_GT(c.certificate_served, path.size() / 4) << name;
  }
}

// Stress meshes (open, degenerate and duplicated triangles, a thin sheet, nested shells, one
// triangle): the certified path gives brute force's answers and the plain path's.
TEST(EbpCertificate, StressMeshesAreExact) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  meshes.push_back({"open cup", bvhbench::test::open_cup()});
  meshes.push_back({"open torus", bvhbench::test::torus(24, 12, 1.0, 0.35, true)});
  meshes.push_back({"one triangle", bvhbench::test::one_triangle()});
  {
    Mesh m = bvhbench::test::icosphere(3);  // duplicates and zero-area triangles
    const std::size_t n = m.triangles.size();
    for (std::size_t i = 0; i < n; i += 7) m.triangles.push_back(m.triangles[i]);
    for (std::size_t i = 0; i < n; i += 11) m.triangles.push_back({m.triangles[i][0], m.triangles[i][1], m.triangles[i][0]});
    const std::uint32_t v0 = m.triangles[5][0], v1 = m.triangles[5][1];
    m.vertices.push_back((m.vertices[v0] + m.vertices[v1]) * 0.5);  // a collinear sliver on an edge
    m.triangles.push_back({v0, v1, std::uint32_t(m.vertices.size() - 1)});
    meshes.push_back({"duplicates and degenerate", m});
  }
  {
    Mesh m = bvhbench::test::unit_cube();  // a thin sheet: a box 1 x 1 x 1e-4
    for (Vec3d& v : m.vertices) v.z *= 1e-4;
    meshes.push_back({"thin sheet", m});
  }
  {
    Mesh m = bvhbench::test::icosphere(2), in = bvhbench::test::icosphere(2, 0.6);  // nested shells
    const std::uint32_t off = std::uint32_t(m.vertices.size());
    m.vertices.insert(m.vertices.end(), in.vertices.begin(), in.vertices.end());
    for (auto f : in.triangles) m.triangles.push_back({f[0] + off, f[2] + off, f[1] + off});
    meshes.push_back({"nested shells", m});
  }
  {
    Mesh m = bvhbench::test::icosphere(2);  // far from the origin: float geometry relative to it
    for (Vec3d& v : m.vertices) v += Vec3d(1e6, -2e6, 5e5);
    meshes.push_back({"far from the origin", m});
  }
  for (const auto& [name, m] : meshes) {
    const Octree t = build(m);
    // Query works in the tree's frame (Octree::origin: not 0 for the model far from the origin),
    // so the reference and the path are in it too: v - origin is exact in double, and rounding it
    // to float gives the geometry the tree holds.
    std::vector<Vec3d> frame_vertices;
    for (const Vec3d& v : m.vertices) frame_vertices.push_back(t.to_frame(v));
    const Reference ref(frame_vertices, m.triangles);
    const double diag = ref.bounds().diagonal();
    const Vec3d c = (ref.bounds().lo + ref.bounds().hi) * 0.5;
    std::vector<Vec3d> path;
    for (int i = 0; i < 1500; ++i) {  // a slow loop around and through the model
      const double a = 2 * M_PI * i / 1500.0;
      path.push_back(c + Vec3d(0.55 * std::cos(a), 0.45 * std::sin(2 * a), 0.35 * std::sin(3 * a)) * diag);
    }
    for (const Vec3d& v : ref.v) {  // exactly onto a vertex and off it again
      path.push_back(v + Vec3d(1e-3, 0, 0) * diag);
      path.push_back(v);
      path.push_back(v + Vec3d(0, 1e-3, 0) * diag);
      if (path.size() > 1700) break;
    }
    const QueryCounters k = expect_certified_path(t, path, name, &ref);
    EXPECT_GT(k.certificate_served, 0u) << name;
  }
}

// The scalar kernel (forced) and the run-time choice give the same answers and the same work
// counters; the kernels agree lane for lane on random packs and points.
TEST(EbpCertificate, ScalarAndAvx2KernelsAgree) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("rocker-arm.obj"));
  const Octree t = build(m);
  const auto path = haptic(m, 2000);
  const QueryCounters a = expect_certified_path(t, path, "scalar", nullptr, ScanKernel::scalar);
  const QueryCounters b = expect_certified_path(t, path, "best", nullptr, best_scan_kernel());
  EXPECT_EQ(a.planes_tested, b.planes_tested);
  EXPECT_EQ(a.triangles_tested, b.triangles_tested);
  EXPECT_EQ(a.certificate_served, b.certificate_served);
  if (best_scan_kernel() != ScanKernel::avx2) GTEST_SKIP() << "this CPU has no AVX2: the scalar kernel only";
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<float> U(-2, 2);
  const std::uint32_t blocks = 64;
  std::vector<float> pack(blocks * kScanRows * kScanLanes);
  std::vector<std::uint8_t> ma(blocks), mb(blocks);
  int set = 0;
  for (int trial = 0; trial < 200; ++trial) {
    for (float& x : pack) x = U(rng);
    for (std::uint32_t j = 0; j < blocks; ++j)
      for (unsigned i = 0; i < kScanLanes; ++i) {
        pack[(j * kScanRows + 16) * kScanLanes + i] = std::fabs(U(rng)) * 0.5f;
        pack[(j * kScanRows + 17) * kScanLanes + i] = trial % 7 == 0 && i == 3 ? -INFINITY : std::fabs(U(rng)) * 0.5f;
      }
    const float q[3] = {U(rng), U(rng), U(rng)};
    const float u2 = std::fabs(U(rng)) * 2;
    scan_lower_bounds(ScanKernel::scalar, pack.data(), blocks, q, u2, ma.data());
    scan_lower_bounds(ScanKernel::avx2, pack.data(), blocks, q, u2, mb.data());
    ASSERT_EQ(ma, mb) << trial;
    for (auto x : ma) set += __builtin_popcount(x);
  }
  EXPECT_GT(set, 1000);  // both outcomes occur
}

// The certificate alone, on a soup of random, sliver and zero-area triangles far from the
// origin: every point of its ball gets brute force's answer from S.
TEST(EbpCertificate, ServesTheBruteForceMinimumInItsBall) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> U(-1, 1);
  const Vec3d far(3e5, -1e5, 2e5);
  Mesh m;
  for (int i = 0; i < 300; ++i) {
    const Vec3d a = far + Vec3d(U(rng), U(rng), U(rng));
    Vec3d b = a + Vec3d(U(rng), U(rng), U(rng)) * 0.2, c = a + Vec3d(U(rng), U(rng), U(rng)) * 0.2;
    if (i % 5 == 1) c = a + (b - a) * 0.5 + Vec3d(1e-9, 0, 0);  // sliver
    if (i % 5 == 2) c = b;                                      // zero area
    const std::uint32_t k = std::uint32_t(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {a, b, c});
    m.triangles.push_back({k, k + 1, k + 2});
  }
  const Reference ref(m.vertices, m.triangles);
  std::uint64_t tested = 0, scanned = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Vec3d p = far + Vec3d(U(rng), U(rng), U(rng)) * 1.2;
    DistanceCertificate cert;
    if (trial % 2) cert.set_kernel(ScanKernel::scalar);
    const double r = 0.05 * (1 + trial % 4);
    cert.begin(p, r, 0.1 * r, certificate_tol(p, far, 4.0));
    for (std::size_t i = 0; i < ref.f.size(); ++i) {  // offer everything (the radius then trims)
      LeafTri lt{};
      const Vec3d v[3] = {ref.v[ref.f[i][0]], ref.v[ref.f[i][1]], ref.v[ref.f[i][2]]};
      for (int k = 0; k < 3; ++k) { lt.a[k] = float(v[0][k]); lt.b[k] = float(v[1][k]); lt.c[k] = float(v[2][k]); }
      const Vec3d cp = bvhbench::closest_point_on_triangle(p, v[0], v[1], v[2]);
      cert.offer(squared_norm(cp - p), cp, i, lt, TriangleSite{});
    }
    CertifiedHit h;
    ASSERT_TRUE(cert.finish(&h));
    ASSERT_EQ(std::int64_t(h.key), brute(ref, p).tri);
    ASSERT_LT(cert.size(), ref.f.size());
    QueryCounters qc;
    for (int k = 0; k < 60; ++k) {
      Vec3d d(U(rng), U(rng), U(rng));
      const Vec3d q = p + d * (cert.r() / (norm(d) * (k % 3 == 0 ? 1.0 : 2.0)) * 0.999999);
      ASSERT_TRUE(cert.covers(q));
      const CertifiedHit x = cert.serve(q, qc);
      const Brute w = brute(ref, q);
      ASSERT_EQ(std::int64_t(x.key), w.tri) << trial << " " << k;
      ASSERT_TRUE(bits_eq(x.d2, w.d2)) << trial << " " << k;
      ASSERT_TRUE(bits_eq(x.closest, w.closest)) << trial << " " << k;
    }
    tested += qc.triangles_tested;
    scanned += 60u * cert.size();
  }
  EXPECT_LT(tested * 2, scanned);  // the pre-test prunes
}

// Out of core (a store of many pages): the certified path gives the in-memory certified path's
// answers and the plain ones, bit for bit, with a cache small enough to evict; the certificate's
// counters are the same pass after pass.
TEST(EbpCertificate, OutOfCoreIsBitIdentical) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("fandisk.obj"));
  BuildParams bp;
  bp.threads = 1;
  const Octree t = build_octree(m.vertices, m.triangles, bp);
  bvhbench::test::TmpDir d("ebp_cert_test");
  StoreWriteOptions o;
  o.page_target = 4096;
  write_store_atomic(t, d.file("f.ebp"), o);
  const auto path = haptic(m, 2000);
  Query mem(t, true);
  OutOfCore ooc(d.file("f.ebp"), 64 << 10, true, false), plain(d.file("f.ebp"), 64 << 10, true, false);
  plain.set_certificate(false);
  plain.set_chained_sign(false);
  QueryCounters first;
  for (int pass = 0; pass < 2; ++pass) {
    mem.reset_path();
    ooc.reset_path();
    plain.reset_path();
    ooc.reset_counters();
    for (std::size_t i = 0; i < path.size(); ++i) {
      const DistanceAnswer a = mem.distance(path[i]), b = ooc.distance(path[i]), c = plain.distance(path[i]);
      ASSERT_EQ(differs(a, b), "") << "pass " << pass << " query " << i;
      ASSERT_EQ(differs(b, c), "") << "pass " << pass << " query " << i;
    }
    const QueryCounters k = ooc.counters();
    EXPECT_GT(k.certificate_served, path.size() / 2);
    EXPECT_GT(k.signs_chained, path.size() / 2);
    if (pass == 0) {
      first = k;
    } else {
      EXPECT_EQ(k.certificate_renewals, first.certificate_renewals);
      EXPECT_EQ(k.certificate_served, first.certificate_served);
      EXPECT_EQ(k.signs_chained, first.signs_chained);
    }
  }
  EXPECT_GT(ooc.cache().evictions, 0u);
}
