// Tests of the out-of-core EBP-Octree (methods/ebp_octree/ebp_store, ebp_cache, ebp_ooc,
// ebp_cli): round trip of the .ebp store, identical answers in memory and from the store (large
// and tiny caches, coherent or not), rejection of corrupt files, clean failure of an interrupted
// build, and the `ebp_octree:store=` method through the registry.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"
#include "methods/ebp_octree/store/crc32c.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/util/errors.hpp"
#include "support/test_support.hpp"

using namespace ebp;
namespace fs = std::filesystem;
using Tris = std::vector<std::array<std::uint32_t, 3>>;

namespace {

std::string shared_mesh(const std::string& name) { return bvhbench::test::shared_mesh_path(name); }

struct TmpDir : bvhbench::test::TmpDir {
  TmpDir() : bvhbench::test::TmpDir("ebp_store_test") {}
};

using bvhbench::test::torus;

Octree build(const bvhbench::Mesh& m) {
  BuildParams bp;
  bp.threads = 1;
  return build_octree(m.vertices, m.triangles, bp);
}

std::string write(const Octree& t, const std::string& path, std::size_t page = 4096) {
  StoreWriteOptions o;
  o.page_target = page;
  o.info_json = R"({"test":true})";
  write_store_atomic(t, path, o);
  return path;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool bits_eq(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool bits_eq(const Vec3d& a, const Vec3d& b) { return bits_eq(a.x, b.x) && bits_eq(a.y, b.y) && bits_eq(a.z, b.z); }

/// Query points: random in the enlarged box, near the vertices, and a smooth path (haptic-like).
std::vector<Vec3d> query_points(const bvhbench::Mesh& m, std::size_t n) {
  std::mt19937_64 rng(7);
  std::vector<Vec3d> q = bvhbench::test::box_and_near_vertex_points(m, n, rng);
  Box3d b;
  for (auto& v : m.vertices) b.add(v);
  const Vec3d e = b.extent();
  q.push_back(m.vertices[0]);  // exactly on the surface
  Vec3d c = (b.lo + b.hi) * 0.5;
  for (std::size_t i = 0; i < n; ++i) {  // a slow walk
    const double t = double(i) / double(n) * 2 * M_PI;
    q.push_back({c.x + 0.45 * e.x * std::cos(t), c.y + 0.45 * e.y * std::sin(2 * t), c.z + 0.3 * e.z * std::sin(t)});
  }
  return q;
}

void expect_same_answers(const Octree& t, const std::string& store, const std::vector<Vec3d>& pts, std::size_t cache,
                         bool coherent, const std::string& what) {
  Query mem(t, coherent);
  OutOfCore ooc(store, cache, coherent, false);
  int bad_inside = 0, bad_dist = 0;
  for (const Vec3d& p : pts) {
    if (mem.inside(p) != ooc.inside(p)) ++bad_inside;
    const DistanceAnswer a = mem.distance(p), b = ooc.distance(p);
    if (!bits_eq(a.distance, b.distance) || !bits_eq(a.closest, b.closest) || !bits_eq(a.normal, b.normal) ||
        a.triangle != b.triangle)
      ++bad_dist;
  }
  EXPECT_EQ(bad_inside, 0) << what;
  EXPECT_EQ(bad_dist, 0) << what;
  if (cache < 4096 && ooc.store().directory().size() > 1) {
    EXPECT_GT(ooc.cache().evictions, 0u) << what;
  }
  EXPECT_GT(ooc.cache().misses, 0u) << what;
}

void check_mesh(const bvhbench::Mesh& m, const std::string& name) {
  const Octree t = build(m);
  TmpDir d;
  const std::string small = write(t, d.file("small.ebp"), 4096);    // many pages, a deep top
  const std::string large = write(t, d.file("large.ebp"), 1 << 26);  // one root page
  {
    StoreReader r(small);
    EXPECT_GT(r.header().num_pages, 4u) << name;
    const Octree back = r.load_all();
    EXPECT_TRUE(same_bytes(back.nodes, t.nodes)) << name;
    EXPECT_TRUE(same_bytes(back.children, t.children)) << name;
    EXPECT_TRUE(same_bytes(back.planes, t.planes)) << name;
    EXPECT_TRUE(same_bytes(back.leaves, t.leaves)) << name;
    EXPECT_TRUE(same_bytes(back.tris, t.tris)) << name;
    EXPECT_EQ(back.leaf_level, t.leaf_level);
    EXPECT_TRUE(bits_eq(back.root_lo, t.root_lo) && bits_eq(back.root_size, t.root_size));
    EXPECT_EQ(r.info_json(), R"({"test":true})");
  }
  {
    StoreReader r(large);
    EXPECT_EQ(r.header().num_pages, 1u);
    const Octree back = r.load_all();
    EXPECT_TRUE(same_bytes(back.nodes, t.nodes) && same_bytes(back.tris, t.tris)) << name;
  }
  const std::vector<Vec3d> pts = query_points(m, 600);
  expect_same_answers(t, small, pts, 256u << 20, false, name + " small pages, large cache");
  expect_same_answers(t, small, pts, 1, false, name + " small pages, 1-byte cache");
  expect_same_answers(t, small, pts, 64 << 10, true, name + " small pages, 64 KiB cache, coherent");
  expect_same_answers(t, large, pts, 1, true, name + " one page, 1-byte cache, coherent");
}

}  // namespace

TEST(EbpStore, Crc32cKnownValue) {
  EXPECT_EQ(crc32c("123456789", 9), 0xE3069283u);  // the standard check value
  EXPECT_EQ(crc32c("", 0), 0u);
}

TEST(EbpStore, ProceduralTorusRoundTripAndSameAnswers) { check_mesh(torus(120, 60), "torus"); }

TEST(EbpStore, SharedClosedMeshesSameAnswers) {
  for (const char* n : {"cow.obj", "fandisk.obj", "homer.obj", "rocker-arm.obj"})
    check_mesh(bvhbench::load_mesh(shared_mesh(n)), n);
}

TEST(EbpStore, OpenMeshSameAnswers) {  // not closed: the answers are still the in-memory ones
  check_mesh(bvhbench::load_mesh(shared_mesh("spot.obj")), "spot.obj");
}

namespace {

std::vector<std::uint8_t> slurp(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}
void spit(const std::string& p, const std::vector<std::uint8_t>& b) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}
void fix_header_crc(std::vector<std::uint8_t>& b) {
  FileHeader h;
  std::memcpy(&h, b.data(), sizeof h);
  h.header_crc = 0;
  h.header_crc = crc32c(&h, sizeof h);
  std::memcpy(b.data(), &h, sizeof h);
}

/// Opens the store and reads every page: must throw InputError whose message names the file and
/// contains `needle`.
void expect_rejected(const std::string& path, const std::string& needle) {
  try {
    StoreReader r(path);
    for (std::uint32_t i = 0; i < r.directory().size(); ++i) (void)r.load_page(i);
    ADD_FAILURE() << "accepted a bad file (" << needle << ")";
  } catch (const bvhbench::InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find(needle), std::string::npos) << "expected '" << needle << "' in: " << m;
  }
}

}  // namespace

