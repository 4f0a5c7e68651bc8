#pragma once
/// The external build's assembler: takes the built leaves in Morton order, keeps the stack of open
/// nodes, builds each inner node when its last child is done (build_inner, the in-memory
/// builder's code), decides the cut into top tree and pages as plan_pages() does for an in-memory
/// tree, and writes each page (the page codec) as soon as its subtrees are complete. The
/// colouring's patch locations are recorded for the end of the build.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "harness/util/atomic_file.hpp"
#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/build/external_build.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/page_codec.hpp"

namespace ebp::detail {

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

}  // namespace ebp::detail
