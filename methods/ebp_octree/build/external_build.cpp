// External-memory build of the `.ebp` store. See external_build.hpp and OUT_OF_CORE.md
// ("`bvhbench ebp build`"): streamed mesh, sorted runs spilled and merged, leaves and inner nodes
// built in octcode order by the in-memory builder's code, pages written as subtrees complete,
// colouring over the node skeleton patched into the pages at the end.
#include "methods/ebp_octree/build/external_build.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <queue>
#include <thread>
#include <stdexcept>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "harness/util/binary_file.hpp"
#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/store/posix_io.hpp"
#include "methods/ebp_octree/store/crc32c.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/page_codec.hpp"
#include "harness/io/mesh_reader.hpp"
#include "methods/ebp_octree/core/predicates.hpp"

namespace ebp {

using namespace detail;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

using io::pwrite_all;

// ---------------------------------------------------------------------------------------------
// Sources
constexpr std::size_t kChunk = 1 << 16;  // triangles per scan chunk

class MemorySource final : public TriangleSource {
 public:
  MemorySource(const std::vector<Vec3d>& v, const std::vector<std::array<std::uint32_t, 3>>& t) : v_(v), t_(t) {
    vf_.reserve(3 * v_.size());
    for (const Vec3d& p : v_) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw std::invalid_argument("ebp_octree: non-finite vertex coordinate");
      for (int k = 0; k < 3; ++k) vf_.push_back(float(p[k]));
    }
  }
  const float* float_vertices() const override { return vf_.data(); }
  std::uint64_t num_triangles() const override { return t_.size(); }
  std::uint64_t num_vertices() const override { return v_.size(); }
  void scan(const Chunk& f) override {
    std::vector<std::uint32_t> idx;
    std::vector<float> xyz;
    for (std::size_t first = 0; first < t_.size(); first += kChunk) {
      const std::size_t n = std::min(kChunk, t_.size() - first);
      idx.resize(3 * n);
      xyz.resize(9 * n);
      for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
          const std::uint32_t vi = t_[first + i][k];
          if (vi >= v_.size()) throw std::invalid_argument("ebp_octree: vertex index out of range");
          idx[3 * i + k] = vi;
          for (int a = 0; a < 3; ++a) xyz[9 * i + 3 * k + a] = float(v_[vi][a]);
        }
      f(first, n, idx.data(), xyz.data());
    }
  }
  std::size_t resident_bytes() const override { return vf_.capacity() * sizeof(float); }

 private:
  const std::vector<Vec3d>& v_;
  std::vector<float> vf_;
  const std::vector<std::array<std::uint32_t, 3>>& t_;
};

/// A mesh file in any format the harness reads, through its mesh reader (mesh_reader.hpp): the
/// vertices read once into float (held), the triangles re-read from the file at every scan.
class FileSource final : public TriangleSource {
 public:
  explicit FileSource(const std::string& path) : reader_(bvhbench::MeshReader::open(path)) {
    vf_.reserve(3 * std::size_t(reader_->num_vertices()));  // the header's count, checked against the file size
    reader_->read_vertices([&](std::uint64_t, const Vec3d* v, std::size_t n) {
      for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) vf_.push_back(float(v[i][k]));
    });
    vf_.shrink_to_fit();
  }
  std::uint64_t num_triangles() const override { return reader_->num_triangles(); }
  std::uint64_t num_vertices() const override { return reader_->num_vertices(); }
  std::string sha256() const override { return reader_->sha256(); }
  const float* float_vertices() const override { return vf_.data(); }
  /// The float vertices, the reader's buffers (an STL's weld table among them) and one chunk.
  std::size_t resident_bytes() const override {
    return vf_.capacity() * sizeof(float) + reader_->resident_bytes() +
           kChunk * (3 * sizeof(std::uint32_t) + 9 * sizeof(float));
  }
  bool streaming() const override { return true; }

  void scan(const Chunk& f) override {
    std::vector<std::uint32_t> idx;
    std::vector<float> xyz;
    reader_->read_triangles([&](std::uint64_t first, const bvhbench::Triangle* t, std::size_t n) {
      idx.resize(3 * n);
      xyz.resize(9 * n);
      for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
          const std::uint32_t v = t[i][k];
          idx[3 * i + std::size_t(k)] = v;
          std::memcpy(&xyz[9 * i + 3 * std::size_t(k)], &vf_[3 * std::size_t(v)], 3 * sizeof(float));
        }
      f(first, n, idx.data(), xyz.data());
    });
  }

 private:
  std::unique_ptr<bvhbench::MeshReader> reader_;
  std::vector<float> vf_;
};

// ---------------------------------------------------------------------------------------------
// Records, runs, merge
struct Rec {
  std::uint64_t m;     // leaf Morton code
  std::uint32_t t;     // triangle
  std::uint32_t v[3];  // its vertices (coordinates: TriangleSource::float_vertices())
};
static_assert(sizeof(Rec) == 24, "Rec is 24 bytes");
struct RecLess {
  bool operator()(const Rec& a, const Rec& b) const { return a.m < b.m || (a.m == b.m && a.t < b.t); }
};

struct RunFile {
  std::string path;
  std::uint64_t records = 0;
};

class RunReader {
 public:
  RunReader(const RunFile& rf, std::size_t buf_records) : path_(rf.path), left_(rf.records), buf_(std::max<std::size_t>(buf_records, 16)) {
    fd_ = ::open(rf.path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) io::fail(rf.path, "cannot open a sorted run");
    ::posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
  }
  ~RunReader() {
    if (fd_ >= 0) ::close(fd_);
  }
  RunReader(const RunReader&) = delete;
  RunReader& operator=(const RunReader&) = delete;
  const Rec* peek() {
    if (pos_ == n_ && !fill()) return nullptr;
    return &buf_[pos_];
  }
  void pop() { ++pos_; }

