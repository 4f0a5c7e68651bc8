#pragma once
/// Derived reference points of the inside query (DESIGN.md, "Inside: sub-references"): one per
/// octant of each grey leaf's cell, on closed meshes. The inside query counts the crossings of
/// the segment from p to a point of known winding number; from the octant's own point that
/// segment spans at most the octant, so its box meets fewer of the leaf's blocks and it crosses
/// fewer faces than the segment to the leaf's one reference point, which may lie across the
/// cell. On a closed mesh the winding number is a function of the point, so either segment gives
/// the same answer, bit for bit; an open mesh keeps the leaf's reference point alone.
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

/// Recomputes tree.sub_refs and tree.sub_sides from the leaves, their triangles and their
/// reference points' winding numbers (empty when the tree is not closed). Needs the leaf blocks
/// (compute_leaf_blocks) first. Called where a whole tree is built or loaded (build_octree,
/// StoreReader::load_all); a page of the store is decoded without them (page_codec.cpp): it is
/// decoded while a query waits, and the answers are the same without.
void compute_sub_references(Octree& tree);

}  // namespace ebp
