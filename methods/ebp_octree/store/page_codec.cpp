// The page encoder (page_codec.hpp).
#include "methods/ebp_octree/store/page_codec.hpp"

#include <algorithm>
#include <stdexcept>

#include "methods/ebp_octree/store/crc32c.hpp"

namespace ebp {

EncodedPage encode_page(PageArrays& a, std::uint32_t id, Octcode parent, PageEntry* e) {
  std::vector<std::uint32_t> local;
  local.reserve(a.tris.size());
  for (const LeafTri& lt : a.tris) local.push_back(lt.tri);
  std::sort(local.begin(), local.end());
  local.erase(std::unique(local.begin(), local.end()), local.end());
  for (LeafTri& lt : a.tris)
    lt.tri = std::uint32_t(std::lower_bound(local.begin(), local.end(), lt.tri) - local.begin());

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

}  // namespace ebp
