// The EBP-Octree far from the origin (octree.hpp, "The frame"): a model 1e6 or 1e7 from the
// origin keeps its own precision, because the structure stores float(v - origin). Inside and
// distance, in memory (through the registry, as the harness runs it) and out of core (the store
// written from memory and the external build, from arrays and from a file), against an exact brute force in double on the very
// vertices the structure holds; the frame chosen for ordinary models is the origin (nothing
// changes for them); a store of the older format (world coordinates) is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"
#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/build/external_build.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/store/crc32c.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

using namespace ebp;
namespace fs = std::filesystem;

namespace {

struct TmpDir : bvhbench::test::TmpDir {
  TmpDir() : bvhbench::test::TmpDir("ebp_far_test") { fs::create_directory(p / "runs"); }
  std::string runs() const { return (p / "runs").string(); }
};

/// `m` moved by `offset` (each coordinate a multiple of a large power of two), with every vertex
/// made exactly offset + a float: then the structure's float(v - origin) is that float, and the
/// brute force below, in double on these vertices, answers for exactly the structure's geometry.
bvhbench::Mesh far_copy(const bvhbench::Mesh& m, double offset) {
  bvhbench::Mesh f = m;
  for (Vec3d& v : f.vertices)
    for (int k = 0; k < 3; ++k) v[k] = offset + double(float(v[k]));
  return f;
}

/// Exact-enough reference in double: winding number (inside iff >= 1/2) and distance.
struct Brute {
  const bvhbench::Mesh& m;
  bool inside(const Vec3d& p) const {
    double w = 0;
    for (const auto& t : m.triangles)
      w += bvhbench::triangle_winding(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]);
    return w > 0.5;
  }
  double distance(const Vec3d& p) const {
    double best = 1e300;
    for (const auto& t : m.triangles)
      best = std::min(best, squared_norm(bvhbench::closest_point_on_triangle(p, m.vertices[t[0]], m.vertices[t[1]],
                                                                           m.vertices[t[2]]) - p));
    return std::sqrt(best);
  }
  double tri_distance(const Vec3d& p, std::int64_t i) const {
    const auto& t = m.triangles[std::size_t(i)];
    return norm(bvhbench::closest_point_on_triangle(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]) - p);
  }
};

/// Random points in the box grown by 10 %, and near the surface (within 1 % of the diagonal).
std::vector<Vec3d> points(const bvhbench::Mesh& m, std::size_t n) {
  std::mt19937_64 rng(5);
  return bvhbench::test::box_and_near_vertex_points(m, n, rng);
}

/// What a query answered, in world coordinates.
struct Answers {
  std::vector<char> inside;
  std::vector<bvhbench::DistanceResult> distance;
};

/// Checks `a` against the brute force: inside exactly; distance, the closest point's distance and
/// the answered triangle's distance within 1e-9 of the model's size plus 1e-13 of its distance
/// from the origin (the brute force's own double rounding there: ~20 ulps of 1e6 seen; float
/// world coordinates would be off by 1e-2). Points within 1e-7 of the size of the surface are
/// skipped for inside (the winding number's own rounding).
void expect_exact(const bvhbench::Mesh& m, const std::vector<Vec3d>& pts, const Answers& a, const std::string& what) {
  const Brute bf{m};
  Box3d b;
  for (const Vec3d& v : m.vertices) b.add(v);
  const double size = b.diagonal();
  const double tol = 1e-9 * size + 1e-13 * std::max({std::fabs(b.lo.x), std::fabs(b.lo.y), std::fabs(b.lo.z)});
  int bad_inside = 0, bad_distance = 0, checked_inside = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const double d = bf.distance(pts[i]);
    if (d > 1e-7 * size) {
      ++checked_inside;
      if (bool(a.inside[i]) != bf.inside(pts[i])) ++bad_inside;
    }
    const bvhbench::DistanceResult& r = a.distance[i];
    const bool in = bool(a.inside[i]);
    if (std::fabs(std::fabs(r.distance) - d) > tol || (d > 0 && (r.distance < 0) != in) ||
        std::fabs(norm(r.closest - pts[i]) - d) > tol || std::fabs(bf.tri_distance(pts[i], r.triangle) - d) > tol)
      ++bad_distance;
  }
  EXPECT_EQ(bad_inside, 0) << what << " (" << checked_inside << " inside queries)";
  EXPECT_EQ(bad_distance, 0) << what;
  EXPECT_GT(checked_inside, int(pts.size() * 3 / 4)) << what;
}

