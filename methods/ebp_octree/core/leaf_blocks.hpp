#pragma once
/// Derived acceleration data of the distance query (DESIGN.md, "Leaf blocks"): the spatial order
/// of each leaf's triangle block (written as it is to the .ebp file: the format does not change),
/// and float boxes computed from the triangles whenever an Octree is built or decoded (a page, or
/// the whole store): one box per block of kBlockTris consecutive LeafTris, one per group of
/// kGroupBlocks consecutive blocks in leaves of more, one per node.
#include <cstddef>
#include <cstdint>

#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

/// Orders a leaf's triangle block spatially: recursive split at the median centroid along the
/// widest axis of the centroids, split points on multiples of a group's triangles while a part
/// holds more, then of kBlockTris, so that each group and each block of consecutive triangles is
/// compact (and each block sorted along its widest axis).
/// Ties by input triangle index: the order is a function of the set of triangles alone.
/// Must run before anything records per-position data of the block (flags, sides).
void order_leaf_triangles(LeafTri* block, std::uint32_t n);

/// Recomputes tree.blocks, tree.leaf_block, tree.groups, tree.leaf_group and tree.node_box from
/// tree.nodes/leaves/tris; `groups` false leaves tree.groups and tree.leaf_group empty (a store's
/// page: its bytes are what the page cache holds, and the groups save too little to take room
/// from other pages; the queries then test every block).
/// Call at the end of every construction of an Octree (build, page decode, load_all).
void compute_leaf_blocks(Octree& tree, bool groups = true);

/// True if tree's derived boxes are present and sized for its nodes/leaves (Query requires it).
bool has_leaf_blocks(const Octree& tree);

}  // namespace ebp
