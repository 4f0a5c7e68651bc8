// The colouring (build_parts.hpp, colour): winding numbers of the leaves' reference points and of
// the empty nodes by exact signed crossings between adjacent cells, joined in a union-find with
// potentials, seeded by the outside of the root (w = 0).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <vector>

#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/predicates.hpp"

namespace ebp::detail {

namespace {

/// Union-find with potentials: off[x] = w(x) - w(parent[x]), w the winding number.
struct UnionFind {
  std::vector<std::uint32_t> parent;
  std::vector<int> off;
  std::vector<std::uint8_t> touched;
  explicit UnionFind(std::size_t n) : parent(n), off(n, 0), touched(n, 0) {
    std::iota(parent.begin(), parent.end(), 0u);
  }
  /// Root of x, and w(x) - w(root) in *pot.
  std::uint32_t find(std::uint32_t x, int* pot) {
    int acc = 0;
    std::uint32_t r = x;
    while (parent[r] != r) { acc += off[r]; r = parent[r]; }
    // Path compression: every node on the path now points at r with its full offset.
    int rest = acc;
    std::uint32_t y = x;
    while (parent[y] != y) {
      const std::uint32_t nx = parent[y];
      const int oy = off[y];
      parent[y] = r;
      off[y] = rest;
      rest -= oy;
      y = nx;
    }
    if (pot) *pot = acc;
    return r;
  }
  /// Records w(b) - w(a) = d.
  void unite(std::uint32_t a, std::uint32_t b, int d) {
    int wa, wb;
    const std::uint32_t ra = find(a, &wa), rb = find(b, &wb);
    touched[a] = touched[b] = 1;
    if (ra == rb) return;
    parent[ra] = rb;
    off[ra] = -d - wa + wb;  // w(ra) - w(rb) = (w(a) - wa) - (w(b) - wb), w(a) - w(b) = -d
  }
};

}  // namespace

std::uint32_t Skeleton::locate_cell(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
  std::uint32_t i = 0;
  while (kind[i] == NodeKind::inner) {
    const int shift = leaf_level - octcode_level(code[i]) - 1;
    const int o = int((x >> shift) & 1u) | int(((y >> shift) & 1u) << 1) | int(((z >> shift) & 1u) << 2);
    i = children[index[i] + std::uint32_t(o)];
  }
  return i;
}

std::size_t Skeleton::bytes() const {
  return code.capacity() * sizeof(Octcode) + kind.capacity() + index.capacity() * 4 + children.capacity() * 4 +
         leaf_node.capacity() * 4 + leaf_ref.capacity() * 12 + leaf_ref_valid.capacity() +
         leaf_halves.capacity() * sizeof(LeafHalves);
}

namespace {

/// Empty nodes touching the root's boundary are outside (joined to `out`): the root is larger
/// than the model's bounding box on every side.
void join_boundary_to_outside(const Skeleton& sk, std::uint32_t out, UnionFind& uf) {
  for (std::size_t i = 0; i < sk.code.size(); ++i) {
    if (sk.kind[i] != NodeKind::white) continue;
    std::uint32_t x, y, z;
    octcode_cell(sk.code[i], &x, &y, &z);
    const std::uint32_t last = (1u << octcode_level(sk.code[i])) - 1;
    if (x == 0 || y == 0 || z == 0 || x == last || y == last || z == last) uf.unite(std::uint32_t(i), out, 0);
  }
}

/// Adjacencies of leaves, in leaf order: w(target) - w(ref_A) from the two half-edges through the
/// portal of the shared face (ref_A -> portal over A's triangles, portal -> ref_B over B's), or
/// the one half-edge to the portal when the target is an empty node or the outside (`out`).
void join_leaf_neighbours(const Skeleton& sk, std::uint32_t out, UnionFind& uf, Colouring& C) {
  const std::uint32_t G = 1u << sk.leaf_level;
  for (std::size_t li = 0; li < sk.leaf_node.size(); ++li) {
    if (!sk.leaf_ref_valid[li]) continue;
    const std::uint32_t ni = sk.leaf_node[li];
    std::uint32_t c[3];
    octcode_cell(sk.code[ni], &c[0], &c[1], &c[2]);
    for (int dir = 0; dir < 6; ++dir) {
      const int axis = dir >> 1;
      const bool pos = dir & 1;
      std::uint32_t nb[3] = {c[0], c[1], c[2]};
      std::uint32_t target;
      bool to_leaf = false;
      if ((!pos && c[axis] == 0) || (pos && c[axis] == G - 1)) {
        target = out;
      } else {
        nb[axis] = pos ? c[axis] + 1 : c[axis] - 1;
        target = sk.locate_cell(nb[0], nb[1], nb[2]);
        to_leaf = sk.kind[target] == NodeKind::leaf;
        if (to_leaf && !sk.leaf_ref_valid[sk.index[target]]) continue;
      }
      int pa, pb;
      if (uf.find(ni, &pa) == uf.find(target, &pb)) continue;
      const std::int32_t ha = sk.leaf_halves[li].h[dir];
      const std::int32_t hb = to_leaf ? sk.leaf_halves[sk.index[target]].h[dir ^ 1] : 0;
      if (ha == kDegenerateHalf || hb == kDegenerateHalf) { ++C.degenerate_edges; continue; }
      // w(portal) - w(ref_A) = ha, w(portal) - w(ref_B) = hb.
      uf.unite(ni, target, ha - hb);
    }
  }
}

/// Empty node i not yet joined: probes the cells just across its faces for a joined empty node
/// and joins it to the first found. Returns whether it did.
bool join_across_faces(const Skeleton& sk, std::size_t i, UnionFind& uf) {
  const int L = sk.leaf_level;
  const std::uint32_t G = 1u << L;
  std::uint32_t c[3];
  octcode_cell(sk.code[i], &c[0], &c[1], &c[2]);
  const std::uint32_t span = 1u << (L - octcode_level(sk.code[i]));
  for (int dir = 0; dir < 6; ++dir) {
    const int axis = dir >> 1;
    const bool pos = dir & 1;
    for (int qd = 0; qd < 4; ++qd) {
      std::uint32_t p[3];
      for (int k = 0; k < 3; ++k) p[k] = c[k] * span;
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      p[a1] += (qd & 1) ? (3 * span) / 4 : span / 4;
      p[a2] += (qd & 2) ? (3 * span) / 4 : span / 4;
      if (pos) p[axis] += span; else if (p[axis] == 0) continue; else p[axis] -= 1;
      if (p[axis] >= G) continue;
      const std::uint32_t k = sk.locate_cell(p[0], p[1], p[2]);
      if (k != i && sk.kind[k] == NodeKind::white && uf.touched[k]) {
        uf.unite(std::uint32_t(i), k, 0);
        return true;
      }
    }
  }
  return false;
}

/// Empty nodes not yet joined, joined through their neighbours until nothing changes.
void join_empty_nodes(const Skeleton& sk, UnionFind& uf) {
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t i = 0; i < sk.code.size(); ++i)
      if (sk.kind[i] == NodeKind::white && !uf.touched[i] && join_across_faces(sk, i, uf)) changed = true;
  }
}

