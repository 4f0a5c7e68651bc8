// The external-memory build of the `.ebp` store (build/external_build.hpp; OUT_OF_CORE.md): with tiny
// sort runs (many runs spilled and merged) and small pages (many subtrees cut), the store must be
// the one the in-memory build writes — same header counts, same top tree, same pages byte for
// byte — and answer exactly as the in-memory octree; failures leave neither the store nor
// temporary files.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "methods/ebp_octree/build/external_build.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "harness/core/mesh.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/sha256.hpp"
#include "support/test_support.hpp"

using namespace ebp;
namespace fs = std::filesystem;

namespace {

std::string shared_mesh(const std::string& name) { return bvhbench::test::shared_mesh_path(name); }

struct TmpDir : bvhbench::test::TmpDir {
  TmpDir() : bvhbench::test::TmpDir("ebp_extbuild_test") { fs::create_directory(p / "runs"); }
  std::string runs() const { return (p / "runs").string(); }
};

using bvhbench::test::torus;

bvhbench::Mesh one_triangle() {
  bvhbench::Mesh m;
  m.vertices = {{0.1, 0.2, 0.3}, {1.3, 0.1, 0.2}, {0.4, 1.1, 0.7}};
  m.triangles = {{0, 1, 2}};
  return m;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
bool bits_eq(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool bits_eq(const Vec3d& a, const Vec3d& b) { return bits_eq(a.x, b.x) && bits_eq(a.y, b.y) && bits_eq(a.z, b.z); }

std::vector<std::uint8_t> read_range(const std::string& path, std::uint64_t off, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(off));
  std::vector<std::uint8_t> b(n);
  in.read(reinterpret_cast<char*>(b.data()), std::streamsize(n));
  return b;
}

std::vector<Vec3d> query_points(const bvhbench::Mesh& m, std::size_t n) {
  Box3d b;
  for (auto& v : m.vertices) b.add(v);
  const Vec3d e = b.extent() + Vec3d(1e-3, 1e-3, 1e-3);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-0.1, 1.1), s(-1, 1);
  std::vector<Vec3d> q;
  for (std::size_t i = 0; i < n; ++i) q.push_back({b.lo.x + u(rng) * e.x, b.lo.y + u(rng) * e.y, b.lo.z + u(rng) * e.z});
  const double h = 0.01 * (b.diagonal() + 1e-3);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d& v = m.vertices[rng() % m.vertices.size()];
    q.push_back({v.x + h * s(rng), v.y + h * s(rng), v.z + h * s(rng)});
  }
  return q;
}

ExtBuildOptions tiny_options(const TmpDir& d, std::size_t page = 4096) {
  ExtBuildOptions o;
  o.params.threads = 2;
  o.memory_budget = 1;     // the floor: the build still works
  o.run_bytes = 24 * 97;   // 97 records per sorted run: many runs, a deep merge
  o.page_target = page;
  o.tmp_dir = d.runs();
  o.info_json = [](const ExtBuildReport&) { return std::string(R"({"test":true})"); };
  return o;
}

