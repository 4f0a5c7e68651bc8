// The whole-store check (verify.hpp): the reader's open, then every page through the reader's
// own load_page, in batches decoded in parallel and judged in page order, then the counts.
#include "methods/ebp_octree/store/verify.hpp"
#include "methods/ebp_octree/store/posix_io.hpp"
#include "methods/ebp_octree/store/crc32c.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <memory>
#include <optional>

#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "harness/util/errors.hpp"

namespace ebp {
namespace {

/// The problem of an InputError the reader raised: its message without the "FILE: " the reader
/// puts first (file_error), and without "page N: " when the verifier names the page itself.
std::string problem_of(const bvhbench::InputError& e, const std::string& path, const std::string& page_prefix) {
  std::string m = e.what();
  const std::string file_prefix = bvhbench::printable(path + ": ");
  if (m.compare(0, file_prefix.size(), file_prefix) == 0) m.erase(0, file_prefix.size());
  if (!page_prefix.empty() && m.compare(0, page_prefix.size(), page_prefix) == 0) m.erase(0, page_prefix.size());
  return m;
}

/// When a store is shorter than its header says (an interrupted copy): which sections lie past
/// the end, in file order. Empty when the header itself is unreadable or corrupt (the reader's
/// message then says so) or nothing is cut.
std::string cut_sections(const std::string& path, std::uint64_t file_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return {};
  FileHeader h{};
  const bool read = io::pread_full(fd, &h, sizeof h, 0) == io::ReadEnd::complete;
  ::close(fd);
  if (!read || std::memcmp(h.magic, kStoreMagic, 8) != 0 || h.file_size <= file_bytes) return {};
  FileHeader c = h;
  c.header_crc = 0;
  if (crc32c(&c, sizeof c) != h.header_crc) return {};
  std::vector<std::pair<std::uint64_t, std::string>> cut;
  const std::pair<const Section*, const char*> secs[] = {
      {&h.top_nodes, "top nodes"}, {&h.top_children, "top children"}, {&h.top_planes, "top planes"},
      {&h.info, "info"},           {&h.pages, "pages"},               {&h.directory, "directory"}};
  for (const auto& [s, name] : secs)
    if (s->size > 0 && s->offset + s->size > file_bytes) cut.push_back({s->offset, name});
  if (cut.empty()) return {};
  std::sort(cut.begin(), cut.end());
  std::string out = "; past the end of the file: section";
  if (cut.size() > 1) out += "s";
  for (std::size_t i = 0; i < cut.size(); ++i) out += (i ? ", '" : " '") + cut[i].second + "'";
  return out;
}

/// What a page holds, for the whole-store counts: its own nodes only (not the root-to-parent
/// chain or the white dummy that load_page adds).
struct PageCounts {
  std::uint64_t nodes = 0, inner = 0, leaves = 0, white = 0, black = 0, triangle_refs = 0, planes = 0;
  void add(const PageCounts& o) {
    nodes += o.nodes, inner += o.inner, leaves += o.leaves, white += o.white, black += o.black;
    triangle_refs += o.triangle_refs, planes += o.planes;
  }
};

PageCounts count_page(const Page& pg) {
  PageCounts c;
  const Octree& t = pg.tree;
  const std::size_t first = pg.chain;  // 0 for the root page: all of its nodes are its own
  c.nodes = t.nodes.size() - first;
  for (std::size_t i = first; i < t.nodes.size(); ++i) {
    if (t.nodes[i].kind == NodeKind::inner) ++c.inner;
    if (t.nodes[i].kind == NodeKind::white) ++c.white;
    if (t.nodes[i].kind == NodeKind::black) ++c.black;
  }
  c.leaves = t.leaves.size();
  c.triangle_refs = t.tris.size();
  c.planes = t.planes.size();
  return c;
}

/// One page's outcome in a batch.
struct PageResult {
  std::optional<std::string> problem;
  PageCounts counts;
};

PageResult check_page(const StoreReader& r, std::uint32_t id) {
  PageResult out;
  const std::string page_prefix = "page " + std::to_string(id) + ": ";
  try {
    const std::unique_ptr<Page> pg = r.load_page(id);
    out.counts = count_page(*pg);
    const PageEntry& e = r.directory()[id];
    // Written by the writer from the page header; nothing reads them back, so only this pass can
    // tell that they agree.
    if (e.nodes != out.counts.nodes || e.triangles != out.counts.triangle_refs)
      out.problem = "the directory says " + std::to_string(e.nodes) + " nodes and " + std::to_string(e.triangles) +
                    " triangle references, the page holds " + std::to_string(out.counts.nodes) + " and " +
                    std::to_string(out.counts.triangle_refs);
  } catch (const bvhbench::InputError& ex) {
    out.problem = problem_of(ex, r.path(), page_prefix);
  }
  return out;
}

/// The header's totals against the top tree plus every page: each grey inner, white and black
/// node is either a top node of that kind or a node of exactly one page (a top node of kind
/// `page` is the page's root, counted in the page); leaves and triangle references are all in
/// pages; planes of the top inner nodes are theirs alone, those of the page roots are copies.
std::optional<std::string> check_totals(const StoreReader& r, const PageCounts& pages) {
  PageCounts all = pages;
  for (const TopNode& t : r.top_nodes()) {
    if (t.kind == TopKind::page) continue;
    ++all.nodes;
    if (t.kind == TopKind::inner) ++all.inner, all.planes += t.plane_count;
    if (t.kind == TopKind::white) ++all.white;
    if (t.kind == TopKind::black) ++all.black;
  }
  const FileHeader& h = r.header();
  const std::pair<const char*, std::pair<std::uint64_t, std::uint64_t>> counts[] = {
      {"nodes", {h.nodes, all.nodes}},    {"grey inner nodes", {h.inner, all.inner}},
      {"grey leaves", {h.leaves, all.leaves}}, {"white nodes", {h.white, all.white}},
      {"black nodes", {h.black, all.black}},   {"triangle references", {h.triangle_refs, all.triangle_refs}},
      {"planes", {h.planes, all.planes}}};
  for (const auto& [name, v] : counts)
    if (v.first != v.second)
      return "the header counts " + std::to_string(v.first) + " " + name + ", the top tree and the pages hold " +
             std::to_string(v.second);
  return std::nullopt;
}

/// Asks the kernel to read pages ahead of the check: on their own, the reader's preads of one
/// page each (16 KiB by default) leave the disk idle while a page is decoded (the 32M bunny's
/// 3 GB store, OS cache dropped, one thread: 285-522 MiB/s without the hint, 704-1095 MiB/s with
/// it, OUT_OF_CORE.md). The hint goes through a descriptor of our own; the OS page cache is
/// shared, so the reader's preads then find the bytes there. No descriptor, no hint: the check
/// is the same, only slower.
class ReadAhead {
 public:
  ReadAhead(const std::string& path, const std::vector<PageEntry>& dir)
      : fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)), dir_(dir) {}
  ~ReadAhead() {
    if (fd_ >= 0) ::close(fd_);
  }
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;
  /// Pages [begin, end) will be read soon.
  void hint(std::size_t begin, std::size_t end) const {
    end = std::min(end, dir_.size());
    if (fd_ < 0 || begin >= end) return;
    std::uint64_t lo = UINT64_MAX, hi = 0;  // the writers put pages in id order, the reader does not ask it
    for (std::size_t i = begin; i < end; ++i) {
      lo = std::min(lo, dir_[i].offset);
      hi = std::max(hi, dir_[i].offset + dir_[i].size);
    }
    (void)::posix_fadvise(fd_, off_t(lo), off_t(hi - lo), POSIX_FADV_WILLNEED);
  }

