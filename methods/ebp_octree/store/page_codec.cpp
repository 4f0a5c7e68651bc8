// The page codec (page_codec.hpp): the encoder both writers use, the decoder the reader uses.
#include "methods/ebp_octree/store/page_codec.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "harness/util/errors.hpp"
#include "methods/ebp_octree/core/leaf_blocks.hpp"
#include "methods/ebp_octree/store/crc32c.hpp"

namespace ebp {

namespace {
bool finite3(const float* f) { return std::isfinite(f[0]) && std::isfinite(f[1]) && std::isfinite(f[2]); }
}  // namespace

EncodedPage encode_page(PageArrays& a, std::uint32_t id, Octcode parent, PageEntry* e) {
  std::vector<std::uint32_t> local;
  local.reserve(a.tris.size());
  for (const LeafTri& lt : a.tris) local.push_back(lt.tri());
  std::sort(local.begin(), local.end());
  local.erase(std::unique(local.begin(), local.end()), local.end());
  for (LeafTri& lt : a.tris)
    lt.set_tri(std::uint32_t(std::lower_bound(local.begin(), local.end(), lt.tri()) - local.begin()));

  PageHeader ph{};
  ph.magic = kPageMagic;
  ph.page_id = id;
  ph.parent = parent;
  ph.nroots = std::uint32_t(a.roots.size());
  ph.nnodes = std::uint32_t(a.nodes.size());
  ph.nchildren = std::uint32_t(a.children.size());
  ph.nplanes = std::uint32_t(a.planes.size());
  ph.nleaves = std::uint32_t(a.leaves.size());
  ph.ntris = std::uint32_t(a.tris.size());
  ph.nlocal = std::uint32_t(local.size());
  EncodedPage out;
  std::vector<std::uint8_t>& b = out.bytes;
  auto put = [&](const void* p, std::size_t n) {
    const auto* u = static_cast<const std::uint8_t*>(p);
    b.insert(b.end(), u, u + n);
  };
  put(&ph, sizeof ph);
  put(a.roots.data(), a.roots.size() * sizeof(PageRoot));
  out.nodes_offset = b.size();
  put(a.nodes.data(), a.nodes.size() * sizeof(Node));
  put(a.children.data(), a.children.size() * sizeof(std::uint32_t));
  put(a.planes.data(), a.planes.size() * sizeof(Plane));
  out.leaves_offset = b.size();
  put(a.leaves.data(), a.leaves.size() * sizeof(Leaf));
  put(a.tris.data(), a.tris.size() * sizeof(LeafTri));
  put(local.data(), local.size() * sizeof(std::uint32_t));
  if (b.size() > kMaxPageBytes) throw std::runtime_error("ebp store: a page exceeds 1 GiB (one leaf too large)");
  e->size = std::uint32_t(b.size());
  e->crc = crc32c(b.data(), b.size());
  e->parent = parent;
  e->triangles = ph.ntris;
  e->nodes = ph.nnodes;
  return out;
}

namespace {

/// A page's failure: InputError naming the file and the page.
struct PageFail {
  const std::string& path;
  std::string where;
  [[noreturn]] void operator()(const std::string& what) const { throw bvhbench::file_error(path, where + what); }
};

/// The page's header, checked against the directory (id, parent) and the page's size; its parent's
/// level in *lp (-1 for the root page).
PageHeader read_page_header(const std::uint8_t* data, std::size_t size, const PageContext& c, const PageFail& fail,
                            int* lp) {
  if (size < sizeof(PageHeader)) fail("bad size " + std::to_string(size));  // the reader checked it
  PageHeader ph;
  std::memcpy(&ph, data, sizeof ph);
  if (ph.magic != kPageMagic) fail("bad page magic");
  if (ph.page_id != c.id) fail("page id mismatch");
  if (ph.parent != c.parent) fail("parent code mismatch");
  const std::uint64_t need = sizeof(PageHeader) + std::uint64_t(ph.nroots) * sizeof(PageRoot) +
                             std::uint64_t(ph.nnodes) * sizeof(Node) + std::uint64_t(ph.nchildren) * 4 +
                             std::uint64_t(ph.nplanes) * sizeof(Plane) + std::uint64_t(ph.nleaves) * sizeof(Leaf) +
                             std::uint64_t(ph.ntris) * sizeof(LeafTri) + std::uint64_t(ph.nlocal) * 4;
  if (need != size) fail("array sizes do not add up to the page size");
  const bool root_page = ph.parent == kNoParent;
  *lp = -1;
  if (!root_page) {
    *lp = octcode_level(ph.parent);
    if (*lp >= c.leaf_level || octcode_make(*lp, octcode_morton(ph.parent)) != ph.parent) fail("bad parent code");
  }
  if (ph.nroots == 0 || ph.nroots > 8 || (root_page && ph.nroots != 1)) fail("bad number of roots");
  if (ph.nnodes == 0) fail("no nodes");
  return ph;
}

/// Roots: octants distinct, matching the top tree's entries for this page, codes right.
void check_roots(const PageHeader& ph, const std::vector<PageRoot>& roots, const Octree& T, std::uint32_t chain,
                 const PageContext& c, const PageFail& fail) {
  const bool root_page = ph.parent == kNoParent;
  std::uint8_t mask = 0;
  for (const PageRoot& r : roots) {
    if (r.node >= ph.nnodes) fail("root node out of range");
    if (root_page) {
      if (r.node != 0 || T.nodes[chain + r.node].code != octcode_root()) fail("bad root");
      mask = 1;
      continue;
    }
    if (r.octant > 7 || (mask & (1u << r.octant))) fail("bad root octant");
    mask |= std::uint8_t(1u << r.octant);
    if (T.nodes[chain + r.node].code != octcode_child(ph.parent, int(r.octant))) fail("root code mismatch");
  }
  if (mask != c.octants) fail("roots do not match the top tree");
}

/// Nodes: every index checked, then moved past the chain (`chain` nodes, `cbase` children).
void check_and_place_nodes(const PageHeader& ph, int L, std::uint32_t chain, std::uint32_t cbase, Octree& T,
                           const PageFail& fail) {
  for (std::uint32_t k = 0; k < ph.nnodes; ++k) {
    Node& nd = T.nodes[chain + k];
    const int lvl = octcode_level(nd.code);
    if (lvl > L || std::uint8_t(nd.kind) > 3 || std::uint8_t(nd.config) > 2) fail("bad node " + std::to_string(k));
    if (std::uint64_t(nd.plane_begin) + nd.plane_count > ph.nplanes) fail("plane range out of bounds");
    if (nd.next > ph.nnodes || nd.next <= k) fail("bad subtree end");
    nd.next += chain;
    if (nd.kind == NodeKind::inner) {
      if (lvl >= L) fail("inner node at the leaf level");
      if (std::uint64_t(nd.index) + 8 > ph.nchildren) fail("children out of bounds");
      for (std::uint32_t o = 0; o < 8; ++o) {
        std::uint32_t& ch = T.children[cbase + nd.index + o];
        if (ch >= ph.nnodes || ch <= k) fail("bad child index");
        if (T.nodes[chain + ch].code != octcode_child(nd.code, int(o))) fail("child code mismatch");
        ch += chain;
      }
      nd.index += cbase;
    } else if (nd.kind == NodeKind::leaf) {
      if (lvl != L) fail("leaf above the leaf level");
      if (nd.index >= ph.nleaves) fail("leaf index out of range");
    }
  }
}

/// Planes, leaves and triangles finite, their ranges inside the page, the triangle table increasing.
void check_records(const PageHeader& ph, const Page& page, const PageContext& c, const PageFail& fail) {
  const Octree& T = page.tree;
  for (const Plane& pl : T.planes)
    if (!finite3(pl.n) || !std::isfinite(pl.d)) fail("non-finite plane");
  for (const Leaf& lf : T.leaves) {
    if (!finite3(lf.centre) || !finite3(lf.ref) || !std::isfinite(lf.eps) || !(lf.eps >= 0))
      fail("non-finite leaf record");
    if (std::uint64_t(lf.tri_begin) + lf.tri_count > ph.ntris) fail("leaf triangle block out of bounds");
  }
  for (const LeafTri& lt : T.tris) {
    if (!finite3(lt.a) || !finite3(lt.b) || !finite3(lt.c) || !std::isfinite(lt.d)) fail("non-finite triangle");
    if ((lt.normal & 0xFFFFu) == 0x8000u || (lt.normal >> 16) == 0x8000u) fail("bad face normal code");
    if (lt.tri() >= ph.nlocal) fail("triangle index out of range");
  }
  for (std::uint32_t k = 0; k < ph.nlocal; ++k)
    if (page.global_tri[k] >= c.num_triangles || (k > 0 && page.global_tri[k] <= page.global_tri[k - 1]))
      fail("bad triangle table");
}

/// The chain of plane-less inner nodes from the root to the parent (level lp), whose every other
/// branch points to one white dummy, and the page's roots under the parent.
void link_chain(const PageHeader& ph, const std::vector<PageRoot>& roots, int lp, std::uint32_t chain, Octree& T) {
  const std::uint32_t dummy = std::uint32_t(lp + 1);
  const std::uint64_t pm = octcode_morton(ph.parent);
  for (int k = 0; k <= lp; ++k) {
    Node& nd = T.nodes[std::size_t(k)];
    nd = Node{};
    nd.code = octcode_make(k, pm >> (3 * (lp - k)));
    nd.kind = NodeKind::inner;
    nd.config = LeafConfig::special;
    nd.index = std::uint32_t(8 * k);
    nd.next = std::uint32_t(T.nodes.size());
    for (std::uint32_t o = 0; o < 8; ++o) T.children[std::size_t(8 * k) + o] = dummy;
    if (k < lp) T.children[std::size_t(8 * k) + std::uint32_t(octcode_octant(octcode_make(k + 1, pm >> (3 * (lp - k - 1)))))] = std::uint32_t(k + 1);
  }
  for (const PageRoot& r : roots) T.children[std::size_t(8 * lp) + r.octant] = chain + r.node;
  Node& d = T.nodes[dummy];
  d = Node{};
  d.code = kNoParent;
  d.kind = NodeKind::white;
  d.next = dummy + 1;
}

}  // namespace

std::unique_ptr<Page> decode_page(const std::uint8_t* data, std::size_t size, const PageContext& c,
                                  const std::string& path) {
  const PageFail fail{path, "page " + std::to_string(c.id) + ": "};
  int lp = -1;
  const PageHeader ph = read_page_header(data, size, c, fail, &lp);
  const int L = c.leaf_level;
  const bool root_page = ph.parent == kNoParent;

  const std::uint8_t* p = data + sizeof(PageHeader);
  std::vector<PageRoot> roots(ph.nroots);
  auto take = [&](void* dst, std::size_t n) {
    if (n) std::memcpy(dst, p, n);
    p += n;
  };
  take(roots.data(), roots.size() * sizeof(PageRoot));
  auto page = std::make_unique<Page>();
  page->id = c.id;
  Octree& T = page->tree;
  const std::uint32_t chain = root_page ? 0u : std::uint32_t(lp + 2);  // chain nodes + the white dummy
  const std::uint32_t cbase = root_page ? 0u : std::uint32_t(8 * (lp + 1));
  if (std::uint64_t(ph.nnodes) + chain >= 0xffffffffull || std::uint64_t(ph.nchildren) + cbase >= 0xffffffffull)
    fail("too many nodes");
  T.nodes.resize(chain + ph.nnodes);
  T.children.resize(cbase + ph.nchildren);
  T.planes.resize(ph.nplanes);
  T.leaves.resize(ph.nleaves);
  T.tris.resize(ph.ntris);
  page->global_tri.resize(ph.nlocal);
  take(T.nodes.data() + chain, std::size_t(ph.nnodes) * sizeof(Node));
  take(T.children.data() + cbase, std::size_t(ph.nchildren) * 4);
  take(T.planes.data(), std::size_t(ph.nplanes) * sizeof(Plane));
  take(T.leaves.data(), std::size_t(ph.nleaves) * sizeof(Leaf));
  take(T.tris.data(), std::size_t(ph.ntris) * sizeof(LeafTri));
  take(page->global_tri.data(), std::size_t(ph.nlocal) * 4);

  check_roots(ph, roots, T, chain, c, fail);
  check_and_place_nodes(ph, L, chain, cbase, T, fail);
  check_records(ph, *page, c, fail);
  if (!root_page) link_chain(ph, roots, lp, chain, T);
  T.origin = c.origin;
  T.root_lo = c.root_lo;
  T.root_size = c.root_size;
  T.root_centre = T.root_lo + Vec3d(0.5, 0.5, 0.5) * T.root_size;
  T.leaf_level = L;
  T.num_triangles = ph.nlocal;
  T.closed = c.closed;
  compute_leaf_blocks(T, false);  // derived boxes (not in the file), without groups
  // No sub-references (sub_references.hpp): a page is decoded while a query waits for it, and
  // they would add ~9 us a leaf to every page load; the inside answers are the same without.
  page->chain = chain;
  return page;
}

}  // namespace ebp