 private:
  bool fill() {
    if (left_ == 0) return false;
    const std::size_t n = std::size_t(std::min<std::uint64_t>(left_, buf_.size()));
    switch (io::pread_full(fd_, buf_.data(), n * sizeof(Rec), off_)) {
      case io::ReadEnd::complete: break;
      case io::ReadEnd::error: io::fail(path_, "read failed");
      case io::ReadEnd::end_of_file: errno = EIO; io::fail(path_, "sorted run shorter than written");
    }
    off_ += n * sizeof(Rec);
    left_ -= n;
    n_ = n;
    pos_ = 0;
    return true;
  }
  std::string path_;
  int fd_ = -1;
  std::uint64_t left_, off_ = 0;
  std::vector<Rec> buf_;
  std::size_t pos_ = 0, n_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Subtree fragments (a subtree serialised as a page would hold it, indices relative to itself)
struct Frag {
  std::vector<Node> nodes;
  std::vector<std::uint32_t> children;
  std::vector<Plane> planes;
  std::vector<Leaf> leaves;
  std::vector<LeafTri> tris;
  std::vector<std::uint32_t> gid;  // global node index of each node
  std::uint64_t bytes = 0;
  void append(const Frag& f) {
    const auto no = std::uint32_t(nodes.size()), co = std::uint32_t(children.size()),
               po = std::uint32_t(planes.size()), lo = std::uint32_t(leaves.size()), to = std::uint32_t(tris.size());
    for (Node nd : f.nodes) {
      nd.plane_begin += po;
      nd.next += no;
      if (nd.kind == NodeKind::inner) nd.index += co;
      else if (nd.kind == NodeKind::leaf) nd.index += lo;
      nodes.push_back(nd);
    }
    for (std::uint32_t c : f.children) children.push_back(c + no);
    planes.insert(planes.end(), f.planes.begin(), f.planes.end());
    for (Leaf l : f.leaves) {
      l.tri_begin += to;
      leaves.push_back(l);
    }
    tris.insert(tris.end(), f.tris.begin(), f.tris.end());
    gid.insert(gid.end(), f.gid.begin(), f.gid.end());
  }
};

struct Child {
  enum State : std::uint8_t { none, empty, held, top } state = none;
  std::uint32_t gid = 0;
  std::uint64_t bytes = 0;
  NodeTmp tmp;  // grey children: planes and bounding volume, for the parent's build_inner
  Frag frag;    // held: the completed subtree, until the parent's place in the cut is known
};

struct Open {
  std::uint32_t gid = 0;
  Octcode code = 0;
  int next_octant = 0;  // octants < next_octant are handled
  Child ch[8];
  bool top = false;
  std::uint64_t partial = 0;
  std::uint32_t top_index = 0, top_cb = 0;
  // the open page group of a top node
  std::vector<Frag> group;
  std::vector<std::uint32_t> group_octants, group_tops;
  std::uint64_t group_bytes = 0;
};

struct Patch {
  std::uint32_t page, off;
  std::uint8_t len;
  std::uint8_t b[2];
};

/// Everything after the merge: the node skeleton, the stack of open nodes, the cut into top tree
/// and pages, the page file.
class Assembler {
 public:
  Assembler(const BuildContext& ctx, const ExtBuildOptions& opt, bvhbench::AtomicOutputFile& out, std::uint64_t pages_off)
      : off_(pages_off), ctx_(ctx), opt_(opt), out_(out), L_(ctx.f.leaf_level),
        target_(std::max<std::size_t>(opt.page_target, 4096)) {
    sk.leaf_level = L_;
    stack_.reserve(std::size_t(kMaxLevel) + 2);
    stats.nodes_per_level.assign(std::size_t(L_) + 1, 0);
  }

  /// The next leaf, in Morton order.
  void add_leaf(std::uint64_t m, Node nd, Leaf lf, std::vector<LeafTri>&& tris, NodeTmp&& tm, const LeafHalves& h) {
    // Close open nodes that are not ancestors of this leaf.
    while (!stack_.empty()) {
      const Open& o = stack_.back();
      const int l = octcode_level(o.code);
      if ((m >> (3 * (L_ - l))) == octcode_morton(o.code)) break;
      close_top_of_stack();
    }
    if (stack_.empty()) {
      if (started_) throw std::logic_error("ebp extbuild: leaves out of order");
      started_ = true;
      open_node(octcode_root());
    }
    // Descend to the leaf's parent, creating nodes in pre-order.
    for (;;) {
      Open& o = stack_.back();
      const int l = octcode_level(o.code);
      const int oct = int((m >> (3 * (L_ - l - 1))) & 7u);
      if (oct < o.next_octant) throw std::logic_error("ebp extbuild: leaves out of order");
      fill_empty(stack_.size() - 1, oct);
      if (l + 1 == L_) {
        // the leaf itself
        const std::uint32_t g = new_node(octcode_child(o.code, oct), NodeKind::leaf);
        Child c;
        c.state = Child::held;
        c.gid = g;
        const auto li = std::uint32_t(sk.leaf_node.size());
        sk.index[g] = li;
        sk.leaf_node.push_back(g);
        sk.leaf_ref.push_back({lf.ref[0], lf.ref[1], lf.ref[2]});
        sk.leaf_ref_valid.push_back(lf.ref_valid);
        sk.leaf_halves.push_back(h);
        // stats
        stats.leaves++;
        stats.triangle_refs += tris.size();
        stats.max_refs_per_leaf = std::max<std::size_t>(stats.max_refs_per_leaf, tris.size());
        if (nd.config == LeafConfig::convex) ++stats.convex;
        else if (nd.config == LeafConfig::concave) ++stats.concave;
        else ++stats.special;
        stats.leaf_planes += tm.planes.size();
        stats.leaf_volume += tm.volume;
        stats.leaf_box_volume += tm.box_volume;
        stats.max_planes_per_node = std::max<std::size_t>(stats.max_planes_per_node, tm.planes.size());
        planes_total_ += tm.planes.size();
        // the leaf's fragment
        Frag& f = c.frag;
        nd.plane_begin = 0;
        nd.plane_count = std::uint16_t(tm.planes.size());
        nd.index = 0;
        nd.next = 1;
        f.nodes.push_back(nd);
        f.planes = tm.planes;
        lf.tri_begin = 0;
        f.leaves.push_back(lf);
        f.tris = std::move(tris);
        f.gid.push_back(g);
        f.bytes = node_page_bytes(NodeKind::leaf, nd.plane_count, lf.tri_count);
        c.bytes = f.bytes;
        c.tmp = std::move(tm);
        handle_child(stack_.size() - 1, oct, std::move(c));
        return;
      }
      open_node(octcode_child(o.code, oct));
    }
  }

