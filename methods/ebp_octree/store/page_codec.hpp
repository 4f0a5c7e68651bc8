#pragma once
/// One page of a `.ebp` store (format.hpp), encoded and decoded: the one encoder that both the
/// in-memory writer (writer.cpp) and the external build's assembler (build/assembler.hpp) use, so
/// that the stores they write are the same bytes, and the decoder the reader (reader.cpp) uses.
///
/// A page's bytes: PageHeader, then the arrays roots, nodes, children, planes, leaves, triangle
/// blocks and the local -> input triangle table, each as plain data, one after the other.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/store/format.hpp"

namespace ebp {

/// The arrays of one page, with page-local indices (nodes in pre-order, children and
/// Node::index/next/plane_begin, Leaf::tri_begin into these arrays); LeafTri::tri is still the
/// input mesh's triangle index.
struct PageArrays {
  std::vector<PageRoot> roots;
  std::vector<Node> nodes;
  std::vector<std::uint32_t> children;
  std::vector<Plane> planes;
  std::vector<Leaf> leaves;
  std::vector<LeafTri> tris;
};

struct EncodedPage {
  std::vector<std::uint8_t> bytes;
  std::size_t nodes_offset = 0;   ///< byte offset of the first Node in `bytes`
  std::size_t leaves_offset = 0;  ///< byte offset of the first Leaf in `bytes`
};

/// Encodes page `id` under the top node `parent` (kNoParent: the root page). Replaces each
/// LeafTri::tri of `a` by its index in the page's table of input triangles (sorted, distinct).
/// Fills `e`'s size, crc, parent, triangles and nodes (not its offset). Throws std::runtime_error
/// if the page exceeds kMaxPageBytes.
EncodedPage encode_page(PageArrays& a, std::uint32_t id, Octcode parent, PageEntry* e);

/// A loaded page: an ordinary Octree (global frame, chain from the root, see reader.hpp) and the
/// map from its local triangle indices to the input mesh's.
struct Page {
  std::uint32_t id = 0;
  std::uint32_t chain = 0;  ///< nodes[0, chain - 1) are the root-to-parent chain, nodes[chain - 1] the dummy (0: root page)
  Octree tree;
  std::vector<std::uint32_t> global_tri;
  std::size_t bytes() const {
    return tree.bytes() + tree.derived_bytes() + global_tri.capacity() * sizeof(std::uint32_t);
  }
};

/// What the reader knows of page `id` before decoding it (header, top tree, directory).
struct PageContext {
  std::uint32_t id = 0;
  Octcode parent = kNoParent;  ///< the top node holding the page
  std::uint8_t octants = 0;    ///< the octants of its roots in that parent (root page: 1)
  int leaf_level = 0;
  std::uint32_t num_triangles = 0;  ///< of the input mesh
  Vec3d origin;  ///< the frame origin (every coordinate of the page is relative to it)
  Vec3d root_lo;
  double root_size = 0;
  bool closed = false;
};

/// Decodes page bytes `data[0, size)` (their checksum already checked) into a Page, checking every
/// count, index and number before its use, rebuilding the chain from the root, and computing the
/// derived boxes. Throws bvhbench::InputError naming `path` and the page.
std::unique_ptr<Page> decode_page(const std::uint8_t* data, std::size_t size, const PageContext& c,
                                  const std::string& path);

}  // namespace ebp
