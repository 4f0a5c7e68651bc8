// Tests of the whole-store check (methods/ebp_octree/ebp_verify, `bvhbench ebp verify`): good
// stores of both writers verify; one flipped byte in a page (first, middle, last), in the header,
// in each section, a truncated file, a page whose structure is bad under a correct checksum and
// counts that disagree are each refused, naming the right page or section; `--all` lists every
// bad page; the command's exit codes, text and JSON; `ebp info` unchanged on a bad page.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "methods/ebp_octree/build/external_build.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/store/crc32c.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "methods/ebp_octree/store/verify.hpp"
#include "harness/core/mesh.hpp"
#include "support/test_support.hpp"

using namespace ebp;
namespace fs = std::filesystem;
using bvhbench::test::read_file_bytes;
using bvhbench::test::torus;
using bvhbench::test::write_file_bytes;

namespace {

struct TmpDir : bvhbench::test::TmpDir {
  TmpDir() : bvhbench::test::TmpDir("ebp_verify_test") {}
};

/// The in-memory writer's store of `m` with 4 KiB pages (many pages, a deep top tree).
std::string write_store_of(const bvhbench::Mesh& m, const std::string& path, std::size_t page = 4096) {
  BuildParams bp;
  bp.threads = 1;
  StoreWriteOptions o;
  o.page_target = page;
  o.info_json = R"({"test":true})";
  write_store_atomic(build_octree(m.vertices, m.triangles, bp), path, o);
  return path;
}

/// The external build's store of `m` (sections after the pages, pages patched in place).
std::string write_external_store_of(const bvhbench::Mesh& m, const std::string& path, const TmpDir& d) {
  ExtBuildOptions o;
  o.params.threads = 2;
  o.memory_budget = 1;
  o.page_target = 4096;
  o.tmp_dir = d.p.string();
  o.info_json = [](const ExtBuildReport&) { return std::string(R"({"test":true})"); };
  build_store_external(*make_memory_source(m.vertices, m.triangles), path, o);
  return path;
}

FileHeader header_of(const std::string& bytes) {
  FileHeader h;
  std::memcpy(&h, bytes.data(), sizeof h);
  return h;
}

/// Rewrites the header with `edit` and a correct checksum, as a writer would have: whatever is
/// wrong after that is for the checks behind the checksum to find.
void edit_header(std::string& b, const std::function<void(FileHeader&)>& edit) {
  FileHeader h = header_of(b);
  edit(h);
  h.header_crc = 0;
  h.header_crc = crc32c(&h, sizeof h);
  std::memcpy(b.data(), &h, sizeof h);
}

PageEntry entry_of(const std::string& b, std::uint32_t id) {
  PageEntry e;
  std::memcpy(&e, b.data() + header_of(b).directory.offset + id * sizeof(PageEntry), sizeof e);
  return e;
}

/// Rewrites directory entry `id` with `edit`, then the directory's and the header's checksums.
void edit_entry(std::string& b, std::uint32_t id, const std::function<void(PageEntry&)>& edit) {
  PageEntry e = entry_of(b, id);
  edit(e);
  const FileHeader h = header_of(b);
  std::memcpy(b.data() + h.directory.offset + id * sizeof(PageEntry), &e, sizeof e);
  edit_header(b, [&](FileHeader& x) { x.directory.crc = crc32c(b.data() + x.directory.offset, x.directory.size); });
}

/// Rewrites page `id`'s bytes with `edit` under a correct page checksum (directory and header
/// checksums follow).
void edit_page(std::string& b, std::uint32_t id, const std::function<void(std::uint8_t* page)>& edit) {
  const PageEntry e = entry_of(b, id);
  auto* p = reinterpret_cast<std::uint8_t*>(b.data() + e.offset);
  edit(p);
  edit_entry(b, id, [&](PageEntry& x) { x.crc = crc32c(p, x.size); });
}

/// verify_store must find exactly one problem, at `page` (-1: not a page), whose message names
/// the file and whose problem says `needle`.
void expect_one_problem(const std::string& path, std::int64_t page, const std::string& needle,
                        const VerifyOptions& opt = {}) {
  const VerifyReport r = verify_store(path, opt);
  ASSERT_EQ(r.problems.size(), 1u) << needle;
  const VerifyProblem& p = r.problems[0];
  EXPECT_EQ(p.page, page) << p.message;
  EXPECT_NE(p.message.find(path), std::string::npos) << p.message;
  EXPECT_NE(p.problem.find(needle), std::string::npos) << "expected '" << needle << "' in: " << p.message;
  if (page >= 0) {
    EXPECT_NE(p.message.find("page " + std::to_string(page) + " "), std::string::npos) << p.message;
  }
}

/// A store with many pages, its bytes and layout, and a scratch file for the variants.
struct Fixture {
  TmpDir d;
  std::string good = write_store_of(torus(60, 30), d.file("good.ebp"));
  std::string bytes = read_file_bytes(good);
  FileHeader h = header_of(bytes);
  std::uint32_t pages = std::uint32_t(h.num_pages);
  std::string bad = d.file("bad.ebp");
  /// Writes the good bytes changed by `mutate` to `bad`.
  const std::string& variant(const std::function<void(std::string&)>& mutate) {
    std::string b = bytes;
    mutate(b);
    write_file_bytes(bad, b);
    return bad;
  }
  const std::string& flip_in_page(std::uint32_t id) {
    return variant([&](std::string& b) { b[std::size_t(entry_of(b, id).offset + entry_of(b, id).size / 2)] ^= 0x20; });
  }
};

int system_rc(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

}  // namespace

TEST(EbpVerify, GoodStoresOfBothWritersVerify) {
  TmpDir d;
  const bvhbench::Mesh tor = torus(60, 30);
  const bvhbench::Mesh cow = bvhbench::test::load_shared_mesh("cow.obj");
  const bvhbench::Mesh spot = bvhbench::test::load_shared_mesh("spot.obj");  // open
  const std::vector<std::string> stores = {
      write_store_of(tor, d.file("torus.ebp")),
      write_store_of(tor, d.file("torus_one_page.ebp"), std::size_t(1) << 26),
      write_store_of(cow, d.file("cow.ebp")),
      write_store_of(spot, d.file("spot.ebp")),
      write_store_of(bvhbench::test::one_triangle(), d.file("one_triangle.ebp")),
      write_external_store_of(tor, d.file("torus_ext.ebp"), d),
      write_external_store_of(cow, d.file("cow_ext.ebp"), d),
  };
  for (const std::string& s : stores)
    for (int threads : {1, 2}) {
      VerifyOptions o;
      o.threads = threads;
      std::uint64_t last_done = 0, calls = 0;
      o.progress = [&](std::uint64_t done, std::uint64_t total) {
        EXPECT_GE(done, last_done);
        EXPECT_LE(done, total);
        last_done = done;
        ++calls;
      };
      const VerifyReport r = verify_store(s, o);
      EXPECT_TRUE(r.ok()) << s << ": " << (r.problems.empty() ? "" : r.problems[0].message);
      const StoreReader sr(s);
      const FileHeader& h = sr.header();
      EXPECT_EQ(r.pages, h.num_pages) << s;
      EXPECT_EQ(r.pages_checked, h.num_pages) << s;
      EXPECT_EQ(r.file_bytes, fs::file_size(s)) << s;
      std::uint64_t expect = sizeof(FileHeader) + h.top_nodes.size + h.top_children.size + h.top_planes.size +
                             h.info.size + h.directory.size;
      for (const PageEntry& e : sr.directory()) expect += e.size;
      EXPECT_EQ(r.bytes_read, expect) << s;
      EXPECT_GT(calls, 0u) << s;
      EXPECT_EQ(last_done, expect - (sizeof(FileHeader) + h.top_nodes.size + h.top_children.size +
                                     h.top_planes.size + h.info.size + h.directory.size))
          << s << ": progress ends at all the pages' bytes";
    }
}

TEST(EbpVerify, FlippedByteInAPageNamesThatPage) {
  Fixture f;
  ASSERT_GE(f.pages, 5u);
  for (std::uint32_t id : {0u, f.pages / 2, f.pages - 1}) {
    SCOPED_TRACE("page " + std::to_string(id));
    // The reader alone would not say so until a query reached the page: the open succeeds.
    EXPECT_NO_THROW(StoreReader(f.flip_in_page(id)));
    expect_one_problem(f.bad, id, "checksum mismatch (corrupted)");
    const VerifyReport r = verify_store(f.bad);
    EXPECT_EQ(r.pages_checked, id + 1u) << "stops at the first bad page";
    EXPECT_EQ(r.problems[0].offset, entry_of(f.bytes, id).offset);
    EXPECT_EQ(r.problems[0].size, entry_of(f.bytes, id).size);
  }
}

TEST(EbpVerify, FlippedByteInTheHeaderOrASectionNamesIt) {
  Fixture f;
  f.variant([](std::string& b) { b[40] ^= 0x10; });  // the root cube
  expect_one_problem(f.bad, -1, "header checksum mismatch");
  const std::pair<const Section*, std::string> sections[] = {{&f.h.top_nodes, "top nodes"},
                                                             {&f.h.top_children, "top children"},
                                                             {&f.h.top_planes, "top planes"},
                                                             {&f.h.info, "info"},
                                                             {&f.h.directory, "directory"}};
  for (const auto& [s, name] : sections) {
    SCOPED_TRACE(name);
    ASSERT_GT(s->size, 0u);
    for (std::uint64_t at : {std::uint64_t(0), s->size - 1}) {
      f.variant([&, s = s](std::string& b) { b[std::size_t(s->offset + at)] ^= 0x01; });
      expect_one_problem(f.bad, -1, "checksum mismatch in section '" + name + "'");
      EXPECT_EQ(verify_store(f.bad).pages_checked, 0u);
    }
  }
}

TEST(EbpVerify, TruncatedStoreNamesTheSectionsCut) {
  Fixture f;
  // The in-memory writer puts the pages, then the directory, last.
  f.variant([&](std::string& b) { b.resize(std::size_t(f.h.pages.offset) + 10); });
  expect_one_problem(f.bad, -1, "size mismatch");
  expect_one_problem(f.bad, -1, "past the end of the file: sections 'pages', 'directory'");
  f.variant([](std::string& b) { b.pop_back(); });
  expect_one_problem(f.bad, -1, "past the end of the file: section 'directory'");
  f.variant([](std::string& b) { b.resize(100); });  // not even a header
  expect_one_problem(f.bad, -1, "truncated: 100 bytes");
  f.variant([](std::string& b) { b.push_back('x'); });  // extended: nothing is cut
  const VerifyReport r = verify_store(f.bad);
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_NE(r.problems[0].problem.find("truncated or extended"), std::string::npos);
  EXPECT_EQ(r.problems[0].problem.find("past the end"), std::string::npos);
  expect_one_problem(f.d.file("no_such.ebp"), -1, "cannot open");

  // The external build puts the sections after the pages: a cut in the pages loses all of them.
  TmpDir d;
  const std::string ext = write_external_store_of(torus(60, 30), d.file("ext.ebp"), d);
  std::string b = read_file_bytes(ext);
  b.resize(std::size_t(header_of(b).pages.offset) + 10);
  write_file_bytes(ext, b);
  expect_one_problem(ext, -1, "sections 'pages', 'directory', 'top nodes', 'top children', 'top planes', 'info'");
}

TEST(EbpVerify, StructureBehindAGoodChecksumIsCheckedAsALoadWould) {
  Fixture f;
  const std::uint32_t id = f.pages / 2;
  f.variant([&](std::string& b) { edit_page(b, id, [](std::uint8_t* p) { p[0] ^= 0xff; }); });
  expect_one_problem(f.bad, id, "bad page magic");
  f.variant([&](std::string& b) {  // a root's node index past the page's nodes
    edit_page(b, id, [](std::uint8_t* p) {
      PageRoot r;
      std::memcpy(&r, p + sizeof(PageHeader), sizeof r);
      r.node = 1u << 30;
      std::memcpy(p + sizeof(PageHeader), &r, sizeof r);
    });
  });
  expect_one_problem(f.bad, id, "root node out of range");
  f.variant([&](std::string& b) {  // the last node's subtree end past the page
    edit_page(b, id, [&](std::uint8_t* p) {
      PageHeader ph;
      std::memcpy(&ph, p, sizeof ph);
      Node nd;
      std::uint8_t* at = p + sizeof(PageHeader) + ph.nroots * sizeof(PageRoot) + (ph.nnodes - 1) * sizeof(Node);
      std::memcpy(&nd, at, sizeof nd);
      nd.next = ph.nnodes + 1;
      std::memcpy(at, &nd, sizeof nd);
    });
  });
  expect_one_problem(f.bad, id, "bad subtree end");
}

TEST(EbpVerify, CountsThatDisagreeWithThePagesAreRefused) {
  Fixture f;
  const std::uint32_t id = f.pages - 1;
  f.variant([&](std::string& b) { edit_entry(b, id, [](PageEntry& e) { e.nodes += 1; }); });
  expect_one_problem(f.bad, id, "the directory says");
  f.variant([&](std::string& b) { edit_entry(b, id, [](PageEntry& e) { e.triangles -= 1; }); });
  expect_one_problem(f.bad, id, "triangle references");
  const std::pair<std::uint64_t FileHeader::*, std::string> totals[] = {
      {&FileHeader::nodes, "nodes"},           {&FileHeader::inner, "grey inner nodes"},
      {&FileHeader::leaves, "grey leaves"},    {&FileHeader::white, "white nodes"},
      {&FileHeader::black, "black nodes"},     {&FileHeader::triangle_refs, "triangle references"},
      {&FileHeader::planes, "planes"}};
  for (const auto& [field, name] : totals) {
    f.variant([&, field = field](std::string& b) { edit_header(b, [&](FileHeader& h) { ++(h.*field); }); });
    const std::uint64_t good = f.h.*field;
    expect_one_problem(f.bad, -1, "the header counts " + std::to_string(good + 1) + " " + name +
                                      ", the top tree and the pages hold " + std::to_string(good));
  }
}

TEST(EbpVerify, AllListsEveryBadPageInOrderWithAnyThreadCount) {
  Fixture f;
  const std::vector<std::uint32_t> bad = {1, f.pages / 2, f.pages - 1};
  f.variant([&](std::string& b) {
    for (std::uint32_t id : bad) b[std::size_t(entry_of(b, id).offset + 7)] ^= 0x80;
  });
  for (int threads : {1, 2, 3}) {
    SCOPED_TRACE(threads);
    VerifyOptions o;
    o.threads = threads;
    expect_one_problem(f.bad, 1, "checksum mismatch", o);
    EXPECT_EQ(verify_store(f.bad, o).pages_checked, 2u);
    o.all = true;
    const VerifyReport r = verify_store(f.bad, o);
    ASSERT_EQ(r.problems.size(), bad.size());
    for (std::size_t k = 0; k < bad.size(); ++k) EXPECT_EQ(r.problems[k].page, std::int64_t(bad[k]));
    EXPECT_EQ(r.pages_checked, f.pages);
  }
  // A bad section ends the check even with --all: the directory is what says where pages are.
  f.variant([&](std::string& b) { b[std::size_t(f.h.directory.offset)] ^= 1; });
  VerifyOptions all;
  all.all = true;
  expect_one_problem(f.bad, -1, "section 'directory'", all);
}

TEST(EbpVerify, CommandExitCodesTextAndJson) {
  Fixture f;
  const std::string exe = BVHBENCH_EXE, out = f.d.file("out.txt"), err = f.d.file("err.txt");
  auto run = [&](const std::string& args) { return system_rc(exe + " ebp verify " + args + " >" + out + " 2>" + err); };

  ASSERT_EQ(run(f.good), 0) << read_file_bytes(err);
  const std::string ok = read_file_bytes(out);
  EXPECT_EQ(ok.rfind("ok " + f.good + ": " + std::to_string(f.pages) + " pages, ", 0), 0u) << ok;
  EXPECT_NE(ok.find("MiB/s)"), std::string::npos) << ok;
  EXPECT_EQ(std::count(ok.begin(), ok.end(), '\n'), 1) << "one line";
  ASSERT_EQ(run("--json " + f.good), 0);
  nlohmann::json j = nlohmann::json::parse(read_file_bytes(out));
  EXPECT_TRUE(j["ok"].get<bool>());
  EXPECT_EQ(j["pages"].get<std::uint32_t>(), f.pages);
  EXPECT_EQ(j["pages_checked"].get<std::uint32_t>(), f.pages);
  EXPECT_GT(j["bytes_read"].get<std::uint64_t>(), 0u);
  EXPECT_TRUE(j["problems"].empty());

  const std::uint32_t mid = f.pages / 2;
  f.flip_in_page(mid);
  EXPECT_EQ(run(f.bad), 2);
  std::string e = read_file_bytes(err);
  EXPECT_NE(e.find(f.bad + ": page " + std::to_string(mid) + " (bytes "), std::string::npos) << e;
  EXPECT_NE(e.find("checksum mismatch (corrupted)"), std::string::npos) << e;
  EXPECT_NE(e.find("--all"), std::string::npos) << e;
  EXPECT_TRUE(read_file_bytes(out).empty());
  EXPECT_EQ(run("--json " + f.bad), 2);
  j = nlohmann::json::parse(read_file_bytes(out));
  EXPECT_FALSE(j["ok"].get<bool>());
  ASSERT_EQ(j["problems"].size(), 1u);
  EXPECT_EQ(j["problems"][0]["page"].get<std::uint32_t>(), mid);
  EXPECT_EQ(j["problems"][0]["offset"].get<std::uint64_t>(), entry_of(f.bytes, mid).offset);
  EXPECT_EQ(j["problems"][0]["problem"].get<std::string>(), "checksum mismatch (corrupted)");

  // `ebp info` reads no page: it works on this store as it always did.
  EXPECT_EQ(system_rc(exe + " ebp info " + f.bad + " >/dev/null 2>" + err), 0) << read_file_bytes(err);

  f.variant([&](std::string& b) {
    for (std::uint32_t id : {0u, f.pages - 1}) b[std::size_t(entry_of(b, id).offset + 3)] ^= 4;
  });
  EXPECT_EQ(run("--all --threads 2 " + f.bad), 2);
  e = read_file_bytes(err);
  EXPECT_NE(e.find(": page 0 (bytes"), std::string::npos) << e;
  EXPECT_NE(e.find(": page " + std::to_string(f.pages - 1) + " (bytes"), std::string::npos) << e;
  EXPECT_NE(e.find("2 bad of " + std::to_string(f.pages) + " pages"), std::string::npos) << e;
  EXPECT_EQ(run("--all --json " + f.bad), 2);
  EXPECT_EQ(nlohmann::json::parse(read_file_bytes(out))["problems"].size(), 2u);

  f.variant([](std::string& b) { b.pop_back(); });
  EXPECT_EQ(run("--json " + f.bad), 2);
  j = nlohmann::json::parse(read_file_bytes(out));
  ASSERT_EQ(j["problems"].size(), 1u);
  EXPECT_TRUE(j["problems"][0]["page"].is_null());
  EXPECT_NE(j["problems"][0]["message"].get<std::string>().find("section 'directory'"), std::string::npos);
  EXPECT_EQ(run(f.bad), 2);
  EXPECT_NE(read_file_bytes(err).find(f.bad + ": size mismatch"), std::string::npos);
  EXPECT_EQ(run(""), 2) << "the store is required";
}