  /// After the last leaf: closes everything (the root last).
  void finish() {
    while (!stack_.empty()) close_top_of_stack();
  }

  // --- results ---
  Skeleton sk;
  Stats stats;
  std::uint64_t planes_total_ = 0;
  std::vector<TopNode> top;
  std::vector<std::uint32_t> top_children;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> top_plane_ref;  // per top node: pool begin, count
  std::vector<Plane> top_plane_pool;
  std::vector<std::uint32_t> top_gid;  // per top node
  std::vector<PageEntry> dir;
  std::vector<std::pair<std::uint32_t, Patch>> white_loc;  // gid, where its kind byte is
  std::vector<Patch> leaf_loc;                               // per leaf: where its ref_winding is
  std::uint64_t off_;                                        // end of the pages written so far

 private:
  std::uint32_t new_node(Octcode code, NodeKind kind) {
    const auto g = std::uint32_t(sk.code.size());
    if (sk.code.size() >= 0xfffffffeull) throw std::runtime_error("ebp_octree: too many nodes");
    sk.code.push_back(code);
    sk.kind.push_back(kind);
    sk.index.push_back(0);
    stats.nodes_per_level[std::size_t(octcode_level(code))]++;
    // the parent's children entry
    if (!stack_.empty()) {
      const Open& p = stack_.back();
      sk.children[sk.index[p.gid] + std::uint32_t(octcode_octant(code))] = g;
    }
    return g;
  }

  void open_node(Octcode code) {
    const std::uint32_t g = new_node(code, NodeKind::inner);
    sk.index[g] = std::uint32_t(sk.children.size());
    sk.children.resize(sk.children.size() + 8, 0);
    stack_.emplace_back();
    stack_.back().gid = g;
    stack_.back().code = code;
    stats.inner++;
  }

  /// Empty children of stack_[d] at octants [next_octant, upto).
  void fill_empty(std::size_t d, int upto) {
    while (stack_[d].next_octant < upto) {
      const int oct = stack_[d].next_octant;
      const Octcode code = octcode_child(stack_[d].code, oct);
      const std::uint32_t g = new_node(code, NodeKind::white);
      Child c;
      c.state = Child::empty;
      c.gid = g;
      Node nd{};
      nd.code = code;
      nd.kind = NodeKind::white;
      nd.config = LeafConfig::special;
      nd.next = 1;
      c.frag.nodes.push_back(nd);
      c.frag.gid.push_back(g);
      c.frag.bytes = node_page_bytes(NodeKind::white, 0, 0);
      c.bytes = c.frag.bytes;
      handle_child(d, oct, std::move(c));
    }
  }

  void close_top_of_stack() {
    const std::size_t d = stack_.size() - 1;
    fill_empty(d, 8);
    Open& X = stack_[d];
    NodeTmp* ch[8];
    for (int o = 0; o < 8; ++o)
      ch[o] = (X.ch[o].state == Child::held || X.ch[o].state == Child::top) && sk.kind[X.ch[o].gid] != NodeKind::white
                  ? &X.ch[o].tmp
                  : nullptr;
    NodeTmp tm;
    build_inner(ctx_, X.code, ch, &tm);
    for (int o = 0; o < 8; ++o) X.ch[o].tmp = NodeTmp();
    stats.inner_planes += tm.planes.size();
    stats.inner_volume += tm.volume;
    stats.inner_box_volume += tm.box_volume;
    stats.max_planes_per_node = std::max<std::size_t>(stats.max_planes_per_node, tm.planes.size());
    planes_total_ += tm.planes.size();
    const std::uint64_t bytes = node_page_bytes(NodeKind::inner, std::uint32_t(tm.planes.size()), 0) + X.partial;
    if (!X.top && bytes > target_) make_top(d);
    Child c;
    c.gid = X.gid;
    c.bytes = bytes;
    if (X.top) {
      flush_group(d);
      top_plane_ref[X.top_index] = {std::uint32_t(top_plane_pool.size()), std::uint32_t(tm.planes.size())};
      top_plane_pool.insert(top_plane_pool.end(), tm.planes.begin(), tm.planes.end());
      c.state = Child::top;
    } else {
      c.state = Child::held;
      Frag& f = c.frag;
      Node nd{};
      nd.code = X.code;
      nd.plane_begin = 0;
      nd.plane_count = std::uint16_t(tm.planes.size());
      nd.kind = NodeKind::inner;
      nd.config = LeafConfig::special;
      nd.index = 0;
      f.nodes.push_back(nd);
      f.gid.push_back(X.gid);
      f.planes = tm.planes;
      f.children.resize(8);
      for (int o = 0; o < 8; ++o) {
        f.children[std::size_t(o)] = std::uint32_t(f.nodes.size());
        f.append(X.ch[o].frag);
      }
      f.nodes[0].next = std::uint32_t(f.nodes.size());
      f.bytes = bytes;
    }
    c.tmp = std::move(tm);
    const int oct = octcode_octant(X.code);
    const bool root = d == 0;
    stack_.pop_back();
    if (root) {
      if (c.state == Child::held) {  // the whole tree fits one page
        const std::uint32_t k = push_top(X_root_code(), TopKind::page, c.gid, &c.frag);
        std::vector<Frag> g;
        g.push_back(std::move(c.frag));
        write_page(kNoParent, g, {0}, {k});
      }
      return;
    }
    handle_child(d - 1, oct, std::move(c));
  }
  static Octcode X_root_code() { return octcode_root(); }