/// External build with tiny runs == in-memory build written by write_store, and the same answers.
void check_same(const bvhbench::Mesh& m, const std::string& name, std::size_t page = 4096) {
  BuildParams bp;
  bp.threads = 2;
  const Octree t = build_octree(m.vertices, m.triangles, bp);
  TmpDir d;
  StoreWriteOptions wo;
  wo.page_target = page;
  wo.params = bp;
  wo.info_json = R"({"test":true})";
  const std::string mem = d.file("mem.ebp"), ext = d.file("ext.ebp");
  write_store_atomic(t, mem, wo);
  auto src = make_memory_source(m.vertices, m.triangles);
  const ExtBuildReport rep = build_store_external(*src, ext, tiny_options(d, page));
  EXPECT_TRUE(fs::is_empty(d.runs())) << name << ": the sorted runs are removed";
  EXPECT_EQ(bvhbench::test::leftover_temporaries(ext), std::vector<std::string>{}) << name;
  if (t.tris.size() > 200) {
    EXPECT_GT(rep.runs, 1u) << name << ": tiny runs";
  }

  StoreReader a(mem), b(ext);
  const FileHeader &ha = a.header(), &hb = b.header();
  EXPECT_EQ(std::memcmp(ha.origin, hb.origin, sizeof ha.origin), 0) << name;
  EXPECT_EQ(std::memcmp(ha.root_lo, hb.root_lo, sizeof ha.root_lo), 0) << name;
  EXPECT_TRUE(bits_eq(ha.root_size, hb.root_size)) << name;
  EXPECT_EQ(ha.leaf_level, hb.leaf_level) << name;
  EXPECT_EQ(ha.num_triangles, hb.num_triangles) << name;
  EXPECT_EQ(ha.flags, hb.flags) << name << ": closed flag";
  EXPECT_EQ(ha.nodes, hb.nodes) << name;
  EXPECT_EQ(ha.inner, hb.inner) << name;
  EXPECT_EQ(ha.leaves, hb.leaves) << name;
  EXPECT_EQ(ha.white, hb.white) << name;
  EXPECT_EQ(ha.black, hb.black) << name;
  EXPECT_EQ(ha.triangle_refs, hb.triangle_refs) << name;
  EXPECT_EQ(ha.planes, hb.planes) << name;
  EXPECT_EQ(ha.num_pages, hb.num_pages) << name;
  EXPECT_TRUE(same_bytes(a.top_nodes(), b.top_nodes())) << name << ": top nodes";
  EXPECT_TRUE(same_bytes(a.top_children(), b.top_children())) << name << ": top children";
  EXPECT_TRUE(same_bytes(a.top_planes(), b.top_planes())) << name << ": top planes";
  EXPECT_EQ(b.info_json(), R"({"test":true})");
  ASSERT_EQ(a.directory().size(), b.directory().size()) << name;
  std::size_t bad_pages = 0;
  for (std::size_t i = 0; i < a.directory().size(); ++i) {
    const PageEntry &ea = a.directory()[i], &eb = b.directory()[i];
    if (ea.size != eb.size || ea.crc != eb.crc || ea.parent != eb.parent || ea.triangles != eb.triangles ||
        ea.nodes != eb.nodes || read_range(mem, ea.offset, ea.size) != read_range(ext, eb.offset, eb.size))
      ++bad_pages;
  }
  EXPECT_EQ(bad_pages, 0u) << name << ": pages differ";
  // Decoded: the whole tree, as the in-memory one.
  const Octree back = b.load_all();
  EXPECT_TRUE(same_bytes(back.nodes, t.nodes)) << name;
  EXPECT_TRUE(same_bytes(back.children, t.children)) << name;
  EXPECT_TRUE(same_bytes(back.planes, t.planes)) << name;
  EXPECT_TRUE(same_bytes(back.leaves, t.leaves)) << name;
  EXPECT_TRUE(same_bytes(back.tris, t.tris)) << name;
  EXPECT_EQ(rep.stats.nodes, t.stats.nodes) << name;
  EXPECT_EQ(rep.stats.white, t.stats.white) << name;
  EXPECT_EQ(rep.stats.black, t.stats.black) << name;
  EXPECT_EQ(rep.stats.colour_fallbacks, t.stats.colour_fallbacks) << name;
  EXPECT_EQ(rep.stats.degenerate_edges, t.stats.degenerate_edges) << name;
  // Answers: in memory vs the external store, inside and distance, bit for bit.
  Query q(t, false);
  OutOfCore ooc(ext, 64 << 10, false, false);
  int bad_inside = 0, bad_dist = 0;
  for (const Vec3d& p : query_points(m, 300)) {
    if (q.inside(p) != ooc.inside(p)) ++bad_inside;
    const DistanceAnswer x = q.distance(p), y = ooc.distance(p);
    if (!bits_eq(x.distance, y.distance) || !bits_eq(x.closest, y.closest) || !bits_eq(x.normal, y.normal) ||
        x.triangle != y.triangle)
      ++bad_dist;
  }
  EXPECT_EQ(bad_inside, 0) << name;
  EXPECT_EQ(bad_dist, 0) << name;
}

}  // namespace

