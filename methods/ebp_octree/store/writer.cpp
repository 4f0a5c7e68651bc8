// The `.ebp` writer (writer.hpp): plans the cut of an in-memory Octree into a pinned top tree
// and pages, encodes each page (page_codec.hpp) and writes the file. See OUT_OF_CORE.md.
#include "methods/ebp_octree/store/writer.hpp"

#include <algorithm>
#include <cstring>
#include <functional>
#include <stdexcept>

#include "harness/util/atomic_file.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/page_codec.hpp"
#include "methods/ebp_octree/store/store_file.hpp"

namespace ebp {

namespace {

std::uint64_t align_up(std::uint64_t v, std::uint64_t a) { return (v + a - 1) / a * a; }

/// The cut of the tree into a pinned top and pages (subtrees packed by parent).
struct PageSpec {
  Octcode parent;
  std::vector<PageRoot> roots;  // octant, node index in the original tree
};

struct Plan {
  std::vector<TopNode> top;
  std::vector<std::uint32_t> top_children;
  std::vector<Plane> top_planes;
  std::vector<PageSpec> pages;
};

std::uint64_t node_own_bytes(const Octree& t, const Node& nd) {
  std::uint64_t b = sizeof(Node) + sizeof(Plane) * nd.plane_count;
  if (nd.kind == NodeKind::inner) b += 8 * sizeof(std::uint32_t);
  if (nd.kind == NodeKind::leaf)
    b += sizeof(Leaf) + std::uint64_t(t.leaves[nd.index].tri_count) * (sizeof(LeafTri) + sizeof(std::uint32_t));
  return b;
}

std::uint64_t subtree_bytes(const Octree& t, std::uint32_t i, std::vector<std::uint64_t>& memo) {
  const Node& nd = t.nodes[i];
  std::uint64_t b = node_own_bytes(t, nd);
  if (nd.kind == NodeKind::inner)
    for (int o = 0; o < 8; ++o) b += subtree_bytes(t, t.children[nd.index + std::uint32_t(o)], memo);
  memo[i] = b;
  return b;
}

std::uint32_t push_top(Plan& P, const Octree& t, std::uint32_t i, TopKind kind, std::uint32_t index) {
  const Node& nd = t.nodes[i];
  TopNode tn{};
  tn.code = nd.code;
  tn.plane_begin = std::uint32_t(P.top_planes.size());
  tn.plane_count = (kind == TopKind::inner || kind == TopKind::page) ? nd.plane_count : 0;
  for (std::uint32_t k = 0; k < tn.plane_count; ++k) P.top_planes.push_back(t.planes[nd.plane_begin + k]);
  tn.kind = kind;
  tn.index = index;
  P.top.push_back(tn);
  return std::uint32_t(P.top.size() - 1);
}

std::uint32_t make_top(Plan& P, const Octree& t, std::uint32_t i, const std::vector<std::uint64_t>& memo,
                       std::uint64_t target) {
  const Node& nd = t.nodes[i];
  const std::uint32_t cb = std::uint32_t(P.top_children.size());
  const std::uint32_t me = push_top(P, t, i, TopKind::inner, cb);
  P.top_children.resize(cb + 8);
  PageSpec group{nd.code, {}};
  std::vector<std::uint32_t> group_top;
  std::uint64_t group_bytes = 0;
  auto flush = [&] {
    if (group.roots.empty()) return;
    const auto id = std::uint32_t(P.pages.size());
    for (std::uint32_t k : group_top) P.top[k].index = id;
    P.pages.push_back(group);
    group.roots.clear();
    group_top.clear();
    group_bytes = 0;
  };
  for (std::uint32_t o = 0; o < 8; ++o) {
    const std::uint32_t c = t.children[nd.index + o];
    const Node& cn = t.nodes[c];
    if (cn.kind == NodeKind::white || cn.kind == NodeKind::black) {
      P.top_children[cb + o] = push_top(P, t, c, cn.kind == NodeKind::white ? TopKind::white : TopKind::black, 0);
    } else if (cn.kind == NodeKind::inner && memo[c] > target) {
      flush();  // keep the pages in octcode order
      P.top_children[cb + o] = make_top(P, t, c, memo, target);
    } else {
      if (!group.roots.empty() && group_bytes + memo[c] > target) flush();
      group.roots.push_back({o, c});
      group_bytes += memo[c];
      const std::uint32_t k = push_top(P, t, c, TopKind::page, 0);
      group_top.push_back(k);
      P.top_children[cb + o] = k;
    }
  }
  flush();
  return me;
}

Plan plan_pages(const Octree& t, std::uint64_t target) {
  Plan P;
  std::vector<std::uint64_t> memo(t.nodes.size(), 0);
  const std::uint64_t total = subtree_bytes(t, 0, memo);
  if (t.nodes[0].kind != NodeKind::inner || total <= target) {
    push_top(P, t, 0, TopKind::page, 0);
    P.pages.push_back({kNoParent, {{0, 0}}});
  } else {
    make_top(P, t, 0, memo, target);
  }
  return P;
}

/// The arrays of one page of the plan (its subtrees copied in pre-order, page-local indices).
PageArrays page_arrays(const Octree& t, const PageSpec& spec) {
  PageArrays a;
  std::vector<Node>& nodes = a.nodes;
  std::vector<std::uint32_t>& children = a.children;
  std::vector<Plane>& planes = a.planes;
  std::vector<Leaf>& leaves = a.leaves;
  std::vector<LeafTri>& tris = a.tris;
  // Pre-order copy of a subtree with page-local indices.
  std::function<std::uint32_t(std::uint32_t)> emit = [&](std::uint32_t i) -> std::uint32_t {
    const Node& src = t.nodes[i];
    const auto li = std::uint32_t(nodes.size());
    nodes.push_back(src);
    nodes[li].plane_begin = std::uint32_t(planes.size());
    planes.insert(planes.end(), t.planes.begin() + src.plane_begin, t.planes.begin() + src.plane_begin + src.plane_count);
    if (src.kind == NodeKind::leaf) {
      Leaf lf = t.leaves[src.index];
      const auto tb = std::uint32_t(tris.size());
      tris.insert(tris.end(), t.tris.begin() + lf.tri_begin, t.tris.begin() + lf.tri_begin + lf.tri_count);
      lf.tri_begin = tb;
      nodes[li].index = std::uint32_t(leaves.size());
      leaves.push_back(lf);
    } else if (src.kind == NodeKind::inner) {
      const auto cb = std::uint32_t(children.size());
      children.resize(cb + 8);
      nodes[li].index = cb;
      for (std::uint32_t o = 0; o < 8; ++o) {
        const std::uint32_t c = emit(t.children[src.index + o]);
        children[cb + o] = c;
      }
    } else {
      nodes[li].index = 0;
    }
    nodes[li].next = std::uint32_t(nodes.size());
    return li;
  };
  for (const PageRoot& r : spec.roots) a.roots.push_back({r.octant, emit(r.node)});
  return a;
}

}  // namespace

void write_store_atomic(const Octree& t, const std::string& path, const StoreWriteOptions& opt) {
  if (t.nodes.empty()) throw std::invalid_argument("ebp store: empty tree");
  const Plan P = plan_pages(t, std::max<std::size_t>(opt.page_target, 4096));
  bvhbench::AtomicOutputFile f(path);

  FileHeader h = new_file_header(t.origin, t.root_lo, t.root_size, t.leaf_level, t.num_triangles, opt.params,
                                 opt.page_target, t.closed);
  h.nodes = t.nodes.size();
  h.leaves = t.leaves.size();
  for (const Node& nd : t.nodes) {
    if (nd.kind == NodeKind::inner) ++h.inner;
    if (nd.kind == NodeKind::white) ++h.white;
    if (nd.kind == NodeKind::black) ++h.black;
  }
  h.triangle_refs = t.tris.size();
  h.planes = t.planes.size();
  h.num_pages = P.pages.size();
  h.num_top_nodes = P.top.size();
  h.num_top_children = P.top_children.size();
  h.num_top_planes = P.top_planes.size();

  std::uint64_t off = sizeof(FileHeader);
  auto section = [&](const void* data, std::size_t n, Section* s) { write_section(f, &off, data, n, s); };
  section(P.top.data(), P.top.size() * sizeof(TopNode), &h.top_nodes);
  section(P.top_children.data(), P.top_children.size() * sizeof(std::uint32_t), &h.top_children);
  section(P.top_planes.data(), P.top_planes.size() * sizeof(Plane), &h.top_planes);
  section(opt.info_json.data(), opt.info_json.size(), &h.info);

  std::vector<PageEntry> dir(P.pages.size());
  off = align_up(off, kPageAlign);
  h.pages.offset = off;
  for (std::uint32_t id = 0; id < P.pages.size(); ++id) {
    if (opt.before_page) opt.before_page(id);
    PageEntry& e = dir[id];
    PageArrays arrays = page_arrays(t, P.pages[id]);
    const std::vector<std::uint8_t> blob = encode_page(arrays, id, P.pages[id].parent, &e).bytes;
    e.offset = off;
    f.write_at(off, blob.data(), blob.size());
    off = align_up(off + blob.size(), kPageAlign);
    if (opt.progress) opt.progress(double(id + 1) / double(P.pages.size()));
  }
  h.pages.size = off - h.pages.offset;
  h.pages.crc = 0;  // each page has its own checksum (in the directory)
  section(dir.data(), dir.size() * sizeof(PageEntry), &h.directory);
  h.file_size = h.directory.offset + h.directory.size;
  write_header(f, h);
  f.commit_durable();
}

}  // namespace ebp