  void handle_child(std::size_t d, int oct, Child&& c) {
    Open& P = stack_[d];
    P.ch[oct] = std::move(c);
    P.next_octant = oct + 1;
    P.partial += P.ch[oct].bytes;
    if (P.top) top_take(d, oct);
    else if (P.partial > target_) make_top(d);
  }

  std::uint32_t push_top(Octcode code, TopKind kind, std::uint32_t gid, const Frag* f) {
    TopNode tn{};
    tn.code = code;
    tn.kind = kind;
    top.push_back(tn);
    top_gid.push_back(gid);
    if (f && kind == TopKind::page) {
      const Node& r = f->nodes[0];
      top_plane_ref.push_back({std::uint32_t(top_plane_pool.size()), r.plane_count});
      top_plane_pool.insert(top_plane_pool.end(), f->planes.begin() + r.plane_begin,
                            f->planes.begin() + r.plane_begin + r.plane_count);
    } else {
      top_plane_ref.push_back({0, 0});
    }
    return std::uint32_t(top.size() - 1);
  }

  /// stack_[d] is found to be above the cut (its subtree exceeds the page target).
  void make_top(std::size_t d) {
    Open& X = stack_[d];
    if (X.top) return;
    std::uint32_t k;
    if (d > 0) {
      make_top(d - 1);
      flush_group(d - 1);  // keep the pages in octcode order
      k = push_top(X.code, TopKind::inner, X.gid, nullptr);
      top_children[stack_[d - 1].top_cb + std::uint32_t(octcode_octant(X.code))] = k;
    } else {
      k = push_top(X.code, TopKind::inner, X.gid, nullptr);
    }
    X.top = true;
    X.top_index = k;
    X.top_cb = std::uint32_t(top_children.size());
    top[k].index = X.top_cb;
    top_children.resize(top_children.size() + 8, 0);
    for (int o = 0; o < X.next_octant; ++o) top_take(d, o);
  }

  /// Child `oct` of the top node stack_[d], in octant order (plan_pages' make_top loop).
  void top_take(std::size_t d, int oct) {
    Open& P = stack_[d];
    Child& c = P.ch[oct];
    if (c.state == Child::empty) {
      top_children[P.top_cb + std::uint32_t(oct)] = push_top(octcode_child(P.code, oct), TopKind::white, c.gid, nullptr);
      c.frag = Frag();
    } else if (c.state == Child::held) {
      if (!P.group.empty() && P.group_bytes + c.bytes > target_) flush_group(d);
      const std::uint32_t k = push_top(octcode_child(P.code, oct), TopKind::page, c.gid, &c.frag);
      top_children[P.top_cb + std::uint32_t(oct)] = k;
      P.group.push_back(std::move(c.frag));
      c.frag = Frag();
      P.group_octants.push_back(std::uint32_t(oct));
      P.group_tops.push_back(k);
      P.group_bytes += c.bytes;
    }
    // top: already in the top tree
  }

  void flush_group(std::size_t d) {
    Open& P = stack_[d];
    if (P.group.empty()) return;
    write_page(P.code, P.group, P.group_octants, P.group_tops);
    P.group.clear();
    P.group_octants.clear();
    P.group_tops.clear();
    P.group_bytes = 0;
  }

  /// One page from fragments, encoded by the page codec that the in-memory writer uses too.
  void write_page(Octcode parent, std::vector<Frag>& g, const std::vector<std::uint32_t>& octants,
                  const std::vector<std::uint32_t>& tops) {
    const auto id = std::uint32_t(dir.size());
    if (opt_.before_page) opt_.before_page(id);
    if (opt_.check) opt_.check();
    Frag all;
    PageArrays a;
    for (std::size_t i = 0; i < g.size(); ++i) {
      a.roots.push_back({octants[i], std::uint32_t(all.nodes.size())});
      all.append(g[i]);
    }
    a.nodes = std::move(all.nodes);
    a.children = std::move(all.children);
    a.planes = std::move(all.planes);
    a.leaves = std::move(all.leaves);
    a.tris = std::move(all.tris);
    PageEntry e{};
    const EncodedPage page = encode_page(a, id, parent, &e);
    const std::vector<std::uint8_t>& out = page.bytes;
    const std::size_t nodes_at = page.nodes_offset, leaves_at = page.leaves_offset;
    e.offset = off_;
    out_.write_at(off_, out.data(), out.size());
    off_ = (off_ + out.size() + kPageAlign - 1) / kPageAlign * kPageAlign;
    dir.push_back(e);
    for (std::uint32_t k : tops) top[k].index = id;
    // Where the colouring will go.
    for (std::size_t i = 0; i < a.nodes.size(); ++i) {
      const Node& nd = a.nodes[i];
      if (nd.kind == NodeKind::white) {
        Patch p{};
        p.page = id;
        p.off = std::uint32_t(nodes_at + i * sizeof(Node) + offsetof(Node, kind));
        white_loc.push_back({all.gid[i], p});
      } else if (nd.kind == NodeKind::leaf) {
        Patch p{};
        p.page = id;
        p.off = std::uint32_t(leaves_at + std::size_t(nd.index) * sizeof(Leaf) + offsetof(Leaf, ref_winding));
        const std::uint32_t li = sk.index[all.gid[i]];
        if (leaf_loc.size() <= li) leaf_loc.resize(li + 1);
        leaf_loc[li] = p;
      }
    }
  }