TEST(EbpExtBuild, TorusSameStoreAsInMemory) { check_same(torus(120, 60), "torus"); }

TEST(EbpExtBuild, SharedMeshesSameStoreAsInMemory) {
  for (const char* n : {"cow.obj", "fandisk.obj", "homer.obj", "rocker-arm.obj"})
    check_same(bvhbench::load_mesh(shared_mesh(n)), n);
}

TEST(EbpExtBuild, OpenMeshesSameStoreAsInMemory) {
  check_same(bvhbench::load_mesh(shared_mesh("spot.obj")), "spot.obj");
  check_same(torus(60, 30, 1.0, 0.35, true), "open torus");
}

TEST(EbpExtBuild, OneTriangleAndOnePage) {
  check_same(one_triangle(), "one triangle");
  {  // degenerate and repeated triangles, an unreferenced vertex
    bvhbench::Mesh m = torus(30, 12);
    m.vertices.push_back({5.0, 5.0, 5.0});
    const std::uint32_t a = m.triangles[0][0], b = m.triangles[0][1];
    m.triangles.push_back({a, a, b});
    m.triangles.push_back(m.triangles[7]);
    m.triangles.push_back({b, a, b});
    check_same(m, "degenerate, repeated, unreferenced");
  }
  check_same(torus(40, 20), "torus, one page", 1 << 26);
}