TEST(EbpStore, CorruptFilesRejected) {
  const bvhbench::Mesh m = torus(60, 30);
  const Octree t = build(m);
  TmpDir d;
  const std::string good = write(t, d.file("good.ebp"), 4096);
  const std::vector<std::uint8_t> g = slurp(good);
  StoreReader ok(good);
  const FileHeader h = ok.header();
  ASSERT_GT(h.num_pages, 2u);
  const std::string bad = d.file("bad.ebp");
  auto variant = [&](auto&& mutate, const std::string& needle) {
    std::vector<std::uint8_t> b = g;
    mutate(b);
    spit(bad, b);
    expect_rejected(bad, needle);
  };
  variant([](auto& b) { b.resize(100); }, "truncated");
  variant([](auto& b) { b.resize(b.size() - 1); }, "size mismatch");
  variant([&](auto& b) { b.resize(std::size_t(h.pages.offset) + 10); }, "size mismatch");
  variant([](auto& b) { b.clear(); }, "truncated");
  variant([](auto& b) { b[0] = 'X'; }, "bad magic");
  variant([](auto& b) { b[8] = 4; }, "unsupported store version 4");
  variant([](auto& b) { b[8] = 1; }, "store format version 1");  // world coordinates: rebuild
  variant([](auto& b) { b[8] = 2; }, "store format version 2 (64-byte triangle records)");  // rebuild
  variant([](auto& b) { b[40] ^= 0x10; }, "header checksum");
  variant([&](auto& b) { b[std::size_t(h.top_nodes.offset) + 3] ^= 1; }, "checksum mismatch in section 'top nodes'");
  variant([&](auto& b) { b[std::size_t(h.directory.offset) + 5] ^= 1; }, "checksum mismatch in section 'directory'");
  variant([&](auto& b) { b[std::size_t(ok.directory()[1].offset) + 100] ^= 4; }, "page 1: checksum mismatch");
  variant([&](auto& b) {  // a section pointing past the end (header checksum fixed)
    FileHeader x;
    std::memcpy(&x, b.data(), sizeof x);
    x.top_planes.offset = x.file_size + 4096;
    std::memcpy(b.data(), &x, sizeof x);
    fix_header_crc(b);
  }, "outside the file");
  variant([&](auto& b) {  // overlapping sections
    FileHeader x;
    std::memcpy(&x, b.data(), sizeof x);
    x.top_children.offset = x.top_nodes.offset;
    std::memcpy(b.data(), &x, sizeof x);
    fix_header_crc(b);
  }, "overlap");
  variant([&](auto& b) {  // wrong counts
    FileHeader x;
    std::memcpy(&x, b.data(), sizeof x);
    x.num_top_nodes += 1;
    std::memcpy(b.data(), &x, sizeof x);
    fix_header_crc(b);
  }, "section 'top nodes'");
  variant([&](auto& b) {  // a page offset out of range, directory checksum fixed
    FileHeader x;
    std::memcpy(&x, b.data(), sizeof x);
    PageEntry e;
    std::memcpy(&e, b.data() + x.directory.offset + sizeof(PageEntry), sizeof e);
    e.offset = x.file_size * 2;
    std::memcpy(b.data() + x.directory.offset + sizeof(PageEntry), &e, sizeof e);
    x.directory.crc = crc32c(b.data() + x.directory.offset, std::size_t(x.directory.size));
    std::memcpy(b.data(), &x, sizeof x);
    fix_header_crc(b);
  }, "outside the pages section");
  // Random single-byte flips anywhere: rejected or, if in padding, harmless; never a crash.
  std::mt19937 rng(3);
  for (int k = 0; k < 200; ++k) {
    std::vector<std::uint8_t> b = g;
    b[rng() % b.size()] ^= std::uint8_t(1 + rng() % 255);
    spit(bad, b);
    try {
      StoreReader r(bad);
      OutOfCore q(bad, 1 << 20, false, false);
      for (const Vec3d& p : query_points(m, 20)) (void)q.distance(p);
    } catch (const bvhbench::InputError&) {
    }
  }
  // The CLI: `ebp info` on a bad file exits 2 with a message naming the file.
  spit(bad, std::vector<std::uint8_t>(g.begin(), g.begin() + 300));
  const std::string cmd = std::string(BVHBENCH_EXE) + " ebp info " + bad + " 2>" + d.file("err.txt");
  const int rc = std::system(cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  const std::vector<std::uint8_t> err = slurp(d.file("err.txt"));
  EXPECT_NE(std::string(err.begin(), err.end()).find(bad), std::string::npos);
}

TEST(EbpStore, FailedWriteLeavesNothing) {
  const Octree t = build(torus(60, 30));
  TmpDir d;
  const std::string out = d.file("m.ebp");
  StoreWriteOptions o;
  o.page_target = 4096;
  o.before_page = [](std::uint32_t id) {
    if (id == 2) throw std::runtime_error("simulated failure");
  };
  EXPECT_THROW(write_store_atomic(t, out, o), std::runtime_error);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(bvhbench::test::leftover_temporaries(out), std::vector<std::string>{});
  EXPECT_TRUE(fs::is_empty(d.p));
  // Unwritable destination: an error naming it, nothing left.
  EXPECT_THROW(write_store_atomic(t, d.file("no/such/dir/m.ebp"), o), std::runtime_error);
  EXPECT_TRUE(fs::is_empty(d.p));
}

TEST(EbpStore, CliBuildInfoAndInterruptedBuild) {
  TmpDir d;
  const bvhbench::Mesh m = torus(80, 40);
  const std::string mesh = d.file("torus.ply");
  bvhbench::write_ply(mesh, m);
  const std::string exe = BVHBENCH_EXE;
  fs::create_directory(d.p / "tmp");
  // A build that fails midway: non-zero exit, no output, no temporary left.
  const std::string out = d.file("t.ebp");
  int rc = std::system((exe + " --quiet ebp build --mesh " + mesh + " --out " + out + " --memory-budget 64 --tmp " +
                        d.file("tmp") + " --page-kb 4 --fail-after-pages 2 2>" + d.file("err.txt"))
                           .c_str());
  EXPECT_NE(WEXITSTATUS(rc), 0);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(bvhbench::test::leftover_temporaries(out), std::vector<std::string>{});
  EXPECT_TRUE(fs::is_empty(d.p / "tmp"));
  const std::vector<std::uint8_t> err = slurp(d.file("err.txt"));
  EXPECT_NE(std::string(err.begin(), err.end()).find("nothing written"), std::string::npos);
  // A temporary directory that cannot be made: exit 2, nothing written.
  rc = std::system((exe + " --quiet ebp build --mesh " + mesh + " --out " + out + " --memory-budget 64 --tmp " +
                    d.file("nonexistent/dir") + " 2>/dev/null").c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  EXPECT_FALSE(fs::exists(out));
  // A bad mesh: exit 2, nothing written.
  spit(d.file("bad.ply"), {'p', 'l', 'y', '\n', 'x'});
  rc = std::system((exe + " --quiet ebp build --mesh " + d.file("bad.ply") + " --out " + out +
                    " --memory-budget 64 2>/dev/null").c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  EXPECT_FALSE(fs::exists(out));
  // A good build, then info.
  rc = std::system((exe + " --quiet ebp build --mesh " + mesh + " --out " + out + " --memory-budget 64 --tmp " +
                    d.file("tmp") + " --page-kb 4 --json >" + d.file("build.json"))
                       .c_str());
  ASSERT_EQ(WEXITSTATUS(rc), 0);
  EXPECT_TRUE(fs::exists(out));
  EXPECT_TRUE(fs::is_empty(d.p / "tmp"));
  const auto bj = nlohmann::json::parse(slurp(d.file("build.json")));
  EXPECT_EQ(bj["triangles"].get<std::size_t>(), m.num_triangles());
  rc = std::system((exe + " ebp info --json " + out + " >" + d.file("info.json")).c_str());
  ASSERT_EQ(WEXITSTATUS(rc), 0);
  const auto ij = nlohmann::json::parse(slurp(d.file("info.json")));
  EXPECT_EQ(ij["triangles"].get<std::size_t>(), m.num_triangles());
  EXPECT_GT(ij["pages"]["count"].get<std::size_t>(), 1u);

  // The method through the registry: same answers as the in-memory method.
  const bvhbench::Mesh loaded = bvhbench::load_mesh(mesh);
  const auto& reg = bvhbench::Registry::global();
  auto mem = reg.create("ebp_octree");
  auto ooc = reg.create("ebp_octree:store=" + out + ",cache_mb=1,coherent=true");
  bvhbench::BuildContext ctx;
  mem->build(loaded, ctx);
  ooc->build(loaded, ctx);
  for (const Vec3d& p : query_points(loaded, 200)) {
    EXPECT_EQ(mem->inside(p), ooc->inside(p));
    const auto a = mem->distance(p), b = ooc->distance(p);
    EXPECT_TRUE(bits_eq(a.distance, b.distance) && bits_eq(a.closest, b.closest) && a.triangle == b.triangle);
  }
  std::uint64_t misses = 0;
  for (const auto& c : ooc->counters())
    if (c.name == "cache_misses") misses = c.value;
  EXPECT_GT(misses, 0u);
  // A store built from another mesh is refused.
  auto other = reg.create("ebp_octree:store=" + out);
  EXPECT_THROW(other->build(torus(10, 10), ctx), bvhbench::InputError);
}
