// The in-memory structure's own functions: names of its enums, its size, cell geometry, and the
// descent to a leaf-grid cell.
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

const char* to_string(NodeKind k) {
  switch (k) {
    case NodeKind::white: return "white";
    case NodeKind::black: return "black";
    case NodeKind::inner: return "inner";
    case NodeKind::leaf: return "leaf";
  }
  return "?";
}
const char* to_string(LeafConfig c) {
  switch (c) {
    case LeafConfig::convex: return "convex";
    case LeafConfig::concave: return "concave";
    case LeafConfig::special: return "special";
  }
  return "?";
}

std::size_t Octree::bytes() const {
  return sizeof(*this) + nodes.capacity() * sizeof(Node) + children.capacity() * sizeof(std::uint32_t) +
         planes.capacity() * sizeof(Plane) + leaves.capacity() * sizeof(Leaf) +
         tris.capacity() * sizeof(LeafTri);
}

void Octree::cell_box(Octcode c, Vec3d* lo, Vec3d* hi) const {
  std::uint32_t x, y, z;
  octcode_cell(c, &x, &y, &z);
  const double s = cell_size(octcode_level(c));
  *lo = {root_lo.x + double(x) * s, root_lo.y + double(y) * s, root_lo.z + double(z) * s};
  *hi = {root_lo.x + double(x + 1) * s, root_lo.y + double(y + 1) * s, root_lo.z + double(z + 1) * s};
}

std::uint32_t Octree::locate_cell(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
  std::uint32_t i = 0;
  while (nodes[i].kind == NodeKind::inner) {
    const int shift = leaf_level - octcode_level(nodes[i].code) - 1;
    const int o = int((x >> shift) & 1u) | int(((y >> shift) & 1u) << 1) | int(((z >> shift) & 1u) << 2);
    i = children[nodes[i].index + std::uint32_t(o)];
  }
  return i;
}

}  // namespace ebp
