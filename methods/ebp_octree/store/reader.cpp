// The `.ebp` reader (reader.hpp): header, top tree and directory checked and pinned at open;
// pages read and decoded into ordinary Octrees on demand. Every number read from the file is
// checked before it is used as a size, an offset or an index. See OUT_OF_CORE.md.
#include "methods/ebp_octree/store/reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>

#include "harness/util/errors.hpp"
#include "methods/ebp_octree/core/leaf_blocks.hpp"
#include "methods/ebp_octree/core/face_sides.hpp"
#include "methods/ebp_octree/core/sub_references.hpp"
#include "methods/ebp_octree/store/crc32c.hpp"
#include "methods/ebp_octree/store/posix_io.hpp"

namespace ebp {

namespace {

bool finite3(const float* f) { return std::isfinite(f[0]) && std::isfinite(f[1]) && std::isfinite(f[2]); }

}  // namespace

StoreReader::StoreReader(const std::string& path, Options opt) : path_(path), opt_(opt) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw bvhbench::file_error(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd_);
    fd_ = -1;
    throw bvhbench::file_error(path, "not a regular file");
  }
  file_size_ = std::uint64_t(st.st_size);
  // Pages are read where queries go, not in file order: without this, the kernel's read-ahead
  // takes a run of misses for a sequential reader and reads up to 128 KiB around a 16 KiB page,
  // which delays the read the query waits for (the 32M store, cold, haptic path: queries over
  // 1 ms 26-32 -> 14-15 of 20,000). The searches ask for the pages they will need themselves
  // (will_need). `ebp verify` reads in file order through its own descriptor, with its own hints.
  (void)::posix_fadvise(fd_, 0, 0, POSIX_FADV_RANDOM);
  try {
    open_and_check();
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

StoreReader::StoreReader(std::vector<std::uint8_t> bytes, const std::string& name, Options opt)
    : path_(name), mem_(std::move(bytes)), in_memory_(true), opt_(opt) {
  file_size_ = mem_.size();
  open_and_check();
}

StoreReader::~StoreReader() {
  if (fd_ >= 0) ::close(fd_);
}

void StoreReader::fail(const std::string& what) const { throw bvhbench::file_error(path_, what); }

void StoreReader::read_at(std::uint64_t off, void* dst, std::size_t n) const {
  if (off > file_size_ || n > file_size_ - off) fail("read past the end of the file (truncated?)");
  if (in_memory_) {
    if (n) std::memcpy(dst, mem_.data() + off, n);
    return;
  }
  switch (io::pread_full(fd_, dst, n, off)) {
    case io::ReadEnd::complete: return;
    case io::ReadEnd::error: fail(std::string("read failed: ") + std::strerror(errno));
    case io::ReadEnd::end_of_file: fail("unexpected end of file (truncated while open?)");
  }
}

void StoreReader::drop_os_cache() const {
  if (fd_ >= 0) (void)::posix_fadvise(fd_, 0, 0, POSIX_FADV_DONTNEED);
}

void StoreReader::will_need(std::uint32_t id) const {
  if (fd_ >= 0 && id < dir_.size())
    (void)::posix_fadvise(fd_, off_t(dir_[id].offset), off_t(dir_[id].size), POSIX_FADV_WILLNEED);
}

std::size_t StoreReader::pinned_bytes() const {
  return sizeof(*this) + top_nodes_.capacity() * sizeof(TopNode) + top_children_.capacity() * 4 +
         top_planes_.capacity() * sizeof(Plane) + dir_.capacity() * sizeof(PageEntry) + info_.capacity() +
         page_parent_.capacity() * sizeof(Octcode) + page_octants_.capacity();
}

void StoreReader::open_and_check() {
  check_header();
  check_sections();
  load_sections();
  const std::vector<std::uint8_t> page_seen = check_top_tree();
  check_directory(page_seen);
}

void StoreReader::check_header() {
  if (file_size_ < sizeof(FileHeader))
    fail("truncated: " + std::to_string(file_size_) + " bytes, smaller than the 512-byte header");
  read_at(0, &h_, sizeof h_);
  if (std::memcmp(h_.magic, kStoreMagic, 8) != 0) fail("not an EBP-Octree store (bad magic)");
  if (h_.version == 1 || h_.version == 2) {
    const char* what = h_.version == 1 ? " (world coordinates, 64-byte triangle records)" : " (64-byte triangle records)";
    fail("store format version " + std::to_string(h_.version) + what +
         ", written by an older bvhbench; this build reads version " + std::to_string(kStoreVersion) +
         " (coordinates relative to a frame origin, 48-byte triangle records): rebuild it with "
         "`bvhbench ebp build --mesh MESH --out STORE`");
  }
  if (h_.version != kStoreVersion)
    fail("unsupported store version " + std::to_string(h_.version) + " (this build reads version " +
         std::to_string(kStoreVersion) + ")");
  if (h_.header_size != sizeof(FileHeader)) fail("bad header size " + std::to_string(h_.header_size));
  if (opt_.verify_checksums) {
    FileHeader c = h_;
    c.header_crc = 0;
    if (crc32c(&c, sizeof c) != h_.header_crc) fail("header checksum mismatch (corrupted header)");
  }
  if (h_.file_size != file_size_)
    fail("size mismatch: the header says " + std::to_string(h_.file_size) + " bytes, the file has " +
         std::to_string(file_size_) + " (truncated or extended)");
  if (h_.leaf_level < 1 || h_.leaf_level > std::uint32_t(kMaxLevel)) fail("bad leaf level " + std::to_string(h_.leaf_level));
  if (!(std::isfinite(h_.root_lo[0]) && std::isfinite(h_.root_lo[1]) && std::isfinite(h_.root_lo[2]) &&
        std::isfinite(h_.root_size) && h_.root_size > 0))
    fail("bad bounding cube");
  if (!(std::isfinite(h_.origin[0]) && std::isfinite(h_.origin[1]) && std::isfinite(h_.origin[2])))
    fail("bad frame origin");
  if (h_.num_triangles == 0) fail("no triangles");
  if (h_.flags & ~kStoreClosed) fail("unknown header flags");
  if (h_.num_pages == 0 || h_.num_pages > 0xffffffffull) fail("bad page count " + std::to_string(h_.num_pages));
}

void StoreReader::check_sections() const {
  struct Named { const char* name; const Section* s; std::uint64_t expect; };
  const Named secs[] = {
      {"top nodes", &h_.top_nodes, h_.num_top_nodes * sizeof(TopNode)},
      {"top children", &h_.top_children, h_.num_top_children * sizeof(std::uint32_t)},
      {"top planes", &h_.top_planes, h_.num_top_planes * sizeof(Plane)},
      {"info", &h_.info, h_.info.size},
      {"pages", &h_.pages, h_.pages.size},
      {"directory", &h_.directory, h_.num_pages * sizeof(PageEntry)},
  };
  if (h_.num_top_nodes > file_size_ || h_.num_top_children > file_size_ || h_.num_top_planes > file_size_)
    fail("bad top-tree counts");
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;
  for (const Named& n : secs) {
    const Section& s = *n.s;
    if (s.size != n.expect)
      fail(std::string("section '") + n.name + "' has " + std::to_string(s.size) + " bytes, expected " +
           std::to_string(n.expect));
    if (s.offset < sizeof(FileHeader) || s.offset > file_size_ || s.size > file_size_ - s.offset)
      fail(std::string("section '") + n.name + "' lies outside the file (offset " + std::to_string(s.offset) +
           ", size " + std::to_string(s.size) + ")");
    if (s.size) ranges.push_back({s.offset, s.offset + s.size});
  }
  std::sort(ranges.begin(), ranges.end());
  for (std::size_t i = 1; i < ranges.size(); ++i)
    if (ranges[i].first < ranges[i - 1].second) fail("sections overlap");
  if (h_.info.size > (64u << 20)) fail("info section larger than 64 MiB");
  if (h_.num_top_nodes == 0) fail("empty top tree");

}

void StoreReader::load_sections() {
  auto load = [&](const Section& s, void* dst, const char* name) {
    read_at(s.offset, dst, std::size_t(s.size));
    if (opt_.verify_checksums && crc32c(dst, std::size_t(s.size)) != s.crc)
      fail(std::string("checksum mismatch in section '") + name + "' (corrupted)");
  };
  top_nodes_.resize(std::size_t(h_.num_top_nodes));
  top_children_.resize(std::size_t(h_.num_top_children));
  top_planes_.resize(std::size_t(h_.num_top_planes));
  dir_.resize(std::size_t(h_.num_pages));
  info_.resize(std::size_t(h_.info.size));
  load(h_.top_nodes, top_nodes_.data(), "top nodes");
  load(h_.top_children, top_children_.data(), "top children");
  load(h_.top_planes, top_planes_.data(), "top planes");
  load(h_.info, info_.data(), "info");
  load(h_.directory, dir_.data(), "directory");

}

std::vector<std::uint8_t> StoreReader::check_top_tree() {
  // Top planes finite.
  for (const Plane& p : top_planes_)
    if (!finite3(p.n) || !std::isfinite(p.d)) fail("non-finite plane in the top tree");
  // Top tree: structure from the root, every child's code the child of its parent's.
  const int L = int(h_.leaf_level);
  page_parent_.assign(dir_.size(), kNoParent);
  page_octants_.assign(dir_.size(), 0);
  std::vector<std::uint8_t> page_seen(dir_.size(), 0);
  if (top_nodes_[0].code != octcode_root()) fail("top tree: node 0 is not the root");
  std::vector<std::pair<std::uint32_t, Octcode>> todo{{0u, kNoParent}};  // node, parent code
  std::size_t visited = 0;
  while (!todo.empty()) {
    const auto [i, parent] = todo.back();
    todo.pop_back();
    if (++visited > top_nodes_.size()) fail("top tree: a node is reached twice");
    const TopNode& n = top_nodes_[i];
    if (std::uint8_t(n.kind) > 3) fail("top tree: bad node kind " + std::to_string(int(n.kind)));
    if (std::uint64_t(n.plane_begin) + n.plane_count > top_planes_.size()) fail("top tree: plane range out of bounds");
    if (octcode_level(n.code) > L) fail("top tree: node below the leaf level");
    if (n.kind == TopKind::inner) {
      if (octcode_level(n.code) >= L) fail("top tree: inner node at the leaf level");
      if (std::uint64_t(n.index) + 8 > top_children_.size()) fail("top tree: children out of bounds");
      for (std::uint32_t o = 0; o < 8; ++o) {
        const std::uint32_t c = top_children_[n.index + o];
        if (c >= top_nodes_.size() || c <= i) fail("top tree: bad child index " + std::to_string(c));
        if (top_nodes_[c].code != octcode_child(n.code, int(o))) fail("top tree: child code mismatch");
        todo.push_back({c, n.code});
      }
    } else if (n.kind == TopKind::page) {
      if (n.index >= dir_.size()) fail("top tree: page index " + std::to_string(n.index) + " out of range");
      if (page_seen[n.index] && page_parent_[n.index] != parent) fail("top tree: a page under two parents");
      page_seen[n.index] = 1;
      page_parent_[n.index] = parent;
      const std::uint32_t oct = parent == kNoParent ? 0u : std::uint32_t(octcode_octant(n.code));
      if (parent == kNoParent) page_octants_[n.index] = 1;
      else page_octants_[n.index] |= std::uint8_t(1u << oct);
    }
  }
  return page_seen;
}

void StoreReader::check_directory(const std::vector<std::uint8_t>& page_seen) const {
  // Directory: pages inside the pages section, aligned, non-overlapping, each referenced.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> pr;
  pr.reserve(dir_.size());
  const std::uint64_t pbeg = h_.pages.offset, pend = h_.pages.offset + h_.pages.size;
  for (std::size_t id = 0; id < dir_.size(); ++id) {
    const PageEntry& e = dir_[id];
    if (!page_seen[id]) fail("page " + std::to_string(id) + " is not referenced by the top tree");
    if (e.parent != page_parent_[id]) fail("page " + std::to_string(id) + ": parent code mismatch");
    if (e.size < sizeof(PageHeader) || e.size > kMaxPageBytes)
      fail("page " + std::to_string(id) + ": bad size " + std::to_string(e.size));
    if (e.offset < pbeg || e.offset > pend || e.size > pend - e.offset)
      fail("page " + std::to_string(id) + ": offset " + std::to_string(e.offset) + " outside the pages section");
    pr.push_back({e.offset, e.offset + e.size});
  }
  std::sort(pr.begin(), pr.end());
  for (std::size_t i = 1; i < pr.size(); ++i)
    if (pr[i].first < pr[i - 1].second) fail("pages overlap");
}

std::unique_ptr<Page> StoreReader::load_page(std::uint32_t id, std::uint64_t* bytes_read) const {
  if (id >= dir_.size()) fail("page " + std::to_string(id) + " out of range");
  const PageEntry& e = dir_[id];
  const std::string where = "page " + std::to_string(id) + ": ";
  std::vector<std::uint8_t> buf(e.size);
  read_at(e.offset, buf.data(), buf.size());
  if (bytes_read) *bytes_read += e.size;
  if (opt_.verify_checksums && crc32c(buf.data(), buf.size()) != e.crc) fail(where + "checksum mismatch (corrupted)");
  return decode_page(buf.data(), buf.size(), page_context(id), path_);
}

PageContext StoreReader::page_context(std::uint32_t id) const {
  PageContext c;
  c.id = id;
  c.parent = page_parent_[id];
  c.octants = page_octants_[id];
  c.leaf_level = int(h_.leaf_level);
  c.num_triangles = h_.num_triangles;
  c.origin = Vec3d(h_.origin[0], h_.origin[1], h_.origin[2]);
  c.root_lo = Vec3d(h_.root_lo[0], h_.root_lo[1], h_.root_lo[2]);
  c.root_size = h_.root_size;
  c.closed = (h_.flags & kStoreClosed) != 0;
  return c;
}

Octree StoreReader::load_all() const {
  Octree T;
  T.origin = Vec3d(h_.origin[0], h_.origin[1], h_.origin[2]);
  T.root_lo = Vec3d(h_.root_lo[0], h_.root_lo[1], h_.root_lo[2]);
  T.root_size = h_.root_size;
  T.root_centre = T.root_lo + Vec3d(0.5, 0.5, 0.5) * T.root_size;
  T.leaf_level = int(h_.leaf_level);
  T.num_triangles = h_.num_triangles;
  T.closed = (h_.flags & kStoreClosed) != 0;
  std::map<std::uint32_t, std::unique_ptr<Page>> pages;
  // Copies node i of page pg's tree (page-local indexing) into T, pre-order.
  std::function<std::uint32_t(const Page&, std::uint32_t)> copy_page = [&](const Page& pg, std::uint32_t i) {
    const Node& src = pg.tree.nodes[i];
    const auto ni = std::uint32_t(T.nodes.size());
    T.nodes.push_back(src);
    T.nodes[ni].plane_begin = std::uint32_t(T.planes.size());
    T.planes.insert(T.planes.end(), pg.tree.planes.begin() + src.plane_begin,
                    pg.tree.planes.begin() + src.plane_begin + src.plane_count);
    if (src.kind == NodeKind::leaf) {
      Leaf lf = pg.tree.leaves[src.index];
      const auto tb = std::uint32_t(T.tris.size());
      for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
        LeafTri lt = pg.tree.tris[lf.tri_begin + k];
        lt.set_tri(pg.global_tri[lt.tri()]);
        T.tris.push_back(lt);
      }
      lf.tri_begin = tb;
      T.nodes[ni].index = std::uint32_t(T.leaves.size());
      T.leaves.push_back(lf);
    } else if (src.kind == NodeKind::inner) {
      const auto cb = std::uint32_t(T.children.size());
      T.children.resize(cb + 8);
      T.nodes[ni].index = cb;
      for (std::uint32_t o = 0; o < 8; ++o) {
        const std::uint32_t c = copy_page(pg, pg.tree.children[src.index + o]);
        T.children[cb + o] = c;
      }
    }
    T.nodes[ni].next = std::uint32_t(T.nodes.size());
    return ni;
  };
  std::function<std::uint32_t(std::uint32_t)> copy_top = [&](std::uint32_t i) -> std::uint32_t {
    const TopNode& tn = top_nodes_[i];
    if (tn.kind == TopKind::page) {
      auto it = pages.find(tn.index);
      if (it == pages.end()) it = pages.emplace(tn.index, load_page(tn.index)).first;
      const Page& pg = *it->second;
      // Find the page node with this code (a root of the page).
      for (std::uint32_t k = 0; k < pg.tree.nodes.size(); ++k)
        if (pg.tree.nodes[k].code == tn.code && pg.tree.nodes[k].kind != NodeKind::white) return copy_page(pg, k);
      fail("page " + std::to_string(tn.index) + " lacks its root");
    }
    const auto ni = std::uint32_t(T.nodes.size());
    Node nd{};
    nd.code = tn.code;
    nd.plane_begin = std::uint32_t(T.planes.size());
    nd.plane_count = tn.plane_count;
    T.planes.insert(T.planes.end(), top_planes_.begin() + tn.plane_begin,
                    top_planes_.begin() + tn.plane_begin + tn.plane_count);
    nd.config = LeafConfig::special;
    nd.kind = tn.kind == TopKind::white ? NodeKind::white : tn.kind == TopKind::black ? NodeKind::black : NodeKind::inner;
    T.nodes.push_back(nd);
    if (tn.kind == TopKind::inner) {
      const auto cb = std::uint32_t(T.children.size());
      T.children.resize(cb + 8);
      T.nodes[ni].index = cb;
      for (std::uint32_t o = 0; o < 8; ++o) {
        const std::uint32_t c = copy_top(top_children_[tn.index + o]);
        T.children[cb + o] = c;
      }
    }
    T.nodes[ni].next = std::uint32_t(T.nodes.size());
    return ni;
  };
  copy_top(0);
  compute_leaf_blocks(T);  // derived boxes (not in the file)
  compute_sub_references(T);  // derived reference points (sub_references.hpp)
  compute_face_sides(T);  // the faces the distance's sign can be taken from (face_sides.hpp)
  return T;
}

}  // namespace ebp