Answers in_memory(const bvhbench::Mesh& m, const std::vector<Vec3d>& pts, const std::string& spec) {
  auto method = bvhbench::Registry::global().create(spec);
  bvhbench::BuildContext ctx;
  method->build(m, ctx);
  method->reset_path();
  Answers a;
  for (const Vec3d& p : pts) {
    a.inside.push_back(method->inside(p));
    a.distance.push_back(method->distance(p));
  }
  return a;
}

Answers out_of_core(const std::string& store, const std::vector<Vec3d>& pts, bool coherent) {
  OutOfCore ooc(store, 64 << 10, coherent, false);
  Answers a;
  for (const Vec3d& p : pts) {
    a.inside.push_back(ooc.inside(p));
    const DistanceAnswer d = ooc.distance(p);
    bvhbench::DistanceResult r;
    r.distance = d.distance;
    r.closest = d.closest;
    r.normal = d.normal;
    r.triangle = d.triangle;
    a.distance.push_back(r);
  }
  return a;
}

bool same_answers(const Answers& a, const Answers& b) {
  if (a.inside != b.inside || a.distance.size() != b.distance.size()) return false;
  for (std::size_t i = 0; i < a.distance.size(); ++i) {
    const auto &x = a.distance[i], &y = b.distance[i];
    if (std::memcmp(&x.distance, &y.distance, sizeof(double)) != 0 || std::memcmp(&x.closest, &y.closest, sizeof(Vec3d)) != 0 ||
        x.triangle != y.triangle)
      return false;
  }
  return true;
}

void check_far(const bvhbench::Mesh& base, double offset, const std::string& name) {
  const bvhbench::Mesh m = far_copy(base, offset);
  const std::vector<Vec3d> pts = points(m, 150);
  BuildParams bp;
  bp.threads = 2;
  const Octree t = build_octree(m.vertices, m.triangles, bp);
  EXPECT_NE(t.origin, Vec3d(0, 0, 0)) << name;
  EXPECT_LT(norm(t.root_centre), 8 * t.root_size) << name << ": the geometry is near the frame's origin";

  const Answers mem = in_memory(m, pts, "ebp_octree");
  expect_exact(m, pts, mem, name + " in memory");
  const Answers coh = in_memory(m, pts, "ebp_octree:coherent=true");
  EXPECT_TRUE(same_answers(mem, coh)) << name << " coherent";

  TmpDir d;
  StoreWriteOptions wo;
  wo.page_target = 4096;
  wo.params = bp;
  const std::string written = d.file("mem.ebp"), external = d.file("ext.ebp");
  write_store_atomic(t, written, wo);
  ExtBuildOptions eo;
  eo.params = bp;
  eo.page_target = 4096;
  eo.tmp_dir = d.runs();
  auto src = make_memory_source(m.vertices, m.triangles);
  build_store_external(*src, external, eo);
  const FileHeader h = StoreReader(external).header();
  EXPECT_EQ(Vec3d(h.origin[0], h.origin[1], h.origin[2]), t.origin) << name;
  // From a file (OBJ with every digit of the doubles): the file source reads the vertices twice
  // (the second time as float(v - origin)); the same store.
  const std::string obj = d.file("far.obj"), from_file = d.file("file.ebp");
  {
    std::ofstream o(obj);
    char line[128];
    for (const Vec3d& v : m.vertices) {
      std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", v.x, v.y, v.z);
      o << line;
    }
    for (const auto& f : m.triangles) o << "f " << f[0] + 1 << ' ' << f[1] + 1 << ' ' << f[2] + 1 << '\n';
  }
  auto file_src = open_mesh_source(obj);
  build_store_external(*file_src, from_file, eo);
  {
    StoreReader a(written), b(from_file);
    EXPECT_EQ(std::memcmp(a.header().origin, b.header().origin, sizeof h.origin), 0) << name;
    ASSERT_EQ(a.directory().size(), b.directory().size()) << name;
    for (std::size_t i = 0; i < a.directory().size(); ++i)
      EXPECT_EQ(a.directory()[i].crc, b.directory()[i].crc) << name << ": page " << i;
  }
  for (const std::string& store : {written, external, from_file}) {
    const Answers ooc = out_of_core(store, pts, false);
    EXPECT_TRUE(same_answers(mem, ooc)) << name << " out of core, " << store;
    EXPECT_TRUE(same_answers(mem, out_of_core(store, pts, true))) << name << " out of core coherent, " << store;
  }
}

}  // namespace

