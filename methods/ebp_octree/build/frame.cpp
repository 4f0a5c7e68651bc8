// The frame of a build (build_parts.hpp): the bounding box and average edge accumulated in input
// order, the root cube and leaf level, the build constants, the distribution of one triangle to
// the leaf cells it touches, and the colouring's face portals.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/build/tri_box.hpp"
#include "methods/ebp_octree/core/predicates.hpp"

namespace ebp::detail {

Vec3d choose_origin(const Box3d& b) {
  if (!(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) return {0, 0, 0};  // empty (or NaN)
  const Vec3d centre = (b.lo + b.hi) * 0.5;
  const Vec3d ext = b.extent();
  double m = std::max({ext.x, ext.y, ext.z});
  if (!std::isfinite(m)) return {0, 0, 0};  // the build refuses non-finite coordinates
  // A single point (or a flat set of coincident vertices) has no size: its magnitude's 1e-6.
  if (m == 0) m = 1e-6 * std::max({std::fabs(centre.x), std::fabs(centre.y), std::fabs(centre.z)});
  if (m == 0) return {0, 0, 0};
  const double g = std::ldexp(1.0, int(std::ceil(std::log2(m))) + 3);
  Vec3d o;
  for (int k = 0; k < 3; ++k) {
    const double r = std::nearbyint(centre[k] / g);
    o[k] = r == 0 ? 0.0 : r * g;  // never -0
  }
  return o;
}

void FrameAccumulator::add(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  bb.add(a); bb.add(b); bb.add(c);
  edge_sum += perimeter(a, b, c);
  ++triangles;
}

void Frame::cell_box(Octcode c, Vec3d* lo, Vec3d* hi) const {
  std::uint32_t x, y, z;
  octcode_cell(c, &x, &y, &z);
  const double s = cell_size(octcode_level(c));
  *lo = {root_lo.x + double(x) * s, root_lo.y + double(y) * s, root_lo.z + double(z) * s};
  *hi = {root_lo.x + double(x + 1) * s, root_lo.y + double(y + 1) * s, root_lo.z + double(z + 1) * s};
}

Frame compute_frame(const FrameAccumulator& acc, const BuildParams& prm) {
  Frame F;
  const Box3d& bb = acc.bb;
  const double avg_edge = acc.edge_sum / (3.0 * double(acc.triangles));
  const Vec3d centre = (bb.lo + bb.hi) * 0.5;
  const Vec3d ext = bb.extent();
  double m = std::max({ext.x, ext.y, ext.z});
  const double cmag = std::max({std::fabs(centre.x), std::fabs(centre.y), std::fabs(centre.z)});
  m = std::max(m, 1e-6 * (cmag + 1e-30));
  if (m == 0) m = 1e-30;
  // Enlarge by 0.1 % (a margin on every side), then round the size to 20 significant bits and
  // the corner to a multiple of size / 2^39, so that every cell boundary at every level is an
  // exactly representable double, computed exactly by cell_box().
  const double s0 = m * 1.001;
  const int j = int(std::ceil(std::log2(s0))) - 20;
  const double M = std::ceil(std::ldexp(s0, -j));
  F.root_size = std::ldexp(M, j);
  const double unit = std::ldexp(1.0, j - kMaxLevel);
  for (int k = 0; k < 3; ++k) F.root_lo[k] = std::floor((centre[k] - 0.5 * F.root_size) / unit) * unit;
  F.root_centre = F.root_lo + Vec3d(0.5, 0.5, 0.5) * F.root_size;
  const int max_level = std::clamp(prm.max_level, 1, kMaxLevel);
  int L = 1;
  const double target = prm.leaf_factor * avg_edge;
  while (L < max_level && F.root_size / double(1u << (L + 1)) >= target) ++L;
  F.leaf_level = L;
  F.average_edge = avg_edge;
  return F;
}

BuildContext::BuildContext(const Frame& frame, const BuildParams& prm)
    : f(frame),
      cs(frame.cell_size(frame.leaf_level)),
      G(1u << frame.leaf_level),
      cos_cluster(std::cos(prm.cluster_angle * M_PI / 180.0)),
      max_planes(std::max(0, prm.max_planes)),
      plane_margin(1e-9 * frame.root_size) {}

void distribute_triangle(const BuildContext& ctx, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                         std::vector<std::uint64_t>& out) {
  const double cs = ctx.cs;
  const std::uint32_t G = ctx.G;
  const Vec3d& rl = ctx.f.root_lo;
  auto cell_range = [&](double lo, double hi, double r, double ext_rel, std::uint32_t* ia, std::uint32_t* ib) {
    const double slack = 1e-6 + 2e-9 * std::max(1.0, ext_rel);
    double fa = std::floor((lo - r) / cs - slack), fb = std::floor((hi - r) / cs + slack);
    fa = std::clamp(fa, 0.0, double(G - 1));
    fb = std::clamp(fb, 0.0, double(G - 1));
    *ia = std::uint32_t(fa);
    *ib = std::uint32_t(fb);
  };
  Box3d tb;
  tb.add(a); tb.add(b); tb.add(c);
  const double ext_rel = tb.diagonal() / cs;
  std::uint32_t x0, x1, y0, y1, z0, z1;
  cell_range(tb.lo.x, tb.hi.x, rl.x, ext_rel, &x0, &x1);
  cell_range(tb.lo.y, tb.hi.y, rl.y, ext_rel, &y0, &y1);
  cell_range(tb.lo.z, tb.hi.z, rl.z, ext_rel, &z0, &z1);
  for (std::uint32_t z = z0; z <= z1; ++z)
    for (std::uint32_t y = y0; y <= y1; ++y)
      for (std::uint32_t x = x0; x <= x1; ++x) {
        const Vec3d lo{rl.x + double(x) * cs, rl.y + double(y) * cs, rl.z + double(z) * cs};
        const Vec3d hi{rl.x + double(x + 1) * cs, rl.y + double(y + 1) * cs, rl.z + double(z + 1) * cs};
        const bool single = x0 == x1 && y0 == y1 && z0 == z1;
        if (single || tri_box_overlap(lo, hi, a, b, c)) out.push_back(morton_encode(x, y, z));
      }
}

Vec3d face_portal(const Frame& f, std::uint32_t x, std::uint32_t y, std::uint32_t z, int dir) {
  const int axis = dir >> 1;
  const double cs = f.cell_size(f.leaf_level);
  const std::int64_t c[3] = {x, y, z};
  // Fixed, non-dyadic fractions of the face (a mesh vertex there is unlikely; if a triangle does
  // pass through the portal the adjacency is degenerate and skipped, as any other).
  static const double frac[3] = {0.4137, 0.5629, 0.4871};
  Vec3d p;
  for (int k = 0; k < 3; ++k) {
    if (k == axis) {
      const std::int64_t face = c[k] + ((dir & 1) ? 1 : 0);
      p[k] = f.root_lo[k] + double(face) * cs;
    } else {
      p[k] = f.root_lo[k] + (double(c[k]) + frac[k]) * cs;
    }
  }
  return p;
}

}  // namespace ebp::detail