/// The winding number of each component's root. OUT has w = 0. Components not joined to the
/// outside (only when every edge of a region was degenerate) take the generalized winding number
/// of one of their points (the first node of the component in node order), computed for all such
/// components in one batch.
std::vector<int> component_windings(const Frame& F, const Skeleton& sk, std::uint32_t out, UnionFind& uf,
                                    const WindingBatch& winding_at, Colouring& C) {
  const std::size_t N = sk.code.size();
  int pout;
  const std::uint32_t rout = uf.find(out, &pout);
  std::vector<int> comp_w(N + 1, 0);
  std::vector<std::uint8_t> comp_known(N + 1, 0);
  comp_w[rout] = -pout;  // w(root) = w(OUT) - (w(OUT) - w(root))
  comp_known[rout] = 1;
  std::vector<Vec3d> fb_pts;
  std::vector<std::pair<std::uint32_t, int>> fb_comp;  // root, pot of the point
  auto point_of = [&](std::size_t i) {
    if (sk.kind[i] == NodeKind::white) {
      Vec3d lo, hi;
      F.cell_box(sk.code[i], &lo, &hi);
      return (lo + hi) * 0.5;
    }
    const auto& r = sk.leaf_ref[sk.index[i]];
    return Vec3d(double(r[0]), double(r[1]), double(r[2]));
  };
  auto needs_colour = [&](std::size_t i) {
    return sk.kind[i] == NodeKind::white || (sk.kind[i] == NodeKind::leaf && sk.leaf_ref_valid[sk.index[i]]);
  };
  for (std::size_t i = 0; i < N; ++i) {
    if (!needs_colour(i)) continue;
    int pot;
    const std::uint32_t r = uf.find(std::uint32_t(i), &pot);
    if (comp_known[r]) continue;
    comp_known[r] = 2;  // pending
    fb_pts.push_back(point_of(i));
    fb_comp.push_back({r, pot});
  }
  if (!fb_pts.empty()) {
    const std::vector<int> w = winding_at(fb_pts);
    for (std::size_t k = 0; k < fb_comp.size(); ++k) {
      comp_w[fb_comp[k].first] = w[k] - fb_comp[k].second;
      comp_known[fb_comp[k].first] = 1;
    }
    C.colour_fallbacks = fb_pts.size();
  }
  return comp_w;
}

}  // namespace

Colouring colour(const Frame& F, Skeleton& sk, const WindingBatch& winding_at) {
  Colouring C;
  const std::size_t N = sk.code.size();
  C.ref_winding.assign(sk.leaf_node.size(), 0);
  const std::uint32_t OUT = std::uint32_t(N);
  UnionFind uf(N + 1);
  join_boundary_to_outside(sk, OUT, uf);
  join_leaf_neighbours(sk, OUT, uf, C);
  join_empty_nodes(sk, uf);
  const std::vector<int> comp_w = component_windings(F, sk, OUT, uf, winding_at, C);
  for (std::size_t i = 0; i < N; ++i) {
    if (sk.kind[i] == NodeKind::white) {
      int pot;
      const std::uint32_t r = uf.find(std::uint32_t(i), &pot);
      if (comp_w[r] + pot >= 1) C.black.push_back(std::uint32_t(i));
    } else if (sk.kind[i] == NodeKind::leaf) {
      const std::uint32_t li = sk.index[i];
      if (sk.leaf_ref_valid[li]) {
        int pot;
        const std::uint32_t r = uf.find(std::uint32_t(i), &pot);
        C.ref_winding[li] = std::int16_t(std::clamp(comp_w[r] + pot, -32768, 32767));
      } else {
        ++C.invalid_refs;
      }
    }
  }
  return C;
}

}  // namespace ebp::detail