  const BuildContext& ctx_;
  const ExtBuildOptions& opt_;
  bvhbench::AtomicOutputFile& out_;
  int L_;
  std::uint64_t target_;
  std::vector<Open> stack_;
  bool started_ = false;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
std::unique_ptr<TriangleSource> make_memory_source(const std::vector<Vec3d>& vertices,
                                                   const std::vector<std::array<std::uint32_t, 3>>& triangles) {
  return std::make_unique<MemorySource>(vertices, triangles);
}

std::unique_ptr<TriangleSource> open_mesh_source(const std::string& path) { return std::make_unique<FileSource>(path); }

namespace {

std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// src.scan() in a producer thread (parsing the file), the chunks handed to `fn` in this thread
/// through a queue of at most 3 chunks: parsing overlaps the work on the previous chunk.
void prefetch_scan(TriangleSource& src, const TriangleSource::Chunk& fn) {
  struct Buf {
    std::uint64_t first = 0;
    std::size_t n = 0;
    std::vector<std::uint32_t> idx;
    std::vector<float> xyz;
  };
  struct Abort {};
  std::mutex mu;
  std::condition_variable cv;
  std::deque<Buf> q;
  std::vector<Buf> spare;
  bool done = false, stop = false;
  std::exception_ptr err;
  std::thread prod([&] {
    try {
      src.scan([&](std::uint64_t first, std::size_t n, const std::uint32_t* idx, const float* xyz) {
        Buf b;
        {
          std::unique_lock<std::mutex> lk(mu);
          cv.wait(lk, [&] { return q.size() < 3 || stop; });
          if (stop) throw Abort{};
          if (!spare.empty()) {
            b = std::move(spare.back());
            spare.pop_back();
          }
        }
        b.first = first;
        b.n = n;
        b.idx.assign(idx, idx + 3 * n);
        b.xyz.assign(xyz, xyz + 9 * n);
        {
          std::lock_guard<std::mutex> lk(mu);
          q.push_back(std::move(b));
        }
        cv.notify_all();
      });
    } catch (const Abort&) {
    } catch (...) {
      err = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lk(mu);
      done = true;
    }
    cv.notify_all();
  });
  try {
    for (;;) {
      Buf b;
      {
        std::unique_lock<std::mutex> lk(mu);
        cv.wait(lk, [&] { return !q.empty() || done; });
        if (q.empty()) break;
        b = std::move(q.front());
        q.pop_front();
      }
      cv.notify_all();
      fn(b.first, b.n, b.idx.data(), b.xyz.data());
      std::lock_guard<std::mutex> lk(mu);
      spare.push_back(std::move(b));
    }
  } catch (...) {
    {
      std::lock_guard<std::mutex> lk(mu);
      stop = true;
    }
    cv.notify_all();
    prod.join();
    throw;
  }
  prod.join();
  if (err) std::rethrow_exception(err);
}

/// Removes its files on scope exit.
struct TempFiles {
  std::vector<std::string> paths;
  ~TempFiles() {
    for (const std::string& p : paths) ::unlink(p.c_str());
  }
};

}  // namespace

ExtBuildReport build_store_external(TriangleSource& src, const std::string& path, const ExtBuildOptions& opt) {
  const auto t_start = Clock::now();
  ExtBuildReport R;
  const BuildParams& prm = opt.params;
  const int threads = std::max(1, prm.threads);
  auto progress = [&](const char* phase, double f) {
    if (opt.progress) opt.progress(phase, f);
  };
  auto check = [&] {
    if (opt.check) opt.check();
  };
  tbb::task_arena arena(threads);

  // ---- 1. frame (streaming): bounding box, average edge, closedness, sha256 ----
  auto t0 = Clock::now();
  FrameAccumulator acc;
  std::uint64_t s1 = 0, s2 = 0;
  const bool check_closed = src.num_vertices() < (std::uint64_t(1) << 31);
  {
    // Per chunk, in parallel: each triangle's edge-length sum (the very expression
    // FrameAccumulator::add adds), per-block boxes and closedness sums; then the edge sums are
    // added in input order, so the total is the in-memory build's double, bit for bit.
    constexpr std::size_t kBlock = 4096;
    std::vector<double> edge(kChunk);
    std::vector<Box3d> boxes(kChunk / kBlock + 1);
    std::vector<std::uint64_t> h1(kChunk / kBlock + 1), h2(kChunk / kBlock + 1);
    prefetch_scan(src, [&](std::uint64_t first, std::size_t n, const std::uint32_t* idx, const float* xyz) {
      if (edge.size() < n) {
        edge.resize(n);
        boxes.resize(n / kBlock + 1);
        h1.resize(n / kBlock + 1);
        h2.resize(n / kBlock + 1);
      }
      const std::size_t nb = (n + kBlock - 1) / kBlock;
      auto block = [&](std::size_t bi) {
        Box3d bb;
        std::uint64_t a1 = 0, a2 = 0;
        for (std::size_t i = bi * kBlock; i < std::min(n, (bi + 1) * kBlock); ++i) {
          const float* v = xyz + 9 * i;
          const Vec3d a{v[0], v[1], v[2]}, b{v[3], v[4], v[5]}, c{v[6], v[7], v[8]};
          bb.add(a); bb.add(b); bb.add(c);
          edge[i] = norm(b - a) + norm(c - b) + norm(a - c);
          if (check_closed)
            for (int k = 0; k < 3; ++k) {
              const std::uint64_t u = idx[3 * i + std::size_t(k)], w = idx[3 * i + std::size_t((k + 1) % 3)];
              if (u == w) continue;
              a1 += mix64(u << 32 | w) - mix64(w << 32 | u);
              a2 += mix64((w << 32 | u) ^ 0x5851f42d4c957f2dull) - mix64((u << 32 | w) ^ 0x5851f42d4c957f2dull);
            }
        }
        boxes[bi] = bb;
        h1[bi] = a1;
        h2[bi] = a2;
      };
      arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 1), [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t bi = r.begin(); bi != r.end(); ++bi) block(bi);
        });
      });
      for (std::size_t bi = 0; bi < nb; ++bi) {
        acc.bb.add(boxes[bi]);
        s1 += h1[bi];
        s2 += h2[bi];
      }
      for (std::size_t i = 0; i < n; ++i) acc.edge_sum += edge[i];
      acc.triangles += n;
      if ((first / kChunk) % 16 == 0) {
        check();
        if (src.num_triangles()) progress("frame", std::min(0.05, 0.05 * double(first) / double(src.num_triangles())));
      }
    });
  }
  const std::uint64_t nt = acc.triangles;
  if (nt == 0) throw std::invalid_argument("ebp_octree: the mesh has no triangle");
  if (nt >= (1ull << 31)) throw std::invalid_argument("ebp_octree: more than 2^31 triangles");
  R.closed = check_closed && s1 == 0 && s2 == 0;
  const Frame F = compute_frame(acc, prm);
  const BuildContext ctx(F, prm);
  const int L = F.leaf_level;
  R.seconds_frame = since(t0);
  progress("frame", 0.05);

  // Memory plan: the source's resident bytes and a fixed reserve come first; the rest goes to the
  // sort runs (phase 2), then to the merge buffers and the leaf batches (phase 3).
  // Also set aside what grows with the model and is kept to the end: the node skeleton, the
  // union-find, the top tree and the patch list, ≈ 2.2 B per triangle measured on the 32M
  // models (at the default leaf_factor); 3 B per triangle is reserved.
  const std::size_t reserve = (std::size_t(48) << 20) + std::size_t(3 * nt);
  const std::size_t resident = src.resident_bytes();
  R.min_budget_bytes = resident + reserve + (std::size_t(8) << 20);
  std::size_t avail = opt.memory_budget > resident + reserve ? opt.memory_budget - resident - reserve : 0;
  avail = std::max<std::size_t>(avail, std::size_t(8) << 20);
  std::size_t run_cap = (opt.run_bytes ? opt.run_bytes : avail / 2) / sizeof(Rec);
  run_cap = std::max<std::size_t>(run_cap, 64);
  R.run_capacity_records = run_cap;

  // ---- 2. distribution into sorted runs ----
  t0 = Clock::now();
  TempFiles run_files;
  std::vector<RunFile> runs;
  std::vector<Rec> run;
  run.reserve(std::min<std::size_t>(run_cap, std::size_t(nt) * 3 + 64));
  auto sort_run = [&] {
    arena.execute([&] { tbb::parallel_sort(run.begin(), run.end(), RecLess()); });
  };
  auto spill = [&] {
    if (run.empty()) return;
    sort_run();
    RunFile rf;
    rf.path = opt.tmp_dir + "/run-" + std::to_string(runs.size()) + ".bin";
    run_files.paths.push_back(rf.path);
    const int fd = ::open(rf.path.c_str(), O_CREAT | O_TRUNC | O_WRONLY | O_CLOEXEC, 0600);
    if (fd < 0) io::fail(rf.path, "cannot create a temporary file");
    try {
      pwrite_all(fd, rf.path, run.data(), run.size() * sizeof(Rec), 0);
    } catch (...) {
      ::close(fd);
      throw;
    }
    if (::close(fd) != 0) io::fail(rf.path, "close failed");
    rf.records = run.size();
    R.spill_bytes += run.size() * sizeof(Rec);
    runs.push_back(rf);
    run.clear();
  };
  {
    tbb::enumerable_thread_specific<std::vector<Rec>> local;
    tbb::enumerable_thread_specific<std::vector<std::uint64_t>> local_ms;
    prefetch_scan(src, [&](std::uint64_t first, std::size_t n, const std::uint32_t* idx, const float* xyz) {
      check();
      arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
          auto& out = local.local();
          auto& ms = local_ms.local();
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const float* v = xyz + 9 * i;
            ms.clear();
            distribute_triangle(ctx, {v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]}, ms);
            Rec rec;
            rec.t = std::uint32_t(first + i);
            std::memcpy(rec.v, idx + 3 * i, sizeof rec.v);
            for (std::uint64_t m : ms) {
              rec.m = m;
              out.push_back(rec);
            }
          }
        });
      });
      for (auto& v : local) {
        std::size_t k = 0;
        while (k < v.size()) {
          if (run.size() == run_cap) spill();
          const std::size_t take = std::min(v.size() - k, run_cap - run.size());
          run.insert(run.end(), v.begin() + std::ptrdiff_t(k), v.begin() + std::ptrdiff_t(k + take));
          k += take;
        }
        R.records += v.size();
        v.clear();
      }
      progress("distributing", 0.05 + 0.3 * double(first + n) / double(nt));
    });
    for (auto& v : local) std::vector<Rec>().swap(v);
  }
  if (!runs.empty()) {
    spill();
    std::vector<Rec>().swap(run);
  } else {
    sort_run();
  }
  R.runs = runs.empty() ? 1 : runs.size();
  R.seconds_distribute = since(t0);
  check();

  // ---- 3. merge; leaves in batches (parallel), inner nodes and pages as subtrees complete ----
  t0 = Clock::now();
  bvhbench::AtomicOutputFile out(path);  // path + ".tmp" until committed, removed on failure
  Assembler as(ctx, opt, out, kPageAlign);
  {
    std::vector<std::unique_ptr<RunReader>> readers;
    const std::size_t merge_bytes = avail / 4;
    for (const RunFile& rf : runs)
      readers.push_back(std::make_unique<RunReader>(rf, merge_bytes / std::max<std::size_t>(1, runs.size()) / sizeof(Rec)));
    struct HeapEnt {
      std::uint64_t m;
      std::uint32_t t, run;
      bool operator>(const HeapEnt& o) const { return m > o.m || (m == o.m && t > o.t); }
    };
    std::priority_queue<HeapEnt, std::vector<HeapEnt>, std::greater<HeapEnt>> heap;
    for (std::uint32_t i = 0; i < readers.size(); ++i)
      if (const Rec* r = readers[i]->peek()) heap.push({r->m, r->t, i});
    std::size_t mem_pos = 0;
    auto next = [&](Rec* out_rec) -> bool {
      if (runs.empty()) {
        if (mem_pos == run.size()) return false;
        *out_rec = run[mem_pos++];
        return true;
      }
      if (heap.empty()) return false;
      const HeapEnt h = heap.top();
      heap.pop();
      *out_rec = *readers[h.run]->peek();
      readers[h.run]->pop();
      if (const Rec* r = readers[h.run]->peek()) heap.push({r->m, r->t, h.run});
      return true;
    };
    // Leaves are built in batches (in parallel); a second thread feeds the built batches to the
    // assembler (inner nodes, the cut, page writes) while the next batch is being built: at most
    // 3 batches alive (built, queued, assembling), each ≈ avail/12.
    const float* vf = src.float_vertices();
    const std::size_t batch_cap = std::max<std::size_t>(4096, (avail / 12) / (sizeof(Rec) + sizeof(LeafTri) + 64));
    struct Built {
      std::vector<std::uint64_t> m;
      std::vector<Node> nodes;
      std::vector<Leaf> leaves;
      std::vector<std::vector<LeafTri>> blocks;
      std::vector<NodeTmp> tmps;
      std::vector<LeafHalves> halves;
    };
    std::mutex mu;
    std::condition_variable cv;
    std::deque<Built> queue;
    bool closing = false, failed = false;
    std::exception_ptr asm_err;
    std::thread assembler([&] {
      try {
        for (;;) {
          Built bt;
          {
            std::unique_lock<std::mutex> lk(mu);
            cv.wait(lk, [&] { return !queue.empty() || closing; });
            if (queue.empty()) break;
            bt = std::move(queue.front());
            queue.pop_front();
          }
          cv.notify_all();
          for (std::size_t i = 0; i < bt.m.size(); ++i)
            as.add_leaf(bt.m[i], bt.nodes[i], bt.leaves[i], std::move(bt.blocks[i]), std::move(bt.tmps[i]), bt.halves[i]);
        }
        bool f;
        {
          std::lock_guard<std::mutex> lk(mu);
          f = failed;
        }
        if (!f) as.finish();
      } catch (...) {
        std::lock_guard<std::mutex> lk(mu);
        asm_err = std::current_exception();
        failed = true;
      }
      cv.notify_all();
    });
    auto stop_assembler = [&] {
      {
        std::lock_guard<std::mutex> lk(mu);
        closing = true;
      }
      cv.notify_all();
      assembler.join();
    };
    try {
      std::vector<Rec> batch;
      std::vector<std::size_t> starts;
      std::uint64_t consumed = 0;
      auto process = [&] {
        const std::size_t nl = starts.size();
        starts.push_back(batch.size());
        Built bt;
        bt.m.resize(nl);
        bt.nodes.resize(nl);
        bt.leaves.resize(nl);
        bt.blocks.resize(nl);
        bt.tmps.resize(nl);
        bt.halves.resize(nl);
        auto one = [&](std::size_t i) {
          const std::size_t b = starts[i], e = starts[i + 1];
          std::vector<std::uint32_t> tri(e - b);
          std::vector<float> xyz(9 * (e - b));
          for (std::size_t k = b; k < e; ++k) {
            tri[k - b] = batch[k].t;
            for (int c = 0; c < 3; ++c) std::memcpy(&xyz[9 * (k - b) + 3 * std::size_t(c)], vf + 3 * std::size_t(batch[k].v[c]), 12);
          }
          bt.blocks[i].resize(e - b);
          bt.m[i] = batch[b].m;
          const Octcode code = octcode_make(L, batch[b].m);
          build_leaf(ctx, code, e - b, tri.data(), xyz.data(), &bt.nodes[i], &bt.leaves[i], bt.blocks[i].data(),
                     &bt.tmps[i], &bt.halves[i]);
        };
        if (threads <= 1 || nl < 2) {
          for (std::size_t i = 0; i < nl; ++i) one(i);
        } else {
          arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nl, 1), [&](const tbb::blocked_range<std::size_t>& r) {
              for (std::size_t i = r.begin(); i != r.end(); ++i) one(i);
            });
          });
        }
        {
          std::unique_lock<std::mutex> lk(mu);
          cv.wait(lk, [&] { return queue.size() < 1 || failed; });
          if (failed) return;
          queue.push_back(std::move(bt));
        }
        cv.notify_all();
        consumed += batch.size();
        batch.clear();
        starts.clear();
        check();
        progress("building", 0.35 + 0.6 * double(consumed) / double(std::max<std::uint64_t>(1, R.records)));
      };
      Rec r;
      while (next(&r)) {
        if (batch.empty() || batch.back().m != r.m) {
          if (batch.size() >= batch_cap) {
            process();
            if (failed) break;
          }
          starts.push_back(batch.size());
        }
        batch.push_back(r);
      }
      if (!batch.empty() && !failed) process();
      std::vector<Rec>().swap(run);
    } catch (...) {
      {
        std::lock_guard<std::mutex> lk(mu);
        failed = true;
        queue.clear();
      }
      stop_assembler();
      throw;
    }
    stop_assembler();
    if (asm_err) std::rethrow_exception(asm_err);
  }
  R.seconds_merge_build = since(t0);
  // The runs are no longer needed.
  for (const std::string& p : run_files.paths) ::unlink(p.c_str());
  run_files.paths.clear();

  // ---- 4. colouring over the skeleton, patched into the pages and the top tree ----
  t0 = Clock::now();
  progress("colouring", 0.95);
  Skeleton& sk = as.sk;
  R.skeleton_bytes = sk.bytes();
  auto winding_at = [&](const std::vector<Vec3d>& pts) {
    std::vector<double> w(pts.size(), 0.0);
    src.scan([&](std::uint64_t, std::size_t n, const std::uint32_t*, const float* xyz) {
      for (std::size_t i = 0; i < n; ++i) {
        const float* v = xyz + 9 * i;
        const Vec3d a{v[0], v[1], v[2]}, b{v[3], v[4], v[5]}, c{v[6], v[7], v[8]};
        for (std::size_t k = 0; k < pts.size(); ++k) w[k] += bvhbench::triangle_winding(pts[k], a, b, c);
      }
    });
    std::vector<int> out;
    for (double x : w) out.push_back(int(std::lround(x)));
    return out;
  };
  const Colouring C = colour(F, sk, winding_at);
  const std::size_t N = sk.code.size();
  std::vector<std::uint8_t> is_black(N, 0);
  for (std::uint32_t i : C.black) is_black[i] = 1;
  std::vector<Patch> patches;
  for (const auto& [g, p] : as.white_loc)
    if (is_black[g]) {
      Patch q = p;
      q.len = 1;
      q.b[0] = std::uint8_t(NodeKind::black);
      patches.push_back(q);
    }
  for (std::size_t li = 0; li < as.leaf_loc.size(); ++li)
    if (C.ref_winding[li] != 0) {
      Patch q = as.leaf_loc[li];
      q.len = 2;
      std::memcpy(q.b, &C.ref_winding[li], 2);
      patches.push_back(q);
    }
  std::sort(patches.begin(), patches.end(),
            [](const Patch& a, const Patch& b) { return a.page < b.page || (a.page == b.page && a.off < b.off); });
  {
    // CRC-32C is affine in the message: crc(x ^ d) = crc(x) ^ crc(d) ^ crc(0...0) (same length),
    // and the patched fields are zero before: the new checksum needs only the patch bytes.
    std::vector<std::uint8_t> zero;
    std::uint32_t zero_crc = 0;
    std::size_t zero_len = SIZE_MAX;
    for (std::size_t i = 0; i < patches.size();) {
      std::size_t j = i;
      PageEntry& e = as.dir[patches[i].page];
      if (zero.size() < e.size) zero.resize(e.size, 0);
      if (zero_len != e.size) {
        zero_crc = crc32c(zero.data(), e.size);
        zero_len = e.size;
      }
      for (; j < patches.size() && patches[j].page == patches[i].page; ++j)
        std::memcpy(&zero[patches[j].off], patches[j].b, patches[j].len);
      e.crc ^= crc32c(zero.data(), e.size) ^ zero_crc;
      for (std::size_t k = i; k < j; ++k) {
        out.write_at(e.offset + patches[k].off, patches[k].b, patches[k].len);
        std::memset(&zero[patches[k].off], 0, patches[k].len);
      }
      i = j;
    }
  }
  for (std::size_t k = 0; k < as.top.size(); ++k)
    if (as.top[k].kind == TopKind::white && is_black[as.top_gid[k]]) as.top[k].kind = TopKind::black;
  std::vector<Plane> top_planes;
  for (std::size_t k = 0; k < as.top.size(); ++k) {
    as.top[k].plane_begin = std::uint32_t(top_planes.size());
    as.top[k].plane_count = std::uint16_t(as.top_plane_ref[k].second);
    top_planes.insert(top_planes.end(), as.top_plane_pool.begin() + as.top_plane_ref[k].first,
                      as.top_plane_pool.begin() + as.top_plane_ref[k].first + as.top_plane_ref[k].second);
  }
  R.seconds_colour = since(t0);

  // ---- 5. stats, the sections after the pages, the header ----
  Stats& S = as.stats;
  S.leaf_level = L;
  S.root_size = F.root_size;
  S.leaf_size = ctx.cs;
  S.average_edge = F.average_edge;
  S.triangles = nt;
  S.nodes = N;
  S.planes = as.planes_total_;
  S.colour_fallbacks = C.colour_fallbacks;
  S.degenerate_edges = C.degenerate_edges;
  S.invalid_refs = C.invalid_refs;
  for (std::size_t i = 0; i < N; ++i)
    if (sk.kind[i] == NodeKind::white) ++(is_black[i] ? S.black : S.white);
  S.seconds_distribute = R.seconds_distribute;
  S.seconds_colour = R.seconds_colour;
  S.build_seconds = since(t_start);
  R.stats = S;
  R.pages = as.dir.size();
  R.top_nodes = as.top.size();

  FileHeader h{};
  std::memcpy(h.magic, kStoreMagic, 8);
  h.version = kStoreVersion;
  h.header_size = sizeof(FileHeader);
  for (int k = 0; k < 3; ++k) h.root_lo[k] = F.root_lo[k];
  h.root_size = F.root_size;
  h.leaf_level = std::uint32_t(L);
  h.num_triangles = std::uint32_t(nt);
  h.leaf_factor = prm.leaf_factor;
  h.cluster_angle = prm.cluster_angle;
  h.max_planes = prm.max_planes;
  h.page_target = std::uint32_t(std::max<std::size_t>(opt.page_target, 4096));
  h.flags = R.closed ? kStoreClosed : 0;
  h.nodes = N;
  h.inner = S.inner;
  h.leaves = S.leaves;
  h.white = S.white;
  h.black = S.black;
  h.triangle_refs = S.triangle_refs;
  h.planes = S.planes;
  h.num_pages = as.dir.size();
  h.num_top_nodes = as.top.size();
  h.num_top_children = as.top_children.size();
  h.num_top_planes = top_planes.size();
  h.pages.offset = kPageAlign;
  h.pages.size = as.off_ - kPageAlign;
  h.pages.crc = 0;  // each page has its own checksum (in the directory)
  std::uint64_t off = as.off_;
  auto section = [&](const void* data, std::size_t n, Section* s) {
    s->offset = off;
    s->size = n;
    s->crc = crc32c(data, n);
    if (n) out.write_at(off, data, n);
    off = (off + n + 7) / 8 * 8;
  };
  section(as.dir.data(), as.dir.size() * sizeof(PageEntry), &h.directory);
  section(as.top.data(), as.top.size() * sizeof(TopNode), &h.top_nodes);
  section(as.top_children.data(), as.top_children.size() * sizeof(std::uint32_t), &h.top_children);
  section(top_planes.data(), top_planes.size() * sizeof(Plane), &h.top_planes);
  const std::string info = opt.info_json ? opt.info_json(R) : std::string("{}");
  section(info.data(), info.size(), &h.info);
  h.file_size = h.info.offset + h.info.size;
  out.resize(h.file_size);
  h.header_crc = 0;
  h.header_crc = crc32c(&h, sizeof h);
  out.write_at(0, &h, sizeof h);
  R.file_bytes = h.file_size;
  check();
  out.commit_durable();
  R.seconds_total = since(t_start);
  progress("done", 1.0);
  return R;
}

}  // namespace ebp
