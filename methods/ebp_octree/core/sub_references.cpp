// One derived reference point per octant of a leaf (sub_references.hpp).
#include "methods/ebp_octree/core/sub_references.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/float_round.hpp"
#include "methods/ebp_octree/core/leaf_kernels.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/core/reference_points.hpp"

namespace ebp {

namespace {

/// The exact side (+1 outer, -1 inner, 0 in the plane) of r for each of the leaf's triangles,
/// into side[0, n): the float face-plane pass decides where it can (the inside query's own
/// kernel and bound), orient3d elsewhere. Degenerate triangles get +1 (they cross nothing).
bool sides_of(const LeafTri* blk, std::uint32_t n, const Leaf& lf, const Vec3d& r, std::vector<int>& side) {
  const LeafKernelTable& K = leaf_kernel_table();
  const float pl[3] = {float(r.x - double(lf.centre[0])), float(r.y - double(lf.centre[1])),
                       float(r.z - double(lf.centre[2]))};
  side.assign(n, 1);
  for (std::uint32_t k0 = 0; k0 < n; k0 += kBlockTris) {
    const unsigned m = std::min(n - k0, kBlockTris);
    float s[kBlockTris];
    K.plane_pass(blk + k0, m, pl, lf.eps, s, kRefSidesFromFlags);
    for (unsigned j = 0; j < m; ++j) {
      const LeafTri& t = blk[k0 + j];
      if (t.flags() & kDegenerate) continue;
      const int o = s[j] > lf.eps ? 1 : s[j] < -lf.eps ? -1 : orient3d(to_d(t.a), to_d(t.b), to_d(t.c), r);
      if (o == 0) return false;
      side[k0 + j] = o;
    }
  }
  return true;
}

}  // namespace

void compute_sub_references(Octree& t) {
  t.sub_refs.clear();
  t.sub_sides.clear();
  if (!t.closed) {
    t.sub_refs.shrink_to_fit();
    t.sub_sides.shrink_to_fit();
    return;
  }
  t.sub_refs.assign(t.leaves.size() * 8, SubRef{});
  t.sub_sides.assign(t.blocks.size() * 8, 0);
  const double half = 0.5 * t.cell_size(t.leaf_level);
  std::vector<int> side;
  for (std::size_t li = 0; li < t.leaves.size(); ++li) {
    const Leaf& lf = t.leaves[li];
    if (!lf.ref_valid || lf.tri_count == 0) continue;
    const LeafTri* blk = t.tris.data() + lf.tri_begin;
    const std::uint32_t n = lf.tri_count;
    const Vec3d ref = to_d(lf.ref);
    const Vec3d lo = t.leaf_corner(lf);
    for (int o = 0; o < 8; ++o) {
      const Vec3d olo = child_corner(lo, half, o), ohi = olo + Vec3d(half, half, half);
      const Vec3d oc = olo + Vec3d(0.5, 0.5, 0.5) * half;
      for (const Vec3d& off : ref_offsets()) {  // candidates about the octant's centre
        const Vec3d r = round_to_float(oc + off * (0.5 * half));
        if (!(r.x > olo.x && r.x < ohi.x && r.y > olo.y && r.y < ohi.y && r.z > olo.z && r.z < ohi.z)) continue;
        if (!sides_of(blk, n, lf, r, side)) continue;
        // w(r) - w(ref): the crossings of ref -> r, over the leaf's triangles (the segment lies in
        // the cell), exactly.
        int delta = 0;
        bool ok = true;
        const float s0[3] = {float(std::min(r.x, ref.x)), float(std::min(r.y, ref.y)), float(std::min(r.z, ref.z))};
        const float s1[3] = {float(std::max(r.x, ref.x)), float(std::max(r.y, ref.y)), float(std::max(r.z, ref.z))};
        for (std::uint32_t k = 0; k < n && ok; ++k) {
          const LeafTri& tr = blk[k];
          if (tr.flags() & kDegenerate) continue;
          const int sq = (tr.flags() & kRefPositive) ? 1 : -1;
          if (side[k] == sq) continue;
          // A triangle whose box misses the segment's cannot cross it (r and ref are floats, so
          // the segment's box is exact in float).
          bool misses = false;
          for (int a = 0; a < 3; ++a)
            misses |= std::max({tr.a[a], tr.b[a], tr.c[a]}) < s0[a] || std::min({tr.a[a], tr.b[a], tr.c[a]}) > s1[a];
          if (misses) continue;
          switch (segment_triangle(r, ref, side[k], sq, to_d(tr.a), to_d(tr.b), to_d(tr.c))) {
            case Cross::none: break;
            case Cross::proper: delta += sq > 0 ? 1 : -1; break;  // ref outer -> r inner: entering
            default: ok = false; break;
          }
        }
        if (!ok) continue;
        SubRef& sr = t.sub_refs[li * 8 + std::size_t(o)];
        sr.p[0] = float(r.x);
        sr.p[1] = float(r.y);
        sr.p[2] = float(r.z);
        sr.winding = std::int16_t(lf.ref_winding + delta);
        sr.valid = 1;
        std::uint8_t* masks = &t.sub_sides[std::size_t(t.leaf_block[li]) * 8];
        for (std::uint32_t k = 0; k < n; ++k)
          if (side[k] > 0 && !(blk[k].flags() & kDegenerate)) masks[(k / kBlockTris) * 8 + std::size_t(o)] |= std::uint8_t(1u << (k % kBlockTris));
        break;
      }
    }
  }
}

}  // namespace ebp
