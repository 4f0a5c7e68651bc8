// The in-memory structure's own functions: names of its enums, its size, cell geometry, and the
// descent to a leaf-grid cell.
#include "methods/ebp_octree/core/octree.hpp"

#include <cmath>

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

Vec3d Octree::leaf_corner(const Leaf& lf) const {
  const double cs = cell_size(leaf_level), inv = 1.0 / cs;
  Vec3d lo;
  for (int k = 0; k < 3; ++k) lo[k] = root_lo[k] + std::floor((double(lf.centre[k]) - root_lo[k]) * inv) * cs;
  return lo;
}

void Octree::cell_box(Octcode c, Vec3d* lo, Vec3d* hi) const {
  std::uint32_t x, y, z;
  octcode_cell(c, &x, &y, &z);
  const double s = cell_size(octcode_level(c));
  *lo = {root_lo.x + double(x) * s, root_lo.y + double(y) * s, root_lo.z + double(z) * s};
  *hi = {root_lo.x + double(x + 1) * s, root_lo.y + double(y + 1) * s, root_lo.z + double(z + 1) * s};
}

std::uint32_t Octree::locate_cell(std::uint32_t x, std::uint32_t y, std::uint32_t z, std::uint32_t from) const {
  std::uint32_t i = from;
  while (nodes[i].kind == NodeKind::inner) {
    const int shift = leaf_level - octcode_level(nodes[i].code) - 1;
    const int o = int((x >> shift) & 1u) | int(((y >> shift) & 1u) << 1) | int(((z >> shift) & 1u) << 2);
    i = children[nodes[i].index + std::uint32_t(o)];
  }
  return i;
}

bool Octree::leaf_cells_holding(const Vec3d& lo, const Vec3d& hi, std::uint32_t r0[3], std::uint32_t r1[3]) const {
  const double cs = cell_size(leaf_level), inv = 1.0 / cs;
  const std::int64_t gmax = (std::int64_t(1) << leaf_level) - 1;
  for (int a = 0; a < 3; ++a) {
    auto cell = [&](double v) {
      const double r = std::floor((v - root_lo[a]) * inv);
      return std::uint32_t(r <= 0 ? 0 : r >= double(gmax) ? gmax : std::int64_t(r));
    };
    r0[a] = cell(lo[a]);
    r1[a] = cell(hi[a]);
    const bool fits = r1[a] - r0[a] <= 1 && root_lo[a] + double(r0[a]) * cs <= lo[a] &&
                      hi[a] <= root_lo[a] + double(r1[a] + 1) * cs;
    if (!fits) return false;
  }
  return true;
}

}  // namespace ebp
