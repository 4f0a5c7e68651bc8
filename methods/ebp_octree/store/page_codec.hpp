#pragma once
/// One page of a `.ebp` store (format.hpp), encoded: the one encoder that both the in-memory
/// writer (writer.cpp) and the external build's assembler (build/external_build.cpp) use, so that
/// the stores they write are the same bytes.
///
/// A page's bytes: PageHeader, then the arrays roots, nodes, children, planes, leaves, triangle
/// blocks and the local -> input triangle table, each as plain data, one after the other.
#include <cstddef>
#include <cstdint>
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

}  // namespace ebp