TEST(EbpExtBuild, StreamedPlySameAsLoaded) {
  // A binary PLY is streamed (vertices as float, faces from the file): same store, same sha256.
  TmpDir d;
  const bvhbench::Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  bvhbench::write_ply(d.file("cow.ply"), m);
  const bvhbench::Mesh loaded = bvhbench::load_mesh(d.file("cow.ply"));
  auto src = open_mesh_source(d.file("cow.ply"));
  EXPECT_TRUE(src->streaming());
  const std::string a = d.file("a.ebp"), b = d.file("b.ebp");
  build_store_external(*src, a, tiny_options(d));
  EXPECT_EQ(src->sha256(), loaded.sha256);
  EXPECT_EQ(src->num_triangles(), loaded.num_triangles());
  auto msrc = make_memory_source(loaded.vertices, loaded.triangles);
  build_store_external(*msrc, b, tiny_options(d));
  const auto fa = read_range(a, 0, std::size_t(fs::file_size(a))), fb = read_range(b, 0, std::size_t(fs::file_size(b)));
  EXPECT_TRUE(fa == fb) << "streamed and in-memory sources give the same file";
  // A truncated PLY: an InputError naming the file, nothing written.
  {
    std::ifstream in(d.file("cow.ply"), std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bytes.resize(bytes.size() - 100);
    std::ofstream(d.file("cut.ply"), std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  }
  auto cut = open_mesh_source(d.file("cut.ply"));
  EXPECT_THROW(build_store_external(*cut, d.file("cut.ebp"), tiny_options(d)), bvhbench::InputError);
  EXPECT_FALSE(fs::exists(d.file("cut.ebp")));
  EXPECT_FALSE(fs::exists(d.file("cut.ebp.tmp")));
  EXPECT_TRUE(fs::is_empty(d.runs()));
}

// Vertices paged from a temporary file (vertex_pages.hpp) instead of held: the same store, byte
// for byte, through a two-page cache that misses all the time; also for a model far from the
// origin, whose vertices are written a second time in the build's frame. The vertex file leaves
// nothing in the temporary directory, and a bad index is still an InputError.
TEST(EbpExtBuild, PagedVerticesGiveTheSameStore) {
  bvhbench::Mesh far = torus(120, 60);
  for (Vec3d& v : far.vertices) v = v + Vec3d(3.0e6, -1.0e6, 2.0e6);
  const std::vector<std::pair<std::string, bvhbench::Mesh>> meshes = {{"torus", torus(120, 60)}, {"far torus", far}};
  for (const auto& [name, m] : meshes) {
    SCOPED_TRACE(name);
    TmpDir d;
    bvhbench::write_ply(d.file("m.ply"), m);
    auto held = open_mesh_source(d.file("m.ply"));
    VertexPaging paging;
    paging.held_limit = 0;
    paging.tmp_dir = d.runs();
    paging.cache_bytes = 1;  // two pages of 2,048 vertices, for 7,200 vertices
    auto paged = open_mesh_source(d.file("m.ply"), paging);
    EXPECT_EQ(paged->origin() != Vec3d(0, 0, 0), name == "far torus");
    EXPECT_TRUE(fs::is_empty(d.runs()));
    const std::string a = d.file("held.ebp"), b = d.file("paged.ebp");
    build_store_external(*held, a, tiny_options(d));
    const ExtBuildReport rep = build_store_external(*paged, b, tiny_options(d));
    EXPECT_EQ(held->vertex_page_reads(), (std::pair<std::uint64_t, std::uint64_t>{0, 0}));
    const auto [reads, misses] = paged->vertex_page_reads();
    EXPECT_GT(misses, 20u);
    EXPECT_GE(reads, 3 * rep.records) << "every record's vertices were read through the pages";
    EXPECT_LT(paged->resident_bytes(), held->resident_bytes());
    const auto fa = read_range(a, 0, std::size_t(fs::file_size(a))), fb = read_range(b, 0, std::size_t(fs::file_size(b)));
    EXPECT_TRUE(fa == fb) << "held and paged vertices give the same file";
    EXPECT_TRUE(fs::is_empty(d.runs()));
  }
  {  // an index out of range, paged: an InputError, nothing written
    TmpDir d;
    bvhbench::Mesh m = torus(30, 12);
    m.triangles[17][1] = std::uint32_t(m.vertices.size() + 5);
    bvhbench::write_ply(d.file("bad.ply"), m);
    VertexPaging paging;
    paging.held_limit = 0;
    paging.tmp_dir = d.runs();
    auto src = open_mesh_source(d.file("bad.ply"), paging);
    EXPECT_THROW(build_store_external(*src, d.file("bad.ebp"), tiny_options(d)), bvhbench::InputError);
    EXPECT_FALSE(fs::exists(d.file("bad.ebp")));
    EXPECT_TRUE(fs::is_empty(d.runs()));
  }
}

TEST(EbpExtBuild, FailuresLeaveNothing) {
  TmpDir d;
  const bvhbench::Mesh m = torus(80, 40);
  const std::string out = d.file("x.ebp");
  // Midway through the pages (the sorted runs exist then).
  {
    auto src = make_memory_source(m.vertices, m.triangles);
    ExtBuildOptions o = tiny_options(d);
    o.before_page = [](std::uint32_t id) {
      if (id == 3) throw std::runtime_error("simulated failure");
    };
    EXPECT_THROW(build_store_external(*src, out, o), std::runtime_error);
    EXPECT_FALSE(fs::exists(out));
    EXPECT_EQ(bvhbench::test::leftover_temporaries(out), std::vector<std::string>{});
    EXPECT_TRUE(fs::is_empty(d.runs()));
  }
  // During the distribution (an interrupt is a throw from `check`).
  {
    auto src = make_memory_source(m.vertices, m.triangles);
    ExtBuildOptions o = tiny_options(d);
    std::atomic<int> calls{0};  // called from the build's threads
    o.check = [&calls] {
      if (++calls == 3) throw std::runtime_error("interrupted");
    };
    EXPECT_THROW(build_store_external(*src, out, o), std::runtime_error);
    EXPECT_FALSE(fs::exists(out));
    EXPECT_EQ(bvhbench::test::leftover_temporaries(out), std::vector<std::string>{});
    EXPECT_TRUE(fs::is_empty(d.runs()));
  }
  // A bad mesh: index out of range.
  {
    bvhbench::Mesh bad = m;
    bad.triangles[100][1] = std::uint32_t(bad.vertices.size());
    auto src = make_memory_source(bad.vertices, bad.triangles);
    EXPECT_THROW(build_store_external(*src, out, tiny_options(d)), std::invalid_argument);
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(fs::is_empty(d.runs()));
  }
  // An unwritable temporary directory: a clear error, nothing written.
  {
    auto src = make_memory_source(m.vertices, m.triangles);
    ExtBuildOptions o = tiny_options(d);
    o.tmp_dir = d.file("missing/dir");
    EXPECT_THROW(build_store_external(*src, out, o), std::runtime_error);
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(EbpExtBuild, StreamedPlyWithPolygonsAndExtraProperties) {
  // Quads and a pentagon (fan-triangulated like load_mesh), double coordinates, an extra vertex
  // property, ushort counts and uint indices: streamed, same triangles and store as loaded.
  TmpDir d;
  const int n = 24;
  std::vector<std::array<double, 3>> v;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double u = 2 * M_PI * i / n, w = 2 * M_PI * j / n;
      v.push_back({(1 + 0.4 * std::cos(w)) * std::cos(u), (1 + 0.4 * std::cos(w)) * std::sin(u), 0.4 * std::sin(w)});
    }
  auto id = [&](int i, int j) { return std::uint32_t(((i + n) % n) * n + (j + n) % n); };
  std::vector<std::vector<std::uint32_t>> faces;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  faces[5] = {faces[5][0], faces[5][1], faces[5][2], faces[5][3], faces[5][0]};  // a degenerate pentagon
  std::string h = "ply\nformat binary_little_endian 1.0\ncomment test\nelement vertex " + std::to_string(v.size()) +
                  "\nproperty double x\nproperty double y\nproperty double z\nproperty uchar flag\nelement face " +
                  std::to_string(faces.size()) + "\nproperty list ushort uint vertex_indices\nend_header\n";
  std::ofstream out(d.file("q.ply"), std::ios::binary);
  out.write(h.data(), std::streamsize(h.size()));
  for (const auto& p : v) {
    out.write(reinterpret_cast<const char*>(p.data()), 24);
    const char flag = 7;
    out.write(&flag, 1);
  }
  for (const auto& f : faces) {
    const std::uint16_t c = std::uint16_t(f.size());
    out.write(reinterpret_cast<const char*>(&c), 2);
    out.write(reinterpret_cast<const char*>(f.data()), std::streamsize(4 * f.size()));
  }
  out.close();
  const bvhbench::Mesh loaded = bvhbench::load_mesh(d.file("q.ply"));
  auto src = open_mesh_source(d.file("q.ply"));
  EXPECT_TRUE(src->streaming());
  const std::string a = d.file("a.ebp"), b = d.file("b.ebp");
  build_store_external(*src, a, tiny_options(d));
  EXPECT_EQ(src->num_triangles(), loaded.num_triangles());
  EXPECT_EQ(src->sha256(), loaded.sha256);
  auto msrc = make_memory_source(loaded.vertices, loaded.triangles);
  build_store_external(*msrc, b, tiny_options(d));
  const auto fa = read_range(a, 0, std::size_t(fs::file_size(a))), fb = read_range(b, 0, std::size_t(fs::file_size(b)));
  EXPECT_TRUE(fa == fb) << "streamed and in-memory sources give the same file";
  // An index out of range in the file: an InputError naming the file.
  {
    std::fstream f(d.file("q.ply"), std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(std::streamoff(h.size() + v.size() * 25 + 2));
    const std::uint32_t bad = std::uint32_t(v.size());
    f.write(reinterpret_cast<const char*>(&bad), 4);
  }
  auto bad = open_mesh_source(d.file("q.ply"));
  EXPECT_THROW(build_store_external(*bad, d.file("c.ebp"), tiny_options(d)), bvhbench::InputError);
  EXPECT_FALSE(fs::exists(d.file("c.ebp")));
  EXPECT_TRUE(fs::is_empty(d.runs()));
}

// Every format streams (vertices as float, triangles re-read per scan): the same mesh written as
// PLY, binary and ASCII STL, OFF, OBJ and a tristrip PLY (restarts, joins, big endian, extra
// vertex properties) gives the same store file, byte for byte (pages, CRCs), as the PLY, which is
// the in-memory build's (check_same). The STL's weld table is resident and counted in the
// build's minimum budget.
TEST(EbpExtBuild, EveryFormatStreamsTheSameStore) {
  for (const char* name : {"cow.obj", "spot.obj"}) {
    SCOPED_TRACE(name);
    TmpDir d;
    const bvhbench::Mesh m = bvhbench::test::stl_canonical(bvhbench::load_mesh(shared_mesh(name)));
    check_same(m, name);
    bvhbench::write_ply(d.file("m.ply"), m);
    std::uint64_t joins = 0;
    const std::pair<const char*, std::string> files[] = {
        {"m.stl", bvhbench::test::stl_binary_bytes(m)},  {"ascii.stl", bvhbench::test::stl_ascii_bytes(m)},
        {"m.off", bvhbench::test::off_bytes(m, "COFF")}, {"m.obj", bvhbench::test::obj_bytes(m)},
        {"strips.ply", bvhbench::test::tristrip_ply_bytes(m, &joins)}};
    auto build = [&](const std::string& file, ExtBuildReport* rep, std::size_t* resident) {
      auto src = open_mesh_source(d.file(file));
      EXPECT_TRUE(src->streaming());
      EXPECT_EQ(src->num_vertices(), m.vertices.size());
      const std::string out = d.file(file + ".ebp");
      *rep = build_store_external(*src, out, tiny_options(d));
      EXPECT_EQ(src->num_triangles(), m.triangles.size());
      EXPECT_EQ(src->sha256(), bvhbench::sha256_file(d.file(file)));
      *resident = src->resident_bytes();
      return read_range(out, 0, std::size_t(fs::file_size(out)));
    };
    ExtBuildReport ply_rep;
    std::size_t ply_resident = 0;
    const auto ply_store = build("m.ply", &ply_rep, &ply_resident);
    for (const auto& [file, bytes] : files) {
      SCOPED_TRACE(file);
      bvhbench::test::write_file_bytes(d.file(file), bytes);
      ExtBuildReport rep;
      std::size_t resident = 0;
      EXPECT_TRUE(build(file, &rep, &resident) == ply_store) << "the same store as from the PLY";
      EXPECT_EQ(rep.min_budget_bytes - resident, ply_rep.min_budget_bytes - ply_resident);
      if (std::string(file).find(".stl") != std::string::npos) {
        EXPECT_GE(resident, ply_resident + 12 * m.vertices.size()) << "the weld table is resident and counted";
      }
    }
    EXPECT_GT(joins, 0u);
    EXPECT_TRUE(fs::is_empty(d.runs()));
  }
}

// A malformed file of any format is an InputError naming it, and nothing is written: problems of
// the vertices when the source opens, problems of the faces at the first scan.
TEST(EbpExtBuild, MalformedFilesOfEveryFormatLeaveNothing) {
  TmpDir d;
  const struct { const char *file, *bytes, *problem; } bad[] = {
      {"v.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "vertex 1 has a NaN coordinate"},
      {"f.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "face 0 has vertex index 7 out of range"},
      {"f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "face 1 has vertex index 9 out of range"},
      {"t.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid t\n",
       "facet 0 has 2 vertices"},
      {"s.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                "element tristrips 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                "4 0 1 2 5\n", "tristrips 0 has vertex index 5 out of range"}};
  for (const auto& [file, bytes, problem] : bad) {
    SCOPED_TRACE(file);
    bvhbench::test::write_file_bytes(d.file(file), bytes);
    const std::string out = d.file(std::string(file) + ".ebp");
    bvhbench::test::expect_input_error(
        [&] {
          auto src = open_mesh_source(d.file(file));
          build_store_external(*src, out, tiny_options(d));
        },
        file, problem);
    EXPECT_FALSE(fs::exists(out));
    EXPECT_EQ(bvhbench::test::leftover_temporaries(out), std::vector<std::string>{});
    EXPECT_TRUE(fs::is_empty(d.runs()));
  }
}

TEST(EbpExtBuild, CliFileSizeLimitLeavesNothing) {
  // "Disk full": a file-size limit (SIGXFSZ ignored, so the write fails with EFBIG) stops the
  // build midway through the pages; the command says so and leaves neither the store nor temp files.
  TmpDir d;
  const std::string out = d.file("x.ebp");
  fs::create_directory(d.p / "tmp");
  const std::string cmd = "sh -c \"trap '' XFSZ; ulimit -f 400; exec " + std::string(BVHBENCH_EXE) +
                          " --quiet ebp build --mesh " + shared_mesh("rocker-arm.obj") + " --out " + out +
                          " --memory-budget 64 --page-kb 4 --tmp " + d.file("tmp") + " 2>" + d.file("err.txt") + "\"";
  const int rc = std::system(cmd.c_str());
  EXPECT_NE(WEXITSTATUS(rc), 0);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(bvhbench::test::leftover_temporaries(out), std::vector<std::string>{});
  EXPECT_TRUE(fs::is_empty(d.p / "tmp"));
  std::ifstream in(d.file("err.txt"));
  const std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(err.find("nothing written"), std::string::npos) << err;
  EXPECT_NE(err.find("File too large"), std::string::npos) << err;
}

// `ebp build` pages the vertices when they would take more than half the budget, and says so:
// the --json summary's "vertex_pages" (absent when they are held), the text's cache share.
TEST(EbpExtBuild, CliPagesVerticesBeyondHalfTheBudget) {
  TmpDir d;
  bvhbench::write_ply(d.file("t.ply"), torus(300, 200));  // 60,000 vertices: 703 KiB as float
  auto run = [&](const std::string& budget, const std::string& out, const std::string& flags) {
    const std::string cmd = std::string(BVHBENCH_EXE) + " --quiet ebp build --mesh " + d.file("t.ply") + " --out " +
                            d.file(out) + " --memory-budget " + budget + " " + flags + " > " + d.file("out.txt");
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::ifstream in(d.file("out.txt"));
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string paged = run("1", "a.ebp", "--json"), held = run("64", "b.ebp", "--json");
  EXPECT_NE(paged.find("\"vertex_pages\""), std::string::npos) << paged;
  EXPECT_NE(paged.find("\"misses\""), std::string::npos) << paged;
  EXPECT_EQ(held.find("\"vertex_pages\""), std::string::npos) << held;
  const std::string text = run("1", "c.ebp", "");
  EXPECT_NE(text.find("vertices paged from a temporary file"), std::string::npos) << text;
  for (const auto& e : fs::directory_iterator(d.p))
    EXPECT_EQ(e.path().filename().string().rfind("ebp-build-", 0), std::string::npos) << "left behind: " << e.path();
  // The same pages: the decoded trees are identical.
  const Octree a = StoreReader(d.file("a.ebp")).load_all(), b = StoreReader(d.file("b.ebp")).load_all();
  EXPECT_TRUE(same_bytes(a.tris, b.tris));
  EXPECT_TRUE(same_bytes(a.nodes, b.nodes));
  EXPECT_TRUE(same_bytes(a.leaves, b.leaves));
}