TEST(EbpFarFromOrigin, OrdinaryModelsKeepTheOrigin) {
  Box3d b;
  b.add({-1, -2, -0.5});
  b.add({3, 1, 2});
  EXPECT_EQ(detail::choose_origin(b), Vec3d(0, 0, 0));
  Box3d off;  // centre 10 sizes away on x only: x moves, y and z stay
  off.add({9.5, -0.5, -0.5});
  off.add({10.5, 0.5, 0.5});
  const Vec3d o = detail::choose_origin(off);
  EXPECT_NE(o.x, 0.0);
  EXPECT_EQ(o.y, 0.0);
  EXPECT_EQ(o.z, 0.0);
  EXPECT_EQ(detail::choose_origin(Box3d{}), Vec3d(0, 0, 0));  // empty
  Box3d point;
  point.add({1e6, 1e6, 1e6});
  const Vec3d po = detail::choose_origin(point);
  EXPECT_LE(std::fabs(po.x - 1e6), 8.0);
  // The built structure of an ordinary model: origin 0, its vertices the input rounded to float.
  const bvhbench::Mesh torus = bvhbench::test::torus(24, 12);
  const Octree t = build_octree(torus.vertices, torus.triangles, BuildParams{});
  EXPECT_EQ(t.origin, Vec3d(0, 0, 0));
  for (const LeafTri& lt : t.tris) {
    const auto& tri = torus.triangles[lt.tri()];
    for (int k = 0; k < 3; ++k) ASSERT_EQ(lt.a[k], float(torus.vertices[tri[0]][k]));
  }
}

TEST(EbpFarFromOrigin, Translated1e6ExactInMemoryAndOutOfCore) {
  check_far(bvhbench::test::torus(48, 24), 1e6, "torus at 1e6");
}

TEST(EbpFarFromOrigin, Translated1e7ExactInMemoryAndOutOfCore) {
  check_far(bvhbench::test::torus(48, 24, 1.0, 0.35, /*open=*/true), 1e7, "open torus at 1e7");
  check_far(bvhbench::test::torus(32, 16), -1e7, "torus at -1e7");
}

TEST(EbpFarFromOrigin, OneTriangleFarOut) {
  bvhbench::Mesh m;
  m.vertices = {{0.1, 0.2, 0.3}, {1.3, 0.1, 0.2}, {0.4, 1.1, 0.7}};
  m.triangles = {{0, 1, 2}};
  const bvhbench::Mesh f = far_copy(m, 1e6);
  const std::vector<Vec3d> pts = points(f, 50);
  const Answers a = in_memory(f, pts, "ebp_octree");
  expect_exact(f, pts, a, "one triangle at 1e6");
}

TEST(EbpFarFromOrigin, OlderStoreFormatRefused) {
  const bvhbench::Mesh m = bvhbench::test::torus(24, 12);
  const Octree t = build_octree(m.vertices, m.triangles, BuildParams{});
  TmpDir d;
  const std::string path = d.file("old.ebp");
  write_store_atomic(t, path, StoreWriteOptions{});
  {  // rewrite the header as version 1 (with a valid checksum): the reader must name the version
    FileHeader h = StoreReader(path).header();
    h.version = 1;
    h.header_crc = 0;
    h.header_crc = crc32c(&h, sizeof h);
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.write(reinterpret_cast<const char*>(&h), sizeof h);
  }
  try {
    StoreReader r(path);
    FAIL() << "a version-1 store was opened";
  } catch (const bvhbench::InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("version 1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("rebuild"), std::string::npos) << msg;
  }
}
