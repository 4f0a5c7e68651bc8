#pragma once
/// The build's figures (`bvhbench ebp stats`, the info of a store and of a result file).
#include <cstddef>
#include <vector>

namespace ebp {

/// Figures researchers cite (`bvhbench ebp stats`).
struct Stats {
  int leaf_level = 0;
  double root_size = 0, leaf_size = 0, average_edge = 0;
  std::size_t triangles = 0, nodes = 0, inner = 0, leaves = 0, white = 0, black = 0;
  std::size_t convex = 0, concave = 0, special = 0;
  std::size_t triangle_refs = 0, max_refs_per_leaf = 0;
  std::size_t planes = 0, max_planes_per_node = 0;
  std::size_t leaf_planes = 0, inner_planes = 0;
  double leaf_box_volume = 0, leaf_volume = 0;    ///< sum over grey leaves: cell boxes, bounding volumes
  double inner_box_volume = 0, inner_volume = 0;  ///< sum over grey inner nodes
  std::size_t colour_fallbacks = 0;   ///< components coloured by the winding number (see DESIGN.md)
  std::size_t degenerate_edges = 0;   ///< colouring edges skipped (segment through an edge/vertex)
  std::size_t invalid_refs = 0;       ///< leaves without a reference point off every plane
  std::size_t front_outside_faces = 0;  ///< faces the distance's sign can be taken from (face_sides.hpp)
  std::vector<std::size_t> nodes_per_level;
  double build_seconds = 0;
  double seconds_distribute = 0, seconds_leaves = 0, seconds_inner = 0, seconds_colour = 0;
  double seconds_derived = 0;     ///< blocks, sub-references and face sides
  double seconds_face_sides = 0;  ///< of which the face sides

};

}  // namespace ebp