 private:
  int fd_;
  const std::vector<PageEntry>& dir_;
};

std::uint64_t file_size_of(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? std::uint64_t(st.st_size) : 0;
}

/// Batches read ahead of the one being checked (a batch: 64 pages per thread, ≈ 1 MiB each).
constexpr std::size_t kAhead = 4;

}  // namespace

VerifyReport verify_store(const std::string& path, const VerifyOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  VerifyReport rep;
  rep.path = path;
  rep.file_bytes = file_size_of(path);
  auto finish = [&] {
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return rep;
  };
  auto store_problem = [&](const std::string& problem) {
    VerifyProblem p;
    p.problem = bvhbench::printable(problem);
    p.message = bvhbench::printable(path + ": " + problem);
    rep.problems.push_back(p);
  };

  std::unique_ptr<StoreReader> r;
  try {
    r = std::make_unique<StoreReader>(path);
  } catch (const bvhbench::InputError& e) {
    store_problem(problem_of(e, path, "") + cut_sections(path, rep.file_bytes));
    return finish();
  }
  const FileHeader& h = r->header();
  const std::vector<PageEntry>& dir = r->directory();
  rep.pages = dir.size();
  rep.bytes_read = sizeof(FileHeader) + h.top_nodes.size + h.top_children.size + h.top_planes.size + h.info.size +
                   h.directory.size;
  std::uint64_t page_bytes = 0, done_bytes = 0;
  for (const PageEntry& e : dir) page_bytes += e.size;

  // Batches of pages: large enough to keep every thread busy, small enough that progress moves
  // and that a stop at the first bad page wastes little work.
  // More threads than cores would only make TBB warn.
  const int threads = std::clamp(opt.threads, 1, std::max(1, tbb::info::default_concurrency()));
  const std::size_t batch = 64 * std::size_t(threads);
  tbb::task_arena arena(threads);
  std::vector<PageResult> results(batch);
  const ReadAhead ahead(path, dir);
  ahead.hint(0, kAhead * batch);
  PageCounts total;
  bool stopped = false;
  for (std::size_t begin = 0; begin < dir.size() && !stopped; begin += batch) {
    const std::size_t n = std::min(batch, dir.size() - begin);
    ahead.hint(begin + kAhead * batch, begin + (kAhead + 1) * batch);
    arena.execute([&] {
      tbb::parallel_for(std::size_t(0), n, [&](std::size_t k) { results[k] = check_page(*r, std::uint32_t(begin + k)); });
    });
    for (std::size_t k = 0; k < n && !stopped; ++k) {
      const std::uint32_t id = std::uint32_t(begin + k);
      const PageEntry& e = dir[id];
      ++rep.pages_checked;
      rep.bytes_read += e.size;
      done_bytes += e.size;
      total.add(results[k].counts);
      if (!results[k].problem) continue;
      VerifyProblem p;
      p.page = id;
      p.offset = e.offset;
      p.size = e.size;
      p.problem = *results[k].problem;
      p.message = bvhbench::printable(path + ": page " + std::to_string(id) + " (bytes " + std::to_string(e.offset) +
                                      ".." + std::to_string(e.offset + e.size) + "): " + p.problem);
      rep.problems.push_back(p);
      stopped = !opt.all;
    }
    if (opt.progress) opt.progress(done_bytes, page_bytes);
  }
  // The totals mean something only when every page was read and good.
  if (rep.problems.empty())
    if (const auto bad = check_totals(*r, total)) store_problem(*bad);
  return finish();
}

}  // namespace ebp
